//! Alpha cut-outs: surfaces with holes drawn by a texture (leaves, fences, grilles).
//!
//! # Where the alpha comes from
//!
//! - glTF `alphaMode: MASK`: the base colour's alpha, `baseColorFactor[3]` times the
//!   `baseColorTexture`'s alpha channel, against `alphaCutoff` (0.5 by default). `BLEND` is
//!   read as a mask at 0.5: hyrt has no transparency, and a hole or a solid surface is the
//!   nearest it can draw.
//! - MTL `map_d`: the image's alpha channel if it has one, else its grey level (a mask painted
//!   in black and white), against 0.5. A plain `d < 1` is transparency, not a cut-out, and is
//!   drawn opaque (with a warning).
//!
//! # The test
//!
//! A point of a triangle with barycentrics `b` is solid when the alpha there, bilinear over
//! the mask's texels at full resolution (the colour texture's addressing: repeat, `v = 0` at
//! the top row), is at least the cut-off. Level 0 always, whatever the footprint: the same
//! point must be solid or a hole for a camera ray, a shadow ray and a mirror ray alike (they
//! have no common footprint), and a shadow map must agree with the rays that settle its
//! borders. Mipmapped alpha would also thin distant foliage to nothing.
//!
//! Every visibility path applies it: the tracer through [`CutoutTest`] (closest hits and
//! occlusion alike), the rasterized G-buffer by casting the pixel's ray where its triangle
//! has a hole, and light and VPL maps by holding, where a texel's centre sees a hole, what
//! lies behind it (`hyrt_shadowmap::map::Holes`; with `--cutout-maps rays` light maps hold
//! cut-outs solid and every point one would shadow goes to a ray,
//! `hyrt_shadowmap::classify::Classifier::cutouts`).

use glam::Vec2;

use super::Scene;
use super::texture::{floor, wrap};

/// Where a [`Mask`]'s alpha is read from in its image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    /// The alpha channel (none: every texel is 1).
    Alpha,
    /// The alpha channel if the image has one, else its grey level (MTL `map_d`).
    AlphaOrGrey,
}

/// A cut-out mask: one alpha value per texel of an image, `0..=255` for `[0, 1]`, full
/// resolution only (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    /// Where it was read from, for messages.
    pub name: String,
    width: u32,
    height: u32,
    alpha: Vec<u8>,
}

impl Mask {
    /// The mask of a decoded image; `None` for an empty one, or with [`Channel::Alpha`] for
    /// one without an alpha channel (it has no holes).
    pub fn from_image(name: &str, img: &image::DynamicImage, channel: Channel) -> Option<Self> {
        let (width, height) = (img.width(), img.height());
        if width == 0 || height == 0 {
            return None;
        }
        let alpha = if img.color().has_alpha() {
            img.to_luma_alpha8().pixels().map(|p| p.0[1]).collect()
        } else if channel == Channel::AlphaOrGrey {
            img.to_luma8().into_raw()
        } else {
            return None;
        };
        Some(Self { name: name.to_string(), width, height, alpha })
    }

    /// A mask from `width x height` alpha bytes (row-major, row 0 at the top); `None` for an
    /// empty image or a buffer of the wrong length.
    pub fn from_bytes(name: &str, width: u32, height: u32, alpha: Vec<u8>) -> Option<Self> {
        (width > 0 && height > 0 && alpha.len() == width as usize * height as usize).then(|| Self {
            name: name.to_string(),
            width,
            height,
            alpha,
        })
    }

    /// The alpha at texture coordinates `uv`, bilinear over the four texel centres around it,
    /// repeating (the colour texture's addressing); non-finite coordinates read texel (0, 0).
    pub fn alpha(&self, uv: Vec2) -> f32 {
        let (w, h) = (self.width as f32, self.height as f32);
        let (x, y) = (uv.x * w - 0.5, uv.y * h - 0.5);
        let t = |x: u32, y: u32| f32::from(self.alpha[(y * self.width + x) as usize]) / 255.0;
        if !(x.is_finite() && y.is_finite()) {
            return t(0, 0);
        }
        let (fx, fy) = (floor(x), floor(y));
        let (ax, ay) = (x - fx as f32, y - fy as f32);
        let (x0, y0) = (wrap(fx, self.width), wrap(fy, self.height));
        let next = |v: u32, n: u32| if v + 1 == n { 0 } else { v + 1 };
        let (x1, y1) = (next(x0, self.width), next(y0, self.height));
        let top = t(x0, y0) * (1.0 - ax) + t(x1, y0) * ax;
        let bottom = t(x0, y1) * (1.0 - ax) + t(x1, y1) * ax;
        top * (1.0 - ay) + bottom * ay
    }
}

