//! Determinism: the buffers are byte-identical for any number of threads, any tile size and any
//! triangle order (unique ids).

mod common;

use common::{Camera, Rng, uv_sphere};
use glam::{DMat3, DVec3, Vec4};
use hyrt_raster::{RasterOptions, Target, rasterize};

/// A scene with many depth conflicts: a 20k-triangle sphere, an interpenetrating floor, a huge
/// triangle passing behind the camera, and 2000 random overlapping triangles.
fn scene() -> (Camera, Vec<[Vec4; 3]>, Vec<u32>) {
    let cam = Camera::new(DVec3::new(0.4, 0.8, 3.0), DVec3::ZERO, DVec3::Y, 55.0, 0.1, 50.0, 333, 251);
    let (verts, idx) = uv_sphere(DVec3::ZERO, 1.0, 128, 80, DMat3::from_rotation_y(0.4));
    let mut tris = cam.clip_tris(&verts, &idx);
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

fn render_with_threads(n: usize, tris: &[[Vec4; 3]], ids: &[u32], cam: &Camera) -> Target {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(|| rasterize(tris, ids, cam.width, cam.height, &RasterOptions::default()))
}

#[test]
fn identical_for_one_two_and_three_threads() {
    let (cam, tris, ids) = scene();
    let reference = bits(&render_with_threads(1, &tris, &ids, &cam));
    for n in [2, 3] {
        assert!(bits(&render_with_threads(n, &tris, &ids, &cam)) == reference, "{n} threads");
    }
}

#[test]
fn identical_for_any_tile_size() {
    let (cam, tris, ids) = scene();
    let reference = bits(&rasterize(&tris, &ids, cam.width, cam.height, &RasterOptions::default()));
    for tile_size in [8, 16, 40, 128, 4096] {
        let opts = RasterOptions { tile_size, cull_backfaces: false, reversed_z: false };
        assert!(
            bits(&rasterize(&tris, &ids, cam.width, cam.height, &opts)) == reference,
            "tile size {tile_size}"
        );
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
