//! The classify pass: 8x8 tile by tile, the shading points, every light's map decision, and
//! the tile's direct light from those decisions (module docs of `shadows`).

use glam::Vec3;
use hyrt_shadowmap::{
    classify::{Decision, Hull, Plane},
    paged::{LightTerms, Resolution},
};
use hyrt_tracer::Hit;
use rayon::prelude::*;

use super::lanes::{FromLight, LANES, TileLanes};
use super::lookup::{classifiers, settle};
use super::map_cache::FrameMaps;
use super::{BorderHint, LightStats, MapCounts, RayCounted, Shadowing, sum_per_light};
use crate::render::gather::ShadePoint;
use crate::render::light::{PlaneSides, on_viewer_side, reflect, seen_winding};
use crate::render::{FrameStats, Progress, Renderer, Shadows, SurfaceHit};

/// One band of rows of classify's outputs: the direct light, and the face, lit and edge bits.
struct Band<'a> {
    direct: &'a mut [Vec3],
    faces: &'a mut [u8],
    lit: &'a mut [u8],
    edge: &'a mut [u8],
}

/// What one band of rows of the classify pass found: per light, its map decisions (lit,
/// shadowed, and how many of those per tile and by their ambiguous triangles) and its
/// map-space borders, in pixel order.
struct BandOut {
    counts: Vec<MapCounts>,
    hints: Vec<Vec<BorderHint>>,
    /// The shading points of the band's pixels with a map-space border, in pixel order.
    points: Vec<(u32, SurfaceHit)>,
}

/// Side of the square pixel tiles of the classify pass: its shading points stay in L1 while
/// every light decides them, and neighbouring pixels look up neighbouring texels.
const TILE: usize = 8;
/// Half a [`TILE`]: the side of the quarters whose points the tile test decides at once when the
/// whole tile's cannot.
const H: usize = TILE / 2;
/// Point `i` (row-major) of quarter `q` (row-major) of a full tile, as the index of a point of
/// the tile (row-major).
const fn quarter(q: usize, i: usize) -> usize {
    (q / 2 * H + i / H) * TILE + q % 2 * H + i % H
}
/// The points of each quarter of a full tile, a bit each.
const QUARTERS: [u64; 4] = {
    let mut m = [0u64; 4];
    let mut q = 0;
    while q < 4 {
        let mut i = 0;
        while i < H * H {
            m[q] |= 1 << quarter(q, i);
            i += 1;
        }
        q += 1;
    }
    m
};
// A tile's points are bits of a `u64` in the classify pass, and lanes of `TileLanes`.
const _: () = assert!(TILE * TILE <= 64 && TILE * TILE <= LANES);

