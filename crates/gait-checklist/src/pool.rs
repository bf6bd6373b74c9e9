//! One verdict from several passes' verdicts of one item and side. A side view sees one leg near
//! the camera and the other far, and an item that weighs one leg against the other reads the
//! near leg's keypoints differently from the far leg's: the bundled sample's healthy walker
//! shows vaulting of +3 % of the leg on her far side from the left view, and the mirrored copy
//! (a right view) -3 %. Over a left and a right view that bias cancels, and the cycles of both
//! count.

use crate::verdict::{Status, Verdict};

/// The items whose cycles are pooled over a visit's side views (each judged per cycle, less
/// the other side's mean, by [`crate::judge`]'s rule).
pub const POOLED_OVER_VIEWS: [&str; 1] = [crate::vaulting::VAULTING.id];

/// Groups of values given as (mean, SD, count) pooled into one: the mean weighted by the counts,
/// the SD of all values (within each group plus the groups' spread about the pooled mean; NaN
/// for one value), the count. A group's SD that is not a number (one value) adds nothing within.
pub fn pool_groups(groups: &[(f64, f64, usize)]) -> Option<(f64, f64, usize)> {
    let n: usize = groups.iter().map(|g| g.2).sum();
    if n == 0 {
        return None;
    }
    let mean = groups.iter().map(|g| g.0 * g.2 as f64).sum::<f64>() / n as f64;
    let ss: f64 = groups
        .iter()
        .map(|&(m, sd, k)| {
            let within = if sd.is_finite() {
                sd * sd * (k as f64 - 1.0)
            } else {
                0.0
            };
            within + k as f64 * (m - mean).powi(2)
        })
        .sum();
    let sd = if n > 1 {
        (ss / (n as f64 - 1.0)).sqrt()
    } else {
        f64::NAN
    };
    Some((mean, sd, n))
}

/// `verdicts` of one item and side, each judged, pooled: the mean over all their cycles, the
/// spread within and between them, and the same rule as one pass's (present when the mean lies
/// past the threshold by at least its standard error). The frames to review are those of the
/// verdict with the most cycles past the threshold. `None` for fewer than two verdicts.
pub fn pooled(verdicts: &[&Verdict]) -> Option<Verdict> {
    let judged: Vec<&Verdict> = verdicts
        .iter()
        .copied()
        .filter(|v| v.status != Status::NotAssessable && v.n > 0 && v.value.is_finite())
        .collect();
    if judged.len() < 2 {
        return None;
    }
    let on = |v: &Verdict| v.judged.unwrap_or(v.value);
    let groups: Vec<(f64, f64, usize)> = judged.iter().map(|v| (on(v), v.spread, v.n)).collect();
    let (mean, spread, n) = pool_groups(&groups)?;
    // A signed value judged on its size (the whip) is reported as the signed values' mean.
    let signed = judged.iter().any(|v| v.judged.is_some()).then(|| {
        let w: f64 = judged.iter().map(|v| v.value * v.n as f64).sum();
        w / n as f64
    });
    let first = judged[0];
    let past = crate::judge::past(first.beyond, first.threshold, mean);
    let se = spread / (n as f64).sqrt();
    let hits: usize = judged.iter().map(|v| v.cycles.len()).sum();
    let (present, reason) = crate::judge::consistent(past, se, (hits, n), &first.unit);
    let links = judged
        .iter()
        .max_by_key(|v| v.cycles.len())
        .copied()
        .unwrap_or(first);
    Some(Verdict {
        status: if present {
            Status::Present
        } else {
            Status::Absent
        },
        value: signed.unwrap_or(mean),
        judged: signed.map(|_| mean),
        spread,
        n,
        cycles: links.cycles.clone(),
        frames: links.frames.clone(),
        run: links.run.clone(),
        reason,
        ..first.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Side;
    use crate::vaulting::VAULTING;

    fn judged(value: f64, spread: f64, n: usize, hits: usize) -> Verdict {
        Verdict {
            status: Status::Absent,
            value,
            spread,
            n,
            threshold: 4.0,
            beyond: "above",
            cycles: vec![10; hits],
            frames: vec![20; hits],
            ..Verdict::not_assessable(VAULTING, Side::Right, "")
        }
    }

    #[test]
    fn a_near_and_a_far_views_bias_cancels() {
        // The sample's walk: +3 % from one view, -3 % from the mirrored one.
        let (a, b) = (judged(3.0, 1.0, 3, 0), judged(-3.0, 1.0, 2, 0));
        let p = pooled(&[&a, &b]).unwrap();
        assert_eq!((p.n, p.status), (5, Status::Absent));
        assert!((p.value - 0.6).abs() < 1e-12, "{}", p.value);
        // Vaulting seen in both views, as a planted 6 cm reads (7.5 and 7.0 %).
        let (a, b) = (judged(7.5, 1.0, 3, 3), judged(7.0, 1.0, 3, 3));
        let p = pooled(&[&a, &b]).unwrap();
        assert_eq!((p.status, p.cycles.len()), (Status::Present, 3));
    }

    #[test]
    fn one_outlying_cycle_is_not_consistent() {
        // One view's three cycles of 5, 3.3 and 19 % (mean 9.3, SD 8.9), the other view's 1.4.
        let (a, b) = (judged(9.26, 8.885, 3, 2), judged(1.41, f64::NAN, 1, 0));
        let p = pooled(&[&a, &b]).unwrap();
        assert_eq!(p.status, Status::Absent);
        assert!(p.reason.starts_with("not consistent"), "{}", p.reason);
        // A single verdict is not pooled.
        assert!(pooled(&[&a]).is_none());
    }
}
