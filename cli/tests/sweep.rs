//! `hyrt sweep` through the real binary: the files it writes and their agreement with each
//! other and with `hyrt compare`, the reference's VPLs, and bad knobs refused before anything
//! is written. Tiny images and one timed frame keep it fast.

mod common;

use std::{fs, path::Path};

use common::*;

fn read_text(p: &Path) -> String {
    fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&read_text(p)).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// A PSNR as the CSV or `hyrt compare --json` writes it (a number, or "inf").
fn psnr_of(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| {
        assert_eq!(v, "inf", "{v}");
        f64::INFINITY
    })
}

#[test]
fn two_by_two_sweep_writes_consistent_csv_json_png_and_images() {
    let d = out_dir("sweep_2x2");
    let out = d.join("out");
    let (ok, stdout, err) = hyrt(&[
        "sweep",
        "cornell",
        "--size",
        "64x48",
        "--runs",
        "1",
        "--knob",
        "shadow-map-res=64,256",
        "--knob",
        "bias=0.5,2",
        "--images",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(!err.contains("warning"), "{err}");
    // One summary line per configuration, and the table on stdout.
    assert!(
        err.contains("[1/4] shadow-map-res=64 bias=0.5:") && err.contains("[4/4] shadow-map-res=256 bias=2:"),
        "{err}"
    );
    assert!(
        stdout.contains("| shadow-map-res | bias | frame ms |") && stdout.contains("**reference**"),
        "{stdout}"
    );

    // CSV: the reference row first, then the 4 combinations, first knob slowest.
    let csv = read_text(&out.join("sweep.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let expected = [
        "config",
        "shadow-map-res",
        "bias",
        "frame_ms_median",
        "frame_ms_min",
        "frame_ms_max",
        "reference_ms_side_by_side",
        "speedup_vs_reference",
        "psnr_db",
        "flip_mean",
        "wrong_pixels",
        "wrong_pairs",
        "map_build_ms",
        "first_frame_ms",
        "map_mb",
        "light_map_mb",
        "shadow_rays",
        "vpl_shadow_rays",
        "total_rays",
        "pareto",
    ];
    assert_eq!(header, expected);
    assert_eq!(lines.len(), 1 + 1 + 4, "{csv}");
    let rows: Vec<Vec<&str>> = lines[1..].iter().map(|l| l.split(',').collect()).collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let num =
        |r: &[&str], name: &str| -> f64 { r[col(name)].parse().unwrap_or_else(|_| panic!("{name}: {r:?}")) };
    assert_eq!(rows[0][0], "reference");
    assert_eq!((rows[0][1], rows[0][2]), ("", ""));
    assert_eq!(num(&rows[0], "psnr_db"), f64::INFINITY);
    assert_eq!(num(&rows[0], "speedup_vs_reference"), 1.0);
    let knobs: Vec<(&str, &str)> = rows[1..].iter().map(|r| (r[1], r[2])).collect();
    assert_eq!(knobs, [("64", "0.5"), ("64", "2"), ("256", "0.5"), ("256", "2")]);
    for r in &rows[1..] {
        assert_eq!(r.len(), header.len());
        assert!(
            num(r, "frame_ms_min") <= num(r, "frame_ms_median")
                && num(r, "frame_ms_median") <= num(r, "frame_ms_max")
        );
        let psnr = num(r, "psnr_db");
        assert!(psnr > 20.0, "{r:?}");
        assert!((0.0..0.5).contains(&num(r, "flip_mean")), "{r:?}");
        assert!(num(r, "map_mb") > 0.0 && num(r, "wrong_pixels") <= num(r, "wrong_pairs"), "{r:?}");
        assert!(num(r, "shadow_rays") <= num(r, "total_rays"));
        // Against the reference's frames alternated with this configuration's.
        let speedup = num(r, "reference_ms_side_by_side") / num(r, "frame_ms_median");
        assert!((num(r, "speedup_vs_reference") / speedup - 1.0).abs() < 0.01, "{r:?}");
    }

    // The Pareto flags agree with a recomputation from the CSV's own numbers.
    let pts: Vec<(f64, f64)> =
        rows[1..].iter().map(|r| (num(r, "frame_ms_median"), num(r, "psnr_db"))).collect();
    for (i, r) in rows[1..].iter().enumerate() {
        let (t, q) = pts[i];
        let dominated = pts.iter().any(|&(t2, q2)| t2 <= t && q2 >= q && (t2 < t || q2 > q));
        assert_eq!(r[col("pareto")], (!dominated).to_string(), "row {r:?} in {pts:?}");
    }
    assert_eq!(rows[0][col("pareto")], "false");

    // Memory: the light maps alone (2^20 bytes) are part of all the maps (10^6 bytes); the
    // reference has none.
    assert_eq!((num(&rows[0], "light_map_mb"), num(&rows[0], "map_mb")), (0.0, 0.0));
    for r in &rows[1..] {
        let light = num(r, "light_map_mb");
        assert!(light > 0.0 && light * 1.048576 <= num(r, "map_mb") + 1e-3, "{r:?}");
    }

    // JSON: every configuration with its knobs, options and measurement.
    let j = json(&out.join("sweep.json"));
    assert_eq!(
        (j["scene"].as_str(), j["width"].as_u64(), j["runs"].as_u64()),
        (Some("cornell"), Some(64), Some(1))
    );
    assert_eq!(j["reference_flags"], serde_json::json!(["--preset", "reference"]));
    let configs = j["configs"].as_array().unwrap();
    assert_eq!(configs.len(), 4);
    for (c, r) in configs.iter().zip(&rows[1..]) {
        assert_eq!(c["knobs"]["shadow-map-res"], r[1]);
        assert_eq!(c["options"]["shadow_map_res"].as_u64().unwrap().to_string(), r[1]);
        assert_eq!(c["options"]["shadows"], "smerts");
        assert_eq!(c["pareto"].as_bool().unwrap().to_string(), r[col("pareto")]);
        let psnr = psnr_of(&c["measurement"]["psnr_db"]);
        assert!(psnr == num(r, "psnr_db") || (psnr - num(r, "psnr_db")).abs() <= 5e-4, "{psnr} vs {r:?}");

        // The image's PSNR by `hyrt compare` is the sweep's, exactly (EXR, exposure 1).
        let png = c["image"].as_str().unwrap();
        assert!(out.join(png).is_file(), "{png}");
        let exr = out.join(png.replace(".png", ".exr"));
        let (ok, cmp, err) = hyrt(&[
            "compare",
            out.join("images/reference.exr").to_str().unwrap(),
            exr.to_str().unwrap(),
            "--json",
        ]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(&cmp).unwrap();
        assert_eq!(psnr_of(&v["psnr_db"]), psnr, "{}", exr.display());
    }
    assert_eq!(j["reference"]["measurement"]["psnr_db"], "inf");
    // The CSV's first frame is the cold one: the renderer's creation (BVH build) and its first
    // frame, in wall time; the memory is the measurement's light maps.
    let measured = std::iter::once(&j["reference"]).chain(configs);
    for (c, r) in measured.map(|c| &c["measurement"]).zip(&rows) {
        let f = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{k}: {c}"));
        assert!((num(r, "first_frame_ms") - f("cold_first_frame_ms")).abs() <= 5e-4, "{r:?}");
        // The BVH is built before the frame, or (raster visibility) beside its first passes.
        let (cold, bvh, first) = (f("cold_first_frame_ms"), f("bvh_build_ms"), f("first_frame_ms"));
        assert!(cold >= first && cold >= bvh, "{c}");
        let mb = f("light_map_bytes") / f64::from(1 << 20);
        assert!((num(r, "light_map_mb") - mb).abs() <= 5e-4, "{r:?}");
    }

    // The plots decode; the README has the command line and the table.
    for png in ["sweep.png", "sweep-first-frame.png"] {
        let img = image::open(out.join(png)).unwrap();
        assert!(img.width() >= 800 && img.height() >= 500, "{png}");
    }
    let readme = read_text(&out.join("README.md"));
    assert!(readme.contains("hyrt sweep cornell --size 64x48"), "{readme}");
    assert!(readme.contains("| shadow-map-res | bias |") && readme.contains("**front**"), "{readme}");
    assert!(readme.contains("![PSNR against frame time"), "{readme}");
    assert!(readme.contains("(sweep-first-frame.png)") && readme.contains("| light map MB |"), "{readme}");
}

/// Both light-map layouts as a knob: each point has its first frame and its light maps'
/// memory.
#[test]
fn light_map_layouts_sweep_with_first_frame_and_memory() {
    let d = out_dir("sweep_layouts");
    let out = d.join("out");
    let (ok, _, err) = hyrt(&[
        "sweep",
        "cornell",
        "--size",
        "32x24",
        "--runs",
        "1",
        "--knob",
        "light-maps=whole,paged",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let csv = read_text(&out.join("sweep.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines[2..].iter().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.iter().map(|r| r[1]).collect::<Vec<_>>(), ["whole", "paged"], "{csv}");
    for r in &rows {
        let num = |name: &str| -> f64 { r[col(name)].parse().unwrap() };
        assert!(num("light_map_mb") > 0.0 && num("first_frame_ms") > 0.0, "{r:?}");
        assert!(num("first_frame_ms") >= num("map_build_ms"), "{r:?}");
    }
    assert!(out.join("sweep-first-frame.png").is_file());
}

/// Indirect light in the base flags: the reference gets the same VPLs, by rays, unless its
/// own flags choose.
#[test]
fn reference_gets_the_sweeps_vpls() {
    let d = out_dir("sweep_vpls");
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "sweep",
            "cornell",
            "--size",
            "32x24",
            "--runs",
            "1",
            "--base",
            "--preset hybrid --shadow-map-res 32 --vpls 3 --vpl-seed 2",
            "--knob",
            "vpl-map-res=16,32",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let (ok, _, err) = hyrt(&args);
        assert!(ok, "{err}");
        json(&out.join("sweep.json"))
    };
    let j = run(&d.join("a"), &[]);
    let flags: Vec<&str> =
        j["reference_flags"].as_array().unwrap().iter().map(|f| f.as_str().unwrap()).collect();
    assert_eq!(flags[..2], ["--preset", "reference"]);
    for f in ["--indirect=rays", "--vpls=3", "--vpl-bounces=1", "--vpl-seed=2", "--vpl-clamp=0.01"] {
        assert!(flags.contains(&f), "{f} missing from {flags:?}");
    }
    assert_eq!(j["reference"]["options"]["indirect"], "rays");
    assert_eq!(j["configs"][0]["options"]["indirect"], "maps");
    assert!(j["reference"]["measurement"]["rays"]["vpl_shadow"].as_u64().unwrap() > 0);

    let j = run(&d.join("b"), &["--reference", "--preset reference --indirect none"]);
    assert_eq!(j["reference_flags"], serde_json::json!(["--preset", "reference", "--indirect", "none"]));
    assert_eq!(j["reference"]["options"]["indirect"], "none");
}

/// Bad knobs fail before anything is rendered or written: a non-zero exit, a message naming
/// the knob, no panic, no output folder (and an existing one untouched).
#[test]
fn bad_knobs_fail_before_writing() {
    let d = out_dir("sweep_bad");
    let kept = d.join("kept");
    fs::create_dir_all(&kept).unwrap();
    fs::write(kept.join("sweep.csv"), "previous").unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (&["--knob", "colour=1,2"], &["unknown knob 'colour'", "shadow-map-res"]),
        (&["--knob", "bias"], &["--knob 'bias'", "NAME=V1,V2"]),
        (&["--knob", "bias="], &["knob 'bias'", "no values"]),
        (&["--knob", "bias=1,,2"], &["knob 'bias'", "empty"]),
        (
            &["--knob", "shadow-map-res=256,abc"],
            &["knob 'shadow-map-res', value 'abc'", "invalid value 'abc'"],
        ),
        (
            &["--knob", "shadow-map-res=64", "--knob", "bias=1,-2"],
            &["knob 'bias', value '-2'", "--bias must be"],
        ),
        (&["--knob", "check-visibility=true,false"], &["knob 'check-visibility'", "on/off"]),
        (&["--knob", "bias=1", "--base", "--preset hybrid --bias 2"], &["knob 'bias'", "--base"]),
        (&["--knob", "bias=1", "--base", "--preset hybrd"], &["--base", "hybrd"]),
        (&["--knob", "bias=1", "--reference", "--shadows ray"], &["--reference", "ray"]),
    ];
    for (i, (extra, expected)) in cases.iter().enumerate() {
        for out in [d.join(format!("new{i}")), kept.clone()] {
            let mut args =
                vec!["sweep", "cornell", "--size", "32x24", "--runs", "1", "--out", out.to_str().unwrap()];
            args.extend_from_slice(extra);
            let (ok, _, err) = hyrt(&args);
            assert!(!ok, "expected failure for {extra:?}");
            assert!(!err.contains("panicked"), "panic for {extra:?}: {err}");
            for e in *expected {
                assert!(err.contains(e), "message for {extra:?} should contain '{e}': {err}");
            }
        }
        assert!(!d.join(format!("new{i}")).exists(), "output folder created for {extra:?}");
        let names: Vec<_> = fs::read_dir(&kept).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["sweep.csv"], "files written for {extra:?}");
        assert_eq!(read_text(&kept.join("sweep.csv")), "previous");
    }
}
