//! Point-light visibility from depth maps: SMeRTS (shadow maps + selective ray tracing).
//!
//! Per frame, for the camera hits of the G-buffer, as a sequence of passes over named buffers:
//!
//! ```text
//! map_build    light maps: only faces some camera hit falls on; cached until the scene changes
//! classify     per light: occlusion map  occ[l]: LIT | SHADOW | NONE (light behind the surface),
//!              hint[l]: occluder triangle, map_border[l]: the 2x2 texel footprint disagrees
//! borders      per light (Smerts): undecided[l] = dilate(laplacian(occ[l]) | map_border[l], R)
//! shadow_rays  per undecided (pixel, light): a shadow ray, hint first, its answer into occ[l]
//! direct       shading with occ (no rays)
//! ```
//!
//! With `Shadows::Maps` the map's decision is final (no borders, no rays): the pure shadow-map
//! baseline. Mirror hits have no screen neighbours: they use the map-space test alone
//! ([`Shadowing::visible_at`]).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use glam::Vec3;
use hyrt_shadowmap::{
    EMPTY, LightMap,
    border::{LIT, NONE, SHADOW, dilate, laplacian_border},
    classify::{Classifier, Plane},
};
use hyrt_tracer::{Hit, PlaneSide, RayCounts, RayKind, plane_side, spawn_ray_to};
use rayon::prelude::*;
use serde::Serialize;

use super::{Borders, FrameStats, MirrorShadows, Renderer, Shadows, SurfaceHit, ms};
use crate::{plan::FrameDecision, scene::PointLight};

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
    let winding = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    match side {
        PlaneSide::In => false,
        PlaneSide::Front => hit.ng.dot(winding) > 0.0,
        PlaneSide::Back => hit.ng.dot(winding) < 0.0,
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

/// The part of [`facing`] that does not ask the side of the plane: `Some((wi, cos, d2))` for
/// a light with some intensity, not at the point, in front of the shading normal. Passes that
/// already know that the light faces the point (a map decision was made for it) use this alone.
#[inline]
pub fn light_geometry(hit: &SurfaceHit, light: &PointLight) -> Option<(Vec3, f32, f32)> {
    // A dark light adds nothing: no ray, no map (the plan says so).
    if light.intensity.max_element() <= 0.0 {
        return None;
    }
    let to_light = light.position - hit.p;
    let d2 = to_light.length_squared();
    if d2 == 0.0 {
        return None;
    }
    let wi = to_light / d2.sqrt();
    let cos = hit.ns.dot(wi);
    (cos > 0.0).then_some((wi, cos, d2))
}

/// Per-renderer state of map-based shadows: the light maps and the per-pixel buffers, recycled
/// from frame to frame.
#[derive(Default)]
pub(crate) struct MapCache {
    maps: Mutex<Vec<Option<Arc<LightMap>>>>,
    /// Per light and face, whether a camera hit falls on it: a renderer's scene and camera are
    /// fixed, so this is computed on the first frame only.
    needed: std::sync::OnceLock<Vec<bool>>,
    /// Buffers of the last frame, reused (allocating ~10 bytes per pixel and light afresh cost
    /// a fifth of the frame in page faults).
    scratch: Mutex<ShadowBuffers>,
}

/// Per-light classification counts of one frame (camera hits only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LightStats {
    /// Hits the light faces that the map decided lit / shadowed without a ray.
    pub lit: u64,
    pub shadowed: u64,
    /// Hits decided by a shadow ray (border pixels).
    pub undecided: u64,
    /// Map faces drawn for this light (cube: of 6, paraboloid: of 2).
    pub faces_drawn: u32,
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

/// The per-pixel buffers of a frame's map-based shadows, one vector per light, row-major. Kept
/// in the [`super::Frame`] with `Options::keep_buffers` (for inspection).
#[derive(Clone, Debug, Default)]
pub struct ShadowBuffers {
    /// The decision: [`LIT`], [`SHADOW`] or [`NONE`] (no decision needed: no hit, the light
    /// behind the surface, or no diffuse reflectance). The map's, except on undecided pixels,
    /// where the shadow ray's answer replaces it.
    pub occ: Vec<Vec<u8>>,
    /// Pixels decided by a shadow ray (borders after dilation; empty under `Shadows::Maps`).
    pub undecided: Vec<Vec<bool>>,
    /// The occluder hint of each pixel (a triangle id, or `EMPTY`).
    pub hint: Vec<Vec<u32>>,
    /// The map-space border test's verdict.
    pub map_border: Vec<Vec<bool>>,
    /// With `check_visibility`: the decisions a plain shadow ray contradicts, whoever made
    /// them: the map, or a border ray answered by its hint or by a traversal (else empty).
    pub wrong: Vec<Vec<bool>>,
    /// With `Options::keep_buffers` (else empty): the border before dilation (pixels with a
    /// decision only), and what each undecided pixel's shadow ray did: [`RAY_NONE`],
    /// [`RAY_HINT`] (its occluder hint blocked it: no traversal) or [`RAY_TRAVERSAL`].
    pub border: Vec<Vec<bool>>,
    pub ray: Vec<Vec<u8>>,
    /// The shading points of the camera hits.
    pub(crate) surf: Vec<Option<SurfaceHit>>,
    /// Per pixel the shading point's position and triangle (`EMPTY` without one): the 16 bytes
    /// classification reads, once per light (the whole shading point is 72).
    points: Vec<(Vec3, u32)>,
    /// Per pixel, bit `l % 8` of byte `l / 8` of its `stride` bytes: whether light `l` faces
    /// the shading point (see [`facing`]). Pixel-major, so that one pass over the shading points
    /// serves every light.
    faces: Vec<u8>,
}

/// [`ShadowBuffers::ray`]: no shadow ray for this pixel and light.
pub const RAY_NONE: u8 = 0;
/// [`ShadowBuffers::ray`]: a shadow ray answered by the map's occluder hint.
pub const RAY_HINT: u8 = 1;
/// [`ShadowBuffers::ray`]: a shadow ray that traversed the BVH.
pub const RAY_TRAVERSAL: u8 = 2;

/// Resizes `v` to `n` buffers of `len` elements equal to `fill`, reusing their memory.
fn reset<T: Clone>(v: &mut Vec<Vec<T>>, n: usize, len: usize, fill: T) {
    v.resize_with(n, Vec::new);
    for b in v.iter_mut() {
        b.clear();
        b.resize(len, fill.clone());
    }
}

/// One frame's map-based shadows: the maps used and the per-pixel buffers.
pub struct Shadowing<'r> {
    pub maps: Vec<Arc<LightMap>>,
    pub bufs: ShadowBuffers,
    pub lights: Vec<LightStats>,
    planes: &'r [Plane],
}

