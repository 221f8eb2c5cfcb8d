//! Running a case: the time loop of `bisph run` with its outputs, checkpoints, diagnostics
//! and settling, and the drivers of `bisph pack` and `bisph shepard`.

pub mod checkpoint;
pub mod diagnostics;
pub mod error;
pub mod outputs;
pub mod pack;
pub mod runner;
pub mod settle;
pub mod shepard;

pub use error::RunError;
pub use runner::{
    build_checked, resume_case, run_built, run_case, run_case_split, run_case_with, run_split,
    settle_fresh, settle_resumable, Progress, RunOptions, Summary,
};
