//! Time to build a point light's depth map ([`LightMap::build`], all faces) at 512 and 1024
//! texels per face, cube and dual paraboloid (8-texel tessellation), on the global rayon pool
//! (one thread per core), for a synthetic scene of 100k triangles around the light:
//!
//! * an 80k-triangle bumpy sphere of radius about 4 enclosing the light (every texel covered,
//!   triangles of a few texels each at 1024);
//! * 20k small random triangles between 0.5 and 3.5 from the light (overlapping clutter, some
//!   large on the maps and tessellated).
//!
//! Run with `cargo bench -p hyrt-shadowmap`. The scene's triangle counts after culling and
//! tessellation are printed first.

use std::sync::OnceLock;

use divan::Bencher;
use glam::Vec3;
use hyrt_shadowmap::{LightMap, MapKind, MapOptions};

const LIGHT: Vec3 = Vec3::new(0.1, 0.2, -0.15);

fn main() {
    let tris = scene();
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        for res in [512, 1024] {
            let map = build(tris, kind, res);
            println!(
                "{kind:?} {res}: {} input triangles, {} rasterized, {} MB of texels",
                tris.len(),
                map.triangles_drawn(),
                map.memory_bytes() >> 20
            );
        }
    }
    divan::main();
}

fn build(tris: &[[Vec3; 3]], kind: MapKind, resolution: u32) -> LightMap {
    let faces = vec![true; LightMap::face_count(kind)];
    LightMap::build(tris, LIGHT, &MapOptions { kind, resolution, tess_texels: 8.0 }, &faces)
}

/// A deterministic PRNG (xorshift64*), uniform in `[0, 1)`.
struct Rng(u64);

impl Rng {
    fn f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn scene() -> &'static [[Vec3; 3]] {
    static SCENE: OnceLock<Vec<[Vec3; 3]>> = OnceLock::new();
    SCENE.get_or_init(|| {
        let (slices, stacks) = (200u32, 201u32);
        let vertex = |i: u32, j: u32| {
            let (theta, phi) = (
                j as f32 / stacks as f32 * std::f32::consts::PI,
                i as f32 / slices as f32 * std::f32::consts::TAU,
            );
            let d = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            d * (4.0 + 0.3 * (5.0 * d.x + 3.0 * d.y * d.z).sin())
        };
        let mut tris = Vec::with_capacity(100_000);
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

#[divan::bench(args = [512, 1024], sample_count = 10)]
fn cube(bencher: Bencher, resolution: u32) {
    let tris = scene();
    bencher.bench(|| build(tris, MapKind::Cube, resolution));
}

#[divan::bench(args = [512, 1024], sample_count = 10)]
fn paraboloid(bencher: Bencher, resolution: u32) {
    let tris = scene();
    bencher.bench(|| build(tris, MapKind::Paraboloid, resolution));
}
