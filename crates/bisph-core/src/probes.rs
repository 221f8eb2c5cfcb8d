//! Probes: pressure sampled at fixed points, and water heights along vertical columns.

use crate::decomposition::ExactSum;
use crate::dim::Vector;
use crate::energy::exact_partial_sum;
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
    /// The probe's value as an exact sum over parts of the fluid: the first `owned` particles
    /// of `fluid` are this part's, and `owns(x)` tells whether this part samples at the point
    /// `x`. A point value (pressures) is added by the part that owns the probe's position, from
    /// the neighbours around it; a height by every part, over its own particles. The sums of
    /// all parts add up to the value of the whole fluid, with its bits.
    pub fn sample_sum(
        &self,
        kernel: &Wendland,
        fluid: &Fluid<V>,
        owned: usize,
        grid: &CellGrid<V>,
        owns: impl Fn(V) -> bool,
    ) -> ExactSum {
        if self.kind == ProbeKind::Height {
            return self.height(kernel, fluid, owned);
        }
        let mut sum = ExactSum::new();
        if !owns(self.position) {
            return sum;
        }
        let mut weighted = 0.0;
        let mut shepard = 0.0;
        grid.for_each_neighbour(self.position, &fluid.position, kernel.support, |i, _, r| {
            let wv = kernel.value(r) * fluid.mass[i] / fluid.density[i];
            weighted += fluid.pressure[i] * wv;
            shepard += wv;
        });
        sum.add(match self.kind {
            ProbeKind::Pressure if shepard > 0.0 => weighted / shepard,
            ProbeKind::WallPressure => 2.0 * weighted,
            _ => 0.0,
        });
        sum
    }

    /// See [`ProbeKind::Height`]: summed exactly over the first `n` particles.
    fn height(&self, kernel: &Wendland, fluid: &Fluid<V>, n: usize) -> ExactSum {
        let h = kernel.h;
        let last = V::DIM - 1;
        let lower = Wendland::new(h, 2);
        exact_partial_sum(n, |i| {
            let mut d = fluid.position[i] - self.position;
            d.set(last, 0.0);
            let r = d.length();
            if r >= 2.0 * h {
                return 0.0;
            }
            let w = if V::DIM == 3 {
                lower.value(r)
            } else {
                let a = 1.0 - 0.5 * r / h;
                5.0 / (8.0 * h) * a * a * a * (1.0 + 1.5 * r / h)
            };
            fluid.mass[i] / fluid.density[i] * w
        })
    }
}
