//! Vector kernels of the z-buffer (x86-64, chosen at run time): AVX2 and AVX-512.
//!
//! They compute exactly what the scalar kernels ([`ZBuffer::draw_scalar`], and the scalar
//! resolve of [`ZBuffer`]) compute:
//!
//! * coverage from the same exact integer edge values (sign tests);
//! * the depth with the same `f64` operations in the same order as [`SetupTri::depth`] (IEEE
//!   operations are correctly rounded whatever the vector width; no fused multiply-add), the same
//!   rounding to `f32` and the same clamp ([`crate::setup::clamp_depth`], written as the `max` /
//!   `min` instructions compute it);
//! * the same comparisons: closer or not, and for `TIE` the same `f32` window test as
//!   [`crate::zbuf::in_tie_window`]; the rare ties (equal depths, or within the window) are decided
//!   by [`wins`] itself;
//! * the barycentrics of the winners with [`SetupTri::bary`]'s `f64` operations, in its order
//!   ([`resolve_avx2`], [`resolve_avx512`], 8 pixels at a time).
//!
//! The traversal ([`draw_all`]) covers the same pixels as [`crate::edge::cover_rect`]; only
//! speed depends on how:
//!
//! * a triangle whose edge functions fit `i32` over its rectangle in the tile (any triangle
//!   spanning less than 64 pixels, and most larger ones: [`QuadEdges`]) is tested 4 x 2 pixels
//!   at a time, in the 8 lanes of one vector ([`draw_quads`]): a single test for most triangles
//!   of detailed meshes, and for larger ones, per pair of rows, only the quads that the rows'
//!   spans may reach ([`QuadEdges::spans`]);
//! * other triangles ([`draw`]) are tested on rows of 8 pixels with `i64` edge functions: after
//!   a test of the whole tile rectangle (every pixel of a tile inside a large triangle is
//!   covered: no per-pixel coverage tests), in 8x8 blocks with whole-block rejection and
//!   acceptance, their edge values stepped from block to block.
//!
//! It is written once, generic over the [`Lanes`] of a tier (AVX2, or AVX-512 with its 8-lane
//! `f64` vectors and mask registers), whose methods are inlined into the `#[target_feature]`
//! entry points ([`draw_all_avx2`], [`draw_all_avx512`]).

use std::arch::x86_64::*;

use hyrt_simd::lanes::{Avx2, Avx512x8, Lanes as Base};

use crate::EMPTY_ID;
use crate::edge::{BLOCK, EdgeFns, low_bits};
use crate::setup::{HALF_PIXEL, SUBPIXEL_ONE, SetupTri};
use crate::zbuf::{NONE, Rows, ZBuffer, clip_to_tile, wins};

/// `[f(0), f(1), f(2)]`. Written out rather than with `array::map` or `from_fn`, which are not
/// always inlined, and then cannot inline vector code into their bodies (no target features).
#[inline(always)]
fn each<T>(mut f: impl FnMut(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

/// What the depth test and the resolve need of a tier beyond its [`Base`] operations on 8 lanes
/// of `f32`: 8 lanes of `i64` (edge values) and of `f64` (depths and barycentrics before their
/// rounding to `f32`), which AVX2 holds in two vectors of 4 and AVX-512 in one, and masked
/// stores.
///
/// # Safety
/// As [`Base`]'s: every method may be called only where the CPU runs the tier, here from the
/// tier's `#[target_feature]` entry points ([`draw_all_avx2`], [`draw_all_avx512`],
/// [`resolve_avx2`], [`resolve_avx512`]), into which the methods are inlined. That is the safety argument of the `unsafe` blocks of the generic
/// kernel, which only its entry points call.
#[allow(clippy::missing_safety_doc)] // One contract for all, stated above.
trait Lanes: Base<F = __m256, I = __m256i> {
    /// 8 `i64`.
    type L: Copy;
    /// 8 `f64`.
    type D: Copy;

    unsafe fn splat_i64(x: i64) -> Self::L;
    /// `[0, s, 2 s, .., 7 s]`.
    unsafe fn ramp_i64(s: i64) -> Self::L;
    unsafe fn add_i64(a: Self::L, b: Self::L) -> Self::L;
    /// Bit `j` set iff lane `j` of each of `r` is `>= 0`.
    unsafe fn inside(r: &[Self::L; 3]) -> u32;
    /// `n as f64` per lane, for edge values of covered samples (`n >= 0`). Unless `wide`, no
    /// lane that matters reaches `2^51` (see [`Triangle::wide`]).
    unsafe fn i64_to_f64(n: Self::L, wide: bool) -> Self::D;
    /// `n as f64` per lane (exact).
    unsafe fn i32_to_f64(n: __m256i) -> Self::D;
    unsafe fn splat_f64(x: f64) -> Self::D;
    unsafe fn add_f64(a: Self::D, b: Self::D) -> Self::D;
    unsafe fn mul_f64(a: Self::D, b: Self::D) -> Self::D;
    /// `d as f32` per lane.
    unsafe fn to_f32(d: Self::D) -> __m256;
    /// Lane `j` set iff bit `j` of `bits` is.
    unsafe fn mask(bits: u32) -> Self::M;
    /// `a` where `m`, `b` elsewhere.
    unsafe fn select_i(m: Self::M, a: __m256i, b: __m256i) -> __m256i;
    /// Writes the lanes `m` of `new` to `p`, which holds `old`.
    unsafe fn store_where(p: &mut [f32; 8], m: Self::M, new: __m256, old: __m256);
    /// Writes the lanes `m` of `new` to `p`.
    unsafe fn store_i_where(p: &mut [u32; 8], m: Self::M, new: __m256i);
    /// `a == b` per lane.
    unsafe fn eq_i(a: __m256i, b: __m256i) -> Self::M;
    /// `d.x (p.y - a.y) - d.y (p.x - a.x)` from [`edge_terms`]: [`EdgeFns::at_pixel`], exact
    /// (each product of two `i32` is exact in `i64`, and the edge function is below `2^60`).
    unsafe fn edge(t: [__m256i; 4]) -> Self::L;
    /// Whether [`Lanes::i64_to_f64`] must be told `wide` for the edge values `e` of the `live`
    /// lanes (`>= 0`: covered samples): some reaches `2^51`.
    unsafe fn needs_wide(e: &[Self::L; 3], live: Self::M) -> bool;
    /// `p as f64` per lane.
    unsafe fn f32_to_f64(p: __m256) -> Self::D;
    /// `(num / den) as f32` in the `live` lanes where `!(den <= 0)` (those [`SetupTri::bary`]
    /// divides in), `+0` elsewhere.
    unsafe fn quotient(num: Self::D, den: Self::D, live: Self::M) -> __m256;
    /// The first `id.len() <= 8` lanes of `v` to `id`.
    unsafe fn store_ids(id: &mut [u32], v: __m256i);
    /// The pairs `[b1[j], b2[j]]` of the first `bary.len() <= 8` lanes to `bary`.
    unsafe fn store_pairs(bary: &mut [[f32; 2]], b1: __m256, b2: __m256);
}

// Each method is one intrinsic or a few; the trait's contract (the tier) is what makes them
// sound, so per-call `unsafe` blocks would add nothing. The work on halves is done by
// `#[inline(always)]` functions rather than closures: a closure is not always inlined, and
// compiled without the target features, its intrinsics become calls.
#[allow(unsafe_op_in_unsafe_fn)]
impl Lanes for Avx2 {
    type L = [__m256i; 2];
    type D = [__m256d; 2];

    #[inline(always)]
    unsafe fn splat_i64(x: i64) -> Self::L {
        [_mm256_set1_epi64x(x); 2]
    }
    #[inline(always)]
    unsafe fn ramp_i64(s: i64) -> Self::L {
        [_mm256_setr_epi64x(0, s, 2 * s, 3 * s), _mm256_setr_epi64x(4 * s, 5 * s, 6 * s, 7 * s)]
    }
    #[inline(always)]
    unsafe fn add_i64(a: Self::L, b: Self::L) -> Self::L {
        [_mm256_add_epi64(a[0], b[0]), _mm256_add_epi64(a[1], b[1])]
    }
    #[inline(always)]
    unsafe fn inside(r: &[Self::L; 3]) -> u32 {
        let lo = _mm256_or_si256(_mm256_or_si256(r[0][0], r[1][0]), r[2][0]);
        let hi = _mm256_or_si256(_mm256_or_si256(r[0][1], r[1][1]), r[2][1]);
        // Sign bits of the ORs: set iff some edge value of the lane is negative.
        let outside =
            _mm256_movemask_pd(_mm256_castsi256_pd(lo)) | _mm256_movemask_pd(_mm256_castsi256_pd(hi)) << 4;
        !(outside as u32) & 0xff
    }
    #[inline(always)]
    unsafe fn i64_to_f64(n: Self::L, wide: bool) -> Self::D {
        if wide {
            [to_f64_exact_avx2(n[0]), to_f64_exact_avx2(n[1])]
        } else {
            [to_f64_avx2(n[0]), to_f64_avx2(n[1])]
        }
    }
    #[inline(always)]
    unsafe fn i32_to_f64(n: __m256i) -> Self::D {
        [_mm256_cvtepi32_pd(_mm256_castsi256_si128(n)), _mm256_cvtepi32_pd(_mm256_extracti128_si256::<1>(n))]
    }
    #[inline(always)]
    unsafe fn splat_f64(x: f64) -> Self::D {
        [_mm256_set1_pd(x); 2]
    }
    #[inline(always)]
    unsafe fn add_f64(a: Self::D, b: Self::D) -> Self::D {
        [_mm256_add_pd(a[0], b[0]), _mm256_add_pd(a[1], b[1])]
    }
    #[inline(always)]
    unsafe fn mul_f64(a: Self::D, b: Self::D) -> Self::D {
        [_mm256_mul_pd(a[0], b[0]), _mm256_mul_pd(a[1], b[1])]
    }
    #[inline(always)]
    unsafe fn to_f32(d: Self::D) -> __m256 {
        _mm256_set_m128(_mm256_cvtpd_ps(d[1]), _mm256_cvtpd_ps(d[0]))
    }
    #[inline(always)]
    unsafe fn mask(bits: u32) -> __m256 {
        _mm256_castsi256_ps(lanes_avx2(bits))
    }
    #[inline(always)]
    unsafe fn select_i(m: __m256, a: __m256i, b: __m256i) -> __m256i {
        _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b), _mm256_castsi256_ps(a), m))
    }
    #[inline(always)]
    unsafe fn store_where(p: &mut [f32; 8], m: __m256, new: __m256, old: __m256) {
        _mm256_storeu_ps(p.as_mut_ptr(), _mm256_blendv_ps(old, new, m));
    }
    #[inline(always)]
    unsafe fn store_i_where(p: &mut [u32; 8], m: __m256, new: __m256i) {
        let old = _mm256_loadu_si256(p.as_ptr().cast());
        _mm256_storeu_si256(p.as_mut_ptr().cast(), Self::select_i(m, new, old));
    }
    #[inline(always)]
    unsafe fn eq_i(a: __m256i, b: __m256i) -> __m256 {
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(a, b))
    }
    #[inline(always)]
    unsafe fn edge(t: [__m256i; 4]) -> Self::L {
        [edge_half::<0>(t), edge_half::<1>(t)]
    }
    #[inline(always)]
    unsafe fn needs_wide(e: &[Self::L; 3], live: __m256) -> bool {
        // `to_f64_avx2` is exact iff no bit from 51 on is set (the values are `>= 0`).
        let live = [half_epi64::<0>(_mm256_castps_si256(live)), half_epi64::<1>(_mm256_castps_si256(live))];
        let lo = _mm256_and_si256(_mm256_or_si256(_mm256_or_si256(e[0][0], e[1][0]), e[2][0]), live[0]);
        let hi = _mm256_and_si256(_mm256_or_si256(_mm256_or_si256(e[0][1], e[1][1]), e[2][1]), live[1]);
        _mm256_testz_si256(_mm256_or_si256(lo, hi), _mm256_set1_epi64x(!((1 << 51) - 1))) == 0
    }
    #[inline(always)]
    unsafe fn f32_to_f64(p: __m256) -> Self::D {
        [_mm256_cvtps_pd(_mm256_castps256_ps128(p)), _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(p))]
    }
    #[inline(always)]
    unsafe fn quotient(num: Self::D, den: Self::D, live: __m256) -> __m256 {
        let live = _mm256_castps_si256(live);
        let lo = quotient_half(num[0], den[0], half_epi64::<0>(live));
        let hi = quotient_half(num[1], den[1], half_epi64::<1>(live));
        Self::to_f32([lo, hi])
    }
    #[inline(always)]
    unsafe fn store_ids(id: &mut [u32], v: __m256i) {
        let mut all = [0u32; 8];
        _mm256_storeu_si256(all.as_mut_ptr().cast(), v);
        id.copy_from_slice(&all[..id.len()]);
    }
    #[inline(always)]
    unsafe fn store_pairs(bary: &mut [[f32; 2]], b1: __m256, b2: __m256) {
        // Within each 128-bit half: pairs 0, 1 (and 4, 5) in `lo`, 2, 3 (and 6, 7) in `hi`.
        let (lo, hi) = (_mm256_unpacklo_ps(b1, b2), _mm256_unpackhi_ps(b1, b2));
        let mut pairs = [[0.0f32; 2]; 8];
        _mm256_storeu_ps(pairs.as_mut_ptr().cast(), _mm256_permute2f128_ps::<0x20>(lo, hi));
        _mm256_storeu_ps(pairs[4..].as_mut_ptr().cast(), _mm256_permute2f128_ps::<0x31>(lo, hi));
        bary.copy_from_slice(&pairs[..bary.len()]);
    }
}

