//! Paged light maps (`LightMaps::Paged`, the default): accuracy where whole maps run out of
//! resolution (a far light and thin occluders), memory per light on the thesis scenes and with
//! 64 lights, determinism across thread counts, and reuse of pages as the camera and a light
//! move. The work is counted (pages, bytes), never timed; run times are printed only
//! (`--nocapture`).

mod common;

use std::time::Instant;

use common::*;
use glam::{Vec3, vec3};
use hyrt::{
    metrics,
    render::{Cache, Frame, LightMaps, Options, Renderer, Subject},
    scene::{Camera, Material, PointLight, Scene, Settings},
};

/// Side of the ground quad (scene units); the thin occluders are 0.05-0.06 across (0.5-0.6 %
/// of it).
const S: f32 = 10.0;

/// The default budget per light, in bytes (`ShadowOptions::map_budget` counts megabytes of
/// `1 << 20` bytes).
fn map_budget_bytes() -> u64 {
    u64::from(hyrt::render::ShadowOptions::default().map_budget) << 20
}

/// Image size of the far-light scenes: 640x480, the size the thesis scenes are measured at.
const W: u32 = 640;
const H: u32 = 480;

/// Wrong-visibility bound of the thesis scenes in tests/shadows.rs, kept here: <= 0.05 % of the
/// pixels may have a light whose decision a plain shadow ray contradicts.
const MAX_WRONG_FRACTION: f64 = 0.0005;

/// PSNR bound against the reference: 50 dB, the golden images' bound (tests/golden.rs), at
/// which one pixel going from black to white at 160x120 already fails; at 640x480 it allows
/// about four such pixels, or rounding noise everywhere.
const MIN_PSNR_DB: f64 = 50.0;

fn light(p: Vec3, i: f32) -> PointLight {
    PointLight { position: p, intensity: Vec3::splat(i), spot: None }
}

/// From the scene's centre towards the far light: a low sun, 25 degrees above the ground,
/// oblique to the rails (which run along x and z), so that every rail casts a long thin shadow
/// across the ground.
fn sun_direction() -> Vec3 {
    vec3(0.8, 0.45, -0.55).normalize()
}

/// A box from `lo` to `hi` (helper for readability).
fn bar(s: &mut Scene, lo: [f32; 3], hi: [f32; 3], m: u32) {
    push_box(s, Vec3::from(lo), Vec3::from(hi), m);
}

/// A chair frame of 0.05-thick bars at `(x, z)`: four legs 0.45 high, a seat frame, a back of
/// two uprights and a top rail.
fn chair(s: &mut Scene, x: f32, z: f32, m: u32) {
    let t = 0.05;
    let (w, seat, back) = (0.45, 0.45, 0.95);
    for (dx, dz) in [(0.0, 0.0), (w - t, 0.0), (0.0, w - t), (w - t, w - t)] {
        bar(s, [x + dx, 0.0, z + dz], [x + dx + t, seat, z + dz + t], m);
    }
    // Seat frame: rails along x and along z, on top of the legs.
    bar(s, [x, seat, z], [x + w, seat + t, z + t], m);
    bar(s, [x, seat, z + w - t], [x + w, seat + t, z + w], m);
    bar(s, [x, seat, z + t], [x + t, seat + t, z + w - t], m);
    bar(s, [x + w - t, seat, z + t], [x + w, seat + t, z + w - t], m);
    // Back: two uprights on the far legs and a top rail.
    bar(s, [x, seat + t, z + w - t], [x + t, back, z + w], m);
    bar(s, [x + w - t, seat + t, z + w - t], [x + w, back, z + w], m);
    bar(s, [x + t, back - t, z + w - t], [x + w - t, back, z + w], m);
}

