//! Textures: read from MTL `map_Kd` and glTF `baseColorTexture` (with `KHR_texture_transform`),
//! sampled at the level the pixel's footprint asks for, the same in the reference and the
//! hybrid; a texture that cannot be read is a warning naming the file and the material.

mod common;

use std::path::Path;

use glam::{Vec2, Vec3, vec3};
use hyrt::{
    render::Options,
    scene::{self, Camera, PointLight},
};

/// Writes a `w x h` PNG whose texel `(x, y)` is `f(x, y)` (sRGB bytes).
fn png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) {
    image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y))).save(path).unwrap();
}

/// A checker of `n x n` texels, black and white.
fn checker(path: &Path, n: u32) {
    png(path, n, n, |x, y| if (x + y) % 2 == 0 { [255, 255, 255] } else { [0, 0, 0] });
}

/// An OBJ quad of half-size `half` in the plane z = 0, facing +z, its texture coordinates
/// `(0, 0)` to `(1, 1)`, with material `tex` (`map_Kd` of `texture`) and a second quad beside
/// it with material `lost` (a `map_Kd` that does not exist).
fn textured_obj(dir: &Path, half: f32, texture: &str) -> std::path::PathBuf {
    std::fs::write(
        dir.join("q.mtl"),
        format!(
            "newmtl tex\nKd 1 1 1\nmap_Kd {texture}\n\nnewmtl lost\nKd 0.5 0.5 0.5\nmap_Kd missing.png\n"
        ),
    )
    .unwrap();
    let (h, l) = (half, -half);
    let obj = format!(
        "mtllib q.mtl\nv {l} {l} 0\nv {h} {l} 0\nv {h} {h} 0\nv {l} {h} 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         usemtl tex\nf 1/1 2/2 3/3 4/4\n\
         v 10 0 0\nv 11 0 0\nv 11 1 0\nusemtl lost\nf 5 6 7\n"
    );
    let p = dir.join("q.obj");
    std::fs::write(&p, obj).unwrap();
    p
}

#[test]
fn obj_textures_load_with_their_coordinates_and_missing_ones_warn() {
    let dir = tempfile::tempdir().unwrap();
    png(&dir.path().join("rgb.png"), 2, 1, |x, _| if x == 0 { [255, 0, 0] } else { [0, 0, 255] });
    // A Windows path and texture options before the file name.
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    png(&dir.path().join("sub/w.png"), 1, 1, |_, _| [0, 255, 0]);
    let q = textured_obj(dir.path(), 1.0, "-s 2 2 1 sub\\w.png");
    let s = scene::load(q.to_str().unwrap()).unwrap();
    assert_eq!(s.albedo(0, [0.25, 0.25, 0.5], 0.0, 1.0), Vec3::new(0.0, 1.0, 0.0));
    let p = textured_obj(dir.path(), 1.0, "RGB.PNG");
    let s = scene::load(p.to_str().unwrap()).unwrap();
    // Found despite the case of its name; one texture for the two materials that name files.
    assert_eq!(s.textures.len(), 1);
    let tex = s.materials.iter().find(|m| m.name == "tex").unwrap();
    assert_eq!(tex.texture, Some(0));
    let lost = s.materials.iter().find(|m| m.name == "lost").unwrap();
    assert_eq!((lost.texture, lost.diffuse), (None, Vec3::splat(0.5)));
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    for part in ["q.obj", "material 'lost'", "missing.png", "rendered with its Kd"] {
        assert!(s.warnings[0].contains(part), "{:?} should mention {part:?}", s.warnings[0]);
    }
    // OBJ's v counts from the bottom; the scene's from the top row.
    assert_eq!(s.uvs.len(), s.triangle_count());
    assert_eq!(s.uvs[0], [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0)]);
    // The untextured triangle's coordinates are zero; its albedo is its Kd exactly.
    assert_eq!(s.uvs[2], [Vec2::ZERO; 3]);
    assert_eq!(s.albedo(2, [0.2, 0.3, 0.5], 1.0, 1.0), Vec3::splat(0.5));
    // Left half red, right half blue, at the finest level: the texel centres (0.25, 0.5) on
    // the second triangle (corners' coordinates (0, 1), (1, 0), (0, 0)) and (0.75, 0.5) on
    // the first ((0, 1), (1, 1), (1, 0)).
    assert_eq!(s.albedo(1, [0.5, 0.25, 0.25], 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(s.albedo(0, [0.25, 0.25, 0.5], 0.0, 1.0), Vec3::new(0.0, 0.0, 1.0));
}

/// A scene file's mirroring transform swaps two corners of every triangle (to keep them
/// counter-clockwise): their texture coordinates follow, so each point keeps its texel.
#[test]
fn a_mirrored_mesh_keeps_its_texture_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    png(&dir.path().join("rgb.png"), 2, 1, |x, _| if x == 0 { [255, 0, 0] } else { [0, 0, 255] });
    textured_obj(dir.path(), 1.0, "rgb.png");
    let load = |scale: &str| {
        let p = dir.path().join("m.toml");
        std::fs::write(&p, format!("[[mesh]]\npath = \"q.obj\"\nscale = {scale}\n")).unwrap();
        scene::file::load(&p).unwrap()
    };
    let (plain, mirrored) = (load("1"), load("[-1, 1, 1]"));
    let (a, b) = (plain.uvs[0], mirrored.uvs[0]);
    assert_eq!(b, [a[0], a[2], a[1]]);
    // The same point of the quad, (0.5, 0.25) in its plane before the mirror: the same colour.
    let (pa, pb) = (plain.positions[0], mirrored.positions[0]);
    let bary_of = |t: [Vec3; 3], q: Vec3| {
        let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], q - t[0]);
        let den = e1.x * e2.y - e1.y * e2.x;
        let (u, v) = ((d.x * e2.y - d.y * e2.x) / den, (e1.x * d.y - e1.y * d.x) / den);
        [1.0 - u - v, u, v]
    };
    let q = vec3(0.5, -0.25, 0.0);
    let qm = vec3(-0.5, -0.25, 0.0);
    assert_eq!(plain.albedo(0, bary_of(pa, q), 0.0, 1.0), mirrored.albedo(0, bary_of(pb, qm), 0.0, 1.0));
}

