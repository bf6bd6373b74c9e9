//! Synthetic side-view walkers for the unit tests.

use crate::config::Side;
use crate::event::{Event, EventKind};
use crate::tracks::{LEG, Tracks};

/// Stride length in pixels (1.5 leg lengths of about 300 px).
pub const STRIDE_PX: f64 = 450.0;

/// A walker whose pelvis is at `pelvis[i]` (image x) while the ground under it has travelled
/// `travel[i]` pixels; `dir[i]` is +1 or -1. Each foot is planted on the ground for 60 % of a
/// stride and swings through the rest, the two feet half a stride apart; hips at y = 300,
/// ankles at y = 600, so the leg is about 300 px long.
fn legs(fps: f64, pelvis: &[f64], travel: &[f64], dir: &[f64]) -> Tracks {
    let n = pelvis.len();
    let mut names = vec!["mid_hip".to_string()];
    for side in ["left", "right"] {
        names.extend(LEG.iter().map(|p| format!("{side}_{p}")));
    }
    let k = names.len();
    let mut t = Tracks {
        fps,
        first_frame: 0,
        names,
        x: vec![vec![0.0; n]; k],
        y: vec![vec![0.0; n]; k],
        likelihood: vec![vec![1.0; n]; k],
    };
    let l = STRIDE_PX;
    for i in 0..n {
        let (x, d) = (pelvis[i], dir[i]);
        t.x[0][i] = x;
        t.y[0][i] = 300.0;
        for side in 0..2 {
            let phase = (travel[i] / l + 0.5 * side as f64).rem_euclid(1.0);
            let (offset, lift) = if phase < 0.6 {
                (0.3 * l - phase * l, 0.0)
            } else {
                let s = (phase - 0.6) / 0.4;
                (
                    -0.3 * l + s * 0.6 * l,
                    30.0 * (std::f64::consts::PI * s).sin(),
                )
            };
            let ankle = (x + d * offset, 600.0 - lift);
            let pts = [
                (x, 300.0),
                (x + d * (offset / 2.0 + 20.0), 450.0 - lift / 2.0),
                ankle,
                (ankle.0 - d * 15.0, ankle.1 + 15.0),
                (ankle.0 + d * 45.0, ankle.1 + 20.0),
            ];
            for (p, &(px, py)) in pts.iter().enumerate() {
                t.x[1 + 5 * side + p][i] = px;
                t.y[1 + 5 * side + p][i] = py;
            }
        }
    }
    t
}

/// Overground walker with pelvis x given per frame; the feet follow the distance walked.
pub fn walker(fps: f64, n: usize, pos: impl Fn(usize) -> f64) -> Tracks {
    let pelvis: Vec<f64> = (0..n).map(&pos).collect();
    let mut travel = vec![0.0; n];
    let mut dir = vec![1.0; n];
    for i in 1..n {
        let step = pelvis[i] - pelvis[i - 1];
        travel[i] = travel[i - 1] + step.abs();
        dir[i] = if step > 0.0 {
            1.0
        } else if step < 0.0 {
            -1.0
        } else {
            dir[i - 1]
        };
    }
    if n > 1 {
        dir[0] = dir[1];
    }
    legs(fps, &pelvis, &travel, &dir)
}

/// Treadmill walker facing image right: pelvis fixed, belt moving at `belt` px/s.
pub fn treadmill(fps: f64, n: usize, belt: f64) -> Tracks {
    let travel: Vec<f64> = (0..n).map(|i| belt * i as f64 / fps).collect();
    legs(fps, &vec![600.0; n], &travel, &vec![1.0; n])
}

/// `(side, frame)` of the toe-offs among `ev`.
pub fn toe_offs(ev: &[Event]) -> Vec<(Side, usize)> {
    ev.iter()
        .filter(|e| e.event == EventKind::ToeOff)
        .map(|e| (e.side, e.frame))
        .collect()
}
