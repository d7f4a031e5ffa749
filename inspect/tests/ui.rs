//! The window, headless (egui_kittest, wgpu on whatever adapter there is: Mesa's llvmpipe
//! here): snapshots of every view on the built-in Cornell box at 96x72, and interactions that
//! check what the window shows against the frame (a picked pixel's triangle, a knob's
//! re-render). Snapshots: `inspect/tests/snapshots/`; `UPDATE_SNAPSHOTS=1` rewrites them.

use std::time::{Duration, Instant};

use eframe::egui::{self, Vec2};
use egui_kittest::{Harness, kittest::Queryable};
use hyrt::render::{Indirect, Options, Subject};
use hyrt_inspect::{Inspector, Setup, View};

fn setup(scene: &str, options: Options) -> Setup {
    Setup {
        scene: scene.into(),
        size: Some((96, 72)),
        max_depth: None,
        camera: None,
        knobs: Default::default(),
        options: Some(options),
    }
}

/// The hybrid with small maps, the visibility check and a few VPLs (every view has something).
fn options() -> Options {
    let mut o = Options::hybrid();
    o.shadow.map.resolution = 256;
    o.check_visibility = true;
    o.indirect = Indirect::Maps;
    o.indirect_opts.vpl.paths = 8;
    o.indirect_opts.map.resolution = 128;
    o
}

fn harness(setup: Setup) -> Harness<'static, Inspector> {
    Harness::builder()
        .with_size(Vec2::new(1400.0, 860.0))
        .with_render_cursor(false)
        .with_max_steps(50)
        .wgpu()
        .build_ui_state(|ui, app: &mut Inspector| app.show(ui), Inspector::new(setup))
}

/// Steps the window until the worker is done, then until the window settles.
fn settle(h: &mut Harness<'static, Inspector>) {
    let start = Instant::now();
    loop {
        h.step();
        if !h.state().busy() {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(300), "the worker did not finish");
        std::thread::sleep(Duration::from_millis(10));
    }
    h.run();
}

/// Clicks the centre of pixel `(x, y)` of the image labelled `label` (zoom 1).
fn click_pixel(h: &mut Harness<'static, Inspector>, label: &str, x: u32, y: u32) {
    let rect = h.get_by_label(label).rect();
    let pos =
        rect.min + Vec2::new((x as f32 + 0.5) / 96.0 * rect.width(), (y as f32 + 0.5) / 72.0 * rect.height());
    h.event(egui::Event::PointerMoved(pos));
    for pressed in [true, false] {
        h.event(egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Default::default(),
        });
    }
    h.run();
    h.remove_cursor();
    h.run();
}

#[test]
fn snapshots_of_every_view() {
    let mut h = harness(setup("cornell", options()));
    settle(&mut h);
    h.state_mut().hide_times = true;
    click_pixel(&mut h, "hybrid image", 30, 50);
    assert_eq!(h.state().picked, Some([30, 50]));
    let mut results = Vec::new();
    for (view, name) in [
        (View::Frame, "frame"),
        (View::Shadows, "shadows"),
        (View::Rays, "rays"),
        (View::LightMaps, "light_maps"),
        (View::Vpls, "vpls"),
    ] {
        h.state_mut().view = view;
        settle(&mut h);
        results.push(h.try_snapshot(name));
    }
    for r in results {
        r.expect("snapshot");
    }
}

#[test]
fn a_picked_pixel_shows_its_triangle_and_lights() {
    let mut o = options();
    o.indirect = Indirect::None;
    let mut h = harness(setup("cornell", o));
    settle(&mut h);
    let (x, y) = (60, 40);
    click_pixel(&mut h, "hybrid image", x, y);
    assert_eq!(h.state().picked, Some([x, y]));
    let (tri, material) = {
        let app = h.state();
        let r = app.result.as_ref().expect("rendered");
        let hit = r.frame.gbuffer.as_ref().expect("kept")[(y * 96 + x) as usize].expect("a wall");
        let scene = &app.loaded.as_ref().expect("loaded").scene;
        (hit.tri, scene.materials[scene.material[hit.tri as usize] as usize].name.clone())
    };
    h.get_by_label(&format!("pixel ({x}, {y})"));
    h.get_by_label(&format!("triangle {tri}"));
    h.get_by_label(&format!("material {material}"));
    // Per light: the texel the pixel read, as the pick reports it.
    let info = h.state().pixel_info().expect("picked");
    for lp in &info.lights {
        assert!(h.query_all_by_label(&format!("light {}", lp.light)).count() >= 1);
        if let Some(m) = &lp.map {
            let text = format!("texel face {}", ["+X", "-X", "+Y", "-Y", "+Z", "-Z"][usize::from(m.face)]);
            let shown = h.get_all_by_label_contains(&text).count();
            assert!(shown >= 1, "{text}");
            let needle = format!(" x {} y {} ", m.lookup.texel[0], m.lookup.texel[1]);
            assert!(h.query_all_by_label_contains(&needle).count() >= 1, "{needle}");
        }
    }
    // A click on the reference picks there too.
    click_pixel(&mut h, "reference image", 10, 20);
    assert_eq!(h.state().picked, Some([10, 20]));
    h.get_by_label("pixel (10, 20)");
}

