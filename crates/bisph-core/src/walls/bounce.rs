//! Elastic bounce: the last line of defence against particles crossing a wall.
//!
//! The boundary-integral wall force is finite, so a fast particle can reach the wall plane.
//! Before the drift, a particle that would cross an element's plane within the element's
//! extent during the step has the normal component of its velocity relative to the element
//! reflected: `u' = u - 2 ((u - U_j) . n_j) n_j`. The speed relative to the wall is kept, so
//! the bounce exchanges no energy with fixed walls; with a moving wall the kinetic energy
//! change is booked as wall work. (Paper 1, section 4.1, mentions this device; the authors'
//! code applies it by default.)

use super::clearance::WallClearance;
use super::BoundaryElements;
use crate::dim::Vector;
use crate::neighbours::CellGrid;
use rayon::prelude::*;

/// Reflects the motion of particles that would cross a wall in the next `dt`.
///
/// `drift` is the velocity the particles move with during the step; when it would carry a
/// particle through an element's plane within the element's reach, its normal component
/// relative to the element is reflected. `end`, when given (midpoint scheme), is the
/// end-of-step velocity: its relative normal component is reflected too when it points into
/// the wall, which keeps its magnitude. Without `end`, `drift` is also the particle velocity.
/// Particles that `clearance` shows farther from every wall than the drift and the fastest
/// element take them together are not searched (a bounce off element `j` needs
/// `|x - c_j| - reach_j <= dt (drift - U_j) . n_j`).
/// Sets `lost_energy` to the kinetic energy each particle lost (energy given to moving
/// walls).
#[allow(clippy::too_many_arguments)]
pub fn elastic_bounce<V: Vector>(
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
    clearance: &WallClearance<V>,
    position: &[V],
    mass: &[f64],
    drift: &mut [V],
    end: Option<&mut [V]>,
    dt: f64,
    lost_energy: &mut Vec<f64>,
) {
    lost_energy.clear();
    lost_energy.resize(position.len(), 0.0);
    if elements.is_empty() {
        return;
    }
    let reflect = |u: &mut V, j: usize| {
        let n = elements.normal[j];
        let normal_speed = (*u - elements.velocity[j]).dot(n);
        if normal_speed > 0.0 {
            *u -= n * (2.0 * normal_speed);
        }
    };
    let wall_speed = elements
        .velocity
        .iter()
        .map(|u| u.length())
        .fold(0.0, f64::max);
    let visit = |i: usize, d: &mut V, mut e: Option<&mut V>, lost: &mut f64| {
        let x = position[i];
        if grid.no_candidates(x) || clearance.clear(i, dt * (d.length() + wall_speed)) {
            // No element near: nothing to reflect (`lost` stays 0).
            return;
        }
        let before = e
            .as_deref()
            .map_or(d.length_squared(), |e| e.length_squared());
        grid.for_each_candidate_shifted(x, |j, shift| {
            let n = elements.normal[j];
            let r = elements.centre[j] + shift - x;
            let normal_distance = r.dot(n);
            if normal_distance < 0.0 {
                return; // behind this element's plane
            }
            let approach = (*d - elements.velocity[j]).dot(n);
            if approach <= 0.0 || normal_distance > dt * approach {
                return; // not reaching the plane in this step
            }
            if (r - n * normal_distance).length_squared()
                <= (elements.reach[j] * (1.0 + 1e-6)).powi(2)
            {
                reflect(d, j);
                if let Some(e) = e.as_deref_mut() {
                    reflect(e, j);
                }
            }
        });
        let after = e
            .as_deref()
            .map_or(d.length_squared(), |e| e.length_squared());
        *lost = 0.5 * mass[i] * (before - after);
    };
    match end {
        Some(end) => drift
            .par_iter_mut()
            .zip(end.par_iter_mut())
            .zip(lost_energy.par_iter_mut())
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, ((d, e), lost))| visit(i, d, Some(e), lost)),
        None => drift
            .par_iter_mut()
            .zip(lost_energy.par_iter_mut())
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, (d, lost))| visit(i, d, None, lost)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::{Body, Motion, PrescribedMotion};
    use crate::walls::Walls;
    use glam::DVec3;

    /// A wall moving towards a particle at rest reflects it when it would reach the particle
    /// within the step, though the particle itself does not move: the skip by the clearance
    /// counts the wall's own speed.
    #[test]
    fn a_wall_moving_onto_a_particle_at_rest_reflects_it() {
        let side = 0.02;
        let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(a, b)| DVec3::new(a, b, 0.0) * (0.5 * side));
        let mut elements = BoundaryElements::default();
        elements.push(DVec3::ZERO, DVec3::Z, side * side, 1, &corners);
        let motion = PrescribedMotion {
            velocity: DVec3::new(0.0, 0.0, -2.0),
            amplitude: DVec3::ZERO,
            frequency: 0.0,
            phase: 0.0,
            axis: DVec3::Z,
            angular_velocity: 0.0,
            angular_amplitude: 0.0,
            angular_frequency: 0.0,
        };
        let piston = Body {
            name: "piston".into(),
            centre: DVec3::ZERO,
            motion: Motion::Prescribed(motion),
        };
        let mut walls = Walls::new(elements, vec![Body::fixed("walls"), piston], 0.25);
        walls.move_to(0.0);
        // 0.05 below the element: clear of it by more than 0.03, which the wall covers in the
        // step of 0.03 s at 2 m/s twice over.
        let position = [DVec3::new(0.0, 0.0, -0.05)];
        let mut clearance = WallClearance::default();
        clearance.measure(&walls, &position, 0.0, None);
        assert!(clearance.clear(0, 0.03));
        let mut drift = [DVec3::ZERO];
        let mut lost = Vec::new();
        let e = &walls.elements;
        elastic_bounce(
            e,
            &walls.grid,
            &clearance,
            &position,
            &[1.0],
            &mut drift,
            None,
            0.03,
            &mut lost,
        );
        assert_eq!(drift[0], DVec3::new(0.0, 0.0, -4.0));
    }
}
