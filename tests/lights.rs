//! Spot lights: their cone and falloff, the same in the reference and the hybrid, no decision
//! or ray outside the cone, VPLs leaving only into it, and how scene files and glTF files
//! give them. Directional lights: placed far away, within their bound of parallel.

mod common;

use glam::{Vec3, vec3};
use hyrt::{
    render::{Options, vpl},
    scene::{self, PointLight, Spot},
};

#[test]
fn the_cone_and_its_falloff() {
    let s = Spot::new(vec3(0.0, -2.0, 0.0), 10f32.to_radians(), 30f32.to_radians());
    let at = |deg: f32| {
        let a = deg.to_radians();
        s.factor(vec3(a.sin(), -a.cos(), 0.0))
    };
    assert_eq!(at(0.0), 1.0);
    assert_eq!(at(9.9), 1.0);
    assert_eq!(at(30.1), 0.0);
    assert_eq!(at(90.0), 0.0);
    // Half-way in cosine between the two cones: (1/2)^2.
    let mid = ((10f32.to_radians().cos() + 30f32.to_radians().cos()) * 0.5).acos().to_degrees();
    assert!((at(mid) - 0.25).abs() < 1e-4, "{}", at(mid));
    // Monotone from the axis outwards.
    let f: Vec<f32> = (0..=40).map(|d| at(d as f32)).collect();
    assert!(f.windows(2).all(|w| w[1] <= w[0]), "{f:?}");
    // A point light is exactly its intensity everywhere; a spot's is scaled.
    let p = PointLight { position: Vec3::ZERO, intensity: Vec3::splat(2.0), spot: None };
    assert_eq!(p.intensity_towards(Vec3::X), Vec3::splat(2.0));
    let q = PointLight { spot: Some(s), ..p };
    assert_eq!(q.intensity_towards(Vec3::NEG_Y), Vec3::splat(2.0));
    assert!(q.dark_towards(Vec3::X) && !q.dark_towards(Vec3::NEG_Y) && !p.dark_towards(Vec3::X));
}

/// A floor seen from above, lit by a spot pointing down from height 2 (outer cone 25
/// degrees: a lit disc of radius 0.93 on a floor of half-size 2).
fn spot_floor(size: u32) -> scene::Scene {
    let spot = Spot::new(Vec3::NEG_Y, 15f32.to_radians(), 25f32.to_radians());
    let light = PointLight { position: vec3(0.0, 2.0, 0.0), intensity: Vec3::splat(4.0), spot: Some(spot) };
    common::floor_scene(2.0, Vec3::splat(0.8), 5.0, 50.0, vec![light], size, size)
}

/// Inside the cone the floor has the irradiance the cone's falloff gives; outside it is black;
/// the hybrid's image is the reference's, and it decides (and traces) nothing outside.
#[test]
fn a_spot_lights_its_cone_alone_the_same_in_both_renderers() {
    let s = spot_floor(64);
    let reference = common::render(&s, Options::reference());
    let hybrid = common::render(&s, Options::hybrid());
    assert_eq!(reference.film.pixels, hybrid.film.pixels);
    let px = |x: usize, y: usize| reference.film.pixels[y * 64 + x];
    // Straight under the light: E = I / h^2 = 1, radiance 0.8 / pi.
    let centre = px(32, 32);
    assert!((centre.x - 0.8 / std::f32::consts::PI).abs() < 0.01, "{centre}");
    // A corner of the floor is 45 degrees off the axis: dark.
    assert_eq!(px(2, 2), Vec3::ZERO);
    let lit = reference.film.pixels.iter().filter(|p| p.x > 0.0).count();
    // The lit disc: radius 2 tan 25 = 0.93 of the floor's visible 4.66 (fov 50 from 5).
    let expect = std::f32::consts::PI * (0.93f32 / 4.66 * 64.0).powi(2);
    assert!((lit as f32 - expect).abs() < 0.15 * expect, "{lit} lit pixels, about {expect} expected");
    // Every decision the hybrid made was for a point in the cone (or on its rim).
    let l = &hybrid.stats.lights[0];
    let decided = l.lit + l.shadowed + l.undecided;
    assert!(
        decided > 0 && decided as f32 <= 1.1 * expect,
        "{decided} decisions for about {expect} lit pixels"
    );
    assert!(
        reference.stats.rays.shadow as f32 <= 1.1 * expect,
        "{} shadow rays",
        reference.stats.rays.shadow
    );
}

/// A spot's VPL paths leave into its outer cone only (a point light's, everywhere).
#[test]
fn spot_vpls_leave_into_the_cone() {
    let s = spot_floor(16);
    let tracer = hyrt_tracer::Tracer::build(&s.positions);
    let opts = vpl::VplOptions { paths: 64, bounces: 1, ..Default::default() };
    let (vpls, _) = vpl::generate(&s, &s.lights, &tracer, &opts);
    assert!(!vpls.is_empty());
    let spot = s.lights[0].spot.unwrap();
    for v in &vpls {
        let d = (v.position - s.lights[0].position).normalize();
        assert!(spot.axis.dot(d) >= spot.cos_outer - 1e-4, "a VPL at {} is outside the cone", v.position);
    }
}

