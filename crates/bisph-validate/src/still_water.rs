//! `still-water`: a tank of water at rest must stay at rest, for every wall model.
//!
//! Four shipped tanks: `cases/hydrostatic-2d.toml` (a 1 m wide box, water H = 0.5 m deep),
//! `cases/still-water-slope-2d.toml` (a step and a 30 degree side, walls that cut the lattice,
//! H = 0.5 m), `cases/still-water-box-3d.toml` (a 0.5 m x 0.5 m box, H = 0.5 m) and
//! `cases/still-water-spheric-3d.toml` (the SPHERIC test 2 tank and obstacle, H = 0.55 m
//! everywhere). Each runs with each wall model chosen by `boundary` (and `shepard`) alone,
//! everything else as the case file has it,
//! settling included. The bars: the largest particle speed over the whole run below 1% of
//! `sqrt(g H)`; the kinetic energy not growing (its mean over the last quarter of the run not
//! above its mean over the second quarter); the wall model's own pressure on the bottom at
//! mid-width (the pressure it applies to the wall) within 1% of `rho g H` (time mean over the
//! second half); no particle behind a wall. `H` is the water depth; in the SPHERIC tank, which the
//! lattice does not tile, it is the depth of the water the particles hold. At quick resolution
//! the SPHERIC tank settles for at most 15 s (its default, `200 / beta`, is 46 s for a tank
//! 3.22 m long). The runs save their state as they go (see [`STATE_FILE`]), so that the full
//! validation, hours long, continues where a stopped invocation left it.

use crate::check::{CaseReport, Check, Tolerance, ValidationCase};
use crate::support::{build_fingerprint, stop_flag, stopping, written_by, BUILD_FILE};
use bisph_core::{Simulation, Vector};
use bisph_io::case::{build_simulation, parse_case, CaseDim};
use bisph_io::formats::plot::line_plot_png as plot;
use bisph_io::run::checkpoint::{self, Checkpoint};
use bisph_io::run::{settle_resumable, RunOptions};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::{Duration, Instant};

/// Gravity [m/s^2] and density [kg/m^3] of every tank.
const G: f64 = 9.81;
const RHO: f64 = 1000.0;

/// A wall model as the user selects it.
struct Model {
    name: &'static str,
    overrides: &'static [&'static str],
}

const ENERGY: Model = Model {
    name: "energy",
    overrides: &["boundary=\"energy\""],
};
const BI: Model = Model {
    name: "bi + geometric",
    overrides: &["boundary=\"bi\"", "shepard=\"geometric\""],
};
const USAW: Model = Model {
    name: "usaw",
    overrides: &["boundary=\"usaw\""],
};

const ENERGY_WALL_PRESSURE: &str = "the energy-conserving walls are zeroth-order consistent (paper 1): next to the side walls they give the water only the part gamma of its vertical support (docs/design.md), and the interior carries the rest: settled at H/20, the pressure at mid-depth and mid-width reads 1.016 rho g H/2, and the floor's element pressure (eq 71) 0.73 rho g H in the corners and 1.020 at mid-width, while the floor as a whole carries the water's weight exactly (mean 1.005 rho0 g H: the water held is 0.5% denser than rho0)";
const ENERGY_LIMITATION: &str = "the energy-conserving walls are zeroth-order consistent (paper 1): within a kernel support of a wall that is not horizontal the model has no static rest state (the fluid sum gives only the part gamma of the vertical pressure gradient, docs/design.md), so a slow flow stays along the sloped and side walls, and the floor's load gathers away from them (eq 71 reads high mid-floor, low in the corners)";

const SPHERIC_BOTTOM: &str = "not met at quick resolution: at dx = 0.55/5 the water is five particles deep and the bottom element's kernel support reaches 80% of the depth; the classic BI wall pressure there reads 3.6% above the weight of the water held (0.7% above rho g times the 0.55 m level, which the lattice does not fill), against 0.3% in the box tanks at H/10 and H/20";

