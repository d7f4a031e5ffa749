//! OBJ + MTL loading via tobj (also gzip-compressed `.obj.gz`).
//!
//! tobj does the parsing, but its errors carry no line number. So when tobj fails, or the loaded
//! data holds a NaN or infinite coordinate, a small scanner re-reads the text to find the
//! offending line; on well-formed files the scanner never runs. Material libraries are small, so
//! they are always checked (and normalised) line by line before tobj sees them: this also keeps
//! tobj away from inputs it would panic on (a `Kd` line with fewer than three numbers).

use std::cell::RefCell;
use std::fmt::Write as _;
use std::io::Read;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use glam::{Vec2, Vec3};

use super::cutout::{Channel, Cutout, Mask};
use super::texture::{Texture, load_image};
use super::{ErrorKind, Material, MeshData, MeshRange, SceneError};

/// Diffuse colour for materials without `Kd` and for faces without a material.
const DEFAULT_KD: Vec3 = Vec3::splat(0.8);

/// Name of the material given to faces that have none (or name one the MTL lacks).
const DEFAULT_MATERIAL: &str = "default";

/// Loads an OBJ file (or `.obj.gz`) with its MTL materials.
///
/// Faces are triangulated as fans; points and lines are ignored. Each object or group (and each
/// material change within one) becomes a [`MeshRange`]. `mtllib` paths are resolved relative to
/// the OBJ file's directory. Faces without a usable material get a grey diffuse material named
/// `"default"`. Texture coordinates (`vt`, v flipped to count rows from the top), `map_Kd`
/// textures and `map_d` alpha maps (cut-outs: `super::cutout`), relative to their MTL file, are
/// read; an image that cannot be read is a warning in [`MeshData::warnings`].
///
/// Errors name the file and, where possible, the line: `office.obj:17: malformed vertex
/// 'v 1.0 abc 2.0'`.
pub fn load(path: &Path) -> Result<MeshData> {
    let text = read_text(path)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    // The struct update keeps this compiling if tobj's optional features (which add fields) get
    // enabled elsewhere in the dependency graph.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };

    // tobj only passes a bare `LoadError` through the material loader, so the real (line-numbered)
    // MTL error is kept here and reported in preference to whatever tobj makes of it.
    let mtl_error: RefCell<Option<anyhow::Error>> = RefCell::new(None);
    // tobj does unchecked index arithmetic on face indices (overflow panics in debug builds);
    // a panic is turned into an ordinary error located by the scanner.
    let parsed = catch_unwind(AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut text.as_bytes(), &options, |mtl: &Path| {
            load_mtllib(path, &text, dir, mtl).unwrap_or_else(|e| {
                let mut slot = mtl_error.borrow_mut();
                if slot.is_none() {
                    *slot = Some(e);
                }
                Err(tobj::LoadError::OpenFileFailed)
            })
        })
    }));
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, materials) = match parsed {
        Ok(Ok((models, materials))) => (models, materials.unwrap_or_default()),
        Ok(Err(e)) => return Err(locate_error(path, &text, &format!("{e}"))),
        Err(_) => return Err(locate_error(path, &text, "the OBJ parser failed")),
    };

    let mut mesh = MeshData::default();
    // Each texture file decoded once, whichever materials read it; one that cannot be read
    // leaves its materials with their Kd, each with a warning.
    let mut loaded: std::collections::HashMap<String, std::result::Result<u32, String>> = Default::default();
    // Each alpha map likewise, as a mask.
    let mut masks: std::collections::HashMap<String, std::result::Result<u32, String>> = Default::default();
    for m in &materials {
        let mut mat = Material::from_mtl(
            &m.name,
            m.diffuse.map_or(DEFAULT_KD, Vec3::from),
            m.specular.map_or(Vec3::ZERO, Vec3::from),
            m.shininess,
            m.illumination_model,
        );
        // An alpha map is a cut-out (`cutout` module); a plain dissolve is transparency, which
        // hyrt does not render: say so rather than draw it solid without a word.
        if let Some(file) = &m.dissolve_texture {
            let got = masks.entry(file.clone()).or_insert_with(|| {
                let file = any_case(Path::new(file));
                let name = file.display().to_string();
                match load_image(&file) {
                    Ok(img) => match Mask::from_image(&name, &img, Channel::AlphaOrGrey) {
                        Some(k) => {
                            mesh.masks.push(k);
                            Ok(mesh.masks.len() as u32 - 1)
                        }
                        None => Err(format!("{name}: the image is empty")),
                    },
                    Err(e) => Err(format!("{e:#}")),
                }
            });
            match got {
                Ok(k) => {
                    mat.cutout = Some(Cutout { mask: Some(*k), scale: 1.0, cutoff: Cutout::DEFAULT_CUTOFF })
                }
                Err(e) => mesh.warnings.push(format!(
                    "{}: material '{}': map_d {e}; it is rendered without holes",
                    path.display(),
                    m.name
                )),
            }
        } else if m.dissolve.is_some_and(|d| d < 1.0) {
            mesh.warnings.push(format!(
                "{}: material '{}' has a dissolve d < 1: hyrt renders it opaque (no transparency)",
                path.display(),
                m.name
            ));
        }
        if let Some(file) = &m.diffuse_texture {
            let got = loaded.entry(file.clone()).or_insert_with(|| {
                match Texture::load(&any_case(Path::new(file))) {
                    Ok(t) => {
                        mesh.textures.push(t);
                        Ok(mesh.textures.len() as u32 - 1)
                    }
                    Err(e) => Err(format!("{e:#}")),
                }
            });
            match got {
                Ok(k) => mat.texture = Some(*k),
                Err(e) => mesh.warnings.push(format!(
                    "{}: material '{}': map_Kd {e}; it is rendered with its Kd",
                    path.display(),
                    m.name
                )),
            }
        }
        mesh.materials.push(mat);
    }
    let mut default_material = None;
    for model in &models {
        let m = &model.mesh;
        if m.indices.len() < 3 {
            continue;
        }
        if !m.normals.iter().all(|c| c.is_finite()) {
            return Err(locate_error(path, &text, "a normal has a NaN or infinite component"));
        }
        let first = mesh.positions.len() as u32;
        let material = match m.material_id.filter(|&i| i < materials.len()) {
            Some(i) => i as u32,
            None => *default_material.get_or_insert_with(|| {
                mesh.materials.push(Material::matte(DEFAULT_MATERIAL, DEFAULT_KD));
                (mesh.materials.len() - 1) as u32
            }),
        };
        // With `single_index`, normals line up with positions only when every corner had one;
        // a model mixing faces with and without normals falls back to face normals. The same
        // for texture coordinates.
        let has_normals = !m.normals.is_empty() && m.normals.len() == m.positions.len();
        let has_uvs = !m.texcoords.is_empty() && m.texcoords.len() / 2 == m.positions.len() / 3;
        for tri in m.indices.chunks_exact(3) {
            let p = corners(&m.positions, tri).ok_or_else(|| {
                anyhow!("{}: internal error: tobj returned an index out of range", path.display())
            })?;
            mesh.positions.push(p);
            mesh.normals.push(if has_normals {
                corners(&m.normals, tri).and_then(unit_normals)
            } else {
                None
            });
            // OBJ's `vt` counts v from the image's bottom; textures count rows from the top.
            let uv = |i: u32| {
                let i = i as usize * 2;
                m.texcoords.get(i..i + 2).map(|t| Vec2::new(t[0], 1.0 - t[1]))
            };
            mesh.uvs.push(if has_uvs { (|| Some([uv(tri[0])?, uv(tri[1])?, uv(tri[2])?]))() } else { None });
            mesh.material.push(material);
        }
        let count = mesh.positions.len() as u32 - first;
        mesh.ranges.push(MeshRange { name: model.name.clone(), first, count });
    }

    if mesh.positions.is_empty() {
        bail!(SceneError::new(
            ErrorKind::Invalid,
            Some(path),
            None,
            format!("{}: has no triangles (no face with three or more vertices)", path.display())
        ));
    }
    if !mesh.positions.iter().flatten().all(|p| p.is_finite()) {
        return Err(locate_error(path, &text, "a vertex has a NaN or infinite coordinate"));
    }
    Ok(mesh)
}

