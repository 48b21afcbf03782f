//! Synthetic measurements: the FE model's loads at known friction factors with Gaussian
//! noise, for the calibration's tests and its corpus benchmark (`holewall bench
//! calibrate-corpus`).

use std::path::Path;

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use super::{model_at, stations, unknowns, MeasuredMode, Measurement};
use crate::case::Case;
use crate::error::Error;

/// What to measure.
#[derive(Clone, Debug)]
pub struct SyntheticPlan {
    /// Bit depths (m).
    pub depths: Vec<f64>,
    /// Modes at every depth.
    pub modes: Vec<MeasuredMode>,
    /// The true friction factors, one per [`unknowns`] key of the case.
    pub mu: Vec<f64>,
    /// Hook-load noise (N).
    pub sigma_hook: f64,
    /// Torque noise (N·m).
    pub sigma_torque: f64,
    /// Noise seed.
    pub seed: u64,
    /// Rotary speed of the rotating rows (rad/s); `None`: the case's.
    pub rpm: Option<f64>,
}

/// Measurements of `case` by `plan`: a hook load in every row, a surface torque in the
/// rotating ones, each the model's plus its noise.
pub fn synthetic(case: &Case, plan: &SyntheticPlan) -> Result<Vec<Measurement>, Error> {
    let mut rows = Vec::new();
    for &d in &plan.depths {
        for &m in &plan.modes {
            rows.push(Measurement {
                line: rows.len() + 2,
                bit_md: d,
                mode: m,
                wob: if m == MeasuredMode::Drilling {
                    40e3
                } else {
                    0.0
                },
                rpm: plan.rpm.filter(|_| m.rotates()),
                hook_load: Some(0.0),
                surface_torque: m.rotates().then_some(0.0),
            });
        }
    }
    let (st, at) = stations(&rows);
    let keys = unknowns(case);
    let loads = model_at(
        case,
        &st,
        &keys,
        &plan.mu,
        &indicatif::ProgressBar::hidden(),
    )?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(plan.seed);
    let unit = Normal::new(0.0, 1.0).map_err(Error::failed)?;
    for (r, &s) in rows.iter_mut().zip(&at) {
        r.hook_load = Some(loads[s].0 + plan.sigma_hook * unit.sample(&mut rng));
        if r.surface_torque.is_some() {
            r.surface_torque = Some(loads[s].1 + plan.sigma_torque * unit.sample(&mut rng));
        }
    }
    Ok(rows)
}

/// Writes measurements as a measured file (SI columns), atomically.
pub fn write_measured(rows: &[Measurement], path: &Path) -> std::io::Result<()> {
    let mut text = String::from("bit_md_m,mode,wob_n,rpm,hook_load_n,surface_torque_nm\n");
    let opt = |x: Option<f64>| x.map(|v| format!("{v}")).unwrap_or_default();
    for r in rows {
        text.push_str(&format!(
            "{},{},{},{},{},{}\n",
            r.bit_md,
            r.mode.name(),
            r.wob,
            opt(r.rpm.map(|w| w * 30.0 / std::f64::consts::PI)),
            opt(r.hook_load),
            opt(r.surface_torque)
        ));
    }
    crate::output::write_atomic(path, text.as_bytes())
}
