//! Point-light visibility from depth maps: SMeRTS (shadow maps + selective ray tracing).
//!
//! Per frame, for the camera hits of the G-buffer, as a sequence of passes over named buffers:
//!
//! ```text
//! map_build    light maps: only faces some camera hit falls on; cached until the scene changes
//! classify     per light: occlusion map  occ[l]: LIT | SHADOW | NONE (light behind the surface),
//!              hint[l]: occluder triangle, map_border[l]: the 2x2 texel footprint disagrees
//! borders      per light (Smerts): undecided[l] = dilate(laplacian(occ[l]) | map_border[l], R)
//! shadow_rays  visible[l] = occ[l], except per undecided (pixel, light): a shadow ray, hint
//!              first
//! direct       shading with visible (no rays)
//! ```
//!
//! With `Shadows::Maps` the map's decision is final (no borders, no rays): the pure shadow-map
//! baseline. Mirror hits have no screen neighbours: they use the map-space test alone
//! ([`Shadowing::visible_at`]).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use glam::{Vec3, Vec4};
use hyrt_shadowmap::{
    EMPTY, LightMap,
    border::{LIT, NONE, SHADOW, dilate, laplacian_border},
    classify::{Classifier, triangle_planes},
};
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray_to};
use rayon::prelude::*;
use serde::Serialize;

use super::{Borders, FrameStats, MirrorShadows, Renderer, Shadows, SurfaceHit, ms};
use crate::scene::PointLight;

/// Whether `light` can light `hit` at all (in front of both normals, not at the point): the
/// condition under which the reference casts a shadow ray. `Some((wi, cos, d2))` if so.
#[inline]
pub fn facing(hit: &SurfaceHit, light: &PointLight) -> Option<(Vec3, f32, f32)> {
    let to_light = light.position - hit.p;
    let d2 = to_light.length_squared();
    if d2 == 0.0 {
        return None;
    }
    let wi = to_light / d2.sqrt();
    let cos = hit.ns.dot(wi);
    if cos <= 0.0 || hit.ng.dot(wi) <= 0.0 {
        return None;
    }
    Some((wi, cos, d2))
}

/// Per-scene cache of the light maps (and the triangle planes their classification needs).
#[derive(Default)]
pub(crate) struct MapCache {
    maps: Mutex<Vec<Option<Arc<LightMap>>>>,
    planes: std::sync::OnceLock<Vec<Vec4>>,
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
    /// With `Options::check_visibility`: map decisions that a shadow ray contradicts.
    pub wrong: Option<u64>,
}

/// The per-light, per-pixel buffers of a frame's map-based shadows (see [`Shadowing`]), kept
/// in the [`super::Frame`] for inspection.
#[derive(Clone, Debug, Default)]
pub struct ShadowBuffers {
    pub occ: Vec<Vec<u8>>,
    pub undecided: Vec<Vec<bool>>,
    pub visible: Vec<Vec<u8>>,
    pub wrong: Vec<Vec<bool>>,
    pub hint: Vec<Vec<u32>>,
}

/// The per-light buffers of one frame.
pub struct Shadowing<'r> {
    pub maps: Vec<Arc<LightMap>>,
    /// `occ[l][pixel]`: the map's decision, [`LIT`], [`SHADOW`] or [`NONE`].
    pub occ: Vec<Vec<u8>>,
    /// `visible[l][pixel]`: the final decision, after [`Shadowing::trace`].
    pub visible: Vec<Vec<u8>>,
    /// With `check_visibility`: the map decisions a shadow ray contradicts (else empty).
    pub wrong: Vec<Vec<bool>>,
    pub hint: Vec<Vec<u32>>,
    /// Undecided pixels (borders, after dilation); empty vectors for `Shadows::Maps`.
    pub undecided: Vec<Vec<bool>>,
    pub lights: Vec<LightStats>,
    planes: &'r [Vec4],
    /// The camera hits' shading points.
    surf: Vec<Option<SurfaceHit>>,
}

