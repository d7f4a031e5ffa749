//! Colour textures: decoded once from sRGB to linear, kept as a mip chain, sampled bilinearly
//! at the level a shading point's footprint asks for.
//!
//! # Levels
//!
//! Level 0 is the image; each next level halves both sides (rounding down, at least one
//! texel), each of its texels the mean of the 2x2 (or, on an odd side's last row or column,
//! 2x1, 1x2 or 1x1) texels of the level above it, in linear light, stored as the nearest sRGB
//! bytes (`Level`).
//!
//! # Which level
//!
//! A shading point covers a footprint of `w` in texture coordinates (`u` and `v` in `[0, 1]`
//! over the image; [`footprint`] derives it). At level `k` a texel spans `2^k / n` of them, `n`
//! the image's larger side, so the level whose texels are about as large as the footprint is
//! `k = floor(log2(w n))`, clamped to the chain: the texels are then no larger than the
//! footprint (at most twice finer), the choice that keeps detail and still averages what one
//! pixel covers. `w <= 0`, NaN or tiny gives level 0.
//!
//! # Addressing
//!
//! Coordinates repeat (glTF's default wrap and what OBJ files expect): `u` and `u + 1` read the
//! same texel. `v = 0` is the image's top row (glTF's convention; OBJ's `vt` counts from the
//! bottom, and the OBJ loader flips it). Bilinear weights come from the point's offset to the
//! four texel centres around it, wrapping at the edges.

use std::path::Path;

use anyhow::{Result, anyhow};
use glam::{Vec2, Vec3};

/// A decoded colour texture with its mip chain (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it was read from, for messages.
    pub name: String,
    levels: Vec<Level>,
}

/// One level of the chain: `width x height` texels, row-major, row 0 at the top, each its
/// sRGB-encoded RGB bytes and a padding byte.
///
/// Why bytes: sampling reads four texels per shading point from levels that do not stay in
/// cache from frame to frame; four bytes a texel, decoded by a table, move a third of what
/// linear `f32` triples do. Level 0 decodes to exactly the linear values of its file; the
/// others are means taken in linear light (from the unrounded level above) and rounded to the
/// nearest sRGB byte, within half a step of the mean.
#[derive(Clone, Debug, PartialEq)]
struct Level {
    width: u32,
    height: u32,
    texels: Vec<[u8; 4]>,
}

/// [`srgb_to_linear`] of every byte.
fn decode_table() -> &'static [f32; 256] {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|c| srgb_to_linear(c as u8)))
}

