//! A tile's shading points seen from one light, a lane per point: the distance, direction and
//! cosines that every (point, light) pair of the classify pass needs, as arrays the compiler
//! turns into vector instructions.
//!
//! Why: per pair this is a square root, four divisions and three dot products, the same for
//! every point; computed inside the loop over a tile's points, it ran one pair at a time. The
//! arithmetic is [`light_geometry_and_terms`](crate::render::light::light_geometry_and_terms)'s,
//! operation for operation (IEEE division and square root are exact in every lane, and Rust
//! never fuses a multiply and an add), so its results are the same bits.

use glam::Vec3;
use hyrt_simd::{Isa, Tier};

use crate::render::SurfaceHit;
use crate::render::light::{is_dark, lights_along};
use crate::scene::PointLight;

/// The most points of a tile.
pub(super) const LANES: usize = 64;

/// A tile's points, a lane each: positions, geometric and shading normals.
pub(super) struct TileLanes {
    n: usize,
    p: [[f32; LANES]; 3],
    ng: [[f32; LANES]; 3],
    ns: [[f32; LANES]; 3],
}

/// One light seen from each point of a [`TileLanes`].
pub(super) struct FromLight {
    /// Squared distance and distance to the light.
    pub d2: [f32; LANES],
    pub r: [f32; LANES],
    /// `|ng . (L - p)| / r`: the cosine the map level needs ([`LightTerms`](hyrt_shadowmap::paged::LightTerms)).
    pub cos_light: [f32; LANES],
    /// The unit direction to the light, and its cosine with the shading normal.
    pub wi: [[f32; LANES]; 3],
    pub cos: [f32; LANES],
}

impl TileLanes {
    pub(super) fn new() -> Self {
        Self { n: 0, p: [[0.0; LANES]; 3], ng: [[0.0; LANES]; 3], ns: [[0.0; LANES]; 3] }
    }

    pub(super) fn clear(&mut self) {
        self.n = 0;
    }

    /// Adds a point (at most [`LANES`]).
    pub(super) fn push(&mut self, s: &SurfaceHit) {
        let k = self.n;
        for (a, v) in [(&mut self.p, s.p), (&mut self.ng, s.ng), (&mut self.ns, s.ns)] {
            a[0][k] = v.x;
            a[1][k] = v.y;
            a[2][k] = v.z;
        }
        self.n += 1;
    }

    /// The points seen from `light`, into `out` (its first `n` lanes), with the widest
    /// instructions the CPU runs ([`Isa::best`]).
    pub(super) fn seen_from(&self, light: Vec3, out: &mut FromLight) {
        self.seen_from_on(Isa::best(), light, out);
    }

