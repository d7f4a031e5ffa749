//! The shadow_rays pass: a shadow ray per undecided (pixel, light), its occluder hint first;
//! and, for inspection, the check of every decision and the per-light buffers.

use glam::Vec3;
use hyrt_shadowmap::{EMPTY, classify::Decision};
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray_to};
use rayon::prelude::*;

use super::lookup::{classifiers, hint, lookup};
use super::{BorderRay, LightBits, RayCounted, Shadowing, WrongCounts, bit, per_light, sum_per_light};
use crate::render::light::{light_geometry, reflect};
use crate::render::{Renderer, Shadows, SurfaceHit};

/// Rows of the image per parallel task of the shadow-ray pass. Each band's rays are found,
/// traced, applied and shaded by its task, so that the pass has no serial part; a band's rays to
/// one light still go out in screen order, from neighbouring points.
const BAND_ROWS: usize = 2;

/// The entry of pixel `i` in `list` (in increasing pixel order, `pixel` of each), walking
/// cursor `at` forward to it: the pass's pixels come in increasing order too, so a walk beside
/// them replaces a search per pixel.
fn walk<'a, T>(list: &'a [T], at: &mut usize, pixel: impl Fn(&T) -> u32, i: usize) -> Option<&'a T> {
    while list.get(*at).is_some_and(|e| (pixel(e) as usize) < i) {
        *at += 1;
    }
    list.get(*at).filter(|e| pixel(e) as usize == i)
}

