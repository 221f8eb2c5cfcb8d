//! Physical terms and the sweep that turns a fluid state into rates.
//!
//! Each term lives in its own file as a pair function that gives both particles' shares;
//! [`compute_rates`] fuses them into one pair loop and asks the wall model for the wall parts.
//! Each particle either sums its own neighbours (a gather) or receives the shares of pairs
//! evaluated once for both particles ([`FluidNeighbours`]); in both the order of each
//! particle's sum depends neither on the number of threads nor on the parts of a split run:
//! - momentum, paper 1 eq 2: `du_i/dt = -(<grad p>_i^Omega + <grad p>_i^{dOmega}) / rho_i + g`,
//!   plus the laminar viscosity of paper 3 eq 18 with its wall shear ([`viscosity`]) and a
//!   uniform driving body force (the flux control of paper 3, section 5);
//! - continuity, paper 1 eq 1: `drho_i/dt = -rho_i (<div u>_i^Omega + <div u>_i^{dOmega}) + D_i`.

pub mod density_diffusion;
mod lanes;
pub mod pressure_gradient;
pub mod velocity_divergence;
pub mod viscosity;

use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::{
    single_precision, CellGrid, KeptBlock, ListedPairs, Listing, Nearby, PairBlocks, RunValues,
    KEPT_BLOCK,
};
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

