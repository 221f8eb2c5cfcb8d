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
//! eqs 13-15). A point on a wall is evaluated a distance `1e-12 h` inside the fluid, the limit
//! from the fluid side (`gamma = 1/2` on a flat wall, `1/4` at a right-angled corner).
//! 3-D planar elements (triangles, quadrilateral patches) are integrated exactly as well, in
//! polar coordinates about the foot of the perpendicular (see [`patch_contribution`]), with
//! `F = [21q^5/1024 - 45q^4/256 + 35q^3/64 - 21q^2/32 + 7/16] / (pi h^3) - 1 / (4 pi q^3 h^3)`.

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
                                 // Both ends from their own offsets (not `s0 + length`): exact near a corner at `x`.
    let s0 = (p0 - x).dot(t) / h;
    let s1 = (p1 - x).dot(t) / h;
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

/// `Phi(q) = int q F_P(q) dq` (3-D, kernel units), the radial antiderivative of the polynomial
/// part: `int_0^rho F_P(q) rho' drho' = Phi(q(rho)) - Phi(|a|)` with `q^2 = a^2 + rho^2`.
fn phi3(q: f64) -> f64 {
    let q2 = q * q;
    let q4 = q2 * q2;
    (7.0 * q2 / 32.0 - 21.0 * q4 / 128.0 + 7.0 * q4 * q / 64.0 - 15.0 * q4 * q2 / 512.0
        + 3.0 * q4 * q2 * q / 1024.0)
        / PI
}

/// Antiderivatives `int_0^t (A + s^2)^(k/2) ds` for `k = -1, 0, 1, 2, 3, 4, 5` (`A > 0`).
fn moments3(big_a: f64, t: f64) -> [f64; 7] {
    let t2 = t * t;
    let r = (big_a + t2).sqrt();
    let ash = (t / big_a.sqrt()).asinh();
    [
        ash,
        t,
        0.5 * (t * r + big_a * ash),
        big_a * t + t * t2 / 3.0,
        t * (2.0 * t2 + 5.0 * big_a) * r / 8.0 + 3.0 * big_a * big_a / 8.0 * ash,
        big_a * big_a * t + 2.0 * big_a * t * t2 / 3.0 + t * t2 * t2 / 5.0,
        t * (8.0 * t2 * t2 + 26.0 * big_a * t2 + 33.0 * big_a * big_a) * r / 48.0
            + 5.0 * big_a * big_a * big_a / 16.0 * ash,
    ]
}

/// Fan triangle of one polygon edge (paper 2, eqs 16-17, integrated exactly): the part of the
/// triangle (foot of the perpendicular, `p(t0)`, `p(t1)`) inside the support, with the edge
/// line `p(t) = d nu + t tau` at signed in-plane distance `d` (> 0 counter-clockwise) and the
/// point at signed height `a` (> 0 on the fluid side), all in units of `h`. Returns
/// `a int F(q) dS` over it, `F = F_P - 1/(4 pi q^3)`.
///
/// In polar coordinates about the foot, `a int_0^rho_max F rho drho` is
/// `a [Phi(Q) - Phi(|a|)] - sign(a) (1 - |a|/Q) / (4 pi)` with `Q = q(rho_max)`; on the edge
/// `dtheta = d dt / (d^2 + t^2)`, and `int (A + t^2)^(k/2) / (d^2 + t^2) dt`, `A = a^2 + d^2`,
/// follows from `f_k = (A + t^2)^(k/2 - 1) + a^2 f_(k-2)` down to `atan` terms. Where the edge
/// leaves the support the remaining angle sees `Q = 2`.
fn edge_integral(a: f64, d: f64, t0: f64, t1: f64) -> f64 {
    let sa = if a >= 0.0 { 1.0 } else { -1.0 };
    let (aa, ad) = (a.abs(), d.abs());
    let rb2 = 4.0 - a * a;
    let phi_a = phi3(aa);
    let arc_value = a * (phi3(2.0) - phi_a) - sa * (1.0 - 0.5 * aa) / (4.0 * PI);
    let angle = |t: f64| (t / d).atan();
    if ad * ad >= rb2 {
        return arc_value * (angle(t1) - angle(t0));
    }
    let tb = (rb2 - d * d).sqrt();
    let mut total = 0.0;
    if t0 < -tb {
        total += arc_value * (angle(t1.min(-tb)) - angle(t0));
    }
    if t1 > tb {
        total += arc_value * (angle(t1) - angle(t0.max(tb)));
    }
    let (u0, u1) = (t0.max(-tb), t1.min(tb));
    if u0 < u1 {
        let a2 = a * a;
        let big_a = a2 + d * d;
        let (m1, m0) = (moments3(big_a, u1), moments3(big_a, u0));
        let i: Vec<f64> = m1.iter().zip(&m0).map(|(x, y)| x - y).collect();
        let e0 = angle(u1) - angle(u0);
        let tilt = |t: f64| (aa * t).atan2(ad * (big_a + t * t).sqrt());
        // |a| d int dt / ((d^2 + t^2) sqrt(A + t^2)).
        let g = d.signum() * (tilt(u1) - tilt(u0));
        let e2 = d * i[1] + a2 * e0;
        let e4 = d * i[3] + a2 * e2;
        let e6 = d * i[5] + a2 * e4;
        let e1 = d * i[0] + aa * g;
        let e3 = d * i[2] + a2 * e1;
        let e5 = d * i[4] + a2 * e3;
        let e7 = d * i[6] + a2 * e5;
        let poly = (7.0 * e2 / 32.0 - 21.0 * e4 / 128.0 + 7.0 * e5 / 64.0 - 15.0 * e6 / 512.0
            + 3.0 * e7 / 1024.0)
            / PI;
        total += a * (poly - phi_a * e0) - sa * (e0 - g) / (4.0 * PI);
    }
    total
}

