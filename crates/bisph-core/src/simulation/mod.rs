//! A simulation: fluid, walls and the chosen models, advanced step by step by one of two
//! integrators: explicit velocity Verlet ([`verlet`]) or the semi-implicit midpoint scheme
//! of paper 1 ([`midpoint`]). Physics turns a state into rates; integrators only combine them.

mod anderson;
mod kept_lists;
mod leaving;
mod midpoint;
mod part;
mod part_state;
mod settings;
mod settle;
mod verlet;
mod wall_models;

pub use part_state::PartLayout;
pub use settings::{MidpointParams, SettleOutcome, SettleParams, SettleReport};
pub use wall_models::{UsawParams, WallModelChoice};

use crate::decomposition::ExactSum;
use crate::dim::Vector;
use crate::energy::{fluid_energy_sums, lowest_height, potential_above, EnergyBudget};
use crate::eos::Eos;
use crate::error::SimError;
use crate::forcing::{FluxControl, FluxHistory};
use crate::kernel::Wendland;
use crate::neighbours::{
    CandidateRows, CellGrid, ListedPairs, Listing, Nearby, PairBlocks, PairList, Periodicity,
};
use crate::particles::{Fluid, FluidState, PermuteScratch};
use crate::probes::Probe;
use crate::terms::{
    compute_rates, pair_listing, particle_operators, DensityDiffusion, DiffusionForm,
    DissipationRates, FluidNeighbours, RateModel, ScatterBuffers, Viscosity,
};
use crate::walls::clearance::WallClearance;
use crate::walls::energy_bi::ListedEnergyWalls;
use crate::walls::shepard::{Shepard, ShepardKind, WallContinuity};
use crate::walls::usaw::Vertices;
use crate::walls::{BoundaryElements, WallModel, Walls};
use part_state::{BadParticle, Fault, HaloFields, Part};
use rayon::prelude::*;
use std::time::Instant;
use wall_models::{WallModelInputs, WallModelTask};

/// Which density diffusion the continuity equation carries (off when its coefficient is 0).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum DiffusionChoice {
    /// delta-SPH with coefficient `delta` ([`SimConfig::delta`]). The default.
    #[default]
    Delta,
    /// Mayrhofer's volume diffusion, paper 3 eqs 44 and 48: `K = c0 dx / eta`.
    Mayrhofer {
        /// `eta` of eq 48 (`O(10)-O(100)`).
        eta: f64,
    },
    /// Ferrari's Riemann form, paper 3 eqs 49-51, times `coefficient` (1 = as printed).
    Ferrari {
        /// Multiplier of the term.
        coefficient: f64,
    },
}

/// Wall-clock seconds spent in each phase of the time loop (summed over steps), and how
/// often the Verlet list was built.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Neighbour search: cell grid rebuilds, reordering included.
    pub neighbours: f64,
    /// Of which reordering the particles by cell.
    pub reorder: f64,
    /// Of which, in a decomposed run, handing particles to other parts and selecting the halo.
    pub handover: f64,
    /// Rate evaluations: equation of state, fluid and wall terms, wall pressures.
    pub rates: f64,
    /// Of which the wall pressures (extrapolation to the elements before the sweep).
    pub wall_pressure: f64,
    /// Whole steps (so integration = steps - neighbours - rates).
    pub steps: f64,
    /// Verlet list builds.
    pub list_builds: u64,
    /// Steps that kept the Verlet lists with some particles moved past half the skin
    /// ([`Simulation::lists_hold`]).
    pub lists_kept_moved: u64,
}

/// Time integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integrator {
    /// Explicit velocity Verlet, one rate evaluation per step.
    Verlet,
    /// Semi-implicit midpoint with fixed-point iterations (paper 1).
    Midpoint(MidpointParams),
}

/// Parameters of a simulation.
#[derive(Clone, Debug)]
pub struct SimConfig<V: Vector> {
    /// The kernel (its `h` sets the support `2h`).
    pub kernel: Wendland,
    /// Equation of state.
    pub eos: Eos,
    /// Gravity.
    pub gravity: V,
    /// delta-SPH coefficient `delta` (0 = off).
    pub delta: f64,
    /// Use the hydrostatic correction in delta-SPH.
    pub delta_hydrostatic: bool,
    /// Courant number `Co`: `dt = Co min(h / c0, sqrt(h / max|a|))`.
    pub courant: f64,
    /// Fixed time step (overrides the Courant rule).
    pub fixed_dt: Option<f64>,
    /// Smallest allowed time step (the run stops below it).
    pub min_dt: f64,
    /// Lower corner of the domain; a particle outside it is removed, or stops the run
    /// ([`SimConfig::max_removed`]).
    pub domain_min: V,
    /// Upper corner of the domain.
    pub domain_max: V,
    /// Most particles the run may lose through the domain's bounds: each is removed as it
    /// leaves ([`Simulation::removed`]), and one more stops the run (0: the first stops it).
    pub max_removed: u64,
    /// Wall model.
    pub wall_model: WallModelChoice,
    /// Time integrator.
    pub integrator: Integrator,
    /// Reorder particles into the cell grid's storage order (rows of cells along a Morton
    /// curve) every this many steps (0 = never).
    pub reorder_interval: u64,
    /// Skin of the neighbour list kept across steps, as a fraction of the kernel support
    /// (0 = search the cell grid at every step): the pairs within `support (1 + skin)` are
    /// listed, each once, and kept until a particle has moved half the skin, or longer while
    /// few have and none has met a partner the list lacks ([`Simulation::lists_hold`],
    /// [`crate::neighbours::PairBlocks`]); the particles are reordered only when it is
    /// rebuilt. The explicit scheme sweeps the pairs; the midpoint scheme lists them with
    /// their kernel gradients for a step. Not used when the list would exceed
    /// [`CANDIDATE_LIST_BUDGET`].
    pub neighbour_skin: f64,
    /// Most bytes the listed pairs of a midpoint step (fluid pairs, and particle-element
    /// pairs for the energy-conserving walls) may take; larger runs filter the Verlet list's
    /// pairs, and search the wall elements, at every iteration instead. The lists repeat
    /// those sweeps in their order and bits, so results do not depend on it, only the time.
    pub pair_list_budget: usize,
    /// Reflect particles about to cross a wall ([`crate::walls::bounce`]).
    pub elastic_bounce: bool,
    /// Periodic axes (the period along an axis is the domain's extent there).
    pub periodicity: Periodicity<V>,
    /// Laminar viscosity (paper 3 eqs 18-20; off when `nu = 0`).
    pub viscosity: Viscosity,
    /// A driving force imposing a volume flux (paper 3, section 5).
    pub flux: Option<FluxControl<V>>,
    /// Density diffusion form (its hydrostatic correction is [`SimConfig::delta_hydrostatic`]).
    pub diffusion: DiffusionChoice,
    /// Initial particle spacing `dx` (vertex volumes, `K = c0 dx / eta`).
    pub particle_spacing: f64,
}

