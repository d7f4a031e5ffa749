//! Only the effects a scene calls for: each rule of the plan, on a scene where it applies and
//! on one where it does not, asserting both the plan (or the frame's decisions) and the
//! counters that show the work was really skipped (or done).

mod common;

use common::floor_scene;
use glam::{Vec3, vec3};
use hyrt::{
    render::{FrameDecision, Subject},
    render::{Indirect, Options, Pass, Renderer},
    scene::{IndirectSettings, PointLight, Scene},
};

fn cornell(w: u32, h: u32) -> Scene {
    let mut s = hyrt::scene::load("cornell").unwrap();
    s.settings.width = w;
    s.settings.height = h;
    s
}

fn decision(d: &[FrameDecision], what: Subject) -> &FrameDecision {
    d.iter().find(|d| d.what == what).unwrap_or_else(|| panic!("no decision about {what}: {d:?}"))
}

fn light(position: Vec3, intensity: f32) -> PointLight {
    PointLight { position, intensity: Vec3::splat(intensity), spot: None }
}

/// No mirror material: no reflection pass and no specular rays. With one (the built-in
/// Cornell box's mirror): the pass runs and casts rays. `max_depth = 0` turns it off as well.
#[test]
fn reflections_only_with_mirrors() {
    let with = cornell(64, 48);
    let mut without = with.clone();
    for m in &mut without.materials {
        m.mirror = Vec3::ZERO;
    }
    let mut depth0 = with.clone();
    depth0.settings.max_depth = 0;
    for opts in [Options::reference(), Options::hybrid()] {
        let r = Renderer::new(&with, opts);
        assert!(r.plan.runs(Pass::Specular));
        assert!(r.render(&|| {}).stats.rays.specular > 0);
        for (s, why) in [(&without, "mirror reflectance"), (&depth0, "max_depth = 0")] {
            let r = Renderer::new(s, opts);
            assert!(!r.plan.runs(Pass::Specular));
            let skipped =
                r.plan.skipped.iter().find(|d| d.pass == Pass::Specular).expect("listed as skipped");
            assert!(skipped.reason.contains(why), "{skipped:?}");
            let f = r.render(&|| {});
            assert_eq!(f.stats.rays.specular, 0);
            assert!(!f.stats.pass_ms.contains_key(&Pass::Specular));
        }
    }
}

/// No indirect settings: no VPLs, no VPL rays, no VPL decisions. An `[indirect]` table (or
/// options asking for VPLs) makes them.
#[test]
fn vpls_only_when_asked() {
    let plain = cornell(48, 36);
    let r = Renderer::new(&plain, Options::hybrid());
    assert!(!r.plan.runs(Pass::Indirect));
    let f = r.render(&|| {});
    assert_eq!((f.stats.vpls, f.stats.rays.vpl_path, f.stats.rays.vpl_shadow), (0, 0, 0));
    assert!(f.stats.decisions.iter().all(|d| !matches!(d.what, Subject::Vpls | Subject::VplMaps)));

    let mut asked = plain.clone();
    asked.indirect = Some(IndirectSettings { vpls: 6, bounces: 1, seed: 0, clamp: None });
    let knobs = hyrt::options::Knobs::from_flags(&["--preset", "hybrid"]).unwrap();
    let opts = knobs.options_for(&asked).unwrap();
    assert_eq!(opts.indirect, Indirect::Maps);
    let r = Renderer::new(&asked, opts);
    assert!(r.plan.runs(Pass::Indirect));
    let f = r.render(&|| {});
    assert!(f.stats.vpls > 0 && f.stats.rays.vpl_path > 0);
    assert!(decision(&f.stats.decisions, Subject::Vpls).run);
    assert!(decision(&f.stats.decisions, Subject::VplMaps).run);
}

