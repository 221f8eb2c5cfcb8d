//! BIPI: boundary-integral based particle initialisation (paper 4, Boregowda & Liu).
//!
//! Step 1 (a lattice inside the region) is done by [`crate::region`]; this module does
//! step 2, shifting particles down the concentration gradient with the boundary term:
//!
//! * `<C_a> = sum_b V_b W_ab / gamma_a` (paper 4, eq 4) and
//!   `<grad C_a> = (sum_b V_b grad_a W_ab - sum_s grad gamma_as) / gamma_a` (eq 5), with the
//!   exact Shepard factor `gamma_a` and exact element integrals `grad gamma_as`
//!   ([`crate::bi`]);
//! * the shift `dx_a = -D (grad C_a - B_a)` with `D = 0.5 h^2` and the boundary push
//!   `B_a = sum_s grad gamma_as(r_push) / (2 gamma_a)` (eq 14 with `p_s = 2 p_a`), where the
//!   push integrates only the part of the wall within `r_push` of the particle: the "ramp" of
//!   paper 4's fig 3c, as the authors' code does with short edges (a ramp that is zero at
//!   `r_push` from the wall and grows as the particle approaches it). In 2-D `r_push` is the
//!   relaxed balance distance ([`relaxed_balance_distance`], `0.472 dx` at `h = 2 dx`): the
//!   wall distance at which a uniformly dense first layer has `grad C = 0` once the layers
//!   behind it have relaxed, so the push leaves eq 5's own equilibrium alone and acts only
//!   against compression beyond it (a push from `dx/2`, the particle radius, holds flat-wall
//!   layers against eq 5's midpoint residual, which then dominates the packed `|grad C|`). In
//!   3-D `r_push` is the balanced radius ([`balanced_push_radius`], `0.62 dx` at `h = 2 dx`):
//!   the disc ramp is flat, so the push must start beyond the layer's target; it holds the
//!   first layer of a uniform lattice at `dx/2` from a flat wall against its residual
//!   `grad C`, where a push within `dx/2` lets the layer sink towards `0.43 dx`; see
//!   [`default_push_radius`];
//! * the shift capped at `0.25 dx` (eq 15);
//! * stages: 2a moves only particles whose kernel is truncated (`gamma < 1`) until the total
//!   particle displacement (TPD) plateaus; 2b freezes the particles next to the wall (within
//!   `0.6 dx`); 2c moves all others for a fixed number of iterations (1000 by default).
//!
//! A particle never crosses a wall: a shift whose path touches an element is halved until it
//! does not (or dropped). Sums gather per particle, so results do not depend on threads.

use crate::bi::ElementIntegrals;
use crate::dim::Vector;
use crate::geometry::ElementShape;
use crate::kernel::Wendland;
use crate::neighbours::CellGrid;
use crate::walls::BoundaryElements;
use rayon::prelude::*;
use std::ops::ControlFlow;

/// Parameters of BIPI; lengths in units of `dx` unless said otherwise.
#[derive(Clone, Debug, PartialEq)]
pub struct PackParams {
    /// Lattice spacing `dx` [m].
    pub dx: f64,
    /// Smoothing length `h` [m] (support `2h`).
    pub h: f64,
    /// Mass of one particle (for the kinetic energy of the shifts only).
    pub mass: f64,
    /// `D / h^2` in the shift `-D grad C` (paper 4: 0.5).
    pub diffusion: f64,
    /// Largest shift per iteration, in `dx` (paper 4, eq 15: 0.25).
    pub max_shift: f64,
    /// Radius of the boundary push, in `dx`; `None`: [`default_push_radius`] (the relaxed
    /// balance distance in 2-D, the balanced radius in 3-D).
    pub push_radius: Option<f64>,
    /// Most iterations of stage 2a.
    pub stage_a_max: usize,
    /// TPD plateau test of stage 2a: window in iterations...
    pub plateau_window: usize,
    /// ...and relative change of TPD over the window below which it has plateaued.
    pub plateau_tolerance: f64,
    /// Stage 2b freezes particles closer than this to a wall, in `dx`.
    pub freeze_distance: f64,
    /// Iterations of stage 2c.
    pub stage_c_iterations: usize,
    /// Stage 2c stops early when mean `|grad C|` changes by less than this relative amount
    /// over `plateau_window` iterations (0: never).
    pub stage_c_tolerance: f64,
    /// Per-particle step control: when a particle's shift reverses direction (a shift against
    /// the previous one: the explicit iteration overshoots, as it does at the boundary push,
    /// whose ramp is steep at `push_radius`), its step factor is multiplied by this; it grows
    /// back by `1 / sqrt(step_damping)` per iteration without reversal, up to 1. Fixed points
    /// are those of eq 15 unchanged. 1 turns it off (plain eq 15).
    pub step_damping: f64,
    /// Evaluate the metrics over all particles every this many iterations during stage 2a
    /// (default 10; in between only particles near a wall are evaluated, and the metrics are
    /// NaN). Stage 2c evaluates everyone anyway.
    pub report_interval: usize,
}

