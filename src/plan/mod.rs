//! The effect planner: which passes this scene needs, and why.
//!
//! Derived from the scene and the chosen strategies before any work is done; printed by the CLI
//! and recorded in the stats, so that what is simulated (and what is skipped) is visible.

use serde::Serialize;

pub mod pass;

pub use pass::{Buffer, Pass};

use crate::{
    options::{Choice, Indirect, Options, Shadows, Visibility},
    scene::{PointLight, Scene},
};

/// A pass of the frame, run or skipped, with the reason.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PassDecision {
    pub pass: Pass,
    pub reason: String,
}

/// The passes one frame runs, in order, and those it skips.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Plan {
    pub run: Vec<PassDecision>,
    pub skipped: Vec<PassDecision>,
}

impl Plan {
    /// Decides the passes for `scene` rendered with `opts`.
    pub fn new(scene: &Scene, opts: &Options) -> Self {
        Self::with_lights(scene, &scene.lights, opts)
    }

    /// The same for `scene` lit by `lights` instead of its own (moved lights, as
    /// `Renderer::set_light` makes them).
    pub fn with_lights(scene: &Scene, lights: &[PointLight], opts: &Options) -> Self {
        let mut plan = Plan::default();
        let tris = scene.triangle_count();
        plan.run(Pass::BvhBuild, format!("ray casting needs a BVH over {tris} triangles"));
        // Alpha cut-outs: how many triangles have holes, which every visibility path honours.
        let cut = scene.cutout_flags().iter().filter(|&&c| c).count();
        let holes = if cut > 0 { " or sees a cut-out's hole" } else { "" };
        let vis = match opts.visibility {
            Visibility::Rays => "rays: one primary ray per pixel".to_string(),
            Visibility::Raster => {
                format!(
                    "raster: z-buffer of {tris} triangles, hit points on the visible triangle (a primary ray only where a pixel's ray leaves it{holes})"
                )
            }
        };
        plan.run(Pass::Visibility, vis);

        let count = lights.len();
        let used = scene.materials_in_use();
        let highlights = used.iter().filter(|m| m.has_highlight()).count();
        let highlights = match highlights {
            0 => "diffuse only".to_string(),
            n => format!("diffuse, highlights on {n} of {} materials", used.len()),
        };
        for (l, light) in lights.iter().enumerate() {
            if light.intensity.max_element() <= 0.0 {
                plan.skip(
                    Pass::MapBuild,
                    format!("light {l}: zero intensity: no map, no shadow rays, no VPLs"),
                );
            }
        }
        if count == 0 {
            plan.skip(Pass::Direct, "the scene has no point lights".into());
        } else {
            let sh = &opts.shadow;
            let kind = sh.map.kind.name();
            let paged = sh.light_maps == crate::options::LightMaps::Paged
                && sh.map.kind == hyrt_shadowmap::MapKind::Cube;
            let maps = if paged {
                format!(
                    "paged {kind} maps: only the {p}x{p}-texel pages that camera hits fall on, each at the level its receivers need ({d} texels per pixel footprint, at most {b} MB per light), cached and extended as views move",
                    p = hyrt_shadowmap::PAGE,
                    d = sh.map_detail,
                    b = sh.map_budget
                )
            } else {
                format!(
                    "{kind} maps of {n}x{n} per face, only faces that camera hits fall on, built once and cached",
                    n = sh.map.resolution
                )
            };
            // A finite horizon: maps only where they pay (`render::shadows::payoff`).
            let pays = paged && sh.map_horizon.is_finite() && opts.shadows == Shadows::Smerts;
            let maps = if pays {
                let frames = if sh.map_horizon == 1.0 {
                    "1 frame".to_string()
                } else {
                    format!("{} frames", sh.map_horizon)
                };
                format!(
                    "{maps}; only for the lights whose maps are predicted to pay within {frames} (the others: a shadow ray per pixel, per frame)"
                )
            } else {
                maps
            };
            let maps = match (cut, paged && sh.cutouts == crate::options::CutoutMaps::Texels) {
                (0, _) => maps,
                (n, true) => format!(
                    "{maps}; {n} cut-out triangles tested at each texel's centre (holes hold what lies behind)"
                ),
                (n, false) => format!(
                    "{maps}; {n} cut-out triangles drawn solid (every point one would shadow gets its ray)"
                ),
            };
            match opts.shadows {
                Shadows::Rays => {
                    plan.skip(Pass::MapBuild, "shadows by rays: no light maps".into());
                    plan.run(
                        Pass::Direct,
                        format!(
                            "{count} point light(s), {highlights}, rays: one shadow ray per lit hit and light"
                        ),
                    );
                }
                Shadows::Maps | Shadows::Smerts => {
                    plan.run(Pass::MapBuild, maps);
                    // Borders that a few triangles explain, settled in classify by testing those
                    // alone with the pair's ray (`render::shadows::lookup::settle`).
                    let smerts = opts.shadows == Shadows::Smerts;
                    let settled = match (
                        smerts && sh.neighbours == crate::options::Neighbours::Triangles,
                        smerts && sh.ambiguous == crate::options::Ambiguous::Triangles,
                    ) {
                        (false, false) => "",
                        (true, false) => {
                            "; borders that only the point's neighbouring facets make settled by testing those alone with its ray"
                        }
                        (false, true) => {
                            "; borders that only occluders within the bias band make settled by testing those alone with its ray"
                        }
                        (true, true) => {
                            "; borders that only the point's neighbouring facets or occluders within the bias band make settled by testing those alone with its ray"
                        }
                    };
                    plan.run(Pass::Classify,
                        format!(
                            "tile by tile: shading points, every light's map decision (bias {} texel footprints), and direct light ({highlights}) from those decisions{settled}",
                            sh.bias
                        ),
                    );
                    if opts.shadows == Shadows::Smerts {
                        plan.run(
                            Pass::Borders,
                            format!("{} borders, dilated by {} px", sh.borders.name(), sh.dilate),
                        );
                        let without =
                            if pays { "; and one per pixel for each light without a map" } else { "" };
                        plan.run(Pass::ShadowRays,
                            format!("one shadow ray per border pixel and light, occluder hint first; those pixels shaded again{without}"),
                        );
                    } else {
                        plan.skip(Pass::Borders, "shadows by maps alone: no borders, no rays".into());
                        plan.skip(
                            Pass::ShadowRays,
                            "shadows by maps alone: the map's decision is final".into(),
                        );
                    }
                    plan.skip(
                        Pass::Direct,
                        "shaded by classify (and shadow_rays on borders), no pass of its own".into(),
                    );
                }
            }
        }

        let mirrors: Vec<_> = used.iter().copied().filter(|m| m.is_mirror()).collect();
        if mirrors.is_empty() {
            plan.skip(Pass::Specular, "no material in use has a mirror reflectance".into());
        } else if scene.settings.max_depth == 0 {
            plan.skip(Pass::Specular, "max_depth = 0".into());
        } else {
            plan.run(
                Pass::Specular,
                format!(
                    "mirror materials {}, up to {} bounce(s)",
                    mirror_reasons(&mirrors),
                    scene.settings.max_depth
                ),
            );
        }
        let io = &opts.indirect_opts;
        let none = match opts.indirect {
            Indirect::None => Some("no indirect-light settings (VPLs) requested"),
            _ if count == 0 => Some("no point lights to place VPLs from"),
            _ if io.vpl.paths == 0 || io.vpl.bounces == 0 => Some("0 VPL paths or bounces requested"),
            _ => None,
        };
        match (none, opts.indirect) {
            (Some(why), _) => plan.skip(Pass::Indirect, why.into()),
            (None, Indirect::Rays) => {
                plan.run(
                    Pass::VplGen,
                    format!(
                        "{} VPL path(s) of {} bounce(s), traced once and cached",
                        io.vpl.paths, io.vpl.bounces
                    ),
                );
                plan.skip(Pass::VplMapBuild, "VPL visibility by rays: no VPL maps".into());
                plan.run(
                    Pass::Indirect,
                    format!(
                        "{} VPL path(s), {} bounce(s), visibility by one shadow ray per hit and VPL",
                        io.vpl.paths, io.vpl.bounces
                    ),
                );
            }
            (None, _) => {
                let n = io.map.resolution;
                let format = match io.format {
                    hyrt_shadowmap::vpl_map::VplFormat::Planes => "planes",
                    hyrt_shadowmap::vpl_map::VplFormat::Depth16 => "16-bit depths",
                };
                plan.run(
                    Pass::VplGen,
                    format!(
                        "{} VPL path(s) of {} bounce(s), traced once and cached",
                        io.vpl.paths, io.vpl.bounces
                    ),
                );
                plan.run(
                    Pass::VplMapBuild,
                    format!("one {n}x{n} paraboloid map of {format} per VPL, built once and cached"),
                );
                plan.run(Pass::Indirect,
                    format!(
                        "{} VPL path(s), {} bounce(s), visibility by one {n}x{n} paraboloid map of {format} per VPL (built once)",
                        io.vpl.paths,
                        io.vpl.bounces,
                    ),
                );
            }
        }
        // In the order a frame runs them.
        plan.run.sort_by_key(|d| d.pass);
        plan.skipped.sort_by_key(|d| d.pass);
        plan
    }

