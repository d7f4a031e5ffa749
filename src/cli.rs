//! The `hyrt` command line: `render` and `compare`.

use std::{
    io::IsTerminal,
    path::{Path, PathBuf},
};

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};

use crate::{
    film::atomic_write,
    metrics,
    render::{Options, Renderer, Visibility},
    scene,
    stats::RenderStats,
};

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
    /// Primary visibility: `rays` (one primary ray per pixel, the reference) or `raster`
    /// (z-buffer; no primary rays).
    #[arg(long, value_enum, default_value_t = VisibilityArg::Rays)]
    pub visibility: VisibilityArg,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `--visibility` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum VisibilityArg {
    Rays,
    Raster,
}

impl From<VisibilityArg> for Visibility {
    fn from(v: VisibilityArg) -> Self {
        match v {
            VisibilityArg::Rays => Visibility::Rays,
            VisibilityArg::Raster => Visibility::Raster,
        }
    }
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

fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WxH, e.g. 640x480, got '{s}'"))?;
    let p =
        |v: &str| v.trim().parse::<u32>().map_err(|_| format!("expected WxH with whole numbers, got '{s}'"));
    Ok((p(w)?, p(h)?))
}

/// Runs the CLI on parsed arguments.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(a) => {
            let threads = a.threads.map(|t| t as usize).unwrap_or(0);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .context("cannot start worker threads")?;
            pool.install(|| render(&a))
        }
        Command::Compare(a) => compare(&a),
    }
}

fn render(a: &RenderArgs) -> Result<()> {
    let say = |s: String| {
        if !a.quiet {
            eprintln!("{s}");
        }
    };
    let mut scene = scene::load(&a.scene)?;
    if let Some((w, h)) = a.size {
        scene.settings.width = w;
        scene.settings.height = h;
    }
    if let Some(d) = a.max_depth {
        scene.settings.max_depth = d;
    }
    if let Some(e) = a.exposure {
        scene.settings.exposure = e;
    }
    scene.validate()?;
    let png = match (&a.output, &a.exr) {
        (Some(p), _) => Some(p.clone()),
        (None, Some(_)) => None,
        (None, None) => Some(PathBuf::from(format!("{}.png", scene.name))),
    };
    // Refuse before rendering if an output cannot be written at all.
    for p in png.iter().chain(&a.exr).chain(&a.stats) {
        check_writable(p)?;
    }

    let options = Options { visibility: a.visibility.into(), ..Options::default() };
    let renderer = Renderer::new(&scene, options);
    say(format!(
        "{}: {} triangles, {} lights, {}x{}, {} threads; BVH {:.1} ms\nplan:\n{}",
        scene.name,
        scene.triangle_count(),
        scene.lights.len(),
        scene.settings.width,
        scene.settings.height,
        rayon::current_num_threads(),
        renderer.bvh_build_ms(),
        renderer.plan.to_string().trim_end()
    ));

    let bar = if a.quiet || !std::io::stderr().is_terminal() {
        indicatif::ProgressBar::hidden()
    } else {
        let total = u64::from(scene.settings.height) * u64::from(renderer.progress_passes());
        let b =
            indicatif::ProgressBar::with_draw_target(Some(total), indicatif::ProgressDrawTarget::stderr());
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rows {elapsed}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    };
    let frame = renderer.render(&|| bar.inc(1));
    bar.finish_and_clear();

    let r = &frame.stats.rays;
    let times: Vec<String> = frame.stats.time_ms.iter().map(|(k, v)| format!("{k} {v:.1}")).collect();
    say(format!(
        "rays: primary {} shadow {} specular {} total {}\ntime ms: {}",
        r.primary,
        r.shadow,
        r.specular,
        r.total(),
        times.join(", ")
    ));

    if let Some(p) = &png {
        frame.film.write_png(p, scene.settings.exposure)?;
        say(format!("wrote {}", p.display()));
    }
    if let Some(p) = &a.exr {
        frame.film.write_exr(p)?;
        say(format!("wrote {}", p.display()));
    }
    if let Some(p) = &a.stats {
        let opts = serde_json::json!({
            "visibility": options.visibility.name(),
            "shadows": options.shadows.name(),
            "indirect": "none",
            "max_depth": scene.settings.max_depth,
        });
        let stats = RenderStats::new(&scene, &renderer.plan, opts, &frame.stats, renderer.bvh_build_ms());
        let json = serde_json::to_string_pretty(&stats)?;
        atomic_write(p, |tmp| std::fs::write(tmp, json.as_bytes()).map_err(Into::into))?;
        say(format!("wrote {}", p.display()));
    }
    Ok(())
}

/// Fails early, naming the file, when `p`'s directory does not exist.
fn check_writable(p: &Path) -> Result<()> {
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !dir.is_dir() {
        bail!("{}: cannot write: directory {} does not exist", p.display(), dir.display());
    }
    Ok(())
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
