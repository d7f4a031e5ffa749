//! Pinhole camera rays through pixel centres.

use glam::Vec3;

use crate::scene::Camera;

/// A camera prepared for one image size.
///
/// Pixel `(x, y)` (row 0 at the top) is sampled at its centre `(x + 0.5, y + 0.5)`; its ray
/// direction is `forward + sx * right + sy * up` with
/// `sx = (2 (x + 0.5) / W - 1) tan(fov_x / 2)` and `sy = (1 - 2 (y + 0.5) / H) tan(fov_y / 2)`.
/// Without an explicit horizontal fov, `tan(fov_x / 2) = tan(fov_y / 2) W / H` (square pixels).
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    pub eye: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub tan_x: f32,
    pub tan_y: f32,
    pub width: u32,
    pub height: u32,
    /// `2 / width` and `2 / height`: products instead of a division per pixel.
    pub two_over_w: f32,
    pub two_over_h: f32,
    /// `1 / tan_x` and `1 / tan_y`, for projecting points.
    pub inv_tan_x: f32,
    pub inv_tan_y: f32,
}

impl CameraRays {
    /// Builds the camera frame; the camera must have passed `Scene::validate`.
    pub fn new(cam: &Camera, width: u32, height: u32) -> Self {
        let forward = cam.forward.normalize();
        let right = forward.cross(cam.up).normalize();
        let up = right.cross(forward);
        let tan_y = (cam.fov_y_deg.to_radians() * 0.5).tan();
        let tan_x = match cam.fov_x_deg {
            Some(fx) => (fx.to_radians() * 0.5).tan(),
            None => tan_y * width as f32 / height as f32,
        };
        Self {
            eye: cam.eye,
            forward,
            right,
            up,
            tan_x,
            tan_y,
            width,
            height,
            two_over_w: 2.0 / width as f32,
            two_over_h: 2.0 / height as f32,
            inv_tan_x: 1.0 / tan_x,
            inv_tan_y: 1.0 / tan_y,
        }
    }

    /// Unnormalised direction through the centre of pixel `(x, y)`.
    #[inline]
    pub fn direction(&self, x: u32, y: u32) -> Vec3 {
        self.direction_at(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// Unnormalised direction through the film point `(fx, fy)` in pixel units (`(0, 0)` is
    /// the top-left corner of the image, `(x + 0.5, y + 0.5)` the centre of pixel `(x, y)`).
    #[inline]
    pub fn direction_at(&self, fx: f32, fy: f32) -> Vec3 {
        let sx = (fx * self.two_over_w - 1.0) * self.tan_x;
        self.forward + self.right * sx + self.row_offset_at(fy)
    }

    /// The vertical part `sy * up` of the directions at film row coordinate `fy`, constant
    /// along a row (row-batched ray generation adds it last, exactly as [`Self::direction_at`]).
    #[inline]
    pub fn row_offset_at(&self, fy: f32) -> Vec3 {
        self.up * ((1.0 - fy * self.two_over_h) * self.tan_y)
    }
}
