//! A pass's progress, ticked once per frame, and the handle a front end keeps
//! to follow the run and stop it between frames (Ctrl-C in Python).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::PipelineError;

/// Shared with the thread that runs the pipeline: stop it, and see the
/// current pass's progress.
#[derive(Clone, Default)]
pub struct RunHandle {
    inner: Arc<Shared>,
}

#[derive(Default)]
struct Shared {
    stop: AtomicBool,
    pass: Mutex<Option<(String, ProgressBar)>>,
}

impl std::fmt::Debug for RunHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunHandle")
            .field("stopped", &self.is_stopped())
            .finish()
    }
}

impl RunHandle {
    /// Asks the run to stop after the frame in flight; it then fails with
    /// [`PipelineError::Interrupted`], its caches consistent.
    pub fn stop(&self) {
        self.inner.stop.store(true, Ordering::SeqCst);
    }

    pub fn is_stopped(&self) -> bool {
        self.inner.stop.load(Ordering::SeqCst)
    }

    /// The current pass: its name, frames done and frames in all (if known).
    pub fn progress(&self) -> Option<(String, u64, Option<u64>)> {
        let pass = self.inner.pass.lock().ok()?;
        let (name, bar) = pass.as_ref()?;
        Some((name.clone(), bar.position(), bar.length()))
    }

    fn follow(&self, name: &str, bar: &ProgressBar) {
        if let Ok(mut pass) = self.inner.pass.lock() {
            *pass = Some((name.to_string(), bar.clone()));
        }
    }
}

/// One pass's progress: a terminal bar (or a hidden one) and the run's handle.
pub(crate) struct Progress {
    bar: ProgressBar,
    pass: String,
    handle: Option<RunHandle>,
}

impl Progress {
    /// A bar for `pass` over `total` frames, drawn on stderr when `draw`.
    pub fn new(draw: bool, total: Option<usize>, pass: &str, handle: Option<&RunHandle>) -> Self {
        let bar = if draw {
            terminal_bar(total, pass)
        } else {
            let bar = ProgressBar::hidden();
            if let Some(n) = total {
                bar.set_length(n as u64);
            }
            bar
        };
        if let Some(h) = handle {
            h.follow(pass, &bar);
        }
        Self {
            bar,
            pass: pass.to_string(),
            handle: handle.cloned(),
        }
    }

    /// One more frame; fails when the run was asked to stop.
    pub fn tick(&self) -> Result<(), PipelineError> {
        self.bar.inc(1);
        match &self.handle {
            Some(h) if h.is_stopped() => Err(PipelineError::Interrupted {
                step: self.pass.clone(),
            }),
            _ => Ok(()),
        }
    }

    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}

fn terminal_bar(total: Option<usize>, pass: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(total.map(|n| n as u64), ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {msg} {wide_bar} {pos}/{len} frames {per_sec} ETA {eta}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_message(pass.to_string());
    bar
}
