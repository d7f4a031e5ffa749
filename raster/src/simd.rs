//! Vector kernels of the z-buffer (x86-64, chosen at run time): AVX2 and AVX-512.
//!
//! Both work on rows of 8 pixels: the three edge functions as 8 `i64` lanes, the depth as 8
//! `f64` lanes, the z-buffer as 8 `f32` / `u32` lanes. They compute exactly what the scalar
//! kernel ([`ZBuffer::draw_scalar`]) computes:
//!
//! * coverage from the same exact integer edge values (sign tests);
//! * the depth with the same `f64` operations in the same order as [`SetupTri::depth`] (IEEE
//!   operations are correctly rounded whatever the vector width; no fused multiply-add), the same
//!   rounding to `f32` and the same clamp ([`crate::setup::clamp_depth`], written as the `max` /
//!   `min` instructions compute it);
//! * the same comparisons: closer or not, and for `TIE` the same `f32` window test as
//!   [`crate::zbuf::in_tie_window`]; the rare ties (equal depths, or within the window) are decided
//!   by [`wins`] itself.
//!
//! The traversal ([`draw`]) is [`crate::edge::cover_rect`]'s, specialised: the same per-pixel
//! coverage tests, plus a test of the whole tile rectangle first (every pixel of a tile inside a
//! large triangle is covered: no per-block work at all), and block edge values stepped from block
//! to block rather than evaluated anew. Only speed depends on these choices. It is generic over
//! the [`Lanes`] of a backend, whose methods are inlined into the `#[target_feature]` entry points
//! ([`draw_all_avx2`], [`draw_all_avx512`]).

use std::arch::x86_64::*;

use crate::edge::{BLOCK, EdgeFns, low_bits};
use crate::setup::SetupTri;
use crate::zbuf::{ZBuffer, clip_to_tile, wins};

