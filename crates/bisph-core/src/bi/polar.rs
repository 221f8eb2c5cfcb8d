//! 3-D triangles by the polar rule: `int_{T cap B(x, R)} f(|y - x|) dA` in polar coordinates
//! about the foot of the perpendicular from `x`, for the kernel `W` (paper 4, eq 3) and the
//! Shepard function `F` (paper 2, eqs 8-9) at once.
//!
//! The radial integral is exact (`int f(sqrt(a^2 + s^2)) s ds = int f(r) r dr`, a
//! polynomial plus, for `F`, the point-source term), and so is the angular one: the radial
//! primitives times the angle where the clipping circle cuts the triangle, the closed-form
//! moments of [`angular_moments`] where an edge lies inside it. Polygons are fans of
//! triangles from their first corner. A triangle well inside the support and far from `x`
//! against its size takes Dunavant's 7-point rule instead ([`far_triangle`]).

use crate::kernel::Wendland;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// A radial integrand of the 3-D polar rule, `F(q) = A sum_k c_k q^k + B / q` with
/// `q = rho / h`, whose primitive difference `F(rho / h) - F(|a| / h)` is
/// `int_0^s f(sqrt(a^2 + u^2)) u du` for the function `f` integrated over the wall.
#[derive(Clone, Copy, Debug)]
struct Radial {
    scale: f64,
    c: [f64; 8],
    inv: f64,
}

/// `P(q) = q^2/2 - 5q^4/8 + q^5/2 - 5q^6/32 + q^7/56`, the primitive of `w(q) q`.
const WENDLAND_P: [f64; 8] = [0.0, 0.0, 0.5, 0.0, -0.625, 0.5, -5.0 / 32.0, 1.0 / 56.0];
/// `Q(q) = 7q^2/32 - 21q^4/128 + 7q^5/64 - 15q^6/512 + 3q^7/1024`, the primitive of
/// `Fp(q) q` (paper 2, eq 9, sign corrected).
const SHEPARD_Q: [f64; 8] = [
    0.0,
    0.0,
    7.0 / 32.0,
    0.0,
    -21.0 / 128.0,
    7.0 / 64.0,
    -15.0 / 512.0,
    3.0 / 1024.0,
];

impl Radial {
    /// The 3-D Wendland kernel: `int_0^s W(sqrt(a^2 + u^2)) u du = alpha h^2 [P(rho/h) -
    /// P(|a|/h)]`, `alpha h^2 = 21 / (16 pi h)`.
    fn wendland(kernel: &Wendland) -> Self {
        Radial {
            scale: 21.0 / (16.0 * PI * kernel.h),
            c: WENDLAND_P,
            inv: 0.0,
        }
    }

    /// `a int_0^s F(sqrt(a^2 + u^2)) u du` for paper 2's 3-D `F` (eq 9, sign corrected):
    /// `F(r) = Fp(q) / (pi h^3) - 1 / (4 pi r^3)`; the primitive of `a F(r) r` is
    /// `a Q(q) / (pi h) + a / (4 pi r)`.
    fn shepard(kernel: &Wendland, a: f64) -> Self {
        Radial {
            scale: a / (PI * kernel.h),
            c: SHEPARD_Q,
            inv: a / (4.0 * PI * kernel.h),
        }
    }

    /// `F(q)`.
    fn value(&self, q: f64) -> f64 {
        let poly = self.c.iter().rev().fold(0.0, |acc, &c| acc * q + c);
        let inv = if self.inv != 0.0 { self.inv / q } else { 0.0 };
        self.scale * poly + inv
    }

    /// `sum_k c_k K_k` over the angular moments of [`angular_moments`].
    fn combine(&self, k: &[f64; 9]) -> f64 {
        let poly: f64 = self.c.iter().zip(k).map(|(c, k)| c * k).sum();
        self.scale * poly + self.inv * k[8]
    }
}

