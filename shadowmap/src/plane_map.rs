//! A virtual point light's map made for many lookups: one paraboloid hemisphere whose texels
//! hold the *plane* of the surface nearest to the origin, not its id or its distance.
//!
//! # Why planes
//!
//! For the plane `n . x = d` and a unit direction `w` from the origin `o`, the plane lies at
//! distance `t = h / (n . w)` along `w`, with `h = d - n . o`. So
//!
//! ```text
//! 1 / t = (n / h) . w
//! ```
//!
//! is *linear* in `w`. A texel stores `g = n / h` of the surface it sees ([`PlaneMap::texels`]);
//! the occluder's distance along a point's own direction is then one dot product away. This is
//! the test [`Classifier`](crate::classify::Classifier) makes with a triangle id and a table
//! of planes, without the id's second, random memory access; and unlike a depth stored at the
//! texel centre it has no slope error inside the texel (a surface seen at a grazing angle moves
//! by many texel footprints in depth across one texel). An empty texel holds `g = 0`: nothing
//! in any direction.
//!
//! # Lookup
//!
//! The map frame is `(t, b, a)`, `a` the hemisphere's axis (as
//! [`LightMap::build_hemisphere`]). A unit direction `w` with `a . w > 0` falls on texel
//! `(floor x, floor y)` with
//!
//! ```text
//! x = ((t . w) / (1 + a . w) + 1) res / 2,    y = (1 - (b . w) / (1 + a . w)) res / 2,
//! ```
//!
//! both clamped to `[0, res)` ([`PlaneMap::index`]; the operations in this order, in `f32`,
//! so that vectorised lookups can repeat them bit for bit). Texels whose centre lies outside the
//! paraboloid's unit disc are never drawn; each holds a copy of the nearest drawn texel, so that
//! a lookup near the rim needs no special case.
//!
//! # Decision
//!
//! A point at distance `r` along `w`, on a surface whose normal makes `cos_g = |n_p . w|` with
//! `w`, is hidden when the stored plane meets `w` in front of it by more than a margin:
//!
//! ```text
//! s = g . w > 0   and   s (r - margin) > 1,
//! margin = bias * texel_angle * r + 1e-5 r + e (1 + 1 / cos_g),
//! texel_angle = (1 + a . w) 2 / res
//! ```
//!
//! (the margin of [`Classifier`](crate::classify::Classifier): `bias` texel footprints, the
//! plane's rounding, and the rounding band `e` of the point; the paraboloid's texel angle is
//! `2 / (1 + u^2 + v^2) * 2 / res`, and `1 + u^2 + v^2 = 2 / (1 + a . w)` on the unit sphere).
//! [`PlaneMap::occluded`] is that test.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::classify::Plane;
use crate::map::{EMPTY, LightMap, MapOptions, disc_contains, nearest_in_disc};
use crate::tess::Frame;

/// Relative rounding margin of the plane distance (as the classifier's `TOLERANCE`).
pub const PLANE_TOLERANCE: f32 = 1e-5;

/// One paraboloid hemisphere of planes (module docs).
#[derive(Clone, Debug)]
pub struct PlaneMap {
    origin: Vec3,
    /// `t, b, a`: the map frame, `a` the axis.
    frame: [Vec3; 3],
    resolution: u32,
    /// `g = n / h` per texel, row-major.
    texels: Vec<[f32; 3]>,
}

impl PlaneMap {
    /// The hemisphere around unit `axis` seen from `origin`, drawn by
    /// [`LightMap::build_hemisphere`] over `tris` with `opts`, each texel's triangle replaced by
    /// its plane from `planes` (`planes[id]` for triangle `id`; a missing or zero plane, or one
    /// through the origin, stores `g = 0`).
    pub fn build(tris: &[[Vec3; 3]], planes: &[Plane], origin: Vec3, axis: Vec3, opts: &MapOptions) -> Self {
        let map = LightMap::build_hemisphere(tris, origin, axis, opts);
        Self::from_ids(&map, planes, Frame::around(axis.as_dvec3()))
    }

