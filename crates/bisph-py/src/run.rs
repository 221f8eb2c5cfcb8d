//! Work done with the GIL released, on the simulation's thread pool, while the calling
//! thread watches for KeyboardInterrupt (and other signals) between steps.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyBool;
use rayon::ThreadPool;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

/// How often the calling thread looks for signals while the work runs.
const SIGNAL_POLL: Duration = Duration::from_millis(20);

/// Where a run stands, given to a progress callable after every step.
#[pyclass(module = "bisph", frozen, get_all)]
#[derive(Clone, Copy)]
pub struct Progress {
    /// Simulated time [s] (the settling time while `settling`).
    pub time: f64,
    /// The time the run goes to [s] (the most settling time while `settling`).
    pub end: f64,
    /// Steps so far (settling steps while `settling`).
    pub step: u64,
    /// `True` while settling before `t = 0`.
    pub settling: bool,
}

impl From<bisph_io::Progress> for Progress {
    fn from(p: bisph_io::Progress) -> Self {
        Progress {
            time: p.time,
            end: p.end,
            step: p.step,
            settling: p.settling,
        }
    }
}

#[pymethods]
impl Progress {
    fn __repr__(&self) -> String {
        format!(
            "Progress(time={}, end={}, step={}, settling={})",
            self.time,
            self.end,
            self.step,
            if self.settling { "True" } else { "False" }
        )
    }
}

/// The stop request of a piece of work: set when a signal handler raised (KeyboardInterrupt)
/// or a progress callable failed; the first such exception is kept to be raised at the end.
#[derive(Default)]
pub struct Stop {
    /// Read by the time loop between steps.
    pub flag: AtomicBool,
    error: Mutex<Option<PyErr>>,
    /// What the watching thread is told between its polls.
    watch: Mutex<Watch>,
    /// Signalled whenever `watch` changes.
    watch_changed: Condvar,
}

/// The hand-off between the work and the thread that watches for signals.
#[derive(Default)]
struct Watch {
    /// Signal checks asked for by the work, each after a progress callable ran (which may
    /// have raised a signal, e.g. by `_thread.interrupt_main()`).
    asked: u64,
    /// Checks asked for before the start of the last completed check (all answered by it).
    answered: u64,
    /// The work has ended (or unwound).
    done: bool,
}

impl Stop {
    /// Asks the work to stop, keeping `e` (the first one only) to raise afterwards.
    fn fail(&self, e: PyErr) {
        if let Ok(mut kept) = self.error.lock() {
            kept.get_or_insert(e);
        }
        self.flag.store(true, Ordering::SeqCst);
    }

    /// Whether a stop was asked for.
    pub fn requested(&self) -> bool {
        self.flag.load(Ordering::SeqCst)
    }

    /// The exception that asked for the stop, if any.
    pub fn take_error(&self) -> Option<PyErr> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }

    /// Calls the progress callable (if any) with `p`; an exception it raises stops the work.
    /// A signal raised meanwhile is checked before the next step, so the work stops right
    /// after the step that reported it.
    pub fn report(&self, progress: Option<&Py<PyAny>>, p: Progress) {
        let Some(callable) = progress else { return };
        Python::attach(|py| {
            if let Err(e) = callable.call1(py, (p,)) {
                self.fail(e);
            }
        });
        if !self.requested() {
            self.await_signal_check();
        }
    }

    fn lock_watch(&self) -> MutexGuard<'_, Watch> {
        self.watch.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Asks the watching thread for a signal check and waits for it; after `SIGNAL_POLL` the
    /// work goes on regardless (no thread may be watching).
    fn await_signal_check(&self) {
        let mut watch = self.lock_watch();
        watch.asked += 1;
        let ticket = watch.asked;
        self.watch_changed.notify_all();
        let _ = self
            .watch_changed
            .wait_timeout_while(watch, SIGNAL_POLL, |w| w.answered < ticket && !w.done);
    }

    /// Tells the watching thread that the work has ended.
    fn finish(&self) {
        self.lock_watch().done = true;
        self.watch_changed.notify_all();
    }

    /// Watches for signals until the work ends: every `SIGNAL_POLL`, and at once when a
    /// progress call asks. A raised signal stops the work.
    fn watch_signals(&self) {
        let mut watch = self.lock_watch();
        while !watch.done {
            watch = self
                .watch_changed
                .wait_timeout_while(watch, SIGNAL_POLL, |w| w.answered == w.asked && !w.done)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
            if watch.done {
                break;
            }
            // Every check asked for so far came before this one starts.
            let ticket = watch.asked;
            drop(watch);
            if !self.requested() {
                if let Err(e) = Python::attach(|py| py.check_signals()) {
                    self.fail(e);
                }
            }
            watch = self.lock_watch();
            watch.answered = ticket;
            self.watch_changed.notify_all();
        }
    }
}

/// Marks the work as ended when dropped, also when it unwinds from a panic.
struct Finished<'a>(&'a Stop);

impl Drop for Finished<'_> {
    fn drop(&mut self) {
        self.0.finish();
    }
}

/// The progress callable of a `progress=` argument: the callable itself, a printer of
/// progress lines on `sys.stderr` for `True`, nothing for `None` or `False`.
pub fn progress_callable(progress: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Py<PyAny>>> {
    let Some(p) = progress else { return Ok(None) };
    if p.is_instance_of::<PyBool>() {
        if !p.is_truthy()? {
            return Ok(None);
        }
        let printer = p.py().import("bisph._progress")?.call_method0("printer")?;
        return Ok(Some(printer.unbind()));
    }
    if !p.is_callable() {
        return Err(PyTypeError::new_err(
            "progress: expected a callable, True, False or None",
        ));
    }
    Ok(Some(p.clone().unbind()))
}

/// Runs `work` with the GIL released: on `pool` when given (else rayon's global pool) in a
/// worker thread, while this thread checks for signals every few milliseconds and after each
/// progress call, and sets `stop` when a handler raises (Ctrl-C raises KeyboardInterrupt). `work` reads `stop`
/// between steps, so it ends at a step boundary and leaves a usable state.
pub fn run_released<T: Send>(
    py: Python<'_>,
    pool: Option<&ThreadPool>,
    stop: &Stop,
    work: impl FnOnce() -> T + Send,
) -> T {
    *stop.lock_watch() = Watch::default();
    py.detach(|| {
        std::thread::scope(|scope| {
            let worker = scope.spawn(move || {
                let _finished = Finished(stop);
                match pool {
                    Some(pool) => pool.install(work),
                    None => work(),
                }
            });
            stop.watch_signals();
            match worker.join() {
                Ok(result) => result,
                Err(panic) => std::panic::resume_unwind(panic),
            }
        })
    })
}
