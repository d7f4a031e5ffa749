//! Indirect light from virtual point lights: an analytic bound, maps against rays, the plan.

mod common;

use common::*;
use glam::{Vec3, vec3};
use hyrt::{
    metrics::{DisplayImage, compare},
    render::{Frame, Indirect, Options, Pass, Renderer, Shadows},
    scene::{Camera, Material, PointLight, Scene, Settings},
};

/// A UV sphere of radius `r` around the origin, `n` segments around (and `n / 2` from pole to
/// pole), facing inwards.
fn push_sphere(s: &mut Scene, r: f32, n: u32, m: u32) {
    let at = |i: u32, j: u32| {
        let (th, ph) =
            (std::f32::consts::PI * j as f32 / (n / 2) as f32, std::f32::consts::TAU * i as f32 / n as f32);
        vec3(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * r
    };
    for j in 0..n / 2 {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if j > 0 {
                s.push_triangle([a, b, c], None, m);
            }
            if j + 1 < n / 2 {
                s.push_triangle([a, c, d], None, m);
            }
        }
    }
}

/// The inside of a closed diffuse sphere (radius 3, albedo 0.5) with a light of intensity 2 at
/// its centre, seen from near the centre; with the exact one-bounce indirect radiance
/// `rho^2 E / pi` and the radius.
fn closed_sphere() -> (Scene, f32, f32) {
    let (rho, intensity, radius) = (0.5f32, 2.0f32, 3.0f32);
    let mut s = Scene::new("sphere");
    let m = s.add_material(Material::matte("wall", Vec3::splat(rho)));
    push_sphere(&mut s, radius, 192, m);
    s.lights = vec![PointLight { position: Vec3::ZERO, intensity: Vec3::splat(intensity), spot: None }];
    s.camera = Some(Camera::look_at(vec3(0.0, 0.3, 0.5), vec3(1.0, 0.1, -3.0), Vec3::Y, 70.0));
    s.settings = Settings { width: 96, height: 72, max_depth: 0, exposure: 1.0 };
    s.validate().unwrap();
    (s, rho * rho * intensity / (radius * radius) / std::f32::consts::PI, radius)
}

/// The indirect part alone: a render with indirect light minus one without.
fn indirect_only(s: &Scene, opts: Options) -> (Vec<Vec3>, Frame) {
    let with = render(s, opts);
    let without = render(s, Options { indirect: Indirect::None, ..opts });
    let diff = with.film.pixels.iter().zip(&without.film.pixels).map(|(a, b)| *a - *b).collect();
    (diff, with)
}

fn options(indirect: Indirect, paths: u32, clamp: f32) -> Options {
    let mut o = Options::reference();
    o.indirect = indirect;
    o.indirect_opts.vpl.paths = paths;
    o.indirect_opts.clamp = clamp;
    o
}

/// Inside a closed diffuse sphere of albedo `rho` with a point light of intensity `I` at its
/// centre, one bounce of indirect irradiance is uniform, `rho E` with `E = I / R^2`, so the
/// indirect radiance is `rho^2 E / pi` everywhere. For two points of a sphere
/// `cos_x cos_v / d^2 = 1 / (4 R^2)` whatever their distance, so every VPL adds the same amount
/// to every pixel and the estimate is exact up to the tessellation (no clamp is needed): bound
/// 1 % on the image mean and on 99 % of the pixels, for both visibility strategies. (The last
/// 0.1 % of the pixels are a few percent off, up to 60 %: a VPL on a neighbouring flat facet
/// a few millimetres away, where the facets' normals break the sphere's identity; the clamp
/// `d_min`, off here, is what bounds those in practice.)
#[test]
fn closed_sphere_one_bounce_is_rho_times_direct() {
    let (s, expected, _) = closed_sphere();
    for ind in [Indirect::Rays, Indirect::Maps] {
        let (img, f) = indirect_only(&s, options(ind, 200, 0.0));
        assert!(f.stats.vpls >= 190, "{ind:?}: {} VPLs", f.stats.vpls);
        let lum: Vec<f32> = img.iter().map(|p| p.x).collect();
        let mean = lum.iter().sum::<f32>() / lum.len() as f32;
        let mut errs: Vec<f32> = lum.iter().map(|l| (l / expected - 1.0).abs()).collect();
        errs.sort_by(f32::total_cmp);
        let p99 = errs[errs.len() * 99 / 100];
        eprintln!(
            "errors: median {:.4} p99 {:.4} p99.9 {:.4} max {:.4}",
            errs[errs.len() / 2],
            p99,
            errs[errs.len() * 999 / 1000],
            errs[errs.len() - 1]
        );
        eprintln!(
            "{ind:?}: mean {mean:.6} expected {expected:.6} ({:+.3} %)",
            100.0 * (mean / expected - 1.0)
        );
        assert!((mean / expected - 1.0).abs() <= 0.01, "{ind:?}: mean {mean} vs {expected}");
        assert!(p99 <= 0.01, "{ind:?}: 1 % of the pixels are more than {:.2} % off", 100.0 * p99);
    }
}

