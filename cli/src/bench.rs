//! `hyrt bench`: the thesis's tables 4.1 to 4.5, reproduced side by side with its figures.
//!
//! Per scene, seven configurations (render flags, listed in the output) are measured in one
//! process with their frames alternated ([`crate::measure`]): so every ratio in a table is
//! between frames rendered minutes apart at most, on the same machine state.
//!
//! | id | flags | used in |
//! |---|---|---|
//! | `rt` | `--preset reference` | 4.1 |
//! | `rt-raster` | `--preset reference --visibility raster` | 4.1, 4.2 (the thesis's reference for 4.2 used projection too) |
//! | `smerts-cube` | `--preset hybrid --shadow-map cube` | 4.2 |
//! | `smerts-para` | `--preset hybrid --shadow-map paraboloid` | 4.2 |
//! | `rt-vpl` | `--preset reference --indirect rays --vpls N` | 4.4, 4.5 |
//! | `vpl-maps` | `--preset reference --indirect maps --vpls N` | 4.4 |
//! | `hybrid-vpl` | `--preset hybrid --indirect maps --vpls N` | 4.5 |
//!
//! A scene with textures is also measured without them (`rt-untextured`, `smerts-untextured`:
//! `rt` and `smerts-cube` with every material's texture dropped, alternated with the others):
//! the difference is texture sampling's share of the frame, and the hybrid's speed-up with and
//! without textures says whether sampling costs it more than the reference.
//!
//! PSNR is on display luminance against `rt` (direct light) or `rt-vpl` (with indirect light).
//! Table 4.3 (SMeRTS on the thesis's GPU tracer) has no CPU counterpart and is not reproduced.

use std::{fmt::Write as _, path::PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use hyrt::{options::Knobs, output::atomic_write};

use crate::{
    measure::{self, Config, MeasureOptions, Measurement},
    report::{Table, csv_rows, round},
};

/// Arguments of `hyrt bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Scenes (names or scene files). Default: the three thesis scenes in `scenes/`.
    #[arg(value_name = "SCENE")]
    pub scenes: Vec<String>,
    /// Timed frames per configuration, after one warm-up frame that builds the maps.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
    /// VPL light paths for tables 4.4 and 4.5 (thesis: 45).
    #[arg(long, default_value_t = 45)]
    pub vpls: u32,
    /// Image size, overriding the scenes' (the thesis used 640x480).
    #[arg(long, value_name = "WxH", value_parser = crate::cli::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Output folder for `tables.md`, `results.csv` and `results.json`.
    #[arg(long, default_value = "bench-results")]
    pub out: PathBuf,
    /// Skip the untimed frames that count wrong-visibility pixels.
    #[arg(long)]
    pub no_check: bool,
    /// Rayon worker threads (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub threads: Option<u32>,
    /// Instead of the tables: N frames along an arc about each scene's target, reference and
    /// hybrid alternated, with the frame-time median and percentiles and the light-map faces
    /// each frame drew (`orbit.md`, `orbit.csv`; see `hyrt::orbit`).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..))]
    pub orbit: Option<u32>,
    /// Instead of the tables: each pass's warm-frame time on 1 thread and on `--threads` (all
    /// cores by default), the reference's and the hybrid's frames alternated, and its speed-up
    /// (`scaling.md`, `scaling.csv`; `--runs` frames per count).
    #[arg(long, conflicts_with = "orbit")]
    pub scaling: bool,
}

/// The configurations of every table: id and render flags (module docs).
fn configs(vpls: u32) -> Vec<(&'static str, String)> {
    let v = format!("--indirect rays --vpls {vpls}");
    let m = format!("--indirect maps --vpls {vpls}");
    vec![
        ("rt", "--preset reference".into()),
        ("rt-raster", "--preset reference --visibility raster".into()),
        ("smerts-cube", "--preset hybrid --shadow-map cube".into()),
        ("smerts-para", "--preset hybrid --shadow-map paraboloid".into()),
        ("rt-vpl", format!("--preset reference {v}")),
        ("vpl-maps", format!("--preset reference {m}")),
        ("hybrid-vpl", format!("--preset hybrid {m}")),
    ]
}

/// The configurations measured again without textures, on a textured scene: (of, id).
const UNTEXTURED: [(&str, &str); 2] = [("rt", "rt-untextured"), ("smerts-cube", "smerts-untextured")];

