//! Running a target over mutated seeds: panics caught and their inputs kept; hangs stopped by a
//! watchdog. Aborts (stack overflow, an allocation over the limit) end the process: the input
//! written to `current` before each run is what the parent process then keeps.

use std::cell::RefCell;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Once;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use crate::mutate::{Rng, variant};
use crate::targets::{Scratch, Target};

/// An input running longer than this is a hang.
pub const HANG: Duration = Duration::from_secs(20);

/// How long to fuzz.
#[derive(Debug, Clone, Copy)]
pub struct Budget {
    pub inputs: u64,
    pub seconds: f64,
}

/// What a run did.
#[derive(Debug, Clone, Default)]
pub struct Stats {
    pub inputs: u64,
    pub seconds: f64,
    /// Saved inputs that crashed, with what happened.
    pub crashes: Vec<(PathBuf, String)>,
}

thread_local! {
    static PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Panics are expected here: their message is kept for the report instead of printed.
fn quiet_panics() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            let at = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()));
            let msg = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_default();
            PANIC.with(|p| {
                *p.borrow_mut() = Some(format!("panic: {msg}{}", at.unwrap_or_default()))
            });
        }));
    });
}

/// Runs one input; `Err` with the panic's message when it panicked.
pub fn run_one(t: &Target, scratch: &Scratch, bytes: &[u8]) -> Result<(), String> {
    quiet_panics();
    match std::panic::catch_unwind(AssertUnwindSafe(|| (t.run)(scratch, bytes))) {
        Ok(()) => Ok(()),
        Err(_) => Err(PANIC
            .with(|p| p.borrow_mut().take())
            .unwrap_or_else(|| "panic".into())),
    }
}

/// The seed files of `t`, then its saved crashes (`fuzz/regressions/<name>/`).
pub fn seeds(t: &Target) -> Vec<(PathBuf, Vec<u8>)> {
    let root = crate::repo();
    let mut files: Vec<PathBuf> = Vec::new();
    for s in t.seeds {
        let p = root.join(s);
        if p.is_dir() {
            let mut inner: Vec<PathBuf> = std::fs::read_dir(&p)
                .into_iter()
                .flatten()
                .flatten()
                .map(|e| e.path())
                .filter(|f| f.extension().is_some_and(|e| e == t.ext))
                .collect();
            inner.sort();
            files.extend(inner);
        } else if p.is_file() {
            files.push(p);
        }
    }
    files.extend(regressions(t));
    files
        .into_iter()
        .filter_map(|f| read_input(&f).ok().map(|b| (f, b)))
        .collect()
}

/// A seed or saved input: the file's bytes, or the input a `.patch` file describes.
pub fn read_input(path: &Path) -> Result<Vec<u8>, String> {
    match path.extension().is_some_and(|e| e == "patch") {
        true => crate::patch::read(path),
        false => std::fs::read(path).map_err(|e| format!("{}: {e}", path.display())),
    }
}

/// Inputs that once crashed `t`, kept as regression cases (`.bin`, or `.patch` of a seed).
pub fn regressions(t: &Target) -> Vec<PathBuf> {
    let dir = crate::repo().join("fuzz/regressions").join(t.name);
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "bin" || e == "patch"))
        .collect();
    v.sort();
    v
}

/// FNV-1a: a stable name for a crashing input.
fn hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

/// Keeps `bytes` as `<crashes>/<target>/<hash>.bin` with `why` beside it; returns the path.
pub fn save_crash(crashes: &Path, t: &Target, bytes: &[u8], why: &str) -> PathBuf {
    let dir = crashes.join(t.name);
    let _ = std::fs::create_dir_all(&dir);
    let p = dir.join(format!("{:016x}.bin", hash(bytes)));
    let _ = std::fs::write(&p, bytes);
    let _ = std::fs::write(p.with_extension("txt"), format!("{why}\n"));
    p
}

fn now_ms() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

/// When the running input started (ms since the epoch; 0: none running).
static STARTED: AtomicU64 = AtomicU64::new(0);

/// Aborts the process when one input runs past [`HANG`] (the parent keeps the input).
fn watchdog() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        std::thread::spawn(|| {
            loop {
                std::thread::sleep(Duration::from_millis(500));
                let s = STARTED.load(Ordering::Relaxed);
                if s != 0 && now_ms().saturating_sub(s) > HANG.as_millis() as u64 {
                    eprintln!("hang: one input ran over {} s", HANG.as_secs());
                    std::process::abort();
                }
            }
        });
    });
}

/// Fuzzes `t` for `budget` from RNG seed `seed`; the seeds themselves run first. Each input is
/// written to `current` (when given) before it runs.
pub fn fuzz(
    t: &Target,
    budget: Budget,
    seed: u64,
    crashes: &Path,
    current: Option<&Path>,
) -> Stats {
    watchdog();
    let corpus = seeds(t);
    let scratch = match Scratch::new() {
        Ok(s) => s,
        Err(e) => {
            return Stats {
                crashes: vec![(PathBuf::new(), format!("no scratch folder: {e}"))],
                ..Default::default()
            };
        }
    };
    let mut rng = Rng::new(seed);
    let mut stats = Stats::default();
    let t0 = Instant::now();
    let mut k = 0usize;
    while stats.inputs < budget.inputs && t0.elapsed().as_secs_f64() < budget.seconds {
        let input = if k < corpus.len() || corpus.is_empty() {
            corpus.get(k).map(|c| c.1.clone()).unwrap_or_default()
        } else {
            let (a, b) = (rng.below(corpus.len()), rng.below(corpus.len()));
            variant(&mut rng, &corpus[a].1, &corpus[b].1)
        };
        k += 1;
        if let Some(c) = current {
            let _ = std::fs::write(c, &input);
        }
        STARTED.store(now_ms(), Ordering::Relaxed);
        let result = run_one(t, &scratch, &input);
        STARTED.store(0, Ordering::Relaxed);
        stats.inputs += 1;
        if let Err(why) = result {
            let p = save_crash(crashes, t, &input, &why);
            stats.crashes.push((p, why));
        }
    }
    stats.seconds = t0.elapsed().as_secs_f64();
    stats
}
