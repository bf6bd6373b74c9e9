//! The `[postprocess]` and `[kinematics]` TOML tables.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::KinError;

/// Each foot's outline contrast per frame, left then right (`None` where not measured): what
/// `gait run` reads from the frames for the motion-blur check.
pub type FeetContrast = std::collections::BTreeMap<usize, [Option<f64>; 2]>;

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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
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
    /// Detect and undo left/right leg label swaps; first drop the lower legs of frames where
    /// the pose model drew both legs on one (`gait_kin::collapse`).
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

/// The amputation level, for the gait-deviation checklist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Amputation {
    Transtibial,
    Transfemoral,
}

impl Amputation {
    pub fn name(self) -> &'static str {
        match self {
            Amputation::Transtibial => "transtibial",
            Amputation::Transfemoral => "transfemoral",
        }
    }
}

/// `[kinematics]`: angles, events, cycles and spatiotemporal parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct KinematicsConfig {
    /// Side of the prosthesis (`left` | `right`); symmetry indices compare it with the intact side.
    pub prosthetic_side: Option<Side>,
    /// `transtibial` or `transfemoral`: which checklist items apply (unset: those of both).
    pub amputation: Option<Amputation>,
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
    /// Video frame `[width, height]` in pixels; when known, a walking bout needs every
    /// lower-limb keypoint at least `bout_edge_margin` inside it.
    pub frame_size: Option<[u32; 2]>,
    /// A walking bout needs the pelvis to move over the ground at least this fast, in leg
    /// lengths (hip to ankle) per second.
    pub bout_min_speed: f64,
    /// Margin to the image border for keypoints in a bout, as a fraction of the frame width.
    pub bout_edge_margin: f64,
    /// Shortest walking bout in seconds; shorter runs of walking frames are dropped.
    pub bout_min_s: f64,
    /// Pauses in walking (too slow, direction unknown) up to this long (s) do not end a bout.
    pub bout_bridge_s: f64,
    /// Walking bouts as inclusive input frame ranges `[[first, last], ...]`; replaces detection.
    pub bouts: Option<Vec<[usize; 2]>>,
    /// A stride whose time differs from the median stride time by more than this fraction is
    /// rejected.
    pub cycle_max_stride_deviation: f64,
    /// A stride with a gap (samples the pose model did not give) longer than this (s) in a
    /// keypoint of its leg is rejected.
    pub cycle_max_filled_s: f64,
    /// A stride whose leg keypoints have a lower mean model likelihood is rejected.
    pub cycle_min_likelihood: f64,
    /// A stride whose median thigh or shank length differs from the bout's median by more than
    /// this fraction is rejected.
    pub cycle_segment_tolerance: f64,
    /// A stride whose leg labels are in doubt in more than this share of its frames is rejected
    /// (0: any such frame rejects). In doubt: the swap correction could hardly tell left from
    /// right (see `swap::ContinuitySwap::doubt_frames`). Labels it exchanged back with clear
    /// evidence do not count: single-frame flips of BlazePose's far leg are ordinary, and how
    /// many of them a stride had tipped with the encoding (3 or 4 of 37 frames).
    pub cycle_max_swapped_share: f64,
    /// A stride whose leg (median thigh + shank over the stride, pixels) is shorter than this is
    /// rejected: the walker is too small in the image for the pose model's keypoints to hold
    /// (the sample at 480p, legs of 92 px, tipped events and cycles; at 720p, 137 px, its
    /// events held). 0 turns the check off.
    pub cycle_min_leg_px: f64,
    /// A stride whose legs' image blur (px, the median of the frames measured in it) exceeds
    /// this share of its leg length is rejected (`blurred`): the walker is too blurred for the
    /// pose model (the sample at 0.8 % sharp, 1.3 % blurred by sigma 2 px, 1.8 % by sigma 4, 2.6 %
    /// by sigma 8 with curves 9-14 deg RMS off). 0.015 lets a walker of `cycle_min_leg_px` be
    /// as soft as a sharp frame reads (1.5 px). 0 turns the check off.
    pub cycle_max_blur_share: f64,
    /// The blur of the legs measured per frame (px; `gait run` fills it, `gait kin` reads it
    /// from run.json beside the keypoints). Not a setting: `None` leaves strides unjudged by it.
    #[serde(skip)]
    pub image_blur_px: Option<std::collections::BTreeMap<usize, f64>>,
    /// A stride whose foot, swinging, keeps less than this share of the contrast its outline
    /// has standing (`swing_contrast`) is rejected (`motion_blurred`): the exposure was long
    /// enough to smear the swinging foot, and the pose model draws it elsewhere. The sample with
    /// a 1/30 s shutter reads 0.41-0.56 per stride (stored at CRF 23: mean curves 5.6 deg RMS off,
    /// 8.3 at the worst joint), with a 1/60 s shutter 0.60-0.76 (3.9 deg, as the matrix's sensor
    /// noise), every copy of the robustness matrix 0.74-1.23. Side views only. 0 turns the check off.
    pub cycle_min_swing_contrast: f64,
    /// Each foot's outline contrast per frame (`gait run` fills it, `gait kin` reads it from
    /// run.json). Not a setting: `None` leaves strides unjudged by it.
    #[serde(skip)]
    pub image_feet_contrast: Option<FeetContrast>,
    /// corrections.toml written by a person, a script or `gait review`: swaps, events, excluded
    /// frames, keypoints (format: `gait_kin::corrections`). Read and checked by the analysis.
    pub corrections: Option<PathBuf>,
    /// What the camera saw: `auto` (decided from the keypoints), `left` or `right` (a side
    /// view), `anterior` (walking toward the camera) or `posterior` (away); see [`crate::view`].
    pub view: crate::view::ViewSetting,
}

