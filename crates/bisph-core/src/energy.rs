//! Energy bookkeeping (paper 1, section 4): kinetic, compressible, potential and the
//! cumulative work the fluid did on walls and bodies.

use crate::decomposition::ExactSum;
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
    /// Cumulative energy (kinetic, compressible and potential) of the particles removed as
    /// they left the domain (zero while none has).
    pub removed: f64,
    /// `kinetic + compressible + potential + wall_work + viscous_dissipation
    /// + diffusion_dissipation + removed - forcing_work`.
    pub total: f64,
}

/// Sums `f(i)` for `i < n` exactly, rounded once ([`ExactSum`]): the same bits for any
/// number of threads, any order of the terms, and any split of them over parts.
pub fn deterministic_sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    exact_partial_sum(n, f).value()
}

/// The exact sum of `f(i)` for `i < n`, not yet rounded: partial sums of several parts merge
/// into the bits of the whole's ([`ExactSum::merge`]).
pub fn exact_partial_sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> ExactSum {
    const CHUNK: usize = 4096;
    (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut sum = ExactSum::new();
            sum.add_all((c * CHUNK..((c + 1) * CHUNK).min(n)).map(&f));
            sum
        })
        .reduce(ExactSum::new, |mut a, b| {
            a.merge(&b);
            a
        })
}

/// The kinetic energy of particle `i`, `m_i |u_i|^2 / 2`.
fn kinetic_energy<V: Vector>(fluid: &Fluid<V>, i: usize) -> f64 {
    0.5 * fluid.mass[i] * fluid.velocity[i].length_squared()
}

/// The compression energy of particle `i`, `m_i e(rho_i)`.
fn compressible_energy<V: Vector>(fluid: &Fluid<V>, i: usize, eos: &Eos) -> f64 {
    fluid.mass[i] * eos.specific_energy(fluid.density[i])
}

/// The potential energy of particle `i` in gravity, `-m_i g . r_i`.
fn potential_energy<V: Vector>(fluid: &Fluid<V>, i: usize, gravity: V) -> f64 {
    -fluid.mass[i] * gravity.dot(fluid.position[i])
}

/// The kinetic, compressible and potential energy of particle `i`,
/// `m_i (|u_i|^2 / 2 + e(rho_i) - g . r_i)`: the terms of [`fluid_energy_sums`].
pub fn particle_energy<V: Vector>(fluid: &Fluid<V>, i: usize, eos: &Eos, gravity: V) -> f64 {
    kinetic_energy(fluid, i)
        + compressible_energy(fluid, i, eos)
        + potential_energy(fluid, i, gravity)
}

/// The fluid's kinetic, compressible and potential energies.
pub fn fluid_energies<V: Vector>(fluid: &Fluid<V>, eos: &Eos, gravity: V) -> (f64, f64, f64) {
    let [kinetic, compressible, potential] = fluid_energy_sums(fluid, fluid.len(), eos, gravity);
    (kinetic.value(), compressible.value(), potential.value())
}

/// The exact kinetic, compressible and potential energies of the first `n` particles.
pub fn fluid_energy_sums<V: Vector>(
    fluid: &Fluid<V>,
    n: usize,
    eos: &Eos,
    gravity: V,
) -> [ExactSum; 3] {
    let kinetic = exact_partial_sum(n, |i| kinetic_energy(fluid, i));
    let compressible = exact_partial_sum(n, |i| compressible_energy(fluid, i, eos));
    let potential = exact_partial_sum(n, |i| potential_energy(fluid, i, gravity));
    [kinetic, compressible, potential]
}

/// Energy scale used to express drift: the initial kinetic and compressible energy plus the
/// potential energy above the lowest particle, `sum m |g| (z_i - z_min)`, of a whole fluid
/// (a split run: [`crate::Simulation::energy_scale`]).
pub fn energy_scale<V: Vector>(fluid: &Fluid<V>, eos: &Eos, gravity: V) -> f64 {
    let (kinetic, compressible, _) = fluid_energies(fluid, eos, gravity);
    let n = fluid.len();
    let lowest = lowest_height(fluid, n, gravity);
    let available = potential_above(fluid, n, gravity, lowest).value();
    kinetic + compressible.abs() + available
}

/// The height `-g . r / |g|`, times `|g|`, of the lowest of the first `n` particles
/// (infinite when there are none).
pub fn lowest_height<V: Vector>(fluid: &Fluid<V>, n: usize, gravity: V) -> f64 {
    fluid.position[..n]
        .iter()
        .map(|&r| -gravity.dot(r))
        .fold(f64::INFINITY, f64::min)
}

/// The potential energy of the first `n` particles above the height `lowest`
/// ([`lowest_height`]), `sum m |g| (z_i - z_min)`, summed exactly.
pub fn potential_above<V: Vector>(fluid: &Fluid<V>, n: usize, gravity: V, lowest: f64) -> ExactSum {
    exact_partial_sum(n, |i| {
        fluid.mass[i] * (-gravity.dot(fluid.position[i]) - lowest)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Terms of mixed signs and magnitudes, where a running sum depends on the order.
    fn terms(n: usize) -> Vec<f64> {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        (0..n)
            .map(|k| {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let unit = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                unit * 10f64.powi((k % 17) as i32 - 8)
            })
            .collect()
    }

    /// The same bits for the terms in any order and for any part of them added in any
    /// grouping: the sum is exact, rounded once.
    #[test]
    fn deterministic_sums_do_not_depend_on_the_order_of_the_terms() {
        let t = terms(20_000);
        let forward = deterministic_sum(t.len(), |i| t[i]);
        let backward = deterministic_sum(t.len(), |i| t[t.len() - 1 - i]);
        let strided = deterministic_sum(t.len(), |i| t[(i * 7919) % t.len()]);
        assert_eq!(forward.to_bits(), backward.to_bits());
        assert_eq!(forward.to_bits(), strided.to_bits());
        // Two parts summed apart and merged give the whole's bits.
        let mut parts = ExactSum::new();
        parts.add_all(t[..7_000].iter().copied());
        let mut rest = ExactSum::new();
        rest.add_all(t[7_000..].iter().copied());
        parts.merge(&rest);
        assert_eq!(forward.to_bits(), parts.value().to_bits());
        // Exact where a running sum loses the small terms.
        let cancelling = [1.0, 1e100, 1.0, -1e100];
        assert_eq!(cancelling.iter().sum::<f64>(), 0.0);
        assert_eq!(deterministic_sum(4, |i| cancelling[i]), 2.0);
    }
}
