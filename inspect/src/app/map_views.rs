//! The central panel's map views: a light's depth map, face by face, and a VPL's paraboloid
//! map.

use super::*;

impl Inspector {
    pub(super) fn maps_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
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

    pub(super) fn vpls_view(&mut self, ui: &mut egui::Ui, r: &Rendered) {
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
}
