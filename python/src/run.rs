//! `run`, `kin` and the config: the pipeline runs on its own thread with the
//! GIL released; this thread waits, checks for Ctrl-C and reports progress.

use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;

use gait_core::{Keypoint, Pose, PoseSequence};
use gait_pipeline::{PipelineConfig, RunHandle, RunOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{input_error, to_py};
use crate::tables;

/// How often the waiting thread looks for Ctrl-C and progress.
const POLL: Duration = Duration::from_millis(100);

/// The resolved config as TOML: `path` (or the default) with `sets` applied.
#[pyfunction]
#[pyo3(signature = (path=None, sets=Vec::new()))]
pub(crate) fn resolve_config(path: Option<PathBuf>, sets: Vec<String>) -> PyResult<String> {
    Ok(load(path, &sets)?.to_toml())
}

/// The models folder used when none is given.
#[pyfunction]
pub(crate) fn default_models_dir() -> PathBuf {
    gait_pipeline::default_models_dir()
}

/// Runs the pipeline on `input` into `out`, as `gait run` does; returns the
/// run's tables. `on_progress(pass, done, total)` is called from this thread.
#[pyfunction]
#[pyo3(signature = (input, out, config=None, sets=Vec::new(), models_dir=None, terminal=true, on_progress=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run<'py>(
    py: Python<'py>,
    input: PathBuf,
    out: PathBuf,
    config: Option<PathBuf>,
    sets: Vec<String>,
    models_dir: Option<PathBuf>,
    terminal: bool,
    on_progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let config = load(config, &sets)?;
    let handle = RunHandle::default();
    let opts = RunOptions {
        command: command(&input, &out, &sets),
        input,
        out,
        models_dir: models_dir.unwrap_or_else(gait_pipeline::default_models_dir),
        progress: terminal,
        handle: Some(handle.clone()),
    };
    let dir = opts.out.clone();
    let (summary, _outputs) = wait(py, &handle, on_progress.as_ref(), move || {
        gait_pipeline::run_and_write(&config, &opts)
    })?;
    let result = tables::of_run(py, &summary)?;
    result.set_item("dir", dir)?;
    Ok(result)
}

/// The kinematics of keypoints (`values`: frames x names x (x, y, likelihood)),
/// written into `out` as `gait kin` writes them.
#[pyfunction]
#[pyo3(signature = (names, frames, values, fps, out, config=None, sets=Vec::new()))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn kin<'py>(
    py: Python<'py>,
    names: Vec<String>,
    frames: Vec<usize>,
    values: Vec<f64>,
    fps: f64,
    out: PathBuf,
    config: Option<PathBuf>,
    sets: Vec<String>,
) -> PyResult<Bound<'py, PyDict>> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(input_error(format!(
            "fps = {fps} must be a positive frame rate"
        )));
    }
    let k = names.len();
    if values.len() != frames.len() * k * 3 {
        return Err(input_error(format!(
            "{} values for {} frames of {k} keypoints (x, y, likelihood)",
            values.len(),
            frames.len()
        )));
    }
    let config = load(config, &sets)?;
    let poses = values
        .chunks_exact((3 * k).max(1))
        .take(frames.len())
        .map(|row| Pose {
            keypoints: row
                .chunks_exact(3)
                .map(|v| Keypoint::new(v[0], v[1], v[2]))
                .collect(),
        })
        .collect();
    let seq = PoseSequence {
        fps,
        names,
        frames,
        poses,
    };
    let dir = out.clone();
    let (kin, _outputs) = py
        .detach(|| -> Result<_, gait_pipeline::PipelineError> {
            // The table is kept as keypoints.csv and named by kin.json, so that
            // `gait review OUT --frame N` (the checklist's links) opens the folder. It is
            // written after the report, which would otherwise draw its skeleton strip, as the
            // report of `gait kin` (whose keypoints lie elsewhere) does not.
            let keypoints = std::path::absolute(out.join("keypoints.csv"))
                .unwrap_or_else(|_| out.join("keypoints.csv"));
            let tool = format!("gait.kin {}", env!("CARGO_PKG_VERSION"));
            let source = gait_pipeline::KinSource {
                keypoints: &keypoints,
                fps,
                individual: None,
                tool: &tool,
            };
            let written = gait_pipeline::kin_and_write(&seq, &config, &out, &source)?;
            gait_pipeline::write_kin_keypoints(&out, &seq)?;
            Ok(written)
        })
        .map_err(to_py)?;
    let result = tables::of_kin(py, &kin, &seq)?;
    result.set_item("dir", dir)?;
    Ok(result)
}

pub(crate) fn load(path: Option<PathBuf>, sets: &[String]) -> PyResult<PipelineConfig> {
    PipelineConfig::load(path.as_deref(), sets).map_err(to_py)
}

/// What run.json records as the command: the call, in the CLI's terms.
fn command(input: &std::path::Path, out: &std::path::Path, sets: &[String]) -> Vec<String> {
    let mut c = vec![
        "gait.run".to_string(),
        "--input".into(),
        input.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ];
    for s in sets {
        c.extend(["--set".to_string(), s.clone()]);
    }
    c
}

/// Runs `work` on its own thread; meanwhile checks for Ctrl-C (then stops
/// the run after the frame in flight and raises KeyboardInterrupt) and
/// reports progress.
fn wait<T: Send + 'static>(
    py: Python<'_>,
    handle: &RunHandle,
    on_progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce() -> Result<T, gait_pipeline::PipelineError> + Send + 'static,
) -> PyResult<T> {
    let (tx, rx) = mpsc::channel();
    let worker = std::thread::spawn(move || {
        let _ = tx.send(work());
    });
    let mut last = None;
    let mut rx = rx;
    loop {
        // The receiver is not Sync: it goes into the GIL-free closure and comes back.
        let (back, done) = py.detach(move || {
            let done = rx.recv_timeout(POLL);
            (rx, done)
        });
        rx = back;
        if let Some(cb) = on_progress {
            let now = handle.progress();
            if now.is_some() && now != last {
                if let Err(e) = cb.call1(now.clone().unwrap_or_default()) {
                    handle.stop();
                    let _ = py.detach(|| worker.join());
                    return Err(e);
                }
                last = now;
            }
        }
        match done {
            Ok(result) => {
                let _ = worker.join();
                return result.map_err(to_py);
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "the gait run thread ended without a result (a panic; please report it)",
                ));
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        if let Err(interrupt) = py.check_signals() {
            handle.stop();
            // The frame in flight finishes, so the cache stays consistent.
            let _ = py.detach(|| worker.join());
            return Err(interrupt);
        }
    }
}
