//! 3-D elements: planar polygons (triangles, quadrilateral patches, outlines of merged planar
//! regions).
//!
//! The Shepard contribution `r_n int_{S cap B} F dS` (paper 2, eqs 8 and 16-17) is exact: the
//! element is clipped to the support sphere and integrated in polar coordinates about the foot
//! of the perpendicular from `x`, one fan triangle (foot, edge) per edge ([`edge_integral`]),
//! so the sum over a region needs only its outline. The divergent part of `F` gives
//! `-Omega / (4 pi)`, `Omega` the solid angle of the clipped element ([`triangle_solid_angle`]
//! for a whole triangle). The kernel integral, and the Shepard contribution where both are
//! wanted together, use the triangle polar rule of [`super::polar`].

use super::polar;
use super::ElementIntegrals;
use crate::kernel::Wendland;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// `Phi(q) = int q F_P(q) dq` (3-D, kernel units), the radial antiderivative of the polynomial
/// part of the 3-D `F` (paper 2, eq 9, sign corrected): `int_0^rho F_P(q) rho' drho' = Phi(q(rho)) - Phi(|a|)` with `q^2 = a^2 + rho^2`.
fn phi3(q: f64) -> f64 {
    let q2 = q * q;
    let q4 = q2 * q2;
    (7.0 * q2 / 32.0 - 21.0 * q4 / 128.0 + 7.0 * q4 * q / 64.0 - 15.0 * q4 * q2 / 512.0
        + 3.0 * q4 * q2 * q / 1024.0)
        / PI
}

/// Antiderivatives `int_0^t (A + s^2)^(k/2) ds` for `k = -1, 0, 1, 2, 3, 4, 5` (`A > 0`), the
/// moments of [`edge_integral`] (paper 2, eqs 16-17).
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
        let i: [f64; 7] = std::array::from_fn(|k| m1[k] - m0[k]);
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

/// Shepard contribution of the planar polygon `corners` (a triangle or a quadrilateral patch,
/// at most 8 corners) with outward normal `n` to `gamma(x) - 1`, `r_n int_{S cap B} F(|y - x|) dS` (paper 2, eqs 8 and
/// 16-17), exact: the element is clipped to the support sphere and integrated in polar
/// coordinates about the foot of the perpendicular from `x`, one fan triangle per edge
/// ([`edge_integral`]); the divergent part is `-Omega/(4 pi)` with `Omega` the solid angle of
/// the clipped element, signed positive on the fluid side. Holds for triangles and for square
/// patches alike, and for a foot inside or outside the element.
pub fn polygon_shepard(kernel: &Wendland, x: DVec3, corners: &[DVec3], n: DVec3) -> f64 {
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
        sum += edge_term(a, p0, p1);
    }
    if twice_area < 0.0 {
        -sum
    } else {
        sum
    }
}

/// The fan triangle of the edge `p0 -> p1` ([`edge_integral`], paper 2, eqs 16-17), its ends given in the plane
/// relative to the foot of the perpendicular, in units of `h`.
fn edge_term(a: f64, p0: DVec2, p1: DVec2) -> f64 {
    let edge = p1 - p0;
    let length = edge.length();
    if length == 0.0 {
        return 0.0;
    }
    let tau = edge / length;
    // `p0 x p1 / L`: exactly antisymmetric, so an edge shared by two elements cancels.
    let d = p0.perp_dot(p1) / length;
    if d == 0.0 {
        return 0.0; // the foot is on this edge's line: an empty fan triangle
    }
    // Both ends from their own offsets: exact when a corner is next to the foot.
    edge_integral(a, d, p0.dot(tau), p1.dot(tau))
}

/// Shepard contribution to `gamma(x) - 1` of a planar region with outward normal `n` given by its
/// boundary edges, `edges[2k] -> edges[2k + 1]`, oriented counter-clockwise about `n`
/// (paper 2, eqs 8 and 16-17): the sum of their fan triangles, as in
/// [`polygon_shepard`], for any union of coplanar elements (edges shared by two of them
/// cancel, so only the region's outline is needed).
pub fn outline_shepard(kernel: &Wendland, x: DVec3, edges: &[DVec3], n: DVec3) -> f64 {
    let h = kernel.h;
    let Some(&p) = edges.first() else {
        return 0.0;
    };
    let a = (p - x).dot(n) / h;
    if a.abs() >= 2.0 {
        return 0.0;
    }
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let foot = x + n * (a * h);
    let local = |c: DVec3| {
        let r = (c - foot) / h;
        DVec2::new(r.dot(e1), r.dot(e2))
    };
    edges
        .chunks_exact(2)
        .map(|e| edge_term(a, local(e[0]), local(e[1])))
        .sum()
}

