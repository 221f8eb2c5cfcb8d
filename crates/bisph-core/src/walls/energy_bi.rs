//! Energy-conserving boundary integrals (paper 1, sections 4.1-4.2 and App. C).
//!
//! With normals out of the fluid and one-point quadrature at the element centre:
//! - eq 51: `<grad p>_i^{dOmega} = 2 p_i sum_j n_j W_ij s_j`;
//! - eq 52: `<div u>_i^{dOmega} = 2 sum_j (U_j - u_i) . n_j W_ij s_j` (eq 43 when `U_j = 0`);
//! - eq 71: wall pressure `P_j = 2 sum_i p_i W_ij m_i / rho_i`, force `f_j = P_j n_j s_j`.
//!
//! Then the fluid's power loss equals `sum_j f_j . U_j` for any particle state, and fixed walls
//! exchange no power.

use super::{geometric_shepard, BoundaryElements, ParticleView, WallModel, WallTerms};
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::{CellGrid, Nearby, PairList};
use crate::particles::FluidState;
use rayon::prelude::*;

/// The energy-conserving wall model of paper 1.
#[derive(Clone, Copy, Debug, Default)]
pub struct EnergyConservingWalls;

impl<V: Vector> WallModel<V> for EnergyConservingWalls {
    const RENORMALISE: bool = false;

    /// The geometric Shepard factor of the walls (paper 2), exactly 1 away from walls, so
    /// that fluid pairs there stay antisymmetric.
    fn laplacian_gamma(
        &self,
        kernel: &Wendland,
        x: V,
        elements: &BoundaryElements<V>,
        grid: &CellGrid<V>,
    ) -> f64 {
        geometric_shepard::gamma(kernel, x, elements, grid)
    }

    fn update_wall_pressure(
        &self,
        kernel: &Wendland,
        elements: &mut BoundaryElements<V>,
        fluid: &FluidState<V>,
        fluid_near: Nearby<'_, V>,
    ) {
        wall_pressure(kernel, elements, fluid, fluid_near);
    }

    #[inline(always)]
    fn particle_terms(
        &self,
        kernel: &Wendland,
        a: &ParticleView<V>,
        elements: &BoundaryElements<V>,
        near: Nearby<'_, V>,
    ) -> WallTerms<V> {
        let mut sums = ElementSums::new(a.u);
        near.for_each(a.index, a.x, &elements.centre, kernel.support, |j, _, r| {
            sums.add(elements, j, kernel.value(r))
        });
        sums.terms(a.p)
    }
}

/// The element sums of eqs 51-52 for one particle with velocity `u`: `sum_j n_j W_ij s_j` and
/// `sum_j (U_j - u) . n_j W_ij s_j`, in the order the elements are added.
struct ElementSums<V> {
    u: V,
    normal_sum: V,
    relative_flux: f64,
}

impl<V: Vector> ElementSums<V> {
    #[inline(always)]
    fn new(u: V) -> Self {
        ElementSums {
            u,
            normal_sum: V::ZERO,
            relative_flux: 0.0,
        }
    }

    /// Adds element `j` with the kernel value `w = W_ij`.
    #[inline(always)]
    fn add(&mut self, elements: &BoundaryElements<V>, j: usize, w: f64) {
        let ws = w * elements.area[j];
        let n = elements.normal[j];
        self.normal_sum += n * ws;
        self.relative_flux += (elements.velocity[j] - self.u).dot(n) * ws;
    }

    /// Eqs 51-52 for the particle pressure `p`.
    #[inline(always)]
    fn terms(&self, p: f64) -> WallTerms<V> {
        WallTerms {
            pressure_gradient: self.normal_sum * (2.0 * p),
            velocity_divergence: 2.0 * self.relative_flux,
        }
    }
}

/// [`EnergyConservingWalls`] with the particle-element pairs listed, for the iterations of a
/// midpoint step (particles and elements frozen at `r^n`, only velocities, densities and
/// pressures change): the same sums in the same order as the grid searches, so the same bits,
/// without searching the grids at every iteration.
#[derive(Clone, Copy, Debug)]
pub struct ListedEnergyWalls<'a, V> {
    /// For each fluid particle, its elements within the support with `W_ij` as the factor
    /// (queries: particles, points: element centres, over the wall grid).
    pub particle_elements: &'a PairList<V>,
    /// For each element, its fluid particles within the support with `W_ij` as the factor
    /// (queries: element centres, points: particles, over the fluid grid).
    pub element_particles: &'a PairList<V>,
}