#[test]
fn a_knob_change_renders_again_and_shows_the_new_frame() {
    let mut o = options();
    o.indirect = Indirect::None;
    let mut h = harness(setup("cornell", o));
    settle(&mut h);
    let first = h.state().result.as_ref().expect("rendered").generation;
    let time = |h: &Harness<'static, Inspector>| {
        let r = h.state().result.as_ref().expect("rendered");
        format!("hybrid frame {:.1} ms", r.frame.stats.total_ms)
    };
    h.get_by_label(&time(&h));

    // Dilation: a new frame with more border rays; nothing rebuilt.
    let rays_before = h.state().result.as_ref().expect("rendered").frame.stats.lights[0].undecided;
    h.get_by_role_and_label(egui::Role::Slider, "dilation (px)").set_value_accesskit(2.0);
    settle(&mut h);
    {
        let r = h.state().result.as_ref().expect("rendered");
        assert!(r.generation > first);
        assert_eq!(r.options.shadow.dilate, 2);
        assert!(r.frame.stats.lights[0].undecided > rays_before);
        assert_eq!(r.frame.stats.maps_built, 0);
    }
    h.get_by_label("Last change dropped: nothing: every cache kept");
    h.get_by_label(&time(&h));
    let undecided = h.state().result.as_ref().expect("rendered").frame.stats.lights[0].undecided;
    assert!(h.query_all_by_label(&undecided.to_string()).count() >= 1, "the lights table shows {undecided}");

    // Map resolution (of whole maps): the light maps are rebuilt whole at the new size.
    h.get_by_label("light maps").click();
    h.run();
    h.get_by_label("whole").click();
    settle(&mut h);
    h.get_by_label("map resolution").click();
    h.run();
    h.get_by_label("512x512").click();
    settle(&mut h);
    {
        let r = h.state().result.as_ref().expect("rendered");
        assert_eq!(r.options.shadow.map.resolution, 512);
        assert!(r.maps.iter().flatten().all(|m| m.resolution() == 512));
    }
    h.get_by_label("Last change dropped: light maps");
    h.get_by_label(&time(&h));
    h.state_mut().view = View::LightMaps;
    settle(&mut h);
    assert!(h.query_all_by_label_contains("512x512 per face").count() >= 1);
}

/// Zoom and pan move every screen image together, and a click still picks the pixel under it.
#[test]
fn zoomed_images_pick_the_pixel_under_the_pointer() {
    let mut o = options();
    o.indirect = Indirect::None;
    let mut h = harness(setup("cornell", o));
    settle(&mut h);
    h.get_by_label("zoom in").click();
    h.run();
    h.get_by_label("zoom 2.0x");
    // Zoomed 2x about the centre: the image's top-left corner shows pixel (24, 18).
    let rect = h.get_by_label("hybrid image").rect();
    let at = |h: &mut Harness<'static, Inspector>, pos: egui::Pos2| {
        h.event(egui::Event::PointerMoved(pos));
        for pressed in [true, false] {
            let e = egui::Event::PointerButton {
                pos,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: Default::default(),
            };
            h.event(e);
        }
        h.run();
    };
    at(&mut h, rect.min + Vec2::splat(1.0));
    assert_eq!(h.state().picked, Some([24, 18]));
    at(&mut h, rect.max - Vec2::splat(1.0));
    assert_eq!(h.state().picked, Some([71, 53]));
    // The reference shows the same window.
    let r = h.get_by_label("reference image").rect();
    at(&mut h, r.min + Vec2::splat(1.0));
    assert_eq!(h.state().picked, Some([24, 18]));
    // Dragging pans (left by a quarter of the image: the window's left edge moves right). The
    // hybrid image is the camera's viewport (a drag there orbits): drag the reference.
    let rect = r;
    let start = rect.center();
    h.event(egui::Event::PointerMoved(start));
    h.event(egui::Event::PointerButton {
        pos: start,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: Default::default(),
    });
    h.run();
    for i in 1..=10 {
        h.event(egui::Event::PointerMoved(start - Vec2::new(rect.width() * 0.05 * i as f32, 0.0)));
        h.run();
    }
    let end = start - Vec2::new(rect.width() * 0.5, 0.0);
    h.event(egui::Event::PointerButton {
        pos: end,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: Default::default(),
    });
    h.run();
    at(&mut h, rect.min + Vec2::splat(1.0));
    assert_eq!(h.state().picked, Some([48, 18]), "panned by half the window (a quarter of the image)");
    assert_eq!(h.state().pose.as_ref().unwrap().camera, scene_camera(&h), "the camera did not move");
    h.get_by_label("reset view").click();
    h.run();
    h.get_by_label("zoom 1.0x");
}

