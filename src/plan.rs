//! The effect planner: which passes this scene needs, and why.
//!
//! Derived from the scene and the chosen strategies before any work is done; printed by the CLI
//! and recorded in the stats, so that what is simulated (and what is skipped) is visible.

use serde::Serialize;

use crate::{
    render::{Options, Visibility},
    scene::Scene,
};

/// A pass of the frame, run or skipped, with the reason.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PassDecision {
    pub pass: &'static str,
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
        let mut plan = Plan::default();
        let tris = scene.triangle_count();
        plan.add(true, "bvh_build", format!("ray casting needs a BVH over {tris} triangles"));
        let vis = match opts.visibility {
            Visibility::Rays => "rays: one primary ray per pixel".to_string(),
            Visibility::Raster => {
                format!(
                    "raster: z-buffer of {tris} triangles, hit points on the visible triangle (no primary rays)"
                )
            }
        };
        plan.add(true, "visibility", vis);

        let lights = scene.lights.len();
        if lights == 0 {
            plan.add(false, "direct", "the scene has no point lights".into());
        } else {
            plan.add(
                true,
                "direct",
                format!(
                    "{lights} point light(s), {}: one shadow ray per lit hit and light",
                    opts.shadows.name()
                ),
            );
        }

        let used_specular = scene.specular_materials_in_use();
        if used_specular.is_empty() {
            plan.add(false, "specular", "no material has a mirror reflectance (Ks > 0)".into());
        } else if scene.settings.max_depth == 0 {
            plan.add(false, "specular", "max_depth = 0".into());
        } else {
            let names = used_specular.join(", ");
            plan.add(
                true,
                "specular",
                format!("mirror materials [{names}], up to {} bounce(s)", scene.settings.max_depth),
            );
        }
        plan.add(false, "indirect", "no indirect-light settings (VPLs) requested".into());
        plan
    }

    fn add(&mut self, run: bool, pass: &'static str, reason: String) {
        let d = PassDecision { pass, reason };
        if run { self.run.push(d) } else { self.skipped.push(d) }
    }

    /// True when `pass` runs.
    pub fn runs(&self, pass: &str) -> bool {
        self.run.iter().any(|d| d.pass == pass)
    }

    /// Names of the passes that run, in order.
    pub fn pass_names(&self) -> Vec<&'static str> {
        self.run.iter().map(|d| d.pass).collect()
    }
}

impl std::fmt::Display for Plan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for d in &self.run {
            writeln!(f, "  run   {:<11} {}", d.pass, d.reason)?;
        }
        for d in &self.skipped {
            writeln!(f, "  skip  {:<11} {}", d.pass, d.reason)?;
        }
        Ok(())
    }
}
