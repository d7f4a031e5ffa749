//! The film: linear RGB radiance per pixel, written as EXR (linear) or PNG (8-bit sRGB).
//!
//! Files are written to a temporary file in the destination directory and renamed into place,
//! so a failure never leaves a half-written image and never destroys an existing one.

use std::path::Path;

use anyhow::{Context, Result, bail};
use glam::Vec3;

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

    /// Writes an 8-bit sRGB PNG.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<()> {
        let bytes = self.to_srgb8(exposure);
        atomic_write(path, |tmp| {
            image::save_buffer_with_format(
                tmp,
                &bytes,
                self.width,
                self.height,
                image::ColorType::Rgb8,
                image::ImageFormat::Png,
            )
            .map_err(Into::into)
        })
    }

    /// Writes a linear float RGB OpenEXR file (uncompressed, 32-bit float).
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        use exr::prelude::*;
        let (w, h) = (self.width as usize, self.height as usize);
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
            let c = self.pixels[p.y() * w + p.x()];
            (c.x, c.y, c.z)
        });
        let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::UNCOMPRESSED, channels);
        atomic_write(path, |tmp| {
            Image::from_layer(layer).write().non_parallel().to_file(tmp).map_err(Into::into)
        })
    }
}

/// Runs `write` on a temporary path beside `path`, then renames it over `path`.
pub fn atomic_write(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if path.file_name().is_none() {
        bail!("{}: not a file name", path.display());
    }
    let mut builder = tempfile::Builder::new();
    // Temporary files are private (0600) by default; the finished file should get the usual
    // permissions (0666 less the umask), like any file the user creates.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let tmp = builder
        .prefix(".hyrt-")
        .suffix(&format!(".{}", path.extension().and_then(|e| e.to_str()).unwrap_or("tmp")))
        .tempfile_in(dir)
        .with_context(|| format!("{}: cannot create a file in {}", path.display(), dir.display()))?;
    write(tmp.path()).with_context(|| format!("{}: cannot write image", path.display()))?;
    tmp.persist(path)
        .with_context(|| format!("{}: cannot move the finished file into place", path.display()))?;
    Ok(())
}