/// Contribution of the planar polygon `corners` (3-D: a triangle or a quadrilateral patch) with
/// outward normal `n` to `gamma(x) - 1`, `r_n int_{S cap B} F(|y - x|) dS` (paper 2, eqs 8 and
/// 16-17), exact: the element is clipped to the support sphere and integrated in polar
/// coordinates about the foot of the perpendicular from `x`, one fan triangle per edge
/// ([`edge_integral`]); the divergent part is `-Omega/(4 pi)` with `Omega` the solid angle of
/// the clipped element, signed positive on the fluid side. Holds for triangles and for square
/// patches alike, and for a foot inside or outside the element.
pub fn patch_contribution(
    kernel: &Wendland,
    x: DVec3,
    corners: &[DVec3],
    n: DVec3,
    _area: f64,
) -> f64 {
    let h = kernel.h;
    if corners.len() < 3 {
        return 0.0;
    }
    let a = (corners[0] - x).dot(n) / h;
    if a.abs() >= 2.0 {
        return 0.0;
    }
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let foot = x + n * (a * h);
    let mut pts = [DVec2::ZERO; 8];
    let m = corners.len().min(8);
    for (p, &c) in pts.iter_mut().zip(corners) {
        let r = (c - foot) / h;
        *p = DVec2::new(r.dot(e1), r.dot(e2));
    }
    let pts = &pts[..m];
    let centroid = pts.iter().copied().sum::<DVec2>() / m as f64;
    let radius = pts
        .iter()
        .map(|&p| (p - centroid).length())
        .fold(0.0, f64::max);
    let rb = (4.0 - a * a).sqrt();
    if centroid.length() - radius >= rb {
        return 0.0;
    }
    let mut twice_area = 0.0;
    let mut sum = 0.0;
    for k in 0..m {
        let (p0, p1) = (pts[k], pts[(k + 1) % m]);
        twice_area += p0.perp_dot(p1);
        let edge = p1 - p0;
        let length = edge.length();
        if length == 0.0 {
            continue;
        }
        let tau = edge / length;
        // `p0 x p1 / L`: exactly antisymmetric, so an edge shared by two elements cancels.
        let d = p0.perp_dot(p1) / length;
        if d == 0.0 {
            continue; // the foot is on this edge's line: an empty fan triangle
        }
        // Both ends from their own offsets: exact when a corner is next to the foot.
        sum += edge_integral(a, d, p0.dot(tau), p1.dot(tau));
    }
    if twice_area < 0.0 {
        -sum
    } else {
        sum
    }
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
/// A point on a wall element is first moved `1e-12 h` into the fluid, along the sum of the
/// inward normals of the elements it lies on (the one-sided limit, exact to about `1e-12`).
/// Every element that overlaps the support is visited, whatever the grid's cell size.
pub fn gamma<V: Vector>(
    kernel: &Wendland,
    x: V,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
) -> f64 {
    let eps = 1e-12 * kernel.h;
    let radius = kernel.support + elements.max_reach;
    // One walk sums the contributions and finds the elements the point lies on; only such a
    // point (rare) is moved and summed again.
    let sum_at = |x: V, shift: &mut V| {
        let mut gamma = 1.0;
        // Periodic axes: the grid hands each element's image shift; the element's corners are
        // stored at its own image, so the point is moved instead (minimum image).
        grid.for_each_candidate_within_shifted(x, radius, |j, image| {
            let r = elements.centre[j] + image - x;
            let reach = elements.reach[j];
            if r.length_squared() > (kernel.support + reach) * (kernel.support + reach) {
                return;
            }
            let rn = r.dot(elements.normal[j]);
            if rn.abs() < eps && (r - elements.normal[j] * rn).length() <= reach * (1.0 + 1e-12) {
                *shift -= elements.normal[j] * eps;
            }
            gamma += V::wall_gamma_contribution(
                kernel,
                x - image,
                elements.current_corners(j),
                elements.normal[j],
                elements.area[j],
            );
        });
        gamma
    };
    let mut shift = V::ZERO;
    let gamma = sum_at(x, &mut shift);
    if shift == V::ZERO {
        return gamma;
    }
    let mut unused = V::ZERO;
    sum_at(x + shift, &mut unused)
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

    use crate::quadrature::gauss_legendre as gauss;

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
        assert!((gamma(&kernel, DVec2::new(0.5, 0.0), &e, &grid) - 0.5).abs() < 1e-10);
        assert!((gamma(&kernel, DVec2::new(0.503, 0.0), &e, &grid) - 0.5).abs() < 1e-10);
        assert!((gamma(&kernel, DVec2::new(0.0, 0.0), &e, &grid) - 0.25).abs() < 1e-10);
        assert!((gamma(&kernel, DVec2::new(1.0, 1.0), &e, &grid) - 0.25).abs() < 1e-10);
    }

    /// Volume integral of W over the box's interior within the support of `x`: iterated Gauss
    /// quadrature over exact limits, each range split at the point's own coordinate.
    fn reference_gamma_3d(kernel: &Wendland, x: DVec3, lo: DVec3, hi: DVec3) -> f64 {
        let s = kernel.support;
        let split = |a: f64, b: f64, c: f64, panels: usize, f: &mut dyn FnMut(f64) -> f64| {
            if b <= a {
                return 0.0;
            }
            if c > a && c < b {
                gauss(a, c, panels, &mut *f) + gauss(c, b, panels, &mut *f)
            } else {
                gauss(a, b, panels, &mut *f)
            }
        };
        let panels = 10;
        split(
            (x.z - s).max(lo.z),
            (x.z + s).min(hi.z),
            x.z,
            panels,
            &mut |z| {
                let dz = z - x.z;
                let ry = (s * s - dz * dz).max(0.0).sqrt();
                split(
                    (x.y - ry).max(lo.y),
                    (x.y + ry).min(hi.y),
                    x.y,
                    panels,
                    &mut |y| {
                        let dy = y - x.y;
                        let rx = (s * s - dz * dz - dy * dy).max(0.0).sqrt();
                        split(
                            (x.x - rx).max(lo.x),
                            (x.x + rx).min(hi.x),
                            x.x,
                            panels,
                            &mut |xx| kernel.value(DVec3::new(xx - x.x, dy, dz).length()),
                        )
                    },
                )
            },
        )
    }

    fn walls_3d(shapes: Vec<crate::geometry::ElementShape<DVec3>>) -> BoundaryElements<DVec3> {
        let mut e = BoundaryElements::default();
        for s in shapes {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        e
    }

    /// The unit cube's walls three ways: square patches, triangles, and faces with patches of
    /// unequal sizes.
    fn cube_walls(dx: f64) -> Vec<(&'static str, BoundaryElements<DVec3>)> {
        use crate::geometry::{box_elements_3d, rectangle_elements, triangulate};
        let (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        let patches = box_elements_3d(lo, hi, &[], dx);
        let triangles = triangulate(patches.clone());
        let mut mixed = Vec::new();
        for k in 0..6 {
            let axis = k / 2;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut origin = lo;
            let mut normal = DVec3::ZERO;
            normal[axis] = if k % 2 == 1 { 1.0 } else { -1.0 };
            if k % 2 == 1 {
                origin[axis] = hi[axis];
            }
            let (mut e1, mut e2) = (DVec3::ZERO, DVec3::ZERO);
            e1[u] = 1.0;
            e2[v] = 1.0;
            let size = dx * [1.0, 0.73, 1.31][axis];
            let face = rectangle_elements(origin, e1, e2, normal, size);
            mixed.extend(if k % 2 == 0 { triangulate(face) } else { face });
        }
        vec![
            ("square patches", walls_3d(patches)),
            ("triangles", walls_3d(triangles)),
            ("unequal mixed elements", walls_3d(mixed)),
        ]
    }

    #[test]
    fn exact_3d_limits_on_walls_edges_and_corners() {
        let kernel = Wendland::new(0.1, 3);
        for (name, e) in cube_walls(0.05) {
            let mut grid = CellGrid::new(kernel.support);
            grid.rebuild(&e.centre);
            let g = |x: f64, y: f64, z: f64| gamma(&kernel, DVec3::new(x, y, z), &e, &grid);
            for (p, expected) in [
                ((0.5, 0.5, 0.0), 0.5),
                ((0.5, 0.5, 1.0), 0.5),
                ((0.525, 0.5, 0.0), 0.5), // a patch edge or a triangle diagonal
                ((0.55, 0.45, 1.0), 0.5), // a patch vertex
                ((0.313, 0.0, 0.77), 0.5), // anywhere
                ((0.5, 0.0, 0.0), 0.25),
                ((1.0, 0.37, 1.0), 0.25),
                ((0.0, 0.0, 0.0), 0.125),
                ((1.0, 1.0, 1.0), 0.125),
                ((1.0, 0.0, 1.0), 0.125),
                ((0.5, 0.5, 0.5), 1.0),
            ] {
                let v = g(p.0, p.1, p.2);
                assert!(
                    (v - expected).abs() < 1e-10,
                    "{name} at {p:?}: {v} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn exact_3d_matches_volume_integral_near_walls_edges_and_corners() {
        let kernel = Wendland::new(0.1, 3);
        let points = [
            DVec3::new(0.5, 0.5, 0.03),
            DVec3::new(0.51, 0.47, 0.17),
            DVec3::new(0.5, 0.02, 0.05),
            DVec3::new(0.03, 0.02, 0.05),
            DVec3::new(0.013, 0.171, 0.007),
            DVec3::new(0.96, 0.99, 0.93),
        ];
        let refs: Vec<f64> = points
            .iter()
            .map(|&p| reference_gamma_3d(&kernel, p, DVec3::ZERO, DVec3::ONE))
            .collect();
        for (name, e) in cube_walls(0.05) {
            let mut grid = CellGrid::new(kernel.support);
            grid.rebuild(&e.centre);
            for (&p, &r) in points.iter().zip(&refs) {
                let v = gamma(&kernel, p, &e, &grid);
                eprintln!(
                    "{name} at {p}: gamma {v:.15} reference {r:.15} diff {:.2e}",
                    v - r
                );
                assert!((v - r).abs() < 1e-10, "{name} at {p}: {v} vs {r}");
            }
        }
    }

    #[test]
    fn divergent_part_is_the_solid_angle_of_a_small_element() {
        // An element entirely inside the support: the divergent part of the exact integral is
        // -Omega / 4 pi, Omega from Van Oosterom-Strackee; the polynomial part is smooth.
        let kernel = Wendland::new(1.0, 3);
        let corners = [
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::new(0.4, 0.1, 0.3),
            DVec3::new(-0.1, 0.3, 0.3),
        ];
        let n = DVec3::Z;
        for x in [DVec3::new(0.05, 0.0, 0.0), DVec3::new(0.9, 0.6, -0.2)] {
            let exact = patch_contribution(&kernel, x, &corners, n, 0.0);
            let omega = triangle_solid_angle(corners[0] - x, corners[1] - x, corners[2] - x).abs();
            // Polynomial part by a fine midpoint rule on barycentric sub-triangles.
            let m = 400;
            let mut poly = 0.0;
            let (a, b, c) = (corners[0], corners[1], corners[2]);
            let area = 0.5 * (b - a).cross(c - a).length();
            for i in 0..m {
                for j in 0..m - i {
                    for (u, v, w) in [
                        ((i as f64 + 1.0 / 3.0), (j as f64 + 1.0 / 3.0), 1.0),
                        ((i as f64 + 2.0 / 3.0), (j as f64 + 2.0 / 3.0), -1.0),
                    ] {
                        if w < 0.0 && i + j + 1 >= m {
                            continue;
                        }
                        let y = a + (b - a) * (u / m as f64) + (c - a) * (v / m as f64);
                        let q = (y - x).length();
                        let fp = (21.0 * q.powi(5) / 1024.0 - 45.0 * q.powi(4) / 256.0
                            + 35.0 * q.powi(3) / 64.0
                            - 21.0 * q * q / 32.0
                            + 7.0 / 16.0)
                            / PI;
                        poly += fp * area / (m * m) as f64;
                    }
                }
            }
            let rn = (a - x).dot(n);
            let expected = rn * poly - omega / (4.0 * PI);
            assert!((exact - expected).abs() < 1e-6, "{exact} vs {expected}");
        }
    }
}
