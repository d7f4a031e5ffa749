//! The window: knobs on the left, the views in the middle, the picked pixel and the frame's
//! plan, times and rays on the right. All rendering happens on the [`Worker`]'s thread; this
//! side only uploads the images it made and draws.

use std::collections::{BTreeMap, BTreeSet, HashMap, VecDeque};
use std::time::{Duration, Instant};

use eframe::egui::{
    self, Align2, Color32, ColorImage, FontId, Pos2, Rect, RichText, Sense, Stroke, TextureHandle,
    TextureOptions, Vec2,
};
use glam::Vec3 as V3;
use hyrt::options::{Choice, Indirect, IndirectOptions, LightMaps, Options, Shadows};
use hyrt::render::{Cache, FrameStats, Subject};
use hyrt::render::{Pass, shadows::BorderRay};
use hyrt_shadowmap::{LightMap, MapKind};
use hyrt_tracer::RayCounts;

use crate::navigate;
use crate::pick::{self, decision_name, tri_name};
use crate::views::{self, RayKindView};
use crate::worker::{Command, Loaded, Pose, Render, Rendered, Reply, Setup, VplMap, Worker};

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
/// The key that brings the camera back to the scene file's.
pub const RESET_KEY: egui::Key = egui::Key::R;
/// How long the frame-time graph looks back.
const HISTORY: Duration = Duration::from_secs(5);
/// Radians the camera turns per point the pointer moves (orbit and look).
const TURN_PER_POINT: f32 = 0.006;

/// What was last asked of the worker.
#[derive(Clone, Debug, PartialEq)]
struct Sent {
    options: Options,
    pose: Pose,
    full: bool,
    reference: bool,
}

/// A frame received, for the fps and the frame-time graph.
struct Sample {
    at: Instant,
    /// Milliseconds per top-level pass ([`Pass::part_of`] is `None`) and the frame's total.
    passes: BTreeMap<Pass, f64>,
    total: f64,
}

/// What a drag in the viewport is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Drag {
    Orbit,
    Pan,
    Look,
    /// Moving the chosen light along a world axis (0: x, 1: y, 2: z).
    Light(usize),
}

