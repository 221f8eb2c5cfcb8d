//! Elastic bounce: the last line of defence against particles crossing a wall.
//!
//! The boundary-integral wall force is finite, so a fast particle can reach the wall plane.
//! Before the drift, a particle that would cross an element's plane within the element's
//! extent during the step has the normal component of its velocity relative to the element
//! reflected: `u' = u - 2 ((u - U_j) . n_j) n_j`. The speed relative to the wall is kept, so
//! the bounce exchanges no energy with fixed walls; with a moving wall the kinetic energy
//! change is booked as wall work. (Paper 1, section 4.1, mentions this device; the authors'
//! code applies it by default.)

use super::BoundaryElements;
use crate::dim::Vector;
use crate::neighbours::CellGrid;
use rayon::prelude::*;

/// Reflects the velocities of particles that would cross a wall in the next `dt`.
///
/// The particles drift with `velocity` or, when `start_velocity` is given, with the mean of
/// the two (midpoint scheme: `velocity` is then the end-of-step velocity, reflected so its
/// magnitude relative to the wall is kept). Returns the kinetic energy the particles lost
/// (energy given to the walls), summed in a fixed order.
#[allow(clippy::too_many_arguments)]
pub fn elastic_bounce<V: Vector>(
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
    position: &[V],
    mass: &[f64],
    velocity: &mut [V],
    start_velocity: Option<&[V]>,
    dt: f64,
    lost_energy: &mut Vec<f64>,
) -> f64 {
    if elements.is_empty() {
        return 0.0;
    }
    lost_energy.clear();
    lost_energy.resize(position.len(), 0.0);
    velocity
        .par_iter_mut()
        .zip(lost_energy.par_iter_mut())
        .enumerate()
        .with_min_len(256)
        .for_each(|(i, (u, lost))| {
            let x = position[i];
            let before = u.length_squared();
            let start = start_velocity.map(|s| s[i]);
            grid.for_each_candidate(x, |j| {
                let n = elements.normal[j];
                let r = elements.centre[j] - x;
                let normal_distance = r.dot(n);
                if normal_distance < 0.0 {
                    return; // behind this element's plane
                }
                if (r - n * normal_distance).length() > elements.reach[j] * (1.0 + 1e-6) {
                    return; // beside the element
                }
                let drift = match start {
                    Some(s) => (*u + s) * 0.5,
                    None => *u,
                };
                let approach = (drift - elements.velocity[j]).dot(n);
                if approach > 0.0 && normal_distance <= dt * approach {
                    let normal_speed = (*u - elements.velocity[j]).dot(n);
                    if normal_speed > 0.0 {
                        *u -= n * (2.0 * normal_speed);
                    }
                }
            });
            *lost = 0.5 * mass[i] * (before - u.length_squared());
        });
    crate::energy::deterministic_sum(lost_energy.len(), |i| lost_energy[i])
}
