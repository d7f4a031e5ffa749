//! The window: knobs on the left, the views in the middle, the picked pixel and the frame's
//! plan, times and rays on the right. All rendering happens on the [`Worker`]'s thread; this
//! side only uploads the images it made and draws.

use std::collections::HashMap;
use std::time::Duration;

use eframe::egui::{
    self, Align2, Color32, ColorImage, FontId, Pos2, Rect, RichText, Sense, Stroke, TextureHandle,
    TextureOptions, Vec2,
};
use hyrt::render::{
    Borders, Indirect, MirrorShadows, Options, Shadows, Visibility,
    shadows::{RAY_HINT, RAY_TRAVERSAL},
};
use hyrt_shadowmap::{LightMap, MapKind};
use hyrt_tracer::RayCounts;

use crate::pick::{self, decision_name, tri_name};
use crate::views::{self, RayKindView};
use crate::worker::{Command, Loaded, Rendered, Reply, Setup, VplMap, Worker};

/// The views of the central panel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    Frame,
    Shadows,
    Rays,
    LightMaps,
    Vpls,
}

impl View {
    pub const ALL: [View; 5] = [View::Frame, View::Shadows, View::Rays, View::LightMaps, View::Vpls];

    pub fn name(self) -> &'static str {
        match self {
            View::Frame => "Frame",
            View::Shadows => "Shadows",
            View::Rays => "Rays per pixel",
            View::LightMaps => "Light maps",
            View::Vpls => "VPLs",
        }
    }
}

const CUBE_FACES: [&str; 6] = ["+X", "-X", "+Y", "-Y", "+Z", "-Z"];
const PARABOLOID_FACES: [&str; 2] = ["+Z hemisphere", "-Z hemisphere"];
const PICK_COLOR: Color32 = Color32::from_rgb(0, 255, 255);
const RESOLUTIONS: [u32; 9] = [64, 128, 256, 512, 1024, 1536, 2048, 4096, 8192];

/// The inspector's state.
pub struct Inspector {
    setup: Setup,
    worker: Option<Worker>,
    pub loaded: Option<Box<Loaded>>,
    /// Why the scene could not be loaded (shown instead of the views).
    pub error: Option<String>,
    /// The knobs as set in the window; a change renders a new frame.
    pub options: Options,
    sent: Option<Options>,
    generation: u64,
    /// The newest frame.
    pub result: Option<Box<Rendered>>,
    textures: HashMap<String, TextureHandle>,
    pub view: View,
    /// The light of the Shadows and Light maps views, the VPL of the VPLs view.
    pub light: usize,
    pub vpl: usize,
    vpl_map: Option<Box<VplMap>>,
    vpl_requested: Option<(u64, usize)>,
    /// Zoom and pan of the screen-sized images (shared by all of them): the magnification and
    /// the centre of the visible window, in image fractions.
    zoom: f32,
    center: Vec2,
    /// The picked pixel.
    pub picked: Option<[u32; 2]>,
    /// Show wall times as "…" (snapshot tests: times vary from run to run).
    pub hide_times: bool,
    scene_field: String,
}

impl Inspector {
    /// An inspector for `setup`; its worker starts with the first frame drawn.
    pub fn new(setup: Setup) -> Self {
        Self {
            scene_field: setup.scene.clone(),
            setup,
            worker: None,
            loaded: None,
            error: None,
            options: Options::hybrid(),
            sent: None,
            generation: 0,
            result: None,
            textures: HashMap::new(),
            view: View::Frame,
            light: 0,
            vpl: 0,
            vpl_map: None,
            vpl_requested: None,
            zoom: 1.0,
            center: Vec2::splat(0.5),
            picked: None,
            hide_times: false,
        }
    }

    /// Whether the worker is loading or rendering (or a requested VPL map is on its way).
    pub fn busy(&self) -> bool {
        if self.error.is_some() {
            return false;
        }
        let vpl_pending = self.vpl_requested.is_some_and(|(g, i)| {
            self.vpl_map.as_ref().is_none_or(|m| m.index != i)
                && self.result.as_ref().is_some_and(|r| r.generation == g)
        });
        self.worker.is_none()
            || self.loaded.is_none()
            || self.result.as_ref().is_none_or(|r| r.generation != self.generation)
            || vpl_pending
    }

    /// Picks pixel `(x, y)` (as a click on it does).
    pub fn pick_pixel(&mut self, x: u32, y: u32) {
        self.picked = Some([x, y]);
    }

    /// What is known at the picked pixel.
    pub fn pixel_info(&self) -> Option<pick::PixelInfo> {
        let [x, y] = self.picked?;
        Some(pick::pick(self.loaded.as_ref()?, self.result.as_ref()?, x, y))
    }

