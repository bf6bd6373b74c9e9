//! A verdict from per-cycle (or per-step) values against a threshold.

use crate::Side;
use crate::verdict::{Item, Status, Verdict};

/// One cycle's (or step's) value: its first frame and the frame where the value is taken.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    pub value: f64,
    pub first: usize,
    pub frame: usize,
}

/// The threshold and where it comes from.
pub struct Threshold {
    pub value: f64,
    /// `above` or `below`.
    pub beyond: &'static str,
    pub source: String,
}

impl Threshold {
    fn passed(&self, v: f64) -> bool {
        self.past(v) > 0.0
    }

    fn past(&self, v: f64) -> f64 {
        past(self.beyond, self.value, v)
    }
}

/// How far `v` lies past `threshold` in the direction `beyond` (negative: short of it).
pub(crate) fn past(beyond: &str, threshold: f64, v: f64) -> f64 {
    match beyond {
        "below" => threshold - v,
        _ => v - threshold,
    }
}

/// Whether a mean `past` its threshold by that much, with standard error `se`, is present: past
/// it by at least `se`. When it passed without that, why it is absent (`hits` of the `n` cycles
/// past the threshold).
pub(crate) fn consistent(
    past: f64,
    se: f64,
    (hits, n): (usize, usize),
    unit: &str,
) -> (bool, String) {
    let present = past > 0.0 && past >= se;
    let reason = if past > 0.0 && !present {
        format!(
            "not consistent over the cycles: {hits} of {n} past the threshold, the mean past it by less than its standard error ({se:.2} {unit})"
        )
    } else {
        String::new()
    };
    (present, reason)
}

/// Mean and sample SD (NaN for one value).
pub fn mean_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = if values.len() > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        f64::NAN
    };
    (mean, sd)
}

/// Present when the mean over the samples passes the threshold; the cycles listed are those
/// whose own value passes it. No sample: not assessable, with `none` as the reason.
pub fn judge(
    item: Item,
    side: Side,
    samples: &[Sample],
    t: Threshold,
    unit: &str,
    none: &str,
) -> Verdict {
    judged(item, side, samples, 0.0, t, (unit, none))
}

/// As [`judge`], on each of `own`'s values less the mean of `other`'s (the same measure of the
/// other side). The standard error of the result holds both sides' (a side's mean is compared
/// with the other's, not with a known value), and so does the spread reported with it: one
/// stride of the other side misplaced by the pose model moves this side's value too.
pub fn judge_over_other(
    item: Item,
    side: Side,
    (own, other): (&[Sample], &[Sample]),
    t: Threshold,
    unit: &str,
    none: &str,
) -> Verdict {
    let values = finite(other);
    if values.is_empty() {
        return Verdict::not_assessable(item, side, none);
    }
    let (base, sd) = mean_sd(&values);
    let base_var = if sd.is_finite() {
        sd * sd / values.len() as f64
    } else {
        0.0
    };
    let less: Vec<Sample> = own
        .iter()
        .map(|s| Sample {
            value: s.value - base,
            ..*s
        })
        .collect();
    judged(item, side, &less, base_var, t, (unit, none))
}

/// The samples' values that are numbers.
fn finite(samples: &[Sample]) -> Vec<f64> {
    samples
        .iter()
        .map(|s| s.value)
        .filter(|v| v.is_finite())
        .collect()
}

