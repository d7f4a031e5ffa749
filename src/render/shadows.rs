//! Point-light visibility from depth maps: SMeRTS (shadow maps + selective ray tracing).
//!
//! Per frame, for the camera hits of the G-buffer, as a sequence of passes over named buffers;
//! the per-pixel buffers hold one bit per light (`LightBits`), not a screen per light:
//!
//! ```text
//! map_build    light maps: only faces some camera hit falls on; cached until the scene changes
//! classify     8x8 tile by tile: the shading points, then per light each point's location and
//!              map decision -> faces, lit, edge (the 2x2 texel footprint disagrees; its occluder
//!              hint kept); then the tile's direct light from those decisions
//! borders      (Smerts) und = dilate(edge and/or laplacian(lit, faces), R), byte ops over 8 lights
//! shadow_rays  the undecided (pixel, light) pairs listed light by light, in screen order: a
//!              shadow ray each (the hint classify kept first), in fixed chunks; the
//!              answers into lit, and the direct light of those pixels again
//! ```
//!
//! Fusing the shading points, the decisions and the shading into one pass keeps a tile's points
//! in L1 while every light decides them; the alternative, a screen-sized buffer per light and a
//! pass per buffer, spent its time writing and reading those buffers. The occluder hint is kept
//! for the map-space border pairs alone, as a list per light in pixel order: the only pairs that
//! need it, and looking the point up in the map again cost each border ray more than the
//! list's search.
//!
//! With `Shadows::Maps` the map's decision is final (no borders, no rays): the pure shadow-map
//! baseline. Mirror hits have no screen neighbours: they use the map-space test alone
//! ([`Shadowing::visible_at`]).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use glam::Vec3;
use hyrt_shadowmap::{
    EMPTY, LightMap, MapCoord, MapKind, PageKey,
    classify::Decision,
    classify::{Classifier, Hull, Lookup, Plane},
    map::Holes,
    paged::{self, LightTerms, PageRect, Resolution},
};
use hyrt_tracer::{Hit, PlaneSide, RayCounts, RayKind, plane_side, spawn_ray_to};
use rayon::prelude::*;
use serde::Serialize;

use super::gather::ShadePoint;
use super::{
    Ambiguous, Borders, CutoutMaps, FrameStats, LightMaps, MirrorShadows, Renderer, Shadows, SurfaceHit,
};

/// One band of classify's outputs: direct light, and the face, lit and edge bits.
type Band<'a> = (((&'a mut [Vec3], &'a mut [u8]), &'a mut [u8]), &'a mut [u8]);
use crate::{
    render::{Cache, FrameDecision, Run, Subject},
    scene::PointLight,
};

/// Whether `light` can light `hit` at all (a light with some intensity, strictly in front of
/// the surface's plane and of its shading normal, not at the point): the condition under which
/// the reference casts a shadow ray. `Some((wi, cos, d2))` if so. `tri` is the hit triangle's
/// corners.
///
/// The side of the plane is decided from the triangle's corners and the light alone
/// ([`plane_side`]), not from `ng . (light - p)`: the shading point's rounding error is as large
/// as that product near a light lying in the plane, whose every exact evaluation is 0. A light
/// in the plane therefore lights none of it, in the reference and the hybrid alike.
#[inline]
pub fn facing(hit: &SurfaceHit, light: &PointLight, tri: &[Vec3; 3]) -> Option<(Vec3, f32, f32)> {
    let g = light_geometry(hit, light)?;
    viewer_side(hit, tri, plane_side(tri, light.position)).then_some(g)
}

/// Whether a light on side `side` of `tri`'s plane ([`plane_side`], which depends on the
/// triangle and the light only, so that callers may reuse it across the pixels of a triangle)
/// is on the side `hit` is seen from: `hit.ng` is the winding's normal flipped towards the
/// viewer.
#[inline]
pub fn viewer_side(hit: &SurfaceHit, tri: &[Vec3; 3], side: PlaneSide) -> bool {
    on_viewer_side(seen_winding(hit, tri), side)
}

/// `hit.ng . winding` of `tri`: its sign says which side of the plane `hit` is seen from, for
/// [`on_viewer_side`] (one per hit, for all lights).
#[inline]
fn seen_winding(hit: &SurfaceHit, tri: &[Vec3; 3]) -> f32 {
    hit.ng.dot((tri[1] - tri[0]).cross(tri[2] - tri[0]))
}

/// [`viewer_side`] from the hit's [`seen_winding`].
#[inline]
fn on_viewer_side(seen: f32, side: PlaneSide) -> bool {
    match side {
        PlaneSide::In => false,
        PlaneSide::Front => seen > 0.0,
        PlaneSide::Back => seen < 0.0,
    }
}

/// [`plane_side`] of every light for the last triangle asked: a pass over a row of pixels
/// crosses runs of pixels on one triangle, and the exact test depends on the triangle and the
/// light only.
pub(crate) struct PlaneSides {
    tri: u32,
    sides: Vec<PlaneSide>,
}

impl PlaneSides {
    pub(crate) fn new() -> Self {
        Self { tri: u32::MAX, sides: Vec::new() }
    }

    /// The side of each of `lights` relative to triangle `id`'s plane (corners `tri`).
    #[inline]
    pub(crate) fn of(&mut self, id: u32, tri: &[Vec3; 3], lights: &[PointLight]) -> &[PlaneSide] {
        if self.tri != id {
            self.tri = id;
            self.sides.clear();
            self.sides.extend(lights.iter().map(|l| plane_side(tri, l.position)));
        }
        &self.sides
    }
}

/// Whether unit direction `d` from a spot light lies outside its cone by more than a margin:
/// marking samples every few pixels and counts on a receiver's neighbours needing its pages,
/// so it stops a little beyond the cone (a page it misses is decided by a ray all the same).
fn outside_with_margin(s: &crate::scene::Spot, d: Vec3) -> bool {
    // 0.05 of the cosine: a few degrees for wide cones, more for narrow ones.
    s.axis.dot(d) < s.cos_outer - 0.05
}

/// The part of [`facing`] that does not ask the side of the plane: `Some((wi, cos, d2))` for
/// a light with some intensity, not at the point, in front of the shading normal. Passes that
/// already know that the light faces the point (a map decision was made for it) use this alone.
#[inline]
pub fn light_geometry(hit: &SurfaceHit, light: &PointLight) -> Option<(Vec3, f32, f32)> {
    light_geometry_and_terms(hit, light).0
}

/// [`light_geometry`], and the point's [`LightTerms`] with its geometric normal (its map level's
/// terms), from one offset to the light and one square root.
#[inline]
fn light_geometry_and_terms(hit: &SurfaceHit, light: &PointLight) -> (Option<(Vec3, f32, f32)>, LightTerms) {
    let to_light = light.position - hit.p;
    let d2 = to_light.length_squared();
    // `length()` is `length_squared().sqrt()`: the terms are `LightTerms::of`'s.
    let r = d2.sqrt();
    let terms = LightTerms::of_offset(hit.ng, to_light, r);
    // A dark light adds nothing: no ray, no map (the plan says so); nor does a spot light
    // outside its cone.
    if light.intensity.max_element() <= 0.0 || d2 == 0.0 {
        return (None, terms);
    }
    let wi = to_light / r;
    if light.dark_towards(-wi) {
        return (None, terms);
    }
    let cos = hit.ns.dot(wi);
    ((cos > 0.0).then_some((wi, cos, d2)), terms)
}

/// Per-renderer state of map-based shadows: the light maps and the per-pixel buffers, recycled
/// from frame to frame.
#[derive(Default)]
pub(crate) struct MapCache {
    maps: Mutex<Vec<Option<Arc<LightMap>>>>,
    /// What the camera hits need of the maps: a renderer's scene and camera are fixed, so this
    /// is computed on the first frame only.
    needed: std::sync::OnceLock<Needs>,
    /// Lights whose map was dropped because they moved ([`Renderer::set_light`]), until the
    /// next frame builds it again (its decision says why).
    moved: Mutex<Vec<bool>>,
    /// Buffers of the last frame, reused (allocating them afresh costs page faults).
    scratch: Mutex<ShadowBuffers>,
}

/// What a view's camera hits need of the light maps.
#[derive(Debug, Default)]
pub(crate) struct Needs {
    /// Per light and face (light-major), whether a camera hit the light faces falls on it.
    faces: Vec<bool>,
    /// Paged maps: per light, the pages the camera hits fall on (sorted), and the level guide
    /// they were marked with (empty for whole maps).
    pages: Vec<Vec<PageKey>>,
    resolution: Vec<Resolution>,
}

/// The level guide of paged maps for `camera` (`hyrt_shadowmap::paged`): a pixel subtends
/// `2 tan(fov_y / 2) / height` radians at the image centre. A frame's guide for light `l` is
/// this one capped at [`LightStats::level_cap`].
pub fn resolution_guide(camera: &crate::camera::CameraRays, shadow: &super::ShadowOptions) -> Resolution {
    let pixel = 2.0 * camera.tan_y / camera.height.max(1) as f32;
    Resolution::new(camera.eye, pixel, shadow.map_detail)
}

