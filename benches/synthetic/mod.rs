//! Synthetic inputs shared by the leaf crates' kernel benchmarks (`raster/benches`,
//! `tracer/benches`, `shadowmap/benches` include this file with `#[path]`: the leaf crates
//! share no dev-dependency crate, and a crate for 60 lines would cost more than it saves).
#![allow(dead_code)]

use std::sync::OnceLock;

use glam::Vec3;

pub use hyrt_testkit::Rng;

/// A UV sphere: `2 * slices * (stacks - 1)` triangles, each vertex `at(d)` for its unit
/// direction `d` from the centre (`|d| d` for the unit sphere at the origin).
pub fn uv_sphere(slices: u32, stacks: u32, at: impl Fn(Vec3) -> Vec3) -> Vec<[Vec3; 3]> {
    let vertex = |i: u32, j: u32| {
        let (theta, phi) = (
            j as f32 / stacks as f32 * std::f32::consts::PI,
            i as f32 / slices as f32 * std::f32::consts::TAU,
        );
        at(Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()))
    };
    let mut tris = Vec::new();
    for j in 0..stacks {
        for i in 0..slices {
            let (a, b, c, d) = (vertex(i, j), vertex(i + 1, j), vertex(i, j + 1), vertex(i + 1, j + 1));
            if j > 0 {
                tris.push([a, b, c]);
            }
            if j + 1 < stacks {
                tris.push([b, d, c]);
            }
        }
    }
    tris
}

/// The point light (or ray origin) inside [`scene`].
pub const LIGHT: Vec3 = Vec3::new(0.1, 0.2, -0.15);

/// 100k triangles around [`LIGHT`]:
///
/// * an 80k-triangle bumpy sphere of radius about 4 enclosing it (every direction covered,
///   triangles of a few texels each on a 1024 map);
/// * 20k small random triangles between 0.5 and 3.5 from it (overlapping clutter, some large
///   on the maps and tessellated).
pub fn scene() -> &'static [[Vec3; 3]] {
    static SCENE: OnceLock<Vec<[Vec3; 3]>> = OnceLock::new();
    SCENE.get_or_init(|| {
        let mut tris = uv_sphere(200, 201, |d| d * (4.0 + 0.3 * (5.0 * d.x + 3.0 * d.y * d.z).sin()));
        tris.reserve(100_000usize.saturating_sub(tris.len()));
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        while tris.len() < 100_000 {
            let dir = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
            if dir.length() < 0.1 || dir.length() > 1.0 {
                continue;
            }
            let c = LIGHT + dir.normalize() * (0.5 + 3.0 * rng.f32());
            let size = 0.02 + 0.1 * rng.f32();
            tris.push([0; 3].map(|_| c + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * size));
        }
        tris
    })
}