/// Lanes 0-3 (`H = 0`) or 4-7 (`H = 1`) of 8 `i32`, sign-extended to `i64`.
#[inline(always)]
fn half_epi64<const H: i32>(r: __m256i) -> __m256i {
    // SAFETY: only called from AVX2 code (see `Lanes`).
    unsafe { _mm256_cvtepi32_epi64(_mm256_extracti128_si256::<H>(r)) }
}

/// [`Lanes::edge`] for lanes `4 H..4 H + 4`.
#[inline(always)]
fn edge_half<const H: i32>(t: [__m256i; 4]) -> __m256i {
    // SAFETY: only called from AVX2 code (see `Lanes`).
    unsafe {
        let [dx, dy, ry, rx] =
            [half_epi64::<H>(t[0]), half_epi64::<H>(t[1]), half_epi64::<H>(t[2]), half_epi64::<H>(t[3])];
        _mm256_sub_epi64(_mm256_mul_epi32(dx, ry), _mm256_mul_epi32(dy, rx))
    }
}

/// [`Lanes::quotient`] on 4 lanes, `live` a mask of `i64` lanes.
#[inline(always)]
fn quotient_half(num: __m256d, den: __m256d, live: __m256i) -> __m256d {
    // SAFETY: only called from AVX2 code (see `Lanes`).
    unsafe {
        let ok =
            _mm256_and_pd(_mm256_cmp_pd::<_CMP_NLE_UQ>(den, _mm256_setzero_pd()), _mm256_castsi256_pd(live));
        _mm256_and_pd(_mm256_div_pd(num, den), ok)
    }
}

/// On AVX-512, the `i64 -> f64` conversion is a single instruction rounding like `as f64`, so
/// every triangle can take it.
#[allow(unsafe_op_in_unsafe_fn)]
impl Lanes for Avx512x8 {
    type L = __m512i;
    type D = __m512d;

