//! Watertight ray-triangle intersection.
//!
//! Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013), in the form of
//! pbrt-v4's `Triangle::Intersect`: translate the vertices to the ray origin, permute axes so
//! the ray's largest direction component is `z`, shear so the ray becomes the `+z` axis, then
//! the 2D edge functions of the sheared vertices at the origin decide the hit. An edge shared by
//! two triangles gives exactly negated edge values in both (`a*b - c*d` rounds symmetrically),
//! so a ray through it hits at least one of them: no cracks. Exact zeros are re-evaluated in
//! f64, where the products of two f32 values are exact.

use glam::Vec3A;

/// `gamma(n) = n u / (1 - n u)`, u the unit roundoff of f32 (Higham; pbrt-v4 section 6.8):
/// a bound on the relative error of `n` chained floating-point operations.
#[inline]
pub fn gamma(n: i32) -> f32 {
    let u = f32::EPSILON * 0.5;
    (n as f32 * u) / (1.0 - n as f32 * u)
}

/// Per-ray values shared by every triangle test of one traversal.
#[derive(Clone, Copy, Debug)]
pub struct RayPrecomp {
    origin: Vec3A,
    /// The largest |direction| component; the test runs in the permuted frame
    /// `(kz + 1, kz + 2, kz) mod 3`.
    kz: usize,
    /// Shear coefficients `(-dx/dz, -dy/dz, 1/dz)` in the permuted frame.
    sx: f32,
    sy: f32,
    sz: f32,
}

impl RayPrecomp {
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let d = dir.to_array();
        // One division: the shear is the same for every triangle of the ray, so rounding it
        // differently (a product with 1/dz rather than a quotient) cannot open a crack.
        let sz = 1.0 / d[kz];
        Self { origin, kz, sx: -d[kx] * sz, sy: -d[ky] * sz, sz }
    }
}

/// A hit in the ray's parameter `t` with barycentric weights of corners 0, 1, 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub bary: [f32; 3],
    /// A bound on the rounding error of `t` (pbrt-v4 section 6.8.7's `deltaT`): the exact
    /// distance to the exact triangle lies within `t +- err`.
    pub err: f32,
}

/// `gamma(n)` of `f64` arithmetic.
#[inline]
fn gamma64(n: f64) -> f64 {
    let u = f64::EPSILON * 0.5;
    n * u / (1.0 - n * u)
}

