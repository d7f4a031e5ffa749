//! Frustum culling of triangle clusters before the raster visibility pass.
//!
//! The rasterizer rejects off-screen triangles cheaply, but only after they were transformed to
//! clip space and read back: on the conference room two thirds of the 331k triangles are off
//! screen, and moving them through memory was the largest part of the pass. Scene files keep
//! the triangles of an object together, so runs of [`CLUSTER`] consecutive triangles are
//! spatially coherent; each run gets a bounding box once per scene, and a frame transforms only
//! the runs whose box may reach a pixel centre.
//!
//! # Exactness
//!
//! A run is culled only when every corner of its box lies, by a margin, beyond one plane that no
//! pixel centre's ray crosses: the near plane of the rasterizer (`w = near`), or one of the four
//! planes a quarter pixel outside the outermost pixel centres. The plane functions are linear,
//! so their maximum over the box is at a corner: every vertex is beyond the plane too, so the
//! triangle (convex) covers no pixel centre and the rasterizer would have written nothing for
//! it. The margin covers the rounding of the `f32` clip coordinates the rasterizer receives (see
//! `Frustum::culls`). Kept triangles stay in input order with their own ids, so the
//! rasterized buffers are bit-identical with and without culling (tested).

use glam::{DVec3, Vec3};

use crate::camera::CameraRays;

/// Triangles per cluster. Small enough that a cluster rarely straddles the view when most of
/// it is off screen (larger clusters cull markedly fewer off-screen triangles), large enough
/// that the boxes are a small fraction of the scene's memory.
pub const CLUSTER: usize = 64;

/// Bounding boxes of runs of [`CLUSTER`] consecutive triangles (the last run may be shorter).
#[derive(Clone, Debug, Default)]
pub struct Clusters {
    bounds: Vec<[Vec3; 2]>,
}

impl Clusters {
    /// The boxes of `positions`, a run of [`CLUSTER`] triangles each.
    pub fn new(positions: &[[Vec3; 3]]) -> Self {
        let bounds = positions
            .chunks(CLUSTER)
            .map(|run| {
                let vs = run.iter().flatten();
                [
                    vs.clone().fold(Vec3::INFINITY, |a, &v| a.min(v)),
                    vs.fold(Vec3::NEG_INFINITY, |a, &v| a.max(v)),
                ]
            })
            .collect();
        Self { bounds }
    }

    /// Number of clusters.
    pub fn len(&self) -> usize {
        self.bounds.len()
    }

    /// Whether there are no clusters.
    pub fn is_empty(&self) -> bool {
        self.bounds.is_empty()
    }

    /// Writes into `out` the indices, increasing, of the clusters that may cover a pixel centre
    /// of `cam` (see the module docs), with the rasterizer's near plane at `near`.
    pub fn visible(&self, cam: &CameraRays, near: f32, out: &mut Vec<u32>) {
        let frustum = Frustum::new(cam, near);
        out.clear();
        out.extend((0..self.bounds.len() as u32).filter(|&c| !frustum.culls(self.bounds[c as usize])));
    }
}

/// The culling planes of one camera, in `f64`.
struct Frustum {
    eye: DVec3,
    /// `right / tan_x`, `up / tan_y`, `forward`: the clip coordinates `x`, `y`, `w` of a point
    /// `p` are these dotted with `p - eye` (as `visibility::to_clip` computes them in `f32`).
    axes: [DVec3; 3],
    /// `1 - 1/(2 width)`, `1 - 1/(2 height)`: the pixel centres have `|x| <= (1 - 1/width) w`,
    /// the planes `x = +-kx w` lie a quarter pixel beyond.
    k: [f64; 2],
    near: f64,
}

/// Relative margin for the `f32` rounding of clip coordinates: `p - eye`, a 3-term dot product
/// and a product each round at `2^-24`, an error below `8 * 2^-24 (|p| + |eye|)` times the axis
/// length (`1/tan` for x and y, 1 for w); `1e-5` is 167 units of `2^-24`.
const MARGIN: f64 = 1e-5;

impl Frustum {
    fn new(cam: &CameraRays, near: f32) -> Self {
        let d = |v: Vec3| v.as_dvec3();
        Self {
            eye: d(cam.eye),
            axes: [
                d(cam.right) * f64::from(cam.inv_tan_x),
                d(cam.up) * f64::from(cam.inv_tan_y),
                d(cam.forward),
            ],
            k: [1.0 - 0.5 / f64::from(cam.width), 1.0 - 0.5 / f64::from(cam.height)],
            near: f64::from(near),
        }
    }