impl Default for KinematicsConfig {
    fn default() -> Self {
        Self {
            prosthetic_side: None,
            amputation: None,
            subject_height_m: None,
            known_length_m: None,
            known_length_px: None,
            events_csv: None,
            min_cycles: 2,
            min_stride_s: 0.5,
            max_stride_s: 3.0,
            frame_size: None,
            bout_min_speed: 0.25,
            bout_edge_margin: 0.01,
            bout_min_s: 1.0,
            bout_bridge_s: 0.2,
            bouts: None,
            cycle_max_stride_deviation: 0.2,
            cycle_max_filled_s: 0.1,
            cycle_min_likelihood: 0.5,
            cycle_segment_tolerance: 0.2,
            cycle_max_swapped_share: 0.1,
            cycle_min_leg_px: 100.0,
            cycle_max_blur_share: 0.015,
            image_blur_px: None,
            cycle_min_swing_contrast: 0.6,
            image_feet_contrast: None,
            corrections: None,
            view: crate::view::ViewSetting::Auto,
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
        self.validate_bouts()?;
        self.validate_quality()
    }

    fn validate_bouts(&self) -> Result<(), KinError> {
        let bad = |key: &str, why: &str| Err(KinError::Config(format!("kinematics.{key}: {why}")));
        if let Some([w, h]) = self.frame_size
            && (w == 0 || h == 0)
        {
            return bad("frame_size", "width and height must be positive");
        }
        for (k, v) in [
            ("bout_min_speed", self.bout_min_speed),
            ("bout_min_s", self.bout_min_s),
            ("bout_bridge_s", self.bout_bridge_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, "must be a non-negative number");
            }
        }
        if !(0.0..0.5).contains(&self.bout_edge_margin) {
            return bad("bout_edge_margin", "must be in [0, 0.5)");
        }
        if let Some(b) = &self.bouts {
            if b.iter().any(|r| r[0] > r[1]) {
                return bad("bouts", "each bout is [first, last] with first <= last");
            }
            let mut sorted = b.clone();
            sorted.sort_unstable();
            if sorted.windows(2).any(|w| w[1][0] <= w[0][1]) {
                return bad("bouts", "bouts must not overlap");
            }
        }
        Ok(())
    }