impl PackParams {
    /// The paper's defaults for spacing `dx` and smoothing length `h`.
    pub fn new(dx: f64, h: f64) -> Self {
        PackParams {
            dx,
            h,
            mass: 1.0,
            diffusion: 0.5,
            max_shift: 0.25,
            push_radius: None,
            stage_a_max: 10_000,
            plateau_window: 100,
            plateau_tolerance: 0.01,
            freeze_distance: 0.6,
            stage_c_iterations: 1000,
            stage_c_tolerance: 0.0,
            step_damping: 0.5,
            report_interval: 10,
        }
    }
}

/// The stage an iteration belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The lattice before any shift (iteration 0).
    Start,
    /// 2a: particles with truncated kernels only.
    A,
    /// 2c: all particles but the frozen first layer.
    C,
}

/// Metrics of one iteration (one row of `pack.csv`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IterationStats {
    /// Iteration number (0: the lattice).
    pub iteration: usize,
    /// Stage.
    pub stage: Stage,
    /// `1/2 sum m |dx_a|^2`: kinetic energy of the shifts, taken as velocities per iteration.
    pub kinetic: f64,
    /// Total particle displacement from the start, `sum |x_a - x_a^0|` [m].
    pub tpd: f64,
    /// Mean `|grad C|` over particles with `gamma = 1` (NaN when not evaluated).
    pub gradc_mean: f64,
    /// Largest `|grad C|` over particles with `gamma = 1`.
    pub gradc_max: f64,
    /// Mean `|grad C|` over all particles.
    pub gradc_mean_all: f64,
    /// Largest `|grad C|` over all particles.
    pub gradc_max_all: f64,
    /// Particles moved in this iteration.
    pub moved: usize,
    /// Mean wall distance over `dx` of the particles closer than `dx` to a wall (the first
    /// layer; NaN when not evaluated).
    pub first_layer: f64,
    /// Mean `|grad C|` over the particles at least `dx` from every wall (all but the first
    /// layer, which the boundary push holds where `grad C` balances it, eq 14).
    pub gradc_mean_deep: f64,
}

/// Wall quantities at a point.
#[derive(Clone, Copy, Debug)]
pub struct WallSample<V> {
    /// Shepard factor `gamma` (paper 2).
    pub gamma: f64,
    /// `sum_s grad gamma_as` (into the fluid).
    pub grad_gamma: V,
    /// `sum_s grad gamma_as` over the wall within the push radius.
    pub push: V,
    /// Distance to the nearest element (infinite when none is within the support).
    pub distance: f64,
    /// Some element lies within the support.
    pub truncated: bool,
}

/// Walls for packing: elements (normals out of the region) and a grid over them.
#[derive(Clone, Debug)]
pub struct PackWalls<V: Vector> {
    /// The elements.
    pub elements: BoundaryElements<V>,
    grid: CellGrid<V>,
}