#[test]
fn a_scene_that_fails_to_load_shows_the_error() {
    let mut h = harness(setup("no-such-dir/missing-scene.toml", options()));
    settle(&mut h);
    assert!(h.state().error.is_some());
    h.get_by_label("The scene could not be loaded");
    assert!(
        h.query_all_by_label_contains("No such file").count() >= 1
            || h.query_all_by_label_contains("missing-scene.toml").count() >= 2
    );
    h.snapshot("load_error");
}

fn scene_camera(h: &Harness<'static, Inspector>) -> hyrt::scene::Camera {
    h.state().loaded.as_ref().expect("loaded").scene.camera.expect("a camera")
}

/// Presses `button` at `from`, moves to `to` in ten steps, and releases it there.
fn drag(h: &mut Harness<'static, Inspector>, button: egui::PointerButton, from: egui::Pos2, to: egui::Pos2) {
    h.event(egui::Event::PointerMoved(from));
    h.event(egui::Event::PointerButton { pos: from, button, pressed: true, modifiers: Default::default() });
    h.run();
    for i in 1..=10 {
        h.event(egui::Event::PointerMoved(from + (to - from) * (i as f32 / 10.0)));
        h.step();
    }
    h.event(egui::Event::PointerButton { pos: to, button, pressed: false, modifiers: Default::default() });
    h.step();
    h.remove_cursor();
}

/// A left drag across the hybrid image orbits the camera about the scene's target, and the new
/// frame reuses the light maps and says so; the reset key brings the scene's camera back;
/// "copy as TOML" gives the view as a scene file's table.
#[test]
fn a_drag_orbits_the_camera_and_the_reset_key_restores_it() {
    let mut o = options();
    o.indirect = Indirect::None;
    o.check_visibility = false;
    let mut h = harness(setup("cornell", o));
    settle(&mut h);
    let home = scene_camera(&h);
    let rect = h.get_by_label("hybrid image").rect();
    drag(&mut h, egui::PointerButton::Primary, rect.center(), rect.center() + Vec2::new(40.0, 10.0));
    settle(&mut h);
    let cam = h.state().pose.as_ref().unwrap().camera;
    assert_ne!(cam.eye, home.eye, "the drag moved the camera");
    let target = |c: &hyrt::scene::Camera| c.eye + c.forward;
    assert!((target(&cam) - target(&home)).length() < 1e-4, "about the scene's target");
    {
        let r = h.state().result.as_ref().expect("rendered");
        assert_eq!(r.pose.camera, cam, "the frame shown is of the new view");
        assert!(r.full && r.comparison.as_ref().is_some_and(|c| c.reference.pose.camera == cam));
        assert_eq!(r.frame.stats.maps_built, 0);
    }
    assert!(h.query_all_by_label_contains("light maps reused").count() >= 1);
    h.get_by_label(&format!("eye ({:.3}, {:.3}, {:.3})", cam.eye.x, cam.eye.y, cam.eye.z));

    h.get_by_label("copy as TOML").click();
    h.step();
    let copied = h.output().platform_output.commands.iter().find_map(|c| match c {
        egui::OutputCommand::CopyText(t) => Some(t.clone()),
        _ => None,
    });
    let t = copied.expect("copied");
    assert!(t.starts_with("[camera]\neye = [") && t.contains("fov_y = "), "{t}");
    h.run();

    h.key_press(hyrt_inspect::app::RESET_KEY);
    settle(&mut h);
    assert_eq!(h.state().pose.as_ref().unwrap().camera, home);
    assert_eq!(h.state().result.as_ref().unwrap().pose.camera, home);
}

