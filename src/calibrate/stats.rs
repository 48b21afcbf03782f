//! The calibration's numerics: the natural cubic spline between grid nodes, the filling of
//! failed nodes, the residuals' trend with depth and the lack-of-fit F-test.

use serde::Serialize;

/// Weights of the natural cubic spline through uniform `nodes`: `f(x) = Σ w_j f_j`.
pub(super) fn spline_weights(nodes: &[f64], x: f64) -> Vec<f64> {
    let n = nodes.len();
    let mut w = vec![0.0; n];
    if n == 1 {
        w[0] = 1.0;
        return w;
    }
    let h = nodes[1] - nodes[0];
    // Second derivatives M = S f: natural ends, interior rows h/6 (M_{i-1} + 4 M_i +
    // M_{i+1}) = (f_{i+1} − 2 f_i + f_{i−1})/h.
    let s = if n > 2 {
        let m = n - 2;
        let a = nalgebra::DMatrix::from_fn(m, m, |i, j| match i.abs_diff(j) {
            0 => 4.0 * h / 6.0,
            1 => h / 6.0,
            _ => 0.0,
        });
        let b = nalgebra::DMatrix::from_fn(m, n, |i, j| match j as i64 - i as i64 {
            0 | 2 => 1.0 / h,
            1 => -2.0 / h,
            _ => 0.0,
        });
        let inner = a
            .lu()
            .solve(&b)
            .unwrap_or_else(|| nalgebra::DMatrix::zeros(m, n));
        let mut s = nalgebra::DMatrix::zeros(n, n);
        s.view_mut((1, 0), (m, n)).copy_from(&inner);
        s
    } else {
        nalgebra::DMatrix::zeros(n, n)
    };
    let i = (((x - nodes[0]) / h).floor().max(0.0) as usize).min(n - 2);
    let b = ((x - nodes[i]) / h).clamp(0.0, 1.0);
    let a = 1.0 - b;
    w[i] += a;
    w[i + 1] += b;
    let (ca, cb) = ((a * a * a - a) * h * h / 6.0, (b * b * b - b) * h * h / 6.0);
    for j in 0..n {
        w[j] += ca * s[(i, j)] + cb * s[(i + 1, j)];
    }
    w
}

/// Fills the NaN entries of a tensor grid's values (`n` per axis, `d` axes, first axis
/// slowest) with the mean of their filled neighbours along the axes, sweeping until none is
/// left (a grid with no finite value stays as it is).
pub(super) fn fill_from_neighbours(values: &mut [f64], n: usize, d: usize) {
    if values.iter().all(|v| !v.is_finite()) {
        return;
    }
    while values.iter().any(|v| !v.is_finite()) {
        let before = values.to_vec();
        for k in 0..values.len() {
            if before[k].is_finite() {
                continue;
            }
            let mut neighbours = Vec::new();
            let stride = |a: usize| n.pow((d - 1 - a) as u32);
            for a in 0..d {
                let i = (k / stride(a)) % n;
                if i > 0 {
                    neighbours.push(before[k - stride(a)]);
                }
                if i + 1 < n {
                    neighbours.push(before[k + stride(a)]);
                }
            }
            let ok: Vec<f64> = neighbours.into_iter().filter(|v| v.is_finite()).collect();
            if !ok.is_empty() {
                values[k] = ok.iter().sum::<f64>() / ok.len() as f64;
            }
        }
    }
}

/// Uniform grid of `n` points on `[lo, hi]`.
pub(super) fn linspace(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![0.5 * (lo + hi)];
    }
    (0..n)
        .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
        .collect()
}

/// A lack-of-fit F-test.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct LackOfFit {
    /// F statistic.
    pub f: f64,
    /// Numerator degrees of freedom (the per-mode parameters).
    pub df1: usize,
    /// Denominator degrees of freedom.
    pub df2: usize,
    /// Its p-value.
    pub p_value: f64,
}

/// The F-test of residuals `groups` (per mode: (depth, residual)) at a fit of `fitted`
/// parameters against per-mode lines in depth (an offset where a mode has one depth):
/// `F = ((SSR₀ − SSR₁)/q) / (SSR₁/(n − fitted − q))`. `None` with too few rows.
pub(super) fn lack_of_fit(groups: &[Vec<(f64, f64)>], fitted: usize) -> Option<LackOfFit> {
    use statrs::distribution::{ContinuousCDF, FisherSnedecor};
    let n: usize = groups.iter().map(|g| g.len()).sum();
    let ssr0: f64 = groups.iter().flatten().map(|p| p.1 * p.1).sum();
    let (mut ssr1, mut q) = (0.0, 0usize);
    for g in groups {
        let m = g.len() as f64;
        let xm = g.iter().map(|p| p.0).sum::<f64>() / m;
        let ym = g.iter().map(|p| p.1).sum::<f64>() / m;
        let sxx: f64 = g.iter().map(|p| (p.0 - xm).powi(2)).sum();
        if g.len() >= 3 && sxx > 0.0 {
            let b = g.iter().map(|p| (p.0 - xm) * (p.1 - ym)).sum::<f64>() / sxx;
            ssr1 += g
                .iter()
                .map(|p| (p.1 - ym - b * (p.0 - xm)).powi(2))
                .sum::<f64>();
            q += 2;
        } else {
            ssr1 += g.iter().map(|p| (p.1 - ym).powi(2)).sum::<f64>();
            q += 1;
        }
    }
    let df2 = n.checked_sub(fitted + q).filter(|d| *d >= 2)?;
    if ssr1 <= 0.0 {
        return None;
    }
    let f = ((ssr0 - ssr1).max(0.0) / q as f64) / (ssr1 / df2 as f64);
    let dist = FisherSnedecor::new(q as f64, df2 as f64).ok()?;
    Some(LackOfFit {
        f,
        df1: q,
        df2,
        p_value: 1.0 - dist.cdf(f),
    })
}

