//! Gauss-Legendre quadrature shared by the wall integrals and their tests.

/// 8-point Gauss-Legendre nodes (positive half) on `[-1, 1]`.
pub const GL_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];

/// Their weights.
pub const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// Composite 8-point Gauss-Legendre rule of `f` over `[a, b]` with `panels` equal panels.
pub fn gauss_legendre(a: f64, b: f64, panels: usize, mut f: impl FnMut(f64) -> f64) -> f64 {
    let width = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * width;
        for k in 0..4 {
            let d = 0.5 * width * GL_X[k];
            sum += GL_W[k] * 0.5 * width * (f(mid - d) + f(mid + d));
        }
    }
    sum
}

/// One 8-point Gauss-Legendre panel over `[a, b]`.
fn gauss_panel(a: f64, b: f64, f: &mut impl FnMut(f64) -> f64) -> f64 {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let mut sum = 0.0;
    for k in 0..4 {
        let d = half * GL_X[k];
        sum += GL_W[k] * half * (f(mid - d) + f(mid + d));
    }
    sum
}

/// Adaptive 8-point Gauss-Legendre quadrature of `f` over `[a, b]` to the absolute
/// `tolerance`: a panel is halved (to depth 40) until the two halves agree with the whole to
/// within the panel's share of the tolerance. For integrands that are smooth except at a few
/// points (kinks, `s^4 log s` terms), where the halving concentrates.
pub fn adaptive_gauss_legendre(
    a: f64,
    b: f64,
    tolerance: f64,
    f: &mut impl FnMut(f64) -> f64,
) -> f64 {
    fn refine(
        a: f64,
        b: f64,
        whole: f64,
        tolerance: f64,
        depth: u32,
        f: &mut impl FnMut(f64) -> f64,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (left, right) = (gauss_panel(a, m, f), gauss_panel(m, b, f));
        if depth == 0 || (left + right - whole).abs() <= tolerance {
            return left + right;
        }
        refine(a, m, left, 0.5 * tolerance, depth - 1, f)
            + refine(m, b, right, 0.5 * tolerance, depth - 1, f)
    }
    let whole = gauss_panel(a, b, f);
    refine(a, b, whole, tolerance, 40, f)
}

#[cfg(test)]
mod tests {
    #[test]
    fn adaptive_rule_handles_a_kink_and_a_log_singularity() {
        let got = super::adaptive_gauss_legendre(-1.0, 2.0, 1e-13, &mut |x: f64| x.abs());
        assert!((got - 2.5).abs() < 1e-12, "{got}");
        // int_0^1 x^4 ln x dx = -1/25
        let got = super::adaptive_gauss_legendre(0.0, 1.0, 1e-13, &mut |x: f64| {
            if x > 0.0 {
                x.powi(4) * x.ln()
            } else {
                0.0
            }
        });
        assert!((got + 0.04).abs() < 1e-12, "{got}");
    }

    #[test]
    fn integrates_polynomials_of_degree_15_exactly() {
        let exact = 1.0 / 16.0;
        let got = super::gauss_legendre(0.0, 1.0, 1, |x| x.powi(15));
        assert!((got - exact).abs() < 1e-15);
    }
}
