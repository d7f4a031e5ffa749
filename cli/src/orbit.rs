//! `hyrt bench --orbit N`: frames along a camera path, for the reference and the hybrid.
//!
//! The camera swings about the scene's target (`eye + forward`, the `target` of a scene file)
//! around its `up` axis, from -[`ARC_DEG`] to +[`ARC_DEG`] degrees in `N` steps: an arc rather
//! than a full turn, since the thesis scenes are rooms that a full turn would leave. The two
//! configurations' frames are alternated at each camera position. The first frame builds the
//! BVH's companions (light maps, VPLs); every later one reuses them and draws only the
//! light-map pages its view newly needs ([`Renderer::set_camera`]), counted per frame.

use std::time::Instant;

use anyhow::{Context, Result};
use glam::{Quat, Vec3};

use hyrt::{
    metrics::percentile,
    options::Knobs,
    output::atomic_write,
    render::Renderer,
    scene::{Camera, Scene},
};

use crate::{
    bench::BenchArgs,
    report::{Table, csv_rows, round},
};

/// Half the arc the camera swings through, in degrees.
pub const ARC_DEG: f32 = 20.0;

/// The configurations of the orbit: id and render flags.
const CONFIGS: [(&str, &str); 2] = [("rt", "--preset reference"), ("smerts-cube", "--preset hybrid")];

/// Camera `i` of `n` on the arc about `cam`'s target.
pub fn orbit_camera(cam: &Camera, i: u32, n: u32) -> Camera {
    let t = if n <= 1 { 0.5 } else { i as f32 / (n - 1) as f32 };
    let angle = (2.0 * t - 1.0) * ARC_DEG.to_radians();
    let target = cam.eye + cam.forward;
    let turn = Quat::from_axis_angle(cam.up.normalize_or(Vec3::Y), angle);
    let forward = turn * cam.forward;
    Camera { eye: target - forward, forward, ..*cam }
}

/// A row of `orbit.csv`: one frame of one configuration.
#[derive(serde::Serialize)]
struct CsvRow {
    scene: String,
    config: &'static str,
    frame: u32,
    ms: f64,
    pages_drawn: u64,
}

/// One configuration's frames along the path.
struct Track {
    label: &'static str,
    first_ms: f64,
    /// Frames after the first, in path order.
    ms: Vec<f64>,
    /// Light-map pages drawn in each frame after the first.
    pages: Vec<u64>,
}

/// Per light, the pages its map has rasterized so far (`LightMap::pages_rasterized`: a whole
/// map's face counts all its pages), and whether the map is paged (`None`: no map).
fn pages_so_far(r: &Renderer, scene: &Scene) -> Vec<Option<(u64, bool)>> {
    (0..scene.lights.len()).map(|l| r.light_map(l).map(|m| (m.pages_rasterized(), m.is_paged()))).collect()
}

/// Light-map pages that a frame drew, over every light, from the pages rasterized before
/// (`before`) and after it (`after`, [`pages_so_far`]). A paged map rebuilt to fit its budget
/// starts its count again, so a paged map's pages are those the frame reports
/// (`LightStats::pages_drawn`, all of a rebuilt map's); whole maps only grow (by merges).
fn pages_drawn(
    before: &[Option<(u64, bool)>],
    after: &[Option<(u64, bool)>],
    lights: &[hyrt::render::shadows::LightStats],
) -> u64 {
    after
        .iter()
        .enumerate()
        .map(|(l, a)| match (a, before.get(l).copied().flatten()) {
            (None, _) => 0,
            (Some((_, true)), _) => lights.get(l).map_or(0, |s| u64::from(s.pages_drawn)),
            (Some((n, false)), b) => n.saturating_sub(b.map_or(0, |b| b.0)),
        })
        .sum()
}

