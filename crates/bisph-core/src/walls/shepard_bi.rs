//! Classic boundary integrals with Shepard renormalisation (paper 1, eqs 24-25), kept for
//! comparison with the energy-conserving walls:
//! - `<grad p>_i = (1/gamma_i) [ -sum_j (p_j + p_i) grad W_ij V_j + sum_k (p_k + p_i) n_k W_ik s_k ]`;
//! - `<div u>_i = (1/gamma_i) [ -sum_j (u_j - u_i) . grad W_ij V_j + sum_k (U_k - u_i) . n_k W_ik s_k ]`;
//!
//! with the Shepard factor of a [`Shepard`] strategy (discrete, geometric or integrated), and the wall
//! pressure `p_k` extrapolated from the fluid with the hydrostatic correction,
//! `p_k = sum_j (p_j + rho_j g . (r_k - r_j)) W_kj V_j / sum_j W_kj V_j`.
//! These operators are not skew-adjoint: energy is not conserved (paper 1, section 4).

use super::shepard::Shepard;
pub use super::shepard::ShepardKind;
use super::{BoundaryElements, ParticleView, WallModel, WallTerms};
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::Nearby;
use crate::particles::FluidState;
use rayon::prelude::*;

/// How the boundary term `sum_k (p_k + p_i) n_k int_{S_k} W dS` integrates the kernel over
/// each element.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BoundaryQuadrature {
    /// `W(|c_k - x_i|) s_k`: the kernel at the element centre times its area (paper 1,
    /// eqs 24-25).
    #[default]
    Centre,
    /// `int_{S_k} W dS` exactly, the integral whose sum over the walls is `-grad gamma` of
    /// the geometric Shepard factor (paper 3, eq 9; paper 4, eq 3), so that a constant
    /// pressure meets walls that cut the kernel support, corners included, without a
    /// quadrature error.
    Exact,
    /// `int_{S_k} W dS` by a low-order Gauss rule (2 points on a segment, 2 x 2 on a
    /// quadrilateral, 3 on a triangle, [`crate::bi::gauss`]): within about 5e-4 of
    /// `Exact` near edges and corners, at a fraction of its cost in 3-D.
    Gauss,
}

impl BoundaryQuadrature {
    /// The farthest an element's centre can lie from a particle whose kernel support of
    /// radius `support` reaches the element: the support itself for the centre rule, plus the
    /// largest distance `max_reach` from a centre to a corner where the whole element counts.
    pub fn reach(self, support: f64, max_reach: f64) -> f64 {
        match self {
            BoundaryQuadrature::Centre => support,
            BoundaryQuadrature::Exact | BoundaryQuadrature::Gauss => support + max_reach,
        }
    }
}

/// Shepard-renormalised boundary integrals with fluid-extrapolated wall pressure.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShepardWalls<V> {
    /// Gravity, for the hydrostatic correction of the extrapolated wall pressure.
    pub gravity: V,
    /// Which Shepard factor renormalises the operators.
    pub shepard: Shepard,
    /// How the boundary term integrates the kernel over an element.
    pub quadrature: BoundaryQuadrature,
}

impl<V: Vector> WallModel<V> for ShepardWalls<V> {
    const RENORMALISE: bool = true;

    fn update_wall_pressure(
        &self,
        kernel: &Wendland,
        elements: &mut BoundaryElements<V>,
        fluid: &FluidState<V>,
        fluid_near: Nearby<'_, V>,
    ) {
        let (centres, in_reach) = (&elements.centre, &elements.in_reach);
        let g = self.gravity;
        elements
            .pressure
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, pk)| {
                if !in_reach.is_empty() && !in_reach[k] {
                    return;
                }
                let (mut weighted, mut shepard) = (0.0, 0.0);
                fluid_near.for_each(
                    k,
                    centres[k],
                    fluid.position,
                    kernel.support,
                    |j, r_kj, r| {
                        let wv = kernel.value(r) * fluid.volume[j];
                        // r_kj = r_j - r_k, so g . (r_k - r_j) = -g . r_kj.
                        weighted += (fluid.pressure[j] - fluid.density[j] * g.dot(r_kj)) * wv;
                        shepard += wv;
                    },
                );
                *pk = if shepard > 0.0 {
                    weighted / shepard
                } else {
                    0.0
                };
            });
    }

    fn needs_discrete_shepard(&self) -> bool {
        self.shepard == Shepard::of(ShepardKind::Discrete)
    }

    fn renormalisation(&self, discrete: f64, state_gamma: f64) -> f64 {
        self.shepard.gamma(discrete, state_gamma)
    }

    #[inline(always)]
    fn particle_terms(
        &self,
        kernel: &Wendland,
        a: &ParticleView<V>,
        elements: &BoundaryElements<V>,
        near: Nearby<'_, V>,
    ) -> WallTerms<V> {
        let (x, u, p) = (a.x, a.u, a.p);
        let mut pressure_gradient = V::ZERO;
        let mut velocity_divergence = 0.0;
        let radius = self.quadrature.reach(kernel.support, elements.max_reach);
        // Elements beyond the Gauss points' reach give exactly zero.
        let radius = match self.quadrature {
            BoundaryQuadrature::Gauss => radius.min(elements.gauss_reach(kernel.support)),
            _ => radius,
        };
        near.for_each(a.index, x, &elements.centre, radius, |k, _, r| {
            let ws = match self.quadrature {
                BoundaryQuadrature::Centre => kernel.value(r) * elements.area[k],
                BoundaryQuadrature::Exact => crate::bi::kernel_integral(
                    kernel,
                    x,
                    elements.current_corners(k),
                    kernel.support,
                ),
                BoundaryQuadrature::Gauss => elements.gauss_integral(kernel, x, k),
            };
            let n = elements.normal[k];
            pressure_gradient += n * ((elements.pressure[k] + p) * ws);
            velocity_divergence += (elements.velocity[k] - u).dot(n) * ws;
        });
        WallTerms {
            pressure_gradient,
            velocity_divergence,
        }
    }
}
