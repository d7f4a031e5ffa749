//! The AVX2 and AVX-512 kernels: one body, generic over the vector operations of each
//! instruction set ([`Lanes`]), so that the two compute the same operations in the same order
//! as [`super::pair`] by construction.

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
