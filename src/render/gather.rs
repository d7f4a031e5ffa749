//! The VPL gather: per diffuse point, `sum_v I_v cos_x cos_v / max(d^2, d_min^2)` over the VPLs
//! that the VPLs' maps ([`VplMap`], planes or 16-bit depths) call visible.
//!
//! It is the inner loop of indirect light (points times VPLs), so it is laid out for it: the
//! points in struct-of-arrays order ([`Points`]), one VPL's constants broadcast
//! ([`VplConsts`]), and sixteen points at a time with AVX-512, or eight with AVX2 and F16C,
//! where the CPU has them ([`Isa`]). The scalar [`pair`] performs the same `f32` operations
//! in the same order (no fused multiply-adds, IEEE square roots and divisions, exact
//! half-float conversions), so all give the same bytes; the tests hold them to it.
//!
//! Per pair, with `w = (p - o) / r` the unit direction from the VPL at `o` to the point `p`:
//! `cos_x = -n_s . w`, `cos_g = -n_g . w` (the geometric normal: the point must face the VPL),
//! `cos_v = a . w` (`a` the VPL's normal, its map's axis); the map decides visibility along
//! `w` as [`VplMap`]'s module docs derive. `1 / max(d^2, d_min^2)` and the rounding band's
//! `1 / cos_g` share one division.

use glam::Vec3;
use hyrt_shadowmap::vpl_map::VplMap;
use hyrt_simd::{Isa, Tier};

use super::{SurfaceHit, vpl::Vpl};

/// Points per vector of the AVX2 kernel.
pub(crate) const LANES: usize = 8;

/// A diffuse shading point as the gather reads it (all zero where a pixel has none: zero
/// normals face nothing). The frame's direct-light pass writes one per pixel when VPL maps
/// will be gathered, so that the indirect pass does not make the shading points again.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ShadePoint {
    pub p: Vec3,
    pub ns: Vec3,
    pub ng: Vec3,
    /// The diffuse albedo there ([`SurfaceHit::albedo`]), which the gathered sum multiplies.
    pub albedo: Vec3,
}

impl ShadePoint {
    pub fn of(s: &SurfaceHit) -> Self {
        Self { p: s.p, ns: s.ns, ng: s.ng, albedo: s.albedo }
    }
}

/// Diffuse shading points in struct-of-arrays order (zero normals: a point that faces
/// nothing).
#[derive(Clone, Debug, Default)]
pub(crate) struct Points {
    pub p: [Vec<f32>; 3],
    pub ns: [Vec<f32>; 3],
    pub ng: [Vec<f32>; 3],
}

impl Points {
    /// Empty, with room for `n` points.
    pub fn with_capacity(n: usize) -> Self {
        let v = || [Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n)];
        Self { p: v(), ns: v(), ng: v() }
    }

    /// Replaces the points with `pts`, in order (a transpose).
    pub fn set(&mut self, pts: &[ShadePoint]) {
        let [px, py, pz] = &mut self.p;
        let [sx, sy, sz] = &mut self.ns;
        let [gx, gy, gz] = &mut self.ng;
        for v in [&mut *px, py, pz, sx, sy, sz, gx, gy, gz] {
            v.clear();
            v.resize(pts.len(), 0.0);
        }
        for (i, s) in pts.iter().enumerate() {
            (px[i], py[i], pz[i]) = (s.p.x, s.p.y, s.p.z);
            (sx[i], sy[i], sz[i]) = (s.ns.x, s.ns.y, s.ns.z);
            (gx[i], gy[i], gz[i]) = (s.ng.x, s.ng.y, s.ng.z);
        }
    }

    pub fn push(&mut self, s: &ShadePoint) {
        self.push_raw(s.p, s.ns, s.ng);
    }

    fn push_raw(&mut self, p: Vec3, ns: Vec3, ng: Vec3) {
        for i in 0..3 {
            self.p[i].push(p[i]);
            self.ns[i].push(ns[i]);
            self.ng[i].push(ng[i]);
        }
    }

    pub fn len(&self) -> usize {
        self.p[0].len()
    }

    fn get(&self, i: usize) -> (Vec3, Vec3, Vec3) {
        let v = |a: &[Vec<f32>; 3]| Vec3::new(a[0][i], a[1][i], a[2][i]);
        (v(&self.p), v(&self.ns), v(&self.ng))
    }
}

