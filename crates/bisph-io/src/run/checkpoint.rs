//! Checkpoints: the complete state of a run in one binary file, so that `bisph run --resume`
//! continues bit for bit where the run stopped.
//!
//! Layout (little endian):
//! ```text
//! magic        8 bytes  "BISPHCKP"
//! format       u32      FORMAT_VERSION
//! version      u32 len + UTF-8   the bisph version that wrote it
//! dim          u32      2 or 3
//! payload      u64 len + bytes   (see `encode_payload`)
//! checksum     u64      FNV-1a 64 of every byte before it
//! ```
//! A file whose magic, format, version, dimension, checksum or lengths do not match is refused
//! as a whole before anything is used. Every length read is checked against the bytes left, so
//! a damaged or hostile file cannot make the reader allocate more than the file's own size.
//!
//! What is saved: the fluid arrays in their current memory order (the run reorders particles
//! by cell, and sums run in memory order, so the order is part of the state), the wall
//! elements' moving geometry, velocities and pressures, the pistons and free rigid bodies
//! (attitude, position, velocities and the accelerations the integrator keeps), the integrator
//! history (rates of the last evaluation and of the step before, from which the midpoint
//! scheme extrapolates its first guess, and which Verlet uses as its first kick), the
//! positions the explicit scheme's Verlet list was built at (so the same list is rebuilt and
//! kept for the same steps), the energy accumulators (wall work, viscous dissipation, forcing
//! work, the energy of the particles removed as they left the domain, and their count), the
//! flux controller's memory and driving force, and the run loop's counters (next output
//! times, frames, CSV lengths, free bodies' CSV lengths, plot histories); a checkpoint taken
//! while settling before `t = 0` saves the settling report instead of the run's counters. The static parts (reference geometry, configuration; masses are saved too) are
//! rebuilt from the case text stored in the checkpoint.

use crate::formats::files::OutputError;
use bisph_core::bodies::{FreeBody, Motion};
use bisph_core::forcing::FluxHistory;
use bisph_core::particles::Fluid;
use bisph_core::simulation::{PartLayout, SettleReport};
use bisph_core::{Simulation, Vector};
use glam::{DQuat, DVec3};
use std::path::{Path, PathBuf};

/// File magic.
pub const MAGIC: &[u8; 8] = b"BISPHCKP";
/// Version of the binary layout.
/// (10: the midpoint first guess's earliest rates and step; 9: the particles removed as
/// they left the domain and their energy, a tenth energy
/// column; 8: the density diffusion's energy books, a ninth energy column; 7: a settling stage
/// part-way; 6: the positions the explicit scheme's Verlet list was
/// built at; 5: the midpoint first
/// guess's earlier rates and step; 4: free rigid bodies and their CSV lengths; 3: without
/// them).
pub const FORMAT_VERSION: u32 = 10;
/// Oldest layout still read: format 4 is format 5 without the earlier rates, so a run written
/// by it resumes with the first guess of a fresh start (last rates) for its first two steps;
/// format 5 is format 6 without the Verlet list's build positions, so an explicit run with a
/// skin written by it builds its list afresh at its first step; format 6 is format 7 without
/// the settling stage (it was never written before `t = 0`); format 7 is format 8 without the
/// density diffusion's books, which resume at zero (the energy rows read it as zero); format 8
/// is format 9 without removed particles (none had left the domain: that stopped the run);
/// format 9 is format 10 without the midpoint first guess's earliest rates, so a midpoint run
/// written by it extrapolates along a line at its first step.
pub const OLDEST_FORMAT_READ: u32 = 4;
/// The bisph version written into (and required of) every checkpoint.
pub const BISPH_VERSION: &str = env!("CARGO_PKG_VERSION");
/// File name of the checkpoint in an output directory.
pub const FILE_NAME: &str = "checkpoint.bin";

/// Why a checkpoint could not be read or used.
#[derive(Debug)]
pub enum CheckpointError {
    /// The file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not a bisph checkpoint, or one of another format or bisph version.
    Foreign {
        /// The file.
        path: PathBuf,
        /// What did not match.
        reason: String,
    },
    /// The file is a bisph checkpoint but is damaged (checksum, lengths).
    Damaged {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The checkpoint does not fit the case it names (particle or element counts, bodies).
    Mismatch {
        /// The file.
        path: PathBuf,
        /// What does not fit.
        reason: String,
    },
}

impl std::fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CheckpointError::Io { path, source } => {
                write!(f, "cannot read checkpoint {}: {source}", path.display())
            }
            CheckpointError::Foreign { path, reason } => write!(
                f,
                "refusing checkpoint {}: not usable by bisph {BISPH_VERSION}: {reason}",
                path.display()
            ),
            CheckpointError::Damaged { path, reason } => write!(
                f,
                "refusing checkpoint {}: the file is damaged: {reason}",
                path.display()
            ),
            CheckpointError::Mismatch { path, reason } => write!(
                f,
                "refusing checkpoint {}: it does not fit its case: {reason}",
                path.display()
            ),
        }
    }
}

impl std::error::Error for CheckpointError {}

/// FNV-1a, 64 bits.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The simulation's dynamic state (what a step changes), in memory order.
#[derive(Clone, Debug, Default)]
pub struct SimState<V: Vector> {
    /// Time.
    pub time: f64,
    /// Steps taken.
    pub step: u64,
    /// Last step size.
    pub last_dt: f64,
    /// Size of the step before the last (the midpoint first guess's earlier rates).
    pub earlier_dt: f64,
    /// Size of the step before that (the midpoint first guess's earliest rates).
    pub earliest_dt: f64,
    /// Cumulative wall work.
    pub wall_work: f64,
    /// Wall power at the last rate evaluation.
    pub wall_power: f64,
    /// Cumulative viscous dissipation.
    pub viscous_dissipation: f64,
    /// Viscous dissipation rate at the last rate evaluation.
    pub viscous_power: f64,
    /// Cumulative work of the driving force.
    pub forcing_work: f64,
    /// Cumulative energy removed by the density diffusion.
    pub diffusion_dissipation: f64,
    /// Diffusion dissipation rate at the last rate evaluation.
    pub diffusion_power: f64,
    /// Particles removed as they left the domain.
    pub removed: u64,
    /// Cumulative energy of the removed particles.
    pub removed_energy: f64,
    /// Current driving acceleration of the flux control.
    pub body_force: V,
    /// The flux controller's memory.
    pub flux_history: FluxHistory,
    /// Midpoint iterations of the last step.
    pub last_iterations: u32,
    /// Midpoint residue of the last step.
    pub last_residue: f64,
    /// Time at which the walls were last placed.
    pub placed_at: f64,
    /// The fluid, all arrays (ids, rates included).
    pub fluid: Fluid<V>,
    /// Where the explicit scheme's Verlet list was built (empty without one).
    pub neighbour_origin: Vec<V>,
    /// Element centres.
    pub centre: Vec<V>,
    /// Element normals.
    pub normal: Vec<V>,
    /// Element areas.
    pub area: Vec<f64>,
    /// Element velocities.
    pub velocity: Vec<V>,
    /// Element reaches.
    pub reach: Vec<f64>,
    /// Largest reach.
    pub max_reach: f64,
    /// Wall pressures.
    pub pressure: Vec<f64>,
    /// Current element corners.
    pub corners: Vec<V>,
    /// Pistons in body order: (body index, position, velocity, acceleration).
    pub pistons: Vec<(u32, f64, f64, f64)>,
    /// Free rigid bodies in body order: (body index, [`free_body_values`]).
    pub free_bodies: Vec<(u32, [f64; FREE_BODY_VALUES])>,
    /// The layout of a part of a split run, whose own fluid and halo [`SimState::fluid`]
    /// then holds (`None` for the state of a whole run, the only one a checkpoint file holds).
    pub layout: Option<PartLayout<V>>,
}