/// `[f(0), f(1), f(2)]`. Written out rather than with `array::map` or `from_fn`, which are not
/// always inlined, and then cannot inline vector code into their bodies (no target features).
#[inline(always)]
fn each<T>(mut f: impl FnMut(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

/// The row primitives of a vector backend, with the per-triangle constants they need.
///
/// A backend value is only created inside its `#[target_feature]` entry point, i.e. after the CPU
/// was found to support it: that is the safety argument of the `unsafe` blocks in the
/// implementations (calls to intrinsics of features the enclosing function does not declare).
trait Lanes<'t> {
    /// 8 consecutive values of one edge function along a row.
    type Row: Copy;
    /// Triangles with `area >= MAX_AREA` take the scalar path (see [`Avx2::MAX_AREA`]).
    const MAX_AREA: i64;

    fn new(tri: &'t SetupTri, idx: u32, ef: &EdgeFns, tie: f32) -> Self;
    /// `e + j sx_i` for `j = 0..8`: edge `i` along a row, from its value `e` at the first pixel.
    fn row(&self, i: usize, e: i64) -> Self::Row;
    /// The row below: `+ sy_i`.
    fn down(&self, i: usize, r: Self::Row) -> Self::Row;
    /// `+ bias_i`: biased edge values to unbiased ones.
    fn unbias(&self, i: usize, r: Self::Row) -> Self::Row;
    /// Bit `j` set iff lane `j` of the three biased rows is inside (all `>= 0`).
    fn inside(&self, r: &[Self::Row; 3]) -> u32;
    /// Depth-tests the 8 pixels of `zb` from index `k` on whose bits are set in `covered`, given
    /// their unbiased `e1`, `e2`.
    fn test_row<const REVERSED: bool, const TIE: bool>(
        &self,
        zb: &mut ZBuffer<'t>,
        k: usize,
        covered: u32,
        e1: Self::Row,
        e2: Self::Row,
    );
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
#[inline(always)]
fn tie_winners<const REVERSED: bool, const TIE: bool>(
    zb: &ZBuffer,
    k: usize,
    tri: &SetupTri,
    d: &[f32; 8],
    ties: u32,
) -> u32 {
    let mut won = 0;
    let mut t = ties;
    while t != 0 {
        let j = t.trailing_zeros() as usize;
        if wins::<REVERSED, TIE>(d[j], tri.id, zb.depth[k + j], zb.win[k + j], &zb.tris, zb.tie) {
            won |= 1 << j;
        }
        t &= t - 1;
    }
    won
}

/// Depth-tests every triangle of the tile.
#[inline(always)]
fn draw_all<'t, L: Lanes<'t>, const REVERSED: bool, const TIE: bool>(zb: &mut ZBuffer<'t>) {
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
        let ef = EdgeFns::new(zb.tris[idx as usize]);
        if ef.area >= L::MAX_AREA {
            zb.draw_scalar::<REVERSED, TIE>(idx);
        } else {
            draw::<L, REVERSED, TIE>(zb, idx, &ef);
        }
    }
}

/// Depth-tests `rows` rows of `n <= 8` pixels, all covered, from tile index `k` and unbiased
/// edge values `e` at its first pixel.
#[inline(always)]
fn test_covered<'t, L: Lanes<'t>, const REVERSED: bool, const TIE: bool>(
    zb: &mut ZBuffer<'t>,
    c: &L,
    mut k: usize,
    n: u32,
    rows: u32,
    e: [i64; 3],
) {
    let covered = low_bits(n);
    let (mut e1, mut e2) = (c.row(1, e[1]), c.row(2, e[2]));
    for _ in 0..rows {
        c.test_row::<REVERSED, TIE>(zb, k, covered, e1, e2);
        e1 = c.down(1, e1);
        e2 = c.down(2, e2);
        k += zb.w;
    }
}

/// Depth-tests `rows` rows of `n <= 8` pixels from tile index `k` and *biased* edge values `e`
/// at its first pixel, testing coverage per pixel.
#[inline(always)]
fn test_partial<'t, L: Lanes<'t>, const REVERSED: bool, const TIE: bool>(
    zb: &mut ZBuffer<'t>,
    c: &L,
    mut k: usize,
    n: u32,
    rows: u32,
    e: [i64; 3],
) {
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
fn draw<'t, L: Lanes<'t>, const REVERSED: bool, const TIE: bool>(
    zb: &mut ZBuffer<'t>,
    idx: u32,
    ef: &EdgeFns,
) {
    let tri = zb.tris[idx as usize];
    let [tx0, ty0, ..] = zb.rect;
    let [x0, y0, x1, y1] = clip_to_tile(zb.rect, tri.bbox);
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let c = L::new(tri, idx, ef, zb.tie);
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
            test_covered::<L, REVERSED, TIE>(zb, &c, index(x, y0), (x1 - x).min(BLOCK), y1 - y0, e);
            x += BLOCK;
        }
        return;
    }
    if x1 - x0 <= BLOCK && y1 - y0 <= BLOCK {
        test_partial::<L, REVERSED, TIE>(zb, &c, index(x0, y0), x1 - x0, y1 - y0, e);
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
                    test_covered::<L, REVERSED, TIE>(zb, &c, k, n, rows, e);
                } else {
                    test_partial::<L, REVERSED, TIE>(zb, &c, k, n, rows, e);
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
    draw_all::<Avx512, REVERSED, TIE>(zb);
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

/// Lane `j` (of 8) all ones iff bit `j` of `mask` is set.
#[inline(always)]
fn lanes_avx2(mask: u32) -> __m256i {
    // SAFETY: only called from AVX2 code (see `Lanes`).
    unsafe {
        let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(mask as i32), bits), bits)
    }
}

impl Avx2<'_> {
    /// Depth of 4 pixels from their unbiased `e1`, `e2`: `(z0 + e1 dz0) + e2 dz1` as
    /// [`SetupTri::depth`], rounded to `f32` (not yet clamped). Lanes of uncovered pixels may hold
    /// garbage (edge values beyond 2^51); they are masked out by the caller.
    #[inline(always)]
    fn depth4(&self, e1: __m256i, e2: __m256i) -> __m128 {
        // SAFETY: see `Lanes`.
        unsafe {
            let d = _mm256_add_pd(
                _mm256_add_pd(self.z0, _mm256_mul_pd(to_f64_avx2(e1), self.dz[0])),
                _mm256_mul_pd(to_f64_avx2(e2), self.dz[1]),
            );
            _mm256_cvtpd_ps(d)
        }
    }
}

/// `|x|` per lane (clears the sign bits).
#[inline(always)]
fn abs_ps(x: __m256) -> __m256 {
    // SAFETY: only called from AVX2 or AVX-512 code (see `Lanes`).
    unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), x) }
}

