//! SMeRTS: point-light shadows from depth maps with selective shadow rays, against the
//! reference's shadow rays.
//!
//! The bound used throughout is the wrong-visibility count: camera hits whose map decision a
//! shadow ray contradicts (`Options::check_visibility`). SMeRTS replaces the decision by a ray on
//! every border pixel, so its wrong decisions are those the borders miss.

mod common;

use common::*;
use glam::{Vec3, vec3};
use hyrt::{
    metrics::{DisplayImage, compare},
    render::{Borders, Cache, Frame, Options, Renderer, Shadows, Subject, Visibility, shadows::LightStats},
    scene::{Camera, Material, PointLight, Scene, Settings},
};
use hyrt_shadowmap::MapKind;

fn with(shadows: Shadows, kind: MapKind) -> Options {
    let mut o = Options::hybrid();
    o.shadows = shadows;
    o.shadow.map.kind = kind;
    o.check_visibility = true;
    o
}

fn wrong(f: &Frame) -> u64 {
    f.stats.lights.iter().map(|l| l.wrong.expect("checked")).sum()
}

fn decided(f: &Frame) -> u64 {
    f.stats.lights.iter().map(|l| l.lit + l.shadowed + l.undecided).sum()
}

fn psnr(a: &Frame, b: &Frame, exposure: f32) -> f64 {
    compare(&DisplayImage::from_film(&a.film, exposure), &DisplayImage::from_film(&b.film, exposure))
        .expect("same size")
        .psnr_db
}

/// A floor of `n x n` quads (coplanar neighbours at every edge) of half-size `half` at y = 0.
fn push_floor(s: &mut Scene, half: f32, n: u32, m: u32) {
    let step = 2.0 * half / n as f32;
    for i in 0..n {
        for j in 0..n {
            let (x0, z0) = (-half + i as f32 * step, -half + j as f32 * step);
            let (x1, z1) = (x0 + step, z0 + step);
            s.push_quad([vec3(x0, 0.0, z0), vec3(x0, 0.0, z1), vec3(x1, 0.0, z1), vec3(x1, 0.0, z0)], m);
        }
    }
}

fn scene(name: &str, lights: Vec<PointLight>, cam: Camera, size: (u32, u32)) -> Scene {
    let mut s = Scene::new(name);
    s.lights = lights;
    s.camera = Some(cam);
    s.settings = Settings { width: size.0, height: size.1, max_depth: 5, exposure: 1.0 };
    s
}

fn light(p: Vec3, i: f32) -> PointLight {
    PointLight { position: p, intensity: Vec3::splat(i), spot: None }
}

/// Renders `s` with the reference and with `opts`; returns both frames.
fn against_reference(s: &Scene, opts: Options) -> (Frame, Frame) {
    s.validate().expect("valid test scene");
    let reference = render(s, Options::reference());
    let f = render(s, opts);
    (reference, f)
}

/// A floor lit at grazing angles (the light 2 cm above a 20 m floor made of 3,200 coplanar
/// triangles): the map alone (no border rays) must shadow nothing: no acne.
#[test]
fn grazing_floor_has_no_acne() {
    for height in [0.02f32, 0.2] {
        let mut s = scene(
            "grazing",
            vec![light(vec3(0.0, height, -9.5), 50.0)],
            Camera::look_at(vec3(0.0, 6.0, 6.0), vec3(0.0, 0.0, -2.0), Vec3::Y, 60.0),
            (160, 120),
        );
        let m = s.add_material(Material::matte("floor", Vec3::splat(0.7)));
        push_floor(&mut s, 10.0, 40, m);
        for kind in [MapKind::Cube, MapKind::Paraboloid] {
            let (_, f) = against_reference(&s, with(Shadows::Maps, kind));
            let l = f.stats.lights[0];
            assert!(l.lit > 10_000, "{kind:?}: the floor should be lit: {l:?}");
            assert_eq!((l.shadowed, wrong(&f)), (0, 0), "{kind:?}, light at {height} m: acne {l:?}");
        }
    }
}

