//! ONNX Runtime allows one environment per process. Every stage with an
//! `ort` backend (HED, BlazePose, ...) takes it from here, so a pipeline that
//! runs several of them in one process shares it instead of failing.
//!
//! The runtime library is loaded at run time (`ort`'s `load-dynamic`) from
//! `$ORT_DYLIB_PATH`; `tools/setup.sh` fetches it from the PyPI
//! `onnxruntime` wheel.

use std::path::Path;
use std::sync::OnceLock;

pub use ort::environment::Environment;

/// The process's ONNX Runtime environment, created on first use.
///
/// The error is a one-line message saying what to do.
pub fn environment() -> Result<Environment, String> {
    static ENV: OnceLock<Result<Environment, String>> = OnceLock::new();
    ENV.get_or_init(|| {
        let lib = std::env::var_os("ORT_DYLIB_PATH").filter(|p| !p.is_empty()).ok_or_else(|| {
            "ORT_DYLIB_PATH is not set; point it at libonnxruntime.so (tools/setup.sh fetches it from the PyPI onnxruntime wheel)"
                .to_string()
        })?;
        ort::init_from(&lib)
            .map_err(|e| format!("cannot load ONNX Runtime from {}: {e}", Path::new(&lib).display()))?
            .with_name("gait")
            .build()
            .map_err(|e| format!("cannot start ONNX Runtime: {e}"))
    })
    .clone()
}

#[cfg(test)]
mod tests {
    #[test]
    fn one_environment_however_often_asked() {
        if std::env::var_os("ORT_DYLIB_PATH").is_none() {
            let e = super::environment().unwrap_err();
            assert!(e.contains("ORT_DYLIB_PATH"), "{e}");
            return;
        }
        // A second real environment would fail inside ONNX Runtime.
        for _ in 0..3 {
            super::environment().unwrap();
        }
    }
}
