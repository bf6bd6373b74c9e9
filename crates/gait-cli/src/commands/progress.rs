//! `gait progress`: a subject's visits side by side, and which differences are changes.

use std::path::{Path, PathBuf};

use gait_visit::VisitRecord;

use crate::error::CliError;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A study's output folder (`gait batch --out`), with --subject; or visit folders (`gait
    /// visit --out`) in any order
    #[arg(required = true, value_name = "DIR")]
    dirs: Vec<PathBuf>,
    /// The subject whose visits to compare (in a study folder)
    #[arg(long)]
    subject: Option<String>,
    /// Where progress.html and progress.csv go [default: STUDY/progress/SUBJECT, else the
    /// last visit's folder]
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

fn fail(e: gait_visit::VisitError) -> CliError {
    CliError::new(e.to_string())
}

/// The visit folders of `subject` under a study's `visits/`.
fn study_visits(study: &Path, subject: &str) -> Result<Vec<PathBuf>, CliError> {
    let dir = study.join("visits");
    let entries = std::fs::read_dir(&dir).map_err(|e| {
        CliError::new(format!(
            "{}: no visits ({e}); a study's rows need subject, session and view",
            dir.display()
        ))
    })?;
    Ok(entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("visit.json").is_file())
        .filter(|p| VisitRecord::read(p).is_ok_and(|v| v.label.subject == subject))
        .collect())
}

pub fn execute(args: Args) -> Result<(), CliError> {
    let (dirs, default_out) = match (&args.subject, args.dirs.as_slice()) {
        (Some(s), [study]) if study.join("visits").is_dir() => {
            (study_visits(study, s)?, study.join("progress").join(s))
        }
        (None, [study]) if study.join("visits").is_dir() => {
            return Err(CliError::new(format!(
                "{} is a study: name the subject with --subject",
                study.display()
            )));
        }
        (_, dirs) => (dirs.to_vec(), dirs[dirs.len() - 1].join("progress")),
    };
    if dirs.len() < 2 {
        return Err(CliError::new(format!(
            "progress needs at least 2 visits; found {}",
            dirs.len()
        )));
    }
    let mut visits = dirs
        .iter()
        .map(|d| VisitRecord::read(d))
        .collect::<Result<Vec<_>, _>>()
        .map_err(fail)?;
    gait_visit::progress::order(&mut visits);
    let out = args.out.unwrap_or(default_out);
    let changes = gait_visit::progress::write(&out, &visits).map_err(fail)?;
    let called: Vec<String> = changes
        .iter()
        .filter(|c| c.call == "change")
        .map(|c| format!("{} ({}) {:+.2} {}", c.item, c.side, c.difference, c.unit))
        .collect();
    eprintln!(
        "{} visits -> {} (changes: {})",
        visits.len(),
        out.join("progress.html").display(),
        if called.is_empty() {
            "none".into()
        } else {
            called.join(", ")
        }
    );
    Ok(())
}
