//! Visibility of a light from a mirror hit, which has no screen neighbours: the map-space test
//! alone, with a ray where it cannot tell; and the pages of paged maps that mirror hits read.
//!
//! Marking finds the pages camera hits need before the map is drawn; mirror hits are known only
//! once the specular pass has traced its paths. Their pages are mostly not among the camera's
//! (the mirror shows other surfaces), and a lookup in a page not drawn cannot tell, so a ray
//! would decide it. So the specular pass, between tracing its paths and shading their hits,
//! draws the missing pages they fall on ([`Shadowing::draw_mirror_pages`]) when those pages pay
//! for themselves over the horizon's frames, as the camera's do (`payoff`), and fit the map's
//! budget. A point seen in a mirror reads the level of a point seen at the length of its whole
//! view path ([`level_along`]). The frames after reuse these pages, as they reuse the camera's,
//! and do not look again (`MapCache::mirror_marked`).

use std::sync::{Arc, atomic::Ordering::Relaxed};

use hyrt_shadowmap::{
    LightMap, PageKey,
    classify::{Decision, Lookup},
    paged::{self, PageRect},
};
use hyrt_tracer::{RayCounts, RayKind, spawn_ray_to};
use rayon::prelude::*;

use super::Shadowing;
use super::lookup::{classifier, level_along, settle};
use super::payoff::COSTS;
use crate::render::light::facing;
use crate::render::{Cache, FrameStats, MirrorShadows, Renderer, Shadows, Subject, SurfaceHit};

impl Shadowing<'_> {
    /// Draws, for each light with a paged map, the pages that the mirror hits `hits` read (each
    /// with the length of its view path, which sets its level: [`level_along`]; the margin as
    /// marking gives a camera hit's) and that the map lacks, merged
    /// into its map here and in the renderer's cache, when they pay: `pages x page cost` below
    /// `horizon x hits on them x ray cost` (each such hit would cast a ray each frame). Counts
    /// them in [`Shadowing::mirror_pages`].
    pub(crate) fn draw_mirror_pages(&mut self, r: &Renderer, hits: &[(&SurfaceHit, f32)]) {
        if !r.paged_maps()
            || r.options.shadow.mirror == MirrorShadows::Rays
            || hits.is_empty()
            || r.maps.mirror_marked.load(Relaxed)
        {
            return;
        }
        let horizon = f64::from(r.options.shadow.map_horizon);
        let mut groups: Option<&[u32]> = None;
        for l in 0..self.maps.len() {
            let map = &self.maps[l];
            if self.by_rays[l] || !map.is_paged() || map.page_count() == 0 {
                continue;
            }
            let light = &r.lights[l];
            // The missing pages the hits facing the light read (packed), and how many hits
            // read one (each would cast a ray).
            let missing: Vec<(Vec<u64>, usize)> = hits
                .par_chunks(256)
                .map(|chunk| {
                    let (mut keys, mut on) = (Vec::new(), 0);
                    for &(s, dist) in chunk {
                        let tri = &r.scene.positions[s.tri as usize];
                        if facing(s, light, tri).is_none() {
                            continue;
                        }
                        let level = level_along(&self.resolution, l, s, dist, r);
                        let before = keys.len();
                        PageRect::around(paged::locate(s.p - light.position, level)).for_each(|k| {
                            if !map.has_page(k) {
                                keys.push(k.pack());
                            }
                        });
                        on += usize::from(keys.len() > before);
                    }
                    (keys, on)
                })
                .collect();
            let hits_on: usize = missing.iter().map(|m| m.1).sum();
            let mut keys: Vec<u64> = missing.into_iter().flat_map(|m| m.0).collect();
            keys.sort_unstable();
            keys.dedup();
            if keys.is_empty()
                || keys.len() as f64 * COSTS.page >= horizon * hits_on as f64 * COSTS.ray
                || !r.fits_map_budget(map.page_count() + keys.len())
            {
                continue;
            }
            let keys: Vec<PageKey> = keys.into_iter().map(PageKey::unpack).collect();
            let groups = *groups.get_or_insert_with(|| r.plane_groups());
            let drawn = r.draw_pages(l, &keys, groups);
            // The cache's copy let go first, so that the merge does not copy the whole map.
            let mut cache = r.maps.maps.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(slot) = cache.get_mut(l) {
                *slot = None;
            }
            Arc::make_mut(&mut self.maps[l]).merge(drawn);
            if let Some(slot) = cache.get_mut(l) {
                *slot = Some(self.maps[l].clone());
            }
            self.mirror_pages[l] += keys.len() as u32;
        }
    }

    /// The end of a frame's mirror paths: this view's mirror hits need not be looked at again
    /// ([`Shadowing::draw_mirror_pages`]).
    pub(crate) fn mirror_pages_done(&self, r: &Renderer) {
        r.maps.mirror_marked.store(true, Relaxed);
    }

    /// Adds the pages drawn for mirror hits ([`Shadowing::draw_mirror_pages`]) to `stats`: each
    /// such light's counts, and its decision, which says so (a map only reused for the camera
    /// hits was extended, and counts as built).
    pub(crate) fn report_mirror_pages(&self, stats: &mut FrameStats) {
        for (l, &n) in self.mirror_pages.iter().enumerate() {
            if n == 0 {
                continue;
            }
            if let Some(st) = stats.lights.get_mut(l) {
                st.pages_drawn += n;
                st.pages_used += n;
                st.pages_held = self.maps[l].page_count() as u32;
                st.map_bytes = self.maps[l].memory_bytes() as u64;
            }
            if let Some(d) = stats.decisions.iter_mut().find(|d| d.what == Subject::Light(l)) {
                d.reason.push_str(&format!("; {n} page(s) drawn for mirror hits"));
                if d.cache == Cache::Reused {
                    d.cache = Cache::Extended;
                    stats.maps_built += 1;
                }
            }
        }
    }

    /// Light `l`'s map decision at `s`, seen at the end of a view path `dist` long, at the
    /// level the point needs (paged maps).
    fn decide(&self, r: &Renderer, l: usize, s: &SurfaceHit, dist: f32) -> Lookup {
        let cls = classifier(&self.maps[l], self.planes, r);
        cls.classify_at(s.p, s.tri, cls.locate_at(s.p, level_along(&self.resolution, l, s, dist, r)))
    }

    /// Visibility of light `l` from a mirror hit (no screen neighbours) at the end of a view
    /// path `dist` long: the map's decision, or, when `Shadows::Smerts` and the map-space
    /// footprint disagrees or the face was not drawn, a shadow ray with the hint.
    /// `MirrorShadows::Rays`: always a ray.
    pub fn visible_at(
        &self,
        r: &Renderer,
        l: usize,
        s: &SurfaceHit,
        dist: f32,
        counts: &mut RayCounts,
    ) -> bool {
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
        let lk = self.decide(r, l, s, dist);
        if let Some(lit) = settle(r, &lk, s, light.position) {
            return lit;
        }
        if r.options.shadows == Shadows::Smerts && lk.map_border {
            return !r.tracer.occluded_with_hint(&ray(), lk.hint, counts);
        }
        lk.decision == Decision::Lit
    }
}
