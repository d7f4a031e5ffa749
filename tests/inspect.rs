//! The buffers kept for inspection (`Options::keep_buffers`, what the inspector shows) agree
//! with the frame's counters, and keeping them changes nothing in the image.

mod common;

use hyrt::render::{Indirect, Options, Renderer, shadows::BorderRay};
use hyrt_tracer::RayCounts;

fn scene(max_depth: u32) -> hyrt::scene::Scene {
    let mut s = hyrt::scene::load(&common::root().join("scenes/cornell-bunny-mirror.toml").to_string_lossy())
        .expect("thesis scene");
    s.settings.width = 96;
    s.settings.height = 72;
    s.settings.max_depth = max_depth;
    s
}

/// Small maps keep the tests quick; the buffers do not depend on the resolution.
fn kept(mut o: Options) -> Options {
    o.keep_buffers = true;
    o.shadow.map.resolution = 512;
    o
}

/// Per-pixel ray counts sum to the frame's rays (minus the VPL path rays, which belong to no
/// pixel), for every strategy, with mirrors and VPLs; `--check-visibility`'s extra rays are in
/// neither.
#[test]
fn pixel_rays_sum_to_the_frame_counts() {
    let s = scene(3);
    let mut vpl_rays = Options::hybrid();
    vpl_rays.indirect = Indirect::Rays;
    vpl_rays.indirect_opts.vpl.paths = 6;
    let mut checked = Options::hybrid();
    checked.check_visibility = true;
    for (name, o) in [
        ("reference", Options::reference()),
        ("hybrid", Options::hybrid()),
        ("hybrid + VPL rays", vpl_rays),
        ("checked", checked),
    ] {
        let f = Renderer::new(&s, kept(o)).render(&|| {});
        let px = f.pixel_rays.as_ref().expect("kept");
        assert_eq!(px.len(), 96 * 72);
        let sum: RayCounts = px.iter().copied().sum();
        let mut frame = f.stats.rays;
        frame.vpl_path = 0;
        assert_eq!(sum, frame, "{name}");
        assert!(sum.total() > 0, "{name}");
        assert!(f.gbuffer.as_ref().is_some_and(|g| g.len() == px.len()));
    }
}

/// The per-light ray outcome: every undecided pixel cast one ray, answered by the hint or by a
/// traversal, and their totals are the frame's hint hits and traversals (no mirrors: camera
/// hits only); the border before dilation lies inside the undecided pixels, and equals them
/// without dilation. The cached maps drew the faces the stats report. A map-space border's ray
/// that its hint answered tested the hint the inspector shows (the classify pass's lookup).
#[test]
fn shadow_ray_outcomes_and_borders_match_the_stats() {
    let s = scene(0);
    for dilate in [0, 2] {
        let mut o = kept(Options::hybrid());
        o.shadow.dilate = dilate;
        let r = Renderer::new(&s, o);
        let f = r.render(&|| {});
        let b = f.shadows.as_ref().expect("kept");
        let (mut hints, mut traversals) = (0, 0);
        for (l, st) in f.stats.lights.iter().enumerate() {
            let rays = &b.ray[l];
            let cast = rays.iter().filter(|&&k| k != BorderRay::None).count() as u64;
            assert_eq!(cast, st.undecided, "light {l}");
            for (i, &k) in rays.iter().enumerate() {
                assert_eq!(
                    k != BorderRay::None,
                    b.undecided[l][i] && b.occ[l][i] != hyrt_shadowmap::classify::Decision::NotNeeded
                );
            }
            for (i, &k) in rays.iter().enumerate() {
                if k == BorderRay::Hint && b.map_border[l][i] {
                    assert_ne!(
                        b.hint[l][i],
                        hyrt_shadowmap::EMPTY,
                        "light {l} pixel {i}: answered by no hint"
                    );
                }
            }
            hints += rays.iter().filter(|&&k| k == BorderRay::Hint).count() as u64;
            traversals += rays.iter().filter(|&&k| k == BorderRay::Traversal).count() as u64;
            let border = &b.border[l];
            assert!(border.iter().zip(&b.undecided[l]).all(|(b, u)| !b || *u), "light {l}");
            if dilate == 0 {
                let undecided: Vec<bool> = b.undecided[l]
                    .iter()
                    .zip(&b.occ[l])
                    .map(|(u, o)| *u && *o != hyrt_shadowmap::classify::Decision::NotNeeded)
                    .collect();
                assert_eq!(border, &undecided, "light {l}");
            }
            let map = r.light_map(l).expect("built");
            assert_eq!(map.faces_drawn().iter().filter(|&&d| d).count() as u32, st.faces_drawn);
        }
        assert_eq!((hints, traversals), (f.stats.rays.shadow_hint_hits, f.stats.rays.shadow_traversals()));
        assert!(hints > 0 && traversals > 0);
    }
}

/// Keeping the buffers is observation only: the same image, the same counts.
#[test]
fn keeping_buffers_changes_nothing() {
    let s = scene(2);
    for mut o in [Options::reference(), Options::hybrid()] {
        o.shadow.map.resolution = 512;
        let a = Renderer::new(&s, o).render(&|| {});
        let b = Renderer::new(&s, kept(o)).render(&|| {});
        assert_eq!(a.film, b.film);
        assert_eq!(a.stats.rays, b.stats.rays);
        assert!(a.pixel_rays.is_none() && a.gbuffer.is_none());
    }
}
