//! A uniform driving force that imposes a volume flux in a periodic flow (paper 3, section 5).
//!
//! The flux through a slice normal to the flow (eq 56),
//! `Q_SPH = (1 / dr_A) sum_{b in slice} V_b u_b . n_A`, gives the cross-averaged (bulk)
//! velocity `v~ = Q_SPH / A` (eq 57). Before each step `n` the driving acceleration along
//! `n_A` is set from the target `v = Q / A` by
//! - eq 58 (Violeau): `F^n = (v - 2 v~^{n-1} + v~^{n-2}) / (2 dt)`, which ignores the internal
//!   forces and so settles at a bulk velocity off by `2 dt F`;
//! - eq 63 (Mayrhofer et al.): `F^n = (v - 2 v~^{n-1} + v~^{n-2}) / dt + F^{n-1}`, which
//!   carries the internal forces over from the last step and settles at `v~ = v`.

use crate::decomposition::ExactSum;
use crate::dim::Vector;
use crate::energy::exact_partial_sum;
use crate::neighbours::Periodicity;

/// Which update rule drives the flux.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FluxRule {
    /// Paper 3 eq 58 (Violeau's book).
    Eq58,
    /// Paper 3 eq 63.
    Eq63,
}

/// A prescribed volume flux.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FluxControl<V> {
    /// Unit flow direction `n_A`.
    pub direction: V,
    /// Target bulk velocity `v = Q / A`.
    pub target_velocity: f64,
    /// Cross-section area `A` (a length in 2-D).
    pub area: f64,
    /// A point on the measuring slice.
    pub slice_point: V,
    /// Slice width `dr_A` (paper 3: twice the particle spacing).
    pub slice_width: f64,
    /// Update rule.
    pub rule: FluxRule,
}

/// The controller's memory: the last two bulk velocities and the last force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FluxHistory {
    /// `v~^{n-1}` (the bulk velocity at the start of the coming step).
    pub last: f64,
    /// `v~^{n-2}`.
    pub before_last: f64,
    /// `F^{n-1}`, the driving acceleration of the last step.
    pub force: f64,
}

impl<V: Vector> FluxControl<V> {
    /// The volume flux through the slice, `sum V_i u_i . e` over the particles in it (of
    /// `position`, the others' arrays at least as long), summed exactly: the sums over parts
    /// of the fluid add up to the whole's. Distances to the slice are taken across the period
    /// where the flow direction is periodic.
    pub fn flux_sum(
        &self,
        position: &[V],
        velocity: &[V],
        mass: &[f64],
        density: &[f64],
        periodicity: &Periodicity<V>,
    ) -> ExactSum {
        let half = 0.5 * self.slice_width;
        exact_partial_sum(position.len(), |i| {
            let d = periodicity
                .minimum_image(position[i] - self.slice_point)
                .dot(self.direction);
            if d >= -half && d < half {
                mass[i] / density[i] * velocity[i].dot(self.direction)
            } else {
                0.0
            }
        })
    }

    /// Bulk velocity `v~ = Q_SPH / A` (eqs 56-57) of the volume flux `flux` through the slice
    /// ([`FluxControl::flux_sum`]).
    pub fn bulk_velocity_of(&self, flux: f64) -> f64 {
        flux / self.slice_width / self.area
    }

    /// The driving acceleration of the coming step of size `dt` (eq 58 or eq 63).
    pub fn next_force(&self, history: &FluxHistory, dt: f64) -> f64 {
        let change = self.target_velocity - 2.0 * history.last + history.before_last;
        match self.rule {
            FluxRule::Eq58 => change / (2.0 * dt),
            FluxRule::Eq63 => change / dt + history.force,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    /// A plug flow with a linear friction `-k v`: eq 63 settles at the target, eq 58 at
    /// `v (1 - 2 dt k)` to first order, as section 5 of paper 3 says.
    #[test]
    fn eq63_settles_at_the_target_and_eq58_does_not() {
        let (k, dt, target) = (5.0, 1e-3, 1.0);
        let run = |rule| {
            let c = FluxControl {
                direction: DVec2::X,
                target_velocity: target,
                area: 1.0,
                slice_point: DVec2::ZERO,
                slice_width: 0.1,
                rule,
            };
            let mut h = FluxHistory::default();
            let mut v: f64 = 0.0;
            for _ in 0..20000 {
                let f = c.next_force(&h, dt);
                v += dt * (f - k * v);
                h = FluxHistory {
                    last: v,
                    before_last: h.last,
                    force: f,
                };
            }
            v
        };
        let e63 = (run(FluxRule::Eq63) - target).abs();
        let e58 = (run(FluxRule::Eq58) - target).abs();
        assert!(e63 < 1e-12, "{e63}");
        assert!((e58 - 2.0 * dt * k).abs() < 2e-4, "{e58}");
    }

    #[test]
    fn bulk_velocity_counts_the_slice_across_the_period() {
        let c = FluxControl {
            direction: DVec2::X,
            target_velocity: 1.0,
            area: 2.0,
            slice_point: DVec2::ZERO,
            slice_width: 0.2,
            rule: FluxRule::Eq63,
        };
        let period = Periodicity {
            min: DVec2::ZERO,
            length: DVec2::new(1.0, 0.0),
        };
        // Two particles in the slice (one across the period), one outside.
        let pos = [
            DVec2::new(0.05, 0.0),
            DVec2::new(0.95, 1.0),
            DVec2::new(0.5, 0.0),
        ];
        let vel = [DVec2::new(2.0, 0.0); 3];
        let flux = c.flux_sum(&pos, &vel, &[0.1; 3], &[1.0; 3], &period);
        let v = c.bulk_velocity_of(flux.value());
        assert!((v - 2.0 * 0.1 * 2.0 / 0.2 / 2.0).abs() < 1e-14);
    }
}
