//! Runs a case to its end time, writing the outputs of the command-line contract.

use crate::case::build::build_simulation_with_layout;
use crate::case::geometry_check::check_geometry;

use crate::case::dim::CaseDim;
use crate::case::schema::{CheckpointSection, LoadedCase};
use crate::formats::files::{at, write_atomic, OutputError};
use crate::formats::plot::{write_png, Plot, Series as PlotSeries, Style};
use crate::formats::series::Series;
use crate::run::checkpoint;
use crate::run::checkpoint::{Checkpoint, CheckpointError, RunCounters, SimState};
use crate::run::diagnostics::{energy_growth, from_sim_error, Diagnosis, Watch};
use crate::run::error::RunError;
use crate::run::outputs::Frames;
use crate::run::settle::SettlingSummary;
use bisph_core::bodies::Motion;
use bisph_core::decomposition::Transport;
use bisph_core::simulation::{MidpointParams, SettleReport};
use bisph_core::Simulation;
use serde::Serialize;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Wall-clock seconds of the time loop by phase.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseSeconds {
    /// Cell grid rebuilds, reordering excluded.
    pub neighbour_search: f64,
    /// Reordering the particles by cell.
    pub reorder: f64,
    /// Fluid and wall terms of the rate sweeps, equation of state included.
    pub forces: f64,
    /// Wall pressures (extrapolation to the elements).
    pub wall_pressure: f64,
    /// The rest of the steps: updates, bounce, checks.
    pub integration: f64,
    /// Everything outside the steps: energies, probes, CSV and VTK output.
    pub output: f64,
}

