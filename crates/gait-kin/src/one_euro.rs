//! One-Euro filter (Casiez, Roussel & Vogel, CHI 2012), the alternative smoother.

use crate::smooth::Smoother;

/// Adaptive low-pass: cut-off `min_cutoff_hz + beta * |speed|`, speed from a derivative
/// smoothed at `d_cutoff_hz`. Causal, so it lags; useful for live previews and ablations.
#[derive(Debug, Clone)]
pub struct OneEuro {
    pub min_cutoff_hz: f64,
    pub beta: f64,
    pub d_cutoff_hz: f64,
}

fn alpha(cutoff_hz: f64, fps: f64) -> f64 {
    let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff_hz);
    let te = 1.0 / fps;
    1.0 / (1.0 + tau / te)
}

impl Smoother for OneEuro {
    fn smooth(&self, x: &[f64], fps: f64) -> Vec<f64> {
        let mut out = Vec::with_capacity(x.len());
        let Some(&first) = x.first() else { return out };
        let (mut prev, mut dprev) = (first, 0.0);
        out.push(first);
        for &v in &x[1..] {
            let d = (v - prev) * fps;
            let ad = alpha(self.d_cutoff_hz, fps);
            dprev = ad * d + (1.0 - ad) * dprev;
            let a = alpha(self.min_cutoff_hz + self.beta * dprev.abs(), fps);
            prev = a * v + (1.0 - a) * prev;
            out.push(prev);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduces_jitter_and_tracks_constants() {
        let f = OneEuro {
            min_cutoff_hz: 1.0,
            beta: 0.0,
            d_cutoff_hz: 1.0,
        };
        assert!(
            f.smooth(&[5.0; 20], 30.0)
                .iter()
                .all(|v| (v - 5.0).abs() < 1e-12)
        );
        let noisy: Vec<f64> = (0..200)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let y = f.smooth(&noisy, 30.0);
        let tail = y[100..].iter().map(|v| v.abs()).fold(0.0, f64::max);
        assert!(tail < 0.2, "{tail}");
        assert!(f.smooth(&[], 30.0).is_empty());
    }
}
