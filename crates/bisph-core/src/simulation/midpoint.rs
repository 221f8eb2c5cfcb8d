//! Semi-implicit midpoint integrator (paper 1, section 5; its ref. 27), the scheme under which
//! the energy-conserving walls conserve energy.
//!
//! Per step, with the neighbour grid and the positions frozen at `r^n`, and as the first guess
//! `(a, rhodot)` the converged rates of the last three steps (at `t^{n-1/2}`, `t^{n-3/2}`,
//! `t^{n-5/2}`) extrapolated to `t^{n+1/2}` by the parabola through them (the line through
//! the last two on the third step, the last step's rates alone on the first two), iterate:
//! 1. midpoint state `u^{n+1/2} = u^n + dt/2 a`, `rho^{n+1/2} = rho^n + dt/2 rhodot`, wall
//!    velocities at `t^{n+1/2}`;
//! 2. new rates `(a', rhodot')` at that state;
//! 3. residue (paper 1, eq 53, on the change of the rates between iterations):
//!    `R = sum_i m_i (|u_i . (a'_i - a_i)| + |p_i / rho_i^2 (rhodot'_i - rhodot_i)|)`;
//! 4. relaxation `a <- f a + (1 - f) a'`: `f = f0` on the first pass, grows as
//!    `f <- inc + (1 - inc) f` whenever `R` fails to fall by the factor
//!    `f + (1 - f) min_decrease` (the rate `min_decrease` of the paper, less the slowing the
//!    relaxation itself causes), and is zero on the last pass; stop when `R < tolerance` or
//!    after `max_iterations`. With `anderson_depth > 0`, Anderson's mixing of the last
//!    iterations ([`super::anderson`]) takes the place of the relaxation.
//!
//! Then `u^{n+1} = u^n + dt a`, `r^{n+1} = r^n + dt (u^n + u^{n+1}) / 2`,
//! `rho^{n+1} = rho^n + dt rhodot`. Dynamic bodies (pistons and free rigid bodies) iterate
//! with the fluid on their generalised velocities `V` and accelerations `A`
//! ([`crate::bodies::Motion::velocities`]): `V^{n+1/2} = V^n + dt/2 A` drives their elements,
//! `A` is re-evaluated from the wall loads each pass and joins the residue
//! (`sum_k I_k |V_k (A'_k - A_k)|`) and the relaxation; then `V^{n+1} = V^n + dt A` and the
//! bodies drift with `V^{n+1/2}`. Staggered free bodies keep the accelerations of the previous
//! step through the iterations and take the new load after it (loose coupling). The wall
//! work grows by `dt sum_j F_j . U_j` at the midpoint: at convergence the fluid's energy
//! change, the wall work and the bodies' kinetic + gravity energy balance exactly, up to the
//! midpoint rule of the compression energy.

use super::anderson::{Anderson, InnerProduct, RatesView};
use super::settings::MidpointParams;
use super::Simulation;
use crate::dim::Vector;
use crate::error::SimError;
use crate::walls::bounce::elastic_bounce;
use crate::walls::shepard::ShepardKind;
use rayon::prelude::*;

impl<V: Vector> Simulation<V> {
    /// One semi-implicit midpoint step of size `dt`: the rates at the midpoint by fixed-point
    /// iteration with the positions frozen, then the bodies and the fluid advanced with them.
    pub(super) fn midpoint_step(
        &mut self,
        dt: f64,
        params: &MidpointParams,
    ) -> Result<(), SimError> {
        self.walls.set_velocities_at(self.time + 0.5 * dt);
        let body_start = self.walls.dynamic_velocities();
        self.extrapolate_rates(dt);
        // Positions and grid stay frozen through the iterations: list the pairs once.
        if params.max_iterations > 1 {
            self.list_pairs();
        }
        let (iterations, residue) = self.iterate_midpoint_rates(dt, &body_start, params);
        self.forget_pairs();
        self.last_iterations = iterations;
        self.last_residue = residue;
        self.wall_work += dt * self.wall_power;
        self.viscous_dissipation += dt * self.viscous_power;
        self.diffusion_dissipation += dt * self.diffusion_power;
        self.advance_midpoint_bodies(dt, &body_start);
        self.advance_midpoint_fluid(dt);
        self.close_step(dt)?;
        self.place_geometric_gamma();
        self.refresh_pressure();
        Ok(())
    }

