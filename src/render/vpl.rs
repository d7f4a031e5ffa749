//! Virtual point lights (instant radiosity, Keller 1997): paths traced from the point lights
//! leave a VPL at every diffuse hit.
//!
//! # Power
//!
//! A point light of intensity `I` (W/sr per channel) emits `Phi = 4 pi I`. Its `n` paths start
//! in directions from a Halton sequence (bases 2 and 3, uniform on the sphere), each carrying
//! `Phi / n`. At a hit on a surface with diffuse reflectance `Kd` the path leaves a VPL with the
//! reflected flux `Phi_path Kd`; it continues (up to `bounces` VPLs) in a cosine-distributed
//! direction (the next two Halton bases), carrying `Phi_path Kd` (the cosine of the BRDF and the
//! pdf `cos / pi` cancel). Mirrors (`Kd = 0`, `Ks > 0`) reflect the path, weighted by `Ks`, and
//! leave no VPL; other surfaces (`Kd = Ks = 0`) end it.
//!
//! A VPL stands for a small Lambertian patch of flux `Phi_v`: its radiance is `Phi_v / (pi A)`,
//! so it lights a point `x` at distance `d` with irradiance
//! `E = Phi_v / pi * cos_v * cos_x / d^2`. [`Vpl::intensity`] is `Phi_v / pi`, and the outgoing
//! radiance at a diffuse `x` is `Kd / pi * intensity * cos_x * cos_v / max(d^2, d_min^2)`, the
//! clamp `d_min` bounding the `1/d^2` spike near a VPL (a bias, measured).
//!
//! # Determinism
//!
//! Path `k` of light `l` uses Halton index `seed * n_l + k` (plus one dimension pair per
//! bounce): no shared random stream, so the VPLs do not depend on threads or on the order in
//! which paths are traced.

use glam::Vec3;
use hyrt_tracer::{RayCounts, RayKind, offset::offset_ray_origin, spawn_ray};
use rayon::prelude::*;

use super::SurfaceHit;
use crate::scene::{PointLight, Scene};

/// One virtual point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    /// Position, pushed off its surface by the hit point's error bound (on the side the light
    /// came from), so rays and maps from it do not start inside the surface.
    pub position: Vec3,
    /// Unit normal of the emitting side.
    pub normal: Vec3,
    /// `Phi_v / pi` per RGB channel: the radiant intensity along the normal (module docs).
    pub intensity: Vec3,
    /// Triangle the VPL lies on.
    pub tri: u32,
    /// The point light whose path left it.
    pub light: u32,
}

pub use crate::options::VplOptions;

/// Radical inverse of `i` in base `b` (the Halton sequence's coordinate).
fn radical_inverse(mut i: u64, b: u64) -> f32 {
    let (mut inv, mut f) = (0.0f64, 1.0 / b as f64);
    while i > 0 {
        inv += (i % b) as f64 * f;
        i /= b;
        f /= b as f64;
    }
    inv.min(1.0 - f64::EPSILON) as f32
}

const PRIMES: [u64; 16] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53];

/// The Halton point of index `i` in dimensions `2 d` and `2 d + 1` (wrapping after 8 pairs).
fn halton2(i: u64, d: usize) -> (f32, f32) {
    let d = (2 * d) % PRIMES.len();
    (radical_inverse(i, PRIMES[d]), radical_inverse(i, PRIMES[d + 1]))
}

/// A unit direction, uniform on the sphere.
fn uniform_sphere((u, v): (f32, f32)) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A unit direction uniform over the cone of directions within `acos(cos_max)` of the unit
/// `axis` (solid angle `2 pi (1 - cos_max)`): `cos = 1 - u (1 - cos_max)`.
fn uniform_cone(axis: Vec3, cos_max: f32, (u, v): (f32, f32)) -> Vec3 {
    let z = 1.0 - u * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    let (b1, b2) = axis.any_orthonormal_pair();
    (b1 * (r * phi.cos()) + b2 * (r * phi.sin()) + axis * z).normalize()
}

