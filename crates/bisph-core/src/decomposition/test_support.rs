//! Pseudo-random data for the decomposition tests.

use crate::dim::Vector;

/// Marsaglia's xorshift64* generator: reproducible pseudo-random numbers from a seed.
pub struct XorShift(u64);

impl XorShift {
    /// A generator started from `seed` (any value; zero is replaced).
    pub fn new(seed: u64) -> Self {
        XorShift(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }

    /// The next 64 pseudo-random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform integer in `[0, n)` (`n > 0`).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }

    /// Fisher-Yates shuffle.
    pub fn shuffle<T>(&mut self, items: &mut [T]) {
        for k in (1..items.len()).rev() {
            let j = self.below(k as u64 + 1) as usize;
            items.swap(k, j);
        }
    }

    /// A point uniform in the box `[lo, hi)`.
    pub fn point_in<V: Vector>(&mut self, lo: V, hi: V) -> V {
        let mut x = V::ZERO;
        for k in 0..V::DIM {
            x.set(k, lo.get(k) + (hi.get(k) - lo.get(k)) * self.uniform());
        }
        x
    }
}
