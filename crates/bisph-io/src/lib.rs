//! # bisph-io
//!
//! Everything between bisph's physics and the outside world: the case-file schema with
//! named errors, building a simulation from a case, VTK/CSV/JSON outputs, plots, and the run
//! loop of `bisph run`.

pub mod build;
pub mod case;
pub mod output;
pub mod pack;
pub mod pack_cases;
pub mod paper1_cases;
pub mod paper2_cases;
pub mod paper3_cases;
pub mod plot;
pub mod regions;
pub mod runner;
pub mod shapes;
pub mod shepard;
pub mod validate;
pub mod vtk;

pub use case::{load_case, parse_case, Case, CaseError, LoadedCase};
pub use runner::{run_case, Progress, RunError, Summary};