/// Numbers of a free body's evolving state in a checkpoint.
pub const FREE_BODY_VALUES: usize = 19;

/// The evolving state of a free body: attitude quaternion `(x, y, z, w)`, displacement,
/// velocity, body-axes angular velocity, acceleration, body-axes angular acceleration (the
/// accelerations are the integrator's memory: the midpoint scheme's first guess, Verlet's first
/// kick, and the load a staggered body moves with). Mass, inertia, locks and coupling are
/// static (rebuilt from the case).
pub fn free_body_values(b: &FreeBody) -> [f64; FREE_BODY_VALUES] {
    let mut v = [0.0; FREE_BODY_VALUES];
    v[..4].copy_from_slice(&b.attitude.to_array());
    for (k, x) in [
        b.position,
        b.velocity,
        b.angular_velocity,
        b.acceleration,
        b.angular_acceleration,
    ]
    .iter()
    .enumerate()
    {
        v[4 + 3 * k..7 + 3 * k].copy_from_slice(&x.to_array());
    }
    v
}

/// Puts [`free_body_values`] back into `b`.
pub fn set_free_body_values(b: &mut FreeBody, v: &[f64; FREE_BODY_VALUES]) {
    let at = |k: usize| DVec3::from_slice(&v[4 + 3 * k..7 + 3 * k]);
    b.attitude = DQuat::from_array([v[0], v[1], v[2], v[3]]);
    b.position = at(0);
    b.velocity = at(1);
    b.angular_velocity = at(2);
    b.acceleration = at(3);
    b.angular_acceleration = at(4);
}

impl<V: Vector> SimState<V> {
    /// The state of the whole run `sim` belongs to: [`SimState::capture`] of a whole
    /// simulation; of a part of a split run, its state with the fluid and the Verlet list's
    /// build positions gathered from every part (every part must call it). A whole
    /// simulation restores it and continues with the bits of the run, split again or not.
    pub fn capture_whole(&mut self, sim: &Simulation<V>) {
        self.capture(sim);
        if sim.is_part() {
            let (fluid, origin) = sim.gathered();
            self.fluid = fluid;
            self.neighbour_origin = origin.unwrap_or_default();
            self.pressure = sim.gathered_wall_pressures();
            self.layout = None;
        }
    }

    /// Copies the state of `sim` into `self`, reusing its buffers (no allocation once warm,
    /// but for the layout of a part of a split run). A part's state goes back into that part
    /// only ([`SimState::restore`]); [`SimState::capture_whole`] gives the whole run's.
    pub fn capture(&mut self, sim: &Simulation<V>) {
        self.time = sim.time;
        self.step = sim.step;
        self.last_dt = sim.last_dt;
        self.earlier_dt = sim.earlier_dt;
        self.earliest_dt = sim.earliest_dt;
        self.wall_work = sim.wall_work;
        self.wall_power = sim.wall_power;
        self.viscous_dissipation = sim.viscous_dissipation;
        self.viscous_power = sim.viscous_power;
        self.forcing_work = sim.forcing_work;
        self.diffusion_dissipation = sim.diffusion_dissipation;
        self.diffusion_power = sim.diffusion_power;
        self.removed = sim.removed;
        self.removed_energy = sim.removed_energy;
        self.body_force = sim.body_force;
        self.flux_history = sim.flux_history;
        self.last_iterations = sim.last_iterations;
        self.last_residue = sim.last_residue;
        self.placed_at = sim.walls.placed_at;
        let (d, s) = (&mut self.fluid, &sim.fluid);
        d.id.clone_from(&s.id);
        d.position.clone_from(&s.position);
        d.velocity.clone_from(&s.velocity);
        d.density.clone_from(&s.density);
        d.mass.clone_from(&s.mass);
        d.pressure.clone_from(&s.pressure);
        d.acceleration.clone_from(&s.acceleration);
        d.density_rate.clone_from(&s.density_rate);
        d.earlier_acceleration.clone_from(&s.earlier_acceleration);
        d.earlier_density_rate.clone_from(&s.earlier_density_rate);
        d.earliest_acceleration.clone_from(&s.earliest_acceleration);
        d.earliest_density_rate.clone_from(&s.earliest_density_rate);
        d.gamma.clone_from(&s.gamma);
        d.grad_gamma.clone_from(&s.grad_gamma);
        d.density_offset.clone_from(&s.density_offset);
        self.neighbour_origin.clear();
        if let Some(origin) = sim.neighbour_list_origin() {
            self.neighbour_origin.extend_from_slice(origin);
        }
        let e = &sim.walls.elements;
        self.centre.clone_from(&e.centre);
        self.normal.clone_from(&e.normal);
        self.area.clone_from(&e.area);
        self.velocity.clone_from(&e.velocity);
        self.reach.clone_from(&e.reach);
        self.max_reach = e.max_reach;
        self.pressure.clone_from(&e.pressure);
        self.corners.clone_from(&e.corners);
        self.pistons.clear();
        self.free_bodies.clear();
        for (b, body) in sim.walls.bodies.iter().enumerate() {
            match &body.motion {
                Motion::Piston(p) => {
                    self.pistons
                        .push((b as u32, p.position, p.velocity, p.acceleration))
                }
                Motion::Free(f) => self.free_bodies.push((b as u32, free_body_values(f))),
                _ => {}
            }
        }
        self.layout = sim.part_layout();
    }

    /// Puts this state into `sim` (built from the same case) and rebuilds its cell grids:
    /// the state of a whole run into a whole simulation, the state of a part of a split run
    /// into that part (every part at once, with states of the same moment). Fails, changing
    /// nothing, when the counts do not fit.
    pub fn restore(&self, sim: &mut Simulation<V>) -> Result<(), String> {
        match (&self.layout, sim.is_part()) {
            (None, true) => {
                return Err("the state of a whole run goes into a whole simulation".into())
            }
            (Some(_), false) => {
                return Err("the state of a part of a split run goes into that part".into())
            }
            _ => {}
        }
        self.check_fluid_counts(sim)?;
        self.check_wall_counts(sim)?;
        self.check_fluid_values(sim)?;
        self.check_wall_values(sim)?;
        self.check_scalars()?;
        self.check_bodies(sim)?;
        self.put_scalars(sim);
        self.put_fluid(sim);
        self.put_walls(sim);
        self.put_bodies(sim);
        if let Some(layout) = &self.layout {
            sim.restore_part_layout(layout);
        }
        // A list that does not fit (a damaged file whose checksum still matched) is rebuilt at
        // the next step instead.
        let origin = &self.neighbour_origin;
        sim.restore_neighbour_list((!origin.is_empty()).then_some(origin));
        sim.walls.grid.rebuild(&sim.walls.elements.centre);
        sim.walls.refresh_gamma();
        // A function of the positions and the walls: the bits of a run never stopped, whatever
        // the file holds for it.
        sim.place_geometric_gamma();
        Ok(())
    }

