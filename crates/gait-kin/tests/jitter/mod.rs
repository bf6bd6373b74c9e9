//! BlazePose-like jitter for keypoints of motion capture seen as a video (issue 38), shared by
//! crates/gait-kin/tests/frontal_mocap.rs and tests/visit.rs (both declare `mod rng` beside it).
#![allow(dead_code)]

use crate::rng::Rng;
use gait_core::PoseSequence;

/// Which noise: as measured at the hips, everywhere (pairs' shared vertical jitter); the same
/// with the knees and feet at their own measured levels ([`part_scale`]); or every coordinate
/// independent at the hips' level (a harsher model for the hips, reported beside it).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Jitter {
    Measured,
    MeasuredLimbs,
    Independent,
}

/// BlazePose's jitter on the bundled sample (`tools/frontal/measure_jitter.py`: residuals of a
/// 9-frame quadratic fit), in a side view (the walker, frames 127-158 of
/// tests/data/sample-blazepose) and a front view (the man on the box facing the camera, frames
/// 0-95 cropped; `tools/frontal/jitter.sh`): about 1 px per 100 px of leg (thigh + shank) at the
/// hips and shoulders (0.9-1.2 at the hips, 0.5-0.8 vertically at the shoulders). The two hips'
/// vertical jitter is shared: their residuals correlate +0.90 (side) and +0.92 (front), so the
/// hip line's height difference jitters by 0.39-0.49 px per 100 px of leg, not the 1.4 of two
/// independent hips; the shoulders' correlate +0.56 and +0.49. Knees and feet: [`part_scale`].
const NOISE_PER_100_LEG_PX: f64 = 1.0;
/// The knees' and feet's jitter as a multiple of the hips'. In stance, where a foot stands
/// still, BlazePose's knees and feet jitter more than its hips
/// (`tools/frontal/measure_stance_jitter.py`: knees 1.1-2.0, feet 1.0-3.4 per 100 px of leg, the
/// feet about twice the hips vertically, on the sample and three re-encodings; BENCHMARKS.md,
/// "Knees and feet"): [`Jitter::MeasuredLimbs`] takes 1.5 and 2. With [`Jitter::Measured`] the
/// environment may set them (`GAIT_TEST_KNEE_JITTER`, `GAIT_TEST_FEET_JITTER`; default 1) to
/// measure the visit's figures at other levels.
fn part_scale(model: Jitter, name: &str) -> f64 {
    let env = |var: &str| {
        std::env::var(var)
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(1.0)
    };
    let (knee, feet) = match model {
        Jitter::MeasuredLimbs => (1.5, 2.0),
        Jitter::Measured => (env("GAIT_TEST_KNEE_JITTER"), env("GAIT_TEST_FEET_JITTER")),
        Jitter::Independent => (1.0, 1.0),
    };
    if name.ends_with("knee") {
        knee
    } else if ["ankle", "heel", "toe"].iter().any(|p| name.ends_with(p)) {
        feet
    } else {
        1.0
    }
}

/// Correlation of a left/right pair's vertical jitter (measured above, rounded); other pairs
/// and all horizontal jitter are drawn independently.
const PAIR_Y_CORRELATION: [(&str, f64); 2] = [("hip", 0.9), ("shoulder", 0.5)];

/// The 150 Hz trial seen as a 30 fps video (every 5th frame, numbered 0, 1, ...) with
/// pose-model jitter added.
pub fn as_video(seq: &PoseSequence, seed: u64, model: Jitter) -> PoseSequence {
    let mut rng = Rng::seeded(seed);
    let mut out = seq.clone();
    out.poses = seq.poses.iter().step_by(5).cloned().collect();
    out.frames = (0..out.poses.len()).collect();
    out.fps = seq.fps / 5.0;
    let idx = |n: &str| seq.names.iter().position(|m| m == n).expect(n);
    let [h, k, a] = ["left_hip", "left_knee", "left_ankle"].map(idx);
    let pairs: Vec<(usize, usize, f64)> = PAIR_Y_CORRELATION
        .iter()
        .filter(|_| model != Jitter::Independent)
        .filter_map(|(part, rho)| {
            let find = |side: &str| {
                seq.names
                    .iter()
                    .position(|m| *m == format!("{side}_{part}"))
            };
            Some((find("left")?, find("right")?, *rho))
        })
        .collect();
    for pose in &mut out.poses {
        let kp = &pose.keypoints;
        let d = |i: usize, j: usize| (kp[i].x - kp[j].x).hypot(kp[i].y - kp[j].y);
        let leg = d(h, k) + d(k, a);
        let sigma = NOISE_PER_100_LEG_PX * leg / 100.0;
        // Drawn in the same order for both models (x then y of each keypoint), so the
        // independent model is the earlier tests' noise, draw for draw.
        let draws: Vec<(f64, f64)> = (0..pose.keypoints.len())
            .map(|_| (rng.normal(), rng.normal()))
            .collect();
        let mut dy: Vec<f64> = draws.iter().map(|d| d.1).collect();
        for &(l, r, rho) in &pairs {
            // Unit variance each, correlation rho: a^2 + b^2 = 1 and 2ab = rho.
            let a = ((1.0 + rho).sqrt() + (1.0 - rho).sqrt()) / 2.0;
            let b = ((1.0 + rho).sqrt() - (1.0 - rho).sqrt()) / 2.0;
            (dy[l], dy[r]) = (
                a * draws[l].1 + b * draws[r].1,
                b * draws[l].1 + a * draws[r].1,
            );
        }
        for (((p, d), dy), name) in pose
            .keypoints
            .iter_mut()
            .zip(&draws)
            .zip(dy)
            .zip(&seq.names)
        {
            let s = sigma * part_scale(model, name);
            p.x += s * d.0;
            p.y += s * dy;
        }
    }
    out
}
