//! The pipeline configuration: one TOML file with a table per stage, plus
//! `--set table.key=value` overrides, resolved into typed stage configs.
//!
//! Each stage table picks its implementation with `kind` (and `backend` where
//! a model runs). Unknown tables, keys, kinds and backends are errors that
//! name the offending key and list the valid choices.

use std::path::{Path, PathBuf};

use gait_core::Device;
use gait_diffuse::RegeneratorConfig;
use gait_edge::EdgeConfig;
use gait_eval::report_config::{ExportConfig, ReportConfig};
use gait_kin::{KinematicsConfig, PostprocessConfig};
use gait_pose::PoseConfig;
use gait_subject::SubjectConfig;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::PipelineError;
use crate::config_origin::Origins;
use crate::one_line;
use crate::selection::SelectionConfig;

/// The built-in baseline: no edge map, passthrough, the default pose model.
pub const DEFAULT_TOML: &str = include_str!("../../../configs/default.toml");

/// Which frames of the input to use.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InputConfig {
    /// First frame index to process (0-based).
    pub first_frame: usize,
    /// Last frame index to process (inclusive); absent = to the end.
    pub last_frame: Option<usize>,
    /// Frame rate; absent = the video's own (image folders default to 30).
    pub fps: Option<f64>,
}

/// How the runner drives the stages.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    /// Frames handed to each stage at once.
    pub batch_size: usize,
    /// Keep per-frame stage results on disk so interrupted or changed runs
    /// recompute only what they must.
    pub cache: bool,
    /// Where the cache lives; absent = `<out>/cache`. Point several runs at
    /// one folder to share stage results between them (ablations).
    pub cache_dir: Option<PathBuf>,
    /// Where the model stages run: "cpu", "cuda" (GPU 0) or "cuda:N"; a GPU
    /// needs a build with `--features cuda` (README, GPU section).
    pub device: Device,
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            batch_size: 4,
            cache: true,
            cache_dir: None,
            device: Device::Cpu,
        }
    }
}

/// The whole resolved configuration of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PipelineConfig {
    pub input: InputConfig,
    pub run: RunConfig,
    /// How people are linked into tracks to follow one subject (gait-subject).
    pub subject: SubjectConfig,
    /// Which frames are regenerated and which are interpolated.
    pub selection: SelectionConfig,
    pub edge: EdgeConfig,
    pub regenerator: RegeneratorConfig,
    pub pose: PoseConfig,
    /// Keypoint clean-up before the angles (gait-kin).
    pub postprocess: PostprocessConfig,
    /// Angles, gait events, cycles and spatiotemporal parameters (gait-kin).
    pub kinematics: KinematicsConfig,
    /// Normative data, overlay video and PDF of the report (gait-eval).
    pub report: ReportConfig,
    /// Files written for other tools (c3d, OpenSim, OpenPose).
    pub export: ExportConfig,
    /// Thresholds of the amputee gait-deviation checklist (gait-checklist).
    pub checklist: gait_checklist::ChecklistConfig,
    /// How each `backend = "auto"` was decided (run.json's `backend_choices`).
    #[serde(skip)]
    pub backend_choices: Vec<String>,
}

const TABLES: [&str; 12] = [
    "input",
    "run",
    "subject",
    "selection",
    "edge",
    "regenerator",
    "pose",
    "postprocess",
    "kinematics",
    "report",
    "export",
    "checklist",
];