    #[inline(always)]
    unsafe fn splat_i64(x: i64) -> __m512i {
        _mm512_set1_epi64(x)
    }
    #[inline(always)]
    unsafe fn ramp_i64(s: i64) -> __m512i {
        // Exact: |7 s| < 2^40 (module docs of `setup`).
        _mm512_mullo_epi64(_mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7), _mm512_set1_epi64(s))
    }
    #[inline(always)]
    unsafe fn add_i64(a: __m512i, b: __m512i) -> __m512i {
        _mm512_add_epi64(a, b)
    }
    #[inline(always)]
    unsafe fn inside(r: &[__m512i; 3]) -> u32 {
        // 0xfe: a | b | c. Its sign bit is set iff some edge value is negative.
        let any = _mm512_ternarylogic_epi64::<0xfe>(r[0], r[1], r[2]);
        u32::from(!_mm512_movepi64_mask(any))
    }
    #[inline(always)]
    unsafe fn i64_to_f64(n: __m512i, _wide: bool) -> __m512d {
        _mm512_cvtepi64_pd(n)
    }
    #[inline(always)]
    unsafe fn i32_to_f64(n: __m256i) -> __m512d {
        _mm512_cvtepi32_pd(n)
    }
    #[inline(always)]
    unsafe fn splat_f64(x: f64) -> __m512d {
        _mm512_set1_pd(x)
    }
    #[inline(always)]
    unsafe fn add_f64(a: __m512d, b: __m512d) -> __m512d {
        _mm512_add_pd(a, b)
    }
    #[inline(always)]
    unsafe fn mul_f64(a: __m512d, b: __m512d) -> __m512d {
        _mm512_mul_pd(a, b)
    }
    #[inline(always)]
    unsafe fn to_f32(d: __m512d) -> __m256 {
        _mm512_cvtpd_ps(d)
    }
    #[inline(always)]
    unsafe fn mask(bits: u32) -> __mmask8 {
        bits as __mmask8
    }
    #[inline(always)]
    unsafe fn select_i(m: __mmask8, a: __m256i, b: __m256i) -> __m256i {
        _mm256_mask_blend_epi32(m, b, a)
    }
    #[inline(always)]
    unsafe fn store_where(p: &mut [f32; 8], m: __mmask8, new: __m256, _old: __m256) {
        _mm256_mask_storeu_ps(p.as_mut_ptr(), m, new);
    }
    #[inline(always)]
    unsafe fn store_i_where(p: &mut [u32; 8], m: __mmask8, new: __m256i) {
        _mm256_mask_storeu_epi32(p.as_mut_ptr().cast(), m, new);
    }
    #[inline(always)]
    unsafe fn eq_i(a: __m256i, b: __m256i) -> __mmask8 {
        _mm256_cmpeq_epi32_mask(a, b)
    }
    #[inline(always)]
    unsafe fn edge(t: [__m256i; 4]) -> __m512i {
        let wide = |r| _mm512_cvtepi32_epi64(r);
        let [dx, dy, ry, rx] = [wide(t[0]), wide(t[1]), wide(t[2]), wide(t[3])];
        _mm512_sub_epi64(_mm512_mul_epi32(dx, ry), _mm512_mul_epi32(dy, rx))
    }
    #[inline(always)]
    unsafe fn needs_wide(_e: &[__m512i; 3], _live: __mmask8) -> bool {
        false
    }
    #[inline(always)]
    unsafe fn f32_to_f64(p: __m256) -> __m512d {
        _mm512_cvtps_pd(p)
    }
    #[inline(always)]
    unsafe fn quotient(num: __m512d, den: __m512d, live: __mmask8) -> __m256 {
        let ok = _mm512_mask_cmp_pd_mask::<_CMP_NLE_UQ>(live, den, _mm512_setzero_pd());
        _mm512_cvtpd_ps(_mm512_maskz_div_pd(ok, num, den))
    }
    #[inline(always)]
    unsafe fn store_ids(id: &mut [u32], v: __m256i) {
        _mm256_mask_storeu_epi32(id.as_mut_ptr().cast(), low_bits(id.len() as u32) as u8, v);
    }
    #[inline(always)]
    unsafe fn store_pairs(bary: &mut [[f32; 2]], b1: __m256, b2: __m256) {
        let pairs = _mm512_permutex2var_ps(
            _mm512_castps256_ps512(b1),
            _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23),
            _mm512_castps256_ps512(b2),
        );
        _mm512_mask_storeu_ps(bary.as_mut_ptr().cast(), low_bits(2 * bary.len() as u32) as u16, pairs);
    }
}

/// The per-triangle constants of the depth test, in every lane.
struct Depth<'t, T: Lanes> {
    tri: &'t SetupTri,
    idx: __m256i,
    z0: T::D,
    dz: [T::D; 2],
    /// The clamp range and the tie window.
    lo: __m256,
    hi: __m256,
    tie: __m256,
}

impl<'t, T: Lanes> Depth<'t, T> {
    #[inline(always)]
    fn new(tri: &'t SetupTri, idx: u32, tie: f32) -> Self {
        let (dz, [lo, hi]) = (tri.dz(), tri.range());
        // SAFETY: see `Lanes`.
        unsafe {
            Self {
                tri,
                idx: _mm256_set1_epi32(idx as i32),
                z0: T::splat_f64(tri.z0()),
                dz: [T::splat_f64(dz[0]), T::splat_f64(dz[1])],
                lo: _mm256_set1_ps(lo),
                hi: _mm256_set1_ps(hi),
                tie: _mm256_set1_ps(tie),
            }
        }
    }

    /// Depth of 8 pixels from their unbiased `e1`, `e2` (as `f64`): `(z0 + e1 dz0) + e2 dz1` as
    /// [`SetupTri::depth`], rounded to `f32` and clamped. Lanes of uncovered pixels may hold
    /// garbage; they are masked out by the caller.
    #[inline(always)]
    fn depth(&self, e1: T::D, e2: T::D) -> __m256 {
        // SAFETY: see `Lanes`.
        unsafe {
            let d = T::add_f64(T::add_f64(self.z0, T::mul_f64(e1, self.dz[0])), T::mul_f64(e2, self.dz[1]));
            clamp::<T>(T::to_f32(d), self.lo, self.hi)
        }
    }

    /// The `covered` lanes where the fragment, of depths `d`, replaces the z-buffer entries
    /// `cur` (lane `j`: the pixel at tile index `index(j)`).
    #[inline(always)]
    fn update<const REVERSED: bool, const TIE: bool>(
        &self,
        zb: &ZBuffer,
        d: __m256,
        cur: __m256,
        covered: T::M,
        index: impl Fn(usize) -> usize,
    ) -> T::M {
        // SAFETY: see `Lanes`; the store writes an array.
        unsafe {
            let closer = T::and(if REVERSED { T::gt(d, cur) } else { T::lt(d, cur) }, covered);
            // Lanes decided by the id: equal depths, or with `TIE` depths in the window (which
            // the depth comparison then must not decide).
            let tied = if TIE { tie_window::<T, REVERSED>(d, cur, self.tie) } else { T::eq(d, cur) };
            let ties = T::and(tied, covered);
            let mut update = if TIE { T::and_not(closer, ties) } else { closer };
            let ties = T::bits(ties);
            if ties != 0 {
                let mut d_arr = [0.0f32; 8];
                _mm256_storeu_ps(d_arr.as_mut_ptr(), d);
                let won = tie_winners::<REVERSED, TIE>(zb, index, self.tri, &d_arr, ties);
                update = T::or(update, T::mask(won));
            }
            update
        }
    }
}

/// Depth-tests the 4 x 2 pixels of `zb` at tile indices `k..k + 4` (lanes 0-3) and
/// `k + w..k + w + 4` (lanes 4-7, `w` the tile width) whose bits are set in `covered`, given
/// their unbiased `e1`, `e2` as 8 lanes of `i32`.
#[inline(always)]
fn test_quad<'t, T: Lanes, const REVERSED: bool, const TIE: bool>(
    c: &Depth<'t, T>,
    zb: &mut ZBuffer<'t>,
    k: usize,
    covered: u32,
    e1: __m256i,
    e2: __m256i,
) {
    let w = zb.w;
    // SAFETY: see `Lanes`; the loads and stores access the 4 elements of `quad_of` slices.
    unsafe {
        let d = c.depth(T::i32_to_f64(e1), T::i32_to_f64(e2));
        let load = |buf: &mut [f32], k: usize| _mm_loadu_ps(quad_of(buf, k).as_ptr());
        let cur = _mm256_set_m128(load(&mut zb.depth, k + w), load(&mut zb.depth, k));
        let update = c.update::<REVERSED, TIE>(zb, d, cur, T::mask(covered), |j| quad_index(k, w, j));
        // Blended and stored whole rather than with masked stores: the next small triangle
        // often reads these entries again, and a masked store cannot forward its data to a
        // load (measured faster on small triangles).
        let new = T::select(update, d, cur);
        _mm_storeu_ps(quad_of(&mut zb.depth, k).as_mut_ptr(), _mm256_castps256_ps128(new));
        _mm_storeu_ps(quad_of(&mut zb.depth, k + w).as_mut_ptr(), _mm256_extractf128_ps::<1>(new));
        let load = |buf: &mut [u32], k: usize| _mm_loadu_si128(quad_of(buf, k).as_ptr().cast());
        let old = _mm256_set_m128i(load(&mut zb.win, k + w), load(&mut zb.win, k));
        let new = T::select_i(update, c.idx, old);
        _mm_storeu_si128(quad_of(&mut zb.win, k).as_mut_ptr().cast(), _mm256_castsi256_si128(new));
        _mm_storeu_si128(quad_of(&mut zb.win, k + w).as_mut_ptr().cast(), _mm256_extracti128_si256::<1>(new));
    }
}

