//! The scene model: flat triangles with materials, point lights, a pinhole camera and settings.
//!
//! Every loader (built-in, OBJ, glTF, TOML scene file) produces a [`Scene`]; everything after
//! loading (planner, pipelines, inspector) reads only this model. [`Scene::validate`] is the one
//! place where bad geometry (NaN or infinite vertices, empty scenes) and degenerate cameras are
//! turned into errors, so a renderer never sees them.

pub mod builtin;
pub mod cutout;
pub mod error;
pub mod file;
pub mod gltf;
pub mod material;
pub mod obj;
pub mod texture;

pub use material::{Material, MirrorSource};

pub use error::{ErrorKind, SceneError};
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use glam::{Mat4, Vec2, Vec3};

/// A point light: isotropic, or a spot light shining into a cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    pub position: Vec3,
    /// Radiant intensity in W/sr per RGB channel (on the cone's axis for a spot light).
    pub intensity: Vec3,
    /// The cone of a spot light; `None`: every direction alike.
    pub spot: Option<Spot>,
}

impl PointLight {
    /// The intensity sent along unit direction `d` from the light: `intensity`, times the
    /// spot's [`Spot::factor`] for a spot light (exactly `intensity` for a point light).
    #[inline]
    pub fn intensity_towards(&self, d: Vec3) -> Vec3 {
        match &self.spot {
            None => self.intensity,
            Some(s) => self.intensity * s.factor(d),
        }
    }

    /// Whether the light sends nothing along unit direction `d` (outside a spot's cone).
    #[inline]
    pub fn dark_towards(&self, d: Vec3) -> bool {
        self.spot.is_some_and(|s| s.factor(d) <= 0.0)
    }
}

/// The cone of a spot light (a point light whose intensity falls off away from an axis).
///
/// Full intensity within `inner` of the axis, none beyond `outer`, and between them the ramp
/// that glTF's `KHR_lights_punctual` recommends: `t^2` with `t = (cos a - cos outer) / (cos
/// inner - cos outer)`, `a` the angle from the axis (linear in the cosine, squared, so that it
/// starts and ends smoothly enough for the eye and costs one dot product).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// Unit direction of the axis: the way the light shines.
    pub axis: Vec3,
    /// Cosine of the inner half-angle.
    pub cos_inner: f32,
    /// Cosine of the outer half-angle (at most `cos_inner`).
    pub cos_outer: f32,
}

impl Spot {
    /// The cone around `axis` (any length) with half-angles `inner` and `outer` (radians);
    /// `outer` is at least `inner`.
    pub fn new(axis: Vec3, inner: f32, outer: f32) -> Self {
        Self { axis: axis.normalize_or_zero(), cos_inner: inner.cos(), cos_outer: outer.max(inner).cos() }
    }

    /// The fraction of the axis's intensity sent along unit direction `d` (type docs).
    #[inline]
    pub fn factor(&self, d: Vec3) -> f32 {
        let c = self.axis.dot(d);
        if c >= self.cos_inner {
            1.0
        } else if c <= self.cos_outer {
            0.0
        } else {
            let t = (c - self.cos_outer) / (self.cos_inner - self.cos_outer);
            t * t
        }
    }
}

/// A directional light (the sun): parallel light travelling along `direction`, giving
/// `irradiance` (W/m^2 per RGB channel, or W per square scene unit) to a surface facing it.
///
/// It is rendered as a point light [`SUN_DISTANCE`] scene diagonals away against `direction`
/// from the centre of the scene's bounds, with intensity `irradiance D^2`
/// ([`Scene::place_directional_lights`]): the reference and the hybrid alike, so the maps and
/// the rays see the same light. Across the scene its rays then deviate from `direction` by at
/// most `(diagonal / 2) / D = 1 / 2000` rad (0.029 degrees: a tenth of the sun's own angular
/// radius, 0.27 degrees, which real sunlight spreads over anyway), and its irradiance varies by
/// at most `(1 + 1/2000)^2 - 1`, 0.1 %. A real orthographic map would need its own map layout
/// and decision rule; this costs neither, and paged maps resolve the distant light at the
/// receivers' resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Directional {
    /// The way the light travels (any length).
    pub direction: Vec3,
    pub irradiance: Vec3,
}

