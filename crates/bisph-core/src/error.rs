//! Errors a running simulation can stop with.

/// Why a simulation stopped before its end time.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A particle's state stopped being a finite number.
    #[error("particle {particle} has a non-finite {quantity} at step {step} (t = {time:.6e} s)")]
    NonFinite {
        /// Original index of the particle.
        particle: u32,
        /// Which quantity (`position`, `velocity`, `density`).
        quantity: &'static str,
        /// Step number.
        step: u64,
        /// Time.
        time: f64,
    },
    /// A particle left the computational domain.
    #[error("particle {particle} left the domain at step {step} (t = {time:.6e} s), position {position:?}")]
    LeftDomain {
        /// Original index of the particle.
        particle: u32,
        /// Where it was.
        position: [f64; 3],
        /// Step number.
        step: u64,
        /// Time.
        time: f64,
    },
    /// The time step fell below the allowed minimum.
    #[error("time step collapsed to {dt:.3e} s at step {step} (t = {time:.6e} s)")]
    TimeStepCollapse {
        /// The step size.
        dt: f64,
        /// Step number.
        step: u64,
        /// Time.
        time: f64,
    },
}
