//! Validation cases of paper 3 (unified semi-analytical walls, `boundary = "usaw"`):
//! - `usaw-gamma`: the exact segment `grad gamma_as` against an independent quadrature, the
//!   polygon sum against finite differences of the area-integral gamma, and the integrated
//!   gamma (eq 4) against the geometric one along a path towards a wall;
//! - `usaw-channel`: the inviscid channel energy budget (section 3.2, eq 39), usaw against the
//!   energy-conserving walls on the same particles, with and without volume diffusion;
//! - `usaw-still-water`: still water (section 7.1) with Mayrhofer's volume diffusion, with and
//!   without the hydrostatic correction of eq 81.
//!
//! Periodic boundaries are not available yet: the channel and the still water run in closed
//! boxes (for the channel the side walls are parallel to the flow, a symmetry of the exact
//! solution; the still-water box is wide and its surface is measured in the middle half).

use crate::build::build_simulation;
use crate::case::parse_case;
use crate::plot::line_plot_png as plot;
use crate::validate::{CaseReport, Check, Tolerance, ValidationCase};
use bisph_core::geometry::box_elements_2d;
use bisph_core::neighbours::CellGrid;
use bisph_core::quadrature::gauss_legendre;
use bisph_core::walls::{geometric_shepard, usaw};
use bisph_core::{BoundaryElements, Simulation, Wendland};
use glam::DVec2;
use std::f64::consts::PI;
use std::path::Path;

/// The paper-3 validation cases.
pub fn cases() -> Vec<Box<dyn ValidationCase>> {
    vec![
        Box::new(UsawGamma),
        Box::new(UsawChannel),
        Box::new(UsawStillWater),
        Box::new(UsawTankCorner),
    ]
}

fn box_walls(
    min: DVec2,
    max: DVec2,
    dx: f64,
    h: f64,
) -> (BoundaryElements<DVec2>, CellGrid<DVec2>) {
    let mut e = BoundaryElements::default();
    for s in box_elements_2d(min, max, &[], dx) {
        e.push(s.centre, s.normal, s.area, 0, &s.corners);
    }
    let mut grid = CellGrid::new(2.0 * h);
    grid.rebuild(&e.centre);
    (e, grid)
}

/// Independent reference for `int_s W`: composite 8-point Gauss-Legendre (64 panels) over
/// the part of the segment inside the support, split at the foot of the perpendicular.
fn reference_segment_integral(kernel: &Wendland, x: DVec2, p0: DVec2, p1: DVec2) -> f64 {
    let d = p1 - p0;
    let len = d.length();
    let t = d / len;
    let foot = (x - p0).dot(t);
    let dist = ((x - p0) - t * foot).length();
    let rb = kernel.support * kernel.support - dist * dist;
    if rb <= 0.0 {
        return 0.0;
    }
    let half = rb.sqrt();
    let (a, b) = ((foot - half).max(0.0), (foot + half).min(len));
    if a >= b {
        return 0.0;
    }
    let f = |s: f64| kernel.value((p0 + t * s - x).length());
    if foot > a && foot < b {
        gauss_legendre(a, foot, 64, f) + gauss_legendre(foot, b, 64, f)
    } else {
        gauss_legendre(a, b, 64, f)
    }
}

/// `usaw-gamma`: the geometric building blocks of the semi-analytical walls.
pub struct UsawGamma;

