//! Results as columns for pandas: each table a list of (name, dtype, data),
//! numbers as raw native-endian bytes for `numpy.frombuffer`, text as lists.

use gait_core::PoseSequence;
use gait_core::table::{Column, Table};
use gait_kin::KinResult;
use gait_pipeline::RunSummary;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

/// The tables, keypoints and run.json of a finished run.
pub(crate) fn of_run<'py>(py: Python<'py>, s: &RunSummary) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let manifest = serde_json::to_string(&s.manifest).unwrap_or_else(|_| "{}".into());
    out.set_item("manifest", manifest)?;
    out.set_item("scorer", scorer(&s.manifest))?;
    out.set_item("keypoints", keypoints(py, &s.poses)?)?;
    let kin = s.kinematics.as_ref();
    out.set_item("tables", kin.map(|k| tables(py, k)).transpose()?)?;
    Ok(out)
}

/// The tables and filtered keypoints of `gait.kin`.
pub(crate) fn of_kin<'py>(
    py: Python<'py>,
    kin: &KinResult,
    seq: &PoseSequence,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("manifest", py.None())?;
    out.set_item("scorer", "gait-kin")?;
    out.set_item("keypoints", keypoints(py, seq)?)?;
    out.set_item("tables", tables(py, kin)?)?;
    Ok(out)
}

/// keypoints.csv's scorer: the pose stage, as the run wrote it.
fn scorer(m: &gait_pipeline::manifest::RunManifest) -> String {
    let kind = m
        .stages
        .get("pose")
        .map_or("pose".to_string(), |r| r.kind.replace('/', "-"));
    format!("gait-{kind}")
}

/// Names, frame numbers and (frames x names x 3) values of a sequence.
fn keypoints<'py>(py: Python<'py>, seq: &PoseSequence) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("names", &seq.names)?;
    let frames: Vec<i64> = seq.frames.iter().map(|&f| f as i64).collect();
    out.set_item("frames", raw(py, &frames, |v| v.to_ne_bytes()))?;
    let values: Vec<f64> = seq
        .poses
        .iter()
        .flat_map(|p| p.keypoints.iter().flat_map(cells))
        .collect();
    out.set_item("values", raw(py, &values, |v| v.to_ne_bytes()))?;
    Ok(out)
}

/// A keypoint's x, y, likelihood as keypoints.csv has them: all empty when not found.
fn cells(k: &gait_core::Keypoint) -> [f64; 3] {
    if k.is_found() {
        [k.x, k.y, k.likelihood]
    } else {
        [f64::NAN; 3]
    }
}

fn tables<'py>(py: Python<'py>, kin: &KinResult) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for (file, table) in gait_kin::tables(kin) {
        out.set_item(file.trim_end_matches(".csv"), columns(py, &table)?)?;
    }
    Ok(out)
}

/// [(name, numpy dtype, bytes or list)] in file order.
fn columns<'py>(py: Python<'py>, t: &Table) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for (name, column) in &t.columns {
        let (dtype, data): (&str, Bound<'py, PyAny>) = match column {
            Column::Int(v) => ("int64", raw(py, v, |x| x.to_ne_bytes()).into_any()),
            Column::Num(v) => ("float64", raw(py, v, |x| x.to_ne_bytes()).into_any()),
            Column::OptInt(v) if v.iter().all(Option::is_some) => {
                let i: Vec<i64> = v.iter().flatten().copied().collect();
                ("int64", raw(py, &i, |x| x.to_ne_bytes()).into_any())
            }
            // pandas reads an integer column with empty cells as float with NaN.
            Column::OptInt(v) => {
                let f: Vec<f64> = v.iter().map(|x| x.map_or(f64::NAN, |x| x as f64)).collect();
                ("float64", raw(py, &f, |x| x.to_ne_bytes()).into_any())
            }
            Column::Bool(v) => {
                let b: Vec<u8> = v.iter().map(|&x| u8::from(x)).collect();
                ("bool", PyBytes::new(py, &b).into_any())
            }
            Column::Text(v) => ("object", PyList::new(py, v)?.into_any()),
        };
        out.append((name, dtype, data))?;
    }
    Ok(out)
}

fn raw<'py, T: Copy, const N: usize>(
    py: Python<'py>,
    values: &[T],
    bytes: impl Fn(T) -> [u8; N],
) -> Bound<'py, PyBytes> {
    let b: Vec<u8> = values.iter().flat_map(|&v| bytes(v)).collect();
    PyBytes::new(py, &b)
}
