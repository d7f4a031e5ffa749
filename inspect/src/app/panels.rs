//! The left panel: the status bar (frame, reference, speed-up), the knobs, the camera and the
//! lights.

use super::*;

impl Inspector {
    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
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

    pub(super) fn knobs(&mut self, ui: &mut egui::Ui) {
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
    pub(super) fn camera_panel(&mut self, ui: &mut egui::Ui) {
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
        let speed = self.nav.fly_speed * 0.01;
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
}

/// The slider range of knob `name`, as [`hyrt::options::KNOBS`] declares it (one place for
/// the CLI's checks and the inspector's sliders).
pub(super) fn knob_range<T: egui::emath::Numeric>(name: &str) -> std::ops::RangeInclusive<T> {
    let (lo, hi) = hyrt::options::knob(name).and_then(|k| k.slider).unwrap_or((0.0, 1.0));
    T::from_f64(lo)..=T::from_f64(hi)
}

/// A combo box over every value of an enum knob, by its names ([`Choice`]).
pub(super) fn combo<T: Choice>(ui: &mut egui::Ui, label: &str, value: &mut T) -> egui::Response {
    egui::ComboBox::from_label(label)
        .selected_text(value.name())
        .show_ui(ui, |ui| {
            for v in T::ALL {
                ui.selectable_value(value, *v, v.name());
            }
        })
        .response
}

pub(super) fn resolution_combo(ui: &mut egui::Ui, label: &str, value: &mut u32) {
    egui::ComboBox::from_label(label).selected_text(format!("{0}x{0}", *value)).show_ui(ui, |ui| {
        for r in RESOLUTIONS {
            ui.selectable_value(value, r, format!("{r}x{r}"));
        }
    });
}
