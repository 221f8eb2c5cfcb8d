//! Equations of state `p(rho)` and the exact specific compression energy `e(rho)`
//! with `de/drho = p / rho^2` and `e(rho0) = 0`.

/// Equation of state of the weakly compressible fluid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Eos {
    /// Paper 1, eq 3: `p = p0 + c0^2 (rho - rho0)`.
    Linear {
        /// Reference density `rho0`.
        rho0: f64,
        /// Speed of sound `c0`.
        c0: f64,
        /// Background pressure `p0`.
        p0: f64,
    },
    /// Paper 3, eq 15 (Tait): `p = p0 + rho0 c0^2 / xi ((rho/rho0)^xi - 1)`.
    Tait {
        /// Reference density `rho0`.
        rho0: f64,
        /// Speed of sound `c0` at `rho0`.
        c0: f64,
        /// Background pressure `p0`.
        p0: f64,
        /// Exponent `xi` (7 for water).
        xi: f64,
    },
}

impl Eos {
    /// Reference density.
    pub fn rho0(&self) -> f64 {
        match *self {
            Eos::Linear { rho0, .. } | Eos::Tait { rho0, .. } => rho0,
        }
    }

    /// Reference speed of sound.
    pub fn c0(&self) -> f64 {
        match *self {
            Eos::Linear { c0, .. } | Eos::Tait { c0, .. } => c0,
        }
    }

    /// Pressure at density `rho`.
    #[inline(always)]
    pub fn pressure(&self, rho: f64) -> f64 {
        match *self {
            Eos::Linear { rho0, c0, p0 } => p0 + c0 * c0 * (rho - rho0),
            Eos::Tait { rho0, c0, p0, xi } => {
                p0 + rho0 * c0 * c0 / xi * (power(rho / rho0, xi) - 1.0)
            }
        }
    }

    /// Pressure above the background `p0` at depth `d` below a free surface at `p0` in
    /// hydrostatic equilibrium with this equation of state, `dp/dd = rho(p) g` (the density
    /// grows with depth), exactly: linear, `rho0 c0^2 (exp(g d / c0^2) - 1)`; Tait with
    /// `B = rho0 c0^2 / xi`, `B ((1 + (1 - 1/xi) rho0 g d / B)^(xi/(xi-1)) - 1)`.
    pub fn hydrostatic_pressure(&self, g: f64, depth: f64) -> f64 {
        match *self {
            Eos::Linear { rho0, c0, .. } => rho0 * c0 * c0 * (g * depth / (c0 * c0)).exp_m1(),
            Eos::Tait { rho0, c0, xi, .. } => {
                let b = rho0 * c0 * c0 / xi;
                b * ((1.0 + (1.0 - 1.0 / xi) * rho0 * g * depth / b).powf(xi / (xi - 1.0)) - 1.0)
            }
        }
    }

    /// Density at pressure `p` (inverse of [`Eos::pressure`]); `None` where no density gives `p`.
    pub fn density(&self, p: f64) -> Option<f64> {
        let rho = match *self {
            Eos::Linear { rho0, c0, p0 } => rho0 + (p - p0) / (c0 * c0),
            Eos::Tait { rho0, c0, p0, xi } => {
                let base = 1.0 + xi * (p - p0) / (rho0 * c0 * c0);
                if base <= 0.0 {
                    return None;
                }
                rho0 * base.powf(1.0 / xi)
            }
        };
        (rho > 0.0 && rho.is_finite()).then_some(rho)
    }

    /// Specific internal (compression) energy `e(rho) = int_{rho0}^{rho} p / r^2 dr`.
    ///
    /// Linear: `e = c0^2 (rho0/rho - 1 + ln(rho/rho0)) + p0 (1/rho0 - 1/rho)`.
    /// Tait, with `B = rho0 c0^2 / xi`:
    /// `e = B [((rho/rho0)^(xi-1) - 1) / ((xi-1) rho0) + 1/rho - 1/rho0] + p0 (1/rho0 - 1/rho)`.
    pub fn specific_energy(&self, rho: f64) -> f64 {
        match *self {
            Eos::Linear { rho0, c0, p0 } => {
                c0 * c0 * (rho0 / rho - 1.0 + (rho / rho0).ln()) + p0 * (1.0 / rho0 - 1.0 / rho)
            }
            Eos::Tait { rho0, c0, p0, xi } => {
                let b = rho0 * c0 * c0 / xi;
                b * (((rho / rho0).powf(xi - 1.0) - 1.0) / ((xi - 1.0) * rho0) + 1.0 / rho
                    - 1.0 / rho0)
                    + p0 * (1.0 / rho0 - 1.0 / rho)
            }
        }
    }

