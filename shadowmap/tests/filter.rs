//! Percentage-closer filtering of VPL map lookups (`Classifier::visibility_at`) against the
//! single texel (`Classifier::visible_at`) and against exact visibility.
//!
//! A VPL on a ceiling looks down (one paraboloid hemisphere) at a floor, with a square occluder
//! turned 17 degrees about the vertical between them, so that its shadow's edges cross the
//! texel grid at every offset. Floor points on a fine grid around the shadow are decided three
//! ways: exactly (an `f64` segment test against the occluder), by the texel under each point,
//! and by the bilinear 2x2 footprint.
//!
//! Why the filtered value should do better in the mean square: along a straight edge that falls
//! at a uniformly random offset between two texel centres, the single texel is wrong over a
//! length of `1/4` texel on average (squared error 1 there), the bilinear ramp leaves a squared
//! error of `((e^3 + (1 - e)^3) / 3)`, `1/6` texel on average: two thirds of it. (In absolute
//! error the ramp is worse, `1/3` against `1/4`: PSNR is a squared-error measure.)

mod common;

use common::blocks;
use glam::Vec3;
use hyrt_shadowmap::{
    LightMap, MapKind, MapOptions,
    classify::{Classifier, triangle_planes},
};

/// Two triangles of the quad `c + (+-1) a + (+-1) b`.
fn quad(c: Vec3, a: Vec3, b: Vec3) -> [[Vec3; 3]; 2] {
    [[c - a - b, c + a - b, c + a + b], [c - a - b, c + a + b, c - a + b]]
}

#[test]
fn bilinear_vpl_lookups_have_less_squared_error_at_shadow_edges() {
    let vpl = Vec3::new(0.0, 1.0, 0.0);
    let (s, c) = 17f32.to_radians().sin_cos();
    let floor = quad(Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 4.0));
    let occluder =
        quad(Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.3 * c, 0.0, 0.3 * s), Vec3::new(-0.3 * s, 0.0, 0.3 * c));
    let tris: Vec<[Vec3; 3]> = floor.into_iter().chain(occluder).collect();
    let planes = triangle_planes(&tris);
    let opts = MapOptions { kind: MapKind::Paraboloid, resolution: 128, tess_texels: 4.0 };
    let map = LightMap::build_hemisphere(&tris, vpl, Vec3::NEG_Y, &opts);
    let cls = Classifier { map: &map, planes: &planes, bias: 0.5, point_error: 0.0, cutouts: &[] };

    let (mut n, mut edge, mut se_texel, mut se_bilinear, mut fractional) = (0, 0, 0.0, 0.0, 0);
    let steps = 400;
    for iz in 0..steps {
        for ix in 0..steps {
            // The shadow is the occluder scaled by 2 about the foot of the VPL: |x|, |z| < 0.85.
            let (x, z) = (
                -1.0 + 2.0 * (ix as f32 + 0.5) / steps as f32,
                -1.0 + 2.0 * (iz as f32 + 0.5) / steps as f32,
            );
            let p = Vec3::new(x, 0.0, z);
            let exact =
                if occluder.iter().any(|t| blocks(vpl.as_dvec3(), p.as_dvec3(), t)) { 0.0 } else { 1.0 };
            let at = cls.locate(p);
            let texel = if cls.visible_at(p, 0, at) { 1.0 } else { 0.0 };
            let bilinear = cls.visibility_at(p, 0, at);
            assert!((0.0..=1.0).contains(&bilinear), "({x}, {z}): {bilinear}");
            if bilinear > 0.0 && bilinear < 1.0 {
                fractional += 1;
            } else {
                // A footprint that agrees everywhere decides as its texel does.
                assert_eq!(bilinear, texel, "({x}, {z}): a whole footprint disagrees with its texel");
            }
            n += 1;
            if texel != exact || bilinear != exact {
                edge += 1;
            }
            se_texel += (texel - exact) * (texel - exact);
            se_bilinear += (bilinear - exact) * (bilinear - exact);
        }
    }
    println!(
        "{n} points, {edge} not exact either way, {fractional} fractional; squared error: texel {se_texel:.1}, bilinear {se_bilinear:.1} ({:.2}x)",
        se_bilinear / se_texel
    );
    // Both are exact away from the edges: within about a texel's footprint (0.03 units at the
    // floor below the VPL) of the shadow's outline (6.8 units long in the 2 x 2 square), a few
    // percent of the points.
    assert!(edge > 100 && edge * 10 < n, "{edge} of {n} points near an edge");
    assert!(fractional > 0, "no footprint straddled an edge");
    // Two thirds in theory (module docs); 0.8 leaves room for the corners and the tessellation.
    assert!(se_bilinear < 0.8 * se_texel, "bilinear {se_bilinear:.1} vs texel {se_texel:.1}");
}