/// A paged light map's pages to draw for a frame ([`Renderer::light_maps`]).
struct PageJob {
    light: usize,
    draw: Vec<PageKey>,
    /// What is done with the cached map, and why.
    why: (Cache, String),
    /// The pages in use, for the decision.
    in_use: String,
    /// The index of the light's decision.
    decision: usize,
}

/// What the map-build pass made for a frame.
struct FrameMaps {
    /// Per light, its map.
    maps: Vec<Arc<LightMap>>,
    /// Maps built or extended.
    built: u32,
    /// Per light, what was done and why.
    decisions: Vec<FrameDecision>,
    /// Paged maps: per light, the pages in use and those drawn for this frame.
    page_counts: Vec<[u32; 2]>,
}

/// Paged maps with SMeRTS: the camera hits marked are one pixel in `MARK_STEP x MARK_STEP`
/// (with maps alone, which cast no rays, every hit).
///
/// Why: marking is a pass over every camera hit and light, a large part of a first frame and of
/// every moved view. A pixel's pages are almost always its neighbours' (they lie within the
/// marking margin of a texel or two at the same level); a lookup that reaches a page no marked
/// neighbour did reads `ABSENT` and is decided by a ray, exactly: a sample costs a few more
/// border rays, and a sparser one more of them (the commit that chose 2 has the figures).
const MARK_STEP: usize = 2;

/// Level caps of paged maps marked in one pass over the camera hits, for lights whose pages do
/// not fit the budget at their own levels ([`Renderer::needs`]).
const COARSER: usize = 3;

/// Per-light classification counts of one frame (camera hits only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LightStats {
    /// Hits the light faces that the map decided lit / shadowed without a ray.
    pub lit: u64,
    pub shadowed: u64,
    /// Hits decided by a shadow ray (border pixels).
    pub undecided: u64,
    /// Of `lit` and `shadowed`, the hits decided with the rest of their 8x8 tile at once, from
    /// the map region under the tile's corners (`Classifier::hull`), not point by point.
    pub by_tile: u64,
    /// Of `lit` and `shadowed`, the hits whose footprint was a border only because of
    /// occluders within the bias band, decided by testing those triangles alone with the
    /// hit's shadow ray (`Ambiguous::Triangles`; `Lookup::suspects`), not by a whole ray.
    pub by_suspects: u64,
    /// Map faces drawn for this light (cube: of 6, paraboloid: of 2).
    pub faces_drawn: u32,
    /// Paged maps: the pages this frame's camera hits read, those of them drawn for this
    /// frame (the others were reused), and the pages the map holds.
    pub pages_used: u32,
    pub pages_drawn: u32,
    pub pages_held: u32,
    /// Paged maps: the finest level in use, and the finest the memory budget allowed
    /// ([`hyrt_shadowmap::MAX_LEVEL`] when it did not bind).
    pub finest_level: u8,
    pub level_cap: u8,
    /// Memory of the light's map (ids and distances), in bytes.
    pub map_bytes: u64,
    /// With `Options::check_visibility`: map decisions that a plain shadow ray contradicts.
    pub wrong: Option<u64>,
    /// With `Options::check_visibility`: decisions of border rays answered by their occluder
    /// hint (no traversal) that a plain shadow ray (a traversal without hint) contradicts.
    pub wrong_hint: Option<u64>,
    /// With `Options::check_visibility`: decisions of border rays answered by a traversal that
    /// a plain shadow ray contradicts (the same ray: none, unless the hint path is broken).
    pub wrong_traversal: Option<u64>,
}

impl LightStats {
    /// With `Options::check_visibility`: every decision a plain shadow ray contradicts (by the
    /// map, a hint or a traversal).
    pub fn wrong_total(&self) -> Option<u64> {
        Some(self.wrong? + self.wrong_hint? + self.wrong_traversal?)
    }
}

/// One bit per light for every pixel: bit `l % 8` of byte `l / 8` of the pixel's `stride`
/// bytes, pixel-major, so that one pass over the pixels serves every light, and the screen
/// passes over them (borders, dilation) treat eight lights per byte operation.
#[derive(Clone, Debug, Default)]
pub(crate) struct LightBits {
    pub(crate) stride: usize,
    pub(crate) bits: Vec<u8>,
}

impl LightBits {
    /// Resizes to `n` pixels of `lights` bits, all clear.
    fn reset(&mut self, n: usize, lights: usize) {
        self.stride = lights.div_ceil(8).max(1);
        self.bits.clear();
        self.bits.resize(n * self.stride, 0);
    }

    #[inline]
    pub(crate) fn get(&self, i: usize, l: usize) -> bool {
        bit(self.pixel(i), l)
    }

    /// Pixel `i`'s bytes.
    #[inline]
    fn pixel(&self, i: usize) -> &[u8] {
        &self.bits[i * self.stride..][..self.stride]
    }

    /// Whether any bit of pixel `i` is set.
    #[inline]
    fn any(&self, i: usize) -> bool {
        self.pixel(i).iter().any(|&b| b != 0)
    }
}

/// The bit of light `l` in a pixel's bytes.
#[inline]
fn bit(bytes: &[u8], l: usize) -> bool {
    bytes[l / 8] >> (l % 8) & 1 != 0
}

/// The per-pixel buffers of a frame's map-based shadows. The public per-light vectors are
/// filled only with `Options::keep_buffers` (for inspection), from the compact per-pixel bits
/// the passes work on; they are then kept in the [`super::Frame`].
#[derive(Clone, Debug, Default)]
pub struct ShadowBuffers {
    /// The decision: lit, shadowed, or [`Decision::NotNeeded`] (no hit, the light
    /// behind the surface, or no diffuse reflectance). The map's, except on undecided pixels,
    /// where the shadow ray's answer replaces it.
    pub occ: Vec<Vec<Decision>>,
    /// Pixels decided by a shadow ray (borders after dilation; empty under `Shadows::Maps`).
    pub undecided: Vec<Vec<bool>>,
    /// The occluder hint of each pixel (a triangle id, or `EMPTY`).
    pub hint: Vec<Vec<u32>>,
    /// The map-space border test's verdict.
    pub map_border: Vec<Vec<bool>>,
    /// With `check_visibility`: the decisions a plain shadow ray contradicts, whoever made
    /// them: the map, or a border ray answered by its hint or by a traversal (else empty).
    pub wrong: Vec<Vec<bool>>,
    /// The border before dilation (pixels with a decision only; with the pixels whose camera
    /// hit came after the map passes, all of whose lights rays decide), and what each undecided
    /// pixel's shadow ray did: [`RAY_NONE`], [`RAY_HINT`] (its occluder hint blocked it: no
    /// traversal) or [`RAY_TRAVERSAL`].
    pub border: Vec<Vec<bool>>,
    pub ray: Vec<Vec<u8>>,
    /// Lights that face each pixel's shading point ([`facing`]): those with a decision.
    pub(crate) faces: LightBits,
    /// The decision, lit or not: the map's, then the border rays'.
    pub(crate) lit: LightBits,
    /// The map-space border test's verdict.
    edge: LightBits,
    /// The (pixel, light) pairs that a shadow ray decides.
    und: LightBits,
    /// Of those, the rays that their occluder hint answered (with `keep_buffers` or a check).
    by_hint: LightBits,
    /// With a check: the decisions a plain shadow ray contradicts.
    wrong_bits: LightBits,
}

/// [`ShadowBuffers::ray`]: no shadow ray for this pixel and light.
pub const RAY_NONE: u8 = 0;
/// [`ShadowBuffers::ray`]: a shadow ray answered by the map's occluder hint.
pub const RAY_HINT: u8 = 1;
/// [`ShadowBuffers::ray`]: a shadow ray that traversed the BVH.
pub const RAY_TRAVERSAL: u8 = 2;

/// One frame's map-based shadows: the maps used and the per-pixel buffers.
pub struct Shadowing<'r> {
    pub maps: Vec<Arc<LightMap>>,
    pub bufs: ShadowBuffers,
    pub lights: Vec<LightStats>,
    planes: &'r [Plane],
    /// Paged maps: per light, how a point picks its level (empty for whole maps).
    resolution: Vec<Resolution>,
    /// Per light, the map's lit and shadowed decisions (before the border rays), and how many
    /// of them were made per tile, and by their ambiguous triangles ([`settle`]).
    map_counts: Vec<[u64; 4]>,
    /// Per light, the pairs of [`Shadowing::add_ray_pixels`] (rays alone decide them).
    added: Vec<u64>,
    /// Per light, the pixels of the map-space borders (in pixel order) and their occluder
    /// hints ([`Lookup::hint`]), as the classify pass found them: a border ray tests that
    /// triangle first without looking the point up again.
    hints: Vec<Vec<BorderHint>>,
}

