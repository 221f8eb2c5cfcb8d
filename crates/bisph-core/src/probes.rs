//! Probes: pressure sampled at fixed points.

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
        }
    }
}
