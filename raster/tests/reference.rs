//! `rasterize` against a straightforward reference z-buffer built from `for_each_fragment`: every
//! fragment depth-tested in input order with the documented rule (with and without a tie window),
//! its barycentrics stored when it wins. `rasterize` defers barycentrics to the winners and runs
//! vector kernels; the buffers must be bit-identical anyway.

mod common;

use common::{Camera, Rng, uv_sphere};
use glam::{DMat3, DVec3, Vec4};
use hyrt_raster::{EMPTY_DEPTH_REVERSED, EMPTY_ID, RasterOptions, Target, for_each_fragment, rasterize};

fn reference(tris: &[[Vec4; 3]], ids: &[u32], w: u32, h: u32, opts: &RasterOptions) -> Target {
    let mut t = Target::empty(w, h);
    if opts.reversed_z {
        t.depth.fill(EMPTY_DEPTH_REVERSED);
    }
    // Whether each pixel's winner is a back face (the empty entry loses every tie).
    let mut back = vec![true; t.id.len()];
    for (tri, &id) in tris.iter().zip(ids) {
        if id == EMPTY_ID {
            continue;
        }
        for_each_fragment(tri, w, h, opts, |f| {
            let i = t.index(f.x, f.y);
            let cur = t.depth[i];
            let closer = if opts.reversed_z { f.depth > cur } else { f.depth < cur };
            // The documented rule, straight from `RasterOptions::depth_tie`.
            let tie = if opts.depth_tie > 0.0 {
                (f.depth - cur).abs() <= opts.depth_tie * f.depth.abs().max(cur.abs())
            } else {
                f.depth == cur
            };
            // Ties: front faces first, then the smaller id.
            if if tie { (f.back, id) < (back[i], t.id[i]) } else { closer } {
                back[i] = f.back;
                t.depth[i] = f.depth;
                t.id[i] = id;
                t.bary[i] = f.bary;
            }
        });
    }
    t
}

fn bits(t: &Target) -> (Vec<u32>, Vec<u32>, Vec<[u32; 2]>) {
    (
        t.depth.iter().map(|d| d.to_bits()).collect(),
        t.id.clone(),
        t.bary.iter().map(|b| b.map(f32::to_bits)).collect(),
    )
}

/// A sphere, an interpenetrating floor passing behind the camera, random overlapping triangles
/// of all sizes, duplicates (depth ties), copies moved by ~1e-6 relative (ties in a window), and
/// copies with the opposite winding (ties between front and back faces).
fn scene(cam: &Camera) -> (Vec<[Vec4; 3]>, Vec<u32>) {
    let (verts, idx) = uv_sphere(DVec3::ZERO, 1.0, 96, 60, DMat3::from_rotation_y(0.3));
    let mut tris = cam.clip_tris(&verts, &idx);
    let floor = |x: f64, z: f64| cam.clip(DVec3::new(x, -0.4, z));
    tris.push([floor(-80.0, 80.0), floor(80.0, 80.0), floor(0.0, -80.0)]);
    let mut rng = Rng(7);
    for i in 0..3000 {
        let c = DVec3::new(rng.f64() * 5.0 - 2.5, rng.f64() * 3.0 - 1.5, rng.f64() * 3.0 - 1.5);
        let s = [0.01, 0.05, 0.3, 1.5][i % 4];
        let mut p = || cam.clip(c + DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * s);
        tris.push([p(), p(), p()]);
    }
    for i in (0..2000).step_by(13) {
        tris.push(tris[i]);
    }
    for i in (0..2000).step_by(7) {
        tris.push(tris[i].map(|v| v * (1.0 + 1e-6 * (1.0 + i as f32 / 2000.0))));
    }
    // Copies with the opposite winding (ties between a front and a back face).
    for i in (0..2000).step_by(11) {
        let [a, b, c] = tris[i];
        tris.push([a, c, b]);
    }
    // Ids in scrambled order (ties go either way), some repeated, some empty.
    let n = tris.len() as u64;
    let ids = (0..n)
        .map(|i| match i % 17 {
            5 => EMPTY_ID,
            9 => 42,
            _ => (i * 7919 % n) as u32,
        })
        .collect();
    (tris, ids)
}

#[test]
fn rasterize_matches_the_fragment_reference() {
    let cam = Camera::new(DVec3::new(0.3, 0.6, 3.2), DVec3::ZERO, DVec3::Y, 60.0, 0.1, 100.0, 301, 227);
    let (tris, ids) = scene(&cam);
    for reversed_z in [false, true] {
        for (tile_size, cull_backfaces) in [(64, false), (16, true)] {
            for depth_tie in [0.0, 1.0 / 65536.0, 1e-2] {
                let opts = RasterOptions {
                    tile_size,
                    cull_backfaces,
                    reversed_z,
                    depth_tie,
                    barycentrics: true,
                    depth: true,
                    rivals: false,
                };
                let expected = reference(&tris, &ids, cam.width, cam.height, &opts);
                let covered = expected.id.iter().filter(|&&id| id != EMPTY_ID).count();
                assert!(covered > 20_000, "{covered} covered pixels");
                let got = rasterize(&tris, &ids, cam.width, cam.height, &opts);
                assert!(bits(&got) == bits(&expected), "{opts:?}");
            }
        }
    }
}
