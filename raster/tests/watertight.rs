//! Watertightness: shared edges cover every pixel centre exactly once (no holes, no double hits),
//! including edges and vertices lying exactly on pixel centres, slivers at silhouettes, sub-pixel
//! triangles, and edges created by near/far clipping.

mod common;

use common::{Camera, Rng, grid_tris, pixel_to_clip, reversed, unambiguous, uv_sphere};
use glam::{DMat3, DVec3, Vec4};
use hyrt_raster::{RasterOptions, coverage_count, for_each_fragment};

const CULL: RasterOptions = RasterOptions {
    tile_size: 64,
    cull_backfaces: true,
    reversed_z: false,
    depth_tie: 0.0,
    barycentrics: true,
    depth: true,
    rivals: false,
};
/// Both faces drawn (the default).
const TWO_SIDED: RasterOptions = RasterOptions::DEFAULT;

/// Checks a closed sphere mesh seen from outside. Bounds:
/// * every pixel is covered by at most 1 front-facing triangle;
/// * front-facing and back-facing coverage are equal at every pixel (closed surface: the winding
///   numbers of its triangles cancel), and two-sided coverage is their sum;
/// * every pixel whose centre is more than `margin` px inside the analytic silhouette circle is
///   covered exactly once, every pixel more than `margin` px outside is not covered.
///
/// Returns the number of pixels asserted to be covered exactly once.
fn check_sphere(cam: &Camera, radius: f64, slices: u32, stacks: u32, margin: f64, min_tris: usize) -> usize {
    let rot = DMat3::from_rotation_x(0.6) * DMat3::from_rotation_z(0.3);
    let (verts, idx) = uv_sphere(DVec3::ZERO, radius, slices, stacks, rot);
    assert!(idx.len() >= min_tris, "{} triangles", idx.len());
    let tris = cam.clip_tris(&verts, &idx);
    let (w, h) = (cam.width, cam.height);
    let front = coverage_count(&tris, w, h, &CULL);
    let back = coverage_count(&reversed(&tris), w, h, &CULL);
    let all = coverage_count(&tris, w, h, &TWO_SIDED);

    // The sphere is centred on the view axis: its silhouette is a circle around the image centre
    // of angular radius asin(r / d).
    let alpha = (radius / cam.eye.length()).asin();
    let r_px = alpha.tan() / FOV_HALF_TAN * f64::from(h) / 2.0;

    let mut inside = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            assert!(front[i] <= 1, "double hit at ({x}, {y}): {}", front[i]);
            assert_eq!(front[i], back[i], "front/back layers differ at ({x}, {y})");
            assert_eq!(all[i], front[i] + back[i]);
            let dx = f64::from(x) + 0.5 - f64::from(w) / 2.0;
            let dy = f64::from(y) + 0.5 - f64::from(h) / 2.0;
            let d = dx.hypot(dy);
            if d < r_px - margin {
                assert_eq!(front[i], 1, "hole at ({x}, {y}), {d:.2} px from centre");
                inside += 1;
            } else if d > r_px + margin {
                assert_eq!(front[i], 0, "coverage outside silhouette at ({x}, {y})");
            }
        }
    }
    inside
}

const FOV_DEG: f64 = 50.0;
/// tan(FOV_DEG / 2).
const FOV_HALF_TAN: f64 = 0.466_307_658_154_998_6;

fn sphere_camera(dist: f64, width: u32, height: u32) -> Camera {
    assert!(((FOV_DEG.to_radians() / 2.0).tan() - FOV_HALF_TAN).abs() < 1e-15);
    Camera::new(DVec3::new(0.0, 0.0, dist), DVec3::ZERO, DVec3::Y, FOV_DEG, 0.1, 100.0, width, height)
}

/// 12k-triangle sphere, ~180 px radius: silhouette margin 1 px (the tessellated silhouette is at
/// most ~0.2 px inside the analytic one).
#[test]
fn closed_sphere_covers_its_silhouette_exactly_once() {
    let cam = sphere_camera(3.2, 512, 512);
    let inside = check_sphere(&cam, 1.0, 96, 64, 1.0, 10_000);
    assert!(inside > 90_000, "{inside}");
}

/// 20k triangles on a ~33 px radius sphere: most triangles are smaller than a pixel and many
/// cover no pixel centre at all.
#[test]
fn closed_sphere_of_subpixel_triangles_covers_its_silhouette_exactly_once() {
    let cam = sphere_camera(5.0, 200, 150);
    let inside = check_sphere(&cam, 1.0, 160, 64, 1.0, 20_000);
    assert!(inside > 2_500, "{inside}");
}

