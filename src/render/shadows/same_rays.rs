//! What a border ray costs against the reference's shadow rays, on the same rays.
//!
//! Why: the border rays are the frame's hardest shadow rays by selection: each passes by the
//! silhouette of an occluder (the map could not tell), where the BVH's boxes overlap the most.
//! The reference's shadow rays are mostly easy ones (wide open, or deep behind one occluder).
//! A border ray's cost per ray against the reference's average then says more about which
//! rays were chosen than about how they are traced. Tracing the very border rays the way the
//! reference traces its own tells the two apart.

use std::time::Instant;

use hyrt_shadowmap::classify::Decision;
use hyrt_tracer::{Ray, RayCounts, RayKind, spawn_ray_to};
use serde::Serialize;

use crate::metrics::Timing;
use crate::render::{Frame, Renderer};

/// CPU nanoseconds per shadow ray of one frame's rays, traced on one thread with no shading,
/// in one process (runs alternated, medians; [`Renderer::same_rays`]).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct SameRays {
    /// The frame's border rays: its undecided (pixel, light) pairs.
    pub border_rays: u64,
    /// The border rays traced as the reference traces its shadow rays (no hint).
    pub border_plain_ns: f64,
    /// The border rays traced as the border-ray pass does (its occluder hint first).
    pub border_hint_ns: f64,
    /// Every (pixel, light) pair of the frame with a decision: the shadow rays the reference
    /// casts for those pixels.
    pub all_rays: u64,
    /// Those traced as the reference does.
    pub all_plain_ns: f64,
}

impl Renderer<'_> {
    /// [`SameRays`] of `frame`, which must have been rendered by this renderer with
    /// `Options::keep_buffers` and map-based shadows (`None` otherwise, or without any border
    /// ray); `runs` runs of each set, alternated.
    pub fn same_rays(&self, frame: &Frame, runs: usize) -> Option<SameRays> {
        let (shadows, gbuffer) = (frame.shadows.as_ref()?, frame.gbuffer.as_ref()?);
        let nl = self.lights.len();
        if shadows.undecided.len() != nl || shadows.hint.len() != nl {
            return None;
        }
        // The border rays in the border-ray pass's order (light by light, each in screen
        // order), with their hints; every pair's ray in the reference's (pixel by pixel).
        let point = |i: usize| self.shading_point(gbuffer, i);
        let mut border: Vec<(Ray, u32)> = Vec::new();
        for (l, light) in self.lights.iter().enumerate() {
            for (i, _) in shadows.undecided[l].iter().enumerate().filter(|(_, u)| **u) {
                let Some(s) = point(i) else { continue };
                border.push((spawn_ray_to(s.p, s.p_err, s.ng, light.position), shadows.hint[l][i]));
            }
        }
        if border.is_empty() {
            return None;
        }
        let mut all: Vec<Ray> = Vec::new();
        for i in 0..gbuffer.len() {
            let decided = |l: usize| shadows.occ[l][i] != Decision::NotNeeded;
            if !(0..nl).any(decided) {
                continue;
            }
            let Some(s) = point(i) else { continue };
            for (_, light) in self.lights.iter().enumerate().filter(|(l, _)| decided(*l)) {
                all.push(spawn_ray_to(s.p, s.p_err, s.ng, light.position));
            }
        }
        // The answers are summed so that no trace is optimised away.
        let time = |f: &mut dyn FnMut() -> usize, n: usize| {
            let start = Instant::now();
            std::hint::black_box(f());
            start.elapsed().as_secs_f64() * 1e9 / n.max(1) as f64
        };
        let tracer = &self.tracer;
        let mut c = RayCounts::default();
        let (mut plain, mut hint, mut every) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..runs.max(1) {
            plain.push(time(
                &mut || border.iter().filter(|(r, _)| tracer.occluded(r, RayKind::Shadow, &mut c)).count(),
                border.len(),
            ));
            hint.push(time(
                &mut || border.iter().filter(|(r, h)| tracer.occluded_with_hint(r, *h, &mut c)).count(),
                border.len(),
            ));
            every.push(time(
                &mut || all.iter().filter(|r| tracer.occluded(r, RayKind::Shadow, &mut c)).count(),
                all.len(),
            ));
        }
        let median = |v: &[f64]| Timing::of(v).median;
        Some(SameRays {
            border_rays: border.len() as u64,
            border_plain_ns: median(&plain),
            border_hint_ns: median(&hint),
            all_rays: all.len() as u64,
            all_plain_ns: median(&every),
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::render::{Options, Renderer};

    /// The rays traced again are the frame's border rays, one per undecided pair, and the
    /// frame's pairs; a frame without its buffers has none to give.
    #[test]
    fn traces_the_frames_own_border_rays() {
        let mut scene = crate::scene::load("cornell").unwrap();
        (scene.settings.width, scene.settings.height) = (64, 48);
        let r = Renderer::new(&scene, Options::hybrid());
        assert!(r.same_rays(&r.render(&|| {}), 1).is_none());
        let r = Renderer::new(&scene, Options { keep_buffers: true, ..Options::hybrid() });
        let f = r.render(&|| {});
        let same = r.same_rays(&f, 1).expect("the built-in scene has border rays");
        let undecided: u64 = f.stats.lights.iter().map(|l| l.undecided).sum();
        let decided: u64 = f.stats.lights.iter().map(|l| l.lit + l.shadowed + l.undecided).sum();
        assert_eq!(same.border_rays, undecided);
        assert_eq!(same.all_rays, decided);
    }
}
