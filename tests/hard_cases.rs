//! Hard cases found from outside (issue 17): a light in a surface's plane, faces meeting at a
//! grazing edge, and outputs kept safe when a run fails. Each test states its bound.

mod common;

use common::*;
use glam::{Vec3, vec3};
use hyrt::{
    render::{Options, Renderer, Visibility},
    scene::{Camera, Material, PointLight, Scene, Settings},
};
use hyrt_shadowmap::MapKind;
use hyrt_tracer::{PlaneSide, RayCounts, RayKind, Tracer, plane_side};

fn settings(w: u32, h: u32) -> Settings {
    Settings { width: w, height: h, max_depth: 5, exposure: 1.0 }
}

/// A wall through `corners` (counter-clockwise seen from the camera), lit only by a light
/// lying exactly in its plane, near its middle.
fn wall_with_light_in_plane(corners: [Vec3; 4], light: Vec3, eye: Vec3) -> Scene {
    let mut s = Scene::new("wall");
    let m = s.add_material(Material::matte("wall", Vec3::splat(0.8)));
    s.push_quad(corners, m);
    let centre = corners.iter().copied().sum::<Vec3>() / 4.0;
    s.lights = vec![PointLight { position: light, intensity: Vec3::splat(50.0), spot: None }];
    s.camera = Some(Camera::look_at(eye, centre, Vec3::Y, 50.0));
    s.settings = settings(96, 96);
    s.validate().unwrap();
    s
}

/// Bound: exactly 0 radiance on every pixel, in the reference and the hybrid, for an
/// axis-aligned wall and a tilted one, each with the light exactly in its plane (the exact
/// cosine is 0 at every point of the plane).
#[test]
fn a_light_in_a_walls_plane_lights_none_of_it() {
    let cases = [
        // The plane z = 0.37, seen from +z.
        (
            [vec3(-1.0, -1.0, 0.37), vec3(1.0, -1.0, 0.37), vec3(1.0, 1.0, 0.37), vec3(-1.0, 1.0, 0.37)],
            vec3(0.1, 0.3, 0.37),
            vec3(0.2, 0.1, 3.0),
        ),
        // The plane x + y = 1, seen from the side where x + y > 1.
        (
            [vec3(1.0, 0.0, 2.0), vec3(1.0, 0.0, -2.0), vec3(0.0, 1.0, -2.0), vec3(0.0, 1.0, 2.0)],
            vec3(0.25, 0.75, 0.125),
            vec3(2.5, 2.0, 0.3),
        ),
    ];
    for (corners, light, eye) in cases {
        let scene = wall_with_light_in_plane(corners, light, eye);
        assert_eq!(plane_side(&[corners[0], corners[1], corners[2]], light), PlaneSide::In);
        for options in [Options::reference(), Options::hybrid()] {
            let frame = render(&scene, options);
            let lit: Vec<_> =
                frame.film.pixels.iter().enumerate().filter(|(_, p)| **p != Vec3::ZERO).collect();
            assert!(
                lit.is_empty(),
                "{:?}: {} pixels lit by a light in the wall's plane, e.g. {:?}",
                options.visibility,
                lit.len(),
                &lit[..lit.len().min(3)]
            );
        }
        // The same light moved off the plane, to the camera's side, lights the wall: the test
        // would see light if there were any.
        let mut off = scene.clone();
        off.lights[0].position += (eye - light).normalize() * 0.05;
        let frame = render(&off, Options::reference());
        assert!(frame.film.pixels.iter().filter(|p| p.max_element() > 0.0).count() > 100);
    }
}