/// The far-light scene: a ground quad of side `S` at y = 0; a fence of two 0.06-thick rails
/// 7 units long on posts; two chair frames; three solid blocks; a 0.04-thick rod leaning over
/// the ground. One point light `factor * S` away from the centre along [`sun_direction`], with
/// its intensity scaled by the distance squared so that the ground's radiance is the same
/// (about 0.6) for every `factor`. Camera above one edge, looking over the ground, at `w x h`.
fn far_light_scene(factor: f32, w: u32, h: u32) -> Scene {
    let mut s = Scene::new(&format!("far light {factor} S"));
    let ground = s.add_material(Material::matte("ground", Vec3::splat(0.6)));
    let metal = s.add_material(Material::matte("rails", vec3(0.5, 0.45, 0.4)));
    let block = s.add_material(Material::matte("blocks", vec3(0.4, 0.5, 0.6)));
    let h2 = S / 2.0;
    s.push_quad([vec3(-h2, 0.0, -h2), vec3(-h2, 0.0, h2), vec3(h2, 0.0, h2), vec3(h2, 0.0, -h2)], ground);
    // Fence along x at z = 1: posts every 1.4 units, rails at 0.4 and 0.8.
    let t = 0.06;
    for i in 0..6 {
        let x = -3.5 + 1.4 * i as f32;
        bar(&mut s, [x, 0.0, 1.0], [x + t, 0.9, 1.0 + t], metal);
    }
    for y in [0.4, 0.8] {
        bar(&mut s, [-3.5, y, 1.0], [3.5 + t, y + t, 1.0 + t], metal);
    }
    // A second fence along z at x = -3, rails only on two posts (long free spans).
    for z in [-4.0, -0.5] {
        bar(&mut s, [-3.0, 0.0, z], [-3.0 + t, 0.7, z + t], metal);
    }
    bar(&mut s, [-3.0, 0.65, -4.0], [-3.0 + t, 0.65 + t, -0.5 + t], metal);
    chair(&mut s, 1.0, -1.5, metal);
    chair(&mut s, -1.2, 2.6, metal);
    // Bigger blocks.
    bar(&mut s, [2.2, 0.0, 2.0], [3.2, 1.0, 3.0], block);
    bar(&mut s, [-1.5, 0.0, -3.5], [-0.7, 1.5, -2.7], block);
    bar(&mut s, [3.0, 0.0, -3.8], [3.6, 0.6, -2.2], block);
    // A thin rod (0.04 square) leaning from the ground up to a block's top edge: a shadow that
    // narrows to nothing where the rod touches the ground.
    let (a, b) = (vec3(0.5, 0.0, 3.8), vec3(2.2, 0.95, 2.5));
    let side = (b - a).cross(Vec3::Y).normalize() * 0.02;
    let up = side.cross(b - a).normalize() * 0.02;
    let c = [a - side - up, a + side - up, a + side + up, a - side + up];
    let d = c.map(|p| p + (b - a));
    for (i, j) in [(0, 1), (1, 2), (2, 3), (3, 0)] {
        s.push_quad([c[i], c[j], d[j], d[i]], metal);
    }
    s.push_quad([c[3], c[2], c[1], c[0]], metal);
    s.push_quad([d[0], d[1], d[2], d[3]], metal);

    let dist = factor * S;
    // The ground's radiance is kd / pi * I cos(theta) / dist^2: 0.6 / pi * 7.5 * 0.42 = 0.6.
    s.lights = vec![light(sun_direction() * dist, 7.5 * dist * dist)];
    s.camera = Some(Camera::look_at(vec3(0.5, 5.5, 8.5), vec3(0.0, 0.0, 0.3), Vec3::Y, 55.0));
    s.settings = Settings { width: w, height: h, max_depth: 5, exposure: 1.0 };
    s.validate().expect("valid test scene");
    s
}

/// A hybrid frame's accuracy against the reference.
#[derive(Debug)]
struct Accuracy {
    psnr_db: f64,
    /// (pixel, light) pairs whose decision (map, hint or traversal) a plain ray contradicts.
    wrong_pairs: u64,
    /// Pixels with at least one such light.
    wrong_pixels: u64,
    pixels: u64,
}

impl Accuracy {
    fn wrong_fraction(&self) -> f64 {
        self.wrong_pixels as f64 / self.pixels as f64
    }
}

/// `opts` with the visibility check and the buffers kept (neither changes the image).
fn checked(mut opts: Options) -> Options {
    opts.check_visibility = true;
    opts.keep_buffers = true;
    opts
}

