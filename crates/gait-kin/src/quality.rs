//! Per-stride quality control: which candidate strides enter the mean curves and the
//! spatiotemporal parameters.
//!
//! A stride is judged on the data it was measured from: a stride time far from the subject's
//! usual one (a missed or extra heel strike), keypoints the model did not give (a long filled
//! gap), keypoints the model was unsure of, a leg whose segments change length (a wrong or
//! partly hidden pose), leg labels the swap correction had to exchange, a stride that does
//! not lie in one walking bout, or one over frames a person excluded (`[[exclude]]` in
//! [`crate::corrections`]). Each rejection names its reasons.

use serde::Serialize;

use crate::bouts::{Bout, bout_of};
use crate::config::{KinematicsConfig, Side};
use crate::corrections::FrameRange;
use crate::cycles::Stride;
use crate::tracks::{LEG, Tracks, dist, median};
use swing_contrast::FeetInMotion;

/// Why a stride was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// Stride time further than `cycle_max_stride_deviation` from the median stride time.
    StrideTime,
    /// A keypoint of the leg missing (filled or not) for longer than `cycle_max_filled_s`.
    FilledGap,
    /// Mean model likelihood of the leg's keypoints below `cycle_min_likelihood`.
    LowLikelihood,
    /// Median thigh or shank length out of line with the bout's median.
    SegmentLength,
    /// Leg labels exchanged by the swap correction inside the stride.
    Swap,
    /// Start and end not in the same walking bout.
    CrossesBout,
    /// Overlaps frames excluded in the corrections (`[[exclude]]`).
    Excluded,
    /// The leg shorter than `cycle_min_leg_px`: the walker too small in the image.
    SmallSubject,
    /// The leg far from the camera in its bout (a side view), while the same leg has accepted
    /// strides near the camera in a bout the other way (a walk there and back).
    FarSide,
    /// The legs' image blur over `cycle_max_blur_share` of the leg: the walker too blurred.
    Blurred,
    /// The foot, swinging, keeps less than `cycle_min_swing_contrast` of its outline's
    /// contrast standing: smeared by a long exposure.
    MotionBlurred,
}

pub const REASONS: [Reason; 11] = [
    Reason::StrideTime,
    Reason::FilledGap,
    Reason::LowLikelihood,
    Reason::SegmentLength,
    Reason::Swap,
    Reason::CrossesBout,
    Reason::Excluded,
    Reason::SmallSubject,
    Reason::FarSide,
    Reason::Blurred,
    Reason::MotionBlurred,
];

impl Reason {
    pub fn name(self) -> &'static str {
        match self {
            Reason::StrideTime => "stride_time",
            Reason::FilledGap => "filled_gap",
            Reason::LowLikelihood => "low_likelihood",
            Reason::SegmentLength => "segment_length",
            Reason::Swap => "swap",
            Reason::CrossesBout => "crosses_bout",
            Reason::Excluded => "excluded",
            Reason::SmallSubject => "small_subject",
            Reason::FarSide => "far_side",
            Reason::Blurred => "blurred",
            Reason::MotionBlurred => "motion_blurred",
        }
    }

    pub(crate) fn describe(self, kin: &KinematicsConfig) -> String {
        match self {
            Reason::StrideTime => format!(
                "stride time more than {:.0} % from the median stride time",
                100.0 * kin.cycle_max_stride_deviation
            ),
            Reason::FilledGap => format!(
                "a leg keypoint missing for more than {} s",
                kin.cycle_max_filled_s
            ),
            Reason::LowLikelihood => format!(
                "mean leg keypoint likelihood below {}",
                kin.cycle_min_likelihood
            ),
            Reason::SegmentLength => format!(
                "thigh or shank length more than {:.0} % from the bout's median",
                100.0 * kin.cycle_segment_tolerance
            ),
            Reason::Swap => "leg labels in doubt (left and right could not be told apart)".into(),
            Reason::CrossesBout => "not inside one walking bout".into(),
            Reason::Excluded => "over frames excluded in the corrections".into(),
            Reason::SmallSubject => format!(
                "legs shorter than {} px (hip to ankle): the walker is too small in the image; film closer or at a higher resolution",
                kin.cycle_min_leg_px
            ),
            Reason::Blurred => format!(
                "the legs' image blurred over {:.1} % of the leg length: too blurred for reliable keypoints; film in focus, in more light or with a shorter exposure",
                100.0 * kin.cycle_max_blur_share
            ),
            Reason::MotionBlurred => format!(
                "the swinging foot's outline under {:.0} % of its contrast standing: smeared by a long exposure; film in more light or with a faster shutter (1/250 s or shorter)",
                100.0 * kin.cycle_min_swing_contrast
            ),
            Reason::FarSide => "the leg far from the camera (half hidden) in this walk; the same leg's strides near the camera in the walk the other way are used".into(),
        }
    }
}

