//! `gait-fuzz`: runs the fuzz targets, each in a child process so that an abort (stack
//! overflow, an allocation over the limit, a hang) is caught and its input kept too.
//!
//! ```text
//! gait-fuzz run [--target NAME]... [--seconds S] [--inputs N] [--seed N] [--crashes DIR]
//! gait-fuzz replay --target NAME FILE...
//! gait-fuzz patch SEED INPUT
//! gait-fuzz record-video VIDEO OUT
//! gait-fuzz list
//! ```
//! `run` prints a table (inputs tried, inputs per second, crashes per target) and exits 1 when
//! any target crashed; every crashing input is saved under `--crashes` (default
//! target/fuzz-crashes) and printed as hex, so a CI log alone is enough to reproduce it.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write as _;
use std::path::PathBuf;
use std::process::{Command, ExitCode, Stdio};

use gait_fuzz::engine::{self, Budget};
use gait_fuzz::targets::{Scratch, TARGETS, Target, target};

/// The largest single allocation a parser may ask for. Every real input of gait needs far less
/// (a 4K frame is 25 MB, SD 1.5's largest tensor 100 MB); a request beyond this comes from a
/// size a hostile file declared, which the parser must refuse before allocating.
const ALLOC_LIMIT: usize = 1 << 30;

struct Limited;

