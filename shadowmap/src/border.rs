//! Shadow borders in screen space: the thesis's Laplacian test on a per-light occlusion map, and
//! dilation of the border.
//!
//! An occlusion map holds, per pixel, whether the light's depth map said [`Decision::Lit`] or
//! [`Decision::Shadow`], or [`Decision::NotNeeded`] (no surface, or the light is behind it). Shadow-map
//! aliasing is confined to where the decision changes, so those pixels are the ones to check with
//! real rays.
//!
//! # The Laplace kernel on a binary map
//!
//! The thesis convolves the map with `[[0,-1,0],[-1,4,-1],[0,-1,0]]` and calls a non-zero
//! response a border: `L(p) = sum over the 4 neighbours q of (v(p) - v(q))`. With values in
//! `{0, 1}` every term has the sign of `v(p)` (all `>= 0` for `v(p) = 1`, all `<= 0` for `0`), so
//! the sum vanishes exactly when every neighbour equals `v(p)`: a pixel is a border pixel iff one
//! of its 4 neighbours has the other decision. That is what [`laplacian_border`] computes,
//! without arithmetic. Neighbours outside the image or with no decision do not count (they carry
//! nothing to disagree with); a pixel with no decision is never a border.
//!
//! # Dilation
//!
//! [`dilate`] marks every pixel within Chebyshev distance `r` of a marked one (radius 1: the 8
//! neighbours, as the thesis). It reads only the input mask, so marks do not cascade.

use rayon::prelude::*;

pub use crate::classify::Decision;

/// Border pixels of a row-major `width x height` occlusion map (see the module docs): `true`
/// where a 4-neighbour holds the other decision. One light of [`laplacian_border_bits`].
///
/// # Panics
///
/// If `occ.len() != width * height`.
pub fn laplacian_border(occ: &[Decision], width: usize, height: usize) -> Vec<bool> {
    assert_eq!(occ.len(), width * height, "occlusion map size");
    let faces: Vec<u8> = occ.iter().map(|&d| u8::from(d != Decision::NotNeeded)).collect();
    let lit: Vec<u8> = occ.iter().map(|&d| u8::from(d == Decision::Lit)).collect();
    let mut out = vec![0u8; occ.len()];
    laplacian_border_bits(&faces, &lit, 1, width, height, &mut out);
    out.into_iter().map(|b| b != 0).collect()
}

/// [`laplacian_border`] of up to `8 stride` lights at once, eight per byte operation. Each
/// pixel has `stride` bytes in each buffer, light `l` in bit `l % 8` of byte `l / 8`: `faces`
/// says which lights have a decision there (not [`Decision::NotNeeded`]), `lit` which of those
/// are lit. The border bits are ORed into `out` (so that a caller may start from other borders).
///
/// # Panics
///
/// If a buffer does not hold `width * height * stride` bytes.
pub fn laplacian_border_bits(
    faces: &[u8],
    lit: &[u8],
    stride: usize,
    width: usize,
    height: usize,
    out: &mut [u8],
) {
    let n = width * height * stride;
    assert!(faces.len() == n && lit.len() == n && out.len() == n, "bit buffer sizes");
    if n == 0 {
        return;
    }
    out.par_chunks_mut(width * stride).enumerate().for_each(|(y, row)| {
        for x in 0..width {
            let p = y * width + x;
            for b in 0..stride {
                let k = p * stride + b;
                let f = faces[k];
                if f == 0 {
                    continue;
                }
                let li = lit[k];
                let mut o = 0;
                let mut differ = |q: usize| o |= f & faces[q * stride + b] & (li ^ lit[q * stride + b]);
                if x > 0 {
                    differ(p - 1);
                }
                if x + 1 < width {
                    differ(p + 1);
                }
                if y > 0 {
                    differ(p - width);
                }
                if y + 1 < height {
                    differ(p + width);
                }
                row[x * stride + b] |= o;
            }
        }
    });
}

/// Marks every pixel within Chebyshev distance `r` of a `true` pixel of `mask` (row-major,
/// `width x height`): a square max filter. One light of [`dilate_bits`].
///
/// # Panics
///
/// If `mask.len() != width * height`.
pub fn dilate(mask: &[bool], width: usize, height: usize, r: usize) -> Vec<bool> {
    assert_eq!(mask.len(), width * height, "mask size");
    let mut bits: Vec<u8> = mask.iter().map(|&m| u8::from(m)).collect();
    dilate_bits(&mut bits, None, 1, width, height, r);
    bits.into_iter().map(|b| b != 0).collect()
}

