//! Lower bounds of the particles' distances to the walls, measured when the explicit
//! scheme's Verlet list is built and valid while it holds, for the particles that have not
//! moved more than half the skin since (the others lose theirs). They spare the elastic
//! bounce and the wall-crossing watch the element search for particles that no wall can
//! concern within a step. A particle that lies behind a wall at the measurement (water that
//! went over the rim of an open wall) gets no bound, so the watch looks at it at every step.
//!
//! Each particle holds two bounds. The fixed walls' bound is the distance to the nearest disc
//! of an element's reach about its centre in its plane: the element lies within it, and the
//! bounce reflects a particle that crosses the plane within it. Walls of moving bodies keep their bound as they move: an element's
//! surface lies within its reach of its centre whatever the body's pose, so the distance to its
//! centre less its reach falls by at most the distance the centre has moved since the
//! measurement, and [`WallClearance::follow`] takes the largest such distance off the moving
//! walls' bounds only. Elements that stretch with a piston change their reach, so walls with
//! such elements get no bounds.

use super::Walls;
use crate::bodies::Motion;
use crate::dim::Vector;
use crate::neighbours::CandidateRows;
use rayon::prelude::*;

/// Relative allowance on an element's reach (the bounce's own test allows `1e-6`).
const REACH_ALLOWANCE: f64 = 1e-5;

/// Per particle, a distance below which no wall surface comes (see the module documentation).
#[derive(Clone, Debug)]
pub struct WallClearance<V> {
    /// The distance from `x_i` to the nearest of the fixed walls' element discs (the disc of
    /// an element's reach about its centre in its plane, which holds the element) in the
    /// wall-grid cells around it at the measurement, each reach widened by
    /// [`REACH_ALLOWANCE`] and the distance lowered by as much; at most one cell less the
    /// largest reach (no farther element can come closer).
    fixed_bound: Vec<f64>,
    /// `min_j (|x_i - c_j| - reach_j)` over the moving bodies' elements in those cells, each
    /// reach widened by [`REACH_ALLOWANCE`], with the same ceiling (the ceiling alone where no
    /// body moves).
    moving_bound: Vec<f64>,
    /// How far a particle may have moved since the measurement.
    slack: f64,
    /// The element centres at the measurement, where some body moves (else empty).
    centres: Vec<V>,
    /// The largest distance an element centre has moved since the measurement.
    wall_drift: f64,
    measured: bool,
}

impl<V> Default for WallClearance<V> {
    fn default() -> Self {
        WallClearance {
            fixed_bound: Vec::new(),
            moving_bound: Vec::new(),
            slack: 0.0,
            centres: Vec::new(),
            wall_drift: 0.0,
            measured: false,
        }
    }
}

