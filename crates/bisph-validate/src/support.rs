//! What the validation cases share: loading an embedded case file, running it, reading the
//! CSV columns a run wrote, and line plots.

use bisph_io::case::{parse_case, LoadedCase};
use bisph_io::formats::plot::{write_png, Plot, Series, Style};
use bisph_io::run::runner::{run_case, Summary};
use std::path::Path;

/// A case file shipped in `cases/`, embedded so `bisph validate` runs from anywhere.
pub fn load(name: &str, text: &str, overrides: &[&str]) -> Result<LoadedCase, String> {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    parse_case(&format!("cases/{name}.toml"), text, &overrides).map_err(|e| e.to_string())
}

/// Runs a loaded case to its end, writing its outputs under `out`.
pub fn run(loaded: &LoadedCase, out: &Path) -> Result<Summary, String> {
    run_case(loaded, out, &mut |_| {}).map_err(|e| e.to_string())
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
