//! Helpers shared by the pipeline benchmarks.
#![allow(dead_code)]

/// Median of `v` ([`hyrt::metrics::Timing`]'s, the one median of every tool).
pub fn median(v: &mut [f64]) -> f64 {
    hyrt::metrics::Timing::of(v).median
}

/// `HYRT_BENCH_FRAMES`, or `default`.
pub fn frames(default: usize) -> usize {
    std::env::var("HYRT_BENCH_FRAMES").ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// Scene files: `HYRT_BENCH_SCENES` (comma-separated paths), or the thesis scenes in
/// `scenes/`; command-line arguments other than cargo's `--bench` filter them by substring.
pub fn scenes() -> Vec<String> {
    let root = env!("CARGO_MANIFEST_DIR");
    let filter: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    std::env::var("HYRT_BENCH_SCENES")
        .map(|s| s.split(',').map(String::from).collect::<Vec<_>>())
        .unwrap_or_else(|_| {
            ["cornell-bunny-mirror", "office", "conference"]
                .iter()
                .map(|s| format!("{root}/scenes/{s}.toml"))
                .collect()
        })
        .into_iter()
        .filter(|s| filter.is_empty() || filter.iter().any(|f| s.contains(f.as_str())))
        .collect()
}

/// `HYRT_BENCH_SIZE` (`WIDTHxHEIGHT`, both from 1 to 16384), or 640x480 (the thesis's size).
/// Exits with a message if it is set but malformed.
pub fn size() -> (u32, u32) {
    let Ok(v) = std::env::var("HYRT_BENCH_SIZE") else { return (640, 480) };
    let parsed = v.split_once('x').and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)));
    match parsed {
        Some((w, h)) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => (w, h),
        _ => {
            eprintln!("HYRT_BENCH_SIZE={v:?}: expected WIDTHxHEIGHT, e.g. 1280x960, each 1 to 16384");
            std::process::exit(2);
        }
    }
}

/// Loads a scene at 640x480 (the thesis's size), or says why it is skipped.
pub fn load_640x480(spec: &str) -> Option<hyrt::scene::Scene> {
    match hyrt::scene::load(spec) {
        Ok(mut s) => {
            s.settings.width = 640;
            s.settings.height = 480;
            Some(s)
        }
        Err(e) => {
            eprintln!("skipping {spec}: {e:#}");
            None
        }
    }
}
