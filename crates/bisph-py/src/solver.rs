//! What the Python `Simulation` asks of a simulation of either dimension: the object-safe
//! [`Solver`] trait, implemented for `bisph_core::Simulation<V>` in 2-D and 3-D.

use crate::errors::Failure;
use crate::run::{Progress, Stop};
use bisph_core::bodies::Motion;
use bisph_core::{EnergyBudget, Simulation};
use bisph_io::case::CaseDim;
use bisph_io::run::diagnostics::from_sim_error;
use bisph_io::run::settle::SettlingSummary;
use bisph_io::{LoadedCase, RunError, RunOptions, Summary};
use pyo3::prelude::*;
use std::path::Path;

/// A per-particle quantity.
#[derive(Clone, Copy, Debug)]
pub enum ParticleField {
    /// Positions `r_i` [m].
    Position,
    /// Velocities `u_i` [m/s].
    Velocity,
    /// Accelerations `du_i/dt` of the last rate evaluation [m/s^2].
    Acceleration,
    /// Densities `rho_i` [kg/m^3].
    Density,
    /// Pressures `p_i` [Pa].
    Pressure,
    /// Masses `m_i` [kg (per unit depth in 2-D: kg/m)].
    Mass,
    /// Shepard factors `gamma_i` [-].
    Gamma,
}

/// A per-element quantity of the walls.
#[derive(Clone, Copy, Debug)]
pub enum ElementField {
    /// Centres `r_j` [m].
    Centre,
    /// Unit normals `n_j`, out of the fluid.
    Normal,
    /// Areas `s_j` [m^2] (lengths [m] in 2-D).
    Area,
    /// Wall pressures `P_j` [Pa].
    Pressure,
    /// Velocities `U_j` [m/s].
    Velocity,
}

/// One body's state at the current time.
pub struct BodyState {
    /// Its name (`forces.csv`).
    pub name: String,
    /// `fixed`, `prescribed`, `piston` or `free`.
    pub motion: &'static str,
    /// Position of its reference point (centre of rotation) [m].
    pub centre: Vec<f64>,
    /// Velocity of that point [m/s].
    pub velocity: Vec<f64>,
    /// Rotation from the reference configuration (angle about z in 2-D; axis times angle in
    /// 3-D) [rad].
    pub rotation: Vec<f64>,
    /// Angular velocity [rad/s].
    pub angular_velocity: Vec<f64>,
    /// Force of the fluid on its walls [N (N/m in 2-D)].
    pub force: Vec<f64>,
    /// Moment of that force about its centre [N m (N m/m in 2-D)].
    pub moment: Vec<f64>,
}

/// A simulation of either dimension, as the Python class drives it.
pub trait Solver: Send + Sync {
    /// 2 or 3.
    fn dim(&self) -> usize;
    /// Simulated time [s].
    fn time(&self) -> f64;
    /// Steps taken.
    fn steps(&self) -> u64;
    /// The size of the next step [s].
    fn next_dt(&self) -> f64;
    /// Fluid particles.
    fn particle_count(&self) -> usize;
    /// Boundary elements.
    fn element_count(&self) -> usize;
    /// One step, never past `end`.
    fn step(&mut self, end: Option<f64>) -> Result<(), Failure>;
    /// Steps to `end` without outputs, reporting progress and ending early when `stop` is
    /// set, between two steps.
    fn run_to(
        &mut self,
        end: f64,
        stop: &Stop,
        progress: Option<&Py<PyAny>>,
    ) -> Result<(), Failure>;
    /// The run loop of `bisph run` from the current state, writing its outputs into `out`.
    fn run_with_outputs(
        &mut self,
        loaded: &LoadedCase,
        settling: Option<SettlingSummary>,
        out: &Path,
        options: &RunOptions,
        progress: &mut dyn FnMut(bisph_io::Progress),
    ) -> Result<Summary, RunError>;
    /// A particle quantity in particle-id order (the order of the case's blocks), flattened
    /// row by row, with its number of components.
    fn particle_field(&self, field: ParticleField) -> (Vec<f64>, usize);
    /// The particle ids in increasing order: the rows of [`Solver::particle_field`].
    fn particle_ids(&self) -> Vec<u32>;
    /// An element quantity as the simulation stores it, with its number of components.
    fn element_field(&self, field: ElementField) -> (&[f64], usize);
    /// The owning body of each element.
    fn element_bodies(&self) -> &[u32];
    /// The energy budget now.
    fn energy(&self) -> EnergyBudget;
    /// The probes' names and values now.
    fn probes(&self) -> Vec<(String, f64)>;
    /// The bodies' states now.
    fn bodies(&self) -> Vec<BodyState>;
}

/// The components of a vector array, in memory order: `glam`'s vectors are `repr(C)`
/// structs of `DIM` f64, so the array reads as `DIM` f64 per entry.
fn components<V: CaseDim>(values: &[V]) -> &[f64] {
    assert_eq!(
        std::mem::size_of::<V>(),
        V::DIM * std::mem::size_of::<f64>()
    );
    // SAFETY: V is a repr(C) struct of V::DIM f64 fields (checked size, f64 alignment), so
    // `values` is `values.len() * V::DIM` initialised f64 in a row, borrowed as long as it.
    unsafe { std::slice::from_raw_parts(values.as_ptr().cast::<f64>(), values.len() * V::DIM) }
}

