//! One module per subcommand.

pub mod ablate;
pub mod edges;
pub mod eval;
pub mod kin;
pub mod models;
pub mod run;

use std::path::PathBuf;

/// The models folder: the flag, else `$GAIT_MODELS_DIR`, else the user cache.
pub fn models_dir(flag: Option<PathBuf>) -> PathBuf {
    if let Some(dir) = flag {
        return dir;
    }
    if let Some(dir) = std::env::var_os("GAIT_MODELS_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(dir);
    }
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(|| PathBuf::from("."));
    cache.join("gait").join("models")
}
