//! The Shepard factor at an arbitrary point by integrating its exact gradient (paper 3, eq 4
//! read as a line integral): `gamma(x) = 1 - int_0^L grad gamma(x + s d) . d ds`, where
//! `x + L d` is a point with no wall element inside its support (so `gamma = 1` there) and the
//! straight path from `x` to it stays in the fluid (crosses no wall element).
//!
//! `grad gamma = sum_s grad gamma_as` is the exact segment sum of paper 3, eqs 9-10
//! ([`super::usaw::grad_gamma`]); the path integral is done by adaptive Gauss-Legendre
//! quadrature ([`crate::quadrature::adaptive_gauss_legendre`]) on panels of length `h/2`.
//! This is the time integration of `dgamma/dt = v . grad gamma` for a particle that travels
//! from the far field to `x` along the path, computed to quadrature accuracy instead of one
//! trapezoidal step per time step; it is an independent check of the geometric gamma
//! (paper 2), which it matches to about `1e-12` (tests below). 2-D (segments) only, like the
//! exact `grad gamma_as`.

use super::usaw::grad_gamma;
use super::BoundaryElements;
use crate::bi::segment::point_segment_distance;
use crate::dim::{xy, Vector};
use crate::kernel::Wendland;
use crate::neighbours::CellGrid;
use crate::quadrature::adaptive_gauss_legendre;
use glam::DVec2;
use std::f64::consts::PI;

/// gamma at a point by path integration, with the path that was used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathGamma {
    /// The Shepard factor at the point.
    pub gamma: f64,
    /// Unit direction of the path from the point into the fluid (zero when no wall is near).
    pub direction: DVec2,
    /// Length of the path, to the first point where no wall element is within the support.
    pub length: f64,
    /// Number of `grad gamma` evaluations.
    pub evaluations: usize,
}

/// Directions tried, after the direction of `grad gamma` at the point, when that one is
/// blocked by a wall (a thin wall, a narrow gap) or undefined (`grad gamma = 0`).
const FALLBACK_DIRECTIONS: usize = 64;

/// Parameter `t` in `[0, 1]` where the path `p -> q` meets the segment `a -> b`, if it does
/// (touching counts; parallel overlapping segments meet at their first common point).
fn crossing(p: DVec2, q: DVec2, a: DVec2, b: DVec2) -> Option<f64> {
    let (r, s) = (q - p, b - a);
    let denom = r.perp_dot(s);
    let ap = a - p;
    let scale = r.length() * s.length();
    if denom.abs() <= 1e-14 * scale {
        // Parallel: only collinear overlap counts.
        if ap.perp_dot(r).abs() > 1e-12 * scale.max(f64::MIN_POSITIVE) {
            return None;
        }
        let rr = r.length_squared();
        let (t0, t1) = (ap.dot(r) / rr, (b - p).dot(r) / rr);
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        return (hi >= 0.0 && lo <= 1.0).then(|| lo.max(0.0));
    }
    let t = ap.perp_dot(s) / denom;
    let u = ap.perp_dot(r) / denom;
    let tol = 1e-12;
    ((-tol..=1.0 + tol).contains(&t) && (-tol..=1.0 + tol).contains(&u)).then_some(t.max(0.0))
}

/// The wall elements near `x` as segments, with their outward normals.
fn segments_near<V: Vector>(
    x: DVec2,
    radius: f64,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
    mut visit: impl FnMut(DVec2, DVec2, DVec2),
) {
    grid.for_each_candidate_within(
        V::from_slice(&[x.x, x.y]),
        radius + elements.max_reach,
        |j| {
            let c = elements.current_corners(j);
            if c.len() == 2 {
                visit(xy(c[0]), xy(c[1]), xy(elements.normal[j]));
            }
        },
    );
}