/// A map-space border pair's pixel and the occluder hint its map lookup found.
#[derive(Clone, Copy, Debug)]
struct BorderHint {
    pixel: u32,
    hint: u32,
}

/// What one band of rows of the classify pass found: per light, its map decisions (lit,
/// shadowed, and how many of those per tile and by their ambiguous triangles) and its
/// map-space borders, in pixel order.
struct BandOut {
    counts: Vec<[u64; 4]>,
    hints: Vec<Vec<BorderHint>>,
}

impl Shadowing<'_> {
    /// Adds `pixels` (whose camera hits came after the map passes: `visibility::run`'s
    /// deferred primary rays) with every light that faces their hit decided by a shadow ray,
    /// and their diffuse shading points to `points`.
    pub(crate) fn add_ray_pixels(
        &mut self,
        r: &Renderer,
        gbuffer: &[Option<Hit>],
        pixels: &[u32],
        mut points: Option<&mut [ShadePoint]>,
    ) {
        let b = &mut self.bufs;
        let stride = b.faces.stride;
        for &i in pixels {
            let i = i as usize;
            let Some(s) = r.shading_point(gbuffer, i) else { continue };
            if let Some(pts) = points.as_deref_mut()
                && r.diffuse(s.tri)
            {
                pts[i] = ShadePoint::of(&s);
            }
            let tri = &r.scene.positions[s.tri as usize];
            for (l, light) in r.lights.iter().enumerate() {
                if facing(&s, light, tri).is_some() {
                    let (byte, m) = (i * stride + l / 8, 1u8 << (l % 8));
                    b.faces.bits[byte] |= m;
                    b.und.bits[byte] |= m;
                    self.added[l] += 1;
                    if let Some(border) = b.border.get_mut(l) {
                        border[i] = true;
                    }
                }
            }
        }
    }
}

/// Side of the square pixel tiles of the classify pass: its shading points stay in L1 while
/// every light decides them, and neighbouring pixels look up neighbouring texels.
const TILE: usize = 8;
/// Half a [`TILE`]: the side of the quarters whose points the tile test decides at once when the
/// whole tile's cannot.
const H: usize = TILE / 2;
// A tile's points are bits of a `u64` in the classify pass.
const _: () = assert!(TILE * TILE <= 64);

/// Rays per parallel chunk of the shadow-ray pass: fixed, so that ray counts add up in the same
/// order for any thread count.
const RAY_CHUNK: usize = 64;

