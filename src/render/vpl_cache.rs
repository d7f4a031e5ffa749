//! The VPLs and their maps, kept from frame to frame: made by the VPL passes (`vpl_gen`,
//! `vpl_map_build`) on first use, dropped or partly kept when lights or knobs change.

use std::sync::OnceLock;

use glam::Vec3;
use hyrt_shadowmap::vpl_map::{Holes, VplMap};
use hyrt_tracer::RayCounts;
use rayon::prelude::*;

use super::{Cache, FrameDecision, FrameStats, Renderer, Run, Subject, runner::timed, vpl};

/// Per-renderer VPLs and VPL maps.
#[derive(Default)]
pub(crate) struct VplCache {
    vpls: OnceLock<(Vec<vpl::Vpl>, RayCounts)>,
    maps: OnceLock<Vec<VplMap>>,
    /// Why the cache was emptied, for the decision of the frame that fills it again.
    cause: Option<&'static str>,
    /// After lights moved ([`VplCache::relight`]): the VPLs and maps from before, which the
    /// next frame keeps for the lights that did not move.
    previous: std::sync::Mutex<Option<Previous>>,
}

/// The VPLs (and maps) of a cache some of whose lights moved.
pub(crate) struct Previous {
    vpls: Vec<vpl::Vpl>,
    maps: Option<Vec<VplMap>>,
    /// Per light, whether it moved (its VPLs are traced again).
    moved: Vec<bool>,
}

impl Renderer<'_> {
    /// The cached VPLs and, with `Indirect::Maps`, their maps (for inspection), once a frame
    /// has made them.
    pub fn cached_vpls(&self) -> Option<(&[vpl::Vpl], &[VplMap])> {
        let (vpls, _) = self.vpl_cache.vpls.get()?;
        Some((vpls, self.vpl_cache.maps.get().map_or(&[][..], |m| &m[..])))
    }
}

impl VplCache {
    /// An empty cache, emptied for `cause` (said by the next frame's decisions).
    pub(crate) fn dropped_because(cause: &'static str) -> Self {
        Self { cause: Some(cause), ..Self::default() }
    }

    /// Drops the VPL maps (made with other map options), keeping the VPLs.
    pub(crate) fn drop_maps(&mut self) {
        self.maps = OnceLock::new();
        if let Some(p) = self.previous.get_mut().unwrap_or_else(|e| e.into_inner()) {
            p.maps = None;
        }
    }

    /// Light `l` (of `lights`) moved, with the same intensity: the next frame traces its
    /// VPLs again and builds their maps, and keeps the other lights' VPLs and maps
    /// ([`vpl::generate_from`]: they are the ones a fresh renderer would make).
    pub(crate) fn relight(&mut self, l: usize, lights: usize) {
        let previous = self.previous.get_mut().unwrap_or_else(|e| e.into_inner());
        if let Some((vpls, _)) = self.vpls.take() {
            *previous = Some(Previous { vpls, maps: self.maps.take(), moved: vec![false; lights] });
        }
        if let Some(p) = previous.as_mut().filter(|p| l < p.moved.len()) {
            p.moved[l] = true;
        }
        self.cause = Some("a light moved");
    }
}

