//! Triangle setup of 8 triangles at a time (x86-64, AVX2 or AVX-512, chosen at run time):
//! bit for bit what [`setup_chunk`](crate::setup::setup_chunk) appends, triangle by triangle,
//! with [`setup_triangle`](crate::setup::setup_triangle).
//!
//! The input is read 8 consecutive triangles at a time, by component (one gather per vertex
//! coordinate: structure of arrays), and classified in `f32` lanes with the comparisons of
//! `classify` (rejected, inside, to clip); after a group that was entirely rejected, the next
//! is first tested whole in memory order ([`all_outside_one_plane`]), which spares the gathers
//! of the long runs of triangles out of view that large scenes have. The triangles inside the
//! viewport and the depth range, and those crossing its sides within the guard band
//! ([`within_guard_band`]), nearly all that are drawn, are then set up together: [`batch`] is
//! `setup_unclipped`
//! step by step, with every early return turned into a lane mask. Each step is the same IEEE
//! operation as the scalar code, in the same order (no fused multiply-add): vector instructions
//! round exactly like scalar ones. The comparisons are the ordered ones of Rust's operators
//! (false on NaN), `min` / `max` are written where the scalar code compares and selects in the
//! same way (`d < lo ? d : lo` is `vminpd(d, lo)`), and `f64::clamp` as its two selects (a
//! `max` would turn `-0` into `+0`). Integers take the `i32` lanes where the values fit (the
//! fixed-point coordinates, below `2^28` in magnitude for the lanes kept, and their
//! differences), `i64` for the area. A lane that the scalar code drops may compute anything
//! (NaN, wrapped integers): it is masked out. The triangles to clip take the scalar path in
//! their turn, so the output stays in input order.
//!
//! The 8 lanes are one register of 8 `f64` with AVX-512, two of 4 with AVX2 ([`Wide`]).

use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

use glam::Vec4;

use crate::EMPTY_ID;
use crate::clip::ClipScratch;
use crate::setup::{
    HALF_PIXEL, MAX_DEPTH_CORRECTION, MAX_FIXED, SUBPIXEL_BITS, SUBPIXEL_ONE, SetupContext, SetupTri,
    TINY_SPAN, setup_clipped,
};

/// Triangles per batch.
const LANES: usize = 8;

/// How many groups of [`LANES`] input triangles ahead setup prefetches.
const PREFETCH_GROUPS: usize = 6;

/// 8 lanes of `f64` and their comparison masks, and the few `i64` operations of the setup.
///
/// A value of an implementing type is only created inside its `#[target_feature]` entry point
/// ([`setup_chunk_avx2`], [`setup_chunk_avx512`]), i.e. after the CPU was found to support it
/// (both backends have AVX2): that is the safety argument of the `unsafe` blocks of the
/// implementations and of the `f32` / `i32` lane code ([`Group`], [`batch`]), which uses AVX2
/// intrinsics directly.
trait Wide: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> {
    /// A lane mask.
    type M: Copy + BitAnd<Output = Self::M> + BitOr<Output = Self::M> + Not<Output = Self::M>;

    fn splat(x: f64) -> Self;
    /// `f64::from` of 8 `f32`.
    fn from_ps(x: __m256) -> Self;
    /// `f64::from` of 8 `i32`.
    fn from_epi32(x: __m256i) -> Self;
    fn abs(self) -> Self;
    /// `self < b ? self : b` per lane (the x86 `min`).
    fn min(self, b: Self) -> Self;
    /// `self > b ? self : b` per lane (the x86 `max`).
    fn max(self, b: Self) -> Self;
    /// `self < b` (false if either is NaN), and so on.
    fn lt(self, b: Self) -> Self::M;
    fn le(self, b: Self) -> Self::M;
    fn gt(self, b: Self) -> Self::M;
    /// `m ? a : b` per lane.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    /// `as f32` per lane (round to nearest even).
    fn to_ps(self) -> __m256;
    /// The low 32 bits of each lane's bit pattern.
    fn low_dwords(self) -> __m256i;
    /// The lanes of an `i32` mask (all ones or zero per lane).
    fn mask_from_epi32(m: __m256i) -> Self::M;
    /// All ones in the `i32` lanes of `m`.
    fn mask_to_epi32(m: Self::M) -> __m256i;
    /// Bit `l` set iff lane `l` of `m` is.
    fn bits(m: Self::M) -> u32;
    /// `a = dx1 dy2 - dy1 dx2` per lane from `i32` operands, exactly (in `i64`), as the masks
    /// `[a == 0, a > 0, a < 0]` and `|a| as f64`.
    fn area(dx1: __m256i, dy1: __m256i, dx2: __m256i, dy2: __m256i) -> ([Self::M; 3], Self);
    fn store(self, out: &mut [f64; LANES]);
}

/// The AVX-512 backend: one register.
#[derive(Clone, Copy)]
struct F8(__m512d);

impl Add for F8 {
    type Output = Self;
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_add_pd(self.0, b.0) })
    }
}

impl Sub for F8 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_sub_pd(self.0, b.0) })
    }
}

impl Mul for F8 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_mul_pd(self.0, b.0) })
    }
}

impl Div for F8 {
    type Output = Self;
    #[inline(always)]
    fn div(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_div_pd(self.0, b.0) })
    }
}

impl Wide for F8 {
    type M = __mmask8;

