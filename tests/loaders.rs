//! Integration tests of the scene loaders: OBJ/MTL (and `.obj.gz`), glTF/GLB and TOML scene
//! files, on the real models in `../shared/scenes/` and on small fixtures written at test time.
//! Bad input must give an `Err` whose text names the file (and the line where one exists),
//! never a panic.

use std::fmt::Debug;
use std::io::Write;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use hyrt::scene::{self, MeshData, MirrorSource, Scene, file, gltf, material, obj};

/// A model under `../shared/scenes/` (relative to the crate root).
fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes").join(rel)
}

/// A committed fixture under `tests/data/`.
fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn write_gz(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    let mut enc =
        flate2::write::GzEncoder::new(std::fs::File::create(&p).unwrap(), flate2::Compression::fast());
    enc.write_all(text.as_bytes()).unwrap();
    enc.finish().unwrap();
    p
}

/// The full error text (with anyhow's context chain) of a result that must be an error.
fn err_text<T: Debug, E: std::fmt::Display>(r: Result<T, E>) -> String {
    format!("{:#}", r.expect_err("expected an error"))
}

fn assert_contains(text: &str, parts: &[&str]) {
    for p in parts {
        assert!(text.contains(p), "error text {text:?} should contain {p:?}");
    }
}

/// Checks invariants every loader must keep and returns the triangle count.
fn check_mesh(m: &MeshData) -> usize {
    let n = m.positions.len();
    assert!(n > 0);
    assert_eq!(m.normals.len(), n);
    assert_eq!(m.material.len(), n);
    assert!(m.material.iter().all(|&i| (i as usize) < m.materials.len()));
    assert!(m.positions.iter().flatten().all(|p| p.is_finite()), "non-finite position");
    assert!(m.normals.iter().flatten().flatten().all(|v| v.is_finite()), "non-finite normal");
    // Ranges are contiguous, non-empty and cover every triangle exactly once.
    let mut next = 0;
    for r in &m.ranges {
        assert_eq!(r.first, next, "range '{}' is not contiguous", r.name);
        assert!(r.count > 0);
        next += r.count;
    }
    assert_eq!(next as usize, n);
    n
}

fn bounds(m: &MeshData) -> (Vec3, Vec3) {
    m.positions
        .iter()
        .flatten()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

fn geometric_normal(t: &[Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize()
}

// ---------------------------------------------------------------------------------------------
// OBJ on real scenes

#[test]
fn obj_cornell_bunny_mirror() {
    let m = obj::load(&shared("cornell-bunny-mirror/cornell-bunny-mirror.obj")).unwrap();
    assert_eq!(check_mesh(&m), 69_465);
    let mirror = m.materials.iter().find(|m| m.name == "mirror").expect("material 'mirror'");
    // `illum 3`: Ks is the mirror reflectance, no highlight; `Kd 0`: a perfect mirror.
    assert_eq!((mirror.diffuse, mirror.highlight, mirror.mirror), (Vec3::ZERO, Vec3::ZERO, Vec3::ONE));
    assert_eq!(mirror.mirror_source, MirrorSource::Mtl { illum: 3 });
    // Every other material is `illum 2` with `Ks 0`: diffuse only.
    assert!(m.materials.iter().filter(|m| m.name != "mirror").all(|m| !m.is_mirror() && !m.has_highlight()));
    assert!(m.material.iter().any(|&i| m.materials[i as usize].name == "mirror"));
}

#[test]
fn obj_radiance_office() {
    let m = obj::load(&shared("radiance-office/office.obj")).unwrap();
    assert_eq!(check_mesh(&m), 34_004);
    assert!(m.materials.iter().any(|m| m.name == "window_glass"));
}

#[test]
fn obj_conference() {
    let m = obj::load(&shared("conference/conference.obj")).unwrap();
    assert_eq!(check_mesh(&m), 331_179);
    // The conference room has no vertex normals.
    assert!(m.normals.iter().all(Option::is_none));
    // 35 materials, all `illum 2` with `Ns 40`: 28 with Ks 0.2 and 7 with Ks 0.43-0.71, read as
    // highlights; none reflects.
    assert_eq!(m.materials.len(), 35);
    assert!(m.materials.iter().all(|m| !m.is_mirror() && (m.shininess - 40.0).abs() < 1e-4));
    assert_eq!(m.materials.iter().filter(|m| m.highlight.max_element() > 0.4).count(), 7);
    assert_eq!(m.materials.iter().filter(|m| m.highlight == Vec3::splat(0.2)).count(), 28);
}

#[test]
fn obj_gz_bitterli_kitchen() {
    let m = obj::load(&shared("bitterli-kitchen/scene.obj.gz")).unwrap();
    assert_eq!(check_mesh(&m), 1_443_517);
}

// ---------------------------------------------------------------------------------------------
// OBJ on fixtures

const CUBE_MTL: &str = "\
# comment
newmtl red
Kd 0.8 0.1 0.1 # trailing comment
Ks 0 0 0
illum 2

newmtl shiny
Kd 0.5
Ks 0.5 0.5 0.5
";

/// A pentagon before any `usemtl` (so without a material), a point and a line (ignored), a quad
/// with normals in `red`, a triangle in `shiny`, and a triangle naming an unknown material.
const SMALL_OBJ: &str = "\
mtllib small.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0.5 1.5 0
vn 0 0 1
o poly
f 1 2 3 5 4
p 1
l 1 2
o quad
usemtl red
f 1//1 2//1 3//1 4//1
o tri
usemtl shiny
f 1 2 3
o unknown
usemtl no_such_material
f -5 -4 -3
";

fn small_fixture(dir: &Path, gz: bool) -> PathBuf {
    write(dir, "small.mtl", CUBE_MTL);
    if gz { write_gz(dir, "small.obj.gz", SMALL_OBJ) } else { write(dir, "small.obj", SMALL_OBJ) }
}

#[test]
fn obj_small_fixture() {
    let dir = tempfile::tempdir().unwrap();
    let m = obj::load(&small_fixture(dir.path(), false)).unwrap();
    // pentagon 3 + quad 2 + triangle 1 + triangle 1
    assert_eq!(check_mesh(&m), 7);
    let names: Vec<&str> = m.ranges.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["poly", "quad", "tri", "unknown"]);
    let mat = |t: usize| &m.materials[m.material[t] as usize];
    assert_eq!(mat(3).name, "red");
    assert_eq!(mat(3).diffuse, Vec3::new(0.8, 0.1, 0.1));
    // `Kd 0.5` means grey; Ks 0.5 without `illum` (nor `Ns`) is a highlight of the default
    // exponent, not a mirror.
    assert_eq!(mat(5).name, "shiny");
    assert_eq!(mat(5).diffuse, Vec3::splat(0.5));
    assert_eq!((mat(5).highlight, mat(5).shininess), (Vec3::splat(0.5), material::DEFAULT_SHININESS));
    assert!(!mat(5).is_mirror());
    // Faces without a (known) material share one grey default.
    assert_eq!(mat(0).name, "default");
    assert_eq!(mat(6).name, "default");
    assert_eq!(m.materials.iter().filter(|m| m.name == "default").count(), 1);
    assert_eq!(mat(0).diffuse, Vec3::splat(0.8));
    // Normals only where the file gave them.
    assert_eq!(m.normals[3], Some([Vec3::Z; 3]));
    assert_eq!(m.normals[0], None);
    assert_eq!(m.normals[5], None);
}

/// Each MTL illumination model as the format means it: 0-2 and none without a reflection ray
/// (a highlight from 2, or without `illum`); 3 and up a mirror of reflectance `Ks`, no highlight.
#[test]
fn obj_illumination_models() {
    let dir = tempfile::tempdir().unwrap();
    let mut mtl = String::new();
    let mut obj = String::from("mtllib illum.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    let models: Vec<Option<u8>> = [None].into_iter().chain((0..=10).map(Some)).collect();
    for (k, illum) in models.iter().enumerate() {
        mtl += &format!("newmtl m{k}\nKd 0.3 0.4 0.5\nKs 0.2 0.1 0.05\nNs 64\n");
        if let Some(i) = illum {
            mtl += &format!("illum {i}\n");
        }
        obj += &format!("usemtl m{k}\nf 1 2 3\n");
    }
    write(dir.path(), "illum.mtl", &mtl);
    let m = obj::load(&write(dir.path(), "illum.obj", &obj)).unwrap();
    let (kd, ks) = (Vec3::new(0.3, 0.4, 0.5), Vec3::new(0.2, 0.1, 0.05));
    for (k, illum) in models.iter().enumerate() {
        let mat = &m.materials[m.material[k] as usize];
        assert_eq!((mat.name.as_str(), mat.diffuse, mat.shininess), (format!("m{k}").as_str(), kd, 64.0));
        let (highlight, mirror) = match illum {
            None | Some(2) => (ks, Vec3::ZERO),
            Some(0 | 1) => (Vec3::ZERO, Vec3::ZERO),
            Some(_) => (Vec3::ZERO, ks),
        };
        assert_eq!((mat.highlight, mat.mirror), (highlight, mirror), "illum {illum:?}");
        if let Some(i @ 3..) = *illum {
            assert_eq!(mat.mirror_source, MirrorSource::Mtl { illum: i });
        }
    }
    // `Ks 1` alone (the old rule's perfect mirror) is a highlight under `illum 2`.
    write(dir.path(), "one.mtl", "newmtl shiny\nKd 0\nKs 1 1 1\nillum 2\n");
    let m = obj::load(&write(
        dir.path(),
        "one.obj",
        "mtllib one.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl shiny\nf 1 2 3\n",
    ))
    .unwrap();
    let shiny = &m.materials[0];
    assert_eq!((shiny.diffuse, shiny.highlight, shiny.mirror), (Vec3::ZERO, Vec3::ONE, Vec3::ZERO));
    assert!(shiny.is_lit() && !shiny.is_mirror());
}

#[test]
fn obj_gz_fixture_matches_plain() {
    let dir = tempfile::tempdir().unwrap();
    let plain = obj::load(&small_fixture(dir.path(), false)).unwrap();
    let gz = obj::load(&small_fixture(dir.path(), true)).unwrap();
    assert_eq!(plain.positions, gz.positions);
    assert_eq!(plain.normals, gz.normals);
    assert_eq!(plain.material, gz.material);
    assert_eq!(plain.materials, gz.materials);
    assert_eq!(plain.ranges, gz.ranges);
}

#[test]
fn obj_corrupt_gz() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "broken.obj.gz", "this is not gzip data");
    assert_contains(&err_text(obj::load(&p)), &["broken.obj.gz", "cannot decompress"]);
}

