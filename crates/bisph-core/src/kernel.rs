//! Quintic Wendland (C2) kernel with support radius `2h`.
//!
//! `W(q) = alpha_d (1 - q/2)^4 (2q + 1)`, `q = |r|/h`, with `alpha_1 = 3 / (4 h)` (for the
//! 1-D wave check of paper 3), `alpha_2 = 7 / (4 pi h^2)` and `alpha_3 = 21 / (16 pi h^3)` so
//! that it integrates to one over the line / plane / space.
//! Its gradient is `grad W(r) = -5 alpha_d / h^2 (1 - q/2)^3 r`: a scalar factor times the
//! argument vector, with no division by `|r|`.

use crate::dim::Vector;
use std::f64::consts::PI;

/// The quintic Wendland kernel for a given smoothing length `h` and dimension `dim`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wendland {
    /// Smoothing length `h`.
    pub h: f64,
    /// Support radius `2h`.
    pub support: f64,
    inv_h: f64,
    alpha: f64,
    grad_alpha: f64,
}

impl Wendland {
    /// Kernel of smoothing length `h` in `dim` (1, 2 or 3) dimensions.
    pub fn new(h: f64, dim: usize) -> Self {
        let alpha = match dim {
            1 => 3.0 / (4.0 * h),
            2 => 7.0 / (4.0 * PI * h * h),
            _ => 21.0 / (16.0 * PI * h * h * h),
        };
        Wendland {
            h,
            support: 2.0 * h,
            inv_h: 1.0 / h,
            alpha,
            grad_alpha: -5.0 * alpha / (h * h),
        }
    }

    /// The constants of [`Wendland::gradient_factor`], `(1 / h, c)`: the factor is
    /// `c a a a` with `a = 1 - q / 2`, `q = r (1 / h)`, and 0 from `q = 2` on.
    pub(crate) fn gradient_constants(&self) -> (f64, f64) {
        (self.inv_h, self.grad_alpha)
    }

    /// Kernel of smoothing length `h` for vectors of type `V`.
    pub fn for_dim<V: Vector>(h: f64) -> Self {
        Self::new(h, V::DIM)
    }

    /// `W(r)` for a distance `r` (zero beyond the support).
    #[inline(always)]
    pub fn value(&self, r: f64) -> f64 {
        let q = r * self.inv_h;
        if q >= 2.0 {
            return 0.0;
        }
        let a = 1.0 - 0.5 * q;
        let a2 = a * a;
        self.alpha * a2 * a2 * (2.0 * q + 1.0)
    }

    /// [`Wendland::value`] computed without a branch (the polynomial, then zero selected
    /// beyond the support): the same bits for every finite `r`, and a form that a loop over
    /// several distances evaluates in vector lanes.
    #[inline(always)]
    pub fn value_or_zero(&self, r: f64) -> f64 {
        let q = r * self.inv_h;
        let a = 1.0 - 0.5 * q;
        let a2 = a * a;
        let w = self.alpha * a2 * a2 * (2.0 * q + 1.0);
        if q < 2.0 {
            w
        } else {
            0.0
        }
    }

    /// Factor `F` with `grad W(r) = F r` (`F <= 0`, zero beyond the support).
    #[inline(always)]
    pub fn gradient_factor(&self, r: f64) -> f64 {
        let q = r * self.inv_h;
        if q >= 2.0 {
            return 0.0;
        }
        let a = 1.0 - 0.5 * q;
        self.grad_alpha * a * a * a
    }

    /// [`Wendland::gradient_factor`] for `r` known to lie within the support (`r <= 2h`, as
    /// the neighbour searches guarantee): the same value without the test.
    #[inline(always)]
    pub fn gradient_factor_within(&self, r: f64) -> f64 {
        let a = 1.0 - 0.5 * (r * self.inv_h);
        self.grad_alpha * a * a * a
    }

    /// `grad W(r)`, the gradient of the kernel with respect to its argument `r`.
    #[inline(always)]
    pub fn gradient<V: Vector>(&self, r: V) -> V {
        r * self.gradient_factor(r.length())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec2, DVec3};

    /// Radial quadrature (composite Simpson) of `W` over the plane / space.
    fn integral(kernel: &Wendland, dim: usize) -> f64 {
        let n = 20_000;
        let dr = kernel.support / n as f64;
        let mut sum = 0.0;
        for k in 0..=n {
            let r = k as f64 * dr;
            let weight = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let shell = if dim == 2 {
                2.0 * PI * r
            } else {
                4.0 * PI * r * r
            };
            sum += weight * shell * kernel.value(r);
        }
        sum * dr / 3.0
    }

    #[test]
    fn integrates_to_one_in_2d_and_3d() {
        for h in [0.01, 0.37, 2.0] {
            assert!((integral(&Wendland::new(h, 2), 2) - 1.0).abs() < 1e-6);
            assert!((integral(&Wendland::new(h, 3), 3) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let k2 = Wendland::for_dim::<DVec2>(0.1);
        let k3 = Wendland::for_dim::<DVec3>(0.1);
        let eps = 1e-7;
        for &(x, y, z) in &[(0.03, -0.05, 0.07), (0.11, 0.02, -0.01), (0.001, 0.0, 0.0)] {
            let r2 = DVec2::new(x, y);
            let g2 = k2.gradient(r2);
            let fd2 = DVec2::new(
                k2.value((r2 + DVec2::X * eps).length()) - k2.value((r2 - DVec2::X * eps).length()),
                k2.value((r2 + DVec2::Y * eps).length()) - k2.value((r2 - DVec2::Y * eps).length()),
            ) / (2.0 * eps);
            assert!(
                (g2 - fd2).length() <= 1e-6 * g2.length().max(1.0),
                "{g2} {fd2}"
            );
            let r3 = DVec3::new(x, y, z);
            let g3 = k3.gradient(r3);
            let mut fd3 = DVec3::ZERO;
            for k in 0..3 {
                let mut e = DVec3::ZERO;
                e[k] = eps;
                fd3[k] = (k3.value((r3 + e).length()) - k3.value((r3 - e).length())) / (2.0 * eps);
            }
            assert!(
                (g3 - fd3).length() <= 1e-6 * g3.length().max(1.0),
                "{g3} {fd3}"
            );
        }
    }

    #[test]
    fn vanishes_at_and_beyond_the_support() {
        let k = Wendland::new(0.5, 2);
        assert_eq!(k.value(1.0), 0.0);
        assert_eq!(k.value(3.0), 0.0);
        assert_eq!(k.gradient_factor(1.0), 0.0);
        assert!(k.value(0.999_999) > 0.0);
    }

    /// Inside the support the untested factor has the bits of the tested one (the sweeps
    /// that use it give the same sums); at the support both vanish.
    #[test]
    fn factor_within_the_support_is_the_same() {
        for (h, dim) in [(0.5, 2), (0.013, 3), (1.7e-3, 2)] {
            let k = Wendland::new(h, dim);
            for step in 0..=10_000 {
                let r = k.support * step as f64 / 10_000.0;
                let (tested, within) = (k.gradient_factor(r), k.gradient_factor_within(r));
                assert!(tested == within, "h = {h}, r = {r}: {tested} vs {within}");
                if step < 10_000 {
                    assert_eq!(tested.to_bits(), within.to_bits(), "h = {h}, r = {r}");
                }
            }
        }
    }
}
