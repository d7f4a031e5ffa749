//! `Rasterizer::stats`: the counts of what the last call processed.

use glam::Vec4;
use hyrt_raster::{RasterOptions, RasterStats, Rasterizer, Target};

/// A triangle in NDC at depth `z`, `w = 1`.
fn tri(p: [[f32; 2]; 3]) -> [Vec4; 3] {
    at(p, 0.5)
}

fn at(p: [[f32; 2]; 3], z: f32) -> [Vec4; 3] {
    p.map(|[x, y]| Vec4::new(x, y, z, 1.0))
}

#[test]
fn stats_count_submitted_set_up_tiny_and_binned_triangles() {
    let (w, h) = (128, 64);
    let px = |x: f32, y: f32| [x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0];
    let tris = vec![
        // A screen-covering quad: two large triangles, in all 2 x 1 tiles of 64 px.
        tri([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0]]),
        tri([[-1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]),
        // Covers the centre of pixel (10, 10) only, in front of the quad: tiny.
        at([px(10.2, 10.2), px(10.9, 10.3), px(10.4, 10.9)], 0.25),
        // Between pixel centres: dropped by setup.
        tri([px(20.6, 20.6), px(21.4, 20.6), px(20.6, 21.4)]),
        // Outside the view.
        tri([[3.0, 3.0], [4.0, 3.0], [3.0, 4.0]]),
    ];
    let ids: Vec<u32> = (0..tris.len() as u32).collect();
    let mut r = Rasterizer::new();
    assert_eq!(r.stats(), RasterStats::default());
    let mut target = Target::default();
    r.rasterize_into(&tris, &ids, w, h, &RasterOptions::default(), &mut target);
    assert_eq!(target.id[10 * w as usize + 10], 2, "the tiny triangle is drawn");
    assert_eq!(r.stats(), RasterStats { submitted: 5, set_up: 3, tiny: 1, bin_entries: 2 + 2 + 1 });
    // The counts are those of the last call only.
    r.rasterize_into(&tris[2..3], &ids[2..3], w, h, &RasterOptions::default(), &mut target);
    assert_eq!(r.stats(), RasterStats { submitted: 1, set_up: 1, tiny: 1, bin_entries: 1 });
    r.rasterize_into(&tris, &ids, 0, h, &RasterOptions::default(), &mut target);
    assert_eq!(r.stats(), RasterStats::default());
}