impl ValidationCase for UsawGamma {
    fn name(&self) -> &'static str {
        "usaw-gamma"
    }
    fn description(&self) -> &'static str {
        "paper 3, eqs 4, 9-10: exact segment grad gamma vs quadrature, polygon sum vs FD of the area gamma, integrated vs geometric gamma over 1000 steps"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let mut report = CaseReport {
            name: self.name().into(),
            ..Default::default()
        };
        let kernel = Wendland::new(0.1, 2);
        // 1. One segment, many points (inside, on, beyond the support; foot on and off it).
        let n_pts = if quick { 41 } else { 161 };
        let segments = [
            (DVec2::new(-0.05, 0.0), DVec2::new(0.05, 0.0)),
            (DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0)),
            (DVec2::new(0.0, -0.03), DVec2::new(0.11, 0.08)),
        ];
        let mut worst: f64 = 0.0;
        for (p0, p1) in segments {
            for i in 0..n_pts {
                for j in 0..n_pts {
                    let x = DVec2::new(
                        -0.3 + 0.6 * i as f64 / (n_pts - 1) as f64,
                        -0.25 + 0.5 * j as f64 / (n_pts - 1) as f64,
                    );
                    let n_out = DVec2::new(0.0, -1.0);
                    let g = usaw::segment_grad_gamma(&kernel, x, p0, p1, n_out);
                    let r = reference_segment_integral(&kernel, x, p0, p1);
                    worst = worst.max((g.y - r).abs());
                }
            }
        }
        report.checks.push(Check::new(
            "segment grad gamma_as: max |closed form - quadrature| (h = 0.1)",
            worst,
            1e-12,
            Tolerance::AtMost,
            "composite Gauss-Legendre over the clipped segment (issue 6 acceptance: 1e-12)",
        ));
        // 2. Closed polygon (a box): sum of grad gamma_as vs FD of the geometric gamma.
        let (dx, h) = (0.025, 0.05);
        let k2 = Wendland::new(h, 2);
        let (e, grid) = box_walls(DVec2::ZERO, DVec2::new(1.0, 0.6), dx, h);
        let probes = if quick { 30 } else { 200 };
        let mut worst_fd: f64 = 0.0;
        for k in 0..probes {
            // Points near the floor, the left wall and the corner (deterministic spread).
            let s = (k as f64 + 0.5) / probes as f64;
            let x = DVec2::new(0.004 + 0.2 * s, 0.003 + 0.11 * ((7.0 * s) % 1.0));
            let g = usaw::grad_gamma(&k2, x, &e, &grid);
            let step = 1e-6;
            let mut fd = DVec2::ZERO;
            for c in 0..2 {
                let mut d = DVec2::ZERO;
                d[c] = step;
                fd[c] = (geometric_shepard::gamma(&k2, x + d, &e, &grid)
                    - geometric_shepard::gamma(&k2, x - d, &e, &grid))
                    / (2.0 * step);
            }
            worst_fd = worst_fd.max((g - fd).length() * h);
        }
        report.checks.push(Check::new(
            "box: max |sum grad gamma_as - FD grad gamma| h",
            worst_fd,
            1e-6,
            Tolerance::AtMost,
            "central differences (step 1e-6) of the exact area-integral gamma (paper 2)",
        ));
        // 3. Integrated gamma (eq 4, trapezoidal) along a path along and towards the floor.
        let (dx, h) = (0.01, 0.02);
        let k3 = Wendland::new(h, 2);
        let (e, grid) = box_walls(DVec2::ZERO, DVec2::ONE, dx, h);
        let (start, end) = (DVec2::new(0.3, 0.05), DVec2::new(0.55, 0.004));
        let steps = 1000;
        let mut x = start;
        let mut gamma = geometric_shepard::gamma(&k3, x, &e, &grid);
        let mut g_old = usaw::grad_gamma(&k3, x, &e, &grid);
        let (mut worst_int, mut ts, mut gi, mut gg): (f64, _, _, _) =
            (0.0, Vec::new(), Vec::new(), Vec::new());
        for k in 1..=steps {
            let next = start + (end - start) * (k as f64 / steps as f64);
            let g_new = usaw::grad_gamma(&k3, next, &e, &grid);
            gamma += 0.5 * (g_old + g_new).dot(next - x);
            x = next;
            g_old = g_new;
            let exact = geometric_shepard::gamma(&k3, x, &e, &grid);
            worst_int = worst_int.max((gamma - exact).abs());
            ts.push(k as f64);
            gi.push(gamma);
            gg.push(exact);
        }
        report.checks.push(Check::new(
            "integrated vs geometric gamma, 1000 steps from d = 2.5h to 0.2h: max |diff|",
            worst_int,
            1e-3,
            Tolerance::AtMost,
            "issue 6 acceptance: within 1e-3",
        ));
        report.plots.push(plot(
            out,
            "gamma_path.png",
            "gamma along a path towards the floor",
            "step",
            "gamma",
            vec![
                ("integrated (eq 4)".into(), ts.clone(), gi),
                ("geometric (paper 2)".into(), ts, gg),
            ],
        )?);
        Ok(report)
    }
}

