//! Every strategy and knob of a frame, defined once.
//!
//! [`Options`] holds them, with the reference ([`Options::reference`]) and the hybrid
//! ([`Options::hybrid`]) as its two presets. Each enum's values and their names live in one
//! [`Choice`] impl, and each knob's flag name, help, accepted values and place in [`Options`]
//! live in one entry of [`KNOBS`]. Everything else reads them from here:
//! - the command line (`Knobs`, behind the `clap` feature: flags built from [`KNOBS`], their
//!   help showing both presets' defaults);
//! - the statistics' JSON ([`to_json`]);
//! - `hyrt sweep`'s knob names;
//! - the inspector's menus ([`Choice::ALL`]);
//! - and the knob table of `docs/cli.md`, which a test holds to [`markdown_table`].

use serde_json::Value;

pub use hyrt_shadowmap::{MapKind, MapOptions, vpl_map::VplFormat};

/// An enum knob: its values, in menu order, and each one's name on the command line, in the
/// statistics and in the inspector.
pub trait Choice: Copy + PartialEq + Sized + 'static {
    /// Every value, in menu order.
    const ALL: &'static [Self];
    /// The values' names, in the order of [`Choice::ALL`].
    const NAMES: &'static [&'static str];
    /// Older names still accepted on the command line: (old, current).
    const ALIASES: &'static [(&'static str, &'static str)] = &[];

    /// The value's name.
    fn name(self) -> &'static str {
        let i = Self::ALL.iter().position(|v| *v == self).expect("every value is in ALL");
        Self::NAMES[i]
    }

    /// The value named `name` (or an alias of it).
    fn from_name(name: &str) -> Option<Self> {
        let name = Self::ALIASES.iter().find(|(old, _)| *old == name).map_or(name, |(_, new)| new);
        Self::NAMES.iter().position(|n| *n == name).map(|i| Self::ALL[i])
    }
}

