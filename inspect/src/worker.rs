//! The background thread that loads the scene and renders, so that the window never waits.
//!
//! It owns the [`Scene`] and one [`Renderer`]: every command first brings the renderer to the
//! hybrid options with [`Renderer::set_options`] (which keeps the BVH and every map and VPL the
//! change leaves valid, and says what it dropped), renders the reference only when its own
//! options changed (the same renderer switched to rays everywhere: same BVH, same VPLs), then
//! the hybrid frame with its inspection buffers (twice when the first frame built maps or VPLs,
//! or ran the visibility check, whose rays are timed with the shadow rays: the time shown is
//! that of a frame with warm caches and no check). Results, the images the views show, and
//! progress (rows done of the passes' rows) go back to the window, which is woken by `notify`.
//! Commands that pile up while a frame renders are coalesced: only the newest knobs render.

use std::collections::VecDeque;
use std::sync::{
    Arc, Mutex,
    atomic::{AtomicU64, Ordering::Relaxed},
    mpsc::{Receiver, Sender, channel},
};
use std::thread::JoinHandle;
use std::time::Instant;

use eframe::egui::ColorImage;
use hyrt::{
    camera::CameraRays,
    film::Film,
    plan::Plan,
    render::{Frame, FrameStats, Indirect, Options, Renderer, Shadows, vpl::Vpl},
    render::{FrameDecision, Subject},
    scene::{Camera, PointLight, Scene},
};
use hyrt_shadowmap::{
    LightMap,
    classify::{Plane, point_error_bound, triangle_planes},
};

use crate::views::{self, RayKindView};

/// Largest side of a light-map face image (maps are sampled down to it).
pub const MAP_IMAGE_SIDE: u32 = 256;

/// What to open, and how.
#[derive(Clone, Debug)]
pub struct Setup {
    /// A built-in scene name, a `.toml` scene file or a mesh file (as `hyrt render`).
    pub scene: String,
    pub size: Option<(u32, u32)>,
    pub max_depth: Option<u32>,
    /// Camera `N` of the scene's glTF files instead of the scene's (`hyrt render --camera`).
    pub camera: Option<usize>,
    /// The render flags (a missing `--preset` means the hybrid one here).
    pub knobs: hyrt::options::Knobs,
    /// Override of the knobs' options (tests set small maps this way).
    pub options: Option<Options>,
}

/// A scene loaded by the worker, shared with the window (for pixel picking).
pub struct Loaded {
    pub scene: Arc<Scene>,
    /// Plane of every triangle: for re-classifying a picked pixel exactly as the renderer does.
    pub planes: Arc<Vec<Plane>>,
    /// The renderer's bound on a shading point's rounding ([`Renderer::occluders`]).
    pub point_error: f32,
    /// Per triangle, whether it has an alpha cut-out ([`Renderer::cutouts`]).
    pub cutouts: Vec<bool>,
    /// The options the flags selected: the knobs' starting values.
    pub options: Options,
    pub load_ms: f64,
}

/// Where the camera and the lights are: the scene file's until the window moves them.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub camera: Camera,
    pub lights: Vec<PointLight>,
}

impl Pose {
    /// The scene file's camera and lights.
    pub fn of(scene: &Scene) -> Self {
        Self { camera: scene.camera.expect("validated scene has a camera"), lights: scene.lights.clone() }
    }
}

/// The reference frame, rendered again only when its options or the pose change.
pub struct Reference {
    pub options: Options,
    pub pose: Pose,
    pub film: Film,
    pub stats: FrameStats,
    pub image: ColorImage,
}

/// The reference set beside a hybrid frame: the reference of the same pose and options, and
/// the error views made from the two.
pub struct Comparison {
    pub reference: Arc<Reference>,
    /// Whether the reference was rendered for this frame (else an earlier one was reused).
    pub rendered: bool,
    pub psnr: f64,
    /// Per pixel, the display-luminance difference to the reference.
    pub error: Vec<f32>,
    pub error_heat: ColorImage,
}