/// A unit box resting on a floor of `cells x cells` quads, lit from above at an angle, seen
/// from above at another.
fn box_on_floor(cells: u32) -> Scene {
    let mut s = scene(
        "box on floor",
        vec![light(vec3(2.0, 4.0, 1.0), 20.0)],
        Camera::look_at(vec3(-3.0, 3.0, 4.0), vec3(0.3, 0.3, 0.0), Vec3::Y, 50.0),
        (200, 150),
    );
    let m = s.add_material(Material::matte("grey", Vec3::splat(0.6)));
    push_floor(&mut s, 4.0, cells, m);
    push_box(&mut s, vec3(-0.5, 0.0, -0.5), vec3(0.5, 1.0, 0.5), m);
    s
}

/// A box resting on the floor, lit from above at an angle: with maps alone, light may leak
/// under the box's edge only within a bounded band (peter-panning); SMeRTS corrects it.
#[test]
fn object_on_floor_does_not_leak_light() {
    let s = box_on_floor(8);
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let (reference, maps) = against_reference(&s, with(Shadows::Maps, kind));
        let shadow_px = maps.stats.lights[0].shadowed;
        assert!(shadow_px > 300, "{kind:?}: a visible shadow {:?}", maps.stats.lights);
        // Maps alone: wrong decisions are confined to a thin band along the shadow's outline.
        assert!(wrong(&maps) * 20 < shadow_px, "{kind:?}: maps alone, {} wrong of {shadow_px}", wrong(&maps));
        let (_, smerts) = against_reference(&s, with(Shadows::Smerts, kind));
        assert_eq!(wrong(&smerts), 0, "{kind:?}: SMeRTS {:?}", smerts.stats.lights);
        assert!(psnr(&reference, &smerts, 1.0) >= 50.0, "{kind:?}");
    }
}

/// Most pixels of a floor (two triangles) with one box on it are decided a whole tile at a
/// time (the map region under the tile sees the floor alone, or the box alone in front of it),
/// never a border pixel; the paraboloid's lookups are not central projections and decide point by
/// point. The images are right either way (the map decisions are the per-point ones).
#[test]
fn most_decisions_are_made_per_tile_on_cube_maps() {
    let s = box_on_floor(1);
    let cube = render(&s, with(Shadows::Smerts, MapKind::Cube));
    let l = cube.stats.lights[0];
    assert!(l.by_tile * 2 > l.lit + l.shadowed, "{l:?}");
    assert!(l.by_tile <= l.lit + l.shadowed);
    let para = render(&s, with(Shadows::Smerts, MapKind::Paraboloid));
    assert_eq!(para.stats.lights[0].by_tile, 0);
    assert_eq!(wrong(&cube), 0, "{:?}", cube.stats.lights);
}

/// Occluders straddling cube-face edges, a cube corner and the paraboloid seam (z = 0 of the
/// map frame) cast their shadows on the walls of a room around the light: no gap along the seams
/// (maps alone stay within a thin band of the outlines) and SMeRTS decides every pixel right.
#[test]
fn occluders_across_cube_edges_and_the_paraboloid_seam() {
    let mut s = scene(
        "seams",
        vec![light(Vec3::ZERO, 30.0)],
        Camera::look_at(vec3(-4.0, -3.5, -4.0), vec3(2.0, 1.5, 1.0), Vec3::Y, 90.0),
        (240, 180),
    );
    let m = s.add_material(Material::matte("wall", Vec3::splat(0.8)));
    // Room: the inside of a box of half-size 5 (its faces seen from inside).
    push_box(&mut s, Vec3::splat(-5.0), Vec3::splat(5.0), m);
    // Across the cube edge x = y (z = 0 also the seam), a corner (1, 1, 1), and the seam z = 0.
    push_box(&mut s, vec3(1.4, 1.4, -0.3) - 0.25, vec3(1.6, 1.6, 0.3) + 0.25, m);
    push_box(&mut s, Vec3::splat(1.2), Vec3::splat(1.5), m);
    push_box(&mut s, vec3(1.8, -0.6, -0.2), vec3(2.0, 0.4, 0.2), m);
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let (_, maps) = against_reference(&s, with(Shadows::Maps, kind));
        let l = maps.stats.lights[0];
        assert!(l.shadowed > 500, "{kind:?}: shadows on the walls {l:?}");
        assert!(wrong(&maps) * 20 < l.shadowed, "{kind:?}: maps alone {} wrong, {l:?}", wrong(&maps));
        let (reference, smerts) = against_reference(&s, with(Shadows::Smerts, kind));
        assert_eq!(wrong(&smerts), 0, "{kind:?}: SMeRTS {:?}", smerts.stats.lights);
        assert!(psnr(&reference, &smerts, 1.0) >= 50.0, "{kind:?}");
    }
}