/// How far a [`Directional`] light is placed, in scene diagonals.
pub const SUN_DISTANCE: f32 = 1000.0;

/// A pinhole camera. The field of view is vertical; `fov_x_deg`, when given (as the Radiance
/// office view does), fixes the horizontal extent too, otherwise it follows the image aspect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    /// Viewing direction (need not be normalised).
    pub forward: Vec3,
    pub up: Vec3,
    pub fov_y_deg: f32,
    pub fov_x_deg: Option<f32>,
}

impl Camera {
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, fov_y_deg: f32) -> Self {
        Self { eye, forward: target - eye, up, fov_y_deg, fov_x_deg: None }
    }
}

/// A camera that a model file defines (a glTF camera placed by a node), in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct FileCamera {
    /// Where it comes from, for messages: the file's camera index and name.
    pub label: String,
    pub camera: Camera,
    /// The file's width over height, if it gives one: the image takes it when no size is set.
    pub aspect: Option<f32>,
}

/// Render settings that travel with a scene (the CLI may override them).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Maximum number of mirror bounces after the camera hit.
    pub max_depth: u32,
    /// Linear scale applied before the sRGB transform when writing PNG.
    pub exposure: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Self { width: 640, height: 480, max_depth: 5, exposure: 1.0 }
    }
}

/// A named range of triangles, as loaded from one mesh or object.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshRange {
    pub name: String,
    pub first: u32,
    pub count: u32,
}

/// The angle one pixel of an image `height` pixels high subtends at the centre of a vertical
/// field of view of `fov_y_deg` degrees. Remembered per thread for the last field of view
/// and height asked (shading asks it for every textured point, and `tan` is a libm call).
fn pixel_angle(fov_y_deg: f32, height: u32) -> f32 {
    thread_local! {
        static LAST: std::cell::Cell<(u32, u32, f32)> = const { std::cell::Cell::new((u32::MAX, 0, 0.0)) };
    }
    LAST.with(|last| {
        let (fov, h, a) = last.get();
        if (fov, h) == (fov_y_deg.to_bits(), height) {
            return a;
        }
        let a = 2.0 * (fov_y_deg.to_radians() * 0.5).tan() / height.max(1) as f32;
        last.set((fov_y_deg.to_bits(), height, a));
        a
    })
}

/// Everything a renderer needs.
///
/// Triangles are flattened: triangle `i` has corners `positions[i]`, per-corner shading normals
/// `normals[i]` (the face normal three times when the source gave none) and material
/// `material[i]`. The index `i` is the triangle's original id: load order, stable across runs;
/// acceleration structures reorder internally but report this id.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub name: String,
    pub positions: Vec<[Vec3; 3]>,
    pub normals: Vec<[Vec3; 3]>,
    pub material: Vec<u32>,
    pub materials: Vec<Material>,
    pub meshes: Vec<MeshRange>,
    pub lights: Vec<PointLight>,
    pub camera: Option<Camera>,
    pub settings: Settings,
    /// Indirect light the scene asks for (VPLs); `None`: direct light only.
    pub indirect: Option<IndirectSettings>,
    /// Where the scene came from (for messages); `None` for built-in scenes.
    pub source: Option<PathBuf>,
    /// The textures its materials read ([`Material::texture`]).
    pub textures: Vec<texture::Texture>,
    /// The alpha masks its materials' cut-outs read ([`cutout::Cutout::mask`]).
    pub masks: Vec<cutout::Mask>,
    /// Per triangle, its corners' texture coordinates: empty when the scene has no texture
    /// and no mask, else one entry per triangle (zero where the file gave none).
    pub uvs: Vec<[Vec2; 3]>,
    /// The cameras its model files define, in file order (`Overrides::camera` picks one).
    pub cameras: Vec<FileCamera>,
    /// Whether the scene file set the image size: a model file's camera aspect then leaves it.
    pub size_given: bool,
    /// What loading skipped or could not honour, for the user (never an error).
    pub warnings: Vec<String>,
    /// Directional lights not yet placed among [`Scene::lights`]
    /// ([`Scene::place_directional_lights`], once the geometry is known).
    pub directional: Vec<Directional>,
}

