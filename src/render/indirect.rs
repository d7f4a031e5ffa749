//! Diffuse indirect light from virtual point lights, with visibility by shadow rays
//! (`Indirect::Rays`, the reference) or by one paraboloid depth map per VPL (`Indirect::Maps`,
//! the thesis's hybrid: lookups only, no selective rays).
//!
//! The VPLs (see [`super::vpl`]) and their maps depend only on the scene: they are made on the
//! first frame and kept.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;
use hyrt_shadowmap::vpl_map::VplMap;
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray_to};
use rayon::prelude::*;

use super::gather::{self, Points, ShadePoint, Sums, VplConsts};
use super::{Progress, Renderer, SurfaceHit, vpl};

pub use crate::options::{IndirectOptions, VplFilter};

/// What the indirect pass needs per frame.
pub struct Vpls<'r> {
    pub vpls: &'r [vpl::Vpl],
    /// One map per VPL with `Indirect::Maps`, else empty.
    pub maps: &'r [VplMap],
    /// Per map, what the gather needs of it and of its VPL.
    consts: Vec<VplConsts>,
    /// `d_min^2` in scene units.
    clamp2: f32,
}

impl Renderer<'_> {
    /// What the indirect pass needs of the VPLs and their maps (`maps` empty with
    /// `Indirect::Rays`).
    pub(crate) fn vpls<'r>(&self, vpls: &'r [vpl::Vpl], maps: &'r [VplMap]) -> Vpls<'r> {
        let opts = &self.options.indirect_opts;
        let diag = self.bounds.map_or(1.0, |(lo, hi)| (hi - lo).length());
        let clamp = opts.clamp.max(0.0) * diag;
        let clamp2 = clamp * clamp;
        let e = self.occluders().1;
        let consts = vpls.iter().zip(maps).map(|(v, m)| VplConsts::new(v, m, clamp2, opts.bias, e)).collect();
        Vpls { vpls, maps, consts, clamp2 }
    }
}

