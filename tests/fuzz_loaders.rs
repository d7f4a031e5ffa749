//! Loader fuzzing: random bytes and mutated OBJ, MTL, glTF and TOML files must load or fail
//! with an error, never panic; a scene that loads also renders (8 x 8, reference and hybrid)
//! without a panic.
//!
//! Bounded for CI: `FUZZ_CASES` cases per target (default 96; proptest's own `PROPTEST_CASES` is
//! not read, so that the suite's time is fixed here), deterministic (proptest's default seed
//! unless `PROPTEST_RNG_SEED` is set). Run longer by hand: `FUZZ_CASES=20000 cargo test
//! --release --test fuzz_loaders`.

use std::path::Path;

use base64::Engine;
use hyrt::render::{Indirect, Options, Renderer};
use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, TestRunner};

const OBJ: &str = "mtllib m.mtl\n\
    v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 -0.5\n\
    vn 0 0 1\nvn 0 1 0\nvt 0 0\nvt 1 0\n\
    o part\ng grp\nusemtl a\n\
    f 1/1/1 2/2/1 3/1/1\nf 1//2 3//2 4//2\n\
    usemtl b\nf -1 -2 -3\nf 2 5 3 4\n";

const MTL: &str = "newmtl a\nKd 0.5 0.4 0.3\nKs 0.2 0.2 0.2\nNs 40\nillum 2\n\
    newmtl b\nKd 0 0 0\nKs 1 1 1\nillum 3\n";

const TOML: &str = "name = \"fuzz\"\n\
    [camera]\neye = [0.5, 0.5, 3.0]\ntarget = [0.3, 0.3, 0.0]\nfov_y = 40.0\n\
    [settings]\nwidth = 8\nheight = 8\nmax_depth = 3\n\
    [indirect]\nvpls = 4\nbounces = 1\n\
    [[mesh]]\npath = \"m.obj\"\nscale = 1.5\nrotate = [0.0, 30.0, 0.0]\n\
    [[mesh]]\npath = \"t.gltf\"\ntranslate = [0.0, 0.0, -1.0]\n\
    [[material]]\nname = \"a\"\ndiffuse = [0.5, 0.5, 0.5]\nhighlight = 0.1\nshininess = 20\n\
    [[light]]\nposition = [0.2, 0.2, 2.0]\nintensity = 3.0\n";

/// A one-triangle glTF with its buffer inline (positions, then u16 indices).
fn gltf() -> String {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend(i.to_le_bytes());
    }
    let data = base64::engine::general_purpose::STANDARD.encode(&bin);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[0.1,0.2,0.0],"scale":[1.0,2.0,1.0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.7,0.6,1.0],"metallicFactor":1.0,"roughnessFactor":0.1}}}}],
"buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{data}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        len = bin.len()
    )
}

/// Tokens that loaders find hard: non-finite and huge numbers, separators, structure.
const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "1e-45",
    "0",
    "-0",
    "-1",
    "4294967296",
    "99999999999999999999",
    " ",
    "/",
    "//",
    "\n",
    "\r\n",
    "#",
    "\"",
    "'",
    "{",
    "}",
    "[",
    "]",
    ",",
    "=",
    ":",
    ".",
    "\u{0}",
    "é",
    "f 1 2 3\n",
    "f 1 1 1\n",
    "f 0 0 0\n",
    "v 1e38 1e38 1e38\n",
    "v nan 0 0\n",
    "vn 0 0 0\n",
    "usemtl x\n",
    "mtllib m.mtl\n",
    "mtllib missing.mtl\n",
    "illum 9\n",
    "Ns -3\n",
    "Kd -1 2 nan\n",
    "[[mesh]]\n",
    "[[light]]\n",
    "path = \"m.obj\"\n",
    "path = \"/\"\n",
    "vpls = 100000000\n",
    "width = 0\n",
    "fov_y = 180\n",
    "\"count\":4294967295",
    "\"byteOffset\":-1",
    "\"uri\":\"x.bin\"",
];

/// One edit of a file: where (a fraction of its length), what, and with which bytes.
#[derive(Clone, Debug)]
enum Edit {
    Delete(f64, usize),
    Insert(f64, Vec<u8>),
    Token(f64, usize),
    Flip(f64, u8),
    DuplicateLine(f64),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (0.0..1.0f64, 1..16usize).prop_map(|(a, n)| Edit::Delete(a, n)),
        (0.0..1.0f64, proptest::collection::vec(any::<u8>(), 1..8)).prop_map(|(a, b)| Edit::Insert(a, b)),
        (0.0..1.0f64, 0..TOKENS.len()).prop_map(|(a, t)| Edit::Token(a, t)),
        (0.0..1.0f64, any::<u8>()).prop_map(|(a, b)| Edit::Flip(a, b)),
        (0.0..1.0f64).prop_map(Edit::DuplicateLine),
    ]
}

