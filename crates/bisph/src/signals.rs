//! SIGINT and SIGTERM: the first asks the runs to finish their step, write a checkpoint and
//! stop (exit code 10); another one at least [`SAME_REQUEST`] later ends the process at once,
//! without a checkpoint, with exit code 128 + the signal's number.

use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Signals closer than this to the first are taken as the same request to stop: `timeout`
/// and some launchers signal both the process and its process group, so one request can
/// arrive twice, and the second must not end the run before its checkpoint.
pub const SAME_REQUEST: Duration = Duration::from_secs(1);

/// The line a second request writes to stderr as it ends the process.
const ENDED_AT_ONCE: &[u8] = b"stopped at once by a second signal: no checkpoint written\n";

/// A flag that the first SIGINT or SIGTERM sets; see the module documentation.
pub fn stop_on_signal() -> Result<Arc<AtomicBool>, String> {
    let stop = Arc::new(AtomicBool::new(false));
    let start = Instant::now();
    // Nanoseconds after `start` at which the first signal came (none yet: `u64::MAX`).
    let first = Arc::new(AtomicU64::new(u64::MAX));
    let same = SAME_REQUEST.as_nanos() as u64;
    for signal in [SIGINT, SIGTERM] {
        let (stop, first) = (Arc::clone(&stop), Arc::clone(&first));
        let action = move || {
            let now = start.elapsed().as_nanos() as u64;
            match first.compare_exchange(u64::MAX, now, Ordering::SeqCst, Ordering::SeqCst) {
                Ok(_) => stop.store(true, Ordering::SeqCst),
                Err(at) if now.saturating_sub(at) >= same => {
                    // SAFETY: writes a static buffer to the standard error descriptor.
                    unsafe { libc::write(2, ENDED_AT_ONCE.as_ptr().cast(), ENDED_AT_ONCE.len()) };
                    signal_hook::low_level::exit(128 + signal);
                }
                Err(_) => {}
            }
        };
        // SAFETY: the action only reads the monotonic clock (clock_gettime), does atomic
        // operations, and may end the process with write(2) and _exit(2): all
        // async-signal-safe, and it allocates nothing.
        unsafe { signal_hook::low_level::register(signal, action) }
            .map_err(|e| format!("cannot install the signal handler: {e}"))?;
    }
    Ok(stop)
}
