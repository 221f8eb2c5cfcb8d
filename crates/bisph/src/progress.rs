//! Progress of `bisph run`: a bar on a terminal, plain lines in logs.
//!
//! When stderr is a terminal the run draws a bar. When it is not (output redirected to a file,
//! a batch job, `nohup`), a bar would print nothing until the end, so the run writes one plain
//! line every `interval` seconds of wall time instead:
//!
//! ```text
//! progress: t = 0.1250 s of 1.0000 s (12.5%), step 812, 81 steps/s, ETA 0:01:47
//! ```
//!
//! Rates and the ETA count from the step this invocation started at, so they stay right for a
//! resumed run.

use bisph_io::Progress;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Default seconds between two plain progress lines.
pub const DEFAULT_INTERVAL: f64 = 10.0;

/// How progress is shown.
pub enum Reporter {
    /// Nothing (`--quiet`).
    Quiet,
    /// A bar redrawn in place (stderr is a terminal).
    Bar(ProgressBar),
    /// One line per interval on stderr.
    Lines {
        /// Wall time between two lines.
        interval: Duration,
        /// When the last line was written.
        last: Instant,
    },
}

/// Where this invocation started: wall clock, step and simulated time of its first report.
struct Start {
    wall: Instant,
    step: Option<u64>,
    time: f64,
}

/// Shows the progress of a run.
pub struct RunProgress {
    reporter: Reporter,
    start: Start,
}

impl RunProgress {
    /// A bar when stderr is a terminal, plain lines every `interval` seconds otherwise; nothing
    /// when `quiet`.
    pub fn new(quiet: bool, interval: f64) -> Self {
        let reporter = if quiet {
            Reporter::Quiet
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(1000);
            bar.set_style(
                ProgressStyle::with_template(
                    "{bar:40} t = {msg} [{elapsed_precise} < {eta_precise}]",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            Reporter::Bar(bar)
        } else {
            Reporter::Lines {
                interval: Duration::from_secs_f64(interval),
                last: Instant::now(),
            }
        };
        RunProgress {
            reporter,
            start: Start {
                wall: Instant::now(),
                step: None,
                time: 0.0,
            },
        }
    }

    /// Takes one report of the run loop (called every step).
    pub fn report(&mut self, p: Progress) {
        if p.settling {
            self.report_settling(&p);
            return;
        }
        let first_step = *self.start.step.get_or_insert_with(|| {
            self.start.time = p.time;
            self.start.wall = Instant::now();
            p.step
        });
        match &mut self.reporter {
            Reporter::Quiet => {}
            Reporter::Bar(bar) => {
                if p.step.is_multiple_of(20) || p.time >= p.end {
                    bar.set_position((1000.0 * p.time / p.end) as u64);
                    let rate = rate(p.step - first_step, self.start.wall.elapsed());
                    bar.set_message(format!(
                        "{:.4} s, step {}, {:.0} steps/s",
                        p.time, p.step, rate
                    ));
                }
            }
            Reporter::Lines { interval, last } => {
                if last.elapsed() >= *interval && p.time < p.end {
                    *last = Instant::now();
                    let line = line(&p, first_step, self.start.time, self.start.wall.elapsed());
                    // A log that cannot be written must not stop the run.
                    let _ = writeln!(std::io::stderr().lock(), "{line}");
                }
            }
        }
    }

    /// A settling step: the bar shows the settling time against its most; plain lines say
    /// that the run is settling.
    fn report_settling(&mut self, p: &Progress) {
        match &mut self.reporter {
            Reporter::Quiet => {}
            Reporter::Bar(bar) => {
                if p.step.is_multiple_of(20) {
                    bar.set_position((1000.0 * p.time / p.end).min(1000.0) as u64);
                    bar.set_message(format!(
                        "{:.4} s of settling before t = 0, step {}",
                        p.time, p.step
                    ));
                }
            }
            Reporter::Lines { interval, last } => {
                if last.elapsed() >= *interval {
                    *last = Instant::now();
                    let _ = writeln!(std::io::stderr().lock(), "{}", settling_line(p));
                }
            }
        }
    }

    /// Removes the bar (the plain lines stay).
    pub fn finish(&self) {
        if let Reporter::Bar(bar) = &self.reporter {
            bar.finish_and_clear();
        }
    }
}

/// Steps per second.
fn rate(steps: u64, elapsed: Duration) -> f64 {
    steps as f64 / elapsed.as_secs_f64().max(1e-9)
}

/// One plain progress line: simulated time, share done, step, steps/s and the ETA from the
/// simulated time advanced per wall second since `time0` at `step0`.
fn line(p: &Progress, step0: u64, time0: f64, elapsed: Duration) -> String {
    let done = if p.end > 0.0 { p.time / p.end } else { 1.0 };
    let advanced = p.time - time0;
    let eta = if advanced > 0.0 {
        let seconds = (p.end - p.time).max(0.0) / advanced * elapsed.as_secs_f64();
        clock(seconds)
    } else {
        "unknown".into()
    };
    format!(
        "progress: t = {:.4} s of {:.4} s ({:.1}%), step {}, {:.0} steps/s, ETA {eta}",
        p.time,
        p.end,
        100.0 * done,
        p.step,
        rate(p.step - step0, elapsed)
    )
}

/// One plain line while settling before `t = 0`.
fn settling_line(p: &Progress) -> String {
    format!(
        "settling before t = 0: {:.4} s of at most {:.4} s, step {} (settle.enabled = false skips it)",
        p.time, p.end, p.step
    )
}

/// `h:mm:ss`.
fn clock(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "unknown".into();
    }
    let s = seconds.round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_gives_time_step_rate_and_eta() {
        let p = Progress {
            time: 0.25,
            end: 1.0,
            step: 1100,
            settling: false,
        };
        let l = line(&p, 100, 0.0, Duration::from_secs(10));
        assert_eq!(
            l,
            "progress: t = 0.2500 s of 1.0000 s (25.0%), step 1100, 100 steps/s, ETA 0:00:30"
        );
    }

    #[test]
    fn a_resumed_run_counts_from_its_own_start() {
        let p = Progress {
            time: 0.6,
            end: 1.0,
            step: 600,
            settling: false,
        };
        // Resumed at t = 0.5, step 500: 0.1 s in 20 s, 0.4 s to go.
        let l = line(&p, 500, 0.5, Duration::from_secs(20));
        assert!(l.contains("5 steps/s, ETA 0:01:20"), "{l}");
    }

    #[test]
    fn clock_reads_hours_minutes_seconds() {
        assert_eq!(clock(3725.4), "1:02:05");
        assert_eq!(clock(f64::INFINITY), "unknown");
    }
}
