//! Light maps against brute-force ray casting, their parameterisation, seams, hard geometry and
//! bad input.
//!
//! The reference casts each texel centre's direction from the light against every triangle
//! with an `f64` Möller-Trumbore test. The texel-centre directions are computed here in `f64`
//! from the documented conventions (not with `LightMap::texel_dir`), so the tests also check
//! that the maps are drawn where the conventions say.

use glam::{DVec3, Vec3};
use hyrt_shadowmap::{CubeFace, EMPTY, LightMap, MapCoord, MapKind, MapOptions};

use hyrt_testkit::Rng;

/// A random unit direction (uniform on the sphere, by rejection).
fn unit(rng: &mut Rng) -> DVec3 {
    loop {
        let v = DVec3::new(rng.f64(), rng.f64(), rng.f64()) * 2.0 - 1.0;
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

fn opts(kind: MapKind, resolution: u32, tess_texels: f32) -> MapOptions {
    MapOptions { kind, resolution, tess_texels }
}

fn all_faces(kind: MapKind) -> Vec<bool> {
    vec![true; LightMap::face_count(kind)]
}

/// Möller-Trumbore in `f64`: distance along unit `dir` from `o` to the triangle, if hit.
fn ray_triangle(o: DVec3, dir: DVec3, tri: &[Vec3; 3]) -> Option<f64> {
    let [v0, v1, v2] = tri.map(|v| v.as_dvec3());
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// The closest triangle along `dir` from `o` (ties to the smaller id), or `EMPTY`.
fn cast(tris: &[[Vec3; 3]], o: DVec3, dir: DVec3) -> (u32, f64) {
    let mut best = (EMPTY, f64::INFINITY);
    for (i, t) in tris.iter().enumerate() {
        if let Some(d) = ray_triangle(o, dir, t)
            && d < best.1
        {
            best = (i as u32, d);
        }
    }
    best
}

/// Distance along unit `dir` from `o` to the plane of `tri`.
fn plane_distance(o: DVec3, dir: DVec3, tri: &[Vec3; 3]) -> f64 {
    let [v0, v1, v2] = tri.map(|v| v.as_dvec3());
    let n = (v1 - v0).cross(v2 - v0);
    n.dot(v0 - o) / n.dot(dir)
}

/// Angle between unit `dir` and the outline of `tri` as seen from `o` (the great-circle arcs of
/// its edges).
fn angle_to_edges(o: DVec3, dir: DVec3, tri: &[Vec3; 3]) -> f64 {
    let v = tri.map(|p| (p.as_dvec3() - o).normalize());
    let angle = |a: DVec3, b: DVec3| a.cross(b).length().atan2(a.dot(b));
    (0..3)
        .map(|k| {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let n = a.cross(b);
            let to_ends = angle(dir, a).min(angle(dir, b));
            if n.length() < 1e-12 {
                return to_ends;
            }
            let n = n.normalize();
            let p = dir - n * dir.dot(n);
            // The foot on the great circle lies on the arc between a and b.
            if a.cross(p).dot(n) >= 0.0 && p.cross(b).dot(n) >= 0.0 {
                dir.dot(n).abs().asin()
            } else {
                to_ends
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Unit direction of the centre of texel `(ix, iy)` of `face`, from the documented conventions.
fn centre_dir(kind: MapKind, res: u32, face: u8, ix: u32, iy: u32) -> DVec3 {
    let inv = 2.0 / f64::from(res);
    let (s, t) = ((f64::from(ix) + 0.5) * inv - 1.0, 1.0 - (f64::from(iy) + 0.5) * inv);
    match kind {
        MapKind::Cube => {
            let (axis, sign, si, ti) = CubeFace::from_index(face).unwrap().axes();
            let mut d = DVec3::ZERO;
            d[axis] = f64::from(sign);
            d[si] = s;
            d[ti] = t;
            d.normalize()
        }
        MapKind::Paraboloid => {
            let r2 = s * s + t * t;
            let z = (1.0 - r2) / (1.0 + r2);
            let d = DVec3::new(s * (1.0 + z), t * (1.0 + z), if face == 0 { z } else { -z });
            d.normalize()
        }
    }
}

/// Triangles in `layers` disjoint shells around `light`, three per shell (layer `k` at distance
/// about `1.25^k`, layers shuffled so that ids are not in depth order), each within a cone of up
/// to 30 degrees around a random direction, the three cones of a shell disjoint. They overlap on
/// the maps, cross cube edges and the paraboloid seam, but never intersect: every point of a
/// triangle is at a distance in `[0.97 cos 30, 1.03] r` of the light, and `1.25 * 0.84 > 1.03`;
/// so the reference has no depth ties.
fn layered_scene(seed: u64, layers: usize, light: DVec3) -> Vec<[Vec3; 3]> {
    let mut rng = Rng(seed);
    let mut order: Vec<usize> = (0..layers).collect();
    for i in (1..layers).rev() {
        order.swap(i, (rng.f64() * (i + 1) as f64) as usize);
    }
    let mut tris = Vec::new();
    for &layer in &order {
        let r = 1.25f64.powi(layer as i32);
        let mut cones: Vec<(DVec3, f64)> = Vec::new();
        while cones.len() < 3 {
            let (c, radius) = (unit(&mut rng), (8.0 + 22.0 * rng.f64()).to_radians());
            if cones.iter().all(|&(c2, r2)| c.dot(c2).clamp(-1.0, 1.0).acos() > radius + r2) {
                cones.push((c, radius));
            }
        }
        for (c, radius) in cones {
            let e1 = c.any_orthonormal_vector();
            let e2 = c.cross(e1);
            tris.push([0.0, 1.0, 2.0].map(|k: f64| {
                let theta = (k + 0.3 * rng.f64()) * std::f64::consts::TAU / 3.0;
                let beta = radius * (0.6 + 0.4 * rng.f64());
                let dir = c * beta.cos() + (e1 * theta.cos() + e2 * theta.sin()) * beta.sin();
                (light + dir * r * (1.0 + 0.03 * (2.0 * rng.f64() - 1.0))).as_vec3()
            }));
        }
    }
    tris
}

/// Per-texel comparison of a map with the reference.
struct Agreement {
    texels: usize,
    agree: usize,
    /// Largest angle, in texels (`LightMap::texel_angle`), from a disagreeing texel's centre
    /// direction to the outline of the reference's or the map's triangle, whichever is closer.
    worst_edge_texels: f64,
    /// Largest relative depth error where the ids agree (against the exact distance along the
    /// texel centre's direction to the stored triangle).
    worst_depth: f64,
    /// Relative depth errors where the ids agree.
    depth_errors: Vec<f64>,
}

fn compare(map: &LightMap, tris: &[[Vec3; 3]], light: Vec3, kind: MapKind) -> Agreement {
    let res = map.resolution();
    let o = light.as_dvec3();
    let mut a =
        Agreement { texels: 0, agree: 0, worst_edge_texels: 0.0, worst_depth: 0.0, depth_errors: vec![] };
    for face in 0..LightMap::face_count(kind) as u8 {
        for iy in 0..res {
            for ix in 0..res {
                if !map.texel_in_domain(face, ix, iy) {
                    continue;
                }
                a.texels += 1;
                let dir = centre_dir(kind, res, face, ix, iy);
                let (want, _) = cast(tris, o, dir);
                let got = map.id(face, ix, iy);
                if got == want {
                    a.agree += 1;
                    if got != EMPTY {
                        let exact = plane_distance(o, dir, &tris[got as usize]);
                        let err = (f64::from(map.depth(face, ix, iy)) - exact).abs() / exact;
                        a.worst_depth = a.worst_depth.max(err);
                        a.depth_errors.push(err);
                    }
                    continue;
                }
                let near_edge = [want, got]
                    .iter()
                    .filter(|&&id| id != EMPTY)
                    .map(|&id| angle_to_edges(o, dir, &tris[id as usize]))
                    .fold(f64::INFINITY, f64::min);
                let c = MapCoord { face, level: 0, x: f64::from(ix) + 0.5, y: f64::from(iy) + 0.5 };
                a.worst_edge_texels = a.worst_edge_texels.max(near_edge / f64::from(map.texel_angle(c)));
            }
        }
    }
    a
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(((v.len() as f64 - 1.0) * p) as usize).copied().unwrap_or(0.0)
}

#[test]
fn cube_ids_and_depths_match_brute_force_ray_casting() {
    let light = Vec3::new(0.3, -0.2, 0.1);
    let tris = layered_scene(7, 30, light.as_dvec3());
    let map = LightMap::build(&tris, light, &opts(MapKind::Cube, 64, 8.0), &all_faces(MapKind::Cube));
    let a = compare(&map, &tris, light, MapKind::Cube);
    let frac = a.agree as f64 / a.texels as f64;
    let mut errs = a.depth_errors;
    println!(
        "cube: {} of {} texels agree ({:.3} %), disagreements within {:.4} texel of an edge, depth error max {:.2e} p99 {:.2e}",
        a.agree,
        a.texels,
        100.0 * frac,
        a.worst_edge_texels,
        a.worst_depth,
        percentile(&mut errs, 0.99)
    );
    assert!(errs.len() > 5000, "the scene covers too little of the map ({} texels)", errs.len());
    assert!(frac >= 0.99, "agreement {frac}");
    // Vertices are snapped to 1/256 texel: a disagreement is a texel centre within that of an edge.
    assert!(a.worst_edge_texels <= 0.01, "a disagreement {} texels from every edge", a.worst_edge_texels);
    assert!(a.worst_depth <= 1e-6, "relative depth error {:e}", a.worst_depth);
}

#[test]
fn paraboloid_ids_and_depths_match_brute_force_ray_casting() {
    let light = Vec3::new(0.3, -0.2, 0.1);
    let tris = layered_scene(11, 30, light.as_dvec3());
    let faces = all_faces(MapKind::Paraboloid);
    let map = LightMap::build(&tris, light, &opts(MapKind::Paraboloid, 256, 4.0), &faces);
    let a = compare(&map, &tris, light, MapKind::Paraboloid);
    let frac = a.agree as f64 / a.texels as f64;
    let mut errs = a.depth_errors;
    println!(
        "paraboloid tess 4: {} of {} texels agree ({:.3} %), disagreements within {:.4} texel of an edge, depth error max {:.2e} p99 {:.2e} median {:.2e}",
        a.agree,
        a.texels,
        100.0 * frac,
        a.worst_edge_texels,
        a.worst_depth,
        percentile(&mut errs, 0.99),
        percentile(&mut errs, 0.5),
    );
    assert!(errs.len() > 20000, "the scene covers too little of the map ({} texels)", errs.len());
    assert!(frac >= 0.995, "agreement {frac}");
    // Chords of 4-texel sub-edges sag by at most 6^2 / (8 * 128) texel on the circles that
    // straight edges become; plus the snapping.
    assert!(a.worst_edge_texels <= 0.1, "a disagreement {} texels from every edge", a.worst_edge_texels);
    assert!(a.worst_depth <= 2e-3, "relative depth error {:e}", a.worst_depth);

    // Without tessellation, ids are still right away from the edges but depth is much worse.
    let coarse = LightMap::build(&tris, light, &opts(MapKind::Paraboloid, 256, f32::INFINITY), &faces);
    let b = compare(&coarse, &tris, light, MapKind::Paraboloid);
    println!(
        "paraboloid, no tessellation: {:.3} % agree, depth error max {:.2e}",
        100.0 * b.agree as f64 / b.texels as f64,
        b.worst_depth
    );
    assert!(b.agree < a.agree && b.worst_depth > 4.0 * a.worst_depth);
}

#[test]
fn hemisphere_ids_match_brute_force_ray_casting() {
    let light = Vec3::new(-0.1, 0.2, 0.05);
    let tris = layered_scene(5, 30, light.as_dvec3());
    let axis = Vec3::new(0.3, -0.8, 0.5).normalize();
    let map = LightMap::build_hemisphere(&tris, light, axis, &opts(MapKind::Cube, 128, 4.0));
    assert_eq!((map.faces(), map.kind()), (1, MapKind::Paraboloid));
    let (mut texels, mut agree) = (0, 0);
    for iy in 0..128 {
        for ix in 0..128 {
            if !map.texel_in_domain(0, ix, iy) {
                assert_eq!(map.id(0, ix, iy), EMPTY);
                continue;
            }
            let dir = map.texel_dir(0, ix as f32 + 0.5, iy as f32 + 0.5).as_dvec3();
            assert!(dir.dot(axis.as_dvec3()) >= -1e-6, "texel ({ix}, {iy}) looks behind the hemisphere");
            let (want, _) = cast(&tris, light.as_dvec3(), dir);
            let got = map.id(0, ix, iy);
            texels += 1;
            if got == want {
                agree += 1;
            } else {
                let near_edge = [want, got]
                    .iter()
                    .filter(|&&id| id != EMPTY)
                    .map(|&id| angle_to_edges(light.as_dvec3(), dir, &tris[id as usize]))
                    .fold(f64::INFINITY, f64::min);
                assert!(near_edge < 0.1 * 4.0 / 128.0, "texel ({ix}, {iy}): {got} instead of {want}");
            }
        }
    }
    println!("hemisphere: {agree} of {texels} texels agree");
    assert!(agree as f64 >= 0.99 * texels as f64);
}

#[test]
fn tessellation_reduces_the_depth_error_of_a_large_close_triangle() {
    // Triangles 3 units wide 0.5 from the light (tessellated 27 x 27 for 8 texels and
    // 53 x 53 for 4 at resolution 64), and 8 units wide 0.3 from it (both at the cap, 64 x 64):
    // without tessellation the linear interpolation of near / |d| across its image is far off.
    let light = Vec3::ZERO;
    let errors = |tris: &[[Vec3; 3]], tess: f32| {
        let res = 64;
        let map = LightMap::build(tris, light, &opts(MapKind::Paraboloid, res, tess), &[true, false]);
        let (mut worst, mut sum, mut n) = (0.0f64, 0.0, 0);
        for iy in 0..res {
            for ix in 0..res {
                if map.id(0, ix, iy) == 0 {
                    let dir = centre_dir(MapKind::Paraboloid, res, 0, ix, iy);
                    let exact = plane_distance(DVec3::ZERO, dir, &tris[0]);
                    let e = (f64::from(map.depth(0, ix, iy)) - exact).abs() / exact;
                    worst = worst.max(e);
                    sum += e;
                    n += 1;
                }
            }
        }
        (worst, sum / n as f64, map.triangles_drawn())
    };
    let medium = [[Vec3::new(-1.5, -1.5, 0.5), Vec3::new(1.5, -1.2, 0.5), Vec3::new(0.2, 1.5, 0.5)]];
    let (none, tess8, tess4) = (errors(&medium, f32::INFINITY), errors(&medium, 8.0), errors(&medium, 4.0));
    println!(
        "3-wide triangle, relative depth error (max, mean, triangles): none {none:?}, tess 8 {tess8:?}, tess 4 {tess4:?}"
    );
    assert_eq!(none.2, 1);
    assert!(tess4.0 < tess8.0 && tess8.0 < none.0 && tess4.1 < tess8.1 && tess8.1 < none.1);
    assert!(tess4.0 < 0.01 * none.0 && tess4.0 < 0.01, "{tess4:?}");
    let large = [[Vec3::new(-4.0, -4.0, 0.3), Vec3::new(4.0, -3.0, 0.3), Vec3::new(0.5, 4.0, 0.3)]];
    let (none, tess4) = (errors(&large, f32::INFINITY), errors(&large, 4.0));
    println!("8-wide triangle: none {none:?}, tess 4 {tess4:?}");
    assert!(tess4.0 < 0.01 * none.0 && tess4.0 < 0.1, "{tess4:?}");
}

/// Directions spread over the sphere (Fibonacci lattice) and the special ones: axes, cube edges
/// and corners, the paraboloid seam, signed zeros.
fn test_directions() -> Vec<Vec3> {
    let n = 4000;
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let mut dirs: Vec<Vec3> = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).sqrt();
            Vec3::new(r * (golden * i as f32).cos(), r * (golden * i as f32).sin(), z)
        })
        .collect();
    for a in [-1.0f32, -0.0, 0.0, 1.0] {
        for b in [-1.0f32, -0.0, 0.0, 1.0] {
            for c in [-1.0f32, -0.0, 0.0, 1.0] {
                if a != 0.0 || b != 0.0 || c != 0.0 {
                    dirs.push(Vec3::new(a, b, c));
                }
            }
        }
    }
    for i in 0..360 {
        let a = (i as f32).to_radians();
        for z in [0.0, -0.0, 1e-30, -1e-30, 1e-7, -1e-7] {
            dirs.push(Vec3::new(a.cos(), a.sin(), z));
        }
    }
    dirs.extend([Vec3::new(1.0, 1e-30, -1e-30), Vec3::new(3e-39, 0.0, 0.0), Vec3::new(-1e30, 1e30, 1e30)]);
    dirs
}

#[test]
fn coord_and_texel_dir_round_trip_and_stay_in_range() {
    let tilted = Vec3::new(0.3, -0.8, 0.5).normalize();
    for res in [1, 2, 3, 64, 101] {
        let maps = [
            (
                LightMap::build(&[], Vec3::ZERO, &opts(MapKind::Cube, res, 8.0), &[true; 6]),
                Some(MapKind::Cube),
            ),
            (
                LightMap::build(&[], Vec3::ZERO, &opts(MapKind::Paraboloid, res, 8.0), &[true; 2]),
                Some(MapKind::Paraboloid),
            ),
            (LightMap::build_hemisphere(&[], Vec3::ZERO, tilted, &opts(MapKind::Cube, res, 8.0)), None),
        ];
        for (map, kind) in &maps {
            let resf = res as f32;
            for d in test_directions() {
                let c = map.coord(d);
                if let Some(kind) = kind {
                    assert_eq!(c.face, LightMap::face_of(*kind, d), "{d}");
                } else {
                    assert_eq!(c.face, 0);
                }
                let resd = f64::from(resf);
                assert!((0.0..resd).contains(&c.x) && (0.0..resd).contains(&c.y), "{d} -> {c:?} (res {res})");
                assert!(map.texel_in_domain(c.face, c.x as u32, c.y as u32), "{d} -> {c:?} (res {res})");
                // Back to (nearly) the same direction: exactly for cube faces, within 1.5 texels
                // at the paraboloid rim (where coord moves into the disc), not at all behind a
                // single hemisphere.
                let back = map.texel_dir_at(c.face, 0, c.x, c.y).as_dvec3();
                let dn = d.as_dvec3().normalize();
                let angle = back.cross(dn).length().atan2(back.dot(dn));
                let bound = match kind {
                    Some(MapKind::Cube) => 1e-5,
                    _ => 1.5 * f64::from(map.texel_angle(c)) + 1e-5,
                };
                if kind.is_some() || dn.dot(tilted.as_dvec3()) > 0.0 {
                    assert!(angle <= bound, "{d} -> {c:?} -> {back}: {angle} rad (res {res})");
                }
            }
            // Continuous positions -> direction -> the same position.
            let mut rng = Rng(3);
            for _ in 0..2000 {
                let face = (rng.f64() * map.faces() as f64) as u8;
                let (x, y) =
                    ((0.01 + rng.f64() * 0.98) * resf as f64, (0.01 + rng.f64() * 0.98) * resf as f64);
                let (x, y) = (x as f32, y as f32);
                let r = (x - resf / 2.0).hypot(y - resf / 2.0);
                if *kind != Some(MapKind::Cube) && r > resf / 2.0 - 1.5 {
                    continue;
                }
                let c = map.coord(map.texel_dir(face, x, y));
                let tol = 2e-3 * resf.max(1.0) / 64.0 + 1e-4;
                assert!(
                    c.face == face
                        && (c.x - f64::from(x)).abs() <= f64::from(tol)
                        && (c.y - f64::from(y)).abs() <= f64::from(tol),
                    "({face}, {x}, {y}) -> {c:?} (res {res})"
                );
            }
        }
    }
}

/// Two triangles of the quad `c + (+-1) a + (+-1) b`.
fn quad(c: Vec3, a: Vec3, b: Vec3) -> [[Vec3; 3]; 2] {
    [[c - a - b, c + a - b, c + a + b], [c - a - b, c + a + b, c - a + b]]
}

/// Whether texel `(ix, iy)`'s centre direction hits one of `ids` by more than `margin` texels
/// from their outlines, per the reference.
fn clearly_hits(
    map: &LightMap,
    tris: &[[Vec3; 3]],
    ids: &[u32],
    kind: MapKind,
    (face, ix, iy): (u8, u32, u32),
) -> bool {
    let dir = centre_dir(kind, map.resolution(), face, ix, iy);
    let o = map.light().as_dvec3();
    let (id, _) = cast(tris, o, dir);
    let angle = ids.iter().map(|&i| angle_to_edges(o, dir, &tris[i as usize])).fold(f64::INFINITY, f64::min);
    let c = MapCoord { face, level: 0, x: f64::from(ix) + 0.5, y: f64::from(iy) + 0.5 };
    ids.contains(&id) && angle > f64::from(map.texel_angle(c))
}

#[test]
fn occluder_across_the_paraboloid_seam_has_no_gap() {
    // A quad at x = 1 from z = -0.5 to 0.5 and a box far around it.
    let mut tris: Vec<[Vec3; 3]> = quad(Vec3::X, Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.0, 0.0, 0.5)).to_vec();
    tris.extend(quad(Vec3::new(0.0, 0.0, -5.0), Vec3::X * 5.0, Vec3::Y * 5.0));
    tris.extend(quad(Vec3::new(0.0, 0.0, 5.0), Vec3::X * 5.0, Vec3::Y * 5.0));
    let ids = [0, 1];
    for tess in [8.0, f32::INFINITY] {
        for res in [64, 255, 256] {
            let map =
                LightMap::build(&tris, Vec3::ZERO, &opts(MapKind::Paraboloid, res, tess), &[true, true]);
            // Every texel of the disc's outer ring (centre within 1.5 texels of the rim) whose
            // direction clearly hits the quad holds it, on both sides of the seam.
            let mut seen = [0, 0];
            for face in 0..2u8 {
                for iy in 0..res {
                    for ix in 0..res {
                        let r =
                            (ix as f32 + 0.5 - res as f32 / 2.0).hypot(iy as f32 + 0.5 - res as f32 / 2.0);
                        if map.texel_in_domain(face, ix, iy)
                            && r > res as f32 / 2.0 - 1.5
                            && clearly_hits(&map, &tris, &ids, MapKind::Paraboloid, (face, ix, iy))
                        {
                            assert!(
                                ids.contains(&map.id(face, ix, iy)),
                                "res {res} tess {tess} face {face} ({ix}, {iy})"
                            );
                            seen[face as usize] += 1;
                        }
                    }
                }
            }
            assert!(seen[0] >= 2 && seen[1] >= 2, "{seen:?}");
            // Lookups of directions on and next to the seam find the quad on both maps.
            for i in 0..=100 {
                let y = -0.45 + 0.9 * i as f32 / 100.0;
                for z in [0.0, 1e-6, -1e-6, 1e-3, -1e-3, -0.0] {
                    let c = map.coord(Vec3::new(1.0, y, z));
                    let id = map.id(c.face, c.x as u32, c.y as u32);
                    assert!(ids.contains(&id), "res {res} tess {tess}: (1, {y}, {z}) -> {c:?} -> {id}");
                }
            }
        }
    }
}

#[test]
fn occluder_across_a_cube_edge_has_no_gap() {
    // A quad facing the light across the edge between +x and +z (and a far box behind).
    let c = Vec3::new(1.0, 0.1, 1.0);
    let mut tris: Vec<[Vec3; 3]> = quad(c, Vec3::new(0.3, 0.0, -0.3), Vec3::new(0.0, 0.35, 0.0)).to_vec();
    tris.extend(quad(Vec3::new(0.0, 0.0, 6.0), Vec3::X * 6.0, Vec3::Y * 6.0));
    let ids = [0, 1];
    let res = 64;
    let map = LightMap::build(&tris, Vec3::ZERO, &opts(MapKind::Cube, res, 8.0), &[true; 6]);
    // +x row 0 (t = z/x = 1) and +z column res-1 (s = x/z = 1) are the two sides of the edge.
    let (px, pz) = (CubeFace::PosX.index(), CubeFace::PosZ.index());
    let mut seen = 0;
    for i in 0..res {
        for texel in [(px, i, 0), (pz, res - 1, i)] {
            if clearly_hits(&map, &tris, &ids, MapKind::Cube, texel) {
                assert!(ids.contains(&map.id(texel.0, texel.1, texel.2)), "{texel:?}");
                seen += 1;
            }
        }
    }
    assert!(seen >= 20, "{seen}");
    for i in 0..=100 {
        let y = -0.2 + 0.5 * i as f32 / 100.0;
        for e in [0.0, 1e-6, -1e-6, 1e-3, -1e-3] {
            let cc = map.coord(Vec3::new(1.0, y, 1.0 + e));
            assert!(cc.face == px || cc.face == pz);
            assert!(ids.contains(&map.id(cc.face, cc.x as u32, cc.y as u32)), "{y} {e} -> {cc:?}");
        }
    }
}

#[test]
fn light_very_close_to_a_wall() {
    // A unit wall 1e-4 from the light, across the paraboloid seam and cube edges.
    let h = 1e-4;
    let tris = quad(Vec3::new(0.1, h, -0.05), Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.5)).to_vec();
    let light = Vec3::ZERO;
    for (kind, res) in [(MapKind::Cube, 64), (MapKind::Paraboloid, 128)] {
        let map = LightMap::build(&tris, light, &opts(kind, res, 8.0), &all_faces(kind));
        let a = compare(&map, &tris, light, kind);
        let mut clear = 0;
        for face in 0..LightMap::face_count(kind) as u8 {
            for iy in 0..res {
                for ix in 0..res {
                    if map.texel_in_domain(face, ix, iy)
                        && clearly_hits(&map, &tris, &[0, 1], kind, (face, ix, iy))
                    {
                        clear += 1;
                        assert!(map.id(face, ix, iy) <= 1, "{kind:?} face {face} ({ix}, {iy})");
                    }
                }
            }
        }
        let mut errs = a.depth_errors.clone();
        let over = errs.iter().filter(|&&e| e > 0.01).count();
        println!(
            "{kind:?}: wall 1e-4 away: {} of {} texels agree, {clear} clearly on the wall, depth error max {:.2e}, median {:.2e}, {over} over 1 %",
            a.agree,
            a.texels,
            a.worst_depth,
            percentile(&mut errs, 0.5)
        );
        assert!(clear as f64 > 0.45 * a.texels as f64);
        assert!(a.agree as f64 >= 0.99 * a.texels as f64);
        if kind == MapKind::Cube {
            assert!(a.worst_depth <= 1e-6, "{}", a.worst_depth);
        }
    }
}

/// The 12 triangles of the box `[lo, hi]`, sharing vertices.
fn cuboid(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let v = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    quads.iter().flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]]).collect()
}