/// A quad filling the view of a camera on its axis at distance `d`, textured with an `n x n`
/// checker, lit by a light at the camera.
fn checker_scene(dir: &Path, n: u32, d: f32, size: u32) -> scene::Scene {
    checker(&dir.join("c.png"), n);
    let p = textured_obj(dir, 1.0, "c.png");
    let mut s = scene::load(p.to_str().unwrap()).unwrap();
    s.camera = Some(Camera {
        eye: vec3(0.0, 0.0, d),
        forward: -Vec3::Z,
        up: Vec3::Y,
        fov_y_deg: 20.0,
        fov_x_deg: None,
    });
    // Irradiance pi on the quad's centre: radiance there is the albedo.
    s.lights = vec![PointLight {
        position: vec3(0.0, 0.0, d),
        intensity: Vec3::splat(std::f32::consts::PI * d * d),
        spot: None,
    }];
    (s.settings.width, s.settings.height) = (size, size);
    s
}

/// Rays and rasterization see the same triangles here, so the same texels: the images are
/// bit-identical. And the checker shows: about half the pixels dark, half bright.
#[test]
fn a_textured_quad_is_the_same_in_the_reference_and_the_hybrid() {
    let dir = tempfile::tempdir().unwrap();
    // 8 texels over the quad; the quad (2 wide) fills about 70 % of a 20-degree view from 8.
    let s = checker_scene(dir.path(), 8, 8.0, 96);
    let reference = common::render(&s, Options::reference()).film;
    let hybrid = common::render(&s, Options::hybrid()).film;
    assert_eq!(reference.pixels, hybrid.pixels);
    let lum: Vec<f32> = reference.pixels.iter().map(|p| p.x).collect();
    let (dark, bright) =
        (lum.iter().filter(|&&l| l < 0.05).count(), lum.iter().filter(|&&l| l > 0.5).count());
    assert!(dark > 96 * 96 / 5 && bright > 96 * 96 / 5, "dark {dark}, bright {bright}");
}