    #[inline(always)]
    fn splat(x: f64) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_set1_pd(x) })
    }

    #[inline(always)]
    fn from_ps(x: __m256) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_cvtps_pd(x) })
    }

    #[inline(always)]
    fn from_epi32(x: __m256i) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_cvtepi32_pd(x) })
    }

    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_abs_pd(self.0) })
    }

    #[inline(always)]
    fn min(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_min_pd(self.0, b.0) })
    }

    #[inline(always)]
    fn max(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_max_pd(self.0, b.0) })
    }

    #[inline(always)]
    fn lt(self, b: Self) -> Self::M {
        // SAFETY: see `Wide`.
        unsafe { _mm512_cmp_pd_mask::<_CMP_LT_OQ>(self.0, b.0) }
    }

    #[inline(always)]
    fn le(self, b: Self) -> Self::M {
        // SAFETY: see `Wide`.
        unsafe { _mm512_cmp_pd_mask::<_CMP_LE_OQ>(self.0, b.0) }
    }

    #[inline(always)]
    fn gt(self, b: Self) -> Self::M {
        // SAFETY: see `Wide`.
        unsafe { _mm512_cmp_pd_mask::<_CMP_GT_OQ>(self.0, b.0) }
    }

    #[inline(always)]
    fn select(m: Self::M, a: Self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { _mm512_mask_blend_pd(m, b.0, a.0) })
    }

    #[inline(always)]
    fn to_ps(self) -> __m256 {
        // SAFETY: see `Wide`.
        unsafe { _mm512_cvtpd_ps(self.0) }
    }

    #[inline(always)]
    fn low_dwords(self) -> __m256i {
        // SAFETY: see `Wide`.
        unsafe { _mm512_cvtepi64_epi32(_mm512_castpd_si512(self.0)) }
    }

    #[inline(always)]
    fn mask_from_epi32(m: __m256i) -> Self::M {
        // SAFETY: see `Wide`.
        unsafe { _mm256_movepi32_mask(m) }
    }

    #[inline(always)]
    fn mask_to_epi32(m: Self::M) -> __m256i {
        // SAFETY: see `Wide`.
        unsafe { _mm256_movm_epi32(m) }
    }

    #[inline(always)]
    fn bits(m: Self::M) -> u32 {
        u32::from(m)
    }

    #[inline(always)]
    fn area(dx1: __m256i, dy1: __m256i, dx2: __m256i, dy2: __m256i) -> ([Self::M; 3], Self) {
        // SAFETY: see `Wide`.
        unsafe {
            let (dx1, dy1) = (_mm512_cvtepi32_epi64(dx1), _mm512_cvtepi32_epi64(dy1));
            let (dx2, dy2) = (_mm512_cvtepi32_epi64(dx2), _mm512_cvtepi32_epi64(dy2));
            let a = _mm512_sub_epi64(_mm512_mul_epi32(dx1, dy2), _mm512_mul_epi32(dy1, dx2));
            let zero = _mm512_setzero_si512();
            let masks = [
                _mm512_cmpeq_epi64_mask(a, zero),
                _mm512_cmpgt_epi64_mask(a, zero),
                _mm512_cmplt_epi64_mask(a, zero),
            ];
            // Rounds like `as f64` (the default rounding mode).
            (masks, Self(_mm512_cvtepi64_pd(_mm512_abs_epi64(a))))
        }
    }

    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        // SAFETY: see `Wide`; writes the 8 elements of `out`.
        unsafe { _mm512_storeu_pd(out.as_mut_ptr(), self.0) }
    }
}

/// The AVX2 backend: two registers of 4 lanes, masks as vectors.
#[derive(Clone, Copy)]
struct F4x2([__m256d; 2]);

/// A lane mask of [`F4x2`]: all ones or zero per 64-bit lane.
#[derive(Clone, Copy)]
struct M4x2([__m256d; 2]);

/// Applies a 4-lane operation (a function path, not a closure, so that it inlines into the
/// `#[target_feature]` code) to both halves.
macro_rules! halves {
    ($f:path, $($x:expr),+) => {
        [$f($($x[0]),+), $f($($x[1]),+)]
    };
}

impl Add for F4x2 {
    type Output = Self;
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_add_pd, self.0, b.0) })
    }
}

impl Sub for F4x2 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_sub_pd, self.0, b.0) })
    }
}

impl Mul for F4x2 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_mul_pd, self.0, b.0) })
    }
}

impl Div for F4x2 {
    type Output = Self;
    #[inline(always)]
    fn div(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_div_pd, self.0, b.0) })
    }
}

impl BitAnd for M4x2 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_and_pd, self.0, b.0) })
    }
}

impl BitOr for M4x2 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_or_pd, self.0, b.0) })
    }
}

impl Not for M4x2 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe {
            let ones = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
            [_mm256_xor_pd(self.0[0], ones), _mm256_xor_pd(self.0[1], ones)]
        })
    }
}

/// The two halves of 8 `i32` lanes, sign-extended to `i64`.
#[inline(always)]
fn widen_avx2(x: __m256i) -> [__m256i; 2] {
    // SAFETY: see `Wide`.
    unsafe {
        [
            _mm256_cvtepi32_epi64(_mm256_castsi256_si128(x)),
            _mm256_cvtepi32_epi64(_mm256_extracti128_si256::<1>(x)),
        ]
    }
}

/// The low 32 bits of the 8 `i64` lanes of two halves, as 8 `i32` lanes.
#[inline(always)]
fn narrow_avx2(x: [__m256i; 2]) -> __m256i {
    // SAFETY: see `Wide`.
    unsafe {
        let even = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
        let lo = _mm256_permutevar8x32_epi32(x[0], even);
        let hi = _mm256_permutevar8x32_epi32(x[1], even);
        _mm256_permute2x128_si256::<0x20>(lo, hi)
    }
}

/// [`Wide::area`] for 4 lanes of `i64` (sign-extended `i32`).
#[inline(always)]
fn area4_avx2(dx1: __m256i, dy1: __m256i, dx2: __m256i, dy2: __m256i) -> ([__m256d; 3], __m256d) {
    // SAFETY: see `Wide`.
    unsafe {
        let a = _mm256_sub_epi64(_mm256_mul_epi32(dx1, dy2), _mm256_mul_epi32(dy1, dx2));
        let zero = _mm256_setzero_si256();
        let neg = _mm256_cmpgt_epi64(zero, a);
        let masks = [_mm256_cmpeq_epi64(a, zero), _mm256_cmpgt_epi64(a, zero), neg];
        // |a| < 2^59 (module docs of `setup`), as two exact halves summed with one rounding:
        // `|a| as f64`.
        let abs = _mm256_sub_epi64(_mm256_xor_si256(a, neg), neg);
        let hi = small_u64_to_f64_avx2(_mm256_srli_epi64::<32>(abs));
        let lo = small_u64_to_f64_avx2(_mm256_and_si256(abs, _mm256_set1_epi64x(0xffff_ffff)));
        let f = _mm256_add_pd(_mm256_mul_pd(hi, _mm256_set1_pd(4_294_967_296.0)), lo);
        ([_mm256_castsi256_pd(masks[0]), _mm256_castsi256_pd(masks[1]), _mm256_castsi256_pd(masks[2])], f)
    }
}

