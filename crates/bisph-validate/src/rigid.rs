//! Validation cases of free rigid bodies in 2-D: a floating box settling to its Archimedes
//! draft and a box held in place.

use crate::check::{CaseReport, Check, Tolerance, ValidationCase};
use crate::support::{column, line, load, plot, read_columns, run};
use std::f64::consts::PI;
use std::path::Path;

/// The 2-D rigid-body validation cases.
pub fn cases() -> Vec<Box<dyn ValidationCase>> {
    vec![Box::new(FloatingBox), Box::new(HeldBox)]
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

/// Oscillation period from the first `first` crossings of `mid` after `t0`, upward and
/// downward (zero-crossing analysis): twice the mean interval between the first and the last
/// of them (`usize::MAX`: all crossings). NaN with fewer than three crossings.
pub(crate) fn period_about(t: &[f64], x: &[f64], mid: f64, t0: f64, first: usize) -> f64 {
    let mut crossings = Vec::new();
    for k in 1..x.len() {
        if t[k] > t0 && (x[k - 1] - mid) * (x[k] - mid) <= 0.0 && x[k] != x[k - 1] {
            crossings.push(t[k - 1] + (mid - x[k - 1]) / (x[k] - x[k - 1]) * (t[k] - t[k - 1]));
        }
    }
    crossings.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    crossings.truncate(first);
    if crossings.len() < 3 {
        return f64::NAN;
    }
    2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

/// Floating box (2-D free body) settling to its Archimedes draft.
pub struct FloatingBox;

/// Start of the window over which the settled draft is averaged [s]: the heave, damped by the
/// viscosity, is then within about 1 mm (0.5% of the draft) of its mean.
const FLOAT_SETTLED: f64 = 1.5;

/// What one run of `floating-box-2d` measures.
struct FloatRun {
    dx: f64,
    /// Settled draft: mean far-field level minus mean bottom height over the window.
    draft: f64,
    /// Heave period from the first four crossings of the settled centre height after 0.2 s
    /// (one and a half periods of the early oscillation, before the sloshing it excites
    /// and the damping blur the later crossings).
    period: f64,
    /// Standard error of `draft` from its means over 0.5 s blocks of the window (the residual
    /// heave and sloshing) [m].
    draft_sigma: f64,
    /// Averaging window `[FLOAT_SETTLED, end]`.
    end: f64,
    /// RMS of the centre height about its mean in the window [m].
    heave_rms: f64,
    /// Largest tilt over the run [deg].
    max_tilt: f64,
    /// Particles behind a wall at the end.
    behind: usize,
    /// Cross-checks: draft from the lattice volume `N dx^2`, level from the pressure probe.
    volume_draft: f64,
    pressure_level: f64,
    level: f64,
    centre: f64,
    steps: u64,
    particles: usize,
    fluid_body_drift: f64,
}

/// Case constants (cases/floating-box-2d.toml): rho0, g, box width B, tank width, height of
/// the centre of mass above the box bottom, mass, pressure-probe height.
const FLOAT_CONSTANTS: (f64, f64, f64, f64, f64, f64, f64) =
    (1000.0, 9.81, 0.6, 2.04, 0.1, 120.0, 0.3);

/// Runs `floating-box-2d` at `dx` to `end` in `out` and measures its settled draft and heave
/// period; writes `floating_box.png` there.
fn float_run(dx: f64, end: f64, out: &Path) -> Result<(FloatRun, std::path::PathBuf), String> {
    let dx_set = format!("resolution.dx={dx}");
    let end_set = format!("time.end={end}");
    let loaded = load(
        "floating-box-2d",
        include_str!("../../../cases/floating-box-2d.toml"),
        &[&dx_set, &end_set, "output.vtk_interval=0"],
    )?;
    let s = run(&loaded, out)?;
    let (h, rows) = read_columns(&out.join("body_box.csv"))?;
    let t = column(&h, &rows, "t")?;
    let y = column(&h, &rows, "y")?;
    let tilt = column(&h, &rows, "yaw")?;
    let (ph, prow) = read_columns(&out.join("probes.csv"))?;
    let tp = column(&ph, &prow, "t")?;
    let p = column(&ph, &prow, "level")?;
    let left = column(&ph, &prow, "depth_left")?;
    let right = column(&ph, &prow, "depth_right")?;
    let (rho, g, b, width, kg, mass, probe_y) = FLOAT_CONSTANTS;
    let draft_ref = mass / (rho * b);
    let end = t.last().copied().unwrap_or(0.0);
    // Free-surface level away from the box: the mean of the two water-depth columns.
    let depth: Vec<f64> = left
        .iter()
        .zip(&right)
        .map(|(l, r)| 0.5 * (l + r))
        .collect();
    let (a, w) = (FLOAT_SETTLED, end);
    let centre = mean_between(&t, &y, a, w);
    let level = mean_between(&tp, &depth, a, w);
    // The bottom lies kg below the centre of mass (cos of a tilt of a few degrees: < 0.2 mm).
    let draft = level - (centre - kg);
    // Block means over 0.5 s: the spread of the window mean.
    let blocks: Vec<f64> = (0..((w - a) / 0.5 + 1e-9).floor() as usize)
        .map(|k| {
            let (b0, b1) = (a + 0.5 * k as f64, a + 0.5 * (k + 1) as f64);
            mean_between(&tp, &depth, b0, b1) - (mean_between(&t, &y, b0, b1) - kg)
        })
        .collect();
    let n = blocks.len() as f64;
    let block_mean = blocks.iter().sum::<f64>() / n;
    let draft_sigma =
        (blocks.iter().map(|d| (d - block_mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    let pressure_level: Vec<f64> = p.iter().map(|p| probe_y + p / (rho * g)).collect();
    let pressure_level_mean = mean_between(&tp, &pressure_level, a, w);
    let volume = s.fluid_particles as f64 * dx * dx;
    let bottom = centre - kg;
    let volume_draft = (volume - width * bottom) / (width - b);
    let heave_rms = mean_between(
        &t,
        &y.iter().map(|y| (y - centre).powi(2)).collect::<Vec<_>>(),
        a,
        w,
    )
    .sqrt();
    let plot = plot(
        out,
        "floating_box.png",
        &format!("Floating box, dx = {dx:.4}: centre height and far-field level"),
        "t [s]",
        "y [m]",
        vec![
            line("box centre of mass", t.clone(), y.clone()),
            line("level (height probes)", tp.clone(), depth),
            line("level (pressure probe)", tp.clone(), pressure_level),
            line(
                "Archimedes centre (settled level)",
                vec![0.0, end],
                vec![level - draft_ref + kg; 2],
            ),
        ],
    )?;
    Ok((
        FloatRun {
            dx,
            draft,
            draft_sigma,
            period: period_about(&t, &y, centre, 0.2, 4),
            end,
            heave_rms,
            max_tilt: tilt.iter().fold(0.0f64, |m, r| m.max(r.abs())),
            behind: s.particles_behind_walls,
            volume_draft,
            pressure_level: pressure_level_mean,
            level,
            centre,
            steps: s.steps,
            particles: s.fluid_particles,
            fluid_body_drift: s.fluid_body_energy_drift_max_relative.unwrap_or(f64::NAN),
        },
        plot,
    ))
}

/// Heave period of the box in the closed tank from linear potential flow [s]: the coupled
/// heave mode of the box (mass m, hydrostatic stiffness rho0 g B) and the free surface, with
/// the water's kinetic energy from the Laplace equation (the box bottom 0.2 m under the
/// surface 0.65 m, tank 2.04 m wide). Finite volumes of 0.04 x 0.05 m, halved and quartered,
/// give 1.317, 1.329 and 1.335 s, extrapolated 1.343 s (`docs/floating_box_linear.py`). The
/// added mass of a half-immersed circle of diameter B in unbounded water gives 1.324 s.
const FLOAT_LINEAR_PERIOD: f64 = 1.343;

/// End of the inviscid heave run [s]: four crossings of the equilibrium (1.5 periods).
const FLOAT_HEAVE_END: f64 = 2.5;

/// The inviscid run of `floating-box-2d` at `dx` (to [`FLOAT_HEAVE_END`]): the early heave
/// period about the settled centre height `centre` of the damped run, and the particles
/// behind a wall at the end. The viscosity of the damped run (nu = 0.05 m^2/s, Stokes layer
/// sqrt(2 nu / omega) = 0.15 m, as thick as the gaps) lengthens its period by 4-10%.
fn heave_run(dx: f64, centre: f64, out: &Path) -> Result<(f64, usize), String> {
    let dx_set = format!("resolution.dx={dx}");
    let end_set = format!("time.end={FLOAT_HEAVE_END}");
    let loaded = load(
        "floating-box-2d",
        include_str!("../../../cases/floating-box-2d.toml"),
        &[
            &dx_set,
            &end_set,
            "output.vtk_interval=0",
            "fluid.viscosity=0",
        ],
    )?;
    let s = run(&loaded, out)?;
    let (h, rows) = read_columns(&out.join("body_box.csv"))?;
    let t = column(&h, &rows, "t")?;
    let y = column(&h, &rows, "y")?;
    Ok((
        period_about(&t, &y, centre, 0.2, 4),
        s.particles_behind_walls,
    ))
}

impl ValidationCase for FloatingBox {
    fn name(&self) -> &'static str {
        "floating-box-2d"
    }
    fn description(&self) -> &'static str {
        "free rigid body: a box released 4 cm above its equilibrium settles to the Archimedes draft (free surface from height probes, mean over t >= 1.5 s), closer at the finer dx; inviscid heave period against linear potential flow"
    }
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String> {
        // Quick: dx = 0.04 to 3 s; full: dx = 0.04 and 0.02 to 4 s (the same window).
        let (dxs, end): (&[f64], f64) = if quick {
            (&[0.04], 3.0)
        } else {
            (&[0.04, 0.02], 4.0)
        };
        let (rho, g, b, _, _, mass, _) = FLOAT_CONSTANTS;
        let draft_ref = mass / (rho * b);
        let t0 = 2.0 * PI * (draft_ref / g).sqrt();
        // Added mass of a half-immersed circle of diameter B: rho pi B^2 / 8.
        let added = rho * PI * b * b / 8.0;
        let t_added = t0 * (1.0 + added / mass).sqrt();
        let mut runs = Vec::new();
        let mut plots = Vec::new();
        for &dx in dxs {
            let dir = if quick {
                out.to_path_buf()
            } else {
                out.join(format!("dx{dx}"))
            };
            let (r, p) = float_run(dx, end, &dir)?;
            let heave = heave_run(dx, r.centre, &dir.join("inviscid"))?;
            runs.push((r, heave));
            plots.push(p);
        }
        let mut checks = Vec::new();
        let mut notes = Vec::new();
        for (r, (period, behind)) in &runs {
            checks.push(Check::new(
                &format!("dx = {}: settled draft [m]", r.dx),
                r.draft,
                draft_ref,
                Tolerance::Relative(0.05),
                "Archimedes d = m / (rho0 B); 5% at the quick resolution",
            ));
            checks.push(Check::new(
                &format!("dx = {}: inviscid heave period [s]", r.dx),
                *period,
                FLOAT_LINEAR_PERIOD,
                Tolerance::Relative(0.05),
                "linear potential flow, box and free surface in the closed tank (docs/floating_box_linear.py)",
            ));
            checks.push(Check::new(
                &format!("dx = {}: particles inside the box at the end", r.dx),
                r.behind.max(*behind) as f64,
                0.0,
                Tolerance::AtMost,
                "no particle crosses a wall",
            ));
            notes.push(format!(
                "dx = {}: draft {:.4} m +- {:.4} (standard error of the window mean) ({:+.2}% against Archimedes {draft_ref:.4}): far-field level {:.4} m from the height probes, mean centre of mass {:.4} m over t in [{FLOAT_SETTLED}, {:.2}] s; cross-checks: the lattice volume N dx^2 gives the draft {:.4} m, the pressure probe the level {:.4} m; heave RMS about the mean in the window {:.2} mm; heave period {:.4} s with the viscosity, {period:.4} s inviscid (linear potential flow {FLOAT_LINEAR_PERIOD}; T0 = {t0:.4} without added mass, {t_added:.4} with that of a half-immersed circle); largest tilt {:.2} deg; fluid + body energy drift {:.2e} (max); {} particles, {} steps.",
                r.dx,
                r.draft,
                r.draft_sigma,
                100.0 * (r.draft / draft_ref - 1.0),
                r.level,
                r.centre,
                r.end,
                r.volume_draft,
                r.pressure_level,
                1e3 * r.heave_rms,
                r.period,
                r.max_tilt,
                r.fluid_body_drift,
                r.particles,
                r.steps,
            ));
        }
        if let [(coarse, (coarse_period, _)), (fine, (fine_period, _))] = &runs[..] {
            // Closer at the finer dx, to within the sampling error of the two window means
            // (block means over 0.5 s; both errors can be below it).
            checks.push(Check::new(
                &format!(
                    "|draft error| at dx = {} minus at dx = {} [m]",
                    fine.dx, coarse.dx
                ),
                (fine.draft - draft_ref).abs() - (coarse.draft - draft_ref).abs(),
                2.0 * fine.draft_sigma.hypot(coarse.draft_sigma),
                Tolerance::AtMost,
                "closer to Archimedes at the finer resolution (bound: twice the standard error of the difference of the window means)",
            ));
            checks.push(Check::new(
                &format!(
                    "inviscid heave period at dx = {} / at dx = {}",
                    fine.dx, coarse.dx
                ),
                fine_period / coarse_period,
                1.0,
                Tolerance::Relative(0.05),
                "inviscid; the period is resolved at the quick dx already",
            ));
        }
        Ok(CaseReport {
            name: self.name().into(),
            checks,
            plots,
            notes,
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
                    "Archimedes; slow sloshing modes move the 0.9 s mean by a few %",
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
