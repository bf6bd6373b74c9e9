//! Front and back views: frontal-plane angles, events, step width and circumduction from a
//! walk toward (anterior) or away from (posterior) the camera. The view is decided in
//! [`crate::view`]; this module supplies the parts of the chain that differ from a side view:
//! the leg labels ([`labels`]), the body's scale per frame ([`scale`]), bouts ([`bouts`]),
//! events ([`events`], heel strikes placed by `heel_strikes`) and the measures ([`measures`],
//! [`cycles`], [`feet`]). Quality control and strides are the side view's, with segment lengths
//! taken in body sizes.

pub mod bouts;
pub mod cycles;
pub mod events;
pub mod feet;
mod heel_strikes;
pub mod labels;
mod lead;
pub mod measures;
pub mod scale;
pub mod tables;

use serde::Serialize;

use crate::bouts::{Bout, bout_of};
use crate::config::KinematicsConfig;
use crate::cycles::{CycleCurve, Stride};
use crate::events::Event;
use crate::quality::CycleQuality;
use crate::tracks::{Tracks, median};
use crate::view::View;
pub use cycles::FrontalScalar;
pub use feet::FootLength;
pub use measures::{FrontalAngles, MEASURES};
pub use scale::Scale;

/// What a frontal run measured (run.json gets the summary; the per-frame series and curves go
/// to the frontal CSV files).
#[derive(Debug, Clone, Serialize)]
pub struct FrontalResult {
    pub view: View,
    /// A straight leg's length over the body size (mid-hip to mid-shoulder).
    pub leg_per_size: f64,
    #[serde(skip)]
    pub angles: FrontalAngles,
    /// The smoothed body size in pixels per timeline frame.
    #[serde(skip)]
    pub size: Vec<f64>,
    /// Mean curves over the accepted cycles, per side and measure (`joint` = the measure).
    pub cycles: Vec<CycleCurve>,
    pub scalars: Vec<FrontalScalar>,
    /// Step width and heel offset at each heel strike in a bout, circumduction in each
    /// accepted stride.
    pub feet: Vec<FootLength>,
    /// Per candidate stride (in the order of cycle_quality): the measures it has no value for
    /// and why, `; `-separated (empty when complete or rejected).
    pub cycle_notes: Vec<String>,
    /// How far beside the camera the walk's line runs, in leg lengths ([`LINE_OFFSET_LIMIT`]).
    pub line_offset_leg: f64,
}

/// Beyond this many leg lengths (about 0.5 m) between the walk's line and the camera, a foot's
/// sideways path is no longer measured at its own depth well enough: with the camera 0.5, 1.0
/// and 1.5 m beside the line of a healthy walk (tools/frontal/oblique.py) the right foot's
/// circumduction read 4.8, 6.1 and 7.5 cm against 2.7 in 3-D (the checklist's threshold is 5),
/// and at 1.0 and 1.5 m walking away a medial or lateral whip was called. The checklist does not
/// judge those items beyond it (`gait-checklist`'s camera gate), and the run warns.
pub const LINE_OFFSET_LIMIT: f64 = 0.6;

/// The inputs of [`measure`] besides the keypoints.
pub struct Found<'a> {
    pub view: View,
    pub scale: &'a Scale,
    pub events: &'a [Event],
    pub bouts: &'a [Bout],
    pub quality: &'a [CycleQuality],
    pub accepted: &'a [Stride],
}

/// The frontal measures of the accepted strides of `t`.
pub fn measure(
    t: &Tracks,
    f: &Found,
    kin: &KinematicsConfig,
    warnings: &mut Vec<String>,
) -> FrontalResult {
    let angles = measures::compute(t, f.view);
    let per_cycle = cycles::per_cycle(&angles, t.first_frame, f.accepted);
    let curves = cycles::curves(&per_cycle, kin.min_cycles);
    if curves.is_empty() {
        warnings.push(format!(
            "fewer than {} complete cycles per side in the {} view: no frontal mean curves",
            kin.min_cycles.max(1),
            view_name(f.view)
        ));
    }
    let cycle_notes = f
        .quality
        .iter()
        .map(|q| {
            per_cycle
                .iter()
                .find(|(s, _)| *s == q.stride())
                .map(|(_, c)| {
                    let why: Vec<&str> =
                        c.iter().filter_map(|r| r.as_ref().err().copied()).collect();
                    why.join("; ")
                })
                .unwrap_or_default()
        })
        .collect();
    let feet = feet::Feet {
        t,
        view: f.view,
        scale: f.scale,
        events: f.events,
        vanishing_x: crate::walk_angle::vanishing_x(t).unwrap_or_else(|| axis_x(t, kin)),
    };
    let in_bout = |frame: usize| bout_of(f.bouts, frame).is_some();
    let mut lengths = feet.step_widths(&in_bout, kin);
    lengths.extend(feet.heel_offsets(&in_bout, kin));
    lengths.extend(feet.circumduction(f.accepted, kin));
    let line_offset_leg = feet.line_offset(&in_bout);
    if line_offset_leg > LINE_OFFSET_LIMIT {
        warnings.push(format!(
            "the walk's line runs about {line_offset_leg:.1} leg lengths beside the camera (more than {LINE_OFFSET_LIMIT}, about 0.5 m): circumduction and whips are not judged; put the camera on the walking line"
        ));
    }
    FrontalResult {
        view: f.view,
        leg_per_size: f.scale.leg_per_size,
        scalars: cycles::scalars(&per_cycle, kin.prosthetic_side),
        angles,
        size: f.scale.size.clone(),
        cycles: curves,
        feet: lengths,
        cycle_notes,
        line_offset_leg,
    }
}

pub fn view_name(v: View) -> &'static str {
    match v {
        View::Anterior => "anterior",
        View::Posterior => "posterior",
        View::Sagittal => "sagittal",
    }
}

/// The camera's axis in the image, where the walk has no vanishing point: the frame's middle
/// when its size is known, else where the walker's pelvis mostly is.
fn axis_x(t: &Tracks, kin: &KinematicsConfig) -> f64 {
    if let Some([w, _]) = kin.frame_size {
        return w as f64 / 2.0;
    }
    let mut xs: Vec<f64> = (0..t.len())
        .filter_map(|i| t.pelvis(i).map(|p| p.0))
        .collect();
    median(&mut xs)
}
