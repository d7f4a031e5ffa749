//! The FLIP error of `hyrt sweep`: NVIDIA's C++ FLIP (the `nv-flip` crate), kept out of the library.

use anyhow::{Result, bail};
use hyrt::metrics::DisplayImage;

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
