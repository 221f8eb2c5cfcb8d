//! Particles that leave the water's region through open space (a splash over a tank without a
//! lid): out of the domain, or over the free edge of a wall to its back (the run's watch finds
//! those). Each is removed as it leaves, its energy booked, until the run has lost
//! [`SimConfig::max_removed`](super::SimConfig::max_removed) of them; one more stops it.

use super::part_state::Fault;
use super::Simulation;
use crate::decomposition::{all_gather, ExactSum};
use crate::dim::Vector;
use crate::energy::particle_energy;
use crate::neighbours::{renumbering, GONE};

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
    /// to [`Simulation::removed_energy`], so the energy total still closes. The neighbour
    /// lists keep the pairs of the remaining particles ([`Simulation::keep_lists_of`]), and
    /// the parts of a split run drop their halo copies of the removed particles. Every part
    /// must call it, with its own particles (none, for some). Returns whether particles were
    /// removed; `false` changes nothing.
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
        let gone = self.gone_with(own);
        let kept: Vec<u32> = (0..gone.len() as u32)
            .filter(|&i| !gone[i as usize])
            .collect();
        let owned = self.owned_len() - own.len();
        self.fluid.permute(&kept, &mut self.scratch.permute);
        if let Some(part) = &mut self.part {
            part.owned = owned;
            // The own particles each part still receives, in the order it stores them.
            let renumbered = renumbering(&kept, gone.len());
            for indices in &mut part.send {
                indices.retain_mut(|i| {
                    *i = renumbered[*i as usize];
                    *i != GONE
                });
            }
        }
        self.removed += count;
        self.removed_energy += energy[0].value();
        self.keep_lists_of(&kept, gone.len(), owned);
        true
    }

    /// Which of this part's particles go with the own particles `own`: those, and in a split
    /// run the halo copies of the particles every other part removes. Every part must call it.
    fn gone_with(&self, own: &[usize]) -> Vec<bool> {
        let f = &self.fluid;
        let mut gone = vec![false; f.len()];
        for &i in own {
            gone[i] = true;
        }
        if let Some(part) = &self.part {
            let ids = own.iter().map(|&i| u64::from(f.id[i])).collect();
            let mut removed: Vec<u64> = all_gather(&part.transport, ids).concat();
            removed.sort_unstable();
            for (i, flag) in gone.iter_mut().enumerate().skip(part.owned) {
                *flag = removed.binary_search(&u64::from(f.id[i])).is_ok();
            }
        }
        gone
    }
}
