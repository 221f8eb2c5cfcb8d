//! Divergence diagnostics: watches on the state after every step, and the report written when
//! one trips (`diagnostics.json`).
//!
//! Besides the simulation's own stops (non-finite state, particle outside the domain, time
//! step below `min_dt`), the run watches:
//! - the density ratio `rho_i / rho0` against `[density_ratio_min, density_ratio_max]`;
//! - the particle speed against `speed_over_c0 * c0` (weak compressibility needs `|u| << c0`);
//! - the time step against `dt_collapse * dt0` (`dt0`: the first step's size);
//! - wall crossings: a particle whose path in the step went from the fluid side of a wall
//!   element's plane to its far side through the element itself, or which lies behind the
//!   wall surface (signed distance to the nearest element, however it got there);
//! - energy growth: `(E_total - E_total(0)) / E_scale > energy_growth`, at every series row.
//!
//! Particles are named by their original index (`id`), stable across reorderings. When several
//! particles trip at once they are listed worst first.

use crate::case::schema::DiagnosticsSection;
use crate::run::checkpoint::SimState;
use bisph_core::bodies::Motion;
use bisph_core::{SimError, Simulation, Vector};
use rayon::prelude::*;
use serde::Serialize;

/// What stopped a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TripKind {
    /// A position, velocity or density stopped being finite (or a density fell to zero).
    NonFinite,
    /// A particle left the `[domain]`.
    LeftDomain,
    /// The time step fell below `time.min_dt` or `diagnostics.dt_collapse * dt0`.
    TimeStepCollapse,
    /// A density ratio left its bounds.
    DensityRatio,
    /// A particle moved faster than `speed_over_c0 * c0`.
    Speed,
    /// A particle crossed a wall element.
    WallCrossing,
    /// The total energy grew beyond its bound.
    EnergyGrowth,
}

impl TripKind {
    /// Exit code of `bisph run` for this kind.
    pub fn exit_code(self) -> u8 {
        match self {
            TripKind::NonFinite => 20,
            TripKind::LeftDomain => 21,
            TripKind::TimeStepCollapse => 22,
            TripKind::DensityRatio => 23,
            TripKind::Speed => 24,
            TripKind::WallCrossing => 25,
            TripKind::EnergyGrowth => 26,
        }
    }

    /// All kinds (for documentation and tests).
    pub const ALL: [TripKind; 7] = [
        TripKind::NonFinite,
        TripKind::LeftDomain,
        TripKind::TimeStepCollapse,
        TripKind::DensityRatio,
        TripKind::Speed,
        TripKind::WallCrossing,
        TripKind::EnergyGrowth,
    ];
}

/// One particle named in a report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParticleReport {
    /// Original index.
    pub id: u32,
    /// Position at the trip.
    pub position: [f64; 3],
    /// Velocity at the trip.
    pub velocity: [f64; 3],
    /// Density at the trip.
    pub density: f64,
    /// The watched quantity's value for this particle.
    pub value: f64,
}

/// A tripped watch.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnosis {
    /// What tripped.
    pub kind: TripKind,
    /// Exit code of `bisph run`.
    pub exit_code: u8,
    /// The watched quantity.
    pub quantity: String,
    /// Worst value found.
    pub value: f64,
    /// The allowed range, in words.
    pub allowed: String,
    /// Step at which it tripped.
    pub step: u64,
    /// Time at which it tripped.
    pub time: f64,
    /// Particles involved, worst first (at most [`MAX_REPORTED`]).
    pub particles: Vec<ParticleReport>,
    /// How many particles tripped in all.
    pub particles_tripped: usize,
    /// Step of the last good state (saved in the checkpoint and the last VTK frame).
    pub last_good_step: u64,
    /// Time of the last good state.
    pub last_good_time: f64,
    /// The checkpoint holding the last good state (relative to the output directory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checkpoint: Option<String>,
    /// The VTK frame holding the last good state (relative to the output directory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vtk_frame: Option<String>,
}

