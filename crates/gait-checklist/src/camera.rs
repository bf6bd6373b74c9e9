//! A front or back view filmed obliquely: its items are not judged.
//!
//! Beyond [`TOLERANCE_DEG`] between the walk and the camera's axis the frontal measures are
//! distorted (BENCHMARKS.md, "Oblique walks"): on healthy and Parkinson's motion capture
//! projected 20-45 deg off the walking line, circumduction, an abducted gait, hip hiking and
//! whips were called where there were none. Such a run's front and back items are not
//! assessable, with the angle as the reason, instead of present or absent.

use gait_kin::walk_angle::TOLERANCE_DEG;

use crate::run_files::RunFiles;
use crate::verdict::{Status, Verdict};

/// Turns the front and back items of `verdicts` into not assessable when `run` is a front or
/// back view whose walk runs beyond the tolerance off the camera's axis.
pub fn gate(verdicts: &mut [Verdict], run: &RunFiles) {
    let angle = run.walk_angle_deg;
    if run.view == "sagittal" || angle.is_nan() || angle <= TOLERANCE_DEG {
        return;
    }
    let why = format!(
        "the walk runs {angle:.0} deg off the camera's axis: a front or back view needs it within {TOLERANCE_DEG:.0} deg (film it straight toward or away from the camera)"
    );
    for v in verdicts
        .iter_mut()
        .filter(|v| v.item.view != "side" && v.status != Status::NotAssessable)
    {
        *v = Verdict::not_assessable(v.item, v.side, why.clone());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Side;
    use crate::frontal_items::CIRCUMDUCTION;
    use crate::sagittal_items::STANCE;

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
}