impl Renderer<'_> {
    /// Whether direct light is computed at `s` at all: not on surfaces that point lights do
    /// not light (perfect mirrors: no diffuse term, no highlight), where the reference casts no
    /// shadow ray either.
    pub(crate) fn needs_light(&self, tri: u32) -> bool {
        self.scene.materials[self.scene.material[tri as usize] as usize].is_lit()
    }

    /// The shading point of the camera hit of pixel `i` of `gbuffer`, where direct light is
    /// computed at all.
    #[inline]
    fn shading_point(&self, gbuffer: &[Option<Hit>], i: usize) -> Option<SurfaceHit> {
        let w = self.scene.settings.width.max(1) as usize;
        let hit = gbuffer[i].as_ref().filter(|h| self.needs_light(h.tri))?;
        Some(SurfaceHit::new(self.scene, hit, self.camera_ray((i % w) as u32, (i / w) as u32).dir))
    }

    /// What marking needs of the camera hit of pixel `i` (where direct light is computed at
    /// all): its position, geometric normal (not flipped to the viewer) and the unit direction
    /// back to the camera, bit for bit the `p`, `+-ng` and `wo` of its [`SurfaceHit`] (made by
    /// the same [`SurfaceHit::point`]), without the shading normal's interpolation.
    #[inline]
    fn receiver_geometry(&self, gbuffer: &[Option<Hit>], i: usize) -> Option<(Vec3, Vec3, Vec3)> {
        let w = self.scene.settings.width.max(1) as usize;
        let hit = gbuffer[i].as_ref().filter(|h| self.needs_light(h.tri))?;
        let (p, _, ng) = SurfaceHit::point(&self.scene.positions[hit.tri as usize], hit);
        let wo = -self.camera_ray((i % w) as u32, (i / w) as u32).dir;
        Some((p, ng, wo))
    }

    /// Whether the light maps are paged: `LightMaps::Paged` with cube maps.
    pub(crate) fn paged_maps(&self) -> bool {
        let o = &self.options.shadow;
        o.light_maps == LightMaps::Paged && o.map.kind == MapKind::Cube
    }

    /// What the camera hits of `gbuffer` need of the maps: per light the faces they fall on,
    /// and for paged maps the pages; a light whose pages exceed the budget gives up the
    /// refinement for grazing light first, then has its finest levels capped, a level at a
    /// time, until they fit (the receivers that need the finest texels give them up first;
    /// the others keep theirs).
    fn needs(&self, gbuffer: &[Option<Hit>]) -> Needs {
        if !self.paged_maps() {
            return Needs { faces: self.needed_faces(gbuffer), ..Needs::default() };
        }
        let nl = self.lights.len();
        let budget_bytes = self.options.shadow.map_budget as usize * (1 << 20);
        let fits = |pages: usize| hyrt_shadowmap::paged_memory_bound(pages) <= budget_bytes;
        let guide = resolution_guide(&self.camera, &self.options.shadow);
        let unrefined = Resolution { min_cos_light: 1.0, ..guide };
        let mut resolution = vec![guide; nl];
        let mut pages = vec![Vec::new(); nl];
        // One pass over the hits marks every light with and without the refinement for grazing
        // light (a light over the budget with it mostly fits without); then, for the lights that
        // still do not fit, several caps at once, until one fits.
        let mut variants: Vec<Vec<Resolution>> = vec![vec![guide, unrefined]; nl];
        let mut todo: Vec<usize> = (0..nl).collect();
        while !todo.is_empty() {
            let marked = self.mark_pages(gbuffer, &todo, &variants);
            let mut next = Vec::new();
            for (&l, sets) in todo.iter().zip(marked) {
                // The first variant that fits; else the finest level of the last one tried
                // less one, next time round (unless at level 0 already).
                let tried = &variants[l];
                let fit = sets.iter().position(|p| fits(p.len()));
                let c = fit.unwrap_or(sets.len() - 1);
                resolution[l] = tried[c];
                let finest = sets[c].iter().map(|k| k.level).max().unwrap_or(0);
                if fit.is_none() && finest > 0 {
                    let cap = finest - 1;
                    variants[l] = (0..COARSER as u8)
                        .map(|j| Resolution { cap: cap.saturating_sub(j), ..tried[c] })
                        .collect();
                    variants[l].dedup();
                    next.push(l);
                } else {
                    pages[l] = sets.into_iter().nth(c).unwrap_or_default();
                }
            }
            todo = next;
        }
        let nf = LightMap::face_count(MapKind::Cube);
        let mut faces = vec![false; nl * nf];
        for (l, p) in pages.iter().enumerate() {
            p.iter().for_each(|k| faces[l * nf + usize::from(k.face)] = true);
        }
        Needs { faces, pages, resolution }
    }

    /// For each light `l` of `lights` and each level guide of `variants[l]`, the pages (sorted)
    /// under the camera hits that face it ([`pages_around`]) at the levels that guide gives
    /// them: one pass over the hits for several guides.
    fn mark_pages(
        &self,
        gbuffer: &[Option<Hit>],
        lights: &[usize],
        variants: &[Vec<Resolution>],
    ) -> Vec<Vec<Vec<PageKey>>> {
        let w = self.scene.settings.width.max(1) as usize;
        // A sample of the hits where rays decide what it misses; every hit for maps alone.
        let step = if self.options.shadows == Shadows::Smerts { MARK_STEP } else { 1 };
        // The receiver's factor is the same for every light and guide (one camera).
        let guide = lights.first().and_then(|&l| variants[l].first()).copied();
        // Bands of rows in parallel, each marking packed keys with neighbours' repeats skipped;
        // then per light and guide one sort of all the bands' keys.
        const ROWS: usize = 8;
        let bands: Vec<Vec<Vec<Vec<u64>>>> = (0..gbuffer.len().div_ceil(w * ROWS))
            .into_par_iter()
            .map(|b| {
                let mut marks: Vec<Vec<Vec<u64>>> =
                    lights.iter().map(|&l| vec![Vec::new(); variants[l].len()]).collect();
                let mut lasts: Vec<Vec<Option<PageRect>>> =
                    lights.iter().map(|&l| vec![None; variants[l].len()]).collect();
                for i in b * w * ROWS..((b + 1) * w * ROWS).min(gbuffer.len()) {
                    if !(i % w).is_multiple_of(step) || !(i / w).is_multiple_of(step) {
                        continue;
                    }
                    let Some((p, ng, wo)) = self.receiver_geometry(gbuffer, i) else { continue };
                    let view = ng.dot(wo);
                    let recv = guide.map_or(0.0, |g| g.receiver(p, view));
                    for (k, &l) in lights.iter().enumerate() {
                        let light = &self.lights[l];
                        // A superset of the lights classification decides (`facing` and the
                        // viewer's side of the plane): a light with some intensity not clearly
                        // behind the surface as the viewer sees it.
                        let v = light.position - p;
                        let side = ng.dot(v);
                        if light.intensity.max_element() <= 0.0
                            || (side * view < 0.0 && side.abs() > 1e-4 * v.length())
                            || light.spot.is_some_and(|s| outside_with_margin(&s, -v.normalize_or_zero()))
                        {
                            continue;
                        }
                        let terms = LightTerms::of(p, ng, light.position);
                        let mut c: Option<MapCoord> = None;
                        for ((g, out), last) in variants[l].iter().zip(&mut marks[k]).zip(&mut lasts[k]) {
                            let level = g.level_from(recv, terms);
                            let c = match c {
                                Some(c) if c.level == level => c,
                                _ => *c.insert(paged::locate(p - light.position, level)),
                            };
                            // Neighbouring pixels mostly mark the same pages: skip the repeats
                            // (the previous receiver's pages, and the last few marked).
                            let rect = PageRect::around(c);
                            if *last == Some(rect) {
                                continue;
                            }
                            *last = Some(rect);
                            rect.for_each(|key| {
                                let key = key.pack();
                                if !out.iter().rev().take(4).any(|&o| o == key) {
                                    out.push(key);
                                }
                            });
                        }
                    }
                }
                marks
            })
            .collect();
        (0..lights.len())
            .into_par_iter()
            .map(|k| {
                (0..variants[lights[k]].len())
                    .map(|j| {
                        let mut all: Vec<u64> = bands.iter().flat_map(|r| r[k][j].iter().copied()).collect();
                        all.sort_unstable();
                        all.dedup();
                        all.into_iter().map(PageKey::unpack).collect()
                    })
                    .collect()
            })
            .collect()
    }

    /// Per light and face (light-major), whether a camera hit the light faces falls on it.
    fn needed_faces(&self, gbuffer: &[Option<Hit>]) -> Vec<bool> {
        let kind = self.options.shadow.map.kind;
        let nf = LightMap::face_count(kind);
        let lights = &self.lights;
        let w = self.scene.settings.width.max(1) as usize;
        (0..gbuffer.len().div_ceil(w))
            .into_par_iter()
            .map(|y| {
                let mut need = vec![false; lights.len() * nf];
                for i in y * w..((y + 1) * w).min(gbuffer.len()) {
                    let Some(s) = self.shading_point(gbuffer, i) else { continue };
                    let tri = &self.scene.positions[s.tri as usize];
                    for (l, light) in lights.iter().enumerate() {
                        if facing(&s, light, tri).is_some() {
                            need[l * nf + LightMap::face_of(kind, s.p - light.position) as usize] = true;
                        }
                    }
                }
                need
            })
            .reduce(
                || vec![false; lights.len() * nf],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(a, b)| *a |= b);
                    a
                },
            )
    }

    /// The light maps covering every face that a camera hit of `gbuffer` falls on, built (or
    /// extended) if the cache lacks a face. Returns the maps, how many were (re)built, and per
    /// light what was done and why. A light that no camera hit is in front of gets an empty
    /// map (no face drawn, nothing allocated): it is neither built nor counted.
    fn light_maps(&self, gbuffer: &[Option<Hit>]) -> FrameMaps {
        let kind = self.options.shadow.map.kind;
        let nf = LightMap::face_count(kind);
        let lights = &self.lights;
        let needed = self.maps.needed.get_or_init(|| self.needs(gbuffer));
        let paged = self.paged_maps();
        let budget_bytes = self.options.shadow.map_budget as usize * (1 << 20);
        let fits = |pages: usize| hyrt_shadowmap::paged_memory_bound(pages) <= budget_bytes;
        // Paged maps: per light, the pages in use and those drawn for this frame.
        let mut page_counts = vec![[0u32; 2]; lights.len()];
        let mut cache = self.maps.maps.lock().unwrap_or_else(|e| e.into_inner());
        cache.resize(lights.len(), None);
        let mut moved = self.maps.moved.lock().unwrap_or_else(|e| e.into_inner());
        moved.resize(lights.len(), false);
        let mut built = 0;
        let mut decisions = Vec::with_capacity(lights.len());
        let mut jobs: Vec<PageJob> = Vec::new();
        for (l, light) in lights.iter().enumerate() {
            let want = &needed.faces[l * nf..(l + 1) * nf];
            let have = cache[l].as_ref().map(|m| m.faces_drawn().to_vec());
            let missing = have.as_ref().is_none_or(|h| want.iter().zip(h).any(|(w, h)| *w && !*h));
            let wanted = want.iter().filter(|&&w| w).count();
            let what = Subject::Light(l);
            if wanted == 0 {
                let why = if light.intensity.max_element() <= 0.0 {
                    "zero intensity"
                } else {
                    "no camera hit is in front of it"
                };
                decisions.push(FrameDecision::new(
                    what,
                    Run::Skip,
                    format!("{why}: no map, no classification, no shadow rays for camera hits"),
                ));
                moved[l] = false;
                if have.is_none() {
                    let empty = if paged {
                        LightMap::build_pages(
                            &self.scene.positions,
                            light.position,
                            &self.options.shadow.map,
                            &[],
                            &[],
                        )
                    } else {
                        LightMap::build(&self.scene.positions, light.position, &self.options.shadow.map, &[])
                    };
                    cache[l] = Some(Arc::new(empty));
                }
                continue;
            }
            if paged {
                let want = &needed.pages[l];
                let old = cache[l].as_ref().filter(|m| m.is_paged());
                let missing: Vec<PageKey> =
                    want.iter().copied().filter(|&k| old.is_none_or(|m| !m.has_page(k))).collect();
                let held = old.map_or(0, |m| m.page_count());
                let fresh = old.is_none();
                // Over the budget: first drop the pages this view does not read (they are drawn
                // again if a later view needs them).
                let evicted = if !fresh && !fits(held + missing.len()) {
                    let keep: std::collections::HashSet<PageKey> = want.iter().copied().collect();
                    if let Some(m) = cache[l].as_mut() {
                        Arc::make_mut(m).retain_pages(|k| keep.contains(&k));
                    }
                    held - (want.len() - missing.len())
                } else {
                    0
                };
                let levels =
                    (want.first().map_or(0, |k| k.level), want.iter().map(|k| k.level).max().unwrap_or(0));
                let coarsened = match needed.resolution[l].cap {
                    hyrt_shadowmap::MAX_LEVEL => String::new(),
                    c => format!(", capped at level {c} to fit {} MB", self.options.shadow.map_budget),
                };
                let in_use =
                    format!("{} pages in use, levels {}..={}{coarsened}", want.len(), levels.0, levels.1);
                if missing.is_empty() {
                    page_counts[l] = [want.len() as u32, 0];
                    let reason =
                        format!("map reused from an earlier frame, not rebuilt: no page drawn ({in_use})");
                    decisions.push(FrameDecision::new(what, Run::Run, reason).with_cache(Cache::Reused));
                    continue;
                }
                let was_moved = std::mem::take(&mut moved[l]);
                let draw = if fresh { want.clone() } else { missing };
                page_counts[l] = [want.len() as u32, draw.len() as u32];
                let why = if !fresh {
                    let evicted = match evicted {
                        0 => String::new(),
                        e => format!(", {e} unused page(s) dropped for the budget"),
                    };
                    (
                        Cache::Extended,
                        format!(
                            "map extended: {} new page(s) drawn for this view, {} reused{evicted}",
                            draw.len(),
                            want.len() - draw.len()
                        ),
                    )
                } else {
                    let why = if was_moved { "map rebuilt: the light moved" } else { "map built" };
                    (Cache::Built, format!("{why}: {} page(s) drawn", draw.len()))
                };
                // Drawn below, with the other lights' pages.
                jobs.push(PageJob { light: l, draw, why, in_use, decision: decisions.len() });
                decisions.push(FrameDecision::new(what, Run::Run, String::new()));
                continue;
            }
            // The light is in use either way; the reason says whether its map was rebuilt.
            let reason = if missing && have.as_ref().is_some_and(|h| h.iter().any(|&d| d)) {
                let new =
                    want.iter().zip(have.as_deref().unwrap_or(&[])).filter(|(w, h)| **w && !**h).count();
                format!(
                    "map extended: {new} new face(s) drawn for this view, the others reused ({wanted} of {nf} faces in use)"
                )
            } else if missing && std::mem::take(&mut moved[l]) {
                format!("map rebuilt: the light moved; {wanted} of {nf} faces (those camera hits fall on)")
            } else if missing {
                format!("map built: {wanted} of {nf} faces (those camera hits fall on)")
            } else {
                format!("map reused from an earlier frame, not rebuilt ({wanted} of {nf} faces)")
            };
            let t = Instant::now();
            if missing {
                // Only the faces not drawn yet (a moved camera's new ones), merged into the map.
                let faces: Vec<bool> = match &have {
                    Some(h) => want.iter().zip(h).map(|(w, h)| *w && !*h).collect(),
                    None => want.to_vec(),
                };
                let map = LightMap::build_grouped(
                    &self.scene.positions,
                    light.position,
                    &self.options.shadow.map,
                    &faces,
                    self.plane_groups().0,
                );
                match &mut cache[l] {
                    Some(old) => Arc::make_mut(old).merge(map),
                    slot => *slot = Some(Arc::new(map)),
                }
                built += 1;
                let done = if have.as_ref().is_some_and(|h| h.iter().any(|&d| d)) {
                    Cache::Extended
                } else {
                    Cache::Built
                };
                let reason = format!("{reason} in {:.1} ms", super::ms(t));
                decisions.push(FrameDecision::new(what, Run::Run, reason).with_cache(done));
            } else {
                decisions.push(FrameDecision::new(what, Run::Run, reason).with_cache(Cache::Reused));
            }
        }
        // The lights' pages drawn concurrently: each build has serial steps (binning's sort,
        // the page tables) that another light's drawing fills.
        let groups = if jobs.is_empty() { &[][..] } else { self.plane_groups().0 };
        // As many at a time as there are threads: each holds its bins until drawn, and more in
        // flight add to the peak memory, not to the speed.
        let drawn: Vec<(LightMap, f64)> = jobs
            .chunks(rayon::current_num_threads().max(1))
            .flat_map(|chunk| {
                chunk
                    .par_iter()
                    .map(|job| {
                        let t = Instant::now();
                        let light = lights[job.light].position;
                        // Cut-outs: each texel's centre decides whether it sees a hole.
                        let hole = |id: u32, dir: Vec3| sees_hole(self.scene, light, id, dir);
                        let holes = Holes { cutouts: self.cutouts(), solid: &[], hole: &hole };
                        let map = LightMap::build_pages_with_holes(
                            &self.scene.positions,
                            light,
                            &self.options.shadow.map,
                            &job.draw,
                            groups,
                            (!self.cutouts().is_empty() && self.options.shadow.cutouts == CutoutMaps::Texels)
                                .then_some(&holes),
                        );
                        (map, super::ms(t))
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        for (job, (map, ms)) in jobs.into_iter().zip(drawn) {
            match &mut cache[job.light] {
                Some(m) if job.why.0 == Cache::Extended => Arc::make_mut(m).merge(map),
                slot => *slot = Some(Arc::new(map)),
            }
            built += 1;
            let (done, why) = job.why;
            let reason = format!("{why} ({}) in {ms:.1} ms", job.in_use);
            let d = &mut decisions[job.decision];
            *d = FrameDecision::new(d.what, Run::Run, reason).with_cache(done);
        }
        FrameMaps {
            maps: cache.iter().map(|m| m.clone().expect("built above")).collect(),
            built,
            decisions,
            page_counts,
        }
    }

    /// The map-build, classify and borders passes for the camera hits (module docs); the
    /// classify pass also writes into `direct` the direct light of every camera hit, with the
    /// map's decisions (the border rays correct the pixels they decide).
    pub(crate) fn shadowing<'r>(
        &'r self,
        gbuffer: &[Option<Hit>],
        direct: &mut [Vec3],
        points: Option<&mut [ShadePoint]>,
        progress: super::Progress,
        stats: &mut FrameStats,
    ) -> Shadowing<'r> {
        let (w, h) = (self.scene.settings.width as usize, self.scene.settings.height as usize);
        let n = w * h;
        let lights = &self.lights;
        let nl = lights.len();
        let mut bufs = std::mem::take(&mut *self.maps.scratch.lock().unwrap_or_else(|e| e.into_inner()));

        let t = Instant::now();
        let FrameMaps { maps, built, decisions, page_counts } = self.light_maps(gbuffer);
        let resolution: Vec<Resolution> = if self.paged_maps() {
            self.maps.needed.get().map_or_else(Vec::new, |n| n.resolution.clone())
        } else {
            Vec::new()
        };
        // The level of a point for light `l` (its receiver factor `recv`): its page level for
        // paged maps, 0 otherwise.
        let receiver = |s: &SurfaceHit| resolution.first().map_or(0.0, |g| g.receiver(s.p, s.ng.dot(s.wo)));
        let level =
            |l: usize, recv: f32, t: LightTerms| resolution.get(l).map_or(0, |r| r.level_from(recv, t));
        stats.record(super::Pass::MapBuild, t);
        stats.maps_built = built;
        stats.decisions.extend(decisions);

        let t = Instant::now();
        let planes: &'r [Plane] = self.occluders().0;
        let cls = classifiers(&maps, planes, self);
        let (groups, shared) = self.plane_groups();
        bufs.faces.reset(n, nl);
        bufs.lit.reset(n, nl);
        bufs.edge.reset(n, nl);
        let stride = bufs.faces.stride;
        let band = (TILE * w).max(1);
        let bands = direct
            .par_chunks_mut(band)
            .zip(bufs.faces.bits.par_chunks_mut(band * stride))
            .zip(bufs.lit.bits.par_chunks_mut(band * stride))
            .zip(bufs.edge.bits.par_chunks_mut(band * stride));
        let band_fn = |b: usize, (((out, faces), lit), edge): Band, mut pts: Option<&mut [ShadePoint]>| {
            let first = b * band;
            let rows = out.len() / w.max(1);
            let mut counts = vec![[0u64; 4]; nl];
            // Per light, the band's map-space borders and their occluder hints.
            let mut hints: Vec<Vec<BorderHint>> = vec![Vec::new(); nl];
            // Per tile: the shading points and the lights they face, then per light every
            // point's location and decision, then the points' direct light from those
            // decisions. (Prefetching the located points' texels before deciding them measured
            // slower once pages were compact: the page-table walk it repeats costs more than
            // the misses it hides.)
            let mut tile: Vec<(usize, SurfaceHit)> = Vec::with_capacity(TILE * TILE);
            // Per point of the tile, its receiver factor and (per light in turn) its level.
            let mut recv: Vec<f32> = Vec::with_capacity(TILE * TILE);
            let mut levels: Vec<u8> = Vec::with_capacity(TILE * TILE);
            let mut located = Vec::with_capacity(TILE * TILE);
            // Per point of the tile and light, `light_geometry`.
            let mut geo: Vec<Option<(Vec3, f32, f32)>> = Vec::with_capacity(TILE * TILE * nl);
            // Per point of the tile and light, its level's `LightTerms`.
            let mut terms: Vec<LightTerms> = Vec::with_capacity(TILE * TILE * nl);
            let mut sides = PlaneSides::new();
            for x0 in (0..w).step_by(TILE) {
                tile.clear();
                recv.clear();
                geo.clear();
                terms.clear();
                let x1 = (x0 + TILE).min(w);
                for y in 0..rows {
                    for j in y * w + x0..y * w + x1 {
                        out[j] = Vec3::ZERO;
                        let Some(s) = self.shading_point(gbuffer, first + j) else { continue };
                        if let Some(pts) = pts.as_deref_mut()
                            && self.diffuse(s.tri)
                        {
                            pts[j] = ShadePoint::of(&s);
                        }
                        let tri = &self.scene.positions[s.tri as usize];
                        let sd = sides.of(s.tri, tri, lights);
                        let bits = &mut faces[j * stride..][..stride];
                        // `facing`, with the plane sides and the winding reused; the light's
                        // geometry kept for the shading below.
                        let seen = seen_winding(&s, tri);
                        for (l, light) in lights.iter().enumerate() {
                            let (g, t) = light_geometry_and_terms(&s, light);
                            terms.push(t);
                            if g.is_some() && on_viewer_side(seen, sd[l]) {
                                bits[l / 8] |= 1 << (l % 8);
                            }
                            geo.push(g);
                        }
                        recv.push(receiver(&s));
                        tile.push((j, s));
                    }
                }
                // A tile wholly on one plane (triangles of one group): its corner points may
                // decide a light at once (`Classifier::hull`).
                let group = |s: &SurfaceHit| groups[s.tri as usize];
                let one_plane =
                    tile.len() == rows * (x1 - x0) && tile.iter().all(|(_, s)| group(s) == group(&tile[0].1));
                let corners = one_plane.then(|| {
                    let k = tile.len() - 1;
                    [tile[0].1.p, tile[x1 - x0 - 1].1.p, tile[k + 1 - (x1 - x0)].1.p, tile[k].1.p]
                });
                // A full tile that the tile test cannot decide as a whole may have quarters it
                // can: each quarter's corners, for the quarters on one plane (a tile's row-major
                // points). A tile on one plane tries them too: what defeats the whole tile (an
                // occluder's edge, a neighbouring triangle) often lies under one quarter.
                let full = tile.len() == TILE * TILE;
                let quarter = |q: usize, i: usize| (q / 2 * H + i / H) * TILE + q % 2 * H + i % H;
                let quarters: [Option<[Vec3; 4]>; 4] = std::array::from_fn(|q| {
                    let on_one = |g| (0..H * H).all(|i| group(&tile[quarter(q, i)].1) == g);
                    (full && on_one(group(&tile[quarter(q, 0)].1)))
                        .then(|| [0, H - 1, H * H - H, H * H - 1].map(|i| tile[quarter(q, i)].1.p))
                });
                for (l, c) in cls.iter().enumerate() {
                    let (byte, bit) = (l / 8, 1u8 << (l % 8));
                    levels.clear();
                    levels.extend(recv.iter().enumerate().map(|(k, &f)| level(l, f, terms[k * nl + l])));
                    // The tile test reads one level: the finest its points need (each point then
                    // gets texels at least as fine as its own level's; where that level's pages
                    // do not cover the tile, the test cannot tell).
                    let hull_of = |k: &[Vec3; 4], first: usize, finest: u8| {
                        let own = tile[first].1.tri;
                        c.hull(k, own, shared[own as usize].then(|| group(&tile[first].1)), finest)
                    };
                    let decide_all = |hull: Hull,
                                      points: &mut dyn Iterator<Item = usize>,
                                      lit: &mut [u8],
                                      counts: &mut [u64; 4]| {
                        let lit_all = hull == Hull::Lit;
                        for k in points {
                            let j = tile[k].0;
                            if faces[j * stride + byte] & bit != 0 {
                                lit[j * stride + byte] |= if lit_all { bit } else { 0 };
                                counts[usize::from(!lit_all)] += 1;
                                counts[2] += 1;
                            }
                        }
                    };
                    let hull = corners
                        .as_ref()
                        .map_or(Hull::Unknown, |k| hull_of(k, 0, levels.iter().copied().max().unwrap_or(0)));
                    if hull != Hull::Unknown {
                        decide_all(hull, &mut (0..tile.len()), lit, &mut counts[l]);
                        continue;
                    }
                    // The points no quarter's test decided, a bit per point of the tile.
                    let mut undecided = u64::MAX;
                    for (q, k) in quarters.iter().enumerate() {
                        let Some(k) = k else { continue };
                        let finest = (0..H * H).map(|i| levels[quarter(q, i)]).max().unwrap_or(0);
                        let hull = hull_of(k, quarter(q, 0), finest);
                        if hull != Hull::Unknown {
                            decide_all(hull, &mut (0..H * H).map(|i| quarter(q, i)), lit, &mut counts[l]);
                            (0..H * H).for_each(|i| undecided &= !(1u64 << quarter(q, i)));
                        }
                    }
                    // Located first, then decided: two loops measured faster than one.
                    located.clear();
                    for (k, (j, s)) in tile.iter().enumerate() {
                        if faces[j * stride + byte] & bit != 0 && undecided >> k & 1 != 0 {
                            located.push((k, c.locate_at(s.p, levels[k])));
                        }
                    }
                    for &(k, m) in &located {
                        let (j, s) = &tile[k];
                        let lk = c.classify_at(s.p, s.tri, m);
                        let settled = settle(self, &lk, s, lights[l].position);
                        let is_lit = settled.unwrap_or(lk.decision == Decision::Lit);
                        if is_lit {
                            lit[j * stride + byte] |= bit;
                        }
                        counts[l][usize::from(!is_lit)] += 1;
                        counts[l][3] += u64::from(settled.is_some());
                        if lk.map_border && settled.is_none() {
                            edge[j * stride + byte] |= bit;
                            hints[l].push(BorderHint { pixel: (first + j) as u32, hint: lk.hint });
                        }
                    }
                }
                for (k, (j, s)) in tile.iter().enumerate() {
                    let lb = &lit[j * stride..][..stride];
                    let g = &geo[k * nl..][..nl];
                    out[*j] = super::direct::reflect(self, s, |l, _| if bit(lb, l) { g[l] } else { None });
                }
            }
            (0..rows).for_each(|_| progress());
            hints.iter_mut().for_each(|h| h.sort_unstable_by_key(|e| e.pixel));
            BandOut { counts, hints }
        };
        let bands: Vec<BandOut> = match points {
            Some(p) => bands
                .zip(p.par_chunks_mut(band))
                .enumerate()
                .map(|(b, (x, p))| band_fn(b, x, Some(p)))
                .collect(),
            None => bands.enumerate().map(|(b, x)| band_fn(b, x, None)).collect(),
        };
        // The bands' lists in band order: each light's in pixel order.
        let hints =
            (0..nl).map(|l| bands.iter().flat_map(|b| b.hints[l].iter().copied()).collect()).collect();
        let map_counts = sum_per_light(bands.into_iter().map(|b| b.counts).collect(), nl);
        stats.record(super::Pass::Classify, t);

        let t = Instant::now();
        self.borders(&mut bufs, w, h);
        stats.record(super::Pass::Borders, t);

        let needed = self.maps.needed.get();
        let lights = maps
            .iter()
            .zip(&page_counts)
            .enumerate()
            .map(|(l, (m, &[used, drawn]))| LightStats {
                faces_drawn: m.faces_drawn().iter().filter(|&&f| f).count() as u32,
                map_bytes: m.memory_bytes() as u64,
                pages_used: used,
                pages_drawn: drawn,
                pages_held: m.page_count() as u32,
                finest_level: needed
                    .and_then(|n| n.pages.get(l))
                    .and_then(|p| p.iter().map(|k| k.level).max())
                    .unwrap_or(0),
                level_cap: resolution.get(l).map_or(hyrt_shadowmap::MAX_LEVEL, |r| r.cap),
                ..LightStats::default()
            })
            .collect();
        let added = vec![0; nl];
        Shadowing { maps, bufs, lights, planes, map_counts, resolution, added, hints }
    }

    /// The borders pass: the (pixel, light) pairs that a shadow ray decides, `bufs.und`, from
    /// the map-space test (`bufs.edge`) and/or the screen-space Laplacian of the decisions,
    /// dilated; eight lights per byte operation. With `keep_buffers`, also the border before
    /// dilation.
    fn borders(&self, bufs: &mut ShadowBuffers, w: usize, h: usize) {
        let opts = &self.options.shadow;
        let n = w * h;
        let nl = self.lights.len();
        bufs.border.clear();
        if self.options.shadows != Shadows::Smerts {
            bufs.und.reset(n, nl);
            return;
        }
        let stride = bufs.faces.stride;
        let (faces, lit, edge) = (&bufs.faces.bits, &bufs.lit.bits, &bufs.edge.bits);
        bufs.und.stride = stride;
        let und = &mut bufs.und.bits;
        und.clear();
        und.resize(n * stride, 0);
        // The Laplacian on a binary map is non-zero exactly where a 4-neighbour with a decision
        // has the other one (`hyrt_shadowmap::border`); the map-space bits are already limited
        // to pixels with a decision.
        let laplacian = opts.borders != Borders::MapSpace;
        let map_space = opts.borders != Borders::Laplacian;
        und.par_chunks_mut((w * stride).max(1)).enumerate().for_each(|(y, row)| {
            for x in 0..w {
                let p = y * w + x;
                for b in 0..stride {
                    let k = p * stride + b;
                    let mut o = if map_space { edge[k] } else { 0 };
                    if laplacian && faces[k] != 0 {
                        let (f, li) = (faces[k], lit[k]);
                        let mut differ =
                            |q: usize| o |= f & faces[q * stride + b] & (li ^ lit[q * stride + b]);
                        if x > 0 {
                            differ(p - 1);
                        }
                        if x + 1 < w {
                            differ(p + 1);
                        }
                        if y > 0 {
                            differ(p - w);
                        }
                        if y + 1 < h {
                            differ(p + w);
                        }
                    }
                    row[x * stride + b] = o;
                }
            }
        });
        if self.options.keep_buffers {
            bufs.border = (0..nl).map(|l| (0..n).map(|i| bit(&und[i * stride..], l)).collect()).collect();
        }
        let r = opts.dilate as usize;
        if r > 0 {
            // A square max filter: a horizontal then a vertical pass of byte ORs, then only the
            // pixels with a decision.
            let mut rows = vec![0u8; n * stride];
            rows.par_chunks_mut((w * stride).max(1)).zip(und.par_chunks((w * stride).max(1))).for_each(
                |(out, row)| {
                    for x in 0..w {
                        for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                            for b in 0..stride {
                                out[x * stride + b] |= row[xx * stride + b];
                            }
                        }
                    }
                },
            );
            und.par_chunks_mut((w * stride).max(1)).enumerate().for_each(|(y, out)| {
                out.fill(0);
                for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                    for (o, &m) in out.iter_mut().zip(&rows[yy * w * stride..(yy + 1) * w * stride]) {
                        *o |= m;
                    }
                }
                for (o, &f) in out.iter_mut().zip(&faces[y * w * stride..(y + 1) * w * stride]) {
                    *o &= f;
                }
            });
        }
    }

    /// Drops light `l`'s map (the light moved), keeping the others; which faces the camera
    /// needs is found again, since light `l`'s depend on where it is.
    pub(crate) fn drop_light_map(&mut self, l: usize) {
        if let Some(m) = self.maps.maps.get_mut().unwrap_or_else(|e| e.into_inner()).get_mut(l) {
            *m = None;
        }
        let moved = self.maps.moved.get_mut().unwrap_or_else(|e| e.into_inner());
        moved.resize(moved.len().max(l + 1), false);
        moved[l] = true;
        self.maps.needed = std::sync::OnceLock::new();
    }

    /// Drops the cached light maps (made with other map options); with `needs_changed`, also
    /// which faces or pages camera hits need (they differ between map kinds and layouts, and
    /// with the detail and budget of paged maps).
    pub(crate) fn drop_light_maps(&mut self, needs_changed: bool) {
        self.maps.maps.get_mut().unwrap_or_else(|e| e.into_inner()).clear();
        if needs_changed {
            self.maps.needed = std::sync::OnceLock::new();
        }
    }

    /// Forgets which light-map faces camera hits fall on (the camera moved), keeping the maps.
    pub(crate) fn forget_needed_faces(&mut self) {
        self.maps.needed = std::sync::OnceLock::new();
    }

    /// Light `l`'s cached map (for inspection), once a frame has built it; faces no camera hit
    /// falls on are not drawn ([`LightMap::faces_drawn`]).
    pub fn light_map(&self, l: usize) -> Option<Arc<LightMap>> {
        self.maps.maps.lock().unwrap_or_else(|e| e.into_inner()).get(l).cloned().flatten()
    }

    /// Keeps a frame's buffers for the next frame.
    pub(crate) fn recycle(&self, bufs: ShadowBuffers) {
        *self.maps.scratch.lock().unwrap_or_else(|e| e.into_inner()) = bufs;
    }
}

