//! The Shepard factor `gamma_i`, the kernel's integral over the fluid around a particle: the
//! one strategy that the renormalised wall models (the classic boundary integrals and the
//! semi-analytical walls) obtain it by, and the time advance of the gamma that particles carry.

use super::{geometric_shepard, usaw, BoundaryElements};
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::CellGrid;
use rayon::prelude::*;

/// How the Shepard factor `gamma_i` is obtained (the case file's `shepard`, and the
/// `--method` of `bisph shepard`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShepardKind {
    /// `gamma_i = sum_j W_ij V_j` over the fluid (paper 2, eq 4); free surfaces lower it too.
    #[default]
    Discrete,
    /// From the wall elements alone (paper 2, eq 8; [`geometric_shepard`]).
    Geometric,
    /// Integrated in time, `dgamma/dt = v_rel . grad gamma` (paper 3, eq 4), from the
    /// geometric value at time zero.
    Integrated,
}

impl std::str::FromStr for ShepardKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "discrete" => Ok(Self::Discrete),
            "geometric" => Ok(Self::Geometric),
            "integrated" => Ok(Self::Integrated),
            _ => Err(format!(
                "expected `discrete`, `geometric` or `integrated`, found `{s}`"
            )),
        }
    }
}

/// The Shepard strategy of a renormalised wall model: which `gamma_i` divides the operators,
/// and whether the particles carry it (set at time zero by [`Shepard::initialise`] and moved
/// with them by [`Shepard::advance`]) or it is evaluated where it is needed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Shepard {
    /// Which gamma.
    pub kind: ShepardKind,
    /// The particles carry gamma and `grad gamma` (paper 3, eqs 4 and 10).
    pub carried: bool,
}

impl Shepard {
    /// gamma evaluated where it is needed, or carried when integrated in time.
    pub fn of(kind: ShepardKind) -> Self {
        Shepard {
            kind,
            carried: kind == ShepardKind::Integrated,
        }
    }

    /// The `gamma_i` that divides the operators of a particle at `x` (paper 1, eqs 24-25):
    /// `discrete` is `sum_j W_ij V_j` over the fluid, `carried` the particle's own gamma.
    pub fn gamma<V: Vector>(
        &self,
        kernel: &Wendland,
        x: V,
        discrete: f64,
        carried: f64,
        elements: &BoundaryElements<V>,
        grid: &CellGrid<V>,
    ) -> f64 {
        match (self.carried, self.kind) {
            (true, _) | (false, ShepardKind::Integrated) => carried,
            (false, ShepardKind::Discrete) => discrete,
            (false, ShepardKind::Geometric) => geometric_shepard::gamma(kernel, x, elements, grid),
        }
    }

    /// Sets every particle's gamma to the geometric Shepard factor (paper 2) and its
    /// `grad gamma` (paper 3, eq 10) at `position`.
    pub fn initialise<V: Vector>(
        kernel: &Wendland,
        elements: &BoundaryElements<V>,
        grid: &CellGrid<V>,
        position: &[V],
        gamma: &mut [f64],
        grad_gamma: &mut [V],
    ) {
        gamma
            .par_iter_mut()
            .zip(grad_gamma.par_iter_mut())
            .zip(position.par_iter())
            .for_each(|((gamma, grad), &x)| {
                *gamma = geometric_shepard::gamma(kernel, x, elements, grid);
                *grad = usaw::grad_gamma(kernel, x, elements, grid);
            });
    }

    /// Advances the carried gamma after a drift `r += u dt` (paper 3, eq 4, fixed walls):
    /// `gamma += (grad gamma^n + grad gamma^{n+1})/2 . u dt` (trapezoidal line integral), or
    /// the geometric value at the new positions for [`ShepardKind::Geometric`].
    #[allow(clippy::too_many_arguments)]
    pub fn advance<V: Vector>(
        &self,
        kernel: &Wendland,
        elements: &BoundaryElements<V>,
        grid: &CellGrid<V>,
        gamma: &mut [f64],
        grad_gamma: &mut [V],
        position: &[V],
        drift: &[V],
        dt: f64,
    ) {
        let integrate = self.kind == ShepardKind::Integrated;
        gamma
            .par_iter_mut()
            .zip(grad_gamma.par_iter_mut())
            .zip(position.par_iter().zip(drift.par_iter()))
            .for_each(|((gamma, grad), (&x, &u))| {
                let new = usaw::grad_gamma(kernel, x, elements, grid);
                if integrate {
                    *gamma += (*grad + new).dot(u) * (0.5 * dt);
                } else {
                    *gamma = geometric_shepard::gamma(kernel, x, elements, grid);
                }
                *grad = new;
            });
    }
}
