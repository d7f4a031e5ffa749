//! Paged light maps ([`LightMap::build_pages`]): each page drawn alone through its own
//! projection agrees with the whole face, pages are independent of which others are drawn,
//! pages not drawn read `ABSENT`, and the fine levels place occluders a whole map of the
//! rasterizer's largest size cannot resolve.

use glam::{DVec3, Vec3};
use hyrt_shadowmap::{
    ABSENT, EMPTY, LightMap, MapKind, MapOptions, PAGE, PageKey,
    classify::{Classifier, Decision, triangle_planes},
    paged,
};
use hyrt_testkit::Rng;

/// Random triangles in a shell around the origin (the light), of all sizes: some spanning many
/// pages, some smaller than a texel.
fn scene(seed: u64, n: usize) -> Vec<[Vec3; 3]> {
    let mut rng = Rng(seed);
    let mut v = || DVec3::new(rng.f64(), rng.f64(), rng.f64()) * 2.0 - 1.0;
    (0..n)
        .map(|i| {
            let c = v().normalize() * (2.0 + 3.0 * (i % 7) as f64);
            let size = [2.0, 0.3, 0.02][i % 3];
            [c + v() * size, c + v() * size, c + v() * size].map(|p| p.as_vec3())
        })
        .collect()
}

fn opts(resolution: u32) -> MapOptions {
    MapOptions { kind: MapKind::Cube, resolution, tess_texels: 8.0 }
}

/// Every page of `level` on every face.
fn all_pages(level: u8) -> Vec<PageKey> {
    let n = 1u32 << level;
    let mut out = Vec::new();
    for face in 0..6 {
        for py in 0..n {
            for px in 0..n {
                out.push(PageKey { level, face, py, px });
            }
        }
    }
    out
}

#[test]
fn pages_agree_with_the_whole_face_at_the_same_resolution() {
    // Level 2 has PAGE << 2 texels per side: the whole map of that resolution is the same grid.
    let tris = scene(7, 600);
    let light = Vec3::ZERO;
    let res = PAGE << 2;
    let whole = LightMap::build(&tris, light, &opts(res), &[true; 6]);
    let paged = LightMap::build_pages(&tris, light, &opts(0), &all_pages(2), &[]);
    assert!(paged.is_paged() && !whole.is_paged());
    let planes = triangle_planes(&tris);
    let cls = Classifier { map: &paged, planes: &planes, bias: 1.0, point_error: 0.0, cutouts: &[] };
    assert_eq!(paged.page_count(), 6 * 16);
    let (mut texels, mut same, mut covered) = (0u64, 0u64, 0u64);
    for face in 0..6u8 {
        for y in 0..res {
            for x in 0..res {
                let (a, b) = (whole.id(face, x, y), paged.id_at(2, face, x, y));
                texels += 1;
                covered += u64::from(a != EMPTY);
                if a == b {
                    same += 1;
                    if a != EMPTY {
                        // Same triangle, same depth: the whole map's stored one and, from the
                        // plane, the paged map's (which stores none), to a few ulps.
                        assert!(paged.depth_at(2, face, x, y).is_nan(), "a paged map stores no depths");
                        let (da, db) = (whole.depth(face, x, y), cls.depth_at(2, face, x, y));
                        assert!((da - db).abs() <= 1e-5 * da, "({face}, {x}, {y}): {da} vs {db}");
                    }
                }
            }
        }
    }
    println!("{same} of {texels} texels agree ({covered} covered)");
    // Each page snaps its vertices in its own coordinates: only texel centres within a
    // snapping step (1/256 texel) of an edge may change hands.
    assert!(covered > texels / 4, "the scene covers too little: {covered}");
    assert!((texels - same) * 1000 < texels, "{} of {texels} texels differ", texels - same);
}