const CHANNEL: &str = r#"
name = "usaw-channel"
dim = 2
boundary = "usaw"
elastic_bounce = false
[usaw]
wall_interpolation = "shepard"
density_power = 0
[fluid]
density = 1.0
sound_speed = 10.0
eos = "tait"
[resolution]
dx = 0.04
h_over_dx = 2.0
[time]
end = 2.0
courant = 0.2
[output]
plots = false
[[fluid_block]]
shape = "box"
min = [0.02, 0.02]
max = [0.98, 0.98]
pressure = 0.0
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [2.0, 1.0]
"#;

/// One channel run: t+, E+, rms(v_x)/(c0/10), and when it stopped early.
struct ChannelRun {
    t: Vec<f64>,
    e_plus: Vec<f64>,
    vx_rms: Vec<f64>,
    stopped: Option<String>,
}

fn channel_run(dx: f64, end_plus: f64, overrides: &[&str]) -> Result<ChannelRun, String> {
    let mut all: Vec<String> = vec![
        format!("resolution.dx={dx}"),
        format!("fluid_block.0.min=[{},{}]", 0.5 * dx, 0.5 * dx),
        format!("fluid_block.0.max=[{},{}]", 2.0 - 0.5 * dx, 1.0 - 0.5 * dx),
    ];
    all.extend(overrides.iter().map(|s| s.to_string()));
    let loaded = parse_case("<usaw-channel>", CHANNEL, &all).map_err(|e| e.to_string())?;
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).map_err(|e| e.to_string())?;
    let (c0, rho0, height) = (10.0, 1.0, 1.0);
    let amplitude = c0 / 10.0;
    for i in 0..sim.fluid.len() {
        let y = sim.fluid.position[i].y;
        sim.fluid.velocity[i] = DVec2::new(0.0, amplitude * (4.0 * PI * y).sin());
    }
    sim.refresh_rates();
    let scale = rho0 * c0 * c0 * height * height;
    let end = end_plus * height / c0;
    let mut run = ChannelRun {
        t: vec![0.0],
        e_plus: vec![0.0],
        vx_rms: vec![0.0],
        stopped: None,
    };
    let mut e = 0.0;
    let mut residual = sim.skew_adjoint_residual();
    let mut sampled_at = 0.0;
    while sim.time < end - 1e-12 {
        if let Err(err) = sim.advance(Some(end)) {
            run.stopped = Some(format!("{err}"));
            break;
        }
        if !sim.step.is_multiple_of(SAMPLE_EVERY) && sim.time < end - 1e-12 {
            continue;
        }
        let next = sim.skew_adjoint_residual();
        // Eq 39, trapezoidal in time between samples (about 25 samples per acoustic period).
        e += 0.5 * (residual + next) * (sim.time - sampled_at);
        residual = next;
        sampled_at = sim.time;
        // rms v_x over the middle half (away from the side walls).
        let f = &sim.fluid;
        let (mut vx2, mut n) = (0.0, 0);
        for (r, u) in f.position.iter().zip(&f.velocity) {
            if r.x > 0.5 && r.x < 1.5 {
                vx2 += u.x * u.x;
                n += 1;
            }
        }
        run.t.push(sim.time * c0 / height);
        run.e_plus.push(e / scale);
        run.vx_rms.push((vx2 / n.max(1) as f64).sqrt() / amplitude);
    }
    Ok(run)
}

