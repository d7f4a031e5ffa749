//! Whitted mirror reflection: paths of perfect reflections from camera hits.

use glam::Vec3;
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray};

use super::{Progress, Renderer, SurfaceHit, direct, indirect::Vpls, shade_hits_where, shadows::Shadowing};

/// Adds the mirror-reflected light of every camera hit on a specular material; the surfaces
/// the mirror paths meet decide shadows with `shadowing`'s maps when given (see
/// `direct::shade_point`).
pub fn run(
    r: &Renderer,
    gbuffer: &[Option<Hit>],
    shadowing: Option<&Shadowing>,
    vpls: Option<&Vpls>,
    out: &mut [Vec3],
    progress: Progress,
) -> RayCounts {
    // Only hits on mirror materials start a path: skip the others before building their
    // shading point (most of the pass's time otherwise, on scenes with few mirrors).
    let mirror = |h: &Hit| r.scene.materials[r.scene.material[h.tri as usize] as usize].ks != Vec3::ZERO;
    // Under interleaved VPL sampling, a pixel's mirror path sees its pixel's VPL subset.
    let (w, k) = (r.scene.settings.width as usize, r.options.indirect_opts.interleave as usize);
    shade_hits_where(r, gbuffer, out, progress, mirror, |i, hit, c| {
        reflected(r, hit, shadowing, vpls.map(|v| (v, Vpls::subset_of(i, w, k))), c)
    })
}

/// Light arriving at `hit` by mirror reflection, followed for up to `max_depth` bounces;
/// each reflection is weighted by the product of `Ks` so far, and each surface it meets is
/// shaded with direct light, indirect light from the VPLs when given (the subset and stride of
/// interleaved sampling, `(0, 1)` for all), and its own reflection, while depth remains.
pub fn reflected(
    r: &Renderer,
    first: &SurfaceHit,
    shadowing: Option<&Shadowing>,
    vpls: Option<(&Vpls, (usize, usize))>,
    counts: &mut RayCounts,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let mut weight = Vec3::ONE;
    let mut hit = *first;
    for _ in 0..r.scene.settings.max_depth {
        let ks = r.scene.materials[r.scene.material[hit.tri as usize] as usize].ks;
        if ks == Vec3::ZERO {
            break;
        }
        weight *= ks;
        // Reflect about the shading normal; fall back to the geometric one if that would send
        // the ray into the surface.
        let mut dir = reflect(-hit.wo, hit.ns);
        if dir.dot(hit.ng) <= 0.0 {
            dir = reflect(-hit.wo, hit.ng);
        }
        let ray = spawn_ray(hit.p, hit.p_err, hit.ng, dir);
        let Some(h) = r.tracer.closest_hit(&ray, RayKind::Specular, counts) else {
            break;
        };
        hit = SurfaceHit::new(r.scene, &h, ray.dir);
        sum += weight * direct::shade_point(r, &hit, shadowing, counts);
        if let Some((v, (subset, stride))) = vpls {
            sum += weight * v.at_subset(r, &hit, subset, stride, counts);
        }
    }
    sum
}

fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}