/// One tank and the models it is run with, with the bars each model is known not to meet yet
/// (by check key: `end`, `speed`, `growth`, `bottom`, `behind`) and why.
struct Tank {
    name: &'static str,
    text: &'static str,
    dim: usize,
    /// Water depth `H` [m].
    depth: f64,
    /// `(dx, end)` at quick and at full resolution.
    quick: (f64, f64),
    full: (f64, f64),
    /// Most settling time [s] at quick resolution (`None`: the default, `200 / beta`).
    quick_settling: Option<f64>,
    /// Where the bottom pressure is read (the nearest element facing down).
    bottom: [f64; 3],
    /// For a tank that the lattice does not tile: its floor area and the volume of the
    /// obstacles below the level. `H` is then the depth of the water the particles hold,
    /// `(sum m/rho + displaced) / area`, rather than `depth`.
    floor: Option<Floor>,
    models: &'static [(Model, &'static [&'static str], &'static str)],
}

const TANKS: [Tank; 4] = [
    Tank {
        name: "box 2-D",
        text: include_str!("../../../cases/hydrostatic-2d.toml"),
        dim: 2,
        depth: 0.5,
        quick: (0.025, 5.0),
        full: (0.0125, 20.0),
        quick_settling: None,
        bottom: [0.5, 0.0, 0.0],
        floor: None,
        models: &[
            (ENERGY, &["bottom"], ENERGY_WALL_PRESSURE),
            (BI, &[], ""),
            (USAW, &[], ""),
        ],
    },
    Tank {
        name: "slope 2-D",
        text: include_str!("../../../cases/still-water-slope-2d.toml"),
        dim: 2,
        depth: 0.5,
        quick: (0.025, 5.0),
        full: (0.0125, 20.0),
        quick_settling: None,
        bottom: [0.15, 0.0, 0.0],
        floor: None,
        models: &[
            (ENERGY, &["bottom"], ENERGY_LIMITATION),
            (BI, &[], ""),
            (USAW, &[], ""),
        ],
    },
    Tank {
        name: "box 3-D",
        text: include_str!("../../../cases/still-water-box-3d.toml"),
        dim: 3,
        depth: 0.5,
        quick: (0.05, 5.0),
        full: (0.025, 10.0),
        quick_settling: None,
        bottom: [0.25, 0.25, 0.0],
        floor: None,
        models: &[
            (ENERGY, &["speed", "growth", "bottom"], ENERGY_LIMITATION),
            (BI, &[], ""),
        ],
    },
    Tank {
        name: "SPHERIC obstacle 3-D",
        text: include_str!("../../../cases/still-water-spheric-3d.toml"),
        dim: 3,
        depth: 0.55,
        quick: (0.55 / 5.0, 2.0),
        full: (0.55 / 10.0, 10.0),
        quick_settling: Some(15.0),
        bottom: [2.0, 0.5, 0.0],
        // The lattice at dx = 0.55/5 leaves 0.03 m of the tank's 3.22 m length and 0.01 m of
        // its 1 m width unfilled, and cuts 0.22 m x 0.55 m x 0.22 m out around the
        // 0.161 m x 0.403 m x 0.161 m obstacle: it holds 0.534 m of water, not 0.55 m.
        floor: Some(Floor {
            area: 3.22,
            displaced: (0.8245 - 0.6635) * (0.6985 - 0.2955) * 0.161,
        }),
        models: &[(BI, &["bottom"], SPHERIC_BOTTOM)],
    },
];

/// A tank's floor area [m^2] and the volume [m^3] its obstacles take below the level.
struct Floor {
    area: f64,
    displaced: f64,
}

/// What one run measured.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct StillWaterRun {
    /// Sample times [s].
    t: Vec<f64>,
    /// Kinetic energy over `M g H` at the samples.
    kinetic: Vec<f64>,
    /// Largest particle speed over `sqrt(g H)`, over every step.
    max_speed: f64,
    /// The wall model's own pressure on the bottom element over `rho g H`.
    bottom: Vec<f64>,
    /// Particles behind a wall at the end.
    behind: usize,
    /// Why the run stopped early.
    stopped: Option<String>,
    /// The water depth `H` the figures are scaled by [m].
    depth: f64,
    /// What settling did.
    settling: String,
}

