//! Thesis table 4.1: primary visibility by rays vs by rasterization.
//!
//! `cargo bench --bench visibility` renders each thesis scene at 640x480 (`HYRT_BENCH_SIZE`, e.g.
//! `1280x960`, for another size) and prints, measured
//! side by side in one process (strategies alternated frame by frame, medians):
//! - the visibility pass alone (`HYRT_BENCH_FRAMES`, default 15 frames each), with the raster
//!   pass split into cluster culling, rasterization (with the transform to clip space) and
//!   hit-point resolve;
//! - the whole reference frame with each visibility strategy (a third as many frames);
//! - what the rasterizer processed (triangles submitted after the cluster culling, set up,
//!   tiny, bin entries) and the CPU time per submitted triangle and per resolved pixel;
//! - rays per frame by kind, for each strategy;
//! - the rasterizer alone in M triangles/s;
//! - the densest mesh of each scene (most triangles per pixel it is seen at): primary rays over
//!   its pixels against rasterizing its triangles alone, and rays over the other pixels. It
//!   shows where the 10x target is lost: a mesh with more triangles than pixels costs the
//!   rasterizer per triangle what it costs rays per pixel;
//! - the ceiling of the speed-up: the raster pass on the same scene with its dense meshes (at
//!   least one triangle per pixel that sees them) left out, against rays over the whole scene.
//!   No improvement of the rasterizer on those meshes can beat it.
//!
//! Threads: all cores (`RAYON_NUM_THREADS` to change). Scenes: `HYRT_BENCH_SCENES`.

mod common;

use std::time::Instant;

use common::{frames, load_640x480, median, scenes, size};

use hyrt::render::{
    Options, Renderer, Visibility,
    visibility::{ClipTransform, raster_options},
};
use hyrt_raster::{Rasterizer, Target, TriangleSource};
use hyrt_tracer::{RayCounts, RayKind};
use rayon::prelude::*;

fn main() {
    let frames = frames(15);
    let (width, height) = size();
    println!(
        "primary visibility at {width}x{height}, {} threads; visibility medians of {frames} frames, whole frames of {}",
        rayon::current_num_threads(),
        frames.div_ceil(3)
    );
    let mut vis_rows = Vec::new();
    let mut ray_rows = Vec::new();
    let mut work_rows = Vec::new();
    let mut dense_rows = Vec::new();
    let mut ceiling_rows = Vec::new();
    for spec in scenes() {
        let Some(mut scene) = load_640x480(&spec) else { continue };
        (scene.settings.width, scene.settings.height) = (width, height);
        let rays = Renderer::new(&scene, Options { visibility: Visibility::Rays, ..Options::default() });
        let raster = Renderer::new(&scene, Options { visibility: Visibility::Raster, ..Options::default() });

        let (mut t_rays, mut t_raster) = (Vec::new(), Vec::new());
        let (mut t_cull, mut t_rz, mut t_rs) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..=frames {
            let (a, _) = timed_visibility(&rays);
            let (b, st) = timed_visibility(&raster);
            if i > 0 {
                t_rays.push(a);
                t_raster.push(b);
                t_cull.push(st.ms(hyrt::render::Pass::VisCull));
                t_rz.push(st.ms(hyrt::render::Pass::VisRaster));
                t_rs.push(st.ms(hyrt::render::Pass::VisResolve));
            }
        }
        let (mut f_rays, mut f_raster) = (Vec::new(), Vec::new());
        let (mut s_rays, mut s_raster) = (None, None);
        for _ in 0..frames.div_ceil(3) {
            let t = Instant::now();
            let f = rays.render(&|| {});
            f_rays.push(t.elapsed().as_secs_f64() * 1e3);
            s_rays = Some(f.stats.rays);
            let t = Instant::now();
            let f = raster.render(&|| {});
            f_raster.push(t.elapsed().as_secs_f64() * 1e3);
            s_raster = Some(f.stats.rays);
        }
        let work = raster.raster_stats();
        // One G-buffer for both per-mesh analyses.
        let (gbuffer, _) = raster.visibility();
        let seen_by = mesh_pixels(&raster, &gbuffer);
        dense_rows.extend(densest_mesh(&raster, &gbuffer, &seen_by, frames));
        raster.recycle_gbuffer(gbuffer);
        ceiling_rows.extend(ceiling(&rays, &seen_by, frames));
        let (vr, vz) = (median(&mut t_rays), median(&mut t_raster));
        let (fr, fz) = (median(&mut f_rays), median(&mut f_raster));
        let (rz, rv) = (median(&mut t_rz), median(&mut t_rs));
        // Per item and core: the pass's CPU time (ms x threads) over what it processed.
        let cpu_ns = |ms: f64, n: usize| ms * 1e6 * rayon::current_num_threads() as f64 / n.max(1) as f64;
        work_rows.push(format!(
            "| {} | {} | {} | {} ({:.0} %) | {} | {:.0} | {:.1} |",
            scene.name,
            work.submitted,
            work.set_up,
            work.tiny,
            100.0 * work.tiny as f64 / work.set_up.max(1) as f64,
            work.bin_entries,
            cpu_ns(rz, work.submitted),
            cpu_ns(rv, (scene.settings.width * scene.settings.height) as usize),
        ));
        vis_rows.push(format!(
            "| {} | {} | {:.1} | {:.1} ({:.2} + {:.1} + {:.1}) | {:.1}x | {:.0} | {:.0} | {:.2}x | {:.1} |",
            scene.name,
            scene.triangle_count(),
            vr,
            vz,
            median(&mut t_cull),
            rz,
            rv,
            vr / vz,
            fr,
            fz,
            fr / fz,
            scene.triangle_count() as f64 / rz / 1e3,
        ));
        for (name, s) in [("rays", s_rays.unwrap()), ("raster", s_raster.unwrap())] {
            ray_rows.push(format!(
                "| {} | {name} | {} | {} | {} | {} |",
                scene.name,
                s.primary,
                s.shadow,
                s.specular,
                s.total()
            ));
        }
    }
    table(
        "| scene | triangles | visibility ms, rays | visibility ms, raster (cull + raster + resolve) | speed-up | frame ms, rays | frame ms, raster | frame speed-up | rasterizer M tris/s |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        &vis_rows,
    );
    table(
        "| scene | triangles submitted | set up | of which tiny (<= 2x2 px) | bin entries | raster ns per submitted triangle and core | resolve ns per pixel and core |",
        "|---|---:|---:|---:|---:|---:|---:|",
        &work_rows,
    );
    table(
        "| scene | densest mesh | triangles | pixels seeing it | rays over its pixels, ms | rasterizing its triangles, ms | speed-up there | rays over the other pixels, ms |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
        &dense_rows,
    );
    table(
        "| scene | dense meshes (>= 1 triangle per pixel seeing them) | their triangles | pixels seeing them | rays over the whole scene, ms | raster pass without them, ms | speed-up ceiling |",
        "|---|---|---:|---:|---:|---:|---:|",
        &ceiling_rows,
    );
    table(
        "| scene | visibility | primary | shadow | specular | total |",
        "|---|---|---:|---:|---:|---:|",
        &ray_rows,
    );
}