/// Least-squares trend of `(depth, residual)`: (mean, rms, slope per km, p of zero slope).
pub(super) fn trend(points: &[(f64, f64)]) -> (f64, f64, f64, Option<f64>) {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let n = points.len() as f64;
    let mean = points.iter().map(|p| p.1).sum::<f64>() / n;
    let rms = (points.iter().map(|p| p.1 * p.1).sum::<f64>() / n).sqrt();
    let xm = points.iter().map(|p| p.0).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - xm).powi(2)).sum();
    if points.len() < 4 || sxx <= 0.0 {
        return (mean, rms, f64::NAN, None);
    }
    let slope = points
        .iter()
        .map(|p| (p.0 - xm) * (p.1 - mean))
        .sum::<f64>()
        / sxx;
    let sse: f64 = points
        .iter()
        .map(|p| (p.1 - mean - slope * (p.0 - xm)).powi(2))
        .sum();
    let df = n - 2.0;
    let se = (sse / df / sxx).sqrt();
    let p = if se > 0.0 {
        StudentsT::new(0.0, 1.0, df)
            .ok()
            .map(|t| 2.0 * (1.0 - t.cdf((slope / se).abs())))
    } else {
        Some(0.0)
    };
    (mean, rms, slope * 1e3, p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spline_reproduces_cubics_away_from_natural_ends_and_interpolates() {
        let nodes = linspace(0.0, 1.0, 9);
        // Interpolates at the nodes.
        for (k, &x) in nodes.iter().enumerate() {
            let w = spline_weights(&nodes, x);
            assert!((w[k] - 1.0).abs() < 1e-12 && w.iter().sum::<f64>() - 1.0 < 1e-12);
        }
        // A smooth function (the kind of load a friction factor makes) to 1e-4.
        let f = |x: f64| (1.3 * x).exp();
        let values: Vec<f64> = nodes.iter().map(|&x| f(x)).collect();
        for i in 0..=100 {
            let x = i as f64 / 100.0;
            let s: f64 = spline_weights(&nodes, x)
                .iter()
                .zip(&values)
                .map(|(w, v)| w * v)
                .sum();
            assert!((s - f(x)).abs() < 2e-3 * f(x), "{x}: {s} vs {}", f(x));
        }
    }

    #[test]
    fn failed_nodes_are_filled_from_their_neighbours() {
        // A 3 × 3 grid, x + 10 y, the centre and a corner missing.
        let mut v: Vec<f64> = (0..9)
            .map(|k| (k / 3) as f64 + 10.0 * (k % 3) as f64)
            .collect();
        v[4] = f64::NAN;
        v[8] = f64::NAN;
        fill_from_neighbours(&mut v, 3, 2);
        assert_eq!(v[4], 11.0); // the mean of 1, 21, 10, 12
        assert_eq!(v[8], 0.5 * (12.0 + 21.0));
        let mut none = vec![f64::NAN; 4];
        fill_from_neighbours(&mut none, 2, 2);
        assert!(none.iter().all(|x| x.is_nan()));
    }

    #[test]
    fn lack_of_fit_sees_per_mode_offsets_not_noise() {
        let noise = [0.3, -0.2, 0.1, -0.4, 0.2, 0.0, -0.1, 0.3, -0.3, 0.1];
        let group = |shift: f64, k: usize| -> Vec<(f64, f64)> {
            (0..5)
                .map(|i| (500.0 + 100.0 * i as f64, noise[(i + k) % 10] + shift))
                .collect()
        };
        let clean = lack_of_fit(&[group(0.0, 0), group(0.0, 3), group(0.0, 6)], 2).unwrap();
        assert!(clean.p_value > 0.01, "{clean:?}");
        let biased = lack_of_fit(&[group(2.0, 0), group(-2.0, 3), group(0.0, 6)], 2).unwrap();
        assert!(biased.p_value < 1e-3, "{biased:?}");
        assert_eq!((biased.df1, biased.df2), (6, 7));
    }

    #[test]
    fn trend_finds_a_slope_and_not_noise() {
        let noise = [0.3, -0.2, 0.1, -0.4, 0.2, 0.0, -0.1, 0.3];
        let flat: Vec<(f64, f64)> = noise
            .iter()
            .enumerate()
            .map(|(i, e)| (500.0 + 100.0 * i as f64, *e))
            .collect();
        assert!(trend(&flat).3.unwrap() > 0.05);
        let sloped: Vec<(f64, f64)> = flat.iter().map(|(x, e)| (*x, e + 0.01 * x)).collect();
        let (_, _, slope, p) = trend(&sloped);
        assert!(p.unwrap() < 1e-4 && (slope - 10.0).abs() < 1.0, "{slope}");
    }
}
