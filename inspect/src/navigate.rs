//! Camera navigation: the moves of a 3D viewer as pure functions of a [`Camera`].
//!
//! A scene's camera looks from `eye` along `forward`, whose length is the distance to the
//! point it looks at (a scene file's `target`, [`target`]). Every move keeps that meaning:
//! orbiting turns the eye about the target, panning slides both, dollying moves the eye
//! towards the target (shortening `forward`), and flying or looking around moves the eye and
//! carries the target along. `up` is the scene's up axis and is never changed, so that the
//! horizon stays level.

use glam::{Quat, Vec3};
use hyrt::scene::Camera;

/// The point the camera orbits about and pans with: `eye + forward`.
pub fn target(c: &Camera) -> Vec3 {
    c.eye + c.forward
}

/// The camera's unit right and up vectors (the image's x and y axes).
fn frame(c: &Camera) -> (Vec3, Vec3) {
    let f = c.forward.normalize_or(Vec3::NEG_Z);
    let right = f.cross(c.up).normalize_or(f.any_orthonormal_vector());
    (right, right.cross(f))
}

/// Turns `forward` by `yaw` about `up` and by `pitch` about the right axis, the pitch clamped
/// so that the view stays more than a degree from `up` and `-up` (where the image would roll
/// over).
fn turn(c: &Camera, yaw: f32, pitch: f32) -> Vec3 {
    let up = c.up.normalize_or(Vec3::Y);
    let (right, _) = frame(c);
    let limit = 89f32.to_radians();
    let elevation = c.forward.normalize_or(Vec3::NEG_Z).dot(up).clamp(-1.0, 1.0).asin();
    let pitch = (elevation + pitch).clamp(-limit, limit) - elevation;
    let yaw = Quat::from_axis_angle(up, yaw);
    yaw * (Quat::from_axis_angle(right, pitch) * c.forward)
}

/// Orbits the eye about the target: `yaw` radians about `up`, `pitch` about the right axis
/// (positive: the eye rises). The target stays where it is.
pub fn orbit(c: &Camera, yaw: f32, pitch: f32) -> Camera {
    let t = target(c);
    let forward = turn(c, yaw, -pitch);
    Camera { eye: t - forward, forward, ..*c }
}

/// Slides eye and target across the view by `dx`, `dy` image heights (positive: the scene
/// moves right and down, as under a dragged pointer), so that points at the target's depth
/// follow the pointer.
pub fn pan(c: &Camera, dx: f32, dy: f32) -> Camera {
    let (right, up) = frame(c);
    let height = 2.0 * c.forward.length() * (c.fov_y_deg.to_radians() * 0.5).tan();
    let step = (up * dy - right * dx) * height;
    Camera { eye: c.eye + step, ..*c }
}

/// Moves the eye towards the target, to `factor` times its distance (below 1: closer). The
/// distance never falls under `min`, so that the target stays ahead of the eye.
pub fn dolly(c: &Camera, factor: f32, min: f32) -> Camera {
    let t = target(c);
    let d = c.forward.length();
    let forward = c.forward * ((d * factor).max(min.min(d)) / d);
    Camera { eye: t - forward, forward, ..*c }
}

/// Moves eye and target together by `step` in the camera's frame: `x` right, `y` up (the
/// scene's up axis), `z` forward (along the view, level or not).
pub fn fly(c: &Camera, step: Vec3) -> Camera {
    let (right, _) = frame(c);
    let up = c.up.normalize_or(Vec3::Y);
    let ahead = c.forward.normalize_or(Vec3::NEG_Z);
    Camera { eye: c.eye + right * step.x + up * step.y + ahead * step.z, ..*c }
}

/// Turns the view about the eye (mouse look): `yaw` radians about `up` (positive: to the
/// left), `pitch` about the right axis (positive: upwards). The target moves with the view.
pub fn look(c: &Camera, yaw: f32, pitch: f32) -> Camera {
    Camera { forward: turn(c, yaw, pitch), ..*c }
}