/// The thesis's figures (`docs/thesis.md`, tables 4.1, 4.2, 4.4, 4.5) for a scene of ours.
#[derive(Clone, Copy, Debug, Serialize)]
struct Thesis {
    name: &'static str,
    /// 4.1: fps ray traced, fps projection, total rays RT / projection.
    t41: (f64, f64, u64, u64),
    /// 4.2: fps reference, fps SMeRTS, PSNR, shadow rays reference / SMeRTS.
    t42: (f64, f64, f64, u64, u64),
    /// 4.4: fps reference, fps maps, PSNR, VPL shadow rays removed (GPU tracer).
    t44: Option<(f64, f64, f64, u64)>,
    /// 4.5: fps reference, fps hybrid, PSNR, total shadow rays reference / hybrid.
    t45: Option<(f64, f64, f64, u64, u64)>,
}

fn thesis(scene: &str) -> Option<Thesis> {
    match scene {
        "conference" => Some(Thesis {
            name: "conference",
            t41: (0.33, 0.48, 1_883_868, 1_528_242),
            t42: (0.48, 1.44, 26.55, 1_454_268, 317_616),
            t44: None,
            t45: None,
        }),
        "office" => Some(Thesis {
            name: "office",
            t41: (0.68, 0.78, 3_238_040, 2_879_503),
            t42: (0.78, 3.13, 19.29, 2_823_805, 503_185),
            t44: Some((3.37, 27.04, 42.86, 12_971_207)),
            t45: Some((3.37, 28.15, 37.45, 13_570_077, 31_100)),
        }),
        "cornell-bunny-mirror" => Some(Thesis {
            name: "CornellBox",
            t41: (2.82, 2.86, 2_414_082, 2_169_063),
            t42: (2.86, 4.75, 34.12, 1_908_247, 665_338),
            t44: Some((4.44, 56.62, 34.72, 12_225_116)),
            t45: Some((4.44, 38.71, 34.41, 12_530_271, 3_339)),
        }),
        _ => None,
    }
}

/// One scene's measurements.
#[derive(Serialize)]
struct SceneResult {
    scene: String,
    triangles: usize,
    lights: usize,
    width: u32,
    height: u32,
    flags: Vec<(String, String)>,
    configs: Vec<Measurement>,
    thesis: Option<Thesis>,
}

impl SceneResult {
    fn get(&self, id: &str) -> &Measurement {
        self.configs.iter().find(|m| m.label == id).expect("every configuration is measured")
    }
}

/// Runs `hyrt bench` (on the caller's rayon pool).
pub fn run(a: &BenchArgs) -> Result<()> {
    bench(a)
}