/// A material's cut-out: solid where `scale * alpha(uv) >= cutoff`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutout {
    /// The mask (an index into the scene's masks); `None`: alpha 1 everywhere.
    pub mask: Option<u32>,
    /// Multiplies the mask's alpha (glTF `baseColorFactor[3]`; 1 for MTL).
    pub scale: f32,
    /// The alpha below which the surface is a hole (glTF `alphaCutoff`; 0.5 for MTL and
    /// glTF `BLEND`).
    pub cutoff: f32,
}

impl Cutout {
    /// The glTF default `alphaCutoff`, and the cut-off of MTL masks and glTF `BLEND`.
    pub const DEFAULT_CUTOFF: f32 = 0.5;
}

impl Scene {
    /// The cut-out of triangle `tri`'s material, if it has one.
    #[inline]
    pub fn cutout(&self, tri: u32) -> Option<&Cutout> {
        let m = self.material.get(tri as usize)?;
        self.materials.get(*m as usize)?.cutout.as_ref()
    }

    /// Whether the point of triangle `tri` at barycentrics `bary` is solid (module docs):
    /// always, for a triangle without a cut-out.
    pub fn solid_at(&self, tri: u32, bary: [f32; 3]) -> bool {
        self.alpha_at(tri, bary).is_none_or(|(alpha, c)| alpha >= c.cutoff)
    }

    /// The alpha at barycentrics `bary` of triangle `tri` (its cut-out's factor times its
    /// mask's alpha there), with the cut-out; `None` for a triangle without one.
    pub fn alpha_at(&self, tri: u32, bary: [f32; 3]) -> Option<(f32, &Cutout)> {
        let c = self.cutout(tri)?;
        let uv = self.uvs.get(tri as usize).copied().unwrap_or([Vec2::ZERO; 3]);
        let alpha = c
            .mask
            .and_then(|k| self.masks.get(k as usize))
            .map_or(1.0, |m| m.alpha(uv[0] * bary[0] + uv[1] * bary[1] + uv[2] * bary[2]));
        Some((c.scale * alpha, c))
    }

    /// Per triangle, whether it has a cut-out; empty when no triangle has (the form
    /// `hyrt_shadowmap::classify::Classifier::cutouts` takes).
    pub fn cutout_flags(&self) -> Vec<bool> {
        if self.materials.iter().all(|m| m.cutout.is_none()) {
            return Vec::new();
        }
        (0..self.triangle_count() as u32).map(|t| self.cutout(t).is_some()).collect()
    }
}

/// The scene's alpha test for the tracer ([`hyrt_tracer::Cutouts`]): its own copy of what
/// [`Scene::solid_at`] reads for the triangles with cut-outs, so that it gives the same
/// answers (the tracer outlives no scene, but holds no borrow of one).
pub struct CutoutTest {
    /// Per triangle, its index in `tris`, or `u32::MAX` for a triangle without a cut-out.
    slot: Vec<u32>,
    /// Per triangle with a cut-out: its corners' texture coordinates and its cut-out.
    tris: Vec<([Vec2; 3], Cutout)>,
    masks: Vec<Mask>,
}

impl CutoutTest {
    /// The test of `scene`'s cut-outs, `flags` its [`Scene::cutout_flags`]; `None` when it has
    /// none.
    pub fn of(scene: &Scene, flags: &[bool]) -> Option<Self> {
        if flags.is_empty() {
            return None;
        }
        let mut slot = vec![u32::MAX; flags.len()];
        let mut tris = Vec::new();
        for (t, _) in flags.iter().enumerate().filter(|(_, f)| **f) {
            let uv = scene.uvs.get(t).copied().unwrap_or([Vec2::ZERO; 3]);
            slot[t] = tris.len() as u32;
            tris.push((uv, *scene.cutout(t as u32).expect("flagged")));
        }
        // Only the masks some cut-out reads, renumbered.
        let mut masks = Vec::new();
        let mut renumber = vec![None; scene.masks.len()];
        for (_, c) in &mut tris {
            c.mask = c.mask.and_then(|k| {
                let k = k as usize;
                let m = scene.masks.get(k)?;
                Some(*renumber[k].get_or_insert_with(|| {
                    masks.push(m.clone());
                    masks.len() as u32 - 1
                }))
            });
        }
        Some(Self { slot, tris, masks })
    }
}

impl hyrt_tracer::Cutouts for CutoutTest {
    #[inline]
    fn has_holes(&self, tri: u32) -> bool {
        self.slot.get(tri as usize).is_some_and(|&s| s != u32::MAX)
    }

    fn solid(&self, tri: u32, bary: [f32; 3]) -> bool {
        let Some((uv, c)) = self.slot.get(tri as usize).and_then(|&s| self.tris.get(s as usize)) else {
            return true;
        };
        let alpha = c
            .mask
            .and_then(|k| self.masks.get(k as usize))
            .map_or(1.0, |m| m.alpha(uv[0] * bary[0] + uv[1] * bary[1] + uv[2] * bary[2]));
        c.scale * alpha >= c.cutoff
    }
}
