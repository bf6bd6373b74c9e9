//! overlay.mp4 of a run folder: the input's analysed frames, decoded again,
//! with gait-overlay's marks drawn over them (and, side by side, the
//! regenerated frames from the run's cache).

use std::path::{Path, PathBuf};

use gait_eval::report_config::OverlayLayout;
use gait_overlay::{
    Backdrop, FrameMarks, Layout, OverlayOptions, OverlayWriter, encoded_size, marks_from_run_dir,
};
use indicatif::{ProgressBar, ProgressStyle};

use crate::input::InputInfo;
use crate::{PipelineConfig, PipelineError};

fn failed(e: impl ToString) -> PipelineError {
    PipelineError::Output {
        what: "overlay.mp4".into(),
        message: e.to_string(),
    }
}

/// The regenerator's cached images of this run (zero-shot runs, one
/// `{frame:06}.png` each), found from the cache key that run.json records.
pub fn regenerated_dir(dir: &Path, config: &PipelineConfig) -> Option<PathBuf> {
    let root = crate::plan::cache_root(config, dir)?;
    let text = std::fs::read_to_string(dir.join("run.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let key = v.pointer("/stages/regenerator/cache_key")?.as_str()?;
    let folder = crate::cache::folder(&root, "regenerator", key);
    folder.is_dir().then_some(folder)
}

/// `m` with its keypoints in the pixels of frames scaled by `s`.
fn scaled(m: &FrameMarks, s: f64) -> FrameMarks {
    let mut m = m.clone();
    if let Some(p) = &mut m.pose {
        for k in &mut p.keypoints {
            (k.x, k.y) = (k.x * s, k.y * s);
        }
    }
    m
}

fn bar(progress: bool, n: usize) -> ProgressBar {
    if !progress {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(n as u64);
    if let Ok(style) =
        ProgressStyle::with_template("overlay.mp4 {bar:30} {pos}/{len} frames ({per_sec}, {eta})")
    {
        b.set_style(style);
    }
    b
}

/// Writes `<dir>/overlay.mp4`; returns its path and warnings (missing run
/// outputs, the mpeg4 fallback).
pub(crate) fn write_overlay(
    dir: &Path,
    input: &Path,
    config: &PipelineConfig,
    progress: bool,
    handle: Option<&crate::RunHandle>,
) -> Result<(PathBuf, Vec<String>), PipelineError> {
    let run = marks_from_run_dir(dir).map_err(failed)?;
    let info = InputInfo::open(input)?;
    let layout = match config.report.overlay_layout {
        OverlayLayout::Skeleton => Layout::Skeleton,
        OverlayLayout::SideBySide => Layout::SideBySide {
            backdrop: Backdrop::Dark,
        },
    };
    let regenerated = match layout {
        Layout::SideBySide { .. } => regenerated_dir(dir, config),
        Layout::Skeleton => None,
    };
    let opts = OverlayOptions {
        layout,
        max_height: Some(config.report.overlay_height),
        ..Default::default()
    };
    // A skeleton overlay shown smaller than the input is decoded at that size.
    let (w, h) = match layout {
        Layout::Skeleton => encoded_size(info.width, info.height, &opts),
        Layout::SideBySide { .. } => (info.width, info.height),
    };
    let scale = f64::from(h) / f64::from(info.height.max(1));
    let path = dir.join("overlay.mp4");
    let (mut writer, mut warnings) =
        OverlayWriter::start(&path, w, h, run.fps, &run.names, &opts).map_err(failed)?;
    warnings.extend(run.warnings);
    let bar = bar(progress, run.marks.len());
    let mut marks = run.marks.iter().peekable();
    let mut reader = info.frames_at(((w, h) != (info.width, info.height)).then_some((w, h)))?;
    while let Some(frame) = reader.next_frame()? {
        // Stopped: the writer's drop removes the unfinished file.
        crate::outputs::stop_point(handle, "overlay.mp4")?;
        // Marks of frames the video lacks (it ended early) are skipped.
        while marks.next_if(|m| m.frame < frame.index).is_some() {}
        let Some(m) = marks.next_if(|m| m.frame == frame.index) else {
            if marks.peek().is_none() {
                break;
            }
            continue;
        };
        let regen = regenerated
            .as_ref()
            .and_then(|d| crate::read_cache_entry(&d.join(format!("{:06}.png", frame.index))))
            .and_then(|png| image::load_from_memory(&png).ok())
            .map(|i| i.to_rgb8());
        writer
            .push(&frame.image, regen.as_ref(), &scaled(m, scale))
            .map_err(failed)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    let path = writer.finish().map_err(failed)?;
    Ok((path, warnings))
}
