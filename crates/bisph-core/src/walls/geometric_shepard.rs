//! The geometric Shepard factor (paper 2): `gamma(x) = int_Omega W(y - x) dy` computed from
//! the wall elements alone, so free surfaces do not change it.
//!
//! With `W = div(r What(|r|))`, `What(rho) = rho^-d int_0^rho s^(d-1) W(s) ds` (paper 2, eq 9),
//! and splitting off the point-source part `1 / (A_d rho^d)` (whose flux through a closed
//! boundary is exactly 1), `gamma(x) = 1 + sum_j r_n,j int_{S_j} F(|y - x|) dS` with normals
//! out of the fluid, `r_n,j = (c_j - x) . n_j` and, inside the support (zero beyond),
//! `F(q) = [q^5/32 - 35q^4/128 + 7q^3/8 - 35q^2/32 + 7/8] / (pi h^2) - 1 / (2 pi q^2 h^2)` in 2-D
//! (the sign of the polynomial part corrected from the paper's printed eq 11).
//!
//! 2-D segments are integrated in closed form: each segment is clipped to the support circle,
//! the polynomial part uses `int (a^2 + u^2)^(k/2) du` exactly, and the divergent part is
//! `-theta / (2 pi)` with `theta` the signed angle the clipped segment subtends (paper 2,
//! eqs 13-15). A point on a wall is evaluated a distance `1e-9 h` inside the fluid, the limit
//! from the fluid side (`gamma = 1/2` on a flat wall, `1/4` at a right-angled corner).
//! 3-D patches use a one-point polynomial rule and the exact solid angle (see
//! [`patch_contribution`]).

use super::BoundaryElements;
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::CellGrid;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// `int_0^u (a^2 + t^2)^(k/2) dt` for `k = 0, 2, 3, 4, 5`, as `[I0, I2, I3, I4, I5]`.
pub(crate) fn radial_moments(a: f64, u: f64) -> [f64; 5] {
    let (a2, u2) = (a * a, u * u);
    let rho = (a2 + u2).sqrt();
    let log_term = if a == 0.0 { 0.0 } else { (u / a.abs()).asinh() };
    let i0 = u;
    let i2 = a2 * u + u * u2 / 3.0;
    let i3 = u * (2.0 * u2 + 5.0 * a2) * rho / 8.0 + 3.0 * a2 * a2 / 8.0 * log_term;
    let i4 = a2 * a2 * u + 2.0 * a2 * u * u2 / 3.0 + u * u2 * u2 / 5.0;
    let i5 = u * (8.0 * u2 * u2 + 26.0 * a2 * u2 + 33.0 * a2 * a2) * rho / 48.0
        + 5.0 * a2 * a2 * a2 / 16.0 * log_term;
    [i0, i2, i3, i4, i5]
}

/// `int F_P(q) dl` (in units of `h`) along the line at distance `a` from the point, from
/// foot offset `u0` to `u1` (all lengths in units of `h`); `F_P` the polynomial part.
fn polynomial_integral(a: f64, u0: f64, u1: f64) -> f64 {
    let m1 = radial_moments(a, u1);
    let m0 = radial_moments(a, u0);
    let d: Vec<f64> = m1.iter().zip(&m0).map(|(x, y)| x - y).collect();
    // [q^5/32 - 35q^4/128 + 7q^3/8 - 35q^2/32 + 7/8] / pi
    (d[4] / 32.0 - 35.0 * d[3] / 128.0 + 7.0 * d[2] / 8.0 - 35.0 * d[1] / 32.0 + 7.0 * d[0] / 8.0)
        / PI
}

/// Contribution of the segment `p0 -> p1` with outward normal `n` to `gamma(x) - 1`.
pub fn segment_contribution(kernel: &Wendland, x: DVec2, p0: DVec2, p1: DVec2, n: DVec2) -> f64 {
    let h = kernel.h;
    let d = p1 - p0;
    let length = d.length();
    if length == 0.0 {
        return 0.0;
    }
    let t = d / length;
    // Work in units of h, with the foot of the perpendicular from x as origin along t.
    let a = (p0 - x).dot(n) / h; // signed normal distance, > 0 on the fluid side
    let s0 = (p0 - x).dot(t) / h;
    let s1 = s0 + length / h;
    let half_chord2 = 4.0 - a * a;
    if half_chord2 <= 0.0 {
        return 0.0;
    }
    let half_chord = half_chord2.sqrt();
    let (u0, u1) = (s0.max(-half_chord), s1.min(half_chord));
    if u0 >= u1 {
        return 0.0;
    }
    let polynomial = a * polynomial_integral(a.abs(), u0, u1);
    // Signed angle subtended by the clipped segment: atan(u1/a) - atan(u0/a).
    let theta = if a == 0.0 {
        0.0
    } else {
        (u1 / a).atan() - (u0 / a).atan()
    };
    polynomial - theta / (2.0 * PI)
}

/// Contribution of the planar quadrilateral patch `corners` (3-D) with outward normal `n`
/// to `gamma(x) - 1`: `r_n F_P(q) s / h^3` at the patch centre (one-point rule) minus
/// `Omega / (4 pi)`, the exact solid angle the patch subtends (two triangles by the
/// Van Oosterom-Strackee formula), signed positive on the fluid side. Elements whose
/// centre lies beyond the support are skipped. An approximation of paper 2's eqs 16-17
/// that is exact in the limit of small patches.
pub fn patch_contribution(
    kernel: &Wendland,
    x: DVec3,
    corners: &[DVec3],
    n: DVec3,
    area: f64,
) -> f64 {
    let h = kernel.h;
    let centre = corners.iter().copied().sum::<DVec3>() / corners.len() as f64;
    let r = centre - x;
    let q = r.length() / h;
    if q >= 2.0 {
        return 0.0;
    }
    let rn = r.dot(n);
    let polynomial = (21.0 * q.powi(5) / 1024.0 - 45.0 * q.powi(4) / 256.0
        + 35.0 * q.powi(3) / 64.0
        - 21.0 * q * q / 32.0
        + 7.0 / 16.0)
        / PI;
    let mut omega = 0.0;
    for k in 1..corners.len() - 1 {
        omega += triangle_solid_angle(corners[0] - x, corners[k] - x, corners[k + 1] - x).abs();
    }
    rn * polynomial * area / (h * h * h) - rn.signum() * omega / (4.0 * PI)
}

