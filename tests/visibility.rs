//! Rasterized primary visibility against ray casting, on the thesis scenes at 640x480.
//!
//! Bound: the rasterized triangle id equals the ray-cast id on at least 99.9 % of pixels, and
//! every pixel where they differ is explained as one of
//! - an **edge**: an edge of one of the two triangles passes within 1/16 pixel of the pixel
//!   centre (the rasterizer snaps vertices to 1/256 pixel and applies the top-left rule; the ray
//!   test is exact in world space: they may disagree about centres that close to an edge), or
//! - a **depth tie**: the pixel's camera ray hits both triangles at distances within the
//!   z-buffer's tie window (`hyrt_tracer::DEPTH_TIE`), where the pass orders the z-buffer's
//!   winner and its rival as the tracer would; a third surface in the same window, which
//!   the z-buffer does not record, may still differ.

mod common;

use common::*;
use hyrt::{
    film::Film,
    render::{Options, Renderer, Visibility},
    scene::Scene,
};
use hyrt_tracer::Hit;

struct Agreement {
    pixels: usize,
    differ: usize,
    edges: usize,
    ties: usize,
    unexplained: Vec<String>,
}

fn id(h: &Option<Hit>) -> u32 {
    h.map_or(u32::MAX, |h| h.tri)
}

fn agreement(scene: &Scene) -> (Agreement, Vec<Option<Hit>>, Vec<Option<Hit>>, Renderer<'_>) {
    let rays = Renderer::new(scene, Options { visibility: Visibility::Rays, ..Options::default() });
    let raster = Renderer::new(scene, Options { visibility: Visibility::Raster, ..Options::default() });
    let (g_rays, st_rays) = rays.visibility();
    let (g_raster, st_raster) = raster.visibility();
    let (w, h) = (scene.settings.width as i64, scene.settings.height as i64);
    // A primary ray only where a pixel's ray leaves its rasterized triangle.
    assert!(st_raster.rays.primary * 1000 <= (w * h) as u64, "{:?}", st_raster.rays);
    assert_eq!(st_rays.rays.primary, (w * h) as u64);
    let mut a = Agreement { pixels: (w * h) as usize, differ: 0, edges: 0, ties: 0, unexplained: vec![] };
    let ray_at = |fx: f32, fy: f32| {
        hyrt_tracer::Ray::new(rays.camera.eye, rays.camera.direction_at(fx, fy).normalize(), f32::INFINITY)
    };
    // Does an edge of `tri` pass within `EDGE_PX` of the centre of pixel (x, y)? Measured in
    // f64 on the film: the distance from the centre to the projected triangle's boundary.
    // Triangles reaching behind the camera plane have no such projection; for them, rays
    // through the centre and a ring of 16 points at that distance must disagree about being
    // inside.
    const EDGE_PX: f32 = 1.0 / 16.0;
    let cam = rays.camera;
    let (w_px, h_px) = (w as f64, h as f64);
    let film = |q: glam::Vec3| {
        let v = (q - cam.eye).as_dvec3();
        let w = v.dot(cam.forward.as_dvec3());
        let x = v.dot(cam.right.as_dvec3()) / cam.tan_x as f64 / w;
        let y = v.dot(cam.up.as_dvec3()) / cam.tan_y as f64 / w;
        (glam::DVec2::new((x + 1.0) * 0.5 * w_px, (1.0 - y) * 0.5 * h_px), w)
    };
    let at_edge = |x: i64, y: i64, tri: u32| {
        let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
        let v = scene.positions[tri as usize].map(film);
        if v.iter().all(|(_, w)| *w > 0.0) {
            let c = glam::DVec2::new(cx as f64, cy as f64);
            let dist = (0..3)
                .map(|i| {
                    let (a, b) = (v[i].0, v[(i + 1) % 3].0);
                    let t = ((c - a).dot(b - a) / (b - a).length_squared().max(1e-300)).clamp(0.0, 1.0);
                    (a + (b - a) * t - c).length()
                })
                .fold(f64::INFINITY, f64::min);
            return dist <= EDGE_PX as f64;
        }
        let inside_centre = rays.tracer.hits_triangle(tri, &ray_at(cx, cy)).is_some();
        (0..16).any(|k| {
            let a = k as f32 * std::f32::consts::TAU / 16.0;
            let r = ray_at(cx + EDGE_PX * a.cos(), cy + EDGE_PX * a.sin());
            rays.tracer.hits_triangle(tri, &r).is_some() != inside_centre
        })
    };
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let (r, z) = (id(&g_rays[i]), id(&g_raster[i]));
            if r == z {
                continue;
            }
            a.differ += 1;
            if (r != u32::MAX && at_edge(x, y, r)) || (z != u32::MAX && at_edge(x, y, z)) {
                a.edges += 1;
                continue;
            }
            let ray = rays.camera_ray(x as u32, y as u32);
            let t = |tri: u32| rays.tracer.hits_triangle(tri, &ray).map(|h| h.t);
            if let (Some(tr), Some(tz)) = (t(r), t(z))
                && hyrt_tracer::depth_tie(tr, tz)
            {
                a.ties += 1;
                continue;
            }
            let (tr, tz) = (t(r), t(z));
            a.unexplained.push(format!("pixel ({x},{y}): rays see {r} at {tr:?}, raster sees {z} at {tz:?}"));
        }
    }
    drop(raster);
    (a, g_rays, g_raster, rays)
}

