//! The stats JSON written by `hyrt render --stats`.

use serde::Serialize;

use hyrt::{plan::Plan, render::FrameStats, scene::Scene};

/// What one render did: scene, plan, rays by kind, time by pass.
#[derive(Serialize)]
pub struct RenderStats<'a> {
    pub scene: &'a str,
    pub source: Option<String>,
    pub triangles: usize,
    pub lights: usize,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub options: serde_json::Value,
    /// Names of the passes that ran, in order.
    pub plan: Vec<&'static str>,
    /// Every pass with the reason it ran or was skipped.
    pub plan_detail: &'a Plan,
    pub rays: hyrt_tracer::RayCounts,
    /// Per light, with map-based shadows: camera hits the map decided lit / shadowed, those
    /// left undecided (given a shadow ray), map faces drawn, pages used, drawn and held, map
    /// memory, and with `--check-visibility` the map decisions a shadow ray contradicts
    /// (`wrong`).
    pub shadow_lights: Vec<hyrt::render::shadows::LightStats>,
    /// With map-based shadows: `light_map_bytes`, `light_map_pages`, `light_map_pages_drawn`
    /// (the lights' totals, [`LightMapTotals`]).
    #[serde(flatten)]
    pub light_maps: Option<LightMapTotals>,
    /// What the frame rebuilt or reused (BVH, light maps, VPLs), and per light whether it
    /// needed a map and rays at all.
    pub frame_decisions: Vec<hyrt::render::FrameDecision>,
    /// Light maps built for this frame (0: all cached).
    pub maps_built: u32,
    /// With indirect light: the VPLs and the memory of their maps.
    pub vpls: u32,
    pub vpl_map_bytes: u64,
    /// (diffuse camera point, VPL) pairs of the indirect pass.
    pub vpl_pairs: u64,
    /// With `--visibility raster`: what the rasterizer processed (`Renderer::raster_stats`):
    /// triangles `submitted` after the cluster culling, `set_up` (kept for drawing), `tiny`
    /// (of those, pixel bounds of at most 2x2) and `bin_entries` ((triangle, tile) pairs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub raster: Option<serde_json::Value>,
    /// Milliseconds: `total` (BVH build + frame), `frame`, `bvh_build` and one entry per pass.
    pub time_ms: serde_json::Map<String, serde_json::Value>,
    /// With `--vs-reference`: the frame against the ray-traced reference.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vs_reference: Option<VsReference>,
    /// With `--vs-reference`: the first frame of each side on a fresh renderer.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_frame: Option<FirstFrame>,
}

/// The light maps of a frame with map-based shadows, summed over the lights
/// ([`hyrt::render::shadows::LightStats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LightMapTotals {
    /// Memory of the maps (`map_bytes`).
    pub light_map_bytes: u64,
    /// Pages the maps hold (`pages_held`).
    pub light_map_pages: u64,
    /// Pages drawn for this frame (`pages_drawn`; the others were reused).
    pub light_map_pages_drawn: u64,
}

impl LightMapTotals {
    /// The totals of `lights`, `None` without map-based shadows (no per-light stats).
    pub fn of(lights: &[hyrt::render::shadows::LightStats]) -> Option<Self> {
        (!lights.is_empty()).then(|| Self {
            light_map_bytes: lights.iter().map(|l| l.map_bytes).sum(),
            light_map_pages: lights.iter().map(|l| u64::from(l.pages_held)).sum(),
            light_map_pages_drawn: lights.iter().map(|l| u64::from(l.pages_drawn)).sum(),
        })
    }
}

/// `hyrt render --vs-reference`: the first frame of each side on a fresh renderer (its BVH
/// built, its maps and VPLs made), wall time, scene loading excluded; medians of a few
/// alternated runs.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FirstFrame {
    pub hybrid_ms: f64,
    /// The hybrid's `map_build` pass in those frames.
    pub hybrid_maps_ms: f64,
    pub reference_ms: f64,
}

/// `hyrt render --vs-reference`: medians of alternated frames with warm caches, and the image
/// against the reference's.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct VsReference {
    pub reference_ms: f64,
    pub hybrid_ms: f64,
    /// `reference_ms / hybrid_ms`.
    pub speedup: f64,
    /// PSNR of display luminance against the reference (`inf`: identical).
    #[serde(serialize_with = "hyrt::metrics::ser_psnr")]
    pub psnr_db: f64,
}

impl<'a> RenderStats<'a> {
    pub fn new(
        scene: &'a Scene,
        plan: &'a Plan,
        options: serde_json::Value,
        frame: &FrameStats,
        bvh_ms: f64,
    ) -> Self {
        let mut time_ms = serde_json::Map::new();
        let frame_ms = frame.total_ms;
        time_ms.insert("total".into(), (bvh_ms + frame_ms).into());
        time_ms.insert("frame".into(), frame_ms.into());
        time_ms.insert("bvh_build".into(), bvh_ms.into());
        for (k, v) in &frame.pass_ms {
            time_ms.insert(k.name().into(), (*v).into());
        }
        Self {
            scene: &scene.name,
            source: scene.source.as_ref().map(|p| p.display().to_string()),
            triangles: scene.triangle_count(),
            lights: scene.lights.len(),
            width: scene.settings.width,
            height: scene.settings.height,
            threads: rayon::current_num_threads(),
            options,
            plan: plan.pass_names(),
            plan_detail: plan,
            shadow_lights: frame.lights.clone(),
            light_maps: LightMapTotals::of(&frame.lights),
            frame_decisions: frame.decisions.clone(),
            maps_built: frame.maps_built,
            vpls: frame.vpls,
            vpl_map_bytes: frame.vpl_map_bytes,
            vpl_pairs: frame.vpl_pairs,
            rays: frame.rays,
            raster: None,
            time_ms,
            vs_reference: None,
            first_frame: None,
        }
    }

    /// Adds the rasterizer's counts ([`RenderStats::raster`]).
    pub fn with_raster(mut self, s: hyrt_raster::RasterStats) -> Self {
        self.raster = Some(serde_json::json!({
            "submitted": s.submitted,
            "set_up": s.set_up,
            "tiny": s.tiny,
            "bin_entries": s.bin_entries,
        }));
        self
    }
}
