//! Energy-conserving boundary integrals (paper 1, sections 4.1-4.2 and App. C).
//!
//! With normals out of the fluid and one-point quadrature at the element centre:
//! - eq 51: `<grad p>_i^{dOmega} = 2 p_i sum_j n_j W_ij s_j`;
//! - eq 52: `<div u>_i^{dOmega} = 2 sum_j (U_j - u_i) . n_j W_ij s_j` (eq 43 when `U_j = 0`);
//! - eq 71: wall pressure `P_j = 2 sum_i p_i W_ij m_i / rho_i`, force `f_j = P_j n_j s_j`.
//!
//! Then the fluid's power loss equals `sum_j f_j . U_j` for any particle state, and fixed walls
//! exchange no power.

use super::{BoundaryElements, ParticleView, WallModel, WallTerms};
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::CellGrid;
use crate::particles::FluidState;
use rayon::prelude::*;

/// The energy-conserving wall model of paper 1.
#[derive(Clone, Copy, Debug, Default)]
pub struct EnergyConservingWalls;

impl<V: Vector> WallModel<V> for EnergyConservingWalls {
    const RENORMALISE: bool = false;

    fn update_wall_pressure(
        &self,
        kernel: &Wendland,
        elements: &mut BoundaryElements<V>,
        fluid: &FluidState<V>,
        fluid_grid: &CellGrid<V>,
    ) {
        wall_pressure(kernel, elements, fluid, fluid_grid);
    }

    #[inline(always)]
    fn particle_terms(
        &self,
        kernel: &Wendland,
        a: &ParticleView<V>,
        elements: &BoundaryElements<V>,
        grid: &CellGrid<V>,
    ) -> WallTerms<V> {
        let (x, u, p) = (a.x, a.u, a.p);
        let mut normal_sum = V::ZERO;
        let mut relative_flux = 0.0;
        grid.for_each_neighbour(x, &elements.centre, kernel.support, |j, _, r| {
            let ws = kernel.value(r) * elements.area[j];
            let n = elements.normal[j];
            normal_sum += n * ws;
            relative_flux += (elements.velocity[j] - u).dot(n) * ws;
        });
        WallTerms {
            pressure_gradient: normal_sum * (2.0 * p),
            velocity_divergence: 2.0 * relative_flux,
        }
    }
}

/// Paper 1, eq 71: `P_j = 2 sum_i p_i W_ij V_i` for every element, written into
/// `elements.pressure` (gathered per element, in parallel).
pub fn wall_pressure<V: Vector>(
    kernel: &Wendland,
    elements: &mut BoundaryElements<V>,
    fluid: &FluidState<V>,
    fluid_grid: &CellGrid<V>,
) {
    let centres = &elements.centre;
    elements
        .pressure
        .par_iter_mut()
        .enumerate()
        .for_each(|(j, pj)| {
            let mut sum = 0.0;
            fluid_grid.for_each_neighbour(centres[j], fluid.position, kernel.support, |i, _, r| {
                sum += fluid.pressure[i] * fluid.volume[i] * kernel.value(r);
            });
            *pj = 2.0 * sum;
        });
}