impl<V: Vector> WallClearance<V> {
    /// Measures the bounds at `points`; `slack` is how far a particle may move before the
    /// caller measures again or [`WallClearance::forget`]s them. Points behind a wall within a
    /// cell less the largest reach ([`Walls::signed_distance`] positive) get no bounds, nor
    /// does any point where elements stretch with a piston. `rows`, when given, lists for the
    /// first points the elements within its listing radius of them (built at `points`, no
    /// wider than a cell of the wall grid): those points look at their rows instead of the
    /// grid's cells, and the ceiling is the listing radius less the largest reach (no
    /// element left out can come closer).
    pub fn measure(
        &mut self,
        walls: &Walls<V>,
        points: &[V],
        slack: f64,
        rows: Option<&CandidateRows<V>>,
    ) {
        if !walls.stretch.is_empty() {
            self.forget();
            return;
        }
        let (elements, grid) = (&walls.elements, &walls.grid);
        let reach = |j: usize| elements.reach[j] * (1.0 + REACH_ALLOWANCE);
        let allowed_reach = elements.max_reach * (1.0 + REACH_ALLOWANCE);
        let behind_search = (grid.cell_size() - allowed_reach).max(0.5 * grid.cell_size());
        let listed = rows.map_or(0, |rows| rows.len());
        let cell = rows.map_or(grid.cell_size(), |rows| {
            grid.cell_size().min(rows.listing_radius())
        });
        let far = cell - allowed_reach;
        let moving: Vec<bool> = walls
            .bodies
            .iter()
            .map(|b| !matches!(b.motion, Motion::Fixed))
            .collect();
        let moves = |j: usize| moving[elements.body[j] as usize];
        self.fixed_bound.resize(points.len(), 0.0);
        self.moving_bound.resize(points.len(), 0.0);
        let centres = &elements.centre;
        self.fixed_bound
            .par_iter_mut()
            .zip(self.moving_bound.par_iter_mut())
            .zip(points.par_iter())
            .enumerate()
            .with_min_len(1024)
            .for_each(|(i, ((fixed, moving), &x))| {
                (*fixed, *moving) = (far, far);
                // `r` runs from element `j`'s centre to `x`.
                let mut visit = |j: usize, r: V| {
                    let d = r.length() - reach(j);
                    if moves(j) {
                        *moving = moving.min(d);
                    } else if d < *fixed {
                        let disc = distance_to_disc(r, elements.normal[j], reach(j));
                        *fixed = fixed.min((disc - REACH_ALLOWANCE * elements.reach[j]).max(d));
                    }
                };
                match rows.filter(|_| i < listed) {
                    Some(rows) => rows.for_each_listed(i, x, centres, |j, r_xj| visit(j, -r_xj)),
                    None if grid.no_candidates(x) => return,
                    None => grid
                        .for_each_candidate_shifted(x, |j, shift| visit(j, x - centres[j] - shift)),
                }
                if fixed.min(*moving) < far
                    && walls.may_be_behind(x, behind_search)
                    && walls
                        .signed_distance(x, behind_search)
                        .is_some_and(|d| d > 0.0)
                {
                    *fixed = f64::NEG_INFINITY;
                }
            });
        self.slack = slack;
        self.centres.clear();
        if walls.has_moving_bodies() {
            self.centres.extend_from_slice(&elements.centre);
        }
        self.wall_drift = 0.0;
        self.measured = !elements.is_empty();
    }

    /// Takes the walls' motion since the measurement into account (after the walls were
    /// placed anew): the largest distance an element centre has moved since then.
    pub fn follow(&mut self, walls: &Walls<V>) {
        if !self.measured || self.centres.is_empty() {
            return;
        }
        let now = &walls.elements.centre;
        self.wall_drift = if now.len() == self.centres.len() {
            now.iter()
                .zip(&self.centres)
                .map(|(&c, &c0)| (c - c0).length())
                .fold(0.0, |a, d| if d > a || d.is_nan() { d } else { a })
        } else {
            f64::INFINITY
        };
    }

    /// Drops the bounds of the particles `moved` (they have moved farther than the slack
    /// since the measurement): none of them is clear until the next measurement.
    pub fn forget_points(&mut self, moved: &[u32]) {
        for &i in moved {
            if let Some(bound) = self.fixed_bound.get_mut(i as usize) {
                *bound = f64::NEG_INFINITY;
            }
            if let Some(bound) = self.moving_bound.get_mut(i as usize) {
                *bound = f64::NEG_INFINITY;
            }
        }
    }

    /// Keeps the bounds of the particles `kept` (old indices, increasing), renumbered `0..`
    /// in that order (the others were removed).
    pub fn retain(&mut self, kept: &[u32]) {
        if self.measured {
            self.fixed_bound = kept.iter().map(|&i| self.fixed_bound[i as usize]).collect();
            self.moving_bound = kept
                .iter()
                .map(|&i| self.moving_bound[i as usize])
                .collect();
        }
    }

    /// Drops the bounds (the particles were reordered).
    pub fn forget(&mut self) {
        self.measured = false;
    }

    /// `true` when particle `i` (in the memory order of the measurement) is provably farther
    /// than `distance` from every wall surface; `false` when that is not known (no
    /// measurement, or no particle `i` in it).
    #[inline(always)]
    pub fn clear(&self, i: usize, distance: f64) -> bool {
        self.measured
            && self
                .fixed_bound
                .get(i)
                .zip(self.moving_bound.get(i))
                .is_some_and(|(&fixed, &moving)| {
                    fixed.min(moving - self.wall_drift) - self.slack > distance
                })
    }
}