/// The verdict on one candidate stride, with the numbers behind it (one row of
/// cycle_quality.csv).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CycleQuality {
    pub side: Side,
    /// Heel strike starting the stride (input frame number).
    pub first_frame: usize,
    /// Next heel strike of the same foot.
    pub last_frame: usize,
    pub accepted: bool,
    pub reasons: Vec<Reason>,
    pub stride_s: f64,
    /// |stride time - median| / median, the median over both sides' strides.
    pub stride_deviation: f64,
    /// Longest run of samples of one leg keypoint the model did not give, in seconds.
    pub max_filled_s: f64,
    /// Mean model likelihood over the leg's keypoints and the stride's frames.
    pub mean_likelihood: f64,
    /// Median thigh length over the stride / median over the bout (both legs).
    pub thigh_ratio: f64,
    pub shank_ratio: f64,
    /// Median thigh + median shank length of the stride's leg, pixels.
    pub leg_px: f64,
    /// Median blur of the legs' image over the frames measured in the stride (px; NaN when
    /// none was measured), judged against `cycle_max_blur_share` of `leg_px`.
    pub blur_px: f64,
    /// The foot's outline contrast swinging fast over standing (NaN when not measured), judged
    /// against `cycle_min_swing_contrast`.
    pub swing_contrast: f64,
    /// Frames inside the stride whose leg labels the swap correction exchanged.
    pub swapped_frames: usize,
    /// Frames inside the stride whose leg labels are in doubt (judged by
    /// `cycle_max_swapped_share`): a clean exchange, corrected, is not.
    pub unsure_frames: usize,
    /// Index into the bouts of the bout holding the whole stride.
    pub bout: Option<usize>,
    /// The heel strikes' sub-frame times ([`Stride::at`]).
    #[serde(skip)]
    pub at: Option<[f64; 2]>,
}

impl CycleQuality {
    pub fn stride(&self) -> Stride {
        Stride {
            at: self.at,
            ..Stride::on_frames(self.side, self.first_frame, self.last_frame)
        }
    }
}

/// Counts per side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct SideCounts {
    pub left: usize,
    pub right: usize,
}

/// The data a verdict is based on.
pub struct Evidence<'a> {
    /// Fully cleaned keypoints.
    pub clean: &'a Tracks,
    /// After the gate and swap correction, before gap filling (missing = not given).
    pub gated: &'a Tracks,
    /// The model's likelihoods before the gate, per keypoint and frame, labels swap-corrected.
    pub raw_likelihood: &'a [Vec<f64>],
    /// Frames whose labels the automatic swap correction exchanged (not those a person swapped).
    pub swapped: &'a [bool],
    /// Frames whose leg labels the swap correction could not tell with confidence.
    pub unsure: &'a [bool],
    pub bouts: &'a [Bout],
    /// Whether a stride must lie in one bout (not for events from a file with detected bouts:
    /// the user's events say where the walking is).
    pub enforce_bouts: bool,
    /// Input frames a person excluded: a stride overlapping one is rejected.
    pub excluded: &'a [FrameRange],
    /// Per timeline frame, the body's size in pixels when it changes with the distance to the
    /// camera (a front or back view): segment lengths are compared in body sizes then.
    pub size: Option<&'a [f64]>,
}