impl Shadowing<'_> {
    /// The `shadow_rays` pass: one shadow ray (hint first) per undecided (pixel, light), whose
    /// answer replaces the map's; the direct light of the pixels whose decision a ray
    /// overturned is computed again into `direct`.
    ///
    /// One task per band of a few rows (`BAND_ROWS`): its pixels with rays and their shading
    /// points, then light by light, each light's rays in screen order (rays to one light from
    /// nearby points traverse the same nodes one after the other; the pixel-major order
    /// alternates lights, and a Morton order of the pixels measured slower than rows), then the
    /// shading.
    pub fn trace(&mut self, r: &Renderer, gbuffer: &[Option<Hit>], direct: &mut [Vec3]) -> RayCounts {
        let nl = self.maps.len();
        let w = r.scene.settings.width.max(1) as usize;
        let b = &mut self.bufs;
        let stride = b.faces.stride;
        // None (no light has a map, or no borders): the classifiers, which need every
        // occluder's plane, are not made.
        if !b.und.bits.par_iter().any(|&m| m != 0) {
            return RayCounts::default();
        }
        let cls = classifiers(&self.maps, self.planes, r);
        let (und, hints, resolution) = (&b.und, &self.hints, &self.resolution);
        let kept_points = &self.border_points;
        let band = w * BAND_ROWS;
        let bands: Vec<(RayCounts, Vec<RayCounted>)> = b
            .lit
            .bits
            .par_chunks_mut(band * stride)
            .zip(b.by_hint.bits.par_chunks_mut(band * stride))
            .zip(direct.par_chunks_mut(band))
            .enumerate()
            .map(|(n, ((lit, by_hint), direct))| {
                let first = n * band;
                let (mut c, mut counted) = (RayCounts::default(), vec![RayCounted::default(); nl]);
                let pixels: Vec<usize> = (first..first + direct.len()).filter(|&i| und.any(i)).collect();
                // Classify's shading points where it kept them (map-space borders), walked in
                // pixel order beside the pixels; made again for the others (the Laplacian's,
                // the dilation's, camera hits found after classify).
                let mut at = kept_points.partition_point(|e| (e.0 as usize) < first);
                let points: Vec<SurfaceHit> = pixels
                    .iter()
                    .map(|&i| match walk(kept_points, &mut at, |e| e.0, i) {
                        Some(&(_, s)) => s,
                        None => r.shading_point(gbuffer, i).expect("undecided pixels have a shading point"),
                    })
                    .collect();
                // The pixels for which a ray overturned the map's decision of some light.
                let mut overturned = vec![false; pixels.len()];
                for (l, counted) in counted.iter_mut().enumerate() {
                    // The light's kept hints are in pixel order too: a cursor walks them
                    // alongside the rays (a search per ray cost a tenth of the pass).
                    let kept = &hints[l];
                    let mut at = kept.partition_point(|e| (e.pixel as usize) < first);
                    let (byte, m) = (l / 8, 1u8 << (l % 8));
                    for ((&i, s), overturned) in pixels.iter().zip(&points).zip(&mut overturned) {
                        if !und.get(i, l) {
                            continue;
                        }
                        let hint = match walk(kept, &mut at, |e| e.pixel, i) {
                            Some(e) => e.hint,
                            // Undecided by the Laplacian, the dilation or no map: no lookup
                            // was kept; the map's texels give a cheaper hint.
                            _ => hint(&cls[l], resolution, l, s, r),
                        };
                        let ray = spawn_ray_to(s.p, s.p_err, s.ng, r.lights[l].position);
                        let (before, hits) = (c, c.shadow_hint_hits);
                        let blocked = r.tracer.occluded_with_hint(&ray, hint, &mut c);
                        r.pixel_rays.add(i, &before, &c);
                        let o = (i - first) * stride + byte;
                        let map_lit = lit[o] & m != 0;
                        counted.rays += 1;
                        counted.map_lit += u64::from(map_lit);
                        *overturned |= map_lit == blocked;
                        if blocked {
                            lit[o] &= !m;
                        } else {
                            lit[o] |= m;
                        }
                        if c.shadow_hint_hits > hits {
                            by_hint[o] |= m;
                        }
                    }
                }
                // The direct light of the pixels whose decisions a ray overturned, again, with
                // their final decisions. The others' is classify's, from the same decisions:
                // `reflect` of the same geometry (`lanes` is `light_geometry` to the bit), or
                // nothing for a pixel whose camera hit came after classify and whose rays all
                // found shadow.
                for ((&i, s), _) in pixels.iter().zip(&points).zip(&overturned).filter(|(_, o)| **o) {
                    let bits = &lit[(i - first) * stride..][..stride];
                    direct[i - first] =
                        reflect(r, s, |l, light| if bit(bits, l) { light_geometry(s, light) } else { None });
                }
                (c, counted)
            })
            .collect();
        let mut total = RayCounts::default();
        let mut counted = Vec::with_capacity(bands.len());
        for (c, per_light) in bands {
            total += c;
            counted.push(per_light);
        }
        for (u, c) in self.und_counts.iter_mut().zip(sum_per_light(counted, nl)) {
            *u += c;
        }
        total
    }

    /// Completes [`Shadowing::lights`] once the map's decisions are final (after the border
    /// rays, if any). With `check` (wrong-visibility count), also a plain shadow ray (no hint)
    /// per (pixel, light) with a decision, not counted as a frame ray, checking every decision:
    /// the map's, the hint's and the traversal's, counted apart. With `Options::keep_buffers`,
    /// the per-light buffers.
    pub fn finish(&mut self, r: &Renderer, gbuffer: &[Option<Hit>], check: bool) {
        let nl = self.maps.len();
        for (((st, m), u), a) in
            self.lights.iter_mut().zip(&self.map_counts).zip(&self.und_counts).zip(&self.added)
        {
            // Undecided pairs: the map's border pairs (lit or shadowed by it), and those no map
            // decided (`add_ray_pixels`).
            st.undecided = u.rays;
            st.lit = m.lit - u.map_lit;
            st.shadowed = m.shadowed - (u.rays - u.map_lit - a);
            st.by_tile = m.by_tile;
            st.by_suspects = m.by_suspects;
        }
        if check {
            self.check(r, gbuffer);
        } else {
            self.bufs.wrong_bits.reset(0, nl);
        }
        if r.options.keep_buffers {
            self.expand(r, gbuffer, check);
        }
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
        let rows: Vec<Vec<WrongCounts>> = b
            .wrong_bits
            .bits
            .par_chunks_mut((w * stride).max(1))
            .enumerate()
            .map(|(y, wrong)| {
                let mut by = vec![WrongCounts::default(); nl];
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
                            let by = &mut by[l];
                            if !und.get(i, l) {
                                by.map += 1;
                            } else if by_hint.get(i, l) {
                                by.hint += 1;
                            } else {
                                by.traversal += 1;
                            }
                        }
                    }
                }
                by
            })
            .collect();
        for (st, by) in self.lights.iter_mut().zip(sum_per_light(rows, nl)) {
            (st.wrong, st.wrong_hint, st.wrong_traversal) = (Some(by.map), Some(by.hint), Some(by.traversal));
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
            (false, _) => BorderRay::None,
            (true, true) => BorderRay::Hint,
            (true, false) => BorderRay::Traversal,
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
}
