//! Whitted mirror reflection: paths of perfect reflections from camera hits.

use glam::Vec3;
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray};

use rayon::prelude::*;

use super::{Progress, Renderer, SurfaceHit, direct, indirect::Vpls, shadows::Shadowing};

/// Adds the mirror-reflected light of every camera hit on a specular material (to `out`, zero
/// where nothing is reflected); the surfaces the mirror paths meet decide shadows with
/// `shadowing`'s maps when given (see `direct::shade_point`), first extended with the pages
/// those hits read (`Shadowing::draw_mirror_pages`).
///
/// The paths advance together, one bounce at a time (a wavefront): all reflection rays of a
/// bounce are traced, then their hits are put in spatial order (a Morton code of the hit
/// point). Once every bounce is traced, the maps get the pages all the hits read (so that a
/// frame shades with the maps the next frame of the view reuses, and renders the same image),
/// and the hits are shaded, bounce by bounce. Mirror hits are scattered over the scene, and shading one looks up every
/// light's map (and every VPL's) at its position and casts shadow rays from it: in pixel order
/// those lookups jump across maps of up to a gigabyte, in spatial order neighbouring hits read
/// neighbouring texels and traverse the same BVH nodes. Each path is still its own pixel's sum,
/// accumulated in the same order as `reflected` does it: the image is bit-identical.
pub fn run(
    r: &Renderer,
    gbuffer: &[Option<Hit>],
    mut shadowing: Option<&mut Shadowing>,
    vpls: Option<&Vpls>,
    out: &mut [Vec3],
    progress: Progress,
) -> RayCounts {
    let (w, h) = (r.scene.settings.width as usize, r.scene.settings.height as usize);
    // Under interleaved VPL sampling, a pixel's mirror path sees its pixel's VPL subset.
    let k = r.options.indirect_opts.interleave as usize;
    let kr_of = |tri: u32| r.scene.materials[r.scene.material[tri as usize] as usize].mirror;
    // Only hits on mirror materials start a path: skip the others before building their
    // shading point.
    let paths: Vec<Path> = gbuffer
        .par_chunks(w.max(1))
        .enumerate()
        .flat_map_iter(|(y, row)| {
            row.iter().enumerate().filter_map(move |(x, hit)| {
                let hit = hit.as_ref().filter(|h| kr_of(h.tri) != Vec3::ZERO)?;
                let dir = r.camera_ray(x as u32, y as u32).dir;
                let hit = SurfaceHit::new(r.scene, hit, dir);
                Some(Path { pixel: (y * w + x) as u32, hit, dist: hit.t, weight: Vec3::ONE, key: 0 })
            })
        })
        .collect();
    let (lo, hi) = r.bounds.unwrap_or_default();
    let depth = r.scene.settings.max_depth as usize;
    let mut total = RayCounts::default();
    // Every bounce traced first, its hits kept in spatial order; the paths that leave the
    // scene or reach a non-mirror end at their bounce.
    let mut bounces: Vec<Vec<Path>> = Vec::new();
    for _ in 0..depth {
        // Each bounce leaves from the last one's hits (the camera hits first).
        let from = bounces.last().unwrap_or(&paths);
        let traced: Vec<(Vec<Path>, RayCounts)> = from
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut c = RayCounts::default();
                let mut live = Vec::with_capacity(chunk.len());
                for p in chunk {
                    let mut p = *p;
                    let before = c;
                    let next = bounce(r, &p.hit, &mut p.weight, kr_of(p.hit.tri), &mut c);
                    r.pixel_rays.add(p.pixel as usize, &before, &c);
                    if let Some(hit) = next {
                        p.hit = hit;
                        p.dist += hit.t;
                        p.key = morton(hit.p, lo, hi);
                        live.push(p);
                    }
                }
                (live, c)
            })
            .collect();
        let mut live = Vec::with_capacity(from.len());
        for (paths, c) in traced {
            live.extend(paths);
            total += c;
        }
        // Spatial order; ties by pixel, so the order (and nothing else) is deterministic.
        // The keys are sorted, not the paths (a hundred bytes each), which then move once.
        let mut keys: Vec<(u64, u32, u32)> =
            live.par_iter().enumerate().map(|(i, p)| (p.key, p.pixel, i as u32)).collect();
        keys.par_sort_unstable();
        let next: Vec<Path> = keys.par_iter().map(|&(_, _, i)| live[i as usize]).collect();
        if next.is_empty() {
            break;
        }
        bounces.push(next);
    }
    // The light-map pages the hits read that no camera hit did (`mirror_hits`), all bounces'
    // at once: every hit is then shaded with the maps the next frame will have.
    if let Some(s) = shadowing.as_mut() {
        let hits: Vec<(&SurfaceHit, f32)> = bounces.iter().flatten().map(|p| (&p.hit, p.dist)).collect();
        s.draw_mirror_pages(r, &hits);
    }
    let shadowing = shadowing.as_deref();
    // Shade the hits, bounce by bounce; each pixel's sum in bounce order.
    let mut rows_reported = 0;
    for (d, hits) in bounces.iter().enumerate() {
        let shaded: Vec<(Vec<Terms>, RayCounts)> = hits
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut c = RayCounts::default();
                // Indirect light at the chunk's hits together: VPL by VPL, with the vector
                // kernel (the same values as one hit at a time).
                let batched = vpls.filter(|v| v.batched(r)).map(|v| {
                    let hits: Vec<SurfaceHit> = chunk.iter().map(|p| p.hit).collect();
                    let subsets: Vec<usize> =
                        chunk.iter().map(|p| Vpls::subset_of(p.pixel as usize, w, k).0).collect();
                    v.at_subsets(r, &hits, &subsets, k * k)
                });
                let terms = chunk
                    .iter()
                    .enumerate()
                    .map(|(n, p)| {
                        let before = c;
                        let direct = p.weight * direct::shade_point(r, &p.hit, p.dist, shadowing, &mut c);
                        let indirect = if let Some(ind) = &batched {
                            Some(p.weight * ind[n])
                        } else {
                            vpls.map(|v| {
                                let (subset, stride) = Vpls::subset_of(p.pixel as usize, w, k);
                                p.weight * v.at_subset(r, &p.hit, subset, stride, &mut c)
                            })
                        };
                        r.pixel_rays.add(p.pixel as usize, &before, &c);
                        (direct, indirect)
                    })
                    .collect();
                (terms, c)
            })
            .collect();
        // Added as `reflected` adds them: the direct term, then the indirect one.
        for (chunk, (terms, c)) in hits.chunks(CHUNK).zip(shaded) {
            for (p, (direct, indirect)) in chunk.iter().zip(terms) {
                let o = &mut out[p.pixel as usize];
                *o += direct;
                if let Some(i) = indirect {
                    *o += i;
                }
            }
            total += c;
        }
        // Progress: the pass's rows, spread over the bounces.
        let rows = h * (d + 1) / bounces.len();
        for _ in rows_reported..rows {
            progress();
        }
        rows_reported = rows;
    }
    for _ in rows_reported..h {
        progress();
    }
    total
}