/// Whether stride `s` overlaps an excluded range.
fn excluded(ev: &Evidence, s: &Stride) -> bool {
    crate::corrections::excluded_overlap(ev.excluded, s.start, s.end)
}

/// The leg's keypoints the model gives (seen in some frame).
fn leg_points(g: &Tracks, side: Side) -> Vec<usize> {
    LEG.iter()
        .filter_map(|p| g.leg_index(side, p))
        .filter(|&j| g.x[j].iter().any(|v| v.is_finite()))
        .collect()
}

/// Median thigh and shank lengths over timeline frames `range` of the given sides, in pixels
/// or, with `size`, in body sizes of each frame.
fn segments(
    t: &Tracks,
    size: Option<&[f64]>,
    sides: &[Side],
    range: std::ops::RangeInclusive<usize>,
) -> [f64; 2] {
    let mut out = [Vec::new(), Vec::new()];
    for &side in sides {
        let idx = ["hip", "knee", "ankle"].map(|p| t.leg_index(side, p));
        let [Some(h), Some(k), Some(a)] = idx else {
            continue;
        };
        for i in range.clone() {
            let unit = size.map_or(1.0, |s| s[i]);
            let (hp, kp, ap) = (t.at(h, i), t.at(k, i), t.at(a, i));
            if let (Some(hp), Some(kp)) = (hp, kp) {
                out[0].push(dist(hp, kp) / unit);
            }
            if let (Some(kp), Some(ap)) = (kp, ap) {
                out[1].push(dist(kp, ap) / unit);
            }
        }
    }
    out.map(|mut v| median(&mut v))
}

/// Longest run of frames in `range` where one of `points` is missing in `g`.
fn longest_gap(g: &Tracks, points: &[usize], range: std::ops::RangeInclusive<usize>) -> usize {
    let mut best = 0;
    for &j in points {
        let mut run = 0;
        for i in range.clone() {
            run = if g.at(j, i).is_none() { run + 1 } else { 0 };
            best = best.max(run);
        }
    }
    best
}

/// The median stride time the deviations are measured from, pooled over both sides: in steady
/// walking both legs share one stride time, even in asymmetric prosthetic gait (the step times
/// differ, the strides do not), and pooling doubles the strides the median rests on. Strides
/// outside a bout do not count where bouts are enforced, nor strides over excluded frames.
fn median_stride_s(ev: &Evidence, strides: &[Stride], fps: f64) -> f64 {
    let dur = |s: &Stride| (s.end - s.start) as f64 / fps;
    let mut inside: Vec<f64> = strides
        .iter()
        .filter(|s| !ev.enforce_bouts || same_bout(ev.bouts, s).is_some())
        .filter(|s| !excluded(ev, s))
        .map(dur)
        .collect();
    if inside.is_empty() {
        inside = strides.iter().map(dur).collect();
    }
    median(&mut inside)
}

fn same_bout(bouts: &[Bout], s: &Stride) -> Option<usize> {
    bout_of(bouts, s.start).filter(|&b| bout_of(bouts, s.end) == Some(b))
}

