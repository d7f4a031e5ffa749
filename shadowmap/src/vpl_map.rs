//! A virtual point light's map made for many lookups: one paraboloid hemisphere whose texels
//! hold either the *plane* of the surface nearest to the origin ([`VplFormat::Planes`]) or its
//! inverse distance in 16 bits ([`VplFormat::Depth16`]), never a triangle id.
//!
//! # Planes
//!
//! For the plane `n . x = d` and a unit direction `w` from the origin `o`, the plane lies at
//! distance `t = h / (n . w)` along `w`, with `h = d - n . o`. So
//!
//! ```text
//! 1 / t = (n / h) . w
//! ```
//!
//! is *linear* in `w`. A texel stores `g = n / h` of the surface it sees
//! ([`VplMap::planes`], 12 bytes); the occluder's distance along a point's own direction is
//! then one dot product away. This is the test
//! [`Classifier`](crate::classify::Classifier) makes with a triangle id and a table of planes,
//! without the id's second, random memory access; and unlike a depth stored at the texel
//! centre it has no slope error inside the texel. An empty texel holds `g = 0`: nothing in any
//! direction.
//!
//! # 16-bit depths
//!
//! A texel stores `s = scale / t`, `t` the distance to the nearest surface along the texel
//! centre's direction `w_c` (computed from the surface's plane, so exact before rounding), as
//! an IEEE half float ([`VplMap::depths`], 2 bytes: six times as many texels in the same
//! memory). `scale` is `2^12` times the map's near distance, that is `2^-8` times its farthest
//! vertex's distance, so that `s` stays within the half floats' normal range for every drawn
//! distance; rounding to 11 significant bits moves `t` by at most `2^-11 t`. An empty texel
//! holds 0.
//!
//! A depth at the texel centre is not a depth at the point: a receiver seen at a grazing angle
//! moves by many texel footprints in depth across one texel. So the lookup extends the
//! *receiver's* plane (its geometric normal `n_p`) to the centre's direction instead, where
//! it lies at `t_own = r cos_g / cos_c` with `cos_g = -n_p . w`, `cos_c = -n_p . w_c`: the
//! point is hidden when the centre's ray meets a surface in front of `min(t_own, r)` by more
//! than the margin. (`min`: a surface beyond the point along the centre's ray cannot hide it;
//! `cos_c <= cos_g` gives `r`.) This mirrors the planes' test, which extends the occluder's
//! plane to the point's direction.
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
//! both clamped to `[0, res)` ([`VplMap::index`]; the operations in this order, in `f32`, so
//! that vectorised lookups can repeat them bit for bit). The centre of texel `(i, j)` lies at
//! `u = (i + 1/2) 2 / res - 1`, `v = 1 - (j + 1/2) 2 / res`, direction
//! `w_c = t u (1 + z) + b v (1 + z) + a z` with `z = (1 - u^2 - v^2) / (1 + u^2 + v^2)` (a unit
//! vector: the inverse of the projection, [`VplMap::centre_dir`]). Texels whose centre lies
//! outside the paraboloid's unit disc are never drawn; each holds the surface of the nearest
//! drawn texel (its plane, or its plane's distance along the texel's own centre direction),
//! so that a lookup near the rim needs no special case.
//!
//! # Decision
//!
//! A point at distance `r` along `w`, on a surface whose normal makes `cos_g = |n_p . w|` with
//! `w`, is hidden when the stored surface is in front of it by more than
//!
//! ```text
//! margin = bias * texel_angle * r + tol r + e (1 + 1 / cos_g),
//! texel_angle = (1 + a . w) 2 / res
//! ```
//!
//! (the margin of [`Classifier`](crate::classify::Classifier): `bias` texel footprints, the
//! stored value's rounding `tol` ([`VplFormat::tolerance`]), and the rounding band `e` of the
//! point; the paraboloid's texel angle is `2 / (1 + u^2 + v^2) * 2 / res`, and
//! `1 + u^2 + v^2 = 2 / (1 + a . w)` on the unit sphere). With planes: `s = g . w > 0` and
//! `s (r - margin) > 1` ([`VplMap::occluded_by_plane`]); with depths:
//! `s / scale * (min(t_own, r) - margin) > 1`, which [`VplMap::hidden_at`] evaluates without a
//! division: with `cos_c = c / d` (`d = 1 + u^2 + v^2 > 0`), `t_own < r` exactly when
//! `c > cos_g d`, and then the test is `s (r cos_g d - margin c) > c`.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::classify::Plane;
pub use crate::map::Holes;
use crate::map::{EMPTY, LightMap, MapOptions, disc_contains, nearest_in_disc};
use crate::tess::Frame;

