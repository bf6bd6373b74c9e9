//! Gait cycles (heel strike to next heel strike of the same foot), time-normalised to 0..100 %.

use serde::Serialize;

use crate::angles::Angles;
use crate::config::Side;
use crate::events::{Event, EventKind};

/// Joints in output order.
pub const JOINTS: [&str; 3] = ["hip", "knee", "ankle"];

/// A stride of one foot: first and next heel strike (input frame numbers).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stride {
    pub side: Side,
    pub start: usize,
    pub end: usize,
    /// The two heel strikes' sub-frame times (input frames), where the detector has them.
    /// The curves are normalised on these: a stride that starts half a frame later has
    /// its 0 % half a frame later, as its duration already has.
    #[serde(skip)]
    pub at: Option<[f64; 2]>,
}

impl Stride {
    /// A stride between two heel strikes placed on frames.
    pub fn on_frames(side: Side, start: usize, end: usize) -> Self {
        Self {
            side,
            start,
            end,
            at: None,
        }
    }

    /// The heel strikes' times in input frames, sub-frame where known.
    pub fn span(&self) -> [f64; 2] {
        self.at.unwrap_or([self.start as f64, self.end as f64])
    }
}

/// Mean and SD curves of one joint of one side over its complete cycles (101 points each).
#[derive(Debug, Clone, Serialize)]
pub struct CycleCurve {
    pub side: Side,
    pub joint: &'static str,
    #[serde(skip)]
    pub mean: Vec<f64>,
    #[serde(skip)]
    pub sd: Vec<f64>,
    pub n_cycles: usize,
}

/// Consecutive heel strikes of each foot whose duration lies within `[min_s, max_s]`.
pub fn strides(events: &[Event], fps: f64, min_s: f64, max_s: f64) -> Vec<Stride> {
    let mut out = Vec::new();
    for side in Side::BOTH {
        let hs: Vec<&Event> = events
            .iter()
            .filter(|e| e.side == side && e.event == EventKind::HeelStrike)
            .collect();
        for w in hs.windows(2) {
            let dur = (w[1].frame - w[0].frame) as f64 / fps;
            if dur >= min_s && dur <= max_s {
                let sub = w[0].at.is_some() || w[1].at.is_some();
                out.push(Stride {
                    at: sub.then(|| [w[0].time(), w[1].time()]),
                    ..Stride::on_frames(side, w[0].frame, w[1].frame)
                });
            }
        }
    }
    out
}

/// `series` (indexed from `first_frame`) resampled linearly at 101 points over the stride,
/// from its heel strikes' sub-frame times where those have their samples, else from its
/// frames; `None` when any needed sample is missing.
pub fn resample(series: &[f64], first_frame: usize, s: &Stride) -> Option<Vec<f64>> {
    let on_frames = [s.start as f64, s.end as f64];
    let span = s.span();
    if span != on_frames
        && let Some(v) = resample_span(series, first_frame, span)
    {
        return Some(v);
    }
    resample_span(series, first_frame, on_frames)
}

/// `series` at 101 points from input frame time `span[0]` to `span[1]`.
fn resample_span(series: &[f64], first_frame: usize, span: [f64; 2]) -> Option<Vec<f64>> {
    let (a, b) = (span[0] - first_frame as f64, span[1] - first_frame as f64);
    if !(a >= 0.0 && b > a && b.ceil() < series.len() as f64) {
        return None;
    }
    (0..=100)
        .map(|p| {
            // At most `b`: rounding must not reach past the last sample checked above.
            let pos = (a + (b - a) * p as f64 / 100.0).min(b);
            let i = pos.floor() as usize;
            let f = pos - i as f64;
            let v = if f == 0.0 {
                series[i]
            } else {
                series[i] * (1.0 - f) + series[i + 1] * f
            };
            v.is_finite().then_some(v)
        })
        .collect()
}

/// One joint's curve over one stride (101 points), for the all-cycles plot and export.
#[derive(Debug, Clone, PartialEq)]
pub struct StrideCurve {
    pub stride: Stride,
    pub joint: &'static str,
    pub values: Vec<f64>,
}

/// Every joint's curve over every given stride that has all its samples.
pub fn each(angles: &Angles, first_frame: usize, strides: &[Stride]) -> Vec<StrideCurve> {
    let mut out = Vec::new();
    for s in strides {
        let leg = angles.leg(s.side);
        for (joint, series) in JOINTS.iter().zip([&leg.hip, &leg.knee, &leg.ankle]) {
            if let Some(values) = resample(series, first_frame, s) {
                out.push(StrideCurve {
                    stride: *s,
                    joint,
                    values,
                });
            }
        }
    }
    out
}