/// How a sweep meets the fluid pairs.
#[derive(Clone, Copy, Debug)]
pub enum FluidNeighbours<'a, V: Vector> {
    /// Each particle searches the cell grid of the fluid for its own neighbours and sums them
    /// in the grid's storage order (a gather, [`fluid_sums`]).
    Grid(&'a CellGrid<V>),
    /// Each pair of an explicit step's Verlet list ([`PairBlocks`], still valid for the
    /// positions) is evaluated once and its shares added to both particles (a scatter,
    /// [`scattered_sums`]): the same pairs, each particle's in the list's order, so sums may
    /// differ from the grid's in the last bits (and `r_ij` too across periodic axes, where
    /// it is the minimum image).
    Pairs(&'a PairBlocks<V>),
    /// The pairs of a [`PairBlocks`] listed with their offsets and kernel gradient factors, or
    /// with their kernel gradients alone ([`pair_listing`]) in single precision, at frozen
    /// positions (the iterations of a midpoint step): the sums of
    /// [`FluidNeighbours::FrozenPairs`] at those positions, to the bit.
    Listed(&'a ListedPairs<V>),
    /// The pairs of [`FluidNeighbours::Listed`] filtered from the Verlet list at every
    /// evaluation, where their listing would take too much memory: the same pairs and order,
    /// and, where the sums read only the kernel gradients, those rounded to single precision
    /// as the listing rounds them.
    FrozenPairs(&'a PairBlocks<V>),
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

/// Calls `f::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(args)` with the switches `[weighted,
/// diffuse, viscid, shepard]` turned into constants, so that the pair loop of each
/// combination carries no test of them.
macro_rules! with_switches {
    ($switches:expr, $f:ident $args:tt) => {
        with_switches!(@arms $switches, $f $args;
            false false false false, false false false true, false false true false,
            false false true true, false true false false, false true false true,
            false true true false, false true true true, true false false false,
            true false false true, true false true false, true false true true,
            true true false false, true true false true, true true true false, true true true true)
    };
    (@arms $switches:expr, $f:ident $args:tt; $($w:literal $d:literal $v:literal $s:literal),*) => {
        match $switches {
            $([$w, $d, $v, $s] => $f::<_, $w, $d, $v, $s> $args,)*
        }
    };
}

/// Operators of particle `i` at the state `fluid`, its neighbours searched in `grid` (the
/// cell grid of `fluid`'s positions).
pub fn particle_operators<V: Vector, W: WallModel<V>>(
    model: &RateModel<V>,
    wall_model: &W,
    fluid: &FluidState<V>,
    grid: &CellGrid<V>,
    elements: &BoundaryElements<V>,
    wall_grid: &CellGrid<V>,
    i: usize,
) -> Operators<V> {
    let mut kept = KeptBlock::new();
    let switches = sum_switches(model, wall_model);
    let sums = with_switches!(switches, fluid_sums(model, fluid, grid, &mut kept, i));
    let walls = (wall_model, elements, Nearby::grid(wall_grid));
    operators_with(model, walls, fluid, &sums, i)
}

/// Which fluid sums a sweep adds: `[weighted, diffuse, viscid, shepard]`.
fn sum_switches<V: Vector, W: WallModel<V>>(model: &RateModel<V>, wall_model: &W) -> [bool; 4] {
    [
        model.density_power != 0,
        model.diffusion.scale != 0.0,
        model.viscosity.active(),
        W::RENORMALISE && wall_model.needs_discrete_shepard(),
    ]
}

/// The operators of particle `i` from its fluid sums `sums` and the wall model's terms.
#[inline(always)]
fn operators_with<V: Vector, W: WallModel<V>>(
    model: &RateModel<V>,
    (wall_model, elements, wall_near): (&W, &BoundaryElements<V>, Nearby<'_, V>),
    fluid: &FluidState<V>,
    sums: &FluidSums<V>,
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
    let FluidSums {
        grad_p,
        div_u,
        diffusion,
        viscous,
        shepard,
    } = *sums;
    let view = ParticleView {
        index: i,
        x: x_i,
        u: u_i,
        p: p_i,
        rho: rho_i,
    };
    let wall = wall_model.particle_terms(kernel, &view, elements, wall_near);
    let wall_viscous = if viscid {
        wall_model.wall_viscous(kernel, &viscosity, &view, elements, wall_near)
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
        let gamma = wall_model.laplacian_gamma(kernel, x_i, elements, wall_near.grid);
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

/// The fluid sums of one particle (before the wall model completes them), laid out as its
/// fields for [`lanes`].
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct FluidSums<V> {
    grad_p: V,
    div_u: f64,
    diffusion: f64,
    viscous: V,
    shepard: f64,
}

impl<V: Vector> FluidSums<V> {
    /// Nothing summed yet.
    pub const ZERO: Self = FluidSums {
        grad_p: V::ZERO,
        div_u: 0.0,
        diffusion: 0.0,
        viscous: V::ZERO,
        shepard: 0.0,
    };

    /// Adds the terms of `c` that are on (the others stay zero).
    #[inline(always)]
    fn add<const DIFFUSE: bool, const VISCID: bool, const SHEPARD: bool>(&mut self, c: &Self) {
        self.grad_p += c.grad_p;
        self.div_u += c.div_u;
        if DIFFUSE {
            self.diffusion += c.diffusion;
        }
        if VISCID {
            self.viscous += c.viscous;
        }
        if SHEPARD {
            self.shepard += c.shepard;
        }
    }
}

/// Sums a scatter adds the pair shares into.
trait Accumulator<V: Vector>: Copy + Send {
    fn accumulate<const DIFFUSE: bool, const VISCID: bool, const SHEPARD: bool>(
        &mut self,
        c: &FluidSums<V>,
    );
}

impl<V: Vector> Accumulator<V> for FluidSums<V> {
    #[inline(always)]
    fn accumulate<const DIFFUSE: bool, const VISCID: bool, const SHEPARD: bool>(
        &mut self,
        c: &FluidSums<V>,
    ) {
        self.add::<DIFFUSE, VISCID, SHEPARD>(c)
    }
}

/// The pressure-gradient and divergence sums alone, for sweeps with no other term on
/// (density diffusion, viscosity and the discrete Shepard sum off); laid out as its fields
/// for [`lanes`].
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct GradientSums<V> {
    grad_p: V,
    div_u: f64,
}

impl<V: Vector> GradientSums<V> {
    const ZERO: Self = GradientSums {
        grad_p: V::ZERO,
        div_u: 0.0,
    };
}

impl<V: Vector> Accumulator<V> for GradientSums<V> {
    #[inline(always)]
    fn accumulate<const DIFFUSE: bool, const VISCID: bool, const SHEPARD: bool>(
        &mut self,
        c: &FluidSums<V>,
    ) {
        debug_assert!(!sums_need_distances(DIFFUSE, VISCID, SHEPARD));
        self.grad_p += c.grad_p;
        self.div_u += c.div_u;
    }
}

/// What the pair terms read of one particle, laid out as its fields for [`lanes`].
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct Side<V> {
    u: V,
    rho: f64,
    p: f64,
    volume: f64,
}

impl<V: Vector> Side<V> {
    const ZERO: Self = Side {
        u: V::ZERO,
        rho: 0.0,
        p: 0.0,
        volume: 0.0,
    };
}

/// The fluid values the pair terms read, as slices of one length (an index checked against
/// one is in range for all).
struct PairValues<'a, V> {
    velocity: &'a [V],
    density: &'a [f64],
    pressure: &'a [f64],
    volume: &'a [f64],
}

impl<'a, V: Vector> PairValues<'a, V> {
    fn of(fluid: &FluidState<'a, V>) -> Self {
        let n = fluid.position.len();
        PairValues {
            velocity: &fluid.velocity[..n],
            density: &fluid.density[..n],
            pressure: &fluid.pressure[..n],
            volume: &fluid.volume[..n],
        }
    }

    #[inline(always)]
    fn side(&self, i: usize) -> Side<V> {
        Side {
            u: self.velocity[i],
            rho: self.density[i],
            p: self.pressure[i],
            volume: self.volume[i],
        }
    }
}

/// The shares of the pair `(i, j)` in the fluid sums of `i` and of `j`, `r_ij = x_j - x_i`,
/// `r = |r_ij|` and `f` the kernel gradient factor: paper 1 eqs 10-11 or paper 3 eqs 37-38,
/// the density diffusion, the viscous Laplacian of paper 3 eq 18 and the discrete Shepard
/// sum. Each share has the bits that a sum over its own particle's neighbours adds, so a
/// gather uses the first alone; the only pair loop body of the sweeps.
#[inline(always)]
fn pair_shares<
    V: Vector,
    const WEIGHTED: bool,
    const DIFFUSE: bool,
    const VISCID: bool,
    const SHEPARD: bool,
>(
    model: &RateModel<V>,
    a: &Side<V>,
    b: &Side<V>,
    r_ij: V,
    r: f64,
    f: f64,
) -> [FluidSums<V>; 2] {
    let grad_w = r_ij * f;
    let volume = [a.volume, b.volume];
    let (grad_p, div_u) = if WEIGHTED {
        let ratio = [a.rho / b.rho, b.rho / a.rho];
        (
            pressure_gradient::pair_k_sides(a.p, b.p, grad_w, volume, ratio),
            velocity_divergence::pair_k_sides(a.u, b.u, grad_w, volume, ratio),
        )
    } else {
        (
            pressure_gradient::pair_sides(a.p, b.p, grad_w, volume),
            velocity_divergence::pair_sides(a.u, b.u, grad_w, volume),
        )
    };
    let diffusion = if DIFFUSE {
        model.diffusion.pair_sides(a.rho, b.rho, r_ij, r, f, volume)
    } else {
        (0.0, 0.0)
    };
    let viscous = if VISCID {
        model
            .viscosity
            .pair_sides(a.u, b.u, [a.rho, b.rho], f, volume)
    } else {
        (V::ZERO, V::ZERO)
    };
    let shepard = if SHEPARD {
        let w = model.kernel.value(r);
        (w * b.volume, w * a.volume)
    } else {
        (0.0, 0.0)
    };
    [
        FluidSums {
            grad_p: grad_p.0,
            div_u: div_u.0,
            diffusion: diffusion.0,
            viscous: viscous.0,
            shepard: shepard.0,
        },
        FluidSums {
            grad_p: grad_p.1,
            div_u: div_u.1,
            diffusion: diffusion.1,
            viscous: viscous.1,
            shepard: shepard.1,
        },
    ]
}

/// The fluid-neighbour sums of particle `i` ([`pair_shares`]), its neighbours searched in
/// `grid` and summed in the grid's storage order.
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
    grid: &CellGrid<V>,
    kept: &mut KeptBlock<V>,
    i: usize,
) -> FluidSums<V> {
    let kernel = &model.kernel;
    let values = PairValues::of(fluid);
    let position = &fluid.position[..values.velocity.len()];
    let a = values.side(i);
    let mut sums = FluidSums::ZERO;
    grid.for_each_neighbour_run(
        position[i],
        position,
        kernel.support,
        kept,
        |index, r_ij, r2| {
            let mut run = sums;
            for (k, (&j, &r_ij)) in index.iter().zip(r_ij).enumerate() {
                let r = r2[k].sqrt();
                let f = kernel.gradient_factor_within(r);
                let b = values.side(j as usize);
                let [share, _] =
                    pair_shares::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(model, &a, &b, r_ij, r, f);
                run.add::<DIFFUSE, VISCID, SHEPARD>(&share);
            }
            // Summed in registers over the run, the bits of one running sum.
            sums = run;
        },
    );
    sums
}

/// Adds the shares of the pairs of `i` with `index[k]` (offsets `r_ij[k]`, `(|r_ij|, F) =
/// r_f(k)`) to the sums of both particles ([`pair_shares`]); `i`'s are summed in registers
/// over the run, the bits of one running sum.
#[inline(always)]
fn scatter_run<
    V: Vector,
    const WEIGHTED: bool,
    const DIFFUSE: bool,
    const VISCID: bool,
    const SHEPARD: bool,
>(
    model: &RateModel<V>,
    sides: &[Side<V>],
    (i, run): (usize, &mut RunValues<'_, impl Accumulator<V>>),
    index: &[u32],
    r_ij: &[V],
    r_f: impl Fn(usize) -> (f64, f64),
) {
    let a = sides[i];
    let mut own = *run.first();
    for (k, (&j, &r_ij)) in index.iter().zip(r_ij).enumerate() {
        let (r, f) = r_f(k);
        let b = sides[j as usize];
        let [to_i, to_j] =
            pair_shares::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(model, &a, &b, r_ij, r, f);
        own.accumulate::<DIFFUSE, VISCID, SHEPARD>(&to_i);
        run.partner(k).accumulate::<DIFFUSE, VISCID, SHEPARD>(&to_j);
    }
    *run.first() = own;
}

/// The pairs of a scatter: a Verlet list filtered at the positions (with the kernel
/// gradients rounded as [`Listing::Product`] rounds them when `round`), or its listed pairs.
#[derive(Clone, Copy)]
enum Scattered<'a, V> {
    Filtered {
        pairs: &'a PairBlocks<V>,
        round: bool,
    },
    Listed(&'a ListedPairs<V>),
}

/// The buffers of the scatter sweeps, kept from one sweep to the next: the values the pair
/// terms read, packed per particle (one load of 48 bytes in 3-D per partner instead of one
/// from each of four arrays), and the sums, as [`FluidSums`] or, when only the pressure gradient and the
/// divergence are summed, as the smaller [`GradientSums`].
#[derive(Clone, Debug, Default)]
pub struct ScatterBuffers<V> {
    sides: Vec<Side<V>>,
    sums: Vec<FluidSums<V>>,
    gradient_sums: Vec<GradientSums<V>>,
    gradient_only: bool,
}

impl<V: Vector> ScatterBuffers<V> {
    /// The fluid sums of particle `i` of the last [`scattered_sums`].
    #[inline(always)]
    fn sums(&self, i: usize) -> FluidSums<V> {
        if self.gradient_only {
            let GradientSums { grad_p, div_u } = self.gradient_sums[i];
            FluidSums {
                grad_p,
                div_u,
                ..FluidSums::ZERO
            }
        } else {
            self.sums[i]
        }
    }
}

/// The fluid sums of every listed particle into `buffers`, each pair of a Verlet list
/// (filtered at the positions) or of its listed pairs evaluated once and its shares added to
/// both particles.
#[inline(never)]
fn scattered_sums<
    V: Vector,
    const WEIGHTED: bool,
    const DIFFUSE: bool,
    const VISCID: bool,
    const SHEPARD: bool,
>(
    model: &RateModel<V>,
    fluid: &FluidState<V>,
    neighbours: Scattered<'_, V>,
    buffers: &mut ScatterBuffers<V>,
) {
    let values = PairValues::of(fluid);
    let n = values.velocity.len();
    buffers.sides.resize(n, Side::ZERO);
    buffers
        .sides
        .par_iter_mut()
        .enumerate()
        .with_min_len(4096)
        .for_each(|(i, side)| *side = values.side(i));
    buffers.gradient_only = !sums_need_distances(DIFFUSE, VISCID, SHEPARD);
    let sides = &buffers.sides[..];
    if buffers.gradient_only {
        let sums = zeroed(&mut buffers.gradient_sums, n, GradientSums::ZERO);
        let in_lanes = match neighbours {
            Scattered::Listed(listed) if !WEIGHTED => {
                lanes::sweep_listed_gradients(sides, listed, sums)
            }
            _ => false,
        };
        if !in_lanes {
            sweep_into::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(
                model, fluid, sides, neighbours, sums,
            );
        }
    } else {
        let sums = zeroed(&mut buffers.sums, n, FluidSums::ZERO);
        let in_lanes = match neighbours {
            Scattered::Filtered {
                pairs,
                round: false,
            } if !WEIGHTED && DIFFUSE && !VISCID && !SHEPARD => {
                lanes::sweep_filtered_diffused(model, fluid.position, sides, pairs, sums)
            }
            _ => false,
        };
        if !in_lanes {
            sweep_into::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(
                model, fluid, sides, neighbours, sums,
            );
        }
    }
}

/// `buffer` resized to `n` values, all `zero`.
fn zeroed<T: Copy + Send + Sync>(buffer: &mut Vec<T>, n: usize, zero: T) -> &mut [T] {
    buffer.resize(n, zero);
    buffer
        .par_iter_mut()
        .with_min_len(4096)
        .for_each(|s| *s = zero);
    buffer
}

/// The shares of every pair of `neighbours` added to the sums of both its particles, with
/// `sides` the packed values of the particles.
fn sweep_into<
    V: Vector,
    const WEIGHTED: bool,
    const DIFFUSE: bool,
    const VISCID: bool,
    const SHEPARD: bool,
>(
    model: &RateModel<V>,
    fluid: &FluidState<V>,
    sides: &[Side<V>],
    neighbours: Scattered<'_, V>,
    sums: &mut [impl Accumulator<V> + Sync],
) {
    let kernel = &model.kernel;
    match neighbours {
        // The kernel gradients of a listing, rounded as it rounds them.
        Scattered::Filtered { pairs, round }
            if round && !sums_need_distances(DIFFUSE, VISCID, SHEPARD) =>
        {
            pairs.sweep(
                fluid.position,
                kernel.support,
                sums,
                |i, run, index, r_ij, r2| {
                    let mut gradient = [V::ZERO; KEPT_BLOCK];
                    for (g, (&r_ij, &r2)) in gradient.iter_mut().zip(r_ij.iter().zip(r2)) {
                        *g = single_precision(r_ij * kernel.gradient_factor(r2.sqrt()));
                    }
                    scatter_run::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(
                        model,
                        sides,
                        (i, run),
                        index,
                        &gradient[..index.len()],
                        |_| (f64::NAN, 1.0),
                    )
                },
            )
        }
        Scattered::Filtered { pairs, .. } => pairs.sweep(
            fluid.position,
            kernel.support,
            sums,
            |i, run, index, r_ij, r2| {
                scatter_run::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(
                    model,
                    sides,
                    (i, run),
                    index,
                    r_ij,
                    |k| {
                        let r = r2[k].sqrt();
                        (r, kernel.gradient_factor_within(r))
                    },
                )
            },
        ),
        // `|r_ij|` as the filter computes it (the root of `r_ij . r_ij`), the same bits.
        Scattered::Listed(listed) => match listed.listing() {
            Listing::OffsetAndFactor => listed.sweep(sums, |i, run, index, r_ij, factor| {
                scatter_run::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(
                    model,
                    sides,
                    (i, run),
                    index,
                    r_ij,
                    |k| (r_ij[k].length(), factor[k]),
                )
            }),
            // The single-precision kernel gradients widened, as offsets with a factor of 1: no
            // term reads `|r_ij|` (the NaN would show).
            Listing::Product => {
                assert!(
                    !sums_need_distances(DIFFUSE, VISCID, SHEPARD),
                    "pairs listed without their distances"
                );
                listed.sweep(sums, |i, run, index, gradient, _| {
                    scatter_run::<V, WEIGHTED, DIFFUSE, VISCID, SHEPARD>(
                        model,
                        sides,
                        (i, run),
                        index,
                        gradient,
                        |_| (f64::NAN, 1.0),
                    )
                })
            }
        },
    }
}

/// `true` when a sweep with these switches reads the pairs' distances and kernel gradient
/// factors, not only their kernel gradients: density diffusion, viscosity or the discrete
/// Shepard sum.
const fn sums_need_distances(diffuse: bool, viscid: bool, shepard: bool) -> bool {
    diffuse || viscid || shepard
}

/// What the pairs of a midpoint step are listed with for the fluid sums of `model` with
/// `wall_model` ([`FluidNeighbours::Listed`]).
pub fn pair_listing<V: Vector, W: WallModel<V>>(model: &RateModel<V>, wall_model: &W) -> Listing {
    let [_, diffuse, viscid, shepard] = sum_switches(model, wall_model);
    if sums_need_distances(diffuse, viscid, shepard) {
        Listing::OffsetAndFactor
    } else {
        Listing::Product
    }
}

/// Evaluates `du/dt` and `drho/dt` of every particle at the state `fluid` (paper 1 eqs 1-2)
/// into `acceleration` and `density_rate`, in parallel; `dissipation` receives each
/// particle's [`DissipationRates`] (zero for a term that is off). `scatter` keeps the buffers
/// of a sweep over [`FluidNeighbours::Pairs`] or [`FluidNeighbours::Listed`]; `wall_near`
/// finds the elements near a particle.
#[allow(clippy::too_many_arguments)]
pub fn compute_rates<V: Vector, W: WallModel<V>>(
    model: &RateModel<V>,
    wall_model: &W,
    fluid: &FluidState<V>,
    neighbours: FluidNeighbours<'_, V>,
    elements: &BoundaryElements<V>,
    wall_near: Nearby<'_, V>,
    acceleration: &mut [V],
    density_rate: &mut [f64],
    dissipation: &mut [DissipationRates],
    scatter: &mut ScatterBuffers<V>,
) {
    let switches = sum_switches(model, wall_model);
    let scattered = match neighbours {
        FluidNeighbours::Grid(_) => None,
        FluidNeighbours::Pairs(pairs) => Some(Scattered::Filtered {
            pairs,
            round: false,
        }),
        FluidNeighbours::FrozenPairs(pairs) => Some(Scattered::Filtered { pairs, round: true }),
        FluidNeighbours::Listed(listed) => Some(Scattered::Listed(listed)),
    };
    if let Some(pairs) = scattered {
        with_switches!(switches, scattered_sums(model, fluid, pairs, scatter));
    }
    let scatter = &*scatter;
    let body = model.gravity + model.body_force;
    acceleration
        .par_iter_mut()
        .zip(density_rate.par_iter_mut().zip(dissipation.par_iter_mut()))
        .enumerate()
        .with_min_len(256)
        .for_each_init(KeptBlock::new, |kept, (i, (a, (drho, dissipation)))| {
            let sums = match neighbours {
                FluidNeighbours::Grid(grid) => {
                    with_switches!(switches, fluid_sums(model, fluid, grid, kept, i))
                }
                _ => scatter.sums(i),
            };
            let walls = (wall_model, elements, wall_near);
            let op = operators_with(model, walls, fluid, &sums, i);
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
