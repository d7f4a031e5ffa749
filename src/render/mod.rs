//! One rendering pipeline whose stages take a strategy.
//!
//! The reference (Whitted) renderer and the hybrid one are two configurations of [`Options`],
//! never two renderers. A [`Renderer`] holds what frames share and cache (the BVH, the plan,
//! the light maps, the VPLs); a frame (`frame`) is the plan's passes in order over named
//! buffers, run and timed by one runner (`runner`). One concept per module: `visibility`,
//! `light` (a light seen from a point), `shadows` (map-based shadows: marking, the map cache,
//! classify, borders, border rays), `direct` (the reference's direct light), `vpl` and
//! `vpl_cache` (instant radiosity's lights), `indirect` and `gather` (indirect light),
//! `specular` (mirror paths).

pub mod cull;
mod decision;
pub mod direct;
mod frame;
mod gather;
pub mod indirect;
mod interleave;
pub mod light;
mod pixel_rays;
mod runner;
pub mod shadows;
pub mod specular;
pub mod surface;
pub mod visibility;
pub mod vpl;
mod vpl_cache;

use std::collections::BTreeMap;

use glam::Vec3;
use hyrt_tracer::{Hit, Ray, RayCounts, Tracer};
use rayon::prelude::*;

pub use crate::plan::Pass;
pub use decision::{Cache, FrameDecision, Run, Subject, format_decisions};
pub use surface::SurfaceHit;

use crate::{camera::CameraRays, film::Film, plan::Plan, scene::Scene};

pub use crate::options::{
    Ambiguous, Borders, CutoutMaps, Indirect, LightMaps, MirrorShadows, Neighbours, Options, ShadowOptions,
    Shadows, Visibility,
};

/// Per-frame statistics.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    pub rays: RayCounts,
    /// Light maps built (or extended) for this frame: 0 when all came from the cache.
    pub maps_built: u32,
    /// Per light: map decisions and borders (map-based shadows only).
    pub lights: Vec<shadows::LightStats>,
    /// With indirect light: the number of VPLs and the memory of their maps.
    pub vpls: u32,
    pub vpl_map_bytes: u64,
    /// (diffuse camera point, VPL) pairs the indirect pass evaluated (each pixel's VPL subset
    /// under interleaving; mirror hits not included): the unit of its cost per pair.
    pub vpl_pairs: u64,
    /// Milliseconds per pass that ran (its parts, [`Pass::part_of`], included apart).
    pub pass_ms: BTreeMap<Pass, f64>,
    /// Milliseconds of the whole frame (scene preparation excluded).
    pub total_ms: f64,
    /// What this frame rebuilt or reused, and the per-light decisions of map-based shadows.
    pub decisions: Vec<crate::render::FrameDecision>,
}

impl FrameStats {
    /// Milliseconds of `pass` in this frame; 0 where it did not run.
    pub fn ms(&self, pass: Pass) -> f64 {
        self.pass_ms.get(&pass).copied().unwrap_or(0.0)
    }
}

/// A rendered frame.
pub struct Frame {
    pub film: Film,
    pub stats: FrameStats,
    /// With map-based shadows and `Options::keep_buffers`: the per-light occlusion, border and
    /// (with `check_visibility`) wrong-decision buffers.
    pub shadows: Option<shadows::ShadowBuffers>,
    /// With `Options::keep_buffers`: the camera hit of every pixel (triangle, distance,
    /// barycentrics), and the rays cast on behalf of every pixel by kind (module
    /// `pixel_rays`: they sum to the frame's rays minus the VPL path rays).
    pub gbuffer: Option<Vec<Option<Hit>>>,
    pub pixel_rays: Option<Vec<RayCounts>>,
}