/// Closed-form angular moments of the polar rule: with `u = d tan(psi)` the coordinate
/// along an edge at distance `d` from the foot of the perpendicular and `q^2 = a^2 + d^2 +
/// u^2` (lengths in units of `h`), `K_k = int_{u0}^{u1} q^k d / (d^2 + u^2) du`, i.e.
/// `int q^k dpsi`, for `k = 0..=7` (entry `k`) and `k = -1` (entry 8); `dpsi` is the angle
/// the piece subtends. With `c^2 = a^2 + d^2` and `R = sqrt(c^2 + u^2)`:
/// `(c^2 + u^2)^m = q_m(u^2) (d^2 + u^2) + a^(2m)`, so `K_2m = d int q_m du + a^(2m) dpsi` and
/// `K_(2m+1) = d int q_m R du + a^(2m) K_1` with `K_1 = [d asinh(u/c) + |a| atan(|a| u /
/// (d R))]` and `K_-1 = [atan(|a| u / (d R))] / |a|`; `int u^(2j) R du` by the recursion
/// `S_n = (u^(n-1) R^3 - (n-1) c^2 S_(n-2)) / (n+2)`. The logarithms and arc tangents enter
/// as differences, one call each.
fn angular_moments(a: f64, d: f64, u0: f64, u1: f64, dpsi: f64) -> [f64; 9] {
    let (a2, d2) = (a * a, d * d);
    let c2 = a2 + d2;
    let (r0, r1) = ((c2 + u0 * u0).sqrt(), (c2 + u1 * u1).sqrt());
    // asinh(u1/c) - asinh(u0/c) = ln(g(u1) / g(u0)), g(u) = u + R, written c^2 / (R - u)
    // for u < 0 (no cancellation).
    let g = |u: f64, r: f64| if u >= 0.0 { u + r } else { c2 / (r - u) };
    let d_asn = (g(u1, r1) / g(u0, r0)).ln();
    let abs_a = a.abs();
    // atan(x1) - atan(x0) = atan2(x1 - x0, 1 + x0 x1), x = |a| u / (d R).
    let (x0, x1) = (abs_a * u0 / (d * r0), abs_a * u1 / (d * r1));
    let d_at = (x1 - x0).atan2(1.0 + x0 * x1);
    let k1 = d * d_asn + abs_a * d_at;
    let k_inv = if abs_a > 0.0 {
        d_at / abs_a
    } else {
        u1 / (d * r1) - u0 / (d * r0)
    };
    // Quotients q_2 = x + (2c^2 - d^2), q_3 = x^2 + (3c^2 - d^2) x + (3c^4 - 3c^2 d^2 + d^4).
    let q2_0 = 2.0 * c2 - d2;
    let (q3_0, q3_1) = (c2 * (3.0 * c2 - 3.0 * d2) + d2 * d2, 3.0 * c2 - d2);
    let du = u1 - u0;
    let du3 = u1 * u1 * u1 - u0 * u0 * u0;
    let du5 = u1.powi(5) - u0.powi(5);
    let s0 = 0.5 * (u1 * r1 - u0 * r0 + c2 * d_asn);
    let s2 = (u1 * r1 * r1 * r1 - u0 * r0 * r0 * r0 - c2 * s0) / 4.0;
    let s4 = (u1.powi(3) * r1.powi(3) - u0.powi(3) * r0.powi(3) - 3.0 * c2 * s2) / 6.0;
    let (a4, a6) = (a2 * a2, a2 * a2 * a2);
    [
        dpsi,
        k1,
        d * du + a2 * dpsi,
        d * s0 + a2 * k1,
        d * (q2_0 * du + du3 / 3.0) + a4 * dpsi,
        d * (q2_0 * s0 + s2) + a4 * k1,
        d * (q3_0 * du + q3_1 * du3 / 3.0 + du5 / 5.0) + a6 * dpsi,
        d * (q3_0 * s0 + q3_1 * s2 + s4) + a6 * k1,
        k_inv,
    ]
}

/// `int_{T cap B(x, radius)} f_k(|y - x|) dA` over the triangle `tri` for `N` functions at
/// once, given as [`Radial`] primitives by `radial(a)` (`a` the signed distance from `x` to
/// the triangle's plane along its corner-order normal), in polar coordinates about the foot
/// of the perpendicular: the triangle is the signed sum of the three triangles (foot, edge);
/// on each the radial integral runs to `min(edge(psi), s_c)`, `s_c = sqrt(radius^2 - a^2)`;
/// the angular integral is exact: the primitives times the angle where the circle clips, the
/// closed-form moments of [`angular_moments`] where the edge lies inside the circle.
fn polar_triangle<const N: usize>(
    x: DVec3,
    tri: [DVec3; 3],
    radius: f64,
    h: f64,
    radial: impl Fn(f64) -> [Radial; N],
) -> [f64; N] {
    polar_triangle_rule(x, tri, radius, h, radial, true)
}

