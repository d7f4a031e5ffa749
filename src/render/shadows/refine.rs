//! Map-space borders refined: the border pairs of paged maps looked up again at finer levels,
//! on pages drawn for them, before any of them casts a ray.
//!
//! A camera hit reads the level whose texels are about its pixel's footprint (`marking`), and
//! its decision is a border when its 2x2 texel footprint disagrees (or lies within the bias
//! band, which is a texel footprint deep): so the band of border pairs along a shadow's edge is
//! about two texels wide, and each finer level halves it. Fernando et al.'s adaptive shadow
//! maps refine where shadow edges are for the same reason. So after classify, the pages up to
//! [`ShadowOptions::refine_borders`](crate::render::ShadowOptions::refine_borders) levels finer
//! that the border pairs read are drawn, a level at a time for the pairs still on a border, and
//! the pairs looked up again there. A page costs a few hundred rays' worth of work once
//! (`COSTS.page`), and each pair it decides saves a ray every frame: as with the other pages,
//! a level's pages are drawn when `pages x page cost` is below
//! `horizon x pairs on them x ray cost / 2`, the half being the pairs that a band half as wide
//! keeps; and when they fit the budget.
//!
//! The frames after read those pages directly: classify looks a border pair up at the finer
//! levels where their pages are ([`refined_lookup`]), which is what this step's second lookup
//! does too, so that the first frame and the later ones decide alike. This step then finds
//! nothing to draw; it runs once per view (`MapCache::border_marked`).

use std::sync::atomic::Ordering::Relaxed;

use glam::Vec3;
use hyrt_shadowmap::{
    EMPTY, MAX_LEVEL, MapCoord,
    classify::{Classifier, Decision, Lookup},
    paged::{self, PageRect, Resolution},
};
use hyrt_tracer::Hit;
use rayon::prelude::*;

use super::lookup::{classifiers, settle};
use super::payoff::COSTS;
use super::{Shadowing, bit};
use crate::render::light::{light_geometry, light_geometry_and_terms, reflect};
use crate::render::{Ambiguous, Options, Renderer, Shadows, SurfaceHit};

/// Whether lookup `lk` decides its pair without a whole ray: its footprint agrees, or its
/// ambiguous triangles settle it ([`settle`] answers exactly then).
#[inline]
fn decides(lk: &Lookup, o: &Options) -> bool {
    !lk.map_border
        || (lk.suspects[0] != EMPTY
            && o.shadows == Shadows::Smerts
            && o.shadow.ambiguous == Ambiguous::Triangles)
}

/// A frame's map lookup of point `p` (on triangle `own`) with options `o`, from its lookup `lk`
/// at its own location `c`: with paged maps and border rays, a pair that `lk` leaves to a ray is
/// looked up up to [`ShadowOptions::refine_borders`](crate::render::ShadowOptions::refine_borders)
/// levels finer, and the first level that decides it gives its lookup (module docs). Returns
/// the location and lookup that decide.
/// Public for the inspector, which shows what the frame read.
#[inline]
pub fn refined_lookup(
    cls: &Classifier,
    o: &Options,
    p: Vec3,
    own: u32,
    c: MapCoord,
    lk: Lookup,
) -> (MapCoord, Lookup) {
    if o.shadows != Shadows::Smerts || o.shadow.refine_borders == 0 || decides(&lk, o) {
        return (c, lk);
    }
    let n = o.shadow.refine_borders.min(u32::from(MAX_LEVEL)) as u8;
    cls.classify_finer(p, own, c.level, n, |lk| decides(lk, o)).unwrap_or((c, lk))
}

/// Whether border pairs are refined: paged maps (`resolution` not empty) with border rays and
/// [`ShadowOptions::refine_borders`](crate::render::ShadowOptions::refine_borders) levels.
pub(super) fn refines(r: &Renderer, resolution: &[Resolution]) -> bool {
    !resolution.is_empty() && r.options.shadows == Shadows::Smerts && r.options.shadow.refine_borders > 0
}

/// The level of light `l`'s paged map that `s` reads in classify, from the receiver factor
/// of the first guide (the same for every light) and the light's terms.
#[inline]
pub(super) fn point_level(resolution: &[Resolution], l: usize, s: &SurfaceHit, r: &Renderer) -> u8 {
    let Some(g) = resolution.get(l) else { return 0 };
    let recv = resolution[0].receiver(s.p, s.ng.dot(s.wo));
    g.level_from(recv, light_geometry_and_terms(s, &r.lights[l]).1)
}