    fn validate_quality(&self) -> Result<(), KinError> {
        let bad = |key: &str, why: &str| Err(KinError::Config(format!("kinematics.{key}: {why}")));
        if !(self.cycle_max_stride_deviation.is_finite() && self.cycle_max_stride_deviation > 0.0) {
            return bad("cycle_max_stride_deviation", "must be a positive number");
        }
        if !(self.cycle_max_filled_s.is_finite() && self.cycle_max_filled_s >= 0.0) {
            return bad("cycle_max_filled_s", "must be a non-negative number");
        }
        if !(0.0..=1.0).contains(&self.cycle_min_likelihood) {
            return bad("cycle_min_likelihood", "must be in [0, 1]");
        }
        if !(0.0..1.0).contains(&self.cycle_segment_tolerance) {
            return bad("cycle_segment_tolerance", "must be in [0, 1)");
        }
        if !(0.0..=1.0).contains(&self.cycle_min_swing_contrast) {
            return bad("cycle_min_swing_contrast", "must be in [0, 1]");
        }
        if !(0.0..=1.0).contains(&self.cycle_max_swapped_share) {
            return bad("cycle_max_swapped_share", "must be in [0, 1]");
        }
        if !(self.cycle_min_leg_px.is_finite() && self.cycle_min_leg_px >= 0.0) {
            return bad(
                "cycle_min_leg_px",
                "must be a non-negative number of pixels",
            );
        }
        if !(self.cycle_max_blur_share.is_finite() && self.cycle_max_blur_share >= 0.0) {
            return bad(
                "cycle_max_blur_share",
                "must be a non-negative share of the leg length (0 turns it off)",
            );
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

    #[test]
    fn default_toml_documents_the_kinematics_defaults() {
        let text = include_str!("../../../configs/default.toml");
        let table: toml::Table = toml::from_str(text).unwrap();
        let k: KinematicsConfig = table["kinematics"].clone().try_into().unwrap();
        assert_eq!(k, KinematicsConfig::default());
        for key in [
            "frame_size",
            "bouts",
            "bout_bridge_s",
            "cycle_max_swapped_share",
        ] {
            assert!(text.contains(&format!("{key} =")), "{key}");
        }
    }

    #[test]
    fn bout_and_quality_keys() {
        let k: KinematicsConfig =
            toml::from_str("frame_size = [1768, 994]\nbouts = [[10, 80], [100, 200]]").unwrap();
        assert_eq!(k.frame_size, Some([1768, 994]));
        assert_eq!(k.bouts, Some(vec![[10, 80], [100, 200]]));
        let c: KinematicsConfig = toml::from_str("corrections = \"corrections.toml\"").unwrap();
        assert_eq!(c.corrections, Some(PathBuf::from("corrections.toml")));
        let back: KinematicsConfig = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
        assert!(k.validate().is_ok());
        let back: KinematicsConfig = toml::from_str(&toml::to_string(&k).unwrap()).unwrap();
        assert_eq!(back, k);
        let d = KinematicsConfig::default();
        assert_eq!(
            (d.bout_min_speed, d.bout_edge_margin, d.bout_min_s),
            (0.25, 0.01, 1.0)
        );
        assert!(d.cycle_max_swapped_share == 0.1 && d.bouts.is_none() && d.frame_size.is_none());
        for (text, key) in [
            ("bouts = [[5, 4]]", "bouts"),
            ("bouts = [[1, 10], [10, 20]]", "overlap"),
            ("frame_size = [0, 10]", "frame_size"),
            ("bout_edge_margin = 0.5", "bout_edge_margin"),
            ("cycle_segment_tolerance = 1.0", "cycle_segment_tolerance"),
            ("cycle_min_likelihood = 1.5", "cycle_min_likelihood"),
            (
                "cycle_max_stride_deviation = 0.0",
                "cycle_max_stride_deviation",
            ),
        ] {
            let k: KinematicsConfig = toml::from_str(text).unwrap();
            let e = k.validate().unwrap_err().to_string();
            assert!(e.contains(key), "{text}: {e}");
        }
    }
}
