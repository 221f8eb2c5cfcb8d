//! 2-D elements: segments, every integral in closed form.
//!
//! Along the segment's line, with `a` the distance of `x` from it and `u` the offset from the
//! foot of the perpendicular (both in units of `h`), `q = sqrt(a^2 + u^2)`; the segment is
//! clipped to the circle of radius `R` about `x` (`|u| <= sqrt(R^2 - a^2)`) and every
//! polynomial in `q` integrates through the moments `int (a^2 + u^2)^(k/2) du`
//! ([`radial_moments`]). Both ends are measured from `x` by their own offsets, so that a
//! corner at `x` is exact and a reversed segment gives the same integral.

use super::ElementIntegrals;
use crate::dim::Vector;
use crate::kernel::Wendland;
use glam::DVec2;
use std::f64::consts::PI;

/// `int_0^u (a^2 + t^2)^(k/2) dt` for `k = 0, 2, 3, 4, 5`, as `[I0, I2, I3, I4, I5]`: the
/// moments of the 2-D closed forms (paper 2, eqs 13-15).
pub fn radial_moments(a: f64, u: f64) -> [f64; 5] {
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
/// foot offset `u0` to `u1` (all lengths in units of `h`); `F_P` the polynomial part of the
/// 2-D `F` (paper 2, eq 11, sign corrected).
fn polynomial_integral(a: f64, u0: f64, u1: f64) -> f64 {
    let m1 = radial_moments(a, u1);
    let m0 = radial_moments(a, u0);
    let d: [f64; 5] = std::array::from_fn(|k| m1[k] - m0[k]);
    // [q^5/32 - 35q^4/128 + 7q^3/8 - 35q^2/32 + 7/8] / pi
    (d[4] / 32.0 - 35.0 * d[3] / 128.0 + 7.0 * d[2] / 8.0 - 35.0 * d[1] / 32.0 + 7.0 * d[0] / 8.0)
        / PI
}

/// Shepard contribution of the segment `p0 -> p1` with outward normal `n` to `gamma(x) - 1`,
/// `r_n int_S F dl` (paper 2, eqs 8 and 13-15): the segment clipped to the support circle,
/// the polynomial part of `F` from the moments, its divergent part `-theta / (2 pi)` with
/// `theta` the signed angle the clipped segment subtends.
pub fn segment_shepard(kernel: &Wendland, x: DVec2, p0: DVec2, p1: DVec2, n: DVec2) -> f64 {
    let h = kernel.h;
    let d = p1 - p0;
    let length = d.length();
    if length == 0.0 {
        return 0.0;
    }
    let t = d / length;
    // Work in units of h, with the foot of the perpendicular from x as origin along t.
    // Signed normal distance, > 0 on the fluid side.
    let a = (p0 - x).dot(n) / h;
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

/// `int_{u0}^{u1} w(sqrt(a^2 + u^2)) du` in units of `h`, with
/// `w(q) = 1 - 5q^2/2 + 5q^3/2 - 15q^4/16 + q^5/8` (the 2-D Wendland kernel over its
/// normalisation `alpha`).
fn wendland_line_integral(a: f64, u0: f64, u1: f64) -> f64 {
    let m1 = radial_moments(a, u1);
    let m0 = radial_moments(a, u0);
    let d = |k: usize| m1[k] - m0[k];
    d(0) - 2.5 * d(1) + 2.5 * d(2) - 15.0 / 16.0 * d(3) + d(4) / 8.0
}

/// `int W(|y - x|) dl` over the part of a line within `radius` (at most the support) of `x`,
/// between the offsets `s0 < s1` from the foot of the perpendicular, `a` the distance of the
/// line (lengths in units of `h`): with `W = 7/(4 pi h^2) w(q)` for `q < 2` the clipped
/// integral is a sum of the moments [`radial_moments`] (paper 3, eq 9; paper 4, eq 3).
fn clipped_line_kernel_integral(kernel: &Wendland, a: f64, s0: f64, s1: f64, radius: f64) -> f64 {
    let h = kernel.h;
    let rq = radius.min(kernel.support) / h;
    let half_chord2 = rq * rq - a * a;
    if half_chord2 <= 0.0 {
        return 0.0;
    }
    let half_chord = half_chord2.sqrt();
    let (u0, u1) = (s0.max(-half_chord), s1.min(half_chord));
    if u0 >= u1 {
        return 0.0;
    }
    // alpha_2 h = 7 / (4 pi h)
    7.0 / (4.0 * PI * h) * wendland_line_integral(a, u0, u1)
}

/// `int_{p0 p1 cap B(x, radius)} W(|y - x|) dl` for a 2-D segment, in closed form (paper 3,
/// eq 9; paper 4, eq 3), `radius` at most the support; both ends from their own offsets, so a
/// reversed segment gives the same integral.
pub fn segment_kernel_integral(
    kernel: &Wendland,
    x: DVec2,
    p0: DVec2,
    p1: DVec2,
    radius: f64,
) -> f64 {
    let h = kernel.h;
    let d = p1 - p0;
    let length = d.length();
    if length == 0.0 {
        return 0.0;
    }
    let t = d / length;
    let r0 = p0 - x;
    let a = t.perp_dot(r0).abs() / h;
    let (s0, s1) = (r0.dot(t) / h, (p1 - x).dot(t) / h);
    clipped_line_kernel_integral(kernel, a, s0, s1, radius)
}

/// [`segment_kernel_integral`] with the far end at the near end's offset plus the length,
/// `s1 = s0 + L/h`, the form [`ElementIntegrals::kernel_integral`] evaluates for segments
/// (the two differ in the last bits only).
pub fn segment_kernel_integral_from_length(
    kernel: &Wendland,
    x: DVec2,
    p0: DVec2,
    p1: DVec2,
    radius: f64,
) -> f64 {
    let h = kernel.h;
    let d = p1 - p0;
    let length = d.length();
    if length == 0.0 {
        return 0.0;
    }
    let t = d / length;
    let r0 = p0 - x;
    let a = t.perp_dot(r0).abs() / h;
    let s0 = r0.dot(t) / h;
    clipped_line_kernel_integral(kernel, a, s0, s0 + length / h, radius)
}

/// Closest distance from `x` to the segment `p0 p1`.
pub fn point_segment_distance<V: Vector>(x: V, p0: V, p1: V) -> f64 {
    let d = p1 - p0;
    let l2 = d.length_squared();
    let s = if l2 > 0.0 {
        ((x - p0).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p0 + d * s - x).length()
}

/// `true` when the closed segments `a0 a1` and `b0 b1` share a point.
pub fn segments_intersect(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> bool {
    let orient = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    let (d1, d2) = (orient(b0, b1, a0), orient(b0, b1, a1));
    let (d3, d4) = (orient(a0, a1, b0), orient(a0, a1, b1));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on(b0, b1, a0))
        || (d2 == 0.0 && on(b0, b1, a1))
        || (d3 == 0.0 && on(a0, a1, b0))
        || (d4 == 0.0 && on(a0, a1, b1))
}

impl ElementIntegrals for DVec2 {
    #[inline(always)]
    fn shepard(kernel: &Wendland, x: Self, corners: &[Self], normal: Self) -> f64 {
        segment_shepard(kernel, x, corners[0], corners[1], normal)
    }
    #[inline(always)]
    fn outline_shepard(kernel: &Wendland, x: Self, outline: &[Self], normal: Self) -> f64 {
        segment_shepard(kernel, x, outline[0], outline[1], normal)
    }
    fn kernel_integral(kernel: &Wendland, x: Self, corners: &[Self], radius: f64) -> f64 {
        segment_kernel_integral_from_length(kernel, x, corners[0], corners[1], radius)
    }
    fn gauss_rule(corners: &[Self], out: &mut Vec<(Self, f64)>) {
        super::gauss::segment_rule(corners[0], corners[1], out)
    }
    fn polar_shepard(kernel: &Wendland, x: Self, corners: &[Self], normal: Self) -> f64 {
        segment_shepard(kernel, x, corners[0], corners[1], normal)
    }
    fn shepard_and_kernel_integral(
        kernel: &Wendland,
        x: Self,
        corners: &[Self],
        normal: Self,
    ) -> (f64, f64) {
        (
            segment_shepard(kernel, x, corners[0], corners[1], normal),
            segment_kernel_integral_from_length(kernel, x, corners[0], corners[1], kernel.support),
        )
    }
    fn element_distance(x: Self, corners: &[Self]) -> f64 {
        point_segment_distance(x, corners[0], corners[1])
    }
    fn path_crosses_element(from: Self, to: Self, corners: &[Self]) -> bool {
        segments_intersect(from, to, corners[0], corners[1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::gauss_legendre;
    use crate::quadrature::gauss_legendre as gauss_n;

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

    /// Independent reference: composite Gauss-Legendre over the part of the segment inside the
    /// support, split at the foot of the perpendicular (where `W` has a kink for `q0 = 0`).
    fn reference_integral(kernel: &Wendland, x: DVec2, p0: DVec2, p1: DVec2) -> f64 {
        let d = p1 - p0;
        let len = d.length();
        let t = d / len;
        let s_foot = (x - p0).dot(t);
        let dist = ((x - p0) - t * s_foot).length();
        let rb = kernel.support * kernel.support - dist * dist;
        if rb <= 0.0 {
            return 0.0;
        }
        let half = rb.sqrt();
        let (a, b) = ((s_foot - half).max(0.0), (s_foot + half).min(len));
        if a >= b {
            return 0.0;
        }
        let f = |s: f64| kernel.value((p0 + t * s - x).length());
        if s_foot > a && s_foot < b {
            gauss_legendre(a, s_foot, 64, f) + gauss_legendre(s_foot, b, 64, f)
        } else {
            gauss_legendre(a, b, 64, f)
        }
    }

    #[test]
    fn segment_integral_matches_quadrature_to_round_off() {
        let kernel = Wendland::new(0.1, 2);
        let mut worst: f64 = 0.0;
        for &(x, y) in &[
            (0.0, 0.0),
            (0.03, 0.0),
            (0.05, 0.07),
            (-0.13, 0.02),
            (0.31, -0.05),
            (0.1, 0.1999),
            (0.12, 0.001),
        ] {
            for &(p0, p1) in &[
                (DVec2::new(-0.05, 0.0), DVec2::new(0.05, 0.0)),
                (DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0)),
                (DVec2::new(0.0, -0.03), DVec2::new(0.11, 0.08)),
                (DVec2::new(0.2, 0.0), DVec2::new(0.25, 0.0)),
            ] {
                let x = DVec2::new(x, y);
                let exact = segment_kernel_integral(&kernel, x, p0, p1, kernel.support);
                let reference = reference_integral(&kernel, x, p0, p1);
                worst = worst.max((exact - reference).abs());
                // Reversed orientation gives the same integral.
                let back = segment_kernel_integral(&kernel, x, p1, p0, kernel.support);
                assert!((back - exact).abs() < 1e-13);
            }
        }
        // W ~ 5.6e1 / h, lengths ~ h: 1e-12 absolute is round-off here.
        eprintln!("segment int W: closed form vs Gauss-Legendre, max |diff| = {worst:e}");
        assert!(worst < 1e-12, "worst {worst:e}");
    }

    #[test]
    fn segment_integral_matches_quadrature_with_clipping() {
        let kernel = Wendland::new(0.1, 2);
        let x = DVec2::new(0.013, -0.021);
        let cases = [
            (DVec2::new(-0.5, 0.05), DVec2::new(0.5, 0.05), 0.2), // longer than the support
            (DVec2::new(-0.03, 0.07), DVec2::new(0.11, 0.02), 0.2), // partly outside
            (DVec2::new(0.0, 0.0), DVec2::new(0.02, 0.01), 0.2),  // inside
            (DVec2::new(-0.5, 0.0), DVec2::new(0.5, 0.0), 0.05),  // push radius
            (DVec2::new(0.013, -0.021), DVec2::new(0.1, -0.021), 0.2), // starts at x
        ];
        for (p0, p1, radius) in cases {
            let exact = segment_kernel_integral(&kernel, x, p0, p1, radius);
            let from_length = segment_kernel_integral_from_length(&kernel, x, p0, p1, radius);
            assert!((exact - from_length).abs() < 1e-14 * exact);
            let len = (p1 - p0).length();
            // The part of the segment inside the circle, from |p0 + s d - x|^2 = R^2.
            let (d, f) = (p1 - p0, p0 - x);
            let (qa, qb, qc) = (d.dot(d), 2.0 * d.dot(f), f.dot(f) - radius * radius);
            let root = (qb * qb - 4.0 * qa * qc).sqrt();
            let (s0, s1) = (
                ((-qb - root) / (2.0 * qa)).max(0.0),
                ((-qb + root) / (2.0 * qa)).min(1.0),
            );
            let num = gauss_n(s0, s1, 64, |s| {
                kernel.value((p0 + d * s - x).length()) * len
            });
            assert!(exact > 0.0);
            assert!((exact - num).abs() < 1e-12 * exact, "{exact} vs {num}");
        }
        // A segment wholly inside the support: the quadrature has no kink, so round-off.
        let (p0, p1) = (DVec2::new(0.0, 0.03), DVec2::new(0.05, 0.01));
        let exact = segment_kernel_integral(&kernel, x, p0, p1, 0.2);
        let len = (p1 - p0).length();
        let num = gauss_n(0.0, 1.0, 64, |s| {
            kernel.value((p0 + (p1 - p0) * s - x).length()) * len
        });
        assert!((exact - num).abs() < 1e-13 * exact, "{exact} vs {num}");
    }

    #[test]
    fn segments_cross_where_they_share_a_point() {
        assert!(segments_intersect(
            DVec2::ZERO,
            DVec2::ONE,
            DVec2::new(0.0, 1.0),
            DVec2::new(1.0, 0.0)
        ));
        assert!(segments_intersect(
            DVec2::ZERO,
            DVec2::new(0.5, 0.0),
            DVec2::new(0.5, -1.0),
            DVec2::new(0.5, 1.0)
        ));
        assert!(!segments_intersect(
            DVec2::ZERO,
            DVec2::new(0.4, 0.0),
            DVec2::new(0.5, -1.0),
            DVec2::new(0.5, 1.0)
        ));
        let d = point_segment_distance(DVec2::new(0.5, 0.3), DVec2::ZERO, DVec2::X);
        assert!((d - 0.3).abs() < 1e-15);
    }
}