/// `[m(0), m(1), m(2)]`.
#[inline(always)]
fn masks_of<M>(m: impl Fn(usize) -> M) -> [M; 3] {
    [m(0), m(1), m(2)]
}

/// `n as f64` for `0 <= n < 2^52` per lane (`2^52 + n` has the bits `2^52 | n`).
#[inline(always)]
fn small_u64_to_f64_avx2(n: __m256i) -> __m256d {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    // SAFETY: see `Wide`.
    unsafe {
        let biased = _mm256_or_si256(n, _mm256_castpd_si256(_mm256_set1_pd(TWO_52)));
        _mm256_sub_pd(_mm256_castsi256_pd(biased), _mm256_set1_pd(TWO_52))
    }
}

impl Wide for F4x2 {
    type M = M4x2;

    #[inline(always)]
    fn splat(x: f64) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { [_mm256_set1_pd(x); 2] })
    }

    #[inline(always)]
    fn from_ps(x: __m256) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe {
            [_mm256_cvtps_pd(_mm256_castps256_ps128(x)), _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(x))]
        })
    }

    #[inline(always)]
    fn from_epi32(x: __m256i) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe {
            [
                _mm256_cvtepi32_pd(_mm256_castsi256_si128(x)),
                _mm256_cvtepi32_pd(_mm256_extracti128_si256::<1>(x)),
            ]
        })
    }

    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe {
            let sign = _mm256_set1_pd(-0.0);
            [_mm256_andnot_pd(sign, self.0[0]), _mm256_andnot_pd(sign, self.0[1])]
        })
    }

    #[inline(always)]
    fn min(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_min_pd, self.0, b.0) })
    }

    #[inline(always)]
    fn max(self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { halves!(_mm256_max_pd, self.0, b.0) })
    }

    #[inline(always)]
    fn lt(self, b: Self) -> Self::M {
        // SAFETY: see `Wide`.
        M4x2(unsafe { halves!(_mm256_cmp_pd::<_CMP_LT_OQ>, self.0, b.0) })
    }

    #[inline(always)]
    fn le(self, b: Self) -> Self::M {
        // SAFETY: see `Wide`.
        M4x2(unsafe { halves!(_mm256_cmp_pd::<_CMP_LE_OQ>, self.0, b.0) })
    }

    #[inline(always)]
    fn gt(self, b: Self) -> Self::M {
        // SAFETY: see `Wide`.
        M4x2(unsafe { halves!(_mm256_cmp_pd::<_CMP_GT_OQ>, self.0, b.0) })
    }

    #[inline(always)]
    fn select(m: Self::M, a: Self, b: Self) -> Self {
        // SAFETY: see `Wide`.
        Self(unsafe { [_mm256_blendv_pd(b.0[0], a.0[0], m.0[0]), _mm256_blendv_pd(b.0[1], a.0[1], m.0[1])] })
    }

    #[inline(always)]
    fn to_ps(self) -> __m256 {
        // SAFETY: see `Wide`.
        unsafe { _mm256_set_m128(_mm256_cvtpd_ps(self.0[1]), _mm256_cvtpd_ps(self.0[0])) }
    }

    #[inline(always)]
    fn low_dwords(self) -> __m256i {
        // SAFETY: see `Wide`.
        narrow_avx2(unsafe { halves!(_mm256_castpd_si256, self.0) })
    }

    #[inline(always)]
    fn mask_from_epi32(m: __m256i) -> Self::M {
        // SAFETY: see `Wide`.
        M4x2(unsafe { halves!(_mm256_castsi256_pd, widen_avx2(m)) })
    }

    #[inline(always)]
    fn mask_to_epi32(m: Self::M) -> __m256i {
        // SAFETY: see `Wide`.
        narrow_avx2(unsafe { halves!(_mm256_castpd_si256, m.0) })
    }

    #[inline(always)]
    fn bits(m: Self::M) -> u32 {
        // SAFETY: see `Wide`.
        unsafe { (_mm256_movemask_pd(m.0[0]) | _mm256_movemask_pd(m.0[1]) << 4) as u32 }
    }

    #[inline(always)]
    fn area(dx1: __m256i, dy1: __m256i, dx2: __m256i, dy2: __m256i) -> ([Self::M; 3], Self) {
        let [dx1, dy1, dx2, dy2] = [widen_avx2(dx1), widen_avx2(dy1), widen_avx2(dx2), widen_avx2(dy2)];
        let a = halves!(area4_avx2, dx1, dy1, dx2, dy2);
        let masks = a.map(|h| h.0);
        let m = |k: usize| M4x2([masks[0][k], masks[1][k]]);
        (masks_of(m), Self([a[0].1, a[1].1]))
    }

    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        // SAFETY: see `Wide`; writes the 8 elements of `out`.
        unsafe {
            _mm256_storeu_pd(out.as_mut_ptr(), self.0[0]);
            _mm256_storeu_pd(out[4..].as_mut_ptr(), self.0[1]);
        }
    }
}

/// Sets up the triangles of `tris` (ids `ids[k]`, or 0), as
/// [`setup_chunk`](crate::setup::setup_chunk), with AVX2.
#[target_feature(enable = "avx2")]
pub(crate) fn setup_chunk_avx2(
    tris: &[[Vec4; 3]],
    ids: Option<&[u32]>,
    ctx: &SetupContext,
    out: &mut Vec<SetupTri>,
) {
    setup_chunk::<F4x2>(tris, ids, ctx, out);
}

/// Sets up the triangles of `tris` (ids `ids[k]`, or 0), as
/// [`setup_chunk`](crate::setup::setup_chunk), with AVX-512.
#[target_feature(enable = "avx2,avx512f,avx512dq,avx512vl")]
pub(crate) fn setup_chunk_avx512(
    tris: &[[Vec4; 3]],
    ids: Option<&[u32]>,
    ctx: &SetupContext,
    out: &mut Vec<SetupTri>,
) {
    setup_chunk::<F8>(tris, ids, ctx, out);
}