/// The constants of a triangle for rows of 8 pixels with `i64` edge functions ([`draw`]).
struct Triangle<'t, T: Lanes> {
    depth: Depth<'t, T>,
    /// `[0, s, .., 7 s]` for each edge's x step `s`.
    off: [T::L; 3],
    /// Each edge's y step and fill-rule bias, in every lane.
    sy: [T::L; 3],
    bias: [T::L; 3],
    /// Whether edge values may reach `2^51`, which AVX2 converts to `f64` with
    /// [`to_f64_exact_avx2`]: covered samples have `0 <= e_i <= area` ([`EdgeFns::area`]), so
    /// only triangles with `area >= 2^51` (hundreds of thousands of pixels across: guard-band
    /// triangles) do; [`to_f64_avx2`] is exact for the others.
    wide: bool,
}

impl<'t, T: Lanes> Triangle<'t, T> {
    #[inline(always)]
    fn new(tri: &'t SetupTri, idx: u32, ef: &EdgeFns, tie: f32) -> Self {
        // SAFETY: see `Lanes`.
        unsafe {
            Self {
                depth: Depth::new(tri, idx, tie),
                off: each(|i| T::ramp_i64(ef.sx[i])),
                sy: each(|i| T::splat_i64(ef.sy[i])),
                bias: each(|i| T::splat_i64(ef.bias[i])),
                wide: ef.area >= 1 << 51,
            }
        }
    }

    /// `e + j sx_i` for `j = 0..8`: edge `i` along a row, from its value `e` at the first pixel.
    #[inline(always)]
    fn row(&self, i: usize, e: i64) -> T::L {
        // SAFETY: see `Lanes`.
        unsafe { T::add_i64(T::splat_i64(e), self.off[i]) }
    }

    /// The row below: `+ sy_i`.
    #[inline(always)]
    fn down(&self, i: usize, r: T::L) -> T::L {
        // SAFETY: see `Lanes`.
        unsafe { T::add_i64(r, self.sy[i]) }
    }

    /// `+ bias_i`: biased edge values to unbiased ones.
    #[inline(always)]
    fn unbias(&self, i: usize, r: T::L) -> T::L {
        // SAFETY: see `Lanes`.
        unsafe { T::add_i64(r, self.bias[i]) }
    }

    /// Bit `j` set iff lane `j` of the three biased rows is inside (all `>= 0`).
    #[inline(always)]
    fn inside(&self, r: &[T::L; 3]) -> u32 {
        // SAFETY: see `Lanes`.
        unsafe { T::inside(r) }
    }

    /// Depth-tests the 8 pixels of `zb` from index `k` on whose bits are set in `covered`, given
    /// their unbiased `e1`, `e2`.
    #[inline(always)]
    fn test_row<const REVERSED: bool, const TIE: bool>(
        &self,
        zb: &mut ZBuffer<'t>,
        k: usize,
        covered: u32,
        e1: T::L,
        e2: T::L,
    ) {
        let c = &self.depth;
        // SAFETY: see `Lanes`; the loads and stores access the 8 elements of `row_of` slices.
        unsafe {
            // One branch, and each conversion compiled for its case.
            let (e1, e2) = if self.wide {
                (T::i64_to_f64(e1, true), T::i64_to_f64(e2, true))
            } else {
                (T::i64_to_f64(e1, false), T::i64_to_f64(e2, false))
            };
            let d = c.depth(e1, e2);
            let cur = _mm256_loadu_ps(row_of(&mut zb.depth, k).as_ptr());
            let update = c.update::<REVERSED, TIE>(zb, d, cur, T::mask(covered), |j| k + j);
            T::store_where(row_of(&mut zb.depth, k), update, d, cur);
            T::store_i_where(row_of(&mut zb.win, k), update, c.idx);
        }
    }
}

/// 8 entries of a tile buffer from `k` on. Bounds-checked: the buffers have `PAD` spare entries
/// after the last pixel, so every pixel of the tile can start a row.
#[inline(always)]
fn row_of<T>(buf: &mut [T], k: usize) -> &mut [T; 8] {
    (&mut buf[k..k + 8]).try_into().unwrap()
}

/// The lanes of `ties` whose fragment beats the z-buffer entry although its depth is equal (or,
/// for `TIE`, within the tie window): [`wins`] per lane (rare: coplanar or intersecting surfaces,
/// or depth 0 against an empty reversed-Z pixel).
/// Lane `j` is the pixel of tile index `index(j)`.
#[inline(always)]
fn tie_winners<const REVERSED: bool, const TIE: bool>(
    zb: &ZBuffer,
    index: impl Fn(usize) -> usize,
    tri: &SetupTri,
    d: &[f32; 8],
    ties: u32,
) -> u32 {
    let mut won = 0;
    let mut t = ties;
    while t != 0 {
        let j = t.trailing_zeros() as usize;
        let k = index(j);
        let wins = wins::<REVERSED, TIE>(d[j], tri, zb.depth[k], zb.win[k], &zb.tris, zb.tie);
        // Every lane here is a tie (`ties`): against a fragment already there, its loser is
        // the pixel's rival.
        if zb.track && zb.win[k] != NONE {
            zb.rival[k].set(if wins { zb.tris[zb.win[k] as usize].id } else { tri.id });
        }
        if wins {
            won |= 1 << j;
        }
        t &= t - 1;
    }
    won
}

/// Depth-tests every triangle of the tile.
#[inline(always)]
fn draw_all<'t, T: Lanes, const REVERSED: bool, const TIE: bool>(zb: &mut ZBuffer<'t>) {
    for idx in 0..zb.tris.len() as u32 {
        if let Some(&next) = zb.tris.get(idx as usize + 6) {
            // Triangles are read from memory written by setup long before: prefetching the (up
            // to 3) cache lines of a coming one hides the latency, for the depth test and for the
            // resolve, which reads the perspective constants of the winners.
            let p: *const i8 = (next as *const SetupTri).cast();
            // SAFETY: prefetching has no effect on memory; SSE is part of x86-64.
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(p);
                _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64));
                _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(size_of::<SetupTri>() - 1));
            }
        }
        let tri = zb.tris[idx as usize];
        let rect = clip_to_tile(zb.rect, tri.bbox);
        if let Some(edges) = QuadEdges::new(tri, rect) {
            draw_quads::<T, REVERSED, TIE>(zb, idx, rect, &edges);
            continue;
        }
        draw::<T, REVERSED, TIE>(zb, idx, &EdgeFns::new(tri));
    }
}

/// Width of the pixel rectangles of [`draw_quads`]: 4 columns by 2 rows fill the 8 lanes.
const QUAD_W: u32 = 4;

/// Fixed-point extent below which a triangle's edge functions fit `i32` over the lanes of
/// [`draw_quads`] (see [`QuadEdges::new`]): `2^14` units, 64 pixels.
const QUAD_SPAN: i32 = 1 << 14;

/// The edge functions of a small triangle (all vertices within [`QUAD_SPAN`] of each other in x
/// and in y) as `i32`, from the centre of the first pixel of its rectangle: unbiased values, x
/// and y steps, fill-rule biases (as [`EdgeFns`], which they equal).
struct QuadEdges {
    e: [i32; 3],
    sx: [i32; 3],
    sy: [i32; 3],
    bias: [i32; 3],
}