/// The inspector's state.
pub struct Inspector {
    setup: Setup,
    worker: Option<Worker>,
    pub loaded: Option<Box<Loaded>>,
    /// Why the scene could not be loaded (shown instead of the views).
    pub error: Option<String>,
    /// The knobs as set in the window; a change renders a new frame.
    pub options: Options,
    sent: Option<Sent>,
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
    /// Where the camera and lights are (the scene file's until moved); `home` is the file's.
    pub pose: Option<Pose>,
    home: Option<Pose>,
    /// When the camera or a light last moved: frames stay light (the hybrid image alone) until
    /// the input has rested for `rest`; then the full frame, its views and the reference.
    moved_at: Option<Instant>,
    pub rest: Duration,
    /// Render the reference whenever the camera rests (else only when asked).
    pub auto_reference: bool,
    /// The pose and options the reference was asked for by hand.
    reference_asked: Option<(Options, Pose)>,
    history: VecDeque<Sample>,
    drag: Option<Drag>,
    /// The light the viewport's gizmo moves.
    pub light_edit: usize,
    /// Fly speed in scene units per second (from the scene's size).
    fly_speed: f32,
    camera_toml: Option<String>,
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
            pose: None,
            home: None,
            moved_at: None,
            rest: Duration::from_millis(300),
            auto_reference: true,
            reference_asked: None,
            history: VecDeque::new(),
            drag: None,
            light_edit: 0,
            fly_speed: 1.0,
            camera_toml: None,
        }
    }

    /// Whether the camera or a light moved less than `rest` ago.
    pub fn moving(&self) -> bool {
        self.moved_at.is_some_and(|t| t.elapsed() < self.rest)
    }

    /// What the worker should render now.
    fn wanted(&self) -> Option<Sent> {
        let pose = self.pose.clone()?;
        let full = !self.moving();
        let reference = full
            && (self.auto_reference
                || self.reference_asked.as_ref().is_some_and(|(o, p)| *o == self.options && *p == pose));
        Some(Sent { options: self.options, pose, full, reference })
    }

    /// Moves the camera (as a drag, the wheel or a key does), rendering from there.
    pub fn set_camera(&mut self, camera: hyrt::scene::Camera) {
        if let Some(p) = &mut self.pose
            && p.camera != camera
        {
            p.camera = camera;
            self.moved_at = Some(Instant::now());
        }
    }

    /// Moves light `l` to `position`.
    pub fn move_light(&mut self, l: usize, position: V3) {
        if let Some(light) = self.pose.as_mut().and_then(|p| p.lights.get_mut(l))
            && light.position != position
            && position.is_finite()
        {
            light.position = position;
            self.moved_at = Some(Instant::now());
        }
    }

    /// Back to the scene file's camera (the reset key). The lights stay where they are.
    pub fn reset_camera(&mut self) {
        if let Some(home) = self.home.clone() {
            self.set_camera(home.camera);
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
        // A full frame that asked for its reference waits for it (the worker sends it unless a
        // newer command came first, which then answers instead).
        let reference_pending = self.result.as_ref().is_some_and(|r| {
            r.generation == self.generation
                && r.comparison.is_none()
                && self.sent.as_ref().is_some_and(|s| s.full && s.reference)
        });
        self.worker.is_none()
            || self.loaded.is_none()
            || self.result.as_ref().is_none_or(|r| r.generation != self.generation)
            || vpl_pending
            || reference_pending
            || self.moving()
            || self.wanted() != self.sent
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
            egui::ScrollArea::vertical().show(ui, |ui| {
                self.camera_panel(ui);
                ui.add_space(8.0);
                ui.separator();
                self.knobs(ui);
            });
        });
        egui::Panel::right("details").default_size(360.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.details(ui));
        });
        egui::CentralPanel::default().show(ui, |ui| self.central(ui));
        self.keys(ui.ctx());

        // Commands never wait for a frame: the worker renders the newest when it is free.
        if let Some(want) = self.wanted()
            && self.sent.as_ref() != Some(&want)
        {
            self.generation += 1;
            if let Some(w) = &self.worker {
                w.send(Command::Render(Render {
                    generation: self.generation,
                    options: want.options,
                    pose: want.pose.clone(),
                    full: want.full,
                    reference: want.reference,
                }));
            }
            self.sent = Some(want);
        }
        if let Some(t) = self.moved_at.filter(|_| self.moving()) {
            // Wake up when the input has rested, for the full frame.
            ui.ctx().request_repaint_after(self.rest.saturating_sub(t.elapsed()));
        }
        if self.busy() {
            ui.ctx().request_repaint_after(Duration::from_millis(100));
        }
    }

    /// The reset key, and WASD/QE flight while the right button is held over the viewport.
    fn keys(&mut self, ctx: &egui::Context) {
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let Some(cam) = self.pose.as_ref().map(|p| p.camera) else { return };
        if ctx.input(|i| i.key_pressed(RESET_KEY)) {
            self.reset_camera();
            return;
        }
        if self.drag != Some(Drag::Look) {
            return;
        }
        let (dt, step) = ctx.input(|i| {
            let axis = |neg: egui::Key, pos: egui::Key| {
                f32::from(u8::from(i.key_down(pos))) - f32::from(u8::from(i.key_down(neg)))
            };
            let step = V3::new(
                axis(egui::Key::A, egui::Key::D),
                axis(egui::Key::Q, egui::Key::E),
                axis(egui::Key::S, egui::Key::W),
            );
            (i.stable_dt.min(0.1), step)
        });
        if step != V3::ZERO {
            let fast = if ctx.input(|i| i.modifiers.shift) { 4.0 } else { 1.0 };
            self.set_camera(navigate::fly(&cam, step * (self.fly_speed * fast * dt)));
            ctx.request_repaint();
        }
    }

    fn poll(&mut self) {
        let Some(worker) = &self.worker else { return };
        while let Some(reply) = worker.try_recv() {
            match reply {
                Reply::Loaded(l) => {
                    self.options = l.options;
                    let pose = Pose::of(&l.scene);
                    self.fly_speed =
                        l.scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length() * 0.25).max(1e-6);
                    self.home = Some(pose.clone());
                    self.pose = Some(pose);
                    self.loaded = Some(l);
                }
                Reply::Failed(e) => self.error = Some(e),
                Reply::Rendered(r) => {
                    let total = r.frame.stats.total_ms;
                    let passes = r
                        .frame
                        .stats
                        .pass_ms
                        .iter()
                        .filter(|(k, _)| k.part_of().is_none())
                        .map(|(k, v)| (*k, *v))
                        .collect();
                    let now = Instant::now();
                    self.history.push_back(Sample { at: now, passes, total });
                    while self.history.front().is_some_and(|s| now - s.at > HISTORY) {
                        self.history.pop_front();
                    }
                    self.textures.clear();
                    self.vpl_map = None;
                    self.vpl_requested = None;
                    self.light =
                        self.light.min(r.frame.stats.lights.len().max(r.maps.len()).saturating_sub(1));
                    self.vpl = self.vpl.min(r.vpls.len().saturating_sub(1));
                    self.result = Some(r);
                }
                Reply::Compared { generation, comparison } => {
                    if let Some(r) = self.result.as_mut().filter(|r| r.generation == generation) {
                        r.comparison = Some(*comparison);
                        self.textures.remove("reference");
                        self.textures.remove("difference");
                    }
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
        self.pose = None;
        self.home = None;
        self.moved_at = None;
        self.history.clear();
        self.light_edit = 0;
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
                let hyb = r.frame.stats.total_ms;
                ui.label(RichText::new(format!("hybrid frame {}", self.ms(hyb))).strong());
                if let Some(first) = &r.first_frame {
                    let t = first.total_ms;
                    let mut built = vec![];
                    if first.maps_built > 0 {
                        built.push("light maps");
                    }
                    if first.decisions.iter().any(|d| d.run && d.what == Subject::Vpls) {
                        built.push("VPLs");
                    }
                    if first.decisions.iter().any(|d| d.run && d.what == Subject::VplMaps) {
                        built.push("VPL maps");
                    }
                    ui.label(format!("(first frame {}: built {})", self.ms(t), built.join(", ")));
                }
                match &r.comparison {
                    Some(c) => {
                        let rf = c.reference.stats.total_ms;
                        let speed = if self.hide_times || hyb <= 0.0 {
                            "…".into()
                        } else {
                            format!("{:.2}x", rf / hyb)
                        };
                        ui.label(format!("reference {} ({speed} speed-up)", self.ms(rf)));
                        ui.separator();
                        ui.label(RichText::new(format!("PSNR {}", psnr_text(c.psnr))).strong());
                    }
                    None => {
                        ui.label(reference_wait(r.full, self.auto_reference));
                    }
                }
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
            combo(ui, "visibility", &mut o.visibility);
            combo(ui, "shadows", &mut o.shadows);
            let maps = o.shadows != Shadows::Rays;
            ui.add_enabled_ui(maps, |ui| {
                let sh = &mut o.shadow;
                combo(ui, "map kind", &mut sh.map.kind);
                combo(ui, "light maps", &mut sh.light_maps);
                let paged = sh.light_maps == LightMaps::Paged && sh.map.kind == MapKind::Cube;
                ui.add_enabled_ui(!paged, |ui| resolution_combo(ui, "map resolution", &mut sh.map.resolution));
                ui.add_enabled_ui(paged, |ui| {
                    ui.add(egui::Slider::new(&mut sh.map_detail, knob_range("map-detail")).text("map detail (texels per pixel)"));
                    ui.add(egui::Slider::new(&mut sh.map_budget, knob_range("map-budget")).text("map budget (MB per light)"));
                });
                ui.add(egui::Slider::new(&mut sh.bias, knob_range("bias")).text("bias (texels)"));
                ui.add_enabled_ui(o.shadows == Shadows::Smerts, |ui| {
                    combo(ui, "borders", &mut sh.borders);
                    ui.add(egui::Slider::new(&mut sh.dilate, knob_range("dilate")).text("dilation (px)"));
                    combo(ui, "ambiguous borders", &mut sh.ambiguous).on_hover_text(
                        "Border pairs made only by occluders within the bias band: a whole shadow ray, or those triangles alone tested with it.",
                    );
                });
                ui.add_enabled_ui(sh.map.kind == MapKind::Paraboloid, |ui| {
                    let mut tess = sh.map.tess_texels.is_finite();
                    if ui.checkbox(&mut tess, "tessellate").changed() {
                        sh.map.tess_texels =
                            if tess { hyrt_shadowmap::MapOptions::default().tess_texels } else { f32::INFINITY };
                    }
                    if tess {
                        ui.add(
                            egui::Slider::new(&mut sh.map.tess_texels, knob_range("tess"))
                                .logarithmic(true)
                                .text("tessellation (texels)"),
                        );
                    }
                });
                combo(ui, "mirror shadows", &mut sh.mirror);
                ui.checkbox(&mut o.check_visibility, "check visibility (a ray per map decision)")
                    .on_hover_text("Renders one more frame that also casts a shadow ray for every map decision and counts those it contradicts; the time shown is that of a frame without the check.");
            });
            ui.add_space(6.0);
            ui.label(RichText::new("Indirect light (VPLs)").strong());
            combo(ui, "indirect", &mut o.indirect);
            ui.add_enabled_ui(o.indirect != Indirect::None, |ui| {
                let io = &mut o.indirect_opts;
                ui.add(egui::Slider::new(&mut io.vpl.paths, knob_range("vpls")).text("VPL paths"));
                ui.add(egui::Slider::new(&mut io.vpl.bounces, knob_range("vpl-bounces")).text("VPL bounces"));
                ui.add(egui::DragValue::new(&mut io.vpl.seed).prefix("VPL seed "));
                ui.add(
                    egui::Slider::new(&mut io.clamp, knob_range("vpl-clamp"))
                        .logarithmic(true)
                        .text("VPL clamp (of the diagonal)"),
                );
                ui.add_enabled_ui(o.indirect == Indirect::Maps, |ui| {
                    resolution_combo(ui, "VPL map resolution", &mut io.map.resolution);
                    combo(ui, "VPL map format", &mut io.format);
                    combo(ui, "VPL filter", &mut io.filter);
                    ui.add(egui::Slider::new(&mut io.bias, knob_range("vpl-bias")).text("VPL bias (texels)"));
                    let mut tess = io.map.tess_texels.is_finite();
                    if ui.checkbox(&mut tess, "tessellate VPL maps").changed() {
                        io.map.tess_texels = if tess { IndirectOptions::default().map.tess_texels } else { f32::INFINITY };
                    }
                    if tess {
                        ui.add(
                            egui::Slider::new(&mut io.map.tess_texels, knob_range("vpl-tess"))
                                .logarithmic(true)
                                .text("VPL tessellation (texels)"),
                        );
                    }
                });
                ui.add(egui::Slider::new(&mut io.interleave, knob_range("interleave")).text("interleave"));
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
            let reference = match &r.comparison {
                Some(c) => format!(
                    "reference {}{}",
                    self.ms(c.reference.stats.total_ms),
                    if c.rendered { ", rendered again" } else { ", reused" }
                ),
                None => "no reference yet".into(),
            };
            ui.label(format!(
                "Frame {} ({}hybrid {}, {reference})",
                r.generation,
                if r.full { "" } else { "moving: " },
                self.ms(r.frame.stats.total_ms),
            ));
        }
    }

    /// The camera (position, reset, copy as TOML), the reference's schedule, and the lights.
    fn camera_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Camera and lights");
        let Some(pose) = self.pose.clone() else { return };
        let c = pose.camera;
        ui.label("Drag the hybrid image: left orbits, shift-left or middle pans, the wheel dollies; hold the right button to look around and fly with W A S D, Q E (shift: faster).");
        ui.label(RichText::new(format!("eye {}", vec3(c.eye))).monospace());
        ui.label(RichText::new(format!("target {}", vec3(navigate::target(&c)))).monospace());
        ui.label(RichText::new(format!("fov_y {:.2}", c.fov_y_deg)).monospace());
        ui.horizontal(|ui| {
            if ui.button(format!("scene camera ({RESET_KEY:?})")).clicked() {
                self.reset_camera();
            }
            if ui.button("copy as TOML").clicked() {
                let t = navigate::toml(&c);
                ui.ctx().copy_text(t.clone());
                self.camera_toml = Some(t);
            }
        });
        if let Some(t) = &self.camera_toml {
            let mut text = t.clone();
            let label = ui.label("copied (paste it into a scene file):");
            ui.add(egui::TextEdit::multiline(&mut text).code_editor().desired_rows(5)).labelled_by(label.id);
        }
        ui.checkbox(&mut self.auto_reference, "reference when the camera rests")
            .on_hover_text("Renders the ray-traced reference and the error views once the camera and lights stop moving; off: only when asked.");
        if ui
            .add_enabled(
                !self.auto_reference && self.result.as_ref().is_some_and(|r| r.comparison.is_none()),
                egui::Button::new("render the reference now"),
            )
            .clicked()
        {
            self.reference_asked = Some((self.options, pose.clone()));
        }
        let n = pose.lights.len();
        if n == 0 {
            return;
        }
        ui.add_space(4.0);
        ui.label(RichText::new("Move a light").strong());
        if n > 1 {
            ui.add(egui::Slider::new(&mut self.light_edit, 0..=n - 1).text("light to move"));
        }
        self.light_edit = self.light_edit.min(n - 1);
        let l = self.light_edit;
        let mut p = pose.lights[l].position;
        let speed = self.fly_speed * 0.01;
        ui.horizontal(|ui| {
            ui.label(format!("light {l}"));
            for (axis, name) in ["x", "y", "z"].iter().enumerate() {
                ui.add(egui::DragValue::new(&mut p[axis]).speed(speed).prefix(format!("{name} ")));
            }
        });
        self.move_light(l, p);
        ui.label("or drag an axis of its handle in the hybrid image (x red, y green, z blue)");
        let home = self.home.as_ref().and_then(|h| h.lights.get(l)).map(|h| h.position);
        if let Some(h) = home.filter(|h| *h != p)
            && ui.button("back to the scene file's position").clicked()
        {
            self.move_light(l, h);
        }
    }

    // ---------------------------------------------------------------------------------------
    // Right panel: pixel, plan, times, rays, lights

    fn details(&mut self, ui: &mut egui::Ui) {
        let Some(r) = self.result.take() else {
            ui.label("Waiting for the first frame…");
            return;
        };
        self.frame_rate(ui, &r);
        ui.separator();
        // What loading skipped or could not honour (a missing texture, a light kind hyrt does
        // not have), as `hyrt render` prints it.
        if let Some(warnings) = self.loaded.as_ref().map(|l| &l.scene.warnings).filter(|w| !w.is_empty()) {
            egui::CollapsingHeader::new(format!("Scene warnings ({})", warnings.len()))
                .default_open(false)
                .show(ui, |ui| {
                    for w in warnings {
                        ui.label(RichText::new(w).color(Color32::from_rgb(255, 200, 120)));
                    }
                });
            ui.separator();
        }
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
            if !r.built_while_moving.is_empty() {
                ui.label(RichText::new("Built by the frames drawn while moving (stats.decisions)").italics());
                for d in &r.built_while_moving {
                    decision_row(ui, d.run, &d.what.to_string(), &self.times(&d.reason));
                }
            }
            if let Some(first) = &r.first_frame {
                ui.label(RichText::new("First frame after the change (stats.decisions)").italics());
                for d in &first.decisions {
                    decision_row(ui, d.run, &d.what.to_string(), &self.times(&d.reason));
                }
            }
            let this = if r.first_frame.is_some() { "The frame shown (caches warm)" } else { "This frame" };
            ui.label(RichText::new(format!("{this} (stats.decisions)")).italics());
            for d in &r.frame.stats.decisions {
                decision_row(ui, d.run, &d.what.to_string(), &self.times(&d.reason));
            }
        });
        egui::CollapsingHeader::new("Time per pass").default_open(true).show(ui, |ui| {
            let first = r.first_frame.as_ref();
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
                    let empty = FrameStats::default();
                    let h = &r.frame.stats;
                    let rf = r.comparison.as_ref().map_or(&empty, |c| &c.reference.stats);
                    let columns = [Some(h), Some(rf), first];
                    // Every pass any column ran, in frame order (`Pass` orders so).
                    let passes: BTreeSet<Pass> =
                        columns.iter().flatten().flat_map(|c| c.pass_ms.keys().copied()).collect();
                    for pass in passes {
                        ui.label(pass.name());
                        for c in columns.iter().flatten() {
                            ui.label(c.pass_ms.get(&pass).map_or("-".into(), |&v| self.ms(v)));
                        }
                        ui.end_row();
                    }
                    ui.label("total");
                    for c in columns.iter().flatten() {
                        ui.label(if c.total_ms > 0.0 { self.ms(c.total_ms) } else { "-".into() });
                    }
                    ui.end_row();
                },
            );
        });
        egui::CollapsingHeader::new("Rays by kind").default_open(true).show(ui, |ui| {
            egui::Grid::new("rays").striped(true).num_columns(3).show(ui, |ui| {
                ui.label(RichText::new("kind").strong());
                ui.label(RichText::new("hybrid").strong());
                ui.label(RichText::new("reference").strong());
                ui.end_row();
                let h = &r.frame.stats.rays;
                let rf = r.comparison.as_ref().map(|c| &c.reference.stats.rays);
                for (name, f) in RAY_ROWS {
                    ui.label(name);
                    ui.label(f(h).to_string());
                    ui.label(rf.map_or("-".into(), |rf| f(rf).to_string()));
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

    /// Frames per second while moving, what the newest frame reran, and a graph of the last
    /// seconds' frame times, split by pass.
    fn frame_rate(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        let recent: Vec<&Sample> = self.history.iter().collect();
        let fps = match recent.as_slice() {
            [first, .., last] if last.at > first.at => {
                (recent.len() - 1) as f64 / (last.at - first.at).as_secs_f64()
            }
            _ => 0.0,
        };
        let total = r.frame.stats.total_ms;
        let fps = if self.hide_times {
            "… fps".to_string()
        } else {
            format!("{fps:.1} fps shown, {:.1} fps the frame alone", 1e3 / total.max(1e-3))
        };
        ui.label(
            RichText::new(format!("{fps} ({} frames in {} s)", recent.len(), HISTORY.as_secs())).strong(),
        );
        ui.label(format!("This frame: {}", reran(&r.frame.stats)));
        // Stacked bars, one per frame received, oldest on the left.
        let (rect, _) =
            ui.allocate_exact_size(Vec2::new(ui.available_width().min(340.0), 90.0), Sense::hover());
        let painter = ui.painter().with_clip_rect(rect);
        painter.rect_filled(rect, 2.0, Color32::from_gray(24));
        let top = recent.iter().map(|s| s.total).fold(1.0, f64::max);
        if !self.hide_times && !recent.is_empty() {
            let now = Instant::now();
            let span = HISTORY.as_secs_f64();
            let bar = (rect.width() / 60.0).max(2.0);
            for s in &recent {
                let x = rect.max.x - ((now - s.at).as_secs_f64() / span) as f32 * rect.width();
                let mut y = rect.max.y;
                for (&pass, &ms) in &s.passes {
                    let h = (ms / top) as f32 * (rect.height() - 4.0);
                    let r = Rect::from_min_max(Pos2::new(x - bar, y - h), Pos2::new(x, y));
                    painter.rect_filled(r, 0.0, pass_color(pass));
                    y -= h;
                }
            }
        }
        painter.text(
            rect.left_top() + Vec2::new(4.0, 2.0),
            Align2::LEFT_TOP,
            if self.hide_times { "… ms".to_string() } else { format!("{top:.0} ms") },
            FontId::proportional(11.0),
            Color32::GRAY,
        );
        let mut seen: BTreeSet<Pass> = recent.iter().flat_map(|s| s.passes.keys().copied()).collect();
        seen.extend(r.frame.stats.pass_ms.keys().copied().filter(|p| p.part_of().is_none()));
        ui.horizontal_wrapped(|ui| {
            for pass in seen {
                swatch(ui, pass_color(pass), pass.name());
            }
        });
    }

    fn pixel_panel(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        ui.heading("Pixel");
        if !r.full {
            ui.label("The camera is moving: picking works on the frame drawn when it rests.");
            return;
        }
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
                if let Some((name, (w, ht))) = &h.texture {
                    let file = std::path::Path::new(name)
                        .file_name()
                        .map_or(name.clone(), |f| f.to_string_lossy().into_owned());
                    ui.label(format!("  texture {file} ({w}x{ht}): albedo {}", vec3(h.albedo)));
                }
                if let Some((mask, alpha, cutoff)) = &h.cutout {
                    let mask = mask.as_deref().map_or("no mask".to_string(), |name| {
                        std::path::Path::new(name)
                            .file_name()
                            .map_or(name.to_string(), |f| f.to_string_lossy().into_owned())
                    });
                    ui.label(format!("  cut-out ({mask}): alpha {alpha:.3}, cut-off {cutoff}"));
                }
                ui.label(format!("  t {:.4}  at {}", h.t, vec3(h.p)));
            }
        }
        match (info.reference, info.error) {
            (Some(rf), Some(e)) => ui.label(format!(
                "radiance hybrid {}  reference {}  |dY| {e:.4}",
                vec3(info.hybrid),
                vec3(rf)
            )),
            _ => ui.label(format!("radiance hybrid {} (no reference yet)", vec3(info.hybrid))),
        };
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
                    BorderRay::Hint => "ray cast: blocked by the hint (no traversal)".to_string(),
                    BorderRay::Traversal => format!(
                        "ray cast: traversal, {}",
                        if lp.decision == Some(hyrt_shadowmap::classify::Decision::Shadow) {
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
            _ if !r.full => {
                ui.label("The camera or a light is moving: this view is drawn when they rest (the Frame view follows every move).");
            }
            View::Shadows => self.shadows_view(ui, &r),
            View::Rays => self.rays_view(ui, &r),
            View::LightMaps => self.maps_view(ui, &r),
            View::Vpls => self.vpls_view(ui, &r),
        }
        self.result = Some(r);
    }

    fn frame_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
        let hyb = r.frame.stats.total_ms;
        let wait = reference_wait(r.full, self.auto_reference);
        let (reference, difference) = match &r.comparison {
            Some(c) => {
                let rf = c.reference.stats.total_ms;
                (
                    (Some(&c.reference.image), format!("reference ({})", self.ms(rf))),
                    (Some(&c.error_heat), format!("luminance error, PSNR {}", psnr_text(c.psnr))),
                )
            }
            None => ((None, format!("reference: {wait}")), (None, format!("luminance error: {wait}"))),
        };
        let mut cells = vec![
            (
                "hybrid",
                Some(&r.images.hybrid),
                format!("hybrid ({}){}", self.ms(hyb), if r.full { "" } else { ", moving" }),
            ),
            ("reference", reference.0, reference.1),
            ("difference", difference.0, difference.1),
        ];
        if let Some(w) = &r.images.wrong {
            cells.push((
                "wrong",
                Some(w),
                format!("wrong map decisions, any light ({} px)", r.wrong_pixels.unwrap_or(0)),
            ));
        }
        self.screen_grid(ui, &cells, 2, 60.0, Some(r));
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
                    "light {l}: occlusion ({} lit, {} shadowed{}, {} by rays)",
                    st.lit,
                    st.shadowed,
                    match st.by_suspects {
                        0 => String::new(),
                        n => format!(" ({n} of them by their triangles)"),
                    },
                    st.undecided
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
        let cells: Vec<_> = cells.iter().map(|(k, i, c)| (*k, Some(*i), c.clone())).collect();
        if smerts {
            self.screen_grid(ui, &cells, 2, 70.0, None);
        } else {
            self.screen_grid(ui, &cells[..1], 1, 70.0, None);
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
        let cells: Vec<(&str, Option<&ColorImage>, String)> = r
            .images
            .rays
            .iter()
            .map(|(k, img, max)| {
                let total: u64 = RayKindView::count(*k, &r.frame.stats.rays);
                let total =
                    if *k == RayKindView::Total { total - r.frame.stats.rays.vpl_path } else { total };
                (k.name(), Some(img), format!("{}: {total} rays, max {max} / px", k.name()))
            })
            .collect();
        if cells.is_empty() {
            ui.label("No per-pixel ray counts (they need Options::keep_buffers).");
            return;
        }
        self.screen_grid(ui, &cells, 3, 40.0, None);
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
        let layout = if map.is_paged() {
            format!(
                "paged: {} pages of {}x{} texels, levels up to {}x{} per face",
                map.page_count(),
                hyrt_shadowmap::PAGE,
                hyrt_shadowmap::PAGE,
                map.resolution_at(map.levels().saturating_sub(1)),
                map.resolution_at(map.levels().saturating_sub(1))
            )
        } else {
            format!("{}x{} per face", map.resolution(), map.resolution())
        };
        ui.label(format!(
            "light {l}: {} map, {layout}, {} of {} faces drawn (those camera hits fall on), {:.1} MB",
            MapKind::name(map.kind()),
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
                                        + Vec2::new(m.x as f32, m.y as f32)
                                            / map.resolution_at(m.level) as f32
                                            * rect.size();
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
                    None,
                );
                let cam = Some(r.camera);
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
    /// left under them; each captioned (a missing image is a captioned blank). Returns nothing:
    /// picking and zoom are handled inside. With `viewport`, the image keyed `hybrid` moves the
    /// camera and the chosen light.
    fn screen_grid(
        &mut self,
        ui: &mut egui::Ui,
        cells: &[(&str, Option<&ColorImage>, String)],
        cols: usize,
        below: f32,
        viewport: Option<&Rendered>,
    ) {
        let Some(first) = cells.iter().find_map(|c| c.1) else { return };
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
                        match img {
                            Some(img) => {
                                let nav = viewport.filter(|_| *key == "hybrid");
                                self.screen_image(ui, key, img, &format!("{key} image"), size, nav);
                            }
                            None => {
                                let (rect, _) = ui.allocate_exact_size(size, Sense::hover());
                                ui.painter().rect_filled(rect, 0.0, Color32::from_gray(30));
                            }
                        }
                    });
                }
            });
        }
    }

    /// A screen-sized image: zoom (scroll), pan (drag), pick (click), reset (double-click),
    /// with the picked pixel marked. As the `viewport` of its frame, drags and the wheel move
    /// the camera or the chosen light instead ([`Inspector::navigate`]).
    fn screen_image(
        &mut self,
        ui: &mut egui::Ui,
        key: &str,
        image: &ColorImage,
        label: &str,
        size: Vec2,
        viewport: Option<&Rendered>,
    ) -> Placed {
        let tex = self.texture(ui.ctx(), key, image);
        let (rect, resp) = ui.allocate_exact_size(size, Sense::click_and_drag());
        let label = label.to_string();
        resp.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Image, true, &label));
        let img = Vec2::new(image.size[0] as f32, image.size[1] as f32);
        let mut clicked_at = None;
        let gizmo =
            viewport.and_then(|r| self.gizmo(r, Placed { rect, uv: self.uv(), img, clicked_at: None }));
        if viewport.is_some() {
            self.navigate(ui, &resp, gizmo.as_ref());
        } else if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let at = resp.hover_pos().map(|p| (p - rect.min) / rect.size());
                self.zoom_by((scroll * 0.004).exp(), at);
            }
        }
        if resp.dragged() && viewport.is_none() {
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
        if let Some(g) = &gizmo {
            let painter = ui.painter().with_clip_rect(rect);
            for (axis, end) in g.ends.iter().enumerate() {
                let active = self.drag == Some(Drag::Light(axis));
                painter.line_segment(
                    [g.at, *end],
                    Stroke::new(if active { 4.0 } else { 2.5 }, AXIS_COLORS[axis]),
                );
            }
            painter.circle(g.at, 5.0, Color32::from_rgb(255, 220, 80), Stroke::new(1.0, Color32::BLACK));
        }
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

    /// The handle of the light being edited, on the viewport `placed` of frame `r`: where the
    /// light is, and the ends of its three axes (each a tenth of its distance to the eye).
    fn gizmo(&self, r: &Rendered, placed: Placed) -> Option<Gizmo> {
        let light = self.pose.as_ref()?.lights.get(self.light_edit)?.position;
        let cam = &r.camera;
        let (fx, fy, _) = views::project(cam, light)?;
        let reach = (light - cam.eye).length() * 0.1;
        let at = placed.to_screen(fx, fy);
        let mut ends = [at; 3];
        for (axis, end) in ends.iter_mut().enumerate() {
            let (ex, ey, _) = views::project(cam, light + V3::AXES[axis] * reach)?;
            *end = placed.to_screen(ex, ey);
        }
        Some(Gizmo { at, ends, reach })
    }

    /// Camera and light moves from the pointer over the viewport: left drag orbits (or moves
    /// the light along the axis of its handle it started on), shift-left or middle drag pans,
    /// the wheel dollies, the right button looks around (and lets W A S D, Q E fly).
    fn navigate(&mut self, ui: &egui::Ui, resp: &egui::Response, gizmo: Option<&Gizmo>) {
        let Some(cam) = self.pose.as_ref().map(|p| p.camera) else { return };
        let (secondary, middle, shift, origin) = ui.input(|i| {
            (
                i.pointer.button_down(egui::PointerButton::Secondary),
                i.pointer.button_down(egui::PointerButton::Middle),
                i.modifiers.shift,
                i.pointer.press_origin(),
            )
        });
        if resp.is_pointer_button_down_on() && secondary {
            self.drag = Some(Drag::Look);
        } else if resp.drag_started() {
            let axis = gizmo.zip(origin).and_then(|(g, o)| {
                (0..3)
                    .map(|a| (a, segment_distance(o, g.at, g.ends[a])))
                    .filter(|(_, d)| *d < 8.0)
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(a, _)| a)
            });
            self.drag = Some(match axis {
                Some(a) if !shift && !middle => Drag::Light(a),
                _ if shift || middle => Drag::Pan,
                _ => Drag::Orbit,
            });
        }
        let d = resp.drag_delta();
        let height = resp.rect.height().max(1.0) / self.zoom;
        match self.drag {
            _ if d == Vec2::ZERO => {}
            Some(Drag::Orbit) => {
                self.set_camera(navigate::orbit(&cam, -d.x * TURN_PER_POINT, d.y * TURN_PER_POINT))
            }
            Some(Drag::Pan) => self.set_camera(navigate::pan(&cam, d.x / height, d.y / height)),
            Some(Drag::Look) => {
                self.set_camera(navigate::look(&cam, -d.x * TURN_PER_POINT, -d.y * TURN_PER_POINT))
            }
            Some(Drag::Light(a)) => {
                if let Some(g) = gizmo {
                    let screen = g.ends[a] - g.at;
                    let along = d.dot(screen) / screen.length_sq().max(1.0);
                    let l = self.light_edit;
                    if let Some(p) = self.pose.as_ref().and_then(|p| p.lights.get(l)).map(|l| l.position) {
                        self.move_light(l, p + V3::AXES[a] * (along * g.reach));
                    }
                }
            }
            None => {}
        }
        let released = !resp.is_pointer_button_down_on() && !resp.dragged();
        if released && (self.drag != Some(Drag::Look) || !secondary) {
            self.drag = None;
        }
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.set_camera(navigate::dolly(&cam, (-scroll * 0.002).exp(), self.fly_speed * 1e-3));
            }
        }
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

