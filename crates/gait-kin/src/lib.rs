//! Keypoint post-processing, sagittal joint angles, gait events and cycles.
//!
//! [`analyse`] runs the whole chain on a [`PoseSequence`]: likelihood gate -> lower legs dropped
//! where both legs are drawn on one ([`collapse`]) -> left/right swap correction -> gap filling
//! -> low-pass filter -> walking direction -> angles -> walking bouts -> events (kept inside
//! bouts) -> candidate strides -> per-stride quality control -> cycles and spatiotemporal
//! parameters of the accepted strides. Each step is a trait
//! ([`SwapCorrector`], [`GapFiller`], [`Smoother`], [`EventDetector`]) so a researcher can
//! replace it; [`analyse_with`] takes them. [`write_outputs`] writes the CSV files of `gait kin`.
//!
//! Bouts ([`bouts`]) are the frames of steady walking in one direction across the view: a real
//! video also shows the subject entering, standing, turning, hidden or leaving, and perhaps
//! someone else afterwards. Quality control ([`quality`]) then keeps or rejects each stride
//! (heel strike to the next of the same foot) with its reasons; only accepted strides enter
//! the mean curves and the spatiotemporal parameters. Events from `kinematics.events_csv` are
//! the user's and are kept as given, unless `kinematics.bouts` is set too.
//!
//! `kinematics.corrections` names a [`corrections`] file a person or a script wrote: leg labels
//! swapped by hand (after the automatic swap correction), keypoints set by hand (before gap
//! filling), events added or removed (after the bout filter) and frames excluded from events
//! and cycles.

pub mod angles;
pub mod bouts;
pub mod butterworth;
pub mod collapse;
pub mod config;
pub mod corrections;
pub mod cycles;
pub mod direction;
pub mod events;
pub mod likelihood;
pub mod one_euro;
mod output;
pub mod quality;
pub mod smooth;
pub mod spatiotemporal;
pub mod spline;
pub mod swap;
#[cfg(test)]
mod testing;
pub mod tracks;

use std::path::PathBuf;

use gait_core::{PoseSequence, StageError};
use serde::Serialize;

pub use angles::Angles;
pub use bouts::Bout;
pub use collapse::CollapseRule;
pub use config::{FilterKind, GapFillKind, KinematicsConfig, PostprocessConfig, Side};
pub use corrections::{
    Corrections, CorrectionsSummary, EventAction, EventEdit, FrameRange, KeypointEdit,
};
pub use cycles::{CycleCurve, Stride};
pub use direction::Direction;
pub use events::{Event, EventDetector, EventKind, ZeniRefined};
pub use likelihood::{KeypointGate, LikelihoodThreshold};
pub use output::write_outputs;
pub use quality::{CycleQuality, Reason, SideCounts};
pub use smooth::Smoother;
pub use spatiotemporal::Param;
pub use spline::GapFiller;
pub use swap::{ContinuitySwap, SwapCorrector};
pub use tracks::Tracks;

#[derive(Debug, thiserror::Error)]
pub enum KinError {
    #[error("invalid configuration: {0}")]
    Config(String),
    #[error("bad input: {0}")]
    BadInput(String),
    #[error("events file {path}: {reason}")]
    EventsCsv { path: PathBuf, reason: String },
    /// A corrections file that cannot be parsed or does not fit the keypoints; `message` is one
    /// line naming the entry.
    #[error("{}: {message}", path.display())]
    Corrections { path: PathBuf, message: String },
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: std::io::Error,
    },
}

impl From<KinError> for StageError {
    fn from(e: KinError) -> Self {
        match e {
            KinError::Io { context, source } => StageError::Io { context, source },
            other => StageError::BadInput(other.to_string()),
        }
    }
}

