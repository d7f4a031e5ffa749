//! Occluders with holes (alpha cut-outs, `Classifier::cutouts`): the map holds them solid, so
//! a point they would shadow is a border that only a ray settles, never a decided shadow, and
//! the tile shortcut does not decide under them; a point they do not cover is decided as
//! before.

use glam::Vec3;
use hyrt_shadowmap::{
    LightMap, MapKind, MapOptions,
    classify::{Classifier, Decision, Hull, plane_groups, triangle_planes},
    map::EMPTY,
};

/// A square at height `h` of half-size `s` around the y axis.
fn square(h: f32, s: f32) -> [Vec3; 4] {
    [Vec3::new(-s, h, -s), Vec3::new(s, h, -s), Vec3::new(s, h, s), Vec3::new(-s, h, s)]
}

/// Its two triangles.
fn quad(c: [Vec3; 4]) -> [[Vec3; 3]; 2] {
    [[c[0], c[2], c[1]], [c[0], c[3], c[2]]]
}

/// A floor of half-size `half` at y = 0 (ids 0, 1) and a lid of half-size 0.5 at y = 1 (ids 2,
/// 3), for lights at y = 2.
fn floor_and_lid(half: f32) -> Vec<[Vec3; 3]> {
    [quad(square(0.0, half)), quad(square(1.0, 0.5))].concat()
}

#[test]
fn points_under_a_cut_out_are_borders_for_a_ray() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    // A floor (ids 0, 1) and a lid half-way to the light over its middle (ids 2, 3).
    let tris = floor_and_lid(2.0);
    let planes = triangle_planes(&tris);
    let opts = MapOptions { kind: MapKind::Cube, resolution: 256, ..MapOptions::default() };
    let map = LightMap::build(&tris, light, &opts, &[true; 6]);
    let solid = Classifier { map: &map, planes: &planes, bias: 1.0, point_error: 0.0, cutouts: &[] };
    let holes = [false, false, true, true];
    let cut = Classifier { cutouts: &holes, ..solid };
    let under = Vec3::new(0.3, 0.0, -0.2);
    let (a, b) = (solid.classify(under, 0), cut.classify(under, 0));
    assert_eq!((a.decision, a.map_border), (Decision::Shadow, false));
    // Still leaning to shadow, with the lid as the ray's hint; a border, and no suspects to
    // settle it by (what the holes let through may meet an occluder that no texel holds).
    assert_eq!((b.decision, b.map_border, b.suspects), (Decision::Shadow, true, [EMPTY; 2]));
    assert!(b.hint == 2 || b.hint == 3, "{b:?}");
    // Beside the lid nothing changes.
    let beside = Vec3::new(1.8, 0.0, 1.8);
    assert_eq!(solid.classify(beside, 0), cut.classify(beside, 0));
    assert_eq!(cut.classify(beside, 0).decision, Decision::Lit);
    // The tile shortcut: shadowed under the solid lid, undecided under the cut-out.
    let tile = [under, under + Vec3::X * 0.01, under + Vec3::Z * 0.01, under + Vec3::new(0.01, 0.0, 0.01)];
    assert_eq!(solid.hull(&tile, 0, 0), Hull::Shadowed);
    assert_eq!(cut.hull(&tile, 0, 0), Hull::Unknown);
    // Plane groups never mix triangles with and without holes (the lid's two triangles are
    // coplanar: one group with or without holes, but apart from a solid twin).
    let mut twin = tris.clone();
    twin.push(tris[2]);
    let g = plane_groups(&triangle_planes(&twin), &[false, false, true, true, false]);
    assert_eq!((g[2], g[3], g[4]), (2, 2, 4));
    assert_eq!(plane_groups(&triangle_planes(&twin), &[])[4], 2);
}

