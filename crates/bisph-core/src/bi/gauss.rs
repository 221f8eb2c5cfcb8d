//! Low-order Gauss rules for the kernel integral over one element, `int_S W(|y - x|) dS`:
//! the kernel at a few points of the element instead of its closed form.
//!
//! - a segment: 2-point Gauss-Legendre (exact for cubics along the segment);
//! - a quadrilateral: 2 x 2 Gauss-Legendre on its bilinear map, with the map's area element
//!   at each point (exact area for any planar quadrilateral);
//! - a triangle: the symmetric 3-point rule at barycentric `(2/3, 1/6, 1/6)` (degree 2);
//! - any other polygon: that rule on each triangle of its fan about the first corner.
//!
//! With elements about `dx` wide and `h = 2 dx`, these rules stay within about 5e-4 of the
//! exact element sum `sum_k n_k int_{S_k} W dS` near flat walls, edges and corners, where the
//! one point at the element centre is off by 1-2 %.

use crate::kernel::Wendland;
use glam::{DVec2, DVec3};

/// Gauss-Legendre abscissae of the 2-point rule on `[0, 1]` (weights 1/2 each).
const GAUSS2: [f64; 2] = [0.211_324_865_405_187_1, 0.788_675_134_594_812_9];

/// The points and weights of the rule for the segment `a -> b` (2-point Gauss-Legendre,
/// weights half the length), appended to `out`.
pub fn segment_rule(a: DVec2, b: DVec2, out: &mut Vec<(DVec2, f64)>) {
    let d = b - a;
    let weight = 0.5 * d.length();
    out.extend(GAUSS2.iter().map(|&t| (a + d * t, weight)));
}

/// The points and weights of the rule for a planar polygon in 3-D (see the module
/// documentation for the rule each corner count takes), appended to `out`.
pub fn polygon_rule(corners: &[DVec3], out: &mut Vec<(DVec3, f64)>) {
    match corners {
        [a, b, c, d] => quadrilateral_rule([*a, *b, *c, *d], out),
        _ => {
            for k in 1..corners.len() - 1 {
                triangle_rule([corners[0], corners[k], corners[k + 1]], out);
            }
        }
    }
}

/// 2 x 2 Gauss-Legendre on the bilinear map of the quadrilateral `c0 c1 c2 c3`,
/// `y(s, t) = (1-s)(1-t) c0 + s(1-t) c1 + s t c2 + (1-s) t c3`, each point weighted by a
/// quarter of the area element `|dy/ds x dy/dt|` there.
fn quadrilateral_rule(c: [DVec3; 4], out: &mut Vec<(DVec3, f64)>) {
    for &s in &GAUSS2 {
        for &t in &GAUSS2 {
            let y = c[0] * ((1.0 - s) * (1.0 - t))
                + c[1] * (s * (1.0 - t))
                + c[2] * (s * t)
                + c[3] * ((1.0 - s) * t);
            let ds = (c[1] - c[0]) * (1.0 - t) + (c[2] - c[3]) * t;
            let dt = (c[3] - c[0]) * (1.0 - s) + (c[2] - c[1]) * s;
            out.push((y, 0.25 * ds.cross(dt).length()));
        }
    }
}

/// The symmetric 3-point rule of degree 2 on the triangle `t` (weights a third of its area).
fn triangle_rule(t: [DVec3; 3], out: &mut Vec<(DVec3, f64)>) {
    let weight = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length() / 3.0;
    let point = |a: DVec3, b: DVec3, c: DVec3| (a * 4.0 + b + c) / 6.0;
    out.push((point(t[0], t[1], t[2]), weight));
    out.push((point(t[1], t[2], t[0]), weight));
    out.push((point(t[2], t[0], t[1]), weight));
}

/// Points of a rule evaluated together: an element's rule is stored in groups of this many.
pub const LANES: usize = 4;

/// [`LANES`] points of an element's rule by coordinate (`z` zero in 2-D), with their weights.
/// The lanes past the rule's last point repeat that point with weight zero, so they add
/// exactly zero to the integral.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointGroup {
    coord: [[f64; LANES]; 3],
    weight: [f64; LANES],
}

/// Appends the rule with points `points` and weights `weights` to `out` in groups of
/// [`LANES`] points (see [`PointGroup`]).
pub fn group_points<V: crate::dim::Vector>(
    points: &[V],
    weights: &[f64],
    out: &mut Vec<PointGroup>,
) {
    for (group_points, group_weights) in points.chunks(LANES).zip(weights.chunks(LANES)) {
        let mut group = PointGroup::default();
        for l in 0..LANES {
            let k = l.min(group_points.len() - 1);
            for c in 0..V::DIM {
                group.coord[c][l] = group_points[k].get(c);
            }
            group.weight[l] = if l < group_weights.len() {
                group_weights[l]
            } else {
                0.0
            };
        }
        out.push(group);
    }
}

/// `sum_k w_k W(|y_k - x|)`: the integral by the rule with points `y_k` and weights `w_k`,
/// stored in groups ([`group_points`]). The points of a group are evaluated lane by lane
/// without a branch and summed in the rule's order: the bits of the point-by-point sum.
#[inline(always)]
pub fn integral<V: crate::dim::Vector>(kernel: &Wendland, x: V, groups: &[PointGroup]) -> f64 {
    let x = [x.get(0), x.get(1), if V::DIM == 3 { x.get(2) } else { 0.0 }];
    let mut sum = 0.0;
    for g in groups {
        let mut term = [0.0; LANES];
        for (l, term) in term.iter_mut().enumerate() {
            let d = [
                g.coord[0][l] - x[0],
                g.coord[1][l] - x[1],
                g.coord[2][l] - x[2],
            ];
            // `|y - x|` as `Vector::length` computes it (a zero `z` adds exactly zero).
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            *term = g.weight[l] * kernel.value_or_zero(r);
        }
        for t in term {
            sum += t;
        }
    }
    sum
}

