//! Near/far clipping: triangles passing behind the camera draw exactly their visible part,
//! triangles entirely behind (or before the near plane) draw nothing.
//!
//! Expected coverage is computed analytically in f64 by casting the ray through each pixel centre.
//! Pixels whose expectation differs from one of their 8 neighbours (centre within about a pixel of
//! an analytic boundary) are not compared; all others must match exactly.

mod common;

use common::{Camera, unambiguous};
use glam::{DVec2, DVec3, Vec4};
use hyrt_raster::{EMPTY_ID, RasterOptions, coverage_count, rasterize};

/// Whether `p` (x, z) is inside the 2D triangle `t` (either winding).
fn inside_xz(t: &[DVec3; 3], p: DVec3) -> bool {
    let q = |v: DVec3| DVec2::new(v.x, v.z);
    let (a, b, c, p) = (q(t[0]), q(t[1]), q(t[2]), q(p));
    let e = |u: DVec2, v: DVec2| (v - u).perp_dot(p - u);
    let (e0, e1, e2) = (e(a, b), e(b, c), e(c, a));
    (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0)
}

/// Rasterizes the horizontal triangle `world` (all vertices at height `plane_y`) and compares
/// every unambiguous pixel with the analytic expectation: the ray hits the plane inside the
/// triangle, at a view depth within [near, far]. Returns the number of covered pixels compared.
fn check_horizontal_triangle(cam: &Camera, world: [DVec3; 3], plane_y: f64) -> usize {
    let (w, h) = (cam.width, cam.height);
    let clip = world.map(|p| cam.clip(p));
    let target = rasterize(&[clip], &[7], w, h, &RasterOptions::default());
    let expect = |x: u32, y: u32| {
        let d = cam.ray(x, y);
        let t = (plane_y - cam.eye.y) / d.y;
        if t.is_nan() || t <= 0.0 {
            return false;
        }
        let p = cam.eye + d * t;
        let depth = cam.view_depth(p);
        inside_xz(&world, p) && depth >= cam.near && depth <= cam.far
    };
    let mut covered = 0;
    for y in 0..h {
        for x in 0..w {
            let id = target.id[target.index(x, y)];
            assert!(id == 7 || id == EMPTY_ID);
            if unambiguous(w, h, x, y, expect) {
                let e = expect(x, y);
                assert_eq!(id == 7, e, "pixel ({x}, {y}): expected covered = {e}");
                covered += usize::from(e);
            }
        }
    }
    covered
}

fn ground_camera() -> Camera {
    Camera::new(DVec3::new(0.0, 3.0, 0.0), DVec3::new(0.0, 0.0, -1.0), DVec3::Y, 60.0, 0.1, 100.0, 320, 240)
}

/// The plane y = 0 seen from above, with one vertex of the triangle behind the camera (negative
/// view depth, so its naive projection would land on the wrong side of the screen).
#[test]
fn one_vertex_behind_the_camera_draws_the_analytic_region() {
    let cam = ground_camera();
    let world = [DVec3::new(-4.0, 0.0, -6.0), DVec3::new(4.0, 0.0, -6.0), DVec3::new(0.5, 0.0, 20.0)];
    assert!(cam.view_depth(world[2]) < 0.0, "vertex must be behind the eye");
    let covered = check_horizontal_triangle(&cam, world, 0.0);
    assert!(covered > 10_000, "{covered}");
}

/// Same plane, two vertices behind the camera: the visible part is a triangle again.
#[test]
fn two_vertices_behind_the_camera_draw_the_analytic_region() {
    let cam = ground_camera();
    let world = [DVec3::new(-6.0, 0.0, 15.0), DVec3::new(5.0, 0.0, 18.0), DVec3::new(0.7, 0.0, -9.0)];
    assert!(cam.view_depth(world[0]) < 0.0 && cam.view_depth(world[1]) < 0.0);
    let covered = check_horizontal_triangle(&cam, world, 0.0);
    assert!(covered > 5_000, "{covered}");
}

