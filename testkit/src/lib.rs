//! hyrt-testkit: what the tests and benchmarks of every hyrt crate share (a dev-dependency
//! only): one deterministic PRNG for their random inputs.
//!
//! ```
//! let mut rng = hyrt_testkit::Rng(7);
//! let (a, b) = (rng.f32(), rng.f64());
//! assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
//! assert!(rng.below(3) < 3);
//! assert_eq!(hyrt_testkit::Rng(7).f32(), a, "the same seed gives the same numbers");
//! ```

/// xorshift64* (Vigna 2016): a seeded, deterministic generator, good enough for test inputs
/// and synthetic scenes, and the same on every machine. The state must not be 0.
#[derive(Clone, Debug)]
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in `[0, 1)`, with 24 random bits.
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[0, 1)`, with 53 random bits.
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// An integer in `0..n` (`n > 0`; the modulo bias is negligible for test inputs).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}