impl std::fmt::Display for Diagnosis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.kind {
            TripKind::NonFinite | TripKind::LeftDomain => write!(
                f,
                "{} outside {} at step {} (t = {:.6e} s)",
                self.quantity, self.allowed, self.step, self.time
            )?,
            _ => write!(
                f,
                "{} = {:.6e} outside {} at step {} (t = {:.6e} s)",
                self.quantity, self.value, self.allowed, self.step, self.time
            )?,
        }
        if let Some(p) = self.particles.first() {
            write!(
                f,
                ", particle {} at {:?}{}",
                p.id,
                p.position,
                if self.particles_tripped > 1 {
                    format!(" (and {} more)", self.particles_tripped - 1)
                } else {
                    String::new()
                }
            )?;
        }
        Ok(())
    }
}

/// Most particles listed in a report.
pub const MAX_REPORTED: usize = 10;

fn report<V: Vector>(sim: &Simulation<V>, i: usize, value: f64) -> ParticleReport {
    let f = &sim.fluid;
    ParticleReport {
        id: f.id[i],
        position: f.position[i].to_xyz(),
        velocity: f.velocity[i].to_xyz(),
        density: f.density[i],
        value,
    }
}

/// A diagnosis for one of the simulation's own stops, naming its particle from the current
/// (bad) state. In a split run every part must call it (it gathers the particle from its
/// owner), and each gets the same diagnosis.
pub fn from_sim_error<V: Vector>(e: &SimError, sim: &Simulation<V>) -> Diagnosis {
    let (kind, quantity, allowed, value, particle) = match e {
        SimError::NonFinite {
            particle, quantity, ..
        } => (
            TripKind::NonFinite,
            format!("particle {quantity}"),
            "finite numbers (positive density)".to_string(),
            f64::NAN,
            Some(*particle),
        ),
        SimError::LeftDomain { particle, .. } => (
            TripKind::LeftDomain,
            "particle position".to_string(),
            format!(
                "the domain {:?} to {:?} ({} particles left it before and were removed, at most \
                 {} may: diagnostics.removed_fraction_max)",
                sim.config.domain_min.to_xyz(),
                sim.config.domain_max.to_xyz(),
                sim.removed,
                sim.config.max_removed
            ),
            f64::NAN,
            Some(*particle),
        ),
        SimError::TimeStepCollapse { dt, .. } => (
            TripKind::TimeStepCollapse,
            "time step".to_string(),
            format!(">= time.min_dt = {:.3e} s", sim.config.min_dt),
            *dt,
            None,
        ),
    };
    let (step, time) = match e {
        SimError::NonFinite { step, time, .. }
        | SimError::LeftDomain { step, time, .. }
        | SimError::TimeStepCollapse { step, time, .. } => (*step, *time),
    };
    let named = match particle {
        Some(id) => {
            let own = &sim.fluid.id[..sim.owned_len()];
            let found = own.iter().position(|&k| k == id);
            let local: Vec<_> = found
                .map(|i| (0.0, report(sim, i, value)))
                .into_iter()
                .collect();
            worst_over_parts(sim, local.len(), local, 1)
        }
        None => largest_acceleration(sim),
    };
    let particles: Vec<ParticleReport> = named.worst.into_iter().map(|(_, r)| r).collect();
    Diagnosis {
        kind,
        exit_code: kind.exit_code(),
        quantity,
        value,
        allowed,
        step,
        time,
        particles_tripped: particles.len(),
        particles,
        last_good_step: 0,
        last_good_time: 0.0,
        checkpoint: None,
        vtk_frame: None,
    }
}

/// The particle with the largest acceleration (the lowest id among equals), over every part.
fn largest_acceleration<V: Vector>(sim: &Simulation<V>) -> Violators {
    fastest(sim, &sim.fluid.acceleration)
}

