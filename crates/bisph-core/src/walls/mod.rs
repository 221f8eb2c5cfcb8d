//! Walls as boundary elements, and the wall models that turn them into terms.
//!
//! **Normal convention (whole code):** element normals point **out of the fluid**, into the
//! wall, as in paper 1. Paper 3 uses the opposite sign; convert at its edges.

pub mod bounce;
pub mod clearance;
pub mod energy_bi;
mod free_edges;
pub mod gamma_cache;
pub mod geometric_shepard;
pub mod integrated_shepard;
pub mod robin;
pub mod shepard;
pub mod shepard_bi;
pub mod usaw;

use crate::bodies::{self, Body, Kinematics, Motion, Piston};
use crate::decomposition::ExactSum;
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::{CellGrid, Nearby, Periodicity};
use crate::particles::FluidState;
use crate::terms::viscosity::Viscosity;
use glam::DVec3;

/// Boundary elements (struct of arrays): flat wall pieces with a centre, unit normal out of the
/// fluid, area (length in 2-D), velocity and owning body.
#[derive(Clone, Debug, Default)]
pub struct BoundaryElements<V: Vector> {
    /// Current element centres `r_j`.
    pub centre: Vec<V>,
    /// Current unit normals `n_j`, out of the fluid.
    pub normal: Vec<V>,
    /// Areas `s_j` (lengths in 2-D).
    pub area: Vec<f64>,
    /// Areas in the reference configuration (stretching elements change theirs).
    pub reference_area: Vec<f64>,
    /// Velocities `U_j`.
    pub velocity: Vec<V>,
    /// Index of the owning body in [`Walls::bodies`].
    pub body: Vec<u32>,
    /// Largest distance from the centre to a corner (the element's reach in its plane).
    pub reach: Vec<f64>,
    /// Largest [`BoundaryElements::reach`] of all elements (for searches that must find every
    /// element overlapping a kernel support).
    pub max_reach: f64,
    /// Wall pressure on each element, refreshed by the wall model before each rate sweep
    /// (paper 1 eq 71 for the energy-conserving walls; extrapolated from the fluid for `bi`).
    pub pressure: Vec<f64>,
    /// The elements whose wall pressure the rate evaluations refresh (every element when
    /// empty): a part of a split run needs only those within reach of its own particles.
    pub in_reach: Vec<bool>,
    /// Centres in the body's reference configuration (time zero).
    pub reference_centre: Vec<V>,
    /// Normals in the reference configuration.
    pub reference_normal: Vec<V>,
    /// Corner points of every element in the reference configuration (for output), flattened:
    /// element `j` owns `reference_corners[corner_start[j]..corner_start[j + 1]]`.
    pub reference_corners: Vec<V>,
    /// Offsets into `reference_corners` (length = elements + 1).
    pub corner_start: Vec<u32>,
    /// Current corner points (same layout as `reference_corners`); placed by
    /// [`Walls::move_to`], set from outside by [`BoundaryElements::set_corners`] (which keeps
    /// the Gauss rules in step).
    pub corners: Vec<V>,
    /// Points and weights of each element's Gauss rule at its current place
    /// ([`crate::bi::gauss`]), in groups, flattened: element `j` owns
    /// `gauss_groups[gauss_start[j]..gauss_start[j + 1]]`.
    gauss_groups: Vec<crate::bi::gauss::PointGroup>,
    /// Offsets into `gauss_groups` (length = elements + 1).
    gauss_start: Vec<u32>,
    /// Largest distance from an element's centre to a point of its Gauss rule: no point of
    /// the rule of an element whose centre lies farther than the support plus this from a
    /// particle is in its support.
    max_gauss_reach: f64,
    /// Merged wall pieces and per-cell candidate lists for the geometric Shepard factor
    /// (empty until [`Walls::prepare_gamma`]; rebuilt whenever the walls are placed).
    pub gamma_cache: gamma_cache::GammaCache<V>,
}