/// Per-point sums of `I_v g_v` (RGB, struct of arrays).
#[derive(Clone, Debug, Default)]
pub(crate) struct Sums(pub [Vec<f32>; 3]);

impl Sums {
    pub fn reset(&mut self, n: usize) {
        for c in &mut self.0 {
            c.clear();
            c.resize(n, 0.0);
        }
    }

    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.0[0][i], self.0[1][i], self.0[2][i])
    }
}

/// What a pair needs of its VPL and the knobs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct VplConsts {
    pub o: Vec3,
    pub t: Vec3,
    pub b: Vec3,
    pub a: Vec3,
    pub intensity: Vec3,
    /// `d_min^2`.
    pub clamp2: f32,
    /// `bias * 2 / res`: the margin's texel footprints per unit of `(1 + cos_v) r`.
    pub bias_k: f32,
    /// The stored value's relative rounding ([`VplFormat::tolerance`]).
    pub tol: f32,
    /// The rounding band's `e` (`sqrt 3` times the per-axis point error).
    pub e: f32,
    pub half: f32,
    pub last: f32,
    pub res: u32,
    /// `1 / scale` of 16-bit depths (1 for planes; [`VplMap::depths`]).
    pub inv_scale: f32,
}

impl VplConsts {
    pub fn new(v: &Vpl, map: &VplMap, clamp2: f32, bias: f32, point_error: f32) -> Self {
        let [t, b, a] = map.frame();
        let res = map.resolution();
        Self {
            o: map.origin(),
            t,
            b,
            a,
            intensity: v.intensity,
            clamp2,
            bias_k: bias * 2.0 / res as f32,
            tol: map.format().tolerance(),
            e: point_error * 3f32.sqrt(),
            half: res as f32 * 0.5,
            last: map.last(),
            res,
            inv_scale: map.depths().map_or(1.0, |(_, inv_scale)| inv_scale),
        }
    }
}

/// What is shared by every texel a pair may look at.
struct Ray {
    w: Vec3,
    r: f32,
    cos_g: f32,
    ng: Vec3,
    /// Continuous texel coordinates of `w`.
    fx: f32,
    fy: f32,
    margin: f32,
    g: f32,
}

/// The pair's geometry, or `None` when the point or the VPL faces away.
#[inline(always)]
fn ray(c: &VplConsts, p: Vec3, ns: Vec3, ng: Vec3) -> Option<Ray> {
    let (dx, dy, dz) = (p.x - c.o.x, p.y - c.o.y, p.z - c.o.z);
    let d2 = dx * dx + dy * dy + dz * dz;
    let r = d2.sqrt();
    let inv = 1.0 / r;
    let w = Vec3::new(dx * inv, dy * inv, dz * inv);
    let cos_x = -(ns.x * w.x + ns.y * w.y + ns.z * w.z);
    let cos_g = -(ng.x * w.x + ng.y * w.y + ng.z * w.z);
    let cos_v = c.a.x * w.x + c.a.y * w.y + c.a.z * w.z;
    if !(cos_x > 0.0 && cos_g > 0.0 && cos_v > 0.0) {
        return None;
    }
    let m2 = d2.max(c.clamp2);
    let q = 1.0 / (cos_g * m2);
    let g = cos_x * cos_v * cos_g * q;
    let den = 1.0 + cos_v;
    let iden = 1.0 / den;
    let u = (c.t.x * w.x + c.t.y * w.y + c.t.z * w.z) * iden;
    let v = (c.b.x * w.x + c.b.y * w.y + c.b.z * w.z) * iden;
    let margin = c.bias_k * den * r + c.tol * r + (c.e + c.e * m2 * q);
    Some(Ray { w, r, cos_g, ng, fx: (u + 1.0) * c.half, fy: (1.0 - v) * c.half, margin, g })
}

/// Whether texel `(x, y)` hides the pair's point ([`VplMap::hidden_at`]).
#[inline(always)]
fn hidden(map: &VplMap, ray: &Ray, x: u32, y: u32) -> bool {
    map.hidden_at(x, y, ray.w, ray.r, ray.ng, ray.cos_g, ray.margin)
}

