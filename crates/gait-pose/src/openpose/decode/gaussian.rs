//! `scipy.ndimage.gaussian_filter` on a 2-D `f64` map: separable correlation
//! along rows then columns, radius `int(truncate * sigma + 0.5)`, border mode
//! `reflect` (half-sample symmetric), summed in scipy's order.

/// Smooths a `width` x `height` row-major map (returned unchanged when empty or `sigma <= 0`).
pub fn gaussian_filter(
    map: &[f64],
    width: usize,
    height: usize,
    sigma: f64,
    truncate: f64,
) -> Vec<f64> {
    let positive = sigma > 0.0;
    if width == 0 || height == 0 || map.len() != width * height || !positive {
        return map.to_vec();
    }
    let w = kernel(sigma, truncate);
    let mut tmp = vec![0.0; map.len()];
    let mut line = Vec::new();
    let mut out_line = Vec::new();
    // Axis 0 (down the columns) first, as scipy loops over axes in order.
    for x in 0..width {
        line.clear();
        line.extend((0..height).map(|y| map[y * width + x]));
        correlate(&line, &w, &mut out_line);
        for (y, v) in out_line.iter().enumerate() {
            tmp[y * width + x] = *v;
        }
    }
    let mut out = vec![0.0; map.len()];
    for y in 0..height {
        correlate(&tmp[y * width..(y + 1) * width], &w, &mut out_line);
        out[y * width..(y + 1) * width].copy_from_slice(&out_line);
    }
    out
}

/// The normalised kernel, summed with numpy's pairwise summation.
fn kernel(sigma: f64, truncate: f64) -> Vec<f64> {
    let radius = (truncate * sigma + 0.5) as i64;
    let factor = -0.5 / (sigma * sigma);
    let phi: Vec<f64> = (-radius..=radius)
        .map(|x| (factor * (x * x) as f64).exp())
        .collect();
    let total = numpy_sum(&phi);
    phi.iter().map(|p| p / total).collect()
}

/// `np.sum` of a short contiguous float64 array (pairwise with 8 accumulators).
fn numpy_sum(a: &[f64]) -> f64 {
    if a.len() < 8 {
        return a.iter().fold(0.0, |s, v| s + v);
    }
    if a.len() > 128 {
        let half = a.len() / 2 / 8 * 8;
        return numpy_sum(&a[..half]) + numpy_sum(&a[half..]);
    }
    let mut r = [0.0; 8];
    r.copy_from_slice(&a[..8]);
    let mut i = 8;
    while i < a.len() - a.len() % 8 {
        for j in 0..8 {
            r[j] += a[i + j];
        }
        i += 8;
    }
    let mut res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for v in &a[i..] {
        res += v;
    }
    res
}

/// Index into a line of length `n` extended by half-sample reflection.
fn reflect(i: isize, n: usize) -> usize {
    let period = 2 * n as isize;
    let m = i.rem_euclid(period);
    if m < n as isize {
        m as usize
    } else {
        (period - 1 - m) as usize
    }
}

/// Symmetric 1-D correlation, outermost taps first (scipy's `NI_Correlate1D`).
fn correlate(line: &[f64], w: &[f64], out: &mut Vec<f64>) {
    let n = line.len();
    let r = (w.len() / 2) as isize;
    let ext: Vec<f64> = (-r..n as isize + r).map(|i| line[reflect(i, n)]).collect();
    out.clear();
    for l in 0..n as isize {
        let c = l + r;
        let mut v = ext[c as usize] * w[r as usize];
        for j in (1..=r).rev() {
            v += (ext[(c - j) as usize] + ext[(c + j) as usize]) * w[(r - j) as usize];
        }
        out.push(v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_is_normalised_with_radius_twelve() {
        let k = kernel(3.0, 4.0);
        assert_eq!(k.len(), 25);
        assert!((k.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn reflection_repeats_for_short_lines() {
        let idx: Vec<usize> = (-4..6).map(|i| reflect(i, 2)).collect();
        assert_eq!(idx, vec![0, 1, 1, 0, 0, 1, 1, 0, 0, 1]);
    }

    #[test]
    fn constant_map_is_unchanged_and_tiny_maps_work() {
        let out = gaussian_filter(&[2.0; 6], 3, 2, 3.0, 4.0);
        assert!(out.iter().all(|v| (v - 2.0).abs() < 1e-12));
        assert_eq!(gaussian_filter(&[1.0], 1, 1, 3.0, 4.0), vec![1.0]);
    }
}
