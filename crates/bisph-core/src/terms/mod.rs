//! Physical terms and the sweep that turns a fluid state into rates.
//!
//! Each term lives in its own file as a pair function; [`compute_rates`] fuses them into one
//! gather loop per particle (each particle sums its own neighbours, so the result does not
//! depend on the number of threads) and asks the wall model for the wall parts:
//! - momentum, paper 1 eq 2: `du_i/dt = -(<grad p>_i^Omega + <grad p>_i^{dOmega}) / rho_i + g`,
//!   plus the laminar viscosity of paper 3 eq 18 with its wall shear ([`viscosity`]) and a
//!   uniform driving body force (the flux control of paper 3, section 5);
//! - continuity, paper 1 eq 1: `drho_i/dt = -rho_i (<div u>_i^Omega + <div u>_i^{dOmega}) + D_i`.

pub mod density_diffusion;
pub mod pressure_gradient;
pub mod velocity_divergence;
pub mod viscosity;

use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::{CandidateList, CellGrid, KeptBlock, PairList};
use crate::particles::FluidState;
use crate::walls::{BoundaryElements, ParticleView, WallModel};
pub use density_diffusion::{DensityDiffusion, DiffusionForm};
use rayon::prelude::*;
pub use viscosity::Viscosity;

/// The operators of one particle, split into fluid and wall parts (for power bookkeeping).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Operators<V> {
    /// `<grad p>_i^Omega` (eq 10).
    pub pressure_gradient: V,
    /// `<div u>_i^Omega` (eq 11).
    pub velocity_divergence: f64,
    /// `<grad p>_i^{dOmega}` from the wall model.
    pub wall_pressure_gradient: V,
    /// `<div u>_i^{dOmega}` from the wall model.
    pub wall_velocity_divergence: f64,
    /// Density diffusion `D_i`.
    pub density_diffusion: f64,
    /// Viscous acceleration, fluid part (paper 3 eq 18).
    pub viscous: V,
    /// Viscous acceleration, wall part (wall shear, paper 3 eqs 18-20).
    pub wall_viscous: V,
}

/// The rates at which one particle's dissipative terms take energy from the fluid.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DissipationRates {
    /// `-m_i u_i . a_i^visc`: the viscous Laplacian (paper 3, eq 18, with its wall shear).
    pub viscous: f64,
    /// `-m_i p_i D_i / rho_i^2`: the compressible energy `m_i e(rho_i)` that the density
    /// diffusion `D_i` removes (`de/drho = p / rho^2`).
    pub diffusion: f64,
}