/// The particle with the largest `|v|` of `values` (the lowest id among equals), over the own
/// particles of every part, with `|v|` as its value.
fn fastest<V: Vector>(sim: &Simulation<V>, values: &[V]) -> Violators {
    let id = &sim.fluid.id;
    let local = (0..sim.owned_len()).max_by(|&i, &j| {
        values[i]
            .length_squared()
            .total_cmp(&values[j].length_squared())
            .then(id[j].cmp(&id[i]))
    });
    let local: Vec<_> = local
        .map(|i| {
            let v = values[i].length();
            (v, report(sim, i, v))
        })
        .into_iter()
        .collect();
    let mut found = worst_over_parts(sim, local.len(), local, 1);
    found.count = found.worst.len();
    found
}

/// Particles named by a watch: the worst few, worst first with their severities, and how many
/// there were in all.
struct Violators {
    worst: Vec<(f64, ParticleReport)>,
    count: usize,
}

/// Words of one [`ParticleReport`] with its severity in a message.
const REPORT_WORDS: usize = 10;

/// The `limit` worst of `local` (some of this simulation's `count` own particles named by a
/// watch, each with its severity) over every part, worst first (ties by id), and how many
/// were named in all: in a split run every part must call it, and each gets the same list,
/// the one a whole run finds.
fn worst_over_parts<V: Vector>(
    sim: &Simulation<V>,
    mut count: usize,
    mut local: Vec<(f64, ParticleReport)>,
    limit: usize,
) -> Violators {
    let order = |a: &(f64, ParticleReport), b: &(f64, ParticleReport)| {
        b.0.total_cmp(&a.0).then(a.1.id.cmp(&b.1.id))
    };
    local.sort_by(order);
    local.truncate(limit);
    if !sim.is_part() {
        return Violators {
            worst: local,
            count,
        };
    }
    let mut words = vec![count as u64];
    for (severity, r) in &local {
        words.extend([severity.to_bits(), u64::from(r.id)]);
        words.extend(r.position.iter().chain(&r.velocity).map(|x| x.to_bits()));
        words.extend([r.density.to_bits(), r.value.to_bits()]);
    }
    let mut worst = Vec::new();
    count = 0;
    for message in sim.gather_over_parts(words) {
        count += message[0] as usize;
        for w in message[1..].chunks_exact(REPORT_WORDS) {
            let x = |k: usize| f64::from_bits(w[k]);
            let report = ParticleReport {
                id: w[1] as u32,
                position: [x(2), x(3), x(4)],
                velocity: [x(5), x(6), x(7)],
                density: x(8),
                value: x(9),
            };
            worst.push((x(0), report));
        }
    }
    worst.sort_by(order);
    worst.truncate(limit);
    Violators { worst, count }
}

/// The watches, with their scratch buffers.
#[derive(Debug, Default)]
pub struct Watch {
    /// Settings.
    pub settings: DiagnosticsSection,
    previous_index: Vec<u32>,
}

impl Watch {
    /// Watches with these settings.
    pub fn new(settings: DiagnosticsSection) -> Self {
        Watch {
            settings,
            previous_index: Vec::new(),
        }
    }