/// Dragging the x axis of a light's handle in the hybrid image moves that light along x: one
/// light map is built again (the other is reused), and the decisions say why.
#[test]
fn dragging_a_light_handle_rebuilds_its_map_alone() {
    let mut o = options();
    o.indirect = Indirect::None;
    o.check_visibility = false;
    let mut h = harness(setup("cornell", o));
    settle(&mut h);
    let before = h.state().pose.as_ref().unwrap().lights.clone();
    assert!(before.len() >= 2, "the test needs a second light that stays");
    // Light 0's handle: where it projects, and the screen direction of its x axis.
    let rect = h.get_by_label("hybrid image").rect();
    let (at, end) = {
        let r = h.state().result.as_ref().unwrap();
        let p = before[0].position;
        let reach = (p - r.camera.eye).length() * 0.1;
        let screen = |q: glam::Vec3| {
            let (fx, fy, _) = hyrt_inspect::views::project(&r.camera, q).expect("in front");
            rect.min + Vec2::new(fx / 96.0 * rect.width(), fy / 72.0 * rect.height())
        };
        (screen(p), screen(p + glam::Vec3::X * reach))
    };
    assert!(rect.contains(at), "light 0 is in view");
    let grab = at + (end - at) * 0.6;
    drag(&mut h, egui::PointerButton::Primary, grab, grab + (end - at) * 0.5);
    settle(&mut h);
    let after = h.state().pose.as_ref().unwrap().lights.clone();
    let moved = after[0].position - before[0].position;
    assert!(moved.x > 0.0 && moved.y == 0.0 && moved.z == 0.0, "moved along x: {moved}");
    assert_eq!(after[1], before[1]);
    assert_eq!(h.state().pose.as_ref().unwrap().camera, scene_camera(&h), "the camera stays");
    let r = h.state().result.as_ref().unwrap();
    assert_eq!(r.pose.lights, after);
    // The frames drawn while dragging rebuilt the map; the full frame at rest reuses it and
    // shows what they built.
    let built: Vec<_> = r.built_while_moving.iter().map(|d| d.what).collect();
    assert!(!built.is_empty() && built.iter().all(|w| *w == Subject::Light(0)), "{built:?}");
    assert_eq!(r.frame.stats.maps_built, 0);
    assert!(h.query_all_by_label_contains("map rebuilt: the light moved").count() >= 1);
}

/// Keys pressed and the camera moved while frames render neither block the window nor panic:
/// every step returns while the worker is busy, and the last view is the one rendered.
#[test]
fn keys_while_rendering_do_not_block() {
    let mut o = options();
    o.indirect_opts.vpl.paths = 32;
    let mut h = harness(setup("cornell", o));
    // Long rests: every move is a light frame until the test says otherwise.
    h.state_mut().rest = Duration::from_secs(3600);
    settle(&mut h);
    let rect = h.get_by_label("hybrid image").rect();
    let mut busy_steps = 0;
    let right = egui::PointerButton::Secondary;
    h.event(egui::Event::PointerMoved(rect.center()));
    h.event(egui::Event::PointerButton {
        pos: rect.center(),
        button: right,
        pressed: true,
        modifiers: Default::default(),
    });
    h.step();
    for i in 0..40 {
        let key = [egui::Key::W, egui::Key::A, egui::Key::E, egui::Key::R, egui::Key::S][i % 5];
        h.key_down(key);
        h.event(egui::Event::PointerMoved(rect.center() + Vec2::new(i as f32, 0.0)));
        h.step();
        h.key_up(key);
        h.step();
        busy_steps += usize::from(h.state().busy());
    }
    h.event(egui::Event::PointerButton {
        pos: rect.center(),
        button: right,
        pressed: false,
        modifiers: Default::default(),
    });
    h.step();
    assert!(busy_steps > 0, "keys were pressed while the worker rendered");
    let moved = h.state().pose.as_ref().unwrap().camera;
    assert_ne!(moved, scene_camera(&h), "flying and looking moved the camera");
    assert!(h.state().moving());
    // Rest: the full frame of the last view, with its reference.
    h.state_mut().rest = Duration::ZERO;
    settle(&mut h);
    let r = h.state().result.as_ref().unwrap();
    assert!(r.full && r.pose.camera == moved && r.comparison.is_some());
}