/// A light 1 mm from a 4 m wall, with a small occluder between: the near plane of the maps
/// keeps the wall, and SMeRTS matches the reference.
#[test]
fn light_very_close_to_a_wall() {
    let mut s = scene(
        "close light",
        vec![light(vec3(0.0, 0.0, 1e-3), 0.5)],
        Camera::look_at(vec3(0.3, 0.2, 3.0), Vec3::ZERO, Vec3::Y, 60.0),
        (160, 120),
    );
    let m = s.add_material(Material::matte("wall", Vec3::splat(0.8)));
    s.push_quad([vec3(-2.0, -2.0, 0.0), vec3(2.0, -2.0, 0.0), vec3(2.0, 2.0, 0.0), vec3(-2.0, 2.0, 0.0)], m);
    push_box(&mut s, vec3(0.1, -0.05, 0.0004), vec3(0.2, 0.05, 0.0006), m);
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let (reference, smerts) = against_reference(&s, with(Shadows::Smerts, kind));
        // The wall is all along the paraboloid's rim (the seam plane is parallel to it), where
        // the map-space test leaves most pixels to rays: correct, not cheap.
        let l = smerts.stats.lights[0];
        assert!(l.lit + l.undecided > 10_000, "{kind:?}: {l:?}");
        assert_eq!(wrong(&smerts), 0, "{kind:?}: {l:?}");
        assert!(psnr(&reference, &smerts, 1.0) >= 50.0, "{kind:?}");
    }
}

/// A light inside a closed box: nothing outside is lit, by the maps alone.
#[test]
fn light_inside_a_closed_box() {
    let mut s = scene(
        "boxed light",
        vec![light(vec3(0.0, 0.5, 0.0), 5.0), light(vec3(3.0, 3.0, 0.0), 5.0)],
        Camera::look_at(vec3(-3.0, 3.0, 4.0), vec3(0.0, 0.3, 0.0), Vec3::Y, 60.0),
        (160, 120),
    );
    let m = s.add_material(Material::matte("grey", Vec3::splat(0.6)));
    push_floor(&mut s, 4.0, 4, m);
    push_box(&mut s, vec3(-0.5, 0.01, -0.5), vec3(0.5, 1.0, 0.5), m);
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let (_, f) = against_reference(&s, with(Shadows::Maps, kind));
        let boxed = f.stats.lights[0];
        assert_eq!(boxed.lit, 0, "{kind:?}: light leaks out of the box: {boxed:?}");
        assert!(boxed.shadowed > 5_000, "{kind:?}: {boxed:?}");
        assert_eq!(boxed.wrong, Some(0), "{kind:?}: {:?}", f.stats.lights);
    }
}

/// Degenerate triangles (zero area, repeated vertices, collinear) in the scene do not disturb
/// maps or decisions.
#[test]
fn degenerate_triangles_in_the_maps() {
    let mut s = scene(
        "degenerate",
        vec![light(vec3(1.0, 3.0, 0.5), 10.0)],
        Camera::look_at(vec3(-3.0, 3.0, 4.0), vec3(0.0, 0.3, 0.0), Vec3::Y, 50.0),
        (160, 120),
    );
    let m = s.add_material(Material::matte("grey", Vec3::splat(0.6)));
    push_floor(&mut s, 3.0, 6, m);
    push_box(&mut s, vec3(-0.4, 0.0, -0.4), vec3(0.4, 0.8, 0.4), m);
    let p = vec3(0.0, 1.5, 0.0);
    s.push_triangle([p, p, p], None, m);
    s.push_triangle([p, p + Vec3::X, p], None, m);
    s.push_triangle([p, p + Vec3::X, p + 2.0 * Vec3::X], None, m);
    let (reference, f) = against_reference(&s, with(Shadows::Smerts, MapKind::Cube));
    assert_eq!(wrong(&f), 0);
    assert!(psnr(&reference, &f, 1.0) >= 50.0);
}

