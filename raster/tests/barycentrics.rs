//! Perspective-correct barycentrics and depth: the reported `(b1, b2)` reconstruct the 3D point
//! that the ray through the pixel centre hits, also for clipped triangles, and the depth is that
//! point's `z / w`.

mod common;

use common::Camera;
use glam::{DVec3, Vec4};
use hyrt_raster::{EMPTY_ID, RasterOptions, for_each_fragment, rasterize};

/// Intersection of the ray `eye + t d` with the plane of `tri` (f64).
fn ray_plane(eye: DVec3, d: DVec3, tri: &[DVec3; 3]) -> DVec3 {
    let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    let t = n.dot(tri[0] - eye) / n.dot(d);
    eye + d * t
}

struct Errors {
    /// Largest |P(bary) - P(ray)| / scale.
    position: f64,
    /// Largest |depth - z/w(P(ray))|.
    depth: f64,
    pixels: usize,
}

/// Rasterizes `tri` and measures, over all covered pixels, how far the point rebuilt from the
/// reported barycentrics is from the ray hit (relative to `scale`), and the depth error.
fn measure(cam: &Camera, tri: [DVec3; 3], scale: f64) -> Errors {
    let clip = tri.map(|p| cam.clip(p));
    let t = rasterize(&[clip], &[0], cam.width, cam.height, &RasterOptions::default());
    let mut e = Errors { position: 0.0, depth: 0.0, pixels: 0 };
    for y in 0..cam.height {
        for x in 0..cam.width {
            let i = t.index(x, y);
            if t.id[i] == EMPTY_ID {
                continue;
            }
            let [b1, b2] = t.bary[i].map(f64::from);
            let p = tri[0] * (1.0 - b1 - b2) + tri[1] * b1 + tri[2] * b2;
            let hit = ray_plane(cam.eye, cam.ray(x, y), &tri);
            e.position = e.position.max((p - hit).length() / scale);
            e.depth = e.depth.max((f64::from(t.depth[i]) - cam.ndc_depth(hit)).abs());
            e.pixels += 1;
        }
    }
    e
}

fn camera() -> Camera {
    Camera::new(DVec3::new(0.5, 1.2, 2.0), DVec3::new(0.0, 0.0, -3.0), DVec3::Y, 60.0, 0.1, 100.0, 400, 300)
}

/// A strongly foreshortened triangle (depth from ~1.5 to ~9): position error below 1e-4 of the
/// triangle's size, depth error below 1e-5.
#[test]
fn perspective_barycentrics_reconstruct_the_ray_hit_point() {
    let cam = camera();
    let tri = [DVec3::new(-2.0, -0.5, -6.0), DVec3::new(2.5, 0.0, 0.0), DVec3::new(0.5, 1.5, -4.0)];
    let size = (tri[1] - tri[0]).length();
    let e = measure(&cam, tri, size);
    assert!(e.pixels > 10_000, "{}", e.pixels);
    assert!(e.position < 1e-4, "relative position error {:e}", e.position);
    assert!(e.depth < 1e-5, "depth error {:e}", e.depth);
}

/// A triangle with one vertex behind the camera: the barycentrics of the clipped part are still
/// relative to the original vertices (same bounds as above).
#[test]
fn clipped_triangle_barycentrics_are_relative_to_the_original_vertices() {
    let cam = camera();
    let tri = [DVec3::new(-3.0, -1.0, -8.0), DVec3::new(3.0, -1.0, -5.0), DVec3::new(0.5, -0.5, 6.0)];
    assert!(cam.view_depth(tri[2]) < 0.0);
    let size = (tri[2] - tri[0]).length();
    let e = measure(&cam, tri, size);
    assert!(e.pixels > 10_000, "{}", e.pixels);
    assert!(e.position < 1e-4, "relative position error {:e}", e.position);
    assert!(e.depth < 1e-5, "depth error {:e}", e.depth);
}

/// [`for_each_fragment`] reports exactly the pixels, depths and barycentrics that [`rasterize`]
/// stores for a lone triangle (bit for bit), including a clipped one.
#[test]
fn for_each_fragment_matches_rasterize() {
    let cam = camera();
    let tris = [
        [DVec3::new(-2.0, -0.5, -6.0), DVec3::new(2.5, 0.0, 0.0), DVec3::new(0.5, 1.5, -4.0)],
        [DVec3::new(-3.0, -1.0, -8.0), DVec3::new(3.0, -1.0, -5.0), DVec3::new(0.5, -0.5, 6.0)],
    ];
    for tri in tris {
        let clip: [Vec4; 3] = tri.map(|p| cam.clip(p));
        let t = rasterize(&[clip], &[0], cam.width, cam.height, &RasterOptions::default());
        let mut n = 0;
        for_each_fragment(&clip, cam.width, cam.height, &RasterOptions::default(), |f| {
            let i = t.index(f.x, f.y);
            assert_eq!(t.id[i], 0);
            assert_eq!(t.depth[i].to_bits(), f.depth.to_bits());
            assert_eq!(t.bary[i].map(f32::to_bits), f.bary.map(f32::to_bits));
            n += 1;
        });
        assert_eq!(n, t.id.iter().filter(|&&id| id == 0).count());
    }
}
