//! What the validation cases share: loading an embedded case file, running it, reading the
//! CSV columns a run wrote, and line plots.

use bisph_io::case::{parse_case, LoadedCase};
use bisph_io::formats::plot::{write_png, Plot, Series, Style};
use bisph_io::run::runner::{resume_case, run_case_with, Summary};
use bisph_io::run::{checkpoint, RunOptions};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// A case file shipped in `cases/`, embedded so `bisph validate` runs from anywhere.
pub fn load(name: &str, text: &str, overrides: &[&str]) -> Result<LoadedCase, String> {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    parse_case(&format!("cases/{name}.toml"), text, &overrides).map_err(|e| e.to_string())
}

/// The flag that stops this process's runs at their next step (set by a signal handler).
static STOP: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Stops every run of the validation cases at its next step once `flag` is set: a
/// resumable run ([`run_resumable`]) then writes a checkpoint to continue from.
pub fn stop_runs_when(flag: Arc<AtomicBool>) {
    // A flag set before stays: the first handler installed is the one that signals.
    let _ = STOP.set(flag);
}

/// The flag of [`stop_runs_when`], for the options of a run.
pub(crate) fn stop_flag() -> Option<&'static AtomicBool> {
    STOP.get().map(|flag| flag.as_ref())
}

/// Whether the runs have been asked to stop ([`stop_runs_when`]).
pub(crate) fn stopping() -> bool {
    stop_flag().is_some_and(|flag| flag.load(Ordering::SeqCst))
}

/// Runs a loaded case to its end, writing its outputs under `out`.
pub fn run(loaded: &LoadedCase, out: &Path) -> Result<Summary, String> {
    let options = RunOptions {
        stop: stop_flag(),
        ..Default::default()
    };
    run_case_with(loaded, out, &options, &mut |_| {}).map_err(|e| e.to_string())
}

/// A fingerprint of the running program (its executable's bytes), so that what one build
/// saved is never mixed with another's.
pub fn build_fingerprint() -> Result<String, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot locate the program: {e}"))?;
    let bytes = std::fs::read(&exe).map_err(|e| format!("cannot read {}: {e}", exe.display()))?;
    Ok(format!("{:016x}", checkpoint::fnv1a64(&bytes)))
}

/// The file naming the build that wrote a resumable run's folder.
pub const BUILD_FILE: &str = "build.txt";

/// Whether build `build` wrote the folder `dir` (its [`BUILD_FILE`]).
pub fn written_by(dir: &Path, build: &str) -> bool {
    std::fs::read_to_string(dir.join(BUILD_FILE)).is_ok_and(|b| b == build)
}

/// Whether `dir`, or a folder in it, holds a checkpoint that a resumable run of the
/// validation continues from when this build runs the same case there again.
pub fn holds_resumable_run(dir: &Path) -> bool {
    build_fingerprint().is_ok_and(|build| holds_run_of(dir, &build))
}

fn holds_run_of(dir: &Path, build: &str) -> bool {
    (written_by(dir, build) && dir.join(checkpoint::FILE_NAME).exists())
        || std::fs::read_dir(dir).is_ok_and(|entries| {
            entries
                .flatten()
                .any(|e| e.path().is_dir() && holds_run_of(&e.path(), build))
        })
}

/// Minutes of wall clock between two checkpoints of a resumable run.
const CHECKPOINT_MINUTES: f64 = 10.0;

/// Runs a loaded case to its end under `out`, saving a checkpoint every
/// [`CHECKPOINT_MINUTES`] and when stopped ([`stop_runs_when`]): a run stopped part-way
/// (stopped, killed, or the machine gone) continues from its last checkpoint when the same
/// build runs the same case into `out` again, with the figures of an uninterrupted run.
/// Anything else in `out` is cleared first.
pub fn run_resumable(loaded: &LoadedCase, out: &Path) -> Result<Summary, String> {
    let build = build_fingerprint()?;
    let resume = written_by(out, &build)
        && out.join(checkpoint::FILE_NAME).exists()
        && resume_case(out).is_ok_and(|saved| saved.text == loaded.text);
    if !resume {
        if out.exists() {
            std::fs::remove_dir_all(out)
                .map_err(|e| format!("cannot clear {}: {e}", out.display()))?;
        }
        std::fs::create_dir_all(out)
            .map_err(|e| format!("cannot create {}: {e}", out.display()))?;
        std::fs::write(out.join(BUILD_FILE), &build)
            .map_err(|e| format!("cannot write {}: {e}", out.join(BUILD_FILE).display()))?;
    }
    let options = RunOptions {
        checkpoint_minutes: Some(CHECKPOINT_MINUTES),
        stop: stop_flag(),
        resume,
        ..Default::default()
    };
    run_case_with(loaded, out, &options, &mut |_| {}).map_err(|e| e.to_string())
}