impl PhaseSeconds {
    fn new(t: &bisph_core::simulation::PhaseTimes, wall_seconds: f64) -> Self {
        PhaseSeconds {
            neighbour_search: t.neighbours - t.reorder,
            reorder: t.reorder,
            forces: t.rates - t.wall_pressure,
            wall_pressure: t.wall_pressure,
            integration: t.steps - t.neighbours - t.rates,
            output: wall_seconds - t.steps,
        }
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Case name.
    pub case: String,
    /// Dimension.
    pub dim: usize,
    /// Fluid particles at the start (those removed included).
    pub fluid_particles: usize,
    /// Fluid particles removed as they left the domain (their energy is the `removed` column
    /// of `energy.csv`).
    pub removed_particles: u64,
    /// Boundary elements.
    pub boundary_elements: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time reached [s].
    pub time: f64,
    /// Wall-clock seconds of the time loop (outputs included; all invocations of a resumed run).
    pub wall_seconds: f64,
    /// Fluid particles times steps over wall seconds.
    pub particle_steps_per_second: f64,
    /// Where the wall seconds went.
    pub phase_seconds: PhaseSeconds,
    /// Builds of the neighbour (Verlet) list in this invocation.
    pub neighbour_list_builds: u64,
    /// Steps of this invocation that kept the neighbour lists although some particles had
    /// moved more than half the skin since their build (none had come within reach of a
    /// partner the lists lack).
    pub neighbour_lists_kept_past_half_skin: u64,
    /// `(E_total(end) - E_total(0)) / E_scale`, where `E_scale` is the initial kinetic and
    /// compressible energy plus the potential energy above the lowest particle.
    pub energy_drift_relative: f64,
    /// `E_scale` [J (per unit depth in 2-D)].
    pub energy_scale: f64,
    /// Initial and final total energy.
    pub energy_total_initial: f64,
    /// Final total energy.
    pub energy_total_final: f64,
    /// Largest `|E_total(t) - E_total(0)| / E_scale` over the run.
    pub energy_drift_max_relative: f64,
    /// Largest particle speed at the end.
    pub max_speed_final: f64,
    /// Largest particle speed seen at any series row.
    pub max_speed_max: f64,
    /// Mean midpoint iterations per step (1 for Verlet).
    pub iterations_mean: f64,
    /// Most midpoint iterations in a step.
    pub iterations_max: u32,
    /// Largest final residue of a step (paper 1, eq 53).
    pub residue_max: f64,
    /// Steps that ended without reaching the residue tolerance.
    pub unconverged_steps: u64,
    /// Threads used (by each process of a split run).
    pub threads: usize,
    /// Processes the run was split over (1 for a run in one process).
    pub ranks: usize,
    /// VTK frames written.
    pub frames: usize,
    /// Checkpoints written by this invocation.
    pub checkpoints: u64,
    /// Step this invocation resumed from (absent for a fresh run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resumed_from_step: Option<u64>,
    /// Free bodies: largest `|E_fluid + E_bodies - (same at 0)| / E_scale` over the run, with
    /// `E_bodies` their kinetic (translation + rotation) and gravity energy; absent without
    /// free bodies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fluid_body_energy_drift_max_relative: Option<f64>,
    /// Free bodies: the same at the end of the run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fluid_body_energy_drift_relative: Option<f64>,
    /// Fluid particles behind a wall (inside a body or through a wall) at the end.
    pub particles_behind_walls: usize,
    /// The settling stage before `t = 0` (absent when `[settle]` is off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settling: Option<SettlingSummary>,
    /// Why the run stopped early (absent when it reached its end).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

/// File in the output folder holding the settling report of a fresh run (read back when the
/// run is resumed).
const SETTLING_FILE: &str = "settling.json";

/// Settles a fresh run when the case asks for it, or continues the settling that a checkpoint
/// taken before `t = 0` holds, and writes `settling.json`; a run resumed after `t = 0` reads
/// that report back (its checkpoint already holds the settled state). Returns the settling
/// report and the checkpoint the run itself resumes from (none after settling). Only the
/// `writer` touches files: the other processes of a split run settle the same whole fluid.
fn settle_or_recall<V: CaseDim>(
    loaded: &LoadedCase,
    sim: &mut Simulation<V>,
    out: &Path,
    resumed: Option<Checkpoint<V>>,
    options: &RunOptions,
    writer: bool,
    progress: &mut dyn FnMut(Progress),
) -> Result<(Option<SettlingSummary>, Option<Checkpoint<V>>), RunError> {
    let path = out.join(SETTLING_FILE);
    let checkpoint_path = out.join(checkpoint::FILE_NAME);
    let settling_state = match resumed {
        Some(c) if c.settling.is_none() => {
            let recalled = std::fs::read_to_string(&path)
                .ok()
                .and_then(|text| serde_json::from_str(&text).ok());
            return Ok((recalled, Some(c)));
        }
        Some(c) => Some(c),
        None => {
            // A checkpoint left by an earlier run in this folder must not be resumed from
            // once this one has started.
            if writer && checkpoint_path.exists() {
                at(&checkpoint_path, std::fs::remove_file(&checkpoint_path))?;
            }
            None
        }
    };
    if writer && path.exists() {
        at(&path, std::fs::remove_file(&path))?;
    }
    let checkpoints = SettlingCheckpoints {
        path: checkpoint_path,
        case_source: canonical_source(loaded),
        loaded,
        options,
        writer,
    };
    let continued = settling_state.and_then(|c| c.settling.map(|report| (c.sim, report)));
    let settling = settle_checkpointed(
        loaded,
        sim,
        continued,
        Some(&checkpoints),
        options.stop,
        progress,
    )?;
    if let (Some(s), true) = (&settling, writer) {
        write_settling(out, s)?;
    }
    Ok((settling, None))
}

/// Settles `sim` (built fresh from the case) when the case asks for it, writing checkpoints
/// of the settling state into `checkpoint` as `options` and the case's `[checkpoint]` ask:
/// from the start, or continued from `resumed`, a checkpoint written so (its settling report
/// set). For front ends that hold the simulation and resume it themselves.
pub fn settle_resumable<V: CaseDim>(
    loaded: &LoadedCase,
    sim: &mut Simulation<V>,
    resumed: Option<Checkpoint<V>>,
    checkpoint: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<Option<SettlingSummary>, RunError> {
    let checkpoints = SettlingCheckpoints {
        path: checkpoint.to_path_buf(),
        case_source: canonical_source(loaded),
        loaded,
        options,
        writer: true,
    };
    let continued = resumed.and_then(|c| c.settling.map(|report| (c.sim, report)));
    settle_checkpointed(
        loaded,
        sim,
        continued,
        Some(&checkpoints),
        options.stop,
        progress,
    )
}

/// Settles a fresh simulation when the case asks for it, as [`run`] does: `progress` sees
/// every settling step (`settling: true`, the most settling time as `end`); a failed step is
/// diagnosed as in a run; `stop`, once set, ends settling after the step in progress with
/// [`RunError::SettlingInterrupted`].
pub fn settle_fresh<V: CaseDim>(
    loaded: &LoadedCase,
    sim: &mut Simulation<V>,
    stop: Option<&AtomicBool>,
    progress: &mut dyn FnMut(Progress),
) -> Result<Option<SettlingSummary>, RunError> {
    settle_checkpointed(loaded, sim, None, None, stop, progress)
}

/// Where and how often settling writes its checkpoints.
struct SettlingCheckpoints<'a> {
    path: PathBuf,
    case_source: String,
    loaded: &'a LoadedCase,
    options: &'a RunOptions<'a>,
    /// Whether this process writes them (the first of a split run's).
    writer: bool,
}

/// Settles `sim` (built fresh from the case) when the case asks for it: from the start, or
/// from the settling state `continued` (a checkpoint's state and report). With `checkpoints`,
/// writes one as the case's `[checkpoint]` asks (and on a stop signal), so that settling
/// resumes where it stopped, bit for bit.
fn settle_checkpointed<V: CaseDim>(
    loaded: &LoadedCase,
    sim: &mut Simulation<V>,
    continued: Option<(SimState<V>, SettleReport)>,
    checkpoints: Option<&SettlingCheckpoints>,
    stop: Option<&AtomicBool>,
    progress: &mut dyn FnMut(Progress),
) -> Result<Option<SettlingSummary>, RunError> {
    // The parameters follow from the fresh start (its depth and width), as when settling began.
    let Some(params) = crate::run::settle::params(loaded, sim) else {
        return Ok(None);
    };
    let original = sim.fluid.clone();
    let so_far = match continued {
        Some((state, report)) => {
            let path = checkpoints.map(|c| c.path.clone()).unwrap_or_default();
            state
                .restore(sim)
                .map_err(|reason| CheckpointError::Mismatch { path, reason })?;
            report
        }
        None => SettleReport::starting(),
    };
    let mut saved = Checkpoint::<V>::default();
    let mut last_checkpoint = Instant::now();
    let mut failed: Option<OutputError> = None;
    let settled = sim.settle_from(&params, &original, so_far, &mut |sim, report| {
        progress(Progress {
            time: report.time,
            end: params.max_time,
            step: report.steps,
            settling: true,
        });
        let signalled = stop.is_some_and(|s| s.load(Ordering::SeqCst));
        if let Some(c) = checkpoints.filter(|c| c.writer) {
            let section = &c.loaded.case.checkpoint;
            if checkpoint_due(section, c.options, report.steps, last_checkpoint, signalled) {
                saved.case_source.clone_from(&c.case_source);
                saved.case_text.clone_from(&c.loaded.text);
                saved.sim.capture(sim);
                saved.settling = Some(*report);
                if let Err(e) = checkpoint::write(&c.path, &saved) {
                    failed = Some(e);
                    return ControlFlow::Break(());
                }
                last_checkpoint = Instant::now();
            }
        }
        match signalled {
            true => ControlFlow::Break(()),
            false => ControlFlow::Continue(()),
        }
    });
    let report = settled.map_err(|e| RunError::Stopped(Box::new(from_sim_error(&e, sim))))?;
    if let Some(e) = failed {
        return Err(RunError::Output(e));
    }
    let summary = SettlingSummary::new(&report, &params);
    if summary.interrupted() {
        return Err(RunError::SettlingInterrupted {
            time: summary.time,
            // Any checkpoint in the folder now is of this settling (a fresh run removes an
            // earlier run's before it starts).
            checkpoint: checkpoints
                .map(|c| c.path.clone())
                .filter(|path| path.exists()),
        });
    }
    Ok(Some(summary))
}

/// Whether a checkpoint is due at step `step`: every `every_steps` steps, every
/// `every_minutes` of wall clock since `last`, or on a stop signal (options override the
/// case's `[checkpoint]`).
fn checkpoint_due(
    section: &CheckpointSection,
    options: &RunOptions,
    step: u64,
    last: Instant,
    signalled: bool,
) -> bool {
    let every_steps = options.checkpoint_steps.unwrap_or(section.every_steps);
    let every_seconds = 60.0 * options.checkpoint_minutes.unwrap_or(section.every_minutes);
    (every_steps > 0 && step > 0 && step.is_multiple_of(every_steps))
        || (every_seconds > 0.0 && last.elapsed().as_secs_f64() >= every_seconds)
        || (signalled && section.on_signal)
}

/// The case file's canonical path (what a checkpoint saves to find relative file names).
fn canonical_source(loaded: &LoadedCase) -> String {
    std::fs::canonicalize(&loaded.source)
        .map(|p| p.display().to_string())
        .unwrap_or_else(|_| loaded.source.clone())
}

/// Writes the settling report into the output folder (`settling.json`).
fn write_settling(out: &Path, settling: &SettlingSummary) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(settling).expect("a settling report serialises");
    write_atomic(&out.join(SETTLING_FILE), text.as_bytes())?;
    Ok(())
}

/// Progress report for a front end.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    /// Current time.
    pub time: f64,
    /// End time.
    pub end: f64,
    /// Steps so far.
    pub step: u64,
    /// `true` while settling before `t = 0`: `time` is then the settling time, `end` the most
    /// settling time and `step` the settling steps.
    pub settling: bool,
}