fn check_scene(file: &str) -> (Agreement, Scene) {
    let mut scene = hyrt::scene::load(root().join("scenes").join(file).to_str().unwrap()).unwrap();
    scene.settings.width = 640;
    scene.settings.height = 480;
    let (a, ..) = agreement(&scene);
    let frac = 1.0 - a.differ as f64 / a.pixels as f64;
    eprintln!(
        "{file}: {} of {} pixels differ ({} edges, {} depth ties)",
        a.differ, a.pixels, a.edges, a.ties
    );
    assert!(frac >= 0.999, "{file}: only {:.4} % of pixels agree", frac * 100.0);
    assert!(a.unexplained.is_empty(), "{file}: unexplained disagreements:\n{}", a.unexplained.join("\n"));
    (a, scene)
}

#[test]
fn raster_ids_match_ray_cast_ids_on_cornell_bunny_mirror() {
    check_scene("cornell-bunny-mirror.toml");
}

#[test]
fn raster_ids_match_ray_cast_ids_on_office() {
    check_scene("office.toml");
}

/// The conference room is closed around the camera, and its ceiling is a few huge triangles
/// that pass behind the camera: the near-plane clipper must draw them, with no hole and no
/// triangle missing or inverted.
#[test]
fn raster_ids_match_ray_cast_ids_on_conference_including_the_clipped_ceiling() {
    let mut scene = hyrt::scene::load(root().join("scenes/conference.toml").to_str().unwrap()).unwrap();
    scene.settings.width = 640;
    scene.settings.height = 480;
    let (a, g_rays, g_raster, rays) = agreement(&scene);
    eprintln!(
        "conference: {} of {} pixels differ ({} edges, {} depth ties)",
        a.differ, a.pixels, a.edges, a.ties
    );
    assert!(a.unexplained.is_empty(), "unexplained disagreements:\n{}", a.unexplained.join("\n"));
    assert!(a.differ as f64 <= 0.001 * a.pixels as f64, "{} pixels differ", a.differ);
    // Every pixel sees something in a closed room, with either strategy.
    assert!(g_rays.iter().all(Option::is_some), "the ray-cast image has holes");
    assert_eq!(g_raster.iter().filter(|h| h.is_none()).count(), 0, "the rasterized image has holes");
    // Triangles with a vertex behind the camera plane: they need clipping.
    let cam = rays.camera;
    let behind =
        |tri: u32| scene.positions[tri as usize].iter().any(|p| (*p - cam.eye).dot(cam.forward) <= 0.0);
    let clipped_px = g_rays.iter().filter(|h| h.is_some_and(|h| behind(h.tri))).count();
    let same = g_rays
        .iter()
        .zip(&g_raster)
        .filter(|(r, z)| r.is_some_and(|r| behind(r.tri)) && id(r) == id(z))
        .count();
    assert!(clipped_px > 10_000, "the test should see clipped triangles: {clipped_px} pixels");
    assert!(same as f64 >= 0.999 * clipped_px as f64, "{same} of {clipped_px} clipped-triangle pixels agree");
}

/// Where both strategies see the same triangle, the hit (and so all shading) is bit-identical.
#[test]
fn raster_hits_are_bit_identical_where_the_triangle_agrees() {
    let scene = hyrt::scene::load("cornell").unwrap();
    let rays = Renderer::new(&scene, Options::default());
    let raster = Renderer::new(&scene, Options { visibility: Visibility::Raster, ..Options::default() });
    let (a, b) = (rays.visibility().0, raster.visibility().0);
    let same = a.iter().zip(&b).filter(|(x, y)| id(x) == id(y) && x.is_some()).count();
    let identical = a.iter().zip(&b).filter(|(x, y)| id(x) == id(y) && x.is_some() && x == y).count();
    assert!(same > 200_000);
    assert_eq!(identical, same);
}

#[test]
fn raster_visibility_casts_few_primary_rays_and_times_its_pass() {
    let mut scene = hyrt::scene::load("cornell").unwrap();
    scene.settings.width = 80;
    scene.settings.height = 60;
    let f = render(&scene, Options { visibility: Visibility::Raster, ..Options::default() });
    assert!(f.stats.rays.primary * 100 < 80 * 60, "{:?}", f.stats.rays);
    assert!(f.stats.pass_ms.contains_key(&hyrt::render::Pass::Visibility));
    let reference = render(&scene, Options::default());
    // Same shading wherever the triangle agrees: the images are nearly identical.
    let c = hyrt::metrics::compare(
        &hyrt::metrics::DisplayImage::from_film(&reference.film, 1.0),
        &hyrt::metrics::DisplayImage::from_film(&f.film, 1.0),
    )
    .unwrap();
    assert!(c.psnr_db >= 40.0, "{c:?}");
}

