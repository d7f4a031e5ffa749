//! Point-light visibility from depth maps: SMeRTS (shadow maps + selective ray tracing).
//!
//! Per frame, for the camera hits of the G-buffer, as a sequence of passes over named buffers;
//! the per-pixel buffers hold one bit per light (`LightBits`), not a screen per light:
//!
//! ```text
//! map_build    light maps: only the pages (or faces) camera hits fall on; cached across frames;
//!              with a finite horizon, only for the lights whose maps pay for themselves in it
//! classify     8x8 tile by tile: the shading points, then per light each point's location and
//!              map decision -> faces, lit, edge (the 2x2 texel footprint disagrees; its occluder
//!              hint kept); then the tile's direct light from those decisions (and the
//!              shading points of the pixels with an edge kept, for their border rays)
//! borders      (Smerts) und = dilate(edge and/or laplacian(lit, faces), R), byte ops over 8 lights
//! shadow_rays  by bands of two rows, the undecided (pixel, light) pairs light by light, in
//!              screen order: a shadow ray each (the hint classify kept first), the answers
//!              into lit, and the direct light of the pixels they overturned again; then, for the
//!              lights without a map, a shadow ray per pixel facing them, streamed by rows,
//!              each testing the light's last blocker in the row first (on a first frame, the
//!              rows are prepared while the BVH is still building)
//! ```
//!
//! Fusing the shading points, the decisions and the shading into one pass keeps a tile's points
//! in L1 while every light decides them; the alternative, a screen-sized buffer per light and a
//! pass per buffer, spent its time writing and reading those buffers. The occluder hint is kept
//! for the map-space border pairs alone, as a list per light in pixel order: the only pairs that
//! need it, and looking the point up in the map again cost each border ray more than walking
//! the list beside the rays.
//!
//! With `Shadows::Maps` the map's decision is final (no borders, no rays): the pure shadow-map
//! baseline. Mirror hits have no screen neighbours: they use the map-space test alone
//! ([`Shadowing::visible_at`]).
//!
//! One concept per file: `marking` (which pages or faces a view needs, at what level),
//! `payoff` (which lights get a map at all), `map_cache` (the maps kept between frames),
//! `classify`, `borders`, `border_rays`, `light_rays` (the passes), `mirror_hits` (decisions at
//! mirror hits), `lookup` (a point's decision in one map), `same_rays` (what border rays cost
//! against the reference's, traced alike); this file holds the per-pixel
//! buffers and counts the passes share.

mod border_rays;
mod borders;
mod classify;
mod lanes;
mod light_rays;
mod lookup;
mod map_cache;
mod marking;
mod mirror_hits;
mod payoff;
mod same_rays;

use std::sync::Arc;

use hyrt_shadowmap::{
    LightMap,
    classify::{Decision, Plane},
    paged::Resolution,
};
use hyrt_tracer::Hit;
use rayon::prelude::*;
use serde::Serialize;

use super::gather::ShadePoint;
use super::light::facing;
use super::{Renderer, SurfaceHit};

pub(crate) use lookup::sees_hole;
pub(crate) use map_cache::MapCache;
pub use marking::resolution_guide;
pub use same_rays::SameRays;

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
    /// Of `lit` and `shadowed`, the hits whose footprint was a border only because of a few
    /// triangles, decided by testing those alone with the hit's shadow ray, not by a whole
    /// ray (`lookup::settle`): occluders within the bias band (`Ambiguous::Triangles`;
    /// `Lookup::suspects`), or triangles sharing a vertex with the hit's own
    /// (`Neighbours::Triangles`; `Lookup::occluders`).
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
    /// pixel's shadow ray did: a [`BorderRay`].
    pub border: Vec<Vec<bool>>,
    pub ray: Vec<Vec<BorderRay>>,
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

