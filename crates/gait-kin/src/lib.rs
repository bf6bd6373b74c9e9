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
mod chain;
mod clean;
pub mod collapse;
pub mod config;
pub mod corrections;
pub mod cycles;
pub mod direction;
mod event;
pub mod events;
mod events_csv;
mod feet;
mod foot_shape;
pub mod frontal;
pub mod glitch;
pub mod ground;
mod input_check;
pub mod likelihood;
pub mod margins;
pub mod one_euro;
mod output;
pub mod peaks;
pub mod quality;
pub mod smooth;
pub mod spatiotemporal;
pub mod spikes;
pub mod spline;
mod stance_check;
mod steps;
pub mod swap;
#[cfg(test)]
mod testing;
pub mod tracks;
pub mod view;
pub mod walk_angle;

use std::path::PathBuf;

use gait_core::{PoseSequence, StageError};
use serde::Serialize;

pub use angles::Angles;
pub use bouts::Bout;
pub use collapse::CollapseRule;
pub use config::{
    Amputation, FeetContrast, FilterKind, GapFillKind, KinematicsConfig, PostprocessConfig, Side,
};
pub use corrections::{
    Corrections, CorrectionsSummary, EventAction, EventEdit, FrameRange, KeypointEdit,
};
pub use cycles::{CycleCurve, Stride};
pub use direction::Direction;
pub use events::{Event, EventDetector, EventKind, ZeniRefined};
pub use input_check::MAX_FRAME;
use input_check::check_input;
pub use likelihood::{KeypointGate, LikelihoodThreshold};
pub use output::{tables, write_outputs};
pub use quality::{CycleQuality, Reason, SideCounts};
pub use smooth::Smoother;
pub use spatiotemporal::Param;
pub use spline::GapFiller;
pub use swap::{ContinuitySwap, SwapCorrector};
pub use tracks::Tracks;
pub use view::{View, ViewDecision, ViewSetting};

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
    /// How close the event and cycle decisions came to their thresholds.
    pub margins: margins::Margins,
    /// Per side, the keypoints the events were detected on (`heel strike/toe-off`): the heel
    /// and the toe, or the ankle for a model without feet.
    pub event_keypoints: std::collections::BTreeMap<String, String>,
    /// Candidate strides: consecutive heel strikes of a foot within the stride time limits.
    pub strides: Vec<Stride>,
    /// The quality verdict on each candidate stride, in the order of `strides`.
    pub cycle_quality: Vec<CycleQuality>,
    pub cycles_accepted: SideCounts,
    pub cycles_rejected: SideCounts,
    /// Mean curves over the accepted strides.
    pub cycles: Vec<CycleCurve>,
    pub spatiotemporal: Vec<Param>,
    /// How fast the ground moved in the image (a side view's; ground.rs): where it moves, the
    /// strides' lengths are their steps'.
    pub ground: Option<ground::GroundMotion>,
    /// Pixels per cm when a scale was configured.
    pub px_per_cm: Option<f64>,
    /// What was applied from `kinematics.corrections`, when set.
    pub corrections: Option<CorrectionsSummary>,
    pub warnings: Vec<String>,
    /// The cleaned keypoints on the dense timeline (written as keypoints_filtered.csv).
    #[serde(skip)]
    pub filtered: PoseSequence,
    /// The view analysed and how it was decided.
    pub view: ViewDecision,
    /// A front or back view's measures (its events, bouts and cycle verdicts are the fields
    /// above; the sagittal angles and curves are empty then).
    pub frontal: Option<frontal::FrontalResult>,
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
    steps::with_configured(post, kin, |steps| analyse_with(seq, post, kin, steps))
}

/// [`analyse`] with corrections already in memory (a review tool's, before it saves them):
/// `path` is the file they are saved to and `sha256` the hash of the bytes saved, for the
/// summary. The result equals [`analyse`] with `kinematics.corrections` naming that file.
pub fn analyse_corrected(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
    corrections: &Corrections,
    path: &std::path::Path,
    sha256: String,
) -> Result<KinResult, KinError> {
    check_input(seq, post, kin)?;
    corrections.validate_file(seq, path)?;
    let given = Given {
        summary: corrections::summary(corrections, path, sha256),
        corrections: corrections.clone(),
        path: path.to_path_buf(),
    };
    steps::with_configured(post, kin, |steps| {
        run_chain(seq, post, kin, steps, Some(given))
    })
}

/// Corrections read and checked, with their file and summary.
struct Given {
    corrections: Corrections,
    path: PathBuf,
    summary: CorrectionsSummary,
}

/// [`analyse`] with caller-chosen steps.
pub fn analyse_with(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
    steps: &Steps,
) -> Result<KinResult, KinError> {
    check_input(seq, post, kin)?;
    let given = match &kin.corrections {
        Some(p) => {
            let (c, sha) = corrections::load(p, seq)?;
            Some(Given {
                summary: corrections::summary(&c, p, sha),
                corrections: c,
                path: p.clone(),
            })
        }
        None => None,
    };
    run_chain(seq, post, kin, steps, given)
}

