use serde::{Deserialize, Serialize};

/// Which inference engine runs a model stage (`backend = "..."` in the TOML).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// candle: pure Rust, no native runtime needed.
    #[default]
    Candle,
    /// ONNX Runtime through the `ort` crate, on ONNX exports of the model.
    Ort,
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Backend::Candle => "candle",
            Backend::Ort => "ort",
        })
    }
}