/// A light that no visible surface faces (under the floor the camera looks at) gets no map and
/// no rays, in the hybrid and in the reference; a dark light (zero intensity) likewise, and the
/// plan names it. The same light above the floor is used.
#[test]
fn lights_that_reach_no_visible_pixel_cost_nothing() {
    let above = light(vec3(0.3, 2.0, 0.1), 5.0);
    let below = light(vec3(0.0, -1.0, 0.0), 5.0);
    let dark = light(vec3(-0.3, 2.0, 0.0), 0.0);
    let s = floor_scene(1.0, Vec3::splat(0.5), 1.5, 60.0, vec![above, below, dark], 40, 30);
    let floor_px = {
        let f = Renderer::new(&s, Options::reference()).render(&|| {});
        f.film.pixels.iter().filter(|p| **p != Vec3::ZERO).count() as u64
    };
    assert!(floor_px > 0);

    let r = Renderer::new(&s, Options::hybrid());
    assert!(r.plan.skipped.iter().any(|d| d.reason.contains("light 2: zero intensity")), "{}", r.plan);
    let f = r.render(&|| {});
    let d = &f.stats.decisions;
    assert!(decision(d, Subject::Light(0)).run);
    for (l, why) in [(1, "no camera hit is in front of it"), (2, "zero intensity")] {
        let dl = decision(d, Subject::Light(l));
        assert!(!dl.run && dl.reason.contains(why), "{dl:?}");
        let st = f.stats.lights[l];
        assert_eq!((st.faces_drawn, st.map_bytes, st.lit + st.shadowed + st.undecided), (0, 0, 0), "{st:?}");
    }
    // Only the light above was built.
    assert_eq!(f.stats.maps_built, 1);
    // Every floor pixel is lit: by the map, or (a pixel whose primary ray came after the maps)
    // by a ray.
    let l0 = f.stats.lights[0];
    assert_eq!((l0.lit + l0.undecided, l0.shadowed), (floor_px, 0), "{l0:?}");

    // The reference casts one shadow ray per floor pixel: for the light above only.
    let f = Renderer::new(&s, Options::reference()).render(&|| {});
    assert_eq!(f.stats.rays.shadow, floor_px);

    // Moved above the floor, the same lights are used: two more maps and rays.
    let mut lit = s.clone();
    lit.lights[1].position = vec3(0.0, 1.0, 0.4);
    lit.lights[2].intensity = Vec3::splat(5.0);
    let f = Renderer::new(&lit, Options::hybrid()).render(&|| {});
    assert_eq!(f.stats.maps_built, 3);
    assert!((0..3).all(|l| decision(&f.stats.decisions, Subject::Light(l)).run));
    let f = Renderer::new(&lit, Options::reference()).render(&|| {});
    assert_eq!(f.stats.rays.shadow, 3 * floor_px);
}

/// A second frame of an unchanged scene rebuilds nothing: 0 light maps built, the VPLs and
/// their maps reused (no path rays), the BVH reused, and the same image. Changing a knob that
/// the maps depend on rebuilds exactly what it must; one they do not depend on rebuilds none,
/// and either way the image equals that of a fresh renderer.
#[test]
fn unchanged_scene_rebuilds_nothing() {
    let mut s = cornell(48, 36);
    s.indirect = Some(IndirectSettings { vpls: 4, bounces: 1, seed: 0, clamp: None });
    let mut opts = Options::hybrid();
    opts.indirect = Indirect::Maps;
    opts.indirect_opts.vpl.paths = 4;
    opts.shadow.map.resolution = 256;
    opts.indirect_opts.map.resolution = 128;
    let mut r = Renderer::new(&s, opts);
    let lights = s.lights.len() as u32;

    let first = r.render(&|| {});
    assert_eq!(first.stats.maps_built, lights);
    assert!(first.stats.rays.vpl_path > 0);
    let second = r.render(&|| {});
    assert_eq!(second.stats.maps_built, 0);
    assert_eq!(second.stats.rays.vpl_path, 0);
    let d = &second.stats.decisions;
    for what in [Subject::Bvh, Subject::Vpls, Subject::VplMaps] {
        let x = decision(d, what);
        assert!(!x.run && x.reason.contains("reused"), "{x:?}");
    }
    for l in 0..lights {
        assert!(decision(d, Subject::Light(l as usize)).reason.contains("not rebuilt"));
    }
    assert_eq!(first.film, second.film);

    let fresh = |o: Options| Renderer::new(&s, o).render(&|| {}).film;

    // Bias: a lookup knob. Nothing rebuilt.
    let mut o = opts;
    o.shadow.bias = 3.0;
    o.indirect_opts.bias = 2.0;
    assert!(r.set_options(o).is_empty());
    let f = r.render(&|| {});
    assert_eq!((f.stats.maps_built, f.stats.rays.vpl_path), (0, 0));
    assert_eq!(f.film, fresh(o));

    // Map resolution: the light maps only.
    o.shadow.map.resolution = 128;
    assert_eq!(r.set_options(o), ["light maps"]);
    let f = r.render(&|| {});
    assert_eq!((f.stats.maps_built, f.stats.rays.vpl_path), (lights, 0));
    assert!(!decision(&f.stats.decisions, Subject::VplMaps).run);
    assert_eq!(f.film, fresh(o));

    // VPL map resolution: the VPL maps only, the VPLs stay.
    o.indirect_opts.map.resolution = 64;
    assert_eq!(r.set_options(o), ["VPL maps"]);
    let f = r.render(&|| {});
    assert_eq!((f.stats.maps_built, f.stats.rays.vpl_path), (0, 0));
    assert!(
        decision(&f.stats.decisions, Subject::VplMaps).run
            && !decision(&f.stats.decisions, Subject::Vpls).run
    );
    assert_eq!(f.film, fresh(o));

    // VPL count: new VPLs and maps; map kind: new light maps.
    o.indirect_opts.vpl.paths = 6;
    o.shadow.map.kind = hyrt_shadowmap::MapKind::Paraboloid;
    assert_eq!(r.set_options(o), ["light maps", "VPLs and their maps"]);
    let f = r.render(&|| {});
    assert_eq!(f.stats.maps_built, lights);
    assert!(f.stats.rays.vpl_path > 0);
    assert_eq!(f.film, fresh(o));
}