impl QuadEdges {
    /// The edge functions of `tri` at the first pixel of `rect` (its pixel rectangle within the
    /// tile, as [`clip_to_tile`] gives it), or `None` if the rectangle is empty or the triangle
    /// is not small (see [`QuadEdges::fit`] for the others).
    ///
    /// Bounds: the vertices are within `S = QUAD_SPAN` of each other, so every edge vector has
    /// `|d| < S`, and the centre `p` of a pixel of `rect` lies within the vertices' bounding box
    /// ([`crate::setup`]'s pixel bounds are the samples inside it), so `|p - a| < S` for every
    /// vertex `a`. The lanes of [`draw_quads`] and the rows of [`QuadEdges::spans`] reach at most
    /// 3 pixels right and 7 rows below pixels of `rect` (`7 * 256` units): `|E| = |d.x (p.y -
    /// a.y) - d.y (p.x - a.x)| < 2 S (S + 7 * 256) < 2^30`, and a step `|4 * 256 d| < 2^24`: all
    /// exact in `i32`.
    #[inline(always)]
    fn new(tri: &SetupTri, rect: [u32; 4]) -> Option<Self> {
        let [v0, v1, v2] = tri.v;
        let span = |c: usize| v0[c].max(v1[c]).max(v2[c]) - v0[c].min(v1[c]).min(v2[c]);
        if span(0) >= QUAD_SPAN || span(1) >= QUAD_SPAN || rect[0] >= rect[2] || rect[1] >= rect[3] {
            return None;
        }
        // Below 2^24 + 2^7: pixel coordinates are below MAX_TARGET_DIM = 2^16.
        let centre = |p: u32| p as i32 * SUBPIXEL_ONE as i32 + HALF_PIXEL as i32;
        let (px, py) = (centre(rect[0]), centre(rect[1]));
        let one = SUBPIXEL_ONE as i32;
        let mut edges = Self { e: [0; 3], sx: [0; 3], sy: [0; 3], bias: [0; 3] };
        for (i, (a, b)) in [(v1, v2), (v2, v0), (v0, v1)].into_iter().enumerate() {
            // As `Edge::new`, `Edge::at_pixel`, `Edge::step_x`, `Edge::step_y`.
            let d = [b[0] - a[0], b[1] - a[1]];
            edges.e[i] = d[0] * (py - a[1]) - d[1] * (px - a[0]);
            edges.sx[i] = -d[1] * one;
            edges.sy[i] = d[0] * one;
            edges.bias[i] = i32::from(!(d[1] < 0 || (d[1] == 0 && d[0] > 0)));
        }
        Some(edges)
    }

    /// The edge functions `ef` (with unbiased values `e` at the first pixel of `rect`) as `i32`,
    /// if every value [`draw_quads`] and [`QuadEdges::spans`] compute from them fits: those at
    /// offsets up to `w + 3` pixels right and `h + 7` rows below the first (`w x h` the size of
    /// `rect`) are within `±2^30` (the extremes of an affine function over a rectangle are at
    /// its corners), hence also the steps and the values of a quad or 8 rows between them, and
    /// the biases (0 or 1) change nothing. Most triangles too large for [`QuadEdges::new`] are
    /// still small at the scale of a tile.
    #[inline(always)]
    fn fit(ef: &EdgeFns, e: [i64; 3], rect: [u32; 4]) -> Option<Self> {
        const LIMIT: i64 = 1 << 30;
        let (dx, dy) = (i64::from(rect[2] - rect[0] + 3), i64::from(rect[3] - rect[1] + 7));
        let mut edges = Self { e: [0; 3], sx: [0; 3], sy: [0; 3], bias: [0; 3] };
        for (i, &e) in e.iter().enumerate() {
            let (ox, oy) = (ef.sx[i] * dx, ef.sy[i] * dy);
            let hi = e + ox.max(0) + oy.max(0);
            let lo = e + ox.min(0) + oy.min(0);
            if lo <= -LIMIT || hi >= LIMIT {
                return None;
            }
            // In range: `|sx| <= |ox|`, `|sy| <= |oy|`, and those are within `hi - lo`.
            edges.e[i] = e as i32;
            edges.sx[i] = ef.sx[i] as i32;
            edges.sy[i] = ef.sy[i] as i32;
            edges.bias[i] = ef.bias[i] as i32;
        }
        Some(edges)
    }

    /// Biased values of edge `i` over the 4 x 2 pixels from the first: lane `j` is column
    /// `j % 4` of row `j / 4`. AVX2 must be available.
    #[inline(always)]
    unsafe fn lanes(&self, i: usize) -> __m256i {
        // SAFETY: AVX2 is available (the caller's contract).
        unsafe {
            let (jx, jy) =
                (_mm256_setr_epi32(0, 1, 2, 3, 0, 1, 2, 3), _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1));
            let e = _mm256_set1_epi32(self.e[i] - self.bias[i]);
            let dx = _mm256_mullo_epi32(jx, _mm256_set1_epi32(self.sx[i]));
            _mm256_add_epi32(e, _mm256_add_epi32(dx, _mm256_mullo_epi32(jy, _mm256_set1_epi32(self.sy[i]))))
        }
    }

    /// Change of edge `i` for two rows down, in every lane. AVX2 must be available.
    #[inline(always)]
    unsafe fn step(&self, i: usize) -> __m256i {
        // SAFETY: AVX2 is available (the caller's contract).
        unsafe { _mm256_set1_epi32(2 * self.sy[i]) }
    }

    /// Change of edge `i` for one quad (4 pixels) right, in every lane. AVX2 must be available.
    #[inline(always)]
    unsafe fn right(&self, i: usize) -> __m256i {
        // SAFETY: AVX2 is available (the caller's contract).
        unsafe { _mm256_set1_epi32(QUAD_W as i32 * self.sx[i]) }
    }

    /// The spans of the 4 pairs of rows from row `row` of the rectangle (`width x height`
    /// pixels, its first pixel the one of [`QuadEdges::new`]): `[lo, hi]` with `lo[p] <= d <=
    /// hi[p]` for every column offset `d` of a pixel of the pair (rows `row + 2 p`, `row + 2 p +
    /// 1`) that the triangle covers, within `[0, width - 1]`; `lo[p] > hi[p]` when there is none
    /// (or the pair is outside the rectangle). AVX2 must be available.
    ///
    /// With the biased value `b` of an edge at the row's first pixel and its x step `s`, a
    /// pixel at offset `d` is inside the edge iff `b + d s >= 0`: `d >= -b / s` for `s > 0`,
    /// `d <= -b / s` for `s < 0`, and `b >= 0` for `s = 0`. The bounds are computed in `f32`
    /// for 8 rows at once (`b` exact in `i32`, see [`QuadEdges::new`] and [`QuadEdges::fit`]),
    /// then rounded outwards (`floor` of the lower, `ceil` of the upper): the few roundings
    /// (each of relative size `2^-24`) move a bound that lies within the rectangle (`|-b / s| <
    /// 2^16`) by far less than a pixel, and a bound beyond it is clamped to it. They only limit
    /// which quads are tested: the coverage is the exact integer test of each lane.
    #[inline(always)]
    unsafe fn spans(&self, row: u32, width: u32, height: u32) -> [[i32; 4]; 2] {
        /// Stands for "no bound": beyond any offset, exact in `f32` and `i32`.
        const FAR: f32 = (1 << 30) as f32;
        // SAFETY: AVX2 is available (the caller's contract); the stores write arrays.
        unsafe {
            let rows =
                _mm256_add_epi32(_mm256_set1_epi32(row as i32), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
            let mut lo = _mm256_setzero_ps();
            let mut hi = _mm256_set1_ps((width - 1) as f32);
            // Rows beyond the rectangle are empty.
            let mut empty = _mm256_cmpgt_epi32(rows, _mm256_set1_epi32(height as i32 - 1));
            for i in 0..3 {
                let (s, b0) = (self.sx[i], self.e[i] - self.bias[i]);
                let b = _mm256_add_epi32(
                    _mm256_set1_epi32(b0),
                    _mm256_mullo_epi32(rows, _mm256_set1_epi32(self.sy[i])),
                );
                if s == 0 {
                    empty = _mm256_or_si256(empty, _mm256_cmpgt_epi32(_mm256_setzero_si256(), b));
                    continue;
                }
                let t = _mm256_mul_ps(_mm256_cvtepi32_ps(b), _mm256_set1_ps(-1.0 / s as f32));
                if s > 0 {
                    lo = _mm256_max_ps(lo, _mm256_floor_ps(t));
                } else {
                    hi = _mm256_min_ps(hi, _mm256_ceil_ps(t));
                }
            }
            // `min(lo, FAR)`: within `i32`; an empty row has `lo > hi`.
            let empty = _mm256_castsi256_ps(empty);
            lo = _mm256_blendv_ps(_mm256_min_ps(lo, _mm256_set1_ps(FAR)), _mm256_set1_ps(FAR), empty);
            hi = _mm256_blendv_ps(_mm256_max_ps(hi, _mm256_set1_ps(-FAR)), _mm256_set1_ps(-FAR), empty);
            // The union of the two rows of each pair.
            let even = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
            let odd = _mm256_setr_epi32(1, 3, 5, 7, 1, 3, 5, 7);
            let lo = _mm_min_ps(
                _mm256_castps256_ps128(_mm256_permutevar8x32_ps(lo, even)),
                _mm256_castps256_ps128(_mm256_permutevar8x32_ps(lo, odd)),
            );
            let hi = _mm_max_ps(
                _mm256_castps256_ps128(_mm256_permutevar8x32_ps(hi, even)),
                _mm256_castps256_ps128(_mm256_permutevar8x32_ps(hi, odd)),
            );
            // Integers within `[-FAR, FAR]`: the conversions are exact.
            let mut spans = [[0i32; 4]; 2];
            _mm_storeu_si128(spans[0].as_mut_ptr().cast(), _mm_cvtps_epi32(lo));
            _mm_storeu_si128(spans[1].as_mut_ptr().cast(), _mm_cvtps_epi32(hi));
            spans
        }
    }
}