impl Vpls<'_> {
    /// `cos_x cos_v / max(d^2, d_min^2)` between the diffuse point `s` and `v`, or `None` when
    /// either faces away.
    #[inline]
    fn geometry(&self, s: &SurfaceHit, v: &vpl::Vpl) -> Option<f32> {
        let to_vpl = v.position - s.p;
        let d2 = to_vpl.length_squared();
        if d2 == 0.0 {
            return None;
        }
        let wi = to_vpl / d2.sqrt();
        let (cos_x, cos_v) = (s.ns.dot(wi), -v.normal.dot(wi));
        if cos_x <= 0.0 || cos_v <= 0.0 || s.ng.dot(wi) <= 0.0 {
            return None;
        }
        Some(cos_x * cos_v / d2.max(self.clamp2))
    }

    /// Indirect radiance leaving the diffuse point `s` towards its viewer:
    /// `Kd / pi * sum_v I_v cos_x cos_v / max(d^2, d_min^2)` over the visible VPLs.
    pub fn at(&self, r: &Renderer, s: &SurfaceHit, counts: &mut RayCounts) -> Vec3 {
        self.at_subset(r, s, 0, 1, counts)
    }

    /// [`Vpls::at`] over the VPLs `subset, subset + stride, ...` only, scaled by `stride`: the
    /// interleaved estimate of a point with no screen neighbours to filter with (a mirror hit
    /// of the pixel whose subset it is), unbiased and noisier.
    pub fn at_subset(
        &self,
        r: &Renderer,
        s: &SurfaceHit,
        subset: usize,
        stride: usize,
        counts: &mut RayCounts,
    ) -> Vec3 {
        if !r.diffuse(s.tri) {
            return Vec3::ZERO;
        }
        let kd = s.albedo;
        let mut sum = Vec3::ZERO;
        let stride = stride.max(1);
        for (k, v) in self.vpls.iter().enumerate().skip(subset).step_by(stride) {
            let Some(g) = self.geometry(s, v) else { continue };
            match self.maps.get(k) {
                // No rays to settle it: an occluder within the bias band is taken to be the
                // point's own curved surface (the commoner case), not a contact shadow.
                Some(map) => {
                    let pair = match r.options.indirect_opts.filter {
                        VplFilter::Texel => gather::pair,
                        VplFilter::Bilinear => gather::pair_bilinear,
                    };
                    sum += v.intensity * pair(&self.consts[k], map, s.p, s.ns, s.ng);
                }
                None => {
                    let ray = spawn_ray_to(s.p, s.p_err, s.ng, v.position);
                    if !r.tracer.occluded(&ray, RayKind::VplShadow, counts) {
                        sum += v.intensity * g;
                    }
                }
            }
        }
        kd * FRAC_1_PI * sum * stride as f32
    }

    /// Whether [`Vpls::at_subsets`] applies: maps looked up by texel.
    pub(crate) fn batched(&self, r: &Renderer) -> bool {
        !self.maps.is_empty() && r.options.indirect_opts.filter == VplFilter::Texel
    }

    /// [`Vpls::at_subset`] of many points at once (when [`Vpls::batched`]), point `j` over the
    /// VPLs `subsets[j], subsets[j] + stride, ...`: the same values to the bit, computed VPL by
    /// VPL with the vector kernel.
    pub(crate) fn at_subsets(
        &self,
        r: &Renderer,
        hits: &[SurfaceHit],
        subsets: &[usize],
        stride: usize,
    ) -> Vec<Vec3> {
        let stride = stride.max(1);
        // The diffuse points of each subset.
        let mut groups: Vec<(Vec<usize>, Points)> = vec![Default::default(); stride];
        for (j, (s, &q)) in hits.iter().zip(subsets).enumerate() {
            if r.diffuse(s.tri) {
                groups[q % stride].0.push(j);
                groups[q % stride].1.push(&ShadePoint::of(s));
            }
        }
        let mut out = vec![Vec3::ZERO; hits.len()];
        for (q, (idx, pts)) in groups.iter_mut().enumerate() {
            if idx.is_empty() {
                continue;
            }
            let mut sums = Sums::default();
            sums.reset(pts.len());
            for vi in (q..self.vpls.len()).step_by(stride) {
                gather::add_vpl(&self.consts[vi], &self.maps[vi], pts, &mut sums);
            }
            for (m, &j) in idx.iter().enumerate() {
                out[j] = hits[j].albedo * FRAC_1_PI * sums.get(m) * stride as f32;
            }
        }
        out
    }

    /// The VPL subset of pixel `i` of a `width`-wide image under `k x k` interleaving, and the
    /// stride between its VPLs (`k^2`).
    pub fn subset_of(i: usize, width: usize, k: usize) -> (usize, usize) {
        let (w, k) = (width.max(1), k.max(1));
        ((i % w) % k + k * ((i / w) % k), k * k)
    }
}

