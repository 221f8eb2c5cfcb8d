//! Bodies that own boundary elements: fixed, moving with a prescribed motion, a piston
//! driven by the fluid (paper 1, section 5.2), or a free rigid body with six degrees of
//! freedom driven by the fluid's force and torque (paper 1, App. C) and gravity.
//!
//! Dynamic bodies (pistons and free bodies) expose their generalised velocities and
//! accelerations as flat lists ([`Motion::velocities`], [`Motion::accelerations`]) so one
//! integrator path (the midpoint iterations, or Verlet) advances all of them with the fluid.

use crate::dim::Vector;
use glam::{DMat3, DQuat, DVec3};
use std::f64::consts::TAU;

/// Position and velocity of a rigid body relative to its reference configuration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kinematics<V: Vector> {
    /// Displacement of the body's centre.
    pub displacement: V,
    /// Rotation (angle about z in 2-D; axis times angle in 3-D) about the centre.
    pub rotation: V::Angular,
    /// Velocity of the centre.
    pub velocity: V,
    /// Angular velocity.
    pub angular_velocity: V::Angular,
}

/// A prescribed rigid motion: the centre moves as
/// `d(t) = v t + A (sin(2 pi f t + phi) - sin(phi))` and the body turns about its centre
/// by `theta(t) = (omega t + B sin(2 pi f_r t)) * axis` (axis = z in 2-D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrescribedMotion<V: Vector> {
    /// Constant translation velocity `v`.
    pub velocity: V,
    /// Oscillation amplitude `A` of the centre.
    pub amplitude: V,
    /// Oscillation frequency `f` in Hz.
    pub frequency: f64,
    /// Oscillation phase `phi` in radians.
    pub phase: f64,
    /// Unit rotation axis (3-D; ignored in 2-D).
    pub axis: V,
    /// Constant angular velocity `omega` in rad/s.
    pub angular_velocity: f64,
    /// Angular oscillation amplitude `B` in radians.
    pub angular_amplitude: f64,
    /// Angular oscillation frequency `f_r` in Hz.
    pub angular_frequency: f64,
}

/// A piston: a rigid wall sliding along `axis` (its outward normal), driven by the fluid's
/// pressure force and a constant outside force pushing it back:
/// `m d2x/dt2 = F_fluid . axis - F_out` (paper 1, section 5.2 and App. C).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piston<V: Vector> {
    /// Unit axis of motion, pointing out of the fluid.
    pub axis: V,
    /// Mass `m`.
    pub mass: f64,
    /// Outside force `F_out` (outside pressure times the piston area), along `-axis`.
    pub outside_force: f64,
    /// Displacement `x` along the axis from the reference configuration.
    pub position: f64,
    /// Velocity along the axis (the midpoint velocity while a midpoint step iterates).
    pub velocity: f64,
    /// Acceleration along the axis from the last force evaluation.
    pub acceleration: f64,
}

impl<V: Vector> Piston<V> {
    /// Kinetic energy `m v^2 / 2`.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass * self.velocity * self.velocity
    }
}

/// How a free body's dynamics couples to the fluid's midpoint iterations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Coupling {
    /// The body's accelerations are re-evaluated in every midpoint iteration with the fluid
    /// (the fluid-body energy exchange closes at convergence).
    #[default]
    Iterated,
    /// Loose, staggered coupling: the body moves through a step with the load of the
    /// previous step (the scheme of paper 1, 5.4), for comparison.
    Staggered,
}

/// A free rigid body (6 degrees of freedom in 3-D, 3 in 2-D) driven by the fluid's pressure
/// force and torque about its centre of mass (paper 1, App. C, eqs 69-71) and gravity:
/// `m dv/dt = F + m g`, `I dOmega/dt = tau_b - Omega x I Omega` in body axes
/// (`Omega` the body-frame angular velocity, `tau_b = q^-1 tau` the torque in body axes,
/// `q` the attitude quaternion from body to world axes). Locked degrees of freedom keep their
/// initial velocity: translations along world axes, rotations about body axes (the locked
/// rows and columns of `I` are dropped from the solve, so the rotational energy balance stays
/// exact when locked rates are zero).
///
/// Under the midpoint rule (`v^{n+1} - v^n = dt a`, `a` at the midpoint velocities and the
/// positions of `t^n`) the body's kinetic energy `m v^2/2 + Omega . I Omega / 2` and gravity
/// potential `-m g . x` change by exactly `dt (F . v + tau . omega)` evaluated at the
/// midpoint, which is `dt sum_j F_j . U_j`: the work the fluid gives the walls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeBody {
    /// Mass `m`.
    pub mass: f64,
    /// Inertia tensor about the centre of mass, in body axes.
    pub inertia: DMat3,
    /// Gravity acting on the body.
    pub gravity: DVec3,
    /// Attitude at time zero (body to world axes).
    pub initial_attitude: DQuat,
    /// Current attitude (body to world axes).
    pub attitude: DQuat,
    /// Displacement of the centre of mass from its position at time zero.
    pub position: DVec3,
    /// Velocity of the centre of mass (world axes); the midpoint velocity while a midpoint
    /// step iterates.
    pub velocity: DVec3,
    /// Angular velocity in body axes `Omega`.
    pub angular_velocity: DVec3,
    /// Acceleration of the centre of mass (world axes) from the last load evaluation.
    pub acceleration: DVec3,
    /// Angular acceleration in body axes.
    pub angular_acceleration: DVec3,
    /// Translations locked along world x, y, z.
    pub locked_translation: [bool; 3],
    /// Rotations locked about body x, y, z.
    pub locked_rotation: [bool; 3],
    /// Coupling with the fluid's iterations.
    pub coupling: Coupling,
}

