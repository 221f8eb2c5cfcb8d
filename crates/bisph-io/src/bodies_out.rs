//! Per-body output of free rigid bodies (`body_<name>.csv`): position, attitude (quaternion
//! and Euler angles), velocities and accelerations in world and body axes, energies and the
//! fluid's load.

use bisph_core::walls::bodies::angular_to_3d;
use bisph_core::walls::FreeBody;
use bisph_core::Vector;
use glam::{DVec3, EulerRot};

/// Columns of `body_<name>.csv`. World axes: `x..`, `vx..`, `ax..`, `wx..` (angular velocity),
/// `alphax..`, `fx..`, `mx..` (fluid force and torque about the centre of mass); body axes:
/// `u, v, w` (velocity), `bax..` (acceleration), `p, q, r` (angular velocity), `balphax..`;
/// attitude: quaternion `qw, qx, qy, qz` (body to world) and Euler angles `roll, pitch, yaw`
/// in degrees (z-y-x sequence: yaw about z, then pitch about y, then roll about x);
/// `kinetic` (translation + rotation) and `potential` (gravity, zero at the start) [J].
pub const FREE_BODY_COLUMNS: [&str; 43] = [
    "t",
    "x",
    "y",
    "z",
    "qw",
    "qx",
    "qy",
    "qz",
    "roll",
    "pitch",
    "yaw",
    "vx",
    "vy",
    "vz",
    "u",
    "v",
    "w",
    "wx",
    "wy",
    "wz",
    "p",
    "q",
    "r",
    "ax",
    "ay",
    "az",
    "bax",
    "bay",
    "baz",
    "alphax",
    "alphay",
    "alphaz",
    "balphax",
    "balphay",
    "balphaz",
    "kinetic",
    "potential",
    "fx",
    "fy",
    "fz",
    "mx",
    "my",
    "mz",
];

/// One row of `body_<name>.csv`.
pub fn free_body_row<V: Vector>(
    t: f64,
    b: &FreeBody,
    centre: V,
    force: V,
    torque: V::Angular,
) -> Vec<f64> {
    let q = b.attitude;
    let inv = q.inverse();
    let (yaw, pitch, roll) = q.to_euler(EulerRot::ZYX);
    let x = DVec3::from_array(centre.to_xyz());
    let f = DVec3::from_array(force.to_xyz());
    let m = angular_to_3d::<V>(torque);
    let mut row = vec![t];
    row.extend(x.to_array());
    row.extend([q.w, q.x, q.y, q.z]);
    row.extend([roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()]);
    row.extend(b.velocity.to_array());
    row.extend((inv * b.velocity).to_array());
    row.extend(b.world_angular_velocity().to_array());
    row.extend(b.angular_velocity.to_array());
    row.extend(b.acceleration.to_array());
    row.extend((inv * b.acceleration).to_array());
    row.extend(b.world_angular_acceleration().to_array());
    row.extend(b.angular_acceleration.to_array());
    row.extend([b.kinetic_energy(), b.potential_energy()]);
    row.extend(f.to_array());
    row.extend(m.to_array());
    row
}