fn bench(a: &BenchArgs) -> Result<()> {
    let scenes: Vec<String> = if a.scenes.is_empty() {
        ["scenes/cornell-bunny-mirror.toml", "scenes/office.toml", "scenes/conference.toml"]
            .map(String::from)
            .to_vec()
    } else {
        a.scenes.clone()
    };
    // Everything that can fail before hours of rendering: scenes, flags, the output folder.
    let mut loaded = Vec::new();
    for s in &scenes {
        loaded
            .push(crate::cli::load_scene(s, hyrt::scene::Overrides { size: a.size, ..Default::default() })?);
    }
    if let Some(n) = a.orbit {
        return crate::orbit::run(a, &loaded, n);
    }
    if a.scaling {
        return crate::scaling::run(a, &loaded);
    }
    let flags = configs(a.vpls);
    let mut per_scene = Vec::new();
    for sc in &loaded {
        let mut cs = Vec::new();
        for (id, f) in &flags {
            let words: Vec<&str> = f.split_whitespace().collect();
            let options = Knobs::from_flags(&words)?.options_for(sc)?;
            cs.push(Config { label: (*id).to_string(), options, scene: None });
        }
        per_scene.push(cs);
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create folder", a.out.display()))?;

    let frames_per_scene = flags.len() as u64 * (1 + u64::from(a.runs)) + if a.no_check { 0 } else { 3 };
    let bar = crate::cli::progress_bar(frames_per_scene * loaded.len() as u64, "frames", false);

    let mut results = Vec::new();
    for (sc, mut cs) in loaded.iter().zip(per_scene) {
        eprintln!(
            "{}: {} triangles, {} lights, {}x{}",
            sc.name,
            sc.triangle_count(),
            sc.lights.len(),
            sc.settings.width,
            sc.settings.height
        );
        // Textured scenes: the same frames without their textures, alternated with the
        // others (module docs).
        if !sc.textures.is_empty() {
            let mut plain = sc.clone();
            plain.materials.iter_mut().for_each(|m| m.texture = None);
            let plain = std::sync::Arc::new(plain);
            for (of, id) in UNTEXTURED {
                let c = cs.iter().find(|c| c.label == of).expect("a bench configuration");
                cs.push(Config { label: id.to_string(), options: c.options, scene: Some(plain.clone()) });
            }
            bar.inc_length(UNTEXTURED.len() as u64 * (1 + u64::from(a.runs)) + u64::from(!a.no_check));
        }
        let mo = MeasureOptions { runs: a.runs as usize, check: !a.no_check, same_rays: true };
        let mut ms = measure::measure(sc, &cs, None, mo, &|label| {
            bar.set_message(format!("{} {label}", sc.name));
            bar.inc(1);
        })?;
        // PSNR against the matching reference: direct light alone, or with the same VPLs.
        let film = |id: &str| ms.iter().find(|m| m.label == id).map(|m| m.film.clone()).expect("measured");
        let (rt, rt_vpl) = (film("rt"), film("rt-vpl"));
        // The untextured frames against the untextured reference.
        let rt_plain = ms.iter().find(|m| m.label == UNTEXTURED[0].1).map(|m| m.film.clone());
        for m in &mut ms {
            let reference = if let Some(f) = rt_plain.as_ref().filter(|_| m.label.ends_with("-untextured")) {
                f
            } else if cs
                .iter()
                .any(|c| c.label == m.label && c.options.indirect != hyrt::render::Indirect::None)
            {
                &rt_vpl
            } else {
                &rt
            };
            m.psnr_db = Some(measure::psnr(sc, reference, &m.film)?);
        }
        for m in &ms {
            eprintln!(
                "  {:<12} median {:>8.1} ms  mean fps {:>6.2}  PSNR {}",
                m.label,
                m.frame_ms.median,
                m.frame_ms.fps_mean(),
                fmt_db(m.psnr_db)
            );
        }
        results.push(SceneResult {
            scene: sc.name.clone(),
            triangles: sc.triangle_count(),
            lights: sc.lights.len(),
            width: sc.settings.width,
            height: sc.settings.height,
            flags: flags.iter().map(|(i, f)| ((*i).to_string(), f.clone())).collect(),
            configs: ms,
            thesis: thesis(&sc.name),
        });
    }
    bar.finish_and_clear();

    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let md = tables(&results, a, &command);
    let csv = csv(&results)?;
    let json = serde_json::to_string_pretty(&serde_json::json!({
        "command": command,
        "threads": rayon::current_num_threads(),
        "runs": a.runs,
        "scenes": results,
    }))?;
    for (name, text) in [("tables.md", &md), ("results.csv", &csv), ("results.json", &json)] {
        let p = a.out.join(name);
        atomic_write(&p, |tmp| std::fs::write(tmp, text).map_err(Into::into))?;
        eprintln!("wrote {}", p.display());
    }
    println!("{md}");
    Ok(())
}

fn fmt_db(p: Option<f64>) -> String {
    match p {
        Some(p) if p.is_infinite() => "inf".into(),
        Some(p) => format!("{p:.2}"),
        None => "-".into(),
    }
}

/// Median milliseconds of pass `k` (0 for a pass the configuration does not run).
fn pass_ms(m: &Measurement, k: &str) -> f64 {
    m.pass_ms.get(k).copied().unwrap_or(0.0)
}

fn fps(m: &Measurement) -> f64 {
    m.frame_ms.fps_mean()
}

/// Thousands separators, as the thesis prints ray counts.
fn n(v: u64) -> String {
    let s = v.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn ratio(a: f64, b: f64) -> String {
    if b > 0.0 { format!("{:.2}x", a / b) } else { "-".into() }
}

/// `part` of `whole`, in per cent with one decimal.
fn percent(part: u64, whole: u64) -> String {
    if whole > 0 { format!("{:.1} %", 100.0 * part as f64 / whole as f64) } else { "-".into() }
}

/// The Markdown report: the tables with the thesis's figures beside ours.
fn tables(results: &[SceneResult], a: &BenchArgs, command: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Produced by `{command}` ({} threads, {} timed frames per configuration after a warm-up, frames of the configurations alternated). \
         fps = frames / total time (the thesis's mean); frame times are medians. Thesis: Intel i5-750, 4 threads (GPU for 4.4 and 4.5).\n",
        rayon::current_num_threads(),
        a.runs
    );
    let _ = writeln!(s, "Configurations (render flags):\n");
    if let Some(r) = results.first() {
        for (id, f) in &r.flags {
            let _ = writeln!(s, "- `{id}`: `{f}`");
        }
    }

    let _ = writeln!(s, "\n### Table 4.1: primary visibility (rays vs rasterization)\n");
    let mut t = Table::new(
        &[
            "scene",
            "fps RT",
            "fps raster",
            "speed-up",
            "thesis fps RT / proj.",
            "visibility ms RT / raster",
            "shadow rays RT / raster",
            "specular rays RT / raster",
            "total rays RT / raster",
            "thesis total rays",
        ],
        1,
    );
    for r in results {
        let (x, y) = (r.get("rt"), r.get("rt-raster"));
        let vis = |m: &Measurement| pass_ms(m, "visibility");
        let th = r.thesis.map_or("-".into(), |t| format!("{} / {}", t.t41.0, t.t41.1));
        let tr = r.thesis.map_or("-".into(), |t| format!("{} / {}", n(t.t41.2), n(t.t41.3)));
        t.row(vec![
            r.scene.clone(),
            format!("{:.2}", fps(x)),
            format!("{:.2}", fps(y)),
            ratio(fps(y), fps(x)),
            th,
            format!("{:.1} / {:.1}", vis(x), vis(y)),
            format!("{} / {}", n(x.rays.shadow), n(y.rays.shadow)),
            format!("{} / {}", n(x.rays.specular), n(y.rays.specular)),
            format!("{} / {}", n(x.rays.total()), n(y.rays.total())),
            tr,
        ]);
    }
    s.push_str(&t.markdown());

    let _ =
        writeln!(s, "\n### Table 4.2: direct light with SMeRTS (reference with rasterized visibility too)\n");
    let mut t = Table::new(
        &[
            "scene",
            "lights",
            "fps ref",
            "fps SMeRTS cube / para",
            "speed-up cube / para",
            "thesis fps ref / SMeRTS",
            "PSNR cube / para",
            "thesis PSNR",
            "wrong px cube / para",
            "shadow rays ref / cube / para",
            "thesis shadow rays",
            "map build ms cube / para",
            "map MB cube / para",
        ],
        1,
    );
    for r in results {
        let (b, c, d) = (r.get("rt-raster"), r.get("smerts-cube"), r.get("smerts-para"));
        let wrong = |m: &Measurement| m.wrong_pixels.map_or("-".into(), |w| w.to_string());
        let (thf, thp, thr) = r.thesis.map_or(("-".into(), "-".into(), "-".into()), |t| {
            (
                format!("{} / {}", t.t42.0, t.t42.1),
                format!("{:.2}", t.t42.2),
                format!("{} / {}", n(t.t42.3), n(t.t42.4)),
            )
        });
        t.row(vec![
            r.scene.clone(),
            r.lights.to_string(),
            format!("{:.2}", fps(b)),
            format!("{:.2} / {:.2}", fps(c), fps(d)),
            format!("{} / {}", ratio(fps(c), fps(b)), ratio(fps(d), fps(b))),
            thf,
            format!("{} / {}", fmt_db(c.psnr_db), fmt_db(d.psnr_db)),
            thp,
            format!("{} / {}", wrong(c), wrong(d)),
            format!("{} / {} / {}", n(b.rays.shadow), n(c.rays.shadow), n(d.rays.shadow)),
            thr,
            format!("{:.0} / {:.0}", c.map_build_ms, d.map_build_ms),
            format!("{:.0} / {:.0}", c.map_bytes as f64 / 1e6, d.map_bytes as f64 / 1e6),
        ]);
    }
    s.push_str(&t.markdown());
    let _ = writeln!(
        s,
        "\nTable 4.3 (SMeRTS on the thesis's GPU tracer, OptiX) has no CPU counterpart here and is not reproduced."
    );

    let _ = writeln!(
        s,
        "\n### Table 4.4: indirect light, {} VPLs: shadow rays vs one paraboloid map per VPL\n",
        a.vpls
    );
    let mut t4 = Table::new(
        &[
            "scene",
            "fps ref",
            "fps maps",
            "speed-up",
            "thesis fps ref / maps",
            "PSNR",
            "thesis PSNR",
            "VPL shadow rays removed",
            "thesis removed",
            "indirect pass ms rays / maps",
            "indirect speed-up",
            "pairs",
            "CPU ns per pair rays / maps",
            "VPL map build ms",
            "VPL maps MB",
        ],
        1,
    );
    // CPU ns of a pass per unit it counts (the indirect pass per (point, VPL) pair, ...): wall
    // time times the threads.
    let threads = rayon::current_num_threads() as f64;
    let per_unit = |ms: f64, units: u64| if units == 0 { 0.0 } else { ms * 1e6 * threads / units as f64 };
    for r in results {
        let (e, f) = (r.get("rt-vpl"), r.get("vpl-maps"));
        let ind = |m: &Measurement| pass_ms(m, "indirect");
        let t = r.thesis.and_then(|t| t.t44);
        t4.row(vec![
            r.scene.clone(),
            format!("{:.2}", fps(e)),
            format!("{:.2}", fps(f)),
            ratio(fps(f), fps(e)),
            t.map_or("-".into(), |t| format!("{} / {}", t.0, t.1)),
            fmt_db(f.psnr_db),
            t.map_or("-".into(), |t| format!("{:.2}", t.2)),
            n(e.rays.vpl_shadow.saturating_sub(f.rays.vpl_shadow)),
            t.map_or("-".into(), |t| n(t.3)),
            format!("{:.1} / {:.1}", ind(e), ind(f)),
            ratio(ind(e), ind(f)),
            n(f.vpl_pairs),
            format!("{:.1} / {:.2}", per_unit(ind(e), e.vpl_pairs), per_unit(ind(f), f.vpl_pairs)),
            format!("{:.0}", f.map_build_ms),
            format!("{:.1}", f.map_bytes as f64 / 1e6),
        ]);
    }
    s.push_str(&t4.markdown());

    let _ = writeln!(
        s,
        "\n### Cost per unit: CPU ns per map decision, border ray, shadow ray and mirror ray\n\n\
         A pass's median time times the threads, divided by what it counted in a frame: the map \
         decisions of SMeRTS's classify pass ((camera hit, light) pairs, with their direct light; \
         the share decided a tile at a time by the tile test, the rest point by point), \
         its border rays (`shadow_rays`: the camera hits' pairs a ray decides, hint first, those \
         pixels shaded again; the shadow rays of mirror hits belong to `specular`), the reference's \
         shadow rays (its `direct` pass, shading included; rasterized visibility), and the mirror \
         rays of each (`specular`, their hits shaded). The border rays are the frame's hardest \
         shadow rays by selection (each passes an occluder's silhouette); the last columns trace \
         one frame's rays again in this process, on one thread and with no shading: the border \
         rays as the reference traces its shadow rays and with their hint, and every shadow ray \
         of the frame's pairs as the reference does (`hyrt::render::shadows::SameRays`).\n"
    );
    let mut tu = Table::new(
        &[
            "scene",
            "map decisions",
            "ns per decision",
            "decided by tile",
            "border rays",
            "ns per border ray",
            "reference shadow rays",
            "ns per reference shadow ray",
            "ns per mirror ray reference / SMeRTS",
            "same rays: ns per border ray, plain / hint",
            "ns per shadow ray of the frame, plain",
            "border / frame, plain",
        ],
        1,
    );
    for r in results {
        let (b, c) = (r.get("rt-raster"), r.get("smerts-cube"));
        tu.row(vec![
            r.scene.clone(),
            n(c.map_decisions),
            format!("{:.1}", per_unit(pass_ms(c, "classify"), c.map_decisions)),
            percent(c.map_decisions_by_tile, c.map_decisions),
            n(c.border_rays),
            format!("{:.0}", per_unit(pass_ms(c, "shadow_rays"), c.border_rays)),
            n(b.rays.shadow),
            format!("{:.0}", per_unit(pass_ms(b, "direct"), b.rays.shadow)),
            format!(
                "{:.0} / {:.0}",
                per_unit(pass_ms(b, "specular"), b.rays.specular),
                per_unit(pass_ms(c, "specular"), c.rays.specular)
            ),
            c.same_rays.map_or("-".into(), |q| format!("{:.0} / {:.0}", q.border_plain_ns, q.border_hint_ns)),
            c.same_rays.map_or("-".into(), |q| format!("{:.0}", q.all_plain_ns)),
            c.same_rays.map_or("-".into(), |q| ratio(q.border_plain_ns, q.all_plain_ns)),
        ]);
    }
    s.push_str(&tu.markdown());

    let textured: Vec<&SceneResult> =
        results.iter().filter(|r| r.configs.iter().any(|m| m.label == UNTEXTURED[0].1)).collect();
    if !textured.is_empty() {
        let _ =
            writeln!(s, "\n### Texture sampling: the textured scenes without their textures (medians, ms)\n");
        let mut tt = Table::new(
            &[
                "scene",
                "reference textured / untextured",
                "textures' share",
                "SMeRTS textured / untextured",
                "textures' share",
                "speed-up textured / untextured",
            ],
            1,
        );
        for r in textured {
            let ms = |id: &str| r.get(id).frame_ms.median;
            let (rt, rtu, sm, smu) = (ms("rt"), ms(UNTEXTURED[0].1), ms("smerts-cube"), ms(UNTEXTURED[1].1));
            let share = |with: f64, without: f64| format!("{:.1} %", 100.0 * (with - without) / with);
            tt.row(vec![
                r.scene.clone(),
                format!("{rt:.1} / {rtu:.1}"),
                share(rt, rtu),
                format!("{sm:.1} / {smu:.1}"),
                share(sm, smu),
                format!("{} / {}", ratio(rt, sm), ratio(rtu, smu)),
            ]);
        }
        s.push_str(&tt.markdown());
    }

    let _ = writeln!(s, "\n### Table 4.5: both together (SMeRTS + VPL maps) vs the full reference\n");
    let mut t5 = Table::new(
        &[
            "scene",
            "fps ref",
            "fps hybrid",
            "speed-up",
            "thesis fps ref / hybrid",
            "PSNR",
            "thesis PSNR",
            "shadow + VPL shadow rays ref / hybrid",
            "thesis",
        ],
        1,
    );
    for r in results {
        let (e, g) = (r.get("rt-vpl"), r.get("hybrid-vpl"));
        let t = r.thesis.and_then(|t| t.t45);
        t5.row(vec![
            r.scene.clone(),
            format!("{:.2}", fps(e)),
            format!("{:.2}", fps(g)),
            ratio(fps(g), fps(e)),
            t.map_or("-".into(), |t| format!("{} / {}", t.0, t.1)),
            fmt_db(g.psnr_db),
            t.map_or("-".into(), |t| format!("{:.2}", t.2)),
            format!("{} / {}", n(e.rays.shadow + e.rays.vpl_shadow), n(g.rays.shadow + g.rays.vpl_shadow)),
            t.map_or("-".into(), |t| format!("{} / {}", n(t.3), n(t.4))),
        ]);
    }
    s.push_str(&t5.markdown());

    let _ = writeln!(s, "\n### Every configuration: frame time (ms) and fps\n");
    let mut tf = Table::new(
        &[
            "scene",
            "config",
            "fps (mean)",
            "median ms",
            "min ms",
            "max ms",
            "first frame ms",
            "BVH ms",
            "PSNR",
        ],
        2,
    );
    for r in results {
        for m in &r.configs {
            let t = &m.frame_ms;
            tf.row(vec![
                r.scene.clone(),
                format!("`{}`", m.label),
                format!("{:.2}", t.fps_mean()),
                format!("{:.1}", t.median),
                format!("{:.1}", t.min),
                format!("{:.1}", t.max),
                format!("{:.0}", m.first_frame_ms),
                format!("{:.0}", m.bvh_build_ms),
                fmt_db(m.psnr_db),
            ]);
        }
    }
    s.push_str(&tf.markdown());

    // Where each frame's time goes: the passes of every configuration, in frame order
    // (`Pass::ALL`); `vis_*` are the parts of `visibility`.
    let mut passes: Vec<&str> =
        results.iter().flat_map(|r| &r.configs).flat_map(|m| m.pass_ms.keys()).map(String::as_str).collect();
    passes.sort_by_key(|k| (hyrt::render::Pass::rank(k), *k));
    passes.dedup();
    let _ = writeln!(
        s,
        "\n### Time per pass (ms, medians over the timed frames; `vis_*` are parts of `visibility`)\n"
    );
    let mut tp = Table::new(&[&["scene", "config", "frame"][..], &passes[..]].concat(), 2);
    for r in results {
        for m in &r.configs {
            let mut cells =
                vec![r.scene.clone(), format!("`{}`", m.label), format!("{:.1}", m.frame_ms.median)];
            cells.extend(passes.iter().map(|k| m.pass_ms.get(*k).map_or("-".into(), |v| format!("{v:.1}"))));
            tp.row(cells);
        }
    }
    s.push_str(&tp.markdown());
    s
}

/// A row of `results.csv`: one scene and configuration.
#[derive(Serialize)]
struct CsvRow<'a> {
    scene: &'a str,
    config: &'a str,
    flags: &'a str,
    fps_mean: f64,
    frame_ms_median: f64,
    frame_ms_mean: f64,
    frame_ms_min: f64,
    frame_ms_max: f64,
    runs: usize,
    first_frame_ms: f64,
    map_build_ms: f64,
    bvh_build_ms: f64,
    map_bytes: u64,
    /// `inf` for an exact match; empty without a reference.
    psnr_db: Option<String>,
    wrong_pixels: Option<u64>,
    wrong_pairs: Option<u64>,
    rays_primary: u64,
    rays_shadow: u64,
    rays_shadow_hint_hits: u64,
    rays_specular: u64,
    rays_vpl_shadow: u64,
    rays_vpl_path: u64,
    rays_total: u64,
    vpl_pairs: u64,
}

/// One row per scene and configuration.
fn csv(results: &[SceneResult]) -> Result<String> {
    let ms = |v: f64| round(v, 3);
    let rows = results.iter().flat_map(|r| {
        r.configs.iter().map(move |m| {
            let t = &m.frame_ms;
            CsvRow {
                scene: &r.scene,
                config: &m.label,
                flags: r.flags.iter().find(|(i, _)| *i == m.label).map_or("", |(_, f)| f.as_str()),
                fps_mean: round(t.fps_mean(), 4),
                frame_ms_median: ms(t.median),
                frame_ms_mean: ms(t.mean),
                frame_ms_min: ms(t.min),
                frame_ms_max: ms(t.max),
                runs: t.runs,
                first_frame_ms: ms(m.first_frame_ms),
                map_build_ms: ms(m.map_build_ms),
                bvh_build_ms: ms(m.bvh_build_ms),
                map_bytes: m.map_bytes,
                psnr_db: m.psnr_db.map(|p| if p.is_infinite() { "inf".into() } else { format!("{p:.3}") }),
                wrong_pixels: m.wrong_pixels,
                wrong_pairs: m.wrong_pairs,
                rays_primary: m.rays.primary,
                rays_shadow: m.rays.shadow,
                rays_shadow_hint_hits: m.rays.shadow_hint_hits,
                rays_specular: m.rays.specular,
                rays_vpl_shadow: m.rays.vpl_shadow,
                rays_vpl_path: m.rays.vpl_path,
                rays_total: m.rays.total(),
                vpl_pairs: m.vpl_pairs,
            }
        })
    });
    csv_rows(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousands() {
        assert_eq!(n(0), "0");
        assert_eq!(n(999), "999");
        assert_eq!(n(1000), "1,000");
        assert_eq!(n(12_971_207), "12,971,207");
    }

    #[test]
    fn every_configuration_parses() {
        for (id, f) in configs(45) {
            let words: Vec<&str> = f.split_whitespace().collect();
            Knobs::from_flags(&words).and_then(|k| k.options()).unwrap_or_else(|e| panic!("{id}: {e}"));
        }
        let e = Knobs::from_flags(&["--no-such-flag"]).expect_err("an unknown flag parses");
        assert!(e.to_string().contains("--no-such-flag"), "{e}");
    }
}