/// Everything [`analyse`] found. Per-frame series are skipped when serialised (run.json gets a
/// summary); write them with [`write_outputs`].
#[derive(Debug, Clone, Serialize)]
pub struct KinResult {
    pub fps: f64,
    /// Input frame number of the first row of the per-frame series.
    pub first_frame: usize,
    pub n_frames: usize,
    /// Frames whose left/right leg labels the automatic swap correction exchanged (not counting
    /// frames a person swapped in the corrections).
    pub swapped_frames: usize,
    /// Frames whose lower-leg keypoints were dropped because both legs were drawn on one
    /// (see [`collapse`]); gap filling bridges them.
    pub collapsed_frames: usize,
    /// Per-frame walking direction.
    #[serde(skip)]
    pub direction: Vec<Direction>,
    /// Frames walking right / left / unknown.
    pub direction_counts: [usize; 3],
    /// The leg nearer the camera in most frames with a known direction.
    pub near_side: Option<Side>,
    #[serde(skip)]
    pub angles: Angles,
    /// Frames of steady walking; detected events outside every bout are dropped.
    pub bouts: Vec<Bout>,
    /// Gait events inside the bouts (all of them when read from `kinematics.events_csv`),
    /// with the corrections' events added and removed and none in excluded frames.
    pub events: Vec<Event>,
    /// True when the events came from `kinematics.events_csv`.
    pub events_from_file: bool,
    /// Candidate strides: consecutive heel strikes of a foot within the stride time limits.
    pub strides: Vec<Stride>,
    /// The quality verdict on each candidate stride, in the order of `strides`.
    pub cycle_quality: Vec<CycleQuality>,
    pub cycles_accepted: SideCounts,
    pub cycles_rejected: SideCounts,
    /// Mean curves over the accepted strides.
    pub cycles: Vec<CycleCurve>,
    pub spatiotemporal: Vec<Param>,
    /// Pixels per cm when a scale was configured.
    pub px_per_cm: Option<f64>,
    /// What was applied from `kinematics.corrections`, when set.
    pub corrections: Option<CorrectionsSummary>,
    pub warnings: Vec<String>,
    /// The cleaned keypoints on the dense timeline (written as keypoints_filtered.csv).
    #[serde(skip)]
    pub filtered: PoseSequence,
}

/// The replaceable steps of [`analyse_with`].
pub struct Steps<'a> {
    pub gate: &'a dyn KeypointGate,
    pub swap: Option<&'a dyn SwapCorrector>,
    pub gap_filler: &'a dyn GapFiller,
    pub smoother: &'a dyn Smoother,
    pub events: &'a dyn EventDetector,
}

/// Runs the configured chain (see the crate docs).
pub fn analyse(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
) -> Result<KinResult, KinError> {
    let gate = LikelihoodThreshold(post.likelihood_threshold);
    let swap = ContinuitySwap::default();
    let gap: Box<dyn GapFiller> = match post.gap_fill {
        GapFillKind::CubicSpline => Box::new(spline::CubicSplineFill),
        GapFillKind::Linear => Box::new(spline::LinearFill),
        GapFillKind::None => Box::new(spline::NoFill),
    };
    let smoother: Box<dyn Smoother> = match post.filter {
        FilterKind::Butterworth => Box::new(butterworth::Butterworth {
            order: post.butterworth_order,
            cutoff_hz: post.cutoff_hz,
        }),
        FilterKind::OneEuro => Box::new(one_euro::OneEuro {
            min_cutoff_hz: post.one_euro_min_cutoff_hz,
            beta: post.one_euro_beta,
            d_cutoff_hz: post.one_euro_d_cutoff_hz,
        }),
        FilterKind::None => Box::new(smooth::Identity),
    };
    let detector = ZeniRefined {
        min_stride_s: kin.min_stride_s,
        ..ZeniRefined::default()
    };
    let steps = Steps {
        gate: &gate,
        swap: post.swap_correction.then_some(&swap as &dyn SwapCorrector),
        gap_filler: gap.as_ref(),
        smoother: smoother.as_ref(),
        events: &detector,
    };
    analyse_with(seq, post, kin, &steps)
}

