//! The material model: a Lambertian diffuse term, a normalised Blinn-Phong highlight for point
//! lights, and a perfect mirror that spawns the Whitted reflection ray; and how MTL and glTF
//! materials are read into it.
//!
//! # Reflection of a point light
//!
//! A point light of intensity `I` (W/sr) at distance `d`, in direction `wi` from a surface
//! point with shading normal `n`, seen from direction `wo`, adds the radiance
//!
//! ```text
//! L = V * I / d^2 * cos_i * f(wi, wo),        cos_i = n . wi,  V = 1 if the light is visible
//! f = Kd / pi  +  Ks * (Ns + 8) / (8 pi) * max(0, n . h)^Ns,    h = normalize(wi + wo)
//! ```
//!
//! The first term is the Lambertian BRDF of albedo `Kd`. The second is Blinn-Phong's lobe
//! (Blinn 1977; the MTL format's own highlight, `Ks (N . H)^Ns`, is written with the half
//! vector too), scaled so that its directional albedo, `int f cos_i dw`, is close to `Ks` for
//! every exponent: the exact factor for the lobe times `cos_i` is
//! `(Ns + 2)(Ns + 4) / (8 pi (2^(-Ns/2) + Ns))`, and `(Ns + 8) / (8 pi)` is its usual bound
//! (Akenine-Moller, Haines and Hoffman, Real-Time Rendering, 3rd ed., section 7.6; the exact
//! factor, for a viewer along the normal, is F. Giesen's 2009 derivation). The bound equals the
//! exact factor at `Ns = 0` (both `1 / pi`), exceeds it by at most 7.5 % (near `Ns = 9`) and by
//! less than 2 % from `Ns = 100` on. Normalised, `Ks` says how much light the highlight reflects and `Ns` only how
//! focused it is, so `Kd + Ks <= 1` keeps a surface from reflecting more than it receives, and
//! `Ks` means what the MGF `rs` and glTF's `F0` it is read from mean: a reflectance. The
//! unnormalised form (the MTL's formula as written, which has neither the `pi` nor `cos_i` of
//! a radiometric renderer) would dim a highlight as `Ns` grows and make the same `Ks` mean
//! another energy at every exponent.
//!
//! The highlight is the reflection of the point lights, which rays can never meet; the mirror
//! term (`Kr`, below) is the reflection of surfaces, which the Whitted ray meets. Reference and
//! hybrid both shade with this one BRDF (`direct::shade`), so their images differ only where their
//! visibility differs. Virtual point lights (indirect light) light the diffuse term only, as in
//! instant radiosity: their gather stays a sum of smooth terms.
//!
//! # Reading MTL
//!
//! - `illum 2` or no `illum`: diffuse `Kd`, highlight `Ks` with exponent `Ns`, no reflection
//!   ray. A material without `Ns` gets [`DEFAULT_SHININESS`].
//! - `illum 0` and `1`: the MTL's models without a highlight (`0` is a constant colour, which a
//!   lit renderer cannot show; it is read as diffuse): `Kd` only, `Ks` ignored.
//! - `illum 3` and up: `Ks` is the mirror reflectance `Kr`, beside `Kd`; a material with
//!   `Kd 0` is a perfect mirror. There is no highlight: the mirror image of a point light is a
//!   point, which a lobe of finite `Ns` would smear into a blob whose size is set by `Ns`
//!   (`Ns 10000` makes a disc of a few degrees), and a scene file can add one where wanted.
//!   Refraction is out of scope: the glass and Fresnel models `4` to `7` are read as `3`
//!   (reflection only, no transmitted ray), so a window of `illum 7` glass is an opaque partial
//!   mirror; scene files leave such panes out (`exclude_materials`).
//!
//! # Reading glTF metallic-roughness
//!
//! With base colour `c`, metallic `m` and roughness `r` (the factors; a base colour texture
//! multiplies `c` in the diffuse term and in the highlight's `F0`, `src/scene/texture.rs`, but
//! not a smooth metal's mirror reflectance):
//!
//! - the diffuse albedo is `c (1 - m)`, and the specular reflectance `F0 = 0.04 (1 - m) + c m`
//!   (the glTF specification's mix of a dielectric's 4 % and the metal's colour);
//! - a smooth metal (`m >= 0.5` and `r <= 0.2`, see [`GLTF_MIRROR_ROUGHNESS`]) is a mirror of
//!   reflectance `F0`, with no highlight;
//! - anything else has a highlight of `F0` whose exponent is the Blinn-Phong equivalent of the
//!   GGX/Beckmann width `alpha = r^2`: `Ns = 2 / alpha^2 - 2` (Walter et al. 2007), capped at
//!   [`MAX_SHININESS`].