/// A Markdown table: `header` and `separator` lines, then `rows`, after a blank line.
fn table(header: &str, separator: &str, rows: &[String]) {
    println!("\n{header}\n{separator}");
    for r in rows {
        println!("{r}");
    }
}

/// One visibility pass of `r`: its wall time in ms, and its stats. The G-buffer is handed back,
/// as frames do, so no pass allocates one.
fn timed_visibility(r: &Renderer) -> (f64, hyrt::render::FrameStats) {
    let t = Instant::now();
    let (g, stats) = r.visibility();
    let ms = t.elapsed().as_secs_f64() * 1e3;
    r.recycle_gbuffer(g);
    (ms, stats)
}

/// Per mesh of `r`'s scene, the pixels of `gbuffer` (its visibility pass) that see it.
fn mesh_pixels(r: &Renderer, gbuffer: &[Option<hyrt_tracer::Hit>]) -> Vec<usize> {
    let meshes = &r.scene.meshes;
    // Mesh ranges are disjoint but need not cover every triangle, nor come in order.
    let mut mesh_of = vec![u32::MAX; r.scene.positions.len()];
    for (i, m) in meshes.iter().enumerate() {
        mesh_of[m.first as usize..][..m.count as usize].fill(i as u32);
    }
    let mut pixels = vec![0; meshes.len()];
    for hit in gbuffer.iter().flatten() {
        if let Some(&m) = mesh_of.get(hit.tri as usize).filter(|&&m| m != u32::MAX) {
            pixels[m as usize] += 1;
        }
    }
    pixels
}

