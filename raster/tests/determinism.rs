//! Determinism: the buffers are byte-identical for any number of threads and any tile size, with
//! or without a depth tie window, and for any triangle order (unique ids) without one.

mod common;

use common::{Camera, Rng, uv_sphere};
use glam::{DMat3, DVec3, Vec4};
use hyrt_raster::{RasterOptions, Target, rasterize};

/// The renderer's tie window, and a wide one under which many random overlaps tie.
const TIES: [f32; 2] = [1.0 / 65536.0, 1e-2];

/// A scene with many depth conflicts: a 20k-triangle sphere, an interpenetrating floor, a huge
/// triangle passing behind the camera, 2000 random overlapping triangles, and copies of 500
/// sphere triangles with other ids, pushed out by ~1e-6 relative (ties within the windows only).
fn scene() -> (Camera, Vec<[Vec4; 3]>, Vec<u32>) {
    let cam = Camera::new(DVec3::new(0.4, 0.8, 3.0), DVec3::ZERO, DVec3::Y, 55.0, 0.1, 50.0, 333, 251);
    let (verts, idx) = uv_sphere(DVec3::ZERO, 1.0, 128, 80, DMat3::from_rotation_y(0.4));
    let mut tris = cam.clip_tris(&verts, &idx);
    let pushed: Vec<DVec3> = verts.iter().map(|&v| v * (1.0 + 1e-6)).collect();
    let copies = cam.clip_tris(&pushed, &idx[..]);
    tris.extend(copies.iter().step_by(idx.len() / 500).copied());
    let floor = |x: f64, z: f64| cam.clip(DVec3::new(x, -0.3, z));
    tris.push([floor(-50.0, 50.0), floor(50.0, 50.0), floor(0.0, -50.0)]);
    let mut rng = Rng(99);
    for _ in 0..2000 {
        let c = DVec3::new(rng.f64() * 4.0 - 2.0, rng.f64() * 2.0 - 1.0, rng.f64() * 2.0 - 1.0);
        let p =
            |rng: &mut Rng| cam.clip(c + DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * 0.6);
        tris.push([p(&mut rng), p(&mut rng), p(&mut rng)]);
    }
    let ids = (0..tris.len() as u32).collect();
    (cam, tris, ids)
}

/// Bit patterns of all buffers, so that -0.0 vs 0.0 or NaN payloads would count as differences.
fn bits(t: &Target) -> (Vec<u32>, Vec<u32>, Vec<[u32; 2]>) {
    (
        t.depth.iter().map(|d| d.to_bits()).collect(),
        t.id.clone(),
        t.bary.iter().map(|b| b.map(f32::to_bits)).collect(),
    )
}

fn render_with_threads(
    n: usize,
    tris: &[[Vec4; 3]],
    ids: &[u32],
    cam: &Camera,
    opts: &RasterOptions,
) -> Target {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(|| rasterize(tris, ids, cam.width, cam.height, opts))
}

#[test]
fn identical_for_one_two_and_three_threads() {
    let (cam, tris, ids) = scene();
    let reference = bits(&render_with_threads(1, &tris, &ids, &cam, &RasterOptions::default()));
    for n in [2, 3] {
        let t = render_with_threads(n, &tris, &ids, &cam, &RasterOptions::default());
        assert!(bits(&t) == reference, "{n} threads");
    }
}

/// With a tie window the survivor of mutually close fragments depends on their order; that order
/// is the input order in every tile, whatever the threads: still byte-identical. In both depth
/// conventions.
#[test]
fn identical_for_one_two_and_three_threads_with_a_tie_window() {
    let (cam, tris, ids) = scene();
    for reversed_z in [false, true] {
        let exact = RasterOptions { reversed_z, ..Default::default() };
        let exact = render_with_threads(1, &tris, &ids, &cam, &exact);
        for depth_tie in TIES {
            let opts = RasterOptions { reversed_z, depth_tie, ..Default::default() };
            let reference = render_with_threads(1, &tris, &ids, &cam, &opts);
            // Not vacuous: the window changes winners.
            assert!(reference.id != exact.id, "tie {depth_tie}");
            let reference = bits(&reference);
            for n in [2, 3] {
                let t = render_with_threads(n, &tris, &ids, &cam, &opts);
                assert!(bits(&t) == reference, "{n} threads, tie {depth_tie}, reversed {reversed_z}");
            }
        }
    }
}

#[test]
fn identical_for_any_tile_size() {
    let (cam, tris, ids) = scene();
    for depth_tie in [0.0, TIES[0], TIES[1]] {
        let opts = RasterOptions { depth_tie, ..Default::default() };
        let reference = bits(&rasterize(&tris, &ids, cam.width, cam.height, &opts));
        for tile_size in [8, 16, 40, 128, 4096] {
            let opts = RasterOptions { tile_size, ..opts };
            assert!(
                bits(&rasterize(&tris, &ids, cam.width, cam.height, &opts)) == reference,
                "tile size {tile_size}, tie {depth_tie}"
            );
        }
    }
}

#[test]
fn identical_for_shuffled_triangle_order() {
    let (cam, tris, ids) = scene();
    let reference = bits(&rasterize(&tris, &ids, cam.width, cam.height, &RasterOptions::default()));
    let mut rng = Rng(5);
    let mut order: Vec<usize> = (0..tris.len()).collect();
    for i in (1..order.len()).rev() {
        order.swap(i, rng.below(i + 1));
    }
    let shuffled: Vec<[Vec4; 3]> = order.iter().map(|&i| tris[i]).collect();
    let shuffled_ids: Vec<u32> = order.iter().map(|&i| ids[i]).collect();
    let t = rasterize(&shuffled, &shuffled_ids, cam.width, cam.height, &RasterOptions::default());
    assert!(bits(&t) == reference);
}