// ---------------------------------------------------------------------------------------------
// OBJ errors

#[test]
fn obj_missing_file() {
    let text = err_text(obj::load(Path::new("no/such/file.obj")));
    assert_eq!(text, "no/such/file.obj: cannot read file: No such file or directory");
}

#[test]
fn obj_malformed_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "bad.obj", "v 0 0 0\nv 1 0 0\nv 1.0 abc 2.0\nf 1 2 3\n");
    let text = err_text(obj::load(&p));
    assert_contains(&text, &["bad.obj:3: malformed vertex 'v 1.0 abc 2.0'"]);
}

#[test]
fn obj_nan_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "bad.obj", "# nan\nv 0 0 0\nv 1 0 0\nv nan 0 0\nf 1 2 3\n");
    assert_contains(&err_text(obj::load(&p)), &["bad.obj:4: vertex has a NaN or infinite coordinate"]);
    let p = write(dir.path(), "inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n");
    assert_contains(&err_text(obj::load(&p)), &["inf.obj:3: vertex has a NaN or infinite coordinate"]);
    let p =
        write(dir.path(), "vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn inf 0 0\nf 1//1 2//2 3//1\n");
    assert_contains(&err_text(obj::load(&p)), &["vn.obj:5: normal has a NaN or infinite component"]);
}

#[test]
fn obj_face_index_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
    assert_contains(
        &err_text(obj::load(&p)),
        &["bad.obj:5: face index 9 is out of range (only 3 vertices defined", "'f 1 2 9'"],
    );
    let p = write(dir.path(), "one.obj", "v 0 0 0\nf 1 2 3\n");
    assert_contains(
        &err_text(obj::load(&p)),
        &["one.obj:2: face index 2 is out of range (only 1 vertex defined"],
    );
    let p = write(dir.path(), "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    assert_contains(&err_text(obj::load(&p)), &["zero.obj:4: face index 0 is invalid"]);
    let p = write(dir.path(), "neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
    assert_contains(&err_text(obj::load(&p)), &["neg.obj:4: face index -4 is out of range"]);
}

#[test]
fn obj_missing_mtl() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "bad.obj",
        "# no library\nmtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let text = err_text(obj::load(&p));
    assert_contains(&text, &["bad.obj:2", "missing.mtl", "No such file or directory"]);
}

