//! Lights without a map this frame (`map_cache`: their map would not pay for itself): a shadow
//! ray per pixel that faces them, as the reference casts it, streamed row by row.
//!
//! One thing differs from the reference: each ray first tests the last triangle that blocked a
//! ray toward the same light in the row (a shadow cache, Haines and Greenberg 1986), which
//! mostly blocks the next pixel's ray as well, and answers it without a traversal. The answers
//! are the traversal's ([`hyrt_tracer::Tracer::occluder_with_hint`]), so the image is that of
//! `--shadows rays` byte for byte; `shadow_hint_hits` counts the rays the cache answered.

use glam::Vec3;
use hyrt_tracer::{Hit, RayCounts, spawn_ray_to};
use rayon::prelude::*;

use super::{RayCounted, Shadowing, sum_per_light};
use crate::render::Renderer;
use crate::render::gather::ShadePoint;
use crate::render::light::{PlaneSides, light_geometry, reflect, viewer_side};

/// One row's direct light, and its face, lit and undecided bits.
type RowBufs<'a> = (&'a mut [Vec3], (&'a mut [u8], (&'a mut [u8], &'a mut [u8])));

impl Shadowing<'_> {
    /// Part of the `shadow_rays` pass, after the border rays: for every pixel and light without
    /// a map ([`Shadowing::by_rays`]) that faces it, a shadow ray (no hint: no map kept one).
    /// The pair goes to `faces` and `und` (decided by a ray), its answer to `lit`, and the
    /// light's direct light is added to `direct` (the other lights' is there already: `reflect`
    /// is a sum over lights). A pixel whose camera hit came after the map passes had all its
    /// lights decided by the border rays (`add_ray_pixels`), and is left alone. When no light
    /// has a map, classify did nothing: this pass also makes the diffuse shading `points`.
    pub(crate) fn trace_without_maps(
        &mut self,
        r: &Renderer,
        gbuffer: &[Option<Hit>],
        direct: &mut [Vec3],
        points: Option<&mut [ShadePoint]>,
    ) -> RayCounts {
        let nl = self.maps.len();
        if !self.by_rays.iter().any(|&b| b) {
            return RayCounts::default();
        }
        let points = if self.by_rays.iter().all(|&b| b) { points } else { None };
        let b = &mut self.bufs;
        let stride = b.faces.stride;
        let w = r.scene.settings.width.max(1) as usize;
        let by_rays = &self.by_rays;
        let row = |y: usize, (out, (faces, (lit, und))): RowBufs, mut pts: Option<&mut [ShadePoint]>| {
            let mut c = RayCounts::default();
            let mut counted = vec![RayCounted::default(); nl];
            // `facing`, the plane side of each light kept for the row's last triangle (as the
            // reference's direct pass does).
            let mut sides = PlaneSides::new();
            // Per light, the last triangle that blocked one of its rays in this row: the next
            // ray's hint (a shadow cache), which usually blocks it too.
            let mut last = vec![u32::MAX; nl];
            for (x, px) in out.iter_mut().enumerate() {
                let i = y * w + x;
                let at = x * stride;
                let Some(s) = r.shading_point(gbuffer, i) else { continue };
                if let Some(pts) = pts.as_deref_mut()
                    && r.diffuse(s.tri)
                {
                    pts[x] = ShadePoint::of(&s);
                }
                let tri = &r.scene.positions[s.tri as usize];
                let sides = sides.of(s.tri, tri, &r.lights);
                let before = c;
                *px += reflect(r, &s, |l, light| {
                    if !by_rays[l] {
                        return None;
                    }
                    let (byte, m) = (at + l / 8, 1u8 << (l % 8));
                    // Decided by a border ray already, and shaded with it (a deferred pixel).
                    if und[byte] & m != 0 {
                        return None;
                    }
                    let g = light_geometry(&s, light)?;
                    if !viewer_side(&s, tri, sides[l]) {
                        return None;
                    }
                    faces[byte] |= m;
                    und[byte] |= m;
                    counted[l].rays += 1;
                    let ray = spawn_ray_to(s.p, s.p_err, s.ng, light.position);
                    if let Some(o) = r.tracer.occluder_with_hint(&ray, last[l], &mut c) {
                        last[l] = o;
                        return None;
                    }
                    lit[byte] |= m;
                    Some(g)
                });
                r.pixel_rays.add(i, &before, &c);
            }
            (c, counted)
        };
        let rows = direct
            .par_chunks_mut(w)
            .zip(
                b.faces
                    .bits
                    .par_chunks_mut(w * stride)
                    .zip(b.lit.bits.par_chunks_mut(w * stride).zip(b.und.bits.par_chunks_mut(w * stride))),
            )
            .enumerate();
        let parts: Vec<(RayCounts, Vec<RayCounted>)> = match points {
            Some(p) => rows.zip(p.par_chunks_mut(w)).map(|((y, bufs), p)| row(y, bufs, Some(p))).collect(),
            None => rows.map(|(y, bufs)| row(y, bufs, None)).collect(),
        };
        let mut total = RayCounts::default();
        let mut per_row = Vec::with_capacity(parts.len());
        for (c, counted) in parts {
            total += c;
            per_row.push(counted);
        }
        // Decided by rays alone, as the pairs of `add_ray_pixels` are.
        for (l, u) in sum_per_light(per_row, nl).into_iter().enumerate() {
            self.und_counts[l].rays += u.rays;
            self.added[l] += u.rays;
        }
        total
    }
}
