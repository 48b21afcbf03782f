//! A Monte Carlo run's report: statistics and sensitivities of every quantity of interest
//! over the samples that succeeded (failed samples counted, never silently dropped), and the
//! plots an engineer reads — histogram with P10/P50/P90, scatter against each input with its
//! rank correlation, a tornado of partial rank correlations, the running mean and P90 with
//! their bands — in engineering units.

use std::path::Path;

use serde::Serialize;

use super::sensitivity::{sensitivities, InputSensitivity};
use super::stats::{qoi_stats, QoiStats};
use super::Sampling;
use crate::keys::{Key, Param};

/// A quantity's unit, for plots (values stay SI in CSV and JSON).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Unit {
    /// N, shown in kN.
    Force,
    /// N·m, shown in kN·m.
    Torque,
    /// N/m, shown in kN/m.
    ForcePerLength,
    /// m.
    Length,
    /// Hz.
    Frequency,
    /// Dimensionless.
    Ratio,
    /// N/m^m.
    Stiffness,
    /// rad/s, shown in rpm.
    AngularSpeed,
    /// N·s/m.
    Damping,
    /// m/s.
    Speed,
    /// rad, shown in degrees.
    Angle,
    /// Degrees (a quantity computed in degrees, e.g. the bit's tilt).
    Degrees,
    /// Curvature in °/30 m (build, turn and equilibrium curvature rates).
    DegPer30m,
}

/// A quantity's column name in words for plot titles and axes: the SI suffix dropped (the
/// axis carries the display unit), `max` read as "largest", the flags as probabilities —
/// `max_surface_torque_nm` → "largest surface torque", `stab1_max_side_force_n` → "stab1:
/// largest side force", `sinusoidal_buckling` → "sinusoidal buckling (1 = buckled)".
pub fn quantity_words(name: &str) -> String {
    let mut n = name.to_string();
    for suffix in [
        "_deg_per_30m",
        "_n_per_m",
        "_nm",
        "_n",
        "_m",
        "_hz",
        "_pa",
        "_s",
        "_deg",
    ] {
        if let Some(stem) = n.strip_suffix(suffix) {
            n = stem.to_string();
            break;
        }
    }
    let (stab, rest) = match n.split_once('_') {
        Some((head, rest)) if head.starts_with("stab") && head[4..].parse::<usize>().is_ok() => {
            (Some(head.to_string()), rest.to_string())
        }
        _ => (None, n),
    };
    let words = rest
        .replace("max_", "largest ")
        .replace("per_length", "per unit length")
        .replace('_', " ");
    let words = match words.as_str() {
        "sinusoidal buckling" | "helical buckling" => format!("{words} (1 = buckled)"),
        "outside hole" => "string outside the hole between contact sites (1 = outside)".into(),
        _ => words,
    };
    match stab {
        Some(s) => format!("{s}: {words}"),
        None => words,
    }
}

impl Unit {
    /// Scale from SI to the display unit, and its label.
    pub fn display(self) -> (f64, &'static str) {
        match self {
            Unit::Force => (1e-3, "kN"),
            Unit::Torque => (1e-3, "kN·m"),
            Unit::ForcePerLength => (1e-3, "kN/m"),
            Unit::Length => (1.0, "m"),
            Unit::Frequency => (1.0, "Hz"),
            Unit::Ratio => (1.0, "–"),
            Unit::Stiffness => (1.0, "N/m"),
            Unit::AngularSpeed => (60.0 / std::f64::consts::TAU, "rpm"),
            Unit::Damping => (1.0, "N·s/m"),
            Unit::Speed => (1.0, "m/s"),
            Unit::Angle => (180.0 / std::f64::consts::PI, "°"),
            Unit::Degrees => (1.0, "°"),
            Unit::DegPer30m => (1.0, "°/30 m"),
        }
    }

    /// The unit of a variant key's values.
    pub fn of_key(key: &Key) -> Unit {
        match key.param {
            Param::Mu | Param::MuT | Param::MuL | Param::Exponent => Unit::Ratio,
            Param::WallStiffness => Unit::Stiffness,
            Param::WallDamping => Unit::Damping,
            Param::Eps => Unit::Speed,
            Param::Rpm => Unit::AngularSpeed,
            Param::Wob => Unit::Force,
            Param::Tob => Unit::Torque,
            Param::Blade | Param::FromBit | Param::Depth | Param::Eccentricity => Unit::Length,
            Param::Mode | Param::Layout => Unit::Ratio,
            Param::Bend => Unit::Angle,
        }
    }
}

/// What a Monte Carlo run asks for.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct MonteCarlo {
    /// Samples.
    pub samples: usize,
    /// Seed.
    pub seed: u64,
    /// Sampling method.
    pub sampling: Sampling,
    /// Percentiles reported beyond P10/P50/P90.
    pub percentiles: Vec<f64>,
    /// Exceedance thresholds: (quantity name, value in SI).
    pub thresholds: Vec<(String, f64)>,
    /// First-order and total Sobol indices from a Saltelli design (`samples` base points,
    /// `samples (d + 2)` runs; `--sobol-indices`, with `--sampling sobol`).
    #[serde(default)]
    pub sobol_indices: bool,
}