/// The thesis scenes at 640x480 with the hybrid defaults: PSNR >= 45 dB against the reference,
/// wrong-visibility pixels <= 0.05 %, shadow rays <= 8 % of the reference's.
fn thesis_scene(file: &str) {
    let mut s = hyrt::scene::load(root().join("scenes").join(file).to_str().unwrap()).unwrap();
    s.settings.width = 640;
    s.settings.height = 480;
    let reference = render(&s, Options::reference());
    let mut opts = Options::hybrid();
    opts.check_visibility = true;
    let f = render(&s, opts);
    let p = psnr(&reference, &f, s.settings.exposure);
    let pixels = 640.0 * 480.0;
    let wrong_px = wrong(&f);
    let ratio = f.stats.rays.shadow as f64 / reference.stats.rays.shadow as f64;
    eprintln!(
        "{file}: PSNR {p:.2} dB, wrong {wrong_px} ({:.4} %), shadow rays {} of {} ({:.2} %), hint hits {}, per light {:?}",
        100.0 * wrong_px as f64 / pixels,
        f.stats.rays.shadow,
        reference.stats.rays.shadow,
        100.0 * ratio,
        f.stats.rays.shadow_hint_hits,
        f.stats.lights
    );
    assert!(p >= 45.0, "{file}: PSNR {p:.2} dB");
    assert!(wrong_px as f64 <= 0.0005 * pixels, "{file}: {wrong_px} wrong-visibility pixels");
    assert!(ratio <= 0.08, "{file}: shadow rays {:.2} % of the reference's", 100.0 * ratio);
    // Primary rays only where a pixel's ray leaves its rasterized triangle (edges).
    assert!(f.stats.rays.primary as f64 <= 0.001 * pixels, "{file}: {:?}", f.stats.rays);
}

#[test]
fn smerts_on_cornell_bunny_mirror() {
    thesis_scene("cornell-bunny-mirror.toml");
}

#[test]
fn smerts_on_office_with_its_blinds() {
    thesis_scene("office.toml");
}

#[test]
fn smerts_on_conference() {
    thesis_scene("conference.toml");
}

/// `--ambiguous triangles`: the pairs whose footprint is a border only because of occluders
/// within the bias band are decided by testing those triangles alone with their shadow ray.
/// They are exactly border pairs of `--ambiguous rays` (the two modes' undecided and settled
/// pairs add up to the same borders), they spare their rays, and the image keeps the thesis
/// scenes' bounds against the reference.
#[test]
fn ambiguous_borders_settled_by_their_triangles() {
    let mut s = hyrt::scene::load(root().join("scenes/cornell-bunny-mirror.toml").to_str().unwrap()).unwrap();
    (s.settings.width, s.settings.height) = (320, 240);
    let reference = render(&s, Options::reference());
    let mut opts = Options::hybrid();
    opts.check_visibility = true;
    // Neighbours by rays: the settled pairs are then the ambiguous ones alone.
    opts.shadow.neighbours = hyrt::render::Neighbours::Rays;
    let rays = render(&s, opts);
    opts.shadow.ambiguous = hyrt::render::Ambiguous::Triangles;
    let tris = render(&s, opts);
    let sum = |f: &Frame, g: fn(&LightStats) -> u64| f.stats.lights.iter().map(g).sum::<u64>();
    let settled = sum(&tris, |l| l.by_suspects);
    assert_eq!(sum(&rays, |l| l.by_suspects), 0);
    assert!(settled > 0, "{:?}", tris.stats.lights);
    assert_eq!(sum(&tris, |l| l.undecided) + settled, sum(&rays, |l| l.undecided));
    assert_eq!(decided(&tris), decided(&rays));
    // Each settled pair spares its ray (the mirror hits' settled pairs too).
    assert!(
        tris.stats.rays.shadow + settled <= rays.stats.rays.shadow,
        "{:?} {:?}",
        tris.stats.rays,
        rays.stats.rays
    );
    let pixels = 320.0 * 240.0;
    assert!(wrong(&tris) as f64 <= 0.0005 * pixels, "{} wrong", wrong(&tris));
    assert!(psnr(&reference, &tris, s.settings.exposure) >= 45.0);
}