/// `g_v` times the visibility of one VPL from one point (0 when it faces away or is hidden):
/// the texel under the point decides. The scalar kernel, the reference for [`add_vpl`].
#[inline]
pub(crate) fn pair(c: &VplConsts, map: &VplMap, p: Vec3, ns: Vec3, ng: Vec3) -> f32 {
    let Some(ray) = ray(c, p, ns, ng) else { return 0.0 };
    let x = ray.fx.max(0.0).min(c.last) as u32;
    let y = ray.fy.max(0.0).min(c.last) as u32;
    if hidden(map, &ray, x, y) { 0.0 } else { ray.g }
}

/// [`pair`] with percentage-closer filtering: the visibility is the sum of the bilinear weights
/// of the 2x2 texels whose centres surround the point's position that leave it visible (the
/// footprint shifted inside the map at its border). Scalar only: measured, it buys no accuracy
/// for its cost (`docs/sweeps/`), and is kept as a knob to show that.
pub(crate) fn pair_bilinear(c: &VplConsts, map: &VplMap, p: Vec3, ns: Vec3, ng: Vec3) -> f32 {
    let Some(ray) = ray(c, p, ns, ng) else { return 0.0 };
    let hi = c.res.saturating_sub(2) as f32;
    let fx = (ray.fx - 0.5).clamp(0.0, hi);
    let fy = (ray.fy - 0.5).clamp(0.0, hi);
    let (x0, y0) = (fx as u32, fy as u32);
    let (ax, ay) = (fx - x0 as f32, fy - y0 as f32);
    let mut visible = 0.0;
    for (dx, dy, wt) in
        [(0, 0, (1.0 - ax) * (1.0 - ay)), (1, 0, ax * (1.0 - ay)), (0, 1, (1.0 - ax) * ay), (1, 1, ax * ay)]
    {
        if !hidden(map, &ray, (x0 + dx).min(c.res - 1), (y0 + dy).min(c.res - 1)) {
            visible += wt;
        }
    }
    ray.g * visible
}

/// Adds VPL `c`'s `I_v g_v` (visible pairs only) to `sums` for every point of `pts`, with the
/// widest kernel the CPU runs ([`Isa::best`]).
pub(crate) fn add_vpl(c: &VplConsts, map: &VplMap, pts: &Points, sums: &mut Sums) {
    add_vpl_on(Isa::best(), c, map, pts, sums);
}

/// [`add_vpl`] with the kernel of tier `isa` (8 pairs per AVX2 vector, 16 per AVX-512 one; all
/// give the same bits): whole vectors with it, the rest one point at a time.
pub(crate) fn add_vpl_on(isa: Isa, c: &VplConsts, map: &VplMap, pts: &Points, sums: &mut Sums) {
    #[allow(unused_mut)]
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    {
        use hyrt_simd::lanes::{Avx2, Avx512, Lanes};
        // The texels: the planes' `f32`, or the half floats of 16-bit depths.
        let texels = match (map.planes(), map.depths()) {
            (Some(g), _) => Some((g.as_ptr().cast(), g.len() * 3, false)),
            (_, Some((bits, _))) => Some((bits.as_ptr().cast::<f32>(), bits.len(), true)),
            _ => None,
        };
        if let Some((texels, len, depth16)) = texels {
            type Kernel = unsafe fn(&VplConsts, *const f32, usize, &Points, usize, &mut Sums);
            let kernel: Option<(usize, Kernel)> = match (isa.tier(), depth16) {
                (Tier::Avx512, false) => Some((Avx512::N, vector::add_vpl_avx512::<false>)),
                (Tier::Avx512, true) => Some((Avx512::N, vector::add_vpl_avx512::<true>)),
                (Tier::Avx2, false) => Some((Avx2::N, vector::add_vpl_avx2::<false>)),
                (Tier::Avx2, true) => Some((Avx2::N, vector::add_vpl_avx2::<true>)),
                _ => None,
            };
            if let Some((n, kernel)) = kernel {
                done = pts.len() / n * n;
                // SAFETY: an `Isa` of a tier exists only where the CPU runs it; the kernels'
                // loads stay within the first `done` points of `pts` and `sums` (asserted there)
                // and their gathers within the map's texels (indices clamped to the resolution;
                // see each kernel).
                unsafe { kernel(c, texels, len, pts, done, sums) }
            }
        }
    }
    add_vpl_from(pair, c, map, pts, done, sums);
}