/// `int W dS` over the segment `a -> b` by its rule ([`segment_rule`]).
pub fn segment(kernel: &Wendland, x: DVec2, a: DVec2, b: DVec2) -> f64 {
    let mut rule = Vec::with_capacity(2);
    segment_rule(a, b, &mut rule);
    rule.iter()
        .map(|&(y, w)| w * kernel.value((y - x).length()))
        .sum()
}

/// `int W dS` over a planar polygon in 3-D by its rule ([`polygon_rule`]).
pub fn polygon(kernel: &Wendland, x: DVec3, corners: &[DVec3]) -> f64 {
    let mut rule = Vec::with_capacity(4);
    polygon_rule(corners, &mut rule);
    rule.iter()
        .map(|&(y, w)| w * kernel.value((y - x).length()))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bi::ElementIntegrals;
    use crate::geometry::{box_elements_2d, box_elements_3d};

    /// The Gauss sum `sum_k n_k int_{S_k} W dS` over a box's walls, near the floor, an edge and
    /// a corner, stays within 1e-3 of the exact sum (scaled by the flat-wall value), where
    /// the centre rule is off by about 1 %. Elements `dx` wide, `h = 2 dx`.
    #[test]
    fn gauss_rules_follow_the_exact_wall_sum_near_edges_and_corners() {
        let dx = 0.05;
        let kernel = Wendland::new(2.0 * dx, 3);
        let shapes = box_elements_3d(DVec3::ZERO, DVec3::ONE, &[], dx);
        let flat = DVec3::kernel_integral(
            &kernel,
            DVec3::new(0.5, 0.5, 0.5 * dx),
            &[
                DVec3::new(-1.0, -1.0, 0.0),
                DVec3::new(2.0, -1.0, 0.0),
                DVec3::new(2.0, 2.0, 0.0),
                DVec3::new(-1.0, 2.0, 0.0),
            ],
            kernel.support,
        );
        let sum = |rule: &dyn Fn(&[DVec3]) -> f64| {
            shapes
                .iter()
                .map(|s| s.normal * rule(&s.corners))
                .fold(DVec3::ZERO, |a, b| a + b)
        };
        let mut worst_centre: f64 = 0.0;
        for x in [
            DVec3::new(0.5, 0.5, 0.5 * dx),
            DVec3::new(0.5 * dx, 0.5, 1.5 * dx),
            DVec3::new(0.5 * dx, 0.5 * dx, 0.5 * dx),
            DVec3::new(1.5 * dx, 2.5 * dx, 0.5 * dx),
            DVec3::new(0.51, 3.5 * dx, 1.5 * dx),
        ] {
            let exact = sum(&|c| DVec3::kernel_integral(&kernel, x, c, kernel.support));
            let gauss = sum(&|c| polygon(&kernel, x, c));
            let centre = sum(&|c| {
                let centre = c.iter().fold(DVec3::ZERO, |a, &b| a + b) / c.len() as f64;
                let area = (c[1] - c[0]).cross(c[3] - c[0]).length();
                kernel.value((centre - x).length()) * area
            });
            let err = (gauss - exact).length() / flat;
            assert!(err < 1e-3, "{x:?}: gauss {gauss:?} vs exact {exact:?}");
            worst_centre = worst_centre.max((centre - exact).length() / flat);
        }
        assert!(
            worst_centre > 5e-3,
            "the centre rule should be visibly off: {worst_centre}"
        );
    }

    /// Triangles (the fan of a quadrilateral), a skewed quadrilateral and segments follow the
    /// exact integral of one element within 0.5 % at 0.6 element sizes from it.
    #[test]
    fn triangle_and_segment_rules_follow_the_exact_integral() {
        let kernel = Wendland::new(0.1, 3);
        let quad = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.05, 0.0, 0.0),
            DVec3::new(0.06, 0.05, 0.0),
            DVec3::new(-0.01, 0.04, 0.0),
        ];
        for x in [DVec3::new(0.02, 0.01, 0.03), DVec3::new(-0.05, 0.08, 0.02)] {
            let exact = DVec3::kernel_integral(&kernel, x, &quad, kernel.support);
            let fan = polygon(&kernel, x, &[quad[0], quad[1], quad[2]])
                + polygon(&kernel, x, &[quad[0], quad[2], quad[3]]);
            let bilinear = polygon(&kernel, x, &quad);
            let five = [
                quad[0],
                quad[1],
                quad[2],
                quad[3],
                quad[3] * 0.5 + quad[0] * 0.5,
            ];
            assert!((fan - exact).abs() < 5e-3 * exact, "{fan} vs {exact}");
            assert!(
                (bilinear - exact).abs() < 5e-3 * exact,
                "{bilinear} vs {exact}"
            );
            assert!((polygon(&kernel, x, &five) - exact).abs() < 5e-3 * exact);
        }
        let k2 = Wendland::new(0.1, 2);
        let box2 = box_elements_2d(DVec2::ZERO, DVec2::ONE, &[], 0.05);
        for x in [DVec2::new(0.5, 0.025), DVec2::new(0.025, 0.025)] {
            for s in &box2 {
                let exact = DVec2::kernel_integral(&k2, x, &s.corners, k2.support);
                let gauss = segment(&k2, x, s.corners[0], s.corners[1]);
                assert!((gauss - exact).abs() < 2e-3 / k2.h, "{gauss} vs {exact}");
            }
        }
    }
}