/// A scene's request for indirect light from virtual point lights: how many, and how they are
/// placed and clamped. The renderer's configuration decides how their visibility is computed
/// (rays for the reference, maps for the hybrid).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndirectSettings {
    /// Light paths over all lights (thesis: 45).
    pub vpls: u32,
    /// Diffuse bounces per path, each leaving a VPL.
    pub bounces: u32,
    /// Offset into the Halton sequence.
    pub seed: u32,
    /// `d_min` as a fraction of the scene's bounding-box diagonal; `None`: the renderer's
    /// default.
    pub clamp: Option<f32>,
}

/// Geometry as a loader produces it, before it is placed in a scene.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub positions: Vec<[Vec3; 3]>,
    /// Per-corner normals; `None` where the source had none for that triangle.
    pub normals: Vec<Option<[Vec3; 3]>>,
    /// Index into `materials`.
    pub material: Vec<u32>,
    pub materials: Vec<Material>,
    pub ranges: Vec<MeshRange>,
    /// Per triangle, its corners' texture coordinates, where the file gave them.
    pub uvs: Vec<Option<[Vec2; 3]>>,
    /// The textures its materials read (their `texture` indexes this list).
    pub textures: Vec<texture::Texture>,
    /// The alpha masks its materials' cut-outs read (their `cutout.mask` indexes this list).
    pub masks: Vec<cutout::Mask>,
    /// Cameras the file defines (glTF), in the file's camera order.
    pub cameras: Vec<FileCamera>,
    /// Point lights the file defines (glTF `KHR_lights_punctual`).
    pub lights: Vec<PointLight>,
    /// Directional lights the file defines.
    pub directional: Vec<Directional>,
    /// What the loader skipped or could not honour.
    pub warnings: Vec<String>,
}

impl MeshData {
    /// Applies an affine transform (normals by the inverse transpose; cameras and lights
    /// move with the geometry).
    pub fn transform(&mut self, m: Mat4) {
        for c in &mut self.cameras {
            let cam = &mut c.camera;
            (cam.eye, cam.forward, cam.up) =
                (m.transform_point3(cam.eye), m.transform_vector3(cam.forward), m.transform_vector3(cam.up));
        }
        for l in &mut self.lights {
            l.position = m.transform_point3(l.position);
            if let Some(s) = &mut l.spot {
                s.axis = m.transform_vector3(s.axis).normalize_or_zero();
            }
        }
        for d in &mut self.directional {
            d.direction = m.transform_vector3(d.direction);
        }
        let n = m.inverse().transpose();
        for t in &mut self.positions {
            for p in t.iter_mut() {
                *p = m.transform_point3(*p);
            }
        }
        for t in self.normals.iter_mut().flatten() {
            for v in t.iter_mut() {
                *v = n.transform_vector3(*v).normalize_or_zero();
            }
        }
    }
}

impl Scene {
    /// An empty scene with a name.
    pub fn new(name: &str) -> Self {
        Self { name: name.to_string(), ..Default::default() }
    }

    pub fn triangle_count(&self) -> usize {
        self.positions.len()
    }

