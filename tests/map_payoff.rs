//! Light maps only where they pay (`ShadowOptions::map_horizon`): a light left to rays is
//! decided exactly as the reference decides it, its pixels shaded as the hybrid shades them, and
//! the choice is the same for any thread count; an infinite horizon (the default) changes
//! nothing. The work is counted (pages, rays), never timed.

mod common;

use common::*;
use hyrt::{
    render::{Frame, Options, Subject},
    scene::Scene,
};

/// The Cornell box with the bunny and a mirror (five lights) at a test's size.
fn cornell(w: u32, h: u32) -> Scene {
    let mut s = hyrt::scene::load(root().join("scenes/cornell-bunny-mirror.toml").to_str().unwrap()).unwrap();
    (s.settings.width, s.settings.height) = (w, h);
    s
}

fn with_horizon(h: f32) -> Options {
    let mut o = Options::hybrid();
    o.shadow.map_horizon = h;
    o.check_visibility = true;
    o
}

fn bits(f: &Frame) -> Vec<u32> {
    f.film.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect()
}

/// With a horizon far too short for any map to pay, every light is decided by rays: no page is
/// drawn, every pair is a ray's, none is wrong, the decisions say why, and the image is, byte
/// for byte, that of raster visibility with shadow rays (`Shadows::Rays`): the same rays, the
/// same shading.
#[test]
fn lights_whose_maps_do_not_pay_are_decided_by_rays_exactly() {
    let s = cornell(160, 120);
    let f = render(&s, with_horizon(1e-6));
    let rays = render(&s, Options { shadows: hyrt::render::Shadows::Rays, ..Options::hybrid() });
    assert_eq!(f.stats.lights.len(), s.lights.len());
    for (l, st) in f.stats.lights.iter().enumerate() {
        assert_eq!((st.pages_used, st.pages_held, st.map_bytes), (0, 0, 0), "light {l}: {st:?}");
        assert!(st.undecided > 0 && st.lit == 0 && st.shadowed == 0, "light {l}: {st:?}");
        assert_eq!(st.wrong_total(), Some(0), "light {l}: a ray-decided pair is wrong: {st:?}");
        let d = f.stats.decisions.iter().find(|d| d.what == Subject::Light(l)).expect("a decision per light");
        assert!(d.run && d.reason.starts_with("no map, shadow rays"), "light {l}: {d:?}");
    }
    let pairs: u64 = f.stats.lights.iter().map(|l| l.undecided).sum();
    assert!(f.stats.rays.shadow >= pairs, "{} shadow rays for {pairs} pairs", f.stats.rays.shadow);
    assert!(bits(&f) == bits(&rays), "the rays-only hybrid differs from raster visibility with shadow rays");
}

/// The choice and the image are the same with 1 and 2 threads (it is made from counts).
#[test]
fn the_choice_is_the_same_for_any_thread_count() {
    let s = cornell(160, 120);
    let run = |n, h| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| render(&s, with_horizon(h)))
    };
    for h in [1e-6, 1.0] {
        let (a, b) = (run(1, h), run(2, h));
        assert!(bits(&a) == bits(&b), "horizon {h}: the films differ between 1 and 2 threads");
        assert_eq!(a.stats.lights, b.stats.lights, "horizon {h}");
        assert_eq!(a.stats.rays, b.stats.rays, "horizon {h}");
    }
}

/// A horizon long enough gives every light its map, and the same bytes as the default's
/// infinite horizon; a renderer whose horizon grows builds the maps it lacked.
#[test]
fn a_long_horizon_builds_every_map_and_changes_nothing() {
    let s = cornell(160, 120);
    let inf = render(&s, Options::hybrid());
    let long = render(&s, Options { check_visibility: false, ..with_horizon(1e9) });
    assert!(inf.stats.lights.iter().all(|l| l.pages_used > 0), "{:?}", inf.stats.lights);
    assert!(bits(&inf) == bits(&long), "a horizon of 1e9 frames changed the image");
    assert_eq!(inf.stats.lights, long.stats.lights);

    let mut r = hyrt::render::Renderer::new(&s, with_horizon(1e-6));
    let first = r.render(&|| {});
    assert_eq!(first.stats.maps_built, 0, "{:?}", first.stats.decisions);
    r.set_options(Options::hybrid());
    let second = r.render(&|| {});
    assert_eq!(second.stats.maps_built as usize, s.lights.len());
    assert!(bits(&second) == bits(&inf), "the grown horizon's frame differs from a fresh renderer's");
}

/// One image of each thesis scene at 640x480 (`hyrt render`'s horizon, 1 frame): the choice the
/// unit costs give, from counts alone. The Cornell box's and the office's maps cost more than
/// the rays they would save in one frame; the conference's four fit in its BVH's build time.
/// (The figures behind it: docs/results.md, "One image: light maps only where they pay".)
#[test]
fn one_image_of_each_thesis_scene_gets_the_maps_that_pay_in_it() {
    for (file, maps) in [("cornell-bunny-mirror.toml", 0), ("office.toml", 0), ("conference.toml", 4)] {
        let s = hyrt::scene::load(root().join("scenes").join(file).to_str().unwrap()).unwrap();
        assert_eq!((s.settings.width, s.settings.height), (640, 480), "{file}");
        let f = render(&s, Options { check_visibility: false, ..with_horizon(1.0) });
        let with_map = f.stats.lights.iter().filter(|l| l.pages_used > 0).count();
        eprintln!("{file}: {with_map} of {} lights with a map; {:#?}", s.lights.len(), f.stats.decisions);
        assert_eq!(with_map, maps, "{file}");
        for (l, st) in f.stats.lights.iter().enumerate() {
            let d =
                f.stats.decisions.iter().find(|d| d.what == Subject::Light(l)).expect("a decision per light");
            let want = if st.pages_used > 0 { "map built: " } else { "no map, shadow rays: " };
            assert!(d.reason.starts_with(want), "{file}, light {l}: {}", d.reason);
            assert!(
                d.reason.contains(&format!("predicted fastest with {maps} of {} maps", s.lights.len())),
                "{}",
                d.reason
            );
        }
    }
}