/// How `bisph run` runs, beyond the case.
#[derive(Debug, Default, Clone, Copy)]
pub struct RunOptions<'a> {
    /// Checkpoint every this many steps (overrides `checkpoint.every_steps`).
    pub checkpoint_steps: Option<u64>,
    /// Checkpoint every this many wall-clock minutes (overrides `checkpoint.every_minutes`).
    pub checkpoint_minutes: Option<f64>,
    /// Set (by a signal handler) to stop at the next step with a checkpoint.
    pub stop: Option<&'a AtomicBool>,
    /// Continue from `out/checkpoint.bin`.
    pub resume: bool,
}

/// Runs the case in its dimension; see [`run`].
pub fn run_case(
    loaded: &LoadedCase,
    out: &Path,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    run_case_with(loaded, out, &RunOptions::default(), progress)
}

/// Runs the case in its dimension with options; see [`run`].
pub fn run_case_with(
    loaded: &LoadedCase,
    out: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    run_case_split(loaded, out, options, None, progress)
}

/// Runs the case in its dimension with options, split over the parts `transport` joins when
/// given; see [`run_split`].
pub fn run_case_split(
    loaded: &LoadedCase,
    out: &Path,
    options: &RunOptions,
    transport: Option<Box<dyn Transport>>,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    if loaded.case.dim == 2 {
        run_split::<glam::DVec2>(loaded, out, options, transport, progress)
    } else {
        run_split::<glam::DVec3>(loaded, out, options, transport, progress)
    }
}

/// The case stored in the checkpoint of output directory `dir`, for `bisph run --resume`.
pub fn resume_case(dir: &Path) -> Result<LoadedCase, RunError> {
    let path = dir.join(checkpoint::FILE_NAME);
    let bytes = std::fs::read(&path).map_err(|source| CheckpointError::Io {
        path: path.clone(),
        source,
    })?;
    let (source, text) = match checkpoint::peek_dim(&bytes) {
        Some(3) => {
            let c = checkpoint::decode::<glam::DVec3>(&path, &bytes)?;
            (c.case_source, c.case_text)
        }
        _ => {
            let c = checkpoint::decode::<glam::DVec2>(&path, &bytes)?;
            (c.case_source, c.case_text)
        }
    };
    crate::case::load::parse_case(&source, &text, &[]).map_err(RunError::Case)
}

/// The open CSV series of a run, in the order of [`checkpoint::SERIES_FILES`].
struct Outputs {
    series: [Option<Series>; checkpoint::SERIES],
}

impl Outputs {
    fn lengths(&self) -> [u64; checkpoint::SERIES] {
        let mut l = [0; checkpoint::SERIES];
        for (k, s) in self.series.iter().enumerate() {
            l[k] = s.as_ref().map_or(0, |s| s.len());
        }
        l
    }
    fn get(&mut self, k: usize) -> Option<&mut Series> {
        self.series[k].as_mut()
    }
}

const ENERGY: usize = 0;
const FORCES: usize = 1;
const PROBES: usize = 2;
const BODIES: usize = 3;
const MIDPOINT: usize = 4;
const FLUX: usize = 5;

/// The headers of a run's CSV series, in the order of [`checkpoint::SERIES_FILES`]; `None`
/// for a series the case does not write (pistons, midpoint iterations, flux forcing).
fn series_headers<V: CaseDim>(
    sim: &Simulation<V>,
    probe_header: &[String],
) -> [Option<Vec<String>>; checkpoint::SERIES] {
    let mut force_header = vec![
        "t".to_string(),
        "body".to_string(),
        "fx".into(),
        "fy".into(),
    ];
    if V::DIM == 3 {
        force_header.extend(["fz", "mx", "my", "mz"].map(String::from));
    }
    let has_pistons = sim
        .walls
        .bodies
        .iter()
        .any(|b| matches!(b.motion, Motion::Piston(_)));
    let midpoint = matches!(
        sim.config.integrator,
        bisph_core::simulation::Integrator::Midpoint(_)
    );
    [
        Some(
            [
                "t",
                "kinetic",
                "compressible",
                "potential",
                "wall_work",
                "total",
                "viscous_dissipation",
                "forcing_work",
                "diffusion_dissipation",
                "removed",
            ]
            .map(String::from)
            .to_vec(),
        ),
        Some(force_header),
        Some(probe_header.to_vec()),
        has_pistons.then(|| {
            [
                "t",
                "body",
                "position",
                "velocity",
                "kinetic",
                "outside_work",
            ]
            .map(String::from)
            .to_vec()
        }),
        midpoint.then(|| ["t", "iterations", "residue"].map(String::from).to_vec()),
        sim.config.flux.map(|_| {
            [
                "t",
                "bulk_velocity",
                "target_velocity",
                "force",
                "relative_error",
            ]
            .map(String::from)
            .to_vec()
        }),
    ]
}