/// Linear light `x` to the nearest sRGB byte (IEC 61966-2-1), clamped to `[0, 1]`.
fn linear_to_srgb8(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let e = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (e * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Decodes an encoded image (PNG or JPEG) named `name` in messages.
pub fn decode_image(name: &str, bytes: &[u8]) -> Result<image::DynamicImage> {
    image::load_from_memory(bytes).map_err(|e| anyhow!("{name}: cannot decode the image: {e}"))
}

/// Reads and decodes an image file (PNG or JPEG).
pub fn load_image(path: &Path) -> Result<image::DynamicImage> {
    let bytes = super::obj::read_bytes(path)?;
    decode_image(&path.display().to_string(), &bytes)
}

/// sRGB-encoded value `c` (0..=255) to linear light (IEC 61966-2-1).
pub fn srgb_to_linear(c: u8) -> f32 {
    let x = f32::from(c) / 255.0;
    if x <= 0.04045 { x / 12.92 } else { ((x + 0.055) / 1.055).powf(2.4) }
}

impl Texture {
    /// A texture from `width x height` sRGB-encoded RGB texels (row-major, 3 bytes each, row 0
    /// at the top); `None` for an empty image or a buffer of the wrong length.
    pub fn from_srgb8(name: &str, width: u32, height: u32, rgb: &[u8]) -> Option<Self> {
        if width == 0 || height == 0 || rgb.len() != width as usize * height as usize * 3 {
            return None;
        }
        let lut = decode_table();
        let texels: Vec<[u8; 4]> = rgb.chunks_exact(3).map(|c| [c[0], c[1], c[2], 0]).collect();
        // The chain is made from linear means of the level above before its rounding.
        let mut linear: Vec<Vec3> = texels
            .iter()
            .map(|c| Vec3::new(lut[c[0] as usize], lut[c[1] as usize], lut[c[2] as usize]))
            .collect();
        let mut levels = vec![Level { width, height, texels }];
        let (mut w, mut h) = (width, height);
        while let Some((w2, h2, next)) = half(w, h, &linear) {
            let texels = next
                .iter()
                .map(|c| [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 0])
                .collect();
            levels.push(Level { width: w2, height: h2, texels });
            (w, h, linear) = (w2, h2, next);
        }
        Some(Self { name: name.to_string(), levels })
    }

    /// Decodes an image file (PNG or JPEG; alpha is dropped: see [`super::cutout::Mask`]).
    pub fn load(path: &Path) -> Result<Self> {
        Self::from_image(&path.display().to_string(), &load_image(path)?)
    }

    /// Decodes an encoded image (PNG or JPEG) named `name` in messages.
    pub fn decode(name: &str, bytes: &[u8]) -> Result<Self> {
        Self::from_image(name, &decode_image(name, bytes)?)
    }

    /// The colour texture of a decoded image (its alpha dropped).
    pub fn from_image(name: &str, img: &image::DynamicImage) -> Result<Self> {
        let rgb = img.to_rgb8();
        Self::from_srgb8(name, rgb.width(), rgb.height(), rgb.as_raw())
            .ok_or_else(|| anyhow!("{name}: the image is empty"))
    }

    /// Width and height of level 0.
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// Number of levels in the chain.
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// The level a footprint of `w` texture coordinates reads (module docs).
    pub fn level_for(&self, w: f32) -> usize {
        self.level_for_squared(w * w)
    }

    /// [`Texture::level_for`] of a footprint whose square is `w2`: `floor(log2(w n))` is
    /// `floor(floor(log2(w^2 n^2)) / 2)` (halving commutes with `floor` on integers), so no
    /// square root is taken.
    pub fn level_for_squared(&self, w2: f32) -> usize {
        let (width, height) = self.size();
        let n = width.max(height) as f32;
        let x = w2 * n * n;
        // Below two texels (NaN too): level 0.
        if x.is_nan() || x < 4.0 {
            return 0;
        }
        // floor(log2(x)) from the exponent, exactly (x is normal and >= 4 here).
        let k = (((x.to_bits() >> 23) & 0xff) as usize - 127) / 2;
        k.min(self.levels.len() - 1)
    }

    /// The colour at texture coordinates `uv` for a footprint of `w` (module docs): bilinear
    /// at [`Texture::level_for`]`(w)`. Non-finite coordinates read texel (0, 0).
    pub fn sample(&self, uv: Vec2, w: f32) -> Vec3 {
        self.levels[self.level_for(w)].bilinear(uv)
    }

    /// [`Texture::sample`] for a footprint whose square is `w2` ([`footprint_squared`]).
    pub fn sample_squared(&self, uv: Vec2, w2: f32) -> Vec3 {
        self.levels[self.level_for_squared(w2)].bilinear(uv)
    }
}

/// The next level of a `width x height` level of linear texels (module docs): its size and
/// texels, `None` at 1x1.
fn half(width: u32, height: u32, texels: &[Vec3]) -> Option<(u32, u32, Vec<Vec3>)> {
    if width == 1 && height == 1 {
        return None;
    }
    let (w, h) = ((width / 2).max(1), (height / 2).max(1));
    let mut out = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        for x in 0..w {
            // The texels of this level that texel (x, y) of the next covers.
            let xs = if width == 1 {
                0..1
            } else {
                2 * x..(2 * x + 2 + u32::from(x == w - 1 && width % 2 == 1)).min(width)
            };
            let ys = if height == 1 {
                0..1
            } else {
                2 * y..(2 * y + 2 + u32::from(y == h - 1 && height % 2 == 1)).min(height)
            };
            let (mut sum, mut n) = (Vec3::ZERO, 0.0f32);
            for sy in ys {
                for sx in xs.clone() {
                    sum += texels[(sy * width + sx) as usize];
                    n += 1.0;
                }
            }
            out.push(sum / n);
        }
    }
    Some((w, h, out))
}

impl Level {
    /// Texel `i`, in linear light.
    #[inline]
    fn texel(&self, i: usize) -> Vec3 {
        let (lut, c) = (decode_table(), self.texels[i]);
        Vec3::new(lut[c[0] as usize], lut[c[1] as usize], lut[c[2] as usize])
    }

    /// Bilinear interpolation of the four texel centres around `uv`, repeating.
    fn bilinear(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as f32, self.height as f32);
        let (x, y) = (uv.x * w - 0.5, uv.y * h - 0.5);
        if !(x.is_finite() && y.is_finite()) {
            return self.texel(0);
        }
        let (fx, fy) = (floor(x), floor(y));
        let (ax, ay) = (x - fx as f32, y - fy as f32);
        let (x0, y0) = (wrap(fx, self.width), wrap(fy, self.height));
        let next = |v: u32, n: u32| if v + 1 == n { 0 } else { v + 1 };
        let (x1, y1) = (next(x0, self.width), next(y0, self.height));
        let t = |x: u32, y: u32| self.texel((y * self.width + x) as usize);
        let top = t(x0, y0) * (1.0 - ax) + t(x1, y0) * ax;
        let bottom = t(x0, y1) * (1.0 - ax) + t(x1, y1) * ax;
        top * (1.0 - ay) + bottom * ay
    }
}

