//! The Whitted reference: analytic radiance, ray counts, plan, determinism.

mod common;

use std::f64::consts::PI;

use common::*;
use glam::{DVec3, Vec3, vec3};
use hyrt::{
    camera::CameraRays,
    render::Options,
    scene::{Material, PointLight},
};

/// A single square lit by one point light: the radiance at chosen pixels equals
/// `Kd / pi * I * cos / r^2` computed independently in f64, within 1e-5 relative.
#[test]
fn single_square_radiance_matches_the_formula() {
    let kd = vec3(0.8, 0.5, 0.25);
    let light = PointLight { position: vec3(0.3, 1.5, -0.2), intensity: vec3(2.0, 1.0, 0.5), spot: None };
    let (w, h) = (64u32, 48u32);
    let scene = floor_scene(1.0, kd, 3.0, 40.0, vec![light], w, h);
    let frame = render(&scene, Options::default());
    let cam = CameraRays::new(&scene.camera.unwrap(), w, h);
    let mut checked = 0;
    for (x, y) in (0..w).step_by(5).flat_map(|x| (0..h).step_by(5).map(move |y| (x, y))) {
        // Independent f64 computation of the pixel-centre ray hitting y = 0.
        let sx = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * cam.tan_x as f64;
        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * cam.tan_y as f64;
        let d = cam.forward.as_dvec3() + cam.right.as_dvec3() * sx + cam.up.as_dvec3() * sy;
        let eye = cam.eye.as_dvec3();
        let t = -eye.y / d.y;
        let p = eye + d * t;
        if p.x.abs() > 1.0 || p.z.abs() > 1.0 {
            assert_eq!(frame.film.get(x, y), Vec3::ZERO, "pixel ({x},{y}) misses the square");
            continue;
        }
        let l = light.position.as_dvec3() - p;
        let r2 = l.length_squared();
        let cos = l.normalize().y;
        let expected: DVec3 = kd.as_dvec3() / PI * light.intensity.as_dvec3() * cos / r2;
        let got = frame.film.get(x, y).as_dvec3();
        let rel = ((got - expected).abs() / expected).max_element();
        assert!(rel <= 1e-5, "pixel ({x},{y}): got {got}, expected {expected}, relative error {rel:e}");
        checked += 1;
    }
    assert!(checked >= 60, "too few pixels on the square: {checked}");
}

/// The highlight: a glossy square, a point light and a camera on opposite sides, placed so
/// that the mirror direction of the light at the square's centre goes to the camera. Every
/// pixel's radiance equals `I cos / r^2 * (Kd / pi + Ks (n + 8) / (8 pi) (n . h)^n)` computed
/// independently in f64; the centre pixel, where `n . h = 1`, is its closed form
/// `I / (2 sqrt 2) * (Kd / pi + Ks (n + 8) / (8 pi))`. Reference and hybrid alike.
#[test]
fn highlight_radiance_matches_the_formula() {
    let (kd, ks, ns) = (vec3(0.5, 0.4, 0.3), vec3(0.3, 0.2, 0.1), 50.0f32);
    let light = PointLight { position: vec3(1.0, 1.0, 0.0), intensity: vec3(2.0, 1.0, 0.5), spot: None };
    // Odd size: the centre pixel's ray goes through the target.
    let (w, h) = (33u32, 33u32);
    let mut scene = floor_scene(1.0, kd, 3.0, 40.0, vec![light], w, h);
    scene.materials[0] = Material::glossy("gloss", kd, ks, ns);
    scene.camera = Some(hyrt::scene::Camera::look_at(vec3(-1.0, 1.0, 0.0), Vec3::ZERO, Vec3::Y, 30.0));
    scene.validate().unwrap();
    let cam = CameraRays::new(&scene.camera.unwrap(), w, h);
    let brdf = |n_h: f64, cos: f64| {
        let n = f64::from(ns);
        (kd.as_dvec3() / PI + ks.as_dvec3() * (n + 8.0) / (8.0 * PI) * n_h.max(0.0).powf(n)) * cos
    };
    for opts in [Options::reference(), Options::hybrid()] {
        let frame = render(&scene, opts);
        let centre = frame.film.get(w / 2, h / 2).as_dvec3();
        let closed = light.intensity.as_dvec3() / (2.0 * 2f64.sqrt())
            * (kd.as_dvec3() / PI + ks.as_dvec3() * (f64::from(ns) + 8.0) / (8.0 * PI));
        let rel = ((centre - closed).abs() / closed).max_element();
        assert!(rel <= 1e-4, "{opts:?}: centre {centre}, closed form {closed}, relative error {rel:e}");
        let mut checked = 0;
        for y in 0..h {
            for x in 0..w {
                let sx = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * cam.tan_x as f64;
                let sy = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * cam.tan_y as f64;
                let d = cam.forward.as_dvec3() + cam.right.as_dvec3() * sx + cam.up.as_dvec3() * sy;
                let eye = cam.eye.as_dvec3();
                let p = eye + d * (-eye.y / d.y);
                if d.y >= 0.0 || p.x.abs() > 0.99 || p.z.abs() > 0.99 {
                    continue;
                }
                let l = light.position.as_dvec3() - p;
                let (wi, wo) = (l.normalize(), (eye - p).normalize());
                let n_h = (wi + wo).normalize().y;
                let expected = light.intensity.as_dvec3() / l.length_squared() * brdf(n_h, wi.y);
                let got = frame.film.get(x, y).as_dvec3();
                let rel = ((got - expected).abs() / expected).max_element();
                assert!(
                    rel <= 1e-4,
                    "{opts:?} pixel ({x},{y}): got {got}, expected {expected}, error {rel:e}"
                );
                checked += 1;
            }
        }
        assert!(checked >= 500, "too few pixels on the square: {checked}");
        // Not a vanishing term: at the centre the highlight is over 4x the diffuse light.
        let diffuse_only = f64::from(light.intensity.x) / (2.0 * 2f64.sqrt()) * f64::from(kd.x) / PI;
        assert!(centre.x > 5.0 * diffuse_only, "{centre} against diffuse {diffuse_only}");
    }
}

