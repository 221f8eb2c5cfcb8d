//! Exact sums of `f64` values, independent of the order of the terms.
//!
//! [`ExactSum`] is a fixed-point superaccumulator: every finite `f64` is an integer multiple
//! of `2^-1074` below `2^1024`, so the running sum is held exactly as a signed integer in
//! units of `2^-1074`, in 64-bit digits stored in `i128` limbs (the spare bits absorb carries,
//! which are propagated only when the value is read or two sums are merged). Adding integers
//! is associative and commutative, so the sum of the same terms is the same integer in any
//! order and under any grouping; [`ExactSum::value`] rounds it once, to nearest with ties to
//! even. Merging the partial sums of several parts therefore gives the bits of the single sum
//! over all terms, however the terms were split and in whatever order the parts are merged.

/// Number of 64-bit digits: a sum of up to `2^62` terms of any finite magnitude.
const LIMBS: usize = 35;
/// The low 64 bits of a limb.
const DIGIT_MASK: i128 = (1i128 << 64) - 1;
/// Additions after which the limbs are normalised (each adds less than `2^64` to a limb, so
/// an `i128` limb cannot overflow in between).
const NORMALISE_EVERY: u64 = 1 << 62;
/// Flag bits of the last word of [`ExactSum::to_words`].
const NAN_FLAG: u64 = 1;
const POSITIVE_INFINITY_FLAG: u64 = 2;
const NEGATIVE_INFINITY_FLAG: u64 = 4;

/// Exact sum of `f64` terms (see the module documentation): the same bits for the same terms
/// in any order and any grouping. A NaN term makes the sum NaN; infinities of both signs make
/// it NaN, of one sign that infinity; an exact zero reads as `+0.0`.
#[derive(Clone, Debug)]
pub struct ExactSum {
    /// The sum in units of `2^-1074`: `sum_j limbs[j] 2^(64 j)`.
    limbs: [i128; LIMBS],
    /// Additions since the last normalisation.
    pending: u64,
    /// NaN and infinity flags (`NAN_FLAG`, ...).
    flags: u64,
}

impl Default for ExactSum {
    fn default() -> Self {
        Self::new()
    }
}

impl PartialEq for ExactSum {
    /// Equal when the two sums hold the same value (whatever their internal carries).
    fn eq(&self, other: &Self) -> bool {
        self.to_words() == other.to_words()
    }
}

impl ExactSum {
    /// Number of `u64` words of [`ExactSum::to_words`].
    pub const WORDS: usize = LIMBS + 1;

    /// The empty sum (zero).
    pub fn new() -> Self {
        ExactSum {
            limbs: [0; LIMBS],
            pending: 0,
            flags: 0,
        }
    }

    /// Adds the term `x` exactly.
    pub fn add(&mut self, x: f64) {
        let bits = x.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as usize;
        let fraction = bits & ((1u64 << 52) - 1);
        if exponent == 0x7ff {
            self.flags |= if fraction != 0 {
                NAN_FLAG
            } else if x > 0.0 {
                POSITIVE_INFINITY_FLAG
            } else {
                NEGATIVE_INFINITY_FLAG
            };
            return;
        }
        // x = mantissa 2^(offset - 1074) for normal and subnormal numbers alike.
        let (mantissa, offset) = if exponent == 0 {
            (fraction, 0)
        } else {
            (fraction | (1u64 << 52), exponent - 1)
        };
        if mantissa == 0 {
            return;
        }
        let shifted = (mantissa as i128) << (offset % 64);
        let (low, high) = (shifted & DIGIT_MASK, shifted >> 64);
        let digit = offset / 64;
        if x < 0.0 {
            self.limbs[digit] -= low;
            self.limbs[digit + 1] -= high;
        } else {
            self.limbs[digit] += low;
            self.limbs[digit + 1] += high;
        }
        self.pending += 1;
        if self.pending == NORMALISE_EVERY {
            normalise(&mut self.limbs);
            self.pending = 0;
        }
    }

    /// Adds every term of `terms`.
    pub fn add_all(&mut self, terms: impl IntoIterator<Item = f64>) {
        for x in terms {
            self.add(x);
        }
    }

    /// Adds the terms of another sum (exactly: the result is the sum of both sets of terms).
    pub fn merge(&mut self, other: &ExactSum) {
        normalise(&mut self.limbs);
        let mut theirs = other.limbs;
        normalise(&mut theirs);
        for (mine, their) in self.limbs.iter_mut().zip(theirs) {
            *mine += their;
        }
        self.pending = 2;
        self.flags |= other.flags;
    }