/// The length of a straight path from `x` along `d` that stays in the fluid and ends at the
/// first point (on a grid of `h/4` steps) with no wall element within the support, if there is
/// one within `max_length`. `x` may lie on a wall, then `d` must point into the fluid.
fn free_path_length<V: Vector>(
    kernel: &Wendland,
    x: DVec2,
    d: DVec2,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
    max_length: f64,
) -> Option<f64> {
    let on_wall = 1e-12 * kernel.h;
    // Leaving a wall the point lies on: only into the fluid.
    let mut ok = true;
    segments_near(x, on_wall, elements, grid, |a, b, n| {
        if point_segment_distance(x, a, b) <= on_wall && d.dot(n) >= 0.0 {
            ok = false;
        }
    });
    if !ok {
        return None;
    }
    let step = 0.25 * kernel.h;
    let steps = (max_length / step).ceil() as usize;
    for k in 1..=steps {
        let (s0, s1) = ((k - 1) as f64 * step, k as f64 * step);
        let (p, q) = (x + d * s0, x + d * s1);
        let mut blocked = false;
        let mut near = false;
        segments_near(
            0.5 * (p + q),
            0.5 * step + kernel.support,
            elements,
            grid,
            |a, b, _| {
                if let Some(t) = crossing(p, q, a, b) {
                    // The start of the path may touch the element the point lies on.
                    if s0 + t * step > on_wall * 10.0 {
                        blocked = true;
                    }
                }
                if point_segment_distance(q, a, b) < kernel.support {
                    near = true;
                }
            },
        );
        if blocked {
            return None;
        }
        if !near {
            return Some(s1);
        }
    }
    None
}