/// Where a run starts: its open CSV series, VTK frames, counters and histories, either fresh
/// (files created with their headers, stale checkpoints removed) or from a checkpoint whose
/// state the simulation already holds (every series cut back to its saved length). Only the
/// `writer` (the first process of a split run) touches the files.
struct RunStart {
    outputs: Outputs,
    free_csv: Vec<Series>,
    fluid_body_max: f64,
    frames: Frames,
    counters: RunCounters,
    history: Vec<[f64; checkpoint::ENERGY_COLUMNS]>,
    probe_history: Vec<Vec<f64>>,
    resumed_from_step: Option<u64>,
}

/// The files a run opens besides its frames: the CSV series (`None` where the case writes
/// none) and each free body's series.
struct SeriesFiles<'a> {
    headers: &'a [Option<Vec<String>>; checkpoint::SERIES],
    free_bodies: &'a [PathBuf],
}

/// Opens the outputs of a run, fresh or resumed from the counters and histories of a
/// checkpoint (see [`RunStart`]).
fn start_run<V: CaseDim>(
    loaded: &LoadedCase,
    out: &Path,
    sim: &Simulation<V>,
    resumed: Option<Resumed>,
    files: SeriesFiles,
    writer: bool,
) -> Result<RunStart, RunError> {
    let mut outputs = Outputs {
        series: Default::default(),
    };
    let mut free_csv = Vec::new();
    match resumed {
        Some(c) => {
            for (k, header) in files.headers.iter().enumerate() {
                if header.is_some() && writer {
                    let path = out.join(checkpoint::SERIES_FILES[k]);
                    outputs.series[k] = Some(Series::reopen(path, c.run.csv_lengths[k])?);
                }
            }
            for (path, &len) in files.free_bodies.iter().zip(&c.run.body_csv_lengths) {
                if writer {
                    free_csv.push(Series::reopen(path.clone(), len)?);
                }
            }
            Ok(RunStart {
                outputs,
                free_csv,
                fluid_body_max: c.run.fluid_body_max,
                frames: Frames::resume(out, &c.run.frame_times, writer)?,
                counters: c.run,
                history: c.history,
                probe_history: c.probe_history,
                resumed_from_step: Some(sim.step),
            })
        }
        None => {
            if writer {
                create_series(loaded, out, &mut outputs, &mut free_csv, files)?;
            }
            Ok(RunStart {
                outputs,
                free_csv,
                fluid_body_max: 0.0,
                frames: Frames::new(out)?,
                counters: RunCounters {
                    scale: sim.energy_scale(),
                    e0_total: sim.energy().total,
                    ..RunCounters::default()
                },
                history: Vec::new(),
                probe_history: Vec::new(),
                resumed_from_step: None,
            })
        }
    }
}

/// The files of a fresh run: the copy of the case, the series with their headers; a stale
/// checkpoint or report of an earlier run in this folder removed, so neither is mistaken for
/// this run's.
fn create_series(
    loaded: &LoadedCase,
    out: &Path,
    outputs: &mut Outputs,
    free_csv: &mut Vec<Series>,
    files: SeriesFiles,
) -> Result<(), RunError> {
    write_atomic(&out.join("case.toml"), loaded.text.as_bytes())?;
    for (k, header) in files.headers.iter().enumerate() {
        if let Some(h) = header {
            let path = out.join(checkpoint::SERIES_FILES[k]);
            outputs.series[k] = Some(Series::create(path, h)?);
        }
    }
    for path in files.free_bodies {
        free_csv.push(Series::create(
            path.clone(),
            &crate::run::outputs::FREE_BODY_COLUMNS.map(String::from),
        )?);
    }
    for stale in [checkpoint::FILE_NAME, "diagnostics.json"] {
        let p = out.join(stale);
        if p.exists() {
            at(&p, std::fs::remove_file(&p))?;
        }
    }
    Ok(())
}

/// What a run resumed from a checkpoint continues besides the simulation state: the counters
/// and the histories of the series.
struct Resumed {
    run: RunCounters,
    history: Vec<[f64; checkpoint::ENERGY_COLUMNS]>,
    probe_history: Vec<Vec<f64>>,
}

/// Puts the state of checkpoint `c` (read from `path`) into the whole simulation `sim`, after
/// checking that it fits the case (its counts, its output intervals, its free bodies).
fn restore_checkpoint<V: CaseDim>(
    loaded: &LoadedCase,
    sim: &mut Simulation<V>,
    c: Checkpoint<V>,
    path: &Path,
) -> Result<Resumed, RunError> {
    let mismatch = |reason| CheckpointError::Mismatch {
        path: path.to_path_buf(),
        reason,
    };
    let output = &loaded.case.output;
    c.sim
        .restore(sim)
        .and_then(|_| {
            c.run
                .check(sim.time, output.series_interval, output.vtk_interval)
        })
        .map_err(mismatch)?;
    let free_bodies = free_body_names(sim).len();
    if c.run.body_csv_lengths.len() != free_bodies {
        return Err(RunError::Checkpoint(mismatch(format!(
            "{} free-body series saved, the case has {free_bodies} free bodies",
            c.run.body_csv_lengths.len(),
        ))));
    }
    Ok(Resumed {
        run: c.run,
        history: c.history,
        probe_history: c.probe_history,
    })
}

/// The names of the free bodies, in body order.
fn free_body_names<V: CaseDim>(sim: &Simulation<V>) -> Vec<&str> {
    sim.walls
        .bodies
        .iter()
        .filter(|b| matches!(b.motion, Motion::Free(_)))
        .map(|b| b.name.as_str())
        .collect()
}

/// Builds the simulation of a fresh run after the memory estimate, and checks its geometry
/// before any step: what [`run`] does first, and what front ends that hold the simulation call.
pub fn build_checked<V: CaseDim>(loaded: &LoadedCase) -> Result<Simulation<V>, RunError> {
    crate::case::resources::check_memory(loaded).map_err(RunError::Resources)?;
    let (sim, layout) = build_simulation_with_layout::<V>(loaded).map_err(RunError::Case)?;
    check_geometry(loaded, &sim, &layout).map_err(RunError::Geometry)?;
    Ok(sim)
}

/// Builds and runs a case, writing `energy.csv`, `forces.csv`, `probes.csv`, VTK frames,
/// `summary.json`, plots and a copy of the case into `out`; checkpoints into
/// `out/checkpoint.bin`; on a tripped watch, `diagnostics.json`.
pub fn run<V: CaseDim>(
    loaded: &LoadedCase,
    out: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    run_split::<V>(loaded, out, options, None, progress)
}

