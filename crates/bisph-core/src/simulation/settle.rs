//! Settling: a start in discrete equilibrium of the case's own operators.
//!
//! A lattice (or packed) start with a hydrostatic pressure is at rest for the continuous
//! equations but not for the discrete ones: near walls and the free surface the operators are
//! only zeroth-order consistent, so particles there start with accelerations of the order of
//! `g` or more. Released into a scheme without dissipation that imbalance becomes sloshing
//! which never decays. Settling runs the same operators, gravity and integrator before
//! `t = 0` with the walls held still and the velocities damped,
//! `u <- u exp(-beta dt)` after every step, until the fluid is at rest to a stated tolerance;
//! the state reached is then a discrete equilibrium and the run starts from it with zero
//! velocities.
//!
//! Fluid that is not in a resting configuration (a dam-break column, a block in free fall)
//! does not come to rest: it flows. Settling detects that by the kinetic energy the fluid
//! gains and then restores the original start untouched.

use super::settings::{SettleOutcome, SettleParams, SettleReport};
use super::Simulation;
use crate::dim::Vector;
use crate::error::SimError;
use crate::particles::Fluid;
use crate::walls::geometric_shepard;
use rayon::prelude::*;
use std::ops::ControlFlow;
use std::time::Instant;

impl<V: Vector> Simulation<V> {
    /// Settles the fluid (see the module documentation) with the walls held at their
    /// `t = 0` place, then restarts the clock and the energy books at the state reached.
    /// `original` is the fluid as it started settling and `so_far` the report at the current
    /// state: [`SettleReport::starting`] for a fresh start, or the report saved with a state
    /// restored from a checkpoint taken in `on_step` (continuing gives the bits of settling
    /// without the break). `on_step` sees the simulation and the report after every settling
    /// step; returning `Break` stops settling there ([`SettleOutcome::Interrupted`]).
    pub fn settle_from(
        &mut self,
        params: &SettleParams,
        original: &Fluid<V>,
        so_far: SettleReport,
        on_step: &mut dyn FnMut(&Self, &SettleReport) -> ControlFlow<()>,
    ) -> Result<SettleReport, SimError> {
        let clock = Instant::now();
        let start = positions_by_id(original);
        let mut report = SettleReport {
            outcome: SettleOutcome::TimedOut,
            ..so_far
        };
        let u_tol = params.speed_tolerance * params.speed_scale;
        let a_tol = params.acceleration_tolerance * params.speed_scale * params.damping;
        while report.time < params.max_time {
            self.advance(None)?;
            report.steps += 1;
            report.time += self.last_dt;
            let damp = (-params.damping * self.last_dt).exp();
            self.fluid
                .velocity
                .par_iter_mut()
                .for_each(|u| *u = *u * damp);
            report.max_speed = self.max_speed();
            report.max_acceleration = self.max_acceleration();
            report.max_displacement = max_displacement(&self.fluid, &start);
            report.wall_seconds = so_far.wall_seconds + clock.elapsed().as_secs_f64();
            if on_step(self, &report).is_break() {
                report.outcome = SettleOutcome::Interrupted;
                break;
            }
            if self.energy().kinetic > params.max_kinetic {
                report.outcome = SettleOutcome::NotAtRest;
                break;
            }
            if report.max_speed < u_tol && report.max_acceleration < a_tol {
                report.outcome = SettleOutcome::Settled;
                break;
            }
        }
        if report.outcome == SettleOutcome::NotAtRest {
            self.fluid = original.clone();
        }
        self.restart_at_rest();
        report.wall_seconds = so_far.wall_seconds + clock.elapsed().as_secs_f64();
        Ok(report)
    }

    /// `true` when the fluid's only free surface is a level top, as in a tank at rest: every
    /// particle deeper than one kernel support below the highest one whose support no wall
    /// reaches (geometric Shepard factor 1, paper 2, eq 8) has it filled with fluid,
    /// `sum_j W_ij V_j >= FILLED`. A dam-break column or a block in free fall has free faces
    /// below its top, where that sum falls to about one half. Particles a wall's support
    /// reaches are not judged: a lattice that does not fit the walls leaves gaps there, which
    /// settling closes.
    pub fn rests_against_walls(&self) -> bool {
        /// Fluid sum below which a particle's support reaches a free surface.
        const FILLED: f64 = 0.8;
        /// Geometric gamma above which no wall reaches a particle's support.
        const AWAY_FROM_WALLS: f64 = 1.0 - 1e-6;
        let g = self.config.gravity;
        if g.length() == 0.0 {
            return false;
        }
        let up = -g / g.length();
        let f = &self.fluid;
        // A copy of the fluid grid (its periodic axes included), so the simulation's own
        // neighbour data stays as it is.
        let mut grid = self.fluid_grid.clone();
        grid.rebuild_keyed(&f.position, &f.id);
        let kernel = &self.config.kernel;
        let top = f
            .position
            .iter()
            .map(|r| r.dot(up))
            .fold(f64::NEG_INFINITY, f64::max);
        let volume: Vec<f64> = f
            .mass
            .iter()
            .zip(&f.density)
            .map(|(m, rho)| m / rho)
            .collect();
        let walls = &self.walls;
        f.position.par_iter().all(|&x| {
            if x.dot(up) > top - kernel.support
                || geometric_shepard::gamma(kernel, x, &walls.elements, &walls.grid)
                    < AWAY_FROM_WALLS
            {
                return true;
            }
            let mut sum = 0.0;
            grid.for_each_neighbour(x, &f.position, kernel.support, |j, _, r| {
                sum += kernel.value(r) * volume[j];
            });
            sum >= FILLED
        })
    }

    /// Zero velocities, the clock at 0 and the energy books closed, rates at the state.
    fn restart_at_rest(&mut self) {
        self.fluid.velocity.iter_mut().for_each(|u| *u = V::ZERO);
        self.time = 0.0;
        self.step = 0;
        self.last_dt = 0.0;
        self.wall_work = 0.0;
        self.viscous_dissipation = 0.0;
        self.diffusion_dissipation = 0.0;
        self.forcing_work = 0.0;
        self.timings = Default::default();
        self.forget_pairs();
        self.scratch.candidates_valid = false;
        self.walls.move_to(0.0);
        self.rebuild_grid(true);
        if self.config.wall_model.needs_gamma() {
            self.geometric_gamma();
        }
        self.refresh_rates();
    }
}

/// Positions indexed by particle id (ids of removed particles hold zero).
fn positions_by_id<V: Vector>(fluid: &Fluid<V>) -> Vec<V> {
    let slots = fluid.id.iter().max().map_or(0, |&m| m as usize + 1);
    let mut by_id = vec![V::ZERO; slots];
    for (i, &id) in fluid.id.iter().enumerate() {
        by_id[id as usize] = fluid.position[i];
    }
    by_id
}

/// Largest distance of a particle from its position in `start` (indexed by id).
fn max_displacement<V: Vector>(fluid: &Fluid<V>, start: &[V]) -> f64 {
    fluid
        .position
        .par_iter()
        .zip(fluid.id.par_iter())
        .map(|(&r, &id)| (r - start[id as usize]).length_squared())
        .reduce(|| 0.0, f64::max)
        .sqrt()
}
