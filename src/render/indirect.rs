//! Diffuse indirect light from virtual point lights, with visibility by shadow rays
//! (`Indirect::Rays`, the reference) or by one paraboloid depth map per VPL (`Indirect::Maps`,
//! the thesis's hybrid: lookups only, no selective rays).
//!
//! The VPLs (see [`super::vpl`]) and their maps depend only on the scene: they are made on the
//! first frame and kept.

use std::f32::consts::FRAC_1_PI;
use std::sync::OnceLock;
use std::time::Instant;

use glam::{Vec3, Vec4};
use hyrt_shadowmap::{
    LightMap, MapOptions,
    classify::{Classifier, triangle_planes},
};
use hyrt_tracer::{Hit, RayCounts, RayKind, spawn_ray_to};
use rayon::prelude::*;

use super::{FrameStats, Indirect, Progress, Renderer, SurfaceHit, ms, shade_hits, vpl};

/// The knobs of indirect light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndirectOptions {
    pub vpl: vpl::VplOptions,
    /// `d_min` of the `1 / max(d^2, d_min^2)` clamp, as a fraction of the scene's bounding-box
    /// diagonal (so the same value suits scenes in millimetres and in metres).
    pub clamp: f32,
    /// The VPL maps (one paraboloid hemisphere each; `kind` is ignored).
    pub map: MapOptions,
    /// Depth margin of map lookups, in texel footprints (as for the light maps).
    pub bias: f32,
}

/// Defaults measured on the thesis scenes with 45 VPLs (maps against rays, full image): at
/// 256x256 per VPL 39.1 / 32.2 dB (Cornell box / office), at 1024x1024 with bias 0.5 about
/// 49 / 39.9 dB, at 2048 the office reaches 42.2 dB but its maps take 1.4 GB and 12 s.
impl Default for IndirectOptions {
    fn default() -> Self {
        Self {
            vpl: vpl::VplOptions::default(),
            clamp: 0.01,
            map: MapOptions { resolution: 1024, ..MapOptions::default() },
            bias: 0.5,
        }
    }
}

/// Per-renderer VPLs and VPL maps.
#[derive(Default)]
pub(crate) struct VplCache {
    vpls: OnceLock<(Vec<vpl::Vpl>, RayCounts)>,
    maps: OnceLock<Vec<LightMap>>,
    planes: OnceLock<Vec<Vec4>>,
}

/// What the indirect pass needs per frame.
pub struct Vpls<'r> {
    pub vpls: &'r [vpl::Vpl],
    /// One map per VPL with `Indirect::Maps`, else empty.
    pub maps: &'r [LightMap],
    planes: &'r [Vec4],
    /// `d_min^2` in scene units.
    clamp2: f32,
}

impl Renderer<'_> {
    /// The VPLs and, with `Indirect::Maps`, their maps; made on the first call (timed in
    /// `stats` as `vpl_gen` and `vpl_map_build`, with the path rays counted), then cached.
    pub(crate) fn vpls(&self, stats: &mut FrameStats) -> Vpls<'_> {
        let opts = &self.options.indirect_opts;
        let t = Instant::now();
        let mut fresh = false;
        let (vpls, _) = self.vpl_cache.vpls.get_or_init(|| {
            fresh = true;
            vpl::generate(self.scene, &self.tracer, &opts.vpl)
        });
        if fresh {
            stats.rays += self.vpl_cache.vpls.get().expect("just made").1;
        }
        stats.time_ms.insert("vpl_gen", ms(t));
        let t = Instant::now();
        let maps: &[LightMap] = if self.options.indirect == Indirect::Maps {
            self.vpl_cache.maps.get_or_init(|| {
                // One VPL map after another: each build is parallel inside.
                vpls.iter()
                    .map(|v| {
                        LightMap::build_hemisphere(&self.scene.positions, v.position, v.normal, &opts.map)
                    })
                    .collect()
            })
        } else {
            &[]
        };
        stats.time_ms.insert("vpl_map_build", ms(t));
        stats.vpls = vpls.len() as u32;
        stats.vpl_map_bytes = maps.iter().map(|m| m.memory_bytes() as u64).sum();
        let planes = self.vpl_cache.planes.get_or_init(|| triangle_planes(&self.scene.positions));
        let diag = self.scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length());
        let clamp = opts.clamp.max(0.0) * diag;
        Vpls { vpls, maps, planes, clamp2: clamp * clamp }
    }
}

