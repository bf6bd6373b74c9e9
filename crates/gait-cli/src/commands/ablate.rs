//! `gait ablate`: the cartesian product of stage choices over a list of
//! videos, with stage results shared through one cache, compared in one table.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use gait_eval::{EvalOptions, Side};
use gait_pipeline::{PipelineConfig, RunOptions};
use serde::Deserialize;

use crate::error::{CliError, one_line};

/// `gait ablate --matrix FILE.toml --out DIR`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Matrix file: [[video]] entries (path, optional truth) and [axes] of config values to combine (format: docs/ablate.md)
    #[arg(long, value_name = "FILE")]
    matrix: PathBuf,
    /// Folder for one run folder per video and configuration, the shared cache and comparison.csv/.md
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Do not draw progress bars
    #[arg(long)]
    no_progress: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Matrix {
    /// Pipeline config every run starts from [default: the built-in default].
    base: Option<PathBuf>,
    /// `table.key=value` overrides applied to every run.
    #[serde(default)]
    set: Vec<String>,
    video: Vec<Video>,
    /// `"table.key" = [values...]`: one run per combination.
    #[serde(default)]
    axes: toml::Table,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Video {
    path: PathBuf,
    /// Ground truth keypoints (DeepLabCut CSV or OpenPose JSON folder).
    truth: Option<PathBuf>,
    #[serde(default)]
    prosthetic_side: Option<String>,
}

/// One row of the comparison table.
struct Row {
    video: String,
    label: String,
    frames: usize,
    from_cache: usize,
    seconds: f64,
    metrics: Option<[Option<f64>; 5]>,
    error: Option<String>,
}

const METRIC_COLUMNS: [&str; 5] = [
    "px_err_prosthetic",
    "px_err_intact",
    "knee_mae_prosthetic_deg",
    "knee_mae_intact_deg",
    "failure_frames_pct",
];

pub fn execute(args: Args, models_dir: &Path) -> Result<(), CliError> {
    let text = std::fs::read_to_string(&args.matrix)
        .map_err(|e| CliError::new(format!("{}: cannot read ({e})", args.matrix.display())))?;
    let matrix: Matrix = toml::from_str(&text).map_err(|e| {
        CliError::new(format!(
            "{}: {}",
            args.matrix.display(),
            one_line(&e.to_string())
        ))
    })?;
    if matrix.video.is_empty() {
        return Err(CliError::new(format!(
            "{}: add at least one [[video]] with a path",
            args.matrix.display()
        )));
    }
    let here = args.matrix.parent().unwrap_or(Path::new("."));
    let combos = combinations(&matrix.axes)
        .map_err(|e| CliError::new(format!("{}: {e}", args.matrix.display())))?;
    let cache = args.out.join("cache");
    let mut rows = Vec::new();
    for video in &matrix.video {
        let input = here.join(&video.path);
        let stem = input
            .file_stem()
            .map_or("video".into(), |s| s.to_string_lossy().into_owned());
        for combo in &combos {
            let label = if combo.is_empty() {
                "base".to_string()
            } else {
                combo.join(",")
            };
            eprintln!("ablate: {stem} [{label}]");
            let out = args.out.join(&stem).join(sanitize(&label));
            let mut sets = matrix.set.clone();
            sets.extend(combo.iter().cloned());
            sets.push(format!("run.cache_dir=\"{}\"", cache.display()));
            let started = Instant::now();
            let mut row = Row {
                video: stem.clone(),
                label,
                frames: 0,
                from_cache: 0,
                seconds: 0.0,
                metrics: None,
                error: None,
            };
            match run_one(
                matrix.base.as_ref().map(|b| here.join(b)).as_deref(),
                &sets,
                &input,
                &out,
                models_dir,
                !args.no_progress,
            ) {
                Ok((config, summary)) => {
                    row.frames = summary.manifest.frames_processed;
                    row.from_cache = summary.manifest.frames_from_cache;
                    row.seconds = started.elapsed().as_secs_f64();
                    if let Some(truth) = &video.truth {
                        match score(
                            &here.join(truth),
                            &summary.poses,
                            &config,
                            video.prosthetic_side.as_deref(),
                        ) {
                            Ok(m) => row.metrics = Some(m),
                            Err(e) => row.error = Some(e.message),
                        }
                    }
                }
                Err(e) => row.error = Some(e.message),
            }
            if let Some(e) = &row.error {
                eprintln!("ablate: {} [{}] failed: {e}", row.video, row.label);
            }
            rows.push(row);
        }
    }
    write_tables(&rows, &args.out)?;
    eprintln!(
        "{} runs -> {}",
        rows.len(),
        args.out.join("comparison.md").display()
    );
    Ok(())
}

fn run_one(
    base: Option<&Path>,
    sets: &[String],
    input: &Path,
    out: &Path,
    models_dir: &Path,
    progress: bool,
) -> Result<(PipelineConfig, gait_pipeline::RunSummary), CliError> {
    let config = PipelineConfig::load(base, sets)?;
    let opts = RunOptions {
        input: input.to_path_buf(),
        out: out.to_path_buf(),
        models_dir: models_dir.to_path_buf(),
        progress,
        command: std::env::args().collect(),
        handle: None,
    };
    let summary = gait_pipeline::run(&config, &opts)?;
    Ok((config, summary))
}

/// Every combination of the axes' values as `--set` strings, in file order.
fn combinations(axes: &toml::Table) -> Result<Vec<Vec<String>>, String> {
    let mut combos: Vec<Vec<String>> = vec![Vec::new()];
    for (key, values) in axes {
        let values = values
            .as_array()
            .filter(|v| !v.is_empty())
            .ok_or_else(|| format!("[axes] `{key}` must be a non-empty array of values"))?;
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push(format!("{key}={v}"));
                    c
                })
            })
            .collect();
    }
    Ok(combos)
}