/// Samples of a run (the kinetic energy and the bottom pressure).
const SAMPLES: usize = 100;

/// How often a run under way saves its state, and (for tests) the sample after which it stops
/// as if killed.
struct Pace {
    save_every: Duration,
    stop_after: Option<usize>,
}

/// Saves every 10 minutes of wall clock, as `bisph run` checkpoints by default.
const PACE: Pace = Pace {
    save_every: Duration::from_secs(600),
    stop_after: None,
};

/// The files of a run under way in its folder: a checkpoint of the simulation (while settling
/// or at the last sample saved), the measurements up to that sample, the build that wrote them
/// and, once the run has ended, its result. A run starts afresh where the build differs.
const STATE_FILE: &str = "checkpoint.bin";
const SERIES_FILE: &str = "series.json";
const RESULT_FILE: &str = "result.json";

/// What a run's folder holds of an earlier invocation by this build.
enum Saved<V: Vector> {
    Nothing,
    Finished(StillWaterRun),
    Settling(Checkpoint<V>),
    Running(Checkpoint<V>, StillWaterRun),
}

/// Reads what `dir` holds of an earlier invocation of build `build`; anything else in it
/// (another build's files, a state whose measurements do not reach it) is cleared.
fn saved<V: CaseDim>(dir: &Path, build: &str) -> Result<Saved<V>, String> {
    let same_build = written_by(dir, build);
    let json = |name: &str| -> Option<StillWaterRun> {
        let text = std::fs::read_to_string(dir.join(name)).ok()?;
        serde_json::from_str(&text).ok()
    };
    if same_build {
        if let Some(run) = json(RESULT_FILE) {
            return Ok(Saved::Finished(run));
        }
        if let Ok(c) = checkpoint::read::<V>(&dir.join(STATE_FILE)) {
            if c.settling.is_some() {
                return Ok(Saved::Settling(c));
            }
            if let Some(run) = json(SERIES_FILE).filter(|r| r.t.last() == Some(&c.sim.time)) {
                return Ok(Saved::Running(c, run));
            }
        }
    }
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(|e| format!("cannot clear {}: {e}", dir.display()))?;
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    write(&dir.join(BUILD_FILE), build.as_bytes())?;
    Ok(Saved::Nothing)
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    bisph_io::formats::files::write_atomic(path, bytes).map_err(|e| e.to_string())
}

fn to_json(run: &StillWaterRun) -> Vec<u8> {
    serde_json::to_vec(run).expect("the measurements serialise")
}

/// Runs one tank with one model: settles, then samples the run. The run keeps its state in
/// `dir` as it goes (see [`STATE_FILE`]), so that a validation stopped part-way continues
/// where it stopped, with the figures of an uninterrupted run.
fn run_tank<V: CaseDim>(
    tank: &Tank,
    model: &Model,
    quick: bool,
    dir: &Path,
    build: &str,
    pace: &Pace,
) -> Result<StillWaterRun, String> {
    if stopping() {
        return Err("not started: asked to stop".into());
    }
    let (dx, end) = if quick { tank.quick } else { tank.full };
    let mut overrides: Vec<String> = model.overrides.iter().map(|s| s.to_string()).collect();
    overrides.push(format!("resolution.dx={dx}"));
    overrides.push(format!("time.end={end}"));
    if let (true, Some(t)) = (quick, tank.quick_settling) {
        overrides.push(format!("settle.max_time={t}"));
    }
    let source = format!("<still-water {}>", tank.name);
    let loaded = parse_case(&source, tank.text, &overrides).map_err(|e| e.to_string())?;
    let mut sim: Simulation<V> = build_simulation(&loaded).map_err(|e| e.to_string())?;
    let depth = match &tank.floor {
        Some(floor) => {
            let held: f64 = (sim.fluid.mass.iter().zip(&sim.fluid.density))
                .map(|(m, rho)| m / rho)
                .sum();
            (held + floor.displaced) / floor.area
        }
        None => tank.depth,
    };
    let state = dir.join(STATE_FILE);
    let mut run = StillWaterRun {
        depth,
        ..Default::default()
    };
    let mut resumed = None;
    match saved::<V>(dir, build)? {
        Saved::Finished(run) => return Ok(run),
        Saved::Running(c, series) => {
            c.sim.restore(&mut sim)?;
            run = series;
        }
        Saved::Settling(c) => resumed = Some(c),
        Saved::Nothing => {}
    }
    if run.t.is_empty() {
        let options = RunOptions {
            checkpoint_minutes: Some(pace.save_every.as_secs_f64() / 60.0),
            stop: stop_flag(),
            ..Default::default()
        };
        run.settling = match settle_resumable(&loaded, &mut sim, resumed, &state, &options, &mut |_| {}) {
            Ok(Some(s)) => format!(
                "settling {} after {:.2} s ({} steps, {:.1} s wall), residual speed {:.2e} sqrt(gH)",
                s.outcome, s.time, s.steps, s.wall_seconds, s.max_speed_relative
            ),
            Ok(None) => "no settling".into(),
            Err(e) => format!("settling stopped: {e}"),
        };
        if stopping() {
            return Err("interrupted while settling".into());
        }
    }
    sample(&mut sim, &mut run, tank, end, dir, &loaded.text, pace)?;
    run.behind = sim
        .walls
        .count_behind(&sim.fluid.position, sim.config.kernel.support);
    write(&dir.join(RESULT_FILE), &to_json(&run))?;
    for name in [STATE_FILE, SERIES_FILE] {
        let _ = std::fs::remove_file(dir.join(name));
    }
    Ok(run)
}

