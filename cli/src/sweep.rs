//! `hyrt sweep`: render every combination of some knobs' values, measure each one's frame time
//! and error against a reference, and find the Pareto front of error against time.
//!
//! Every combination is the base flags (`--base`, default `--preset hybrid`) followed by
//! `--NAME=VALUE` for each knob, parsed exactly as `hyrt render` parses its flags
//! ([`Knobs::from_flags`], then [`Knobs::options_for`] the scene). All knob names and values,
//! and every combination, are checked before anything is rendered or written.
//!
//! Measuring ([`crate::measure::measure`]): the reference is measured first (one warm-up frame,
//! then `--runs` timed frames; its last frame is the reference film), then each combination in
//! turn, its frames alternated with the reference's (a warm-up frame each, which builds the
//! maps, then `--runs` timed frames of both, then for map-based shadows one untimed frame with
//! a shadow ray per map decision that counts wrong-visibility pixels). The warm-up frame is on
//! a fresh renderer, so its wall time with the renderer's creation is what one image of the
//! configuration costs from scratch (`first_frame_ms`: BVH build, map building and the frame,
//! scene loading excluded; [`crate::measure::cold_first_frame`], as `hyrt render
//! --vs-reference` measures it). Memory: `light_map_mb`, the light maps of the last frame
//! (`LightStats::map_bytes` summed over the lights, in 2^20 bytes). A combination's speed-up
//! is the reference's median over those alternated frames divided by its own: measured side by
//! side, so that a machine whose load drifts during a long sweep (shared machines do) moves
//! both alike. It costs twice the frames. Combinations are not alternated with each other:
//! their maps can be large (2048x2048 cube maps take about 1 GB per scene) and only one set is
//! alive at once; so compare two combinations by their speed-ups rather than their times.
//!
//! Error: PSNR of display luminance ([`crate::measure::psnr`]), the mean FLIP error
//! ([`crate::flip::flip_mean`]), and wrong-visibility pixels and (pixel, light) pairs. The
//! Pareto front ([`crate::plot::pareto_front`]) is over (median frame ms, PSNR), both rounded to
//! the 3 decimals the CSV shows, so it can be recomputed from the CSV exactly.
//!
//! Output in `--out`: `sweep.csv`, `sweep.json` (both rewritten after every combination, so an
//! interrupted sweep keeps what it measured), `sweep.png` (PSNR against frame time, front
//! marked), `sweep-first-frame.png` (PSNR against first-frame time, labels with the light maps'
//! memory, that plot's own front marked) and `README.md` (the command line and a table sorted
//! by time); with `--images`, `images/` holds each film as PNG and EXR.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;

use hyrt::{
    film::Film,
    metrics::DisplayImage,
    options::{Knobs, parse_size},
    output::atomic_write,
    render::{Indirect, Options, Shadows},
    scene::Scene,
};

use crate::{
    flip::flip_mean,
    measure::{Config, MeasureOptions, Measurement, measure},
    plot,
    report::{Table, csv_records},
};

/// `hyrt sweep` arguments.
#[derive(Args, Debug)]
pub struct SweepArgs {
    /// A built-in scene name (`cornell`), a `.toml` scene file, or a mesh file (as for
    /// `render`).
    pub scene: String,
    /// A knob to sweep: a render flag's name without `--` and its values, e.g.
    /// `shadow-map-res=256,512,1024`. Repeat for more knobs: every combination is rendered.
    /// On/off flags (`check-visibility`) cannot be swept.
    #[arg(long = "knob", value_name = "NAME=V1,V2,...", required = true)]
    pub knobs: Vec<String>,
    /// Output directory (created if missing; files in it are replaced).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Image size, overriding the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Timed frames per configuration (after one warm-up frame); the median is reported.
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
    /// Render flags every combination starts from (split on whitespace); each combination
    /// appends `--NAME=VALUE` for every knob.
    #[arg(long, value_name = "FLAGS", default_value = "--preset hybrid", allow_hyphen_values = true)]
    pub base: String,
    /// Render flags of the reference that errors are measured against (its film is rendered
    /// once; its frames are alternated with each combination's, and the speed-ups are
    /// measured side by side).
    ///
    /// When the base flags or any knob turn indirect light on and these flags set neither
    /// `--indirect` nor `--vpls`, the reference gets `--indirect rays` with the same VPLs
    /// (`--vpls`, `--vpl-bounces`, `--vpl-seed`, `--vpl-clamp`) as the first such combination,
    /// so that the error measures the approximations rather than a different set of VPLs.
    /// (When a knob changes the VPLs themselves, the others are measured against those of the
    /// first combination; set `--reference` to choose.)
    #[arg(long, value_name = "FLAGS", default_value = "--preset reference", allow_hyphen_values = true)]
    pub reference: String,
    /// Also write every configuration's image to `DIR/images/` as PNG and as EXR (with exposure
    /// 1, `hyrt compare` of two EXRs gives exactly the PSNR of the CSV).
    #[arg(long)]
    pub images: bool,
    /// Rayon worker threads (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,
}

