//! Starts by a parallel launcher (`mpirun -np K`, `srun` with several tasks, ...): one process
//! per rank. `bisph run` and `bisph bench --single` split their case over the ranks (with the
//! `mpi` feature); every other command runs in one process and refuses such a start.

use bisph_core::decomposition::Transport;

/// Where Open MPI, MPICH (and the PMI launchers, Slurm's included) and MVAPICH give the number
/// of processes they started.
const SIZE_VARIABLES: [&str; 3] = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE"];

/// The first of `variables` that holds a count above one, with that count.
fn count_above_one(variables: &[&'static str]) -> Option<(&'static str, usize)> {
    variables.iter().find_map(|&name| {
        let n = std::env::var(name).ok()?.trim().parse::<usize>().ok()?;
        (n > 1).then_some((name, n))
    })
}

/// The variable and the number of processes of a launch that started more than one.
fn several_processes() -> Option<(&'static str, usize)> {
    count_above_one(&SIZE_VARIABLES)
}

/// Where Open MPI, MPICH and Slurm give the number of processes of a launch on this machine.
const LOCAL_SIZE_VARIABLES: [&str; 3] = [
    "OMPI_COMM_WORLD_LOCAL_SIZE",
    "MPI_LOCALNRANKS",
    "SLURM_NTASKS_PER_NODE",
];

/// The threads each process of a launch takes when `--threads` is not given: the cores it
/// may run on shared by the processes the launch started on this machine, at least one
/// (`None`: a start as one process, which takes every core it may run on). A process bound
/// to one core sees that core alone; unbound processes would otherwise each take every core
/// and slow one another several times over.
pub fn threads_per_rank() -> Option<usize> {
    let (_, local) = count_above_one(&LOCAL_SIZE_VARIABLES)?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    Some((cores / local).max(1))
}

/// Refuses a start as one of several processes: each would run the whole case and write the
/// same outputs.
pub fn one_process() -> Result<(), (u8, String)> {
    match several_processes() {
        None => Ok(()),
        Some((name, count)) => Err((
            1,
            format!(
                "started as one of {count} processes ({name} = {count}): each would run the \
                 whole case and write the same outputs; expected one process (bisph uses \
                 every core through threads, `--threads N`): start it without the \
                 launcher, or with -np 1"
            ),
        )),
    }
}

/// The transport between the ranks of a launch that started several processes (`None` for
/// one process).
pub fn rank_transport() -> Result<Option<Box<dyn Transport>>, (u8, String)> {
    let Some((name, count)) = several_processes() else {
        return Ok(None);
    };
    mpi_transport(name, count).map(Some)
}

#[cfg(feature = "mpi")]
fn mpi_transport(_: &str, _: usize) -> Result<Box<dyn Transport>, (u8, String)> {
    match bisph_core::decomposition::MpiTransport::initialise() {
        Some(transport) => Ok(Box::new(transport)),
        None => Err((1, "MPI could not be initialised".into())),
    }
}

#[cfg(not(feature = "mpi"))]
fn mpi_transport(name: &str, count: usize) -> Result<Box<dyn Transport>, (u8, String)> {
    Err((
        1,
        format!(
            "started as one of {count} processes ({name} = {count}), but this bisph was built \
             without MPI: build it with `cargo install --locked --path crates/bisph --features \
             mpi` (needs Open MPI and libclang), or start one process"
        ),
    ))
}