/// Lane `j` set iff depths `d[j]` and `cur[j]` are a tie for the window `tie`:
/// [`crate::zbuf::in_tie_window`] with the same `f32` operations, as a lane mask.
///
/// An empty standard-depth entry (`cur = +inf`) is excluded (for any finite `d` the formula
/// gives `inf <= inf`): the fragment beats it either way (see [`wins`]), and as a tie it would
/// go through the scalar path for every first fragment of a pixel.
#[inline(always)]
fn tie_window<const REVERSED: bool>(d: __m256, cur: __m256, tie: __m256) -> __m256 {
    // SAFETY: only called from AVX2 or AVX-512 code (see `Lanes`).
    unsafe {
        let diff = abs_ps(_mm256_sub_ps(d, cur));
        let limit = _mm256_mul_ps(tie, _mm256_max_ps(abs_ps(d), abs_ps(cur)));
        let in_window = _mm256_cmp_ps::<_CMP_LE_OQ>(diff, limit);
        if REVERSED {
            in_window
        } else {
            _mm256_and_ps(in_window, _mm256_cmp_ps::<_CMP_LT_OQ>(cur, _mm256_set1_ps(f32::INFINITY)))
        }
    }
}

/// `clamp_depth` per lane: `min(max(d, lo), hi)` with `d` as the first operand of each, which
/// is [`crate::setup::clamp_depth`]'s comparisons exactly.
#[inline(always)]
fn clamp_ps(d: __m256, lo: __m256, hi: __m256) -> __m256 {
    // SAFETY: only called from AVX2 or AVX-512 code (see `Lanes`).
    unsafe { _mm256_min_ps(_mm256_max_ps(d, lo), hi) }
}

/// The AVX2 backend: a row is two vectors of 4 `i64`.
struct Avx2<'t> {
    tri: &'t SetupTri,
    idx: __m256i,
    /// `[0, s, 2 s, 3 s]` and `4 s` for each edge's x step `s`.
    off: [__m256i; 3],
    step4: [__m256i; 3],
    /// Each edge's y step and fill-rule bias, in every lane.
    sy: [__m256i; 3],
    bias: [__m256i; 3],
    z0: __m256d,
    dz: [__m256d; 2],
    /// The clamp range and the tie window, in every lane.
    lo: __m256,
    hi: __m256,
    tie: __m256,
}

