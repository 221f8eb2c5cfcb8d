//! Particles that leave the water's region through open space (a splash over a tank without a
//! lid): out of the domain, or over the free edge of a wall to its back (the run's watch finds
//! those). Each is removed as it leaves, its energy booked, until the run has lost
//! [`SimConfig::max_removed`](super::SimConfig::max_removed) of them; one more stops it.

use super::part_state::Fault;
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

    /// Removes the own particles with a finite state outside the domain
    /// ([`Simulation::remove_own`]). Every part must call it. Each step calls it when a
    /// particle left the domain.
    pub fn remove_leaving(&mut self) -> bool {
        let leaving: Vec<usize> = (0..self.owned_len())
            .filter(|&i| self.fault(i) == Some(Fault::Outside))
            .collect();
        self.remove_own(&leaving)
    }

    /// Removes the own particles `own` (distinct indices below [`Simulation::owned_len`])
    /// when the run may still lose them all, over every part ([`SimConfig::max_removed`]).
    /// Their energy, `sum m (|u|^2 / 2 + e(rho) - g . r)` summed exactly over the parts, goes
    /// to [`Simulation::removed_energy`], so the energy total still closes; the neighbour
    /// list is dropped, so the next step rebuilds the grid and the list (and a split run hands
    /// its particles over and selects its halos again, which drops the halo copies of the
    /// removed particles). Every part must call it, with its own particles (none, for some).
    /// Returns whether particles were removed; `false` changes nothing.
    ///
    /// [`SimConfig::max_removed`]: super::SimConfig::max_removed
    pub fn remove_own(&mut self, own: &[usize]) -> bool {
        let count = self.total_over_parts(own.len() as f64) as u64;
        if count == 0 || self.removed + count > self.config.max_removed {
            return false;
        }
        let f = &self.fluid;
        let (eos, gravity) = (&self.config.eos, self.config.gravity);
        let mut energy = ExactSum::new();
        energy.add_all(own.iter().map(|&i| particle_energy(f, i, eos, gravity)));
        let mut energy = [energy];
        self.sum_over_parts(&mut energy);
        let mut gone = vec![false; f.len()];
        for &i in own {
            gone[i] = true;
        }
        let kept: Vec<u32> = (0..f.len() as u32).filter(|&i| !gone[i as usize]).collect();
        self.fluid.permute(&kept, &mut self.scratch.permute);
        if let Some(part) = &mut self.part {
            part.owned -= own.len();
        }
        self.removed += count;
        self.removed_energy += energy[0].value();
        self.scratch.candidates_valid = false;
        self.wall_clearance.forget();
        true
    }
}
