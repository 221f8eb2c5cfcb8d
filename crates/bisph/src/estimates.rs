//! Run-time estimates of the validation cases, printed by `bisph validate --list`.
//!
//! Where the figures come from: the quick column is the wall-clock time of each case in
//! `bisph validate --quick` on a 2-vCPU machine (AMD EPYC KVM guest, release build, 2 threads),
//! as its `report.md` gives it (`apollo`, which `--quick` skips, run by name). In the full
//! column, cases that take minutes at most were run at full resolution on the same machine
//! (`Measured`); the others are scaled from their quick time by the cost of the full
//! resolutions (`Scaled`: particles times steps, about `(dx_quick / dx_full)^(d + 1)` per run,
//! times the longer end times and the extra runs; see the comment of each). The machine was
//! shared with compilations at the time, so the figures may be high by some tens of per cent.
//! They are meant for planning (seconds, minutes or hours); more cores shorten them. Update a
//! figure when a case changes its resolutions or end times.

/// A run time in seconds, measured or scaled.
#[derive(Clone, Copy, Debug)]
pub enum Figure {
    /// Measured.
    Measured(f64),
    /// Scaled from the quick run; not measured.
    Scaled(f64),
}

impl std::fmt::Display for Figure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (prefix, seconds) = match *self {
            Figure::Measured(s) => ("", s),
            Figure::Scaled(s) => ("~", s),
        };
        let text = if seconds < 1.0 {
            "<1 s".to_string()
        } else if seconds < 90.0 {
            format!("{seconds:.0} s")
        } else if seconds < 5400.0 {
            format!("{:.0} min", seconds / 60.0)
        } else {
            format!("{:.0} h", seconds / 3600.0)
        };
        f.pad(&format!("{prefix}{text}"))
    }
}

/// Quick and full run times of one validation case.
#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    /// The case's name in the registry.
    pub name: &'static str,
    /// `bisph validate --quick NAME`.
    pub quick: Figure,
    /// `bisph validate NAME`.
    pub full: Figure,
}

use Figure::{Measured, Scaled};

const fn e(name: &'static str, quick: Figure, full: Figure) -> Estimate {
    Estimate { name, quick, full }
}

/// Every validation case, in the registry's order.
pub const ESTIMATES: &[Estimate] = &[
    // dx 0.02 -> 0.0025: 8^3.
    e("jet-impact", Measured(1.6), Scaled(1.6 * 512.0)),
    // 25 and 64 per side -> 25, 50 and 100: (25^3 + 50^3 + 100^3) / (25^3 + 64^3).
    e("adiabatic-piston", Measured(110.0), Scaled(110.0 * 4.1)),
    // H/30 -> H/50 and H/100, and three variants at H/50: (5/3)^3 * 4 + (10/3)^3.
    e("lobovsky-dam-break", Measured(68.0), Scaled(68.0 * 55.5)),
    e("shepard-gamma-2d", Measured(0.2), Measured(0.4)),
    e("shepard-corner-2d", Measured(0.0), Measured(0.0)),
    // 2 190 particles -> 10k, 50k and 100k: sum of (N / 2190)^(3/2).
    e("hydrostatic-shepard", Measured(10.0), Scaled(10.0 * 423.0)),
    e("usaw-gamma", Measured(0.0), Measured(0.2)),
    // dx h/20 -> h/50, t+ 12 -> 30: 2.5^3 * 2.5.
    e("usaw-channel", Measured(3.5), Scaled(3.5 * 39.0)),
    // dx h/15 -> h/30 and twice the period: 2^3 * 2.
    e("usaw-still-water", Measured(9.6), Scaled(9.6 * 16.0)),
    // dx h/10 -> h/20, t c0/h 30 -> 120: 2^3 * 4.
    e("usaw-tank-corner", Measured(15.8), Scaled(15.8 * 32.0)),
    e("usaw-wedge", Measured(5.5), Measured(22.2)),
    e("poiseuille-flux", Measured(2.8), Measured(18.0)),
    e("robin-wave", Measured(3.6), Measured(1.9)),
    e("pack-trapezoid-2d", Measured(1.0), Measured(3.1)),
    e("pack-trapezoid-2d-h1.5", Measured(1.1), Measured(4.2)),
    e("pack-bunny-2d", Measured(2.6), Measured(9.1)),
    e("pack-naca6412-2d", Measured(12.2), Measured(12.2)),
    e("pack-sphere-3d", Measured(6.5), Measured(30.6)),
    e("pack-torus-3d", Measured(12.6), Measured(128.0)),
    // dx 0.04 to 3 s -> 0.04 and 0.02 to 4 s: (1 + 2^3) * 4/3.
    e("floating-box-2d", Measured(16.2), Scaled(16.2 * 12.0)),
    e("floating-box-held-2d", Measured(3.6), Measured(13.9)),
    // dx 0.55/45 (364,500 particles, 80,200 elements) to 6 s: about 49,100 steps on 2
    // threads at 0.425 s per step over 236 steps from t = 1.32 s (docs/performance.md),
    // taken for the rest.
    e("spheric-test2", Measured(17.6), Scaled(0.425 * 49_100.0)),
    // The paper's setting, one run (500,000 particles) to 0.22 s: 2,750 steps, 3,538 s on 2
    // threads for the whole validation (docs/validation-report/full/report.md).
    e("apollo", Measured(75.7), Measured(3_538.0)),
    // Four tanks: 2-D dx 0.025 -> 0.0125, end 5 s -> 20 s (2^3 * 4); 3-D box dx 0.05 ->
    // 0.025, end 5 s -> 10 s (2^4 * 2); SPHERIC tank dx 0.11 -> 0.055, end 2 s -> 10 s with
    // settling uncapped (more): about 32x the quick time. Settling (up to 200 / beta) takes
    // most of it.
    e("still-water", Measured(690.0), Scaled(690.0 * 32.0)),
];

/// The estimate of the case `name`, if the table has one.
pub fn estimate(name: &str) -> Option<&'static Estimate> {
    ESTIMATES.iter().find(|e| e.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every case of the registry has an estimate, and every estimate a case.
    #[test]
    fn every_validation_case_has_an_estimate() {
        let cases = bisph_validate::registry();
        for c in &cases {
            assert!(estimate(c.name()).is_some(), "no estimate for {}", c.name());
        }
        for e in ESTIMATES {
            assert!(
                cases.iter().any(|c| c.name() == e.name),
                "estimate for {}, which is no validation case",
                e.name
            );
        }
    }

    #[test]
    fn figures_read_in_seconds_minutes_or_hours() {
        assert_eq!(Measured(0.2).to_string(), "<1 s");
        assert_eq!(Measured(42.6).to_string(), "43 s");
        assert_eq!(Scaled(450.0).to_string(), "~8 min");
        assert_eq!(Scaled(4230.0).to_string(), "~70 min");
        assert_eq!(Scaled(340_000.0).to_string(), "~94 h");
    }
}
