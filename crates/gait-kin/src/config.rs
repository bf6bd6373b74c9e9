//! The `[postprocess]` and `[kinematics]` TOML tables.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::KinError;

/// Which low-pass filter smooths the keypoint trajectories.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FilterKind {
    /// Zero-phase Butterworth (scipy `butter` + `filtfilt`), the paper's choice.
    Butterworth,
    /// One-Euro filter (Casiez et al. 2012): causal, adaptive cut-off.
    OneEuro,
    /// No smoothing.
    None,
}

/// How gaps left by dropped keypoints are filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GapFillKind {
    /// scipy `CubicSpline` (not-a-knot) through all kept samples of the track.
    CubicSpline,
    /// Straight line between the samples either side of the gap.
    Linear,
    /// Leave gaps empty.
    None,
}

/// Body side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    Left,
    Right,
}

impl Side {
    pub const BOTH: [Side; 2] = [Side::Left, Side::Right];

    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    pub fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

/// `[postprocess]`: keypoint cleaning before the kinematics. Defaults are the paper's settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PostprocessConfig {
    /// Keypoints with a lower likelihood are dropped (paper: 0.5).
    pub likelihood_threshold: f64,
    /// Gap filling method: `cubic_spline` | `linear` | `none`.
    pub gap_fill: GapFillKind,
    /// Longest gap (in frames) that is filled; longer gaps stay empty and are reported.
    /// When unset, `max_gap_s` decides.
    pub max_gap_frames: Option<usize>,
    /// Longest gap (in seconds) that is filled, used when `max_gap_frames` is unset.
    pub max_gap_s: f64,
    /// Low-pass filter: `butterworth` | `one_euro` | `none`.
    pub filter: FilterKind,
    /// Butterworth order (paper: 4).
    pub butterworth_order: usize,
    /// Butterworth cut-off in Hz (paper: 6).
    pub cutoff_hz: f64,
    /// One-Euro minimum cut-off in Hz.
    pub one_euro_min_cutoff_hz: f64,
    /// One-Euro speed coefficient (per pixel/second).
    pub one_euro_beta: f64,
    /// One-Euro cut-off of the derivative filter in Hz.
    pub one_euro_d_cutoff_hz: f64,
    /// Detect and undo left/right leg label swaps.
    pub swap_correction: bool,
}

impl Default for PostprocessConfig {
    fn default() -> Self {
        Self {
            likelihood_threshold: 0.5,
            gap_fill: GapFillKind::CubicSpline,
            max_gap_frames: None,
            max_gap_s: 0.33,
            filter: FilterKind::Butterworth,
            butterworth_order: 4,
            cutoff_hz: 6.0,
            one_euro_min_cutoff_hz: 1.0,
            one_euro_beta: 0.05,
            one_euro_d_cutoff_hz: 1.0,
            swap_correction: true,
        }
    }
}

impl PostprocessConfig {
    /// The gap limit in frames at the given frame rate.
    pub fn max_gap(&self, fps: f64) -> usize {
        match self.max_gap_frames {
            Some(n) => n,
            None => (self.max_gap_s * fps).round().max(0.0) as usize,
        }
    }

    /// Rejects values no analysis can run with.
    pub fn validate(&self, fps: f64) -> Result<(), KinError> {
        let bad =
            |key: &str, why: String| Err(KinError::Config(format!("postprocess.{key}: {why}")));
        if !(0.0..=1.0).contains(&self.likelihood_threshold) {
            return bad("likelihood_threshold", "must be in [0, 1]".into());
        }
        if !(self.max_gap_s.is_finite() && self.max_gap_s >= 0.0) {
            return bad("max_gap_s", "must be a non-negative number".into());
        }
        if self.filter == FilterKind::Butterworth {
            if !(1..=12).contains(&self.butterworth_order) {
                return bad("butterworth_order", "must be 1..=12".into());
            }
            if !(self.cutoff_hz > 0.0 && self.cutoff_hz < fps / 2.0) {
                return bad(
                    "cutoff_hz",
                    format!(
                        "{} Hz must be above 0 and below half the frame rate ({} fps)",
                        self.cutoff_hz, fps
                    ),
                );
            }
        }
        if self.filter == FilterKind::OneEuro {
            for (k, v) in [
                ("one_euro_min_cutoff_hz", self.one_euro_min_cutoff_hz),
                ("one_euro_d_cutoff_hz", self.one_euro_d_cutoff_hz),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return bad(k, "must be a positive number".into());
                }
            }
            if !(self.one_euro_beta.is_finite() && self.one_euro_beta >= 0.0) {
                return bad("one_euro_beta", "must be a non-negative number".into());
            }
        }
        Ok(())
    }
}

