//! Simple 2D line / marker plots written to PNG with `plotters`.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::prelude::*;

/// One data series: `x[i]` pairs with `y[i]`.
#[derive(Debug, Clone, Default)]
pub struct Series {
    /// Legend text (an empty label gets no legend entry).
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates, same length as `x`.
    pub y: Vec<f64>,
}

/// How a series is drawn: a line, or marker-style points for experiment data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Connected line (broken at non-finite points).
    Line,
    /// Unconnected circle markers.
    Points,
}

/// A plot: titles, axis labels and the series to draw, in legend order.
#[derive(Debug, Clone, Default)]
pub struct Plot {
    /// Caption above the chart.
    pub title: String,
    /// Label of the horizontal axis.
    pub x_label: String,
    /// Label of the vertical axis.
    pub y_label: String,
    /// Series and their drawing style.
    pub series: Vec<(Series, Style)>,
}

/// A plotting failure; the message names the output file.
#[derive(Debug)]
pub struct PlotError(pub String);

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PlotError {}

/// Largest accepted image side, in pixels.
const MAX_SIDE: u32 = 16_384;
/// Smallest accepted image side, in pixels (room for axes and labels).
const MIN_SIDE: u32 = 64;
/// Axis ranges are clamped to this magnitude so their span stays finite.
const MAX_ABS: f64 = 1e300;

/// Distinct colours (the "tab10" palette), cycled for more series.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Register the bundled font with plotters once; later calls reuse the result.
fn ensure_font() -> Result<(), String> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            plotters::style::FontStyle::Normal,
            include_bytes!("DejaVuSans.ttf"),
        )
        .map_err(|_| "the bundled DejaVuSans font could not be loaded".to_string())
    })
    .clone()
}

/// Render `plot` to a `width` x `height` PNG at `path`.
///
/// Axis ranges follow the finite data with a 5% margin; non-finite points are
/// skipped (and break lines); magnitudes beyond 1e300 are pinned to the axis
/// edge. The image is written to a temporary file next to `path` and renamed
/// into place. Sides must be 64..=16384 pixels.
pub fn write_png(plot: &Plot, path: &Path, width: u32, height: u32) -> Result<(), PlotError> {
    let err = |msg: String| PlotError(format!("plot {}: {msg}", path.display()));
    if !(MIN_SIDE..=MAX_SIDE).contains(&width) || !(MIN_SIDE..=MAX_SIDE).contains(&height) {
        return Err(err(format!(
            "image size {width}x{height} outside {MIN_SIDE}..={MAX_SIDE} pixels"
        )));
    }
    for (s, _) in &plot.series {
        if s.x.len() != s.y.len() {
            return Err(err(format!(
                "series \"{}\" has {} x values but {} y values",
                s.label,
                s.x.len(),
                s.y.len()
            )));
        }
    }
    ensure_font().map_err(err)?;

    // The bitmap encoder picks the format from the extension, so the
    // temporary keeps a `.png` suffix.
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp.png");
    let tmp = PathBuf::from(tmp);
    let result = render(plot, &tmp, width, height)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(err)
}

