//! Gap filling: not-a-knot cubic spline (scipy `CubicSpline` default) and a linear fallback.

/// Fills gaps (NaN runs) of at most `max_gap` samples strictly inside the track; leading and
/// trailing gaps and longer gaps stay NaN. Returns the gaps left empty as `(start, len)`.
pub trait GapFiller {
    fn fill(&self, x: &mut [f64], max_gap: usize) -> Vec<(usize, usize)>;
}

/// Interior NaN runs `(start, len)`, plus whether each is bounded on both sides.
fn gaps(x: &[f64]) -> Vec<(usize, usize, bool)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < x.len() {
        if x[i].is_finite() {
            i += 1;
            continue;
        }
        let start = i;
        while i < x.len() && !x[i].is_finite() {
            i += 1;
        }
        out.push((start, i - start, start > 0 && i < x.len()));
    }
    out
}

/// A gap in the middle of a present track, too long to fill: reported. Missing data at the ends
/// is not a gap (the person is not yet or no longer tracked).
fn fill_with(
    x: &mut [f64],
    max_gap: usize,
    mut value: impl FnMut(usize) -> f64,
) -> Vec<(usize, usize)> {
    let mut left = Vec::new();
    for (start, len, interior) in gaps(x) {
        if !interior {
            continue;
        }
        if len > max_gap {
            left.push((start, len));
            continue;
        }
        for (i, v) in x.iter_mut().enumerate().skip(start).take(len) {
            *v = value(i);
        }
    }
    left
}

/// scipy's `CubicSpline(t_kept, x_kept)` (not-a-knot ends) through every kept sample.
#[derive(Debug, Clone, Default)]
pub struct CubicSplineFill;

impl GapFiller for CubicSplineFill {
    fn fill(&self, x: &mut [f64], max_gap: usize) -> Vec<(usize, usize)> {
        let t: Vec<f64> = (0..x.len())
            .filter(|&i| x[i].is_finite())
            .map(|i| i as f64)
            .collect();
        let y: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
        match CubicSpline::new(&t, &y) {
            Some(s) => fill_with(x, max_gap, |i| s.eval(i as f64)),
            None => gaps(x)
                .into_iter()
                .filter(|g| g.2)
                .map(|(s, l, _)| (s, l))
                .collect(),
        }
    }
}

/// Straight line between the samples either side of each gap.
#[derive(Debug, Clone, Default)]
pub struct LinearFill;

impl GapFiller for LinearFill {
    fn fill(&self, x: &mut [f64], max_gap: usize) -> Vec<(usize, usize)> {
        let src = x.to_vec();
        fill_with(x, max_gap, |i| {
            let lo = (0..i).rev().find(|&j| src[j].is_finite()).unwrap_or(i);
            let hi = (i + 1..src.len())
                .find(|&j| src[j].is_finite())
                .unwrap_or(i);
            if lo == hi {
                return f64::NAN;
            }
            let w = (i - lo) as f64 / (hi - lo) as f64;
            src[lo] * (1.0 - w) + src[hi] * w
        })
    }
}

/// Leaves gaps empty; every interior gap is reported.
#[derive(Debug, Clone, Default)]
pub struct NoFill;

impl GapFiller for NoFill {
    fn fill(&self, x: &mut [f64], _max_gap: usize) -> Vec<(usize, usize)> {
        fill_with(x, 0, |_| f64::NAN)
    }
}

/// Piecewise cubic with C2 continuity and scipy's not-a-knot end conditions.
#[derive(Debug, Clone)]
pub struct CubicSpline {
    t: Vec<f64>,
    /// Per interval: coefficients of (dt^3, dt^2, dt, 1).
    c: Vec<[f64; 4]>,
}

impl CubicSpline {
    /// Needs at least two strictly increasing knots; `None` otherwise.
    pub fn new(t: &[f64], y: &[f64]) -> Option<Self> {
        let n = t.len();
        if n < 2 || y.len() != n || t.windows(2).any(|w| w[1] <= w[0]) {
            return None;
        }
        let dx: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let slope: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / dx[i]).collect();
        // Derivatives s at the knots, as scipy solves for them.
        let s: Vec<f64> = if n == 2 {
            vec![slope[0]; 2]
        } else if n == 3 {
            // Not-a-knot on three points: the parabola through them.
            let a = [
                [1.0, 1.0, 0.0],
                [dx[1], 2.0 * (dx[0] + dx[1]), dx[0]],
                [0.0, 1.0, 1.0],
            ];
            let b = [
                2.0 * slope[0],
                3.0 * (dx[0] * slope[1] + dx[1] * slope[0]),
                2.0 * slope[1],
            ];
            solve3(a, b)?.to_vec()
        } else {
            let mut lower = vec![0.0; n];
            let mut diag = vec![0.0; n];
            let mut upper = vec![0.0; n];
            let mut b = vec![0.0; n];
            for i in 1..n - 1 {
                lower[i] = dx[i];
                diag[i] = 2.0 * (dx[i - 1] + dx[i]);
                upper[i] = dx[i - 1];
                b[i] = 3.0 * (dx[i] * slope[i - 1] + dx[i - 1] * slope[i]);
            }
            let d0 = t[2] - t[0];
            diag[0] = dx[1];
            upper[0] = d0;
            b[0] = ((dx[0] + 2.0 * d0) * dx[1] * slope[0] + dx[0] * dx[0] * slope[1]) / d0;
            let dn = t[n - 1] - t[n - 3];
            diag[n - 1] = dx[n - 3];
            lower[n - 1] = dn;
            b[n - 1] = (dx[n - 2] * dx[n - 2] * slope[n - 3]
                + (2.0 * dn + dx[n - 2]) * dx[n - 3] * slope[n - 2])
                / dn;
            solve_tridiagonal(&lower, &diag, &upper, &b)?
        };
        let c = (0..n - 1)
            .map(|i| {
                let tt = (s[i] + s[i + 1] - 2.0 * slope[i]) / dx[i];
                [tt / dx[i], (slope[i] - s[i]) / dx[i] - tt, s[i], y[i]]
            })
            .collect();
        Some(Self { t: t.to_vec(), c })
    }

    /// Value at `x` (extrapolates with the end polynomials, like scipy).
    pub fn eval(&self, x: f64) -> f64 {
        let last = self.c.len() - 1;
        // Interval i with t[i] <= x < t[i+1]; the last one also takes x >= t[last].
        let i = self
            .t
            .partition_point(|&k| k <= x)
            .saturating_sub(1)
            .min(last);
        let d = x - self.t[i];
        let c = self.c[i];
        ((c[0] * d + c[1]) * d + c[2]) * d + c[3]
    }
}