/// One swept knob: a render flag (long name without `--`) and its values, as given.
#[derive(Clone, Debug, PartialEq)]
pub struct Knob {
    pub name: String,
    pub values: Vec<String>,
}

/// The render flags that take a value (sweepable), and the on/off ones, by long name.
fn render_flags() -> (Vec<String>, Vec<String>) {
    let cmd = <Knobs as clap::Args>::augment_args(clap::Command::new("knobs"));
    let (mut valued, mut switches) = (Vec::new(), Vec::new());
    for a in cmd.get_arguments() {
        if let Some(long) = a.get_long() {
            if a.get_action().takes_values() {
                valued.push(long.to_string())
            } else {
                switches.push(long.to_string())
            }
        }
    }
    (valued, switches)
}

/// Parses the `--knob NAME=V1,V2,...` arguments: names must be render flags that take a value,
/// each given once, with a non-empty list of distinct, non-empty values.
pub fn parse_knobs(specs: &[String]) -> Result<Vec<Knob>> {
    let (valued, switches) = render_flags();
    let mut knobs: Vec<Knob> = Vec::new();
    for spec in specs {
        let Some((name, list)) = spec.split_once('=') else {
            bail!("--knob '{spec}': expected NAME=V1,V2,..., e.g. shadow-map-res=256,512,1024");
        };
        let name = name.trim().trim_start_matches("--");
        if name.is_empty() {
            bail!("--knob '{spec}': no knob name before '='");
        }
        if switches.iter().any(|s| s == name) {
            bail!("knob '{name}' is an on/off flag and cannot be swept (put --{name} in --base instead)");
        }
        if !valued.iter().any(|v| v == name) {
            bail!("unknown knob '{name}' (--knob '{spec}'): not a render flag; knobs: {}", valued.join(", "));
        }
        if list.trim().is_empty() {
            bail!("knob '{name}': no values after '=' (--knob '{spec}')");
        }
        let values: Vec<String> = list.split(',').map(|v| v.trim().to_string()).collect();
        if let Some(i) = values.iter().position(|v| v.is_empty()) {
            bail!("knob '{name}': value {} is empty (--knob '{spec}')", i + 1);
        }
        for (i, v) in values.iter().enumerate() {
            if values[..i].contains(v) {
                bail!("knob '{name}': value '{v}' is listed twice");
            }
        }
        if knobs.iter().any(|k| k.name == name) {
            bail!("knob '{name}' is given twice: list all its values in one --knob");
        }
        knobs.push(Knob { name: name.to_string(), values });
    }
    Ok(knobs)
}

/// Every combination of the knobs' values (the first knob varies slowest), as value indices.
pub fn combinations(knobs: &[Knob]) -> Vec<Vec<usize>> {
    knobs.iter().fold(vec![Vec::new()], |acc, k| {
        acc.iter()
            .flat_map(|c| {
                (0..k.values.len()).map(move |i| {
                    let mut c = c.clone();
                    c.push(i);
                    c
                })
            })
            .collect()
    })
}

/// The first line of an error from [`Knobs::from_flags`] or [`Knobs::options_for`], without
/// clap's `error: ` prefix and its hint to try `--help`.
fn flag_error(e: &anyhow::Error) -> String {
    let s = format!("{e:#}");
    let first = s.lines().next().unwrap_or("").trim();
    first.strip_prefix("error: ").unwrap_or(first).to_string()
}

/// Render flags split as a POSIX shell splits words (quotes and escapes included), so that
/// `--base` reads as the same flags on the command line would.
fn split_flags(what: &str, s: &str) -> Result<Vec<String>> {
    shlex::split(s).ok_or_else(|| anyhow!("{what} '{s}': unbalanced quotes or a trailing backslash"))
}

/// Whether `flags` set the render flag `--name` (as `--name V` or `--name=V`).
fn sets(flags: &[String], name: &str) -> bool {
    let long = format!("--{name}");
    flags.iter().any(|f| *f == long || f.starts_with(&format!("{long}=")))
}