/// The chain of [`analyse_with`] on checked input and corrections.
fn run_chain(
    seq: &PoseSequence,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
    steps: &Steps,
    corr: Option<Given>,
) -> Result<KinResult, KinError> {
    let fps = seq.fps;
    let mut warnings = Vec::new();
    if let Some(g) = &corr {
        warnings.push(corrections::warning(&g.summary));
    }
    let no_corrections = Corrections::default();
    let fixes = corr.as_ref().map_or(&no_corrections, |g| &g.corrections);
    let view = decide_view(seq, steps, kin, &mut warnings);
    let c = clean::clean(seq, post, steps, fixes, view.view, &mut warnings);
    let (t, n) = (&c.clean, c.clean.len());
    let frontal_scale = view.view.is_frontal().then(|| frontal::Scale::measure(t));
    let dirs = match frontal_scale {
        Some(_) => direction::Directions::unknown(n),
        None => directions(t, &mut warnings),
    };
    warnings.extend(view::side_disagreement(view.declared, &dirs, t.fps));
    let angles = angles::compute(t, &dirs.per_frame);
    feet::warn_missing_toes(t, &mut warnings);

    let bouts = chain::bouts(&c, &dirs, frontal_scale.as_ref(), view.view, post, kin);
    // Detected events count only where the subject walks; a user's events file says itself
    // where that is, unless bouts are given by hand too.
    let enforce_bouts = kin.events_csv.is_none() || kin.bouts.is_some();
    chain::warn_no_bout(n, &bouts, enforce_bouts, &mut warnings);
    let event_keypoints = feet::event_keypoints(t, kin, &mut warnings);
    let (events, event_margins, from_file) = chain::events(
        t,
        &dirs,
        frontal_scale.as_ref().map(|s| (view.view, s)),
        steps,
        kin,
        (&bouts, enforce_bouts),
        corr.as_ref().map(|g| (&g.corrections, g.path.as_path())),
        &mut warnings,
    )?;
    let strides = cycles::strides(&events, fps, kin.min_stride_s, kin.max_stride_s);
    let evidence = quality::Evidence {
        clean: t,
        gated: &c.gated,
        raw_likelihood: &c.raw_likelihood,
        swapped: &c.swapped,
        unsure: &c.unsure,
        bouts: &bouts,
        enforce_bouts,
        excluded: &fixes.exclude,
        size: frontal_scale.as_ref().map(|s| &s.size[..]),
    };
    quality::warn::small_subject(t, kin, &mut warnings);
    let cycle_quality = quality::assess(&evidence, &strides, kin);
    quality::warn::blurred(&cycle_quality, kin, &mut warnings);
    quality::warn::motion_blurred(&cycle_quality, kin, &mut warnings);
    warnings.extend(quality::warn::per_reason(&cycle_quality, kin));
    let (cycles_accepted, cycles_rejected) = quality::counts(&cycle_quality);
    let accepted = quality::accepted(&cycle_quality);
    let cycles = match frontal_scale {
        Some(_) => Vec::new(),
        None => cycles::curves(
            &angles,
            t.first_frame,
            &accepted,
            kin.min_cycles,
            &mut warnings,
        ),
    };
    let step_ok = |a: usize, b: usize| {
        !corrections::excluded_overlap(&fixes.exclude, a, b)
            && quality::step_ok(&cycle_quality, &bouts, enforce_bouts, a, b)
    };
    let ground = match frontal_scale {
        Some(_) => None,
        None => ground::measure(t, &events),
    };
    let moving = ground.filter(ground::GroundMotion::moves);
    if let Some(g) = moving {
        warnings.push(format!(
            "the ground moves in the image at {:.0} % of the walking speed (a camera following the walker, or a treadmill): stride lengths and speeds are taken from the steps, each measured within one frame",
            100.0 * g.share()
        ));
    }
    let mut spatiotemporal =
        spatiotemporal::compute(t, &events, &accepted, &step_ok, kin, moving.is_some());
    let frontal = frontal_scale.as_ref().map(|scale| {
        // Lengths along the walk are depth in a front view: only the timing holds.
        spatiotemporal.retain(spatiotemporal::Param::is_temporal);
        let found = frontal::Found {
            view: view.view,
            scale,
            events: &events,
            bouts: &bouts,
            quality: &cycle_quality,
            accepted: &accepted,
        };
        frontal::measure(t, &found, kin, &mut warnings)
    });
    let px_per_cm = match frontal {
        Some(_) => None,
        None => spatiotemporal::px_per_cm(t, kin),
    };
    if (kin.subject_height_m.is_some() || kin.known_length_px.is_some())
        && px_per_cm.is_none()
        && frontal.is_none()
    {
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
        event_keypoints,
        ground,
        margins: margins::Margins {
            events: event_margins,
            cycles: margins::cycles(&cycle_quality, kin),
        },
        strides,
        cycle_quality,
        cycles_accepted,
        cycles_rejected,
        cycles,
        spatiotemporal,
        px_per_cm,
        corrections: corr.map(|g| g.summary),
        warnings,
        filtered: t.to_sequence(),
        view,
        frontal,
    })
}

/// The view from the gated keypoints, before any label correction (which depends on it).
fn decide_view(
    seq: &PoseSequence,
    steps: &Steps,
    kin: &KinematicsConfig,
    warnings: &mut Vec<String>,
) -> ViewDecision {
    let mut t = Tracks::from_sequence(seq);
    steps.gate.apply(&mut t);
    let mut decision = view::decide(&t, kin.view, warnings);
    if let Some([width, _]) = kin.frame_size {
        decision.walk_angle_deg = walk_angle::estimate(&t, width);
        if decision.walk_angle_deg.is_finite() {
            decision.how += &format!(
                "; the walk about {:.0} deg off the camera's axis",
                decision.walk_angle_deg
            );
        }
        warnings.extend(walk_angle::warning(decision.view, decision.walk_angle_deg));
    }
    decision
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

#[cfg(test)]
mod tests;