#[test]
fn light_inside_a_closed_box_sees_it_in_every_texel() {
    let tris = cuboid(Vec3::new(-1.0, -0.7, -1.3), Vec3::new(2.0, 0.9, 0.8));
    let check = |map: &LightMap, what: &str| {
        for face in 0..map.faces() as u8 {
            for iy in 0..map.resolution() {
                for ix in 0..map.resolution() {
                    if map.texel_in_domain(face, ix, iy) {
                        assert!(map.id(face, ix, iy) < 12, "{what}: face {face} ({ix}, {iy}) empty");
                        assert!(map.depth(face, ix, iy).is_finite());
                    }
                }
            }
        }
    };
    for light in [Vec3::ZERO, Vec3::new(1.9, 0.85, -1.25), Vec3::new(-0.99, 0.0, 0.0)] {
        for res in [1, 2, 5, 64] {
            let m = LightMap::build(&tris, light, &opts(MapKind::Cube, res, 8.0), &[true; 6]);
            check(&m, &format!("cube {res} at {light}"));
            for tess in [8.0, 2.0, f32::INFINITY] {
                let m = LightMap::build(&tris, light, &opts(MapKind::Paraboloid, res, tess), &[true; 2]);
                check(&m, &format!("paraboloid {res} tess {tess} at {light}"));
                let axis = Vec3::new(-0.4, 0.1, 0.9).normalize();
                let m = LightMap::build_hemisphere(&tris, light, axis, &opts(MapKind::Cube, res, tess));
                check(&m, &format!("hemisphere {res} tess {tess} at {light}"));
            }
        }
    }
}

