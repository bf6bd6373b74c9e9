//! The subject's boxes handed to a Python pose stage: `estimate(self, frames, boxes)` gets, per
//! frame, `None` (the subject is not in view; gait empties that frame whatever the stage
//! returns) or a dict in frame pixels: `x0, y0, x1, y1` (the square that holds the whole body,
//! as the built-in BlazePose crops it), `centre` (x, y: the mid-hip), `size` (the square's
//! side) and `score` (the detector's). A top-down model crops there and so follows the same
//! person as the built-in estimator.

use gait_core::PersonBox;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{PythonStageConfig, interpreter};

/// The number of parameters of `owner.estimate`, by `inspect.signature`.
fn estimate_parameters(py: Python<'_>, owner: &Bound<'_, PyAny>) -> PyResult<usize> {
    let method = owner.getattr("estimate")?;
    let signature = py.import("inspect")?.call_method1("signature", (method,))?;
    signature.getattr("parameters")?.len()
}

/// Whether a stage object's `estimate` takes the boxes: its bound method has two parameters,
/// `(frames, boxes)`.
pub(crate) fn wanted(py: Python<'_>, object: &Bound<'_, PyAny>) -> bool {
    estimate_parameters(py, object).is_ok_and(|n| n >= 2)
}

/// Whether the class of a `[pose] kind = "python"` stage takes the subject's boxes, read from
/// its `estimate` (`self, frames, boxes`) without making an instance, so that the subject pass
/// runs for it; false when the module or class does not import (loading the stage says why).
pub fn class_takes_boxes(cfg: &PythonStageConfig) -> bool {
    interpreter::ensure();
    Python::attach(|py| {
        let Ok(module) = py.import(cfg.module.as_str()) else {
            return false;
        };
        module
            .getattr(cfg.class.as_str())
            .and_then(|class| estimate_parameters(py, &class))
            .is_ok_and(|n| n >= 3)
    })
}

/// The Python list of `boxes` (see the module docs).
pub(crate) fn to_python<'py>(
    py: Python<'py>,
    boxes: &[Option<PersonBox>],
) -> PyResult<Bound<'py, PyAny>> {
    let list = PyList::empty(py);
    for b in boxes {
        match b {
            None => list.append(py.None())?,
            Some(b) => {
                let d = PyDict::new(py);
                let [x0, y0, x1, y1] = b.bounds();
                for (k, v) in [("x0", x0), ("y0", y0), ("x1", x1), ("y1", y1)] {
                    d.set_item(k, f64::from(v))?;
                }
                d.set_item("centre", (f64::from(b.centre[0]), f64::from(b.centre[1])))?;
                d.set_item("size", f64::from(b.size()))?;
                d.set_item("score", f64::from(b.score))?;
                list.append(d)?;
            }
        }
    }
    Ok(list.into_any())
}
