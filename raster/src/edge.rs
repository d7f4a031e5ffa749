//! Edge functions, the top-left fill rule, and the traversal of a triangle over a pixel rectangle
//! with hierarchical 8x8 block rejection/acceptance.
//!
//! # Edge functions
//!
//! For a directed edge `a -> b` and a point `p` (all fixed point, y down), the edge function is
//!
//! ```text
//!     E_ab(p) = (b.x - a.x) (p.y - a.y) - (b.y - a.y) (p.x - a.x) = cross(b - a, p - a)
//! ```
//!
//! twice the signed area of `(a, b, p)`. It is affine in `p`: one pixel step right adds
//! `-(b.y - a.y) * ONE`, one step down adds `(b.x - a.x) * ONE`, so it can be evaluated once per
//! block and then stepped with integer additions. Setup orients every triangle so that
//! `E_01(v2) = area > 0`; a sample is inside when all three edge functions are positive, and the
//! three values, one per edge opposite each vertex, are the unnormalised screen-space
//! barycentrics (`e0 + e1 + e2 = area` exactly).
//!
//! All values are exact in `i64` (bounds derived in [`crate::setup`]: `|E| < 2^60`), so coverage is
//! decided without rounding, independently of the evaluation order, the tile or the thread.
//!
//! # Fill rule
//!
//! A sample exactly on an edge (`E = 0`) belongs to the triangle only if that edge is a *top* edge
//! (horizontal, with the interior below it) or a *left* edge (interior to its right), the D3D /
//! OpenGL top-left rule. With positive orientation and y down, `E_ab(p) = d.x (p.y - a.y) - d.y
//! (p.x - a.x)` with `d = b - a`:
//!
//! * horizontal edge (`d.y = 0`), interior below (`p.y > a.y`): `E > 0` needs `d.x > 0`;
//! * interior to the right of the edge (`p.x > a.x` on a horizontal line): `E > 0` needs `d.y < 0`.
//!
//! So `a -> b` is top-left iff `d.y < 0 || (d.y == 0 && d.x > 0)`. Two triangles sharing an edge
//! on opposite sides see it with opposite directions `d` and `-d`, their edge functions are exact
//! negatives of each other, and exactly one of `d`, `-d` is top-left: a sample on the shared
//! edge is owned by exactly one of them, and a sample off it by the one whose side it is on. That
//! is what makes meshes watertight without double hits. The rule is applied as an integer bias:
//! inside iff `E - bias >= 0` with `bias = 0` for top-left edges and `1` otherwise (values are
//! integers, so `E - 1 >= 0` is `E > 0`).
//!
//! # Hierarchical traversal (Abrash, "Rasterization on Larrabee")
//!
//! The rectangle is walked in 8x8 blocks aligned to the pixel grid. Because `E` is affine, its
//! extreme values over the block's 64 sample points are at two opposite corners, found from the
//! signs of the steps. If the largest value of some edge is negative, no sample in the block is
//! inside (reject); if the smallest values of all three edges are inside, every sample is (accept,
//! no per-pixel tests); otherwise the block is walked pixel by pixel with incremental stepping.

use crate::setup::{HALF_PIXEL, SUBPIXEL_ONE, SetupTri, cross};

/// Side of the square blocks used for hierarchical rejection/acceptance.
pub(crate) const BLOCK: u32 = 8;

/// One directed edge `a -> b` of a positively oriented triangle.
#[derive(Clone, Copy, Debug)]
struct Edge {
    a: [i64; 2],
    d: [i64; 2],
    /// 0 for top-left edges, 1 otherwise.
    bias: i64,
}

impl Edge {
    #[inline]
    fn new(a: [i32; 2], b: [i32; 2]) -> Self {
        let a = [i64::from(a[0]), i64::from(a[1])];
        let d = [i64::from(b[0]) - a[0], i64::from(b[1]) - a[1]];
        let top_left = d[1] < 0 || (d[1] == 0 && d[0] > 0);
        Self { a, d, bias: i64::from(!top_left) }
    }

    /// Unbiased `E_ab` at the centre of pixel `(px, py)`.
    #[inline]
    fn at_pixel(&self, px: u32, py: u32) -> i64 {
        let x = i64::from(px) * SUBPIXEL_ONE + HALF_PIXEL;
        let y = i64::from(py) * SUBPIXEL_ONE + HALF_PIXEL;
        self.d[0] * (y - self.a[1]) - self.d[1] * (x - self.a[0])
    }