/// Depth-tests the pixels of the tile rectangle `rect` covered by small triangle `idx` of the
/// tile list, whose edge functions are `edges`: 2 rows at a time, 4 pixels each, in the 8 lanes
/// of one vector, with `i32` edge functions. Most triangles of detailed meshes cover a few
/// pixels, many of the rest are slivers a pixel or two wide: per pair of rows, only the 4-pixel
/// quads from the first to the last pixel that the pair's span may reach ([`QuadEdges::spans`])
/// are tested.
#[inline(always)]
fn draw_quads<'t, T: Lanes, const REVERSED: bool, const TIE: bool>(
    zb: &mut ZBuffer<'t>,
    idx: u32,
    [x0, y0, x1, y1]: [u32; 4],
    edges: &QuadEdges,
) {
    let tri = zb.tris[idx as usize];
    // Only run inside the `#[target_feature]` entry points (see `Lanes`), both with AVX2.
    let c = Depth::<T>::new(tri, idx, zb.tie);
    let w = zb.w;
    let (width, height) = (x1 - x0, y1 - y0);
    let k0 = (y0 - zb.rect[1]) as usize * w + (x0 - zb.rect[0]) as usize;
    // SAFETY: AVX2 is available (see `c`).
    unsafe {
        // Biased values at the first quad of each pair of rows: inside iff all three are `>= 0`.
        let mut e = [edges.lanes(0), edges.lanes(1), edges.lanes(2)];
        let down = [edges.step(0), edges.step(1), edges.step(2)];
        let right = [edges.right(0), edges.right(1), edges.right(2)];
        let bias = [_mm256_set1_epi32(edges.bias[1]), _mm256_set1_epi32(edges.bias[2])];
        if width <= QUAD_W && height <= 2 {
            // A single quad: most triangles of detailed meshes.
            let columns = low_bits(width) * 0x11;
            let rows = if height == 2 { 0xff } else { 0x0f };
            let outside = _mm256_or_si256(_mm256_or_si256(e[0], e[1]), e[2]);
            let mask = !(_mm256_movemask_ps(_mm256_castsi256_ps(outside)) as u32) & rows & columns;
            if mask != 0 {
                let (e1, e2) = (_mm256_add_epi32(e[1], bias[0]), _mm256_add_epi32(e[2], bias[1]));
                test_quad::<T, REVERSED, TIE>(&c, zb, k0, mask, e1, e2);
            }
            return;
        }
        let mut row = 0;
        while row < height {
            // One quad per pair of rows is all a narrow rectangle has.
            let [lo, hi] = if width <= QUAD_W { [[0; 4], [0; 4]] } else { edges.spans(row, width, height) };
            for p in 0..4 {
                let y = row + 2 * p as u32;
                if y >= height {
                    break;
                }
                // Lanes 4-7 are the second row of the pair, if the rectangle has it.
                let rows = if y + 1 < height { 0xff } else { 0x0f };
                let (mut d, mut ev) = (lo[p], e);
                if d <= hi[p] {
                    for (ev, sx) in ev.iter_mut().zip(edges.sx) {
                        *ev = _mm256_add_epi32(*ev, _mm256_set1_epi32(d * sx));
                    }
                }
                while d <= hi[p] {
                    // Lanes `j` and `j + 4` are column `d + j`: those in the rectangle.
                    let columns = low_bits((width - d as u32).min(QUAD_W)) * 0x11;
                    let outside = _mm256_or_si256(_mm256_or_si256(ev[0], ev[1]), ev[2]);
                    let mask = !(_mm256_movemask_ps(_mm256_castsi256_ps(outside)) as u32) & rows & columns;
                    // Tested even when no lane is covered (the blend then stores the z-buffer's
                    // own values): the quads of a span are nearly all covered, and a branch on
                    // the mask, mispredicted at the ends of every span, cost more (measured on
                    // slivers, such as the conference room's chairs).
                    let (e1, e2) = (_mm256_add_epi32(ev[1], bias[0]), _mm256_add_epi32(ev[2], bias[1]));
                    let k = k0 + y as usize * w + d as usize;
                    test_quad::<T, REVERSED, TIE>(&c, zb, k, mask, e1, e2);
                    for i in 0..3 {
                        ev[i] = _mm256_add_epi32(ev[i], right[i]);
                    }
                    d += QUAD_W as i32;
                }
                for i in 0..3 {
                    e[i] = _mm256_add_epi32(e[i], down[i]);
                }
            }
            row += 8;
        }
    }
}

/// Depth-tests `rows` rows of `n <= 8` pixels from tile index `k`, from the edge values `e` at
/// their first pixel: with `COVERED`, every pixel is covered and `e` is unbiased; otherwise `e`
/// is biased, and coverage is tested per pixel.
#[inline(always)]
fn test_block<'t, T: Lanes, const REVERSED: bool, const TIE: bool, const COVERED: bool>(
    zb: &mut ZBuffer<'t>,
    c: &Triangle<'t, T>,
    mut k: usize,
    n: u32,
    rows: u32,
    e: [i64; 3],
) {
    if COVERED {
        let covered = low_bits(n);
        let (mut e1, mut e2) = (c.row(1, e[1]), c.row(2, e[2]));
        for _ in 0..rows {
            c.test_row::<REVERSED, TIE>(zb, k, covered, e1, e2);
            e1 = c.down(1, e1);
            e2 = c.down(2, e2);
            k += zb.w;
        }
        return;
    }
    let mut ev = each(|i| c.row(i, e[i]));
    for _ in 0..rows {
        let mask = c.inside(&ev) & low_bits(n);
        if mask != 0 {
            c.test_row::<REVERSED, TIE>(zb, k, mask, c.unbias(1, ev[1]), c.unbias(2, ev[2]));
        }
        ev = each(|i| c.down(i, ev[i]));
        k += zb.w;
    }
}