/// `--neighbours triangles` (the default): on the Cornell box, whose bunny is a curved mesh of
/// small facets, most border pairs are borders only because of facets next to their own
/// (their planes cross the ray to the light over the point): testing those facets alone
/// settles them. At 320x240 at least two in five border rays go (at 640x480, about seven in
/// ten: finer levels put fewer facets in a footprint), every decision is still made (the same
/// count as with whole rays), and the image keeps the thesis scenes' bounds.
#[test]
fn neighbours_settled_by_their_triangles_on_the_cornell_box() {
    let mut s = hyrt::scene::load(root().join("scenes/cornell-bunny-mirror.toml").to_str().unwrap()).unwrap();
    (s.settings.width, s.settings.height) = (320, 240);
    let reference = render(&s, Options::reference());
    let mut opts = Options::hybrid();
    opts.check_visibility = true;
    let tris = render(&s, opts);
    opts.shadow.neighbours = hyrt::render::Neighbours::Rays;
    let rays = render(&s, opts);
    let sum = |f: &Frame, g: fn(&LightStats) -> u64| f.stats.lights.iter().map(g).sum::<u64>();
    let (settled, border) = (sum(&tris, |l| l.by_suspects), sum(&tris, |l| l.undecided));
    eprintln!("border rays {border} (whole rays: {}), settled {settled}", sum(&rays, |l| l.undecided));
    assert_eq!(sum(&rays, |l| l.by_suspects), 0);
    assert!(5 * border <= 3 * sum(&rays, |l| l.undecided), "{border} border rays");
    assert!(settled > 0);
    assert_eq!(decided(&tris), decided(&rays));
    let pixels = 320.0 * 240.0;
    assert!(wrong(&tris) as f64 <= 0.0005 * pixels, "{} wrong", wrong(&tris));
    assert!(psnr(&reference, &tris, s.settings.exposure) >= 50.0);
}

/// A concave crease: a floor and a short wall leaning over it from its edge, the wall's
/// triangles sharing vertices with the floor's along the crease, and a light behind the wall
/// whose shadow edge falls on the floor's last row next to the crease. The border pairs there
/// are settled by testing the wall's triangles (the point's neighbours) with their rays: where
/// one is hit, shadow, exactly as the reference. Every decision agrees with a ray, and the image
/// is the one whole rays give, bit for bit.
#[test]
fn a_crease_whose_neighbour_shadows_is_settled_exactly() {
    let mut s = scene(
        "crease",
        vec![light(vec3(2.5, 4.0, 0.3), 12.0)],
        Camera::look_at(vec3(-0.5, 2.2, 2.2), vec3(0.5, 0.0, 0.0), Vec3::Y, 50.0),
        (160, 120),
    );
    let m = s.add_material(Material::matte("grey", Vec3::splat(0.7)));
    push_floor(&mut s, 1.0, 8, m);
    // The wall: one row of quads from the floor's edge at x = 1 up to (0.9, 0.3), over the
    // floor, cut along z as the floor is (so the crease's vertices are shared).
    let step = 0.25;
    for j in 0..8 {
        let (z0, z1) = (-1.0 + j as f32 * step, -1.0 + (j + 1) as f32 * step);
        s.push_quad([vec3(1.0, 0.0, z0), vec3(0.9, 0.3, z0), vec3(0.9, 0.3, z1), vec3(1.0, 0.0, z1)], m);
    }
    let mut opts = Options::hybrid();
    opts.check_visibility = true;
    let (reference, tris) = against_reference(&s, opts);
    opts.shadow.neighbours = hyrt::render::Neighbours::Rays;
    let rays = render(&s, opts);
    let settled: u64 = tris.stats.lights.iter().map(|l| l.by_suspects).sum();
    eprintln!("settled {settled}, {:?}", tris.stats.lights[0]);
    assert!(settled > 0, "no border pair was settled by its neighbours");
    assert_eq!(wrong(&tris), 0);
    assert_eq!(wrong(&rays), 0);
    assert!(tris.film.pixels == rays.film.pixels, "the settled pairs changed the image");
    assert!(tris.stats.rays.shadow < rays.stats.rays.shadow);
    assert!(psnr(&reference, &tris, s.settings.exposure) >= 50.0);
}