    /// Change of `E` for one pixel to the right.
    #[inline]
    fn step_x(&self) -> i64 {
        -self.d[1] * SUBPIXEL_ONE
    }

    /// Change of `E` for one pixel down.
    #[inline]
    fn step_y(&self) -> i64 {
        self.d[0] * SUBPIXEL_ONE
    }
}

/// The three edge functions of a set-up triangle (`e_i`: the edge opposite vertex `i`), with
/// their steps and fill-rule biases.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeFns {
    edges: [Edge; 3],
    /// Change of each `e_i` for one pixel to the right.
    pub sx: [i64; 3],
    /// Change of each `e_i` for one pixel down.
    pub sy: [i64; 3],
    /// Fill-rule bias of each edge: a sample is inside iff `e_i - bias_i >= 0` for all `i`.
    pub bias: [i64; 3],
    /// `e0 + e1 + e2` at every sample: twice the triangle's area, `> 0`. Each `e_i` of a covered
    /// sample is in `[0, area]` (all three are `>= bias_i >= 0` and they add up to `area`).
    pub area: i64,
}

impl EdgeFns {
    #[inline]
    pub fn new(tri: &SetupTri) -> Self {
        let [v0, v1, v2] = tri.v;
        let edges = [Edge::new(v1, v2), Edge::new(v2, v0), Edge::new(v0, v1)];
        let [e0, e1, e2] = &edges;
        let wide = |v: [i32; 2]| [i64::from(v[0]), i64::from(v[1])];
        Self {
            edges,
            sx: [e0.step_x(), e1.step_x(), e2.step_x()],
            sy: [e0.step_y(), e1.step_y(), e2.step_y()],
            bias: [e0.bias, e1.bias, e2.bias],
            area: cross(wide(v0), wide(v1), wide(v2)),
        }
    }

    /// Unbiased `[e0, e1, e2]` at the centre of pixel `(px, py)`.
    #[inline]
    pub fn at_pixel(&self, px: u32, py: u32) -> [i64; 3] {
        let [e0, e1, e2] = &self.edges;
        [e0.at_pixel(px, py), e1.at_pixel(px, py), e2.at_pixel(px, py)]
    }
}

/// Bit mask with the lowest `n` bits set, `n <= 8`.
#[inline]
pub(crate) fn low_bits(n: u32) -> u32 {
    (1 << n) - 1
}

/// Coverage of a row from pixel `x` on: bit `j` of the result is set iff pixel `x + j`,
/// `j < n <= 8`, is inside. `row` holds the biased edge values at pixel `x`, `sx` their steps.
#[inline]
pub(crate) fn row_mask(row: [i64; 3], sx: &[i64; 3], n: u32) -> u32 {
    let mut p = row;
    let mut mask = 0;
    for j in 0..n {
        // Inside iff all three biased values are >= 0, i.e. the sign bit of their OR is clear.
        mask |= u32::from((p[0] | p[1] | p[2]) >= 0) << j;
        for i in 0..3 {
            p[i] += sx[i];
        }
    }
    mask
}