/// The images of a frame's views, made on the worker thread.
pub struct Images {
    pub hybrid: ColorImage,
    /// With the visibility check: the pixels where some light's map decision is wrong.
    pub wrong: Option<ColorImage>,
    /// Per light (map-based shadows with kept buffers): occlusion, border before dilation,
    /// undecided (border after dilation: the pixels that cast a ray), ray outcomes.
    pub lights: Vec<LightImages>,
    /// Per ray kind, the heat map and its maximum per pixel.
    pub rays: Vec<(RayKindView, ColorImage, u64)>,
    /// Per point light with a map: one image per face (`None`: not drawn) and the depth range.
    pub maps: Vec<Option<MapImages>>,
}

pub struct LightImages {
    pub occlusion: ColorImage,
    pub border: ColorImage,
    pub undecided: ColorImage,
    pub rays: ColorImage,
}

pub struct MapImages {
    pub faces: Vec<Option<ColorImage>>,
    pub range: Option<(f32, f32)>,
}

/// One rendered frame with everything the views show.
pub struct Rendered {
    /// The number of the render command this answers.
    pub generation: u64,
    /// The options the frame was rendered with: the window's, except that a moving frame
    /// keeps no buffers and runs no visibility check.
    pub options: Options,
    pub pose: Pose,
    /// The camera of `pose`, for this image size (picking, projecting points).
    pub camera: CameraRays,
    /// A full frame: rendered with its inspection buffers, every view's images made. A moving
    /// frame ([`Command::Render`] with `full: false`) has the hybrid image alone.
    pub full: bool,
    /// What [`Renderer::set_options`], [`Renderer::set_camera`] and [`Renderer::set_light`]
    /// dropped for this command.
    pub dropped: Vec<&'static str>,
    pub plan: Plan,
    pub frame: Frame,
    /// The reference and the error views, when they exist for this pose and these options:
    /// reused at once, or rendered afterwards ([`Reply::Compared`]) for a full frame that asks.
    pub comparison: Option<Comparison>,
    /// When this command built light maps or VPLs: the stats of that first frame (`frame` is
    /// then a second one, with the caches warm). Full frames only.
    pub first_frame: Option<FrameStats>,
    /// A full frame after moving ones: what those built (maps, faces, VPLs), with the time it
    /// took, since this frame only reuses it.
    pub built_while_moving: Vec<FrameDecision>,
    /// With the visibility check: pixels with at least one wrong map decision.
    pub wrong_pixels: Option<u64>,
    /// The point lights' maps (map-based shadows).
    pub maps: Vec<Option<Arc<LightMap>>>,
    pub vpls: Vec<Vpl>,
    /// Number of VPL maps (0 unless `Indirect::Maps`).
    pub vpl_maps: usize,
    pub bvh_ms: f64,
    pub images: Images,
    /// Wall time of the command, reference and images included.
    pub wall_ms: f64,
}

/// A VPL's map, as an image.
pub struct VplMap {
    pub index: usize,
    pub image: Option<ColorImage>,
    pub range: Option<(f32, f32)>,
    pub resolution: u32,
}

pub enum Command {
    /// Render the hybrid frame with these options, from this pose. A worker whose window is
    /// gone stops when the channel closes (after its current frame).
    Render(Render),
    /// The image of VPL `index`'s map.
    VplMap(usize),
}

pub enum Reply {
    Loaded(Box<Loaded>),
    /// The scene could not be loaded (the message has the causes).
    Failed(String),
    Rendered(Box<Rendered>),
    /// The reference rendered after frame `generation` had been sent.
    Compared {
        generation: u64,
        comparison: Box<Comparison>,
    },
    VplMap(Box<VplMap>),
}

/// Progress of the current command: a stage name and rows done of the rows expected.
#[derive(Default)]
pub struct Progress {
    stage: Mutex<String>,
    done: AtomicU64,
    total: AtomicU64,
}

