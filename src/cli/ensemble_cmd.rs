//! `holewall ensemble` and `holewall merge`: the command line's own part — the Monte Carlo
//! and shard arguments checked into library options. The work is `crate::ensemble::job`.

use crate::error::{Error, InputError};

/// The Monte Carlo request from the command line (`None` without `--samples`); percentiles
/// in 0–100 and `QOI=VALUE` thresholds, else an input error (exit 2).
pub fn monte_carlo(
    samples: Option<usize>,
    seed: u64,
    sampling: crate::uq::Sampling,
    percentiles: &[f64],
    exceed: &[String],
    sobol_indices: bool,
) -> Result<Option<crate::uq::report::MonteCarlo>, Error> {
    let err = |key: &str, message: String| -> Error {
        InputError {
            source_name: "command line".into(),
            line: 0,
            key: key.into(),
            message,
        }
        .into()
    };
    let Some(samples) = samples else {
        if !percentiles.is_empty() || !exceed.is_empty() {
            return Err(err(
                "--samples",
                "--percentile and --exceed need --samples N".into(),
            ));
        }
        return Ok(None);
    };
    if samples == 0 {
        return Err(err("--samples", "at least 1".into()));
    }
    if sobol_indices && sampling != crate::uq::Sampling::Sobol {
        return Err(err(
            "--sobol-indices",
            "needs --sampling sobol (the Saltelli design is built on Sobol points)".into(),
        ));
    }
    if let Some(p) = percentiles.iter().find(|p| !(0.0..=100.0).contains(*p)) {
        return Err(err("--percentile", format!("{p} is outside 0 … 100")));
    }
    let thresholds = exceed
        .iter()
        .map(|e| {
            let (name, value) = e
                .split_once('=')
                .ok_or_else(|| err("--exceed", format!("{e:?}: expected QOI=VALUE")))?;
            let v: f64 = value.trim().parse().map_err(|_| {
                err(
                    "--exceed",
                    format!("{e:?}: {value:?} is not a number (SI units)"),
                )
            })?;
            Ok((name.trim().to_string(), v))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    Ok(Some(crate::uq::report::MonteCarlo {
        samples,
        seed,
        sampling,
        percentiles: percentiles.to_vec(),
        thresholds,
        sobol_indices,
    }))
}

/// `--shard K/N` (1 ≤ K ≤ N), else an input error.
pub fn parse_shard(text: &str) -> Result<(usize, usize), Error> {
    let bad = || -> Error {
        InputError {
            source_name: "command line".into(),
            line: 0,
            key: "--shard".into(),
            message: format!("{text:?}: expected K/N with 1 ≤ K ≤ N"),
        }
        .into()
    };
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}
