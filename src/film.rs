//! The film: linear RGB radiance per pixel, written as EXR (linear) or PNG (8-bit sRGB).
//!
//! Files are written through [`crate::output`]: to a temporary file in the destination
//! directory, renamed into place, so a failure never leaves a half-written image and never
//! destroys an existing one.

use std::path::Path;

use anyhow::Result;
use glam::Vec3;

use crate::output::atomic_write;

/// Linear radiance, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// The sRGB transfer function (IEC 61966-2-1) for a linear value in [0, 1].
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

/// Display transform: exposure, clamp to [0, 1], sRGB. Non-finite values display as black.
pub fn display(v: Vec3, exposure: f32) -> Vec3 {
    let f = |c: f32| if c.is_finite() { srgb_encode((c * exposure).clamp(0.0, 1.0)) } else { 0.0 };
    Vec3::new(f(v.x), f(v.y), f(v.z))
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    /// 8-bit sRGB bytes (RGB) after the display transform.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|&p| display(p, exposure).to_array())
            .map(|c| (c * 255.0).round() as u8)
            .collect()
    }

    /// Writes an 8-bit sRGB PNG to `path` as it is (see [`Film::write_png`] for the safe way).
    pub fn save_png(&self, path: &Path, exposure: f32) -> Result<()> {
        let bytes = self.to_srgb8(exposure);
        image::save_buffer_with_format(
            path,
            &bytes,
            self.width,
            self.height,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(Into::into)
    }

    /// Writes a linear float RGB OpenEXR file (uncompressed, 32-bit float) to `path` as it is.
    pub fn save_exr(&self, path: &Path) -> Result<()> {
        use exr::prelude::*;
        let (w, h) = (self.width as usize, self.height as usize);
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
            let c = self.pixels[p.y() * w + p.x()];
            (c.x, c.y, c.z)
        });
        let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::UNCOMPRESSED, channels);
        Image::from_layer(layer).write().non_parallel().to_file(path).map_err(Into::into)
    }

    /// Writes an 8-bit sRGB PNG atomically ([`atomic_write`]).
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<()> {
        atomic_write(path, |tmp| self.save_png(tmp, exposure))
    }

    /// Writes a linear OpenEXR file atomically ([`atomic_write`]).
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        atomic_write(path, |tmp| self.save_exr(tmp))
    }
}
