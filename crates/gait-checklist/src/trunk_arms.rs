//! The upper body from the side: trunk flexion and arm swing, from the shoulders, the mid-hip
//! and the wrists of keypoints_filtered.csv over each accepted stride.

use crate::judge::{Sample, Threshold, judge, mean_sd};
use crate::run_files::{RunFiles, Stride};
use crate::verdict::{Item, Status, Verdict};
use crate::{ChecklistConfig, Side};

pub const TRUNK_FLEXION: Item = Item {
    id: "excessive_trunk_flexion",
    name: "Excessive trunk flexion",
    measure: "forward lean of the trunk (mid-hip to mid-shoulder) from the vertical, mean over the side's strides (a lordosis is not seen by keypoints)",
    unit: "deg",
    view: "side",
    amputation: "both",
    paired: false,
};
pub const ARM_SWING: Item = Item {
    id: "uneven_arm_swing",
    name: "Uneven arm swing",
    measure: "the arm's swing (range of the shoulder-wrist angle over the stride); present on the side that swings less when the symmetry index passes the threshold",
    unit: "deg",
    view: "side",
    amputation: "both",
    paired: true,
};

/// Degrees from the upward vertical of the line `from -> to`, positive toward the walking
/// direction `dir` (image y is down).
fn lean(from: [f64; 2], to: [f64; 2], dir: f64) -> f64 {
    (dir * (to[0] - from[0]))
        .atan2(from[1] - to[1])
        .to_degrees()
}

/// Degrees from the downward vertical of a hanging arm `shoulder -> wrist`, positive forward.
fn arm_angle(shoulder: [f64; 2], wrist: [f64; 2], dir: f64) -> f64 {
    (dir * (wrist[0] - shoulder[0]))
        .atan2(wrist[1] - shoulder[1])
        .to_degrees()
}

/// The midpoint of the keypoints `a` and `b` at `frame`, when both are seen.
fn midpoint(run: &RunFiles, a: &str, b: &str, frame: usize) -> Option<[f64; 2]> {
    let (l, r) = (run.at(a, frame)?, run.at(b, frame)?);
    Some([(l[0] + r[0]) / 2.0, (l[1] + r[1]) / 2.0])
}

/// The mid-hip at `frame`: the model's own point, else the hips' midpoint (motion capture).
fn mid_hip(run: &RunFiles, frame: usize) -> Option<[f64; 2]> {
    run.at("mid_hip", frame)
        .or_else(|| midpoint(run, "left_hip", "right_hip", frame))
}

/// Per frame of the stride with a known direction, `f(frame, direction)`.
fn over(s: &Stride, run: &RunFiles, f: impl Fn(usize, f64) -> Option<f64>) -> Vec<f64> {
    (s.first..=s.last)
        .filter_map(|i| f(i, run.direction(i)?))
        .filter(|v| v.is_finite())
        .collect()
}

/// Trunk flexion over each accepted stride of `side`.
fn trunk(run: &RunFiles, side: Side) -> Vec<Sample> {
    run.strides_of(side)
        .filter_map(|s| {
            let v = over(s, run, |i, d| {
                Some(lean(
                    mid_hip(run, i)?,
                    midpoint(run, "left_shoulder", "right_shoulder", i)?,
                    d,
                ))
            });
            // Most of the stride, so that a stride seen half is not read as the trunk's.
            (v.len() * 2 > s.last - s.first).then(|| Sample {
                value: v.iter().sum::<f64>() / v.len() as f64,
                first: s.first,
                frame: (s.first + s.last) / 2,
            })
        })
        .collect()
}

/// The arm swing of `side` over each of its accepted strides.
fn swing(run: &RunFiles, side: Side) -> Vec<f64> {
    let (shoulder, wrist) = (
        format!("{}_shoulder", side.name()),
        format!("bp_{}_wrist", side.name()),
    );
    run.strides_of(side)
        .filter_map(|s| {
            let v = over(s, run, |i, d| {
                Some(arm_angle(run.at(&shoulder, i)?, run.at(&wrist, i)?, d))
            });
            let (lo, hi) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            (v.len() * 2 > s.last - s.first).then_some(hi - lo)
        })
        .collect()
}

/// Both items for both sides.
pub fn assess(run: &RunFiles, cfg: &ChecklistConfig) -> Vec<Verdict> {
    if run.view != "sagittal" {
        return Side::BOTH
            .iter()
            .flat_map(|&s| {
                [TRUNK_FLEXION, ARM_SWING]
                    .map(|i| Verdict::not_assessable(i, s, "needs a side view"))
            })
            .collect();
    }
    let mut out: Vec<Verdict> = Side::BOTH
        .iter()
        .map(|&side| {
            let t = Threshold {
                value: cfg.trunk_flexion_deg,
                beyond: "above",
                source: "checklist.trunk_flexion_deg: no published 2-D value".into(),
            };
            let none = "needs both shoulders and the mid-hip over most of an accepted stride";
            judge(TRUNK_FLEXION, side, &trunk(run, side), t, "deg", none)
        })
        .collect();
    out.extend(arm_swing(run, cfg));
    out
}

/// Uneven arm swing: each side's mean swing, present on the smaller when the symmetry index
/// passes `checklist.arm_swing_pct`.
fn arm_swing(run: &RunFiles, cfg: &ChecklistConfig) -> [Verdict; 2] {
    let both = Side::BOTH.map(|s| swing(run, s));
    if both.iter().any(Vec::is_empty) {
        let why =
            "needs the shoulder and the wrist of both arms over accepted strides of both sides";
        return Side::BOTH.map(|s| Verdict::not_assessable(ARM_SWING, s, why));
    }
    let stats = |v: &[f64]| {
        let (m, sd) = mean_sd(v);
        (m, sd, v.len())
    };
    let (l, r) = (stats(&both[0]), stats(&both[1]));
    let si = 100.0 * (l.0 - r.0) / (0.5 * (l.0 + r.0));
    Side::BOTH.map(|side| {
        let (own, smaller) = match side {
            Side::Left => (l, si < 0.0),
            Side::Right => (r, si > 0.0),
        };
        let mut v = Verdict::not_assessable(ARM_SWING, side, "");
        v.status = if smaller && si.abs() > cfg.arm_swing_pct {
            Status::Present
        } else {
            Status::Absent
        };
        (v.value, v.spread, v.n) = own;
        v.threshold = cfg.arm_swing_pct;
        v.threshold_unit = "%".into();
        v.source = format!(
            "checklist.arm_swing_pct, on the symmetry index (here {si:.1} %): no published 2-D value"
        );
        v.reason.clear();
        v
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lean_is_positive_toward_the_walking_direction() {
        // Shoulders 10 px ahead of the hip and 100 px above it, walking right.
        let d = lean([100.0, 500.0], [110.0, 400.0], 1.0);
        assert!((d - 5.71).abs() < 0.01, "{d}");
        assert!((lean([100.0, 500.0], [110.0, 400.0], -1.0) + d).abs() < 1e-12);
    }
}