/// Declares an enum knob: the enum, its [`Choice`] impl and its `Serialize` (by name).
macro_rules! choice {
    (
        $(#[$meta:meta])*
        pub enum $name:ident { $( $(#[$vmeta:meta])* $variant:ident = $text:literal ),+ $(,)? }
        $(aliases $($old:literal => $new:literal),+)?
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum $name { $( $(#[$vmeta])* $variant ),+ }

        impl Choice for $name {
            const ALL: &'static [Self] = &[$($name::$variant),+];
            const NAMES: &'static [&'static str] = &[$($text),+];
            $(const ALIASES: &'static [(&'static str, &'static str)] = &[$(($old, $new)),+];)?
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.name())
            }
        }
    };
}

choice! {
    /// How primary visibility is found.
    #[derive(Default)]
    pub enum Visibility {
        /// One primary ray through each pixel centre.
        #[default]
        Rays = "rays",
        /// A z-buffer pass; hit points on the visible triangle's plane, and a primary ray only
        /// where a pixel's ray passes outside the triangle that the z-buffer gave it (edges).
        Raster = "raster",
    }
}

choice! {
    /// How point-light visibility is decided.
    #[derive(Default)]
    pub enum Shadows {
        /// One shadow ray per hit and light.
        #[default]
        Rays = "rays",
        /// The light's depth map decides, no rays (the plain shadow-map baseline).
        Maps = "maps",
        /// SMeRTS: the map decides, except on shadow borders, where a shadow ray (occluder hint
        /// first) does.
        Smerts = "smerts",
    }
}

choice! {
    /// How SMeRTS finds the border pixels that get a shadow ray.
    pub enum Borders {
        /// The thesis: the Laplace kernel on the screen-space occlusion map.
        Laplacian = "laplacian",
        /// In the map: the texels around the point's projection disagree.
        MapSpace = "map-space",
        /// Either.
        Both = "both",
    }
    aliases "depth" => "map-space"
}

choice! {
    /// How a (point, light) pair is decided whose map footprint is a border only because of
    /// occluders within the bias band (a neighbouring triangle's plane past a crease, or a
    /// contact shadow): see `hyrt_shadowmap::classify::Lookup::suspects`.
    #[derive(Default)]
    pub enum Ambiguous {
        /// A whole shadow ray (a border pair, as the thesis's SMeRTS).
        #[default]
        Rays = "rays",
        /// Those one or two triangles tested with the point's shadow ray alone (no traversal):
        /// most such pairs are lit, and a traversal to prove it costs what a handful of
        /// decisions do; what it misses is an occluder that no texel of the footprint holds.
        Triangles = "triangles",
    }
}

choice! {
    /// How a (point, light) pair is decided whose map footprint is a border only because of
    /// triangles that share a vertex with the point's own (a curved mesh's facets past its
    /// own, whose planes cross the ray to the light; a crease): see
    /// `hyrt_shadowmap::classify::Lookup::occluders`.
    #[derive(Default)]
    pub enum Neighbours {
        /// Those triangles (up to four) tested with the point's shadow ray alone: blocked if one
        /// is hit (the reference's ray would meet it), else lit, as the map decides wherever the
        /// texels around a point hold no occluder; what it misses is an occluder that no texel
        /// of the footprint holds.
        #[default]
        Triangles = "triangles",
        /// A whole shadow ray (a border pair, as the thesis's SMeRTS).
        Rays = "rays",
    }
}

choice! {
    /// How shadows are decided at mirror hits (which have no screen neighbours).
    #[derive(Default)]
    pub enum MirrorShadows {
        /// The same maps, with the map-space border test (under `Shadows::Smerts`).
        #[default]
        Maps = "maps",
        /// A shadow ray, as the thesis did.
        Rays = "rays",
    }
}

choice! {
    /// How indirect light is computed.
    #[derive(Default)]
    pub enum Indirect {
        /// No indirect light.
        #[default]
        None = "none",
        /// VPLs, visibility by one shadow ray per hit and VPL (the reference).
        Rays = "rays",
        /// VPLs, visibility by one paraboloid map per VPL (lookups only).
        Maps = "maps",
    }
}

/// How VPLs are generated ([`crate::render::vpl`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VplOptions {
    /// Number of light paths, over all lights (each path leaves up to `bounces` VPLs).
    pub paths: u32,
    /// Diffuse bounces per path, each leaving a VPL.
    pub bounces: u32,
    /// Offset into the Halton sequence (another set of VPLs for another seed).
    pub seed: u32,
}

impl Default for VplOptions {
    fn default() -> Self {
        Self { paths: 45, bounces: 1, seed: 0 }
    }
}

choice! {
    /// [`IndirectOptions::filter`].
    #[derive(Default)]
    pub enum VplFilter {
        /// The texel under the point decides: visible or not.
        #[default]
        Texel = "texel",
        /// Percentage-closer filtering over the 2x2 texels around the point: a fraction.
        Bilinear = "bilinear",
    }
}

/// The knobs of indirect light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndirectOptions {
    pub vpl: VplOptions,
    /// `d_min` of the `1 / max(d^2, d_min^2)` clamp, as a fraction of the scene's bounding-box
    /// diagonal (so the same value suits scenes in millimetres and in metres).
    pub clamp: f32,
    /// The VPL maps (one paraboloid hemisphere each; `kind` is ignored).
    pub map: MapOptions,
    /// Depth margin of map lookups, in texel footprints (as for the light maps).
    pub bias: f32,
    /// Interleaved sampling: each pixel of a `k x k` pattern evaluates a `1 / k^2` subset of
    /// the VPLs, then a geometry-aware filter reconstructs (see
    /// `hyrt::render::indirect`); 1 = off.
    pub interleave: u32,
    /// How a VPL map decides visibility: the texel under the point (the thesis), or the 2x2
    /// texels around it, bilinearly weighted.
    pub filter: VplFilter,
    /// What a VPL map's texels hold: occluder planes or 16-bit depths
    /// ([`hyrt_shadowmap::vpl_map::VplMap`]).
    pub format: VplFormat,
}

/// Defaults chosen by measuring the thesis scenes with 45 VPLs, maps against rays on the full
/// image (the sweeps under `docs/sweeps/*-vpl-maps`): 16-bit depths are as accurate as planes
/// at the same resolution, in a sixth of the memory, so the default is depths at 512x512
/// (0.5 MB per VPL), which keep the Cornell box and the conference room above 40 dB; the
/// office stays below it at any size that fits 1 MB (its blinds' shadows need about 1500
/// texels a side). The tessellation only has to keep the ids right, not the depths (which
/// come from the planes): 32 texels costs no accuracy at 512 and saves a third of the build.
impl Default for IndirectOptions {
    fn default() -> Self {
        Self {
            vpl: VplOptions::default(),
            clamp: 0.01,
            map: MapOptions { resolution: 512, tess_texels: 32.0, ..MapOptions::default() },
            bias: 0.5,
            interleave: 1,
            filter: VplFilter::default(),
            format: VplFormat::default(),
        }
    }
}

choice! {
    /// The two starting points of the knobs.
    #[derive(Default)]
    pub enum Preset {
        /// Rays everywhere: the Whitted ground truth.
        Reference = "reference",
        /// Raster visibility and SMeRTS with the measured defaults: the product, and the
        /// default.
        #[default]
        Hybrid = "hybrid",
    }
}

impl Preset {
    pub fn options(self) -> Options {
        match self {
            Preset::Reference => Options::reference(),
            Preset::Hybrid => Options::hybrid(),
        }
    }
}

// The leaf crates' enums: their names are theirs (`MapKind::name`, `VplFormat::name`).
impl Choice for MapKind {
    const ALL: &'static [Self] = &[MapKind::Cube, MapKind::Paraboloid];
    const NAMES: &'static [&'static str] = &[MapKind::Cube.name(), MapKind::Paraboloid.name()];
}

impl Choice for VplFormat {
    const ALL: &'static [Self] = &[VplFormat::Planes, VplFormat::Depth16];
    const NAMES: &'static [&'static str] = &[VplFormat::Planes.name(), VplFormat::Depth16.name()];
}

choice! {
    /// How the point lights' maps are laid out ([`ShadowOptions::light_maps`]).
    #[derive(Default)]
    pub enum LightMaps {
        /// Only the pages (32 x 32 texels) that the frame's receivers fall on, each at the
        /// resolution its receivers need (`hyrt_shadowmap::paged`). Cube maps only: paraboloid
        /// maps are drawn whole.
        #[default]
        Paged = "paged",
        /// Every texel of each face that a receiver falls on, at `--shadow-map-res`.
        Whole = "whole",
    }
}

choice! {
    /// How light maps hold alpha cut-outs ([`ShadowOptions::cutouts`]).
    #[derive(Default)]
    pub enum CutoutMaps {
        /// Paged maps test each cut-out texel's centre: a texel that sees a hole holds what
        /// lies behind it (the page drawn again without cut-outs), so points decide from the
        /// map like any other, and a footprint that straddles a hole's edge is a border. A hole
        /// narrower than a texel is missed as a thin occluder is. Whole maps hold cut-outs solid,
        /// as with `rays`.
        #[default]
        Texels = "texels",
        /// Cut-outs are drawn solid, and every point that one would shadow is left to its shadow
        /// ray: exact, with no texel tests, and a ray for every point under a cut-out.
        Rays = "rays",
    }
}

/// The knobs of map-based shadows (ignored by `Shadows::Rays`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowOptions {
    /// Map kind, resolution (of whole maps), paraboloid tessellation.
    pub map: MapOptions,
    /// Paged maps (resolution matched to the receivers) or whole faces.
    pub light_maps: LightMaps,
    /// Paged maps: texels per pixel footprint (per side) that each receiver asks for.
    pub map_detail: f32,
    /// Paged maps: most megabytes of pages per light; a light whose receivers ask for more
    /// gets coarser levels, one at a time, until it fits.
    pub map_budget: u32,
    /// Paged maps with border rays: the frames a light's map is expected to serve. A light whose
    /// map is predicted to cost more than the shadow rays it saves over that many frames gets
    /// none: rays decide its pairs, as the reference's do (`shadows::payoff`). Infinite (the
    /// default): every light gets its map. `hyrt render`, which renders one image, uses 1.
    pub map_horizon: f32,
    /// Depth margin in texel footprints (see `hyrt_shadowmap::classify`).
    pub bias: f32,
    pub borders: Borders,
    /// Border dilation radius in pixels.
    pub dilate: u32,
    pub mirror: MirrorShadows,
    pub ambiguous: Ambiguous,
    pub neighbours: Neighbours,
    /// How light maps hold alpha cut-outs.
    pub cutouts: CutoutMaps,
}

