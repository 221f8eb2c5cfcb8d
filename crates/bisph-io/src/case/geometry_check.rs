//! Geometry checked before a run: every fluid particle on or in front of the walls (on the
//! side their normals point away from), closed walls drawn the right way round,
//! 2-D wall polygons that do not cross themselves, no open box face or cylinder end lying on
//! another wall. Each mistake is a [`GeometryError`] naming the block or wall, a position and
//! what was expected.

use crate::case::build::Layout;
use crate::case::error::CaseError;
use crate::case::schema::{LoadedCase, WallShape, WallSpec};
use bisph_core::{Simulation, Vector};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::ops::Range;

/// Particles of each block tested with the exact signed distance whatever their distance to
/// the walls (the rest are tested within the kernel support only).
const FAR_SAMPLES: usize = 64;

/// Beyond this many kernel supports, the side of a far particle is taken from the nearest
/// element centre's plane alone.
const FAR_SEARCH_SUPPORTS: f64 = 20.0;

/// A geometry mistake found before the first step (exit code 7).
#[derive(Debug, Clone, PartialEq)]
pub struct GeometryError(pub CaseError);

impl std::fmt::Display for GeometryError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl std::error::Error for GeometryError {}

/// Checks the geometry of a built case: 2-D wall polygons that cross themselves, then, per
/// fluid block, particles behind or too close to a wall, a block outside the walls and a
/// closed wall whose normals point into the fluid.
pub fn check_geometry<V: Vector>(
    loaded: &LoadedCase,
    sim: &Simulation<V>,
    layout: &Layout,
) -> Result<(), GeometryError> {
    check_self_intersections(loaded).map_err(GeometryError)?;
    check_open_faces(loaded, sim, layout).map_err(GeometryError)?;
    if sim.walls.elements.is_empty() {
        return Ok(());
    }
    for (k, block) in layout.blocks.iter().enumerate() {
        check_block(loaded, sim, layout, k, block.clone()).map_err(GeometryError)?;
    }
    Ok(())
}

/// A 2-D `polygon` or `polyline` wall whose sides cross (or touch) each other.
fn check_self_intersections(loaded: &LoadedCase) -> Result<(), CaseError> {
    if loaded.case.dim != 2 {
        return Ok(());
    }
    for (k, wall) in loaded.case.wall.iter().enumerate() {
        let closed = match wall.shape {
            WallShape::Polygon => true,
            WallShape::Polyline => false,
            _ => continue,
        };
        let points: Vec<DVec2> = wall
            .points
            .iter()
            .flatten()
            .map(|p| DVec2::from_slice(p))
            .collect();
        if let Some((i, j, at)) = first_crossing(&points, closed) {
            let side = |s: usize| {
                let (a, b) = (points[s], points[(s + 1) % points.len()]);
                format!(
                    "side {s} from ({}, {}) to ({}, {})",
                    num(a.x),
                    num(a.y),
                    num(b.x),
                    num(b.y)
                )
            };
            return Err(loaded.error(
                &format!("wall[{k}].points"),
                format!(
                    "the wall crosses itself: its {} meets its {} at ({}, {}); expected a \
                     simple {} whose sides meet only at shared points",
                    side(i),
                    side(j),
                    num(at.x),
                    num(at.y),
                    wall.shape.name()
                ),
            ));
        }
    }
    Ok(())
}

