//! glTF 2.0 / GLB loading via the gltf crate: geometry, node transforms, material factors,
//! cameras and point lights.
//!
//! **Cameras.** Each perspective camera placed by a node of the scene, in the file's camera
//! order (the first node that places it): the eye at the node's origin, looking down its -Z
//! with +Y up, `yfov` as the vertical field of view and `aspectRatio`, when given, as the
//! image's (`Scene::use_file_camera`). Orthographic cameras and cameras no node places are
//! skipped with a warning.
//!
//! **Textures.** A material's `baseColorTexture` (an external file, a `data:` URI or a buffer
//! view; PNG or JPEG) multiplies its base colour, in the diffuse term and in the highlight's
//! `F0` (`Material::highlight_base`), read at the texture coordinates of its `texCoord` set,
//! transformed by `KHR_texture_transform` when present (`offset`, `rotation` and `scale`, as
//! the specification's matrix does them). A smooth metal's mirror reflectance keeps its
//! factor; metallic-roughness, normal and emissive textures are ignored. An image that cannot
//! be read is a warning; the material keeps its factors.
//!
//! **Alpha.** `alphaMode: MASK` makes a cut-out at `alphaCutoff`: the base colour's alpha
//! (`baseColorFactor[3]` times the texture's alpha channel) decides holes (`super::cutout`).
//! `BLEND` is drawn as a mask at 0.5, with a warning.
//!
//! **Lights** (`KHR_lights_punctual`). Point lights at their node's origin. Their intensity is
//! in candela (lumens per steradian); hyrt's lights are radiometric, in watts per steradian,
//! so it is divided by 683 lm/W (the luminous efficacy that defines the candela, of light of
//! 555 nm) and multiplied by the light's linear `color`. `range` is ignored: light falls off
//! with the square of the distance alone, as the specification allows. Spot lights shine down
//! their node's -Z with the cone's `innerConeAngle` and `outerConeAngle` (and the smooth
//! falloff between them that the specification recommends, `Spot`). Directional lights travel
//! down their node's -Z; their intensity is in lux (lm/m^2), divided by 683 to W/m^2 (they
//! are placed as `Directional` says).
//!
//! The crate is built without its `import` feature, so buffers are resolved here: the GLB binary
//! chunk, external files relative to the glTF file, and base64 `data:` URIs. Every accessor is
//! range-checked before the crate's reader touches it, because the reader assumes valid input
//! (it panics or overflows on short buffers, bad strides or empty accessors).

use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};
use base64::Engine as _;
use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};

use super::cutout::{Channel, Cutout, Mask};
use super::obj::{read_bytes, unit_normals};
use super::texture::{Texture, decode_image as decode_bytes, load_image};
use super::{
    Camera, Directional, ErrorKind, FileCamera, Material, MeshData, MeshRange, PointLight, SceneError, Spot,
};

/// Diffuse colour of the material given to primitives without one.
const DEFAULT_KD: Vec3 = Vec3::splat(0.8);

/// Lumens per watt of light at 555 nm: candela (lm/sr) to W/sr (module docs).
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Required extensions that do not affect geometry; hyrt ignores materials' extensions and
/// textures, and reads the lights it can (module docs), so files requiring them still load.
fn ignorable_extension(name: &str) -> bool {
    name.starts_with("KHR_materials_")
        || matches!(
            name,
            "KHR_texture_transform"
                | "KHR_texture_basisu"
                | "EXT_texture_webp"
                | "EXT_texture_avif"
                | "MSFT_texture_dds"
                | "KHR_lights_punctual"
        )
}

/// An [`ErrorKind::Syntax`] error in `path`: not valid glTF.
fn syntax(path: &Path, what: String) -> SceneError {
    SceneError::new(ErrorKind::Syntax, Some(path), None, what)
}