impl<'t> Lanes<'t> for Avx2<'t> {
    type Row = [__m256i; 2];
    /// Edge values with `|e| >= 2^51` would not convert exactly (see [`MAGIC`]); covered samples
    /// have `0 <= e_i <= area` ([`EdgeFns::area`]), so triangles with `area < 2^51` are safe.
    /// Bigger ones (hundreds of thousands of pixels across: only guard-band triangles) take the
    /// scalar path.
    const MAX_AREA: i64 = 1 << 51;

    #[inline(always)]
    fn new(tri: &'t SetupTri, idx: u32, ef: &EdgeFns, tie: f32) -> Self {
        let (dz, [lo, hi]) = (tri.dz(), tri.range());
        // SAFETY: see `Lanes`.
        unsafe {
            Self {
                tri,
                idx: _mm256_set1_epi32(idx as i32),
                off: each(|i| _mm256_setr_epi64x(0, ef.sx[i], 2 * ef.sx[i], 3 * ef.sx[i])),
                step4: each(|i| _mm256_set1_epi64x(4 * ef.sx[i])),
                sy: each(|i| _mm256_set1_epi64x(ef.sy[i])),
                bias: each(|i| _mm256_set1_epi64x(ef.bias[i])),
                z0: _mm256_set1_pd(tri.z0()),
                dz: [_mm256_set1_pd(dz[0]), _mm256_set1_pd(dz[1])],
                lo: _mm256_set1_ps(lo),
                hi: _mm256_set1_ps(hi),
                tie: _mm256_set1_ps(tie),
            }
        }
    }

    #[inline(always)]
    fn row(&self, i: usize, e: i64) -> Self::Row {
        // SAFETY: see `Lanes`.
        unsafe {
            let lo = _mm256_add_epi64(_mm256_set1_epi64x(e), self.off[i]);
            [lo, _mm256_add_epi64(lo, self.step4[i])]
        }
    }

    #[inline(always)]
    fn down(&self, i: usize, [lo, hi]: Self::Row) -> Self::Row {
        // SAFETY: see `Lanes`.
        unsafe { [_mm256_add_epi64(lo, self.sy[i]), _mm256_add_epi64(hi, self.sy[i])] }
    }

    #[inline(always)]
    fn unbias(&self, i: usize, [lo, hi]: Self::Row) -> Self::Row {
        // SAFETY: see `Lanes`.
        unsafe { [_mm256_add_epi64(lo, self.bias[i]), _mm256_add_epi64(hi, self.bias[i])] }
    }

    #[inline(always)]
    fn inside(&self, r: &[Self::Row; 3]) -> u32 {
        // SAFETY: see `Lanes`.
        unsafe {
            let lo = _mm256_or_si256(_mm256_or_si256(r[0][0], r[1][0]), r[2][0]);
            let hi = _mm256_or_si256(_mm256_or_si256(r[0][1], r[1][1]), r[2][1]);
            // Sign bits of the ORs: set iff some edge value of the lane is negative.
            let outside = _mm256_movemask_pd(_mm256_castsi256_pd(lo))
                | _mm256_movemask_pd(_mm256_castsi256_pd(hi)) << 4;
            !(outside as u32) & 0xff
        }
    }

    #[inline(always)]
    fn test_row<const REVERSED: bool, const TIE: bool>(
        &self,
        zb: &mut ZBuffer<'t>,
        k: usize,
        covered: u32,
        e1: Self::Row,
        e2: Self::Row,
    ) {
        // SAFETY: see `Lanes`; the loads and stores access the 8 elements of `row_of` slices.
        unsafe {
            let d = _mm256_set_m128(self.depth4(e1[1], e2[1]), self.depth4(e1[0], e2[0]));
            let d = clamp_ps(d, self.lo, self.hi);

            let covered = lanes_avx2(covered);
            let cur = _mm256_loadu_ps(row_of(&mut zb.depth, k).as_ptr());
            let closer = _mm256_castps_si256(if REVERSED {
                _mm256_cmp_ps::<_CMP_GT_OQ>(d, cur)
            } else {
                _mm256_cmp_ps::<_CMP_LT_OQ>(d, cur)
            });
            // Lanes decided by the id: equal depths, or with `TIE` depths in the window (which
            // the depth comparison then must not decide).
            let tied = if TIE {
                tie_window::<REVERSED>(d, cur, self.tie)
            } else {
                _mm256_cmp_ps::<_CMP_EQ_OQ>(d, cur)
            };
            let ties = _mm256_and_si256(_mm256_castps_si256(tied), covered);
            let mut update = if TIE {
                _mm256_andnot_si256(ties, _mm256_and_si256(closer, covered))
            } else {
                _mm256_and_si256(closer, covered)
            };
            let ties = _mm256_movemask_ps(_mm256_castsi256_ps(ties)) as u32;
            if ties != 0 {
                let mut d_arr = [0.0f32; 8];
                _mm256_storeu_ps(d_arr.as_mut_ptr(), d);
                let won = tie_winners::<REVERSED, TIE>(zb, k, self.tri, &d_arr, ties);
                update = _mm256_or_si256(update, lanes_avx2(won));
            }
            let update = _mm256_castsi256_ps(update);
            let depth = row_of(&mut zb.depth, k);
            _mm256_storeu_ps(depth.as_mut_ptr(), _mm256_blendv_ps(cur, d, update));
            let win = row_of(&mut zb.win, k);
            let old = _mm256_castsi256_ps(_mm256_loadu_si256(win.as_ptr().cast()));
            let new = _mm256_blendv_ps(old, _mm256_castsi256_ps(self.idx), update);
            _mm256_storeu_si256(win.as_mut_ptr().cast(), _mm256_castps_si256(new));
        }
    }
}

/// The AVX-512 backend: a row is one vector of 8 `i64`, masks are mask registers, and the
/// `i64 -> f64` conversion is a single instruction rounding like `as f64`, so every triangle
/// can take it.
struct Avx512<'t> {
    tri: &'t SetupTri,
    idx: __m256i,
    /// `[0, s, .., 7 s]` for each edge's x step `s`.
    off: [__m512i; 3],
    /// Each edge's y step and fill-rule bias, in every lane.
    sy: [__m512i; 3],
    bias: [__m512i; 3],
    z0: __m512d,
    dz: [__m512d; 2],
    /// The clamp range and the tie window, in every lane.
    lo: __m256,
    hi: __m256,
    tie: __m256,
}