/// A combination ready to measure.
struct Combo {
    /// Knob values, in knob order.
    values: Vec<String>,
    label: String,
    flags: Vec<String>,
    options: Options,
}

/// A measured configuration (the reference or a combination).
struct Row {
    values: Vec<String>,
    label: String,
    flags: Vec<String>,
    options: Options,
    m: Measurement,
    /// Mean FLIP error against the reference (0 for the reference itself).
    flip: f64,
    /// The reference's median frame time over the frames alternated with this row's, and
    /// the ratio of it to this row's median.
    ref_ms: f64,
    speedup: f64,
    /// Relative to the output directory, with `--images`.
    image: Option<String>,
}

impl Row {
    /// Median frame ms and PSNR as the CSV shows them (3 decimals): the Pareto front's inputs.
    fn front_point(&self) -> (f64, f64) {
        (round3(self.m.frame_ms.median), round3(self.m.psnr_db.unwrap_or(f64::NAN)))
    }

    /// First-frame ms and PSNR as the CSV shows them: the first-frame plot's front.
    fn first_frame_point(&self) -> (f64, f64) {
        (round3(self.m.cold_first_frame_ms), round3(self.m.psnr_db.unwrap_or(f64::NAN)))
    }

    /// The light maps' memory in MB (2^20 bytes).
    fn light_map_mb(&self) -> f64 {
        self.m.light_map_bytes as f64 / f64::from(1 << 20)
    }
}

/// To the 3 decimals of the CSV (non-finite values unchanged).
fn round3(v: f64) -> f64 {
    if v.is_finite() { (v * 1e3).round() / 1e3 } else { v }
}