/// First `t+` at which `rms(v_x) / (c0/10)` exceeds `threshold` (the flow is no longer
/// uniform in x: break-up), or `None`.
fn break_up(run: &ChannelRun, threshold: f64) -> Option<f64> {
    run.t
        .iter()
        .zip(&run.vx_rms)
        .find(|(_, &v)| v > threshold)
        .map(|(&t, _)| t)
}

/// Steps between evaluations of the energy budget's integrand.
const SAMPLE_EVERY: u64 = 2;

/// `usaw-channel`: paper 3, section 3.2.
pub struct UsawChannel;

/// Break-up threshold on `rms(v_x) / (c0/10)`.
const BREAK_UP: f64 = 0.05;

impl ValidationCase for UsawChannel {
    fn name(&self) -> &'static str {
        "usaw-channel"
    }
    fn description(&self) -> &'static str {
        "paper 3, 3.2: inviscid channel energy budget E+ (eq 39) vs t+, usaw vs energy walls on the same particles; break-up time with and without volume diffusion"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let (dx, end_plus) = if quick { (0.05, 12.0) } else { (0.02, 30.0) };
        let mut report = CaseReport {
            name: self.name().into(),
            ..Default::default()
        };
        let energy = channel_run(dx, end_plus, &["boundary=\"energy\""])?;
        let plain = channel_run(dx, end_plus, &[])?;
        let diffused = channel_run(
            dx,
            end_plus,
            &["fluid.diffusion=mayrhofer", "fluid.eta=10.0"],
        )?;
        let max_abs = |r: &ChannelRun| r.e_plus.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let fmt_break = |r: &ChannelRun| match break_up(r, BREAK_UP) {
            Some(t) => format!("{t:.2}"),
            None => format!("none up to t+ = {end_plus}"),
        };
        for (name, r) in [
            ("energy walls", &energy),
            ("usaw", &plain),
            ("usaw + volume diffusion (eta = 10)", &diffused),
        ] {
            report.notes.push(format!(
                "{name}: max |E+| = {:.3e}, final E+ = {:.3e}, break-up (rms v_x > {BREAK_UP} c0/10) at t+ = {}, final rms v_x/(c0/10) = {:.3e}{}",
                max_abs(r),
                r.e_plus.last().copied().unwrap_or(f64::NAN),
                fmt_break(r),
                r.vx_rms.last().copied().unwrap_or(f64::NAN),
                r.stopped.as_ref().map(|s| format!("; stopped: {s}")).unwrap_or_default()
            ));
        }
        report.checks.push(Check::new(
            "energy walls: max |E+|",
            max_abs(&energy),
            1e-12,
            Tolerance::AtMost,
            "paper 1: fixed energy-conserving walls exchange no power (round-off)",
        ));
        report.checks.push(Check::new(
            "usaw: max |E+| (not skew-adjoint, paper 3 fig 2)",
            max_abs(&plain),
            1e-9,
            Tolerance::AtLeast,
            "paper 3, 3.1: discrete operators with boundary terms are not skew-adjoint",
        ));
        let t_plain = break_up(&plain, BREAK_UP).unwrap_or(f64::INFINITY);
        let t_diff = break_up(&diffused, BREAK_UP).unwrap_or(f64::INFINITY);
        report.checks.push(Check::new(
            "volume diffusion postpones break-up: t+_break(diffusion) - t+_break(plain)",
            if t_diff.is_infinite() && t_plain.is_infinite() {
                0.0
            } else if t_diff.is_infinite() {
                end_plus - t_plain
            } else {
                t_diff - t_plain
            },
            0.0,
            Tolerance::AtLeast,
            "paper 3, section 4: volume diffusion suppresses the numerical turbulence",
        ));
        let ser = |r: &ChannelRun, f: &dyn Fn(f64) -> f64, vals: &[f64]| -> Vec<f64> {
            let _ = r;
            vals.iter().map(|&v| f(v)).collect()
        };
        let id = |v: f64| v;
        report.plots.push(plot(
            out,
            "energy_budget.png",
            "channel: energy budget E+ (eq 39)",
            "t+ = t c0 / h",
            "E+ = E / (rho0 c0^2 h^2)",
            vec![
                (
                    "energy walls".into(),
                    energy.t.clone(),
                    ser(&energy, &id, &energy.e_plus),
                ),
                (
                    "usaw".into(),
                    plain.t.clone(),
                    ser(&plain, &id, &plain.e_plus),
                ),
                (
                    "usaw + volume diffusion".into(),
                    diffused.t.clone(),
                    ser(&diffused, &id, &diffused.e_plus),
                ),
            ],
        )?);
        report.plots.push(plot(
            out,
            "break_up.png",
            "channel: rms v_x / (c0/10) (zero for the exact flow)",
            "t+ = t c0 / h",
            "log10 rms v_x / (c0/10)",
            [
                ("energy walls", &energy),
                ("usaw", &plain),
                ("usaw + volume diffusion", &diffused),
            ]
            .iter()
            .map(|(n, r)| {
                (
                    n.to_string(),
                    r.t.clone(),
                    r.vx_rms.iter().map(|v| v.max(1e-16).log10()).collect(),
                )
            })
            .collect(),
        )?);
        Ok(report)
    }
}

