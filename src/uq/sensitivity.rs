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
