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

/// A row of spatiotemporal.csv over the values `v`.
fn row(parameter: &str, side: &str, v: &[f64], unit: &str) -> Param {
    let (mean, sd) = stats(v);
    Param {
        parameter: parameter.into(),
        side: side.into(),
        mean,
        sd,
        n: v.len(),
        unit: unit.into(),
    }
}

/// What each side's strides and steps are measured on: the tracks, the events and the length
/// scale (pixels per output unit).
struct Measure<'a> {
    t: &'a Tracks,
    events: &'a [Event],
    per: f64,
    /// The ground moves in the image (ground.rs): a stride is its two steps.
    ground_moves: bool,
}

impl Measure<'_> {
    /// The heel's (else the ankle's) image x of `side` at input frame `frame`.
    fn heel_x(&self, side: Side, frame: usize) -> Option<f64> {
        let t = self.t;
        let i = frame.checked_sub(t.first_frame)?;
        let j = t
            .seen_leg_index(side, "heel")
            .or_else(|| t.leg_index(side, "ankle"))?;
        t.at(j, i).map(|p| p.0)
    }

    /// The heel strike of `side` at `frame`, at its sub-frame time where the detector has one.
    fn heel_strike_at(&self, side: Side, frame: usize) -> f64 {
        self.events
            .iter()
            .find(|e| e.key() == (side, EventKind::HeelStrike, frame))
            .map_or(frame as f64, Event::time)
    }

    /// Per stride of `side`: [stride time, stance %, stride length, speed].
    fn strides(&self, side: Side, strides: &[Stride]) -> [Vec<f64>; 4] {
        let [mut stride_t, mut stance, mut stride_len, mut speed] = [(); 4].map(|_| Vec::new());
        for s in strides.iter().filter(|s| s.side == side) {
            let (t0, t1) = (
                self.heel_strike_at(side, s.start),
                self.heel_strike_at(side, s.end),
            );
            let dur = (t1 - t0) / self.t.fps;
            stride_t.push(dur);
            if let Some(to) = self.events.iter().find(|e| {
                e.side == side
                    && e.event == EventKind::ToeOff
                    && e.frame > s.start
                    && e.frame < s.end
            }) {
                stance.push(100.0 * (to.time() - t0) / (t1 - t0));
            }
            if let Some(l) = self.stride_length(side, s) {
                stride_len.push(l);
                speed.push(l / dur);
            }
        }
        [stride_t, stance, stride_len, speed]
    }

    /// A stride's length: how far its heel moved between its strikes, or, where the ground
    /// moves in the image, its two steps (the heels' distance at the other foot's strike within
    /// it and at its own closing strike).
    fn stride_length(&self, side: Side, s: &Stride) -> Option<f64> {
        let px = if self.ground_moves {
            let mid = self.events.iter().find(|e| {
                e.side == side.other()
                    && e.event == EventKind::HeelStrike
                    && e.frame > s.start
                    && e.frame < s.end
            })?;
            let apart =
                |f: usize| Some((self.heel_x(side, f)? - self.heel_x(side.other(), f)?).abs());
            apart(mid.frame)? + apart(s.end)?
        } else {
            (self.heel_x(side, s.end)? - self.heel_x(side, s.start)?).abs()
        };
        Some(px / self.per)
    }

    /// Per step of `side` (the other foot's heel strike to this foot's next one) that `step_ok`
    /// accepts and that is at most half the longest stride: [step time, step length].
    fn steps(
        &self,
        side: Side,
        step_ok: &dyn Fn(usize, usize) -> bool,
        max_step_s: f64,
    ) -> [Vec<f64>; 2] {
        let fps = self.t.fps;
        let (mut step_t, mut step_len) = (Vec::new(), Vec::new());
        let hs: Vec<&Event> = self
            .events
            .iter()
            .filter(|e| e.event == EventKind::HeelStrike)
            .collect();
        for w in hs.windows(2) {
            if w[1].side == side && w[0].side != side && step_ok(w[0].frame, w[1].frame) {
                let dur = (w[1].frame - w[0].frame) as f64 / fps;
                if dur > 0.0 && dur <= max_step_s {
                    step_t.push((w[1].time() - w[0].time()) / fps);
                    if let (Some(a), Some(b)) = (
                        self.heel_x(side, w[1].frame),
                        self.heel_x(side.other(), w[1].frame),
                    ) {
                        step_len.push((a - b).abs() / self.per);
                    }
                }
            }
        }
        [step_t, step_len]
    }
}

/// Steps per minute from every step, else from every stride (two steps each).
fn cadence(per_side: &[(Side, [Vec<f64>; 6])]) -> Param {
    let all = |k: usize| -> Vec<f64> {
        per_side
            .iter()
            .flat_map(|(_, p)| p[k].iter().copied())
            .collect()
    };
    let (steps, strides) = (all(1), all(0));
    let cadence: Vec<f64> = if !steps.is_empty() {
        steps.iter().map(|s| 60.0 / s).collect()
    } else {
        strides.iter().map(|s| 120.0 / s).collect()
    };
    row("cadence", "both", &cadence, "steps/min")
}

/// Symmetry index (Robinson et al. 1987) of each parameter: 100 * (X_a - X_b) / (0.5 * (X_a +
/// X_b)), with a the prosthetic and b the intact side, or a = left and b = right when no side
/// is configured.
fn symmetry(
    per_side: &[(Side, [Vec<f64>; 6])],
    names: &[(&str, &str); 6],
    prosthetic: Option<Side>,
) -> Vec<Param> {
    let (a, b, label) = match prosthetic {
        Some(p) => (p, p.other(), "prosthetic_vs_intact"),
        None => (Side::Left, Side::Right, "left_vs_right"),
    };
    let mean_of = |side: Side, k: usize| {
        per_side
            .iter()
            .find(|(s, _)| *s == side)
            .map(|(_, p)| stats(&p[k]).0)
    };
    let mut out = Vec::new();
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

/// All parameters over the given strides, and the steps (other foot's heel strike to this
/// foot's, input frames) `step_ok` accepts; lengths in cm when a scale is known, else in px.
pub fn compute(
    t: &Tracks,
    events: &[Event],
    strides: &[Stride],
    step_ok: &dyn Fn(usize, usize) -> bool,
    cfg: &KinematicsConfig,
    ground_moves: bool,
) -> Vec<Param> {
    let scale = px_per_cm(t, cfg);
    let (len_unit, per) = match scale {
        Some(s) => ("cm", s),
        None => ("px", 1.0),
    };
    let m = Measure {
        t,
        events,
        per,
        ground_moves,
    };
    let per_side: Vec<(Side, [Vec<f64>; 6])> = Side::BOTH
        .iter()
        .map(|&side| {
            let [stride_t, stance, stride_len, speed] = m.strides(side, strides);
            let [step_t, step_len] = m.steps(side, step_ok, cfg.max_stride_s / 2.0);
            (
                side,
                [stride_t, step_t, stance, stride_len, step_len, speed],
            )
        })
        .collect();
    let names = [
        ("stride_time", "s"),
        ("step_time", "s"),
        ("stance", "%"),
        ("stride_length", len_unit),
        ("step_length", len_unit),
        ("speed", if scale.is_some() { "cm/s" } else { "px/s" }),
    ];
    let mut out = vec![cadence(&per_side)];
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
    out.extend(symmetry(&per_side, &names, cfg.prosthetic_side));
    out
}
