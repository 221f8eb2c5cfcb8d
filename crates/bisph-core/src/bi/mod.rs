//! Boundary integrals of one wall element at a point: the one home of the integrals of the
//! kernel `W`, of the geometric Shepard function `F` and of `grad gamma`.
//!
//! **Conventions.** Element normals `n` point **out of the fluid** (the whole code's
//! convention); lengths inside the closed forms are in units of the smoothing length `h`;
//! `W` is the quintic Wendland kernel of support `2h`.
//!
//! * `W`: `int_{S cap B(x, R)} W(|y - x|) dS`, the part of the element within `R` (at most the
//!   support) of `x`. It gives the element's share of the Shepard factor's gradient,
//!   `grad gamma_as = -n int_S W dS` (paper 3, eq 9; paper 4, eq 3), which points into the
//!   fluid, and `grad gamma_a = sum_s grad gamma_as` (paper 3, eq 10).
//! * `F`: with `W = div(r What(|r|))`, `What(rho) = rho^-d int_0^rho s^(d-1) W(s) ds`
//!   (paper 2, eq 9), and the point-source part `1 / (A_d rho^d)` split off (its flux through a
//!   closed boundary is exactly 1), `gamma(x) = 1 + sum_s r_n,s int_{S_s} F(|y - x|) dS` with
//!   `r_n,s = (c_s - x) . n_s` (paper 2, eq 8) and, inside the support,
//!   `F(q) = [q^5/32 - 35q^4/128 + 7q^3/8 - 35q^2/32 + 7/8] / (pi h^2) - 1 / (2 pi q^2 h^2)` in
//!   2-D (paper 2, eq 11, the sign of the polynomial part corrected) and
//!   `F = [21q^5/1024 - 45q^4/256 + 35q^3/64 - 21q^2/32 + 7/16] / (pi h^3) - 1 / (4 pi q^3 h^3)`
//!   in 3-D. Each element's term `r_n int_S F dS` is called its *Shepard contribution*.
//!
//! The forms per dimension:
//!
//! * [`segment`]: 2-D segments in closed form (paper 2, eqs 13-15): the segment clipped to the
//!   support circle, the polynomial parts from the moments `int (a^2 + u^2)^(k/2) du`, the
//!   divergent part of `F` from the angle the clipped segment subtends.
//! * [`polygon`]: 3-D planar polygons, exact: `F` by fan triangles about the foot of the
//!   perpendicular, one per edge (paper 2, eqs 16-17), whose divergent part is the solid angle
//!   of the clipped element; the same on the outline of a merged planar region.
//! * [`polar`]: 3-D triangles by the polar rule about the foot of the perpendicular, `W` and
//!   `F` from shared closed-form angular moments (what BIPI evaluates, paper 4).
//!
//! [`ElementIntegrals`] is the one interface, implemented for [`glam::DVec2`] in [`segment`]
//! and for [`glam::DVec3`] in [`polygon`]. Code bounded only by [`Vector`] reaches it through
//! the functions [`shepard`] and [`outline_shepard`], which pick the implementation of the
//! concrete type ([`Vector::as_concrete`]); 2-D-only code calls [`segment`] directly.

pub mod gauss;
pub mod polar;
pub mod polygon;
pub mod segment;

use crate::dim::{Concrete, Vector};
use crate::kernel::Wendland;
use glam::{DVec2, DVec3};

/// The integrals of one wall element (its corners and unit normal out of the fluid) at a
/// point `x`: 2-D segments and 3-D planar polygons.
pub trait ElementIntegrals: Vector {
    /// The element's Shepard contribution to `gamma(x) - 1`, `r_n int_S F(|y - x|) dS`
    /// (paper 2, eq 8), exact: closed form for a segment (eqs 13-15), fan triangles per edge
    /// for a polygon (eqs 16-17). `x` on the element gives the principal value; callers move
    /// such points into the fluid first.
    fn shepard(kernel: &Wendland, x: Self, corners: &[Self], normal: Self) -> f64;

    /// [`ElementIntegrals::shepard`] of a planar region given by its outline (paper 2, eqs 8
    /// and 16-17): in 3-D the edges `outline[2k] -> outline[2k + 1]`, oriented
    /// counter-clockwise about `normal`, so that any union of coplanar elements is one region
    /// (edges shared by two elements cancel); in 2-D a segment by its two ends.
    fn outline_shepard(kernel: &Wendland, x: Self, outline: &[Self], normal: Self) -> f64;

    /// `int_{S cap B(x, radius)} W(|y - x|) dS` over the part of the element within `radius`
    /// (at most the support `2h`) of `x` (paper 4, eq 3; paper 3, eq 9).
    fn kernel_integral(kernel: &Wendland, x: Self, corners: &[Self], radius: f64) -> f64;