impl<V: Vector> BoundaryElements<V> {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.centre.len()
    }

    /// `true` when there are no elements.
    pub fn is_empty(&self) -> bool {
        self.centre.is_empty()
    }

    /// Appends a fixed-shape element at rest, owned by `body`, with its corner points.
    pub fn push(&mut self, centre: V, normal: V, area: f64, body: u32, corners: &[V]) {
        if self.corner_start.is_empty() {
            self.corner_start.push(0);
        }
        self.centre.push(centre);
        self.normal.push(normal);
        self.area.push(area);
        self.reference_area.push(area);
        self.velocity.push(V::ZERO);
        self.body.push(body);
        self.pressure.push(0.0);
        let reach = corners
            .iter()
            .map(|&c| (c - centre).length())
            .fold(0.0, f64::max);
        self.reach.push(reach);
        self.max_reach = self.max_reach.max(reach);
        self.reference_centre.push(centre);
        self.reference_normal.push(normal);
        self.reference_corners.extend_from_slice(corners);
        self.corners.extend_from_slice(corners);
        self.corner_start.push(self.reference_corners.len() as u32);
        if self.gauss_start.is_empty() {
            self.gauss_start.push(0);
        }
        self.push_gauss_rule(corners);
    }

    /// Appends the Gauss rule of an element with corners `corners`.
    fn push_gauss_rule(&mut self, corners: &[V]) {
        let (mut points, mut weights) = (Vec::with_capacity(8), Vec::with_capacity(8));
        crate::bi::gauss_rule(corners, &mut points, &mut weights);
        let centre = self.centre[self.gauss_start.len() - 1];
        for &y in &points {
            self.max_gauss_reach = self.max_gauss_reach.max((y - centre).length());
        }
        crate::bi::gauss::group_points(&points, &weights, &mut self.gauss_groups);
        self.gauss_start.push(self.gauss_groups.len() as u32);
    }

    /// The farthest an element's centre can lie from a particle for its Gauss rule
    /// ([`BoundaryElements::gauss_integral`]) to give the particle other than zero, with
    /// kernel support `support`: the support plus the largest distance from a centre to a
    /// Gauss point, widened by `1e-9` of itself so that every point of the rule of an element
    /// farther off is beyond the support after rounding.
    pub fn gauss_reach(&self, support: f64) -> f64 {
        (support + self.max_gauss_reach) * (1.0 + 1e-9)
    }

    /// `int_{S_j} W(|y - x|) dS` over element `j` by its Gauss rule ([`crate::bi::gauss`]).
    #[inline(always)]
    pub fn gauss_integral(&self, kernel: &Wendland, x: V, j: usize) -> f64 {
        let range = self.gauss_start[j] as usize..self.gauss_start[j + 1] as usize;
        crate::bi::gauss::integral(kernel, x, &self.gauss_groups[range])
    }

    /// Sets the current corner points (the layout of `reference_corners`) and the Gauss rules
    /// that follow from them.
    pub fn set_corners(&mut self, corners: &[V]) {
        self.corners.clear();
        self.corners.extend_from_slice(corners);
        self.refresh_gauss_rules();
    }

    /// Recomputes the Gauss rules of every element from the current corners (after the
    /// corners moved).
    fn refresh_gauss_rules(&mut self) {
        self.gauss_groups.clear();
        self.gauss_start.clear();
        self.gauss_start.push(0);
        self.max_gauss_reach = 0.0;
        let corners = std::mem::take(&mut self.corners);
        for j in 0..self.len() {
            self.push_gauss_rule(
                &corners[self.corner_start[j] as usize..self.corner_start[j + 1] as usize],
            );
        }
        self.corners = corners;
    }

    /// Corner points of element `j` in the reference configuration.
    pub fn reference_corners(&self, j: usize) -> &[V] {
        &self.reference_corners[self.corner_start[j] as usize..self.corner_start[j + 1] as usize]
    }

    /// Current corner points of element `j`.
    pub fn current_corners(&self, j: usize) -> &[V] {
        &self.corners[self.corner_start[j] as usize..self.corner_start[j + 1] as usize]
    }

    /// The current geometry of the elements, borrowed (what a [`gamma_cache::GammaCache`] is
    /// built from).
    pub fn geometry(&self) -> gamma_cache::ElementGeometry<'_, V> {
        gamma_cache::ElementGeometry {
            corners: &self.corners,
            corner_start: &self.corner_start,
            normal: &self.normal,
            area: &self.area,
            centre: &self.centre,
            reach: &self.reach,
            max_reach: self.max_reach,
        }
    }
}

/// Walls: boundary elements, the bodies that own them and a cell grid over the elements.
#[derive(Clone, Debug)]
pub struct Walls<V: Vector> {
    /// The boundary elements.
    pub elements: BoundaryElements<V>,
    /// Bodies; body 0 is the fixed walls.
    pub bodies: Vec<Body<V>>,
    /// Cell grid over the element centres.
    pub grid: CellGrid<V>,
    /// Time at which the element positions were last placed.
    pub placed_at: f64,
    /// Elements that stretch with a piston so their number stays constant.
    pub stretch: Vec<Stretch>,
    /// Periodic axes: element centres are kept in the primary period (their corners move with
    /// them), so an element straddling the period is seen from both sides through the grid.
    pub periodicity: Periodicity<V>,
}

/// Wall elements aligned with a piston's axis that stretch affinely between a fixed anchor
/// and the piston face (paper 1, section 5.2): a point at `a` along the axis moves to
/// `anchor + (a - anchor) lambda`, `lambda = (face - anchor) / (face0 - anchor)`, and areas
/// scale by `lambda`.
#[derive(Clone, Debug, PartialEq)]
pub struct Stretch {
    /// The piston body.
    pub body: u32,
    /// Fixed end, as a coordinate along the piston axis.
    pub anchor: f64,
    /// The piston face in the reference configuration, along the axis.
    pub face: f64,
    /// The stretching elements.
    pub elements: Vec<u32>,
}

impl<V: Vector> Walls<V> {
    /// Walls with the given elements and bodies (body 0 must exist).
    pub fn new(elements: BoundaryElements<V>, bodies: Vec<Body<V>>, cell_size: f64) -> Self {
        let mut walls = Walls {
            elements,
            bodies,
            grid: CellGrid::new(cell_size),
            placed_at: 0.0,
            stretch: Vec::new(),
            periodicity: Periodicity::none(),
        };
        walls.grid.rebuild(&walls.elements.centre);
        walls
    }

    /// `true` when some body moves.
    pub fn has_moving_bodies(&self) -> bool {
        self.bodies
            .iter()
            .any(|b| !matches!(b.motion, Motion::Fixed))
    }

