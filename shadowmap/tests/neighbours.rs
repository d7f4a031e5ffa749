//! `Lookup::occluders` on a curved mesh: a half cylinder of flat strips, lit from the side,
//! has no point that the mesh shadows on its lit side (it is convex), yet near the terminator
//! its points' 2x2 footprints hold the next strips, whose planes cross the ray to the light
//! over the point: borders. Each such border names its occluders, and where they all share a
//! vertex with the point's own triangle, none of them blocks the point's segment to the light
//! (an exact `f64` test): testing them alone decides the point lit, as the truth is.

mod common;

use common::blocks;
use glam::Vec3;
use hyrt_shadowmap::{
    EMPTY, LightMap, MapKind, MapOptions,
    classify::{Classifier, triangle_planes},
};

#[test]
fn a_convex_meshs_borders_name_neighbours_that_do_not_block() {
    // The half cylinder y >= 0 of radius 1 about the z axis, 48 strips from angle 0 to pi, each
    // two triangles, z from -2 to 2.
    let n = 48;
    let at = |k: usize, z: f32| {
        let a = std::f32::consts::PI * k as f32 / n as f32;
        Vec3::new(a.cos(), a.sin(), z)
    };
    let tris: Vec<[Vec3; 3]> = (0..n)
        .flat_map(|k| {
            let (a0, a1, b0, b1) = (at(k, -2.0), at(k + 1, -2.0), at(k, 2.0), at(k + 1, 2.0));
            [[a0, b0, b1], [a0, b1, a1]]
        })
        .collect();
    let planes = triangle_planes(&tris);
    // Low over the +x side: the terminator crosses the upper strips.
    let light = Vec3::new(6.0, 1.5, 0.3);
    let opts = MapOptions { kind: MapKind::Cube, resolution: 256, tess_texels: f32::INFINITY };
    let map = LightMap::build(&tris, light, &opts, &[true; 6]);
    let cls = Classifier { map: &map, planes: &planes, bias: 1.0, point_error: 0.0, cutouts: &[] };
    let shares_vertex = |a: u32, b: u32| tris[a as usize].iter().any(|v| tris[b as usize].contains(v));

    let (mut borders, mut by_neighbours) = (0, 0);
    for (own, tri) in tris.iter().enumerate() {
        let own = own as u32;
        let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        for (u, v) in [(0.2, 0.2), (0.6, 0.2), (0.2, 0.6), (0.33, 0.33)] {
            let p = tri[0] + u * (tri[1] - tri[0]) + v * (tri[2] - tri[0]);
            // Points facing the light (the outward normal: away from the axis).
            let outward = if normal.dot(Vec3::new(p.x, p.y, 0.0)) > 0.0 { normal } else { -normal };
            if outward.dot(light - p) <= 0.0 {
                continue;
            }
            let lk = cls.classify(p, own);
            let named: Vec<u32> = lk.occluders.iter().copied().filter(|&t| t != EMPTY).collect();
            if !lk.map_border {
                assert!(named.is_empty(), "a lookup that is no border names occluders: {lk:?}");
                continue;
            }
            borders += 1;
            assert!(!named.contains(&own), "{lk:?}");
            let mut sorted = named.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), named.len(), "occluders named twice: {lk:?}");
            if named.is_empty() || !named.iter().all(|&t| shares_vertex(own, t)) {
                continue;
            }
            by_neighbours += 1;
            // The truth: nothing blocks a lit point of a convex mesh; and so none of its named
            // neighbours does.
            let (o, q) = (light.as_dvec3(), p.as_dvec3());
            // (Its own triangle left out: `p`, rounded to `f32`, may lie a hair behind it.)
            let mut others = tris.iter().enumerate().filter(|&(i, _)| i as u32 != own);
            assert!(!others.any(|(_, t)| blocks(o, q, t)), "the half cylinder shadows itself at {p}");
            assert!(!named.iter().any(|&t| blocks(o, q, &tris[t as usize])), "{lk:?}");
        }
    }
    eprintln!("{borders} borders, {by_neighbours} named only neighbours");
    assert!(by_neighbours > 0, "no border named only the point's neighbours ({borders} borders)");
}
