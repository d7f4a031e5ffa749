//! The tracer's kernels on a synthetic 100k-triangle scene (a bumpy sphere of 80k triangles
//! around the origin plus 20k small random triangles inside it), on the calling thread (one
//! core: rays/s per core; the renderer runs one such loop per core):
//!
//! * `bvh_build`: [`Tracer::build`] (obvhs CWBVH, parallel inside, on the global rayon pool);
//! * `closest_hit`: 64k coherent camera rays from inside the sphere (a 256x256 view);
//! * `occlusion`: 64k shadow rays from points on the sphere to a point light inside it
//!   (some blocked by the clutter), without and with a correct occluder hint.
//!
//! divan prints rays/s (`item/s`) beside the time: comparable across commits.
//! Run with `cargo bench -p hyrt-tracer`.

use std::sync::OnceLock;

#[path = "../../benches/synthetic/mod.rs"]
mod synthetic;

use divan::{Bencher, counter::ItemsCount};
use glam::Vec3;
use hyrt_tracer::{Ray, RayCounts, RayKind, Tracer};
use synthetic::{LIGHT, scene};

fn main() {
    divan::main();
}

fn tracer() -> &'static Tracer {
    static T: OnceLock<Tracer> = OnceLock::new();
    T.get_or_init(|| Tracer::build(scene()))
}

const SIDE: u32 = 256;

/// Camera rays of a 90-degree view from near the centre, looking along +x.
fn camera_rays() -> Vec<Ray> {
    let eye = Vec3::new(-1.0, 0.3, 0.2);
    (0..SIDE * SIDE)
        .map(|i| {
            let (x, y) = ((i % SIDE) as f32 + 0.5, (i / SIDE) as f32 + 0.5);
            let (u, v) = (2.0 * x / SIDE as f32 - 1.0, 1.0 - 2.0 * y / SIDE as f32);
            Ray::new(eye, Vec3::new(1.0, v, u).normalize(), f32::INFINITY)
        })
        .collect()
}

/// Shadow rays from the camera rays' hits towards the light, and the occluder of each (the
/// triangle a full traversal finds, as a map's hint would give), or `u32::MAX`.
fn shadow_rays() -> &'static (Vec<Ray>, Vec<u32>) {
    static S: OnceLock<(Vec<Ray>, Vec<u32>)> = OnceLock::new();
    S.get_or_init(|| {
        let t = tracer();
        let mut c = RayCounts::default();
        let mut rays = Vec::new();
        let mut hints = Vec::new();
        for r in camera_rays() {
            let Some(h) = t.closest_hit(&r, RayKind::Primary, &mut c) else { continue };
            let p = r.origin + r.dir * h.t * (1.0 - 1e-4);
            let to = LIGHT - p;
            let ray = Ray::new(p, to.normalize(), to.length() * (1.0 - 1e-4));
            let hint = t.closest_hit(&ray, RayKind::Primary, &mut c).map_or(u32::MAX, |h| h.tri);
            rays.push(ray);
            hints.push(hint);
        }
        (rays, hints)
    })
}

#[divan::bench(sample_count = 10)]
fn bvh_build(bencher: Bencher) {
    let tris = scene();
    bencher.counter(ItemsCount::new(tris.len())).bench(|| Tracer::build(tris));
}

#[divan::bench]
fn closest_hit(bencher: Bencher) {
    let (t, rays) = (tracer(), camera_rays());
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        let mut c = RayCounts::default();
        rays.iter().filter(|r| t.closest_hit(r, RayKind::Primary, &mut c).is_some()).count()
    });
}

#[divan::bench(args = [false, true])]
fn occlusion(bencher: Bencher, with_hint: bool) {
    let (t, (rays, hints)) = (tracer(), shadow_rays());
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        let mut c = RayCounts::default();
        if with_hint {
            rays.iter().zip(hints).filter(|(r, h)| t.occluded_with_hint(r, **h, &mut c)).count()
        } else {
            rays.iter().filter(|r| t.occluded(r, RayKind::Shadow, &mut c)).count()
        }
    });
}
