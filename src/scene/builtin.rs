//! Built-in scenes that need no files.
//!
//! `cornell`: the classic Cornell box from the published measurements (Cornell Program of
//! Computer Graphics, "Cornell Box data"; numbers in
//! `shared/scenes/cornell-box-mitsuba/cornell_original_data.txt`), converted from millimetres
//! to metres, with both blocks, the McGuire/Bitterli RGB reflectances, a mirror panel on the
//! green wall, and two point lights under the ceiling lamp. Camera: the published one at
//! (278, 273, -800) mm looking along +Z with a 39.3077 degree field of view on a square film.

use glam::{Vec3, vec3};

use super::{Camera, Material, MeshRange, PointLight, Scene, Settings};

/// Names accepted by [`by_name`].
pub const NAMES: &[&str] = &["cornell"];

/// A built-in scene by name.
pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        "cornell" => Some(cornell()),
        _ => None,
    }
}

/// A point given in the data's millimetres, in metres.
fn mm(x: f32, y: f32, z: f32) -> Vec3 {
    vec3(x, y, z) * 1e-3
}

/// The Cornell box (see the module docs).
pub fn cornell() -> Scene {
    let mut s = Scene::new("cornell");
    let white = s.add_material(Material::matte("white", vec3(0.725, 0.71, 0.68)));
    let red = s.add_material(Material::matte("red", vec3(0.63, 0.065, 0.05)));
    let green = s.add_material(Material::matte("green", vec3(0.14, 0.45, 0.091)));
    let mirror = s.add_material(Material::mirror("mirror", Vec3::ZERO, Vec3::splat(0.95)));

    let group = |s: &mut Scene, name: &str, quads: &[[Vec3; 4]], m: u32| {
        let first = s.triangle_count() as u32;
        for q in quads {
            s.push_quad(*q, m);
        }
        s.meshes.push(MeshRange { name: name.into(), first, count: s.triangle_count() as u32 - first });
    };
    group(
        &mut s,
        "floor",
        &[[mm(552.8, 0.0, 0.0), mm(0.0, 0.0, 0.0), mm(0.0, 0.0, 559.2), mm(549.6, 0.0, 559.2)]],
        white,
    );
    group(
        &mut s,
        "ceiling",
        &[[mm(556.0, 548.8, 0.0), mm(556.0, 548.8, 559.2), mm(0.0, 548.8, 559.2), mm(0.0, 548.8, 0.0)]],
        white,
    );
    group(
        &mut s,
        "back_wall",
        &[[mm(549.6, 0.0, 559.2), mm(0.0, 0.0, 559.2), mm(0.0, 548.8, 559.2), mm(556.0, 548.8, 559.2)]],
        white,
    );
    group(
        &mut s,
        "green_wall",
        &[[mm(0.0, 0.0, 559.2), mm(0.0, 0.0, 0.0), mm(0.0, 548.8, 0.0), mm(0.0, 548.8, 559.2)]],
        green,
    );
    group(
        &mut s,
        "red_wall",
        &[[mm(552.8, 0.0, 0.0), mm(549.6, 0.0, 559.2), mm(556.0, 548.8, 559.2), mm(556.0, 548.8, 0.0)]],
        red,
    );
    group(
        &mut s,
        "short_block",
        &[
            [
                mm(130.0, 165.0, 65.0),
                mm(82.0, 165.0, 225.0),
                mm(240.0, 165.0, 272.0),
                mm(290.0, 165.0, 114.0),
            ],
            [mm(290.0, 0.0, 114.0), mm(290.0, 165.0, 114.0), mm(240.0, 165.0, 272.0), mm(240.0, 0.0, 272.0)],
            [mm(130.0, 0.0, 65.0), mm(130.0, 165.0, 65.0), mm(290.0, 165.0, 114.0), mm(290.0, 0.0, 114.0)],
            [mm(82.0, 0.0, 225.0), mm(82.0, 165.0, 225.0), mm(130.0, 165.0, 65.0), mm(130.0, 0.0, 65.0)],
            [mm(240.0, 0.0, 272.0), mm(240.0, 165.0, 272.0), mm(82.0, 165.0, 225.0), mm(82.0, 0.0, 225.0)],
        ],
        white,
    );
    group(
        &mut s,
        "tall_block",
        &[
            [
                mm(423.0, 330.0, 247.0),
                mm(265.0, 330.0, 296.0),
                mm(314.0, 330.0, 456.0),
                mm(472.0, 330.0, 406.0),
            ],
            [mm(423.0, 0.0, 247.0), mm(423.0, 330.0, 247.0), mm(472.0, 330.0, 406.0), mm(472.0, 0.0, 406.0)],
            [mm(472.0, 0.0, 406.0), mm(472.0, 330.0, 406.0), mm(314.0, 330.0, 456.0), mm(314.0, 0.0, 456.0)],
            [mm(314.0, 0.0, 456.0), mm(314.0, 330.0, 456.0), mm(265.0, 330.0, 296.0), mm(265.0, 0.0, 296.0)],
            [mm(265.0, 0.0, 296.0), mm(265.0, 330.0, 296.0), mm(423.0, 330.0, 247.0), mm(423.0, 0.0, 247.0)],
        ],
        white,
    );
    // A mirror panel 2 mm in front of the green wall, facing into the box.
    group(
        &mut s,
        "mirror",
        &[[mm(2.0, 90.0, 130.0), mm(2.0, 90.0, 470.0), mm(2.0, 420.0, 470.0), mm(2.0, 420.0, 130.0)]],
        mirror,
    );
    // Two lights 9 cm under the ceiling lamp (130 x 105 mm, centred at x 278, z 279.5), as
    // far below the ceiling, relative to the box, as the thesis scene's lights.
    for (x, z) in [(245.0, 255.0), (311.0, 304.0)] {
        s.lights.push(PointLight { position: mm(x, 458.0, z), intensity: Vec3::splat(0.25), spot: None });
    }
    s.camera = Some(Camera::look_at(mm(278.0, 273.0, -800.0), mm(278.0, 273.0, 0.0), Vec3::Y, 39.3077));
    s.settings = Settings { width: 512, height: 512, ..Settings::default() };
    s
}
