//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use glam::{Vec3, vec3};
use hyrt::{
    render::{Frame, Options, Renderer},
    scene::{Camera, Material, PointLight, Scene, Settings},
};

/// The project root (the workspace's, where `Cargo.lock` is), also from the tests of a
/// member package that include this module.
pub fn root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.ancestors().find(|d| d.join("Cargo.lock").exists()).unwrap_or(here).to_path_buf()
}

/// A path under `../shared/scenes`.
pub fn shared_scene(rel: &str) -> PathBuf {
    root().join("../shared/scenes").join(rel)
}

/// A fresh directory under `target/test-output/<name>` for files a test writes.
pub fn out_dir(name: &str) -> PathBuf {
    let d = root().join("target/test-output").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create test output dir");
    d
}

/// Renders a scene with the given options, no progress.
pub fn render(scene: &Scene, options: Options) -> Frame {
    Renderer::new(scene, options).render(&|| {})
}

/// A square of half-size `half` in the plane y = 0 centred at the origin, diffuse `kd`,
/// seen by a camera straight above at height `cam_h`, with the given lights.
pub fn floor_scene(
    half: f32,
    kd: Vec3,
    cam_h: f32,
    fov: f32,
    lights: Vec<PointLight>,
    w: u32,
    h: u32,
) -> Scene {
    let mut s = Scene::new("floor");
    let m = s.add_material(Material::matte("floor", kd));
    s.push_quad(
        [vec3(-half, 0.0, -half), vec3(-half, 0.0, half), vec3(half, 0.0, half), vec3(half, 0.0, -half)],
        m,
    );
    s.lights = lights;
    s.camera = Some(Camera {
        eye: vec3(0.0, cam_h, 0.0),
        forward: -Vec3::Y,
        up: -Vec3::Z,
        fov_y_deg: fov,
        fov_x_deg: None,
    });
    s.settings = Settings { width: w, height: h, max_depth: 5, exposure: 1.0 };
    s.validate().expect("valid test scene");
    s
}

/// An axis-aligned closed box (12 triangles, outward faces).
pub fn push_box(s: &mut Scene, lo: Vec3, hi: Vec3, m: u32) {
    let c = |i: u32| {
        vec3(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    for q in [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]] {
        s.push_quad(q.map(c), m);
    }
}
