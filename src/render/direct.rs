//! Direct light from point lights at a surface point.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray_to};

use super::{Progress, Renderer, Shadows, SurfaceHit, shade_hits};

/// Shades every camera hit of the G-buffer with direct light.
pub fn run(r: &Renderer, gbuffer: &[Option<Hit>], out: &mut [Vec3], progress: Progress) -> RayCounts {
    shade_hits(r, gbuffer, out, progress, |hit, c| shade(r, hit, c))
}

/// Diffuse direct light at `hit`: `L = Kd / pi * sum_lights I * cos(theta) / r^2` over the
/// lights that are in front of the surface and unoccluded.
///
/// No shadow ray is cast for a light behind the surface (by the shading or the geometric
/// normal: a ray leaving through the back would only find the surface itself), nor on a
/// surface without diffuse reflectance (a perfect mirror).
pub fn shade(r: &Renderer, hit: &SurfaceHit, counts: &mut RayCounts) -> Vec3 {
    let m = &r.scene.materials[r.scene.material[hit.tri as usize] as usize];
    if m.kd == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let mut sum = Vec3::ZERO;
    for light in &r.scene.lights {
        let to_light = light.position - hit.p;
        let d2 = to_light.length_squared();
        if d2 == 0.0 {
            continue;
        }
        let wi = to_light / d2.sqrt();
        let cos = hit.ns.dot(wi);
        if cos <= 0.0 || hit.ng.dot(wi) <= 0.0 {
            continue;
        }
        let visible = match r.options.shadows {
            Shadows::Rays => {
                let ray = spawn_ray_to(hit.p, hit.p_err, hit.ng, light.position);
                !r.tracer.occluded(&ray, RayKind::Shadow, counts)
            }
        };
        if visible {
            sum += light.intensity * (cos / d2);
        }
    }
    m.kd * FRAC_1_PI * sum
}