/// The solid angle a light sends light into: the sphere's `4 pi`, or a spot's outer cone.
fn emitting_solid_angle(light: &PointLight) -> f32 {
    match light.spot {
        None => 4.0 * std::f32::consts::PI,
        Some(s) => std::f32::consts::TAU * (1.0 - s.cos_outer),
    }
}

/// A unit direction around `n`, cosine-distributed (Malley: a uniform disc point lifted).
fn cosine_hemisphere(n: Vec3, (u, v): (f32, f32)) -> Vec3 {
    let r = u.sqrt();
    let phi = std::f32::consts::TAU * v;
    let (b1, b2) = n.any_orthonormal_pair();
    let (x, y) = (r * phi.cos(), r * phi.sin());
    (b1 * x + b2 * y + n * (1.0 - u).max(0.0).sqrt()).normalize()
}

/// Paths per light, proportional to the lights' power (largest remainder, ties to the first
/// light), so that every path carries about the same flux.
fn paths_per_light(lights: &[PointLight], total: u32) -> Vec<u32> {
    // A spot light's power is bounded by its axis intensity over its outer cone.
    let power: Vec<f64> = lights
        .iter()
        .map(|l| {
            let p = f64::from(l.intensity.max_element().max(0.0));
            if l.spot.is_some() {
                p * f64::from(emitting_solid_angle(l)) / (4.0 * std::f64::consts::PI)
            } else {
                p
            }
        })
        .collect();
    let sum: f64 = power.iter().sum();
    if sum <= 0.0 || total == 0 {
        return vec![0; power.len()];
    }
    let exact: Vec<f64> = power.iter().map(|p| p / sum * f64::from(total)).collect();
    let mut n: Vec<u32> = exact.iter().map(|e| e.floor() as u32).collect();
    let mut left = total - n.iter().sum::<u32>();
    let mut order: Vec<usize> = (0..n.len()).collect();
    order.sort_by(|&a, &b| {
        (exact[b] - exact[b].floor()).total_cmp(&(exact[a] - exact[a].floor())).then(a.cmp(&b))
    });
    for &i in order.iter().cycle().take(n.len() * 2) {
        if left == 0 {
            break;
        }
        if power[i] > 0.0 {
            n[i] += 1;
            left -= 1;
        }
    }
    n
}

/// Traces the light paths of `opts` and returns their VPLs, in (light, path, bounce) order, with
/// the rays cast (counted as [`RayKind::VplPath`]). `lights` are the scene's, or moved ones
/// ([`crate::render::Renderer::set_light`]).
pub fn generate(
    scene: &Scene,
    lights: &[PointLight],
    tracer: &hyrt_tracer::Tracer,
    opts: &VplOptions,
) -> (Vec<Vpl>, RayCounts) {
    generate_from(scene, lights, tracer, opts, &vec![true; lights.len()])
}

