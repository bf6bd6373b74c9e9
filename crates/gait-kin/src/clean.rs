//! The cleaning chain: the pose model's keypoints -> gated, labels corrected, gaps filled,
//! smoothed; with what the quality rules need from before it.

use gait_core::PoseSequence;

use crate::corrections::{self, Corrections};
use crate::{PostprocessConfig, Tracks, View};
use crate::{Steps, collapse, foot_shape, frontal, glitch, smooth, spikes, swap};

/// The keypoints after cleaning, plus what the quality rules need from before it.
pub(crate) struct Cleaned {
    /// Gated, swap-corrected, gap-filled and smoothed.
    pub clean: Tracks,
    /// Gated and swap-corrected, before gap filling: what the pose model really gave.
    pub gated: Tracks,
    /// The model's likelihoods before the gate, leg labels swap-corrected.
    pub raw_likelihood: Vec<Vec<f64>>,
    /// Frames the automatic swap correction exchanged, outside the ranges a person swapped.
    pub swapped: Vec<bool>,
    /// Frames whose leg labels are in doubt, outside the ranges a person swapped.
    pub unsure: Vec<bool>,
    /// Frames whose lower legs were dropped as collapsed.
    pub collapsed: usize,
}

/// Likelihood gate -> glitches dropped -> collapsed frames dropped -> swap correction ->
/// single-frame jumps and misplaced heels and toes dropped -> the corrections' swaps and
/// keypoints -> gap filling -> smoothing (collapsed frames filled after it).
pub(crate) fn clean(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    steps: &Steps,
    fixes: &Corrections,
    view: View,
    warnings: &mut Vec<String>,
) -> Cleaned {
    let mut t = Tracks::from_sequence(seq);
    let mut raw = t.clone();
    gate(&mut t, steps, post, warnings);
    // Frames where the pose left the subject's path for a moment (someone else drawn while
    // the subject passes them) are not the subject: dropped whole, bridged by the gap filler.
    glitch::drop_glitches(&mut t, warnings);
    let collapsed = drop_collapsed(&mut t, steps, view, warnings);
    let mut labels = correct_labels(&mut t, &mut raw, steps, view);
    drop_misplaced(&mut t, view, warnings);
    // A person's swaps come after the automatic correction, which therefore cannot undo them;
    // their frames stop counting as swapped (a confirmed fix, see `apply_swaps`).
    corrections::apply_swaps(
        fixes,
        &mut t,
        &mut raw,
        [&mut labels.swapped, &mut labels.unsure],
    );
    let swapped_frames = labels.swapped.iter().filter(|&&s| s).count();
    if swapped_frames > 0 {
        warnings.push(format!(
            "left/right leg labels corrected in {swapped_frames} frames"
        ));
    }
    // A person's keypoints are in the labels they see in the output, so they come after both
    // label corrections; before gap filling and smoothing, as if the pose model had given them.
    corrections::apply_keypoints(fixes, &mut t, &mut raw);
    let gated = t.clone();
    fill_and_smooth(&mut t, &gated, &collapsed, steps, post, warnings);
    Cleaned {
        clean: t,
        gated,
        raw_likelihood: raw.likelihood,
        swapped: labels.swapped,
        unsure: labels.unsure,
        collapsed: collapsed.iter().filter(|&&c| c).count(),
    }
}

/// The likelihood gate, with warnings for an empty input and for nothing left.
fn gate(t: &mut Tracks, steps: &Steps, post: &PostprocessConfig, warnings: &mut Vec<String>) {
    let n = t.len();
    if n == 0 {
        warnings.push("no frames in the input".into());
    }
    steps.gate.apply(t);
    if n > 0 && t.x.iter().all(|x| x.iter().all(|v| !v.is_finite())) {
        warnings.push(format!(
            "no keypoint with likelihood >= {} in any frame",
            post.likelihood_threshold
        ));
    }
}

/// Frames with both legs drawn on one carry no labels and mislead the swap correction; they
/// are part of the label cleaning and go with it. In a front or back view the legs are apart
/// and the hips say which is which: neither the collapse rule nor the side view's continuity
/// swap applies. Returns the collapsed frames.
fn drop_collapsed(
    t: &mut Tracks,
    steps: &Steps,
    view: View,
    warnings: &mut Vec<String>,
) -> Vec<bool> {
    let collapsed = match steps.swap {
        Some(_) if !view.is_frontal() => collapse::CollapseRule::default().find(t),
        _ => vec![false; t.len()],
    };
    let frames = collapsed.iter().filter(|&&c| c).count();
    if frames > 0 {
        collapse::drop_frames(t, &collapsed);
        warnings.push(format!(
            "lower-leg keypoints dropped in {frames} frames where both legs were drawn on one"
        ));
    }
    collapsed
}

