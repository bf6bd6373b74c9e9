//! Motion blur of the swinging foot. A long exposure (a phone indoors: up to the whole 1/30 s
//! frame interval) smears a foot moving at several leg lengths a second over tens of pixels,
//! and the pose model then draws the swinging foot elsewhere while its likelihoods stay high
//! (the sample with a 1/30 s shutter: an ankle curve 29 deg RMS off). Defocus and encoding soften
//! a foot alike standing and swinging; motion blur only swinging. So each stride's foot is
//! judged by the contrast of its outline while it swings fast against the same foot's while
//! it stands (`gait_edge::edge_contrast`, measured by `gait run` in every frame).

use crate::config::{FeetContrast, KinematicsConfig, Side};
use crate::cycles::Stride;
use crate::tracks::{Tracks, median};

/// A foot slower than this (leg lengths per second, the ankle) stands: a planted foot's
/// keypoint jitters by well under it.
const STILL: f64 = 0.3;
/// A foot faster than this swings fast: mid-swing runs at 4-5 leg lengths per second, so
/// about a third of the swing's frames.
const FAST: f64 = 2.0;
/// Fewer frames than this standing (over the whole walk) or swinging fast (in the stride):
/// no figure.
const MIN_FRAMES: usize = 3;
/// A standing foot whose outline is fainter than this (grey levels per pixel) gives no figure:
/// the ratio of two faint outlines is noise (the sample's feet read about 25 sharp, 11 blurred by
/// a Gaussian of sigma 2 px, 3.5 by sigma 8).
const MIN_STANDING: f64 = 5.0;

/// Both feet's speeds and contrasts over the walk, measured once for every stride.
pub(super) struct FeetInMotion {
    /// Left, right; `None` for a foot without a figure (no contrasts, no ankle, too few frames
    /// standing, a standing outline too faint, or a front or back view, where the foot moves
    /// across the rows little).
    feet: [Option<Foot>; 2],
}

/// One foot's frames of the walk where its speed and contrast are known, as (frame, ankle speed
/// in leg lengths per second, outline contrast), and its median contrast standing.
struct Foot {
    frames: Vec<(usize, f64, f64)>,
    standing: f64,
}

impl FeetInMotion {
    pub(super) fn measure(t: &Tracks, kin: &KinematicsConfig, frontal: bool) -> Self {
        let leg = t.leg_length();
        let feet = match &kin.image_feet_contrast {
            Some(contrast) if !frontal && leg.is_finite() => {
                Side::BOTH.map(|side| foot(t, contrast, side, leg))
            }
            _ => [None, None],
        };
        Self { feet }
    }

    /// The stride's foot's median outline contrast while it swings fast over its median
    /// contrast while it stands anywhere in the walk; NaN without a figure.
    pub(super) fn swing_contrast(&self, s: &Stride) -> f64 {
        let Some(foot) = &self.feet[usize::from(s.side == Side::Right)] else {
            return f64::NAN;
        };
        let mut fast: Vec<f64> = foot
            .frames
            .iter()
            .filter(|f| (s.start..=s.end).contains(&f.0) && f.1 > FAST)
            .map(|f| f.2)
            .collect();
        if fast.len() < MIN_FRAMES {
            return f64::NAN;
        }
        median(&mut fast) / foot.standing
    }
}

/// `side`'s foot (`None` under [`MIN_FRAMES`] standing or [`MIN_STANDING`]).
fn foot(t: &Tracks, contrast: &FeetContrast, side: Side, leg: f64) -> Option<Foot> {
    let ankle = t.leg_index(side, "ankle")?;
    let column = usize::from(side == Side::Right);
    let speed = |i: usize| -> Option<f64> {
        let (a, b) = (t.at(ankle, i.checked_sub(1)?)?, t.at(ankle, i + 1)?);
        Some((b.0 - a.0).hypot(b.1 - a.1) / 2.0 * t.fps / leg)
    };
    let frames: Vec<(usize, f64, f64)> = (0..t.len())
        .filter_map(|i| {
            let frame = t.first_frame + i;
            let c = contrast.get(&frame)?[column]?;
            Some((frame, speed(i)?, c))
        })
        .collect();
    let mut still: Vec<f64> = frames.iter().filter(|f| f.1 < STILL).map(|f| f.2).collect();
    if still.len() < MIN_FRAMES {
        return None;
    }
    let standing = median(&mut still);
    (standing >= MIN_STANDING).then_some(Foot { frames, standing })
}