    /// Adds a material and returns its id.
    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        (self.materials.len() - 1) as u32
    }

    /// Appends loaded geometry, with the cameras, lights and warnings of its file; its material
    /// ids are remapped after this scene's own.
    pub fn add_mesh(&mut self, mesh: MeshData) {
        let mat_base = self.materials.len() as u32;
        let tri_base = self.positions.len() as u32;
        self.cameras.extend(mesh.cameras);
        self.lights.extend(mesh.lights);
        self.directional.extend(mesh.directional);
        self.warnings.extend(mesh.warnings);
        let tex_base = self.textures.len() as u32;
        let mask_base = self.masks.len() as u32;
        self.materials.extend(mesh.materials.into_iter().map(|mut m| {
            m.texture = m.texture.map(|t| t + tex_base);
            if let Some(c) = &mut m.cutout {
                c.mask = c.mask.map(|k| k + mask_base);
            }
            m
        }));
        self.textures.extend(mesh.textures);
        self.masks.extend(mesh.masks);
        if !self.textures.is_empty() || !self.masks.is_empty() {
            // Coordinates for every triangle once any texture exists (zero where none).
            self.uvs.resize(tri_base as usize, [Vec2::ZERO; 3]);
            let n = mesh.positions.len();
            self.uvs.extend((0..n).map(|i| mesh.uvs.get(i).copied().flatten().unwrap_or([Vec2::ZERO; 3])));
        }
        for (i, t) in mesh.positions.iter().enumerate() {
            let n = mesh.normals.get(i).copied().flatten();
            self.push_triangle(*t, n, mat_base + mesh.material[i]);
        }
        for r in mesh.ranges {
            self.meshes.push(MeshRange { first: r.first + tri_base, ..r });
        }
    }

    /// Appends one triangle; without corner normals, the geometric normal is used.
    pub fn push_triangle(&mut self, p: [Vec3; 3], n: Option<[Vec3; 3]>, material: u32) {
        let n = n.unwrap_or_else(|| {
            let g = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            [g; 3]
        });
        self.positions.push(p);
        self.normals.push(n);
        self.material.push(material);
    }

    /// Appends a quad `a b c d` (counter-clockwise) as two triangles.
    pub fn push_quad(&mut self, q: [Vec3; 4], material: u32) {
        self.push_triangle([q[0], q[1], q[2]], None, material);
        self.push_triangle([q[0], q[2], q[3]], None, material);
    }

    /// The diffuse albedo at barycentrics `bary` of triangle `tri`, hit at distance `t` along
    /// a ray making cosine `cos` with its normal: the material's `diffuse`, times its texture
    /// at the level the footprint of one pixel of the scene's camera asks for there
    /// ([`texture::footprint`]; for rays that are not the camera's, their own length stands
    /// for the distance). Exactly `diffuse` for a material without a texture.
    pub fn albedo(&self, tri: u32, bary: [f32; 3], t: f32, cos: f32) -> Vec3 {
        self.colours(tri, bary, t, cos).0
    }

    /// [`Scene::albedo`], and the highlight's reflectance there: the material's `highlight`,
    /// its base-colour part ([`Material::highlight_base`]) times the texture. Both exactly the
    /// material's without a texture.
    pub fn colours(&self, tri: u32, bary: [f32; 3], t: f32, cos: f32) -> (Vec3, Vec3) {
        let m = &self.materials[self.material[tri as usize] as usize];
        let Some(k) = m.texture else { return (m.diffuse, m.highlight) };
        let (Some(tex), Some(uv)) = (self.textures.get(k as usize), self.uvs.get(tri as usize)) else {
            return (m.diffuse, m.highlight);
        };
        let at = uv[0] * bary[0] + uv[1] * bary[1] + uv[2] * bary[2];
        let w2 = texture::footprint_squared(t, self.pixel_angle(), cos, &self.positions[tri as usize], uv);
        let c = tex.sample_squared(at, w2);
        (m.diffuse * c, m.highlight + m.highlight_base * (c - Vec3::ONE))
    }

    /// The angle one pixel of the camera subtends vertically (radians, at the image's centre);
    /// 0 without a camera.
    pub fn pixel_angle(&self) -> f32 {
        self.camera.map_or(0.0, |c| pixel_angle(c.fov_y_deg, self.settings.height))
    }

    /// Axis-aligned bounds of all triangles, `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.positions.iter().flatten();
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
    }

    /// A short human name for messages: the source path or the scene name.
    pub fn origin(&self) -> String {
        match &self.source {
            Some(p) => p.display().to_string(),
            None => format!("built-in scene '{}'", self.name),
        }
    }

    /// Places the pending directional lights ([`Scene::directional`]) among the lights, as
    /// [`Directional`] says, after the others; without geometry (no bounds) they are dropped.
    pub fn place_directional_lights(&mut self) {
        let Some((lo, hi)) = self.bounds() else {
            self.directional.clear();
            return;
        };
        let centre = (lo + hi) * 0.5;
        let d = SUN_DISTANCE * (hi - lo).length().max(f32::MIN_POSITIVE.sqrt());
        for sun in std::mem::take(&mut self.directional) {
            let dir = sun.direction.normalize_or_zero();
            self.lights.push(PointLight {
                position: centre - dir * d,
                intensity: sun.irradiance * (d * d),
                spot: None,
            });
        }
    }

    /// Views the scene through camera `n` of its model files ([`Scene::cameras`]); unless the
    /// image size was given, the image takes the camera's aspect (its width kept).
    pub fn use_file_camera(&mut self, n: usize) -> Result<()> {
        let Some(c) = self.cameras.get(n) else {
            let list = if self.cameras.is_empty() {
                "its files define none".to_string()
            } else {
                let names: Vec<String> =
                    self.cameras.iter().enumerate().map(|(i, c)| format!("{i}: {}", c.label)).collect();
                format!("its cameras are {}", names.join(", "))
            };
            bail!("{}: there is no camera {n}: {list}", self.origin());
        };
        self.camera = Some(c.camera);
        if let Some(a) = c.aspect.filter(|a| a.is_finite() && *a > 0.0)
            && !self.size_given
        {
            self.settings.height = ((self.settings.width as f32 / a).round() as u32).max(1);
        }
        Ok(())
    }

    /// An exposure for the scene's lights: a white diffuse surface at the centre of the bounds
    /// facing them shows radiance about 1 (the irradiance there, `sum I / d^2` of the brightest
    /// channel, times the exposure, is about pi). For model files that bring their own lights
    /// in physical units, whose brightness no scene file has set an exposure for. `None`
    /// without bounds or lit points.
    pub fn exposure_for_lights(&self) -> Option<f32> {
        let (lo, hi) = self.bounds()?;
        let centre = (lo + hi) * 0.5;
        let scale = (hi - lo).length().max(f32::MIN_POSITIVE.sqrt());
        let e: f32 = self
            .lights
            .iter()
            // At least a hundredth of the scene's size away: a light at the centre is not infinite.
            .map(|l| {
                l.intensity.max_element() / (l.position - centre).length_squared().max((scale * 0.01).powi(2))
            })
            .sum();
        let x = std::f32::consts::PI / e;
        (x.is_finite() && x > 0.0).then_some(x)
    }

    /// Frames the scene with an automatic camera and one light when it has none (used for
    /// bare mesh files): the camera looks at the bounds' centre from the front (+Z) and
    /// slightly above, the light sits at the camera (the automatic one or the scene's own),
    /// bright enough for an irradiance of about pi at the centre (a white diffuse surface
    /// facing it shows radiance ~1).
    pub fn frame_automatically(&mut self) {
        let Some((lo, hi)) = self.bounds() else { return };
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(f32::MIN_POSITIVE.sqrt());
        let fov_y = 45.0f32;
        // Distance at which a sphere of this radius fits the vertical field of view.
        let dist = radius / (fov_y.to_radians() * 0.5).sin();
        let dir = Vec3::new(0.0, 0.35, 1.0).normalize();
        let eye = centre + dir * dist;
        let camera = *self.camera.get_or_insert(Camera::look_at(eye, centre, Vec3::Y, fov_y));
        if self.lights.is_empty() {
            // Beside the camera (the automatic one or the scene's own): what it sees is lit.
            let up = camera.up.normalize_or(Vec3::Y);
            let pos = camera.eye + up * radius * 0.5;
            let d2 = (pos - centre).length_squared();
            self.lights.push(PointLight {
                position: pos,
                intensity: Vec3::splat(std::f32::consts::PI * d2),
                spot: None,
            });
        }
    }

    /// Checks everything a renderer relies on; the error ([`ErrorKind::Invalid`]) names the
    /// scene's origin.
    pub fn validate(&self) -> std::result::Result<(), SceneError> {
        self.check()
            .map_err(|e| SceneError::new(ErrorKind::Invalid, self.source.as_deref(), None, format!("{e:#}")))
    }

    fn check(&self) -> Result<()> {
        let origin = self.origin();
        if self.positions.is_empty() {
            bail!("{origin}: the scene has no triangles");
        }
        if let Some((i, _)) =
            self.positions.iter().enumerate().find(|(_, t)| !t.iter().all(|p| p.is_finite()))
        {
            let mesh = self.mesh_of(i as u32).map(|m| format!(" (mesh '{}')", m.name)).unwrap_or_default();
            bail!("{origin}: triangle {i}{mesh} has a NaN or infinite vertex coordinate");
        }
        if let Some((i, _)) = self.normals.iter().enumerate().find(|(_, t)| !t.iter().all(|n| n.is_finite()))
        {
            bail!("{origin}: triangle {i} has a NaN or infinite normal");
        }
        for (i, l) in self.lights.iter().enumerate() {
            if !l.position.is_finite() || !l.intensity.is_finite() || l.intensity.min_element() < 0.0 {
                bail!("{origin}: light {i} has a non-finite position or a negative/non-finite intensity");
            }
            if let Some(s) = l.spot
                && !(s.axis.is_finite()
                    && s.axis != Vec3::ZERO
                    && s.cos_outer.is_finite()
                    && s.cos_inner.is_finite()
                    && s.cos_inner >= s.cos_outer)
            {
                bail!("{origin}: spot light {i} has no direction or a non-finite cone");
            }
        }
        for m in &self.materials {
            if let Err(e) = m.check() {
                bail!("{origin}: material '{}': {e}", m.name);
            }
        }
        let s = &self.settings;
        if s.width == 0 || s.height == 0 {
            bail!("{origin}: image size {}x{} is empty", s.width, s.height);
        }
        if !(s.exposure.is_finite() && s.exposure > 0.0) {
            bail!("{origin}: exposure must be a positive number, got {}", s.exposure);
        }
        let Some(cam) = &self.camera else { bail!("{origin}: the scene has no camera") };
        validate_camera(cam).map_err(|e| anyhow::anyhow!("{origin}: degenerate camera: {e}"))?;
        Ok(())
    }

    /// The mesh range containing triangle `tri`.
    pub fn mesh_of(&self, tri: u32) -> Option<&MeshRange> {
        self.meshes.iter().find(|m| tri >= m.first && tri < m.first + m.count)
    }

    /// Path of the scene file's directory, for resolving relative mesh paths.
    pub fn base_dir(&self) -> Option<&Path> {
        self.source.as_deref().and_then(Path::parent)
    }
}