    /// Steps 1-4 of the module's iteration from the first guess in the rates: the state and
    /// the bodies' velocities `body_start + dt/2 A` at the midpoint, the rates there, the
    /// residue and the relaxation (or Anderson's mixing), until the residue falls below the
    /// tolerance or `max_iterations` have run. Leaves the last rates in the fluid and the
    /// bodies; returns the iterations run and the last residue.
    fn iterate_midpoint_rates(
        &mut self,
        dt: f64,
        body_start: &[f64],
        params: &MidpointParams,
    ) -> (u32, f64) {
        let half = 0.5 * dt;
        let t_mid = self.time + half;
        let body_inertia = self.walls.dynamic_inertias();
        let mut body_velocity = body_start.to_vec();
        let mut relaxation = params.initial_relaxation;
        let mut previous_residue = f64::INFINITY;
        let mut iterations = 0;
        let mut residue = 0.0;
        let depth = params.anderson_depth as usize;
        let mut anderson = std::mem::take(&mut self.scratch.anderson);
        if anderson.depth() != depth {
            anderson = Anderson::new(depth);
        }
        anderson.restart();
        for m in 0..params.max_iterations.max(1) {
            iterations = m + 1;
            {
                let (f, s) = (&self.fluid, &mut self.scratch);
                s.previous_acceleration.clone_from(&f.acceleration);
                s.previous_density_rate.clone_from(&f.density_rate);
            }
            self.stage_state(half);
            let body_previous = self.walls.dynamic_accelerations();
            for (k, v) in body_velocity.iter_mut().enumerate() {
                *v = body_start[k] + half * body_previous[k];
            }
            self.walls.set_dynamic_velocities(&body_velocity);
            self.walls.set_velocities_at(t_mid);
            self.evaluate_rates();
            let mut body_acceleration = self.body_accelerations(false);
            residue = self.residue();
            for k in 0..body_acceleration.len() {
                residue += (body_inertia[k]
                    * body_velocity[k]
                    * (body_acceleration[k] - body_previous[k]))
                    .abs();
            }
            let converged = residue < params.tolerance;
            // The relaxation already applied slows the fall by itself: the rate expected of
            // a relaxed pass is `f + (1 - f) min_decrease`.
            let expected = relaxation + (1.0 - relaxation) * params.min_decrease;
            if m > 0 && residue > expected * previous_residue {
                relaxation = params.relax_increment + (1.0 - params.relax_increment) * relaxation;
            }
            if m == 0 {
                relaxation = params.initial_relaxation;
            }
            if converged {
                relaxation = 0.0;
            }
            previous_residue = residue;
            let last = m + 1 == params.max_iterations.max(1);
            if depth > 0 {
                if !converged && !last {
                    self.accelerate(
                        &mut anderson,
                        &mut body_acceleration,
                        &body_previous,
                        &body_inertia,
                    );
                }
            } else if relaxation > 0.0 {
                self.relax_rates(relaxation, &mut body_acceleration, &body_previous);
            }
            self.walls.set_dynamic_accelerations(&body_acceleration);
            if converged {
                break;
            }
        }
        self.scratch.anderson = anderson;
        (iterations, residue)
    }