/// Scratch buffers reused every step.
#[derive(Debug, Default)]
struct Scratch<V> {
    velocity: Vec<V>,
    density: Vec<f64>,
    volume: Vec<f64>,
    dissipation: Vec<DissipationRates>,
    lost_energy: Vec<f64>,
    previous_acceleration: Vec<V>,
    previous_density_rate: Vec<f64>,
    /// The history of the midpoint iterations of the current step.
    anderson: anderson::Anderson<V>,
    drift_velocity: Vec<V>,
    permute: PermuteScratch<V>,
    /// The fluid pairs of the current positions, with kernel gradient factors or gradients
    /// ([`pair_listing`]), while `pairs_listed` (inside a midpoint step, see
    /// [`Simulation::list_pairs`]).
    pairs: ListedPairs<V>,
    pairs_listed: bool,
    /// The positions are frozen (inside a midpoint step) and the Verlet list holds the pairs
    /// within the support at them (see [`Simulation::list_pairs`]).
    pairs_frozen: bool,
    /// The particle-element and element-particle pairs of the current positions with the
    /// kernel values, while `wall_pairs_listed` (energy-conserving walls inside a midpoint
    /// step, see [`Simulation::list_pairs`]).
    particle_elements: PairList<V>,
    element_particles: PairList<V>,
    wall_pairs_listed: bool,
    /// The Verlet list (see [`SimConfig::neighbour_skin`]), valid while `candidates_valid`
    /// and [`Simulation::lists_hold`].
    candidates: PairBlocks<V>,
    /// The particles that have moved more than half the skin since the list's build.
    moved: Vec<u32>,
    /// Some particle of the run (on any part) has.
    moved_anywhere: bool,
    /// The cell grid indexes the positions of the list's build (else the current ones).
    grid_at_build: bool,
    /// The buffers of a sweep over the Verlet list's or the listed pairs.
    scatter: ScatterBuffers<V>,
    candidates_valid: bool,
    /// The list was checked for the current positions: the next rate evaluation reads it.
    use_candidates: bool,
    /// Absolute skin length (0: no list).
    skin: f64,
    /// The wall elements near each own particle and the particles near each element, listed
    /// with the Verlet list at the same positions (fixed walls only, see
    /// [`Simulation::list_wall_candidates`]); valid while `wall_rows_valid` and the Verlet
    /// list is.
    particle_element_rows: CandidateRows<V>,
    element_particle_rows: CandidateRows<V>,
    wall_rows_valid: bool,
}

/// [`SimConfig::pair_list_budget`] where the memory of the machine is not known.
pub const PAIR_LIST_BUDGET: usize = 2 << 30;

/// Most bytes the Verlet list may take (4 per pair, each pair once); larger runs search the
/// cell grid at every step instead.
pub const CANDIDATE_LIST_BUDGET: usize = 8 << 30;

/// Estimated pairs within `radius` of `n` particles at the case's spacing (a lattice's count
/// plus 25%), for the list budgets.
fn listed_pairs<V: Vector>(config: &SimConfig<V>, n: usize, radius: f64) -> f64 {
    let r = radius / config.particle_spacing;
    let per_particle = if V::DIM == 2 {
        std::f64::consts::PI * r * r
    } else {
        4.0 / 3.0 * std::f64::consts::PI * r * r * r
    };
    1.25 * per_particle * n as f64
}

/// The state of a running simulation.
#[derive(Debug)]
pub struct Simulation<V: Vector> {
    /// Parameters.
    pub config: SimConfig<V>,
    /// Fluid particles.
    pub fluid: Fluid<V>,
    /// Walls and bodies.
    pub walls: Walls<V>,
    /// Vertex particles of the semi-analytical walls (paper 3, table 1; empty for the other
    /// models).
    pub vertices: Vertices<V>,
    /// Probes.
    pub probes: Vec<Probe<V>>,
    /// Current time.
    pub time: f64,
    /// Steps taken.
    pub step: u64,
    /// Size of the last step.
    pub last_dt: f64,
    /// Size of the step whose rates are in `fluid.earlier_acceleration` (0: none held).
    pub earlier_dt: f64,
    /// Size of the step whose rates are in `fluid.earliest_acceleration` (0: none held).
    pub earliest_dt: f64,
    /// Cumulative work of the fluid on walls, `int sum_j F_j . U_j dt`.
    pub wall_work: f64,
    /// Wall power at the last rate evaluation.
    pub wall_power: f64,
    /// Cumulative viscous dissipation `int sum_i -m_i u_i . a_i^visc dt`.
    pub viscous_dissipation: f64,
    /// Viscous dissipation rate at the last rate evaluation.
    pub viscous_power: f64,
    /// Cumulative compressible energy removed by the density diffusion,
    /// `int sum_i -m_i p_i D_i / rho_i^2 dt`.
    pub diffusion_dissipation: f64,
    /// Diffusion dissipation rate at the last rate evaluation.
    pub diffusion_power: f64,
    /// Cumulative work of the driving force, `int F . sum_i m_i u_i dt`.
    pub forcing_work: f64,
    /// Particles removed so far as they left the domain (over every part).
    pub removed: u64,
    /// Cumulative energy of the removed particles, `sum m (|u|^2 / 2 + e(rho) - g . r)` at
    /// their removal.
    pub removed_energy: f64,
    /// Current driving acceleration (zero without flux control).
    pub body_force: V,
    /// The flux controller's memory (bulk velocities and last force).
    pub flux_history: FluxHistory,
    /// Fixed-point iterations of the last midpoint step (1 for Verlet).
    pub last_iterations: u32,
    /// Final energy residue (paper 1, eq 53) of the last midpoint step (0 for Verlet).
    pub last_residue: f64,
    /// Cell grid over the fluid particles.
    pub fluid_grid: CellGrid<V>,
    /// Lower bounds of the particles' distances to the walls, kept with the Verlet list.
    wall_clearance: WallClearance<V>,
    /// Wall-clock seconds spent per phase since the start.
    pub timings: PhaseTimes,
    scratch: Scratch<V>,
    /// What makes this simulation one part of a decomposed run (`None`: the whole run).
    part: Option<Part<V>>,
}

