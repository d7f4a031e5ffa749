//! Round trips and seams of the omnidirectional parameterisations.

use glam::{Vec2, Vec3};
use hyrt_shadowmap::{CubeFace, Hemisphere, cube_lookup, paraboloid_project, paraboloid_unproject};

/// Deterministic directions spread over the sphere (a Fibonacci lattice).
fn directions(n: usize) -> impl Iterator<Item = Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n).map(move |i| {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f32;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

#[test]
fn paraboloid_round_trip_is_within_a_few_ulps() {
    let mut worst = 0.0f32;
    for d in directions(20_000) {
        let (h, uv) = paraboloid_project(d);
        assert!(uv.length() <= 1.0 + 1e-6, "{d} -> {uv} leaves the disc");
        let back = paraboloid_unproject(h, uv);
        worst = worst.max((back - d).length());
    }
    assert!(worst < 4e-7, "worst round-trip error {worst:e}");
}

#[test]
fn paraboloid_seam_is_continuous() {
    // Directions at the equator (z = 0) land on the rim of both maps at the same place.
    for i in 0..360 {
        let a = (i as f32).to_radians();
        let eq = Vec3::new(a.cos(), a.sin(), 0.0);
        let (h, uv) = paraboloid_project(eq);
        assert_eq!(h, Hemisphere::Front);
        assert!((uv.length() - 1.0).abs() < 1e-6);
        let just_below = Vec3::new(a.cos(), a.sin(), -1e-4);
        let (h2, uv2) = paraboloid_project(just_below);
        assert_eq!(h2, Hemisphere::Back);
        assert!((uv - uv2).length() < 2e-4, "seam jump at {i} degrees: {uv} vs {uv2}");
    }
    assert_eq!(paraboloid_project(Vec3::Z).1, Vec2::ZERO);
}

#[test]
fn cube_lookup_picks_the_major_axis_and_stays_in_range() {
    assert_eq!(cube_lookup(Vec3::new(0.2, -0.9, 0.1)).0, CubeFace::NegY);
    assert_eq!(cube_lookup(Vec3::new(0.0, 0.0, 3.0)), (CubeFace::PosZ, Vec2::ZERO));
    for d in directions(5_000) {
        let (_, uv) = cube_lookup(d);
        assert!(uv.abs().max_element() <= 1.0, "{d} -> {uv}");
    }
}
