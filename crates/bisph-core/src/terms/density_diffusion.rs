//! Density (volume) diffusion in the continuity equation, fluid neighbours only (no wall
//! term: `drho/dn = 0` at walls, paper 3 section 4.2), in two forms:
//! - Laplacian (Morris) form: delta-SPH (Molteni & Colagrossi 2009) with
//!   `scale = delta h c0`, or Mayrhofer's volume diffusion (paper 3, eqs 44 and 48) with
//!   `scale = K = c0 dx / eta`: `D_i = 2 scale sum_j rho~_ij (r_ij . grad_i W_ij / r_ij^2) V_j`;
//! - Riemann form (Ferrari et al., paper 3, eqs 49-51 and 54):
//!   `D_i = scale sum_j c_ij rho~_ij (r_ij / r_ij) . grad_i W_ij V_j`, `c_ij = max(c_i, c_j)`,
//!   `c_i` the sound speed of the equation of state at `rho_i`.
//!
//! `rho~_ij = rho_i - rho_j` or, with the hydrostatic correction (paper 3, eq 81; Fourtakas et
//! al. 2019 for delta-SPH), `rho_i - rho_j + (rho_j^H - rho_i^H)` with the hydrostatic density
//! difference of the equation of state, `rho_j^H - rho_i^H = rho g . (r_j - r_i) / c(rho)^2`
//! at the pair's mean density (denser below; `rho0 g . r_ij / c0^2` times
//! [`Eos::hydrostatic_density_factor`]). With `rho0 / c0^2` in place of `rho / c(rho)^2`
//! the term would hold the density to a profile the momentum equation does not balance: with
//! Tait's equation (`xi = 7`) the pressure at a depth `d` would sit `3 rho0 (g d)^2 / c0^2`
//! above its hydrostatic value.

use crate::dim::Vector;
use crate::eos::Eos;

/// Which form the diffusion takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DiffusionForm {
    /// Laplacian form (delta-SPH, or paper 3 eq 44).
    Laplacian,
    /// Riemann form of paper 3, eqs 49-51, with the sound speed of `eos`.
    Riemann(Eos),
}

/// Coefficients of the diffusion term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensityDiffusion<V: Vector> {
    /// `delta h c0`, `K`, or the Riemann form's dimensionless coefficient (zero switches the
    /// term off).
    pub scale: f64,
    /// `rho0 g / c0^2` when the hydrostatic correction is on, else zero.
    pub hydrostatic_gradient: V,
    /// The equation of state, for the hydrostatic density difference.
    pub eos: Eos,
    /// The form of the term.
    pub form: DiffusionForm,
}

impl<V: Vector> DensityDiffusion<V> {
    /// One pair's contribution. `gradient_factor` is `F` of `grad W(r) = F r` at `r = |r_ij|`,
    /// `r_ij = r_j - r_i`, so `r_ij . grad_i W_ij = -F r^2`.
    #[inline(always)]
    pub fn pair(
        &self,
        rho_i: f64,
        rho_j: f64,
        r_ij: V,
        r: f64,
        gradient_factor: f64,
        volume_j: f64,
    ) -> f64 {
        self.pair_sides(rho_i, rho_j, r_ij, r, gradient_factor, [0.0, volume_j])
            .0
    }

    /// One pair's contributions to both particles, `(to i, to j)`, with `volume = [V_i, V_j]`:
    /// `rho~_ji = -rho~_ij`, so the term is antisymmetric (`V_i D_i = -V_j D_j` pair by pair,
    /// each the bits its own particle's sum would add).
    #[inline(always)]
    pub fn pair_sides(
        &self,
        rho_i: f64,
        rho_j: f64,
        r_ij: V,
        r: f64,
        gradient_factor: f64,
        volume: [f64; 2],
    ) -> (f64, f64) {
        // excess = -rho~_ij = (rho_j - rho_i) - (rho_j^H - rho_i^H).
        let mut hydrostatic = self.hydrostatic_gradient.dot(r_ij);
        if hydrostatic != 0.0 {
            hydrostatic *= self.eos.hydrostatic_density_factor(0.5 * (rho_i + rho_j));
        }
        let excess = (rho_j - rho_i) - hydrostatic;
        let e = match self.form {
            DiffusionForm::Laplacian => -2.0 * self.scale * excess * gradient_factor,
            DiffusionForm::Riemann(eos) => {
                let c = eos.sound_speed(rho_i).max(eos.sound_speed(rho_j));
                -self.scale * c * excess * gradient_factor * r
            }
        };
        (e * volume[1], -(e * volume[0]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Wendland;
    use glam::DVec2;

    /// The hydrostatic density profile of the equation of state gives no diffusion with the
    /// correction, for both forms and both equations of state, where the uncorrected term and
    /// a correction with the gradient at `rho0` leave a residue.
    #[test]
    fn hydrostatic_density_does_not_diffuse() {
        let (rho0, c0, g) = (1000.0, 20.0, DVec2::new(0.0, -9.81));
        let kernel = Wendland::new(0.02, 2);
        for eos in [
            Eos::Linear { rho0, c0, p0: 0.0 },
            Eos::Tait {
                rho0,
                c0,
                xi: 7.0,
                p0: 0.0,
            },
        ] {
            // Water 2 m deep, surface at y = 2: denser below.
            let rho = |x: DVec2| {
                eos.density(eos.hydrostatic_pressure(9.81, 2.0 - x.y))
                    .unwrap()
            };
            let xi = DVec2::new(0.1, 0.3);
            for form in [DiffusionForm::Laplacian, DiffusionForm::Riemann(eos)] {
                let d = DensityDiffusion {
                    scale: 1.0,
                    hydrostatic_gradient: g * (rho0 / (c0 * c0)),
                    eos,
                    form,
                };
                let plain = DensityDiffusion {
                    hydrostatic_gradient: DVec2::ZERO,
                    ..d
                };
                let (mut sum, mut uncorrected, mut frozen) = (0.0, 0.0, 0.0);
                for k in -3..=3 {
                    for l in 1..=3 {
                        let xj = xi + DVec2::new(k as f64, l as f64) * 0.01;
                        let r_ij = xj - xi;
                        let r = r_ij.length();
                        let f = kernel.gradient_factor(r);
                        let (a, b) = (rho(xi), rho(xj));
                        sum += d.pair(a, b, r_ij, r, f, 1e-4);
                        uncorrected += plain.pair(a, b, r_ij, r, f, 1e-4);
                        // The same difference about rho0, where the factor is 1: the
                        // correction with the gradient at rho0.
                        frozen += d.pair(rho0, rho0 + b - a, r_ij, r, f, 1e-4);
                    }
                }
                assert!(
                    sum.abs() < 1e-6 * uncorrected.abs(),
                    "{eos:?}: {sum} vs {uncorrected}"
                );
                assert!(
                    frozen.abs() > 1e-3 * uncorrected.abs(),
                    "{eos:?}: {frozen} vs {uncorrected}"
                );
            }
        }
    }
}
