//! The Slurm executor: job arrays submitted with `sbatch`, one task per row (and per part of a
//! split row), then a dependent job (`afterany`) that aggregates. Job ids are recorded in
//! `batch/jobs.json`, so `scancel` can stop a batch and `gait batch status` can ask `squeue`.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use serde::{Deserialize, Serialize};

use crate::BatchError;
use crate::launch::{Launcher, quote};
use crate::plan::Plan;

/// What was submitted.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Jobs {
    /// Array jobs of split rows' parts: job id -> array index of each row part (row * parts + part).
    pub parts: Vec<ArrayJob>,
    /// Array jobs of the rows' runs (array index = study row).
    pub runs: Vec<ArrayJob>,
    pub aggregate: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArrayJob {
    pub id: String,
    pub indices: Vec<usize>,
    pub gpu: bool,
}

impl Jobs {
    /// Every job id, the aggregate's last.
    pub fn ids(&self) -> Vec<String> {
        self.parts
            .iter()
            .chain(&self.runs)
            .map(|j| j.id.clone())
            .chain(self.aggregate.clone())
            .collect()
    }

    pub fn read(out: &Path) -> Option<Jobs> {
        let text = std::fs::read_to_string(out.join("batch").join("jobs.json")).ok()?;
        serde_json::from_str(&text).ok()
    }

    fn write(&self, out: &Path) -> Result<(), BatchError> {
        let path = out.join("batch").join("jobs.json");
        let json = serde_json::to_vec_pretty(self).unwrap_or_default();
        gait_pipeline::atomic::write(&path, &json)
            .map_err(|e| BatchError::io(format!("writing {}", path.display()), e))
    }
}

/// Seconds before the time limit at which Slurm warns a task (SIGUSR1): time to finish the
/// frame in flight (a ControlNet frame on a GPU takes seconds), requeue, and exit.
pub const WARN_BEFORE_LIMIT_S: u32 = 120;

/// What every task asks of Slurm: run again after a node failure or preemption (`--requeue`),
/// and a warning to the task itself (`B:`: our script `exec`s gait) before the time limit.
fn requeue_args() -> [String; 2] {
    [
        "--requeue".into(),
        format!("--signal=B:USR1@{WARN_BEFORE_LIMIT_S}"),
    ]
}

/// Puts the calling task back in Slurm's queue (it stopped at the time-limit warning); the
/// requeued task resumes from the cache.
pub fn requeue_self() -> Result<(), BatchError> {
    let Ok(id) = std::env::var("SLURM_JOB_ID") else {
        return Ok(());
    };
    run(
        Command::new("scontrol").args(["requeue", &id]),
        &format!("scontrol requeue {id} failed"),
    )?;
    eprintln!("requeued slurm job {id}: it resumes from the cache");
    Ok(())
}

/// Runs a Slurm command; its stdout, or `failed: <its stderr on one line>`.
fn run(cmd: &mut Command, failed: &str) -> Result<Vec<u8>, BatchError> {
    let program = cmd.get_program().to_string_lossy().into_owned();
    let out = cmd
        .output()
        .map_err(|e| BatchError::Slurm(format!("{program} could not run: {e}")))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(BatchError::Slurm(format!(
            "{failed}: {}",
            err.split_whitespace().collect::<Vec<_>>().join(" ")
        )));
    }
    Ok(out.stdout)
}

/// `sbatch` must be on the PATH for `--executor slurm`.
pub fn check_sbatch() -> Result<(), BatchError> {
    match Command::new("sbatch").arg("--version").output() {
        Ok(o) if o.status.success() => Ok(()),
        _ => Err(BatchError::Slurm(
            "--executor slurm needs Slurm's `sbatch` on the PATH (none found); install Slurm's client or use --executor local".into(),
        )),
    }
}

/// `sbatch` options: the user's `--slurm-args` plus what the task needs.
pub struct SubmitOptions {
    pub slurm_args: Vec<String>,
    /// At most this many tasks of an array at once (`%N`).
    pub jobs: Option<usize>,
}

/// A job script that runs `command` (the job's name and log file are sbatch options, which
/// take any path).
fn script(out: &Path, name: &str, command: &str) -> Result<std::path::PathBuf, BatchError> {
    let path = out.join("batch").join(name);
    let text =
        format!("#!/bin/bash\n# Written by `gait batch`; submitted with sbatch.\n{command}\n");
    gait_pipeline::atomic::write(&path, text.as_bytes())
        .map_err(|e| BatchError::io(format!("writing {}", path.display()), e))?;
    Ok(path)
}

/// `sbatch --parsable ...`: the job id.
fn sbatch(args: &[String], script: &Path) -> Result<String, BatchError> {
    let stdout = run(
        Command::new("sbatch")
            .arg("--parsable")
            .args(args)
            .arg(script),
        "sbatch refused the batch",
    )?;
    let text = String::from_utf8_lossy(&stdout);
    // `--parsable` prints `id` or `id;cluster`.
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() {
        return Err(BatchError::Slurm("sbatch printed no job id".into()));
    }
    Ok(id)
}

fn array_list(indices: &[usize], jobs: Option<usize>) -> String {
    let list: Vec<String> = indices.iter().map(usize::to_string).collect();
    match jobs {
        Some(n) => format!("{}%{n}", list.join(",")),
        None => list.join(","),
    }
}