impl Shadowing<'_> {
    /// The refine step (module docs): per light with a paged map, the pages one level finer
    /// that its border pairs read and the map lacks are drawn when they pay and fit the
    /// budget; then every border pair is looked up there ([`finer`]), and those it decides
    /// leave the borders, their pixels shaded again into `direct`.
    pub(crate) fn refine_borders(&mut self, r: &Renderer, gbuffer: &[Option<Hit>], direct: &mut [Vec3]) {
        if !refines(r, &self.resolution)
            || self.hints.iter().all(Vec::is_empty)
            || r.maps.border_marked.load(Relaxed)
        {
            return;
        }
        let horizon = f64::from(r.options.shadow.map_horizon);
        let mut groups: Option<&[u32]> = None;
        let nl = self.maps.len();
        let mut changed: Vec<u32> = Vec::new();
        for l in 0..nl {
            if self.by_rays[l] || self.hints[l].is_empty() || !self.maps[l].is_paged() {
                continue;
            }
            let light = r.lights[l].position;
            let resolution = &self.resolution;
            // The border pairs' points and levels.
            let points: Vec<(SurfaceHit, u8)> = self.hints[l]
                .par_iter()
                .map(|h| {
                    let s = r
                        .shading_point(gbuffer, h.pixel as usize)
                        .expect("border pairs have a shading point");
                    let level = point_level(resolution, l, &s, r);
                    (s, level)
                })
                .collect();
            // Level by level, the pairs still on a border: the pages they read that the map
            // lacks, drawn if they pay; then those pairs looked up again.
            let mut decided: Vec<Option<(Lookup, Option<bool>)>> = vec![None; points.len()];
            let mut pending: Vec<usize> = (0..points.len()).collect();
            for step in 1..=r.options.shadow.refine_borders.min(u32::from(MAX_LEVEL)) as u8 {
                let map = &self.maps[l];
                let missing: Vec<(Vec<u64>, usize)> = pending
                    .par_chunks(256)
                    .map(|chunk| {
                        let (mut keys, mut on) = (Vec::new(), 0);
                        for &k in chunk {
                            let (s, level) = &points[k];
                            let Some(level) = level.checked_add(step).filter(|&v| v <= MAX_LEVEL) else {
                                continue;
                            };
                            let before = keys.len();
                            PageRect::around(paged::locate(s.p - light, level)).for_each(|key| {
                                if !map.has_page(key) {
                                    keys.push(key.pack());
                                }
                            });
                            on += usize::from(keys.len() > before);
                        }
                        (keys, on)
                    })
                    .collect();
                let pairs_on: usize = missing.iter().map(|m| m.1).sum();
                let mut keys: Vec<u64> = missing.into_iter().flat_map(|m| m.0).collect();
                keys.sort_unstable();
                keys.dedup();
                if !keys.is_empty()
                    && (keys.len() as f64) * COSTS.page < horizon * pairs_on as f64 * COSTS.ray / 2.0
                    && r.fits_map_budget(map.page_count() + keys.len())
                {
                    let groups = *groups.get_or_insert_with(|| r.plane_groups().0);
                    self.border_pages[l] += self.extend_map(r, l, keys, groups);
                }
                let cls = &classifiers(&self.maps[l..=l], self.planes, r)[0];
                let n = r.options.shadow.refine_borders.min(u32::from(MAX_LEVEL)) as u8;
                let now: Vec<_> = pending
                    .par_iter()
                    .map(|&k| {
                        let (s, level) = &points[k];
                        let (_, lk) =
                            cls.classify_finer(s.p, s.tri, *level, n, |lk| decides(lk, &r.options))?;
                        Some((lk, settle(r, &lk, s, light)))
                    })
                    .collect();
                let mut still = Vec::new();
                for (&k, d) in pending.iter().zip(now) {
                    if d.is_some() {
                        decided[k] = d;
                    } else {
                        still.push(k);
                    }
                }
                pending = still;
                if pending.is_empty() {
                    break;
                }
            }
            let b = &mut self.bufs;
            let stride = b.faces.stride;
            let (byte_of, m) = (l / 8, 1u8 << (l % 8));
            let counts = &mut self.map_counts[l];
            let mut kept = Vec::with_capacity(self.hints[l].len());
            for (h, d) in self.hints[l].iter().zip(decided) {
                let Some((lk, settled)) = d else {
                    kept.push(*h);
                    continue;
                };
                let i = h.pixel as usize;
                let byte = i * stride + byte_of;
                let was_lit = b.lit.bits[byte] & m != 0;
                let is_lit = settled.unwrap_or(lk.decision == Decision::Lit);
                if was_lit != is_lit {
                    counts.decided(is_lit);
                    if was_lit {
                        counts.lit -= 1;
                    } else {
                        counts.shadowed -= 1;
                    }
                }
                counts.by_suspects += u64::from(settled.is_some());
                if is_lit {
                    b.lit.bits[byte] |= m;
                } else {
                    b.lit.bits[byte] &= !m;
                }
                b.edge.bits[byte] &= !m;
                changed.push(h.pixel);
            }
            self.hints[l] = kept;
        }
        r.maps.border_marked.store(true, Relaxed);
        // The pixels whose pairs left the borders: their direct light with the finer decisions.
        changed.sort_unstable();
        changed.dedup();
        let lit = &self.bufs.lit;
        let colors: Vec<Vec3> = changed
            .par_iter()
            .map(|&i| {
                let s = r.shading_point(gbuffer, i as usize).expect("border pairs have a shading point");
                let bits = lit.pixel(i as usize);
                reflect(r, &s, |l, light| if bit(bits, l) { light_geometry(&s, light) } else { None })
            })
            .collect();
        for (&i, c) in changed.iter().zip(colors) {
            direct[i as usize] = c;
        }
    }
}
