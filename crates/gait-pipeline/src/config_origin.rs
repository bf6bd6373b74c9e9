//! Where each `table.key` of a configuration came from (a file's line, a
//! `--set` option, or the defaults), so an error about a value points at the
//! place the user wrote it rather than at the whole config.

use std::collections::BTreeMap;

/// The origin of every key given in a config file or by `--set`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Origins {
    /// The config as a whole: the file's path or the built-in default.
    base: String,
    /// `table.key` → e.g. `my.toml line 4` or `--set pose.backend=ort`.
    keys: BTreeMap<String, String>,
}

impl Origins {
    /// Origins of a config whose keys all come from `base` (no lines known).
    pub(crate) fn new(base: impl Into<String>) -> Self {
        Self {
            base: base.into(),
            keys: BTreeMap::new(),
        }
    }

    /// Origins of the TOML `text` of `base`: each `key = value` line under a
    /// `[table]` header (or a dotted `table.key = value`) with its line number.
    /// Inline tables are not followed; their keys fall back to the file.
    pub(crate) fn from_toml(base: impl Into<String>, text: &str) -> Self {
        let mut origins = Self::new(base);
        let mut table = String::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if let Some(header) = line.strip_prefix('[') {
                table = header
                    .trim_start_matches('[')
                    .split(']')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .to_string();
                continue;
            }
            let Some((key, _)) = line.split_once('=') else {
                continue;
            };
            let key = key.trim().trim_matches('"');
            if key.is_empty() || key.starts_with('#') || key.contains(char::is_whitespace) {
                continue;
            }
            let path = if table.is_empty() {
                key.to_string()
            } else {
                format!("{table}.{key}")
            };
            let at = format!("{} line {}", origins.base, i + 1);
            origins.keys.entry(path).or_insert(at);
        }
        origins
    }

    /// Records that `path` (`table.key`) was set by the option `set`.
    pub(crate) fn set(&mut self, path: &str, set: &str) {
        // A new `kind` starts the table afresh: its other keys no longer come from the file.
        if let Some(table) = path.strip_suffix(".kind") {
            let prefix = format!("{table}.");
            self.keys.retain(|k, _| !k.starts_with(&prefix));
        }
        self.keys.insert(path.to_string(), format!("--set {set}"));
    }

    /// Where `table.key` came from: its line or `--set`, else the config as a whole.
    pub(crate) fn of(&self, path: &str) -> String {
        match self.keys.get(path) {
            Some(at) => at.clone(),
            None => self.base.clone(),
        }
    }

    /// Where a table came from: its first key given, else the config as a whole.
    pub(crate) fn of_table(&self, table: &str) -> String {
        let prefix = format!("{table}.");
        self.keys
            .iter()
            .find(|(k, _)| k.starts_with(&prefix))
            .map_or_else(|| self.base.clone(), |(_, at)| at.clone())
    }

    /// True when `table.key` was written in the file or by `--set`.
    pub(crate) fn given(&self, path: &str) -> bool {
        self.keys.contains_key(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_get_their_line_and_sets_override_them() {
        let text = "# top\n[pose]\nkind = \"blazepose\"\nbackend = \"ort\"\n\n[run]\nbatch_size = 2\ninput.fps = 25\n";
        let mut o = Origins::from_toml("my.toml", text);
        assert_eq!(o.of("pose.backend"), "my.toml line 4");
        assert_eq!(o.of("run.batch_size"), "my.toml line 7");
        assert_eq!(o.of("run.input.fps"), "my.toml line 8");
        assert_eq!(o.of("edge.kind"), "my.toml");
        assert!(!o.given("edge.kind"));
        o.set("run.batch_size", "run.batch_size=3");
        assert_eq!(o.of("run.batch_size"), "--set run.batch_size=3");
        o.set("pose.kind", "pose.kind=python");
        assert_eq!(o.of("pose.backend"), "my.toml");
    }
}