    /// Whether every corner of the box is beyond the same plane by more than the rounding
    /// margin.
    fn culls(&self, [lo, hi]: [Vec3; 2]) -> bool {
        if !(lo.is_finite() && hi.is_finite()) {
            // Empty or invalid (validated scenes have finite vertices): let the rasterizer
            // decide triangle by triangle.
            return false;
        }
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        // Beyond each plane for all corners so far: right, left, top, bottom, near.
        let mut beyond = [true; 5];
        let scale = lo.abs().max(hi.abs()).max_element() + self.eye.abs().max_element();
        let [ax, ay, aw] = self.axes;
        let m = |axis: DVec3| MARGIN * scale * (axis.length() + 1.0);
        let (mx, my, mw) = (m(ax), m(ay), m(aw));
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let v = c - self.eye;
            let (x, y, w) = (v.dot(ax), v.dot(ay), v.dot(aw));
            let (kx, ky) = (self.k[0] * w, self.k[1] * w);
            beyond[0] &= x - kx > mx + mw;
            beyond[1] &= -x - kx > mx + mw;
            beyond[2] &= y - ky > my + mw;
            beyond[3] &= -y - ky > my + mw;
            beyond[4] &= self.near - w > mw;
        }
        beyond.iter().any(|&b| b)
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec4, vec3};
    use hyrt_raster::{RasterOptions, for_each_fragment};

    use super::*;
    use crate::{render::visibility::to_clip, scene::Camera};

    /// Whether the rasterizer writes any pixel for the triangle.
    fn covers(cam: &CameraRays, near: f32, tri: &[Vec3; 3]) -> bool {
        let clip: [Vec4; 3] = tri.map(|p| to_clip(cam, near, p));
        let mut any = false;
        let opts = RasterOptions { reversed_z: true, ..RasterOptions::default() };
        for_each_fragment(&clip, cam.width, cam.height, &opts, |_| any = true);
        any
    }

    /// Triangles hugging the frustum's planes from both sides (a hair inside, on, a hair
    /// outside the outermost pixel centres and the image border), behind and across the eye,
    /// at scales from 1e-3 to 1e3: no culled cluster would have covered a pixel, and culling
    /// is not vacuous.
    #[test]
    fn culls_only_clusters_that_cover_no_pixel() {
        let mut culled = 0;
        for (scale, (w, h)) in [1e-3f32, 1.0, 1e3].into_iter().zip([(64, 48), (37, 23), (640, 480)]) {
            let cam =
                Camera::look_at(vec3(0.3, 0.2, 1.0) * scale, vec3(0.3, 0.2, -1.0) * scale, Vec3::Y, 60.0);
            let rays = CameraRays::new(&cam, w, h);
            let near = 1e-6 * scale;
            let mut tris = Vec::new();
            // Points at NDC (nx, ny) and distance `dist` along the view: via the camera's rays.
            let at = |nx: f32, ny: f32, dist: f32| {
                rays.eye
                    + (rays.forward + rays.right * (nx * rays.tan_x) + rays.up * (ny * rays.tan_y)) * dist
            };
            let edge_x = 1.0 - 1.0 / w as f32; // the outermost pixel centres
            for dist in [0.5, 3.0, -1.0].map(|d| d * scale) {
                for off in [-2e-3, -1e-5, 0.0, 1e-5, 1e-3, 0.2, 1.0 / w as f32] {
                    for s in [1.0f32, -1.0] {
                        let x = s * (edge_x + off);
                        // A thin triangle along the side of the frustum, one along the top.
                        tris.push([at(x, -0.5, dist), at(x + s * 0.3, 0.0, dist), at(x, 0.5, dist * 1.01)]);
                        tris.push([at(-0.5, x, dist), at(0.0, x + s * 0.3, dist), at(0.5, x, dist * 1.01)]);
                    }
                }
            }
            // Across the eye plane and right at the near plane.
            tris.push([at(0.0, 0.0, -scale), at(0.1, 0.0, scale), at(0.0, 0.1, scale)]);
            tris.push([at(0.0, 0.0, near), at(0.5, 0.0, near), at(0.0, 0.5, near * 0.99)]);
            // One triangle per cluster, so the boxes are tight.
            for tri in &tris {
                let clusters = Clusters::new(std::slice::from_ref(tri));
                let mut vis = Vec::new();
                clusters.visible(&rays, near, &mut vis);
                if vis.is_empty() {
                    culled += 1;
                    assert!(!covers(&rays, near, tri), "culled a covering triangle {tri:?} at scale {scale}");
                }
            }
        }
        assert!(culled > 30, "culling must not be vacuous: {culled}");
    }

    /// Clusters of many triangles: a cluster is kept when any one of them may be visible.
    #[test]
    fn keeps_a_cluster_with_one_visible_triangle() {
        let cam = CameraRays::new(&Camera::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 60.0), 64, 64);
        let behind = [vec3(0.0, 0.0, 5.0), vec3(1.0, 0.0, 5.0), vec3(0.0, 1.0, 5.0)];
        let front = [vec3(0.0, 0.0, -5.0), vec3(1.0, 0.0, -5.0), vec3(0.0, 1.0, -5.0)];
        let mut positions = vec![behind; 2 * CLUSTER + 3];
        positions[CLUSTER + 17] = front;
        let clusters = Clusters::new(&positions);
        assert_eq!(clusters.len(), 3);
        let mut vis = Vec::new();
        clusters.visible(&cam, 1e-6, &mut vis);
        assert_eq!(vis, [1]);
    }
}