/// `[kinematics]`: angles, events, cycles and spatiotemporal parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct KinematicsConfig {
    /// Side of the prosthesis (`left` | `right`); symmetry indices compare it with the intact side.
    pub prosthetic_side: Option<Side>,
    /// Subject height in metres; scales pixels to cm from the median leg length (Winter's
    /// anthropometry: hip-to-ankle = 0.491 x height).
    pub subject_height_m: Option<f64>,
    /// A length known in metres ...
    pub known_length_m: Option<f64>,
    /// ... and the same length measured in the image in pixels (takes precedence over the height).
    pub known_length_px: Option<f64>,
    /// A CSV `side,event,frame[,time_s]` whose events replace the detected ones.
    pub events_csv: Option<PathBuf>,
    /// Fewer complete cycles than this for a side give empty cycles for it and a warning.
    pub min_cycles: usize,
    /// Shortest plausible stride in seconds (closer heel strikes of one foot are merged).
    pub min_stride_s: f64,
    /// Longest plausible stride in seconds (longer heel-strike pairs are not a cycle).
    pub max_stride_s: f64,
}

impl Default for KinematicsConfig {
    fn default() -> Self {
        Self {
            prosthetic_side: None,
            subject_height_m: None,
            known_length_m: None,
            known_length_px: None,
            events_csv: None,
            min_cycles: 2,
            min_stride_s: 0.5,
            max_stride_s: 3.0,
        }
    }
}

impl KinematicsConfig {
    pub fn validate(&self) -> Result<(), KinError> {
        let bad = |key: &str, why: &str| Err(KinError::Config(format!("kinematics.{key}: {why}")));
        for (k, v) in [
            ("subject_height_m", self.subject_height_m),
            ("known_length_m", self.known_length_m),
            ("known_length_px", self.known_length_px),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return bad(k, "must be a positive number");
            }
        }
        if self.known_length_m.is_some() != self.known_length_px.is_some() {
            return bad(
                "known_length_m",
                "set together with known_length_px (or neither)",
            );
        }
        if !(self.min_stride_s > 0.0 && self.max_stride_s > self.min_stride_s) {
            return bad("max_stride_s", "need 0 < min_stride_s < max_stride_s");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers() {
        let p = PostprocessConfig::default();
        assert_eq!(p.likelihood_threshold, 0.5);
        assert_eq!(
            (p.filter, p.butterworth_order, p.cutoff_hz),
            (FilterKind::Butterworth, 4, 6.0)
        );
        assert_eq!(p.gap_fill, GapFillKind::CubicSpline);
        assert_eq!(p.max_gap(30.0), 10);
        assert!(p.validate(30.0).is_ok());
        assert!(p.validate(10.0).is_err(), "6 Hz is above Nyquist at 10 fps");
    }

    #[test]
    fn toml_round_trip_and_unknown_keys() {
        let p: PostprocessConfig =
            toml::from_str("filter = \"one_euro\"\nmax_gap_frames = 5").unwrap();
        assert_eq!((p.filter, p.max_gap(30.0)), (FilterKind::OneEuro, 5));
        let k: KinematicsConfig =
            toml::from_str("prosthetic_side = \"right\"\nsubject_height_m = 1.8").unwrap();
        assert_eq!(k.prosthetic_side, Some(Side::Right));
        let e = toml::from_str::<PostprocessConfig>("cutof_hz = 6")
            .unwrap_err()
            .to_string();
        assert!(e.contains("cutof_hz") && e.contains("cutoff_hz"), "{e}");
        let e = toml::from_str::<PostprocessConfig>("filter = \"kalman\"")
            .unwrap_err()
            .to_string();
        assert!(e.contains("butterworth") && e.contains("one_euro"), "{e}");
        let back: KinematicsConfig = toml::from_str(&toml::to_string(&k).unwrap()).unwrap();
        assert_eq!(back, k);
    }
}
