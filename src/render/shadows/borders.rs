//! The borders pass: the (pixel, light) pairs a shadow ray decides.

use rayon::prelude::*;

use super::{ShadowBuffers, bit};
use crate::render::{Borders, Renderer, Shadows};

impl Renderer<'_> {
    /// The borders pass: the (pixel, light) pairs that a shadow ray decides, `bufs.und`, from
    /// the map-space test (`bufs.edge`) and/or the screen-space Laplacian of the decisions,
    /// dilated; eight lights per byte operation. With `keep_buffers`, also the border before
    /// dilation.
    pub(super) fn borders(&self, bufs: &mut ShadowBuffers, w: usize, h: usize) {
        let opts = &self.options.shadow;
        let n = w * h;
        let nl = self.lights.len();
        bufs.border.clear();
        if self.options.shadows != Shadows::Smerts {
            bufs.und.reset(n, nl);
            return;
        }
        let stride = bufs.faces.stride;
        let (faces, lit, edge) = (&bufs.faces.bits, &bufs.lit.bits, &bufs.edge.bits);
        bufs.und.stride = stride;
        let und = &mut bufs.und.bits;
        und.clear();
        und.resize(n * stride, 0);
        // The Laplacian on a binary map is non-zero exactly where a 4-neighbour with a decision
        // has the other one (`hyrt_shadowmap::border`); the map-space bits are already limited
        // to pixels with a decision.
        let laplacian = opts.borders != Borders::MapSpace;
        let map_space = opts.borders != Borders::Laplacian;
        und.par_chunks_mut((w * stride).max(1)).enumerate().for_each(|(y, row)| {
            for x in 0..w {
                let p = y * w + x;
                for b in 0..stride {
                    let k = p * stride + b;
                    let mut o = if map_space { edge[k] } else { 0 };
                    if laplacian && faces[k] != 0 {
                        let (f, li) = (faces[k], lit[k]);
                        let mut differ =
                            |q: usize| o |= f & faces[q * stride + b] & (li ^ lit[q * stride + b]);
                        if x > 0 {
                            differ(p - 1);
                        }
                        if x + 1 < w {
                            differ(p + 1);
                        }
                        if y > 0 {
                            differ(p - w);
                        }
                        if y + 1 < h {
                            differ(p + w);
                        }
                    }
                    row[x * stride + b] = o;
                }
            }
        });
        if self.options.keep_buffers {
            bufs.border = (0..nl).map(|l| (0..n).map(|i| bit(&und[i * stride..], l)).collect()).collect();
        }
        let r = opts.dilate as usize;
        if r > 0 {
            // A square max filter: a horizontal then a vertical pass of byte ORs, then only the
            // pixels with a decision.
            let mut rows = vec![0u8; n * stride];
            rows.par_chunks_mut((w * stride).max(1)).zip(und.par_chunks((w * stride).max(1))).for_each(
                |(out, row)| {
                    for x in 0..w {
                        for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                            for b in 0..stride {
                                out[x * stride + b] |= row[xx * stride + b];
                            }
                        }
                    }
                },
            );
            und.par_chunks_mut((w * stride).max(1)).enumerate().for_each(|(y, out)| {
                out.fill(0);
                for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                    for (o, &m) in out.iter_mut().zip(&rows[yy * w * stride..(yy + 1) * w * stride]) {
                        *o |= m;
                    }
                }
                for (o, &f) in out.iter_mut().zip(&faces[y * w * stride..(y + 1) * w * stride]) {
                    *o &= f;
                }
            });
        }
    }
}