#[test]
fn degenerate_triangles_are_skipped_without_panicking() {
    let good = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)];
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let tris = vec![
        [Vec3::new(-1.0, 0.0, 1.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0)], // collinear
        [good[0], good[0], good[1]],                                                     // repeated vertex
        [good[2]; 3],                                                                    // a point
        [good[0], good[1], Vec3::new(nan, 0.0, 1.0)],
        [good[0], good[1], Vec3::new(0.0, inf, 1.0)],
        [Vec3::splat(-inf), Vec3::splat(inf), Vec3::splat(nan)],
        [Vec3::new(-3e38, -3e38, 3e38), Vec3::new(3e38, -3e38, 3e38), Vec3::new(0.0, 3e38, 3e38)],
        [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)], // through the light
        [Vec3::new(1.0, 1.0, 0.0), Vec3::new(2.0, 1.0, 0.0), Vec3::new(1.0, 2.0, 0.0)],    // edge-on
        [Vec3::new(1e-30, 0.0, 1.0), Vec3::new(2e-30, 0.0, 1.0), Vec3::new(1e-30, 1e-30, 1.0)], // tiny
        good,
    ];
    let last = tris.len() as u32 - 1;
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        for tess in [8.0, 0.0, -1.0, f32::NAN, f32::INFINITY] {
            let map = LightMap::build(&tris, Vec3::ZERO, &opts(kind, 32, tess), &all_faces(kind));
            let mut good_seen = 0;
            for face in 0..map.faces() as u8 {
                for iy in 0..32 {
                    for ix in 0..32 {
                        let id = map.id(face, ix, iy);
                        assert!(id == EMPTY || id == last, "{kind:?}: degenerate triangle {id} drawn");
                        good_seen += usize::from(id == last);
                    }
                }
            }
            assert!(good_seen > 10, "{kind:?} tess {tess}: the good triangle covers {good_seen} texels");
        }
    }
}

