//! Semi-implicit midpoint integrator (paper 1, section 5; its ref. 27), the scheme under which
//! the energy-conserving walls conserve energy.
//!
//! Per step, with the neighbour grid and the positions frozen at `r^n` and the rates of the
//! previous step as the first guess `(a, rhodot)`, iterate:
//! 1. midpoint state `u^{n+1/2} = u^n + dt/2 a`, `rho^{n+1/2} = rho^n + dt/2 rhodot`, wall
//!    velocities at `t^{n+1/2}`;
//! 2. new rates `(a', rhodot')` at that state;
//! 3. residue (paper 1, eq 53, on the change of the rates between iterations):
//!    `R = sum_i m_i (|u_i . (a'_i - a_i)| + |p_i / rho_i^2 (rhodot'_i - rhodot_i)|)`;
//! 4. relaxation `a <- f a + (1 - f) a'`: `f = f0` on the first pass, grows as
//!    `f <- inc + (1 - inc) f` whenever `R` fails to fall by the factor `min_decrease`, and is
//!    zero on the last pass; stop when `R < tolerance` or after `max_iterations`.
//!
//! Then `u^{n+1} = u^n + dt a`, `r^{n+1} = r^n + dt (u^n + u^{n+1}) / 2`,
//! `rho^{n+1} = rho^n + dt rhodot`; pistons iterate with the fluid (their midpoint velocity
//! drives their elements, their acceleration joins the residue and the relaxation); the wall work grows by `dt sum_j F_j . U_j` at the
//! midpoint: at convergence the fluid's energy change and the wall work balance exactly, up to
//! the midpoint rule of the compression energy.

use super::Simulation;
use crate::dim::Vector;
use crate::energy::deterministic_sum;
use crate::error::SimError;
use crate::walls::bounce::elastic_bounce;
use rayon::prelude::*;

/// Settings of the midpoint iterations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MidpointParams {
    /// Most fixed-point iterations per step.
    pub max_iterations: u32,
    /// Absolute residue (a power) below which the iterations stop.
    pub tolerance: f64,
    /// Geometric rate the residue must fall at; slower growth of `f` is triggered above it.
    pub min_decrease: f64,
    /// Relaxation increment `inc`.
    pub relax_increment: f64,
    /// Relaxation at the start of a step `f0` (0: none).
    pub initial_relaxation: f64,
}

impl Default for MidpointParams {
    fn default() -> Self {
        MidpointParams {
            max_iterations: 10,
            tolerance: 0.0,
            min_decrease: 0.2,
            relax_increment: 0.25,
            initial_relaxation: 0.0,
        }
    }
}

impl<V: Vector> Simulation<V> {
    /// One semi-implicit midpoint step of size `dt`.
    pub(super) fn midpoint_step(
        &mut self,
        dt: f64,
        params: &MidpointParams,
    ) -> Result<(), SimError> {
        let half = 0.5 * dt;
        let t_mid = self.time + half;
        self.walls.set_velocities_at(t_mid);
        let piston_start: Vec<f64> = self.walls.pistons_mut().map(|p| p.velocity).collect();
        let mut piston_previous: Vec<f64> = Vec::new();
        let mut relaxation = params.initial_relaxation;
        let mut previous_residue = f64::INFINITY;
        let mut iterations = 0;
        let mut residue = 0.0;
        for m in 0..params.max_iterations.max(1) {
            iterations = m + 1;
            {
                let (f, s) = (&self.fluid, &mut self.scratch);
                s.previous_acceleration.clone_from(&f.acceleration);
                s.previous_density_rate.clone_from(&f.density_rate);
            }
            self.stage_state(half);
            piston_previous.clear();
            for (p, &v0) in self.walls.pistons_mut().zip(&piston_start) {
                p.velocity = v0 + half * p.acceleration;
                piston_previous.push(p.acceleration);
            }
            self.walls.set_velocities_at(t_mid);
            self.evaluate_rates();
            self.store_piston_accelerations();
            residue = self.residue();
            for (p, &old) in self.walls.pistons_mut().zip(&piston_previous) {
                residue += (p.mass * p.velocity * (p.acceleration - old)).abs();
            }
            let converged = residue < params.tolerance;
            if m > 0 && residue > params.min_decrease * previous_residue {
                relaxation = params.relax_increment + (1.0 - params.relax_increment) * relaxation;
            }
            if m == 0 {
                relaxation = params.initial_relaxation;
            }
            if converged {
                relaxation = 0.0;
            }
            previous_residue = residue;
            if relaxation > 0.0 {
                let s = &self.scratch;
                let f = &mut self.fluid;
                let keep = relaxation;
                f.acceleration
                    .par_iter_mut()
                    .zip(s.previous_acceleration.par_iter())
                    .for_each(|(a, &old)| *a = old * keep + *a * (1.0 - keep));
                f.density_rate
                    .par_iter_mut()
                    .zip(s.previous_density_rate.par_iter())
                    .for_each(|(d, &old)| *d = keep * old + (1.0 - keep) * *d);
                for (p, &old) in self.walls.pistons_mut().zip(&piston_previous) {
                    p.acceleration = keep * old + (1.0 - keep) * p.acceleration;
                }
            }
            if converged {
                break;
            }
        }
        self.last_iterations = iterations;
        self.last_residue = residue;
        self.wall_work += dt * self.wall_power;
        self.viscous_dissipation += dt * self.viscous_power;
        for (p, &v0) in self.walls.pistons_mut().zip(&piston_start) {
            p.position += dt * (v0 + half * p.acceleration);
            p.velocity = v0 + dt * p.acceleration;
        }

        // Corrector: u^{n+1} = u^n + dt a, drift (u^n + u^{n+1}) / 2.
        let f = &mut self.fluid;
        let drift = &mut self.scratch.drift_velocity;
        drift.clear();
        drift.extend(
            f.velocity
                .iter()
                .zip(&f.acceleration)
                .map(|(&u, &a)| u + a * half),
        );
        f.velocity
            .par_iter_mut()
            .zip(f.acceleration.par_iter())
            .for_each(|(u, &a)| *u += a * dt);
        if self.config.elastic_bounce {
            self.wall_work += elastic_bounce(
                &self.walls.elements,
                &self.walls.grid,
                &f.position,
                &f.mass,
                drift,
                Some(&mut f.velocity),
                dt,
                &mut self.scratch.lost_energy,
            );
        }
        f.position
            .par_iter_mut()
            .zip(drift.par_iter())
            .for_each(|(r, &u)| *r += u * dt);
        f.density
            .par_iter_mut()
            .zip(f.density_rate.par_iter())
            .for_each(|(rho, &d)| *rho += d * dt);
        self.wrap_positions();
        self.time += dt;
        self.step += 1;
        self.last_dt = dt;
        self.check_state()?;
        self.walls.move_to(self.time);
        let interval = self.config.reorder_interval;
        self.rebuild_grid(interval > 0 && self.step.is_multiple_of(interval));
        self.refresh_pressure();
        Ok(())
    }

    /// Paper 1, eq 53, on the change of the rates between two iterations, at the midpoint
    /// state held in the scratch buffers.
    fn residue(&self) -> f64 {
        let f = &self.fluid;
        let s = &self.scratch;
        deterministic_sum(f.len(), |i| {
            let rho = s.density[i];
            f.mass[i]
                * ((s.velocity[i].dot(f.acceleration[i] - s.previous_acceleration[i])).abs()
                    + (f.pressure[i] / (rho * rho)
                        * (f.density_rate[i] - s.previous_density_rate[i]))
                        .abs())
        })
    }
}
