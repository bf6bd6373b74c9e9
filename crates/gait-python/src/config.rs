//! The `[edge|regenerator|pose] kind = "python"` table.

use serde::{Deserialize, Serialize};

/// A stage written in Python. The stage table's `kind` is removed before
/// this is deserialized.
///
/// ```toml
/// [pose]
/// kind = "python"
/// module = "mediapipe_pose"   # found on sys.path (PYTHONPATH, the active venv)
/// class = "MediapipePose"
/// [pose.options]              # the constructor's one argument, as a dict
/// static_image_mode = false
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PythonStageConfig {
    /// The module to import, e.g. "mypkg.model".
    pub module: String,
    /// The class in it; instantiated once per stage with `options`.
    pub class: String,
    #[serde(default)]
    pub options: toml::Table,
}

impl PythonStageConfig {
    /// "module.Class", how messages name the stage.
    pub fn label(&self) -> String {
        format!("{}.{}", self.module, self.class)
    }

    /// The module's source file, for run.json's checksums and the cache key
    /// (so an edited stage is rerun); `None` when it cannot be found.
    pub fn module_file(&self) -> Option<std::path::PathBuf> {
        crate::interpreter::module_file(&self.module)
    }

    /// The options as JSON, which Python turns into its dict.
    pub(crate) fn options_json(&self) -> String {
        // A TOML table always has a JSON form (datetimes become strings).
        serde_json::to_string(&self.options).unwrap_or_else(|_| "{}".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn module_class_and_options() {
        let c: PythonStageConfig =
            toml::from_str("module = \"a.b\"\nclass = \"C\"\n[options]\nk = 2").unwrap();
        assert_eq!(c.label(), "a.b.C");
        assert_eq!(c.options_json(), r#"{"k":2}"#);
    }

    #[test]
    fn unknown_keys_and_missing_class_are_named() {
        let err = toml::from_str::<PythonStageConfig>("module = \"m\"\nclass = \"C\"\nk = 1")
            .unwrap_err()
            .to_string();
        assert!(err.contains('k') && err.contains("options"), "{err}");
        let err = toml::from_str::<PythonStageConfig>("module = \"m\"")
            .unwrap_err()
            .to_string();
        assert!(err.contains("class"), "{err}");
    }
}