impl Default for ShadowOptions {
    /// The hybrid defaults, chosen by measurement on the three thesis scenes at 640x480 (see
    /// docs/results.md, SMeRTS): cube maps of 2048x2048 per face, bias 1 texel footprint,
    /// map-space borders without dilation.
    fn default() -> Self {
        Self {
            map: MapOptions { resolution: 2048, ..MapOptions::default() },
            light_maps: LightMaps::Paged,
            map_detail: 1.5,
            map_budget: 10,
            map_horizon: f32::INFINITY,
            bias: 1.0,
            borders: Borders::MapSpace,
            dilate: 0,
            mirror: MirrorShadows::default(),
            ambiguous: Ambiguous::default(),
            neighbours: Neighbours::default(),
            cutouts: CutoutMaps::default(),
        }
    }
}

/// The strategy of each stage. `Options::default()` is the Whitted reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Options {
    pub visibility: Visibility,
    pub shadows: Shadows,
    pub shadow: ShadowOptions,
    pub indirect: Indirect,
    /// VPL count, bounces, seed, clamp and map knobs (used unless `indirect` is `None`).
    pub indirect_opts: IndirectOptions,
    /// Diagnostics: for every camera hit and light decided by a map, also cast a shadow ray
    /// (not counted in the frame's rays) and count the decisions it contradicts
    /// (`FrameStats::lights[l].wrong`).
    pub check_visibility: bool,
    /// Return the per-pixel shadow buffers in `Frame::shadows` (for
    /// inspection); otherwise the renderer keeps them for the next frame.
    pub keep_buffers: bool,
}