/// gamma at `x` by integrating the exact `grad gamma` (paper 3, eqs 4, 9-10) along a straight
/// path inside the fluid from a point where `gamma = 1` (see the module notes). The path goes
/// along `grad gamma(x)` (into the fluid) when that is free of walls, else along the first of
/// 64 evenly spread directions that is. `tolerance` is the absolute quadrature tolerance on
/// gamma. Errors: 3-D walls, or no such path within `max_length`.
pub fn gamma_by_path<V: Vector>(
    kernel: &Wendland,
    x: V,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
    tolerance: f64,
    max_length: f64,
) -> Result<PathGamma, String> {
    if V::DIM != 2 {
        return Err(
            "the integrated gamma needs the exact segment grad gamma of paper 3 (eqs 9-10), which is 2-D only; use --method geometric in 3-D"
                .into(),
        );
    }
    let xp = xy(x);
    let mut near = false;
    segments_near(xp, kernel.support, elements, grid, |a, b, _| {
        near |= point_segment_distance(xp, a, b) < kernel.support;
    });
    if !near {
        return Ok(PathGamma {
            gamma: 1.0,
            direction: DVec2::ZERO,
            length: 0.0,
            evaluations: 0,
        });
    }
    let g = xy(grad_gamma(kernel, x, elements, grid));
    let mut candidates = Vec::with_capacity(FALLBACK_DIRECTIONS + 1);
    if g.length() * kernel.h > 1e-12 {
        candidates.push(g.normalize());
    }
    candidates.extend((0..FALLBACK_DIRECTIONS).map(|k| {
        let a = 2.0 * PI * k as f64 / FALLBACK_DIRECTIONS as f64;
        DVec2::new(a.cos(), a.sin())
    }));
    let (direction, length) = candidates
        .iter()
        .find_map(|&d| free_path_length(kernel, xp, d, elements, grid, max_length).map(|l| (d, l)))
        .ok_or_else(|| {
            format!(
                "no straight path inside the fluid from ({}, {}) to a point with no wall within the kernel support (2h = {}) within {max_length}: the point is outside the fluid or in a gap narrower than 2h",
                xp.x, xp.y, kernel.support
            )
        })?;
    let mut evaluations = 0;
    let mut slope = |s: f64| {
        evaluations += 1;
        let p = xp + direction * s;
        xy(grad_gamma(
            kernel,
            V::from_slice(&[p.x, p.y]),
            elements,
            grid,
        ))
        .dot(direction)
    };
    let panels = (length / (0.5 * kernel.h)).ceil().max(1.0) as usize;
    let width = length / panels as f64;
    let mut rise = 0.0;
    for k in 0..panels {
        rise += adaptive_gauss_legendre(
            k as f64 * width,
            (k + 1) as f64 * width,
            tolerance / panels as f64,
            &mut slope,
        );
    }
    Ok(PathGamma {
        gamma: 1.0 - rise,
        direction,
        length,
        evaluations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{box_elements_2d, polyline_elements};
    use crate::walls::geometric_shepard;

    fn walls(shapes: Vec<crate::geometry::ElementShape<DVec2>>) -> BoundaryElements<DVec2> {
        let mut e = BoundaryElements::default();
        for s in shapes {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        e
    }

    /// Max |integrated - geometric| over the points.
    fn worst(kernel: &Wendland, e: &BoundaryElements<DVec2>, points: &[DVec2]) -> f64 {
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let mut worst: f64 = 0.0;
        for &x in points {
            let p = gamma_by_path(kernel, x, e, &grid, 1e-13, 10.0).unwrap();
            let g = geometric_shepard::gamma(kernel, x, e, &grid);
            worst = worst.max((p.gamma - g).abs());
        }
        worst
    }

    #[test]
    fn matches_the_geometric_gamma_at_a_flat_wall_a_corner_and_a_circle() {
        let dx = 0.01;
        let e = walls(box_elements_2d(DVec2::ZERO, DVec2::new(1.0, 1.0), &[], dx));
        let radius = 0.2;
        let sides = (2.0 * PI * radius / dx).round() as usize;
        let circle: Vec<DVec2> = (0..sides)
            .map(|k| {
                let a = 2.0 * PI * k as f64 / sides as f64;
                DVec2::new(radius * a.cos(), radius * a.sin())
            })
            .collect();
        let c = walls(polyline_elements(&circle, true, dx));
        for hk in [2.0, 3.0, 4.0] {
            let kernel = Wendland::new(hk * dx, 2);
            let s: Vec<f64> = (0..=24)
                .map(|k| 1.2 * kernel.support * k as f64 / 24.0)
                .collect();
            let wall: Vec<DVec2> = s.iter().map(|&s| DVec2::new(0.5, s)).collect();
            let corner: Vec<DVec2> = s
                .iter()
                .flat_map(|&s| [DVec2::new(s, 0.5 * dx), DVec2::new(s, s)])
                .collect();
            let dir = DVec2::new(0.3f64.cos(), 0.3f64.sin());
            let rim = radius * (PI / sides as f64).cos();
            let radial: Vec<DVec2> = s.iter().map(|&s| dir * (rim - s)).collect();
            let w = worst(&kernel, &e, &wall);
            let k = worst(&kernel, &e, &corner);
            let r = worst(&kernel, &c, &radial);
            eprintln!(
                "h/dx = {hk}: |integrated - geometric| wall {w:e}, corner {k:e}, circle {r:e}"
            );
            assert!(w < 1e-10 && k < 1e-10 && r < 1e-10, "{w:e} {k:e} {r:e}");
        }
        // Exact values on the wall and at the corner.
        let kernel = Wendland::new(2.0 * dx, 2);
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let on = |x: DVec2| {
            gamma_by_path(&kernel, x, &e, &grid, 1e-13, 10.0)
                .unwrap()
                .gamma
        };
        assert!((on(DVec2::new(0.5, 0.0)) - 0.5).abs() < 1e-10);
        assert!((on(DVec2::new(0.0, 0.0)) - 0.25).abs() < 1e-10);
        assert!((on(DVec2::new(0.5, 0.5)) - 1.0).abs() == 0.0);
    }

    #[test]
    fn a_blocked_direction_falls_back_and_no_path_is_a_named_error() {
        // A reservoir with a narrow outlet channel (height 0.12 < 2 * support): at the middle
        // of the channel grad gamma vanishes by symmetry and the first fallback direction (+x)
        // runs into the channel's end, so the path must turn back into the reservoir.
        let poly = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 0.44),
            DVec2::new(1.6, 0.44),
            DVec2::new(1.6, 0.56),
            DVec2::new(1.0, 0.56),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let e = walls(polyline_elements(&poly, true, 0.01));
        let kernel = Wendland::new(0.05, 2);
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let x = DVec2::new(1.3, 0.5);
        let p = gamma_by_path(&kernel, x, &e, &grid, 1e-13, 10.0).unwrap();
        let g = geometric_shepard::gamma(&kernel, x, &e, &grid);
        assert!(p.direction.x < -0.9, "{:?}", p.direction);
        assert!(g < 0.99 && (p.gamma - g).abs() < 1e-10, "{} {g}", p.gamma);
        // A closed narrow channel alone: no point with gamma = 1 anywhere.
        let e = walls(box_elements_2d(
            DVec2::ZERO,
            DVec2::new(1.0, 0.16),
            &[],
            0.01,
        ));
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let err = gamma_by_path(&kernel, DVec2::new(0.5, 0.08), &e, &grid, 1e-13, 10.0);
        assert!(err.unwrap_err().contains("narrower than 2h"));
        let err = gamma_by_path::<glam::DVec3>(
            &kernel,
            glam::DVec3::ZERO,
            &BoundaryElements::default(),
            &CellGrid::new(0.1),
            1e-13,
            1.0,
        );
        assert!(err.unwrap_err().contains("2-D only"));
    }
}
