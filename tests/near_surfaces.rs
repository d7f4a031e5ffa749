//! Near-coincident surfaces: the nearer one is shaded, by rays and by the z-buffer alike,
//! wherever rounding can order the two at all; surfaces that it cannot (coplanar ones) go to
//! the tie rule (a face the ray enters, then the smaller id), the same in both renderers and
//! for any thread count.

mod common;

use glam::{Vec3, vec3};
use hyrt::{
    render::{Options, Renderer},
    scene::{Camera, Material, PointLight, Scene, Settings},
};

/// A square of half-size `h` in the plane z = `z`, facing +z, as two triangles.
fn square(s: &mut Scene, z: f32, h: f32, m: u32) {
    s.push_quad([vec3(-h, -h, z), vec3(h, -h, z), vec3(h, h, z), vec3(-h, h, z)], m);
}

/// Squares at z = `za` (half-size `ha`, material 0) and z = `zb` (half-size `hb`, material 1), in
/// that order (the first has the lower ids), seen from distance 2 along a direction `angle`
/// degrees off their normal.
fn scene(a: (f32, f32), b: (f32, f32), angle: f32) -> Scene {
    let mut s = Scene::new("near");
    let ma = s.add_material(Material::matte("a", Vec3::X));
    let mb = s.add_material(Material::matte("b", Vec3::Y));
    square(&mut s, a.0, a.1, ma);
    square(&mut s, b.0, b.1, mb);
    let t = angle.to_radians();
    // Slightly off the axes, so that no edge falls on a column of pixel centres.
    let eye = vec3(t.sin(), 0.013, t.cos()) * 2.0;
    s.camera = Some(Camera::look_at(eye, vec3(0.003, 0.002, 0.0), Vec3::Y, 20.0));
    s.lights = vec![PointLight { position: eye, intensity: Vec3::splat(4.0), spot: None }];
    s.settings = Settings { width: 96, height: 96, max_depth: 0, exposure: 1.0 };
    s.validate().expect("valid");
    s
}

/// The material each pixel sees (`None`: nothing), by `options`.
fn seen(s: &Scene, mut options: Options) -> Vec<Option<u32>> {
    options.keep_buffers = true;
    let f = Renderer::new(s, options).render(&|| {});
    f.gbuffer.expect("kept").iter().map(|h| h.map(|h| s.material[h.tri as usize])).collect()
}

/// Two parallel squares 1e-7 to 1e-3 of their size apart, the nearer one larger (so that the
/// farther never shows past it), head-on and at 80 degrees, the nearer one's ids below or
/// above the farther's: no pixel shows the farther one, with rays or with the z-buffer. (With a
/// fixed relative tie window of `2^-16`, every pixel did up to 1e-5 wherever it had the lower
/// ids.)
#[test]
fn the_nearer_of_two_parallel_squares_is_shaded() {
    for sep in [1e-7f32, 1e-6, 1e-5, 1e-4, 1e-3] {
        for angle in [0.0, 80.0] {
            for nearer_first in [true, false] {
                let (near, far) = ((sep, 0.6), (0.0, 0.5));
                let s = if nearer_first { scene(near, far, angle) } else { scene(far, near, angle) };
                let far_material = u32::from(nearer_first);
                for (name, o) in [("rays", Options::reference()), ("raster", Options::hybrid())] {
                    let px = seen(&s, o);
                    let shown = px.iter().filter(|m| **m == Some(far_material)).count();
                    let on = px.iter().filter(|m| m.is_some()).count();
                    assert!(on > 1000, "{sep} {angle} {nearer_first} {name}: {on} pixels on the squares");
                    assert_eq!(
                        shown, 0,
                        "{name}: separation {sep}, {angle} degrees, nearer first {nearer_first}"
                    );
                }
            }
        }
    }
}

/// A panel 1e-5 of the wall's size behind it (inset into it), with the lower ids: the wall is
/// shaded everywhere, by rays and by the z-buffer.
#[test]
fn a_panel_inset_into_a_wall_stays_hidden() {
    let s = scene((-1e-5, 0.2), (0.0, 0.5), 30.0);
    for o in [Options::reference(), Options::hybrid()] {
        let px = seen(&s, o);
        assert!(px.iter().all(|m| *m != Some(0)));
        assert!(px.iter().filter(|m| **m == Some(1)).count() > 1000);
    }
}

/// Coplanar overlapping squares (one plane, no order to find): the tie rule, the smaller ids,
/// the same in both renderers, head-on and grazing, and the same bytes on 1 and 2 threads.
#[test]
fn coplanar_squares_go_to_the_tie_rule_alike_on_any_thread_count() {
    for angle in [0.0, 80.0] {
        let s = scene((0.0, 0.5), (0.0, 0.4), angle);
        let rays = seen(&s, Options::reference());
        let raster = seen(&s, Options::hybrid());
        assert!(rays.iter().filter(|m| m.is_some()).all(|m| *m == Some(0)), "{angle}");
        assert_eq!(rays, raster, "{angle}");
        let film = |threads: usize, o: Options| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| common::render(&s, o)).film.pixels
        };
        for o in [Options::reference(), Options::hybrid()] {
            assert_eq!(film(1, o), film(2, o), "{angle}");
        }
    }
}