#[test]
fn raster_visibility_is_the_same_for_one_and_two_threads() {
    let mut scene = hyrt::scene::load("cornell").unwrap();
    scene.settings.width = 160;
    scene.settings.height = 120;
    let run =
        |n| -> Film {
            rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(|| {
                render(&scene, Options { visibility: Visibility::Raster, ..Options::default() }).film
            })
        };
    assert!(run(1).pixels == run(2).pixels);
}

/// Frustum culling of triangle clusters (`render::cull`) removes only triangles that cover no
/// pixel: on the conference room, where it drops most clusters, the raster pass gives exactly
/// the ids of rasterizing every triangle; and a second frame, drawn into the buffers the first
/// one left, is identical.
#[test]
fn cluster_culling_and_buffer_reuse_change_no_pixel() {
    let mut scene = hyrt::scene::load(root().join("scenes/conference.toml").to_str().unwrap()).unwrap();
    scene.settings.width = 640;
    scene.settings.height = 480;
    let r = Renderer::new(&scene, Options { visibility: Visibility::Raster, ..Options::default() });
    let mut visible = Vec::new();
    r.clusters.visible(&r.camera, r.raster_near, &mut visible);
    assert!(visible.len() * 2 < r.clusters.len(), "{} of {} clusters kept", visible.len(), r.clusters.len());

    let (g, st) = r.visibility();
    let clip: Vec<[glam::Vec4; 3]> = scene
        .positions
        .iter()
        .map(|t| t.map(|p| hyrt::render::visibility::to_clip(&r.camera, r.raster_near, p)))
        .collect();
    let ids: Vec<u32> = (0..clip.len() as u32).collect();
    let opts = hyrt_raster::RasterOptions {
        reversed_z: true,
        depth_tie: hyrt_tracer::DEPTH_TIE,
        rivals: true,
        ..Default::default()
    };
    let all = hyrt_raster::rasterize(&clip, &ids, 640, 480, &opts);
    // The pass casts a ray exactly where the pixel's ray leaves the rasterized triangle (its
    // point on the plane would be off the mesh); where the z-buffer had a rival, it keeps the
    // nearer of the two by the tracer's rule; everywhere else it keeps the raster's id.
    let (mut leaves, mut rivals) = (0, 0);
    for (i, ((h, &t), &rival)) in g.iter().zip(&all.id).zip(&all.rival).enumerate() {
        let ray = r.camera_ray(i as u32 % 640, i as u32 / 640);
        let outside = t != hyrt_raster::EMPTY_ID
            && r.tracer.hit_on_plane(t, &ray).is_some_and(|p| p.bary.iter().any(|&b| b < 0.0));
        if outside {
            leaves += 1;
        } else if rival != hyrt_raster::EMPTY_ID {
            rivals += 1;
            let want = r.tracer.nearer_hit(&ray, t, rival).map_or(t, |n| n.tri);
            assert_eq!(id(h), want, "pixel {i}: not the nearer of its triangle and its rival");
        } else {
            assert_eq!(id(h), t, "pixel {i}: culling changed the id");
        }
    }
    assert!(rivals > 0, "the conference room has near-coincident surfaces");
    assert_eq!(st.rays.primary, leaves, "a ray for each pixel whose ray leaves its triangle, and only those");
    assert!(leaves * 1000 <= g.len() as u64, "{leaves} rays");
    assert!(r.visibility().0 == g, "the second frame differs");
    // Frames reuse the last G-buffer without clearing it: every pixel must be overwritten.
    r.recycle_gbuffer(vec![Some(Hit { t: 1.0, tri: 7, bary: [0.25, 0.25, 0.5] }); g.len()]);
    assert!(r.visibility().0 == g, "a recycled G-buffer's old contents leaked into the frame");
}

/// The ray-cast G-buffer, too, overwrites every pixel of a recycled one (misses included).
#[test]
fn recycled_gbuffer_is_overwritten_by_rays() {
    let scene = hyrt::scene::load("cornell").unwrap();
    let r = Renderer::new(&scene, Options::default());
    let (g, _) = r.visibility();
    assert!(g.iter().any(|h| h.is_none()) && g.iter().any(|h| h.is_some()));
    r.recycle_gbuffer(vec![Some(Hit { t: 1.0, tri: 7, bary: [0.25, 0.25, 0.5] }); g.len()]);
    assert!(r.visibility().0 == g, "a recycled G-buffer's old contents leaked into the frame");
}
