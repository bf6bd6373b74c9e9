//! The paper's two speed-ups (Discussion): regenerate only the frames whose
//! pose on the original frame is poor, and run the pipeline on every k-th
//! frame only. This file holds the `[selection]` config and the poor-frame
//! rule; `interpolate.rs` fills the skipped frames.

use gait_core::keypoint::LOWER_LIMB;
use std::collections::BTreeMap;

use gait_core::Pose;
use serde::{Deserialize, Serialize};

/// Which frames go through edges -> regenerator -> pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SelectionMode {
    /// Every processed frame is regenerated (the paper's pipeline).
    All,
    /// The pose estimator first runs on the original frames; only frames
    /// with a poor lower-limb pose are regenerated, the rest keep it.
    Poor,
}

/// How the lower-limb likelihoods of a frame are combined before the
/// threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LikelihoodStat {
    /// The weakest keypoint decides (matches the postprocess, which drops
    /// single keypoints below its threshold).
    Min,
    Mean,
}

/// The `[selection]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SelectionConfig {
    pub mode: SelectionMode,
    /// Run the pipeline on every `stride`-th frame (and the last one);
    /// keypoints of the frames between are interpolated.
    pub stride: usize,
    /// A frame is poor when the `likelihood` statistic of its lower-limb
    /// keypoints is below this (or one of them is missing).
    pub min_likelihood: f64,
    pub likelihood: LikelihoodStat,
    /// Allowed band of each thigh and shank length relative to the median
    /// length of that segment over the run's frames that pass the
    /// likelihood test (both sides pooled).
    pub segment_ratio: [f64; 2],
    /// Allowed band of left / right thigh and left / right shank length.
    pub side_ratio: [f64; 2],
    /// The keypoints the rule looks at; models without feet can drop the
    /// heels and toes here.
    pub keypoints: Vec<String>,
}

impl Default for SelectionConfig {
    fn default() -> Self {
        Self {
            mode: SelectionMode::All,
            stride: 1,
            min_likelihood: 0.5,
            likelihood: LikelihoodStat::Min,
            segment_ratio: [0.6, 1.6],
            side_ratio: [0.6, 1.6],
            keypoints: LOWER_LIMB.iter().map(|s| s.to_string()).collect(),
        }
    }
}

impl SelectionConfig {
    /// Checks the values; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        if self.stride == 0 {
            return Err("stride must be at least 1 (1 = every frame)".into());
        }
        if !(0.0..=1.0).contains(&self.min_likelihood) {
            return Err(format!(
                "min_likelihood must be in [0, 1], got {}",
                self.min_likelihood
            ));
        }
        for (key, [lo, hi]) in [
            ("segment_ratio", self.segment_ratio),
            ("side_ratio", self.side_ratio),
        ] {
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
                return Err(format!(
                    "{key} must be [lo, hi] with 0 < lo <= hi, got [{lo}, {hi}]"
                ));
            }
        }
        if self.mode == SelectionMode::Poor && self.keypoints.is_empty() {
            return Err("keypoints is empty: the poor-frame rule needs keypoints to judge".into());
        }
        Ok(())
    }

    /// True for the plain pipeline (every frame, all regenerated).
    pub fn is_default_flow(&self) -> bool {
        self.mode == SelectionMode::All && self.stride == 1
    }

    /// What, besides the pose config, decides the order in which the pose
    /// estimator sees the regenerated frames (and so a tracker's state);
    /// `None` for the plain pipeline, whose cache keys stay as they were.
    pub(crate) fn tracking_key(&self) -> Option<serde_json::Value> {
        match self.mode {
            _ if self.is_default_flow() => None,
            SelectionMode::All => Some(serde_json::json!({ "stride": self.stride })),
            SelectionMode::Poor => serde_json::to_value(self).ok(),
        }
    }
}

/// Why a frame was judged poor; the first rule that fires is recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PoorReason {
    Missing,
    LowLikelihood,
    SegmentLength,
    LeftRight,
}

impl PoorReason {
    pub fn describe(self) -> &'static str {
        match self {
            PoorReason::Missing => "missing keypoints",
            PoorReason::LowLikelihood => "low likelihood",
            PoorReason::SegmentLength => "segment lengths",
            PoorReason::LeftRight => "left/right mismatch",
        }
    }
}

