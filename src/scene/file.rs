//! The TOML scene file format.
//!
//! A scene file places one or more mesh files (OBJ, gzipped OBJ, glTF, GLB), overrides
//! materials, and adds a camera, point lights and render settings:
//!
//! ```toml
//! name = "cornell-bunny-mirror"          # optional, default: the file name without extension
//!
//! [camera]                               # optional: without it, a glTF file's or an automatic one
//! eye = [0.0, 1.0, 6.8]
//! target = [0.0, 1.0, 0.0]               # exactly one of target / direction
//! # direction = [-0.5607, -0.2336, 0.7944]
//! up = [0.0, 1.0, 0.0]                   # optional, default +Y
//! fov_y = 19.5                           # vertical field of view in degrees (required)
//! # fov_x = 39.9                         # optional horizontal fov (Radiance-style views)
//!
//! [settings]                             # optional table; every key optional
//! width = 640
//! height = 480
//! max_depth = 5                          # maximum number of mirror bounces
//! exposure = 1.0
//!
//! [indirect]                             # optional: ask for indirect light (VPLs)
//! vpls = 45                              # light paths over all lights (required)
//! bounces = 1                            # optional, default 1
//! seed = 0                               # optional, default 0
//! clamp = 0.01                           # optional: d_min / scene diagonal
//!
//! [[mesh]]                               # one or more
//! path = "../../shared/scenes/cornell-bunny-mirror/cornell-bunny-mirror.obj"   # relative to this file
//! scale = 1.0                            # optional: number or [x, y, z]
//! rotate = [0.0, 90.0, 0.0]              # optional: Euler angles in degrees (see below)
//! translate = [0.0, 0.0, 0.0]            # optional
//! exclude_materials = ["window_glass"]   # optional: drop triangles with these material names
//!
//! [[material]]                           # optional overrides, matched by material name
//! name = "chrome"
//! diffuse = [0.08, 0.08, 0.08]           # optional: Kd, number or [r, g, b]
//! highlight = 0.0                        # optional: Ks of the highlight
//! shininess = 40.0                       # optional: its exponent Ns
//! mirror = 0.72                          # optional: Kr, the reflection ray's weight
//!
//! [[light]]                              # zero or more point lights
//! position = [0.0, 1.9, -0.03]
//! intensity = [0.6, 0.6, 0.6]            # W/sr, number or [r, g, b]
//!
//! [[light]]                              # a spot light
//! kind = "spot"                          # "point" (the default) or "spot"
//! position = [0.0, 1.9, 0.0]
//! direction = [0.0, -1.0, 0.0]           # the way it shines (need not be normalised)
//! inner_angle = 15.0                     # degrees from the axis at full intensity (default 0)
//! outer_angle = 30.0                     # degrees from the axis beyond which it is dark
//! intensity = 2.0                        # W/sr on the axis
//!
//! [[light]]                              # the sun
//! kind = "directional"
//! direction = [-0.35, -0.55, -0.76]      # the way the light travels
//! irradiance = 2.0                       # W/m^2 (W per square scene unit) on a surface facing it
//! ```
//!
//! Rules:
//!
//! - Unknown keys and tables are errors, as are missing required keys (`camera.eye`,
//!   `camera.fov_y`, `mesh.path`, `material.name`, `light.position`, `light.intensity`) and a
//!   file without any `[[mesh]]`. Integers are accepted wherever a number is expected.
//! - `[camera]`: the viewing direction is `target - eye`, or `direction` as given (it need not
//!   be normalised); giving both or neither is an error. Without a `[camera]` table the scene
//!   is seen through the first camera its glTF files define (`--camera N` picks another), and
//!   without one either the camera looks at the centre of the scene's bounds from the front
//!   (+Z) and slightly above, with a vertical fov of 45 degrees; a light at the camera is then
//!   added only if the scene has no light (`[[light]]` or a glTF file's). With a `[camera]` and
//!   no light, the scene has no lights.
//! - glTF files bring their cameras and point lights (`KHR_lights_punctual`), moved by the
//!   mesh's transform; `[[light]]`s are added to those lights. See [`super::gltf`] for their
//!   units.
//! - `[settings]`: defaults are width 640, height 480, max_depth 5, exposure 1.0. Without a
//!   `width` or `height`, a glTF camera's aspect ratio sets the height from the width.
//! - `[indirect]`: the scene is rendered with indirect light from `vpls` virtual point lights
//!   (visibility by rays in the reference, by maps in the hybrid; see the CLI's `--indirect`).
//!   Without it, only direct light. `clamp` must be a finite number `>= 0`.
//! - `[[mesh]]`: `path` is relative to the scene file's directory (absolute paths work too).
//!   Each mesh is transformed by `M = T * R * S`: first scaled (about the origin), then rotated,
//!   then translated; normals use the inverse transpose of `M`, and a mirroring transform
//!   (negative determinant) keeps triangles counter-clockwise. `rotate = [rx, ry, rz]` turns
//!   about the fixed world axes, first X by `rx`, then Y by `ry`, then Z by `rz`:
//!   `R = Rz(rz) * Ry(ry) * Rx(rx)` (glam's extrinsic `EulerRot::XYZEx`). Positive angles turn counter-clockwise
//!   when looking down the axis towards the origin (right-handed). `exclude_materials` drops
//!   every triangle whose material has one of the names (before the transform); a name that
//!   no material of that mesh has is an error.
//! - `[[material]]`: every material called `name`, in any mesh, gets the parts it gives set
//!   exactly as given, the others kept as the mesh file's loader read them (see
//!   [`super::material`] for the model and how MTL and glTF are read): `diffuse` (albedo `Kd`),
//!   `highlight` (`Ks` of the point lights' Blinn-Phong highlight), `shininess` (its exponent)
//!   and `mirror` (reflectance of the Whitted reflection ray; the plan then names the scene
//!   file as the reason the material reflects). Colours are a number (grey) or `[r, g, b]`,
//!   finite and `>= 0`, and `shininess` finite and `>= 0`. A name that matches no material is
//!   an error. Overrides are applied in file order after all meshes are loaded.
//! - `[[light]]`: an isotropic point light; a single number for `intensity` means grey. With
//!   `kind = "spot"`, a spot light: the point light's intensity (now on the axis) times
//!   1 within `inner_angle` of `direction`, 0 beyond `outer_angle`, and between them the smooth
//!   ramp glTF recommends, `t^2` with `t = (cos a - cos outer) / (cos inner - cos outer)`;
//!   `0 <= inner_angle <= outer_angle <= 90`. Points outside the cone get neither a map
//!   decision nor a shadow ray, and VPL paths leave into the cone only. With
//!   `kind = "directional"`, parallel light along `direction` with `irradiance` (no `position`
//!   nor `intensity`): it is rendered as a point light 1000 scene diagonals away, so that its
//!   rays deviate from `direction` by at most 1/2000 rad (0.029 degrees, a tenth of the sun's
//!   own angular radius) and its irradiance by at most 0.1 % across the scene, the same for the
//!   reference and the hybrid (`scene::Directional`). Keys of another kind are an error.
//!
//! Errors name the scene file, with a line number where one is known (the TOML parser's
//! messages include line and column); an error inside a mesh file names both files.