#[test]
fn bad_input_does_not_panic() {
    let tris = cuboid(Vec3::splat(-1.0), Vec3::splat(1.0));
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let faces = all_faces(kind);
        for res in [0, 1] {
            let map = LightMap::build(&tris, Vec3::ZERO, &opts(kind, res, 8.0), &faces);
            assert_eq!(map.resolution(), 1, "resolution 0 is treated as 1");
            for face in 0..map.faces() as u8 {
                assert!(map.id(face, 0, 0) < 12);
                assert_eq!(map.id(face, 1, 0), EMPTY, "out of range");
                assert_eq!(map.depth(face, 0, 1), f32::INFINITY);
            }
        }
        // Empty scene, NaN light, a light exactly on a wall (its two triangles are edge-on),
        // wrong-length face lists.
        let empty = LightMap::build(&[], Vec3::ZERO, &opts(kind, 16, 8.0), &faces);
        assert_eq!((empty.id(0, 3, 3), empty.depth(0, 3, 3)), (EMPTY, f32::INFINITY));
        let nan = LightMap::build(&tris, Vec3::NAN, &opts(kind, 16, 8.0), &faces);
        assert_eq!(nan.id(0, 8, 8), EMPTY);
        let on_wall = LightMap::build(&tris, Vec3::new(1.0, 0.2, -0.3), &opts(kind, 16, 8.0), &faces);
        let mut seen = std::collections::BTreeSet::new();
        for face in 0..on_wall.faces() as u8 {
            for i in 0..16 * 16 {
                seen.insert(on_wall.id(face, i % 16, i / 16));
            }
        }
        // The +x wall is triangles 2 * 5 and 2 * 5 + 1 of `cuboid` (quad [1, 5, 7, 3]).
        assert!(!seen.contains(&10) && !seen.contains(&11), "{seen:?}");
        assert!(seen.len() >= 6, "{seen:?}");
        let short = LightMap::build(&tris, Vec3::ZERO, &opts(kind, 16, 8.0), &[true]);
        assert_eq!(short.faces_drawn().iter().filter(|&&d| d).count(), 1);
        let long = LightMap::build(&tris, Vec3::ZERO, &opts(kind, 16, 8.0), &[true; 9]);
        assert_eq!(long.faces_drawn().len(), LightMap::face_count(kind));
        assert_eq!(long.id(9, 0, 0), EMPTY);
        let _ = long.texel_dir(9, f32::NAN, 3.0);
        let _ = long.coord(Vec3::ZERO);
        let _ = long.coord(Vec3::NAN);
        let _ = long.texel_angle(MapCoord { face: 7, level: 0, x: f64::NAN, y: -1.0 });
    }
}