    /// The fluid arrays have one length: with the removed particles, the case's particle
    /// count; the ids are distinct and below it.
    fn check_fluid_counts(&self, sim: &Simulation<V>) -> Result<(), String> {
        let n = self.fluid.id.len();
        let f = &self.fluid;
        if [
            f.position.len(),
            f.velocity.len(),
            f.density.len(),
            f.mass.len(),
            f.pressure.len(),
            f.acceleration.len(),
            f.density_rate.len(),
            f.gamma.len(),
            f.grad_gamma.len(),
            f.density_offset.len(),
        ]
        .iter()
        .any(|&k| k != n)
            || [
                f.earlier_acceleration.len(),
                f.earlier_density_rate.len(),
                f.earliest_acceleration.len(),
                f.earliest_density_rate.len(),
            ]
            .iter()
            .any(|&k| k != n && k != 0)
        {
            return Err("fluid arrays of different lengths".into());
        }
        if !(self.neighbour_origin.is_empty() || self.neighbour_origin.len() == n) {
            return Err("neighbour-list positions of another length than the fluid".into());
        }
        // A part holds some of the ids, its own first; a whole run holds each id of the case
        // but those of the particles removed as they left the domain (`sim` is the case built
        // afresh, or a run of it that may have removed some).
        let case_particles = sim.fluid.len() as u64 + sim.removed;
        let slots = match &self.layout {
            Some(layout) if layout.owned() > n => {
                return Err(format!(
                    "{n} fluid particles saved for a part owning {}",
                    layout.owned()
                ))
            }
            Some(_) => f.id.iter().max().map_or(0, |&m| m as usize + 1),
            None if (n as u64).checked_add(self.removed) != Some(case_particles) => {
                return Err(format!(
                    "{n} fluid particles saved and {} removed, the case builds {case_particles}",
                    self.removed,
                ))
            }
            None => case_particles as usize,
        };
        let mut seen = vec![false; slots];
        for &id in &f.id {
            match seen.get_mut(id as usize) {
                Some(s) if !*s => *s = true,
                _ => return Err(format!("particle id {id} repeated or out of range")),
            }
        }
        Ok(())
    }

    /// As many boundary elements and corners as the case builds.
    fn check_wall_counts(&self, sim: &Simulation<V>) -> Result<(), String> {
        let e = &sim.walls.elements;
        let m = e.len();
        if [
            self.centre.len(),
            self.normal.len(),
            self.area.len(),
            self.velocity.len(),
            self.reach.len(),
            self.pressure.len(),
        ]
        .iter()
        .any(|&k| k != m)
            || self.corners.len() != e.corners.len()
        {
            return Err(format!(
                "{} boundary elements ({} corners) saved, the case builds {m} ({})",
                self.centre.len(),
                self.corners.len(),
                e.corners.len()
            ));
        }
        Ok(())
    }

    /// Finite fluid values, positive densities, every particle inside the domain.
    fn check_fluid_values(&self, sim: &Simulation<V>) -> Result<(), String> {
        let finite_v = |v: &[V]| v.iter().all(|x| x.is_finite());
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let f = &self.fluid;
        if !(finite_v(&f.velocity)
            && finite_v(&f.acceleration)
            && finite(&f.mass)
            && finite(&f.pressure)
            && finite(&f.density_rate)
            && finite_v(&f.earlier_acceleration)
            && finite(&f.earlier_density_rate)
            && finite_v(&f.earliest_acceleration)
            && finite(&f.earliest_density_rate)
            && finite(&f.gamma)
            && finite_v(&f.grad_gamma)
            && finite(&f.density_offset)
            && f.density.iter().all(|&r| r.is_finite() && r > 0.0))
        {
            return Err("non-finite fluid values".into());
        }
        let (lo, hi) = (sim.config.domain_min, sim.config.domain_max);
        if let Some(p) = f
            .position
            .iter()
            .find(|r| (0..V::DIM).any(|k| !(r.get(k) >= lo.get(k) && r.get(k) <= hi.get(k))))
        {
            return Err(format!(
                "a particle outside the domain, at {:?}",
                p.to_xyz()
            ));
        }
        Ok(())
    }

    /// Finite element values, and elements that do not spread far beyond the case's walls.
    fn check_wall_values(&self, sim: &Simulation<V>) -> Result<(), String> {
        let e = &sim.walls.elements;
        let finite_v = |v: &[V]| v.iter().all(|x| x.is_finite());
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !(finite_v(&self.centre)
            && finite_v(&self.normal)
            && finite_v(&self.velocity)
            && finite_v(&self.corners)
            && finite(&self.area)
            && finite(&self.reach)
            && finite(&self.pressure)
            && self.max_reach.is_finite())
        {
            return Err("non-finite wall element values".into());
        }
        // The element grid may not need far more cells than the case's own walls do.
        let cells = |points: &[V]| -> f64 {
            let Some(&first) = points.first() else {
                return 0.0;
            };
            let (mut a, mut b) = (first, first);
            for &p in points {
                a = a.min_by_component(p);
                b = b.max_by_component(p);
            }
            let cell = sim.walls.grid.cell_size();
            (0..V::DIM)
                .map(|k| (b.get(k) - a.get(k)) / cell + 1.0)
                .product()
        };
        if cells(&self.centre) > 64.0 * cells(&e.centre) + 1e6 {
            return Err("wall elements spread far beyond the case's walls".into());
        }
        Ok(())
    }

    /// Finite piston states and scalars, and a time that is not negative.
    fn check_scalars(&self) -> Result<(), String> {
        if self
            .pistons
            .iter()
            .any(|p| !(p.1.is_finite() && p.2.is_finite() && p.3.is_finite()))
            || ![
                self.time,
                self.last_dt,
                self.earlier_dt,
                self.earliest_dt,
                self.wall_work,
                self.wall_power,
                self.viscous_dissipation,
                self.viscous_power,
                self.forcing_work,
                self.diffusion_dissipation,
                self.diffusion_power,
                self.removed_energy,
                self.flux_history.last,
                self.flux_history.before_last,
                self.flux_history.force,
                self.last_residue,
                self.placed_at,
            ]
            .iter()
            .all(|x| x.is_finite())
            || self.time < 0.0
        {
            return Err("non-finite or negative scalars".into());
        }
        Ok(())
    }