/// The three corners of a triangle from tobj's flat `[x, y, z, x, y, z, ...]` array.
fn corners(flat: &[f32], tri: &[u32]) -> Option<[Vec3; 3]> {
    let v = |i: u32| {
        let i = i as usize * 3;
        flat.get(i..i + 3).map(Vec3::from_slice)
    };
    Some([v(tri[0])?, v(tri[1])?, v(tri[2])?])
}

/// Normalised corner normals, or `None` (use the face normal) if one has no direction: a zero
/// `vn` would otherwise reach the shading code.
pub(super) fn unit_normals(n: [Vec3; 3]) -> Option<[Vec3; 3]> {
    let u = n.map(Vec3::normalize_or_zero);
    u.iter().all(|v| *v != Vec3::ZERO).then_some(u)
}

/// Reads a whole file; the error names the path (`path: cannot read file: <reason>`).
pub(super) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| {
        let what = format!("{}: cannot read file: {}", path.display(), io_message(&e));
        SceneError::new(ErrorKind::Io, Some(path), None, what).into()
    })
}

/// An I/O error's text without the trailing `(os error N)`, which says nothing to a user.
pub(super) fn io_message(e: &std::io::Error) -> String {
    let s = e.to_string();
    match s.find(" (os error") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

/// Reads a text file, gunzipping `*.gz`. Invalid UTF-8 is replaced rather than rejected: names
/// in old exporters' files are often Latin-1, and only numbers and keywords matter here.
fn read_text(path: &Path) -> Result<String> {
    let mut bytes = read_bytes(path)?;
    let gz = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    if gz {
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(bytes.as_slice()).read_to_end(&mut out).map_err(|e| {
            let what = format!("{}: cannot decompress gzip data: {}", path.display(), io_message(&e));
            SceneError::new(ErrorKind::Syntax, Some(path), None, what)
        })?;
        bytes = out;
    }
    Ok(match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    })
}

