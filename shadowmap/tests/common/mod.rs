//! Helpers shared by the integration tests.

use glam::{DVec3, Vec3};

/// Whether the segment from `o` to `p` crosses triangle `tri` strictly between them (`f64`
/// Möller-Trumbore).
pub fn blocks(o: DVec3, p: DVec3, tri: &[Vec3; 3]) -> bool {
    let [v0, v1, v2] = tri.map(|v| v.as_dvec3());
    let (e1, e2) = (v1 - v0, v2 - v0);
    let d = p - o;
    let q = d.cross(e2);
    let det = e1.dot(q);
    if det == 0.0 {
        return false;
    }
    let s = o - v0;
    let u = s.dot(q) / det;
    let r = s.cross(e1);
    let v = d.dot(r) / det;
    let t = e2.dot(r) / det;
    (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && t > 1e-9 && t < 1.0 - 1e-9
}
