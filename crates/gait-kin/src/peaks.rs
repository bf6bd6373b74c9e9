//! Peaks of a trajectory and how far they stand out: the extrema the event detector turns into
//! heel strikes and toe-offs.

/// A local maximum and its prominence: its height above the higher of the two lowest points on
/// the way down to a higher point on either side. A side that ends (NaN, the end of the signal)
/// before a higher point does not count; when both do, the peak is its run's highest and stands
/// above the lower of the two.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    pub index: usize,
    pub prominence: f64,
}

/// Local maxima with at least `prominence`, at least `min_dist` samples apart (larger wins).
/// NaN splits the signal; extrema at the ends of a run are not peaks.
pub fn find_peaks(x: &[f64], prominence: f64, min_dist: usize) -> Vec<usize> {
    with_prominence(x, prominence, min_dist)
        .into_iter()
        .map(|p| p.index)
        .collect()
}

/// As [`find_peaks`], with each peak's prominence.
pub fn with_prominence(x: &[f64], prominence: f64, min_dist: usize) -> Vec<Peak> {
    let n = x.len();
    let mut peaks = Vec::new();
    let mut i = 1;
    while i + 1 < n {
        if !(x[i].is_finite() && x[i - 1].is_finite()) || x[i] <= x[i - 1] {
            i += 1;
            continue;
        }
        // Plateau: take its middle.
        let mut j = i;
        while j + 1 < n && x[j + 1] == x[i] {
            j += 1;
        }
        if j + 1 < n && x[j + 1].is_finite() && x[j + 1] < x[i] {
            let p = (i + j) / 2;
            // The lowest point on the way down to a higher point, and whether one was reached
            // (else the run ended: a NaN or the end of the signal).
            let side_min = |range: &mut dyn Iterator<Item = usize>| {
                let mut m = x[p];
                for k in range {
                    if !x[k].is_finite() {
                        return (m, false);
                    }
                    if x[k] > x[p] {
                        return (m, true);
                    }
                    m = m.min(x[k]);
                }
                (m, false)
            };
            let left = side_min(&mut (0..p).rev());
            let right = side_min(&mut (p + 1..n));
            // A side cut short by the end of the run has not shown how low it goes: a foot's
            // first peak after the walker comes into view is judged by its other side alone
            // (the sample's first toe-off, 6 frames after she appears, stood out by 60 px on
            // its far side and 20 px on the near one).
            let base = match (left, right) {
                ((l, true), (r, true)) => l.max(r),
                ((l, true), (_, false)) => l,
                ((_, false), (r, true)) => r,
                // The highest point of its run: the deeper side shows its excursion.
                ((l, false), (r, false)) => l.min(r),
            };
            let prom = x[p] - base;
            if prom >= prominence {
                peaks.push(Peak {
                    index: p,
                    prominence: prom,
                });
            }
        }
        i = j + 1;
    }
    // Enforce the minimum distance, highest peaks first.
    let mut order = peaks.clone();
    order.sort_by(|a, b| x[b.index].total_cmp(&x[a.index]));
    let mut keep: Vec<Peak> = Vec::new();
    for p in order {
        if keep.iter().all(|k| k.index.abs_diff(p.index) >= min_dist) {
            keep.push(p);
        }
    }
    keep.sort_unstable_by_key(|p| p.index);
    keep
}

/// The peaks of a foot's forward excursion that are strides, not wobbles: at least `floor`
/// prominent, and at least `share` of the median prominence of those candidates. A foot swings
/// through most of a leg length each stride while a stance foot's keypoint wobbles by a tenth
/// of one; a fixed threshold near the wobbles tipped on a few pixels of encoder noise (the
/// bundled sample re-encoded at H.264 CRF 18 had a stance wobble of 23 px against a threshold
/// of 20 px, where the original's was 12 px, and its strides stood out by 190 px). Each peak
/// keeps its prominence over the threshold, the margin of its decision.
pub fn gait_peaks(x: &[f64], floor: f64, share: f64, min_dist: usize) -> GaitPeaks {
    let candidates = with_prominence(x, floor, min_dist);
    let mut proms: Vec<f64> = candidates.iter().map(|p| p.prominence).collect();
    let typical = crate::tracks::median(&mut proms);
    let threshold = if typical.is_finite() {
        floor.max(share * typical)
    } else {
        floor
    };
    let (kept, dropped): (Vec<Peak>, Vec<Peak>) = candidates
        .into_iter()
        .partition(|p| p.prominence >= threshold);
    GaitPeaks {
        kept,
        threshold,
        strongest_dropped: dropped.iter().map(|p| p.prominence).reduce(f64::max),
    }
}

/// The strides among a trajectory's peaks, with what the decision rested on.
#[derive(Debug, Clone, PartialEq)]
pub struct GaitPeaks {
    pub kept: Vec<Peak>,
    /// The prominence a peak needed.
    pub threshold: f64,
    /// The largest prominence of a candidate that fell short (above the floor).
    pub strongest_dropped: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peaks_need_prominence_and_distance() {
        let x = [0.0, 1.0, 0.0, 5.0, 4.9, 5.1, 0.0, f64::NAN, 3.0, 0.0];
        assert_eq!(find_peaks(&x, 0.5, 1), vec![1, 5]);
        assert_eq!(find_peaks(&x, 2.0, 1), vec![5]);
        assert_eq!(find_peaks(&x, 0.5, 5), vec![5]);
        assert_eq!(find_peaks(&[f64::NAN, 0.0, 3.0, 0.0], 1.0, 1), vec![2]);
        assert!(find_peaks(&[1.0, 2.0, 3.0], 0.0, 1).is_empty());
    }

    /// Three strides of 10 and a wobble of 2.3 between them: the fixed floor of 2 takes the
    /// wobble, the share of the strides' prominence does not.
    #[test]
    fn wobbles_are_not_strides() {
        let mut x = Vec::new();
        for _ in 0..3 {
            x.extend([0.0, 5.0, 10.0, 5.0, 0.0, -2.3, 0.0, -2.3, -4.0, -2.0]);
        }
        let all = find_peaks(&x, 2.0, 1);
        let g = gait_peaks(&x, 2.0, 0.5, 1);
        assert_eq!(
            g.kept.iter().map(|p| p.index).collect::<Vec<_>>(),
            vec![2, 12, 22]
        );
        assert!(all.len() > g.kept.len(), "{all:?}");
        assert!(g.threshold > 2.3 && g.threshold < 10.0, "{}", g.threshold);
        assert!(g.strongest_dropped.is_some_and(|d| (d - 2.3).abs() < 1e-9));
    }
}