/// Finds the line behind a failure with [`scan_obj`]; `fallback` describes the failure when
/// the scanner finds nothing.
fn locate_error(path: &Path, text: &str, fallback: &str) -> anyhow::Error {
    let (line, what) = match scan_obj(text) {
        Some((line, msg)) => (Some(line), format!("{}:{line}: {msg}", path.display())),
        None => (None, format!("{}: {fallback}", path.display())),
    };
    SceneError::new(ErrorKind::Syntax, Some(path), line, what).into()
}

/// A source line for an error message, shortened so a huge line cannot flood the terminal.
fn quote(line: &str) -> String {
    const MAX: usize = 80;
    if line.chars().count() <= MAX {
        format!("'{line}'")
    } else {
        format!("'{}...'", line.chars().take(MAX).collect::<String>())
    }
}

/// The first problem in OBJ text as `(1-based line, message)`, mirroring what tobj rejects plus
/// non-finite vertex coordinates and normals. Runs only after a failure, so it favours clear
/// messages over speed.
fn scan_obj(text: &str) -> Option<(usize, String)> {
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let args: Vec<&str> = words.collect();
        let problem = match keyword {
            "v" => check_vertex(line, &args),
            "vt" => check_numbers(line, &args, 2, "texture coordinate", false),
            "vn" => check_numbers(line, &args, 3, "normal", true),
            "f" | "l" => check_face(line, &args, [nv, nvt, nvn]),
            // tobj takes the name after the first space (a tab does not count).
            "usemtl" if line.split_once(' ').is_none_or(|(_, name)| name.trim().is_empty()) => {
                Some(format!("'usemtl' without a material name {}", quote(line)))
            }
            _ => None,
        };
        if let Some(msg) = problem {
            return Some((i + 1, msg));
        }
        match keyword {
            "v" => nv += 1,
            "vt" => nvt += 1,
            "vn" => nvn += 1,
            _ => {}
        }
    }
    None
}

/// `v x y z [w | r g b]`, as tobj accepts it (it does not check the colours).
fn check_vertex(line: &str, args: &[&str]) -> Option<String> {
    let malformed = || Some(format!("malformed vertex {}", quote(line)));
    if !matches!(args.len(), 3 | 4 | 6) {
        return malformed();
    }
    let mut xyz = [0.0f32; 3];
    for (c, a) in xyz.iter_mut().zip(args) {
        let Ok(v) = a.parse() else { return malformed() };
        *c = v;
    }
    let w = match args.get(3) {
        Some(a) if args.len() == 4 => match a.parse::<f32>() {
            Ok(w) => w,
            Err(_) => return malformed(),
        },
        _ => 1.0,
    };
    if w == 0.0 {
        return Some(format!("vertex has w = 0 {}", quote(line)));
    }
    if xyz.iter().any(|c| !(c / w).is_finite()) {
        return Some(format!("vertex has a NaN or infinite coordinate {}", quote(line)));
    }
    None
}

/// `n` leading numbers (extra words are ignored, as tobj does).
fn check_numbers(line: &str, args: &[&str], n: usize, what: &str, finite: bool) -> Option<String> {
    if args.len() < n {
        return Some(format!("malformed {what} (expected {n} numbers) {}", quote(line)));
    }
    let mut nums = Vec::with_capacity(n);
    for a in &args[..n] {
        match a.parse::<f32>() {
            Ok(x) => nums.push(x),
            Err(_) => return Some(format!("malformed {what} {}", quote(line))),
        }
    }
    if finite && nums.iter().any(|x| !x.is_finite()) {
        return Some(format!("{what} has a NaN or infinite component {}", quote(line)));
    }
    None
}

