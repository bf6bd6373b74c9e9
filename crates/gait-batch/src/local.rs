//! The local executor: the tasks run on this machine, `jobs` at a time, each as its own `gait`
//! process (a crash in one video never stops the others); logs in `logs/`.

use std::collections::VecDeque;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Mutex;

use crate::BatchError;
use crate::launch::{Launcher, Task};
use crate::plan::{Plan, PlannedRow};
use crate::state;

fn log_name(row: &PlannedRow, task: Task) -> String {
    match task {
        Task::Part { part, .. } => format!("{}.part{part}.log", row.name),
        Task::Run { .. } => format!("{}.log", row.name),
    }
}

/// Runs `tasks` `jobs` at a time. A task that dies without leaving its error (a crash, a
/// signal) gets one recorded from its exit status.
fn run_all(
    out: &Path,
    plan: &Plan,
    tasks: Vec<Task>,
    jobs: usize,
    launcher: &Launcher,
    on_done: &(dyn Fn(Task, bool) + Sync),
) -> Result<(), BatchError> {
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs)
        .map_err(|e| BatchError::io(format!("creating {}", logs.display()), e))?;
    let queue = Mutex::new(tasks.into_iter().collect::<VecDeque<_>>());
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1) {
            s.spawn(|| {
                while let Some(task) = queue.lock().unwrap_or_else(|p| p.into_inner()).pop_front() {
                    let index = match task {
                        Task::Part { row, .. } | Task::Run { row } => row,
                    };
                    let Some(row) = plan.row(index) else { continue };
                    let log = logs.join(log_name(row, task));
                    let status = std::fs::File::create(&log).and_then(|f| {
                        Command::new(&launcher.exe)
                            .args(launcher.args(out, task))
                            .stdin(Stdio::null())
                            .stdout(Stdio::null())
                            .stderr(f)
                            .status()
                    });
                    let ok = matches!(&status, Ok(s) if s.success());
                    if !ok && state::failure(out, row).is_none() {
                        let why = match status {
                            Ok(s) => format!("the task stopped ({s}); see {}", log.display()),
                            Err(e) => format!("the task could not start ({e})"),
                        };
                        let _ = state::record_failure(out, row, &why);
                    }
                    on_done(task, ok);
                }
            });
        }
    });
    Ok(())
}

/// Runs `rows` (study indices): first the parts of split rows, then every row's run.
pub fn run_local(
    out: &Path,
    plan: &Plan,
    rows: &[usize],
    jobs: usize,
    launcher: &Launcher,
    on_done: &(dyn Fn(Task, bool) + Sync),
) -> Result<(), BatchError> {
    let parts: Vec<Task> = rows
        .iter()
        .filter_map(|&i| plan.row(i))
        .filter(|r| r.regenerates && plan.split_frames > 1)
        .flat_map(|r| (0..plan.split_frames).map(move |part| Task::Part { row: r.index, part }))
        .collect();
    run_all(out, plan, parts, jobs, launcher, on_done)?;
    let runs = rows.iter().map(|&row| Task::Run { row }).collect();
    run_all(out, plan, runs, jobs, launcher, on_done)
}