impl FreeBody {
    /// A body at rest with the given mass, body-axes inertia and initial attitude.
    pub fn new(mass: f64, inertia: DMat3, attitude: DQuat, gravity: DVec3) -> Self {
        FreeBody {
            mass,
            inertia,
            gravity,
            initial_attitude: attitude,
            attitude,
            position: DVec3::ZERO,
            velocity: DVec3::ZERO,
            angular_velocity: DVec3::ZERO,
            acceleration: DVec3::ZERO,
            angular_acceleration: DVec3::ZERO,
            locked_translation: [false; 3],
            locked_rotation: [false; 3],
            coupling: Coupling::Iterated,
        }
    }

    /// Locks what a 2-D body cannot do: translation along z, rotation about x and y.
    pub fn planar(mut self) -> Self {
        self.locked_translation[2] = true;
        self.locked_rotation[0] = true;
        self.locked_rotation[1] = true;
        self
    }

    /// Angular velocity in world axes, `omega = q Omega`.
    pub fn world_angular_velocity(&self) -> DVec3 {
        self.attitude * self.angular_velocity
    }

    /// Angular acceleration in world axes, `q dOmega/dt`.
    pub fn world_angular_acceleration(&self) -> DVec3 {
        self.attitude * self.angular_acceleration
    }

    /// Kinetic energy `m v^2 / 2 + Omega . I Omega / 2`.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass * self.velocity.length_squared()
            + 0.5
                * self
                    .angular_velocity
                    .dot(self.inertia * self.angular_velocity)
    }

    /// Gravity potential `-m g . x` (zero at the initial position).
    pub fn potential_energy(&self) -> f64 {
        -self.mass * self.gravity.dot(self.position)
    }

    /// Accelerations from the fluid's force and torque (world axes, torque about the centre
    /// of mass) at the current velocities and attitude.
    pub fn accelerations(&self, force: DVec3, torque: DVec3) -> (DVec3, DVec3) {
        let mut a = force / self.mass + self.gravity;
        for k in 0..3 {
            if self.locked_translation[k] {
                a[k] = 0.0;
            }
        }
        let w = self.angular_velocity;
        let mut rhs = self.attitude.inverse() * torque - w.cross(self.inertia * w);
        let mut m = self.inertia;
        for k in 0..3 {
            if self.locked_rotation[k] {
                rhs[k] = 0.0;
                for l in 0..3 {
                    let (value_kl, value_lk) = if k == l { (1.0, 1.0) } else { (0.0, 0.0) };
                    m.col_mut(l)[k] = value_kl;
                    m.col_mut(k)[l] = value_lk;
                }
            }
        }
        (a, m.inverse() * rhs)
    }

    /// Moves the body through `dt` with the (midpoint) velocities it holds:
    /// `x += dt v`, `q <- q exp(dt Omega)` (body-axes rotation).
    pub fn drift(&mut self, dt: f64) {
        self.position += self.velocity * dt;
        let turn = self.angular_velocity * dt;
        let angle = turn.length();
        if angle > 0.0 {
            self.attitude =
                (self.attitude * DQuat::from_axis_angle(turn / angle, angle)).normalize();
        }
    }
}

/// An angular quantity of the space `V` from a 3-D vector (its z-component in 2-D).
pub fn angular_of<V: Vector>(w: DVec3) -> V::Angular {
    if V::DIM == 2 {
        V::angular_from_slice(&[w.z])
    } else {
        V::angular_from_slice(&w.to_array())
    }
}

/// A 3-D vector from an angular quantity of the space `V` (`(0, 0, w)` in 2-D).
pub fn angular_to_3d<V: Vector>(w: V::Angular) -> DVec3 {
    let v = V::angular_to_vec(w);
    if V::DIM == 2 {
        DVec3::new(0.0, 0.0, v[0])
    } else {
        DVec3::new(v[0], v[1], v[2])
    }
}

