//! Depth test and tie-breaking: the nearer fragment wins; at equal depth the smaller id wins,
//! whatever the order of the triangles; with a tie window (`RasterOptions::depth_tie`), depths
//! within the window count as equal.

mod common;

use common::{Camera, pixel_to_clip};
use glam::{DVec3, Vec4};
use hyrt_raster::{EMPTY_ID, RasterOptions, Target, rasterize};

const W: u32 = 48;
const H: u32 = 40;

fn tri_px(p: [(f64, f64); 3], depth: f64) -> [Vec4; 3] {
    p.map(|(x, y)| pixel_to_clip(x, y, depth, W, H))
}

/// Rasterizes `(tri, id)` pairs in the given order.
fn draw(items: &[([Vec4; 3], u32)]) -> Target {
    let tris: Vec<[Vec4; 3]> = items.iter().map(|i| i.0).collect();
    let ids: Vec<u32> = items.iter().map(|i| i.1).collect();
    rasterize(&tris, &ids, W, H, &RasterOptions::default())
}

/// Two overlapping coplanar triangles at constant depth (every covered pixel is an exact tie),
/// ids 5 and 3, in both orders: the overlap is id 3, the rest belongs to whichever covers it, and
/// the two results are identical.
#[test]
fn coplanar_overlapping_triangles_resolve_to_the_smaller_id_in_both_orders() {
    let a = tri_px([(2.0, 2.0), (40.0, 5.0), (10.0, 35.0)], 0.4);
    let b = tri_px([(6.0, 30.0), (20.0, 1.0), (45.0, 33.0)], 0.4);
    let ab = draw(&[(a, 5), (b, 3)]);
    let ba = draw(&[(b, 3), (a, 5)]);
    assert_eq!(ab, ba);
    let only_a = draw(&[(a, 5)]);
    let only_b = draw(&[(b, 3)]);
    let mut overlap = 0;
    for i in 0..(W * H) as usize {
        let (in_a, in_b) = (only_a.id[i] == 5, only_b.id[i] == 3);
        let expected = match (in_a, in_b) {
            (_, true) => 3,
            (true, false) => 5,
            (false, false) => EMPTY_ID,
        };
        assert_eq!(ab.id[i], expected);
        overlap += usize::from(in_a && in_b);
    }
    assert!(overlap > 100, "{overlap}");
}

/// The same with perspective: two triangles in a plane facing the camera (constant view depth,
/// hence constant z/w: exact ties), and an exact duplicate of a triangle with another id.
#[test]
fn perspective_ties_and_duplicates_resolve_to_the_smaller_id() {
    let cam = Camera::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), DVec3::Y, 60.0, 0.1, 10.0, W, H);
    let p = |x: f64, y: f64| cam.clip(DVec3::new(x, y, -3.0));
    let a = [p(-1.5, -1.0), p(1.2, -1.1), p(0.0, 1.5)];
    let b = [p(-1.0, 1.2), p(-0.2, -1.4), p(1.6, 0.9)];
    for order in [[0, 1, 2], [2, 1, 0], [1, 2, 0]] {
        let items = [(a, 9), (b, 4), (a, 2)];
        let t = draw(&order.map(|k| items[k]));
        let mut seen = [false; 3];
        for &id in &t.id {
            // id 9 (duplicate of id 2) never survives; 4 survives only where a does not cover.
            assert_ne!(id, 9);
            seen[match id {
                2 => 0,
                4 => 1,
                _ => 2,
            }] = true;
        }
        assert!(seen.iter().all(|&s| s), "{seen:?}");
        assert_eq!(t, draw(&items));
    }
}

/// A nearer triangle wins over a farther one whatever the ids and the order.
#[test]
fn nearer_triangle_wins_whatever_the_id_and_order() {
    let far = tri_px([(0.0, 0.0), (48.0, 0.0), (0.0, 40.0)], 0.7);
    let near = tri_px([(0.0, 0.0), (48.0, 0.0), (0.0, 40.0)], 0.3);
    for (ids, order) in [((1, 2), false), ((2, 1), true), ((1, 2), true), ((2, 1), false)] {
        let items = if order { [(far, ids.0), (near, ids.1)] } else { [(near, ids.1), (far, ids.0)] };
        let t = draw(&items);
        for (i, &id) in t.id.iter().enumerate() {
            if id != EMPTY_ID {
                assert_eq!(id, ids.1);
                assert_eq!(t.depth[i], 0.3);
            }
        }
    }
}

/// A full-screen quad at view depth `d` (x, y spanning NDC [-1.5, 1.5]), with clip z chosen by
/// the depth convention: standard `z = f/(f-n) (w - n)` or reversed `z = n`.
fn quad_at(d: f32, n: f32, f: f32, reversed: bool) -> [[Vec4; 3]; 2] {
    let z = if reversed { n } else { f / (f - n) * (d - n) };
    let v = |x: f32, y: f32| Vec4::new(x * d, y * d, z, d);
    [[v(-1.5, -1.5), v(1.5, -1.5), v(1.5, 1.5)], [v(-1.5, -1.5), v(1.5, 1.5), v(-1.5, 1.5)]]
}

