//! Fluid particles as a struct of arrays.

use crate::decomposition::{push_vector, read_scalar, read_vector};
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
    /// Accelerations of the step before `earlier_acceleration`'s (empty unless the midpoint
    /// integrator runs): the third point of its first guess.
    pub earliest_acceleration: Vec<V>,
    /// Density rates of the step before the earlier (see `earliest_acceleration`).
    pub earliest_density_rate: Vec<f64>,
    /// The Shepard factor `gamma_i` the particle carries: geometric (paper 2) or integrated
    /// (paper 3, eq 4); 1 when unused.
    pub gamma: Vec<f64>,
    /// `grad gamma_i` at the current position, for the trapezoidal step of the integrated
    /// gamma (paper 3, eq 10; zero when unused).
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
        if !self.earliest_acceleration.is_empty() {
            permute_into(&mut self.earliest_acceleration, order, &mut scratch.vectors);
            permute_into(&mut self.earliest_density_rate, order, &mut scratch.scalars);
        }
        permute_into(&mut self.gamma, order, &mut scratch.scalars);
        permute_into(&mut self.grad_gamma, order, &mut scratch.vectors);
        permute_into(&mut self.density_offset, order, &mut scratch.scalars);
    }
}

impl<V: Vector> Fluid<V> {
    /// Words per particle in [`Fluid::encode`]: the id and every state and rate array.
    pub const RECORD_WORDS: usize = 9 + 6 * V::DIM;

    /// Keeps the first `n` particles.
    pub fn truncate(&mut self, n: usize) {
        self.id.truncate(n);
        self.position.truncate(n);
        self.velocity.truncate(n);
        self.density.truncate(n);
        self.mass.truncate(n);
        self.pressure.truncate(n);
        self.acceleration.truncate(n);
        self.density_rate.truncate(n);
        self.earlier_acceleration.truncate(n);
        self.earlier_density_rate.truncate(n);
        self.earliest_acceleration.truncate(n);
        self.earliest_density_rate.truncate(n);
        self.gamma.truncate(n);
        self.grad_gamma.truncate(n);
        self.density_offset.truncate(n);
    }

    /// Gives every particle the arrays of the steps before (zero), so that every particle
    /// carries the same fields ([`Fluid::encode`]).
    pub fn hold_earlier_rates(&mut self) {
        self.earlier_acceleration.resize(self.len(), V::ZERO);
        self.earlier_density_rate.resize(self.len(), 0.0);
        self.earliest_acceleration.resize(self.len(), V::ZERO);
        self.earliest_density_rate.resize(self.len(), 0.0);
    }

    /// Appends the whole record of each particle of `indices` to `out`, bit for bit
    /// ([`Fluid::RECORD_WORDS`] words each, read back by [`Fluid::append_encoded`]). The
    /// arrays of the step before must be held ([`Fluid::hold_earlier_rates`]).
    pub fn encode(&self, indices: impl IntoIterator<Item = usize>, out: &mut Vec<u64>) {
        for i in indices {
            out.push(u64::from(self.id[i]));
            for v in [
                self.position[i],
                self.velocity[i],
                self.acceleration[i],
                self.earlier_acceleration[i],
                self.earliest_acceleration[i],
                self.grad_gamma[i],
            ] {
                push_vector(out, v);
            }
            out.extend(
                [
                    self.density[i],
                    self.mass[i],
                    self.pressure[i],
                    self.density_rate[i],
                    self.earlier_density_rate[i],
                    self.earliest_density_rate[i],
                    self.gamma[i],
                    self.density_offset[i],
                ]
                .map(f64::to_bits),
            );
        }
    }

    /// Appends the particles whose records [`Fluid::encode`] wrote to `words`.
    ///
    /// # Panics
    /// When `words` does not hold whole records.
    pub fn append_encoded(&mut self, words: &[u64]) {
        assert_eq!(
            words.len() % Self::RECORD_WORDS,
            0,
            "whole particle records"
        );
        for record in words.chunks_exact(Self::RECORD_WORDS) {
            let mut next = record[1..].iter().copied();
            self.id.push(record[0] as u32);
            self.position.push(read_vector(&mut next));
            self.velocity.push(read_vector(&mut next));
            self.acceleration.push(read_vector(&mut next));
            self.earlier_acceleration.push(read_vector(&mut next));
            self.earliest_acceleration.push(read_vector(&mut next));
            self.grad_gamma.push(read_vector(&mut next));
            self.density.push(read_scalar(&mut next));
            self.mass.push(read_scalar(&mut next));
            self.pressure.push(read_scalar(&mut next));
            self.density_rate.push(read_scalar(&mut next));
            self.earlier_density_rate.push(read_scalar(&mut next));
            self.earliest_density_rate.push(read_scalar(&mut next));
            self.gamma.push(read_scalar(&mut next));
            self.density_offset.push(read_scalar(&mut next));
        }
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
