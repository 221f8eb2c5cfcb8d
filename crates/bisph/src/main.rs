//! `bisph`: the command line of the boundary-integral SPH solver.

mod bench;
mod estimates;
mod launch;
mod progress;
mod signals;

use bisph_io::{load_case, resume_case, run_case_split, RunError, RunOptions};
use clap::{Parser, Subcommand};
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::sync::Arc;

#[derive(Parser)]
#[command(name = "bisph", version, about = "Boundary-integral SPH solver")]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case (the built-in 2-D dam break when no case is given).
    Run(RunArgs),
    /// Run a throughput benchmark suite (standard by default).
    Bench(bench::BenchArgs),
    /// Run validation cases and compare them with their references.
    Validate(ValidateArgs),
    /// Print the Shepard factor gamma of a case's walls at given points (`x,y[,z],gamma`).
    Shepard(ShepardArgs),
    /// Pack the case's blocks with BIPI (paper 4); writes particles and pack.csv.
    Pack(PackArgs),
}

#[derive(clap::Args)]
struct ShepardArgs {
    /// Case file (TOML): its walls, and its fluid for `--method discrete`.
    case: PathBuf,
    /// CSV file of points, `x,y` or `x,y,z` per line (optional header).
    #[arg(long)]
    points: PathBuf,
    /// `discrete` (sum over the case's fluid particles), `geometric` (walls only, paper 2)
    /// or `integrated` (2-D: grad gamma of the walls integrated along a path from gamma = 1).
    #[arg(long, default_value = "geometric")]
    method: bisph_core::walls::shepard::ShepardKind,
    /// Override a case key, e.g. --set resolution.dx=0.01 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
}

#[derive(clap::Args)]
struct PackArgs {
    /// Case file (TOML).
    case: PathBuf,
    /// Output directory (default: out/<case name>-pack).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override a case key, e.g. --set pack.stage_c_iterations=500 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Number of threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// No progress output.
    #[arg(long)]
    quiet: bool,
}

#[derive(clap::Args)]
struct ValidateArgs {
    /// Cases to run (default: all).
    names: Vec<String>,
    /// Quick (CI) resolution.
    #[arg(long)]
    quick: bool,
    /// Output directory (default: out/validate).
    #[arg(long)]
    out: Option<PathBuf>,
    /// List the cases with their quick and full run times, and exit.
    #[arg(long)]
    list: bool,
}

#[derive(clap::Args, Default)]
struct RunArgs {
    /// Case file (TOML).
    case: Option<PathBuf>,
    /// Output directory (default: out/<case name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override a case key, e.g. --set resolution.dx=0.01 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Number of threads (default: all cores; under a parallel launch, each process takes
    /// its share of the cores it may run on).
    #[arg(long)]
    threads: Option<usize>,
    /// No progress output.
    #[arg(long)]
    quiet: bool,
    /// Seconds of wall time between two plain progress lines when stderr is not a terminal
    /// (a log file, a batch job); on a terminal a bar is drawn instead.
    #[arg(long, value_name = "SECONDS", default_value_t = progress::DEFAULT_INTERVAL)]
    progress_interval: f64,
    /// Continue the run whose output directory is DIR from its checkpoint (no case argument).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["case", "out", "overrides"])]
    resume: Option<PathBuf>,
    /// Write a checkpoint every N steps (overrides checkpoint.every_steps).
    #[arg(long, value_name = "N")]
    checkpoint_steps: Option<u64>,
    /// Write a checkpoint every M wall-clock minutes (overrides checkpoint.every_minutes).
    #[arg(long, value_name = "M")]
    checkpoint_minutes: Option<f64>,
}

/// Exit code of `bisph validate` when a check is out of tolerance or a case fails to run
/// (2 is a command-line usage error, as clap reports it).
const EXIT_VALIDATION_FAILED: u8 = 3;
/// Exit code of `bisph run --resume` when there is no checkpoint to continue from.
const EXIT_CHECKPOINT_REFUSED: u8 = 5;
/// Exit code of a run interrupted by SIGINT or SIGTERM (a checkpoint was written).
const EXIT_INTERRUPTED: u8 = 10;

