//! Hostile input: degenerate, sliver, huge, NaN and infinite triangles, tiny and extreme targets.
//! Nothing panics, every buffer has exactly `width * height` entries, every reported pixel is
//! inside the target, every stored value is in its documented range, and zero-area triangles
//! cover nothing.

mod common;

use common::{Rng, pixel_to_clip};
use glam::Vec4;
use hyrt_raster::{
    EMPTY_DEPTH, EMPTY_ID, MAX_TARGET_DIM, RasterOptions, Target, coverage_count, for_each_fragment,
    rasterize,
};

/// Both faces drawn (the default).
const TWO_SIDED: RasterOptions = RasterOptions::DEFAULT;

/// Every buffer has the right size; a pixel is either empty (id EMPTY_ID, depth EMPTY_DEPTH,
/// bary 0) or holds a known id, a depth in [0, 1] and finite barycentrics.
fn assert_valid(t: &Target, n_tris: usize) {
    let len = t.width as usize * t.height as usize;
    assert_eq!((t.depth.len(), t.id.len(), t.bary.len()), (len, len, len));
    for i in 0..len {
        if t.id[i] == EMPTY_ID {
            assert_eq!(t.depth[i], EMPTY_DEPTH);
            assert_eq!(t.bary[i], [0.0, 0.0]);
        } else {
            assert!((t.id[i] as usize) < n_tris);
            assert!((0.0..=1.0).contains(&t.depth[i]), "depth {}", t.depth[i]);
            assert!(t.bary[i].iter().all(|b| b.is_finite()), "{:?}", t.bary[i]);
        }
    }
}

/// Values spanning every magnitude from 0 through denormals, 1e-4 ... 1e4 ... f32::MAX, plus NaN
/// and infinities, with both signs.
fn nasty_value(rng: &mut Rng) -> f32 {
    const TABLE: [f32; 16] = [
        0.0,
        1e-40,
        f32::MIN_POSITIVE,
        1e-4,
        0.01,
        0.5,
        1.0,
        1.5,
        3.0,
        1e2,
        1e4,
        1e8,
        1e20,
        f32::MAX,
        f32::INFINITY,
        f32::NAN,
    ];
    let magnitude = if rng.below(3) == 0 {
        // Also arbitrary in-between values.
        (10f64.powf(rng.f64() * 12.0 - 6.0)) as f32
    } else {
        TABLE[rng.below(TABLE.len())]
    };
    if rng.below(2) == 0 { -magnitude } else { magnitude }
}

/// 20k random triangles built from extreme coordinates (each component independently), and 20k
/// triangles with reasonable coordinates but one extreme component, on several target sizes
/// including 1x1 and non-multiples of the tile and block sizes.
#[test]
fn extreme_coordinates_never_panic_or_escape_the_buffer() {
    let mut rng = Rng(1234);
    let mut tris = Vec::new();
    for _ in 0..20_000 {
        tris.push(std::array::from_fn(|_| {
            Vec4::new(
                nasty_value(&mut rng),
                nasty_value(&mut rng),
                nasty_value(&mut rng),
                nasty_value(&mut rng),
            )
        }));
    }
    for _ in 0..20_000 {
        let mut t: [Vec4; 3] = std::array::from_fn(|_| {
            Vec4::new(
                (rng.f64() * 4.0 - 2.0) as f32,
                (rng.f64() * 4.0 - 2.0) as f32,
                rng.f64() as f32,
                (rng.f64() * 2.0 - 0.2) as f32,
            )
        });
        t[rng.below(3)][rng.below(4)] = nasty_value(&mut rng);
        tris.push(t);
    }
    let ids: Vec<u32> = (0..tris.len() as u32).collect();
    let mut drawn = 0;
    for (w, h) in [(1, 1), (7, 3), (64, 64), (100, 37), (129, 65)] {
        let culled = RasterOptions { tile_size: 8, cull_backfaces: true, ..TWO_SIDED };
        // A wide tie window: many of these overlapping triangles tie.
        let tied = RasterOptions { depth_tie: 1e-3, ..TWO_SIDED };
        for opts in [TWO_SIDED, culled, tied] {
            let t = rasterize(&tris, &ids, w, h, &opts);
            assert_valid(&t, tris.len());
            drawn += t.id.iter().filter(|&&id| id != EMPTY_ID).count();
            assert_eq!(coverage_count(&tris, w, h, &opts).len(), (w * h) as usize);
        }
        for tri in &tris {
            for_each_fragment(tri, w, h, &TWO_SIDED, |f| {
                assert!(f.x < w && f.y < h, "({}, {}) outside {w}x{h}", f.x, f.y);
                assert!((0.0..=1.0).contains(&f.depth));
                assert!(f.bary.iter().all(|b| b.is_finite()));
            });
        }
    }
    // Not vacuous: plenty of these triangles are visible.
    assert!(drawn > 5_000, "{drawn}");
}