impl Progress {
    fn start(&self, stage: &str, total: u64) {
        *self.stage.lock().unwrap_or_else(|e| e.into_inner()) = stage.to_string();
        self.done.store(0, Relaxed);
        self.total.store(total, Relaxed);
    }

    /// The stage and the fraction done (0 when unknown).
    pub fn get(&self) -> (String, f32) {
        let stage = self.stage.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let (done, total) = (self.done.load(Relaxed), self.total.load(Relaxed));
        (stage, if total == 0 { 0.0 } else { (done as f32 / total as f32).min(1.0) })
    }
}

/// The handle the window keeps.
pub struct Worker {
    tx: Sender<Command>,
    rx: Receiver<Reply>,
    pub progress: Arc<Progress>,
    /// Not joined when the window closes: that must not wait for a long render.
    _thread: JoinHandle<()>,
}

impl Worker {
    /// Starts the thread: it loads the scene at once and answers with [`Reply::Loaded`] or
    /// [`Reply::Failed`]; `notify` is called after every reply and now and then during a render.
    pub fn spawn(setup: Setup, notify: impl Fn() + Send + Sync + 'static) -> Self {
        let (tx, commands) = channel();
        let (replies, rx) = channel();
        let progress = Arc::new(Progress::default());
        let p = progress.clone();
        let thread = std::thread::Builder::new()
            .name("hyrt-inspect worker".into())
            .spawn(move || run(setup, commands, replies, &p, &notify))
            .expect("cannot start the worker thread");
        Self { tx, rx, progress, _thread: thread }
    }

    pub fn send(&self, c: Command) {
        // A worker that stopped (failed load) ignores commands.
        let _ = self.tx.send(c);
    }

    pub fn try_recv(&self) -> Option<Reply> {
        // Empty, or disconnected (the worker stopped after a failed load): nothing.
        self.rx.try_recv().ok()
    }
}

/// Loads the scene with the setup's size and depth overrides, validated, and the options.
pub fn load(setup: &Setup) -> anyhow::Result<(Scene, Options)> {
    let overrides = hyrt::scene::Overrides {
        size: setup.size,
        max_depth: setup.max_depth,
        camera: setup.camera,
        ..Default::default()
    };
    let scene = hyrt::scene::load_with(&setup.scene, overrides)?;
    let mut knobs = setup.knobs.clone();
    knobs.preset = knobs.preset.or(Some(hyrt::options::Preset::Hybrid));
    let mut options = match setup.options {
        Some(o) => o,
        None => knobs.options_for(&scene)?,
    };
    options.keep_buffers = true;
    // Wrong-visibility counts cost a shadow ray per map decision (untimed): on by default up
    // to the thesis's 640x480.
    let pixels = u64::from(scene.settings.width) * u64::from(scene.settings.height);
    options.check_visibility |= setup.options.is_none() && pixels <= 640 * 480;
    Ok((scene, options))
}

/// Whether two reference options (of [`Options::reference_for`]) render the same image: only the
/// indirect light and its VPLs matter (the map knobs are unused by rays).
pub fn same_reference(a: &Options, b: &Options) -> bool {
    let (x, y) = (&a.indirect_opts, &b.indirect_opts);
    a.indirect == b.indirect && (a.indirect == Indirect::None || (x.vpl == y.vpl && x.clamp == y.clamp))
}

