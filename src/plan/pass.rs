//! The passes of a frame: one name per pass, written here once.
//!
//! The plan gates passes by this type ([`crate::plan::Plan::runs`]), the frame records their
//! times by it ([`crate::render::FrameStats::pass_ms`]), and the CLI's statistics, `hyrt bench`
//! and the inspector list them in [`Pass::ALL`]'s order under [`Pass::name`]. What each reads
//! and writes is declared here too ([`Pass::reads`], [`Pass::writes`]).

use serde::{Serialize, Serializer};

/// A pass of the frame (or of the scene's preparation: the BVH).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Pass {
    /// The BVH over the scene's triangles, built once per scene.
    BvhBuild,
    /// Primary visibility: the G-buffer, by rays or by the z-buffer.
    Visibility,
    /// Part of `Visibility` (raster): frustum culling of triangle clusters.
    VisCull,
    /// Part of `Visibility` (raster): the z-buffer.
    VisRaster,
    /// Part of `Visibility` (raster): hit points from the z-buffer's triangles.
    VisResolve,
    /// Light maps: the faces camera hits fall on, cached until the scene changes.
    MapBuild,
    /// Map-based shadows, tile by tile: shading points, every light's map decision, and direct
    /// light from those decisions.
    Classify,
    /// SMeRTS: the (pixel, light) pairs a shadow ray decides.
    Borders,
    /// SMeRTS: the border pairs' shadow rays, and those pixels shaded again.
    ShadowRays,
    /// Direct light with one shadow ray per hit and light (the reference).
    Direct,
    /// Instant radiosity: the VPLs.
    VplGen,
    /// One paraboloid map per VPL.
    VplMapBuild,
    /// Indirect light from the VPLs.
    Indirect,
    /// Mirror paths.
    Specular,
}

impl Pass {
    /// Every pass, in the order a frame runs them (the parts of `Visibility` after it).
    pub const ALL: [Pass; 14] = [
        Pass::BvhBuild,
        Pass::Visibility,
        Pass::VisCull,
        Pass::VisRaster,
        Pass::VisResolve,
        Pass::MapBuild,
        Pass::Classify,
        Pass::Borders,
        Pass::ShadowRays,
        Pass::Direct,
        Pass::VplGen,
        Pass::VplMapBuild,
        Pass::Indirect,
        Pass::Specular,
    ];

    /// The pass's name in plans, statistics, tables and the inspector.
    pub const fn name(self) -> &'static str {
        match self {
            Pass::BvhBuild => "bvh_build",
            Pass::Visibility => "visibility",
            Pass::VisCull => "vis_cull",
            Pass::VisRaster => "vis_raster",
            Pass::VisResolve => "vis_resolve",
            Pass::MapBuild => "map_build",
            Pass::Classify => "classify",
            Pass::Borders => "borders",
            Pass::ShadowRays => "shadow_rays",
            Pass::Direct => "direct",
            Pass::VplGen => "vpl_gen",
            Pass::VplMapBuild => "vpl_map_build",
            Pass::Indirect => "indirect",
            Pass::Specular => "specular",
        }
    }

    /// The pass named `name`.
    pub fn from_name(name: &str) -> Option<Pass> {
        Pass::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The pass this one is a part of (its time is included in that pass's).
    pub fn part_of(self) -> Option<Pass> {
        matches!(self, Pass::VisCull | Pass::VisRaster | Pass::VisResolve).then_some(Pass::Visibility)
    }

    /// Whether this pass runs once per frame and reports progress per image row.
    pub fn reports_rows(self) -> bool {
        matches!(self, Pass::Visibility | Pass::Classify | Pass::Direct | Pass::Indirect | Pass::Specular)
    }

    /// Rank of a timing key (a pass name, then any other key, then `total` and `frame`) for
    /// listing timings in frame order.
    pub fn rank(key: &str) -> usize {
        match (Pass::from_name(key), key) {
            (Some(p), _) => p as usize,
            (None, "total" | "frame") => Pass::ALL.len() + 1,
            _ => Pass::ALL.len(),
        }
    }
}

/// A named buffer of a frame (or a cache a frame fills): what passes read and write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Buffer {
    /// The BVH over the scene's triangles.
    Bvh,
    /// Per pixel, the camera hit: triangle, distance, barycentrics.
    Gbuffer,
    /// The pixels whose primary ray waits for the BVH (raster visibility under SMeRTS).
    Deferred,
    /// The light maps (cached across frames).
    LightMaps,
    /// Per pixel and light: whether it faces the pixel, and the decision, lit or not.
    Decisions,
    /// Per pixel and light: the pairs a shadow ray decides.
    BorderPairs,
    /// Per pixel, the direct light.
    Direct,
    /// Per pixel, the diffuse shading point (for the VPL maps' gather).
    Points,
    /// The VPLs (cached).
    Vpls,
    /// One paraboloid map per VPL (cached).
    VplMaps,
    /// Per pixel, the indirect light.
    Indirect,
    /// Per pixel, the light of the mirror paths.
    Specular,
    /// Per pixel, the rays cast on its behalf, by kind (kept with `Options::keep_buffers`,
    /// for inspection; atomic counters every pass that casts rays for a pixel adds to).
    PixelRays,
}

