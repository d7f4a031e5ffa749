//! Affine maps of points to clip space, applied to whole triangles with a vector kernel.
//!
//! A pinhole camera's projection (and a cube-map face's) is affine in homogeneous clip
//! coordinates: `clip = x v.x + y v.y + z v.z + offset` with `v = p - origin`, the columns `x`,
//! `y`, `z` and the offset chosen by the caller. The rasterizer never builds one: callers do,
//! and may use [`Affine::apply_triangles`] to transform their triangles fast (in a
//! [`crate::TriangleSource`], say).
//!
//! # Exactness
//!
//! Every kernel computes, per output component, `((x_c v.x + y_c v.y) + z_c v.z) + offset_c`
//! with `v = p - origin`: single-precision subtractions, products and sums, correctly rounded
//! in vector registers as in scalar ones, in this order and never fused. The results are bit for
//! bit those of [`Affine::apply`] (tested), which is what glam computes for the same
//! expression.

use glam::{Vec3, Vec4};

/// `clip = columns[0] v.x + columns[1] v.y + columns[2] v.z + offset` with `v = p - origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Subtracted from every point first (a camera's eye: keeps `v` small where precision
    /// matters).
    pub origin: Vec3,
    /// The clip-space images of the three unit axes.
    pub columns: [Vec4; 3],
    /// Added last.
    pub offset: Vec4,
}

impl Affine {
    /// The clip-space position of `p`: the reference the vector kernel reproduces.
    #[inline(always)]
    pub fn apply(&self, p: Vec3) -> Vec4 {
        // Scalar differences: widening `p` to a `Vec4` first went through the stack, a
        // store-forwarding stall per vertex.
        let v = p - self.origin;
        let [x, y, z] = self.columns;
        x * v.x + y * v.y + z * v.z + self.offset
    }

    /// `out[i] = tris[i].map(|p| self.apply(p))`, bit for bit, with AVX-512 where the CPU has
    /// it (a triangle per instruction sequence, 3 to 4 times fewer instructions than the
    /// scalar loop).
    ///
    /// # Panics
    ///
    /// If `tris` and `out` differ in length.
    pub fn apply_triangles(&self, tris: &[[Vec3; 3]], out: &mut [[Vec4; 3]]) {
        assert_eq!(tris.len(), out.len(), "one output per triangle");
        #[cfg(target_arch = "x86_64")]
        if hyrt_simd::Isa::best().tier() == hyrt_simd::Tier::Avx512 {
            // SAFETY: the AVX-512 tier (which includes AVX-512F) was detected.
            unsafe { self.apply_triangles_avx512(tris, out) };
            return;
        }
        self.apply_triangles_scalar(tris, out);
    }

    fn apply_triangles_scalar(&self, tris: &[[Vec3; 3]], out: &mut [[Vec4; 3]]) {
        for (o, t) in out.iter_mut().zip(tris) {
            *o = t.map(|p| self.apply(p));
        }
    }

    /// One triangle per 16-lane register: its 9 coordinates loaded at once, each lane of the
    /// 12 outputs (3 vertices x 4 components) fed its vertex's `v.x`, `v.y`, `v.z` by a
    /// permutation.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn apply_triangles_avx512(&self, tris: &[[Vec3; 3]], out: &mut [[Vec4; 3]]) {
        use std::arch::x86_64::*;

