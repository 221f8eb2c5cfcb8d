//! Bodies that own boundary elements: fixed, moving with a prescribed motion, or a piston
//! driven by the fluid (paper 1, section 5.2).

use crate::dim::Vector;
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

/// How a body moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion<V: Vector> {
    /// Never moves.
    Fixed,
    /// Moves as a given function of time.
    Prescribed(PrescribedMotion<V>),
    /// Moves with its own dynamics along one axis.
    Piston(Piston<V>),
}

impl<V: Vector> Motion<V> {
    /// Kinematics at time `t` (a piston's come from its own state).
    pub fn kinematics(&self, t: f64) -> Kinematics<V> {
        match self {
            Motion::Fixed => Kinematics::default(),
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
