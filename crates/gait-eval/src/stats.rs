//! Mean and standard deviation of error samples.

use serde::{Deserialize, Serialize};

/// Count, mean and sample standard deviation (n - 1 in the denominator) of a
/// set of errors; `mean` is `None` without samples, `sd` with fewer than two.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    pub n: usize,
    pub mean: Option<f64>,
    pub sd: Option<f64>,
}

impl Stat {
    pub fn of(values: &[f64]) -> Stat {
        let n = values.len();
        if n == 0 {
            return Stat {
                n,
                mean: None,
                sd: None,
            };
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let sd = (n > 1).then(|| {
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        });
        Stat {
            n,
            mean: Some(mean),
            sd,
        }
    }

    /// Statistics of the union of the samples behind `parts` (exact pooling of
    /// counts, means and sample variances).
    pub fn pool(parts: &[Stat]) -> Stat {
        let parts: Vec<(usize, f64, f64)> = parts
            .iter()
            .filter_map(|s| Some((s.n, s.mean?, s.sd.unwrap_or(0.0))))
            .filter(|p| p.0 > 0)
            .collect();
        let n: usize = parts.iter().map(|p| p.0).sum();
        if n == 0 {
            return Stat {
                n: 0,
                mean: None,
                sd: None,
            };
        }
        let mean = parts.iter().map(|p| p.0 as f64 * p.1).sum::<f64>() / n as f64;
        let ss: f64 = parts
            .iter()
            .map(|&(k, m, s)| (k as f64 - 1.0) * s * s + k as f64 * (m - mean).powi(2))
            .sum();
        Stat {
            n,
            mean: Some(mean),
            sd: (n > 1).then(|| (ss / (n - 1) as f64).sqrt()),
        }
    }

    /// "12.01 (3.54)" as in the paper's table; "–" without samples.
    pub fn cell(&self) -> String {
        match (self.mean, self.sd) {
            (Some(m), Some(s)) => format!("{m:.2} ({s:.2})"),
            (Some(m), None) => format!("{m:.2}"),
            _ => "–".into(),
        }
    }
}

/// Median (mean of the two middle values for an even count); `None` when empty.
pub(crate) fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_sd_median() {
        let s = Stat::of(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(s.mean, Some(5.0));
        assert!((s.sd.unwrap() - (32.0f64 / 7.0).sqrt()).abs() < 1e-12);
        assert_eq!(s.cell(), "5.00 (2.14)");
        assert_eq!(Stat::of(&[1.0]).sd, None);
        assert_eq!(Stat::of(&[]).cell(), "–");
        let (a, b) = ([1.0, 2.0, 4.0], [7.0, 8.0]);
        let pooled = Stat::pool(&[Stat::of(&a), Stat::of(&b)]);
        let all = Stat::of(&[1.0, 2.0, 4.0, 7.0, 8.0]);
        assert_eq!(pooled.n, 5);
        assert!((pooled.mean.unwrap() - all.mean.unwrap()).abs() < 1e-12);
        assert!((pooled.sd.unwrap() - all.sd.unwrap()).abs() < 1e-12);
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), Some(2.5));
    }
}
