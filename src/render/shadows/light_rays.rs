//! Lights without a map this frame (`map_cache`: their map would not pay for itself): a shadow
//! ray per pixel that faces them, as the reference casts it, row by row.
//!
//! Two things differ from the reference:
//! - Each ray first tests the last triangle that blocked a ray toward the same light in the
//!   row (a shadow cache, Haines and Greenberg 1986), which mostly blocks the next pixel's ray
//!   as well, and answers it without a traversal. The answers are the traversal's
//!   ([`hyrt_tracer::Tracer::occluder_with_hint`]); `shadow_hint_hits` counts the rays the
//!   cache answered.
//! - A row is prepared (its shading points, the lights each faces, their rays) before it is
//!   traced. On a renderer's first frame the BVH is still being built on a thread of its own
//!   when this pass starts (rasterized visibility did not need it), and the reference would
//!   wait for it with a core idle: here the calling thread prepares rows, in order, until the
//!   BVH is ready, and the pass then traces those and prepares and traces the rest.
//!
//! Neither changes an answer or the order of a row's rays, so the image is that of
//! `--shadows rays` byte for byte, however many rows were prepared ahead.

use glam::Vec3;
use hyrt_tracer::{Hit, RayCounts, offset_ray_origin, ray_to};
use rayon::prelude::*;

use super::{RayCounted, Shadowing, sum_per_light};
use crate::render::gather::ShadePoint;
use crate::render::light::{PlaneSides, light_geometry, reflect, viewer_side};
use crate::render::{Renderer, SurfaceHit};