/// Exit codes: 0 success, 1 bad input, 2 command-line usage error, 3 validation out of
/// tolerance, 4 I/O error, 5 checkpoint refused, 6 not enough memory, 10 interrupted
/// (checkpoint written), 20-26 a divergence watch tripped, 130/143 a second stop signal
/// ([`signals`]; docs/outputs-and-errors.md).
fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = unsplit_in_one_process(&cli.command).and_then(|()| match cli.command {
        None => run(RunArgs {
            progress_interval: progress::DEFAULT_INTERVAL,
            ..RunArgs::default()
        }),
        Some(Command::Run(args)) => run(args),
        Some(Command::Bench(args)) => bench::bench(args),
        Some(Command::Validate(args)) => validate(args),
        Some(Command::Shepard(args)) => shepard(args),
        Some(Command::Pack(args)) => pack(args),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A rank of a split run other than the first: the first reports.
        Err((code, message)) if message.is_empty() => ExitCode::from(code),
        // An interrupt is what the user asked for, not an error: its line says where the
        // checkpoint is and how to continue.
        Err((EXIT_INTERRUPTED, message)) => {
            eprintln!("{message}");
            ExitCode::from(EXIT_INTERRUPTED)
        }
        Err((code, message)) => {
            eprintln!("error: {message}");
            ExitCode::from(code)
        }
    }
}

/// Refuses a start as one of several processes of a parallel launch, unless the command
/// splits its case over them: a run, or one bench configuration.
fn unsplit_in_one_process(command: &Option<Command>) -> Result<(), (u8, String)> {
    match command {
        None | Some(Command::Run(_)) => Ok(()),
        Some(Command::Bench(args)) if args.is_single() => Ok(()),
        Some(_) => launch::one_process(),
    }
}

/// Sets the size of rayon's global pool.
pub(crate) fn set_threads(threads: Option<usize>) -> Result<(), (u8, String)> {
    if let Some(n) = threads {
        if n == 0 {
            return Err((1, "--threads: expected a positive number".into()));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| (1, format!("--threads: {e}")))?;
    }
    Ok(())
}