/// Draw the chart into a PNG file at `file`.
fn render(plot: &Plot, file: &Path, width: u32, height: u32) -> Result<(), String> {
    let finite = |s: &Series| {
        s.x.iter()
            .zip(&s.y)
            .map(|(&x, &y)| (x, y))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect::<Vec<_>>()
    };
    let all: Vec<(f64, f64)> = plot.series.iter().flat_map(|(s, _)| finite(s)).collect();
    let x_range = axis_range(all.iter().map(|p| p.0));
    let y_range = axis_range(all.iter().map(|p| p.1));
    // A no-op except for magnitudes beyond `MAX_ABS`: plotters overflows on
    // points far outside the axis range.
    let pin =
        move |(x, y): (f64, f64)| (x.clamp(x_range.0, x_range.1), y.clamp(y_range.0, y_range.1));

    let de = |e: &dyn fmt::Display| e.to_string();
    let root = BitMapBackend::new(file, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| de(&e))?;

    let small = width.min(height);
    let font = (small / 40).clamp(10, 28);
    let mut chart = ChartBuilder::on(&root)
        .caption(&plot.title, ("sans-serif", font + font / 2))
        .margin(small / 40 + 4)
        .x_label_area_size(font * 3)
        .y_label_area_size(font * 5)
        .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)
        .map_err(|e| de(&e))?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .label_style(("sans-serif", font))
        .axis_desc_style(("sans-serif", font + 2))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| de(&e))?;

    let marker = (small / 160).clamp(2, 8);
    let mut any_label = false;
    for (i, (s, style)) in plot.series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let anno = match style {
            Style::Line => {
                let stroke = color.stroke_width((small / 300).clamp(1, 4));
                chart
                    .draw_series(finite_runs(s).into_iter().map(move |run| {
                        PathElement::new(run.into_iter().map(pin).collect::<Vec<_>>(), stroke)
                    }))
                    .map_err(|e| de(&e))?
            }
            Style::Points => chart
                .draw_series(
                    finite(s)
                        .into_iter()
                        .map(move |p| Circle::new(pin(p), marker, color.filled())),
                )
                .map_err(|e| de(&e))?,
        };
        if !s.label.is_empty() {
            any_label = true;
            let legend_stroke = color.stroke_width(2);
            let sz = font as i32;
            match style {
                Style::Line => anno.label(s.label.as_str()).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + sz * 2, y)], legend_stroke)
                }),
                Style::Points => anno
                    .label(s.label.as_str())
                    .legend(move |(x, y)| Circle::new((x + sz, y), marker, color.filled())),
            };
        }
    }
    if any_label {
        chart
            .configure_series_labels()
            .label_font(("sans-serif", font))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| de(&e))?;
    }
    root.present().map_err(|e| de(&e))
}

/// Maximal runs of consecutive finite points (a line breaks at NaN/inf).
fn finite_runs(s: &Series) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur = Vec::new();
    for (&x, &y) in s.x.iter().zip(&s.y) {
        if x.is_finite() && y.is_finite() {
            cur.push((x, y));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

/// Axis range covering `values` (all finite) with a 5% margin; a constant
/// gets a margin around its value and no data gives `0..1`.
fn axis_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if lo > hi {
        return (0.0, 1.0);
    }
    let (lo, hi) = (lo.clamp(-MAX_ABS, MAX_ABS), hi.clamp(-MAX_ABS, MAX_ABS));
    let pad = 0.05 * (hi - lo);
    if pad.is_normal() && lo - pad < lo && hi + pad > hi {
        return (lo - pad, hi + pad);
    }
    // Constant (or numerically degenerate) data: pad around the middle.
    let mid = 0.5 * (lo + hi);
    let pad = 0.05 * mid.abs();
    let pad = if pad.is_normal() && mid - pad < mid {
        pad
    } else {
        1.0
    };
    (mid - pad, mid + pad)
}

/// A PNG of labelled lines (1000 x 600) written as `out/file`; returns `file`, the path
/// relative to `out` that a report links to.
pub fn line_plot_png(
    out: &Path,
    file: &str,
    title: &str,
    xl: &str,
    yl: &str,
    series: Vec<(String, Vec<f64>, Vec<f64>)>,
) -> Result<PathBuf, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let path = out.join(file);
    let plot = Plot {
        title: title.into(),
        x_label: xl.into(),
        y_label: yl.into(),
        series: series
            .into_iter()
            .map(|(label, x, y)| (Series { label, x, y }, Style::Line))
            .collect(),
    };
    write_png(&plot, &path, 1000, 600).map_err(|e| e.0)?;
    Ok(PathBuf::from(file))
}

#[cfg(test)]
mod tests {
    use super::*;

    const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

    /// A fresh, empty folder for one test, removed when dropped.
    fn scratch(name: &str) -> tempfile::TempDir {
        let prefix = format!("bisph-plot-{name}-");
        tempfile::Builder::new().prefix(&prefix).tempdir().unwrap()
    }

    fn series(label: &str, x: Vec<f64>, y: Vec<f64>) -> Series {
        Series {
            label: label.into(),
            x,
            y,
        }
    }

