//! Direct light from point lights at a surface point.

use glam::Vec3;
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray_to};

use rayon::prelude::*;

use super::gather::ShadePoint;
use super::light::{PlaneSides, facing, light_geometry, reflect, viewer_side};
use super::{Progress, Renderer, SurfaceHit, shadows::Shadowing};

/// Shades every camera hit of the G-buffer with direct light, one shadow ray per light (the
/// reference; map-based shadows shade in their classify pass, `shadows`).
pub(crate) fn run(
    r: &Renderer,
    gbuffer: &[Option<Hit>],
    out: &mut [Vec3],
    points: Option<&mut [ShadePoint]>,
    progress: Progress,
) -> RayCounts {
    // `shade` with shadow rays, the plane side of each light kept for the row's last
    // triangle (`facing` asks it per pixel; it depends on the triangle and light only).
    let w = r.scene.settings.width as usize;
    let row = |y: usize, row: &mut [Vec3], mut pts: Option<&mut [ShadePoint]>| {
        let mut c = RayCounts::default();
        let first = y * w;
        let mut sides = PlaneSides::new();
        let hits = &gbuffer[first..][..row.len()];
        for (x, (px, hit)) in row.iter_mut().zip(hits).enumerate() {
            let Some(hit) = hit else { continue };
            let s = SurfaceHit::new(r.scene, hit, r.camera_ray(x as u32, y as u32).dir);
            if let Some(pts) = pts.as_deref_mut()
                && r.diffuse(s.tri)
            {
                pts[x] = ShadePoint::of(&s);
            }
            let tri = &r.scene.positions[s.tri as usize];
            let before = c;
            let sides = sides.of(s.tri, tri, &r.lights);
            *px = reflect(r, &s, |l, light| {
                let g = light_geometry(&s, light)?;
                (viewer_side(&s, tri, sides[l]) && shadow_ray(&s, &light.position, r, &mut c)).then_some(g)
            });
            r.pixel_rays.add(first + x, &before, &c);
        }
        progress();
        c
    };
    let rows = out.par_chunks_mut(w.max(1)).enumerate();
    let counts: Vec<RayCounts> = match points {
        Some(p) => rows.zip(p.par_chunks_mut(w.max(1))).map(|((y, o), p)| row(y, o, Some(p))).collect(),
        None => rows.map(|(y, o)| row(y, o, None)).collect(),
    };
    counts.into_iter().sum()
}

/// Whether a shadow ray from `s` reaches `light` (the reference's test).
fn shadow_ray(s: &SurfaceHit, light: &Vec3, r: &Renderer, c: &mut RayCounts) -> bool {
    let ray = spawn_ray_to(s.p, s.p_err, s.ng, *light);
    !r.tracer.occluded(&ray, RayKind::Shadow, c)
}

/// Direct light at `hit`: `L = sum_lights I / r^2 * cos(theta) * (Kd / pi + Ks * lobe)` over
/// the lights that are in front of the surface and visible, `visible(l, light, hit, counts)`
/// deciding visibility; `lobe` is the material's highlight ([`Material::highlight_lobe`],
/// whose module derives the model).
///
/// Visibility is not asked for a light behind the surface (by the shading or the geometric
/// normal: a ray leaving through the back would only find the surface itself), nor on a
/// surface that point lights do not light (a perfect mirror: no diffuse term, no highlight).
///
/// [`Material::highlight_lobe`]: crate::scene::Material::highlight_lobe
pub fn shade(
    r: &Renderer,
    hit: &SurfaceHit,
    counts: &mut RayCounts,
    mut visible: impl FnMut(usize, &crate::scene::PointLight, &SurfaceHit, &mut RayCounts) -> bool,
) -> Vec3 {
    let tri = &r.scene.positions[hit.tri as usize];
    reflect(r, hit, |l, light| {
        let g = facing(hit, light, tri)?;
        visible(l, light, hit, counts).then_some(g)
    })
}

/// [`shade`] at a point with no screen neighbours (a mirror hit, at the end of a view path
/// `dist` long): shadow rays, or the maps' map-space test with `shadowing`.
pub fn shade_point(
    r: &Renderer,
    hit: &SurfaceHit,
    dist: f32,
    shadowing: Option<&Shadowing>,
    counts: &mut RayCounts,
) -> Vec3 {
    match shadowing {
        None => shade(r, hit, counts, |_, light, s, c| shadow_ray(s, &light.position, r, c)),
        Some(sh) => shade(r, hit, counts, |l, _, s, c| sh.visible_at(r, l, s, dist, c)),
    }
}
