//! Each side's curves of a visit: the sagittal ones from the side views where that limb is near
//! the camera, the frontal ones from the front or back view with the most cycles; where several
//! passes of that kind have cycles (a clinic films a short walkway more than once), their cycles
//! are pooled.

use gait_eval::plot::CycleCurve;

use crate::combine::Source;
use crate::pass::Pass;

const SIDES: [&str; 2] = ["left", "right"];

/// Each side's sagittal curves: pooled over the side views where that limb was near the camera
/// (its own side's view, or a walk there and back), else over those where it was far (half
/// hidden), said so.
pub fn sagittal(passes: &[Pass], sources: &mut Vec<Source>) -> Vec<CycleCurve> {
    let mut out = Vec::new();
    for side in SIDES {
        let seen = |near: bool| -> Vec<&Pass> {
            (passes.iter())
                .filter(|p| {
                    !p.is_frontal() && p.near_camera(side) == near && p.cycles(side, false) > 0
                })
                .collect()
        };
        let (near, far) = (seen(true), seen(false));
        let (group, how) = if !near.is_empty() {
            (near, "near the camera")
        } else if !far.is_empty() {
            (far, "far from the camera: no pass shows it near")
        } else {
            sources.push(Source {
                what: format!("{side} sagittal curves"),
                pass: "none: no side view with an accepted cycle of this limb".into(),
            });
            continue;
        };
        out.extend(pooled(&group, side, false));
        sources.push(Source {
            what: format!("{side} sagittal curves"),
            pass: format!(
                "{} ({how}), {}",
                labels(&group),
                cycles(&group, side, false)
            ),
        });
    }
    out
}

/// Each side's frontal curves from the front or back view whose pass has the most of its
/// cycles, pooled over that view's passes; the view they come from.
pub fn frontal(passes: &[Pass], sources: &mut Vec<Source>) -> (Vec<CycleCurve>, Option<String>) {
    let mut out = Vec::new();
    let mut view = None;
    for side in SIDES {
        let with_cycles = |p: &&Pass| p.is_frontal() && p.cycles(side, true) > 0;
        let Some(best) = passes
            .iter()
            .filter(with_cycles)
            .max_by_key(|p| p.cycles(side, true))
        else {
            sources.push(Source {
                what: format!("{side} frontal curves"),
                pass: "none: no front or back view with an accepted cycle of this side".into(),
            });
            continue;
        };
        let group: Vec<&Pass> = (passes.iter())
            .filter(with_cycles)
            .filter(|p| p.view == best.view)
            .collect();
        view.get_or_insert_with(|| best.view.clone());
        out.extend(pooled(&group, side, true));
        sources.push(Source {
            what: format!("{side} frontal curves"),
            pass: format!("{}, {}", labels(&group), cycles(&group, side, true)),
        });
    }
    (out, view)
}

/// `left view (a.mp4) + left view (b.mp4)`.
fn labels(group: &[&Pass]) -> String {
    group
        .iter()
        .map(|p| p.label())
        .collect::<Vec<_>>()
        .join(" + ")
}

/// `3 cycles`, or `5 cycles pooled` over several passes.
fn cycles(group: &[&Pass], side: &str, frontal: bool) -> String {
    let n: usize = group.iter().map(|p| p.cycles(side, frontal)).sum();
    let pooled = if group.len() > 1 { " pooled" } else { "" };
    format!("{n} cycles{pooled}")
}

/// `side`'s curves of the passes in `group`, each curve's cycles pooled over them: at each
/// point the mean weighted by the cycles, the SD of all the cycles (within and between the
/// passes).
fn pooled(group: &[&Pass], side: &str, frontal: bool) -> Vec<CycleCurve> {
    let curves_of = |p: &Pass| -> Vec<CycleCurve> {
        let all = if frontal { &p.frontal } else { &p.sagittal };
        all.iter()
            .filter(|c| c.side.as_str() == side)
            .cloned()
            .collect()
    };
    let mut out: Vec<CycleCurve> = Vec::new();
    for c in group.iter().flat_map(|p| curves_of(p)) {
        match out.iter_mut().find(|o| o.joint == c.joint) {
            Some(o) => *o = pool_two(o, &c),
            None => out.push(c),
        }
    }
    out
}

/// Two curves of one measure pooled point by point (on the first's points).
fn pool_two(a: &CycleCurve, b: &CycleCurve) -> CycleCurve {
    let at = |c: &CycleCurve, i: usize| {
        let (m, sd) = (c.mean.get(i).copied(), c.sd.get(i).copied());
        m.filter(|m| m.is_finite())
            .map(|m| (m, sd.unwrap_or(f64::NAN), c.n_cycles))
    };
    let (mut mean, mut sd) = (Vec::new(), Vec::new());
    for i in 0..a.percent.len() {
        let groups: Vec<(f64, f64, usize)> = [at(a, i), at(b, i)].into_iter().flatten().collect();
        let (m, s, _) = gait_checklist::pool_groups(&groups).unwrap_or((f64::NAN, f64::NAN, 0));
        mean.push(m);
        sd.push(s);
    }
    CycleCurve {
        mean,
        sd,
        n_cycles: a.n_cycles + b.n_cycles,
        ..a.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A side view with `n` left knee cycles of mean `mean` (SD 1) at every point.
    fn pass(view: &str, video: &str, n: usize, mean: f64) -> Pass {
        let knee = CycleCurve {
            side: "left".parse().unwrap(),
            joint: "knee".into(),
            percent: vec![0.0, 50.0, 100.0],
            mean: vec![mean; 3],
            sd: vec![if n > 1 { 1.0 } else { f64::NAN }; 3],
            n_cycles: n,
        };
        Pass::with_curves(view, video, vec![knee])
    }

    /// Two passes from the left: the left knee's cycles of both, weighted by their counts; the
    /// right view (the left limb far) is not mixed in.
    #[test]
    fn the_near_passes_cycles_are_pooled() {
        let passes = [
            pass("left", "a.mp4", 2, 10.0),
            pass("left", "b.mp4", 1, 16.0),
            pass("right", "c.mp4", 3, 40.0),
        ];
        let mut sources = Vec::new();
        let curves = sagittal(&passes, &mut sources);
        let knee = &curves[0];
        assert_eq!((curves.len(), knee.n_cycles), (1, 3));
        assert!(
            knee.mean.iter().all(|m| (m - 12.0).abs() < 1e-12),
            "{knee:?}"
        );
        // Within (1 + 0) + between (2 x 4 + 1 x 16), over 2.
        assert!((knee.sd[0] - 12.5f64.sqrt()).abs() < 1e-12, "{knee:?}");
        assert_eq!(
            sources[0].pass,
            "left view (a.mp4) + left view (b.mp4) (near the camera), 3 cycles pooled"
        );
        // One near pass: its own curve, as before.
        let one = sagittal(&passes[..1], &mut Vec::new());
        assert_eq!((one[0].mean.clone(), one[0].n_cycles), (vec![10.0; 3], 2));
    }
}