/// A VPL map's texels that see a cut-out's hole hold what lies behind it; its solid parts
/// stay. Here a lid over a floor is all hole to the left of `x = 0` and solid to the right, as
/// the test says at each texel's centre.
#[test]
fn vpl_map_texels_see_through_holes() {
    use hyrt_shadowmap::vpl_map::{Holes, VplFormat, VplMap};
    let o = Vec3::new(0.0, 2.0, 0.0);
    let tris = floor_and_lid(3.0);
    let planes = triangle_planes(&tris);
    let opts = MapOptions { kind: MapKind::Cube, resolution: 64, ..MapOptions::default() };
    let cutouts = [false, false, true, true];
    let gone = [Vec3::NAN; 3];
    let solid = vec![tris[0], tris[1], gone, gone];
    let left_hole = |_: u32, dir: Vec3| dir.x < 0.0;
    let holes = Holes { cutouts: &cutouts, solid: &solid, hole: &left_hole };
    let down = Vec3::NEG_Y;
    let planes_of = |m: &VplMap| m.planes().expect("planes").to_vec();
    let with_lid = planes_of(&VplMap::build(&tris, &planes, o, down, &opts, VplFormat::Planes));
    let without = planes_of(&VplMap::build(&solid, &planes, o, down, &opts, VplFormat::Planes));
    let cut = VplMap::build_with_holes(&tris, &planes, o, down, &opts, VplFormat::Planes, Some(&holes));
    let got = planes_of(&cut);
    let (mut through, mut kept) = (0, 0);
    for (i, g) in got.iter().enumerate() {
        let (x, y) = (i as u32 % 64, i as u32 / 64);
        if with_lid[i] == without[i] {
            assert_eq!(*g, with_lid[i]);
            continue;
        }
        // A texel that sees the lid: the floor behind it on the left, the lid on the right.
        if cut.centre_dir(x, y).x < 0.0 {
            assert_eq!(*g, without[i], "texel ({x}, {y})");
            through += 1;
        } else {
            assert_eq!(*g, with_lid[i], "texel ({x}, {y})");
            kept += 1;
        }
    }
    assert!(through > 50 && kept > 50, "{through} through, {kept} kept");
    // No cut-outs: the plain map.
    let none = VplMap::build_with_holes(&tris, &planes, o, down, &opts, VplFormat::Planes, None);
    assert_eq!(planes_of(&none), with_lid);
}

/// Paged maps that resolve holes: a texel whose centre sees a cut-out's hole holds what lies
/// behind it; where another cut-out lies along its ray too, the map cannot tell (`ABSENT`).
#[test]
fn paged_texels_see_through_holes_unless_another_cut_out_is_along_the_ray() {
    use hyrt_shadowmap::{ABSENT, PageKey, map::Holes};
    let light = Vec3::new(0.0, 2.0, 0.0);
    let mut tris = floor_and_lid(3.0);
    let opts = MapOptions { kind: MapKind::Cube, ..MapOptions::default() };
    let face = LightMap::face_of(MapKind::Cube, Vec3::NEG_Y);
    let pages = [PageKey { level: 0, face, px: 0, py: 0 }];
    let left_hole = |_: u32, dir: Vec3| dir.x < 0.0;
    let cutouts = [false, false, true, true, true, true];
    let holes = Holes { cutouts: &cutouts, solid: &[], hole: &left_hole };
    let plain = LightMap::build_pages(&tris, light, &opts, &pages, &[]);
    let cut = LightMap::build_pages_with_holes(&tris, light, &opts, &pages, &[], Some(&holes));
    assert!(cut.resolves_holes() && !plain.resolves_holes());
    let (mut through, mut kept) = (0, 0);
    for y in 0..32 {
        for x in 0..32 {
            let (a, b) = (plain.id_at(0, face, x, y), cut.id_at(0, face, x, y));
            if a < 2 {
                assert_eq!(a, b);
            } else if cut.texel_dir_at(face, 0, f64::from(x) + 0.5, f64::from(y) + 0.5).x < 0.0 {
                assert!(b < 2, "({x}, {y}): {b}");
                through += 1;
            } else {
                assert_eq!(a, b);
                kept += 1;
            }
        }
    }
    assert!(through > 20 && kept > 20, "{through} through, {kept} kept");
    // A second cut-out under the first: behind a hole of the first lies the second, which the
    // map without cut-outs would not show.
    tris.extend(quad(square(0.5, 1.0)));
    let cut = LightMap::build_pages_with_holes(&tris, light, &opts, &pages, &[], Some(&holes));
    let (mut absent, mut lid) = (0, 0);
    for y in 0..32 {
        for x in 0..32 {
            match cut.id_at(0, face, x, y) {
                ABSENT => absent += 1,
                2 | 3 => lid += 1,
                _ => {}
            }
        }
    }
    assert!(absent > 20 && lid > 20, "{absent} absent, {lid} on the lid");
}