/// Loads the default scene (or the first scene) of a `.gltf` or `.glb` file, flattened to
/// world space.
///
/// Node transforms are accumulated down the hierarchy; positions are transformed by the world
/// matrix and normals by its inverse transpose, and triangles of mirrored nodes (negative
/// determinant) are re-wound so they stay counter-clockwise. Only `TRIANGLES` primitives are
/// loaded; other modes are skipped. Each glTF material's metallic-roughness factors become a
/// [`Material`] as [`Material::from_gltf`] maps them, its `baseColorTexture` (with its
/// `KHR_texture_transform`) multiplying the base colour (module docs). Each node instance of a mesh becomes a
/// [`MeshRange`] named after the node (or the mesh).
pub fn load(path: &Path) -> Result<MeshData> {
    let shown = path.display();
    let bytes = read_bytes(path)?;
    // The gltf crate subtracts the 12-byte header size from the GLB's declared length unchecked
    // (a panic in debug builds).
    if bytes.starts_with(b"glTF")
        && bytes.get(8..12).is_some_and(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]) < 12)
    {
        bail!(syntax(
            path,
            format!("{shown}: not a valid GLB file: the header declares a length shorter than the header")
        ));
    }
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| syntax(path, format!("{shown}: not a valid glTF or GLB file: {e}")))?;

    // Unsupported required extensions are reported by name before validation, which would only
    // say "Unsupported extension".
    let mut json = document.into_json();
    if let Some(ext) = json.extensions_required.iter().find(|e| !ignorable_extension(e)) {
        let what = match ext.as_str() {
            "KHR_draco_mesh_compression" => {
                " (Draco-compressed geometry; re-export the model without Draco compression)"
            }
            "EXT_meshopt_compression" => {
                " (meshoptimizer-compressed geometry; re-export the model uncompressed)"
            }
            "KHR_mesh_quantization" => " (quantized vertex attributes)",
            _ => "",
        };
        bail!(SceneError::new(
            ErrorKind::Unsupported,
            Some(path),
            None,
            format!("{shown}: requires the glTF extension {ext}, which hyrt does not support{what}")
        ));
    }
    json.extensions_required.clear();
    // gltf-json's validation reads each primitive's POSITION accessor before checking that the
    // index exists (a panic on an index out of range): check every attribute's index first.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some((_, a)) = prim.attributes.iter().find(|(_, a)| a.value() >= json.accessors.len()) {
                bail!(syntax(
                    path,
                    format!(
                        "{shown}: invalid glTF: meshes[{m}].primitives[{p}] uses accessor {} of {}",
                        a.value(),
                        json.accessors.len()
                    )
                ));
            }
        }
    }
    let document =
        gltf::Document::from_json(json).map_err(|e| syntax(path, format!("{shown}: invalid glTF: {e}")))?;
    let buffers = load_buffers(path, &document, blob)?;

    // Each image decoded once, whichever materials read it; one that cannot be read leaves
    // its materials with their factors, each with a warning.
    let mut textures = Vec::new();
    let mut images: Vec<Option<std::result::Result<(u32, ImageMask), String>>> =
        (0..document.images().len()).map(|_| None).collect();
    let mut masks = Vec::new();
    let mut warnings = Vec::new();
    let mut uv_maps = Vec::new();
    let mut materials = Vec::new();
    for m in document.materials() {
        let pbr = m.pbr_metallic_roughness();
        let c = pbr.base_color_factor();
        let name = m.name().map_or_else(|| format!("material{}", m.index().unwrap_or(0)), str::to_string);
        let mut mat = Material::from_gltf(
            &name,
            Vec3::new(c[0], c[1], c[2]),
            pbr.metallic_factor(),
            pbr.roughness_factor(),
        );
        // A mask is a cut-out (`cutout` module); blending is read as a mask at 0.5, and said.
        let cutoff = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => None,
            gltf::material::AlphaMode::Mask => Some(m.alpha_cutoff().unwrap_or(Cutout::DEFAULT_CUTOFF)),
            gltf::material::AlphaMode::Blend => {
                warnings.push(format!(
                    "{shown}: material '{name}' has alphaMode BLEND: hyrt draws it as a cut-out at alpha {} (no transparency)",
                    Cutout::DEFAULT_CUTOFF
                ));
                Some(Cutout::DEFAULT_CUTOFF)
            }
        };
        mat.cutout = cutoff.map(|cutoff| Cutout { mask: None, scale: c[3], cutoff });
        let mut uv_map = None;
        if let Some(info) = pbr.base_color_texture() {
            let image = info.texture().source();
            let got = images[image.index()].get_or_insert_with(|| {
                decode_image(path, &image, &buffers).map(|(t, mask)| {
                    textures.push(t);
                    (textures.len() as u32 - 1, mask)
                })
            });
            match got {
                Ok((k, mask)) => {
                    mat.texture = Some(*k);
                    uv_map = Some(UvMap::of(&info));
                    if let Some(c) = &mut mat.cutout {
                        // The image's alpha, made a mask once, for the first material that asks.
                        if let ImageMask::Unused(m) = std::mem::replace(mask, ImageMask::None) {
                            masks.push(m);
                            *mask = ImageMask::At(masks.len() as u32 - 1);
                        }
                        c.mask = match mask {
                            ImageMask::At(k) => Some(*k),
                            _ => None,
                        };
                    }
                }
                Err(e) => warnings.push(format!(
                    "{shown}: material '{name}': baseColorTexture: {e}; it is rendered with its factors"
                )),
            }
        }
        materials.push(mat);
        uv_maps.push(uv_map);
    }
    let draco_used = document.extensions_used().any(|e| e == "KHR_draco_mesh_compression");
    let mut loader = Loader {
        draco_used,
        path,
        buffers: &buffers,
        uv_maps,
        mesh: MeshData { materials, textures, masks, warnings, ..Default::default() },
        default_material: None,
        skipped: 0,
    };

    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            // No scene at all: show every node tree once.
            let mut is_child = vec![false; document.nodes().len()];
            for c in document.nodes().flat_map(|n| n.children()) {
                is_child[c.index()] = true;
            }
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    // Depth-first, children in file order. glTF requires the node graph to be a forest, so a
    // node reached twice means a cycle (or a shared child): rejected rather than looped over.
    let mut visited = vec![false; document.nodes().len()];
    // Each camera as the first node that places it sees it, by camera index.
    let mut cameras: Vec<Option<Result<FileCamera, String>>> = vec![None; document.cameras().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            bail!("{shown}: node {} is reached twice (the node hierarchy must be a tree)", node.index());
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            loader.add_instance(&node, &mesh, world)?;
        }
        if let Some(cam) = node.camera()
            && let Some(slot @ None) = cameras.get_mut(cam.index())
        {
            *slot = Some(file_camera(&cam, world));
        }
        if let Some(light) = node.light() {
            loader.add_light(&light, world);
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    for (cam, placed) in document.cameras().zip(cameras) {
        match placed {
            Some(Ok(c)) => loader.mesh.cameras.push(c),
            Some(Err(why)) => {
                loader.mesh.warnings.push(format!("{shown}: {} {why}: skipped", camera_label(&cam)))
            }
            None => loader
                .mesh
                .warnings
                .push(format!("{shown}: {} is placed by no node: skipped", camera_label(&cam))),
        }
    }

    let Loader { mesh, skipped, .. } = loader;
    if mesh.positions.is_empty() {
        let what = if skipped > 0 {
            format!(
                "{shown}: has no triangles: {skipped} primitive(s) skipped because they are points, lines, strips or fans (only TRIANGLES is supported)"
            )
        } else {
            format!("{shown}: has no triangles")
        };
        bail!(SceneError::new(ErrorKind::Invalid, Some(path), None, what));
    }
    Ok(mesh)
}