fn validate_camera(c: &Camera) -> std::result::Result<(), String> {
    if !(c.eye.is_finite() && c.forward.is_finite() && c.up.is_finite()) {
        return Err("non-finite eye, direction or up".into());
    }
    if c.forward.length_squared() <= f32::MIN_POSITIVE {
        return Err("eye and target coincide (no viewing direction)".into());
    }
    if c.forward.normalize().cross(c.up.normalize_or_zero()).length_squared() < 1e-10 {
        return Err("up vector is zero or parallel to the viewing direction".into());
    }
    let ok = |f: f32| f.is_finite() && f > 0.0 && f < 180.0;
    if !ok(c.fov_y_deg) || !c.fov_x_deg.is_none_or(ok) {
        return Err("field of view must be in (0, 180) degrees".into());
    }
    Ok(())
}

/// Loads geometry from a mesh file, choosing the loader by extension
/// (`.obj`, `.obj.gz`, `.gltf`, `.glb`).
pub fn load_mesh(path: &Path) -> Result<MeshData> {
    let name = path.file_name().map(|n| n.to_string_lossy().to_lowercase()).unwrap_or_default();
    if name.ends_with(".obj") || name.ends_with(".obj.gz") {
        obj::load(path)
    } else if name.ends_with(".gltf") || name.ends_with(".glb") {
        gltf::load(path)
    } else {
        bail!(SceneError::new(
            ErrorKind::Unsupported,
            Some(path),
            None,
            format!("{}: unknown mesh format (expected .obj, .obj.gz, .gltf or .glb)", path.display())
        ))
    }
}