/// How a body moves. (A case has a handful of bodies: the size of the free variant does not
/// matter, and keeping `Motion` `Copy` keeps the integrators simple.)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion<V: Vector> {
    /// Never moves.
    Fixed,
    /// Moves as a given function of time.
    Prescribed(PrescribedMotion<V>),
    /// Moves with its own dynamics along one axis.
    Piston(Piston<V>),
    /// A free rigid body.
    Free(FreeBody),
}

impl<V: Vector> Motion<V> {
    /// `true` for bodies with their own dynamics (pistons, free bodies).
    pub fn is_dynamic(&self) -> bool {
        matches!(self, Motion::Piston(_) | Motion::Free(_))
    }

    /// Appends the generalised velocities of a dynamic body (piston: 1; free: `v` then
    /// `Omega`, 6 numbers).
    pub fn velocities(&self, out: &mut Vec<f64>) {
        match self {
            Motion::Piston(p) => out.push(p.velocity),
            Motion::Free(b) => {
                out.extend(b.velocity.to_array());
                out.extend(b.angular_velocity.to_array());
            }
            _ => {}
        }
    }

    /// Appends the generalised accelerations (same layout as [`Motion::velocities`]).
    pub fn accelerations(&self, out: &mut Vec<f64>) {
        match self {
            Motion::Piston(p) => out.push(p.acceleration),
            Motion::Free(b) => {
                out.extend(b.acceleration.to_array());
                out.extend(b.angular_acceleration.to_array());
            }
            _ => {}
        }
    }

    /// Appends the inertia of every generalised coordinate (mass, or the diagonal of `I`), the
    /// weights of the energy residue.
    pub fn inertias(&self, out: &mut Vec<f64>) {
        match self {
            Motion::Piston(p) => out.push(p.mass),
            Motion::Free(b) => {
                out.extend([b.mass; 3]);
                out.extend([b.inertia.x_axis.x, b.inertia.y_axis.y, b.inertia.z_axis.z]);
            }
            _ => {}
        }
    }

    /// Sets the generalised velocities from `values` (consumed from the front); returns how
    /// many were used.
    pub fn set_velocities(&mut self, values: &[f64]) -> usize {
        match self {
            Motion::Piston(p) => {
                p.velocity = values[0];
                1
            }
            Motion::Free(b) => {
                b.velocity = DVec3::from_slice(&values[0..3]);
                b.angular_velocity = DVec3::from_slice(&values[3..6]);
                6
            }
            _ => 0,
        }
    }

    /// Sets the generalised accelerations (see [`Motion::set_velocities`]).
    pub fn set_accelerations(&mut self, values: &[f64]) -> usize {
        match self {
            Motion::Piston(p) => {
                p.acceleration = values[0];
                1
            }
            Motion::Free(b) => {
                b.acceleration = DVec3::from_slice(&values[0..3]);
                b.angular_acceleration = DVec3::from_slice(&values[3..6]);
                6
            }
            _ => 0,
        }
    }

    /// Moves a dynamic body through `dt` with the velocities it holds.
    pub fn drift(&mut self, dt: f64) {
        match self {
            Motion::Piston(p) => p.position += dt * p.velocity,
            Motion::Free(b) => b.drift(dt),
            _ => {}
        }
    }

    /// `true` when the body's accelerations follow the fluid's iterations (staggered free
    /// bodies keep the load of the previous step).
    pub fn iterated(&self) -> bool {
        match self {
            Motion::Free(b) => b.coupling == Coupling::Iterated,
            _ => true,
        }
    }

    /// Kinematics at time `t` (a piston's come from its own state).
    pub fn kinematics(&self, t: f64) -> Kinematics<V> {
        match self {
            Motion::Fixed => Kinematics::default(),
            Motion::Free(b) => {
                let relative = b.attitude * b.initial_attitude.inverse();
                Kinematics {
                    displacement: V::from_slice(&b.position.to_array()),
                    rotation: angular_of::<V>(relative.to_scaled_axis()),
                    velocity: V::from_slice(&b.velocity.to_array()),
                    angular_velocity: angular_of::<V>(b.world_angular_velocity()),
                }
            }
            Motion::Piston(p) => Kinematics {
                displacement: p.axis * p.position,
                velocity: p.axis * p.velocity,
                ..Kinematics::default()
            },
            Motion::Prescribed(m) => {
                let w = TAU * m.frequency;
                let arg = w * t + m.phase;
                let displacement = m.velocity * t + m.amplitude * (arg.sin() - m.phase.sin());
                let velocity = m.velocity + m.amplitude * (w * arg.cos());
                let wr = TAU * m.angular_frequency;
                let angle = m.angular_velocity * t + m.angular_amplitude * (wr * t).sin();
                let rate = m.angular_velocity + m.angular_amplitude * wr * (wr * t).cos();
                let axis = V::angular_from_slice(&m.axis.to_xyz());
                let (rotation, angular_velocity) = if V::DIM == 2 {
                    (
                        V::angular_from_slice(&[angle]),
                        V::angular_from_slice(&[rate]),
                    )
                } else {
                    (axis * angle, axis * rate)
                };
                Kinematics {
                    displacement,
                    rotation,
                    velocity,
                    angular_velocity,
                }
            }
        }
    }
}