/// Maps are built once per scene: the second frame builds none, and gives the same bytes.
/// Faces that no camera hit falls on are not drawn: a light above a floor needs no upward face.
#[test]
fn maps_are_cached_and_only_needed_faces_drawn() {
    let s = hyrt::scene::load("cornell").unwrap();
    let r = Renderer::new(&s, Options::hybrid());
    let a = r.render(&|| {});
    let b = r.render(&|| {});
    assert_eq!(a.stats.maps_built, s.lights.len() as u32);
    assert_eq!(b.stats.maps_built, 0);
    assert!(a.film.pixels == b.film.pixels);
    let lights = |f: &Frame| -> Vec<(bool, bool)> {
        f.stats
            .decisions
            .iter()
            .filter(|d| matches!(d.what, Subject::Light(_)))
            .map(|d| (d.run, d.built()))
            .collect()
    };
    assert_eq!(lights(&a), vec![(true, true); s.lights.len()], "the first frame builds every map");
    assert_eq!(lights(&b), vec![(true, false); s.lights.len()], "the second reuses them");

    let floor = floor_scene(5.0, Vec3::splat(0.5), 4.0, 60.0, vec![light(vec3(0.5, 2.0, 0.0), 5.0)], 64, 64);
    // The camera sees |x|, |z| < 2.31 of the floor; from the light at (0.5, 2, 0) that is the
    // -y face, and the -x, +z, -z faces where the horizontal offset exceeds the height 2; not
    // +y (up) nor +x (offsets up to 1.81).
    let f = render(&floor, Options::hybrid());
    assert_eq!(f.stats.lights[0].faces_drawn, 4, "{:?}", f.stats.lights);
}

/// Same bytes for 1 and 2 threads, for both map kinds.
#[test]
fn smerts_is_deterministic_across_thread_counts() {
    let mut s = hyrt::scene::load("cornell").unwrap();
    s.settings.width = 128;
    s.settings.height = 96;
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let mut o = Options::hybrid();
        o.shadow.map.kind = kind;
        let run =
            |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(|| render(&s, o));
        let (a, b) = (run(1), run(2));
        assert!(a.film.pixels == b.film.pixels, "{kind:?}");
        assert_eq!(a.stats.rays, b.stats.rays, "{kind:?}");
    }
}

/// The stats split shadow rays into hint hits and traversals, every facing (hit, light) is
/// counted once as lit, shadowed or undecided, and undecided ones are exactly the camera's
/// shadow rays (the built-in Cornell box has a mirror: its shadow rays come on top).
#[test]
fn stats_account_for_every_decision() {
    let s = hyrt::scene::load("cornell").unwrap();
    let mut o = Options::hybrid();
    o.shadow.mirror = hyrt::render::MirrorShadows::Maps;
    let f = render(&s, o);
    let und: u64 = f.stats.lights.iter().map(|l| l.undecided).sum();
    assert!(und > 0);
    assert!(f.stats.rays.shadow >= und);
    assert!(f.stats.rays.shadow_hint_hits > 0 && f.stats.rays.shadow_traversals() > 0, "{:?}", f.stats.rays);
    // Each facing (hit, light) pair of the reference is one shadow ray from a camera hit.
    let mut reference_opts = Options::reference();
    reference_opts.visibility = Visibility::Raster;
    let mut no_mirror = s.clone();
    no_mirror.settings.max_depth = 0;
    let rf = render(&no_mirror, reference_opts);
    let ff = render(&no_mirror, o);
    assert_eq!(rf.stats.rays.shadow, decided(&ff));
    assert_eq!(ff.stats.rays.shadow, ff.stats.lights.iter().map(|l| l.undecided).sum::<u64>());
    let _: Vec<LightStats> = ff.stats.lights;
}