/// The clamp `d_min` is a bias, measured, not hidden: in the sphere above a VPL at distance
/// `d` adds `(d^2 / 4R^2) / max(d^2, d_min^2)` instead of `1 / 4R^2`, and for points spread
/// uniformly over the sphere `P(d < x) = x^2 / 4R^2`, so the expected relative loss is
/// `integral_0^d_min (1 - x^2/d_min^2) 2x / 4R^2 dx = d_min^2 / 8R^2`. With `d_min` a tenth of
/// the bounding-box diagonal (1.04 for R = 3: a 1.5 % loss) the measured mean must match that
/// within 0.3 % (the VPLs are a finite sample); with 0.01 the loss is 0.015 %.
#[test]
fn distance_clamp_bias_matches_its_analytic_value() {
    let (s, expected, radius) = closed_sphere();
    let diag = {
        let (lo, hi) = s.bounds().unwrap();
        (hi - lo).length()
    };
    let mean = |clamp| {
        let (img, _) = indirect_only(&s, options(Indirect::Rays, 400, clamp));
        img.iter().map(|p| p.x).sum::<f32>() / img.len() as f32
    };
    let unclamped = mean(0.0);
    for clamp in [0.01f32, 0.1] {
        let d_min = clamp * diag;
        let predicted = -(d_min * d_min) / (8.0 * radius * radius);
        let measured = mean(clamp) / unclamped - 1.0;
        eprintln!(
            "clamp {clamp}: d_min {d_min:.3}, bias {:+.3} % (predicted {:+.3} %)",
            100.0 * measured,
            100.0 * predicted
        );
        assert!((measured - predicted).abs() <= 0.003, "clamp {clamp}: {measured} vs {predicted}");
    }
    assert!((unclamped / expected - 1.0).abs() <= 0.01);
}

/// With the same VPLs, maps and rays agree on the thesis scenes (45 VPLs, 640x480): PSNR of
/// the full image >= `bound` dB with VPL maps of `res` texels a side (the default if `None`),
/// and the indirect-only images compared separately (printed).
fn maps_against_rays(file: &str, res: Option<u32>, bound: f64) {
    let mut s = hyrt::scene::load(root().join("scenes").join(file).to_str().unwrap()).unwrap();
    s.settings.width = 640;
    s.settings.height = 480;
    let (ind_rays, rays) = indirect_only(&s, options(Indirect::Rays, 45, 0.01));
    let mut o = options(Indirect::Maps, 45, 0.01);
    if let Some(res) = res {
        o.indirect_opts.map.resolution = res;
    }
    let (ind_maps, maps) = indirect_only(&s, o);
    let e = s.settings.exposure;
    let full = compare(&DisplayImage::from_film(&rays.film, e), &DisplayImage::from_film(&maps.film, e))
        .unwrap()
        .psnr_db;
    let film = |px: Vec<Vec3>| hyrt::film::Film { width: 640, height: 480, pixels: px };
    let only =
        compare(&DisplayImage::from_film(&film(ind_rays), e), &DisplayImage::from_film(&film(ind_maps), e))
            .unwrap()
            .psnr_db;
    eprintln!(
        "{file}: full image {full:.2} dB, indirect only {only:.2} dB; VPL rays {} -> {}; {} VPLs, maps {:.1} MB",
        rays.stats.rays.vpl_shadow,
        maps.stats.rays.vpl_shadow,
        maps.stats.vpls,
        maps.stats.vpl_map_bytes as f64 / 1e6
    );
    assert_eq!(maps.stats.rays.vpl_shadow, 0);
    assert!(rays.stats.rays.vpl_shadow > 1_000_000);
    assert!(full >= bound, "{file}: {full:.2} dB");
}