impl Buffer {
    /// The buffer's name in the inspector and the docs.
    pub const fn name(self) -> &'static str {
        match self {
            Buffer::Bvh => "bvh",
            Buffer::Gbuffer => "gbuffer",
            Buffer::Deferred => "deferred",
            Buffer::LightMaps => "light_maps",
            Buffer::Decisions => "decisions",
            Buffer::BorderPairs => "border_pairs",
            Buffer::Direct => "direct",
            Buffer::Points => "points",
            Buffer::Vpls => "vpls",
            Buffer::VplMaps => "vpl_maps",
            Buffer::Indirect => "indirect",
            Buffer::Specular => "specular",
            Buffer::PixelRays => "pixel_rays",
        }
    }
}

impl Pass {
    /// The buffers the pass reads: each is written by a pass that runs before it in every plan
    /// that runs it (a test holds the plans to it). `Points` is read where it was made (VPL
    /// maps); else the pass makes its own shading points.
    pub const fn reads(self) -> &'static [Buffer] {
        use Buffer::*;
        match self {
            Pass::BvhBuild => &[],
            Pass::Visibility | Pass::VisCull | Pass::VisRaster | Pass::VisResolve => &[Bvh],
            Pass::MapBuild => &[Gbuffer],
            Pass::Classify => &[Gbuffer, LightMaps],
            Pass::Borders => &[Decisions],
            Pass::ShadowRays => &[Bvh, Gbuffer, Deferred, LightMaps, Decisions, BorderPairs],
            Pass::Direct => &[Bvh, Gbuffer],
            Pass::VplGen => &[Bvh],
            Pass::VplMapBuild => &[Vpls],
            Pass::Indirect => &[Bvh, Gbuffer, Vpls],
            Pass::Specular => &[Bvh, Gbuffer],
        }
    }

    /// The buffers the pass writes (or adds to).
    pub const fn writes(self) -> &'static [Buffer] {
        use Buffer::*;
        match self {
            Pass::BvhBuild => &[Bvh],
            Pass::Visibility | Pass::VisCull | Pass::VisRaster | Pass::VisResolve => {
                &[Gbuffer, Deferred, PixelRays]
            }
            Pass::MapBuild => &[LightMaps],
            Pass::Classify => &[Decisions, Direct, Points],
            Pass::Borders => &[BorderPairs],
            // The deferred pixels' hits, their decisions by rays and their shading points; the
            // border pairs' decisions; those pixels' direct light again.
            Pass::ShadowRays => &[Gbuffer, Decisions, Direct, Points, PixelRays],
            Pass::Direct => &[Direct, Points, PixelRays],
            Pass::VplGen => &[Vpls],
            Pass::VplMapBuild => &[VplMaps],
            Pass::Indirect => &[Indirect, PixelRays],
            Pass::Specular => &[Specular, PixelRays],
        }
    }
}

impl std::fmt::Display for Pass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

impl Serialize for Pass {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_round_trip_in_frame_order() {
        for (i, p) in Pass::ALL.iter().enumerate() {
            assert_eq!(*p as usize, i, "{p}: ALL is in declaration order");
            assert_eq!(Pass::from_name(p.name()), Some(*p));
            assert_eq!(Pass::rank(p.name()), i);
        }
        assert_eq!(Pass::from_name("surface"), None);
        assert!(Pass::rank("total") > Pass::rank("unknown"));
        assert_eq!(Pass::VisRaster.part_of(), Some(Pass::Visibility));
        assert_eq!(format!("{:<8}|", Pass::Direct), "direct  |");
    }
}