    /// Places every moving body at time `t`: element centres, normals and velocities
    /// (`U_j = v + omega x (r_j - c)`), then rebuilds the element grid.
    pub fn move_to(&mut self, t: f64) {
        self.placed_at = t;
        if !self.has_moving_bodies() {
            return;
        }
        let kin: Vec<Kinematics<V>> = self.bodies.iter().map(|b| b.motion.kinematics(t)).collect();
        let e = &mut self.elements;
        for j in 0..e.centre.len() {
            let b = e.body[j] as usize;
            if matches!(self.bodies[b].motion, Motion::Fixed) {
                continue;
            }
            let k = &kin[b];
            let c = self.bodies[b].centre + k.displacement;
            let arm = (e.reference_centre[j] - self.bodies[b].centre).rotated_by(k.rotation);
            e.centre[j] = c + arm;
            e.normal[j] = e.reference_normal[j].rotated_by(k.rotation);
            e.velocity[j] = k.velocity + V::angular_cross(k.angular_velocity, arm);
            let body_centre = self.bodies[b].centre;
            for m in e.corner_start[j] as usize..e.corner_start[j + 1] as usize {
                e.corners[m] = c + (e.reference_corners[m] - body_centre).rotated_by(k.rotation);
            }
        }
        self.place_stretching(true);
        self.wrap_corners();
        self.elements.refresh_gauss_rules();
        self.grid.rebuild(&self.elements.centre);
        self.refresh_gamma();
    }

    /// Builds the geometric-gamma cache ([`gamma_cache::GammaCache`]) for kernel
    /// support `support` from the current element positions; [`Walls::move_to`] keeps it up
    /// to date from then on.
    pub fn prepare_gamma(&mut self, support: f64) {
        let mut cache = std::mem::take(&mut self.elements.gamma_cache);
        cache.rebuild(self.elements.geometry(), support, self.periodicity);
        self.elements.gamma_cache = cache;
    }

    /// Rebuilds the geometric-gamma cache, if one was prepared, from the current element
    /// positions (after elements were moved other than by [`Walls::move_to`]).
    pub fn refresh_gamma(&mut self) {
        let support = self.elements.gamma_cache.support();
        if support > 0.0 {
            self.prepare_gamma(support);
        }
    }

    /// Moves every element whose centre left the primary period back by whole periods (its
    /// corners and Gauss rule with it).
    pub fn wrap_elements(&mut self) {
        if self.wrap_corners() {
            self.elements.refresh_gauss_rules();
        }
    }

    /// [`Walls::wrap_elements`] without the Gauss rules; `true` when some element moved.
    fn wrap_corners(&mut self) -> bool {
        if !self.periodicity.any() {
            return false;
        }
        let e = &mut self.elements;
        let mut moved = false;
        for j in 0..e.len() {
            let shift = self.periodicity.wrap(e.centre[j]) - e.centre[j];
            if shift != V::ZERO {
                e.centre[j] += shift;
                for m in e.corner_start[j] as usize..e.corner_start[j + 1] as usize {
                    e.corners[m] += shift;
                }
                moved = true;
            }
        }
        moved
    }

    /// Sets the element velocities of moving bodies to their values at time `t`, keeping the
    /// element positions (the midpoint scheme evaluates at frozen positions).
    pub fn set_velocities_at(&mut self, t: f64) {
        for (b, body) in self.bodies.iter().enumerate() {
            if matches!(body.motion, Motion::Fixed) {
                continue;
            }
            let k = body.motion.kinematics(t);
            let now = body.motion.kinematics(self.placed_at);
            let centre = body.centre + now.displacement;
            let e = &mut self.elements;
            for j in 0..e.len() {
                if e.body[j] as usize == b {
                    e.velocity[j] =
                        k.velocity + V::angular_cross(k.angular_velocity, e.centre[j] - centre);
                }
            }
        }
        self.place_stretching(false);
    }

    /// Stretching elements: positions (when `positions`) and velocities from their piston.
    fn place_stretching(&mut self, positions: bool) {
        for group in &self.stretch {
            let Motion::Piston(p) = self.bodies[group.body as usize].motion else {
                continue;
            };
            let length0 = group.face - group.anchor;
            let lambda = (length0 + p.position) / length0;
            let rate = p.velocity / length0;
            let e = &mut self.elements;
            for &j in &group.elements {
                let j = j as usize;
                let along = e.reference_centre[j].dot(p.axis) - group.anchor;
                e.velocity[j] = p.axis * (along * rate);
                if positions {
                    e.centre[j] = e.reference_centre[j] + p.axis * (along * (lambda - 1.0));
                    e.area[j] = e.reference_area[j] * lambda;
                    let mut reach: f64 = 0.0;
                    for m in e.corner_start[j] as usize..e.corner_start[j + 1] as usize {
                        let a = e.reference_corners[m].dot(p.axis) - group.anchor;
                        e.corners[m] = e.reference_corners[m] + p.axis * (a * (lambda - 1.0));
                        reach = reach.max((e.corners[m] - e.centre[j]).length());
                    }
                    e.reach[j] = reach;
                    e.max_reach = e.max_reach.max(reach);
                }
            }
        }
    }

    /// Generalised accelerations of every dynamic body (pistons, free bodies), in body order
    /// and the layout of [`Motion::accelerations`], from the wall loads `loads` (one per body,
    /// [`Walls::body_loads`]) and the bodies' current (midpoint) velocities. A piston:
    /// `(F_fluid . axis - F_out) / m`; a free body: [`FreeBody::accelerations`]. Bodies with
    /// `iterated == false` and `all == false` keep their stored accelerations (staggered
    /// coupling).
    pub fn body_accelerations(&self, all: bool, loads: &[(V, V::Angular)]) -> Vec<f64> {
        let mut out = Vec::new();
        for (b, &(force, torque)) in self.bodies.iter().zip(loads) {
            if !all && !b.motion.iterated() {
                b.motion.accelerations(&mut out);
                continue;
            }
            match b.motion {
                Motion::Piston(p) => out.push((force.dot(p.axis) - p.outside_force) / p.mass),
                Motion::Free(free) => {
                    let f = DVec3::from_array(force.to_xyz());
                    let (a, alpha) = free.accelerations(f, bodies::angular_to_3d::<V>(torque));
                    out.extend(a.to_array());
                    out.extend(alpha.to_array());
                }
                _ => {}
            }
        }
        out
    }

