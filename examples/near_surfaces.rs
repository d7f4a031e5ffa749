//! Near-coincident surfaces (issue "the nearer one is shaded"): which surface the camera sees
//! where two parallel quads lie a small distance apart, by rays (the reference) and by the
//! z-buffer (the hybrid), for separations of 1e-7 to 1e-3 of the scene's size, head-on and at
//! a grazing angle, with the nearer quad's ids below or above the farther one's.
//!
//! `cargo run --release --example near_surfaces` prints one line per case: the share of the
//! pixels where both quads overlap in view that show the *farther* quad (0 is right), for rays
//! and for the z-buffer.

use glam::{Vec3, vec3};
use hyrt::{
    render::{Options, Renderer},
    scene::{Camera, Material, PointLight, Scene, Settings},
};

/// A unit quad (half-size 0.5) in the plane z = `z`, facing +z, as two triangles.
fn quad(s: &mut Scene, z: f32, m: u32) {
    let h = 0.5;
    s.push_quad([vec3(-h, -h, z), vec3(h, -h, z), vec3(h, h, z), vec3(-h, h, z)], m);
}

/// The two quads `sep` apart (the nearer at z = `sep`, the farther at 0), the nearer one drawn
/// first (lower ids) or second, seen from distance 2 along a direction `angle` degrees off the
/// normal.
fn scene(sep: f32, nearer_first: bool, angle: f32) -> Scene {
    let mut s = Scene::new("near");
    let (near, far) =
        (s.add_material(Material::matte("near", Vec3::X)), s.add_material(Material::matte("far", Vec3::Y)));
    if nearer_first {
        quad(&mut s, sep, near);
        quad(&mut s, 0.0, far);
    } else {
        quad(&mut s, 0.0, far);
        quad(&mut s, sep, near);
    }
    let a = angle.to_radians();
    let eye = vec3(a.sin(), 0.0, a.cos()) * 2.0;
    s.camera = Some(Camera::look_at(eye, Vec3::ZERO, Vec3::Y, 20.0));
    s.lights = vec![PointLight { position: eye, intensity: Vec3::splat(4.0), spot: None }];
    s.settings = Settings { width: 96, height: 96, max_depth: 0, exposure: 1.0 };
    s.validate().expect("valid");
    s
}

fn main() {
    println!("separation  view     nearer ids  far shown: rays  raster  (of pixels on both)");
    for sep in [1e-7f32, 1e-6, 1e-5, 3e-5, 1e-4, 1e-3] {
        for (view, angle) in [("head-on", 0.0), ("grazing", 80.0)] {
            for nearer_first in [true, false] {
                let s = scene(sep, nearer_first, angle);
                let shown = |o: Options| {
                    let mut o = o;
                    o.keep_buffers = true;
                    let f = Renderer::new(&s, o).render(&|| {});
                    let g = f.gbuffer.expect("kept");
                    let hits: Vec<u32> = g.iter().flatten().map(|h| s.material[h.tri as usize]).collect();
                    let far = hits.iter().filter(|&&m| m == 1).count();
                    (far, hits.len())
                };
                let ((fr, nr), (fz, nz)) = (shown(Options::reference()), shown(Options::hybrid()));
                println!(
                    "{sep:>9.0e}  {view:<8} {:<10}  {:>10.4}  {:>6.4}  ({nr} / {nz})",
                    if nearer_first { "lower" } else { "higher" },
                    fr as f64 / nr.max(1) as f64,
                    fz as f64 / nz.max(1) as f64,
                );
            }
        }
    }
}
