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
/// where a 4-neighbour holds the other decision.
///
/// # Panics
///
/// If `occ.len() != width * height`.
pub fn laplacian_border(occ: &[Decision], width: usize, height: usize) -> Vec<bool> {
    assert_eq!(occ.len(), width * height, "occlusion map size");
    let mut out = vec![false; occ.len()];
    if width == 0 {
        return out;
    }
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let at = |x: usize, y: usize| occ[y * width + x];
        for (x, b) in row.iter_mut().enumerate() {
            let v = at(x, y);
            let other = match v {
                Decision::Lit => Decision::Shadow,
                Decision::Shadow => Decision::Lit,
                Decision::NotNeeded => continue,
            };
            *b = (x > 0 && at(x - 1, y) == other)
                || (x + 1 < width && at(x + 1, y) == other)
                || (y > 0 && at(x, y - 1) == other)
                || (y + 1 < height && at(x, y + 1) == other);
        }
    });
    out
}

/// Marks every pixel within Chebyshev distance `r` of a `true` pixel of `mask` (row-major,
/// `width x height`): a square max filter, done as a horizontal then a vertical pass.
///
/// # Panics
///
/// If `mask.len() != width * height`.
pub fn dilate(mask: &[bool], width: usize, height: usize, r: usize) -> Vec<bool> {
    assert_eq!(mask.len(), width * height, "mask size");
    if r == 0 || width == 0 {
        return mask.to_vec();
    }
    // Horizontal: a pixel is marked if a marked pixel is within r in its row. Prefix counts make
    // it O(1) per pixel for any radius.
    let mut rows = vec![false; mask.len()];
    rows.par_chunks_mut(width).zip(mask.par_chunks(width)).for_each(|(out, row)| {
        let mut prefix = vec![0u32; width + 1];
        for (x, &m) in row.iter().enumerate() {
            prefix[x + 1] = prefix[x] + u32::from(m);
        }
        for (x, o) in out.iter_mut().enumerate() {
            let (a, b) = (x.saturating_sub(r), (x + r + 1).min(width));
            *o = prefix[b] > prefix[a];
        }
    });
    // Vertical, on the horizontal result, a row of output at a time.
    let mut out = vec![false; mask.len()];
    out.par_chunks_mut(width).enumerate().for_each(|(y, o)| {
        let (a, b) = (y.saturating_sub(r), (y + r + 1).min(height));
        for yy in a..b {
            for (o, &m) in o.iter_mut().zip(&rows[yy * width..(yy + 1) * width]) {
                *o |= m;
            }
        }
    });
    out
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

    #[test]
    fn empty_and_degenerate_sizes() {
        assert!(laplacian_border(&[], 0, 0).is_empty());
        assert!(dilate(&[], 0, 5, 2).is_empty());
        assert_eq!(laplacian_border(&[Decision::Shadow], 1, 1), vec![false]);
        assert_eq!(dilate(&[true], 1, 1, 3), vec![true]);
    }
}
