//! A point light seen from a surface point: which side of the surface it lies on, its
//! direction, distance and cosine, and the reflection of its light (the one place the
//! material's response to point lights is evaluated, for the reference and the hybrid alike).

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;
use hyrt_shadowmap::paged::LightTerms;
use hyrt_tracer::{PlaneSide, plane_side};

use super::{Renderer, SurfaceHit};
use crate::scene::PointLight;

/// Whether `light` can light `hit` at all (a light with some intensity, strictly in front of
/// the surface's plane and of its shading normal, not at the point): the condition under which
/// the reference casts a shadow ray. `Some((wi, cos, d2))` if so. `tri` is the hit triangle's
/// corners.
///
/// The side of the plane is decided from the triangle's corners and the light alone
/// ([`plane_side`]), not from `ng . (light - p)`: the shading point's rounding error is as large
/// as that product near a light lying in the plane, whose every exact evaluation is 0. A light
/// in the plane therefore lights none of it, in the reference and the hybrid alike.
#[inline]
pub fn facing(hit: &SurfaceHit, light: &PointLight, tri: &[Vec3; 3]) -> Option<(Vec3, f32, f32)> {
    let g = light_geometry(hit, light)?;
    viewer_side(hit, tri, plane_side(tri, light.position)).then_some(g)
}

/// Whether a light on side `side` of `tri`'s plane ([`plane_side`], which depends on the
/// triangle and the light only, so that callers may reuse it across the pixels of a triangle)
/// is on the side `hit` is seen from: `hit.ng` is the winding's normal flipped towards the
/// viewer.
#[inline]
pub fn viewer_side(hit: &SurfaceHit, tri: &[Vec3; 3], side: PlaneSide) -> bool {
    on_viewer_side(seen_winding(hit, tri), side)
}

/// `hit.ng . winding` of `tri`: its sign says which side of the plane `hit` is seen from, for
/// [`on_viewer_side`] (one per hit, for all lights).
#[inline]
pub(crate) fn seen_winding(hit: &SurfaceHit, tri: &[Vec3; 3]) -> f32 {
    hit.ng.dot((tri[1] - tri[0]).cross(tri[2] - tri[0]))
}

/// [`viewer_side`] from the hit's [`seen_winding`].
#[inline]
pub(crate) fn on_viewer_side(seen: f32, side: PlaneSide) -> bool {
    match side {
        PlaneSide::In => false,
        PlaneSide::Front => seen > 0.0,
        PlaneSide::Back => seen < 0.0,
    }
}

/// [`plane_side`] of every light for the last triangle asked: a pass over a row of pixels
/// crosses runs of pixels on one triangle, and the exact test depends on the triangle and the
/// light only.
pub(crate) struct PlaneSides {
    tri: u32,
    sides: Vec<PlaneSide>,
}

impl PlaneSides {
    pub(crate) fn new() -> Self {
        Self { tri: u32::MAX, sides: Vec::new() }
    }

    /// The side of each of `lights` relative to triangle `id`'s plane (corners `tri`).
    #[inline]
    pub(crate) fn of(&mut self, id: u32, tri: &[Vec3; 3], lights: &[PointLight]) -> &[PlaneSide] {
        if self.tri != id {
            self.tri = id;
            self.sides.clear();
            self.sides.extend(lights.iter().map(|l| plane_side(tri, l.position)));
        }
        &self.sides
    }
}

/// Whether unit direction `d` from a spot light lies outside its cone by more than a margin:
/// marking samples every few pixels and counts on a receiver's neighbours needing its pages,
/// so it stops a little beyond the cone (a page it misses is decided by a ray all the same).
pub(crate) fn outside_with_margin(s: &crate::scene::Spot, d: Vec3) -> bool {
    // 0.05 of the cosine: a few degrees for wide cones, more for narrow ones.
    s.axis.dot(d) < s.cos_outer - 0.05
}

/// The part of [`facing`] that does not ask the side of the plane: `Some((wi, cos, d2))` for
/// a light with some intensity, not at the point, in front of the shading normal. Passes that
/// already know that the light faces the point (a map decision was made for it) use this alone.
#[inline]
pub fn light_geometry(hit: &SurfaceHit, light: &PointLight) -> Option<(Vec3, f32, f32)> {
    light_geometry_and_terms(hit, light).0
}

/// [`light_geometry`], and the point's [`LightTerms`] with its geometric normal (its map level's
/// terms), from one offset to the light and one square root.
#[inline]
pub(crate) fn light_geometry_and_terms(
    hit: &SurfaceHit,
    light: &PointLight,
) -> (Option<(Vec3, f32, f32)>, LightTerms) {
    let to_light = light.position - hit.p;
    let d2 = to_light.length_squared();
    // `length()` is `length_squared().sqrt()`: the terms are `LightTerms::of`'s.
    let r = d2.sqrt();
    let terms = LightTerms::of_offset(hit.ng, to_light, r);
    if is_dark(light) || d2 == 0.0 {
        return (None, terms);
    }
    let wi = to_light / r;
    (lights_along(light, wi, hit.ns.dot(wi), d2), terms)
}

/// Whether `light` sends nothing at all: a dark light adds nothing, no ray, no map (the plan
/// says so).
#[inline]
pub(crate) fn is_dark(light: &PointLight) -> bool {
    light.intensity.max_element() <= 0.0
}

/// [`light_geometry`] from its parts, for a light that is not [dark](is_dark):
/// `Some((wi, cos, d2))` when it sends something along `-wi` (the unit direction to it, at
/// squared distance `d2 > 0`; not so outside a spot light's cone) and `cos`, the shading
/// normal's cosine with `wi`, is positive.
#[inline]
pub(crate) fn lights_along(light: &PointLight, wi: Vec3, cos: f32, d2: f32) -> Option<(Vec3, f32, f32)> {
    (!light.dark_towards(-wi) && cos > 0.0).then_some((wi, cos, d2))
}

/// The sum of [`shade`](super::direct::shade) over the lights for which `lit(l, light)` gives their geometry
/// `(wi, cos, d2)` (those in front of the surface and visible); the one place where the
/// material's reflection of point lights is evaluated, for the reference and the hybrid alike.
pub(crate) fn reflect(
    r: &Renderer,
    hit: &SurfaceHit,
    mut lit: impl FnMut(usize, &crate::scene::PointLight) -> Option<(Vec3, f32, f32)>,
) -> Vec3 {
    let m = &r.scene.materials[r.scene.material[hit.tri as usize] as usize];
    if !m.is_lit() {
        return Vec3::ZERO;
    }
    let highlight = m.has_highlight();
    // Irradiance at normal incidence times cos(theta), summed; and weighted by the lobe.
    let (mut sum, mut lobe_sum) = (Vec3::ZERO, Vec3::ZERO);
    for (l, light) in r.lights.iter().enumerate() {
        let Some((wi, cos, d2)) = lit(l, light) else { continue };
        let e = light.intensity_towards(-wi) * (cos / d2);
        sum += e;
        if highlight {
            lobe_sum += e * m.highlight_lobe(hit.ns, wi, hit.wo);
        }
    }
    let diffuse = hit.albedo * FRAC_1_PI * sum;
    if highlight { diffuse + hit.highlight * lobe_sum } else { diffuse }
}