/// [`polar_triangle`]; `winding` allows the shortcut for a triangle wholly inside the
/// clipping circle: no edge piece is clipped, and the moments' terms linear in the subtended
/// angle (`K_0`, and the `a^(2m) dpsi` parts of `K_2m`, together with `-F(|a|) dpsi`) sum over
/// the three edges to the triangle's winding angle about the foot (`+-2 pi` when the foot
/// lies inside it, 0 outside), so the per-edge angles (two `atan2` each) are not needed.
fn polar_triangle_rule<const N: usize>(
    x: DVec3,
    tri: [DVec3; 3],
    radius: f64,
    h: f64,
    radial: impl Fn(f64) -> [Radial; N],
    winding: bool,
) -> [f64; N] {
    let mut total = [0.0; N];
    let m = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    let m_len = m.length();
    if m_len == 0.0 {
        return total;
    }
    let nn = m / m_len;
    let a = (tri[0] - x).dot(nn);
    if a.abs() >= radius {
        return total;
    }
    let sc = (radius * radius - a * a).sqrt();
    let foot = x + nn * a;
    let e1 = (tri[1] - tri[0]).normalize();
    let e2 = nn.cross(e1);
    let p = tri.map(|v| DVec2::new((v - foot).dot(e1), (v - foot).dot(e2)));
    let scale = (tri[1] - tri[0]).length().max(sc);
    let f = radial(a);
    let q_a = a.abs() / h;
    let f_a = f.map(|f| f.value(q_a));
    let mut f_clip = [0.0; N];
    for k in 0..N {
        f_clip[k] = f[k].value(radius / h) - f_a[k];
    }
    // Angle subtended from the foot by the edge piece u0..u1 at distance d.
    let angle = |d: f64, u0: f64, u1: f64| (d * (u1 - u0)).atan2(d * d + u0 * u1);
    if winding && p.iter().all(|v| v.length_squared() < sc * sc) {
        let mut turns = [0i32; 2];
        let mut regular = true;
        let mut sum = [0.0; N];
        for k in 0..3 {
            let (pa, pb) = (p[k], p[(k + 1) % 3]);
            let edge = pb - pa;
            let len = edge.length();
            let cross = pa.perp_dot(pb);
            if len == 0.0 || cross.abs() / len <= 1e-14 * scale {
                regular = false; // the foot on an edge's line: the general rule
                break;
            }
            let d = cross.abs() / len;
            let e = edge / len;
            let moments = angular_moments(a / h, d / h, pa.dot(e) / h, pb.dot(e) / h, 0.0);
            let sign = cross.signum();
            turns[usize::from(sign < 0.0)] += 1;
            for n in 0..N {
                sum[n] += sign * f[n].combine(&moments);
            }
        }
        if regular {
            let phi = match turns {
                [3, 0] => 2.0 * PI,
                [0, 3] => -2.0 * PI,
                _ => 0.0,
            };
            let a2 = (a / h) * (a / h);
            for n in 0..N {
                let c = &f[n].c;
                let even = c[0] + a2 * (c[2] + a2 * (c[4] + a2 * c[6]));
                total[n] = sum[n] + phi * (f[n].scale * even - f_a[n]);
            }
            return total;
        }
    }
    for k in 0..3 {
        let (pa, pb) = (p[k], p[(k + 1) % 3]);
        let edge = pb - pa;
        let len = edge.length();
        if len == 0.0 {
            continue;
        }
        let cross = pa.perp_dot(pb);
        let d = cross.abs() / len;
        if d <= 1e-14 * scale {
            continue; // the foot lies on this edge's line: a sector of zero area
        }
        let sign = cross.signum();
        let e = edge / len;
        let (ua, ub) = (pa.dot(e), pb.dot(e));
        let whole = angle(d, ua, ub);
        // The piece of the edge inside the circle, |u| < u_star; the rest is clipped.
        let mut clipped = whole;
        if d < sc {
            let u_star = (sc * sc - d * d).sqrt();
            let (u0, u1) = (ua.max(-u_star), ub.min(u_star));
            if u1 > u0 {
                let inside = angle(d, u0, u1);
                clipped = whole - inside;
                let moments = angular_moments(a / h, d / h, u0 / h, u1 / h, inside);
                for n in 0..N {
                    total[n] += sign * (f[n].combine(&moments) - f_a[n] * inside);
                }
            }
        }
        for (t, h) in total.iter_mut().zip(f_clip) {
            *t += sign * h * clipped;
        }
    }
    total
}