/// Solid angle subtended by the triangle with corners at `a`, `b`, `c` (relative to the
/// viewpoint), Van Oosterom & Strackee (1983); signed by the corner order.
pub fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let numerator = a.dot(b.cross(c));
    let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * numerator.atan2(denominator)
}

/// Geometric Shepard factor at `x` from the wall elements near it (paper 2, eq 8).
///
/// A point on a wall element is first moved `1e-9 h` into the fluid (the one-sided limit).
pub fn gamma<V: Vector>(
    kernel: &Wendland,
    x: V,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
) -> f64 {
    let mut x = x;
    let eps = 1e-9 * kernel.h;
    grid.for_each_candidate(x, |j| {
        let r = elements.centre[j] - x;
        let rn = r.dot(elements.normal[j]);
        if rn.abs() < eps
            && (r - elements.normal[j] * rn).length() <= elements.reach[j] * (1.0 + 1e-12)
        {
            x -= elements.normal[j] * eps;
        }
    });
    let mut gamma = 1.0;
    grid.for_each_candidate(x, |j| {
        gamma += V::wall_gamma_contribution(
            kernel,
            x,
            elements.current_corners(j),
            elements.normal[j],
            elements.area[j],
        );
    });
    gamma
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::box_elements_2d;

    #[test]
    fn radial_moments_match_quadrature() {
        for &a in &[0.0, 0.3, 1.7] {
            let u = 1.3;
            let n = 200_000;
            let mut num = [0.0; 5];
            for k in 0..n {
                let t = (k as f64 + 0.5) * u / n as f64;
                let rho = (a * a + t * t).sqrt();
                for (m, p) in num.iter_mut().zip([0, 2, 3, 4, 5]) {
                    *m += rho.powi(p) * u / n as f64;
                }
            }
            let exact = radial_moments(a, u);
            for k in 0..5 {
                assert!(
                    (num[k] - exact[k]).abs() < 1e-8 * (1.0 + exact[k].abs()),
                    "a={a} k={k}"
                );
            }
        }
    }

    /// Composite 8-point Gauss-Legendre rule of `f` over `[a, b]` with `panels` panels.
    fn gauss(a: f64, b: f64, panels: usize, mut f: impl FnMut(f64) -> f64) -> f64 {
        const X: [f64; 4] = [
            0.1834346424956498,
            0.525532409916329,
            0.7966664774136267,
            0.9602898564975363,
        ];
        const W: [f64; 4] = [
            0.362683783378362,
            0.3137066458778873,
            0.2223810344533745,
            0.1012285362903763,
        ];
        let width = (b - a) / panels as f64;
        let mut sum = 0.0;
        for p in 0..panels {
            let mid = a + (p as f64 + 0.5) * width;
            for k in 0..4 {
                let d = 0.5 * width * X[k];
                sum += W[k] * 0.5 * width * (f(mid - d) + f(mid + d));
            }
        }
        sum
    }

    /// Area integral of W over the box's interior within the support of `x`, by iterated
    /// Gauss quadrature over exact limits (the integrand is smooth inside them).
    fn reference_gamma(kernel: &Wendland, x: DVec2, lo: DVec2, hi: DVec2) -> f64 {
        let s = kernel.support;
        let (y0, y1) = ((x.y - s).max(lo.y), (x.y + s).min(hi.y));
        gauss(y0, y1, 64, |y| {
            let half = (s * s - (y - x.y) * (y - x.y)).max(0.0).sqrt();
            let (x0, x1) = ((x.x - half).max(lo.x), (x.x + half).min(hi.x));
            if x1 <= x0 {
                return 0.0;
            }
            gauss(x0, x1, 64, |xx| {
                kernel.value(DVec2::new(xx - x.x, y - x.y).length())
            })
        })
    }

    #[test]
    fn matches_area_integral_near_walls_and_corners() {
        let (lo, hi) = (DVec2::ZERO, DVec2::new(1.0, 1.0));
        let dx = 0.01;
        let kernel = Wendland::new(0.02, 2);
        let mut e = BoundaryElements::default();
        for s in box_elements_2d(lo, hi, &[], dx) {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        for &(x, y) in &[
            (0.5, 0.013),
            (0.5, 0.031),
            (0.007, 0.021),
            (0.011, 0.013),
            (0.5, 0.5),
            (0.5, 0.0399),
        ] {
            let p = DVec2::new(x, y);
            let g = gamma(&kernel, p, &e, &grid);
            let r = reference_gamma(&kernel, p, lo, hi);
            assert!((g - r).abs() < 1e-9, "({x},{y}): {g} vs {r}");
        }
        // On the wall and at a corner: exact limits.
        assert!((gamma(&kernel, DVec2::new(0.5, 0.0), &e, &grid) - 0.5).abs() < 1e-8);
        assert!((gamma(&kernel, DVec2::new(0.503, 0.0), &e, &grid) - 0.5).abs() < 1e-8);
        assert!((gamma(&kernel, DVec2::new(0.0, 0.0), &e, &grid) - 0.25).abs() < 1e-8);
    }
}