fn run(
    setup: Setup,
    commands: Receiver<Command>,
    replies: Sender<Reply>,
    progress: &Progress,
    notify: &(dyn Fn() + Send + Sync),
) {
    let reply = |r: Reply| {
        let _ = replies.send(r);
        notify();
    };
    let t = Instant::now();
    progress.start(&format!("loading {}", setup.scene), 0);
    notify();
    let (scene, options) = match load(&setup) {
        Ok(s) => s,
        Err(e) => return reply(Reply::Failed(format!("{e:#}"))),
    };
    let scene = Arc::new(scene);
    let planes = Arc::new(triangle_planes(&scene.positions));
    reply(Reply::Loaded(Box::new(Loaded {
        scene: scene.clone(),
        planes,
        point_error: point_error_bound(&scene.positions),
        cutouts: scene.cutout_flags(),
        options,
        load_ms: t.elapsed().as_secs_f64() * 1e3,
    })));

    progress.start(&format!("building the BVH of {} triangles", scene.triangle_count()), 0);
    notify();
    let mut state = State {
        renderer: Renderer::new(&scene, options),
        pose: Pose::of(&scene),
        reference: None,
        queue: VecDeque::new(),
        film: None,
        built_while_moving: Vec::new(),
    };
    loop {
        if state.queue.is_empty() {
            match commands.recv() {
                Ok(c) => state.queue.push_back(c),
                Err(_) => return,
            }
        }
        state.queue.extend(commands.try_iter());
        let (newest, maps) = coalesce(state.queue.drain(..));
        if let Some(Render { generation, options, pose, full, reference }) = newest {
            let r = state.render(generation, options, pose, full, progress, notify);
            let compare = full && reference && r.comparison.is_none();
            reply(Reply::Rendered(Box::new(r)));
            // The reference comes after the frame it belongs to, unless the window has moved on.
            state.queue.extend(commands.try_iter());
            let waiting = state.queue.iter().any(|c| matches!(c, Command::Render(_)));
            if compare && !waiting {
                let comparison = state.compare(progress, notify);
                reply(Reply::Compared { generation, comparison: Box::new(comparison) });
            }
        }
        for i in maps {
            reply(Reply::VplMap(Box::new(vpl_map(&state.renderer, i))));
        }
    }
}

/// What a [`Command::Render`] asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct Render {
    /// The number the window gave the command; the frame answering it carries it back.
    pub generation: u64,
    /// The window's knobs.
    pub options: Options,
    pub pose: Pose,
    /// With every view (else the hybrid image alone, as fast as the frame goes: the camera or
    /// a light is moving).
    pub full: bool,
    /// With a full frame, also the reference of this pose and options (rendered only if the
    /// last one is of another pose or other options, and dropped if newer commands wait).
    pub reference: bool,
}

/// The commands waiting: only the newest render matters (knobs dragged or the camera moved
/// while a frame renders queue up); map requests are all answered, in order, after it.
pub fn coalesce(commands: impl Iterator<Item = Command>) -> (Option<Render>, Vec<usize>) {
    let (mut newest, mut maps) = (None, Vec::new());
    for cmd in commands {
        match cmd {
            Command::Render(r) => newest = Some(r),
            Command::VplMap(i) => maps.push(i),
        }
    }
    (newest, maps)
}

/// The worker's renderer and what it remembers between commands.
struct State<'s> {
    renderer: Renderer<'s>,
    /// The pose the renderer is at.
    pose: Pose,
    /// The last reference rendered (reused while its pose and options hold).
    reference: Option<Arc<Reference>>,
    /// Commands received and not yet handled.
    queue: VecDeque<Command>,
    /// The last frame's image, for its reference's error views.
    film: Option<Film>,
    /// What the moving frames since the last full one built.
    built_while_moving: Vec<FrameDecision>,
}

