//! SPHERIC test 2 (Kleefsman et al. 2005; paper 2, 3.2): 3-D dam break against a box,
//! pressures P1-P4 on the box's front face and heights H1-H4 against the MARIN experiment.

use crate::check::{CaseReport, Check, Tolerance, ValidationCase};
use crate::support::{column, line, load, plot, read_columns, run_resumable};
use std::path::Path;

/// The experiment file in the data folder: time, P1-P4 and H1-H4 of the MARIN experiment,
/// the heights labelled by the probes' positions (`data/README.md`).
pub const DATA_FILE: &str = "spheric-test2/kleefsman2005-p1-p4-h1-h4.dat";

/// The gauges compared, as named in the case file and in the experiment file's header.
const PRESSURES: [&str; 4] = ["P1", "P2", "P3", "P4"];
const HEIGHTS: [&str; 4] = ["H1", "H2", "H3", "H4"];

/// The experiment series the case compares with.
pub struct Experiment {
    /// Time [s].
    pub t: Vec<f64>,
    /// Pressures P1-P4 [Pa].
    pub pressure: [Vec<f64>; 4],
    /// Water heights H1-H4 (x = 0.496, 0.992, 1.488, 2.638 m) [m].
    pub height: [Vec<f64>; 4],
}

/// Reads the experiment file found in the data folder.
pub fn experiment() -> Result<Experiment, String> {
    let path = crate::data::find(DATA_FILE)?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse_experiment(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses whitespace-separated columns under a header of names with units in brackets
/// (`Time (s) P1 (Pa) ... H4 (m)`), taking the columns by their names.
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
    let wanted: Vec<&str> = std::iter::once("Time")
        .chain(PRESSURES)
        .chain(HEIGHTS)
        .collect();
    let columns = wanted
        .iter()
        .map(|name| index(name))
        .collect::<Result<Vec<_>, _>>()?;
    let mut series: Vec<Vec<f64>> = vec![Vec::new(); columns.len()];
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
    // One series per wanted column, in the order of `wanted`.
    let [t, p1, p2, p3, p4, h1, h2, h3, h4]: [Vec<f64>; 9] = series
        .try_into()
        .map_err(|_| "the time, four pressures and four heights".to_string())?;
    Ok(Experiment {
        t,
        pressure: [p1, p2, p3, p4],
        height: [h1, h2, h3, h4],
    })
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
        "paper 2, 3.2: SPHERIC test 2 3-D dam break on a box; front arrival at P1, first-impact peaks P1-P4, heights H1-H4 against the MARIN experiment"
    }
    fn check_data(&self) -> Result<(), String> {
        experiment().map(|_| ())
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        // Quick: dx = 0.55/8 with the energy-conserving walls (the geometric Shepard factor
        // costs about 9x more per step on this scale); full: the case file (dx = 0.55/45,
        // classic BI with the geometric Shepard factor) over the experiment's six seconds,
        // resumable (hours on a few cores).
        let settings: &[&str] = if quick {
            &[
                "resolution.dx=0.06875",
                "boundary=energy",
                "time.end=0.7",
                "output.vtk_interval=0",
                "output.series_interval=0.005",
            ]
        } else {
            &["time.end=6", "output.vtk_interval=0"]
        };
        let loaded = load(
            "spheric-test2",
            include_str!("../../../cases/spheric-test2.toml"),
            settings,
        )?;
        let s = run_resumable(&loaded, out)?;
        let end = s.time;
        let (h, rows) = read_columns(&out.join("probes.csv"))?;
        let t = column(&h, &rows, "t")?;
        let gauges = |names: [&str; 4]| -> Result<Vec<Vec<f64>>, String> {
            names.iter().map(|name| column(&h, &rows, name)).collect()
        };
        let (pressure, height) = (gauges(PRESSURES)?, gauges(HEIGHTS)?);
        let exp = experiment()?;
        let arrival_sim = arrival(&t, &pressure[0], ARRIVAL_PA);
        let arrival_exp = arrival(&exp.t, &exp.pressure[0], ARRIVAL_PA);
        // First impact: the largest pressure within FIRST_IMPACT_S of the sensor's own arrival.
        let first_peak = |tt: &[f64], y: &[f64]| {
            let from = arrival(tt, y, ARRIVAL_PA);
            tt.iter()
                .zip(y)
                .filter(|(&t, _)| t >= from && t <= from + FIRST_IMPACT_S)
                .fold(0.0f64, |a, (_, &v)| a.max(v))
        };
        let peak_sim: Vec<f64> = pressure.iter().map(|p| first_peak(&t, p)).collect();
        let peak_exp: Vec<f64> = (exp.pressure.iter())
            .map(|p| first_peak(&exp.t, p))
            .collect();
        let rms_height: Vec<f64> = (height.iter().zip(&exp.height))
            .map(|(h, e)| rms(&t, h, &exp.t, e, end))
            .collect();
        let rms_pressure: Vec<f64> = (pressure.iter().zip(&exp.pressure))
            .map(|(p, e)| rms(&t, p, &exp.t, e, end))
            .collect();
        let plots = gauge_plots(out, &t, (&pressure, &height), &exp, end)?;
        let mut checks = vec![Check::new(
            "front arrival at P1 [s]",
            arrival_sim,
            arrival_exp,
            Tolerance::Absolute(0.05),
            "MARIN experiment (first P1 > 1 kPa); within 0.05 s",
        )];
        for (k, (name, x)) in HEIGHTS.iter().zip(PROBE_X).enumerate() {
            checks.push(Check::new(
                &format!("RMS({name} - experiment) [m]"),
                rms_height[k],
                0.05,
                Tolerance::AtMost,
                &format!("MARIN experiment, {name} (x = {x}), over the run"),
            ));
        }
        if !quick {
            checks.push(Check::new(
                "P1 first-impact peak [Pa]",
                peak_sim[0],
                peak_exp[0],
                Tolerance::Relative(0.3),
                "MARIN experiment; within 30% at dx = 0.55/45",
            ));
        }
        let peaks: Vec<String> = (PRESSURES.iter().zip(peak_sim.iter().zip(&peak_exp)))
            .map(|(name, (sim, exp))| format!("{name} {sim:.0} Pa (experiment {exp:.0})"))
            .collect();
        let heights: Vec<String> = (HEIGHTS.iter().zip(&rms_height))
            .map(|(name, r)| format!("{name} {r:.4} m"))
            .collect();
        let pressures: Vec<String> = (PRESSURES.iter().zip(&rms_pressure))
            .map(|(name, r)| format!("{name} {r:.0} Pa"))
            .collect();
        Ok(CaseReport {
            name: self.name().into(),
            checks,
            plots,
            notes: vec![format!(
                "arrival at P1 {arrival_sim:.4} s (experiment {arrival_exp:.4} s); first-impact peaks (within 0.06 s of each sensor's first 1 kPa) {}; RMS of the heights {} and of the pressures {} over [0, {end:.2}] s; {} particles, {} boundary elements, {} steps, {:.3e} particle-steps/s.",
                peaks.join(", "),
                heights.join(", "),
                pressures.join(", "),
                s.fluid_particles, s.boundary_elements, s.steps, s.particle_steps_per_second
            )],
            wall_seconds: 0.0,
        })
    }
}