/// Runs `sim` to `end`, recording the samples from the first one `run` lacks and the largest
/// speed after every step, and saving the state at a sample as `pace` says, or to stop there
/// when asked ([`crate::support::stop_runs_when`]).
fn sample<V: CaseDim>(
    sim: &mut Simulation<V>,
    run: &mut StillWaterRun,
    tank: &Tank,
    end: f64,
    dir: &Path,
    case_text: &str,
    pace: &Pace,
) -> Result<(), String> {
    let speed_scale = (G * run.depth).sqrt();
    let mass: f64 = sim.fluid.mass.iter().sum();
    let bottom = bottom_element(sim, V::from_slice(&tank.bottom[..V::DIM]))
        .ok_or("the tank has no bottom wall element")?;
    let mut saved_at = Instant::now();
    let mut state = Checkpoint::<V> {
        case_text: case_text.into(),
        ..Default::default()
    };
    'outer: for k in run.t.len()..=SAMPLES {
        let target = end * k as f64 / SAMPLES as f64;
        while sim.time < target - 1e-12 {
            // Steps are clamped at the end of the run only: the samples need no tiny steps.
            if let Err(e) = sim.advance(Some(end)) {
                run.stopped = Some(e.to_string());
                break 'outer;
            }
            run.max_speed = run.max_speed.max(sim.max_speed() / speed_scale);
            if run.max_speed > 1.0 {
                run.stopped = Some(format!(
                    "a particle reached sqrt(g H) at t = {:.3} s",
                    sim.time
                ));
                break 'outer;
            }
        }
        run.t.push(sim.time);
        run.kinetic
            .push(sim.energy().kinetic / (mass * G * run.depth));
        run.bottom
            .push(sim.walls.elements.pressure[bottom] / (RHO * G * run.depth));
        // Asked to stop: the state is saved at this sample, to continue from it.
        let stop = stopping();
        if (stop || saved_at.elapsed() >= pace.save_every) && k < SAMPLES {
            // The measurements first: a state without them is not resumed from.
            write(&dir.join(SERIES_FILE), &to_json(run))?;
            state.sim.capture(sim);
            checkpoint::write(&dir.join(STATE_FILE), &state).map_err(|e| e.to_string())?;
            saved_at = Instant::now();
        }
        if stop || pace.stop_after == Some(k) {
            return Err(format!("stopped after sample {k}"));
        }
    }
    Ok(())
}