/// [`judge`] with `base_var`, the variance of a baseline subtracted from every sample.
fn judged(
    item: Item,
    side: Side,
    samples: &[Sample],
    base_var: f64,
    t: Threshold,
    (unit, none): (&str, &str),
) -> Verdict {
    let values = finite(samples);
    if values.is_empty() || !t.value.is_finite() {
        return Verdict::not_assessable(item, side, none);
    }
    let (mean, own_sd) = mean_sd(&values);
    // The spread whose standard error over these samples is the mean's whole standard error.
    let spread = if base_var > 0.0 && own_sd.is_finite() {
        (own_sd * own_sd + base_var * values.len() as f64).sqrt()
    } else {
        own_sd
    };
    let hits: Vec<&Sample> = samples.iter().filter(|s| t.passed(s.value)).collect();
    // Present when the side's cycles show it consistently: the mean lies past the threshold by
    // at least its standard error. One deviant cycle among two or three (a pose model's foot
    // misplaced in one stride) moved the mean past the threshold in 10-12 of 15 re-encodings of
    // the bundled sample's healthy walk (foot slap, vaulting); none had its mean past it by a
    // standard error, while the planted deviations are past it by several.
    let se = if values.len() > 1 {
        spread / (values.len() as f64).sqrt()
    } else {
        0.0
    };
    let (present, reason) = consistent(t.past(mean), se, (hits.len(), values.len()), unit);
    Verdict {
        item,
        side,
        status: if present {
            Status::Present
        } else {
            Status::Absent
        },
        value: mean,
        spread,
        n: values.len(),
        unit: unit.into(),
        threshold: t.value,
        threshold_unit: unit.into(),
        beyond: t.beyond,
        source: t.source,
        cycles: hits.iter().map(|s| s.first).collect(),
        frames: hits.iter().map(|s| s.frame).collect(),
        reason,
        run: String::new(),
        judged: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontal_items::TRUNK;

    fn at(values: &[f64]) -> Vec<Sample> {
        values
            .iter()
            .enumerate()
            .map(|(i, &value)| Sample {
                value,
                first: 100 * i,
                frame: 100 * i + 7,
            })
            .collect()
    }

    fn t(value: f64, beyond: &'static str) -> Threshold {
        Threshold {
            value,
            beyond,
            source: "test".into(),
        }
    }

    /// The mean decides; the cycles listed are those past the threshold on their own.
    #[test]
    fn the_mean_decides_and_the_cycles_past_the_threshold_are_named() {
        let values = [4.0, 7.0, 7.5];
        let v = judge(
            TRUNK,
            Side::Right,
            &at(&values),
            t(5.0, "above"),
            "deg",
            "none",
        );
        assert_eq!((v.status, v.reason.as_str()), (Status::Present, ""));
        assert_eq!(
            (v.cycles.clone(), v.frames.clone(), v.n),
            (vec![100, 200], vec![107, 207], 3)
        );
        let mean = values.iter().sum::<f64>() / 3.0;
        let sd = (values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
        assert!((v.value - mean).abs() < 1e-12 && (v.spread - sd).abs() < 1e-9);
        let v = judge(
            TRUNK,
            Side::Right,
            &at(&values),
            t(5.0, "below"),
            "deg",
            "none",
        );
        assert_eq!((v.status, v.cycles), (Status::Absent, vec![0]));
    }

    /// A side judged against the other side's mean carries that mean's uncertainty: on the
    /// sample's sensor-noise copy one misplaced stride of the right heel (rises 1, 2, 27 % of
    /// the leg) put the left's vaulting at -10 +- 2.6 over its own two strides, which `gait
    /// progress` then called a change from its -3.0 +- 0.2.
    #[test]
    fn a_value_over_the_other_side_s_mean_carries_that_mean_s_spread() {
        let (own, other) = (at(&[0.0, 1.0]), at(&[1.0, 2.0, 27.0]));
        let v = judge_over_other(
            TRUNK,
            Side::Left,
            (&own, &other),
            t(5.0, "above"),
            "% leg",
            "none",
        );
        assert!((v.value - (0.5 - 10.0)).abs() < 1e-12, "{}", v.value);
        let other_var = ((9.0f64).powi(2) + 8.0f64.powi(2) + 17.0f64.powi(2)) / 2.0 / 3.0;
        let se = (0.5f64 / 2.0 + other_var).sqrt();
        assert!(
            (v.spread / 2f64.sqrt() - se).abs() < 1e-9,
            "{} vs {se}",
            v.spread
        );
        assert!(
            v.spread > 10.0,
            "the other side's outlier is in the spread: {}",
            v.spread
        );
    }

    /// One deviant cycle that carries the mean past the threshold is not a deviation of the
    /// side: absent, saying so; the same mean from cycles that agree is present.
    #[test]
    fn a_mean_past_the_threshold_by_less_than_its_standard_error_is_not_called() {
        let above_5 = |values: &[f64]| {
            judge(
                TRUNK,
                Side::Left,
                &at(values),
                t(5.0, "above"),
                "deg",
                "none",
            )
        };
        let v = above_5(&[2.0, 12.0]);
        assert_eq!(v.status, Status::Absent);
        assert!(
            v.reason.contains("1 of 2 past the threshold"),
            "{}",
            v.reason
        );
        assert_eq!(v.cycles, vec![100]);
        let v = above_5(&[6.5, 7.5]);
        assert_eq!((v.status, v.reason.as_str()), (Status::Present, ""));
        // A single cycle has no spread: its value decides.
        assert_eq!(above_5(&[5.5]).status, Status::Present);
    }

    #[test]
    fn no_samples_or_no_threshold_is_not_assessable_with_the_reason() {
        let v = judge(TRUNK, Side::Left, &[], t(5.0, "above"), "deg", "no cycle");
        assert_eq!(
            (v.status, v.reason.as_str()),
            (Status::NotAssessable, "no cycle")
        );
        let v = judge(
            TRUNK,
            Side::Left,
            &at(&[9.0]),
            t(f64::NAN, "above"),
            "deg",
            "no band",
        );
        assert_eq!(
            (v.status, v.reason.as_str()),
            (Status::NotAssessable, "no band")
        );
    }
}