use std::fmt;

use glam::Vec3;

/// Exponent of an MTL highlight when the material gives no `Ns`: the MTL format sets no
/// default; this is tinyobjloader's (of which `tobj` is the Rust port): a broad lobe.
pub const DEFAULT_SHININESS: f32 = 1.0;

/// The largest exponent the glTF mapping produces (`r -> 0` would give infinity).
pub const MAX_SHININESS: f32 = 10_000.0;

/// A glTF metal (`metallic >= 0.5`) at most this rough is read as a mirror. At `r = 0.2` the
/// equivalent Blinn-Phong exponent is about 1250: a lobe of about 2 degrees, already below
/// what the mirror's point-light image would show at a few hundred pixels across.
pub const GLTF_MIRROR_ROUGHNESS: f32 = 0.2;

/// How a surface reflects light (see the module docs for the model).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse albedo `Kd` per RGB channel.
    pub diffuse: Vec3,
    /// Highlight reflectance `Ks` per channel (normalised Blinn-Phong, point lights only).
    pub highlight: Vec3,
    /// Highlight exponent `Ns` (`>= 0`).
    pub shininess: f32,
    /// Mirror reflectance `Kr` per channel: the weight of the Whitted reflection ray.
    pub mirror: Vec3,
    /// Why the material has a mirror reflectance (shown by the plan); meaningless without one.
    pub mirror_source: MirrorSource,
    /// The texture that multiplies `diffuse` (an index into the scene's textures; MTL
    /// `map_Kd`, glTF `baseColorTexture`), if any.
    pub texture: Option<u32>,
    /// The part of `highlight` that is the base colour, which the texture multiplies too: a
    /// glTF metal's `base m` (its highlight is `0.04 (1 - m) + base m`); zero otherwise.
    pub highlight_base: Vec3,
    /// Holes drawn by an alpha mask (MTL `map_d`, glTF `alphaMode` `MASK` or `BLEND`), if any.
    pub cutout: Option<super::cutout::Cutout>,
}

/// Where a material's mirror reflectance came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MirrorSource {
    /// Made in code (built-in scenes, tests).
    Code,
    /// The MTL's illumination model (3 and up).
    Mtl { illum: u8 },
    /// A smooth glTF metal.
    Gltf { metallic: f32, roughness: f32 },
    /// A `[[material]]` override in a scene file.
    SceneFile,
}

impl fmt::Display for MirrorSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MirrorSource::Code => write!(f, "set in code"),
            MirrorSource::Mtl { illum } => write!(f, "MTL illum {illum}"),
            MirrorSource::Gltf { metallic, roughness } => {
                write!(f, "glTF smooth metal: metallic {metallic}, roughness {roughness}")
            }
            MirrorSource::SceneFile => write!(f, "scene file override"),
        }
    }
}

impl Material {
    /// A purely diffuse material of albedo `kd`.
    pub fn matte(name: &str, kd: Vec3) -> Self {
        Self {
            name: name.to_string(),
            diffuse: kd,
            highlight: Vec3::ZERO,
            shininess: DEFAULT_SHININESS,
            mirror: Vec3::ZERO,
            mirror_source: MirrorSource::Code,
            texture: None,
            highlight_base: Vec3::ZERO,
            cutout: None,
        }
    }

    /// A mirror of reflectance `kr` beside a diffuse albedo `kd`, made in code.
    pub fn mirror(name: &str, kd: Vec3, kr: Vec3) -> Self {
        Self { mirror: kr, ..Self::matte(name, kd) }
    }

    /// A diffuse material with a highlight `ks` of exponent `ns`, made in code.
    pub fn glossy(name: &str, kd: Vec3, ks: Vec3, ns: f32) -> Self {
        Self { highlight: ks, shininess: ns, ..Self::matte(name, kd) }
    }