/// What a VPL map's texels hold (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VplFormat {
    /// The nearest surface's plane as `g = n / h`, three `f32` (12 bytes).
    Planes,
    /// The nearest surface's inverse distance along the texel centre, a half float (2 bytes).
    #[default]
    Depth16,
}

impl VplFormat {
    /// Relative rounding of the stored distance, as a margin: `1e-5` for planes (a few ulps of
    /// `f32` in `1 / t`), `2^-10` for half floats (twice their rounding).
    pub fn tolerance(self) -> f32 {
        match self {
            VplFormat::Planes => 1e-5,
            VplFormat::Depth16 => 1.0 / 1024.0,
        }
    }

    /// Bytes per texel.
    pub fn texel_bytes(self) -> usize {
        match self {
            VplFormat::Planes => 12,
            VplFormat::Depth16 => 2,
        }
    }

    /// The format's name on the command line and in statistics.
    pub const fn name(self) -> &'static str {
        match self {
            VplFormat::Planes => "planes",
            VplFormat::Depth16 => "depth16",
        }
    }
}

/// The texels of a [`VplMap`], row-major.
#[derive(Clone, Debug)]
enum Texels {
    Planes(Vec<[f32; 3]>),
    /// Half-float bits of `scale / t`, plus one padding element (so that a 4-byte load at the
    /// last texel stays in bounds), and `1 / scale`.
    Depth16 {
        inv_scale: f32,
        bits: Vec<u16>,
    },
}

/// One paraboloid hemisphere of planes or 16-bit depths (module docs).
#[derive(Clone, Debug)]
pub struct VplMap {
    origin: Vec3,
    /// `t, b, a`: the map frame, `a` the axis.
    frame: [Vec3; 3],
    resolution: u32,
    texels: Texels,
}

impl VplMap {
    /// The hemisphere around unit `axis` seen from `origin`, drawn by
    /// [`LightMap::build_hemisphere`] over `tris` with `opts`, each texel's triangle replaced by
    /// what `format` stores of its plane from `planes` (`planes[id]` for triangle `id`; a
    /// missing or zero plane, or one through the origin, stores an empty texel).
    pub fn build(
        tris: &[[Vec3; 3]],
        planes: &[Plane],
        origin: Vec3,
        axis: Vec3,
        opts: &MapOptions,
        format: VplFormat,
    ) -> Self {
        Self::build_with_holes(tris, planes, origin, axis, opts, format, None)
    }