/// [`setup_chunk`](crate::setup::setup_chunk) with the backend `W` (module docs).
#[inline(always)]
fn setup_chunk<W: Wide>(
    tris: &[[Vec4; 3]],
    ids: Option<&[u32]>,
    ctx: &SetupContext,
    out: &mut Vec<SetupTri>,
) {
    let mut scratch = ClipScratch::new();
    // Whether the previous group was entirely rejected: then the next one is likely to be too
    // (the triangles of an object out of view are consecutive), and is first tested whole.
    let mut rejecting = false;
    for (g, group) in tris.chunks(LANES).enumerate() {
        let first = g * LANES;
        // The cache lines of the group `PREFETCH_GROUPS` ahead (8 triangles are 6 lines): the
        // input is read once, and the gathers would otherwise wait for it.
        let ahead = tris
            .as_ptr()
            .cast::<i8>()
            .wrapping_add((first + PREFETCH_GROUPS * LANES) * size_of::<[Vec4; 3]>());
        for line in 0..LANES * size_of::<[Vec4; 3]>() / 64 {
            // SAFETY: prefetching has no effect on memory (any address, even past the input);
            // SSE is part of x86-64.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(ahead.wrapping_add(64 * line)) };
        }
        let n = group.len();
        // Lanes with an id: the others are skipped entirely.
        let mut live = 0u32;
        let mut lane_ids = [0u32; LANES];
        for (l, id) in lane_ids.iter_mut().enumerate().take(n) {
            *id = ids.map_or(0, |ids| ids[first + l]);
            live |= u32::from(*id != EMPTY_ID) << l;
        }
        if live == 0 {
            continue;
        }
        if rejecting && n == LANES && all_outside_one_plane(group) {
            continue;
        }
        let gr = Group::load(tris, first, n);
        let (inside, clip) = gr.classify();
        rejecting = (inside | clip) & live == 0;
        // Triangles crossing the viewport's sides but within the guard band and the depth range
        // (large ones seen from inside a room) are also set up in the batch, as
        // `clip_triangle` returns `Inside` for them.
        let (inside, clip) = if clip & live != 0 {
            let unclipped = clip & within_guard_band::<W>(&gr, ctx);
            (inside | unclipped, clip & !unclipped)
        } else {
            (inside, clip)
        };
        let mut todo = clip & live;
        let mut lanes = None;
        if inside & live != 0 {
            let b = batch::<W>(&gr, ctx);
            todo |= b.valid & inside & live;
            lanes = Some(b);
        }
        while todo != 0 {
            let l = todo.trailing_zeros() as usize;
            todo &= todo - 1;
            match &lanes {
                Some(b) if clip >> l & 1 == 0 => out.push(b.tri(l, lane_ids[l])),
                _ => setup_clipped(&tris[first + l], lane_ids[l], ctx, &mut scratch, out),
            }
        }
    }
}

/// Whether every vertex of the 8 triangles lies outside one and the same viewport plane (by
/// `outcode`'s comparisons): then `classify` rejects each triangle (their outcodes share that
/// plane's bit), and the group needs no gathers. Tested on the input as it lies in memory, two
/// vertices per register: the `w` of each broadcast over its vertex's lanes, and the plane
/// tests of each component accumulated (ANDed) over the 24 vertices.
#[inline(always)]
fn all_outside_one_plane(group: &[[Vec4; 3]]) -> bool {
    assert_eq!(group.len(), LANES);
    // SAFETY: AVX2 is available (see `Wide`); the loads read the 96 floats of `group`.
    unsafe {
        let floats = group.as_ptr().cast::<f32>();
        let ones = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        let sign = _mm256_set1_ps(-0.0);
        let (mut below_neg_w, mut above_w, mut negative) = (ones, ones, ones);
        for pair in 0..LANES * 3 / 2 {
            let v = _mm256_loadu_ps(floats.add(8 * pair));
            let w = _mm256_permute_ps::<0xff>(v);
            // Lanes x, y: `v < -w` (left, bottom); x, y, z: `w < v` (right, top, far); z: near.
            below_neg_w = _mm256_and_ps(below_neg_w, _mm256_cmp_ps::<_CMP_LT_OQ>(v, _mm256_xor_ps(w, sign)));
            above_w = _mm256_and_ps(above_w, _mm256_cmp_ps::<_CMP_LT_OQ>(w, v));
            negative = _mm256_and_ps(negative, _mm256_cmp_ps::<_CMP_LT_OQ>(v, _mm256_setzero_ps()));
        }
        // A plane's lane must hold in both vertices of every register (bits c and c + 4).
        let both = |m: __m256| {
            let m = _mm256_movemask_ps(m);
            m & (m >> 4)
        };
        both(below_neg_w) & 0b11 != 0 || both(above_w) & 0b111 != 0 || both(negative) & 0b100 != 0
    }
}

/// 8 input triangles by component: `pos[i][c]` is component `c` (x, y, z, w) of vertex `i` of
/// the triangle in each lane.
struct Group {
    pos: [[__m256; 4]; 3],
}

impl Group {
    /// Triangles `first..first + n` of `tris` (`1 <= n <= 8`) in lanes `0..n`; the other lanes
    /// repeat the last.
    #[inline(always)]
    fn load(tris: &[[Vec4; 3]], first: usize, n: usize) -> Self {
        assert!(n >= 1 && first + n <= tris.len());
        const FLOATS: i32 = 12;
        // SAFETY: AVX2 is available (see `Wide`); the gathers read floats
        // `(first + min(l, n - 1)) * 12 + 4 i + c < 12 tris.len()` of the input.
        unsafe {
            let last = (n - 1) as i32;
            let lanes = _mm256_min_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32(last));
            let base = _mm256_mullo_epi32(lanes, _mm256_set1_epi32(FLOATS));
            let floats = tris[first..].as_ptr().cast::<f32>();
            let mut pos = [[_mm256_setzero_ps(); 4]; 3];
            for (i, v) in pos.iter_mut().enumerate() {
                for (c, x) in v.iter_mut().enumerate() {
                    let index = _mm256_add_epi32(base, _mm256_set1_epi32((4 * i + c) as i32));
                    *x = _mm256_i32gather_ps::<4>(floats, index);
                }
            }
            Self { pos }
        }
    }

    /// `classify` per lane: the bit masks of the lanes inside the viewport and the depth range,
    /// and of those to clip (the others are rejected). The comparisons are those of `outcode`.
    #[inline(always)]
    fn classify(&self) -> (u32, u32) {
        // SAFETY: AVX2 is available (see `Wide`).
        unsafe {
            let inf = _mm256_set1_ps(f32::INFINITY);
            let sign = _mm256_set1_ps(-0.0);
            let zero = _mm256_setzero_ps();
            let ones = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
            let mut finite = ones;
            let mut all_out = [ones; 6];
            let mut any_out = zero;
            for [x, y, z, w] in self.pos {
                for c in [x, y, z, w] {
                    finite =
                        _mm256_and_ps(finite, _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, c), inf));
                }
                let neg_w = _mm256_xor_ps(w, sign);
                let out = [
                    _mm256_cmp_ps::<_CMP_LT_OQ>(x, neg_w),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(y, neg_w),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(w, x),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(w, y),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(w, z),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(z, zero),
                ];
                for (a, o) in all_out.iter_mut().zip(out) {
                    *a = _mm256_and_ps(*a, o);
                    any_out = _mm256_or_ps(any_out, o);
                }
            }
            let mut rejected = zero;
            for a in all_out {
                rejected = _mm256_or_ps(rejected, a);
            }
            let finite = _mm256_movemask_ps(finite) as u32;
            let (rejected, any_out) =
                (_mm256_movemask_ps(rejected) as u32, _mm256_movemask_ps(any_out) as u32);
            let kept = finite & !rejected;
            (kept & !any_out, kept & any_out)
        }
    }
}

