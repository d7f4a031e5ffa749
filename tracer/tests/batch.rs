//! The batched plane hits (`Tracer::hits_on_row`) against the scalar reference
//! (`Tracer::hit_on_plane`, one ray at a time): bit-identical for every kernel this machine
//! can run, on random and on adversarial rays and triangles.

use glam::{Vec3, vec3};
use hyrt_tracer::{Hit, Isa, RowRays, Tracer};

use hyrt_testkit::Rng;

/// A point with each coordinate uniform in `[-r, r)`.
fn vec(rng: &mut Rng, r: f32) -> Vec3 {
    vec3(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
}

/// A hit as bits, so that `-0.0` and `0.0` (or two NaNs) are told apart.
fn bits(h: Option<Hit>) -> Option<(u32, u32, [u32; 3])> {
    h.map(|h| (h.t.to_bits(), h.tri, h.bary.map(f32::to_bits)))
}

#[derive(Default, Debug)]
struct Seen {
    lanes: usize,
    hits: usize,
    misses: usize,
    /// Hits with a barycentric exactly zero: the ray met an edge exactly, which the triangle
    /// test settles by re-evaluating its edge functions in f64.
    on_edge: usize,
}

/// Runs every available kernel on one row and compares each lane with the scalar reference.
fn check(tracer: &Tracer, rays: &RowRays, x0: u32, ids: &[u32], seen: &mut Seen) {
    let n = tracer.triangle_count();
    let reference: Vec<Option<Hit>> = (x0..)
        .zip(ids)
        .map(|(x, &id)| if (id as usize) < n { tracer.hit_on_plane(id, &rays.ray(x)) } else { None })
        .collect();
    let misses = ids.iter().zip(&reference).filter(|(id, h)| (**id as usize) < n && h.is_none()).count();
    for kernel in Isa::available() {
        // Stale values in `out` must not leak into the result.
        let mut out = vec![Some(Hit { t: -1.0, tri: 7, bary: [9.0; 3] }); ids.len()];
        let m = tracer.hits_on_row_with(kernel, rays, x0, ids, &mut out);
        for (i, (a, b)) in out.iter().zip(&reference).enumerate() {
            assert_eq!(
                bits(*a),
                bits(*b),
                "{kernel:?}, lane {i} (column {}, id {}) of {rays:?}: {a:?} != {b:?}",
                x0 + i as u32,
                ids[i]
            );
        }
        assert_eq!(m, misses, "{kernel:?}: miss count");
    }
    seen.lanes += ids.len();
    seen.hits += reference.iter().flatten().count();
    seen.misses += misses;
    seen.on_edge += reference.iter().flatten().filter(|h| h.bary.contains(&0.0)).count();
}

fn kernels_note() {
    Isa::for_tests("row kernels");
}

/// An n x n grid of quads in the plane z = 0 over [0, n]^2, two triangles each.
fn grid(n: usize) -> Vec<[Vec3; 3]> {
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f32, j as f32);
            let (a, b, c, d) =
                (vec3(x, y, 0.0), vec3(x + 1.0, y, 0.0), vec3(x + 1.0, y + 1.0, 0.0), vec3(x, y + 1.0, 0.0));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    t
}

/// The ids a rasterizer would write: runs of one triangle, some empty pixels.
fn runs(rng: &mut Rng, len: usize, n: u32, max_run: u64) -> Vec<u32> {
    let mut ids = Vec::with_capacity(len);
    while ids.len() < len {
        let id = match rng.below(10) {
            0 => u32::MAX,
            1 => n + rng.below(3) as u32,
            _ => rng.below(n as usize) as u32,
        };
        let run = 1 + rng.below(max_run as usize);
        ids.extend(std::iter::repeat_n(id, run.min(len - ids.len())));
    }
    ids
}