const STILL_WATER: &str = include_str!("../../../cases/usaw-still-water.toml");

/// One still-water run: `t+`, the free-surface elevation over the middle half, the largest
/// particle speed, and when it stopped early.
struct StillRun {
    t: Vec<f64>,
    eta: Vec<f64>,
    max_speed: Vec<f64>,
    stopped: Option<String>,
}

fn still_water_run(
    dx: f64,
    width: f64,
    end_plus: f64,
    extra: &[String],
) -> Result<StillRun, String> {
    let mut overrides = vec![
        format!("resolution.dx={dx}"),
        format!("wall.0.max=[{width},1.5]"),
        format!("fluid_block.0.min=[{},{}]", 0.5 * dx, 0.5 * dx),
        format!(
            "fluid_block.0.max=[{},{}]",
            width - 0.5 * dx,
            1.0 + 0.5 * dx
        ),
        "output.plots=false".into(),
    ];
    overrides.extend(extra.iter().cloned());
    let loaded =
        parse_case("<usaw-still-water>", STILL_WATER, &overrides).map_err(|e| e.to_string())?;
    let mut sim: Simulation<DVec2> = build_simulation(&loaded).map_err(|e| e.to_string())?;
    let (c0, h) = (10.0, 1.0);
    // Free-surface elevation: the highest particle of each bin (width 2 dx) over the middle
    // half of the box, averaged over the bins.
    let level = |sim: &Simulation<DVec2>| {
        let (lo, hi) = (0.25 * width, 0.75 * width);
        let bins = ((hi - lo) / (2.0 * dx)).floor().max(1.0) as usize;
        let mut top = vec![f64::NEG_INFINITY; bins];
        for r in &sim.fluid.position {
            if r.x >= lo && r.x < hi {
                let b = (((r.x - lo) / (hi - lo)) * bins as f64) as usize;
                top[b.min(bins - 1)] = top[b.min(bins - 1)].max(r.y);
            }
        }
        top.iter().sum::<f64>() / bins as f64 / h
    };
    let samples = 200;
    let mut run = StillRun {
        t: vec![0.0],
        eta: vec![level(&sim)],
        max_speed: vec![sim.max_speed()],
        stopped: None,
    };
    for k in 1..=samples {
        let target = end_plus * h / c0 * k as f64 / samples as f64;
        let mut peak: f64 = 0.0;
        while sim.time < target - 1e-12 {
            if let Err(e) = sim.advance(Some(target)) {
                run.stopped = Some(format!("{e}"));
                break;
            }
            peak = peak.max(sim.max_speed());
        }
        if run.stopped.is_some() {
            break;
        }
        run.t.push(sim.time * c0 / h);
        run.eta.push(level(&sim));
        run.max_speed.push(peak);
    }
    Ok(run)
}

/// `usaw-still-water`: paper 3, section 7.1.
pub struct UsawStillWater;

