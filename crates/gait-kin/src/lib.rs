//! Keypoint post-processing, sagittal joint angles, gait events and cycles.
//!
//! [`analyse`] runs the whole chain on a [`PoseSequence`]: likelihood gate -> left/right swap
//! correction -> gap filling -> low-pass filter -> walking direction -> angles -> events ->
//! cycles -> spatiotemporal parameters. Each step is a trait ([`SwapCorrector`], [`GapFiller`],
//! [`Smoother`], [`EventDetector`]) so a researcher can replace it; [`analyse_with`] takes them.
//! [`write_outputs`] writes the CSV files of `gait kin`.

pub mod angles;
pub mod butterworth;
pub mod config;
pub mod cycles;
pub mod direction;
pub mod events;
pub mod likelihood;
pub mod one_euro;
mod output;
pub mod smooth;
pub mod spatiotemporal;
pub mod spline;
pub mod swap;
pub mod tracks;

use std::path::PathBuf;

use gait_core::{PoseSequence, StageError};
use serde::Serialize;

pub use angles::Angles;
pub use config::{FilterKind, GapFillKind, KinematicsConfig, PostprocessConfig, Side};
pub use cycles::{CycleCurve, Stride};
pub use direction::Direction;
pub use events::{Event, EventDetector, EventKind, ZeniRefined};
pub use likelihood::{KeypointGate, LikelihoodThreshold};
pub use output::write_outputs;
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
    /// Frames whose left/right leg labels were exchanged and corrected.
    pub swapped_frames: usize,
    /// Per-frame walking direction.
    #[serde(skip)]
    pub direction: Vec<Direction>,
    /// Frames walking right / left / unknown.
    pub direction_counts: [usize; 3],
    /// The leg nearer the camera in most frames with a known direction.
    pub near_side: Option<Side>,
    #[serde(skip)]
    pub angles: Angles,
    pub events: Vec<Event>,
    /// True when the events came from `kinematics.events_csv`.
    pub events_from_file: bool,
    pub strides: Vec<Stride>,
    pub cycles: Vec<CycleCurve>,
    pub spatiotemporal: Vec<Param>,
    /// Pixels per cm when a scale was configured.
    pub px_per_cm: Option<f64>,
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
    let mut warnings = Vec::new();
    let mut t = Tracks::from_sequence(seq);
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

    let swapped = steps
        .swap
        .map(|s| s.correct(&mut t))
        .unwrap_or_else(|| vec![false; n]);
    let swapped_frames = swapped.iter().filter(|&&s| s).count();
    if swapped_frames > 0 {
        warnings.push(format!(
            "left/right leg labels corrected in {swapped_frames} frames"
        ));
    }

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
        for coord in [&mut t.x[j], &mut t.y[j]] {
            smooth::smooth_segments(steps.smoother, coord, fps);
        }
    }

    let dirs = direction::detect(&t);
    let mut counts = [0usize; 3];
    for d in &dirs.per_frame {
        counts[match d {
            Direction::Right => 0,
            Direction::Left => 1,
            Direction::Unknown => 2,
        }] += 1;
    }
    let frontal = dirs.frontal.iter().filter(|&&f| f).count();
    if frontal > 0 {
        warnings.push(format!(
            "{frontal} frames look like a front or back view (hips far apart): no sagittal angles there"
        ));
    }
    if n > 0 && counts[2] == n {
        warnings
            .push("walking direction unknown in every frame: no angles, events or cycles".into());
    }
    let near_side = match counts[0].cmp(&counts[1]) {
        std::cmp::Ordering::Greater => Direction::Right.near_side(),
        std::cmp::Ordering::Less => Direction::Left.near_side(),
        std::cmp::Ordering::Equal => None,
    };
    let angles = angles::compute(&t, &dirs.per_frame);
    // Without a toe there is no foot segment: say so instead of leaving the
    // reader to wonder why the ankle column is empty (OpenPose COCO-18 has no feet).
    for side in ["left", "right"] {
        let toe = format!("{side}_toe");
        let seen = t
            .names
            .iter()
            .position(|name| *name == toe)
            .is_some_and(|j| t.x[j].iter().any(|v| v.is_finite()));
        if n > 0 && !seen {
            warnings.push(format!(
                "no {toe} keypoint in any frame (the pose model may have no feet, e.g. OpenPose COCO-18): the {side} ankle angle is unavailable"
            ));
        }
    }

    let (events, from_file) = match &kin.events_csv {
        Some(p) => (events::read_csv(p)?, true),
        None => (steps.events.detect(&t, &dirs.per_frame), false),
    };
    for side in Side::BOTH {
        if !events
            .iter()
            .any(|e| e.side == side && e.event == EventKind::HeelStrike)
        {
            warnings.push(format!("no heel strike found for the {} leg", side.name()));
        }
    }
    let strides = cycles::strides(&events, fps, kin.min_stride_s, kin.max_stride_s);
    let cycles = cycles::curves(
        &angles,
        t.first_frame,
        &strides,
        kin.min_cycles,
        &mut warnings,
    );
    let spatiotemporal = spatiotemporal::compute(&t, &events, &strides, kin);
    let px_per_cm = spatiotemporal::px_per_cm(&t, kin);
    if (kin.subject_height_m.is_some() || kin.known_length_px.is_some()) && px_per_cm.is_none() {
        warnings.push("no leg length could be measured: lengths stay in pixels".into());
    }
    Ok(KinResult {
        fps,
        first_frame: t.first_frame,
        n_frames: n,
        swapped_frames,
        direction: dirs.per_frame,
        direction_counts: counts,
        near_side,
        angles,
        events,
        events_from_file: from_file,
        strides,
        cycles,
        spatiotemporal,
        px_per_cm,
        warnings,
        filtered: t.to_sequence(),
    })
}