    /// The sum rounded to the nearest `f64` (ties to even; beyond the largest finite value,
    /// an infinity).
    pub fn value(&self) -> f64 {
        if self.flags & NAN_FLAG != 0
            || self.flags & (POSITIVE_INFINITY_FLAG | NEGATIVE_INFINITY_FLAG)
                == POSITIVE_INFINITY_FLAG | NEGATIVE_INFINITY_FLAG
        {
            return f64::NAN;
        }
        if self.flags & POSITIVE_INFINITY_FLAG != 0 {
            return f64::INFINITY;
        }
        if self.flags & NEGATIVE_INFINITY_FLAG != 0 {
            return f64::NEG_INFINITY;
        }
        let mut limbs = self.limbs;
        normalise(&mut limbs);
        let negative = limbs[LIMBS - 1] < 0;
        if negative {
            for limb in limbs.iter_mut() {
                *limb = -*limb;
            }
            normalise(&mut limbs);
        }
        let magnitude = magnitude_to_f64(&limbs);
        if negative {
            -magnitude
        } else {
            magnitude
        }
    }

    /// The sum as words, for sending between processes: the normalised digits (the last one
    /// signed) and a word of NaN and infinity flags. [`ExactSum::from_words`] restores it.
    pub fn to_words(&self) -> [u64; Self::WORDS] {
        let mut limbs = self.limbs;
        normalise(&mut limbs);
        let mut words = [0u64; Self::WORDS];
        for (word, limb) in words.iter_mut().zip(limbs) {
            *word = limb as u64; // two's complement: the signed top digit survives
        }
        words[LIMBS] = self.flags;
        words
    }

    /// The sum written by [`ExactSum::to_words`].
    pub fn from_words(words: &[u64; Self::WORDS]) -> Self {
        let mut sum = ExactSum::new();
        for (limb, &word) in sum.limbs.iter_mut().zip(words).take(LIMBS - 1) {
            *limb = word as i128;
        }
        sum.limbs[LIMBS - 1] = words[LIMBS - 1] as i64 as i128;
        sum.flags = words[LIMBS];
        sum.pending = 1;
        sum
    }
}

/// The exact sum of `terms`, rounded once (see [`ExactSum`]).
pub fn exact_sum(terms: impl IntoIterator<Item = f64>) -> f64 {
    let mut sum = ExactSum::new();
    sum.add_all(terms);
    sum.value()
}

/// Propagates carries so that every limb but the last lies in `[0, 2^64)`; the last one
/// carries the sign of the whole.
fn normalise(limbs: &mut [i128; LIMBS]) {
    for j in 0..LIMBS - 1 {
        let carry = limbs[j] >> 64;
        limbs[j] &= DIGIT_MASK;
        limbs[j + 1] += carry;
    }
}

/// The non-negative normalised integer `limbs` (units of `2^-1074`) rounded to an `f64`.
fn magnitude_to_f64(limbs: &[i128; LIMBS]) -> f64 {
    let Some(top) = (0..LIMBS).rev().find(|&j| limbs[j] != 0) else {
        return 0.0;
    };
    let digit = |j: usize| limbs[j] as u64;
    if top == 0 {
        // Below 2^64 units: the conversion rounds once; the scaling is exact (a result
        // under 2^53 units is a subnormal or small normal number held exactly).
        return times_power_of_two(digit(0) as f64, -1074);
    }
    // The leading 128 bits, then a sticky bit for anything below them: the single rounding
    // of the u128 conversion is then the correct rounding of the whole integer.
    let lead = digit(top).leading_zeros();
    let upper = ((digit(top) as u128) << 64) | digit(top - 1) as u128;
    let below = if top >= 2 { digit(top - 2) } else { 0 };
    let (mut significant, left_out) = if lead == 0 {
        (upper, below)
    } else {
        (
            (upper << lead) | (below >> (64 - lead)) as u128,
            below << lead,
        )
    };
    if left_out != 0 || limbs[..top.saturating_sub(2)].iter().any(|&l| l != 0) {
        significant |= 1;
    }
    let exponent = 64 * (top as i32 - 1) - lead as i32 - 1074;
    times_power_of_two(significant as f64, exponent)
}

