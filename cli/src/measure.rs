//! Measuring configurations side by side: the core of `hyrt bench` and `hyrt sweep`.
//!
//! The machines are shared and noisy, so a comparison is measured in one process, with the
//! configurations' frames alternated (frame 1 of every configuration, then frame 2, ...) and
//! summarised by medians. Every configuration renders one warm-up frame first, on a fresh
//! renderer ([`cold_first_frame`]): it builds the BVH-independent caches (light maps, VPLs and
//! their maps), whose cost is reported separately (`first_frame_ms`, `map_build_ms`, and with
//! the BVH build and in wall time `cold_first_frame_ms`) because a second frame of an unchanged
//! scene reuses them.
//!
//! Accuracy is measured against a reference film: PSNR of display luminance
//! ([`hyrt::metrics`]), and for map-based shadows the wrong-visibility pixels, from one more
//! frame rendered with `check_visibility` (a shadow ray per map decision; not timed).

use std::{collections::BTreeMap, time::Instant};

use hyrt_tracer::RayCounts;
use serde::Serialize;

pub use hyrt::metrics::{Timing, psnr, wrong_visibility};
use hyrt::{
    film::Film,
    render::{Frame, Options, Pass, Renderer, Shadows, shadows::SameRays},
    scene::Scene,
};

/// A named configuration to measure.
#[derive(Clone, Debug)]
pub struct Config {
    pub label: String,
    pub options: Options,
    /// The scene this configuration renders instead of [`measure`]'s (the same scene made
    /// otherwise, such as without its textures), its frames alternated with the others.
    pub scene: Option<std::sync::Arc<Scene>>,
}

/// What measuring one configuration on one scene gave.
#[derive(Clone, Debug, Serialize)]
pub struct Measurement {
    pub label: String,
    /// Steady-state frame time (caches warm), over the timed frames.
    pub frame_ms: Timing,
    /// Median per pass over the timed frames (`FrameStats::time_ms` keys, `total` excluded).
    pub pass_ms: BTreeMap<String, f64>,
    /// The first frame, which builds the light and VPL maps (its `total`, the BVH excluded).
    pub first_frame_ms: f64,
    /// What one image of this configuration costs from scratch ([`cold_first_frame`]): the
    /// wall time of creating the renderer (BVH build) and rendering the first frame (map
    /// building), scene loading excluded.
    pub cold_first_frame_ms: f64,
    /// Light-map and VPL-map build time of the first frame.
    pub map_build_ms: f64,
    /// BVH build when the renderer was created.
    pub bvh_build_ms: f64,
    /// Rays of one steady-state frame, by kind (identical from frame to frame).
    pub rays: RayCounts,
    /// Memory of the light maps and VPL maps after the first frame, in bytes.
    pub map_bytes: u64,
    /// Memory of the light maps alone in the last frame (`LightStats::map_bytes` summed over
    /// the lights; 0 without map-based shadows), in bytes.
    pub light_map_bytes: u64,
    /// (camera point, VPL) pairs of the indirect pass per frame (`FrameStats::vpl_pairs`).
    pub vpl_pairs: u64,
    /// Map-based shadows: the (camera hit, light) pairs the classify pass decides per frame
    /// (lit, shadowed, or left to a ray; `LightStats`), summed over the lights.
    pub map_decisions: u64,
    /// Of those, the pairs decided with the rest of their tile at once (`LightStats::by_tile`):
    /// the rest were decided point by point, at several times the cost.
    pub map_decisions_by_tile: u64,
    /// Map-based shadows: the (camera hit, light) pairs a shadow ray decided per frame (the
    /// border rays of the `shadow_rays` pass; `LightStats::undecided`), summed over the lights.
    /// The shadow rays of mirror hits are the specular pass's.
    pub border_rays: u64,
    /// Against the reference film, if one was given.
    pub psnr_db: Option<f64>,
    /// Map-based shadows with a check frame: (pixel, light) pairs whose map decision a shadow
    /// ray contradicts, summed over the lights, and the number of distinct such pixels.
    pub wrong_pairs: Option<u64>,
    pub wrong_pixels: Option<u64>,
    /// Border rays with shadow rays from the reference's: what each costs traced alike, on
    /// one frame's very rays ([`hyrt::render::shadows::SameRays`]; with border rays only).
    pub same_rays: Option<SameRays>,
    /// The last frame's film (not serialised).
    #[serde(skip)]
    pub film: Film,
}

