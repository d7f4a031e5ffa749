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

/// What a [`FrameDecision`] concerns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Subject {
    /// The BVH over the scene's triangles.
    Bvh,
    /// A point light (its map, its classification and its shadow rays).
    Light(usize),
    /// The VPLs of instant radiosity.
    Vpls,
    /// The VPLs' paraboloid maps.
    VplMaps,
}

impl std::fmt::Display for Subject {
    /// `bvh`, `light 3`, `vpls`, `vpl_maps`: as printed and as written in statistics.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Subject::Bvh => f.pad("bvh"),
            Subject::Light(l) => f.pad(&format!("light {l}")),
            Subject::Vpls => f.pad("vpls"),
            Subject::VplMaps => f.pad("vpl_maps"),
        }
    }
}

impl Serialize for Subject {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Whether a pass, or the work a decision concerns, ran in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Run {
    Run,
    Skip,
}

impl Run {
    /// `Run` where `ran`, else `Skip`.
    pub fn when(ran: bool) -> Self {
        if ran { Run::Run } else { Run::Skip }
    }
}

/// A decision taken while rendering a frame, where the static [`crate::plan::Plan`] cannot
/// know the answer beforehand: per light whether it needs a map and rays at all, and whether
/// cached data (BVH, light maps, VPLs) was reused, built or extended.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FrameDecision {
    /// What it concerns.
    pub what: Subject,
    /// Whether work was done for it in this frame (a build, a map, rays).
    pub run: bool,
    /// What was done with its cached data.
    pub cache: Cache,
    pub reason: String,
}

impl FrameDecision {
    /// A decision about no cached data, for which work was done (`Run::Run`) or not.
    pub fn new(what: Subject, run: Run, reason: impl Into<String>) -> Self {
        Self { what, run: run == Run::Run, cache: Cache::None, reason: reason.into() }
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
        .map(|d| {
            format!("  {}  {:<13} {}\n", if d.run { "run " } else { "skip" }, d.what.to_string(), d.reason)
        })
        .collect()
}