/// Walks the pixels of `[x0, x1) x [y0, y1)` whose centre the triangle covers, as *spans*: calls
/// `span(x, y, mask, e)` where bit `j` of `mask` (never 0, `j < 8`) is set iff pixel `(x + j, y)`
/// is covered, and `e` are the unbiased edge functions at pixel `(x, y)` (which need not be
/// covered itself; the values at `x + j` are `e + j * ef.sx`). Every covered pixel is reported
/// exactly once, block by block, each block in row-major order.
///
/// Rectangles of at most 8x8 pixels (most triangles of a detailed mesh) are tested pixel by pixel
/// from their corner; larger ones are walked in 8x8 blocks aligned to the pixel grid, with
/// whole-block rejection and acceptance (module docs). Coverage is decided by the exact integer
/// sign tests either way, so the two give the same pixels.
///
/// `row_mask(row, n)` must return [`row_mask`]`(row, &ef.sx, n)`; it is a parameter so that
/// callers can pass a vectorised implementation.
#[inline(always)]
pub(crate) fn cover_rect(
    ef: &EdgeFns,
    [x0, y0, x1, y1]: [u32; 4],
    row_mask: impl Fn([i64; 3], u32) -> u32,
    mut span: impl FnMut(u32, u32, u32, [i64; 3]),
) {
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let (sx, sy, bias) = (&ef.sx, &ef.sy, &ef.bias);
    let unbias = |p: [i64; 3]| [p[0] + bias[0], p[1] + bias[1], p[2] + bias[2]];

    if x1 - x0 <= BLOCK && y1 - y0 <= BLOCK {
        let e = ef.at_pixel(x0, y0);
        let mut row = [e[0] - bias[0], e[1] - bias[1], e[2] - bias[2]];
        for y in y0..y1 {
            let mask = row_mask(row, x1 - x0);
            if mask != 0 {
                span(x0, y, mask, unbias(row));
            }
            for i in 0..3 {
                row[i] += sy[i];
            }
        }
        return;
    }

    let span_len = i64::from(BLOCK - 1);
    // Offsets from a block's top-left sample to its sample with the largest / smallest E.
    let max_off: [i64; 3] = std::array::from_fn(|i| (sx[i] * span_len).max(0) + (sy[i] * span_len).max(0));
    let min_off: [i64; 3] = std::array::from_fn(|i| (sx[i] * span_len).min(0) + (sy[i] * span_len).min(0));

    let mut by = y0 - y0 % BLOCK;
    while by < y1 {
        let mut bx = x0 - x0 % BLOCK;
        while bx < x1 {
            // Biased edge values at the block's top-left sample: inside iff >= 0.
            let e = ef.at_pixel(bx, by);
            let e: [i64; 3] = std::array::from_fn(|i| e[i] - bias[i]);
            let rejected = (0..3).any(|i| e[i] + max_off[i] < 0);
            if !rejected {
                let accepted = (0..3).all(|i| e[i] + min_off[i] >= 0);
                // Part of the block inside the rectangle.
                let (px0, px1) = (bx.max(x0), (bx + BLOCK).min(x1));
                let (py0, py1) = (by.max(y0), (by + BLOCK).min(y1));
                let (dx, dy) = (i64::from(px0 - bx), i64::from(py0 - by));
                let mut row: [i64; 3] = std::array::from_fn(|i| e[i] + sx[i] * dx + sy[i] * dy);
                let full = low_bits(px1 - px0);
                for py in py0..py1 {
                    let mask = if accepted { full } else { row_mask(row, px1 - px0) };
                    if mask != 0 {
                        span(px0, py, mask, unbias(row));
                    }
                    for i in 0..3 {
                        row[i] += sy[i];
                    }
                }
            }
            bx += BLOCK;
        }
        by += BLOCK;
    }
}

/// Calls `emit(px, py, [e0, e1, e2])` for every pixel of `[x0, x1) x [y0, y1)` whose centre the
/// triangle covers, with the unbiased edge functions there (`e_i`: edge opposite vertex `i`).
/// Pixels are visited in the order of [`cover_rect`]; each at most once.
#[inline]
pub(crate) fn raster_rect(tri: &SetupTri, rect: [u32; 4], mut emit: impl FnMut(u32, u32, [i64; 3])) {
    let ef = EdgeFns::new(tri);
    cover_rect(
        &ef,
        rect,
        |row, n| row_mask(row, &ef.sx, n),
        |x, y, mask, e| {
            let mut m = mask;
            while m != 0 {
                let j = m.trailing_zeros();
                let dj = i64::from(j);
                emit(x + j, y, [e[0] + ef.sx[0] * dj, e[1] + ef.sx[1] * dj, e[2] + ef.sx[2] * dj]);
                m &= m - 1;
            }
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(a: [i32; 2], b: [i32; 2]) -> Edge {
        Edge::new(a, b)
    }

    #[test]
    fn top_left_classification() {
        // Triangle (0,0) (10,0) (0,10) in y-down pixels is positively oriented: top edge 0->1,
        // left edge 2->0, hypotenuse 1->2 is bottom-right.
        let s = SUBPIXEL_ONE as i32;
        let (v0, v1, v2) = ([0, 0], [10 * s, 0], [0, 10 * s]);
        assert_eq!(edge(v0, v1).bias, 0);
        assert_eq!(edge(v2, v0).bias, 0);
        assert_eq!(edge(v1, v2).bias, 1);
        // Reversed edges flip the classification.
        assert_eq!(edge(v1, v0).bias, 1);
        assert_eq!(edge(v0, v2).bias, 1);
        assert_eq!(edge(v2, v1).bias, 0);
    }

    #[test]
    fn steps_match_direct_evaluation() {
        let e = edge([123, -456], [7890, 3456]);
        assert_eq!(e.at_pixel(5, 9) + e.step_x(), e.at_pixel(6, 9));
        assert_eq!(e.at_pixel(5, 9) + e.step_y(), e.at_pixel(5, 10));
    }
}
