//! Which faces or pages of the light maps a view's camera hits need, and at what level
//! (`hyrt_shadowmap::paged` derives the levels).

use glam::Vec3;
use hyrt_shadowmap::{
    LightMap, MapCoord, MapKind, PageKey,
    paged::{self, LightTerms, PageRect, Resolution},
};
use hyrt_tracer::Hit;
use rayon::prelude::*;

use super::payoff::{COSTS, LightLoad, Payoff, choose};
use crate::render::light::{facing, outside_with_margin};
use crate::render::{Renderer, Shadows, SurfaceHit};

/// What a view's camera hits need of the light maps.
#[derive(Debug, Default)]
pub(crate) struct Needs {
    /// Per light and face (light-major), whether a camera hit the light faces falls on it.
    pub(super) faces: Vec<bool>,
    /// Paged maps: per light, the pages the camera hits fall on (sorted), and the level guide
    /// they were marked with (empty for whole maps).
    pub(super) pages: Vec<Vec<PageKey>>,
    pub(super) resolution: Vec<Resolution>,
    /// Paged maps with a finite horizon: per light, what its map and its rays would cost
    /// (`payoff`), and whether rays decide it (no map, no pages marked).
    pub(super) payoff: Vec<Option<Payoff>>,
    pub(super) by_rays: Vec<bool>,
}