        let o = self.origin;
        let origin = _mm512_setr_ps(o.x, o.y, o.z, o.x, o.y, o.z, o.x, o.y, o.z, 0., 0., 0., 0., 0., 0., 0.);
        // Lanes 4 k .. 4 k + 3: component 0-3 of vertex k (k < 3); lanes 12-15 unused.
        let per_vertex = |c: Vec4| {
            _mm512_setr_ps(c.x, c.y, c.z, c.w, c.x, c.y, c.z, c.w, c.x, c.y, c.z, c.w, 0., 0., 0., 0.)
        };
        let [x, y, z] = self.columns.map(per_vertex);
        let offset = per_vertex(self.offset);
        // Vertex k's coordinate c sits at lane 3 k + c of the loaded triangle.
        let pick = |c: i32| {
            _mm512_setr_epi32(c, c, c, c, 3 + c, 3 + c, 3 + c, 3 + c, 6 + c, 6 + c, 6 + c, 6 + c, c, c, c, c)
        };
        let (px, py, pz) = (pick(0), pick(1), pick(2));
        for (t, o) in tris.iter().zip(out) {
            // SAFETY: the masked load reads the triangle's 9 floats (36 bytes, `[Vec3; 3]` is
            // 9 packed `f32`), the masked store writes the 12 of `[Vec4; 3]`.
            unsafe {
                let v = _mm512_sub_ps(_mm512_maskz_loadu_ps(0x01ff, t.as_ptr().cast()), origin);
                let (vx, vy, vz) = (
                    _mm512_permutexvar_ps(px, v),
                    _mm512_permutexvar_ps(py, v),
                    _mm512_permutexvar_ps(pz, v),
                );
                let xy = _mm512_add_ps(_mm512_mul_ps(x, vx), _mm512_mul_ps(y, vy));
                let clip = _mm512_add_ps(_mm512_add_ps(xy, _mm512_mul_ps(z, vz)), offset);
                _mm512_mask_storeu_ps(o.as_mut_ptr().cast(), 0x0fff, clip);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    /// Every kernel gives `apply`'s bits, on points of every scale and sign (and non-finite
    /// ones, whose NaN results must be NaN alike), for a camera-like map and a random one.
    #[test]
    fn triangles_transform_bit_for_bit_like_points() {
        // `apply_triangles` takes the AVX-512 kernel where the CPU has it; elsewhere this says
        // that it went untested.
        hyrt_simd::Isa::for_tests("affine triangle kernel");
        let mut rng = Rng(7);
        let mut r = |scale: f32| (rng.f32() * 2.0 - 1.0) * scale;
        let mut tris = Vec::new();
        for scale in [1e-30, 1e-4, 1.0, 3.7, 1e4, 1e30] {
            for _ in 0..200 {
                tris.push([0; 3].map(|_| Vec3::new(r(scale), r(scale), r(scale))));
            }
        }
        tris.push([Vec3::new(f32::NAN, 0.0, 1.0), Vec3::splat(f32::INFINITY), Vec3::new(-0.0, -0.0, -0.0)]);
        let maps = [
            Affine {
                origin: Vec3::new(0.0, 1.0, 6.8),
                columns: [
                    Vec4::new(5.8, 0.0, 0.0, 0.0),
                    Vec4::new(0.0, 5.8, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, 0.0, -1.0),
                ],
                offset: Vec4::new(0.0, 0.0, 1e-6, 0.0),
            },
            Affine {
                origin: Vec3::new(r(10.0), r(10.0), r(10.0)),
                columns: [0; 3].map(|_| Vec4::new(r(2.0), r(2.0), r(2.0), r(2.0))),
                offset: Vec4::new(r(1.0), r(1.0), r(1.0), r(1.0)),
            },
        ];
        let bits = |v: &[[Vec4; 3]]| -> Vec<u32> {
            v.iter().flatten().flat_map(|p| p.to_array()).map(f32::to_bits).collect()
        };
        for m in maps {
            let expected: Vec<[Vec4; 3]> = tris.iter().map(|t| t.map(|p| m.apply(p))).collect();
            let mut out = vec![[Vec4::ZERO; 3]; tris.len()];
            m.apply_triangles_scalar(&tris, &mut out);
            assert_eq!(bits(&out), bits(&expected));
            out.fill([Vec4::ZERO; 3]);
            m.apply_triangles(&tris, &mut out);
            assert_eq!(bits(&out), bits(&expected), "apply_triangles");
        }
    }
}