/// One row's direct light, and its face, lit and undecided bits.
type RowBufs<'a> = (&'a mut [Vec3], (&'a mut [u8], (&'a mut [u8], &'a mut [u8])));

/// Bytes that rows prepared ahead (while the BVH builds) may hold at most: a small part of a
/// frame's memory, which the one-image renders that prepare rows ahead keep low (a row of a
/// scene with many lights holds tens of thousands of rays).
const AHEAD_BYTES: usize = 16 << 20;

/// A row made ready to trace: its shading points (with their column) and, pixel by pixel and
/// light by light in that order, the rays to cast: the point's index in `hits`, the light,
/// and the ray's origin ([`ray_to`] makes the ray).
#[derive(Default)]
struct Row {
    hits: Vec<(usize, SurfaceHit)>,
    rays: Vec<(u32, u32, Vec3)>,
}

impl Row {
    fn bytes(&self) -> usize {
        self.hits.len() * size_of::<(usize, SurfaceHit)>() + self.rays.len() * size_of::<(u32, u32, Vec3)>()
    }

    /// Row `y` of `gbuffer`: every shading point, and a ray for each light without a map
    /// (`by_rays`) that faces it, unless the pair was decided by a border ray already (its
    /// `und` bit set in `und`, the row's undecided bits: a deferred pixel, shaded with it).
    fn prepare(r: &Renderer, gbuffer: &[Option<Hit>], y: usize, by_rays: &[bool], und: &[u8]) -> Self {
        let w = r.scene.settings.width.max(1) as usize;
        let stride = und.len() / w;
        let mut row = Row::default();
        // `facing`, the plane side of each light kept for the row's last triangle (as the
        // reference's direct pass does).
        let mut sides = PlaneSides::new();
        for x in 0..w {
            let Some(s) = r.shading_point(gbuffer, y * w + x) else { continue };
            let k = row.hits.len() as u32;
            let tri = &r.scene.positions[s.tri as usize];
            let sides = sides.of(s.tri, tri, &r.lights);
            for (l, light) in r.lights.iter().enumerate() {
                if !by_rays[l] || und[x * stride + l / 8] & (1 << (l % 8)) != 0 {
                    continue;
                }
                if light_geometry(&s, light).is_some() && viewer_side(&s, tri, sides[l]) {
                    let o = offset_ray_origin(s.p, s.p_err, s.ng, light.position - s.p);
                    row.rays.push((k, l as u32, o));
                }
            }
            row.hits.push((x, s));
        }
        row
    }

    /// Traces the row's rays and shades its points (see [`Shadowing::trace_without_maps`]).
    fn finish(
        &self,
        r: &Renderer,
        y: usize,
        (out, (faces, (lit, und))): RowBufs,
        pts: Option<&mut [ShadePoint]>,
        counted: &mut [RayCounted],
    ) -> RayCounts {
        let w = r.scene.settings.width.max(1) as usize;
        let stride = faces.len() / w;
        if let Some(pts) = pts {
            for (x, s) in &self.hits {
                if r.diffuse(s.tri) {
                    pts[*x] = ShadePoint::of(s);
                }
            }
        }
        let mut c = RayCounts::default();
        // Per light, the last triangle that blocked one of its rays in this row: the next
        // ray's hint.
        let mut last = vec![u32::MAX; r.lights.len()];
        // Per point, the lights whose rays reached them (bits as in `faces`).
        let mut reached = vec![0u8; self.hits.len() * stride];
        for &(k, l, o) in &self.rays {
            let (k, l) = (k as usize, l as usize);
            let ray = &ray_to(o, r.lights[l].position);
            let x = self.hits[k].0;
            let (byte, m) = (x * stride + l / 8, 1u8 << (l % 8));
            faces[byte] |= m;
            und[byte] |= m;
            counted[l].rays += 1;
            let before = c;
            match r.tracer.occluder_with_hint(ray, last[l], &mut c) {
                Some(o) => last[l] = o,
                None => {
                    lit[byte] |= m;
                    reached[k * stride + l / 8] |= m;
                }
            }
            r.pixel_rays.add(y * w + x, &before, &c);
        }
        for (k, (x, s)) in self.hits.iter().enumerate() {
            let reached = &reached[k * stride..][..stride];
            out[*x] += reflect(r, s, |l, light| {
                if reached[l / 8] & (1 << (l % 8)) == 0 {
                    return None;
                }
                light_geometry(s, light)
            });
        }
        c
    }
}

/// The first rows of [`Shadowing::trace_without_maps`], prepared while the BVH builds.
#[derive(Default)]
pub(crate) struct RowsAhead(Vec<Row>);

impl Shadowing<'_> {
    /// While a first frame's BVH is still being built: the rows of the lights without a map,
    /// prepared from the top (module docs) on the calling thread until `ready()` (the BVH is;
    /// [`hyrt_tracer::Tracer::is_ready`]) or [`AHEAD_BYTES`], for
    /// [`Shadowing::trace_without_maps`]. Call it before the deferred camera rays wait for the
    /// BVH: the deferred pixels, without a hit yet, are left out, as their rays would be
    /// (`add_ray_pixels` decides all their lights by border rays).
    pub(crate) fn rows_ahead(
        &self,
        r: &Renderer,
        gbuffer: &[Option<Hit>],
        ready: &dyn Fn() -> bool,
    ) -> RowsAhead {
        let mut ahead = Vec::new();
        if !self.by_rays.iter().any(|&b| b) {
            return RowsAhead(ahead);
        }
        let w = r.scene.settings.width.max(1) as usize;
        let mut bytes = 0;
        for und in self.bufs.und.bits.chunks(w * self.bufs.und.stride) {
            if ready() || bytes > AHEAD_BYTES {
                break;
            }
            let row = Row::prepare(r, gbuffer, ahead.len(), &self.by_rays, und);
            bytes += row.bytes();
            ahead.push(row);
        }
        RowsAhead(ahead)
    }

    /// Part of the `shadow_rays` pass, after the border rays: for every pixel and light without
    /// a map ([`Shadowing::by_rays`]) that faces it, a shadow ray (module docs).
    /// The pair goes to `faces` and `und` (decided by a ray), its answer to `lit`, and the
    /// light's direct light is added to `direct` (the other lights' is there already: `reflect`
    /// is a sum over lights). A pixel whose camera hit came after the map passes had all its
    /// lights decided by the border rays (`add_ray_pixels`), and is left alone. When no light
    /// has a map, classify did nothing: this pass also makes the diffuse shading `points`.
    /// Rows in `ahead` ([`Shadowing::rows_ahead`]) are traced as they were prepared.
    pub(crate) fn trace_without_maps(
        &mut self,
        r: &Renderer,
        gbuffer: &[Option<Hit>],
        direct: &mut [Vec3],
        points: Option<&mut [ShadePoint]>,
        ahead: RowsAhead,
    ) -> RayCounts {
        let nl = self.maps.len();
        if !self.by_rays.iter().any(|&b| b) {
            return RayCounts::default();
        }
        let ahead = ahead.0;
        let points = if self.by_rays.iter().all(|&b| b) { points } else { None };
        let b = &mut self.bufs;
        let stride = b.faces.stride;
        let w = r.scene.settings.width.max(1) as usize;
        let by_rays = &self.by_rays;
        let row = |y: usize, bufs: RowBufs, pts: Option<&mut [ShadePoint]>| {
            let mut counted = vec![RayCounted::default(); nl];
            let c = match ahead.get(y) {
                Some(row) => row.finish(r, y, bufs, pts, &mut counted),
                None => {
                    Row::prepare(r, gbuffer, y, by_rays, bufs.1.1.1).finish(r, y, bufs, pts, &mut counted)
                }
            };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Options, Renderer};

    /// Rows prepared ahead are traced as rows prepared in the pass: the same direct light and
    /// the same face, lit and undecided bits, whether every row, none or some were prepared
    /// ahead (how many depends on the BVH build's timing).
    #[test]
    fn rows_prepared_ahead_trace_as_the_others() {
        let mut scene = crate::scene::load("cornell").unwrap();
        (scene.settings.width, scene.settings.height) = (64, 48);
        let mut o = Options::hybrid();
        // No map pays in so short a horizon: every light is left to rays.
        o.shadow.map_horizon = 1e-6;
        let r = Renderer::new(&scene, o);
        let (gbuffer, _) = r.visibility();
        let n = gbuffer.len();
        let frame = |ahead_rows: usize| {
            let mut direct = vec![Vec3::ZERO; n];
            let maps = r.map_build(&gbuffer, &mut crate::render::FrameStats::default());
            let mut s = r.classify(&gbuffer, maps, &mut direct, None, &|| {});
            assert!(s.by_rays.iter().all(|&b| b), "every light by rays");
            let rows = std::cell::Cell::new(0);
            let ahead = s.rows_ahead(&r, &gbuffer, &|| {
                rows.set(rows.get() + 1);
                rows.get() > ahead_rows
            });
            assert_eq!(ahead.0.len(), ahead_rows.min(48));
            let c = s.trace_without_maps(&r, &gbuffer, &mut direct, None, ahead);
            let bits: Vec<u32> = direct.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect();
            (bits, s.bufs.faces.bits.clone(), s.bufs.lit.bits.clone(), s.bufs.und.bits.clone(), c.shadow)
        };
        let none = frame(0);
        assert!(none.4 > 0 && none.2.iter().any(|&b| b != 0), "rays cast, some lit");
        assert!(frame(48) == none, "every row prepared ahead");
        assert!(frame(17) == none, "some rows prepared ahead");
    }
}
