//! A walk filmed obliquely: the items its view cannot measure there are not judged.
//!
//! Beyond [`TOLERANCE_DEG`] between the walk and the direction its view needs, the measures are
//! distorted (BENCHMARKS.md, "Oblique walks"): on healthy and Parkinson's motion capture
//! projected 20-45 deg off the walking line, a front or back view called circumduction, an
//! abducted gait, hip hiking and whips where there were none; a side view 20 deg off across
//! called an uneven step length on a healthy walk (its steps 64.7 and 53.2 cm: seen obliquely,
//! each step is further away than the last, and the step width shows along the image's x,
//! lengthening one side's steps and shortening the other's). Such a run's front and back items,
//! or a side view's step length, are not assessable, with the angle as the reason, instead of
//! present or absent. A side view's timing holds at any angle, its angles within a few degrees.
//! A front or back view whose walking line runs beside the camera ([`LINE_OFFSET_LIMIT`]) does
//! not judge circumduction and whips, the items that follow a foot's sideways path.

use gait_kin::frontal::LINE_OFFSET_LIMIT;
use gait_kin::walk_angle::{TOLERANCE_DEG, degrees_off};

use crate::frontal_items::CIRCUMDUCTION;
use crate::run_files::RunFiles;
use crate::sagittal_items::STEP_LENGTH;
use crate::verdict::{Status, Verdict};
use crate::whip::WHIP;

/// Turns the items of `verdicts` that `run`'s view cannot measure obliquely into not assessable
/// when its walk runs beyond the tolerance off what the view needs: a front or back view's
/// front and back items, a side view's step length.
pub fn gate(verdicts: &mut [Verdict], run: &RunFiles) {
    gate_angle(verdicts, run);
    gate_line_offset(verdicts, run);
}

/// A front or back view's circumduction and whips not judged when its walking line runs more
/// than [`LINE_OFFSET_LIMIT`] beside the camera.
fn gate_line_offset(verdicts: &mut [Verdict], run: &RunFiles) {
    let offset = run.line_offset_leg;
    if run.view == "sagittal" || offset.is_nan() || offset <= LINE_OFFSET_LIMIT {
        return;
    }
    let why = format!(
        "the walk's line runs {offset:.1} leg lengths beside the camera: a foot's sideways path needs it within {LINE_OFFSET_LIMIT} (about 0.5 m; put the camera on the walking line)"
    );
    not_assessable(
        verdicts,
        |v| [CIRCUMDUCTION.id, WHIP.id].contains(&v.item.id),
        &why,
    );
}

/// The items of a view filmed beyond [`TOLERANCE_DEG`] off the direction it needs.
fn gate_angle(verdicts: &mut [Verdict], run: &RunFiles) {
    let angle = run.walk_angle_deg;
    let side_view = run.view == "sagittal";
    let off = degrees_off(!side_view, angle);
    if angle.is_nan() || off <= TOLERANCE_DEG {
        return;
    }
    let why = if side_view {
        format!(
            "the walk runs {off:.0} deg off across the camera: step lengths need it within {TOLERANCE_DEG:.0} deg (film the walk straight across)"
        )
    } else {
        format!(
            "the walk runs {angle:.0} deg off the camera's axis: a front or back view needs it within {TOLERANCE_DEG:.0} deg (film it straight toward or away from the camera)"
        )
    };
    let gated = |v: &Verdict| match side_view {
        true => v.item.id == STEP_LENGTH.id,
        false => v.item.view != "side",
    };
    not_assessable(verdicts, gated, &why);
}

/// The judged verdicts that `gated` picks turned into not assessable, `why`.
fn not_assessable(verdicts: &mut [Verdict], gated: impl Fn(&Verdict) -> bool, why: &str) {
    for v in verdicts
        .iter_mut()
        .filter(|v| gated(v) && v.status != Status::NotAssessable)
    {
        *v = Verdict::not_assessable(v.item, v.side, why);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Side;
    use crate::frontal_items::CIRCUMDUCTION;
    use crate::sagittal_items::{STANCE, STEP_LENGTH};

    fn present(item: crate::verdict::Item) -> Verdict {
        let mut v = Verdict::not_assessable(item, Side::Right, "");
        v.status = Status::Present;
        v
    }

    #[test]
    fn an_oblique_front_view_judges_no_front_item() {
        let run = |view: &str, angle| RunFiles {
            view: view.into(),
            walk_angle_deg: angle,
            ..Default::default()
        };
        let mut v = vec![present(CIRCUMDUCTION), present(STANCE)];
        gate(&mut v, &run("anterior", 10.0));
        assert_eq!(v[0].status, Status::Present);
        gate(&mut v, &run("sagittal", 40.0));
        assert_eq!(v[0].status, Status::Present);
        gate(&mut v, &run("posterior", f64::NAN));
        assert_eq!(v[0].status, Status::Present);
        gate(&mut v, &run("anterior", 28.0));
        assert_eq!(v[0].status, Status::NotAssessable);
        assert!(
            v[0].reason.contains("28 deg off the camera's axis"),
            "{}",
            v[0].reason
        );
        assert_eq!(v[1].status, Status::Present);
    }

    /// A front view 1.1 leg lengths beside the camera: circumduction and whips not judged,
    /// the trunk's lean still judged; a side view's line offset means nothing.
    #[test]
    fn a_walking_line_beside_the_camera_judges_no_sideways_path() {
        use crate::frontal_items::TRUNK;
        let run = |view: &str, offset| RunFiles {
            view: view.into(),
            walk_angle_deg: 2.0,
            line_offset_leg: offset,
            ..Default::default()
        };
        let items = || vec![present(CIRCUMDUCTION), present(WHIP), present(TRUNK)];
        let mut v = items();
        gate(&mut v, &run("anterior", 0.5));
        assert!(v.iter().all(|v| v.status == Status::Present));
        gate(&mut v, &run("sagittal", 1.1));
        assert!(v.iter().all(|v| v.status == Status::Present));
        gate(&mut v, &run("posterior", 1.1));
        assert_eq!(v[0].status, Status::NotAssessable);
        assert_eq!(v[1].status, Status::NotAssessable);
        assert!(
            v[0].reason.contains("1.1 leg lengths beside"),
            "{}",
            v[0].reason
        );
        assert_eq!(v[2].status, Status::Present);
    }

    /// A side view 20 deg off across: its step length is not judged, its timing is; at 10 deg
    /// off both are.
    #[test]
    fn an_oblique_side_view_judges_no_step_length() {
        let run = |angle| RunFiles {
            view: "sagittal".into(),
            walk_angle_deg: angle,
            ..Default::default()
        };
        let mut v = vec![present(STEP_LENGTH), present(STANCE)];
        gate(&mut v, &run(80.0));
        assert_eq!(v[0].status, Status::Present);
        gate(&mut v, &run(70.0));
        assert_eq!(v[0].status, Status::NotAssessable);
        assert!(v[0].reason.contains("20 deg off across"), "{}", v[0].reason);
        assert_eq!(v[1].status, Status::Present);
    }
}