/// `f(pixel, light)` for each of `lights` lights and `n` pixels, light-major.
fn per_light<T: Send>(lights: usize, n: usize, f: impl Fn(usize, usize) -> T + Sync) -> Vec<Vec<T>> {
    (0..lights).map(|l| (0..n).into_par_iter().map(|i| f(i, l)).collect()).collect()
}

/// Per-light counts of parts (bands, rows) summed in order, for `lights` lights.
fn sum_per_light<const K: usize>(parts: Vec<Vec<[u64; K]>>, lights: usize) -> Vec<[u64; K]> {
    let mut sum = vec![[0u64; K]; lights];
    for part in parts {
        for (a, b) in sum.iter_mut().zip(part) {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
        }
    }
    sum
}

/// Under SMeRTS with `Ambiguous::Triangles`, whether light `light` reaches `s` when its lookup
/// `lk` names suspects ([`Lookup::suspects`]): its shadow ray, made as the reference makes it,
/// tested against those triangles alone (with the tracer's watertight test, so that each
/// answers as it would in a traversal): lit unless one blocks it. `None` otherwise (the map's
/// decision stands, or a whole ray decides a border).
fn settle(r: &Renderer, lk: &Lookup, s: &SurfaceHit, light: Vec3) -> Option<bool> {
    if lk.suspects[0] == EMPTY
        || r.options.shadows != Shadows::Smerts
        || r.options.shadow.ambiguous != Ambiguous::Triangles
    {
        return None;
    }
    let ray = spawn_ray_to(s.p, s.p_err, s.ng, light);
    Some(!lk.suspects.iter().any(|&t| t != EMPTY && r.tracer.hits_triangle(t, &ray).is_some()))
}

