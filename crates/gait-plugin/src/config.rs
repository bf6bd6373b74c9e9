//! The `[edge|regenerator|pose] kind = "plugin"` table.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// A stage loaded from a shared library. The stage table's `kind` is removed
/// before this is deserialized.
///
/// ```toml
/// [edge]
/// kind = "plugin"
/// path = "target/release/libgait_sobel_edge.so"
/// [edge.options]
/// threshold = 120.0
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PluginConfig {
    /// The library; a relative path is taken from the current directory.
    pub path: PathBuf,
    /// The plugin's own options, handed to it as a JSON object.
    #[serde(default)]
    pub options: toml::Table,
}

impl PluginConfig {
    /// The library path, relative paths resolved against the current directory.
    pub fn resolved_path(&self) -> PathBuf {
        resolve(&self.path)
    }

    /// The options as the JSON object the plugin receives.
    pub fn options_json(&self) -> String {
        // A TOML table always has a JSON form (datetimes become strings).
        serde_json::to_string(&self.options).unwrap_or_else(|_| "{}".into())
    }
}

fn resolve(path: &Path) -> PathBuf {
    if path.is_absolute() {
        return path.to_path_buf();
    }
    match std::env::current_dir() {
        Ok(cwd) => cwd.join(path),
        Err(_) => path.to_path_buf(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_and_options() {
        let c: PluginConfig =
            toml::from_str("path = \"lib/x.so\"\n[options]\nthreshold = 3.5\nname = \"a\"")
                .unwrap();
        assert_eq!(c.path, PathBuf::from("lib/x.so"));
        assert_eq!(c.options_json(), r#"{"name":"a","threshold":3.5}"#);
        assert!(c.resolved_path().is_absolute());
        assert!(c.resolved_path().ends_with("lib/x.so"));
    }

    #[test]
    fn options_default_to_empty() {
        let c: PluginConfig = toml::from_str("path = \"/abs/x.so\"").unwrap();
        assert_eq!(c.options_json(), "{}");
        assert_eq!(c.resolved_path(), PathBuf::from("/abs/x.so"));
    }

    #[test]
    fn unknown_key_is_named() {
        let err = toml::from_str::<PluginConfig>("path = \"x.so\"\nthreshold = 3")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("threshold") && err.contains("options"),
            "{err}"
        );
    }

    /// The way the stage crates hold it: a variant of their `kind`-tagged
    /// config enum (serde removes `kind` before the variant sees the table).
    #[derive(Debug, Deserialize)]
    #[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
    enum StageTable {
        #[allow(dead_code, reason = "only parsed")]
        Canny {
            low: f64,
        },
        Plugin(PluginConfig),
    }

    #[test]
    fn as_a_variant_of_a_kind_tagged_enum() {
        let t: StageTable =
            toml::from_str("kind = \"plugin\"\npath = \"x.so\"\n[options]\nthreshold = 2").unwrap();
        let StageTable::Plugin(c) = t else {
            panic!("not a plugin: {t:?}")
        };
        assert_eq!(c.options_json(), r#"{"threshold":2}"#);
        let err = toml::from_str::<StageTable>("kind = \"plugin\"\npath = \"x.so\"\nthreshold = 2")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("threshold") && err.contains("options"),
            "{err}"
        );
        let err = toml::from_str::<StageTable>("kind = \"plugn\"")
            .unwrap_err()
            .to_string();
        assert!(err.contains("plugin") && err.contains("canny"), "{err}");
    }

    #[test]
    fn path_is_required() {
        let err = toml::from_str::<PluginConfig>("").unwrap_err().to_string();
        assert!(err.contains("path"), "{err}");
    }
}
