//! Two steps of [`crate::analyse`]'s chain that differ between a side view and a front or back
//! view: the walking bouts and the gait events.

use std::path::Path;

use crate::bouts::{self, Bout};
use crate::clean::Cleaned;
use crate::config::{KinematicsConfig, PostprocessConfig, Side};
use crate::corrections::{self, Corrections};
use crate::direction::Directions;
use crate::events::{self, Event, EventKind};
use crate::frontal;
use crate::margins::EventMargin;
use crate::tracks::Tracks;
use crate::view::View;
use crate::{KinError, Steps};

/// The walking bouts: a front or back view's from the body's growth, a side view's from the
/// walk across the image.
pub(crate) fn bouts(
    c: &Cleaned,
    dirs: &Directions,
    scale: Option<&frontal::Scale>,
    view: View,
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
) -> Vec<Bout> {
    match scale {
        Some(scale) => frontal::bouts::find(&c.clean, view, scale, kin),
        None => bouts::find(
            &bouts::Frames {
                clean: &c.clean,
                gated: &c.gated,
                dirs: &dirs.per_frame,
                max_gap: post.max_gap(c.clean.fps),
            },
            kin,
        ),
    }
}

/// A warning when frames were seen but no bout was found.
pub(crate) fn warn_no_bout(n: usize, bouts: &[Bout], enforce: bool, warnings: &mut Vec<String>) {
    if n > 0 && bouts.is_empty() {
        warnings.push(if enforce {
            "no walking bout found: no events or cycles".into()
        } else {
            "no walking bout found: the events of events_csv are used as given".into()
        });
    }
}

/// The events (read from `kinematics.events_csv`, else detected for the view), kept inside the
/// bouts when `bouts.1` says so, with a person's corrections applied; their margins, and
/// whether they came from the file.
#[allow(clippy::too_many_arguments)]
pub(crate) fn events(
    t: &Tracks,
    dirs: &Directions,
    frontal: Option<(View, &frontal::Scale)>,
    steps: &Steps,
    kin: &KinematicsConfig,
    bouts: (&[Bout], bool),
    fixes: Option<(&Corrections, &Path)>,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Event>, Vec<EventMargin>, bool), KinError> {
    let (mut found, margins, from_file) = match (&kin.events_csv, frontal) {
        (Some(p), _) => (events::read_csv(p)?, Vec::new(), true),
        (None, Some((view, scale))) => {
            let (ev, m) = frontal::events::detect(t, view, scale, kin.min_stride_s);
            (ev, m, false)
        }
        (None, None) => {
            let (ev, m) = steps.events.detect_with_margins(t, &dirs.per_frame);
            (ev, m, false)
        }
    };
    if bouts.1 {
        found.retain(|e| bouts::bout_of(bouts.0, e.frame).is_some());
    }
    if let Some((c, path)) = fixes {
        corrections::apply_events(c, &mut found, path)?;
    }
    for side in Side::BOTH {
        if !found
            .iter()
            .any(|e| e.side == side && e.event == EventKind::HeelStrike)
        {
            warnings.push(format!("no heel strike found for the {} leg", side.name()));
        }
    }
    Ok((found, margins, from_file))
}