#[test]
fn faces_not_asked_for_are_empty_and_cost_nothing() {
    let light = Vec3::new(0.3, -0.2, 0.1);
    let tris = layered_scene(13, 20, light.as_dvec3());
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let n = LightMap::face_count(kind);
        let full = LightMap::build(&tris, light, &opts(kind, 32, 8.0), &vec![true; n]);
        let faces: Vec<bool> = (0..n).map(|i| i % 2 == 0).collect();
        let part = LightMap::build(&tris, light, &opts(kind, 32, 8.0), &faces);
        assert_eq!(part.faces_drawn(), &faces[..]);
        assert_eq!(part.memory_bytes(), full.memory_bytes() / 2);
        assert!(part.triangles_drawn() < full.triangles_drawn());
        for face in 0..n as u8 {
            for iy in 0..32 {
                for ix in 0..32 {
                    if faces[face as usize] {
                        assert_eq!(part.id(face, ix, iy), full.id(face, ix, iy));
                        assert_eq!(part.depth(face, ix, iy).to_bits(), full.depth(face, ix, iy).to_bits());
                    } else {
                        assert_eq!((part.id(face, ix, iy), part.depth(face, ix, iy)), (EMPTY, f32::INFINITY));
                    }
                }
            }
        }
        let none = LightMap::build(&tris, light, &opts(kind, 32, 8.0), &vec![false; n]);
        assert_eq!((none.memory_bytes(), none.triangles_drawn()), (0, 0));
    }
}

