//! `holewall calibrate CASE --measured FILE --out DIR`: the cased- and open-hole friction
//! factors that best explain measured hook loads and surface torques, with their posterior
//! ([`crate::calibrate`]): `summary.json`, `residuals.csv`, `posterior.csv`,
//! `posterior.png`, `residuals.png` (`residuals_torque.png`), `broomstick.png`
//! (`torque.png`) with the measurements over the model at the calibrated factors.

use std::path::Path;

use serde::Serialize;

use crate::calibrate::{calibrate, read_measured, CalibrateOptions, Calibration};
use crate::case::load_case;
use crate::error::{Error, InputError};
use crate::output::RunFolder;

/// `summary.json` of `holewall calibrate`.
#[derive(Clone, Debug, Serialize)]
pub struct CalibrateSummary {
    /// Case title.
    pub title: String,
    /// The measured file.
    pub measured: String,
    /// Rows read.
    pub rows: usize,
    /// Friction range and grid nodes per unknown.
    pub range: (f64, f64),
    /// Grid nodes per unknown.
    pub nodes: usize,
    /// The result.
    pub calibration: Calibration,
    /// Files written.
    pub outputs: Vec<String>,
    /// Wall time (s).
    pub seconds: f64,
    /// The case's warnings.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Runs the command. A calibration the checks reject still writes every output; the caller
/// reads `calibration.accepted`.
pub fn run(
    case_path: &Path,
    measured: &Path,
    out: &Path,
    options: CalibrateOptions,
    show_progress: bool,
) -> Result<CalibrateSummary, Error> {
    let start = std::time::Instant::now();
    let case = load_case(case_path)?;
    super::print_warnings(&case);
    let rows = read_measured(measured)?;
    if !(2..=41).contains(&options.nodes) {
        return Err(InputError {
            source_name: "--nodes".into(),
            line: 0,
            key: "nodes".into(),
            message: format!("{}: allowed 2 … 41", options.nodes),
        }
        .into());
    }
    let (lo, hi) = options.range;
    if !(lo >= 0.0 && hi > lo && hi <= 2.0) {
        return Err(InputError {
            source_name: "--mu-range".into(),
            line: 0,
            key: "mu-range".into(),
            message: format!("{lo},{hi}: allowed 0 ≤ low < high ≤ 2"),
        }
        .into());
    }
    let folder = RunFolder::prepare(out)?.with_report("calibrate", case_path);
    let bar = crate::output::progress_bar(
        show_progress,
        0,
        "calibrate {bar:40} {pos}/{len} model runs, {elapsed} (eta {eta})",
    );
    let cal = calibrate(&case, &rows, &options, &bar)?;
    let outputs = crate::calibrate::report::write(&case, &rows, &cal, folder.path(), &bar)?;
    bar.finish_and_clear();
    let summary = CalibrateSummary {
        title: case.title.clone(),
        measured: measured.display().to_string(),
        rows: rows.len(),
        range: options.range,
        nodes: options.nodes,
        calibration: cal,
        outputs,
        seconds: start.elapsed().as_secs_f64(),
        warnings: case.warnings.clone(),
    };
    let json = serde_json::to_vec_pretty(&summary)?;
    folder.finish(&json)?;
    Ok(summary)
}
