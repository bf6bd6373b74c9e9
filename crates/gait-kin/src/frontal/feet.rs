//! The feet's lateral lengths in a front or back view: step width and each heel's offset from
//! the pelvis at heel strikes, circumduction over each stride.
//!
//! A lateral position is taken against the walk's vanishing point, at its own depth. Lines
//! parallel to the walk all end in that point, and a point's image offset from it is its
//! lateral offset from the camera over its depth; a foot ahead of the pelvis is nearer the
//! camera. Taken at the pelvis' scale, as before, a walk that does not run through the camera
//! (a camera beside the walkway's line, or turned from it) made every foot ahead of the pelvis
//! seem further out by that offset times the relative depth: on projected motion capture
//! (tools/frontal/oblique.py) a healthy walk straight toward a camera 1 m beside its line read
//! 12.0 cm of circumduction on one side, against 2.7 with the camera on the line (now 6.1
//! against 3.4; BENCHMARKS.md, "A camera beside the walking line"). A planted foot stays where
//! it landed, at the depth the pelvis has when it passes over it (mid-stance); a swinging foot
//! moves between two such places, and its depth (as 1 / its leg's image length) is taken as
//! moving between them evenly in time: on the healthy trial's motion capture the ankle's depth
//! in swing kept within 6 % of its travel of that, while a minimum-jerk profile was up to 13 %
//! off.

use serde::Serialize;

use crate::config::{KinematicsConfig, Side};
use crate::cycles::Stride;
use crate::events::{Event, EventKind};
use crate::frontal::scale::Scale;
use crate::spatiotemporal::LEG_PER_HEIGHT;
use crate::tracks::{Tracks, median};
use crate::view::View;

/// A length measured at one event or over one stride.
#[derive(Debug, Clone, Serialize)]
pub struct FootLength {
    pub side: Side,
    /// `step_width` or `heel_offset` (at a heel strike), or `circumduction` (over a stride).
    pub measure: &'static str,
    pub first_frame: usize,
    pub last_frame: usize,
    /// In `unit`: cm with a known scale, else leg lengths.
    pub value: f64,
    pub unit: &'static str,
}

/// What the foot measures need besides the keypoints.
pub struct Feet<'a> {
    pub t: &'a Tracks,
    pub view: View,
    pub scale: &'a Scale,
    pub events: &'a [Event],
    /// Image x of the walk's vanishing point (else of the camera's axis).
    pub vanishing_x: f64,
}