    /// Checks the state after a step; `previous` is the state before it, `dt0` the first
    /// step's size. Returns the first watch that trips, in the order of [`TripKind`]. Removes
    /// the particles that came round the walls while the run may lose them
    /// ([`Watch::wall_crossing`]).
    pub fn check<V: Vector>(
        &mut self,
        sim: &mut Simulation<V>,
        previous: &SimState<V>,
        dt0: f64,
    ) -> Option<Diagnosis> {
        let s = self.settings.clone();
        if !s.enabled {
            return None;
        }
        if s.wall_crossing && !sim.walls.elements.is_empty() {
            if let Some(d) = self.wall_crossing(sim, previous) {
                return Some(d);
            }
        }
        let rho0 = sim.config.eos.rho0();
        let (lo, hi) = (s.density_ratio_min, s.density_ratio_max);
        let bad = violators(sim, |i| {
            let ratio = sim.fluid.density[i] / rho0;
            if ratio < lo {
                Some((lo / ratio, ratio))
            } else if ratio > hi {
                Some((ratio / hi, ratio))
            } else {
                None
            }
        });
        if bad.count > 0 {
            return Some(diagnosis(
                sim,
                TripKind::DensityRatio,
                "density ratio rho / rho0",
                format!("[{lo}, {hi}] (diagnostics.density_ratio_min/max)"),
                bad,
            ));
        }
        let c0 = sim.config.eos.c0();
        let limit = s.speed_over_c0 * c0;
        let bad = violators(sim, |i| {
            let u = sim.fluid.velocity[i].length();
            (u > limit).then_some((u, u))
        });
        if bad.count > 0 {
            return Some(diagnosis(
                sim,
                TripKind::Speed,
                "particle speed [m/s]",
                format!(
                    "<= {} c0 = {limit:.4e} m/s (diagnostics.speed_over_c0)",
                    s.speed_over_c0
                ),
                bad,
            ));
        }
        if dt0 > 0.0 && s.dt_collapse > 0.0 {
            let dt = sim.next_dt();
            if dt < s.dt_collapse * dt0 {
                let mut d = diagnosis(
                    sim,
                    TripKind::TimeStepCollapse,
                    "next time step [s]",
                    format!(
                        ">= {} dt0 = {:.4e} s (diagnostics.dt_collapse)",
                        s.dt_collapse,
                        s.dt_collapse * dt0
                    ),
                    largest_acceleration(sim),
                );
                d.value = dt;
                return Some(d);
            }
        }
        None
    }

    /// Particles more than `h / 100` behind a wall (a moving wall may sweep over a particle
    /// by a hair within a step; the wall term pushes it back the next one), by two tests:
    /// - the straight path over the step crossed an element from its fluid side
    ///   (`(r - c_j) . n_j <= 0`, normals point out of the fluid) to its far side, through the
    ///   element's own extent (a fast particle through a thin wall);
    /// - the particle now lies behind the wall surface: its signed distance to the nearest
    ///   element within the kernel support less the largest element reach (at least half the
    ///   support), with pseudonormals at corners and edges, is positive
    ///   ([`bisph_core::walls::Walls::signed_distance`]). This catches crossings built up over
    ///   many steps, each too small for the path test. Particles within that distance of a
    ///   moving body's walls are left to the path test (a moving wall
    ///   may end a step a little past a particle it sweeps over).
    ///
    /// The depth reported is the larger of the two. A particle found by the second test alone,
    /// within a kernel support of a free edge of the walls (the rim of an open side,
    /// [`bisph_core::walls::Walls::near_free_edge`]), or coming from beyond the reach of every
    /// wall or from behind a wall by more than h/100 already, came round the walls to their
    /// back: it left the water's region, and is removed like a particle leaving the domain
    /// ([`Simulation::remove_own`]) while the run may lose it, at any depth: left there, its
    /// wall terms would see the walls from behind and the water in front through them. The
    /// others stop the run.
    fn wall_crossing<V: Vector>(
        &mut self,
        sim: &mut Simulation<V>,
        previous: &SimState<V>,
    ) -> Option<Diagnosis> {
        let behind = self.behind_walls(sim, previous);
        let depth = |i: usize, around: bool| {
            let k = behind.binary_search_by_key(&i, |b| b.0).ok()?;
            match behind[k].1 {
                Behind::Crossed(d) if !around => Some((d, d)),
                Behind::Around(d) if around => Some((d, d)),
                _ => None,
            }
        };
        let flagged = violators(sim, |i| depth(i, false).or(depth(i, true)));
        if flagged.count == 0 {
            return None;
        }
        let allowed = format!(
            "at most h/100 = {:e} (particles stay on the fluid side; diagnostics.wall_crossing)",
            0.01 * sim.config.kernel.h
        );
        let quantity = "depth behind a crossed wall element [m]";
        let crossed = violators(sim, |i| depth(i, false));
        if crossed.count > 0 {
            return Some(diagnosis(
                sim,
                TripKind::WallCrossing,
                quantity,
                allowed,
                crossed,
            ));
        }
        let around: Vec<usize> = behind.iter().map(|b| b.0).collect();
        if sim.remove_own(&around) {
            return None;
        }
        let around = violators(sim, |i| depth(i, true));
        let allowed = format!(
            "{allowed}; these came round the walls, over the free edge of a wall or from open \
             space, and {} particles left before and were removed, at most {} may \
             (diagnostics.removed_fraction_max)",
            sim.removed, sim.config.max_removed
        );
        Some(diagnosis(
            sim,
            TripKind::WallCrossing,
            quantity,
            allowed,
            around,
        ))
    }