/// Grid of `cell`-pixel squares whose corners are all pixel centres, covering more than the
/// target, split along alternating diagonals (which also pass through pixel centres): every
/// pixel exactly once, with and without culling, for several tile sizes.
#[test]
fn grid_with_edges_through_pixel_centres_covers_every_pixel_exactly_once() {
    let (w, h) = (203, 157);
    for cell in [1u32, 2, 3, 4, 7] {
        let n = (w.max(h) + 20) / cell + 2;
        let tris = grid_tris(
            n,
            n,
            |i, j| {
                let x = -8.5 + f64::from(i * cell);
                let y = -8.5 + f64::from(j * cell);
                pixel_to_clip(x, y, 0.5, w, h)
            },
            |i, j| (i + j) % 2 == 0,
        );
        for opts in [CULL, TWO_SIDED, RasterOptions { tile_size: 8, ..CULL }] {
            let count = coverage_count(&tris, w, h, &opts);
            for (k, &c) in count.iter().enumerate() {
                assert_eq!(c, 1, "cell {cell}: pixel ({}, {}) covered {c}x", k as u32 % w, k as u32 / w);
            }
        }
        // All triangles are front-facing: culling back faces of the reversed grid removes all.
        let none = coverage_count(&reversed(&tris), w, h, &CULL);
        assert!(none.iter().all(|&c| c == 0));
    }
}

/// Shared vertices jittered randomly (up to 0.2 cell per axis, which keeps every triangle
/// counter-clockwise), random diagonals, non-integer cell size: every pixel exactly once.
#[test]
fn jittered_grid_covers_every_pixel_exactly_once() {
    let (w, h) = (160, 120);
    let cell = 5.3;
    let n = 36;
    let mut rng = Rng(42);
    let jitter: Vec<(f64, f64)> = (0..(n + 1) * (n + 1))
        .map(|_| ((rng.f64() - 0.5) * 0.4 * cell, (rng.f64() - 0.5) * 0.4 * cell))
        .collect();
    let flips: Vec<bool> = (0..n * n).map(|_| rng.f64() < 0.5).collect();
    let tris = grid_tris(
        n,
        n,
        |i, j| {
            // Keep the border straight so the grid surely covers the target.
            let border = i == 0 || j == 0 || i == n || j == n;
            let (jx, jy) = if border { (0.0, 0.0) } else { jitter[(j * (n + 1) + i) as usize] };
            let x = -10.0 + f64::from(i) * cell + jx;
            let y = -10.0 + f64::from(j) * cell + jy;
            pixel_to_clip(x, y, 0.25 + 0.5 * (x / 200.0), w, h)
        },
        |i, j| flips[(j * n + i) as usize],
    );
    let count = coverage_count(&tris, w, h, &CULL);
    for (k, &c) in count.iter().enumerate() {
        assert_eq!(c, 1, "pixel ({}, {}) covered {c}x", k as u32 % w, k as u32 / w);
    }
}

/// A fan of 37 triangles around a vertex on a pixel centre (like a sphere pole): pixels more than
/// 1 px inside the fan's inscribed circle are covered exactly once; none more than once.
#[test]
fn fan_around_a_pixel_centre_covers_exactly_once() {
    let (w, h) = (96, 96);
    let (cx, cy, r) = (48.5, 47.5, 40.0);
    let n = 37;
    let rim = |k: u32| {
        let a = std::f64::consts::TAU * f64::from(k % n) / f64::from(n);
        pixel_to_clip(cx + r * a.cos(), cy + r * a.sin(), 0.5, w, h)
    };
    let centre = pixel_to_clip(cx, cy, 0.5, w, h);
    let tris: Vec<[Vec4; 3]> = (0..n).map(|k| [centre, rim(k), rim(k + 1)]).collect();
    let count = coverage_count(&tris, w, h, &TWO_SIDED);
    let inner = r * (std::f64::consts::PI / f64::from(n)).cos() - 1.0;
    for y in 0..h {
        for x in 0..w {
            let c = count[(y * w + x) as usize];
            assert!(c <= 1);
            let d = (f64::from(x) + 0.5 - cx).hypot(f64::from(y) + 0.5 - cy);
            if d < inner {
                assert_eq!(c, 1, "hole at ({x}, {y})");
            }
        }
    }
}

/// Top-left rule on the simplest case: a square with corners on pixel centres `(a + 1/2, b + 1/2)`
/// and side `s` covers exactly the `s x s` pixels `[a, a + s) x [b, b + s)` (left and top edges
/// included, right and bottom excluded).
#[test]
fn square_with_corners_on_pixel_centres_covers_exactly_its_pixels() {
    let (w, h) = (32, 32);
    let (a, b, s) = (5u32, 9u32, 11u32);
    let p = |x: u32, y: u32| pixel_to_clip(f64::from(x) + 0.5, f64::from(y) + 0.5, 0.5, w, h);
    let quad = [[p(a, b), p(a, b + s), p(a + s, b + s)], [p(a, b), p(a + s, b + s), p(a + s, b)]];
    let mut hits = vec![0u32; (w * h) as usize];
    for tri in &quad {
        for_each_fragment(tri, w, h, &TWO_SIDED, |f| hits[(f.y * w + f.x) as usize] += 1);
    }
    for y in 0..h {
        for x in 0..w {
            let expected = u32::from((a..a + s).contains(&x) && (b..b + s).contains(&y));
            assert_eq!(hits[(y * w + x) as usize], expected, "({x}, {y})");
        }
    }
}