    /// [`VplMap::build`], with the texels that see a hole of a cut-out ([`Holes`]) holding
    /// what lies behind it instead: the surface the same texel sees with the cut-outs left out.
    /// Decided at the texel's centre, as an alpha-tested shadow map does: a lookup casts no
    /// ray to settle a texel that straddles a hole's edge.
    pub fn build_with_holes(
        tris: &[[Vec3; 3]],
        planes: &[Plane],
        origin: Vec3,
        axis: Vec3,
        opts: &MapOptions,
        format: VplFormat,
        holes: Option<&Holes>,
    ) -> Self {
        let map = LightMap::build_hemisphere(tris, origin, axis, opts);
        let frame = Frame::around(axis.as_dvec3());
        let res = map.resolution();
        // The texel (x, y) stands for (outside the disc: the nearest texel inside).
        let source = |x: u32, y: u32| -> Option<(u32, u32)> {
            if disc_contains(res, x, y) {
                Some((x, y))
            } else {
                nearest_in_disc(res, x as f32 + 0.5, y as f32 + 0.5)
            }
        };
        // With cut-outs: the map without them, drawn if some texel sees a hole.
        let behind = holes.and_then(|h| {
            let sees_hole =
                |x: u32, y: u32| h.sees_hole(map.id(0, x, y), centre_dir_f64(frame, res, x, y).as_vec3());
            let any = (0..res)
                .into_par_iter()
                .any(|y| (0..res).any(|x| disc_contains(res, x, y) && sees_hole(x, y)));
            any.then(|| (LightMap::build_hemisphere(h.solid, origin, axis, opts), sees_hole))
        });
        // The plane seen by texel (x, y).
        let plane_at = |x: u32, y: u32| -> Option<&Plane> {
            let (sx, sy) = source(x, y)?;
            let id = match &behind {
                Some((solid, sees_hole)) if sees_hole(sx, sy) => solid.id(0, sx, sy),
                _ => map.id(0, sx, sy),
            };
            planes.get(id as usize).filter(|_| id != EMPTY)
        };
        let n = res as usize * res as usize;
        let texels = match format {
            VplFormat::Planes => {
                let mut g = vec![[0f32; 3]; n];
                g.par_chunks_mut(res as usize).enumerate().for_each(|(y, row)| {
                    for (x, g) in row.iter_mut().enumerate() {
                        let Some(pl) = plane_at(x as u32, y as u32) else { continue };
                        let h = pl.offset_from(origin);
                        let v = pl.n.as_dvec3() / h;
                        if h != 0.0 && v.is_finite() {
                            *g = v.as_vec3().to_array();
                        }
                    }
                });
                Texels::Planes(g)
            }
            VplFormat::Depth16 => {
                let scale = map.near() * 4096.0;
                let mut bits = vec![0u16; n + 1];
                let centre = |x: u32, y: u32| centre_dir_f64(frame, res, x, y);
                bits[..n].par_chunks_mut(res as usize).enumerate().for_each(|(y, row)| {
                    for (x, b) in row.iter_mut().enumerate() {
                        let Some(pl) = plane_at(x as u32, y as u32) else { continue };
                        let cos = pl.n.as_dvec3().dot(centre(x as u32, y as u32));
                        let t = pl.offset_from(origin) / cos;
                        if t > 0.0 && t.is_finite() {
                            *b = half::f16::from_f64(f64::from(scale) / t).to_bits();
                        }
                    }
                });
                Texels::Depth16 { inv_scale: 1.0 / scale, bits }
            }
        };
        let f = |v: DVec3| v.as_vec3();
        VplMap { origin, frame: [f(frame.t), f(frame.b), f(frame.n)], resolution: res, texels }
    }

    /// The texel under unit direction `w` (from the origin), as an index into the texels
    /// (module docs: the formula and its order of operations).
    #[inline]
    pub fn index(&self, w: Vec3) -> usize {
        let [t, b, a] = self.frame;
        let den = 1.0 + (a.x * w.x + a.y * w.y + a.z * w.z);
        let iden = 1.0 / den;
        let u = (t.x * w.x + t.y * w.y + t.z * w.z) * iden;
        let v = (b.x * w.x + b.y * w.y + b.z * w.z) * iden;
        let half = self.resolution as f32 * 0.5;
        let lim = self.last();
        let x = ((u + 1.0) * half).max(0.0).min(lim) as usize;
        let y = ((1.0 - v) * half).max(0.0).min(lim) as usize;
        y * self.resolution as usize + x
    }

    /// The unit direction of texel `(x, y)`'s centre (module docs), in `f32`.
    pub fn centre_dir(&self, x: u32, y: u32) -> Vec3 {
        let [t, b, a] = self.frame;
        let (u, v, z) = centre_uvz(self.resolution, x, y);
        let f = 1.0 + z;
        t * (u * f) + b * (v * f) + a * z
    }

    /// The largest `f32` below the resolution: the clamp of [`VplMap::index`].
    #[inline]
    pub fn last(&self) -> f32 {
        f32::from_bits((self.resolution as f32).to_bits() - 1)
    }

    /// Whether the plane `g` hides the point at distance `r` along `w` by more than `margin`
    /// (module docs).
    #[inline]
    pub fn occluded_by_plane(g: [f32; 3], w: Vec3, r: f32, margin: f32) -> bool {
        let s = g[0] * w.x + g[1] * w.y + g[2] * w.z;
        s > 0.0 && s * (r - margin) > 1.0
    }

