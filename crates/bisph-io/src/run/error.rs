//! What can stop a run, with its exit status.

use crate::case::error::CaseError;
use crate::case::geometry_check::GeometryError;
use crate::formats::files::OutputError;
use crate::run::checkpoint::CheckpointError;
use crate::run::diagnostics::Diagnosis;
use std::path::PathBuf;

/// Why a run failed.
#[derive(Debug)]
pub enum RunError {
    /// The case is wrong.
    Case(CaseError),
    /// The case's geometry is wrong (found before the first step; nothing is written).
    Geometry(GeometryError),
    /// An output could not be written (the last checkpoint on disk is kept).
    Output(OutputError),
    /// A checkpoint was refused.
    Checkpoint(CheckpointError),
    /// The case needs more memory than the machine has.
    Resources(String),
    /// The run was interrupted by a signal; a checkpoint was written.
    Interrupted {
        /// Step reached.
        step: u64,
        /// Time reached.
        time: f64,
        /// The checkpoint to resume from.
        checkpoint: PathBuf,
    },
    /// Settling was interrupted by a signal, before `t = 0`.
    SettlingInterrupted {
        /// Settling time reached [s].
        time: f64,
        /// The checkpoint of the settling state to resume from (none when `checkpoint.on_signal`
        /// is off and no periodic one was written).
        checkpoint: Option<PathBuf>,
    },
    /// A divergence watch tripped (outputs up to the last good state are kept;
    /// `diagnostics.json` says what happened).
    Stopped(Box<Diagnosis>),
}

impl RunError {
    /// Exit code of `bisph run` for this error (see the table in `docs/outputs-and-errors.md`).
    pub fn exit_code(&self) -> u8 {
        match self {
            RunError::Case(_) => 1,
            RunError::Geometry(_) => 7,
            RunError::Output(_) => 4,
            RunError::Checkpoint(_) => 5,
            RunError::Resources(_) => 6,
            RunError::Interrupted { .. } | RunError::SettlingInterrupted { .. } => 10,
            RunError::Stopped(d) => d.exit_code,
        }
    }
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Case(e) => write!(f, "{e}"),
            RunError::Geometry(e) => write!(f, "{e}"),
            RunError::Output(e) => write!(f, "{e}"),
            RunError::Checkpoint(e) => write!(f, "{e}"),
            RunError::Resources(e) => write!(f, "{e}"),
            RunError::Interrupted {
                step,
                time,
                checkpoint,
            } => write!(
                f,
                "interrupted at step {step} (t = {time:.6e} s); checkpoint written to {}",
                checkpoint.display()
            ),
            RunError::SettlingInterrupted {
                time,
                checkpoint: Some(checkpoint),
            } => write!(
                f,
                "interrupted while settling (settling time {time:.3} s), before the run started; checkpoint written to {}",
                checkpoint.display()
            ),
            RunError::SettlingInterrupted {
                time,
                checkpoint: None,
            } => write!(
                f,
                "interrupted while settling (settling time {time:.3} s), before the run started: nothing to resume, run it again"
            ),
            RunError::Stopped(d) => write!(f, "simulation stopped: {d}"),
        }
    }
}

impl std::error::Error for RunError {}

impl From<OutputError> for RunError {
    fn from(e: OutputError) -> Self {
        RunError::Output(e)
    }
}

impl From<CheckpointError> for RunError {
    fn from(e: CheckpointError) -> Self {
        RunError::Checkpoint(e)
    }
}
