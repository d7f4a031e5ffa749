//! Interleaved sampling's filter: each pixel of a `k x k` block gathers its own `1 / k^2` of the
//! VPLs, and a box filter over the block that keeps to one surface (similar normals and
//! distances) gives every pixel the light of all of them.

use glam::Vec3;
use rayon::prelude::*;

/// The geometry-aware `k x k` box filter of interleaved sampling (see [`super::indirect::run`]), on the
/// per-pixel sums `irr` of `k^2`-strided VPL subsets; `geo` holds each pixel's shading normal
/// and camera distance (0: no diffuse point).
pub(crate) fn filter(irr: &[Vec3], geo: &[[f32; 4]], w: usize, k: usize) -> Vec<Vec3> {
    let h = irr.len() / w;
    let lo = k / 2;
    let scale = (k * k) as f32;
    (0..irr.len())
        .into_par_iter()
        .map(|i| {
            let [nx, ny, nz, t] = geo[i];
            if t == 0.0 {
                return Vec3::ZERO;
            }
            let ns = Vec3::new(nx, ny, nz);
            let (x, y) = (i % w, i / w);
            let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
            // A window of k consecutive columns and rows holds every residue once; near the
            // image border it is shifted inside.
            let x0 = x.saturating_sub(lo).min(w.saturating_sub(k));
            let y0 = y.saturating_sub(lo).min(h.saturating_sub(k));
            for yy in y0..(y0 + k).min(h) {
                for xx in x0..(x0 + k).min(w) {
                    let j = yy * w + xx;
                    let [mx, my, mz, u] = geo[j];
                    if u != 0.0 && ns.dot(Vec3::new(mx, my, mz)) >= 0.9 && (t - u).abs() <= 0.05 * t {
                        sum += irr[j];
                        weight += 1.0;
                    }
                }
            }
            // The pixel itself always passes, so `weight >= 1`. Each pixel's subset sum times
            // `k^2` estimates the full sum; the filter returns the mean of those estimates.
            sum * (scale / weight)
        })
        .collect()
}
