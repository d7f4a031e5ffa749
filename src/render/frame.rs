//! A frame: the plan's passes in order, over named buffers.
//!
//! What each pass reads and writes is declared once, by [`Pass::reads`] and [`Pass::writes`]
//! (the buffers are [`crate::plan::Buffer`]); a test holds every plan to it (each buffer a pass
//! reads was written by a pass before it) and every frame to its plan (it runs those passes and
//! no other).
//!
//! Which passes run is the [`Plan`](crate::plan::Plan)'s decision alone; the
//! [`Runner`] runs, times and records them. `classify` shades as it decides (direct light
//! from a tile's decisions while its points are in L1; `shadows` says why), so the border
//! rays shade their pixels again into `direct`.

use glam::Vec3;
use rayon::prelude::*;

use super::runner::Runner;
use super::{
    Cache, Frame, FrameDecision, Pass, Progress, Renderer, Run, Subject, Visibility, direct, gather,
    indirect, specular, visibility,
};
use crate::film::Film;

impl Renderer<'_> {
    /// Renders one frame: the plan's passes, in order, over the frame's named buffers (module
    /// docs), each run, timed and recorded by the runner.
    pub fn render(&self, progress: Progress) -> Frame {
        let mut run = Runner::new(&self.plan);
        self.pixel_rays.clear();
        let (w, h) = (self.scene.settings.width, self.scene.settings.height);
        let n = w as usize * h as usize;

        // With raster visibility and border rays, the few pixels that need a primary ray (at
        // triangle edges) get it in the shadow-ray pass, after the map passes, which need no
        // BVH: a background build of the BVH (`Renderer::new`) then overlaps them. Those
        // pixels' lights are all decided by rays.
        let defer = self.plan.runs(Pass::ShadowRays) && self.options.visibility == Visibility::Raster;
        let (mut gbuffer, deferred) = run
            .pass(Pass::Visibility, |run| visibility::run(self, progress, run, defer))
            .unwrap_or_else(|| (vec![None; n], Vec::new()));

        let mut direct = vec![Vec3::ZERO; n];
        // The diffuse shading points, made by the direct-light pass (classify or direct) for
        // the VPL maps' gather.
        let mut points = self.plan.runs(Pass::VplMapBuild).then(|| vec![gather::ShadePoint::default(); n]);
        let maps = run.pass(Pass::MapBuild, |run| self.map_build(&gbuffer, &mut run.stats));
        let mut shadowing = maps.and_then(|maps| {
            run.pass(Pass::Classify, |_| {
                self.classify(&gbuffer, maps, &mut direct, points.as_deref_mut(), progress)
            })
        });
        if let Some(s) = &mut shadowing {
            run.pass(Pass::Borders, |_| self.borders(&mut s.bufs, w as usize, h as usize));
            let check = self.options.check_visibility;
            let traced = run.pass(Pass::ShadowRays, |run| {
                // Work for the core a first frame's background BVH build leaves idle.
                let ahead = s.rows_ahead(self, &gbuffer, &|| self.tracer.is_ready());
                if !deferred.is_empty() {
                    run.stats.rays += visibility::resolve_deferred(self, &mut gbuffer, &deferred);
                    s.add_ray_pixels(self, &gbuffer, &deferred, points.as_deref_mut());
                }
                run.stats.rays += s.trace(self, &gbuffer, &mut direct);
                run.stats.rays +=
                    s.trace_without_maps(self, &gbuffer, &mut direct, points.as_deref_mut(), ahead);
                s.finish(self, &gbuffer, check);
            });
            if traced.is_none() {
                s.finish(self, &gbuffer, check);
            }
            run.stats.lights = s.lights.clone();
        }
        if let Some(rays) = run
            .pass(Pass::Direct, |_| direct::run(self, &gbuffer, &mut direct, points.as_deref_mut(), progress))
        {
            run.stats.rays += rays;
        }

        let mut indirect = vec![Vec3::ZERO; n];
        let paths = run.pass(Pass::VplGen, |run| self.vpl_paths(&mut run.stats));
        let vpls = paths.map(|(paths, previous)| {
            let maps = run.pass(Pass::VplMapBuild, |run| self.vpl_maps(paths, previous, &mut run.stats));
            self.vpls(paths, maps.unwrap_or(&[]))
        });
        if let Some(v) = &vpls {
            run.pass(Pass::Indirect, |run| {
                let (rays, pairs) =
                    indirect::run(self, v, &gbuffer, points.as_deref(), &mut indirect, progress);
                run.stats.rays += rays;
                run.stats.vpl_pairs = pairs;
            });
        }

        let mut spec = vec![Vec3::ZERO; n];
        if let Some(rays) = run.pass(Pass::Specular, |_| {
            specular::run(self, &gbuffer, shadowing.as_mut(), vpls.as_ref(), &mut spec, progress)
        }) {
            run.stats.rays += rays;
        }
        if let Some(s) = &shadowing
            && self.plan.runs(Pass::Specular)
        {
            s.mirror_pages_done(self);
            s.report_mirror_pages(&mut run.stats);
        }

        // Compose.
        let mut film = Film::new(w, h);
        film.pixels.par_iter_mut().enumerate().for_each(|(i, p)| *p = direct[i] + indirect[i] + spec[i]);
        // Last: a background build may have finished only during the frame.
        run.stats.decisions.insert(
            0,
            FrameDecision::new(
                Subject::Bvh,
                Run::Skip,
                format!(
                    "reused: built once for the scene ({:.1} ms), which is unchanged",
                    self.bvh_build_ms()
                ),
            )
            .with_cache(Cache::Reused),
        );
        let stats = run.finish();
        let shadows = shadowing.map(|s| s.bufs).and_then(|b| {
            if self.options.keep_buffers {
                Some(b)
            } else {
                self.recycle(b);
                None
            }
        });
        let (gbuffer, pixel_rays) = if self.options.keep_buffers {
            (Some(gbuffer), Some(self.pixel_rays.snapshot()))
        } else {
            self.recycle_gbuffer(gbuffer);
            (None, None)
        };
        Frame { film, stats, shadows, gbuffer, pixel_rays }
    }
}

/// Passes run outside a frame, for unit tests of a pass's parts.
#[cfg(test)]
impl Renderer<'_> {
    /// The VPLs and (with `super::Indirect::Maps`) their maps, as the VPL passes make them.
    pub(crate) fn test_vpls(&self) -> indirect::Vpls<'_> {
        let mut stats = super::FrameStats::default();
        let (paths, previous) = self.vpl_paths(&mut stats);
        let maps = if self.options.indirect == super::Indirect::Maps {
            self.vpl_maps(paths, previous, &mut stats)
        } else {
            &[]
        };
        self.vpls(paths, maps)
    }

    /// The map-build, classify and borders passes on `gbuffer` (with `trace`, the border rays
    /// too), as a frame runs them.
    pub(crate) fn test_shadowing(
        &self,
        gbuffer: &[Option<hyrt_tracer::Hit>],
        direct: &mut [Vec3],
        points: Option<&mut [gather::ShadePoint]>,
        trace: bool,
    ) -> super::shadows::Shadowing<'_> {
        let maps = self.map_build(gbuffer, &mut super::FrameStats::default());
        let mut s = self.classify(gbuffer, maps, direct, points, &|| {});
        let (w, h) = (self.scene.settings.width as usize, self.scene.settings.height as usize);
        self.borders(&mut s.bufs, w, h);
        if trace {
            s.trace(self, gbuffer, direct);
        }
        s.finish(self, gbuffer, false);
        s
    }
}