impl PipelineConfig {
    /// Loads `path` (a pipeline TOML, or a previous run's `run.json` to
    /// repeat that run), or the built-in default, then applies `sets`.
    pub fn load(path: Option<&Path>, sets: &[String]) -> Result<Self, PipelineError> {
        let (mut origins, mut table) = match path {
            None => (
                Origins::new("configs/default.toml (built in)"),
                parse_toml("default", DEFAULT_TOML)?,
            ),
            Some(p) => {
                let origin = p.display().to_string();
                let text = std::fs::read_to_string(p).map_err(|e| {
                    PipelineError::config(&origin, format!("cannot read the file ({e})"))
                })?;
                if p.extension().is_some_and(|e| e == "json") {
                    let table = from_run_json(&origin, &text)?;
                    (Origins::new(origin), table)
                } else {
                    let table = parse_toml(&origin, &text)?;
                    (Origins::from_toml(origin, &text), table)
                }
            }
        };
        for set in sets {
            apply_set(&mut table, set, &mut origins)?;
        }
        Self::resolve(&origins, table)
    }

    /// Resolves a parsed TOML table; errors name `origin` as the place of every key.
    pub fn from_table(origin: &str, table: toml::Table) -> Result<Self, PipelineError> {
        Self::resolve(&Origins::new(origin), table)
    }

    fn resolve(origins: &Origins, mut table: toml::Table) -> Result<Self, PipelineError> {
        if let Some(bad) = table.keys().find(|k| !TABLES.contains(&k.as_str())) {
            return Err(PipelineError::config(
                origins.of_table(bad),
                format!(
                    "unknown table `[{bad}]`; valid tables: {}",
                    TABLES.join(", ")
                ),
            ));
        }
        let defaults = parse_toml("default", DEFAULT_TOML)?;
        let mut take = |name: &str| -> Result<toml::Table, PipelineError> {
            let given = match table.remove(name) {
                None => toml::Table::new(),
                Some(toml::Value::Table(t)) => t,
                Some(_) => {
                    return Err(PipelineError::config(
                        origins.of(name),
                        format!("`{name}` must be a table `[{name}]`"),
                    ));
                }
            };
            Ok(with_default_kind(given, defaults.get(name)))
        };
        let mut config = Self {
            input: table_as(origins, "input", take("input")?)?,
            run: table_as(origins, "run", take("run")?)?,
            subject: table_as(origins, "subject", take("subject")?)?,
            selection: table_as(origins, "selection", take("selection")?)?,
            edge: table_as(origins, "edge", take("edge")?)?,
            regenerator: table_as(origins, "regenerator", take("regenerator")?)?,
            pose: table_as(origins, "pose", take("pose")?)?,
            postprocess: table_as(origins, "postprocess", take("postprocess")?)?,
            kinematics: table_as(origins, "kinematics", take("kinematics")?)?,
            report: table_as(origins, "report", take("report")?)?,
            export: table_as(origins, "export", take("export")?)?,
            checklist: table_as(origins, "checklist", take("checklist")?)?,
            backend_choices: Vec::new(),
        };
        config.validate(origins)?;
        config.backend_choices = crate::backend_choice::decide(&mut config);
        Ok(config)
    }

    fn validate(&self, origins: &Origins) -> Result<(), PipelineError> {
        let invalid = |table: &str, message: &str| invalid(origins, table, message);
        if self.run.batch_size == 0 {
            return Err(invalid("run", "batch_size must be at least 1"));
        }
        if let Some(last) = self.input.last_frame
            && last < self.input.first_frame
        {
            let key = if origins.given("input.first_frame") {
                "first_frame is after last_frame"
            } else {
                "last_frame is before first_frame"
            };
            return Err(invalid("input", key));
        }
        if self.input.fps.is_some_and(|f| !(f.is_finite() && f > 0.0)) {
            return Err(invalid("input", "fps must be a positive number"));
        }
        self.subject
            .validate()
            .map_err(|e| invalid("subject", &e.to_string()))?;
        self.selection
            .validate()
            .map_err(|e| invalid("selection", &e))?;
        // The frame rate is known only once the input is open; 30 stands in
        // for checks that do not depend on it.
        self.postprocess
            .validate(self.input.fps.unwrap_or(30.0))
            .map_err(|e| invalid("postprocess", &e.to_string()))?;
        self.kinematics
            .validate()
            .map_err(|e| invalid("kinematics", &e.to_string()))?;
        self.checklist
            .validate()
            .map_err(|e| invalid("checklist", &e.to_string()))?;
        if self.report.overlay_height < 64 {
            return Err(invalid(
                "report",
                "overlay_height must be at least 64 (pixels; 540 by default)",
            ));
        }
        // A bad normative file is found before any frame is processed.
        self.report.load_normative().map_err(|e| {
            invalid(
                "report",
                &format!("normative: {}", one_line(&e.to_string())),
            )
        })?;
        if self.regenerator.subject_crop().is_some() && !self.subject.enabled {
            return Err(invalid(
                "regenerator",
                "region = \"subject\" needs the subject pass; set subject.enabled = true or region = \"frame\"",
            ));
        }
        if self.regenerator.needs_edges() && matches!(self.edge, EdgeConfig::None) {
            return Err(invalid(
                "regenerator",
                "kind needs an edge map but [edge] kind is \"none\"; set edge.kind (e.g. \"canny\")",
            ));
        }
        Ok(())
    }