/// One quantity of interest over the samples (NaN where a sample has no value).
#[derive(Clone, Debug)]
pub struct Qoi {
    /// Name (the `variants.csv` column).
    pub name: String,
    /// Unit.
    pub unit: Unit,
    /// Value per sample.
    pub values: Vec<f64>,
}

/// One quantity's statistics and sensitivities.
#[derive(Clone, Debug, Serialize)]
pub struct QoiReport {
    /// Name.
    pub name: String,
    /// Unit of the values (SI).
    pub unit: Unit,
    /// Statistics over the samples with a value; `None` when none has one.
    pub stats: Option<QoiStats>,
    /// Spearman and PRCC with each input.
    pub sensitivity: Vec<InputSensitivity>,
    /// First-order and total Sobol indices with their 95 % intervals (`--sobol-indices`).
    pub sobol: Option<Vec<super::sensitivity::SobolIndex>>,
}

/// The uncertainty part of `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct UncertaintyReport {
    /// Samples drawn.
    pub samples: usize,
    /// Seed.
    pub seed: u64,
    /// Method.
    pub sampling: Sampling,
    /// Uncertain inputs, in sampling order.
    pub inputs: Vec<String>,
    /// Samples that failed (excluded from every statistic; listed in `failures`).
    pub failed: usize,
    /// Runs the statistics use: every run, or the 2n independent ones of a Saltelli design.
    pub base_samples: usize,
    /// Per quantity.
    pub qois: Vec<QoiReport>,
    /// Of the runs the statistics use whose outcome is known (solved, or stopped where the
    /// string does: a lock-up), those that stop on their way, with the probability's Wilson
    /// 95 % interval; `None` where no run stops (set by the ensemble, which knows stops).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stops: Option<super::stats::Proportion>,
    /// Of the same runs, those past the weight indicator's lock-up: solved with the string
    /// pushed from the surface (a hook load below zero) or stopped on their way; `None`
    /// where none is (static runs; set by the ensemble).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub past_weight_lock_up: Option<super::stats::Proportion>,
}

/// The report of a run: `inputs` (key, value per sample), `qois`, and which samples failed.
pub fn analyse(
    mc: &MonteCarlo,
    inputs: &[(Key, Vec<f64>)],
    qois: &[Qoi],
    failed: &[bool],
) -> UncertaintyReport {
    let names: Vec<String> = inputs.iter().map(|(k, _)| k.name.clone()).collect();
    // With a Saltelli design the statistics and rank correlations use its independent
    // samples, A and B (the first 2n runs); the indices use every run.
    let base = if mc.sobol_indices {
        (2 * mc.samples).min(failed.len())
    } else {
        failed.len()
    };
    let cols: Vec<Vec<f64>> = inputs.iter().map(|(_, v)| v[..base].to_vec()).collect();
    UncertaintyReport {
        samples: mc.samples,
        seed: mc.seed,
        sampling: mc.sampling,
        inputs: names.clone(),
        failed: failed.iter().filter(|f| **f).count(),
        base_samples: base,
        stops: None,
        past_weight_lock_up: None,
        qois: qois
            .iter()
            .map(|q| {
                let values: Vec<f64> = q
                    .values
                    .iter()
                    .zip(failed)
                    .map(|(v, f)| if *f { f64::NAN } else { *v })
                    .collect();
                let thresholds: Vec<f64> = mc
                    .thresholds
                    .iter()
                    .filter(|(n, _)| n == &q.name)
                    .map(|(_, t)| *t)
                    .collect();
                let sample = &values[..base];
                QoiReport {
                    name: q.name.clone(),
                    unit: q.unit,
                    stats: qoi_stats(sample, &mc.percentiles, &thresholds),
                    sensitivity: if sample.iter().filter(|v| v.is_finite()).count() > 2 {
                        sensitivities(&names, &cols, sample)
                    } else {
                        Vec::new()
                    },
                    sobol: if mc.sobol_indices {
                        super::sensitivity::sobol_indices(&names, &values, mc.samples, mc.seed)
                    } else {
                        None
                    },
                }
            })
            .collect(),
    }
}