    /// [`TileLanes::seen_from`] compiled for tier `isa` (the same bits on every tier).
    pub(super) fn seen_from_on(&self, isa: Isa, light: Vec3, out: &mut FromLight) {
        #[cfg(target_arch = "x86_64")]
        match isa.tier() {
            // SAFETY: an `Isa` of a tier exists only where the CPU runs its instructions.
            Tier::Avx512 => return unsafe { self.seen_from_avx512(light, out) },
            // SAFETY: as above.
            Tier::Avx2 => return unsafe { self.seen_from_avx2(light, out) },
            Tier::Scalar => {}
        }
        let _ = isa;
        self.lanes_from(light, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,f16c")]
    fn seen_from_avx2(&self, light: Vec3, out: &mut FromLight) {
        self.lanes_from(light, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,f16c,avx512f,avx512dq,avx512vl")]
    fn seen_from_avx512(&self, light: Vec3, out: &mut FromLight) {
        self.lanes_from(light, out);
    }

    /// The loop of [`TileLanes::seen_from`], inlined into each tier's function so that the
    /// compiler vectorises it at that tier's width.
    #[inline(always)]
    fn lanes_from(&self, light: Vec3, out: &mut FromLight) {
        let n = self.n;
        let [px, py, pz] = &self.p;
        let [gx, gy, gz] = &self.ng;
        let [sx, sy, sz] = &self.ns;
        let [wx, wy, wz] = &mut out.wi;
        for k in 0..n.min(LANES) {
            // `light - p`, its squared length and length, as glam's `Vec3` computes them.
            let (tx, ty, tz) = (light.x - px[k], light.y - py[k], light.z - pz[k]);
            let d2 = tx * tx + ty * ty + tz * tz;
            let r = d2.sqrt();
            out.d2[k] = d2;
            out.r[k] = r;
            out.cos_light[k] = (gx[k] * tx + gy[k] * ty + gz[k] * tz).abs() / r;
            let (ux, uy, uz) = (tx / r, ty / r, tz / r);
            (wx[k], wy[k], wz[k]) = (ux, uy, uz);
            out.cos[k] = sx[k] * ux + sy[k] * uy + sz[k] * uz;
        }
    }
}

impl FromLight {
    pub(super) fn new() -> Self {
        Self {
            d2: [0.0; LANES],
            r: [0.0; LANES],
            cos_light: [0.0; LANES],
            wi: [[0.0; LANES]; 3],
            cos: [0.0; LANES],
        }
    }

    /// The first `n` lanes (at most [`LANES`]) that `light`, as seen from them by
    /// [`TileLanes::seen_from`], shines on: where `light_geometry_and_terms` gives its geometry
    /// (not dark, not at the point, [`lights_along`]), a bit each (bit `k` for lane `k`).
    pub(super) fn shone_on(&self, light: &PointLight, n: usize) -> u64 {
        let n = n.min(LANES);
        let mut bits = 0u64;
        if is_dark(light) {
            return bits;
        }
        if light.spot.is_none() {
            // `lights_along` without a cone: the shading normal's cosine alone, a compare per
            // lane the compiler vectorises.
            for k in 0..n {
                bits |= u64::from((self.d2[k] != 0.0) & (self.cos[k] > 0.0)) << k;
            }
        } else {
            for k in 0..n {
                let g =
                    self.d2[k] != 0.0 && lights_along(light, self.wi(k), self.cos[k], self.d2[k]).is_some();
                bits |= u64::from(g) << k;
            }
        }
        bits
    }

    /// Lane `k`'s direction to the light.
    #[inline]
    pub(super) fn wi(&self, k: usize) -> Vec3 {
        Vec3::new(self.wi[0][k], self.wi[1][k], self.wi[2][k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::light_geometry_and_terms;
    use crate::scene::PointLight;
    use hyrt_testkit::Rng;

    /// Every tier's lanes hold the bits of `light_geometry_and_terms` for every point, near
    /// the origin and far from it, with lights near and far (and one at a point itself).
    #[test]
    fn lanes_are_light_geometry_bit_for_bit() {
        let mut rng = Rng(0x5851_f42d_4c95_7f2d);
        let mut v = |scale: f32| Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * scale;
        for (centre, scale) in [(Vec3::ZERO, 1.0), (Vec3::new(3e4, -2e3, 1e4), 50.0)] {
            let points: Vec<SurfaceHit> = (0..LANES - 3)
                .map(|_| SurfaceHit {
                    tri: 0,
                    t: 1.0,
                    p: centre + v(scale),
                    p_err: Vec3::ZERO,
                    ng: v(1.0).normalize(),
                    ns: v(1.0).normalize(),
                    wo: Vec3::Y,
                    albedo: Vec3::ONE,
                    highlight: Vec3::ZERO,
                })
                .collect();
            let mut lanes = TileLanes::new();
            points.iter().for_each(|s| lanes.push(s));
            let lights = [centre + v(scale), centre + v(1e3 * scale), points[7].p];
            for isa in Isa::for_tests("TileLanes::seen_from") {
                for &position in &lights {
                    let light = PointLight { position, intensity: Vec3::ONE, spot: None };
                    let mut from = FromLight::new();
                    lanes.seen_from_on(isa, position, &mut from);
                    for (k, s) in points.iter().enumerate() {
                        let (g, t) = light_geometry_and_terms(s, &light);
                        let bits = |x: f32| x.to_bits();
                        assert_eq!(
                            (bits(from.r[k]), bits(from.cos_light[k])),
                            (bits(t.r), bits(t.cos_light))
                        );
                        if let Some((wi, cos, d2)) = g {
                            assert_eq!(from.wi(k).to_array().map(bits), wi.to_array().map(bits), "{isa:?}");
                            assert_eq!((bits(from.cos[k]), bits(from.d2[k])), (bits(cos), bits(d2)));
                        } else {
                            assert!(from.d2[k] == 0.0 || from.cos[k] <= 0.0 || from.cos[k].is_nan());
                        }
                    }
                }
            }
        }
    }
}