/// The folder name of a run: its tank, model and resolution.
fn run_folder(tank: &Tank, model: &Model, quick: bool) -> String {
    let name = format!(
        "{}-{}-{}",
        tank.name,
        model.name,
        if quick { "quick" } else { "full" }
    );
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

/// The wall element facing down (normal along gravity, out of the fluid) nearest to `point`.
fn bottom_element<V: Vector>(sim: &Simulation<V>, point: V) -> Option<usize> {
    let e = &sim.walls.elements;
    let down = sim.config.gravity / sim.config.gravity.length();
    (0..e.len())
        .filter(|&j| e.normal[j].dot(down) > 0.99)
        .min_by(|&a, &b| {
            let da = (e.centre[a] - point).length();
            let db = (e.centre[b] - point).length();
            da.total_cmp(&db)
        })
}

/// Mean of `values` over the samples with `t` in `[from, to)`.
fn window_mean(t: &[f64], values: &[f64], from: f64, to: f64) -> f64 {
    let picked: Vec<f64> = t
        .iter()
        .zip(values)
        .filter(|(&t, _)| t >= from && t < to)
        .map(|(_, &v)| v)
        .collect();
    if picked.is_empty() {
        f64::NAN
    } else {
        picked.iter().sum::<f64>() / picked.len() as f64
    }
}

/// The checks of one run, keyed for the known failures.
fn checks(label: &str, run: &StillWaterRun, end: f64) -> [(&'static str, Check); 5] {
    let second = window_mean(&run.t, &run.kinetic, 0.25 * end, 0.5 * end);
    let last = window_mean(&run.t, &run.kinetic, 0.75 * end, f64::INFINITY);
    let bottom = window_mean(&run.t, &run.bottom, 0.5 * end, f64::INFINITY);
    [
        (
            "end",
            Check::new(
                &format!("{label}: reached the end"),
                if run.stopped.is_none() { 1.0 } else { 0.0 },
                1.0,
                Tolerance::AtLeast,
                "no blow-up, no particle leaves the tank",
            ),
        ),
        (
            "speed",
            Check::new(
                &format!("{label}: peak speed / sqrt(gH)"),
                run.max_speed,
                0.01,
                Tolerance::AtMost,
                "water at rest stays at rest (1% of sqrt(g H))",
            ),
        ),
        (
            "growth",
            Check::new(
                &format!("{label}: KE last / second quarter"),
                last / second,
                1.0,
                Tolerance::AtMost,
                "the kinetic energy does not grow",
            ),
        ),
        (
            "bottom",
            Check::new(
                &format!("{label}: bottom pressure / (rho g H)"),
                bottom,
                1.0,
                Tolerance::Relative(0.01),
                "hydrostatic pressure rho g H at the bottom",
            ),
        ),
        (
            "behind",
            Check::new(
                &format!("{label}: particles behind walls"),
                run.behind as f64,
                0.0,
                Tolerance::AtMost,
                "no particle crosses a wall",
            ),
        ),
    ]
}

/// Still water for each tank and wall model (the bars are in the module documentation).
pub struct StillWater;

impl ValidationCase for StillWater {
    fn name(&self) -> &'static str {
        "still-water"
    }
    fn description(&self) -> &'static str {
        "still water in 2-D and 3-D tanks (a box, a step and a sloped side, the SPHERIC test 2 obstacle) for each wall model with the case defaults: peak speed, kinetic energy trend, bottom pressure, no particle behind a wall"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let mut report = CaseReport {
            name: self.name().into(),
            ..Default::default()
        };
        // The runs are independent and small, so they share the cores run by run rather than
        // step by step; each run's results do not depend on the thread count.
        let jobs: Vec<(usize, usize)> = TANKS
            .iter()
            .enumerate()
            .flat_map(|(k, tank)| (0..tank.models.len()).map(move |m| (k, m)))
            .collect();
        let build = build_fingerprint()?;
        let folders = out.join("runs");
        let mut runs = jobs
            .par_iter()
            .map(|&(k, m)| {
                let (tank, model) = (&TANKS[k], &TANKS[k].models[m].0);
                let dir = folders.join(run_folder(tank, model, quick));
                match tank.dim {
                    2 => run_tank::<DVec2>(tank, model, quick, &dir, &build, &PACE),
                    _ => run_tank::<DVec3>(tank, model, quick, &dir, &build, &PACE),
                }
            })
            .collect::<Result<Vec<_>, _>>()?
            .into_iter();
        // Every run has ended: nothing is left to resume.
        let _ = std::fs::remove_dir_all(&folders);
        for (k, tank) in TANKS.iter().enumerate() {
            let end = if quick { tank.quick.1 } else { tank.full.1 };
            let mut kinetic_series = Vec::new();
            for (model, known_failures, limitation) in tank.models {
                let run = runs.next().expect("one run per tank and model");
                let label = format!("{}, {}", tank.name, model.name);
                report.notes.push(format!(
                    "{label}: H = {:.4} m; {}; peak speed {:.3e} sqrt(gH); {} particles behind walls{}",
                    run.depth,
                    run.settling,
                    run.max_speed,
                    run.behind,
                    run.stopped
                        .as_ref()
                        .map(|s| format!("; stopped: {s}"))
                        .unwrap_or_default()
                ));
                for (key, check) in checks(&label, &run, end) {
                    report.checks.push(if known_failures.contains(&key) {
                        check.known_failure(limitation)
                    } else {
                        check
                    });
                }
                kinetic_series.push((
                    model.name.to_string(),
                    run.t.clone(),
                    run.kinetic.iter().map(|v| v.max(1e-16).log10()).collect(),
                ));
            }
            report.plots.push(plot(
                out,
                &format!("kinetic_energy_{k}.png"),
                &format!("still water, {}: kinetic energy", tank.name),
                "t [s]",
                "log10 KE/(M g H)",
                kinetic_series,
            )?);
        }
        Ok(report)
    }
}

