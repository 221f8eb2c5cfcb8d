//! Validation cases of free rigid bodies and 3-D walls from meshes: a floating box settling
//! to its Archimedes draft, SPHERIC test 2 (paper 2, 3.2) and the Apollo capsule water
//! landing (paper 1, 5.4).

use crate::paper1_cases::{column, line, load, plot, read_columns, run};
use crate::validate::{CaseReport, Check, Tolerance, ValidationCase};
use std::f64::consts::PI;
use std::path::Path;

/// The rigid-body and mesh-wall validation cases.
pub fn cases() -> Vec<Box<dyn ValidationCase>> {
    vec![
        Box::new(FloatingBox),
        Box::new(HeldBox),
        Box::new(crate::spheric2::SphericTest2),
        Box::new(Apollo),
    ]
}

/// Mean of `y` where `t` lies in `[a, b]`.
pub(crate) fn mean_between(t: &[f64], y: &[f64], a: f64, b: f64) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for (&t, &y) in t.iter().zip(y) {
        if t >= a && t <= b {
            s += y;
            n += 1;
        }
    }
    s / n as f64
}

/// Oscillation period from the crossings of `mid` after `t0`, upward and downward (zero-crossing
/// analysis): twice the mean interval between the first and the last crossing. NaN with
/// fewer than three crossings.
pub(crate) fn period_about(t: &[f64], x: &[f64], mid: f64, t0: f64) -> f64 {
    let mut crossings = Vec::new();
    for k in 1..x.len() {
        if t[k] > t0 && (x[k - 1] - mid) * (x[k] - mid) <= 0.0 && x[k] != x[k - 1] {
            crossings.push(t[k - 1] + (mid - x[k - 1]) / (x[k] - x[k - 1]) * (t[k] - t[k - 1]));
        }
    }
    crossings.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    if crossings.len() < 3 {
        return f64::NAN;
    }
    2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

/// The window `[a, b]` between the first and the last upward crossing of `mid` after `t0`
/// (a whole number of oscillation periods), or `[t0, end]` with fewer than two crossings.
pub(crate) fn whole_periods(t: &[f64], x: &[f64], mid: f64, t0: f64) -> (f64, f64) {
    let ups: Vec<f64> = (1..x.len())
        .filter(|&k| t[k] > t0 && x[k - 1] < mid && x[k] >= mid)
        .map(|k| t[k - 1] + (mid - x[k - 1]) / (x[k] - x[k - 1]) * (t[k] - t[k - 1]))
        .collect();
    match (ups.first(), ups.last()) {
        (Some(&a), Some(&b)) if b > a => (a, b),
        _ => (t0, t.last().copied().unwrap_or(t0)),
    }
}

/// Floating box (2-D free body) settling to its Archimedes draft.
pub struct FloatingBox;

impl ValidationCase for FloatingBox {
    fn name(&self) -> &'static str {
        "floating-box-2d"
    }
    fn description(&self) -> &'static str {
        "free rigid body: a box released at half its draft settles to the Archimedes draft (free surface from height probes); heave period between the linear estimates without and with added mass"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let settings: &[&str] = if quick {
            &[
                "resolution.dx=0.04",
                "time.end=3.0",
                "output.vtk_interval=0",
            ]
        } else {
            &["resolution.dx=0.02"]
        };
        let loaded = load(
            "floating-box-2d",
            include_str!("../../../cases/floating-box-2d.toml"),
            settings,
        )?;
        let s = run(&loaded, out)?;
        let (h, rows) = read_columns(&out.join("body_box.csv"))?;
        let t = column(&h, &rows, "t")?;
        let y = column(&h, &rows, "y")?;
        let roll = column(&h, &rows, "yaw")?;
        let (ph, prow) = read_columns(&out.join("probes.csv"))?;
        let tp = column(&ph, &prow, "t")?;
        let p = column(&ph, &prow, "level")?;
        let left = column(&ph, &prow, "depth_left")?;
        let right = column(&ph, &prow, "depth_right")?;
        // Case constants (cases/floating-box-2d.toml).
        let (rho, g, b, width, half_height, mass, probe_y) =
            (1000.0, 9.81, 0.6, 2.0, 0.2, 120.0, 0.3);
        let draft_ref = mass / (rho * b);
        let end = t.last().copied().unwrap_or(0.0);
        let settle = 0.6;
        // Free-surface level away from the box: the mean of the two water-depth columns.
        let depth: Vec<f64> = left
            .iter()
            .zip(&right)
            .map(|(l, r)| 0.5 * (l + r))
            .collect();
        // Means over whole heave periods after the settling time.
        let rough_centre = mean_between(&t, &y, settle, end);
        let (a, w) = whole_periods(&t, &y, rough_centre, settle);
        let centre_mean = mean_between(&t, &y, a, w);
        let level_mean = mean_between(&tp, &depth, a, w);
        let draft = level_mean - (centre_mean - half_height);
        // Cross-checks: the level the pressure probe implies (y + p / (rho0 g)), and the level
        // that keeps the lattice volume N dx^2 of the water with the box at its mean height.
        let pressure_level: Vec<f64> = p.iter().map(|p| probe_y + p / (rho * g)).collect();
        let pressure_level_mean = mean_between(&tp, &pressure_level, a, w);
        let dx = loaded.case.resolution.dx;
        let volume = s.fluid_particles as f64 * dx * dx;
        let bottom = centre_mean - half_height;
        let volume_draft = (volume - width * bottom) / (width - b);
        let period = period_about(&t, &y, centre_mean, 0.2);
        let t0 = 2.0 * PI * (draft_ref / g).sqrt();
        // Added mass of a half-immersed circle of diameter B: rho pi B^2 / 8.
        let added = rho * PI * b * b / 8.0;
        let t_added = t0 * (1.0 + added / mass).sqrt();
        let exchange = (s.energy_drift_max_relative
            - s.fluid_body_energy_drift_max_relative.unwrap_or(f64::NAN))
        .abs();
        let plots = vec![plot(
            out,
            "floating_box.png",
            "Floating box: centre height and far-field level",
            "t [s]",
            "y [m]",
            vec![
                line("box centre", t.clone(), y.clone()),
                line("level (height probes)", tp.clone(), depth),
                line("level (pressure probe)", tp.clone(), pressure_level),
                line(
                    "Archimedes centre",
                    vec![0.0, end],
                    vec![level_mean - draft_ref + half_height; 2],
                ),
            ],
        )?];
        let max_roll = roll.iter().fold(0.0f64, |a, r| a.max(r.abs()));
        // How far the heave is from settled: the RMS of the centre about its mean in the window.
        let heave_rms = (mean_between(
            &t,
            &y.iter()
                .map(|y| (y - centre_mean).powi(2))
                .collect::<Vec<_>>(),
            a,
            w,
        ))
        .sqrt();
        Ok(CaseReport {
            name: self.name().into(),
            checks: vec![
                Check::new(
                    "equilibrium draft [m]",
                    draft,
                    draft_ref,
                    Tolerance::Relative(0.05),
                    "Archimedes d = m / (rho0 B); issue 8: 5% at the quick resolution",
                ),
                Check::new(
                    "heave period / no-added-mass period",
                    period / t0,
                    1.0,
                    Tolerance::AtLeast,
                    "T0 = 2 pi sqrt(d/g): the added mass lengthens the period",
                ),
                Check::new(
                    "heave period / period with added mass rho pi B^2/8",
                    period / t_added,
                    1.1,
                    Tolerance::AtMost,
                    "linear heave with the added mass of a half-immersed circle of diameter B",
                ),
                Check::new(
                    "particles inside the box at the end",
                    s.particles_behind_walls as f64,
                    0.0,
                    Tolerance::AtMost,
                    "no particle crosses a wall",
                ),
            ],
            plots,
            notes: vec![format!(
                "draft {draft:.4} m (Archimedes {draft_ref:.4}): far-field level {level_mean:.4} m from the height probes, mean centre {centre_mean:.4} m over t in [{a:.2}, {w:.2}] s (whole heave periods); cross-checks: the lattice volume N dx^2 gives the draft {volume_draft:.4} m, the pressure probe the level {pressure_level_mean:.4} m; heave RMS about the mean {heave_rms:.4} m; heave period {period:.4} s (T0 = {t0:.4}, with added mass {t_added:.4}); largest tilt {max_roll:.3} deg; energy drift (fluid + wall work) {:.3e}, fluid + body energy drift {:.3e} (max), difference {exchange:.2e}; {} particles, {} steps, {:.2} iterations per step.",
                s.energy_drift_max_relative,
                s.fluid_body_energy_drift_max_relative.unwrap_or(f64::NAN),
                s.fluid_particles,
                s.steps,
                s.iterations_mean,
            )],
            wall_seconds: 0.0,
        })
    }
}