/// Runs the orbit of `n` frames on every scene of `a` and writes `orbit.md` and `orbit.csv`.
pub fn run(a: &BenchArgs, scenes: &[Scene], n: u32) -> Result<()> {
    let mut md = format!(
        "Produced by `hyrt bench --orbit {n}` ({} threads): the camera swings +-{ARC_DEG} degrees about the scene's target in {n} frames; the two configurations' frames alternate at each position. Times are of the frames after the first (which builds the maps); percentiles by nearest rank; fps = frames / total time. Pages: light-map pages ({p}x{p} texels) drawn after the first frame (0 when the first view's maps serve the whole path).\n\n",
        rayon::current_num_threads(),
        p = hyrt_shadowmap::PAGE
    );
    let mut table = Table::new(
        &[
            "scene",
            "config",
            "frames",
            "median ms",
            "p5 ms",
            "p95 ms",
            "fps",
            "first frame ms",
            "pages drawn after the first",
        ],
        2,
    );
    let mut frames = Vec::new();
    for sc in scenes {
        let cam = sc.camera.context("the scene has no camera")?;
        let mut renderers = Vec::new();
        for (label, flags) in CONFIGS {
            let words: Vec<&str> = flags.split_whitespace().collect();
            let options = Knobs::from_flags(&words)?.options_for(sc)?;
            renderers.push((label, Renderer::new(sc, options)));
        }
        let mut tracks: Vec<Track> = CONFIGS
            .iter()
            .map(|(label, _)| Track { label, first_ms: 0.0, ms: vec![], pages: vec![] })
            .collect();
        for i in 0..n {
            let c = orbit_camera(&cam, i, n);
            for ((_, r), t) in renderers.iter_mut().zip(&mut tracks) {
                r.set_camera(&c);
                let before = pages_so_far(r, sc);
                let start = Instant::now();
                let frame = r.render(&|| {});
                let ms = start.elapsed().as_secs_f64() * 1e3;
                let pages = pages_drawn(&before, &pages_so_far(r, sc), &frame.stats.lights);
                frames.push(CsvRow {
                    scene: sc.name.clone(),
                    config: t.label,
                    frame: i,
                    ms: round(ms, 3),
                    pages_drawn: pages,
                });
                if i == 0 {
                    t.first_ms = ms;
                } else {
                    t.ms.push(ms);
                    t.pages.push(pages);
                }
            }
        }
        for t in &tracks {
            let total: f64 = t.ms.iter().sum();
            let fps = if total > 0.0 { t.ms.len() as f64 * 1e3 / total } else { 0.0 };
            table.row(vec![
                sc.name.clone(),
                format!("`{}`", t.label),
                t.ms.len().to_string(),
                format!("{:.1}", percentile(&t.ms, 50.0)),
                format!("{:.1}", percentile(&t.ms, 5.0)),
                format!("{:.1}", percentile(&t.ms, 95.0)),
                format!("{fps:.2}"),
                format!("{:.0}", t.first_ms),
                t.pages.iter().sum::<u64>().to_string(),
            ]);
        }
        eprintln!("{}: orbit done", sc.name);
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create folder", a.out.display()))?;
    md.push_str(&table.markdown());
    let csv = csv_rows(frames)?;
    for (name, text) in [("orbit.md", &md), ("orbit.csv", &csv)] {
        atomic_write(&a.out.join(name), |tmp| std::fs::write(tmp, text).map_err(Into::into))?;
    }
    print!("{md}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_arc_keeps_the_target_and_the_distance() {
        let cam = Camera::look_at(Vec3::new(3.0, 1.0, 2.0), Vec3::new(0.0, 0.5, -1.0), Vec3::Y, 50.0);
        let target = cam.eye + cam.forward;
        for i in 0..5 {
            let c = orbit_camera(&cam, i, 5);
            assert!((c.eye + c.forward - target).length() < 1e-5);
            assert!((c.forward.length() - cam.forward.length()).abs() < 1e-5);
        }
        assert!(
            (orbit_camera(&cam, 2, 5).eye - cam.eye).length() < 1e-5,
            "the middle frame is the scene's view"
        );
        // Horizontal parts: the swing is about `up`, the vertical part stays.
        let flat = |i| (orbit_camera(&cam, i, 5).forward * Vec3::new(1.0, 0.0, 1.0)).normalize();
        let a = flat(0).dot(flat(4));
        assert!((a - (2.0 * ARC_DEG).to_radians().cos()).abs() < 1e-3, "{a}");
        assert_eq!(percentile(&[3.0, 1.0, 2.0, 4.0], 50.0), 2.0);
        assert_eq!(percentile(&[3.0, 1.0, 2.0, 4.0], 95.0), 4.0);
    }
}