impl Feet<'_> {
    /// Step width at each heel strike `keep` admits: the heels' lateral distance, each heel
    /// where its foot stands.
    pub fn step_widths(
        &self,
        keep: &dyn Fn(usize) -> bool,
        kin: &KinematicsConfig,
    ) -> Vec<FootLength> {
        self.at_heel_strikes(keep, kin, "step_width", &|side, heel, frame| {
            let other = self.point(side.other(), &["heel", "ankle"], frame)?;
            let (a, b) = (
                self.lateral(side, heel.0, self.planted_leg(side, frame)),
                self.lateral(side, other.0, self.planted_leg(side.other(), frame)),
            );
            Some((a - b).abs())
        })
    }

    /// At each heel strike `keep` admits, the striking heel's lateral distance from the
    /// pelvis' midpoint (half the walking base, the side's own share of it: a step width
    /// grows at both feet's heel strikes when one foot is placed wide).
    pub fn heel_offsets(
        &self,
        keep: &dyn Fn(usize) -> bool,
        kin: &KinematicsConfig,
    ) -> Vec<FootLength> {
        self.at_heel_strikes(keep, kin, "heel_offset", &|side, heel, frame| {
            let p = self.t.pelvis(frame.checked_sub(self.t.first_frame)?)?;
            let pelvis = self.lateral(side, p.0, self.leg_at(frame as f64));
            Some(self.lateral(side, heel.0, self.planted_leg(side, frame)) - pelvis)
        })
    }

    /// Circumduction of each stride: the swing ankle's largest lateral excursion from the
    /// chord joining where the foot stood before and after the swing, followed over the swing
    /// only, from toe-off to heel strike (over the whole stride a standing foot moved against a
    /// chord that had already begun to move). Where it stood: its median lateral position over
    /// the middle third of each stance.
    pub fn circumduction(&self, strides: &[Stride], kin: &KinematicsConfig) -> Vec<FootLength> {
        let (per_leg, unit) = unit(kin);
        strides
            .iter()
            .filter_map(|s| {
                let lift = self
                    .toe_off_after(s.side, s.start)
                    .filter(|&to| to < s.end)?;
                let (a, leg_a) = self.stood(s.side, s.start)?;
                let (b, leg_b) = self.stood(s.side, s.end)?;
                let span = (s.end - lift) as f64;
                let mut most = 0.0f64;
                for f in lift..=s.end {
                    let travel = (f - lift) as f64 / span;
                    let leg = 1.0 / (1.0 / leg_a + (1.0 / leg_b - 1.0 / leg_a) * travel);
                    let x = self.point(s.side, &["ankle"], f)?.0;
                    most = most.max(self.lateral(s.side, x, leg) - (a + (b - a) * travel));
                }
                let value = most * per_leg;
                value.is_finite().then_some(FootLength {
                    side: s.side,
                    measure: "circumduction",
                    first_frame: s.start,
                    last_frame: s.end,
                    value,
                    unit,
                })
            })
            .collect()
    }

    /// How far beside the camera the walk's line runs: the pelvis' median lateral distance
    /// from the line through the vanishing point, in leg lengths, over the frames `keep`
    /// admits (NaN without any).
    pub fn line_offset(&self, keep: &dyn Fn(usize) -> bool) -> f64 {
        let mut at: Vec<f64> = (0..self.t.len())
            .filter(|&i| keep(self.t.first_frame + i))
            .filter_map(|i| {
                let p = self.t.pelvis(i)?;
                let leg = self.scale.leg_px(i);
                Some((p.0 - self.vanishing_x).abs() / leg)
            })
            .collect();
        median(&mut at)
    }

    /// Where the ankle of `side` stood in the stance that starts at heel strike `hs`, in leg
    /// lengths, and the leg's image length at that depth; at the heel strike itself where the
    /// stance has no toe-off.
    fn stood(&self, side: Side, hs: usize) -> Option<(f64, f64)> {
        let Some(to) = self.toe_off_after(side, hs) else {
            let leg = self.leg_at(hs as f64);
            return Some((
                self.lateral(side, self.point(side, &["ankle"], hs)?.0, leg),
                leg,
            ));
        };
        let leg = self.leg_at((hs + to) as f64 / 2.0);
        let third = (to - hs) / 3;
        let mut at: Vec<f64> = (hs + third..=to - third)
            .filter_map(|f| Some(self.lateral(side, self.point(side, &["ankle"], f)?.0, leg)))
            .collect();
        Some((median(&mut at), leg)).filter(|(m, _)| m.is_finite())
    }

    fn point(&self, side: Side, parts: &[&str], frame: usize) -> Option<(f64, f64)> {
        let i = frame.checked_sub(self.t.first_frame)?;
        let j = parts.iter().find_map(|p| self.t.seen_leg_index(side, p))?;
        self.t.at(j, i)
    }

    /// Lateral position toward `side` of image x `x` at a depth where a leg is `leg` px long,
    /// in leg lengths from the line through the vanishing point.
    fn lateral(&self, side: Side, x: f64, leg: f64) -> f64 {
        self.view.toward(side) * (x - self.vanishing_x) / leg
    }

    /// A leg's image length at (sub-)frame `frame`, at the pelvis' depth then.
    fn leg_at(&self, frame: f64) -> f64 {
        let i = frame - self.t.first_frame as f64;
        if i < 0.0 {
            return f64::NAN;
        }
        let (lo, w) = (i.floor() as usize, i.fract());
        let a = self.scale.leg_px(lo);
        if w == 0.0 {
            return a;
        }
        a + (self.scale.leg_px(lo + 1) - a) * w
    }

    /// A leg's image length at the depth where the foot of `side` stood last at `frame` (at a
    /// heel strike: the striking foot's new place, the other foot's, in terminal stance, the
    /// old one): the pelvis' in the middle of that stance; at `frame` where it is not known.
    fn planted_leg(&self, side: Side, frame: usize) -> f64 {
        let hs = (self.events.iter())
            .filter(|e| e.side == side && e.event == EventKind::HeelStrike && e.frame <= frame)
            .map(|e| e.frame)
            .max();
        match hs.and_then(|hs| Some((hs, self.toe_off_after(side, hs)?))) {
            Some((hs, to)) => self.leg_at((hs + to) as f64 / 2.0),
            None => self.leg_at(frame as f64),
        }
    }

    fn toe_off_after(&self, side: Side, after: usize) -> Option<usize> {
        (self.events.iter())
            .filter(|e| e.side == side && e.event == EventKind::ToeOff && e.frame > after)
            .map(|e| e.frame)
            .min()
    }

    /// `measure` at each heel strike `keep` admits: `lateral` gives it in leg lengths from the
    /// striking side, its heel and the frame; scaled here to cm or leg lengths.
    fn at_heel_strikes(
        &self,
        keep: &dyn Fn(usize) -> bool,
        kin: &KinematicsConfig,
        measure: &'static str,
        lateral: &dyn Fn(Side, (f64, f64), usize) -> Option<f64>,
    ) -> Vec<FootLength> {
        let (per_leg, unit) = unit(kin);
        self.events
            .iter()
            .filter(|e| e.event == EventKind::HeelStrike && keep(e.frame))
            .filter_map(|e| {
                let heel = self.point(e.side, &["heel", "ankle"], e.frame)?;
                let value = lateral(e.side, heel, e.frame)? * per_leg;
                value.is_finite().then_some(FootLength {
                    side: e.side,
                    measure,
                    first_frame: e.frame,
                    last_frame: e.frame,
                    value,
                    unit,
                })
            })
            .collect()
    }
}

/// Leg lengths in cm (from the subject's height) or leg lengths as the unit.
fn unit(kin: &KinematicsConfig) -> (f64, &'static str) {
    match kin.subject_height_m {
        Some(h) => (LEG_PER_HEIGHT * h * 100.0, "cm"),
        None => (1.0, "leg"),
    }
}
