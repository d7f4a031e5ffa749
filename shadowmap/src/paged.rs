//! Paged light maps: which texels a frame needs, and at what resolution.
//!
//! A whole cube map draws every texel of a face at one resolution, though a frame's receivers
//! touch few of them, and need more texels where they are small in the map than where they are
//! large. A paged map ([`LightMap::build_pages`](crate::LightMap::build_pages)) has levels
//! `k = 0 ..= MAX_LEVEL`, level `k` with `PAGE << k` texels per face side, cut into pages of
//! [`PAGE`] texels square, and draws only the pages that receivers fall on, each at the level
//! that receiver needs (after Fernando et al. 2001, adaptive shadow maps; Lefohn, Sengupta and
//! Owens 2007, resolution-matched shadow maps; and Unreal Engine 5's virtual shadow maps).
//!
//! # The level a receiver needs
//!
//! A pixel of the camera sees a square of side `d theta` on a surface at distance `d` facing
//! the camera, `theta = 2 tan(fov_y / 2) / height` the angle of one pixel; on a surface whose
//! normal makes cosine `cos_v` with the direction to the camera, the footprint stretches by
//! `1 / cos_v` along the slant, an area of `(d theta)^2 / cos_v`. The texel is matched to the
//! square of the same area, of side `f = d theta / sqrt(cos_v)` (with `cos_v` clamped to at
//! least `1/16`, so at most four times the face-on side): matching the short side instead would
//! spend up to `1 / cos_v` texels per pixel on surfaces seen at a slant, which resolve no more
//! shadow detail in the image than they have pixels. Seen from the light at distance `r`, that
//! side subtends `f / r` radians across the light's direction, but only `f cos_l / r` along it
//! on a surface the light grazes (`cos_l` between the normal and the direction to the light):
//! the shadow of an occluder stretches by `1 / cos_l` there, so the occluder that casts a shadow
//! a pixel wide subtends that much less. The texel is matched to `f cos_l / r`, with `cos_l`
//! clamped to at least [`MIN_COS_LIGHT`] (a surface lit at more of a slant than that gets no
//! finer texels: its shadows rely on the border test and rays). A light whose pages exceed the
//! memory budget gives up this refinement first (`cos_l` taken as 1), then its finest levels. A texel of level `k`
//! subtends at most `2 / (PAGE 2^k)` radians (at the face centre: see
//! [`LightMap::texel_angle`](crate::LightMap::texel_angle)). For texels no larger than
//! `1 / detail` of the footprint, seen from the light,
//!
//! `2 / (PAGE 2^k) <= f cos_l / (r detail)  <=>  2^k >= 2 r detail / (PAGE f cos_l)`,
//!
//! so the level is `k = ceil(log2(r sqrt(cos_v) / (d cos_l) * scale))` with
//! `scale = 2 detail / (PAGE theta)`,
//! clamped to `[0, MAX_LEVEL]` ([`Resolution::level`]). The ceiling of the logarithm is read
//! from the `f32`'s exponent and mantissa bits: exact, so that marking and classification (the
//! same function of the same point) always agree.
//!
//! What resolution buys: an occluder thinner than a texel may fall between the texel centres
//! and be missed by the map and its borders. An occluder of width `w` at distance `r_o` from
//! the light casts a shadow of width `w r / r_o >= w` on a receiver at `r`; it covers a pixel
//! only if that width is about `f` or more, and then the occluder subtends `w / r_o >= f / r`
//! radians: at least `detail` texels. Shadows thinner than a pixel's footprint may still be
//! missed (they cover a pixel centre by chance); `detail` above 1 shrinks that chance.
//!
//! # Marking
//!
//! Each receiver marks the pages under the texels a decision can read: its 2x2 footprint and
//! the margin of the tile test ([`Classifier::hull`](crate::classify::Classifier::hull)), that
//! is every page within [`MARGIN`] texels of its projection ([`pages_around`]). A lookup that
//! still reaches a page not drawn reads [`ABSENT`](crate::map::ABSENT): the point is left to a
//! ray. (So a renderer may mark a sample of the receivers, their neighbours' pages being
//! mostly the same: what it misses costs rays, not accuracy.)
//!
//! # Paraboloid maps
//!
//! Paraboloid maps are not paged: their triangles are tessellated until each projected edge is
//! a few texels long, and at the fine levels that is tens of thousands of sub-triangles per
//! scene triangle (the tessellation cap, [`MAX_TESS`](crate::map::MAX_TESS), then binds and the
//! depths' error grows), where a cube face needs none.

