//! Golden images: renders compared with committed PNGs by PSNR of display luminance.
//!
//! Bound: 50 dB. At these sizes a single pixel that changes from black to white gives about
//! 42-43 dB, so any real change of the image fails, while 1-LSB rounding noise on up to a
//! third of the pixels (e.g. another libm's `powf` in the sRGB curve) passes.
//!
//! A failing comparison writes `<name>.actual.png` and `<name>.diff.png` (absolute luminance
//! difference, amplified 10x) to `target/test-output/golden/`. Goldens are regenerated only on
//! purpose: `HYRT_BLESS=1 cargo test --release --test golden`, with the reason in the commit.

mod common;

use common::*;
use hyrt::{
    film::Film,
    metrics,
    render::{Indirect, Options},
};

const MIN_PSNR_DB: f64 = 50.0;

fn check(name: &str, spec: &str, w: u32, h: u32) {
    check_with(name, spec, w, h, Options::reference());
}

/// [`check`] with `options` (the hybrid's goldens).
fn check_with(name: &str, spec: &str, w: u32, h: u32, options: Options) {
    let mut scene = hyrt::scene::load(spec).unwrap_or_else(|e| panic!("{e:#}"));
    scene.settings.width = w;
    scene.settings.height = h;
    let frame = render(&scene, options);
    let golden = root().join("tests/golden").join(format!("{name}.png"));
    if std::env::var_os("HYRT_BLESS").is_some() {
        std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
        frame.film.write_png(&golden, scene.settings.exposure).unwrap();
        eprintln!("blessed {}", golden.display());
        return;
    }
    let out = out_dir(&format!("golden/{name}"));
    let actual = out.join(format!("{name}.actual.png"));
    frame.film.write_png(&actual, scene.settings.exposure).unwrap();
    let a = metrics::read_display_image(&actual).unwrap();
    let g = metrics::read_display_image(&golden)
        .unwrap_or_else(|e| panic!("{e:#}; run with HYRT_BLESS=1 to create it"));
    let c = metrics::compare(&g, &a).unwrap();
    if c.psnr_db < MIN_PSNR_DB {
        let mut diff = Film::new(w, h);
        for (i, p) in diff.pixels.iter_mut().enumerate() {
            let d = (metrics::luminance(a.pixels[i]) - metrics::luminance(g.pixels[i])).abs() as f32;
            *p = glam::Vec3::splat(d * 10.0);
        }
        diff.write_png(&out.join(format!("{name}.diff.png")), 1.0).unwrap();
        panic!(
            "{name}: PSNR {:.2} dB < {MIN_PSNR_DB} dB ({} pixels differ); see {}",
            c.psnr_db,
            c.differing_pixels,
            out.display()
        );
    }
}

#[test]
fn builtin_cornell() {
    check("cornell", "cornell", 128, 128);
}

#[test]
fn cornell_bunny_mirror() {
    let spec = root().join("scenes/cornell-bunny-mirror.toml");
    check("cornell-bunny-mirror", spec.to_str().unwrap(), 160, 120);
}

/// The office: highlights on its `illum 2` materials, and mirrors (chrome, brass) set by its
/// scene file; this is the golden that holds the material model's highlight term.
#[test]
fn office() {
    let spec = root().join("scenes/office.toml");
    check("office", spec.to_str().unwrap(), 160, 120);
}

/// The hybrid, the product, on the thesis's first scene: raster visibility, SMeRTS with cube
/// maps, and indirect light from 45 VPLs with one paraboloid map each (the defaults).
#[test]
fn hybrid_cornell_bunny_mirror() {
    let spec = root().join("scenes/cornell-bunny-mirror.toml");
    let mut o = Options::hybrid();
    o.indirect = Indirect::Maps;
    check_with("hybrid-cornell-bunny-mirror", spec.to_str().unwrap(), 160, 120, o);
}

/// The hybrid on the conference room: four lights, SMeRTS with the default maps.
#[test]
fn hybrid_conference() {
    let spec = root().join("scenes/conference.toml");
    check_with("hybrid-conference", spec.to_str().unwrap(), 160, 120, Options::hybrid());
}

/// Textures: Dabrovic's Sponza (MTL `map_Kd` JPEGs), by the reference and by the hybrid.
#[test]
fn sponza_textured() {
    let spec = root().join("scenes/sponza.toml");
    check("sponza", spec.to_str().unwrap(), 160, 120);
    check_with("hybrid-sponza", spec.to_str().unwrap(), 160, 120, Options::hybrid());
}

/// Alpha cut-outs: the lattice fence and grille of `scenes/fence.toml` (an MTL `map_d`), seen
/// and shadowed through their holes, by the hybrid.
#[test]
fn hybrid_fence_cut_outs() {
    let spec = root().join("scenes/fence.toml");
    check_with("hybrid-fence", spec.to_str().unwrap(), 160, 120, Options::hybrid());
}