impl<V: Vector> Simulation<V> {
    /// Sets up a simulation and evaluates the rates at time zero.
    ///
    /// # Panics
    /// When a period of `config.periodicity` holds fewer than three kernel supports (check it
    /// first with [`CellGrid::with_period`]).
    pub fn new(
        config: SimConfig<V>,
        fluid: Fluid<V>,
        walls: Walls<V>,
        probes: Vec<Probe<V>>,
    ) -> Self {
        let cell = config.kernel.support;
        // The Verlet list needs fluid cells of the listing radius (when every period can
        // hold three of them).
        let skin = cell * config.neighbour_skin;
        let list_bytes = 2.0 * listed_pairs(&config, fluid.len(), cell + skin);
        let skin = if skin > 0.0 && list_bytes <= CANDIDATE_LIST_BUDGET as f64 {
            skin
        } else {
            0.0
        };
        let fluid_grid = CellGrid::with_period(cell + skin, config.periodicity);
        let (skin, fluid_grid) = match fluid_grid {
            Ok(grid) if skin > 0.0 => (skin, Some(grid)),
            _ => (0.0, None),
        };
        let mut sim = Simulation {
            config,
            fluid,
            walls,
            vertices: Vertices::default(),
            probes,
            time: 0.0,
            step: 0,
            last_dt: 0.0,
            earlier_dt: 0.0,
            earliest_dt: 0.0,
            wall_work: 0.0,
            wall_power: 0.0,
            viscous_dissipation: 0.0,
            viscous_power: 0.0,
            diffusion_dissipation: 0.0,
            diffusion_power: 0.0,
            forcing_work: 0.0,
            removed: 0,
            removed_energy: 0.0,
            body_force: V::ZERO,
            flux_history: FluxHistory::default(),
            last_iterations: 0,
            last_residue: 0.0,
            fluid_grid: CellGrid::new(cell),
            wall_clearance: WallClearance::default(),
            timings: PhaseTimes::default(),
            scratch: Scratch::default(),
            part: None,
        };
        let period = sim.config.periodicity;
        let grid = CellGrid::with_period(cell, period)
            .expect("periods must hold three kernel supports (checked by the caller)");
        sim.fluid_grid = fluid_grid.unwrap_or_else(|| grid.clone());
        sim.scratch.skin = skin;
        // One cell around a particle holds every element its wall terms reach, and every
        // element the Verlet list lists for it (that reach plus the skin).
        sim.walls.grid = CellGrid::with_period(sim.wall_reach() + skin, period).unwrap_or(grid);
        sim.walls.periodicity = period;
        sim.walls.wrap_elements();
        sim.wrap_positions();
        sim.walls.grid.rebuild(&sim.walls.elements.centre);
        sim.walls.move_to(0.0);
        if sim.uses_geometric_gamma() {
            sim.walls.prepare_gamma(cell);
        }
        if sim.config.wall_model.has_vertex_particles() {
            sim.vertices = Vertices::from_elements(
                &sim.walls.elements,
                sim.config.eos.rho0(),
                cell,
                sim.config.particle_spacing,
                period,
            )
            .unwrap_or_default();
        }
        sim.rebuild_grid(true);
        if sim.config.wall_model.needs_gamma() {
            sim.geometric_gamma();
        }
        if sim.summation() {
            // C_i = gamma_i rho_i - sum_P m_j W_ij: the initial densities are kept.
            let sums = sim.kernel_sums();
            let f = &mut sim.fluid;
            for (i, s) in sums.iter().enumerate() {
                f.density_offset[i] = f.gamma[i] * f.density[i] - s;
            }
        }
        sim.scratch.velocity = sim.fluid.velocity.clone();
        sim.scratch.density = sim.fluid.density.clone();
        sim.evaluate_rates();
        sim.store_body_accelerations(true);
        sim.refresh_pressure();
        let bulk = sim.bulk_velocity();
        sim.flux_history = FluxHistory {
            last: bulk,
            before_last: bulk,
            force: 0.0,
        };
        sim
    }

    /// A simulation holding `fluid` in the state of `whole`, with no neighbour list (the
    /// start of [`Simulation::part_of`]).
    fn new_part(whole: &Simulation<V>, fluid: Fluid<V>) -> Self {
        Simulation {
            config: whole.config.clone(),
            fluid,
            walls: whole.walls.clone(),
            vertices: whole.vertices.clone(),
            probes: whole.probes.clone(),
            time: whole.time,
            step: whole.step,
            last_dt: whole.last_dt,
            earlier_dt: whole.earlier_dt,
            earliest_dt: whole.earliest_dt,
            wall_work: whole.wall_work,
            wall_power: whole.wall_power,
            viscous_dissipation: whole.viscous_dissipation,
            viscous_power: whole.viscous_power,
            diffusion_dissipation: whole.diffusion_dissipation,
            diffusion_power: whole.diffusion_power,
            forcing_work: whole.forcing_work,
            removed: whole.removed,
            removed_energy: whole.removed_energy,
            body_force: whole.body_force,
            flux_history: whole.flux_history,
            last_iterations: whole.last_iterations,
            last_residue: whole.last_residue,
            fluid_grid: whole.fluid_grid.clone(),
            wall_clearance: WallClearance::default(),
            timings: PhaseTimes::default(),
            scratch: Scratch {
                skin: whole.scratch.skin,
                ..Scratch::default()
            },
            part: None,
        }
    }

    /// Bulk velocity over the flux controller's slice (paper 3 eqs 56-57; 0 without one),
    /// summed exactly.
    pub fn bulk_velocity(&self) -> f64 {
        let Some(flux) = &self.config.flux else {
            return 0.0;
        };
        let f = &self.fluid;
        let mut sum = [flux.flux_sum(
            &f.position[..self.owned_len()],
            &f.velocity,
            &f.mass,
            &f.density,
            &self.config.periodicity,
        )];
        self.sum_over_parts(&mut sum);
        flux.bulk_velocity_of(sum[0].value())
    }

    /// Total momentum `sum_i m_i u_i`, summed exactly (the same bits for any thread count,
    /// memory order and decomposition).
    pub fn momentum(&self) -> V {
        let f = &self.fluid;
        let mut sums: Vec<ExactSum> = (0..V::DIM)
            .map(|k| {
                crate::energy::exact_partial_sum(self.owned_len(), |i| {
                    f.mass[i] * f.velocity[i].get(k)
                })
            })
            .collect();
        self.sum_over_parts(&mut sums);
        V::from_slice(&sums.iter().map(ExactSum::value).collect::<Vec<_>>())
    }

    /// Sets the driving acceleration of the coming step of size `dt` (eq 58 or 63), moving
    /// the stored accelerations along with it.
    fn update_flux_force(&mut self, dt: f64) {
        let Some(flux) = self.config.flux else {
            return;
        };
        let force = flux.next_force(&self.flux_history, dt);
        let new = flux.direction * force;
        let change = new - self.body_force;
        self.fluid
            .acceleration
            .par_iter_mut()
            .for_each(|a| *a += change);
        self.body_force = new;
        self.flux_history.force = force;
    }

    /// Fills the evaluation state (scratch velocities and densities) with
    /// `u + tau a`, `rho + tau rhodot` from the stored state and rates.
    pub(crate) fn stage_state(&mut self, tau: f64) {
        let (f, s) = (&self.fluid, &mut self.scratch);
        s.velocity.resize(f.len(), V::ZERO);
        s.velocity
            .par_iter_mut()
            .zip(f.velocity.par_iter().zip(f.acceleration.par_iter()))
            .with_min_len(4096)
            .for_each(|(staged, (&u, &a))| *staged = u + a * tau);
        s.density.resize(f.len(), 0.0);
        s.density
            .par_iter_mut()
            .zip(f.density.par_iter().zip(f.density_rate.par_iter()))
            .with_min_len(4096)
            .for_each(|(staged, (&rho, &d))| *staged = rho + d * tau);
    }

    /// Sets every particle's gamma to the geometric Shepard factor (paper 2) and its
    /// `grad gamma` (paper 3, eq 10) at the current positions ([`Shepard::initialise`]).
    pub fn geometric_gamma(&mut self) {
        let f = &mut self.fluid;
        Shepard::initialise(
            &self.config.kernel,
            &self.walls.elements,
            &self.walls.grid,
            &f.position,
            &mut f.gamma,
            &mut f.grad_gamma,
        );
    }

    /// Which gamma the particles carry, if any.
    pub(crate) fn carried_gamma(&self) -> Option<ShepardKind> {
        let shepard = self.config.wall_model.shepard();
        shepard.filter(Shepard::carried).map(|s| s.kind)
    }

    /// Sets the gamma the particles carry to the geometric value where they and the walls now
    /// are, when that is the gamma they carry (the other models keep theirs).
    pub fn place_geometric_gamma(&mut self) {
        if self.carried_gamma() == Some(ShepardKind::Geometric) {
            self.geometric_gamma();
        }
    }

    /// Advances gamma after a drift by `dt` with the current velocities (see [`advance_gamma`]),
    /// with the walls' part of the continuity equation when the drift integrates it
    /// ([`Simulation::wall_continuity_in_drift`]).
    pub(crate) fn advance_gamma(&mut self, dt: f64) {
        let in_drift = self.wall_continuity_in_drift();
        let rest = self.config.eos.rho0();
        let f = &mut self.fluid;
        advance_gamma(
            &self.config,
            &self.walls,
            &mut f.gamma,
            &mut f.grad_gamma,
            &f.position,
            &f.velocity,
            dt,
            in_drift.then_some(WallContinuity {
                density: &mut f.density,
                rest,
            }),
        );
    }