/// Runs `hyrt sweep`.
pub fn run(a: &SweepArgs) -> Result<()> {
    // Everything is checked before anything is rendered or written.
    let knobs = parse_knobs(&a.knobs)?;
    let base = split_flags("--base", &a.base)?;
    for k in &knobs {
        if sets(&base, &k.name) {
            bail!("knob '{}' is also set in --base '{}': set it in one place only", k.name, a.base);
        }
    }
    let scene =
        crate::cli::load_scene(&a.scene, hyrt::scene::Overrides { size: a.size, ..Default::default() })?;
    let options_of = |flags: &[String]| -> Result<Options> { Knobs::from_flags(flags)?.options_for(&scene) };
    options_of(&base).map_err(|e| anyhow!("--base '{}': {}", a.base, flag_error(&e)))?;
    for k in &knobs {
        for v in &k.values {
            let mut flags = base.clone();
            flags.push(format!("--{}={v}", k.name));
            options_of(&flags).map_err(|e| anyhow!("knob '{}', value '{v}': {}", k.name, flag_error(&e)))?;
        }
    }
    let mut combos = Vec::new();
    for c in combinations(&knobs) {
        let values: Vec<String> = c.iter().zip(&knobs).map(|(&i, k)| k.values[i].clone()).collect();
        let label =
            knobs.iter().zip(&values).map(|(k, v)| format!("{}={v}", k.name)).collect::<Vec<_>>().join(" ");
        let mut flags = base.clone();
        flags.extend(knobs.iter().zip(&values).map(|(k, v)| format!("--{}={v}", k.name)));
        let options = options_of(&flags).map_err(|e| anyhow!("{label}: {}", flag_error(&e)))?;
        combos.push(Combo { values, label, flags, options });
    }
    let (ref_flags, vpls_from) = reference_flags(&a.reference, &combos)?;
    let ref_options =
        options_of(&ref_flags).map_err(|e| anyhow!("--reference '{}': {}", a.reference, flag_error(&e)))?;

    if a.out.exists() && !a.out.is_dir() {
        bail!("--out {}: exists and is not a directory", a.out.display());
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("--out {}: cannot create", a.out.display()))?;
    let images = a.out.join("images");
    if a.images {
        std::fs::create_dir_all(&images).with_context(|| format!("{}: cannot create", images.display()))?;
    }

    let runs = a.runs as usize;
    let frames = |o: &Options| (1 + runs + usize::from(o.shadows != Shadows::Rays)) as u64;
    // Each combination's frames come with as many of the reference's.
    let total = frames(&ref_options) * (1 + combos.len() as u64)
        + combos.iter().map(|c| frames(&c.options)).sum::<u64>();
    let bar = crate::cli::progress_bar(total, "frames", false);
    let say = |s: String| bar.suspend(|| eprintln!("{s}"));
    let progress = |label: &str| {
        bar.set_message(label.to_string());
        bar.inc(1);
    };
    say(format!(
        "{}: {}x{}, {} threads; {} configuration(s) x ({runs} timed + 1 warm-up frame), reference '{}'{}",
        scene.name,
        scene.settings.width,
        scene.settings.height,
        rayon::current_num_threads(),
        combos.len(),
        ref_flags.join(" "),
        vpls_from.as_ref().map_or(String::new(), |l| format!(" (VPLs of {l})"))
    ));
    if let Some(l) = &vpls_from {
        let vpls = |o: &Options| (o.indirect_opts.vpl, o.indirect_opts.clamp.to_bits());
        let first = combos.iter().find(|c| c.label == *l).map(|c| vpls(&c.options));
        if combos.iter().any(|c| c.options.indirect != Indirect::None && Some(vpls(&c.options)) != first) {
            say(format!(
                "note: the configurations' VPLs differ; the reference has those of {l}, so the others' \
                 errors include the change of VPLs (set --reference to choose the reference's)"
            ));
        }
    }

    let mo = MeasureOptions { runs, check: true, same_rays: false };
    let exposure = scene.settings.exposure;
    let ref_config = Config { label: "reference".into(), options: ref_options, scene: None };
    let mut m = measure(&scene, std::slice::from_ref(&ref_config), None, mo, &progress)?.remove(0);
    m.psnr_db = Some(f64::INFINITY);
    let ref_film = std::mem::replace(&mut m.film, Film::new(0, 0));
    let ref_display = DisplayImage::from_film(&ref_film, exposure);
    let mut reference = Row {
        values: Vec::new(),
        label: "reference".into(),
        flags: ref_flags.clone(),
        options: ref_options,
        m,
        flip: 0.0,
        ref_ms: 0.0,
        speedup: 1.0,
        image: None,
    };
    if a.images {
        reference.image = Some(write_images(&images, "reference", &ref_film, exposure)?);
    }
    let ref_ms = reference.m.frame_ms.median;
    reference.ref_ms = ref_ms;
    say(format!("reference: {} ms", fmt_ms(ref_ms)));

    let ctx =
        Sweep { a, scene: &scene, knobs: &knobs, ref_flags: &ref_flags, vpls_from: vpls_from.as_deref() };
    let mut rows: Vec<Row> = Vec::new();
    let n = combos.len();
    for (i, c) in combos.into_iter().enumerate() {
        let config = Config { label: c.label.clone(), options: c.options, scene: None };
        let mut pair = measure(&scene, &[ref_config.clone(), config], None, mo, &progress)?;
        let mut m = pair.remove(1);
        let side_by_side_ref_ms = pair[0].frame_ms.median;
        let film = std::mem::replace(&mut m.film, Film::new(0, 0));
        m.psnr_db = Some(crate::measure::psnr(&scene, &ref_film, &film)?);
        let flip = flip_mean(&ref_display, &DisplayImage::from_film(&film, exposure))?;
        let image = if a.images {
            let name = format!("{:02}_{}", i + 1, file_stem(&c.label));
            Some(write_images(&images, &name, &film, exposure)?)
        } else {
            None
        };
        let speedup =
            if m.frame_ms.median > 0.0 { side_by_side_ref_ms / m.frame_ms.median } else { f64::NAN };
        let row = Row {
            values: c.values,
            label: c.label,
            flags: c.flags,
            options: c.options,
            m,
            flip,
            ref_ms: side_by_side_ref_ms,
            speedup,
            image,
        };
        say(format!("[{}/{n}] {}", i + 1, one_line(&row)));
        rows.push(row);
        write_tables(&ctx, &reference, &rows)?;
    }
    bar.finish_and_clear();

    let front = front_of(&rows);
    let text = match plot::register_font() {
        Ok(p) => {
            if let Some(f) = std::env::var_os("HYRT_FONT").filter(|f| !f.is_empty() && Path::new(f) != p) {
                eprintln!(
                    "warning: HYRT_FONT {} is not a usable font; using {}",
                    f.to_string_lossy(),
                    p.display()
                );
            }
            true
        }
        Err(tried) => {
            eprintln!("warning: no font for the plot's text (tried {tried}); drawing it without text");
            false
        }
    };
    // Few points: label them all; many: only the front's, or the plot is unreadable.
    let points = |front: &[bool], x: &dyn Fn(&Row) -> f64, label: &dyn Fn(&Row) -> String| {
        rows.iter()
            .zip(front)
            .map(|(r, &f)| plot::Point {
                x: x(r),
                y: r.m.psnr_db.unwrap_or(f64::NAN),
                label: if rows.len() <= 12 || f { label(r) } else { String::new() },
                front: f,
            })
            .collect::<Vec<_>>()
    };
    let names: Vec<&str> = knobs.iter().map(|k| k.name.as_str()).collect();
    let title = |against: &str, labels: &str| {
        format!(
            "{} {}x{}: PSNR against {against} (labels: {labels})",
            scene.name, scene.settings.width, scene.settings.height
        )
    };
    let y_name = "PSNR of luminance vs reference (dB)";
    let png = a.out.join("sweep.png");
    plot::write_png(
        &png,
        &plot::Plot {
            title: &title("frame time", &names.join(", ")),
            x_name: "median frame time (ms)",
            y_name,
            points: &points(&front, &|r| r.m.frame_ms.median, &|r| r.values.join(", ")),
            x_marker: Some((ref_ms, &format!("reference {} ms", fmt_ms(ref_ms)))),
            size: (1100, 750),
        },
        text,
    )?;
    // The same errors against what one image costs from scratch, and the light maps' memory.
    let first_front = plot::pareto_front(&rows.iter().map(Row::first_frame_point).collect::<Vec<_>>());
    let ref_first = reference.m.cold_first_frame_ms;
    let first_png = a.out.join("sweep-first-frame.png");
    plot::write_png(
        &first_png,
        &plot::Plot {
            title: &title("first-frame time", &format!("{}; light-map MB", names.join(", "))),
            x_name: "first frame on a fresh renderer, BVH and maps built (ms)",
            y_name,
            points: &points(&first_front, &|r| r.m.cold_first_frame_ms, &|r| {
                format!("{}; {:.1} MB", r.values.join(", "), r.light_map_mb())
            }),
            x_marker: Some((ref_first, &format!("reference {} ms", fmt_ms(ref_first)))),
            size: (1100, 750),
        },
        text,
    )?;
    let table = summary_table(&knobs, &reference, &rows);
    let readme = summary(&ctx, &reference, &table);
    let md = a.out.join("README.md");
    atomic_write(&md, |tmp| std::fs::write(tmp, readme.as_bytes()).map_err(Into::into))?;
    println!("{table}");
    eprintln!(
        "wrote {}, {}, {}, {}, {}{}",
        a.out.join("sweep.csv").display(),
        a.out.join("sweep.json").display(),
        png.display(),
        first_png.display(),
        md.display(),
        if a.images { format!(", {}/", images.display()) } else { String::new() }
    );
    Ok(())
}

