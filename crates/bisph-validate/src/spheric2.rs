//! SPHERIC test 2 (Kleefsman et al. 2005; paper 2, 3.2): 3-D dam break against a box,
//! pressures P1-P4 and heights H2, H4 against the MARIN experiment.

use crate::check::{CaseReport, Check, Tolerance, ValidationCase};
use crate::support::{column, line, load, plot, read_columns, run};
use std::path::Path;

/// The experiment file in the data folder: time, P1, H2 and H4 of the MARIN experiment
/// (`data/README.md`).
pub const DATA_FILE: &str = "spheric-test2/kleefsman2005-p1-h2-h4.dat";

/// The experiment series the case compares with.
pub struct Experiment {
    /// Time [s].
    pub t: Vec<f64>,
    /// Pressure P1 [Pa].
    pub p1: Vec<f64>,
    /// Water height H2 (x = 0.992 m) [m].
    pub h2: Vec<f64>,
    /// Water height H4 (x = 2.638 m) [m].
    pub h4: Vec<f64>,
}

/// Reads the experiment file found in the data folder.
pub fn experiment() -> Result<Experiment, String> {
    let path = crate::data::find(DATA_FILE)?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse_experiment(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses whitespace-separated columns under a header of names with units in brackets
/// (`Time (s) P1 (Pa) ... H2 (m) ... H4 (m)`), so that the official file with all its columns
/// reads as well. Only H2 and H4 are taken of the heights: they are the same in every copy of
/// the file (the official file's H1 and H3 columns are swapped).
fn parse_experiment(text: &str) -> Result<Experiment, String> {
    let mut lines = text.lines();
    let names: Vec<&str> = lines
        .next()
        .unwrap_or("")
        .split_whitespace()
        .filter(|w| !w.starts_with('('))
        .collect();
    let index = |name: &str| {
        names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| format!("line 1: no column `{name}` in the header"))
    };
    let columns = [index("Time")?, index("P1")?, index("H2")?, index("H4")?];
    let mut series: [Vec<f64>; 4] = Default::default();
    for (k, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let values: Vec<f64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|_| format!("line {}: expected numbers, found `{line}`", k + 2))?;
        if values.len() != names.len() {
            return Err(format!(
                "line {}: expected {} values, found {}",
                k + 2,
                names.len(),
                values.len()
            ));
        }
        for (s, &c) in series.iter_mut().zip(&columns) {
            s.push(values[c]);
        }
    }
    if series[0].is_empty() {
        return Err("no data rows".into());
    }
    let [t, p1, h2, h4] = series;
    Ok(Experiment { t, p1, h2, h4 })
}

/// First time `p` rises above `threshold` (linear interpolation), NaN if never.
pub fn arrival(t: &[f64], p: &[f64], threshold: f64) -> f64 {
    for k in 1..p.len() {
        if p[k - 1] < threshold && p[k] >= threshold {
            return t[k - 1] + (threshold - p[k - 1]) / (p[k] - p[k - 1]) * (t[k] - t[k - 1]);
        }
    }
    f64::NAN
}

/// Value of the series `(t, y)` at `x` (linear interpolation, clamped at the ends).
fn at(t: &[f64], y: &[f64], x: f64) -> f64 {
    let k = t.partition_point(|&v| v < x);
    if k == 0 {
        return y[0];
    }
    if k >= t.len() {
        return y[t.len() - 1];
    }
    let s = (x - t[k - 1]) / (t[k] - t[k - 1]);
    y[k - 1] + s * (y[k] - y[k - 1])
}

/// RMS of `sim - experiment` at the simulation's sample times in `[0, end]`.
fn rms(t: &[f64], sim: &[f64], te: &[f64], exp: &[f64], end: f64) -> f64 {
    let (mut s, mut n) = (0.0, 0);
    for (&t, &y) in t.iter().zip(sim) {
        if t <= end {
            let d = y - at(te, exp, t);
            s += d * d;
            n += 1;
        }
    }
    (s / n.max(1) as f64).sqrt()
}

/// SPHERIC test 2.
pub struct SphericTest2;

/// Pressure above which the front has arrived at P1 [Pa] (the gauge offset is about 50 Pa).
const ARRIVAL_PA: f64 = 1000.0;

/// Length of the first-impact window after the arrival at P1 [s] (the experiment's peak comes
/// 0.02 s after the arrival; later peaks come from the water falling back).
const FIRST_IMPACT_S: f64 = 0.06;