/// Far away, a fine checker's texels are far smaller than a pixel: its pixels read a coarse
/// level, whose texels are the checker's mean (half white, in linear light). Close up they
/// read level 0 and vary.
#[test]
fn far_textures_read_coarser_levels() {
    let spread = |d: f32| {
        let dir = tempfile::tempdir().unwrap();
        let s = checker_scene(dir.path(), 256, d, 64);
        let film = common::render(&s, Options::reference()).film;
        // The middle 16x16 pixels: on the quad at both distances.
        let mid: Vec<f32> = (24..40)
            .flat_map(|y| (24..40).map(move |x| (x, y)))
            .map(|(x, y)| film.pixels[y * 64 + x].x)
            .collect();
        let mean = mid.iter().sum::<f32>() / mid.len() as f32;
        let var = mid.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / mid.len() as f32;
        (mean, var.sqrt())
    };
    // From 0.2 the 256 texels over 2 units are several pixels each; from 8 a pixel covers
    // about 6 texels (level 2, whose texels average 4x4 of the checker's).
    let (near_mean, near_sd) = spread(0.2);
    let (far_mean, far_sd) = spread(8.0);
    // (Bilinear between texel centres: ramps, not steps, close up.)
    assert!(near_sd > 0.1, "near: mean {near_mean}, sd {near_sd}");
    assert!(far_sd < 0.02 && (far_mean - 0.5).abs() < 0.05, "far: mean {far_mean}, sd {far_sd}");
}

/// glTF: the base colour texture (an embedded PNG), its texture coordinates and
/// `KHR_texture_transform` (offset, scale, rotation as the specification's matrix does them).
#[test]
fn gltf_base_color_texture_and_its_transform() {
    use base64::Engine as _;
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("t.png");
    png(&img, 2, 2, |x, y| [(x * 255) as u8, (y * 255) as u8, 0]);
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let png64 = b64(&std::fs::read(&img).unwrap());
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let quarter = std::f32::consts::FRAC_PI_2;
    let gltf = |transform: &str, image: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "material": 0}}]}}],
  "materials": [{{"name": "painted", "pbrMetallicRoughness": {{"metallicFactor": 0.0,
     "baseColorTexture": {{"index": 0{transform}}}}}}}],
  "textures": [{{"source": 0}}], "images": [{image}],
  "extensionsUsed": ["KHR_texture_transform"],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
                {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC2"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 60}}],
  "buffers": [{{"byteLength": 60, "uri": "data:application/octet-stream;base64,{}"}}]}}"#,
            b64(&bin)
        )
    };
    let embedded = format!(r#"{{"uri": "data:image/png;base64,{png64}"}}"#);
    let transform = format!(
        r#", "extensions": {{"KHR_texture_transform": {{"offset": [0.5, 0.25], "scale": [2, 3], "rotation": {quarter}}}}}"#
    );
    let p = dir.path().join("t.gltf");
    std::fs::write(&p, gltf(&transform, &embedded)).unwrap();
    let m = scene::gltf::load(&p).unwrap();
    assert_eq!((m.textures.len(), m.materials[0].texture), (1, Some(0)));
    assert_eq!(m.textures[0].size(), (2, 2));
    // uv' = offset + R (scale uv), R = [[cos, -sin], [sin, cos]]: (1, 0) -> (2, 0) -> (0, 2).
    let uv = m.uvs[0].unwrap();
    let close = |a: Vec2, b: Vec2| (a - b).length() < 1e-6;
    assert!(close(uv[0], Vec2::new(0.5, 0.25)), "{uv:?}");
    assert!(close(uv[1], Vec2::new(0.5, 2.25)), "{uv:?}");
    assert!(close(uv[2], Vec2::new(-2.5, 0.25)), "{uv:?}");
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);

    // A rough metal: its colour is its highlight's F0 = base m, which the texture tints too
    // (its diffuse term, base (1 - m), is zero).
    let metal = gltf("", &embedded).replace(r#""metallicFactor": 0.0"#, r#""metallicFactor": 1.0"#);
    std::fs::write(&p, metal).unwrap();
    let s = scene::load(p.to_str().unwrap()).unwrap();
    let b = [0.2, 0.5, 0.3];
    let uv = s.uvs[0][0] * b[0] + s.uvs[0][1] * b[1] + s.uvs[0][2] * b[2];
    let (albedo, highlight) = s.colours(0, b, 0.0, 1.0);
    assert_eq!(albedo, Vec3::ZERO);
    assert!((highlight - s.textures[0].sample(uv, 0.0)).length() < 1e-6, "{highlight}");

    // An image file that is missing: a warning naming it and the material; the factors stay.
    std::fs::write(&p, gltf("", r#"{"uri": "gone.png"}"#)).unwrap();
    let m = scene::gltf::load(&p).unwrap();
    assert_eq!((m.textures.len(), m.materials[0].texture), (0, None));
    assert_eq!(m.warnings.len(), 1);
    for part in ["t.gltf", "material 'painted'", "gone.png"] {
        assert!(m.warnings[0].contains(part), "{:?} should mention {part:?}", m.warnings[0]);
    }
}
