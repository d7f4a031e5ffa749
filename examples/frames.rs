//! Renders frames of one scene in a loop and prints the median milliseconds per pass: a target
//! for `perf record` and `valgrind --tool=callgrind`, without the bench's other configurations.
//!
//! `cargo run --release --example frames -- SCENE [FRAMES] [reference|hybrid]` (default: 30
//! frames of the hybrid at 640x480, after a first frame that builds the maps). `HYRT_MAP_RES`
//! overrides the light maps' resolution; `HYRT_VPLS=N` adds indirect light from `N` VPL paths
//! by maps (`HYRT_VPL_RAYS=1`: by rays), `HYRT_VPL_RES` and `HYRT_INTERLEAVE` set its knobs;
//! `HYRT_NO_TEXTURES=1` drops the materials' textures; `HYRT_SIZE=WxH` sets the image size (a
//! small frame for `valgrind --tool=cachegrind`). The last line is a frame's map decisions.

use std::collections::BTreeMap;

use hyrt::render::{Options, Pass, Renderer};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(spec) = args.first() else {
        eprintln!("usage: frames SCENE [FRAMES] [reference|hybrid]");
        std::process::exit(2);
    };
    let mut scene = match hyrt::scene::load(spec) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{spec}: {e:#}");
            std::process::exit(1);
        }
    };
    (scene.settings.width, scene.settings.height) = std::env::var("HYRT_SIZE")
        .ok()
        .and_then(|v| v.split_once('x').and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?))))
        .unwrap_or((640, 480));
    if std::env::var_os("HYRT_NO_TEXTURES").is_some() {
        scene.materials.iter_mut().for_each(|m| m.texture = None);
    }
    let frames: usize = args.get(1).and_then(|n| n.parse().ok()).unwrap_or(30);
    let mut opts = match args.get(2).map(String::as_str) {
        Some("reference") => Options::reference(),
        _ => Options::hybrid(),
    };
    if let Some(res) = std::env::var("HYRT_MAP_RES").ok().and_then(|v| v.parse().ok()) {
        opts.shadow.map.resolution = res;
    }
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u32>().ok());
    if let Some(n) = env("HYRT_VPLS") {
        opts.indirect = if env("HYRT_VPL_RAYS") == Some(1) {
            hyrt::render::Indirect::Rays
        } else {
            hyrt::render::Indirect::Maps
        };
        opts.indirect_opts.vpl.paths = n;
    }
    if let Some(res) = env("HYRT_VPL_RES") {
        opts.indirect_opts.map.resolution = res;
    }
    if let Some(k) = env("HYRT_INTERLEAVE") {
        opts.indirect_opts.interleave = k;
    }
    let r = Renderer::new(&scene, opts);
    let first = r.render(&|| {}).stats;
    // Map decisions of a frame (each frame of the loop makes the same), to divide a profile by.
    let decisions: u64 = first.lights.iter().map(|l| l.lit + l.shadowed + l.undecided).sum();
    let mut times: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for _ in 0..frames {
        let stats = r.render(&|| {}).stats;
        for (k, v) in stats.pass_ms {
            times.entry(k.name()).or_default().push(v);
        }
        times.entry("total").or_default().push(stats.total_ms);
    }
    let mut rows: Vec<_> = times.into_iter().collect();
    rows.sort_by_key(|(k, _)| (Pass::rank(k), *k));
    for (k, mut v) in rows {
        v.sort_by(f64::total_cmp);
        println!("{k:>14} {:8.2}", v[v.len() / 2]);
    }
    println!("{:>14} {decisions:8}", "decisions");
}