/// A rigid body owning boundary elements.
#[derive(Clone, Debug)]
pub struct Body<V: Vector> {
    /// Name used in outputs (`forces.csv`).
    pub name: String,
    /// Reference point at time zero: centre of rotation and of moments.
    pub centre: V,
    /// Its motion.
    pub motion: Motion<V>,
}

impl<V: Vector> Body<V> {
    /// The fixed walls (body 0 of every case).
    pub fn fixed(name: &str) -> Self {
        Body {
            name: name.to_string(),
            centre: V::ZERO,
            motion: Motion::Fixed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Midpoint steps of a free body under a constant world force and torque:
    /// `V^{n+1/2} = V^n + dt/2 A(V^{n+1/2})` iterated to convergence, as the integrator does.
    fn midpoint_step(b: &mut FreeBody, force: DVec3, torque: DVec3, dt: f64) -> f64 {
        let (v0, w0) = (b.velocity, b.angular_velocity);
        let e0 = b.kinetic_energy() + b.potential_energy();
        for _ in 0..60 {
            b.velocity = v0 + b.acceleration * (0.5 * dt);
            b.angular_velocity = w0 + b.angular_acceleration * (0.5 * dt);
            let (a, alpha) = b.accelerations(force, torque);
            b.acceleration = a;
            b.angular_acceleration = alpha;
        }
        b.velocity = v0 + b.acceleration * (0.5 * dt);
        b.angular_velocity = w0 + b.angular_acceleration * (0.5 * dt);
        // Work of the load at the midpoint velocities (what sum_j F_j . U_j gives).
        let work = dt * (force.dot(b.velocity) + torque.dot(b.world_angular_velocity()));
        b.drift(dt);
        b.velocity = v0 + b.acceleration * dt;
        b.angular_velocity = w0 + b.angular_acceleration * dt;
        (b.kinetic_energy() + b.potential_energy()) - e0 - work
    }

    #[test]
    fn free_body_energy_balances_the_load_work_under_the_midpoint_rule() {
        let inertia = DMat3::from_diagonal(DVec3::new(5560.0, 5270.0, 4180.0));
        let mut b = FreeBody::new(
            3900.0,
            inertia,
            DQuat::from_rotation_y(0.2),
            DVec3::new(0.0, 0.0, -9.81),
        );
        b.velocity = DVec3::new(0.3, 0.0, -9.08);
        b.angular_velocity = DVec3::new(0.7, -1.1, 2.0);
        let (force, torque) = (
            DVec3::new(100.0, -50.0, 2e4),
            DVec3::new(300.0, 800.0, -100.0),
        );
        for _ in 0..50 {
            let error = midpoint_step(&mut b, force, torque, 1e-3);
            assert!(error.abs() < 1e-9 * 2e5, "energy error {error}");
        }
        // Torque-free: the angular momentum in world axes is conserved too (to the order of
        // the scheme) and the kinetic energy exactly.
        let mut free = FreeBody::new(1.0, inertia, DQuat::IDENTITY, DVec3::ZERO);
        free.angular_velocity = DVec3::new(0.01, 1.0, 0.02);
        let l0 = free.attitude * (free.inertia * free.angular_velocity);
        let e0 = free.kinetic_energy();
        for _ in 0..1000 {
            midpoint_step(&mut free, DVec3::ZERO, DVec3::ZERO, 1e-3);
        }
        let l1 = free.attitude * (free.inertia * free.angular_velocity);
        assert!((free.kinetic_energy() - e0).abs() < 1e-9 * e0);
        assert!((l1 - l0).length() < 1e-4 * l0.length(), "{l0} {l1}");
    }

    #[test]
    fn locked_degrees_of_freedom_stay_locked() {
        let inertia = DMat3::from_cols_array(&[4.0, 0.5, 0.0, 0.5, 3.0, 0.2, 0.0, 0.2, 2.0]);
        let mut b = FreeBody::new(2.0, inertia, DQuat::IDENTITY, DVec3::new(0.0, 0.0, -9.81));
        b.locked_translation = [true, false, true];
        b.locked_rotation = [true, false, true];
        let (a, alpha) = b.accelerations(DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, 1.0, 1.0));
        assert_eq!((a.x, a.z, alpha.x, alpha.z), (0.0, 0.0, 0.0, 0.0));
        assert!((a.y - 1.0).abs() < 1e-15 && (alpha.y - 1.0 / 3.0).abs() < 1e-15);
    }
}