impl Options {
    /// The Whitted reference: rays everywhere.
    pub fn reference() -> Self {
        Self::default()
    }

    /// The hybrid: rasterized visibility and SMeRTS with the default knobs.
    pub fn hybrid() -> Self {
        Self { visibility: Visibility::Raster, shadows: Shadows::Smerts, ..Self::default() }
    }

    /// The ground truth these options are measured against: rays everywhere, with the same
    /// VPLs (by rays, every VPL at every pixel: no interleaving) when these have indirect
    /// light. The map and VPL-map knobs stay these options' (unused by rays), so that one
    /// renderer switched between the two keeps its caches.
    pub fn reference_for(&self) -> Options {
        let mut r = Options {
            visibility: Visibility::Rays,
            shadows: Shadows::Rays,
            indirect: if self.indirect == Indirect::None { Indirect::None } else { Indirect::Rays },
            check_visibility: false,
            keep_buffers: false,
            ..*self
        };
        r.indirect_opts.interleave = 1;
        r
    }
}

/// The values a knob accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Values {
    /// One of these names (the `Choice`'s), or an alias.
    Names(&'static [&'static str], &'static [(&'static str, &'static str)]),
    /// A whole number in `min..=max`.
    Count { min: u32, max: u32 },
    /// A finite number `>= 0`.
    NonNegative,
    /// A number `> 0`, or `inf`.
    PositiveOrInf,
}