/// Where the fluid sums find each particle's fluid neighbours. Both give the same neighbours
/// in the same order with the same `r_ij` and kernel gradient factors, so the sums agree to
/// the bit; one pair loop serves both ([`fluid_sums`]).
#[derive(Clone, Copy, Debug)]
pub enum FluidNeighbours<'a, V: Vector> {
    /// Searched in the cell grid of the fluid at every evaluation.
    Grid(&'a CellGrid<V>),
    /// Read from a list made by [`PairList::rebuild`] over the same grid and positions, with
    /// the kernel gradient factor as its per-pair factor (the iterations of a midpoint step,
    /// where the positions are frozen).
    List(&'a PairList<V>),
    /// Filtered from the candidates of an explicit step's Verlet list ([`CandidateList`],
    /// still valid for the positions): the same neighbours, in the list's order (the storage
    /// order when it was built), so sums may differ from the grid's in the last bits (and
    /// `r_ij` too across periodic axes, where it is the minimum image).
    Candidates(&'a CandidateList<V>),
}

/// What the sweep needs besides the state.
#[derive(Clone, Copy, Debug)]
pub struct RateModel<V: Vector> {
    /// The kernel.
    pub kernel: Wendland,
    /// Gravity `g`.
    pub gravity: V,
    /// Density diffusion (delta-SPH or paper 3's volume diffusion).
    pub diffusion: DensityDiffusion<V>,
    /// Laminar viscosity (off when `nu = 0`).
    pub viscosity: Viscosity,
    /// Uniform driving acceleration (e.g. the flux control of paper 3, section 5), added to
    /// every particle like gravity but booked apart in the energy.
    pub body_force: V,
    /// The density power `k` of paper 3, eqs 37-38 (0: paper 1, eqs 10-11; or 1).
    pub density_power: u8,
    /// Density by summation (paper 3, eqs 13 and 84): the sweep's density rate is then the
    /// diffusion term alone, which the integrator accumulates (see [`crate::simulation`]).
    pub summation_density: bool,
    /// The walls' part of the continuity equation is left to the integrator, which
    /// integrates it over each drift ([`crate::walls::shepard::Shepard::advance`]): the
    /// renormalised velocity divergence is then the fluid sum over gamma alone.
    pub wall_continuity_in_drift: bool,
}

/// Operators of particle `i` at the state `fluid`.
pub fn particle_operators<V: Vector, W: WallModel<V>>(
    model: &RateModel<V>,
    wall_model: &W,
    fluid: &FluidState<V>,
    neighbours: FluidNeighbours<'_, V>,
    elements: &BoundaryElements<V>,
    wall_grid: &CellGrid<V>,
    i: usize,
) -> Operators<V> {
    let mut kept = KeptBlock::new();
    let walls = (wall_model, elements, wall_grid);
    operators_with(model, walls, fluid, neighbours, &mut kept, i)
}

/// [`particle_operators`] with the neighbour filter's buffers `kept` of the calling task.
#[inline(always)]
fn operators_with<V: Vector, W: WallModel<V>>(
    model: &RateModel<V>,
    (wall_model, elements, wall_grid): (&W, &BoundaryElements<V>, &CellGrid<V>),
    fluid: &FluidState<V>,
    neighbours: FluidNeighbours<'_, V>,
    kept: &mut KeptBlock<V>,
    i: usize,
) -> Operators<V> {
    let kernel = &model.kernel;
    let (x_i, u_i, rho_i, p_i) = (
        fluid.position[i],
        fluid.velocity[i],
        fluid.density[i],
        fluid.pressure[i],
    );
    let viscosity = model.viscosity;
    let viscid = viscosity.active();
    let discrete_shepard = W::RENORMALISE && wall_model.needs_discrete_shepard();
    let sums = fluid_sums_dispatch(
        model,
        fluid,
        neighbours,
        kept,
        i,
        [
            model.density_power != 0,
            model.diffusion.scale != 0.0,
            viscid,
            discrete_shepard,
        ],
    );
    let FluidSums {
        grad_p,
        div_u,
        diffusion,
        viscous,
        shepard,
    } = sums;
    let view = ParticleView {
        index: i,
        x: x_i,
        u: u_i,
        p: p_i,
        rho: rho_i,
    };
    let wall = wall_model.particle_terms(kernel, &view, elements, wall_grid);
    let wall_viscous = if viscid {
        wall_model.wall_viscous(kernel, &viscosity, x_i, u_i, elements, wall_grid)
    } else {
        V::ZERO
    };
    let gamma = if W::RENORMALISE {
        wall_model.renormalisation(shepard, fluid.gamma[i])
    } else {
        1.0
    };
    if W::RENORMALISE && gamma > 0.0 {
        // Paper 1 eqs 33-34: the wall part is the renormalised total minus the fluid part.
        let scale = 1.0 / gamma;
        let total_grad = (grad_p + wall.pressure_gradient) * scale;
        let wall_div = if model.wall_continuity_in_drift {
            0.0
        } else {
            wall.velocity_divergence
        };
        let total_div = (div_u + wall_div) * scale;
        // Paper 3 eq 18: the Laplacian (fluid and wall sums) over gamma as well.
        let total_viscous = (viscous + wall_viscous) * scale;
        return Operators {
            pressure_gradient: grad_p,
            velocity_divergence: div_u,
            wall_pressure_gradient: total_grad - grad_p,
            wall_velocity_divergence: total_div - div_u,
            density_diffusion: if W::RENORMALISE_DIFFUSION {
                diffusion * scale
            } else {
                diffusion
            },
            viscous,
            wall_viscous: total_viscous - viscous,
        };
    }
    // Paper 3 eq 18 divides the Laplacian by gamma_i, the kernel's integral over the fluid;
    // models that do not renormalise supply it ([`WallModel::laplacian_gamma`]).
    let (viscous, wall_viscous) = if viscid {
        let gamma = wall_model.laplacian_gamma(kernel, x_i, elements, wall_grid);
        if gamma > 0.0 && gamma != 1.0 {
            (viscous / gamma, wall_viscous / gamma)
        } else {
            (viscous, wall_viscous)
        }
    } else {
        (viscous, wall_viscous)
    };
    Operators {
        pressure_gradient: grad_p,
        velocity_divergence: div_u,
        wall_pressure_gradient: wall.pressure_gradient,
        wall_velocity_divergence: wall.velocity_divergence,
        density_diffusion: diffusion,
        viscous,
        wall_viscous,
    }
}

/// The fluid sums of one particle (before the wall model completes them).
#[derive(Clone, Copy, Debug)]
struct FluidSums<V> {
    grad_p: V,
    div_u: f64,
    diffusion: f64,
    viscous: V,
    shepard: f64,
}

/// What the pair terms of particle `i` read: its own values and the neighbours' slices
/// (all of one length, so one bounds check covers them).
struct PairInputs<'a, V: Vector> {
    model: &'a RateModel<V>,
    velocity: &'a [V],
    density: &'a [f64],
    pressure: &'a [f64],
    volume: &'a [f64],
    u_i: V,
    rho_i: f64,
    p_i: f64,
}

impl<V: Vector> PairInputs<'_, V> {
    /// Adds the pair `(i, j)` with `r_ij`, `r = |r_ij|` and the kernel gradient factor `f` to
    /// the sums of `i`: the only pair loop body of [`fluid_sums`], for searched and listed
    /// neighbours alike (a function, not a closure with two call sites, so that it is always
    /// inlined into both loops).
    #[inline(always)]
    fn add<const WEIGHTED: bool, const DIFFUSE: bool, const VISCID: bool, const SHEPARD: bool>(
        &self,
        sums: &mut FluidSums<V>,
        j: usize,
        r_ij: V,
        r: f64,
        f: f64,
    ) {
        let (u_i, rho_i, p_i) = (self.u_i, self.rho_i, self.p_i);
        let (velocity, density, pressure) = (self.velocity, self.density, self.pressure);
        let grad_w = r_ij * f;
        let volume_j = self.volume[j];
        if WEIGHTED {
            let ratio = rho_i / density[j];
            sums.grad_p += pressure_gradient::pair_k(p_i, pressure[j], grad_w, volume_j, ratio);
            sums.div_u += velocity_divergence::pair_k(u_i, velocity[j], grad_w, volume_j, ratio);
        } else {
            sums.grad_p += pressure_gradient::pair(p_i, pressure[j], grad_w, volume_j);
            sums.div_u += velocity_divergence::pair(u_i, velocity[j], grad_w, volume_j);
        }
        if DIFFUSE {
            sums.diffusion += self
                .model
                .diffusion
                .pair(rho_i, density[j], r_ij, r, f, volume_j);
        }
        if VISCID {
            let viscosity = self.model.viscosity;
            sums.viscous += viscosity.pair(u_i, velocity[j], rho_i, density[j], f, volume_j);
        }
        if SHEPARD {
            sums.shepard += self.model.kernel.value(r) * volume_j;
        }
    }

    /// Adds a run of neighbours `index[k]` with offsets `r_ij[k]`, `(|r_ij|, F) = r_f(k)`, to
    /// the sums of `i`. The run is summed into a copy of the sums (held in registers, not in
    /// memory) that replaces them at its end: the pair order and so the bits are those of one
    /// running sum.
    #[inline(always)]
    fn add_run<
        const WEIGHTED: bool,
        const DIFFUSE: bool,
        const VISCID: bool,
        const SHEPARD: bool,
    >(
        &self,
        sums: &mut FluidSums<V>,
        index: &[u32],
        r_ij: &[V],
        r_f: impl Fn(usize) -> (f64, f64),
    ) {
        let mut run = *sums;
        for (k, (&j, &r_ij)) in index.iter().zip(r_ij).enumerate() {
            let (r, f) = r_f(k);
            self.add::<WEIGHTED, DIFFUSE, VISCID, SHEPARD>(&mut run, j as usize, r_ij, r, f);
        }
        *sums = run;
    }
}