impl ValidationCase for UsawStillWater {
    fn name(&self) -> &'static str {
        "usaw-still-water"
    }
    fn description(&self) -> &'static str {
        "paper 3, 7.1: still water (h = 1, c0 = 10) with usaw walls and volume diffusion: surface height with and without the hydrostatic correction (eq 81)"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let (dx, width) = if quick {
            (1.0 / 15.0, 1.5)
        } else {
            (1.0 / 30.0, 3.0)
        };
        let end_plus = 100.0;
        let mut report = CaseReport {
            name: self.name().into(),
            ..Default::default()
        };
        let mut series = Vec::new();
        for hydrostatic in [true, false] {
            let run = still_water_run(
                dx,
                width,
                end_plus,
                &[format!("fluid.delta_hydrostatic={hydrostatic}")],
            )?;
            let (t, eta, stopped) = (run.t, run.eta, run.stopped);
            // Settled height: mean over 20 <= t+ <= 30.
            let window: Vec<f64> = t
                .iter()
                .zip(&eta)
                .filter(|(&t, _)| (20.0..=30.0).contains(&t))
                .map(|(_, &e)| e)
                .collect();
            let settled = window.iter().sum::<f64>() / window.len().max(1) as f64;
            let dev = t
                .iter()
                .zip(&eta)
                .filter(|(&t, _)| t >= 20.0)
                .map(|(_, &e)| (e - settled).abs() / settled)
                .fold(0.0, f64::max);
            let last = eta.last().copied().unwrap_or(f64::NAN);
            let label = if hydrostatic {
                "with eq 81"
            } else {
                "without eq 81"
            };
            report.notes.push(format!(
                "{label}: initial surface {:.4}, settled (20 <= t+ <= 30) {settled:.4}, final (t+ = {:.1}) {last:.4}, max |eta - settled|/settled for t+ >= 20: {:.3}%{}",
                eta[0],
                t.last().copied().unwrap_or(0.0),
                100.0 * dev,
                stopped.as_ref().map(|s| format!("; stopped: {s}")).unwrap_or_default()
            ));
            if hydrostatic {
                report.checks.push(Check::new(
                    "with eq 81: max |eta - settled| / settled, 20 <= t c0/h <= 100",
                    dev,
                    0.01,
                    Tolerance::AtMost,
                    "paper 3, fig 8: the surface stays (issue 6 acceptance: within 1%)",
                ).known_failure(
                    "a vertical acoustic mode (period 4 h/c0) grows slowly to +-0.6% and the level drifts by -0.4% over t c0/h = 100 without viscosity (issue 7); measured 1.23% at dx = h/15",
                ));
                report.checks.push(Check::new(
                    "with eq 81: reached t c0/h = 100",
                    if stopped.is_none() { 1.0 } else { 0.0 },
                    1.0,
                    Tolerance::AtLeast,
                    "stable run",
                ));
            } else {
                report.checks.push(Check::new(
                    "without eq 81: surface rise (final - settled) / h",
                    last - settled,
                    0.0,
                    Tolerance::AtLeast,
                    "paper 3, fig 8: without the correction the surface detaches upwards",
                ));
            }
            series.push((label.to_string(), t, eta));
        }
        // Time-independent continuity (eqs 13 and 84) with eq 81.
        let run = still_water_run(dx, width, end_plus, &["usaw.continuity=summation".into()])?;
        let window: Vec<f64> = run
            .t
            .iter()
            .zip(&run.eta)
            .filter(|(&t, _)| (20.0..=30.0).contains(&t))
            .map(|(_, &e)| e)
            .collect();
        let settled = window.iter().sum::<f64>() / window.len().max(1) as f64;
        let dev = run
            .t
            .iter()
            .zip(&run.eta)
            .filter(|(&t, _)| t >= 20.0)
            .map(|(_, &e)| (e - settled).abs() / settled)
            .fold(0.0, f64::max);
        report.notes.push(format!(
            "summation density (eq 84) with eq 81: settled {settled:.4}, final (t+ = {:.1}) {:.4}, max |eta - settled|/settled for t+ >= 20: {:.3}%{}",
            run.t.last().copied().unwrap_or(0.0),
            run.eta.last().copied().unwrap_or(f64::NAN),
            100.0 * dev,
            run.stopped.as_ref().map(|s| format!("; stopped: {s}")).unwrap_or_default()
        ));
        report.checks.push(Check::new(
            "eq 84 + eq 81: max |eta - settled| / settled, 20 <= t c0/h <= 100",
            dev,
            0.01,
            Tolerance::AtMost,
            "paper 3, fig 8 (issue 6 acceptance: within 1%)",
        )
        .known_failure(
            "marginal and sensitive to the box: 0.65% in a 2 m box, 1.30% in the 1.5 m quick box (dx = h/15), from the same slowly growing acoustic mode",
        ));
        report.checks.push(Check::new(
            "summation density (eq 84) with eq 81: reached t c0/h = 100",
            if run.stopped.is_none() { 1.0 } else { 0.0 },
            1.0,
            Tolerance::AtLeast,
            "stable run",
        ));
        series.push(("eq 84 + eq 81".into(), run.t, run.eta));
        report.plots.push(plot(
            out,
            "surface.png",
            "still water: free-surface elevation (middle half)",
            "t c0 / h_swl",
            "eta / h_swl",
            series,
        )?);
        Ok(report)
    }
}