/// Bits of every texel of every face.
fn snapshot(map: &LightMap) -> Vec<(u32, u32)> {
    let res = map.resolution();
    (0..map.faces() as u8)
        .flat_map(|f| (0..res * res).map(move |i| (f, i % res, i / res)))
        .map(|(f, x, y)| (map.id(f, x, y), map.depth(f, x, y).to_bits()))
        .collect()
}

#[test]
fn maps_are_identical_for_any_thread_count() {
    // Enough triangles for several parallel chunks.
    let mut rng = Rng(21);
    let light = Vec3::new(0.1, 0.2, -0.1);
    let tris: Vec<[Vec3; 3]> = (0..12_000)
        .map(|_| {
            let c = unit(&mut rng) * (1.0 + 4.0 * rng.f64());
            [0; 3].map(|_| (c + (DVec3::new(rng.f64(), rng.f64(), rng.f64()) - 0.5) * 0.6).as_vec3())
        })
        .collect();
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            [
                LightMap::build(&tris, light, &opts(MapKind::Cube, 96, 8.0), &[true; 6]),
                LightMap::build(&tris, light, &opts(MapKind::Paraboloid, 128, 4.0), &[true; 2]),
                LightMap::build_hemisphere(
                    &tris,
                    light,
                    Vec3::new(0.0, 0.6, 0.8),
                    &opts(MapKind::Cube, 128, 4.0),
                ),
            ]
            .map(|m| (snapshot(&m), m.triangles_drawn()))
        })
    };
    let (one, two) = (build(1), build(2));
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(a.1, b.1);
        assert!(a.0 == b.0, "maps differ between 1 and 2 threads");
        assert!(a.0.iter().filter(|t| t.0 != EMPTY).count() > 1000);
    }
}