/// Median segment lengths (pixels) the segment test compared with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SegmentMedians {
    pub thigh: Option<f64>,
    pub shank: Option<f64>,
}

/// The verdict on each frame, in the order of the poses given.
#[derive(Debug, Clone, PartialEq)]
pub struct Judgement {
    pub reasons: Vec<Option<PoorReason>>,
    pub medians: SegmentMedians,
}

/// Applies the poor-frame rule to the original-frame poses of a run.
/// `names` are the estimator's keypoint names; a configured keypoint the
/// estimator lacks is an error naming it.
pub fn judge(
    poses: &[Pose],
    names: &[String],
    config: &SelectionConfig,
) -> Result<Judgement, String> {
    let index = |name: &str| names.iter().position(|n| n == name);
    let mut watched = Vec::new();
    for k in &config.keypoints {
        watched.push(index(k).ok_or_else(|| {
            format!(
                "the pose model has no keypoint `{k}`; it has {}",
                names.join(", ")
            )
        })?);
    }
    let in_rule = |name: &str| config.keypoints.iter().any(|k| k == name);
    // Segments whose both ends are judged: (kind, left, right) as index pairs.
    let mut segments = Vec::new();
    for (kind, a, b) in [(0, "hip", "knee"), (1, "knee", "ankle")] {
        let pair = |side: &str| {
            let (x, y) = (format!("{side}_{a}"), format!("{side}_{b}"));
            (in_rule(&x) && in_rule(&y)).then(|| (index(&x), index(&y)))
        };
        if let (Some((Some(la), Some(lb))), Some((Some(ra), Some(rb)))) =
            (pair("left"), pair("right"))
        {
            segments.push((kind, (la, lb), (ra, rb)));
        }
    }

    let mut reasons: Vec<Option<PoorReason>> = poses
        .iter()
        .map(|p| likelihood_reason(p, &watched, config))
        .collect();
    let length = |p: &Pose, (a, b): (usize, usize)| {
        let (ka, kb) = (p.keypoints[a], p.keypoints[b]);
        (ka.x - kb.x).hypot(ka.y - kb.y)
    };
    let mut pooled = [Vec::new(), Vec::new()];
    for (pose, reason) in poses.iter().zip(&reasons) {
        if reason.is_none() {
            for &(kind, l, r) in &segments {
                pooled[kind].push(length(pose, l));
                pooled[kind].push(length(pose, r));
            }
        }
    }
    let medians = [median(&mut pooled[0]), median(&mut pooled[1])];
    let inside = |ratio: f64, [lo, hi]: [f64; 2]| ratio >= lo && ratio <= hi;
    for (pose, reason) in poses.iter().zip(reasons.iter_mut()) {
        if reason.is_some() {
            continue;
        }
        for &(kind, l, r) in &segments {
            let (left, right) = (length(pose, l), length(pose, r));
            if let Some(m) = medians[kind].filter(|m| *m > 0.0)
                && !(inside(left / m, config.segment_ratio)
                    && inside(right / m, config.segment_ratio))
            {
                *reason = Some(PoorReason::SegmentLength);
                break;
            }
            // 0 / 0 is NaN and fails the band: a collapsed leg is poor.
            if !inside(left / right, config.side_ratio) {
                *reason = Some(PoorReason::LeftRight);
                break;
            }
        }
    }
    Ok(Judgement {
        reasons,
        medians: SegmentMedians {
            thigh: medians[0],
            shank: medians[1],
        },
    })
}

fn likelihood_reason(
    pose: &Pose,
    watched: &[usize],
    config: &SelectionConfig,
) -> Option<PoorReason> {
    let points: Vec<_> = watched
        .iter()
        .filter_map(|&i| pose.keypoints.get(i))
        .collect();
    if points.len() != watched.len() || points.iter().any(|k| !k.is_found()) {
        return Some(PoorReason::Missing);
    }
    let values = points.iter().map(|k| k.likelihood);
    let stat = match config.likelihood {
        LikelihoodStat::Min => values.fold(f64::INFINITY, f64::min),
        LikelihoodStat::Mean => values.sum::<f64>() / points.len() as f64,
    };
    // NaN likelihoods fail the test too.
    if stat >= config.min_likelihood {
        None
    } else {
        Some(PoorReason::LowLikelihood)
    }
}

