//! The `hyrt` command line: `render`, `compare`, `plan` and `sweep`.

use std::{
    io::IsTerminal,
    path::{Path, PathBuf},
};

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use hyrt::{
    metrics, output,
    render::{Renderer, Visibility},
    scene,
};

use crate::stats::{FirstFrame, RenderStats, VsReference};

/// hyrt: a hybrid CPU renderer (rasterization + selective ray tracing).
#[derive(Parser, Debug)]
#[command(name = "hyrt", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to PNG and/or EXR.
    Render(RenderArgs),
    /// PSNR (dB) of luminance between two images (PNG or EXR), as displayed.
    Compare(CompareArgs),
    /// Print the passes a scene needs and, for each skipped effect, why.
    Plan(PlanArgs),
    /// Reproduce the thesis's tables 4.1 to 4.5: reference and hybrid configurations measured
    /// side by side, with the thesis's figures.
    Bench(crate::bench::BenchArgs),
    /// Render every combination of some knobs' values (`--knob NAME=V1,V2,...`), measure each
    /// one's frame time and error against a reference, and write a CSV, JSON, a plot of PSNR
    /// against frame time with the Pareto front marked, and a summary.
    Sweep(crate::sweep::SweepArgs),
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// A built-in scene name (`cornell`), a `.toml` scene file, or a mesh file
    /// (`.obj`, `.obj.gz`, `.gltf`, `.glb`, framed automatically).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Output PNG (8-bit sRGB). Default: `<scene name>.png` unless `--exr` is given.
    #[arg(short = 'o', long = "output", value_name = "OUT.png")]
    pub output: Option<PathBuf>,
    /// Output OpenEXR (linear float RGB).
    #[arg(long, value_name = "OUT.exr")]
    pub exr: Option<PathBuf>,
    /// Image size, overriding the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Rayon worker threads (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,
    /// Write statistics (plan, rays by kind, time per pass) as JSON.
    #[arg(long, value_name = "OUT.json")]
    pub stats: Option<PathBuf>,
    /// Maximum mirror bounces, overriding the scene's.
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u32>,
    /// Exposure (linear scale) for the PNG, overriding the scene's.
    #[arg(long, value_name = "E")]
    pub exposure: Option<f32>,
    /// View through camera N of the scene's glTF files (0 is the first), instead of the
    /// scene's camera.
    #[arg(long, value_name = "N")]
    pub camera: Option<usize>,
    #[command(flatten)]
    pub knobs: Knobs,
    /// Also render the ray-traced reference of the same scene (rays everywhere, the same VPLs),
    /// and print the speed-up (medians of a few alternated frames, caches warm), the first
    /// frames of both on fresh renderers (BVH and maps built; cold) and the PSNR.
    #[arg(long)]
    pub vs_reference: bool,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

pub use hyrt::options::{Knobs, parse_size};

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// A built-in scene name, a `.toml` scene file, or a mesh file (as for `render`).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Image size, overriding the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Maximum mirror bounces, overriding the scene's.
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u32>,
    #[command(flatten)]
    pub knobs: Knobs,
    /// Also render two frames and print the plan each one carried out (per light: map and rays
    /// or skipped; maps rebuilt or reused), with its counters.
    #[arg(long)]
    pub frames: bool,
    /// With `--frames`: render N frames along `hyrt bench --orbit N`'s camera path instead of
    /// two at the scene's camera, to show which passes each moved view runs again and which
    /// maps it reuses or extends.
    #[arg(long, value_name = "N", requires = "frames", value_parser = clap::value_parser!(u32).range(1..))]
    pub orbit: Option<u32>,
    /// Print the plan as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// First image (e.g. the reference).
    pub a: PathBuf,
    /// Second image.
    pub b: PathBuf,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Loads a scene (a built-in name, a scene file or a mesh file) with the command line's
/// overrides of its image size, mirror depth, exposure and camera, and validates the result.
pub fn load_scene(name: &str, o: scene::Overrides) -> Result<scene::Scene> {
    Ok(scene::load_with(name, o)?)
}

/// Runs the CLI on parsed arguments.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(a) => in_pool(a.threads, || render(&a)),
        Command::Compare(a) => compare(&a),
        Command::Plan(a) => plan(&a),
        Command::Bench(a) => in_pool(a.threads, || crate::bench::run(&a)),
        Command::Sweep(a) => in_pool(a.threads, || crate::sweep::run(&a)),
    }
}

/// Runs `f` in a rayon pool of `threads` workers (default: all cores).
fn in_pool(threads: Option<u32>, f: impl FnOnce() -> Result<()> + Send) -> Result<()> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.map_or(0, |t| t as usize))
        .build()
        .context("cannot start worker threads")?;
    pool.install(f)
}