impl<V: Vector> ListedEnergyWalls<'_, V> {
    /// Lists both pair sets at the current positions (kernel values as the factors): the
    /// elements' particles by a search of the fluid grid, the particles' elements by
    /// transposing them in the wall grid's search order (the rows and bits of a search of
    /// the wall grid, [`PairList::transpose`]), or by that search on a periodic grid.
    pub fn rebuild(
        kernel: &Wendland,
        particle_elements: &mut PairList<V>,
        element_particles: &mut PairList<V>,
        elements: &BoundaryElements<V>,
        wall_grid: &CellGrid<V>,
        fluid_position: &[V],
        fluid_grid: &CellGrid<V>,
    ) {
        let k = *kernel;
        element_particles.rebuild(
            fluid_grid,
            &elements.centre,
            fluid_position,
            kernel.support,
            |r| k.value(r),
        );
        match wall_grid.points_in_search_order() {
            Some(order) => {
                particle_elements.transpose(element_particles, fluid_position.len(), &order)
            }
            None => particle_elements.rebuild(
                wall_grid,
                fluid_position,
                &elements.centre,
                kernel.support,
                |r| k.value(r),
            ),
        }
    }
}

impl<V: Vector> WallModel<V> for ListedEnergyWalls<'_, V> {
    const RENORMALISE: bool = false;

    /// The geometric Shepard factor of the walls (paper 2), exactly 1 away from walls, so
    /// that fluid pairs there stay antisymmetric.
    fn laplacian_gamma(
        &self,
        kernel: &Wendland,
        x: V,
        elements: &BoundaryElements<V>,
        grid: &CellGrid<V>,
    ) -> f64 {
        geometric_shepard::gamma(kernel, x, elements, grid)
    }

    fn update_wall_pressure(
        &self,
        _kernel: &Wendland,
        elements: &mut BoundaryElements<V>,
        fluid: &FluidState<V>,
        _fluid_near: Nearby<'_, V>,
    ) {
        wall_pressure_over(
            elements,
            fluid,
            ElementNeighbours::List(self.element_particles),
        );
    }

    #[inline(always)]
    fn particle_terms(
        &self,
        _kernel: &Wendland,
        a: &ParticleView<V>,
        elements: &BoundaryElements<V>,
        _near: Nearby<'_, V>,
    ) -> WallTerms<V> {
        let mut sums = ElementSums::new(a.u);
        self.particle_elements
            .for_each(a.index, |j, _, w| sums.add(elements, j, w));
        sums.terms(a.p)
    }
}

/// Paper 1, eq 71: `P_j = 2 sum_i p_i W_ij V_i` for every element in reach
/// ([`BoundaryElements::in_reach`]), written into `elements.pressure` (gathered per element,
/// in parallel); `fluid_near` finds the particles near an element.
pub fn wall_pressure<V: Vector>(
    kernel: &Wendland,
    elements: &mut BoundaryElements<V>,
    fluid: &FluidState<V>,
    fluid_near: Nearby<'_, V>,
) {
    let near = ElementNeighbours::Search {
        kernel,
        near: fluid_near,
    };
    wall_pressure_over(elements, fluid, near);
}

/// Where eq 71 finds the particles within an element's support: a search (of the fluid grid
/// or of the element's candidates), or the element-particle pairs listed for a midpoint step
/// (same order, same `W_ij` bits).
#[derive(Clone, Copy)]
enum ElementNeighbours<'a, V: Vector> {
    Search {
        kernel: &'a Wendland,
        near: Nearby<'a, V>,
    },
    List(&'a PairList<V>),
}

/// Paper 1, eq 71 over the particles `near` gives each element.
fn wall_pressure_over<V: Vector>(
    elements: &mut BoundaryElements<V>,
    fluid: &FluidState<V>,
    near: ElementNeighbours<'_, V>,
) {
    let (centres, in_reach) = (&elements.centre, &elements.in_reach);
    elements
        .pressure
        .par_iter_mut()
        .enumerate()
        .for_each(|(j, pj)| {
            if !in_reach.is_empty() && !in_reach[j] {
                return;
            }
            let mut sum = 0.0;
            let mut add = |i: usize, w: f64| sum += fluid.pressure[i] * fluid.volume[i] * w;
            match near {
                ElementNeighbours::Search { kernel, near } => {
                    near.for_each(j, centres[j], fluid.position, kernel.support, |i, _, r| {
                        add(i, kernel.value(r))
                    })
                }
                ElementNeighbours::List(list) => list.for_each(j, |i, _, w| add(i, w)),
            }
            *pj = 2.0 * sum;
        });
}