/// What the output files say about the sweep as a whole.
struct Sweep<'c> {
    a: &'c SweepArgs,
    scene: &'c Scene,
    knobs: &'c [Knob],
    ref_flags: &'c [String],
    vpls_from: Option<&'c str>,
}

/// The reference's flags: `--reference`, plus the VPLs of the first combination with indirect
/// light when it has some and the reference flags choose none (see `SweepArgs::reference`).
/// Also the label of the combination whose VPLs were taken.
fn reference_flags(reference: &str, combos: &[Combo]) -> Result<(Vec<String>, Option<String>)> {
    let mut flags = split_flags("--reference", reference)?;
    let k =
        Knobs::from_flags(&flags).map_err(|e| anyhow!("--reference '{reference}': {}", flag_error(&e)))?;
    if k.given("indirect").is_some() || k.given("vpls").is_some() {
        return Ok((flags, None));
    }
    let Some(c) = combos.iter().find(|c| c.options.indirect != Indirect::None) else {
        return Ok((flags, None));
    };
    // The reference flags may set the other VPL knobs; the combination's values replace them.
    for name in ["vpl-bounces", "vpl-seed", "vpl-clamp"] {
        if sets(&flags, name) {
            bail!(
                "--reference '{reference}' sets --{name} but not --vpls: give the reference's VPLs in \
                 full (--indirect rays --vpls N ...) or leave them to the sweep"
            );
        }
    }
    let io = &c.options.indirect_opts;
    flags.extend([
        "--indirect=rays".to_string(),
        format!("--vpls={}", io.vpl.paths),
        format!("--vpl-bounces={}", io.vpl.bounces),
        format!("--vpl-seed={}", io.vpl.seed),
        format!("--vpl-clamp={}", io.clamp),
    ]);
    Ok((flags, Some(c.label.clone())))
}

/// A file name from a label: letters, digits, `.`, `-` and `_` kept, `=` as `-`, the rest `_`.
fn file_stem(label: &str) -> String {
    label
        .chars()
        .map(|c| match c {
            '=' => '-',
            c if c.is_ascii_alphanumeric() || ".-_".contains(c) => c,
            _ => '_',
        })
        .collect()
}

