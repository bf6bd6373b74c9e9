//! Cadence, stride/step time, stance %, lengths and speed, and the symmetry index.

use serde::Serialize;

use crate::config::{KinematicsConfig, Side};
use crate::cycles::Stride;
use crate::events::{Event, EventKind};
use crate::tracks::Tracks;

/// Hip-to-ankle length as a fraction of body height (Winter, Biomechanics and Motor Control of
/// Human Movement: thigh 0.245 H + shank 0.246 H).
pub const LEG_PER_HEIGHT: f64 = 0.491;

/// One row of `spatiotemporal.csv`.
#[derive(Debug, Clone, Serialize)]
pub struct Param {
    pub parameter: String,
    /// `left`, `right`, `both`, or for symmetry rows `prosthetic_vs_intact` / `left_vs_right`.
    pub side: String,
    pub mean: f64,
    pub sd: f64,
    pub n: usize,
    pub unit: String,
}

impl Param {
    /// Whether the row is a timing (stride and step time, stance, cadence and their symmetry),
    /// not a length or speed measured along the image's x axis.
    pub fn is_temporal(&self) -> bool {
        ["stride_time", "step_time", "stance", "cadence"]
            .iter()
            .any(|p| self.parameter.contains(p))
    }
}

fn stats(v: &[f64]) -> (f64, f64) {
    let n = v.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    let sd = if n < 2 {
        f64::NAN
    } else {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    };
    (mean, sd)
}

/// Pixels per cm from a known length, else from the subject height via the median leg length.
pub fn px_per_cm(t: &Tracks, cfg: &KinematicsConfig) -> Option<f64> {
    if let (Some(m), Some(px)) = (cfg.known_length_m, cfg.known_length_px) {
        return Some(px / (m * 100.0));
    }
    let h = cfg.subject_height_m?;
    let leg = t.leg_length();
    (leg.is_finite() && leg > 0.0).then(|| leg / (LEG_PER_HEIGHT * h * 100.0))
}