fn render(a: &RenderArgs) -> Result<()> {
    let say = |s: String| {
        if !a.quiet {
            eprintln!("{s}");
        }
    };
    let o = scene::Overrides { size: a.size, max_depth: a.max_depth, exposure: a.exposure, camera: a.camera };
    let scene = load_scene(&a.scene, o)?;
    for w in &scene.warnings {
        say(format!("warning: {w}"));
    }
    let png = match (&a.output, &a.exr) {
        (Some(p), _) => Some(p.clone()),
        (None, Some(_)) => None,
        (None, None) => Some(PathBuf::from(format!("{}.png", scene.name))),
    };
    // Refuse before rendering if the outputs cannot all be written.
    let outputs: Vec<&Path> = png.iter().chain(&a.exr).chain(&a.stats).map(PathBuf::as_path).collect();
    output::check_outputs(&outputs)?;

    // One image: a light map must pay for itself within this frame (unless told otherwise).
    let mut knobs = a.knobs.clone();
    if knobs.given("map-horizon").is_none() {
        knobs.set("map-horizon", "1")?;
    }
    let options = knobs.options_for(&scene)?;
    let mut renderer = Renderer::new(&scene, options);
    // Not the BVH's build time yet: asking for it waits for a background build.
    say(format!(
        "{}: {} triangles, {} lights, {}x{}, {} threads\nplan:\n{}",
        scene.name,
        scene.triangle_count(),
        scene.lights.len(),
        scene.settings.width,
        scene.settings.height,
        rayon::current_num_threads(),
        renderer.plan.to_string().trim_end()
    ));

    let rows = u64::from(scene.settings.height) * u64::from(renderer.progress_passes());
    let bar = progress_bar(rows, "rows", a.quiet);
    let frame = renderer.render(&|| bar.inc(1));
    bar.finish_and_clear();
    let (bvh_ms, raster) = (renderer.bvh_build_ms(), renderer.raster_stats());
    let (vs, first) = if a.vs_reference {
        let (vs, first) = vs_reference(&mut renderer, &frame.film, a.quiet)?;
        (Some(vs), Some(first))
    } else {
        (None, None)
    };

    say(format!("this frame:\n{}", hyrt::render::format_decisions(&frame.stats.decisions).trim_end()));
    let r = &frame.stats.rays;
    let times: Vec<String> = (frame.stats.pass_ms.iter().map(|(k, v)| format!("{k} {v:.1}")))
        .chain([format!("total {:.1}", frame.stats.total_ms)])
        .collect();
    say(format!(
        "rays: primary {} shadow {} (hint hits {}) specular {} vpl_shadow {} vpl_path {} total {}\ntime ms: {}",
        r.primary,
        r.shadow,
        r.shadow_hint_hits,
        r.specular,
        r.vpl_shadow,
        r.vpl_path,
        r.total(),
        times.join(", ")
    ));
    if let Some(v) = &vs {
        say(format!(
            "vs the reference: {:.1} ms against {:.1} ms (medians of {} alternated frames, caches warm): {:.2}x faster, PSNR {}",
            v.hybrid_ms,
            v.reference_ms,
            VS_FRAMES,
            v.speedup,
            if v.psnr_db.is_infinite() {
                "inf dB (identical)".into()
            } else {
                format!("{:.2} dB", v.psnr_db)
            }
        ));
    }
    if let Some(f) = &first {
        say(first_frame_line(f));
    }
    for (l, s) in frame.stats.lights.iter().enumerate() {
        let wrong = match (s.wrong, s.wrong_hint, s.wrong_traversal) {
            (Some(m), Some(h), Some(t)) => {
                format!(", wrong: {m} by the map, {h} by a hint, {t} by a traversal")
            }
            _ => String::new(),
        };
        let settled = match s.by_suspects {
            0 => String::new(),
            n => format!(", {n} of those borders settled by testing their triangles alone"),
        };
        say(format!(
            "light {l}: {} lit, {} shadowed{settled}, {} undecided (rays){wrong}; {} map face(s), {} page(s) held ({} drawn), {:.1} MB",
            s.lit,
            s.shadowed,
            s.undecided,
            s.faces_drawn,
            s.pages_held,
            s.pages_drawn,
            s.map_bytes as f64 / f64::from(1 << 20)
        ));
    }

    // Every output is written before any is moved into place: a failure leaves all as they were.
    let mut staged = Vec::new();
    if let Some(p) = &png {
        staged.push(output::stage(p, |tmp| frame.film.save_png(tmp, scene.settings.exposure))?);
    }
    if let Some(p) = &a.exr {
        staged.push(output::stage(p, |tmp| frame.film.save_exr(tmp))?);
    }
    if let Some(p) = &a.stats {
        let opts = hyrt::options::to_json(&options, scene.settings.max_depth);
        let mut stats = RenderStats::new(&scene, &renderer.plan, opts, &frame.stats, bvh_ms);
        if options.visibility == Visibility::Raster {
            stats = stats.with_raster(raster);
        }
        stats.vs_reference = vs;
        stats.first_frame = first;
        let json = serde_json::to_string_pretty(&stats)?;
        staged.push(output::stage(p, |tmp| std::fs::write(tmp, json.as_bytes()).map_err(Into::into))?);
    }
    let written: Vec<PathBuf> = staged.iter().map(|s| s.path().to_path_buf()).collect();
    output::commit_all(staged)?;
    for p in written {
        say(format!("wrote {}", p.display()));
    }
    Ok(())
}