/// [`run`], split over the parts that `transport` joins when given (every part calls it at
/// once, each with its end of the transport; see [`Simulation::part_of`]). Every part builds
/// and settles the whole case, resumes the whole state of a checkpoint, then takes its part.
/// The outputs are those of the run in one process, to the bit, but for the VTK frames,
/// written as one piece per part with a `.pvtu` index; the first part writes every other
/// file, and the checkpoints hold the whole state (a run resumes on any number of parts).
pub fn run_split<V: CaseDim>(
    loaded: &LoadedCase,
    out: &Path,
    options: &RunOptions,
    transport: Option<Box<dyn Transport>>,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    let writer = transport.as_ref().is_none_or(|t| t.rank() == 0);
    let mut sim = build_checked::<V>(loaded)?;
    at(out, std::fs::create_dir_all(out))?;
    if writer {
        crate::formats::files::remove_stale_temporaries(out);
    }
    let checkpoint_path = out.join(checkpoint::FILE_NAME);
    let resumed = match options.resume {
        true => Some(checkpoint::read::<V>(&checkpoint_path)?),
        false => None,
    };
    let (settling, resumed) =
        settle_or_recall(loaded, &mut sim, out, resumed, options, writer, progress)?;
    let fluid_body0 = fluid_and_body_energy(&sim);
    let resumed = resumed
        .map(|c| restore_checkpoint(loaded, &mut sim, c, &checkpoint_path))
        .transpose()?;
    if let Some(transport) = transport {
        sim = Simulation::part_of(&sim, transport);
    }
    let start = RunBeginning {
        resumed,
        fluid_body0,
        checkpoint_path,
    };
    let ran = ActiveRun::open(loaded, out, &mut sim, start).and_then(|mut active| {
        let ending = active.advance_to_end(&mut sim, options, progress)?;
        active.finish(&mut sim, settling, ending)
    });
    // Every part meets the same stops, but only the part that met it knows of a file it
    // could not write.
    if let Err(RunError::Output(_)) = &ran {
        sim.abandon_split();
    }
    ran
}

/// Runs a simulation built (and settled) by the caller from its current state to the case's
/// end time, writing the outputs of a fresh run into `out` exactly as [`run`] does after its
/// build and settling: the entry point of front ends that hold the simulation themselves.
/// `settling` is the report of the settling that preceded it, if any (`settling.json` and the
/// summary's `settling`). The series and frames start at the simulation's current time.
pub fn run_built<V: CaseDim>(
    loaded: &LoadedCase,
    sim: &mut Simulation<V>,
    settling: Option<SettlingSummary>,
    out: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    at(out, std::fs::create_dir_all(out))?;
    crate::formats::files::remove_stale_temporaries(out);
    let settling_path = out.join(SETTLING_FILE);
    match &settling {
        Some(s) => write_settling(out, s)?,
        None if settling_path.exists() => at(&settling_path, std::fs::remove_file(&settling_path))?,
        None => {}
    }
    let start = RunBeginning {
        resumed: None,
        fluid_body0: fluid_and_body_energy(sim),
        checkpoint_path: out.join(checkpoint::FILE_NAME),
    };
    let mut active = ActiveRun::open(loaded, out, sim, start)?;
    let ending = active.advance_to_end(sim, options, progress)?;
    active.finish(sim, settling, ending)
}

/// How the time loop of a run ended.
enum Ending {
    /// The end time was reached.
    Reached,
    /// A stop signal arrived (after a checkpoint when the case asks for one).
    Interrupted,
    /// A watch tripped or a step failed.
    Tripped(Diagnosis),
}

/// The fluid's kinetic, compressible and potential energy plus the free bodies' kinetic and
/// gravity energy.
fn fluid_and_body_energy<V: CaseDim>(sim: &Simulation<V>) -> f64 {
    let e = sim.energy();
    let (k, p) = sim.walls.body_energy();
    e.kinetic + e.compressible + e.potential + k + p
}

/// How a run begins, besides its simulation: the checkpoint it resumes from (its state
/// already restored), the fluid and body energy at the start of the run, and where its
/// checkpoints go.
struct RunBeginning {
    resumed: Option<Resumed>,
    fluid_body0: f64,
    checkpoint_path: PathBuf,
}

/// A run between its start and its end: the open outputs, the counters and histories a
/// checkpoint saves, the last good state the watches fall back to, and the clocks.
struct ActiveRun<'a, V: CaseDim> {
    loaded: &'a LoadedCase,
    out: &'a Path,
    /// Whether this process writes the files other than its frame pieces: the only one of a
    /// whole run, the first of a split run.
    writer: bool,
    checkpoint_path: PathBuf,
    /// The case file's canonical path, saved in each checkpoint.
    case_source: String,
    probe_header: Vec<String>,
    midpoint: Option<MidpointParams>,
    /// Whether the case has free bodies (one CSV each, and the fluid + bodies energy).
    has_free: bool,
    /// [`fluid_and_body_energy`] at the start.
    fluid_body0: f64,
    outputs: Outputs,
    free_csv: Vec<Series>,
    fluid_body_max: f64,
    frames: Frames,
    counters: RunCounters,
    history: Vec<[f64; checkpoint::ENERGY_COLUMNS]>,
    probe_history: Vec<Vec<f64>>,
    resumed_from_step: Option<u64>,
    watch: Watch,
    /// The last good state (at the last loop point) with its counters and history lengths.
    good: SimState<V>,
    good_counters: RunCounters,
    good_rows: (usize, usize),
    /// Checkpoints written by this invocation.
    checkpoints: u64,
    started: Instant,
    /// Wall seconds of the earlier invocations of a resumed run.
    wall_before: f64,
    last_checkpoint: Instant,
}