/// The automatic label correction (the front view's by the hips, a side view's by continuity),
/// applied to `t` and to the likelihoods' copy `raw`.
fn correct_labels(t: &mut Tracks, raw: &mut Tracks, steps: &Steps, view: View) -> swap::Labels {
    let n = t.len();
    let labels = match steps.swap {
        _ if view.is_frontal() => {
            let swapped = frontal::labels::fix(t, view);
            swap::Labels {
                unsure: swapped.clone(),
                swapped,
            }
        }
        Some(s) => s.correct_judged(t),
        None => swap::Labels {
            swapped: vec![false; n],
            unsure: vec![false; n],
        },
    };
    for i in (0..n).filter(|&i| labels.swapped[i]) {
        swap::swap_frame(raw, i);
    }
    labels
}

/// Keypoints the model misplaced for a frame or two move the events once filtered: a knee or
/// foot jumping for one frame, and a heel or toe drawn where the foot cannot be (too near or
/// too far from its ankle). Judged on the corrected labels (an exchanged frame is a jump of
/// both legs, not of one point), before a person's swaps (whose range edges are jumps by
/// design). Side views only: in a front or back view the foot turns out of the image plane.
fn drop_misplaced(t: &mut Tracks, view: View, warnings: &mut Vec<String>) {
    if view.is_frontal() {
        return;
    }
    let spikes = spikes::SpikeRule::default().drop(t);
    let feet = foot_shape::FootShapeRule::default().drop(t);
    for (n, what) in [
        (spikes, "single-frame jumps of a knee or foot keypoint"),
        (
            feet,
            "heel or toe keypoints too near or too far from their ankle",
        ),
    ] {
        if n > 0 {
            warnings.push(format!("{n} {what} dropped (bridged)"));
        }
    }
}

/// Gap filling and smoothing of every keypoint; a collapsed frame is filled after smoothing.
fn fill_and_smooth(
    t: &mut Tracks,
    gated: &Tracks,
    collapsed: &[bool],
    steps: &Steps,
    post: &PostprocessConfig,
    warnings: &mut Vec<String>,
) {
    let (n, fps) = (t.len(), t.fps);
    let max_gap = post.max_gap(fps);
    for j in 0..t.names.len() {
        let present = t.x[j].iter().any(|v| v.is_finite());
        if !present {
            continue;
        }
        let mut left = Vec::new();
        for coord in [&mut t.x[j], &mut t.y[j]] {
            left = steps.gap_filler.fill(coord, max_gap);
        }
        // Gaps matter to the reader only where the kinematics use the point;
        // a model's extra native keypoints (hands, face) are filled silently.
        let used = gait_core::keypoint::canonical_index(&t.names[j]).is_some();
        for (start, len) in left.into_iter().filter(|_| used) {
            warnings.push(format!(
                "gap of {len} frames in {} (from frame {}) left empty (longer than {max_gap})",
                t.names[j],
                t.first_frame + start
            ));
        }
        // Filled samples carry no model likelihood; mark them as at the threshold.
        for i in 0..n {
            if t.x[j][i].is_finite() && t.likelihood[j][i] < post.likelihood_threshold {
                t.likelihood[j][i] = post.likelihood_threshold;
            }
        }
        // A collapsed frame is filled only after smoothing, from the smoothed frames around it:
        // filtered with the rest, the filled guess would spread over the well-seen frames
        // either side. Collapses come with fast movement (motion blur; both inside the sample's
        // walk are at a foot leaving the ground), and the guess then moves its onset into them.
        let late: Vec<usize> = (0..n)
            .filter(|&i| collapsed[i] && gated.x[j][i].is_nan() && t.x[j][i].is_finite())
            .collect();
        for coord in [&mut t.x[j], &mut t.y[j]] {
            for &i in &late {
                coord[i] = f64::NAN;
            }
            smooth::smooth_segments(steps.smoother, coord, fps);
            if !late.is_empty() {
                steps.gap_filler.fill(coord, max_gap);
            }
        }
    }
}