/// The still-water case.
pub fn cases() -> Vec<Box<dyn ValidationCase>> {
    vec![Box::new(StillWater)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run stopped part-way (after its state was saved at a sample) and run again continues
    /// from the saved state to the figures of an uninterrupted run, bit for bit; a folder left
    /// by another build is started afresh.
    #[test]
    fn a_stopped_run_continues_to_the_figures_of_an_uninterrupted_one() {
        let box_2d = &TANKS[0];
        let tank = Tank {
            quick: (0.1, 0.5),
            quick_settling: Some(0.2),
            floor: None,
            models: &[],
            ..*box_2d
        };
        let scratch = tempfile::Builder::new()
            .prefix("bisph-still-water-")
            .tempdir()
            .unwrap();
        let root = scratch.path();
        let every_sample = |stop_after| Pace {
            save_every: Duration::ZERO,
            stop_after,
        };
        let (a, b) = (root.join("a"), root.join("b"));
        let whole = run_tank::<DVec2>(&tank, &BI, true, &a, "one", &every_sample(None)).unwrap();
        let stopped = run_tank::<DVec2>(&tank, &BI, true, &b, "one", &every_sample(Some(40)));
        assert_eq!(stopped.unwrap_err(), "stopped after sample 40");
        assert!(b.join(STATE_FILE).exists() && b.join(SERIES_FILE).exists());
        let continued =
            run_tank::<DVec2>(&tank, &BI, true, &b, "one", &every_sample(None)).unwrap();
        let figures = |r: &StillWaterRun| {
            (
                r.t.clone(),
                r.kinetic.clone(),
                r.bottom.clone(),
                r.max_speed,
                r.behind,
                r.stopped.clone(),
            )
        };
        assert_eq!(whole.t.len(), SAMPLES + 1);
        assert_eq!(figures(&whole), figures(&continued));
        // Outcome, settling time and steps (the wall seconds differ).
        let settled = |r: &StillWaterRun| r.settling.split(" steps").next().unwrap().to_string();
        assert!(
            whole.settling.starts_with("settling "),
            "{}",
            whole.settling
        );
        assert_eq!(settled(&whole), settled(&continued));
        // The finished run is recalled by its build, and run again by another.
        let recalled =
            run_tank::<DVec2>(&tank, &BI, true, &b, "one", &every_sample(Some(0))).unwrap();
        assert_eq!(figures(&recalled), figures(&whole));
        let other = run_tank::<DVec2>(&tank, &BI, true, &b, "two", &every_sample(Some(0)));
        assert_eq!(other.unwrap_err(), "stopped after sample 0");
    }
}