    /// `true` when some body moves under the fluid's loads (a piston or a free body).
    pub fn has_dynamic_bodies(&self) -> bool {
        self.bodies
            .iter()
            .any(|b| matches!(b.motion, Motion::Piston(_) | Motion::Free(_)))
    }

    /// Staggered coupling: bodies that do not iterate with the fluid take the accelerations of
    /// the wall loads `loads` (used through the next step); the others keep theirs.
    pub fn update_staggered(&mut self, loads: &[(V, V::Angular)]) {
        if self.bodies.iter().all(|b| b.motion.iterated()) {
            return;
        }
        let fresh = self.body_accelerations(true, loads);
        let mut k = 0;
        for b in &mut self.bodies {
            let mut n = Vec::new();
            b.motion.accelerations(&mut n);
            if !b.motion.iterated() {
                b.motion.set_accelerations(&fresh[k..k + n.len()]);
            }
            k += n.len();
        }
    }

    /// Generalised velocities of every dynamic body (see [`Motion::velocities`]).
    pub fn dynamic_velocities(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for b in &self.bodies {
            b.motion.velocities(&mut out);
        }
        out
    }

    /// Generalised accelerations of every dynamic body, as stored.
    pub fn dynamic_accelerations(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for b in &self.bodies {
            b.motion.accelerations(&mut out);
        }
        out
    }

    /// Inertias of the generalised coordinates (residue weights).
    pub fn dynamic_inertias(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for b in &self.bodies {
            b.motion.inertias(&mut out);
        }
        out
    }

    /// Sets the generalised velocities of every dynamic body.
    pub fn set_dynamic_velocities(&mut self, values: &[f64]) {
        let mut k = 0;
        for b in &mut self.bodies {
            k += b.motion.set_velocities(&values[k..]);
        }
    }

    /// Sets the generalised accelerations of every dynamic body.
    pub fn set_dynamic_accelerations(&mut self, values: &[f64]) {
        let mut k = 0;
        for b in &mut self.bodies {
            k += b.motion.set_accelerations(&values[k..]);
        }
    }

    /// Moves every dynamic body through `dt` with the velocities it holds (elements are
    /// placed by the next [`Walls::move_to`]).
    pub fn drift_bodies(&mut self, dt: f64) {
        for b in &mut self.bodies {
            b.motion.drift(dt);
        }
    }

    /// Kinetic and gravity-potential energy of the free bodies.
    pub fn body_energy(&self) -> (f64, f64) {
        let mut e = (0.0, 0.0);
        for b in &self.bodies {
            if let Motion::Free(f) = &b.motion {
                e.0 += f.kinetic_energy();
                e.1 += f.potential_energy();
            }
        }
        e
    }

    /// Mutable access to the pistons, in body order.
    pub fn pistons_mut(&mut self) -> impl Iterator<Item = &mut Piston<V>> {
        self.bodies.iter_mut().filter_map(|b| match &mut b.motion {
            Motion::Piston(p) => Some(p),
            _ => None,
        })
    }

    /// Pressure force `sum_j P_j n_j s_j` and torque about the body's current centre, per body
    /// (paper 1, App. C, eqs 69-71), summed exactly ([`Walls::body_load_sums`]).
    pub fn body_loads(&self, t: f64) -> Vec<(V, V::Angular)> {
        self.loads_of_sums(&self.body_load_sums(t, |_| true))
    }

    /// Components per body in [`Walls::body_load_sums`]: the force's, then the torque's.
    pub fn load_components() -> usize {
        V::DIM + V::angular_to_vec(V::Angular::default()).len()
    }

    /// The exact sums of the loads of [`Walls::body_loads`] over the elements `j` with
    /// `counted(j)`, [`Walls::load_components`] per body: the sums of several parts of the
    /// elements merge into the bits of the whole's.
    pub fn body_load_sums(&self, t: f64, counted: impl Fn(usize) -> bool) -> Vec<ExactSum> {
        let per_body = Self::load_components();
        let mut sums = vec![ExactSum::new(); self.bodies.len() * per_body];
        let centres: Vec<V> = self
            .bodies
            .iter()
            .map(|b| b.centre + b.motion.kinematics(t).displacement)
            .collect();
        let e = &self.elements;
        for j in (0..e.len()).filter(|&j| counted(j)) {
            let b = e.body[j] as usize;
            let f = e.normal[j] * (e.pressure[j] * e.area[j]);
            let torque = V::angular_to_vec((e.centre[j] - centres[b]).cross(f));
            let body = &mut sums[b * per_body..(b + 1) * per_body];
            for (k, sum) in body.iter_mut().enumerate().take(V::DIM) {
                sum.add(f.get(k));
            }
            for (sum, m) in body[V::DIM..].iter_mut().zip(torque) {
                sum.add(m);
            }
        }
        sums
    }