#[test]
fn a_page_is_the_same_whichever_others_are_drawn_and_merges_are_exact() {
    let tris = scene(11, 400);
    let light = Vec3::new(0.1, -0.2, 0.05);
    let pages = all_pages(3);
    let (even, odd): (Vec<PageKey>, Vec<PageKey>) =
        pages.iter().partition(|k| (k.px + k.py + u32::from(k.face)) % 2 == 0);
    let full = LightMap::build_pages(&tris, light, &opts(0), &pages, &[]);
    let mut merged = LightMap::build_pages(&tris, light, &opts(0), &even, &[]);
    let part = merged.clone();
    merged.merge(LightMap::build_pages(&tris, light, &opts(0), &odd, &[]));
    assert_eq!(merged.pages(), full.pages());
    let res = PAGE << 3;
    let mut absent = 0;
    for face in 0..6u8 {
        for y in (0..res).step_by(3) {
            for x in (0..res).step_by(3) {
                assert_eq!(merged.id_at(3, face, x, y), full.id_at(3, face, x, y));
                assert_eq!(merged.depth_at(3, face, x, y).to_bits(), full.depth_at(3, face, x, y).to_bits());
                let k = PageKey { level: 3, face, py: y / PAGE, px: x / PAGE };
                if part.has_page(k) {
                    assert_eq!(part.id_at(3, face, x, y), full.id_at(3, face, x, y));
                } else {
                    assert_eq!(part.id_at(3, face, x, y), ABSENT);
                    assert_eq!(part.depth_at(3, face, x, y), f32::INFINITY);
                    absent += 1;
                }
            }
        }
    }
    assert!(absent > 0);
    // Levels not drawn at all read ABSENT too; outside the face, EMPTY.
    assert_eq!(full.id_at(5, 0, 10, 10), ABSENT);
    assert_eq!(full.id_at(3, 0, res, 0), EMPTY);
    // Eviction keeps what it keeps, bit for bit.
    let mut kept = full.clone();
    kept.retain_pages(|k| k.face == 2);
    assert_eq!(kept.page_count(), 64);
    for y in 0..res {
        assert_eq!(kept.id_at(3, 2, 17, y), full.id_at(3, 2, 17, y));
        assert_eq!(kept.id_at(3, 1, 17, y), ABSENT);
    }
    assert!(kept.memory_bytes() < full.memory_bytes() / 5);
}

#[test]
fn points_whose_pages_were_not_drawn_are_left_to_rays() {
    // A floor under a small occluder; only the pages around one point are drawn.
    let q = |y: f32, r: f32| {
        let v = |x: f32, z: f32| Vec3::new(x, y, z);
        [[v(-r, -r), v(r, r), v(r, -r)], [v(-r, -r), v(-r, r), v(r, r)]]
    };
    let tris: Vec<[Vec3; 3]> = q(0.0, 4.0).into_iter().chain(q(1.0, 0.25)).collect();
    let planes = triangle_planes(&tris);
    let light = Vec3::new(0.0, 2.0, 0.0);
    let level = 4;
    let marked = |p: Vec3| {
        let mut keys = Vec::new();
        paged::pages_around(paged::locate(p - light, level), |k| keys.push(k));
        keys
    };
    let under = Vec3::new(0.0, 0.0, 0.1);
    let map = LightMap::build_pages(&tris, light, &opts(0), &marked(under), &[]);
    let cls = Classifier { map: &map, planes: &planes, bias: 1.0, point_error: 0.0, cutouts: &[] };
    let lk = cls.classify_at(under, 1, cls.locate_at(under, level));
    assert_eq!((lk.decision, lk.map_border), (Decision::Shadow, false));
    assert!(lk.hint == 2 || lk.hint == 3);
    // The border rays' cheaper hint names the occluder too, and never the floor's other
    // triangle (the point's own plane), nor anything where the pages are missing.
    assert!(matches!(cls.hint_at(1, cls.locate_at(under, level)), 2 | 3));
    let open = Vec3::new(0.7, 0.0, 0.0);
    let marked_open = marked(open);
    let map_open = LightMap::build_pages(&tris, light, &opts(0), &marked_open, &[]);
    let cls_open = Classifier { map: &map_open, ..cls };
    assert_eq!(cls_open.hint_at(1, cls_open.locate_at(open, level)), EMPTY);
    assert_eq!(cls.hint_at(0, cls.locate_at(Vec3::new(3.5, 0.0, 3.5), level)), EMPTY);
    // Far from the drawn pages: undecided, no hint (a ray decides).
    let far = Vec3::new(3.5, 0.0, 3.5);
    let lk = cls.classify_at(far, 0, cls.locate_at(far, level));
    assert!(lk.map_border && lk.hint == EMPTY, "{lk:?}");
    // At a level with no page: the same.
    let lk = cls.classify_at(under, 1, cls.locate_at(under, level + 1));
    assert!(lk.map_border, "{lk:?}");
}