/// One knob: its flag, what it takes, and where it lives in [`Options`].
pub struct Knob {
    /// The flag's long name (`--NAME`), also the statistics' key (with `_` for `-`) and the
    /// sweep's knob name.
    pub name: &'static str,
    /// The value's placeholder in the help.
    pub value_name: &'static str,
    pub help: &'static str,
    pub values: Values,
    /// The knob's value in some options, as the statistics write it.
    pub get: fn(&Options) -> Value,
    /// Sets the knob from a value that [`Knob::values`] accepts; the message says why not.
    pub set: fn(&mut Options, &str) -> Result<(), String>,
    /// The range an interactive slider offers (within [`Knob::values`]; the inspector's),
    /// for numeric knobs.
    pub slider: Option<(f64, f64)>,
}

impl Knob {
    /// The statistics' key.
    pub fn key(&self) -> String {
        self.name.replace('-', "_")
    }

    /// The knob's value in `o`, as a flag would give it (an `f32` in its shortest form).
    pub fn show(&self, o: &Options) -> String {
        match (self.get)(o) {
            Value::String(s) => s,
            Value::Number(n) if matches!(self.values, Values::NonNegative | Values::PositiveOrInf) => {
                (n.as_f64().unwrap_or(f64::NAN) as f32).to_string()
            }
            v => v.to_string(),
        }
    }
}

fn count(name: &str, v: &str, min: u32, max: u32) -> Result<u32, String> {
    let n: u32 = v.trim().parse().map_err(|_| format!("--{name} takes a whole number, got '{v}'"))?;
    if !(min..=max).contains(&n) {
        return Err(format!("--{name} must be in {min}..={max}, got {n}"));
    }
    Ok(n)
}

fn non_negative(name: &str, v: &str) -> Result<f32, String> {
    match v.trim().parse::<f32>() {
        Ok(x) if x >= 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("--{name} must be a finite number >= 0, got {v}")),
    }
}

fn positive_or_inf(name: &str, v: &str) -> Result<f32, String> {
    match v.trim().parse::<f32>() {
        Ok(x) if x > 0.0 => Ok(x),
        _ => Err(format!("--{name} must be > 0 (or inf), got {v}")),
    }
}

fn choice<T: Choice>(name: &str, v: &str) -> Result<T, String> {
    T::from_name(v).ok_or_else(|| format!("--{name} takes one of {}, got '{v}'", T::NAMES.join(", ")))
}

/// A number as the statistics write it: `inf` as a string (JSON has no infinity).
fn number(x: f32) -> Value {
    if x.is_finite() { Value::from(x) } else { Value::from("inf") }
}

/// One [`Knob`] entry: `knob!(NAME, VALUE_NAME, HELP, KIND, field.path)`.
macro_rules! knob {
    (@slider) => {
        None
    };
    (@slider $lo:literal, $hi:literal) => {
        Some(($lo as f64, $hi as f64))
    };
    ($name:literal, $vn:literal, $help:literal, choice $t:ty, $($f:ident).+ $(, slider $lo:literal ..= $hi:literal)?) => {
        Knob {
            name: $name,
            value_name: $vn,
            help: $help,
            values: Values::Names(<$t as Choice>::NAMES, <$t as Choice>::ALIASES),
            get: |o| Value::from(o.$($f).+.name()),
            set: |o, v| {
                o.$($f).+ = choice::<$t>($name, v)?;
                Ok(())
            },
            slider: knob!(@slider $($lo, $hi)?),
        }
    };
    ($name:literal, $vn:literal, $help:literal, count $min:literal ..= $max:literal, $($f:ident).+ $(, slider $lo:literal ..= $hi:literal)?) => {
        Knob {
            name: $name,
            value_name: $vn,
            help: $help,
            values: Values::Count { min: $min, max: $max },
            get: |o| Value::from(o.$($f).+),
            set: |o, v| {
                o.$($f).+ = count($name, v, $min, $max)?;
                Ok(())
            },
            slider: knob!(@slider $($lo, $hi)?),
        }
    };
    ($name:literal, $vn:literal, $help:literal, non_negative, $($f:ident).+ $(, slider $lo:literal ..= $hi:literal)?) => {
        Knob {
            name: $name,
            value_name: $vn,
            help: $help,
            values: Values::NonNegative,
            get: |o| number(o.$($f).+),
            set: |o, v| {
                o.$($f).+ = non_negative($name, v)?;
                Ok(())
            },
            slider: knob!(@slider $($lo, $hi)?),
        }
    };
    ($name:literal, $vn:literal, $help:literal, positive_or_inf, $($f:ident).+ $(, slider $lo:literal ..= $hi:literal)?) => {
        Knob {
            name: $name,
            value_name: $vn,
            help: $help,
            values: Values::PositiveOrInf,
            get: |o| number(o.$($f).+),
            set: |o, v| {
                o.$($f).+ = positive_or_inf($name, v)?;
                Ok(())
            },
            slider: knob!(@slider $($lo, $hi)?),
        }
    };
}

