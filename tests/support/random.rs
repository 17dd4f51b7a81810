//! Deterministic pseudo-random numbers for the tests' random inputs (the same sequence on every
//! run and platform): an LCG, SplitMix64 and xorshift64. `tests/corpus` includes this file by path.
#![allow(dead_code)]

/// A 64-bit linear congruential generator (Knuth's MMIX constants), uniform in [0, 1).
pub struct Lcg(pub u64);

impl Lcg {
    /// The next value, uniform in [0, 1) (the upper 53 bits of the state).
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Log-uniform in [lo, hi).
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + self.next() * (hi.ln() - lo.ln())).exp()
    }

    /// One of `values`, uniformly.
    pub fn pick<T: Copy>(&mut self, values: &[T]) -> T {
        values[((self.next() * values.len() as f64) as usize).min(values.len() - 1)]
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014), uniform in [0, 1).
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next value, uniform in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Marsaglia's xorshift64 (Marsaglia 2003; shifts 13, 7, 17), uniform in [−1, 1): the random
/// harmonic inputs of the contact-law tests.
pub struct XorShift(pub u64);

impl XorShift {
    /// Uniform in [−1, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    /// `n` values uniform in [−scale, scale).
    pub fn vec(&mut self, n: usize, scale: f64) -> Vec<f64> {
        (0..n).map(|_| scale * self.uniform()).collect()
    }
}
