//! The borders pass: the (pixel, light) pairs a shadow ray decides.

use hyrt_shadowmap::border;

use super::{ShadowBuffers, bit};
use crate::render::{Borders, Renderer};

impl Renderer<'_> {
    /// The borders pass: the (pixel, light) pairs that a shadow ray decides, `bufs.und`, from
    /// the map-space test (`bufs.edge`) and/or the screen-space Laplacian of the decisions,
    /// dilated; eight lights per byte operation ([`border::laplacian_border_bits`],
    /// [`border::dilate_bits`]). With `keep_buffers`, also the border before
    /// dilation.
    pub(crate) fn borders(&self, bufs: &mut ShadowBuffers, w: usize, h: usize) {
        let opts = &self.options.shadow;
        let n = w * h;
        let nl = self.lights.len();
        let stride = bufs.faces.stride;
        let (faces, lit, edge) = (&bufs.faces.bits, &bufs.lit.bits, &bufs.edge.bits);
        // `und` comes from classify cleared, sized as `faces`. The map-space bits are already
        // limited to pixels with a decision.
        let und = &mut bufs.und.bits;
        if opts.borders != Borders::Laplacian {
            und.copy_from_slice(edge);
        }
        if opts.borders != Borders::MapSpace {
            border::laplacian_border_bits(faces, lit, stride, w, h, und);
        }
        if self.options.keep_buffers {
            bufs.border = (0..nl).map(|l| (0..n).map(|i| bit(&und[i * stride..], l)).collect()).collect();
        }
        // Then only the pixels with a decision (a border without dilation has no others).
        if opts.dilate > 0 {
            border::dilate_bits(und, Some(faces), stride, w, h, opts.dilate as usize);
        }
    }
}
