//! A shading point: where a ray (or, later, a rasterized pixel) met a triangle.

use glam::Vec3;
use hyrt_tracer::{Hit, offset::hit_point};

use crate::scene::Scene;

/// Everything shading needs about a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Original triangle id.
    pub tri: u32,
    /// Distance along the incoming ray.
    pub t: f32,
    pub p: Vec3,
    /// Absolute rounding-error bound of `p` per axis (for ray-origin offsets).
    pub p_err: Vec3,
    /// Geometric normal, flipped to face the incoming ray (surfaces are two-sided).
    pub ng: Vec3,
    /// Shading normal (interpolated vertex normals), flipped with `ng`.
    pub ns: Vec3,
    /// Unit direction back along the incoming ray.
    pub wo: Vec3,
    /// Diffuse albedo here: the material's `Kd`, times its texture ([`Scene::albedo`]).
    pub albedo: Vec3,
    /// The highlight's reflectance here ([`Scene::colours`]).
    pub highlight: Vec3,
}

impl SurfaceHit {
    /// Builds the shading point of a tracer hit for a ray with unit direction `dir`.
    pub fn new(scene: &Scene, hit: &Hit, dir: Vec3) -> Self {
        let tri = scene.positions[hit.tri as usize];
        let (p, p_err, ng) = Self::point(&tri, hit);
        let n = scene.normals[hit.tri as usize];
        let b = hit.bary;
        let ns = (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).normalize_or(ng);
        let wo = -dir;
        let (albedo, highlight) = scene.colours(hit.tri, hit.bary, hit.t, ng.dot(wo));
        // Two-sided: the side facing the viewer is the front.
        let flip = if ng.dot(wo) < 0.0 { -1.0 } else { 1.0 };
        let (ng, mut ns) = (ng * flip, ns * flip);
        // Vertex normals may disagree with the face across a silhouette; keep the shading
        // normal on the viewer's side so lighting and reflection stay above the surface.
        if ns.dot(ng) <= 0.0 {
            ns = ng;
        }
        Self { tri: hit.tri, t: hit.t, p, p_err, ng, ns, wo, albedo, highlight }
    }

    /// The hit's point on triangle `tri`, its rounding bound, and the triangle's unit normal
    /// (before any flip to the viewer): the part of [`SurfaceHit::new`] that needs neither the
    /// ray nor the vertex normals.
    #[inline]
    pub(crate) fn point(tri: &[Vec3; 3], hit: &Hit) -> (Vec3, Vec3, Vec3) {
        let (p, p_err) = hit_point(tri, hit.bary);
        let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
        (p, p_err, ng)
    }
}