/// The bounds are the measured values of the default maps, rounded down by half a decibel or
/// so: a change that costs accuracy shows. (The target is 40 dB.)
#[test]
fn vpl_maps_match_vpl_rays_on_cornell_bunny_mirror() {
    maps_against_rays("cornell-bunny-mirror.toml", None, 42.0);
}

/// The hardest of the three: VPLs within a fraction of a unit of a wall see that wall, and the
/// blinds in front of it, squeezed into a band a texel or two wide of their map. The default
/// maps fall short of 40 dB here (measured 37.1 dB); maps of 1536 texels a side reach it
/// (41.1 dB), at 4.7 MB per VPL.
#[test]
fn vpl_maps_match_vpl_rays_on_office() {
    maps_against_rays("office.toml", None, 36.5);
    maps_against_rays("office.toml", Some(1536), 40.0);
}

#[test]
fn vpl_maps_match_vpl_rays_on_conference() {
    maps_against_rays("conference.toml", None, 43.5);
}

/// A light sealed in a closed box places its VPLs inside the box only: nothing outside gets
/// indirect light, with either strategy.
#[test]
fn light_that_reaches_no_visible_surface_adds_nothing() {
    let mut s = floor_scene(3.0, Vec3::splat(0.5), 4.0, 60.0, vec![], 48, 48);
    let m = s.add_material(Material::matte("box", Vec3::splat(0.8)));
    push_box(&mut s, vec3(-0.5, 0.5, -0.5), vec3(0.5, 1.5, 0.5), m);
    s.lights = vec![PointLight { position: vec3(0.0, 1.0, 0.0), intensity: Vec3::splat(5.0), spot: None }];
    s.validate().unwrap();
    for ind in [Indirect::Rays, Indirect::Maps] {
        let f = render(&s, options(ind, 64, 0.01));
        assert!(f.stats.vpls > 0);
        assert!(f.film.pixels.iter().all(|p| *p == Vec3::ZERO), "{ind:?}: light escaped the box");
    }
}

/// Indirect light runs only when asked; the plan says so, and no VPL work is done otherwise.
#[test]
fn indirect_runs_only_when_asked() {
    let s = hyrt::scene::load("cornell").unwrap();
    let off = Renderer::new(&s, Options::hybrid());
    assert!(off.plan.skipped.iter().any(|d| d.pass == Pass::Indirect));
    let f = off.render(&|| {});
    assert_eq!((f.stats.vpls, f.stats.rays.vpl_shadow, f.stats.rays.vpl_path), (0, 0, 0));
    assert!(!f.stats.pass_ms.contains_key(&hyrt::render::Pass::VplGen));

    let mut on = Options::hybrid();
    on.indirect = Indirect::Maps;
    let r = Renderer::new(&s, on);
    assert!(r.plan.runs(Pass::Indirect));
    let (a, b) = (r.render(&|| {}), r.render(&|| {}));
    assert!(a.stats.vpls > 0 && a.stats.rays.vpl_path > 0);
    // Cached: the second frame traces no paths and builds no maps, and gives the same bytes.
    assert_eq!(b.stats.rays.vpl_path, 0);
    let built = |f: &hyrt::render::Frame| {
        f.stats.decisions.iter().any(|d| d.what == hyrt::render::Subject::VplMaps && d.run)
    };
    assert!(built(&a) && !built(&b));
    assert!(a.film.pixels == b.film.pixels);
    let _ = Shadows::Smerts;
}

/// Same bytes for 1 and 2 threads, with either strategy.
#[test]
fn indirect_is_deterministic_across_thread_counts() {
    let mut s = hyrt::scene::load("cornell").unwrap();
    s.settings.width = 96;
    s.settings.height = 72;
    for ind in [Indirect::Rays, Indirect::Maps] {
        let run = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
                .install(|| render(&s, options(ind, 45, 0.01)))
        };
        let (a, b) = (run(1), run(2));
        assert!(a.film.pixels == b.film.pixels, "{ind:?}");
        assert_eq!(a.stats.rays, b.stats.rays, "{ind:?}");
    }
}

