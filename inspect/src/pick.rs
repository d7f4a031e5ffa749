//! Pixel picking: what the renderer knew and did at one pixel (no window needed).

use glam::Vec3;
use hyrt::render::{
    Shadows, SurfaceHit,
    light::facing,
    shadows::{BorderRay, resolution_guide},
};
use hyrt_shadowmap::{
    EMPTY,
    classify::Decision,
    classify::{Classifier, Lookup},
    paged::Resolution,
};
use hyrt_tracer::RayCounts;

use crate::worker::{Loaded, Rendered};

/// Everything shown for a picked pixel.
#[derive(Clone, Debug)]
pub struct PixelInfo {
    pub x: u32,
    pub y: u32,
    /// The camera hit (G-buffer), if any.
    pub hit: Option<HitInfo>,
    /// Linear radiance of the hybrid and (once rendered) the reference, and their
    /// display-luminance difference.
    pub hybrid: Vec3,
    pub reference: Option<Vec3>,
    pub error: Option<f32>,
    /// Rays cast on behalf of this pixel, by kind.
    pub rays: Option<RayCounts>,
    pub lights: Vec<LightPick>,
}

#[derive(Clone, Debug)]
pub struct HitInfo {
    pub tri: u32,
    pub t: f32,
    pub bary: [f32; 3],
    pub p: Vec3,
    pub material: hyrt::scene::Material,
    /// The diffuse albedo there (the material's `Kd`, times its texture if it has one).
    pub albedo: Vec3,
    /// The material's texture: its file and size.
    pub texture: Option<(String, (u32, u32))>,
    /// The material's cut-out: its mask's file (none: the factor alone), the alpha there and
    /// the cut-off.
    pub cutout: Option<(Option<String>, f32, f32)>,
}

/// One light at the picked pixel.
#[derive(Clone, Debug)]
pub struct LightPick {
    pub light: usize,
    /// The light can add something here (in front of the surface, which has a diffuse
    /// reflectance): a visibility decision is needed.
    pub needed: bool,
    /// Shadows by rays (no maps): every needed pixel casts one shadow ray.
    pub by_rays: bool,
    /// Map-based shadows: where the point falls in the light's map and what the map says.
    pub map: Option<MapPick>,
    /// The final decision, from the frame's occlusion buffer.
    pub decision: Option<Decision>,
    /// Border before dilation, and undecided (border after dilation: a ray was cast).
    pub border: bool,
    pub undecided: bool,
    /// What its shadow ray did.
    pub ray: BorderRay,
    /// With the visibility check: whether a ray contradicts the map's decision.
    pub wrong: Option<bool>,
}

/// The texel a point read, as `map.coord(p - light.position)` and the classification.
#[derive(Clone, Debug)]
pub struct MapPick {
    pub face: u8,
    /// The level read (paged maps; 0 for whole ones).
    pub level: u8,
    /// Continuous texel coordinates at that level.
    pub x: f64,
    pub y: f64,
    /// The texel's stored distance from the light (`inf`: empty) and triangle.
    pub depth: f32,
    pub id: u32,
    /// The point's distance from the light.
    pub distance: f32,
    /// The map's own decision (before any ray): decision, hint, map-space border, ambiguity.
    pub lookup: Lookup,
}

/// What is known at pixel `(x, y)` of `r` (a full frame: a moving one keeps no buffers, and
/// shows no more than its radiance).
pub fn pick(loaded: &Loaded, r: &Rendered, x: u32, y: u32) -> PixelInfo {
    let scene = &loaded.scene;
    let w = scene.settings.width;
    let i = (y * w + x) as usize;
    let hit = r.frame.gbuffer.as_ref().and_then(|g| g[i]);
    let surf = hit.map(|h| SurfaceHit::new(scene, &h, r.camera.direction(x, y).normalize()));
    let hit_info = hit.zip(surf).map(|(h, s)| {
        let m = &scene.materials[scene.material[h.tri as usize] as usize];
        let texture =
            m.texture.and_then(|k| scene.textures.get(k as usize)).map(|t| (t.name.clone(), t.size()));
        let cutout = scene.alpha_at(h.tri, h.bary).map(|(alpha, c)| {
            (c.mask.and_then(|k| scene.masks.get(k as usize)).map(|m| m.name.clone()), alpha, c.cutoff)
        });
        HitInfo {
            tri: h.tri,
            t: h.t,
            bary: h.bary,
            p: s.p,
            material: m.clone(),
            albedo: s.albedo,
            texture,
            cutout,
        }
    });
    let bufs = r.frame.shadows.as_ref();
    let by_rays = r.options.shadows == Shadows::Rays;
    let lights = r
        .pose
        .lights
        .iter()
        .enumerate()
        .map(|(l, light)| {
            let needed = surf.is_some_and(|s| {
                scene.materials[scene.material[s.tri as usize] as usize].is_lit()
                    && facing(&s, light, &scene.positions[s.tri as usize]).is_some()
            });
            let map = r.maps.get(l).cloned().flatten().zip(surf).filter(|_| needed).map(|(m, s)| {
                // The level the frame read this point at (paged maps; 0 for whole ones).
                let level = if m.is_paged() {
                    let cap =
                        r.frame.stats.lights.get(l).map_or(hyrt_shadowmap::MAX_LEVEL, |st| st.level_cap);
                    let guide = Resolution { cap, ..resolution_guide(&r.camera, &r.options.shadow) };
                    guide.level(s.p, s.ng, s.ng.dot(s.wo), light.position)
                } else {
                    0
                };
                let c = m.coord_at(s.p - light.position, level);
                let cls = Classifier {
                    map: &m,
                    planes: &loaded.planes[..],
                    bias: r.options.shadow.bias,
                    point_error: loaded.point_error,
                    cutouts: &loaded.cutouts,
                };
                let lookup = cls.classify_at(s.p, s.tri, c);
                let [tx, ty] = lookup.texel;
                MapPick {
                    face: c.face,
                    level,
                    x: c.x,
                    y: c.y,
                    depth: cls.depth_at(level, lookup.face, tx, ty),
                    id: m.id_at(level, lookup.face, tx, ty),
                    distance: (s.p - light.position).length(),
                    lookup,
                }
            });
            let at = |v: &Vec<Vec<bool>>| v.get(l).and_then(|b| b.get(i)).copied().unwrap_or(false);
            LightPick {
                light: l,
                needed,
                by_rays,
                map,
                decision: bufs.and_then(|b| b.occ.get(l)).map(|o| o[i]),
                border: bufs.is_some_and(|b| at(&b.border)),
                undecided: bufs.is_some_and(|b| at(&b.undecided)),
                ray: bufs.and_then(|b| b.ray.get(l)).map_or(BorderRay::None, |v| v[i]),
                wrong: bufs.filter(|b| !b.wrong.is_empty()).map(|b| at(&b.wrong)),
            }
        })
        .collect();
    PixelInfo {
        x,
        y,
        hit: hit_info,
        hybrid: r.frame.film.pixels[i],
        reference: r.comparison.as_ref().map(|c| c.reference.film.pixels[i]),
        error: r.comparison.as_ref().map(|c| c.error[i]),
        rays: r.frame.pixel_rays.as_ref().map(|p| p[i]),
        lights,
    }
}

/// A decision's name.
pub fn decision_name(d: Decision) -> &'static str {
    match d {
        Decision::Lit => "lit",
        Decision::Shadow => "shadowed",
        Decision::NotNeeded => "none",
    }
}

/// A triangle id, or `empty`.
pub fn tri_name(id: u32) -> String {
    if id == EMPTY { "empty".into() } else { id.to_string() }
}
