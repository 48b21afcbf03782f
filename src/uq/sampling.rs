//! Points in the unit cube `(0, 1)^d` for `N` samples: random, Latin hypercube or
//! Owen-scrambled Sobol (`sobol_burley`). Point `i` depends only on `(seed, i, N, method)`,
//! never on the order or the machine that draws it: random numbers come from ChaCha8 with
//! one stream per sample (portable, unlike `StdRng`), and the Latin hypercube's
//! permutations from one stream per dimension. So a shard, a resumed run and a whole run
//! see the same inputs, bit for bit.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// How the unit-cube points are drawn.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Independent uniform points.
    Random,
    /// Latin hypercube: each dimension's N strata hold one point each.
    Lhs,
    /// Owen-scrambled Sobol points (at most 2^16 samples, 256 inputs).
    Sobol,
}

/// Why a set of samples cannot be drawn.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SamplingError {
    /// More Sobol samples than `sobol_burley` indexes.
    #[error("Sobol sampling takes at most {SOBOL_MAX_SAMPLES} samples, not {0}")]
    TooManySobolSamples(usize),
    /// More Sobol dimensions than `sobol_burley` has.
    #[error("Sobol sampling takes at most {max} inputs, not {0}", max = sobol_burley::NUM_DIMENSIONS)]
    TooManySobolInputs(usize),
    /// Too few samples for a rank correlation of this many inputs.
    #[error("rank correlation needs more samples than inputs + 1 ({samples} for {inputs})")]
    TooFewForCorrelation {
        /// Samples.
        samples: usize,
        /// Inputs.
        inputs: usize,
    },
    /// A correlation matrix that is not positive definite.
    #[error("the correlation matrix is not positive definite")]
    NotPositiveDefinite,
    /// The normal scores of a rank correlation are degenerate.
    #[error("the scores are degenerate")]
    DegenerateScores,
    /// No uncertain inputs to sample.
    #[error("no uncertain inputs: add an [ensemble.uncertain] table")]
    NoInputs,
    /// No samples asked for.
    #[error("--samples must be at least 1")]
    NoSamples,
    /// Sobol indices asked of another sampling.
    #[error("Sobol indices need --sampling sobol (the Saltelli design is built on Sobol points)")]
    IndicesNeedSobol,
    /// A correlation asked of Sobol points.
    #[error("ensemble.correlation reorders the samples, which breaks Sobol points' structure: use --sampling lhs or random")]
    CorrelationBreaksSobol,
    /// A drawn value outside its key's range.
    #[error("sample {sample}: {key} drew {value} from a {dist}, outside the key's range ({range}); truncate the distribution")]
    OutOfRange {
        /// The sample's index (0-based).
        sample: usize,
        /// The key.
        key: String,
        /// The value drawn (SI).
        value: f64,
        /// The distribution, in words.
        dist: String,
        /// The key's range, in words.
        range: &'static str,
    },
}

/// The largest sample count Sobol sampling takes (`sobol_burley`'s index range).
pub const SOBOL_MAX_SAMPLES: usize = 1 << 16;