    /// The case's pistons and free bodies, each in a state one step cannot throw far away.
    fn check_bodies(&self, sim: &Simulation<V>) -> Result<(), String> {
        let (lo, hi) = (sim.config.domain_min, sim.config.domain_max);
        let pistons: Vec<u32> = sim
            .walls
            .bodies
            .iter()
            .enumerate()
            .filter(|(_, b)| matches!(b.motion, Motion::Piston(_)))
            .map(|(k, _)| k as u32)
            .collect();
        if pistons != self.pistons.iter().map(|p| p.0).collect::<Vec<_>>() {
            return Err("the pistons saved are not the case's pistons".into());
        }
        let free: Vec<u32> = sim
            .walls
            .bodies
            .iter()
            .enumerate()
            .filter(|(_, b)| matches!(b.motion, Motion::Free(_)))
            .map(|(k, _)| k as u32)
            .collect();
        if free != self.free_bodies.iter().map(|b| b.0).collect::<Vec<_>>() {
            return Err("the free bodies saved are not the case's free bodies".into());
        }
        // Dynamic bodies must stay where one step cannot throw their walls far away (the
        // element grid is sized by their spread): displacements within the domain's extent,
        // speeds up to 1000 c0, accelerations up to 1000 c0^2 / h.
        let extent = (0..V::DIM)
            .map(|k| hi.get(k) - lo.get(k))
            .fold(0.0, f64::max);
        let c0 = sim.config.eos.c0();
        let (speed, accel) = (1e3 * c0, 1e3 * c0 * c0 / sim.config.kernel.h);
        let fits =
            |x: f64, v: f64, a: f64| x.abs() <= extent && v.abs() <= speed && a.abs() <= accel;
        for &(b, x, v, a) in &self.pistons {
            if !fits(x, v, a) {
                return Err(format!(
                    "piston {b}: position {x}, velocity {v} or acceleration {a} out of range \
                     (|x| <= {extent}, |v| <= {speed}, |a| <= {accel})"
                ));
            }
        }
        for (b, values) in &self.free_bodies {
            let q = DQuat::from_array([values[0], values[1], values[2], values[3]]);
            let norm = DVec3::from_slice(&values[4..7]).length();
            let length = |k: usize| DVec3::from_slice(&values[4 + 3 * k..7 + 3 * k]).length();
            if values.iter().any(|x| !x.is_finite()) || (q.length() - 1.0).abs() > 1e-9 {
                return Err(format!(
                    "free body {b}: non-finite state or an attitude that is not a unit quaternion"
                ));
            }
            if !fits(norm, length(1), length(3)) {
                return Err(format!(
                    "free body {b}: displacement {norm}, speed {} or acceleration {} out of range \
                     (<= {extent}, {speed}, {accel})",
                    length(1),
                    length(3)
                ));
            }
            // Rotation rates: a turn of at most 1000 c0 / extent rad/s (rim speeds like the
            // linear bound); angular accelerations likewise.
            if length(2) * extent > speed || length(4) * extent > accel {
                return Err(format!(
                    "free body {b}: angular velocity {} or angular acceleration {} out of range",
                    length(2),
                    length(4)
                ));
            }
        }
        Ok(())
    }

    /// The time, step sizes, energy accounts and forcing state into `sim`.
    fn put_scalars(&self, sim: &mut Simulation<V>) {
        sim.time = self.time;
        sim.step = self.step;
        sim.last_dt = self.last_dt;
        sim.earlier_dt = self.earlier_dt;
        sim.earliest_dt = self.earliest_dt;
        sim.wall_work = self.wall_work;
        sim.wall_power = self.wall_power;
        sim.viscous_dissipation = self.viscous_dissipation;
        sim.viscous_power = self.viscous_power;
        sim.forcing_work = self.forcing_work;
        sim.diffusion_dissipation = self.diffusion_dissipation;
        sim.diffusion_power = self.diffusion_power;
        sim.removed = self.removed;
        sim.removed_energy = self.removed_energy;
        sim.body_force = self.body_force;
        sim.flux_history = self.flux_history;
        sim.last_iterations = self.last_iterations;
        sim.last_residue = self.last_residue;
        sim.walls.placed_at = self.placed_at;
    }

    /// The fluid arrays into `sim`.
    fn put_fluid(&self, sim: &mut Simulation<V>) {
        let f = &self.fluid;
        let d = &mut sim.fluid;
        d.id.clone_from(&f.id);
        d.position.clone_from(&f.position);
        d.velocity.clone_from(&f.velocity);
        d.density.clone_from(&f.density);
        d.mass.clone_from(&f.mass);
        d.pressure.clone_from(&f.pressure);
        d.acceleration.clone_from(&f.acceleration);
        d.density_rate.clone_from(&f.density_rate);
        d.earlier_acceleration.clone_from(&f.earlier_acceleration);
        d.earlier_density_rate.clone_from(&f.earlier_density_rate);
        d.earliest_acceleration.clone_from(&f.earliest_acceleration);
        d.earliest_density_rate.clone_from(&f.earliest_density_rate);
        d.gamma.clone_from(&f.gamma);
        d.grad_gamma.clone_from(&f.grad_gamma);
        d.density_offset.clone_from(&f.density_offset);
    }

    /// The boundary elements into `sim`.
    fn put_walls(&self, sim: &mut Simulation<V>) {
        let e = &mut sim.walls.elements;
        e.centre.clone_from(&self.centre);
        e.normal.clone_from(&self.normal);
        e.area.clone_from(&self.area);
        e.velocity.clone_from(&self.velocity);
        e.reach.clone_from(&self.reach);
        e.max_reach = self.max_reach;
        e.pressure.clone_from(&self.pressure);
        e.set_corners(&self.corners);
    }

    /// The pistons' and free bodies' states into `sim`.
    fn put_bodies(&self, sim: &mut Simulation<V>) {
        for &(b, position, velocity, acceleration) in &self.pistons {
            if let Motion::Piston(p) = &mut sim.walls.bodies[b as usize].motion {
                p.position = position;
                p.velocity = velocity;
                p.acceleration = acceleration;
            }
        }
        for (b, values) in &self.free_bodies {
            if let Motion::Free(f) = &mut sim.walls.bodies[*b as usize].motion {
                set_free_body_values(f, values);
            }
        }
    }
}

/// Columns of `energy.csv` (and of the energy history a checkpoint keeps).
pub const ENERGY_COLUMNS: usize = 10;

/// Energy columns a checkpoint of layout `format` keeps (format 8 without the last, earlier
/// formats without the last two).
fn energy_columns(format: u32) -> usize {
    match format {
        9.. => ENERGY_COLUMNS,
        8 => ENERGY_COLUMNS - 1,
        _ => ENERGY_COLUMNS - 2,
    }
}

/// Exactly one vector, from a list.
fn single<V: Vector>(v: Vec<V>) -> Result<V, String> {
    match v[..] {
        [x] => Ok(x),
        _ => Err(format!("expected one vector, found {}", v.len())),
    }
}

/// Number of CSV series whose lengths a checkpoint keeps.
pub const SERIES: usize = 6;
/// Their file names, in the order of [`RunCounters::csv_lengths`].
pub const SERIES_FILES: [&str; SERIES] = [
    "energy.csv",
    "forces.csv",
    "probes.csv",
    "bodies.csv",
    "midpoint.csv",
    "flux.csv",
];

/// The run loop's own state (outputs and running statistics).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunCounters {
    /// Time of the next series row.
    pub next_series: f64,
    /// Time of the next VTK frame.
    pub next_frame: f64,
    /// Times of the frames written (their index is the frame number).
    pub frame_times: Vec<f64>,
    /// Initial total energy.
    pub e0_total: f64,
    /// Energy scale.
    pub scale: f64,
    /// Largest relative drift so far.
    pub max_drift: f64,
    /// Largest speed so far.
    pub max_speed: f64,
    /// Sum of midpoint iterations.
    pub iterations_sum: u64,
    /// Most midpoint iterations in a step.
    pub iterations_max: u32,
    /// Largest residue.
    pub residue_max: f64,
    /// Unconverged steps.
    pub unconverged: u64,
    /// Bytes of each series file (see [`SERIES_FILES`]; 0 when absent).
    pub csv_lengths: [u64; SERIES],
    /// Wall seconds of the time loop before this checkpoint.
    pub wall_seconds: f64,
    /// Step size the run started with (for the time-step collapse watch).
    pub dt0: f64,
    /// Bytes of each free body's `body_<name>.csv`, in body order.
    pub body_csv_lengths: Vec<u64>,
    /// Largest fluid + free bodies energy drift so far (see `Summary`).
    pub fluid_body_max: f64,
}

