//! Free edges of the wall surface: the edges (end points in 2-D) that bound a single element,
//! such as the rim of a box wall's open side or the ends of an open polyline. Water that goes
//! over such an edge to the back of the wall has left the region the walls bound.

use super::Walls;
use crate::bi::segment::point_segment_distance;
use crate::dim::Vector;

impl<V: Vector> Walls<V> {
    /// Whether a free edge of the wall surface passes within `radius` of `x`: an edge of an
    /// element (an end point of a 2-D segment) that no other element shares. Edges are shared
    /// when their end points agree to `1e-9` of the largest element reach, either way round.
    /// Only the elements near `x` are looked at, so the cost is that of a neighbour search.
    pub fn near_free_edge(&self, x: V, radius: f64) -> bool {
        let e = &self.elements;
        // An edge within `radius` of `x` belongs to an element whose centre lies within
        // `radius` plus its reach, and every element sharing that edge lies within one more
        // reach.
        let mut near = Vec::new();
        self.grid
            .for_each_candidate_within_shifted(x, radius + 2.0 * e.max_reach, |j, shift| {
                near.push((j, shift));
            });
        let eps = 1e-9 * e.max_reach;
        let same = |a: V, b: V| (a - b).length_squared() <= eps * eps;
        let edges = |j: usize, shift: V| -> Vec<(V, V)> {
            let c: Vec<V> = e.current_corners(j).iter().map(|&p| p + shift).collect();
            match c.len() {
                0 | 1 => Vec::new(),
                2 => vec![(c[0], c[0]), (c[1], c[1])],
                m => (0..m).map(|k| (c[k], c[(k + 1) % m])).collect(),
            }
        };
        near.iter().any(|&(j, shift)| {
            edges(j, shift).into_iter().any(|(a, b)| {
                point_segment_distance(x, a, b) <= radius
                    && !near.iter().any(|&(k, other)| {
                        k != j
                            && edges(k, other).into_iter().any(|(c, d)| {
                                (same(a, c) && same(b, d)) || (same(a, d) && same(b, c))
                            })
                    })
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::Body;
    use crate::walls::BoundaryElements;
    use glam::{DVec2, DVec3};

    /// The walls of a unit square tank in 2-D, its top open: three walls of `n` segments
    /// each, normals out of the fluid.
    fn open_tank_2d(n: usize) -> Walls<DVec2> {
        let mut e = BoundaryElements::default();
        let corners = [
            (
                DVec2::new(0.0, 1.0),
                DVec2::new(0.0, 0.0),
                DVec2::new(-1.0, 0.0),
            ),
            (
                DVec2::new(0.0, 0.0),
                DVec2::new(1.0, 0.0),
                DVec2::new(0.0, -1.0),
            ),
            (
                DVec2::new(1.0, 0.0),
                DVec2::new(1.0, 1.0),
                DVec2::new(1.0, 0.0),
            ),
        ];
        for (from, to, normal) in corners {
            for k in 0..n {
                let a = from + (to - from) * (k as f64 / n as f64);
                let b = from + (to - from) * ((k + 1) as f64 / n as f64);
                e.push((a + b) * 0.5, normal, (b - a).length(), 0, &[a, b]);
            }
        }
        Walls::new(e, vec![Body::fixed("walls")], 0.1)
    }

    /// The five faces of a unit cube, its top open, each split into `n x n` squares.
    fn open_box_3d(n: usize) -> Walls<DVec3> {
        let mut e = BoundaryElements::default();
        // Each face: origin, two edge vectors, outward normal.
        let faces = [
            (DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::NEG_Z),
            (DVec3::ZERO, DVec3::Y, DVec3::Z, DVec3::NEG_X),
            (DVec3::X, DVec3::Y, DVec3::Z, DVec3::X),
            (DVec3::ZERO, DVec3::X, DVec3::Z, DVec3::NEG_Y),
            (DVec3::Y, DVec3::X, DVec3::Z, DVec3::Y),
        ];
        let s = 1.0 / n as f64;
        for (o, u, v, normal) in faces {
            for i in 0..n {
                for k in 0..n {
                    let p = |a: usize, b: usize| o + u * (a as f64 * s) + v * (b as f64 * s);
                    let c = [p(i, k), p(i + 1, k), p(i + 1, k + 1), p(i, k + 1)];
                    let centre = (c[0] + c[1] + c[2] + c[3]) * 0.25;
                    e.push(centre, normal, s * s, 0, &c);
                }
            }
        }
        Walls::new(e, vec![Body::fixed("walls")], 0.2)
    }

    #[test]
    fn the_rim_of_an_open_tank_is_its_only_free_edge_in_2d() {
        let w = open_tank_2d(10);
        let r = 0.05;
        // Just outside the two top corners: the ends of the open polyline.
        assert!(w.near_free_edge(DVec2::new(-0.02, 0.98), r));
        assert!(w.near_free_edge(DVec2::new(1.03, 1.01), r));
        // Along the walls, at the bottom corners and at the seams between segments: none.
        for x in [
            DVec2::new(-0.02, 0.5),
            DVec2::new(0.0, 0.0),
            DVec2::new(0.5, -0.01),
            DVec2::new(0.3, 0.02),
            DVec2::new(1.0, 0.9),
        ] {
            assert!(!w.near_free_edge(x, r), "{x}");
        }
    }

    #[test]
    fn the_rim_of_an_open_box_is_its_only_free_edge_in_3d() {
        let w = open_box_3d(8);
        let r = 0.05;
        for x in [
            DVec3::new(-0.01, 0.5, 0.98),
            DVec3::new(0.5, 1.02, 0.99),
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(0.3, 0.0, 1.04),
        ] {
            assert!(w.near_free_edge(x, r), "{x}");
        }
        // The floor, the vertical and bottom edges of the box, the seams of the faces.
        for x in [
            DVec3::new(0.5, 0.5, -0.01),
            DVec3::new(0.0, 0.0, 0.5),
            DVec3::new(1.0, 0.5, 0.0),
            DVec3::new(-0.01, 0.5, 0.5),
            DVec3::new(0.375, 0.25, 0.0),
            DVec3::new(-0.01, 0.5, 0.94),
        ] {
            assert!(!w.near_free_edge(x, r), "{x}");
        }
    }
}