/// Frames of each side timed by `--vs-reference`.
const VS_FRAMES: usize = 3;

/// Cold first frames of each side timed by `--vs-reference` (each on a fresh renderer): one
/// image's time varies by a tenth from run to run on a shared machine, and the median of four
/// holds still better than that of two.
const COLD_FRAMES: usize = 4;

/// `--vs-reference`: the hybrid's frame against the reference's, both timed with warm caches,
/// alternated, and the image compared; and the first frame of each on a fresh renderer
/// ([`cold_first_frames`]).
fn vs_reference(
    renderer: &mut Renderer,
    film: &hyrt::film::Film,
    quiet: bool,
) -> Result<(VsReference, FirstFrame)> {
    // The cold first frame is this command's one image; warm frames are a viewer's, whose maps
    // serve every frame (an infinite horizon).
    let hybrid = *renderer.options();
    let warm = hyrt::render::Options {
        shadow: hyrt::render::ShadowOptions { map_horizon: f32::INFINITY, ..hybrid.shadow },
        ..hybrid
    };
    // From `warm`: switching between the two then keeps the maps (`Renderer::set_options`).
    let reference = warm.reference_for();
    let bar = progress_bar(2 * (VS_FRAMES + COLD_FRAMES) as u64 + 2, "frames", quiet);
    bar.set_message("first frames, cold");
    let first = cold_first_frames(renderer.scene, hybrid, reference, &|| bar.inc(1));
    bar.set_message("the reference");
    renderer.set_options(reference);
    let ref_film = renderer.render(&|| {}).film;
    bar.inc(1);
    bar.set_message("warm frames");
    let (mut h, mut r) = (Vec::new(), Vec::new());
    renderer.set_options(warm);
    renderer.render(&|| {});
    for _ in 0..VS_FRAMES {
        for (o, times) in [(warm, &mut h), (reference, &mut r)] {
            renderer.set_options(o);
            times.push(renderer.render(&|| {}).stats.total_ms);
            bar.inc(1);
        }
    }
    renderer.set_options(hybrid);
    bar.finish_and_clear();
    let (hybrid_ms, reference_ms) = (metrics::Timing::of(&h).median, metrics::Timing::of(&r).median);
    let vs = VsReference {
        reference_ms,
        hybrid_ms,
        speedup: reference_ms / hybrid_ms.max(1e-9),
        psnr_db: metrics::psnr(renderer.scene, &ref_film, film)?,
    };
    Ok((vs, first))
}

/// The first frame of each side as one image costs from the command line, scene loading
/// excluded: a fresh [`Renderer`] (its BVH built, no map or VPL cached), then one frame, in
/// wall time. [`COLD_FRAMES`] of each, in pairs alternately reference first and hybrid first
/// (so that neither side always goes first), summarised by medians; the hybrid's light-map build
/// is its frames' `map_build` pass. Each renderer is dropped before the next is made.
fn cold_first_frames(
    scene: &hyrt::scene::Scene,
    hybrid: hyrt::render::Options,
    reference: hyrt::render::Options,
    done: &dyn Fn(),
) -> FirstFrame {
    let (mut h, mut maps, mut r) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..COLD_FRAMES {
        let order = if i % 2 == 0 { [false, true] } else { [true, false] };
        for is_hybrid in order {
            let (renderer, frame, ms) =
                crate::measure::cold_first_frame(scene, if is_hybrid { hybrid } else { reference });
            drop(renderer);
            if is_hybrid {
                h.push(ms);
                maps.push(frame.stats.ms(hyrt::render::Pass::MapBuild));
            } else {
                r.push(ms);
            }
            done();
        }
    }
    let median = |v: &[f64]| metrics::Timing::of(v).median;
    FirstFrame { hybrid_ms: median(&h), hybrid_maps_ms: median(&maps), reference_ms: median(&r) }
}