impl RunCounters {
    /// Checks that the counters fit a run at time `t` with these output intervals (so that no
    /// loop over output times can run away on a hostile file).
    pub fn check(&self, t: f64, series_interval: f64, vtk_interval: f64) -> Result<(), String> {
        let near = |next: f64, interval: f64| {
            next.is_finite() && next >= t - interval && next <= t + 2.0 * interval
        };
        if !near(self.next_series, series_interval) {
            return Err(format!(
                "next series time {} does not fit t = {t}",
                self.next_series
            ));
        }
        if vtk_interval > 0.0 && !near(self.next_frame, vtk_interval) {
            return Err(format!(
                "next frame time {} does not fit t = {t}",
                self.next_frame
            ));
        }
        if self.frame_times.iter().any(|x| !x.is_finite())
            || !self.dt0.is_finite()
            || !self.fluid_body_max.is_finite()
        {
            return Err("non-finite frame times or first step".into());
        }
        Ok(())
    }
}

/// A whole checkpoint.
#[derive(Clone, Debug, Default)]
pub struct Checkpoint<V: Vector> {
    /// Where the case came from (its folder resolves relative file names).
    pub case_source: String,
    /// The case text after overrides.
    pub case_text: String,
    /// The simulation state.
    pub sim: SimState<V>,
    /// The run loop's counters.
    pub run: RunCounters,
    /// Rows of `energy.csv` so far (for the plots).
    pub history: Vec<[f64; ENERGY_COLUMNS]>,
    /// Rows of `probes.csv` so far (for the plots).
    pub probe_history: Vec<Vec<f64>>,
    /// Written while settling before `t = 0`: the settling report at the state saved (the run
    /// counters and histories are then empty).
    pub settling: Option<SettleReport>,
}

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.0.extend_from_slice(s.as_bytes());
    }
    fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for &x in v {
            self.f64(x);
        }
    }
    fn u32s(&mut self, v: &[u32]) {
        self.u64(v.len() as u64);
        for &x in v {
            self.u32(x);
        }
    }
    fn vectors<V: Vector>(&mut self, v: &[V]) {
        self.u64(v.len() as u64);
        for x in v {
            for k in 0..V::DIM {
                self.f64(x.get(k));
            }
        }
    }
}

/// Bounds-checked reader: every length is checked against the bytes left before allocating.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        if self.bytes.len() - self.at < n {
            return Err(format!(
                "truncated: {n} bytes wanted at offset {}, {} left",
                self.at,
                self.bytes.len() - self.at
            ));
        }
        let s = &self.bytes[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn u64(&mut self) -> Result<u64, String> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A count of items of `size` bytes each, checked against the bytes left.
    fn len(&mut self, size: usize) -> Result<usize, String> {
        let n = self.u64()?;
        let left = (self.bytes.len() - self.at) as u64;
        if size > 0 && n > left / size as u64 {
            return Err(format!(
                "a list of {n} entries of {size} bytes at offset {} exceeds the {left} bytes left",
                self.at
            ));
        }
        Ok(n as usize)
    }
    fn str(&mut self) -> Result<String, String> {
        let n = self.len(1)?;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| "a text is not UTF-8".to_string())
    }
    fn f64s(&mut self) -> Result<Vec<f64>, String> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    fn u32s(&mut self) -> Result<Vec<u32>, String> {
        let n = self.len(4)?;
        (0..n).map(|_| self.u32()).collect()
    }
    fn vectors<V: Vector>(&mut self) -> Result<Vec<V>, String> {
        let n = self.len(8 * V::DIM)?;
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            let mut v = V::ZERO;
            for k in 0..V::DIM {
                v.set(k, self.f64()?);
            }
            out.push(v);
        }
        Ok(out)
    }
}

/// The payload of layout `format`: the case, the state, the run counters, the histories, the
/// settling report, then the state's fields added in later layouts (see [`decode_payload`]).
fn encode_payload<V: Vector>(c: &Checkpoint<V>, format: u32) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    w.str(&c.case_source);
    w.str(&c.case_text);
    write_state(&mut w, &c.sim, format);
    write_run(&mut w, &c.run);
    write_histories(&mut w, c, format);
    if format >= 7 {
        write_settling(&mut w, c.settling.as_ref());
    }
    write_later_state(&mut w, &c.sim, format);
    w.0
}

/// The state's clock, books, fluid, walls and bodies.
fn write_state<V: Vector>(w: &mut Writer, s: &SimState<V>, format: u32) {
    let has_earlier_rates = format >= 5;
    w.f64(s.time);
    w.u64(s.step);
    w.f64(s.last_dt);
    if has_earlier_rates {
        w.f64(s.earlier_dt);
    }
    w.f64(s.wall_work);
    w.f64(s.wall_power);
    w.f64(s.viscous_dissipation);
    w.f64(s.viscous_power);
    w.f64(s.forcing_work);
    w.vectors(&[s.body_force]);
    w.f64(s.flux_history.last);
    w.f64(s.flux_history.before_last);
    w.f64(s.flux_history.force);
    w.u32(s.last_iterations);
    w.f64(s.last_residue);
    w.f64(s.placed_at);
    let f = &s.fluid;
    w.u32s(&f.id);
    w.vectors(&f.position);
    w.vectors(&f.velocity);
    w.f64s(&f.density);
    w.f64s(&f.mass);
    w.f64s(&f.pressure);
    w.vectors(&f.acceleration);
    w.f64s(&f.density_rate);
    w.f64s(&f.gamma);
    w.vectors(&f.grad_gamma);
    w.f64s(&f.density_offset);
    if has_earlier_rates {
        w.vectors(&f.earlier_acceleration);
        w.f64s(&f.earlier_density_rate);
    }
    if format >= 6 {
        w.vectors(&s.neighbour_origin);
    }
    w.vectors(&s.centre);
    w.vectors(&s.normal);
    w.f64s(&s.area);
    w.vectors(&s.velocity);
    w.f64s(&s.reach);
    w.f64(s.max_reach);
    w.f64s(&s.pressure);
    w.vectors(&s.corners);
    w.u64(s.pistons.len() as u64);
    for &(b, x, v, a) in &s.pistons {
        w.u32(b);
        w.f64(x);
        w.f64(v);
        w.f64(a);
    }
    w.u64(s.free_bodies.len() as u64);
    for (b, values) in &s.free_bodies {
        w.u32(*b);
        for &x in values {
            w.f64(x);
        }
    }
}

/// The run loop's counters.
fn write_run(w: &mut Writer, r: &RunCounters) {
    w.f64(r.next_series);
    w.f64(r.next_frame);
    w.f64s(&r.frame_times);
    w.f64(r.e0_total);
    w.f64(r.scale);
    w.f64(r.max_drift);
    w.f64(r.max_speed);
    w.u64(r.iterations_sum);
    w.u32(r.iterations_max);
    w.f64(r.residue_max);
    w.u64(r.unconverged);
    for &l in &r.csv_lengths {
        w.u64(l);
    }
    w.f64(r.wall_seconds);
    w.f64(r.dt0);
    w.u64(r.body_csv_lengths.len() as u64);
    for &l in &r.body_csv_lengths {
        w.u64(l);
    }
    w.f64(r.fluid_body_max);
}