    /// `true` when the explicit integrator takes the walls' part of the continuity equation
    /// out of the rates and integrates it exactly over each drift, `rho *= gamma^n /
    /// gamma^{n+1}` ([`Shepard::advance`]): under velocity Verlet, the classic boundary
    /// integrals whose wall term is `-rho dln(gamma)/dt`
    /// ([`WallModelChoice::wall_divergence_is_gamma_rate`]). Taken from the rates instead, the
    /// exchange it drives between a particle's density and its velocity across a wall, of
    /// frequency `sqrt(2) c0 |grad gamma| / gamma` (about `6 c0 / h` in a concave edge), would
    /// grow under the explicit scheme's predictor.
    pub(crate) fn wall_continuity_in_drift(&self) -> bool {
        self.config.integrator == Integrator::Verlet
            && self.config.wall_model.wall_divergence_is_gamma_rate()
    }

    /// `true` when some term evaluates the geometric Shepard factor during the run: the
    /// geometric renormalisation, gamma of the semi-analytical or integrated walls, or the
    /// viscous Laplacian of the other models (paper 3, eq 18).
    fn uses_geometric_gamma(&self) -> bool {
        self.config.wall_model.evaluates_geometric_gamma() || self.config.viscosity.active()
    }

    /// `true` when the densities come from summation (paper 3, eq 84).
    pub(crate) fn summation(&self) -> bool {
        self.config.wall_model.summation_density()
    }

    /// `sum_P m_j W_ij` over fluid and vertex particles at the current positions, for the own
    /// particles.
    fn kernel_sums(&self) -> Vec<f64> {
        let kernel = self.config.kernel;
        let (f, v, grid) = (&self.fluid, &self.vertices, &self.fluid_grid);
        (0..self.owned_len())
            .into_par_iter()
            .map(|i| {
                let x = f.position[i];
                let mut s = 0.0;
                grid.for_each_neighbour(x, &f.position, kernel.support, |j, _, r| {
                    s += f.mass[j] * kernel.value(r);
                });
                v.grid
                    .for_each_neighbour(x, &v.position, kernel.support, |j, _, r| {
                        s += v.mass[j] * kernel.value(r);
                    });
                s
            })
            .collect()
    }

    /// Paper 3, eq 84, after a drift by `dt`: `C_i += dt gamma_i D_i` with the diffusion rate
    /// `D_i` of the last evaluation (held in `density_rate`), then
    /// `rho_i = (sum_P m_j W_ij + C_i) / gamma_i` at the new positions; the density rates are
    /// cleared so the staged state uses these densities.
    pub(crate) fn summation_densities(&mut self, dt: f64) {
        let sums = self.kernel_sums();
        let f = &mut self.fluid;
        for i in 0..f.len() {
            f.density_offset[i] += dt * f.gamma[i] * f.density_rate[i];
            // The halo's sums are its owners' (copied below).
            let s = sums.get(i).copied().unwrap_or(0.0);
            f.density[i] = (s + f.density_offset[i]) / f.gamma[i];
            f.density_rate[i] = 0.0;
        }
        self.refresh_halo(HaloFields::Density);
    }

    /// Semi-analytical walls: vertex masses `m_v = rho_v V_v` from their current extrapolated
    /// densities (they were built with `rho0 V_v`), the counterpart of the fluid's `"initial"`
    /// mass rule for a fluid that starts compressed; then the summation offsets (eq 84) and
    /// the rates again. Call once, before the first step.
    pub fn vertex_masses_from_density(&mut self) {
        if !self.config.wall_model.has_vertex_particles() {
            return;
        }
        // The last rate evaluation extrapolated the vertex densities from the initial fluid.
        let rho0 = self.config.eos.rho0();
        let v = &mut self.vertices;
        for i in 0..v.len() {
            v.mass[i] *= v.density[i] / rho0;
            v.volume[i] = v.mass[i] / v.density[i];
        }
        if self.summation() {
            let sums = self.kernel_sums();
            let f = &mut self.fluid;
            for (i, s) in sums.iter().enumerate() {
                f.density_offset[i] = f.gamma[i] * f.density[i] - s;
            }
        }
        self.refresh_rates();
    }

    /// Re-evaluates the rates at the stored state (after editing velocities or densities by
    /// hand, e.g. to set an initial velocity field).
    pub fn refresh_rates(&mut self) {
        self.earlier_dt = 0.0;
        self.earliest_dt = 0.0;
        self.stage_state(0.0);
        self.evaluate_rates();
        self.store_body_accelerations(true);
        self.refresh_pressure();
    }

    /// Stores the dynamic bodies' accelerations from the wall pressures of the last rate evaluation
    /// (staggered free bodies only when `all`).
    pub(crate) fn store_body_accelerations(&mut self, all: bool) {
        let acc = self.body_accelerations(all);
        self.walls.set_dynamic_accelerations(&acc);
    }

    /// Dynamic bodies' accelerations from the wall pressures of the last rate evaluation
    /// ([`Walls::body_accelerations`]; staggered free bodies keep theirs unless `all`).
    pub(crate) fn body_accelerations(&self, all: bool) -> Vec<f64> {
        if !self.walls.has_dynamic_bodies() {
            return Vec::new();
        }
        self.walls.body_accelerations(all, &self.body_loads())
    }

    /// Pressure force and torque on each body (see [`Walls::body_loads`]) at the current wall
    /// pressures, summed over the elements of every part.
    pub fn body_loads(&self) -> Vec<(V, V::Angular)> {
        let t = self.walls.placed_at;
        let mut sums = self.walls.body_load_sums(t, self.element_counter());
        self.sum_over_parts(&mut sums);
        self.walls.loads_of_sums(&sums)
    }

    /// The rate model handed to the sweep.
    pub fn rate_model(&self) -> RateModel<V> {
        let c = &self.config;
        let c0 = c.eos.c0();
        let hydrostatic_gradient = if c.delta_hydrostatic {
            c.gravity * (c.eos.rho0() / (c0 * c0))
        } else {
            V::ZERO
        };
        let (scale, form) = match c.diffusion {
            DiffusionChoice::Delta => (c.delta * c.kernel.h * c0, DiffusionForm::Laplacian),
            DiffusionChoice::Mayrhofer { eta } => {
                (c0 * c.particle_spacing / eta, DiffusionForm::Laplacian)
            }
            DiffusionChoice::Ferrari { coefficient } => {
                (coefficient, DiffusionForm::Riemann(c.eos))
            }
        };
        RateModel {
            kernel: c.kernel,
            gravity: c.gravity,
            diffusion: DensityDiffusion {
                scale,
                hydrostatic_gradient,
                eos: c.eos,
                form,
            },
            viscosity: c.viscosity,
            body_force: self.body_force,
            density_power: c.wall_model.density_power(),
            summation_density: self.summation(),
            wall_continuity_in_drift: self.wall_continuity_in_drift(),
        }
    }

    /// Brings every particle back into the primary period along the periodic axes.
    pub(crate) fn wrap_positions(&mut self) {
        let period = self.config.periodicity;
        if period.any() {
            self.fluid
                .position
                .par_iter_mut()
                .for_each(|r| *r = period.wrap(*r));
        }
    }

