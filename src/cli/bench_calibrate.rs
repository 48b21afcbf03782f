//! `holewall bench calibrate-corpus`: the friction calibration ([`crate::calibrate`]) on
//! generated wells ([`crate::corpus`], re-meshed to 10 m pipe / 1 m BHA elements). Per well:
//! the cased- and open-hole friction factors drawn from the seed (0.10–0.30, 0.15–0.45),
//! synthetic pick-up, slack-off and rotating loads at five bit depths over the open hole
//! (noise 5 kN, 0.3 kN·m), calibrated; then the same measurements made on a string whose
//! drill pipe is 30 % heavier, calibrated with the well's own string, which should be
//! rejected. Reported: calibrated / total, truth inside the 95 % intervals, heavier strings
//! rejected, the widest interval and the worst well, as `calibrate_corpus.csv` and
//! `summary.json`.

use std::path::Path;

use rand::{Rng, SeedableRng};
use serde::Serialize;

use crate::calibrate::synthetic::{synthetic, SyntheticPlan};
use crate::calibrate::{calibrate, CalibrateOptions, MeasuredMode};
use crate::error::Error;

/// One well's row of `calibrate_corpus.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct CalibrateRow {
    /// Corpus seed.
    pub seed: u64,
    /// Trajectory.
    pub trajectory: String,
    /// Bit depth (m).
    pub total_md: f64,
    /// Cased-hole shoe (MD, m); 0 for none.
    pub shoe_md: f64,
    /// The true factors.
    pub mu_cased: f64,
    /// Open hole's.
    pub mu_open: f64,
    /// The calibration ran.
    pub calibrated: bool,
    /// It was accepted.
    pub accepted: bool,
    /// Every truth inside its 95 % interval.
    pub recovered: bool,
    /// The cased factor's interval.
    pub cased_lo: f64,
    /// Upper end.
    pub cased_hi: f64,
    /// The open factor's interval.
    pub open_lo: f64,
    /// Upper end.
    pub open_hi: f64,
    /// Largest spline error at the MAP (N).
    pub surrogate_error_n: f64,
    /// The heavier string's data were rejected.
    pub heavier_rejected: bool,
    /// Wall time of both calibrations (s).
    pub seconds: f64,
    /// Why it failed, if it did.
    pub error: String,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct CalibrateCorpusSummary {
    /// Wells.
    pub wells: usize,
    /// Calibrations that ran to the end.
    pub calibrated: usize,
    /// Accepted by the residual checks.
    pub accepted: usize,
    /// Truths inside their 95 % intervals (every factor of the well).
    pub recovered: usize,
    /// Heavier strings rejected.
    pub heavier_rejected: usize,
    /// Median width of the open hole's 95 % interval.
    pub median_open_interval: f64,
    /// Wells that failed, were rejected, missed the truth or let the heavier string pass:
    /// (seed, what).
    pub worst: Vec<(u64, String)>,
    /// Wall time (s).
    pub wall_seconds: f64,
}

/// The well's case text with its drill pipe 30 % heavier (a smaller bore, same OD).
fn heavier(text: &str) -> Result<String, String> {
    let mut table: toml::Table = text.parse().map_err(|e| format!("{e}"))?;
    let Some(toml::Value::Array(string)) = table.get_mut("string") else {
        return Err("no [[string]]".into());
    };
    let inches = |v: Option<&toml::Value>| -> Option<f64> {
        v?.as_str()?.strip_suffix(" in")?.trim().parse().ok()
    };
    let mut changed = false;
    for c in string.iter_mut() {
        let Some(t) = c.as_table_mut() else { continue };
        if t.get("kind").and_then(|k| k.as_str()) != Some("drill_pipe") {
            continue;
        }
        let (Some(od), Some(id)) = (inches(t.get("od")), inches(t.get("id"))) else {
            continue;
        };
        let id2 = (od * od - 1.3 * (od * od - id * id)).max(0.0).sqrt();
        t.insert("id".into(), toml::Value::String(format!("{id2:.4} in")));
        changed = true;
    }
    if !changed {
        return Err("no drill pipe".into());
    }
    toml::to_string(&table).map_err(|e| e.to_string())
}