/// The energy and probe rows so far.
fn write_histories<V: Vector>(w: &mut Writer, c: &Checkpoint<V>, format: u32) {
    w.u64(c.history.len() as u64);
    let columns = energy_columns(format);
    for row in &c.history {
        for &x in &row[..columns] {
            w.f64(x);
        }
    }
    w.u64(c.probe_history.len() as u64);
    for row in &c.probe_history {
        w.f64s(row);
    }
}

/// The settling report: a flag, then the report when there is one.
fn write_settling(w: &mut Writer, settling: Option<&SettleReport>) {
    match settling {
        None => w.u32(0),
        Some(s) => {
            w.u32(1);
            w.u64(s.steps);
            w.f64s(&[
                s.time,
                s.max_speed,
                s.max_acceleration,
                s.max_displacement,
                s.wall_seconds,
            ]);
        }
    }
}

/// The state's fields added in layouts 8 (diffusion books), 9 (removed particles) and 10
/// (the earliest rates).
fn write_later_state<V: Vector>(w: &mut Writer, s: &SimState<V>, format: u32) {
    if format >= 8 {
        w.f64(s.diffusion_dissipation);
        w.f64(s.diffusion_power);
    }
    if format >= 9 {
        w.u64(s.removed);
        w.f64(s.removed_energy);
    }
    if format >= 10 {
        w.f64(s.earliest_dt);
        w.vectors(&s.fluid.earliest_acceleration);
        w.f64s(&s.fluid.earliest_density_rate);
    }
}

/// Reads a payload of layout `format` (the inverse of [`encode_payload`]); a payload with
/// bytes left over is refused.
fn decode_payload<V: Vector>(bytes: &[u8], format: u32) -> Result<Checkpoint<V>, String> {
    let mut r = Reader { bytes, at: 0 };
    let case_source = r.str()?;
    let case_text = r.str()?;
    let mut sim = read_state(&mut r, format)?;
    let run = read_run(&mut r)?;
    let (history, probe_history) = read_histories(&mut r, format)?;
    let settling = if format >= 7 {
        read_settling(&mut r)?
    } else {
        None
    };
    read_later_state(&mut r, &mut sim, format)?;
    if r.at != bytes.len() {
        return Err(format!(
            "{} bytes left over after the payload",
            bytes.len() - r.at
        ));
    }
    Ok(Checkpoint {
        case_source,
        case_text,
        sim,
        run,
        history,
        probe_history,
        settling,
    })
}

/// See [`write_state`].
fn read_state<V: Vector>(r: &mut Reader, format: u32) -> Result<SimState<V>, String> {
    let has_earlier_rates = format >= 5;
    let mut s = SimState::<V> {
        time: r.f64()?,
        step: r.u64()?,
        last_dt: r.f64()?,
        earlier_dt: if has_earlier_rates { r.f64()? } else { 0.0 },
        wall_work: r.f64()?,
        wall_power: r.f64()?,
        viscous_dissipation: r.f64()?,
        viscous_power: r.f64()?,
        forcing_work: r.f64()?,
        body_force: single(r.vectors()?)?,
        flux_history: FluxHistory {
            last: r.f64()?,
            before_last: r.f64()?,
            force: r.f64()?,
        },
        last_iterations: r.u32()?,
        last_residue: r.f64()?,
        placed_at: r.f64()?,
        ..SimState::default()
    };
    s.fluid = Fluid {
        id: r.u32s()?,
        position: r.vectors()?,
        velocity: r.vectors()?,
        density: r.f64s()?,
        mass: r.f64s()?,
        pressure: r.f64s()?,
        acceleration: r.vectors()?,
        density_rate: r.f64s()?,
        gamma: r.f64s()?,
        grad_gamma: r.vectors()?,
        density_offset: r.f64s()?,
        earlier_acceleration: if has_earlier_rates {
            r.vectors()?
        } else {
            Vec::new()
        },
        earlier_density_rate: if has_earlier_rates {
            r.f64s()?
        } else {
            Vec::new()
        },
        ..Fluid::default()
    };
    if format >= 6 {
        s.neighbour_origin = r.vectors()?;
    }
    s.centre = r.vectors()?;
    s.normal = r.vectors()?;
    s.area = r.f64s()?;
    s.velocity = r.vectors()?;
    s.reach = r.f64s()?;
    s.max_reach = r.f64()?;
    s.pressure = r.f64s()?;
    s.corners = r.vectors()?;
    let n = r.len(28)?;
    for _ in 0..n {
        s.pistons.push((r.u32()?, r.f64()?, r.f64()?, r.f64()?));
    }
    let n = r.len(4 + 8 * FREE_BODY_VALUES)?;
    for _ in 0..n {
        let b = r.u32()?;
        let mut values = [0.0; FREE_BODY_VALUES];
        for x in values.iter_mut() {
            *x = r.f64()?;
        }
        s.free_bodies.push((b, values));
    }
    Ok(s)
}

/// See [`write_run`].
fn read_run(r: &mut Reader) -> Result<RunCounters, String> {
    let mut run = RunCounters {
        next_series: r.f64()?,
        next_frame: r.f64()?,
        frame_times: r.f64s()?,
        e0_total: r.f64()?,
        scale: r.f64()?,
        max_drift: r.f64()?,
        max_speed: r.f64()?,
        iterations_sum: r.u64()?,
        iterations_max: r.u32()?,
        residue_max: r.f64()?,
        unconverged: r.u64()?,
        ..RunCounters::default()
    };
    for l in run.csv_lengths.iter_mut() {
        *l = r.u64()?;
    }
    run.wall_seconds = r.f64()?;
    run.dt0 = r.f64()?;
    let n = r.len(8)?;
    for _ in 0..n {
        run.body_csv_lengths.push(r.u64()?);
    }
    run.fluid_body_max = r.f64()?;
    Ok(run)
}

/// Energy rows and probe rows (see [`write_histories`]).
type Histories = (Vec<[f64; ENERGY_COLUMNS]>, Vec<Vec<f64>>);

/// See [`write_histories`].
fn read_histories(r: &mut Reader, format: u32) -> Result<Histories, String> {
    let columns = energy_columns(format);
    let n = r.len(8 * columns)?;
    let mut history = Vec::with_capacity(n);
    for _ in 0..n {
        let mut row = [0.0; ENERGY_COLUMNS];
        for x in row[..columns].iter_mut() {
            *x = r.f64()?;
        }
        history.push(row);
    }
    let n = r.len(8)?;
    let mut probe_history = Vec::with_capacity(n);
    for _ in 0..n {
        probe_history.push(r.f64s()?);
    }
    Ok((history, probe_history))
}

/// See [`write_settling`].
fn read_settling(r: &mut Reader) -> Result<Option<SettleReport>, String> {
    match r.u32()? {
        0 => Ok(None),
        1 => {
            let steps = r.u64()?;
            let v = r.f64s()?;
            let [time, max_speed, max_acceleration, max_displacement, wall_seconds] = v[..] else {
                return Err(format!("{} settling values, expected 5", v.len()));
            };
            Ok(Some(SettleReport {
                steps,
                time,
                max_speed,
                max_acceleration,
                max_displacement,
                wall_seconds,
                ..SettleReport::starting()
            }))
        }
        flag => Err(format!("settling flag {flag}, expected 0 or 1")),
    }
}

