//! A study turned into runs: each row checked and given its run folder and resolved config,
//! written into the batch folder so that every task (local or on a cluster node) reads the same.
//!
//! The batch folder holds `batch/plan.json`, `batch/configs/NAME.toml`, `runs/NAME/` (one
//! `gait run` folder per row), `logs/`, the shared `cache/`, and the cohort files.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gait_pipeline::PipelineConfig;
use serde::{Deserialize, Serialize};

use crate::BatchError;
use crate::study::{Study, StudyRow, VIEWS};

/// One row ready to run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedRow {
    /// Position in the study (from 0): the Slurm array index.
    pub index: usize,
    /// Run folder name under `runs/`.
    pub name: String,
    /// The video, absolute.
    pub video: PathBuf,
    pub subject: String,
    pub session: String,
    pub view: String,
    pub prosthetic_side: String,
    /// ISO 8601, or empty.
    #[serde(default)]
    pub date: String,
    /// The regenerator runs a model (the rows `--split-frames` spreads).
    pub regenerates: bool,
    /// Some stage runs on a GPU (Slurm asks for one).
    pub gpu: bool,
}

/// Every row of a study, planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub study: PathBuf,
    pub rows: Vec<PlannedRow>,
    /// Array tasks each row's regeneration is spread over (1: not split).
    pub split_frames: usize,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> BatchError + '_ {
    move |e| BatchError::io(format!("writing {}", path.display()), e)
}

