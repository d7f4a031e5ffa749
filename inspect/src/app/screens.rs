//! The central panel: one view at a time (frame, shadows, rays, light maps, VPLs), drawn over the
//! screen grid.

use super::*;

impl Inspector {
    pub(super) fn central(&mut self, ui: &mut egui::Ui) {
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
                self.nav.zoom = 1.0;
                self.nav.center = Vec2::splat(0.5);
            }
            ui.label(format!("zoom {:.1}x", self.nav.zoom));
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

    pub(super) fn frame_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
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

    pub(super) fn shadows_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
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

    pub(super) fn rays_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
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

    pub(super) fn light_selector(&mut self, ui: &mut egui::Ui, n: usize) {
        if n > 1 {
            ui.add(egui::Slider::new(&mut self.light, 0..=n - 1).text("light"));
        }
        self.light = self.light.min(n - 1);
    }

    pub(super) fn texture(&mut self, ctx: &egui::Context, key: &str, image: &ColorImage) -> TextureHandle {
        self.textures
            .entry(key.to_string())
            .or_insert_with(|| ctx.load_texture(key, image.clone(), TextureOptions::NEAREST))
            .clone()
    }

    /// Screen-sized images in a grid of `cols` columns, as large as fits with `below` points
    /// left under them; each captioned (a missing image is a captioned blank). Returns nothing:
    /// picking and zoom are handled inside. With `viewport`, the image keyed `hybrid` moves the
    /// camera and the chosen light.
    pub(super) fn screen_grid(
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
    pub(super) fn screen_image(
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
            self.nav.center -= resp.drag_delta() / rect.size() / self.nav.zoom;
            self.clamp_view();
        }
        if resp.double_clicked() {
            self.nav.zoom = 1.0;
            self.nav.center = Vec2::splat(0.5);
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
                let active = self.nav.drag == Some(Drag::Light(axis));
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

    /// An image fitted into `size` (no zoom); returns where it was drawn.
    pub(super) fn plain_image(
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
}

pub(super) fn face_name(r: &Rendered, l: usize, face: u8) -> String {
    let kind = r.maps.get(l).cloned().flatten().map_or(MapKind::Cube, |m: std::sync::Arc<LightMap>| m.kind());
    let names: &[&str] = if kind == MapKind::Cube { &CUBE_FACES } else { &PARABOLOID_FACES };
    names.get(usize::from(face)).map_or(face.to_string(), |s| s.to_string())
}

pub(super) fn legend_scale(
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

pub(super) fn depth_legend(ui: &mut egui::Ui, app: &mut Inspector, range: Option<(f32, f32)>) {
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

pub(super) fn crosshair(ui: &egui::Ui, p: Pos2) {
    let s = Stroke::new(1.5, PICK_COLOR);
    ui.painter().line_segment([p - Vec2::new(7.0, 0.0), p + Vec2::new(7.0, 0.0)], s);
    ui.painter().line_segment([p - Vec2::new(0.0, 7.0), p + Vec2::new(0.0, 7.0)], s);
    ui.painter().circle_stroke(p, 4.0, s);
}