impl State<'_> {
    /// Moves the renderer to `pose`: the camera, and each light that moved.
    fn set_pose(&mut self, pose: Pose) -> Vec<&'static str> {
        let mut dropped = Vec::new();
        if pose.camera != self.pose.camera {
            self.renderer.set_camera(&pose.camera);
        }
        for (l, light) in pose.lights.iter().enumerate() {
            for d in self.renderer.set_light(l, *light) {
                if !dropped.contains(&d) {
                    dropped.push(d);
                }
            }
        }
        self.pose = pose;
        dropped
    }

    /// The reference of the renderer's pose and hybrid options `o`, if the last one is.
    fn reference_of(&self, o: &Options) -> Option<Arc<Reference>> {
        let r = self.reference.as_ref()?;
        (same_reference(&r.options, &o.reference_for()) && r.pose == self.pose).then(|| r.clone())
    }

    fn render(
        &mut self,
        generation: u64,
        window_options: Options,
        pose: Pose,
        full: bool,
        progress: &Progress,
        notify: &(dyn Fn() + Send + Sync),
    ) -> Rendered {
        let start = Instant::now();
        // A moving frame: the hybrid image alone, as fast as the frame goes.
        let options = Options {
            keep_buffers: full,
            check_visibility: full && window_options.check_visibility,
            ..window_options
        };
        let mut dropped = self.renderer.set_options(options);
        dropped.extend(self.set_pose(pose));
        let renderer = &mut self.renderer;
        let scene = renderer.scene;
        let (w, h) = (scene.settings.width, scene.settings.height);
        let exposure = scene.settings.exposure;
        let tick = ticker(progress, h, notify);

        rows(progress, renderer, h, "rendering the hybrid frame");
        let mut frame = renderer.render(&tick);
        // The frame whose time is shown has warm caches and no visibility check (its rays run
        // in the timed shadow-ray pass): render again if this one built maps or VPLs, or
        // checked. Moving frames show what they cost, building included.
        let built = frame.stats.maps_built > 0
            || frame
                .stats
                .decisions
                .iter()
                .any(|d| d.run && matches!(d.what, Subject::Vpls | Subject::VplMaps));
        let mut first_frame = None;
        if full && (built || options.check_visibility) {
            renderer.set_options(Options { check_visibility: false, ..options });
            rows(progress, renderer, h, "rendering the hybrid frame again (timed: caches warm, no check)");
            let mut timed = renderer.render(&tick);
            renderer.set_options(options);
            if options.check_visibility {
                // The same decisions (the check only compares): take its verdicts over.
                for (t, c) in timed.stats.lights.iter_mut().zip(&frame.stats.lights) {
                    t.wrong = c.wrong;
                }
                if let (Some(t), Some(c)) = (timed.shadows.as_mut(), frame.shadows.as_mut()) {
                    debug_assert_eq!(t.occ, c.occ);
                    t.wrong = std::mem::take(&mut c.wrong);
                }
            }
            if built {
                first_frame = Some(frame.stats);
            }
            frame = timed;
        }
        let built_while_moving = if full {
            std::mem::take(&mut self.built_while_moving)
        } else {
            self.built_while_moving.extend(frame.stats.decisions.iter().filter(|d| d.built()).cloned());
            Vec::new()
        };
        progress.start("making the views", 0);
        notify();
        let wrong_pixels = frame.shadows.as_ref().filter(|b| !b.wrong.is_empty()).map(|b| {
            (0..frame.film.pixels.len())
                .filter(|&i| b.wrong.iter().any(|l| l.get(i).copied().unwrap_or(false)))
                .count() as u64
        });
        let renderer = &self.renderer;
        let maps: Vec<Option<Arc<LightMap>>> = if options.shadows == Shadows::Rays {
            vec![None; scene.lights.len()]
        } else {
            (0..scene.lights.len()).map(|l| renderer.light_map(l)).collect()
        };
        let (vpls, vpl_maps) = renderer.cached_vpls().map_or((Vec::new(), 0), |(v, m)| (v.to_vec(), m.len()));
        let images = if full {
            images(&frame, &maps, renderer.occluders().0, exposure, w, h)
        } else {
            Images {
                hybrid: views::film_image(&frame.film, exposure),
                wrong: None,
                lights: Vec::new(),
                rays: Vec::new(),
                maps: Vec::new(),
            }
        };
        let comparison =
            self.reference_of(&options).map(|reference| comparison(reference, false, &frame.film, scene));
        if full {
            // Only a full frame gets a reference afterwards.
            self.film = Some(frame.film.clone());
        }
        Rendered {
            generation,
            options,
            camera: self.renderer.camera,
            pose: self.pose.clone(),
            full,
            dropped,
            plan: self.renderer.plan.clone(),
            frame,
            comparison,
            first_frame,
            built_while_moving,
            wrong_pixels,
            maps,
            vpls,
            vpl_maps,
            bvh_ms: self.renderer.bvh_build_ms(),
            images,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
        }
    }

    /// Renders the reference of the last frame's pose and options (the same renderer switched
    /// to rays everywhere: same BVH, same VPLs), and compares the two.
    fn compare(&mut self, progress: &Progress, notify: &(dyn Fn() + Send + Sync)) -> Comparison {
        let options = *self.renderer.options();
        let ref_opts = options.reference_for();
        let h = self.renderer.scene.settings.height;
        let exposure = self.renderer.scene.settings.exposure;
        self.renderer.set_options(ref_opts);
        rows(progress, &self.renderer, h, "rendering the reference");
        let f = self.renderer.render(&ticker(progress, h, notify));
        let image = views::film_image(&f.film, exposure);
        let reference = Arc::new(Reference {
            options: ref_opts,
            pose: self.pose.clone(),
            film: f.film,
            stats: f.stats,
            image,
        });
        self.reference = Some(reference.clone());
        self.renderer.set_options(options);
        let film = self.film.as_ref().expect("a frame was rendered before its reference");
        comparison(reference, true, film, self.renderer.scene)
    }
}