/// A light's handle on the viewport: where the light is and where its x, y, z axes end, and
/// the world length of an axis.
struct Gizmo {
    at: Pos2,
    ends: [Pos2; 3],
    reach: f32,
}

const AXIS_COLORS: [Color32; 3] =
    [Color32::from_rgb(235, 70, 70), Color32::from_rgb(80, 220, 80), Color32::from_rgb(80, 140, 255)];

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-6)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// What a frame did again and what it reused, in a few words ("light maps reused, VPLs
/// reused"), from its decisions.
pub fn reran(stats: &hyrt::render::FrameStats) -> String {
    let d = &stats.decisions;
    let lights: Vec<_> = d.iter().filter(|d| matches!(d.what, Subject::Light(_))).collect();
    let mut parts = Vec::new();
    let of = |cache: Cache| -> Vec<String> {
        lights.iter().filter(|d| d.cache == cache).map(|d| d.what.to_string()).collect()
    };
    let (built, extended) = (of(Cache::Built), of(Cache::Extended));
    if !lights.is_empty() {
        if built.is_empty() && extended.is_empty() {
            parts.push("light maps reused".to_string());
        }
        if !extended.is_empty() {
            parts.push(format!("light maps extended ({})", extended.join(", ")));
        }
        if !built.is_empty() {
            parts.push(format!("light maps built ({})", built.join(", ")));
        }
    }
    for (what, name) in [(Subject::Vpls, "VPLs"), (Subject::VplMaps, "VPL maps")] {
        if let Some(v) = d.iter().find(|d| d.what == what) {
            parts.push(format!("{name} {}", if v.built() { "rebuilt" } else { "reused" }));
        }
    }
    if parts.is_empty() { "nothing cached to reuse".into() } else { parts.join(", ") }
}

