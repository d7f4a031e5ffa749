//! Light maps per light, side by side with the llvmpipe peer benchmark (`peers/llvmpipe`):
//! each thesis scene's point lights, a full cube of 6 faces per light (as the peer draws them;
//! frames draw only the faces camera hits fall on), at 512, 1024 and 2048 texels per side,
//! with triangle ids and distances (what classification reads). Per light the median of
//! `HYRT_BENCH_FRAMES` builds (default 7) after a warm-up; the table gives the median over the
//! scene's lights, in ms per light and per face. Threads: all cores (`RAYON_NUM_THREADS`).
//!
//! `cargo bench --bench light_maps`; scenes filter by name as in the other benches.

mod common;

use std::time::Instant;

use common::{frames, median, scenes};
use hyrt_shadowmap::{LightMap, MapKind, MapOptions};

fn main() {
    let runs = frames(7);
    println!(
        "light maps, 6 cube faces per light, {} threads; medians of {runs} builds\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene | triangles | lights | resolution | ms per light (6 faces) | ms per face | MB per light |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for spec in scenes() {
        let scene = match hyrt::scene::load(&spec) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("skipping {spec}: {e:#}");
                continue;
            }
        };
        for resolution in [512, 1024, 2048] {
            let opts = MapOptions { kind: MapKind::Cube, resolution, ..MapOptions::default() };
            let mut per_light = Vec::new();
            let mut bytes = 0;
            for light in &scene.lights {
                let build = || LightMap::build(&scene.positions, light.position, &opts, &[true; 6]);
                bytes = build().memory_bytes();
                let mut t: Vec<f64> = (0..runs)
                    .map(|_| {
                        let s = Instant::now();
                        std::hint::black_box(build());
                        s.elapsed().as_secs_f64() * 1e3
                    })
                    .collect();
                per_light.push(median(&mut t));
            }
            let ms = median(&mut per_light);
            println!(
                "| {} | {} | {} | {resolution} | {ms:.1} | {:.2} | {:.0} |",
                scene.name,
                scene.positions.len(),
                scene.lights.len(),
                ms / 6.0,
                bytes as f64 / 1e6
            );
        }
    }
}