#[test]
fn obj_malformed_mtl() {
    let dir = tempfile::tempdir().unwrap();
    let obj_text = "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    let p = write(dir.path(), "bad.obj", obj_text);
    let cases = [
        ("newmtl a\nKs 0 0 0\nKd 0.5 abc 0.2\n", "bad.mtl:3: malformed number in 'Kd 0.5 abc 0.2'"),
        ("newmtl a\nKd 0.5 0.5\n", "bad.mtl:2: expected 1 or 3 numbers in 'Kd 0.5 0.5'"),
        ("newmtl a\nKs nan 0 0\n", "bad.mtl:2: colour has a NaN or infinite component"),
        ("newmtl a\n\nillum three\n", "bad.mtl:3: malformed illumination model"),
        ("newmtl a\nNs\n", "bad.mtl:2: malformed number in 'Ns'"),
        ("newmtl a\nNs -1\n", "bad.mtl:2: the highlight exponent must be finite and >= 0 in 'Ns -1'"),
        ("newmtl a\n\nNs inf\n", "bad.mtl:3: the highlight exponent must be finite and >= 0"),
        ("newmtl a\nKd 0.5 -0.1 0.2\n", "bad.mtl:2: negative reflectance in 'Kd 0.5 -0.1 0.2'"),
        ("newmtl a\nKs -1\n", "bad.mtl:2: negative reflectance"),
        ("newmtl\n", "bad.mtl:1: 'newmtl' without a material name"),
    ];
    for (mtl, expected) in cases {
        write(dir.path(), "bad.mtl", mtl);
        let text = err_text(obj::load(&p));
        assert_contains(&text, &[expected, "bad.obj"]);
    }
}

#[test]
fn obj_mtllib_with_several_files() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "a.mtl", "newmtl a\nKd 1 0 0\n");
    write(dir.path(), "b.mtl", "newmtl b\nKd 0 1 0\n");
    let p =
        write(dir.path(), "two.obj", "mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl b\nf 1 2 3\n");
    let m = obj::load(&p).unwrap();
    assert_eq!(m.materials[m.material[0] as usize].diffuse, Vec3::Y);
}

#[test]
fn obj_empty() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [
        ("empty.obj", ""),
        ("verts.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        ("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\nf 1\n"),
    ] {
        let p = write(dir.path(), name, text);
        assert_contains(&err_text(obj::load(&p)), &[name, "has no triangles"]);
    }
}

/// Hostile lines must give an error (or load), never a panic.
#[test]
fn obj_hostile_input_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let lines = [
        "f 1/0/0 2/0/0 3/0/0",
        "f 1/-9/ 2/-9/ 3/-9/",
        "f 1//-99 2//-99 3//-99",
        "f -10 1 2",
        "f 99999999999999999999 1 2",
        "f 1/2/3/4 1 2",
        "f /1 2 3",
        "f",
        "l",
        "usemtl",
        "vt",
        "vt 1",
        "vn 1 2",
        "v 1 2 3 0",
        "v 1 2 3 4 5",
        "v 1 2 3 4 5 6 7",
        "v 1 2 3 a b c",
        "o",
        "mtllib",
        "mtllib /",
        "\u{0}\u{1}\u{2}",
    ];
    for (i, line) in lines.iter().enumerate() {
        let text = format!("vt 0 0\nvn 0 0 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\n{line}\nf 1 2 3\n");
        let p = write(dir.path(), &format!("hostile{i}.obj"), &text);
        if let Err(e) = obj::load(&p) {
            assert!(format!("{e:#}").contains(&format!("hostile{i}.obj")), "{e:#}");
        }
    }
    // Invalid UTF-8 is tolerated (names in old files are often Latin-1).
    let p = dir.path().join("latin1.obj");
    std::fs::write(&p, b"g caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!(obj::load(&p).unwrap().positions.len(), 1);
}

// ---------------------------------------------------------------------------------------------
// glTF

#[test]
fn gltf_samples_load() {
    let cases = [
        ("Triangle/glTF/Triangle.gltf", 1),
        ("SimpleMeshes/glTF/SimpleMeshes.gltf", 2),
        ("BoxTextured/glTF/BoxTextured.gltf", 12),
        ("BoxTextured/glTF-Binary/BoxTextured.glb", 12),
        ("Duck/glTF/Duck.gltf", 4212),
        ("Duck/glTF-Binary/Duck.glb", 4212),
        ("DamagedHelmet/glTF/DamagedHelmet.gltf", 15_452),
        ("2CylinderEngine/glTF/2CylinderEngine.gltf", 121_496),
    ];
    for (rel, tris) in cases {
        let m =
            gltf::load(&shared(&format!("gltf-samples/{rel}"))).unwrap_or_else(|e| panic!("{rel}: {e:#}"));
        assert_eq!(check_mesh(&m), tris, "{rel}");
    }
}

#[test]
fn gltf_glb_matches_gltf() {
    let a = gltf::load(&shared("gltf-samples/Duck/glTF/Duck.gltf")).unwrap();
    let b = gltf::load(&shared("gltf-samples/Duck/glTF-Binary/Duck.glb")).unwrap();
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.materials, b.materials);
    // The duck's node scales it by 0.01: it is about 1.6 units long, not 160.
    let (lo, hi) = bounds(&a);
    let size = hi - lo;
    assert!(size.max_element() > 1.0 && size.max_element() < 3.0, "{size}");
    assert!(a.normals.iter().all(Option::is_some));
}

#[test]
fn gltf_simple_meshes_instancing() {
    // One mesh used by two nodes, the second translated by +1 in x.
    let m = gltf::load(&shared("gltf-samples/SimpleMeshes/glTF/SimpleMeshes.gltf")).unwrap();
    assert_eq!(m.ranges.len(), 2);
    let d = m.positions[1][0] - m.positions[0][0];
    assert!((d - Vec3::X).length() < 1e-6, "{d}");
}

#[test]
fn gltf_2cylinder_engine_bounds() {
    let m = gltf::load(&shared("gltf-samples/2CylinderEngine/glTF/2CylinderEngine.gltf")).unwrap();
    // 67 node instances of 29 meshes.
    assert_eq!(m.ranges.len(), 67);
    // Bounds computed independently (Python, from the node hierarchy and the raw buffer).
    let (lo, hi) = bounds(&m);
    let expect_lo = Vec3::new(-371.69, -180.97, -140.0);
    let expect_hi = Vec3::new(371.69, 92.04, 128.0);
    assert!((lo - expect_lo).abs().max_element() < 0.1, "lo {lo}");
    assert!((hi - expect_hi).abs().max_element() < 0.1, "hi {hi}");
}

#[test]
fn gltf_draco_errors_clearly() {
    let text = err_text(gltf::load(&shared("gltf-samples/Duck/glTF-Draco/Duck.gltf")));
    assert_contains(&text, &["Duck.gltf", "KHR_draco_mesh_compression", "not support"]);
}

/// A minimal glTF whose single buffer is a base64 `data:` URI: a triangle (0,0,0) (1,0,0)
/// (0,1,0) and the given nodes/primitives JSON.
fn tiny_gltf(nodes: &str, mode: u32) -> String {
    use base64::Engine as _;
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": {nodes},
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 0}}, "mode": {mode}, "material": 0}}]}}],
  "materials": [{{"name": "orange", "pbrMetallicRoughness": {{"baseColorFactor": [1.0, 0.5, 0.0, 1.0]}}}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,{b64}"}}]
}}"#
    )
}

