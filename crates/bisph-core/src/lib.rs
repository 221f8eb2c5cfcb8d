//! # bisph-core
//!
//! Weakly compressible SPH with walls modelled by boundary integrals: the physics of bisph,
//! free of any file I/O. 2-D and 3-D share one source through the [`dim::Vector`] trait.
//!
//! References (paper numbers as in the project's design brief):
//! 1. Cercos-Pita et al. (2024), energy-conserving boundary integrals;
//! 2. Calderon-Sanchez et al., the geometric Shepard factor;
//! 3. Mayrhofer et al. (2013), unified semi-analytical wall boundary conditions;
//! 4. Boregowda & Liu, BIPI particle initialisation.
#![deny(missing_docs)]

mod avx2;
pub mod bi;
pub mod bodies;
pub mod decomposition;
pub mod dim;
pub mod energy;
pub mod eos;
pub mod error;
pub mod forcing;
pub mod geometry;
pub mod kernel;
pub mod neighbours;
pub mod packing;
pub mod particles;
pub mod probes;
pub mod quadrature;
pub mod region;
pub mod simulation;
pub mod surface;
pub mod terms;
pub mod walls;

pub use dim::Vector;
pub use energy::EnergyBudget;
pub use eos::Eos;
pub use error::SimError;
pub use kernel::Wendland;
pub use particles::Fluid;
pub use simulation::{SimConfig, Simulation, WallModelChoice};
pub use walls::{BoundaryElements, Walls};
