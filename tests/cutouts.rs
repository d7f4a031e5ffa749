//! Alpha cut-outs: read from MTL `map_d` and glTF `alphaMode`, honoured by every visibility
//! path (camera rays and the z-buffer, shadow rays and light maps, mirror rays), so that the
//! hybrid agrees with the reference under point, spot and directional lights.

mod common;

use std::path::Path;

use glam::{Vec2, Vec3, vec3};
use hyrt::{
    metrics,
    render::{CutoutMaps, Frame, Options, Renderer},
    scene::{self, Directional, PointLight, Scene, Spot},
};

/// `scenes/fence.toml`: a lattice fence and grille cut out by `fence/lattice.png`.
fn fence() -> Scene {
    let p = common::root().join("scenes/fence.toml");
    scene::load(p.to_str().unwrap()).expect("scenes/fence.toml loads")
}

/// The fence lit by one light of each kind in turn.
fn lit_by(kind: &str) -> Scene {
    let mut s = fence();
    match kind {
        "point" => {}
        "spot" => {
            let from = vec3(-2.0, 5.0, 4.0);
            let spot =
                Spot::new((vec3(0.0, 0.0, -1.5) - from).normalize(), 20f32.to_radians(), 35f32.to_radians());
            s.lights = vec![PointLight { position: from, intensity: Vec3::splat(30.0), spot: Some(spot) }];
        }
        "sun" => {
            s.lights.clear();
            s.directional =
                vec![Directional { direction: vec3(-0.3, -0.8, -0.5), irradiance: Vec3::splat(2.0) }];
            s.place_directional_lights();
        }
        _ => unreachable!("a light kind of this test"),
    }
    s.validate().expect("valid");
    s
}

fn checked() -> Options {
    let mut o = Options::hybrid();
    o.check_visibility = true;
    o.keep_buffers = true;
    o
}

/// Pixels with a (pixel, light) decision that a plain shadow ray contradicts.
fn wrong_pixels(f: &Frame) -> usize {
    let b = f.shadows.as_ref().expect("kept buffers");
    (0..f.film.pixels.len()).filter(|&i| b.wrong.iter().any(|w| w.get(i).copied().unwrap_or(false))).count()
}

/// For each light kind: the hybrid against the reference gives at least 45 dB and at most
/// 0.05 % wrong-visibility pixels, and the holes matter: without its cut-outs the lattice
/// would shadow a much larger part of the image.
/// Both ways of holding cut-outs in light maps: tested at texels' centres (the default), with
/// fewer shadow rays than drawn solid with a ray for every point under them.
#[test]
fn the_lattice_shadows_alike_in_the_hybrid_and_the_reference_for_every_light_kind() {
    for kind in ["point", "spot", "sun"] {
        let s = lit_by(kind);
        let reference = common::render(&s, Options::reference());
        let mut shadow_rays = Vec::new();
        for cutouts in [CutoutMaps::Texels, CutoutMaps::Rays] {
            let mut o = checked();
            o.shadow.cutouts = cutouts;
            let hybrid = common::render(&s, o);
            let psnr = metrics::psnr(&s, &reference.film, &hybrid.film).unwrap();
            let wrong = wrong_pixels(&hybrid);
            let n = hybrid.film.pixels.len();
            let rays = hybrid.stats.rays;
            eprintln!("{kind} {cutouts:?}: {psnr:.2} dB, {wrong} wrong-visibility pixels, {rays:?}");
            assert!(psnr >= 45.0, "{kind} {cutouts:?}: {psnr:.2} dB");
            assert!(wrong as f64 <= 0.0005 * n as f64, "{kind} {cutouts:?}: {wrong} wrong pixels of {n}");
            // Some decisions went to rays, and some of those the hint (the lattice's bars)
            // answered without a traversal.
            assert!(rays.shadow > 0 && rays.shadow_hint_hits > 0, "{kind} {cutouts:?}");
            shadow_rays.push(rays.shadow);
        }
        assert!(shadow_rays[0] * 10 < shadow_rays[1] * 9, "{kind}: {shadow_rays:?} shadow rays");

        let n = reference.film.pixels.len();
        let mut solid = s.clone();
        solid.materials.iter_mut().for_each(|m| m.cutout = None);
        let without = common::render(&solid, Options::reference());
        let dark = |f: &Frame| f.film.pixels.iter().filter(|p| p.max_element() < 1e-4).count();
        assert!(
            dark(&without) > dark(&reference) + n / 20,
            "{kind}: {} dark pixels with holes, {} without",
            dark(&reference),
            dark(&without)
        );
    }
}