/// The lanes of `gr` whose vertices are all inside the near and far planes and the guard band:
/// those for which `clip_triangle` (given a triangle that `classify` did not reject) returns
/// `Inside`, with its `f64` distances (`Plane::distance`) and comparisons.
#[inline(always)]
fn within_guard_band<W: Wide>(gr: &Group, ctx: &SetupContext) -> u32 {
    let (gx, gy) = (W::splat(ctx.guard.x), W::splat(ctx.guard.y));
    let zero = W::splat(0.0);
    let mut outside = zero.lt(zero);
    for [x, y, z, w] in gr.pos {
        let (x, y, z, w) = (W::from_ps(x), W::from_ps(y), W::from_ps(z), W::from_ps(w));
        let distances = [z, w - z, gx * w + x, gx * w - x, gy * w + y, gy * w - y];
        for d in distances {
            outside = outside | d.lt(zero);
        }
    }
    W::bits(!outside)
}

/// The set-up triangles of the lanes of a [`Group`] (as `setup_unclipped` computes them), by
/// component.
struct Batch {
    /// The lanes `setup_unclipped` keeps (given that they need no clipping).
    valid: u32,
    /// The lanes whose area is negative: vertices 1 and 2 swap.
    swap: u32,
    fx: [[i32; LANES]; 3],
    fy: [[i32; LANES]; 3],
    bbox: [[i32; LANES]; 4],
    z0: [f64; LANES],
    dz: [[f64; LANES]; 2],
    range: [[f32; LANES]; 2],
    q: [[f32; LANES]; 3],
}

impl Batch {
    /// The [`SetupTri`] of lane `l`, with id `id`: what `setup_unclipped` pushes.
    #[inline(always)]
    fn tri(&self, l: usize, id: u32) -> SetupTri {
        let v = |i: usize| [self.fx[i][l], self.fy[i][l]];
        let q = |i: usize| self.q[i][l];
        // `setup_unclipped`'s `persp` and order of the vertices.
        let (b, c) = ((v(1), [q(1), q(1), 0.0]), (v(2), [q(2), 0.0, q(2)]));
        let (b, c) = if self.swap >> l & 1 != 0 { (c, b) } else { (b, c) };
        SetupTri::from_parts(
            [v(0), b.0, c.0],
            // In [0, width) x [0, height) by the clamps, for the lanes kept.
            self.bbox.map(|b| b[l] as u32),
            id,
            // Swapped lanes have negative area: front faces (`setup_unclipped`).
            self.swap >> l & 1 == 0,
            [self.z0[l], self.dz[0][l], self.dz[1][l]],
            [self.range[0][l], self.range[1][l]],
            [[q(0), 0.0, 0.0], b.1, c.1],
        )
    }
}

