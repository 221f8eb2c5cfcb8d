//! The geometric Shepard factor (paper 2): `gamma(x) = int_Omega W(y - x) dy` computed from
//! the wall elements alone, so free surfaces do not change it.
//!
//! `gamma(x) = 1 + sum_j r_n,j int_{S_j} F(|y - x|) dS` (paper 2, eq 8), each element's
//! Shepard contribution exact ([`crate::bi`]: closed forms on 2-D segments, fan triangles on
//! 3-D polygons). A point on a wall is evaluated a distance `1e-12 h` inside the fluid, the
//! limit from the fluid side (`gamma = 1/2` on a flat wall, `1/4` at a right-angled corner in
//! 2-D). Simulations sum over merged pieces instead of elements
//! ([`super::gamma_cache::GammaCache`]).

use super::BoundaryElements;
use crate::bi;
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::CellGrid;

/// Geometric Shepard factor at `x` from the wall elements near it (paper 2, eq 8).
///
/// A point on a wall element is first moved `1e-12 h` into the fluid, along the sum of the
/// inward normals of the elements it lies on (the one-sided limit, exact to about `1e-12`).
/// Every element that overlaps the support is visited, whatever the grid's cell size. When
/// `elements` carry a [`super::gamma_cache::GammaCache`] built for this kernel (simulations
/// build one), its merged pieces and candidate lists are used instead of the walk over `grid`.
pub fn gamma<V: Vector>(
    kernel: &Wendland,
    x: V,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
) -> f64 {
    if elements.gamma_cache.is_built_for(kernel.support) {
        return elements.gamma_cache.gamma(kernel, x);
    }
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
            gamma += bi::shepard(
                kernel,
                x - image,
                elements.current_corners(j),
                elements.normal[j],
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
    use crate::neighbours::Periodicity;
    use crate::walls::gamma_cache::GammaCache;
    use glam::{DVec2, DVec3};
    use std::f64::consts::PI;

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

    /// Gamma from the cache against the element-by-element walk at `points`.
    fn cache_matches_walk<V: Vector>(
        kernel: &Wendland,
        e: &BoundaryElements<V>,
        period: Periodicity<V>,
        points: &[V],
        tolerance: f64,
    ) {
        let mut grid = CellGrid::with_period(kernel.support, period).unwrap();
        grid.rebuild(&e.centre);
        let mut cached = e.clone();
        cached
            .gamma_cache
            .rebuild(e.geometry(), kernel.support, period);
        assert!(cached.gamma_cache.pieces() <= e.len());
        for &x in points {
            let walk = gamma(kernel, x, e, &grid);
            let fast = gamma(kernel, x, &cached, &grid);
            assert!(
                (walk - fast).abs() < tolerance,
                "at {x:?}: walk {walk} cache {fast}"
            );
        }
    }

    /// Seeded uniform numbers in `[0, 1)` (a 64-bit linear congruential generator).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A scatter of points over `[lo, hi]` plus the given extra ones.
    fn scatter_2d(lo: DVec2, hi: DVec2, n: usize, extra: &[DVec2]) -> Vec<DVec2> {
        let mut next = uniform(12345);
        let mut v: Vec<DVec2> = (0..n)
            .map(|_| lo + (hi - lo) * DVec2::new(next(), next()))
            .collect();
        v.extend_from_slice(extra);
        v
    }

    #[test]
    fn cache_merges_straight_walls_and_matches_the_walk() {
        let kernel = Wendland::new(0.02, 2);
        let dx = 0.01;
        let mut e = BoundaryElements::default();
        for s in box_elements_2d(DVec2::ZERO, DVec2::new(1.0, 0.6), &["+y".into()], dx) {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        // A polygon of unequal segments (a circle of 40 sides, radius 0.1) inside the box.
        let c = DVec2::new(0.5, 0.3);
        for k in 0..40 {
            // Unequal sides.
            let angle = |k: usize| {
                let t = 2.0 * PI * (k % 40) as f64 / 40.0;
                t + 0.05 * (3.0 * t).sin()
            };
            let (a0, a1) = (angle(k), angle(k + 1));
            let (p0, p1) = (
                c + 0.1 * DVec2::new(a0.cos(), a0.sin()),
                c + 0.1 * DVec2::new(a1.cos(), a1.sin()),
            );
            let t = (p1 - p0).normalize();
            // Fluid outside the circle: normals point into it.
            e.push(
                (p0 + p1) * 0.5,
                DVec2::new(-t.y, t.x),
                (p1 - p0).length(),
                1,
                &[p0, p1],
            );
        }
        let mut cached = e.clone();
        cached
            .gamma_cache
            .rebuild(e.geometry(), kernel.support, Periodicity::none());
        // Bottom, right and left walls, one piece each; the circle's 40 sides.
        assert_eq!(cached.gamma_cache.pieces(), 3 + 40);
        let extra = [
            DVec2::new(0.5, 0.0),
            DVec2::new(0.503, 0.0),
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 0.3),
            DVec2::new(0.5, 0.2),
            DVec2::new(0.5, 0.62),
            DVec2::new(-0.5, 0.3),
            DVec2::new(0.4, 0.3), // inside the circle (behind its wall)
        ];
        let points = scatter_2d(
            DVec2::new(-0.05, -0.05),
            DVec2::new(1.05, 0.7),
            4000,
            &extra,
        );
        cache_matches_walk(&kernel, &e, Periodicity::none(), &points, 1e-12);
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let g = |x: f64, y: f64| gamma(&kernel, DVec2::new(x, y), &cached, &grid);
        assert!((g(0.5, 0.0) - 0.5).abs() < 1e-10);
        assert!((g(0.503, 0.0) - 0.5).abs() < 1e-10);
        assert!((g(0.0, 0.0) - 0.25).abs() < 1e-10);
        assert!((g(1.0, 0.0) - 0.25).abs() < 1e-10);
        assert_eq!(g(0.25, 0.3), 1.0);
    }

    #[test]
    fn cache_sees_periodic_images() {
        // A channel periodic along x: floor and ceiling cut into elements, the floor's
        // elements wrapped so that one straddles the period's ends.
        let kernel = Wendland::new(0.02, 2);
        let period = Periodicity {
            min: DVec2::ZERO,
            length: DVec2::new(0.5, 0.0),
        };
        let mut e = BoundaryElements::default();
        let shapes =
            crate::geometry::segment_elements(DVec2::new(0.013, 0.0), DVec2::new(0.513, 0.0), 0.01);
        for s in shapes.into_iter().chain(crate::geometry::segment_elements(
            DVec2::new(0.5, 0.2),
            DVec2::new(0.0, 0.2),
            0.01,
        )) {
            let w = period.wrap(s.centre) - s.centre;
            let corners: Vec<DVec2> = s.corners.iter().map(|&c| c + w).collect();
            e.push(s.centre + w, s.normal, s.area, 0, &corners);
        }
        let points = scatter_2d(
            DVec2::new(0.0, -0.01),
            DVec2::new(0.5, 0.21),
            3000,
            &[
                DVec2::new(0.0, 0.0),
                DVec2::new(0.013, 0.0),
                DVec2::new(0.4999, 0.2),
                DVec2::new(0.7, 0.01), // outside the primary period
            ],
        );
        cache_matches_walk(&kernel, &e, period, &points, 1e-12);
    }

    #[test]
    fn cache_matches_the_walk_in_3d() {
        let kernel = Wendland::new(0.1, 3);
        let mut next = uniform(777);
        let mut points: Vec<DVec3> = (0..300)
            .map(|_| DVec3::new(next(), next(), next()) * 1.2 - DVec3::splat(0.1))
            .collect();
        points.extend([
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.37, 1.0),
        ]);
        for (name, e) in cube_walls(0.05) {
            // On a wall the walk moves a point 1e-12 h off the wall once per element it lies
            // on (up to eight triangles), the cache once per face: 1e-10 apart there.
            cache_matches_walk(&kernel, &e, Periodicity::none(), &points, 1e-10);
            // Each face one rectangle of four edges.
            let mut cache = GammaCache::default();
            cache.rebuild(e.geometry(), kernel.support, Periodicity::none());
            assert_eq!(cache.pieces(), 6, "{name}");
            for p in 0..6 {
                assert_eq!(cache.piece_corners(p).len(), 8, "{name}");
            }
        }
    }
}
