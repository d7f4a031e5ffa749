//! Visibility pass: which surface each pixel sees.
//!
//! - [`Visibility::Rays`]: one primary ray through each pixel centre.
//! - [`Visibility::Raster`]: a z-buffer pass (`hyrt-raster`) gives each pixel its visible
//!   triangle; the hit point is then computed exactly by meeting the pixel's camera ray with
//!   that one triangle's plane, using the tracer's own watertight arithmetic. Wherever both
//!   strategies see the same triangle, the hit point, normal and shading are bit-identical;
//!   they can differ only where the two coverage rules disagree (within a pixel of an edge)
//!   or where two surfaces tie in depth.

use glam::{Vec3, Vec4};
use hyrt_raster::{Affine, EMPTY_ID, RasterOptions, Rasterizer, Target, TriangleSource};
use hyrt_tracer::{Hit, RayCounts, RayKind, RowRays};

use rayon::prelude::*;

use super::{Pass, Progress, Renderer, Visibility, cull::CLUSTER, par_rows, runner::Runner};
use crate::camera::CameraRays;

/// Fills the G-buffer: per pixel the visible triangle, the distance along the pixel's camera
/// ray and the barycentrics of the hit; `None` where the pixel sees nothing. Shading points
/// (normals, error bounds) are built from it by the shading passes.
///
/// Both strategies write every pixel, so the G-buffer of the previous frame is reused as it is.
///
/// With `defer` (raster visibility only), the pixels that need a primary ray get none here:
/// they are left `None` and listed (in pixel order), for [`resolve_deferred`] to cast once the
/// shading passes that need no ray are done (the BVH may still be building meanwhile).
pub(crate) fn run(
    r: &Renderer,
    progress: Progress,
    run: &mut Runner,
    defer: bool,
) -> (Vec<Option<Hit>>, Vec<u32>) {
    let deferred = std::sync::Mutex::new(Vec::new());
    let (w, h) = (r.scene.settings.width, r.scene.settings.height);
    let mut gbuffer = r.take_gbuffer(w as usize * h as usize);
    match r.options.visibility {
        Visibility::Rays => {
            run.stats.rays += par_rows(&mut gbuffer, w as usize, progress, |y, row, c| {
                for (x, px) in row.iter_mut().enumerate() {
                    let before = *c;
                    *px = primary_ray(r, x as u32, y, c);
                    r.pixel_rays.add(y as usize * w as usize + x, &before, c);
                }
            });
        }
        Visibility::Raster => {
            let mut scratch = r.raster.lock().unwrap_or_else(|e| e.into_inner());
            let RasterScratch { rasterizer, target, clusters } = &mut *scratch;
            run.part(Pass::VisCull, |_| r.clusters.visible(&r.camera, r.raster_near, clusters));
            run.part(Pass::VisRaster, |_| {
                rasterizer.rasterize_from(&ClusterSource::new(r, clusters), w, h, &raster_options(), target)
            });
            let rays = run.part(Pass::VisResolve, |_| {
                par_rows(&mut gbuffer, w as usize, progress, |y, row, c| {
                    let ids = &target.id[y as usize * w as usize..][..row.len()];
                    let rivals = &target.rival[y as usize * w as usize..][..row.len()];
                    // Each pixel's camera ray on its triangle's plane, a row at a time (SIMD);
                    // EMPTY_ID is no triangle id, so those pixels stay `None`.
                    let parallel = r.tracer.hits_on_row(&row_rays(&r.camera, y), 0, ids, row) > 0;
                    // Pixels that need a ray: some ray runs (numerically) parallel to its
                    // triangle's plane (a sliver seen exactly edge-on; the rasterizer writes only
                    // ids below the triangle count or EMPTY_ID, so the miss count covers these);
                    // and some ray passes just outside the triangle that the z-buffer gave its
                    // pixel (the coverage rule and the ray test differ by a fraction of a pixel
                    // along edges), where its point on the plane lies off the mesh: past a concave
                    // crease, under the neighbouring face, which would shadow it from every light.
                    // Ask the BVH, and count the ray: the G-buffer is then the ray-cast one there.
                    // And some pixel sees a cut-out's hole (the z-buffer draws cut-outs solid): what
                    // lies behind is the ray's to find, as the reference's primary ray does.
                    let holes = !r.cutouts().is_empty();
                    let rays = row_rays(&r.camera, y);
                    // Asked only for pixels with a rival (the groups are made on first use).
                    let same_plane = |a: u32, b: u32| {
                        let groups = r.plane_groups();
                        groups.get(a as usize) == groups.get(b as usize)
                    };
                    for (x, ((px, &id), &rival)) in row.iter_mut().zip(ids).zip(rivals).enumerate() {
                        // Two surfaces too close for the z-buffer's depths to order
                        // (`hyrt_tracer::DEPTH_TIE`): the pixel's ray orders the pair as the
                        // tracer orders any two hits (no traversal). Not needed for two triangles
                        // of the very same plane (a duplicate), which nothing orders: both apply
                        // the same tie rule (the face the camera's ray enters is the rasterizer's
                        // front face; then the smaller id).
                        if rival != EMPTY_ID
                            && !same_plane(rival, id)
                            && px.is_some_and(|h| h.bary.iter().all(|&b| b >= 0.0))
                            && let Some(h) = r.tracer.nearer_hit(&rays.ray(x as u32), id, rival)
                        {
                            *px = Some(h);
                        }
                        let outside = px.is_some_and(|h| h.bary.iter().any(|&b| b < 0.0));
                        let hole = holes && px.is_some_and(|h| !r.scene.solid_at(h.tri, h.bary));
                        if outside || hole || (parallel && px.is_none() && id != EMPTY_ID) {
                            if defer {
                                *px = None;
                                deferred.lock().unwrap_or_else(|e| e.into_inner()).push(y * w + x as u32);
                                continue;
                            }
                            let before = *c;
                            *px = primary_ray(r, x as u32, y, c);
                            r.pixel_rays.add(y as usize * w as usize + x, &before, c);
                        }
                    }
                })
            });
            run.stats.rays += rays;
        }
    }
    let mut deferred = deferred.into_inner().unwrap_or_else(|e| e.into_inner());
    deferred.sort_unstable();
    (gbuffer, deferred)
}

