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
pub use ort::session::Session;

/// Where ONNX Runtime runs a model (`[run] device`). CUDA needs an ONNX
/// Runtime library built with it (the `onnxruntime-gpu` wheel's, not
/// `onnxruntime`'s).
pub use gait_core::Device;

/// Opens the ONNX file `path` in the shared environment, on `device`, with
/// one intra-op thread per two cores and no busy-waiting workers.
///
/// A CUDA request that the loaded library cannot serve fails instead of
/// silently running on the CPU.
pub fn session(path: &Path, device: Device) -> Result<Session, SessionError> {
    let runtime = |e: ort::Error<_>| SessionError::Runtime(e.to_string());
    let env = environment().map_err(SessionError::Runtime)?;
    // Half the cores: ffmpeg decodes the next frames and the pipeline prepares crops beside the
    // model, and BlazePose's small convolutions gain little from more threads. On the 2-core
    // machine of BENCHMARKS.md one thread took 0.4-1.1 CPU s less on the sample's run than two,
    // at the same wall time, with identical keypoints.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = (cores / 2).max(1);
    let mut builder = Session::builder(&env)
        .map_err(|e| SessionError::Runtime(e.to_string()))?
        .with_intra_threads(threads)
        .map_err(runtime)?
        // Spinning workers burn the cores that other stages (and other
        // processes on a small machine) need between ops; measured on the
        // BlazePose detector with 2 threads: 23 ms spinning, 12 ms not.
        .with_intra_op_spinning(false)
        .map_err(runtime)?;
    if let Device::Cuda(ordinal) = device {
        let cuda = ort::ep::CUDA::default()
            .with_device_id(ordinal as i32)
            .build()
            .error_on_failure();
        builder = builder.with_execution_providers([cuda]).map_err(|e| {
            SessionError::Runtime(format!(
                "cannot use CUDA device {ordinal} in ONNX Runtime ({e}); the library at $ORT_DYLIB_PATH must come from the onnxruntime-gpu wheel"
            ))
        })?;
    }
    builder
        .commit_from_file(path)
        .map_err(|e| SessionError::Model(format!("{}: {e}", path.display())))
}

/// Why [`session`] failed, as one-line messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SessionError {
    /// ONNX Runtime itself: library not found or not loadable, or the
    /// requested execution provider missing. Not the model file's fault.
    Runtime(String),
    /// The model file: missing, unreadable, or not a valid ONNX graph.
    Model(String),
}

impl std::fmt::Display for SessionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SessionError::Runtime(m) | SessionError::Model(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for SessionError {}

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
    use super::*;

    #[test]
    fn cuda_on_a_cpu_only_runtime_is_a_clear_error() {
        // The provider is registered before the model is read, so no model is needed.
        let err = session(Path::new("/nonexistent.onnx"), Device::Cuda(0))
            .err()
            .unwrap();
        assert!(matches!(err, SessionError::Runtime(_)), "{err:?}");
        let text = err.to_string();
        if std::env::var_os("ORT_DYLIB_PATH").is_none() {
            assert!(text.contains("ORT_DYLIB_PATH"), "{text}");
            return;
        }
        eprintln!("{text}");
        assert!(
            text.contains("CUDA") && text.contains("onnxruntime-gpu"),
            "{text}"
        );
        let err = session(Path::new("/nonexistent.onnx"), Device::Cpu)
            .err()
            .unwrap();
        assert!(matches!(err, SessionError::Model(_)), "{err:?}");
        assert!(err.to_string().contains("/nonexistent.onnx"), "{err}");
    }

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
