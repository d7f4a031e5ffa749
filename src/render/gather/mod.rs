//! The VPL gather: per diffuse point, `sum_v I_v cos_x cos_v / max(d^2, d_min^2)` over the VPLs
//! that the VPLs' maps ([`VplMap`], planes or 16-bit depths) call visible.
//!
//! It is the inner loop of indirect light (points times VPLs), so it is laid out for it: the
//! points in struct-of-arrays order ([`Points`]), one VPL's constants broadcast
//! ([`VplConsts`]), and sixteen points at a time with AVX-512, or eight with AVX2 and F16C,
//! where the CPU has them ([`Isa`]). The scalar [`pair`] performs the same `f32` operations
//! in the same order (no fused multiply-adds, IEEE square roots and divisions, exact
//! half-float conversions), so all give the same bytes; the tests hold them to it.
//!
//! Per pair, with `w = (p - o) / r` the unit direction from the VPL at `o` to the point `p`:
//! `cos_x = -n_s . w`, `cos_g = -n_g . w` (the geometric normal: the point must face the VPL),
//! `cos_v = a . w` (`a` the VPL's normal, its map's axis); the map decides visibility along
//! `w` as [`VplMap`]'s module docs derive. `1 / max(d^2, d_min^2)` and the rounding band's
//! `1 / cos_g` share one division.

use glam::Vec3;
use hyrt_shadowmap::vpl_map::VplMap;
use hyrt_simd::{Isa, Tier};

use super::{SurfaceHit, vpl::Vpl};

/// Points per vector of the AVX2 kernel.
pub(crate) const LANES: usize = 8;

/// A diffuse shading point as the gather reads it (all zero where a pixel has none: zero
/// normals face nothing). The frame's direct-light pass writes one per pixel when VPL maps
/// will be gathered, so that the indirect pass does not make the shading points again.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ShadePoint {
    pub p: Vec3,
    pub ns: Vec3,
    pub ng: Vec3,
    /// The diffuse albedo there ([`SurfaceHit::albedo`]), which the gathered sum multiplies.
    pub albedo: Vec3,
}

impl ShadePoint {
    pub fn of(s: &SurfaceHit) -> Self {
        Self { p: s.p, ns: s.ns, ng: s.ng, albedo: s.albedo }
    }
}

/// Diffuse shading points in struct-of-arrays order (zero normals: a point that faces
/// nothing).
#[derive(Clone, Debug, Default)]
pub(crate) struct Points {
    pub p: [Vec<f32>; 3],
    pub ns: [Vec<f32>; 3],
    pub ng: [Vec<f32>; 3],
}

impl Points {
    /// Empty, with room for `n` points.
    pub fn with_capacity(n: usize) -> Self {
        let v = || [Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n)];
        Self { p: v(), ns: v(), ng: v() }
    }

    /// Replaces the points with `pts`, in order (a transpose).
    pub fn set(&mut self, pts: &[ShadePoint]) {
        let [px, py, pz] = &mut self.p;
        let [sx, sy, sz] = &mut self.ns;
        let [gx, gy, gz] = &mut self.ng;
        for v in [&mut *px, py, pz, sx, sy, sz, gx, gy, gz] {
            v.clear();
            v.resize(pts.len(), 0.0);
        }
        for (i, s) in pts.iter().enumerate() {
            (px[i], py[i], pz[i]) = (s.p.x, s.p.y, s.p.z);
            (sx[i], sy[i], sz[i]) = (s.ns.x, s.ns.y, s.ns.z);
            (gx[i], gy[i], gz[i]) = (s.ng.x, s.ng.y, s.ng.z);
        }
    }

    pub fn push(&mut self, s: &ShadePoint) {
        self.push_raw(s.p, s.ns, s.ng);
    }

    fn push_raw(&mut self, p: Vec3, ns: Vec3, ng: Vec3) {
        for i in 0..3 {
            self.p[i].push(p[i]);
            self.ns[i].push(ns[i]);
            self.ng[i].push(ng[i]);
        }
    }

    pub fn len(&self) -> usize {
        self.p[0].len()
    }

    fn get(&self, i: usize) -> (Vec3, Vec3, Vec3) {
        let v = |a: &[Vec<f32>; 3]| Vec3::new(a[0][i], a[1][i], a[2][i]);
        (v(&self.p), v(&self.ns), v(&self.ng))
    }
}

/// Per-point sums of `I_v g_v` (RGB, struct of arrays).
#[derive(Clone, Debug, Default)]
pub(crate) struct Sums(pub [Vec<f32>; 3]);