/// How messages name camera `cam`: its index and, if it has one, its name.
fn camera_label(cam: &gltf::Camera) -> String {
    match cam.name() {
        Some(n) => format!("camera {} '{n}'", cam.index()),
        None => format!("camera {}", cam.index()),
    }
}

/// Camera `cam` placed by a node with world transform `world` (module docs), or why not.
fn file_camera(cam: &gltf::Camera, world: Mat4) -> std::result::Result<FileCamera, String> {
    match cam.projection() {
        gltf::camera::Projection::Perspective(p) => Ok(FileCamera {
            label: camera_label(cam),
            camera: Camera {
                eye: world.transform_point3(Vec3::ZERO),
                forward: world.transform_vector3(Vec3::NEG_Z),
                up: world.transform_vector3(Vec3::Y),
                fov_y_deg: p.yfov().to_degrees(),
                fov_x_deg: None,
            },
            aspect: p.aspect_ratio(),
        }),
        gltf::camera::Projection::Orthographic(_) => {
            Err("is orthographic (hyrt has perspective cameras only)".to_string())
        }
    }
}

/// Which texture coordinates a material's base colour texture reads, and how they are
/// transformed (`KHR_texture_transform`: `uv' = offset + R(rotation) (scale uv)`, `R` the
/// specification's `[[cos, -sin], [sin, cos]]`).
#[derive(Clone, Copy, Debug)]
struct UvMap {
    set: u32,
    offset: Vec2,
    cos_sin: Vec2,
    scale: Vec2,
}

