//! hyrt-inspect: an egui window that shows why the hybrid renderer is fast and where it is
//! wrong: the hybrid frame against the reference and their difference, per light the occlusion
//! map, the shadow borders before and after dilation and where the selective rays went, rays
//! per pixel by kind, the light and VPL depth maps, the plan and the frame's decisions, times
//! per pass and rays by kind, pixel picking, knobs that re-render, and a camera and lights that
//! move while the hybrid keeps rendering.
//!
//! [`worker`] renders on a background thread, [`views`] turns buffers into images (pure
//! functions), [`pick`] gathers what is known at one pixel, [`navigate`] moves the camera,
//! [`app`] is the window (its panels, central views and viewport navigation in files of
//! their own).

pub mod app;
pub mod navigate;
pub mod pick;
pub mod views;
pub mod worker;

pub use app::{Inspector, View};
pub use worker::Setup;