/// The level guide of paged maps for `camera` (`hyrt_shadowmap::paged`): a pixel subtends
/// `2 tan(fov_y / 2) / height` radians at the image centre. A frame's guide for light `l` is
/// this one capped at [`LightStats::level_cap`](super::LightStats::level_cap).
pub fn resolution_guide(
    camera: &crate::camera::CameraRays,
    shadow: &crate::render::ShadowOptions,
) -> Resolution {
    let pixel = 2.0 * camera.tan_y / camera.height.max(1) as f32;
    Resolution::new(camera.eye, pixel, shadow.map_detail)
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

/// The payoff estimate (`payoff`) marks one camera hit in `s x s`, `s` the least power of two
/// from 8 at which it marks at most `ESTIMATE_MARKS` (hit, light) pairs: a sixteenth of the
/// marking's work or less, for the counts of a decision whose error bars are wider (with many
/// lights, the estimate would otherwise cost a good part of what it decides).
fn estimate_step(hits: usize, lights: usize) -> usize {
    const ESTIMATE_MARKS: usize = 1 << 17;
    let mut s = 8;
    while s < 64 && hits / (s * s) * lights > ESTIMATE_MARKS {
        s *= 2;
    }
    s
}

/// One band of rows' marks: per light and guide its packed page keys, and per light the
/// receivers that face it.
type BandMarks = (Vec<Vec<Vec<u64>>>, Vec<u64>);

impl Renderer<'_> {
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

    /// What the camera hits of `gbuffer` need of the maps: per light the faces they fall on,
    /// and for paged maps the pages; a light whose pages exceed the budget gives up the
    /// refinement for grazing light first, then has its finest levels capped, a level at a
    /// time, until they fit (the receivers that need the finest texels give them up first;
    /// the others keep theirs).
    ///
    /// With a finite [`map_horizon`](crate::render::ShadowOptions::map_horizon) (and border
    /// rays), first the payoff of each light's map (`payoff`) from a sparse sample of the hits:
    /// a light whose map does not pay, and that has none already (`have_map`), gets no pages;
    /// rays decide it. `first_frame`: the BVH is still being built.
    pub(super) fn needs(&self, gbuffer: &[Option<Hit>], have_map: &[bool], first_frame: bool) -> Needs {
        if !self.paged_maps() {
            return Needs { faces: self.needed_faces(gbuffer), ..Needs::default() };
        }
        let nl = self.lights.len();
        let horizon = self.options.shadow.map_horizon;
        let budget_bytes = self.options.shadow.map_budget as usize * (1 << 20);
        let fits = |pages: usize| hyrt_shadowmap::paged_memory_bound(pages) <= budget_bytes;
        let guide = resolution_guide(&self.camera, &self.options.shadow);
        let unrefined = Resolution { min_cos_light: 1.0, ..guide };
        // With a horizon, first a sparse estimate: its pages (the fewer of the two guides',
        // which the marking below chooses between) are a lower bound of what a map needs, so
        // the lights that get no map even with them are decided here, unmarked. A light with
        // a map already builds nothing.
        let pay = horizon.is_finite() && self.options.shadows == Shadows::Smerts;
        let horizon = f64::from(horizon);
        let first = first_frame.then_some((self.scene.positions.len(), gbuffer.len()));
        let mut receivers = vec![0u64; nl];
        let mut by_rays = vec![false; nl];
        let mut payoff: Vec<Option<Payoff>> = vec![None; nl];
        if pay {
            let all: Vec<usize> = (0..nl).collect();
            let step = estimate_step(gbuffer.len(), nl);
            let (sets, counted) = self.mark_pages(gbuffer, &all, &vec![vec![guide, unrefined]; nl], step);
            let area = (step * step) as u64;
            receivers = counted.iter().map(|&r| r * area).collect();
            let least: Vec<LightLoad> = (0..nl)
                .map(|l| {
                    let pages = if have_map[l] { 0 } else { sets[l].iter().map(Vec::len).min().unwrap_or(0) };
                    LightLoad { pages: pages as u64, receivers: receivers[l] }
                })
                .collect();
            let p = choose(&least, horizon, first, &COSTS);
            // (A light the sample finds no receiver for is left to the marking: none may face it.)
            by_rays = p.iter().zip(&receivers).map(|(p, &r)| !p.map && r > 0).collect();
            // The decided lights' reason: the estimate's (a lower bound of the build).
            payoff = p
                .into_iter()
                .zip(&by_rays)
                .map(|(p, &r)| r.then_some(Payoff { at_least: true, ..p }))
                .collect();
        }
        let mut resolution = vec![guide; nl];
        let mut pages = vec![Vec::new(); nl];
        // One pass over the hits marks every light with and without the refinement for grazing
        // light (a light over the budget with it mostly fits without); then, for the lights that
        // still do not fit, several caps at once, until one fits.
        let mut variants: Vec<Vec<Resolution>> = vec![vec![guide, unrefined]; nl];
        let mut todo: Vec<usize> = (0..nl).filter(|&l| !by_rays[l]).collect();
        while !todo.is_empty() {
            let (marked, _) = self.mark_pages(gbuffer, &todo, &variants, MARK_STEP);
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
        // Then the same choice among the lights left, with their marked pages: those it gives
        // no map lose their pages.
        if pay {
            let left: Vec<usize> = (0..nl).filter(|&l| !by_rays[l]).collect();
            let loads: Vec<LightLoad> = left
                .iter()
                .map(|&l| {
                    let pages = if have_map[l] { 0 } else { pages[l].len() };
                    LightLoad { pages: pages as u64, receivers: receivers[l] }
                })
                .collect();
            let chosen = choose(&loads, horizon, first, &COSTS);
            let maps = chosen.iter().filter(|p| p.map).count();
            for (&l, p) in left.iter().zip(chosen) {
                if receivers[l] == 0 {
                    continue;
                }
                payoff[l] = Some(Payoff { lights: nl, ..p });
                if !p.map {
                    by_rays[l] = true;
                    pages[l].clear();
                }
            }
            payoff.iter_mut().flatten().for_each(|p| p.maps = maps);
        }
        let nf = LightMap::face_count(MapKind::Cube);
        let mut faces = vec![false; nl * nf];
        for (l, p) in pages.iter().enumerate() {
            p.iter().for_each(|k| faces[l * nf + usize::from(k.face)] = true);
        }
        Needs { faces, pages, resolution, payoff, by_rays }
    }

    /// For each light `l` of `lights` and each level guide of `variants[l]`, the pages (sorted)
    /// under the camera hits that face it ([`pages_around`]) at the levels that guide gives
    /// them: one pass over the hits for several guides. Only one hit in `step x step` is marked
    /// under border rays (rays decide what the sample misses; every hit for maps alone). Also,
    /// per light, how many of those hits face it.
    fn mark_pages(
        &self,
        gbuffer: &[Option<Hit>],
        lights: &[usize],
        variants: &[Vec<Resolution>],
        step: usize,
    ) -> (Vec<Vec<Vec<PageKey>>>, Vec<u64>) {
        let w = self.scene.settings.width.max(1) as usize;
        let step = if self.options.shadows == Shadows::Smerts { step } else { 1 };
        // The receiver's factor is the same for every light and guide (one camera).
        let guide = lights.first().and_then(|&l| variants[l].first()).copied();
        // Bands of rows in parallel, each marking packed keys with neighbours' repeats skipped;
        // then per light and guide one sort of all the bands' keys.
        const ROWS: usize = 8;
        let bands: Vec<BandMarks> = (0..gbuffer.len().div_ceil(w * ROWS))
            .into_par_iter()
            .map(|b| {
                let mut receivers = vec![0u64; lights.len()];
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
                        receivers[k] += 1;
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
                (marks, receivers)
            })
            .collect();
        let receivers = (0..lights.len()).map(|k| bands.iter().map(|b| b.1[k]).sum()).collect();
        let sets = (0..lights.len())
            .into_par_iter()
            .map(|k| {
                (0..variants[lights[k]].len())
                    .map(|j| {
                        let mut all: Vec<u64> =
                            bands.iter().flat_map(|r| r.0[k][j].iter().copied()).collect();
                        all.sort_unstable();
                        all.dedup();
                        all.into_iter().map(PageKey::unpack).collect()
                    })
                    .collect()
            })
            .collect();
        (sets, receivers)
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
}
