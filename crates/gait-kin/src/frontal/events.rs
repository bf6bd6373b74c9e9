//! Heel strikes and toe-offs from a front or back view.
//!
//! Zeni's rule (heel strike where the heel is furthest ahead of the pelvis, toe-off where the
//! toe is furthest behind) needs "ahead" along the walk, which a frontal camera sees as depth.
//! A floor point nearer the camera lies lower in the image, and with every length divided by
//! the body's size in its frame, `(y_foot - y_pelvis) / size` grows with `Z_pelvis / Z_foot`:
//! for a foot on the floor that is a monotonic function of how far it is ahead of the pelvis
//! (the pelvis' own height only adds a constant). So the extrema of that signal, negated for a
//! walk away from the camera, are Zeni's extrema, without knowing the camera's height or lens.
//! Stenum et al. (2024) take events in a frontal view from the ankles' vertical image distance;
//! this uses each foot against the pelvis, as Zeni does, so that one foot's heel rising at the
//! end of its stance does not move the other foot's heel strike.

use crate::config::Side;
use crate::events::{Event, EventKeypoints, EventKind};
use crate::frontal::scale::Scale;
use crate::margins::EventMargin;
use crate::peaks::gait_peaks;
use crate::tracks::Tracks;
use crate::view::View;

/// An excursion counts as a stride when it stands out by at least this share of the foot's
/// median excursion, and at least [`FLOOR`] body sizes (as the side view's rule, see
/// [`crate::peaks::gait_peaks`]).
const SHARE: f64 = 0.5;
/// A walker 5 m from the camera moves a foot 0.7 m from behind to ahead of the pelvis, which
/// changes the signal by about 0.25; a stance foot's keypoint wobbles by a few hundredths.
const FLOOR: f64 = 0.03;

/// The events of both feet, heel strikes from the heel (else the ankle) and toe-offs from the
/// toe (else the ankle), with the margins of the stride decisions.
pub fn detect(
    t: &Tracks,
    view: View,
    scale: &Scale,
    min_stride_s: f64,
) -> (Vec<Event>, Vec<EventMargin>) {
    let ahead = view_sign(view);
    let min_dist = ((0.8 * min_stride_s * t.fps).round() as usize).max(1);
    let mut events = Vec::new();
    let mut margins = Vec::new();
    for side in Side::BOTH {
        let Some(kp) = EventKeypoints::of(t, side) else {
            continue;
        };
        for (kind, j, sign) in [
            (EventKind::HeelStrike, kp.heel_strike, ahead),
            (EventKind::ToeOff, kp.toe_off, -ahead),
        ] {
            let x = forward(t, j, scale, sign);
            let peaks = gait_peaks(&x, FLOOR, SHARE, min_dist);
            margins.push(EventMargin::of(side, kind, &peaks));
            events.extend(peaks.kept.iter().map(|p| Event {
                side,
                event: kind,
                frame: t.first_frame + p.index,
            }));
        }
    }
    events.sort_by_key(|e| (e.frame, e.side == Side::Right, e.event));
    (events, margins)
}

/// +1 when a foot ahead of the pelvis lies lower in the image (walking toward the camera).
fn view_sign(view: View) -> f64 {
    match view {
        View::Posterior => -1.0,
        _ => 1.0,
    }
}

/// `sign * (y_j - y_pelvis) / size` per frame (NaN where a point is missing).
fn forward(t: &Tracks, j: usize, scale: &Scale, sign: f64) -> Vec<f64> {
    (0..t.len())
        .map(|i| match (t.at(j, i), t.pelvis(i), scale.size[i]) {
            (Some(p), Some(c), s) if s > 0.0 => sign * (p.1 - c.1) / s,
            _ => f64::NAN,
        })
        .collect()
}
