//! Fluid particles as a struct of arrays.

use crate::dim::Vector;
use rayon::prelude::*;

/// State and rates of the fluid particles (struct of arrays, one entry per particle).
///
/// Particles are reordered by cell for memory locality; `id` keeps each particle's original
/// index so outputs and diagnostics can name it.
#[derive(Clone, Debug, Default)]
pub struct Fluid<V: Vector> {
    /// Original index of each particle (stable across reorderings).
    pub id: Vec<u32>,
    /// Positions `r_i`.
    pub position: Vec<V>,
    /// Velocities `u_i`.
    pub velocity: Vec<V>,
    /// Densities `rho_i`.
    pub density: Vec<f64>,
    /// Masses `m_i` (constant in time).
    pub mass: Vec<f64>,
    /// Pressures `p_i = p(rho_i)`, refreshed from the equation of state before each rate sweep.
    pub pressure: Vec<f64>,
    /// Accelerations `du_i/dt` from the last rate evaluation.
    pub acceleration: Vec<V>,
    /// Density rates `drho_i/dt` from the last rate evaluation.
    pub density_rate: Vec<f64>,
    /// Accelerations of the step before the last (empty unless the midpoint integrator
    /// runs): with `acceleration`, the midpoint integrator extrapolates its first guess.
    pub earlier_acceleration: Vec<V>,
    /// Density rates of the step before (see `earlier_acceleration`).
    pub earlier_density_rate: Vec<f64>,
    /// Integrated Shepard factor `gamma_i` (paper 3, eq 4; 1 when unused).
    pub gamma: Vec<f64>,
    /// `grad gamma_i` at the current position (paper 3, eq 10; zero when unused).
    pub grad_gamma: Vec<V>,
    /// Density by summation (paper 3, eq 84): `C_i` in
    /// `gamma_i rho_i = sum_P m_j W_ij + C_i`, the accumulated diffusion (zero when unused).
    pub density_offset: Vec<f64>,
}

impl<V: Vector> Fluid<V> {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// `true` when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Appends a particle at rest with zero rates.
    pub fn push(&mut self, position: V, velocity: V, density: f64, mass: f64, pressure: f64) {
        self.id.push(self.position.len() as u32);
        self.position.push(position);
        self.velocity.push(velocity);
        self.density.push(density);
        self.mass.push(mass);
        self.pressure.push(pressure);
        self.acceleration.push(V::ZERO);
        self.density_rate.push(0.0);
        self.gamma.push(1.0);
        self.grad_gamma.push(V::ZERO);
        self.density_offset.push(0.0);
    }

    /// Reorders every array so that new entry `k` is old entry `order[k]`.
    pub fn permute(&mut self, order: &[u32], scratch: &mut PermuteScratch<V>) {
        permute_into(&mut self.id, order, &mut scratch.ids);
        permute_into(&mut self.position, order, &mut scratch.vectors);
        permute_into(&mut self.velocity, order, &mut scratch.vectors);
        permute_into(&mut self.acceleration, order, &mut scratch.vectors);
        permute_into(&mut self.density, order, &mut scratch.scalars);
        permute_into(&mut self.mass, order, &mut scratch.scalars);
        permute_into(&mut self.pressure, order, &mut scratch.scalars);
        permute_into(&mut self.density_rate, order, &mut scratch.scalars);
        if !self.earlier_acceleration.is_empty() {
            permute_into(&mut self.earlier_acceleration, order, &mut scratch.vectors);
            permute_into(&mut self.earlier_density_rate, order, &mut scratch.scalars);
        }
        permute_into(&mut self.gamma, order, &mut scratch.scalars);
        permute_into(&mut self.grad_gamma, order, &mut scratch.vectors);
        permute_into(&mut self.density_offset, order, &mut scratch.scalars);
    }
}

/// Reusable buffers for [`Fluid::permute`], so reordering allocates nothing per step.
#[derive(Debug, Default)]
pub struct PermuteScratch<V> {
    ids: Vec<u32>,
    vectors: Vec<V>,
    scalars: Vec<f64>,
}

/// `data[i] = data[order[i]]`, gathered in parallel (each slot written once: deterministic).
fn permute_into<T: Copy + Send + Sync>(data: &mut Vec<T>, order: &[u32], scratch: &mut Vec<T>) {
    scratch.clear();
    let source = &*data;
    scratch.par_extend(
        order
            .par_iter()
            .with_min_len(4096)
            .map(|&k| source[k as usize]),
    );
    std::mem::swap(data, scratch);
}

/// A read-only view of the fluid state at which rates are evaluated (the integrator may
/// evaluate at predicted velocities and densities, not the stored ones).
#[derive(Clone, Copy, Debug)]
pub struct FluidState<'a, V> {
    /// Positions.
    pub position: &'a [V],
    /// Velocities.
    pub velocity: &'a [V],
    /// Densities.
    pub density: &'a [f64],
    /// Masses.
    pub mass: &'a [f64],
    /// Pressures (from the densities by the equation of state).
    pub pressure: &'a [f64],
    /// Volumes `m / rho` (precomputed once per evaluation: no division per pair).
    pub volume: &'a [f64],
    /// Integrated Shepard factors (paper 3, eq 4).
    pub gamma: &'a [f64],
}