/// An open box face or cylinder end that lies on another wall: an obstacle standing on a floor
/// without a bottom of its own. The floor then runs on under the obstacle, so the walls no
/// longer bound the water: the geometric Shepard factor (paper 2, eq 8) near the obstacle's
/// foot counts the floor inside the obstacle (up to 0.1 too low beside the SPHERIC test 2
/// obstacle at `h = 0.22 m`) and the wall terms push on water that is not there. Closed, the
/// obstacle's bottom lies on the floor with the opposite normal and cancels it where they
/// overlap.
fn check_open_faces<V: Vector>(
    loaded: &LoadedCase,
    sim: &Simulation<V>,
    layout: &Layout,
) -> Result<(), CaseError> {
    let e = &sim.walls.elements;
    let tolerance = 1e-9 * loaded.case.resolution.dx;
    for (k, wall) in loaded.case.wall.iter().enumerate() {
        for (kind, face, centre, normal) in open_faces(wall) {
            let others = layout
                .walls
                .iter()
                .enumerate()
                .filter(|&(m, _)| m != k)
                .flat_map(|(m, range)| range.clone().map(move |j| (m, j)));
            let lies_on = others.into_iter().find(|&(_, j)| {
                let (c, n) = (xyz(e.centre[j]), xyz(e.normal[j]));
                let offset = centre - c;
                let height = offset.dot(n);
                height.abs() <= tolerance
                    && n.dot(normal).abs() >= 1.0 - 1e-9
                    && (offset - n * height).length() <= e.reach[j]
            });
            if let Some((m, _)) = lies_on {
                return Err(loaded.error(
                    &format!("wall[{k}].open"),
                    format!(
                        "the open {kind} \"{face}\" lies on wall[{m}], which then runs on under this wall \
                         (a floor under an obstacle standing on it): the walls no longer bound \
                         the water and the Shepard factor next to it is wrong; expected it \
                         closed (remove \"{face}\" from open): its elements then cancel \
                         wall[{m}] where it lies under this wall"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The open faces of a box (`"-x"`, ...) and the open ends of a cylinder: what it is, its
/// name, centre and unit normal.
fn open_faces(wall: &WallSpec) -> Vec<(&'static str, &str, DVec3, DVec3)> {
    let point = |v: &Option<Vec<f64>>| {
        let v = v.as_deref().unwrap_or(&[]);
        DVec3::new(
            v.first().copied().unwrap_or(0.0),
            v.get(1).copied().unwrap_or(0.0),
            v.get(2).copied().unwrap_or(0.0),
        )
    };
    let mut faces = Vec::new();
    for name in &wall.open {
        match wall.shape {
            WallShape::Box => {
                let (min, max) = (point(&wall.min), point(&wall.max));
                let axis = match name.as_bytes().get(1) {
                    Some(b'x') => 0,
                    Some(b'y') => 1,
                    _ => 2,
                };
                let upper = name.starts_with('+');
                let mut centre = (min + max) * 0.5;
                centre[axis] = if upper { max[axis] } else { min[axis] };
                let mut normal = DVec3::ZERO;
                normal[axis] = if upper { 1.0 } else { -1.0 };
                faces.push(("face", name.as_str(), centre, normal));
            }
            WallShape::Cylinder => {
                let (start, end) = (point(&wall.start), point(&wall.end));
                let axis = (end - start).normalize_or_zero();
                let centre = if name == "start" { start } else { end };
                faces.push(("end", name.as_str(), centre, axis));
            }
            _ => {}
        }
    }
    faces
}

/// The first two non-adjacent sides of a polyline (closed: the last point joins the first)
/// that meet, and where.
fn first_crossing(points: &[DVec2], closed: bool) -> Option<(usize, usize, DVec2)> {
    let n = points.len();
    let sides = if closed && n > 2 {
        n
    } else {
        n.saturating_sub(1)
    };
    let ends = |s: usize| (points[s], points[(s + 1) % n]);
    for i in 0..sides {
        for j in i + 2..sides {
            if closed && i == 0 && j == sides - 1 {
                continue;
            }
            let (a, b) = ends(i);
            let (c, d) = ends(j);
            if let Some(at) = segments_meet(a, b, c, d) {
                return Some((i, j, at));
            }
        }
    }
    None
}

/// The point where segments `a-b` and `c-d` meet, if they do (parallel ones are skipped).
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Option<DVec2> {
    let (r, s) = (b - a, d - c);
    let denom = r.perp_dot(s);
    let scale = r.length() * s.length();
    if denom.abs() <= 1e-12 * scale {
        return None;
    }
    let t = (c - a).perp_dot(s) / denom;
    let u = (c - a).perp_dot(r) / denom;
    let eps = 1e-12;
    ((-eps..=1.0 + eps).contains(&t) && (-eps..=1.0 + eps).contains(&u)).then(|| a + r * t)
}

/// One block: its particles near the walls, then a sample of all its particles.
fn check_block<V: Vector>(
    loaded: &LoadedCase,
    sim: &Simulation<V>,
    layout: &Layout,
    k: usize,
    particles: Range<usize>,
) -> Result<(), CaseError> {
    if particles.is_empty() {
        return Ok(());
    }
    let positions = &sim.fluid.position[particles.clone()];
    let support = sim.config.kernel.support;
    let near: Vec<(usize, f64)> = positions
        .par_iter()
        .enumerate()
        .filter_map(|(i, &x)| {
            let d = sim.walls.signed_distance(x, support)?;
            (d > 0.0).then_some((i, d))
        })
        .collect();
    let stride = positions.len().div_ceil(FAR_SAMPLES).max(1);
    let samples: Vec<usize> = (0..positions.len()).step_by(stride).collect();
    let far: Vec<f64> = samples
        .par_iter()
        .map(|&i| far_signed_distance(sim, positions[i]))
        .collect();
    let key = format!("fluid_block[{k}]");
    if far.iter().all(|&d| d > 0.0) {
        let x = positions[samples[0]];
        return Err(outside_or_reversed(loaded, sim, layout, &key, x, far[0]));
    }
    let Some(&(i, d)) = near.first() else {
        return match samples.iter().zip(&far).find(|(_, &d)| d > 0.0) {
            Some((&i, &d)) => Err(overlap(loaded, sim, layout, &key, positions[i], d, 1)),
            None => Ok(()),
        };
    };
    Err(overlap(
        loaded,
        sim,
        layout,
        &key,
        positions[i],
        d,
        near.len(),
    ))
}

/// A block with particles behind a wall.
fn overlap<V: Vector>(
    loaded: &LoadedCase,
    sim: &Simulation<V>,
    layout: &Layout,
    key: &str,
    x: V,
    d: f64,
    count: usize,
) -> CaseError {
    let wall = nearest_wall(sim, layout, x);
    loaded.error(
        key,
        format!(
            "the block overlaps wall[{wall}]: its particle at {} lies {} m behind it ({count} of \
             its particles lie behind a wall); expected every particle on or in front of the \
             walls: shrink the block or give it holes where the walls are",
            point(x),
            num(d)
        ),
    )
}

/// A block entirely behind the walls: inside a closed wall drawn the wrong way round, or
/// outside the walls.
fn outside_or_reversed<V: Vector>(
    loaded: &LoadedCase,
    sim: &Simulation<V>,
    layout: &Layout,
    key: &str,
    x: V,
    d: f64,
) -> CaseError {
    let reversed = layout
        .walls
        .iter()
        .position(|w| !w.is_empty() && winding_number(sim, w.clone(), x) < -0.5);
    if let Some(wall) = reversed {
        let expected = if loaded.case.wall[wall].shape.is_round() {
            "`fluid = \"inside\"` on a circle, sphere or cylinder that holds the fluid (they are \
             obstacles by default)"
        } else if V::DIM == 2 {
            "a tank's points listed counter-clockwise (an obstacle's clockwise)"
        } else {
            "a tank's triangles facing out of it (an obstacle's into it)"
        };
        return loaded.error(
            &format!("wall[{wall}]"),
            format!(
                "the wall is drawn the wrong way round: it encloses {key} (particle at {}) \
                 but its normals point into the fluid; expected normals out of the fluid: {expected}",
                point(x)
            ),
        );
    }
    let wall = nearest_wall(sim, layout, x);
    loaded.error(
        key,
        format!(
            "the block lies outside the walls: its particles are behind them (the particle at \
             {} is {} m behind wall[{wall}]); expected the fluid inside the walls, on the side \
             their normals point away from",
            point(x),
            num(d)
        ),
    )
}

/// The signed distance of `x` to the walls at any distance (positive behind them); far from
/// every wall, the side of the plane of the nearest element centre.
fn far_signed_distance<V: Vector>(sim: &Simulation<V>, x: V) -> f64 {
    let e = &sim.walls.elements;
    let support = sim.config.kernel.support;
    let (mut bound, mut nearest) = (f64::INFINITY, 0);
    for j in 0..e.len() {
        let r = (x - e.centre[j]).length();
        if r + e.reach[j] < bound {
            bound = r + e.reach[j];
        }
        if r < (x - e.centre[nearest]).length() {
            nearest = j;
        }
    }
    if bound <= FAR_SEARCH_SUPPORTS * support {
        if let Some(d) = sim.walls.signed_distance(x, 1.001 * bound + 1e-9 * support) {
            return d;
        }
    }
    let side = (x - e.centre[nearest]).dot(e.normal[nearest]);
    side.signum() * (x - e.centre[nearest]).length()
}

/// The wall (index in the case) whose element centre is nearest to `x`.
fn nearest_wall<V: Vector>(sim: &Simulation<V>, layout: &Layout, x: V) -> usize {
    let e = &sim.walls.elements;
    let j = (0..e.len())
        .min_by(|&a, &b| {
            let da = (x - e.centre[a]).length_squared();
            let db = (x - e.centre[b]).length_squared();
            da.total_cmp(&db)
        })
        .unwrap_or(0);
    layout
        .walls
        .iter()
        .position(|w| w.contains(&j))
        .unwrap_or(0)
}

/// Generalised winding number of the elements `range` about `x`, counted positive where the
/// normals point away from `x`: about 1 inside a closed wall whose normals point out of it,
/// -1 inside one whose normals point into it, 0 outside.
fn winding_number<V: Vector>(sim: &Simulation<V>, range: Range<usize>, x: V) -> f64 {
    let e = &sim.walls.elements;
    let x3 = xyz(x);
    let full = if V::DIM == 2 { 2.0 * PI } else { 4.0 * PI };
    let mut total = 0.0;
    for j in range {
        let corners: Vec<DVec3> = e.current_corners(j).iter().map(|&c| xyz(c) - x3).collect();
        let angle = if V::DIM == 2 {
            let (a, b) = (corners[0], corners[corners.len() - 1]);
            a.cross(b).length().atan2(a.dot(b))
        } else {
            (1..corners.len().saturating_sub(1))
                .map(|m| solid_angle(corners[0], corners[m], corners[m + 1]))
                .sum()
        };
        total += (e.centre[j] - x).dot(e.normal[j]).signum() * angle;
    }
    total / full
}

/// Unsigned solid angle of the triangle `a b c` seen from the origin (Van Oosterom and
/// Strackee 1983).
fn solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let numerator = a.dot(b.cross(c)).abs();
    let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * numerator.atan2(denominator)
}

fn xyz<V: Vector>(v: V) -> DVec3 {
    DVec3::from_array(v.to_xyz())
}

fn point<V: Vector>(v: V) -> String {
    let c: Vec<String> = (0..V::DIM).map(|k| num(v.get(k))).collect();
    format!("({})", c.join(", "))
}

/// A length or coordinate, to 6 significant digits.
fn num(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}