    /// Places the moving walls at the current time; the wall-distance bounds follow them.
    pub(crate) fn move_walls(&mut self) {
        self.walls.move_to(self.time);
        self.wall_clearance.follow(&self.walls);
    }

    pub(crate) fn rebuild_grid(&mut self, reorder: bool) {
        let start = Instant::now();
        self.scratch.candidates_valid = false;
        self.wall_clearance.forget();
        self.fluid_grid
            .rebuild_keyed(&self.fluid.position, &self.fluid.id);
        if reorder {
            let sorted = Instant::now();
            // Into the grid's storage order: the grid stays valid, its slots now contiguous.
            self.fluid
                .permute(self.fluid_grid.sorted_items(), &mut self.scratch.permute);
            self.fluid_grid.mark_reordered();
            self.timings.reorder += sorted.elapsed().as_secs_f64();
        }
        self.timings.neighbours += start.elapsed().as_secs_f64();
    }

    /// The neighbour data of a step at the current positions: with a skin
    /// ([`SimConfig::neighbour_skin`]), the Verlet list is kept while it holds
    /// ([`Simulation::lists_hold`], which places the cell grid), else the grid is rebuilt
    /// (the particles reordered when `reorder_interval` > 0) and the list with it. Without a
    /// skin, the grid is rebuilt (reordered every `reorder_interval` steps).
    pub(crate) fn step_neighbours(&mut self) {
        let interval = self.config.reorder_interval;
        let skin = self.scratch.skin;
        if skin <= 0.0 {
            let reorder = interval > 0 && self.step.is_multiple_of(interval);
            self.rebuild_neighbours(reorder);
            return;
        }
        let start = Instant::now();
        let holds = self.lists_hold();
        if self.on_all_parts(holds) {
            self.scratch.use_candidates = true;
            self.timings.lists_kept_moved += u64::from(self.scratch.moved_anywhere);
            self.timings.neighbours += start.elapsed().as_secs_f64();
            return;
        }
        self.rebuild_neighbours(interval > 0);
        let start = Instant::now();
        let radius = self.config.kernel.support + skin;
        // A part lists its own particles' candidates: the halo takes the owners' rates.
        let queries = self.owned_len();
        self.scratch
            .candidates
            .rebuild(&self.fluid_grid, &self.fluid.position, queries, radius);
        self.scratch.candidates_valid = true;
        self.scratch.grid_at_build = true;
        self.scratch.use_candidates = true;
        self.timings.list_builds += 1;
        self.list_wall_candidates(None);
        self.measure_wall_clearance(None);
        self.timings.neighbours += start.elapsed().as_secs_f64();
    }

    /// Rebuilds the cell grid, the particles reordered by it when `reorder`; a part first
    /// hands the particles that left its region to their owners and selects its halo again
    /// ([`Simulation::repartition`]).
    fn rebuild_neighbours(&mut self, reorder: bool) {
        if self.part.is_some() {
            let start = Instant::now();
            self.repartition(reorder);
            let seconds = start.elapsed().as_secs_f64();
            self.timings.neighbours += seconds;
            self.timings.handover += seconds;
            self.rebuild_grid(false);
        } else {
            self.rebuild_grid(reorder);
        }
    }

    /// Lists, beside the Verlet list, the wall elements within the walls' reach plus the skin
    /// of each own particle and the particles within the support plus the skin of each
    /// element, at the positions `origin` of the list's build (the current positions when
    /// `None`): the wall terms and wall pressures then filter these instead of searching the
    /// grids. Only for the boundary-integral walls, and only where the walls are fixed (the
    /// list's check follows the particles alone).
    fn list_wall_candidates(&mut self, origin: Option<&[V]>) {
        let reach = self.wall_reach();
        let owned = self.owned_len();
        let s = &mut self.scratch;
        s.wall_rows_valid = false;
        let walls = &self.walls;
        // A period too short for three cells of that width keeps cells of one support.
        if self.config.wall_model.has_vertex_particles()
            || walls.elements.is_empty()
            || walls.has_moving_bodies()
            || walls.grid.cell_size() < reach + s.skin
        {
            return;
        }
        let position = origin.unwrap_or(&self.fluid.position);
        let centres = &walls.elements.centre;
        s.particle_element_rows
            .rebuild(&walls.grid, &position[..owned], centres, reach, s.skin);
        let support = self.config.kernel.support;
        s.element_particle_rows
            .rebuild(&self.fluid_grid, centres, position, support, s.skin);
        s.wall_rows_valid = true;
    }

    /// Measures the particles' wall-distance bounds ([`WallClearance::measure`]) at the
    /// positions `origin` of the list's build (the current positions when `None`), from the
    /// wall candidate rows where they were listed there.
    fn measure_wall_clearance(&mut self, origin: Option<&[V]>) {
        let s = &self.scratch;
        let rows = s.wall_rows_valid.then_some(&s.particle_element_rows);
        let points = origin.unwrap_or(&self.fluid.position);
        self.wall_clearance
            .measure(&self.walls, points, 0.5 * s.skin, rows);
    }

    /// The farthest an element's centre can lie from a particle and count in its wall terms:
    /// the support, plus the largest element reach where the `bi` walls integrate whole
    /// elements.
    fn wall_reach(&self) -> f64 {
        let support = self.config.kernel.support;
        match self.config.wall_model {
            WallModelChoice::ShepardBi(_, quadrature) => {
                quadrature.reach(support, self.walls.elements.max_reach)
            }
            WallModelChoice::Energy | WallModelChoice::Usaw(_) => support,
        }
    }

    /// Lower bounds of the particles' distances to the walls: with a Verlet list and walls
    /// that do not stretch, measured at its build and valid for the current positions of the
    /// particles and the walls; else none ([`WallClearance::clear`] answers `false`).
    pub fn wall_clearance(&self) -> &WallClearance<V> {
        &self.wall_clearance
    }

    /// The positions at which the Verlet list in use was built (`None`
    /// without a skin or before the first build). A checkpoint saves them so that a resumed
    /// run rebuilds the same list and keeps it for the same steps as an uninterrupted one.
    pub fn neighbour_list_origin(&self) -> Option<&[V]> {
        let s = &self.scratch;
        (s.skin > 0.0 && s.candidates_valid).then(|| s.candidates.origin())
    }