    /// Whether the surface stored at texel `(x, y)` hides the point at distance `r` along unit
    /// `w`, on a surface of unit normal `ng` facing the origin (`cos_g = -ng . w > 0`), by more
    /// than `margin` (module docs). In the order of operations of the vectorised lookups.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn hidden_at(&self, x: u32, y: u32, w: Vec3, r: f32, ng: Vec3, cos_g: f32, margin: f32) -> bool {
        let i = (y * self.resolution + x) as usize;
        match &self.texels {
            Texels::Planes(g) => Self::occluded_by_plane(g[i], w, r, margin),
            Texels::Depth16 { inv_scale, bits } => {
                let s = half_to_f32(bits[i]) * inv_scale;
                let [t, b, a] = self.frame;
                // The centre's direction is (2u, 2v, 1 - u^2 - v^2) / (1 + u^2 + v^2) in the map
                // frame: cos_c = c / d, and the test is multiplied through by d and c (no
                // divisions; module docs).
                let inv2 = 2.0 / self.resolution as f32;
                let u = (x as f32 + 0.5) * inv2 - 1.0;
                let v = 1.0 - (y as f32 + 0.5) * inv2;
                let r2 = u * u + v * v;
                let d = 1.0 + r2;
                let nt = ng.x * t.x + ng.y * t.y + ng.z * t.z;
                let nb = ng.x * b.x + ng.y * b.y + ng.z * b.z;
                let na = ng.x * a.x + ng.y * a.y + ng.z * a.z;
                let c = -((nt * (u + u) + nb * (v + v)) + na * (1.0 - r2));
                let beyond =
                    if c > cos_g * d { s * (r * cos_g * d - margin * c) > c } else { s * (r - margin) > 1.0 };
                s > 0.0 && beyond
            }
        }
    }

    /// How the texels are stored.
    pub fn format(&self) -> VplFormat {
        match self.texels {
            Texels::Planes(_) => VplFormat::Planes,
            Texels::Depth16 { .. } => VplFormat::Depth16,
        }
    }

    /// `g = n / h` per texel, row-major, with [`VplFormat::Planes`].
    pub fn planes(&self) -> Option<&[[f32; 3]]> {
        match &self.texels {
            Texels::Planes(g) => Some(g),
            Texels::Depth16 { .. } => None,
        }
    }

    /// With [`VplFormat::Depth16`]: the half-float bits of `scale / t` per texel, row-major,
    /// followed by one padding element, and `1 / scale`.
    pub fn depths(&self) -> Option<(&[u16], f32)> {
        match &self.texels {
            Texels::Depth16 { inv_scale, bits } => Some((bits, *inv_scale)),
            Texels::Planes(_) => None,
        }
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

    /// The distance from the origin to the stored surface along the centre of texel `(x, y)`
    /// (infinite where the texel is empty or out of range).
    pub fn depth(&self, x: u32, y: u32) -> f32 {
        let res = self.resolution;
        if x >= res || y >= res {
            return f32::INFINITY;
        }
        let i = (y * res + x) as usize;
        let s = match &self.texels {
            Texels::Planes(g) => Vec3::from(g[i]).dot(self.centre_dir(x, y)),
            Texels::Depth16 { inv_scale, bits } => half_to_f32(bits[i]) * inv_scale,
        };
        if s > 0.0 { 1.0 / s } else { f32::INFINITY }
    }

    /// Whether texel `(x, y)`'s centre lies in the paraboloid's disc (the texels drawn; the
    /// others hold copies).
    pub fn in_domain(&self, x: u32, y: u32) -> bool {
        x < self.resolution && y < self.resolution && disc_contains(self.resolution, x, y)
    }

    /// Bytes held by the texels.
    pub fn memory_bytes(&self) -> usize {
        match &self.texels {
            Texels::Planes(g) => std::mem::size_of_val(g.as_slice()),
            Texels::Depth16 { bits, .. } => std::mem::size_of_val(bits.as_slice()),
        }
    }
}

/// The value of half-float bits (exact: every half float is an `f32`), as the vectorised
/// lookups convert them.
#[inline]
pub fn half_to_f32(bits: u16) -> f32 {
    half::f16::from_bits(bits).to_f32()
}

/// `(u, v, z)` of texel `(x, y)`'s centre (module docs), in `f32`.
#[inline]
fn centre_uvz(res: u32, x: u32, y: u32) -> (f32, f32, f32) {
    let inv2 = 2.0 / res as f32;
    let u = (x as f32 + 0.5) * inv2 - 1.0;
    let v = 1.0 - (y as f32 + 0.5) * inv2;
    let r2 = u * u + v * v;
    (u, v, (1.0 - r2) / (1.0 + r2))
}

/// The centre direction of texel `(x, y)` in `f64`, for building.
fn centre_dir_f64(frame: Frame, res: u32, x: u32, y: u32) -> DVec3 {
    let inv2 = 2.0 / f64::from(res);
    let (u, v) = ((f64::from(x) + 0.5) * inv2 - 1.0, 1.0 - (f64::from(y) + 0.5) * inv2);
    let r2 = u * u + v * v;
    let z = (1.0 - r2) / (1.0 + r2);
    frame.to_world(DVec3::new(u * (1.0 + z), v * (1.0 + z), z))
}
