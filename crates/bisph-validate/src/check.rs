//! A validation case and what it reports: checks of measured quantities against a reference
//! with a tolerance.

use std::path::{Path, PathBuf};

/// How a value is compared with its reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// `|value - reference| <= tol`.
    Absolute(f64),
    /// `|value - reference| <= tol * |reference|`.
    Relative(f64),
    /// `value <= reference` (the reference is an upper bound).
    AtMost,
    /// `value >= reference` (the reference is a lower bound).
    AtLeast,
}

/// One measured quantity against its reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// What is measured.
    pub quantity: String,
    /// The measured value.
    pub value: f64,
    /// The reference (analytic, paper or experiment value, or a bound).
    pub reference: f64,
    /// How they are compared.
    pub tolerance: Tolerance,
    /// Where the reference comes from.
    pub source: String,
    /// Why this check is known to fail (a stated limitation): reported as `xfail`, not counted
    /// as a failure; `None` for a normal check.
    pub known_failure_reason: Option<String>,
}

impl Check {
    /// A check of `value` against `reference` with `tolerance`.
    pub fn new(
        quantity: &str,
        value: f64,
        reference: f64,
        tolerance: Tolerance,
        source: &str,
    ) -> Self {
        Check {
            quantity: quantity.into(),
            value,
            reference,
            tolerance,
            source: source.into(),
            known_failure_reason: None,
        }
    }

    /// Marks the check as a known failure, with the reason (shown in the report).
    pub fn known_failure(mut self, why: &str) -> Self {
        self.known_failure_reason = Some(why.into());
        self
    }

    /// Verdict for the table: `yes`, `NO`, `xfail` (known failure) or `xpass`.
    pub fn verdict(&self) -> &'static str {
        match (self.passed(), self.known_failure_reason.is_some()) {
            (true, false) => "yes",
            (false, false) => "NO",
            (false, true) => "xfail",
            (true, true) => "xpass",
        }
    }

    /// `true` when the check counts as a failure of the run.
    pub fn fails(&self) -> bool {
        !self.passed() && self.known_failure_reason.is_none()
    }

    /// `true` when the value is within tolerance (a NaN never passes).
    pub fn passed(&self) -> bool {
        let (v, r) = (self.value, self.reference);
        if !v.is_finite() {
            return false;
        }
        match self.tolerance {
            Tolerance::Absolute(t) => (v - r).abs() <= t,
            Tolerance::Relative(t) => (v - r).abs() <= t * r.abs(),
            Tolerance::AtMost => v <= r,
            Tolerance::AtLeast => v >= r,
        }
    }

    /// The tolerance as printed in the table and the report.
    pub fn tolerance_text(&self) -> String {
        match self.tolerance {
            Tolerance::Absolute(t) => format!("± {t:.3e}"),
            Tolerance::Relative(t) => format!("± {:.3}%", 100.0 * t),
            Tolerance::AtMost => "at most".into(),
            Tolerance::AtLeast => "at least".into(),
        }
    }
}

/// What one case produced.
#[derive(Debug, Clone, Default)]
pub struct CaseReport {
    /// Case name.
    pub name: String,
    /// Its checks.
    pub checks: Vec<Check>,
    /// Plots written (paths relative to the report directory are best).
    pub plots: Vec<PathBuf>,
    /// Free text: figures worth reading beside the checks.
    pub notes: Vec<String>,
    /// Wall-clock seconds the case took.
    pub wall_seconds: f64,
}

/// A validation case.
pub trait ValidationCase: Sync {
    /// Name used on the command line.
    fn name(&self) -> &'static str;
    /// One line saying what it checks.
    fn description(&self) -> &'static str;
    /// Finds and reads the experiment data the case compares with, so that missing or
    /// unreadable data are reported before any simulation starts (none by default).
    fn check_data(&self) -> Result<(), String> {
        Ok(())
    }
    /// Runs the case (quick or full resolution) writing its outputs under `out`.
    fn run(&self, quick: bool, out: &Path) -> Result<CaseReport, String>;
    /// `false` for cases too expensive for `--quick` runs of the whole registry (CI): they run
    /// at full resolution, or at their quick resolution only when named explicitly.
    fn in_quick_suite(&self) -> bool {
        true
    }
}