/// The camera sees through the holes: the hybrid's z-buffer draws the lattice solid and casts
/// the pixel's ray where its triangle has a hole there, so its G-buffer is the reference's.
#[test]
fn the_camera_sees_through_the_holes_with_rays_and_with_the_z_buffer() {
    let s = fence();
    let mut opts = Options::reference();
    opts.keep_buffers = true;
    let reference = Renderer::new(&s, opts).render(&|| {});
    let mut opts = Options::hybrid();
    opts.keep_buffers = true;
    let hybrid = Renderer::new(&s, opts).render(&|| {});
    let (a, b) = (reference.gbuffer.unwrap(), hybrid.gbuffer.unwrap());
    // The two coverage rules differ only along the silhouettes of the quads (the geometry's
    // own edges, not the holes'): within a pixel of them.
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(differ <= a.len() / 2000, "{differ} pixels differ");
    let lattice = |h: &Option<hyrt_tracer::Hit>| h.is_some_and(|h| s.cutout(h.tri).is_some());
    let seen = a.iter().filter(|h| lattice(h)).count();
    assert!(seen > 1000, "the lattice covers {seen} pixels");
    // Every hit on the lattice is on a solid point of it.
    assert!(a.iter().flatten().all(|h| s.solid_at(h.tri, h.bary)));
    // Rays cast by the hybrid's visibility pass for the holes: about as many as the pixels
    // that look through the lattice's quads, which is more than none and less than all.
    let holes = hybrid.stats.rays.primary;
    assert!(holes > 1000 && holes < a.len() as u64 / 2, "{holes} primary rays");
}

