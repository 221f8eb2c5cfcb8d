//! Explicit velocity Verlet (kick-drift-kick, extended to the density), second order, one
//! rate evaluation per step:
//! 1. `u* = u^n + dt/2 a^n`, `rho* = rho^n + dt/2 rhodot^n`, `r^{n+1} = r^n + dt u*`;
//! 2. walls to `t^{n+1}`; the gamma the particles carry to `r^{n+1}`, and with it the walls'
//!    part of the continuity equation of the classic walls, `rho* *= gamma^n / gamma^{n+1}`
//!    (it is then left out of `rhodot`, see [`crate::walls::shepard::Shepard::advance`]);
//!    rates `a^{n+1}, rhodot^{n+1}` at `r^{n+1}` and the predicted `u* + dt/2 a^n`,
//!    `rho* + dt/2 rhodot^n`;
//! 3. `u^{n+1} = u* + dt/2 a^{n+1}`, `rho^{n+1} = rho* + dt/2 rhodot^{n+1}`.
//!
//! The wall work is integrated with the trapezoidal rule of the same step.

use super::Simulation;
use crate::dim::Vector;
use crate::error::SimError;
use crate::walls::bounce::elastic_bounce;
use rayon::prelude::*;

impl<V: Vector> Simulation<V> {
    /// After a step's drift of `dt`: positions wrapped across periodic axes, the clock
    /// advanced, the state checked, then the walls moved to the new time and the neighbour
    /// structures brought to the new positions.
    pub(super) fn close_step(&mut self, dt: f64) -> Result<(), SimError> {
        self.wrap_positions();
        self.time += dt;
        self.step += 1;
        self.last_dt = dt;
        self.check_state()?;
        self.move_walls();
        self.step_neighbours();
        Ok(())
    }

    /// One explicit Verlet step of size `dt`.
    pub(super) fn verlet_step(&mut self, dt: f64) -> Result<(), SimError> {
        let half = 0.5 * dt;
        let summation = self.summation();
        // 1. kick, bounce off walls, drift.
        {
            let f = &mut self.fluid;
            f.velocity
                .par_iter_mut()
                .zip(f.acceleration.par_iter())
                .for_each(|(u, &a)| *u += a * half);
            if self.config.elastic_bounce {
                elastic_bounce(
                    &self.walls.elements,
                    &self.walls.grid,
                    &self.wall_clearance,
                    &f.position,
                    &f.mass,
                    &mut f.velocity,
                    None,
                    dt,
                    &mut self.scratch.lost_energy,
                );
            }
        }
        if self.config.elastic_bounce {
            let lost = &self.scratch.lost_energy;
            self.wall_work += self.sum_owned(|i| lost[i]);
        }
        {
            let f = &mut self.fluid;
            f.position
                .par_iter_mut()
                .zip(f.velocity.par_iter())
                .for_each(|(r, &u)| *r += u * dt);
            if !summation {
                f.density
                    .par_iter_mut()
                    .zip(f.density_rate.par_iter())
                    .for_each(|(rho, &drho)| *rho += drho * half);
            }
        }
        // Dynamic bodies: kick and drift like the fluid.
        let mut body_velocity = self.walls.dynamic_velocities();
        for (v, a) in body_velocity
            .iter_mut()
            .zip(self.walls.dynamic_accelerations())
        {
            *v += half * a;
        }
        self.walls.set_dynamic_velocities(&body_velocity);
        self.walls.drift_bodies(dt);
        let power_before = self.wall_power;
        let viscous_before = self.viscous_power;
        let diffusion_before = self.diffusion_power;
        // 2. walls, neighbours, rates at the predicted state.
        self.close_step(dt)?;
        self.advance_gamma(dt);
        if summation {
            self.summation_densities(dt);
        }
        self.stage_state(half);
        let predicted: Vec<f64> = body_velocity
            .iter()
            .zip(self.walls.dynamic_accelerations())
            .map(|(v, a)| v + half * a)
            .collect();
        self.walls.set_dynamic_velocities(&predicted);
        self.walls.set_velocities_at(self.time);
        self.evaluate_rates();
        self.store_body_accelerations(true);
        for (v, a) in body_velocity
            .iter_mut()
            .zip(self.walls.dynamic_accelerations())
        {
            *v += half * a;
        }
        self.walls.set_dynamic_velocities(&body_velocity);
        self.walls.set_velocities_at(self.time);
        // 3. kick.
        {
            let f = &mut self.fluid;
            f.velocity
                .par_iter_mut()
                .zip(f.acceleration.par_iter())
                .for_each(|(u, &a)| *u += a * half);
            if !summation {
                f.density
                    .par_iter_mut()
                    .zip(f.density_rate.par_iter())
                    .for_each(|(rho, &drho)| *rho += drho * half);
            }
        }
        self.wall_work += half * (power_before + self.wall_power);
        self.viscous_dissipation += half * (viscous_before + self.viscous_power);
        self.diffusion_dissipation += half * (diffusion_before + self.diffusion_power);
        self.refresh_pressure();
        self.last_iterations = 1;
        self.last_residue = 0.0;
        Ok(())
    }
}