#[test]
fn gltf_data_uri_and_mirrored_node() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = r#"[{"name": "plain", "mesh": 0},
                    {"name": "mirrored", "mesh": 0, "scale": [-1, 1, 1], "translation": [5, 0, 0]}]"#;
    let p = write(dir.path(), "tiny.gltf", &tiny_gltf(nodes, 4));
    let m = gltf::load(&p).unwrap();
    assert_eq!(check_mesh(&m), 2);
    assert_eq!(m.ranges[1].name, "mirrored");
    // Only a base colour: glTF's default metallic and roughness (both 1) make a rough metal,
    // whose highlight of exponent 0 is a Lambertian lobe of the base colour.
    let orange = &m.materials[m.material[0] as usize];
    assert_eq!(
        (orange.diffuse, orange.highlight, orange.shininess),
        (Vec3::ZERO, Vec3::new(1.0, 0.5, 0.0), 0.0)
    );
    // The mirrored copy is re-wound: both still face +Z.
    assert!(geometric_normal(&m.positions[0]).z > 0.99);
    assert!(geometric_normal(&m.positions[1]).z > 0.99);
    assert!(m.positions[1].iter().all(|p| p.x >= 4.0 - 1e-6 && p.x <= 5.0 + 1e-6));
}

/// The documented glTF mapping: diffuse `c (1 - m)`, `F0 = 0.04 (1 - m) + c m`; smooth metals
/// reflect, everything else has a highlight whose exponent comes from the roughness.
#[test]
fn gltf_metallic_roughness_mapping() {
    let dir = tempfile::tempdir().unwrap();
    let materials = r#"[
      {"name": "plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}},
      {"name": "chrome", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.8, 0.7, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.1}},
      {"name": "brushed", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.8, 0.7, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3}},
      {"name": "half", "pbrMetallicRoughness": {"metallicFactor": 0.5, "roughnessFactor": 0.0}},
      {"name": "glass-smooth", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0}}
    ]"#;
    let text = tiny_gltf(r#"[{"mesh": 0}, {"mesh": 0}]"#, 4)
        .replace(r#""material": 0"#, r#""material": 1"#)
        .replace(
            r#"[{"name": "orange", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.5, 0.0, 1.0]}}]"#,
            materials,
        );
    let m = gltf::load(&write(dir.path(), "mats.gltf", &text)).unwrap();
    let by = |n: &str| m.materials.iter().find(|m| m.name == n).unwrap_or_else(|| panic!("{n}")).clone();
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * b.abs().max(1.0);

    let p = by("plastic");
    assert_eq!(
        (p.diffuse, p.highlight, p.mirror),
        (Vec3::new(0.5, 0.25, 1.0), Vec3::splat(0.04), Vec3::ZERO)
    );
    // r = 0.5: alpha = 0.25, Ns = 2 / 0.0625 - 2 = 30.
    assert!(close(p.shininess, 30.0), "{}", p.shininess);

    let c = by("chrome");
    assert_eq!((c.diffuse, c.highlight, c.mirror), (Vec3::ZERO, Vec3::ZERO, Vec3::new(0.9, 0.8, 0.7)));
    assert_eq!(c.mirror_source, MirrorSource::Gltf { metallic: 1.0, roughness: 0.1 });

    let b = by("brushed");
    assert_eq!((b.diffuse, b.highlight, b.mirror), (Vec3::ZERO, Vec3::new(0.9, 0.8, 0.7), Vec3::ZERO));
    // r = 0.3: alpha = 0.09, Ns = 2 / 0.0081 - 2.
    assert!(close(b.shininess, 2.0 / 0.0081 - 2.0), "{}", b.shininess);

    // Default base colour 1: metallic 0.5 and roughness 0 is a smooth metal, F0 = 0.52.
    let h = by("half");
    assert_eq!(h.diffuse, Vec3::splat(0.5));
    assert!(h.mirror.to_array().iter().all(|&k| close(k, 0.52)), "{}", h.mirror);

    // A smooth dielectric never reflects: its highlight's exponent is capped.
    let g = by("glass-smooth");
    assert_eq!(
        (g.diffuse, g.highlight, g.shininess, g.mirror),
        (Vec3::ONE, Vec3::splat(0.04), material::MAX_SHININESS, Vec3::ZERO)
    );
}

#[test]
fn gltf_non_triangle_primitives_only() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = r#"[{"mesh": 0}, {"mesh": 0}]"#;
    let p = write(dir.path(), "points.gltf", &tiny_gltf(nodes, 0));
    assert_contains(
        &err_text(gltf::load(&p)),
        &["points.gltf", "has no triangles", "2 primitive(s) skipped"],
    );
}