/// Every configuration's plan, in frame order: each buffer a pass reads ([`Pass::reads`]) is
/// written by a pass that runs before it ([`Pass::writes`]); and a frame runs exactly the
/// plan's passes (the runner gates by the plan alone: its times name those passes and no
/// other).
#[test]
fn passes_read_what_earlier_passes_wrote_and_frames_run_the_plan() {
    use hyrt::plan::Buffer;
    use hyrt::render::{Shadows, Visibility};
    let scene = cornell(24, 18);
    let mut checked = 0;
    for visibility in [Visibility::Rays, Visibility::Raster] {
        for shadows in [Shadows::Rays, Shadows::Maps, Shadows::Smerts] {
            for indirect in [Indirect::None, Indirect::Rays, Indirect::Maps] {
                let mut o = Options::hybrid();
                (o.visibility, o.shadows, o.indirect) = (visibility, shadows, indirect);
                o.indirect_opts.vpl.paths = 4;
                o.indirect_opts.map.resolution = 32;
                let r = Renderer::new(&scene, o);
                let mut written: Vec<Buffer> = Vec::new();
                let run: Vec<Pass> = r.plan.run.iter().map(|d| d.pass).collect();
                assert!(run.windows(2).all(|w| w[0] < w[1]), "{o:?}: plan not in frame order: {run:?}");
                for &p in &run {
                    for b in p.reads() {
                        assert!(written.contains(b), "{o:?}: {p} reads {b:?}, which no earlier pass wrote");
                    }
                    written.extend(p.writes());
                }
                let f = r.render(&|| {});
                let timed: Vec<Pass> =
                    f.stats.pass_ms.keys().copied().filter(|p| p.part_of().is_none()).collect();
                let planned: Vec<Pass> = run.iter().copied().filter(|&p| p != Pass::BvhBuild).collect();
                assert_eq!(timed, planned, "{o:?}: the frame ran other passes than the plan");
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 18);
}

/// The classify pass says when it settles borders by their few triangles: by default the
/// borders that only the point's neighbouring facets make; with `--neighbours rays`, none (and
/// with `--ambiguous triangles` as well, the bias band's); without border rays, never.
#[test]
fn classify_says_which_borders_it_settles() {
    let s = cornell(32, 24);
    let reason = |o: Options| {
        let r = Renderer::new(&s, o);
        r.plan.run.iter().find(|d| d.pass == Pass::Classify).expect("classify runs").reason.clone()
    };
    assert!(reason(Options::hybrid()).contains("neighbouring facets"), "{}", reason(Options::hybrid()));
    let mut o = Options::hybrid();
    o.shadow.neighbours = hyrt::render::Neighbours::Rays;
    assert!(!reason(o).contains("settled"), "{}", reason(o));
    o.shadow.ambiguous = hyrt::render::Ambiguous::Triangles;
    assert!(reason(o).contains("bias band") && !reason(o).contains("neighbouring"), "{}", reason(o));
    let mut maps = Options::hybrid();
    maps.shadows = hyrt::render::Shadows::Maps;
    assert!(!reason(maps).contains("settled"), "{}", reason(maps));
}