use glam::Vec3;

use crate::map::{MAX_LEVEL, MapCoord, PAGE, PageKey, cube_coord};

/// Texels around a receiver's projection whose pages it marks: the half texel of the 2x2
/// footprint plus the tile test's margin of 1.5 texels, rounded up.
pub const MARGIN: f64 = 2.0;

/// The least cosine between a receiver's normal and the direction to the light that
/// [`Resolution::level`] refines for: a surface the light grazes more gets the texels of one at
/// this slant (module docs).
pub const MIN_COS_LIGHT: f32 = 1.0 / 16.0;

/// How a frame picks the level of a receiver (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolution {
    /// The camera's position.
    pub eye: Vec3,
    /// `2 detail / (PAGE theta)`, `theta` the angle of one pixel.
    pub scale: f32,
    /// The finest level allowed (a memory budget's doing): receivers that need finer texels
    /// get this level's. [`MAX_LEVEL`] by default.
    pub cap: u8,
    /// The least `cos_l` refined for ([`MIN_COS_LIGHT`] by default; 1 refines none: the first
    /// thing a memory budget gives up).
    pub min_cos_light: f32,
}

impl Resolution {
    /// The resolution guide for a camera at `eye` whose pixels subtend `pixel_angle` radians,
    /// with texels `detail` times finer than a pixel's footprint.
    pub fn new(eye: Vec3, pixel_angle: f32, detail: f32) -> Self {
        Self {
            eye,
            scale: 2.0 * detail / (PAGE as f32 * pixel_angle),
            cap: MAX_LEVEL,
            min_cos_light: MIN_COS_LIGHT,
        }
    }

    /// The level a receiver at `p`, whose surface's normal makes cosine `cos_view` with the
    /// direction to the camera, needs for a light at `light` (module docs): the coarsest whose
    /// texels are no larger than `1 / detail` of the pixel's footprint, then
    /// capped at [`Resolution::cap`]; 0 for NaN input.
    #[inline]
    pub fn level(&self, p: Vec3, n: Vec3, cos_view: f32, light: Vec3) -> u8 {
        self.level_for(self.receiver(p, cos_view), p, n, light)
    }

    /// The part of [`Resolution::level`] that depends on the receiver alone (the same for
    /// every light): `sqrt(cos_view) / d * scale`, `cos_view` clamped to `[1/16, 1]`.
    #[inline]
    pub fn receiver(&self, p: Vec3, cos_view: f32) -> f32 {
        self.receiver_at((p - self.eye).length(), cos_view)
    }

    /// [`Resolution::receiver`] for a point seen at distance `dist` along its view path: a
    /// point seen in a flat mirror is seen as through a window, at the length of the whole
    /// path (eye to mirror to point), not at its distance from the eye.
    #[inline]
    pub fn receiver_at(&self, dist: f32, cos_view: f32) -> f32 {
        cos_view.abs().clamp(1.0 / 16.0, 1.0).sqrt() / dist * self.scale
    }

    /// [`Resolution::level`] from [`Resolution::receiver`]'s factor, for a receiver with unit
    /// normal `n`: `r / max(cos_l, MIN_COS_LIGHT)` times the factor, `cos_l = |n . (L - p)| / r`.
    #[inline]
    pub fn level_for(&self, receiver: f32, p: Vec3, n: Vec3, light: Vec3) -> u8 {
        self.level_from(receiver, LightTerms::of(p, n, light))
    }

    /// [`Resolution::level_for`] from the receiver's [`LightTerms`] (which do not depend on
    /// the guide: several guides share them).
    #[inline]
    pub fn level_from(&self, receiver: f32, t: LightTerms) -> u8 {
        self.level_of_ratio(self.ratio(receiver, t))
    }

