//! Time per 640x480 frame of [`Rasterizer::rasterize_into`] on synthetic scenes, with the options
//! a renderer uses (reversed-Z, two-sided, the tracer's `2^-16` depth tie window, buffers kept
//! from frame to frame), with and without barycentrics (argument `bary`), on the global rayon pool
//! (one thread per core):
//!
//! * `sphere`: a 100k-triangle sphere filling the middle of the screen (setup-bound: small
//!   triangles, a few pixels each);
//! * `quads`: 6 layers of 8x6 overlapping quads covering the screen (fill-bound: large triangles,
//!   6 fragments per pixel);
//! * `tiny`: 200k random sub-pixel to 3-pixel triangles over the whole screen;
//! * `offscreen`: 300k small triangles, four fifths of them outside the view (trivial rejection),
//!   plus two huge floor triangles crossing the near plane (clipping, guard band).
//!
//! * `map_1024`: a shadow-map face: the inside of a 100k-triangle sphere seen from its centre
//!   through a 90-degree square frustum at 1024x1024 (a sixth of the triangles in view, each a
//!   few texels).
//!
//! divan prints input triangles per second (`item/s`) beside the time per frame.
//! Run with `cargo bench -p hyrt-raster`.

#[path = "../../benches/synthetic/mod.rs"]
mod synthetic;

use divan::Bencher;
use glam::{Mat4, Vec3, Vec4};
use hyrt_raster::{RasterOptions, Rasterizer, Target};
use synthetic::Rng;

const WIDTH: u32 = 640;
const HEIGHT: u32 = 480;

fn main() {
    divan::main();
}

/// Reversed-Z infinite perspective looking down -z from `eye`, 60 degrees vertical field of view.
fn camera(eye: Vec3, target: Vec3) -> Mat4 {
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let proj = glam::camera::rh::proj::directx::perspective_infinite_reverse(60f32.to_radians(), aspect, 0.1);
    proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y)
}

fn transform(view_proj: &Mat4, world: &[[Vec3; 3]]) -> Vec<[Vec4; 3]> {
    world.iter().map(|t| t.map(|p| *view_proj * p.extend(1.0))).collect()
}

fn scene_sphere() -> Vec<[Vec4; 3]> {
    let view_proj = camera(Vec3::new(0.0, 0.0, 3.2), Vec3::ZERO);
    transform(&view_proj, &synthetic::uv_sphere(250, 201, |d| d))
}

fn scene_quads() -> Vec<[Vec4; 3]> {
    let view_proj = camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO);
    let mut world = Vec::new();
    for layer in 0..6 {
        let z = -(layer as f32) * 0.7;
        for qy in 0..6 {
            for qx in 0..8 {
                // Each quad overlaps its neighbours by half its size; the grid covers the view.
                let (x, y) = (qx as f32 * 2.0 - 8.0 + layer as f32 * 0.3, qy as f32 * 2.0 - 6.0);
                let p = |dx: f32, dy: f32| Vec3::new(x + dx, y + dy, z);
                world.push([p(0.0, 0.0), p(3.0, 0.0), p(0.0, 3.0)]);
                world.push([p(3.0, 0.0), p(3.0, 3.0), p(0.0, 3.0)]);
            }
        }
    }
    transform(&view_proj, &world)
}

fn scene_tiny() -> Vec<[Vec4; 3]> {
    let view_proj = camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO);
    let mut rng = Rng(1);
    let world: Vec<_> = (0..200_000)
        .map(|_| {
            let c = Vec3::new(rng.f32() * 12.0 - 6.0, rng.f32() * 9.0 - 4.5, rng.f32() * -5.0);
            let mut p = || c + Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 0.06;
            [p(), p(), p()]
        })
        .collect();
    transform(&view_proj, &world)
}

fn scene_offscreen() -> Vec<[Vec4; 3]> {
    let view_proj = camera(Vec3::new(0.0, 1.5, 0.0), Vec3::new(0.0, 1.5, -1.0));
    let mut rng = Rng(2);
    let mut world: Vec<_> = (0..300_000)
        .map(|_| {
            let angle = rng.f32() * std::f32::consts::TAU;
            let r = 2.0 + rng.f32() * 30.0;
            let c = Vec3::new(angle.cos() * r, rng.f32() * 3.0, angle.sin() * r);
            let mut p = || c + Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 0.2;
            [p(), p(), p()]
        })
        .collect();
    let floor = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    world.push([floor(-500.0, 500.0), floor(500.0, 500.0), floor(0.0, -500.0)]);
    world.push([floor(-500.0, -500.0), floor(500.0, -500.0), floor(0.0, 500.0)]);
    transform(&view_proj, &world)
}

fn bench(bencher: Bencher, tris: Vec<[Vec4; 3]>, bary: bool) {
    bench_size(bencher, tris, bary, WIDTH, HEIGHT);
}

fn bench_size(bencher: Bencher, tris: Vec<[Vec4; 3]>, bary: bool, width: u32, height: u32) {
    let ids: Vec<u32> = (0..tris.len() as u32).collect();
    let opts = RasterOptions {
        reversed_z: true,
        depth_tie: 1.0 / 65536.0,
        barycentrics: bary,
        ..Default::default()
    };
    let (mut r, mut target) = (Rasterizer::new(), Target::default());
    bencher.counter(divan::counter::ItemsCount::new(tris.len())).bench_local(|| {
        r.rasterize_into(divan::black_box(&tris), &ids, width, height, &opts, &mut target);
        divan::black_box(&target);
    });
}

#[divan::bench(args = [false, true])]
fn sphere_100k(bencher: Bencher, bary: bool) {
    bench(bencher, scene_sphere(), bary);
}

#[divan::bench(args = [false, true])]
fn quads_fill(bencher: Bencher, bary: bool) {
    bench(bencher, scene_quads(), bary);
}

#[divan::bench(args = [false, true])]
fn tiny_200k(bencher: Bencher, bary: bool) {
    bench(bencher, scene_tiny(), bary);
}

#[divan::bench(args = [false, true])]
fn offscreen_300k(bencher: Bencher, bary: bool) {
    bench(bencher, scene_offscreen(), bary);
}

#[divan::bench(args = [false, true])]
fn map_1024(bencher: Bencher, bary: bool) {
    let proj = glam::camera::rh::proj::directx::perspective_infinite_reverse(90f32.to_radians(), 1.0, 0.01);
    let view_proj = proj * glam::camera::rh::view::look_at_mat4(Vec3::ZERO, Vec3::Z, Vec3::Y);
    bench_size(bencher, transform(&view_proj, &synthetic::uv_sphere(250, 201, |d| d)), bary, 1024, 1024);
}