/// `v.floor()` as an integer, by conversions (without SSE4.1 in the target `f32::floor` is a
/// call into libm, once per sample). `v` is finite; beyond `i64`'s range it saturates, which
/// [`wrap`] then takes to some texel of the image.
#[inline]
pub(crate) fn floor(v: f32) -> i64 {
    let i = v as i64;
    if (i as f32) > v { i - 1 } else { i }
}

/// Texel index `i` repeated into `0..n` (`n > 0`). Divisions are slow: an index already in
/// range (coordinates in `[0, 1)`) is itself, a power-of-two side takes a mask (two's
/// complement makes it the Euclidean remainder for negative `i` too), and only the rest a
/// remainder.
#[inline]
pub(crate) fn wrap(i: i64, n: u32) -> u32 {
    if (0..i64::from(n)).contains(&i) {
        i as u32
    } else if n.is_power_of_two() {
        i as u32 & (n - 1)
    } else if let Ok(i) = i32::try_from(i) {
        // `n <= i32::MAX` for any image: a 32-bit division, a fraction of a 64-bit one.
        i.rem_euclid(n as i32) as u32
    } else {
        i.rem_euclid(i64::from(n)) as u32
    }
}

/// The footprint in texture coordinates of a shading point seen at distance `t` along a ray
/// whose pixel subtends `pixel_angle` radians, on a triangle whose texture coordinates cover
/// `uv_per_world` of them per unit of length (`sqrt(uv area / world area)`), seen at cosine
/// `cos` to its normal: the pixel's footprint on the surface is about `t pixel_angle` across,
/// stretched by `1 / cos` along one axis; its geometric mean `t pixel_angle / sqrt(cos)` is
/// the width used (anisotropy is not filtered). `cos` is taken as at least 1/64, so that
/// grazing views do not blur to the last level.
pub fn footprint(t: f32, pixel_angle: f32, cos: f32, uv_per_world: f32) -> f32 {
    t * pixel_angle / cos.abs().max(1.0 / 64.0).sqrt() * uv_per_world
}

/// The square of [`footprint`]`(t, pixel_angle, cos, uv_per_world(p, uv))`, with one square
/// root where the product takes three (shading asks it for every textured point):
/// `(t pixel_angle)^2 / max(|cos|, 1/64) * uv area / world area`. 0 for a degenerate triangle.
pub fn footprint_squared(t: f32, pixel_angle: f32, cos: f32, p: &[Vec3; 3], uv: &[Vec2; 3]) -> f32 {
    let world = (p[1] - p[0]).cross(p[2] - p[0]).length();
    let (a, b) = (uv[1] - uv[0], uv[2] - uv[0]);
    let tex = (a.x * b.y - a.y * b.x).abs();
    let ta = t * pixel_angle;
    let w2 = ta * ta * tex / (cos.abs().max(1.0 / 64.0) * world);
    if w2.is_finite() { w2 } else { 0.0 }
}