/// Writes the report's plots into `dir`; returns the files written.
pub fn plot(
    report: &UncertaintyReport,
    inputs: &[(Key, Vec<f64>)],
    qois: &[Qoi],
    dir: &Path,
    title: &str,
) -> std::io::Result<Vec<String>> {
    use crate::plots::{histogram, scatter, tornado};
    let mut files = Vec::new();
    let base = report.base_samples;
    for (q, r) in qois.iter().zip(&report.qois) {
        let Some(s) = &r.stats else { continue };
        let (scale, unit) = q.unit.display();
        let words = quantity_words(&q.name);
        let label = if unit.is_empty() {
            words.clone()
        } else {
            format!("{words} ({unit})")
        };
        let file = format!("hist_{}.png", q.name);
        let shown: Vec<f64> = q.values[..base].iter().map(|v| v * scale).collect();
        histogram(
            &dir.join(&file),
            &format!("{title}: {words} over {} samples", s.n),
            &label,
            &shown,
            &[
                ("P10", s.p10 * scale),
                ("P50", s.p50 * scale),
                ("P90", s.p90 * scale),
            ],
        )?;
        files.push(file);
        for ((key, x), sens) in inputs.iter().zip(&r.sensitivity) {
            let (xs, xu) = Unit::of_key(key).display();
            let points: Vec<(f64, f64)> = x[..base]
                .iter()
                .zip(&q.values[..base])
                .map(|(a, b)| (a * xs, b * scale))
                .collect();
            let file = format!("scatter_{}_vs_{}.png", q.name, key.name);
            scatter(
                &dir.join(&file),
                &format!(
                    "{words} against {}: Spearman {:.2}, PRCC {:.2}",
                    key.name, sens.spearman, sens.prcc
                ),
                &format!("{} ({xu})", key.name),
                &label,
                &points,
            )?;
            files.push(file);
        }
        if !r.sensitivity.is_empty() {
            let file = format!("tornado_{}.png", q.name);
            tornado(
                &dir.join(&file),
                &format!("{title}: what drives the {words}"),
                "partial rank correlation (PRCC)",
                &r.sensitivity
                    .iter()
                    .map(|s| (s.input.clone(), s.prcc))
                    .collect::<Vec<_>>(),
            )?;
            files.push(file);
        }
        if let Some(sobol) = &r.sobol {
            let file = format!("sobol_{}.png", q.name);
            tornado(
                &dir.join(&file),
                &format!("{title}: total Sobol indices of the {words}"),
                "total Sobol index S_T (share of the variance with its interactions)",
                &sobol
                    .iter()
                    .map(|s| (s.input.clone(), s.total))
                    .collect::<Vec<_>>(),
            )?;
            files.push(file);
        }
        if s.convergence.len() > 1 {
            let file = format!("convergence_{}.png", q.name);
            let c = &s.convergence;
            crate::plots::convergence_plot(
                &dir.join(&file),
                &format!("{words}: mean and P90 against the number of samples"),
                &label,
                &[
                    (
                        "mean",
                        c.iter()
                            .map(|r| {
                                (
                                    r.n as f64,
                                    r.mean * scale,
                                    r.mean_ci95.0 * scale,
                                    r.mean_ci95.1 * scale,
                                )
                            })
                            .collect(),
                    ),
                    (
                        "P90",
                        c.iter()
                            .map(|r| {
                                let (lo, hi) = r.p90_ci95.unwrap_or((f64::NAN, f64::NAN));
                                (r.n as f64, r.p90 * scale, lo * scale, hi * scale)
                            })
                            .collect(),
                    ),
                ],
            )?;
            files.push(file);
        }
    }
    Ok(files)
}

/// Where runs stop on their way ([`UncertaintyReport::stops`]): how far each run's loads
/// get (`reached`: 1 where it reaches them, its stopped load factor where it stops, NaN
/// where its outcome is unknown) against each input, `scatter_loads_reached_vs_<key>.png`.
pub fn plot_reached(
    report: &UncertaintyReport,
    inputs: &[(Key, Vec<f64>)],
    reached: &[f64],
    dir: &Path,
    title: &str,
) -> std::io::Result<Vec<String>> {
    let Some(stops) = &report.stops else {
        return Ok(Vec::new());
    };
    let base = report.base_samples;
    let mut files = Vec::new();
    for (key, x) in inputs {
        let (xs, xu) = Unit::of_key(key).display();
        let points: Vec<(f64, f64)> = x[..base]
            .iter()
            .zip(&reached[..base])
            .filter(|(_, y)| y.is_finite())
            .map(|(a, y)| (a * xs, *y))
            .collect();
        let file = format!("scatter_loads_reached_vs_{}.png", key.name);
        crate::plots::scatter(
            &dir.join(&file),
            &format!(
                "{title}: {} of {} runs stop on their way (P {:.2}, 95 %: {:.2}–{:.2}), against {}",
                stops.count, stops.of, stops.probability, stops.ci95.0, stops.ci95.1, key.name
            ),
            &format!("{} ({xu})", key.name),
            "fraction of the friction and bit loads with an equilibrium",
            &points,
        )?;
        files.push(file);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    #[test]
    fn quantity_names_read_as_words() {
        use super::quantity_words as w;
        assert_eq!(w("max_surface_torque_nm"), "largest surface torque");
        assert_eq!(w("hook_load_n"), "hook load");
        assert_eq!(w("stab1_max_side_force_n"), "stab1: largest side force");
        assert_eq!(w("stab2_whirl_hz"), "stab2: whirl");
        assert_eq!(
            w("max_side_force_per_length_n_per_m"),
            "largest side force per unit length"
        );
        assert_eq!(w("helical_buckling"), "helical buckling (1 = buckled)");
        assert_eq!(
            w("outside_hole"),
            "string outside the hole between contact sites (1 = outside)"
        );
    }
}