/// The bytes of a `w x h` PNG whose texel `(x, y)` is `f(x, y)` (grey and alpha).
fn png_bytes(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 2]) -> Vec<u8> {
    let img = image::GrayAlphaImage::from_fn(w, h, |x, y| image::LumaA(f(x, y)));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// A quad `(0, 0)-(1, 1)` in z = 0 with texture coordinates `(0, 0)-(1, 1)` (v from the top)
/// and the materials of `mtl` (`usemtl cut` on it), as `dir/q.obj`.
fn quad_obj(dir: &Path, mtl: &str) -> std::path::PathBuf {
    std::fs::write(dir.join("q.mtl"), mtl).unwrap();
    let obj = "mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\n\
               usemtl cut\nf 1/1 2/2 3/3 4/4\n";
    let p = dir.join("q.obj");
    std::fs::write(&p, obj).unwrap();
    p
}

/// The barycentrics of point `(x, y)` of [`quad_obj`]'s quad on its triangle 0 (corners
/// (0, 0), (1, 0), (1, 1)); `x >= y`.
fn bary(x: f32, y: f32) -> [f32; 3] {
    [1.0 - x, x - y, y]
}

/// MTL `map_d`: a grey image is its own alpha, an image with alpha uses that; holes below 0.5.
/// A missing map is a warning and the material is solid; a plain `d < 1` is a warning too.
#[test]
fn mtl_alpha_maps_make_cut_outs() {
    let dir = tempfile::tempdir().unwrap();
    // Left column a hole, right column solid (texel centres at x = 0.25 and 0.75).
    let grey = image::GrayImage::from_fn(2, 2, |x, _| image::Luma([if x == 0 { 0 } else { 255 }]));
    grey.save(dir.path().join("grey.png")).unwrap();
    std::fs::write(dir.path().join("rgba.png"), png_bytes(2, 2, |x, _| [255, if x == 0 { 0 } else { 255 }]))
        .unwrap();
    for file in ["grey.png", "RGBA.PNG"] {
        let p = quad_obj(dir.path(), &format!("newmtl cut\nKd 1 1 1\nmap_d {file}\n"));
        let s = scene::load(p.to_str().unwrap()).unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(s.masks.len(), 1);
        assert!(s.cutout(0).is_some() && s.cutout_flags() == [true, true]);
        assert!(!s.solid_at(0, bary(0.26, 0.25)), "{file}: the left column is a hole");
        assert!(s.solid_at(0, bary(0.74, 0.25)), "{file}: the right column is solid");
        // Bilinear between the two columns: the edge is half-way.
        assert!(!s.solid_at(0, bary(0.49, 0.25)) && s.solid_at(0, bary(0.51, 0.25)), "{file}");
    }
    let p = quad_obj(dir.path(), "newmtl cut\nKd 1 1 1\nmap_d gone.png\n\nnewmtl glass\nd 0.3\n");
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert!(s.cutout(0).is_none() && s.cutout_flags().is_empty());
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    for part in ["q.obj", "material 'cut'", "gone.png", "without holes"] {
        assert!(s.warnings[0].contains(part), "{:?} should mention {part:?}", s.warnings[0]);
    }
    assert!(s.warnings[1].contains("'glass' has a dissolve d < 1"), "{:?}", s.warnings[1]);
}

/// glTF `alphaMode`: `MASK` cuts at `alphaCutoff` by the base colour's alpha (factor times
/// texture); `BLEND` is a mask at 0.5, with a warning; `OPAQUE` ignores alpha.
#[test]
fn gltf_alpha_modes() {
    use base64::Engine as _;
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    // Alpha 0.2 in the left column, 0.8 in the right.
    let png64 = b64(&png_bytes(2, 1, |x, _| [255, if x == 0 { 51 } else { 204 }]));
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let gltf = |mode: &str, factor: f32| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "material": 0}}]}}],
  "materials": [{{"name": "leaf", {mode} "pbrMetallicRoughness": {{"metallicFactor": 0.0,
     "baseColorFactor": [1, 1, 1, {factor}], "baseColorTexture": {{"index": 0}}}}}}],
  "textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{png64}"}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
                {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC2"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 60}}],
  "buffers": [{{"byteLength": 60, "uri": "data:application/octet-stream;base64,{}"}}]}}"#,
            b64(&bin)
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("leaf.gltf");
    let load = |text: String| {
        std::fs::write(&p, text).unwrap();
        scene::load(p.to_str().unwrap()).unwrap()
    };
    // The triangle's corners (0, 0), (1, 0), (1, 1) read u = x.
    let left = [0.8, 0.1, 0.1];
    let right = [0.1, 0.1, 0.8];
    let s = load(gltf(r#""alphaMode": "MASK", "alphaCutoff": 0.5,"#, 1.0));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!(!s.solid_at(0, left) && s.solid_at(0, right));
    // The factor scales the texture's alpha: 0.8 * 0.5 = 0.4 < 0.5, a hole everywhere.
    let s = load(gltf(r#""alphaMode": "MASK","#, 0.5));
    assert!(!s.solid_at(0, left) && !s.solid_at(0, right));
    // A lower cut-off keeps the left column too.
    let s = load(gltf(r#""alphaMode": "MASK", "alphaCutoff": 0.1,"#, 1.0));
    assert!(s.solid_at(0, left) && s.solid_at(0, right));
    let s = load(gltf(r#""alphaMode": "BLEND","#, 1.0));
    assert!(!s.solid_at(0, left) && s.solid_at(0, right));
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("'leaf' has alphaMode BLEND") && s.warnings[0].contains("cut-out"));
    let s = load(gltf("", 0.1));
    assert!(s.cutout_flags().is_empty() && s.solid_at(0, left) && s.masks.is_empty());
    // A negative cut-off is an error naming the material.
    std::fs::write(&p, gltf(r#""alphaMode": "MASK", "alphaCutoff": -0.5,"#, 1.0)).unwrap();
    let e = format!("{:#}", scene::load(p.to_str().unwrap()).unwrap_err());
    assert!(e.contains("leaf") && e.contains("alpha cut-off -0.5"), "{e}");
    // Texture coordinates: the scene's, which the mask reads as the colour texture does.
    assert_eq!(s.uvs[0], [Vec2::ZERO, Vec2::X, Vec2::ONE]);
}

/// Indirect light: VPL paths leave through the holes (rays), and each VPL's map holds what a
/// hole lets it see (decided at the texel's centre). Against the reference's VPL shadow rays,
/// the VPL maps' image is within 55 dB; drawn solid, the lattice in the maps cost about ten
/// decibels more.
#[test]
fn vpl_maps_see_through_the_holes() {
    use hyrt::render::Indirect;
    let mut s = fence();
    (s.settings.width, s.settings.height) = (320, 240);
    let with = |indirect: Indirect, mut o: Options| {
        o.indirect = indirect;
        o.indirect_opts.vpl.paths = 45;
        common::render(&s, o)
    };
    let reference = with(Indirect::Rays, Options::reference());
    let maps = with(Indirect::Maps, Options::reference());
    let psnr = metrics::psnr(&s, &reference.film, &maps.film).unwrap();
    assert!(psnr >= 55.0, "{psnr:.2} dB");
}

/// `hyrt plan` says how cut-outs are handled: the visibility pass's rays through holes, and
/// the light maps' way (`--cutout-maps`); a scene without cut-outs says nothing of them.
#[test]
fn the_plan_names_the_cut_outs() {
    let s = fence();
    let text = |o: &Options| format!("{:?}", hyrt::plan::Plan::new(&s, o));
    let mut rays = Options::hybrid();
    rays.shadow.cutouts = CutoutMaps::Rays;
    let (texels, rays) = (text(&Options::hybrid()), text(&rays));
    assert!(
        texels.contains("sees a cut-out's hole") && texels.contains("4 cut-out triangles tested"),
        "{texels}"
    );
    assert!(rays.contains("4 cut-out triangles drawn solid"), "{rays}");
    let plain = hyrt::scene::load("cornell").unwrap();
    assert!(!format!("{:?}", hyrt::plan::Plan::new(&plain, &Options::hybrid())).contains("cut-out"));
}
