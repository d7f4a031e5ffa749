//! Moving about the viewport: the camera by dragging and zooming, a light by its gizmo.

use super::*;

impl Inspector {
    /// The handle of the light being edited, on the viewport `placed` of frame `r`: where the
    /// light is, and the ends of its three axes (each a tenth of its distance to the eye).
    pub(super) fn gizmo(&self, r: &Rendered, placed: Placed) -> Option<Gizmo> {
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
    pub(super) fn navigate(&mut self, ui: &egui::Ui, resp: &egui::Response, gizmo: Option<&Gizmo>) {
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
            self.nav.drag = Some(Drag::Look);
        } else if resp.drag_started() {
            let axis = gizmo.zip(origin).and_then(|(g, o)| {
                (0..3)
                    .map(|a| (a, segment_distance(o, g.at, g.ends[a])))
                    .filter(|(_, d)| *d < 8.0)
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(a, _)| a)
            });
            self.nav.drag = Some(match axis {
                Some(a) if !shift && !middle => Drag::Light(a),
                _ if shift || middle => Drag::Pan,
                _ => Drag::Orbit,
            });
        }
        let d = resp.drag_delta();
        let height = resp.rect.height().max(1.0) / self.nav.zoom;
        match self.nav.drag {
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
        if released && (self.nav.drag != Some(Drag::Look) || !secondary) {
            self.nav.drag = None;
        }
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.set_camera(navigate::dolly(&cam, (-scroll * 0.002).exp(), self.nav.fly_speed * 1e-3));
            }
        }
    }

    pub(super) fn uv(&self) -> Rect {
        let half = Vec2::splat(0.5 / self.nav.zoom);
        Rect::from_min_max((self.nav.center - half).to_pos2(), (self.nav.center + half).to_pos2())
    }

    /// Zooms by `factor` keeping image point `at` (fractions of the visible window) in place.
    pub(super) fn zoom_by(&mut self, factor: f32, at: Option<Vec2>) {
        let at = at.unwrap_or(Vec2::splat(0.5));
        let uv = self.uv();
        let fixed = uv.min.to_vec2() + at * uv.size();
        let zoom = (self.nav.zoom * factor).clamp(1.0, 64.0);
        // The fixed point keeps its place in the window.
        self.nav.center = fixed + (Vec2::splat(0.5) - at) / zoom;
        self.nav.zoom = zoom;
        self.clamp_view();
    }

    pub(super) fn clamp_view(&mut self) {
        let half = 0.5 / self.nav.zoom;
        self.nav.center.x = self.nav.center.x.clamp(half, 1.0 - half);
        self.nav.center.y = self.nav.center.y.clamp(half, 1.0 - half);
    }
}

/// A light's handle on the viewport: where the light is and where its x, y, z axes end, and
/// the world length of an axis.
pub(super) struct Gizmo {
    pub(super) at: Pos2,
    pub(super) ends: [Pos2; 3],
    pub(super) reach: f32,
}

pub(super) const AXIS_COLORS: [Color32; 3] =
    [Color32::from_rgb(235, 70, 70), Color32::from_rgb(80, 220, 80), Color32::from_rgb(80, 140, 255)];

/// Distance from `p` to the segment `a`-`b`.
pub(super) fn segment_distance(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-6)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Where a screen-sized image was drawn, and which part of it is visible.
pub(super) struct Placed {
    pub(super) rect: Rect,
    pub(super) uv: Rect,
    /// Image size in pixels.
    pub(super) img: Vec2,
    /// Where it was clicked this frame.
    pub(super) clicked_at: Option<Pos2>,
}

impl Placed {
    /// Screen position of image point `(fx, fy)` (pixel units).
    pub(super) fn to_screen(&self, fx: f32, fy: f32) -> Pos2 {
        let u = (Vec2::new(fx, fy) / self.img - self.uv.min.to_vec2()) / self.uv.size();
        self.rect.min + u * self.rect.size()
    }

    /// Image point (pixel units) under screen position `p`.
    pub(super) fn to_image(&self, p: Pos2) -> (f32, f32) {
        let u = (p - self.rect.min) / self.rect.size() * self.uv.size() + self.uv.min.to_vec2();
        (u.x * self.img.x, u.y * self.img.y)
    }
}