    /// The resolved configuration as TOML, with every default filled in.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot serialise the config: {e}\n"))
    }
}

fn parse_toml(origin: &str, text: &str) -> Result<toml::Table, PipelineError> {
    text.parse::<toml::Table>()
        .map_err(|e| PipelineError::config(origin, one_line(&e.to_string())))
}

/// A run.json holds the resolved config under `config`; running from it
/// repeats that run.
fn from_run_json(origin: &str, text: &str) -> Result<toml::Table, PipelineError> {
    let json: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| PipelineError::config(origin, format!("not valid JSON ({e})")))?;
    let config = json.get("config").ok_or_else(|| {
        PipelineError::config(
            origin,
            "a .json config must be a run.json with a `config` field",
        )
    })?;
    toml::Table::try_from(without_nulls(config.clone()))
        .map_err(|e| PipelineError::config(origin, e))
}

/// TOML has no null: an unset optional key (JSON `null`) is simply absent.
fn without_nulls(value: serde_json::Value) -> serde_json::Value {
    match value {
        serde_json::Value::Object(map) => serde_json::Value::Object(
            map.into_iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| (k, without_nulls(v)))
                .collect(),
        ),
        serde_json::Value::Array(items) => {
            serde_json::Value::Array(items.into_iter().map(without_nulls).collect())
        }
        other => other,
    }
}

/// A table without `kind` gets the default table's kind, so
/// `--set pose.backend=ort` alone keeps the default pose model.
fn with_default_kind(mut given: toml::Table, default: Option<&toml::Value>) -> toml::Table {
    if !given.contains_key("kind")
        && let Some(kind) = default.and_then(|d| d.get("kind"))
    {
        given.insert("kind".into(), kind.clone());
    }
    given
}

fn table_as<T: DeserializeOwned>(
    origins: &Origins,
    name: &str,
    table: toml::Table,
) -> Result<T, PipelineError> {
    T::deserialize(toml::Value::Table(table.clone())).map_err(|e| {
        let message = one_line(&e.to_string());
        let path = match culprit::<T>(&table, &message) {
            Some(key) => format!("{name}.{key}"),
            None => name.to_string(),
        };
        // A missing key was not written anywhere: the kind that asks for it was.
        let at = if origins.given(&path) {
            origins.of(&path)
        } else {
            origins.of(&format!("{name}.kind"))
        };
        PipelineError::config(at, format!("{path}: {message}"))
    })
}