/// The progress of `passes` passes of `h` rows each.
fn rows(progress: &Progress, renderer: &Renderer, h: u32, stage: &str) {
    progress.start(stage, u64::from(h) * u64::from(renderer.progress_passes()));
}

/// A row counter that repaints the window every eighth of a pass.
fn ticker<'p>(progress: &'p Progress, h: u32, notify: &'p (dyn Fn() + Send + Sync)) -> impl Fn() + Sync + 'p {
    let step = (u64::from(h) / 8).max(1);
    move || {
        let d = progress.done.fetch_add(1, Relaxed) + 1;
        if d.is_multiple_of(step) {
            notify();
        }
    }
}

/// The comparison of `frame` with `reference`.
fn comparison(reference: Arc<Reference>, rendered: bool, film: &Film, scene: &Scene) -> Comparison {
    let (w, h) = (film.width, film.height);
    let error = views::luminance_error(film, &reference.film, scene.settings.exposure);
    let psnr = hyrt::metrics::psnr(scene, &reference.film, film).unwrap_or(f64::NAN);
    let error_heat = views::error_heat(&error, w, h);
    Comparison { reference, rendered, psnr, error, error_heat }
}

/// Every image of the frame's views.
fn images(
    frame: &Frame,
    maps: &[Option<Arc<LightMap>>],
    planes: &[Plane],
    exposure: f32,
    w: u32,
    h: u32,
) -> Images {
    let back = views::backdrop(&frame.film, exposure);
    let lights = frame.shadows.as_ref().map_or_else(Vec::new, |b| {
        (0..b.occ.len())
            .map(|l| {
                let empty = Vec::new();
                let get = |v: &'_ Vec<Vec<bool>>| v.get(l).map_or(&empty[..], |x| &x[..]).to_vec();
                let undecided = get(&b.undecided);
                LightImages {
                    occlusion: views::occlusion_image(&b.occ[l], &undecided, &get(&b.wrong), w, h),
                    border: views::mask_image(&get(&b.border), &back, w, h),
                    undecided: views::mask_image(&undecided, &back, w, h),
                    rays: views::ray_image(b.ray.get(l).map_or(&[][..], |r| &r[..]), &b.occ[l], &back, w, h),
                }
            })
            .collect()
    });
    let rays = frame.pixel_rays.as_ref().map_or_else(Vec::new, |px| {
        RayKindView::ALL
            .iter()
            .map(|&k| {
                let (img, max) = views::ray_heat(px, k, w, h);
                (k, img, max)
            })
            .collect()
    });
    let maps = maps
        .iter()
        .map(|m| {
            m.as_ref().map(|m| {
                let range = views::depth_range(m, planes, MAP_IMAGE_SIDE);
                let r = range.unwrap_or((1.0, 2.0));
                let faces = (0..m.faces() as u8)
                    .map(|f| views::depth_face_image(m, planes, f, MAP_IMAGE_SIDE, r))
                    .collect();
                MapImages { faces, range }
            })
        })
        .collect();
    let wrong = frame.shadows.as_ref().filter(|b| !b.wrong.is_empty()).map(|b| {
        let any: Vec<bool> =
            (0..back.len()).map(|i| b.wrong.iter().any(|l| l.get(i).copied().unwrap_or(false))).collect();
        views::mask_image_in(&any, &back, w, h, views::WRONG_COLOR)
    });
    Images { hybrid: views::film_image(&frame.film, exposure), wrong, lights, rays, maps }
}

