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
mod details;
mod map_views;
mod navigation;
mod panels;
mod screens;

pub use details::reran;
use details::*;
use navigation::*;
use screens::*;

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

/// The viewport's navigation state.
struct Navigation {
    /// Zoom and pan of the screen-sized images (shared by all of them): the magnification and
    /// the centre of the visible window, in image fractions.
    zoom: f32,
    center: Vec2,
    /// What a drag in progress is doing.
    drag: Option<Drag>,
    /// Fly speed in scene units per second (from the scene's size).
    fly_speed: f32,
}

impl Default for Navigation {
    fn default() -> Self {
        Self { zoom: 1.0, center: Vec2::splat(0.5), drag: None, fly_speed: 1.0 }
    }
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
    /// How the viewport is being looked at and moved about.
    nav: Navigation,
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
    /// The light the viewport's gizmo moves.
    pub light_edit: usize,
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
            nav: Navigation::default(),
            picked: None,
            hide_times: false,
            pose: None,
            home: None,
            moved_at: None,
            rest: Duration::from_millis(300),
            auto_reference: true,
            reference_asked: None,
            history: VecDeque::new(),
            light_edit: 0,
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
        if self.nav.drag != Some(Drag::Look) {
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
            self.set_camera(navigate::fly(&cam, step * (self.nav.fly_speed * fast * dt)));
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
                    self.nav.fly_speed =
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
        self.nav.zoom = 1.0;
        self.nav.center = Vec2::splat(0.5);
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

    // ---------------------------------------------------------------------------------------
    // Knobs

    // ---------------------------------------------------------------------------------------
    // Right panel: pixel, plan, times, rays, lights

    // ---------------------------------------------------------------------------------------
    // Central panel

    // ---------------------------------------------------------------------------------------
    // Images
}

impl eframe::App for Inspector {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }
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

#[cfg(test)]
mod tests;
