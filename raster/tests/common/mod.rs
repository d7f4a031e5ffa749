//! Shared test fixtures: an f64 pinhole camera (the analytic reference), mesh builders and a tiny
//! deterministic PRNG.

// Each test binary uses a different subset of the helpers.
#![allow(dead_code)]

use glam::{DMat3, DMat4, DVec3, DVec4, Vec4};

/// A perspective camera in the wgpu / D3D convention (`glam::dcamera::rh::proj::directx`: NDC z in
/// [0, 1], y up), evaluated in f64 so that it can serve as the analytic reference for the
/// rasterizer's f32 input.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub eye: DVec3,
    pub view: DMat4,
    pub view_proj: DMat4,
    pub inv_view_proj: DMat4,
    pub width: u32,
    pub height: u32,
    pub near: f64,
    pub far: f64,
}

impl Camera {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        fovy_deg: f64,
        near: f64,
        far: f64,
        width: u32,
        height: u32,
    ) -> Self {
        let view = glam::dcamera::rh::view::look_at_mat4(eye, target, up);
        let proj = glam::dcamera::rh::proj::directx::perspective(
            fovy_deg.to_radians(),
            f64::from(width) / f64::from(height),
            near,
            far,
        );
        let view_proj = proj * view;
        Self { eye, view, view_proj, inv_view_proj: view_proj.inverse(), width, height, near, far }
    }

    /// Clip-space position, rounded to f32 as a renderer would pass it.
    pub fn clip(&self, p: DVec3) -> Vec4 {
        (self.view_proj * p.extend(1.0)).as_vec4()
    }

    pub fn clip_tris(&self, verts: &[DVec3], tris: &[[u32; 3]]) -> Vec<[Vec4; 3]> {
        let clip: Vec<Vec4> = verts.iter().map(|&v| self.clip(v)).collect();
        tris.iter().map(|t| t.map(|i| clip[i as usize])).collect()
    }

    /// Unit direction of the ray through the centre of pixel `(px, py)`.
    pub fn ray(&self, px: u32, py: u32) -> DVec3 {
        let nx = (f64::from(px) + 0.5) / f64::from(self.width) * 2.0 - 1.0;
        let ny = 1.0 - (f64::from(py) + 0.5) / f64::from(self.height) * 2.0;
        let unproject = |z: f64| {
            let p = self.inv_view_proj * DVec4::new(nx, ny, z, 1.0);
            p.truncate() / p.w
        };
        (unproject(1.0) - unproject(0.0)).normalize()
    }

    /// Distance along the view axis (clip w).
    pub fn view_depth(&self, p: DVec3) -> f64 {
        -(self.view * p.extend(1.0)).z
    }

    /// NDC depth z / w.
    pub fn ndc_depth(&self, p: DVec3) -> f64 {
        let c = self.view_proj * p.extend(1.0);
        c.z / c.w
    }
}

/// A UV sphere with `slices` meridians and `stacks` bands (pole fans + quads), every triangle
/// counter-clockwise seen from outside. Vertices are shared, so shared edges are bit-identical.
pub fn uv_sphere(
    center: DVec3,
    radius: f64,
    slices: u32,
    stacks: u32,
    rotation: DMat3,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    use std::f64::consts::PI;
    let mut verts = vec![center + rotation * DVec3::Y * radius];
    for i in 1..stacks {
        let theta = PI * f64::from(i) / f64::from(stacks);
        for j in 0..slices {
            let phi = 2.0 * PI * f64::from(j) / f64::from(slices);
            let d = DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            verts.push(center + rotation * d * radius);
        }
    }
    verts.push(center - rotation * DVec3::Y * radius);
    let south = verts.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * slices + j % slices;
    let mut tris = Vec::new();
    for j in 0..slices {
        tris.push([0, ring(1, j), ring(1, j + 1)]);
        tris.push([south, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1));
            tris.push([a, c, d]);
            tris.push([a, d, b]);
        }
    }
    orient_outward(&verts, &mut tris, center);
    (verts, tris)
}

/// Makes every triangle counter-clockwise seen from outside (normal pointing away from `center`).
pub fn orient_outward(verts: &[DVec3], tris: &mut [[u32; 3]], center: DVec3) {
    for t in tris {
        let [a, b, c] = t.map(|i| verts[i as usize]);
        if (b - a).cross(c - a).dot(a + b + c - 3.0 * center) < 0.0 {
            t.swap(1, 2);
        }
    }
}

/// Reverses the winding of clip-space triangles (front faces become back faces).
pub fn reversed(tris: &[[Vec4; 3]]) -> Vec<[Vec4; 3]> {
    tris.iter().map(|t| [t[0], t[2], t[1]]).collect()
}

/// Clip-space position (w = 1, z = `depth`) of a point given in pixel coordinates (y down).
pub fn pixel_to_clip(x: f64, y: f64, depth: f64, width: u32, height: u32) -> Vec4 {
    Vec4::new(
        (x / f64::from(width) * 2.0 - 1.0) as f32,
        (1.0 - y / f64::from(height) * 2.0) as f32,
        depth as f32,
        1.0,
    )
}

/// A `nx x ny` grid of quads over shared vertices `corner(i, j)`, each quad split along a
/// diagonal chosen by `flip(i, j)`. When `corner` maps `i` to the right and `j` downwards on
/// screen, every triangle is counter-clockwise in NDC (front-facing).
pub fn grid_tris(
    nx: u32,
    ny: u32,
    corner: impl Fn(u32, u32) -> Vec4,
    flip: impl Fn(u32, u32) -> bool,
) -> Vec<[Vec4; 3]> {
    let verts: Vec<Vec<Vec4>> = (0..=ny).map(|j| (0..=nx).map(|i| corner(i, j)).collect()).collect();
    let mut tris = Vec::new();
    for j in 0..ny as usize {
        for i in 0..nx as usize {
            // a b   (y down). a -> c -> d is clockwise on screen, i.e. counter-clockwise in NDC
            // c d   (y up); likewise a -> d -> b, a -> c -> b and b -> c -> d.
            let (a, b) = (verts[j][i], verts[j][i + 1]);
            let (c, d) = (verts[j + 1][i], verts[j + 1][i + 1]);
            if flip(i as u32, j as u32) {
                tris.push([a, c, b]);
                tris.push([b, c, d]);
            } else {
                tris.push([a, c, d]);
                tris.push([a, d, b]);
            }
        }
    }
    tris
}

#[allow(unused_imports)] // Not every test that includes this module draws random inputs.
pub use hyrt_testkit::Rng;

/// Whether `value(x, y)` equals `value` at all 8 neighbours inside the image: pixels whose centre
/// is within about a pixel of an analytic boundary are excluded from exact comparisons.
pub fn unambiguous<T: PartialEq>(
    width: u32,
    height: u32,
    x: u32,
    y: u32,
    value: impl Fn(u32, u32) -> T,
) -> bool {
    let v = value(x, y);
    for dy in -1i64..=1 {
        for dx in -1i64..=1 {
            let (nx, ny) = (i64::from(x) + dx, i64::from(y) + dy);
            if nx < 0 || ny < 0 || nx >= i64::from(width) || ny >= i64::from(height) {
                continue;
            }
            if value(nx as u32, ny as u32) != v {
                return false;
            }
        }
    }
    true
}