/// Resolves what the CLI was given: a built-in scene name, a `.toml` scene file, or a bare mesh
/// file (which gets an automatic camera and light). The result is validated.
pub fn load(spec: &str) -> std::result::Result<Scene, SceneError> {
    let file = builtin::by_name(spec).is_none().then(|| Path::new(spec));
    load_untyped(spec).map_err(|e| SceneError::from_chain(&e, file))
}

fn load_untyped(spec: &str) -> Result<Scene> {
    let scene = if let Some(s) = builtin::by_name(spec) {
        s
    } else {
        let path = Path::new(spec);
        let lower = spec.to_lowercase();
        if lower.ends_with(".toml") {
            file::load(path)?
        } else if ["obj", "obj.gz", "gltf", "glb"].iter().any(|e| lower.ends_with(&format!(".{e}"))) {
            let mut scene =
                Scene::new(&path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default());
            scene.source = Some(path.to_path_buf());
            scene.add_mesh(load_mesh(path)?);
            scene.place_directional_lights();
            // The file's own camera and lights first; what it lacks is made up.
            if !scene.cameras.is_empty() {
                scene.use_file_camera(0)?;
            }
            if !scene.lights.is_empty()
                && let Some(e) = scene.exposure_for_lights()
            {
                scene.settings.exposure = e;
            }
            scene.frame_automatically();
            scene
        } else {
            bail!(SceneError::new(
                ErrorKind::UnknownScene,
                None,
                None,
                format!(
                    "unknown scene '{spec}': not a built-in scene ({}) nor a .toml, .obj, .obj.gz, .gltf or .glb file",
                    builtin::NAMES.join(", ")
                )
            ));
        }
    };
    scene.validate()?;
    Ok(scene)
}