    /// The bodies after the iterations: they drift with `V^{n+1/2} = V^n + dt/2 A`
    /// (`body_start` holding `V^n`), then `V^{n+1} = V^n + dt A`; staggered bodies take the
    /// load of this step for the next one.
    fn advance_midpoint_bodies(&mut self, dt: f64, body_start: &[f64]) {
        let half = 0.5 * dt;
        let body_acceleration = self.walls.dynamic_accelerations();
        let mut body_velocity: Vec<f64> = (body_start.iter().zip(&body_acceleration))
            .map(|(&v, &a)| v + half * a)
            .collect();
        self.walls.set_dynamic_velocities(&body_velocity);
        if self.walls.has_dynamic_bodies() {
            let loads = self.body_loads();
            self.walls.update_staggered(&loads);
        }
        self.walls.drift_bodies(dt);
        for (k, v) in body_velocity.iter_mut().enumerate() {
            *v = body_start[k] + dt * body_acceleration[k];
        }
        self.walls.set_dynamic_velocities(&body_velocity);
    }

    /// The fluid's corrector: `u^{n+1} = u^n + dt a`, the drift with `(u^n + u^{n+1}) / 2`
    /// (through the elastic bounce where it is on), the carried gamma along the drift, and
    /// `rho^{n+1} = rho^n + dt rhodot`.
    fn advance_midpoint_fluid(&mut self, dt: f64) {
        let half = 0.5 * dt;
        let integrated_gamma = self.carried_gamma() == Some(ShepardKind::Integrated);
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
            elastic_bounce(
                &self.walls.elements,
                &self.walls.grid,
                &self.wall_clearance,
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
        if integrated_gamma {
            super::advance_gamma(
                &self.config,
                &self.walls,
                &mut f.gamma,
                &mut f.grad_gamma,
                &f.position,
                drift,
                dt,
                None,
            );
        }
        f.density
            .par_iter_mut()
            .zip(f.density_rate.par_iter())
            .for_each(|(rho, &d)| *rho += d * dt);
        if self.config.elastic_bounce {
            let lost = &self.scratch.lost_energy;
            self.wall_work += self.sum_owned(|i| lost[i]);
        }
    }

    /// Under-relaxes the rates of an iteration towards those of the previous one:
    /// `a <- keep a_prev + (1 - keep) a` for the fluid's accelerations and density rates and
    /// the bodies' generalised accelerations.
    fn relax_rates(&mut self, keep: f64, body_acceleration: &mut [f64], body_previous: &[f64]) {
        let s = &self.scratch;
        let f = &mut self.fluid;
        f.acceleration
            .par_iter_mut()
            .zip(s.previous_acceleration.par_iter())
            .for_each(|(a, &old)| *a = old * keep + *a * (1.0 - keep));
        f.density_rate
            .par_iter_mut()
            .zip(s.previous_density_rate.par_iter())
            .for_each(|(d, &old)| *d = keep * old + (1.0 - keep) * *d);
        for (a, &old) in body_acceleration.iter_mut().zip(body_previous) {
            *a = keep * old + (1.0 - keep) * *a;
        }
    }

    /// The next guess of the rates by Anderson's mixing of the iterations so far
    /// ([`super::anderson`]): the fluid's rates (the evaluation) and `body_acceleration` are
    /// overwritten, the guess they were evaluated at being in the scratch buffers and
    /// `body_previous`.
    fn accelerate(
        &mut self,
        anderson: &mut Anderson<V>,
        body_acceleration: &mut [f64],
        body_previous: &[f64],
        body_inertia: &[f64],
    ) {
        let mut acceleration = std::mem::take(&mut self.fluid.acceleration);
        let mut density_rate = std::mem::take(&mut self.fluid.density_rate);
        let eos = self.config.eos;
        let scale = eos.c0() / eos.rho0();
        let product = MidpointNorm {
            sim: self,
            density_weight: scale * scale,
            body_inertia,
        };
        let s = &self.scratch;
        let x = RatesView {
            acceleration: &s.previous_acceleration,
            density_rate: &s.previous_density_rate,
            body: body_previous,
        };
        anderson.next_guess(
            x,
            (&mut acceleration, &mut density_rate, body_acceleration),
            &product,
        );
        self.fluid.acceleration = acceleration;
        self.fluid.density_rate = density_rate;
    }

    /// First guess of the rates at `t^{n+1/2}`: the converged rates of the last three steps
    /// (at `t^{n-1/2}`, `t^{n-3/2}`, `t^{n-5/2}`) extrapolated by the parabola through them
    /// ([`FirstGuess`]), by the line through the last two while fewer are held; keeps the
    /// rates of the last two steps as the earlier and earliest ones for the next step.
    fn extrapolate_rates(&mut self, dt: f64) {
        let f = &mut self.fluid;
        let n = f.len();
        let earlier = self.earlier_dt > 0.0 && f.earlier_acceleration.len() == n;
        if earlier {
            let earliest = self.earliest_dt > 0.0 && f.earliest_acceleration.len() == n;
            let guess = FirstGuess::new(
                dt,
                self.last_dt,
                self.earlier_dt,
                earliest.then_some(self.earliest_dt),
            );
            f.earliest_acceleration.resize(n, V::ZERO);
            f.earliest_density_rate.resize(n, 0.0);
            f.acceleration
                .par_iter_mut()
                .zip(f.earlier_acceleration.par_iter_mut())
                .zip(f.earliest_acceleration.par_iter_mut())
                .for_each(|((a, e), ee)| {
                    let last = *a;
                    *a = guess.of(last, *e, *ee);
                    *ee = *e;
                    *e = last;
                });
            f.density_rate
                .par_iter_mut()
                .zip(f.earlier_density_rate.par_iter_mut())
                .zip(f.earliest_density_rate.par_iter_mut())
                .for_each(|((d, e), ee)| {
                    let last = *d;
                    *d = guess.of(last, *e, *ee);
                    *ee = *e;
                    *e = last;
                });
        } else {
            f.earlier_acceleration.clone_from(&f.acceleration);
            f.earlier_density_rate.clone_from(&f.density_rate);
        }
        self.earliest_dt = if earlier { self.earlier_dt } else { 0.0 };
        self.earlier_dt = self.last_dt;
    }

    /// Paper 1, eq 53, on the change of the rates between two iterations, at the midpoint
    /// state held in the scratch buffers.
    fn residue(&self) -> f64 {
        let f = &self.fluid;
        let s = &self.scratch;
        self.sum_owned(|i| {
            let rho = s.density[i];
            f.mass[i]
                * ((s.velocity[i].dot(f.acceleration[i] - s.previous_acceleration[i])).abs()
                    + (f.pressure[i] / (rho * rho)
                        * (f.density_rate[i] - s.previous_density_rate[i]))
                        .abs())
        })
    }
}

/// The weighted inner product of [`super::anderson`]: particle masses, density rates in the
/// units of accelerations (`c0 / rho0`), bodies by their generalised inertias; the fluid's
/// part summed exactly over the own particles of every part.
struct MidpointNorm<'a, V: Vector> {
    sim: &'a Simulation<V>,
    density_weight: f64,
    body_inertia: &'a [f64],
}