impl<V: ElementIntegrals> PackWalls<V> {
    /// Walls from element shapes, for a kernel of support `support`.
    pub fn new(shapes: &[ElementShape<V>], support: f64) -> Self {
        let mut elements = BoundaryElements::default();
        for s in shapes {
            elements.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let reach = elements.reach.iter().copied().fold(0.0, f64::max);
        let mut grid = CellGrid::new(support + reach);
        grid.rebuild(&elements.centre);
        PackWalls { elements, grid }
    }

    /// Exact wall quantities at `x` (paper 4, eqs 3-5; paper 2, eq 8).
    pub fn sample(&self, kernel: &Wendland, x: V, push_radius: f64) -> WallSample<V> {
        let e = &self.elements;
        let mut s = WallSample {
            gamma: 1.0,
            grad_gamma: V::ZERO,
            push: V::ZERO,
            distance: f64::INFINITY,
            truncated: false,
        };
        if e.is_empty() {
            return s;
        }
        let support = kernel.support;
        // A point on a wall: the Shepard factor is the limit from the fluid side.
        let mut on_wall = None;
        self.grid.for_each_candidate(x, |j| {
            if (e.centre[j] - x).length() >= support + e.reach[j] {
                return;
            }
            let corners = e.current_corners(j);
            let d = V::element_distance(x, corners);
            s.distance = s.distance.min(d);
            if d >= support {
                return;
            }
            s.truncated = true;
            if d <= 1e-9 * kernel.h {
                on_wall = Some(e.normal[j]);
            }
            let (g, w) = V::shepard_and_kernel_integral(kernel, x, corners, e.normal[j]);
            s.gamma += g;
            s.grad_gamma -= e.normal[j] * w;
            if d < push_radius {
                s.push += V::grad_gamma(kernel, x, corners, e.normal[j], push_radius);
            }
        });
        if let Some(n) = on_wall {
            let x_eval = x - n * (1e-9 * kernel.h);
            s.gamma = 1.0;
            self.grid.for_each_candidate(x_eval, |j| {
                if (e.centre[j] - x_eval).length() < support + e.reach[j] {
                    s.gamma += V::polar_shepard(kernel, x_eval, e.current_corners(j), e.normal[j]);
                }
            });
        }
        s
    }

    /// `true` when the straight path from `from` to `to` touches an element.
    pub fn path_crosses(&self, from: V, to: V) -> bool {
        let e = &self.elements;
        let span = (to - from).length();
        let mut hit = false;
        self.grid.for_each_candidate(from, |j| {
            if !hit
                && (e.centre[j] - from).length() <= span + e.reach[j]
                && V::path_crosses_element(from, to, e.current_corners(j))
            {
                hit = true;
            }
        });
        hit
    }

    /// Distance from `x` to the nearest element within reach of the grid (infinite if none).
    pub fn distance(&self, x: V) -> f64 {
        let e = &self.elements;
        let mut d = f64::INFINITY;
        self.grid.for_each_candidate(x, |j| {
            // An element whose bounding sphere lies beyond the best so far cannot be nearer.
            if (e.centre[j] - x).length() - e.reach[j] < d {
                d = d.min(V::element_distance(x, e.current_corners(j)));
            }
        });
        d
    }

    /// `true` when some element lies closer than `radius` to `x` (`radius` at most the
    /// grid's reach, the support).
    pub fn within(&self, x: V, radius: f64) -> bool {
        let e = &self.elements;
        let mut found = false;
        self.grid.for_each_candidate(x, |j| {
            if !found
                && (e.centre[j] - x).length() < radius + e.reach[j]
                && V::element_distance(x, e.current_corners(j)) < radius
            {
                found = true;
            }
        });
        found
    }
}

/// Per-particle result of one evaluation.
#[derive(Clone, Copy, Debug)]
struct Evaluation<V> {
    gradc: V,
    shift: V,
    truncated: bool,
    distance: f64,
}

/// The state of a BIPI run.
#[derive(Debug)]
pub struct Packer<V: ElementIntegrals> {
    /// Parameters.
    pub params: PackParams,
    /// Kernel.
    pub kernel: Wendland,
    /// Walls.
    pub walls: PackWalls<V>,
    /// Current positions.
    pub positions: Vec<V>,
    /// Lattice positions (start of step 2).
    pub start: Vec<V>,
    /// Particles frozen in stage 2b.
    pub frozen: Vec<bool>,
    /// Radius of the boundary push in use, in `dx`.
    pub push_radius: f64,
    /// Step factor of each particle (see [`PackParams::step_damping`]).
    step: Vec<f64>,
    /// Each particle's previous (undamped) shift.
    last_shift: Vec<V>,
    /// Stage 2a: whether each particle lies within the support of a wall (empty until then).
    near: Vec<bool>,
    /// Each particle's last wall sample and the position it was taken at: a particle that
    /// has not moved since (the frozen layer, rejected shifts) reuses it, bit for bit.
    wall_cache: Vec<Option<(V, WallSample<V>)>>,
    volume: f64,
    grid: CellGrid<V>,
    iteration: usize,
}

/// Why packing could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PackError {
    /// No particle to pack.
    #[error("no particle to pack: no lattice point of spacing {dx} lies inside the region")]
    NoParticles {
        /// The spacing.
        dx: f64,
    },
    /// A parameter is out of range.
    #[error("pack parameter `{name}` = {value}: {expected}")]
    BadParameter {
        /// Name.
        name: &'static str,
        /// Value.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
}

impl<V: ElementIntegrals> Packer<V> {
    /// A packer for the lattice `positions` bounded by `walls` (normals out of the region).
    pub fn new(
        params: PackParams,
        positions: Vec<V>,
        walls: PackWalls<V>,
    ) -> Result<Self, PackError> {
        let check = |name: &'static str, value: f64, ok: bool, expected: &'static str| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(PackError::BadParameter {
                    name,
                    value,
                    expected,
                })
            }
        };
        check(
            "dx",
            params.dx,
            params.dx > 0.0,
            "expected a positive length",
        )?;
        check("h", params.h, params.h > 0.0, "expected a positive length")?;
        check(
            "diffusion",
            params.diffusion,
            params.diffusion > 0.0,
            "expected a positive number",
        )?;
        check(
            "max_shift",
            params.max_shift,
            params.max_shift > 0.0 && params.max_shift <= 1.0,
            "expected a value in (0, 1]",
        )?;
        if let Some(r) = params.push_radius {
            check(
                "push_radius",
                r,
                r >= 0.0 && r * params.dx <= 2.0 * params.h,
                "expected a value in [0, 2h/dx]",
            )?;
        }
        check(
            "step_damping",
            params.step_damping,
            params.step_damping > 0.0 && params.step_damping <= 1.0,
            "expected a value in (0, 1]",
        )?;
        check(
            "freeze_distance",
            params.freeze_distance,
            params.freeze_distance >= 0.0,
            "expected zero or a positive number",
        )?;
        check(
            "plateau_tolerance",
            params.plateau_tolerance,
            params.plateau_tolerance >= 0.0,
            "expected zero or a positive number",
        )?;
        check(
            "stage_c_tolerance",
            params.stage_c_tolerance,
            params.stage_c_tolerance >= 0.0,
            "expected zero or a positive number",
        )?;
        if positions.is_empty() {
            return Err(PackError::NoParticles { dx: params.dx });
        }
        let kernel = Wendland::for_dim::<V>(params.h);
        let push_radius = params
            .push_radius
            .unwrap_or_else(|| default_push_radius::<V>(&kernel, params.dx));
        let n = positions.len();
        Ok(Packer {
            volume: params.dx.powi(V::DIM as i32),
            grid: CellGrid::new(kernel.support),
            kernel,
            walls,
            start: positions.clone(),
            positions,
            frozen: vec![false; n],
            push_radius,
            step: vec![1.0; n],
            last_shift: vec![V::ZERO; n],
            near: Vec::new(),
            wall_cache: vec![None; n],
            params,
            iteration: 0,
        })
    }

    /// Particle volume `V_b = dx^d`.
    pub fn volume(&self) -> f64 {
        self.volume
    }

    /// Evaluates `grad C` and the capped shift (paper 4, eqs 5, 14, 15) of the particles
    /// selected by `select` (others: `None`).
    fn evaluate(&mut self, select: impl Fn(usize) -> bool + Sync) -> Vec<Option<Evaluation<V>>> {
        self.grid.rebuild(&self.positions);
        let (kernel, walls, grid, pos) = (&self.kernel, &self.walls, &self.grid, &self.positions);
        let cache = &mut self.wall_cache;
        let p = &self.params;
        let volume = self.volume;
        let d_coef = p.diffusion * p.h * p.h;
        let cap = p.max_shift * p.dx;
        let push_radius = self.push_radius * p.dx;
        cache
            .par_iter_mut()
            .enumerate()
            .with_min_len(256)
            .map(|(i, slot)| {
                if !select(i) {
                    return None;
                }
                let x = pos[i];
                let w = match slot {
                    Some((at, w)) if *at == x => *w,
                    _ => {
                        let w = walls.sample(kernel, x, push_radius);
                        *slot = Some((x, w));
                        w
                    }
                };
                let mut sum = V::ZERO;
                grid.for_each_neighbour(x, pos, kernel.support, |_, r, _| {
                    // grad_a W_ab = grad W(x_a - x_b) = -grad W(r), r = x_b - x_a
                    sum -= kernel.gradient(r) * volume;
                });
                let gradc = (sum - w.grad_gamma) / w.gamma;
                let mut shift = -(gradc - w.push / (2.0 * w.gamma)) * d_coef;
                let len = shift.length();
                if len > cap {
                    shift = shift * (cap / len);
                }
                Some(Evaluation {
                    gradc,
                    shift,
                    truncated: w.truncated,
                    distance: w.distance,
                })
            })
            .collect()
    }

    /// One shifting iteration in `stage`; returns its metrics. `full` evaluates `grad C`
    /// for every particle (for the metrics), otherwise only for those that may move.
    fn iterate(&mut self, stage: Stage, full: bool) -> IterationStats {
        let walls_present = !self.walls.elements.is_empty();
        // In stage 2a only truncated particles move; those are within the support of a wall.
        // Only moved particles change their distance, so the flags are kept between iterations
        // and refreshed for the particles that moved.
        if stage == Stage::A && self.near.len() != self.positions.len() {
            let kernel = self.kernel;
            self.near = self
                .positions
                .par_iter()
                .map(|&x| walls_present && self.walls.within(x, kernel.support))
                .collect();
        }
        let near = std::mem::take(&mut self.near);
        let evals = self.evaluate(|i| full || stage != Stage::A || near[i]);
        self.near = near;
        let mut stats = IterationStats {
            iteration: self.iteration,
            stage,
            kinetic: 0.0,
            tpd: 0.0,
            gradc_mean: f64::NAN,
            gradc_max: f64::NAN,
            gradc_mean_all: f64::NAN,
            gradc_max_all: f64::NAN,
            moved: 0,
            first_layer: f64::NAN,
            gradc_mean_deep: f64::NAN,
        };
        if full {
            metrics(&evals, self.params.dx, &mut stats);
        }
        if stage != Stage::Start {
            let walls = &self.walls;
            let frozen = &self.frozen;
            let damping = self.params.step_damping;
            let growth = 1.0 / damping.sqrt();
            // Step control (per particle, so independent of the thread count).
            for (i, e) in evals.iter().enumerate() {
                if let Some(e) = e {
                    if !frozen[i] && (stage == Stage::C || e.truncated) {
                        self.step[i] = if e.shift.dot(self.last_shift[i]) < 0.0 {
                            self.step[i] * damping
                        } else {
                            (self.step[i] * growth).min(1.0)
                        };
                        self.last_shift[i] = e.shift;
                    }
                }
            }
            let step = &self.step;
            let moves: Vec<Option<V>> = evals
                .par_iter()
                .zip(self.positions.par_iter())
                .enumerate()
                .map(|(i, (e, &x))| {
                    let e = e.as_ref()?;
                    let movable = !frozen[i] && (stage == Stage::C || e.truncated);
                    if !movable {
                        return None;
                    }
                    let mut shift = e.shift * step[i];
                    // Never cross a wall: halve the shift until the path is clear.
                    if e.distance < walls_reach(e.shift) {
                        for _ in 0..8 {
                            if !walls.path_crosses(x, x + shift) {
                                return Some(shift);
                            }
                            shift = shift * 0.5;
                        }
                        return None;
                    }
                    Some(shift)
                })
                .collect();
            let support = self.kernel.support;
            for (i, m) in moves.iter().enumerate() {
                if let Some(s) = m {
                    self.positions[i] += *s;
                    if let Some(flag) = self.near.get_mut(i) {
                        *flag = walls_present && self.walls.within(self.positions[i], support);
                    }
                    stats.kinetic += 0.5 * self.params.mass * s.length_squared();
                    stats.moved += 1;
                }
            }
        }
        stats.tpd = self
            .positions
            .iter()
            .zip(&self.start)
            .map(|(&a, &b)| (a - b).length())
            .sum();
        stats
    }

    /// Runs stages 2a, 2b and 2c, calling `observe` with the metrics of the lattice and of
    /// every iteration; returns the metrics of all iterations. `Break` from `observe` stops
    /// packing after that iteration (the positions reached are kept).
    pub fn run(
        &mut self,
        mut observe: impl FnMut(&IterationStats) -> ControlFlow<()>,
    ) -> Vec<IterationStats> {
        let mut history = Vec::new();
        let first = self.iterate(Stage::Start, true);
        history.push(first);
        if observe(&first).is_break() {
            return history;
        }
        let p = self.params.clone();
        let has_walls = !self.walls.elements.is_empty();
        // Stage 2a.
        if has_walls {
            let mut tpd: Vec<f64> = Vec::new();
            for k in 1..=p.stage_a_max {
                self.iteration += 1;
                let full = p.report_interval > 0 && k % p.report_interval.max(1) == 0;
                let s = self.iterate(Stage::A, full);
                tpd.push(s.tpd);
                history.push(s);
                if observe(&s).is_break() {
                    return history;
                }
                if k > p.plateau_window {
                    let (now, then) = (tpd[k - 1], tpd[k - 1 - p.plateau_window]);
                    if (now - then).abs() <= p.plateau_tolerance * now.abs() {
                        break;
                    }
                }
                if s.moved == 0 {
                    break;
                }
            }
        }
        // Stage 2b: freeze the layer next to the wall.
        if has_walls {
            let freeze = p.freeze_distance * p.dx;
            let walls = &self.walls;
            self.frozen = self
                .positions
                .par_iter()
                .map(|&x| walls.within(x, freeze))
                .collect();
        }
        // Stage 2c.
        let mut means: Vec<f64> = Vec::new();
        for k in 1..=p.stage_c_iterations {
            self.iteration += 1;
            let s = self.iterate(Stage::C, true);
            means.push(s.gradc_mean_all);
            history.push(s);
            if observe(&s).is_break() {
                return history;
            }
            if p.stage_c_tolerance > 0.0 && k > p.plateau_window {
                let (now, then) = (means[k - 1], means[k - 1 - p.plateau_window]);
                if (now - then).abs() <= p.stage_c_tolerance * now.abs() {
                    break;
                }
            }
        }
        // Final metrics at the packed positions.
        let mut last = self.iterate(Stage::Start, true);
        last.iteration = self.iteration + 1;
        last.stage = Stage::C;
        last.tpd = history.last().map_or(0.0, |s| s.tpd);
        // The last report: nothing is left to stop.
        let _ = observe(&last);
        history.push(last);
        history
    }

    /// Distance of every particle to the nearest wall (infinite beyond the element grid).
    pub fn wall_distances(&self) -> Vec<f64> {
        self.positions
            .par_iter()
            .map(|&x| self.walls.distance(x))
            .collect()
    }

    /// `|grad C|` of every particle at the current positions, and whether its kernel is
    /// truncated by a wall.
    pub fn gradc_magnitudes(&mut self) -> Vec<(f64, bool)> {
        self.evaluate(|_| true)
            .into_iter()
            .map(|e| e.map_or((f64::NAN, false), |e| (e.gradc.length(), e.truncated)))
            .collect()
    }
}