impl UvMap {
    fn of(info: &gltf::texture::Info) -> Self {
        match info.texture_transform() {
            Some(t) => Self {
                set: t.tex_coord().unwrap_or(info.tex_coord()),
                offset: Vec2::from(t.offset()),
                cos_sin: Vec2::new(t.rotation().cos(), t.rotation().sin()),
                scale: Vec2::from(t.scale()),
            },
            None => Self { set: info.tex_coord(), offset: Vec2::ZERO, cos_sin: Vec2::X, scale: Vec2::ONE },
        }
    }

    fn apply(&self, uv: Vec2) -> Vec2 {
        let s = uv * self.scale;
        let (c, n) = (self.cos_sin.x, self.cos_sin.y);
        self.offset + Vec2::new(c * s.x - n * s.y, n * s.x + c * s.y)
    }
}

/// Decodes image `image` of the file at `path` (an external file, a `data:` URI or a buffer
/// view), or says why not.
/// An image's alpha channel as a cut-out mask: kept until a material asks for it, then its
/// index among the file's masks.
enum ImageMask {
    /// No alpha channel: no holes.
    None,
    Unused(Mask),
    At(u32),
}

/// Decodes image `image` to a colour texture, and its alpha channel (if it has one) to a mask.
fn decode_image(
    path: &Path,
    image: &gltf::Image,
    buffers: &[Vec<u8>],
) -> std::result::Result<(Texture, ImageMask), String> {
    let name = format!("image {}", image.index());
    let decoded = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let data =
                buffers.get(view.buffer().index()).ok_or_else(|| format!("{name}: its buffer is missing"))?;
            let bytes = view
                .offset()
                .checked_add(view.length())
                .and_then(|end| data.get(view.offset()..end))
                .ok_or_else(|| format!("{name}: its buffer view lies outside the buffer"))?;
            decode(&name, bytes)
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(rest) => decode(&name, &decode_data_uri(rest).map_err(|e| format!("{name}: {e}"))?),
            None => {
                let file = path.parent().unwrap_or(Path::new("")).join(percent_decode(uri));
                load_image(&file).map(|img| (file.display().to_string(), img))
            }
        },
    };
    let (name, img) = decoded.map_err(|e| format!("{e:#}"))?;
    let texture = Texture::from_image(&name, &img).map_err(|e| format!("{e:#}"))?;
    let mask = Mask::from_image(&name, &img, Channel::Alpha).map_or(ImageMask::None, ImageMask::Unused);
    Ok((texture, mask))
}

/// An encoded image named `name`, decoded.
fn decode(name: &str, bytes: &[u8]) -> Result<(String, image::DynamicImage)> {
    decode_bytes(name, bytes).map(|img| (name.to_string(), img))
}