/// The accuracy of `f` (rendered with [`checked`] options) against `reference`.
fn accuracy(s: &Scene, reference: &Frame, f: &Frame) -> Accuracy {
    let psnr_db = metrics::psnr(s, &reference.film, &f.film).expect("same size");
    let wrong_pairs = f.stats.lights.iter().map(|l| l.wrong_total().expect("checked")).sum();
    let b = f.shadows.as_ref().expect("kept buffers");
    let n = f.film.pixels.len();
    let wrong_pixels =
        (0..n).filter(|&i| b.wrong.iter().any(|w| w.get(i).copied().unwrap_or(false))).count() as u64;
    Accuracy { psnr_db, wrong_pairs, wrong_pixels, pixels: n as u64 }
}

/// Writes `reference.png`, and per frame `<name>.png` and `<name>.wrong.png` (its wrong-visibility
/// pixels in red over the dimmed image; with kept buffers) to `target/test-output/paged_maps/<test>`.
fn write_images(test: &str, s: &Scene, reference: &Frame, frames: &[(&str, &Frame)]) -> std::path::PathBuf {
    let dir = out_dir(&format!("paged_maps/{test}"));
    let e = s.settings.exposure;
    reference.film.write_png(&dir.join("reference.png"), e).unwrap();
    for (name, f) in frames {
        f.film.write_png(&dir.join(format!("{name}.png")), e).unwrap();
        if let Some(b) = &f.shadows {
            let mut film = f.film.clone();
            for (i, p) in film.pixels.iter_mut().enumerate() {
                let wrong = b.wrong.iter().any(|w| w.get(i).copied().unwrap_or(false));
                *p = if wrong { vec3(1.0, 0.0, 0.0) } else { *p * 0.3 };
            }
            film.write_png(&dir.join(format!("{name}.wrong.png")), e).unwrap();
        }
    }
    dir
}

fn whole() -> Options {
    let mut o = Options::hybrid();
    o.shadow.light_maps = LightMaps::Whole;
    o
}

/// Test 1: the far light. Returns (paged, whole) accuracy.
fn far_light(factor: f32) -> (Accuracy, Accuracy) {
    let t = Instant::now();
    let s = far_light_scene(factor, W, H);
    let reference = render(&s, Options::reference());
    let t_ref = t.elapsed();
    let t = Instant::now();
    let paged = render(&s, checked(Options::hybrid()));
    let t_paged = t.elapsed();
    let a = accuracy(&s, &reference, &paged);
    let t = Instant::now();
    let whole_f = render(&s, checked(whole()));
    let t_whole = t.elapsed();
    let b = accuracy(&s, &reference, &whole_f);
    let (lp, lw) = (paged.stats.lights[0], whole_f.stats.lights[0]);
    let dir = write_images(
        &format!("far-light-{factor}"),
        &s,
        &reference,
        &[("paged", &paged), ("whole", &whole_f)],
    );
    eprintln!(
        "far light {factor} S, {W}x{H} (images in {}):\n  paged: PSNR {:.2} dB, wrong {} pixels ({:.4} %), {} pairs \
         (map {:?}, hint {:?}, traversal {:?}); shadow rays {}; \
         pages used {}, levels ..={}, level_cap {}, {} bytes; lit {} shadowed {} undecided {}\n  \
         whole: PSNR {:.2} dB, wrong {} pixels ({:.4} %), {} pairs; shadow rays {}; {} bytes; lit {} shadowed {} \
         undecided {}\n  reference shadow rays {}; run times (checked renders, debug info only): reference {:?}, \
         paged {:?}, whole {:?}",
        dir.display(),
        a.psnr_db,
        a.wrong_pixels,
        100.0 * a.wrong_fraction(),
        a.wrong_pairs,
        lp.wrong,
        lp.wrong_hint,
        lp.wrong_traversal,
        paged.stats.rays.shadow,
        lp.pages_used,
        lp.finest_level,
        lp.level_cap,
        lp.map_bytes,
        lp.lit,
        lp.shadowed,
        lp.undecided,
        b.psnr_db,
        b.wrong_pixels,
        100.0 * b.wrong_fraction(),
        b.wrong_pairs,
        whole_f.stats.rays.shadow,
        lw.map_bytes,
        lw.lit,
        lw.shadowed,
        lw.undecided,
        reference.stats.rays.shadow,
        t_ref,
        t_paged,
        t_whole,
    );
    // The scene must be a test of thin shadows at all: most of the ground lit, and shadows
    // covering a real part of the image (the rails' and blocks' shadows).
    assert!(lp.lit > (W * H / 4) as u64, "the ground should be mostly lit: {lp:?}");
    assert!(lp.shadowed + lp.undecided > 2_000, "visible shadows: {lp:?}");
    (a, b)
}

