//! The right panel: the plan and the frame's decisions, times per pass, rays by kind, the frame
//! rate, and the picked pixel.

use super::*;

impl Inspector {
    pub(super) fn details(&mut self, ui: &mut egui::Ui) {
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
                let names =
                    |b: &[hyrt::plan::Buffer]| b.iter().map(|b| b.name()).collect::<Vec<_>>().join(", ");
                let io = format!("reads: {}\nwrites: {}", names(d.pass.reads()), names(d.pass.writes()));
                decision_row(ui, run, d.pass.name(), &d.reason).on_hover_text(io);
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
    pub(super) fn frame_rate(&mut self, ui: &mut egui::Ui, r: &Rendered) {
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

    pub(super) fn pixel_panel(&mut self, ui: &mut egui::Ui, r: &Rendered) {
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
                    // A border with no ray: its few triangles were tested alone with the ray.
                    _ if lp.map.as_ref().is_some_and(|m| m.lookup.map_border) => {
                        "no ray: a border settled by its triangles alone".to_string()
                    }
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
pub(super) fn reference_wait(full: bool, auto: bool) -> &'static str {
    match (full, auto) {
        (false, _) => "drawn when the camera rests",
        (true, true) => "rendering…",
        (true, false) => "on demand (render the reference now)",
    }
}

/// A pass's colour in the frame-time graph: one per top-level pass, in frame order.
pub(super) fn pass_color(pass: Pass) -> Color32 {
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

pub(super) fn psnr_text(p: f64) -> String {
    if p.is_infinite() { "inf dB (identical)".into() } else { format!("{p:.2} dB") }
}

pub(super) fn wrong_text(r: &Rendered) -> String {
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

pub(super) fn vec3(v: glam::Vec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}

/// One row of the plan or the frame's decisions; the response is the row's.
pub(super) fn decision_row(ui: &mut egui::Ui, run: bool, what: &str, reason: &str) -> egui::Response {
    ui.horizontal_wrapped(|ui| {
        let (t, c) = if run {
            ("run ", Color32::from_rgb(110, 210, 110))
        } else {
            ("skip", Color32::from_rgb(170, 170, 170))
        };
        ui.label(RichText::new(t).monospace().color(c));
        ui.label(RichText::new(what).monospace().strong());
        ui.label(reason);
    })
    .response
}

pub(super) fn swatch(ui: &mut egui::Ui, color: Color32, text: &str) {
    let (rect, _) = ui.allocate_exact_size(Vec2::splat(12.0), Sense::hover());
    ui.painter().rect_filled(rect, 2.0, color);
    ui.painter().rect_stroke(rect, 2.0, Stroke::new(1.0, Color32::GRAY), egui::StrokeKind::Inside);
    ui.label(text);
}