/// A VPL's map decides, for points on the scene's triangles, what a ray from the VPL finds (a
/// nearer triangle or not), away from the outlines where a texel stands for its neighbours:
/// random layers of triangles, random points on them, both formats.
#[test]
fn vpl_map_decisions_match_brute_force_ray_casting() {
    use hyrt_shadowmap::{
        classify::triangle_planes,
        vpl_map::{VplFormat, VplMap},
    };
    let o = Vec3::new(0.1, -0.2, 0.05);
    let tris = layered_scene(11, 30, o.as_dvec3());
    let planes = triangle_planes(&tris);
    let axis = Vec3::new(-0.2, 0.9, 0.3).normalize();
    let res = 256;
    for format in [VplFormat::Planes, VplFormat::Depth16] {
        let map = VplMap::build(&tris, &planes, o, axis, &opts(MapKind::Cube, res, 8.0), format);
        // The texels, and the half floats' one padding element.
        let texels = (res * res) as usize * format.texel_bytes();
        assert!((texels..=texels + 2).contains(&map.memory_bytes()), "{}", map.memory_bytes());
        let texel = 4.0 / res as f64;
        let mut rng = Rng(3);
        let (mut checked, mut hidden) = (0, 0);
        for _ in 0..40_000 {
            let own = (rng.f64() * tris.len() as f64) as usize;
            let (a, b) = (rng.f64(), rng.f64());
            let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
            let [v0, v1, v2] = tris[own].map(|v| v.as_dvec3());
            let p = v0 + (v1 - v0) * a + (v2 - v0) * b;
            let d = p - o.as_dvec3();
            let (r, w) = (d.length(), d.normalize());
            if w.dot(axis.as_dvec3()) <= 0.05 {
                continue; // behind the hemisphere or on its rim
            }
            let (id, t) = cast(&tris, o.as_dvec3(), w);
            // Away from every outline the ray passes near, by two texels.
            if tris.iter().any(|tri| angle_to_edges(o.as_dvec3(), w, tri) < 2.0 * texel) {
                continue;
            }
            let want_hidden = id != EMPTY && id as usize != own && t < r * (1.0 - 1e-3);
            let (wv, rv) = (w.as_vec3(), r as f32);
            // The receiver's normal, facing the VPL.
            let n = planes[own].n;
            let ng = if n.dot(wv) < 0.0 { n } else { -n };
            let margin = 0.5 * (1.0 + wv.dot(axis)) * 2.0 / res as f32 * rv + format.tolerance() * rv;
            let i = map.index(wv) as u32;
            let got = map.hidden_at(i % res, i / res, wv, rv, ng, -ng.dot(wv), margin);
            assert_eq!(
                got, want_hidden,
                "{format:?}: point {p} of triangle {own}: the ray meets {id} at {t} of {r}"
            );
            checked += 1;
            hidden += usize::from(got);
        }
        println!("{format:?}: {checked} points checked, {hidden} hidden");
        assert!(checked > 2000 && hidden > 500 && checked - hidden > 500, "{checked} {hidden}");
    }
}

