//! Particles that leave the domain through open space (a splash over a tank without a lid):
//! each is removed as it leaves, its energy booked, until the run has lost
//! [`SimConfig::max_removed`](super::SimConfig::max_removed) of them; one more stops it.

use super::Simulation;
use crate::decomposition::ExactSum;
use crate::dim::Vector;
use crate::energy::particle_energy;

impl<V: Vector> Simulation<V> {
    /// Whether `r` lies outside the domain (not between its corners in every direction).
    pub fn outside_domain(&self, r: V) -> bool {
        let (lo, hi) = (self.config.domain_min, self.config.domain_max);
        (0..V::DIM).any(|k| !(r.get(k) >= lo.get(k) && r.get(k) <= hi.get(k)))
    }

    /// Removes the own particles with a finite state outside the domain, when the run may
    /// still lose all of them. Their energy, `sum m (|u|^2 / 2 + e(rho) - g . r)` summed
    /// exactly over every part, goes to [`Simulation::removed_energy`], so the energy total
    /// still closes; the neighbour list is dropped, so the next step rebuilds the grid and the
    /// list (and a split run hands its particles over and selects its halos again, which drops
    /// the halo copies of the removed particles). Every part must call it. Returns whether
    /// particles were removed; `false` changes nothing. Each step calls it when a particle
    /// left the domain.
    pub fn remove_leaving(&mut self) -> bool {
        let f = &self.fluid;
        let owned = self.owned_len();
        let leaving: Vec<usize> = (0..owned)
            .filter(|&i| {
                let r = f.position[i];
                r.is_finite()
                    && f.velocity[i].is_finite()
                    && f.density[i].is_finite()
                    && f.density[i] > 0.0
                    && self.outside_domain(r)
            })
            .collect();
        let count = self.total_over_parts(leaving.len() as f64) as u64;
        if count == 0 || self.removed + count > self.config.max_removed {
            return false;
        }
        let (eos, gravity) = (&self.config.eos, self.config.gravity);
        let mut energy = ExactSum::new();
        energy.add_all(leaving.iter().map(|&i| particle_energy(f, i, eos, gravity)));
        let mut energy = [energy];
        self.sum_over_parts(&mut energy);
        let mut gone = vec![false; f.len()];
        for &i in &leaving {
            gone[i] = true;
        }
        let kept: Vec<u32> = (0..f.len() as u32).filter(|&i| !gone[i as usize]).collect();
        self.fluid.permute(&kept, &mut self.scratch.permute);
        if let Some(part) = &mut self.part {
            part.owned -= leaving.len();
        }
        self.removed += count;
        self.removed_energy += energy[0].value();
        self.scratch.candidates_valid = false;
        self.wall_clearance.forget();
        true
    }
}