impl Renderer<'_> {
    /// Whether direct light is computed at `s` at all: not on surfaces without a diffuse
    /// reflectance (perfect mirrors), where the reference casts no shadow ray either.
    fn needs_light(&self, s: &SurfaceHit) -> bool {
        self.scene.materials[self.scene.material[s.tri as usize] as usize].kd != Vec3::ZERO
    }

    fn planes(&self) -> &[Vec4] {
        self.maps.planes.get_or_init(|| triangle_planes(&self.scene.positions))
    }

    /// The light maps covering every face that a camera hit of `gbuffer` falls on, built (or
    /// extended) if the cache lacks a face. Returns the maps and how many were (re)built.
    fn light_maps(&self, surf: &[Option<SurfaceHit>]) -> (Vec<Arc<LightMap>>, u32) {
        let kind = self.options.shadow.map.kind;
        let nf = LightMap::face_count(kind);
        let lights = &self.scene.lights;
        // Faces needed: per light, any hit the light faces whose direction falls on the face.
        let w = self.scene.settings.width as usize;
        let needed = surf
            .par_chunks(w.max(1))
            .fold(
                || vec![false; lights.len() * nf],
                |mut acc, row| {
                    for s in row.iter().flatten().filter(|s| self.needs_light(s)) {
                        for (l, light) in lights.iter().enumerate() {
                            if facing(s, light).is_some() {
                                acc[l * nf + LightMap::face_of(kind, s.p - light.position) as usize] = true;
                            }
                        }
                    }
                    acc
                },
            )
            .reduce(
                || vec![false; lights.len() * nf],
                |a, b| a.iter().zip(&b).map(|(x, y)| *x | *y).collect(),
            );
        let mut cache = self.maps.maps.lock().unwrap_or_else(|e| e.into_inner());
        cache.resize(lights.len(), None);
        let mut built = 0;
        for (l, light) in lights.iter().enumerate() {
            let want = &needed[l * nf..(l + 1) * nf];
            let have = cache[l].as_ref().map(|m| m.faces_drawn().to_vec());
            let missing = have.as_ref().is_none_or(|h| want.iter().zip(h).any(|(w, h)| *w && !*h));
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
        (cache.iter().map(|m| m.clone().expect("built above")).collect(), built)
    }

    /// The map-build, classify and borders passes for the camera hits (module docs).
    pub(crate) fn shadowing<'r>(&'r self, gbuffer: &[Option<Hit>], stats: &mut FrameStats) -> Shadowing<'r> {
        let t = Instant::now();
        let w = self.scene.settings.width as usize;
        // The shading points, once for all lights and passes.
        let mut surf = Vec::with_capacity(gbuffer.len());
        gbuffer
            .par_iter()
            .enumerate()
            .map(|(i, hit)| {
                let (x, y) = ((i % w) as u32, (i / w) as u32);
                hit.as_ref().map(|h| SurfaceHit::new(self.scene, h, self.camera_ray(x, y).dir))
            })
            .collect_into_vec(&mut surf);
        stats.time_ms.insert("surface", ms(t));

        let t = Instant::now();
        let (maps, built) = self.light_maps(&surf);
        stats.time_ms.insert("map_build", ms(t));
        stats.maps_built = built;

        let t = Instant::now();
        let planes: &'r [Vec4] = self.planes();
        let h = self.scene.settings.height as usize;
        let bias = self.options.shadow.bias;
        let mut occ = Vec::with_capacity(maps.len());
        let mut hint = Vec::with_capacity(maps.len());
        let mut map_border = Vec::with_capacity(maps.len());
        for (light, map) in self.scene.lights.iter().zip(&maps) {
            let cls = Classifier { map, planes, bias };
            let mut o = vec![NONE; w * h];
            let mut hi = vec![EMPTY; w * h];
            let mut mb = vec![false; w * h];
            o.par_chunks_mut(w.max(1))
                .zip(hi.par_chunks_mut(w.max(1)))
                .zip(mb.par_chunks_mut(w.max(1)))
                .zip(surf.par_chunks(w.max(1)))
                .for_each(|(((o, hi), mb), surf)| {
                    for (x, s) in surf.iter().enumerate() {
                        let Some(s) = s else { continue };
                        if !self.needs_light(s) || facing(s, light).is_none() {
                            continue;
                        }
                        let lk = cls.classify(s.p, s.tri);
                        o[x] = lk.decision;
                        hi[x] = lk.hint;
                        mb[x] = lk.map_border;
                    }
                });
            occ.push(o);
            hint.push(hi);
            map_border.push(mb);
        }
        stats.time_ms.insert("classify", ms(t));

        let t = Instant::now();
        let opts = &self.options.shadow;
        let undecided: Vec<Vec<bool>> = if self.options.shadows == Shadows::Smerts {
            occ.iter()
                .zip(&map_border)
                .map(|(o, mb)| {
                    let mut b = match opts.borders {
                        Borders::Depth => vec![false; w * h],
                        Borders::Laplacian | Borders::Both => laplacian_border(o, w, h),
                    };
                    if opts.borders != Borders::Laplacian {
                        b.par_iter_mut().zip(mb).for_each(|(b, m)| *b |= *m);
                    }
                    let mut d = dilate(&b, w, h, opts.dilate as usize);
                    // Only pixels the light faces need a decision.
                    d.par_iter_mut().zip(o).for_each(|(d, o)| *d &= *o != NONE);
                    d
                })
                .collect()
        } else {
            vec![Vec::new(); maps.len()]
        };
        stats.time_ms.insert("borders", ms(t));

        let lights = occ
            .iter()
            .zip(&undecided)
            .zip(&maps)
            .map(|((o, u), m)| {
                let mut s = LightStats {
                    faces_drawn: m.faces_drawn().iter().filter(|&&f| f).count() as u32,
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
        let (visible, wrong) = (Vec::new(), Vec::new());
        Shadowing { maps, occ, visible, wrong, hint, undecided, lights, planes, surf }
    }
}

impl Shadowing<'_> {
    /// The `shadow_rays` pass: one shadow ray (hint first) per undecided (pixel, light), whose
    /// answer replaces the map's in `occ`. With `check` (wrong-visibility count), also a ray
    /// per decided (pixel, light), not counted as a frame ray, comparing the map's decision.
    pub fn trace(&mut self, r: &Renderer, check: bool) -> RayCounts {
        let w = r.scene.settings.width as usize;
        let mut total = RayCounts::default();
        self.visible = self.occ.clone();
        self.wrong = if check { vec![vec![false; self.surf.len()]; self.maps.len()] } else { Vec::new() };
        for (l, visible) in self.visible.iter_mut().enumerate() {
            let light = &r.scene.lights[l];
            let (hint, und, surf) = (&self.hint[l], &self.undecided[l], &self.surf);
            let mut wrong = self.wrong.get_mut(l).map(std::mem::take).unwrap_or_default();
            let mut rows: Vec<&mut [bool]> = wrong.chunks_mut(w.max(1)).collect();
            rows.resize_with(visible.len().div_ceil(w.max(1)), Default::default);
            let counts: Vec<RayCounts> = visible
                .par_chunks_mut(w.max(1))
                .zip(rows.into_par_iter())
                .enumerate()
                .map(|(y, (row, wrong_row))| {
                    let mut c = RayCounts::default();
                    for (x, o) in row.iter_mut().enumerate() {
                        let i = y * w + x;
                        if *o == NONE {
                            continue;
                        }
                        let is_und = und.get(i).copied().unwrap_or(false);
                        if !is_und && !check {
                            continue;
                        }
                        let s = surf[i].as_ref().expect("classified pixels have a hit");
                        let ray = spawn_ray_to(s.p, s.p_err, s.ng, light.position);
                        if is_und {
                            *o =
                                if r.tracer.occluded_with_hint(&ray, hint[i], &mut c) { SHADOW } else { LIT };
                        } else {
                            let truth = r.tracer.occluded(&ray, RayKind::Shadow, &mut RayCounts::default());
                            wrong_row[x] = truth != (*o == SHADOW);
                        }
                    }
                    c
                })
                .collect();
            total += counts.into_iter().sum();
            if check {
                self.lights[l].wrong = Some(wrong.iter().filter(|&&b| b).count() as u64);
                self.wrong[l] = wrong;
            }
        }
        total
    }

    /// The per-pixel buffers, for inspection after the frame.
    pub fn into_buffers(self) -> ShadowBuffers {
        ShadowBuffers {
            occ: self.occ,
            undecided: self.undecided,
            visible: self.visible,
            wrong: self.wrong,
            hint: self.hint,
        }
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
        let cls = Classifier { map, planes: self.planes, bias: r.options.shadow.bias };
        let lk = cls.classify(s.p, s.tri);
        if r.options.shadows == Shadows::Smerts && lk.map_border {
            return !r.tracer.occluded_with_hint(&ray(), lk.hint, counts);
        }
        lk.decision == LIT
    }
}