/// Flattening state while walking the node tree.
struct Loader<'a> {
    path: &'a Path,
    buffers: &'a [Vec<u8>],
    /// Per material, its base colour texture's coordinates, if it has one.
    uv_maps: Vec<Option<UvMap>>,
    mesh: MeshData,
    /// Index of the lazily added default material.
    default_material: Option<u32>,
    /// Primitives skipped because their mode is not `TRIANGLES`.
    skipped: usize,
    /// The file uses (without requiring) Draco: accessors without data are probably compressed.
    draco_used: bool,
}

impl Loader<'_> {
    /// Adds a `KHR_lights_punctual` light placed by `world`: a point, spot or directional
    /// light (module docs).
    fn add_light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4) {
        use gltf::khr_lights_punctual::Kind;
        let intensity = Vec3::from(light.color()) * (light.intensity() / LUMENS_PER_WATT);
        let position = world.transform_point3(Vec3::ZERO);
        let spot = match light.kind() {
            Kind::Point => None,
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                Some(Spot::new(world.transform_vector3(Vec3::NEG_Z), inner_cone_angle, outer_cone_angle))
            }
            Kind::Directional => {
                // Lux (lm/m^2) to W/m^2, as candela to W/sr.
                let irradiance = Vec3::from(light.color()) * (light.intensity() / LUMENS_PER_WATT);
                let direction = world.transform_vector3(Vec3::NEG_Z);
                self.mesh.directional.push(Directional { direction, irradiance });
                return;
            }
        };
        self.mesh.lights.push(PointLight { position, intensity, spot });
    }

    /// Appends one instance of `mesh` (all its triangle primitives) placed by `world`.
    fn add_instance(&mut self, node: &gltf::Node, mesh: &gltf::Mesh, world: Mat4) -> Result<()> {
        let name =
            node.name().or(mesh.name()).map_or_else(|| format!("node{}", node.index()), str::to_string);
        let context = || format!("{}: mesh '{name}'", self.path.display());
        let first = self.mesh.positions.len() as u32;

        let linear = Mat3::from_mat4(world);
        let det = linear.determinant();
        // A singular transform has no normal matrix: those triangles fall back to face normals.
        let normal_matrix = (det.is_finite() && det != 0.0).then(|| linear.inverse().transpose());
        let mirrored = det < 0.0;

        for (k, primitive) in mesh.primitives().enumerate() {
            if primitive.mode() != Mode::Triangles {
                self.skipped += 1;
                continue;
            }
            let PrimitiveData { positions, normals, indices } =
                self.read_primitive(&primitive).with_context(|| format!("{}, primitive {k}", context()))?;
            let material = match primitive.material().index() {
                Some(i) if i < self.mesh.materials.len() => i as u32,
                _ => *self.default_material.get_or_insert_with(|| {
                    self.mesh.materials.push(Material::matte("default", DEFAULT_KD));
                    (self.mesh.materials.len() - 1) as u32
                }),
            };
            // The base colour texture's coordinates, transformed; none (a texture then reads
            // its first texel) where the primitive lacks them.
            let uvs: Option<Vec<Vec2>> =
                self.uv_maps.get(material as usize).copied().flatten().and_then(|map| {
                    let acc = primitive.get(&Semantic::TexCoords(map.set))?;
                    let types = [DataType::F32, DataType::U8, DataType::U16];
                    (acc.count() == positions.len()
                        && check_accessor(&acc, self.buffers, &types, Dimensions::Vec2).is_ok())
                    .then_some(())?;
                    let reader = primitive.reader(|b| self.buffers.get(b.index()).map(Vec::as_slice));
                    Some(
                        reader
                            .read_tex_coords(map.set)?
                            .into_f32()
                            .map(|t| map.apply(Vec2::from(t)))
                            .collect(),
                    )
                });
            for tri in indices.chunks_exact(3) {
                let corner = |i: u32| {
                    positions.get(i as usize).copied().ok_or_else(|| {
                        anyhow!(
                            "{}, primitive {k}: index {i} is out of range ({} vertices)",
                            context(),
                            positions.len()
                        )
                    })
                };
                let mut p =
                    [corner(tri[0])?, corner(tri[1])?, corner(tri[2])?].map(|v| world.transform_point3(v));
                let mut n = match (&normals, normal_matrix) {
                    (Some(ns), Some(m)) => {
                        let get = |i: u32| ns.get(i as usize).map(|v| m * *v);
                        match (get(tri[0]), get(tri[1]), get(tri[2])) {
                            (Some(a), Some(b), Some(c)) => unit_normals([a, b, c]),
                            _ => None,
                        }
                    }
                    _ => None,
                };
                let mut uv = uvs.as_ref().and_then(|u| {
                    Some([*u.get(tri[0] as usize)?, *u.get(tri[1] as usize)?, *u.get(tri[2] as usize)?])
                });
                if mirrored {
                    p.swap(1, 2);
                    if let Some(n) = &mut n {
                        n.swap(1, 2);
                    }
                    if let Some(uv) = &mut uv {
                        uv.swap(1, 2);
                    }
                }
                if !p.iter().all(|v| v.is_finite()) {
                    bail!("{}: a vertex position is NaN or infinite (after node transforms)", context());
                }
                self.mesh.positions.push(p);
                self.mesh.normals.push(n);
                self.mesh.uvs.push(uv);
                self.mesh.material.push(material);
            }
        }
        let count = self.mesh.positions.len() as u32 - first;
        if count > 0 {
            self.mesh.ranges.push(MeshRange { name, first, count });
        }
        Ok(())
    }

    /// Positions, optional normals (when usable) and triangle-list indices of a primitive.
    fn read_primitive(&self, primitive: &gltf::Primitive) -> Result<PrimitiveData> {
        let buffers = self.buffers;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));

        let pos = primitive.get(&Semantic::Positions).ok_or_else(|| anyhow!("no POSITION attribute"))?;
        check_accessor(&pos, buffers, &[DataType::F32], Dimensions::Vec3)?;
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| {
                let hint = if self.draco_used { " (Draco-compressed? hyrt cannot decode Draco)" } else { "" };
                anyhow!("POSITION accessor {} has no data{hint}", pos.index())
            })?
            .map(Vec3::from)
            .collect();

        // Normals are optional: unusable ones fall back to face normals instead of failing.
        let normals = primitive
            .get(&Semantic::Normals)
            .filter(|a| a.count() == positions.len())
            .filter(|a| check_accessor(a, buffers, &[DataType::F32], Dimensions::Vec3).is_ok())
            .and_then(|_| reader.read_normals())
            .map(|it| it.map(Vec3::from).collect::<Vec<_>>());

        let indices: Vec<u32> = match primitive.indices() {
            Some(acc) => {
                check_accessor(
                    &acc,
                    buffers,
                    &[DataType::U8, DataType::U16, DataType::U32],
                    Dimensions::Scalar,
                )?;
                reader
                    .read_indices()
                    .ok_or_else(|| anyhow!("index accessor {} has no data", acc.index()))?
                    .into_u32()
                    .collect()
            }
            None => (0..positions.len() as u32).collect(),
        };
        Ok(PrimitiveData { positions, normals, indices })
    }
}

