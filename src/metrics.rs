//! Image comparison: PSNR on display luminance, as the thesis measured.
//!
//! Both images are taken as displayed: PNG values are sRGB bytes / 255; EXR values go through
//! the same display transform as our PNG output (exposure 1, clamp, sRGB). Luminance
//! `Y = 0.2126 R + 0.7152 G + 0.0722 B` of those values, `MSE = mean (Y1 - Y2)^2`,
//! `PSNR = 10 log10(MAX^2 / MSE)` with `MAX = 1`; identical images give infinity.

use std::path::Path;

use anyhow::{Context, Result, bail};
use glam::Vec3;

use crate::film::display;

/// An image as displayed: sRGB-encoded values in [0, 1].
#[derive(Clone, Debug)]
pub struct DisplayImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

/// Rec. 709 luminance weights.
pub fn luminance(c: Vec3) -> f64 {
    0.2126 * c.x as f64 + 0.7152 * c.y as f64 + 0.0722 * c.z as f64
}

/// Result of comparing two images.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Comparison {
    pub width: u32,
    pub height: u32,
    /// PSNR in dB of luminance; `f64::INFINITY` when identical.
    #[serde(serialize_with = "ser_psnr")]
    pub psnr_db: f64,
    pub mse: f64,
    /// Pixels whose RGB values differ at all.
    pub differing_pixels: u64,
}

fn ser_psnr<S: serde::Serializer>(v: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
    if v.is_infinite() { s.serialize_str("inf") } else { s.serialize_f64(*v) }
}

/// Compares two displayed images of the same size.
pub fn compare(a: &DisplayImage, b: &DisplayImage) -> Result<Comparison> {
    if (a.width, a.height) != (b.width, b.height) {
        bail!("images differ in size: {}x{} vs {}x{}", a.width, a.height, b.width, b.height);
    }
    let mut sum = 0.0f64;
    let mut differing = 0u64;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let d = luminance(*p) - luminance(*q);
        sum += d * d;
        differing += u64::from(p != q);
    }
    let n = (a.pixels.len().max(1)) as f64;
    let mse = sum / n;
    let psnr_db = if mse == 0.0 { f64::INFINITY } else { 10.0 * (1.0 / mse).log10() };
    Ok(Comparison { width: a.width, height: a.height, psnr_db, mse, differing_pixels: differing })
}

/// Reads a PNG (any bit depth, taken as sRGB) or an EXR (linear, display-transformed).
pub fn read_display_image(path: &Path) -> Result<DisplayImage> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_lowercase();
    if ext == "exr" {
        use exr::prelude::*;
        let img = read_first_rgba_layer_from_file(
            path,
            |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
            |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = display(Vec3::new(r, g, b), 1.0);
            },
        )
        .with_context(|| format!("{}: cannot read EXR", path.display()))?;
        let size = img.layer_data.size;
        Ok(DisplayImage {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels: img.layer_data.channel_data.pixels.1,
        })
    } else {
        let img =
            image::open(path).with_context(|| format!("{}: cannot read image", path.display()))?.to_rgb32f();
        let (width, height) = img.dimensions();
        let pixels = img.pixels().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        Ok(DisplayImage { width, height, pixels })
    }
}

impl DisplayImage {
    /// The display image of a film, without 8-bit quantisation.
    pub fn from_film(f: &crate::film::Film, exposure: f32) -> Self {
        Self {
            width: f.width,
            height: f.height,
            pixels: f.pixels.iter().map(|&p| display(p, exposure)).collect(),
        }
    }
}

/// Mean FLIP error of `test` against `reference` (NVIDIA's perceptual difference of LDR
/// images: 0 where identical, up to 1; lower is better), both as displayed and quantised to
/// 8-bit sRGB like our PNGs, under FLIP's default viewing conditions (67 pixels per degree).
pub fn flip_mean(reference: &DisplayImage, test: &DisplayImage) -> Result<f64> {
    if (reference.width, reference.height) != (test.width, test.height) {
        bail!(
            "images differ in size: {}x{} vs {}x{}",
            reference.width,
            reference.height,
            test.width,
            test.height
        );
    }
    let flip_image = |img: &DisplayImage| {
        let bytes: Vec<u8> = img
            .pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect();
        nv_flip::FlipImageRgb8::with_data(img.width, img.height, &bytes)
    };
    let map = nv_flip::flip(flip_image(reference), flip_image(test), nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let v = map.to_vec();
    Ok(v.iter().map(|&e| f64::from(e)).sum::<f64>() / v.len().max(1) as f64)
}