// SAFETY: every call is forwarded to the system allocator unchanged, except requests over the
// limit, which end the process before anything is allocated.
unsafe impl GlobalAlloc for Limited {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() > ALLOC_LIMIT {
            over_limit();
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if layout.size() > ALLOC_LIMIT {
            over_limit();
        }
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > ALLOC_LIMIT {
            over_limit();
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOC: Limited = Limited;

/// Writes without allocating, then aborts: the parent keeps the input.
fn over_limit() -> ! {
    let _ = std::io::stderr().write_all(b"allocation over the 1 GiB limit\n");
    std::process::abort()
}

struct Options {
    targets: Vec<&'static Target>,
    budget: Budget,
    seed: u64,
    crashes: PathBuf,
}

fn usage() -> ExitCode {
    eprintln!(
        "usage: gait-fuzz run [--target NAME]... [--seconds S] [--inputs N] [--seed N] [--crashes DIR]\n       gait-fuzz replay --target NAME FILE...\n       gait-fuzz patch SEED INPUT\n       gait-fuzz record-video VIDEO OUT\n       gait-fuzz list"
    );
    ExitCode::from(2)
}

fn parse(args: &[String]) -> Result<(Options, Vec<PathBuf>), String> {
    let mut o = Options {
        targets: Vec::new(),
        budget: Budget {
            inputs: u64::MAX,
            seconds: 10.0,
        },
        seed: 1,
        crashes: gait_fuzz::repo().join("target/fuzz-crashes"),
    };
    let mut files = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().cloned().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--target" => {
                let n = value()?;
                o.targets
                    .push(target(&n).ok_or(format!("no target `{n}` (gait-fuzz list)"))?);
            }
            "--seconds" => {
                o.budget.seconds = value()?.parse().map_err(|_| "--seconds: a number")?
            }
            "--inputs" => o.budget.inputs = value()?.parse().map_err(|_| "--inputs: a count")?,
            "--seed" => o.seed = value()?.parse().map_err(|_| "--seed: a number")?,
            "--crashes" => o.crashes = PathBuf::from(value()?),
            f if !f.starts_with("--") => files.push(PathBuf::from(f)),
            other => return Err(format!("unknown option {other}")),
        }
    }
    if o.targets.is_empty() {
        o.targets = TARGETS.iter().collect();
    }
    Ok((o, files))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// One target in a child process; restarted after an abort until the budget is spent.
fn run_target(t: &Target, o: &Options) -> (u64, f64, Vec<(PathBuf, String)>) {
    let exe = std::env::current_exe().expect("the running executable");
    let _ = std::fs::create_dir_all(&o.crashes);
    // The child writes every input here before running it: on tmpfs where there is one, so
    // that large seeds (a 3 MB model) cost a memory copy rather than a disk write per input.
    let scratch = Scratch::new().ok();
    let current = match &scratch {
        Some(s) => s.path().join(format!(".current-{}", t.name)),
        None => o.crashes.join(format!(".current-{}", t.name)),
    };
    let (mut inputs, mut seconds, mut crashes) = (0u64, 0f64, Vec::new());
    let mut seed = o.seed;
    while inputs < o.budget.inputs && seconds < o.budget.seconds {
        let out = Command::new(&exe)
            .args(["child", t.name])
            .args(["--inputs", &(o.budget.inputs - inputs).to_string()])
            .args(["--seconds", &(o.budget.seconds - seconds).to_string()])
            .args(["--seed", &seed.to_string()])
            .arg("--crashes")
            .arg(&o.crashes)
            .arg(&current)
            .stdin(Stdio::null())
            .output();
        let Ok(out) = out else {
            crashes.push((PathBuf::new(), "could not start the child process".into()));
            break;
        };
        let text = String::from_utf8_lossy(&out.stdout);
        let mut n = 0u64;
        let mut s = 0f64;
        for line in text.lines() {
            if let Some(rest) = line.strip_prefix("stats ") {
                let v: Vec<&str> = rest.split_whitespace().collect();
                n = v.first().and_then(|x| x.parse().ok()).unwrap_or(0);
                s = v.get(1).and_then(|x| x.parse().ok()).unwrap_or(0.0);
            } else if let Some(rest) = line.strip_prefix("crash ") {
                let (p, why) = rest.split_once('\t').unwrap_or((rest, ""));
                crashes.push((PathBuf::from(p), why.to_string()));
            }
        }
        if out.status.success() {
            inputs += n;
            seconds += s;
            break;
        }
        // Aborted: the input it was on is in `current`.
        let bytes = std::fs::read(&current).unwrap_or_default();
        let err = String::from_utf8_lossy(&out.stderr);
        let why = err
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("aborted")
            .to_string();
        let p = engine::save_crash(&o.crashes, t, &bytes, &format!("{why} ({})", out.status));
        crashes.push((p, why));
        // The child's own count is lost with it; count the input and go on from another seed.
        inputs += 1;
        seconds += 1.0;
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
    }
    let _ = std::fs::remove_file(&current);
    (inputs, seconds, crashes)
}

/// Prints the `.patch` text of `input` against `seed` (a path from the repository root).
fn patch(seed: &str, input: &str) -> ExitCode {
    let (Ok(s), Ok(i)) = (
        std::fs::read(gait_fuzz::repo().join(seed)),
        std::fs::read(input),
    ) else {
        eprintln!("gait-fuzz: cannot read {seed} (from the repository root) or {input}");
        return ExitCode::from(2);
    };
    match gait_fuzz::patch::write(seed, &s, &i) {
        Some(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        None => {
            eprintln!("gait-fuzz: {input} differs from {seed} in too many bytes; keep it whole");
            ExitCode::FAILURE
        }
    }
}

/// Writes a `video_stream` seed: ffprobe's and ffmpeg's output on `video`, as gait runs them.
fn record_video(video: &str, out: &str) -> ExitCode {
    match gait_fuzz::recording::record(std::path::Path::new(video))
        .and_then(|bytes| std::fs::write(out, bytes))
    {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gait-fuzz: cannot record {video} to {out} ({e})");
            ExitCode::from(2)
        }
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(cmd) = args.first() else {
        return usage();
    };
    match cmd.as_str() {
        "list" => {
            for t in TARGETS {
                println!("{}", t.name);
            }
            ExitCode::SUCCESS
        }
        "child" => match args.get(1).and_then(|n| target(n)) {
            Some(t) => with_options(&args[2..], |o, files| child(t, o, files)),
            None => usage(),
        },
        "patch" => match (args.get(1), args.get(2)) {
            (Some(seed), Some(input)) => patch(seed, input),
            _ => usage(),
        },
        "record-video" => match (args.get(1), args.get(2)) {
            (Some(video), Some(out)) => record_video(video, out),
            _ => usage(),
        },
        "replay" => with_options(&args[1..], replay),
        "run" => with_options(&args[1..], |o, _| run(o)),
        _ => usage(),
    }
}

/// Runs `f` on the parsed options, or says what is wrong with them (exit 2).
fn with_options(args: &[String], f: impl FnOnce(&Options, &[PathBuf]) -> ExitCode) -> ExitCode {
    match parse(args) {
        Ok((o, files)) => f(&o, &files),
        Err(e) => {
            eprintln!("gait-fuzz: {e}");
            ExitCode::from(2)
        }
    }
}

/// The child process of `run`: fuzzes `t`, printing its crashes and counts for the parent.
fn child(t: &Target, o: &Options, files: &[PathBuf]) -> ExitCode {
    let current = files.first().map(PathBuf::as_path);
    let stats = engine::fuzz(t, o.budget, o.seed, &o.crashes, current);
    for (p, why) in &stats.crashes {
        println!("crash {}\t{why}", p.display());
    }
    println!("stats {} {}", stats.inputs, stats.seconds);
    ExitCode::SUCCESS
}

/// Runs each file through the chosen targets; fails when any of them panics.
fn replay(o: &Options, files: &[PathBuf]) -> ExitCode {
    let scratch = Scratch::new().expect("a scratch folder");
    let mut bad = 0;
    for f in files {
        let bytes = engine::read_input(f).unwrap_or_default();
        for t in &o.targets {
            if let Err(why) = engine::run_one(t, &scratch, &bytes) {
                bad += 1;
                println!("{} on {}: {why}", t.name, f.display());
            }
        }
    }
    match bad {
        0 => ExitCode::SUCCESS,
        _ => ExitCode::FAILURE,
    }
}

/// Fuzzes every chosen target in turn; prints the table, then each crash with its input.
fn run(o: &Options) -> ExitCode {
    println!("| target | inputs | seconds | inputs/s | crashes |\n| --- | --- | --- | --- | --- |");
    let mut all = Vec::new();
    for t in &o.targets {
        let (n, s, crashes) = run_target(t, o);
        let rate = n as f64 / s.max(1e-9);
        println!(
            "| {} | {n} | {s:.1} | {rate:.0} | {} |",
            t.name,
            crashes.len()
        );
        all.extend(crashes.into_iter().map(|c| (t.name, c)));
    }
    for (name, (p, why)) in &all {
        let bytes = std::fs::read(p).unwrap_or_default();
        eprintln!(
            "CRASH {name}: {why}\n  input {} ({} bytes)",
            p.display(),
            bytes.len()
        );
        if bytes.len() <= 4096 {
            eprintln!("  hex {}", hex(&bytes));
        }
    }
    match all.is_empty() {
        true => ExitCode::SUCCESS,
        false => ExitCode::FAILURE,
    }
}