/// `f v[/vt[/vn]] ...` (and `l`, which tobj parses the same way). Indices are checked against
/// the elements defined before this line, as the OBJ format requires; texture and normal
/// indices only when the file has such elements (tobj ignores them otherwise). Faces with fewer
/// than three corners are ignored by the loader, so only their syntax is checked.
fn check_face(line: &str, args: &[&str], counts: [usize; 3]) -> Option<String> {
    const WHAT: [(&str, &str); 3] =
        [("vertex", "vertices"), ("texture coordinate", "texture coordinates"), ("normal", "normals")];
    if args.is_empty() {
        return Some(format!("face without vertices {}", quote(line)));
    }
    for corner in args {
        let parts: Vec<&str> = corner.split('/').collect();
        if parts.len() > 3 || parts[0].is_empty() {
            return Some(format!("malformed face {}", quote(line)));
        }
        for (k, part) in parts.iter().enumerate() {
            if part.is_empty() {
                continue;
            }
            let Ok(index) = part.parse::<i64>() else {
                return Some(format!("malformed face {}", quote(line)));
            };
            if index == 0 {
                return Some(format!("face index 0 is invalid (OBJ indices start at 1) {}", quote(line)));
            }
            let n = counts[k];
            let in_range =
                if index > 0 { index as u64 <= n as u64 } else { index.unsigned_abs() <= n as u64 };
            let checked = k == 0 || n > 0;
            if args.len() >= 3 && checked && !in_range {
                return Some(format!(
                    "face index {index} is out of range (only {n} {} defined before this line) {}",
                    if n == 1 { WHAT[k].0 } else { WHAT[k].1 },
                    quote(line)
                ));
            }
        }
    }
    None
}

/// Loads the material library named on an `mtllib` line of `obj`. tobj passes the rest of the
/// line as one name (to allow spaces in file names); when no such file exists, the line is
/// retried as a list of names, which the OBJ format also allows.
fn load_mtllib(obj: &Path, obj_text: &str, dir: &Path, name: &Path) -> Result<tobj::MTLLoadResult> {
    let whole = dir.join(name);
    let name_str = name.to_string_lossy();
    let files: Vec<PathBuf> = if !whole.exists() && name_str.contains(char::is_whitespace) {
        let parts: Vec<PathBuf> = name_str.split_whitespace().map(|p| dir.join(p)).collect();
        if parts.iter().all(|p| p.exists()) { parts } else { vec![whole] }
    } else {
        vec![whole]
    };

    let mut materials = Vec::new();
    let mut names = Default::default();
    for file in files {
        let bytes = std::fs::read(&file).map_err(|e| {
            let line = mtllib_line(obj_text, &name_str);
            let at = line.map(|l| format!(":{l}")).unwrap_or_default();
            let what = format!(
                "{}{at}: cannot read material library {}: {}",
                obj.display(),
                file.display(),
                io_message(&e)
            );
            SceneError::new(ErrorKind::Io, Some(obj), line, what)
        })?;
        let text = String::from_utf8_lossy(&bytes);
        let normalised = normalise_mtl(&file, obj, &text)?;
        let (mut mats, map) = tobj::load_mtl_buf(&mut normalised.as_bytes()).map_err(|e| {
            let what = format!("{}: malformed material library: {e}", file.display());
            SceneError::new(ErrorKind::Syntax, Some(&file), None, what)
        })?;
        // A texture's file is relative to its library: kept as a path from here.
        let lib_dir = file.parent().unwrap_or(Path::new(""));
        for m in &mut mats {
            for t in [&mut m.diffuse_texture, &mut m.dissolve_texture].into_iter().flatten() {
                *t = lib_dir.join(texture_file(t)).to_string_lossy().into_owned();
            }
        }
        merge_materials(&mut materials, &mut names, mats, map);
    }
    Ok(Ok((materials, names)))
}

/// `path`, or when no such file exists, the file of its directory whose name matches it but
/// for case: MTL files written on case-insensitive systems often name `WALL.JPG` for
/// `wall.jpg`.
fn any_case(path: &Path) -> PathBuf {
    if path.exists() {
        return path.to_path_buf();
    }
    let (Some(dir), Some(name)) = (path.parent(), path.file_name().and_then(|n| n.to_str())) else {
        return path.to_path_buf();
    };
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    let found = std::fs::read_dir(dir).ok().and_then(|entries| {
        entries
            .flatten()
            .map(|e| e.path())
            .find(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.eq_ignore_ascii_case(name)))
    });
    found.unwrap_or_else(|| path.to_path_buf())
}

