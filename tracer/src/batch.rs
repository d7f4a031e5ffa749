//! Plane hits of a whole row of camera rays at once: the resolve step of rasterized visibility.
//!
//! A z-buffer gives each pixel its visible triangle; the hit itself must then come from the
//! pixel's camera ray and that triangle's plane, computed with exactly the arithmetic of
//! [`Tracer::hit_on_plane`] so that it is bit-identical to what ray casting finds. Pixel by
//! pixel that is some 200 instructions: normalising the direction, the two divisions of
//! [`RayPrecomp`](crate::RayPrecomp), the watertight test and its conservative `t` bound.
//!
//! [`Tracer::hits_on_row`] does the same for a row of pixels, 8 (AVX2) or 16 (AVX-512) lanes
//! at a time, with the same IEEE operations in the same order as the scalar code:
//! single-precision add, subtract, multiply, divide and square root are correctly rounded in
//! SIMD registers as in scalar ones, and Rust never fuses or reassociates them, so every lane
//! is bit-identical to the scalar path. The directions come from a few numbers per row
//! ([`RowRays`]); the axis permutation of the test is fixed per chunk of lanes when they all
//! agree (nearly always along a camera row) and selected lane by lane otherwise; the vertices
//! are broadcast when the lanes share a triangle (the usual case) and gathered otherwise.
//!
//! The vector test only ever *accepts* a lane when the scalar test would return the same hit;
//! every other lane (an edge value exactly zero, which the scalar test re-evaluates in f64; a
//! miss; anything non-finite; a `NaN` the scalar comparisons would let through) is handed to
//! the scalar [`Tracer::hit_on_plane`], which stays the reference. A rare lane costs a scalar
//! test, never a different answer.

use glam::Vec3;
use hyrt_simd::{Isa, Tier};

use crate::{Hit, Ray, Tracer, triangle::gamma};

/// The rays of one image row of a pinhole camera, as plain numbers (the tracer knows no
/// cameras): all start at `origin`, and column `x` has the direction
///
/// ```text
/// s = ((x + 0.5) * two_over_w - 1) * tan_x
/// d = normalize((forward + right * s) + row_offset)      (glam: d * (1 / sqrt((dx dx + dy dy) + dz dz)))
/// ```
///
/// rounded in f32 operation by operation, in this order ([`RowRays::dir`]). A camera whose
/// pixel ray is `forward + right * sx + up * sy` gets exactly its directions with
/// `row_offset = up * sy` of the row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowRays {
    pub origin: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    /// The part of the direction that is constant along the row (`up * sy`).
    pub row_offset: Vec3,
    pub two_over_w: f32,
    pub tan_x: f32,
    /// Hits are accepted for `0 < t < tmax`.
    pub tmax: f32,
}

impl RowRays {
    /// The normalised direction of column `x`: the reference the vector kernels reproduce.
    #[inline]
    pub fn dir(&self, x: u32) -> Vec3 {
        let s = ((x as f32 + 0.5) * self.two_over_w - 1.0) * self.tan_x;
        (self.forward + self.right * s + self.row_offset).normalize()
    }

    /// The ray of column `x`.
    #[inline]
    pub fn ray(&self, x: u32) -> Ray {
        Ray::new(self.origin, self.dir(x), self.tmax)
    }
}

/// Vertex data is gathered with 32-bit indices `9 id + k` (three `Vec3` per triangle).
const MAX_VECTOR_TRIS: usize = (i32::MAX as usize - 8) / 9;

impl Tracer {
    /// `out[i] = self.hit_on_plane(ids[i], &rays.ray(x0 + i))` for every `i`, bit for bit, with
    /// the widest kernel this CPU runs ([`Isa::best`]). Returns the number of lanes whose id is a triangle
    /// (`< triangle_count()`) but whose result is `None` (a ray parallel to the plane, or the
    /// plane behind the origin): the lanes a caller may want to resolve otherwise. Lanes with
    /// any other id get `None` and are not counted.
    ///
    /// # Panics
    /// If `ids` and `out` differ in length.
    pub fn hits_on_row(&self, rays: &RowRays, x0: u32, ids: &[u32], out: &mut [Option<Hit>]) -> usize {
        self.hits_on_row_with(Isa::best(), rays, x0, ids, out)
    }