impl<V: Vector> InnerProduct<V> for MidpointNorm<'_, V> {
    fn inner(&self, y: RatesView<'_, V>, z: RatesView<'_, V>) -> f64 {
        let mass = &self.sim.fluid.mass;
        let w = self.density_weight;
        let fluid = self.sim.sum_owned(|i| {
            mass[i]
                * (y.acceleration[i].dot(z.acceleration[i])
                    + w * y.density_rate[i] * z.density_rate[i])
        });
        let bodies: f64 = self
            .body_inertia
            .iter()
            .zip(y.body.iter().zip(z.body))
            .map(|(i, (a, b))| i * a * b)
            .sum();
        fluid + bodies
    }
}

/// The midpoint first guess, extrapolated in Newton's form through the rates `r_0, r_1, r_2`
/// of the last three steps, each held at its step's midpoint: with `s_0 = (dt + dt_0)/2` the
/// time from the last midpoint to `t^{n+1/2}`, `s_1 = (dt_0 + dt_1)/2` and
/// `s_2 = (dt_1 + dt_2)/2` the times between the held midpoints (`dt_0` the last step's size,
/// `dt_1`, `dt_2` those before), the guess is `r_0 + (r_0 - r_1) (c_1 + c_2) - (r_1 - r_2) c_3`
/// with `c_1 = s_0/s_1`, `q = s_0 (s_0 + s_1)/(s_1 + s_2)`, `c_2 = q/s_1`, `c_3 = q/s_2`:
/// `3 r_0 - 3 r_1 + r_2` for steps of one size. Where `r_2` is not held, the line through
/// `r_0, r_1` (`c_2 = c_3 = 0`).
#[derive(Clone, Copy, Debug)]
struct FirstGuess {
    slope: f64,
    curvature: f64,
}