    /// Draws the whole window (eframe's `App::ui` and the tests call this).
    pub fn show(&mut self, ui: &mut egui::Ui) {
        if self.worker.is_none() && self.error.is_none() {
            let ctx = ui.ctx().clone();
            self.worker = Some(Worker::spawn(self.setup.clone(), move || ctx.request_repaint()));
        }
        self.poll();

        egui::Panel::top("status").show(ui, |ui| self.status_bar(ui));
        if let Some(e) = self.error.clone() {
            egui::CentralPanel::default().show(ui, |ui| {
                ui.add_space(20.0);
                ui.heading(RichText::new("The scene could not be loaded").color(Color32::from_rgb(255, 110, 110)));
                ui.add_space(8.0);
                ui.label(RichText::new(e).monospace());
                ui.add_space(8.0);
                ui.label("Type another scene (a built-in name, a .toml scene file or a mesh file) above and press Open.");
            });
            return;
        }
        egui::Panel::left("knobs").default_size(250.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.knobs(ui));
        });
        egui::Panel::right("details").default_size(360.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.details(ui));
        });
        egui::CentralPanel::default().show(ui, |ui| self.central(ui));

        if self.loaded.is_some() && self.sent != Some(self.options) {
            self.generation += 1;
            self.sent = Some(self.options);
            if let Some(w) = &self.worker {
                w.send(Command::Render { generation: self.generation, options: self.options });
            }
        }
        if self.busy() {
            ui.ctx().request_repaint_after(Duration::from_millis(100));
        }
    }

    fn poll(&mut self) {
        let Some(worker) = &self.worker else { return };
        while let Some(reply) = worker.try_recv() {
            match reply {
                Reply::Loaded(l) => {
                    self.options = l.options;
                    self.loaded = Some(l);
                }
                Reply::Failed(e) => self.error = Some(e),
                Reply::Rendered(r) => {
                    self.textures.clear();
                    self.vpl_map = None;
                    self.vpl_requested = None;
                    self.light =
                        self.light.min(r.frame.stats.lights.len().max(r.maps.len()).saturating_sub(1));
                    self.vpl = self.vpl.min(r.vpls.len().saturating_sub(1));
                    self.result = Some(r);
                }
                Reply::VplMap(m) => self.vpl_map = Some(m),
            }
        }
    }

    /// Opens another scene: a new worker (the old one finishes its frame and stops).
    fn open(&mut self, scene: String) {
        self.setup.scene = scene;
        self.setup.options = None;
        self.worker = None;
        self.loaded = None;
        self.error = None;
        self.result = None;
        self.sent = None;
        self.picked = None;
        self.textures.clear();
        self.vpl_map = None;
        self.vpl_requested = None;
        self.zoom = 1.0;
        self.center = Vec2::splat(0.5);
    }

    fn ms(&self, v: f64) -> String {
        if self.hide_times { "… ms".into() } else { format!("{v:.1} ms") }
    }

    fn times(&self, s: &str) -> String {
        if self.hide_times { mask_ms(s) } else { s.to_string() }
    }

    // ---------------------------------------------------------------------------------------
    // Top bar

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.label(RichText::new("hyrt-inspect").strong());
            let field = ui.add(
                egui::TextEdit::singleline(&mut self.scene_field)
                    .hint_text("scene: built-in name, .toml or mesh file")
                    .desired_width(260.0),
            );
            let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if ui.button("Open").clicked() || enter {
                let s = self.scene_field.trim().to_string();
                self.open(s);
            }
            if let Some(l) = &self.loaded {
                let s = &l.scene;
                ui.label(format!(
                    "{}: {} triangles, {} lights, {}x{}",
                    s.name,
                    s.triangle_count(),
                    s.lights.len(),
                    s.settings.width,
                    s.settings.height
                ));
            }
        });
        ui.horizontal(|ui| {
            if self.error.is_some() {
                ui.label(RichText::new("load failed").color(Color32::from_rgb(255, 110, 110)));
            } else if self.busy() {
                let (stage, frac) = self.worker.as_ref().map_or((String::new(), 0.0), |w| w.progress.get());
                ui.spinner();
                ui.add(egui::ProgressBar::new(frac).desired_width(220.0).show_percentage());
                ui.label(stage);
            }
            if let Some(r) = &self.result {
                let hyb = r.frame.stats.time_ms.get("total").copied().unwrap_or(0.0);
                let rf = r.reference.stats.time_ms.get("total").copied().unwrap_or(0.0);
                let speed =
                    if self.hide_times || hyb <= 0.0 { "…".into() } else { format!("{:.2}x", rf / hyb) };
                ui.label(RichText::new(format!("hybrid frame {}", self.ms(hyb))).strong());
                if let Some(first) = &r.first_frame {
                    let t = first.time_ms.get("total").copied().unwrap_or(0.0);
                    let mut built = vec![];
                    if first.maps_built > 0 {
                        built.push("light maps");
                    }
                    if first.decisions.iter().any(|d| d.run && d.what == "vpls") {
                        built.push("VPLs");
                    }
                    if first.decisions.iter().any(|d| d.run && d.what == "vpl_maps") {
                        built.push("VPL maps");
                    }
                    ui.label(format!("(first frame {}: built {})", self.ms(t), built.join(", ")));
                }
                ui.label(format!("reference {} ({speed} speed-up)", self.ms(rf)));
                ui.separator();
                ui.label(RichText::new(format!("PSNR {}", psnr_text(r.psnr))).strong());
                ui.separator();
                ui.label(wrong_text(r));
            }
        });
    }

    // ---------------------------------------------------------------------------------------
    // Knobs

    fn knobs(&mut self, ui: &mut egui::Ui) {
        ui.heading("Knobs");
        let enabled = self.loaded.is_some();
        ui.add_enabled_ui(enabled, |ui| {
            ui.horizontal(|ui| {
                if ui.button("hybrid preset").clicked() {
                    self.options =
                        Options { check_visibility: self.options.check_visibility, ..Options::hybrid() };
                }
                if ui.button("reference preset").clicked() {
                    self.options = Options::reference();
                }
            });
            let o = &mut self.options;
            ui.add_space(4.0);
            ui.label(RichText::new("Visibility and shadows").strong());
            combo(
                ui,
                "visibility",
                &mut o.visibility,
                &[(Visibility::Rays, "rays"), (Visibility::Raster, "raster")],
            );
            combo(
                ui,
                "shadows",
                &mut o.shadows,
                &[(Shadows::Rays, "rays"), (Shadows::Maps, "maps"), (Shadows::Smerts, "smerts")],
            );
            let maps = o.shadows != Shadows::Rays;
            ui.add_enabled_ui(maps, |ui| {
                let sh = &mut o.shadow;
                combo(
                    ui,
                    "map kind",
                    &mut sh.map.kind,
                    &[(MapKind::Cube, "cube"), (MapKind::Paraboloid, "paraboloid")],
                );
                resolution_combo(ui, "map resolution", &mut sh.map.resolution);
                ui.add(egui::Slider::new(&mut sh.bias, 0.0..=4.0).text("bias (texels)"));
                ui.add_enabled_ui(o.shadows == Shadows::Smerts, |ui| {
                    combo(
                        ui,
                        "borders",
                        &mut sh.borders,
                        &[
                            (Borders::Laplacian, "laplacian"),
                            (Borders::Depth, "depth"),
                            (Borders::Both, "both"),
                        ],
                    );
                    ui.add(egui::Slider::new(&mut sh.dilate, 0..=4).text("dilation (px)"));
                });
                ui.add_enabled_ui(sh.map.kind == MapKind::Paraboloid, |ui| {
                    let mut tess = sh.map.tess_texels.is_finite();
                    if ui.checkbox(&mut tess, "tessellate").changed() {
                        sh.map.tess_texels = if tess { 8.0 } else { f32::INFINITY };
                    }
                    if tess {
                        ui.add(
                            egui::Slider::new(&mut sh.map.tess_texels, 1.0..=64.0)
                                .logarithmic(true)
                                .text("tessellation (texels)"),
                        );
                    }
                });
                combo(
                    ui,
                    "mirror shadows",
                    &mut sh.mirror,
                    &[(MirrorShadows::Maps, "maps"), (MirrorShadows::Rays, "rays")],
                );
                ui.checkbox(&mut o.check_visibility, "check visibility (a ray per map decision)")
                    .on_hover_text("Renders one more frame that also casts a shadow ray for every map decision and counts those it contradicts; the time shown is that of a frame without the check.");
            });
            ui.add_space(6.0);
            ui.label(RichText::new("Indirect light (VPLs)").strong());
            combo(
                ui,
                "indirect",
                &mut o.indirect,
                &[(Indirect::None, "none"), (Indirect::Rays, "rays"), (Indirect::Maps, "maps")],
            );
            ui.add_enabled_ui(o.indirect != Indirect::None, |ui| {
                let io = &mut o.indirect_opts;
                ui.add(egui::Slider::new(&mut io.vpl.paths, 0..=256).text("VPL paths"));
                ui.add(egui::Slider::new(&mut io.vpl.bounces, 1..=4).text("VPL bounces"));
                ui.add_enabled_ui(o.indirect == Indirect::Maps, |ui| {
                    resolution_combo(ui, "VPL map resolution", &mut io.map.resolution);
                });
                ui.add(egui::Slider::new(&mut io.interleave, 1..=8).text("interleave"));
            });
        });
        if let Some(r) = &self.result {
            ui.add_space(8.0);
            ui.separator();
            let dropped = if r.dropped.is_empty() {
                "nothing: every cache kept".to_string()
            } else {
                r.dropped.join(", ")
            };
            ui.label(format!("Last change dropped: {dropped}"));
            ui.label(format!(
                "Frame {} (hybrid {}, reference {}{})",
                r.generation,
                self.ms(r.frame.stats.time_ms.get("total").copied().unwrap_or(0.0)),
                self.ms(r.reference.stats.time_ms.get("total").copied().unwrap_or(0.0)),
                if r.reference_rendered { ", rendered again" } else { ", reused" }
            ));
        }
    }

    // ---------------------------------------------------------------------------------------
    // Right panel: pixel, plan, times, rays, lights

    fn details(&mut self, ui: &mut egui::Ui) {
        let Some(r) = self.result.take() else {
            ui.label("Waiting for the first frame…");
            return;
        };
        self.pixel_panel(ui, &r);
        ui.separator();
        egui::CollapsingHeader::new("Plan").default_open(true).show(ui, |ui| {
            ui.label(RichText::new("Passes (renderer.plan)").italics());
            for (run, d) in
                r.plan.run.iter().map(|d| (true, d)).chain(r.plan.skipped.iter().map(|d| (false, d)))
            {
                decision_row(ui, run, d.pass.name(), &d.reason);
            }
            ui.add_space(4.0);
            if let Some(first) = &r.first_frame {
                ui.label(RichText::new("First frame after the change (stats.decisions)").italics());
                for d in &first.decisions {
                    decision_row(ui, d.run, &d.what, &self.times(&d.reason));
                }
            }
            let this = if r.first_frame.is_some() { "The frame shown (caches warm)" } else { "This frame" };
            ui.label(RichText::new(format!("{this} (stats.decisions)")).italics());
            for d in &r.frame.stats.decisions {
                decision_row(ui, d.run, &d.what, &self.times(&d.reason));
            }
        });
        egui::CollapsingHeader::new("Time per pass").default_open(true).show(ui, |ui| {
            let first = r.first_frame.as_ref().map(|f| &f.time_ms);
            egui::Grid::new("times").striped(true).num_columns(3 + usize::from(first.is_some())).show(
                ui,
                |ui| {
                    ui.label(RichText::new("pass").strong());
                    ui.label(RichText::new("hybrid").strong());
                    ui.label(RichText::new("reference").strong());
                    if first.is_some() {
                        ui.label(RichText::new("first frame").strong());
                    }
                    ui.end_row();
                    let (h, rf) = (&r.frame.stats.time_ms, &r.reference.stats.time_ms);
                    let names = h.keys().chain(rf.keys()).chain(first.into_iter().flat_map(|f| f.keys()));
                    for pass in pass_order(names.copied()) {
                        ui.label(pass);
                        for c in [Some(h), Some(rf), first].into_iter().flatten() {
                            ui.label(c.get(pass).map_or("-".into(), |&v| self.ms(v)));
                        }
                        ui.end_row();
                    }
                },
            );
        });
        egui::CollapsingHeader::new("Rays by kind").default_open(true).show(ui, |ui| {
            egui::Grid::new("rays").striped(true).num_columns(3).show(ui, |ui| {
                ui.label(RichText::new("kind").strong());
                ui.label(RichText::new("hybrid").strong());
                ui.label(RichText::new("reference").strong());
                ui.end_row();
                let (h, rf) = (&r.frame.stats.rays, &r.reference.stats.rays);
                for (name, f) in RAY_ROWS {
                    ui.label(name);
                    ui.label(f(h).to_string());
                    ui.label(f(rf).to_string());
                    ui.end_row();
                }
            });
        });
        if !r.frame.stats.lights.is_empty() {
            egui::CollapsingHeader::new("Lights").default_open(true).show(ui, |ui| {
                egui::Grid::new("lights").striped(true).num_columns(7).show(ui, |ui| {
                    for h in ["light", "lit", "shadowed", "rays", "wrong", "faces", "map MB"] {
                        ui.label(RichText::new(h).strong());
                    }
                    ui.end_row();
                    for (l, s) in r.frame.stats.lights.iter().enumerate() {
                        ui.label(l.to_string());
                        ui.label(s.lit.to_string());
                        ui.label(s.shadowed.to_string());
                        ui.label(s.undecided.to_string());
                        ui.label(s.wrong_total().map_or("-".into(), |w| w.to_string()));
                        ui.label(s.faces_drawn.to_string());
                        ui.label(format!("{:.1}", s.map_bytes as f64 / 1048576.0));
                        ui.end_row();
                    }
                });
            });
        }
        if r.frame.stats.vpls > 0 {
            ui.label(format!(
                "{} VPLs, maps {:.1} MB",
                r.frame.stats.vpls,
                r.frame.stats.vpl_map_bytes as f64 / 1048576.0
            ));
        }
        self.result = Some(r);
    }

    fn pixel_panel(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        ui.heading("Pixel");
        let info = match (self.picked, self.loaded.as_ref()) {
            (Some([x, y]), Some(l)) => pick::pick(l, r, x, y),
            _ => {
                ui.label("Click a pixel in any image to see its triangle, material and, per light, the map's decision, the texel it read and the ray it cast.");
                return;
            }
        };
        ui.label(RichText::new(format!("pixel ({}, {})", info.x, info.y)).strong());
        match &info.hit {
            None => {
                ui.label("no camera hit (background)");
            }
            Some(h) => {
                ui.label(format!("triangle {}", h.tri));
                let m = &h.material;
                ui.label(format!("material {}", m.name));
                if m.has_highlight() {
                    ui.label(format!(
                        "  Kd {}  Ks {}  Ns {}",
                        vec3(m.diffuse),
                        vec3(m.highlight),
                        m.shininess
                    ));
                } else {
                    ui.label(format!("  Kd {}", vec3(m.diffuse)));
                }
                if m.is_mirror() {
                    ui.label(format!("  Kr {} ({})", vec3(m.mirror), m.mirror_source));
                }
                ui.label(format!("  t {:.4}  at {}", h.t, vec3(h.p)));
            }
        }
        ui.label(format!(
            "radiance hybrid {}  reference {}  |dY| {:.4}",
            vec3(info.hybrid),
            vec3(info.reference),
            info.error
        ));
        if let Some(c) = info.rays {
            ui.label(format!(
                "rays here: primary {} shadow {} (hint hits {}) specular {} VPL shadow {}",
                c.primary, c.shadow, c.shadow_hint_hits, c.specular, c.vpl_shadow
            ));
        }
        for lp in &info.lights {
            ui.add_space(2.0);
            let mut lines = vec![];
            if !lp.needed {
                lines.push("no decision: light behind the surface, no hit, or a mirror".to_string());
            } else if lp.by_rays {
                lines.push("shadows by rays: one shadow ray, no map".to_string());
            } else {
                if let Some(m) = &lp.map {
                    let face = face_name(r, lp.light, m.face);
                    lines.push(format!(
                        "map decision {}{}{}, hint {}",
                        decision_name(m.lookup.decision),
                        if m.lookup.map_border { ", map-space border" } else { "" },
                        if m.lookup.ambiguous { ", ambiguous" } else { "" },
                        tri_name(m.lookup.hint)
                    ));
                    lines.push(format!(
                        "texel face {} x {} y {} (at {:.2}, {:.2})",
                        face, m.lookup.texel[0], m.lookup.texel[1], m.x, m.y
                    ));
                    lines.push(format!(
                        "texel depth {:.4} triangle {}; point at {:.4}",
                        m.depth,
                        tri_name(m.id),
                        m.distance
                    ));
                }
                let ray = match lp.ray {
                    RAY_HINT => "ray cast: blocked by the hint (no traversal)".to_string(),
                    RAY_TRAVERSAL => format!(
                        "ray cast: traversal, {}",
                        if lp.decision == Some(hyrt_shadowmap::border::SHADOW) {
                            "blocked"
                        } else {
                            "reached the light"
                        }
                    ),
                    _ if lp.undecided => "undecided, but no ray recorded".to_string(),
                    _ => "no ray: the map decided".to_string(),
                };
                lines.push(ray);
                let mut flags = vec![];
                if lp.border {
                    flags.push("border");
                }
                if lp.undecided {
                    flags.push("after dilation: undecided");
                }
                if !flags.is_empty() {
                    lines.push(flags.join(", "));
                }
                if let Some(d) = lp.decision {
                    lines.push(format!("final: {}", decision_name(d)));
                }
                if let Some(w) = lp.wrong {
                    lines.push(if w {
                        "WRONG: a ray contradicts the map".into()
                    } else {
                        "checked: correct".into()
                    });
                }
            }
            ui.label(RichText::new(format!("light {}", lp.light)).strong());
            for l in lines {
                ui.label(format!("  {l}"));
            }
        }
    }

    // ---------------------------------------------------------------------------------------
    // Central panel

    fn central(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            for v in View::ALL {
                ui.selectable_value(&mut self.view, v, v.name());
            }
            ui.separator();
            if ui.button("zoom in").clicked() {
                self.zoom_by(2.0, None);
            }
            if ui.button("zoom out").clicked() {
                self.zoom_by(0.5, None);
            }
            if ui.button("reset view").clicked() {
                self.zoom = 1.0;
                self.center = Vec2::splat(0.5);
            }
            ui.label(format!("zoom {:.1}x", self.zoom));
        });
        ui.separator();
        let Some(r) = self.result.take() else {
            ui.label(if self.loaded.is_some() {
                "Rendering the first frame…"
            } else {
                "Loading the scene…"
            });
            return;
        };
        match self.view {
            View::Frame => self.frame_view(ui, &r),
            View::Shadows => self.shadows_view(ui, &r),
            View::Rays => self.rays_view(ui, &r),
            View::LightMaps => self.maps_view(ui, &r),
            View::Vpls => self.vpls_view(ui, &r),
        }
        self.result = Some(r);
    }

    fn frame_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        let hyb = r.frame.stats.time_ms.get("total").copied().unwrap_or(0.0);
        let rf = r.reference.stats.time_ms.get("total").copied().unwrap_or(0.0);
        let mut cells = vec![
            ("hybrid", &r.images.hybrid, format!("hybrid ({})", self.ms(hyb))),
            ("reference", &r.reference.image, format!("reference ({})", self.ms(rf))),
            ("difference", &r.images.error_heat, format!("luminance error, PSNR {}", psnr_text(r.psnr))),
        ];
        if let Some(w) = &r.images.wrong {
            cells.push((
                "wrong",
                w,
                format!("wrong map decisions, any light ({} px)", r.wrong_pixels.unwrap_or(0)),
            ));
        }
        self.screen_grid(ui, &cells, 2, 60.0);
        legend_scale(
            ui,
            self,
            "error-scale",
            views::inferno,
            "≤ 0.001",
            "1 (|ΔY| of display luminance, log)",
        );
        ui.label(wrong_text(r));
    }

    fn shadows_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        if r.options.shadows == Shadows::Rays {
            ui.label("Shadows by rays: one shadow ray per hit and light, no maps, no borders. Choose shadows = maps or smerts.");
            return;
        }
        let n = r.images.lights.len();
        if n == 0 {
            ui.label("No light needs a map (no point lights).");
            return;
        }
        self.light_selector(ui, n);
        let l = self.light;
        let li = &r.images.lights[l];
        let st = r.frame.stats.lights.get(l).copied().unwrap_or_default();
        let smerts = r.options.shadows == Shadows::Smerts;
        let cells = [
            (
                "occ",
                &li.occlusion,
                format!(
                    "light {l}: occlusion ({} lit, {} shadowed, {} by rays)",
                    st.lit, st.shadowed, st.undecided
                ),
            ),
            ("border", &li.border, "border before dilation".to_string()),
            (
                "undecided",
                &li.undecided,
                format!("after dilation by {} px: rays cast", r.options.shadow.dilate),
            ),
            ("rays", &li.rays, "selective rays: hint hit / traversal".to_string()),
        ];
        if smerts {
            self.screen_grid(ui, &cells, 2, 70.0);
        } else {
            self.screen_grid(ui, &cells[..1], 1, 70.0);
        }
        ui.horizontal_wrapped(|ui| {
            swatch(ui, views::LIT_COLOR, "lit");
            swatch(ui, views::SHADOW_COLOR, "shadowed");
            swatch(ui, views::UNDECIDED_COLOR, "decided by a ray");
            swatch(ui, views::NONE_COLOR, "no decision needed");
            swatch(ui, views::WRONG_COLOR, "wrong (visibility check)");
        });
        if smerts {
            ui.horizontal_wrapped(|ui| {
                swatch(ui, views::BORDER_COLOR, "border pixel");
                swatch(ui, views::HINT_COLOR, "hint hit");
                swatch(ui, views::TRAVERSAL_BLOCKED_COLOR, "traversal, blocked");
                swatch(ui, views::TRAVERSAL_CLEAR_COLOR, "traversal, reached the light");
            });
        }
    }

    fn rays_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        let cells: Vec<(&str, &ColorImage, String)> = r
            .images
            .rays
            .iter()
            .map(|(k, img, max)| {
                let total: u64 = RayKindView::count(*k, &r.frame.stats.rays);
                let total =
                    if *k == RayKindView::Total { total - r.frame.stats.rays.vpl_path } else { total };
                (k.name(), img, format!("{}: {total} rays, max {max} / px", k.name()))
            })
            .collect();
        if cells.is_empty() {
            ui.label("No per-pixel ray counts (they need Options::keep_buffers).");
            return;
        }
        self.screen_grid(ui, &cells, 3, 40.0);
        legend_scale(
            ui,
            self,
            "ray-scale",
            |t| views::inferno(0.15 + 0.85 * t),
            "1 ray",
            "the image's maximum (black: none)",
        );
    }

    fn maps_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        let n = r.maps.len();
        if r.options.shadows == Shadows::Rays || n == 0 {
            ui.label("No light maps: shadows by rays. Choose shadows = maps or smerts.");
            return;
        }
        self.light_selector(ui, n);
        let l = self.light;
        let (Some(map), Some(imgs)) = (r.maps[l].clone(), r.images.maps[l].as_ref()) else {
            ui.label(format!("light {l}: no map (no camera hit is in front of it)"));
            return;
        };
        ui.label(format!(
            "light {l}: {} map, {}x{} per face, {} of {} faces drawn (those camera hits fall on), {:.1} MB",
            kind_name(map.kind()),
            map.resolution(),
            map.resolution(),
            map.faces_drawn().iter().filter(|&&d| d).count(),
            map.faces(),
            map.memory_bytes() as f64 / 1048576.0
        ));
        // The texel the picked pixel read, marked on its face.
        let marker = self.picked.zip(self.loaded.as_ref()).and_then(|([x, y], loaded)| {
            pick::pick(loaded, r, x, y).lights.get(l).and_then(|lp| lp.map.clone())
        });
        let cols = if map.faces() == 6 { 3 } else { 2 };
        let avail = ui.available_size() - Vec2::new(0.0, 50.0);
        let rows = map.faces().div_ceil(cols);
        let side = ((avail.x - 8.0 * (cols as f32 - 1.0)) / cols as f32)
            .min((avail.y - rows as f32 * 22.0) / rows as f32)
            .max(32.0);
        for row in 0..rows {
            ui.horizontal(|ui| {
                for f in row * cols..((row + 1) * cols).min(map.faces()) {
                    ui.vertical(|ui| {
                        let name = face_name(r, l, f as u8);
                        ui.label(format!("face {name}"));
                        let label = format!("light {l} face {name}");
                        match &imgs.faces[f] {
                            Some(img) => {
                                let key = format!("map-{l}-{f}");
                                let rect = self.plain_image(ui, &key, img, &label, Vec2::splat(side));
                                if let Some(m) = marker.as_ref().filter(|m| usize::from(m.face) == f) {
                                    let p = rect.min
                                        + Vec2::new(m.x, m.y) / map.resolution() as f32 * rect.size();
                                    crosshair(ui, p);
                                }
                            }
                            None => {
                                let (rect, _) = ui.allocate_exact_size(Vec2::splat(side), Sense::hover());
                                ui.painter().rect_filled(rect, 0.0, views::OUTSIDE_COLOR);
                                ui.painter().text(
                                    rect.center(),
                                    Align2::CENTER_CENTER,
                                    "not drawn",
                                    FontId::proportional(13.0),
                                    Color32::LIGHT_GRAY,
                                );
                            }
                        }
                    });
                }
            });
        }
        depth_legend(ui, self, imgs.range);
    }

    fn vpls_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        if r.vpls.is_empty() {
            ui.label("No VPLs: indirect light is off. Choose indirect = rays or maps.");
            return;
        }
        let n = r.vpls.len();
        ui.horizontal(|ui| {
            ui.add(egui::Slider::new(&mut self.vpl, 0..=n - 1).text("VPL"));
            ui.label(format!(
                "of {n} (dots: white in view, hollow: hidden behind a surface; red: the chosen one)"
            ));
        });
        let v = r.vpls[self.vpl];
        ui.label(format!(
            "VPL {}: at {} normal {} intensity {} on triangle {}",
            self.vpl,
            vec3(v.position),
            vec3(v.normal),
            vec3(v.intensity),
            v.tri
        ));
        if r.vpl_maps > 0 {
            let want = (r.generation, self.vpl);
            if self.vpl_requested != Some(want) {
                if let Some(w) = &self.worker {
                    w.send(Command::VplMap(self.vpl));
                }
                self.vpl_requested = Some(want);
            }
        }
        let avail = ui.available_size() - Vec2::new(0.0, 40.0);
        let (w, h) = (r.images.hybrid.size[0] as f32, r.images.hybrid.size[1] as f32);
        let img_w = (avail.x * 0.6).min(avail.y * w / h);
        let map_side = (avail.x - img_w - 16.0).min(avail.y - 22.0).max(32.0);
        let mut clicked_vpl = None;
        ui.horizontal(|ui| {
            ui.vertical(|ui| {
                ui.label("VPLs over the hybrid frame");
                let placed = self.screen_image(
                    ui,
                    "vpl-frame",
                    &r.images.hybrid,
                    "VPL positions",
                    Vec2::new(img_w, img_w * h / w),
                );
                let cam = self.loaded.as_ref().map(|l| l.camera);
                let g = r.frame.gbuffer.as_ref();
                let painter = ui.painter().with_clip_rect(placed.rect);
                let mut nearest: Option<(f32, usize)> = None;
                for (i, vpl) in r.vpls.iter().enumerate() {
                    let Some((fx, fy, _)) = cam.and_then(|c| views::project(&c, vpl.position)) else {
                        continue;
                    };
                    let p = placed.to_screen(fx, fy);
                    // Hidden when the pixel's camera hit is clearly nearer than the VPL (the
                    // pixel's centre ray meets the VPL's surface a little off its position).
                    let (ix, iy) = (fx.floor() as i64, fy.floor() as i64);
                    let inside = ix >= 0 && iy >= 0 && (ix as f32) < w && (iy as f32) < h;
                    let d = cam.map_or(0.0, |c| (vpl.position - c.eye).length());
                    let hidden = inside
                        && g.and_then(|g| g[iy as usize * w as usize + ix as usize])
                            .is_some_and(|hit| hit.t < d * 0.98);
                    let chosen = i == self.vpl;
                    let (rad, col) = if chosen { (5.0, Color32::RED) } else { (3.0, Color32::WHITE) };
                    if hidden {
                        painter.circle_stroke(p, rad, Stroke::new(1.5, col));
                    } else {
                        painter.circle(p, rad, col, Stroke::new(1.0, Color32::BLACK));
                    }
                    if let Some(c) = placed.clicked_at {
                        let d = c.distance(p);
                        if d < 10.0 && nearest.is_none_or(|(b, _)| d < b) {
                            nearest = Some((d, i));
                        }
                    }
                }
                clicked_vpl = nearest.map(|(_, i)| i);
            });
            let shown = self
                .vpl_map
                .as_ref()
                .filter(|m| m.index == self.vpl)
                .map(|m| (m.index, m.resolution, m.image.clone()));
            ui.vertical(|ui| match shown {
                Some((index, res, Some(img))) => {
                    ui.label(format!("VPL {index} map ({res}x{res}, the hemisphere around its normal)"));
                    let key = format!("vpl-map-{index}");
                    self.plain_image(ui, &key, &img, &format!("VPL {index} map"), Vec2::splat(map_side));
                }
                Some((_, _, None)) => {
                    ui.label("this VPL has no map");
                }
                None if r.vpl_maps == 0 => {
                    ui.label("VPL maps exist only with indirect = maps.");
                }
                None => {
                    ui.spinner();
                }
            });
        });
        if let Some(i) = clicked_vpl {
            self.vpl = i;
        }
        if let Some(m) = self.vpl_map.as_ref().filter(|m| m.index == self.vpl && m.image.is_some()) {
            let range = m.range;
            depth_legend(ui, self, range);
        }
    }

    fn light_selector(&mut self, ui: &mut egui::Ui, n: usize) {
        if n > 1 {
            ui.add(egui::Slider::new(&mut self.light, 0..=n - 1).text("light"));
        }
        self.light = self.light.min(n - 1);
    }

    // ---------------------------------------------------------------------------------------
    // Images

    fn texture(&mut self, ctx: &egui::Context, key: &str, image: &ColorImage) -> TextureHandle {
        self.textures
            .entry(key.to_string())
            .or_insert_with(|| ctx.load_texture(key, image.clone(), TextureOptions::NEAREST))
            .clone()
    }

    /// Screen-sized images in a grid of `cols` columns, as large as fits with `below` points
    /// left under them; each captioned. Returns nothing: picking and zoom are handled inside.
    fn screen_grid(
        &mut self,
        ui: &mut egui::Ui,
        cells: &[(&str, &ColorImage, String)],
        cols: usize,
        below: f32,
    ) {
        let Some((_, first, _)) = cells.first() else { return };
        let aspect = first.size[0] as f32 / first.size[1].max(1) as f32;
        let rows = cells.len().div_ceil(cols);
        let sp = ui.spacing().item_spacing;
        let avail = ui.available_size() - Vec2::new(0.0, below);
        let cell_w = (avail.x - sp.x * (cols as f32 - 1.0)) / cols as f32;
        let cell_h = (avail.y - rows as f32 * (20.0 + sp.y)) / rows as f32;
        let w = cell_w.min(cell_h * aspect).max(16.0);
        let size = Vec2::new(w, w / aspect);
        for row in cells.chunks(cols) {
            ui.horizontal(|ui| {
                for (key, img, caption) in row {
                    ui.vertical(|ui| {
                        ui.set_width(size.x);
                        ui.label(caption.as_str());
                        self.screen_image(ui, key, img, &format!("{key} image"), size);
                    });
                }
            });
        }
    }

    /// A screen-sized image: zoom (scroll), pan (drag), pick (click), reset (double-click),
    /// with the picked pixel marked.
    fn screen_image(
        &mut self,
        ui: &mut egui::Ui,
        key: &str,
        image: &ColorImage,
        label: &str,
        size: Vec2,
    ) -> Placed {
        let tex = self.texture(ui.ctx(), key, image);
        let (rect, resp) = ui.allocate_exact_size(size, Sense::click_and_drag());
        let label = label.to_string();
        resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Image, true, &label));
        let img = Vec2::new(image.size[0] as f32, image.size[1] as f32);
        let mut clicked_at = None;
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let at = resp.hover_pos().map(|p| (p - rect.min) / rect.size());
                self.zoom_by((scroll * 0.004).exp(), at);
            }
        }
        if resp.dragged() {
            self.center -= resp.drag_delta() / rect.size() / self.zoom;
            self.clamp_view();
        }
        if resp.double_clicked() {
            self.zoom = 1.0;
            self.center = Vec2::splat(0.5);
        } else if resp.clicked()
            && let Some(p) = resp.interact_pointer_pos()
        {
            clicked_at = Some(p);
            let placed = Placed { rect, uv: self.uv(), img, clicked_at: None };
            let (fx, fy) = placed.to_image(p);
            if fx >= 0.0 && fy >= 0.0 && fx < img.x && fy < img.y {
                self.picked = Some([fx as u32, fy as u32]);
            }
        }
        let uv = self.uv();
        ui.painter().image(tex.id(), rect, uv, Color32::WHITE);
        let placed = Placed { rect, uv, img, clicked_at };
        if let Some([x, y]) = self.picked {
            let a = placed.to_screen(x as f32, y as f32);
            let b = placed.to_screen(x as f32 + 1.0, y as f32 + 1.0);
            let r = Rect::from_min_max(a, b).expand(1.5);
            ui.painter().with_clip_rect(rect).rect_stroke(
                r,
                0.0,
                Stroke::new(1.5, PICK_COLOR),
                egui::StrokeKind::Outside,
            );
        }
        placed
    }

    /// An image fitted into `size` (no zoom); returns where it was drawn.
    fn plain_image(
        &mut self,
        ui: &mut egui::Ui,
        key: &str,
        image: &ColorImage,
        label: &str,
        size: Vec2,
    ) -> Rect {
        let tex = self.texture(ui.ctx(), key, image);
        let (rect, resp) = ui.allocate_exact_size(size, Sense::hover());
        let label = label.to_string();
        resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Image, true, &label));
        ui.painter().image(
            tex.id(),
            rect,
            Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
            Color32::WHITE,
        );
        rect
    }

    fn uv(&self) -> Rect {
        let half = Vec2::splat(0.5 / self.zoom);
        Rect::from_min_max((self.center - half).to_pos2(), (self.center + half).to_pos2())
    }

    /// Zooms by `factor` keeping image point `at` (fractions of the visible window) in place.
    fn zoom_by(&mut self, factor: f32, at: Option<Vec2>) {
        let at = at.unwrap_or(Vec2::splat(0.5));
        let uv = self.uv();
        let fixed = uv.min.to_vec2() + at * uv.size();
        let zoom = (self.zoom * factor).clamp(1.0, 64.0);
        // The fixed point keeps its place in the window.
        self.center = fixed + (Vec2::splat(0.5) - at) / zoom;
        self.zoom = zoom;
        self.clamp_view();
    }

    fn clamp_view(&mut self) {
        let half = 0.5 / self.zoom;
        self.center.x = self.center.x.clamp(half, 1.0 - half);
        self.center.y = self.center.y.clamp(half, 1.0 - half);
    }
}

