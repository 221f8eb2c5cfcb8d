//! Validation cases of paper 1 (energy-conserving boundary integrals): jet impact,
//! adiabatic piston and the Lobovsky dam break.

use crate::case::{parse_case, LoadedCase};
use crate::plot::{write_png, Plot, Series, Style};
use crate::runner::{run_case, Summary};
use crate::validate::{CaseReport, Check, Tolerance, ValidationCase};
use std::path::Path;

/// The paper-1 validation cases.
pub fn cases() -> Vec<Box<dyn ValidationCase>> {
    vec![Box::new(JetImpact), Box::new(AdiabaticPiston)]
}

/// A case file shipped in `cases/`, embedded so `bisph validate` runs from anywhere.
fn load(name: &str, text: &str, overrides: &[&str]) -> Result<LoadedCase, String> {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    parse_case(&format!("cases/{name}.toml"), text, &overrides).map_err(|e| e.to_string())
}

fn run(loaded: &LoadedCase, out: &Path) -> Result<Summary, String> {
    run_case(loaded, out, &mut |_| {}).map_err(|e| e.to_string())
}

/// Columns of a CSV file written by a run, by header name.
pub fn read_columns(path: &Path) -> Result<(Vec<String>, Vec<Vec<String>>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap_or("").split(',').map(String::from).collect();
    let rows = lines.map(|l| l.split(',').map(String::from).collect()).collect();
    Ok((header, rows))
}

/// A numeric column by name.
pub fn column(header: &[String], rows: &[Vec<String>], name: &str) -> Result<Vec<f64>, String> {
    let k = header.iter().position(|h| h == name).ok_or_else(|| format!("no column `{name}`"))?;
    Ok(rows.iter().filter_map(|r| r.get(k)).filter_map(|v| v.parse().ok()).collect())
}

fn plot(out: &Path, file: &str, title: &str, x_label: &str, y_label: &str, series: Vec<(Series, Style)>) -> Result<std::path::PathBuf, String> {
    let path = out.join(file);
    let plot = Plot { title: title.into(), x_label: x_label.into(), y_label: y_label.into(), series };
    write_png(&plot, &path, 1000, 600).map_err(|e| e.0)?;
    Ok(path)
}

fn line(label: &str, x: Vec<f64>, y: Vec<f64>) -> (Series, Style) {
    (Series { label: label.into(), x, y }, Style::Line)
}

/// Energy components (relative to the initial total) against time, as a plot.
fn energy_plot(out: &Path, title: &str, scale: f64) -> Result<std::path::PathBuf, String> {
    let (h, rows) = read_columns(&out.join("energy.csv"))?;
    let t = column(&h, &rows, "t")?;
    let mut series = Vec::new();
    for name in ["kinetic", "compressible", "wall_work", "total"] {
        let y = column(&h, &rows, name)?;
        let y0 = if name == "total" { y.first().copied().unwrap_or(0.0) } else { 0.0 };
        series.push(line(name, t.clone(), y.iter().map(|v| (v - y0) / scale).collect()));
    }
    plot(out, "energy_components.png", title, "t [s]", "energy / E_scale (total: change)", series)
}

/// Jet impact on a fixed wall (paper 1, 5.1).
pub struct JetImpact;

impl ValidationCase for JetImpact {
    fn name(&self) -> &'static str {
        "jet-impact"
    }
    fn description(&self) -> &'static str {
        "paper 1, 5.1: fluid block hitting a fixed wall at Ma = 0.01; total energy conserved over three acoustic periods"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let dx = if quick { "resolution.dx=0.02" } else { "resolution.dx=0.0025" };
        let loaded = load("jet-impact", include_str!("../../../cases/jet-impact.toml"), &[dx, "output.vtk_interval=0.005"])?;
        let s = run(&loaded, out)?;
        let (h, rows) = read_columns(&out.join("forces.csv"))?;
        let peak = column(&h, &rows, "fy")?.iter().fold(0.0f64, |m, f| m.max(-f));
        Ok(CaseReport {
            name: self.name().into(),
            checks: vec![Check::new(
                "max |E(t) - E(0)| / E_k(0), 3 periods",
                s.energy_drift_max_relative,
                0.005,
                Tolerance::AtMost,
                "issue 3 acceptance (paper 1 fig 3: constant total)",
            )],
            plots: vec![energy_plot(out, "Jet impact: energy", s.energy_scale)?],
            notes: vec![format!(
                "{} particles, {} steps, {:.2} midpoint iterations per step (max {}, {} steps above tolerance). \
                 Peak wall force {peak:.1} N/m (Joukowsky rho0 c0 U L = 100 N/m).",
                s.fluid_particles, s.steps, s.iterations_mean, s.iterations_max, s.unconverged_steps
            )],
            wall_seconds: 0.0,
        })
    }
}

/// Adiabatic piston (paper 1, 5.2).
pub struct AdiabaticPiston;

