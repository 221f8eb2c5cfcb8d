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

#[cfg(test)]
mod tests {
    #[test]
    fn integrates_polynomials_of_degree_15_exactly() {
        let exact = 1.0 / 16.0;
        let got = super::gauss_legendre(0.0, 1.0, 1, |x| x.powi(15));
        assert!((got - exact).abs() < 1e-15);
    }
}
