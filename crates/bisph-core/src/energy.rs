//! Energy bookkeeping (paper 1, section 4): kinetic, compressible, potential and the
//! cumulative work the fluid did on walls and bodies.

use crate::dim::Vector;
use crate::eos::Eos;
use crate::particles::Fluid;
use rayon::prelude::*;

/// The energy budget at one instant. `total` is conserved by the continuous equations.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyBudget {
    /// `sum m |u|^2 / 2`.
    pub kinetic: f64,
    /// `sum m e(rho)` with the exact `e(rho)` of the equation of state.
    pub compressible: f64,
    /// `-sum m g . r`.
    pub potential: f64,
    /// Cumulative energy given by the fluid to walls and bodies, `int sum_j F_j . U_j dt`.
    pub wall_work: f64,
    /// Cumulative viscous dissipation `int sum_i -m_i u_i . a_i^visc dt` (paper 3 eq 18 with
    /// its wall shear; zero without viscosity).
    pub viscous_dissipation: f64,
    /// Cumulative work done on the fluid by the driving body force (zero without one).
    pub forcing_work: f64,
    /// Cumulative compressible energy removed by the density diffusion,
    /// `int sum_i -m_i p_i D_i / rho_i^2 dt` (zero without diffusion).
    pub diffusion_dissipation: f64,
    /// `kinetic + compressible + potential + wall_work + viscous_dissipation
    /// + diffusion_dissipation - forcing_work`.
    pub total: f64,
}

/// Sums `f(i)` for `i < n` in fixed chunks combined in order: the same bits for any number
/// of threads.
pub fn deterministic_sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    const CHUNK: usize = 4096;
    let partial: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(n)).map(&f).sum::<f64>())
        .collect();
    partial.iter().sum()
}

/// The fluid's kinetic, compressible and potential energies.
pub fn fluid_energies<V: Vector>(fluid: &Fluid<V>, eos: &Eos, gravity: V) -> (f64, f64, f64) {
    let n = fluid.len();
    let kinetic = deterministic_sum(n, |i| {
        0.5 * fluid.mass[i] * fluid.velocity[i].length_squared()
    });
    let compressible =
        deterministic_sum(n, |i| fluid.mass[i] * eos.specific_energy(fluid.density[i]));
    let potential = deterministic_sum(n, |i| -fluid.mass[i] * gravity.dot(fluid.position[i]));
    (kinetic, compressible, potential)
}

/// Energy scale used to express drift: the initial kinetic and compressible energy plus the
/// potential energy above the lowest particle, `sum m |g| (z_i - z_min)`.
pub fn energy_scale<V: Vector>(fluid: &Fluid<V>, eos: &Eos, gravity: V) -> f64 {
    let (kinetic, compressible, _) = fluid_energies(fluid, eos, gravity);
    let heights: Vec<f64> = fluid.position.iter().map(|&r| -gravity.dot(r)).collect();
    let lowest = heights.iter().copied().fold(f64::INFINITY, f64::min);
    let available: f64 = if heights.is_empty() {
        0.0
    } else {
        (0..fluid.len())
            .map(|i| fluid.mass[i] * (heights[i] - lowest))
            .sum()
    };
    kinetic + compressible.abs() + available
}
