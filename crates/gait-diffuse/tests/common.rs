//! Shared helpers for the fixture tests.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::PathBuf;

use candle_core::{DType, Device, Tensor};

pub fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

pub fn tiny() -> PathBuf {
    fixtures().join("tiny")
}

/// Reference tensors written by tools/diffuse/make_fixtures.py.
pub fn expected() -> HashMap<String, Tensor> {
    candle_core::safetensors::load(fixtures().join("expected.safetensors"), &Device::Cpu)
        .expect("expected.safetensors")
}

/// max |ours - ref| / max |ref|.
pub fn rel_err(ours: &Tensor, reference: &Tensor) -> f64 {
    assert_eq!(ours.dims(), reference.dims(), "shape");
    let a = ours
        .to_dtype(DType::F64)
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1::<f64>()
        .unwrap();
    let b = reference
        .to_dtype(DType::F64)
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1::<f64>()
        .unwrap();
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let scale = b.iter().map(|y| y.abs()).fold(0.0, f64::max).max(1e-12);
    diff / scale
}

pub fn assert_close(name: &str, ours: &Tensor, reference: &Tensor, tol: f64) {
    let e = rel_err(ours, reference);
    println!("{name}: max relative error {e:.3e}");
    assert!(e <= tol, "{name}: relative error {e:.3e} > {tol:.0e}");
}

/// The ONNX exports of the tiny models (tools/diffuse/export_onnx.py).
pub fn tiny_onnx() -> PathBuf {
    fixtures().join("tiny_onnx")
}

/// Fails the calling test, saying why, when ONNX Runtime cannot be found.
pub fn require_ort() {
    assert!(
        std::env::var_os("ORT_DYLIB_PATH").is_some_and(|p| !p.is_empty()),
        "ORT_DYLIB_PATH is not set: the ort tests need libonnxruntime.so \
         (from the PyPI onnxruntime==1.31.1 wheel; tools/setup.sh fetches it, tools/test.sh sets it)"
    );
}