    /// The loads per body of the sums of [`Walls::body_load_sums`].
    pub fn loads_of_sums(&self, sums: &[ExactSum]) -> Vec<(V, V::Angular)> {
        let values: Vec<f64> = sums.iter().map(ExactSum::value).collect();
        values
            .chunks(Self::load_components())
            .map(|c| {
                (
                    V::from_slice(&c[..V::DIM]),
                    V::angular_from_slice(&c[V::DIM..]),
                )
            })
            .collect()
    }

    /// `false` when `x` is in front of the plane of every element that comes within `radius`
    /// of it (to 1e-9 `radius`): then [`Walls::signed_distance`] is not positive, since being
    /// behind the surface means being behind the plane of an element meeting at the nearest
    /// point. One dot product per candidate: the cheap pre-test of the wall-crossing watch.
    pub fn may_be_behind(&self, x: V, radius: f64) -> bool {
        let e = &self.elements;
        let slack = -1e-9 * radius;
        let mut behind = false;
        self.grid
            .for_each_candidate_within_shifted(x, radius + e.max_reach, |j, shift| {
                behind |= (x - e.centre[j] - shift).dot(e.normal[j]) > slack;
            });
        behind
    }

    /// Signed distance from `x` to the wall surface, positive behind it (on the side the
    /// normals point to, out of the fluid), from the nearest point `q` on the elements that
    /// come within `radius` of `x`; `None` when none does. The side is that of the
    /// angle-weighted pseudonormal at `q` (Baerentzen & Aanaes 2005): the element's normal on
    /// its interior, the sum of the normals of the elements meeting at `q` on an edge (weight
    /// pi each) or a corner (weight: each element's interior angle there), which gives the
    /// exact side for closed polygons and closed meshes, convex and concave corners alike.
    /// Points whose nearest feature is the free end of an open polyline (the free edge or
    /// corner of a single 3-D element) count as in front (negative): nothing bounds the fluid
    /// there. Back-to-back elements (a thin plate seen from both sides) cancel and count as in
    /// front too. Exact ties are resolved by element order, so the result is deterministic.
    pub fn signed_distance(&self, x: V, radius: f64) -> Option<f64> {
        let e = &self.elements;
        let search = radius + e.max_reach;
        // An element whose centre is farther than `bound` plus its reach holds no point within
        // `bound`; every centre seen so far bounds the distance to the surface from above.
        let beyond = |j: usize, shift: V, bound: f64| {
            (x - e.centre[j] - shift).length_squared() > (bound + e.reach[j]).powi(2)
        };
        // First pass: the nearest point.
        let mut bound = radius;
        let mut best: Option<(f64, V)> = None;
        self.grid
            .for_each_candidate_within_shifted(x, search, |j, shift| {
                bound = bound.min((x - e.centre[j] - shift).length());
                if beyond(j, shift, bound) {
                    return;
                }
                if let Some((d2, q, _)) = nearest_on_element(e.current_corners(j), shift, x) {
                    if d2 < radius * radius && best.is_none_or(|(b, _)| d2 < b) {
                        best = Some((d2, q));
                    }
                }
            });
        let (d2, q) = best?;
        let d = d2.sqrt();
        // Second pass: the pseudonormal of the elements sharing that nearest point.
        let eps = 1e-9 * radius;
        let (mut n, mut count, mut interior) = (V::ZERO, 0usize, false);
        self.grid
            .for_each_candidate_within_shifted(x, search, |j, shift| {
                if beyond(j, shift, d + eps) {
                    return;
                }
                if let Some((dj2, qj, w)) = nearest_on_element(e.current_corners(j), shift, x) {
                    if (dj2.sqrt() - d).abs() <= eps && (qj - q).length() <= eps {
                        n += e.normal[j] * w;
                        count += 1;
                        interior |= w >= 2.0 * std::f64::consts::PI;
                    }
                }
            });
        let side = (x - q).dot(n);
        if count == 1 && !interior || side <= 0.0 {
            return Some(-d);
        }
        Some(d)
    }

    /// Number of points (fluid particles) that lie behind the walls within `radius` of them:
    /// [`Walls::signed_distance`] positive (the side of the angle-weighted pseudonormal at the
    /// nearest point of the surface, exact at edges and corners). A diagnostic of particles
    /// that got into a body or through a wall.
    pub fn count_behind(&self, points: &[V], radius: f64) -> usize {
        use rayon::prelude::*;
        points
            .par_iter()
            .filter(|&&x| {
                self.may_be_behind(x, radius)
                    && self.signed_distance(x, radius).is_some_and(|d| d > 0.0)
            })
            .count()
    }

    /// Power the fluid gives to the walls, `sum_j F_j . U_j` with `F_j = P_j n_j s_j`, summed
    /// exactly over the elements `j` with `counted(j)`.
    pub fn power_sum(&self, counted: impl Fn(usize) -> bool) -> ExactSum {
        let e = &self.elements;
        let mut sum = ExactSum::new();
        for j in (0..e.len()).filter(|&j| counted(j)) {
            let u = e.velocity[j];
            if u != V::ZERO {
                sum.add(e.pressure[j] * e.area[j] * e.normal[j].dot(u));
            }
        }
        sum
    }
}

/// Wall part of the two operators of one fluid particle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WallTerms<V> {
    /// `<grad p>_i^{dOmega}`, added to the fluid pressure gradient.
    pub pressure_gradient: V,
    /// `<div u>_i^{dOmega}`, added to the fluid velocity divergence.
    pub velocity_divergence: f64,
}