    /// Rebuilds the Verlet list from the positions `origin` it was built at (see
    /// [`Simulation::neighbour_list_origin`]; the particles in the order they had then, which
    /// is kept until the next build), checked at the current positions by the run that saved
    /// it, and the cell grid: over `origin`, or over the current positions where an axis is
    /// periodic or a particle has moved past half the skin (the next step places it as the run
    /// did, [`Simulation::lists_hold`]). Returns whether the list was restored: with `None`,
    /// without a skin, or when `origin` does not fit the particles (another length, not
    /// finite, or a particle farther than the drift limit from it, so the list could miss
    /// pairs), the list is dropped instead (the next step builds one) and the grid is built
    /// over the current positions.
    pub fn restore_neighbour_list(&mut self, origin: Option<&[V]>) -> bool {
        let skin = self.scratch.skin;
        let period = self.config.periodicity;
        let position = &self.fluid.position;
        let limit = self.drift_limit();
        let fits = |origin: &[V]| {
            origin.len() == position.len()
                && origin.iter().zip(position).all(|(&o, &p)| {
                    o.is_finite() && period.minimum_image(p - o).length_squared() <= limit * limit
                })
        };
        let Some(origin) = origin.filter(|o| skin > 0.0 && fits(o)) else {
            self.scratch.candidates_valid = false;
            self.wall_clearance.forget();
            self.fluid_grid
                .rebuild_keyed(&self.fluid.position, &self.fluid.id);
            return false;
        };
        self.fluid_grid.rebuild_keyed(origin, &self.fluid.id);
        let radius = self.config.kernel.support + skin;
        let queries = self.owned_len();
        self.scratch
            .candidates
            .rebuild(&self.fluid_grid, origin, queries, radius);
        self.scratch.candidates_valid = true;
        self.scratch.grid_at_build = true;
        self.list_wall_candidates(Some(origin));
        self.measure_wall_clearance(Some(origin));
        // The run had checked the list at these positions; the particles that have moved past
        // half the skin since the build have no wall-distance bounds, and the grid is over
        // the current positions where they are (the next step places it as the run did).
        let s = &mut self.scratch;
        s.use_candidates = true;
        s.candidates
            .moved_points(&self.fluid.position, 0.5 * skin, limit, &mut s.moved);
        self.wall_clearance.forget_points(&self.scratch.moved);
        if period.any() || !self.scratch.moved.is_empty() {
            self.fluid_grid
                .rebuild_keyed(&self.fluid.position, &self.fluid.id);
            self.scratch.grid_at_build = false;
        }
        true
    }

    /// Freezes the fluid pairs at the current positions for the rate evaluations until
    /// [`Simulation::forget_pairs`] (the iterations of a midpoint step, whose positions and
    /// grid are frozen): the Verlet list's pairs while it holds, else those within the
    /// support from the cell grid; listed with their offsets and kernel gradient factors, or
    /// their kernel gradients alone in single precision ([`Listing::Product`]), unless the
    /// listed pairs would take more than [`SimConfig::pair_list_budget`] bytes (estimated from
    /// the particle spacing, 25% over a lattice), filtered at each evaluation otherwise
    /// ([`FluidNeighbours::FrozenPairs`]), with the same bits.
    pub(crate) fn list_pairs(&mut self) {
        let start = Instant::now();
        let kernel = self.config.kernel;
        let owned = self.owned_len();
        let position = &self.fluid.position;
        let s = &mut self.scratch;
        // The list was checked at these positions by the step's neighbour search.
        if !(s.skin > 0.0 && s.candidates_valid && s.use_candidates) {
            // The own particles' pairs: the halo takes its rates from the owners.
            s.candidates_valid = false;
            s.candidates
                .rebuild(&self.fluid_grid, position, owned, kernel.support);
        }
        s.pairs_frozen = true;
        let inputs = WallModelInputs {
            gravity: self.config.gravity,
            vertices: &self.vertices,
            listed: None,
        };
        let listing = self
            .config
            .wall_model
            .run(inputs, PairListing(&self.rate_model()));
        // Each pair once.
        let bytes = 0.5
            * listed_pairs(&self.config, self.fluid.len(), kernel.support)
            * listing.pair_bytes::<V>() as f64;
        if !bytes.is_finite() || bytes > self.config.pair_list_budget as f64 {
            self.timings.neighbours += start.elapsed().as_secs_f64();
            return;
        }
        let factor = |r| kernel.gradient_factor(r);
        let s = &mut self.scratch;
        match listing {
            Listing::Product => s
                .candidates
                .list_kernel_gradients(position, &kernel, &mut s.pairs),
            Listing::OffsetAndFactor => {
                s.candidates
                    .list(position, kernel.support, factor, listing, &mut s.pairs)
            }
        }
        s.pairs_listed = true;
        // The energy-conserving walls' pairs (eqs 51-52 and 71): each pair is stored twice
        // (once per side); a wetted element sees at most half a kernel sphere of particles.
        let elements = self.walls.elements.len();
        let wall_bytes =
            listed_pairs(&self.config, elements, kernel.support) * PairList::<V>::PAIR_BYTES as f64;
        if matches!(self.config.wall_model, WallModelChoice::Energy)
            && elements > 0
            && bytes + wall_bytes <= self.config.pair_list_budget as f64
        {
            let s = &mut self.scratch;
            ListedEnergyWalls::rebuild(
                &kernel,
                &mut s.particle_elements,
                &mut s.element_particles,
                &self.walls.elements,
                &self.walls.grid,
                position,
                &self.fluid_grid,
            );
            s.wall_pairs_listed = true;
        }
        self.timings.neighbours += start.elapsed().as_secs_f64();
    }

    /// Rate evaluations search the neighbours again (call before the positions move).
    pub(crate) fn forget_pairs(&mut self) {
        self.scratch.pairs_frozen = false;
        self.scratch.pairs_listed = false;
        self.scratch.wall_pairs_listed = false;
    }

    /// Pressures from the stored densities.
    pub(crate) fn refresh_pressure(&mut self) {
        let eos = self.config.eos;
        self.fluid
            .pressure
            .par_iter_mut()
            .zip(self.fluid.density.par_iter())
            .for_each(|(p, &rho)| *p = eos.pressure(rho));
    }

    /// Rates at the positions in `fluid`, the velocities and densities in the scratch buffers;
    /// also refreshes the wall pressures and the wall power.
    pub(crate) fn evaluate_rates(&mut self) {
        let start = Instant::now();
        let eos = self.config.eos;
        let model = self.rate_model();
        // The halo takes its rates from the owners afterwards.
        let owned = self.owned_len();
        self.mark_elements_in_reach();
        // The wall candidates hold where the Verlet list they were listed with does.
        let s = &self.scratch;
        let wall_rows =
            s.wall_rows_valid && s.candidates_valid && (s.use_candidates || s.pairs_frozen);
        let Fluid {
            position,
            mass,
            pressure,
            acceleration,
            density_rate,
            gamma,
            ..
        } = &mut self.fluid;
        pressure
            .par_iter_mut()
            .zip(self.scratch.density.par_iter())
            .for_each(|(p, &rho)| *p = eos.pressure(rho));
        let volume = &mut self.scratch.volume;
        volume.resize(mass.len(), 0.0);
        let dissipation = &mut self.scratch.dissipation;
        dissipation.resize(mass.len(), DissipationRates::default());
        volume
            .par_iter_mut()
            .zip(mass.par_iter().zip(self.scratch.density.par_iter()))
            .for_each(|(v, (&m, &rho))| *v = m / rho);
        let state = FluidState {
            position,
            velocity: &self.scratch.velocity,
            density: &self.scratch.density,
            mass,
            pressure,
            volume,
            gamma,
        };
        let (grid, walls) = (&self.fluid_grid, &mut self.walls);
        let neighbours = if self.scratch.pairs_listed {
            FluidNeighbours::Listed(&self.scratch.pairs)
        } else if self.scratch.pairs_frozen {
            FluidNeighbours::FrozenPairs(&self.scratch.candidates)
        } else if self.scratch.use_candidates {
            FluidNeighbours::Pairs(&self.scratch.candidates)
        } else {
            FluidNeighbours::Grid(grid)
        };
        // The vertex values of the semi-analytical walls first (their pressures are the
        // segments' wall pressures).
        let vertex_start = Instant::now();
        if let WallModelChoice::Usaw(params) = self.config.wall_model {
            self.vertices.update(
                &model.kernel,
                &eos,
                model.gravity,
                params.interpolation,
                &state,
                grid,
            );
        }
        let vertex_seconds = vertex_start.elapsed().as_secs_f64();
        let Walls {
            elements,
            grid: wall_grid,
            ..
        } = walls;
        let inputs = WallModelInputs {
            gravity: model.gravity,
            vertices: &self.vertices,
            listed: self.scratch.wall_pairs_listed.then_some(ListedEnergyWalls {
                particle_elements: &self.scratch.particle_elements,
                element_particles: &self.scratch.element_particles,
            }),
        };
        let sweep = Sweep {
            model: &model,
            state: &state,
            fluid_near: Nearby {
                grid,
                listed: wall_rows.then_some(&self.scratch.element_particle_rows),
            },
            neighbours,
            elements,
            wall_near: Nearby {
                grid: wall_grid,
                listed: wall_rows.then_some(&self.scratch.particle_element_rows),
            },
            acceleration: &mut acceleration[..owned],
            density_rate: &mut density_rate[..owned],
            dissipation: &mut dissipation[..owned],
            scatter: &mut self.scratch.scatter,
        };
        self.timings.wall_pressure += vertex_seconds + self.config.wall_model.run(inputs, sweep);
        let d = &self.scratch.dissipation;
        self.viscous_power = if model.viscosity.active() {
            self.sum_owned(|i| d[i].viscous)
        } else {
            0.0
        };
        self.diffusion_power = if model.diffusion.scale != 0.0 {
            self.sum_owned(|i| d[i].diffusion)
        } else {
            0.0
        };
        let mut power = [self.walls.power_sum(self.element_counter())];
        self.sum_over_parts(&mut power);
        self.wall_power = power[0].value();
        // The list was checked for these positions only.
        self.scratch.use_candidates = false;
        self.refresh_halo(HaloFields::Rates);
        self.timings.rates += start.elapsed().as_secs_f64();
    }

