//! # bisph-io
//!
//! Everything between bisph's physics and the outside world, in three layers that depend
//! downwards only:
//!
//! - [`run`]: the run loop of `bisph run` with its outputs, checkpoints and diagnostics, and
//!   the drivers of `bisph pack` and `bisph shepard`;
//! - [`case`]: the case-file schema with named errors, its checks, and building a simulation
//!   from a case;
//! - [`formats`]: VTK, CSV series, plots, mesh and point files.

pub mod case;
pub mod formats;
pub mod run;

pub use case::{load_case, parse_case, Case, CaseError, LoadedCase};
pub use run::{
    resume_case, run_case, run_case_split, run_case_with, Progress, RunError, RunOptions, Summary,
};