use std::collections::HashSet;
use std::fmt;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use glam::{EulerRot, Mat4, Quat, Vec3};
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use toml::Spanned;

use super::obj::read_bytes;
use super::{Camera, ErrorKind, MeshData, PointLight, Scene, SceneError, load_mesh};

/// The whole file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    camera: Option<Spanned<CameraSpec>>,
    settings: Option<SettingsSpec>,
    indirect: Option<Spanned<IndirectSpec>>,
    #[serde(default)]
    mesh: Vec<Spanned<MeshSpec>>,
    #[serde(default)]
    material: Vec<Spanned<MaterialSpec>>,
    #[serde(default)]
    light: Vec<Spanned<LightSpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    eye: V3,
    target: Option<V3>,
    direction: Option<V3>,
    up: Option<V3>,
    fov_y: f32,
    fov_x: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct IndirectSpec {
    vpls: u32,
    bounces: Option<u32>,
    seed: Option<u32>,
    clamp: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SettingsSpec {
    width: Option<u32>,
    height: Option<u32>,
    max_depth: Option<u32>,
    exposure: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshSpec {
    path: PathBuf,
    scale: Option<Splat3>,
    rotate: Option<V3>,
    translate: Option<V3>,
    #[serde(default)]
    exclude_materials: Vec<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialSpec {
    name: String,
    diffuse: Option<Splat3>,
    highlight: Option<Splat3>,
    shininess: Option<f32>,
    mirror: Option<Splat3>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightSpec {
    /// `point` (the default), `spot` or `directional`.
    kind: Option<String>,
    position: Option<V3>,
    intensity: Option<Splat3>,
    /// Directional lights: what a surface facing them receives, W/m^2.
    irradiance: Option<Splat3>,
    /// Spot lights: the axis (the way the light shines) and the cone's half-angles in degrees.
    direction: Option<V3>,
    inner_angle: Option<f32>,
    outer_angle: Option<f32>,
}

/// What a `[[light]]` table makes.
enum Light {
    Point(PointLight),
    Directional(super::Directional),
}

impl LightSpec {
    /// The light, or why the table does not make one.
    fn light(&self) -> std::result::Result<Light, String> {
        let kind = self.kind.as_deref().unwrap_or("point");
        if kind == "directional" {
            let (Some(d), Some(e)) = (self.direction, self.irradiance) else {
                return Err("a directional light needs 'direction' and 'irradiance'".to_string());
            };
            if self.position.is_some()
                || self.intensity.is_some()
                || self.inner_angle.is_some()
                || self.outer_angle.is_some()
            {
                return Err("a directional light has 'direction' and 'irradiance' only".to_string());
            }
            if !(d.0.is_finite() && d.0 != Vec3::ZERO) {
                return Err("a directional light's 'direction' must be a finite, non-zero vector".to_string());
            }
            return Ok(Light::Directional(super::Directional { direction: d.0, irradiance: e.0 }));
        }
        if self.irradiance.is_some() {
            return Err(
                "'irradiance' belongs to kind = \"directional\" ('intensity' gives a point or spot light's)"
                    .to_string(),
            );
        }
        let (Some(position), Some(intensity)) = (self.position, self.intensity) else {
            return Err(format!("a {kind} light needs 'position' and 'intensity'"));
        };
        self.point(PointLight { position: position.0, intensity: intensity.0, spot: None }).map(Light::Point)
    }

    /// A point or spot light at `light`'s position and intensity.
    fn point(&self, light: PointLight) -> std::result::Result<PointLight, String> {
        let spot_keys = self.direction.is_some() || self.inner_angle.is_some() || self.outer_angle.is_some();
        match self.kind.as_deref().unwrap_or("point") {
            "point" if spot_keys => {
                Err("'direction', 'inner_angle' and 'outer_angle' belong to kind = \"spot\"".to_string())
            }
            "point" => Ok(light),
            "spot" => {
                let (Some(d), Some(outer)) = (self.direction, self.outer_angle) else {
                    return Err("a spot light needs 'direction' and 'outer_angle'".to_string());
                };
                let inner = self.inner_angle.unwrap_or(0.0);
                if !(0.0..=90.0).contains(&outer) || !(0.0..=outer).contains(&inner) {
                    return Err(format!(
                        "a spot light's angles must satisfy 0 <= inner_angle <= outer_angle <= 90 degrees, got {inner} and {outer}"
                    ));
                }
                if !(d.0.is_finite() && d.0 != Vec3::ZERO) {
                    return Err("a spot light's 'direction' must be a finite, non-zero vector".to_string());
                }
                let spot = super::Spot::new(d.0, inner.to_radians(), outer.to_radians());
                Ok(PointLight { spot: Some(spot), ..light })
            }
            other => {
                Err(format!("unknown light kind '{other}' (expected \"point\", \"spot\" or \"directional\")"))
            }
        }
    }
}

/// An `[x, y, z]` array of exactly three numbers. (serde's `[f32; 3]` would silently ignore
/// extra elements with the toml deserializer.)
#[derive(Clone, Copy, Default)]
struct V3(Vec3);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let v = Vec::<f32>::deserialize(d)?;
        match v[..] {
            [x, y, z] => Ok(V3(Vec3::new(x, y, z))),
            _ => Err(de::Error::invalid_length(v.len(), &"an array of three numbers")),
        }
    }
}

/// A number meaning `[v, v, v]`, or an `[x, y, z]` array.
#[derive(Clone, Copy)]
struct Splat3(Vec3);

impl<'de> Deserialize<'de> for Splat3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        // A hand-written visitor rather than an untagged enum, whose error ("data did not match
        // any variant") would not say what is expected.
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Splat3;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of three numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Splat3, E> {
                Ok(Splat3(Vec3::splat(v as f32)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Splat3, E> {
                Ok(Splat3(Vec3::splat(v as f32)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Splat3, E> {
                Ok(Splat3(Vec3::splat(v as f32)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> std::result::Result<Splat3, A::Error> {
                let v = V3::deserialize(de::value::SeqAccessDeserializer::new(seq))?;
                Ok(Splat3(v.0))
            }
        }
        d.deserialize_any(V)
    }
}

/// A line of a scene file.
#[derive(Clone, Copy)]
struct Loc<'p> {
    file: &'p Path,
    line: usize,
}

impl std::fmt::Display for Loc<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.file.display(), self.line)
    }
}

/// An [`ErrorKind::Invalid`] error at `at`: the message is `file:line: what`.
fn invalid(at: Loc, what: String) -> anyhow::Error {
    SceneError::new(ErrorKind::Invalid, Some(at.file), Some(at.line), format!("{at}: {what}")).into()
}

/// Loads a `.toml` scene file (format in the [module documentation](self)); mesh paths are
/// relative to the file. The scene is not validated: the caller does that.
pub fn load(path: &Path) -> Result<Scene> {
    let shown = path.display();
    let bytes = read_bytes(path)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let line = line_of(e.as_bytes(), e.utf8_error().valid_up_to());
        SceneError::new(
            ErrorKind::Syntax,
            Some(path),
            Some(line),
            format!("{shown}:{line}: the file is not valid UTF-8"),
        )
    })?;
    let file: SceneFile = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| line_of(text.as_bytes(), s.start));
        SceneError::new(ErrorKind::Syntax, Some(path), line, format!("{shown}: {}", e.to_string().trim_end()))
    })?;
    let at = |span: std::ops::Range<usize>| Loc { file: path, line: line_of(text.as_bytes(), span.start) };

    if file.mesh.is_empty() {
        bail!("{shown}: the scene has no [[mesh]] (at least one is required)");
    }
    let name = match file.name {
        Some(n) => n,
        None => path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
    };
    // The camera is checked before any (possibly slow) mesh is loaded.
    let camera = match &file.camera {
        Some(spec) => {
            let c = spec.get_ref();
            let eye = c.eye.0;
            let forward = match (c.target, c.direction) {
                (Some(t), None) => t.0 - eye,
                (None, Some(d)) => d.0,
                _ => {
                    return Err(invalid(
                        at(spec.span()),
                        "[camera] needs exactly one of 'target' and 'direction'".into(),
                    ));
                }
            };
            let up = c.up.map_or(Vec3::Y, |u| u.0);
            Some(Camera { eye, forward, up, fov_y_deg: c.fov_y, fov_x_deg: c.fov_x })
        }
        None => None,
    };

    let mut scene = Scene::new(&name);
    scene.source = Some(path.to_path_buf());
    let dir = path.parent().unwrap_or(Path::new(""));

    for spec in &file.mesh {
        let m = spec.get_ref();
        let mesh_path = dir.join(&m.path);
        let mut mesh =
            load_mesh(&mesh_path).with_context(|| format!("{shown}: mesh {}", m.path.display()))?;
        if !m.exclude_materials.is_empty() {
            mesh = exclude(mesh, &m.exclude_materials)
                .map_err(|e| invalid(at(spec.span()), format!("mesh {}: {e}", m.path.display())))?;
        }
        let scale = m.scale.map_or(Vec3::ONE, |s| s.0);
        let [rx, ry, rz] = m.rotate.unwrap_or_default().0.to_array().map(f32::to_radians);
        let rotation = Quat::from_euler(EulerRot::XYZEx, rx, ry, rz);
        let translation = m.translate.unwrap_or_default().0;
        let transform = Mat4::from_scale_rotation_translation(scale, rotation, translation);
        // A zero scale would make the normal matrix infinite (zero normals after normalising).
        if !transform.is_finite() || transform.determinant() == 0.0 {
            return Err(invalid(
                at(spec.span()),
                format!(
                    "mesh {}: scale, rotate and translate must be finite numbers and scale non-zero",
                    m.path.display()
                ),
            ));
        }
        if transform != Mat4::IDENTITY {
            mesh.transform(transform);
            // A mirroring transform turns counter-clockwise triangles clockwise; swap two
            // corners so face orientation survives.
            if transform.determinant() < 0.0 {
                for t in &mut mesh.positions {
                    t.swap(1, 2);
                }
                for n in mesh.normals.iter_mut().flatten() {
                    n.swap(1, 2);
                }
                for uv in mesh.uvs.iter_mut().flatten() {
                    uv.swap(1, 2);
                }
            }
        }
        scene.add_mesh(mesh);
    }

    for spec in &file.material {
        let o = spec.get_ref();
        let mut found = false;
        for m in scene.materials.iter_mut().filter(|m| m.name == o.name) {
            found = true;
            if let Some(c) = o.diffuse {
                m.diffuse = c.0;
            }
            if let Some(c) = o.highlight {
                // As given: a texture no longer tints it.
                m.highlight = c.0;
                m.highlight_base = Vec3::ZERO;
            }
            if let Some(n) = o.shininess {
                m.shininess = n;
            }
            if let Some(c) = o.mirror {
                m.mirror = c.0;
                m.mirror_source = super::MirrorSource::SceneFile;
            }
            if let Err(e) = m.check() {
                return Err(invalid(at(spec.span()), format!("[[material]] '{}': {e}", o.name)));
            }
        }
        if !found {
            return Err(invalid(
                at(spec.span()),
                format!(
                    "[[material]] '{}' matches no material in the scene (materials: {})",
                    o.name,
                    name_list(scene.materials.iter().map(|m| m.name.as_str()))
                ),
            ));
        }
    }

    for spec in &file.light {
        match spec.get_ref().light().map_err(|e| invalid(at(spec.span()), format!("[[light]]: {e}")))? {
            Light::Point(l) => scene.lights.push(l),
            Light::Directional(d) => scene.directional.push(d),
        }
    }
    scene.place_directional_lights();

    if let Some(s) = &file.settings {
        let d = &mut scene.settings;
        d.width = s.width.unwrap_or(d.width);
        d.height = s.height.unwrap_or(d.height);
        d.max_depth = s.max_depth.unwrap_or(d.max_depth);
        d.exposure = s.exposure.unwrap_or(d.exposure);
        scene.size_given = s.width.is_some() || s.height.is_some();
    }

    if let Some(ind) = &file.indirect {
        if let Some(c) = ind.get_ref().clamp
            && !(c >= 0.0 && c.is_finite())
        {
            return Err(invalid(
                at(ind.span()),
                format!("[indirect] clamp must be a finite number >= 0, got {c}"),
            ));
        }
        let i = ind.get_ref();
        scene.indirect = Some(super::IndirectSettings {
            vpls: i.vpls,
            bounces: i.bounces.unwrap_or(1),
            seed: i.seed.unwrap_or(0),
            clamp: i.clamp,
        });
    }

    match camera {
        Some(c) => scene.camera = Some(c),
        None => {
            if !scene.cameras.is_empty() {
                scene.use_file_camera(0)?;
            }
            scene.frame_automatically();
        }
    }
    Ok(scene)
}