#[test]
fn gltf_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let good = tiny_gltf(r#"[{"mesh": 0}, {"mesh": 0}]"#, 4);

    let missing_bin =
        good.replace(&good[good.find("data:").unwrap()..good.rfind('"').unwrap()], "nowhere.bin");
    let p = write(dir.path(), "missing-bin.gltf", &missing_bin);
    assert_contains(&err_text(gltf::load(&p)), &["missing-bin.gltf", "nowhere.bin", "cannot read file"]);

    let short = good.replace(r#""buffers": [{"byteLength": 36"#, r#""buffers": [{"byteLength": 48"#);
    let p = write(dir.path(), "short.gltf", &short);
    assert_contains(&err_text(gltf::load(&p)), &["short.gltf", "buffer 0 has 36 bytes"]);

    let past_view = good.replace(r#""count": 3"#, r#""count": 4"#);
    let p = write(dir.path(), "past-view.gltf", &past_view);
    assert_contains(&err_text(gltf::load(&p)), &["past-view.gltf", "reads past the end of buffer view 0"]);

    let stride = good.replace(r#""byteLength": 36}]"#, r#""byteLength": 36, "byteStride": 4}]"#);
    let p = write(dir.path(), "stride.gltf", &stride);
    assert_contains(&err_text(gltf::load(&p)), &["stride.gltf", "stride"]);

    let cycle =
        good.replace(r#"[{"mesh": 0}, {"mesh": 0}]"#, r#"[{"mesh": 0, "children": [1]}, {"children": [0]}]"#);
    let p = write(dir.path(), "cycle.gltf", &cycle);
    assert_contains(&err_text(gltf::load(&p)), &["cycle.gltf", "reached twice"]);

    let bad_index = good.replace(r#""nodes": [0, 1]"#, r#""nodes": [0, 7]"#);
    let p = write(dir.path(), "bad-index.gltf", &bad_index);
    assert_contains(&err_text(gltf::load(&p)), &["bad-index.gltf", "invalid glTF"]);

    // An attribute naming an accessor that does not exist (the gltf crate's own validation
    // panicked on it; found by tests/fuzz_loaders.rs).
    let no_accessor = good.replace(r#""POSITION": 0"#, r#""POSITION": 5"#);
    assert_ne!(no_accessor, good);
    let p = write(dir.path(), "no-accessor.gltf", &no_accessor);
    assert_contains(&err_text(gltf::load(&p)), &["no-accessor.gltf", "primitives[0] uses accessor 5 of 1"]);

    let p = write(dir.path(), "garbage.glb", "glTF\u{2}\u{0}\u{0}\u{0}garbage");
    assert_contains(&err_text(gltf::load(&p)), &["garbage.glb", "not a valid glTF"]);

    let p = dir.path().join("short-header.glb");
    std::fs::write(&p, b"glTF\x02\0\0\0\x04\0\0\0").unwrap();
    assert_contains(&err_text(gltf::load(&p)), &["short-header.glb", "not a valid GLB"]);

    let p = write(dir.path(), "broken.gltf", "{ \"asset\": ");
    assert_contains(&err_text(gltf::load(&p)), &["broken.gltf", "not a valid glTF"]);

    assert_contains(&err_text(gltf::load(Path::new("no/such.glb"))), &["no/such.glb: cannot read file"]);
}

/// [`tiny_gltf`] with cameras and `KHR_lights_punctual` lights: node 0 the triangle; node 1
/// a parent (translated by (0, 0, 10)) of node 2, a perspective camera at (1, 2, 3) in it,
/// turned by a quarter turn about +Y (so that it looks down -X); node 3 an orthographic
/// camera; nodes 4-6 a point, a spot and a directional light. Camera 2 is placed by no node.
fn gltf_with_cameras_and_lights() -> String {
    let nodes = r#"[{"mesh": 0},
        {"translation": [0, 0, 10], "children": [2]},
        {"name": "cam", "camera": 0, "rotation": [0, 0.70710678, 0, 0.70710678], "translation": [1, 2, 3]},
        {"camera": 1},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 5, 0]},
        {"extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"extensions": {"KHR_lights_punctual": {"light": 2}}}]"#;
    tiny_gltf(nodes, 4).replace(
        r#""scenes": [{"nodes": [0, 1]}],"#,
        r#""scenes": [{"nodes": [0, 1, 3, 4, 5, 6]}],
  "cameras": [
    {"name": "main", "type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1}},
    {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}},
    {"name": "spare", "type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}],
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"name": "bulb", "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 683.0, "range": 2.0},
    {"type": "spot", "intensity": 10.0, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}},
    {"type": "directional", "intensity": 3.0}]}},"#,
    )
}

/// glTF cameras placed by their nodes (the parent's transform too) and point lights in W/sr
/// (candela / 683, times the colour), spot and directional lights; what hyrt has no model for
/// is skipped with a warning
/// that names it.
#[test]
fn gltf_cameras_and_lights() {
    let dir = tempfile::tempdir().unwrap();
    let text = gltf_with_cameras_and_lights();
    let m = gltf::load(&write(dir.path(), "lit.gltf", &text)).unwrap();
    assert_eq!(m.cameras.len(), 1, "{:?}", m.cameras);
    let c = &m.cameras[0];
    assert_eq!(c.label, "camera 0 'main'");
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    assert!(close(c.camera.eye, Vec3::new(1.0, 2.0, 13.0)), "{:?}", c.camera.eye);
    // A quarter turn about +Y takes -Z to -X.
    assert!(close(c.camera.forward.normalize(), Vec3::NEG_X), "{:?}", c.camera.forward);
    assert!(close(c.camera.up.normalize(), Vec3::Y), "{:?}", c.camera.up);
    assert!((c.camera.fov_y_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    assert_eq!(c.aspect, Some(2.0));
    assert_eq!(m.lights.len(), 2);
    assert_eq!(m.lights[0].position, Vec3::new(0.0, 5.0, 0.0));
    assert!(close(m.lights[0].intensity, Vec3::new(1.0, 0.5, 0.25)), "{:?}", m.lights[0].intensity);
    assert!(m.lights[0].spot.is_none());
    // The spot shines down its node's -Z, its cone's half-angles in radians.
    let spot = m.lights[1].spot.unwrap();
    assert_eq!(spot.axis, Vec3::NEG_Z);
    assert!((spot.cos_inner - 0.1f32.cos()).abs() < 1e-6 && (spot.cos_outer - 0.5f32.cos()).abs() < 1e-6);
    assert!(close(m.lights[1].intensity, Vec3::splat(10.0 / 683.0)));
    // The directional light travels down its node's -Z, 3 lux = 3 / 683 W/m^2; it is placed
    // with the scene's bounds.
    assert_eq!(m.directional.len(), 1);
    assert_eq!(m.directional[0].direction, Vec3::NEG_Z);
    assert!(close(m.directional[0].irradiance, Vec3::splat(3.0 / 683.0)));
    let warnings = m.warnings.join("\n");
    assert_eq!(m.warnings.len(), 2, "{warnings}");
    for part in ["camera 1 is orthographic", "camera 2 'spare' is placed by no node"] {
        assert!(warnings.contains(part), "{warnings:?} should mention {part:?}");
    }
    assert!(m.warnings.iter().all(|w| w.starts_with(&format!("{}", dir.path().join("lit.gltf").display()))));

    // A bare file: its camera, its aspect (the width kept), its light, and an exposure for
    // that light; `--camera` out of range names the cameras there are.
    let p = dir.path().join("lit.gltf");
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.camera, Some(c.camera));
    assert_eq!((s.settings.width, s.settings.height), (640, 320));
    assert_eq!(s.lights.len(), 3);
    assert!(s.settings.exposure > 0.0 && s.settings.exposure.is_finite() && s.settings.exposure != 1.0);
    assert_eq!(s.warnings.len(), 2);
    let o = scene::Overrides { camera: Some(1), ..Default::default() };
    assert_contains(
        &err_text(scene::load_with(p.to_str().unwrap(), o)),
        &["lit.gltf", "no camera 1", "0: camera 0 'main'"],
    );
    let o = scene::Overrides { camera: Some(0), size: Some((100, 100)), ..Default::default() };
    let s = scene::load_with(p.to_str().unwrap(), o).unwrap();
    assert_eq!((s.settings.width, s.settings.height), (100, 100));

    // Without cameras, the automatic framing; its light sits beside the file's camera
    // otherwise, so that what the camera sees is lit.
    let no_cam = text.replace(r#""camera": 0, "#, "");
    let s = scene::load(write(dir.path(), "nocam.gltf", &no_cam).to_str().unwrap()).unwrap();
    assert_ne!(s.camera, Some(c.camera));
    assert_eq!((s.settings.width, s.settings.height), (640, 480));
}

/// A scene file's glTF mesh brings its camera (unless the file has a `[camera]`) and its
/// lights (the file's `[[light]]`s are added), both moved by the mesh's transform; a size in
/// `[settings]` is kept whatever the camera's aspect.
#[test]
fn toml_with_gltf_cameras_and_lights() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "lit.gltf", &gltf_with_cameras_and_lights());
    let p = write(
        dir.path(),
        "s.toml",
        "[[mesh]]\npath = \"lit.gltf\"\ntranslate = [100, 0, 0]\n\n[[light]]\nposition = [0, 1, 0]\nintensity = 2\n",
    );
    let s = file::load(&p).unwrap();
    let cam = s.camera.unwrap();
    assert!((cam.eye - Vec3::new(101.0, 2.0, 13.0)).length() < 1e-4, "{:?}", cam.eye);
    assert_eq!((s.settings.width, s.settings.height), (640, 320));
    // The glTF's point and spot lights, the [[light]], then the directional light.
    assert_eq!(s.lights.len(), 4);
    assert_eq!(s.lights[0].position, Vec3::new(100.0, 5.0, 0.0));
    assert_eq!(s.lights[2].intensity, Vec3::splat(2.0));
    assert!(s.lights[3].position.z > 1e3, "{}", s.lights[3].position);
    // A rotation turns a spot's axis with it: a quarter turn about +Y takes -Z to -X.
    let p = write(dir.path(), "turned.toml", "[[mesh]]\npath = \"lit.gltf\"\nrotate = [0, 90, 0]\n");
    let axis = file::load(&p).unwrap().lights[1].spot.unwrap().axis;
    assert!((axis - Vec3::NEG_X).length() < 1e-6, "{axis}");
    // The file's exposure stays as written (the default).
    assert_eq!(s.settings.exposure, 1.0);

    let p = write(
        dir.path(),
        "sized.toml",
        "[settings]\nwidth = 300\n\n[camera]\neye = [0, 0, 50]\ntarget = [0, 0, 0]\nfov_y = 30\n\n[[mesh]]\npath = \"lit.gltf\"\n",
    );
    let s = file::load(&p).unwrap();
    assert_eq!(s.camera.unwrap().eye, Vec3::new(0.0, 0.0, 50.0));
    let o = scene::Overrides { camera: Some(0), ..Default::default() };
    let s = scene::load_with(p.to_str().unwrap(), o).unwrap();
    assert!((s.camera.unwrap().eye - Vec3::new(1.0, 2.0, 13.0)).length() < 1e-4);
    assert_eq!((s.settings.width, s.settings.height), (300, 480));
}

// ---------------------------------------------------------------------------------------------
// TOML scene files

#[test]
fn toml_cornell_bunny_mirror_fixture() {
    let s = file::load(&data("cornell-bunny-mirror.toml")).unwrap();
    assert_eq!(s.name, "cornell-bunny-mirror");
    assert_eq!(s.triangle_count(), 69_465);
    assert_eq!(s.lights.len(), 5);
    assert_eq!(s.lights[0].intensity, Vec3::splat(0.6));
    let cam = s.camera.unwrap();
    assert_eq!(cam.eye, Vec3::new(0.0, 1.0, 6.8));
    assert_eq!(cam.forward, Vec3::new(0.0, 0.0, -6.8));
    assert_eq!(cam.fov_y_deg, 19.5);
    assert_eq!(cam.fov_x_deg, None);
    let mirror = s.materials.iter().find(|m| m.name == "mirror").unwrap();
    assert_eq!((mirror.diffuse, mirror.mirror), (Vec3::ZERO, Vec3::ONE));
    assert_eq!(s.source.as_deref(), Some(data("cornell-bunny-mirror.toml").as_path()));
    s.validate().unwrap();
    // The CLI entry point accepts the same file (and validates it).
    let via_cli = scene::load(data("cornell-bunny-mirror.toml").to_str().unwrap()).unwrap();
    assert_eq!(via_cli.triangle_count(), 69_465);
}

#[test]
fn toml_office_fixture_direction_and_exclusion() {
    let s = file::load(&data("radiance-office.toml")).unwrap();
    let cam = s.camera.unwrap();
    assert_eq!(cam.forward, Vec3::new(-0.5607, -0.2336, 0.7944));
    assert_eq!((cam.fov_y_deg, cam.fov_x_deg), (27.5, Some(39.9)));
    assert_eq!(s.lights.len(), 9);
    assert_eq!(s.lights[8].intensity, Vec3::splat(800.0));
    let full = obj::load(&shared("radiance-office/office.obj")).unwrap();
    let glass = full.material.iter().filter(|&&i| full.materials[i as usize].name == "window_glass").count();
    assert!(glass > 0);
    assert_eq!(s.triangle_count(), 34_004 - glass);
    assert!(s.material.iter().all(|&i| s.materials[i as usize].name != "window_glass"));
    // Ranges stay consistent after exclusion.
    let covered: u32 = s.meshes.iter().map(|r| r.count).sum();
    assert_eq!(covered as usize, s.triangle_count());
    s.validate().unwrap();
}

/// A scene directory with a one-triangle OBJ `tri.obj` (0,0,0) (1,0,0) (0,1,0), material `m`.
fn tri_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "tri.mtl",
        "newmtl m\nKd 0.5 0.5 0.5\nKs 0.25\nNs 20\nillum 2\nnewmtl other\nKd 1 1 1\n",
    );
    write(dir.path(), "tri.obj", "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n");
    dir
}

const CAMERA: &str = "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nfov_y = 45\n";

#[test]
fn toml_transform_order_and_convention() {
    let dir = tri_dir();
    let p = write(
        dir.path(),
        "s.toml",
        &format!(
            "{CAMERA}[[mesh]]\npath = \"tri.obj\"\nscale = 2\nrotate = [90, 90, 0]\ntranslate = [1, 2, 3]\n"
        ),
    );
    let s = file::load(&p).unwrap();
    // Scale, then X by 90 and Y by 90 about the world axes, then translate:
    // (1,0,0) -> (2,0,0) -> X: (2,0,0) -> Y: (0,0,-2) -> (1,2,1).
    let corner = s.positions[0][1];
    assert!((corner - Vec3::new(1.0, 2.0, 1.0)).length() < 1e-5, "{corner}");
    // (0,1,0) -> (0,2,0) -> X: (0,0,2) -> Y: (2,0,0) -> (3,2,3): the X turn came first.
    let top = s.positions[0][2];
    assert!((top - Vec3::new(3.0, 2.0, 3.0)).length() < 1e-5, "{top}");
    assert!((s.positions[0][0] - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-5);

    // Per-axis scale and a mirror keep the triangle facing the same way it was transformed to.
    let p =
        write(dir.path(), "m.toml", &format!("{CAMERA}[[mesh]]\npath = \"tri.obj\"\nscale = [-1, 2, 1]\n"));
    let s = file::load(&p).unwrap();
    let expected = Mat4::from_scale(Vec3::new(-1.0, 2.0, 1.0));
    for p in [Vec3::ZERO, Vec3::X, Vec3::Y] {
        assert!(s.positions[0].iter().any(|q| (*q - expected.transform_point3(p)).length() < 1e-6));
    }
    assert!(geometric_normal(&s.positions[0]).z > 0.99);
    assert!(s.normals[0].iter().all(|n| n.z > 0.99));
}

#[test]
fn toml_defaults_and_automatic_framing() {
    let dir = tri_dir();
    let p = write(dir.path(), "plain.toml", "[[mesh]]\npath = \"tri.obj\"\n");
    let s = file::load(&p).unwrap();
    assert_eq!(s.name, "plain");
    assert_eq!(s.settings, hyrt::scene::Settings::default());
    assert!(s.camera.is_some());
    assert_eq!(s.lights.len(), 1);
    s.validate().unwrap();

    // Given lights are kept as they are when the camera is automatic.
    let p = write(
        dir.path(),
        "lit.toml",
        "name = \"lit scene\"\n[settings]\nwidth = 32\n\n[[mesh]]\npath = \"tri.obj\"\n[[light]]\nposition = [0, 0, 1]\nintensity = 2\n",
    );
    let s = file::load(&p).unwrap();
    assert_eq!(s.name, "lit scene");
    assert_eq!(s.settings.width, 32);
    assert_eq!(s.settings.height, 480);
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.lights[0].intensity, Vec3::splat(2.0));
}

#[test]
fn toml_missing_file() {
    assert_eq!(
        err_text(file::load(Path::new("no/such/scene.toml"))),
        "no/such/scene.toml: cannot read file: No such file or directory"
    );
}

#[test]
fn toml_malformed() {
    let dir = tri_dir();
    let p = write(dir.path(), "bad.toml", "[[mesh]]\npath = \"tri.obj\"\nscale = [1, 2\n\n");
    assert_contains(&err_text(file::load(&p)), &["bad.toml", "line 3"]);
}

#[test]
fn toml_unknown_key() {
    let dir = tri_dir();
    let p = write(dir.path(), "bad.toml", "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nfov = 45\n");
    assert_contains(&err_text(file::load(&p)), &["bad.toml", "line 4", "unknown field `fov`"]);
    let p =
        write(dir.path(), "table.toml", "[[mesh]]\npath = \"tri.obj\"\n[[lights]]\nposition = [0, 0, 0]\n");
    assert_contains(&err_text(file::load(&p)), &["table.toml", "line 3", "unknown field `lights`"]);
}

#[test]
fn toml_bad_values() {
    let dir = tri_dir();
    let cases = [
        ("scale = \"big\"", "a number or an array of three numbers"),
        ("scale = [1, 2]", "line 3"),
        ("rotate = [1, 2, 3, 4]", "line 3"),
        ("translate = [1, 2, \"x\"]", "line 3"),
    ];
    for (line, expected) in cases {
        let p = write(dir.path(), "bad.toml", &format!("[[mesh]]\npath = \"tri.obj\"\n{line}\n"));
        assert_contains(&err_text(file::load(&p)), &["bad.toml", expected]);
    }
    let p = write(dir.path(), "w.toml", "[settings]\nwidth = -3\n[[mesh]]\npath = \"tri.obj\"\n");
    assert_contains(&err_text(file::load(&p)), &["w.toml", "line 2"]);
    let p = write(dir.path(), "zero.toml", "\n[[mesh]]\npath = \"tri.obj\"\nscale = [1, 0, 1]\n");
    assert_contains(&err_text(file::load(&p)), &["zero.toml:2: mesh tri.obj", "scale non-zero"]);
    let p = write(dir.path(), "inf.toml", "[[mesh]]\npath = \"tri.obj\"\ntranslate = [1, inf, 1]\n");
    assert_contains(&err_text(file::load(&p)), &["inf.toml:1: mesh tri.obj", "finite"]);
}

#[test]
fn toml_mesh_fails() {
    let dir = tri_dir();
    write(dir.path(), "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    let p = write(dir.path(), "scene.toml", &format!("{CAMERA}\n[[mesh]]\npath = \"bad.obj\"\n"));
    let text = err_text(file::load(&p));
    assert_contains(&text, &["scene.toml: mesh bad.obj", "bad.obj:4: face index 4 is out of range"]);

    let p = write(dir.path(), "missing.toml", "[[mesh]]\npath = \"nowhere.glb\"\n");
    assert_contains(
        &err_text(file::load(&p)),
        &["missing.toml: mesh nowhere.glb", "nowhere.glb: cannot read file"],
    );

    let p = write(dir.path(), "format.toml", "[[mesh]]\npath = \"tri.ply\"\n");
    assert_contains(&err_text(file::load(&p)), &["format.toml: mesh tri.ply", "unknown mesh format"]);
}