/// Mean and sample SD (NaN for one cycle) at each of the 101 points of equal-length cycles.
pub fn mean_sd(cycles: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let n = cycles.len();
    let len = cycles.first().map_or(0, Vec::len);
    let mean: Vec<f64> = (0..len)
        .map(|p| cycles.iter().map(|c| c[p]).sum::<f64>() / n as f64)
        .collect();
    let sd = (0..len)
        .map(|p| {
            if n < 2 {
                return f64::NAN;
            }
            let ss: f64 = cycles.iter().map(|c| (c[p] - mean[p]).powi(2)).sum();
            (ss / (n - 1) as f64).sqrt()
        })
        .collect();
    (mean, sd)
}

/// Mean and sample SD per joint and side over complete strides; a side with fewer than
/// `min_cycles` complete strides for a joint gets no curve and a warning.
pub fn curves(
    angles: &Angles,
    first_frame: usize,
    strides: &[Stride],
    min_cycles: usize,
    warnings: &mut Vec<String>,
) -> Vec<CycleCurve> {
    let mut out = Vec::new();
    // (side, joint, cycles found) of every curve left out: one warning line for all of them.
    let mut short: Vec<(&str, &str, usize)> = Vec::new();
    for side in Side::BOTH {
        let leg = angles.leg(side);
        for (joint, series) in JOINTS.iter().zip([&leg.hip, &leg.knee, &leg.ankle]) {
            let cycles: Vec<Vec<f64>> = strides
                .iter()
                .filter(|s| s.side == side)
                .filter_map(|s| resample(series, first_frame, s))
                .collect();
            let n = cycles.len();
            if n < min_cycles.max(1) {
                short.push((side.name(), *joint, n));
                continue;
            }
            let (mean, sd) = mean_sd(&cycles);
            out.push(CycleCurve {
                side,
                joint,
                mean,
                sd,
                n_cycles: n,
            });
        }
    }
    if !short.is_empty() {
        // Joints of one side with the same count read as one group: "left hip, knee, ankle (1 found)".
        let mut groups: Vec<(&str, Vec<&str>, usize)> = Vec::new();
        for (side, joint, n) in short {
            match groups.last_mut() {
                Some((s, joints, m)) if *s == side && *m == n => joints.push(joint),
                _ => groups.push((side, vec![joint], n)),
            }
        }
        let groups: Vec<String> = groups
            .iter()
            .map(|(side, joints, n)| format!("{side} {} ({n} found)", joints.join(", ")))
            .collect();
        warnings.push(format!(
            "fewer than {} complete cycles for the {}: no mean curve",
            min_cycles.max(1),
            groups.join("; ")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strides_and_resampling() {
        let hs = |side, frame| Event::on_frame(side, EventKind::HeelStrike, frame);
        let ev = [
            hs(Side::Left, 10),
            hs(Side::Left, 40),
            hs(Side::Left, 200),
            hs(Side::Right, 25),
        ];
        let s = strides(&ev, 30.0, 0.5, 3.0);
        assert_eq!(s, vec![Stride::on_frames(Side::Left, 10, 40)]);
        let series: Vec<f64> = (0..50).map(|i| i as f64).collect();
        let r = resample(&series, 5, &s[0]).unwrap();
        assert_eq!((r[0], r[50], r[100]), (5.0, 20.0, 35.0));
        let mut gap = series.clone();
        gap[20] = f64::NAN;
        assert!(resample(&gap, 5, &s[0]).is_none());
    }

    #[test]
    fn curves_start_at_the_heel_strikes_sub_frame_times() {
        let hs = |frame, at| Event {
            at: Some(at),
            ..Event::on_frame(Side::Left, EventKind::HeelStrike, frame)
        };
        let s = strides(&[hs(10, 10.4), hs(40, 39.6)], 30.0, 0.5, 3.0);
        assert_eq!(s[0].span(), [10.4, 39.6]);
        let series: Vec<f64> = (0..50).map(|i| i as f64).collect();
        let r = resample(&series, 5, &s[0]).unwrap();
        assert!(
            (r[0] - 5.4).abs() < 1e-9 && (r[100] - 34.6).abs() < 1e-9,
            "{r:?}"
        );
        // A last heel strike after the last sample: the frames' span instead.
        let short: Vec<f64> = (0..36).map(|i| i as f64).collect();
        let late = Stride {
            at: Some([10.4, 40.3]),
            ..s[0]
        };
        let r = resample(&short, 5, &late).unwrap();
        assert_eq!((r[0], r[100]), (5.0, 35.0));
    }
}
