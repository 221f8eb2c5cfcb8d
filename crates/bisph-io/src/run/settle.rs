//! `[settle]`: from the case to the settling parameters, the checks that settling applies,
//! and what `summary.json` reports of it.

use crate::case::schema::LoadedCase;
use bisph_core::simulation::{SettleOutcome, SettleParams, SettleReport};
use bisph_core::{Simulation, Vector};
use serde::{Deserialize, Serialize};

/// Default tolerance of `settle.tolerance`.
pub const DEFAULT_TOLERANCE: f64 = 1e-3;

/// Settling time over `1 / beta` when `settle.max_time` is left out.
const DEFAULT_MAX_TIME_BETA: f64 = 200.0;

/// Kinetic energy over `M g H` above which the fluid counts as flowing.
const FLOW_KINETIC: f64 = 1e-3;

/// What `summary.json` (key `settling`) and `settling.json` report of the settling stage.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SettlingSummary {
    /// `"settled"`, `"timed_out"` (the run starts from the state reached, at rest) or
    /// `"not_at_rest"` (the fluid flows or the scheme is unstable: the original start is kept).
    pub outcome: String,
    /// Settling steps.
    pub steps: u64,
    /// Settling time [s].
    pub time: f64,
    /// Wall-clock seconds spent settling.
    pub wall_seconds: f64,
    /// Damping rate used [1/s].
    pub damping: f64,
    /// Largest speed at the end of settling [m/s].
    pub max_speed: f64,
    /// The same over `sqrt(g H)`.
    pub max_speed_relative: f64,
    /// Largest acceleration at the end of settling [m/s^2].
    pub max_acceleration: f64,
    /// Farthest a particle moved from its start [m].
    pub max_displacement: f64,
}

/// The outcome of settling stopped by the caller (never in `summary.json`: the run does not
/// start).
const INTERRUPTED: &str = "interrupted";

impl SettlingSummary {
    /// Whether the caller stopped settling before it ended.
    pub fn interrupted(&self) -> bool {
        self.outcome == INTERRUPTED
    }

    /// The summary of a settling stage that ended with `report`.
    pub(crate) fn new(report: &SettleReport, params: &SettleParams) -> Self {
        SettlingSummary {
            outcome: match report.outcome {
                SettleOutcome::Settled => "settled",
                SettleOutcome::TimedOut => "timed_out",
                SettleOutcome::NotAtRest => "not_at_rest",
                SettleOutcome::Interrupted => INTERRUPTED,
            }
            .into(),
            steps: report.steps,
            time: report.time,
            wall_seconds: report.wall_seconds,
            damping: params.damping,
            max_speed: report.max_speed,
            max_speed_relative: report.max_speed / params.speed_scale,
            max_acceleration: report.max_acceleration,
            max_displacement: report.max_displacement,
        }
    }
}

/// Whether the run settles first: as `settle.enabled` says, or, left out, when the case can
/// settle and its fluid rests against walls below a level free surface
/// ([`Simulation::rests_against_walls`]; a dam-break column does not).
pub fn settles<V: Vector>(loaded: &LoadedCase, sim: &Simulation<V>) -> bool {
    let c = &loaded.case;
    c.settle
        .enabled
        .unwrap_or_else(|| c.settle_obstacle().is_none() && sim.rests_against_walls())
}

/// The settling parameters of a built simulation (`None` when it does not settle,
/// [`settles`]).
pub fn params<V: Vector>(loaded: &LoadedCase, sim: &Simulation<V>) -> Option<SettleParams> {
    let s = &loaded.case.settle;
    if !settles(loaded, sim) {
        return None;
    }
    let gravity = sim.config.gravity;
    let g = gravity.length();
    // Particle centres lie half a spacing inside the water.
    let (depth, width) = fluid_extent(&sim.fluid.position, gravity);
    let depth = depth + sim.config.particle_spacing;
    let width = width + sim.config.particle_spacing;
    // Lowest sloshing mode of water of this width and depth: omega^2 = g k tanh(k H).
    let k = std::f64::consts::PI / width;
    let omega = (g * k * (k * depth).tanh()).sqrt();
    let damping = s.damping.unwrap_or(2.0 * omega);
    let mass: f64 = sim.fluid.mass.iter().sum();
    Some(SettleParams {
        damping,
        speed_scale: (g * depth).sqrt(),
        speed_tolerance: s.tolerance.unwrap_or(DEFAULT_TOLERANCE),
        acceleration_tolerance: s.tolerance.unwrap_or(DEFAULT_TOLERANCE),
        max_time: s.max_time.unwrap_or(DEFAULT_MAX_TIME_BETA / damping),
        max_kinetic: FLOW_KINETIC * mass * g * depth,
    })
}

/// Depth (extent along `g`) and width (largest extent along a coordinate axis across `g`) of
/// the particles.
fn fluid_extent<V: Vector>(points: &[V], gravity: V) -> (f64, f64) {
    let g = gravity.length();
    let down = gravity / g;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let first = points.first().copied().unwrap_or(V::ZERO);
    let (mut min, mut max) = (first, first);
    for &r in points {
        let height = -down.dot(r);
        lo = lo.min(height);
        hi = hi.max(height);
        min = min.min_by_component(r);
        max = max.max_by_component(r);
    }
    let width = (0..V::DIM)
        .filter(|&k| down.get(k).abs() < 0.5)
        .map(|k| max.get(k) - min.get(k))
        .fold(0.0, f64::max);
    (hi - lo, width)
}