/// Drops the triangles whose material is named in `names`, keeping ranges consistent (empty
/// ranges disappear). Every name must belong to one of the mesh's materials.
fn exclude(mut mesh: MeshData, names: &[String]) -> Result<MeshData> {
    let known: HashSet<&str> = mesh.materials.iter().map(|m| m.name.as_str()).collect();
    if let Some(missing) = names.iter().find(|n| !known.contains(n.as_str())) {
        bail!(
            "exclude_materials: no material named '{missing}' (materials: {})",
            name_list(mesh.materials.iter().map(|m| m.name.as_str()))
        );
    }
    let names: HashSet<&str> = names.iter().map(String::as_str).collect();
    let dropped: Vec<bool> = mesh.materials.iter().map(|m| names.contains(m.name.as_str())).collect();
    let keep: Vec<bool> =
        mesh.material.iter().map(|&m| !dropped.get(m as usize).copied().unwrap_or(false)).collect();

    // kept_before[i] = number of kept triangles before triangle i, to remap range starts.
    let mut kept_before = Vec::with_capacity(keep.len() + 1);
    let mut n = 0u32;
    kept_before.push(0);
    for &k in &keep {
        n += u32::from(k);
        kept_before.push(n);
    }
    let remap = |i: u32| kept_before.get(i as usize).copied().unwrap_or(n);
    mesh.ranges = mesh
        .ranges
        .iter()
        .map(|r| {
            let first = remap(r.first);
            let end = remap(r.first.saturating_add(r.count));
            super::MeshRange { name: r.name.clone(), first, count: end - first }
        })
        .filter(|r| r.count > 0)
        .collect();

    let mut it = keep.iter();
    mesh.positions.retain(|_| it.next().copied().unwrap_or(true));
    let mut it = keep.iter();
    mesh.normals.retain(|_| it.next().copied().unwrap_or(true));
    let mut it = keep.iter();
    mesh.material.retain(|_| it.next().copied().unwrap_or(true));
    let mut it = keep.iter();
    mesh.uvs.retain(|_| it.next().copied().unwrap_or(true));
    Ok(mesh)
}

/// Up to 12 distinct names, comma-separated, for "did you mean" style messages.
fn name_list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let mut seen = HashSet::new();
    let unique: Vec<&str> = names.filter(|n| seen.insert(*n)).collect();
    let mut s = unique.iter().take(12).map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ");
    if unique.len() > 12 {
        s.push_str(&format!(", ... ({} in all)", unique.len()));
    }
    if s.is_empty() { "none".to_string() } else { s }
}

/// 1-based line number of a byte offset.
fn line_of(text: &[u8], offset: usize) -> usize {
    text.iter().take(offset).filter(|&&b| b == b'\n').count() + 1
}