fn median(values: &mut Vec<f64>) -> Option<f64> {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    })
}

pub use gait_core::ranges;

/// What `run.json` records under `selection`: which frames went which way.
/// Frame lists are inclusive `[first, last]` ranges.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SelectionRecord {
    /// Frames in the run (rows of keypoints.csv).
    pub frames: usize,
    /// Frames that went through the pipeline (every `stride`-th and the last).
    pub processed: Vec<[usize; 2]>,
    /// Processed frames that went through edges -> regenerator -> pose.
    pub regenerated: Vec<[usize; 2]>,
    pub regenerated_count: usize,
    /// Processed frames that kept the pose found on the original frame.
    pub original: Vec<[usize; 2]>,
    pub original_count: usize,
    /// Frames whose keypoints were interpolated between processed frames.
    pub interpolated: Vec<[usize; 2]>,
    pub interpolated_count: usize,
    /// Poor frames per reason (`selection.mode = "poor"` only).
    pub poor: BTreeMap<PoorReason, Vec<[usize; 2]>>,
    pub poor_counts: BTreeMap<PoorReason, usize>,
    /// The medians the segment test used (`selection.mode = "poor"` only).
    pub segment_medians_px: Option<SegmentMedians>,
}

impl SelectionRecord {
    /// One line for the end of `gait run`, e.g. "regenerated 12 of 130
    /// frames (9 low likelihood, 3 segment lengths); 65 interpolated".
    pub fn summary(&self) -> String {
        let mut line = format!(
            "regenerated {} of {} frames",
            self.regenerated_count, self.frames
        );
        let why: Vec<String> = self
            .poor_counts
            .iter()
            .filter(|(_, n)| **n > 0)
            .map(|(r, n)| format!("{n} {}", r.describe()))
            .collect();
        if !why.is_empty() {
            line += &format!(" ({})", why.join(", "));
        }
        if self.original_count > 0 {
            line += &format!("; {} kept the original-frame pose", self.original_count);
        }
        line + &format!("; {} interpolated", self.interpolated_count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_core::{CANONICAL, Keypoint};

    fn names() -> Vec<String> {
        CANONICAL.iter().map(|s| s.to_string()).collect()
    }

    /// A standing pose: hips at y=100, knees y=140, ankles y=180, feet below.
    fn pose(likelihood: f64) -> Pose {
        let mut p = Pose::empty(CANONICAL.len());
        let at = |name: &str| gait_core::keypoint::canonical_index(name).unwrap();
        for (side, x) in [("left", 50.0), ("right", 60.0)] {
            for (part, y) in [
                ("hip", 100.0),
                ("knee", 140.0),
                ("ankle", 180.0),
                ("heel", 185.0),
                ("toe", 186.0),
            ] {
                p.keypoints[at(&format!("{side}_{part}"))] = Keypoint::new(x, y, likelihood);
            }
        }
        p
    }

    fn set(p: &mut Pose, name: &str, k: Keypoint) {
        p.keypoints[gait_core::keypoint::canonical_index(name).unwrap()] = k;
    }

    #[test]
    fn likelihood_missing_and_segment_rules() {
        let cfg = SelectionConfig::default();
        let mut poses = vec![pose(0.9); 8];
        // 1: one weak toe -> low likelihood under "min".
        set(&mut poses[1], "left_toe", Keypoint::new(50.0, 186.0, 0.3));
        // 2: a missing heel.
        set(&mut poses[2], "right_heel", Keypoint::missing());
        // 3: both shanks twice as long (ankles lower) -> segment length.
        set(&mut poses[3], "left_ankle", Keypoint::new(50.0, 220.0, 0.9));
        set(
            &mut poses[3],
            "right_ankle",
            Keypoint::new(60.0, 220.0, 0.9),
        );
        // 4: left thigh 1.5x the median, right thigh 0.75x: each inside
        // [0.6, 1.6], but their ratio 2.0 is outside side_ratio.
        set(&mut poses[4], "left_hip", Keypoint::new(50.0, 80.0, 0.9));
        set(&mut poses[4], "right_knee", Keypoint::new(60.0, 130.0, 0.9));
        // 5: the nose does not matter.
        set(&mut poses[5], "nose", Keypoint::missing());
        let j = judge(&poses, &names(), &cfg).unwrap();
        use PoorReason::*;
        assert_eq!(
            j.reasons,
            vec![
                None,
                Some(LowLikelihood),
                Some(Missing),
                Some(SegmentLength),
                Some(LeftRight),
                None,
                None,
                None
            ]
        );
        // Medians over the likelihood-good frames 0 and 3..8 (both sides).
        assert_eq!(j.medians.thigh, Some(40.0));
        assert_eq!(j.medians.shank, Some(40.0));

        // "mean" forgives the one weak toe: (9 * 0.9 + 0.3) / 10 = 0.84.
        let mean = SelectionConfig {
            likelihood: LikelihoodStat::Mean,
            ..cfg.clone()
        };
        assert_eq!(judge(&poses, &names(), &mean).unwrap().reasons[1], None);
        // A threshold above every likelihood makes every frame poor.
        let strict = SelectionConfig {
            min_likelihood: 0.95,
            ..cfg.clone()
        };
        assert!(
            judge(&poses, &names(), &strict)
                .unwrap()
                .reasons
                .iter()
                .all(|r| r.is_some())
        );
        // Without feet in the rule, the missing heel is forgiven.
        let no_feet = SelectionConfig {
            keypoints: LOWER_LIMB[..6].iter().map(|s| s.to_string()).collect(),
            ..cfg.clone()
        };
        assert_eq!(judge(&poses, &names(), &no_feet).unwrap().reasons[2], None);
    }

    #[test]
    fn unknown_keypoint_is_named() {
        let cfg = SelectionConfig {
            keypoints: vec!["left_paw".into()],
            ..SelectionConfig::default()
        };
        let e = judge(&[pose(0.9)], &names(), &cfg).unwrap_err();
        assert!(e.contains("left_paw") && e.contains("left_knee"), "{e}");
    }

    #[test]
    fn collapsed_leg_is_poor() {
        let mut p = pose(0.9);
        for name in ["left_hip", "left_knee", "right_hip", "right_knee"] {
            set(&mut p, name, Keypoint::new(50.0, 100.0, 0.9));
        }
        let j = judge(
            &[pose(0.9), pose(0.9), p],
            &names(),
            &SelectionConfig::default(),
        )
        .unwrap();
        assert_eq!(j.reasons[2], Some(PoorReason::SegmentLength));
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |c: SelectionConfig| c.validate().unwrap_err();
        assert!(
            bad(SelectionConfig {
                stride: 0,
                ..Default::default()
            })
            .contains("stride")
        );
        assert!(
            bad(SelectionConfig {
                segment_ratio: [1.6, 0.6],
                ..Default::default()
            })
            .contains("segment_ratio")
        );
        assert!(
            bad(SelectionConfig {
                side_ratio: [0.0, 2.0],
                ..Default::default()
            })
            .contains("side_ratio")
        );
        assert!(
            bad(SelectionConfig {
                min_likelihood: 1.5,
                ..Default::default()
            })
            .contains("min_likelihood")
        );
        assert!(SelectionConfig::default().validate().is_ok());
    }

    #[test]
    fn ranges_compact_runs() {
        assert_eq!(ranges([1, 2, 3, 5, 7, 8]), vec![[1, 3], [5, 5], [7, 8]]);
        assert!(ranges([]).is_empty());
    }

    #[test]
    fn summary_line() {
        let mut r = SelectionRecord {
            frames: 130,
            regenerated_count: 12,
            original_count: 53,
            interpolated_count: 65,
            ..Default::default()
        };
        r.poor_counts.insert(PoorReason::LowLikelihood, 9);
        r.poor_counts.insert(PoorReason::SegmentLength, 3);
        r.poor_counts.insert(PoorReason::Missing, 0);
        assert_eq!(
            r.summary(),
            "regenerated 12 of 130 frames (9 low likelihood, 3 segment lengths); 53 kept the original-frame pose; 65 interpolated"
        );
    }
}
