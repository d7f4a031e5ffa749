//! `hyrt bench --scaling`: how each pass's time scales from one thread to all of them.
//!
//! A pass that does not halve its time on two threads has a serial section, an imbalance
//! between its tasks, or a memory bottleneck, and it will lose more on machines with more
//! cores. Per scene, the reference and the hybrid each render warm frames (caches built by a
//! first frame) on a one-thread pool and on the command's pool, alternated frame by frame:
//! `rt 1, rt N, hybrid 1, hybrid N, rt 1, ...`, so that the ratios compare frames seconds
//! apart. Each pass's median at both counts and their ratio go to `scaling.md` and
//! `scaling.csv`; the ratio is the pass's speed-up (ideally the thread count).

use std::{collections::BTreeMap, time::Instant};

use anyhow::{Context, Result};

use hyrt::{metrics::Timing, options::Knobs, output::atomic_write, render::Renderer, scene::Scene};

use crate::{
    bench::BenchArgs,
    report::{Table, csv_rows, round},
};

/// The configurations measured: id and render flags.
const CONFIGS: [(&str, &str); 2] = [("rt", "--preset reference"), ("smerts-cube", "--preset hybrid")];

/// The name of the whole frame among the passes.
const FRAME: &str = "frame";

/// A row of `scaling.csv`: one pass of one configuration.
#[derive(serde::Serialize)]
struct CsvRow {
    scene: String,
    config: &'static str,
    pass: String,
    threads: usize,
    ms_one_thread: f64,
    ms_threads: f64,
    speed_up: f64,
}

/// Per pass (and [`FRAME`]), the milliseconds of every timed frame.
type Times = BTreeMap<String, Vec<f64>>;

/// Runs the scaling measurement of `a.runs` frames per count on every scene of `a` and writes
/// `scaling.md` and `scaling.csv`. Runs on the caller's pool, whose size is the second count.
pub fn run(a: &BenchArgs, scenes: &[Scene]) -> Result<()> {
    let threads = rayon::current_num_threads();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .thread_name(|i| format!("hyrt-one-{i}"))
        .build()
        .context("cannot start a worker thread")?;
    let mut md = format!(
        "Produced by `hyrt bench --scaling --runs {}` on {threads} threads: warm frames (after a first frame that builds the caches) on 1 thread and on {threads}, alternated frame by frame with the other configuration's; medians of {} frames per count. Speed-up: the pass's time on 1 thread over its time on {threads} (ideally {threads}).\n\n",
        a.runs, a.runs
    );
    let mut table = Table::new(&["scene", "config", "pass", "ms, 1 thread", "ms, N threads", "speed-up"], 3);
    let mut rows = Vec::new();
    for sc in scenes {
        let mut renderers = Vec::new();
        for (label, flags) in CONFIGS {
            let words: Vec<&str> = flags.split_whitespace().collect();
            let options = Knobs::from_flags(&words)?.options_for(sc)?;
            let r = Renderer::new(sc, options);
            r.render(&|| {});
            renderers.push((label, r));
        }
        // Per configuration, per count (1, N): the frames' times.
        let mut times: Vec<[Times; 2]> = CONFIGS.iter().map(|_| Default::default()).collect();
        for _ in 0..a.runs {
            for ((_, r), t) in renderers.iter().zip(&mut times) {
                for (k, t) in t.iter_mut().enumerate() {
                    let start = Instant::now();
                    let frame = if k == 0 { one.install(|| r.render(&|| {})) } else { r.render(&|| {}) };
                    t.entry(FRAME.into()).or_default().push(start.elapsed().as_secs_f64() * 1e3);
                    for (p, ms) in &frame.stats.pass_ms {
                        t.entry(p.name().to_string()).or_default().push(*ms);
                    }
                }
            }
        }
        for ((label, _), [t1, tn]) in renderers.iter().zip(&times) {
            for (pass, v1) in t1 {
                let median = |v: &[f64]| Timing::of(v).median;
                let (m1, mn) = (median(v1), tn.get(pass).map_or(0.0, |v| median(v)));
                let speed_up = if mn > 0.0 { m1 / mn } else { 0.0 };
                table.row(vec![
                    sc.name.clone(),
                    format!("`{label}`"),
                    pass.clone(),
                    format!("{m1:.2}"),
                    format!("{mn:.2}"),
                    format!("{speed_up:.2}x"),
                ]);
                rows.push(CsvRow {
                    scene: sc.name.clone(),
                    config: label,
                    pass: pass.clone(),
                    threads,
                    ms_one_thread: round(m1, 3),
                    ms_threads: round(mn, 3),
                    speed_up: round(speed_up, 3),
                });
            }
        }
        eprintln!("{}: scaling done", sc.name);
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create folder", a.out.display()))?;
    md.push_str(&table.markdown());
    let csv = csv_rows(rows)?;
    for (name, text) in [("scaling.md", &md), ("scaling.csv", &csv)] {
        atomic_write(&a.out.join(name), |tmp| std::fs::write(tmp, text).map_err(Into::into))?;
    }
    print!("{md}");
    Ok(())
}