/// Submits the tasks of `rows` (study indices) and the aggregate; records and returns the jobs.
pub fn submit(
    out: &Path,
    plan: &Plan,
    rows: &[usize],
    launcher: &Launcher,
    opts: &SubmitOptions,
) -> Result<Jobs, BatchError> {
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs)
        .map_err(|e| BatchError::io(format!("creating {}", logs.display()), e))?;
    let exe = quote(launcher.exe.as_os_str());
    let named = |job: &str, log: &str| {
        vec![
            format!("--job-name=gait-{job}"),
            format!("--output={}", logs.join(log).display()),
        ]
    };
    let task = |extra: &str| {
        let mut a: Vec<String> = launcher.global.iter().map(|g| quote(g)).collect();
        a.extend(["batch".into(), "task".into(), quote(out.as_os_str())]);
        format!("exec {exe} {} {extra}", a.join(" "))
    };
    let k = plan.split_frames;
    let parts_script = script(
        out,
        "parts.sh",
        &task(&format!(
            "--row $((SLURM_ARRAY_TASK_ID / {k})) --part $((SLURM_ARRAY_TASK_ID % {k}))"
        )),
    )?;
    let runs_script = script(out, "runs.sh", &task("--row $SLURM_ARRAY_TASK_ID"))?;
    let mut agg_args: Vec<String> = launcher
        .aggregate_args(out)
        .iter()
        .map(|g| quote(g))
        .collect();
    agg_args.insert(0, exe.clone());
    let agg_script = script(out, "aggregate.sh", &format!("exec {}", agg_args.join(" ")))?;

    // One array per resource class: the rows that need a GPU ask for one.
    let mut by_gpu: BTreeMap<bool, Vec<usize>> = BTreeMap::new();
    for r in rows.iter().filter_map(|&i| plan.row(i)) {
        by_gpu.entry(r.gpu).or_default().push(r.index);
    }
    let base = |gpu: bool, job: &str, log: &str| {
        // The user's options come after ours, so theirs win (sbatch takes the last).
        let mut a: Vec<String> = requeue_args().into();
        a.extend(opts.slurm_args.iter().cloned());
        a.extend(named(job, log));
        if gpu {
            a.push("--gres=gpu:1".into());
        }
        a
    };
    let mut jobs = Jobs::default();
    for (&gpu, indices) in &by_gpu {
        let split: Vec<usize> = indices
            .iter()
            .filter(|&&i| k > 1 && plan.row(i).is_some_and(|r| r.regenerates))
            .flat_map(|&i| (0..k).map(move |p| i * k + p))
            .collect();
        let mut after = Vec::new();
        if !split.is_empty() {
            let mut a = base(gpu, "part", "slurm-%A_%a.out");
            a.push(format!("--array={}", array_list(&split, opts.jobs)));
            let id = sbatch(&a, &parts_script)?;
            after.push(id.clone());
            jobs.parts.push(ArrayJob {
                id,
                indices: split,
                gpu,
            });
            jobs.write(out)?;
        }
        let mut a = base(gpu, "run", "slurm-%A_%a.out");
        a.push(format!("--array={}", array_list(indices, opts.jobs)));
        if !after.is_empty() {
            a.push(format!("--dependency=afterany:{}", after.join(":")));
        }
        let id = sbatch(&a, &runs_script)?;
        jobs.runs.push(ArrayJob {
            id,
            indices: indices.clone(),
            gpu,
        });
        jobs.write(out)?;
    }
    let runs: Vec<String> = jobs.runs.iter().map(|j| j.id.clone()).collect();
    let mut a = opts.slurm_args.clone();
    a.extend(named("aggregate", "slurm-aggregate-%j.out"));
    if !runs.is_empty() {
        a.push(format!("--dependency=afterany:{}", runs.join(":")));
    }
    jobs.aggregate = Some(sbatch(&a, &agg_script)?);
    jobs.write(out)?;
    Ok(jobs)
}

/// The jobs of `ids` still in Slurm's queue: `(job id, array index or None, state)`, one per
/// task (`squeue -r`). Empty when squeue is missing or knows none of them.
pub fn queued(ids: &[String]) -> Vec<(String, Option<usize>, String)> {
    if ids.is_empty() {
        return Vec::new();
    }
    let Ok(o) = Command::new("squeue")
        .args(["-h", "-r", "-o", "%i %T", "-j", &ids.join(",")])
        .output()
    else {
        return Vec::new();
    };
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| {
            let (id, state) = l.trim().split_once(' ')?;
            let (job, index) = match id.split_once('_') {
                Some((j, i)) => (j.to_string(), i.parse().ok()),
                None => (id.to_string(), None),
            };
            Some((job, index, state.trim().to_string()))
        })
        .collect()
}

/// Blocks until none of `ids` is in the queue (polling squeue every `every`).
pub fn wait(ids: &[String], every: std::time::Duration) {
    while !queued(ids).is_empty() {
        std::thread::sleep(every);
    }
}

/// `sacct`'s final states of `ids`, where accounting is set up (`None` otherwise).
pub fn accounted(ids: &[String]) -> Option<Vec<(String, String)>> {
    let o = Command::new("sacct")
        .args(["-n", "-P", "-X", "-o", "JobID,State", "-j", &ids.join(",")])
        .output()
        .ok()?;
    if !o.status.success() {
        return None;
    }
    Some(
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter_map(|l| l.split_once('|'))
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect(),
    )
}