/// Period of `x'' = w2 x0 (x0 / x - 1)`, `x(0) = x0 - a`, `x'(0) = 0` (paper 1, eq 54), by RK4:
/// twice the time between the first two turning points.
pub fn piston_ode_period(w2: f64, x0: f64, a: f64) -> (f64, Vec<f64>, Vec<f64>) {
    let dt = 1e-3;
    let (mut x, mut v, mut t) = (x0 - a, 0.0f64, 0.0);
    let acc = |x: f64| w2 * x0 * (x0 / x - 1.0);
    let (mut ts, mut xs) = (vec![t], vec![x]);
    let mut turns = Vec::new();
    while t < 60.0 && turns.len() < 3 {
        let (k1x, k1v) = (v, acc(x));
        let (k2x, k2v) = (v + 0.5 * dt * k1v, acc(x + 0.5 * dt * k1x));
        let (k3x, k3v) = (v + 0.5 * dt * k2v, acc(x + 0.5 * dt * k2x));
        let (k4x, k4v) = (v + dt * k3v, acc(x + dt * k3x));
        let v_new = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        if v > 0.0 && v_new <= 0.0 || v < 0.0 && v_new >= 0.0 {
            // linear interpolation of the turning point
            turns.push(t + dt * v / (v - v_new));
        }
        v = v_new;
        t += dt;
        ts.push(t);
        xs.push(x);
    }
    let period = if turns.len() >= 2 { 2.0 * (turns[1] - turns[0]) } else { f64::NAN };
    (period, ts, xs)
}

/// Mean period of a sampled oscillation from its crossings of its mean value.
pub fn measured_period(t: &[f64], x: &[f64]) -> f64 {
    if x.len() < 3 {
        return f64::NAN;
    }
    let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let mid = 0.5 * (lo + hi);
    let mut ups = Vec::new();
    for k in 1..x.len() {
        if x[k - 1] < mid && x[k] >= mid {
            ups.push(t[k - 1] + (mid - x[k - 1]) / (x[k] - x[k - 1]) * (t[k] - t[k - 1]));
        }
    }
    if ups.len() < 2 {
        return f64::NAN;
    }
    (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64
}

impl ValidationCase for AdiabaticPiston {
    fn name(&self) -> &'static str {
        "adiabatic-piston"
    }
    fn description(&self) -> &'static str {
        "paper 1, 5.2: Ruchardt piston driven by the fluid; period against the ODE eq 54, fluid + piston + outside work conserved"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let settings: &[&str] = if quick {
            &["resolution.dx=0.0396", "resolution.h_over_dx=2.0", "output.vtk_interval=0"]
        } else {
            &["resolution.dx=0.0099010", "time.courant=0.025"]
        };
        let loaded = load("adiabatic-piston", include_str!("../../../cases/adiabatic-piston.toml"), settings)?;
        let s = run(&loaded, out)?;
        let (h, rows) = read_columns(&out.join("bodies.csv"))?;
        let t = column(&h, &rows, "t")?;
        let position = column(&h, &rows, "position")?;
        // Case constants (see cases/adiabatic-piston.toml).
        let (x0, a, m, big_m, c0) = (1.0, 0.0099, 4.84, 1.0, 1.0);
        let w2 = (c0 / x0) * (c0 / x0) * big_m / m;
        let (ode_period, ode_t, ode_x) = piston_ode_period(w2, x0, a);
        let period = measured_period(&t, &position);
        let omega = w2.sqrt();
        let oscillation_energy = 0.5 * m * (a * omega) * (a * omega);
        let drift = s.energy_drift_max_relative * s.energy_scale / oscillation_energy;
        let x_sim: Vec<f64> = position.iter().map(|p| x0 - a + p).collect();
        let harmonic: Vec<f64> = t.iter().map(|&t| x0 - a * (omega * t).cos()).collect();
        let plots = vec![
            plot(
                out,
                "piston_position.png",
                "Adiabatic piston: position",
                "t",
                "x",
                vec![line("bisph", t.clone(), x_sim), line("harmonic", t.clone(), harmonic), line("ODE eq 54", ode_t, ode_x)],
            )?,
            energy_plot(out, "Adiabatic piston: energy (wall_work = piston kinetic + outside work)", s.energy_scale)?,
        ];
        Ok(CaseReport {
            name: self.name().into(),
            checks: vec![
                Check::new("period / ODE period", period / ode_period, 1.0, Tolerance::Absolute(0.05), "paper 1 eq 54 (RK4)"),
                Check::new(
                    "max |E(t) - E(0)| / oscillation energy",
                    drift,
                    0.005,
                    Tolerance::AtMost,
                    "issue 3 acceptance; oscillation energy m (A omega)^2 / 2",
                ),
            ],
            plots,
            notes: vec![format!(
                "measured period {period:.4}, ODE {ode_period:.4}, harmonic {:.4}; {} particles, {} steps, {:.2} iterations per step (max {}, {} steps above tolerance).",
                2.0 * std::f64::consts::PI / omega,
                s.fluid_particles,
                s.steps,
                s.iterations_mean,
                s.iterations_max,
                s.unconverged_steps
            )],
            wall_seconds: 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ode_period_tends_to_the_harmonic_one_for_small_amplitudes() {
        let w2: f64 = 0.25;
        let (period, _, _) = piston_ode_period(w2, 1.0, 1e-4);
        assert!((period - 2.0 * std::f64::consts::PI / w2.sqrt()).abs() < 1e-3);
    }

    #[test]
    fn measured_period_of_a_sine() {
        let t: Vec<f64> = (0..4000).map(|k| k as f64 * 0.01).collect();
        let x: Vec<f64> = t.iter().map(|t| (2.0 * std::f64::consts::PI * t / 7.0).sin()).collect();
        assert!((measured_period(&t, &x) - 7.0).abs() < 1e-3);
    }
}