/// `values` (one entry per particle, in memory order) in increasing particle id, flattened
/// (the ids of particles removed as they left the domain are skipped).
fn by_id<T: Copy>(
    ids: &[u32],
    values: &[T],
    cols: usize,
    flat: impl Fn(T, &mut [f64]),
) -> Vec<f64> {
    let mut order: Vec<usize> = (0..ids.len()).collect();
    order.sort_unstable_by_key(|&i| ids[i]);
    let mut out = vec![0.0; values.len() * cols];
    for (row, i) in out.chunks_exact_mut(cols).zip(order) {
        flat(values[i], row);
    }
    out
}

impl<V: CaseDim> Solver for Simulation<V> {
    fn dim(&self) -> usize {
        V::DIM
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn steps(&self) -> u64 {
        self.step
    }

    fn next_dt(&self) -> f64 {
        Simulation::next_dt(self)
    }

    fn particle_count(&self) -> usize {
        self.fluid.len()
    }

    fn element_count(&self) -> usize {
        self.walls.elements.len()
    }

    fn step(&mut self, end: Option<f64>) -> Result<(), Failure> {
        self.advance(end).map_err(|e| {
            let d = from_sim_error(&e, self);
            Failure::run(e.to_string(), d.exit_code)
        })
    }

    fn run_to(
        &mut self,
        end: f64,
        stop: &Stop,
        progress: Option<&Py<PyAny>>,
    ) -> Result<(), Failure> {
        loop {
            let time = self.time;
            let step = self.step;
            let settling = false;
            stop.report(
                progress,
                Progress {
                    time,
                    end,
                    step,
                    settling,
                },
            );
            // The end test of `bisph run`'s loop, so both take the same steps.
            if time >= end * (1.0 - 1e-12) || stop.requested() {
                return Ok(());
            }
            Solver::step(self, Some(end))?;
        }
    }

    fn run_with_outputs(
        &mut self,
        loaded: &LoadedCase,
        settling: Option<SettlingSummary>,
        out: &Path,
        options: &RunOptions,
        progress: &mut dyn FnMut(bisph_io::Progress),
    ) -> Result<Summary, RunError> {
        bisph_io::run::run_built(loaded, self, settling, out, options, progress)
    }

    fn particle_field(&self, field: ParticleField) -> (Vec<f64>, usize) {
        let f = &self.fluid;
        let d = V::DIM;
        let vector = |values: &[V]| {
            by_id(&f.id, values, d, |v: V, row: &mut [f64]| {
                row.copy_from_slice(&v.to_xyz()[..d])
            })
        };
        let scalar = |values: &[f64]| by_id(&f.id, values, 1, |v, row: &mut [f64]| row[0] = v);
        match field {
            ParticleField::Position => (vector(&f.position), d),
            ParticleField::Velocity => (vector(&f.velocity), d),
            ParticleField::Acceleration => (vector(&f.acceleration), d),
            ParticleField::Density => (scalar(&f.density), 1),
            ParticleField::Pressure => (scalar(&f.pressure), 1),
            ParticleField::Mass => (scalar(&f.mass), 1),
            ParticleField::Gamma => (scalar(&f.gamma), 1),
        }
    }

    fn particle_ids(&self) -> Vec<u32> {
        let mut ids = self.fluid.id.clone();
        ids.sort_unstable();
        ids
    }

    fn element_field(&self, field: ElementField) -> (&[f64], usize) {
        let e = &self.walls.elements;
        match field {
            ElementField::Centre => (components(&e.centre), V::DIM),
            ElementField::Normal => (components(&e.normal), V::DIM),
            ElementField::Velocity => (components(&e.velocity), V::DIM),
            ElementField::Area => (&e.area, 1),
            ElementField::Pressure => (&e.pressure, 1),
        }
    }

    fn element_bodies(&self) -> &[u32] {
        &self.walls.elements.body
    }

    fn energy(&self) -> EnergyBudget {
        Simulation::energy(self)
    }

    fn probes(&self) -> Vec<(String, f64)> {
        let names = self.probes.iter().map(|p| p.name.clone());
        names.zip(self.sample_probes()).collect()
    }

    fn bodies(&self) -> Vec<BodyState> {
        let t = self.time;
        let loads = self.walls.body_loads(t);
        let xyz = |v: V| v.to_xyz()[..V::DIM].to_vec();
        self.walls
            .bodies
            .iter()
            .zip(loads)
            .map(|(b, (force, moment))| {
                let k = b.motion.kinematics(t);
                BodyState {
                    name: b.name.clone(),
                    motion: match b.motion {
                        Motion::Fixed => "fixed",
                        Motion::Prescribed(_) => "prescribed",
                        Motion::Piston(_) => "piston",
                        Motion::Free(_) => "free",
                    },
                    centre: xyz(b.centre + k.displacement),
                    velocity: xyz(k.velocity),
                    rotation: V::angular_to_vec(k.rotation),
                    angular_velocity: V::angular_to_vec(k.angular_velocity),
                    force: xyz(force),
                    moment: V::angular_to_vec(moment),
                }
            })
            .collect()
    }
}