impl eframe::App for Inspector {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }
}

/// Where a screen-sized image was drawn, and which part of it is visible.
struct Placed {
    rect: Rect,
    uv: Rect,
    /// Image size in pixels.
    img: Vec2,
    /// Where it was clicked this frame.
    clicked_at: Option<Pos2>,
}

impl Placed {
    /// Screen position of image point `(fx, fy)` (pixel units).
    fn to_screen(&self, fx: f32, fy: f32) -> Pos2 {
        let u = (Vec2::new(fx, fy) / self.img - self.uv.min.to_vec2()) / self.uv.size();
        self.rect.min + u * self.rect.size()
    }

    /// Image point (pixel units) under screen position `p`.
    fn to_image(&self, p: Pos2) -> (f32, f32) {
        let u = (p - self.rect.min) / self.rect.size() * self.uv.size() + self.uv.min.to_vec2();
        (u.x * self.img.x, u.y * self.img.y)
    }
}

/// A row of the rays table: its name and the count it shows.
type RayRow = (&'static str, fn(&RayCounts) -> u64);

const RAY_ROWS: [RayRow; 8] = [
    ("primary", |c| c.primary),
    ("shadow", |c| c.shadow),
    ("  hint hits", |c| c.shadow_hint_hits),
    ("  traversals", |c| c.shadow_traversals()),
    ("specular", |c| c.specular),
    ("VPL shadow", |c| c.vpl_shadow),
    ("VPL path", |c| c.vpl_path),
    ("total", |c| c.total()),
];

/// Passes in pipeline order (then any others, then `total`).
fn pass_order<'a>(names: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let rank = hyrt::render::Pass::rank;
    let mut v: Vec<&str> = names.collect();
    v.sort_by_key(|n| (rank(n), *n));
    v.dedup();
    v
}