impl Sums {
    pub fn reset(&mut self, n: usize) {
        for c in &mut self.0 {
            c.clear();
            c.resize(n, 0.0);
        }
    }

    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.0[0][i], self.0[1][i], self.0[2][i])
    }
}

/// What a pair needs of its VPL and the knobs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct VplConsts {
    pub o: Vec3,
    pub t: Vec3,
    pub b: Vec3,
    pub a: Vec3,
    pub intensity: Vec3,
    /// `d_min^2`.
    pub clamp2: f32,
    /// `bias * 2 / res`: the margin's texel footprints per unit of `(1 + cos_v) r`.
    pub bias_k: f32,
    /// The stored value's relative rounding ([`VplFormat::tolerance`]).
    pub tol: f32,
    /// The rounding band's `e` (`sqrt 3` times the per-axis point error).
    pub e: f32,
    pub half: f32,
    pub last: f32,
    pub res: u32,
    /// `1 / scale` of 16-bit depths (1 for planes; [`VplMap::depths`]).
    pub inv_scale: f32,
}

impl VplConsts {
    pub fn new(v: &Vpl, map: &VplMap, clamp2: f32, bias: f32, point_error: f32) -> Self {
        let [t, b, a] = map.frame();
        let res = map.resolution();
        Self {
            o: map.origin(),
            t,
            b,
            a,
            intensity: v.intensity,
            clamp2,
            bias_k: bias * 2.0 / res as f32,
            tol: map.format().tolerance(),
            e: point_error * 3f32.sqrt(),
            half: res as f32 * 0.5,
            last: map.last(),
            res,
            inv_scale: map.depths().map_or(1.0, |(_, inv_scale)| inv_scale),
        }
    }
}

/// What is shared by every texel a pair may look at.
struct Ray {
    w: Vec3,
    r: f32,
    cos_g: f32,
    ng: Vec3,
    /// Continuous texel coordinates of `w`.
    fx: f32,
    fy: f32,
    margin: f32,
    g: f32,
}

/// The pair's geometry, or `None` when the point or the VPL faces away.
#[inline(always)]
fn ray(c: &VplConsts, p: Vec3, ns: Vec3, ng: Vec3) -> Option<Ray> {
    let (dx, dy, dz) = (p.x - c.o.x, p.y - c.o.y, p.z - c.o.z);
    let d2 = dx * dx + dy * dy + dz * dz;
    let r = d2.sqrt();
    let inv = 1.0 / r;
    let w = Vec3::new(dx * inv, dy * inv, dz * inv);
    let cos_x = -(ns.x * w.x + ns.y * w.y + ns.z * w.z);
    let cos_g = -(ng.x * w.x + ng.y * w.y + ng.z * w.z);
    let cos_v = c.a.x * w.x + c.a.y * w.y + c.a.z * w.z;
    if !(cos_x > 0.0 && cos_g > 0.0 && cos_v > 0.0) {
        return None;
    }
    let m2 = d2.max(c.clamp2);
    let q = 1.0 / (cos_g * m2);
    let g = cos_x * cos_v * cos_g * q;
    let den = 1.0 + cos_v;
    let iden = 1.0 / den;
    let u = (c.t.x * w.x + c.t.y * w.y + c.t.z * w.z) * iden;
    let v = (c.b.x * w.x + c.b.y * w.y + c.b.z * w.z) * iden;
    let margin = c.bias_k * den * r + c.tol * r + (c.e + c.e * m2 * q);
    Some(Ray { w, r, cos_g, ng, fx: (u + 1.0) * c.half, fy: (1.0 - v) * c.half, margin, g })
}

/// Whether texel `(x, y)` hides the pair's point ([`VplMap::hidden_at`]).
#[inline(always)]
fn hidden(map: &VplMap, ray: &Ray, x: u32, y: u32) -> bool {
    map.hidden_at(x, y, ray.w, ray.r, ray.ng, ray.cos_g, ray.margin)
}

/// `g_v` times the visibility of one VPL from one point (0 when it faces away or is hidden):
/// the texel under the point decides. The scalar kernel, the reference for [`add_vpl`].
#[inline]
pub(crate) fn pair(c: &VplConsts, map: &VplMap, p: Vec3, ns: Vec3, ng: Vec3) -> f32 {
    let Some(ray) = ray(c, p, ns, ng) else { return 0.0 };
    let x = ray.fx.max(0.0).min(c.last) as u32;
    let y = ray.fy.max(0.0).min(c.last) as u32;
    if hidden(map, &ray, x, y) { 0.0 } else { ray.g }
}