/// A number in (0, 1) from 53 random bits, never 0 or 1 (quantile functions diverge there).
fn open_unit(bits: u64) -> f64 {
    ((bits >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

/// Sample `i`'s random stream.
fn sample_stream(seed: u64, i: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(i as u64);
    rng
}

/// `n` points in `(0, 1)^d` (`[i][k]`: sample `i`, input `k`).
pub fn unit_samples(
    n: usize,
    d: usize,
    seed: u64,
    method: Sampling,
) -> Result<Vec<Vec<f64>>, SamplingError> {
    match method {
        Sampling::Random => Ok((0..n)
            .map(|i| {
                let mut rng = sample_stream(seed, i);
                (0..d).map(|_| open_unit(rng.next_u64())).collect()
            })
            .collect()),
        Sampling::Lhs => {
            // One permutation of the strata per input, from a stream of its own.
            let perms: Vec<Vec<usize>> = (0..d)
                .map(|k| {
                    let mut rng = ChaCha8Rng::seed_from_u64(seed);
                    rng.set_stream((1u64 << 63) + k as u64);
                    let mut p: Vec<usize> = (0..n).collect();
                    for j in (1..n).rev() {
                        let r = (rng.next_u64() % (j as u64 + 1)) as usize;
                        p.swap(j, r);
                    }
                    p
                })
                .collect();
            Ok((0..n)
                .map(|i| {
                    let mut rng = sample_stream(seed, i);
                    (0..d)
                        .map(|k| (perms[k][i] as f64 + open_unit(rng.next_u64())) / n as f64)
                        .collect()
                })
                .collect())
        }
        Sampling::Sobol => {
            if n > SOBOL_MAX_SAMPLES {
                return Err(SamplingError::TooManySobolSamples(n));
            }
            if d > sobol_burley::NUM_DIMENSIONS as usize {
                return Err(SamplingError::TooManySobolInputs(d));
            }
            let seed32 = (seed ^ (seed >> 32)) as u32;
            Ok((0..n)
                .map(|i| {
                    (0..d)
                        .map(|k| {
                            // The 24-bit cell's centre: never 0.
                            let u = sobol_burley::sample(i as u32, k as u32, seed32);
                            ((u * (1 << 24) as f32).floor() as f64 + 0.5) / (1 << 24) as f64
                        })
                        .collect()
                })
                .collect())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::Distribution;

    #[test]
    fn sample_moments_within_their_standard_errors() {
        // N = 1e4 random samples of each law: the sample mean within 4 standard errors of
        // the law's mean (√(σ²/N)), the sample variance within 4 of its own
        // (√((μ₄ − σ⁴)/N), μ₄ the sample's fourth central moment about the law's mean).
        let laws = [
            Distribution::Uniform { min: 0.2, max: 0.4 },
            Distribution::Normal {
                mean: 75e3,
                sd: 7e3,
                min: f64::NEG_INFINITY,
                max: f64::INFINITY,
            },
            Distribution::Normal {
                mean: 75e3,
                sd: 7e3,
                min: 65e3,
                max: 80e3,
            },
            Distribution::LogNormal {
                median: 6e7,
                sigma: 0.3,
            },
            Distribution::Triangular {
                min: 6.0,
                mode: 9.0,
                max: 13.0,
            },
            Distribution::Triangular {
                min: 6.0,
                mode: 6.0,
                max: 13.0,
            },
            Distribution::Discrete {
                values: vec![10.0, 15.0, 20.0],
                weights: vec![1.0, 2.0, 1.0],
            },
        ];
        let n = 10_000;
        let u = unit_samples(n, laws.len(), 7, Sampling::Random).unwrap();
        for (k, law) in laws.iter().enumerate() {
            law.check().unwrap();
            let x: Vec<f64> = u.iter().map(|p| law.quantile(p[k])).collect();
            let m = x.iter().sum::<f64>() / n as f64;
            let v = x.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (n - 1) as f64;
            let (mu, var) = law.moments();
            let se_mean = (var / n as f64).sqrt();
            let fourth = x.iter().map(|y| (y - mu).powi(4)).sum::<f64>() / n as f64;
            let se_var = ((fourth - var * var) / n as f64).sqrt();
            eprintln!(
                "{law:?}: mean {m:.6e} vs {mu:.6e} ({:.2} se), variance {v:.6e} vs {var:.6e} ({:.2} se)",
                (m - mu) / se_mean,
                (v - var) / se_var
            );
            assert!((m - mu).abs() <= 4.0 * se_mean, "{law:?} mean");
            assert!((v - var).abs() <= 4.0 * se_var, "{law:?} variance");
            let (lo, hi) = law.support();
            assert!(x.iter().all(|y| *y >= lo && *y <= hi), "{law:?} support");
        }
    }

    #[test]
    fn latin_hypercube_puts_one_point_in_each_stratum() {
        for n in [1, 7, 100, 1000] {
            let u = unit_samples(n, 5, 42, Sampling::Lhs).unwrap();
            for k in 0..5 {
                let mut seen = vec![false; n];
                for p in &u {
                    let s = (p[k] * n as f64).floor() as usize;
                    assert!(!seen[s], "n {n}, input {k}: stratum {s} twice");
                    seen[s] = true;
                }
            }
        }
    }

    #[test]
    fn sobol_points_are_nets() {
        // Owen-scrambled Sobol points: the first 2^m of them have exactly one point in each
        // interval [j/2^m, (j+1)/2^m) of every input, and every pair of the first two
        // inputs has one point in each of the 2^m cells of a 2^a × 2^(m−a) grid (a (0, m, 2)-net).
        for m in [4u32, 8, 10] {
            let n = 1usize << m;
            let u = unit_samples(n, 4, 3, Sampling::Sobol).unwrap();
            for k in 0..4 {
                let mut count = vec![0; n];
                for p in &u {
                    count[(p[k] * n as f64).floor() as usize] += 1;
                }
                assert!(count.iter().all(|&c| c == 1), "m {m}, input {k}");
            }
            for a in 0..=m {
                let (nx, ny) = (1usize << a, 1usize << (m - a));
                let mut count = vec![0; n];
                for p in &u {
                    let (x, y) = ((p[0] * nx as f64) as usize, (p[1] * ny as f64) as usize);
                    count[x * ny + y] += 1;
                }
                assert!(count.iter().all(|&c| c == 1), "m {m}, grid {nx}×{ny}");
            }
        }
        assert!(unit_samples(SOBOL_MAX_SAMPLES + 1, 1, 0, Sampling::Sobol).is_err());
    }

    #[test]
    fn a_sample_is_the_same_whoever_draws_it() {
        for method in [Sampling::Random, Sampling::Lhs, Sampling::Sobol] {
            let a = unit_samples(64, 3, 11, method).unwrap();
            let b = unit_samples(64, 3, 11, method).unwrap();
            assert_eq!(a, b);
            let c = unit_samples(64, 3, 12, method).unwrap();
            assert_ne!(a, c, "{method:?}: the seed matters");
            assert!(a.iter().flatten().all(|x| *x > 0.0 && *x < 1.0));
        }
        // Random points do not depend on N (a prefix is the smaller run's points).
        let small = unit_samples(10, 3, 11, Sampling::Random).unwrap();
        let big = unit_samples(100, 3, 11, Sampling::Random).unwrap();
        assert_eq!(small[..], big[..10]);
    }
}

/// Imposes the rank correlation `target` (d × d, unit diagonal, positive definite) on the
/// points `u` (`[i][k]`) by Iman & Conover's method (1982) — exactly, the correlation of
/// the normal scores, whose rank correlation is (6/π)·asin(ρ/2), within 0.02 of ρ: van der
/// Waerden scores in a
/// seeded random order per input, given the target's correlation by Cholesky factors, and
/// each input's values reordered to the scores' ranks. Every input keeps its values (so its
/// distribution, and a Latin hypercube's strata); only their pairing changes.
pub fn iman_conover(
    u: &mut [Vec<f64>],
    target: &nalgebra::DMatrix<f64>,
    seed: u64,
) -> Result<(), SamplingError> {
    use nalgebra::DMatrix;
    use statrs::distribution::{ContinuousCDF, Normal};
    let n = u.len();
    let d = target.nrows();
    if n < d + 2 {
        return Err(SamplingError::TooFewForCorrelation {
            samples: n,
            inputs: d,
        });
    }
    let p = target
        .clone()
        .cholesky()
        .ok_or(SamplingError::NotPositiveDefinite)?
        .l();
    let normal = Normal::new(0.0, 1.0).map_err(|_| SamplingError::DegenerateScores)?;
    let scores: Vec<f64> = (1..=n)
        .map(|i| normal.inverse_cdf(i as f64 / (n as f64 + 1.0)))
        .collect();
    let mut r = DMatrix::zeros(n, d);
    for k in 0..d {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x1c0a_0c0e);
        rng.set_stream(k as u64);
        let mut perm: Vec<usize> = (0..n).collect();
        for j in (1..n).rev() {
            perm.swap(j, (rng.next_u64() % (j as u64 + 1)) as usize);
        }
        for i in 0..n {
            r[(i, k)] = scores[perm[i]];
        }
    }
    // The scores' own correlation T = Q Qᵀ; R* = R (P Q⁻¹)ᵀ has correlation ≈ P Pᵀ = target.
    let mean = r.row_mean();
    let centred = DMatrix::from_fn(n, d, |i, k| r[(i, k)] - mean[k]);
    let cov = centred.transpose() * &centred / (n as f64 - 1.0);
    let sd: Vec<f64> = (0..d).map(|k| cov[(k, k)].sqrt()).collect();
    let t = DMatrix::from_fn(d, d, |a, b| cov[(a, b)] / (sd[a] * sd[b]));
    let q = t.cholesky().ok_or(SamplingError::DegenerateScores)?.l();
    let q_inv = q.try_inverse().ok_or(SamplingError::DegenerateScores)?;
    let s = &p * q_inv;
    let target_scores = &r * s.transpose();
    for k in 0..d {
        let mut values: Vec<f64> = u.iter().map(|row| row[k]).collect();
        values.sort_by(|a, b| a.total_cmp(b));
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| target_scores[(a, k)].total_cmp(&target_scores[(b, k)]));
        for (rank, &i) in order.iter().enumerate() {
            u[i][k] = values[rank];
        }
    }
    Ok(())
}

#[cfg(test)]
mod correlation_tests {
    use super::*;

    #[test]
    fn iman_conover_gives_the_rank_correlation_and_keeps_the_strata() {
        let n = 1000;
        let mut u = unit_samples(n, 3, 5, Sampling::Lhs).unwrap();
        let before: Vec<Vec<f64>> = (0..3)
            .map(|k| {
                let mut c: Vec<f64> = u.iter().map(|p| p[k]).collect();
                c.sort_by(|a, b| a.total_cmp(b));
                c
            })
            .collect();
        let mut target = nalgebra::DMatrix::identity(3, 3);
        target[(0, 1)] = 0.7;
        target[(1, 0)] = 0.7;
        target[(1, 2)] = -0.4;
        target[(2, 1)] = -0.4;
        iman_conover(&mut u, &target, 9).unwrap();
        let col = |k: usize| u.iter().map(|p| p[k]).collect::<Vec<f64>>();
        let rho = |a: usize, b: usize| crate::uq::sensitivity::spearman(&col(a), &col(b));
        eprintln!(
            "rank correlations: {:.3} {:.3} {:.3}",
            rho(0, 1),
            rho(1, 2),
            rho(0, 2)
        );
        assert!((rho(0, 1) - 0.7).abs() < 0.05);
        assert!((rho(1, 2) + 0.4).abs() < 0.05);
        assert!(rho(0, 2).abs() < 0.05, "asked 0");
        for (k, sorted) in before.iter().enumerate() {
            let mut c = col(k);
            c.sort_by(|a, b| a.total_cmp(b));
            assert_eq!(&c, sorted, "input {k} keeps its values");
        }
        let mut bad = nalgebra::DMatrix::identity(2, 2);
        bad[(0, 1)] = 1.5;
        bad[(1, 0)] = 1.5;
        assert!(iman_conover(&mut u.clone(), &bad, 1).is_err());
    }
}
