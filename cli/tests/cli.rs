//! The real binary: determinism of output bytes, stats JSON, compare, and bad input.
//!
//! Every bad input must give a clear message naming the file (and line where the format has
//! lines), a non-zero exit, no panic, and must leave existing outputs untouched.

mod common;

use std::{fs, path::Path};

use common::*;

fn read(p: &Path) -> Vec<u8> {
    fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn one_and_two_threads_write_identical_png_and_exr() {
    let d = out_dir("threads");
    for n in ["1", "2"] {
        let png = d.join(format!("t{n}.png"));
        let exr = d.join(format!("t{n}.exr"));
        let (ok, _, err) = hyrt(&[
            "render",
            "cornell",
            "--size",
            "200x150",
            "--threads",
            n,
            "-q",
            "-o",
            png.to_str().unwrap(),
            "--exr",
            exr.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
    }
    assert!(read(&d.join("t1.png")) == read(&d.join("t2.png")), "PNG bytes differ");
    assert!(read(&d.join("t1.exr")) == read(&d.join("t2.exr")), "EXR bytes differ");
}

#[test]
fn stats_json_has_plan_rays_and_times() {
    let d = out_dir("stats");
    let stats = d.join("s.json");
    let (ok, _, err) = hyrt(&[
        "render",
        "cornell",
        "--size",
        "64x48",
        "-q",
        "--preset",
        "reference",
        "-o",
        d.join("c.png").to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_slice(&read(&stats)).unwrap();
    assert!(v.get("vs_reference").is_none(), "only with --vs-reference");
    assert!(v.get("first_frame").is_none(), "only with --vs-reference");
    assert!(v.get("light_map_bytes").is_none() && v.get("light_map_pages").is_none(), "no maps: {v}");
    assert_eq!(v["scene"], "cornell");
    assert_eq!(v["width"], 64);
    assert_eq!(v["height"], 48);
    assert_eq!(v["triangles"], 32);
    assert_eq!(v["rays"]["primary"], 64 * 48);
    let r = &v["rays"];
    let sum: u64 = ["primary", "shadow", "specular", "vpl_shadow", "vpl_path"]
        .iter()
        .map(|k| r[k].as_u64().unwrap())
        .sum();
    assert_eq!(r["total"].as_u64().unwrap(), sum);
    assert_eq!(r["vpl_shadow"], 0);
    let plan: Vec<&str> = v["plan"].as_array().unwrap().iter().map(|p| p.as_str().unwrap()).collect();
    assert_eq!(plan, ["bvh_build", "visibility", "direct", "specular"]);
    let skipped: Vec<&str> =
        v["plan_detail"]["skipped"].as_array().unwrap().iter().map(|p| p["pass"].as_str().unwrap()).collect();
    assert_eq!(skipped, ["map_build", "indirect"]);
    for k in ["total", "frame", "bvh_build", "visibility", "direct", "specular"] {
        assert!(v["time_ms"][k].as_f64().is_some_and(|t| t >= 0.0), "time_ms.{k} missing");
    }
}

#[test]
fn plan_is_printed() {
    let d = out_dir("plan");
    let (ok, _, err) =
        hyrt(&["render", "cornell", "--size", "32x32", "-o", d.join("c.png").to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(err.contains("run   specular") && err.contains("skip  indirect"), "{err}");
    let (ok, _, err) = hyrt(&[
        "render",
        "cornell",
        "--size",
        "32x32",
        "--max-depth",
        "0",
        "-o",
        d.join("c.png").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(err.contains("skip  specular      max_depth = 0"), "{err}");
}

#[test]
fn compare_reports_psnr_and_differences() {
    let d = out_dir("compare");
    let (a, b, small, exr) = (d.join("a.png"), d.join("b.png"), d.join("small.png"), d.join("a.exr"));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    assert!(hyrt(&["render", "cornell", "--size", "64x64", "-q", "-o", &s(&a), "--exr", &s(&exr)]).0);
    assert!(hyrt(&["render", "cornell", "--size", "64x64", "-q", "--max-depth", "0", "-o", &s(&b)]).0);
    assert!(hyrt(&["render", "cornell", "--size", "32x32", "-q", "-o", &s(&small)]).0);

    let (ok, out, _) = hyrt(&["compare", &s(&a), &s(&a)]);
    assert!(ok && out.contains("PSNR inf dB") && out.contains("0 of 4096 pixels differ"), "{out}");

    let (ok, out, _) = hyrt(&["compare", &s(&a), &s(&b), "--json"]);
    assert!(ok);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let psnr = v["psnr_db"].as_f64().unwrap();
    // Without reflections the mirror panel goes black: clearly different, not wildly so.
    assert!(psnr > 10.0 && psnr < 40.0, "psnr {psnr}");
    assert!(v["differing_pixels"].as_u64().unwrap() > 50);

    // The EXR through the display transform matches its own 8-bit PNG up to quantisation
    // (uniform error of at most half a step: PSNR above 20 log10(255 * 2) = 54 dB).
    let (ok, out, _) = hyrt(&["compare", &s(&a), &s(&exr), "--json"]);
    assert!(ok);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["psnr_db"].as_f64().unwrap() > 54.0, "{out}");

    let (ok, _, err) = hyrt(&["compare", &s(&a), &s(&small)]);
    assert!(!ok && err.contains("differ in size: 64x64 vs 32x32"), "{err}");
    assert!(!err.contains("panicked"));
}

/// Runs a render that must fail; checks the message, the absence of a panic, and that a
/// pre-existing output file is untouched and no temporary file is left behind.
fn assert_fails(dir: &Path, args: &[&str], expected: &[&str]) {
    let out = dir.join("out.png");
    fs::write(&out, b"previous output").unwrap();
    let mut full = vec!["render"];
    full.extend_from_slice(args);
    full.extend_from_slice(&["-o", out.to_str().unwrap()]);
    let (ok, _, err) = hyrt_in(dir, &full);
    assert!(!ok, "expected failure for {args:?}");
    assert!(!err.contains("panicked"), "panic for {args:?}: {err}");
    for e in expected {
        assert!(err.contains(e), "message for {args:?} should contain '{e}': {err}");
    }
    assert_eq!(fs::read(&out).unwrap(), b"previous output", "output was touched");
    let leftovers: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(".hyrt-"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

const CAMERA: &str = "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\n";

#[test]
fn bad_input_gives_clear_errors() {
    let d = out_dir("bad_input");
    let w = |name: &str, text: &str| fs::write(d.join(name), text).unwrap();

    assert_fails(&d, &["no_such_scene"], &["unknown scene 'no_such_scene'", "cornell"]);
    assert_fails(&d, &["missing.obj"], &["missing.obj"]);
    assert_fails(&d, &["missing.toml"], &["missing.toml"]);

    w("bad_vertex.obj", "v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n");
    assert_fails(&d, &["bad_vertex.obj"], &["bad_vertex.obj:3"]);

    w("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
    assert_fails(&d, &["nan.obj"], &["nan.obj", "NaN"]);

    w("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n");
    assert_fails(&d, &["inf.obj"], &["inf.obj"]);

    w("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    assert_fails(&d, &["bad_index.obj"], &["bad_index.obj:4"]);

    w("empty.obj", "# nothing\nv 0 0 0\n");
    assert_fails(&d, &["empty.obj"], &["empty.obj", "no triangles"]);

    w("with_mtl.obj", "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n");
    w("bad.mtl", "newmtl m\nKd 0.5 zz 0.5\n");
    assert_fails(&d, &["with_mtl.obj"], &["bad.mtl:2"]);

    w("bad.gltf", "{ this is not json");
    assert_fails(&d, &["bad.gltf"], &["bad.gltf"]);

    w("bad_syntax.toml", &format!("{CAMERA}\n[settings]\nwidth = = 3\n"));
    assert_fails(&d, &["bad_syntax.toml"], &["bad_syntax.toml", "line 7"]);

    w("unknown_key.toml", &format!("{CAMERA}colour = 3\n"));
    assert_fails(&d, &["unknown_key.toml"], &["unknown_key.toml", "colour"]);

    w("tri.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n");
    w("no_mesh.toml", &format!("{CAMERA}\n[[mesh]]\npath = \"nope.obj\"\n"));
    assert_fails(&d, &["no_mesh.toml"], &["no_mesh.toml", "nope.obj"]);

    w(
        "degenerate_camera.toml",
        "[camera]\neye = [1.0, 2.0, 3.0]\ntarget = [1.0, 2.0, 3.0]\nfov_y = 40.0\n\n[[mesh]]\npath = \"tri.obj\"\n",
    );
    assert_fails(&d, &["degenerate_camera.toml"], &["degenerate_camera.toml", "degenerate camera"]);

    w(
        "parallel_up.toml",
        "[camera]\neye = [0.0, 5.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 40.0\n\n[[mesh]]\npath = \"tri.obj\"\n",
    );
    assert_fails(&d, &["parallel_up.toml"], &["degenerate camera", "parallel"]);

    w(
        "zero_fov.toml",
        "[camera]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 0.0\n\n[[mesh]]\npath = \"tri.obj\"\n",
    );
    assert_fails(&d, &["zero_fov.toml"], &["degenerate camera", "field of view"]);

    assert_fails(&d, &["cornell", "--size", "0x10"], &["image size 0x10 is empty"]);
    assert_fails(&d, &["cornell", "--size", "12by10"], &["WxH"]);
    assert_fails(&d, &["cornell", "--threads", "0"], &["threads"]);
    assert_fails(&d, &["cornell", "--exr", "no/such/dir/x.exr"], &["no/such/dir/x.exr", "does not exist"]);
}

/// A bare mesh file without a camera gets an automatic camera and light that frame it: the
/// object fills a good part of the image and is lit. One with a camera (the Duck's glTF) is
/// seen through it, lit by a light beside it; `--camera` names a camera it does not have.
#[test]
fn bare_mesh_files_are_framed_and_lit() {
    let d = out_dir("bare_mesh");
    // The duck fills about a twentieth of its own camera's view.
    for (name, mesh, share) in
        [("duck", "gltf-samples/Duck/glTF-Binary/Duck.glb", 30), ("office", "radiance-office/office.obj", 10)]
    {
        let png = d.join(format!("{name}.png"));
        let path = shared_scene(mesh);
        let (ok, _, err) =
            hyrt(&["render", path.to_str().unwrap(), "--size", "64x48", "-q", "-o", png.to_str().unwrap()]);
        assert!(ok, "{name}: {err}");
        let img = hyrt::metrics::read_display_image(&png).unwrap();
        let lit = img.pixels.iter().filter(|p| p.max_element() > 0.05).count();
        assert!(lit > img.pixels.len() / share, "{name}: only {lit} of {} pixels lit", img.pixels.len());
    }
    let duck = shared_scene("gltf-samples/Duck/glTF-Binary/Duck.glb");
    let png = d.join("duck-1.png");
    let (ok, _, err) =
        hyrt(&["render", duck.to_str().unwrap(), "--camera", "1", "-o", png.to_str().unwrap()]);
    assert!(!ok && err.contains("no camera 1") && err.contains("0: camera 0"), "{err}");
    assert!(!png.exists());
}

#[test]
fn raster_visibility_from_the_cli() {
    let d = out_dir("raster_cli");
    let stats = d.join("s.json");
    let (ok, _, err) = hyrt(&[
        "render",
        "cornell",
        "--size",
        "64x48",
        "--visibility",
        "raster",
        "-o",
        d.join("c.png").to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(err.contains("run   visibility    raster: z-buffer of 32 triangles"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&read(&stats)).unwrap();
    // A primary ray only where a pixel's ray leaves its rasterized triangle (edges).
    assert!(v["rays"]["primary"].as_u64().unwrap() * 100 < 64 * 48, "{}", v["rays"]);
    assert_eq!(v["options"]["visibility"], "raster");
    for k in ["visibility", "vis_cull", "vis_raster", "vis_resolve"] {
        assert!(v["time_ms"][k].as_f64().is_some(), "time_ms.{k} missing");
    }
    // What the rasterizer processed: the built-in box's 32 triangles, some set up and binned.
    let raster = &v["raster"];
    assert_eq!(raster["submitted"], 32, "{raster}");
    let (set_up, tiny, bins) = (
        raster["set_up"].as_u64().unwrap(),
        raster["tiny"].as_u64().unwrap(),
        raster["bin_entries"].as_u64().unwrap(),
    );
    assert!((1..=32).contains(&set_up) && tiny <= set_up && bins >= set_up, "{raster}");
    let (ok, _, err) =
        hyrt(&["render", "cornell", "--visibility", "zbuffer", "-o", d.join("x.png").to_str().unwrap()]);
    assert!(!ok && err.contains("possible values: rays, raster"), "{err}");
}

/// `--preset hybrid` selects raster visibility and SMeRTS, explicit flags override it, the
/// stats carry the per-light decisions and the new passes, and bad knob values are refused
/// (with every light's map: `--map-horizon inf`).
#[test]
fn smerts_presets_and_knobs_from_the_cli() {
    let d = out_dir("smerts_cli");
    let (stats, png) = (d.join("s.json"), d.join("c.png"));
    let run = |extra: &[&str]| {
        let mut args =
            vec!["render", "cornell", "--size", "64x48", "-q", "--preset", "hybrid", "--map-horizon", "inf"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", png.to_str().unwrap(), "--stats", stats.to_str().unwrap()]);
        let (ok, _, err) = hyrt(&args);
        assert!(ok, "{err}");
        serde_json::from_slice::<serde_json::Value>(&read(&stats)).unwrap()
    };
    let v = run(&["--check-visibility"]);
    assert_eq!(
        (v["options"]["visibility"].as_str(), v["options"]["shadows"].as_str()),
        (Some("raster"), Some("smerts"))
    );
    // A primary ray only where a pixel's ray leaves its rasterized triangle (edges).
    assert!(v["rays"]["primary"].as_u64().unwrap() * 100 < 64 * 48, "{}", v["rays"]);
    let lights = v["shadow_lights"].as_array().unwrap();
    assert_eq!(lights.len(), 2);
    for l in lights {
        assert!(l["lit"].as_u64().unwrap() > 0 && l["wrong"].as_u64().is_some(), "{l}");
    }
    assert_eq!(v["maps_built"], 2);
    for k in ["map_build", "classify", "borders", "shadow_rays"] {
        assert!(v["time_ms"][k].as_f64().is_some(), "time_ms.{k} missing");
    }
    let r = &v["rays"];
    assert_eq!(
        r["shadow"].as_u64().unwrap(),
        r["shadow_hint_hits"].as_u64().unwrap() + r["shadow_traversals"].as_u64().unwrap()
    );

    // Explicit flags override the preset, one knob each.
    let v = run(&["--shadows", "rays"]);
    assert_eq!(
        (v["options"]["visibility"].as_str(), v["options"]["shadows"].as_str()),
        (Some("raster"), Some("rays"))
    );
    assert!(v["shadow_lights"].as_array().unwrap().is_empty());
    let v = run(&[
        "--shadow-map",
        "paraboloid",
        "--shadow-map-res",
        "256",
        "--bias",
        "2",
        "--borders",
        "both",
        "--dilate",
        "2",
        "--tess",
        "inf",
        "--mirror-shadows",
        "rays",
    ]);
    let o = &v["options"];
    assert_eq!(o["shadow_map"], "paraboloid");
    assert_eq!(o["shadow_map_res"], 256);
    assert_eq!(o["bias"], 2.0);
    assert_eq!((o["borders"].as_str(), o["dilate"].as_u64()), (Some("both"), Some(2)));
    assert_eq!((o["tess"].as_str(), o["mirror_shadows"].as_str()), (Some("inf"), Some("rays")));
    assert!(v["shadow_lights"][0]["faces_drawn"].as_u64().unwrap() <= 2);

    assert_fails(&d, &["--preset", "hybrid", "--bias", "-1"], &["--bias must be a finite number >= 0"]);
    assert_fails(&d, &["--preset", "hybrid", "--tess", "0"], &["--tess must be > 0"]);
    assert_fails(&d, &["--shadow-map-res", "0"], &["--shadow-map-res"]);
    assert_fails(&d, &["--borders", "edges"], &["possible values: laplacian, map-space, both"]);
}

/// A scene file's `[indirect]` table asks for VPLs: they are simulated (rays under the reference
/// preset, maps under the hybrid one) with the file's values, flags override them, and
/// `--indirect none` turns them off; a bad clamp names the file and line.
#[test]
fn scene_file_indirect_table_asks_for_vpls() {
    let d = out_dir("indirect_cli");
    let w = |name: &str, text: &str| fs::write(d.join(name), text).unwrap();
    // A floor and a wall, a light between them.
    w(
        "room.obj",
        "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nv -2 0 -2\nv 2 0 -2\nv 2 3 -2\nv -2 3 -2\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\n",
    );
    let scene = format!(
        "{CAMERA}\n[indirect]\nvpls = 12\nbounces = 2\nclamp = 0.02\n\n[[mesh]]\npath = \"room.obj\"\n\n[[light]]\nposition = [0.0, 1.0, 0.0]\nintensity = 2.0\n"
    );
    w("room.toml", &scene);
    let (stats, png) = (d.join("s.json"), d.join("r.png"));
    let run = |extra: &[&str]| {
        let mut args = vec!["render", "room.toml", "--size", "32x24", "-q"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", png.to_str().unwrap(), "--stats", stats.to_str().unwrap()]);
        let (ok, _, err) = hyrt_in(&d, &args);
        assert!(ok, "{err}");
        serde_json::from_slice::<serde_json::Value>(&read(&stats)).unwrap()
    };
    let v = run(&[]);
    assert_eq!(v["options"]["indirect"], "maps", "the hybrid (the default preset) uses VPL maps");
    assert_eq!(v["options"]["visibility"], "raster");
    let v = run(&["--preset", "reference"]);
    assert_eq!(v["options"]["indirect"], "rays");
    assert_eq!((v["options"]["vpls"].as_u64(), v["options"]["vpl_bounces"].as_u64()), (Some(12), Some(2)));
    assert!((v["options"]["vpl_clamp"].as_f64().unwrap() - 0.02).abs() < 1e-6);
    assert!(v["plan"].as_array().unwrap().iter().any(|p| p == "indirect"));
    assert!(v["vpls"].as_u64().unwrap() > 0 && v["rays"]["vpl_shadow"].as_u64().unwrap() > 0);

    let v = run(&["--preset", "hybrid", "--vpls", "20"]);
    assert_eq!((v["options"]["indirect"].as_str(), v["options"]["vpls"].as_u64()), (Some("maps"), Some(20)));
    assert_eq!(v["rays"]["vpl_shadow"], 0);
    assert!(v["vpl_map_bytes"].as_u64().unwrap() > 0);

    let v = run(&["--indirect", "none"]);
    assert_eq!(v["options"]["indirect"], "none");
    assert_eq!((v["vpls"].as_u64(), v["rays"]["vpl_path"].as_u64()), (Some(0), Some(0)));

    w("bad_clamp.toml", &scene.replace("clamp = 0.02", "clamp = -1.0"));
    assert_fails(&d, &["bad_clamp.toml"], &["bad_clamp.toml:", "clamp must be a finite number >= 0"]);
}

/// `hyrt plan`: the static plan names skipped effects; with `--frames`, the second frame of the
/// unchanged scene builds no map (counters from the JSON).
#[test]
fn plan_command_prints_plan_and_frame_decisions() {
    let (ok, out, err) = common::hyrt(&["plan", "cornell", "--max-depth", "0"]);
    assert!(ok, "{err}");
    assert!(out.contains("skip  specular") && out.contains("max_depth = 0"), "{out}");
    assert!(out.contains("skip  indirect"), "{out}");

    let (ok, out, err) =
        common::hyrt(&["plan", "cornell", "--preset", "hybrid", "--size", "48x36", "--frames", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2);
    assert_eq!(frames[0]["maps_built"], 2);
    assert_eq!(frames[1]["maps_built"], 0);
    assert!(frames[1]["rays"]["primary"].as_u64().unwrap() * 100 < 48 * 36, "{}", frames[1]["rays"]);
    assert!(
        frames[1]["decisions"].as_array().unwrap().iter().any(|d| d["what"] == "bvh" && d["run"] == false)
    );
    assert!(v["plan"]["run"].as_array().unwrap().iter().any(|d| d["pass"] == "classify"));

    let (ok, _, err) = common::hyrt(&["plan", "no-such-scene.toml"]);
    assert!(!ok && err.contains("no-such-scene.toml"), "{err}");
}

/// `hyrt plan --frames --orbit N`: N frames along the orbit, each at its own camera; after
/// the first, no light map is built whole, and the VPLs are reused.
#[test]
fn plan_along_the_orbit_shows_what_each_frame_reruns() {
    let args = ["plan", "cornell", "--preset", "hybrid", "--size", "48x36", "--vpls", "4", "--frames"];
    let (ok, out, err) = common::hyrt(&[&args[..], &["--orbit", "4", "--json"]].concat());
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 4);
    let eyes: Vec<_> = frames.iter().map(|f| f["eye"].to_string()).collect();
    assert!(eyes.windows(2).all(|w| w[0] != w[1]), "the camera moves: {eyes:?}");
    assert_eq!(frames[0]["maps_built"], 2);
    for f in &frames[1..] {
        let d = f["decisions"].as_array().unwrap();
        let reason = |what: &str| d.iter().find(|d| d["what"] == what).map(|d| d["reason"].to_string());
        assert!(reason("vpls").is_some_and(|r| r.contains("reused")), "{d:?}");
        for l in ["light 0", "light 1"] {
            let r = reason(l).unwrap();
            assert!(r.contains("reused") || r.contains("extended"), "{l}: {r}");
        }
        assert!(f["passes"].as_array().unwrap().iter().any(|p| p == "visibility"));
    }
    let (ok, out, err) = common::hyrt(&[&args[..], &["--orbit", "2"]].concat());
    assert!(ok, "{err}");
    assert!(out.contains("frame 2 (eye (") && out.contains("passes run: visibility"), "{out}");
    let (ok, _, err) = common::hyrt(&["plan", "cornell", "--orbit", "3"]);
    assert!(!ok && err.contains("--frames"), "--orbit needs --frames: {err}");
}

/// `hyrt bench` on the built-in scene: every table, one CSV row per configuration with its
/// flags, and the reference compared with itself is exact.
#[test]
fn bench_writes_the_thesis_tables() {
    let dir = common::out_dir("bench");
    let out = dir.to_str().unwrap();
    let (ok, stdout, err) =
        common::hyrt(&["bench", "cornell", "--size", "40x30", "--runs", "1", "--vpls", "4", "--out", out]);
    assert!(ok, "{err}");
    for t in ["Table 4.1", "Table 4.2", "Table 4.4", "Table 4.5"] {
        assert!(stdout.contains(t), "{t} missing: {stdout}");
    }
    let md = std::fs::read_to_string(dir.join("tables.md")).unwrap();
    assert_eq!(md.trim(), stdout.trim());
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[0].starts_with("scene,config,flags,fps_mean,frame_ms_median"), "{}", rows[0]);
    assert_eq!(rows.len(), 1 + 7, "{csv}");
    let col = |name: &str| rows[0].split(',').position(|c| c == name).unwrap();
    let rt: Vec<&str> = rows[1].split(',').collect();
    assert_eq!((rt[1], rt[col("psnr_db")]), ("rt", "inf"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).unwrap()).unwrap();
    let configs = v["scenes"][0]["configs"].as_array().unwrap();
    assert_eq!(configs.len(), 7);
    // Map-based shadows have a wrong-visibility count; the reference has none.
    assert!(configs.iter().any(|c| c["label"] == "smerts-cube" && c["wrong_pixels"].is_u64()));
    // The time per pass: a row per configuration, each cell the JSON's median.
    let table: Vec<&str> = md.split("### Time per pass").nth(1).expect("per-pass table").lines().collect();
    let header: Vec<&str> = table.iter().find(|l| l.starts_with("| scene")).unwrap().split(" | ").collect();
    let rows: Vec<&&str> = table.iter().filter(|l| l.starts_with("| cornell")).collect();
    assert_eq!(rows.len(), 7);
    let smerts: Vec<&str> = rows.iter().find(|l| l.contains("`smerts-cube`")).unwrap().split(" | ").collect();
    let c = configs.iter().find(|c| c["label"] == "smerts-cube").unwrap();
    for pass in ["classify", "borders", "shadow_rays"] {
        let k = header.iter().position(|h| h.trim() == pass).unwrap_or_else(|| panic!("{pass}: {header:?}"));
        assert_eq!(smerts[k].trim(), format!("{:.1}", c["pass_ms"][pass].as_f64().unwrap()), "{pass}");
    }
    assert!(configs.iter().any(|c| c["label"] == "rt" && c["wrong_pixels"].is_null()));
    // Cost per unit: SMeRTS's map decisions, and the classify pass's CPU ns per decision (its
    // median times the threads over the decisions).
    let unit: Vec<&str> = md
        .split("### Cost per unit")
        .nth(1)
        .expect("cost-per-unit table")
        .lines()
        .find(|l| l.starts_with("| cornell"))
        .unwrap()
        .split(" | ")
        .collect();
    let decisions = c["map_decisions"].as_u64().unwrap();
    assert!(decisions > 0);
    assert_eq!(unit[1].trim().replace(',', ""), decisions.to_string());
    let ns =
        c["pass_ms"]["classify"].as_f64().unwrap() * 1e6 * v["threads"].as_f64().unwrap() / decisions as f64;
    assert_eq!(unit[2].trim(), format!("{ns:.1}"));
    // Of those, the share the tile test decided.
    let by_tile = c["map_decisions_by_tile"].as_u64().unwrap();
    assert!(by_tile > 0 && by_tile < decisions, "{by_tile} of {decisions}");
    assert_eq!(unit[3].trim(), format!("{:.1} %", 100.0 * by_tile as f64 / decisions as f64));
    // Border rays: the camera hits' pairs a ray decided (not the mirror hits' rays), over the
    // shadow-ray pass.
    let border = c["border_rays"].as_u64().unwrap();
    assert!(border > 0 && border <= c["rays"]["shadow"].as_u64().unwrap(), "{border}");
    assert_eq!(unit[4].trim().replace(',', ""), border.to_string());
    let ns =
        c["pass_ms"]["shadow_rays"].as_f64().unwrap() * 1e6 * v["threads"].as_f64().unwrap() / border as f64;
    assert_eq!(unit[5].trim(), format!("{ns:.0}"));

    let (ok, _, err) = common::hyrt(&["bench", "missing-scene.toml", "--out", out]);
    assert!(!ok && err.contains("missing-scene.toml"), "{err}");
}

/// A failed run leaves every existing output as it was, and refuses before rendering: an
/// output that is a directory (for any of `-o`, `--exr`, `--stats`) and one file named for two
/// outputs are errors, and no temporary file is left behind.
#[test]
fn failed_runs_keep_existing_outputs() {
    let d = out_dir("outputs_kept");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let (png, exr, stats, sub) =
        (d.join("old.png"), d.join("old.exr"), d.join("old.json"), d.join("somedir"));
    fs::create_dir(&sub).unwrap();
    for p in [&png, &exr, &stats] {
        fs::write(p, b"precious").unwrap();
    }
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["-o".into(), s(&png), "--exr".into(), s(&sub)], "it is a directory"),
        (vec!["-o".into(), s(&png), "--exr".into(), s(&exr), "--stats".into(), s(&sub)], "it is a directory"),
        (vec!["-o".into(), s(&sub)], "it is a directory"),
        (vec!["-o".into(), s(&png), "--exr".into(), s(&png)], "the same file is given for two outputs"),
        (vec!["-o".into(), s(&png), "--stats".into(), s(&d.join(".").join("old.png"))], "the same file"),
        (vec!["-o".into(), s(&png), "--exr".into(), s(&d.join("missing/x.exr"))], "does not exist"),
    ];
    for (outputs, expected) in cases {
        let mut args = vec!["render", "cornell", "--size", "16x16", "-q"];
        args.extend(outputs.iter().map(String::as_str));
        let (ok, _, err) = hyrt(&args);
        assert!(!ok, "{args:?} succeeded");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        for p in [&png, &exr, &stats] {
            assert_eq!(read(p), b"precious", "{args:?} changed {}", p.display());
        }
    }
    let left: Vec<_> = fs::read_dir(&d).unwrap().flatten().map(|e| e.file_name()).collect();
    assert_eq!(left.len(), 4, "temporaries left behind: {left:?}");
}

/// A render stopped by SIGTERM while it writes leaves no temporary file (and the old output).
#[cfg(unix)]
#[test]
fn a_terminated_render_leaves_no_temporaries() {
    let d = out_dir("terminated");
    let png = d.join("big.png");
    fs::write(&png, b"precious").unwrap();
    let exr = d.join("big.exr");
    // Large enough that the EXR takes a while to write; killed once its temporary exists.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_hyrt"))
        .args(["render", "cornell", "--size", "3000x3000", "--max-depth", "0", "-q", "-o"])
        .arg(&png)
        .arg("--exr")
        .arg(&exr)
        .spawn()
        .unwrap();
    let temporary =
        || fs::read_dir(&d).unwrap().flatten().any(|e| e.file_name().to_string_lossy().starts_with(".hyrt-"));
    let start = std::time::Instant::now();
    while !temporary() && child.try_wait().unwrap().is_none() && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(temporary(), "no temporary output seen while the render ran");
    // SIGTERM, by the shell's built-in `kill` (no kill binary needed).
    let sent = std::process::Command::new("sh").args(["-c", &format!("kill -TERM {}", child.id())]).status();
    assert!(sent.is_ok_and(|s| s.success()) || child.try_wait().unwrap().is_some(), "kill failed");
    let status = child.wait().unwrap();
    assert!(!temporary(), "a temporary was left behind ({status})");
    if !status.success() {
        assert_eq!(read(&png), b"precious", "a terminated run replaced the old output");
    }
}

/// `hyrt bench --orbit N` renders N frames per configuration along the arc and writes a row
/// per configuration (the frames after the first) and a CSV row per frame, and not the
/// thesis tables.
#[test]
fn bench_orbit_writes_frame_times_along_the_path() {
    let dir = common::out_dir("bench-orbit");
    let out = dir.to_str().unwrap();
    let (ok, stdout, err) =
        common::hyrt(&["bench", "cornell", "--size", "40x30", "--orbit", "4", "--out", out]);
    assert!(ok, "{err}");
    let md = std::fs::read_to_string(dir.join("orbit.md")).unwrap();
    assert_eq!(md.trim(), stdout.trim());
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| cornell")).collect();
    assert_eq!(rows.len(), 2, "{md}");
    assert!(rows[0].contains("`rt`") && rows[1].contains("`smerts-cube`"));
    // Frames after the first: 3 each.
    assert!(rows.iter().all(|r| r.split(" | ").nth(2) == Some("3")), "{md}");
    let csv = std::fs::read_to_string(dir.join("orbit.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 4, "{csv}");
    // The reference draws no maps at all.
    assert!(csv.lines().filter(|l| l.contains(",rt,")).all(|l| l.ends_with(",0")), "{csv}");
    assert!(!std::path::Path::new(out).join("tables.md").exists());
}

/// `hyrt bench --scaling` times every pass of both configurations on 1 thread and on
/// `--threads`, and writes a row per pass: each pass the frame ran, and the whole frame, with
/// its two medians and their ratio; not the thesis tables.
#[test]
fn bench_scaling_writes_each_pass_at_both_thread_counts() {
    let dir = common::out_dir("bench-scaling");
    let out = dir.to_str().unwrap();
    let (ok, stdout, err) = common::hyrt(&[
        "bench",
        "cornell",
        "--size",
        "40x30",
        "--scaling",
        "--runs",
        "2",
        "--threads",
        "2",
        "--out",
        out,
    ]);
    assert!(ok, "{err}");
    let md = std::fs::read_to_string(dir.join("scaling.md")).unwrap();
    assert_eq!(md.trim(), stdout.trim());
    let csv = std::fs::read_to_string(dir.join("scaling.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    let passes =
        |config: &str| -> Vec<&str> { rows.iter().filter(|r| r[1] == config).map(|r| r[2]).collect() };
    for (config, has, lacks) in
        [("rt", ["direct", "frame"], "classify"), ("smerts-cube", ["classify", "frame"], "direct")]
    {
        let p = passes(config);
        assert!(has.iter().all(|h| p.contains(h)) && !p.contains(&lacks), "{config}: {p:?}");
    }
    for r in &rows {
        assert_eq!(r[3], "2", "{r:?}");
        let (one, two, up): (f64, f64, f64) =
            (r[4].parse().unwrap(), r[5].parse().unwrap(), r[6].parse().unwrap());
        assert!(one >= 0.0 && two >= 0.0, "{r:?}");
        // Up to the CSV's rounding of each figure to 3 decimals.
        if one > 0.01 && two > 0.01 {
            let slack = up * (5e-4 / one + 5e-4 / two) + 1e-3;
            assert!((up - one / two).abs() <= slack, "speed-up is the ratio: {r:?}");
        }
    }
    assert_eq!(md.lines().filter(|l| l.starts_with("| cornell")).count(), rows.len());
    assert!(!std::path::Path::new(out).join("tables.md").exists());
    let (ok, _, err) = common::hyrt(&["bench", "cornell", "--scaling", "--orbit", "3"]);
    assert!(!ok && err.contains("cannot be used with"), "{err}");
}

/// `docs/cli.md`'s knob table is the one `hyrt::options` makes (flags, values, both presets'
/// defaults): a knob or default changed in code changes it. `UPDATE_DOCS=1` rewrites it.
#[test]
fn knob_table_in_docs_is_current() {
    let path = root().join("docs/cli.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let (start, end) = ("<!-- knobs: generated -->\n", "<!-- /knobs -->");
    let a = doc.find(start).expect("the table's start marker") + start.len();
    let b = doc.find(end).expect("the table's end marker");
    let table = hyrt::options::markdown_table();
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(&path, format!("{}{table}{}", &doc[..a], &doc[b..])).unwrap();
        return;
    }
    assert!(
        doc[a..b] == table,
        "docs/cli.md's knob table is stale: UPDATE_DOCS=1 cargo test --release -p hyrt-cli --test cli knob_table"
    );
}

/// The numbers of `hyrt render --vs-reference`'s line
/// `first frame: hybrid X ms (maps Y ms) vs reference Z ms (Rx)` (R possibly followed by a
/// comma and words): `[X, Y, Z, R]`, or `None` if the line is not of that form.
fn first_frame_numbers(line: &str) -> Option<[f64; 4]> {
    let w: Vec<&str> = line.strip_prefix("first frame: hybrid ")?.split_whitespace().collect();
    if w.len() < 10 || (w[1], w[2], w[4], w[5], w[6], w[8]) != ("ms", "(maps", "ms)", "vs", "reference", "ms")
    {
        return None;
    }
    let ratio = w[9].strip_prefix('(')?.trim_end_matches([')', ',']).strip_suffix('x')?;
    if w.len() == 10 && !w[9].ends_with(')') {
        return None;
    }
    Some([w[0].parse().ok()?, w[3].parse().ok()?, w[7].parse().ok()?, ratio.parse().ok()?])
}

/// `hyrt render` renders one image: a light map must pay for itself within it (`--map-horizon`
/// 1, unless given); each light's decision says which it got and why.
#[test]
fn one_image_renders_give_maps_only_where_they_pay_in_it() {
    let d = out_dir("one_image");
    let (png, stats) = (d.join("c.png"), d.join("s.json"));
    for (extra, horizon) in
        [(&[][..], serde_json::json!(1.0)), (&["--map-horizon", "inf"][..], serde_json::json!("inf"))]
    {
        let args = ["render", "cornell", "--size", "64x48", "-q", "-o", png.to_str().unwrap(), "--stats"];
        let (ok, _, err) = hyrt(&[&args[..], &[stats.to_str().unwrap()], extra].concat());
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_slice(&read(&stats)).unwrap();
        assert_eq!(v["options"]["map_horizon"], horizon, "{extra:?}");
        let lights: Vec<&serde_json::Value> = v["frame_decisions"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| d["what"].as_str().unwrap().starts_with("light"))
            .collect();
        assert_eq!(lights.len(), 2, "{v}");
        for d in lights {
            let r = d["reason"].as_str().unwrap();
            // The tiny test box's maps do not pay in one frame; with an infinite horizon
            // every light gets its map.
            let want = if extra.is_empty() { "no map, shadow rays: " } else { "map built: " };
            assert!(r.starts_with(want), "{extra:?}: {r}");
        }
    }
}

/// `hyrt render` without a preset renders the hybrid; `--vs-reference` also renders the
/// reference and reports the speed-up and the PSNR, and the first frame of each on a fresh
/// renderer, on the terminal and in the stats; the stats total the light maps (with every
/// light's map: `--map-horizon inf`).
#[test]
fn render_defaults_to_the_hybrid_and_compares_with_the_reference() {
    let d = out_dir("vs_reference");
    let (png, stats) = (d.join("c.png"), d.join("s.json"));
    let args = [
        "render",
        "cornell",
        "--size",
        "64x48",
        "--vs-reference",
        "--map-horizon",
        "inf",
        "-o",
        png.to_str().unwrap(),
    ];
    let (ok, _, err) = hyrt(&[&args[..], &["--stats", stats.to_str().unwrap()]].concat());
    assert!(ok, "{err}");
    assert!(err.contains("vs the reference: ") && err.contains("faster, PSNR "), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&read(&stats)).unwrap();
    assert_eq!(v["options"]["visibility"], "raster");
    assert_eq!(v["options"]["shadows"], "smerts");
    let vs = &v["vs_reference"];
    let (r, h) = (vs["reference_ms"].as_f64().unwrap(), vs["hybrid_ms"].as_f64().unwrap());
    assert!(r > 0.0 && h > 0.0 && (vs["speedup"].as_f64().unwrap() - r / h).abs() < 1e-9, "{vs}");
    assert!(vs["psnr_db"] == "inf" || vs["psnr_db"].as_f64().unwrap() > 30.0, "{vs}");
    // The cold first frames: one line with their numbers, the same as the stats'.
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("first frame:")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    let [x, y, z, ratio] = first_frame_numbers(lines[0]).unwrap_or_else(|| panic!("{}", lines[0]));
    let first = &v["first_frame"];
    let num = |k: &str| first[k].as_f64().unwrap_or_else(|| panic!("first_frame.{k}: {first}"));
    let (fh, fm, fr) = (num("hybrid_ms"), num("hybrid_maps_ms"), num("reference_ms"));
    assert!(fh > 0.0 && fr > 0.0 && (0.0..=fh).contains(&fm), "{first}");
    for (printed, exact) in [(x, fh), (y, fm), (z, fr)] {
        assert!((printed - exact).abs() <= 0.05 + 1e-9, "{} against {first}", lines[0]);
    }
    assert!((ratio - fr / fh).abs() <= 0.005 + 1e-9, "{} against {first}", lines[0]);
    assert_eq!(lines[0].contains("slower"), fr < fh, "{}", lines[0]);
    // The light maps, summed over the lights; the first frame drew every page it holds.
    let total = |k: &str| v[k].as_u64().unwrap_or_else(|| panic!("{k} missing"));
    let lights = v["shadow_lights"].as_array().unwrap();
    let sum = |k: &str| lights.iter().map(|l| l[k].as_u64().unwrap()).sum::<u64>();
    assert!(total("light_map_bytes") > 0 && total("light_map_pages") > 0, "{v}");
    assert_eq!(total("light_map_bytes"), sum("map_bytes"));
    assert_eq!(total("light_map_pages"), sum("pages_held"));
    assert_eq!(total("light_map_pages_drawn"), total("light_map_pages"));
    // The image written is the hybrid's, as without the flag.
    let (ok, _, err) =
        hyrt(&["render", "cornell", "--size", "64x48", "-q", "-o", d.join("plain.png").to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(read(&png) == read(&d.join("plain.png")), "--vs-reference changed the image");
    // The reference preset against itself is exact.
    let (ok, _, err) = hyrt(&[
        "render",
        "cornell",
        "--size",
        "32x24",
        "--preset",
        "reference",
        "--vs-reference",
        "-o",
        d.join("r.png").to_str().unwrap(),
    ]);
    assert!(ok && err.contains("PSNR inf dB (identical)"), "{err}");
}
