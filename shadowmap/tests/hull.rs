//! `Classifier::hull`, the tile shortcut of classification, against `Classifier::classify`
//! point by point: whenever it says a hull of points is lit (shadowed), every point in it is,
//! with no border.

use glam::Vec3;
use hyrt_shadowmap::{
    LightMap, MapKind, MapOptions,
    classify::Decision,
    classify::{Classifier, Hull, Plane, plane_groups, point_error_bound, triangle_planes},
};

use hyrt_testkit::Rng;

/// A floor of two triangles (ids 0 and 1) at `y = 0` of half-size `size` around `centre`, and
/// small random occluders (ids from 2) scattered above it, below a light.
fn scene(rng: &mut Rng, centre: Vec3, size: f32) -> Vec<[Vec3; 3]> {
    let c = |x: f32, z: f32| centre + Vec3::new(x * size, 0.0, z * size);
    let mut tris =
        vec![[c(-1.0, -1.0), c(1.0, -1.0), c(1.0, 1.0)], [c(-1.0, -1.0), c(1.0, 1.0), c(-1.0, 1.0)]];
    for k in 0..25 {
        let p = centre
            + Vec3::new(
                (2.0 * rng.f32() - 1.0) * size,
                (0.02 + 0.5 * rng.f32()) * size,
                (2.0 * rng.f32() - 1.0) * size,
            );
        // A few large occluders (tables) cast shadows that whole tiles fall in; two of them
        // flat and just above the floor, where the margin decides (contact shadows).
        let s = if k < 4 { 0.8 } else { 0.3 * (0.1 + rng.f32()) } * size;
        if k < 2 {
            let p = Vec3::new(p.x, centre.y + (0.002 + 0.01 * rng.f32()) * size, p.z);
            tris.push([p, p + Vec3::new(s, 0.0, 0.0), p + Vec3::new(0.0, 0.0, s)]);
            continue;
        }
        tris.push([p, p + Vec3::new(s, 0.1 * s, 0.0), p + Vec3::new(0.0, -0.1 * s, s)]);
    }
    tris
}

/// Calls `f` with the `(n + 1)^2` points of a grid over the bilinear patch of `corners` (in
/// tile order: the corners at `(0, 0)`, `(1, 0)`, `(0, 1)`, `(1, 1)`).
fn each_point(corners: &[Vec3; 4], n: usize, mut f: impl FnMut(Vec3)) {
    for i in 0..=n {
        for j in 0..=n {
            let (a, b) = (i as f32 / n as f32, j as f32 / n as f32);
            f(corners[0] * (1.0 - a) * (1.0 - b)
                + corners[1] * a * (1.0 - b)
                + corners[2] * (1.0 - a) * b
                + corners[3] * a * b);
        }
    }
}

/// The classifier the tests use: bias 1, the points' rounding bound of `tris`.
fn classifier<'a>(map: &'a LightMap, planes: &'a [Plane], tris: &[[Vec3; 3]]) -> Classifier<'a> {
    Classifier { map, planes, bias: 1.0, point_error: point_error_bound(tris), cutouts: &[] }
}

/// Asserts that every point of a grid over the patch of `corners` (`n` steps a side; `own`
/// its triangle) is decided as the tile test decided them (`hull`, not `Unknown`), with no
/// border.
fn every_point_agrees(
    cls: &Classifier,
    corners: &[Vec3; 4],
    n: usize,
    own: impl Fn(Vec3) -> u32,
    hull: Hull,
    what: &str,
) {
    each_point(corners, n, |p| {
        let lk = cls.classify(p, own(p));
        assert!(
            (lk.decision == Decision::Lit) == (hull == Hull::Lit) && !lk.map_border,
            "{what}: {hull:?} but {p} is {lk:?}"
        );
    });
}

