//! A run split over the ranks of an MPI job gives the bits of one process: the energy budget,
//! the bodies' motion, the probes and the time at every step, and every particle's final
//! state, for 1 to 4 ranks (oversubscribed where the machine has fewer cores).
//!
//! `cargo test --features mpi --test mpi` runs the cases in one process, then launches this
//! program under `mpirun` for each case and rank count; each rank runs its part, and rank 0
//! writes the trace for the comparison.

#[path = "support/split_runs.rs"]
mod split_runs;

use bisph_core::decomposition::MpiTransport;
use bisph_core::dim::Vector;
use bisph_core::Simulation;
use bisph_io::case::CaseDim;
use glam::{DVec2, DVec3};
use split_runs::{advance, SplitCase, SPLIT_CASES};
use std::path::Path;
use std::process::Command;

/// Set for the ranks: the index of the case in [`SPLIT_CASES`].
const CASE_VARIABLE: &str = "BISPH_SPLIT_CASE";
/// Set for the ranks: where rank 0 writes the trace.
const TRACE_VARIABLE: &str = "BISPH_SPLIT_TRACE";

fn main() {
    match std::env::var(CASE_VARIABLE) {
        Ok(index) => run_rank(&SPLIT_CASES[index.parse::<usize>().expect("a case index")]),
        Err(_) => compare_all(),
    }
}

/// One rank of the MPI job: its part of the case, the trace written by rank 0.
fn run_rank(case: &SplitCase) {
    let transport = MpiTransport::initialise().expect("MPI initialised once");
    let lines = if case.three_d {
        part_trace::<DVec3>(case, transport)
    } else {
        part_trace::<DVec2>(case, transport)
    };
    if let Some(lines) = lines {
        let path = std::env::var(TRACE_VARIABLE).expect("a trace path");
        std::fs::write(path, lines.join("\n")).expect("the trace written");
    }
}

/// This rank's run of `case`; the trace on rank 0.
fn part_trace<V: CaseDim>(case: &SplitCase, transport: MpiTransport) -> Option<Vec<String>> {
    let whole = case.build::<V>();
    let mut part = Simulation::part_of(&whole, Box::new(transport));
    drop(whole);
    let trace = advance(&mut part, case.steps);
    (part.rank() == 0).then(|| trace.lines())
}

fn whole_trace<V: Vector + CaseDim>(case: &SplitCase) -> Vec<String> {
    let mut whole = case.build::<V>();
    advance(&mut whole, case.steps).lines()
}

/// Every case on 1 to 4 ranks against one process.
fn compare_all() {
    let program = std::env::current_exe().expect("the test program's path");
    let scratch = tempfile::Builder::new()
        .prefix("bisph-mpi-")
        .tempdir()
        .expect("a scratch folder");
    let dir = scratch.path();
    let mut failures = Vec::new();
    for (index, case) in SPLIT_CASES.iter().enumerate() {
        let expected = if case.three_d {
            whole_trace::<DVec3>(case)
        } else {
            whole_trace::<DVec2>(case)
        };
        for ranks in 1..=4 {
            let trace = dir.join(format!("trace-{index}-{ranks}.txt"));
            launch(&program, index, ranks, &trace);
            let text = std::fs::read_to_string(&trace).expect("rank 0 wrote its trace");
            let got: Vec<&str> = text.lines().collect();
            let verdict = match got.iter().zip(&expected).position(|(g, e)| g != e) {
                Some(line) => format!("differs at line {} of {}", line + 1, expected.len()),
                None if got.len() != expected.len() => {
                    format!("{} lines against {}", got.len(), expected.len())
                }
                None => "same bits".to_string(),
            };
            println!("{} on {ranks} ranks: {verdict}", case.name);
            if verdict != "same bits" {
                failures.push(format!("{} on {ranks} ranks", case.name));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "runs that differ from one process: {failures:?}"
    );
}

/// Runs case `index` of this program under `mpirun` on `ranks` ranks, one thread each.
fn launch(program: &Path, index: usize, ranks: usize, trace: &Path) {
    let status = Command::new("mpirun")
        .args(["-np", &ranks.to_string(), "--oversubscribe"])
        .args([
            "-x",
            CASE_VARIABLE,
            "-x",
            TRACE_VARIABLE,
            "-x",
            "RAYON_NUM_THREADS",
        ])
        .arg(program)
        .env(CASE_VARIABLE, index.to_string())
        .env(TRACE_VARIABLE, trace)
        .env("RAYON_NUM_THREADS", "1")
        // Containers often run tests as root, which Open MPI refuses unless told.
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .status()
        .unwrap_or_else(|e| panic!("mpirun could not be started ({e}): install Open MPI"));
    assert!(status.success(), "mpirun -np {ranks} failed: {status}");
}
