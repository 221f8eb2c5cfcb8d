//! delta-SPH density diffusion (Molteni & Colagrossi 2009, with the hydrostatic correction of
//! Fourtakas et al. 2019):
//! `D_i = delta h c0 sum_j psi_ij . grad_i W_ij V_j`,
//! `psi_ij = 2 [(rho_j - rho_i) - (rho_j^H - rho_i^H)] (r_j - r_i) / |r_j - r_i|^2`,
//! with the hydrostatic density difference `rho_j^H - rho_i^H = -rho0 g . (r_j - r_i) / c0^2`.
//! Fluid neighbours only; no wall term. Off (`delta = 0`) by default.

use crate::dim::Vector;

/// Coefficients of the diffusion term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensityDiffusion<V: Vector> {
    /// `delta h c0` (zero switches the term off).
    pub scale: f64,
    /// `-rho0 g / c0^2` when the hydrostatic correction is on, else zero.
    pub hydrostatic_gradient: V,
}

impl<V: Vector> DensityDiffusion<V> {
    /// One pair's contribution. `gradient_factor` is `F` of `grad W(r) = F r` at `|r_ij|`, so
    /// `psi_ij . grad_i W_ij = -2 F [(rho_j - rho_i) - (rho_j^H - rho_i^H)]`.
    #[inline(always)]
    pub fn pair(
        &self,
        rho_i: f64,
        rho_j: f64,
        r_ij: V,
        gradient_factor: f64,
        volume_j: f64,
    ) -> f64 {
        let excess = (rho_j - rho_i) - self.hydrostatic_gradient.dot(r_ij);
        -2.0 * self.scale * excess * gradient_factor * volume_j
    }
}