    /// The hydrostatic density gradient at density `rho` over its value at `rho0`:
    /// `dp = rho g dd` and `dp = c(rho)^2 drho` give `drho/dd = rho g / c(rho)^2`, which is
    /// `(rho0 g / c0^2)` times `rho c0^2 / (rho0 c(rho)^2)`: linear, `rho / rho0`; Tait,
    /// `(rho / rho0)^(2 - xi)`.
    #[inline(always)]
    pub fn hydrostatic_density_factor(&self, rho: f64) -> f64 {
        match *self {
            Eos::Linear { rho0, .. } => rho / rho0,
            Eos::Tait { rho0, xi, .. } => power(rho / rho0, 2.0 - xi),
        }
    }

    /// Sound speed at density `rho`, `sqrt(dp/drho)`.
    pub fn sound_speed(&self, rho: f64) -> f64 {
        match *self {
            Eos::Linear { c0, .. } => c0,
            Eos::Tait { rho0, c0, xi, .. } => c0 * power(rho / rho0, 0.5 * (xi - 1.0)),
        }
    }
}

/// `x^e` for Tait's equation, kept out of line: `powf` is an intrinsic that the optimiser may
/// evaluate ahead of the `match` selecting it, which made a linear equation of state pay for
/// the power in every pair of the fluid sweep.
#[inline(never)]
fn power(x: f64, e: f64) -> f64 {
    x.powf(e)
}

#[cfg(test)]
mod tests {
    /// The exact hydrostatic profile satisfies `dp/dd = rho(p) g` (central differences).
    #[test]
    fn hydrostatic_profile_balances_the_density() {
        for eos in [
            super::Eos::Linear {
                rho0: 1000.0,
                c0: 10.0,
                p0: 0.0,
            },
            super::Eos::Tait {
                rho0: 1000.0,
                c0: 10.0,
                p0: 0.0,
                xi: 7.0,
            },
        ] {
            let (g, step) = (9.81, 1e-4);
            for d in [0.1, 0.5, 1.0] {
                let slope = (eos.hydrostatic_pressure(g, d + step)
                    - eos.hydrostatic_pressure(g, d - step))
                    / (2.0 * step);
                let rho = eos.density(eos.hydrostatic_pressure(g, d)).unwrap();
                assert!((slope / (rho * g) - 1.0).abs() < 1e-8, "{eos:?} {d}");
                let density_at = |d: f64| eos.density(eos.hydrostatic_pressure(g, d)).unwrap();
                let density_slope = (density_at(d + step) - density_at(d - step)) / (2.0 * step);
                let (rho0, c0) = (eos.rho0(), eos.c0());
                let factor = density_slope / (rho0 * g / (c0 * c0));
                assert!(
                    (factor / eos.hydrostatic_density_factor(rho) - 1.0).abs() < 1e-7,
                    "{eos:?} {d}: {factor}"
                );
            }
            assert_eq!(eos.hydrostatic_pressure(g, 0.0), 0.0);
        }
    }
    use super::*;

    fn check(eos: Eos) {
        let rho0 = eos.rho0();
        assert_eq!(eos.specific_energy(rho0), 0.0);
        for f in [0.97, 0.999, 1.0, 1.003, 1.05] {
            let rho = rho0 * f;
            let d = 1e-6 * rho0;
            let de = (eos.specific_energy(rho + d) - eos.specific_energy(rho - d)) / (2.0 * d);
            let expected = eos.pressure(rho) / (rho * rho);
            assert!(
                (de - expected).abs() < 1e-6 * (1.0 + expected.abs()),
                "{eos:?} {f}"
            );
            let back = eos.density(eos.pressure(rho)).unwrap();
            assert!((back - rho).abs() < 1e-9 * rho0);
        }
    }

    #[test]
    fn energy_derivative_is_p_over_rho_squared() {
        check(Eos::Linear {
            rho0: 1000.0,
            c0: 20.0,
            p0: 0.0,
        });
        check(Eos::Linear {
            rho0: 1.0,
            c0: 1.0,
            p0: 0.015,
        });
        check(Eos::Tait {
            rho0: 998.0,
            c0: 30.0,
            p0: 0.0,
            xi: 7.0,
        });
        check(Eos::Tait {
            rho0: 1.0,
            c0: 2.0,
            p0: 0.5,
            xi: 7.0,
        });
    }
}