/// `x 2^e`, in steps that stay in the normal range on the way to the result (exact whenever
/// the result is representable).
fn times_power_of_two(mut x: f64, mut e: i32) -> f64 {
    let power = |k: i32| f64::from_bits(((k + 1023) as u64) << 52);
    while e > 1000 {
        x *= power(1000);
        e -= 1000;
    }
    while e < -1000 {
        x *= power(-1000);
        e += 1000;
    }
    x * power(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomposition::test_support::XorShift;

    /// Values spanning 600 orders of magnitude, both signs, with exact cancellations.
    fn mixed_magnitudes(rng: &mut XorShift, n: usize) -> Vec<f64> {
        let mut values: Vec<f64> = (0..n)
            .map(|_| {
                let magnitude = 10f64.powi(rng.below(600) as i32 - 300);
                (rng.uniform() - 0.5) * magnitude
            })
            .collect();
        values.push(1e300);
        values.push(-1e300);
        values.push(f64::from_bits(3)); // a subnormal
        values
    }

    #[test]
    fn split_over_parts_in_any_order_gives_the_same_bits() {
        let mut rng = XorShift::new(17);
        let values = mixed_magnitudes(&mut rng, 5000);
        let reference = exact_sum(values.iter().copied());
        let mut naive_results = Vec::new();
        for trial in 0..40 {
            let parts = 1 + trial % 4;
            let mut shuffled = values.clone();
            rng.shuffle(&mut shuffled);
            naive_results.push(shuffled.iter().sum::<f64>().to_bits());
            // Random split points, then the parts merged in a random order.
            let mut partials: Vec<ExactSum> = (0..parts).map(|_| ExactSum::new()).collect();
            for &x in &shuffled {
                partials[rng.below(parts as u64) as usize].add(x);
            }
            rng.shuffle(&mut partials);
            let mut total = ExactSum::new();
            for partial in &partials {
                total.merge(partial);
            }
            assert_eq!(
                total.value().to_bits(),
                reference.to_bits(),
                "trial {trial}"
            );
            // Through the words sent between processes as well.
            let mut from_words = ExactSum::new();
            for partial in &partials {
                from_words.merge(&ExactSum::from_words(&partial.to_words()));
            }
            assert_eq!(from_words.value().to_bits(), reference.to_bits());
        }
        naive_results.sort_unstable();
        naive_results.dedup();
        assert!(
            naive_results.len() > 1,
            "the data must be order-sensitive for a plain sum, or the test proves nothing"
        );
    }

    #[test]
    fn rounds_the_exact_integer_sum_correctly() {
        // Terms m 2^e with e in [-30, 20]: their exact sum is an integer in units of 2^-30
        // that an i128 holds, and i128 -> f64 rounds to nearest, ties to even.
        let mut rng = XorShift::new(5);
        for _ in 0..200 {
            let mut sum = ExactSum::new();
            let mut reference: i128 = 0;
            for _ in 0..1 + rng.below(50) {
                let m = rng.below(1 << 50) as i64 - (1 << 49);
                let e = rng.below(51) as i32 - 30;
                sum.add(m as f64 * 2f64.powi(e));
                reference += (m as i128) << (e + 30);
            }
            let expected = reference as f64 * 2f64.powi(-30);
            assert_eq!(sum.value().to_bits(), expected.to_bits(), "{reference}");
        }
    }

    #[test]
    fn cancellation_ties_subnormals_and_overflow() {
        assert_eq!(exact_sum([1e100, 1.0, -1e100]), 1.0);
        let two53 = 2f64.powi(53);
        assert_eq!(exact_sum([two53, 1.0]), two53, "a tie rounds to even");
        // Just above a tie: the extra term decides, whether it lies within the 128 leading
        // bits, in the digit partly read, or digits below.
        for nudge in [2f64.powi(-40), 2f64.powi(-100), 2f64.powi(-200)] {
            assert_eq!(exact_sum([two53, 1.0, nudge]), two53 + 2.0, "{nudge:e}");
            assert_eq!(exact_sum([two53, 1.0, -nudge]), two53, "{nudge:e}");
        }
        assert_eq!(
            exact_sum([two53 + 2.0, 1.0]),
            two53 + 4.0,
            "a tie rounds to even"
        );
        let tiny = f64::from_bits(1);
        assert_eq!(exact_sum([tiny, tiny, tiny]), f64::from_bits(3));
        assert_eq!(
            exact_sum([f64::MIN_POSITIVE, -tiny]).to_bits(),
            0x000f_ffff_ffff_ffff
        );
        assert_eq!(exact_sum([f64::MAX, f64::MAX]), f64::INFINITY);
        assert_eq!(exact_sum([f64::MAX, f64::MAX, -f64::MAX]), f64::MAX);
        assert_eq!(exact_sum([-f64::MAX, -f64::MAX]), f64::NEG_INFINITY);
        assert_eq!(exact_sum([-0.5, 0.25, -1e-300]), -0.25 - 1e-300);
        assert_eq!(exact_sum(Vec::new()), 0.0);
        assert_eq!(exact_sum([3.0, -3.0]).to_bits(), 0.0f64.to_bits());
    }

    #[test]
    fn nan_and_infinities() {
        assert!(exact_sum([1.0, f64::NAN]).is_nan());
        assert!(exact_sum([f64::INFINITY, f64::NEG_INFINITY]).is_nan());
        assert_eq!(exact_sum([f64::INFINITY, -1e308]), f64::INFINITY);
        let mut a = ExactSum::new();
        a.add(f64::NEG_INFINITY);
        let mut b = ExactSum::new();
        b.add(2.0);
        b.merge(&a);
        assert_eq!(b.value(), f64::NEG_INFINITY);
        assert_eq!(
            ExactSum::from_words(&b.to_words()).value(),
            f64::NEG_INFINITY
        );
    }

    #[test]
    fn equality_compares_values_not_carries() {
        let mut a = ExactSum::new();
        a.add_all([0.75, 0.25]);
        let mut b = ExactSum::new();
        b.add(1.0);
        assert_eq!(a, b);
        b.add(f64::from_bits(1));
        assert_ne!(a, b);
    }
}