/// Replaces every number followed by " ms" with "…" (for snapshots).
pub fn mask_ms(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let chars: Vec<char> = s.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        if chars[i].is_ascii_digit() {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            let rest: String = chars[i..].iter().take(3).collect();
            if rest == " ms" {
                out.push('…');
            } else {
                out.extend(&chars[start..i]);
            }
        } else {
            out.push(chars[i]);
            i += 1;
        }
    }
    out
}

fn psnr_text(p: f64) -> String {
    if p.is_infinite() { "inf dB (identical)".into() } else { format!("{p:.2} dB") }
}

fn wrong_text(r: &Rendered) -> String {
    match r.wrong_pixels {
        Some(px) => {
            let pairs: u64 = r.frame.stats.lights.iter().filter_map(|l| l.wrong_total()).sum();
            format!("wrong visibility: {px} pixels ({pairs} pixel-light pairs)")
        }
        None if r.options.shadows == Shadows::Rays => {
            "wrong visibility: none possible (shadows by rays)".into()
        }
        None => "wrong visibility: not checked (turn on 'check visibility')".into(),
    }
}

fn vec3(v: glam::Vec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}

fn kind_name(k: MapKind) -> &'static str {
    match k {
        MapKind::Cube => "cube",
        MapKind::Paraboloid => "dual-paraboloid",
    }
}