/// Primary rays = width x height; shadow rays = (hits facing the lights) x lights, where the
/// hits are counted by hand: the pixel centres whose rays fall inside the square.
#[test]
fn ray_counts_match_a_hand_count() {
    let lights = vec![
        PointLight { position: vec3(0.0, 2.0, 0.0), intensity: Vec3::ONE, spot: None },
        PointLight { position: vec3(0.5, 1.0, 0.5), intensity: Vec3::ONE, spot: None },
        PointLight { position: vec3(-3.0, 0.5, 0.2), intensity: Vec3::ONE, spot: None },
    ];
    let (w, h) = (40u32, 30u32);
    // A square of half-size 0.61 seen from height 2 with a 60 degree fov: partly covered.
    let scene = floor_scene(0.61, Vec3::splat(0.5), 2.0, 60.0, lights, w, h);
    let frame = render(&scene, Options::default());
    let cam = CameraRays::new(&scene.camera.unwrap(), w, h);
    let mut hits = 0u64;
    for y in 0..h {
        for x in 0..w {
            let d = cam.direction(x, y).as_dvec3();
            let p = cam.eye.as_dvec3() + d * (-(cam.eye.y as f64) / d.y);
            if p.x.abs() < 0.61 && p.z.abs() < 0.61 {
                hits += 1;
            }
        }
    }
    assert!(hits > 100 && hits < u64::from(w * h), "the square should cover part of the image: {hits}");
    let r = frame.stats.rays;
    assert_eq!(r.primary, u64::from(w * h));
    // Every hit sees every light from the front (all lights are above the floor).
    assert_eq!(r.shadow, hits * 3);
    assert_eq!(r.specular, 0);
}

/// Mirror rays: a camera looking at a mirror floor with a diffuse wall behind the camera.
#[test]
fn specular_rays_are_cast_only_when_a_mirror_is_seen() {
    let lights = vec![PointLight { position: vec3(0.0, 2.0, 0.0), intensity: Vec3::ONE, spot: None }];
    let mut scene = floor_scene(1.0, Vec3::splat(0.5), 2.0, 30.0, lights, 16, 16);
    let r = render(&scene, Options::default());
    assert_eq!(r.stats.rays.specular, 0);
    assert!(!r.stats.pass_ms.contains_key(&hyrt::render::Pass::Specular), "no mirror: no specular pass");

    scene.materials[0] = Material::mirror("mirror", Vec3::ZERO, Vec3::ONE);
    let r = render(&scene, Options::default());
    // Every pixel sees the mirror; each reflection goes up and escapes: one ray per pixel.
    assert_eq!(r.stats.rays.specular, 16 * 16);
    // A perfect mirror has no diffuse term: no shadow rays from it.
    assert_eq!(r.stats.rays.shadow, 0);
}

#[test]
fn same_image_for_one_and_two_threads() {
    let scene = hyrt::scene::load("cornell").unwrap();
    let mut s = scene.clone();
    s.settings.width = 96;
    s.settings.height = 96;
    let run = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| render(&s, Options::default()))
    };
    let (a, b) = (run(1), run(2));
    assert!(a.film.pixels == b.film.pixels, "pixels differ between 1 and 2 threads");
    assert_eq!(a.stats.rays, b.stats.rays);
}