/// A scene prepared for rendering: its BVH and plan, built once and reused by every frame.
pub struct Renderer<'a> {
    pub scene: &'a Scene,
    pub tracer: Tracer,
    pub plan: Plan,
    /// Private so that changes go through [`Renderer::set_options`], which drops stale caches.
    pub(crate) options: Options,
    pub camera: CameraRays,
    /// The point lights: the scene's, until [`Renderer::set_light`] moves one.
    pub(crate) lights: Vec<crate::scene::PointLight>,
    /// Rasterization near-plane distance (see `visibility::near_plane`), fixed per scene.
    pub raster_near: f32,
    /// Bounding boxes of runs of triangles, for frustum culling before rasterization.
    pub clusters: cull::Clusters,
    /// Buffers of the raster visibility pass, kept between frames (see
    /// [`visibility::RasterScratch`]).
    raster: std::sync::Mutex<visibility::RasterScratch>,
    /// Light maps, built on first use and kept while the scene is unchanged.
    maps: shadows::MapCache,
    /// VPLs and their maps, likewise.
    vpl_cache: vpl_cache::VplCache,
    /// Rays per pixel, with `Options::keep_buffers`.
    pub(crate) pixel_rays: pixel_rays::PixelRays,
    /// The G-buffer of the last frame, reused by the next: the visibility pass overwrites every
    /// pixel, and a fresh one (tens of bytes per pixel) cost a fill pass of its own.
    gbuffer: std::sync::Mutex<Vec<Option<Hit>>>,
    /// The scene's bounding box (`Scene::bounds` walks every vertex: once per scene).
    pub(crate) bounds: Option<(Vec3, Vec3)>,
    /// What map classification needs of the scene, made on first use and shared by the light
    /// maps and the VPL maps: every triangle's plane, and the rounding error of a shading point
    /// ([`hyrt_shadowmap::classify::point_error_bound`]).
    occluders: std::sync::OnceLock<(Vec<hyrt_shadowmap::classify::Plane>, f32)>,
    /// Per triangle, its group of coplanar triangles ([`hyrt_shadowmap::classify::plane_groups`]):
    /// the light maps summarise their regions by group, and classification decides a tile on
    /// one plane at once. Made on first use.
    plane_groups: std::sync::OnceLock<Vec<u32>>,
    /// [`Renderer::cutouts`].
    cutouts: Vec<bool>,
}

/// Called once per finished row of each pass (for progress bars).
pub type Progress<'p> = &'p (dyn Fn() + Sync);

impl<'a> Renderer<'a> {
    /// Builds the BVH and the plan. The scene must have passed `Scene::validate`.
    pub fn new(scene: &'a Scene, options: Options) -> Self {
        let plan = Plan::with_lights(scene, &scene.lights, &options);
        // A frame that rasterizes its visibility casts no ray before its shading passes: the
        // BVH (a serial build) is then built on a thread of its own meanwhile.
        let tracer = match options.visibility {
            Visibility::Raster => Tracer::build_in_background(&scene.positions),
            Visibility::Rays => Tracer::build(&scene.positions),
        };
        let cutouts = scene.cutout_flags();
        let tracer = match crate::scene::cutout::CutoutTest::of(scene, &cutouts) {
            Some(test) => tracer.with_cutouts(Box::new(test)),
            None => tracer,
        };
        let cam = scene.camera.expect("validated scene has a camera");
        let camera = CameraRays::new(&cam, scene.settings.width, scene.settings.height);
        let raster_near = visibility::near_plane(scene, &camera);
        // Always: a few milliseconds for the largest scenes, and `set_options` may switch to
        // raster visibility.
        let clusters = cull::Clusters::new(&scene.positions);
        let (raster, maps, vpl_cache) = Default::default();
        let n = scene.settings.width as usize * scene.settings.height as usize;
        let pixel_rays = pixel_rays::PixelRays::new(n, options.keep_buffers);
        Self {
            scene,
            tracer,
            plan,
            options,
            camera,
            lights: scene.lights.clone(),
            raster_near,
            clusters,
            raster,
            maps,
            vpl_cache,
            pixel_rays,
            gbuffer: Default::default(),
            bounds: scene.bounds(),
            occluders: Default::default(),
            plane_groups: Default::default(),
            cutouts,
        }
    }

    /// Per triangle, whether it has an alpha cut-out; empty when none has
    /// ([`crate::scene::Scene::cutout_flags`]).
    pub fn cutouts(&self) -> &[bool] {
        &self.cutouts
    }