/// `usaw-tank-corner`: paper 3, section 7.2 (fig 9): still water in a closed tank at low
/// resolution, vertex pressures with the Neumann constraint of eq 82 against the
/// hydrostatic-corrected eq 83; the spurious velocities start where the free surface meets
/// the side walls.
pub struct UsawTankCorner;

impl ValidationCase for UsawTankCorner {
    fn name(&self) -> &'static str {
        "usaw-tank-corner"
    }
    fn description(&self) -> &'static str {
        "paper 3, 7.2: still water in a closed tank at low resolution, peak spurious speed with eq 82 vs eq 83"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let (dx, width, end_plus) = if quick {
            (0.1, 1.0, 30.0)
        } else {
            (0.05, 1.0, 60.0)
        };
        let mut report = CaseReport {
            name: self.name().into(),
            ..Default::default()
        };
        let mut peaks = Vec::new();
        let mut series = Vec::new();
        for (label, interpolation) in [("eq 82", "neumann"), ("eq 83", "hydrostatic")] {
            let run = still_water_run(
                dx,
                width,
                end_plus,
                &[format!("usaw.wall_interpolation={interpolation}")],
            )?;
            // Spurious speed after the start-up (t c0/h >= 5), over sqrt(g h).
            let scale = (9.81f64 * 1.0).sqrt();
            let peak = run
                .t
                .iter()
                .zip(&run.max_speed)
                .filter(|(&t, _)| t >= 5.0)
                .map(|(_, &v)| v / scale)
                .fold(0.0, f64::max);
            report.notes.push(format!(
                "{label} ({interpolation}): peak speed for t c0/h >= 5: {peak:.3e} sqrt(g h){}",
                run.stopped
                    .as_ref()
                    .map(|s| format!("; stopped: {s}"))
                    .unwrap_or_default()
            ));
            peaks.push(peak);
            series.push((
                label.to_string(),
                run.t,
                run.max_speed
                    .iter()
                    .map(|v| (v / scale).max(1e-16).log10())
                    .collect(),
            ));
        }
        report.checks.push(Check::new(
            "peak spurious speed, eq 82 / eq 83",
            peaks[0] / peaks[1],
            10.0,
            Tolerance::AtLeast,
            "paper 3, fig 9: an order of magnitude (issue 6 acceptance: tenfold)",
        )
        .known_failure(
            "both reach ~0.1 sqrt(g h) at dx = h/10: the start-up transient of the whole free surface, not only the wall corners, dominates; not yet diagnosed",
        ));
        report.plots.push(plot(
            out,
            "spurious_speed.png",
            "closed tank: largest particle speed",
            "t c0 / h",
            "log10 max |u| / sqrt(g h)",
            series,
        )?);
        Ok(report)
    }
}
