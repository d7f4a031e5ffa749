//! Hit-point error bounds and ray-origin offsetting (pbrt-v4, section 6.8.6).
//!
//! A hit point is computed from the first corner and the two edges leaving it,
//! `p = p0 + (b1 e1 + b2 e2)` with `e_i = p_i - p0`, rather than pbrt's `b0 p0 + b1 p1 + b2 p2`.
//! Far from the origin the corners are large and the edges small: pbrt's form rounds three
//! products and two sums at the corners' magnitude (`gamma(7) |p|` per axis), ours only the
//! final sum (`gamma(1) |p|`), so the point, and every ray leaving it, is seven times tighter
//! there. The bound: `e_i` and `b_i e_i` are each rounded once and their sum once more, so
//! `s = b1 e1 + b2 e2` is within `gamma(3) (|b1 e1| + |b2 e2|)` of its exact value (the
//! products' factors `|b_i e_i|` taken from the computed edges, which are within `gamma(1)` of
//! theirs, absorbed in the `gamma(3)`); adding `p0` rounds once at the result's magnitude,
//! `gamma(1) |p|`. Any `(b1, b2)` gives a point of the plane (in exact arithmetic), so errors in
//! the barycentrics themselves move the point along the surface, not off it. The point lies
//! within a box of half-size `gamma(1) |p| + gamma(3) (|b1 e1| + |b2 e2|)` (per axis) around a
//! point of the surface. A new ray that
//! starts exactly at the computed point may re-hit the same surface at a tiny `t`. Instead of
//! a fixed epsilon, the origin is pushed along the geometric normal just far enough to leave
//! that box (`d = |n| . error`), to the side the new ray leaves towards, then rounded one more
//! ulp away so the rounding of the addition itself cannot pull it back.

use glam::Vec3;

use crate::{Ray, triangle::gamma};

/// The interpolated hit point and its per-axis absolute error bound (module docs). `b[0]` is
/// implied by the other two (the weights sum to 1).
pub fn hit_point(tri: &[Vec3; 3], b: [f32; 3]) -> (Vec3, Vec3) {
    let (m1, m2) = ((tri[1] - tri[0]) * b[1], (tri[2] - tri[0]) * b[2]);
    let p = tri[0] + (m1 + m2);
    (p, p.abs() * gamma(1) + (m1.abs() + m2.abs()) * gamma(3))
}

/// Moves `p` out of its error box along the geometric normal `n`, to the side of `w`.
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let mut offset = n * d;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let mut po = (p + offset).to_array();
    for (i, o) in offset.to_array().into_iter().enumerate() {
        if o > 0.0 {
            po[i] = po[i].next_up();
        } else if o < 0.0 {
            po[i] = po[i].next_down();
        }
    }
    Vec3::from(po)
}

/// A ray leaving a surface point in direction `dir` (normalised here).
pub fn spawn_ray(p: Vec3, p_error: Vec3, n: Vec3, dir: Vec3) -> Ray {
    let d = dir.normalize();
    Ray::new(offset_ray_origin(p, p_error, n, d), d, f32::INFINITY)
}

/// Fraction of the distance to the target that a shadow ray leaves untested, so a surface
/// passing exactly through a point light does not shadow it (pbrt-v4's `ShadowEpsilon`).
/// Relative, hence independent of the scene's scale.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// A shadow ray from a surface point towards `target`, stopping just short of it.
pub fn spawn_ray_to(p: Vec3, p_error: Vec3, n: Vec3, target: Vec3) -> Ray {
    ray_to(offset_ray_origin(p, p_error, n, target - p), target)
}

/// The shadow ray from `o`, an origin already offset ([`offset_ray_origin`]), towards
/// `target`, stopping just short of it: the second half of [`spawn_ray_to`], for a caller that
/// keeps origins and makes their rays later.
#[inline]
pub fn ray_to(o: Vec3, target: Vec3) -> Ray {
    let v = target - o;
    let dist = v.length();
    Ray::new(o, v / dist, dist * (1.0 - SHADOW_EPSILON))
}