/// A kernel of one pair: [`pair`] or [`pair_bilinear`].
pub(crate) type PairFn = fn(&VplConsts, &VplMap, Vec3, Vec3, Vec3) -> f32;

/// [`add_vpl`] one point at a time, with kernel `f`.
pub(crate) fn add_vpl_with(f: PairFn, c: &VplConsts, map: &VplMap, pts: &Points, sums: &mut Sums) {
    add_vpl_from(f, c, map, pts, 0, sums);
}

/// [`add_vpl_with`] from point `first` on.
fn add_vpl_from(f: PairFn, c: &VplConsts, map: &VplMap, pts: &Points, first: usize, sums: &mut Sums) {
    for i in first..pts.len() {
        let (p, ns, ng) = pts.get(i);
        let g = f(c, map, p, ns, ng);
        for k in 0..3 {
            sums.0[k][i] += c.intensity[k] * g;
        }
    }
}

/// The AVX2 and AVX-512 kernels: one body, generic over the vector operations of each
/// instruction set ([`Lanes`]), so that the two compute the same operations in the same order
/// as [`super::pair`] by construction.
#[cfg(target_arch = "x86_64")]
mod vector {
    use std::arch::x86_64::*;

    use super::{Points, Sums, VplConsts};

    use hyrt_simd::lanes::{Avx2, Avx512, Lanes as Base};

    /// The lane operations of the tier ([`Base`], shared with the tracer's kernels), and the
    /// one only this kernel needs.
    ///
    /// # Safety
    /// As [`Base`]: the methods may be called only where the CPU runs the tier, from the
    /// kernel's `#[target_feature]` entry points, into which they are inlined.
    pub(super) trait Lanes: Base {
        /// The half float `base[idx]` (a `u16` array; a 4-byte load there must be in bounds)
        /// as `f32` where `m`, `0.0` elsewhere.
        unsafe fn gather_half(base: *const u16, idx: Self::I, m: Self::M) -> Self::F;
    }

    impl Lanes for Avx2 {
        #[inline(always)]
        unsafe fn gather_half(base: *const u16, idx: __m256i, m: __m256) -> __m256 {
            // SAFETY: the caller provides AVX2 and F16C and indices within `base` for the
            // lanes of `m` (the trait method's contract).
            unsafe {
                let word = _mm256_mask_i32gather_epi32::<2>(
                    _mm256_setzero_si256(),
                    base.cast(),
                    idx,
                    _mm256_castps_si256(m),
                );
                let low = _mm256_and_si256(word, _mm256_set1_epi32(0xffff));
                let packed = _mm256_packus_epi32(low, _mm256_setzero_si256());
                _mm256_cvtph_ps(_mm256_castsi256_si128(_mm256_permute4x64_epi64::<0b1000>(packed)))
            }
        }
    }

    impl Lanes for Avx512 {
        #[inline(always)]
        unsafe fn gather_half(base: *const u16, idx: __m512i, m: __mmask16) -> __m512 {
            // SAFETY: the caller provides AVX-512 and indices within `base` for the lanes of
            // `m` (the trait method's contract).
            unsafe {
                let word = _mm512_mask_i32gather_epi32::<2>(_mm512_setzero_si512(), m, idx, base.cast());
                let halves = _mm512_cvtepi32_epi16(_mm512_and_si512(word, _mm512_set1_epi32(0xffff)));
                _mm512_cvtph_ps(halves)
            }
        }
    }

    /// [`add_vpl`] with AVX2 and F16C.
    ///
    /// # Safety
    /// As [`add_vpl`], on a CPU with AVX2 and F16C.
    #[target_feature(enable = "avx2,f16c")]
    pub(super) unsafe fn add_vpl_avx2<const DEPTH16: bool>(
        c: &VplConsts,
        texels: *const f32,
        len: usize,
        pts: &Points,
        n: usize,
        sums: &mut Sums,
    ) {
        // SAFETY: this function's contract (AVX2 and F16C present, `texels` holding `len`
        // values) is `add_vpl`'s.
        unsafe { add_vpl::<Avx2, DEPTH16>(c, texels, len, pts, n, sums) }
    }