/// Judges every candidate stride.
pub fn assess(ev: &Evidence, strides: &[Stride], kin: &KinematicsConfig) -> Vec<CycleQuality> {
    let t = ev.clean;
    let (n, fps, f0) = (t.len(), t.fps, t.first_frame);
    if n == 0 {
        return Vec::new();
    }
    let med = median_stride_s(ev, strides, fps);
    let whole = segments(t, ev.size, &Side::BOTH, 0..=n - 1);
    let per_bout: Vec<[f64; 2]> = ev
        .bouts
        .iter()
        .map(|b| {
            let a = b.first.saturating_sub(f0).min(n - 1);
            segments(t, ev.size, &Side::BOTH, a..=(b.last - f0).min(n - 1))
        })
        .collect();
    let feet = FeetInMotion::measure(t, kin, ev.size.is_some());
    let mut out: Vec<CycleQuality> = strides
        .iter()
        .map(|s| {
            let bout = same_bout(ev.bouts, s);
            let reference = bout.map_or(whole, |b| per_bout[b]);
            let mut q = measure(ev, s, reference, med);
            q.blur_px = stride_blur(kin, s);
            q.swing_contrast = feet.swing_contrast(s);
            q.bout = bout;
            q.reasons = verdict(&q, kin, ev.enforce_bouts);
            if excluded(ev, s) {
                q.reasons.push(Reason::Excluded);
            }
            q.accepted = q.reasons.is_empty();
            q
        })
        .collect();
    reject_far_sides(&mut out, ev);
    out
}

/// Side views: a leg's strides far from the camera are rejected where the same leg has
/// accepted strides near it, in a bout walked the other way. From a side view the far leg is
/// half hidden behind the near one: on the bundled sample walked there and back its mean
/// curves differ from the near walk's by 4.5-8.7 deg RMS, and pooled they would move the near
/// curves by 2.7-5.2. A walk one way only keeps every stride (the far leg's are all it has).
fn reject_far_sides(strides: &mut [CycleQuality], ev: &Evidence) {
    if ev.size.is_some() {
        return;
    }
    let near = |q: &CycleQuality| {
        q.bout
            .and_then(|b| ev.bouts.get(b))
            .and_then(|b| b.direction.near_side())
            .map(|s| s == q.side)
    };
    for side in Side::BOTH {
        let has_near = strides
            .iter()
            .any(|q| q.side == side && q.accepted && near(q) == Some(true));
        if !has_near {
            continue;
        }
        for q in strides
            .iter_mut()
            .filter(|q| q.side == side && near(q) == Some(false))
        {
            q.reasons.push(Reason::FarSide);
            q.accepted = false;
        }
    }
}

/// The median of the legs' blur measured in the frames of stride `s` (NaN: none measured).
fn stride_blur(kin: &KinematicsConfig, s: &Stride) -> f64 {
    let Some(blur) = &kin.image_blur_px else {
        return f64::NAN;
    };
    let mut v: Vec<f64> = blur.range(s.start..=s.end).map(|(_, b)| *b).collect();
    median(&mut v)
}

/// The numbers of one stride (bout, reasons and verdict left for the caller).
fn measure(ev: &Evidence, s: &Stride, reference: [f64; 2], median_s: f64) -> CycleQuality {
    let t = ev.clean;
    let (n, fps) = (t.len(), t.fps);
    let a = s.start.saturating_sub(t.first_frame).min(n - 1);
    let b = s.end.saturating_sub(t.first_frame).min(n - 1);
    let points = leg_points(ev.gated, s.side);
    let lik: Vec<f64> = points
        .iter()
        .flat_map(|&j| ev.raw_likelihood[j][a..=b].iter().copied())
        .collect();
    let own = segments(t, ev.size, &[s.side], a..=b);
    let px = match ev.size {
        Some(_) => segments(t, None, &[s.side], a..=b),
        None => own,
    };
    let stride_s = (s.end - s.start) as f64 / fps;
    CycleQuality {
        side: s.side,
        first_frame: s.start,
        last_frame: s.end,
        accepted: false,
        reasons: Vec::new(),
        stride_s,
        stride_deviation: (stride_s - median_s).abs() / median_s,
        max_filled_s: longest_gap(ev.gated, &points, a..=b) as f64 / fps,
        mean_likelihood: lik.iter().sum::<f64>() / lik.len() as f64,
        thigh_ratio: own[0] / reference[0],
        shank_ratio: own[1] / reference[1],
        leg_px: px[0] + px[1],
        blur_px: f64::NAN,
        swing_contrast: f64::NAN,
        swapped_frames: ev.swapped[a..=b].iter().filter(|&&x| x).count(),
        unsure_frames: ev.unsure[a..=b].iter().filter(|&&x| x).count(),
        bout: None,
        at: s.at,
    }
}