/// Random triangles, directions, row lengths, offsets and id patterns; coherent rows (a
/// camera's small angular step, long runs of one triangle) and wild ones (every lane a
/// different axis permutation and triangle).
#[test]
fn random_rows_are_bit_identical_to_single_rays() {
    kernels_note();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut seen = Seen::default();
    for scene in 0..12 {
        // Scene sizes from millimetres to kilometres: the tracer's internal scale differs.
        let size = [1e-3f32, 1.0, 7.0, 3e3][scene % 4];
        let mut tris: Vec<[Vec3; 3]> = (0..300)
            .map(|_| {
                let c = vec(&mut rng, size);
                let r = size * rng.range(0.01, 0.5);
                [c + vec(&mut rng, r), c + vec(&mut rng, r), c + vec(&mut rng, r)]
            })
            .collect();
        // Degenerate ones: a point, a segment, collinear points; and non-finite ones.
        let p = vec(&mut rng, size);
        tris.push([p, p, p]);
        tris.push([p, p + Vec3::X * size, p]);
        tris.push([p, p + Vec3::Y * size, p + Vec3::Y * size * 2.0]);
        tris.push([p, vec3(f32::NAN, 0.0, 0.0), p + Vec3::Z]);
        tris.push([p, vec3(f32::INFINITY, 1.0, 0.0), p + Vec3::Z]);
        let tracer = Tracer::build(&tris);
        let n = tris.len() as u32;
        for row in 0..150 {
            let wild = row % 3 == 0;
            let rays = RowRays {
                origin: vec(&mut rng, size * 1.5),
                forward: vec(&mut rng, 1.0) * if row % 7 == 0 { 1e-3 } else { 1.0 },
                right: vec(&mut rng, 1.0),
                row_offset: vec(&mut rng, 0.5),
                two_over_w: if wild { rng.range(0.1, 1.0) } else { 2.0 / rng.range(100.0, 2000.0) },
                tan_x: rng.range(0.05, 3.0),
                tmax: match row % 5 {
                    0 => rng.range(0.0, 3.0 * size),
                    1 => f32::MAX,
                    _ => f32::INFINITY,
                },
            };
            let len = rng.below(70);
            let x0 = rng.below(3000) as u32;
            let ids: Vec<u32> = match row % 4 {
                // One triangle for all lanes (the vector kernels broadcast it).
                0 => vec![rng.below(n as usize) as u32; len],
                // Every lane its own (gathered).
                1 => (0..len).map(|_| rng.below(n as usize + 2) as u32).collect(),
                _ => runs(&mut rng, len, n, if wild { 3 } else { 40 }),
            };
            check(&tracer, &rays, x0, &ids, &mut seen);
        }
    }
    eprintln!("{seen:?}");
    assert!(seen.hits > 10_000 && seen.misses > 1_000, "{seen:?}");
}

/// Origins a hair's breadth from the triangle's plane: `t` is then of the order of the
/// rounding bound below which the test rejects a hit as possibly behind the origin (pbrt-v4's
/// conservative `t > 0`), so the vector kernels' bound is exercised where it decides. (A bound
/// too small by a thousandth fails here; one too large cannot give a wrong hit, only send
/// lanes to the scalar path. Single-ulp differences would need `t` within an ulp of the bound,
/// which random rays practically never are; the code mirrors the scalar order of operations.)
#[test]
fn origins_next_to_the_plane_are_bit_identical() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut seen = Seen::default();
    for scene in 0..6 {
        let size = [0.01f32, 1.0, 500.0][scene % 3];
        let tris: Vec<[Vec3; 3]> =
            (0..64).map(|_| [vec(&mut rng, size), vec(&mut rng, size), vec(&mut rng, size)]).collect();
        let tracer = Tracer::build(&tris);
        for _ in 0..400 {
            let id = rng.below(tris.len()) as u32;
            let [a, b, c] = tris[id as usize];
            let n = (b - a).cross(c - a).normalize();
            let (u, v) = (rng.f32(), rng.f32());
            let on_plane = a + (b - a) * u + (c - a) * v;
            // From 2^-26 to 2^-14 of the scene's size off the plane, on either side.
            let off = size * 2f32.powf(-rng.range(14.0, 26.0)) * if rng.below(2) == 0 { 1.0 } else { -1.0 };
            let rays = RowRays {
                origin: on_plane + n * off,
                forward: -n * off.signum() + vec(&mut rng, 0.7),
                right: vec(&mut rng, 1.0),
                row_offset: Vec3::ZERO,
                two_over_w: 2.0 / rng.range(50.0, 500.0),
                tan_x: rng.range(0.1, 1.5),
                tmax: f32::INFINITY,
            };
            let ids = vec![id; 1 + rng.below(40)];
            check(&tracer, &rays, rng.below(100) as u32, &ids, &mut seen);
        }
    }
    eprintln!("{seen:?}");
    assert!(seen.hits > 1000 && seen.misses > 1000, "{seen:?}");
}

/// Rays along the axes onto an axis-aligned grid with integer vertices: most rays pass
/// exactly through edges and vertices, where the edge functions are exactly zero and the
/// triangle test decides in f64 (the vector kernels hand those lanes to the scalar path).
#[test]
fn rays_exactly_through_edges_and_vertices_are_bit_identical() {
    let tracer = Tracer::build(&grid(8));
    let n = tracer.triangle_count() as u32;
    let mut seen = Seen::default();
    for (origin, right) in [
        (vec3(3.0, 3.0, 10.0), vec3(1.0, 0.0, 0.0)),
        (vec3(3.0, 3.0, 10.0), vec3(0.0, 1.0, 0.0)),
        (vec3(1.0, 1.0, 4.0), vec3(1.0, 1.0, 0.0)),
        (vec3(2.0, 5.0, 8.0), vec3(1.0, -1.0, 0.0)),
        (vec3(0.0, 0.0, 2.0), vec3(1.0, 0.5, 0.0)),
    ] {
        // two_over_w = 2: column 0 has s = 0 exactly (the ray straight down through a vertex);
        // column x has s = 2 x tan_x, a multiple of 1/32.
        let rays = RowRays {
            origin,
            forward: vec3(0.0, 0.0, -1.0),
            right,
            row_offset: Vec3::ZERO,
            two_over_w: 2.0,
            tan_x: 1.0 / 64.0,
            tmax: f32::INFINITY,
        };
        let len = 48;
        // Every triangle for every lane, as runs and one by one.
        for id in 0..n {
            check(&tracer, &rays, 0, &vec![id; len], &mut seen);
        }
        let ids: Vec<u32> = (0..len as u32).map(|i| (i * 7) % n).collect();
        check(&tracer, &rays, 0, &ids, &mut seen);
    }
    eprintln!("{seen:?}");
    assert!(seen.on_edge > 100, "{seen:?}");
}

