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

#[path = "../../benches/synthetic/mod.rs"]
mod synthetic;

use divan::Bencher;
use glam::Vec3;
use hyrt_shadowmap::{LightMap, MapKind, MapOptions};
use synthetic::{LIGHT, Rng, scene};

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

/// 64k points on the scene's surfaces with their triangle ids: random points of the triangles
/// that random texels of a cube map show (mostly lit, some shadowed by the clutter). Fixed for
/// every benchmark below.
fn points() -> &'static [(Vec3, u32)] {
    static P: OnceLock<Vec<(Vec3, u32)>> = OnceLock::new();
    P.get_or_init(|| {
        let tris = scene();
        let map = build(tris, MapKind::Cube, 1024);
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        let mut out = Vec::with_capacity(1 << 16);
        while out.len() < 1 << 16 {
            // A random texel's surface point: the triangle it stores, at its centre's direction.
            let d = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0).normalize_or(Vec3::X);
            let c = map.coord(d);
            let id = map.id(c.face, c.x as u32, c.y as u32);
            if id == hyrt_shadowmap::EMPTY {
                continue;
            }
            let [a, b, e] = tris[id as usize];
            let (u, v) = (rng.f32(), rng.f32());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            out.push((a + (b - a) * u + (e - a) * v, id));
        }
        out
    })
}

fn planes() -> &'static [hyrt_shadowmap::classify::Plane] {
    static P: OnceLock<Vec<hyrt_shadowmap::classify::Plane>> = OnceLock::new();
    P.get_or_init(|| hyrt_shadowmap::classify::triangle_planes(scene()))
}

/// Map lookup and three-way classification ([`Classifier::classify`]) of 64k surface points
/// against a 1024 map, in random order (cache-unfriendly, as at mirror hits; the screen-space
/// pass visits neighbouring texels together and is faster); divan prints lookups/s (one core).
#[divan::bench(args = ["cube", "paraboloid"])]
fn classify(bencher: Bencher, kind: &str) {
    use hyrt_shadowmap::classify::Classifier;
    let kind = if kind == "cube" { MapKind::Cube } else { MapKind::Paraboloid };
    static MAPS: OnceLock<[LightMap; 2]> = OnceLock::new();
    let maps =
        MAPS.get_or_init(|| [build(scene(), MapKind::Cube, 1024), build(scene(), MapKind::Paraboloid, 1024)]);
    let map = &maps[usize::from(kind == MapKind::Paraboloid)];
    let cls = Classifier {
        map,
        planes: planes(),
        bias: 1.0,
        point_error: hyrt_shadowmap::classify::point_error_bound(scene()),
        cutouts: &[],
    };
    let pts = points();
    bencher.counter(divan::counter::ItemsCount::new(pts.len())).bench_local(|| {
        pts.iter()
            .filter(|(p, id)| cls.classify(*p, *id).decision == hyrt_shadowmap::classify::Decision::Lit)
            .count()
    });
}

/// Border detection on a 640x480 occlusion map (a disc of shadow with a ragged edge and
/// scattered thin occluders): the Laplacian, and dilation by 1 and 3 pixels; pixels/s.
#[divan::bench(args = [0, 1, 3])]
fn borders(bencher: Bencher, dilate: usize) {
    use Decision::{Lit as LIT, NotNeeded as NONE, Shadow as SHADOW};
    use hyrt_shadowmap::border::{Decision, dilate as grow, laplacian_border};
    let (w, h) = (640usize, 480usize);
    let mut rng = Rng(7);
    let occ: Vec<Decision> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 - 320.0, (i / w) as f32 - 240.0);
            let r = (x * x + y * y).sqrt() + 8.0 * (x.atan2(y) * 7.0).sin();
            match rng.f32() {
                v if v < 0.02 => NONE,
                v if v < 0.05 => SHADOW,
                _ if r < 150.0 => SHADOW,
                _ => LIT,
            }
        })
        .collect();
    bencher.counter(divan::counter::ItemsCount::new(w * h)).bench(|| {
        let b = laplacian_border(&occ, w, h);
        if dilate > 0 { grow(&b, w, h, dilate) } else { b }
    });
}

/// 45 VPLs on the sphere, facing inwards, one 256x256 paraboloid hemisphere map each (the
/// renderer's interactive setting).
fn vpl_maps() -> &'static [LightMap] {
    static VPLS: OnceLock<Vec<LightMap>> = OnceLock::new();
    VPLS.get_or_init(|| {
        let mut rng = Rng(99);
        (0..45)
            .map(|_| {
                let d = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0).normalize_or(Vec3::Y);
                let opts = MapOptions { kind: MapKind::Paraboloid, resolution: 256, tess_texels: 8.0 };
                LightMap::build_hemisphere(scene(), d * 3.5, -d, &opts)
            })
            .collect()
    })
}

/// VPL gather: visibility of 4096 surface points from each of [`vpl_maps`], by lookup alone,
/// the texel under each point deciding (the thesis); divan prints point-VPL lookups/s (one
/// core).
#[divan::bench(sample_count = 20)]
fn vpl_gather(bencher: Bencher) {
    let (maps, pts) = (vpl_maps(), &points()[..4096]);
    bencher.counter(divan::counter::ItemsCount::new(pts.len() * maps.len())).bench_local(|| {
        let mut seen = 0usize;
        for map in maps {
            let cls = vpl_classifier(map);
            seen += pts.iter().filter(|(p, id)| cls.visible(*p, *id)).count();
        }
        seen
    });
}

/// The classifier of a VPL map of [`vpl_maps`], with the renderer's VPL bias.
fn vpl_classifier(map: &hyrt_shadowmap::LightMap) -> hyrt_shadowmap::classify::Classifier<'_> {
    hyrt_shadowmap::classify::Classifier {
        map,
        planes: planes(),
        bias: 0.5,
        point_error: hyrt_shadowmap::classify::point_error_bound(scene()),
        cutouts: &[],
    }
}

/// [`vpl_gather`] with the renderer's default lookups: the 2x2 texels around each point,
/// bilinearly weighted (percentage-closer filtering). A separate function, not an argument:
/// one closure holding both lookups measured the texel one 20 % slower (other inlining).
#[divan::bench(sample_count = 20)]
fn vpl_gather_bilinear(bencher: Bencher) {
    let (maps, pts) = (vpl_maps(), &points()[..4096]);
    bencher.counter(divan::counter::ItemsCount::new(pts.len() * maps.len())).bench_local(|| {
        let mut sum = 0.0f32;
        for map in maps {
            let cls = vpl_classifier(map);
            sum += pts.iter().map(|(p, id)| cls.visibility_at(*p, *id, cls.locate(*p))).sum::<f32>();
        }
        sum
    });
}