/// Hard cases in one room: a light 2 cm above the floor and 2 cm from two walls, so that many
/// VPLs lie within centimetres of a wall (which their maps see edge-on, on the paraboloid's rim),
/// and a thin plate stands between the corner and the room. Both strategies give finite images, and maps stay within
/// a stated PSNR of rays on the indirect-only image (bound 35 dB, the thesis's lower range).
#[test]
fn vpls_near_walls_and_on_the_paraboloid_rim() {
    let mut s = floor_scene(2.0, Vec3::splat(0.6), 3.0, 80.0, vec![], 64, 64);
    let m = s.add_material(Material::matte("wall", Vec3::splat(0.7)));
    s.push_quad(
        [vec3(-2.0, 0.0, -2.0), vec3(2.0, 0.0, -2.0), vec3(2.0, 2.5, -2.0), vec3(-2.0, 2.5, -2.0)],
        m,
    );
    s.push_quad(
        [vec3(-2.0, 0.0, -2.0), vec3(-2.0, 2.5, -2.0), vec3(-2.0, 2.5, 2.0), vec3(-2.0, 0.0, 2.0)],
        m,
    );
    // A thin upright plate (a single quad, zero thickness) near the corner: VPLs on both sides
    // of it, and receivers in its shadow.
    s.push_quad(
        [vec3(-1.9, 0.0, -1.0), vec3(-0.5, 0.0, -1.0), vec3(-0.5, 0.6, -1.0), vec3(-1.9, 0.6, -1.0)],
        m,
    );
    s.lights =
        vec![PointLight { position: vec3(-1.98, 0.02, -1.98), intensity: Vec3::splat(3.0), spot: None }];
    s.camera = Some(Camera::look_at(vec3(1.5, 2.2, 1.8), vec3(-1.0, 0.5, -1.0), Vec3::Y, 70.0));
    s.validate().unwrap();
    let (rays, _) = indirect_only(&s, options(Indirect::Rays, 200, 0.01));
    let (maps, f) = indirect_only(&s, options(Indirect::Maps, 200, 0.01));
    assert!(f.stats.vpls > 100);
    assert!(rays.iter().chain(&maps).all(|p| p.is_finite() && p.min_element() >= 0.0));
    let mean = |v: &[Vec3]| v.iter().map(|p| p.x).sum::<f32>() / v.len() as f32;
    eprintln!("near walls: mean indirect {} (rays) {} (maps)", mean(&rays), mean(&maps));
    assert!(mean(&rays) > 0.01, "the test needs visible indirect light");
    let film = |px: Vec<Vec3>| hyrt::film::Film { width: 64, height: 64, pixels: px };
    let psnr =
        compare(&DisplayImage::from_film(&film(rays), 4.0), &DisplayImage::from_film(&film(maps), 4.0))
            .unwrap()
            .psnr_db;
    eprintln!("near walls: indirect only, maps vs rays {psnr:.2} dB");
    assert!(psnr >= 35.0, "{psnr:.2} dB");
}

