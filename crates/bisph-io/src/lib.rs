//! # bisph-io
//!
//! Everything between bisph's physics and the outside world: the case-file schema with
//! named errors, building a simulation from a case, VTK/CSV/JSON outputs, plots, and the run
//! loop of `bisph run`.

pub mod apollo;
pub mod bodies_out;
pub mod build;
pub mod case;
pub mod checkpoint;
pub mod diagnostics;
pub mod mesh_walls;
pub mod output;
pub mod pack;
pub mod pack_cases;
pub mod paper1_cases;
pub mod paper2_cases;
pub mod paper3_cases;
pub mod paper3_flow_cases;
pub mod plot;
pub mod regions;
pub mod resources;
pub mod rigid_cases;
pub mod runner;
pub mod settle;
pub mod shapes;
pub mod shepard;
pub mod spheric2;
pub mod still_water;
pub mod validate;
pub mod vtk;

pub use case::{load_case, parse_case, Case, CaseError, LoadedCase};
pub use runner::{resume_case, run_case, run_case_with, Progress, RunError, RunOptions, Summary};