/// See [`write_later_state`].
fn read_later_state<V: Vector>(
    r: &mut Reader,
    s: &mut SimState<V>,
    format: u32,
) -> Result<(), String> {
    if format >= 8 {
        s.diffusion_dissipation = r.f64()?;
        s.diffusion_power = r.f64()?;
    }
    if format >= 9 {
        s.removed = r.u64()?;
        s.removed_energy = r.f64()?;
    }
    if format >= 10 {
        s.earliest_dt = r.f64()?;
        s.fluid.earliest_acceleration = r.vectors()?;
        s.fluid.earliest_density_rate = r.f64s()?;
    }
    Ok(())
}

/// The whole file's bytes.
pub fn encode<V: Vector>(c: &Checkpoint<V>) -> Vec<u8> {
    encode_format(c, FORMAT_VERSION)
}

/// The file's bytes in layout `format` (the current one, or an older one that tests read back).
fn encode_format<V: Vector>(c: &Checkpoint<V>, format: u32) -> Vec<u8> {
    let payload = encode_payload(c, format);
    let mut w = Writer(Vec::with_capacity(payload.len() + 64));
    w.0.extend_from_slice(MAGIC);
    w.u32(format);
    w.str(BISPH_VERSION);
    w.u32(V::DIM as u32);
    w.u64(payload.len() as u64);
    w.0.extend_from_slice(&payload);
    let sum = fnv1a64(&w.0);
    w.u64(sum);
    w.0
}

/// The dimension a checkpoint file declares (read from its header only; the checksum is
/// checked by [`decode`]).
pub fn peek_dim(bytes: &[u8]) -> Option<u32> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(8).ok()? != MAGIC {
        return None;
    }
    r.u32().ok()?;
    r.str().ok()?;
    r.u32().ok()
}

/// Decodes a checkpoint file's bytes; `path` is for messages only.
pub fn decode<V: Vector>(path: &Path, bytes: &[u8]) -> Result<Checkpoint<V>, CheckpointError> {
    let foreign = |reason: String| CheckpointError::Foreign {
        path: path.to_path_buf(),
        reason,
    };
    let damaged = |reason: String| CheckpointError::Damaged {
        path: path.to_path_buf(),
        reason,
    };
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        return Err(foreign(
            "it does not start with the bisph checkpoint magic".into(),
        ));
    }
    let mut r = Reader { bytes, at: 8 };
    let format = r.u32().map_err(damaged)?;
    if !(OLDEST_FORMAT_READ..=FORMAT_VERSION).contains(&format) {
        return Err(foreign(format!(
            "checkpoint format {format}, this bisph reads formats {OLDEST_FORMAT_READ} to {FORMAT_VERSION}"
        )));
    }
    let version = r.str().map_err(damaged)?;
    if version != BISPH_VERSION {
        return Err(foreign(format!("written by bisph {version}")));
    }
    let dim = r.u32().map_err(damaged)?;
    if dim as usize != V::DIM {
        return Err(foreign(format!(
            "a {dim}-D checkpoint, the case is {}-D",
            V::DIM
        )));
    }
    if bytes.len() < r.at + 16 {
        return Err(damaged("truncated header".into()));
    }
    let (body, tail) = bytes.split_at(bytes.len() - 8);
    let mut sum = [0u8; 8];
    sum.copy_from_slice(tail);
    if fnv1a64(body) != u64::from_le_bytes(sum) {
        return Err(damaged("checksum mismatch (truncated or altered)".into()));
    }
    let mut r = Reader {
        bytes: body,
        at: r.at,
    };
    let n = r.len(1).map_err(&damaged)?;
    let payload = r.take(n).map_err(&damaged)?;
    if r.at != body.len() {
        return Err(damaged("bytes after the payload".into()));
    }
    decode_payload(payload, format).map_err(damaged)
}

/// Reads and decodes `path`.
pub fn read<V: Vector>(path: &Path) -> Result<Checkpoint<V>, CheckpointError> {
    let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    decode(path, &bytes)
}