fn face_name(r: &Rendered, l: usize, face: u8) -> String {
    let kind = r.maps.get(l).cloned().flatten().map_or(MapKind::Cube, |m: std::sync::Arc<LightMap>| m.kind());
    let names: &[&str] = if kind == MapKind::Cube { &CUBE_FACES } else { &PARABOLOID_FACES };
    names.get(usize::from(face)).map_or(face.to_string(), |s| s.to_string())
}

fn decision_row(ui: &mut egui::Ui, run: bool, what: &str, reason: &str) {
    ui.horizontal_wrapped(|ui| {
        let (t, c) = if run {
            ("run ", Color32::from_rgb(110, 210, 110))
        } else {
            ("skip", Color32::from_rgb(170, 170, 170))
        };
        ui.label(RichText::new(t).monospace().color(c));
        ui.label(RichText::new(what).monospace().strong());
        ui.label(reason);
    });
}

/// A generic combo box over labelled values.
fn combo<T: PartialEq + Copy>(ui: &mut egui::Ui, label: &str, value: &mut T, choices: &[(T, &str)]) {
    let current = choices.iter().find(|(v, _)| v == value).map_or("?", |(_, n)| n);
    egui::ComboBox::from_label(label).selected_text(current).show_ui(ui, |ui| {
        for (v, name) in choices {
            ui.selectable_value(value, *v, *name);
        }
    });
}