impl Renderer<'_> {
    /// The map-build pass: the light maps the camera hits of `gbuffer` need, from the cache or
    /// built; what was done per light goes to `stats`' decisions.
    pub(crate) fn map_build(&self, gbuffer: &[Option<Hit>], stats: &mut FrameStats) -> FrameMaps {
        let mut maps = self.light_maps(gbuffer);
        stats.maps_built = maps.built;
        stats.decisions.append(&mut maps.decisions);
        maps
    }

    /// The classify pass (module docs) over the camera hits of `gbuffer` with the maps of the
    /// map-build pass: per pixel and light the map's decision (`faces`, `lit` and `edge` bits of
    /// the returned buffers), and into `direct` the direct light of every camera hit from those
    /// decisions (the border rays correct the pixels they decide), and into `points` the diffuse
    /// shading points.
    pub(crate) fn classify<'r>(
        &'r self,
        gbuffer: &[Option<Hit>],
        maps: FrameMaps,
        direct: &mut [Vec3],
        points: Option<&mut [ShadePoint]>,
        progress: Progress,
    ) -> Shadowing<'r> {
        let (w, h) = (self.scene.settings.width as usize, self.scene.settings.height as usize);
        let n = w * h;
        let lights = &self.lights;
        let nl = lights.len();
        let mut bufs = std::mem::take(&mut *self.maps.scratch.lock().unwrap_or_else(|e| e.into_inner()));
        let FrameMaps { maps, page_counts, by_rays, .. } = maps;
        let resolution: Vec<Resolution> = if self.paged_maps() {
            self.maps.needed.get().map_or_else(Vec::new, |n| n.resolution.clone())
        } else {
            Vec::new()
        };
        // The level of a point for light `l` (its receiver factor `recv`): its page level for
        // paged maps, 0 otherwise.
        let receiver = |s: &SurfaceHit| resolution.first().map_or(0.0, |g| g.receiver(s.p, s.ng.dot(s.wo)));
        // Levels through their ratios (`Resolution::ratio`): a tile's finest level is that of
        // its largest ratio.
        let level = |l: usize, ratio: f32| resolution.get(l).map_or(0, |r| r.level_of_ratio(ratio));

        // No light with a map: nothing is decided here, and the occluders' planes and groups
        // (a pass over every triangle, the first time) are not needed at all.
        let no_map = !by_rays.is_empty() && by_rays.iter().all(|&b| b);
        let planes: &'r [Plane] = if no_map { &[] } else { self.occluders().0 };
        let cls = if no_map { Vec::new() } else { classifiers(&maps, planes, self) };
        let groups = if no_map { &[][..] } else { self.plane_groups() };
        // Only border rays (Smerts) leave from the border pixels' shading points.
        let keep_points = self.options.shadows == Shadows::Smerts;
        bufs.faces.reset(n, nl);
        bufs.lit.reset(n, nl);
        bufs.edge.reset(n, nl);
        bufs.by_hint.reset(n, nl);
        // None until the borders pass (which runs with border rays alone) marks some.
        bufs.und.reset(n, nl);
        bufs.border.clear();
        let stride = bufs.faces.stride;
        let band = (TILE * w).max(1);
        let bands = direct
            .par_chunks_mut(band)
            .zip(bufs.faces.bits.par_chunks_mut(band * stride))
            .zip(bufs.lit.bits.par_chunks_mut(band * stride))
            .zip(bufs.edge.bits.par_chunks_mut(band * stride))
            .map(|(((direct, faces), lit), edge)| Band { direct, faces, lit, edge });
        let band_fn = |b: usize, band_bufs: Band, mut pts: Option<&mut [ShadePoint]>| {
            let Band { direct: out, faces, lit, edge } = band_bufs;
            let first = b * band;
            let rows = out.len() / w.max(1);
            let mut counts = vec![MapCounts::default(); nl];
            // Per light, the band's map-space borders and their occluder hints.
            let mut hints: Vec<Vec<BorderHint>> = vec![Vec::new(); nl];
            let mut border_points = Vec::new();
            // No light with a map: nothing to decide; the ray pass shades every pixel and
            // makes the shading points (`Shadowing::trace_without_maps`).
            if no_map {
                (0..rows).for_each(|_| progress());
                return BandOut { counts, hints, points: border_points };
            }
            // Per tile: the shading points and the lights they face, then per light every
            // point's location and decision, then the points' direct light from those
            // decisions. (Prefetching the located points' texels before deciding them measured
            // slower once pages were compact: the page-table walk it repeats costs more than
            // the misses it hides.)
            let mut tile: Vec<(usize, SurfaceHit)> = Vec::with_capacity(TILE * TILE);
            // The same points a lane each, and each light seen from them (`lanes`): kept for
            // the shading.
            let mut lanes = TileLanes::new();
            let mut froms: Vec<FromLight> = (0..nl).map(|_| FromLight::new()).collect();
            // Per point of the tile, its receiver factor; per light and point (`l * LANES + k`),
            // its level's ratio.
            let mut recv: Vec<f32> = Vec::with_capacity(TILE * TILE);
            let mut ratios: Vec<f32> = vec![0.0; LANES * nl];
            let mut located = Vec::with_capacity(TILE * TILE);
            // Per light, a bit per point of the tile (`k` for point `k`): the points on the side
            // of their plane it is seen from, those it faces (that side, and it shines on them:
            // the `faces` bits), those it lights (`lit`); written to the per-pixel buffers once
            // the tile is decided.
            let (mut side, mut facing, mut lit_by) = (vec![0u64; nl], vec![0u64; nl], vec![0u64; nl]);
            let mut sides = PlaneSides::new();
            for x0 in (0..w).step_by(TILE) {
                tile.clear();
                lanes.clear();
                recv.clear();
                side.fill(0);
                let x1 = (x0 + TILE).min(w);
                for y in 0..rows {
                    for j in y * w + x0..y * w + x1 {
                        out[j] = Vec3::ZERO;
                        let Some(s) = self.shading_point(gbuffer, first + j) else { continue };
                        if let Some(pts) = pts.as_deref_mut()
                            && self.diffuse(s.tri)
                        {
                            pts[j] = ShadePoint::of(&s);
                        }
                        let tri = &self.scene.positions[s.tri as usize];
                        let sd = sides.of(s.tri, tri, lights);
                        // `facing`'s side test, with the plane sides and the winding reused.
                        let seen = seen_winding(&s, tri);
                        for (m, &d) in side.iter_mut().zip(sd) {
                            *m |= u64::from(on_viewer_side(seen, d)) << tile.len();
                        }
                        recv.push(receiver(&s));
                        lanes.push(&s);
                        tile.push((j, s));
                    }
                }
                // Per light, every point's geometry (kept for the shading below), its `faces`
                // bit and its level's ratio. A light without a map: the ray pass decides and
                // shades it. With no `faces` bit it has no border either (borders are within
                // `faces`).
                facing.fill(0);
                lit_by.fill(0);
                for (l, light) in lights.iter().enumerate() {
                    if by_rays[l] {
                        continue;
                    }
                    let from = &mut froms[l];
                    lanes.seen_from(light.position, from);
                    facing[l] = from.shone_on(light, tile.len()) & side[l];
                    // (A loop of the lanes' arithmetic, one guide for all the points.)
                    let ratios = &mut ratios[l * LANES..][..tile.len()];
                    match resolution.get(l) {
                        Some(g) => {
                            for (k, q) in ratios.iter_mut().enumerate() {
                                *q = g.ratio(
                                    recv[k],
                                    LightTerms { r: from.r[k], cos_light: from.cos_light[k] },
                                );
                            }
                        }
                        None => ratios.fill(0.0),
                    }
                }
                // A tile wholly on one plane (triangles of one group): its corner points may
                // decide a light at once (`Classifier::hull`).
                let group = |s: &SurfaceHit| groups[s.tri as usize];
                let one_plane =
                    tile.len() == rows * (x1 - x0) && tile.iter().all(|(_, s)| group(s) == group(&tile[0].1));
                let corners = one_plane.then(|| {
                    let k = tile.len() - 1;
                    [tile[0].1.p, tile[x1 - x0 - 1].1.p, tile[k + 1 - (x1 - x0)].1.p, tile[k].1.p]
                });
                // A full tile that the tile test cannot decide as a whole may have quarters it
                // can: each quarter's corners, for the quarters on one plane (a tile's row-major
                // points). A tile on one plane tries them too: what defeats the whole tile (an
                // occluder's edge, a neighbouring triangle) often lies under one quarter.
                let full = tile.len() == TILE * TILE;
                let quarters: [Option<[Vec3; 4]>; 4] = std::array::from_fn(|q| {
                    let on_one = |g| (0..H * H).all(|i| group(&tile[quarter(q, i)].1) == g);
                    (full && on_one(group(&tile[quarter(q, 0)].1)))
                        .then(|| [0, H - 1, H * H - H, H * H - 1].map(|i| tile[quarter(q, i)].1.p))
                });
                // The tile's points with a map-space border for some light, a bit each.
                let mut bordered = 0u64;
                for (l, c) in cls.iter().enumerate() {
                    if by_rays[l] {
                        continue;
                    }
                    let (byte, bit) = (l / 8, 1u8 << (l % 8));
                    let (faces_l, lit_l) = (facing[l], &mut lit_by[l]);
                    let ratios = &ratios[l * LANES..][..tile.len()];
                    // The tile test reads one level: the finest its points need (each point then
                    // gets texels at least as fine as its own level's; where that level's pages
                    // do not cover the tile, the test cannot tell).
                    let hull_of =
                        |k: &[Vec3; 4], first: usize, finest: u8| c.hull(k, tile[first].1.tri, finest);
                    // The points of `points` (a bit each) that the light faces, decided as the
                    // tile test decided them.
                    let decide_all = |hull: Hull, points: u64, lit: &mut u64, counts: &mut MapCounts| {
                        let decided = points & faces_l;
                        let n = u64::from(decided.count_ones());
                        if hull == Hull::Lit {
                            *lit |= decided;
                            counts.lit += n;
                        } else {
                            counts.shadowed += n;
                        }
                        counts.by_tile += n;
                    };
                    let hull = corners.as_ref().map_or(Hull::Unknown, |k| {
                        hull_of(k, 0, level(l, ratios.iter().copied().fold(0.0, f32::max)))
                    });
                    if hull != Hull::Unknown {
                        decide_all(hull, u64::MAX, lit_l, &mut counts[l]);
                        continue;
                    }
                    // The points no quarter's test decided, a bit per point of the tile.
                    let mut undecided = u64::MAX;
                    for (q, k) in quarters.iter().enumerate() {
                        let Some(k) = k else { continue };
                        let finest = level(l, (0..H * H).map(|i| ratios[quarter(q, i)]).fold(0.0, f32::max));
                        let hull = hull_of(k, quarter(q, 0), finest);
                        if hull != Hull::Unknown {
                            decide_all(hull, QUARTERS[q], lit_l, &mut counts[l]);
                            undecided &= !QUARTERS[q];
                        }
                    }
                    // Located first, then decided: two loops measured faster than one.
                    located.clear();
                    let mut left = faces_l & undecided;
                    while left != 0 {
                        let k = left.trailing_zeros() as usize;
                        located.push((k, c.locate_at(tile[k].1.p, level(l, ratios[k]))));
                        left &= left - 1;
                    }
                    for &(k, m) in &located {
                        let (j, s) = &tile[k];
                        let lk = c.classify_at(s.p, s.tri, m);
                        let settled = settle(self, &lk, s, lights[l].position);
                        let is_lit = settled.unwrap_or(lk.decision == Decision::Lit);
                        *lit_l |= u64::from(is_lit) << k;
                        counts[l].decided(is_lit);
                        counts[l].by_suspects += u64::from(settled.is_some());
                        if lk.map_border && settled.is_none() {
                            edge[j * stride + byte] |= bit;
                            bordered |= 1 << k;
                            hints[l].push(BorderHint { pixel: (first + j) as u32, hint: lk.hint });
                        }
                    }
                }
                // The tile's bits into the per-pixel buffers.
                for (l, (&f, &lb)) in facing.iter().zip(&lit_by).enumerate() {
                    let (byte, bit) = (l / 8, 1u8 << (l % 8));
                    for (bits, buf) in [(f, &mut *faces), (lb, &mut *lit)] {
                        let mut bits = bits;
                        while bits != 0 {
                            buf[tile[bits.trailing_zeros() as usize].0 * stride + byte] |= bit;
                            bits &= bits - 1;
                        }
                    }
                }
                // The direct light of the lights that light each point, with the geometry they
                // were decided with (a light lights only the points it faces, where
                // `lights_along` gave it).
                for (k, (j, s)) in tile.iter().enumerate() {
                    let along = |l: usize| {
                        let f = &froms[l];
                        (lit_by[l] >> k & 1 != 0).then(|| (f.wi(k), f.cos[k], f.d2[k]))
                    };
                    out[*j] = reflect(self, s, |l, _| along(l));
                }
                // Kept for the border rays, which would make the points again.
                while keep_points && bordered != 0 {
                    let (j, s) = &tile[bordered.trailing_zeros() as usize];
                    border_points.push(((first + j) as u32, *s));
                    bordered &= bordered - 1;
                }
            }
            (0..rows).for_each(|_| progress());
            hints.iter_mut().for_each(|h| h.sort_unstable_by_key(|e| e.pixel));
            border_points.sort_unstable_by_key(|e| e.0);
            BandOut { counts, hints, points: border_points }
        };
        let bands: Vec<BandOut> = match points {
            Some(p) => bands
                .zip(p.par_chunks_mut(band))
                .enumerate()
                .map(|(b, (x, p))| band_fn(b, x, Some(p)))
                .collect(),
            None => bands.enumerate().map(|(b, x)| band_fn(b, x, None)).collect(),
        };
        // The bands' lists in band order: each light's in pixel order.
        let hints =
            (0..nl).map(|l| bands.iter().flat_map(|b| b.hints[l].iter().copied()).collect()).collect();
        let border_points = bands.iter().flat_map(|b| b.points.iter().copied()).collect();
        let map_counts = sum_per_light(bands.into_iter().map(|b| b.counts).collect(), nl);

        let needed = self.maps.needed.get();
        let lights = maps
            .iter()
            .zip(&page_counts)
            .enumerate()
            .map(|(l, (m, &[used, drawn]))| LightStats {
                faces_drawn: m.faces_drawn().iter().filter(|&&f| f).count() as u32,
                map_bytes: m.memory_bytes() as u64,
                pages_used: used,
                pages_drawn: drawn,
                pages_held: m.page_count() as u32,
                finest_level: needed
                    .and_then(|n| n.pages.get(l))
                    .and_then(|p| p.iter().map(|k| k.level).max())
                    .unwrap_or(0),
                level_cap: resolution.get(l).map_or(hyrt_shadowmap::MAX_LEVEL, |r| r.cap),
                ..LightStats::default()
            })
            .collect();
        let (added, und_counts) = (vec![0; nl], vec![RayCounted::default(); nl]);
        let mirror_pages = vec![0; nl];
        Shadowing {
            maps,
            bufs,
            lights,
            planes,
            map_counts,
            resolution,
            added,
            und_counts,
            hints,
            border_points,
            by_rays,
            mirror_pages,
        }
    }
}