#[test]
fn fine_levels_resolve_a_thin_occluder_far_from_the_light() {
    // A light 1000 units away; a rail 0.01 wide (1e-5 radians from the light) over a floor.
    // A whole face of 2048 texels has texels of about 1e-3 radians: the rail falls between
    // texel centres. At the level of 262144 texels per side, 2 / 262144 = 7.6e-6 radians.
    let light = Vec3::new(0.0, 1000.0, 0.0);
    let rail = |x0: f32, x1: f32, y: f32| {
        let v = |x: f32, z: f32| Vec3::new(x, y, z);
        [[v(x0, -2.0), v(x1, 2.0), v(x1, -2.0)], [v(x0, -2.0), v(x0, 2.0), v(x1, 2.0)]]
    };
    let tris: Vec<[Vec3; 3]> = rail(-3.0, 3.0, 0.0).into_iter().chain(rail(-0.005, 0.005, 1.0)).collect();
    let planes = triangle_planes(&tris);
    // Points under the rail, across its shadow.
    let shadowed = |map: &LightMap, level: u8| -> usize {
        let cls = Classifier { map, planes: &planes, bias: 1.0, point_error: 0.0, cutouts: &[] };
        (0..20)
            .filter(|&i| {
                let p = Vec3::new(-0.0045 + 0.009 * i as f32 / 19.0, 0.0, 0.3);
                let lk = cls.classify_at(p, 0, cls.locate_at(p, level));
                lk.decision == Decision::Shadow
            })
            .count()
    };
    let whole = LightMap::build(&tris, light, &opts(2048), &[true; 6]);
    let level = (262144 / PAGE).trailing_zeros() as u8;
    let mut keys = Vec::new();
    for i in 0..20 {
        let p = Vec3::new(-0.0045 + 0.009 * i as f32 / 19.0, 0.0, 0.3);
        paged::pages_around(paged::locate(p - light, level), |k| keys.push(k));
    }
    let paged_map = LightMap::build_pages(&tris, light, &opts(0), &keys, &[]);
    let (w, p) = (shadowed(&whole, 0), shadowed(&paged_map, level));
    println!("shadowed points: whole 2048 {w} of 20, paged level {level} {p} of 20");
    assert_eq!(p, 20);
    assert!(w < 20);
}

/// `LightMap::quad_ids` (a footprint's 2x2 ids from one page) gives `ids_at`'s ids wherever it
/// answers, answers wherever the four lie in one page of the face, and reads `ABSENT` in pages
/// not drawn and on faces with none: every 2x2 block of two levels of a map drawn with every
/// other page, and of a whole map.
#[test]
fn a_footprints_ids_from_one_page_are_the_texels_ids() {
    let tris = scene(11, 300);
    let light = Vec3::ZERO;
    let keys: Vec<PageKey> = [all_pages(1), all_pages(2)]
        .concat()
        .into_iter()
        .filter(|k| (k.px + k.py) % 2 == 0 && k.face != 3)
        .collect();
    let paged = LightMap::build_pages(&tris, light, &opts(0), &keys, &[]);
    let whole = LightMap::build(&tris, light, &opts(64), &[true; 6]);
    let (mut answered, mut absent) = (0, 0);
    for (map, levels) in [(&paged, 1..=2u8), (&whole, 0..=0)] {
        for level in levels {
            let res = map.resolution_at(level);
            for face in 0..6u8 {
                for y in 0..res {
                    for x in 0..res {
                        let quad = map.quad_ids(level, face, x, y);
                        let one_page =
                            x % PAGE != PAGE - 1 && y % PAGE != PAGE - 1 && x + 1 < res && y + 1 < res;
                        assert_eq!(quad.is_some(), one_page, "({level}, {face}, {x}, {y})");
                        if let Some(q) = quad {
                            let ids =
                                map.ids_at(level, face, [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)]);
                            assert_eq!(q, ids, "level {level}, face {face}, ({x}, {y})");
                            answered += 1;
                            absent += usize::from(q[0] == ABSENT);
                        }
                    }
                }
            }
        }
    }
    assert!(answered > 10_000 && absent > 1_000, "{answered} answered, {absent} absent");
    assert!(whole.quad_ids(0, 0, 0, 0).is_some_and(|q| q.iter().all(|&id| id != ABSENT)));
}