impl Renderer<'_> {
    /// Whether direct light is computed at `s` at all: not on surfaces that point lights do
    /// not light (perfect mirrors: no diffuse term, no highlight), where the reference casts no
    /// shadow ray either.
    pub(crate) fn needs_light(&self, tri: u32) -> bool {
        self.scene.materials[self.scene.material[tri as usize] as usize].is_lit()
    }

    /// The light maps covering every face that a camera hit of `gbuffer` falls on, built (or
    /// extended) if the cache lacks a face. Returns the maps, how many were (re)built, and per
    /// light what was done and why. A light that no camera hit is in front of gets an empty
    /// map (no face drawn, nothing allocated): it is neither built nor counted.
    fn light_maps(
        &self,
        points: &[(Vec3, u32)],
        faces: &[u8],
    ) -> (Vec<Arc<LightMap>>, u32, Vec<FrameDecision>) {
        let kind = self.options.shadow.map.kind;
        let nf = LightMap::face_count(kind);
        let lights = &self.scene.lights;
        // Faces needed: per light, any hit the light faces whose direction falls on the face.
        let stride = lights.len().div_ceil(8).max(1);
        let needed = self.maps.needed.get_or_init(|| {
            lights
                .par_iter()
                .enumerate()
                .flat_map_iter(|(l, light)| {
                    let mut need = vec![false; nf];
                    let lit = faces.chunks(stride).map(|b| b[l / 8] >> (l % 8) & 1 != 0);
                    for (&(p, _), _) in points.iter().zip(lit).filter(|(_, f)| *f) {
                        need[LightMap::face_of(kind, p - light.position) as usize] = true;
                    }
                    need
                })
                .collect()
        });
        let mut cache = self.maps.maps.lock().unwrap_or_else(|e| e.into_inner());
        cache.resize(lights.len(), None);
        let mut built = 0;
        let mut decisions = Vec::with_capacity(lights.len());
        for (l, light) in lights.iter().enumerate() {
            let want = &needed[l * nf..(l + 1) * nf];
            let have = cache[l].as_ref().map(|m| m.faces_drawn().to_vec());
            let missing = have.as_ref().is_none_or(|h| want.iter().zip(h).any(|(w, h)| *w && !*h));
            let wanted = want.iter().filter(|&&w| w).count();
            let what = format!("light {l}");
            if wanted == 0 {
                let why = if light.intensity.max_element() <= 0.0 {
                    "zero intensity"
                } else {
                    "no camera hit is in front of it"
                };
                decisions.push(FrameDecision::new(
                    what,
                    false,
                    format!("{why}: no map, no classification, no shadow rays for camera hits"),
                ));
                if have.is_none() {
                    cache[l] = Some(Arc::new(LightMap::build(
                        &self.scene.positions,
                        light.position,
                        &self.options.shadow.map,
                        &[],
                    )));
                }
                continue;
            }
            // The light is in use either way; the reason says whether its map was rebuilt.
            decisions.push(FrameDecision::new(
                what,
                true,
                if missing {
                    format!("map built: {wanted} of {nf} faces (those camera hits fall on)")
                } else {
                    format!("map reused from an earlier frame, not rebuilt ({wanted} of {nf} faces)")
                },
            ));
            if missing {
                let faces: Vec<bool> = match &have {
                    Some(h) => want.iter().zip(h).map(|(w, h)| *w | *h).collect(),
                    None => want.to_vec(),
                };
                let map =
                    LightMap::build(&self.scene.positions, light.position, &self.options.shadow.map, &faces);
                cache[l] = Some(Arc::new(map));
                built += 1;
            }
        }
        (cache.iter().map(|m| m.clone().expect("built above")).collect(), built, decisions)
    }

    /// The map-build, classify and borders passes for the camera hits (module docs).
    pub(crate) fn shadowing<'r>(&'r self, gbuffer: &[Option<Hit>], stats: &mut FrameStats) -> Shadowing<'r> {
        let t = Instant::now();
        let (w, h) = (self.scene.settings.width as usize, self.scene.settings.height as usize);
        let n = w * h;
        let nl = self.scene.lights.len();
        let mut bufs = std::mem::take(&mut *self.maps.scratch.lock().unwrap_or_else(|e| e.into_inner()));
        // The shading points, once for all lights and passes; only where direct light is
        // computed at all (surfaces with a diffuse reflectance). One pass by rows writes the
        // shading point, its position and triangle, and the lights it faces: three passes
        // over the 72-byte shading points took twice as long. Every element is overwritten,
        // so recycled buffers are only resized.
        let lights = &self.scene.lights;
        let stride = nl.div_ceil(8).max(1);
        bufs.surf.resize(n, None);
        bufs.points.resize(n, (Vec3::ZERO, EMPTY));
        bufs.faces.resize(n * stride, 0);
        let rows = bufs.surf.par_chunks_mut(w.max(1)).zip(bufs.points.par_chunks_mut(w.max(1)));
        rows.zip(bufs.faces.par_chunks_mut(w.max(1) * stride)).enumerate().for_each(
            |(y, ((surf, points), faces))| {
                let hits = &gbuffer[y * w..][..surf.len()];
                let pixels = surf.iter_mut().zip(points.iter_mut()).zip(faces.chunks_mut(stride));
                let mut sides = PlaneSides::new();
                for (x, (((s, pt), bits), hit)) in pixels.zip(hits).enumerate() {
                    *s = hit
                        .as_ref()
                        .filter(|h| self.needs_light(h.tri))
                        .map(|h| SurfaceHit::new(self.scene, h, self.camera_ray(x as u32, y as u32).dir));
                    *pt = s.as_ref().map_or((Vec3::ZERO, EMPTY), |s| (s.p, s.tri));
                    bits.fill(0);
                    let Some(s) = s else { continue };
                    let tri = &self.scene.positions[s.tri as usize];
                    let sides = sides.of(s.tri, tri, lights);
                    for (l, light) in lights.iter().enumerate() {
                        // `facing`, with the plane side reused.
                        if light_geometry(s, light).is_some() && viewer_side(s, tri, sides[l]) {
                            bits[l / 8] |= 1 << (l % 8);
                        }
                    }
                }
            },
        );
        stats.time_ms.insert("surface", ms(t));

        let t = Instant::now();
        let (maps, built, decisions) = self.light_maps(&bufs.points, &bufs.faces);
        stats.time_ms.insert("map_build", ms(t));
        stats.maps_built = built;
        stats.decisions.extend(decisions);

        let t = Instant::now();
        let (planes, point_error): (&'r [Plane], f32) = self.occluders();
        let bias = self.options.shadow.bias;
        reset(&mut bufs.occ, nl, n, NONE);
        reset(&mut bufs.hint, nl, n, EMPTY);
        reset(&mut bufs.map_border, nl, n, false);
        // Bands of TILE rows, visited in TILE x TILE pixel tiles: neighbouring pixels look up
        // neighbouring texels, and a tile's texels stay in the cache (scan lines sweep long
        // strips across the map).
        const TILE: usize = 8;
        let band = (TILE * w).max(1);
        let stride = nl.div_ceil(8).max(1);
        for (l, (map, ((occ, hint), mb))) in
            maps.iter().zip(bufs.occ.iter_mut().zip(&mut bufs.hint).zip(&mut bufs.map_border)).enumerate()
        {
            let cls = Classifier { map, planes, bias, point_error };
            let (byte, bit) = (l / 8, 1u8 << (l % 8));
            occ.par_chunks_mut(band)
                .zip(hint.par_chunks_mut(band))
                .zip(mb.par_chunks_mut(band))
                .zip(bufs.points.par_chunks(band).zip(bufs.faces.par_chunks(band * stride)))
                .for_each(|(((o, hi), mb), (points, faces))| {
                    let rows = points.len() / w.max(1);
                    // Per tile, first locate every point and prefetch its texels, then decide:
                    // the tile's cache misses overlap.
                    let mut located = Vec::with_capacity(TILE * TILE);
                    for x0 in (0..w).step_by(TILE) {
                        located.clear();
                        for y in 0..rows {
                            let (first, last) = (y * w + x0, y * w + (x0 + TILE).min(w));
                            for i in (first..last).filter(|&i| faces[i * stride + byte] & bit != 0) {
                                let c = cls.locate(points[i].0);
                                cls.prefetch(c);
                                located.push((i, c));
                            }
                        }
                        for &(i, c) in &located {
                            let (p, tri) = points[i];
                            let lk = cls.classify_at(p, tri, c);
                            o[i] = lk.decision;
                            hi[i] = lk.hint;
                            mb[i] = lk.map_border;
                        }
                    }
                });
        }
        stats.time_ms.insert("classify", ms(t));

        let t = Instant::now();
        let opts = &self.options.shadow;
        let keep = self.options.keep_buffers;
        bufs.border.clear();
        if self.options.shadows == Shadows::Smerts {
            bufs.undecided.resize_with(nl, Vec::new);
            for ((u, o), mb) in bufs.undecided.iter_mut().zip(&bufs.occ).zip(&bufs.map_border) {
                let mut b = match opts.borders {
                    Borders::Depth => mb.clone(),
                    Borders::Laplacian => laplacian_border(o, w, h),
                    Borders::Both => {
                        let mut b = laplacian_border(o, w, h);
                        b.par_iter_mut().zip(mb).for_each(|(b, m)| *b |= *m);
                        b
                    }
                };
                if keep {
                    bufs.border.push(b.iter().zip(o).map(|(b, o)| *b && *o != NONE).collect());
                }
                if opts.dilate > 0 {
                    b = dilate(&b, w, h, opts.dilate as usize);
                }
                // Only pixels with a decision to make.
                b.par_iter_mut().zip(o).for_each(|(d, o)| *d &= *o != NONE);
                *u = b;
            }
        } else {
            bufs.undecided.clear();
            bufs.undecided.resize_with(nl, Vec::new);
        }
        stats.time_ms.insert("borders", ms(t));

        let lights = bufs
            .occ
            .par_iter()
            .zip(&bufs.undecided)
            .zip(&maps)
            .map(|((o, u), m)| {
                let mut s = LightStats {
                    faces_drawn: m.faces_drawn().iter().filter(|&&f| f).count() as u32,
                    map_bytes: m.memory_bytes() as u64,
                    ..LightStats::default()
                };
                for (i, &v) in o.iter().enumerate() {
                    if v == NONE {
                        continue;
                    }
                    if u.get(i).copied().unwrap_or(false) {
                        s.undecided += 1;
                    } else if v == LIT {
                        s.lit += 1;
                    } else {
                        s.shadowed += 1;
                    }
                }
                s
            })
            .collect();
        Shadowing { maps, bufs, lights, planes }
    }

    /// Drops the cached light maps (made with other map options); with `kind_changed`, also
    /// which faces camera hits fall on (faces differ between map kinds).
    pub(crate) fn drop_light_maps(&mut self, kind_changed: bool) {
        self.maps.maps.get_mut().unwrap_or_else(|e| e.into_inner()).clear();
        if kind_changed {
            self.maps.needed = std::sync::OnceLock::new();
        }
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

impl Shadowing<'_> {
    /// The `shadow_rays` pass: one shadow ray (hint first) per undecided (pixel, light), whose
    /// answer replaces the map's in `occ`. With `check` (wrong-visibility count), also a plain
    /// shadow ray (no hint) per (pixel, light), not counted as a frame ray, checking every
    /// decision: the map's, the hint's and the traversal's, counted apart.
    pub fn trace(&mut self, r: &Renderer, check: bool) -> RayCounts {
        let w = r.scene.settings.width.max(1) as usize;
        let n = self.bufs.surf.len();
        let nl = self.maps.len();
        let mut total = RayCounts::default();
        if check {
            reset(&mut self.bufs.wrong, nl, n, false);
        } else {
            self.bufs.wrong.clear();
        }
        let keep = r.options.keep_buffers;
        if keep {
            reset(&mut self.bufs.ray, nl, n, RAY_NONE);
        } else {
            self.bufs.ray.clear();
        }
        let b = &mut self.bufs;
        for l in 0..nl {
            let light = r.scene.lights[l].position;
            let (occ, hint, und, surf) = (&mut b.occ[l], &b.hint[l], &b.undecided[l], &b.surf);
            let mut no_check = Vec::new();
            let wrong = b.wrong.get_mut(l).unwrap_or(&mut no_check);
            let wrong_rows: Vec<&mut [bool]> = if check {
                wrong.chunks_mut(w).collect()
            } else {
                (0..n.div_ceil(w)).map(|_| &mut [][..]).collect()
            };
            if !check {
                // Only the undecided pixels, listed first (in order) and traced in fixed
                // chunks: counts add up in the same order for any thread count.
                let list: Vec<u32> = und
                    .par_iter()
                    .enumerate()
                    .filter(|&(i, &u)| u && occ[i] != NONE)
                    .map(|(i, _)| i as u32)
                    .collect();
                // Per ray: blocked, and answered by the hint.
                let answers: Vec<(Vec<(bool, bool)>, RayCounts)> = list
                    .par_chunks(256)
                    .map(|chunk| {
                        let mut c = RayCounts::default();
                        let blocked = chunk
                            .iter()
                            .map(|&i| {
                                let s = surf[i as usize].as_ref().expect("classified pixels have a hit");
                                let ray = spawn_ray_to(s.p, s.p_err, s.ng, light);
                                let before = c;
                                let blocked = r.tracer.occluded_with_hint(&ray, hint[i as usize], &mut c);
                                r.pixel_rays.add(i as usize, &before, &c);
                                (blocked, c.shadow_hint_hits > before.shadow_hint_hits)
                            })
                            .collect();
                        (blocked, c)
                    })
                    .collect();
                let mut rays = b.ray.get_mut(l);
                for (chunk, (blocked, c)) in list.chunks(256).zip(answers) {
                    for (&i, (b, by_hint)) in chunk.iter().zip(blocked) {
                        occ[i as usize] = if b { SHADOW } else { LIT };
                        if let Some(rays) = rays.as_mut() {
                            rays[i as usize] = if by_hint { RAY_HINT } else { RAY_TRAVERSAL };
                        }
                    }
                    total += c;
                }
                continue;
            }
            let ray_rows: Vec<&mut [u8]> = match b.ray.get_mut(l) {
                Some(v) => v.chunks_mut(w).collect(),
                None => (0..n.div_ceil(w)).map(|_| &mut [][..]).collect(),
            };
            // Per row: frame rays, and wrong decisions by [map, hint, traversal].
            let counts: Vec<(RayCounts, [u64; 3])> = occ
                .par_chunks_mut(w)
                .zip(wrong_rows)
                .zip(ray_rows)
                .enumerate()
                .map(|(y, ((row, wrong_row), ray_row))| {
                    let mut c = RayCounts::default();
                    let mut wrong_by = [0u64; 3];
                    for (x, o) in row.iter_mut().enumerate() {
                        let i = y * w + x;
                        let is_und = und.get(i).copied().unwrap_or(false);
                        if *o == NONE || !(is_und || check) {
                            continue;
                        }
                        let s = surf[i].as_ref().expect("classified pixels have a hit");
                        let ray = spawn_ray_to(s.p, s.p_err, s.ng, light);
                        // Who decides: 0 the map, 1 the hint, 2 a traversal.
                        let mut by = 0;
                        if is_und {
                            let before = c;
                            let blocked = r.tracer.occluded_with_hint(&ray, hint[i], &mut c);
                            r.pixel_rays.add(i, &before, &c);
                            by = if c.shadow_hint_hits > before.shadow_hint_hits { 1 } else { 2 };
                            if let Some(k) = ray_row.get_mut(x) {
                                *k = if by == 1 { RAY_HINT } else { RAY_TRAVERSAL };
                            }
                            *o = if blocked { SHADOW } else { LIT };
                        }
                        let truth = r.tracer.occluded(&ray, RayKind::Shadow, &mut RayCounts::default());
                        let wrong = truth != (*o == SHADOW);
                        wrong_row[x] = wrong;
                        wrong_by[by] += u64::from(wrong);
                    }
                    (c, wrong_by)
                })
                .collect();
            let mut wrong_by = [0u64; 3];
            for (c, by) in counts {
                total += c;
                for k in 0..3 {
                    wrong_by[k] += by[k];
                }
            }
            let st = &mut self.lights[l];
            (st.wrong, st.wrong_hint, st.wrong_traversal) =
                (Some(wrong_by[0]), Some(wrong_by[1]), Some(wrong_by[2]));
        }
        total
    }

    /// Visibility of light `l` from a mirror hit (no screen neighbours): the map's decision, or,
    /// when `Shadows::Smerts` and the map-space footprint disagrees or the face was not drawn,
    /// a shadow ray with the hint. `MirrorShadows::Rays`: always a ray.
    pub fn visible_at(&self, r: &Renderer, l: usize, s: &SurfaceHit, counts: &mut RayCounts) -> bool {
        let light = &r.scene.lights[l];
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
        let cls = Classifier {
            map,
            planes: self.planes,
            bias: r.options.shadow.bias,
            point_error: r.occluders().1,
        };
        let lk = cls.classify(s.p, s.tri);
        if r.options.shadows == Shadows::Smerts && lk.map_border {
            return !r.tracer.occluded_with_hint(&ray(), lk.hint, counts);
        }
        lk.decision == LIT
    }
}