/// The bounds of test 1 on the paged maps' frame.
fn assert_bounds(factor: f32, a: &Accuracy) {
    assert!(
        a.psnr_db >= MIN_PSNR_DB,
        "far light {factor} S, paged maps: PSNR {:.2} dB < {MIN_PSNR_DB}",
        a.psnr_db
    );
    assert!(
        a.wrong_fraction() <= MAX_WRONG_FRACTION,
        "far light {factor} S, paged maps: {} wrong-visibility pixels ({:.4} %) > {} %",
        a.wrong_pixels,
        100.0 * a.wrong_fraction(),
        100.0 * MAX_WRONG_FRACTION
    );
}

/// A light 100 S away: paged maps match the reference (PSNR >= 50 dB, <= 0.05 % wrong pixels);
/// whole maps (2048^2 per face) are printed for contrast.
#[test]
fn far_light_100_s_thin_occluders() {
    let (paged, _) = far_light(100.0);
    assert_bounds(100.0, &paged);
}

/// A light 1000 S away: the whole scene falls within a few texels of a whole 2048^2 map (the
/// ground subtends about 1 / 1000 rad, a texel about 1 / 1024 rad), while paged maps pick the
/// level the receivers need. The same bounds as at 100 S. (Until the maps' depth-tie window
/// was narrowed to a few ulps, about 150 pixels at the foot of each post and block corner were
/// wrong: a window of `2^-16 r`, 0.15 units here, tied the posts' bases with the ground, and
/// the ground's smaller id won those texels.)
#[test]
fn far_light_1000_s_thin_occluders() {
    let (paged, whole) = far_light(1000.0);
    assert_bounds(1000.0, &paged);
    // The contrast, robust by construction: a whole map's texel (2 / 2048 rad at a face's
    // centre) is 10 units wide at 10,000 units, the whole ground: every shadow of the scene is
    // below its resolution, so whole maps get more pixels wrong than paged ones.
    assert!(
        whole.wrong_pixels > paged.wrong_pixels && whole.psnr_db < paged.psnr_db,
        "whole maps should be worse at 1000 S: whole {whole:?}, paged {paged:?}"
    );
}

/// One hybrid frame of `file` (scenes/), at its own 640x480: every light's map within the
/// budget. The budget is the default `map_budget`; the pages are sized before drawing,
/// so the map's bytes (pages plus its page table) staying under it is what is tested.
fn thesis_memory(file: &str) {
    let t = Instant::now();
    let s = hyrt::scene::load(root().join("scenes").join(file).to_str().unwrap()).unwrap();
    let loaded = t.elapsed();
    let t = Instant::now();
    let f = render(&s, Options::hybrid());
    let rendered = t.elapsed();
    let bytes: Vec<u64> = f.stats.lights.iter().map(|l| l.map_bytes).collect();
    eprintln!(
        "{file}: {}x{}, load {loaded:?}, hybrid frame {rendered:?}; per light: map bytes {bytes:?}, pages {:?}, \
         finest level {:?}, level_cap {:?}; total {:.1} MB",
        s.settings.width,
        s.settings.height,
        f.stats.lights.iter().map(|l| l.pages_held).collect::<Vec<_>>(),
        f.stats.lights.iter().map(|l| l.finest_level).collect::<Vec<_>>(),
        f.stats.lights.iter().map(|l| l.level_cap).collect::<Vec<_>>(),
        bytes.iter().sum::<u64>() as f64 / (1u64 << 20) as f64,
    );
    assert_eq!(bytes.len(), s.lights.len());
    assert!(bytes.iter().any(|&b| b > 0), "{file}: no map was built");
    for (l, &b) in bytes.iter().enumerate() {
        assert!(b <= map_budget_bytes(), "{file}: light {l}'s map holds {b} bytes > the budget");
    }
}

#[test]
fn memory_per_light_cornell_bunny_mirror() {
    thesis_memory("cornell-bunny-mirror.toml");
}

