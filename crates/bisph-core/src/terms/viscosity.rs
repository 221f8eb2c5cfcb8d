//! Laminar viscosity: the Morris Laplacian with its wall-shear boundary term (paper 3,
//! eqs 18-20; Morris, Fox & Zhu 1997; Ferrand et al. 2013).
//!
//! Fluid part, eq 18 with `f = mu = rho nu`, `B = u`, per unit mass:
//! `a_i = sum_j m_j (mu_i + mu_j) / (rho_i rho_j) (u_i - u_j) (r_ij . grad_i W_ij) / r_ij^2`
//! `    = sum_j V_j nu (rho_i + rho_j) / rho_i (u_i - u_j) F(r_ij)`, with `grad W(r) = F r`.
//! Pairs are antisymmetric (`m_i a_ij = -m_j a_ji`: momentum is conserved) and dissipative
//! (`sum_i m_i u_i . a_i <= 0`).
//!
//! Wall part, the boundary term `-2/rho_i sum_s mu (grad u)_s . grad gamma_is` of eq 18 with
//! the laminar wall shear of eqs 19-20, `mu du/dn = rho nu u_tau / z`: per element,
//! `a_i += -2 nu |grad gamma_is| (u_i - U_s)_tau / delta_is`, where `(.)_tau` is the part
//! tangent to the element, `delta_is = max(|r_is . n_s|, delta_min)` the distance to the
//! element's plane (floored at `delta_min`, about one particle spacing) and
//! `|grad gamma_is| = int_s W dS` (one-point quadrature `W_is s_s` for the boundary-integral
//! walls; the analytic value for the semi-analytical walls).

use crate::dim::Vector;

/// Laminar viscosity parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viscosity {
    /// Kinematic viscosity `nu` (0 switches the term off).
    pub nu: f64,
    /// Smallest wall distance `delta_min` in the wall-shear term (about `dx`).
    pub min_wall_distance: f64,
}

impl Default for Viscosity {
    fn default() -> Self {
        Viscosity {
            nu: 0.0,
            min_wall_distance: 1.0,
        }
    }
}

impl Viscosity {
    /// `true` when the term is on.
    #[inline(always)]
    pub fn active(&self) -> bool {
        self.nu > 0.0
    }

    /// One fluid pair's contribution to `du_i/dt` (eq 18, fluid sum): `gradient_factor` is
    /// `F` of `grad W(r) = F r` at `|r_ij|`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn pair<V: Vector>(
        &self,
        u_i: V,
        u_j: V,
        rho_i: f64,
        rho_j: f64,
        gradient_factor: f64,
        volume_j: f64,
    ) -> V {
        self.pair_sides(u_i, u_j, [rho_i, rho_j], gradient_factor, [0.0, volume_j])
            .0
    }

    /// One pair's contributions to both particles, `(to i, to j)`, with `rho = [rho_i,
    /// rho_j]` and `volume = [V_i, V_j]` (each the bits its own particle's sum would add).
    #[inline(always)]
    pub fn pair_sides<V: Vector>(
        &self,
        u_i: V,
        u_j: V,
        rho: [f64; 2],
        gradient_factor: f64,
        volume: [f64; 2],
    ) -> (V, V) {
        let du = u_i - u_j;
        let mu = self.nu * (rho[0] + rho[1]);
        (
            du * (mu / rho[0] * gradient_factor * volume[1]),
            -(du * (mu / rho[1] * gradient_factor * volume[0])),
        )
    }

    /// One wall element's contribution to `du_i/dt` (eqs 18-20, laminar wall shear):
    /// `-2 nu |grad gamma_is| (u_i - U_s)_tau / max(|r_is . n_s|, delta_min)`.
    ///
    /// `r_is` is the element centre minus the particle position (any sign convention of the
    /// unit normal `n_s` works), `grad_gamma` is `|grad gamma_is|` (`W_is s_s` with one-point
    /// quadrature).
    #[inline(always)]
    pub fn wall_shear<V: Vector>(
        &self,
        u_i: V,
        velocity_s: V,
        r_is: V,
        normal_s: V,
        grad_gamma: f64,
    ) -> V {
        let relative = u_i - velocity_s;
        let tangential = relative - normal_s * relative.dot(normal_s);
        let distance = r_is.dot(normal_s).abs().max(self.min_wall_distance);
        tangential * (-2.0 * self.nu * grad_gamma / distance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    #[test]
    fn pairs_conserve_momentum_and_dissipate() {
        let v = Viscosity {
            nu: 1e-3,
            min_wall_distance: 0.01,
        };
        let (u_i, u_j) = (DVec2::new(0.3, -0.1), DVec2::new(-0.2, 0.4));
        let (rho_i, rho_j, m_i, m_j) = (1001.0, 998.0, 0.1, 0.12);
        let f = -3.5;
        let a_ij = v.pair(u_i, u_j, rho_i, rho_j, f, m_j / rho_j);
        let a_ji = v.pair(u_j, u_i, rho_j, rho_i, f, m_i / rho_i);
        assert!((a_ij * m_i + a_ji * m_j).length() < 1e-18);
        assert!(m_i * u_i.dot(a_ij) + m_j * u_j.dot(a_ji) < 0.0);
    }

    #[test]
    fn wall_shear_opposes_the_tangential_slip_only() {
        let v = Viscosity {
            nu: 1e-2,
            min_wall_distance: 0.01,
        };
        let n = DVec2::new(0.0, -1.0);
        let a = v.wall_shear(
            DVec2::new(2.0, 5.0),
            DVec2::ZERO,
            DVec2::new(0.0, -0.05),
            n,
            3.0,
        );
        // -2 nu |grad gamma| u_tau / z = -2 * 0.01 * 3 * 2 / 0.05 along x.
        assert!((a - DVec2::new(-2.4, 0.0)).length() < 1e-12);
        // Closer than delta_min: the floor applies.
        let b = v.wall_shear(DVec2::X, DVec2::ZERO, DVec2::new(0.0, -0.001), n, 1.0);
        assert!((b.x + 2.0).abs() < 1e-12);
    }
}