fn run(args: RunArgs) -> Result<(), (u8, String)> {
    set_threads(args.threads.or_else(launch::threads_per_rank))?;
    let (loaded, out) = match &args.resume {
        Some(dir) => {
            nothing_to_resume(dir)?;
            (
                resume_case(dir).map_err(|e| (e.exit_code(), e.to_string()))?,
                dir.clone(),
            )
        }
        None => {
            let loaded =
                load_case(args.case.as_deref(), &args.overrides).map_err(|e| (1, e.to_string()))?;
            let out = args
                .out
                .clone()
                .unwrap_or_else(|| bisph_io::case::default_out_dir(&loaded.case));
            (loaded, out)
        }
    };
    if !(args.progress_interval >= 0.0 && args.progress_interval.is_finite()) {
        return Err((
            1,
            format!(
                "--progress-interval: expected zero or a positive number of seconds, found {}",
                args.progress_interval
            ),
        ));
    }
    if let Some(m) = args.checkpoint_minutes {
        if !(m >= 0.0 && m.is_finite()) {
            return Err((
                1,
                format!("--checkpoint-minutes: expected zero or a positive number, found {m}"),
            ));
        }
    }
    let stop = signals::stop_on_signal().map_err(|e| (1, e))?;
    let options = RunOptions {
        checkpoint_steps: args.checkpoint_steps,
        checkpoint_minutes: args.checkpoint_minutes,
        stop: Some(&stop),
        resume: args.resume.is_some(),
    };
    // Split over the ranks of a parallel launch: the first one reports.
    let transport = launch::rank_transport()?;
    let first = transport.as_ref().is_none_or(|t| t.rank() == 0);
    let mut shown = progress::RunProgress::new(args.quiet || !first, args.progress_interval);
    let result = run_case_split(&loaded, &out, &options, transport, &mut |p| shown.report(p));
    shown.finish();
    match result {
        // Every rank meets the same end but for a file only it could not write.
        Ok(_) if !first => Ok(()),
        Err(e) if !first && !matches!(e, RunError::Output(_)) => {
            Err((e.exit_code(), String::new()))
        }
        Ok(s) => {
            println!(
                "{}: {} fluid particles, {} boundary elements, {} steps in {:.1} s ({:.3e} particle-steps/s), energy drift {:.3e}; outputs in {}",
                s.case,
                s.fluid_particles,
                s.boundary_elements,
                s.steps,
                s.wall_seconds,
                s.particle_steps_per_second,
                s.energy_drift_relative,
                out.display()
            );
            if s.removed_particles > 0 {
                println!(
                    "{} fluid particles ({:.2}%) left the water's region (the domain, or over the rim of a wall) and were removed; their energy is the `removed` column of energy.csv",
                    s.removed_particles,
                    100.0 * s.removed_particles as f64 / s.fluid_particles.max(1) as f64
                );
            }
            if let Some(settling) = &s.settling {
                println!(
                    "settling before t = 0: {} after {:.3} s ({} steps, {:.1} s wall), residual speed {:.2e} sqrt(g H)",
                    settling.outcome,
                    settling.time,
                    settling.steps,
                    settling.wall_seconds,
                    settling.max_speed_relative
                );
            }
            Ok(())
        }
        Err(e @ RunError::Stopped(_)) => Err((
            e.exit_code(),
            format!(
                "{e}; outputs up to the last good state kept in {}, see diagnostics.json",
                out.display()
            ),
        )),
        Err(
            e @ (RunError::Interrupted { .. }
            | RunError::SettlingInterrupted {
                checkpoint: Some(_),
                ..
            }),
        ) => Err((
            e.exit_code(),
            format!("{e}; continue with: bisph run --resume {}", out.display()),
        )),
        Err(e) => Err((e.exit_code(), e.to_string())),
    }
}

/// Refuses `--resume DIR` with a message naming the folder when there is nothing to continue:
/// no such folder, or a run that finished (it removes its checkpoint at the end). A folder
/// with neither a checkpoint nor a finished run is left to the checkpoint reader's message.
fn nothing_to_resume(dir: &std::path::Path) -> Result<(), (u8, String)> {
    let refused = EXIT_CHECKPOINT_REFUSED;
    if !dir.is_dir() {
        return Err((
            refused,
            format!(
                "cannot resume {}: no such folder (give the output folder of an interrupted or stopped run)",
                dir.display()
            ),
        ));
    }
    let checkpoint = dir.join(bisph_io::run::checkpoint::FILE_NAME);
    if checkpoint.exists() {
        return Ok(());
    }
    let finished = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|text| serde_json::from_str::<serde_json::Value>(&text).ok())
        .is_some_and(|summary| summary.get("stopped").is_none());
    if finished {
        return Err((
            refused,
            format!(
                "nothing to resume in {}: the run there reached its end (see its summary.json) and removed its checkpoint; to run it again: bisph run {} --out NEW_FOLDER",
                dir.display(),
                dir.join("case.toml").display()
            ),
        ));
    }
    Ok(())
}

fn shepard(args: ShepardArgs) -> Result<(), (u8, String)> {
    let loaded = load_case(Some(&args.case), &args.overrides).map_err(|e| (1, e.to_string()))?;
    let table = bisph_io::run::shepard::shepard_table(&loaded, &args.points, args.method)
        .map_err(|e| (1, e))?;
    print!("{table}");
    Ok(())
}