/// What a (pixel, light) pair's shadow ray did ([`ShadowBuffers::ray`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BorderRay {
    /// No shadow ray: the map decided.
    #[default]
    None,
    /// A shadow ray answered by the map's occluder hint (no traversal).
    Hint,
    /// A shadow ray that traversed the BVH.
    Traversal,
}

/// One frame's map-based shadows: the maps used and the per-pixel buffers.
pub struct Shadowing<'r> {
    pub maps: Vec<Arc<LightMap>>,
    pub bufs: ShadowBuffers,
    pub lights: Vec<LightStats>,
    planes: &'r [Plane],
    /// Paged maps: per light, how a point picks its level (empty for whole maps).
    resolution: Vec<Resolution>,
    /// Per light, the map's decisions (before the border rays).
    map_counts: Vec<MapCounts>,
    /// Per light, the pairs of [`Shadowing::add_ray_pixels`] (rays alone decide them).
    added: Vec<u64>,
    /// Per light, the pairs the border rays decided.
    und_counts: Vec<RayCounted>,
    /// Per light, the pixels of the map-space borders (in pixel order) and their occluder
    /// hints ([`Lookup::hint`]), as the classify pass found them: a border ray tests that
    /// triangle first without looking the point up again.
    hints: Vec<Vec<BorderHint>>,
    /// The shading points of the pixels with a map-space border, in pixel order, as the classify
    /// pass made them: the border rays leave from them (the camera hits of those pixels are
    /// final before classify; pixels whose hit came after it have none).
    border_points: Vec<(u32, SurfaceHit)>,
    /// Per light, whether shadow rays decide it this frame (no map).
    pub(crate) by_rays: Vec<bool>,
    /// Per light, the pages drawn for mirror hits this frame ([`Shadowing::draw_mirror_pages`]).
    pub(crate) mirror_pages: Vec<u32>,
}

/// A map-space border pair's pixel and the occluder hint its map lookup found.
#[derive(Clone, Copy, Debug)]
struct BorderHint {
    pixel: u32,
    hint: u32,
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
fn sum_per_light<T: Copy + Default + std::ops::AddAssign>(parts: Vec<Vec<T>>, lights: usize) -> Vec<T> {
    let mut sum = vec![T::default(); lights];
    for part in parts {
        for (a, b) in sum.iter_mut().zip(part) {
            *a += b;
        }
    }
    sum
}

/// One light's map decisions in a frame, before the border rays.
#[derive(Clone, Copy, Debug, Default)]
struct MapCounts {
    lit: u64,
    shadowed: u64,
    /// Of those, the decisions made for a whole tile at once (`Classifier::hull`).
    by_tile: u64,
    /// Of those, the decisions settled by their ambiguous triangles (`lookup::settle`).
    by_suspects: u64,
}

impl MapCounts {
    /// Counts one decision, lit or not.
    #[inline]
    fn decided(&mut self, lit: bool) {
        if lit {
            self.lit += 1;
        } else {
            self.shadowed += 1;
        }
    }
}

impl std::ops::AddAssign for MapCounts {
    fn add_assign(&mut self, o: Self) {
        self.lit += o.lit;
        self.shadowed += o.shadowed;
        self.by_tile += o.by_tile;
        self.by_suspects += o.by_suspects;
    }
}

/// One light's pairs decided by border rays: how many, and of those how many the map had lit.
#[derive(Clone, Copy, Debug, Default)]
struct RayCounted {
    rays: u64,
    map_lit: u64,
}

impl std::ops::AddAssign for RayCounted {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.map_lit += o.map_lit;
    }
}

/// One light's decisions that a plain shadow ray contradicts, by who made them.
#[derive(Clone, Copy, Debug, Default)]
struct WrongCounts {
    map: u64,
    hint: u64,
    traversal: u64,
}

impl std::ops::AddAssign for WrongCounts {
    fn add_assign(&mut self, o: Self) {
        self.map += o.map;
        self.hint += o.hint;
        self.traversal += o.traversal;
    }
}