    /// Skew-adjointness residual of the operators at the stored state (paper 3, eq 26, the
    /// summand of eq 39): `<Grad p, u> + <p, Div u> = sum_a V_a (u_a . Grad_a p + p_a Div_a u)`
    /// with the full (fluid + wall, renormalised) operators of the wall model in use. Zero
    /// for skew-adjoint operators; summed in particle order (thread-independent).
    pub fn skew_adjoint_residual(&mut self) -> f64 {
        self.scratch.velocity.clone_from(&self.fluid.velocity);
        self.scratch.density.clone_from(&self.fluid.density);
        // Refresh pressures, volumes and wall values at the stored state.
        let saved = (
            self.fluid.acceleration.clone(),
            self.fluid.density_rate.clone(),
        );
        let wall_power = self.wall_power;
        self.evaluate_rates();
        self.fluid.acceleration = saved.0;
        self.fluid.density_rate = saved.1;
        self.wall_power = wall_power;
        // The full operators, the walls' divergence included.
        let model = RateModel {
            wall_continuity_in_drift: false,
            ..self.rate_model()
        };
        let f = &self.fluid;
        let state = FluidState {
            position: &f.position,
            velocity: &f.velocity,
            density: &f.density,
            mass: &f.mass,
            pressure: &f.pressure,
            volume: &self.scratch.volume,
            gamma: &f.gamma,
        };
        let walls = &self.walls;
        let inputs = WallModelInputs {
            gravity: model.gravity,
            vertices: &self.vertices,
            listed: None,
        };
        let residual = SkewResidual {
            model: &model,
            state: &state,
            fluid_grid: &self.fluid_grid,
            elements: &walls.elements,
            wall_grid: &walls.grid,
        };
        let terms = self.config.wall_model.run(inputs, residual);
        terms.iter().sum()
    }

    /// Time step for the next step: fixed, or `Co min(h / c0, sqrt(h / max|a|))`.
    pub fn next_dt(&self) -> f64 {
        if let Some(dt) = self.config.fixed_dt {
            return dt;
        }
        let h = self.config.kernel.h;
        let a_max = self.max_acceleration();
        let mut dt = h / self.config.eos.c0();
        if a_max > 0.0 {
            dt = dt.min((h / a_max).sqrt());
        }
        dt *= self.config.courant;
        let nu = self.config.viscosity.nu;
        if nu > 0.0 {
            // Viscous diffusion limit (Morris et al. 1997).
            dt = dt.min(0.125 * h * h / nu);
        }
        dt
    }

    /// Advances one step of size `next_dt()` (never past `t_end` when given).
    pub fn advance(&mut self, t_end: Option<f64>) -> Result<(), SimError> {
        let mut dt = self.next_dt();
        if let Some(end) = t_end {
            if self.time + dt > end && end > self.time {
                dt = end - self.time;
            }
        }
        if dt.is_nan() || dt < self.config.min_dt {
            return Err(SimError::TimeStepCollapse {
                dt,
                step: self.step,
                time: self.time,
            });
        }
        let start = Instant::now();
        let forced = self.config.flux.is_some();
        self.update_flux_force(dt);
        let momentum_before = if forced { self.momentum() } else { V::ZERO };
        match self.config.integrator {
            Integrator::Verlet => self.verlet_step(dt)?,
            Integrator::Midpoint(params) => self.midpoint_step(dt, &params)?,
        }
        if forced {
            // A uniform force changes the kinetic energy by exactly F . (P^n + P^{n+1}) dt / 2.
            let momentum_after = self.momentum();
            self.forcing_work += 0.5 * dt * self.body_force.dot(momentum_before + momentum_after);
        }
        if self.config.flux.is_some() {
            let bulk = self.bulk_velocity();
            self.flux_history.before_last = self.flux_history.last;
            self.flux_history.last = bulk;
        }
        self.timings.steps += start.elapsed().as_secs_f64();
        self.check_state()
    }

    /// Removes the particles that left the domain while the run may still lose them
    /// ([`Simulation::remove_leaving`]), then stops on the particle with the lowest id, over
    /// every part, whose state is not finite or which left the domain.
    fn check_state(&mut self) -> Result<(), SimError> {
        let mut bad = self.first_bad_over_parts(self.first_bad_particle());
        if bad.is_some_and(|b| b.fault() == Fault::Outside) && self.remove_leaving() {
            bad = self.first_bad_over_parts(self.first_bad_particle());
        }
        match bad {
            Some(bad) => Err(bad.error(self.step, self.time)),
            None => Ok(()),
        }
    }

    /// What is wrong with particle `i`, in the order the checks look: a non-finite state,
    /// then a place outside the domain (`None`: nothing).
    pub(crate) fn fault(&self, i: usize) -> Option<Fault> {
        let f = &self.fluid;
        let r = f.position[i];
        if !r.is_finite() {
            Some(Fault::Position)
        } else if !f.velocity[i].is_finite() {
            Some(Fault::Velocity)
        } else if !(f.density[i].is_finite() && f.density[i] > 0.0) {
            Some(Fault::Density)
        } else if self.outside_domain(r) {
            Some(Fault::Outside)
        } else {
            None
        }
    }

    /// Of the own particles with a non-finite state or outside the domain, the one with the
    /// lowest id.
    fn first_bad_particle(&self) -> Option<BadParticle> {
        let f = &self.fluid;
        let bad = |i: usize| {
            let fault = self.fault(i)?;
            Some(BadParticle::new(f.id[i], fault, f.position[i].to_xyz()))
        };
        // Blocks scanned in parallel for any bad particle; all are then looked at in turn
        // (only when the run stops).
        const BLOCK: usize = 4096;
        let n = self.owned_len();
        let any = (0..n.div_ceil(BLOCK))
            .into_par_iter()
            .any(|b| (b * BLOCK..((b + 1) * BLOCK).min(n)).any(|i| bad(i).is_some()));
        if !any {
            return None;
        }
        (0..n).filter_map(bad).min_by_key(|b| b.id())
    }

