//! The screenshot of the viewer mid-flight that the README shows (`docs/inspector-flight.png`):
//! the window, headless, orbiting a scene with the left button held, a frame rendered for each
//! step of the drag, captured before the button is released.
//!
//! `cargo run --release -p hyrt-inspect --example flight -- [SCENE] [OUT.png] [STEPS]`
//! (default `scenes/conference.toml`, `docs/inspector-flight.png`, 24 steps).

use std::time::{Duration, Instant};

use eframe::egui::{self, Vec2};
use egui_kittest::{Harness, kittest::Queryable};
use hyrt_inspect::{Inspector, Setup};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "scenes/conference.toml".into());
    let out = args.next().unwrap_or_else(|| "docs/inspector-flight.png".into());
    let steps: u32 = args.next().map_or(Ok(24), |s| s.parse())?;
    let setup =
        Setup { scene, size: None, max_depth: None, camera: None, knobs: Default::default(), options: None };
    let mut h = Harness::builder()
        .with_size(Vec2::new(1500.0, 920.0))
        .with_max_steps(50)
        .wgpu()
        .build_ui_state(|ui, app: &mut Inspector| app.show(ui), Inspector::new(setup));
    let wait = |h: &mut Harness<'static, Inspector>, done: &dyn Fn(&Inspector) -> bool| {
        let start = Instant::now();
        while !done(h.state()) {
            anyhow::ensure!(start.elapsed() < Duration::from_secs(600), "no frame came");
            if let Some(e) = &h.state().error {
                anyhow::bail!("{e}");
            }
            h.step();
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(())
    };
    wait(&mut h, &|a| !a.busy())?;
    // While the button is held the input never rests: every frame is a moving one.
    h.state_mut().rest = Duration::from_secs(3600);
    let rect = h.get_by_label("hybrid image").rect();
    let mut at = rect.center() - Vec2::new(rect.width() * 0.2, 0.0);
    h.event(egui::Event::PointerMoved(at));
    h.event(egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: Default::default(),
    });
    h.step();
    // Per moving frame: the worker's wall time for the command, and the hybrid frame's own.
    let (mut wall, mut frame) = (Vec::new(), Vec::<f64>::new());
    for _ in 0..steps {
        at += Vec2::new(rect.width() * 0.12 / steps as f32, -rect.height() * 0.03 / steps as f32);
        h.event(egui::Event::PointerMoved(at));
        h.step();
        let shown = |a: &Inspector| a.result.as_ref().zip(a.pose.as_ref()).is_some_and(|(r, p)| r.pose == *p);
        wait(&mut h, &shown)?;
        let r = h.state().result.as_ref().expect("shown");
        wall.push(r.wall_ms);
        frame.push(r.frame.stats.total_ms);
    }
    // The graph keeps repainting while moving: a few steps, not `run` (which waits for rest).
    h.run_steps(3);
    h.render().map_err(anyhow::Error::msg)?.save(&out)?;
    let median = |v: &[f64]| hyrt::metrics::Timing::of(v).median;
    println!(
        "{out}: {steps} moving frames, median {:.1} ms per command ({:.1} ms the hybrid frame)",
        median(&wall),
        median(&frame)
    );
    Ok(())
}