/// The default radius of the boundary push, in units of `dx`: in 2-D the
/// [`relaxed_balance_distance`] (`0.472 dx` at `h = 2 dx`), where eq 5 itself leaves a
/// uniformly dense first layer unforced once the layers behind it have relaxed; the chord ramp
/// `2 sqrt(R^2 - d^2)` is steep, so the push radius is where the first layer settles (flat walls
/// near it with `|grad C|` near zero, sparse or convex walls a little inside). In 3-D
/// [`balanced_push_radius`]: the disc ramp `pi (R^2 - d^2)` is flat, so a push that starts at
/// the layer's target lets it sink well inside (sphere, dx = 0.05 m: 0.44 dx with `R = dx/2`);
/// the balanced radius holds a uniform lattice's first layer at `dx/2`.
///
/// Measured in 2-D: `R = dx/2` (the particle radius) holds every first layer at
/// 0.50 dx against eq 5's midpoint residual, and the trapezoid's mean `|grad C|` falls only
/// 1.67x (its flat walls keep 0.35-0.40 1/m at dx = 0.02 m); [`lattice_balance_distance`]
/// (0.437 dx) lets the airfoil's inside sink to 0.443 dx, outside the 10% band.
pub fn default_push_radius<V: ElementIntegrals>(kernel: &Wendland, dx: f64) -> f64 {
    if V::DIM == 2 {
        relaxed_balance_distance::<V>(kernel, dx)
    } else {
        balanced_push_radius::<V>(kernel, dx)
    }
}

