//! Visibility of a light from a mirror hit, which has no screen neighbours: the map-space test
//! alone, with a ray where it cannot tell.

use hyrt_shadowmap::{
    LightMap,
    classify::{Decision, Lookup},
};
use hyrt_tracer::{RayCounts, RayKind, spawn_ray_to};

use super::Shadowing;
use super::lookup::{classifier, lookup, settle};
use crate::render::{MirrorShadows, Renderer, Shadows, SurfaceHit};

impl Shadowing<'_> {
    /// Light `l`'s map decision at `s`, at the level the point needs (paged maps).
    fn decide(&self, r: &Renderer, l: usize, s: &SurfaceHit) -> Lookup {
        lookup(&classifier(&self.maps[l], self.planes, r), &self.resolution, l, s, r)
    }

    /// Visibility of light `l` from a mirror hit (no screen neighbours): the map's decision, or,
    /// when `Shadows::Smerts` and the map-space footprint disagrees or the face was not drawn,
    /// a shadow ray with the hint. `MirrorShadows::Rays`: always a ray.
    pub fn visible_at(&self, r: &Renderer, l: usize, s: &SurfaceHit, counts: &mut RayCounts) -> bool {
        let light = &r.lights[l];
        let ray = || spawn_ray_to(s.p, s.p_err, s.ng, light.position);
        if r.options.shadow.mirror == MirrorShadows::Rays {
            return !r.tracer.occluded(&ray(), RayKind::Shadow, counts);
        }
        let map = &self.maps[l];
        let kind = map.kind();
        let face = LightMap::face_of(kind, s.p - light.position) as usize;
        if !map.faces_drawn()[face] {
            return !r.tracer.occluded(&ray(), RayKind::Shadow, counts);
        }
        let lk = self.decide(r, l, s);
        if let Some(lit) = settle(r, &lk, s, light.position) {
            return lit;
        }
        if r.options.shadows == Shadows::Smerts && lk.map_border {
            return !r.tracer.occluded_with_hint(&ray(), lk.hint, counts);
        }
        lk.decision == Decision::Lit
    }
}