/// `S01_1_left_walk`: the non-empty fields and the video's stem, in characters any file system
/// takes.
fn folder_name(row: &StudyRow) -> String {
    let stem = Path::new(&row.video)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let parts: Vec<&str> = [&row.subject, &row.session, &row.view, &stem]
        .into_iter()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .collect();
    parts
        .join("_")
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The config of a row: its file (or the default), its `set` overrides, the prosthetic side,
/// and the batch's shared cache.
fn row_config(study: &Study, row: &StudyRow, cache: &Path) -> Result<PipelineConfig, String> {
    let file = (!row.config.trim().is_empty()).then(|| study.resolve(row.config.trim()));
    if let Some(f) = &file
        && !f.is_file()
    {
        return Err(format!("config {} not found", f.display()));
    }
    let mut sets: Vec<String> = row
        .set
        .split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect();
    match row.prosthetic_side.trim() {
        "" => {}
        s @ ("left" | "right") => sets.push(format!("kinematics.prosthetic_side=\"{s}\"")),
        other => {
            return Err(format!(
                "prosthetic_side `{other}` is not left, right or empty"
            ));
        }
    }
    // The view column says what the camera saw; a front or back view is analysed as one.
    if VIEWS.contains(&row.view.trim()) {
        sets.push(format!("kinematics.view=\"{}\"", row.view.trim()));
    }
    sets.push(format!("run.cache_dir={:?}", cache.display().to_string()));
    let config = PipelineConfig::load(file.as_deref(), &sets).map_err(|e| {
        e.to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    })?;
    Ok(config)
}

impl Plan {
    /// Checks every row (video present, view and side known, config and overrides valid, run
    /// folders distinct) and lists all the bad ones in one error.
    pub fn make(
        study: &Study,
        out: &Path,
        split_frames: usize,
    ) -> Result<(Plan, Vec<PipelineConfig>), BatchError> {
        let out = std::path::absolute(out).map_err(|e| BatchError::io("the --out folder", e))?;
        let cache = out.join("cache");
        let mut rows = Vec::new();
        let mut configs = Vec::new();
        let mut bad = Vec::new();
        let mut names: BTreeMap<String, usize> = BTreeMap::new();
        for (i, row) in study.rows.iter().enumerate() {
            let what = format!("row {} ({})", i + 1, row.video);
            let video = std::path::absolute(study.resolve(&row.video)).unwrap_or_default();
            let name = folder_name(row);
            let mut problems = Vec::new();
            if row.video.trim().is_empty() {
                problems.push("no video".to_string());
            } else if !video.is_file() {
                problems.push(format!("video {} not found", video.display()));
            }
            if !row.view.is_empty() && !VIEWS.contains(&row.view.as_str()) {
                problems.push(format!(
                    "view `{}` is not one of {}",
                    row.view,
                    VIEWS.join(", ")
                ));
            }
            if !row.date.trim().is_empty() && !crate::study::is_iso_date(row.date.trim()) {
                problems.push(format!(
                    "date `{}` is not ISO 8601 (YYYY-MM-DD, e.g. 2026-12-04)",
                    row.date
                ));
            }
            if let Some(first) = names.get(&name) {
                problems.push(format!(
                    "writes the same run folder `{name}` as row {}",
                    first + 1
                ));
            }
            names.entry(name.clone()).or_insert(i);
            let config = row_config(study, row, &cache)
                .map_err(|e| problems.push(e))
                .ok();
            if split_frames > 1
                && config
                    .as_ref()
                    .is_some_and(|c| c.regenerator.chains_frames())
            {
                problems.push(
                    "regenerator.init = \"previous\" starts each frame from the one before, which \
                     --split-frames would cut apart: use init = \"noise\" or no --split-frames"
                        .to_string(),
                );
            }
            if !problems.is_empty() {
                bad.push(format!("{what}: {}", problems.join(", ")));
                continue;
            }
            let Some(config) = config else { continue };
            rows.push(PlannedRow {
                index: i,
                name,
                video,
                subject: row.subject.clone(),
                session: row.session.clone(),
                view: row.view.clone(),
                prosthetic_side: row.prosthetic_side.clone(),
                date: row.date.trim().to_string(),
                regenerates: !config.regenerator.is_identity(),
                gpu: config.run.device != gait_core::Device::Cpu,
            });
            configs.push(config);
        }
        bad.extend(Self::inconsistent_visits(&rows, &configs));
        if !bad.is_empty() {
            return Err(BatchError::BadRows {
                path: study.path.clone(),
                rows: bad,
            });
        }
        let study = std::path::absolute(&study.path).unwrap_or_else(|_| study.path.clone());
        let plan = Plan {
            study,
            rows,
            split_frames: split_frames.max(1),
        };
        Ok((plan, configs))
    }

    /// Rows of one visit (subject and session) must agree on the prosthetic side and the
    /// amputation level: the visit's checklist is one patient's.
    fn inconsistent_visits(rows: &[PlannedRow], configs: &[PipelineConfig]) -> Vec<String> {
        let mut bad = Vec::new();
        for ((subject, session), group) in crate::visits::groups(rows) {
            let of = |r: &PlannedRow| {
                let c = rows
                    .iter()
                    .position(|x| x.index == r.index)
                    .map(|i| &configs[i].kinematics);
                (
                    c.and_then(|k| k.prosthetic_side).map(|s| s.name()),
                    c.and_then(|k| k.amputation).map(|a| a.name()),
                )
            };
            let first = of(group[0]);
            if group.iter().any(|r| of(r) != first) {
                let names: Vec<String> = group
                    .iter()
                    .map(|r| format!("row {}", r.index + 1))
                    .collect();
                bad.push(format!(
                "the visit of subject {subject} session {session} ({}): its rows differ in prosthetic side or amputation level",
                names.join(", ")
            ));
            }
        }
        bad
    }

    /// Writes `batch/plan.json` and each row's resolved config into `out`.
    pub fn write(&self, out: &Path, configs: &[PipelineConfig]) -> Result<(), BatchError> {
        let dir = out.join("batch").join("configs");
        std::fs::create_dir_all(&dir).map_err(io(&dir))?;
        for (row, config) in self.rows.iter().zip(configs) {
            let path = dir.join(format!("{}.toml", row.name));
            gait_pipeline::atomic::write(&path, config.to_toml().as_bytes()).map_err(io(&path))?;
        }
        let path = out.join("batch").join("plan.json");
        let json = serde_json::to_vec_pretty(self).unwrap_or_default();
        gait_pipeline::atomic::write(&path, &json).map_err(io(&path))
    }

    /// The plan a `gait batch` wrote into `out`.
    pub fn read(out: &Path) -> Result<Plan, BatchError> {
        let path = out.join("batch").join("plan.json");
        let text = std::fs::read_to_string(&path).map_err(|e| BatchError::NotABatch {
            path: out.to_path_buf(),
            message: format!("cannot read batch/plan.json: {e}"),
        })?;
        serde_json::from_str(&text).map_err(|e| BatchError::NotABatch {
            path: out.to_path_buf(),
            message: format!("batch/plan.json: {e}"),
        })
    }

    /// The resolved config of `row`, as planned.
    pub fn config(out: &Path, row: &PlannedRow) -> Result<PipelineConfig, BatchError> {
        let path = out
            .join("batch")
            .join("configs")
            .join(format!("{}.toml", row.name));
        PipelineConfig::load(Some(&path), &[]).map_err(|e| BatchError::NotABatch {
            path: out.to_path_buf(),
            message: e.to_string(),
        })
    }

    /// The row at study index `index`.
    pub fn row(&self, index: usize) -> Option<&PlannedRow> {
        self.rows.iter().find(|r| r.index == index)
    }
}

/// The run folder of `row`.
pub fn run_dir(out: &Path, row: &PlannedRow) -> PathBuf {
    out.join("runs").join(&row.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn study(dir: &Path, rows: &str) -> Study {
        std::fs::write(dir.join("a.mp4"), b"not decoded at planning").unwrap();
        let path = dir.join("study.csv");
        std::fs::write(&path, format!("{}\n{rows}", crate::study::HEADER.join(","))).unwrap();
        Study::read(&path).unwrap()
    }

    #[test]
    fn rows_get_their_folder_config_and_the_shared_cache() {
        let dir = tempfile::tempdir().unwrap();
        let s = study(
            dir.path(),
            "a.mp4,S 01,2,left,right,,pose.backend=\"ort\"\na.mp4,S02,,,,,\n",
        );
        let out = dir.path().join("out");
        let (plan, configs) = Plan::make(&s, &out, 1).unwrap();
        let names: Vec<&str> = plan.rows.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names, ["S_01_2_left_a", "S02_a"]);
        assert_eq!(
            plan.rows[0].video,
            std::path::absolute(dir.path().join("a.mp4")).unwrap()
        );
        let c = &configs[0];
        assert_eq!(c.kinematics.prosthetic_side, Some(gait_kin::Side::Right));
        assert_eq!(
            c.run.cache_dir,
            Some(std::path::absolute(&out).unwrap().join("cache"))
        );
        assert!(configs[1].kinematics.prosthetic_side.is_none());
        assert!(!plan.rows[0].regenerates && !plan.rows[0].gpu);
        // What a task reads back is what was planned.
        plan.write(&out, &configs).unwrap();
        assert_eq!(Plan::read(&out).unwrap(), plan);
        let back = Plan::config(&out, &plan.rows[0]).unwrap();
        assert_eq!(
            serde_json::to_value(&back).unwrap(),
            serde_json::to_value(c).unwrap()
        );
    }

    #[test]
    fn every_bad_row_is_listed() {
        let dir = tempfile::tempdir().unwrap();
        let s = study(
            dir.path(),
            "a.mp4,S1,,,,,\nb.mp4,S2,,,,,\na.mp4,S1,,,,,\na.mp4,S3,,top,up,,\na.mp4,S4,,,,none.toml,\n",
        );
        let e = Plan::make(&s, &dir.path().join("out"), 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("4 bad row(s)"), "{e}");
        assert!(e.contains("row 2 (b.mp4): video"), "{e}");
        assert!(
            e.contains("row 3 (a.mp4): writes the same run folder `S1_a` as row 1"),
            "{e}"
        );
        assert!(
            e.contains("view `top`") && e.contains("prosthetic_side `up`"),
            "{e}"
        );
        assert!(e.contains("none.toml not found"), "{e}");
    }
}
