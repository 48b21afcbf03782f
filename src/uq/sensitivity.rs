//! Sensitivity of a quantity of interest to the uncertain inputs, from the samples: Spearman
//! rank correlation and partial rank correlation (PRCC: the correlation of the ranks' residuals
//! after the other inputs' ranks are regressed out, by least squares).

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Average ranks (1-based; ties share their mean rank).
pub fn ranks(x: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..x.len()).collect();
    idx.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let mut r = vec![0.0; x.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && x[idx[j + 1]] == x[idx[i]] {
            j += 1;
        }
        let mean_rank = (i + j) as f64 / 2.0 + 1.0;
        for &k in &idx[i..=j] {
            r[k] = mean_rank;
        }
        i = j + 1;
    }
    r
}

/// Pearson correlation (NaN when either side is constant).
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    sab / (saa * sbb).sqrt()
}

/// Spearman rank correlation.
pub fn spearman(a: &[f64], b: &[f64]) -> f64 {
    pearson(&ranks(a), &ranks(b))
}

/// Residuals of `y` after least squares on the columns of `x` and an intercept.
fn residuals(x: &DMatrix<f64>, y: &DVector<f64>) -> DVector<f64> {
    let n = y.len();
    let mut a = DMatrix::from_element(n, x.ncols() + 1, 1.0);
    a.columns_mut(1, x.ncols()).copy_from(x);
    let svd = a.clone().svd(true, true);
    match svd.solve(y, 1e-12) {
        Ok(beta) => y - a * beta,
        Err(_) => y.clone(),
    }
}

/// The sensitivity of one quantity to one input.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct InputSensitivity {
    /// Input name.
    pub input: String,
    /// Spearman rank correlation.
    pub spearman: f64,
    /// Partial rank correlation.
    pub prcc: f64,
}