/// The camera as a scene file's `[camera]` table. Numbers are written in Rust's shortest form
/// that reads back to the same `f32`, so that the table reproduces this exact view.
pub fn toml(c: &Camera) -> String {
    let v = |v: Vec3| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z);
    let mut s = format!(
        "[camera]\neye = {}\ntarget = {}\nup = {}\nfov_y = {:?}\n",
        v(c.eye),
        v(target(c)),
        v(c.up),
        c.fov_y_deg
    );
    if let Some(fx) = c.fov_x_deg {
        s.push_str(&format!("fov_x = {fx:?}\n"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0)
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn orbit_keeps_the_target_and_the_distance() {
        let c = cam();
        let o = orbit(&c, 0.7, 0.3);
        assert!(close(target(&o), target(&c)));
        assert!((o.forward.length() - 5.0).abs() < 1e-4);
        assert!(o.eye.y > c.eye.y, "a positive pitch raises the eye");
        let back = orbit(&orbit(&c, 0.5, 0.0), -0.5, 0.0);
        assert!(close(back.eye, c.eye));
        // Over the top is refused (the image would roll over): the eye stops a degree short.
        let top = orbit(&c, 0.0, 1.6);
        let elevation = (-top.forward.normalize().y).asin().to_degrees();
        assert!((elevation - 89.0).abs() < 1e-3, "{elevation}");
        assert!((top.forward.length() - 5.0).abs() < 1e-4);
    }

    #[test]
    fn pan_moves_eye_and_target_together() {
        let c = cam();
        let p = pan(&c, 0.5, 0.0);
        assert_eq!(p.forward, c.forward);
        // Half an image height at distance 5 with a 40 degree fov, towards -x (the scene
        // follows the pointer to the right).
        let h = 2.0 * 5.0 * 20f32.to_radians().tan();
        assert!(close(p.eye, c.eye - Vec3::X * 0.5 * h));
        assert!(close(pan(&c, 0.0, 0.25).eye, c.eye + Vec3::Y * 0.25 * h));
    }

    #[test]
    fn dolly_approaches_the_target_and_stops_short_of_it() {
        let c = cam();
        let d = dolly(&c, 0.5, 0.01);
        assert!(close(d.eye, Vec3::new(0.0, 1.0, 2.5)));
        assert!(close(target(&d), target(&c)));
        let near = dolly(&c, 1e-9, 0.01);
        assert!((near.forward.length() - 0.01).abs() < 1e-6);
        assert!(dolly(&c, 2.0, 0.01).eye.z > 9.99);
    }

    #[test]
    fn fly_and_look() {
        let c = cam();
        let f = fly(&c, Vec3::new(1.0, 2.0, 3.0));
        assert!(close(f.eye, Vec3::new(1.0, 3.0, 2.0)), "{}", f.eye);
        assert_eq!(f.forward, c.forward);
        let l = look(&c, std::f32::consts::FRAC_PI_2, 0.0);
        assert_eq!(l.eye, c.eye);
        assert!(close(l.forward, Vec3::new(-5.0, 0.0, 0.0)), "a positive yaw turns left: {}", l.forward);
        assert!(look(&c, 0.0, 0.2).forward.y > 0.0);
    }

    #[test]
    fn toml_reads_back_as_the_same_camera() {
        let mut c = orbit(&cam(), 0.123, 0.05);
        c.fov_x_deg = Some(39.9);
        let t = toml(&c);
        assert!(t.starts_with("[camera]\neye = ["), "{t}");
        let v: toml::Value = toml::from_str(&t).unwrap();
        let cam = &v["camera"];
        let get = |k: &str| {
            let a = cam[k].as_array().unwrap();
            Vec3::from_array(std::array::from_fn(|i| a[i].as_float().unwrap() as f32))
        };
        assert_eq!(get("eye"), c.eye);
        assert!(close(get("target"), target(&c)));
        assert_eq!(cam["fov_y"].as_float().unwrap() as f32, c.fov_y_deg);
        assert_eq!(cam["fov_x"].as_float().unwrap() as f32, 39.9);
    }
}
