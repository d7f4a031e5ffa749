//! The vector operations of each tier, written once: the kernels of the tracer, of the VPL
//! gather and of the rasterizer's depth test are generic over [`Lanes`] and extend it with what
//! only they need. The depth test keeps eight lanes on AVX-512 too ([`Avx512x8`]), whose `f64`
//! and `i64` halves fill one 512-bit vector.
//!
//! Float operations are the IEEE ones of the same name (correctly rounded, no fused
//! multiply-add), so a kernel that performs the scalar kernel's operations in its order gives its
//! bits; comparisons are ordered (false when either side is NaN).
//!
//! # Safety
//! Every method may be called only where the CPU runs the implementation's tier (an
//! [`Isa`](crate::Isa) of it exists), from a function compiled with its target features, into
//! which the methods are inlined.

use std::arch::x86_64::*;

/// The operations on one tier's vectors: `F` of `f32` lanes, `I` of `i32` lanes, `M` a lane
/// mask.
///
/// # Safety
/// Every method: as the module's, the CPU must run the tier (and pointers be valid where said).
#[allow(clippy::missing_safety_doc)] // One contract for all, stated above and in the module.
pub trait Lanes {
    /// Lanes per vector.
    const N: usize;
    type F: Copy;
    type I: Copy;
    type M: Copy;
    unsafe fn splat(x: f32) -> Self::F;
    unsafe fn splat_i(x: i32) -> Self::I;
    /// `N` floats from `p`, which must be readable.
    unsafe fn load(p: *const f32) -> Self::F;
    /// `N` floats to `p`, which must be writable.
    unsafe fn store(p: *mut f32, v: Self::F);
    unsafe fn add(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn sub(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn mul(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn div(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn sqrt(a: Self::F) -> Self::F;
    /// The sign bit cleared.
    unsafe fn abs(a: Self::F) -> Self::F;
    /// The sign bit flipped.
    unsafe fn neg(a: Self::F) -> Self::F;
    /// `a < b ? a : b`, as the instruction: `b` where either is NaN.
    unsafe fn min(a: Self::F, b: Self::F) -> Self::F;
    /// `a > b ? a : b`, as the instruction: `b` where either is NaN (`f32::max` otherwise).
    unsafe fn max(a: Self::F, b: Self::F) -> Self::F;
    unsafe fn lt(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn le(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn gt(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn ge(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn eq(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn ne(a: Self::F, b: Self::F) -> Self::M;
    unsafe fn and(a: Self::M, b: Self::M) -> Self::M;
    unsafe fn or(a: Self::M, b: Self::M) -> Self::M;
    /// `a & !b`.
    unsafe fn and_not(a: Self::M, b: Self::M) -> Self::M;
    unsafe fn any(m: Self::M) -> bool;
    /// Bit `i` set when lane `i` of `m` is.
    unsafe fn bits(m: Self::M) -> u32;
    /// `a` where `m`, else `b`.
    unsafe fn select(m: Self::M, a: Self::F, b: Self::F) -> Self::F;
    /// `v` where `m`, `+0.0` elsewhere.
    unsafe fn keep(m: Self::M, v: Self::F) -> Self::F;
    /// Truncation towards zero.
    unsafe fn trunc(a: Self::F) -> Self::I;
    unsafe fn to_f(a: Self::I) -> Self::F;
    unsafe fn add_i(a: Self::I, b: Self::I) -> Self::I;
    unsafe fn mul_i(a: Self::I, b: Self::I) -> Self::I;
    /// `base[idx]` where `m`, `0.0` elsewhere (not read).
    unsafe fn gather(base: *const f32, idx: Self::I, m: Self::M) -> Self::F;
}

/// The AVX2 tier: eight lanes, masks as vectors of all-ones or zero lanes.
pub struct Avx2;

/// The AVX-512 tier: sixteen lanes, masks as bit masks.
pub struct Avx512;

/// The AVX-512 tier on eight lanes (256-bit vectors, AVX-512 VL), masks as bit masks: for
/// kernels whose eight `f32` lanes go with eight `f64` or `i64` lanes in one 512-bit vector, as
/// the rasterizer's depth test.
pub struct Avx512x8;

/// The arithmetic of the tiers on 256-bit vectors ([`Avx2`], [`Avx512x8`]): the same
/// instructions, whatever form their masks take.
macro_rules! ymm_arithmetic {
    () => {
        #[inline(always)]
        unsafe fn splat(x: f32) -> __m256 {
            _mm256_set1_ps(x)
        }
        #[inline(always)]
        unsafe fn splat_i(x: i32) -> __m256i {
            _mm256_set1_epi32(x)
        }
        #[inline(always)]
        unsafe fn load(p: *const f32) -> __m256 {
            _mm256_loadu_ps(p)
        }
        #[inline(always)]
        unsafe fn store(p: *mut f32, v: __m256) {
            _mm256_storeu_ps(p, v)
        }
        #[inline(always)]
        unsafe fn add(a: __m256, b: __m256) -> __m256 {
            _mm256_add_ps(a, b)
        }
        #[inline(always)]
        unsafe fn sub(a: __m256, b: __m256) -> __m256 {
            _mm256_sub_ps(a, b)
        }
        #[inline(always)]
        unsafe fn mul(a: __m256, b: __m256) -> __m256 {
            _mm256_mul_ps(a, b)
        }
        #[inline(always)]
        unsafe fn div(a: __m256, b: __m256) -> __m256 {
            _mm256_div_ps(a, b)
        }
        #[inline(always)]
        unsafe fn sqrt(a: __m256) -> __m256 {
            _mm256_sqrt_ps(a)
        }
        #[inline(always)]
        unsafe fn abs(a: __m256) -> __m256 {
            _mm256_andnot_ps(_mm256_set1_ps(-0.0), a)
        }
        #[inline(always)]
        unsafe fn neg(a: __m256) -> __m256 {
            _mm256_xor_ps(_mm256_set1_ps(-0.0), a)
        }
        #[inline(always)]
        unsafe fn min(a: __m256, b: __m256) -> __m256 {
            _mm256_min_ps(a, b)
        }
        #[inline(always)]
        unsafe fn max(a: __m256, b: __m256) -> __m256 {
            _mm256_max_ps(a, b)
        }
        #[inline(always)]
        unsafe fn trunc(a: __m256) -> __m256i {
            _mm256_cvttps_epi32(a)
        }
        #[inline(always)]
        unsafe fn to_f(a: __m256i) -> __m256 {
            _mm256_cvtepi32_ps(a)
        }
        #[inline(always)]
        unsafe fn add_i(a: __m256i, b: __m256i) -> __m256i {
            _mm256_add_epi32(a, b)
        }
        #[inline(always)]
        unsafe fn mul_i(a: __m256i, b: __m256i) -> __m256i {
            _mm256_mullo_epi32(a, b)
        }
    };
}

/// The logic of masks held in mask registers ([`Avx512`], [`Avx512x8`]): plain integer bits.
macro_rules! mask_register_logic {
    ($m:ty) => {
        #[inline(always)]
        unsafe fn and(a: $m, b: $m) -> $m {
            a & b
        }
        #[inline(always)]
        unsafe fn or(a: $m, b: $m) -> $m {
            a | b
        }
        #[inline(always)]
        unsafe fn and_not(a: $m, b: $m) -> $m {
            a & !b
        }
        #[inline(always)]
        unsafe fn any(m: $m) -> bool {
            m != 0
        }
        #[inline(always)]
        unsafe fn bits(m: $m) -> u32 {
            u32::from(m)
        }
    };
}

// Each method is one intrinsic or two; the trait's contract (the tier) is what makes them
// sound, so per-call `unsafe` blocks would add nothing.
#[allow(unsafe_op_in_unsafe_fn)]
impl Lanes for Avx2 {
    const N: usize = 8;
    type F = __m256;
    type I = __m256i;
    type M = __m256;
    ymm_arithmetic!();
    #[inline(always)]
    unsafe fn lt(a: __m256, b: __m256) -> __m256 {
        _mm256_cmp_ps::<_CMP_LT_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn le(a: __m256, b: __m256) -> __m256 {
        _mm256_cmp_ps::<_CMP_LE_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn gt(a: __m256, b: __m256) -> __m256 {
        _mm256_cmp_ps::<_CMP_GT_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn ge(a: __m256, b: __m256) -> __m256 {
        _mm256_cmp_ps::<_CMP_GE_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn eq(a: __m256, b: __m256) -> __m256 {
        _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn ne(a: __m256, b: __m256) -> __m256 {
        _mm256_cmp_ps::<_CMP_NEQ_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn and(a: __m256, b: __m256) -> __m256 {
        _mm256_and_ps(a, b)
    }
    #[inline(always)]
    unsafe fn or(a: __m256, b: __m256) -> __m256 {
        _mm256_or_ps(a, b)
    }
    #[inline(always)]
    unsafe fn and_not(a: __m256, b: __m256) -> __m256 {
        _mm256_andnot_ps(b, a)
    }
    #[inline(always)]
    unsafe fn any(m: __m256) -> bool {
        _mm256_movemask_ps(m) != 0
    }
    #[inline(always)]
    unsafe fn bits(m: __m256) -> u32 {
        _mm256_movemask_ps(m) as u32
    }
    #[inline(always)]
    unsafe fn select(m: __m256, a: __m256, b: __m256) -> __m256 {
        _mm256_blendv_ps(b, a, m)
    }
    #[inline(always)]
    unsafe fn keep(m: __m256, v: __m256) -> __m256 {
        _mm256_and_ps(m, v)
    }
    #[inline(always)]
    unsafe fn gather(base: *const f32, idx: __m256i, m: __m256) -> __m256 {
        _mm256_mask_i32gather_ps::<4>(_mm256_setzero_ps(), base, idx, m)
    }
}

#[allow(unsafe_op_in_unsafe_fn)]
impl Lanes for Avx512 {
    const N: usize = 16;
    type F = __m512;
    type I = __m512i;
    type M = __mmask16;
    #[inline(always)]
    unsafe fn splat(x: f32) -> __m512 {
        _mm512_set1_ps(x)
    }
    #[inline(always)]
    unsafe fn splat_i(x: i32) -> __m512i {
        _mm512_set1_epi32(x)
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> __m512 {
        _mm512_loadu_ps(p)
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: __m512) {
        _mm512_storeu_ps(p, v)
    }
    #[inline(always)]
    unsafe fn add(a: __m512, b: __m512) -> __m512 {
        _mm512_add_ps(a, b)
    }
    #[inline(always)]
    unsafe fn sub(a: __m512, b: __m512) -> __m512 {
        _mm512_sub_ps(a, b)
    }
    #[inline(always)]
    unsafe fn mul(a: __m512, b: __m512) -> __m512 {
        _mm512_mul_ps(a, b)
    }
    #[inline(always)]
    unsafe fn div(a: __m512, b: __m512) -> __m512 {
        _mm512_div_ps(a, b)
    }
    #[inline(always)]
    unsafe fn sqrt(a: __m512) -> __m512 {
        _mm512_sqrt_ps(a)
    }
    #[inline(always)]
    unsafe fn abs(a: __m512) -> __m512 {
        _mm512_abs_ps(a)
    }
    #[inline(always)]
    unsafe fn neg(a: __m512) -> __m512 {
        _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), _mm512_set1_epi32(i32::MIN)))
    }
    #[inline(always)]
    unsafe fn min(a: __m512, b: __m512) -> __m512 {
        _mm512_min_ps(a, b)
    }
    #[inline(always)]
    unsafe fn max(a: __m512, b: __m512) -> __m512 {
        _mm512_max_ps(a, b)
    }
    #[inline(always)]
    unsafe fn lt(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn le(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn gt(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn ge(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_GE_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn eq(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn ne(a: __m512, b: __m512) -> __mmask16 {
        _mm512_cmp_ps_mask::<_CMP_NEQ_OQ>(a, b)
    }
    mask_register_logic!(__mmask16);
    #[inline(always)]
    unsafe fn select(m: __mmask16, a: __m512, b: __m512) -> __m512 {
        _mm512_mask_blend_ps(m, b, a)
    }
    #[inline(always)]
    unsafe fn keep(m: __mmask16, v: __m512) -> __m512 {
        _mm512_maskz_mov_ps(m, v)
    }
    #[inline(always)]
    unsafe fn trunc(a: __m512) -> __m512i {
        _mm512_cvttps_epi32(a)
    }
    #[inline(always)]
    unsafe fn to_f(a: __m512i) -> __m512 {
        _mm512_cvtepi32_ps(a)
    }
    #[inline(always)]
    unsafe fn add_i(a: __m512i, b: __m512i) -> __m512i {
        _mm512_add_epi32(a, b)
    }
    #[inline(always)]
    unsafe fn mul_i(a: __m512i, b: __m512i) -> __m512i {
        _mm512_mullo_epi32(a, b)
    }
    #[inline(always)]
    unsafe fn gather(base: *const f32, idx: __m512i, m: __mmask16) -> __m512 {
        _mm512_mask_i32gather_ps::<4>(_mm512_setzero_ps(), m, idx, base.cast())
    }
}

#[allow(unsafe_op_in_unsafe_fn)]
impl Lanes for Avx512x8 {
    const N: usize = 8;
    type F = __m256;
    type I = __m256i;
    type M = __mmask8;
    ymm_arithmetic!();
    mask_register_logic!(__mmask8);
    #[inline(always)]
    unsafe fn lt(a: __m256, b: __m256) -> __mmask8 {
        _mm256_cmp_ps_mask::<_CMP_LT_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn le(a: __m256, b: __m256) -> __mmask8 {
        _mm256_cmp_ps_mask::<_CMP_LE_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn gt(a: __m256, b: __m256) -> __mmask8 {
        _mm256_cmp_ps_mask::<_CMP_GT_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn ge(a: __m256, b: __m256) -> __mmask8 {
        _mm256_cmp_ps_mask::<_CMP_GE_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn eq(a: __m256, b: __m256) -> __mmask8 {
        _mm256_cmp_ps_mask::<_CMP_EQ_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn ne(a: __m256, b: __m256) -> __mmask8 {
        _mm256_cmp_ps_mask::<_CMP_NEQ_OQ>(a, b)
    }
    #[inline(always)]
    unsafe fn select(m: __mmask8, a: __m256, b: __m256) -> __m256 {
        _mm256_mask_blend_ps(m, b, a)
    }
    #[inline(always)]
    unsafe fn keep(m: __mmask8, v: __m256) -> __m256 {
        _mm256_maskz_mov_ps(m, v)
    }
    #[inline(always)]
    unsafe fn gather(base: *const f32, idx: __m256i, m: __mmask8) -> __m256 {
        _mm256_mmask_i32gather_ps::<4>(_mm256_setzero_ps(), m, idx, base)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Isa, Tier};

    /// Operands with the cases the operations' docs single out: signed zeros, NaN, infinities,
    /// and values that round.
    const A: [f32; 16] = [
        1.5,
        -0.0,
        0.0,
        f32::NAN,
        f32::INFINITY,
        -3.25,
        1e-30,
        7.0,
        -2.5,
        0.1,
        1e30,
        -1e-3,
        2.0,
        9.75,
        -7.0,
        0.3,
    ];
    const B: [f32; 16] = [
        1.5,
        0.0,
        -0.0,
        1.0,
        2.0,
        f32::NAN,
        3.0,
        -7.0,
        -2.5,
        0.7,
        -1e30,
        5.0,
        f32::NEG_INFINITY,
        9.5,
        4.0,
        0.3,
    ];

    type Predicate = fn(f32, f32) -> bool;

    /// Equal bits, or both NaN: a NaN's payload is not part of the operations' contract (the
    /// hardware's default NaN is negative, a constant-folded one positive).
    fn same_value(x: f32, y: f32) -> bool {
        x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan())
    }

    /// Every operation of tier `L` against its scalar definition, lane by lane, bit for bit (but
    /// NaN payloads); the names of those that differ.
    #[inline(always)]
    unsafe fn check<L: Lanes>() -> Vec<String> {
        let n = L::N;
        let mut bad = Vec::new();
        let mut out = [0.0f32; 16];
        // SAFETY: the caller provides `L`'s instruction set; the loads read `L::N <= 16`
        // values from the 16-element `A` and `B`, the stores write into the 16-element `out`.
        unsafe {
            let (a, b) = (L::load(A.as_ptr()), L::load(B.as_ptr()));
            let mut same = |name: &str, v: L::F, f: &dyn Fn(f32, f32) -> f32| {
                L::store(out.as_mut_ptr(), v);
                if (0..n).any(|j| !same_value(out[j], f(A[j], B[j]))) {
                    bad.push(name.to_string());
                }
            };
            same("add", L::add(a, b), &|x, y| x + y);
            same("sub", L::sub(a, b), &|x, y| x - y);
            same("mul", L::mul(a, b), &|x, y| x * y);
            same("div", L::div(a, b), &|x, y| x / y);
            same("sqrt", L::sqrt(a), &|x, _| x.sqrt());
            same("abs", L::abs(a), &|x, _| x.abs());
            same("neg", L::neg(a), &|x, _| -x);
            same("min", L::min(a, b), &|x, y| if x < y { x } else { y });
            same("max", L::max(a, b), &|x, y| if x > y { x } else { y });
            same("splat", L::splat(-0.0), &|_, _| -0.0);
            let lt = L::lt(a, b);
            let gt = L::gt(a, b);
            same("select", L::select(lt, a, b), &|x, y| if x < y { x } else { y });
            same("keep", L::keep(gt, a), &|x, y| if x > y { x } else { 0.0 });
            let i = L::trunc(L::min(L::max(a, L::splat(-100.0)), L::splat(100.0)));
            // `max(NaN, -100)` is `-100` (the instruction's rule).
            let t = |x: f32| if x.is_nan() { -100 } else { x.clamp(-100.0, 100.0) as i32 };
            same("trunc, to_f", L::to_f(i), &|x, _| t(x) as f32);
            same("add_i", L::to_f(L::add_i(i, L::splat_i(3))), &|x, _| (t(x) + 3) as f32);
            same("mul_i", L::to_f(L::mul_i(i, L::splat_i(-2))), &|x, _| (t(x) * -2) as f32);
            // Lane `j` reads `A[15 - j]` where `A[j] < B[j]`.
            let reversed: [f32; 16] = std::array::from_fn(|j| (15 - j) as f32);
            let idx = L::trunc(L::load(reversed.as_ptr()));
            let lt_ = |j: usize| A[j] < B[j];
            L::store(out.as_mut_ptr(), L::gather(A.as_ptr(), idx, lt));
            if (0..n).any(|j| !same_value(out[j], if lt_(j) { A[15 - j] } else { 0.0 })) {
                bad.push("gather".to_string());
            }
            let mut masks = Vec::new();
            let pred: [(&str, L::M, Predicate); 6] = [
                ("lt", lt, |x, y| x < y),
                ("le", L::le(a, b), |x, y| x <= y),
                ("gt", gt, |x, y| x > y),
                ("ge", L::ge(a, b), |x, y| x >= y),
                ("eq", L::eq(a, b), |x, y| x == y),
                ("ne", L::ne(a, b), |x, y| !x.is_nan() && !y.is_nan() && x != y),
            ];
            for (name, m, f) in pred {
                let want = (0..n).filter(|&j| f(A[j], B[j])).fold(0u32, |m, j| m | 1 << j);
                if L::bits(m) != want {
                    bad.push(name.to_string());
                }
                masks.push(want);
            }
            let (l, g) = (masks[0], masks[2]);
            if L::bits(L::and(lt, L::le(a, b))) != l
                || L::bits(L::or(lt, gt)) != l | g
                || L::bits(L::and_not(L::le(a, b), lt)) != masks[1] & !l
                || L::any(L::and(lt, gt))
                || !L::any(lt)
            {
                bad.push("and, or, and_not, any".to_string());
            }
        }
        bad
    }

    #[target_feature(enable = "avx2,f16c")]
    unsafe fn check_avx2() -> Vec<String> {
        // SAFETY: this function is compiled for AVX2, which its caller checked.
        unsafe { check::<Avx2>() }
    }

    #[target_feature(enable = "avx2,f16c,avx512f,avx512dq,avx512vl")]
    unsafe fn check_avx512() -> Vec<String> {
        // SAFETY: this function is compiled for AVX-512, which its caller checked.
        unsafe {
            let mut bad = check::<Avx512>();
            bad.extend(check::<Avx512x8>().into_iter().map(|b| format!("{b} (8 lanes)")));
            bad
        }
    }

    #[test]
    fn every_operation_of_every_tier_is_its_scalar_definition() {
        for isa in Isa::for_tests("lane operations") {
            // SAFETY: the tier's `Isa` exists, so the CPU runs it.
            let bad = unsafe {
                match isa.tier() {
                    Tier::Scalar => continue,
                    Tier::Avx2 => check_avx2(),
                    Tier::Avx512 => check_avx512(),
                }
            };
            assert!(bad.is_empty(), "{}: {bad:?}", isa.tier().name());
        }
    }
}