#[test]
fn scene_files_give_spot_lights_and_report_bad_ones() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let write = |name: &str, light: &str| {
        let p = dir.path().join(name);
        std::fs::write(
            &p,
            format!(
                "[[mesh]]\npath = \"tri.obj\"\n\n[[light]]\nposition = [0, 0, 5]\nintensity = 2\n{light}"
            ),
        )
        .unwrap();
        p
    };
    let p =
        write("spot.toml", "kind = \"spot\"\ndirection = [0, 0, -1]\ninner_angle = 10\nouter_angle = 20\n");
    let s = scene::file::load(&p).unwrap();
    let spot = s.lights[0].spot.unwrap();
    assert_eq!(spot.axis, Vec3::NEG_Z);
    assert!((spot.cos_outer - 20f32.to_radians().cos()).abs() < 1e-6);
    assert!(scene::file::load(&write("point.toml", "")).unwrap().lights[0].spot.is_none());
    for (name, light, says) in [
        ("no-dir.toml", "kind = \"spot\"\nouter_angle = 20\n", "needs 'direction'"),
        ("wide.toml", "kind = \"spot\"\ndirection = [0, 0, -1]\nouter_angle = 120\n", "<= 90 degrees"),
        (
            "inverted.toml",
            "kind = \"spot\"\ndirection = [0, 0, -1]\ninner_angle = 30\nouter_angle = 20\n",
            "inner_angle <= outer_angle",
        ),
        ("point-dir.toml", "direction = [0, 0, -1]\n", "belong to kind = \"spot\""),
        ("sun.toml", "kind = \"directional\"\n", "needs 'direction' and 'irradiance'"),
        ("irradiant.toml", "irradiance = 2\n", "'irradiance' belongs to kind = \"directional\""),
        ("lamp.toml", "kind = \"lamp\"\n", "unknown light kind 'lamp'"),
    ] {
        let e = format!("{:#}", scene::file::load(&write(name, light)).unwrap_err());
        // Located at the `[[light]]` table (line 4).
        assert!(e.contains(&format!("{name}:4: [[light]]")) && e.contains(says), "{e}");
    }
}

/// A directional light is a point light `SUN_DISTANCE` scene diagonals away: across the scene
/// its rays stay within 1/2000 rad of its direction and its irradiance within 0.1 % of the
/// one given (`scene::Directional`). Seen by both renderers alike.
#[test]
fn directional_lights_are_parallel_within_their_bound() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("floor.obj"), "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 4 3 2\n")
        .unwrap();
    let p = dir.path().join("sun.toml");
    std::fs::write(
        &p,
        "[camera]\neye = [0, 6, 0]\ndirection = [0, -1, 0]\nup = [0, 0, -1]\nfov_y = 40\n\n[settings]\nwidth = 48\nheight = 48\n\n\
         [[mesh]]\npath = \"floor.obj\"\n\n[[light]]\nkind = \"directional\"\ndirection = [1, -1, 0]\nirradiance = 2\n",
    )
    .unwrap();
    let s = scene::file::load(&p).unwrap();
    assert_eq!(s.lights.len(), 1);
    let light = s.lights[0];
    let (lo, hi) = s.bounds().unwrap();
    let d = scene::SUN_DISTANCE * (hi - lo).length();
    let travel = vec3(1.0, -1.0, 0.0).normalize();
    assert!(((light.position - (lo + hi) * 0.5) / d + travel).length() < 1e-5);
    for &q in &[lo, hi, vec3(-2.0, 0.0, 2.0), vec3(2.0, 0.0, -2.0)] {
        let to = (q - light.position).normalize();
        assert!(to.angle_between(travel) <= 0.5 / scene::SUN_DISTANCE, "{q}");
        let e = light.intensity.x / (q - light.position).length_squared();
        assert!((e / 2.0 - 1.0).abs() <= 1.1e-3, "{q}: {e}");
    }
    // On the floor: E cos 45 degrees, radiance E cos / pi for the default grey 0.8.
    let reference = common::render(&s, Options::reference());
    let hybrid = common::render(&s, Options::hybrid());
    assert_eq!(reference.film.pixels, hybrid.film.pixels);
    let c = reference.film.pixels[24 * 48 + 24].x;
    let want = 0.8 * 2.0 * std::f32::consts::FRAC_1_SQRT_2 / std::f32::consts::PI;
    assert!((c / want - 1.0).abs() < 5e-3, "{c} against {want}");
}