/// [`analyse`] with caller-chosen steps.
pub fn analyse_with(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
    steps: &Steps,
) -> Result<KinResult, KinError> {
    check_input(seq, post, kin)?;
    let fps = seq.fps;
    let mut warnings = Vec::new();
    let corr = match &kin.corrections {
        Some(p) => {
            let (c, sha) = corrections::load(p, seq)?;
            let summary = corrections::summary(&c, p, sha);
            warnings.push(corrections::warning(&summary));
            Some((c, p.as_path(), summary))
        }
        None => None,
    };
    let no_corrections = Corrections::default();
    let fixes = corr.as_ref().map_or(&no_corrections, |c| &c.0);
    let c = clean(seq, post, steps, fixes, &mut warnings);
    let (t, n) = (&c.clean, c.clean.len());
    let dirs = directions(t, &mut warnings);
    let angles = angles::compute(t, &dirs.per_frame);
    warn_missing_toes(t, &mut warnings);

    let frames = bouts::Frames {
        clean: t,
        gated: &c.gated,
        dirs: &dirs.per_frame,
        max_gap: post.max_gap(fps),
    };
    let bouts = bouts::find(&frames, kin);
    // Detected events count only where the subject walks; a user's events file says itself
    // where that is, unless bouts are given by hand too.
    let enforce_bouts = kin.events_csv.is_none() || kin.bouts.is_some();
    if n > 0 && bouts.is_empty() {
        warnings.push(if enforce_bouts {
            "no walking bout found: no events or cycles".into()
        } else {
            "no walking bout found: the events of events_csv are used as given".into()
        });
    }
    let (mut events, from_file) = match &kin.events_csv {
        Some(p) => (events::read_csv(p)?, true),
        None => (steps.events.detect(t, &dirs.per_frame), false),
    };
    if enforce_bouts {
        events.retain(|e| bouts::bout_of(&bouts, e.frame).is_some());
    }
    if let Some((c, path, _)) = &corr {
        corrections::apply_events(c, &mut events, path)?;
    }
    for side in Side::BOTH {
        if !events
            .iter()
            .any(|e| e.side == side && e.event == EventKind::HeelStrike)
        {
            warnings.push(format!("no heel strike found for the {} leg", side.name()));
        }
    }
    let strides = cycles::strides(&events, fps, kin.min_stride_s, kin.max_stride_s);
    let evidence = quality::Evidence {
        clean: t,
        gated: &c.gated,
        raw_likelihood: &c.raw_likelihood,
        swapped: &c.swapped,
        bouts: &bouts,
        enforce_bouts,
        excluded: &fixes.exclude,
    };
    let cycle_quality = quality::assess(&evidence, &strides, kin);
    warnings.extend(quality::warnings(&cycle_quality, kin));
    let (cycles_accepted, cycles_rejected) = quality::counts(&cycle_quality);
    let accepted = quality::accepted(&cycle_quality);
    let cycles = cycles::curves(
        &angles,
        t.first_frame,
        &accepted,
        kin.min_cycles,
        &mut warnings,
    );
    let step_ok = |a: usize, b: usize| {
        !corrections::excluded_overlap(&fixes.exclude, a, b)
            && quality::step_ok(&cycle_quality, &bouts, enforce_bouts, a, b)
    };
    let spatiotemporal = spatiotemporal::compute(t, &events, &accepted, &step_ok, kin);
    let px_per_cm = spatiotemporal::px_per_cm(t, kin);
    if (kin.subject_height_m.is_some() || kin.known_length_px.is_some()) && px_per_cm.is_none() {
        warnings.push("no leg length could be measured: lengths stay in pixels".into());
    }
    let counts = dirs.counts();
    Ok(KinResult {
        fps,
        first_frame: t.first_frame,
        n_frames: n,
        swapped_frames: c.swapped.iter().filter(|&&s| s).count(),
        collapsed_frames: c.collapsed,
        direction_counts: counts,
        near_side: dirs.near_side(),
        direction: dirs.per_frame,
        angles,
        bouts,
        events,
        events_from_file: from_file,
        strides,
        cycle_quality,
        cycles_accepted,
        cycles_rejected,
        cycles,
        spatiotemporal,
        px_per_cm,
        corrections: corr.map(|c| c.2),
        warnings,
        filtered: t.to_sequence(),
    })
}

fn check_input(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
) -> Result<(), KinError> {
    let fps = seq.fps;
    if !(fps.is_finite() && fps > 0.0) {
        return Err(KinError::BadInput(format!(
            "frame rate {fps} is not a positive number"
        )));
    }
    post.validate(fps)?;
    kin.validate()?;
    if seq.frames.len() != seq.poses.len() {
        return Err(KinError::BadInput(
            "frames and poses differ in length".into(),
        ));
    }
    if let (Some(lo), Some(hi)) = (seq.frames.iter().min(), seq.frames.iter().max())
        && hi - lo > 10 * seq.frames.len() + 10_000
    {
        return Err(KinError::BadInput(format!(
            "frame numbers {lo}..{hi} are too sparse for {} poses",
            seq.len()
        )));
    }
    Ok(())
}