/// [`fluid_sums`] with its switches `[weighted, diffuse, viscid, shepard]` turned into
/// constants, so that the pair loop of each combination carries no test of them.
#[inline(always)]
fn fluid_sums_dispatch<V: Vector>(
    model: &RateModel<V>,
    fluid: &FluidState<V>,
    neighbours: FluidNeighbours<'_, V>,
    kept: &mut KeptBlock<V>,
    i: usize,
    switches: [bool; 4],
) -> FluidSums<V> {
    macro_rules! pick {
        ($($w:literal $d:literal $v:literal $s:literal),*) => {
            match switches {
                $([$w, $d, $v, $s] => fluid_sums::<V, $w, $d, $v, $s>(model, fluid, neighbours, kept, i),)*
            }
        };
    }
    pick!(
        false false false false, false false false true, false false true false,
        false false true true, false true false false, false true false true,
        false true true false, false true true true, true false false false,
        true false false true, true false true false, true false true true,
        true true false false, true true false true, true true true false, true true true true
    )
}

/// The fluid-neighbour sums of particle `i` (paper 1 eqs 10-11 or paper 3 eqs 37-38, the
/// density diffusion, the viscous Laplacian of paper 3 eq 18 and the discrete Shepard sum),
/// in the grid's storage order of the neighbours, searched or listed ([`FluidNeighbours`]).
#[inline(never)]
fn fluid_sums<
    V: Vector,
    const WEIGHTED: bool,
    const DIFFUSE: bool,
    const VISCID: bool,
    const SHEPARD: bool,