    /// What [`Resolution::level_from`] takes the logarithm of: `r / max(cos_l, MIN_COS_LIGHT)`
    /// times the receiver's factor. The level never falls as it grows (NaN gives level 0), so
    /// the finest level of several receivers is that of their largest ratio: one logarithm for
    /// a tile of points.
    #[inline]
    pub fn ratio(&self, receiver: f32, t: LightTerms) -> f32 {
        t.r / t.cos_light.max(self.min_cos_light) * receiver
    }

    /// The level of a [`Resolution::ratio`], capped.
    #[inline]
    pub fn level_of_ratio(&self, ratio: f32) -> u8 {
        ceil_log2(ratio).min(self.cap).min(MAX_LEVEL)
    }
}

/// The parts of [`Resolution::level_for`] that depend on the receiver and the light alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightTerms {
    /// The distance from the receiver to the light.
    pub r: f32,
    /// `|n . (L - p)| / r`.
    pub cos_light: f32,
}

impl LightTerms {
    /// The terms of a receiver at `p` with unit normal `n`, for a light at `light`.
    #[inline]
    pub fn of(p: Vec3, n: Vec3, light: Vec3) -> Self {
        let v = light - p;
        Self::of_offset(n, v, v.length())
    }

    /// [`LightTerms::of`] from the receiver's offset `v = light - p` and its length `r`, for
    /// callers that have them already.
    #[inline]
    pub fn of_offset(n: Vec3, v: Vec3, r: f32) -> Self {
        Self { r, cos_light: n.dot(v).abs() / r }
    }
}

/// `ceil(log2(x))` clamped to `[0, 255]` for `x > 0` (0 for `x <= 1`, NaN, subnormals; 255
/// for infinity), exactly, from the bits.
#[inline]
pub fn ceil_log2(x: f32) -> u8 {
    if x.is_nan() || x <= 1.0 {
        return 0;
    }
    if x.is_infinite() {
        return u8::MAX;
    }
    let b = x.to_bits();
    let exp = ((b >> 23) & 0xff) as i32 - 127;
    let k = exp + i32::from(b & 0x7f_ffff != 0);
    k.clamp(0, 255) as u8
}

/// Where direction `dir` (from the light) falls in a paged cube map at `level`: the same as
/// [`LightMap::coord_at`](crate::LightMap::coord_at) of such a map, without one.
#[inline]
pub fn locate(dir: Vec3, level: u8) -> MapCoord {
    cube_coord(dir, PAGE << level.min(MAX_LEVEL), level)
}

/// Calls `mark` with each page within [`MARGIN`] texels of `c` (a paged cube map's
/// coordinate): one to four pages, on `c`'s face only (footprints that leave the face are left
/// to rays).
#[inline]
pub fn pages_around(c: MapCoord, mark: impl FnMut(PageKey)) {
    PageRect::around(c).for_each(mark);
}

/// A rectangle of pages of one level and face: pages `x0..=x1` by `y0..=y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageRect {
    pub level: u8,
    pub face: u8,
    pub x0: u32,
    pub x1: u32,
    pub y0: u32,
    pub y1: u32,
}

impl PageRect {
    /// The pages within [`MARGIN`] texels of `c` ([`pages_around`]): neighbouring receivers
    /// mostly have the same rectangle, which a marker compares instead of its pages.
    #[inline]
    pub fn around(c: MapCoord) -> Self {
        let n = 1u32 << c.level.min(MAX_LEVEL);
        // Truncation is the floor here (the value is clamped to >= 0 first; NaN gives 0).
        let page = |v: f64| ((v.max(0.0) / f64::from(PAGE)) as u32).min(n - 1);
        let (x0, x1) = (page(c.x - MARGIN), page(c.x + MARGIN));
        let (y0, y1) = (page(c.y - MARGIN), page(c.y + MARGIN));
        Self { level: c.level, face: c.face, x0, x1, y0, y1 }
    }