impl Vpls<'_> {
    /// `cos_x cos_v / max(d^2, d_min^2)` between the diffuse point `s` and `v`, or `None` when
    /// either faces away.
    #[inline]
    fn geometry(&self, s: &SurfaceHit, v: &vpl::Vpl) -> Option<f32> {
        let to_vpl = v.position - s.p;
        let d2 = to_vpl.length_squared();
        if d2 == 0.0 {
            return None;
        }
        let wi = to_vpl / d2.sqrt();
        let (cos_x, cos_v) = (s.ns.dot(wi), -v.normal.dot(wi));
        if cos_x <= 0.0 || cos_v <= 0.0 || s.ng.dot(wi) <= 0.0 {
            return None;
        }
        Some(cos_x * cos_v / d2.max(self.clamp2))
    }

    /// Indirect radiance leaving the diffuse point `s` towards its viewer:
    /// `Kd / pi * sum_v I_v cos_x cos_v / max(d^2, d_min^2)` over the visible VPLs.
    pub fn at(&self, r: &Renderer, s: &SurfaceHit, counts: &mut RayCounts) -> Vec3 {
        let kd = r.scene.materials[r.scene.material[s.tri as usize] as usize].kd;
        if kd == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let mut sum = Vec3::ZERO;
        for (k, v) in self.vpls.iter().enumerate() {
            let Some(g) = self.geometry(s, v) else { continue };
            let visible = match self.maps.get(k) {
                // No rays to settle it: an occluder within the bias band is taken to be the
                // point's own curved surface (the commoner case), not a contact shadow.
                Some(map) => Classifier { map, planes: self.planes, bias: r.options.indirect_opts.bias }
                    .visible(s.p, s.tri),
                None => {
                    let ray = spawn_ray_to(s.p, s.p_err, s.ng, v.position);
                    !r.tracer.occluded(&ray, RayKind::VplShadow, counts)
                }
            };
            if visible {
                sum += v.intensity * g;
            }
        }
        kd * FRAC_1_PI * sum
    }
}

/// The indirect pass over the camera hits.
///
/// With maps, a band of rows at a time, VPL by VPL: the band's points are first located in the
/// VPL's map and their texels prefetched, then decided, so that the cache misses of a band (a
/// 1024^2 map is 4 MB of ids: nearly every lookup is a new cache line) overlap. Each pixel adds
/// its VPLs in VPL order, exactly as [`Vpls::at`] does, so the sums are the same bytes either
/// way and for any thread count.
pub fn run(
    r: &Renderer,
    v: &Vpls,
    gbuffer: &[Option<Hit>],
    out: &mut [Vec3],
    progress: Progress,
) -> RayCounts {
    if v.maps.is_empty() {
        return shade_hits(r, gbuffer, out, progress, |_, s, c| v.at(r, s, c));
    }
    let w = r.scene.settings.width.max(1) as usize;
    const BAND: usize = 4;
    let bias = r.options.indirect_opts.bias;
    out.par_chunks_mut(w * BAND).enumerate().for_each(|(b, out)| {
        let first = b * w * BAND;
        // The band's diffuse points: (pixel in band, shading point, Kd).
        let pts: Vec<(usize, SurfaceHit, Vec3)> = (first..first + out.len())
            .filter_map(|i| {
                let h = gbuffer[i].as_ref()?;
                let kd = r.scene.materials[r.scene.material[h.tri as usize] as usize].kd;
                let dir = r.camera_ray((i % w) as u32, (i / w) as u32).dir;
                (kd != Vec3::ZERO).then(|| (i - first, SurfaceHit::new(r.scene, h, dir), kd))
            })
            .collect();
        let mut sum = vec![Vec3::ZERO; pts.len()];
        let mut located = Vec::with_capacity(pts.len());
        for (vpl, map) in v.vpls.iter().zip(v.maps) {
            let cls = Classifier { map, planes: v.planes, bias };
            located.clear();
            for (k, (_, s, _)) in pts.iter().enumerate() {
                if let Some(g) = v.geometry(s, vpl) {
                    let c = cls.locate(s.p);
                    cls.prefetch(c);
                    located.push((k, g, c));
                }
            }
            for &(k, g, c) in &located {
                let s = &pts[k].1;
                if cls.visible_at(s.p, s.tri, c) {
                    sum[k] += vpl.intensity * g;
                }
            }
        }
        for ((i, _, kd), acc) in pts.iter().zip(sum) {
            out[*i] = *kd * FRAC_1_PI * acc;
        }
        for _ in 0..out.len() / w {
            progress();
        }
    });
    RayCounts::default()
}

/// Total flux of the VPLs per channel (for tests: `pi * sum of intensities`).
pub fn total_flux(vpls: &[vpl::Vpl]) -> Vec3 {
    vpls.par_iter().map(|v| v.intensity * std::f32::consts::PI).reduce(|| Vec3::ZERO, |a, b| a + b)
}