    /// The energy budget of the current state.
    pub fn energy(&self) -> EnergyBudget {
        let mut sums = fluid_energy_sums(
            &self.fluid,
            self.owned_len(),
            &self.config.eos,
            self.config.gravity,
        );
        self.sum_over_parts(&mut sums);
        let [kinetic, compressible, potential] = sums.map(|s| s.value());
        EnergyBudget {
            kinetic,
            compressible,
            potential,
            wall_work: self.wall_work,
            viscous_dissipation: self.viscous_dissipation,
            forcing_work: self.forcing_work,
            diffusion_dissipation: self.diffusion_dissipation,
            removed: self.removed_energy,
            total: kinetic
                + compressible
                + potential
                + self.wall_work
                + self.viscous_dissipation
                + self.diffusion_dissipation
                + self.removed_energy
                - self.forcing_work,
        }
    }

    /// Energy scale used to express drift: the kinetic and compressible energy plus the
    /// potential energy above the lowest particle, `sum m |g| (z_i - z_min)`, over every
    /// part.
    pub fn energy_scale(&self) -> f64 {
        let (f, gravity, n) = (&self.fluid, self.config.gravity, self.owned_len());
        let e = self.energy();
        let lowest = -self.max_over_parts(-lowest_height(f, n, gravity));
        let mut available = [potential_above(f, n, gravity, lowest)];
        self.sum_over_parts(&mut available);
        e.kinetic + e.compressible.abs() + available[0].value()
    }

    /// Total fluid mass, over every part.
    pub fn fluid_mass(&self) -> f64 {
        let mass = &self.fluid.mass;
        self.sum_owned(|i| mass[i])
    }

    /// Probe values for the current state. A probe is sampled by the part whose region holds
    /// it, or summed over the own particles of every part (heights).
    pub fn sample_probes(&self) -> Vec<f64> {
        let mut sums: Vec<ExactSum> = self
            .probes
            .iter()
            .map(|p| {
                let kernel = &self.config.kernel;
                p.sample_sum(
                    kernel,
                    &self.fluid,
                    self.owned_len(),
                    &self.fluid_grid,
                    |x| self.owns_point(x),
                )
            })
            .collect();
        self.sum_over_parts(&mut sums);
        sums.iter().map(ExactSum::value).collect()
    }

    /// Number of fluid-fluid pairs within the support (each particle counts its neighbours,
    /// itself included), over every part, for throughput figures.
    pub fn count_pairs(&self) -> u64 {
        let f = &self.fluid;
        let support = self.config.kernel.support;
        let own: u64 = (0..self.owned_len())
            .into_par_iter()
            .map(|i| {
                let mut n = 0u64;
                self.fluid_grid.for_each_neighbour(
                    f.position[i],
                    &f.position,
                    support,
                    |_, _, _| n += 1,
                );
                n
            })
            .sum();
        self.total_over_parts(own as f64) as u64
    }

    /// Largest particle acceleration of the last rate evaluation (over every part).
    pub fn max_acceleration(&self) -> f64 {
        let largest = self.fluid.acceleration[..self.owned_len()]
            .par_iter()
            .map(|a| a.length_squared())
            .reduce(|| 0.0, f64::max)
            .sqrt();
        self.max_over_parts(largest)
    }

    /// Largest particle speed (over every part).
    pub fn max_speed(&self) -> f64 {
        let largest = self.fluid.velocity[..self.owned_len()]
            .iter()
            .map(|u| u.length())
            .fold(0.0, f64::max);
        self.max_over_parts(largest)
    }
}

/// Advances the gamma the particles carry after a drift `r += u dt`, and with `continuity` the
/// walls' part of the continuity equation ([`Shepard::advance`]). Does nothing for models
/// whose particles carry none.
#[allow(clippy::too_many_arguments)]
pub(crate) fn advance_gamma<V: Vector>(
    config: &SimConfig<V>,
    walls: &Walls<V>,
    gamma: &mut [f64],
    grad_gamma: &mut [V],
    position: &[V],
    drift: &[V],
    dt: f64,
    continuity: Option<WallContinuity<'_>>,
) {
    let Some(shepard) = config.wall_model.shepard().filter(Shepard::carried) else {
        return;
    };
    let (e, g) = (&walls.elements, &walls.grid);
    shepard.advance(
        &config.kernel,
        e,
        g,
        gamma,
        grad_gamma,
        position,
        drift,
        dt,
        continuity,
    );
}

/// Wall pressures, then rates, for one wall model; returns the seconds spent on the wall
/// pressures.
struct Sweep<'a, V: Vector> {
    model: &'a RateModel<V>,
    state: &'a FluidState<'a, V>,
    /// Finds the particles near an element.
    fluid_near: Nearby<'a, V>,
    neighbours: FluidNeighbours<'a, V>,
    elements: &'a mut BoundaryElements<V>,
    /// Finds the elements near a particle.
    wall_near: Nearby<'a, V>,
    acceleration: &'a mut [V],
    density_rate: &'a mut [f64],
    dissipation: &'a mut [DissipationRates],
    scatter: &'a mut ScatterBuffers<V>,
}

impl<V: Vector> WallModelTask<V> for Sweep<'_, V> {
    type Output = f64;

    fn run<W: WallModel<V>>(self, wall_model: &W) -> f64 {
        let start = Instant::now();
        let kernel = &self.model.kernel;
        wall_model.update_wall_pressure(kernel, self.elements, self.state, self.fluid_near);
        let wall_seconds = start.elapsed().as_secs_f64();
        compute_rates(
            self.model,
            wall_model,
            self.state,
            self.neighbours,
            self.elements,
            self.wall_near,
            self.acceleration,
            self.density_rate,
            self.dissipation,
            self.scatter,
        );
        wall_seconds
    }
}

/// What a midpoint step lists with its fluid pairs for the sums of one wall model
/// ([`pair_listing`]).
struct PairListing<'a, V: Vector>(&'a RateModel<V>);

impl<V: Vector> WallModelTask<V> for PairListing<'_, V> {
    type Output = Listing;

    fn run<W: WallModel<V>>(self, wall_model: &W) -> Listing {
        pair_listing(self.0, wall_model)
    }
}

/// Each particle's summand of the skew-adjointness residual (paper 3, eq 26),
/// `V_a (u_a . Grad_a p + p_a Div_a u)` with the full operators of one wall model.
struct SkewResidual<'a, V: Vector> {
    model: &'a RateModel<V>,
    state: &'a FluidState<'a, V>,
    fluid_grid: &'a CellGrid<V>,
    elements: &'a BoundaryElements<V>,
    wall_grid: &'a CellGrid<V>,
}

impl<V: Vector> WallModelTask<V> for SkewResidual<'_, V> {
    type Output = Vec<f64>;

    fn run<W: WallModel<V>>(self, wall_model: &W) -> Vec<f64> {
        let state = self.state;
        (0..state.position.len())
            .into_par_iter()
            .map(|i| {
                let op = particle_operators(
                    self.model,
                    wall_model,
                    state,
                    self.fluid_grid,
                    self.elements,
                    self.wall_grid,
                    i,
                );
                let grad = op.pressure_gradient + op.wall_pressure_gradient;
                let div = op.velocity_divergence + op.wall_velocity_divergence;
                state.volume[i] * (state.velocity[i].dot(grad) + state.pressure[i] * div)
            })
            .collect()
    }
}