#[test]
fn toml_material_override_without_match() {
    let dir = tri_dir();
    let p = write(
        dir.path(),
        "bad.toml",
        &format!(
            "{CAMERA}[[mesh]]\npath = \"tri.obj\"\n\n[[material]]\nname = \"mirorr\"\nmirror = [1, 1, 1]\n"
        ),
    );
    assert_contains(&err_text(file::load(&p)), &["bad.toml:8", "'mirorr' matches no material", "'m'"]);
}

/// Each part of a material can be overridden on its own; what is not given stays as the MTL
/// read it; a mirror set by the file names the file as its reason.
#[test]
fn toml_material_overrides_each_part() {
    let dir = tri_dir();
    let load = |body: &str| {
        let p = write(
            dir.path(),
            "ok.toml",
            &format!("{CAMERA}[[mesh]]\npath = \"tri.obj\"\n[[material]]\nname = \"m\"\n{body}"),
        );
        let s = file::load(&p).unwrap_or_else(|e| panic!("{body}: {e:#}"));
        s.materials[s.material[0] as usize].clone()
    };
    // As the MTL says: `Kd 0.5`, `Ks 0.25`, `Ns 20`, `illum 2`.
    let mtl = load("");
    assert_eq!(
        (mtl.diffuse, mtl.highlight, mtl.shininess, mtl.mirror),
        (Vec3::splat(0.5), Vec3::splat(0.25), 20.0, Vec3::ZERO)
    );
    let m = load("diffuse = [0.1, 0.2, 0.3]\n");
    assert_eq!(m, hyrt::scene::Material { diffuse: Vec3::new(0.1, 0.2, 0.3), ..mtl.clone() });
    let m = load("highlight = 0.5\n");
    assert_eq!(m, hyrt::scene::Material { highlight: Vec3::splat(0.5), ..mtl.clone() });
    let m = load("shininess = 300\n");
    assert_eq!(m, hyrt::scene::Material { shininess: 300.0, ..mtl.clone() });
    let m = load("mirror = [1, 0.5, 0.25]\nhighlight = 0\n");
    assert_eq!(
        m,
        hyrt::scene::Material {
            mirror: Vec3::new(1.0, 0.5, 0.25),
            highlight: Vec3::ZERO,
            mirror_source: MirrorSource::SceneFile,
            ..mtl.clone()
        }
    );
}