    /// The own particles that lie behind a wall ([`Watch::wall_crossing`]), in increasing
    /// index, and how they got there.
    fn behind_walls<V: Vector>(
        &mut self,
        sim: &Simulation<V>,
        previous: &SimState<V>,
    ) -> Vec<(usize, Behind)> {
        let f = &sim.fluid;
        // Where each particle was before the step, by id. A part of a split run finds there
        // its own particles and its halo of that moment: a particle it took over at a cut of
        // new regions during the step may be missing, and is then tested as if it had not
        // moved.
        let ids = previous.fluid.id.iter();
        let slots = ids.clone().max().map_or(0, |&m| m as usize + 1);
        self.previous_index.clear();
        self.previous_index.resize(slots, u32::MAX);
        for (k, &id) in ids.enumerate() {
            self.previous_index[id as usize] = k as u32;
        }
        let e = &sim.walls.elements;
        let support = sim.config.kernel.support;
        let tolerance = 0.01 * sim.config.kernel.h;
        // The gradual-crossing search reaches one wall-grid cell (the kernel support) with the
        // element reach included: a particle drifting behind a wall is caught while shallow,
        // so a deeper search would only visit five times the cells in 3-D.
        let behind_search = (support - e.max_reach).max(0.5 * support);
        let index = &self.previous_index;
        let moving = sim.walls.has_moving_bodies();
        let clearance = sim.wall_clearance();
        (0..sim.owned_len())
            .into_par_iter()
            .filter_map(|i| {
                let p1 = f.position[i];
                // The position before the step (the particle itself when it has none).
                let p0 = index
                    .get(f.id[i] as usize)
                    .and_then(|&k| previous.fluid.position.get(k as usize))
                    .copied()
                    .unwrap_or(p1);
                // A path through an element ends within the step's length of the wall, and a
                // particle at most `tolerance` behind a wall before the step lies at most that
                // plus the step's length from it after: farther, neither test can trip.
                if clearance.clear(i, (p1 - p0).length() + tolerance) {
                    return None;
                }
                let radius = ((p1 - p0).length() + e.max_reach).min(support);
                let mut depth: Option<f64> = None;
                let mut through = false;
                sim.walls
                    .grid
                    .for_each_neighbour(p1, &e.centre, radius, |j, _, _| {
                        let (c, nrm) = (e.centre[j], e.normal[j]);
                        let s0 = (p0 - c).dot(nrm);
                        let s1 = (p1 - c).dot(nrm);
                        if !(s0 <= 0.0 && s1 > 0.0) {
                            return;
                        }
                        let x = p0 + (p1 - p0) * (-s0 / (s1 - s0));
                        if inside_element(x, nrm, e.current_corners(j)) {
                            depth = Some(depth.map_or(s1, |d: f64| d.max(s1)));
                            through = true;
                        }
                    });
                // Gradual crossings: the particle lies behind the wall surface now, whatever its
                // path (the signed distance to the nearest element, with pseudonormals at corners).
                // Near a moving body's walls only the path test applies: a moving wall may end a
                // step a little past a particle it sweeps over (the wall term pushes it back).
                let mut near_moving = false;
                if moving {
                    sim.walls.grid.for_each_neighbour(
                        p1,
                        &e.centre,
                        behind_search + e.max_reach,
                        |j, _, _| {
                            near_moving |= !matches!(
                                sim.walls.bodies[e.body[j] as usize].motion,
                                Motion::Fixed
                            );
                        },
                    );
                }
                if !near_moving && sim.walls.may_be_behind(p1, behind_search) {
                    if let Some(behind) = sim.walls.signed_distance(p1, behind_search) {
                        if behind > 0.0 {
                            depth = Some(depth.map_or(behind, |d: f64| d.max(behind)));
                        }
                    }
                }
                let depth = depth.filter(|&d| d > 0.0)?;
                // Round the walls: over a free edge, or from a place before the step beyond
                // every wall's reach or already behind a wall by more than the tolerance (a
                // particle in front of the walls is caught as soon as it gets that deep, so this
                // one never was in front: it came over a rim out of the watch's reach and falls
                // down the back of the wall).
                let around = !through
                    && (sim.walls.near_free_edge(p1, support)
                        || (p0 != p1
                            && sim
                                .walls
                                .signed_distance(p0, behind_search)
                                .is_none_or(|d0| d0 > tolerance)));
                if around {
                    Some((i, Behind::Around(depth)))
                } else {
                    (depth > tolerance).then_some((i, Behind::Crossed(depth)))
                }
            })
            .collect()
    }
}

