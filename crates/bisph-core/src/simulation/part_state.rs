//! What a part of a split run keeps besides its simulation state ([`Part`]), and what its
//! exchanges carry: halo fields and the particle that stops a run.

use crate::decomposition::{
    push_vector, read_scalar, read_vector, Counted, Decomposition, Message, RebalancePolicy,
};
use crate::dim::Vector;
use crate::error::SimError;
use crate::particles::Fluid;

/// What makes a simulation one part of a decomposed run.
#[derive(Debug)]
pub(crate) struct Part<V: Vector> {
    pub(super) transport: Counted,
    pub(super) decomposition: Decomposition<V>,
    /// Particles `0..owned` are this part's own; the rest are its halo.
    pub(super) owned: usize,
    /// For each part, the own particles it holds in its halo, in the order it stores them.
    pub(super) send: Vec<Vec<u32>>,
    /// How far outside its region a part needs the particles, besides two drift limits of
    /// the neighbour list (own and halo particles may each move that far while the lists
    /// are kept, [`Simulation::drift_limit`]): two kernel supports and twice the largest
    /// element reach (a particle sums over wall points within a support, and the wall values
    /// there are sums over the fluid within a support of an element's quadrature points).
    /// With a skin of at most a support, this also covers a Verlet list taken over from a
    /// restored whole, whose particles may each be up to the drift limit from where it was
    /// built.
    ///
    /// [`Simulation::drift_limit`]: super::Simulation::drift_limit
    pub(super) reach: f64,
    /// Particles this part has handed to others since it was built.
    pub(super) departed: u64,
    /// Times the regions were cut again since it was built.
    pub(super) rebalances: u64,
}

/// Where a part stands in its split: the regions, how many of its particles are its own, and
/// which of them each other part holds in its halo. With its fluid arrays, what a part needs
/// to go back to an earlier state ([`crate::Simulation::part_layout`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PartLayout<V: Vector> {
    pub(super) decomposition: Decomposition<V>,
    pub(super) owned: usize,
    pub(super) send: Vec<Vec<u32>>,
}

impl<V: Vector> PartLayout<V> {
    /// Number of the part's own particles (stored first).
    pub fn owned(&self) -> usize {
        self.owned
    }
}

/// When a split run cuts its regions again: at a neighbour-list rebuild, once the part with
/// the most work (its particles weighted by their neighbour candidates) has 10% more than the
/// mean.
pub(super) const REBALANCE: RebalancePolicy = RebalancePolicy { threshold: 1.1 };

/// The results of neighbour sums copied from the owners to the halos.
#[derive(Clone, Copy, Debug)]
pub(crate) enum HaloFields {
    /// Accelerations and density rates.
    Rates,
    /// Densities (by summation).
    Density,
}

/// A particle whose state stops the run (`Simulation::check_state`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BadParticle {
    id: u32,
    fault: Fault,
    position: [f64; 3],
}

/// What is wrong with a [`BadParticle`], in the order the checks look.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Fault {
    /// The position is not finite.
    Position,
    /// The velocity is not finite.
    Velocity,
    /// The density is not finite and positive.
    Density,
    /// The particle left the domain.
    Outside,
}

impl Fault {
    const ALL: [Fault; 4] = [
        Fault::Position,
        Fault::Velocity,
        Fault::Density,
        Fault::Outside,
    ];
}

impl BadParticle {
    pub(crate) fn new(id: u32, fault: Fault, position: [f64; 3]) -> Self {
        BadParticle {
            id,
            fault,
            position,
        }
    }

    pub(crate) fn id(&self) -> u32 {
        self.id
    }

    pub(crate) fn fault(&self) -> Fault {
        self.fault
    }

    pub(super) fn to_words(self) -> Message {
        let mut words = vec![u64::from(self.id), self.fault as u64];
        words.extend(self.position.map(f64::to_bits));
        words
    }

    pub(super) fn from_words(words: &[u64]) -> Self {
        BadParticle {
            id: words[0] as u32,
            fault: Fault::ALL[words[1] as usize],
            position: [2, 3, 4].map(|k| f64::from_bits(words[k])),
        }
    }

    /// The error naming this particle.
    pub(crate) fn error(self, step: u64, time: f64) -> SimError {
        let quantity = match self.fault {
            Fault::Position => "position",
            Fault::Velocity => "velocity",
            Fault::Density => "density",
            Fault::Outside => {
                return SimError::LeftDomain {
                    particle: self.id,
                    position: self.position,
                    step,
                    time,
                }
            }
        };
        SimError::NonFinite {
            particle: self.id,
            quantity,
            step,
            time,
        }
    }
}

/// Appends the `fields` of particle `i` to `out`.
pub(super) fn halo_words<V: Vector>(f: &Fluid<V>, i: usize, fields: HaloFields, out: &mut Message) {
    match fields {
        HaloFields::Rates => {
            push_vector(out, f.acceleration[i]);
            out.push(f.density_rate[i].to_bits());
        }
        HaloFields::Density => out.push(f.density[i].to_bits()),
    }
}

/// Sets the `fields` of particle `i` from the values `next` (written by [`halo_words`]).
pub(super) fn set_halo<V: Vector>(
    f: &mut Fluid<V>,
    i: usize,
    fields: HaloFields,
    next: &mut impl Iterator<Item = u64>,
) {
    match fields {
        HaloFields::Rates => {
            f.acceleration[i] = read_vector(next);
            f.density_rate[i] = read_scalar(next);
        }
        HaloFields::Density => f.density[i] = read_scalar(next),
    }
}
