//! Uncertainty quantification (issue 14): the distributions of uncertain inputs, sampling
//! (random, Latin hypercube, scrambled Sobol), statistics of the quantities of interest and
//! their sensitivity to the inputs. Library code: `holewall ensemble` calls it, and so can
//! any program that builds variants of a case.

pub mod distribution;
pub mod report;
pub mod sampling;
pub mod sensitivity;
pub mod stats;

pub use distribution::Distribution;
pub use sampling::{unit_samples, Sampling};

use crate::ensemble::{Key, Variant};

/// `n` samples of the uncertain inputs as variants named `s00001`, … (each overriding every
/// uncertain key), drawn by `sampling` with `seed`: the unit-cube points mapped through each
/// input's quantile function. Sample `i` is the same whatever `n`'s other samples, the
/// chunking or the machine (for `random`; `lhs` and `sobol` depend on `n` as a whole). A
/// sampled value outside the key's allowed range is an error naming it.
///
/// With `sobol_indices` the points are a Saltelli design for `n` base samples
/// ([`sensitivity::saltelli_design`]): `n (d + 2)` variants, the first `2n` of them
/// independent samples of the inputs (`A` and `B`), the rest `A` with one input from `B`.
pub fn sample_variants(
    uncertain: &[(Key, Distribution)],
    n: usize,
    seed: u64,
    sampling: Sampling,
    sobol_indices: bool,
    correlation: Option<&nalgebra::DMatrix<f64>>,
) -> Result<Vec<Variant>, String> {
    if uncertain.is_empty() {
        return Err("no uncertain inputs: add an [ensemble.uncertain] table".into());
    }
    if n == 0 {
        return Err("--samples must be at least 1".into());
    }
    let mut u = if sobol_indices {
        if sampling != Sampling::Sobol {
            return Err("Sobol indices need --sampling sobol (the Saltelli design is built on Sobol points)".into());
        }
        sensitivity::saltelli_design(n, uncertain.len(), seed)?
    } else {
        unit_samples(n, uncertain.len(), seed, sampling)?
    };
    if let Some(c) = correlation {
        if sampling == Sampling::Sobol {
            return Err("ensemble.correlation reorders the samples, which breaks Sobol points' structure: use --sampling lhs or random".into());
        }
        sampling::iman_conover(&mut u, c, seed)?;
    }
    let width = u.len().to_string().len().max(5);
    u.iter()
        .enumerate()
        .map(|(i, p)| {
            let overrides = uncertain
                .iter()
                .zip(p)
                .map(|((key, dist), &ui)| {
                    let v = dist.quantile(ui);
                    key.value(&v.to_string())
                        .map(|v| (key.clone(), v))
                        .map_err(|m| {
                            format!(
                                "sample {i}: {} drew {v} from {dist:?}, outside the key's range ({m}); truncate the distribution",
                                key.name
                            )
                        })
                })
                .collect::<Result<Vec<_>, String>>()?;
            Ok(Variant {
                name: format!("s{:0width$}", i + 1),
                overrides,
            })
        })
        .collect()
}
