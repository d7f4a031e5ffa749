//! The shadow_rays pass: a shadow ray per undecided (pixel, light), its occluder hint first;
//! and, for inspection, the check of every decision and the per-light buffers.

use glam::Vec3;
use hyrt_shadowmap::{EMPTY, classify::Decision};
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray_to};
use rayon::prelude::*;

use super::lookup::{classifiers, hint, lookup};
use super::{BorderRay, LightBits, Shadowing, WrongCounts, bit, per_light, sum_per_light};
use crate::render::light::{light_geometry, reflect};
use crate::render::{Renderer, Shadows, SurfaceHit};

/// Rays per parallel chunk of the shadow-ray pass: fixed, so that ray counts add up in the same
/// order for any thread count.
const RAY_CHUNK: usize = 64;

impl Shadowing<'_> {
    /// The `shadow_rays` pass: one shadow ray (hint first) per undecided (pixel, light), whose
    /// answer replaces the map's; the direct light of the pixels with such rays is computed
    /// again into `direct`.
    pub fn trace(&mut self, r: &Renderer, gbuffer: &[Option<Hit>], direct: &mut [Vec3]) -> RayCounts {
        let n = gbuffer.len();
        let nl = self.maps.len();
        let b = &mut self.bufs;
        let stride = b.faces.stride;
        // The pixels with rays, in order, and their shading points.
        let w = r.scene.settings.width.max(1) as usize;
        let pixels: Vec<u32> = (0..n.div_ceil(w))
            .into_par_iter()
            .flat_map_iter(|y| (y * w..((y + 1) * w).min(n)).filter(|&i| b.und.any(i)).map(|i| i as u32))
            .collect();
        // None (no light has a map, or no borders): the classifiers, which need every
        // occluder's plane, are not made.
        if pixels.is_empty() {
            return RayCounts::default();
        }
        let cls = classifiers(&self.maps, self.planes, r);
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
                // A light's rays and its kept hints are both in pixel order: a cursor walks the
                // hints alongside the rays (a search per ray cost a tenth of the pass).
                let mut cursor: Option<(usize, usize)> = None;
                let out = chunk
                    .iter()
                    .map(|&(l, k)| {
                        let (l, s) = (l as usize, &points[k as usize]);
                        let i = pixels[k as usize];
                        let kept = &self.hints[l];
                        let mut at = match cursor {
                            Some((cl, at)) if cl == l => at,
                            _ => kept.partition_point(|e| e.pixel < i),
                        };
                        while kept.get(at).is_some_and(|e| e.pixel < i) {
                            at += 1;
                        }
                        cursor = Some((l, at));
                        let hint = match kept.get(at) {
                            Some(e) if e.pixel == i => e.hint,
                            // Undecided by the Laplacian, the dilation or no map: no lookup
                            // was kept; the map's texels give a cheaper hint.
                            _ => hint(&cls[l], &self.resolution, l, s, r),
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
        let und_counts = &mut self.und_counts;
        // The pixels for which a ray overturned the map's decision of some light.
        let mut overturned = vec![false; pixels.len()];
        for (chunk, (out, c)) in order.chunks(RAY_CHUNK).zip(answers) {
            for (&(l, k), (blocked, hinted)) in chunk.iter().zip(out) {
                let (l, i) = (l as usize, pixels[k as usize] as usize);
                let (byte, m) = (i * stride + l / 8, 1u8 << (l % 8));
                let map_lit = b.lit.bits[byte] & m != 0;
                und_counts[l].rays += 1;
                und_counts[l].map_lit += u64::from(map_lit);
                overturned[k as usize] |= map_lit == blocked;
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
        // The direct light of the pixels whose decisions a ray overturned, again, with their
        // final decisions. The others' is classify's, from the same decisions: `reflect` of
        // the same geometry (`lanes` is `light_geometry` to the bit), or nothing for a pixel
        // whose camera hit came after classify and whose rays all found shadow.
        let lit = &b.lit;
        let colors: Vec<(u32, Vec3)> = pixels
            .par_iter()
            .zip(&points)
            .zip(&overturned)
            .filter(|(_, o)| **o)
            .map(|((&i, s), _)| {
                let bits = lit.pixel(i as usize);
                (i, reflect(r, s, |l, light| if bit(bits, l) { light_geometry(s, light) } else { None }))
            })
            .collect();
        for (i, c) in colors {
            direct[i as usize] = c;
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
