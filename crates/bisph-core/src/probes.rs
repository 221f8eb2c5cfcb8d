//! Probes: pressure sampled at fixed points, and water heights along vertical columns.

use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::CellGrid;
use crate::particles::Fluid;

/// What a probe measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProbeKind {
    /// Fluid pressure, Shepard-normalised: `sum p W V / sum W V` (zero where no fluid is near).
    Pressure,
    /// Wall pressure on a wall point, the estimator of paper 1 eq 71: `2 sum p W V`.
    WallPressure,
    /// Water height of the column through the probe along the last axis (y in 2-D, z in 3-D):
    /// `sum_i V_i W'(|d_i|)`, `d_i` the particle's offset across the column and `W'` the
    /// Wendland C2 kernel of the same `h` one dimension lower (`5/(8h) (1-q/2)^3 (1+3q/2)` in
    /// 1-D, `7/(4 pi h^2) (1-q/2)^4 (1+2q)` in 2-D): the column integral of the particle
    /// volume density, equal to the depth for a uniformly filled column.
    Height,
}

/// A named probe at a fixed point.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe<V> {
    /// Column name in `probes.csv`.
    pub name: String,
    /// What it measures.
    pub kind: ProbeKind,
    /// Where.
    pub position: V,
}

impl<V: Vector> Probe<V> {
    /// The probe's value for the current fluid state.
    pub fn sample(&self, kernel: &Wendland, fluid: &Fluid<V>, grid: &CellGrid<V>) -> f64 {
        let mut weighted = 0.0;
        let mut shepard = 0.0;
        grid.for_each_neighbour(self.position, &fluid.position, kernel.support, |i, _, r| {
            let wv = kernel.value(r) * fluid.mass[i] / fluid.density[i];
            weighted += fluid.pressure[i] * wv;
            shepard += wv;
        });
        match self.kind {
            ProbeKind::Pressure if shepard > 0.0 => weighted / shepard,
            ProbeKind::Pressure => 0.0,
            ProbeKind::WallPressure => 2.0 * weighted,
            ProbeKind::Height => self.height(kernel, fluid),
        }
    }

    /// See [`ProbeKind::Height`]: summed in particle order over all particles.
    fn height(&self, kernel: &Wendland, fluid: &Fluid<V>) -> f64 {
        let h = kernel.h;
        let last = V::DIM - 1;
        let lower = Wendland::new(h, 2);
        let mut sum = 0.0;
        for i in 0..fluid.len() {
            let mut d = fluid.position[i] - self.position;
            d.set(last, 0.0);
            let r = d.length();
            if r >= 2.0 * h {
                continue;
            }
            let w = if V::DIM == 3 {
                lower.value(r)
            } else {
                let a = 1.0 - 0.5 * r / h;
                5.0 / (8.0 * h) * a * a * a * (1.0 + 1.5 * r / h)
            };
            sum += fluid.mass[i] / fluid.density[i] * w;
        }
        sum
    }
}
