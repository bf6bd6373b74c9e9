//! The command lines of a batch's tasks: the same `gait` binary, run again per row (and per
//! part of a split row), so a task does exactly what `gait run` does.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// How to start a task.
#[derive(Debug, Clone)]
pub struct Launcher {
    /// The `gait` executable.
    pub exe: PathBuf,
    /// Arguments before the subcommand (e.g. `--models-dir DIR`).
    pub global: Vec<OsString>,
}

/// One task of a batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Task {
    /// Part `part` of a split row's regeneration.
    Part { row: usize, part: usize },
    /// The row's run (poses, kinematics, report), from the shared cache.
    Run { row: usize },
}

impl Launcher {
    /// The arguments that run `task` of the batch in `out`.
    pub fn args(&self, out: &Path, task: Task) -> Vec<OsString> {
        let mut a = self.global.clone();
        a.extend(["batch".into(), "task".into(), out.as_os_str().to_owned()]);
        match task {
            Task::Part { row, part } => {
                a.extend(["--row".into(), row.to_string().into()]);
                a.extend(["--part".into(), part.to_string().into()]);
            }
            Task::Run { row } => a.extend(["--row".into(), row.to_string().into()]),
        }
        a
    }

    /// The aggregate step's arguments.
    pub fn aggregate_args(&self, out: &Path) -> Vec<OsString> {
        let mut a = self.global.clone();
        a.extend([
            "batch".into(),
            "aggregate".into(),
            out.as_os_str().to_owned(),
        ]);
        a
    }
}

/// A shell word, single-quoted (for the sbatch scripts).
pub(crate) fn quote(s: &std::ffi::OsStr) -> String {
    format!("'{}'", s.to_string_lossy().replace('\'', r"'\''"))
}