    /// An MTL material as its illumination model means it (see the module docs).
    pub fn from_mtl(name: &str, kd: Vec3, ks: Vec3, ns: Option<f32>, illum: Option<u8>) -> Self {
        let base = Self { shininess: ns.unwrap_or(DEFAULT_SHININESS), ..Self::matte(name, kd) };
        match illum {
            None | Some(2) => Self { highlight: ks, ..base },
            Some(0 | 1) => base,
            Some(illum) => Self { mirror: ks, mirror_source: MirrorSource::Mtl { illum }, ..base },
        }
    }

    /// A glTF metallic-roughness material from its factors (see the module docs).
    pub fn from_gltf(name: &str, base_color: Vec3, metallic: f32, roughness: f32) -> Self {
        let (m, r) = (metallic.clamp(0.0, 1.0), roughness.clamp(0.0, 1.0));
        let kd = base_color * (1.0 - m);
        let f0 = Vec3::splat(0.04 * (1.0 - m)) + base_color * m;
        if m >= 0.5 && r <= GLTF_MIRROR_ROUGHNESS {
            return Self {
                mirror: f0,
                mirror_source: MirrorSource::Gltf { metallic, roughness },
                ..Self::matte(name, kd)
            };
        }
        Self { highlight_base: base_color * m, ..Self::glossy(name, kd, f0, gltf_shininess(r)) }
    }

    /// True when the material spawns reflection rays.
    pub fn is_mirror(&self) -> bool {
        self.mirror.max_element() > 0.0
    }

    /// True when point lights (and so their visibility) matter here: a diffuse term or a
    /// highlight. A perfect mirror has neither; its light arrives by its reflection ray.
    pub fn is_lit(&self) -> bool {
        self.diffuse != Vec3::ZERO || self.highlight != Vec3::ZERO
    }

    /// The highlight's lobe `(Ns + 8) / (8 pi) * max(0, n . h)^Ns` of the module docs, with
    /// `h = normalize(wi + wo)`: `n` the shading normal, `wi` the unit direction to the light,
    /// `wo` the unit direction to the viewer. The BRDF is `Kd / pi + Ks * lobe`.
    #[inline]
    pub fn highlight_lobe(&self, n: Vec3, wi: Vec3, wo: Vec3) -> f32 {
        let n_h = n.dot((wi + wo).normalize_or_zero());
        if n_h <= 0.0 {
            return 0.0;
        }
        (self.shininess + 8.0) * (std::f32::consts::FRAC_1_PI / 8.0) * n_h.powf(self.shininess)
    }

    /// True when the material has a highlight.
    pub fn has_highlight(&self) -> bool {
        self.highlight != Vec3::ZERO
    }

    /// The first problem with this material's numbers, if any: colours must be finite and
    /// non-negative, the exponent finite and non-negative.
    pub fn check(&self) -> Result<(), String> {
        for (what, c) in [("diffuse", self.diffuse), ("highlight", self.highlight), ("mirror", self.mirror)] {
            if !c.is_finite() || c.min_element() < 0.0 {
                return Err(format!("{what} colour {c} must be finite and >= 0"));
            }
        }
        if !(self.shininess.is_finite() && self.shininess >= 0.0) {
            return Err(format!("highlight exponent {} must be finite and >= 0", self.shininess));
        }
        if let Some(c) = &self.cutout
            && !(c.cutoff.is_finite() && c.cutoff >= 0.0 && c.scale.is_finite() && c.scale >= 0.0)
        {
            return Err(format!(
                "alpha cut-off {} and alpha factor {} must be finite and >= 0",
                c.cutoff, c.scale
            ));
        }
        Ok(())
    }
}

/// The Blinn-Phong exponent equivalent to a glTF roughness `r`: `alpha = r^2`,
/// `Ns = 2 / alpha^2 - 2`, capped at [`MAX_SHININESS`].
pub fn gltf_shininess(roughness: f32) -> f32 {
    let a2 = roughness * roughness * roughness * roughness;
    if a2 <= 2.0 / (MAX_SHININESS + 2.0) { MAX_SHININESS } else { (2.0 / a2 - 2.0).max(0.0) }
}