impl ValidationCase for SphericTest2 {
    fn name(&self) -> &'static str {
        "spheric-test2"
    }
    fn description(&self) -> &'static str {
        "paper 2, 3.2: SPHERIC test 2 3-D dam break on a box; front arrival at P1, P1 first peak, heights H2 and H4 against the MARIN experiment"
    }
    fn check_data(&self) -> Result<(), String> {
        experiment().map(|_| ())
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        // Quick: dx = 0.55/8 with the energy-conserving walls (the geometric Shepard factor
        // costs about 9x more per step on this scale); full: the case file
        // (dx = 0.55/45, classic BI with the geometric Shepard factor).
        let settings: &[&str] = if quick {
            &[
                "resolution.dx=0.06875",
                "boundary=energy",
                "time.end=0.7",
                "output.vtk_interval=0",
                "output.series_interval=0.005",
            ]
        } else {
            &[]
        };
        let loaded = load(
            "spheric-test2",
            include_str!("../../../cases/spheric-test2.toml"),
            settings,
        )?;
        let s = run(&loaded, out)?;
        let end = s.time;
        let (h, rows) = read_columns(&out.join("probes.csv"))?;
        let t = column(&h, &rows, "t")?;
        let p1 = column(&h, &rows, "P1")?;
        let h2 = column(&h, &rows, "H2")?;
        let h4 = column(&h, &rows, "H4")?;
        let Experiment {
            t: te,
            p1: ep1,
            h2: eh2,
            h4: eh4,
        } = experiment()?;
        let arrival_sim = arrival(&t, &p1, ARRIVAL_PA);
        let arrival_exp = arrival(&te, &ep1, ARRIVAL_PA);
        // First impact: the largest P1 within FIRST_IMPACT_S of the front's arrival.
        let window = |tt: &[f64], y: &[f64], from: f64| {
            tt.iter()
                .zip(y)
                .filter(|(&t, _)| t >= from && t <= from + FIRST_IMPACT_S)
                .fold(0.0f64, |a, (_, &v)| a.max(v))
        };
        let peak_sim = window(&t, &p1, arrival_sim);
        let peak_exp = window(&te, &ep1, arrival_exp);
        let rms_h2 = rms(&t, &h2, &te, &eh2, end);
        let rms_h4 = rms(&t, &h4, &te, &eh4, end);
        let clip = |tt: &[f64], y: &[f64]| -> (Vec<f64>, Vec<f64>) {
            tt.iter()
                .zip(y)
                .filter(|(&t, _)| t <= end)
                .map(|(&t, &y)| (t, y))
                .unzip()
        };
        let (te1, ep1c) = clip(&te, &ep1);
        let (te2, eh2c) = clip(&te, &eh2);
        let (te4, eh4c) = clip(&te, &eh4);
        let plots = vec![
            plot(
                out,
                "spheric2_p1.png",
                "SPHERIC test 2: pressure P1",
                "t [s]",
                "p [Pa]",
                vec![
                    line("bisph", t.clone(), p1.clone()),
                    line("experiment", te1, ep1c),
                ],
            )?,
            plot(
                out,
                "spheric2_heights.png",
                "SPHERIC test 2: heights H2 and H4",
                "t [s]",
                "height [m]",
                vec![
                    line("H2 bisph", t.clone(), h2.clone()),
                    line("H2 experiment", te2, eh2c),
                    line("H4 bisph", t.clone(), h4.clone()),
                    line("H4 experiment", te4, eh4c),
                ],
            )?,
        ];
        let mut checks = vec![
            Check::new(
                "front arrival at P1 [s]",
                arrival_sim,
                arrival_exp,
                Tolerance::Absolute(0.05),
                "MARIN experiment (first P1 > 1 kPa); within 0.05 s",
            ),
            Check::new(
                "RMS(H2 - experiment) [m]",
                rms_h2,
                0.05,
                Tolerance::AtMost,
                "MARIN experiment, H2 (x = 0.992), over the run",
            ),
            Check::new(
                "RMS(H4 - experiment) [m]",
                rms_h4,
                0.05,
                Tolerance::AtMost,
                "MARIN experiment, H4 (x = 2.638), over the run",
            ),
        ];
        if !quick {
            checks.push(Check::new(
                "P1 first-impact peak [Pa]",
                peak_sim,
                peak_exp,
                Tolerance::Relative(0.3),
                "MARIN experiment; within 30% at dx = 0.55/45",
            ));
        }
        Ok(CaseReport {
            name: self.name().into(),
            checks,
            plots,
            notes: vec![format!(
                "arrival at P1 {arrival_sim:.4} s (experiment {arrival_exp:.4} s); P1 first-impact peak (within 0.06 s of the arrival) {peak_sim:.0} Pa (experiment {peak_exp:.0} Pa); RMS H2 {rms_h2:.4} m, H4 {rms_h4:.4} m over [0, {end:.2}] s; {} particles, {} boundary elements, {} steps, {:.3e} particle-steps/s.",
                s.fluid_particles, s.boundary_elements, s.steps, s.particle_steps_per_second
            )],
            wall_seconds: 0.0,
        })
    }
}

/// The SPHERIC test 2 case.
pub fn cases() -> Vec<Box<dyn ValidationCase>> {
    vec![Box::new(SphericTest2)]
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_source_tree_holds_the_experiment_data() {
        let source = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data");
        crate::data::find_in(&[source], super::DATA_FILE).unwrap();
    }
}
