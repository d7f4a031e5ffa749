//! The paraboloid parameterisation of a hemisphere.
//!
//! A unit direction `d = (x, y, z)` with `z >= 0` in the map's frame reflects off the
//! paraboloid `f(x, y) = 1/2 - (x^2 + y^2) / 2` towards +z at the point `(u, v) = (x, y) / (1 + z)`
//! of the unit disc: the whole hemisphere fits in one map, and two maps back to back (`z >= 0`
//! and `z <= 0`) cover the sphere. The inverse follows from `|d| = 1`:
//! `z = (1 - u^2 - v^2) / (1 + u^2 + v^2)` and `(x, y) = (u, v) (1 + z)`.
//! Straight lines do not stay straight under this mapping, which is why triangles are
//! tessellated before they are projected (see the shadow-map issue).

use glam::{Vec2, Vec3};

/// Which half of the sphere a dual-paraboloid map covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hemisphere {
    /// `z >= 0` in the map's frame.
    Front,
    /// `z < 0`, stored mirrored (`z -> -z`) in the second map.
    Back,
}

/// Projects a direction (any length, non-zero) to the paraboloid disc, choosing the
/// hemisphere by the sign of `z`. The result satisfies `|uv| <= 1`.
pub fn paraboloid_project(d: Vec3) -> (Hemisphere, Vec2) {
    let d = d.normalize();
    if d.z >= 0.0 {
        (Hemisphere::Front, Vec2::new(d.x, d.y) / (1.0 + d.z))
    } else {
        (Hemisphere::Back, Vec2::new(d.x, d.y) / (1.0 - d.z))
    }
}

/// The unit direction of disc point `uv` in the given hemisphere.
pub fn paraboloid_unproject(h: Hemisphere, uv: Vec2) -> Vec3 {
    let r2 = uv.length_squared();
    let z = (1.0 - r2) / (1.0 + r2);
    let xy = uv * (1.0 + z);
    match h {
        Hemisphere::Front => Vec3::new(xy.x, xy.y, z),
        Hemisphere::Back => Vec3::new(xy.x, xy.y, -z),
    }
}
