//! SIGINT and SIGTERM (Ctrl-C, `kill`, `scancel`, Slurm at the time limit),
//! and SIGUSR1 (the warning `gait batch` asks Slurm to send before the time
//! limit): the run stops after the frame in flight with its caches
//! consistent, run.json says "interrupted", and the command exits 128 + the
//! signal (130, 143, 138). A second signal ends the process at once.

use std::sync::atomic::{AtomicI32, Ordering};

use gait_pipeline::RunHandle;
use signal_hook::consts::{SIGINT, SIGTERM, SIGUSR1};
use signal_hook::iterator::Signals;

/// The first signal received (0: none).
static RECEIVED: AtomicI32 = AtomicI32::new(0);

/// Stops `handle`'s run on SIGINT, SIGTERM or SIGUSR1, from a thread of its own.
pub fn install(handle: &RunHandle) {
    let Ok(mut signals) = Signals::new([SIGINT, SIGTERM, SIGUSR1]) else {
        // Without the handler the default applies: the process ends, the cache resumes it.
        return;
    };
    let handle = handle.clone();
    std::thread::spawn(move || {
        for signal in signals.forever() {
            if RECEIVED.swap(signal, Ordering::SeqCst) != 0 {
                std::process::exit(128 + signal);
            }
            eprintln!(
                "\nstopping after the frame in flight (signal {signal}; again to stop at once)"
            );
            handle.stop();
        }
    });
}

/// True when the run was stopped by Slurm's warning before the time limit.
pub fn time_limit_warning() -> bool {
    RECEIVED.load(Ordering::SeqCst) == SIGUSR1
}

/// The exit code for an interrupted run: 128 + the signal.
pub fn exit_code() -> Option<u8> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => u8::try_from(128 + s).ok(),
    }
}
