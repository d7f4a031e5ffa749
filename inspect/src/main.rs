//! `hyrt-inspect [SCENE] [--size WxH] [--max-depth N] [render flags]`: the inspector window.

use clap::Parser;
use hyrt::options::{Knobs, parse_size};
use hyrt_inspect::{Inspector, Setup};

/// hyrt-inspect: see why the hybrid renderer is fast and where it is wrong.
///
/// Opens a window with the hybrid frame (the hybrid preset unless `--preset` says otherwise)
/// against the Whitted reference, the shadow maps and borders per light, rays per pixel, the
/// light and VPL depth maps, the plan and times per pass; click a pixel to inspect it, change a
/// knob to render again. Render flags are those of `hyrt render`.
#[derive(Parser, Debug)]
#[command(name = "hyrt-inspect", version)]
struct Args {
    /// A built-in scene name (`cornell`), a `.toml` scene file, or a mesh file.
    #[arg(default_value = "cornell")]
    scene: String,
    /// Image size, overriding the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Maximum mirror bounces, overriding the scene's.
    #[arg(long, value_name = "N")]
    max_depth: Option<u32>,
    /// View through camera N of the scene's glTF files (as `hyrt render --camera`).
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
    #[command(flatten)]
    knobs: Knobs,
}

fn main() -> eframe::Result {
    hyrt::process::limit_malloc_arenas();
    let a = Args::parse();
    let setup = Setup {
        scene: a.scene,
        size: a.size,
        max_depth: a.max_depth,
        camera: a.camera,
        knobs: a.knobs,
        options: None,
    };
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_title("hyrt-inspect")
            .with_inner_size([1500.0, 920.0]),
        ..Default::default()
    };
    eframe::run_native("hyrt-inspect", options, Box::new(|_cc| Ok(Box::new(Inspector::new(setup)))))
}