/// The floating box held at its Archimedes draft: the time-mean fluid force against
/// `rho0 g B d` (the hydrostatic error of the wall model, without the free case's dynamics).
pub struct HeldBox;

impl ValidationCase for HeldBox {
    fn name(&self) -> &'static str {
        "floating-box-held-2d"
    }
    fn description(&self) -> &'static str {
        "the floating box held at its Archimedes draft: time-mean fluid lift against rho0 g B d, and the far-field pressure level against the free surface"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        let settings: &[&str] = if quick { &["resolution.dx=0.04"] } else { &[] };
        let loaded = load(
            "floating-box-held-2d",
            include_str!("../../../cases/floating-box-held-2d.toml"),
            settings,
        )?;
        let s = run(&loaded, out)?;
        let (h, rows) = read_columns(&out.join("body_box.csv"))?;
        let t = column(&h, &rows, "t")?;
        let fy = column(&h, &rows, "fy")?;
        let (ph, prow) = read_columns(&out.join("probes.csv"))?;
        let tp = column(&ph, &prow, "t")?;
        let p = column(&ph, &prow, "far_pressure")?;
        let left = column(&ph, &prow, "depth_left")?;
        let right = column(&ph, &prow, "depth_right")?;
        // Case constants (cases/floating-box-held-2d.toml).
        let (rho, g, b, bottom, surface) = (1000.0, 9.81, 0.6, 0.44, 0.64);
        let lift_ref = rho * g * b * (surface - bottom);
        let end = t.last().copied().unwrap_or(0.0);
        // The first acoustic periods (about 4 x depth / c0 = 0.17 s) are left out.
        let start = 0.3;
        let lift = mean_between(&t, &fy, start, end);
        let depth: Vec<f64> = left
            .iter()
            .zip(&right)
            .map(|(l, r)| 0.5 * (l + r))
            .collect();
        let level = mean_between(&tp, &depth, start, end);
        let pressure_level: Vec<f64> = p.iter().map(|p| bottom + p / (rho * g)).collect();
        let p_level = mean_between(&tp, &pressure_level, start, end);
        let dx = loaded.case.resolution.dx;
        let tolerance = if quick { 0.1 } else { 0.05 };
        let plots = vec![plot(
            out,
            "held_box_lift.png",
            "Held box: fluid lift against rho0 g B d",
            "t [s]",
            "F_y [N/m]",
            vec![
                line("fluid force", t.clone(), fy.clone()),
                line("rho0 g B d", vec![0.0, end], vec![lift_ref; 2]),
            ],
        )?];
        Ok(CaseReport {
            name: self.name().into(),
            checks: vec![
                Check::new(
                    "time-mean lift / (rho0 g B d)",
                    lift / lift_ref,
                    1.0,
                    Tolerance::Relative(tolerance),
                    "Archimedes; slow sloshing modes move the 0.9 s mean by a few % (README)",
                ),
                Check::new(
                    "particles inside the box at the end",
                    s.particles_behind_walls as f64,
                    0.0,
                    Tolerance::AtMost,
                    "no particle crosses a wall",
                ),
            ],
            plots,
            notes: vec![format!(
                "dx = {dx}: mean lift {lift:.1} N/m over t in [{start}, {end:.2}] s (rho0 g B d = {lift_ref:.1}, {:+.2}%); free surface from the height probes {level:.4} m (set {surface}); far-field pressure level y + p/(rho0 g) at the box-bottom depth {p_level:.4} m, {:+.3} dx from the surface; {} particles, {} steps.",
                100.0 * (lift / lift_ref - 1.0),
                (p_level - level) / dx,
                s.fluid_particles,
                s.steps,
            )],
            wall_seconds: 0.0,
        })
    }
}

/// Apollo capsule water landing (paper 1, 5.4).
pub struct Apollo;

impl ValidationCase for Apollo {
    fn name(&self) -> &'static str {
        "apollo"
    }
    fn description(&self) -> &'static str {
        "paper 1, 5.4: Apollo capsule water landing, free 6-DOF body; no particle inside, fluid + body energy drift with the body inside the iterations vs staggered"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        crate::apollo::run_apollo(self.name(), quick, out)
    }
    fn in_quick_suite(&self) -> bool {
        false
    }
}