/// The file name of a texture statement's argument: its last word when options (`-s 1 1 1`,
/// `-bm 0.5`, ...) come first, which hyrt does not honour; the whole argument otherwise (file
/// names may hold spaces).
fn texture_file(arg: &str) -> String {
    let arg = arg.trim();
    let file = if arg.starts_with('-') { arg.split_whitespace().last().unwrap_or(arg) } else { arg };
    // Files written on Windows name `textures\wall.jpg`.
    file.replace('\\', "/")
}

/// Appends one library's materials, later definitions of a name winning (as in tobj).
fn merge_materials<M: Extend<(String, usize)>>(
    materials: &mut Vec<tobj::Material>,
    names: &mut M,
    mats: Vec<tobj::Material>,
    map: impl IntoIterator<Item = (String, usize)>,
) {
    let offset = materials.len();
    materials.extend(mats);
    names.extend(map.into_iter().map(|(k, v)| (k, v + offset)));
}

/// The 1-based line of the `mtllib` statement naming `name`.
fn mtllib_line(obj_text: &str, name: &str) -> Option<usize> {
    obj_text
        .lines()
        .position(|l| l.trim().strip_prefix("mtllib").is_some_and(|rest| rest.trim() == name))
        .map(|i| i + 1)
}

/// Checks an MTL file line by line and returns the text tobj should parse: colour lines are
/// rewritten as exactly `K? r g b` (the MTL format allows a single value meaning grey, and a
/// trailing `# comment`; tobj rejects both and panics on fewer than three numbers).
fn normalise_mtl(file: &Path, obj: &Path, text: &str) -> Result<String> {
    let mut out = String::with_capacity(text.len() + 64);
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let err = |msg: String| -> anyhow::Error {
            let what = format!("{}:{}: {msg} (material library of {})", file.display(), i + 1, obj.display());
            SceneError::new(ErrorKind::Syntax, Some(file), Some(i + 1), what).into()
        };
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let has_argument = words.clone().next().is_some();
        // In numeric statements, everything from a word starting with `#` on is a comment.
        let args: Vec<&str> = words.take_while(|w| !w.starts_with('#')).collect();
        match keyword {
            "Ka" | "Kd" | "Ks" | "Ke" => {
                let nums: Vec<f32> = args
                    .iter()
                    .map(|a| a.parse::<f32>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| err(format!("malformed number in {}", quote(line))))?;
                let rgb = match nums[..] {
                    [v] => [v; 3],
                    [r, g, b] => [r, g, b],
                    _ => return Err(err(format!("expected 1 or 3 numbers in {}", quote(line)))),
                };
                if rgb.iter().any(|c| !c.is_finite()) {
                    return Err(err(format!("colour has a NaN or infinite component {}", quote(line))));
                }
                if keyword != "Ke" && rgb.iter().any(|&c| c < 0.0) {
                    return Err(err(format!("negative reflectance in {}", quote(line))));
                }
                let _ = writeln!(out, "{keyword} {} {} {}", rgb[0], rgb[1], rgb[2]);
                continue;
            }
            "Ns" | "Ni" | "d" if args.first().and_then(|a| a.parse::<f32>().ok()).is_none() => {
                return Err(err(format!("malformed number in {}", quote(line))));
            }
            "Ns" if !args[0].parse::<f32>().is_ok_and(|n| n.is_finite() && n >= 0.0) => {
                return Err(err(format!(
                    "the highlight exponent must be finite and >= 0 in {}",
                    quote(line)
                )));
            }
            "illum" if args.first().and_then(|a| a.parse::<u8>().ok()).is_none() => {
                return Err(err(format!("malformed illumination model (expected 0-255) in {}", quote(line))));
            }
            "newmtl" if !has_argument => return Err(err("'newmtl' without a material name".to_string())),
            "map_Ka" | "map_Kd" | "map_Ks" | "map_Bump" | "map_bump" | "map_Ns" | "map_ns" | "map_NS"
            | "bump" | "map_d"
                if !has_argument =>
            {
                return Err(err(format!("'{keyword}' without a file name")));
            }
            _ => {}
        }
        out.push_str(raw);
        out.push('\n');
    }
    Ok(out)
}