/// `sqrt(uv area / world area)` of a triangle with corners `p` and texture coordinates `uv`:
/// texture coordinates per unit of length on it, for [`footprint`]. 0 for a degenerate one.
pub fn uv_per_world(p: &[Vec3; 3], uv: &[Vec2; 3]) -> f32 {
    let world = (p[1] - p[0]).cross(p[2] - p[0]).length();
    let (a, b) = (uv[1] - uv[0], uv[2] - uv[0]);
    let tex = (a.x * b.y - a.y * b.x).abs();
    let r = (tex / world).sqrt();
    if r.is_finite() { r } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Texture {
        let f = &f;
        let rgb: Vec<u8> = (0..h).flat_map(|y| (0..w).flat_map(move |x| f(x, y))).collect();
        Texture::from_srgb8("t", w, h, &rgb).unwrap()
    }

    #[test]
    fn srgb_decoding_is_the_standard_curve() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        assert!((srgb_to_linear(188) - 0.5029).abs() < 1e-3);
        assert!((srgb_to_linear(10) - 10.0 / 255.0 / 12.92).abs() < 1e-7);
    }

    #[test]
    fn mip_chain_halves_odd_sides_and_averages_in_linear_light() {
        let t = tex(5, 3, |x, _| if x % 2 == 0 { [255, 255, 255] } else { [0, 0, 0] });
        let sizes: Vec<(u32, u32)> = t.levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(5, 3), (2, 1), (1, 1)]);
        // Level 1's last texel covers columns 2, 3 and 4 (odd width) of all three rows: 2/3
        // white in linear light, not in sRGB.
        // Each within half an sRGB step of the mean (under 0.003 in linear light there).
        let close = |l: usize, i: usize, want: f32| {
            let got = t.levels[l].texel(i).x;
            assert!((got - want).abs() < 0.003, "level {l} texel {i}: {got} for {want}");
        };
        close(1, 1, 2.0 / 3.0);
        close(1, 0, 0.5);
        // The next level averages level 1's two texels (not all 15 of level 0's), before their
        // rounding.
        close(2, 0, (0.5 + 2.0 / 3.0) / 2.0);
        // Rounding: the byte nearest the encoded value, and back.
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb_to_linear(c)), c);
        }
        assert!(Texture::from_srgb8("e", 0, 4, &[]).is_none());
        assert!(Texture::from_srgb8("short", 2, 2, &[0; 11]).is_none());
    }

    #[test]
    fn sampling_reads_texel_centres_exactly_and_repeats() {
        let t = tex(4, 2, |x, y| [(x * 60) as u8, (y * 200) as u8, 7]);
        for y in 0..2 {
            for x in 0..4 {
                let uv = Vec2::new((x as f32 + 0.5) / 4.0, (y as f32 + 0.5) / 2.0);
                let want = Vec3::new(
                    srgb_to_linear((x * 60) as u8),
                    srgb_to_linear((y * 200) as u8),
                    srgb_to_linear(7),
                );
                assert_eq!(t.sample(uv, 0.0), want);
                assert_eq!(t.sample(uv + Vec2::new(3.0, -2.0), 0.0), want, "repeat");
            }
        }
        // Half-way between the last column and the first (wrapping).
        let mid = t.sample(Vec2::new(1.0, 0.25), 0.0);
        assert!((mid.x - 0.5 * srgb_to_linear(180)).abs() < 1e-6);
        assert_eq!(t.sample(Vec2::new(f32::NAN, 0.5), 0.0), t.levels[0].texel(0));
    }

    #[test]
    fn the_level_matches_the_footprint() {
        let t = tex(64, 16, |_, _| [1, 2, 3]);
        assert_eq!(t.levels(), 7);
        // One texel of 64 per side is 1/64 of the coordinates: level 0 up to (not at) 2 texels.
        assert_eq!(t.level_for(0.0), 0);
        assert_eq!(t.level_for(f32::NAN), 0);
        assert_eq!(t.level_for(1.9 / 64.0), 0);
        assert_eq!(t.level_for(2.0 / 64.0), 1);
        assert_eq!(t.level_for(7.9 / 64.0), 2);
        assert_eq!(t.level_for(8.0 / 64.0), 3);
        assert_eq!(t.level_for(1e9), 6);
        assert_eq!(t.level_for(f32::INFINITY), 6);
    }

    #[test]
    fn footprint_and_texture_density() {
        let p = [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)];
        let uv = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
        assert!((uv_per_world(&p, &uv) - 0.5).abs() < 1e-6);
        assert_eq!(uv_per_world(&[Vec3::ZERO; 3], &uv), 0.0);
        assert!((footprint(10.0, 0.001, 1.0, 0.5) - 0.005).abs() < 1e-9);
        assert!((footprint(10.0, 0.001, 0.25, 0.5) - 0.01).abs() < 1e-9);
        assert_eq!(footprint(10.0, 0.001, 0.0, 0.5), footprint(10.0, 0.001, 1.0 / 64.0, 0.5));
        // The squared form, without its square roots: the same up to rounding.
        for cos in [1.0, 0.25, 0.0] {
            let w = footprint(10.0, 0.001, cos, uv_per_world(&p, &uv));
            let w2 = footprint_squared(10.0, 0.001, cos, &p, &uv);
            assert!((w2 / (w * w) - 1.0).abs() < 1e-6, "{w2} {w}");
        }
        assert_eq!(footprint_squared(10.0, 0.001, 1.0, &[Vec3::ZERO; 3], &uv), 0.0);
    }
}
