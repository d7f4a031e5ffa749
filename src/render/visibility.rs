//! Visibility pass: which surface each pixel sees.
//!
//! - [`Visibility::Rays`]: one primary ray through each pixel centre.
//! - [`Visibility::Raster`]: a z-buffer pass (`hyrt-raster`) gives each pixel its visible
//!   triangle; the hit point is then computed exactly by meeting the pixel's camera ray with
//!   that one triangle's plane, using the tracer's own watertight arithmetic. Wherever both
//!   strategies see the same triangle, the hit point, normal and shading are bit-identical;
//!   they can differ only where the two coverage rules disagree (within a pixel of an edge)
//!   or where two surfaces tie in depth.

use std::time::Instant;

use glam::Vec4;
use hyrt_raster::{EMPTY_ID, RasterOptions, rasterize};
use hyrt_tracer::{Hit, RayCounts, RayKind};
use rayon::prelude::*;

use super::{FrameStats, Progress, Renderer, Visibility, par_rows};
use crate::camera::CameraRays;

/// Fills the G-buffer: per pixel the visible triangle, the distance along the pixel's camera
/// ray and the barycentrics of the hit; `None` where the pixel sees nothing. Shading points
/// (normals, error bounds) are built from it by the shading passes.
pub fn run(r: &Renderer, progress: Progress, stats: &mut FrameStats) -> Vec<Option<Hit>> {
    let (w, h) = (r.scene.settings.width, r.scene.settings.height);
    let mut gbuffer = vec![None; w as usize * h as usize];
    match r.options.visibility {
        Visibility::Rays => {
            stats.rays += par_rows(&mut gbuffer, w as usize, progress, |y, row, c| {
                for (x, px) in row.iter_mut().enumerate() {
                    *px = primary_ray(r, x as u32, y, c);
                }
            });
        }
        Visibility::Raster => {
            let t = Instant::now();
            let near = r.raster_near;
            let clip: Vec<[Vec4; 3]> =
                r.scene.positions.par_iter().map(|tri| tri.map(|p| to_clip(&r.camera, near, p))).collect();
            let ids: Vec<u32> = (0..clip.len() as u32).collect();
            stats.time_ms.insert("vis_transform", super::ms(t));

            let t = Instant::now();
            // The tracer's tie rule, so coplanar duplicates resolve alike in both strategies.
            let opts = RasterOptions {
                reversed_z: true,
                depth_tie: hyrt_tracer::DEPTH_TIE,
                ..RasterOptions::default()
            };
            let target = rasterize(&clip, &ids, w, h, &opts);
            stats.time_ms.insert("vis_raster", super::ms(t));

            let t = Instant::now();
            stats.rays += par_rows(&mut gbuffer, w as usize, progress, |y, row, c| {
                let ids = &target.id[y as usize * w as usize..][..row.len()];
                for (x, (px, &id)) in row.iter_mut().zip(ids).enumerate() {
                    if id == EMPTY_ID {
                        continue;
                    }
                    let ray = r.camera_ray(x as u32, y);
                    *px = match r.tracer.hit_on_plane(id, &ray) {
                        Some(hit) => Some(hit),
                        // The ray runs (numerically) parallel to the triangle's plane: a
                        // sliver seen exactly edge-on. Ask the BVH, and count the ray.
                        None => primary_ray(r, x as u32, y, c),
                    };
                }
            });
            stats.time_ms.insert("vis_resolve", super::ms(t));
        }
    }
    gbuffer
}

fn primary_ray(r: &Renderer, x: u32, y: u32, c: &mut RayCounts) -> Option<Hit> {
    r.tracer.closest_hit(&r.camera_ray(x, y), RayKind::Primary, c)
}

/// Near-plane distance for rasterization: `2^-20` of the scene's extent. With reversed-Z the
/// near distance costs no depth precision, so it only needs to be small enough that nothing
/// a primary ray would see is clipped; it stays non-zero so that `w >= near > 0` after
/// clipping.
pub(crate) fn near_plane(scene: &crate::scene::Scene, camera: &CameraRays) -> f32 {
    let (lo, hi) = scene.bounds().unwrap_or_default();
    let extent = (hi - lo).max_element().max((camera.eye - lo).abs().max_element());
    (extent * (-20f32).exp2()).max(f32::MIN_POSITIVE)
}

/// Clip-space position (reversed-Z) of `p` for the camera's pinhole projection.
///
/// The camera's pixel rays are `forward + sx right + sy up` with `sx = x_ndc tan_x`,
/// `sy = y_ndc tan_y` (see [`CameraRays`]). A point `v = p - eye` lies on that ray when
/// `v.right / v.forward = sx` and `v.up / v.forward = sy`, so `x = v.right / tan_x`,
/// `y = v.up / tan_y`, `w = v.forward` give exactly the NDC of the pixel whose ray passes
/// through `p`. `z = near` for every vertex stores `near / w` (reversed-Z).
#[inline]
pub fn to_clip(cam: &CameraRays, near: f32, p: glam::Vec3) -> Vec4 {
    let v = p - cam.eye;
    // Products with precomputed reciprocals: the rasterizer's coverage and exact-depth plane
    // are both relative to these clip coordinates, so their rounding needs no match elsewhere.
    Vec4::new(v.dot(cam.right) * cam.inv_tan_x, v.dot(cam.up) * cam.inv_tan_y, near, v.dot(cam.forward))
}