/// Rays parallel to the plane, planes behind the origin or beyond `tmax`, non-finite rays,
/// unknown ids and an empty tracer: all `None` exactly where the scalar test says so.
#[test]
fn misses_and_bad_input_agree_with_single_rays() {
    let tris = vec![
        [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)],
        [vec3(0.0, 0.0, 5.0), vec3(1.0, 0.0, 5.0), vec3(0.0, 1.0, 5.0)],
        [vec3(0.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, 1.0)],
    ];
    let tracer = Tracer::build(&tris);
    let mut seen = Seen::default();
    let ids: Vec<u32> = (0..40).map(|i| [0, 1, 2, 3, u32::MAX][i % 5]).collect();
    let base = RowRays {
        origin: vec3(0.2, 0.2, 2.0),
        forward: vec3(0.0, 0.0, -1.0),
        right: vec3(1.0, 0.0, 0.0),
        row_offset: Vec3::ZERO,
        two_over_w: 0.05,
        tan_x: 1.0,
        tmax: f32::INFINITY,
    };
    let rows = [
        base,
        // Horizontal rays: parallel to the planes z = 0 and z = 5.
        RowRays { forward: vec3(1.0, 0.0, 0.0), right: vec3(0.0, 1.0, 0.0), ..base },
        // Away from z = 0, towards z = 5, with a short range.
        RowRays { forward: vec3(0.0, 0.0, 1.0), tmax: 2.5, ..base },
        RowRays { tmax: 0.0, ..base },
        RowRays { tmax: f32::NAN, ..base },
        RowRays { origin: vec3(f32::NAN, 0.0, 0.0), ..base },
        RowRays { origin: vec3(f32::INFINITY, 0.0, 0.0), ..base },
        RowRays { forward: vec3(f32::INFINITY, 0.0, 0.0), ..base },
        RowRays { right: vec3(0.0, f32::NAN, 0.0), ..base },
        // Zero directions (0 / 0 when normalised).
        RowRays { forward: Vec3::ZERO, right: Vec3::ZERO, ..base },
        // Directions so large or small that normalising over- or underflows.
        RowRays { forward: vec3(0.0, 0.0, -3e38), right: vec3(3e38, 0.0, 0.0), ..base },
        RowRays { forward: vec3(0.0, 0.0, -1e-30), right: vec3(1e-30, 0.0, 0.0), ..base },
    ];
    for rays in &rows {
        check(&tracer, rays, 0, &ids, &mut seen);
        check(&tracer, rays, 5, &ids[..13], &mut seen);
    }
    // No triangles at all.
    let empty = Tracer::build(&[]);
    check(&empty, &base, 0, &ids, &mut seen);
    check(&empty, &base, 0, &[], &mut seen);
    eprintln!("{seen:?}");
    assert!(seen.misses > 50 && seen.hits > 20, "{seen:?}");
}

/// The batched hits of a camera-like row through a dense mesh agree with the BVH where the
/// ray lands inside the triangle: the property the renderer relies on.
#[test]
fn row_hits_equal_closest_hits_inside_the_triangle() {
    let tris = grid(32).into_iter().map(|t| t.map(|p| p * 0.25 + vec3(-4.0, -4.0, -6.0))).collect::<Vec<_>>();
    let tracer = Tracer::build(&tris);
    let mut counts = hyrt_tracer::RayCounts::default();
    let mut inside = 0;
    for y in 0..40 {
        let sy = 1.0 - (y as f32 + 0.5) / 20.0;
        let rays = RowRays {
            origin: vec3(0.1, 0.2, 3.0),
            forward: vec3(0.0, 0.0, -1.0),
            right: vec3(1.0, 0.0, 0.0),
            row_offset: vec3(0.0, 1.0, 0.0) * (sy * 0.4),
            two_over_w: 2.0 / 61.0,
            tan_x: 0.4,
            tmax: f32::INFINITY,
        };
        let want: Vec<Option<Hit>> = (0..61)
            .map(|x| tracer.closest_hit(&rays.ray(x), hyrt_tracer::RayKind::Primary, &mut counts))
            .collect();
        let ids: Vec<u32> = want.iter().map(|h| h.map_or(u32::MAX, |h| h.tri)).collect();
        let mut out = vec![None; ids.len()];
        tracer.hits_on_row(&rays, 0, &ids, &mut out);
        assert_eq!(
            out.iter().map(|h| bits(*h)).collect::<Vec<_>>(),
            want.iter().map(|h| bits(*h)).collect::<Vec<_>>()
        );
        inside += want.iter().flatten().count();
    }
    assert!(inside > 2000);
}