/// Unknown keys (among them `kd` and `ks`, which once meant diffuse and mirror) and
/// out-of-range numbers are errors that name the file and line.
#[test]
fn toml_material_override_errors() {
    let dir = tri_dir();
    let cases = [
        (
            "ks = [1, 1, 1]\n",
            "unknown field `ks`, expected one of `name`, `diffuse`, `highlight`, `shininess`, `mirror`",
        ),
        ("kd = 0.5\n", "unknown field `kd`"),
        ("mirror = -0.5\n", "mirror colour [-0.5, -0.5, -0.5] must be finite and >= 0"),
        ("diffuse = [0.5, nan, 0.5]\n", "diffuse colour"),
        ("shininess = -1\n", "highlight exponent -1 must be finite and >= 0"),
        ("shininess = inf\n", "highlight exponent inf must be finite and >= 0"),
        ("highlight = [1, 2]\n", "invalid length 2, expected an array of three numbers"),
    ];
    for (body, expected) in cases {
        let p = write(
            dir.path(),
            "bad.toml",
            &format!("{CAMERA}[[mesh]]\npath = \"tri.obj\"\n[[material]]\nname = \"m\"\n{body}"),
        );
        assert_contains(&err_text(file::load(&p)), &["bad.toml:", expected]);
    }
}