impl<'a, V: CaseDim> ActiveRun<'a, V> {
    /// Opens the outputs of the run of `loaded` into `out`, fresh or resumed (`sim` then
    /// holds the checkpoint's state), and starts the clocks.
    fn open(
        loaded: &'a LoadedCase,
        out: &'a Path,
        sim: &mut Simulation<V>,
        beginning: RunBeginning,
    ) -> Result<Self, RunError> {
        let writer = sim.rank() == 0;
        let mut probe_header = vec!["t".to_string()];
        probe_header.extend(sim.probes.iter().map(|p| p.name.clone()));
        let midpoint = match sim.config.integrator {
            bisph_core::simulation::Integrator::Midpoint(p) => Some(p),
            bisph_core::simulation::Integrator::Verlet => None,
        };
        let headers = series_headers(sim, &probe_header);
        let free_bodies: Vec<PathBuf> = free_body_names(sim)
            .iter()
            .map(|name| out.join(format!("body_{name}.csv")))
            .collect();
        let files = SeriesFiles {
            headers: &headers,
            free_bodies: &free_bodies,
        };
        let start = start_run(loaded, out, sim, beginning.resumed, files, writer)?;
        let watch = Watch::new(loaded.case.diagnostics.clone());
        sim.timings = Default::default();
        let good_counters = start.counters.clone();
        let good_rows = (start.history.len(), start.probe_history.len());
        Ok(ActiveRun {
            loaded,
            out,
            writer,
            checkpoint_path: beginning.checkpoint_path,
            case_source: canonical_source(loaded),
            probe_header,
            midpoint,
            has_free: !free_bodies.is_empty(),
            fluid_body0: beginning.fluid_body0,
            outputs: start.outputs,
            free_csv: start.free_csv,
            fluid_body_max: start.fluid_body_max,
            frames: start.frames,
            wall_before: start.counters.wall_seconds,
            counters: start.counters,
            history: start.history,
            probe_history: start.probe_history,
            resumed_from_step: start.resumed_from_step,
            watch,
            good: SimState::default(),
            good_counters,
            good_rows,
            checkpoints: 0,
            started: Instant::now(),
            last_checkpoint: Instant::now(),
        })
    }