/// Every knob, in the order of `--help` and of the statistics.
pub const KNOBS: &[Knob] = &[
    knob!(
        "visibility",
        "MODE",
        "Primary visibility: `rays` (one primary ray per pixel) or `raster` (z-buffer; no primary rays).",
        choice Visibility,
        visibility
    ),
    knob!(
        "shadows",
        "MODE",
        "Point-light shadows: `rays` (one shadow ray per hit and light), `maps` (depth maps only) or `smerts` (maps + shadow rays on the borders).",
        choice Shadows,
        shadows
    ),
    knob!("shadow-map", "KIND", "Light map parameterisation.", choice MapKind, shadow.map.kind),
    knob!(
        "shadow-map-res",
        "N",
        "Light map resolution: texels per side of each face.",
        count 1..=16384,
        shadow.map.resolution
    ),
    knob!(
        "light-maps",
        "LAYOUT",
        "Light maps: `paged` (only the 32x32-texel pages that receivers fall on, at the resolution each needs; cube maps) or `whole` (every texel of the faces receivers fall on, at --shadow-map-res).",
        choice LightMaps,
        shadow.light_maps
    ),
    knob!(
        "map-detail",
        "D",
        "Paged light maps: texels per pixel footprint (per side) that each receiver asks for.",
        non_negative,
        shadow.map_detail, slider 0.25..=4.0
    ),
    knob!(
        "map-budget",
        "MB",
        "Paged light maps: most megabytes of pages per light (coarser levels beyond it).",
        count 1..=65536,
        shadow.map_budget, slider 1..=256
    ),
    knob!(
        "map-horizon",
        "FRAMES",
        "Paged light maps with border rays: frames each light's map is expected to serve; a light whose map would cost more than the shadow rays it saves over that many frames gets none, and rays decide it (`inf`: every light gets its map; `hyrt render`, one image, uses 1).",
        positive_or_inf,
        shadow.map_horizon
    ),
    knob!("bias", "B", "Depth margin of map decisions, in texel footprints.", non_negative, shadow.bias, slider 0.0..=4.0),
    knob!(
        "borders",
        "METHOD",
        "SMeRTS border detection: screen-space Laplacian, map-space texel disagreement, or both.",
        choice Borders,
        shadow.borders
    ),
    knob!("dilate", "R", "SMeRTS border dilation radius, in pixels.", count 0..=4294967295, shadow.dilate, slider 0..=4),
    knob!(
        "tess",
        "T",
        "Paraboloid maps: tessellate triangles until projected edges are at most T texels (`inf`: no tessellation).",
        positive_or_inf,
        shadow.map.tess_texels, slider 1.0..=64.0
    ),
    knob!(
        "ambiguous",
        "MODE",
        "SMeRTS: a pair whose map footprint is a border only because an occluder lies within the bias band (a crease, a contact): `rays` casts the whole shadow ray, `triangles` tests those triangles alone with it (fewer rays, a little less accurate: occluders the map missed stay missed).",
        choice Ambiguous,
        shadow.ambiguous
    ),
    knob!(
        "neighbours",
        "MODE",
        "SMeRTS: a pair whose map footprint is a border only because of triangles sharing a vertex with its own (a curved mesh's facets, a crease): `triangles` tests those triangles alone with its shadow ray (blocked if one is hit, else lit, as the map decides elsewhere), `rays` casts the whole shadow ray.",
        choice Neighbours,
        shadow.neighbours
    ),
    knob!(
        "cutout-maps",
        "MODE",
        "Alpha cut-outs in paged light maps: `texels` (each texel's centre tested: holes hold what lies behind; borders go to rays) or `rays` (drawn solid; every point a cut-out would shadow gets its ray).",
        choice CutoutMaps,
        shadow.cutouts
    ),
    knob!(
        "mirror-shadows",
        "MODE",
        "Shadows at mirror hits: from the `maps` (map-space border test) or by `rays`.",
        choice MirrorShadows,
        shadow.mirror
    ),
    knob!(
        "indirect",
        "MODE",
        "Indirect light from virtual point lights: `none`, `rays` (one shadow ray per hit and VPL) or `maps` (one paraboloid map per VPL). `--vpls` alone picks `rays` under the reference preset and `maps` under the hybrid one.",
        choice Indirect,
        indirect
    ),
    knob!("vpls", "N", "Number of VPL light paths (thesis: 45), over all lights.", count 0..=4294967295, indirect_opts.vpl.paths, slider 0..=256),
    knob!("vpl-bounces", "B", "Diffuse bounces per VPL path (each leaves a VPL).", count 0..=4294967295, indirect_opts.vpl.bounces, slider 1..=4),
    knob!("vpl-seed", "S", "Offset into the VPLs' Halton sequence.", count 0..=4294967295, indirect_opts.vpl.seed),
    knob!(
        "vpl-clamp",
        "F",
        "VPL distance clamp `d_min`, as a fraction of the scene's bounding-box diagonal.",
        non_negative,
        indirect_opts.clamp, slider 0.0..=0.1
    ),
    knob!(
        "interleave",
        "K",
        "Interleaved VPL sampling: each pixel of a K x K pattern evaluates 1/K^2 of the VPLs, then a geometry-aware filter reconstructs (1 = off).",
        count 1..=16,
        indirect_opts.interleave, slider 1..=16
    ),
    knob!(
        "vpl-bias",
        "B",
        "Depth margin of VPL map lookups, in texel footprints.",
        non_negative,
        indirect_opts.bias, slider 0.0..=4.0
    ),
    knob!(
        "vpl-map-res",
        "N",
        "Resolution of each VPL's paraboloid map.",
        count 1..=16384,
        indirect_opts.map.resolution
    ),
    knob!(
        "vpl-tess",
        "T",
        "VPL maps: tessellate triangles until projected edges are at most T texels (`inf`: no tessellation), as `--tess` for the light maps.",
        positive_or_inf,
        indirect_opts.map.tess_texels, slider 1.0..=64.0
    ),
    knob!(
        "vpl-filter",
        "FILTER",
        "How a VPL map decides visibility: the `texel` under the point (the thesis), or `bilinear` over the 2x2 texels around it (percentage-closer filtering).",
        choice VplFilter,
        indirect_opts.filter
    ),
    knob!(
        "vpl-format",
        "FORMAT",
        "What a VPL map's texels hold: the occluder's `planes` (12 bytes a texel) or its distance as a 16-bit float, `depth16` (2 bytes).",
        choice VplFormat,
        indirect_opts.format
    ),
];