/// All parameters over the given strides, and the steps (other foot's heel strike to this
/// foot's, input frames) `step_ok` accepts; lengths in cm when a scale is known, else in px.
pub fn compute(
    t: &Tracks,
    events: &[Event],
    strides: &[Stride],
    step_ok: &dyn Fn(usize, usize) -> bool,
    cfg: &KinematicsConfig,
) -> Vec<Param> {
    let fps = t.fps;
    let scale = px_per_cm(t, cfg);
    let (len_unit, per) = match scale {
        Some(s) => ("cm", s),
        None => ("px", 1.0),
    };
    let heel_x = |side: Side, frame: usize| -> Option<f64> {
        let i = frame.checked_sub(t.first_frame)?;
        let j = t
            .seen_leg_index(side, "heel")
            .or_else(|| t.leg_index(side, "ankle"))?;
        t.at(j, i).map(|p| p.0)
    };
    // Durations from the events' sub-frame times where the detector has them.
    let heel_strike_at = |side: Side, frame: usize| {
        events
            .iter()
            .find(|e| e.key() == (side, EventKind::HeelStrike, frame))
            .map_or(frame as f64, Event::time)
    };
    let mut per_side: Vec<(Side, [Vec<f64>; 6])> = Vec::new();
    for side in Side::BOTH {
        let mut stride_t = Vec::new();
        let mut stance = Vec::new();
        let mut stride_len = Vec::new();
        let mut speed = Vec::new();
        for s in strides.iter().filter(|s| s.side == side) {
            let (t0, t1) = (heel_strike_at(side, s.start), heel_strike_at(side, s.end));
            let dur = (t1 - t0) / fps;
            stride_t.push(dur);
            if let Some(to) = events.iter().find(|e| {
                e.side == side
                    && e.event == EventKind::ToeOff
                    && e.frame > s.start
                    && e.frame < s.end
            }) {
                stance.push(100.0 * (to.time() - t0) / (t1 - t0));
            }
            if let (Some(a), Some(b)) = (heel_x(side, s.start), heel_x(side, s.end)) {
                let l = (b - a).abs() / per;
                stride_len.push(l);
                speed.push(l / dur);
            }
        }
        // Step: from the other foot's heel strike to this foot's next one.
        let mut step_t = Vec::new();
        let mut step_len = Vec::new();
        let hs: Vec<&Event> = events
            .iter()
            .filter(|e| e.event == EventKind::HeelStrike)
            .collect();
        for w in hs.windows(2) {
            if w[1].side == side && w[0].side != side && step_ok(w[0].frame, w[1].frame) {
                let dur = (w[1].frame - w[0].frame) as f64 / fps;
                if dur > 0.0 && dur <= cfg.max_stride_s / 2.0 {
                    step_t.push((w[1].time() - w[0].time()) / fps);
                    if let (Some(a), Some(b)) =
                        (heel_x(side, w[1].frame), heel_x(side.other(), w[1].frame))
                    {
                        step_len.push((a - b).abs() / per);
                    }
                }
            }
        }
        per_side.push((
            side,
            [stride_t, step_t, stance, stride_len, step_len, speed],
        ));
    }
    let names = [
        ("stride_time", "s"),
        ("step_time", "s"),
        ("stance", "%"),
        ("stride_length", len_unit),
        ("step_length", len_unit),
        ("speed", if scale.is_some() { "cm/s" } else { "px/s" }),
    ];
    let mut out = Vec::new();
    let row = |parameter: &str, side: &str, v: &[f64], unit: &str| {
        let (mean, sd) = stats(v);
        Param {
            parameter: parameter.into(),
            side: side.into(),
            mean,
            sd,
            n: v.len(),
            unit: unit.into(),
        }
    };
    let all_steps: Vec<f64> = per_side
        .iter()
        .flat_map(|(_, p)| p[1].iter().copied())
        .collect();
    let all_strides: Vec<f64> = per_side
        .iter()
        .flat_map(|(_, p)| p[0].iter().copied())
        .collect();
    let cadence: Vec<f64> = if !all_steps.is_empty() {
        all_steps.iter().map(|s| 60.0 / s).collect()
    } else {
        all_strides.iter().map(|s| 120.0 / s).collect()
    };
    out.push(row("cadence", "both", &cadence, "steps/min"));
    // Thigh + shank (median over frames): the leg length L that Hof's dimensionless speed,
    // cadence and step length are scaled by, so the report can set them against the norms.
    let leg = t.leg_length() / per;
    if leg.is_finite() && leg > 0.0 {
        out.push(Param {
            parameter: "leg_length".into(),
            side: "both".into(),
            mean: leg,
            sd: f64::NAN,
            n: t.len(),
            unit: len_unit.into(),
        });
    }
    for (side, params) in &per_side {
        for ((name, unit), v) in names.iter().zip(params) {
            out.push(row(name, side.name(), v, unit));
        }
    }
    // Symmetry index (Robinson et al. 1987): 100 * (X_a - X_b) / (0.5 * (X_a + X_b)), with a the
    // prosthetic and b the intact side, or a = left and b = right when no side is configured.
    let (a, b, label) = match cfg.prosthetic_side {
        Some(p) => (p, p.other(), "prosthetic_vs_intact"),
        None => (Side::Left, Side::Right, "left_vs_right"),
    };
    let mean_of = |side: Side, k: usize| {
        per_side
            .iter()
            .find(|(s, _)| *s == side)
            .map(|(_, p)| stats(&p[k]).0)
    };
    for (k, (name, _)) in names.iter().enumerate() {
        if let (Some(xa), Some(xb)) = (mean_of(a, k), mean_of(b, k)) {
            let si = 100.0 * (xa - xb) / (0.5 * (xa + xb));
            let n = per_side.iter().map(|(_, p)| p[k].len()).min().unwrap_or(0);
            out.push(Param {
                parameter: format!("symmetry_index_{name}"),
                side: label.into(),
                mean: si,
                sd: f64::NAN,
                n: if si.is_finite() { n } else { 0 },
                unit: "%".into(),
            });
        }
    }
    out
}