/// The mesh with the most triangles per pixel that sees it (among meshes seen by at least 1 %
/// of the pixels of `gbuffer`, `r`'s visibility pass; `seen_by` of [`mesh_pixels`]), timed alone: primary rays over its pixels, the
/// rasterizer (transform to clip space, setup, depth test; the renderer's options) over its
/// triangles less an empty frame, and rays over the other pixels; alternated, medians of
/// `frames`. `None` if no mesh qualifies.
fn densest_mesh(
    r: &Renderer,
    gbuffer: &[Option<hyrt_tracer::Hit>],
    seen_by: &[usize],
    frames: usize,
) -> Option<String> {
    let scene = r.scene;
    let (w, h) = (scene.settings.width, scene.settings.height);
    let seen = |m: &hyrt::scene::MeshRange, id: u32| id >= m.first && id - m.first < m.count;
    let min_pixels = (w * h / 100) as usize;
    let (mesh, count) = scene
        .meshes
        .iter()
        .zip(seen_by.iter().copied())
        .filter(|&(_, n)| n >= min_pixels.max(1))
        .max_by(|a, b| (a.0.count as f64 / a.1 as f64).total_cmp(&(b.0.count as f64 / b.1 as f64)))?;
    let (mine, other): (Vec<u32>, Vec<u32>) =
        (0..w * h).partition(|&k| gbuffer[k as usize].is_some_and(|hit| seen(mesh, hit.tri)));

    // Rows of pixels in image order, as the rays pass traces them.
    let trace = |px: &[u32]| {
        let t = Instant::now();
        let hits: usize = px
            .par_chunks(w as usize)
            .map(|run| {
                let mut c = RayCounts::default();
                let ray = |k: u32| r.camera_ray(k % w, k / w);
                run.iter()
                    .filter(|&&k| r.tracer.closest_hit(&ray(k), RayKind::Primary, &mut c).is_some())
                    .count()
            })
            .sum();
        std::hint::black_box(hits);
        t.elapsed().as_secs_f64() * 1e3
    };
    let tris = &scene.positions[mesh.first as usize..][..mesh.count as usize];
    let xf = ClipTransform::new(&r.camera, r.raster_near);
    let opts = raster_options();
    let (mut rasterizer, mut target) = (Rasterizer::new(), Target::default());
    // As the pass does: transformed by the setup tasks.
    let mut raster = |tris: &[[glam::Vec3; 3]]| {
        let t = Instant::now();
        let source = MeshSource { tris, first_id: mesh.first, xf };
        rasterizer.rasterize_from(&source, w, h, &opts, &mut target);
        t.elapsed().as_secs_f64() * 1e3
    };
    let (mut t_mine, mut t_raster, mut t_other) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..=frames {
        let a = trace(&mine);
        // The mesh's own cost: minus a frame of no triangles (clearing the buffers, visiting
        // the tiles), which the whole pass pays once.
        let b = raster(tris) - raster(&[]);
        let c = trace(&other);
        if i > 0 {
            t_mine.push(a);
            t_raster.push(b);
            t_other.push(c);
        }
    }
    let (a, b) = (median(&mut t_mine), median(&mut t_raster));
    Some(format!(
        "| {} | {} | {} | {count} | {a:.2} | {b:.2} | {:.1}x | {:.2} |",
        scene.name,
        mesh.name,
        mesh.count,
        a / b,
        median(&mut t_other)
    ))
}

/// Consecutive triangles with consecutive ids from `first_id`, transformed on demand.
struct MeshSource<'a> {
    tris: &'a [[glam::Vec3; 3]],
    first_id: u32,
    xf: ClipTransform,
}

impl TriangleSource for MeshSource<'_> {
    fn len(&self) -> usize {
        self.tris.len()
    }

    fn fill(&self, first: usize, tris: &mut [[glam::Vec4; 3]], ids: &mut [u32]) {
        self.xf.0.apply_triangles(&self.tris[first..first + tris.len()], tris);
        for (k, id) in ids.iter_mut().enumerate() {
            *id = self.first_id + (first + k) as u32;
        }
    }
}

/// The ceiling of the raster pass's speed-up over `rays` (a renderer with ray visibility): the
/// pass on a copy of the scene whose dense meshes (seen by at least one pixel, with at least as
/// many triangles as pixels seeing them; `seen_by` of [`mesh_pixels`]) have every vertex moved
/// behind the camera, so that the cluster culling drops them, timed against rays over the whole
/// scene; alternated, each raster pass after a ray pass as in the main table, medians of
/// `frames`. Their pixels are still resolved, on what lies behind them: larger triangles, which
/// the resolve handles faster (one triangle for 16 pixels instead of a gather), so the ceiling
/// errs high. `None` if the scene has no dense mesh.
fn ceiling(rays: &Renderer, seen_by: &[usize], frames: usize) -> Option<String> {
    let scene = rays.scene;
    let dense: Vec<_> = scene
        .meshes
        .iter()
        .zip(seen_by.iter().copied())
        .filter(|&(m, n)| n > 0 && m.count as usize >= n)
        .collect();
    if dense.is_empty() {
        return None;
    }
    let mut without = scene.clone();
    let behind = rays.camera.eye - rays.camera.forward;
    for (m, _) in &dense {
        without.positions[m.first as usize..][..m.count as usize].fill([behind; 3]);
    }
    let raster = Renderer::new(&without, Options { visibility: Visibility::Raster, ..Options::default() });
    let (mut t_rays, mut t_raster) = (Vec::new(), Vec::new());
    for i in 0..=frames {
        let (a, _) = timed_visibility(rays);
        let (b, _) = timed_visibility(&raster);
        if i > 0 {
            t_rays.push(a);
            t_raster.push(b);
        }
    }
    // The names of the three largest, and how many more.
    let mut by_size = dense.clone();
    by_size.sort_by_key(|(m, _)| std::cmp::Reverse(m.count));
    let mut names: Vec<String> = by_size.iter().take(3).map(|(m, _)| m.name.clone()).collect();
    if dense.len() > 3 {
        names.push(format!("{} more", dense.len() - 3));
    }
    let (a, b) = (median(&mut t_rays), median(&mut t_raster));
    Some(format!(
        "| {} | {} | {} | {} | {a:.1} | {b:.2} | {:.1}x |",
        scene.name,
        names.join(", "),
        dense.iter().map(|(m, _)| m.count as usize).sum::<usize>(),
        dense.iter().map(|&(_, n)| n).sum::<usize>(),
        a / b
    ))
}