/// Writes `images/NAME.png` and `images/NAME.exr`; returns `images/NAME.png`.
fn write_images(dir: &Path, name: &str, film: &Film, exposure: f32) -> Result<String> {
    film.write_png(&dir.join(format!("{name}.png")), exposure)?;
    film.write_exr(&dir.join(format!("{name}.exr")))?;
    Ok(format!("images/{name}.png"))
}

fn front_of(rows: &[Row]) -> Vec<bool> {
    plot::pareto_front(&rows.iter().map(Row::front_point).collect::<Vec<_>>())
}

/// Milliseconds to about 3 significant digits (1 decimal from 10 ms up).
fn fmt_ms(v: f64) -> String {
    if v < 10.0 { format!("{v:.2}") } else { format!("{v:.1}") }
}

fn fmt_psnr(v: Option<f64>) -> String {
    match v {
        Some(v) if v.is_infinite() => "inf".into(),
        Some(v) => format!("{v:.3}"),
        None => String::new(),
    }
}

fn fmt_opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

/// A per-configuration progress line.
fn one_line(r: &Row) -> String {
    let m = &r.m;
    let wrong = m.wrong_pixels.map_or(String::new(), |w| format!(", {w} wrong px"));
    let maps = if m.map_bytes > 0 {
        format!(", maps {:.0} ms / {:.0} MB", m.map_build_ms, m.map_bytes as f64 / 1e6)
    } else {
        String::new()
    };
    format!(
        "{}: {} ms ({:.2}x), first frame {} ms, PSNR {} dB, FLIP {:.4}{wrong}{maps}",
        r.label,
        fmt_ms(m.frame_ms.median),
        r.speedup,
        fmt_ms(m.cold_first_frame_ms),
        fmt_psnr(m.psnr_db),
        r.flip
    )
}

const CSV_COLUMNS: [&str; 17] = [
    "frame_ms_median",
    "frame_ms_min",
    "frame_ms_max",
    "reference_ms_side_by_side",
    "speedup_vs_reference",
    "psnr_db",
    "flip_mean",
    "wrong_pixels",
    "wrong_pairs",
    "map_build_ms",
    "first_frame_ms",
    "map_mb",
    "light_map_mb",
    "shadow_rays",
    "vpl_shadow_rays",
    "total_rays",
    "pareto",
];

/// The CSV: a `config` column (`reference`, or the configuration's number), one column per
/// knob, then the measurements; the reference first (its knob columns empty).
fn csv(knobs: &[Knob], reference: &Row, rows: &[Row]) -> Result<String> {
    let front = front_of(rows);
    let mut header = vec!["config".to_string()];
    header.extend(knobs.iter().map(|k| k.name.clone()));
    header.extend(CSV_COLUMNS.iter().map(|s| s.to_string()));
    let line = |id: String, r: &Row, pareto: bool| {
        let m = &r.m;
        let (median, _) = r.front_point();
        let mut f = vec![id];
        f.extend(if r.values.is_empty() { vec![String::new(); knobs.len()] } else { r.values.clone() });
        f.extend([
            // All three through `round3` (the median is the front's): formatting the min and max
            // straight would round a value equal to the median the other way, now and then.
            format!("{median:.3}"),
            format!("{:.3}", round3(m.frame_ms.min)),
            format!("{:.3}", round3(m.frame_ms.max)),
            format!("{:.3}", r.ref_ms),
            format!("{:.4}", r.speedup),
            fmt_psnr(m.psnr_db),
            format!("{:.6}", r.flip),
            fmt_opt(m.wrong_pixels),
            fmt_opt(m.wrong_pairs),
            format!("{:.3}", m.map_build_ms),
            format!("{:.3}", m.cold_first_frame_ms),
            format!("{:.3}", m.map_bytes as f64 / 1e6),
            format!("{:.3}", r.light_map_mb()),
            m.rays.shadow.to_string(),
            m.rays.vpl_shadow.to_string(),
            m.rays.total().to_string(),
            pareto.to_string(),
        ]);
        f
    };
    let mut records = vec![line("reference".into(), reference, false)];
    records.extend(rows.iter().zip(&front).enumerate().map(|(i, (r, &p))| line((i + 1).to_string(), r, p)));
    csv_records(&header, &records)
}

/// `inf` PSNR as the string "inf" (JSON has no infinity).
fn measurement_json(m: &Measurement) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(m)?;
    if m.psnr_db.is_some_and(f64::is_infinite) {
        v["psnr_db"] = "inf".into();
    }
    Ok(v)
}