/// The indirect pass over the camera hits.
///
/// Per pixel it first sums `I_v cos_x cos_v / max(d^2, d_min^2)` over its visible VPLs (the
/// irradiance-like part), then multiplies by `Kd / pi`. With maps, it goes a band of rows at a
/// time, VPL by VPL: the band's points are first located in the VPL's map and their texels
/// prefetched, then decided, so that the cache misses of a band overlap (a 1024^2 map is 4 MB of
/// ids). Each pixel adds its VPLs in VPL order either way, so the sums are the same bytes as
/// [`Vpls::at`]'s and for any thread count.
///
/// # Interleaved sampling
///
/// With `interleave = k > 1` (beyond the thesis), pixel `(x, y)` evaluates only the VPLs whose
/// index is `(x mod k) + k (y mod k)` modulo `k^2`, scaled by `k^2`: `k^2` times fewer VPL
/// evaluations, an unbiased but noisy estimate. A geometry-aware box filter over the `k x k`
/// window around each pixel (which holds every subset once) then averages the estimates of
/// the window's pixels on the same surface: shading normals within 25 degrees and camera
/// distances within 5 %. Mirror hits always use every VPL.
///
/// `points`, when the direct-light pass has made them (with maps only), are the pixels'
/// shading points; otherwise this pass makes them.
pub(crate) fn run(
    r: &Renderer,
    v: &Vpls,
    gbuffer: &[Option<Hit>],
    points: Option<&[ShadePoint]>,
    out: &mut [Vec3],
    progress: Progress,
) -> (RayCounts, u64) {
    let w = r.scene.settings.width.max(1) as usize;
    let k = r.options.indirect_opts.interleave.max(1) as usize;
    let n = out.len();
    if let Some(points) = points.filter(|_| k == 1 && !v.maps.is_empty()) {
        return gather_all(r, v, gbuffer, points, out, progress);
    }
    let takes = |i: usize, vpl: usize| k == 1 || vpl % (k * k) == Vpls::subset_of(i, w, k).0;
    // Per pixel: the VPL sum, and what the interleaving filter compares (the shading normal
    // and the camera distance; distance 0 where the pixel has no diffuse point).
    let mut irr = vec![Vec3::ZERO; n];
    let mut geo = vec![[0f32; 4]; n];
    // Per pixel, the albedo of its diffuse point, which the filtered sum multiplies.
    let mut albedo = vec![Vec3::ZERO; n];
    // The shading point of pixel `i`, if it is diffuse.
    let diffuse = |i: usize| {
        let h = gbuffer[i].as_ref()?;
        let dir = r.camera_ray((i % w) as u32, (i / w) as u32).dir;
        r.diffuse(h.tri).then(|| SurfaceHit::new(r.scene, h, dir))
    };

    // The direct-light pass's shading points, which only the maps' gather reads.
    let shared = points.filter(|_| !v.maps.is_empty());
    // Rows per parallel job: with interleaving, each of the k^2 subsets gets a row or more.
    let band = 4usize.max(k);
    let filter = r.options.indirect_opts.filter;
    let counts: Vec<(RayCounts, u64)> = irr
        .par_chunks_mut(w * band)
        .zip(geo.par_chunks_mut(w * band))
        .zip(albedo.par_chunks_mut(w * band))
        .enumerate()
        .map(|(b, ((irr, geo), albedo))| {
            let first = b * w * band;
            let mut c = RayCounts::default();
            let mut pairs = 0u64;
            // The band's points of each VPL subset (all of them without interleaving), in
            // struct-of-arrays order, with their pixels.
            let room = if v.maps.is_empty() { 0 } else { irr.len() / (k * k) + gather::LANES };
            let mut groups: Vec<(Vec<usize>, Points)> =
                (0..k * k).map(|_| (Vec::with_capacity(room), Points::with_capacity(room))).collect();
            for (j, ((acc, geo), albedo)) in irr.iter_mut().zip(geo.iter_mut()).zip(albedo).enumerate() {
                let i = first + j;
                if let Some(points) = shared {
                    let (sp, Some(h)) = (&points[i], &gbuffer[i]) else { continue };
                    if sp.ns != Vec3::ZERO {
                        *geo = [sp.ns.x, sp.ns.y, sp.ns.z, h.t];
                        *albedo = sp.albedo;
                        let (group, pts) = &mut groups[Vpls::subset_of(i, w, k).0];
                        group.push(j);
                        pts.push(sp);
                    }
                    continue;
                }
                let Some(s) = diffuse(i) else { continue };
                *geo = [s.ns.x, s.ns.y, s.ns.z, s.t];
                *albedo = s.albedo;
                if !v.maps.is_empty() {
                    let (group, pts) = &mut groups[Vpls::subset_of(i, w, k).0];
                    group.push(j);
                    pts.push(&ShadePoint::of(&s));
                    continue;
                }
                let before = c;
                for (_, vpl) in v.vpls.iter().enumerate().filter(|(vi, _)| takes(i, *vi)) {
                    pairs += 1;
                    let Some(g) = v.geometry(&s, vpl) else { continue };
                    let ray = spawn_ray_to(s.p, s.p_err, s.ng, vpl.position);
                    if !r.tracer.occluded(&ray, RayKind::VplShadow, &mut c) {
                        *acc += vpl.intensity * g;
                    }
                }
                r.pixel_rays.add(i, &before, &c);
            }
            if !v.maps.is_empty() {
                let mut sums: Vec<Sums> = groups
                    .iter()
                    .map(|(_, p)| {
                        let mut s = Sums::default();
                        s.reset(p.len());
                        s
                    })
                    .collect();
                for (vi, (consts, map)) in v.consts.iter().zip(v.maps).enumerate() {
                    let (q, sums) = (vi % (k * k), &mut sums[vi % (k * k)]);
                    pairs += groups[q].0.len() as u64;
                    add_vpl(filter, consts, map, &groups[q].1, sums);
                }
                for ((group, _), sums) in groups.iter().zip(&sums) {
                    for (m, &j) in group.iter().enumerate() {
                        irr[j] = sums.get(m);
                    }
                }
            }
            for _ in 0..irr.len() / w {
                progress();
            }
            (c, pairs)
        })
        .collect();

    let filtered = if k > 1 { super::interleave::filter(&irr, &geo, w, k) } else { irr };
    out.par_iter_mut().zip(filtered).enumerate().for_each(|(i, (o, e))| {
        if let Some(h) = &gbuffer[i]
            && r.diffuse(h.tri)
        {
            *o = albedo[i] * FRAC_1_PI * e;
        }
    });
    counts.into_iter().fold((RayCounts::default(), 0), |(mut c, n), (d, m)| {
        c += d;
        (c, n + m)
    })
}

