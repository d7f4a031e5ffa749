//! The light maps kept from frame to frame: built, extended or reused for the pages (or faces)
//! a view needs, within the memory budget; dropped when their light or options change.

use std::sync::{Arc, Mutex};

use glam::Vec3;
use hyrt_shadowmap::{LightMap, MapKind, PageKey, map::Holes};
use hyrt_tracer::Hit;
use rayon::prelude::*;

use super::{ShadowBuffers, lookup::sees_hole, marking::Needs};
use crate::render::runner::timed;
use crate::render::{Cache, CutoutMaps, FrameDecision, LightMaps, Renderer, Run, Subject};

/// Per-renderer state of map-based shadows: the light maps and the per-pixel buffers, recycled
/// from frame to frame.
#[derive(Default)]
pub(crate) struct MapCache {
    pub(super) maps: Mutex<Vec<Option<Arc<LightMap>>>>,
    /// What the camera hits need of the maps: a renderer's scene and camera are fixed, so this
    /// is computed on the first frame only.
    pub(super) needed: std::sync::OnceLock<Needs>,
    /// Lights whose map was dropped because they moved ([`Renderer::set_light`]), until the
    /// next frame builds it again (its decision says why).
    pub(super) moved: Mutex<Vec<bool>>,
    /// Buffers of the last frame, reused (allocating them afresh costs page faults).
    pub(super) scratch: Mutex<ShadowBuffers>,
    /// Whether a frame has asked for maps: the first one's BVH is still being built
    /// (`payoff`).
    pub(super) framed: std::sync::atomic::AtomicBool,
    /// Whether a frame of this view has drawn the pages its mirror hits read (or found them
    /// not worth it): the same view's mirror hits are the same, so later frames need not look
    /// (`mirror_hits`). Forgotten with `needed`.
    pub(super) mirror_marked: std::sync::atomic::AtomicBool,
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
pub(crate) struct FrameMaps {
    /// Per light, its map.
    pub(super) maps: Vec<Arc<LightMap>>,
    /// Maps built or extended.
    pub(super) built: u32,
    /// Per light, what was done and why.
    pub(super) decisions: Vec<FrameDecision>,
    /// Paged maps: per light, the pages in use and those drawn for this frame.
    pub(super) page_counts: Vec<[u32; 2]>,
    /// Per light, whether shadow rays decide it this frame (no map).
    pub(super) by_rays: Vec<bool>,
}

impl Renderer<'_> {
    /// Whether the light maps are paged: `LightMaps::Paged` with cube maps.
    pub(crate) fn paged_maps(&self) -> bool {
        let o = &self.options.shadow;
        o.light_maps == LightMaps::Paged && o.map.kind == MapKind::Cube
    }

