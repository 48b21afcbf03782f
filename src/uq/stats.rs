//! Statistics of one quantity of interest over the samples that succeeded: moments,
//! percentiles (linear interpolation between order statistics, numpy's default), the 95 %
//! confidence interval of the mean (Student t) and of a percentile (order statistics,
//! distribution-free: the ranks whose binomial coverage is ≥ 95 %), exceedance
//! probabilities with Wilson intervals, and how the mean and P90 settle as N grows.

use serde::Serialize;
use statrs::distribution::{Binomial, ContinuousCDF, DiscreteCDF, StudentsT};

/// Percentile `p` (0–100) of sorted data, linear between order statistics.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = (sorted.len() - 1) as f64 * (p / 100.0).clamp(0.0, 1.0);
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// The distribution-free 95 % confidence interval of percentile `p` from sorted data: order
/// statistics `x_(l)`, `x_(u)` with `P(l ≤ B < u) ≥ 0.95` for `B ~ Binomial(n, p/100)`,
/// chosen as near the median rank as the coverage allows; `None` when `n` is too small for
/// any pair to cover 95 % (e.g. P90 below 29 samples).
pub fn percentile_ci(sorted: &[f64], p: f64) -> Option<(f64, f64)> {
    let n = sorted.len();
    if n < 2 {
        return None;
    }
    let q = (p / 100.0).clamp(0.0, 1.0);
    let b = Binomial::new(q, n as u64).ok()?;
    // P(l ≤ B ≤ u − 1) = F(u − 1) − F(l − 1), ranks 1-based.
    let cover = |l: usize, u: usize| -> f64 {
        let upper = b.cdf(u as u64 - 1);
        let lower = if l >= 1 { b.cdf(l as u64 - 1) } else { 0.0 };
        upper - lower
    };
    let centre = ((n as f64 + 1.0) * q).round().clamp(1.0, n as f64) as usize;
    let (mut l, mut u) = (centre, centre);
    while cover(l, u) < 0.95 {
        let can_down = l > 1;
        let can_up = u < n;
        if !can_down && !can_up {
            return None;
        }
        // Widen on the side that adds more probability.
        let down = if can_down { cover(l - 1, u) } else { -1.0 };
        let up = if can_up { cover(l, u + 1) } else { -1.0 };
        if down >= up {
            l -= 1;
        } else {
            u += 1;
        }
    }
    Some((sorted[l - 1], sorted[u - 1]))
}

/// Probability that the quantity exceeds a threshold, with its Wilson 95 % interval.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Exceedance {
    /// The threshold.
    pub threshold: f64,
    /// Fraction of the samples above it.
    pub probability: f64,
    /// Wilson 95 % interval of that probability.
    pub ci95: (f64, f64),
}

/// A proportion of samples (`count` of `of`), with its Wilson 95 % interval.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Proportion {
    /// Samples counted.
    pub count: usize,
    /// Of these samples.
    pub of: usize,
    /// `count / of` (NaN where `of` is 0).
    pub probability: f64,
    /// Wilson 95 % interval of that probability.
    pub ci95: (f64, f64),
}

impl Proportion {
    /// `count` of `of`.
    pub fn of(count: usize, of: usize) -> Self {
        Proportion {
            count,
            of,
            probability: count as f64 / of as f64,
            ci95: wilson(count, of),
        }
    }
}

/// Wilson's 95 % interval of a proportion `k/n`.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_984_540_054;
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let denom = 1.0 + z * z / n;
    let centre = (p + z * z / (2.0 * n)) / denom;
    let half = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// The mean and P90 after the first `n` samples (the estimates' convergence).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Running {
    /// Samples used.
    pub n: usize,
    /// Mean of the first `n`.
    pub mean: f64,
    /// Its 95 % interval.
    pub mean_ci95: (f64, f64),
    /// P90 of the first `n`.
    pub p90: f64,
    /// Its 95 % interval, where `n` allows one.
    pub p90_ci95: Option<(f64, f64)>,
}

/// Statistics of one quantity over the samples.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct QoiStats {
    /// Samples with a finite value.
    pub n: usize,
    /// Samples without one (failed variants, or a quantity a variant does not have).
    pub missing: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: f64,
    /// Smallest and largest value.
    pub min: f64,
    /// See `min`.
    pub max: f64,
    /// P10, P50, P90.
    pub p10: f64,
    /// See `p10`.
    pub p50: f64,
    /// See `p10`.
    pub p90: f64,
    /// Further percentiles asked for: (percent, value).
    pub percentiles: Vec<(f64, f64)>,
    /// 95 % interval of the mean (Student t).
    pub mean_ci95: Option<(f64, f64)>,
    /// 95 % interval of P90 (order statistics).
    pub p90_ci95: Option<(f64, f64)>,
    /// Exceedance of each threshold asked for.
    pub exceedance: Vec<Exceedance>,
    /// Mean and P90 at N = 10, 20, 50, 100, 200, 500, … and at the full N.
    pub convergence: Vec<Running>,
}