/// Depth-tests the pixels of the tile covered by triangle `idx` of the tile list.
#[inline(always)]
fn draw<'t, T: Lanes, const REVERSED: bool, const TIE: bool>(zb: &mut ZBuffer<'t>, idx: u32, ef: &EdgeFns) {
    let tri = zb.tris[idx as usize];
    let [tx0, ty0, ..] = zb.rect;
    let [x0, y0, x1, y1] = clip_to_tile(zb.rect, tri.bbox);
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let c = Triangle::<T>::new(tri, idx, ef, zb.tie);
    let (sx, sy, bias) = (ef.sx, ef.sy, ef.bias);
    let w = zb.w;
    let index = |x: u32, y: u32| (y - ty0) as usize * w + (x - tx0) as usize;

    // Biased edge values at the rectangle's first pixel, and their extremes over its pixels.
    let e = ef.at_pixel(x0, y0);
    let e: [i64; 3] = each(|i| e[i] - bias[i]);
    let (dx, dy) = (i64::from(x1 - x0 - 1), i64::from(y1 - y0 - 1));
    let max: [i64; 3] = each(|i| e[i] + (sx[i] * dx).max(0) + (sy[i] * dy).max(0));
    let min: [i64; 3] = each(|i| e[i] + (sx[i] * dx).min(0) + (sy[i] * dy).min(0));
    if max.iter().any(|&m| m < 0) {
        return;
    }
    if min.iter().all(|&m| m >= 0) {
        // Every pixel of the rectangle is covered: rows of 8 without coverage tests.
        let mut x = x0;
        while x < x1 {
            let d = i64::from(x - x0);
            let e = each(|i| e[i] + bias[i] + sx[i] * d);
            test_block::<T, REVERSED, TIE, true>(zb, &c, index(x, y0), (x1 - x).min(BLOCK), y1 - y0, e);
            x += BLOCK;
        }
        return;
    }
    if let Some(edges) = QuadEdges::fit(ef, each(|i| e[i] + bias[i]), [x0, y0, x1, y1]) {
        draw_quads::<T, REVERSED, TIE>(zb, idx, [x0, y0, x1, y1], &edges);
        return;
    }
    if x1 - x0 <= BLOCK && y1 - y0 <= BLOCK {
        test_block::<T, REVERSED, TIE, false>(zb, &c, index(x0, y0), x1 - x0, y1 - y0, e);
        return;
    }

    // 8x8 blocks aligned to the pixel grid, as in `cover_rect`.
    let span = i64::from(BLOCK - 1);
    let max_off: [i64; 3] = each(|i| (sx[i] * span).max(0) + (sy[i] * span).max(0));
    let min_off: [i64; 3] = each(|i| (sx[i] * span).min(0) + (sy[i] * span).min(0));
    let block_sx: [i64; 3] = each(|i| sx[i] * i64::from(BLOCK));
    let (bx0, mut by) = (x0 - x0 % BLOCK, y0 - y0 % BLOCK);
    while by < y1 {
        // Biased values at the top-left pixel of the row's first block, then of each block.
        let row = ef.at_pixel(bx0, by);
        let mut eb: [i64; 3] = each(|i| row[i] - bias[i]);
        let (py0, py1) = (by.max(y0), (by + BLOCK).min(y1));
        let dy = i64::from(py0 - by);
        let mut bx = bx0;
        while bx < x1 {
            if (0..3).all(|i| eb[i] + max_off[i] >= 0) {
                let accepted = (0..3).all(|i| eb[i] + min_off[i] >= 0);
                let (px0, px1) = (bx.max(x0), (bx + BLOCK).min(x1));
                let dx = i64::from(px0 - bx);
                let e: [i64; 3] = each(|i| eb[i] + sx[i] * dx + sy[i] * dy);
                let (k, n, rows) = (index(px0, py0), px1 - px0, py1 - py0);
                if accepted {
                    let e = each(|i| e[i] + bias[i]);
                    test_block::<T, REVERSED, TIE, true>(zb, &c, k, n, rows, e);
                } else {
                    test_block::<T, REVERSED, TIE, false>(zb, &c, k, n, rows, e);
                }
            }
            eb = each(|i| eb[i] + block_sx[i]);
            bx += BLOCK;
        }
        by += BLOCK;
    }
}

/// Depth-tests every triangle of the tile with the AVX2 kernel.
#[target_feature(enable = "avx2")]
pub(crate) fn draw_all_avx2<const REVERSED: bool, const TIE: bool>(zb: &mut ZBuffer) {
    draw_all::<Avx2, REVERSED, TIE>(zb);
}

/// Depth-tests every triangle of the tile with the AVX-512 kernel.
#[target_feature(enable = "avx2,avx512f,avx512dq,avx512vl")]
pub(crate) fn draw_all_avx512<const REVERSED: bool, const TIE: bool>(zb: &mut ZBuffer) {
    draw_all::<Avx512x8, REVERSED, TIE>(zb);
}

/// `2^52 + 2^51` as the bits of an `f64`: for an integer `|n| < 2^51`, the `f64` with bits
/// `MAGIC + n` is exactly `2^52 + 2^51 + n` (its unit in the last place is 1), so subtracting
/// `MAGIC_F` gives `n as f64` exactly. AVX2 has no `i64 -> f64` conversion.
const MAGIC: i64 = 0x4338_0000_0000_0000;
const MAGIC_F: f64 = 6_755_399_441_055_744.0;

/// `n as f64` for `|n| < 2^51`, per lane.
#[inline(always)]
fn to_f64_avx2(n: __m256i) -> __m256d {
    // SAFETY: only called from AVX2 code (see `Lanes`).
    unsafe {
        _mm256_sub_pd(
            _mm256_castsi256_pd(_mm256_add_epi64(n, _mm256_set1_epi64x(MAGIC))),
            _mm256_set1_pd(MAGIC_F),
        )
    }
}

/// `n as f64` for any `|n| < 2^63`, per lane: the high half `n >> 32` (a signed `i32`) times
/// `2^32` and the low half (an unsigned `u32`, through `2^52 + lo`) are exact in `f64`, and
/// their sum is rounded once, which is `as f64`'s rounding.
#[inline(always)]
fn to_f64_exact_avx2(n: __m256i) -> __m256d {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    // SAFETY: only called from AVX2 code (see `Lanes`).
    unsafe {
        let odd = _mm256_setr_epi32(1, 3, 5, 7, 1, 3, 5, 7);
        let hi = _mm256_cvtepi32_pd(_mm256_castsi256_si128(_mm256_permutevar8x32_epi32(n, odd)));
        let lo = _mm256_or_si256(
            _mm256_and_si256(n, _mm256_set1_epi64x(0xffff_ffff)),
            _mm256_castpd_si256(_mm256_set1_pd(TWO_52)),
        );
        let lo = _mm256_sub_pd(_mm256_castsi256_pd(lo), _mm256_set1_pd(TWO_52));
        _mm256_add_pd(_mm256_mul_pd(hi, _mm256_set1_pd(4_294_967_296.0)), lo)
    }
}

/// Lane `j` (of 8) all ones iff bit `j` of `mask` is set.
#[inline(always)]
fn lanes_avx2(mask: u32) -> __m256i {
    // SAFETY: only called from AVX2 code (see `Lanes`).
    unsafe {
        let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(mask as i32), bits), bits)
    }
}

/// Lane `j` set iff depths `d[j]` and `cur[j]` are a tie for the window `tie`:
/// [`crate::zbuf::in_tie_window`] with the same `f32` operations, as a lane mask.
///
/// An empty standard-depth entry (`cur = +inf`) is excluded (for any finite `d` the formula
/// gives `inf <= inf`): the fragment beats it either way (see [`wins`]), and as a tie it would
/// go through the scalar path for every first fragment of a pixel.
///
/// `max(|d|, |cur|)` is computed as `max(d, cur)`: both are `+inf`, in `[0, 1]` or `-0`
/// (fragment depths are clamped to their triangle's range within `[0, 1]`, whose ends can be
/// `-0`, and the empty depths are `+inf` and `0`), so the two differ only by the sign of a
/// zero maximum, which makes `limit` `-0` instead of `+0`, and `diff <= limit` is the same for
/// both (`diff >= 0`).
#[inline(always)]
fn tie_window<T: Lanes, const REVERSED: bool>(d: __m256, cur: __m256, tie: __m256) -> T::M {
    // SAFETY: see `Lanes`.
    unsafe {
        let diff = T::abs(T::sub(d, cur));
        let limit = T::mul(tie, T::max(d, cur));
        let in_window = T::le(diff, limit);
        if REVERSED { in_window } else { T::and(in_window, T::lt(cur, T::splat(f32::INFINITY))) }
    }
}

/// `clamp_depth` per lane: `min(max(d, lo), hi)` with `d` as the first operand of each, which
/// is [`crate::setup::clamp_depth`]'s comparisons exactly.
#[inline(always)]
fn clamp<T: Lanes>(d: __m256, lo: __m256, hi: __m256) -> __m256 {
    // SAFETY: see `Lanes`.
    unsafe { T::min(T::max(d, lo), hi) }
}

/// 4 entries of a tile buffer from `k` on (bounds-checked).
#[inline(always)]
fn quad_of<T>(buf: &mut [T], k: usize) -> &mut [T; 4] {
    (&mut buf[k..k + 4]).try_into().unwrap()
}

/// Tile index of lane `j` of a 4 x 2 quad from tile index `k` (see [`test_quad`]).
#[inline(always)]
fn quad_index(k: usize, w: usize, j: usize) -> usize {
    k + (j & 3) + (j >> 2) * w
}

/// Resolves the tile with the AVX2 kernel: [`ZBuffer::resolve`]'s depths, ids and
/// barycentrics, 8 pixels at a time ([`resolve_rows`]), emptying the z-buffer.
#[target_feature(enable = "avx2")]
pub(crate) fn resolve_avx2(zb: &mut ZBuffer, depth: Rows<f32>, id: Rows<u32>, bary: Rows<[f32; 2]>) {
    resolve_rows::<Avx2>(zb, depth, id, bary);
}

/// Resolves the tile with the AVX-512 kernel (see [`resolve_avx2`]).
#[target_feature(enable = "avx2,avx512f,avx512dq,avx512vl")]
pub(crate) fn resolve_avx512(zb: &mut ZBuffer, depth: Rows<f32>, id: Rows<u32>, bary: Rows<[f32; 2]>) {
    resolve_rows::<Avx512x8>(zb, depth, id, bary);
}

