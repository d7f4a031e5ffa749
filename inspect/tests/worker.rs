//! The worker and the pixel picking, without a window: frames, caches kept across knob changes,
//! and what a picked pixel shows against the frame's own buffers.

use std::time::{Duration, Instant};

use hyrt::render::{Indirect, Options, shadows::BorderRay};
use hyrt_inspect::{
    Setup, navigate, pick,
    worker::{Command, Comparison, Loaded, Pose, Render, Rendered, Reply, Worker},
};
use hyrt_shadowmap::classify::Decision;

fn setup(options: Options) -> Setup {
    Setup {
        scene: "cornell".into(),
        size: Some((96, 72)),
        max_depth: None,
        camera: None,
        knobs: Default::default(),
        options: Some(options),
    }
}

fn small_hybrid() -> Options {
    let mut o = Options::hybrid();
    o.shadow.map.resolution = 256;
    o.check_visibility = true;
    o
}

/// The next reply, waiting at most a minute.
fn next(w: &Worker) -> Reply {
    let start = Instant::now();
    loop {
        if let Some(r) = w.try_recv() {
            return r;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "the worker did not answer");
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn rendered(w: &Worker) -> Box<Rendered> {
    match next(w) {
        Reply::Rendered(r) => r,
        Reply::Failed(e) => panic!("failed: {e}"),
        _ => panic!("expected a frame"),
    }
}

/// The scene the worker loaded, and its first full frame (its own options and pose, no
/// reference).
fn first_full_frame(w: &Worker) -> (Box<Loaded>, Box<Rendered>) {
    let Reply::Loaded(loaded) = next(w) else { panic!("expected the scene") };
    w.send(Command::Render(Render {
        generation: 1,
        options: loaded.options,
        pose: Pose::of(&loaded.scene),
        full: true,
        reference: false,
    }));
    (loaded, rendered(w))
}

/// The reference rendered after frame `generation`.
fn compared(w: &Worker, generation: u64) -> Comparison {
    match next(w) {
        Reply::Compared { generation: g, comparison } => {
            assert_eq!(g, generation);
            *comparison
        }
        _ => panic!("expected the reference"),
    }
}

/// A full frame with its reference.
fn full(generation: u64, options: Options, pose: &Pose) -> Command {
    Command::Render(Render { generation, options, pose: pose.clone(), full: true, reference: true })
}

#[test]
fn renders_and_keeps_what_a_change_leaves_valid() {
    let w = Worker::spawn(setup(small_hybrid()), || {});
    let Reply::Loaded(loaded) = next(&w) else { panic!("expected the scene") };
    assert_eq!(loaded.scene.name, "cornell");
    assert_eq!((loaded.scene.settings.width, loaded.scene.settings.height), (96, 72));
    assert_eq!(loaded.options.shadow.map.resolution, 256);
    assert!(loaded.options.keep_buffers);

    let pose = Pose::of(&loaded.scene);
    w.send(full(1, loaded.options, &pose));
    let a = rendered(&w);
    assert_eq!(a.generation, 1);
    assert!(a.full);
    assert!(a.comparison.is_none(), "the reference comes after the frame");
    let ac = compared(&w, 1);
    assert!(ac.rendered);
    assert!(ac.psnr > 30.0, "{}", ac.psnr);
    assert_eq!(a.images.hybrid.size, [96, 72]);
    assert_eq!(ac.error.len(), 96 * 72);
    assert_eq!(a.images.lights.len(), loaded.scene.lights.len());
    assert_eq!(a.images.rays.len(), 6);
    // Paged maps by default.
    assert!(a.maps.iter().all(|m| m.as_ref().is_some_and(|m| m.is_paged())));
    // The first frame built the maps; the frame shown is a second one, with warm caches and
    // the visibility check's verdicts carried over from the first.
    assert!(a.first_frame.as_ref().is_some_and(|f| f.maps_built > 0));
    assert_eq!(a.frame.stats.maps_built, 0);
    assert!(a.wrong_pixels.is_some());
    assert!(a.frame.stats.lights.iter().all(|l| l.wrong.is_some()));
    assert_eq!(a.frame.shadows.as_ref().expect("kept").wrong.len(), loaded.scene.lights.len());
    assert_eq!(ac.reference.stats.rays.primary, 96 * 72);
    assert_eq!(a.frame.stats.rays.primary, 0, "raster visibility");

    // A new bias rebuilds nothing, and the reference is reused.
    let mut o = loaded.options;
    o.shadow.bias = 2.0;
    w.send(full(2, o, &pose));
    let b = rendered(&w);
    assert_eq!(b.generation, 2);
    assert!(b.dropped.is_empty(), "{:?}", b.dropped);
    let bc = b.comparison.as_ref().expect("the reference is reused at once");
    assert!(!bc.rendered);
    assert_eq!(b.frame.stats.maps_built, 0);
    assert!(b.first_frame.is_none(), "nothing was built");
    assert!(b.wrong_pixels.is_some(), "still checked");
    assert_eq!(bc.reference.film, ac.reference.film);

    // Whole maps at a new resolution rebuild the light maps only. Two commands in a row: the
    // second may be coalesced with the first (if it queued while the first rendered), or render
    // after it.
    o.shadow.light_maps = hyrt::options::LightMaps::Whole;
    o.shadow.map.resolution = 128;
    w.send(full(3, o, &pose));
    o.shadow.map.resolution = 512;
    w.send(full(4, o, &pose));
    let mut c = rendered(&w);
    if c.generation == 3 {
        assert_eq!(c.dropped, vec!["light maps"]);
        c = rendered(&w);
    }
    assert_eq!(c.generation, 4);
    assert_eq!(c.dropped, vec!["light maps"]);
    assert!(c.first_frame.as_ref().is_some_and(|f| f.maps_built > 0));
    assert!(c.maps.iter().flatten().all(|m| m.resolution() == 512));

    // Indirect light: VPLs, their maps on request, and a reference with the same VPLs by rays.
    o.indirect = Indirect::Maps;
    o.indirect_opts.vpl.paths = 6;
    o.indirect_opts.map.resolution = 128;
    w.send(full(5, o, &pose));
    w.send(Command::VplMap(1));
    let d = rendered(&w);
    let dc = compared(&w, 5);
    assert!(dc.rendered);
    assert_eq!(dc.reference.options.indirect, Indirect::Rays);
    assert!(dc.reference.stats.rays.vpl_shadow > 0);
    assert!(!d.vpls.is_empty());
    assert_eq!(d.vpl_maps, d.vpls.len());
    let Reply::VplMap(m) = next(&w) else { panic!("expected a VPL map") };
    assert_eq!((m.index, m.resolution), (1, 128));
    assert!(m.image.is_some() && m.range.is_some());
}

#[test]
fn a_missing_scene_is_an_error_reply() {
    let mut s = setup(small_hybrid());
    s.scene = "no-such-dir/missing.toml".into();
    let w = Worker::spawn(s, || {});
    match next(&w) {
        Reply::Failed(e) => assert!(e.contains("missing.toml"), "{e}"),
        _ => panic!("expected a failure"),
    }
}

/// Every picked pixel agrees with the frame's buffers: the G-buffer's triangle, the map's own
/// decision wherever no ray was cast and the footprint is no border (re-classified from the
/// texel the pick reports), a ray exactly where the frame cast one.
#[test]
fn picking_agrees_with_the_frame_buffers() {
    let w = Worker::spawn(setup(small_hybrid()), || {});
    let (loaded, r) = first_full_frame(&w);
    let g = r.frame.gbuffer.as_ref().expect("kept");
    let b = r.frame.shadows.as_ref().expect("kept");
    let (mut decided, mut rays) = (0, 0);
    for y in 0..72 {
        for x in 0..96 {
            let i = (y * 96 + x) as usize;
            let p = pick::pick(&loaded, &r, x, y);
            assert_eq!(p.hit.as_ref().map(|h| h.tri), g[i].map(|h| h.tri), "({x}, {y})");
            assert_eq!(p.rays, Some(r.frame.pixel_rays.as_ref().expect("kept")[i]));
            for lp in &p.lights {
                let l = lp.light;
                assert_eq!(lp.decision, Some(b.occ[l][i]));
                assert_eq!(lp.needed, b.occ[l][i] != Decision::NotNeeded, "({x}, {y}) light {l}");
                let Some(m) = &lp.map else { continue };
                // The frame's border bits hold the borders left to rays: a settled one is a border
                // of the lookup, not of the buffer (and no ray).
                assert!(!b.map_border[l][i] || m.lookup.map_border, "({x}, {y}) light {l}");
                if m.lookup.map_border && !b.map_border[l][i] {
                    assert!(!lp.undecided && lp.ray == BorderRay::None, "({x}, {y}) light {l}");
                }
                assert_eq!(m.lookup.hint, b.hint[l][i]);
                assert_eq!(m.face, m.lookup.face);
                assert_eq!([m.x as u32, m.y as u32], m.lookup.texel);
                if lp.undecided {
                    assert_ne!(lp.ray, BorderRay::None);
                    rays += 1;
                } else {
                    assert_eq!(lp.ray, BorderRay::None);
                    // A border without a ray was settled by testing its triangles alone (the
                    // answer is the ray's, not the texel's).
                    if !m.lookup.map_border {
                        assert_eq!(m.lookup.decision, b.occ[l][i], "({x}, {y}) light {l}");
                    }
                    decided += 1;
                }
            }
        }
    }
    assert!(decided > 1000 && rays > 10, "{decided} {rays}");
}

/// A moving camera gets light frames (the hybrid image alone, maps and VPLs reused); at rest
/// the full frame and the reference of the new view follow. A moved light rebuilds its own
/// map and the VPLs, and the frame says so.
#[test]
fn moves_render_light_frames_and_reuse_the_maps() {
    let mut o = small_hybrid();
    o.indirect = Indirect::Maps;
    o.indirect_opts.vpl.paths = 4;
    o.indirect_opts.map.resolution = 64;
    let w = Worker::spawn(setup(o), || {});
    let Reply::Loaded(loaded) = next(&w) else { panic!("expected the scene") };
    let home = Pose::of(&loaded.scene);
    w.send(full(1, o, &home));
    let a = rendered(&w);
    let ac = compared(&w, 1);

    let mut pose = home.clone();
    pose.camera = navigate::orbit(&home.camera, 0.15, 0.05);
    w.send(Command::Render(Render {
        generation: 2,
        options: o,
        pose: pose.clone(),
        full: false,
        reference: true,
    }));
    let m = rendered(&w);
    assert!(!m.full && m.comparison.is_none(), "a moving frame has no reference");
    assert!(m.frame.gbuffer.is_none() && m.frame.shadows.is_none(), "nor inspection buffers");
    assert!(m.images.lights.is_empty() && m.images.rays.is_empty());
    assert_eq!(m.images.hybrid.size, [96, 72]);
    assert_ne!(m.frame.film, a.frame.film, "the view moved");
    // A small orbit draws only the pages the new view newly needs: no map is built anew.
    let reran = hyrt_inspect::app::reran(&m.frame.stats);
    assert!(!reran.contains("light maps built"), "{reran}");
    assert!(reran.ends_with("VPLs reused, VPL maps reused"), "{reran}");
    assert!(m.frame.stats.rays.vpl_path == 0, "no VPL was traced again");

    w.send(full(3, o, &pose));
    let f = rendered(&w);
    assert!(f.full && f.frame.gbuffer.is_some());
    let fc = compared(&w, 3);
    assert!(fc.rendered, "a new view's reference");
    assert_eq!(fc.reference.pose, pose);
    assert_ne!(fc.reference.film, ac.reference.film);

    let mut lit = pose.clone();
    lit.lights[0].position += glam::Vec3::new(0.05, -0.05, 0.02);
    w.send(Command::Render(Render {
        generation: 4,
        options: o,
        pose: lit.clone(),
        full: true,
        reference: false,
    }));
    let l = rendered(&w);
    assert_eq!(l.dropped, vec!["the light's map", "the light's VPLs and their maps"]);
    let first = l.first_frame.as_ref().expect("the moved light's frame built its map");
    assert_eq!(first.maps_built, 1);
    assert!(
        first
            .decisions
            .iter()
            .any(|d| d.what == hyrt::render::Subject::Light(0) && d.reason.contains("the light moved"))
    );
    assert!(
        first
            .decisions
            .iter()
            .any(|d| d.what == hyrt::render::Subject::Light(1) && d.reason.contains("reused"))
    );
    assert!(l.comparison.is_none(), "not asked for");
    assert_eq!(l.pose, lit);
}

/// A picked pixel on a cut-out names its mask, the alpha there (at least the cut-off: the
/// camera sees only solid points) and the cut-off; a pixel elsewhere names none.
#[test]
fn picking_names_the_cut_out() {
    let mut s = setup(small_hybrid());
    s.scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fence.toml").into();
    let w = Worker::spawn(s, || {});
    let (loaded, r) = first_full_frame(&w);
    let (mut on, mut off) = (0, 0);
    for y in 0..72 {
        for x in 0..96 {
            let Some(h) = pick::pick(&loaded, &r, x, y).hit else { continue };
            match &h.cutout {
                Some((mask, alpha, cutoff)) => {
                    assert!(mask.as_deref().is_some_and(|m| m.ends_with("lattice.png")), "{mask:?}");
                    assert!(alpha >= cutoff, "({x}, {y}): alpha {alpha} below {cutoff}");
                    on += 1;
                }
                None => off += 1,
            }
        }
    }
    assert!(on > 100 && off > 100, "{on} on the lattice, {off} elsewhere");
}