/// How to measure.
#[derive(Clone, Copy, Debug)]
pub struct MeasureOptions {
    /// Timed frames per configuration, after one warm-up frame.
    pub runs: usize,
    /// Render one more, untimed frame with `check_visibility` to count wrong-visibility pixels
    /// (configurations with map-based shadows only).
    pub check: bool,
    /// Trace one frame's border rays and shadow rays again, alike, in this process
    /// (configurations with border rays only): [`Measurement::same_rays`].
    pub same_rays: bool,
}

/// Runs of each set of rays in [`Renderer::same_rays`].
const SAME_RAYS_RUNS: usize = 5;

/// A fresh [`Renderer`] of `options` and its first frame, as one image costs from the command
/// line: the wall time of [`Renderer::new`] (BVH, plan) and of the frame (light maps, VPLs and
/// their maps built, nothing cached), in milliseconds; scene loading excluded.
pub fn cold_first_frame(scene: &Scene, options: Options) -> (Renderer<'_>, Frame, f64) {
    let start = Instant::now();
    let renderer = Renderer::new(scene, options);
    let frame = renderer.render(&|| {});
    let ms = start.elapsed().as_secs_f64() * 1e3;
    (renderer, frame, ms)
}

/// The light maps' memory in `frame` (0 without map-based shadows).
fn light_map_bytes(frame: &Frame) -> u64 {
    frame.stats.lights.iter().map(|l| l.map_bytes).sum()
}

fn border_rays(frame: &Frame) -> u64 {
    frame.stats.lights.iter().map(|l| l.undecided).sum()
}

fn map_decisions(frame: &Frame) -> u64 {
    frame.stats.lights.iter().map(|l| l.lit + l.shadowed + l.undecided).sum()
}

fn map_decisions_by_tile(frame: &Frame) -> u64 {
    frame.stats.lights.iter().map(|l| l.by_tile).sum()
}