    /// The time loop: outputs when due, checkpoints when due, one step at a time until the
    /// end time, a stop signal or a tripped watch.
    fn advance_to_end(
        &mut self,
        sim: &mut Simulation<V>,
        options: &RunOptions,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Ending, RunError> {
        let case = &self.loaded.case;
        let end = case.time.end;
        // A resumed run wrote the outputs of its first loop point before the checkpoint.
        let mut skip_outputs = self.resumed_from_step.is_some();
        loop {
            let t = sim.time;
            let last = t >= end * (1.0 - 1e-12);
            if !skip_outputs && (t >= self.counters.next_series || last) {
                if let Some(d) = self.write_series(sim)? {
                    return Ok(Ending::Tripped(d));
                }
            }
            if !skip_outputs
                && case.output.vtk_interval > 0.0
                && (t >= self.counters.next_frame || last)
            {
                self.write_frame(sim)?;
            }
            skip_outputs = false;
            progress(Progress {
                time: t,
                end,
                step: sim.step,
                settling: false,
            });
            if last {
                return Ok(Ending::Reached);
            }
            self.mark_good(sim);
            // The parts of a split run stop and checkpoint together, when one of them asks.
            let signalled = options.stop.is_some_and(|s| s.load(Ordering::SeqCst));
            let section = &self.loaded.case.checkpoint;
            let due = checkpoint_due(section, options, sim.step, self.last_checkpoint, signalled);
            let [signalled, due] = sim.on_any_part([signalled, due]);
            if due && Some(sim.step) != self.resumed_from_step {
                self.write_checkpoint(sim)?;
                self.checkpoints += 1;
                self.last_checkpoint = Instant::now();
            }
            if signalled {
                return Ok(Ending::Interrupted);
            }
            if let Err(e) = sim.advance(Some(end)) {
                return Ok(Ending::Tripped(from_sim_error(&e, sim)));
            }
            if let Some(d) = self.watch.check(sim, &self.good, self.counters.dt0) {
                return Ok(Ending::Tripped(d));
            }
            self.record_step(sim)?;
        }
    }

    /// One row of each CSV series at the current time (energy, flux forcing, forces, free
    /// bodies, pistons, probes), then the next series time. Returns the diagnosis instead,
    /// writing nothing, when the energy has grown past its watch.
    fn write_series(&mut self, sim: &Simulation<V>) -> Result<Option<Diagnosis>, RunError> {
        let t = sim.time;
        let e = sim.energy();
        let counters = &mut self.counters;
        if let Some(d) = energy_growth(
            &self.watch.settings,
            sim,
            e.total,
            counters.e0_total,
            counters.scale,
        ) {
            return Ok(Some(d));
        }
        counters.max_drift = counters
            .max_drift
            .max((e.total - counters.e0_total).abs() / counters.scale);
        counters.max_speed = counters.max_speed.max(sim.max_speed());
        let row = [
            t,
            e.kinetic,
            e.compressible,
            e.potential,
            e.wall_work,
            e.total,
            e.viscous_dissipation,
            e.forcing_work,
            e.diffusion_dissipation,
            e.removed,
        ];
        if let Some(csv) = self.outputs.get(ENERGY) {
            csv.row(&row)?;
        }
        self.write_flux_rows(sim)?;
        self.history.push(row);
        self.write_body_rows(sim)?;
        let mut row = vec![t];
        row.extend(sim.sample_probes());
        if let Some(csv) = self.outputs.get(PROBES) {
            csv.row(&row)?;
        }
        self.probe_history.push(row);
        let interval = self.loaded.case.output.series_interval;
        let counters = &mut self.counters;
        counters.next_series = if interval > 0.0 {
            counters.next_series + interval
        } else {
            t
        };
        while interval > 0.0 && counters.next_series <= t {
            counters.next_series += interval;
        }
        Ok(None)
    }

    /// Flux forcing: the row of `flux.csv` and the driving force on the whole fluid,
    /// `F sum_i m_i`, in `forces.csv`.
    fn write_flux_rows(&mut self, sim: &Simulation<V>) -> Result<(), RunError> {
        let Some(flux) = sim.config.flux else {
            return Ok(());
        };
        let t = sim.time;
        let bulk = sim.bulk_velocity();
        let target = flux.target_velocity;
        if let Some(csv) = self.outputs.get(FLUX) {
            csv.row(&[
                t,
                bulk,
                target,
                sim.flux_history.force,
                (bulk - target) / target,
            ])?;
        }
        let total_mass = sim.fluid_mass();
        let force = sim.body_force * total_mass;
        let mut values: Vec<f64> = force.to_xyz()[..V::DIM].to_vec();
        if V::DIM == 3 {
            values.extend([0.0; 3]);
        }
        if let Some(csv) = self.outputs.get(FORCES) {
            csv.named_row(t, "driving", &values)?;
        }
        Ok(())
    }

    /// The bodies' rows: loads in `forces.csv`, each free body's `body_<name>.csv` (and the
    /// fluid + bodies energy drift), each piston's row in `bodies.csv`.
    fn write_body_rows(&mut self, sim: &Simulation<V>) -> Result<(), RunError> {
        let t = sim.time;
        let loads = sim.body_loads();
        for (b, &(force, moment)) in loads.iter().enumerate() {
            let mut values: Vec<f64> = force.to_xyz()[..V::DIM].to_vec();
            if V::DIM == 3 {
                values.extend(V::angular_to_vec(moment));
            }
            if let Some(csv) = self.outputs.get(FORCES) {
                csv.named_row(t, &sim.walls.bodies[b].name, &values)?;
            }
        }
        if self.has_free {
            let mut k = 0;
            for (b, body) in sim.walls.bodies.iter().enumerate() {
                if let Motion::Free(f) = &body.motion {
                    let centre = body.centre + body.motion.kinematics(t).displacement;
                    let row = crate::run::outputs::free_body_row::<V>(
                        t, f, centre, loads[b].0, loads[b].1,
                    );
                    if let Some(csv) = self.free_csv.get_mut(k) {
                        csv.row(&row)?;
                    }
                    k += 1;
                }
            }
            self.fluid_body_max = self
                .fluid_body_max
                .max((fluid_and_body_energy(sim) - self.fluid_body0).abs() / self.counters.scale);
        }
        if let Some(csv) = self.outputs.get(BODIES) {
            for b in &sim.walls.bodies {
                if let Motion::Piston(p) = b.motion {
                    let values = [
                        p.position,
                        p.velocity,
                        p.kinetic_energy(),
                        p.outside_force * p.position,
                    ];
                    csv.named_row(t, &b.name, &values)?;
                }
            }
        }
        Ok(())
    }

    /// A VTK frame of the current state, then the next frame time.
    fn write_frame(&mut self, sim: &Simulation<V>) -> Result<(), RunError> {
        self.frames.write(sim)?;
        while self.counters.next_frame <= sim.time {
            self.counters.next_frame += self.loaded.case.output.vtk_interval;
        }
        Ok(())
    }

    /// The loop point: brings the counters up to date (series lengths, frames, wall seconds)
    /// and keeps the state as the one a checkpoint holds and the watches fall back to.
    fn mark_good(&mut self, sim: &Simulation<V>) {
        let counters = &mut self.counters;
        if counters.dt0 == 0.0 {
            counters.dt0 = sim.next_dt();
        }
        counters.csv_lengths = self.outputs.lengths();
        counters.body_csv_lengths.clear();
        counters
            .body_csv_lengths
            .extend(self.free_csv.iter().map(|s| s.len()));
        counters.fluid_body_max = self.fluid_body_max;
        counters.frame_times.clear();
        counters.frame_times.extend_from_slice(self.frames.times());
        counters.wall_seconds = self.wall_before + self.started.elapsed().as_secs_f64();
        self.good.capture(sim);
        self.good_counters.clone_from(&self.counters);
        self.good_rows = (self.history.len(), self.probe_history.len());
    }

    /// Writes the last good state, which `sim` holds, with the counters and histories as the
    /// checkpoint: the whole state, gathered from every part of a split run (each must call
    /// it), written by the first.
    fn write_checkpoint(&self, sim: &Simulation<V>) -> Result<(), OutputError> {
        let state = match sim.is_part() {
            true => {
                let mut whole = SimState::default();
                whole.capture_whole(sim);
                whole
            }
            false => self.good.clone(),
        };
        if !self.writer {
            return Ok(());
        }
        let c = Checkpoint {
            case_source: self.case_source.clone(),
            case_text: self.loaded.text.clone(),
            sim: state,
            run: self.counters.clone(),
            history: self.history.clone(),
            probe_history: self.probe_history.clone(),
            settling: None,
        };
        checkpoint::write(&self.checkpoint_path, &c)
    }

    /// After a step: the midpoint iteration counters and the row of `midpoint.csv`.
    fn record_step(&mut self, sim: &Simulation<V>) -> Result<(), RunError> {
        let counters = &mut self.counters;
        counters.iterations_sum += sim.last_iterations as u64;
        counters.iterations_max = counters.iterations_max.max(sim.last_iterations);
        counters.residue_max = counters.residue_max.max(sim.last_residue);
        if let Some(p) = self.midpoint {
            // With no tolerance (0) every step runs its maximum iterations: none is a failure.
            if p.tolerance > 0.0 && sim.last_residue >= p.tolerance {
                counters.unconverged += 1;
            }
            if let Some(csv) = self.outputs.get(MIDPOINT) {
                csv.row(&[sim.time, sim.last_iterations as f64, sim.last_residue])?;
            }
        }
        Ok(())
    }

    /// After a tripped watch: back to the last good state, which is checkpointed and written
    /// as a VTK frame, and `diagnostics.json` reporting `d` with where to find them.
    fn fall_back(&mut self, sim: &mut Simulation<V>, d: &mut Diagnosis) -> Result<(), RunError> {
        self.good
            .restore(sim)
            .map_err(|reason| CheckpointError::Mismatch {
                path: self.checkpoint_path.clone(),
                reason,
            })?;
        self.history.truncate(self.good_rows.0);
        self.probe_history.truncate(self.good_rows.1);
        self.counters.clone_from(&self.good_counters);
        self.write_checkpoint(sim)?;
        self.checkpoints += 1;
        self.frames.write(sim)?;
        d.last_good_step = self.good.step;
        d.last_good_time = self.good.time;
        d.checkpoint = Some(checkpoint::FILE_NAME.to_string());
        d.vtk_frame = self.frames.last_fluid_file();
        if self.writer {
            let json = serde_json::to_string_pretty(&*d).unwrap_or_default();
            write_atomic(&self.out.join("diagnostics.json"), json.as_bytes())?;
        }
        Ok(())
    }

    /// Ends the run: falls back on a trip, writes `summary.json`, and then either returns the
    /// stop as an error or writes the plots and removes the now stale checkpoint.
    fn finish(
        mut self,
        sim: &mut Simulation<V>,
        settling: Option<SettlingSummary>,
        mut ending: Ending,
    ) -> Result<Summary, RunError> {
        if let Ending::Tripped(d) = &mut ending {
            self.fall_back(sim, d)?;
        }
        let summary = self.summary(sim, settling, &ending);
        if self.writer {
            let json = serde_json::to_string_pretty(&summary).unwrap_or_default();
            write_atomic(&self.out.join("summary.json"), json.as_bytes())?;
        }
        match ending {
            Ending::Tripped(d) => return Err(RunError::Stopped(Box::new(d))),
            Ending::Interrupted => {
                return Err(RunError::Interrupted {
                    step: sim.step,
                    time: sim.time,
                    checkpoint: self.checkpoint_path,
                })
            }
            Ending::Reached => {}
        }
        if !self.writer {
            return Ok(summary);
        }
        if self.loaded.case.output.plots {
            write_plots(
                self.out,
                &self.history,
                &self.probe_header,
                &self.probe_history,
            )?;
        }
        if self.checkpoint_path.exists() {
            at(
                &self.checkpoint_path,
                std::fs::remove_file(&self.checkpoint_path),
            )?;
        }
        Ok(summary)
    }

    /// `summary.json` of the run as it ended.
    fn summary(
        &self,
        sim: &Simulation<V>,
        settling: Option<SettlingSummary>,
        ending: &Ending,
    ) -> Summary {
        let counters = &self.counters;
        let wall_seconds = self.wall_before + self.started.elapsed().as_secs_f64();
        let e_final = sim.energy();
        Summary {
            case: self.loaded.case.name.clone(),
            dim: V::DIM,
            fluid_particles: sim.fluid_count() + sim.removed as usize,
            removed_particles: sim.removed,
            boundary_elements: sim.walls.elements.len(),
            steps: sim.step,
            time: sim.time,
            wall_seconds,
            particle_steps_per_second: sim.fluid_count() as f64 * sim.step as f64
                / wall_seconds.max(1e-9),
            phase_seconds: PhaseSeconds::new(&sim.timings, self.started.elapsed().as_secs_f64()),
            neighbour_list_builds: sim.timings.list_builds,
            neighbour_lists_kept_past_half_skin: sim.timings.lists_kept_moved,
            energy_drift_relative: (e_final.total - counters.e0_total) / counters.scale,
            energy_scale: counters.scale,
            energy_total_initial: counters.e0_total,
            energy_total_final: e_final.total,
            energy_drift_max_relative: counters.max_drift,
            max_speed_final: sim.max_speed(),
            max_speed_max: counters.max_speed,
            iterations_mean: counters.iterations_sum as f64 / sim.step.max(1) as f64,
            iterations_max: counters.iterations_max,
            residue_max: counters.residue_max,
            unconverged_steps: counters.unconverged,
            threads: rayon::current_num_threads(),
            ranks: sim.parts(),
            frames: self.frames.count(),
            checkpoints: self.checkpoints,
            resumed_from_step: self.resumed_from_step,
            fluid_body_energy_drift_max_relative: self.has_free.then_some(self.fluid_body_max),
            fluid_body_energy_drift_relative: self
                .has_free
                .then(|| (fluid_and_body_energy(sim) - self.fluid_body0) / counters.scale),
            particles_behind_walls: sim.total_over_parts(sim.walls.count_behind(
                &sim.fluid.position[..sim.owned_len()],
                sim.config.kernel.support,
            ) as f64) as usize,
            settling,
            stopped: match ending {
                Ending::Tripped(d) => Some(d.to_string()),
                Ending::Interrupted => Some("interrupted by a signal; resume with --resume".into()),
                Ending::Reached => None,
            },
        }
    }
}

/// Writes `energy.png` from the energy `history` and, when there are probes, `probes.png`.
fn write_plots(
    out: &Path,
    history: &[[f64; checkpoint::ENERGY_COLUMNS]],
    probe_header: &[String],
    probes: &[Vec<f64>],
) -> Result<(), OutputError> {
    let column = |k: usize| history.iter().map(|r| r[k]).collect::<Vec<f64>>();
    let t = column(0);
    let e0 = history.first().map(|r| r[5]).unwrap_or(0.0);
    let all = [
        "kinetic",
        "compressible",
        "potential",
        "wall_work",
        "total",
        "viscous_dissipation",
        "forcing_work",
        "diffusion_dissipation",
        "removed",
    ];
    // Columns 6 to 9 only when they are used; `k + 1` is the column of `all[k]`.
    let shown: Vec<(usize, &str)> = all
        .iter()
        .copied()
        .enumerate()
        .filter(|&(k, _)| k < 5 || history.iter().any(|r| r[k + 1] != 0.0))
        .collect();
    let series = shown
        .iter()
        .map(|&(k, name)| {
            let base = if name == "potential" || name == "total" {
                history.first().map(|r| r[k + 1]).unwrap_or(0.0)
            } else {
                0.0
            };
            let y = column(k + 1).iter().map(|v| v - base).collect();
            (
                PlotSeries {
                    label: if base != 0.0 {
                        format!("{name} - initial")
                    } else {
                        name.to_string()
                    },
                    x: t.clone(),
                    y,
                },
                Style::Line,
            )
        })
        .collect();
    let plot = Plot {
        title: format!("Energy budget (initial total {e0:.4e})"),
        x_label: "t [s]".into(),
        y_label: "energy [J]".into(),
        series,
    };
    let path = out.join("energy.png");
    write_png(&plot, &path, 1000, 600).map_err(|e| OutputError {
        path: path.clone(),
        source: std::io::Error::other(e.0),
    })?;
    if probe_header.len() > 1 {
        let series = (1..probe_header.len())
            .map(|k| {
                let y = probes.iter().map(|r| r[k]).collect();
                let x = probes.iter().map(|r| r[0]).collect();
                (
                    PlotSeries {
                        label: probe_header[k].clone(),
                        x,
                        y,
                    },
                    Style::Line,
                )
            })
            .collect();
        let plot = Plot {
            title: "Probes".into(),
            x_label: "t [s]".into(),
            y_label: "pressure [Pa]".into(),
            series,
        };
        let path = out.join("probes.png");
        write_png(&plot, &path, 1000, 600).map_err(|e| OutputError {
            path: path.clone(),
            source: std::io::Error::other(e.0),
        })?;
    }
    Ok(())
}
