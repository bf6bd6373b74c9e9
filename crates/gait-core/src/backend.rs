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
    /// The faster one available here: ONNX Runtime when its library loads,
    /// else candle. The pipeline decides it when it reads the config and
    /// writes the choice into run.json; a stage given `Auto` undecided runs
    /// candle, which is always there.
    Auto,
}

impl Backend {
    /// `Auto` decided by `ort_loads` (ONNX Runtime's library loads: `Ok`, or why not);
    /// with the reason for the choice, `None` for an explicit backend.
    pub fn decide(
        self,
        ort_loads: impl FnOnce() -> Result<(), String>,
    ) -> (Backend, Option<String>) {
        if self != Backend::Auto {
            return (self, None);
        }
        match ort_loads() {
            Ok(()) => (
                Backend::Ort,
                Some("ONNX Runtime loads here, and is the faster".into()),
            ),
            Err(why) => (
                Backend::Candle,
                Some(format!("ONNX Runtime is not available ({why})")),
            ),
        }
    }
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Backend::Candle => "candle",
            Backend::Ort => "ort",
            Backend::Auto => "auto",
        })
    }
}