/// One primitive's vertex data in its mesh's local space.
struct PrimitiveData {
    positions: Vec<Vec3>,
    /// Present only when the primitive has usable normals (one per position).
    normals: Option<Vec<Vec3>>,
    /// Triangle list indices into `positions`.
    indices: Vec<u32>,
}

/// Checks everything the gltf crate's accessor reader assumes: component type and shape, a
/// non-empty count, strides at least one element wide, and all reads inside their buffer view
/// and buffer (including sparse index and value arrays).
fn check_accessor(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    types: &[DataType],
    dims: Dimensions,
) -> Result<()> {
    let i = acc.index();
    if !types.contains(&acc.data_type()) || acc.dimensions() != dims {
        bail!(
            "accessor {i} has type {:?} {:?}, expected {:?} {:?}",
            acc.data_type(),
            acc.dimensions(),
            types,
            dims
        );
    }
    if acc.count() == 0 {
        bail!("accessor {i} is empty");
    }
    let elem = acc.size();
    if let Some(view) = acc.view() {
        check_view(&view, acc.offset(), acc.count(), elem, buffers)
            .with_context(|| format!("accessor {i}"))?;
    }
    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        if n == 0 {
            bail!("accessor {i} has an empty sparse section");
        }
        // Validation guarantees unsigned index types, so `index_type` cannot panic.
        let idx = sparse.indices();
        check_view(&idx.view(), idx.offset(), n, idx.index_type().size(), buffers)
            .with_context(|| format!("accessor {i}, sparse indices"))?;
        let values = sparse.values();
        check_view(&values.view(), values.offset(), n, elem, buffers)
            .with_context(|| format!("accessor {i}, sparse values"))?;
    }
    Ok(())
}