/// The border methods differ: the map-space test alone finds borders the Laplacian misses (thin
/// occluders), and both together cast at least as many rays as either.
#[test]
fn border_methods_are_knobs() {
    let s = hyrt::scene::load("cornell").unwrap();
    let rays = |b| {
        let mut o = Options::hybrid();
        o.shadow.borders = b;
        render(&s, o).stats.lights.iter().map(|l| l.undecided).sum::<u64>()
    };
    let (lap, depth, both) = (rays(Borders::Laplacian), rays(Borders::MapSpace), rays(Borders::Both));
    assert!(lap > 0 && depth > 0);
    assert!(both >= lap.max(depth), "laplacian {lap}, depth {depth}, both {both}");
}

/// A camera moved between two frames: no light-map face (for paged maps, the cube default: no
/// page) already drawn is drawn again, the faces the new view needs are drawn (the map is
/// extended), and the image equals a fresh renderer's image of the new view, byte for byte.
/// Cube and paraboloid maps.
#[test]
fn a_moved_camera_draws_only_the_faces_it_newly_needs() {
    // A light above a floor with a box: looking straight down at a patch of floor on one side
    // of the light needs one face of its map (cube: the lower one; dual paraboloid: the +z
    // one); a wide view of the floor and the box needs others as well.
    let mut s = box_on_floor(8);
    s.lights = vec![light(vec3(0.2, 1.6, 0.1), 4.0)];
    let down = Camera::look_at(vec3(0.2, 4.0, 1.6), vec3(0.2, 0.0, 1.61), Vec3::Y, 8.0);
    let around = Camera::look_at(vec3(3.5, 0.4, -3.0), vec3(-1.0, 1.2, 1.0), Vec3::Y, 70.0);
    for kind in [MapKind::Cube, MapKind::Paraboloid] {
        let opts = with(Shadows::Smerts, kind);
        s.camera = Some(down);
        let mut r = Renderer::new(&s, opts);
        r.render(&|| {});
        let before = r.light_map(0).unwrap().faces_drawn().to_vec();
        r.set_camera(&around);
        let moved = r.render(&|| {});
        let map = r.light_map(0).unwrap();
        let after = map.faces_drawn().to_vec();
        let drawn = after.iter().filter(|&&d| d).count() as u32;
        eprintln!("{kind:?}: faces {before:?} -> {after:?}, rasterized {}", map.faces_rasterized());
        assert!(before.iter().zip(&after).all(|(b, a)| !b || *a), "{kind:?}: a face was dropped");
        assert!(after.iter().zip(&before).any(|(a, b)| *a && !*b), "{kind:?}: the test needs a new face");
        if map.is_paged() {
            assert_eq!(map.pages_rasterized(), map.page_count() as u64, "{kind:?}: a page was drawn twice");
        } else {
            assert_eq!(map.faces_rasterized(), drawn, "{kind:?}: a face was drawn twice");
        }
        assert!(
            moved
                .stats
                .decisions
                .iter()
                .any(|d| d.reason.contains("map extended") && d.cache == Cache::Extended),
            "{kind:?}: {:#?}",
            moved.stats.decisions
        );

        let mut fresh_scene = s.clone();
        fresh_scene.camera = Some(around);
        let fresh = Renderer::new(&fresh_scene, opts).render(&|| {});
        let bits =
            |f: &Frame| f.film.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert!(bits(&moved) == bits(&fresh), "{kind:?}: the moved camera's image differs from a fresh one");
    }
}