/// The key of `table` that a deserialisation error is about. Serde names it for unknown and
/// missing fields only; otherwise the table is rebuilt key by key (its kind first) and the
/// first key whose arrival brings the same error is the one.
fn culprit<T: DeserializeOwned>(table: &toml::Table, message: &str) -> Option<String> {
    for named in ["unknown field `", "missing field `"] {
        if let Some(rest) = message.split(named).nth(1) {
            return rest.split('`').next().map(str::to_string);
        }
    }
    let mut keys: Vec<&String> = table.keys().collect();
    keys.sort_by_key(|k| k.as_str() != "kind");
    let mut part = toml::Table::new();
    for key in keys {
        part.insert(key.clone(), table[key].clone());
        if let Err(e) = T::deserialize(toml::Value::Table(part.clone()))
            && one_line(&e.to_string()) == message
        {
            return Some(key.clone());
        }
    }
    None
}

/// A config error found after the values were read: `message` starts with the key it is
/// about (alone, or as `table.key`, possibly after a crate's own prefix), and is reported
/// as `table.key ...` at the place that key was given.
fn invalid(origins: &Origins, table: &str, message: &str) -> PipelineError {
    let prefix = format!("{table}.");
    let rest = match message.find(&prefix) {
        Some(at) => &message[at + prefix.len()..],
        None => message,
    };
    let key: String = rest
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect();
    let path = format!("{table}.{key}");
    let at = if origins.given(&path) {
        origins.of(&path)
    } else {
        origins.of_table(table)
    };
    PipelineError::config(at, format!("{table}.{rest}"))
}