impl FirstGuess {
    fn new(dt: f64, last_dt: f64, earlier_dt: f64, earliest_dt: Option<f64>) -> Self {
        let s0 = 0.5 * (dt + last_dt);
        let s1 = 0.5 * (last_dt + earlier_dt);
        let c1 = s0 / s1;
        match earliest_dt {
            Some(earliest_dt) => {
                let s2 = 0.5 * (earlier_dt + earliest_dt);
                let q = s0 * (s0 + s1) / (s1 + s2);
                FirstGuess {
                    slope: c1 + q / s1,
                    curvature: q / s2,
                }
            }
            None => FirstGuess {
                slope: c1,
                curvature: 0.0,
            },
        }
    }

    /// The guess from the rates of the last step, the earlier and the earliest.
    #[inline(always)]
    fn of<T>(&self, last: T, earlier: T, earliest: T) -> T
    where
        T: Copy
            + std::ops::Sub<Output = T>
            + std::ops::Add<Output = T>
            + std::ops::Mul<f64, Output = T>,
    {
        if self.curvature == 0.0 {
            last + (last - earlier) * self.slope
        } else {
            last + (last - earlier) * self.slope - (earlier - earliest) * self.curvature
        }
    }
}

#[cfg(test)]
mod tests {
    use super::FirstGuess;

    /// The rates sampled at the midpoints of steps `dt_2, dt_1, dt_0` and extrapolated to the
    /// midpoint of the step `dt` that follows them.
    fn extrapolate(rate: impl Fn(f64) -> f64, dt: f64, steps: [f64; 3], quadratic: bool) -> f64 {
        let [dt0, dt1, dt2] = steps;
        let (t0, t1, t2) = (-0.5 * dt0, -dt0 - 0.5 * dt1, -dt0 - dt1 - 0.5 * dt2);
        let guess = FirstGuess::new(dt, dt0, dt1, quadratic.then_some(dt2));
        guess.of(rate(t0), rate(t1), rate(t2))
    }

    #[test]
    fn steps_of_one_size_give_three_three_one() {
        let g = FirstGuess::new(0.5, 0.5, 0.5, Some(0.5));
        assert_eq!((g.slope, g.curvature), (2.0, 1.0));
        assert_eq!(g.of(5.0, 2.0, 1.0), 3.0 * 5.0 - 3.0 * 2.0 + 1.0);
    }

    #[test]
    fn the_parabola_through_three_midpoints_is_exact_for_uneven_steps() {
        let parabola = |t: f64| 2.0 - 3.0 * t + 7.0 * t * t;
        let (dt, steps) = (1.3e-3, [1.1e-3, 0.9e-3, 1.2e-3]);
        let guess = extrapolate(parabola, dt, steps, true);
        let exact = parabola(0.5 * dt);
        assert!(
            (guess - exact).abs() <= 1e-14 * exact.abs(),
            "{guess} against {exact}"
        );
        // The line through the last two misses the curvature.
        let line = extrapolate(parabola, dt, steps, false);
        assert!((line - exact).abs() > 1e-6);
        let straight = |t: f64| 2.0 - 3.0 * t;
        let line = extrapolate(straight, dt, steps, false);
        assert!((line - straight(0.5 * dt)).abs() <= 1e-14 * 2.0);
    }
}