/// [`pair`] with percentage-closer filtering: the visibility is the sum of the bilinear weights
/// of the 2x2 texels whose centres surround the point's position that leave it visible (the
/// footprint shifted inside the map at its border). Scalar only: measured, it buys no accuracy
/// for its cost (`docs/sweeps/`), and is kept as a knob to show that.
pub(crate) fn pair_bilinear(c: &VplConsts, map: &VplMap, p: Vec3, ns: Vec3, ng: Vec3) -> f32 {
    let Some(ray) = ray(c, p, ns, ng) else { return 0.0 };
    let hi = c.res.saturating_sub(2) as f32;
    let fx = (ray.fx - 0.5).clamp(0.0, hi);
    let fy = (ray.fy - 0.5).clamp(0.0, hi);
    let (x0, y0) = (fx as u32, fy as u32);
    let (ax, ay) = (fx - x0 as f32, fy - y0 as f32);
    let mut visible = 0.0;
    for (dx, dy, wt) in
        [(0, 0, (1.0 - ax) * (1.0 - ay)), (1, 0, ax * (1.0 - ay)), (0, 1, (1.0 - ax) * ay), (1, 1, ax * ay)]
    {
        if !hidden(map, &ray, (x0 + dx).min(c.res - 1), (y0 + dy).min(c.res - 1)) {
            visible += wt;
        }
    }
    ray.g * visible
}

/// Adds VPL `c`'s `I_v g_v` (visible pairs only) to `sums` for every point of `pts`, with the
/// widest kernel the CPU runs ([`Isa::best`]).
pub(crate) fn add_vpl(c: &VplConsts, map: &VplMap, pts: &Points, sums: &mut Sums) {
    add_vpl_on(Isa::best(), c, map, pts, sums);
}

/// [`add_vpl`] with the kernel of tier `isa` (8 pairs per AVX2 vector, 16 per AVX-512 one; all
/// give the same bits): whole vectors with it, the rest one point at a time.
pub(crate) fn add_vpl_on(isa: Isa, c: &VplConsts, map: &VplMap, pts: &Points, sums: &mut Sums) {
    #[allow(unused_mut)]
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    {
        use hyrt_simd::lanes::{Avx2, Avx512, Lanes};
        // The texels: the planes' `f32`, or the half floats of 16-bit depths.
        let texels = match (map.planes(), map.depths()) {
            (Some(g), _) => Some((g.as_ptr().cast(), g.len() * 3, false)),
            (_, Some((bits, _))) => Some((bits.as_ptr().cast::<f32>(), bits.len(), true)),
            _ => None,
        };
        if let Some((texels, len, depth16)) = texels {
            type Kernel = unsafe fn(&VplConsts, *const f32, usize, &Points, usize, &mut Sums);
            let kernel: Option<(usize, Kernel)> = match (isa.tier(), depth16) {
                (Tier::Avx512, false) => Some((Avx512::N, vector::add_vpl_avx512::<false>)),
                (Tier::Avx512, true) => Some((Avx512::N, vector::add_vpl_avx512::<true>)),
                (Tier::Avx2, false) => Some((Avx2::N, vector::add_vpl_avx2::<false>)),
                (Tier::Avx2, true) => Some((Avx2::N, vector::add_vpl_avx2::<true>)),
                _ => None,
            };
            if let Some((n, kernel)) = kernel {
                done = pts.len() / n * n;
                // SAFETY: an `Isa` of a tier exists only where the CPU runs it; the kernels'
                // loads stay within the first `done` points of `pts` and `sums` (asserted there)
                // and their gathers within the map's texels (indices clamped to the resolution;
                // see each kernel).
                unsafe { kernel(c, texels, len, pts, done, sums) }
            }
        }
    }
    add_vpl_from(pair, c, map, pts, done, sums);
}

/// A kernel of one pair: [`pair`] or [`pair_bilinear`].
pub(crate) type PairFn = fn(&VplConsts, &VplMap, Vec3, Vec3, Vec3) -> f32;

/// [`add_vpl`] one point at a time, with kernel `f`.
pub(crate) fn add_vpl_with(f: PairFn, c: &VplConsts, map: &VplMap, pts: &Points, sums: &mut Sums) {
    add_vpl_from(f, c, map, pts, 0, sums);
}

/// [`add_vpl_with`] from point `first` on.
fn add_vpl_from(f: PairFn, c: &VplConsts, map: &VplMap, pts: &Points, first: usize, sums: &mut Sums) {
    for i in first..pts.len() {
        let (p, ns, ng) = pts.get(i);
        let g = f(c, map, p, ns, ng);
        for k in 0..3 {
            sums.0[k][i] += c.intensity[k] * g;
        }
    }
}

/// The AVX2 and AVX-512 kernels (their module docs).
#[cfg(target_arch = "x86_64")]
mod vector;