fn apply(seed: &str, edits: &[Edit]) -> Vec<u8> {
    let mut b = seed.as_bytes().to_vec();
    for e in edits {
        let at = |a: f64, len: usize| ((a * len as f64) as usize).min(len);
        match e {
            Edit::Delete(a, n) => {
                let i = at(*a, b.len());
                let j = (i + n).min(b.len());
                b.drain(i..j);
            }
            Edit::Insert(a, bytes) => {
                let i = at(*a, b.len());
                b.splice(i..i, bytes.iter().copied());
            }
            Edit::Token(a, t) => {
                let i = at(*a, b.len());
                b.splice(i..i, TOKENS[*t].bytes());
            }
            Edit::Flip(a, x) => {
                if !b.is_empty() {
                    let i = at(*a, b.len() - 1);
                    b[i] ^= x;
                }
            }
            Edit::DuplicateLine(a) => {
                let i = at(*a, b.len());
                let start = b[..i].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
                let end = b[i..].iter().position(|&c| c == b'\n').map_or(b.len(), |p| i + p + 1);
                let line = b[start..end].to_vec();
                b.splice(end..end, line);
            }
        }
    }
    b
}

/// Writes the four seed files into `dir`, with `name` replaced by `bytes`.
fn write_files(dir: &Path, name: &str, bytes: &[u8]) {
    let g = gltf();
    for (n, seed) in [("m.obj", OBJ), ("m.mtl", MTL), ("scene.toml", TOML), ("t.gltf", g.as_str())] {
        let content = if n == name { bytes } else { seed.as_bytes() };
        std::fs::write(dir.join(n), content).unwrap();
    }
}

/// Loads `spec` and, if it loads, renders a few pixels of it both ways; panics propagate.
fn load_and_render(spec: &Path) {
    let Ok(mut scene) = hyrt::scene::load(spec.to_str().unwrap()) else { return };
    scene.settings.width = 8;
    scene.settings.height = 8;
    scene.settings.max_depth = scene.settings.max_depth.min(4);
    if let Some(ind) = scene.indirect.as_mut() {
        ind.vpls = ind.vpls.min(8);
        ind.bounces = ind.bounces.min(2);
    }
    for (mut options, indirect) in
        [(Options::reference(), Indirect::Rays), (Options::hybrid(), Indirect::Maps)]
    {
        options.shadow.map.resolution = 16;
        options.indirect_opts.map.resolution = 16;
        if let Some(ind) = scene.indirect {
            options.indirect = indirect;
            options.indirect_opts.vpl.paths = ind.vpls;
            options.indirect_opts.vpl.bounces = ind.bounces;
        }
        let _ = Renderer::new(&scene, options).render(&|| {});
    }
}

fn runner() -> TestRunner {
    let cases = std::env::var("FUZZ_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(96);
    TestRunner::new(Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..Config::default()
    })
}

/// Mutates the file `name` of the scene and loads `spec` (the scene file or the mesh itself).
fn fuzz_file(name: &str, spec: &str) {
    let seed = match name {
        "m.obj" => OBJ.to_string(),
        "m.mtl" => MTL.to_string(),
        "scene.toml" => TOML.to_string(),
        _ => gltf(),
    };
    let dir = tempfile::tempdir().unwrap();
    // The unmutated files load: the mutations start from a working scene.
    write_files(dir.path(), name, seed.as_bytes());
    hyrt::scene::load(dir.path().join(spec).to_str().unwrap()).unwrap_or_else(|e| panic!("seed: {e:#}"));
    runner()
        .run(&proptest::collection::vec(edit(), 1..6), |edits| {
            write_files(dir.path(), name, &apply(&seed, &edits));
            load_and_render(&dir.path().join(spec));
            Ok(())
        })
        .unwrap();
    runner()
        .run(&proptest::collection::vec(any::<u8>(), 0..512), |bytes| {
            write_files(dir.path(), name, &bytes);
            load_and_render(&dir.path().join(spec));
            Ok(())
        })
        .unwrap();
}

#[test]
fn mutated_obj_files_never_panic() {
    fuzz_file("m.obj", "m.obj");
}

#[test]
fn mutated_mtl_files_never_panic() {
    fuzz_file("m.mtl", "m.obj");
}

#[test]
fn mutated_gltf_files_never_panic() {
    fuzz_file("t.gltf", "t.gltf");
}

#[test]
fn mutated_scene_files_never_panic() {
    fuzz_file("scene.toml", "scene.toml");
}
