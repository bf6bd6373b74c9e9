//! Where a run's wall time goes: each step in the order it ran, and what no
//! step accounts for (run.json's `timings`), so a profile of a run is read
//! from its own folder.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::Serialize;

static PROCESS_START: OnceLock<Instant> = OnceLock::new();
/// Whether a run of this process has counted the start-up already: `gait batch`,
/// `gait visit` and Python run several in one process, and only the first had it.
static START_TAKEN: AtomicBool = AtomicBool::new(false);

/// Marks the start of the process (call first thing in `main`), so the
/// start-up before a run (arguments, config) is counted too.
pub fn mark_process_start() {
    PROCESS_START.get_or_init(Instant::now);
}

fn process_start() -> Instant {
    *PROCESS_START.get_or_init(Instant::now)
}

/// One named step and its wall-clock seconds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    pub step: String,
    pub seconds: f64,
}

/// The steps of a run, with its total and the rest no step accounts for.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Timings {
    pub steps: Vec<Step>,
    pub total_s: f64,
    pub unaccounted_s: f64,
    /// Where the total counts from.
    #[serde(skip)]
    origin: Option<Instant>,
}

impl Timings {
    /// Timings of a run starting now; the first run of the process also
    /// counts the time from the process start (arguments, config).
    pub fn from_process_start() -> Self {
        let first = !START_TAKEN.swap(true, Ordering::Relaxed);
        let origin = if first {
            process_start()
        } else {
            Instant::now()
        };
        let mut t = Self {
            origin: Some(origin),
            ..Self::default()
        };
        t.add(
            "start-up (arguments, config)",
            origin.elapsed().as_secs_f64(),
        );
        t
    }

    pub fn add(&mut self, step: impl Into<String>, seconds: f64) {
        self.steps.push(Step {
            step: step.into(),
            seconds,
        });
    }

    /// Runs `f` as the step `step`.
    pub fn time<T>(&mut self, step: &str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let out = f();
        self.add(step, t.elapsed().as_secs_f64());
        out
    }

    /// A pass of `seconds` split into the model's share, the time spent
    /// waiting for decoded frames, and the rest (caches, tracking, copies).
    pub fn add_pass(&mut self, pass: &str, seconds: f64, model: f64, decoding: f64) {
        self.add(format!("{pass}: decoding (waiting for frames)"), decoding);
        self.add(format!("{pass}: model"), model);
        self.add(
            format!("{pass}: the rest (caches, tracking, copies)"),
            (seconds - model - decoding).max(0.0),
        );
    }

    /// Sets the total to the time since the run (or, for the first, the process) started.
    pub fn close(&mut self) {
        self.total_s = self.origin.map_or(0.0, |o| o.elapsed().as_secs_f64());
        let sum: f64 = self.steps.iter().map(|s| s.seconds).sum();
        self.unaccounted_s = (self.total_s - sum).max(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rest_is_what_no_step_accounts_for() {
        mark_process_start();
        let mut t = Timings::from_process_start();
        t.time("sleep", || {
            std::thread::sleep(std::time::Duration::from_millis(20))
        });
        std::thread::sleep(std::time::Duration::from_millis(30));
        t.close();
        assert!(t.steps[1].seconds >= 0.02);
        assert!(t.unaccounted_s >= 0.03, "{t:?}");
        let sum: f64 = t.steps.iter().map(|s| s.seconds).sum();
        assert!((t.total_s - sum - t.unaccounted_s).abs() < 1e-9);
    }

    #[test]
    fn a_later_run_of_the_process_counts_from_its_own_start() {
        let _first = Timings::from_process_start();
        std::thread::sleep(std::time::Duration::from_millis(30));
        let mut second = Timings::from_process_start();
        second.close();
        assert!(second.steps[0].seconds < 0.02, "{second:?}");
        assert!(second.total_s < 0.02, "{second:?}");
    }

    #[test]
    fn a_pass_is_split_into_model_decoding_and_the_rest() {
        let mut t = Timings::default();
        t.add_pass("pose pass", 10.0, 6.0, 3.0);
        let s: Vec<f64> = t.steps.iter().map(|s| s.seconds).collect();
        assert_eq!(s, [3.0, 6.0, 1.0]);
    }
}