fn sanitize(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Pixel error per leg, knee MAE per leg and the share of failed frames.
fn score(
    truth: &Path,
    pred: &gait_core::PoseSequence,
    config: &PipelineConfig,
    side: Option<&str>,
) -> Result<[Option<f64>; 5], CliError> {
    let side = match side {
        Some("left") => Side::Left,
        None | Some("right") => Side::Right,
        Some(other) => {
            return Err(CliError::new(format!(
                "prosthetic_side `{other}` must be left or right"
            )));
        }
    };
    let truth = gait_eval::read_poses(truth, pred.fps, None)
        .map_err(|e| CliError::new(format!("{}: {}", truth.display(), one_line(&e.to_string()))))?;
    let opts = EvalOptions {
        prosthetic_side: side,
        ..EvalOptions::default()
    };
    let e = gait_eval::evaluate(&truth, pred, &config.postprocess, &config.kinematics, &opts)
        .map_err(|e| CliError::new(one_line(&e.to_string())))?;
    let v = serde_json::to_value(&e).unwrap_or_default();
    let leg = |role: &str| {
        v["legs"]
            .as_array()
            .and_then(|l| l.iter().find(|x| x["role"] == role))
            .and_then(|x| x["stat"]["mean"].as_f64())
    };
    let knee = |role: &str| {
        v["kinematics"]["joints"]
            .as_array()
            .and_then(|l| l.iter().find(|x| x["role"] == role && x["joint"] == "knee"))
            .and_then(|x| x["deg"]["mean"].as_f64())
    };
    Ok([
        leg("prosthetic"),
        leg("intact"),
        knee("prosthetic"),
        knee("intact"),
        v["failures"]["any"]["percent"].as_f64(),
    ])
}

fn write_tables(rows: &[Row], out: &Path) -> Result<(), CliError> {
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::new(format!("creating {}: {e}", out.display())))?;
    let cell = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.3}"));
    let mut csv = format!(
        "video,config,frames,frames_from_cache,seconds,seconds_per_frame,{},error\n",
        METRIC_COLUMNS.join(",")
    );
    let mut md = format!(
        "| video | config | frames | from cache | s/frame | {} | error |\n|{}\n",
        METRIC_COLUMNS.join(" | "),
        "---|".repeat(6 + METRIC_COLUMNS.len())
    );
    for r in rows {
        let per_frame = (r.frames > 0).then(|| r.seconds / r.frames as f64);
        let metrics: Vec<String> = r.metrics.map_or(vec![String::new(); 5], |m| {
            m.iter().map(|v| cell(*v)).collect()
        });
        let error = r.error.clone().unwrap_or_default();
        let _ = writeln!(
            csv,
            "{},\"{}\",{},{},{:.3},{},{},\"{}\"",
            r.video,
            r.label.replace('"', "\"\""),
            r.frames,
            r.from_cache,
            r.seconds,
            cell(per_frame),
            metrics.join(","),
            error.replace('"', "\"\"")
        );
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} |",
            r.video,
            r.label,
            r.frames,
            r.from_cache,
            cell(per_frame),
            metrics.join(" | "),
            error.replace('|', "/")
        );
    }
    for (name, text) in [("comparison.csv", csv), ("comparison.md", md)] {
        let path = out.join(name);
        gait_pipeline::atomic::write(&path, text.as_bytes())
            .map_err(|e| CliError::new(format!("writing {}: {e}", path.display())))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn combinations_are_the_cartesian_product() {
        let axes: toml::Table = toml::from_str(
            "\"edge.kind\" = [\"none\", \"canny\"]\n\"pose.backend\" = [\"candle\", \"ort\"]\n",
        )
        .unwrap();
        let c = combinations(&axes).unwrap();
        assert_eq!(c.len(), 4);
        assert_eq!(
            c[0],
            vec![
                "edge.kind=\"none\"".to_string(),
                "pose.backend=\"candle\"".to_string()
            ]
        );
        assert_eq!(
            c[3],
            vec![
                "edge.kind=\"canny\"".to_string(),
                "pose.backend=\"ort\"".to_string()
            ]
        );
        assert!(combinations(&toml::from_str("\"a.b\" = []").unwrap()).is_err());
        assert_eq!(
            combinations(&toml::Table::new()).unwrap(),
            vec![Vec::<String>::new()]
        );
    }
}