fn mean_ci(x: &[f64]) -> Option<(f64, f64, f64)> {
    let n = x.len();
    if n == 0 {
        return None;
    }
    let m = x.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return Some((m, f64::NAN, f64::NAN));
    }
    let sd = (x.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    let t = StudentsT::new(0.0, 1.0, (n - 1) as f64)
        .map(|d| d.inverse_cdf(0.975))
        .unwrap_or(1.96);
    Some((m, sd, t * sd / (n as f64).sqrt()))
}

/// The statistics of `values` (in sample order; non-finite values count as missing), with
/// extra `percentiles` and exceedance `thresholds`.
pub fn qoi_stats(values: &[f64], percentiles: &[f64], thresholds: &[f64]) -> Option<QoiStats> {
    let x: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let n = x.len();
    let (mean, sd, half) = mean_ci(&x)?;
    let mut sorted = x.clone();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let mut marks: Vec<usize> = Vec::new();
    let mut m = 10;
    while m < n {
        marks.push(m);
        m = match m.to_string().as_bytes()[0] {
            b'1' => m * 2,
            b'2' => m / 2 * 5,
            _ => m * 2,
        };
    }
    marks.push(n);
    let convergence = marks
        .iter()
        .map(|&k| {
            let (mk, _, hk) = mean_ci(&x[..k]).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            let mut s = x[..k].to_vec();
            s.sort_by(|a, b| a.total_cmp(b));
            Running {
                n: k,
                mean: mk,
                mean_ci95: (mk - hk, mk + hk),
                p90: percentile(&s, 90.0),
                p90_ci95: percentile_ci(&s, 90.0),
            }
        })
        .collect();
    Some(QoiStats {
        n,
        missing: values.len() - n,
        mean,
        sd,
        min: sorted[0],
        max: sorted[n - 1],
        p10: percentile(&sorted, 10.0),
        p50: percentile(&sorted, 50.0),
        p90: percentile(&sorted, 90.0),
        percentiles: percentiles
            .iter()
            .map(|&p| (p, percentile(&sorted, p)))
            .collect(),
        mean_ci95: half.is_finite().then_some((mean - half, mean + half)),
        p90_ci95: percentile_ci(&sorted, 90.0),
        exceedance: thresholds
            .iter()
            .map(|&t| {
                let k = x.iter().filter(|v| **v > t).count();
                Exceedance {
                    threshold: t,
                    probability: k as f64 / n as f64,
                    ci95: wilson(k, n),
                }
            })
            .collect(),
        convergence,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_follow_numpy() {
        let x = [1.0, 2.0, 3.0, 4.0, 10.0];
        // numpy.percentile(x, [10, 50, 90]) = [1.4, 3.0, 7.6]
        assert!((percentile(&x, 10.0) - 1.4).abs() < 1e-12);
        assert_eq!(percentile(&x, 50.0), 3.0);
        assert!((percentile(&x, 90.0) - 7.6).abs() < 1e-12);
    }

    #[test]
    fn order_statistic_interval_covers_ninety_five_percent() {
        // Uniform data on [0, 1): the true P90 is 0.9. Over 400 repetitions of 200 samples the
        // interval holds it in at least 95 % of them, give or take the binomial noise of 400
        // trials (3 standard deviations: 92 %).
        use crate::uq::{unit_samples, Sampling};
        let mut hits = 0;
        for rep in 0..400 {
            let u = unit_samples(200, 1, rep, Sampling::Random).unwrap();
            let mut x: Vec<f64> = u.iter().map(|p| p[0]).collect();
            x.sort_by(|a, b| a.total_cmp(b));
            let (lo, hi) = percentile_ci(&x, 90.0).unwrap();
            if lo <= 0.9 && 0.9 <= hi {
                hits += 1;
            }
        }
        eprintln!("P90 interval coverage: {hits}/400");
        assert!(hits as f64 >= 0.92 * 400.0, "{hits}");
        assert!(
            percentile_ci(&[1.0; 20], 90.0).is_none(),
            "20 samples cannot bound P90"
        );
    }

    #[test]
    fn statistics_of_a_known_sample() {
        let x: Vec<f64> = (1..=100).map(f64::from).collect();
        let s = qoi_stats(&x, &[95.0], &[80.0]).unwrap();
        assert_eq!((s.n, s.missing), (100, 0));
        assert!((s.mean - 50.5).abs() < 1e-12);
        assert!((s.sd - (100.0f64 * 101.0 / 12.0).sqrt()).abs() < 1e-9);
        assert!((s.p90 - 90.1).abs() < 1e-12);
        assert_eq!(s.exceedance[0].probability, 0.2);
        let (lo, hi) = s.exceedance[0].ci95;
        assert!(lo < 0.2 && hi > 0.2 && lo > 0.12 && hi < 0.3);
        assert_eq!(s.convergence.last().unwrap().n, 100);
        assert_eq!(
            s.convergence.iter().map(|r| r.n).collect::<Vec<_>>(),
            vec![10, 20, 50, 100]
        );
        let with_nan = qoi_stats(&[1.0, f64::NAN, 3.0], &[], &[]).unwrap();
        assert_eq!((with_nan.n, with_nan.missing), (2, 1));
    }
}