#[test]
fn memory_per_light_office() {
    thesis_memory("office.toml");
}

#[test]
fn memory_per_light_conference() {
    thesis_memory("conference.toml");
}

/// 64 lights in the conference room (scenes/conference-64.toml): each map within the default
/// budget, all of them within 64 budgets (the sum bound follows from the per-light one and is
/// asserted for plain reporting), and the image within 50 dB of the
/// reference (64 shadow rays per camera hit). The wrong-visibility pixels are printed, not
/// bounded: with 64 lights a pixel has 64 decisions that can go wrong, and the 0.05 % bound of
/// the four-light scenes was not set for that. The hybrid is rendered with the check, which
/// casts a ray per map decision: its time is not the hybrid's (about 20 s here, of the test's
/// 25-30 s on 2 cores).
#[test]
fn sixty_four_lights_conference() {
    let t = Instant::now();
    let s = hyrt::scene::load(root().join("scenes/conference-64.toml").to_str().unwrap()).unwrap();
    assert_eq!(s.lights.len(), 64);
    let loaded = t.elapsed();
    let t = Instant::now();
    let f = render(&s, checked(Options::hybrid()));
    let hybrid = t.elapsed();
    let t = Instant::now();
    let reference = render(&s, Options::reference());
    let reference_t = t.elapsed();
    let a = accuracy(&s, &reference, &f);
    let bytes: Vec<u64> = f.stats.lights.iter().map(|l| l.map_bytes).collect();
    let total: u64 = bytes.iter().sum();
    eprintln!(
        "conference-64: load {loaded:?}, hybrid frame (checked) {hybrid:?}, reference {reference_t:?}; \
         PSNR {:.2} dB, wrong {} pixels ({:.4} %), {} pairs; shadow rays {} of {}; map bytes total {:.1} MB, \
         largest {:.2} MB, pages held {}, finest levels {:?}, level_cap {:?}",
        a.psnr_db,
        a.wrong_pixels,
        100.0 * a.wrong_fraction(),
        a.wrong_pairs,
        f.stats.rays.shadow,
        reference.stats.rays.shadow,
        total as f64 / (1u64 << 20) as f64,
        *bytes.iter().max().unwrap() as f64 / (1u64 << 20) as f64,
        f.stats.lights.iter().map(|l| u64::from(l.pages_held)).sum::<u64>(),
        f.stats.lights.iter().map(|l| l.finest_level).collect::<Vec<_>>(),
        f.stats.lights.iter().map(|l| l.level_cap).collect::<Vec<_>>(),
    );
    for (l, &b) in bytes.iter().enumerate() {
        assert!(b <= map_budget_bytes(), "light {l}'s map holds {b} bytes > the budget");
    }
    assert!(total <= 64 * map_budget_bytes(), "the 64 maps hold {total} bytes > 64 budgets");
    assert!(a.psnr_db >= MIN_PSNR_DB, "conference-64: PSNR {:.2} dB < {MIN_PSNR_DB}", a.psnr_db);

    // One image (`hyrt render`'s horizon of 1 frame): the 64 maps' builds exceed the BVH's
    // build time many times over, and none pays in one frame; every pair is a ray's.
    let mut one = Options::hybrid();
    one.shadow.map_horizon = 1.0;
    let f = render(&s, one);
    assert_eq!(f.stats.maps_built, 0, "{:?}", f.stats.decisions.iter().take(3).collect::<Vec<_>>());
    assert!(
        f.stats.lights.iter().all(|l| l.map_bytes == 0 && l.lit + l.shadowed == 0),
        "{:?}",
        f.stats.lights[0]
    );
    // As many shadow rays as the reference casts, but for the few pixels whose rasterized hit
    // differs from the primary ray's (8 pixels' 64 lights at most).
    let (h, r) = (f.stats.rays.shadow, reference.stats.rays.shadow);
    assert!(h.abs_diff(r) <= 8 * 64, "one image: {h} shadow rays against the reference's {r}");
}