/// Paths per parallel task: small enough that the two halves of a bounce (whose paths, in
/// spatial order, cost unevenly) balance on a few threads.
const CHUNK: usize = 64;

/// A mirror hit's weighted direct light, and its weighted indirect light (with VPLs).
type Terms = (Vec3, Option<Vec3>);

/// A mirror path in flight: its pixel, the surface it last met and the path's length to it
/// from the eye, and the product of `Kr` so far; `key` orders the paths spatially.
#[derive(Clone, Copy)]
struct Path {
    pixel: u32,
    hit: SurfaceHit,
    dist: f32,
    weight: Vec3,
    key: u64,
}

/// One mirror bounce from `hit` (reflectance `kr`): the next surface, with `weight` multiplied
/// by `kr`; `None` when `hit` is no mirror or the reflection leaves the scene.
fn bounce(
    r: &Renderer,
    hit: &SurfaceHit,
    weight: &mut Vec3,
    kr: Vec3,
    counts: &mut RayCounts,
) -> Option<SurfaceHit> {
    if kr == Vec3::ZERO {
        return None;
    }
    *weight *= kr;
    // Reflect about the shading normal; fall back to the geometric one if that would send the
    // ray into the surface.
    let mut dir = reflect(-hit.wo, hit.ns);
    if dir.dot(hit.ng) <= 0.0 {
        dir = reflect(-hit.wo, hit.ng);
    }
    let ray = spawn_ray(hit.p, hit.p_err, hit.ng, dir);
    let h = r.tracer.closest_hit(&ray, RayKind::Specular, counts)?;
    Some(SurfaceHit::new(r.scene, &h, ray.dir))
}

