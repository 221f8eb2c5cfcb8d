//! Settings of the midpoint iterations and of settling, and what settling reports (the types
//! the integrators and [`super::Simulation::settle_from`] take and give, apart from their code).

/// Settings of the midpoint iterations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MidpointParams {
    /// Most fixed-point iterations per step.
    pub max_iterations: u32,
    /// Absolute residue (a power) below which the iterations stop.
    pub tolerance: f64,
    /// Geometric rate the residue must fall at; slower growth of `f` is triggered above it.
    pub min_decrease: f64,
    /// Relaxation increment `inc`.
    pub relax_increment: f64,
    /// Relaxation at the start of a step `f0` (0: none).
    pub initial_relaxation: f64,
    /// Differences of past iterations that Anderson's mixing uses (0: the plain or relaxed
    /// iteration; see [`super::anderson`]).
    pub anderson_depth: u32,
}

impl Default for MidpointParams {
    fn default() -> Self {
        MidpointParams {
            max_iterations: 10,
            tolerance: 0.0,
            min_decrease: 0.2,
            relax_increment: 0.25,
            initial_relaxation: 0.0,
            anderson_depth: 0,
        }
    }
}

/// How settling runs and when it stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettleParams {
    /// Damping rate `beta` [1/s] of `u <- u exp(-beta dt)`.
    pub damping: f64,
    /// Speed scale `U` [m/s] of the tolerances (e.g. `sqrt(g H)`).
    pub speed_scale: f64,
    /// At rest when every speed is below `speed_tolerance U` ...
    pub speed_tolerance: f64,
    /// ... and every acceleration below `acceleration_tolerance U beta`.
    pub acceleration_tolerance: f64,
    /// Most settling time [s] (of the case's own time scale) before giving up.
    pub max_time: f64,
    /// The fluid flows (is not in a resting configuration) once its kinetic energy exceeds
    /// this [J (per unit depth in 2-D)]: a dam-break column reaches a sizeable part of its
    /// potential energy within a fraction of `sqrt(H/g)`, while the imbalance of a resting
    /// start stays many orders of magnitude below it.
    pub max_kinetic: f64,
}

/// How settling ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SettleOutcome {
    /// At rest to the tolerances: the run starts from the settled state.
    Settled,
    /// Not at rest within `max_time`: the run starts from the state reached, at zero velocity.
    TimedOut,
    /// The fluid gained more kinetic energy than a resting start can release (it flows, as a
    /// dam-break column does, or the scheme is unstable): the original start is kept.
    NotAtRest,
    /// The caller stopped it between two steps: the state reached is kept, at zero velocity.
    Interrupted,
}

/// What settling did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettleReport {
    /// How it ended.
    pub outcome: SettleOutcome,
    /// Steps taken.
    pub steps: u64,
    /// Settling time [s].
    pub time: f64,
    /// Largest speed at the end [m/s] (before the velocities are zeroed).
    pub max_speed: f64,
    /// Largest acceleration at the end [m/s^2].
    pub max_acceleration: f64,
    /// Farthest a particle travelled from its start [m].
    pub max_displacement: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

impl SettleReport {
    /// The report before the first settling step.
    pub fn starting() -> Self {
        SettleReport {
            outcome: SettleOutcome::TimedOut,
            steps: 0,
            time: 0.0,
            max_speed: 0.0,
            max_acceleration: 0.0,
            max_displacement: 0.0,
            wall_seconds: 0.0,
        }
    }
}