    fn from_ids(map: &LightMap, planes: &[Plane], frame: Frame) -> Self {
        let res = map.resolution();
        let ids = map.face_ids(0);
        let origin = map.light();
        let plane_of = |id: u32| -> [f32; 3] {
            let Some(pl) = planes.get(id as usize).filter(|_| id != EMPTY) else { return [0.0; 3] };
            let h = pl.offset_from(origin);
            let g = pl.n.as_dvec3() / h;
            if h == 0.0 || !g.is_finite() { [0.0; 3] } else { g.as_vec3().to_array() }
        };
        let mut texels = vec![[0f32; 3]; res as usize * res as usize];
        texels.par_chunks_mut(res as usize).enumerate().for_each(|(y, row)| {
            let y = y as u32;
            for (x, g) in row.iter_mut().enumerate() {
                let x = x as u32;
                let (sx, sy) = if disc_contains(res, x, y) {
                    (x, y)
                } else {
                    match nearest_in_disc(res, x as f32 + 0.5, y as f32 + 0.5) {
                        Some(n) => n,
                        None => continue,
                    }
                };
                if !ids.is_empty() {
                    *g = plane_of(ids[map.texel_index(sx, sy)]);
                }
            }
        });
        let f = |v: DVec3| v.as_vec3();
        PlaneMap { origin, frame: [f(frame.t), f(frame.b), f(frame.n)], resolution: res, texels }
    }

    /// The texel under unit direction `w` (from the origin), as an index into
    /// [`PlaneMap::texels`] (module docs: the formula and its order of operations).
    #[inline]
    pub fn index(&self, w: Vec3) -> usize {
        let [t, b, a] = self.frame;
        let den = 1.0 + (a.x * w.x + a.y * w.y + a.z * w.z);
        let u = (t.x * w.x + t.y * w.y + t.z * w.z) / den;
        let v = (b.x * w.x + b.y * w.y + b.z * w.z) / den;
        let half = self.resolution as f32 * 0.5;
        let lim = self.last();
        let x = ((u + 1.0) * half).max(0.0).min(lim) as usize;
        let y = ((1.0 - v) * half).max(0.0).min(lim) as usize;
        y * self.resolution as usize + x
    }

    /// The largest `f32` below the resolution: the clamp of [`PlaneMap::index`].
    #[inline]
    pub fn last(&self) -> f32 {
        f32::from_bits((self.resolution as f32).to_bits() - 1)
    }

    /// Whether the plane `g` hides the point at distance `r` along `w` by more than `margin`
    /// (module docs).
    #[inline]
    pub fn occluded(g: [f32; 3], w: Vec3, r: f32, margin: f32) -> bool {
        let s = g[0] * w.x + g[1] * w.y + g[2] * w.z;
        s > 0.0 && s * (r - margin) > 1.0
    }

    /// The origin (the VPL's position).
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// The map frame `[t, b, a]`, `a` the axis.
    pub fn frame(&self) -> [Vec3; 3] {
        self.frame
    }

    /// Texels per side.
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// `g = n / h` per texel, row-major (module docs).
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// The distance from the origin to the stored surface along the centre of texel `(x, y)`
    /// (infinite where the texel is empty or out of range).
    pub fn depth(&self, x: u32, y: u32) -> f32 {
        let res = self.resolution;
        if x >= res || y >= res {
            return f32::INFINITY;
        }
        let g = self.texels[(y * res + x) as usize];
        let inv = 2.0 / res as f32;
        let (u, v) = ((x as f32 + 0.5) * inv - 1.0, 1.0 - (y as f32 + 0.5) * inv);
        // Inverse of the paraboloid projection on the unit sphere.
        let r2 = u * u + v * v;
        let z = (1.0 - r2) / (1.0 + r2);
        let [t, b, a] = self.frame;
        let w = (t * (u * (1.0 + z)) + b * (v * (1.0 + z)) + a * z).normalize();
        let s = Vec3::from(g).dot(w);
        if s > 0.0 { 1.0 / s } else { f32::INFINITY }
    }

    /// Whether texel `(x, y)`'s centre lies in the paraboloid's disc (the texels drawn; the
    /// others hold copies).
    pub fn in_domain(&self, x: u32, y: u32) -> bool {
        x < self.resolution && y < self.resolution && disc_contains(self.resolution, x, y)
    }

    /// Bytes held by the texels.
    pub fn memory_bytes(&self) -> usize {
        self.texels.len() * std::mem::size_of::<[f32; 3]>()
    }
}