fn vpl_map(renderer: &Renderer, index: usize) -> VplMap {
    let map = renderer.cached_vpls().and_then(|(_, maps)| maps.get(index));
    let range = map.and_then(|m| views::vpl_map_range(m, MAP_IMAGE_SIDE));
    let image = map.map(|m| views::vpl_map_image(m, MAP_IMAGE_SIDE, range.unwrap_or((1.0, 2.0))));
    VplMap { index, image, range, resolution: map.map_or(0, |m| m.resolution()) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyrt::render::Visibility;

    #[test]
    fn progress_is_rows_done_of_the_stage() {
        let p = Progress::default();
        assert_eq!(p.get(), (String::new(), 0.0));
        p.start("rendering", 4);
        p.done.fetch_add(1, Relaxed);
        assert_eq!(p.get(), ("rendering".to_string(), 0.25));
        p.done.fetch_add(9, Relaxed);
        assert_eq!(p.get().1, 1.0, "clamped");
        p.start("making the views", 0);
        assert_eq!(p.get(), ("making the views".to_string(), 0.0));
    }

    #[test]
    fn queued_renders_coalesce_to_the_newest() {
        let o = Options::hybrid();
        let mut p = o;
        p.shadow.bias = 3.0;
        let scene = hyrt::scene::builtin::cornell();
        let pose = Pose::of(&scene);
        let render = |generation, options| Render {
            generation,
            options,
            pose: pose.clone(),
            full: true,
            reference: true,
        };
        let cmds = vec![
            Command::Render(render(1, o)),
            Command::VplMap(4),
            Command::Render(render(2, p)),
            Command::VplMap(2),
        ];
        let (newest, maps) = coalesce(cmds.into_iter());
        assert_eq!(newest, Some(render(2, p)));
        assert_eq!(maps, vec![4, 2]);
        assert_eq!(coalesce(std::iter::once(Command::VplMap(1))), (None, vec![1]));
    }

    #[test]
    fn the_reference_ignores_the_map_knobs() {
        let mut h = Options::hybrid();
        h.indirect = Indirect::Maps;
        h.indirect_opts.interleave = 4;
        let r = h.reference_for();
        assert_eq!((r.visibility, r.shadows, r.indirect), (Visibility::Rays, Shadows::Rays, Indirect::Rays));
        assert_eq!(r.indirect_opts.interleave, 1, "the reference evaluates every VPL");
        // The caches' keys are the hybrid's: switching between the two drops nothing.
        assert_eq!(
            (r.shadow.map, r.indirect_opts.map, r.indirect_opts.vpl),
            (h.shadow.map, h.indirect_opts.map, h.indirect_opts.vpl)
        );
        let mut h2 = h;
        h2.shadow.bias = 3.0;
        h2.shadow.map.resolution = 64;
        h2.indirect_opts.map.resolution = 64;
        assert!(same_reference(&r, &h2.reference_for()));
        h2.indirect_opts.vpl.paths += 1;
        assert!(!same_reference(&r, &h2.reference_for()));
        h2.indirect = Indirect::None;
        assert!(!same_reference(&r, &h2.reference_for()));
    }
}
