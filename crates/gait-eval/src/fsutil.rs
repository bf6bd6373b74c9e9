//! Writing files so that a reader never sees a half-written one.

use std::path::Path;

use crate::EvalError;

/// Writes `bytes` to `path` atomically (a temporary sibling renamed into place).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), EvalError> {
    gait_core::atomic::write(path, bytes)
        .map_err(|e| EvalError::io(format!("writing {}", path.display()), e))
}

/// Creates `dir` and its parents.
pub fn ensure_dir(dir: &Path) -> Result<(), EvalError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| EvalError::io(format!("creating {}", dir.display()), e))
}