    /// The points and weights of the low-order Gauss rule for `int_S W(|y - x|) dS` over the
    /// whole element ([`gauss`]), appended to `out`.
    fn gauss_rule(corners: &[Self], out: &mut Vec<(Self, f64)>);

    /// `grad gamma_as`, the element's share of the gradient of the Shepard factor,
    /// `-n int_{S cap B(x, radius)} W dS` (paper 3, eq 9; paper 4, eq 3), pointing into the
    /// fluid.
    #[inline(always)]
    fn grad_gamma(kernel: &Wendland, x: Self, corners: &[Self], normal: Self, radius: f64) -> Self {
        -normal * Self::kernel_integral(kernel, x, corners, radius)
    }

    /// The Shepard contribution by the rule of
    /// [`ElementIntegrals::shepard_and_kernel_integral`]: the closed form in 2-D, the
    /// triangle polar rule in 3-D (paper 2, eq 8). `x` must not lie on the element.
    fn polar_shepard(kernel: &Wendland, x: Self, corners: &[Self], normal: Self) -> f64;

    /// The Shepard contribution and the kernel integral over the support together,
    /// `(r_n int_S F dS, int_S W dS)` (paper 2, eq 8; paper 4, eq 3), in one pass where
    /// that is cheaper (3-D: one polar rule for both, [`polar`]).
    fn shepard_and_kernel_integral(
        kernel: &Wendland,
        x: Self,
        corners: &[Self],
        normal: Self,
    ) -> (f64, f64);

    /// Euclidean distance from `x` to the (closed) element.
    fn element_distance(x: Self, corners: &[Self]) -> f64;

    /// `true` when the straight path from `from` to `to` touches the (closed) element.
    fn path_crosses_element(from: Self, to: Self, corners: &[Self]) -> bool;
}

/// One element's point, corners and normal as their concrete type.
enum Element<'a> {
    Two(DVec2, &'a [DVec2], DVec2),
    Three(DVec3, &'a [DVec3], DVec3),
}

/// The element seen as its concrete type ([`Vector::as_concrete`]).
#[inline(always)]
fn concrete<V: Vector>(x: V, corners: &[V], normal: V) -> Element<'_> {
    let one = |v: &V| match V::as_concrete(std::slice::from_ref(v)) {
        Concrete::Two(v) => (v[0], DVec3::ZERO),
        Concrete::Three(v) => (DVec2::ZERO, v[0]),
    };
    let ((x2, x3), (n2, n3)) = (one(&x), one(&normal));
    match V::as_concrete(corners) {
        Concrete::Two(c) => Element::Two(x2, c, n2),
        Concrete::Three(c) => Element::Three(x3, c, n3),
    }
}

/// [`ElementIntegrals::shepard`] for any vector type.
#[inline(always)]
pub fn shepard<V: Vector>(kernel: &Wendland, x: V, corners: &[V], normal: V) -> f64 {
    match concrete(x, corners, normal) {
        Element::Two(x, c, n) => DVec2::shepard(kernel, x, c, n),
        Element::Three(x, c, n) => DVec3::shepard(kernel, x, c, n),
    }
}

/// [`ElementIntegrals::outline_shepard`] for any vector type.
#[inline(always)]
pub fn outline_shepard<V: Vector>(kernel: &Wendland, x: V, outline: &[V], normal: V) -> f64 {
    match concrete(x, outline, normal) {
        Element::Two(x, c, n) => DVec2::outline_shepard(kernel, x, c, n),
        Element::Three(x, c, n) => DVec3::outline_shepard(kernel, x, c, n),
    }
}

/// [`ElementIntegrals::kernel_integral`] for any vector type.
#[inline(always)]
pub fn kernel_integral<V: Vector>(kernel: &Wendland, x: V, corners: &[V], radius: f64) -> f64 {
    match (
        V::as_concrete(std::slice::from_ref(&x)),
        V::as_concrete(corners),
    ) {
        (Concrete::Two(x), Concrete::Two(c)) => DVec2::kernel_integral(kernel, x[0], c, radius),
        (Concrete::Three(x), Concrete::Three(c)) => DVec3::kernel_integral(kernel, x[0], c, radius),
        _ => unreachable!("a point and its element's corners share one vector type"),
    }
}

/// [`ElementIntegrals::gauss_rule`] for any vector type: the points into `points`, the
/// weights into `weights`.
pub fn gauss_rule<V: Vector>(corners: &[V], points: &mut Vec<V>, weights: &mut Vec<f64>) {
    let back = |xyz: [f64; 3]| V::from_slice(&xyz[..V::DIM]);
    match V::as_concrete(corners) {
        Concrete::Two(c) => {
            let mut rule = Vec::new();
            DVec2::gauss_rule(c, &mut rule);
            for (y, w) in rule {
                points.push(back([y.x, y.y, 0.0]));
                weights.push(w);
            }
        }
        Concrete::Three(c) => {
            let mut rule = Vec::new();
            DVec3::gauss_rule(c, &mut rule);
            for (y, w) in rule {
                points.push(back(y.to_array()));
                weights.push(w);
            }
        }
    }
}