/// A scene's render settings overridden by a caller (the command line, the inspector).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Image width and height.
    pub size: Option<(u32, u32)>,
    pub max_depth: Option<u32>,
    pub exposure: Option<f32>,
    /// View through this camera of the scene's model files ([`Scene::use_file_camera`]).
    pub camera: Option<usize>,
}

/// [`load`], with some render settings overridden, validated again with them.
pub fn load_with(spec: &str, o: Overrides) -> std::result::Result<Scene, SceneError> {
    let mut scene = load(spec)?;
    if let Some(n) = o.camera {
        scene.use_file_camera(n).map_err(|e| SceneError::from_chain(&e, scene.source.as_deref()))?;
    }
    let s = &mut scene.settings;
    if let Some((w, h)) = o.size {
        (s.width, s.height) = (w, h);
    }
    s.max_depth = o.max_depth.unwrap_or(s.max_depth);
    s.exposure = o.exposure.unwrap_or(s.exposure);
    scene.validate()?;
    Ok(scene)
}

impl Scene {
    /// The materials that at least one triangle uses, in material order.
    pub fn materials_in_use(&self) -> Vec<&Material> {
        let mut used = vec![false; self.materials.len()];
        for &m in &self.material {
            if let Some(u) = used.get_mut(m as usize) {
                *u = true;
            }
        }
        self.materials.iter().zip(used).filter(|(_, u)| *u).map(|(m, _)| m).collect()
    }
}