/// The resolve of [`resolve_avx2`] and [`resolve_avx512`]: for every run of 8 pixels of every
/// row of the tile (fewer at the end of a row), the ids and barycentrics of [`resolve8`], and
/// the depths; then the run's z-buffer entries are emptied. That is every entry of the tile's
/// rows, the spare row and the padding were never written (only rewritten with their values):
/// the z-buffer is [`ZBuffer::clean`] afterwards.
#[inline(always)]
fn resolve_rows<T: Lanes>(zb: &mut ZBuffer, depth: Rows<f32>, id: Rows<u32>, bary: Rows<[f32; 2]>) {
    let [tx0, ty0, ..] = zb.rect;
    let w = zb.w;
    // SAFETY: see `Lanes` (only called from `resolve_avx2` and `resolve_avx512`); the loads and
    // stores access 8 elements of `row_of` slices, or of a chunk of exactly 8.
    unsafe {
        let empty = (_mm256_set1_epi32(zb.empty_bits() as i32), _mm256_set1_epi32(NONE as i32));
        for (r, ((d_row, i_row), b_row)) in depth.into_iter().zip(id).zip(bary).enumerate() {
            let chunks = d_row.chunks_mut(BLOCK as usize).zip(i_row.chunks_mut(BLOCK as usize));
            for (c, ((d, i), b)) in chunks.zip(b_row.chunks_mut(BLOCK as usize)).enumerate() {
                let k = r * w + c * BLOCK as usize;
                let (x, y) = (tx0 + (c as u32) * BLOCK, ty0 + r as u32);
                resolve8::<T>(zb, k, x, y, i, b);
                let cur = _mm256_loadu_si256(row_of(&mut zb.depth, k).as_ptr().cast());
                if d.len() == BLOCK as usize {
                    _mm256_storeu_si256(d.as_mut_ptr().cast(), cur);
                    _mm256_storeu_si256(row_of(&mut zb.depth, k).as_mut_ptr().cast(), empty.0);
                    _mm256_storeu_si256(row_of(&mut zb.win, k).as_mut_ptr().cast(), empty.1);
                } else {
                    let n = d.len();
                    d.copy_from_slice(&zb.depth[k..k + n]);
                    let empty = f32::from_bits(zb.empty_bits());
                    zb.depth[k..k + n].fill(empty);
                    zb.win[k..k + n].fill(NONE);
                }
            }
        }
    }
    zb.clean = true;
}

/// Fixed-point x of the centres of the 8 pixels from `(x, y)` on, and y of row `y`, in every
/// lane (see [`crate::setup`]): below `2^24 + 2^11` for pixel coordinates below
/// `MAX_TARGET_DIM = 2^16`, so `i32`.
#[inline(always)]
fn centres(x: u32, y: u32) -> (__m256i, __m256i) {
    let c = |p: u32| (i64::from(p) * SUBPIXEL_ONE + HALF_PIXEL) as i32;
    let one = SUBPIXEL_ONE as i32;
    // SAFETY: only called from AVX2 or AVX-512 code (see `Lanes`).
    unsafe {
        let steps = _mm256_setr_epi32(0, one, 2 * one, 3 * one, 4 * one, 5 * one, 6 * one, 7 * one);
        (_mm256_add_epi32(_mm256_set1_epi32(c(x)), steps), _mm256_set1_epi32(c(y)))
    }
}

/// The vertices, ids and perspective constants of the winners of 8 pixels, one per lane (see
/// [`resolve8`]).
struct Winners {
    /// `[x0, y0, x1, y1, x2, y2]`, fixed point.
    v: [__m256i; 6],
    id: __m256i,
    /// `persp[i][c]` of [`SetupTri::persp`] at `3 i + c`.
    p: [__m256; 9],
}

/// Edge `a -> b` (the edge opposite vertex `i` is `(i + 1) % 3 -> (i + 2) % 3`, as in
/// [`EdgeFns::new`]) as its coordinate differences, `[d.x, d.y, p.y - a.y, p.x - a.x]` at the
/// pixel centres `(px, py)`, each lane in `i32` (below `2^29` in magnitude): the terms of
/// [`Lanes::edge`].
#[inline(always)]
fn edge_terms(v: &[__m256i; 6], a: usize, b: usize, px: __m256i, py: __m256i) -> [__m256i; 4] {
    // SAFETY: only called from AVX2 or AVX-512 code (see `Lanes`).
    unsafe {
        let (ax, ay) = (v[2 * a], v[2 * a + 1]);
        [
            _mm256_sub_epi32(v[2 * b], ax),
            _mm256_sub_epi32(v[2 * b + 1], ay),
            _mm256_sub_epi32(py, ay),
            _mm256_sub_epi32(px, ax),
        ]
    }
}

/// `(e0 q0 + e1 q1) + e2 q2`: a sum of [`SetupTri::bary`], in its order.
#[inline(always)]
fn dot<T: Lanes>(e: &[T::D; 3], q: [T::D; 3]) -> T::D {
    // SAFETY: see `Lanes`.
    unsafe { T::add_f64(T::add_f64(T::mul_f64(e[0], q[0]), T::mul_f64(e[1], q[1])), T::mul_f64(e[2], q[2])) }
}

/// The ids and barycentrics of [`ZBuffer::resolve`] for the `n = id.len() <= 8` pixels of a
/// row from tile index `k`, pixel `(x, y)`, on.
///
/// The pixels' winners are found by comparing the 8 entries of `zb.win` with each distinct
/// winner in turn (a few per run of 8 for small triangles, one for large ones), which blends its
/// vertices, id and perspective constants into the lanes it won. Then, per lane, the exact
/// integer edge functions at the pixel centre ([`edge_terms`]) and [`SetupTri::bary`]'s `f64`
/// operations, in its order.
#[inline(always)]
fn resolve8<T: Lanes>(zb: &ZBuffer, k: usize, x: u32, y: u32, id: &mut [u32], bary: &mut [[f32; 2]]) {
    let n = id.len();
    // SAFETY: see `Lanes` (only called from `resolve_rows`); the loads read the 8 elements of
    // `win[k..k + 8]` (bounds-checked), the stores the first `n` elements of `id` and `bary`.
    unsafe {
        let wins = _mm256_loadu_si256(zb.win[k..k + 8].as_ptr().cast());
        let live = T::and_not(T::mask(low_bits(n as u32)), T::eq_i(wins, T::splat_i(NONE as i32)));
        let mut w = Winners { v: [T::splat_i(0); 6], id: T::splat_i(EMPTY_ID as i32), p: [T::splat(0.0); 9] };
        let mut rem = T::bits(live);
        while rem != 0 {
            let win = zb.win[k + rem.trailing_zeros() as usize];
            // Lanes from `n` on may have the same winner: they are blended, but not stored.
            let m = T::eq_i(wins, T::splat_i(win as i32));
            rem &= !T::bits(m);
            let tri = zb.tris[win as usize];
            for f in 0..6 {
                w.v[f] = T::select_i(m, T::splat_i(tri.v[f / 2][f % 2]), w.v[f]);
            }
            w.id = T::select_i(m, T::splat_i(tri.id as i32), w.id);
            let persp = tri.persp();
            for f in 0..9 {
                w.p[f] = T::select(m, T::splat(persp[f / 3][f % 3]), w.p[f]);
            }
        }
        let (px, py) = centres(x, y);
        let e = [
            T::edge(edge_terms(&w.v, 1, 2, px, py)),
            T::edge(edge_terms(&w.v, 2, 0, px, py)),
            T::edge(edge_terms(&w.v, 0, 1, px, py)),
        ];
        let wide = T::needs_wide(&e, live);
        let e = [T::i64_to_f64(e[0], wide), T::i64_to_f64(e[1], wide), T::i64_to_f64(e[2], wide)];
        let mut q = [T::splat_f64(0.0); 9];
        for (q, p) in q.iter_mut().zip(w.p) {
            *q = T::f32_to_f64(p);
        }
        let den = dot::<T>(&e, [q[0], q[3], q[6]]);
        let b1 = T::quotient(dot::<T>(&e, [q[1], q[4], q[7]]), den, live);
        let b2 = T::quotient(dot::<T>(&e, [q[2], q[5], q[8]]), den, live);
        T::store_ids(id, w.id);
        T::store_pairs(bary, b1, b2);
    }
}