/// Dunavant's 7-point rule (degree 5) on a triangle: barycentric points and weights.
const DUNAVANT7: [([f64; 3], f64); 7] = [
    ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
    (
        [
            0.059_715_871_789_770,
            0.470_142_064_105_115,
            0.470_142_064_105_115,
        ],
        0.132_394_152_788_506,
    ),
    (
        [
            0.470_142_064_105_115,
            0.059_715_871_789_770,
            0.470_142_064_105_115,
        ],
        0.132_394_152_788_506,
    ),
    (
        [
            0.470_142_064_105_115,
            0.470_142_064_105_115,
            0.059_715_871_789_770,
        ],
        0.132_394_152_788_506,
    ),
    (
        [
            0.797_426_985_353_087,
            0.101_286_507_323_456,
            0.101_286_507_323_456,
        ],
        0.125_939_180_544_827,
    ),
    (
        [
            0.101_286_507_323_456,
            0.797_426_985_353_087,
            0.101_286_507_323_456,
        ],
        0.125_939_180_544_827,
    ),
    (
        [
            0.101_286_507_323_456,
            0.101_286_507_323_456,
            0.797_426_985_353_087,
        ],
        0.125_939_180_544_827,
    ),
];

/// For a triangle wholly inside the support and far from `x` against its size (closest
/// centre at least 2.5 times its longest edge away), `(a int F dA, int W dA)` by Dunavant's 7-point
/// rule (smooth integrands there; relative error below about 1e-4 of the element's share);
/// `None` otherwise (the exact polar rule is used).
fn far_triangle(kernel: &Wendland, x: DVec3, tri: &[DVec3; 3]) -> Option<(f64, f64)> {
    let longest = (tri[1] - tri[0])
        .length_squared()
        .max((tri[2] - tri[1]).length_squared())
        .max((tri[0] - tri[2]).length_squared())
        .sqrt();
    let support2 = kernel.support * kernel.support;
    if tri.iter().any(|&v| (v - x).length_squared() >= support2) {
        return None;
    }
    let centre = (tri[0] + tri[1] + tri[2]) / 3.0;
    if (centre - x).length() < 2.5 * longest {
        return None;
    }
    let m = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    let area = 0.5 * m.length();
    let nn = m / (2.0 * area);
    let a = (tri[0] - x).dot(nn);
    let h = kernel.h;
    let (mut g, mut w) = (0.0, 0.0);
    for (b, weight) in DUNAVANT7 {
        let y = tri[0] * b[0] + tri[1] * b[1] + tri[2] * b[2];
        let r = (y - x).length();
        let q = r / h;
        let fp = (21.0 * q.powi(5) / 1024.0 - 45.0 * q.powi(4) / 256.0 + 35.0 * q.powi(3) / 64.0
            - 21.0 * q * q / 32.0
            + 7.0 / 16.0)
            / (PI * h * h * h);
        g += weight * (fp - 1.0 / (4.0 * PI * r * r * r));
        w += weight * kernel.value(r);
    }
    Some((a * g * area, w * area))
}

/// Triangles of a planar polygon element (a fan from its first corner).
pub(crate) fn fan(corners: &[DVec3]) -> impl Iterator<Item = [DVec3; 3]> + '_ {
    (1..corners.len().saturating_sub(1)).map(move |k| [corners[0], corners[k], corners[k + 1]])
}