/// A flat wall `x_last = 0` wider than the support on every side (normal out of the fluid
/// side `x_last > 0`) and `grad C . n_in` (paper 4, eq 5) of the first layer of a uniform half
/// lattice (square in 2-D, cubic in 3-D) whose layers lie at `d + k dx`, `k >= 0`, evaluated
/// at a particle of that first layer: the wall's corners, the particle, its `gamma` and
/// `grad C . n_in`.
fn half_lattice_first_layer<V: ElementIntegrals>(
    kernel: &Wendland,
    dx: f64,
    d: f64,
) -> (Vec<V>, V, f64, f64) {
    let m = (kernel.support / dx).ceil() as usize + 1;
    let layers: Vec<f64> = (0..=m).map(|k| d + k as f64 * dx).collect();
    half_lattice_layer(kernel, dx, &layers, 0)
}

/// As [`half_lattice_first_layer`] for a half lattice whose layers (each a uniform square row
/// or sheet of spacing `dx`, aligned with the others) lie at the wall distances `layers`,
/// evaluated at a particle of layer `i`.
fn half_lattice_layer<V: ElementIntegrals>(
    kernel: &Wendland,
    dx: f64,
    layers: &[f64],
    i: usize,
) -> (Vec<V>, V, f64, f64) {
    let last = V::DIM - 1;
    let support = kernel.support;
    let half = 2.0 * support + dx;
    let corner = |signs: [f64; 2]| {
        let mut c = V::ZERO;
        for (k, s) in signs.iter().enumerate().take(last) {
            c.set(k, s * half);
        }
        c
    };
    let corners: Vec<V> = if V::DIM == 2 {
        vec![corner([-1.0, 0.0]), corner([1.0, 0.0])]
    } else {
        vec![
            corner([-1.0, -1.0]),
            corner([-1.0, 1.0]),
            corner([1.0, 1.0]),
            corner([1.0, -1.0]),
        ]
    };
    let mut normal = V::ZERO;
    normal.set(last, -1.0);
    let mut xa = V::ZERO;
    xa.set(last, layers[i]);
    // sum_b V_b grad_a W_ab over the half lattice.
    let m = (support / dx).ceil() as i64 + 1;
    let volume = dx.powi(V::DIM as i32);
    let tangential = if V::DIM == 2 { 0..=0 } else { -m..=m };
    let mut sum = V::ZERO;
    for &yk in layers {
        if (yk - layers[i]).abs() >= support {
            continue;
        }
        for a in -m..=m {
            for b in tangential.clone() {
                let mut xb = V::ZERO;
                xb.set(0, a as f64 * dx);
                if V::DIM == 3 {
                    xb.set(1, b as f64 * dx);
                }
                xb.set(last, yk);
                sum -= kernel.gradient(xb - xa) * volume;
            }
        }
    }
    let (gamma, w) = if layers[i] < support {
        let (g, w) = V::shepard_and_kernel_integral(kernel, xa, &corners, normal);
        (1.0 + g, w)
    } else {
        (1.0, 0.0)
    };
    let gradc = (sum.get(last) - w) / gamma;
    (corners, xa, gamma, gradc)
}