fn one_well(seed: u64, dir: &Path) -> Result<CalibrateRow, String> {
    let start = std::time::Instant::now();
    let well = crate::corpus::write_well(seed, dir).map_err(|e| e.to_string())?;
    let well = crate::corpus::remesh(&well, 10.0, 1.0).map_err(|e| e.to_string())?;
    let case = crate::case::load_case(&well.case_path).map_err(|e| e.to_string())?;
    let shoe = case
        .hole
        .iter()
        .filter(|h| h.cased)
        .map(|h| h.bottom_md)
        .fold(0.0, f64::max);
    let total = well.spec.total_md;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0xca11b);
    let (mu_cased, mu_open) = (rng.random_range(0.10..0.30), rng.random_range(0.15..0.45));
    let keys = crate::calibrate::unknowns(&case);
    let mu: Vec<f64> = keys
        .iter()
        .map(|k| {
            if k.name == "mu.cased" {
                mu_cased
            } else {
                mu_open
            }
        })
        .collect();
    let top = (shoe + 0.25 * (total - shoe)).max(0.5 * total);
    let plan = SyntheticPlan {
        depths: (0..5)
            .map(|i| top + (total - top) * i as f64 / 4.0)
            .collect(),
        modes: vec![
            MeasuredMode::PickUp,
            MeasuredMode::SlackOff,
            MeasuredMode::Rotating,
        ],
        mu: mu.clone(),
        sigma_hook: 5e3,
        sigma_torque: 300.0,
        seed,
        rpm: Some(120.0 * std::f64::consts::PI / 30.0),
    };
    let mut row = CalibrateRow {
        seed,
        trajectory: well.spec.trajectory.name().to_string(),
        total_md: total,
        shoe_md: shoe,
        mu_cased,
        mu_open,
        calibrated: false,
        accepted: false,
        recovered: false,
        cased_lo: f64::NAN,
        cased_hi: f64::NAN,
        open_lo: f64::NAN,
        open_hi: f64::NAN,
        surrogate_error_n: f64::NAN,
        heavier_rejected: false,
        seconds: 0.0,
        error: String::new(),
    };
    let hidden = indicatif::ProgressBar::hidden();
    let outcome = (|| -> Result<(), String> {
        let rows = synthetic(&case, &plan).map_err(|e| e.to_string())?;
        let cal = calibrate(&case, &rows, &CalibrateOptions::default(), &hidden)
            .map_err(|e| e.to_string())?;
        row.calibrated = true;
        row.accepted = cal.accepted;
        row.surrogate_error_n = cal.surrogate_error.0;
        row.recovered = true;
        for (e, truth) in cal.estimates.iter().zip(&mu) {
            row.recovered &= e.interval_95.0 <= *truth && *truth <= e.interval_95.1;
            let (lo, hi) = if e.key == "mu.cased" {
                (&mut row.cased_lo, &mut row.cased_hi)
            } else {
                (&mut row.open_lo, &mut row.open_hi)
            };
            (*lo, *hi) = e.interval_95;
        }
        if !cal.accepted {
            row.error = cal.rejected_because.join("; ");
        }
        // The same measurements on a heavier string, calibrated with the well's own.
        let text = std::fs::read_to_string(&well.case_path).map_err(|e| e.to_string())?;
        let heavy_path = well
            .case_path
            .with_file_name(format!("well_{seed}_heavier.toml"));
        crate::output::write_atomic(&heavy_path, heavier(&text)?.as_bytes())
            .map_err(|e| e.to_string())?;
        let heavy = crate::case::load_case(&heavy_path).map_err(|e| e.to_string())?;
        let rows = synthetic(&heavy, &plan).map_err(|e| e.to_string())?;
        let cal = calibrate(&case, &rows, &CalibrateOptions::default(), &hidden)
            .map_err(|e| e.to_string())?;
        row.heavier_rejected = !cal.accepted;
        Ok(())
    })();
    if let Err(e) = outcome {
        row.error = e;
    }
    row.seconds = start.elapsed().as_secs_f64();
    Ok(row)
}

/// Runs the benchmark over seeds `first_seed …` into `out`.
pub fn run(
    out: &Path,
    wells: usize,
    first_seed: u64,
    show_progress: bool,
) -> Result<CalibrateCorpusSummary, Error> {
    use rayon::prelude::*;
    let clock = std::time::Instant::now();
    let dir = out.join("wells");
    std::fs::create_dir_all(&dir)?;
    let bar = crate::output::progress_bar(
        show_progress,
        wells as u64,
        "{bar:40} {pos}/{len} wells, {elapsed} elapsed (eta {eta})",
    );
    // Wells one after another, each calibration parallel inside.
    let rows: Vec<CalibrateRow> = (first_seed..first_seed + wells as u64)
        .collect::<Vec<_>>()
        .into_iter()
        .map(|seed| {
            let r = one_well(seed, &dir).map_err(Error::failed);
            bar.inc(1);
            r
        })
        .collect::<Result<_, _>>()?;
    bar.finish_and_clear();
    crate::output::write_csv_rows(&out.join("calibrate_corpus.csv"), &rows)?;
    let mut widths: Vec<f64> = rows
        .par_iter()
        .map(|r| r.open_hi - r.open_lo)
        .filter(|w| w.is_finite())
        .collect();
    widths.sort_by(f64::total_cmp);
    let worst = rows
        .iter()
        .filter(|r| !(r.calibrated && r.accepted && r.recovered && r.heavier_rejected))
        .map(|r| {
            let what = if !r.calibrated {
                format!("failed: {}", r.error)
            } else if !r.accepted {
                format!("rejected: {}", r.error)
            } else if !r.recovered {
                format!(
                    "truth ({:.3}, {:.3}) outside [{:.3}, {:.3}] × [{:.3}, {:.3}]",
                    r.mu_cased, r.mu_open, r.cased_lo, r.cased_hi, r.open_lo, r.open_hi
                )
            } else {
                "heavier string accepted".into()
            };
            (r.seed, what.chars().take(300).collect())
        })
        .collect();
    let summary = CalibrateCorpusSummary {
        wells: rows.len(),
        calibrated: rows.iter().filter(|r| r.calibrated).count(),
        accepted: rows.iter().filter(|r| r.accepted).count(),
        recovered: rows.iter().filter(|r| r.recovered).count(),
        heavier_rejected: rows.iter().filter(|r| r.heavier_rejected).count(),
        median_open_interval: widths.get(widths.len() / 2).copied().unwrap_or(f64::NAN),
        worst,
        wall_seconds: clock.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_vec_pretty(&summary)?;
    crate::output::write_atomic(&out.join("summary.json"), &json)?;
    Ok(summary)
}