/// `count` elements of `elem` bytes from `offset` inside `view` fit in the view and its buffer.
fn check_view(
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    elem: usize,
    buffers: &[Vec<u8>],
) -> Result<()> {
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        bail!(
            "buffer view {} has a stride of {stride} bytes, less than the element size {elem}",
            view.index()
        );
    }
    let end = count
        .checked_sub(1)
        .and_then(|c| c.checked_mul(stride))
        .and_then(|b| b.checked_add(elem))
        .and_then(|b| b.checked_add(offset));
    if end.is_none_or(|e| e > view.length()) {
        bail!("reads past the end of buffer view {}", view.index());
    }
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    if view.offset().checked_add(view.length()).is_none_or(|e| e > buffer_len) {
        bail!("buffer view {} extends past the end of buffer {}", view.index(), view.buffer().index());
    }
    Ok(())
}

/// The data of every buffer: the GLB binary chunk, `data:` URIs, or files next to the glTF.
fn load_buffers(path: &Path, document: &gltf::Document, blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>> {
    let shown = path.display();
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut blob = blob;
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                anyhow!("{shown}: buffer {i} refers to a GLB binary chunk that the file does not have")
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    decode_data_uri(rest).map_err(|e| anyhow!("{shown}: buffer {i}: {e}"))?
                } else if uri.contains("://") {
                    bail!(
                        "{shown}: buffer {i}: unsupported URI '{uri}' (only relative file names and data: URIs)"
                    );
                } else {
                    read_bytes(&dir.join(percent_decode(uri)))
                        .with_context(|| format!("{shown}: buffer {i}"))?
                }
            }
        };
        if data.len() < buffer.length() {
            bail!("{shown}: buffer {i} has {} bytes, but the file declares {}", data.len(), buffer.length());
        }
        out.push(data);
    }
    Ok(out)
}

/// The payload of a `data:` URI (after the `data:` prefix): base64 or percent-encoded.
fn decode_data_uri(rest: &str) -> Result<Vec<u8>> {
    let (header, payload) = rest.split_once(',').ok_or_else(|| anyhow!("malformed data: URI (no ',')"))?;
    if header.ends_with(";base64") {
        base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| anyhow!("invalid base64 in data: URI: {e}"))
    } else {
        Ok(percent_decode_bytes(payload))
    }
}

/// Decodes `%XX` escapes in a relative URI (glTF URIs are percent-encoded, e.g. `%20`).
fn percent_decode(uri: &str) -> String {
    String::from_utf8_lossy(&percent_decode_bytes(uri)).into_owned()
}

fn percent_decode_bytes(s: &str) -> Vec<u8> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b
            .get(i + 1..i + 3)
            .filter(|h| h.iter().all(u8::is_ascii_hexdigit))
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (b[i], hex) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}
