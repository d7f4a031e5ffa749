//! Thesis tables 4.2 and 4.3: direct light with SMeRTS against the reference.
//!
//! `cargo bench --bench shadows` renders each thesis scene at 640x480 with, in one process and
//! alternated frame by frame (medians of `HYRT_BENCH_FRAMES`, default 10, after a warm-up frame
//! that builds the maps):
//! - `reference`: the full Whitted reference (primary and shadow rays);
//! - `raster+rays`: rasterized visibility, shadow rays (the thesis's table 4.2 baseline);
//! - `smerts cube`, `smerts paraboloid`: the hybrid preset with each map kind;
//! - `maps cube`: maps alone, no border rays (the accuracy SMeRTS buys back).
//!
//! For each: frame time, shadow rays (and how many the occluder hint answered), PSNR against the
//! reference, wrong-visibility pixels (a separate checked frame), and the map build time of the
//! first frame. Threads: all cores (`RAYON_NUM_THREADS`). Scenes: `HYRT_BENCH_SCENES` or
//! arguments filtering by name.

mod common;

use std::time::Instant;

use common::{frames, load_640x480, median, scenes};
use hyrt::{
    metrics::{DisplayImage, compare},
    render::{Options, Renderer, Shadows, Visibility},
};
use hyrt_shadowmap::MapKind;

fn configs() -> Vec<(&'static str, Options)> {
    let mut raster_rays = Options::reference();
    raster_rays.visibility = Visibility::Raster;
    let smerts = |k| {
        let mut o = Options::hybrid();
        o.shadow.map.kind = k;
        o
    };
    let mut maps = smerts(MapKind::Cube);
    maps.shadows = Shadows::Maps;
    vec![
        ("reference", Options::reference()),
        ("raster+rays", raster_rays),
        ("smerts cube", smerts(MapKind::Cube)),
        ("smerts paraboloid", smerts(MapKind::Paraboloid)),
        ("maps cube", maps),
    ]
}

fn main() {
    let frames = frames(10);
    println!(
        "direct light at 640x480, {} threads; medians of {frames} frames after a warm-up frame\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene | configuration | frame ms | fps | speed-up | shadow rays | hint hits | PSNR dB | wrong px | map build ms |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for spec in scenes() {
        let Some(scene) = load_640x480(&spec) else { continue };
        let cfgs = configs();
        let renderers: Vec<Renderer> = cfgs.iter().map(|(_, o)| Renderer::new(&scene, *o)).collect();
        // Warm-up: builds the maps (timed), gives the images and ray counts.
        let first: Vec<_> = renderers.iter().map(|r| r.render(&|| {})).collect();
        let mut times = vec![Vec::new(); cfgs.len()];
        for _ in 0..frames {
            for (r, t) in renderers.iter().zip(&mut times) {
                let s = Instant::now();
                let f = r.render(&|| {});
                t.push(s.elapsed().as_secs_f64() * 1e3);
                assert_eq!(f.stats.maps_built, 0, "maps are cached");
            }
        }
        let exposure = scene.settings.exposure;
        let reference = DisplayImage::from_film(&first[0].film, exposure);
        let ref_ms = median(&mut times[0].clone());
        for (i, ((name, opts), f)) in cfgs.iter().zip(&first).enumerate() {
            let ms = median(&mut times[i]);
            let psnr = compare(&reference, &DisplayImage::from_film(&f.film, exposure)).unwrap().psnr_db;
            let (wrong, build) = if opts.shadows == Shadows::Rays {
                ("-".to_string(), "-".to_string())
            } else {
                let mut checked = *opts;
                checked.check_visibility = true;
                let c = Renderer::new(&scene, checked).render(&|| {});
                let w: u64 = c.stats.lights.iter().map(|l| l.wrong.unwrap_or(0)).sum();
                (w.to_string(), format!("{:.1}", f.stats.ms(hyrt::render::Pass::MapBuild)))
            };
            let psnr = if psnr.is_infinite() { "inf".to_string() } else { format!("{psnr:.2}") };
            println!(
                "| {} | {name} | {ms:.1} | {:.2} | {:.2}x | {} | {} | {psnr} | {wrong} | {build} |",
                scene.name,
                1e3 / ms,
                ref_ms / ms,
                f.stats.rays.shadow,
                f.stats.rays.shadow_hint_hits,
            );
        }
    }
}