/// The knob named `name` (a flag's long name without `--`).
pub fn knob(name: &str) -> Option<&'static Knob> {
    KNOBS.iter().find(|k| k.name == name)
}

/// The options as the statistics write them: every knob by its key, and the scene's mirror
/// depth.
pub fn to_json(o: &Options, max_depth: u32) -> Value {
    let mut m: serde_json::Map<String, Value> = KNOBS.iter().map(|k| (k.key(), (k.get)(o))).collect();
    m.insert("max_depth".into(), Value::from(max_depth));
    Value::Object(m)
}

/// What a knob's help adds: both presets' values, or the one they share.
pub fn defaults_text(k: &Knob) -> String {
    let (r, h) = (k.show(&Options::reference()), k.show(&Options::hybrid()));
    if r == h { format!("default: {r}") } else { format!("reference: {r}; hybrid: {h}") }
}

/// The knobs as a Markdown table: flag, values, both presets' defaults, help. `docs/cli.md`
/// carries it (a test holds it to this).
pub fn markdown_table() -> String {
    let mut s =
        String::from("| flag | values | reference | hybrid | what it sets |\n|---|---|---|---|---|\n");
    for k in KNOBS {
        let values = match k.values {
            Values::Names(names, _) => names.join(", "),
            Values::Count { min, max: u32::MAX } => format!(">= {min}"),
            Values::Count { min, max } => format!("{min}..={max}"),
            Values::NonNegative => ">= 0".into(),
            Values::PositiveOrInf => "> 0, or inf".into(),
        };
        s.push_str(&format!(
            "| `--{} {}` | {values} | {} | {} | {} |\n",
            k.name,
            k.value_name,
            k.show(&Options::reference()),
            k.show(&Options::hybrid()),
            k.help.replace('|', "\\|")
        ));
    }
    s
}

