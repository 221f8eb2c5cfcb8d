//! Domain decomposition: the deterministic pieces a distributed run is built from.
//!
//! Every function here is pure and gives the same result from the same data whatever the
//! order the data comes in, so every process of a distributed run that evaluates it on the
//! same input reaches the same answer without talking to the others.
//!
//! - [`bisect`]: recursive coordinate bisection of weighted points into any number of parts,
//!   each with an axis-aligned region ([`Bounds`]); [`Decomposition::owner`] names the part
//!   whose region holds a point;
//! - [`plan_migration`] and [`MigrationPlan::apply`]: which points leave which part for
//!   which other part when the regions change or the points move;
//! - [`select_halos`] and [`Decomposition::parts_within`]: the copies of other parts' points
//!   (with the periodic shift that brings each image next to the region) a part needs to
//!   evaluate its own points' neighbour sums;
//! - [`part_loads`], [`imbalance`] and [`RebalancePolicy`]: when the work has drifted far
//!   enough from the cuts to decompose again;
//! - [`ExactSum`]: an exact, order-independent sum of `f64` values, so a global reduction
//!   gives the same bits however its terms are spread over parts;
//! - [`Transport`]: the all-to-all exchange between parts the collectives are built on, with
//!   [`InProcess`] for parts that are threads of one process.

mod balance;
mod bisection;
mod bounds;
mod exact_sum;
mod halo;
mod migration;
#[cfg(feature = "mpi")]
mod mpi;
#[cfg(test)]
mod test_support;
mod transport;

pub use balance::{imbalance, part_loads, RebalancePolicy};
pub use bisection::{bisect, Cut, Decomposition};
pub use bounds::Bounds;
pub use exact_sum::{exact_sum, ExactSum};
pub use halo::{select_halos, HaloEntry};
pub use migration::{plan_migration, Departures, MigrationPlan};
#[cfg(feature = "mpi")]
pub use mpi::MpiTransport;
pub use transport::{
    all_gather, all_parts, max_over_parts, push_vector, read_scalar, read_vector, sum_over_parts,
    Counted, InProcess, Message, Traffic, Transport,
};

/// Global particle identity, as stored in [`crate::Fluid::id`]: unique over the whole run,
/// independent of which part holds the particle and where in its arrays.
pub type GlobalId = u32;