/// Applies one `table.key=value` override. The value is read as TOML
/// (numbers, booleans, arrays, quoted strings); anything else is a string.
fn apply_set(
    table: &mut toml::Table,
    set: &str,
    origins: &mut Origins,
) -> Result<(), PipelineError> {
    let origin = format!("--set {set}");
    let (path, raw) = set
        .split_once('=')
        .ok_or_else(|| PipelineError::config(&origin, "expected table.key=value"))?;
    let keys: Vec<&str> = path.trim().split('.').collect();
    if keys.len() < 2 || keys.iter().any(|k| k.is_empty()) {
        return Err(PipelineError::config(
            &origin,
            "expected table.key=value, e.g. pose.backend=ort",
        ));
    }
    let value = format!("v = {raw}")
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(raw.trim().to_string()));
    let mut node = table;
    for key in &keys[..keys.len() - 1] {
        let entry = node
            .entry(key.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        node = entry
            .as_table_mut()
            .ok_or_else(|| PipelineError::config(&origin, format!("`{key}` is not a table")))?;
    }
    let last = keys[keys.len() - 1];
    // Another `kind` is another stage: the old one's keys would not apply to it.
    if last == "kind" && keys.len() == 2 && node.get("kind") != Some(&value) {
        node.clear();
    }
    node.insert(last.to_string(), value);
    origins.set(&keys.join("."), set);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn setting_another_kind_drops_the_old_kinds_keys() {
        let text = "[pose]\nkind = \"blazepose\"\nbackend = \"ort\"\n";
        let c = load_str(text, &["pose.kind=python", "pose.module=m", "pose.class=C"]).unwrap();
        assert!(
            matches!(c.pose, gait_pose::PoseConfig::Python(_)),
            "{:?}",
            c.pose
        );
        let c = load_str(text, &["pose.kind=blazepose"]).unwrap();
        let gait_pose::PoseConfig::Blazepose(b) = c.pose else {
            panic!("{:?}", c.pose)
        };
        assert_eq!(b.backend, gait_core::Backend::Ort);
    }

    fn load_str(text: &str, sets: &[&str]) -> Result<PipelineConfig, PipelineError> {
        let mut t = parse_toml("test", text)?;
        let mut origins = Origins::from_toml("test", text);
        for s in sets {
            apply_set(&mut t, s, &mut origins)?;
        }
        PipelineConfig::resolve(&origins, t)
    }

    #[test]
    fn default_is_the_baseline() {
        let c = PipelineConfig::load(None, &[]).unwrap();
        assert_eq!(c.edge, EdgeConfig::None);
        assert_eq!(c.regenerator, RegeneratorConfig::Passthrough);
        assert!(matches!(c.pose, PoseConfig::Blazepose(_)));
    }

    #[test]
    fn set_overrides_and_keeps_the_kind() {
        let c = load_str("", &["pose.backend=ort", "run.batch_size=2"]).unwrap();
        let PoseConfig::Blazepose(b) = &c.pose else {
            panic!("default pose model changed: {:?}", c.pose)
        };
        assert_eq!(b.backend, gait_core::Backend::Ort);
        assert_eq!(c.run.batch_size, 2);
    }

    #[test]
    fn errors_name_the_key_and_the_choices() {
        let e = load_str("[edge]\nkind = \"sobelx\"\n", &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("edge.kind") && e.contains("sobelx") && e.contains("none"),
            "{e}"
        );
        let e = load_str("[pose]\nbackend = \"tensorrt\"\n", &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("test line 2: pose.backend")
                && e.contains("tensorrt")
                && e.contains("candle")
                && e.contains("ort"),
            "{e}"
        );
        let e = load_str("[pose]\nbackend_typo = 1\n", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("backend_typo") && e.contains("backend"), "{e}");
        let e = load_str("[edges]\n", &[]).unwrap_err().to_string();
        assert!(e.contains("[edges]") && e.contains("edge"), "{e}");
        let e = load_str("[run]\nbatch_size = 0\n", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("batch_size"), "{e}");
        assert!(load_str("x = [", &[]).is_err());
        assert!(load_str("", &["nodot=1"]).is_err());
    }

    #[test]
    fn device_defaults_to_cpu_and_names_the_choices() {
        assert_eq!(load_str("", &[]).unwrap().run.device, Device::Cpu);
        let c = load_str("[run]\ndevice = \"cuda:1\"\n", &[]).unwrap();
        assert_eq!(c.run.device, Device::Cuda(1));
        let c = load_str("", &["run.device=cuda"]).unwrap();
        assert_eq!(c.run.device, Device::Cuda(0));
        let e = load_str("[run]\ndevice = \"gpu\"\n", &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("run.device") && e.contains("gpu") && e.contains("cuda:N"),
            "{e}"
        );
    }

    #[test]
    fn every_error_names_table_key_and_where_the_value_came_from() {
        let cases: [(&str, &[&str], &str); 6] = [
            (
                "",
                &["pose.backnd=ort"],
                "--set pose.backnd=ort: pose.backnd: unknown field",
            ),
            (
                "",
                &["pose.backend=nonsense"],
                "--set pose.backend=nonsense: pose.backend: unknown variant `nonsense`",
            ),
            (
                "",
                &["regenerator.kind=controlnet", "regenerator.crop_size=300"],
                "--set regenerator.crop_size=300: regenerator.crop_size: invalid type: integer `300`",
            ),
            (
                "# study\n[run]\ncache = true\nbatch_size = 0\n",
                &[],
                "test line 4: run.batch_size must be at least 1",
            ),
            (
                "[pose]\nbackend = \"ort\"\n\n[input]\nfirst_frame = \"ten\"\n",
                &[],
                "test line 5: input.first_frame: invalid type: string \"ten\"",
            ),
            (
                "[input]\nlast_frame = 3\n",
                &["input.first_frame=5"],
                "--set input.first_frame=5: input.first_frame is after last_frame",
            ),
        ];
        for (text, sets, expected) in cases {
            let e = load_str(text, sets).unwrap_err().to_string();
            assert!(e.contains(expected), "{sets:?}: {e}");
            assert!(!e.contains("built in"), "{e}");
        }
    }

    #[test]
    fn resolved_config_round_trips() {
        let c = load_str("[run]\nbatch_size = 3\ndevice = \"cuda:2\"\n", &[]).unwrap();
        let text = c.to_toml();
        let back =
            PipelineConfig::from_table("again", parse_toml("again", &text).unwrap()).unwrap();
        assert_eq!(back, c);
    }
}
