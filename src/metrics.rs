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

/// Writes a PSNR for JSON, which has no infinity: `"inf"` for identical images.
pub fn ser_psnr<S: serde::Serializer>(v: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
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

/// Median, mean, minimum and maximum of repeated timings, in milliseconds: the one summary of
/// samples that the benchmarks, sweeps and tools use.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Timing {
    pub runs: usize,
    pub median: f64,
    pub mean: f64,
    pub min: f64,
    pub max: f64,
}

impl Timing {
    /// Summary of `samples` (all zero if empty). The median of an even count is the mean of
    /// the two middle samples.
    pub fn of(samples: &[f64]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        let mut s = samples.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let median = if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) };
        Self { runs: n, median, mean: s.iter().sum::<f64>() / n as f64, min: s[0], max: s[n - 1] }
    }

    /// Frames per second as the thesis reports them: frames over total time (1000 / mean ms).
    pub fn fps_mean(&self) -> f64 {
        if self.mean > 0.0 { 1e3 / self.mean } else { 0.0 }
    }
}

/// The `p`-th percentile of `samples` by nearest rank (0 if empty).
pub fn percentile(samples: &[f64], p: f64) -> f64 {
    let mut s = samples.to_vec();
    s.sort_by(f64::total_cmp);
    if s.is_empty() {
        return 0.0;
    }
    let k = ((p / 100.0) * s.len() as f64).ceil().max(1.0) as usize - 1;
    s[k.min(s.len() - 1)]
}

/// PSNR (dB, display luminance at the scene's exposure) of `film` against `reference`.
pub fn psnr(
    scene: &crate::scene::Scene,
    reference: &crate::film::Film,
    film: &crate::film::Film,
) -> Result<f64> {
    let e = scene.settings.exposure;
    let c = compare(&DisplayImage::from_film(reference, e), &DisplayImage::from_film(film, e))?;
    Ok(c.psnr_db)
}

/// Wrong-visibility counts of map-based shadows with `options`: (pixel, light) pairs whose
/// decision (by the map, a hint or a traversal) a plain shadow ray contradicts, and distinct
/// pixels with at least one such light.
pub fn wrong_visibility(scene: &crate::scene::Scene, mut options: crate::options::Options) -> (u64, u64) {
    options.check_visibility = true;
    options.keep_buffers = true;
    let f = crate::render::Renderer::new(scene, options).render(&|| {});
    let pairs = f.stats.lights.iter().filter_map(|l| l.wrong_total()).sum();
    let pixels = f.shadows.as_ref().map_or(0, |b| {
        let n = f.film.pixels.len();
        (0..n).filter(|&i| b.wrong.iter().any(|w| w.get(i).copied().unwrap_or(false))).count() as u64
    });
    (pairs, pixels)
}

#[cfg(test)]
mod timing_tests {
    use super::*;

    #[test]
    fn timing_summarises() {
        let t = Timing::of(&[4.0, 1.0, 3.0, 2.0]);
        assert_eq!((t.runs, t.median, t.mean, t.min, t.max), (4, 2.5, 2.5, 1.0, 4.0));
        assert_eq!(Timing::of(&[5.0, 1.0, 9.0]).median, 5.0);
        assert_eq!(Timing::of(&[]).runs, 0);
        assert_eq!(Timing::of(&[2.0, 2.0]).fps_mean(), 500.0);
    }

    #[test]
    fn percentiles_by_nearest_rank() {
        let v = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!((percentile(&v, 5.0), percentile(&v, 50.0), percentile(&v, 95.0)), (1.0, 3.0, 5.0));
        assert_eq!(percentile(&[], 50.0), 0.0);
    }
}