#[cfg(test)]
mod tests {
    use super::*;
    use hyrt_shadowmap::{MapOptions, classify::triangle_planes, vpl_map::VplFormat};

    const FORMATS: [VplFormat; 2] = [VplFormat::Planes, VplFormat::Depth16];

    /// A floor (`y = 0`, 4 units square) under a square lid (`y = 0.5`, half a unit square) and
    /// a VPL above both, facing down.
    fn scene(res: u32, format: VplFormat) -> (VplMap, VplConsts) {
        let quad = |y: f32, h: f32| {
            let (a, b, c, d) =
                (Vec3::new(-h, y, -h), Vec3::new(h, y, -h), Vec3::new(h, y, h), Vec3::new(-h, y, h));
            [[a, b, c], [a, c, d]]
        };
        let tris: Vec<[Vec3; 3]> = quad(0.0, 2.0).into_iter().chain(quad(0.5, 0.25)).collect();
        let planes = triangle_planes(&tris);
        let o = Vec3::new(0.0, 1.0, 0.0);
        let opts = MapOptions { resolution: res, ..MapOptions::default() };
        let map = VplMap::build(&tris, &planes, o, Vec3::NEG_Y, &opts, format);
        let v =
            Vpl { position: o, normal: Vec3::NEG_Y, intensity: Vec3::new(1.0, 2.0, 3.0), tri: 0, light: 0 };
        let c = VplConsts::new(&v, &map, 0.0, 0.5, 1e-7);
        (map, c)
    }

    /// Floor points in the lid's shadow (the square of half-width 0.5 under a lid of
    /// half-width 0.25 halfway up) are hidden, and the others lit, beyond a texel of the edge,
    /// with either format.
    #[test]
    fn the_lid_hides_what_it_covers() {
        for format in FORMATS {
            let (map, c) = scene(256, format);
            let (mut hidden, mut lit) = (0, 0);
            for i in 0..64 {
                for j in 0..64 {
                    let p = Vec3::new(
                        -1.5 + 3.0 * (i as f32 + 0.5) / 64.0,
                        0.0,
                        -1.5 + 3.0 * (j as f32 + 0.5) / 64.0,
                    );
                    let edge = p.x.abs().max(p.z.abs());
                    if (edge - 0.5).abs() < 0.03 {
                        continue;
                    }
                    let g = pair(&c, &map, p, Vec3::Y, Vec3::Y);
                    if edge < 0.5 {
                        assert_eq!(g, 0.0, "{format:?}: {p} is under the lid");
                        hidden += 1;
                    } else {
                        let d = Vec3::new(0.0, 1.0, 0.0) - p;
                        let want = (d.y / d.length()).powi(2) / d.length_squared();
                        assert!((g - want).abs() <= 1e-5 * want, "{format:?}: {p}: {g} vs {want}");
                        lit += 1;
                    }
                }
            }
            assert!(hidden > 200 && lit > 2000, "{hidden} {lit}");
        }
    }

    /// The vector kernel gives the scalar kernel's bytes, on points all over the scene with
    /// normals in every direction (facing the VPL or not, in front of the lid or behind it).
    #[test]
    fn vector_and_scalar_kernels_agree_bit_for_bit() {
        for format in FORMATS {
            let (map, c) = scene(64, format);
            let mut pts = Points::default();
            for i in 0..1001u32 {
                let f = i as f32;
                let p =
                    Vec3::new((f * 0.37).sin() * 1.8, (f * 0.11).cos() * 0.3 + 0.25, (f * 0.23).cos() * 1.8);
                let n = Vec3::new((f * 1.3).sin(), (f * 0.7).cos(), (f * 2.1).sin()).normalize_or(Vec3::Y);
                let ns = (n + Vec3::new(0.1, 0.0, -0.1)).normalize();
                pts.push_raw(p, ns, n);
            }
            let bits = |s: &Sums| s.0.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
            let mut b = Sums::default();
            b.reset(pts.len());
            for _ in 0..3 {
                add_vpl_with(pair, &c, &map, &pts, &mut b);
            }
            for k in Isa::for_tests("VPL gather kernels") {
                let mut a = Sums::default();
                a.reset(pts.len());
                for _ in 0..3 {
                    add_vpl_on(k, &c, &map, &pts, &mut a);
                }
                assert_eq!(bits(&a), bits(&b), "{format:?}, {k:?}");
            }
            let nonzero = (0..pts.len()).filter(|&i| b.get(i) != Vec3::ZERO).count();
            assert!(nonzero > 100 && nonzero < 900, "{format:?}: {nonzero}: the points must mix lit and not");
        }
    }
}