/// Columns of a CSV file written by a run, by header name.
pub fn read_columns(path: &Path) -> Result<(Vec<String>, Vec<Vec<String>>), String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    Ok((header, rows))
}

/// A numeric column by name.
pub fn column(header: &[String], rows: &[Vec<String>], name: &str) -> Result<Vec<f64>, String> {
    let k = header
        .iter()
        .position(|h| h == name)
        .ok_or_else(|| format!("no column `{name}`"))?;
    Ok(rows
        .iter()
        .filter_map(|r| r.get(k))
        .filter_map(|v| v.parse().ok())
        .collect())
}

/// A text column by name.
pub fn column_text(
    header: &[String],
    rows: &[Vec<String>],
    name: &str,
) -> Result<Vec<String>, String> {
    let k = header
        .iter()
        .position(|h| h == name)
        .ok_or_else(|| format!("no column `{name}`"))?;
    Ok(rows.iter().filter_map(|r| r.get(k).cloned()).collect())
}

/// A line plot of `series` written to `out/file` (1000 x 600 pixels); returns its path.
pub fn plot(
    out: &Path,
    file: &str,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: Vec<(Series, Style)>,
) -> Result<std::path::PathBuf, String> {
    let path = out.join(file);
    let plot = Plot {
        title: title.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        series,
    };
    write_png(&plot, &path, 1000, 600).map_err(|e| e.0)?;
    Ok(path)
}

/// One line of a plot.
pub fn line(label: &str, x: Vec<f64>, y: Vec<f64>) -> (Series, Style) {
    (
        Series {
            label: label.into(),
            x,
            y,
        },
        Style::Line,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicBool;

    const TANK: &str = r#"
name = "resumable"
dim = 2
boundary = "energy"
[fluid]
density = 1000.0
sound_speed = 10.0
gravity = [0.0, -9.81]
[resolution]
dx = 0.05
h_over_dx = 2.0
[time]
end = 0.03
[output]
vtk_interval = 0.0
series_interval = 0.005
[settle]
enabled = false
[[fluid_block]]
shape = "box"
min = [0.0, 0.0]
max = [0.4, 0.2]
pressure = "hydrostatic"
[[wall]]
shape = "box"
min = [0.0, 0.0]
max = [0.4, 0.4]
open = ["+y"]
"#;

    fn tank(overrides: &[&str]) -> LoadedCase {
        load("resumable", TANK, overrides).unwrap()
    }

    /// A run stopped part-way continues from its checkpoint when the same build runs the same
    /// case into its folder again, and ends with the outputs of an uninterrupted run; a
    /// different case starts afresh.
    #[test]
    fn a_stopped_run_resumes_with_the_figures_of_an_uninterrupted_one() {
        let scratch = tempfile::Builder::new()
            .prefix("bisph-resumable-")
            .tempdir()
            .unwrap();
        let root = scratch.path();
        let (stopped, whole) = (root.join("stopped"), root.join("whole"));
        let loaded = tank(&[]);
        let stop_now = |dir: &Path, loaded: &LoadedCase| {
            std::fs::create_dir_all(dir).unwrap();
            std::fs::write(dir.join(BUILD_FILE), build_fingerprint().unwrap()).unwrap();
            // Stopped as a signal stops a run, some steps in.
            let stop = AtomicBool::new(false);
            let options = RunOptions {
                stop: Some(&stop),
                ..Default::default()
            };
            let mut on_progress = |p: bisph_io::run::runner::Progress| {
                if p.step >= 5 {
                    stop.store(true, std::sync::atomic::Ordering::Relaxed);
                }
            };
            let stopped = run_case_with(loaded, dir, &options, &mut on_progress);
            assert!(
                matches!(stopped, Err(bisph_io::run::RunError::Interrupted { step, .. }) if step >= 5),
                "{stopped:?}"
            );
            assert!(dir.join(checkpoint::FILE_NAME).exists());
        };
        stop_now(&stopped, &loaded);
        let resumed = run_resumable(&loaded, &stopped).unwrap();
        assert!(resumed.resumed_from_step.is_some(), "not resumed");
        let uninterrupted = run_resumable(&loaded, &whole).unwrap();
        assert!(uninterrupted.resumed_from_step.is_none());
        assert_eq!(resumed.steps, uninterrupted.steps);
        let series = |dir: &Path| std::fs::read(dir.join("energy.csv")).unwrap();
        assert_eq!(series(&stopped), series(&whole));

        stop_now(&stopped, &loaded);
        let other = run_resumable(&tank(&["time.end=0.02"]), &stopped).unwrap();
        assert!(other.resumed_from_step.is_none(), "another case resumed");
    }
}