/// `RasterOptions::depth` off: no depth buffer, and the same ids and barycentrics as with it,
/// on 1 and 2 threads.
#[test]
fn without_depths_the_same_ids_and_barycentrics() {
    let (cam, tris, ids) = scene();
    let opts = RasterOptions { reversed_z: true, depth_tie: TIES[0], ..Default::default() };
    let (_, id, bary) = bits(&render_with_threads(1, &tris, &ids, &cam, &opts));
    for n in [1, 2] {
        for barycentrics in [true, false] {
            let off = RasterOptions { depth: false, barycentrics, ..opts };
            let (d, i, b) = bits(&render_with_threads(n, &tris, &ids, &cam, &off));
            assert!(d.is_empty() && i == id, "{n} threads, barycentrics {barycentrics}");
            assert!(b == if barycentrics { &bary[..] } else { &[] }, "{n} threads");
        }
    }
}

/// Triangles handed out on demand, a chunk at a time.
struct Slices<'a>(&'a [[Vec4; 3]], &'a [u32]);

impl hyrt_raster::TriangleSource for Slices<'_> {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn fill(&self, first: usize, tris: &mut [[Vec4; 3]], ids: &mut [u32]) {
        tris.copy_from_slice(&self.0[first..first + tris.len()]);
        ids.copy_from_slice(&self.1[first..first + ids.len()]);
    }
}

/// A source whose `fill` lets rayon run other work, as parallel work of its own would while it
/// waits: its thread then takes another chunk, and sets it up inside the first one's `fill`.
struct YieldingSlices<'a>(&'a [[Vec4; 3]], &'a [u32], std::sync::atomic::AtomicUsize);

impl hyrt_raster::TriangleSource for YieldingSlices<'_> {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn fill(&self, first: usize, tris: &mut [[Vec4; 3]], ids: &mut [u32]) {
        if rayon::yield_now() == Some(rayon::Yield::Executed) {
            self.2.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        tris.copy_from_slice(&self.0[first..first + tris.len()]);
        ids.copy_from_slice(&self.1[first..first + ids.len()]);
    }
}

#[test]
fn a_source_may_run_other_work_while_filling() {
    let (cam, tris, ids) = scene();
    let opts = RasterOptions::default();
    let reference = bits(&rasterize(&tris, &ids, cam.width, cam.height, &opts));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let source = YieldingSlices(&tris, &ids, Default::default());
    let mut target = Target::default();
    let mut r = hyrt_raster::Rasterizer::new();
    pool.install(|| r.rasterize_from(&source, cam.width, cam.height, &opts, &mut target));
    assert!(bits(&target) == reference);
    // Not vacuous: some chunk was set up inside another's `fill`.
    assert!(source.2.into_inner() > 0, "no fill ran other work");
}

/// `Rasterizer::rasterize_from` gives the buffers of `rasterize` with the same triangles in
/// slices, on 1 to 3 threads, into a target that held another frame.
#[test]
fn triangles_from_a_source_give_the_same_buffers() {
    let (cam, tris, ids) = scene();
    for opts in [
        RasterOptions::default(),
        RasterOptions { reversed_z: true, depth_tie: TIES[0], barycentrics: false, ..Default::default() },
    ] {
        let reference = bits(&rasterize(&tris, &ids, cam.width, cam.height, &opts));
        for n in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
            let mut r = hyrt_raster::Rasterizer::new();
            let mut target = Target::default();
            pool.install(|| {
                r.rasterize_from(
                    &Slices(&tris[..100], &ids[..100]),
                    cam.width,
                    cam.height,
                    &opts,
                    &mut target,
                );
                r.rasterize_from(&Slices(&tris, &ids), cam.width, cam.height, &opts, &mut target);
            });
            assert!(bits(&target) == reference, "{n} threads, {opts:?}");
            assert_eq!(r.stats().submitted, tris.len());
        }
    }
}

/// One `Rasterizer` reused for a sequence of calls (a light map's pages: one-tile targets, whose
/// z-buffer the rasterizer keeps) gives each call the buffers of a fresh one: alternating
/// scenes, sizes, depth orders and tie windows, so that anything left from a call would show.
#[test]
fn a_reused_rasterizer_gives_each_call_a_fresh_ones_buffers() {
    let (cam, tris, ids) = scene();
    let mut kept = hyrt_raster::Rasterizer::new();
    let mut target = Target::empty(0, 0);
    let half = tris.len() / 2;
    let calls = [
        (0..tris.len(), 4096, false, 0.0, true),
        (0..half, 4096, true, TIES[1], false),
        (half..tris.len(), 64, true, TIES[0], true),
        (0..half, 4096, false, TIES[0], false),
        (half..tris.len(), 4096, true, 0.0, true),
    ];
    for (k, (range, tile_size, reversed_z, depth_tie, depth)) in calls.into_iter().enumerate() {
        let opts = RasterOptions { tile_size, reversed_z, depth_tie, depth, ..Default::default() };
        let (t, i) = (&tris[range.clone()], &ids[range]);
        kept.rasterize_into(t, i, cam.width, cam.height, &opts, &mut target);
        let fresh = rasterize(t, i, cam.width, cam.height, &opts);
        assert!(bits(&target) == bits(&fresh), "call {k}");
    }
}