/// The hybrid with paged maps gives the same bytes, rays and page counts with 1 and 2 threads
/// (the far light at 1000 S: the finest levels, pages marked by rows in parallel and merged).
#[test]
fn paged_maps_are_deterministic_across_thread_counts() {
    let s = far_light_scene(1000.0, 320, 240);
    let run = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| render(&s, Options::hybrid()))
    };
    let (a, b) = (run(1), run(2));
    assert!(a.stats.lights[0].pages_used > 0, "{:?}", a.stats.lights);
    let bits =
        |f: &Frame| f.film.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    assert!(bits(&a) == bits(&b), "the films differ between 1 and 2 threads");
    assert_eq!(a.stats.rays, b.stats.rays);
    assert_eq!(a.stats.lights, b.stats.lights);
}

/// A renderer's second frame after a small camera move draws only the pages it newly needs
/// (fewer than it uses: the others are reused), and its image equals a fresh renderer's of the
/// new view, byte for byte; a moved light draws all its pages again, the other light none.
#[test]
fn moving_camera_reuses_pages_and_a_moved_light_redraws_its_own() {
    // The far light at 100 S and a near one above the ground, on the far-light scene.
    let mut s = far_light_scene(100.0, 320, 240);
    s.lights.push(light(vec3(-2.0, 4.0, 3.0), 10.0));
    let near = s.camera.unwrap();
    // A little: 0.3 units sideways and 0.2 closer, about 3 % of the camera's distance.
    let moved = Camera { eye: near.eye + vec3(0.3, -0.1, -0.2), ..near };
    let opts = Options::hybrid();

    let mut r = Renderer::new(&s, opts);
    let first = r.render(&|| {});
    for (l, st) in first.stats.lights.iter().enumerate() {
        assert!(st.pages_used > 0 && st.pages_drawn == st.pages_used, "first frame, light {l}: {st:?}");
    }
    r.set_camera(&moved);
    let second = r.render(&|| {});
    eprintln!(
        "moved camera: first frame pages (used, drawn, held) {:?}, second {:?}; decisions {:#?}",
        first.stats.lights.iter().map(|l| (l.pages_used, l.pages_drawn, l.pages_held)).collect::<Vec<_>>(),
        second.stats.lights.iter().map(|l| (l.pages_used, l.pages_drawn, l.pages_held)).collect::<Vec<_>>(),
        second.stats.decisions.iter().filter(|d| matches!(d.what, Subject::Light(_))).collect::<Vec<_>>(),
    );
    for (l, st) in second.stats.lights.iter().enumerate() {
        assert!(st.pages_used > 0, "light {l}: {st:?}");
        assert!(st.pages_drawn < st.pages_used, "light {l}: no page reused after a small move: {st:?}");
        let d = second
            .stats
            .decisions
            .iter()
            .find(|d| d.what == Subject::Light(l))
            .expect("a decision per light");
        assert!(
            matches!(d.cache, Cache::Extended | Cache::Reused),
            "light {l}: the map should be extended or reused: {d:?}"
        );
        assert_eq!(d.cache == Cache::Reused, st.pages_drawn == 0, "light {l}: {d:?} but {st:?}");
    }
    let mut fresh_scene = s.clone();
    fresh_scene.camera = Some(moved);
    let fresh = render(&fresh_scene, opts);
    let bits =
        |f: &Frame| f.film.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    assert!(bits(&second) == bits(&fresh), "the moved camera's image differs from a fresh renderer's");

    // Move the near light a little: its pages are all drawn again, the far light's none.
    let mut l1 = r.lights()[1];
    l1.position += vec3(0.2, 0.0, -0.1);
    assert_eq!(r.set_light(1, l1), vec!["the light's map", "the light's VPLs and their maps"]);
    let third = r.render(&|| {});
    let (far, nearl) = (third.stats.lights[0], third.stats.lights[1]);
    eprintln!("moved light: far light {far:?}\n  moved light {nearl:?}");
    assert!(nearl.pages_used > 0 && nearl.pages_drawn == nearl.pages_used, "the moved light: {nearl:?}");
    assert_eq!(far.pages_drawn, 0, "the unmoved light drew pages: {far:?}");
    assert!(far.pages_used > 0, "{far:?}");
    let d = |l: usize| {
        third.stats.decisions.iter().find(|d| d.what == Subject::Light(l)).expect("decision").clone()
    };
    assert_eq!(d(0).cache, Cache::Reused, "{:?}", d(0));
    assert_eq!(d(1).cache, Cache::Built, "{:?}", d(1));
}