/// The distance along the ray from `origin` in direction `dir` to the plane of triangle `v`,
/// and a bound on its rounding error: the watertight test's arithmetic (translate, permute,
/// shear, edge functions, `t = sum e_i z_i / sum e_i`) and its error bound, in `f64`. `None` for
/// a ray parallel to the plane (or non-finite values).
///
/// Why: two surfaces closer than the `f32` test's error bounds ([`TriHit::err`], a few ulps of
/// `t`) cannot be ordered by it, though their `f32` corners are distinct and one of them is
/// nearer. In `f64` the same computation is about `2^29` times more precise, which orders any
/// two planes that `f32` corners can place apart by more than a few `f64` ulps of the distance.
pub fn plane_distance_f64(origin: Vec3A, dir: Vec3A, v: &[Vec3A; 3]) -> Option<(f64, f64)> {
    let a = dir.abs();
    let kz = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    let d = dir.to_array().map(f64::from);
    let sz = 1.0 / d[kz];
    let (sx, sy) = (-d[kx] * sz, -d[ky] * sz);
    let o = origin.to_array().map(f64::from);
    // Sheared x and y, scaled z, and the unscaled z (for the error bound).
    let p = |q: Vec3A| {
        let q = q.to_array().map(f64::from);
        let (x, y, z) = (q[kx] - o[kx], q[ky] - o[ky], q[kz] - o[kz]);
        [x + sx * z, y + sy * z, z * sz, z]
    };
    let (p0, p1, p2) = (p(v[0]), p(v[1]), p(v[2]));
    let e0 = p1[0] * p2[1] - p1[1] * p2[0];
    let e1 = p2[0] * p0[1] - p2[1] * p0[0];
    let e2 = p0[0] * p1[1] - p0[1] * p1[0];
    let det = e0 + e1 + e2;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let t = (e0 * p0[2] + e1 * p1[2] + e2 * p2[2]) / det;
    // pbrt-v4's bound (section 6.8.7) with f64's gamma, the z's already scaled; plus one
    // rounding of the translation, which pbrt's exact-origin derivation leaves out, folded in
    // by taking gamma one step higher everywhere, and the final division.
    let max_zt = p0[2].abs().max(p1[2].abs()).max(p2[2].abs());
    let max_xt = p0[0].abs().max(p1[0].abs()).max(p2[0].abs());
    let max_yt = p0[1].abs().max(p1[1].abs()).max(p2[1].abs());
    let max_z_unscaled = p0[3].abs().max(p1[3].abs()).max(p2[3].abs());
    let delta_z = gamma64(4.0) * max_zt;
    // As in the f32 test: the shear's error is relative to `|s z|`, not to the scaled `|z|`.
    let delta_x = gamma64(6.0) * (max_xt + sx.abs() * max_z_unscaled);
    let delta_y = gamma64(6.0) * (max_yt + sy.abs() * max_z_unscaled);
    let delta_e = 2.0 * (gamma64(3.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let err = 3.0 * (gamma64(4.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) / det.abs()
        + gamma64(2.0) * t.abs();
    (t.is_finite() && err.is_finite()).then_some((t, err))
}

/// Intersects one triangle; returns hits with `0 < t < tmax` only.
///
/// Degenerate triangles (zero area, including collinear and coincident vertices) are never hit:
/// the determinant, the sum of the three edge values, is zero for them.
#[inline]
pub fn intersect_triangle(r: &RayPrecomp, v: &[Vec3A; 3], tmax: f32) -> Option<TriHit> {
    intersect::<true>(r, v, tmax)
}

/// Intersects the triangle's *plane*: the same arithmetic as [`intersect_triangle`] without
/// the inside test, so the barycentrics may be negative (the point lies outside the triangle)
/// and, where the ray does pass inside, the result is bit-identical to [`intersect_triangle`].
/// Used to reconstruct hit points for rasterized pixels, whose coverage rule may differ from
/// the ray test by a fraction of a pixel along edges.
#[inline]
pub fn intersect_plane(r: &RayPrecomp, v: &[Vec3A; 3], tmax: f32) -> Option<TriHit> {
    intersect::<false>(r, v, tmax)
}

#[inline(always)]
fn intersect<const INSIDE: bool>(r: &RayPrecomp, v: &[Vec3A; 3], tmax: f32) -> Option<TriHit> {
    // One copy of the test per axis permutation: with constant indices the permuted vertices
    // stay in registers (runtime-indexed arrays go through the stack). The branch is the same
    // for every triangle a ray meets, so it predicts perfectly.
    match r.kz {
        0 => intersect_perm::<INSIDE, 1, 2, 0>(r, v, tmax),
        1 => intersect_perm::<INSIDE, 2, 0, 1>(r, v, tmax),
        _ => intersect_perm::<INSIDE, 0, 1, 2>(r, v, tmax),
    }
}

#[inline(always)]
fn intersect_perm<const INSIDE: bool, const KX: usize, const KY: usize, const KZ: usize>(
    r: &RayPrecomp,
    v: &[Vec3A; 3],
    tmax: f32,
) -> Option<TriHit> {
    // Translate to the ray origin and permute.
    let p = |q: Vec3A| {
        let a = (q - r.origin).to_array();
        [a[KX], a[KY], a[KZ]]
    };
    let (mut p0, mut p1, mut p2) = (p(v[0]), p(v[1]), p(v[2]));
    // Shear x and y so the ray runs along +z; z is scaled later, only if needed.
    for q in [&mut p0, &mut p1, &mut p2] {
        q[0] += r.sx * q[2];
        q[1] += r.sy * q[2];
    }
    // Edge functions: twice the signed area of (origin, edge) in the sheared xy plane.
    let mut e0 = p1[0] * p2[1] - p1[1] * p2[0];
    let mut e1 = p2[0] * p0[1] - p2[1] * p0[0];
    let mut e2 = p0[0] * p1[1] - p0[1] * p1[0];
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        // On an edge within f32 rounding: decide exactly (f32 * f32 is exact in f64).
        let d = |a: f32, b: f32, c: f32, e: f32| (a as f64 * b as f64 - c as f64 * e as f64) as f32;
        e0 = d(p1[0], p2[1], p1[1], p2[0]);
        e1 = d(p2[0], p0[1], p2[1], p0[0]);
        e2 = d(p0[0], p1[1], p0[1], p1[0]);
    }
    if INSIDE && (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    // Scaled hit distance: t * det, compared against the range without dividing.
    let (z0, z1, z2) = (p0[2] * r.sz, p1[2] * r.sz, p2[2] * r.sz);
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < tmax * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > tmax * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if t >= tmax {
        return None;
    }
    // Conservative check that t > 0 despite rounding (pbrt-v4, section 6.8.7): bound the error
    // of the sheared coordinates, the edge values and t_scaled, and reject t within the bound.
    //
    // The sheared `x = x_t + sx z_t` (`z_t` unscaled) is off by at most `gamma(5) (|x| + |sx z_t|)`;
    // pbrt bounds `|sx z_t|` by the scaled `|z|` (which needs `|sx| <= 1` only), which for a ray
    // from far away (`|z_t|` huge, `sx` tiny) exceeds the distance itself and rejects every hit.
    // `|sx| max |z_t|` is the bound the derivation gives before that step.
    let max_zt = z0.abs().max(z1.abs()).max(z2.abs());
    let delta_z = gamma(3) * max_zt;
    let max_z_unscaled = p0[2].abs().max(p1[2].abs()).max(p2[2].abs());
    let max_xt = p0[0].abs().max(p1[0].abs()).max(p2[0].abs());
    let max_yt = p0[1].abs().max(p1[1].abs()).max(p2[1].abs());
    let delta_x = gamma(5) * (max_xt + r.sx.abs() * max_z_unscaled);
    let delta_y = gamma(5) * (max_yt + r.sy.abs() * max_z_unscaled);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t = 3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t <= delta_t {
        return None;
    }
    Some(TriHit { t, bary: [e0 * inv_det, e1 * inv_det, e2 * inv_det], err: delta_t })
}