fn json(ctx: &Sweep, reference: &Row, rows: &[Row]) -> Result<serde_json::Value> {
    let front = front_of(rows);
    let max_depth = ctx.scene.settings.max_depth;
    let row = |r: &Row, pareto: Option<bool>| -> Result<serde_json::Value> {
        let knobs: serde_json::Map<String, serde_json::Value> =
            ctx.knobs.iter().zip(&r.values).map(|(k, v)| (k.name.clone(), v.clone().into())).collect();
        Ok(serde_json::json!({
            "label": r.label,
            "knobs": knobs,
            "flags": r.flags,
            "options": hyrt::options::to_json(&r.options, max_depth),
            "measurement": measurement_json(&r.m)?,
            "reference_ms_side_by_side": r.ref_ms,
            "speedup_vs_reference": r.speedup,
            "flip_mean": r.flip,
            "pareto": pareto,
            "image": r.image,
        }))
    };
    Ok(serde_json::json!({
        "command": command_line(),
        "scene": ctx.scene.name,
        "width": ctx.scene.settings.width,
        "height": ctx.scene.settings.height,
        "runs": ctx.a.runs,
        "threads": rayon::current_num_threads(),
        "base_flags": split_flags("--base", &ctx.a.base)?,
        "reference_flags": ctx.ref_flags,
        "reference_vpls_from": ctx.vpls_from,
        "knobs": ctx.knobs.iter().map(|k| serde_json::json!({"name": k.name, "values": k.values})).collect::<Vec<_>>(),
        "flip_pixels_per_degree": nv_flip::DEFAULT_PIXELS_PER_DEGREE,
        "reference": row(reference, None)?,
        "configs": rows.iter().zip(&front).map(|(r, &p)| row(r, Some(p))).collect::<Result<Vec<_>>>()?,
    }))
}

fn write_tables(ctx: &Sweep, reference: &Row, rows: &[Row]) -> Result<()> {
    let out = &ctx.a.out;
    let text = csv(ctx.knobs, reference, rows)?;
    atomic_write(&out.join("sweep.csv"), |tmp| std::fs::write(tmp, text.as_bytes()).map_err(Into::into))?;
    let j = serde_json::to_string_pretty(&json(ctx, reference, rows)?)?;
    atomic_write(&out.join("sweep.json"), |tmp| std::fs::write(tmp, j.as_bytes()).map_err(Into::into))
}

/// Markdown table of the reference and every configuration, fastest first, front marked.
fn summary_table(knobs: &[Knob], reference: &Row, rows: &[Row]) -> String {
    let front = front_of(rows);
    let mut all: Vec<(&Row, Option<bool>)> = vec![(reference, None)];
    all.extend(rows.iter().zip(front.iter().map(|&f| Some(f))));
    all.sort_by(|a, b| a.0.m.frame_ms.median.total_cmp(&b.0.m.frame_ms.median));
    let mut head: Vec<String> = knobs.iter().map(|k| k.name.clone()).collect();
    head.extend(
        [
            "frame ms",
            "min-max ms",
            "speed-up",
            "PSNR dB",
            "FLIP",
            "wrong px",
            "map build ms",
            "first frame ms",
            "map MB",
            "light map MB",
            "rays",
            "front",
        ]
        .map(String::from),
    );
    let mut t = Table::new(&head, knobs.len());
    for (r, f) in all {
        let m = &r.m;
        let mut cells: Vec<String> = if f.is_none() {
            let mut c = vec!["**reference**".to_string()];
            c.resize(knobs.len(), String::new());
            c
        } else {
            r.values.clone()
        };
        cells.extend([
            fmt_ms(m.frame_ms.median),
            format!("{}-{}", fmt_ms(m.frame_ms.min), fmt_ms(m.frame_ms.max)),
            format!("{:.2}x", r.speedup),
            m.psnr_db.map_or("-".into(), |v| if v.is_infinite() { "inf".into() } else { format!("{v:.2}") }),
            format!("{:.4}", r.flip),
            m.wrong_pixels.map_or("-".into(), |v| v.to_string()),
            if m.map_bytes > 0 { format!("{:.0}", m.map_build_ms) } else { "-".into() },
            format!("{:.0}", m.cold_first_frame_ms),
            if m.map_bytes > 0 { format!("{:.0}", m.map_bytes as f64 / 1e6) } else { "-".into() },
            if m.light_map_bytes > 0 { format!("{:.1}", r.light_map_mb()) } else { "-".into() },
            m.rays.total().to_string(),
            match f {
                Some(true) => "**front**".into(),
                _ => String::new(),
            },
        ]);
        t.row(cells);
    }
    t.markdown()
}

