//! Thesis tables 4.4 and 4.5: indirect light from 45 VPLs by rays and by paraboloid maps, and
//! the combined hybrid against the full reference.
//!
//! `cargo bench --bench indirect` renders each thesis scene at 640x480 with, in one process
//! (medians of `HYRT_BENCH_FRAMES`, default 5, after a warm-up frame that builds the maps):
//! - `vpl rays`: the reference with indirect light, one shadow ray per hit and VPL;
//! - `vpl maps`: the same with one paraboloid map per VPL;
//! - `hybrid`: rasterized visibility + SMeRTS + VPL maps.
//!
//! It prints the indirect pass time, the frame time, VPL shadow rays, PSNR against `vpl rays`,
//! and the VPL map build time and memory.

mod common;

use std::time::Instant;

use common::{frames, load_640x480, median, scenes};
use hyrt::{
    metrics::{DisplayImage, compare},
    render::{Indirect, Options, Renderer},
};

fn main() {
    let frames = frames(5);
    println!(
        "indirect light (45 VPL paths) at 640x480, {} threads; medians of {frames} frames after a warm-up\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene | configuration | indirect ms | frame ms | speed-up | VPL shadow rays | PSNR dB | VPL map build ms | VPL maps MB |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for spec in scenes() {
        let Some(scene) = load_640x480(&spec) else { continue };
        let with = |mut o: Options, ind| {
            o.indirect = ind;
            o.indirect_opts.vpl.paths = 45;
            o
        };
        let cfgs = [
            ("vpl rays", with(Options::reference(), Indirect::Rays)),
            ("vpl maps", with(Options::reference(), Indirect::Maps)),
            ("hybrid", with(Options::hybrid(), Indirect::Maps)),
        ];
        let renderers: Vec<Renderer> = cfgs.iter().map(|(_, o)| Renderer::new(&scene, *o)).collect();
        let first: Vec<_> = renderers.iter().map(|r| r.render(&|| {})).collect();
        let mut frame_ms = vec![Vec::new(); cfgs.len()];
        let mut ind_ms = vec![Vec::new(); cfgs.len()];
        for _ in 0..frames {
            for (i, r) in renderers.iter().enumerate() {
                let t = Instant::now();
                let f = r.render(&|| {});
                frame_ms[i].push(t.elapsed().as_secs_f64() * 1e3);
                ind_ms[i].push(f.stats.ms(hyrt::render::Pass::Indirect));
            }
        }
        let e = scene.settings.exposure;
        let reference = DisplayImage::from_film(&first[0].film, e);
        let base = median(&mut frame_ms[0].clone());
        for (i, ((name, _), f)) in cfgs.iter().zip(&first).enumerate() {
            let ms = median(&mut frame_ms[i]);
            let psnr = compare(&reference, &DisplayImage::from_film(&f.film, e)).unwrap().psnr_db;
            let psnr = if psnr.is_infinite() { "inf".to_string() } else { format!("{psnr:.2}") };
            println!(
                "| {} | {name} | {:.1} | {ms:.1} | {:.2}x | {} | {psnr} | {:.0} | {:.0} |",
                scene.name,
                median(&mut ind_ms[i]),
                base / ms,
                f.stats.rays.vpl_shadow,
                f.stats.ms(hyrt::render::Pass::VplMapBuild),
                f.stats.vpl_map_bytes as f64 / 1e6,
            );
        }
    }
}