/// The state of one particle as a wall model sees it.
#[derive(Clone, Copy, Debug)]
pub struct ParticleView<V> {
    /// Index of the particle in the fluid arrays.
    pub index: usize,
    /// Position.
    pub x: V,
    /// Velocity.
    pub u: V,
    /// Pressure.
    pub p: f64,
    /// Density.
    pub rho: f64,
}

/// A wall model: supplies the wall part of the operators for a fluid particle and the wall
/// pressure on each element. Physical terms ask it; they never test which model is active.
pub trait WallModel<V: Vector>: Sync {
    /// `true` when the whole operator (fluid and wall sums) is divided by the particle's
    /// discrete Shepard factor `gamma_i = sum_j W_ij V_j` (paper 1, eqs 24-25).
    const RENORMALISE: bool;

    /// `true` when the density diffusion is divided by `gamma_i` as well (paper 3, eq 54).
    const RENORMALISE_DIFFUSION: bool = false;

    /// Refreshes `elements.pressure`, the wall pressure used for forces and, where the model
    /// needs it, in the wall terms, of at least the elements in reach
    /// ([`BoundaryElements::in_reach`]). Called before every rate sweep; `fluid_near` finds
    /// the particles near an element (queried by the element's index).
    fn update_wall_pressure(
        &self,
        kernel: &Wendland,
        elements: &mut BoundaryElements<V>,
        fluid: &FluidState<V>,
        fluid_near: Nearby<'_, V>,
    );

    /// Whether [`WallModel::renormalisation`] reads the discrete sum `sum_j W_ij V_j`, so the
    /// fluid sweep must accumulate it (one extra kernel value per pair).
    fn needs_discrete_shepard(&self) -> bool {
        Self::RENORMALISE
    }

    /// The Shepard factor `gamma_i` that divides the operators of a particle when
    /// [`WallModel::RENORMALISE`] is set; `discrete` is `sum_j W_ij V_j` over the fluid,
    /// `state_gamma` the gamma the particle carries (geometric, paper 2; or integrated,
    /// paper 3, eq 4).
    fn renormalisation(&self, discrete: f64, _state_gamma: f64) -> f64 {
        discrete
    }

    /// The Shepard factor `gamma_i` that divides the viscous Laplacian (paper 3, eq 18) of a
    /// particle at `x` when the model does not renormalise its operators (those that do divide
    /// the Laplacian by [`WallModel::renormalisation`] instead, and leave this at 1).
    fn laplacian_gamma(
        &self,
        _kernel: &Wendland,
        _x: V,
        _elements: &BoundaryElements<V>,
        _grid: &CellGrid<V>,
    ) -> f64 {
        1.0
    }

    /// Wall part of the viscous acceleration of a particle at `x` with velocity `u`: the
    /// laminar wall shear of paper 3 eqs 18-20, [`Viscosity::wall_shear`] summed over the
    /// elements with `|grad gamma_is| = W_is s_s` (one-point quadrature). Models with an
    /// exact `grad gamma` override it.
    fn wall_viscous(
        &self,
        kernel: &Wendland,
        viscosity: &Viscosity,
        a: &ParticleView<V>,
        elements: &BoundaryElements<V>,
        near: Nearby<'_, V>,
    ) -> V {
        let mut acceleration = V::ZERO;
        near.for_each(
            a.index,
            a.x,
            &elements.centre,
            kernel.support,
            |s, r_is, r| {
                acceleration += viscosity.wall_shear(
                    a.u,
                    elements.velocity[s],
                    r_is,
                    elements.normal[s],
                    kernel.value(r) * elements.area[s],
                );
            },
        );
        acceleration
    }

    /// Wall sums for the fluid particle `a`; `near` finds the elements near it (queried by
    /// the particle's index).
    fn particle_terms(
        &self,
        kernel: &Wendland,
        a: &ParticleView<V>,
        elements: &BoundaryElements<V>,
        near: Nearby<'_, V>,
    ) -> WallTerms<V>;
}