/// Distance from the point `r` (from an element's centre) to the disc of radius `reach`
/// about the centre in the element's plane (normal `n`; in 2-D, the segment of half-length
/// `reach`): the element lies within it, and the bounce reflects a particle crossing the
/// plane within it.
fn distance_to_disc<V: Vector>(r: V, n: V, reach: f64) -> f64 {
    let normal = r.dot(n);
    let beyond = ((r - n * normal).length() - reach).max(0.0);
    (normal * normal + beyond * beyond).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::{Body, Motion, PrescribedMotion};
    use crate::geometry::box_elements_3d;
    use crate::walls::BoundaryElements;
    use glam::DVec3;

    /// A unit box open at the top, in square elements of side 0.1, on a grid of cells 0.25.
    fn open_box() -> Walls<DVec3> {
        let mut e = BoundaryElements::default();
        for s in box_elements_3d(DVec3::ZERO, DVec3::ONE, &["+z".to_string()], 0.1) {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        Walls::new(e, vec![Body::fixed("walls")], 0.25)
    }

    /// The box of [`open_box`] as body 1, sliding and turning about its centre.
    fn moving_box() -> Walls<DVec3> {
        let mut walls = open_box();
        walls.elements.body.iter_mut().for_each(|b| *b = 1);
        let motion = PrescribedMotion {
            velocity: DVec3::new(0.3, -0.1, 0.2),
            amplitude: DVec3::ZERO,
            frequency: 0.0,
            phase: 0.0,
            axis: DVec3::new(1.0, 2.0, 2.0) / 3.0,
            angular_velocity: 1.5,
            angular_amplitude: 0.0,
            angular_frequency: 0.0,
        };
        walls.bodies.push(Body {
            name: "box".into(),
            centre: DVec3::splat(0.5),
            motion: Motion::Prescribed(motion),
        });
        walls.move_to(0.0);
        walls
    }

    /// Points in and around the unit box.
    fn scattered_points() -> Vec<DVec3> {
        (0..4000)
            .map(|k| {
                let f = |m: u64| ((k as u64 * m) % 1009) as f64 / 1009.0;
                DVec3::new(f(389), f(677), f(853)) * 1.4 - DVec3::splat(0.2)
            })
            .collect()
    }

    /// Distance from `x` to the nearest element, each an axis-aligned rectangle.
    fn distance_to_elements(walls: &Walls<DVec3>, x: DVec3) -> f64 {
        (0..walls.elements.len())
            .map(|j| {
                let corners = walls.elements.current_corners(j);
                let lo = corners.iter().fold(DVec3::INFINITY, |a, &c| a.min(c));
                let hi = corners.iter().fold(DVec3::NEG_INFINITY, |a, &c| a.max(c));
                (x - x.clamp(lo, hi)).length()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The bounds never exceed the distance to the walls, at points inside, outside and on
    /// them; inside (below the rim), the fixed walls' bounds are that distance (up to the
    /// allowance) where it is below the ceiling; without a measurement nothing is clear.
    #[test]
    fn bounds_stay_below_the_distance_to_the_walls() {
        let walls = open_box();
        let points = scattered_points();
        let mut clearance = WallClearance::default();
        assert!(!clearance.clear(0, 0.0));
        clearance.measure(&walls, &points, 0.0, None);
        let mut clear = 0;
        for (i, &x) in points.iter().enumerate() {
            let distance = distance_to_elements(&walls, x);
            assert!(
                clearance.fixed_bound[i] <= distance,
                "{x}: bound {} above the distance {distance}",
                clearance.fixed_bound[i]
            );
            // Below the open top, where the discs of the side walls' elements reach past
            // the rim.
            let inside = x.cmpgt(DVec3::ZERO).all() && x.cmplt(DVec3::new(1.0, 1.0, 0.8)).all();
            let ceiling = walls.grid.cell_size() - walls.elements.max_reach * (1.0 + 1e-5);
            if inside {
                assert!(
                    clearance.fixed_bound[i] >= distance.min(ceiling) - 1e-5,
                    "{x}: bound {} below the distance {distance}",
                    clearance.fixed_bound[i]
                );
            }
            clear += usize::from(clearance.clear(i, 0.05));
        }
        assert!(clear > 900, "{clear} points clear by 0.05");
        let centre = [DVec3::splat(0.5)];
        clearance.measure(&walls, &centre, 0.1, None);
        assert!(clearance.clear(0, 0.05) && !clearance.clear(0, 0.2));
        clearance.forget();
        assert!(!clearance.clear(0, 0.0));
    }

    /// Bounds measured from candidate rows listed one wall-grid cell wide are the bounds
    /// measured from the grid's cells, bit for bit, for the points the rows list and for
    /// those beyond them (the grid then serves); rows listed narrower lower the ceiling to
    /// their listing radius less the largest reach, and the bounds stay below the distances.
    #[test]
    fn rows_give_the_bounds_of_the_grid() {
        let walls = open_box();
        let points = scattered_points();
        let listed = points.len() / 2;
        let mut from_grid = WallClearance::default();
        from_grid.measure(&walls, &points, 0.0, None);
        let centres = &walls.elements.centre;
        let mut rows = CandidateRows::default();
        rows.rebuild(&walls.grid, &points[..listed], centres, 0.2, 0.05);
        let mut from_rows = WallClearance::default();
        from_rows.measure(&walls, &points, 0.0, Some(&rows));
        let bits = |c: &WallClearance<DVec3>| c.fixed_bound.iter().map(|b| b.to_bits()).collect();
        let grid_bits: Vec<u64> = bits(&from_grid);
        assert_eq!(grid_bits, bits(&from_rows));
        rows.rebuild(&walls.grid, &points[..listed], centres, 0.1, 0.05);
        from_rows.measure(&walls, &points, 0.0, Some(&rows));
        let ceiling = rows.listing_radius() - walls.elements.max_reach * (1.0 + 1e-5);
        let mut lowered = 0;
        for (i, &x) in points.iter().enumerate() {
            let bound = from_rows.fixed_bound[i];
            let distance = distance_to_elements(&walls, x);
            assert!(
                bound <= distance && bound <= ceiling,
                "{x}: {bound}, {distance}"
            );
            // Points behind a wall beyond the lowered ceiling hold it as their bound.
            let grid_bound = from_grid.fixed_bound[i];
            assert!(bound <= grid_bound || grid_bound == f64::NEG_INFINITY);
            lowered += usize::from(bound < grid_bound);
        }
        assert!(lowered > 500, "{lowered} bounds lowered");
    }

    /// A point behind a wall (out of the box, as water that went over its rim) is never
    /// clear; its mirror image inside is.
    #[test]
    fn points_behind_a_wall_get_no_bound() {
        let walls = open_box();
        let points = [DVec3::new(-0.1, 0.5, 0.5), DVec3::new(0.1, 0.5, 0.5)];
        let mut clearance = WallClearance::default();
        clearance.measure(&walls, &points, 0.0, None);
        assert!(
            !clearance.clear(0, 0.0),
            "behind: {}",
            clearance.fixed_bound[0]
        );
        assert!(
            clearance.clear(1, 0.01),
            "inside: {}",
            clearance.fixed_bound[1]
        );
    }

    /// Bounds measured before a body moves hold wherever it has moved: a point clear by a
    /// distance is farther than that from the moved walls (measured in the body's own frame,
    /// where they are the box of [`open_box`]); as the body moves away from the measurement,
    /// fewer points are clear.
    #[test]
    fn bounds_follow_a_moving_body() {
        let mut walls = moving_box();
        let at_rest = open_box();
        let points = scattered_points();
        let mut clearance = WallClearance::default();
        clearance.measure(&walls, &points, 0.0, None);
        let margin = 0.02;
        let clear_at = |clearance: &WallClearance<DVec3>| {
            (0..points.len())
                .filter(|&i| clearance.clear(i, margin))
                .count()
        };
        let mut clear = vec![clear_at(&clearance)];
        for t in [0.02, 0.05, 0.1] {
            walls.move_to(t);
            clearance.follow(&walls);
            let k = walls.bodies[1].motion.kinematics(t);
            let centre = walls.bodies[1].centre;
            for (i, &x) in points.iter().enumerate() {
                if clearance.clear(i, margin) {
                    let in_body = (x - centre - k.displacement).rotated_by(-k.rotation) + centre;
                    let distance = distance_to_elements(&at_rest, in_body);
                    assert!(distance > margin, "t = {t}, {x}: distance {distance}");
                }
            }
            clear.push(clear_at(&clearance));
        }
        assert!(clear[1] > 400, "{clear:?} points clear");
        assert!(
            clear.windows(2).all(|w| w[1] < w[0]),
            "{clear:?} points clear"
        );
    }
}