fn resolution_combo(ui: &mut egui::Ui, label: &str, value: &mut u32) {
    egui::ComboBox::from_label(label).selected_text(format!("{0}x{0}", *value)).show_ui(ui, |ui| {
        for r in RESOLUTIONS {
            ui.selectable_value(value, r, format!("{r}x{r}"));
        }
    });
}

fn swatch(ui: &mut egui::Ui, color: Color32, text: &str) {
    let (rect, _) = ui.allocate_exact_size(Vec2::splat(12.0), Sense::hover());
    ui.painter().rect_filled(rect, 2.0, color);
    ui.painter().rect_stroke(rect, 2.0, Stroke::new(1.0, Color32::GRAY), egui::StrokeKind::Inside);
    ui.label(text);
}

fn legend_scale(
    ui: &mut egui::Ui,
    app: &mut Inspector,
    key: &str,
    scale: impl Fn(f32) -> Color32,
    lo: &str,
    hi: &str,
) {
    ui.horizontal(|ui| {
        ui.label(lo);
        let strip = views::scale_strip(160, 1, scale);
        let tex = app.texture(ui.ctx(), key, &strip);
        let (rect, _) = ui.allocate_exact_size(Vec2::new(160.0, 12.0), Sense::hover());
        ui.painter().image(
            tex.id(),
            rect,
            Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
            Color32::WHITE,
        );
        ui.label(hi);
    });
}