/// The real case: a huge ceiling triangle (20 km across) over a camera standing in a room,
/// passing behind it, and cut by the far plane in front of it.
#[test]
fn huge_ceiling_triangle_over_the_camera_draws_the_analytic_region() {
    let cam = Camera::new(
        DVec3::new(0.3, 1.6, -0.2),
        DVec3::new(0.0, 2.0, -1.5),
        DVec3::Y,
        90.0,
        0.05,
        20.0,
        320,
        240,
    );
    let world = [DVec3::new(-1e4, 2.5, 1e4), DVec3::new(1e4, 2.5, 1e4), DVec3::new(0.0, 2.5, -1e4)];
    let covered = check_horizontal_triangle(&cam, world, 2.5);
    assert!(covered > 20_000, "{covered}");
}

/// Entirely behind the eye, including the case where dividing by the negative w would project
/// all three vertices into the screen: nothing is drawn. Likewise for triangles between the eye
/// and the near plane, and beyond the far plane.
#[test]
fn triangles_entirely_behind_or_outside_the_depth_range_draw_nothing() {
    let cam = Camera::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), DVec3::Y, 60.0, 0.5, 50.0, 64, 48);
    let cases: [[DVec3; 3]; 4] = [
        // Behind: w = -5 < 0, naive x/w, y/w are inside [-1, 1].
        [DVec3::new(-1.0, -1.0, 5.0), DVec3::new(1.0, -1.0, 5.0), DVec3::new(0.0, 1.0, 5.0)],
        // Behind and huge.
        [DVec3::new(-1e5, -1e5, 1.0), DVec3::new(1e5, -1e5, 1.0), DVec3::new(0.0, 1e5, 1.0)],
        // Between the eye and the near plane (0 < w < near).
        [DVec3::new(-0.1, -0.1, -0.3), DVec3::new(0.1, -0.1, -0.3), DVec3::new(0.0, 0.1, -0.3)],
        // Beyond the far plane.
        [DVec3::new(-10.0, -10.0, -60.0), DVec3::new(10.0, -10.0, -60.0), DVec3::new(0.0, 10.0, -60.0)],
    ];
    for world in cases {
        let tri = world.map(|p| cam.clip(p));
        for t in [tri, [tri[0], tri[2], tri[1]]] {
            let count = coverage_count(&[t], 64, 48, &RasterOptions::default());
            assert!(count.iter().all(|&c| c == 0), "{world:?} drew something");
        }
    }
}

/// Orthographic projection (w = 1, as for a directional shadow map) with depth crossing both
/// near (z = 0) and far (z = 1): only the band 0 <= z <= 1 is drawn, with depth z exactly
/// interpolated (bound 1e-6).
#[test]
fn orthographic_quad_is_clipped_to_the_depth_range() {
    let (w, h) = (100, 20);
    // z = 0.5 + x_ndc: below 0 left of x_ndc = -0.5, above 1 right of x_ndc = 0.5.
    let v = |x: f32, y: f32| Vec4::new(x, y, 0.5 + x, 1.0);
    let tris = [[v(-1.0, -1.0), v(1.0, -1.0), v(1.0, 1.0)], [v(-1.0, -1.0), v(1.0, 1.0), v(-1.0, 1.0)]];
    let t = rasterize(&tris, &[0, 1], w, h, &RasterOptions::default());
    for y in 0..h {
        for x in 0..w {
            let i = t.index(x, y);
            let x_ndc = (f64::from(x) + 0.5) / f64::from(w) * 2.0 - 1.0;
            let z = 0.5 + x_ndc;
            let covered = t.id[i] != EMPTY_ID;
            // Pixel centres are at x_ndc = -0.99, -0.97, ..., never exactly on +-0.5.
            assert_eq!(covered, (0.0..=1.0).contains(&z), "({x}, {y}) z = {z}");
            if covered {
                assert!((f64::from(t.depth[i]) - z).abs() < 1e-6, "{} vs {z}", t.depth[i]);
            }
        }
    }
}