#[cfg(feature = "clap")]
mod flags;
#[cfg(feature = "clap")]
pub use flags::{Knobs, parse_size};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_aliases_map_to_current_names() {
        fn check<T: Choice + std::fmt::Debug>() {
            assert_eq!(T::ALL.len(), T::NAMES.len());
            for v in T::ALL {
                assert_eq!(T::from_name(v.name()), Some(*v));
            }
            assert_eq!(T::from_name("no such value"), None);
        }
        check::<Visibility>();
        check::<Shadows>();
        check::<Borders>();
        check::<MirrorShadows>();
        check::<Ambiguous>();
        check::<Neighbours>();
        check::<Indirect>();
        check::<Preset>();
        check::<MapKind>();
        check::<VplFormat>();
        check::<VplFilter>();
        assert_eq!(Borders::from_name("depth"), Some(Borders::MapSpace));
    }

    #[test]
    fn every_knob_sets_what_it_shows() {
        for k in KNOBS {
            let mut o = Options::hybrid();
            let shown = k.show(&o);
            (k.set)(&mut o, &shown).unwrap_or_else(|e| panic!("{}: {e}", k.name));
            assert_eq!(o, Options::hybrid(), "{}", k.name);
            let other = match k.values {
                Values::Names(names, _) => {
                    names.iter().find(|n| **n != shown).expect("two values").to_string()
                }
                Values::Count { min, max } => (if shown == min.to_string() { max } else { min }).to_string(),
                Values::NonNegative | Values::PositiveOrInf => "3.5".into(),
            };
            (k.set)(&mut o, &other).unwrap_or_else(|e| panic!("{}: {e}", k.name));
            assert_eq!(k.show(&o), other, "{}", k.name);
            assert_ne!(o, Options::hybrid(), "{} changes the options", k.name);
        }
        let names: std::collections::HashSet<_> = KNOBS.iter().map(|k| k.name).collect();
        assert_eq!(names.len(), KNOBS.len(), "knob names are unique");
    }

    #[test]
    fn bad_values_say_which_flag() {
        let mut o = Options::hybrid();
        let err = |name: &str, v: &str| (knob(name).unwrap().set)(&mut o.clone(), v).unwrap_err();
        assert_eq!(err("bias", "-1"), "--bias must be a finite number >= 0, got -1");
        assert_eq!(err("tess", "0"), "--tess must be > 0 (or inf), got 0");
        assert!(err("borders", "edges").starts_with("--borders takes one of laplacian, map-space, both"));
        assert!(err("shadow-map-res", "0").contains("1..=16384"));
        (knob("tess").unwrap().set)(&mut o, "inf").unwrap();
        assert_eq!(o.shadow.map.tess_texels, f32::INFINITY);
        assert_eq!(to_json(&o, 5)["tess"], "inf");
    }
}