impl<'t> Lanes<'t> for Avx512<'t> {
    type Row = __m512i;
    const MAX_AREA: i64 = i64::MAX;

    #[inline(always)]
    fn new(tri: &'t SetupTri, idx: u32, ef: &EdgeFns, tie: f32) -> Self {
        let (dz, [lo, hi]) = (tri.dz(), tri.range());
        // SAFETY: see `Lanes`.
        unsafe {
            let j = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
            Self {
                tri,
                idx: _mm256_set1_epi32(idx as i32),
                // Exact: |7 s| < 2^40 (module docs of `setup`).
                off: each(|i| _mm512_mullo_epi64(j, _mm512_set1_epi64(ef.sx[i]))),
                sy: each(|i| _mm512_set1_epi64(ef.sy[i])),
                bias: each(|i| _mm512_set1_epi64(ef.bias[i])),
                z0: _mm512_set1_pd(tri.z0()),
                dz: [_mm512_set1_pd(dz[0]), _mm512_set1_pd(dz[1])],
                lo: _mm256_set1_ps(lo),
                hi: _mm256_set1_ps(hi),
                tie: _mm256_set1_ps(tie),
            }
        }
    }

    #[inline(always)]
    fn row(&self, i: usize, e: i64) -> Self::Row {
        // SAFETY: see `Lanes`.
        unsafe { _mm512_add_epi64(_mm512_set1_epi64(e), self.off[i]) }
    }

    #[inline(always)]
    fn down(&self, i: usize, r: Self::Row) -> Self::Row {
        // SAFETY: see `Lanes`.
        unsafe { _mm512_add_epi64(r, self.sy[i]) }
    }

    #[inline(always)]
    fn unbias(&self, i: usize, r: Self::Row) -> Self::Row {
        // SAFETY: see `Lanes`.
        unsafe { _mm512_add_epi64(r, self.bias[i]) }
    }

    #[inline(always)]
    fn inside(&self, r: &[Self::Row; 3]) -> u32 {
        // SAFETY: see `Lanes`.
        unsafe {
            // 0xfe: a | b | c. Its sign bit is set iff some edge value is negative.
            let any = _mm512_ternarylogic_epi64::<0xfe>(r[0], r[1], r[2]);
            u32::from(!_mm512_movepi64_mask(any))
        }
    }

    #[inline(always)]
    fn test_row<const REVERSED: bool, const TIE: bool>(
        &self,
        zb: &mut ZBuffer<'t>,
        k: usize,
        covered: u32,
        e1: Self::Row,
        e2: Self::Row,
    ) {
        // SAFETY: see `Lanes`; the loads and stores access the 8 elements of `row_of` slices.
        unsafe {
            // `(z0 + e1 dz0) + e2 dz1`, as `SetupTri::depth` (the conversions round like
            // `as f64`), rounded and clamped as in the AVX2 backend.
            let d = _mm512_add_pd(
                _mm512_add_pd(self.z0, _mm512_mul_pd(_mm512_cvtepi64_pd(e1), self.dz[0])),
                _mm512_mul_pd(_mm512_cvtepi64_pd(e2), self.dz[1]),
            );
            let d = clamp_ps(_mm512_cvtpd_ps(d), self.lo, self.hi);

            let covered = covered as __mmask8;
            let cur = _mm256_loadu_ps(row_of(&mut zb.depth, k).as_ptr());
            let closer = if REVERSED {
                _mm256_mask_cmp_ps_mask::<_CMP_GT_OQ>(covered, d, cur)
            } else {
                _mm256_mask_cmp_ps_mask::<_CMP_LT_OQ>(covered, d, cur)
            };
            // As in the AVX2 backend.
            let (mut update, ties) = if TIE {
                let ties = _mm256_movemask_ps(tie_window::<REVERSED>(d, cur, self.tie)) as __mmask8 & covered;
                (closer & !ties, ties)
            } else {
                (closer, _mm256_mask_cmp_ps_mask::<_CMP_EQ_OQ>(covered, d, cur))
            };
            if ties != 0 {
                let mut d_arr = [0.0f32; 8];
                _mm256_storeu_ps(d_arr.as_mut_ptr(), d);
                update |= tie_winners::<REVERSED, TIE>(zb, k, self.tri, &d_arr, u32::from(ties)) as __mmask8;
            }
            _mm256_mask_storeu_ps(row_of(&mut zb.depth, k).as_mut_ptr(), update, d);
            _mm256_mask_storeu_epi32(row_of(&mut zb.win, k).as_mut_ptr().cast(), update, self.idx);
        }
    }
}