/// The keypoints after cleaning, plus what the quality rules need from before it.
struct Cleaned {
    /// Gated, swap-corrected, gap-filled and smoothed.
    clean: Tracks,
    /// Gated and swap-corrected, before gap filling: what the pose model really gave.
    gated: Tracks,
    /// The model's likelihoods before the gate, leg labels swap-corrected.
    raw_likelihood: Vec<Vec<f64>>,
    /// Frames the automatic swap correction exchanged, outside the ranges a person swapped.
    swapped: Vec<bool>,
    /// Frames whose lower legs were dropped as collapsed.
    collapsed: usize,
}

/// Likelihood gate -> collapsed frames dropped -> swap correction -> the corrections' swaps and
/// keypoints -> gap filling -> smoothing (collapsed frames filled after it).
fn clean(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    steps: &Steps,
    fixes: &Corrections,
    warnings: &mut Vec<String>,
) -> Cleaned {
    let fps = seq.fps;
    let mut t = Tracks::from_sequence(seq);
    let mut raw = t.clone();
    let n = t.len();
    if n == 0 {
        warnings.push("no frames in the input".into());
    }
    steps.gate.apply(&mut t);
    if n > 0 && t.x.iter().all(|x| x.iter().all(|v| !v.is_finite())) {
        warnings.push(format!(
            "no keypoint with likelihood >= {} in any frame",
            post.likelihood_threshold
        ));
    }

    // Frames with both legs drawn on one carry no labels and mislead the swap correction; they
    // are part of the label cleaning and go with it.
    let collapsed = match steps.swap {
        Some(_) => collapse::CollapseRule::default().find(&t),
        None => vec![false; n],
    };
    let collapsed_frames = collapsed.iter().filter(|&&c| c).count();
    if collapsed_frames > 0 {
        collapse::drop_frames(&mut t, &collapsed);
        warnings.push(format!(
            "lower-leg keypoints dropped in {collapsed_frames} frames where both legs were drawn on one"
        ));
    }
    let mut swapped = steps
        .swap
        .map(|s| s.correct(&mut t))
        .unwrap_or_else(|| vec![false; n]);
    for i in (0..n).filter(|&i| swapped[i]) {
        swap::swap_frame(&mut raw, i);
    }
    // A person's swaps come after the automatic correction, which therefore cannot undo them;
    // their frames stop counting as swapped (a confirmed fix, see `apply_swaps`).
    corrections::apply_swaps(fixes, &mut t, &mut raw, &mut swapped);
    let swapped_frames = swapped.iter().filter(|&&s| s).count();
    if swapped_frames > 0 {
        warnings.push(format!(
            "left/right leg labels corrected in {swapped_frames} frames"
        ));
    }
    // A person's keypoints are in the labels they see in the output, so they come after both
    // label corrections; before gap filling and smoothing, as if the pose model had given them.
    corrections::apply_keypoints(fixes, &mut t, &mut raw);
    let gated = t.clone();

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
    Cleaned {
        clean: t,
        gated,
        raw_likelihood: raw.likelihood,
        swapped,
        collapsed: collapsed_frames,
    }
}

/// Per-frame direction, with warnings for front views and no direction at all.
fn directions(t: &Tracks, warnings: &mut Vec<String>) -> direction::Directions {
    let dirs = direction::detect(t);
    let frontal = dirs.frontal.iter().filter(|&&f| f).count();
    if frontal > 0 {
        warnings.push(format!(
            "{frontal} frames look like a front or back view (hips far apart): no sagittal angles there"
        ));
    }
    let n = t.len();
    if n > 0 && dirs.counts()[2] == n {
        warnings
            .push("walking direction unknown in every frame: no angles, events or cycles".into());
    }
    dirs
}