/// Two parallel surfaces 1e-4 apart (relative) at 5e4 near-plane distances: standard z/w
/// cannot tell them apart (the tie goes to the smaller id, the farther surface here), while
/// reversed-Z resolves them everywhere.
#[test]
fn reversed_z_resolves_surfaces_that_standard_depth_cannot() {
    let (n, f) = (0.01f32, 1000.0f32);
    let (near_d, far_d) = (500.0f32, 500.05f32);
    let run = |reversed: bool| {
        let mut tris = Vec::new();
        let mut ids = Vec::new();
        for (d, id) in [(far_d, 1u32), (near_d, 2u32)] {
            for t in quad_at(d, n, f, reversed) {
                tris.push(t);
                ids.push(id);
            }
        }
        let opts = RasterOptions { reversed_z: reversed, ..Default::default() };
        rasterize(&tris, &ids, W, H, &opts)
    };
    let rev = run(true);
    assert!(rev.id.iter().all(|&id| id == 2), "reversed-Z: the nearer surface must win everywhere");
    assert!(rev.depth.iter().all(|&d| (d - n / near_d).abs() <= 1e-6 * d), "reversed depth is n/w");
    let std = run(false);
    let wrong = std.id.iter().filter(|&&id| id != 2).count();
    assert!(wrong > 0, "standard depth was expected to fail here (the test would prove nothing)");
}

#[test]
fn reversed_z_empty_pixels_hold_zero() {
    let opts = RasterOptions { reversed_z: true, ..Default::default() };
    let t = rasterize(&[], &[], 4, 3, &opts);
    assert!(t.depth.iter().all(|&d| d == hyrt_raster::EMPTY_DEPTH_REVERSED));
    assert!(t.id.iter().all(|&i| i == EMPTY_ID));
}

/// Two parallel full-screen quads at view depths `d` and `d * (1 + gap)`, the farther one with
/// the smaller id (1, the nearer 2), drawn in both orders with the tie window `depth_tie`: the
/// ids seen (every pixel must be covered, and by the same id in both orders).
fn parallel_quads(reversed: bool, gap: f64, depth_tie: f32) -> u32 {
    // Standard depth `z/w = f/(f-n) (1 - n/w)` must resolve the gap with `depth_tie = 0`: a near
    // plane at 0.6 of the distance makes the relative change of z/w 1.5 times the gap (14 f32
    // ulps for 1e-6) rather than 1e-4 times it. Reversed-Z resolves it at any near distance.
    let (n, f) = if reversed { (0.1, 1000.0) } else { (60.0, 200.0) };
    let near_d = 100.0f32;
    let far_d = (100.0 * (1.0 + gap)) as f32;
    assert!(far_d > near_d);
    let far = quad_at(far_d, n, f, reversed).map(|t| (t, 1));
    let near = quad_at(near_d, n, f, reversed).map(|t| (t, 2));
    let opts = RasterOptions { reversed_z: reversed, depth_tie, ..Default::default() };
    let run = |items: Vec<([Vec4; 3], u32)>| {
        let tris: Vec<[Vec4; 3]> = items.iter().map(|i| i.0).collect();
        let ids: Vec<u32> = items.iter().map(|i| i.1).collect();
        rasterize(&tris, &ids, W, H, &opts)
    };
    let far_first = run(far.iter().chain(&near).copied().collect());
    let near_first = run(near.iter().chain(&far).copied().collect());
    assert_eq!(far_first, near_first, "reversed {reversed}, gap {gap}, tie {depth_tie}");
    let id = far_first.id[0];
    assert!(id != EMPTY_ID && far_first.id.iter().all(|&i| i == id), "reversed {reversed}, gap {gap}");
    id
}

/// The tie window, at view depth 100, in both depth conventions: surfaces 1e-6 apart (relative)
/// are a tie for `depth_tie = 2^-16` (the smaller id, the farther surface, wins on every pixel)
/// and resolved exactly with `0` (the nearer wins on every pixel); surfaces 1e-3 apart are never a
/// tie (the nearer wins with either setting).
#[test]
fn tie_window_gives_close_surfaces_to_the_smaller_id_and_keeps_distinct_ones_apart() {
    const TIE: f32 = 1.0 / 65536.0;
    for reversed in [false, true] {
        assert_eq!(parallel_quads(reversed, 1e-6, TIE), 1, "reversed {reversed}: a tie");
        assert_eq!(parallel_quads(reversed, 1e-6, 0.0), 2, "reversed {reversed}: exact");
        assert_eq!(parallel_quads(reversed, 1e-3, TIE), 2, "reversed {reversed}: no tie");
        assert_eq!(parallel_quads(reversed, 1e-3, 0.0), 2, "reversed {reversed}: exact");
    }
}
