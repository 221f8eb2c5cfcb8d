//! `bisph shepard`: the Shepard factor of a case's walls at arbitrary points, by each method,
//! so that gamma can be checked from outside the solver.
//!
//! - `discrete`: `gamma(x) = sum_j W(x_j - x) V_j` over the case's initial fluid particles
//!   (paper 2, eq 4);
//! - `geometric`: from the wall elements alone (paper 2, eq 8; exact, see
//!   [`bisph_core::walls::geometric_shepard`]);
//! - `integrated`: the exact `grad gamma` of the walls (paper 3, eqs 9-10) integrated along a
//!   straight path in the fluid from a point where `gamma = 1` (paper 3, eq 4 as a line
//!   integral; 2-D; [`bisph_core::walls::integrated_shepard`]).
//!
//! Points come from a CSV file with `dim` numbers per line (`x,y` or `x,y,z`); an optional
//! header line (`x,y[,z]`), blank lines and lines starting with `#` are skipped.

use crate::case::build::build_simulation;

use crate::case::dim::CaseDim;
use crate::case::schema::{LoadedCase, WallShape};
use bisph_core::neighbours::CellGrid;
use bisph_core::walls::shepard::ShepardKind;
use bisph_core::walls::{geometric_shepard, integrated_shepard};
use bisph_core::Simulation;
use std::fmt::Write as _;
use std::path::Path;

/// Reads the points of `path`: `dim` comma-separated numbers per line. Errors name the file,
/// the line and what was expected.
pub fn read_points(path: &Path, dim: usize) -> Result<Vec<[f64; 3]>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read the points file: {e}", path.display()))?;
    parse_points(&path.display().to_string(), &text, dim)
}

/// Parses the text of a points file (see [`read_points`]).
pub fn parse_points(file: &str, text: &str, dim: usize) -> Result<Vec<[f64; 3]>, String> {
    let names = ["x", "y", "z"];
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if out.is_empty()
            && fields
                .iter()
                .zip(names)
                .all(|(f, n)| f.eq_ignore_ascii_case(n))
        {
            if fields.len() != dim {
                return Err(format!(
                    "{file}: line {}: header `{line}` has {} columns, expected {} (a {dim}-D case)",
                    k + 1,
                    fields.len(),
                    dim
                ));
            }
            continue;
        }
        if fields.len() != dim {
            return Err(format!(
                "{file}: line {}: expected {dim} comma-separated numbers ({}) for a {dim}-D case, found {} field(s) in `{line}`",
                k + 1,
                names[..dim].join(","),
                fields.len()
            ));
        }
        let mut p = [0.0; 3];
        for (c, f) in fields.iter().enumerate() {
            p[c] = match f.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                _ => {
                    return Err(format!(
                        "{file}: line {}, column {} ({}): expected a finite number, found `{f}`",
                        k + 1,
                        c + 1,
                        names[c]
                    ))
                }
            };
        }
        out.push(p);
    }
    if out.is_empty() {
        return Err(format!("{file}: expected at least one point, found none"));
    }
    Ok(out)
}

/// gamma at `points` for the walls (and, for `discrete`, the initial fluid) of a case.
pub fn gamma_at<V: CaseDim>(
    loaded: &LoadedCase,
    points: &[[f64; 3]],
    method: ShepardKind,
) -> Result<Vec<f64>, String> {
    let sim: Simulation<V> = build_simulation(loaded).map_err(|e| e.to_string())?;
    let kernel = sim.config.kernel;
    let points: Vec<V> = points.iter().map(|p| V::from_slice(p)).collect();
    Ok(match method {
        ShepardKind::Geometric => {
            let walls = &sim.walls;
            points
                .iter()
                .map(|&x| geometric_shepard::gamma(&kernel, x, &walls.elements, &walls.grid))
                .collect()
        }
        ShepardKind::Integrated => {
            let walls = &sim.walls;
            let corners: Vec<[f64; 3]> =
                walls.elements.corners.iter().map(|c| c.to_xyz()).collect();
            if let Some([x, y]) = open_wall_end(&corners) {
                let named = open_walls(loaded);
                return Err(format!(
                    "--method integrated needs walls that close around the fluid (it integrates \
                     grad gamma along a path from where gamma = 1, and a path through an opening \
                     gives a wrong gamma), but the walls end at ({x}, {y}){}; close them (a box \
                     without `open` sides, a polygon) or use --method geometric",
                    if named.is_empty() {
                        String::new()
                    } else {
                        format!(" (open: {})", named.join(", "))
                    }
                ));
            }
            // Any path that stays in the fluid fits in the walls' bounding box, plus the support.
            let (mut lo, mut hi) = (V::from_slice(&[f64::MAX; 3]), V::from_slice(&[f64::MIN; 3]));
            for &c in &walls.elements.corners {
                lo = lo.min_by_component(c);
                hi = hi.max_by_component(c);
            }
            let max_length = if walls.elements.is_empty() {
                0.0
            } else {
                (hi - lo).length() + 4.0 * kernel.support
            };
            points
                .iter()
                .enumerate()
                .map(|(k, &x)| {
                    integrated_shepard::gamma_by_path(
                        &kernel,
                        x,
                        &walls.elements,
                        &walls.grid,
                        1e-13,
                        max_length,
                    )
                    .map(|p| p.gamma)
                    .map_err(|e| format!("--method integrated, point {}: {e}", k + 1))
                })
                .collect::<Result<_, _>>()?
        }
        ShepardKind::Discrete => {
            let fluid = &sim.fluid;
            let mut grid = CellGrid::new(kernel.support);
            grid.rebuild(&fluid.position);
            points
                .iter()
                .map(|&x| {
                    let mut sum = 0.0;
                    grid.for_each_neighbour(x, &fluid.position, kernel.support, |j, _, r| {
                        sum += kernel.value(r) * fluid.mass[j] / fluid.density[j];
                    });
                    sum
                })
                .collect()
        }
    })
}