/// Casts the primary rays the visibility pass deferred (pixels `deferred`) into `gbuffer`.
pub(crate) fn resolve_deferred(r: &Renderer, gbuffer: &mut [Option<Hit>], deferred: &[u32]) -> RayCounts {
    let w = r.scene.settings.width.max(1);
    let hits: Vec<(Option<Hit>, RayCounts)> = deferred
        .par_iter()
        .map(|&i| {
            let mut c = RayCounts::default();
            let hit = primary_ray(r, i % w, i / w, &mut c);
            r.pixel_rays.add(i as usize, &RayCounts::default(), &c);
            (hit, c)
        })
        .collect();
    let mut total = RayCounts::default();
    for (&i, (hit, c)) in deferred.iter().zip(hits) {
        gbuffer[i as usize] = hit;
        total += c;
    }
    total
}

/// The rasterizer's options for the visibility pass: reversed-Z ([`ClipTransform`]), and the
/// tracer's tie rule, so that coplanar duplicates resolve alike in both strategies. No
/// barycentrics nor depths: the resolve recomputes each hit exactly from the pixel's ray.
pub fn raster_options() -> RasterOptions {
    RasterOptions {
        reversed_z: true,
        depth_tie: hyrt_tracer::DEPTH_TIE,
        barycentrics: false,
        depth: false,
        rivals: true,
        ..RasterOptions::default()
    }
}

/// The buffers of the raster pass, kept from frame to frame: freshly allocated, megabytes of
/// them would be mapped, faulted in page by page and unmapped every frame.
#[derive(Debug, Default)]
pub(crate) struct RasterScratch {
    pub(crate) rasterizer: Rasterizer,
    target: Target,
    /// Indices of the clusters in view.
    clusters: Vec<u32>,
}

/// The triangles of the clusters in view, in input order with their indices as ids,
/// transformed to clip space by the rasterizer's setup tasks as they need them
/// ([`TriangleSource`]).
///
/// Why: a transform pass of its own wrote megabytes of clip coordinates that setup then read
/// back from memory, after waiting for the slower thread.
struct ClusterSource<'a> {
    tris: &'a [[Vec3; 3]],
    /// Increasing cluster indices. Every cluster but the scene's last has exactly CLUSTER
    /// triangles, and that one, if in view, comes last: triangle `k` of the source is triangle
    /// `k % CLUSTER` of cluster `visible[k / CLUSTER]`.
    visible: &'a [u32],
    len: usize,
    xf: ClipTransform,
}

