//! Runs a case to its end time, writing the outputs of the command-line contract.

use crate::build::{build_simulation, CaseDim};
use crate::case::{CaseError, LoadedCase};
use crate::output::{at, write_atomic, Frames, OutputError, Series};
use crate::plot::{write_png, Plot, Series as PlotSeries, Style};
use bisph_core::energy::energy_scale;
use bisph_core::walls::Motion;
use bisph_core::{SimError, Simulation};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// Why a run failed.
#[derive(Debug)]
pub enum RunError {
    /// The case is wrong.
    Case(CaseError),
    /// An output could not be written.
    Output(OutputError),
    /// The simulation stopped early (outputs up to then are kept; `summary.json` says why).
    Stopped(SimError),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Case(e) => write!(f, "{e}"),
            RunError::Output(e) => write!(f, "{e}"),
            RunError::Stopped(e) => write!(f, "simulation stopped: {e}"),
        }
    }
}

impl std::error::Error for RunError {}

impl From<OutputError> for RunError {
    fn from(e: OutputError) -> Self {
        RunError::Output(e)
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Case name.
    pub case: String,
    /// Dimension.
    pub dim: usize,
    /// Fluid particles.
    pub fluid_particles: usize,
    /// Boundary elements.
    pub boundary_elements: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time reached [s].
    pub time: f64,
    /// Wall-clock seconds of the time loop (outputs included).
    pub wall_seconds: f64,
    /// Fluid particles times steps over wall seconds.
    pub particle_steps_per_second: f64,
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
    /// Threads used.
    pub threads: usize,
    /// VTK frames written.
    pub frames: usize,
    /// Why the run stopped early (absent when it reached its end).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
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
}

/// Runs the case in its dimension; see [`run`].
pub fn run_case(
    loaded: &LoadedCase,
    out: &Path,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    if loaded.case.dim == 2 {
        run::<glam::DVec2>(loaded, out, progress)
    } else {
        run::<glam::DVec3>(loaded, out, progress)
    }
}

/// Builds and runs a case, writing `energy.csv`, `forces.csv`, `probes.csv`, VTK frames,
/// `summary.json`, plots and a copy of the case into `out`.
pub fn run<V: CaseDim>(
    loaded: &LoadedCase,
    out: &Path,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, RunError> {
    let mut sim: Simulation<V> = build_simulation(loaded).map_err(RunError::Case)?;
    at(out, std::fs::create_dir_all(out))?;
    write_atomic(&out.join("case.toml"), loaded.text.as_bytes())?;
    let case = &loaded.case;
    let end = case.time.end;

    let mut energy_csv = Series::create(
        out.join("energy.csv"),
        &[
            "t",
            "kinetic",
            "compressible",
            "potential",
            "wall_work",
            "total",
            "viscous_dissipation",
            "forcing_work",
        ]
        .map(String::from),
    )?;
    let mut flux_csv = match sim.config.flux {
        Some(_) => Some(Series::create(
            out.join("flux.csv"),
            &[
                "t",
                "bulk_velocity",
                "target_velocity",
                "force",
                "relative_error",
            ]
            .map(String::from),
        )?),
        None => None,
    };
    let mut force_header = vec![
        "t".to_string(),
        "body".to_string(),
        "fx".into(),
        "fy".into(),
    ];
    if V::DIM == 3 {
        force_header.extend(["fz", "mx", "my", "mz"].map(String::from));
    }
    let mut forces_csv = Series::create(out.join("forces.csv"), &force_header)?;
    let mut probe_header = vec!["t".to_string()];
    probe_header.extend(sim.probes.iter().map(|p| p.name.clone()));
    let mut probes_csv = Series::create(out.join("probes.csv"), &probe_header)?;
    let mut frames = Frames::new(out)?;
    let has_pistons = sim
        .walls
        .bodies
        .iter()
        .any(|b| matches!(b.motion, Motion::Piston(_)));
    let mut bodies_csv = match has_pistons {
        true => Some(Series::create(
            out.join("bodies.csv"),
            &[
                "t",
                "body",
                "position",
                "velocity",
                "kinetic",
                "outside_work",
            ]
            .map(String::from),
        )?),
        false => None,
    };
    let midpoint = match sim.config.integrator {
        bisph_core::simulation::Integrator::Midpoint(p) => Some(p),
        bisph_core::simulation::Integrator::Verlet => None,
    };
    let mut iterations_csv = match midpoint {
        Some(_) => Some(Series::create(
            out.join("midpoint.csv"),
            &["t", "iterations", "residue"].map(String::from),
        )?),
        None => None,
    };
    let (mut iterations_sum, mut iterations_max, mut residue_max, mut unconverged) =
        (0u64, 0u32, 0.0f64, 0u64);

    let scale = energy_scale(&sim.fluid, &sim.config.eos, sim.config.gravity);
    let e0 = sim.energy();
    let mut history: Vec<[f64; 8]> = Vec::new();
    let mut probe_history: Vec<Vec<f64>> = Vec::new();
    let mut max_drift: f64 = 0.0;
    let mut max_speed: f64 = 0.0;
    let started = Instant::now();
    let mut next_series = 0.0;
    let mut next_frame = 0.0;
    let mut stopped = None;
    loop {
        let t = sim.time;
        let last = t >= end * (1.0 - 1e-12);
        if t >= next_series || last {
            let e = sim.energy();
            max_drift = max_drift.max((e.total - e0.total).abs() / scale);
            max_speed = max_speed.max(sim.max_speed());
            let row = [
                t,
                e.kinetic,
                e.compressible,
                e.potential,
                e.wall_work,
                e.total,
                e.viscous_dissipation,
                e.forcing_work,
            ];
            energy_csv.row(&row)?;
            if let (Some(csv), Some(flux)) = (flux_csv.as_mut(), sim.config.flux) {
                let bulk = sim.bulk_velocity();
                let target = flux.target_velocity;
                csv.row(&[
                    t,
                    bulk,
                    target,
                    sim.flux_history.force,
                    (bulk - target) / target,
                ])?;
                // The driving force on the whole fluid, `F sum_i m_i`.
                let total_mass: f64 = sim.fluid.mass.iter().sum();
                let force = sim.body_force * total_mass;
                let mut values: Vec<f64> = force.to_xyz()[..V::DIM].to_vec();
                if V::DIM == 3 {
                    values.extend([0.0; 3]);
                }
                forces_csv.named_row(t, "driving", &values)?;
            }
            history.push(row);
            for (b, (force, moment)) in sim.walls.body_loads(t).into_iter().enumerate() {
                let mut values: Vec<f64> = force.to_xyz()[..V::DIM].to_vec();
                if V::DIM == 3 {
                    values.extend(V::angular_to_vec(moment));
                }
                forces_csv.named_row(t, &sim.walls.bodies[b].name, &values)?;
            }
            if let Some(csv) = bodies_csv.as_mut() {
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
            let mut row = vec![t];
            row.extend(sim.sample_probes());
            probes_csv.row(&row)?;
            probe_history.push(row);
            next_series = if case.output.series_interval > 0.0 {
                next_series + case.output.series_interval
            } else {
                t
            };
            while case.output.series_interval > 0.0 && next_series <= t {
                next_series += case.output.series_interval;
            }
        }
        if case.output.vtk_interval > 0.0 && (t >= next_frame || last) {
            frames.write(&sim)?;
            while next_frame <= t {
                next_frame += case.output.vtk_interval;
            }
        }
        progress(Progress {
            time: t,
            end,
            step: sim.step,
        });
        if last {
            break;
        }
        if let Err(e) = sim.advance(Some(end)) {
            stopped = Some(e);
            break;
        }
        iterations_sum += sim.last_iterations as u64;
        iterations_max = iterations_max.max(sim.last_iterations);
        residue_max = residue_max.max(sim.last_residue);
        if let (Some(csv), Some(p)) = (iterations_csv.as_mut(), midpoint) {
            csv.row(&[sim.time, sim.last_iterations as f64, sim.last_residue])?;
            if sim.last_residue >= p.tolerance {
                unconverged += 1;
            }
        }
    }
    let wall_seconds = started.elapsed().as_secs_f64();
    if stopped.is_some() && case.output.vtk_interval > 0.0 {
        // Keep what was written and add the last state for inspection.
        frames.write(&sim)?;
    }
    let e_final = sim.energy();
    let summary = Summary {
        case: case.name.clone(),
        dim: V::DIM,
        fluid_particles: sim.fluid.len(),
        boundary_elements: sim.walls.elements.len(),
        steps: sim.step,
        time: sim.time,
        wall_seconds,
        particle_steps_per_second: sim.fluid.len() as f64 * sim.step as f64
            / wall_seconds.max(1e-9),
        energy_drift_relative: (e_final.total - e0.total) / scale,
        energy_scale: scale,
        energy_total_initial: e0.total,
        energy_total_final: e_final.total,
        energy_drift_max_relative: max_drift,
        max_speed_final: sim.max_speed(),
        max_speed_max: max_speed,
        iterations_mean: iterations_sum as f64 / sim.step.max(1) as f64,
        iterations_max,
        residue_max,
        unconverged_steps: unconverged,
        threads: rayon::current_num_threads(),
        frames: frames.count(),
        stopped: stopped.as_ref().map(|e| e.to_string()),
    };
    let json = serde_json::to_string_pretty(&summary).unwrap_or_default();
    write_atomic(&out.join("summary.json"), json.as_bytes())?;
    if case.output.plots {
        write_plots(out, &history, &probe_header, &probe_history)?;
    }
    match stopped {
        Some(e) => Err(RunError::Stopped(e)),
        None => Ok(summary),
    }
}

fn write_plots(
    out: &Path,
    history: &[[f64; 8]],
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
    ];
    // Columns 6 and 7 only when they are used; `k + 1` is the column of `all[k]`.
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