/// `first frame: hybrid X ms (maps Y ms) vs reference Z ms (Rx)`, R = Z / X; below 1, it says
/// that the hybrid is slower.
fn first_frame_line(f: &FirstFrame) -> String {
    let ratio = f.reference_ms / f.hybrid_ms.max(1e-9);
    let slower = if ratio < 1.0 { ", the hybrid is slower" } else { "" };
    format!(
        "first frame: hybrid {:.1} ms (maps {:.1} ms) vs reference {:.1} ms ({ratio:.2}x{slower})",
        f.hybrid_ms, f.hybrid_maps_ms, f.reference_ms
    )
}

/// The one progress bar of the commands: `total` units on stderr, hidden when `quiet` or when
/// stderr is not a terminal.
pub fn progress_bar(total: u64, unit: &str, quiet: bool) -> indicatif::ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let b = indicatif::ProgressBar::with_draw_target(Some(total), indicatif::ProgressDrawTarget::stderr());
    let template = format!("{{bar:40}} {{pos}}/{{len}} {unit} {{elapsed}} {{msg}}");
    b.set_style(
        indicatif::ProgressStyle::with_template(&template)
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    b
}

fn compare(a: &CompareArgs) -> Result<()> {
    let ia = metrics::read_display_image(&a.a)?;
    let ib = metrics::read_display_image(&a.b)?;
    let c = metrics::compare(&ia, &ib).with_context(|| format!("{} vs {}", a.a.display(), a.b.display()))?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
    } else {
        let psnr = if c.psnr_db.is_infinite() { "inf".to_string() } else { format!("{:.2}", c.psnr_db) };
        println!(
            "PSNR {psnr} dB (luminance), {} of {} pixels differ",
            c.differing_pixels,
            u64::from(c.width) * u64::from(c.height)
        );
    }
    Ok(())
}

fn vec3_text(v: glam::Vec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}

/// `hyrt plan`: the static plan, and with `--frames` what two frames (or the frames of an
/// orbit) actually did.
fn plan(a: &PlanArgs) -> Result<()> {
    let scene = load_scene(
        &a.scene,
        scene::Overrides { size: a.size, max_depth: a.max_depth, ..Default::default() },
    )?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let options = a.knobs.options_for(&scene)?;
    if !a.frames {
        let plan = hyrt::plan::Plan::new(&scene, &options);
        if a.json {
            println!("{}", serde_json::to_string_pretty(&plan)?);
        } else {
            println!("{}: {} triangles, {} lights", scene.name, scene.triangle_count(), scene.lights.len());
            print!("{plan}");
        }
        return Ok(());
    }
    let mut renderer = Renderer::new(&scene, options);
    let cam = scene.camera.context("the scene has no camera")?;
    // The camera of each frame: the scene's twice, or the orbit's path.
    let cameras: Vec<_> = match a.orbit {
        None => vec![cam; 2],
        Some(n) => (0..n).map(|i| crate::orbit::orbit_camera(&cam, i, n)).collect(),
    };
    let frames: Vec<_> = cameras
        .iter()
        .map(|c| {
            renderer.set_camera(c);
            renderer.render(&|| {}).stats
        })
        .collect();
    let passes = |s: &hyrt::render::FrameStats| s.pass_ms.keys().map(|p| p.name()).collect::<Vec<_>>();
    if a.json {
        let f: Vec<_> = frames
            .iter()
            .zip(&cameras)
            .map(|(s, c)| {
                serde_json::json!({
                    "eye": c.eye.to_array(),
                    "forward": c.forward.to_array(),
                    "decisions": s.decisions,
                    "maps_built": s.maps_built,
                    "rays": s.rays,
                    "passes": passes(s),
                })
            })
            .collect();
        let v = serde_json::json!({ "plan": renderer.plan, "frames": f });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("{}: {} triangles, {} lights", scene.name, scene.triangle_count(), scene.lights.len());
    print!("{}", renderer.plan);
    for (i, (s, c)) in frames.iter().zip(&cameras).enumerate() {
        let r = &s.rays;
        println!("frame {} (eye {}):", i + 1, vec3_text(c.eye));
        println!("  passes run: {}", passes(s).join(", "));
        print!("{}", hyrt::render::format_decisions(&s.decisions));
        println!(
            "  rays: primary {} shadow {} specular {} vpl_shadow {} vpl_path {}; light maps built {}",
            r.primary, r.shadow, r.specular, r.vpl_shadow, r.vpl_path, s.maps_built
        );
    }
    Ok(())
}