/// The relaxed balance distance, in units of `dx`: where the first layer of a half lattice
/// settles at a flat wall when the layers that step 2a moves (those the wall truncates,
/// `(k + 1/2) dx < 2h`) are in equilibrium under paper 4's eq 12 (`grad C = 0`, eq 5) and the
/// layers behind them stay at their lattice places `(k + 1/2) dx`. It is the discrete
/// counterpart of paper 4's "a particle radius from the wall": the uniformly dense wall layer
/// that eq 5 itself leaves unforced once the layers behind it have relaxed, so a push ramp
/// starting there acts only against compression beyond it. `0.4720 dx` at `h = 2 dx` and
/// `0.4822 dx` at `h = 1.5 dx` in 2-D: outside [`lattice_balance_distance`] (the first layer
/// alone relaxed in front of a rigid lattice, 0.437 / 0.453), inside `dx/2`. Freeing more
/// layers moves it out slowly (a uniform strain of the free layers costs no `grad C`: 0.4729
/// with 6 free layers, 0.4746 with 30, at `h = 2 dx`). The free layers move by the shift of
/// eq 12 (capped at 0.02 dx) until `|grad C| dx < 1e-11` on each (about 100 iterations).
pub fn relaxed_balance_distance<V: ElementIntegrals>(kernel: &Wendland, dx: f64) -> f64 {
    // The layers whose kernel the wall truncates, (k + 1/2) dx < support: those step 2a moves.
    let truncated = (0..)
        .take_while(|&k| (k as f64 + 0.5) * dx < kernel.support)
        .count();
    relaxed_layers::<V>(kernel, dx, truncated)
}

