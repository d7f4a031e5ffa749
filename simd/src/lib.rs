//! hyrt-simd: which vector instruction set this CPU runs, detected once for every crate.
//!
//! The kernels of the rasterizer, the tracer and the renderer come in three [`Tier`]s: scalar
//! (the reference, everywhere), AVX2 and AVX-512, each vector kernel computing the scalar
//! kernel's result bit for bit. A tier is one feature set for all of them:
//! - [`Tier::Avx2`]: AVX2 and F16C (every AVX2 CPU has both);
//! - [`Tier::Avx512`]: the AVX2 tier and AVX-512 F, DQ and VL.
//!
//! An [`Isa`] is a tier that detection found: its field is private, so only [`Isa::best`],
//! [`Isa::available`] and [`Isa::of`] make one, and a kernel given an `Isa` of some tier may
//! use that tier's instructions. The `unsafe` calls into `#[target_feature]` functions rely on
//! exactly that.
//!
//! ```
//! use hyrt_simd::{Isa, Tier};
//!
//! let best = Isa::best();
//! assert!(Isa::available().contains(&best));
//! assert_eq!(Isa::available()[0], Isa::SCALAR);
//! // An AVX-512 token exists only where the CPU has AVX-512 (and then AVX2 too).
//! if let Some(isa) = Isa::of(Tier::Avx512) {
//!     assert!(isa <= best && Isa::of(Tier::Avx2).is_some());
//! }
//! ```

use std::sync::OnceLock;

#[cfg(target_arch = "x86_64")]
pub mod lanes;

/// A set of vector instructions, narrowest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Tier {
    /// No vector instructions beyond the baseline: the reference kernels.
    Scalar,
    /// AVX2 and F16C: 8 lanes of 32 bits.
    Avx2,
    /// The AVX2 tier and AVX-512 F, DQ and VL: 16 lanes of 32 bits, masks.
    Avx512,
}

impl Tier {
    /// Every tier, narrowest first.
    pub const ALL: [Tier; 3] = [Tier::Scalar, Tier::Avx2, Tier::Avx512];

    /// The tier's name in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Tier::Scalar => "scalar",
            Tier::Avx2 => "avx2",
            Tier::Avx512 => "avx512",
        }
    }

    /// Whether this CPU runs the tier's instructions.
    fn detected(self) -> bool {
        match self {
            Tier::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Tier::Avx2 => {
                use std::arch::is_x86_feature_detected as has;
                has!("avx2") && has!("f16c")
            }
            #[cfg(target_arch = "x86_64")]
            Tier::Avx512 => {
                use std::arch::is_x86_feature_detected as has;
                Tier::Avx2.detected() && has!("avx512f") && has!("avx512dq") && has!("avx512vl")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }
}

/// A [`Tier`] that this CPU runs: only detection makes one (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Isa(Tier);

impl Isa {
    /// The scalar tier, which every CPU runs.
    pub const SCALAR: Isa = Isa(Tier::Scalar);

    /// The tier.
    pub fn tier(self) -> Tier {
        self.0
    }

    /// `tier`, if this CPU runs it.
    pub fn of(tier: Tier) -> Option<Isa> {
        Isa::available().into_iter().find(|i| i.0 == tier)
    }

    /// Every tier this CPU runs, narrowest first (the scalar one always), detected once.
    pub fn available() -> Vec<Isa> {
        static AVAILABLE: OnceLock<Vec<Isa>> = OnceLock::new();
        AVAILABLE.get_or_init(|| Tier::ALL.into_iter().filter(|t| t.detected()).map(Isa).collect()).clone()
    }

    /// The widest tier this CPU runs. Valgrind reports no AVX-512 to the programs it runs, so
    /// under it this is the AVX2 tier.
    pub fn best() -> Isa {
        static BEST: OnceLock<Isa> = OnceLock::new();
        *BEST.get_or_init(|| *Isa::available().last().expect("the scalar tier is always there"))
    }

    /// The tiers a kernel test covers on this CPU, with a line on standard error naming the
    /// vector tiers it cannot run here (so a host without AVX-512 says that it skipped it).
    pub fn for_tests(what: &str) -> Vec<Isa> {
        let have = Isa::available();
        for t in Tier::ALL.into_iter().filter(|t| !have.iter().any(|i| i.0 == *t)) {
            eprintln!("{what}: the {} kernel is skipped: this CPU does not run it", t.name());
        }
        have
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiers_are_nested_and_the_best_is_the_widest() {
        let a = Isa::available();
        assert_eq!(a[0], Isa::SCALAR);
        assert!(a.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(Isa::best(), *a.last().unwrap());
        if Isa::of(Tier::Avx512).is_some() {
            assert!(Isa::of(Tier::Avx2).is_some(), "AVX-512 implies the AVX2 tier");
        }
        assert_eq!(Isa::of(Tier::Scalar), Some(Isa::SCALAR));
    }
}