/// Zero-size targets give empty buffers (and never call back).
#[test]
fn zero_size_targets_return_empty_buffers() {
    let tri =
        [Vec4::new(-1.0, -1.0, 0.5, 1.0), Vec4::new(3.0, -1.0, 0.5, 1.0), Vec4::new(-1.0, 3.0, 0.5, 1.0)];
    for (w, h) in [(0, 0), (0, 10), (10, 0)] {
        let t = rasterize(&[tri], &[0], w, h, &TWO_SIDED);
        assert_eq!((t.width, t.height), (w, h));
        assert!(t.depth.is_empty() && t.id.is_empty() && t.bary.is_empty());
        assert!(coverage_count(&[tri], w, h, &TWO_SIDED).is_empty());
        for_each_fragment(&tri, w, h, &TWO_SIDED, |_| panic!("fragment in an empty target"));
    }
    let empty = rasterize(&[], &[], 5, 4, &TWO_SIDED);
    assert_eq!(empty, Target::empty(5, 4));
}

/// Zero-area triangles cover nothing: repeated vertices, collinear vertices (in clip space and
/// only after projection), a triangle edge-on to the eye, all-zero and w = 0 vertices.
#[test]
fn degenerate_triangles_cover_nothing() {
    let (w, h) = (32, 32);
    let a = Vec4::new(-0.5, -0.5, 0.5, 1.0);
    let b = Vec4::new(0.5, 0.25, 0.5, 1.0);
    let cases = [
        [a, a, a],
        [a, a, b],
        [a, b, (a + b) * 0.5],
        // Collinear on screen, not in clip space: c = 2 * midpoint (same x/w, y/w).
        [a, b, (a + b)],
        // Plane through the eye: all points on one screen line.
        [Vec4::new(0.1, 0.1, 0.2, 1.0), Vec4::new(0.3, 0.3, 0.5, 3.0), Vec4::new(-0.2, -0.2, 0.3, 2.0)],
        [Vec4::ZERO; 3],
        [Vec4::new(0.0, 0.0, 0.0, 0.0), a, b],
        [Vec4::new(1.0, 0.0, 0.0, 0.0), Vec4::new(0.0, 1.0, 0.0, 0.0), Vec4::new(1.0, 1.0, 0.0, 0.0)],
    ];
    for tri in cases {
        let count = coverage_count(&[tri], w, h, &TWO_SIDED);
        assert!(count.iter().all(|&c| c == 0), "{tri:?} covered pixels");
    }
}

/// A triangle with clip coordinates up to 1e30 covering the screen, and a screen-covering quad
/// of two such triangles (their shared edge is clipped by the guard band in both): every pixel
/// exactly once, also on the widest and tallest supported targets.
#[test]
fn huge_triangles_cover_the_screen_exactly_once() {
    let v = |x: f32, y: f32| Vec4::new(x, y, 0.5, 1.0);
    let big = 1e30f32;
    let single = vec![[v(-big, -big), v(3.0 * big, -big), v(-big, 3.0 * big)]];
    let quad = vec![[v(-big, -big), v(big, -big), v(big, 1e4)], [v(-big, -big), v(big, 1e4), v(-big, big)]];
    // Perspective-like: huge x, y with tiny w.
    let tiny_w = vec![[
        Vec4::new(-1.0, -1.0, 1e-20, 1e-20),
        Vec4::new(3.0, -1.0, 1e-20, 1e-20),
        Vec4::new(-1.0, 3.0, 1e-20, 1e-20),
    ]];
    for tris in [single, quad, tiny_w] {
        for (w, h) in [(61, 47), (MAX_TARGET_DIM, 1), (1, MAX_TARGET_DIM)] {
            let count = coverage_count(&tris, w, h, &TWO_SIDED);
            assert!(count.iter().all(|&c| c == 1), "{tris:?} at {w}x{h}");
        }
    }
}

/// Long slivers (1e4 px long, 1e-3 px thick, and thicker) in a fan that tiles a thin wedge: no
/// pixel is covered twice and the area they cover matches the wedge's, within 1 pixel per row.
#[test]
fn slivers_never_double_cover() {
    let (w, h) = (200, 100);
    // 200 triangles sharing the apex (-1e4, 50) and fanning over the right border column x = 150,
    // from y = 20 to y = 80: each is a sliver 0.3 px tall at the border and 1e4 px long.
    let apex = pixel_to_clip(-1e4, 50.0, 0.5, w, h);
    let n = 200;
    let rim = |k: u32| pixel_to_clip(150.0, 20.0 + 60.0 * f64::from(k) / f64::from(n), 0.5, w, h);
    let tris: Vec<[Vec4; 3]> = (0..n).map(|k| [apex, rim(k), rim(k + 1)]).collect();
    let count = coverage_count(&tris, w, h, &TWO_SIDED);
    assert!(count.iter().all(|&c| c <= 1));
    // The wedge is ~60 px tall across the whole visible width (the apex is 1e4 px away).
    for x in 0..150 {
        let column: u32 = (0..h).map(|y| count[(y * w + x) as usize]).sum();
        assert!((58..=61).contains(&column), "column {x}: {column}");
    }
}

/// Triangles with the reserved id are skipped.
#[test]
fn reserved_id_is_skipped() {
    let tri =
        [Vec4::new(-1.0, -1.0, 0.5, 1.0), Vec4::new(3.0, -1.0, 0.5, 1.0), Vec4::new(-1.0, 3.0, 0.5, 1.0)];
    let t = rasterize(&[tri], &[EMPTY_ID], 8, 8, &TWO_SIDED);
    assert_eq!(t, Target::empty(8, 8));
}