/// Without a toe there is no foot segment: say so instead of leaving the reader to wonder why
/// the ankle column is empty (OpenPose COCO-18 has no feet).
fn warn_missing_toes(t: &Tracks, warnings: &mut Vec<String>) {
    for side in ["left", "right"] {
        let toe = format!("{side}_toe");
        let seen = t
            .names
            .iter()
            .position(|name| *name == toe)
            .is_some_and(|j| t.x[j].iter().any(|v| v.is_finite()));
        if !t.is_empty() && !seen {
            warnings.push(format!(
                "no {toe} keypoint in any frame (the pose model may have no feet, e.g. OpenPose COCO-18): the {side} ankle angle is unavailable"
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Walk 3 s, stand 2 s, walk 3 s: two bouts, events only inside them, and no accepted
    /// stride across the standing.
    #[test]
    fn events_and_cycles_stay_inside_the_bouts() {
        let pos = |i: usize| {
            let moving = i.min(90) + i.saturating_sub(150);
            100.0 + 400.0 * moving as f64 / 30.0
        };
        let seq = testing::walker(30.0, 240, pos).to_sequence();
        let kin = KinematicsConfig::default();
        let r = analyse(&seq, &PostprocessConfig::default(), &kin).unwrap();
        assert_eq!(r.bouts.len(), 2, "{:?}", r.bouts);
        assert!(
            r.bouts[0].last < 100 && r.bouts[1].first > 140,
            "{:?}",
            r.bouts
        );
        assert!(!r.events.is_empty());
        assert!(
            r.events
                .iter()
                .all(|e| bouts::bout_of(&r.bouts, e.frame).is_some())
        );
        for q in &r.cycle_quality {
            assert_eq!(q.accepted, q.bout.is_some(), "{q:?}");
        }
        assert!(
            r.cycles_accepted.left >= 2 && r.cycles_accepted.right >= 2,
            "{r:?}"
        );
        assert_eq!(r.cycles.len(), 6);

        // Standing only: no bout, no events, and the warning says so.
        let still = testing::walker(30.0, 90, |_| 500.0).to_sequence();
        let r = analyse(&still, &PostprocessConfig::default(), &kin).unwrap();
        assert!(r.bouts.is_empty() && r.events.is_empty() && r.cycle_quality.is_empty());
        assert!(
            r.warnings
                .iter()
                .any(|w| w == "no walking bout found: no events or cycles"),
            "{:?}",
            r.warnings
        );
    }

    /// The pose model drawing both legs on one leg right at the right foot's toe-offs (where
    /// BlazePose did it on the sample): the frames are dropped and filled, no label is
    /// "corrected", and every event stays within a frame of where it was.
    #[test]
    fn collapses_at_toe_off_leave_the_events() {
        let clean = testing::walker(30.0, 180, |i| 100.0 + 13.0 * i as f64);
        let (post, kin) = (PostprocessConfig::default(), KinematicsConfig::default());
        let before = analyse(&clean.to_sequence(), &post, &kin).unwrap();
        let toe_offs: Vec<usize> = before
            .events
            .iter()
            .filter(|e| e.side == Side::Right && e.event == EventKind::ToeOff)
            .map(|e| e.frame)
            .collect();
        assert!(toe_offs.len() >= 3, "{:?}", before.events);
        let mut t = clean.clone();
        for &f in &toe_offs {
            for p in tracks::LOWER_LEG {
                let (l, r) = (
                    t.leg_index(Side::Left, p).unwrap(),
                    t.leg_index(Side::Right, p).unwrap(),
                );
                t.x[r][f] = t.x[l][f] + 6.0;
                t.y[r][f] = t.y[l][f] - 4.0;
            }
        }
        let after = analyse(&t.to_sequence(), &post, &kin).unwrap();
        assert_eq!(after.collapsed_frames, toe_offs.len());
        assert_eq!(after.swapped_frames, 0);
        assert_eq!(
            after.events.len(),
            before.events.len(),
            "{:?}",
            after.events
        );
        for (a, b) in before.events.iter().zip(&after.events) {
            assert!(
                a.side == b.side && a.event == b.event && a.frame.abs_diff(b.frame) <= 1,
                "{a:?} vs {b:?}"
            );
        }
        assert_eq!(after.cycles_accepted, before.cycles_accepted);
    }

    /// Writes `text` as a corrections file in `dir` and returns the config that applies it.
    fn with_corrections(dir: &std::path::Path, text: &str) -> KinematicsConfig {
        let p = dir.join("corrections.toml");
        std::fs::write(&p, text).unwrap();
        KinematicsConfig {
            corrections: Some(p),
            ..Default::default()
        }
    }

    /// No smoothing: every cleaned sample of a fully seen frame is the input's own.
    fn unsmoothed() -> PostprocessConfig {
        PostprocessConfig {
            filter: FilterKind::None,
            ..Default::default()
        }
    }

    /// The leg keypoint indices `[left, right]` of each leg part.
    fn leg_pairs(t: &Tracks) -> Vec<[usize; 2]> {
        tracks::LEG
            .iter()
            .map(|p| {
                [
                    t.leg_index(Side::Left, p).unwrap(),
                    t.leg_index(Side::Right, p).unwrap(),
                ]
            })
            .collect()
    }

    /// A person's swap comes after the automatic correction, which cannot undo it, and does not
    /// count against the cycle quality; where the automatic correction had exchanged the labels
    /// a person's swap gives the model's labels back, and those frames no longer count either.
    #[test]
    fn swaps_by_hand_come_last_and_do_not_reject_strides() {
        let walker = testing::walker(30.0, 180, |i| 100.0 + 13.0 * i as f64);
        let dir = tempfile::tempdir().unwrap();
        let kin = with_corrections(dir.path(), "[[swap]]\nfirst = 60\nlast = 67\n");
        let post = unsmoothed();
        let r = analyse(&walker.to_sequence(), &post, &kin).unwrap();
        let f = Tracks::from_sequence(&r.filtered);
        for [l, rt] in leg_pairs(&walker) {
            for i in 0..180 {
                let (a, b) = if (60..=67).contains(&i) {
                    (rt, l)
                } else {
                    (l, rt)
                };
                assert_eq!(f.at(a, i), walker.at(l, i), "frame {i}");
                assert_eq!(f.at(b, i), walker.at(rt, i), "frame {i}");
            }
        }
        assert_eq!(r.swapped_frames, 0);
        let over: Vec<&CycleQuality> = r
            .cycle_quality
            .iter()
            .filter(|q| q.first_frame <= 67 && 60 <= q.last_frame)
            .collect();
        assert!(!over.is_empty());
        // 8 swapped frames in a 34-frame stride would be over cycle_max_swapped_share (0.1).
        assert!(
            over.iter()
                .all(|q| q.swapped_frames == 0 && !q.reasons.contains(&Reason::Swap)),
            "{over:?}"
        );
        let s = r.corrections.as_ref().unwrap();
        assert_eq!(
            (s.swaps, s.swapped_frames, s.path.clone()),
            (1, 8, dir.path().join("corrections.toml"))
        );
        assert_eq!(
            r.warnings[0],
            format!(
                "corrections applied from {}: 1 swap (8 frames)",
                s.path.display()
            )
        );

        // The model exchanged the labels over 60-67: the automatic correction undoes it and the
        // strides over it are rejected for swaps; a person who says the model was right gets
        // the model's labels and accepted strides.
        let mut exchanged = walker.clone();
        for i in 60..=67 {
            swap::swap_frame(&mut exchanged, i);
        }
        let seq = exchanged.to_sequence();
        let auto = analyse(&seq, &post, &KinematicsConfig::default()).unwrap();
        assert_eq!(auto.swapped_frames, 8);
        assert!(
            auto.cycle_quality
                .iter()
                .any(|q| q.reasons.contains(&Reason::Swap))
        );
        let fixed = analyse(&seq, &post, &kin).unwrap();
        assert_eq!(fixed.swapped_frames, 0);
        assert!(
            fixed
                .cycle_quality
                .iter()
                .all(|q| !q.reasons.contains(&Reason::Swap))
        );
        let f = Tracks::from_sequence(&fixed.filtered);
        for [l, rt] in leg_pairs(&walker) {
            for i in 60..=67 {
                assert_eq!(
                    (f.at(l, i), f.at(rt, i)),
                    (exchanged.at(l, i), exchanged.at(rt, i))
                );
            }
        }
    }

    /// A keypoint set by hand is in the output's labels, with likelihood 1, before gap filling
    /// (a gap of the model's is filled around it) and smoothing.
    #[test]
    fn keypoints_by_hand_replace_the_models() {
        let mut walker = testing::walker(30.0, 120, |i| 100.0 + 13.0 * i as f64);
        let ankle = walker.index("right_ankle").unwrap();
        for i in 48..=52 {
            walker.likelihood[ankle][i] = 0.1;
        }
        let dir = tempfile::tempdir().unwrap();
        let kin = with_corrections(
            dir.path(),
            "[[keypoint]]\nframe = 50\nname = \"right_ankle\"\nx = 812.5\ny = 601.0\n",
        );
        let r = analyse(&walker.to_sequence(), &unsmoothed(), &kin).unwrap();
        let f = Tracks::from_sequence(&r.filtered);
        assert_eq!(f.at(ankle, 50), Some((812.5, 601.0)));
        assert_eq!(f.likelihood[ankle][50], 1.0);
        // The gated frames either side are filled, now through the person's point.
        let before = analyse(
            &walker.to_sequence(),
            &unsmoothed(),
            &KinematicsConfig::default(),
        )
        .unwrap();
        let b = Tracks::from_sequence(&before.filtered);
        assert!(f.at(ankle, 49).is_some() && f.at(ankle, 49) != b.at(ankle, 49));
        assert_eq!(f.at(ankle, 20), b.at(ankle, 20));
        assert_eq!(r.corrections.as_ref().unwrap().keypoints, 1);
    }

    /// Walk 3 s, then stand: events removed, added (also where nobody walks) and excluded
    /// exactly as written, and strides over excluded frames rejected.
    #[test]
    fn events_by_hand_and_excluded_frames() {
        let pos = |i: usize| 100.0 + 400.0 * i.min(150) as f64 / 30.0;
        let seq = testing::walker(30.0, 200, pos).to_sequence();
        let post = PostprocessConfig::default();
        let before = analyse(&seq, &post, &KinematicsConfig::default()).unwrap();
        let hs = |r: &KinResult, side: Side| -> Vec<usize> {
            r.events
                .iter()
                .filter(|e| e.side == side && e.event == EventKind::HeelStrike)
                .map(|e| e.frame)
                .collect()
        };
        let left = hs(&before, Side::Left);
        assert!(left.len() >= 4, "{:?}", before.events);
        assert!(before.bouts.iter().all(|b| !b.contains(190)));
        // Remove the second left heel strike (named 2 frames late), exclude the third one's
        // frame, add a right toe-off at 190 where she stands.
        let (second, third) = (left[1], left[2]);
        let text = format!(
            "[[event]]\nside = \"left\"\nkind = \"heel_strike\"\nframe = {}\naction = \"remove\"\n\
             [[event]]\nside = \"right\"\nkind = \"toe_off\"\nframe = 190\naction = \"add\"\n\
             [[exclude]]\nfirst = {third}\nlast = {third}\n",
            second + 2
        );
        let dir = tempfile::tempdir().unwrap();
        let kin = with_corrections(dir.path(), &text);
        let r = analyse(&seq, &post, &kin).unwrap();
        let mut expect: Vec<Event> = before
            .events
            .iter()
            .copied()
            .filter(|e| {
                !(e.side == Side::Left && e.event == EventKind::HeelStrike && e.frame == second)
                    && e.frame != third
            })
            .collect();
        expect.push(Event {
            side: Side::Right,
            event: EventKind::ToeOff,
            frame: 190,
        });
        events::sort(&mut expect);
        assert_eq!(r.events, expect);
        // The left strides now run first -> fourth heel strike (too long: no candidate) and
        // fourth -> fifth; every stride over the excluded frame is rejected for it.
        for q in &r.cycle_quality {
            let over = (q.first_frame..=q.last_frame).contains(&third);
            assert_eq!(q.reasons.contains(&Reason::Excluded), over, "{q:?}");
        }
        assert!(
            r.cycle_quality
                .iter()
                .any(|q| q.reasons.contains(&Reason::Excluded))
        );
        assert!(
            !r.cycle_quality
                .iter()
                .any(|q| q.side == Side::Left && q.first_frame == second)
        );

        // A removal that finds nothing stops the analysis, naming the file and the entry.
        let kin = with_corrections(
            dir.path(),
            "[[event]]\nside = \"left\"\nkind = \"toe_off\"\nframe = 195\naction = \"remove\"\n",
        );
        let e = analyse(&seq, &post, &kin).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "{}: [[event]] #1 (remove left toe_off at frame 195): no left toe_off within 3 frames to remove",
                dir.path().join("corrections.toml").display()
            )),
            "{e}"
        );
        // So does an invalid file.
        let kin = with_corrections(dir.path(), "[[swap]]\nfirst = 150\nlast = 250\n");
        let e = analyse(&seq, &post, &kin).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "[[swap]] #1 (frames 150-250): frame 250 is outside the run (frames 0-199)"
            ),
            "{e}"
        );
    }
}