/// A segment end of 2-D walls that no other segment shares (where the walls stop and leave
/// the fluid open, like an open box side or the end of a polyline); `None` when the walls
/// close.
fn open_wall_end(corners: &[[f64; 3]]) -> Option<[f64; 2]> {
    let extent = corners
        .iter()
        .flat_map(|c| [c[0].abs(), c[1].abs()])
        .fold(1.0f64, f64::max);
    let tolerance = 1e-9 * extent;
    let mut ends: Vec<[f64; 2]> = corners.iter().map(|c| [c[0], c[1]]).collect();
    ends.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut partners = vec![0usize; ends.len()];
    for i in 0..ends.len() {
        for j in i + 1..ends.len() {
            if ends[j][0] - ends[i][0] > tolerance {
                break;
            }
            if (ends[j][1] - ends[i][1]).abs() <= tolerance {
                partners[i] += 1;
                partners[j] += 1;
            }
        }
    }
    ends.iter()
        .zip(&partners)
        .find(|(_, &n)| n == 0)
        .map(|(e, _)| *e)
}

/// The walls of a case that are open by their definition: boxes with `open` sides,
/// polylines and cylinders with `open` ends, as `wall[k], ...`.
fn open_walls(loaded: &LoadedCase) -> Vec<String> {
    loaded
        .case
        .wall
        .iter()
        .enumerate()
        .filter_map(|(k, w)| match w.shape {
            WallShape::Box if !w.open.is_empty() => {
                Some(format!("wall[{k}], a box open at {}", w.open.join(" and ")))
            }
            WallShape::Polyline => Some(format!("wall[{k}], a polyline")),
            WallShape::Cylinder if !w.open.is_empty() => Some(format!(
                "wall[{k}], a cylinder open at its {}",
                w.open.join(" and ")
            )),
            _ => None,
        })
        .collect()
}

/// The `x,y[,z],gamma` table `bisph shepard` prints.
pub fn shepard_table(
    loaded: &LoadedCase,
    points_file: &Path,
    method: ShepardKind,
) -> Result<String, String> {
    let dim = loaded.case.dim as usize;
    let points = read_points(points_file, dim)?;
    let gamma = if dim == 2 {
        gamma_at::<glam::DVec2>(loaded, &points, method)?
    } else {
        gamma_at::<glam::DVec3>(loaded, &points, method)?
    };
    let mut s = String::from(if dim == 2 {
        "x,y,gamma\n"
    } else {
        "x,y,z,gamma\n"
    });
    for (p, g) in points.iter().zip(gamma) {
        for c in &p[..dim] {
            let _ = write!(s, "{c},");
        }
        let _ = writeln!(s, "{g:.17e}");
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_parse_with_header_comments_and_named_errors() {
        let p = parse_points("p.csv", "x,y\n# c\n0.1, 0.2\n\n0.3,0.4\n", 2).unwrap();
        assert_eq!(p, vec![[0.1, 0.2, 0.0], [0.3, 0.4, 0.0]]);
        let e = parse_points("p.csv", "0.1,0.2\n0.3\n", 2).unwrap_err();
        assert!(
            e.contains("p.csv: line 2") && e.contains("expected 2"),
            "{e}"
        );
        let e = parse_points("p.csv", "0.1,abc\n", 2).unwrap_err();
        assert!(e.contains("line 1, column 2 (y)"), "{e}");
        let e = parse_points("p.csv", "0.1,nan\n", 2).unwrap_err();
        assert!(e.contains("finite"), "{e}");
        let e = parse_points("p.csv", "x,y\n0.1,0.2\n", 3).unwrap_err();
        assert!(e.contains("line 1") && e.contains("3-D"), "{e}");
        assert!(parse_points("p.csv", "# nothing\n", 2).is_err());
    }
}