/// `setup_unclipped` for the 8 lanes of `gr` (module docs; the references are to its steps and
/// the functions it calls, in `crate::setup`).
#[inline(always)]
fn batch<W: Wide>(gr: &Group, ctx: &SetupContext) -> Batch {
    let f = W::splat;
    let (width, height) = (f(f64::from(ctx.width)), f(f64::from(ctx.height)));
    let one_px = f(SUBPIXEL_ONE as f64);
    // SAFETY: AVX2 is available (see `Wide`); the stores write 8 elements of arrays.
    unsafe {
        let mut ok = W::mask_from_epi32(_mm256_set1_epi32(-1));
        // Per vertex: fixed-point position (`i32` lanes), unsnapped [X, Y, D], 1 / w.
        let mut fx = [_mm256_setzero_si256(); 3];
        let mut fy = [_mm256_setzero_si256(); 3];
        let mut u = [[f(0.0); 3]; 3];
        let mut inv_w = [f(0.0); 3];
        for i in 0..3 {
            let [x, y, z, w] = gr.pos[i];
            let (x, y, z, w) = (W::from_ps(x), W::from_ps(y), W::from_ps(z), W::from_ps(w));
            let iw = f(1.0) / w;
            // `if pos.w <= 0.0 || !inv_w.is_finite()`: `w` is finite (`classify`), so this is
            // `1 / w` positive and finite.
            ok = ok & f(0.0).lt(iw) & iw.abs().lt(f(f64::INFINITY));
            let sx = (x * iw + f(1.0)) * f(0.5) * width;
            let sy = (f(1.0) - y * iw) * f(0.5) * height;
            let (okx, x_fixed) = to_fixed::<W>(sx * one_px);
            let (oky, y_fixed) = to_fixed::<W>(sy * one_px);
            ok = ok & okx & oky;
            (fx[i], fy[i]) = (x_fixed, y_fixed);
            u[i] = [sx * one_px, sy * one_px, z * iw];
            inv_w[i] = iw;
        }

        // `cross` and `pixel_bounds`, in `i32` (exact for the lanes kept, see `to_fixed`).
        let dx1 = _mm256_sub_epi32(fx[1], fx[0]);
        let dy1 = _mm256_sub_epi32(fy[1], fy[0]);
        let dx2 = _mm256_sub_epi32(fx[2], fx[0]);
        let dy2 = _mm256_sub_epi32(fy[2], fy[0]);
        let ([zero, pos, neg], abs_area) = W::area(dx1, dy1, dx2, dy2);
        ok = ok & !zero;
        if ctx.cull_backfaces {
            ok = ok & !pos;
        }
        let bbox = [
            bound_lower(_mm256_min_epi32(_mm256_min_epi32(fx[0], fx[1]), fx[2])),
            bound_lower(_mm256_min_epi32(_mm256_min_epi32(fy[0], fy[1]), fy[2])),
            bound_upper(_mm256_max_epi32(_mm256_max_epi32(fx[0], fx[1]), fx[2]), ctx.width),
            bound_upper(_mm256_max_epi32(_mm256_max_epi32(fy[0], fy[1]), fy[2]), ctx.height),
        ];
        let empty =
            _mm256_or_si256(_mm256_cmpgt_epi32(bbox[0], bbox[2]), _mm256_cmpgt_epi32(bbox[1], bbox[3]));
        ok = ok & !W::mask_from_epi32(empty);
        ok = ok & !W::mask_from_epi32(misses_every_sample(fx, fy, W::mask_to_epi32(neg), bbox));

        // `depth_gradient`.
        let [u0, u1, u2] = u;
        let [x1, y1, d1] = [u1[0] - u0[0], u1[1] - u0[1], u1[2] - u0[2]];
        let [x2, y2, d2] = [u2[0] - u0[0], u2[1] - u0[1], u2[2] - u0[2]];
        let inv_den = f(1.0) / (x1 * y2 - x2 * y1);
        let grad = [(d1 * y2 - d2 * y1) * inv_den, (x1 * d2 - x2 * d1) * inv_den];
        let usable = ((grad[0].abs() + grad[1].abs()) * f(0.5)).le(f(MAX_DEPTH_CORRECTION));
        let grad = [W::select(usable, grad[0], f(0.0)), W::select(usable, grad[1], f(0.0))];
        // `depth_at_snapped` and `depth_difference`, with the exact `snapped_offset`s.
        let z0 =
            u0[2] + (grad[0] * (W::from_epi32(fx[0]) - u0[0]) + grad[1] * (W::from_epi32(fy[0]) - u0[1]));
        let dz1 = depth_difference::<W>(grad, u0, u1, [W::from_epi32(dx1), W::from_epi32(dy1)]);
        let dz2 = depth_difference::<W>(grad, u0, u2, [W::from_epi32(dx2), W::from_epi32(dy2)]);
        let inv_area = f(1.0) / abs_area;
        let dz = [W::select(neg, dz2, dz1) * inv_area, W::select(neg, dz1, dz2) * inv_area];
        // `depth_range`: the fold from `[inf, -inf]`, then `f64::clamp(0, 1)`.
        let lo = u2[2].min(u1[2].min(u0[2]));
        let hi = u2[2].max(u1[2].max(u0[2]));
        // `scale` and `persp`: the maximum of positive values is exact and order-independent.
        let scale = f(1.0) / inv_w[0].max(inv_w[1]).max(inv_w[2]);

        let mut b = Batch {
            valid: W::bits(ok),
            swap: W::bits(neg),
            fx: [[0; LANES]; 3],
            fy: [[0; LANES]; 3],
            bbox: [[0; LANES]; 4],
            z0: [0.0; LANES],
            dz: [[0.0; LANES]; 2],
            range: [[0.0; LANES]; 2],
            q: [[0.0; LANES]; 3],
        };
        for i in 0..3 {
            _mm256_storeu_si256(b.fx[i].as_mut_ptr().cast(), fx[i]);
            _mm256_storeu_si256(b.fy[i].as_mut_ptr().cast(), fy[i]);
            _mm256_storeu_ps(b.q[i].as_mut_ptr(), (inv_w[i] * scale).to_ps());
        }
        for (out, x) in b.bbox.iter_mut().zip(bbox) {
            _mm256_storeu_si256(out.as_mut_ptr().cast(), x);
        }
        z0.store(&mut b.z0);
        dz[0].store(&mut b.dz[0]);
        dz[1].store(&mut b.dz[1]);
        _mm256_storeu_ps(b.range[0].as_mut_ptr(), clamp_unit(lo).to_ps());
        _mm256_storeu_ps(b.range[1].as_mut_ptr(), clamp_unit(hi).to_ps());
        b
    }
}