/// [`ElementIntegrals::path_crosses_element`] for any vector type.
#[inline(always)]
pub fn path_crosses_element<V: Vector>(from: V, to: V, corners: &[V]) -> bool {
    let ends = [from, to];
    match (V::as_concrete(&ends), V::as_concrete(corners)) {
        (Concrete::Two(e), Concrete::Two(c)) => DVec2::path_crosses_element(e[0], e[1], c),
        (Concrete::Three(e), Concrete::Three(c)) => DVec3::path_crosses_element(e[0], e[1], c),
        _ => unreachable!("a path and its element's corners share one vector type"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{box_elements_2d, box_elements_3d};

    /// `grad gamma` from the element integrals equals the finite-difference gradient of the
    /// exact Shepard factor (two independent closed forms), near walls and a corner.
    fn check_gradient<V: ElementIntegrals>(
        kernel: &Wendland,
        shapes: &[crate::geometry::ElementShape<V>],
        points: &[V],
        tol: f64,
    ) {
        let gamma = |x: V| -> f64 {
            1.0 + shapes
                .iter()
                .map(|s| V::polar_shepard(kernel, x, &s.corners, s.normal))
                .sum::<f64>()
        };
        for &x in points {
            let grad: V = shapes
                .iter()
                .map(|s| V::grad_gamma(kernel, x, &s.corners, s.normal, kernel.support))
                .fold(V::ZERO, |a, b| a + b);
            let eps = 1e-5 * kernel.h;
            let mut fd = V::ZERO;
            for k in 0..V::DIM {
                let mut e = V::ZERO;
                e.set(k, eps);
                fd.set(k, (gamma(x + e) - gamma(x - e)) / (2.0 * eps));
            }
            assert!(grad.length() > 0.0, "test point must see a wall");
            assert!(
                (grad - fd).length() < tol / kernel.h,
                "{x:?}: {grad:?} vs {fd:?}"
            );
        }
    }

    #[test]
    fn grad_gamma_is_the_gradient_of_gamma_2d() {
        let kernel = Wendland::new(0.02, 2);
        let shapes = box_elements_2d(DVec2::ZERO, DVec2::ONE, &[], 0.013);
        let points = [
            DVec2::new(0.5, 0.013),
            DVec2::new(0.007, 0.021),
            DVec2::new(0.011, 0.013),
            DVec2::new(0.5, 0.0399),
            DVec2::new(0.981, 0.992),
        ];
        check_gradient(&kernel, &shapes, &points, 1e-7);
    }

    #[test]
    fn grad_gamma_is_the_gradient_of_gamma_3d() {
        let kernel = Wendland::new(0.1, 3);
        let shapes = box_elements_3d(DVec3::ZERO, DVec3::ONE, &[], 0.17);
        let points = [
            DVec3::new(0.5, 0.5, 0.07),
            DVec3::new(0.05, 0.13, 0.11),
            DVec3::new(0.03, 0.04, 0.06),
            DVec3::new(0.52, 0.48, 0.19),
        ];
        check_gradient(&kernel, &shapes, &points, 1e-7);
    }

    /// The two exact 3-D rules for the Shepard contribution (fan triangles per edge, triangle
    /// polar rule) and the generic entry points agree with the per-type ones.
    #[test]
    fn the_two_3d_rules_and_the_generic_entry_points_agree() {
        let kernel = Wendland::new(0.1, 3);
        let corners = [
            DVec3::new(-0.05, -0.1, 0.02),
            DVec3::new(0.25, 0.03, -0.01),
            DVec3::new(0.01, 0.18, 0.05),
        ];
        let n = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize();
        for x in [DVec3::new(0.02, 0.01, 0.07), DVec3::new(0.1, 0.0, -0.05)] {
            let fan = DVec3::shepard(&kernel, x, &corners, n);
            let polar = DVec3::polar_shepard(&kernel, x, &corners, n);
            assert!((fan - polar).abs() < 1e-11, "{fan} vs {polar}");
            assert_eq!(shepard(&kernel, x, &corners, n), fan);
            let outline: Vec<DVec3> = (0..3)
                .flat_map(|k| [corners[k], corners[(k + 1) % 3]])
                .collect();
            let o = outline_shepard(&kernel, x, &outline, n);
            assert!((o - fan).abs() < 1e-14, "{o} vs {fan}");
        }
        let k2 = Wendland::new(0.1, 2);
        let (x, c, n) = (
            DVec2::new(0.01, 0.03),
            [DVec2::new(-0.1, 0.0), DVec2::new(0.2, 0.0)],
            DVec2::new(0.0, -1.0),
        );
        assert_eq!(shepard(&k2, x, &c, n), DVec2::shepard(&k2, x, &c, n));
    }
}