/// A light moved between two frames: its map alone is built again (the other light's map is
/// the same object, reused), its VPLs alone are traced again and get new maps (the other
/// light's are kept), and the image equals a fresh renderer's image of the scene with the
/// light there, byte for byte. A new intensity retraces every VPL (paths go by power).
#[test]
fn a_moved_light_rebuilds_exactly_its_own_map() {
    let mut s = box_on_floor(8);
    s.lights = vec![light(vec3(2.0, 4.0, 1.0), 20.0), light(vec3(-1.5, 2.5, -1.0), 6.0)];
    let mut opts = with(Shadows::Smerts, MapKind::Cube);
    opts.check_visibility = false;
    opts.indirect = hyrt::render::Indirect::Maps;
    opts.indirect_opts.vpl.paths = 32;
    opts.indirect_opts.map.resolution = 64;
    let moved_light = light(vec3(-0.5, 1.8, 1.2), 6.0);

    let mut r = Renderer::new(&s, opts);
    r.render(&|| {});
    let kept = r.light_map(0).unwrap();
    let of = |r: &Renderer, l: u32| -> Vec<_> {
        r.cached_vpls().unwrap().0.iter().filter(|v| v.light == l).copied().collect()
    };
    let (vpls0, vpls1) = (of(&r, 0), of(&r, 1));
    assert!(!vpls0.is_empty() && !vpls1.is_empty(), "both lights leave VPLs");
    assert_eq!(r.set_light(1, s.lights[1]), Vec::<&str>::new(), "an unchanged light drops nothing");
    assert_eq!(r.set_light(1, moved_light), vec!["the light's map", "the light's VPLs and their maps"]);
    let f = r.render(&|| {});
    assert_eq!(f.stats.maps_built, 1, "one map built");
    assert!(std::sync::Arc::ptr_eq(&kept, &r.light_map(0).unwrap()), "light 0's map was rebuilt");
    let says = |what: Subject, text: &str| {
        f.stats.decisions.iter().any(|d| d.what == what && d.reason.contains(text))
    };
    assert!(says(Subject::Light(0), "map reused"), "{:#?}", f.stats.decisions);
    assert!(says(Subject::Light(1), "map rebuilt: the light moved"), "{:#?}", f.stats.decisions);
    let retraced = format!("{} traced again from the moved light(s), {} reused", vpls1.len(), vpls0.len());
    assert!(says(Subject::Vpls, &retraced), "{:#?}", f.stats.decisions);
    let rebuilt = format!("{} of {} paraboloid maps", vpls1.len(), vpls0.len() + vpls1.len());
    assert!(says(Subject::VplMaps, &rebuilt), "{:#?}", f.stats.decisions);
    assert_eq!(of(&r, 0), vpls0, "light 0's VPLs are kept");
    assert_ne!(of(&r, 1), vpls1, "light 1's VPLs moved with it");
    assert_eq!(r.lights()[1], moved_light);

    let mut fresh_scene = s.clone();
    fresh_scene.lights[1] = moved_light;
    let fresh = Renderer::new(&fresh_scene, opts).render(&|| {});
    let bits =
        |f: &Frame| f.film.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    assert!(bits(&f) == bits(&fresh), "the moved light's image differs from a fresh one");
    assert_ne!(bits(&f), bits(&Renderer::new(&s, opts).render(&|| {})), "the light did not move");

    // A new intensity shares the paths out afresh: every VPL is traced again.
    let brighter = light(moved_light.position, 12.0);
    assert_eq!(r.set_light(1, brighter), vec!["VPLs and their maps"]);
    let f = r.render(&|| {});
    assert_eq!(f.stats.maps_built, 0, "the map depends on the position alone");
    assert!(says_in(&f, Subject::Vpls, "generated from 32 light path(s) (a light's intensity changed)"));
    fresh_scene.lights[1] = brighter;
    let fresh = Renderer::new(&fresh_scene, opts).render(&|| {});
    assert!(bits(&f) == bits(&fresh), "the brighter light's image differs from a fresh one");
}

fn says_in(f: &Frame, what: Subject, text: &str) -> bool {
    f.stats.decisions.iter().any(|d| d.what == what && d.reason.contains(text))
}
