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

/// The Shepard strategy of a renormalised wall model: which `gamma_i` divides the operators.
/// The discrete gamma is evaluated in the sweep; the particles carry the geometric and the
/// integrated ones (set at time zero by [`Shepard::initialise`] and moved with them by
/// [`Shepard::advance`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Shepard {
    /// Which gamma.
    pub kind: ShepardKind,
}

impl Shepard {
    /// The strategy of `kind`.
    pub fn of(kind: ShepardKind) -> Self {
        Shepard { kind }
    }

    /// `true` when the particles carry gamma (all but the discrete one).
    pub fn carried(&self) -> bool {
        self.kind != ShepardKind::Discrete
    }

    /// The `gamma_i` that divides the operators of a particle (paper 1, eqs 24-25):
    /// `discrete` is `sum_j W_ij V_j` over the fluid, `carried` the particle's own gamma.
    pub fn gamma(&self, discrete: f64, carried: f64) -> f64 {
        match self.kind {
            ShepardKind::Discrete => discrete,
            ShepardKind::Geometric | ShepardKind::Integrated => carried,
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

    /// Moves the carried gamma with the particles after a drift `r += u dt`: the geometric
    /// value at the new positions (walls where they now are) for [`ShepardKind::Geometric`],
    /// or `gamma += (grad gamma^n + grad gamma^{n+1})/2 . u dt` (paper 3, eq 4, fixed walls;
    /// a trapezoidal line integral) for [`ShepardKind::Integrated`].
    ///
    /// With `continuity`, the walls' part of the continuity equation is integrated over the
    /// drift as well: the renormalised boundary term `(rho / gamma) sum_k (u - U_k) . n_k
    /// int_{S_k} W dS` is `-rho dln(gamma)/dt`, since `sum_k n_k int_{S_k} W dS =
    /// -grad gamma` (paper 3, eq 9) and the walls move their elements rigidly, so
    /// `rho *= gamma^n / gamma^{n+1}` integrates it exactly along the particle's path
    /// ([`WallContinuity`]).
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
        continuity: Option<WallContinuity<'_>>,
    ) {
        let integrate = self.kind == ShepardKind::Integrated;
        let next = |gamma: f64, grad: &mut V, x: V, u: V| {
            if integrate {
                let new = usaw::grad_gamma(kernel, x, elements, grid);
                let next = gamma + (*grad + new).dot(u) * (0.5 * dt);
                *grad = new;
                next
            } else {
                geometric_shepard::gamma(kernel, x, elements, grid)
            }
        };
        let particles = gamma
            .par_iter_mut()
            .zip(grad_gamma.par_iter_mut())
            .zip(position.par_iter().zip(drift.par_iter()));
        match continuity {
            None => particles.for_each(|((gamma, grad), (&x, &u))| {
                *gamma = next(*gamma, grad, x, u);
            }),
            Some(WallContinuity { density, rest }) => particles
                .zip(density.par_iter_mut())
                .for_each(|(((gamma, grad), (&x, &u)), rho)| {
                    let new = next(*gamma, grad, x, u);
                    if *gamma > 0.0 && new > 0.0 {
                        *rho = WallContinuity::compress(*rho, *gamma / new, rest);
                    }
                    *gamma = new;
                }),
        }
    }
}

/// The walls' part of the continuity equation integrated over a drift ([`Shepard::advance`]):
/// the densities it changes and the rest density `rho0`.
#[derive(Debug)]
pub struct WallContinuity<'a> {
    /// The particles' densities.
    pub density: &'a mut [f64],
    /// Rest density `rho0`.
    pub rest: f64,
}

impl WallContinuity<'_> {
    /// `rho gamma^n / gamma^{n+1}` (`ratio = gamma^n / gamma^{n+1}`), except that walls do not
    /// stretch water below its rest density: a particle that leaves a wall expands to `rho0`
    /// at most, and not at all below it. The term's `-u . grad gamma / gamma` takes the
    /// kernel support as filled with fluid, which a particle at a free surface next to a wall
    /// (spray, a jet up a corner) is not; followed there, a particle that leaves a concave
    /// edge (gamma 1/4) for open space (gamma 1) would fall to a quarter of its density and
    /// be pulled back by the tension.
    #[inline]
    pub fn compress(rho: f64, ratio: f64, rest: f64) -> f64 {
        let stretched = rho * ratio;
        if ratio >= 1.0 {
            stretched
        } else {
            stretched.max(rho.min(rest))
        }
    }
}