fn pack(args: PackArgs) -> Result<(), (u8, String)> {
    set_threads(args.threads)?;
    let loaded = load_case(Some(&args.case), &args.overrides).map_err(|e| (1, e.to_string()))?;
    let out = args
        .out
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{}-pack", loaded.case.name)));
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new_spinner()
    };
    let mut report = |block: usize, s: &bisph_core::packing::IterationStats| {
        if s.iteration.is_multiple_of(50) {
            bar.set_message(format!(
                "block {block}: iteration {} ({:?}), mean |grad C| {:.4e}, TPD {:.4e}",
                s.iteration, s.stage, s.gradc_mean_all, s.tpd
            ));
            bar.tick();
        }
    };
    let result = bisph_io::run::pack::pack_case(&loaded, &out, &mut report);
    bar.finish_and_clear();
    let summary = result.map_err(|e| (1, e.to_string()))?;
    for b in &summary.blocks {
        println!(
            "{} block {}: {} particles, {} + {} iterations in {:.2} s ({:.3e} s/iteration); mean |grad C| {:.4e} -> {:.4e} (all), {:.4e} -> {:.4e} (gamma = 1); first layer at {:.3} dx (std {:.3}, {} particles); {} outside",
            summary.case,
            b.block,
            b.particles,
            b.stage_a_iterations,
            b.stage_c_iterations,
            b.seconds,
            b.seconds_per_iteration,
            b.gradc_mean_all[0],
            b.gradc_mean_all[1],
            b.gradc_mean[0],
            b.gradc_mean[1],
            b.first_layer.mean,
            b.first_layer.std,
            b.first_layer.count,
            b.outside
        );
    }
    println!("outputs in {}", out.display());
    Ok(())
}

/// Writes `text` to stdout; a reader that closed the pipe early (`| head`) is not an error.
fn print_all(text: &str) -> Result<(), (u8, String)> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err((4, format!("cannot write to stdout: {e}")))
        }
        _ => Ok(()),
    }
}

fn validate(args: ValidateArgs) -> Result<(), (u8, String)> {
    use bisph_validate::{markdown, registry, table, CaseReport};
    use rayon::prelude::*;
    let cases = registry();
    if args.list {
        use std::fmt::Write as _;
        let mut text = format!(
            "{:<24} {:>7} {:>7}  what it checks\n",
            "case", "quick", "full"
        );
        for c in &cases {
            let (quick, full) = match estimates::estimate(c.name()) {
                Some(e) => (e.quick.to_string(), e.full.to_string()),
                None => ("?".into(), "?".into()),
            };
            let _ = writeln!(
                text,
                "{:<24} {quick:>7} {full:>7}  {}",
                c.name(),
                c.description()
            );
        }
        text.push_str(
            "\nrun times on 2 threads of a 2-vCPU machine; ~: scaled from the quick run by the cost of the full resolution, not measured\n",
        );
        return print_all(&text);
    }
    for name in &args.names {
        if !cases.iter().any(|c| c.name() == name) {
            let known: Vec<&str> = cases.iter().map(|c| c.name()).collect();
            return Err((
                1,
                format!(
                    "unknown validation case `{name}`; known: {}",
                    known.join(", ")
                ),
            ));
        }
    }
    let selected: Vec<&dyn bisph_validate::ValidationCase> = cases
        .iter()
        .filter(|c| {
            if args.names.is_empty() && args.quick && !c.in_quick_suite() {
                eprintln!(
                    "skipping {} in --quick (full only; `bisph validate --quick {}` runs its reduced variant)",
                    c.name(),
                    c.name()
                );
                return false;
            }
            args.names.is_empty() || args.names.iter().any(|n| n == c.name())
        })
        .map(|c| c.as_ref())
        .collect();
    check_validation_data(&selected)?;
    let out = args.out.unwrap_or_else(|| PathBuf::from("out/validate"));
    std::fs::create_dir_all(&out)
        .map_err(|e| (1, format!("cannot create {}: {e}", out.display())))?;
    let stop = signals::stop_on_signal().map_err(|e| (1, e))?;
    bisph_validate::support::stop_runs_when(Arc::clone(&stop));
    // The cases run side by side: most are small, and share the cores better case by case
    // than step by step. Each case's figures do not depend on the thread count; the reports
    // keep the registry's order.
    let runs: Vec<(Result<CaseReport, String>, f64)> = selected
        .par_iter()
        .map(|case| {
            if stop.load(Ordering::SeqCst) {
                return (Err("not started: asked to stop".into()), 0.0);
            }
            eprintln!(
                "validating {} ({})",
                case.name(),
                if args.quick { "quick" } else { "full" }
            );
            let started = std::time::Instant::now();
            let run = case.run(args.quick, &out.join(case.name()));
            (run, started.elapsed().as_secs_f64())
        })
        .collect();
    if stop.load(Ordering::SeqCst) {
        return Err((EXIT_INTERRUPTED, interrupted_validation(&selected, &out)));
    }
    let mut reports = Vec::new();
    let mut failed = Vec::new();
    for (case, (run, seconds)) in selected.iter().zip(runs) {
        match run {
            Ok(mut report) => {
                report.wall_seconds = seconds;
                if report.checks.iter().any(|c| c.fails()) {
                    failed.push(case.name().to_string());
                }
                reports.push(report);
            }
            Err(e) => {
                eprintln!("error: validation case {} failed to run: {e}", case.name());
                failed.push(case.name().to_string());
            }
        }
    }
    print!("{}", table(&reports));
    // Plot links relative to report.md, so that the report folder reads the same wherever it
    // is moved or published.
    for r in &mut reports {
        let case_dir = out.join(&r.name);
        for p in &mut r.plots {
            *p = report_link(p, &out, &case_dir, &r.name);
        }
    }
    let report_path = out.join("report.md");
    std::fs::write(&report_path, markdown(&reports, args.quick))
        .map_err(|e| (1, format!("cannot write {}: {e}", report_path.display())))?;
    println!("report: {}", report_path.display());
    if failed.is_empty() {
        Ok(())
    } else {
        Err((
            EXIT_VALIDATION_FAILED,
            format!("out of tolerance or failed: {}", failed.join(", ")),
        ))
    }
}