/// [`dilate`] of up to `8 stride` lights at once (bits laid out as in
/// [`laplacian_border_bits`]), in place: a horizontal then a vertical pass of byte ORs. With
/// `within`, only its bits are kept (the pixels with a decision).
///
/// # Panics
///
/// If `mask` (or `within`) does not hold `width * height * stride` bytes.
pub fn dilate_bits(
    mask: &mut [u8],
    within: Option<&[u8]>,
    stride: usize,
    width: usize,
    height: usize,
    r: usize,
) {
    let n = width * height * stride;
    assert!(mask.len() == n && within.is_none_or(|w| w.len() == n), "bit buffer sizes");
    if r == 0 || n == 0 {
        if let Some(w) = within {
            mask.iter_mut().zip(w).for_each(|(m, &w)| *m &= w);
        }
        return;
    }
    let row_bytes = width * stride;
    // Horizontal: a pixel is marked if a marked pixel is within r in its row.
    let mut rows = vec![0u8; n];
    rows.par_chunks_mut(row_bytes).zip(mask.par_chunks(row_bytes)).for_each(|(out, row)| {
        for x in 0..width {
            for xx in x.saturating_sub(r)..(x + r + 1).min(width) {
                for b in 0..stride {
                    out[x * stride + b] |= row[xx * stride + b];
                }
            }
        }
    });
    // Vertical, on the horizontal result, a row of output at a time.
    mask.par_chunks_mut(row_bytes).enumerate().for_each(|(y, out)| {
        out.fill(0);
        for yy in y.saturating_sub(r)..(y + r + 1).min(height) {
            for (o, &m) in out.iter_mut().zip(&rows[yy * row_bytes..(yy + 1) * row_bytes]) {
                *o |= m;
            }
        }
        if let Some(w) = within {
            for (o, &f) in out.iter_mut().zip(&w[y * row_bytes..(y + 1) * row_bytes]) {
                *o &= f;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shortcut equals the thesis's convolution on every 3x3 binary pattern (with NONE
    /// pixels excluded from the sum).
    #[test]
    fn border_is_the_nonzero_laplacian() {
        for bits in 0u32..(1 << 9) {
            let occ: Vec<Decision> =
                (0..9).map(|i| if bits >> i & 1 == 1 { Decision::Shadow } else { Decision::Lit }).collect();
            let b = laplacian_border(&occ, 3, 3);
            let v = |x: usize, y: usize| i32::from(occ[y * 3 + x] as u8);
            let lap = 4 * v(1, 1) - v(0, 1) - v(2, 1) - v(1, 0) - v(1, 2);
            assert_eq!(b[4], lap != 0, "pattern {bits:09b}");
        }
    }

    #[test]
    fn none_pixels_neither_are_nor_make_borders() {
        use Decision::{Lit as LIT, NotNeeded as NONE, Shadow as SHADOW};
        let occ = [LIT, NONE, SHADOW, NONE, NONE, NONE];
        assert_eq!(laplacian_border(&occ, 3, 2), vec![false; 6]);
        let occ = [LIT, SHADOW, NONE];
        assert_eq!(laplacian_border(&occ, 3, 1), vec![true, true, false]);
    }

    #[test]
    fn a_shadow_edge_gives_a_two_pixel_wide_border() {
        let (w, h) = (8, 5);
        let occ: Vec<Decision> =
            (0..w * h).map(|i| if i % w < 3 { Decision::Shadow } else { Decision::Lit }).collect();
        let b = laplacian_border(&occ, w, h);
        for y in 0..h {
            for x in 0..w {
                assert_eq!(b[y * w + x], x == 2 || x == 3, "({x}, {y})");
            }
        }
    }

    #[test]
    fn dilation_is_a_square_window_and_does_not_cascade() {
        let (w, h) = (9, 7);
        let mut mask = vec![false; w * h];
        mask[3 * w + 4] = true;
        for r in 0..4 {
            let d = dilate(&mask, w, h, r);
            for y in 0..h {
                for x in 0..w {
                    let inside = x.abs_diff(4) <= r && y.abs_diff(3) <= r;
                    assert_eq!(d[y * w + x], inside, "r {r} at ({x}, {y})");
                }
            }
        }
        // Corners clip at the image border.
        let mut mask = vec![false; w * h];
        mask[0] = true;
        assert_eq!(dilate(&mask, w, h, 1).iter().filter(|&&m| m).count(), 4);
    }

    /// Many lights packed eight to a byte give, light by light, what one light alone gives
    /// (so the renderer's packed pass is these tested functions).
    #[test]
    fn packed_lights_equal_one_light_at_a_time() {
        let (w, h, lights) = (23usize, 17usize, 19usize);
        let stride = lights.div_ceil(8);
        // A fixed pseudo-random pattern per light: decisions, lit, and none.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let occ: Vec<Vec<Decision>> = (0..lights)
            .map(|_| {
                (0..w * h)
                    .map(|_| match next() % 5 {
                        0 => Decision::NotNeeded,
                        1 | 2 => Decision::Lit,
                        _ => Decision::Shadow,
                    })
                    .collect()
            })
            .collect();
        let pack = |f: &dyn Fn(usize, usize) -> bool| -> Vec<u8> {
            let mut v = vec![0u8; w * h * stride];
            for (l, i) in (0..lights).flat_map(|l| (0..w * h).map(move |i| (l, i))) {
                if f(l, i) {
                    v[i * stride + l / 8] |= 1 << (l % 8);
                }
            }
            v
        };
        let faces = pack(&|l, i| occ[l][i] != Decision::NotNeeded);
        let lit = pack(&|l, i| occ[l][i] == Decision::Lit);
        let mut border = vec![0u8; w * h * stride];
        laplacian_border_bits(&faces, &lit, stride, w, h, &mut border);
        let one: Vec<Vec<bool>> = occ.iter().map(|o| laplacian_border(o, w, h)).collect();
        assert_eq!(border, pack(&|l, i| one[l][i]));
        for r in 0..3 {
            let mut dilated = border.clone();
            dilate_bits(&mut dilated, Some(&faces), stride, w, h, r);
            let one: Vec<Vec<bool>> = one.iter().map(|b| dilate(b, w, h, r)).collect();
            assert_eq!(dilated, pack(&|l, i| one[l][i] && occ[l][i] != Decision::NotNeeded), "r {r}");
        }
    }

    #[test]
    fn empty_and_degenerate_sizes() {
        assert!(laplacian_border(&[], 0, 0).is_empty());
        assert!(dilate(&[], 0, 5, 2).is_empty());
        assert_eq!(laplacian_border(&[Decision::Shadow], 1, 1), vec![false]);
        assert_eq!(dilate(&[true], 1, 1, 3), vec![true]);
    }
}