/// A floor grid (80x80 quads) extending behind the camera, with near and far planes both cutting
/// through the visible floor: the shared edges created by clipping leave no holes and no double
/// hits. Bounds: no pixel covered twice; every pixel whose expected coverage (ray hits the floor
/// inside the grid, at view depth in [near, far]) agrees with its 8 neighbours matches it exactly.
#[test]
fn floor_grid_clipped_by_near_and_far_planes_is_watertight() {
    let (w, h) = (320, 240);
    let cam =
        Camera::new(DVec3::new(0.3, 1.0, 0.2), DVec3::new(0.5, 0.0, -4.0), DVec3::Y, 60.0, 1.5, 25.0, w, h);
    let (n, half) = (80u32, 40.0);
    let mut verts = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let x = -half + 2.0 * half * f64::from(i) / f64::from(n);
            let z = -half + 2.0 * half * f64::from(j) / f64::from(n);
            verts.push(DVec3::new(x, 0.0, z));
        }
    }
    let v = |i: u32, j: u32| j * (n + 1) + i;
    let mut idx = Vec::new();
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from above (+y): front faces for this camera.
            idx.push([v(i, j), v(i, j + 1), v(i + 1, j + 1)]);
            idx.push([v(i, j), v(i + 1, j + 1), v(i + 1, j)]);
        }
    }
    let tris = cam.clip_tris(&verts, &idx);
    let front = coverage_count(&tris, w, h, &CULL);
    let all = coverage_count(&tris, w, h, &TWO_SIDED);
    assert_eq!(front, all, "the floor seen from above is all front faces");

    #[derive(PartialEq, Clone, Copy, Debug)]
    enum Expect {
        Sky,
        Floor,
        NearClipped,
        FarClipped,
        OffGrid,
    }
    let expect = |x: u32, y: u32| {
        let d = cam.ray(x, y);
        if d.y >= 0.0 {
            return Expect::Sky;
        }
        let p = cam.eye + d * (-cam.eye.y / d.y);
        if p.x.abs() > half || p.z.abs() > half {
            return Expect::OffGrid;
        }
        let depth = cam.view_depth(p);
        if depth < cam.near {
            Expect::NearClipped
        } else if depth > cam.far {
            Expect::FarClipped
        } else {
            Expect::Floor
        }
    };
    let mut seen = [0usize; 5];
    for y in 0..h {
        for x in 0..w {
            let c = front[(y * w + x) as usize];
            assert!(c <= 1, "double hit at ({x}, {y})");
            let e = expect(x, y);
            if unambiguous(w, h, x, y, expect) {
                seen[e as usize] += 1;
                assert_eq!(c, u32::from(e == Expect::Floor), "({x}, {y}) expected {e:?}");
            }
        }
    }
    // Every case is actually exercised.
    assert!(seen.iter().all(|&s| s > 100), "{seen:?}");
}

/// Jittered mesh whose vertices are on a quarter-pixel lattice (exact in fixed point), so that
/// many edges of many slopes pass exactly through pixel centres: every pixel exactly once.
#[test]
fn quarter_pixel_random_mesh_covers_every_pixel_exactly_once() {
    let (w, h) = (64, 48);
    let n = 12;
    let mut rng = Rng(7);
    let q = |v: f64| (v * 4.0).round() / 4.0;
    let pts: Vec<(f64, f64)> = (0..(n + 1) * (n + 1))
        .map(|k| {
            let (i, j) = (k % (n + 1), k / (n + 1));
            let border = i == 0 || j == 0 || i == n || j == n;
            let (jx, jy) =
                if border { (0.0, 0.0) } else { ((rng.f64() - 0.5) * 3.0, (rng.f64() - 0.5) * 3.0) };
            (q(-4.0 + f64::from(i) * 6.0 + jx), q(-4.0 + f64::from(j) * 6.0 + jy))
        })
        .collect();
    let tris = grid_tris(
        n,
        n,
        |i, j| {
            let (x, y) = pts[(j * (n + 1) + i) as usize];
            pixel_to_clip(x, y, 0.5, w, h)
        },
        |i, j| (i * 7 + j * 3) % 5 < 2,
    );
    let count = coverage_count(&tris, w, h, &TWO_SIDED);
    assert!(count.iter().all(|&c| c == 1), "{count:?}");
}
