//! Reference (Whitted) frame time and rays per second, with 1 and 2 threads.
//!
//! `cargo bench --bench reference` renders each scene at 640x480, alternating the thread
//! counts frame by frame in one process (so both see the same machine load), and prints the
//! median frame time and rays per second over `HYRT_BENCH_FRAMES` frames (default 7) after one
//! warm-up frame each. Scenes: `HYRT_BENCH_SCENES` (comma-separated scene files), default the
//! thesis's cornell-bunny-mirror, conference and office.

mod common;

use std::time::Instant;

use common::{frames, load_640x480, median, scenes};

use hyrt::render::{Options, Renderer};

fn main() {
    let frames = frames(7);
    let pools: Vec<(usize, rayon::ThreadPool)> = [1, 2]
        .iter()
        .map(|&n| (n, rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap()))
        .collect();

    println!("reference (Whitted) at 640x480, median of {frames} frames, threads alternated per frame\n");
    println!("| scene | triangles | BVH build ms | threads | frame ms | rays/frame | M rays/s | speed-up |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for spec in scenes() {
        let Some(scene) = load_640x480(&spec) else { continue };
        let renderer = Renderer::new(&scene, Options::default());
        let mut times = vec![Vec::new(); pools.len()];
        let mut rays = 0;
        for i in 0..=frames {
            for (k, (_, pool)) in pools.iter().enumerate() {
                let t = Instant::now();
                let f = pool.install(|| renderer.render(&|| {}));
                let ms = t.elapsed().as_secs_f64() * 1e3;
                rays = f.stats.rays.total();
                if i > 0 {
                    times[k].push(ms);
                }
            }
        }
        let medians: Vec<f64> = times.iter_mut().map(|t| median(t)).collect();
        for (k, (n, _)) in pools.iter().enumerate() {
            println!(
                "| {} | {} | {:.1} | {} | {:.1} | {} | {:.2} | {:.2}x |",
                scene.name,
                scene.triangle_count(),
                renderer.bvh_build_ms(),
                n,
                medians[k],
                rays,
                rays as f64 / medians[k] / 1e3,
                medians[0] / medians[k],
            );
        }
    }
}