/// Nearest point to `x` on the element with these corners (moved by `shift`): its squared
/// distance, the point, and the angle the element subtends there (2 pi on its interior, pi on a
/// 3-D edge or at a 2-D end point, the interior angle at a 3-D corner). `None` for elements
/// without extent. 3-D elements are planar convex polygons.
pub(crate) fn nearest_on_element<V: Vector>(
    corners: &[V],
    shift: V,
    x: V,
) -> Option<(f64, V, f64)> {
    use std::f64::consts::PI;
    let m = corners.len();
    if m < 2 {
        return None;
    }
    let c = |k: usize| corners[k % m] + shift;
    if m == 2 {
        let (a, b) = (c(0), c(1));
        let ab = b - a;
        let l2 = ab.length_squared();
        if l2 <= 0.0 {
            return None;
        }
        let t = (x - a).dot(ab) / l2;
        let (q, w) = if t <= 0.0 {
            (a, PI)
        } else if t >= 1.0 {
            (b, PI)
        } else {
            (a + ab * t, 2.0 * PI)
        };
        return Some(((x - q).length_squared(), q, w));
    }
    // 3-D polygon: the projection onto its plane when it falls inside, else the nearest point
    // of its edges.
    let (p0, p1, p2) = (c(0).to_xyz(), c(1).to_xyz(), c(2).to_xyz());
    let u = DVec3::from(p1) - DVec3::from(p0);
    let v = DVec3::from(p2) - DVec3::from(p0);
    let normal = u.cross(v).normalize_or_zero();
    if normal == DVec3::ZERO {
        return None;
    }
    let xv = DVec3::from(x.to_xyz());
    let proj = xv - normal * (xv - DVec3::from(p0)).dot(normal);
    let mut inside = true;
    let mut sign = 0.0;
    for k in 0..m {
        let a = DVec3::from(c(k).to_xyz());
        let b = DVec3::from(c(k + 1).to_xyz());
        let s = (b - a).cross(proj - a).dot(normal);
        if s != 0.0 {
            if sign != 0.0 && s.signum() != sign {
                inside = false;
                break;
            }
            sign = s.signum();
        }
    }
    if inside {
        return Some((
            (xv - proj).length_squared(),
            V::from_slice(&proj.to_array()),
            2.0 * PI,
        ));
    }
    let mut best = (f64::INFINITY, DVec3::ZERO, 0.0);
    for k in 0..m {
        let a = DVec3::from(c(k).to_xyz());
        let b = DVec3::from(c(k + 1).to_xyz());
        let ab = b - a;
        let t = ((xv - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        let q = a + ab * t;
        let d2 = (xv - q).length_squared();
        if d2 < best.0 {
            let w = if t > 0.0 && t < 1.0 {
                PI
            } else {
                // The interior angle at the corner reached.
                let k0 = if t <= 0.0 { k } else { k + 1 };
                let here = DVec3::from(c(k0).to_xyz());
                let prev = DVec3::from(c(k0 + m - 1).to_xyz()) - here;
                let next = DVec3::from(c(k0 + 1).to_xyz()) - here;
                prev.angle_between(next)
            };
            best = (d2, q, w);
        }
    }
    Some((best.0, V::from_slice(&best.1.to_array()[..V::DIM]), best.2))
}

#[cfg(test)]
mod signed_distance_tests {
    use super::*;
    use crate::geometry::{box_elements_3d, polyline_elements, triangulate, winding_number};
    use glam::DVec2;

    fn walls_2d(lines: &[(&[DVec2], bool)], dx: f64) -> Walls<DVec2> {
        let mut e = BoundaryElements::default();
        for (points, closed) in lines {
            for s in polyline_elements(points, *closed, dx) {
                e.push(s.centre, s.normal, s.area, 0, &s.corners);
            }
        }
        Walls::new(e, vec![Body::fixed("walls")], 0.1)
    }

    /// A tank 2.2 m wide with a 90-degree wedge on its floor (convex and concave corners),
    /// open at the top: its polyline from the top of the left wall to that of the right one.
    fn wedge_tank() -> [DVec2; 7] {
        let s = 0.5f64.sqrt() * 0.25;
        [
            DVec2::new(0.0, 1.0),
            DVec2::new(0.0, 0.0),
            DVec2::new(0.85, 0.0),
            DVec2::new(0.85 + s, s),
            DVec2::new(0.85 + 2.0 * s, 0.0),
            DVec2::new(2.2, 0.0),
            DVec2::new(2.2, 1.0),
        ]
    }

    /// Distance from `x` to the polyline through `points`.
    fn distance_to_polyline(x: DVec2, points: &[DVec2]) -> f64 {
        points
            .windows(2)
            .map(|w| {
                let (a, b) = (w[0], w[1]);
                let t = ((x - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                (x - a - (b - a) * t).length()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// A tank with a 90-degree wedge on its floor (convex and concave corners): the sign
    /// agrees with the winding number and the magnitude with the distance to the polygon.
    #[test]
    fn signed_distance_matches_the_polygon_2d() {
        let tank = wedge_tank();
        // The tank as three polylines, as a case lists them (elements of varying length).
        let walls = walls_2d(
            &[
                (&tank[..3], false),
                (&tank[2..4], false),
                (&tank[3..], false),
            ],
            0.037,
        );
        let closed: Vec<DVec2> = tank.iter().copied().chain([DVec2::new(0.0, 1.0)]).collect();
        let radius = 0.1;
        let (mut behind, mut front) = (0, 0);
        for i in 0..223 {
            for k in 0..113 {
                let x = DVec2::new(-0.05 + 0.01003 * i as f64, -0.05 + 0.00997 * k as f64);
                if x.y > 0.95 {
                    continue; // near the open top (free ends)
                }
                let Some(d) = walls.signed_distance(x, radius) else {
                    continue;
                };
                let inside = winding_number(x, &closed[..closed.len() - 1]) != 0;
                let exact = distance_to_polyline(x, &tank);
                assert!((d.abs() - exact).abs() < 1e-12, "{x}: {d} vs {exact}");
                if exact > 1e-12 {
                    assert_eq!(d > 0.0, !inside, "{x}: {d}");
                }
                if d > 0.0 {
                    behind += 1;
                } else {
                    front += 1;
                }
            }
        }
        assert!(behind > 1000 && front > 1000, "{behind} {front}");
        // Beyond the free top end of the left wall: in front.
        assert!(
            walls
                .signed_distance(DVec2::new(-0.02, 1.03), radius)
                .unwrap()
                < 0.0
        );
        // Far from every wall: none.
        assert!(walls
            .signed_distance(DVec2::new(1.0, 0.6), radius)
            .is_none());
    }

    /// `count_behind` counts exactly the points outside the tank within reach of a wall, at
    /// the wedge's convex corners (where the nearest element centre can face away) as well.
    #[test]
    fn count_behind_counts_the_points_outside() {
        let tank = wedge_tank();
        // Elements as long as the support: the nearest centre is a poor guide at corners.
        let walls = walls_2d(&[(&tank, false)], 0.1);
        let radius = 0.1;
        let points: Vec<DVec2> = (0..223)
            .flat_map(|i| (0..95).map(move |k| (i, k)))
            .map(|(i, k)| DVec2::new(-0.05 + 0.01003 * i as f64, -0.05 + 0.00997 * k as f64))
            .collect();
        let outside = points
            .iter()
            .filter(|&&x| distance_to_polyline(x, &tank) < radius && winding_number(x, &tank) == 0)
            .count();
        assert!(outside > 500, "{outside}");
        assert_eq!(walls.count_behind(&points, radius), outside);
    }

    /// An open-top 3-D box of triangles: behind outside the box, in front inside it, at
    /// faces, edges and corners.
    #[test]
    fn signed_distance_matches_the_box_3d() {
        let mut e = BoundaryElements::default();
        let shapes = triangulate(box_elements_3d(
            DVec3::ZERO,
            DVec3::ONE,
            &["+z".to_string()],
            0.23,
        ));
        for s in shapes {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let walls = Walls::new(e, vec![Body::fixed("walls")], 0.1);
        let radius = 0.1;
        let mut n = 0;
        for i in 0..31 {
            for j in 0..31 {
                for k in 0..25 {
                    let x = DVec3::new(
                        -0.08 + 0.0387 * i as f64,
                        -0.08 + 0.0391 * j as f64,
                        -0.08 + 0.0383 * k as f64,
                    );
                    let Some(d) = walls.signed_distance(x, radius) else {
                        continue;
                    };
                    let inside = x.cmpgt(DVec3::ZERO).all() && x.cmplt(DVec3::ONE).all();
                    let q = x.clamp(DVec3::ZERO, DVec3::ONE);
                    let exact = if inside {
                        x.min_element()
                            .min((DVec3::ONE - x).truncate().min_element())
                    } else {
                        (x - q).length()
                    };
                    assert!((d.abs() - exact).abs() < 1e-12, "{x}: {d} vs {exact}");
                    assert_eq!(d > 0.0, !inside, "{x}: {d}");
                    n += 1;
                }
            }
        }
        assert!(n > 5000, "{n}");
    }
}

#[cfg(test)]
mod gauss_rule_tests {
    use super::*;
    use crate::bodies::PrescribedMotion;
    use crate::geometry::{box_elements_3d, triangulate};

    /// Each element's stored Gauss rule follows its corners: at the start, after a rotating
    /// body is placed, and after the corners are set from outside (a restored checkpoint),
    /// the stored rule gives the bits of the rule built from the current corners.
    #[test]
    fn gauss_rules_follow_moving_and_restored_corners() {
        let mut e = BoundaryElements::default();
        let mut shapes = box_elements_3d(DVec3::ZERO, DVec3::ONE, &[], 0.25);
        let quads = shapes.len();
        shapes.extend(triangulate(box_elements_3d(
            DVec3::splat(2.0),
            DVec3::splat(2.5),
            &[],
            0.25,
        )));
        for (k, s) in shapes.iter().enumerate() {
            e.push(s.centre, s.normal, s.area, (k >= quads) as u32, &s.corners);
        }
        let spin = PrescribedMotion {
            velocity: DVec3::new(0.3, 0.0, 0.1),
            amplitude: DVec3::ZERO,
            frequency: 0.0,
            phase: 0.0,
            axis: DVec3::new(0.0, 0.6, 0.8),
            angular_velocity: 2.0,
            angular_amplitude: 0.0,
            angular_frequency: 0.0,
        };
        let bodies = vec![
            Body::fixed("walls"),
            Body {
                name: "spinner".into(),
                centre: DVec3::splat(2.25),
                motion: Motion::Prescribed(spin),
            },
        ];
        let mut walls = Walls::new(e, bodies, 0.5);
        let kernel = Wendland::new(0.3, 3);
        let agree = |walls: &Walls<DVec3>| {
            let e = &walls.elements;
            for j in 0..e.len() {
                let x = e.centre[j] + e.normal[j] * -0.1 + DVec3::new(0.05, -0.03, 0.02);
                let stored = e.gauss_integral(&kernel, x, j);
                let direct = crate::bi::gauss::polygon(&kernel, x, e.current_corners(j));
                assert_eq!(stored, direct, "element {j}");
                assert!(stored > 0.0);
                // At the Gauss reach towards each corner (and so towards the Gauss points
                // nearest it), the rule gives exactly zero.
                let reach = e.gauss_reach(kernel.support);
                for &corner in e.current_corners(j) {
                    let out = e.centre[j] + (corner - e.centre[j]).normalize() * reach;
                    assert_eq!(
                        e.gauss_integral(&kernel, out, j).to_bits(),
                        0,
                        "element {j}"
                    );
                }
            }
            e.max_gauss_reach / e.max_reach
        };
        // The farthest Gauss points are the squares' (side a), at 1/sqrt(3) of their reach
        // a / sqrt(2); the largest reach is the half squares', a sqrt(5) / 3.
        let tight = |ratio: f64| assert!((ratio - 3.0 / 30f64.sqrt()).abs() < 1e-12, "{ratio}");
        tight(agree(&walls));
        walls.move_to(0.7);
        assert_ne!(walls.elements.corners, walls.elements.reference_corners);
        tight(agree(&walls));
        // Corners set apart from their centres: the Gauss reach, measured from the centres,
        // grows with the gap and still holds.
        let moved = walls.elements.corners.clone();
        walls.move_to(0.0);
        walls.elements.set_corners(&moved);
        assert!(agree(&walls) > 1.0);
    }
}