/// Whether the ray from `origin` in direction `dir` meets triangle `id` (one with a cut-out) in
/// a hole: a map texel's centre, for maps that resolve holes texel by texel. Its barycentrics
/// by Möller and Trumbore's ratios, whose vectors depend on the triangle and the origin alone
/// (`u = d . (e2 x s) / d . (e2 x e1)`, `v = d . (s x e1) / d . (e2 x e1)`, `s = origin - a`):
/// three dot products a texel, where a watertight ray test costs several times that. Not the
/// tracer's bit for bit, which a texel's sample does not need (its footprint's borders go to
/// rays, which are exact).
pub(crate) fn sees_hole(scene: &crate::scene::Scene, origin: Vec3, id: u32, dir: Vec3) -> bool {
    let Some(&[a, b, c]) = scene.positions.get(id as usize) else { return false };
    let (e1, e2, s) = (b - a, c - a, origin - a);
    let den = e2.cross(e1).dot(dir);
    if den == 0.0 || !den.is_finite() {
        return false;
    }
    let (u, v) = (e2.cross(s).dot(dir) / den, s.cross(e1).dot(dir) / den);
    !scene.solid_at(id, [1.0 - u - v, u, v])
}

/// The classifier of `map`, with the renderer's bias.
fn classifier<'m>(map: &'m LightMap, planes: &'m [Plane], r: &'m Renderer) -> Classifier<'m> {
    Classifier {
        map,
        planes,
        bias: r.options.shadow.bias,
        point_error: r.occluders().1,
        cutouts: r.cutouts(),
    }
}

