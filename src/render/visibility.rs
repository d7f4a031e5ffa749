//! Visibility pass: which surface each pixel sees.

use hyrt_tracer::{Ray, RayCounts, RayKind};

use super::{Progress, Renderer, SurfaceHit, Visibility, par_rows};

/// Fills the G-buffer: one entry per pixel, `None` where the pixel sees nothing.
pub fn run(r: &Renderer, progress: Progress, counts: &mut RayCounts) -> Vec<Option<SurfaceHit>> {
    let (w, h) = (r.scene.settings.width, r.scene.settings.height);
    let mut gbuffer = vec![None; w as usize * h as usize];
    match r.options.visibility {
        Visibility::Rays => {
            *counts += par_rows(&mut gbuffer, w as usize, progress, |y, row, c| {
                for (x, px) in row.iter_mut().enumerate() {
                    let dir = r.camera.direction(x as u32, y).normalize();
                    let ray = Ray::new(r.camera.eye, dir, f32::INFINITY);
                    *px = r
                        .tracer
                        .closest_hit(&ray, RayKind::Primary, c)
                        .map(|hit| SurfaceHit::new(r.scene, &hit, dir));
                }
            });
        }
    }
    gbuffer
}