/// Adds the light of VPL `consts` at every point of `pts` to `sums`, looked up as `filter` asks.
fn add_vpl(filter: VplFilter, consts: &VplConsts, map: &VplMap, pts: &Points, sums: &mut Sums) {
    match filter {
        VplFilter::Texel => gather::add_vpl(consts, map, pts, sums),
        VplFilter::Bilinear => gather::add_vpl_with(gather::pair_bilinear, consts, map, pts, sums),
    }
}

/// [`run`] without interleaving, from the direct-light pass's shading points: a band of
/// pixels at a time, all of them in order (those without a diffuse point face nothing), so
/// the points need only a transpose and the sums land on their pixels, which are shaded at
/// once: no frame-sized buffers besides `out`.
fn gather_all(
    r: &Renderer,
    v: &Vpls,
    gbuffer: &[Option<Hit>],
    points: &[ShadePoint],
    out: &mut [Vec3],
    progress: Progress,
) -> (RayCounts, u64) {
    let w = r.scene.settings.width.max(1) as usize;
    const BAND: usize = 4;
    let filter = r.options.indirect_opts.filter;
    let pairs: u64 = out
        .par_chunks_mut(w * BAND)
        .zip(points.par_chunks(w * BAND))
        .zip(gbuffer.par_chunks(w * BAND))
        .map(|((out, points), hits)| {
            let mut pts = Points::with_capacity(points.len());
            pts.set(points);
            let mut sums = Sums::default();
            sums.reset(pts.len());
            for (consts, map) in v.consts.iter().zip(v.maps) {
                add_vpl(filter, consts, map, &pts, &mut sums);
            }
            let mut diffuse = 0u64;
            for (j, (o, (p, h))) in out.iter_mut().zip(points.iter().zip(hits)).enumerate() {
                if let (Some(_), true) = (h, p.ns != Vec3::ZERO) {
                    *o = p.albedo * FRAC_1_PI * sums.get(j);
                    diffuse += 1;
                }
            }
            for _ in 0..out.len() / w {
                progress();
            }
            diffuse * v.vpls.len() as u64
        })
        .sum();
    (RayCounts::default(), pairs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Indirect, Options};

    /// The indirect pass (without interleaving) gives, at every pixel, the bytes of
    /// [`Vpls::at`] at that pixel's camera hit: with VPL rays, and with VPL maps, whether the
    /// pass makes its own shading points or is given the direct-light pass's.
    #[test]
    fn the_pass_equals_vpls_at_bit_for_bit() {
        let mut scene = crate::scene::load("cornell").unwrap();
        (scene.settings.width, scene.settings.height) = (40, 30);
        for indirect in [Indirect::Rays, Indirect::Maps] {
            let mut o = Options::hybrid();
            o.indirect = indirect;
            o.indirect_opts.vpl.paths = 12;
            o.indirect_opts.map.resolution = 64;
            let r = Renderer::new(&scene, o);
            let v = r.test_vpls();
            let (gbuffer, _) = r.visibility();
            let w = scene.settings.width as usize;
            let hit = |i: usize| {
                let h = gbuffer[i].as_ref().filter(|h| r.diffuse(h.tri))?;
                Some(SurfaceHit::new(&scene, h, r.camera_ray((i % w) as u32, (i / w) as u32).dir))
            };
            let expected: Vec<Vec3> = (0..gbuffer.len())
                .map(|i| hit(i).map_or(Vec3::ZERO, |s| v.at(&r, &s, &mut RayCounts::default())))
                .collect();
            assert!(expected.iter().filter(|e| **e != Vec3::ZERO).count() > 500, "{indirect:?}: lit pixels");
            let bits = |x: &[Vec3]| x.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            let mut out = vec![Vec3::ZERO; gbuffer.len()];
            run(&r, &v, &gbuffer, None, &mut out, &|| {});
            assert!(bits(&out) == bits(&expected), "{indirect:?}: the pass differs from Vpls::at");
            if indirect == Indirect::Maps {
                let points: Vec<ShadePoint> = (0..gbuffer.len())
                    .map(|i| hit(i).map_or_else(ShadePoint::default, |s| ShadePoint::of(&s)))
                    .collect();
                let mut shared = vec![Vec3::ZERO; gbuffer.len()];
                run(&r, &v, &gbuffer, Some(&points), &mut shared, &|| {});
                assert!(
                    bits(&shared) == bits(&expected),
                    "the pass with shared points differs from Vpls::at"
                );
            }
        }
    }

    /// The batched gather of mirror hits gives what one hit at a time gives, to the bit, with
    /// and without interleaving.
    #[test]
    fn batched_points_match_one_at_a_time() {
        let mut scene = crate::scene::load("cornell").unwrap();
        (scene.settings.width, scene.settings.height) = (48, 36);
        let mut o = Options::hybrid();
        o.indirect = Indirect::Maps;
        o.indirect_opts.map.resolution = 64;
        let r = Renderer::new(&scene, o);
        let v = r.test_vpls();
        assert!(v.batched(&r) && v.vpls.len() > 10);
        let (gbuffer, _) = r.visibility();
        let w = scene.settings.width as usize;
        let hits: Vec<SurfaceHit> = gbuffer
            .iter()
            .enumerate()
            .filter_map(|(i, h)| {
                Some(SurfaceHit::new(&scene, h.as_ref()?, r.camera_ray((i % w) as u32, (i / w) as u32).dir))
            })
            .collect();
        for stride in [1, 4] {
            let subsets: Vec<usize> = (0..hits.len()).map(|j| j % stride).collect();
            let batch = v.at_subsets(&r, &hits, &subsets, stride);
            let mut counts = RayCounts::default();
            let one: Vec<Vec3> =
                hits.iter().zip(&subsets).map(|(s, &q)| v.at_subset(&r, s, q, stride, &mut counts)).collect();
            assert!(
                batch
                    .iter()
                    .zip(&one)
                    .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits))
            );
            assert!(one.iter().filter(|v| **v != Vec3::ZERO).count() > hits.len() / 2);
        }
    }

    /// The shading points the direct-light pass makes (the reference's `direct`, the hybrid's
    /// `classify`) give the indirect pass the bytes it gets making them itself.
    #[test]
    fn shading_points_from_the_direct_pass_change_nothing() {
        let mut scene = crate::scene::load("cornell").unwrap();
        (scene.settings.width, scene.settings.height) = (48, 36);
        for hybrid in [false, true] {
            let mut o = if hybrid { Options::hybrid() } else { Options::reference() };
            o.indirect = Indirect::Maps;
            o.indirect_opts.map.resolution = 64;
            let r = Renderer::new(&scene, o);
            let v = r.test_vpls();
            let (gbuffer, _) = r.visibility();
            let n = gbuffer.len();
            let (mut direct, mut points) = (vec![Vec3::ZERO; n], vec![ShadePoint::default(); n]);
            if hybrid {
                r.test_shadowing(&gbuffer, &mut direct, Some(&mut points), false);
            } else {
                crate::render::direct::run(&r, &gbuffer, &mut direct, Some(&mut points), &|| {});
            }
            assert!(points.iter().filter(|p| p.ns != Vec3::ZERO).count() > n / 2);
            let (mut a, mut b) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            run(&r, &v, &gbuffer, Some(&points), &mut a, &|| {});
            run(&r, &v, &gbuffer, None, &mut b, &|| {});
            let bits = |x: &[Vec3]| x.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b), "hybrid: {hybrid}");
            assert!(a.iter().filter(|p| **p != Vec3::ZERO).count() > n / 2);
        }
    }
}
