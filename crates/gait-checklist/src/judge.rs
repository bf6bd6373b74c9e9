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
        match self.beyond {
            "below" => v < self.value,
            _ => v > self.value,
        }
    }
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
    let values: Vec<f64> = samples
        .iter()
        .map(|s| s.value)
        .filter(|v| v.is_finite())
        .collect();
    if values.is_empty() || !t.value.is_finite() {
        return Verdict::not_assessable(item, side, none);
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let spread = if values.len() > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        f64::NAN
    };
    let hits: Vec<&Sample> = samples.iter().filter(|s| t.passed(s.value)).collect();
    Verdict {
        item,
        side,
        status: if t.passed(mean) {
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
        reason: String::new(),
    }
}
