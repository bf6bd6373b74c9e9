//! Keypoint candidates: local maxima of the Gaussian-smoothed heatmaps.

use super::gaussian::gaussian_filter;

/// A keypoint candidate, in full-resolution pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    pub x: usize,
    pub y: usize,
    /// The unsmoothed heatmap at the peak.
    pub score: f64,
    /// Position in the list of all peaks (ids run over parts in order).
    pub id: usize,
}

/// Peaks of one part's heatmap: the smoothed map is `>=` its four
/// neighbours (0 outside the map) and `> thresh`; row-major order, ids from
/// `first_id`. NaN never makes a peak.
pub(crate) fn find_peaks(
    map: &[f64],
    width: usize,
    height: usize,
    sigma: f64,
    thresh: f64,
    first_id: usize,
) -> Vec<Peak> {
    let smooth = gaussian_filter(map, width, height, sigma, 4.0);
    let at = |x: isize, y: isize| -> f64 {
        if x < 0 || y < 0 || x >= width as isize || y >= height as isize {
            0.0
        } else {
            smooth[y as usize * width + x as usize]
        }
    };
    let mut peaks = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let v = smooth[y * width + x];
            let (xi, yi) = (x as isize, y as isize);
            if v >= at(xi, yi - 1)
                && v >= at(xi, yi + 1)
                && v >= at(xi - 1, yi)
                && v >= at(xi + 1, yi)
                && v > thresh
            {
                peaks.push(Peak {
                    x,
                    y,
                    score: map[y * width + x],
                    id: first_id + peaks.len(),
                });
            }
        }
    }
    peaks
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_bump_gives_one_peak_and_nan_none() {
        let (w, h) = (20, 15);
        let mut map = vec![0.0; w * h];
        map[7 * w + 11] = 50.0;
        let p = find_peaks(&map, w, h, 3.0, 0.1, 4);
        assert_eq!(p.len(), 1);
        assert_eq!((p[0].x, p[0].y, p[0].score, p[0].id), (11, 7, 50.0, 4));
        let nan = vec![f64::NAN; w * h];
        assert!(find_peaks(&nan, w, h, 3.0, 0.1, 0).is_empty());
        assert!(find_peaks(&[], 0, 0, 3.0, 0.1, 0).is_empty());
    }
}
