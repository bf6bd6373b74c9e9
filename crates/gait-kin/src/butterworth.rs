//! Butterworth low-pass design and zero-phase filtering, matching scipy's `butter` and `filtfilt`.

use crate::smooth::Smoother;

/// Minimal complex number for the pole/zero algebra of the design.
#[derive(Debug, Clone, Copy)]
struct C {
    re: f64,
    im: f64,
}

impl C {
    fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn div(self, o: C) -> C {
        let d = o.re * o.re + o.im * o.im;
        C::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}

/// Coefficients `(b, a)` of a digital low-pass Butterworth filter, as scipy's
/// `butter(order, cutoff_hz, fs=fs)`: analog prototype, pre-warping, bilinear transform.
pub fn design_lowpass(order: usize, cutoff_hz: f64, fs: f64) -> (Vec<f64>, Vec<f64>) {
    let n = order as f64;
    // Analog prototype poles on the unit circle, left half-plane.
    let poles: Vec<C> = (0..order)
        .map(|k| {
            let m = -(n - 1.0) + 2.0 * k as f64;
            let theta = std::f64::consts::PI * m / (2.0 * n);
            // -exp(j*theta)
            C::new(-theta.cos(), -theta.sin())
        })
        .collect();
    // Normalised frequency as scipy computes it (fs = 2 after normalisation).
    let wn = 2.0 * cutoff_hz / fs;
    let fs_norm = 2.0;
    let warped = 2.0 * fs_norm * (std::f64::consts::PI * wn / fs_norm).tan();
    let p: Vec<C> = poles
        .iter()
        .map(|p| C::new(p.re * warped, p.im * warped))
        .collect();
    let k = warped.powi(order as i32);
    // Bilinear transform with fs2 = 2 * fs_norm; all zeros land at z = -1.
    let fs2 = C::new(2.0 * fs_norm, 0.0);
    let pz: Vec<C> = p.iter().map(|&p| fs2.add(p).div(fs2.sub(p))).collect();
    let mut denom = C::new(1.0, 0.0);
    for &p in &p {
        denom = denom.mul(fs2.sub(p));
    }
    let kz = k * C::new(1.0, 0.0).div(denom).re;
    let zz = vec![C::new(-1.0, 0.0); order];
    let b: Vec<f64> = poly(&zz).iter().map(|c| kz * c.re).collect();
    let a: Vec<f64> = poly(&pz).iter().map(|c| c.re).collect();
    (b, a)
}

/// Monic polynomial with the given roots (numpy's `poly`), highest power first.
fn poly(roots: &[C]) -> Vec<C> {
    let mut c = vec![C::new(1.0, 0.0)];
    for &r in roots {
        let mut next = vec![C::new(0.0, 0.0); c.len() + 1];
        for (i, &ci) in c.iter().enumerate() {
            next[i] = next[i].add(ci);
            next[i + 1] = next[i + 1].sub(ci.mul(r));
        }
        c = next;
    }
    c
}

/// Steady-state initial conditions of `lfilter` for a unit step (scipy's `lfilter_zi`).
fn lfilter_zi(b: &[f64], a: &[f64]) -> Vec<f64> {
    let n = a.len().max(b.len());
    let a0 = a[0];
    let pad = |v: &[f64]| {
        let mut out: Vec<f64> = v.iter().map(|x| x / a0).collect();
        out.resize(n, 0.0);
        out
    };
    let (b, a) = (pad(b), pad(a));
    // Closed form of solving (I - A^T) zi = b[1:] - a[1:] b[0] for the companion matrix A.
    let sum_a: f64 = a.iter().sum();
    let sum_b: f64 = (1..n).map(|i| b[i] - a[i] * b[0]).sum();
    let mut zi = vec![0.0; n - 1];
    if n < 2 {
        return zi;
    }
    zi[0] = sum_b / sum_a;
    let (mut asum, mut csum) = (1.0, 0.0);
    for k in 1..n - 1 {
        asum += a[k];
        csum += b[k] - a[k] * b[0];
        zi[k] = asum * zi[0] - csum;
    }
    zi
}

/// Direct form II transposed IIR filter (scipy's `lfilter`) starting from state `zi`.
fn lfilter(b: &[f64], a: &[f64], x: &[f64], mut z: Vec<f64>) -> Vec<f64> {
    let n = a.len().max(b.len());
    let a0 = a[0];
    let coef = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0) / a0;
    let mut y = Vec::with_capacity(x.len());
    for &xi in x {
        let yi = coef(b, 0) * xi + z.first().copied().unwrap_or(0.0);
        for i in 0..n.saturating_sub(1) {
            let next = if i + 1 < n - 1 { z[i + 1] } else { 0.0 };
            z[i] = coef(b, i + 1) * xi + next - coef(a, i + 1) * yi;
        }
        y.push(yi);
    }
    y
}

/// Forward-backward filtering with odd extension, as scipy's `filtfilt(b, a, x)` with its
/// default `padtype="odd"`, `padlen = 3 * max(len(a), len(b))`. Signals not longer than that
/// padding (where scipy raises) use `padlen = len - 1`; fewer than 2 samples are returned as is.
pub fn filtfilt(b: &[f64], a: &[f64], x: &[f64]) -> Vec<f64> {
    let len = x.len();
    if len < 2 {
        return x.to_vec();
    }
    let padlen = (3 * a.len().max(b.len())).min(len - 1);
    let mut ext = Vec::with_capacity(len + 2 * padlen);
    for i in (1..=padlen).rev() {
        ext.push(2.0 * x[0] - x[i]);
    }
    ext.extend_from_slice(x);
    for i in 1..=padlen {
        ext.push(2.0 * x[len - 1] - x[len - 1 - i]);
    }
    let zi = lfilter_zi(b, a);
    let scaled = |s: f64| zi.iter().map(|z| z * s).collect::<Vec<_>>();
    let fwd = lfilter(b, a, &ext, scaled(ext[0]));
    let mut rev: Vec<f64> = fwd.into_iter().rev().collect();
    let first = rev[0];
    rev = lfilter(b, a, &rev, scaled(first));
    rev.reverse();
    rev[padlen..padlen + len].to_vec()
}

/// Zero-phase low-pass Butterworth smoother (the paper's 4th order, 6 Hz by default).
#[derive(Debug, Clone)]
pub struct Butterworth {
    pub order: usize,
    pub cutoff_hz: f64,
}

impl Smoother for Butterworth {
    fn smooth(&self, x: &[f64], fps: f64) -> Vec<f64> {
        let (b, a) = design_lowpass(self.order, self.cutoff_hz, fps);
        filtfilt(&b, &a, x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_dc_gain_and_constant_passthrough() {
        let (b, a) = design_lowpass(4, 6.0, 30.0);
        let gain = b.iter().sum::<f64>() / a.iter().sum::<f64>();
        assert!((gain - 1.0).abs() < 1e-12, "{gain}");
        let y = filtfilt(&b, &a, &[3.5; 40]);
        assert!(y.iter().all(|v| (v - 3.5).abs() < 1e-9));
        assert_eq!(filtfilt(&b, &a, &[1.0]), vec![1.0]);
        // Shorter than scipy's padding: still finite and near the straight line.
        let short: Vec<f64> = (0..5).map(|i| i as f64).collect();
        let y = filtfilt(&b, &a, &short);
        assert!(
            y.iter().zip(&short).all(|(a, b)| (a - b).abs() < 0.2),
            "{y:?}"
        );
    }
}