/// How a particle came to lie behind a wall.
#[derive(Clone, Copy, Debug)]
enum Behind {
    /// Through the wall, to this depth (more than h/100): its path crossed an element, or it
    /// lies behind the wall away from any free edge.
    Crossed(f64),
    /// Round the walls, to this depth, without crossing an element in the step: over a free
    /// edge of a wall (the rim of an open side), or from beyond the reach of every wall or
    /// from behind a wall already (water that went over a rim earlier and falls down the back
    /// of the wall).
    Around(f64),
}

/// `true` when `x` (on the element's plane) lies within the element: between the two end
/// points of a 2-D segment, inside the convex polygon of a 3-D element.
fn inside_element<V: Vector>(x: V, normal: V, corners: &[V]) -> bool {
    match corners.len() {
        0 | 1 => false,
        2 => {
            let (a, b) = (corners[0], corners[1]);
            let t = (x - a).dot(b - a);
            t >= 0.0 && t <= (b - a).length_squared()
        }
        m => {
            let n = normal.to_xyz();
            let mut sign = 0.0;
            for k in 0..m {
                let a = corners[k].to_xyz();
                let b = corners[(k + 1) % m].to_xyz();
                let p = x.to_xyz();
                let (e, r) = (
                    [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                    [p[0] - a[0], p[1] - a[1], p[2] - a[2]],
                );
                let c = [
                    e[1] * r[2] - e[2] * r[1],
                    e[2] * r[0] - e[0] * r[2],
                    e[0] * r[1] - e[1] * r[0],
                ];
                let s = c[0] * n[0] + c[1] * n[1] + c[2] * n[2];
                if s != 0.0 {
                    if sign != 0.0 && s.signum() != sign {
                        return false;
                    }
                    sign = s.signum();
                }
            }
            true
        }
    }
}

/// Particles for which `test` gives `(severity, value)`, over the own particles of every part
/// (see [`worst_over_parts`]): found in memory order through an ordered parallel collect, so
/// the result does not depend on threads.
fn violators<V: Vector>(
    sim: &Simulation<V>,
    test: impl Fn(usize) -> Option<(f64, f64)> + Sync,
) -> Violators {
    let mut bad: Vec<(usize, f64, f64)> = (0..sim.owned_len())
        .into_par_iter()
        .filter_map(|i| test(i).map(|(sev, v)| (i, sev, v)))
        .collect();
    let id = &sim.fluid.id;
    bad.sort_by(|a, b| b.1.total_cmp(&a.1).then(id[a.0].cmp(&id[b.0])));
    let local = bad
        .iter()
        .take(MAX_REPORTED)
        .map(|&(i, severity, v)| (severity, report(sim, i, v)))
        .collect();
    worst_over_parts(sim, bad.len(), local, MAX_REPORTED)
}

fn diagnosis<V: Vector>(
    sim: &Simulation<V>,
    kind: TripKind,
    quantity: &str,
    allowed: String,
    bad: Violators,
) -> Diagnosis {
    let value = bad.worst.first().map_or(f64::NAN, |b| b.1.value);
    Diagnosis {
        kind,
        exit_code: kind.exit_code(),
        quantity: quantity.to_string(),
        value,
        allowed,
        step: sim.step,
        time: sim.time,
        particles_tripped: bad.count,
        particles: bad.worst.into_iter().map(|(_, r)| r).collect(),
        last_good_step: 0,
        last_good_time: 0.0,
        checkpoint: None,
        vtk_frame: None,
    }
}

/// The energy-growth watch, at a series row.
pub fn energy_growth<V: Vector>(
    settings: &DiagnosticsSection,
    sim: &Simulation<V>,
    total: f64,
    e0: f64,
    scale: f64,
) -> Option<Diagnosis> {
    if !settings.enabled
        || settings.energy_growth.is_nan()
        || settings.energy_growth <= 0.0
        || scale.is_nan()
        || scale <= 0.0
    {
        return None;
    }
    let growth = (total - e0) / scale;
    if growth > settings.energy_growth || growth.is_nan() {
        // Name the fastest particle: energy grows where the speed does.
        let mut d = diagnosis(
            sim,
            TripKind::EnergyGrowth,
            "energy growth (E - E0) / E_scale",
            format!("<= {} (diagnostics.energy_growth)", settings.energy_growth),
            fastest(sim, &sim.fluid.velocity),
        );
        d.value = growth;
        return Some(d);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::build::build_simulation;
    use crate::case::load::parse_case;
    use glam::DVec2;

    /// A particle that creeps behind a wall by steps far below the path test's depth
    /// trips the watch once it lies more than h/100 behind; at rest in front it does not.
    #[test]
    fn gradual_crossing_trips_the_watch() {
        let text = include_str!("../../../../cases/dam-break-2d.toml");
        let loaded = parse_case("<dam-break-2d>", text, &["resolution.dx=0.02".into()]).unwrap();
        let mut sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
        let mut watch = Watch::new(loaded.case.diagnostics.clone());
        let mut previous = SimState::default();
        previous.capture(&sim);
        assert!(watch.check(&mut sim, &previous, 0.0).is_none());
        let h = sim.config.kernel.h;
        // The particle nearest the left wall, moved behind it: 0.009 h last step (within the
        // tolerance), 0.0115 h now.
        let i = (0..sim.fluid.len())
            .min_by(|&a, &b| {
                let (pa, pb) = (sim.fluid.position[a], sim.fluid.position[b]);
                (pa.x, pa.y).partial_cmp(&(pb.x, pb.y)).unwrap()
            })
            .unwrap();
        let y = sim.fluid.position[i].y;
        sim.fluid.position[i] = DVec2::new(-0.009 * h, y);
        previous.capture(&sim);
        sim.fluid.position[i] = DVec2::new(-0.0115 * h, y);
        let d = watch
            .check(&mut sim, &previous, 0.0)
            .expect("the watch trips");
        assert_eq!(d.kind, TripKind::WallCrossing);
        assert!((d.value - 0.0115 * h).abs() < 1e-12, "{}", d.value);
        assert_eq!(d.particles[0].id, sim.fluid.id[i]);
        // Behind by less than h/100: no trip.
        sim.fluid.position[i] = DVec2::new(-0.009 * h, y);
        previous.capture(&sim);
        assert!(watch.check(&mut sim, &previous, 0.0).is_none());
    }

    /// The dam break at `dx = 0.02` in its tank without a lid, with `removed_fraction_max`;
    /// its particle nearest the left wall.
    fn open_tank(removed_fraction_max: f64) -> (Simulation<DVec2>, Watch, usize) {
        let text = include_str!("../../../../cases/dam-break-2d.toml");
        let overrides = [
            "resolution.dx=0.02".to_string(),
            "wall.0.open=[\"+y\"]".to_string(),
            format!("diagnostics.removed_fraction_max={removed_fraction_max}"),
        ];
        let loaded = parse_case("<dam-break-2d>", text, &overrides).unwrap();
        let sim: Simulation<DVec2> = build_simulation(&loaded).unwrap();
        let watch = Watch::new(loaded.case.diagnostics.clone());
        let i = (0..sim.fluid.len())
            .min_by(|&a, &b| sim.fluid.position[a].x.total_cmp(&sim.fluid.position[b].x))
            .unwrap();
        (sim, watch, i)
    }

    /// Puts particle `i` behind the left wall at height `y`, `0.009 h` deep before the step
    /// (within the watch's tolerance) and `0.06 h` after it (no path through an element), and
    /// checks the state; the energy total before the check.
    fn behind_left_wall(
        sim: &mut Simulation<DVec2>,
        watch: &mut Watch,
        i: usize,
        y: f64,
    ) -> (Option<Diagnosis>, f64) {
        let h = sim.config.kernel.h;
        sim.fluid.position[i] = DVec2::new(-0.009 * h, y);
        let mut previous = SimState::default();
        previous.capture(sim);
        sim.fluid.position[i] = DVec2::new(-0.06 * h, y);
        let total = sim.energy().total;
        (watch.check(sim, &previous, 0.0), total)
    }

    /// Water that went over the rim of the open tank's wall (behind it, just below its top,
    /// without crossing an element) left the tank: it is removed, within the allowance, as is
    /// water that comes to the back of the wall from beyond its reach. Behind the wall away
    /// from the rim, from in front of it, it went through the wall: the watch trips.
    #[test]
    fn water_over_the_rim_of_an_open_wall_is_removed() {
        let (mut sim, mut watch, i) = open_tank(0.01);
        let (n, id) = (sim.fluid.len(), sim.fluid.id[i]);
        let (tripped, e0) = behind_left_wall(&mut sim, &mut watch, i, 0.59);
        assert!(tripped.is_none());
        assert_eq!((sim.removed, sim.fluid.len()), (1, n - 1));
        assert!(!sim.fluid.id.contains(&id));
        let e = sim.energy();
        assert!(
            e.removed != 0.0 && (e.total - e0).abs() <= 1e-12 * e0.abs(),
            "{e:?}"
        );

        let (mut sim, mut watch, i) = open_tank(0.01);
        let d = behind_left_wall(&mut sim, &mut watch, i, 0.3)
            .0
            .expect("the watch trips");
        assert_eq!(
            (d.kind, d.particles[0].id),
            (TripKind::WallCrossing, sim.fluid.id[i])
        );
        assert_eq!(sim.removed, 0);

        // Falling down the back of the wall from beyond its reach: removed as well.
        let (mut sim, mut watch, i) = open_tank(0.01);
        let h = sim.config.kernel.h;
        sim.fluid.position[i] = DVec2::new(-0.2, 0.35);
        let mut previous = SimState::default();
        previous.capture(&sim);
        sim.fluid.position[i] = DVec2::new(-0.06 * h, 0.3);
        assert!(watch.check(&mut sim, &previous, 0.0).is_none());
        assert_eq!(sim.removed, 1);

        // Less than h/100 behind: over the rim it is removed all the same (its wall terms would
        // see the wall from behind); away from the rim the wall term pushes it back.
        for (y, removed) in [(0.59, 1), (0.3, 0)] {
            let (mut sim, mut watch, i) = open_tank(0.01);
            let h = sim.config.kernel.h;
            sim.fluid.position[i] = DVec2::new(-0.0005 * h, y);
            let mut previous = SimState::default();
            previous.capture(&sim);
            sim.fluid.position[i] = DVec2::new(-0.001 * h, y);
            assert!(watch.check(&mut sim, &previous, 0.0).is_none());
            assert_eq!(sim.removed, removed, "y = {y}");
        }

        let (mut sim, mut watch, i) = open_tank(0.0);
        let d = behind_left_wall(&mut sim, &mut watch, i, 0.59)
            .0
            .expect("no allowance");
        assert_eq!(d.kind, TripKind::WallCrossing);
        assert!(d.allowed.contains("free edge of a wall"), "{}", d.allowed);
        assert_eq!(sim.removed, 0);
    }
}