/// Why a frame has no reference beside it.
fn reference_wait(full: bool, auto: bool) -> &'static str {
    match (full, auto) {
        (false, _) => "drawn when the camera rests",
        (true, true) => "rendering…",
        (true, false) => "on demand (render the reference now)",
    }
}

/// A pass's colour in the frame-time graph: one per top-level pass, in frame order.
fn pass_color(pass: Pass) -> Color32 {
    const COLORS: [Color32; 12] = [
        Color32::from_rgb(170, 170, 170),
        Color32::from_rgb(86, 180, 233),
        Color32::from_rgb(230, 159, 0),
        Color32::from_rgb(0, 158, 115),
        Color32::from_rgb(240, 228, 66),
        Color32::from_rgb(213, 94, 0),
        Color32::from_rgb(204, 121, 167),
        Color32::from_rgb(0, 114, 178),
        Color32::from_rgb(120, 200, 120),
        Color32::from_rgb(255, 140, 140),
        Color32::from_rgb(160, 120, 220),
        Color32::from_rgb(250, 250, 250),
    ];
    let top = Pass::ALL.iter().filter(|p| p.part_of().is_none());
    let i = top.clone().position(|&p| p == pass).unwrap_or(top.count());
    COLORS[i % COLORS.len()]
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

/// The slider range of knob `name`, as [`hyrt::options::KNOBS`] declares it (one place for
/// the CLI's checks and the inspector's sliders).
fn knob_range<T: egui::emath::Numeric>(name: &str) -> std::ops::RangeInclusive<T> {
    let (lo, hi) = hyrt::options::knob(name).and_then(|k| k.slider).unwrap_or((0.0, 1.0));
    T::from_f64(lo)..=T::from_f64(hi)
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

/// A combo box over every value of an enum knob, by its names ([`Choice`]).
fn combo<T: Choice>(ui: &mut egui::Ui, label: &str, value: &mut T) -> egui::Response {
    egui::ComboBox::from_label(label)
        .selected_text(value.name())
        .show_ui(ui, |ui| {
            for v in T::ALL {
                ui.selectable_value(value, *v, v.name());
            }
        })
        .response
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

    /// Every knob the inspector offers a slider for declares the slider's range, within the
    /// values the knob accepts.
    #[test]
    fn sliders_take_their_ranges_from_the_knobs() {
        let src = include_str!("app.rs");
        let names: Vec<&str> =
            src.split("knob_range(\"").skip(1).filter_map(|r| r.split('"').next()).collect();
        assert!(names.len() >= 11, "{names:?}");
        for name in names {
            let k = hyrt::options::knob(name).unwrap_or_else(|| panic!("no knob {name}"));
            let (lo, hi) = k.slider.unwrap_or_else(|| panic!("knob {name} declares no slider range"));
            assert!(lo < hi, "{name}");
            for v in [lo, hi] {
                assert!(
                    (k.set)(&mut hyrt::options::Options::hybrid(), &v.to_string()).is_ok(),
                    "{name}: {v}"
                );
            }
        }
    }

    #[test]
    fn times_are_masked() {
        assert_eq!(mask_ms("reused: built once (12.5 ms), 3 lights"), "reused: built once (… ms), 3 lights");
        assert_eq!(mask_ms("1.0 ms and 2 ms, 3 px"), "… ms and … ms, 3 px");
        assert_eq!(mask_ms("no times"), "no times");
    }
}
