//! `gait batch`: a study file -> one `gait run` folder per row, locally or on Slurm, then
//! cohort.csv and cohort.html. Exit codes: 0 every row done, 2 nothing ran (bad input), 3 some
//! rows failed (cohort.csv and `gait batch status` say why).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};

use gait_batch::{Launcher, Plan, RowState, Study, Task, slurm, state};
use gait_pipeline::RunOptions;

use crate::error::{CliError, one_line};

/// Exit code of a batch in which some rows failed.
pub const SOME_FAILED: u8 = 3;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Executor {
    Local,
    Slurm,
}

/// `gait batch STUDY --out DIR`, or `gait batch status DIR`.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    #[command(subcommand)]
    command: Option<Sub>,
    /// Study file: CSV with the header video,subject,session,view,prosthetic_side,config,set (or TOML [[row]] tables)
    #[arg(value_name = "STUDY", required = true)]
    study: Option<PathBuf>,
    /// Batch folder: runs/<row>/ (one run folder per row), the shared cache/, logs/, cohort.csv, cohort.html
    #[arg(long, value_name = "DIR", required = true)]
    out: Option<PathBuf>,
    /// Where the runs go
    #[arg(long, value_enum, default_value = "local")]
    executor: Executor,
    /// Runs at a time (local: default 1; slurm: the array's limit, default none)
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// sbatch options for every job, e.g. "--partition=gpu --time=04:00:00 --account=lab"
    #[arg(long, value_name = "ARGS", allow_hyphen_values = true)]
    slurm_args: Option<String>,
    /// Spread each video's regeneration over K tasks (ControlNet rows); a last task per video
    /// runs the poses and kinematics from the shared cache
    #[arg(long, value_name = "K", default_value_t = 1)]
    split_frames: usize,
    /// Slurm: block until the batch and its aggregate have finished, and exit with its status
    #[arg(long)]
    wait: bool,
}

#[derive(Debug, clap::Subcommand)]
enum Sub {
    /// Done / running / failed per row of a batch folder
    Status {
        #[arg(value_name = "DIR")]
        dir: PathBuf,
    },
    /// One task of a batch (what the executors run)
    #[command(hide = true)]
    Task {
        #[arg(value_name = "DIR")]
        dir: PathBuf,
        #[arg(long)]
        row: usize,
        #[arg(long)]
        part: Option<usize>,
    },
    /// cohort.csv and cohort.html from the run folders (the last job of a Slurm batch)
    #[command(hide = true)]
    Aggregate {
        #[arg(value_name = "DIR")]
        dir: PathBuf,
    },
}

fn fail(e: gait_batch::BatchError) -> CliError {
    CliError::new(one_line(&e.to_string()))
}

pub fn execute(args: Args, models_dir: &Path) -> Result<ExitCode, CliError> {
    match args.command {
        Some(Sub::Status { dir }) => status(&dir),
        Some(Sub::Task { dir, row, part }) => task(&dir, row, part, models_dir),
        Some(Sub::Aggregate { dir }) => aggregate(&dir),
        None => {
            let (Some(study), Some(out)) = (args.study.clone(), args.out.clone()) else {
                return Err(CliError::new("give a study file and --out DIR"));
            };
            submit(&args, &study, &out, models_dir)
        }
    }
}

fn launcher(models_dir: &Path) -> Result<Launcher, CliError> {
    let exe = std::env::current_exe()
        .map_err(|e| CliError::new(format!("cannot find the gait executable ({e})")))?;
    let models = std::path::absolute(models_dir).unwrap_or_else(|_| models_dir.to_path_buf());
    Ok(Launcher {
        exe,
        global: vec!["--models-dir".into(), models.into_os_string()],
    })
}

