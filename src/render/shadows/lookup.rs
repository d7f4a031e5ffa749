//! A point's decision in a light's map: the classifier with the renderer's bias, the level a
//! point reads, and the ambiguous triangles settled by the point's own shadow ray.

use std::sync::Arc;

use glam::Vec3;
use hyrt_shadowmap::{
    EMPTY, LightMap, MapCoord,
    classify::{Classifier, Lookup, Plane},
    paged::{LightTerms, Resolution},
};
use hyrt_tracer::spawn_ray_to;

use crate::render::{Ambiguous, Neighbours, Renderer, Shadows, SurfaceHit};

/// Under SMeRTS, whether light `light` reaches `s` when its lookup `lk` is a border that a
/// few triangles explain, tested alone with its shadow ray (made as the reference makes it,
/// with the tracer's watertight test, so that each answers as it would in a traversal): lit
/// unless one blocks it. Those triangles are
/// - with `Ambiguous::Triangles`, the one or two within the bias band ([`Lookup::suspects`]);
/// - with `Neighbours::Triangles`, the footprint's occluders ([`Lookup::occluders`]) when each
///   shares a vertex with the point's own triangle: a curved mesh's facets next to its own,
///   whose planes cross the ray to the light over the point though the facets themselves may
///   not, a border on every lit part of the mesh near its terminator.
///
/// A blocked answer is the reference's. A lit one is the map's kind of answer: the texels
/// around the point's direction hold those triangles and no other occluder, so what the ray
/// could still meet is an occluder no texel of the footprint holds, which a lit decision
/// anywhere else misses too. `None` otherwise: the map's decision stands, or a whole ray
/// decides a border.
pub(super) fn settle(r: &Renderer, lk: &Lookup, s: &SurfaceHit, light: Vec3) -> Option<bool> {
    if !lk.map_border || r.options.shadows != Shadows::Smerts {
        return None;
    }
    let o = &r.options.shadow;
    let tris: &[u32] = if lk.suspects[0] != EMPTY && o.ambiguous == Ambiguous::Triangles {
        &lk.suspects
    } else if lk.occluders[0] != EMPTY
        && o.neighbours == Neighbours::Triangles
        && lk.occluders.iter().all(|&t| t == EMPTY || shares_vertex(r, s.tri, t))
    {
        &lk.occluders
    } else {
        return None;
    };
    let ray = spawn_ray_to(s.p, s.p_err, s.ng, light);
    Some(!tris.iter().any(|&t| t != EMPTY && r.tracer.hits_triangle(t, &ray).is_some()))
}

/// Whether triangles `a` and `b` share a vertex (by position: meshes are stored as triangle
/// soups).
#[inline]
fn shares_vertex(r: &Renderer, a: u32, b: u32) -> bool {
    let (pa, pb) = (&r.scene.positions[a as usize], &r.scene.positions[b as usize]);
    pa.iter().any(|v| pb.contains(v))
}

/// Whether the ray from `origin` in direction `dir` meets triangle `id` (one with a cut-out) in
/// a hole: a map texel's centre, for maps that resolve holes texel by texel. Its barycentrics
/// by Möller and Trumbore's ratios, whose vectors depend on the triangle and the origin alone
/// (`u = d . (e2 x s) / d . (e2 x e1)`, `v = d . (s x e1) / d . (e2 x e1)`, `s = origin - a`):
/// three dot products a texel, where a watertight ray test costs several times that. Not the
/// tracer's bit for bit, which a texel's sample does not need (its footprint's borders go to
/// rays, which are exact).
pub(crate) fn sees_hole(scene: &crate::scene::Scene, origin: Vec3, id: u32, dir: Vec3) -> bool {
    let Some(&[a, b, c]) = scene.positions.get(id as usize) else { return false };
    let (e1, e2, s) = (b - a, c - a, origin - a);
    let den = e2.cross(e1).dot(dir);
    if den == 0.0 || !den.is_finite() {
        return false;
    }
    let (u, v) = (e2.cross(s).dot(dir) / den, s.cross(e1).dot(dir) / den);
    !scene.solid_at(id, [1.0 - u - v, u, v])
}

/// The classifier of `map`, with the renderer's bias.
pub(super) fn classifier<'m>(map: &'m LightMap, planes: &'m [Plane], r: &'m Renderer) -> Classifier<'m> {
    Classifier {
        map,
        planes,
        bias: r.options.shadow.bias,
        point_error: r.occluders().1,
        cutouts: r.cutouts(),
    }
}

/// Light `l`'s decision at `s` by its classifier `cls`, at the level `resolution` gives the
/// point (paged maps; level 0 when `resolution` is empty).
pub(super) fn lookup(
    cls: &Classifier,
    resolution: &[Resolution],
    l: usize,
    s: &SurfaceHit,
    r: &Renderer,
) -> Lookup {
    cls.classify_at(s.p, s.tri, locate(cls, resolution, l, s, r))
}

/// The occluder a border ray from `s` to light `l` tests first when classify kept no hint for
/// its pair (undecided by the Laplacian, the dilation or no map): [`Classifier::hint_at`], at
/// the point's level.
pub(super) fn hint(
    cls: &Classifier,
    resolution: &[Resolution],
    l: usize,
    s: &SurfaceHit,
    r: &Renderer,
) -> u32 {
    cls.hint_at(s.tri, locate(cls, resolution, l, s, r))
}

/// The level of light `l`'s paged map (0 for whole maps) that `s` reads when it is seen at the
/// end of a view path `dist` long (a mirror hit: [`Resolution::receiver_at`]).
pub(super) fn level_along(
    resolution: &[Resolution],
    l: usize,
    s: &SurfaceHit,
    dist: f32,
    r: &Renderer,
) -> u8 {
    resolution.get(l).map_or(0, |g| {
        g.level_from(g.receiver_at(dist, s.ng.dot(s.wo)), LightTerms::of(s.p, s.ng, r.lights[l].position))
    })
}

/// Where `s` falls in light `l`'s map, at its level (paged maps; 0 otherwise).
pub(super) fn locate(
    cls: &Classifier,
    resolution: &[Resolution],
    l: usize,
    s: &SurfaceHit,
    r: &Renderer,
) -> MapCoord {
    let level = resolution.get(l).map_or(0, |g| g.level(s.p, s.ng, s.ng.dot(s.wo), r.lights[l].position));
    cls.locate_at(s.p, level)
}

/// The classifier of each of `maps`.
pub(super) fn classifiers<'m>(
    maps: &'m [Arc<LightMap>],
    planes: &'m [Plane],
    r: &'m Renderer,
) -> Vec<Classifier<'m>> {
    maps.iter().map(|map| classifier(map, planes, r)).collect()
}
