//! Hit-point error bounds and ray-origin offsetting (pbrt-v4, section 6.8.6).
//!
//! A hit point computed as `b0 p0 + b1 p1 + b2 p2` lies within a box of half-size
//! `gamma(7) * (|b0 p0| + |b1 p1| + |b2 p2|)` around the true surface point. A new ray that
//! starts exactly at the computed point may re-hit the same surface at a tiny `t`. Instead of
//! a fixed epsilon, the origin is pushed along the geometric normal just far enough to leave
//! that box (`d = |n| . error`), to the side the new ray leaves towards, then rounded one more
//! ulp away so the rounding of the addition itself cannot pull it back.

use glam::Vec3;

use crate::{Ray, triangle::gamma};

/// The interpolated hit point and its per-axis absolute error bound.
pub fn hit_point(tri: &[Vec3; 3], b: [f32; 3]) -> (Vec3, Vec3) {
    let p = tri[0] * b[0] + tri[1] * b[1] + tri[2] * b[2];
    let abs_sum = (tri[0] * b[0]).abs() + (tri[1] * b[1]).abs() + (tri[2] * b[2]).abs();
    (p, abs_sum * gamma(7))
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
    let o = offset_ray_origin(p, p_error, n, target - p);
    let v = target - o;
    let dist = v.length();
    Ray::new(o, v / dist, dist * (1.0 - SHADOW_EPSILON))
}