/// A 63-bit Morton code of `p` in the box `[lo, hi]` (21 bits per axis): points close in space
/// get close codes.
fn morton(p: Vec3, lo: Vec3, hi: Vec3) -> u64 {
    let ext = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let q = ((p - lo) / ext).clamp(Vec3::ZERO, Vec3::ONE) * ((1u32 << 21) - 1) as f32;
    // Spreads the 21 bits of `v` to every third bit.
    let spread = |v: f32| {
        let mut x = v as u64 & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    spread(q.x) | spread(q.y) << 1 | spread(q.z) << 2
}

/// Light arriving at `hit` by mirror reflection, followed for up to `max_depth` bounces, one
/// pixel's path on its own: what [`run`] computes for all of them at once (the test below holds
/// the two to the same bits);
/// each reflection is weighted by the product of `Kr` so far, and each surface it meets is
/// shaded with direct light, indirect light from the VPLs when given (the subset and stride of
/// interleaved sampling, `(0, 1)` for all), and its own reflection, while depth remains.
#[cfg(test)]
fn reflected(
    r: &Renderer,
    first: &SurfaceHit,
    shadowing: Option<&Shadowing>,
    vpls: Option<(&Vpls, (usize, usize))>,
    counts: &mut RayCounts,
) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let mut weight = Vec3::ONE;
    let mut hit = *first;
    let mut dist = first.t;
    for _ in 0..r.scene.settings.max_depth {
        let kr = r.scene.materials[r.scene.material[hit.tri as usize] as usize].mirror;
        if kr == Vec3::ZERO {
            break;
        }
        weight *= kr;
        // Reflect about the shading normal; fall back to the geometric one if that would send
        // the ray into the surface.
        let mut dir = reflect(-hit.wo, hit.ns);
        if dir.dot(hit.ng) <= 0.0 {
            dir = reflect(-hit.wo, hit.ng);
        }
        let ray = spawn_ray(hit.p, hit.p_err, hit.ng, dir);
        let Some(h) = r.tracer.closest_hit(&ray, RayKind::Specular, counts) else {
            break;
        };
        hit = SurfaceHit::new(r.scene, &h, ray.dir);
        dist += hit.t;
        sum += weight * direct::shade_point(r, &hit, dist, shadowing, counts);
        if let Some((v, (subset, stride))) = vpls {
            sum += weight * v.at_subset(r, &hit, subset, stride, counts);
        }
    }
    sum
}

fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Indirect, Options};

    /// The wavefront gives every pixel exactly the light of its own path traced alone, with
    /// the same rays: maps with SMeRTS at mirror hits, VPL maps with interleaving, and rays.
    #[test]
    fn wavefront_equals_per_pixel_paths() {
        let mut s =
            crate::scene::load(&format!("{}/scenes/cornell-bunny-mirror.toml", env!("CARGO_MANIFEST_DIR")))
                .expect("thesis scene");
        s.settings.width = 80;
        s.settings.height = 60;
        let mut hybrid = Options::hybrid();
        hybrid.shadow.map.resolution = 256;
        hybrid.indirect = Indirect::Maps;
        hybrid.indirect_opts.vpl.paths = 8;
        hybrid.indirect_opts.map.resolution = 128;
        hybrid.indirect_opts.interleave = 2;
        let mut rays = Options::reference();
        rays.indirect = Indirect::Rays;
        rays.indirect_opts.vpl.paths = 8;
        for o in [hybrid, rays] {
            let r = Renderer::new(&s, o);
            let (g, _) = r.visibility();
            let mut sh = (o.shadows != crate::render::Shadows::Rays).then(|| {
                let mut direct = vec![Vec3::ZERO; g.len()];
                r.test_shadowing(&g, &mut direct, None, true)
            });
            let v = r.test_vpls();
            let mut out = vec![Vec3::ZERO; g.len()];
            let c = run(&r, &g, sh.as_mut(), Some(&v), &mut out, &|| {});
            let (w, k) = (80, o.indirect_opts.interleave as usize);
            let mut c2 = RayCounts::default();
            let mut mirrors = 0;
            for (i, hit) in g.iter().enumerate() {
                let Some(hit) = hit else { continue };
                if !r.scene.materials[r.scene.material[hit.tri as usize] as usize].is_mirror() {
                    assert_eq!(out[i], Vec3::ZERO);
                    continue;
                }
                mirrors += 1;
                let first = SurfaceHit::new(r.scene, hit, r.camera_ray((i % w) as u32, (i / w) as u32).dir);
                let alone = reflected(&r, &first, sh.as_ref(), Some((&v, Vpls::subset_of(i, w, k))), &mut c2);
                assert_eq!(
                    out[i].to_array().map(f32::to_bits),
                    alone.to_array().map(f32::to_bits),
                    "pixel {i}"
                );
            }
            assert!(mirrors > 100, "{mirrors}");
            assert_eq!(c, c2);
        }
    }
}