>(
    model: &RateModel<V>,
    fluid: &FluidState<V>,
    neighbours: FluidNeighbours<'_, V>,
    kept: &mut KeptBlock<V>,
    i: usize,
) -> FluidSums<V> {
    let kernel = &model.kernel;
    let n = fluid.position.len();
    // Slices of one length: a neighbour index checked against the positions is in range
    // for all of them.
    let (position, velocity, density) = (
        &fluid.position[..n],
        &fluid.velocity[..n],
        &fluid.density[..n],
    );
    let (pressure, volume) = (&fluid.pressure[..n], &fluid.volume[..n]);
    let (x_i, u_i, rho_i, p_i) = (position[i], velocity[i], density[i], pressure[i]);
    let mut sums = FluidSums {
        grad_p: V::ZERO,
        div_u: 0.0,
        diffusion: 0.0,
        viscous: V::ZERO,
        shepard: 0.0,
    };
    let pair = PairInputs {
        model,
        velocity,
        density,
        pressure,
        volume,
        u_i,
        rho_i,
        p_i,
    };
    // The two searched arms are written out: one closure shared by reference is not inlined
    // into the searches (callgrind, 20k dam break: +8% instructions).
    match neighbours {
        FluidNeighbours::Grid(grid) => {
            grid.for_each_neighbour_run(x_i, position, kernel.support, kept, |index, r_ij, r2| {
                pair.add_run::<WEIGHTED, DIFFUSE, VISCID, SHEPARD>(&mut sums, index, r_ij, |k| {
                    let r = r2[k].sqrt();
                    (r, kernel.gradient_factor_within(r))
                })
            })
        }
        FluidNeighbours::Candidates(list) => list.for_each_neighbour_run(
            i,
            x_i,
            position,
            kernel.support,
            kept,
            |index, r_ij, r2| {
                pair.add_run::<WEIGHTED, DIFFUSE, VISCID, SHEPARD>(&mut sums, index, r_ij, |k| {
                    let r = r2[k].sqrt();
                    (r, kernel.gradient_factor_within(r))
                })
            },
        ),
        // `|r_ij|` as the search computes it (the root of `r_ij . r_ij`), the same bits.
        FluidNeighbours::List(list) => {
            let (index, r_ij, factor) = list.neighbours(i);
            pair.add_run::<WEIGHTED, DIFFUSE, VISCID, SHEPARD>(&mut sums, index, r_ij, |k| {
                (r_ij[k].length(), factor[k])
            })
        }
    }
    sums
}

/// Evaluates `du/dt` and `drho/dt` of every particle at the state `fluid` (paper 1 eqs 1-2)
/// into `acceleration` and `density_rate`, in parallel; `dissipation` receives each
/// particle's [`DissipationRates`] (zero for a term that is off).
#[allow(clippy::too_many_arguments)]
pub fn compute_rates<V: Vector, W: WallModel<V>>(
    model: &RateModel<V>,
    wall_model: &W,
    fluid: &FluidState<V>,
    neighbours: FluidNeighbours<'_, V>,
    elements: &BoundaryElements<V>,
    wall_grid: &CellGrid<V>,
    acceleration: &mut [V],
    density_rate: &mut [f64],
    dissipation: &mut [DissipationRates],
) {
    let body = model.gravity + model.body_force;
    acceleration
        .par_iter_mut()
        .zip(density_rate.par_iter_mut().zip(dissipation.par_iter_mut()))
        .enumerate()
        .with_min_len(256)
        .for_each_init(KeptBlock::new, |kept, (i, (a, (drho, dissipation)))| {
            let walls = (wall_model, elements, wall_grid);
            let op = operators_with(model, walls, fluid, neighbours, kept, i);
            let rho = fluid.density[i];
            let viscous = op.viscous + op.wall_viscous;
            *a = (op.pressure_gradient + op.wall_pressure_gradient) * (-1.0 / rho) + viscous + body;
            *drho = if model.summation_density {
                op.density_diffusion
            } else {
                -rho * (op.velocity_divergence + op.wall_velocity_divergence) + op.density_diffusion
            };
            let m = fluid.mass[i];
            *dissipation = DissipationRates {
                viscous: -m * fluid.velocity[i].dot(viscous),
                diffusion: -m * fluid.pressure[i] * op.density_diffusion / (rho * rho),
            };
        });
}