/// Writes the checkpoint to `path` through a temporary file, synced, then renamed, so a crash
/// leaves either the old checkpoint or the new one, never a half-written file.
pub fn write<V: Vector>(path: &Path, c: &Checkpoint<V>) -> Result<(), OutputError> {
    crate::formats::files::write_atomic(path, &encode(c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn sample() -> Checkpoint<DVec2> {
        let mut c = Checkpoint::<DVec2> {
            case_source: "cases/x.toml".into(),
            case_text: "name = \"x\"".into(),
            ..Default::default()
        };
        c.sim.time = 0.25;
        c.sim.step = 7;
        for k in 0..5 {
            let x = k as f64;
            c.sim
                .fluid
                .push(DVec2::new(x, -x), DVec2::new(0.5, x), 1000.0 + x, 0.1, x);
        }
        c.sim.fluid.id.reverse();
        c.sim.centre = vec![DVec2::new(1.0, 2.0)];
        c.sim.normal = vec![DVec2::Y];
        c.sim.area = vec![0.1];
        c.sim.velocity = vec![DVec2::X];
        c.sim.reach = vec![0.05];
        c.sim.pressure = vec![3.0];
        c.sim.corners = vec![DVec2::ZERO, DVec2::X];
        c.sim.neighbour_origin = c.sim.fluid.position.iter().map(|&x| x * 0.5).collect();
        c.sim.pistons = vec![(1, 0.1, -0.2, 0.3)];
        let mut free = FreeBody::new(
            2.0,
            glam::DMat3::IDENTITY,
            DQuat::from_rotation_z(0.3),
            DVec3::new(0.0, -9.81, 0.0),
        );
        free.position = DVec3::new(0.1, -0.2, 0.0);
        free.velocity = DVec3::new(0.5, 0.25, 0.0);
        free.angular_velocity = DVec3::new(0.0, 0.0, 1.5);
        free.acceleration = DVec3::new(-1.0, 2.0, 0.0);
        free.angular_acceleration = DVec3::new(0.0, 0.0, -3.0);
        c.sim.free_bodies = vec![(2, free_body_values(&free))];
        c.run.body_csv_lengths = vec![1234];
        c.run.fluid_body_max = 0.01;
        c.run.frame_times = vec![0.0, 0.1];
        c.run.csv_lengths = [10, 20, 30, 0, 0, 40];
        c.sim.viscous_dissipation = 0.5;
        c.sim.forcing_work = 0.75;
        c.sim.body_force = DVec2::new(1e-3, 0.0);
        c.sim.flux_history.last = 0.9;
        c.sim.diffusion_dissipation = 0.125;
        c.sim.diffusion_power = -0.5;
        c.sim.removed = 3;
        c.sim.removed_energy = 0.375;
        c.history = vec![[1.0, 2.0, 3.0, 4.0, 5.0, f64::NAN, 7.0, 8.0, 9.0, 10.0]];
        c.probe_history = vec![vec![0.0, 1.0], vec![0.1, 2.0]];
        c.settling = Some(SettleReport {
            steps: 321,
            time: 1.5,
            max_speed: 0.02,
            max_acceleration: 0.3,
            max_displacement: 0.004,
            wall_seconds: 12.0,
            ..SettleReport::starting()
        });
        c
    }

    #[test]
    fn round_trip_is_exact() {
        let c = sample();
        let bytes = encode(&c);
        let back = decode::<DVec2>(Path::new("x"), &bytes).unwrap();
        // NaN != NaN: compare the encodings.
        assert_eq!(encode(&back), bytes);
        assert_eq!(back.sim.fluid.id, c.sim.fluid.id);
        assert_eq!(back.sim.pistons, c.sim.pistons);
        assert_eq!(back.sim.free_bodies, c.sim.free_bodies);
        assert_eq!(back.run.body_csv_lengths, vec![1234]);
        assert_eq!(back.settling, c.settling);
        let mut b = FreeBody::new(1.0, glam::DMat3::IDENTITY, DQuat::IDENTITY, DVec3::ZERO);
        set_free_body_values(&mut b, &c.sim.free_bodies[0].1);
        assert_eq!(free_body_values(&b), c.sim.free_bodies[0].1);
        assert_eq!(b.attitude, DQuat::from_rotation_z(0.3));
    }

    #[test]
    fn other_formats_are_refused_by_name() {
        let mut bytes = encode(&sample());
        bytes[8..12].copy_from_slice(&3u32.to_le_bytes());
        let e = decode::<DVec2>(Path::new("old.bin"), &bytes).unwrap_err();
        assert!(matches!(e, CheckpointError::Foreign { .. }), "{e}");
        assert!(
            e.to_string()
                .contains("checkpoint format 3, this bisph reads formats 4 to 10"),
            "{e}"
        );
    }

    /// `c` as a layout before format 9 keeps it: no removed particles.
    fn without_removal(mut c: Checkpoint<DVec2>) -> Checkpoint<DVec2> {
        c.sim.removed = 0;
        c.sim.removed_energy = 0.0;
        for row in &mut c.history {
            row[ENERGY_COLUMNS - 1] = 0.0;
        }
        c
    }

    /// `c` as a layout before format 8 keeps it: no removed particles and no density
    /// diffusion books.
    fn without_diffusion_books(c: Checkpoint<DVec2>) -> Checkpoint<DVec2> {
        let mut c = without_removal(c);
        c.sim.diffusion_dissipation = 0.0;
        c.sim.diffusion_power = 0.0;
        for row in &mut c.history {
            row[ENERGY_COLUMNS - 2] = 0.0;
        }
        c
    }

    #[test]
    fn format_9_reads_without_the_earliest_rates() {
        let mut c = sample();
        let f = &mut c.sim.fluid;
        f.earlier_acceleration = f.acceleration.clone();
        f.earlier_density_rate = f.density_rate.clone();
        f.earliest_acceleration = f.velocity.clone();
        f.earliest_density_rate = f.pressure.clone();
        (c.sim.earlier_dt, c.sim.earliest_dt) = (1e-3, 2e-3);
        let whole = decode::<DVec2>(Path::new("v10.bin"), &encode(&c)).unwrap();
        assert_eq!(whole.sim.earliest_dt, 2e-3);
        assert_eq!(whole.sim.fluid.earliest_acceleration, c.sim.fluid.velocity);
        assert_eq!(encode(&whole), encode(&c));
        let back = decode::<DVec2>(Path::new("v9.bin"), &encode_format(&c, 9)).unwrap();
        assert_eq!(back.sim.earlier_dt, 1e-3);
        assert_eq!(back.sim.earliest_dt, 0.0);
        assert!(back.sim.fluid.earliest_acceleration.is_empty());
        assert!(back.sim.fluid.earliest_density_rate.is_empty());
        c.sim.earliest_dt = 0.0;
        c.sim.fluid.earliest_acceleration.clear();
        c.sim.fluid.earliest_density_rate.clear();
        assert_eq!(encode(&back), encode(&c));
    }

    #[test]
    fn format_8_reads_without_removed_particles() {
        let c = sample();
        let back = decode::<DVec2>(Path::new("v8.bin"), &encode_format(&c, 8)).unwrap();
        assert_eq!((back.sim.removed, back.sim.removed_energy), (0, 0.0));
        assert_eq!(back.history[0][ENERGY_COLUMNS - 1], 0.0);
        assert_eq!(back.sim.diffusion_dissipation, c.sim.diffusion_dissipation);
        assert_eq!(encode(&back), encode(&without_removal(c)));
    }

    #[test]
    fn format_7_reads_without_the_diffusion_books() {
        let c = sample();
        let back = decode::<DVec2>(Path::new("v7.bin"), &encode_format(&c, 7)).unwrap();
        assert_eq!(back.sim.diffusion_dissipation, 0.0);
        assert_eq!(back.history[0][ENERGY_COLUMNS - 2], 0.0);
        assert_eq!(back.settling, c.settling);
        assert_eq!(encode(&back), encode(&without_diffusion_books(c)));
    }

    #[test]
    fn format_6_reads_without_a_settling_stage() {
        let mut c = without_diffusion_books(sample());
        let back = decode::<DVec2>(Path::new("v6.bin"), &encode_format(&c, 6)).unwrap();
        assert_eq!(back.settling, None);
        c.settling = None;
        assert_eq!(encode(&back), encode(&c));
    }

    #[test]
    fn format_5_reads_without_the_neighbour_list() {
        let mut c = without_diffusion_books(sample());
        c.settling = None;
        c.sim.neighbour_origin = c.sim.fluid.position.clone();
        let back = decode::<DVec2>(Path::new("v5.bin"), &encode_format(&c, 5)).unwrap();
        assert!(back.sim.neighbour_origin.is_empty());
        c.sim.neighbour_origin.clear();
        assert_eq!(encode(&back), encode(&c));
    }

    #[test]
    fn format_4_reads_without_the_earlier_rates() {
        let mut c = without_diffusion_books(sample());
        c.settling = None;
        c.sim.earlier_dt = 1e-3;
        c.sim.fluid.earlier_acceleration = c.sim.fluid.acceleration.clone();
        c.sim.fluid.earlier_density_rate = c.sim.fluid.density_rate.clone();
        let back = decode::<DVec2>(Path::new("v4.bin"), &encode_format(&c, 4)).unwrap();
        assert_eq!(back.sim.earlier_dt, 0.0);
        assert!(back.sim.fluid.earlier_acceleration.is_empty());
        assert!(back.sim.fluid.earlier_density_rate.is_empty());
        c.sim.earlier_dt = 0.0;
        c.sim.neighbour_origin.clear();
        c.sim.fluid.earlier_acceleration.clear();
        c.sim.fluid.earlier_density_rate.clear();
        assert_eq!(encode(&back), encode(&c));
    }

    #[test]
    fn damaged_and_foreign_files_are_refused() {
        let bytes = encode(&sample());
        let p = Path::new("ck.bin");
        for cut in [0, 5, 8, 20, bytes.len() / 2, bytes.len() - 1] {
            assert!(decode::<DVec2>(p, &bytes[..cut]).is_err(), "cut {cut}");
        }
        for at in [9, 30, bytes.len() / 2, bytes.len() - 3] {
            let mut b = bytes.clone();
            b[at] ^= 0x10;
            let e = decode::<DVec2>(p, &b).unwrap_err();
            assert!(
                matches!(
                    e,
                    CheckpointError::Damaged { .. } | CheckpointError::Foreign { .. }
                ),
                "{e}"
            );
        }
        let e = decode::<glam::DVec3>(p, &bytes).unwrap_err();
        assert!(e.to_string().contains("2-D checkpoint"), "{e}");
        let e = decode::<DVec2>(p, b"PK\x03\x04 not a checkpoint").unwrap_err();
        assert!(e.to_string().contains("magic"), "{e}");
    }
}