/// Interleaved sampling: with `k x k` interleaving each pixel evaluates 1/k^2 of the VPLs (so
/// `k^2` times fewer VPL shadow rays or lookups), and the geometry-aware filter keeps the image
/// within a stated PSNR of the all-VPL one of the same strategy (measured in the message), for
/// rays and maps alike.
#[test]
fn interleaved_sampling_trades_vpl_evaluations_for_filtered_noise() {
    let mut s = hyrt::scene::load("cornell").unwrap();
    s.settings.width = 160;
    s.settings.height = 160;
    s.settings.max_depth = 0;
    let with_in = |s: &Scene, ind, k| {
        let mut o = options(ind, 128, 0.01);
        o.indirect_opts.interleave = k;
        render(s, o)
    };
    let with = |ind, k| with_in(&s, ind, k);
    let all = with(Indirect::Rays, 1);
    let all_maps = with(Indirect::Maps, 1);
    let shown = |f: &Frame| DisplayImage::from_film(&f.film, 1.0);
    for (k, bound) in [(2u32, 35.0), (4, 30.0)] {
        let f = with(Indirect::Rays, k);
        let ratio = f.stats.rays.vpl_shadow as f64 / all.stats.rays.vpl_shadow as f64;
        let psnr = compare(&shown(&all), &shown(&f)).unwrap().psnr_db;
        let maps = with(Indirect::Maps, k);
        let psnr_maps = compare(&shown(&all_maps), &shown(&maps)).unwrap().psnr_db;
        let pairs = maps.stats.vpl_pairs as f64 / all_maps.stats.vpl_pairs as f64;
        assert!((pairs - 1.0 / (k * k) as f64).abs() <= 0.1 / (k * k) as f64, "k {k}: pair ratio {pairs}");
        eprintln!(
            "k {k}: VPL rays x{ratio:.4}, PSNR vs all VPLs {psnr:.2} dB (rays) {psnr_maps:.2} dB (maps)"
        );
        let expect = 1.0 / (k * k) as f64;
        assert!((ratio - expect).abs() <= 0.1 * expect, "k {k}: ray ratio {ratio}");
        assert!(psnr >= bound && psnr_maps >= bound - 1.0, "k {k}: {psnr:.2} / {psnr_maps:.2} dB");
    }
    // Mirror paths use their pixel's subset too: with the built-in mirror, k = 4 still casts
    // about 1/16 of the VPL rays.
    let mut mirrors = s.clone();
    mirrors.settings.max_depth = 5;
    let (all, k4) = (with_in(&mirrors, Indirect::Rays, 1), with_in(&mirrors, Indirect::Rays, 4));
    let ratio = k4.stats.rays.vpl_shadow as f64 / all.stats.rays.vpl_shadow as f64;
    assert!((ratio - 1.0 / 16.0).abs() <= 0.1 / 16.0, "with mirror paths: ray ratio {ratio}");
}

/// VPLs on thin geometry: a light above a stack of venetian-blind slats (1 mm thick, 2 cm
/// apart) puts many VPLs on the slats, whose maps must see the neighbouring slats; the room
/// below gets light only through the gaps. Maps stay within a stated PSNR of rays on the
/// indirect-only image (bound 30 dB, measured in the message).
#[test]
fn vpls_on_thin_slats() {
    let mut s = floor_scene(2.0, Vec3::splat(0.6), 3.0, 70.0, vec![], 64, 64);
    let m = s.add_material(Material::matte("slat", Vec3::splat(0.8)));
    for i in 0..20 {
        let z = -1.0 + 0.1 * i as f32;
        push_box(&mut s, vec3(-1.0, 1.2, z), vec3(1.0, 1.201, z + 0.08), m);
    }
    // A wall behind the slats: the slats' VPLs light it past their neighbours.
    let wall = s.add_material(Material::matte("wall", Vec3::splat(0.7)));
    s.push_quad(
        [vec3(-2.0, 0.0, -1.2), vec3(2.0, 0.0, -1.2), vec3(2.0, 2.5, -1.2), vec3(-2.0, 2.5, -1.2)],
        wall,
    );
    s.lights = vec![PointLight { position: vec3(0.3, 1.8, 0.2), intensity: Vec3::splat(3.0), spot: None }];
    s.camera = Some(Camera::look_at(vec3(0.8, 1.5, 2.5), vec3(0.0, 1.0, -1.2), Vec3::Y, 60.0));
    s.validate().unwrap();
    let (rays, f) = indirect_only(&s, options(Indirect::Rays, 200, 0.01));
    let (maps, _) = indirect_only(&s, options(Indirect::Maps, 200, 0.01));
    assert!(f.stats.vpls > 30, "{} VPLs", f.stats.vpls);
    let mean = |v: &[Vec3]| v.iter().map(|p| p.x).sum::<f32>() / v.len() as f32;
    assert!(mean(&rays) > 1e-3, "the test needs visible indirect light");
    let film = |px: Vec<Vec3>| hyrt::film::Film { width: 64, height: 64, pixels: px };
    let e = 0.5 / mean(&rays);
    let psnr = compare(&DisplayImage::from_film(&film(rays), e), &DisplayImage::from_film(&film(maps), e))
        .unwrap()
        .psnr_db;
    eprintln!("thin slats: indirect only, maps vs rays {psnr:.2} dB");
    assert!(psnr >= 30.0, "{psnr:.2} dB");
}