#[test]
fn hull_decisions_are_every_points_decision_without_border() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut lit, mut shadowed, mut asked, mut straddling) = (0, 0, 0, 0);
    // Near the origin and far from it (rounding of the points grows with their coordinates).
    for (centre, size) in [(Vec3::ZERO, 1.0), (Vec3::new(3.0e4, 1.0e3, -2.0e4), 20.0)] {
        // Maps summarised by triangle, and by plane group (the floor's two triangles as one,
        // so that a hull may straddle their shared edge).
        for (res, grouped) in
            [(64, false), (256, false), (1024, false), (64, true), (256, true), (1024, true)]
        {
            let tris = scene(&mut rng, centre, size);
            let light = centre + Vec3::new(0.3 * size, 1.5 * size, -0.2 * size);
            let opts = MapOptions { kind: MapKind::Cube, resolution: res, ..MapOptions::default() };
            let planes = triangle_planes(&tris);
            let groups = if grouped { plane_groups(&planes, &[]) } else { (0..tris.len() as u32).collect() };
            assert_eq!(groups[1] == groups[0], grouped, "the floor's triangles share their plane");
            let map =
                LightMap::build_grouped(&tris, light, &opts, &[true; 6], if grouped { &groups } else { &[] });
            let cls = classifier(&map, &planes, &tris);
            for _ in 0..400 {
                // A small convex quad on the floor (a tile's corners: a perspective image of a
                // square, here a random convex quad): on triangle 0 (x > z side), or with
                // groups anywhere on the floor.
                let (u, v) = (-0.8 + 1.5 * rng.f32(), -0.9 + 1.5 * rng.f32());
                let (u, v) = if u > v || grouped { (u, v) } else { (v, u) };
                let d = 0.002 + 0.05 * rng.f32();
                let corners = [(0.0, 0.0), (1.0, 0.1 * rng.f32()), (0.1 * rng.f32(), 1.0), (1.0, 1.0)]
                    .map(|(a, b)| centre + Vec3::new((u + d * a) * size, 0.0, (v - d - d * b) * size));
                // The floor triangle under a point (0 where x - z > 0).
                let own = |p: Vec3| u32::from((p.x - centre.x) <= (p.z - centre.z));
                let on_floor = |p: Vec3| (p.x - centre.x).abs() < size && (p.z - centre.z).abs() < size;
                if !corners.iter().all(|&p| on_floor(p) && (grouped || own(p) == 0)) {
                    continue;
                }
                asked += 1;
                let hull = cls.hull(&corners, own(corners[0]), 0);
                match hull {
                    Hull::Lit => lit += 1,
                    Hull::Shadowed => shadowed += 1,
                    Hull::Unknown => continue,
                }
                straddling += usize::from(corners.iter().any(|&p| own(p) != own(corners[0])));
                every_point_agrees(&cls, &corners, 16, own, hull, &format!("res {res}, centre {centre}"));
            }
        }
    }
    // Not vacuous: the shortcut answers often, both ways, and declines at shadow borders (far
    // from the origin the points' rounding nears the tolerance, and lit hulls on a plane group
    // are declined there); some decided hulls straddle the floor's two triangles.
    assert!(
        lit * 6 > asked && shadowed * 40 > asked && lit + shadowed < asked && straddling > 20,
        "{lit} + {shadowed} of {asked}, {straddling} straddling"
    );
}

#[test]
fn hull_declines_paraboloids_and_empty_input() {
    let tris = vec![[Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)]];
    let opts = MapOptions { kind: MapKind::Paraboloid, resolution: 64, ..MapOptions::default() };
    let map = LightMap::build(&tris, Vec3::Y, &opts, &[true; 2]);
    let planes = triangle_planes(&tris);
    let cls = Classifier { map: &map, planes: &planes, bias: 1.0, point_error: 0.0, cutouts: &[] };
    assert_eq!(cls.hull(&[Vec3::ZERO, Vec3::new(0.01, 0.0, 0.0)], 0, 0), Hull::Unknown);
    assert_eq!(cls.hull(&[], 0, 0), Hull::Unknown);
}

/// An occluder that hides a floor exactly, as the light sees it (the floor scaled towards the
/// light), with nothing beyond the floor's edge: tiles at the edge read a region of the
/// occluder's texels and empty ones. A point whose footprint holds an empty texel is a border,
/// so the tile test may not call the tile shadowed.
#[test]
fn hull_over_an_occluder_and_nothing_is_no_shadow() {
    let light = Vec3::new(0.1, 2.0, 0.05);
    let floor = [
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, 1.0),
    ];
    let lid = floor.map(|p| light + (p - light) * 0.5);
    let tris = vec![
        [floor[0], floor[1], floor[2]],
        [floor[0], floor[2], floor[3]],
        [lid[0], lid[1], lid[2]],
        [lid[0], lid[2], lid[3]],
    ];
    let planes = triangle_planes(&tris);
    let (mut asked, mut declined) = (0, 0);
    for res in [64, 256, 1024] {
        let opts = MapOptions { kind: MapKind::Cube, resolution: res, ..MapOptions::default() };
        let map = LightMap::build(&tris, light, &opts, &[true; 6]);
        let cls = classifier(&map, &planes, &tris);
        // Tiles along the floor's x = 1 edge (on triangle 0, where x > z), a few texels wide.
        for k in 0..200 {
            let z = -0.9 + 1.0 * k as f32 / 200.0;
            let d = 4.0 / res as f32;
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(a, b)| Vec3::new(1.0 - d * (1.0 - a) - 1e-4, 0.0, z + d * b * 0.5));
            asked += 1;
            let hull = cls.hull(&corners, 0, 0);
            if hull == Hull::Unknown {
                declined += 1;
                continue;
            }
            every_point_agrees(&cls, &corners, 8, |_| 0, hull, &format!("res {res}"));
        }
    }
    assert!(declined > 0 && asked > 0, "{declined} of {asked} declined");
}

