//! Which side of a triangle's plane a point lies on, with "in the plane" decided exactly
//! enough to be trusted.
//!
//! Shading asks whether a point light is in front of a surface. Computed from the shading
//! point, `n . (light - p)` carries the rounding error of `p`, which near the light is as large
//! as the quantity itself: a light lying in a wall's plane would light the wall around it,
//! where every exact evaluation gives `cos = 0`. The side of the plane depends only on the
//! triangle's corners and the light, so we ask it of them, as the orientation predicate
//!
//! ```text
//! s = (b - a) x (c - a) . (q - a) = det [a - q; b - q; c - q]
//! ```
//!
//! (positive when `q` is on the side that `(b - a) x (c - a)` points to). It is evaluated in
//! f64 on the f32 inputs, with Shewchuk's forward error bound for its first stage
//! (Shewchuk 1997, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
//! Predicates", `o3derrboundA`): with `u = 2^-53`, the computed `s` differs from the exact one
//! by at most `(7 + 56 u) u P`, where `P` is the permanent (the same expansion with every
//! term's absolute value). Outside that band the sign is certain; inside it, the point is in
//! the plane to within what f64 arithmetic on these inputs can tell, which, for f32 inputs
//! whose products are exact in f64, is in practice exactly in the plane.

use glam::Vec3;

/// Where a point lies relative to an oriented triangle's plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneSide {
    /// On the side the normal `(b - a) x (c - a)` points to.
    Front,
    /// On the other side.
    Back,
    /// In the plane, within the bound (also every point, for a degenerate triangle).
    In,
}

/// The side of the plane of `tri` (corners `a, b, c`, counter-clockwise seen from the front)
/// on which `q` lies (see the module docs). Non-finite inputs give [`PlaneSide::In`].
pub fn plane_side(tri: &[Vec3; 3], q: Vec3) -> PlaneSide {
    let d = |p: Vec3| {
        [f64::from(p.x) - f64::from(q.x), f64::from(p.y) - f64::from(q.y), f64::from(p.z) - f64::from(q.z)]
    };
    let (a, b, c) = (d(tri[0]), d(tri[1]), d(tri[2]));
    let (bycz, bzcy) = (b[1] * c[2], b[2] * c[1]);
    let (czay, cyaz) = (c[2] * a[1], c[1] * a[2]);
    let (aybz, azby) = (a[1] * b[2], a[2] * b[1]);
    let det = a[0] * (bycz - bzcy) + b[0] * (cyaz - czay) + c[0] * (aybz - azby);
    let permanent = (bycz.abs() + bzcy.abs()) * a[0].abs()
        + (cyaz.abs() + czay.abs()) * b[0].abs()
        + (aybz.abs() + azby.abs()) * c[0].abs();
    let u = f64::EPSILON * 0.5;
    let bound = (7.0 + 56.0 * u) * u * permanent;
    // det [a - q; b - q; c - q] is (b - a) x (c - a) . (a - q): positive with q behind.
    if !(det.is_finite() && bound.is_finite()) {
        PlaneSide::In
    } else if det > bound {
        PlaneSide::Back
    } else if det < -bound {
        PlaneSide::Front
    } else {
        PlaneSide::In
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [Vec3; 3] = [Vec3::ZERO, Vec3::X, Vec3::Y];

    #[test]
    fn sides_of_the_xy_plane() {
        assert_eq!(plane_side(&TRI, Vec3::new(0.3, 0.3, 1.0)), PlaneSide::Front);
        assert_eq!(plane_side(&TRI, Vec3::new(0.3, 0.3, -1.0)), PlaneSide::Back);
        assert_eq!(plane_side(&TRI, Vec3::new(5.0, -7.0, 0.0)), PlaneSide::In);
        let flipped = [TRI[0], TRI[2], TRI[1]];
        assert_eq!(plane_side(&flipped, Vec3::new(0.3, 0.3, 1.0)), PlaneSide::Back);
    }

    #[test]
    fn the_smallest_step_off_the_plane_is_seen() {
        // One f32 ulp above a tilted plane, far from the origin: the sign must still be right.
        let o = Vec3::splat(1.0e5);
        let tri = [o, o + Vec3::new(3.0, 0.0, 1.0), o + Vec3::new(0.0, 2.0, 0.0)];
        // The plane contains o + (3, 0, 1) s + (0, 2, 0) t; take s = 2/3 (x = 1e5 + 2).
        let on = o + Vec3::new(2.0, 0.5, 0.0);
        let z = on.z + 2.0 / 3.0; // not representable: the point is just off the plane
        let q = Vec3::new(on.x, on.y, z);
        let side = plane_side(&tri, q);
        let exact = {
            let n = [-2.0f64, 0.0, 6.0]; // (3, 0, 1) x (0, 2, 0) = (-2, 0, 6)
            let dq = [f64::from(q.x) - 1e5, f64::from(q.y) - 1e5, f64::from(q.z) - 1e5];
            n[0] * dq[0] + n[1] * dq[1] + n[2] * dq[2]
        };
        assert_ne!(exact, 0.0);
        assert_eq!(side, if exact > 0.0 { PlaneSide::Front } else { PlaneSide::Back });
    }

    #[test]
    fn points_exactly_in_a_plane_far_away_are_in_it() {
        for k in 0..200 {
            let o = Vec3::new(1.0e5 + k as f32 * 0.37, -3.0e4, 7.5e4);
            let tri = [o, o + Vec3::new(4.0, 0.0, 0.0), o + Vec3::new(0.0, 0.0, -4.0)];
            let q = Vec3::new(o.x + k as f32 * 0.011, o.y, o.z - 9.0);
            assert_eq!(plane_side(&tri, q), PlaneSide::In, "k = {k}");
        }
    }

    #[test]
    fn degenerate_and_non_finite_inputs_are_in() {
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert_eq!(plane_side(&line, Vec3::Z), PlaneSide::In);
        assert_eq!(plane_side(&TRI, Vec3::new(f32::NAN, 0.0, 1.0)), PlaneSide::In);
        let inf = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, f32::INFINITY, 0.0)];
        assert_eq!(plane_side(&inf, Vec3::Z), PlaneSide::In);
    }
}