/// Solid angle subtended by the triangle with corners at `a`, `b`, `c` (relative to the
/// viewpoint), Van Oosterom & Strackee (1983); signed by the corner order.
pub fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let numerator = a.dot(b.cross(c));
    let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * numerator.atan2(denominator)
}

/// Closest point on the triangle `tri` to `x` (Ericson, Real-Time Collision Detection 5.1.5).
pub fn closest_point_on_triangle(x: DVec3, tri: [DVec3; 3]) -> DVec3 {
    let [a, b, c] = tri;
    let (ab, ac, ap) = (b - a, c - a, x - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = x - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = x - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// `true` when the segment `p q` touches the closed triangle `tri`.
pub fn segment_touches_triangle(p: DVec3, q: DVec3, tri: [DVec3; 3]) -> bool {
    let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    let (dp, dq) = ((p - tri[0]).dot(n), (q - tri[0]).dot(n));
    if (dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) {
        return false;
    }
    if dp == dq {
        // Both ends in the plane: touching iff the closest distance is zero.
        return closest_point_on_triangle(p, tri) == p || closest_point_on_triangle(q, tri) == q;
    }
    let s = dp / (dp - dq);
    let y = p + (q - p) * s;
    // Inside test by same-sign edge functions (closed).
    let mut sign = 0.0;
    for k in 0..3 {
        let (u, v) = (tri[k], tri[(k + 1) % 3]);
        let e = (v - u).cross(y - u).dot(n);
        if e != 0.0 {
            if sign != 0.0 && e.signum() != sign {
                return false;
            }
            sign = e.signum();
        }
    }
    true
}

impl ElementIntegrals for DVec3 {
    #[inline(always)]
    fn shepard(kernel: &Wendland, x: Self, corners: &[Self], normal: Self) -> f64 {
        polygon_shepard(kernel, x, corners, normal)
    }
    #[inline(always)]
    fn outline_shepard(kernel: &Wendland, x: Self, outline: &[Self], normal: Self) -> f64 {
        outline_shepard(kernel, x, outline, normal)
    }
    fn kernel_integral(kernel: &Wendland, x: Self, corners: &[Self], radius: f64) -> f64 {
        polar::kernel_integral(kernel, x, corners, radius)
    }
    fn gauss_rule(corners: &[Self], out: &mut Vec<(Self, f64)>) {
        super::gauss::polygon_rule(corners, out)
    }
    fn polar_shepard(kernel: &Wendland, x: Self, corners: &[Self], normal: Self) -> f64 {
        polar::shepard(kernel, x, corners, normal)
    }
    fn shepard_and_kernel_integral(
        kernel: &Wendland,
        x: Self,
        corners: &[Self],
        normal: Self,
    ) -> (f64, f64) {
        polar::shepard_and_kernel_integral(kernel, x, corners, normal)
    }
    fn element_distance(x: Self, corners: &[Self]) -> f64 {
        polar::fan(corners)
            .map(|tri| (closest_point_on_triangle(x, tri) - x).length())
            .fold(f64::INFINITY, f64::min)
    }
    fn path_crosses_element(from: Self, to: Self, corners: &[Self]) -> bool {
        polar::fan(corners).any(|tri| segment_touches_triangle(from, to, tri))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let exact = polygon_shepard(&kernel, x, &corners, n);
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

    #[test]
    fn segments_touch_triangles_and_distances() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(segment_touches_triangle(
            DVec3::new(0.2, 0.2, -1.0),
            DVec3::new(0.2, 0.2, 1.0),
            tri
        ));
        assert!(!segment_touches_triangle(
            DVec3::new(0.8, 0.8, -1.0),
            DVec3::new(0.8, 0.8, 1.0),
            tri
        ));
        assert!(segment_touches_triangle(
            DVec3::new(0.2, 0.2, 1.0),
            DVec3::new(0.2, 0.2, 0.0),
            tri
        ));
        assert!((DVec3::element_distance(DVec3::new(0.2, 0.2, 0.3), &tri) - 0.3).abs() < 1e-15);
        assert!((DVec3::element_distance(DVec3::new(2.0, 0.0, 0.0), &tri) - 1.0).abs() < 1e-15);
    }
}