/// The first-layer distance of [`relaxed_balance_distance`] with `free` free layers.
fn relaxed_layers<V: ElementIntegrals>(kernel: &Wendland, dx: f64, free: usize) -> f64 {
    let reach = (kernel.support / dx - 1e-9).ceil() as usize;
    let mut layers: Vec<f64> = (0..free + reach + 2)
        .map(|k| (k as f64 + 0.5) * dx)
        .collect();
    let d_coef = 0.5 * kernel.h * kernel.h;
    let cap = 0.02 * dx;
    for _ in 0..20_000 {
        let g: Vec<f64> = (0..free)
            .map(|i| half_lattice_layer::<V>(kernel, dx, &layers, i).3)
            .collect();
        if g.iter().all(|g| g.abs() * dx < 1e-11) {
            break;
        }
        for (y, g) in layers.iter_mut().zip(&g) {
            *y -= (d_coef * g).clamp(-cap, cap);
        }
    }
    layers[0] / dx
}

/// The balance distance of a uniform lattice at a flat wall, in units of `dx`: the distance
/// `d` at which the first layer of a uniform half lattice (layers at `d + k dx`) has
/// `grad C = 0` (paper 4, eq 5), the fixed point of eq 12 for that layer. The lattice sum is a
/// midpoint rule of `gamma`'s volume integral, so `d` is not `dx/2`: about `0.44 dx` at
/// `h = 2 dx` in 2-D. Bisection on `[0.25, 0.75] dx` (`grad C . n_in` grows with `d` there);
/// `1/2` if it has no root there.
pub fn lattice_balance_distance<V: ElementIntegrals>(kernel: &Wendland, dx: f64) -> f64 {
    let f = |d: f64| half_lattice_first_layer::<V>(kernel, dx, d).3;
    let (mut lo, mut hi) = (0.25 * dx, 0.75 * dx);
    if f(lo) > 0.0 || f(hi) < 0.0 {
        return 0.5;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi) / dx
}

