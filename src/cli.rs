//! The `hyrt` command line: `render`, `compare`, `plan` and `sweep`.

use std::{
    io::IsTerminal,
    path::{Path, PathBuf},
};

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use hyrt_shadowmap::{MapKind, vpl_map::VplFormat};

use crate::{
    metrics, output,
    render::{Borders, Indirect, MirrorShadows, Options, Renderer, Shadows, Visibility, indirect::VplFilter},
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
    #[command(flatten)]
    pub knobs: Knobs,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The strategy of each stage and the knobs of every approximation. A preset sets all of them;
/// each explicit flag then overrides its own.
#[derive(Args, Debug, Clone, Default)]
pub struct Knobs {
    /// `reference`: rays everywhere (the default); `hybrid`: raster visibility + SMeRTS with the
    /// default knobs.
    #[arg(long, value_enum)]
    pub preset: Option<PresetArg>,
    /// Primary visibility: `rays` (one primary ray per pixel) or `raster` (z-buffer; no primary
    /// rays).
    #[arg(long, value_enum)]
    pub visibility: Option<VisibilityArg>,
    /// Point-light shadows: `rays` (one shadow ray per hit and light), `maps` (depth maps
    /// only) or `smerts` (maps + shadow rays on the borders).
    #[arg(long, value_enum)]
    pub shadows: Option<ShadowsArg>,
    /// Light map parameterisation.
    #[arg(long, value_enum, value_name = "KIND")]
    pub shadow_map: Option<MapKindArg>,
    /// Light map resolution: texels per side of each face.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub shadow_map_res: Option<u32>,
    /// Depth margin of map decisions, in texel footprints.
    #[arg(long, value_name = "B", allow_negative_numbers = true)]
    pub bias: Option<f32>,
    /// SMeRTS border detection: screen-space Laplacian, map-space texel disagreement, or both.
    #[arg(long, value_enum)]
    pub borders: Option<BordersArg>,
    /// SMeRTS border dilation radius, in pixels.
    #[arg(long, value_name = "R")]
    pub dilate: Option<u32>,
    /// Paraboloid maps: tessellate triangles until projected edges are at most T texels
    /// (`inf`: no tessellation).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub tess: Option<f32>,
    /// Shadows at mirror hits: from the `maps` (map-space border test) or by `rays`.
    #[arg(long, value_enum)]
    pub mirror_shadows: Option<MirrorArg>,
    /// Indirect light from virtual point lights: `none`, `rays` (one shadow ray per hit and
    /// VPL) or `maps` (one paraboloid map per VPL). `--vpls` alone picks `rays` under the
    /// reference preset and `maps` under the hybrid one.
    #[arg(long, value_enum)]
    pub indirect: Option<IndirectArg>,
    /// Number of VPL light paths (thesis: 45), over all lights.
    #[arg(long, value_name = "N")]
    pub vpls: Option<u32>,
    /// Diffuse bounces per VPL path (each leaves a VPL).
    #[arg(long, value_name = "B")]
    pub vpl_bounces: Option<u32>,
    /// Offset into the VPLs' Halton sequence.
    #[arg(long, value_name = "S")]
    pub vpl_seed: Option<u32>,
    /// VPL distance clamp `d_min`, as a fraction of the scene's bounding-box diagonal.
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub vpl_clamp: Option<f32>,
    /// Interleaved VPL sampling: each pixel of a K x K pattern evaluates 1/K^2 of the VPLs,
    /// then a geometry-aware filter reconstructs (1 = off).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=16))]
    pub interleave: Option<u32>,
    /// Depth margin of VPL map lookups, in texel footprints.
    #[arg(long, value_name = "B", allow_negative_numbers = true)]
    pub vpl_bias: Option<f32>,
    /// Resolution of each VPL's paraboloid map.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub vpl_map_res: Option<u32>,
    /// VPL maps: tessellate triangles until projected edges are at most T texels (`inf`: no
    /// tessellation), as `--tess` for the light maps.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub vpl_tess: Option<f32>,
    /// How a VPL map decides visibility: the `texel` under the point (the thesis; the
    /// default), or `bilinear` over the 2x2 texels around it (percentage-closer filtering).
    #[arg(long, value_enum)]
    pub vpl_filter: Option<VplFilterArg>,
    /// What a VPL map's texels hold: the occluder's `planes` (12 bytes a texel) or its
    /// distance as a 16-bit float, `depth16` (2 bytes; the default).
    #[arg(long, value_enum)]
    pub vpl_format: Option<VplFormatArg>,
    /// Also cast a shadow ray for every map decision and count those it contradicts
    /// (wrong-visibility pixels, in the stats; these rays are not counted as frame rays).
    #[arg(long)]
    pub check_visibility: bool,
}

/// Parses render flags alone (for `hyrt sweep` and `hyrt bench`).
#[derive(Parser, Debug)]
#[command(no_binary_name = true)]
struct KnobParser {
    #[command(flatten)]
    knobs: Knobs,
}

impl Knobs {
    /// The knobs of render flags, e.g. `["--preset", "hybrid", "--shadow-map-res", "512"]`;
    /// clap's message (naming the flag) on error.
    pub fn from_flags<S: AsRef<str>>(flags: &[S]) -> Result<Knobs> {
        let args = flags.iter().map(|f| f.as_ref().to_string());
        KnobParser::try_parse_from(args)
            .map(|p| p.knobs)
            .map_err(|e| anyhow::anyhow!("{}", e.render().to_string().trim_end()))
    }

    /// The options these flags select for `scene`: a scene with an `[indirect]` table gets its
    /// VPL settings and indirect light (by rays under the reference preset, by maps under the
    /// hybrid one) unless `--indirect` says otherwise; flags override the scene's values.
    pub fn options_for(&self, scene: &scene::Scene) -> Result<Options> {
        let mut k = self.clone();
        if let Some(ind) = scene.indirect {
            k.vpls = k.vpls.or(Some(ind.vpls));
            k.vpl_bounces = k.vpl_bounces.or(Some(ind.bounces));
            k.vpl_seed = k.vpl_seed.or(Some(ind.seed));
            k.vpl_clamp = k.vpl_clamp.or(ind.clamp);
        }
        k.options()
    }

    /// The options these flags select.
    pub fn options(&self) -> Result<Options> {
        let mut o = match self.preset.unwrap_or(PresetArg::Reference) {
            PresetArg::Reference => Options::reference(),
            PresetArg::Hybrid => Options::hybrid(),
        };
        if let Some(v) = self.visibility {
            o.visibility = match v {
                VisibilityArg::Rays => Visibility::Rays,
                VisibilityArg::Raster => Visibility::Raster,
            };
        }
        if let Some(s) = self.shadows {
            o.shadows = match s {
                ShadowsArg::Rays => Shadows::Rays,
                ShadowsArg::Maps => Shadows::Maps,
                ShadowsArg::Smerts => Shadows::Smerts,
            };
        }
        let sh = &mut o.shadow;
        if let Some(k) = self.shadow_map {
            sh.map.kind = match k {
                MapKindArg::Cube => MapKind::Cube,
                MapKindArg::Paraboloid => MapKind::Paraboloid,
            };
        }
        if let Some(n) = self.shadow_map_res {
            sh.map.resolution = n;
        }
        if let Some(b) = self.bias {
            if !(b >= 0.0 && b.is_finite()) {
                bail!("--bias must be a finite number >= 0, got {b}");
            }
            sh.bias = b;
        }
        if let Some(b) = self.borders {
            sh.borders = match b {
                BordersArg::Laplacian => Borders::Laplacian,
                BordersArg::Depth => Borders::Depth,
                BordersArg::Both => Borders::Both,
            };
        }
        if let Some(r) = self.dilate {
            sh.dilate = r;
        }
        if let Some(t) = self.tess {
            if t.is_nan() || t <= 0.0 {
                bail!("--tess must be > 0 (or inf), got {t}");
            }
            sh.map.tess_texels = t;
        }
        if let Some(m) = self.mirror_shadows {
            sh.mirror = match m {
                MirrorArg::Maps => MirrorShadows::Maps,
                MirrorArg::Rays => MirrorShadows::Rays,
            };
        }
        let io = &mut o.indirect_opts;
        if let Some(n) = self.vpls {
            io.vpl.paths = n;
        }
        if let Some(b) = self.vpl_bounces {
            io.vpl.bounces = b;
        }
        if let Some(sd) = self.vpl_seed {
            io.vpl.seed = sd;
        }
        if let Some(c) = self.vpl_clamp {
            if !(c >= 0.0 && c.is_finite()) {
                bail!("--vpl-clamp must be a finite number >= 0, got {c}");
            }
            io.clamp = c;
        }
        if let Some(n) = self.vpl_map_res {
            io.map.resolution = n;
        }
        if let Some(t) = self.vpl_tess {
            if t.is_nan() || t <= 0.0 {
                bail!("--vpl-tess must be > 0 (or inf), got {t}");
            }
            io.map.tess_texels = t;
        }
        if let Some(k) = self.interleave {
            io.interleave = k;
        }
        if let Some(f) = self.vpl_format {
            io.format = match f {
                VplFormatArg::Planes => VplFormat::Planes,
                VplFormatArg::Depth16 => VplFormat::Depth16,
            };
        }
        if let Some(f) = self.vpl_filter {
            io.filter = match f {
                VplFilterArg::Texel => VplFilter::Texel,
                VplFilterArg::Bilinear => VplFilter::Bilinear,
            };
        }
        if let Some(b) = self.vpl_bias {
            if !(b >= 0.0 && b.is_finite()) {
                bail!("--vpl-bias must be a finite number >= 0, got {b}");
            }
            io.bias = b;
        }
        o.indirect = match (self.indirect, self.vpls) {
            (Some(IndirectArg::None), _) => Indirect::None,
            (Some(IndirectArg::Rays), _) => Indirect::Rays,
            (Some(IndirectArg::Maps), _) => Indirect::Maps,
            (None, Some(_)) if self.preset == Some(PresetArg::Hybrid) => Indirect::Maps,
            (None, Some(_)) => Indirect::Rays,
            (None, None) => Indirect::None,
        };
        o.check_visibility = self.check_visibility;
        Ok(o)
    }
}

/// The options as JSON, for the stats.
pub fn options_json(o: &Options, max_depth: u32) -> serde_json::Value {
    let sh = &o.shadow;
    serde_json::json!({
        "visibility": o.visibility.name(),
        "shadows": o.shadows.name(),
        "shadow_map": match sh.map.kind { MapKind::Cube => "cube", MapKind::Paraboloid => "paraboloid" },
        "shadow_map_res": sh.map.resolution,
        "bias": sh.bias,
        "borders": sh.borders.name(),
        "dilate": sh.dilate,
        "tess": if sh.map.tess_texels.is_finite() { serde_json::json!(sh.map.tess_texels) } else { serde_json::json!("inf") },
        "mirror_shadows": match sh.mirror { MirrorShadows::Maps => "maps", MirrorShadows::Rays => "rays" },
        "indirect": o.indirect.name(),
        "vpls": o.indirect_opts.vpl.paths,
        "vpl_bounces": o.indirect_opts.vpl.bounces,
        "vpl_seed": o.indirect_opts.vpl.seed,
        "vpl_clamp": o.indirect_opts.clamp,
        "vpl_map_res": o.indirect_opts.map.resolution,
        "vpl_tess": if o.indirect_opts.map.tess_texels.is_finite() { serde_json::json!(o.indirect_opts.map.tess_texels) } else { serde_json::json!("inf") },
        "vpl_bias": o.indirect_opts.bias,
        "vpl_filter": o.indirect_opts.filter.name(),
        "vpl_format": o.indirect_opts.format.name(),
        "interleave": o.indirect_opts.interleave,
        "max_depth": max_depth,
    })
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum VplFilterArg {
    Texel,
    Bilinear,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum VplFormatArg {
    Planes,
    Depth16,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PresetArg {
    Reference,
    Hybrid,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum VisibilityArg {
    Rays,
    Raster,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ShadowsArg {
    Rays,
    Maps,
    Smerts,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MapKindArg {
    Cube,
    Paraboloid,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BordersArg {
    Laplacian,
    Depth,
    Both,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IndirectArg {
    None,
    Rays,
    Maps,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MirrorArg {
    Maps,
    Rays,
}

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

/// Parses `WxH` (e.g. `640x480`) for clap.
pub fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WxH, e.g. 640x480, got '{s}'"))?;
    let p =
        |v: &str| v.trim().parse::<u32>().map_err(|_| format!("expected WxH with whole numbers, got '{s}'"));
    Ok((p(w)?, p(h)?))
}

/// Loads a scene (a built-in name, a scene file or a mesh file) with the command line's
/// overrides of its image size, mirror depth and exposure, and validates the result.
pub fn load_scene(
    name: &str,
    size: Option<(u32, u32)>,
    max_depth: Option<u32>,
    exposure: Option<f32>,
) -> Result<scene::Scene> {
    let mut scene = scene::load(name)?;
    let s = &mut scene.settings;
    if let Some((w, h)) = size {
        (s.width, s.height) = (w, h);
    }
    s.max_depth = max_depth.unwrap_or(s.max_depth);
    s.exposure = exposure.unwrap_or(s.exposure);
    scene.validate()?;
    Ok(scene)
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
    let scene = load_scene(&a.scene, a.size, a.max_depth, a.exposure)?;
    let png = match (&a.output, &a.exr) {
        (Some(p), _) => Some(p.clone()),
        (None, Some(_)) => None,
        (None, None) => Some(PathBuf::from(format!("{}.png", scene.name))),
    };
    // Refuse before rendering if the outputs cannot all be written.
    let outputs: Vec<&Path> = png.iter().chain(&a.exr).chain(&a.stats).map(PathBuf::as_path).collect();
    output::check_outputs(&outputs)?;

    let options = a.knobs.options_for(&scene)?;
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

    say(format!("this frame:\n{}", crate::plan::format_decisions(&frame.stats.decisions).trim_end()));
    let r = &frame.stats.rays;
    let times: Vec<String> = frame.stats.time_ms.iter().map(|(k, v)| format!("{k} {v:.1}")).collect();
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
    for (l, s) in frame.stats.lights.iter().enumerate() {
        let wrong = match (s.wrong, s.wrong_hint, s.wrong_traversal) {
            (Some(m), Some(h), Some(t)) => {
                format!(", wrong: {m} by the map, {h} by a hint, {t} by a traversal")
            }
            _ => String::new(),
        };
        say(format!(
            "light {l}: {} lit, {} shadowed, {} undecided (rays){wrong}; {} map face(s)",
            s.lit, s.shadowed, s.undecided, s.faces_drawn
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
        let opts = options_json(&options, scene.settings.max_depth);
        let mut stats = RenderStats::new(&scene, &renderer.plan, opts, &frame.stats, renderer.bvh_build_ms());
        if options.visibility == Visibility::Raster {
            stats = stats.with_raster(renderer.raster_stats());
        }
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
    let scene = load_scene(&a.scene, a.size, a.max_depth, None)?;
    let options = a.knobs.options_for(&scene)?;
    if !a.frames {
        let plan = crate::plan::Plan::new(&scene, &options);
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
    let passes = |s: &crate::render::FrameStats| {
        let mut p: Vec<&str> = s.time_ms.keys().copied().filter(|k| *k != "total").collect();
        p.sort_by_key(|n| crate::render::Pass::rank(n));
        p
    };
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
                    "rays": crate::measure::RayCountsJson::from(s.rays),
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
        print!("{}", crate::plan::format_decisions(&s.decisions));
        println!(
            "  rays: primary {} shadow {} specular {} vpl_shadow {} vpl_path {}; light maps built {}",
            r.primary, r.shadow, r.specular, r.vpl_shadow, r.vpl_path, s.maps_built
        );
    }
    Ok(())
}
