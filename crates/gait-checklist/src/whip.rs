//! Medial or lateral whip: at heel-off and toe-off the heel swings inward (medial whip) or
//! outward (lateral whip) about the forefoot. Seen from behind as the heel's sideways shift
//! against the toe, from where the foot stands flat to the shift's extreme around toe-off.

use crate::judge::{Sample, Threshold, judge};
use crate::run_files::RunFiles;
use crate::verdict::{Item, Verdict};
use crate::{ChecklistConfig, Side};

pub const WHIP: Item = Item {
    id: "medial_lateral_whip",
    name: "Medial or lateral whip at toe-off",
    measure: "the heel's sideways shift against the toe from foot flat (15-30 % of the stride) to its extreme around toe-off (-15 % to +5 %), in % of the leg; + lateral, - medial",
    unit: "% leg",
    view: "back",
    amputation: "both",
    paired: false,
};

/// Per accepted stride of `side` with a toe-off: the signed whip (lateral positive), % leg.
fn whips(run: &RunFiles, side: Side) -> Vec<Sample> {
    let (heel, toe) = (
        format!("{}_heel", side.name()),
        format!("{}_toe", side.name()),
    );
    // From behind the subject's right is the image's right: lateral is +x for the right foot.
    let lateral = match side {
        Side::Right => 1.0,
        Side::Left => -1.0,
    };
    let shift = |i: usize| Some(lateral * (run.at(&heel, i)?[0] - run.at(&toe, i)?[0]));
    run.strides_of(side)
        .filter_map(|s| {
            let len = (s.last - s.first) as f64;
            let at = |share: f64| (s.first as f64 + share * len).round() as usize;
            let to = s.toe_off?;
            let mut flat: Vec<f64> = (at(0.15)..=at(0.3)).filter_map(shift).collect();
            if flat.is_empty() || s.leg_px.is_nan() || s.leg_px <= 0.0 {
                return None;
            }
            flat.sort_by(f64::total_cmp);
            let base = flat[flat.len() / 2];
            let (frame, d) = (at(to - 0.15)..=at((to + 0.05).min(1.0)))
                .filter_map(|i| Some((i, shift(i)? - base)))
                .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
            Some(Sample {
                value: 100.0 * d / s.leg_px,
                first: s.first,
                frame,
            })
        })
        .collect()
}

/// The whip of each side, judged on its size; its sign says which.
pub fn assess(run: &RunFiles, cfg: &ChecklistConfig) -> [Verdict; 2] {
    Side::BOTH.map(|side| {
        if run.view != "posterior" {
            return Verdict::not_assessable(WHIP, side, "needs a back view");
        }
        let samples = whips(run, side);
        let t = Threshold {
            value: 100.0 * cfg.whip_leg,
            beyond: "above",
            source: "checklist.whip_leg, on the size (about 4 cm): no published value".into(),
        };
        let abs: Vec<Sample> = samples
            .iter()
            .map(|s| Sample {
                value: s.value.abs(),
                ..*s
            })
            .collect();
        let none = "needs accepted strides with toe-offs and both the heel and the toe";
        let mut v = judge(WHIP, side, &abs, t, "% leg", none);
        // The reported value keeps its sign: lateral (+) or medial (-).
        if !samples.is_empty() {
            v.judged = Some(v.value);
            v.value = samples.iter().map(|s| s.value).sum::<f64>() / samples.len() as f64;
        }
        v
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Status;
    use crate::run_files::Stride;

    /// A right foot seen from behind whose heel swings 6 px outward (image right) against the
    /// toe just before toe-off, over a 100 px leg: a lateral whip of 6 % of the leg.
    fn run(shift: f64) -> RunFiles {
        let mut r = RunFiles {
            view: "posterior".into(),
            ..Default::default()
        };
        for side in Side::BOTH {
            r.strides.push(Stride {
                side,
                first: 0,
                last: 100,
                toe_off: Some(0.6),
                leg_px: 100.0,
            });
            let heel = (0..=100)
                .map(|i| {
                    let out = if (50..=60).contains(&i) && side == Side::Right {
                        shift
                    } else {
                        0.0
                    };
                    (i, [500.0 + out, 900.0])
                })
                .collect();
            let toe = (0..=100).map(|i| (i, [500.0, 880.0])).collect();
            r.points.insert(format!("{}_heel", side.name()), heel);
            r.points.insert(format!("{}_toe", side.name()), toe);
        }
        r
    }

    #[test]
    fn a_heel_swinging_out_before_toe_off_is_a_lateral_whip_of_its_side() {
        let cfg = ChecklistConfig::default();
        let [left, right] = assess(&run(6.0), &cfg);
        assert_eq!(
            (left.status, right.status),
            (Status::Absent, Status::Present)
        );
        assert!((right.value - 6.0).abs() < 1e-9, "{right:?}");
        assert!(right.frames.len() == 1 && (50..=60).contains(&right.frames[0]));
        // Inward (image left for the right foot): the same size, medial.
        let [_, right] = assess(&run(-6.0), &cfg);
        assert!(right.status == Status::Present && (right.value + 6.0).abs() < 1e-9);
        let [_, right] = assess(&run(3.0), &cfg);
        assert_eq!(right.status, Status::Absent);
        let mut side_view = run(6.0);
        side_view.view = "sagittal".into();
        assert_eq!(assess(&side_view, &cfg)[1].status, Status::NotAssessable);
    }
}