impl<'a> ClusterSource<'a> {
    fn new(r: &'a Renderer, visible: &'a [u32]) -> Self {
        let tris = &r.scene.positions;
        let len = visible.iter().map(|&c| (tris.len() - c as usize * CLUSTER).min(CLUSTER)).sum();
        Self { tris, visible, len, xf: ClipTransform::new(&r.camera, r.raster_near) }
    }
}

impl TriangleSource for ClusterSource<'_> {
    fn len(&self) -> usize {
        self.len
    }

    fn fill(&self, first: usize, mut clip: &mut [[Vec4; 3]], mut ids: &mut [u32]) {
        let mut k = first;
        while !clip.is_empty() {
            // The rest of the cluster holding triangle `k`, as far as asked.
            let start = self.visible[k / CLUSTER] as usize * CLUSTER + k % CLUSTER;
            let n = (CLUSTER - k % CLUSTER).min(self.tris.len() - start).min(clip.len());
            let (out, rest) = std::mem::take(&mut clip).split_at_mut(n);
            let (out_ids, rest_ids) = std::mem::take(&mut ids).split_at_mut(n);
            self.xf.0.apply_triangles(&self.tris[start..start + n], out);
            for (j, id) in out_ids.iter_mut().enumerate() {
                *id = (start + j) as u32;
            }
            (clip, ids, k) = (rest, rest_ids, k + n);
        }
    }
}

fn primary_ray(r: &Renderer, x: u32, y: u32, c: &mut RayCounts) -> Option<Hit> {
    r.tracer.closest_hit(&r.camera_ray(x, y), RayKind::Primary, c)
}

/// The camera rays of row `y` as the tracer's [`RowRays`]: bit for bit the directions of
/// [`Renderer::camera_ray`] (`CameraRays::direction`, then glam's `normalize`). The part of
/// the direction that is constant along the row, `up * sy`, is computed once, with
/// `CameraRays::direction_at`'s formula for `sy`; the test below holds the two together.
fn row_rays(cam: &CameraRays, y: u32) -> RowRays {
    RowRays {
        origin: cam.eye,
        forward: cam.forward,
        right: cam.right,
        row_offset: cam.row_offset_at(y as f32 + 0.5),
        two_over_w: cam.two_over_w,
        tan_x: cam.tan_x,
        tmax: f32::INFINITY,
    }
}

/// Near-plane distance for rasterization: `2^-20` of the scene's extent. With reversed-Z the
/// near distance costs no depth precision, so it only needs to be small enough that nothing
/// a primary ray would see is clipped; it stays non-zero so that `w >= near > 0` after
/// clipping.
pub(crate) fn near_plane(scene: &crate::scene::Scene, camera: &CameraRays) -> f32 {
    let (lo, hi) = scene.bounds().unwrap_or_default();
    let extent = (hi - lo).max_element().max((camera.eye - lo).abs().max_element());
    (extent * (-20f32).exp2()).max(f32::MIN_POSITIVE)
}

/// The camera's pinhole projection to clip space (reversed-Z), as an affine map.
///
/// The camera's pixel rays are `forward + sx right + sy up` with `sx = x_ndc tan_x`,
/// `sy = y_ndc tan_y` (see [`CameraRays`]). A point `v = p - eye` lies on that ray when
/// `v.right / v.forward = sx` and `v.up / v.forward = sy`, so `x = v.right / tan_x`,
/// `y = v.up / tan_y`, `w = v.forward` give exactly the NDC of the pixel whose ray passes
/// through `p`. `z = near` for every vertex stores `near / w` (reversed-Z).
///
/// Kept as the images of the three world axes (the columns of an [`Affine`] map), so that a
/// vertex is three 4-wide multiply-adds, `clip = vx cx + vy cy + vz cz + (0, 0, near, 0)`,
/// instead of three horizontal dot products, and a triangle a few 16-wide ones
/// ([`Affine::apply_triangles`]): the transform was a tenth of the raster pass. The rasterizer's
/// coverage and exact-depth plane are both relative to these clip coordinates, so their
/// rounding needs to match nothing else (the frustum culling's margin covers it, `cull.rs`).
#[derive(Clone, Copy, Debug)]
pub struct ClipTransform(pub Affine);

impl ClipTransform {
    pub fn new(cam: &CameraRays, near: f32) -> Self {
        let (x, y, w) = (cam.right * cam.inv_tan_x, cam.up * cam.inv_tan_y, cam.forward);
        Self(Affine {
            origin: cam.eye,
            columns: [0, 1, 2].map(|k| Vec4::new(x[k], y[k], 0.0, w[k])),
            offset: Vec4::new(0.0, 0.0, near, 0.0),
        })
    }