/// Plans the study, then runs (local) or submits (slurm) the rows that are not complete.
fn submit(args: &Args, study: &Path, out: &Path, models_dir: &Path) -> Result<ExitCode, CliError> {
    if args.executor == Executor::Slurm {
        slurm::check_sbatch().map_err(fail)?;
    }
    if args.split_frames == 0 {
        return Err(CliError::new("--split-frames must be at least 1"));
    }
    let study = Study::read(study).map_err(fail)?;
    let (plan, configs) = Plan::make(&study, out, args.split_frames).map_err(fail)?;
    let out = &std::path::absolute(out).unwrap_or_else(|_| out.to_path_buf());
    // One `gait batch` per study folder at a time (each row's run locks its own folder).
    let _lock = gait_pipeline::FolderLock::acquire(out, "gait batch")?;
    if let Some(jobs) = slurm::Jobs::read(out) {
        let busy = slurm::queued(&jobs.ids());
        if !busy.is_empty() {
            return Err(CliError::new(format!(
                "{}: this batch still has jobs in the queue ({}); wait for them or `scancel {}`",
                out.display(),
                jobs.ids().join(", "),
                jobs.ids().join(" ")
            )));
        }
    }
    plan.write(out, &configs).map_err(fail)?;
    let todo: Vec<usize> = plan
        .rows
        .iter()
        .zip(&configs)
        .filter(|(r, c)| !state::is_complete(out, r, c))
        .map(|(r, _)| r.index)
        .collect();
    eprintln!(
        "{} rows, {} complete already, {} to run -> {}",
        plan.rows.len(),
        plan.rows.len() - todo.len(),
        todo.len(),
        out.display()
    );
    let launcher = launcher(models_dir)?;
    match args.executor {
        Executor::Local => {
            let done = AtomicUsize::new(0);
            let total = todo.len();
            let on_done = |t: Task, ok: bool| {
                if let Task::Run { row } = t {
                    let k = done.fetch_add(1, Ordering::SeqCst) + 1;
                    let name = plan.row(row).map_or("", |r| r.name.as_str());
                    eprintln!(
                        "[{k}/{total}] {name}: {}",
                        if ok { "done" } else { "failed" }
                    );
                }
            };
            gait_batch::local::run_local(
                out,
                &plan,
                &todo,
                args.jobs.unwrap_or(1),
                &launcher,
                &on_done,
            )
            .map_err(fail)?;
            aggregate(out)
        }
        Executor::Slurm => {
            let opts = slurm::SubmitOptions {
                slurm_args: args
                    .slurm_args
                    .as_deref()
                    .unwrap_or("")
                    .split_whitespace()
                    .map(String::from)
                    .collect(),
                jobs: args.jobs,
            };
            let jobs = slurm::submit(out, &plan, &todo, &launcher, &opts).map_err(fail)?;
            let ids = jobs.ids();
            println!("{}", ids.join(" "));
            eprintln!(
                "submitted {} job(s): {}; aggregate {}; stop with `scancel {}`; follow with `gait batch status {}`",
                ids.len(),
                ids.join(", "),
                jobs.aggregate.as_deref().unwrap_or("-"),
                ids.join(" "),
                out.display()
            );
            if !args.wait {
                return Ok(ExitCode::SUCCESS);
            }
            slurm::wait(&ids, std::time::Duration::from_secs(2));
            exit_status(out, &plan)
        }
    }
}

/// 0 when every row completed (with a result or none), [`SOME_FAILED`] otherwise.
fn exit_status(out: &Path, plan: &Plan) -> Result<ExitCode, CliError> {
    let states: Vec<RowState> = plan
        .rows
        .iter()
        .map(|r| state::row_state(out, r, Plan::config(out, r).ok().as_ref()))
        .collect();
    let failed = states.iter().filter(|s| !s.finished()).count();
    let empty = states.iter().filter(|s| **s == RowState::NoResult).count();
    if failed == 0 {
        // Empty runs completed, but a study must not take them for results.
        let empty = if empty > 0 {
            format!(" ({empty} with no result: `gait batch status` says why)")
        } else {
            String::new()
        };
        eprintln!(
            "all {} rows done{empty}; cohort.csv and cohort.html in {}",
            plan.rows.len(),
            out.display()
        );
        Ok(ExitCode::SUCCESS)
    } else {
        eprintln!(
            "{failed} of {} rows failed or did not finish (`gait batch status {}` says why)",
            plan.rows.len(),
            out.display()
        );
        Ok(ExitCode::from(SOME_FAILED))
    }
}

fn aggregate(out: &Path) -> Result<ExitCode, CliError> {
    let plan = Plan::read(out).map_err(fail)?;
    gait_batch::aggregate(out, &plan).map_err(fail)?;
    exit_status(out, &plan)
}

