//! Vaulting: the other foot rising on its toes while this side swings, to give
//! a prosthesis that does not shorten room to swing through. Seen from the side
//! as the other heel's rise above the ground during this side's early and mid
//! swing (heel rise normally starts in terminal stance, at 30-40 % of the
//! cycle: Perry, Gait Analysis, 1992), judged against the same rise while the
//! other side swings: vaulting is one-sided, and a real video of a healthy
//! walker (the bundled sample) already shows a heel 4-7 % of a leg up there on
//! both sides, from the pose model's heel point and her own early heel rise.

use crate::judge::{Sample, Threshold, judge_over_other};
use crate::run_files::RunFiles;
use crate::verdict::{Item, Verdict};
use crate::{ChecklistConfig, Side};

pub const VAULTING: Item = Item {
    id: "vaulting",
    name: "Vaulting (the sound foot rising early on its toes)",
    measure: "height of the other foot's heel above its lowest point in the 30 % of the stride before, median over 25-50 % of this side's swing, in % of the leg length (thigh + shank), minus the same for the other side",
    unit: "% leg",
    view: "side",
    amputation: "both",
    paired: true,
};

/// Per accepted stride of `side` with a toe-off, the other heel's median rise
/// (image y is down) over the stride's 25-50 % of swing, per leg length.
fn rises(run: &RunFiles, side: Side) -> Vec<Sample> {
    let Some(heel) = run.heel_y.get(&side.other()) else {
        return Vec::new();
    };
    run.strides_of(side)
        .filter_map(|s| {
            let to = s.first as f64 + s.toe_off? * (s.last - s.first) as f64;
            let swing = s.last as f64 - to;
            let (a, b) = (
                (to + 0.25 * swing).ceil() as usize,
                (to + 0.5 * swing) as usize,
            );
            // A swing of a few frames (a toe-off found late on jittered feet) has no frame in
            // its 25-50 %: no sample, rather than an empty range.
            if a > b {
                return None;
            }
            // The other heel's ground: its lowest point over the 30 % of the stride before the
            // window, where it lands and is flat. Not the whole stride's: walking obliquely to
            // the camera the ground line itself moves up or down the image.
            let from = (a as f64 - 0.3 * (s.last - s.first) as f64).max(s.first as f64) as usize;
            let ground = heel
                .range(from..=a)
                .map(|(_, y)| *y)
                .filter(|y| y.is_finite())
                .fold(f64::NAN, f64::max);
            let mut window: Vec<f64> = heel
                .range(a..=b)
                .map(|(_, y)| ground - y)
                .filter(|v| v.is_finite())
                .collect();
            if window.is_empty() || s.leg_px.is_nan() || s.leg_px <= 0.0 {
                return None;
            }
            window.sort_by(f64::total_cmp);
            Some(Sample {
                value: 100.0 * window[window.len() / 2] / s.leg_px,
                first: s.first,
                frame: (a + b) / 2,
            })
        })
        .collect()
}

/// Vaulting over each side (the other foot rising while it swings), each
/// stride's rise less the other side's mean rise.
pub fn assess(run: &RunFiles, cfg: &ChecklistConfig) -> [Verdict; 2] {
    let both = Side::BOTH.map(|s| rises(run, s));
    Side::BOTH.map(|side| {
        if run.view != "sagittal" {
            return Verdict::not_assessable(VAULTING, side, "needs a side view");
        }
        let (own, other) = match side {
            Side::Left => (&both[0], &both[1]),
            Side::Right => (&both[1], &both[0]),
        };
        let t = Threshold {
            value: 100.0 * cfg.vaulting_leg,
            beyond: "above",
            source: "checklist.vaulting_leg, over the other side's rise (about 3.4 cm over a 0.84 m leg): no published value; the unmodified and 6 cm-vaulting trials of tests/visit.rs and the sample lie either side of it".into(),
        };
        if other.is_empty() {
            let why = "needs accepted strides with toe-offs of both sides";
            return Verdict::not_assessable(VAULTING, side, why);
        }
        let none = "no accepted stride of this side with its toe-off and the other heel";
        judge_over_other(VAULTING, side, (own, other), t, "% leg", none)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run_files::Stride;

    /// Strides of `len` frames with toe-off at `toe_off` of them, heels flat on the floor.
    fn run(len: usize, toe_off: f64) -> RunFiles {
        let mut r = RunFiles {
            view: "sagittal".into(),
            ..Default::default()
        };
        for side in Side::BOTH {
            r.strides.push(Stride {
                side,
                first: 0,
                last: len,
                toe_off: Some(toe_off),
                leg_px: 100.0,
            });
            r.heel_y
                .insert(side, (0..=len).map(|i| (i, 900.0)).collect());
        }
        r
    }

    #[test]
    fn a_swing_too_short_for_its_window_gives_no_sample() {
        // 25-50 % of a 1-frame swing (frames 32-33) holds no whole frame: 33 > 32 (this
        // panicked on jittered feet before).
        assert!(rises(&run(33, 32.0 / 33.0), Side::Left).is_empty());
        let [left, _] = assess(&run(33, 32.0 / 33.0), &ChecklistConfig::default());
        assert_eq!(left.status, crate::Status::NotAssessable);
        // A usual stride: one sample a side, the heels did not rise.
        let rises = rises(&run(100, 0.6), Side::Left);
        assert!(rises.len() == 1 && rises[0].value == 0.0, "{rises:?}");
    }
}