    /// Calls `mark` with each page of the rectangle.
    #[inline]
    pub fn for_each(self, mut mark: impl FnMut(PageKey)) {
        for py in self.y0..=self.y1 {
            for px in self.x0..=self.x1 {
                mark(PageKey { level: self.level, face: self.face, py, px });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceil_log2_is_exact() {
        assert_eq!(ceil_log2(0.0), 0);
        assert_eq!(ceil_log2(f32::NAN), 0);
        assert_eq!(ceil_log2(-4.0), 0);
        assert_eq!(ceil_log2(1.0), 0);
        assert_eq!(ceil_log2(1.0f32.next_up()), 1);
        assert_eq!(ceil_log2(2.0), 1);
        assert_eq!(ceil_log2(3.0), 2);
        assert_eq!(ceil_log2(4.0), 2);
        assert_eq!(ceil_log2(4.0f32.next_up()), 3);
        assert_eq!(ceil_log2(f32::INFINITY), 255);
        for k in 0..100 {
            let x = 2f32.powi(k);
            assert_eq!(ceil_log2(x), k as u8);
            assert_eq!(ceil_log2(x.next_up()), k as u8 + 1);
        }
    }

    #[test]
    fn level_grows_with_distance_from_the_light_and_shrinks_with_the_camera() {
        let r = Resolution::new(Vec3::ZERO, 2.0 / 480.0, 1.0);
        let up = Vec3::Y;
        let near = r.level(Vec3::new(0.0, 0.0, 1.0), up, 1.0, Vec3::new(0.0, 1.0, 1.0));
        let far_light = r.level(Vec3::new(0.0, 0.0, 1.0), up, 1.0, Vec3::new(0.0, 100.0, 1.0));
        let far_cam = r.level(Vec3::new(0.0, 0.0, 10.0), up, 1.0, Vec3::new(0.0, 1.0, 10.0));
        // A surface slanted to the camera needs coarser texels, at most 2 levels (a factor 4).
        let slant = r.level(Vec3::new(0.0, 0.0, 1.0), up, 0.2, Vec3::new(0.0, 100.0, 1.0));
        let grazing = r.level(Vec3::new(0.0, 0.0, 1.0), up, 0.0, Vec3::new(0.0, 100.0, 1.0));
        assert!(slant < far_light && grazing == far_light - 2, "{slant} {grazing} {far_light}");
        // One the light grazes needs finer ones, at most 4 levels (a factor 16).
        let lit_slant = r.level(Vec3::new(0.0, 0.0, 1.0), up, 1.0, Vec3::new(100.0, 0.0, 1.0));
        assert_eq!(lit_slant, far_light + 4, "{lit_slant} {far_light}");
        assert!(far_light > near && far_cam < near, "{near} {far_light} {far_cam}");
        // A texel at the level is no larger than the footprint: 2 / (PAGE 2^k) <= f / r.
        let (d, dist) = (1.0f32, 100.0f32);
        let k = far_light;
        assert!(2.0 / (PAGE as f32 * 2f32.powi(k.into())) <= d * 2.0 / 480.0 / dist);
        assert!(2.0 / (PAGE as f32 * 2f32.powi(i32::from(k) - 1)) > d * 2.0 / 480.0 / dist);
        // Degenerate input: no panic, a level in range.
        assert!(r.level(Vec3::ZERO, up, 1.0, Vec3::ZERO) <= MAX_LEVEL);
        assert!(r.level(Vec3::NAN, up, f32::NAN, Vec3::ONE) <= MAX_LEVEL);
        assert_eq!(r.level(Vec3::ONE, up, 1.0, Vec3::splat(1e30)), MAX_LEVEL);
    }

    #[test]
    fn pages_around_cover_the_margin() {
        for (x, y) in [(0.5, 0.5), (63.0, 10.0), (64.5, 127.9), (200.0, 5.0)] {
            let c = MapCoord { face: 2, level: 2, x, y };
            let mut got = Vec::new();
            pages_around(c, |k| got.push(k));
            for dx in [-MARGIN, 0.0, MARGIN] {
                for dy in [-MARGIN, 0.0, MARGIN] {
                    let page = f64::from(PAGE);
                    let (px, py) = (((x + dx).max(0.0) / page) as u32, ((y + dy).max(0.0) / page) as u32);
                    let (px, py) = (px.min(3), py.min(3));
                    assert!(
                        got.contains(&PageKey { level: 2, face: 2, py, px }),
                        "({x}, {y}) + ({dx}, {dy})"
                    );
                }
            }
            assert!(got.len() <= 4);
        }
    }
}