/// One task: a part of a split row's regeneration, or a row's run (as `gait run`). A failure is
/// recorded in the run folder before the task exits. A signal stops it after the frame in
/// flight; Slurm's time-limit warning (SIGUSR1, see `gait_batch::slurm`) also requeues it, and
/// the requeued task resumes from the cache.
fn task(
    out: &Path,
    index: usize,
    part: Option<usize>,
    models_dir: &Path,
) -> Result<ExitCode, CliError> {
    let plan = Plan::read(out).map_err(fail)?;
    let row = plan
        .row(index)
        .ok_or_else(|| CliError::new(format!("{}: no row {index} in the batch", out.display())))?;
    let config = Plan::config(out, row).map_err(fail)?;
    let handle = gait_pipeline::RunHandle::default();
    crate::interrupt::install(&handle);
    let opts = RunOptions {
        input: row.video.clone(),
        out: gait_batch::run_dir(out, row),
        models_dir: models_dir.to_path_buf(),
        progress: false,
        command: std::env::args().collect(),
        handle: Some(handle),
    };
    let result = match part {
        Some(p) => gait_pipeline::regenerate_part(&config, &opts, p, plan.split_frames)
            .map(|_| ())
            .map_err(CliError::from),
        None => {
            state::clear_failure(out, row);
            crate::commands::run::run_and_report(&config, &opts)
        }
    };
    match &result {
        Err(_) if crate::interrupt::time_limit_warning() => slurm::requeue_self().map_err(fail)?,
        // Stopped, not failed: the task (or its requeue) resumes from the cache.
        Err(_) if crate::interrupt::exit_code().is_some() => {}
        Err(e) => {
            let what = match part {
                Some(p) => format!("part {p} of the regeneration: {e}"),
                None => e.to_string(),
            };
            let _ = state::record_failure(out, row, &what);
        }
        Ok(()) => {}
    }
    result.map(|()| ExitCode::SUCCESS)
}

/// `gait batch status DIR`: a line per row.
fn status(out: &Path) -> Result<ExitCode, CliError> {
    let plan = Plan::read(out).map_err(fail)?;
    let jobs = slurm::Jobs::read(out).unwrap_or_default();
    let queued = slurm::queued(&jobs.ids());
    let k = plan.split_frames;
    let in_queue = |index: usize| {
        queued.iter().find_map(|(job, task, st)| {
            let runs = jobs.runs.iter().any(|j| &j.id == job) && *task == Some(index);
            let parts =
                jobs.parts.iter().any(|j| &j.id == job) && task.is_some_and(|t| t / k == index);
            (runs || parts).then(|| st.to_lowercase())
        })
    };
    let mut counts = std::collections::BTreeMap::new();
    println!("{:<5} {:<40} {:<9} detail", "row", "run", "state");
    for r in &plan.rows {
        let config = Plan::config(out, r).ok();
        let mut st = state::row_state(out, r, config.as_ref());
        let mut detail = state::failure(out, r).unwrap_or_default();
        if !st.finished()
            && let Some(q) = in_queue(r.index)
        {
            st = RowState::Running;
            detail = format!("slurm: {q}");
        }
        match st {
            RowState::Done => detail.clear(),
            RowState::NoResult => {
                detail = format!(
                    "no result: {}",
                    state::no_result(out, r).unwrap_or_default()
                )
            }
            _ => {}
        }
        *counts.entry(st.name()).or_insert(0) += 1;
        println!(
            "{:<5} {:<40} {:<9} {detail}",
            r.index + 1,
            r.name,
            st.name()
        );
    }
    let summary: Vec<String> = counts.iter().map(|(k, v)| format!("{v} {k}")).collect();
    let ids = jobs.ids();
    let sacct = slurm::accounted(&ids)
        .map(|v| {
            v.iter()
                .map(|(j, s)| format!("{j} {s}"))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .filter(|s| !s.is_empty());
    eprintln!(
        "{}{}{}",
        summary.join(", "),
        if ids.is_empty() {
            String::new()
        } else {
            format!("; slurm jobs {}", ids.join(" "))
        },
        sacct.map_or(String::new(), |s| format!(" (sacct: {s})"))
    );
    Ok(ExitCode::SUCCESS)
}