/// Gaussian elimination with partial pivoting for the 3x3 not-a-knot system.
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    for col in 0..3 {
        let piv = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col] == 0.0 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for r in col + 1..3 {
            let f = a[r][col] / a[col][col];
            let pivot_row = a[col];
            for (ark, ack) in a[r].iter_mut().zip(pivot_row).skip(col) {
                *ark -= f * ack;
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for r in (0..3).rev() {
        let s: f64 = (r + 1..3).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    Some(x)
}

/// Tridiagonal solve with partial pivoting (LAPACK gtsv style, fill-in kept in `u2`).
fn solve_tridiagonal(lower: &[f64], diag: &[f64], upper: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let n = diag.len();
    // Row i holds (d[i], u1[i], u2[i]) at columns i, i+1, i+2 after elimination.
    let mut d = diag.to_vec();
    let mut u1: Vec<f64> = (0..n)
        .map(|i| if i + 1 < n { upper[i] } else { 0.0 })
        .collect();
    let mut u2 = vec![0.0; n];
    let mut l: Vec<f64> = (0..n)
        .map(|i| if i + 1 < n { lower[i + 1] } else { 0.0 })
        .collect();
    let mut rhs = b.to_vec();
    for i in 0..n - 1 {
        // Row i+1 currently: l[i] at column i, d[i+1] at i+1, u1[i+1] at i+2.
        if l[i].abs() > d[i].abs() {
            // Swap rows i and i+1.
            let (di, u1i, u2i) = (d[i], u1[i], u2[i]);
            d[i] = l[i];
            u1[i] = d[i + 1];
            u2[i] = u1[i + 1];
            l[i] = di;
            d[i + 1] = u1i;
            u1[i + 1] = u2i;
            rhs.swap(i, i + 1);
        }
        if d[i] == 0.0 {
            return None;
        }
        let f = l[i] / d[i];
        d[i + 1] -= f * u1[i];
        u1[i + 1] -= f * u2[i];
        rhs[i + 1] -= f * rhs[i];
        l[i] = 0.0;
    }
    if d[n - 1] == 0.0 {
        return None;
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = rhs[i];
        if i + 1 < n {
            s -= u1[i] * x[i + 1];
        }
        if i + 2 < n {
            s -= u2[i] * x[i + 2];
        }
        x[i] = s / d[i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_cubics_exactly() {
        // Not-a-knot reproduces any cubic polynomial.
        let f = |t: f64| 0.5 * t * t * t - 2.0 * t * t + t - 3.0;
        let t = [0.0, 1.0, 2.5, 3.0, 4.5, 7.0];
        let y: Vec<f64> = t.iter().map(|&v| f(v)).collect();
        let s = CubicSpline::new(&t, &y).unwrap();
        for x in [0.3, 1.7, 2.9, 5.0, 6.9] {
            assert!((s.eval(x) - f(x)).abs() < 1e-9, "{x}");
        }
    }

    #[test]
    fn fills_only_short_interior_gaps() {
        let nan = f64::NAN;
        let mut x = [nan, 1.0, 2.0, nan, 4.0, nan, nan, nan, 8.0, 9.0, nan];
        let left = LinearFill.fill(&mut x, 2);
        assert_eq!(x[3], 3.0);
        assert!(x[0].is_nan() && x[6].is_nan() && x[10].is_nan());
        assert_eq!(left, vec![(5, 3)]);
        let mut y = [nan, nan];
        assert!(CubicSplineFill.fill(&mut y, 5).is_empty());
        let mut z = [1.0, nan, 3.0];
        assert_eq!(NoFill.fill(&mut z, 5), vec![(1, 1)]);
        assert!(CubicSpline::new(&[0.0, 0.0], &[1.0, 2.0]).is_none());
    }
}