/// Sign of the element's normal relative to a triangle's corner-order normal.
fn orientation(tri: &[DVec3; 3], normal: DVec3) -> f64 {
    let nn = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    if nn.dot(normal) < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// Shepard contribution `r_n int_S F dS` of the polygon `corners` with outward normal `normal`
/// (paper 2, eq 8), by the polar rule on each fan triangle.
pub fn shepard(kernel: &Wendland, x: DVec3, corners: &[DVec3], normal: DVec3) -> f64 {
    fan(corners)
        .map(|tri| {
            // The polar rule measures a along the corner-order normal.
            orientation(&tri, normal)
                * polar_triangle(x, tri, kernel.support, kernel.h, |a| {
                    [Radial::shepard(kernel, a)]
                })[0]
        })
        .sum()
}

/// `int_{S cap B(x, radius)} W(|y - x|) dS` over the polygon `corners` (paper 4, eq 3), by the
/// polar rule on each fan triangle; `radius` is at most the support.
pub fn kernel_integral(kernel: &Wendland, x: DVec3, corners: &[DVec3], radius: f64) -> f64 {
    let r = radius.min(kernel.support);
    fan(corners)
        .map(|tri| polar_triangle(x, tri, r, kernel.h, |_| [Radial::wendland(kernel)])[0])
        .sum()
}

/// `(r_n int_S F dS, int_S W dS)` over the polygon `corners` (paper 2, eq 8; paper 4, eq 3):
/// one polar rule for both on each fan triangle, or [`far_triangle`] where it applies.
pub fn shepard_and_kernel_integral(
    kernel: &Wendland,
    x: DVec3,
    corners: &[DVec3],
    normal: DVec3,
) -> (f64, f64) {
    let mut out = (0.0, 0.0);
    for tri in fan(corners) {
        if let Some((g, w)) = far_triangle(kernel, x, &tri) {
            out.0 += orientation(&tri, normal) * g;
            out.1 += w;
            continue;
        }
        let v = polar_triangle(x, tri, kernel.support, kernel.h, |a| {
            [Radial::shepard(kernel, a), Radial::wendland(kernel)]
        });
        out.0 += orientation(&tri, normal) * v[0];
        out.1 += v[1];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::gauss_legendre as gauss_n;

    /// Half-space values: `int_plane W dA = 2 pi alpha h^2 (P(2) - P(a/h))` and
    /// `gamma(a) = 1 - int_a^{2h} 2 pi alpha h^2 (P(2) - P(z/h)) dz`.
    #[test]
    fn half_space_values_3d() {
        let h = 0.1;
        let kernel = Wendland::new(h, 3);
        let alpha = 21.0 / (16.0 * PI * h * h * h);
        let p = |q: f64| {
            q * q / 2.0 - 5.0 * q.powi(4) / 8.0 + q.powi(5) / 2.0 - 5.0 * q.powi(6) / 32.0
                + q.powi(7) / 56.0
        };
        let plane_integral = |a: f64| 2.0 * PI * alpha * h * h * (p(2.0) - p(a / h));
        // A square plane z = 0 of side 1 around the point, normal -z (fluid above).
        let c = [
            DVec3::new(-0.5, -0.5, 0.0),
            DVec3::new(-0.5, 0.5, 0.0),
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(0.5, -0.5, 0.0),
        ];
        let n = DVec3::new(0.0, 0.0, -1.0);
        for a in [1e-3, 0.03, 0.1, 0.17, 0.199] {
            let x = DVec3::new(0.013, -0.02, a);
            let w = kernel_integral(&kernel, x, &c, 2.0 * h);
            let exact = plane_integral(a);
            assert!(
                (w - exact).abs() < 1e-13 * plane_integral(0.0),
                "a={a}: {w} vs {exact}"
            );
            let g = 1.0 + shepard(&kernel, x, &c, n);
            let g_exact = 1.0 - gauss_n(a, 2.0 * h, 16, plane_integral);
            assert!((g - g_exact).abs() < 1e-12, "a={a}: {g} vs {g_exact}");
        }
        // Clipped to a push radius: the disc of radius sqrt(R^2 - a^2).
        let (a, radius) = (0.02, 0.05);
        let x = DVec3::new(0.0, 0.0, a);
        let w = kernel_integral(&kernel, x, &c, radius);
        let exact = 2.0 * PI * alpha * h * h * (p(radius / h) - p(a / h));
        assert!((w - exact).abs() < 1e-12 * exact);
    }

    /// The winding shortcut for triangles inside the clipping circle agrees with the
    /// per-edge rule: foot inside and outside the triangle, either side of its plane, either
    /// corner order, both integrands.
    #[test]
    fn winding_shortcut_matches_the_edge_rule() {
        let kernel = Wendland::new(0.1, 3);
        let tri = [
            DVec3::new(-0.03, -0.02, 0.01),
            DVec3::new(0.05, 0.01, -0.01),
            DVec3::new(0.0, 0.06, 0.02),
        ];
        let flipped = [tri[0], tri[2], tri[1]];
        for x in [
            DVec3::new(0.005, 0.01, 0.03),
            DVec3::new(0.005, 0.01, -0.04),
            DVec3::new(0.09, -0.05, 0.02),
            DVec3::new(-0.06, 0.07, -0.01),
        ] {
            for t in [tri, flipped] {
                let m = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
                let a = (t[0] - x).dot(m);
                let radial = |a: f64| [Radial::shepard(&kernel, a), Radial::wendland(&kernel)];
                let fast = polar_triangle_rule(x, t, kernel.support, kernel.h, radial, true);
                let edge = polar_triangle_rule(x, t, kernel.support, kernel.h, radial, false);
                assert!(a.abs() > 0.0);
                for n in 0..2 {
                    assert!(
                        (fast[n] - edge[n]).abs() <= 1e-12 * edge[n].abs().max(1e-3),
                        "x = {x}, n = {n}: {} vs {}",
                        fast[n],
                        edge[n]
                    );
                }
            }
        }
    }

    #[test]
    fn triangle_integral_matches_brute_force() {
        let kernel = Wendland::new(0.1, 3);
        let tri = [
            DVec3::new(-0.05, -0.1, 0.02),
            DVec3::new(0.25, 0.03, -0.01),
            DVec3::new(0.01, 0.18, 0.05),
        ];
        let x = DVec3::new(0.02, 0.01, 0.07);
        let area2 = (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
        for radius in [0.2, 0.09] {
            let exact = kernel_integral(&kernel, x, &tri, radius);
            // Collapsed square map (u, v) -> a + u (b - a) + u v (c - b), Jacobian u.
            let num = gauss_n(0.0, 1.0, 400, |u| {
                gauss_n(0.0, 1.0, 400, |v| {
                    let y = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[1]) * (u * v);
                    let r = (y - x).length();
                    if r < radius {
                        kernel.value(r) * u * area2
                    } else {
                        0.0
                    }
                })
            });
            let tol = if radius < 0.2 { 1e-4 } else { 1e-8 };
            assert!(
                (exact - num).abs() < tol * exact,
                "R={radius}: {exact} vs {num}"
            );
        }
    }

    #[test]
    fn far_triangle_rule_matches_the_polar_rule() {
        let kernel = Wendland::new(0.1, 3);
        let x = DVec3::new(0.01, 0.02, 0.03);
        // Longest edge 0.05, centre about 0.13 away: the threshold.
        let tri = [
            DVec3::new(0.10, 0.05, -0.04),
            DVec3::new(0.15, 0.06, -0.035),
            DVec3::new(0.125, 0.09, -0.03),
        ];
        let (g, w) = far_triangle(&kernel, x, &tri).expect("far enough");
        let exact_w = polar_triangle(x, tri, kernel.support, kernel.h, |_| {
            [Radial::wendland(&kernel)]
        })[0];
        let exact_g = polar_triangle(x, tri, kernel.support, kernel.h, |a| {
            [Radial::shepard(&kernel, a)]
        })[0];
        assert!(
            (w - exact_w).abs() < 1e-4 * exact_w.abs(),
            "{w} vs {exact_w}"
        );
        assert!(
            (g - exact_g).abs() < 1e-4 * exact_g.abs(),
            "{g} vs {exact_g}"
        );
    }

    /// The closed-form angular moments against Gauss-Legendre in `t`, `u = d sinh(t)`
    /// (`int q^k d / (d^2 + u^2) du = int q^k / cosh(t) dt`, smooth), including a point in the triangle's plane (`a = 0`)
    /// and one close to an edge's line (small `d`).
    #[test]
    fn angular_moments_match_quadrature() {
        for (a, d, u0, u1) in [
            (0.3, 0.7, -0.4, 1.1),
            (-1.2, 0.2, 0.05, 1.5),
            (0.0, 0.5, -1.0, 0.3),
            (1e-3, 1.9, -0.2, 0.25),
            (0.8, 1e-3, -1.7, 1.6),
        ] {
            let moments = angular_moments(a, d, u0, u1, f64::atan2(u1, d) - f64::atan2(u0, d));
            for (k, &exact) in moments.iter().enumerate() {
                let power = if k == 8 { -1 } else { k as i32 };
                let num = gauss_n((u0 / d).asinh(), (u1 / d).asinh(), 400, |t| {
                    let u = d * t.sinh();
                    (a * a + d * d + u * u).sqrt().powi(power) / t.cosh()
                });
                assert!(
                    (exact - num).abs() < 1e-11 * num.abs().max(1e-3),
                    "a={a} d={d} k={power}: {exact} vs {num}"
                );
            }
        }
    }
}
