//! Rays cast per pixel, by kind: for inspection (`Options::keep_buffers`), e.g. the inspector's
//! rays-per-pixel heat maps.
//!
//! Every pass that casts rays on behalf of a pixel adds what it cast (the difference of its ray
//! counter around the pixel's work): the primary ray, the camera hit's shadow rays (all of
//! them, or the border rays of SMeRTS), its VPL shadow rays, and everything its mirror path
//! cast. The VPL path rays belong to no pixel and are not included; `--check-visibility`'s
//! extra rays are not frame rays and are not included either. So the per-pixel counts sum to
//! the frame's counts minus the VPL path rays (a test holds them to it).

use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use hyrt_tracer::RayCounts;
use rayon::prelude::*;

/// Per-pixel ray counters; empty (and free: one bounds check per pixel) unless enabled.
#[derive(Debug, Default)]
pub(crate) struct PixelRays {
    /// Per pixel: primary, shadow, of which hint hits, specular, VPL shadow.
    counts: Vec<[AtomicU32; 5]>,
}

impl PixelRays {
    /// Counters for `n` pixels, or none.
    pub fn new(n: usize, enabled: bool) -> Self {
        let counts = if enabled { (0..n).map(|_| Default::default()).collect() } else { Vec::new() };
        Self { counts }
    }

    pub fn enabled(&self) -> bool {
        !self.counts.is_empty()
    }

    /// Zeroes every counter (start of a frame).
    pub fn clear(&self) {
        self.counts.par_iter().for_each(|c| c.iter().for_each(|a| a.store(0, Relaxed)));
    }

    /// Adds to pixel `i` the rays counted between `before` and `after` (the same counter).
    /// Atomic adds: the passes run rows in parallel, and sums do not depend on their order.
    #[inline]
    pub fn add(&self, i: usize, before: &RayCounts, after: &RayCounts) {
        let Some(c) = self.counts.get(i) else { return };
        let d = [
            after.primary - before.primary,
            after.shadow - before.shadow,
            after.shadow_hint_hits - before.shadow_hint_hits,
            after.specular - before.specular,
            after.vpl_shadow - before.vpl_shadow,
        ];
        for (a, v) in c.iter().zip(d) {
            if v > 0 {
                a.fetch_add(v as u32, Relaxed);
            }
        }
    }

    /// The counts of every pixel (`vpl_path` is always 0).
    pub fn snapshot(&self) -> Vec<RayCounts> {
        self.counts
            .par_iter()
            .map(|c| {
                let v = |k: usize| u64::from(c[k].load(Relaxed));
                RayCounts {
                    primary: v(0),
                    shadow: v(1),
                    shadow_hint_hits: v(2),
                    specular: v(3),
                    vpl_shadow: v(4),
                    vpl_path: 0,
                }
            })
            .collect()
    }
}