/// The balanced radius of the boundary push, in units of `dx`: the radius `R` for which the
/// push of eq 14 (`p_s = 2 p_a` on the wall within `R`) balances the concentration gradient of
/// the first layer of a uniform lattice (square in 2-D, cubic in 3-D) whose first layer lies
/// at `dx/2` from a flat wall, `int_{S cap B(x, R)} W dS / (2 gamma) = grad C . n` (paper 4,
/// eqs 5, 14), so that the layer paper 4 asks for (a particle radius from the wall) is a
/// fixed point of the shift. The lattice sum is a midpoint rule of `gamma`'s volume
/// integral, so `grad C` of that layer is not zero (it vanishes about `0.06 dx` nearer the
/// wall, [`lattice_balance_distance`]); a push that only starts at `dx/2` (`R = dx/2`) leaves
/// the layer where the ramp meets that residual: just inside `dx/2` in 2-D, where the chord
/// `2 sqrt(R^2 - d^2)` makes the ramp steep, but well inside in 3-D, where the disc
/// `pi (R^2 - d^2)` makes it flat. Depends only on the kernel and `h / dx`; at least `1/2`, at
/// most the support.
pub fn balanced_push_radius<V: ElementIntegrals>(kernel: &Wendland, dx: f64) -> f64 {
    let support = kernel.support;
    let (corners, xa, gamma, gradc) = half_lattice_first_layer::<V>(kernel, dx, 0.5 * dx);
    let push = |r: f64| V::kernel_integral(kernel, xa, &corners, r) / (2.0 * gamma);
    let (mut lo, mut hi) = (0.5 * dx, support);
    if gradc <= 0.0 {
        return 0.5;
    }
    if push(hi) <= gradc {
        return hi / dx;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if push(mid) < gradc {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi) / dx
}

/// How close to a wall a particle must be for its shift to need the crossing test.
fn walls_reach<V: Vector>(shift: V) -> f64 {
    shift.length() * (1.0 + 1e-9) + 1e-300
}

fn metrics<V: Vector>(evals: &[Option<Evaluation<V>>], dx: f64, stats: &mut IterationStats) {
    let (mut sum_i, mut max_i, mut n_i) = (0.0, 0.0f64, 0usize);
    let (mut sum_a, mut max_a, mut n_a) = (0.0, 0.0f64, 0usize);
    let (mut sum_layer, mut n_layer, mut sum_deep, mut n_deep) = (0.0, 0usize, 0.0, 0usize);
    for e in evals.iter().flatten() {
        let g = e.gradc.length();
        sum_a += g;
        max_a = max_a.max(g);
        n_a += 1;
        if e.distance < dx {
            sum_layer += e.distance / dx;
            n_layer += 1;
        } else {
            sum_deep += g;
            n_deep += 1;
        }
        if !e.truncated {
            sum_i += g;
            max_i = max_i.max(g);
            n_i += 1;
        }
    }
    if n_a > 0 {
        stats.gradc_mean_all = sum_a / n_a as f64;
        stats.gradc_max_all = max_a;
    }
    if n_i > 0 {
        stats.gradc_mean = sum_i / n_i as f64;
        stats.gradc_max = max_i;
    }
    if n_layer > 0 {
        stats.first_layer = sum_layer / n_layer as f64;
    }
    if n_deep > 0 {
        stats.gradc_mean_deep = sum_deep / n_deep as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::region::PolygonRegion;
    use glam::DVec2;

    /// A trapezoid packed with reduced iteration counts: every particle stays inside, the
    /// first layer moves to about `dx/2` from the walls, and mean `|grad C|` drops.
    #[test]
    fn packs_a_trapezoid() {
        let dx = 0.05;
        let region = PolygonRegion::new(vec![vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.8, 0.6),
            DVec2::new(0.15, 0.6),
        ]])
        .unwrap();
        let lattice = region.lattice(dx);
        let mut params = PackParams::new(dx, 2.0 * dx);
        params.stage_a_max = 1500;
        params.stage_c_iterations = 200;
        let walls = PackWalls::new(&region.elements(dx), 2.0 * params.h);
        let mut packer = Packer::new(params, lattice, walls).unwrap();
        let history = packer.run(|_| ControlFlow::Continue(()));
        let (first, last) = (history[0], *history.last().unwrap());
        assert!(
            last.gradc_mean_all < 0.5 * first.gradc_mean_all,
            "{} -> {}",
            first.gradc_mean_all,
            last.gradc_mean_all
        );
        assert!(packer.positions.iter().all(|&p| region.contains(p)));
        let layer: Vec<f64> = packer
            .wall_distances()
            .into_iter()
            .filter(|&d| d < 0.8 * dx)
            .collect();
        let mean = layer.iter().sum::<f64>() / layer.len() as f64;
        assert!(
            (mean / dx - 0.5).abs() < 0.05,
            "first layer at {} dx",
            mean / dx
        );
    }

    /// The balanced push radius makes the first layer of a uniform half lattice at `dx/2` a
    /// fixed point; the values match an independent flat-wall quadrature (about 0.505 dx in
    /// 2-D, 0.600 dx and 0.620 dx in 3-D at h = 1.5 dx and 2 dx).
    #[test]
    fn balanced_push_radius_values() {
        let dx = 0.05;
        for (hr, r2, r3) in [(1.5, 0.505, 0.6005), (2.0, 0.505, 0.6205)] {
            let b2 = balanced_push_radius::<DVec2>(&Wendland::new(hr * dx, 2), dx);
            let b3 = balanced_push_radius::<glam::DVec3>(&Wendland::new(hr * dx, 3), dx);
            assert!((b2 - r2).abs() < 2e-3, "2-D h = {hr} dx: {b2}");
            assert!((b3 - r3).abs() < 2e-3, "3-D h = {hr} dx: {b3}");
        }
    }

    /// The first layer of a uniform half lattice has `grad C = 0` inside `dx/2` (the lattice
    /// sum is a midpoint rule), at the same distance for every `dx` (it depends on `h / dx`).
    #[test]
    fn lattice_balance_distance_values() {
        for hr in [1.5, 2.0] {
            let mut got = Vec::new();
            for dx in [0.02, 0.05] {
                let k2 = Wendland::new(hr * dx, 2);
                let d2 = lattice_balance_distance::<DVec2>(&k2, dx);
                let d3 = lattice_balance_distance::<glam::DVec3>(&Wendland::new(hr * dx, 3), dx);
                let g = half_lattice_first_layer::<DVec2>(&k2, dx, d2 * dx).3;
                println!("h = {hr} dx, dx = {dx}: 2-D {d2:.4} dx, 3-D {d3:.4} dx");
                assert!(g.abs() < 1e-9 / dx, "{g}");
                assert!((0.4..0.5).contains(&d2) && (0.4..0.5).contains(&d3));
                got.push((d2, d3));
            }
            assert!((got[0].0 - got[1].0).abs() < 1e-9 && (got[0].1 - got[1].1).abs() < 1e-9);
        }
    }

    /// The relaxed balance distance lies between the lattice balance distance and `dx/2` and
    /// does not depend on `dx`; an independent Python model of the same layered problem
    /// (Shepard factor by a 1-D rule) gives 0.4720 dx at h = 2 dx and 0.4822 dx at h = 1.5 dx.
    #[test]
    fn relaxed_balance_distance_values() {
        for (hr, want) in [(2.0, 0.4720), (1.5, 0.4822)] {
            let mut got = Vec::new();
            for dx in [0.02, 0.05] {
                let k2 = Wendland::new(hr * dx, 2);
                let d = relaxed_balance_distance::<DVec2>(&k2, dx);
                println!("h = {hr} dx, dx = {dx}: relaxed {d:.5} dx");
                assert!((d - want).abs() < 2e-4, "{d}");
                assert!(d > lattice_balance_distance::<DVec2>(&k2, dx) && d < 0.5);
                got.push(d);
            }
            assert!((got[0] - got[1]).abs() < 1e-6);
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let walls = PackWalls::<DVec2>::new(&[], 0.2);
        let mut p = PackParams::new(0.05, 0.1);
        p.max_shift = -1.0;
        let e = Packer::new(p, vec![DVec2::ZERO], walls.clone()).unwrap_err();
        assert!(e.to_string().contains("max_shift"));
        let e = Packer::new(PackParams::new(0.05, 0.1), Vec::new(), walls).unwrap_err();
        assert!(matches!(e, PackError::NoParticles { .. }));
    }
}
