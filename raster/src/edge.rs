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

use crate::setup::{HALF_PIXEL, SUBPIXEL_ONE, SetupTri};

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
    fn new(a: [i32; 2], b: [i32; 2]) -> Self {
        let a = a.map(i64::from);
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

/// Calls `emit(px, py, [e0, e1, e2])` for every pixel of `[x0, x1) x [y0, y1)` whose centre the
/// triangle covers, with the unbiased edge functions there (`e_i`: edge opposite vertex `i`).
/// Pixels are visited block by block, each block in row-major order; each at most once.
#[inline]
pub(crate) fn raster_rect(
    tri: &SetupTri,
    [x0, y0, x1, y1]: [u32; 4],
    mut emit: impl FnMut(u32, u32, [i64; 3]),
) {
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let [v0, v1, v2] = tri.v;
    let edges = [Edge::new(v1, v2), Edge::new(v2, v0), Edge::new(v0, v1)];
    let sx = edges.map(|e| e.step_x());
    let sy = edges.map(|e| e.step_y());
    let bias = edges.map(|e| e.bias);
    let span = i64::from(BLOCK - 1);
    // Offsets from a block's top-left sample to its sample with the largest / smallest E.
    let max_off: [i64; 3] = std::array::from_fn(|i| (sx[i] * span).max(0) + (sy[i] * span).max(0));
    let min_off: [i64; 3] = std::array::from_fn(|i| (sx[i] * span).min(0) + (sy[i] * span).min(0));

    let mut by = y0 - y0 % BLOCK;
    while by < y1 {
        let mut bx = x0 - x0 % BLOCK;
        while bx < x1 {
            // Biased edge values at the block's top-left sample: inside iff >= 0.
            let e: [i64; 3] = std::array::from_fn(|i| edges[i].at_pixel(bx, by) - bias[i]);
            let rejected = (0..3).any(|i| e[i] + max_off[i] < 0);
            if !rejected {
                let accepted = (0..3).all(|i| e[i] + min_off[i] >= 0);
                // Part of the block inside the rectangle.
                let (px0, px1) = (bx.max(x0), (bx + BLOCK).min(x1));
                let (py0, py1) = (by.max(y0), (by + BLOCK).min(y1));
                let (dx, dy) = (i64::from(px0 - bx), i64::from(py0 - by));
                let mut row: [i64; 3] = std::array::from_fn(|i| e[i] + sx[i] * dx + sy[i] * dy);
                for py in py0..py1 {
                    let mut p = row;
                    for px in px0..px1 {
                        if accepted || (p[0] | p[1] | p[2]) >= 0 {
                            emit(px, py, [p[0] + bias[0], p[1] + bias[1], p[2] + bias[2]]);
                        }
                        for i in 0..3 {
                            p[i] += sx[i];
                        }
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