    /// Clip-space position of `p`.
    #[inline(always)]
    pub fn apply(&self, p: glam::Vec3) -> Vec4 {
        self.0.apply(p)
    }
}

/// Clip-space position (reversed-Z) of `p` for the camera's pinhole projection
/// ([`ClipTransform`]; build that once to transform many points).
pub fn to_clip(cam: &CameraRays, near: f32, p: glam::Vec3) -> Vec4 {
    ClipTransform::new(cam, near).apply(p)
}

#[cfg(test)]
mod tests {
    use glam::{Vec3, vec3};

    use super::*;
    use crate::{render::Options, scene::Camera};

    /// The source hands out the triangles of the clusters in view in order, with their indices
    /// as ids and `ClipTransform::apply`'s clip coordinates, for any window the setup tasks ask
    /// for: across cluster boundaries and into a last, shorter cluster.
    #[test]
    fn cluster_source_fills_any_window_with_the_clusters_triangles() {
        let mut scene = crate::scene::load("cornell").unwrap();
        // 11 copies of the box's 32 triangles, shifted: 5 full clusters and one of 32.
        let n = scene.positions.len();
        for copy in 1..11 {
            for i in 0..n {
                let shift = Vec3::splat(copy as f32 * 0.01);
                scene.positions.push(scene.positions[i].map(|p| p + shift));
                scene.normals.push(scene.normals[i]);
                scene.material.push(scene.material[i]);
            }
        }
        assert_eq!(scene.positions.len(), 5 * CLUSTER + 32);
        let r = Renderer::new(&scene, Options::default());
        let visible = [0u32, 2, 3, 5];
        let source = ClusterSource::new(&r, &visible);
        let expected: Vec<usize> = visible
            .iter()
            .flat_map(|&c| c as usize * CLUSTER..(c as usize * CLUSTER + CLUSTER).min(352))
            .collect();
        assert_eq!(source.len(), expected.len());
        let xf = ClipTransform::new(&r.camera, r.raster_near);
        let bits = |t: &[Vec4; 3]| t.map(|v| v.to_array().map(f32::to_bits));
        for (first, len) in [(0, expected.len()), (50, 80), (190, 34), (0, 1), (63, 2), (127, 66)] {
            let mut clip = vec![[Vec4::NAN; 3]; len];
            let mut ids = vec![u32::MAX; len];
            source.fill(first, &mut clip, &mut ids);
            for (k, (t, &id)) in clip.iter().zip(&ids).enumerate() {
                let want = expected[first + k];
                assert_eq!(id as usize, want, "window ({first}, {len}), entry {k}");
                assert_eq!(bits(t), bits(&scene.positions[want].map(|p| xf.apply(p))));
            }
        }
    }

    /// `row_rays` must reproduce `Renderer::camera_ray` exactly, or raster and ray hits would
    /// no longer be bit-identical: every pixel of odd image sizes and cameras, including a
    /// horizontal fov and directions where another axis dominates.
    #[test]
    fn row_rays_are_the_camera_rays_bit_for_bit() {
        let mut scene = crate::scene::load("cornell").unwrap();
        let cameras = [
            scene.camera.unwrap(),
            Camera::look_at(vec3(0.3, -2.0, 1.0), vec3(5.0, 1.0, -0.7), vec3(0.2, 1.0, 0.1), 70.0),
            Camera {
                eye: vec3(1e3, 2.5, -3.0),
                forward: vec3(-0.1, -1.0, 0.05),
                up: Vec3::Z,
                fov_y_deg: 120.0,
                fov_x_deg: Some(150.0),
            },
        ];
        for (cam, (w, h)) in cameras.into_iter().zip([(37, 23), (64, 48), (131, 7)]) {
            scene.camera = Some(cam);
            scene.settings.width = w;
            scene.settings.height = h;
            let r = Renderer::new(&scene, Options::default());
            for y in 0..h {
                let rays = row_rays(&r.camera, y);
                for x in 0..w {
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    let (a, b) = (rays.ray(x), r.camera_ray(x, y));
                    assert_eq!(bits(a.dir), bits(b.dir), "pixel ({x}, {y}) of a {w}x{h} image");
                    assert_eq!((bits(a.origin), a.tmax), (bits(b.origin), b.tmax));
                }
            }
        }
    }
}
