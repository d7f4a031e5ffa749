//! What a frame decided as it ran: the work the static plan cannot foresee.

use serde::Serialize;

/// What a frame did with the data it caches between frames (maps, VPLs, the BVH).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Cache {
    /// The decision concerns no cached data (a light that needs no map).
    #[default]
    None,
    /// Made by an earlier frame and used as it was.
    Reused,
    /// Made (or made again) in this frame.
    Built,
    /// Kept, with the parts this frame newly needs added (a light map's new faces).
    Extended,
}

/// A decision taken while rendering a frame, where the static [`crate::plan::Plan`] cannot
/// know the answer beforehand: per light whether it needs a map and rays at all, and whether
/// cached data (BVH, light maps, VPLs) was reused, built or extended.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FrameDecision {
    /// What it concerns: `bvh`, `light 3`, `vpls`, `vpl_maps`.
    pub what: String,
    /// Whether work was done for it in this frame (a build, a map, rays).
    pub run: bool,
    /// What was done with its cached data.
    pub cache: Cache,
    pub reason: String,
}

impl FrameDecision {
    /// A decision about no cached data.
    pub fn new(what: impl Into<String>, run: bool, reason: impl Into<String>) -> Self {
        Self { what: what.into(), run, cache: Cache::None, reason: reason.into() }
    }

    /// The same decision, saying what was done with its cached data.
    pub fn with_cache(self, cache: Cache) -> Self {
        Self { cache, ..self }
    }

    /// Whether cached data was built or extended for it in this frame.
    pub fn built(&self) -> bool {
        matches!(self.cache, Cache::Built | Cache::Extended)
    }
}

/// Prints frame decisions one per line, as [`crate::plan::Plan`]'s `Display` does.
pub fn format_decisions(d: &[FrameDecision]) -> String {
    d.iter()
        .map(|d| format!("  {}  {:<11} {}\n", if d.run { "run " } else { "skip" }, d.what, d.reason))
        .collect()
}