/// `misses_every_sample` per lane, as a lane mask: the tiny triangles (pixel bounds `bbox` of at
/// most 2 x 2 pixels, vertices within `TINY_SPAN` of each other) that cover none of the
/// samples of their bounds, given the fixed-point vertices and the lanes of negative area
/// (whose vertices 1 and 2 swap, as in `setup_unclipped`).
///
/// The edge functions are `crate::edge`'s, in `i32`: exact for a tiny triangle, whose edge
/// vectors and offsets from a vertex to a sample of its bounds (which lie within the vertices'
/// bounding box) are below `TINY_SPAN = 2^14` in magnitude, so `|E| < 2^29`. Other lanes may
/// compute anything: they are not tiny.
#[inline(always)]
fn misses_every_sample(fx: [__m256i; 3], fy: [__m256i; 3], swap: __m256i, bbox: [__m256i; 4]) -> __m256i {
    // SAFETY: AVX2 is available (see `Wide`).
    unsafe {
        let span_x = _mm256_sub_epi32(
            _mm256_max_epi32(_mm256_max_epi32(fx[0], fx[1]), fx[2]),
            _mm256_min_epi32(_mm256_min_epi32(fx[0], fx[1]), fx[2]),
        );
        let span_y = _mm256_sub_epi32(
            _mm256_max_epi32(_mm256_max_epi32(fy[0], fy[1]), fy[2]),
            _mm256_min_epi32(_mm256_min_epi32(fy[0], fy[1]), fy[2]),
        );
        let one = _mm256_set1_epi32(1);
        let wide_x = _mm256_cmpgt_epi32(_mm256_sub_epi32(bbox[2], bbox[0]), _mm256_setzero_si256());
        let wide_y = _mm256_cmpgt_epi32(_mm256_sub_epi32(bbox[3], bbox[1]), _mm256_setzero_si256());
        let limit = _mm256_set1_epi32(TINY_SPAN);
        let tiny = _mm256_andnot_si256(
            _mm256_or_si256(
                _mm256_or_si256(
                    _mm256_cmpgt_epi32(_mm256_sub_epi32(bbox[2], bbox[0]), one),
                    _mm256_cmpgt_epi32(_mm256_sub_epi32(bbox[3], bbox[1]), one),
                ),
                _mm256_or_si256(
                    _mm256_cmpgt_epi32(span_x, _mm256_sub_epi32(limit, one)),
                    _mm256_cmpgt_epi32(span_y, _mm256_sub_epi32(limit, one)),
                ),
            ),
            _mm256_set1_epi32(-1),
        );
        // The vertices in `setup_unclipped`'s order, and the centre of the first sample.
        let v = [
            (fx[0], fy[0]),
            (_mm256_blendv_epi8(fx[1], fx[2], swap), _mm256_blendv_epi8(fy[1], fy[2], swap)),
            (_mm256_blendv_epi8(fx[2], fx[1], swap), _mm256_blendv_epi8(fy[2], fy[1], swap)),
        ];
        let half = _mm256_set1_epi32(HALF_PIXEL as i32);
        let px = _mm256_add_epi32(_mm256_slli_epi32::<{ SUBPIXEL_BITS as i32 }>(bbox[0]), half);
        let py = _mm256_add_epi32(_mm256_slli_epi32::<{ SUBPIXEL_BITS as i32 }>(bbox[1]), half);
        // OR of the biased edge values at each sample: inside iff non-negative (sign clear).
        let mut outside = [_mm256_setzero_si256(); 4];
        for (a, b) in [(v[1], v[2]), (v[2], v[0]), (v[0], v[1])] {
            // As `Edge::new` and `Edge::at_pixel`, and the steps `Edge::step_x`, `Edge::step_y`.
            let (dx, dy) = (_mm256_sub_epi32(b.0, a.0), _mm256_sub_epi32(b.1, a.1));
            let e = _mm256_sub_epi32(
                _mm256_mullo_epi32(dx, _mm256_sub_epi32(py, a.1)),
                _mm256_mullo_epi32(dy, _mm256_sub_epi32(px, a.0)),
            );
            let top_left = _mm256_or_si256(
                _mm256_cmpgt_epi32(_mm256_setzero_si256(), dy),
                _mm256_and_si256(
                    _mm256_cmpeq_epi32(dy, _mm256_setzero_si256()),
                    _mm256_cmpgt_epi32(dx, _mm256_setzero_si256()),
                ),
            );
            // Bias 1, or 0 for a top-left edge (`top_left` is -1 there).
            let e00 = _mm256_sub_epi32(e, _mm256_add_epi32(one, top_left));
            let (sx, sy) = (
                _mm256_sub_epi32(_mm256_setzero_si256(), _mm256_slli_epi32::<{ SUBPIXEL_BITS as i32 }>(dy)),
                _mm256_slli_epi32::<{ SUBPIXEL_BITS as i32 }>(dx),
            );
            let e01 = _mm256_add_epi32(e00, sy);
            for (o, e) in
                outside.iter_mut().zip([e00, _mm256_add_epi32(e00, sx), e01, _mm256_add_epi32(e01, sx)])
            {
                *o = _mm256_or_si256(*o, e);
            }
        }
        let inside = _mm256_set1_epi32(-1);
        let mut covered = outside;
        for c in &mut covered {
            *c = _mm256_cmpgt_epi32(*c, inside);
        }
        let any = _mm256_or_si256(
            _mm256_or_si256(covered[0], _mm256_and_si256(covered[1], wide_x)),
            _mm256_or_si256(
                _mm256_and_si256(covered[2], wide_y),
                _mm256_and_si256(covered[3], _mm256_and_si256(wide_x, wide_y)),
            ),
        );
        _mm256_andnot_si256(any, tiny)
    }
}

/// `depth_difference` per lane: `(D_k - D_0) + A (dX' - dX) + B (dY' - dY)`.
#[inline(always)]
fn depth_difference<W: Wide>(grad: [W; 2], p0: [W; 3], pk: [W; 3], snapped: [W; 2]) -> W {
    (pk[2] - p0[2]) + (grad[0] * (snapped[0] - (pk[0] - p0[0])) + grad[1] * (snapped[1] - (pk[1] - p0[1])))
}

/// `f64::clamp(x, 0, 1)` per lane, as its two selects (a `max` would turn `-0` into `+0`).
#[inline(always)]
fn clamp_unit<W: Wide>(x: W) -> W {
    let x = W::select(x.lt(W::splat(0.0)), W::splat(0.0), x);
    W::select(x.gt(W::splat(1.0)), W::splat(1.0), x)
}

/// `div_ceil_i64(m - HALF, ONE).max(0)` of `pixel_bounds` per `i32` lane: `-((HALF - m) >> 8)`
/// (ONE = 2^8), clamped to 0.
#[inline(always)]
fn bound_lower(m: __m256i) -> __m256i {
    // SAFETY: AVX2 is available (see `Wide`).
    unsafe {
        let q = _mm256_srai_epi32::<{ SUBPIXEL_BITS as i32 }>(_mm256_sub_epi32(
            _mm256_set1_epi32(HALF_PIXEL as i32),
            m,
        ));
        _mm256_max_epi32(_mm256_sub_epi32(_mm256_setzero_si256(), q), _mm256_setzero_si256())
    }
}

/// `(m - HALF).div_euclid(ONE).min(size - 1)` of `pixel_bounds` per `i32` lane: an arithmetic
/// shift (ONE = 2^8).
#[inline(always)]
fn bound_upper(m: __m256i, size: u32) -> __m256i {
    // SAFETY: AVX2 is available (see `Wide`).
    unsafe {
        let q = _mm256_srai_epi32::<{ SUBPIXEL_BITS as i32 }>(_mm256_sub_epi32(
            m,
            _mm256_set1_epi32(HALF_PIXEL as i32),
        ));
        _mm256_min_epi32(q, _mm256_set1_epi32(size as i32 - 1))
    }
}