/// The reasons to reject a measured stride; a number that could not be measured (NaN) is no
/// reason.
fn verdict(q: &CycleQuality, kin: &KinematicsConfig, enforce_bouts: bool) -> Vec<Reason> {
    let tol = kin.cycle_segment_tolerance;
    let off = |r: f64| r.is_finite() && (r < 1.0 - tol || r > 1.0 + tol);
    // A hair of slack so that a deviation of exactly the limit (e.g. 3 of 30 frames
    // at 0.1 s) is not rejected by rounding.
    let eps = 1e-9;
    let defocused =
        kin.cycle_max_blur_share > 0.0 && q.blur_px > kin.cycle_max_blur_share * q.leg_px;
    [
        (
            Reason::StrideTime,
            q.stride_deviation > kin.cycle_max_stride_deviation + eps,
        ),
        (
            Reason::FilledGap,
            q.max_filled_s > kin.cycle_max_filled_s + eps,
        ),
        (
            Reason::LowLikelihood,
            q.mean_likelihood < kin.cycle_min_likelihood,
        ),
        (
            Reason::SegmentLength,
            off(q.thigh_ratio) || off(q.shank_ratio),
        ),
        (
            Reason::Swap,
            q.unsure_frames as f64
                > kin.cycle_max_swapped_share * (q.last_frame - q.first_frame + 1) as f64 + eps,
        ),
        (Reason::CrossesBout, enforce_bouts && q.bout.is_none()),
        (Reason::SmallSubject, q.leg_px < kin.cycle_min_leg_px),
        (Reason::Blurred, defocused),
        // Out of focus, every outline is weak and the ratio says little: the defocus is
        // the reason.
        (
            Reason::MotionBlurred,
            q.swing_contrast < kin.cycle_min_swing_contrast && !defocused,
        ),
    ]
    .into_iter()
    .filter_map(|(r, bad)| bad.then_some(r))
    .collect()
}

/// The accepted strides.
pub fn accepted(q: &[CycleQuality]) -> Vec<Stride> {
    q.iter()
        .filter(|c| c.accepted)
        .map(|c| c.stride())
        .collect()
}

/// Accepted and rejected strides per side.
pub fn counts(q: &[CycleQuality]) -> (SideCounts, SideCounts) {
    let mut acc = SideCounts::default();
    let mut rej = SideCounts::default();
    for c in q {
        let bucket = if c.accepted { &mut acc } else { &mut rej };
        match c.side {
            Side::Left => bucket.left += 1,
            Side::Right => bucket.right += 1,
        }
    }
    (acc, rej)
}

/// Whether a step between heel strikes at input frames `from` and `to` counts for the
/// spatiotemporal parameters: not when every stride around it was rejected, and, where bouts
/// are enforced, only inside one bout.
pub fn step_ok(
    q: &[CycleQuality],
    ev_bouts: &[Bout],
    enforce: bool,
    from: usize,
    to: usize,
) -> bool {
    if enforce {
        match bout_of(ev_bouts, from) {
            Some(b) if bout_of(ev_bouts, to) == Some(b) => {}
            _ => return false,
        }
    }
    let mut around = q
        .iter()
        .filter(|c| c.first_frame <= from && to <= c.last_frame)
        .peekable();
    around.peek().is_none() || around.any(|c| c.accepted)
}

mod swing_contrast;
pub(crate) mod warn;

#[cfg(test)]
mod tests;