    /// The planes of the scene's triangles and the rounding error of a shading point, for
    /// [`hyrt_shadowmap::classify::Classifier`] (made on the first call).
    pub fn occluders(&self) -> (&[hyrt_shadowmap::classify::Plane], f32) {
        let (planes, e) = self.occluders.get_or_init(|| {
            use hyrt_shadowmap::classify::{point_error_bound, triangle_planes};
            (triangle_planes(&self.scene.positions), point_error_bound(&self.scene.positions))
        });
        (planes, *e)
    }

    /// Per triangle, its group of coplanar triangles (see [`Renderer::occluders`]).
    pub fn plane_groups(&self) -> &[u32] {
        self.plane_groups
            .get_or_init(|| hyrt_shadowmap::classify::plane_groups(self.occluders().0, self.cutouts()))
    }

    /// Changes the strategies and knobs of the next frames, keeping every cache the change
    /// leaves valid: the BVH always (the scene is the same), the light maps unless their kind,
    /// resolution or tessellation changed, the VPLs unless their count, bounces or seed changed,
    /// and the VPL maps unless those or the VPL map options changed. Returns what was dropped.
    pub fn set_options(&mut self, options: Options) -> Vec<&'static str> {
        let old = self.options;
        let mut dropped = Vec::new();
        let (a, b) = (&old.shadow, &options.shadow);
        if a.map != b.map
            || a.light_maps != b.light_maps
            || a.map_detail != b.map_detail
            || a.map_budget != b.map_budget
            || a.map_horizon != b.map_horizon
            || a.cutouts != b.cutouts
        {
            // Which pages (or faces) the view needs depends on all of these but the resolution
            // and tessellation of whole maps.
            let needs = a.map.kind != b.map.kind
                || a.light_maps != b.light_maps
                || a.map_detail != b.map_detail
                || a.map_budget != b.map_budget
                || a.map_horizon != b.map_horizon;
            self.drop_light_maps(needs);
            dropped.push("light maps");
        }
        let (a, b) = (&old.indirect_opts, &options.indirect_opts);
        if a.vpl != b.vpl {
            self.vpl_cache = vpl_cache::VplCache::dropped_because("the VPL knobs changed");
            dropped.push("VPLs and their maps");
        } else if a.map != b.map {
            self.vpl_cache.drop_maps();
            dropped.push("VPL maps");
        }
        if options.keep_buffers != self.pixel_rays.enabled() {
            let n = self.scene.settings.width as usize * self.scene.settings.height as usize;
            self.pixel_rays = pixel_rays::PixelRays::new(n, options.keep_buffers);
        }
        self.plan = Plan::with_lights(self.scene, &self.lights, &options);
        self.options = options;
        dropped
    }

    /// The strategies and knobs of the next frame.
    pub fn options(&self) -> &Options {
        &self.options
    }

    /// Wall time of the BVH build, in milliseconds.
    pub fn bvh_build_ms(&self) -> f64 {
        self.tracer.build_time().as_secs_f64() * 1e3
    }

    /// Number of pixel passes that report progress (rows each).
    pub fn progress_passes(&self) -> u32 {
        Pass::ALL.iter().filter(|p| p.reports_rows() && self.plan.runs(**p)).count() as u32
    }

    /// Moves the camera (same image size). What depends on the scene alone is kept: the BVH,
    /// the light maps, the VPLs and their maps. The next frame finds which light-map faces the
    /// new view's hits fall on and draws only those not drawn yet
    /// ([`LightMap::merge`](hyrt_shadowmap::LightMap::merge)); its decisions say so.
    pub fn set_camera(&mut self, camera: &crate::scene::Camera) {
        self.camera = CameraRays::new(camera, self.scene.settings.width, self.scene.settings.height);
        self.raster_near = visibility::near_plane(self.scene, &self.camera);
        self.forget_needed_faces();
    }

    /// The point lights the frames use: the scene's, as moved by [`Renderer::set_light`].
    pub fn lights(&self) -> &[crate::scene::PointLight] {
        &self.lights
    }

    /// Moves (or changes the intensity of) light `l`. What depends on that light is dropped:
    /// its map, which the next frame builds again (the other lights' maps are kept and reused),
    /// and the VPLs its paths left, with their maps (all VPLs when the intensity changed, since
    /// the paths are shared out by power). The next frame's decisions say what was rebuilt and
    /// how long it took. Returns what was dropped; nothing when the light is unchanged, or `l`
    /// is not a light.
    pub fn set_light(&mut self, l: usize, light: crate::scene::PointLight) -> Vec<&'static str> {
        let Some(old) = self.lights.get(l).copied() else { return Vec::new() };
        if old == light {
            return Vec::new();
        }
        self.lights[l] = light;
        let mut dropped = Vec::new();
        if old.position != light.position
            || (old.intensity.max_element() > 0.0) != (light.intensity.max_element() > 0.0)
        {
            self.drop_light_map(l);
            dropped.push("the light's map");
        }
        if old.intensity == light.intensity {
            // The paths are shared out by power: the same, so the other lights' VPLs stay.
            self.vpl_cache.relight(l, self.lights.len());
            dropped.push("the light's VPLs and their maps");
        } else {
            self.vpl_cache = vpl_cache::VplCache::dropped_because("a light's intensity changed");
            dropped.push("VPLs and their maps");
        }
        self.plan = Plan::with_lights(self.scene, &self.lights, &self.options);
        dropped
    }

    /// Whether triangle `tri`'s material reflects diffusely (indirect light reaches it).
    pub(crate) fn diffuse(&self, tri: u32) -> bool {
        self.scene.materials[self.scene.material[tri as usize] as usize].diffuse != Vec3::ZERO
    }

    /// The camera ray through the centre of pixel `(x, y)`.
    #[inline]
    pub fn camera_ray(&self, x: u32, y: u32) -> Ray {
        Ray::new(self.camera.eye, self.camera.direction(x, y).normalize(), f32::INFINITY)
    }

    /// Runs only the visibility pass (for tests and benchmarks): the G-buffer and its stats.
    /// Give the G-buffer back with [`Renderer::recycle_gbuffer`] to spare the next pass its
    /// allocation, as frames do.
    pub fn visibility(&self) -> (Vec<Option<Hit>>, FrameStats) {
        let mut run = runner::Runner::new(&self.plan);
        let (g, _) = visibility::run(self, &|| {}, &mut run, false);
        (g, run.finish())
    }

    /// What the rasterizer processed in the last raster visibility pass (all zero before one):
    /// submitted, set-up and tiny triangles, bin entries. Counted on demand, outside any pass.
    pub fn raster_stats(&self) -> hyrt_raster::RasterStats {
        self.raster.lock().unwrap_or_else(|e| e.into_inner()).rasterizer.stats()
    }

    /// Keeps `gbuffer` for the next visibility pass to overwrite.
    pub fn recycle_gbuffer(&self, gbuffer: Vec<Option<Hit>>) {
        *self.gbuffer.lock().unwrap_or_else(|e| e.into_inner()) = gbuffer;
    }

    /// The recycled G-buffer with `n` elements (of any value), or a fresh one.
    pub(crate) fn take_gbuffer(&self, n: usize) -> Vec<Option<Hit>> {
        let mut g = std::mem::take(&mut *self.gbuffer.lock().unwrap_or_else(|e| e.into_inner()));
        if g.len() != n {
            // In parallel: a sequential fill was a visible part of the raster pass.
            g.clear();
            g.par_extend(rayon::iter::repeat_n(None, n));
        }
        g
    }
}

/// Runs `f` on every row of `buf` in parallel, each row with its own ray counts; the counts are
/// summed in row order, so totals do not depend on the thread count.
pub(crate) fn par_rows<T: Send>(
    buf: &mut [T],
    width: usize,
    progress: Progress,
    f: impl Fn(u32, &mut [T], &mut RayCounts) + Sync,
) -> RayCounts {
    buf.par_chunks_mut(width.max(1))
        .enumerate()
        .map(|(y, row)| {
            let mut c = RayCounts::default();
            f(y as u32, row, &mut c);
            progress();
            c
        })
        .collect::<Vec<_>>()
        .into_iter()
        .sum()
}