/// Measures `configs` on `scene`, their timed frames alternated, and compares each film with
/// `reference` (a film of the same size) when given. `progress` is called after every frame
/// with the configuration's label.
///
/// Each configuration's warm-up frame is its [`cold_first_frame`], made after the previous
/// configurations' warm-up frames. All renderers (and their maps) are alive at once: pass a few
/// configurations at a time.
pub fn measure(
    scene: &Scene,
    configs: &[Config],
    reference: Option<&Film>,
    mo: MeasureOptions,
    progress: &dyn Fn(&str),
) -> anyhow::Result<Vec<Measurement>> {
    if let Some(r) = reference
        && (r.width, r.height) != (scene.settings.width, scene.settings.height)
    {
        anyhow::bail!(
            "reference film is {}x{}, the scene renders {}x{}",
            r.width,
            r.height,
            scene.settings.width,
            scene.settings.height
        );
    }
    let (mut renderers, mut out) = (Vec::new(), Vec::new());
    for c in configs {
        let (r, f, cold_ms) = cold_first_frame(c.scene.as_deref().unwrap_or(scene), c.options);
        progress(&c.label);
        let t = |p: Pass| f.stats.ms(p);
        out.push(Measurement {
            label: c.label.clone(),
            frame_ms: Timing::default(),
            pass_ms: BTreeMap::new(),
            first_frame_ms: f.stats.total_ms,
            cold_first_frame_ms: cold_ms,
            map_build_ms: t(Pass::MapBuild) + t(Pass::VplMapBuild),
            bvh_build_ms: r.bvh_build_ms(),
            rays: f.stats.rays,
            map_bytes: light_map_bytes(&f) + f.stats.vpl_map_bytes,
            light_map_bytes: light_map_bytes(&f),
            vpl_pairs: f.stats.vpl_pairs,
            map_decisions: map_decisions(&f),
            map_decisions_by_tile: map_decisions_by_tile(&f),
            border_rays: border_rays(&f),
            psnr_db: None,
            wrong_pairs: None,
            wrong_pixels: None,
            same_rays: None,
            film: f.film,
        });
        renderers.push(r);
    }

    let mut frames: Vec<Vec<f64>> = vec![Vec::new(); configs.len()];
    let mut passes: Vec<BTreeMap<String, Vec<f64>>> = vec![BTreeMap::new(); configs.len()];
    for _ in 0..mo.runs {
        for (i, r) in renderers.iter().enumerate() {
            let f = r.render(&|| {});
            progress(&configs[i].label);
            frames[i].push(f.stats.total_ms);
            for (k, v) in &f.stats.pass_ms {
                {
                    passes[i].entry(k.name().to_string()).or_default().push(*v);
                }
            }
            out[i].rays = f.stats.rays;
            out[i].light_map_bytes = light_map_bytes(&f);
            out[i].map_decisions = map_decisions(&f);
            out[i].map_decisions_by_tile = map_decisions_by_tile(&f);
            out[i].border_rays = border_rays(&f);
            out[i].film = f.film;
        }
    }
    for (i, m) in out.iter_mut().enumerate() {
        m.frame_ms = Timing::of(&frames[i]);
        m.pass_ms = passes[i].iter().map(|(k, v)| (k.clone(), Timing::of(v).median)).collect();
        if let Some(r) = reference {
            m.psnr_db = Some(psnr(scene, r, &m.film)?);
        }
    }
    drop(renderers);

    if mo.same_rays {
        for (m, c) in out.iter_mut().zip(configs) {
            if c.options.shadows != Shadows::Smerts {
                continue;
            }
            // A warm frame, its buffers kept: the timed frames' decisions.
            let options = Options { keep_buffers: true, ..c.options };
            let r = Renderer::new(c.scene.as_deref().unwrap_or(scene), options);
            r.render(&|| {});
            m.same_rays = r.same_rays(&r.render(&|| {}), SAME_RAYS_RUNS);
            progress(&c.label);
        }
    }

    if mo.check {
        for (m, c) in out.iter_mut().zip(configs) {
            if c.options.shadows == Shadows::Rays {
                continue;
            }
            let (pairs, pixels) = wrong_visibility(c.scene.as_deref().unwrap_or(scene), c.options);
            progress(&c.label);
            (m.wrong_pairs, m.wrong_pixels) = (Some(pairs), Some(pixels));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Alternated frames of two configurations on the built-in scene: every timed frame is
    /// counted, the reference compared with itself is exact, and the hybrid's wrong-visibility
    /// pixels are counted (and no more than its (pixel, light) pairs).
    #[test]
    fn measures_side_by_side() {
        let mut scene = hyrt::scene::load("cornell").unwrap();
        scene.settings.width = 64;
        scene.settings.height = 48;
        let reference = Renderer::new(&scene, Options::reference()).render(&|| {}).film;
        let configs = [
            Config { label: "reference".into(), options: Options::reference(), scene: None },
            Config { label: "hybrid".into(), options: Options::hybrid(), scene: None },
        ];
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let mo = MeasureOptions { runs: 3, check: true, same_rays: true };
        let m = measure(&scene, &configs, Some(&reference), mo, &|_| {
            calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
        // 2 warm-up + 2 x 3 timed + 1 check frame (the reference has no map decisions) + 1
        // frame whose rays are traced again (the reference has no border rays).
        assert_eq!(calls.into_inner(), 2 + 6 + 1 + 1);
        assert_eq!(m[0].frame_ms.runs, 3);
        assert_eq!(m[0].psnr_db, Some(f64::INFINITY));
        assert!(m[1].psnr_db.unwrap() > 30.0, "{:?}", m[1].psnr_db);
        assert_eq!(m[0].wrong_pairs, None);
        // The border rays traced again are the timed frames' own, and among the frame's pairs.
        assert!(m[0].same_rays.is_none());
        let same = m[1].same_rays.expect("the hybrid has border rays");
        assert_eq!(same.border_rays, m[1].border_rays);
        assert!(same.all_rays >= same.border_rays && same.all_rays <= m[1].map_decisions, "{same:?}");
        assert!(same.border_plain_ns > 0.0 && same.border_hint_ns > 0.0 && same.all_plain_ns > 0.0);
        let (pairs, pixels) = (m[1].wrong_pairs.unwrap(), m[1].wrong_pixels.unwrap());
        assert!(pixels <= pairs, "{pixels} > {pairs}");
        // Raster visibility: a ray only where a pixel's ray leaves its rasterized triangle.
        assert!(m[1].rays.primary * 100 < m[0].rays.primary, "{:?}", m[1].rays);
        assert!(m[0].rays.primary > 0 && m[0].map_bytes == 0 && m[1].map_bytes > 0);
        // The hybrid's maps are light maps (no VPLs here); the cold first frame holds the BVH
        // build and the warm-up frame, in wall time: one after the other for ray visibility,
        // side by side for raster visibility (the BVH builds beside the first passes).
        assert!(m[0].light_map_bytes == 0 && m[1].light_map_bytes == m[1].map_bytes);
        let (cold, bvh, first) = (m[0].cold_first_frame_ms, m[0].bvh_build_ms, m[0].first_frame_ms);
        assert!(cold >= bvh + first, "{}: {cold} < {bvh} + {first}", m[0].label);
        let (cold, bvh, first) = (m[1].cold_first_frame_ms, m[1].bvh_build_ms, m[1].first_frame_ms);
        assert!(cold >= bvh.max(first), "{}: {cold} < max({bvh}, {first})", m[1].label);
    }
}