/// Triangles of a box `lo..hi`, outward-facing, with the bottom face (`y = lo.y`) first, so
/// that its ids are smaller than the sides': the old tie rule (smaller id) picked it.
fn bar(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let c = |i: u32| {
        vec3(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let mut out = Vec::new();
    for q in [[0, 1, 5, 4], [0, 4, 6, 2], [1, 3, 7, 5], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]] {
        let q = q.map(c);
        out.push([q[0], q[1], q[2]]);
        out.push([q[0], q[2], q[3]]);
    }
    out
}

/// Bound: a ray through a bar's bottom edge, which enters the side face and leaves through
/// the bottom face at the same distance, gets the side face (the one it enters), although the
/// bottom face has the smaller ids; and each of the two faces alone is hit at that distance.
#[test]
fn an_exact_tie_goes_to_the_face_the_ray_enters() {
    let tris = bar(vec3(0.0, 0.0, -1.0), vec3(0.02, 0.3, 1.0));
    let tracer = Tracer::build(&tris);
    let mut c = RayCounts::default();
    // From the -x side, above the bottom plane, aimed at the edge x = 0, y = 0.
    for z in [-0.7f32, -0.25, 0.0, 0.3, 0.55] {
        let origin = vec3(-1.0, 0.5, z * 0.9);
        let target = vec3(0.0, 0.0, z);
        let ray = hyrt_tracer::Ray::new(origin, (target - origin).normalize(), f32::INFINITY);
        let hit = tracer.closest_hit(&ray, RayKind::Primary, &mut c).expect("the bar is hit");
        let tri = tris[hit.tri as usize];
        assert_eq!(plane_side(&tri, origin), PlaneSide::Front, "z = {z}: got face {} ({tri:?})", hit.tri);
        assert!(hit.tri >= 2, "z = {z}: the bottom face (ids 0, 1) was chosen");
        // The bottom face is hit there too (the tie is real).
        let bottom = (0..2).filter_map(|i| tracer.hits_triangle(i, &ray)).next();
        if let Some(b) = bottom {
            assert!(hyrt_tracer::depth_tie(b.t, hit.t), "z = {z}: {} vs {}", b.t, hit.t);
        }
    }
}

/// A grille of thin bars seen from above: each bar's bottom edge crosses some pixel rays
/// within the tie window of the face they enter (the side) and the one they leave (the bottom).
fn grille() -> Scene {
    let mut s = Scene::new("grille");
    let m = s.add_material(Material::matte("bar", Vec3::splat(0.7)));
    let floor = s.add_material(Material::matte("floor", Vec3::splat(0.5)));
    for k in 0..24 {
        let x = -1.2 + k as f32 * 0.1;
        for t in bar(vec3(x, 0.2, -1.5), vec3(x + 0.013, 0.24, 1.5)) {
            s.push_triangle(t, None, m);
        }
    }
    s.push_quad(
        [vec3(-3.0, 0.0, -3.0), vec3(-3.0, 0.0, 3.0), vec3(3.0, 0.0, 3.0), vec3(3.0, 0.0, -3.0)],
        floor,
    );
    s.lights = vec![PointLight { position: vec3(-2.0, 2.0, 1.0), intensity: Vec3::splat(20.0), spot: None }];
    s.camera = Some(Camera::look_at(vec3(-3.1, 1.2, 0.4), vec3(0.0, 0.2, 0.0), Vec3::Y, 30.0));
    s.settings = settings(160, 120);
    s.validate().unwrap();
    s
}

/// Bound: no pixel of the reference or of the rasterized G-buffer shows a face from behind
/// (every visible triangle has the camera on its front side, by the exact predicate), on a
/// scene where some pixels' rays do tie a side face with a bottom face.
#[test]
fn thin_bars_show_the_faces_seen_from_outside() {
    let scene = grille();
    let rays = Renderer::new(&scene, Options { visibility: Visibility::Rays, ..Options::default() });
    let raster = Renderer::new(&scene, Options { visibility: Visibility::Raster, ..Options::default() });
    let eye = rays.camera.eye;
    // The case arises: pixels whose ray meets a face it leaves within the tie window of its hit.
    let tracer = Tracer::build(&scene.positions);
    let (g, _) = rays.visibility();
    let (w, h) = (scene.settings.width, scene.settings.height);
    let mut ties = 0;
    for y in 0..h {
        for x in 0..w {
            let Some(hit) = g[(y * w + x) as usize] else { continue };
            let ray = rays.camera_ray(x, y);
            let leaves = (0..scene.positions.len() as u32).any(|t| {
                plane_side(&scene.positions[t as usize], eye) == PlaneSide::Back
                    && tracer.hits_triangle(t, &ray).is_some_and(|o| hyrt_tracer::depth_tie(o.t, hit.t))
            });
            ties += usize::from(leaves);
        }
    }
    assert!(ties >= 3, "only {ties} pixels with a tie between a face entered and one left");
    for (name, r) in [("rays", &rays), ("raster", &raster)] {
        let (g, _) = r.visibility();
        let from_behind = g
            .iter()
            .flatten()
            .filter(|h| plane_side(&scene.positions[h.tri as usize], eye) == PlaneSide::Back)
            .count();
        assert_eq!(from_behind, 0, "{name}: {from_behind} pixels show a face from behind");
    }
}

/// A small furnished room (about 5 units across): a floor and walls, a table (a thin top on
/// four legs) and boxes resting on the floor, lit by two lights; everything moved by `offset`.
fn room(offset: Vec3) -> Scene {
    scaled_room(offset, 1.0)
}

/// [`room`] scaled by `k` about its own origin, then moved by `offset`.
fn scaled_room(offset: Vec3, k: f32) -> Scene {
    let mut s = Scene::new("room");
    let grey = s.add_material(Material::matte("grey", Vec3::splat(0.7)));
    let wood = s.add_material(Material::glossy("wood", vec3(0.6, 0.4, 0.25), Vec3::splat(0.1), 40.0));
    let o = offset;
    let quad = |s: &mut Scene, q: [Vec3; 4], m| s.push_quad(q.map(|p| p * k + o), m);
    quad(
        &mut s,
        [vec3(-2.5, 0.0, -2.5), vec3(-2.5, 0.0, 2.5), vec3(2.5, 0.0, 2.5), vec3(2.5, 0.0, -2.5)],
        grey,
    );
    quad(
        &mut s,
        [vec3(-2.5, 0.0, -2.5), vec3(2.5, 0.0, -2.5), vec3(2.5, 2.5, -2.5), vec3(-2.5, 2.5, -2.5)],
        grey,
    );
    quad(
        &mut s,
        [vec3(-2.5, 0.0, -2.5), vec3(-2.5, 2.5, -2.5), vec3(-2.5, 2.5, 2.5), vec3(-2.5, 0.0, 2.5)],
        grey,
    );
    let mut boxed = |lo: Vec3, hi: Vec3, m| push_box(&mut s, lo * k + o, hi * k + o, m);
    boxed(vec3(-0.8, 0.72, -0.6), vec3(0.9, 0.76, 0.5), wood);
    for (x, z) in [(-0.75, -0.55), (0.8, -0.55), (-0.75, 0.4), (0.8, 0.4)] {
        boxed(vec3(x, 0.0, z), vec3(x + 0.06, 0.72, z + 0.06), wood);
    }
    boxed(vec3(1.2, 0.0, 1.0), vec3(1.7, 0.5, 1.6), grey);
    boxed(vec3(-1.9, 0.0, 0.8), vec3(-1.5, 0.9, 1.1), grey);
    boxed(vec3(-0.3, 0.76, -0.2), vec3(-0.1, 0.86, 0.0), grey);
    s.lights = vec![
        PointLight { position: o + vec3(0.4, 2.2, 0.9) * k, intensity: Vec3::splat(3.0 * k * k), spot: None },
        PointLight {
            position: o + vec3(-1.2, 1.8, -0.7) * k,
            intensity: Vec3::splat(2.0 * k * k),
            spot: None,
        },
    ];
    s.camera =
        Some(Camera::look_at(o + vec3(2.2, 2.0, 3.4) * k, o + vec3(-0.2, 0.4, -0.2) * k, Vec3::Y, 50.0));
    s.settings = settings(320, 240);
    s.validate().unwrap();
    s
}

/// Pixels whose display luminance differs by more than 0.02 between two images.
fn differing(a: &hyrt::metrics::DisplayImage, b: &hyrt::metrics::DisplayImage) -> usize {
    use hyrt::metrics::luminance;
    a.pixels.iter().zip(&b.pixels).filter(|(p, q)| (luminance(**p) - luminance(**q)).abs() > 0.02).count()
}

/// Bounds, for the room moved far from the origin (320 x 240, two lights):
/// - the reference resolves it (at most 0.05 % of the pixels differ from the room at the
///   origin) up to an offset of 1e4, 2,000 times the room's size;
/// - the hybrid agrees with its own reference (at most 0.05 % of the pixels with a wrong
///   decision, every decision checked by a plain shadow ray) up to 3e4, beyond that;
/// - at every offset, up to 1e6, no border ray answered by its occluder hint or by a traversal
///   disagrees with the plain shadow ray.
#[test]
fn far_from_the_origin_the_hybrid_agrees_with_its_reference() {
    use hyrt::metrics::DisplayImage;
    let at_origin = DisplayImage::from_film(&render(&room(Vec3::ZERO), Options::reference()).film, 1.0);
    let bound = at_origin.pixels.len() / 2000;
    for off in [0.0f32, 1e3, 1e4, 3e4, 1e5, 1e6] {
        let scene = room(vec3(1.0, 0.37, -0.61) * off);
        let reference = DisplayImage::from_film(&render(&scene, Options::reference()).film, 1.0);
        let moved = differing(&at_origin, &reference);
        if off <= 1e4 {
            assert!(moved <= bound, "offset {off}: the reference differs from the origin's on {moved} px");
        }
        for kind in [MapKind::Cube, MapKind::Paraboloid] {
            let mut o = Options::hybrid();
            o.shadow.map.kind = kind;
            o.check_visibility = true;
            o.keep_buffers = true;
            let hybrid = render(&scene, o);
            let wrong_px = hybrid
                .shadows
                .as_ref()
                .map_or(0, |b| (0..reference.pixels.len()).filter(|&i| b.wrong.iter().any(|w| w[i])).count());
            let by_rays: u64 =
                hybrid.stats.lights.iter().map(|l| l.wrong_hint.unwrap() + l.wrong_traversal.unwrap()).sum();
            if off <= 3e4 {
                assert!(wrong_px <= bound, "offset {off}, {kind:?}: {wrong_px} wrong pixels (bound {bound})");
            }
            assert_eq!(by_rays, 0, "offset {off}, {kind:?}: border rays disagree with plain shadow rays");
        }
    }
}

/// Bound: the room scaled by 1e-6, 1e-4, 1e4 and 1e6 (intensities by the square, so the image is the
/// same) renders within 0.05 % of the pixels of the unscaled room, in the reference and the
/// hybrid, and the hybrid's decisions agree with plain shadow rays on all but 0.05 %.
#[test]
fn tiny_and_huge_scales_give_the_same_image() {
    use hyrt::metrics::DisplayImage;
    let shot = |s: &Scene, o: Options| DisplayImage::from_film(&render(s, o).film, 1.0);
    let unit = room(Vec3::ZERO);
    let (ref1, hyb1) = (shot(&unit, Options::reference()), shot(&unit, Options::hybrid()));
    let bound = ref1.pixels.len() / 2000;
    for k in [1e-6f32, 1e-4, 1e4, 1e6] {
        let scene = scaled_room(Vec3::ZERO, k);
        let moved = differing(&ref1, &shot(&scene, Options::reference()));
        assert!(moved <= bound, "scale {k}: the reference differs on {moved} px");
        let moved = differing(&hyb1, &shot(&scene, Options::hybrid()));
        assert!(moved <= bound, "scale {k}: the hybrid differs on {moved} px");
        let (_, wrong_px) = hyrt::metrics::wrong_visibility(&scene, Options::hybrid());
        assert!(wrong_px as usize <= bound, "scale {k}: {wrong_px} wrong pixels");
    }
}

/// A camera 1 to 1e5 times the scene's size away from a grid of 512 triangles (the view
/// narrowed to keep the grid in frame): no pixel inside the grid's image misses it, with rays
/// or the z-buffer, and both see the same hit on every pixel, bit for bit. (Before the shear's
/// error bound followed the shear, `|sx z|` rather than `|z|`, every ray from 3e4 sizes away
/// was rejected as possibly behind its origin.) From 1e6 sizes away the BVH's box padding no
/// longer covers the box test's rounding (docs: `BOX_PAD`).
#[test]
fn a_camera_far_from_the_scene_sees_it_whole() {
    for dist in [1.0f32, 1e3, 1e4, 1e5] {
        let mut s = Scene::new("grid");
        let m = s.add_material(Material::matte("g", Vec3::splat(0.8)));
        let n = 16;
        for j in 0..n {
            for i in 0..n {
                let (x, y, d) = (i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5, 1.0 / n as f32);
                s.push_quad(
                    [vec3(x, y, 0.0), vec3(x + d, y, 0.0), vec3(x + d, y + d, 0.0), vec3(x, y + d, 0.0)],
                    m,
                );
            }
        }
        // The grid (size 1) spans 0.6 of the view's height.
        let fov = 2.0 * (0.5 / 0.6 / dist).atan().to_degrees();
        let eye = vec3(0.013, 0.021, dist);
        s.camera = Some(Camera { eye, forward: -Vec3::Z, up: Vec3::Y, fov_y_deg: fov, fov_x_deg: None });
        s.lights =
            vec![PointLight { position: vec3(0.0, 0.0, 2.0), intensity: Vec3::splat(4.0), spot: None }];
        s.settings = settings(128, 128);
        s.validate().unwrap();
        let gbuffer = |o: Options| {
            let mut o = o;
            o.keep_buffers = true;
            render(&s, o).gbuffer.unwrap()
        };
        let (rays, raster) = (gbuffer(Options::reference()), gbuffer(Options::hybrid()));
        // The middle 60 x 60 pixels lie well inside the grid's image (its middle 77 x 77).
        let holes = |g: &[Option<hyrt_tracer::Hit>]| {
            (34..94)
                .flat_map(|y| (34..94).map(move |x| (x, y)))
                .filter(|&(x, y)| g[y * 128 + x].is_none())
                .count()
        };
        assert_eq!((holes(&rays), holes(&raster)), (0, 0), "{dist} sizes away");
        assert!(rays == raster, "{dist} sizes away: rays and raster see different hits");
    }
}