/// Positions `x` of the height probes H1-H4 [m].
const PROBE_X: [f64; 4] = [0.496, 0.992, 1.488, 2.638];

/// Plots of the pressures (P1 and P2, P3 and P4) and heights (H1 and H2, H3 and H4) of the
/// run (`t`, `(pressure, height)`) against the experiment over `[0, end]`.
fn gauge_plots(
    out: &Path,
    t: &[f64],
    (pressure, height): (&[Vec<f64>], &[Vec<f64>]),
    exp: &Experiment,
    end: f64,
) -> Result<Vec<std::path::PathBuf>, String> {
    let clip = |y: &[f64]| -> (Vec<f64>, Vec<f64>) {
        (exp.t.iter())
            .zip(y)
            .filter(|(&t, _)| t <= end)
            .map(|(&t, &y)| (t, y))
            .unzip()
    };
    let mut plots = Vec::new();
    let groups = [
        ("pressures", "p [Pa]", &PRESSURES, pressure, &exp.pressure),
        ("heights", "height [m]", &HEIGHTS, height, &exp.height),
    ];
    for (kind, unit, names, sim, measured) in groups {
        for pair in [0, 2] {
            let mut series = Vec::new();
            for k in pair..pair + 2 {
                let (te, ye) = clip(&measured[k]);
                series.push(line(
                    &format!("{} bisph", names[k]),
                    t.to_vec(),
                    sim[k].clone(),
                ));
                series.push(line(&format!("{} experiment", names[k]), te, ye));
            }
            let (a, b) = (names[pair], names[pair + 1]);
            plots.push(plot(
                out,
                &format!("spheric2_{}_{}.png", a.to_lowercase(), b.to_lowercase()),
                &format!("SPHERIC test 2: {kind} {a} and {b}"),
                "t [s]",
                unit,
                series,
            )?);
        }
    }
    Ok(plots)
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
        let path = crate::data::find_in(&[source], super::DATA_FILE).unwrap();
        let text = std::fs::read_to_string(path).unwrap();
        let exp = super::parse_experiment(&text).unwrap();
        assert_eq!(exp.t.len(), 7395);
        // The water reaches the probes in the order of their distance from the reservoir
        // (H4 stands in it): H3, then H2, then H1 behind the box.
        let rise = |h: &[f64]| exp.t[h.iter().position(|&h| h > 0.02).unwrap()];
        let [h1, h2, h3] = [0, 1, 2].map(|k| rise(&exp.height[k]));
        assert!(
            h3 < h2 && h2 < h1,
            "rise at H1 {h1} s, H2 {h2} s, H3 {h3} s"
        );
        assert!(exp.height[3][0] > 0.5, "H4 in the reservoir");
        // P1, the lowest sensor, is reached first.
        let first = |p: &[f64]| super::arrival(&exp.t, p, super::ARRIVAL_PA);
        let arrivals: Vec<f64> = exp.pressure.iter().map(|p| first(p)).collect();
        assert!(
            arrivals[1..].iter().all(|&a| a > arrivals[0]),
            "{arrivals:?}"
        );
    }

    #[test]
    fn a_missing_column_is_named() {
        let text =
            "Time (s) P1 (Pa) P2 (Pa) P3 (Pa) H1 (m) H2 (m) H3 (m) H4 (m)\n0 1 2 3 4 5 6 7\n";
        let e = super::parse_experiment(text).err().unwrap();
        assert!(e.contains("`P4`"), "{e}");
    }
}