/// The VPLs of [`generate`] that come from the lights `from[l]` selects, in the same order and
/// with the same values: a path depends on its own light only (and on the powers of all the
/// lights, which share the paths out), so the VPLs of one moved light can be traced again
/// alone and put back among the others'.
pub fn generate_from(
    scene: &Scene,
    lights: &[PointLight],
    tracer: &hyrt_tracer::Tracer,
    opts: &VplOptions,
    from: &[bool],
) -> (Vec<Vpl>, RayCounts) {
    let per_light = paths_per_light(lights, opts.paths);
    let jobs: Vec<(usize, u32)> = per_light
        .iter()
        .enumerate()
        .filter(|(l, _)| from.get(*l).copied().unwrap_or(false))
        .flat_map(|(l, &n)| (0..n).map(move |k| (l, k)))
        .collect();
    let traced: Vec<(Vec<Vpl>, RayCounts)> = jobs
        .par_iter()
        .map(|&(l, k)| {
            let light = &lights[l];
            let n = per_light[l];
            let index = u64::from(opts.seed) * u64::from(n) + u64::from(k);
            // A point light's paths leave uniformly over the sphere, a spot light's over its
            // outer cone, each carrying the intensity it sends that way times its share of the
            // solid angle.
            let (mut flux, dir) = match light.spot {
                None => (
                    light.intensity * (4.0 * std::f32::consts::PI / n as f32),
                    uniform_sphere(halton2(index, 0)),
                ),
                Some(s) => {
                    let d = uniform_cone(s.axis, s.cos_outer, halton2(index, 0));
                    (light.intensity_towards(d) * (emitting_solid_angle(light) / n as f32), d)
                }
            };
            let mut counts = RayCounts::default();
            let mut vpls = Vec::new();
            let mut ray = hyrt_tracer::Ray::new(light.position, dir, f32::INFINITY);
            let (mut dim, mut mirror_bounces) = (1, 0);
            while (vpls.len() as u32) < opts.bounces {
                let Some(h) = tracer.closest_hit(&ray, RayKind::VplPath, &mut counts) else { break };
                let s = SurfaceHit::new(scene, &h, ray.dir);
                let m = &scene.materials[scene.material[h.tri as usize] as usize];
                if m.diffuse != Vec3::ZERO {
                    flux *= s.albedo;
                    let position = offset_ray_origin(s.p, s.p_err, s.ng, s.ng);
                    vpls.push(Vpl {
                        position,
                        normal: s.ng,
                        intensity: flux / std::f32::consts::PI,
                        tri: h.tri,
                        light: l as u32,
                    });
                    let dir = cosine_hemisphere(s.ng, halton2(index, dim));
                    dim += 1;
                    ray = spawn_ray(s.p, s.p_err, s.ng, dir);
                } else if m.is_mirror() && mirror_bounces < scene.settings.max_depth {
                    mirror_bounces += 1;
                    flux *= m.mirror;
                    let d = ray.dir - 2.0 * ray.dir.dot(s.ng) * s.ng;
                    ray = spawn_ray(s.p, s.p_err, s.ng, d);
                } else {
                    break;
                }
            }
            (vpls, counts)
        })
        .collect();
    let mut counts = RayCounts::default();
    let mut vpls = Vec::new();
    for (v, c) in traced {
        vpls.extend(v);
        counts += c;
    }
    (vpls, counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_is_the_radical_inverse() {
        assert_eq!(radical_inverse(1, 2), 0.5);
        assert_eq!(radical_inverse(3, 2), 0.75);
        assert_eq!(radical_inverse(1, 3), 1.0 / 3.0);
        assert_eq!(radical_inverse(5, 3), 7.0 / 9.0);
    }

    /// Uniform on the sphere: the mean direction of many samples is near zero and every sample
    /// is a unit vector; cosine-distributed: the mean cosine is 2/3.
    #[test]
    fn direction_samplers_have_their_moments() {
        let n = 4096;
        let mut mean = Vec3::ZERO;
        let mut mean_cos = 0.0;
        let axis = Vec3::new(0.3, -0.5, 0.8).normalize();
        for i in 0..n {
            let d = uniform_sphere(halton2(i, 0));
            assert!((d.length() - 1.0).abs() < 1e-5);
            mean += d / n as f32;
            let c = cosine_hemisphere(axis, halton2(i, 1));
            assert!(c.dot(axis) >= 0.0);
            mean_cos += c.dot(axis) / n as f32;
        }
        assert!(mean.length() < 2e-3, "{mean}");
        assert!((mean_cos - 2.0 / 3.0).abs() < 2e-3, "{mean_cos}");
    }

    #[test]
    fn paths_follow_the_lights_power() {
        let mut s = Scene::new("t");
        for i in [1.0, 3.0, 0.0] {
            s.lights.push(crate::scene::PointLight {
                position: Vec3::ZERO,
                intensity: Vec3::splat(i),
                spot: None,
            });
        }
        assert_eq!(paths_per_light(&s.lights, 45), [11, 34, 0]);
        assert_eq!(paths_per_light(&s.lights, 1), [0, 1, 0]);
        assert_eq!(paths_per_light(&s.lights, 0), [0, 0, 0]);
    }
}