    /// [`Tracer::hits_on_row`] with the kernel of tier `isa` (for tests and benchmarks). All
    /// tiers give bit-identical results; the scalar one is [`Tracer::hit_on_plane`] lane by
    /// lane.
    ///
    /// # Panics
    /// If `ids` and `out` differ in length.
    pub fn hits_on_row_with(
        &self,
        isa: Isa,
        rays: &RowRays,
        x0: u32,
        ids: &[u32],
        out: &mut [Option<Hit>],
    ) -> usize {
        assert_eq!(ids.len(), out.len(), "one output per id");
        // The vector kernels convert columns with signed 32-bit conversions, exact below 2^24
        // as `x as f32` is; a non-finite origin makes every lane `None`, which the scalar path
        // answers at once.
        let vector = !self.by_id.is_empty()
            && self.by_id.len() <= MAX_VECTOR_TRIS
            && rays.origin.is_finite()
            && x0 as u64 + ids.len() as u64 <= 1 << 24;
        match isa.tier() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX2 tier exists only where the CPU runs it.
            Tier::Avx2 if vector => unsafe { x86::row_avx2(self, rays, x0, ids, out) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX-512 tier (which includes AVX-512F) exists only where
            // the CPU runs it.
            Tier::Avx512 if vector => unsafe { x86::row_avx512(self, rays, x0, ids, out) },
            _ => self.row_scalar(rays, x0, ids, out),
        }
    }

    fn row_scalar(&self, rays: &RowRays, x0: u32, ids: &[u32], out: &mut [Option<Hit>]) -> usize {
        let mut misses = 0;
        for (x, (o, &id)) in (x0..).zip(out.iter_mut().zip(ids)) {
            *o = self.lane_scalar(rays, x, id, &mut misses);
        }
        misses
    }

    /// One lane by the reference path, counting a miss on a known triangle.
    #[inline]
    fn lane_scalar(&self, rays: &RowRays, x: u32, id: u32, misses: &mut usize) -> Option<Hit> {
        if id as usize >= self.by_id.len() {
            return None;
        }
        let h = self.hit_on_plane(id, &rays.ray(x));
        *misses += h.is_none() as usize;
        h
    }
}