/// Light `l`'s decision at `s` by its classifier `cls`, at the level `resolution` gives the
/// point (paged maps; level 0 when `resolution` is empty).
fn lookup(cls: &Classifier, resolution: &[Resolution], l: usize, s: &SurfaceHit, r: &Renderer) -> Lookup {
    cls.classify_at(s.p, s.tri, locate(cls, resolution, l, s, r))
}

/// The occluder a border ray from `s` to light `l` tests first when classify kept no hint for
/// its pair (undecided by the Laplacian, the dilation or no map): [`Classifier::hint_at`], at
/// the point's level.
fn hint(cls: &Classifier, resolution: &[Resolution], l: usize, s: &SurfaceHit, r: &Renderer) -> u32 {
    cls.hint_at(s.tri, locate(cls, resolution, l, s, r))
}

/// Where `s` falls in light `l`'s map, at its level (paged maps; 0 otherwise).
fn locate(cls: &Classifier, resolution: &[Resolution], l: usize, s: &SurfaceHit, r: &Renderer) -> MapCoord {
    let level = resolution.get(l).map_or(0, |g| g.level(s.p, s.ng, s.ng.dot(s.wo), r.lights[l].position));
    cls.locate_at(s.p, level)
}

/// The classifier of each of `maps`.
fn classifiers<'m>(maps: &'m [Arc<LightMap>], planes: &'m [Plane], r: &'m Renderer) -> Vec<Classifier<'m>> {
    maps.iter().map(|map| classifier(map, planes, r)).collect()
}

