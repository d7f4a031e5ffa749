//! Ray counters by kind.
//!
//! Counts are plain integers owned by one piece of work (a tile, a row); a parallel pass gives
//! each chunk its own [`RayCounts`] and adds them up afterwards. Integer addition is
//! associative, so the totals are the same for any thread count, and no atomic traffic sits
//! on the hot path.

use std::ops::AddAssign;

/// The kinds of rays the renderers cast.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Camera rays.
    Primary,
    /// Point-light visibility rays (from camera and mirror hits).
    Shadow,
    /// Mirror reflection rays.
    Specular,
    /// Visibility rays towards virtual point lights.
    VplShadow,
    /// Light paths that place virtual point lights.
    VplPath,
}

/// Number of rays cast, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    pub primary: u64,
    pub shadow: u64,
    pub specular: u64,
    pub vpl_shadow: u64,
    pub vpl_path: u64,
    /// Of the `shadow` rays, those answered by their occluder hint (one triangle test, no
    /// traversal; see [`crate::Tracer::occluded_with_hint`]). The others traversed the BVH.
    pub shadow_hint_hits: u64,
}

impl RayCounts {
    #[inline]
    pub fn add(&mut self, kind: RayKind, n: u64) {
        match kind {
            RayKind::Primary => self.primary += n,
            RayKind::Shadow => self.shadow += n,
            RayKind::Specular => self.specular += n,
            RayKind::VplShadow => self.vpl_shadow += n,
            RayKind::VplPath => self.vpl_path += n,
        }
    }

    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.specular + self.vpl_shadow + self.vpl_path
    }

    /// Shadow rays that traversed the BVH (those not answered by a hint).
    pub fn shadow_traversals(&self) -> u64 {
        self.shadow - self.shadow_hint_hits
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: Self) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.specular += o.specular;
        self.vpl_shadow += o.vpl_shadow;
        self.vpl_path += o.vpl_path;
        self.shadow_hint_hits += o.shadow_hint_hits;
    }
}

impl std::iter::Sum for RayCounts {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::default(), |mut a, b| {
            a += b;
            a
        })
    }
}

/// The counts and their derived totals (`shadow_traversals`, `total`), as every report writes
/// them.
#[cfg(feature = "serde")]
impl serde::Serialize for RayCounts {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut m = s.serialize_struct("RayCounts", 8)?;
        m.serialize_field("primary", &self.primary)?;
        m.serialize_field("shadow", &self.shadow)?;
        m.serialize_field("shadow_hint_hits", &self.shadow_hint_hits)?;
        m.serialize_field("shadow_traversals", &self.shadow_traversals())?;
        m.serialize_field("specular", &self.specular)?;
        m.serialize_field("vpl_shadow", &self.vpl_shadow)?;
        m.serialize_field("vpl_path", &self.vpl_path)?;
        m.serialize_field("total", &self.total())?;
        m.end()
    }
}