    #[test]
    fn two_series_png() {
        let scratch = scratch("two");
        let dir = scratch.path();
        let path = dir.join("dam_break.png");
        let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.02).collect();
        let y: Vec<f64> = x.iter().map(|t| 1.0 + 0.5 * (2.0 * t).sin()).collect();
        let xe: Vec<f64> = (0..12).map(|i| i as f64 * 0.35).collect();
        let ye: Vec<f64> = xe
            .iter()
            .map(|t| 1.0 + 0.5 * (2.0 * t).sin() + 0.03)
            .collect();
        let plot = Plot {
            title: "Surge front position".into(),
            x_label: "t (s)".into(),
            y_label: "x / H".into(),
            series: vec![
                (series("bisph", x, y), Style::Line),
                (series("experiment", xe, ye), Style::Points),
            ],
        };
        write_png(&plot, &path, 800, 500).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.starts_with(&PNG_SIGNATURE));
        assert!(!dir.join("dam_break.png.tmp.png").exists());
        if std::env::var_os("BISPH_KEEP_PLOT").is_some() {
            eprintln!("plot kept in {}", scratch.keep().display());
        }
    }

    #[test]
    fn degenerate_data_does_not_fail() {
        let scratch = scratch("degenerate");
        let dir = scratch.path();
        let nan = f64::NAN;
        let inf = f64::INFINITY;
        let cases: Vec<Vec<(Series, Style)>> = vec![
            vec![],
            vec![(series("", vec![], vec![]), Style::Line)],
            vec![(series("c", vec![1.0, 2.0, 3.0], vec![5.0; 3]), Style::Line)],
            vec![(series("zero", vec![0.0; 3], vec![0.0; 3]), Style::Points)],
            vec![(series("one", vec![2.0], vec![-3.0]), Style::Line)],
            vec![(
                series(
                    "nan",
                    vec![nan, 1.0, 2.0, inf, 4.0],
                    vec![1.0, nan, 2.0, 3.0, -inf],
                ),
                Style::Line,
            )],
            vec![(series("all nan", vec![nan; 4], vec![nan; 4]), Style::Points)],
            vec![(
                series("huge", vec![-f64::MAX, f64::MAX], vec![f64::MAX, -f64::MAX]),
                Style::Line,
            )],
            vec![(
                series("tiny", vec![0.0, 5e-324], vec![1e-310, 2e-310]),
                Style::Line,
            )],
        ];
        for (i, series) in cases.into_iter().enumerate() {
            let plot = Plot {
                title: format!("case {i}"),
                series,
                ..Plot::default()
            };
            let path = dir.join(format!("case{i}.png"));
            for (w, h) in [(320, 240), (MIN_SIDE, MIN_SIDE), (MIN_SIDE, 2000)] {
                write_png(&plot, &path, w, h).unwrap();
                assert!(std::fs::read(&path).unwrap().starts_with(&PNG_SIGNATURE));
            }
        }
    }

    #[test]
    fn errors_name_the_file() {
        let scratch = scratch("errors");
        let dir = scratch.path();
        let plot = Plot {
            series: vec![(series("bad", vec![1.0, 2.0], vec![1.0]), Style::Line)],
            ..Plot::default()
        };
        let path = dir.join("mismatch.png");
        let e = write_png(&plot, &path, 400, 300).unwrap_err();
        assert!(
            e.to_string().contains("mismatch.png") && e.to_string().contains("bad"),
            "{e}"
        );
        let e = write_png(&Plot::default(), &path, 0, 300).unwrap_err();
        assert!(e.to_string().contains("mismatch.png"), "{e}");
        let missing = dir.join("no/such/dir/out.png");
        let e = write_png(&Plot::default(), &missing, 400, 300).unwrap_err();
        assert!(e.to_string().contains("out.png"), "{e}");
    }

    #[test]
    fn axis_range_cases() {
        assert_eq!(axis_range([].into_iter()), (0.0, 1.0));
        assert_eq!(axis_range([0.0, 0.0].into_iter()), (-1.0, 1.0));
        let (lo, hi) = axis_range([10.0].into_iter());
        assert!(lo < 10.0 && hi > 10.0);
        let (lo, hi) = axis_range([0.0, 10.0].into_iter());
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
        let (lo, hi) = axis_range([-f64::MAX, f64::MAX].into_iter());
        assert!(lo.is_finite() && hi.is_finite() && lo < hi);
    }
}