/// Along each texel centre's direction, the stored surface is at the distance of the nearest
/// triangle's plane (the map's id there), to the format's rounding; empty texels are at
/// infinity, and every texel outside the disc holds a neighbour's surface.
#[test]
fn vpl_map_depths_are_the_planes_along_texel_centres() {
    use hyrt_shadowmap::{
        classify::triangle_planes,
        vpl_map::{VplFormat, VplMap},
    };
    let o = Vec3::new(-0.3, 0.1, 0.2);
    let tris = layered_scene(7, 20, o.as_dvec3());
    let axis = Vec3::new(0.5, 0.5, -0.7).normalize();
    let res = 64;
    let ids = LightMap::build_hemisphere(&tris, o, axis, &opts(MapKind::Cube, res, 4.0));
    for format in [VplFormat::Planes, VplFormat::Depth16] {
        let map =
            VplMap::build(&tris, &triangle_planes(&tris), o, axis, &opts(MapKind::Cube, res, 4.0), format);
        let (mut drawn, mut empty, mut outside) = (0, 0, 0);
        for y in 0..res {
            for x in 0..res {
                let id = ids.id(0, x, y);
                let got = map.depth(x, y);
                if !map.in_domain(x, y) {
                    // Finite only where a neighbour in the disc sees a surface.
                    let near = (y.saturating_sub(1)..=(y + 1).min(res - 1))
                        .flat_map(|yy| (x.saturating_sub(1)..=(x + 1).min(res - 1)).map(move |xx| (xx, yy)))
                        .any(|(xx, yy)| map.in_domain(xx, yy) && ids.id(0, xx, yy) != EMPTY);
                    assert!(near || got == f32::INFINITY, "{format:?}: texel ({x}, {y}) outside the disc");
                    outside += usize::from(got.is_finite());
                    continue;
                }
                if id == EMPTY {
                    assert_eq!(got, f32::INFINITY);
                    empty += 1;
                    continue;
                }
                let dir = ids.texel_dir(0, x as f32 + 0.5, y as f32 + 0.5).as_dvec3();
                let want = plane_distance(o.as_dvec3(), dir, &tris[id as usize]);
                let tol = 2.0 * f64::from(format.tolerance()).max(1e-5);
                assert!(
                    (f64::from(got) / want - 1.0).abs() < tol,
                    "{format:?}: texel ({x}, {y}): {got} vs {want}"
                );
                drawn += 1;
            }
        }
        assert!(drawn > 1000 && empty > 10 && outside > 10, "{drawn} {empty} {outside}");
    }
}

/// No triangles, or only unusable ones (NaN, zero area), give a map of empty texels: nothing
/// is hidden.
#[test]
fn vpl_map_of_nothing_hides_nothing() {
    use hyrt_shadowmap::{
        classify::triangle_planes,
        vpl_map::{VplFormat, VplMap},
    };
    let bad = vec![
        [Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)],
        [Vec3::splat(f32::NAN), Vec3::Y, Vec3::Z],
        [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, f32::INFINITY), Vec3::new(0.0, 1.0, 1.0)],
    ];
    for tris in [vec![], bad] {
        for format in [VplFormat::Planes, VplFormat::Depth16] {
            let map = VplMap::build(
                &tris,
                &triangle_planes(&tris),
                Vec3::ZERO,
                Vec3::Z,
                &opts(MapKind::Cube, 16, 4.0),
                format,
            );
            for y in 0..16 {
                for x in 0..16 {
                    assert_eq!(map.depth(x, y), f32::INFINITY);
                    assert!(!map.hidden_at(x, y, Vec3::Z, 5.0, Vec3::NEG_Z, 1.0, 0.0));
                }
            }
        }
    }
}

/// A map that gains faces by `merge` equals one build of all of them, texel for texel, and
/// counts each face rasterized once.
#[test]
fn merged_faces_equal_one_build() {
    let light = Vec3::new(0.1, 0.2, -0.3);
    let tris = layered_scene(9, 20, light.as_dvec3());
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let n = LightMap::face_count(kind);
        let o = opts(kind, 64, 8.0);
        let all = LightMap::build(&tris, light, &o, &vec![true; n]);
        let first: Vec<bool> = (0..n).map(|f| f % 2 == 0).collect();
        let rest: Vec<bool> = first.iter().map(|f| !f).collect();
        let mut merged = LightMap::build(&tris, light, &o, &first);
        merged.merge(LightMap::build(&tris, light, &o, &rest));
        assert_eq!(merged.faces_drawn(), all.faces_drawn());
        assert_eq!((merged.faces_rasterized(), merged.near()), (n as u32, all.near()));
        for f in 0..n as u8 {
            for y in 0..64 {
                for x in 0..64 {
                    assert_eq!(merged.id(f, x, y), all.id(f, x, y), "{kind:?} face {f} ({x}, {y})");
                    assert_eq!(merged.depth(f, x, y).to_bits(), all.depth(f, x, y).to_bits());
                }
            }
        }
        // An empty map (a light no hit was in front of) takes a build's faces whole.
        let mut empty = LightMap::build(&tris, light, &o, &[]);
        empty.merge(LightMap::build(&tris, light, &o, &vec![true; n]));
        assert_eq!((empty.near(), empty.faces_rasterized()), (all.near(), n as u32));
    }
}