/// Spearman and PRCC of `y` with each input (`inputs[k][i]`: input k of sample i), over the
/// samples where `y` is finite. Constant inputs give NaN.
pub fn sensitivities(names: &[String], inputs: &[Vec<f64>], y: &[f64]) -> Vec<InputSensitivity> {
    let keep: Vec<usize> = (0..y.len()).filter(|&i| y[i].is_finite()).collect();
    let n = keep.len();
    let yr = DVector::from_vec(ranks(&keep.iter().map(|&i| y[i]).collect::<Vec<_>>()));
    let xr: Vec<Vec<f64>> = inputs
        .iter()
        .map(|col| ranks(&keep.iter().map(|&i| col[i]).collect::<Vec<_>>()))
        .collect();
    (0..inputs.len())
        .map(|k| {
            let others: Vec<usize> = (0..inputs.len()).filter(|&j| j != k).collect();
            let prcc = if n > others.len() + 2 {
                let x = DMatrix::from_fn(n, others.len(), |i, c| xr[others[c]][i]);
                let rx = residuals(&x, &DVector::from_vec(xr[k].clone()));
                let ry = residuals(&x, &yr);
                pearson(rx.as_slice(), ry.as_slice())
            } else {
                f64::NAN
            };
            InputSensitivity {
                input: names[k].clone(),
                spearman: pearson(&xr[k], yr.as_slice()),
                prcc,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::{unit_samples, Sampling};

    #[test]
    fn ranks_average_ties() {
        assert_eq!(ranks(&[3.0, 1.0, 3.0, 2.0]), vec![3.5, 1.0, 3.5, 2.0]);
        assert!((spearman(&[1.0, 2.0, 3.0], &[10.0, 20.0, 1e9]) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn the_dominant_input_has_the_largest_index() {
        // y = 10 x0 + x1 − 0.5 x2 + noise, Latin hypercube, 300 samples: x0 dominates by
        // construction, x2 pulls the other way, x3 does nothing.
        let n = 300;
        let u = unit_samples(n, 5, 9, Sampling::Lhs).unwrap();
        let inputs: Vec<Vec<f64>> = (0..4).map(|k| u.iter().map(|p| p[k]).collect()).collect();
        let y: Vec<f64> = u
            .iter()
            .map(|p| 10.0 * p[0] + p[1] - 0.5 * p[2] + 0.3 * (p[4] - 0.5))
            .collect();
        let names: Vec<String> = (0..4).map(|k| format!("x{k}")).collect();
        let s = sensitivities(&names, &inputs, &y);
        for r in &s {
            eprintln!(
                "{}: Spearman {:.3}, PRCC {:.3}",
                r.input, r.spearman, r.prcc
            );
        }
        assert!(s[0].prcc > 0.9 && s[0].spearman > 0.9);
        let largest = s
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.prcc.abs().total_cmp(&b.1.prcc.abs()))
            .unwrap()
            .0;
        assert_eq!(largest, 0);
        assert!(s[1].prcc > 0.3 && s[2].prcc < -0.2, "signs and order");
        assert!(
            s[3].prcc.abs() < 0.2 && s[3].spearman.abs() < 0.2,
            "the idle input"
        );
    }
}

/// First-order and total Sobol indices of one input, with bootstrap 95 % intervals.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SobolIndex {
    /// Input name.
    pub input: String,
    /// First-order index `S_i` (Saltelli 2010).
    pub first: f64,
    /// Its 95 % interval (bootstrap percentiles).
    pub first_ci95: (f64, f64),
    /// Total index `S_Ti` (Jansen 1999).
    pub total: f64,
    /// Its 95 % interval.
    pub total_ci95: (f64, f64),
}

/// The unit-cube points of a Saltelli design for `n` base samples of `d` inputs: rows
/// `A` (n), `B` (n), then `AB_i` for each input i (n each: `A` with column i from `B`), from
/// one Owen-scrambled Sobol sequence of 2d dimensions (`A` the first d, `B` the next d).
/// `n (d + 2)` points.
pub fn saltelli_design(
    n: usize,
    d: usize,
    seed: u64,
) -> Result<Vec<Vec<f64>>, super::sampling::SamplingError> {
    let ab = super::unit_samples(n, 2 * d, seed, super::Sampling::Sobol)?;
    let a: Vec<Vec<f64>> = ab.iter().map(|p| p[..d].to_vec()).collect();
    let b: Vec<Vec<f64>> = ab.iter().map(|p| p[d..].to_vec()).collect();
    let mut rows = a.clone();
    rows.extend(b.iter().cloned());
    for i in 0..d {
        rows.extend(a.iter().zip(&b).map(|(ra, rb)| {
            let mut r = ra.clone();
            r[i] = rb[i];
            r
        }));
    }
    Ok(rows)
}

/// Sobol indices from the outputs `y` of a [`saltelli_design`] (`n (d + 2)` values in its
/// order; a non-finite output drops its base sample `j` from every estimate). `None` when
/// fewer than 8 base samples remain or the output does not vary.
pub fn sobol_indices(names: &[String], y: &[f64], n: usize, seed: u64) -> Option<Vec<SobolIndex>> {
    let d = names.len();
    if y.len() != n * (d + 2) {
        return None;
    }
    let at = |block: usize, j: usize| y[block * n + j];
    let keep: Vec<usize> = (0..n)
        .filter(|&j| (0..d + 2).all(|b| at(b, j).is_finite()))
        .collect();
    if keep.len() < 8 {
        return None;
    }
    let estimate = |idx: &[usize]| -> Vec<(f64, f64)> {
        let m = idx.len() as f64;
        let all: Vec<f64> = idx.iter().flat_map(|&j| [at(0, j), at(1, j)]).collect();
        let mean = all.iter().sum::<f64>() / all.len() as f64;
        let var = all.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (all.len() - 1) as f64;
        (0..d)
            .map(|i| {
                let (mut s1, mut st) = (0.0, 0.0);
                for &j in idx {
                    let (fa, fb, fab) = (at(0, j), at(1, j), at(2 + i, j));
                    s1 += fb * (fab - fa);
                    st += (fa - fab).powi(2);
                }
                (s1 / m / var, st / (2.0 * m) / var)
            })
            .collect()
    };
    let point = estimate(&keep);
    if point.iter().any(|(a, b)| !a.is_finite() || !b.is_finite()) {
        return None;
    }
    // Bootstrap over the base samples (seeded: the same run, the same intervals).
    use rand::{RngCore, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x50b0_1d1c);
    let reps = 500;
    let mut boot: Vec<Vec<(f64, f64)>> = Vec::with_capacity(reps);
    for _ in 0..reps {
        let idx: Vec<usize> = (0..keep.len())
            .map(|_| keep[(rng.next_u64() % keep.len() as u64) as usize])
            .collect();
        boot.push(estimate(&idx));
    }
    let interval = |i: usize, total: bool| -> (f64, f64) {
        let mut v: Vec<f64> = boot
            .iter()
            .map(|b| if total { b[i].1 } else { b[i].0 })
            .filter(|x| x.is_finite())
            .collect();
        v.sort_by(|a, b| a.total_cmp(b));
        (
            super::stats::percentile(&v, 2.5),
            super::stats::percentile(&v, 97.5),
        )
    };
    Some(
        (0..d)
            .map(|i| SobolIndex {
                input: names[i].clone(),
                first: point[i].0,
                first_ci95: interval(i, false),
                total: point[i].1,
                total_ci95: interval(i, true),
            })
            .collect(),
    )
}

#[cfg(test)]
mod sobol_tests {
    use super::*;

    #[test]
    fn sobol_indices_of_the_ishigami_function() {
        // f = sin x1 + 7 sin² x2 + 0.1 x3⁴ sin x1, x ~ U(−π, π)³: S = (0.3139, 0.4424, 0),
        // S_T = (0.5576, 0.4424, 0.2437) (Ishigami & Homma 1990; Saltelli et al. 2010).
        let n = 4096;
        let pts = saltelli_design(n, 3, 17).unwrap();
        let pi = std::f64::consts::PI;
        let y: Vec<f64> = pts
            .iter()
            .map(|p| {
                let x: Vec<f64> = p.iter().map(|u| -pi + 2.0 * pi * u).collect();
                x[0].sin() + 7.0 * x[1].sin().powi(2) + 0.1 * x[2].powi(4) * x[0].sin()
            })
            .collect();
        let names = vec!["x1".to_string(), "x2".into(), "x3".into()];
        let s = sobol_indices(&names, &y, n, 17).unwrap();
        let exact = [(0.3139, 0.5576), (0.4424, 0.4424), (0.0, 0.2437)];
        for (k, (s1, st)) in exact.iter().enumerate() {
            eprintln!(
                "{}: S {:.4} [{:.4}, {:.4}] (exact {s1}), S_T {:.4} [{:.4}, {:.4}] (exact {st})",
                s[k].input,
                s[k].first,
                s[k].first_ci95.0,
                s[k].first_ci95.1,
                s[k].total,
                s[k].total_ci95.0,
                s[k].total_ci95.1
            );
            assert!((s[k].first - s1).abs() < 0.03, "S{}", k + 1);
            assert!((s[k].total - st).abs() < 0.03, "S_T{}", k + 1);
            assert!(s[k].first_ci95.0 <= s[k].first && s[k].first <= s[k].first_ci95.1);
        }
        // The dominant input by total index is x1.
        let top = (0..3)
            .max_by(|&a, &b| s[a].total.total_cmp(&s[b].total))
            .unwrap();
        assert_eq!(top, 0);
    }
}