impl Renderer<'_> {
    /// The VPL generation pass: the VPLs, made on the first call (with the path rays counted
    /// in `stats`), then cached; and what a frame with moved lights kept from before, for
    /// [`Renderer::vpl_maps`].
    pub(crate) fn vpl_paths(&self, stats: &mut FrameStats) -> (&[vpl::Vpl], Option<Previous>) {
        let opts = &self.options.indirect_opts;
        let mut fresh = false;
        let previous = self.vpl_cache.previous.lock().unwrap_or_else(|e| e.into_inner()).take();
        // With lights moved: the VPLs traced again, of how many.
        let mut retraced = None;
        let ((vpls, _), ms) = timed(|| {
            self.vpl_cache.vpls.get_or_init(|| {
                fresh = true;
                match &previous {
                    Some(p) => {
                        let (new, counts) =
                            vpl::generate_from(self.scene, &self.lights, &self.tracer, &opts.vpl, &p.moved);
                        retraced = Some(new.len());
                        // In light order, as `generate` makes them.
                        let merged = (0..self.lights.len() as u32)
                            .flat_map(|l| {
                                let from = if p.moved[l as usize] { &new } else { &p.vpls };
                                from.iter().filter(move |v| v.light == l).copied()
                            })
                            .collect();
                        (merged, counts)
                    }
                    None => vpl::generate(self.scene, &self.lights, &self.tracer, &opts.vpl),
                }
            })
        });
        if fresh {
            stats.rays += self.vpl_cache.vpls.get().expect("just made").1;
        }
        let cause = self.vpl_cache.cause.map_or(String::new(), |c| format!(" ({c})"));
        stats.decisions.push(
            FrameDecision::new(
                Subject::Vpls,
                Run::when(fresh),
                if let Some(m) = retraced {
                    format!(
                        "{} VPLs: {m} traced again from the moved light(s), {} reused{cause} in {ms:.1} ms",
                        vpls.len(),
                        vpls.len() - m,
                    )
                } else if fresh {
                    format!(
                        "{} VPLs generated from {} light path(s){cause} in {ms:.1} ms",
                        vpls.len(),
                        opts.vpl.paths,
                    )
                } else {
                    format!("{} VPLs reused from an earlier frame", vpls.len())
                },
            )
            .with_cache(if fresh { Cache::Built } else { Cache::Reused }),
        );
        stats.vpls = vpls.len() as u32;
        (vpls, previous)
    }

    /// The VPL map build pass: one map per VPL of `vpls` (those of [`Renderer::vpl_paths`],
    /// which says what `previous` kept), made on the first call, then cached.
    pub(crate) fn vpl_maps(
        &self,
        vpls: &[vpl::Vpl],
        previous: Option<Previous>,
        stats: &mut FrameStats,
    ) -> &[VplMap] {
        let opts = &self.options.indirect_opts;
        let cause = self.vpl_cache.cause.map_or(String::new(), |c| format!(" ({c})"));
        let mut fresh = false;
        let mut built = 0;
        let (maps, ms) = timed(|| {
            self.vpl_cache.maps.get_or_init(|| {
                fresh = true;
                let planes = self.occluders().0;
                // The maps of VPLs kept from before (lights that did not move), in order.
                let mut kept: Vec<Option<VplMap>> = match previous {
                    Some(Previous { vpls: old, maps: Some(maps), moved }) => {
                        let mut by_light: Vec<std::collections::VecDeque<VplMap>> =
                            (0..moved.len()).map(|_| Default::default()).collect();
                        for (v, m) in old.iter().zip(maps) {
                            by_light[v.light as usize].push_back(m);
                        }
                        vpls.iter()
                            .map(|v| {
                                let l = v.light as usize;
                                if moved[l] { None } else { by_light[l].pop_front() }
                            })
                            .collect()
                    }
                    _ => vpls.iter().map(|_| None).collect(),
                };
                // Cut-outs: a texel that sees a hole holds what lies behind it (decided at the
                // texel's centre, `shadows::sees_hole`).
                let cutouts = self.cutouts();
                let solid: Vec<[Vec3; 3]> = if cutouts.is_empty() {
                    Vec::new()
                } else {
                    let gone = [Vec3::NAN; 3];
                    self.scene
                        .positions
                        .iter()
                        .zip(cutouts)
                        .map(|(t, &c)| if c { gone } else { *t })
                        .collect()
                };
                // Maps in parallel as well as inside each build: a small map's build has too
                // little work per parallel step to keep both cores busy alone.
                let new: Vec<(usize, VplMap)> = (0..vpls.len())
                    .into_par_iter()
                    .filter(|&i| kept[i].is_none())
                    .map(|i| {
                        let v = &vpls[i];
                        let hole =
                            |id: u32, dir: Vec3| super::shadows::sees_hole(self.scene, v.position, id, dir);
                        let holes = Holes { cutouts, solid: &solid, hole: &hole };
                        (
                            i,
                            VplMap::build_with_holes(
                                &self.scene.positions,
                                planes,
                                v.position,
                                v.normal,
                                &opts.map,
                                opts.format,
                                (!cutouts.is_empty()).then_some(&holes),
                            ),
                        )
                    })
                    .collect();
                built = new.len();
                for (i, m) in new {
                    kept[i] = Some(m);
                }
                kept.into_iter().map(|m| m.expect("kept or built")).collect()
            })
        });
        {
            let n = self.options.indirect_opts.map.resolution;
            stats.decisions.push(FrameDecision::new(
                Subject::VplMaps,
                Run::when(fresh),
                if fresh && built < maps.len() {
                    format!(
                        "{built} of {} paraboloid maps of {n}x{n} built{cause}, the others reused, in {ms:.1} ms",
                        maps.len(),
                    )
                } else if fresh {
                    format!(
                        "{} paraboloid maps of {n}x{n} built{cause} in {ms:.1} ms",
                        maps.len(),
                    )
                } else {
                    format!("{} maps reused from an earlier frame", maps.len())
                },
            ).with_cache(if fresh { Cache::Built } else { Cache::Reused }));
        }
        stats.vpl_map_bytes = maps.iter().map(|m| m.memory_bytes() as u64).sum();
        maps
    }
}