/// The vector kernels: one generic body over a small set of lane operations ([`x86::Lanes`]),
/// instantiated for AVX2 and AVX-512.
#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;

    pub(super) use hyrt_simd::lanes::{Avx2, Avx512, Lanes as Base};

    /// The lane operations of the tier ([`Base`], shared with the other kernels), and those
    /// only this kernel needs: triangle ids and the vertex gathers.
    ///
    /// # Safety
    /// As [`Base`]: every method may only be called from a function compiled with the tier's
    /// target features (the two `row_*` entry points below), where they are inlined.
    pub(super) trait Lanes: Base {
        /// `[f32; N]`.
        type A: Copy + std::ops::Index<usize, Output = f32>;
        /// `N` ids from `p`.
        unsafe fn load_ids(p: *const u32) -> Self::I;
        /// Lanes whose id is at most `last`.
        unsafe fn ids_le(ids: Self::I, last: u32) -> Self::M;
        /// True when all lanes hold the same id.
        unsafe fn ids_uniform(ids: Self::I) -> bool;
        /// `9 min(id, last)`: the index of each lane's first coordinate, clamped so that
        /// lanes without a triangle still read valid memory.
        unsafe fn vertex_index(ids: Self::I, last: u32) -> Self::I;
        /// `base[index + k]` per lane.
        unsafe fn vertex<const K: usize>(base: *const f32, index: Self::I) -> Self::F;
        /// `x0 + i` in lane `i`, as f32 (exact below 2^24).
        unsafe fn columns(x0: u32) -> Self::F;
        /// The lanes as an array (`[f32; N]`).
        unsafe fn to_array(a: Self::F) -> Self::A;
    }

    // Each method is one intrinsic or a few; the trait's contract (the target features) is
    // what makes them sound, so per-call `unsafe` blocks would add nothing.
    #[allow(unsafe_op_in_unsafe_fn)]
    impl Lanes for Avx2 {
        type A = [f32; 8];
        #[inline(always)]
        unsafe fn load_ids(p: *const u32) -> __m256i {
            _mm256_loadu_si256(p.cast())
        }
        #[inline(always)]
        unsafe fn ids_le(ids: __m256i, last: u32) -> __m256 {
            let le = _mm256_cmpeq_epi32(_mm256_min_epu32(ids, _mm256_set1_epi32(last as i32)), ids);
            _mm256_castsi256_ps(le)
        }
        #[inline(always)]
        unsafe fn ids_uniform(ids: __m256i) -> bool {
            let first = _mm256_permutevar8x32_epi32(ids, _mm256_setzero_si256());
            _mm256_movemask_epi8(_mm256_cmpeq_epi32(ids, first)) == -1
        }
        #[inline(always)]
        unsafe fn vertex_index(ids: __m256i, last: u32) -> __m256i {
            let i = _mm256_min_epu32(ids, _mm256_set1_epi32(last as i32));
            _mm256_add_epi32(_mm256_slli_epi32::<3>(i), i)
        }
        #[inline(always)]
        unsafe fn vertex<const K: usize>(base: *const f32, index: __m256i) -> __m256 {
            _mm256_i32gather_ps::<4>(base.add(K), index)
        }
        #[inline(always)]
        unsafe fn columns(x0: u32) -> __m256 {
            let x = _mm256_add_epi32(_mm256_set1_epi32(x0 as i32), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
            _mm256_cvtepi32_ps(x)
        }
        #[inline(always)]
        unsafe fn to_array(a: __m256) -> [f32; 8] {
            std::mem::transmute(a)
        }
    }

    #[allow(unsafe_op_in_unsafe_fn)]
    impl Lanes for Avx512 {
        type A = [f32; 16];
        #[inline(always)]
        unsafe fn load_ids(p: *const u32) -> __m512i {
            _mm512_loadu_si512(p.cast())
        }
        #[inline(always)]
        unsafe fn ids_le(ids: __m512i, last: u32) -> __mmask16 {
            _mm512_cmple_epu32_mask(ids, _mm512_set1_epi32(last as i32))
        }
        #[inline(always)]
        unsafe fn ids_uniform(ids: __m512i) -> bool {
            let first = _mm512_permutexvar_epi32(_mm512_setzero_si512(), ids);
            _mm512_cmpeq_epi32_mask(ids, first) == 0xffff
        }
        #[inline(always)]
        unsafe fn vertex_index(ids: __m512i, last: u32) -> __m512i {
            let i = _mm512_min_epu32(ids, _mm512_set1_epi32(last as i32));
            _mm512_add_epi32(_mm512_slli_epi32::<3>(i), i)
        }
        #[inline(always)]
        unsafe fn vertex<const K: usize>(base: *const f32, index: __m512i) -> __m512 {
            _mm512_i32gather_ps::<4>(index, base.add(K).cast())
        }
        #[inline(always)]
        unsafe fn columns(x0: u32) -> __m512 {
            let lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
            _mm512_cvtepi32_ps(_mm512_add_epi32(_mm512_set1_epi32(x0 as i32), lanes))
        }
        #[inline(always)]
        unsafe fn to_array(a: __m512) -> [f32; 16] {
            std::mem::transmute(a)
        }
    }

    /// # Safety
    /// The CPU must support AVX2; `Tracer::hits_on_row_with`'s `vector` conditions must hold.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn row_avx2(
        t: &Tracer,
        rays: &RowRays,
        x0: u32,
        ids: &[u32],
        out: &mut [Option<Hit>],
    ) -> usize {
        // SAFETY: this function's own contract (AVX2 present, the `vector` conditions hold) is
        // `row`'s.
        unsafe { row::<Avx2>(t, rays, x0, ids, out) }
    }

    /// # Safety
    /// The CPU must support AVX-512F; `Tracer::hits_on_row_with`'s `vector` conditions must
    /// hold.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn row_avx512(
        t: &Tracer,
        rays: &RowRays,
        x0: u32,
        ids: &[u32],
        out: &mut [Option<Hit>],
    ) -> usize {
        // SAFETY: this function's own contract (AVX-512F present, the `vector` conditions
        // hold) is `row`'s.
        unsafe { row::<Avx512>(t, rays, x0, ids, out) }
    }

    /// The axis permutation `(kz + 1, kz + 2, kz) mod 3` of `RayPrecomp`. `KZ` 0, 1 or 2: the
    /// same for every lane (no selects); [`MIXED`]: lane by lane, where `kz0` marks the lanes
    /// with `kz = 0` and `kz1` those with `kz = 1` unless `kz0` is set.
    #[inline(always)]
    unsafe fn permute<L: Lanes, const KZ: usize>(kz0: L::M, kz1: L::M, [x, y, z]: [L::F; 3]) -> [L::F; 3] {
        // SAFETY: lane selects only, on registers; the caller's contract provides `L`'s
        // instruction set.
        unsafe {
            match KZ {
                0 => [y, z, x],
                1 => [z, x, y],
                2 => [x, y, z],
                _ => [
                    L::select(kz0, y, L::select(kz1, z, x)),
                    L::select(kz0, z, L::select(kz1, x, y)),
                    L::select(kz0, x, L::select(kz1, y, z)),
                ],
            }
        }
    }

    /// `KZ` for lanes whose permutations differ.
    const MIXED: usize = 3;

    /// `[v.x, v.y, v.z]` in every lane.
    #[inline(always)]
    unsafe fn splat3<L: Lanes>(v: Vec3) -> [L::F; 3] {
        // SAFETY: register operations only; the caller provides `L`'s instruction set.
        unsafe { [L::splat(v.x), L::splat(v.y), L::splat(v.z)] }
    }

    /// `max(max(|a|, |b|), |c|)`, as `a.abs().max(b.abs()).max(c.abs())`.
    #[inline(always)]
    unsafe fn max3<L: Lanes>(a: L::F, b: L::F, c: L::F) -> L::F {
        // SAFETY: register operations only; the caller provides `L`'s instruction set.
        unsafe { L::max(L::max(L::abs(a), L::abs(b)), L::abs(c)) }
    }

    /// Values shared by every chunk of a row, in every lane.
    struct Shared<'a, L: Lanes> {
        tracer: &'a Tracer,
        rays: &'a RowRays,
        /// The largest valid id and the vertex data (9 floats per id).
        last: u32,
        base: *const f32,
        origin: [L::F; 3],
        tmax: L::F,
        inv_scale: L::F,
        zero: L::F,
        one: L::F,
        two: L::F,
        three: L::F,
        inf: L::F,
        gamma: [L::F; 3],
    }

    /// One chunk's rays after `RayPrecomp`.
    struct Chunk<L: Lanes> {
        /// The chunk's ids and which of them are valid (`ids_le(last)`; 0: nothing to do).
        idv: L::I,
        valid_bits: u32,
        /// Lanes still fit for the vector path.
        ok: L::M,
        /// The permutation: `KZ` of [`permute`] when all lanes agree, else [`MIXED`] with
        /// its lane masks.
        variant: usize,
        kz: (L::M, L::M),
        /// `(sx, sy)` and `sz` of `RayPrecomp`.
        shear: (L::F, L::F),
        sz: L::F,
    }

    impl<L: Lanes> Clone for Chunk<L> {
        fn clone(&self) -> Self {
            *self
        }
    }

    impl<L: Lanes> Copy for Chunk<L> {}

    /// Chunks per block: the rays of a block are prepared first, then their triangles tested.
    const BLOCK: usize = 8;

    /// The whole row, in blocks of `BLOCK` chunks of `L::N` lanes. Two passes per block: the
    /// first prepares every chunk's rays (direction, normalisation, `RayPrecomp`: a chain of
    /// a square root and two divisions), the second tests the triangles (one more division).
    /// Within each pass the chunks are independent, so the processor overlaps their long
    /// latencies; in one pass per chunk it would mostly wait for them.
    ///
    /// Each step names the scalar code it reproduces, whose order of operations it keeps.
    /// (No closures: they would not inherit the entry point's target features, and the lane
    /// operations must inline into it.)
    #[inline(always)]
    unsafe fn row<L: Lanes>(
        t: &Tracer,
        rays: &RowRays,
        x0: u32,
        ids: &[u32],
        out: &mut [Option<Hit>],
    ) -> usize {
        // SAFETY: the caller provides `L`'s instruction set and `hits_on_row_with`'s `vector`
        // conditions. The id loads read `L::N` ids from a full chunk of `ids` or from a padded
        // copy; the vertex gathers (in `chunk`) index `by_id` by ids checked `<= last` first.
        unsafe {
            // `Tracer::scaled`: the origin and range in the tracer's frame. `t / scale` equals
            // `t * (1 / scale)` exactly: both are the correctly rounded value of the same real
            // number, `1 / scale` being a power of two within the normal range.
            let sh = Shared::<L> {
                tracer: t,
                rays,
                last: t.by_id.len() as u32 - 1,
                base: t.by_id.as_ptr().cast::<f32>(),
                origin: splat3::<L>(rays.origin * t.scale),
                tmax: L::splat(rays.tmax * t.scale),
                inv_scale: L::splat(1.0 / t.scale),
                zero: L::splat(0.0),
                one: L::splat(1.0),
                two: L::splat(2.0),
                three: L::splat(3.0),
                inf: L::splat(f32::INFINITY),
                gamma: [L::splat(gamma(2)), L::splat(gamma(3)), L::splat(gamma(5))],
            };
            let half = L::splat(0.5);
            let fwd = splat3::<L>(rays.forward);
            let right = splat3::<L>(rays.right);
            let offset = splat3::<L>(rays.row_offset);
            let (two_over_w, tan_x) = (L::splat(rays.two_over_w), L::splat(rays.tan_x));
            let full = (1u32 << L::N) - 1;
            let none = L::lt(sh.zero, sh.zero);
            let empty = Chunk::<L> {
                idv: L::load_ids([u32::MAX; 16].as_ptr()),
                valid_bits: 0,
                ok: none,
                variant: MIXED,
                kz: (none, none),
                shear: (sh.zero, sh.zero),
                sz: sh.zero,
            };

            let mut misses = 0;
            let mut x = x0;
            for (ids, out) in ids.chunks(L::N * BLOCK).zip(out.chunks_mut(L::N * BLOCK)) {
                let xb = x;
                x += ids.len() as u32;
                let mut pre = [empty; BLOCK];
                for (j, (c, ids)) in pre.iter_mut().zip(ids.chunks(L::N)).enumerate() {
                    let xs = xb + (j * L::N) as u32;
                    let idv = if ids.len() == L::N {
                        L::load_ids(ids.as_ptr())
                    } else {
                        let mut pad = [u32::MAX; 16];
                        pad[..ids.len()].copy_from_slice(ids);
                        L::load_ids(pad.as_ptr())
                    };
                    let valid = L::ids_le(idv, sh.last);
                    let valid_bits = L::bits(valid);
                    if valid_bits == 0 {
                        continue;
                    }
                    // `RowRays::dir`: s, then (forward + right * s) + row_offset, then normalize.
                    let s = L::mul(L::sub(L::mul(L::add(L::columns(xs), half), two_over_w), sh.one), tan_x);
                    let dx = L::add(L::add(fwd[0], L::mul(right[0], s)), offset[0]);
                    let dy = L::add(L::add(fwd[1], L::mul(right[1], s)), offset[1]);
                    let dz = L::add(L::add(fwd[2], L::mul(right[2], s)), offset[2]);
                    let len2 = L::add(L::add(L::mul(dx, dx), L::mul(dy, dy)), L::mul(dz, dz));
                    let recip = L::div(sh.one, L::sqrt(len2));
                    let d = [L::mul(dx, recip), L::mul(dy, recip), L::mul(dz, recip)];
                    // `on_triangle`: a non-finite direction gives `None`, left to the scalar path.
                    let a = [L::abs(d[0]), L::abs(d[1]), L::abs(d[2])];
                    let finite =
                        L::and(L::lt(a[0], sh.inf), L::and(L::lt(a[1], sh.inf), L::lt(a[2], sh.inf)));
                    // `RayPrecomp::new`: kz is the largest |component|, ties to the lower axis.
                    // The direction is permuted lane by lane here (6 selects); along a camera
                    // row kz rarely changes, so the triangle test, which permutes 9 vertex
                    // coordinates, branches once per chunk on `variant` (predictably) instead.
                    let kz = (L::and(L::ge(a[0], a[1]), L::ge(a[0], a[2])), L::ge(a[1], a[2]));
                    let (b0, b1) = (L::bits(kz.0), L::bits(kz.1));
                    let variant = match (b0, b1) {
                        (b0, _) if b0 == full => 0,
                        (0, b1) if b1 == full => 1,
                        (0, 0) => 2,
                        _ => MIXED,
                    };
                    let [dx, dy, dz] = permute::<L, MIXED>(kz.0, kz.1, d);
                    let sz = L::div(sh.one, dz);
                    let shear = (L::mul(L::neg(dx), sz), L::mul(L::neg(dy), sz));
                    *c = Chunk { idv, valid_bits, ok: L::and(valid, finite), variant, kz, shear, sz };
                }
                for (j, (c, (ids, out))) in
                    pre.iter().zip(ids.chunks(L::N).zip(out.chunks_mut(L::N))).enumerate()
                {
                    let xs = xb + (j * L::N) as u32;
                    misses += match c.variant {
                        _ if c.valid_bits == 0 => {
                            out.fill(None);
                            0
                        }
                        0 => chunk::<L, 0>(&sh, c, xs, ids, out),
                        1 => chunk::<L, 1>(&sh, c, xs, ids, out),
                        2 => chunk::<L, 2>(&sh, c, xs, ids, out),
                        _ => chunk::<L, MIXED>(&sh, c, xs, ids, out),
                    };
                }
            }
            misses
        }
    }

    /// One chunk from `RayPrecomp` on, for the permutation `KZ`: writes `out` and returns the
    /// number of misses on valid ids.
    #[inline(always)]
    unsafe fn chunk<L: Lanes, const KZ: usize>(
        sh: &Shared<L>,
        c: &Chunk<L>,
        x: u32,
        ids: &[u32],
        out: &mut [Option<Hit>],
    ) -> usize {
        // SAFETY: the caller (`row`) provides `L`'s instruction set; the gathers read only the
        // lanes of `c.valid` (ids `<= last`, within `by_id`) and `out` is written through
        // slice indexing.
        unsafe {
            let [g2, g3, g5] = sh.gamma;
            let zero = sh.zero;
            let (sz, shear) = (c.sz, c.shear);

            // The vertices: one triangle for all lanes (broadcast), or one each (gather).
            let full = (1u32 << L::N) - 1;
            let v: [L::F; 9] = if c.valid_bits == full && L::ids_uniform(c.idv) {
                let [a, b, c] = sh.tracer.by_id[ids[0] as usize];
                [
                    L::splat(a.x),
                    L::splat(a.y),
                    L::splat(a.z),
                    L::splat(b.x),
                    L::splat(b.y),
                    L::splat(b.z),
                    L::splat(c.x),
                    L::splat(c.y),
                    L::splat(c.z),
                ]
            } else {
                let (base, i) = (sh.base, L::vertex_index(c.idv, sh.last));
                [
                    L::vertex::<0>(base, i),
                    L::vertex::<1>(base, i),
                    L::vertex::<2>(base, i),
                    L::vertex::<3>(base, i),
                    L::vertex::<4>(base, i),
                    L::vertex::<5>(base, i),
                    L::vertex::<6>(base, i),
                    L::vertex::<7>(base, i),
                    L::vertex::<8>(base, i),
                ]
            };
            // `intersect_perm` from here on.
            let p0 = sheared::<L, KZ>([v[0], v[1], v[2]], sh.origin, c.kz, shear);
            let p1 = sheared::<L, KZ>([v[3], v[4], v[5]], sh.origin, c.kz, shear);
            let p2 = sheared::<L, KZ>([v[6], v[7], v[8]], sh.origin, c.kz, shear);
            // Edge functions; an exact zero sends the lane to the scalar f64 re-evaluation.
            let e0 = L::sub(L::mul(p1[0], p2[1]), L::mul(p1[1], p2[0]));
            let e1 = L::sub(L::mul(p2[0], p0[1]), L::mul(p2[1], p0[0]));
            let e2 = L::sub(L::mul(p0[0], p1[1]), L::mul(p0[1], p1[0]));
            let mut ok = L::and(c.ok, L::and(L::ne(e0, zero), L::and(L::ne(e1, zero), L::ne(e2, zero))));
            let det = L::add(L::add(e0, e1), e2);
            ok = L::and(ok, L::and(L::ne(det, zero), L::lt(L::abs(det), sh.inf)));
            let (z0, z1, z2) = (L::mul(p0[2], sz), L::mul(p1[2], sz), L::mul(p2[2], sz));
            let t_scaled = L::add(L::add(L::mul(e0, z0), L::mul(e1, z1)), L::mul(e2, z2));
            // The range test without dividing, written as the accepting conditions: they
            // reject NaN, which the scalar test lets through, so such lanes go scalar.
            let bound = L::mul(sh.tmax, det);
            let pos = L::and(L::lt(zero, det), L::and(L::lt(zero, t_scaled), L::le(t_scaled, bound)));
            let neg = L::and(L::lt(det, zero), L::and(L::lt(t_scaled, zero), L::ge(t_scaled, bound)));
            ok = L::and(ok, L::or(pos, neg));
            let inv_det = L::div(sh.one, det);
            let tt = L::mul(t_scaled, inv_det);
            ok = L::and(ok, L::lt(tt, sh.tmax));
            // The conservative `t > 0` bound (pbrt-v4 6.8.7), term by term.
            let max_zt = max3::<L>(z0, z1, z2);
            let delta_z = L::mul(g3, max_zt);
            let max_z_unscaled = max3::<L>(p0[2], p1[2], p2[2]);
            let max_xt = max3::<L>(p0[0], p1[0], p2[0]);
            let max_yt = max3::<L>(p0[1], p1[1], p2[1]);
            let delta_x = L::mul(g5, L::add(max_xt, L::mul(L::abs(shear.0), max_z_unscaled)));
            let delta_y = L::mul(g5, L::add(max_yt, L::mul(L::abs(shear.1), max_z_unscaled)));
            let delta_e = L::mul(
                sh.two,
                L::add(
                    L::add(L::mul(L::mul(g2, max_xt), max_yt), L::mul(delta_y, max_xt)),
                    L::mul(delta_x, max_yt),
                ),
            );
            let max_e = max3::<L>(e0, e1, e2);
            let delta_t = L::mul(
                L::mul(
                    sh.three,
                    L::add(
                        L::add(L::mul(L::mul(g3, max_e), max_zt), L::mul(delta_e, max_zt)),
                        L::mul(delta_z, max_e),
                    ),
                ),
                L::abs(inv_det),
            );
            ok = L::and(ok, L::lt(delta_t, tt));

            let hit_bits = L::bits(ok);
            // The results as arrays held by value: the compiler writes each hit's fields
            // straight into `out`. (From arrays filled by vector stores it assembled each
            // `Some(Hit)` on the stack and copied it out with wider loads than its stores: a
            // store-forwarding stall per pixel. Check the assembly when changing this.)
            let th = L::to_array(L::mul(tt, sh.inv_scale));
            let b = [
                L::to_array(L::mul(e0, inv_det)),
                L::to_array(L::mul(e1, inv_det)),
                L::to_array(L::mul(e2, inv_det)),
            ];
            let mut misses = 0;
            if hit_bits == full && out.len() == L::N {
                // Every lane hit (nearly every chunk): a loop of fixed length, unrolled, with
                // no test per lane.
                for k in 0..L::N {
                    out[k] = Some(Hit { t: th[k], tri: ids[k], bary: [b[0][k], b[1][k], b[2][k]] });
                }
                return 0;
            }
            for (k, (o, &id)) in out.iter_mut().zip(ids).enumerate() {
                if hit_bits >> k & 1 != 0 {
                    *o = Some(Hit { t: th[k], tri: id, bary: [b[0][k], b[1][k], b[2][k]] });
                } else {
                    *o = sh.tracer.lane_scalar(sh.rays, x + k as u32, id, &mut misses);
                }
            }
            misses
        }
    }

    /// One vertex in the ray's frame (`intersect_perm`): translated to the origin, permuted,
    /// then x and y sheared so that the ray runs along +z.
    #[inline(always)]
    unsafe fn sheared<L: Lanes, const KZ: usize>(
        v: [L::F; 3],
        o: [L::F; 3],
        (kz0, kz1): (L::M, L::M),
        (sx, sy): (L::F, L::F),
    ) -> [L::F; 3] {
        // SAFETY: register operations only; the caller provides `L`'s instruction set.
        unsafe {
            let q = [L::sub(v[0], o[0]), L::sub(v[1], o[1]), L::sub(v[2], o[2])];
            let [px, py, pz] = permute::<L, KZ>(kz0, kz1, q);
            [L::add(px, L::mul(sx, pz)), L::add(py, L::mul(sy, pz)), pz]
        }
    }
}