#[test]
fn toml_exclude_without_match() {
    let dir = tri_dir();
    let p = write(dir.path(), "bad.toml", "[[mesh]]\npath = \"tri.obj\"\nexclude_materials = [\"glass\"]\n");
    assert_contains(&err_text(file::load(&p)), &["bad.toml:1", "mesh tri.obj", "no material named 'glass'"]);
    // Excluding a material that exists but is unused is fine.
    let p = write(dir.path(), "ok.toml", "[[mesh]]\npath = \"tri.obj\"\nexclude_materials = [\"other\"]\n");
    assert_eq!(file::load(&p).unwrap().triangle_count(), 1);
}

#[test]
fn toml_camera_needs_one_direction() {
    let dir = tri_dir();
    for cam in [
        "eye = [0, 0, 5]\nfov_y = 45",
        "eye = [0, 0, 5]\ntarget = [0, 0, 0]\ndirection = [0, 0, -1]\nfov_y = 45",
    ] {
        let p = write(dir.path(), "bad.toml", &format!("[[mesh]]\npath = \"tri.obj\"\n\n[camera]\n{cam}\n"));
        assert_contains(
            &err_text(file::load(&p)),
            &["bad.toml:4", "exactly one of 'target' and 'direction'"],
        );
    }
    let p = write(
        dir.path(),
        "nofov.toml",
        "[[mesh]]\npath = \"tri.obj\"\n[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n",
    );
    assert_contains(&err_text(file::load(&p)), &["nofov.toml", "fov_y"]);
}

#[test]
fn toml_without_meshes() {
    let dir = tri_dir();
    let p = write(dir.path(), "empty.toml", CAMERA);
    assert_contains(&err_text(file::load(&p)), &["empty.toml", "no [[mesh]]"]);
}

#[test]
fn scene_from_gltf_toml() {
    // glTF through a scene file, with a transform.
    let dir = tempfile::tempdir().unwrap();
    let engine = shared("gltf-samples/2CylinderEngine/glTF/2CylinderEngine.gltf");
    let p = write(
        dir.path(),
        "engine.toml",
        &format!("[[mesh]]\npath = {:?}\nscale = 0.001\n", engine.to_str().unwrap()),
    );
    let s: Scene = file::load(&p).unwrap();
    assert_eq!(s.triangle_count(), 121_496);
    let (lo, hi) = s.bounds().unwrap();
    assert!(((hi - lo).x - 0.7434).abs() < 1e-3, "{}", hi - lo);
    s.validate().unwrap();
}

/// Scene loading's errors are typed: the kind a caller can act on, the file at fault and its
/// line, whatever the format; the message still names them for people.
#[test]
fn scene_errors_give_kind_file_and_line() {
    use hyrt::scene::ErrorKind;
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.toml");
    let e = scene::load(missing.to_str().unwrap()).unwrap_err();
    assert_eq!((e.kind, e.file.as_deref(), e.line), (ErrorKind::Io, Some(missing.as_path()), None), "{e}");

    let bad = write(dir.path(), "bad.toml", "name = \"x\"\n[camera\n");
    let e = scene::load(bad.to_str().unwrap()).unwrap_err();
    assert_eq!((e.kind, e.file.as_deref(), e.line), (ErrorKind::Syntax, Some(bad.as_path()), Some(2)), "{e}");

    let obj = write(dir.path(), "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let invalid = write(
        dir.path(),
        "invalid.toml",
        &format!(
            "[[mesh]]\npath = \"{}\"\n\n[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\ndirection = [0, 0, -1]\nfov_y = 40\n",
            obj.file_name().unwrap().to_str().unwrap()
        ),
    );
    let e = scene::load(invalid.to_str().unwrap()).unwrap_err();
    assert_eq!(
        (e.kind, e.file.as_deref(), e.line),
        (ErrorKind::Invalid, Some(invalid.as_path()), Some(4)),
        "{e}"
    );
    assert!(e.to_string().contains("invalid.toml:4: [camera] needs exactly one"), "{e}");

    let nan = write(dir.path(), "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
    let e = scene::load(nan.to_str().unwrap()).unwrap_err();
    assert_eq!((e.kind, e.file.as_deref(), e.line), (ErrorKind::Syntax, Some(nan.as_path()), Some(3)), "{e}");

    let draco = shared("gltf-samples/Duck/glTF-Draco/Duck.gltf");
    let e = scene::load(draco.to_str().unwrap()).unwrap_err();
    assert_eq!((e.kind, e.file.as_deref()), (ErrorKind::Unsupported, Some(draco.as_path())), "{e}");

    let e = scene::load("no-such-scene").unwrap_err();
    assert_eq!((e.kind, e.file.as_deref()), (ErrorKind::UnknownScene, None), "{e}");
}
