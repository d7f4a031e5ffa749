//! What a frame decided as it ran: the work the static plan cannot foresee.

use serde::Serialize;

/// A decision taken while rendering a frame, where the static [`crate::plan::Plan`] cannot know the answer
/// beforehand: per light whether it needs a map and rays at all, and whether cached data (BVH,
/// light maps, VPLs) was reused or rebuilt.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FrameDecision {
    /// What it concerns: `bvh`, `light 3`, `vpls`, `vpl_maps`.
    pub what: String,
    /// Whether work was done for it in this frame (a build, a map, rays).
    pub run: bool,
    /// Whether cached data (a light map or some of its faces, the VPLs, their maps) was built
    /// for it in this frame, rather than reused.
    pub built: bool,
    pub reason: String,
}

impl FrameDecision {
    /// A decision that built nothing.
    pub fn new(what: impl Into<String>, run: bool, reason: impl Into<String>) -> Self {
        Self { what: what.into(), run, built: false, reason: reason.into() }
    }

    /// A decision that built (or extended) cached data.
    pub fn built(what: impl Into<String>, reason: impl Into<String>) -> Self {
        Self { built: true, ..Self::new(what, true, reason) }
    }

    /// Cached data that was either built in this frame (work done) or reused (none).
    pub fn cached(what: impl Into<String>, built: bool, reason: impl Into<String>) -> Self {
        Self { built, ..Self::new(what, built, reason) }
    }
}

/// Prints frame decisions one per line, as [`crate::plan::Plan`]'s `Display` does.
pub fn format_decisions(d: &[FrameDecision]) -> String {
    d.iter()
        .map(|d| format!("  {}  {:<11} {}\n", if d.run { "run " } else { "skip" }, d.what, d.reason))
        .collect()
}