fn depth_legend(ui: &mut egui::Ui, app: &mut Inspector, range: Option<(f32, f32)>) {
    match range {
        Some((near, far)) => legend_scale(
            ui,
            app,
            "depth-scale",
            views::viridis,
            &format!("near {near:.3}"),
            &format!("far {far:.3} (distance from the light, log; black: empty, grey: outside)"),
        ),
        None => {
            ui.label("empty map");
        }
    }
}

fn crosshair(ui: &egui::Ui, p: Pos2) {
    let s = Stroke::new(1.5, PICK_COLOR);
    ui.painter().line_segment([p - Vec2::new(7.0, 0.0), p + Vec2::new(7.0, 0.0)], s);
    ui.painter().line_segment([p - Vec2::new(0.0, 7.0), p + Vec2::new(0.0, 7.0)], s);
    ui.painter().circle_stroke(p, 4.0, s);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_are_masked() {
        assert_eq!(mask_ms("reused: built once (12.5 ms), 3 lights"), "reused: built once (… ms), 3 lights");
        assert_eq!(mask_ms("1.0 ms and 2 ms, 3 px"), "… ms and … ms, 3 px");
        assert_eq!(mask_ms("no times"), "no times");
    }

    #[test]
    fn passes_in_pipeline_order() {
        let v = pass_order(["total", "direct", "aaa", "visibility", "classify", "direct"].into_iter());
        assert_eq!(v, vec!["visibility", "classify", "direct", "aaa", "total"]);
    }
}