/// `to_fixed` of an unsnapped coordinate in fixed-point units, `px * SUBPIXEL_ONE` (the product
/// `to_fixed` computes): whether it is in range, and its value in `i32` lanes (exact in range:
/// below `MAX_FIXED = 2^28` in magnitude).
///
/// `f = px + 1/2`; `m = f + 1.5 * 2^52` has the bits of `1.5 * 2^52` plus the rounded `f`,
/// whose low 32 bits are the low 32 bits of `m`'s (those of the constant are zero); the floor
/// is one less where `m - 1.5 * 2^52 > f`.
#[inline(always)]
fn to_fixed<W: Wide>(px: W) -> (W::M, __m256i) {
    const MAGIC: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52, as in `to_fixed`
    let f = px + W::splat(0.5);
    // `!(f.is_nan() || f.abs() > MAX_FIXED)`.
    let ok = f.abs().le(W::splat(MAX_FIXED as f64));
    let m = f + W::splat(MAGIC);
    let rounded_up = f.lt(m - W::splat(MAGIC));
    // SAFETY: AVX2 is available (see `Wide`).
    let fixed = unsafe { _mm256_add_epi32(m.low_dwords(), W::mask_to_epi32(rounded_up)) };
    (ok, fixed)
}

#[cfg(test)]
mod tests {
    use glam::Vec4;

    use super::*;
    use crate::setup::setup_chunk;
    use crate::zbuf::{Isa, Tier};

    use crate::test_rng::Rng;

    /// Triangles of every kind the setup treats differently, in random order: sub-pixel to
    /// screen-filling, slivers and degenerate ones, both orientations, crossing the near or far
    /// plane or the viewport sides, behind the eye, beyond the guard band, with `w` near 0, with
    /// `-0` depths, non-finite coordinates, and ids including `EMPTY_ID`.
    fn scene() -> (Vec<[Vec4; 3]>, Vec<u32>) {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let mut tris = Vec::new();
        for i in 0..40_000 {
            let size = [0.001, 0.01, 0.05, 0.3, 2.0, 1e6][i % 6];
            let squash = if i % 7 == 0 { 1e-5 } else { 1.0 };
            let (cx, cy) = (rng.f32() * 2.6 - 1.3, rng.f32() * 2.6 - 1.3);
            let mut tri = [Vec4::ZERO; 3];
            for v in &mut tri {
                let w = match i % 11 {
                    0 => rng.f32() * 2.0 - 1.0,
                    1 => rng.f32() * 1e-30,
                    _ => 0.1 + rng.f32() * 20.0,
                };
                let z = match i % 13 {
                    0 => rng.f32() * 2.0 - 0.5,
                    1 => -0.0,
                    2 => w,
                    _ => rng.f32() * w,
                };
                let (x, y) = (cx + (rng.f32() - 0.5) * size, cy + (rng.f32() - 0.5) * size * squash);
                *v = Vec4::new(x * w, y * w, z, w);
            }
            if i % 97 == 0 {
                tri[1] = tri[0];
            }
            if i % 101 == 0 {
                tri[2].x = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][i % 3];
            }
            tris.push(tri);
        }
        // Runs of triangles outside one viewport plane each (as the objects out of view of a
        // scene), some with a triangle in view among them, for `all_outside_one_plane`.
        for run in 0..240 {
            let plane = run % 6;
            for k in 0..8 + run % 29 {
                let mut tri = [Vec4::ZERO; 3];
                for v in &mut tri {
                    let w = 0.5 + rng.f32() * 5.0;
                    let (mut x, mut y, mut z) = (rng.f32() * 2.0 - 1.0, rng.f32() * 2.0 - 1.0, rng.f32());
                    // Every other run lies just inside the plane (and in the lower half, to
                    // tell the planes apart), right after one outside it.
                    let inside = run % 12 >= 6;
                    if inside {
                        y = -rng.f32() * 0.9;
                        match plane {
                            0 => x = -1.0 + rng.f32() * 0.05,
                            1 => x = 1.0 - rng.f32() * 0.05,
                            2 => y = -1.0 + rng.f32() * 0.05,
                            3 => y = 1.0 - rng.f32() * 0.05,
                            4 => z = 1.0 - rng.f32() * 0.05,
                            _ => z = rng.f32() * 0.05,
                        }
                    } else if k != 13 {
                        match plane {
                            0 => x = -1.0 - rng.f32() * 3.0 - 1e-3,
                            1 => x = 1.0 + rng.f32() * 3.0 + 1e-3,
                            2 => y = -1.0 - rng.f32() * 3.0 - 1e-3,
                            3 => y = 1.0 + rng.f32() * 3.0 + 1e-3,
                            4 => z = 1.0 + rng.f32() + 1e-3,
                            _ => z = -rng.f32() - 1e-3,
                        }
                    }
                    *v = Vec4::new(x * w, y * w, z * w, w);
                }
                tris.push(tri);
            }
        }
        let ids = (0..tris.len() as u32).map(|i| if i % 17 == 5 { EMPTY_ID } else { i * 7 }).collect();
        (tris, ids)
    }

    /// The vector kernels give the scalar setup's triangles, bit for bit (the `Debug` form of
    /// `f64` and `f32` is exact), with and without ids, culling and partial groups.
    #[test]
    fn vector_setup_matches_the_scalar_setup() {
        let (tris, ids) = scene();
        for cull in [false, true] {
            for (w, h) in [(640, 480), (97, 61)] {
                let ctx = SetupContext::new(w, h, cull);
                for len in [tris.len(), 4_093, 40_000 + 1_013] {
                    for ids in [Some(&ids[..len]), None] {
                        let mut reference = Vec::new();
                        setup_chunk(&tris[..len], ids, &ctx, &mut reference);
                        assert!(reference.len() > len / 8, "{}", reference.len());
                        let reference = format!("{reference:?}");
                        for isa in Isa::for_tests("setup kernels") {
                            let mut out = Vec::new();
                            // SAFETY: `Isa::for_tests` lists the tiers this CPU runs.
                            match isa.tier() {
                                Tier::Scalar => continue,
                                // SAFETY: as above.
                                Tier::Avx2 => unsafe { setup_chunk_avx2(&tris[..len], ids, &ctx, &mut out) },
                                // SAFETY: as above.
                                Tier::Avx512 => unsafe {
                                    setup_chunk_avx512(&tris[..len], ids, &ctx, &mut out)
                                },
                            }
                            assert!(format!("{out:?}") == reference, "{isa:?}, cull {cull}, {w}x{h}, {len}");
                        }
                    }
                }
            }
        }
    }
}