impl Shadowing<'_> {
    /// The `shadow_rays` pass: one shadow ray (hint first) per undecided (pixel, light), whose
    /// answer replaces the map's; the direct light of the pixels with such rays is computed
    /// again into `direct`. With `check` (wrong-visibility count), also a plain shadow ray (no
    /// hint) per (pixel, light) with a decision, not counted as a frame ray, checking every
    /// decision: the map's, the hint's and the traversal's, counted apart. Completes
    /// [`Shadowing::lights`], and with `Options::keep_buffers` the per-light buffers.
    pub fn trace(
        &mut self,
        r: &Renderer,
        gbuffer: &[Option<Hit>],
        direct: &mut [Vec3],
        check: bool,
    ) -> RayCounts {
        let n = gbuffer.len();
        let nl = self.maps.len();
        let keep = r.options.keep_buffers;
        let cls = classifiers(&self.maps, self.planes, r);
        let b = &mut self.bufs;
        let stride = b.faces.stride;
        b.by_hint.reset(n, nl);
        // The pixels with rays, in order, and their shading points.
        let w = r.scene.settings.width.max(1) as usize;
        let pixels: Vec<u32> = (0..n.div_ceil(w))
            .into_par_iter()
            .flat_map_iter(|y| (y * w..((y + 1) * w).min(n)).filter(|&i| b.und.any(i)).map(|i| i as u32))
            .collect();
        let points: Vec<SurfaceHit> = pixels
            .par_iter()
            .map(|&i| r.shading_point(gbuffer, i as usize).expect("undecided pixels have a shading point"))
            .collect();
        // The rays, light by light, each light's in screen order: rays to one light from
        // nearby points traverse the same nodes one after the other (the pixel-major order
        // alternates lights, and a Morton order of the pixels measured slower than rows).
        let und = &b.und;
        let mut order: Vec<(u32, u32)> = Vec::new();
        for l in 0..nl {
            order.extend(
                (0..pixels.len() as u32)
                    .filter(|&k| und.get(pixels[k as usize] as usize, l))
                    .map(|k| (l as u32, k)),
            );
        }
        // Per chunk of rays: whether each is blocked, and whether its hint answered.
        let answers: Vec<(Vec<(bool, bool)>, RayCounts)> = order
            .par_chunks(RAY_CHUNK)
            .map(|chunk| {
                let mut c = RayCounts::default();
                let out = chunk
                    .iter()
                    .map(|&(l, k)| {
                        let (l, s) = (l as usize, &points[k as usize]);
                        let i = pixels[k as usize];
                        let hint = match self.hints[l].binary_search_by_key(&i, |e| e.pixel) {
                            Ok(at) => self.hints[l][at].hint,
                            // Undecided by the Laplacian, the dilation or no map: no lookup
                            // was kept; the map's texels give a cheaper hint.
                            Err(_) => hint(&cls[l], &self.resolution, l, s, r),
                        };
                        let ray = spawn_ray_to(s.p, s.p_err, s.ng, r.lights[l].position);
                        let (before, hits) = (c, c.shadow_hint_hits);
                        let blocked = r.tracer.occluded_with_hint(&ray, hint, &mut c);
                        r.pixel_rays.add(i as usize, &before, &c);
                        (blocked, c.shadow_hint_hits > hits)
                    })
                    .collect();
                (out, c)
            })
            .collect();
        let mut total = RayCounts::default();
        let mut und_counts = vec![[0u64; 2]; nl];
        for (chunk, (out, c)) in order.chunks(RAY_CHUNK).zip(answers) {
            for (&(l, k), (blocked, hinted)) in chunk.iter().zip(out) {
                let (l, i) = (l as usize, pixels[k as usize] as usize);
                let (byte, m) = (i * stride + l / 8, 1u8 << (l % 8));
                und_counts[l][0] += 1;
                und_counts[l][1] += u64::from(b.lit.bits[byte] & m != 0);
                if blocked {
                    b.lit.bits[byte] &= !m;
                } else {
                    b.lit.bits[byte] |= m;
                }
                if hinted {
                    b.by_hint.bits[byte] |= m;
                }
            }
            total += c;
        }
        // The direct light of the pixels with rays, again, with their final decisions.
        let lit = &b.lit;
        let colors: Vec<Vec3> = pixels
            .par_iter()
            .zip(&points)
            .map(|(&i, s)| {
                let bits = lit.pixel(i as usize);
                super::direct::reflect(
                    r,
                    s,
                    |l, light| if bit(bits, l) { light_geometry(s, light) } else { None },
                )
            })
            .collect();
        for (&i, c) in pixels.iter().zip(colors) {
            direct[i as usize] = c;
        }
        for (((st, m), u), a) in
            self.lights.iter_mut().zip(&self.map_counts).zip(&und_counts).zip(&self.added)
        {
            // Undecided pairs: the map's border pairs (lit or shadowed by it), and those no map
            // decided (`add_ray_pixels`).
            st.undecided = u[0];
            st.lit = m[0] - u[1];
            st.shadowed = m[1] - (u[0] - u[1] - a);
            st.by_tile = m[2];
            st.by_suspects = m[3];
        }
        if check {
            self.check(r, gbuffer);
        } else {
            self.bufs.wrong_bits.reset(0, nl);
        }
        if keep {
            self.expand(r, gbuffer, check);
        }
        total
    }

    /// Checks every decision with a plain shadow ray (not counted as a frame ray): fills
    /// `wrong_bits` and the `wrong*` counts of [`Shadowing::lights`].
    fn check(&mut self, r: &Renderer, gbuffer: &[Option<Hit>]) {
        let n = gbuffer.len();
        let nl = self.maps.len();
        let w = r.scene.settings.width.max(1) as usize;
        let b = &mut self.bufs;
        b.wrong_bits.reset(n, nl);
        let stride = b.faces.stride;
        let (faces, lit, und, by_hint) = (&b.faces, &b.lit, &b.und, &b.by_hint);
        // Per row: per light, wrong decisions by [map, hint, traversal].
        let rows: Vec<Vec<[u64; 3]>> = b
            .wrong_bits
            .bits
            .par_chunks_mut((w * stride).max(1))
            .enumerate()
            .map(|(y, wrong)| {
                let mut by = vec![[0u64; 3]; nl];
                for x in 0..wrong.len() / stride {
                    let i = y * w + x;
                    if !faces.any(i) {
                        continue;
                    }
                    let s = r.shading_point(gbuffer, i).expect("pixels with decisions have a shading point");
                    for (l, light) in r.lights.iter().enumerate() {
                        if !faces.get(i, l) {
                            continue;
                        }
                        let ray = spawn_ray_to(s.p, s.p_err, s.ng, light.position);
                        let truth = r.tracer.occluded(&ray, RayKind::Shadow, &mut RayCounts::default());
                        if truth == lit.get(i, l) {
                            wrong[x * stride + l / 8] |= 1 << (l % 8);
                            let k = if !und.get(i, l) {
                                0
                            } else if by_hint.get(i, l) {
                                1
                            } else {
                                2
                            };
                            by[l][k] += 1;
                        }
                    }
                }
                by
            })
            .collect();
        for (st, by) in self.lights.iter_mut().zip(sum_per_light(rows, nl)) {
            (st.wrong, st.wrong_hint, st.wrong_traversal) = (Some(by[0]), Some(by[1]), Some(by[2]));
        }
    }

    /// The per-light buffers of [`ShadowBuffers`] (for inspection), from the per-pixel bits;
    /// the hints are looked up again.
    fn expand(&mut self, r: &Renderer, gbuffer: &[Option<Hit>], check: bool) {
        let n = gbuffer.len();
        let nl = self.maps.len();
        let cls = classifiers(&self.maps, self.planes, r);
        let b = &self.bufs;
        let occ = per_light(nl, n, |i, l| match (b.faces.get(i, l), b.lit.get(i, l)) {
            (false, _) => Decision::NotNeeded,
            (true, true) => Decision::Lit,
            (true, false) => Decision::Shadow,
        });
        let flags = |bits: &LightBits| per_light(nl, n, |i, l| bits.get(i, l));
        let smerts = r.options.shadows == Shadows::Smerts;
        let undecided = if smerts { flags(&b.und) } else { vec![Vec::new(); nl] };
        let map_border = flags(&b.edge);
        let wrong = if check { flags(&b.wrong_bits) } else { Vec::new() };
        let ray = per_light(nl, n, |i, l| match (b.und.get(i, l), b.by_hint.get(i, l)) {
            (false, _) => RAY_NONE,
            (true, true) => RAY_HINT,
            (true, false) => RAY_TRAVERSAL,
        });
        let hint = per_light(nl, n, |i, l| {
            if !b.faces.get(i, l) {
                return EMPTY;
            }
            let s = r.shading_point(gbuffer, i).expect("pixels with decisions have a shading point");
            lookup(&cls[l], &self.resolution, l, &s, r).hint
        });
        let b = &mut self.bufs;
        (b.occ, b.undecided, b.map_border, b.wrong, b.ray, b.hint) =
            (occ, undecided, map_border, wrong, ray, hint);
    }

    /// Light `l`'s map decision at `s`, at the level the point needs (paged maps).
    fn decide(&self, r: &Renderer, l: usize, s: &SurfaceHit) -> Lookup {
        lookup(&classifier(&self.maps[l], self.planes, r), &self.resolution, l, s, r)
    }

    /// Visibility of light `l` from a mirror hit (no screen neighbours): the map's decision, or,
    /// when `Shadows::Smerts` and the map-space footprint disagrees or the face was not drawn,
    /// a shadow ray with the hint. `MirrorShadows::Rays`: always a ray.
    pub fn visible_at(&self, r: &Renderer, l: usize, s: &SurfaceHit, counts: &mut RayCounts) -> bool {
        let light = &r.lights[l];
        let ray = || spawn_ray_to(s.p, s.p_err, s.ng, light.position);
        if r.options.shadow.mirror == MirrorShadows::Rays {
            return !r.tracer.occluded(&ray(), RayKind::Shadow, counts);
        }
        let map = &self.maps[l];
        let kind = map.kind();
        let face = LightMap::face_of(kind, s.p - light.position) as usize;
        if !map.faces_drawn()[face] {
            return !r.tracer.occluded(&ray(), RayKind::Shadow, counts);
        }
        let lk = self.decide(r, l, s);
        if let Some(lit) = settle(r, &lk, s, light.position) {
            return lit;
        }
        if r.options.shadows == Shadows::Smerts && lk.map_border {
            return !r.tracer.occluded_with_hint(&ray(), lk.hint, counts);
        }
        lk.decision == Decision::Lit
    }
}