    /// The light maps covering every face that a camera hit of `gbuffer` falls on, built (or
    /// extended) if the cache lacks a face. Returns the maps, how many were (re)built, and per
    /// light what was done and why. A light that no camera hit is in front of gets an empty
    /// map (no face drawn, nothing allocated): it is neither built nor counted.
    pub(super) fn light_maps(&self, gbuffer: &[Option<Hit>]) -> FrameMaps {
        let kind = self.options.shadow.map.kind;
        let nf = LightMap::face_count(kind);
        let lights = &self.lights;
        let needed = self.maps.needed.get_or_init(|| {
            let cached = self.maps.maps.lock().unwrap_or_else(|e| e.into_inner());
            let have: Vec<bool> = (0..self.lights.len())
                .map(|l| cached.get(l).is_some_and(|m| m.as_ref().is_some_and(|m| m.page_count() > 0)))
                .collect();
            drop(cached);
            self.needs(gbuffer, &have, !self.maps.framed.load(std::sync::atomic::Ordering::Relaxed))
        });
        self.maps.framed.store(true, std::sync::atomic::Ordering::Relaxed);
        let paged = self.paged_maps();
        // Paged maps: per light, the pages in use and those drawn for this frame.
        let mut page_counts = vec![[0u32; 2]; lights.len()];
        let mut cache = self.maps.maps.lock().unwrap_or_else(|e| e.into_inner());
        cache.resize(lights.len(), None);
        let mut moved = self.maps.moved.lock().unwrap_or_else(|e| e.into_inner());
        moved.resize(lights.len(), false);
        let mut built = 0;
        let mut decisions = Vec::with_capacity(lights.len());
        let mut jobs: Vec<PageJob> = Vec::new();
        let mut by_rays = vec![false; lights.len()];
        for (l, light) in lights.iter().enumerate() {
            let what = Subject::Light(l);
            // A light whose map would not pay for itself over the horizon: rays decide it.
            if let (Some(true), Some(Some(p))) = (needed.by_rays.get(l), needed.payoff.get(l)) {
                by_rays[l] = true;
                if cache[l].is_none() {
                    cache[l] = Some(Arc::new(LightMap::build_pages(
                        &self.scene.positions,
                        light.position,
                        &self.options.shadow.map,
                        &[],
                        &[],
                    )));
                }
                let why = p.why(self.options.shadow.map_horizon);
                decisions.push(FrameDecision::new(what, Run::Run, format!("no map, shadow rays: {why}")));
                continue;
            }
            let want = &needed.faces[l * nf..(l + 1) * nf];
            let have = cache[l].as_ref().map(|m| m.faces_drawn().to_vec());
            let missing = have.as_ref().is_none_or(|h| want.iter().zip(h).any(|(w, h)| *w && !*h));
            let wanted = want.iter().filter(|&&w| w).count();
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
                let evicted = if !fresh && !self.fits_map_budget(held + missing.len()) {
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
                    let pays =
                        needed.payoff.get(l).copied().flatten().map_or(String::new(), |p| {
                            format!(" ({})", p.why(self.options.shadow.map_horizon))
                        });
                    (Cache::Built, format!("{why}: {} page(s) drawn{pays}", draw.len()))
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
            if missing {
                // Only the faces not drawn yet (a moved camera's new ones), merged into the map.
                let faces: Vec<bool> = match &have {
                    Some(h) => want.iter().zip(h).map(|(w, h)| *w && !*h).collect(),
                    None => want.to_vec(),
                };
                let ((), ms) = timed(|| {
                    let map = LightMap::build_grouped(
                        &self.scene.positions,
                        light.position,
                        &self.options.shadow.map,
                        &faces,
                        self.plane_groups(),
                    );
                    match &mut cache[l] {
                        Some(old) => Arc::make_mut(old).merge(map),
                        slot => *slot = Some(Arc::new(map)),
                    }
                });
                built += 1;
                let done = if have.as_ref().is_some_and(|h| h.iter().any(|&d| d)) {
                    Cache::Extended
                } else {
                    Cache::Built
                };
                let reason = format!("{reason} in {ms:.1} ms");
                decisions.push(FrameDecision::new(what, Run::Run, reason).with_cache(done));
            } else {
                decisions.push(FrameDecision::new(what, Run::Run, reason).with_cache(Cache::Reused));
            }
        }
        // The lights' pages drawn concurrently: each build has serial steps (binning's sort,
        // the page tables) that another light's drawing fills.
        let groups = if jobs.is_empty() { &[][..] } else { self.plane_groups() };
        // As many at a time as there are threads: each holds its bins until drawn, and more in
        // flight add to the peak memory, not to the speed.
        let drawn: Vec<(LightMap, f64)> = jobs
            .chunks(rayon::current_num_threads().max(1))
            .flat_map(|chunk| {
                chunk
                    .par_iter()
                    .map(|job| timed(|| self.draw_pages(job.light, &job.draw, groups)))
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
            by_rays,
        }
    }

    /// Whether a paged map of `pages` pages fits one light's memory budget (`--map-budget`).
    pub(super) fn fits_map_budget(&self, pages: usize) -> bool {
        hyrt_shadowmap::paged_memory_bound(pages) <= self.options.shadow.map_budget as usize * (1 << 20)
    }

    /// Light `l`'s map of pages `draw` alone (to merge into its cached map), with the triangles'
    /// plane `groups`.
    pub(super) fn draw_pages(&self, l: usize, draw: &[PageKey], groups: &[u32]) -> LightMap {
        let light = self.lights[l].position;
        // Cut-outs: each texel's centre decides whether it sees a hole.
        let hole = |id: u32, dir: Vec3| sees_hole(self.scene, light, id, dir);
        let holes = Holes { cutouts: self.cutouts(), solid: &[], hole: &hole };
        LightMap::build_pages_with_holes(
            &self.scene.positions,
            light,
            &self.options.shadow.map,
            draw,
            groups,
            (!self.cutouts().is_empty() && self.options.shadow.cutouts == CutoutMaps::Texels)
                .then_some(&holes),
        )
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
        self.forget_needed_faces();
    }

    /// Drops the cached light maps (made with other map options); with `needs_changed`, also
    /// which faces or pages camera hits need (they differ between map kinds and layouts, and
    /// with the detail and budget of paged maps).
    pub(crate) fn drop_light_maps(&mut self, needs_changed: bool) {
        self.maps.maps.get_mut().unwrap_or_else(|e| e.into_inner()).clear();
        // The mirror hits' pages went with the maps.
        *self.maps.mirror_marked.get_mut() = false;
        if needs_changed {
            self.forget_needed_faces();
        }
    }

    /// Forgets which light-map faces camera hits fall on (the camera moved), keeping the maps.
    pub(crate) fn forget_needed_faces(&mut self) {
        self.maps.needed = std::sync::OnceLock::new();
        *self.maps.mirror_marked.get_mut() = false;
    }

    /// Light `l`'s cached map (for inspection), once a frame has built it; faces no camera hit
    /// falls on are not drawn ([`LightMap::faces_drawn`]).
    pub fn light_map(&self, l: usize) -> Option<Arc<LightMap>> {
        self.maps.maps.lock().unwrap_or_else(|e| e.into_inner()).get(l).cloned().flatten()
    }
}
