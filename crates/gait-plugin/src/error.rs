//! Why loading or calling a plugin failed.

use std::path::PathBuf;

use gait_core::StageError;

/// A plugin could not be loaded, or misbehaved.
#[derive(Debug, thiserror::Error)]
pub enum PluginError {
    #[error(
        "plugin library {path} not found; build it (`cargo build --release -p <plugin crate>`) and check `path` in the stage table (relative paths start at the current directory)"
    )]
    NotFound { path: PathBuf },
    #[error("cannot load plugin library {path}: {reason}")]
    Open { path: PathBuf, reason: String },
    #[error(
        "{path} is not a gait plugin: it does not export `{symbol}` (use gait_plugin::export_edge_detector! or its siblings)"
    )]
    NoEntry { path: PathBuf, symbol: &'static str },
    #[error(
        "plugin {path} was built for gait plugin ABI version {plugin}, but this gait needs ABI version {host}; rebuild the plugin against a gait-plugin crate of ABI version {host}"
    )]
    AbiMismatch {
        path: PathBuf,
        plugin: u32,
        host: u32,
    },
    #[error("plugin {path} is {found}, but the `[{table}]` table needs {wanted}")]
    WrongFamily {
        path: PathBuf,
        table: &'static str,
        found: String,
        wanted: &'static str,
    },
    #[error("plugin {path} is malformed: {reason}")]
    BadDescriptor { path: PathBuf, reason: String },
    #[error("plugin `{plugin}` options: {reason}")]
    Options { plugin: String, reason: String },
    /// The plugin reported an error about its input or options.
    #[error("plugin `{plugin}` {call}: {message}")]
    BadInput {
        plugin: String,
        call: &'static str,
        message: String,
    },
    /// The plugin reported a failure or a caught panic.
    #[error("plugin `{plugin}` {call} failed: {message}")]
    Failed {
        plugin: String,
        call: &'static str,
        message: String,
    },
    /// The plugin's output breaks the ABI's rules; nothing of it was used.
    #[error("plugin `{plugin}` {call} returned malformed data: {reason}")]
    Malformed {
        plugin: String,
        call: &'static str,
        reason: String,
    },
}

impl From<PluginError> for StageError {
    fn from(e: PluginError) -> Self {
        match e {
            PluginError::BadInput { .. } | PluginError::Options { .. } => {
                StageError::BadInput(e.to_string())
            }
            other => StageError::backend("plugin", other),
        }
    }
}