/// The output folder's README.md.
fn summary(ctx: &Sweep, reference: &Row, table: &str) -> String {
    let (a, s) = (ctx.a, ctx.scene);
    let knobs: Vec<String> =
        ctx.knobs.iter().map(|k| format!("`{}` = {}", k.name, k.values.join(", "))).collect();
    let vpls = ctx.vpls_from.map_or(String::new(), |l| format!(" (VPLs as in `{l}`)"));
    format!(
        "# Sweep: {name}, {w}x{h}\n\n\
         ```\n{cmd}\n```\n\n\
         - Knobs: {knobs}; each configuration is `{base}` followed by `--NAME=VALUE` per knob.\n\
         - Reference: `{reference}`{vpls}, {ref_ms} ms per frame.\n\
         - Frame time: median of {runs} frames after a warm-up frame; {threads} threads; each \
         configuration's frames alternated with the reference's, and its speed-up measured \
         against those (side by side).\n\
         - `first frame ms`: the warm-up frame on a fresh renderer, in wall time with the \
         renderer's creation: its BVH build, map building and frame (scene loading excluded), \
         what one image costs from scratch. `map MB`: light and VPL maps (10^6 bytes); \
         `light map MB`: the light maps alone (2^20 bytes).\n\
         - Error against the reference: PSNR of display luminance (higher is better), mean \
         FLIP (0 = identical, lower is better), `wrong px`: pixels whose map decision a shadow ray \
         contradicts, counted in an extra untimed frame.\n\
         - Pareto front (**front**): no other configuration is at least as fast and as accurate \
         (PSNR), and better in one. `rays`: all rays of one frame.\n\n\
         ![PSNR against frame time, Pareto front in red](sweep.png)\n\n\
         ![PSNR against first-frame time, labelled with the light maps' MB; that plot's front in \
         red](sweep-first-frame.png)\n\n\
         Fastest first:\n\n{table}\n\
         All numbers: `sweep.csv`, `sweep.json` (with every configuration's options).\n",
        name = s.name,
        w = s.settings.width,
        h = s.settings.height,
        cmd = command_line(),
        knobs = knobs.join("; "),
        base = a.base.split_whitespace().collect::<Vec<_>>().join(" "),
        reference = ctx.ref_flags.join(" "),
        ref_ms = fmt_ms(reference.m.frame_ms.median),
        runs = a.runs,
        threads = rayon::current_num_threads(),
    )
}

/// This process's command line, quoted for a POSIX shell, as `hyrt ...`.
fn command_line() -> String {
    let quote = |s: &str| {
        if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=,:+@%".contains(c)) {
            s.to_string()
        } else {
            format!("'{}'", s.replace('\'', "'\\''"))
        }
    };
    std::iter::once("hyrt".to_string())
        .chain(std::env::args().skip(1).map(|s| quote(&s)))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn specs(s: &[&str]) -> Vec<String> {
        s.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn knobs_parse_and_combine() {
        let k = parse_knobs(&specs(&["shadow-map-res=64, 256", "--bias=0.5,2,4"])).unwrap();
        assert_eq!(k[0], Knob { name: "shadow-map-res".into(), values: specs(&["64", "256"]) });
        assert_eq!(k[1].name, "bias");
        let c = combinations(&k);
        assert_eq!(c.len(), 6);
        assert_eq!((c[0].clone(), c[1].clone(), c[5].clone()), (vec![0, 0], vec![0, 1], vec![1, 2]));
        assert_eq!(combinations(&[]), vec![Vec::<usize>::new()]);
    }

    #[test]
    fn bad_knobs_are_named() {
        let err = |s: &[&str]| parse_knobs(&specs(s)).unwrap_err().to_string();
        assert!(err(&["colour=1,2"]).contains("unknown knob 'colour'"));
        assert!(err(&["bias"]).contains("--knob 'bias': expected NAME=V1,V2"));
        assert!(err(&["bias="]).contains("knob 'bias': no values"));
        assert!(err(&["bias=1,,2"]).contains("knob 'bias': value 2 is empty"));
        assert!(err(&["bias=1,1"]).contains("'1' is listed twice"));
        assert!(err(&["bias=1", "bias=2"]).contains("knob 'bias' is given twice"));
        assert!(err(&["check-visibility=1"]).contains("on/off flag"));
        assert!(err(&["=1"]).contains("no knob name"));
    }

    #[test]
    fn file_stems_keep_the_knob_values() {
        assert_eq!(file_stem("shadow-map-res=256 bias=0.5"), "shadow-map-res-256_bias-0.5");
    }
}