/// A floor of many small triangles of one plane (in a map summarised by triangle, so no
/// summary sees one triangle under a tile) under a crumpled roof of many small triangles of
/// different planes: tiles away from the roof see several floor triangles and decide lit,
/// tiles under it see several occluder planes and decide shadowed, and every decision is every
/// point's, with no border.
#[test]
fn hull_decides_regions_of_several_planes() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    // A power of two: every cell the same to the bit, and so every plane.
    let n = 32;
    let height = |_: f32, _: f32| 0.0;
    let at = |i: usize, j: usize| {
        let (x, z) = (-1.0 + 2.0 * i as f32 / n as f32, -1.0 + 2.0 * j as f32 / n as f32);
        Vec3::new(x, height(x, z), z)
    };
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    // The floor triangle under `(x, z)`: cell `(i, j)`, the first of its pair where x - x_i >
    // z - z_j.
    let own = |p: Vec3| {
        let (u, v) = ((p.x + 1.0) * n as f32 / 2.0, (p.z + 1.0) * n as f32 / 2.0);
        let (i, j) = ((u as usize).min(n - 1), (v as usize).min(n - 1));
        (2 * (j * n + i) + usize::from(u - i as f32 <= v - j as f32)) as u32
    };
    let floor = tris.len();
    // The roof over x < 0: a grid of triangles at heights 0.9 to 1.1 above the floor.
    let m = 8;
    let roof: Vec<Vec<Vec3>> = (0..=m)
        .map(|j| {
            (0..=m)
                .map(|i| {
                    let (x, z) = (-0.9 + 0.8 * i as f32 / m as f32, -0.8 + 1.6 * j as f32 / m as f32);
                    Vec3::new(x, height(x, z) + 0.9 + 0.2 * rng.f32(), z)
                })
                .collect()
        })
        .collect();
    for j in 0..m {
        for i in 0..m {
            tris.push([roof[j][i], roof[j][i + 1], roof[j + 1][i + 1]]);
            tris.push([roof[j][i], roof[j + 1][i + 1], roof[j + 1][i]]);
        }
    }
    let light = Vec3::new(-0.3, 3.0, 0.1);
    let planes = triangle_planes(&tris);
    assert!(planes[..floor].iter().all(|p| *p == planes[0]), "the floor's triangles share a plane");
    let (mut asked, mut lit, mut shadowed) = (0, 0, 0);
    for res in [256, 1024] {
        let opts = MapOptions { kind: MapKind::Cube, resolution: res, ..MapOptions::default() };
        let map = LightMap::build(&tris, light, &opts, &[true; 6]);
        let cls = classifier(&map, &planes, &tris);
        for _ in 0..400 {
            // A tile's corners on the floor, spanning several of its triangles.
            let (x, z) = (-0.95 + 1.8 * rng.f32(), -0.95 + 1.8 * rng.f32());
            let d = 0.05 + 0.1 * rng.f32();
            let corners = [(0.0, 0.0), (d, 0.0), (0.0, d), (d, d)]
                .map(|(a, b)| Vec3::new(x + a, height(x + a, z + b), z + b));
            asked += 1;
            let hull = cls.hull(&corners, own(corners[0]), 0);
            match hull {
                Hull::Lit => lit += 1,
                Hull::Shadowed => shadowed += 1,
                Hull::Unknown => continue,
            }
            every_point_agrees(&cls, &corners, 12, own, hull, &format!("res {res}"));
        }
    }
    // Each tile spans several floor triangles (and, under the roof, several occluders), so
    // without reading the triangles the summaries cannot name, every one would be declined.
    assert!(lit * 3 > asked && shadowed * 3 > asked, "{lit} lit and {shadowed} shadowed of {asked}");
}