/// A page whose texels all hold one id stores that id alone, and reads as a stored one: a
/// light inside a box (two triangles a side, so that each face's diagonal pages hold two ids
/// and the others one) reads the whole map's ids at every texel of every face, through
/// `id_at`, `ids_at` and `quad_ids`, after a merge and after an eviction too, and stores
/// under half the texels of its pages.
#[test]
fn pages_of_one_id_store_that_id_alone() {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * 2.0;
    let corner = |i: u32| {
        c(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        )
    };
    let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    let tris: Vec<[Vec3; 3]> = quads
        .iter()
        .flat_map(|q| {
            [[corner(q[0]), corner(q[1]), corner(q[2])], [corner(q[0]), corner(q[2]), corner(q[3])]]
        })
        .collect();
    let light = Vec3::new(0.01, 0.02, 0.03);
    let level = 3;
    let keys = all_pages(level);
    let (even, odd): (Vec<PageKey>, Vec<PageKey>) = keys.iter().partition(|k| (k.px + k.py) % 2 == 0);
    let paged = LightMap::build_pages(&tris, light, &opts(0), &keys, &[]);
    let mut merged = LightMap::build_pages(&tris, light, &opts(0), &even, &[]);
    merged.merge(LightMap::build_pages(&tris, light, &opts(0), &odd, &[]));
    let mut kept = paged.clone();
    kept.retain_pages(|k| k.face != 4);
    let res = PAGE << level;
    let whole = LightMap::build(&tris, light, &opts(res), &[true; 6]);
    for face in 0..6u8 {
        for y in 0..res {
            for x in 0..res {
                let want = whole.id_at(0, face, x, y);
                assert_eq!(paged.id_at(level, face, x, y), want, "({face}, {x}, {y})");
                assert_eq!(merged.id_at(level, face, x, y), want, "merged ({face}, {x}, {y})");
                assert_eq!(kept.id_at(level, face, x, y), if face == 4 { ABSENT } else { want });
                assert_eq!(paged.ids_at(level, face, [(x, y)]), [want]);
                if let Some(q) = paged.quad_ids(level, face, x, y) {
                    assert_eq!(q[0], want);
                }
            }
        }
    }
    let texels = keys.len() * (PAGE * PAGE) as usize * 4;
    assert!(paged.memory_bytes() < texels / 2, "{} of {texels}", paged.memory_bytes());
    assert_eq!(merged.memory_bytes(), paged.memory_bytes());
}

/// `LightMap::region_ids` reports every id the box's texels hold and no other (pages of one
/// id, palettes and plain ids; boxes across blocks, pages and pages not drawn), as reading each
/// texel with `id_at` does.
#[test]
fn region_ids_are_the_ids_of_the_boxs_texels() {
    let tris = scene(23, 900);
    let light = Vec3::new(0.05, 0.1, -0.02);
    // Every other page of level 3: boxes meet drawn pages and absent ones.
    let pages: Vec<PageKey> = all_pages(3).into_iter().filter(|k| (k.px + k.py) % 2 == 0).collect();
    let map = LightMap::build_pages(&tris, light, &opts(0), &pages, &[]);
    let res = PAGE << 3;
    let mut rng = Rng(5);
    let (mut boxes, mut mixed) = (0, 0);
    for _ in 0..3000 {
        let face = rng.below(6) as u8;
        let (x0, y0) = (rng.below(res as usize) as u32, rng.below(res as usize) as u32);
        let (x1, y1) = ((x0 + rng.below(40) as u32).min(res - 1), (y0 + rng.below(40) as u32).min(res - 1));
        let mut truth: Vec<u32> = (y0..=y1)
            .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
            .map(|(x, y)| map.id_at(3, face, x, y))
            .collect();
        truth.sort_unstable();
        truth.dedup();
        let mut seen = Vec::new();
        assert!(map.region_ids(face, 3, x0, y0, x1, y1, |id| {
            seen.push(id);
            true
        }));
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen, truth, "face {face}, [{x0}, {x1}] x [{y0}, {y1}]");
        boxes += 1;
        mixed += usize::from(truth.len() > 2);
    }
    // Stopping: the first `false` ends the walk.
    let mut calls = 0;
    assert!(!map.region_ids(0, 3, 0, 0, res - 1, res - 1, |_| {
        calls += 1;
        false
    }));
    assert_eq!(calls, 1);
    assert!(mixed > boxes / 10, "too few boxes of several triangles: {mixed} of {boxes}");
}