/// What an interrupted `bisph validate` says: which cases continue from a checkpoint when
/// the same command runs again (the others run again from the start).
fn interrupted_validation(cases: &[&dyn bisph_validate::ValidationCase], out: &Path) -> String {
    let resumable: Vec<&str> = cases
        .iter()
        .map(|c| c.name())
        .filter(|name| bisph_validate::support::holds_resumable_run(&out.join(name)))
        .collect();
    let mut text = String::from("interrupted: no report written");
    if !resumable.is_empty() {
        text.push_str(&format!(
            "; {} saved a checkpoint under {} and continues from it when the same command runs again",
            resumable.join(", "),
            out.display()
        ));
    }
    text
}

/// Reads the experiment data of every selected case before any of them runs: exit code 1
/// naming each case whose data are missing or unreadable.
fn check_validation_data(
    cases: &[&dyn bisph_validate::ValidationCase],
) -> Result<(), (u8, String)> {
    let problems: Vec<String> = cases
        .iter()
        .filter_map(|c| {
            c.check_data()
                .err()
                .map(|e| format!("validation case {}: {e}", c.name()))
        })
        .collect();
    if problems.is_empty() {
        Ok(())
    } else {
        Err((1, problems.join("\n")))
    }
}

/// A plot path as `report.md` in `out` links it: relative to `out` when it lies there, else
/// (a bare name written by a case) inside the case's folder when the file is there.
fn report_link(
    plot: &std::path::Path,
    out: &std::path::Path,
    case_dir: &std::path::Path,
    case: &str,
) -> PathBuf {
    if let Ok(inside) = plot.strip_prefix(out) {
        return inside.to_path_buf();
    }
    if plot.is_relative() && case_dir.join(plot).is_file() {
        return std::path::Path::new(case).join(plot);
    }
    plot.to_path_buf()
}
