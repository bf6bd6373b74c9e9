//! What a Python pose stage costs per frame beyond its own time: calls of
//! examples/python/constant_pose.py through gait (frames handed as numpy views,
//! keypoints read back and checked) against the same call made from Python on
//! an array of the same shape. Run by tools/python/bench_stage.sh.
//!
//! Usage: stage_overhead [WIDTH HEIGHT CALLS] with PYTHONPATH=examples/python
//! and a virtual environment with numpy active.

use std::time::Instant;

use gait_core::{Frame, StageContext};
use gait_python::PythonStageConfig;
use image::RgbImage;
use pyo3::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let (w, h, calls) = match args[..] {
        [w, h, n] => (w, h, n),
        _ => (1920, 1080, 2000),
    };
    let cfg: PythonStageConfig =
        toml::from_str("module = \"constant_pose\"\nclass = \"ConstantPose\"")?;
    let mut stage = gait_python::load_pose_estimator(&cfg, &StageContext::new("."))?;
    let frame = vec![Frame::new(
        0,
        RgbImage::from_pixel(w as u32, h as u32, image::Rgb([90, 120, 150])),
    )];
    for _ in 0..100 {
        stage.estimate(&frame)?;
    }
    let t = Instant::now();
    for _ in 0..calls {
        stage.estimate(&frame)?;
    }
    let through_gait = t.elapsed().as_secs_f64() / calls as f64;
    let own = Python::attach(|py| own_time(py, w, h, calls))?;
    println!(
        "{w}x{h}, {calls} calls: through gait {:.1} us/frame, the stage's own {:.1} us/frame, overhead {:.1} us/frame",
        through_gait * 1e6,
        own * 1e6,
        (through_gait - own) * 1e6
    );
    Ok(())
}

/// Seconds per `estimate([frame])` called from Python itself.
fn own_time(py: Python<'_>, w: usize, h: usize, calls: usize) -> PyResult<f64> {
    let code = format!(
        "import timeit, numpy as np, constant_pose\n\
         s = constant_pose.ConstantPose({{}})\n\
         f = np.zeros(({h}, {w}, 3), np.uint8)\n\
         f.flags.writeable = False\n\
         t = timeit.timeit(lambda: s.estimate([f]), number={calls}) / {calls}\n"
    );
    let globals = pyo3::types::PyDict::new(py);
    py.run(&std::ffi::CString::new(code)?, Some(&globals), None)?;
    globals.get_item("t")?.map_or(Ok(f64::NAN), |t| t.extract())
}
