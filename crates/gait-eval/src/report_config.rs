//! The `[report]` and `[export]` tables of a pipeline config.

use serde::{Deserialize, Serialize};

use crate::EvalError;

/// What goes with `report.html`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReportConfig {
    /// Normative set: a built-in name, a lab's CSV path, or "none".
    pub normative: String,
    /// Write overlay.mp4 (the skeleton drawn on the input video).
    pub overlay: bool,
    /// "skeleton" (the video with the skeleton) or "side_by_side" (original |
    /// regenerated | keypoints, for zero-shot runs).
    pub overlay_layout: OverlayLayout,
    /// overlay.mp4's largest height in pixels (inputs higher are scaled down). 540 is the size
    /// the report plays it at (960 px wide for 16:9) and costs 2 CPU s less than 720 on the
    /// sample (BENCHMARKS.md); 720 or 1080 for a sharper full-screen picture.
    pub overlay_height: u32,
    /// Print report.pdf with headless Chromium; absent = when one is on the PATH.
    pub pdf: Option<bool>,
}

/// How overlay.mp4 is laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OverlayLayout {
    Skeleton,
    SideBySide,
}

impl Default for ReportConfig {
    fn default() -> Self {
        Self {
            normative: crate::normative::builtin_names()[0].to_string(),
            overlay: true,
            overlay_layout: OverlayLayout::Skeleton,
            overlay_height: 540,
            pdf: None,
        }
    }
}

impl ReportConfig {
    /// The normative set, loaded; None when `normative = "none"`.
    pub fn load_normative(&self) -> Result<Option<crate::Normative>, EvalError> {
        if self.normative == "none" {
            return Ok(None);
        }
        crate::Normative::load(&self.normative).map(Some)
    }
}

/// File formats a run can be exported to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExportFormat {
    /// keypoints.c3d: 2-D markers and Vicon-style events.
    C3d,
    /// keypoints.trc: OpenSim marker trajectories.
    Trc,
    /// angles.mot: OpenSim joint angles.
    Mot,
    /// openpose/: one OpenPose JSON per frame.
    Openpose,
}

impl ExportFormat {
    pub const ALL: [ExportFormat; 4] = [Self::C3d, Self::Trc, Self::Mot, Self::Openpose];

    pub fn as_str(self) -> &'static str {
        match self {
            ExportFormat::C3d => "c3d",
            ExportFormat::Trc => "trc",
            ExportFormat::Mot => "mot",
            ExportFormat::Openpose => "openpose",
        }
    }

    /// The file or folder it writes in the run folder.
    pub fn file_name(self) -> &'static str {
        match self {
            ExportFormat::C3d => "keypoints.c3d",
            ExportFormat::Trc => "keypoints.trc",
            ExportFormat::Mot => "angles.mot",
            ExportFormat::Openpose => "openpose",
        }
    }
}

impl std::str::FromStr for ExportFormat {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|f| f.as_str() == s)
            .ok_or_else(|| {
                let all: Vec<&str> = Self::ALL.iter().map(|f| f.as_str()).collect();
                format!(
                    "unknown export format `{s}`; valid formats: {}",
                    all.join(", ")
                )
            })
    }
}

/// Which exports `gait run` writes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExportConfig {
    pub formats: Vec<ExportFormat>,
}

impl Default for ExportConfig {
    fn default() -> Self {
        Self {
            formats: vec![ExportFormat::C3d, ExportFormat::Trc, ExportFormat::Mot],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_parse_with_defaults_and_name_bad_keys() {
        let r: ReportConfig = toml::from_str("overlay = false").unwrap();
        assert!(!r.overlay && r.pdf.is_none());
        assert_eq!(r.normative, crate::normative::builtin_names()[0]);
        let e: ExportConfig = toml::from_str("formats = [\"openpose\", \"c3d\"]").unwrap();
        assert_eq!(e.formats, vec![ExportFormat::Openpose, ExportFormat::C3d]);
        let bad = toml::from_str::<ExportConfig>("formats = [\"xlsx\"]")
            .unwrap_err()
            .to_string();
        assert!(bad.contains("xlsx") && bad.contains("c3d"), "{bad}");
        let none = ReportConfig {
            normative: "none".into(),
            ..Default::default()
        };
        assert!(none.load_normative().unwrap().is_none());
    }
}
