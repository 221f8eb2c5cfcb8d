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
//! difference `rho_j^H - rho_i^H = rho0 g . (r_j - r_i) / c0^2` (denser below).

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
        // excess = -rho~_ij = (rho_j - rho_i) - (rho_j^H - rho_i^H).
        let excess = (rho_j - rho_i) - self.hydrostatic_gradient.dot(r_ij);
        match self.form {
            DiffusionForm::Laplacian => -2.0 * self.scale * excess * gradient_factor * volume_j,
            DiffusionForm::Riemann(eos) => {
                let c = eos.sound_speed(rho_i).max(eos.sound_speed(rho_j));
                -self.scale * c * excess * gradient_factor * r * volume_j
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Wendland;
    use glam::DVec2;

    /// A hydrostatic density field gives no diffusion with the correction, for both forms.
    #[test]
    fn hydrostatic_density_does_not_diffuse() {
        let (rho0, c0, g) = (1000.0, 20.0, DVec2::new(0.0, -9.81));
        let kernel = Wendland::new(0.02, 2);
        let rho = |x: DVec2| rho0 + rho0 * g.dot(x) / (c0 * c0);
        let xi = DVec2::new(0.1, 0.3);
        let eos = Eos::Tait {
            rho0,
            c0,
            xi: 7.0,
            p0: 0.0,
        };
        for form in [DiffusionForm::Laplacian, DiffusionForm::Riemann(eos)] {
            let d = DensityDiffusion {
                scale: 1.0,
                hydrostatic_gradient: g * (rho0 / (c0 * c0)),
                form,
            };
            let mut sum = 0.0;
            let mut uncorrected = 0.0;
            for k in -3..=3 {
                for l in 1..=3 {
                    let xj = xi + DVec2::new(k as f64, l as f64) * 0.01;
                    let r_ij = xj - xi;
                    let r = r_ij.length();
                    if r == 0.0 {
                        continue;
                    }
                    let f = kernel.gradient_factor(r);
                    sum += d.pair(rho(xi), rho(xj), r_ij, r, f, 1e-4);
                    let plain = DensityDiffusion {
                        hydrostatic_gradient: DVec2::ZERO,
                        ..d
                    };
                    uncorrected += plain.pair(rho(xi), rho(xj), r_ij, r, f, 1e-4);
                }
            }
            assert!(
                sum.abs() < 1e-9 * uncorrected.abs(),
                "{sum} vs {uncorrected}"
            );
            assert!(uncorrected.abs() > 0.0);
        }
    }
}
