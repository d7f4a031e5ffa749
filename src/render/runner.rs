//! The runner of a frame's passes: it runs a pass only where the plan runs it, times it, and
//! records the time under the pass; the frame's statistics come from it alone.
//!
//! Nothing else in `render/` reads the clock: a build whose time a decision states (a light's
//! map, the VPLs) is timed by [`timed`].

use std::time::Instant;

use super::{FrameStats, Pass};
use crate::plan::Plan;

/// Runs, times and records the passes of one frame.
pub(crate) struct Runner<'p> {
    plan: &'p Plan,
    /// What the passes counted and decided, and (on [`Runner::finish`]) their times.
    pub(crate) stats: FrameStats,
    start: Instant,
}

impl<'p> Runner<'p> {
    /// A frame begins: its total time counts from here.
    pub(crate) fn new(plan: &'p Plan) -> Self {
        Self { plan, stats: FrameStats::default(), start: Instant::now() }
    }

    /// Runs `pass` where the plan runs it, recording its wall time; `None` where the plan
    /// skips it.
    pub(crate) fn pass<T>(&mut self, pass: Pass, f: impl FnOnce(&mut Self) -> T) -> Option<T> {
        if !self.plan.runs(pass) {
            return None;
        }
        Some(self.time(pass, f))
    }

    /// Runs `part`, a part of the running pass ([`Pass::part_of`]), recording its wall time.
    pub(crate) fn part<T>(&mut self, part: Pass, f: impl FnOnce(&mut Self) -> T) -> T {
        debug_assert!(part.part_of().is_some(), "{part} is a pass, not a part of one");
        self.time(part, f)
    }

    fn time<T>(&mut self, pass: Pass, f: impl FnOnce(&mut Self) -> T) -> T {
        let t = Instant::now();
        let out = f(self);
        self.stats.pass_ms.insert(pass, ms(t));
        out
    }

    /// The frame's statistics, with its total time.
    pub(crate) fn finish(mut self) -> FrameStats {
        self.stats.total_ms = ms(self.start);
        self.stats
    }
}

/// `f`'s result and its wall time in milliseconds.
pub(crate) fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    (out, ms(t))
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