    fn run(&mut self, pass: Pass, reason: String) {
        self.run.push(PassDecision { pass, reason });
    }

    fn skip(&mut self, pass: Pass, reason: String) {
        self.skipped.push(PassDecision { pass, reason });
    }

    /// True when `pass` runs.
    pub fn runs(&self, pass: Pass) -> bool {
        self.run.iter().any(|d| d.pass == pass)
    }

    /// Names of the passes that run, in order.
    pub fn pass_names(&self) -> Vec<&'static str> {
        self.run.iter().map(|d| d.pass.name()).collect()
    }
}

/// The mirror materials grouped by why they reflect, in material order:
/// `[mirror (MTL illum 3)]`, `[chrome, polished_brass (scene file override)]`. A group lists at
/// most four names (a scene may give every material a little reflectance).
fn mirror_reasons(mirrors: &[&crate::scene::Material]) -> String {
    let mut groups: Vec<(String, Vec<&str>)> = Vec::new();
    for m in mirrors {
        let why = m.mirror_source.to_string();
        match groups.iter_mut().find(|(w, _)| *w == why) {
            Some((_, names)) => names.push(&m.name),
            None => groups.push((why, vec![&m.name])),
        }
    }
    let groups: Vec<String> = groups
        .into_iter()
        .map(|(why, names)| {
            let mut list = names.iter().take(4).copied().collect::<Vec<_>>().join(", ");
            if names.len() > 4 {
                list += &format!(" and {} more", names.len() - 4);
            }
            format!("{list} ({why})")
        })
        .collect();
    format!("[{}]", groups.join("; "))
}

impl std::fmt::Display for Plan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for d in &self.run {
            writeln!(f, "  run   {:<13} {}", d.pass, d.reason)?;
        }
        for d in &self.skipped {
            writeln!(f, "  skip  {:<13} {}", d.pass, d.reason)?;
        }
        Ok(())
    }
}