    /// [`add_vpl`] with AVX-512 (the F instructions, and F16C, which every AVX-512 CPU has).
    ///
    /// # Safety
    /// As [`add_vpl`], on a CPU of the AVX-512 tier.
    #[target_feature(enable = "avx2,f16c,avx512f")]
    pub(super) unsafe fn add_vpl_avx512<const DEPTH16: bool>(
        c: &VplConsts,
        texels: *const f32,
        len: usize,
        pts: &Points,
        n: usize,
        sums: &mut Sums,
    ) {
        // SAFETY: this function's contract (AVX-512 present, `texels` holding `len` values)
        // is `add_vpl`'s.
        unsafe { add_vpl::<Avx512, DEPTH16>(c, texels, len, pts, n, sums) }
    }

    /// [`super::pair`] on `L::N` points at once for the first `n` points (a multiple of
    /// `L::N`), summed into `sums`: texels are planes (three `f32` each) or, with `DEPTH16`,
    /// half floats. The same `f32` operations as [`super::pair`], in its order.
    ///
    /// # Safety
    /// The CPU must run `L`'s instructions; `texels` must point to `len` elements: `3 res^2`
    /// `f32` for planes, or more than `res^2` `u16` for half floats (the padding element keeps
    /// a 4-byte load at the last texel in bounds).
    #[inline(always)]
    unsafe fn add_vpl<L: Lanes, const DEPTH16: bool>(
        c: &VplConsts,
        texels: *const f32,
        len: usize,
        pts: &Points,
        n: usize,
        sums: &mut Sums,
    ) {
        assert!(n.is_multiple_of(L::N) && n <= pts.len() && sums.0.iter().all(|s| s.len() >= n));
        let texels_n = c.res as usize * c.res as usize;
        assert!(if DEPTH16 { len > texels_n } else { len == 3 * texels_n });
        // SAFETY: (the whole body) the caller guarantees the instruction set; the loads and
        // stores stay within the first `n` points (asserted above), the gathers within the map
        // (see each).
        unsafe {
            let s = |x: f32| L::splat(x);
            let (ox, oy, oz) = (s(c.o.x), s(c.o.y), s(c.o.z));
            let (tx, ty, tz) = (s(c.t.x), s(c.t.y), s(c.t.z));
            let (bx, by, bz) = (s(c.b.x), s(c.b.y), s(c.b.z));
            let (ax, ay, az) = (s(c.a.x), s(c.a.y), s(c.a.z));
            let (ir, ig, ib) = (s(c.intensity.x), s(c.intensity.y), s(c.intensity.z));
            let (clamp2, bias_k, e, half, last) = (s(c.clamp2), s(c.bias_k), s(c.e), s(c.half), s(c.last));
            let (zero, one, tol) = (s(0.0), s(1.0), s(c.tol));
            let (inv_scale, inv2, halfpx) = (s(c.inv_scale), s(2.0 / c.res as f32), s(0.5));
            let res = L::splat_i(c.res as i32);
            let dot = |x: L::F, y: L::F, z: L::F, a: L::F, b: L::F, c: L::F| {
                L::add(L::add(L::mul(a, x), L::mul(b, y)), L::mul(c, z))
            };
            let [px, py, pz] = &pts.p;
            let [nsx, nsy, nsz] = &pts.ns;
            let [ngx, ngy, ngz] = &pts.ng;
            let [sr, sg, sb] = &mut sums.0;
            for i in (0..n).step_by(L::N) {
                let ld = |v: &[f32]| L::load(v.as_ptr().add(i));
                let dx = L::sub(ld(px), ox);
                let dy = L::sub(ld(py), oy);
                let dz = L::sub(ld(pz), oz);
                let d2 = L::add(L::add(L::mul(dx, dx), L::mul(dy, dy)), L::mul(dz, dz));
                let r = L::sqrt(d2);
                let inv = L::div(one, r);
                let (wx, wy, wz) = (L::mul(dx, inv), L::mul(dy, inv), L::mul(dz, inv));
                let (ngxv, ngyv, ngzv) = (ld(ngx), ld(ngy), ld(ngz));
                let cos_x = L::neg(dot(wx, wy, wz, ld(nsx), ld(nsy), ld(nsz)));
                let cos_g = L::neg(dot(wx, wy, wz, ngxv, ngyv, ngzv));
                let cos_v = dot(wx, wy, wz, ax, ay, az);
                let faces = L::and(L::and(L::gt(cos_x, zero), L::gt(cos_g, zero)), L::gt(cos_v, zero));
                if !L::any(faces) {
                    continue;
                }
                let m2 = L::max(d2, clamp2);
                let q = L::div(one, L::mul(cos_g, m2));
                let g = L::mul(L::mul(L::mul(cos_x, cos_v), cos_g), q);
                let den = L::add(one, cos_v);
                let iden = L::div(one, den);
                let u = L::mul(dot(wx, wy, wz, tx, ty, tz), iden);
                let v = L::mul(dot(wx, wy, wz, bx, by, bz), iden);
                let margin = L::add(
                    L::add(L::mul(L::mul(bias_k, den), r), L::mul(tol, r)),
                    L::add(e, L::mul(L::mul(e, m2), q)),
                );
                // `max(x, 0)` first, as `f32::max`: a NaN becomes 0 (the second operand).
                let fx = L::min(L::max(L::mul(L::add(u, one), half), zero), last);
                let fy = L::min(L::max(L::mul(L::sub(one, v), half), zero), last);
                let (ix, iy) = (L::trunc(fx), L::trunc(fy));
                let idx = L::add_i(L::mul_i(iy, res), ix);
                let hidden = if DEPTH16 {
                    // Facing lanes' indices are below `res^2`, and a 4-byte load at half float
                    // `idx` ends within the padded array; other lanes are masked off.
                    let sv = L::mul(L::gather_half(texels.cast(), idx, faces), inv_scale);
                    // As `VplMap::hidden_at`: no divisions.
                    let u = L::sub(L::mul(L::add(L::to_f(ix), halfpx), inv2), one);
                    let v = L::sub(one, L::mul(L::add(L::to_f(iy), halfpx), inv2));
                    let r2 = L::add(L::mul(u, u), L::mul(v, v));
                    let d = L::add(one, r2);
                    let nt = dot(tx, ty, tz, ngxv, ngyv, ngzv);
                    let nb = dot(bx, by, bz, ngxv, ngyv, ngzv);
                    let na = dot(ax, ay, az, ngxv, ngyv, ngzv);
                    let cc = L::neg(L::add(
                        L::add(L::mul(nt, L::add(u, u)), L::mul(nb, L::add(v, v))),
                        L::mul(na, L::sub(one, r2)),
                    ));
                    let near = L::gt(cc, L::mul(cos_g, d));
                    let own = L::gt(L::mul(sv, L::sub(L::mul(L::mul(r, cos_g), d), L::mul(margin, cc))), cc);
                    let point = L::gt(L::mul(sv, L::sub(r, margin)), one);
                    L::and(L::gt(sv, zero), L::or(L::and(own, near), L::and_not(point, near)))
                } else {
                    // Facing lanes' indices are below `res^2`, so every gathered float lies
                    // within the `3 res^2` of `texels`; other lanes are masked off and not read.
                    let idx3 = L::add_i(L::add_i(idx, idx), idx);
                    let gx = L::gather(texels, idx3, faces);
                    let gy = L::gather(texels.add(1), idx3, faces);
                    let gz = L::gather(texels.add(2), idx3, faces);
                    let sdot = dot(wx, wy, wz, gx, gy, gz);
                    L::and(L::gt(sdot, zero), L::gt(L::mul(sdot, L::sub(r, margin)), one))
                };
                let g = L::keep(L::and_not(faces, hidden), g);
                for (acc, int) in [(&mut *sr, ir), (&mut *sg, ig), (&mut *sb, ib)] {
                    let a = acc.as_mut_ptr().add(i);
                    L::store(a, L::add(L::load(a), L::mul(int, g)));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyrt_shadowmap::{MapOptions, classify::triangle_planes, vpl_map::VplFormat};

    const FORMATS: [VplFormat; 2] = [VplFormat::Planes, VplFormat::Depth16];

    /// A floor (`y = 0`, 4 units square) under a square lid (`y = 0.5`, half a unit square) and
    /// a VPL above both, facing down.
    fn scene(res: u32, format: VplFormat) -> (VplMap, VplConsts) {
        let quad = |y: f32, h: f32| {
            let (a, b, c, d) =
                (Vec3::new(-h, y, -h), Vec3::new(h, y, -h), Vec3::new(h, y, h), Vec3::new(-h, y, h));
            [[a, b, c], [a, c, d]]
        };
        let tris: Vec<[Vec3; 3]> = quad(0.0, 2.0).into_iter().chain(quad(0.5, 0.25)).collect();
        let planes = triangle_planes(&tris);
        let o = Vec3::new(0.0, 1.0, 0.0);
        let opts = MapOptions { resolution: res, ..MapOptions::default() };
        let map = VplMap::build(&tris, &planes, o, Vec3::NEG_Y, &opts, format);
        let v =
            Vpl { position: o, normal: Vec3::NEG_Y, intensity: Vec3::new(1.0, 2.0, 3.0), tri: 0, light: 0 };
        let c = VplConsts::new(&v, &map, 0.0, 0.5, 1e-7);
        (map, c)
    }

    /// Floor points in the lid's shadow (the square of half-width 0.5 under a lid of
    /// half-width 0.25 halfway up) are hidden, and the others lit, beyond a texel of the edge,
    /// with either format.
    #[test]
    fn the_lid_hides_what_it_covers() {
        for format in FORMATS {
            let (map, c) = scene(256, format);
            let (mut hidden, mut lit) = (0, 0);
            for i in 0..64 {
                for j in 0..64 {
                    let p = Vec3::new(
                        -1.5 + 3.0 * (i as f32 + 0.5) / 64.0,
                        0.0,
                        -1.5 + 3.0 * (j as f32 + 0.5) / 64.0,
                    );
                    let edge = p.x.abs().max(p.z.abs());
                    if (edge - 0.5).abs() < 0.03 {
                        continue;
                    }
                    let g = pair(&c, &map, p, Vec3::Y, Vec3::Y);
                    if edge < 0.5 {
                        assert_eq!(g, 0.0, "{format:?}: {p} is under the lid");
                        hidden += 1;
                    } else {
                        let d = Vec3::new(0.0, 1.0, 0.0) - p;
                        let want = (d.y / d.length()).powi(2) / d.length_squared();
                        assert!((g - want).abs() <= 1e-5 * want, "{format:?}: {p}: {g} vs {want}");
                        lit += 1;
                    }
                }
            }
            assert!(hidden > 200 && lit > 2000, "{hidden} {lit}");
        }
    }

    /// The vector kernel gives the scalar kernel's bytes, on points all over the scene with
    /// normals in every direction (facing the VPL or not, in front of the lid or behind it).
    #[test]
    fn vector_and_scalar_kernels_agree_bit_for_bit() {
        for format in FORMATS {
            let (map, c) = scene(64, format);
            let mut pts = Points::default();
            for i in 0..1001u32 {
                let f = i as f32;
                let p =
                    Vec3::new((f * 0.37).sin() * 1.8, (f * 0.11).cos() * 0.3 + 0.25, (f * 0.23).cos() * 1.8);
                let n = Vec3::new((f * 1.3).sin(), (f * 0.7).cos(), (f * 2.1).sin()).normalize_or(Vec3::Y);
                let ns = (n + Vec3::new(0.1, 0.0, -0.1)).normalize();
                pts.push_raw(p, ns, n);
            }
            let bits = |s: &Sums| s.0.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
            let mut b = Sums::default();
            b.reset(pts.len());
            for _ in 0..3 {
                add_vpl_with(pair, &c, &map, &pts, &mut b);
            }
            for k in Isa::for_tests("VPL gather kernels") {
                let mut a = Sums::default();
                a.reset(pts.len());
                for _ in 0..3 {
                    add_vpl_on(k, &c, &map, &pts, &mut a);
                }
                assert_eq!(bits(&a), bits(&b), "{format:?}, {k:?}");
            }
            let nonzero = (0..pts.len()).filter(|&i| b.get(i) != Vec3::ZERO).count();
            assert!(nonzero > 100 && nonzero < 900, "{format:?}: {nonzero}: the points must mix lit and not");
        }
    }
}
