//! Studies of a user's case (issue 16): `holewall study precision` — the error of each
//! path (CPU f64, GPU f64, GPU f32) and time step against a fine-step f64 CPU reference,
//! beside its run time (a work-precision diagram), and the cheapest run within a tolerance.
//!
//! The quantities compared are the dynamic run's quantities of interest (the ensemble's,
//! [`crate::ensemble::qoi`]): the hook load at the end, the largest surface torque, and per
//! stabilizer its largest side force and lateral displacement. The error of a run is the
//! largest of their relative errors, each against the reference value or, where that is
//! near zero, a floor (1 N, 1 N·m, 1 µm). The bit's stick-slip severity is left out: it
//! is a max − min over the integrator's own instants, which move with the step, so its
//! change measures the sampling (≈ 1 % on `cases/spinup_short.toml`, not shrinking with
//! the step), not the integration.

use std::path::Path;

use serde::Serialize;

use crate::backend::{Backend, BackendChoice, Precision};
use crate::case::{load_case, Case};
use crate::ensemble::qoi::{Status, VariantResult};
use crate::ensemble::Variant;
use crate::error::{Error, InputError};
use crate::keys::Key;
use crate::output::RunFolder;

/// Options of `holewall study precision`.
#[derive(Clone, Copy, Debug)]
pub struct PrecisionOptions {
    /// Time steps tried: the case's, and halved this many times.
    pub refinements: usize,
    /// Simulated time (s); `None`: the case's duration.
    pub duration: Option<f64>,
    /// Largest acceptable error (relative) for the recommendation.
    pub tolerance: f64,
    /// Progress on stderr.
    pub show_progress: bool,
}

impl Default for PrecisionOptions {
    fn default() -> Self {
        PrecisionOptions {
            refinements: 2,
            duration: None,
            tolerance: 1e-3,
            show_progress: true,
        }
    }
}

/// One run of the study.
#[derive(Clone, Debug, Serialize)]
pub struct PrecisionRow {
    /// `cpu-f64`, `gpu-f64`, `gpu-f32`.
    pub path: String,
    /// Time step (s).
    pub dt_s: f64,
    /// Wall time of the run (s).
    pub seconds: f64,
    /// Largest relative error against the reference (NaN if the run failed).
    pub max_error: f64,
    /// The quantity with the largest error.
    pub worst: String,
    /// Every quantity's relative error (summary.json only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub errors: Option<std::collections::BTreeMap<String, f64>>,
    /// `converged`, `step_cut`, `failed`, or why the path did not run.
    pub status: String,
}

/// `summary.json` of the study.
#[derive(Clone, Debug, Serialize)]
pub struct PrecisionSummary {
    /// Case title.
    pub title: String,
    /// Simulated time (s).
    pub duration_s: f64,
    /// The reference's time step (s) and wall time (s).
    pub reference_dt_s: f64,
    /// See `reference_dt_s`.
    pub reference_seconds: f64,
    /// Every run.
    pub runs: Vec<PrecisionRow>,
    /// The tolerance asked.
    pub tolerance: f64,
    /// The cheapest run within it, if any.
    pub recommendation: Option<PrecisionRow>,
    /// Paths that could not run and why; why nothing is recommended (and what step would
    /// be); quantities left out of the errors.
    pub notes: Vec<String>,
}

/// The compared quantities of a result: (name, value, floor).
fn quantities(r: &VariantResult) -> Vec<(String, f64, f64)> {
    let mut q = vec![
        (
            "hook_load_n".to_string(),
            r.hook_load_n.unwrap_or(f64::NAN),
            1.0,
        ),
        (
            "max_surface_torque_nm".to_string(),
            r.max_surface_torque_nm,
            1.0,
        ),
    ];
    for (k, s) in r.stabilizers.iter().enumerate() {
        q.push((
            format!("{}_max_side_force_n", crate::model::stabilizer_name(k + 1)),
            s.max_side_force_n,
            1.0,
        ));
        q.push((
            format!("{}_max_lateral_m", crate::model::stabilizer_name(k + 1)),
            s.max_lateral_m,
            1e-6,
        ));
    }
    q
}

/// Each quantity's relative error of `r` against `reference`.
fn errors_of(r: &VariantResult, reference: &VariantResult) -> Vec<(String, f64)> {
    if r.status == Status::Failed {
        return vec![("failed".into(), f64::NAN)];
    }
    quantities(r)
        .into_iter()
        .zip(quantities(reference))
        .filter(|((_, a, _), (_, b, floor))| a.abs() >= *floor || b.abs() >= *floor)
        .map(|((name, a, _), (_, b, floor))| (name, (a - b).abs() / b.abs().max(floor)))
        .collect()
}

/// The quantities that stay at zero (below their floor) in the reference run — a
/// stabilizer that never touches the wall has no side force — named for the summary:
/// they are left out of the errors where the run has them at zero too (an error of 0
/// there would read as "perfect").
fn zero_in_reference(reference: &VariantResult) -> Vec<String> {
    quantities(reference)
        .into_iter()
        .filter(|(_, b, floor)| b.abs() < *floor)
        .map(|(name, _, _)| name)
        .collect()
}

/// Why no run is within `tolerance`, and what time step would be, from the observed
/// order of the CPU runs' errors at successive halvings (`rows`: the study's runs).
fn no_recommendation_note(rows: &[PrecisionRow], tolerance: f64) -> String {
    let best = rows
        .iter()
        .filter(|r| r.max_error.is_finite())
        .min_by(|a, b| a.max_error.total_cmp(&b.max_error));
    let Some(best) = best else {
        return format!("no run finished, so none is within the tolerance {tolerance:.1e}");
    };
    let mut text = format!(
        "no run is within the tolerance {tolerance:.1e}: the smallest error is {:.2e} ({}, \
         dt = {:.2e} s, {})",
        best.max_error, best.path, best.dt_s, best.worst
    );
    let cpu: Vec<&PrecisionRow> = rows
        .iter()
        .filter(|r| r.path == "cpu-f64" && r.max_error.is_finite() && r.max_error > 0.0)
        .collect();
    if let [.., a, b] = cpu.as_slice() {
        let order = (a.max_error / b.max_error).log2() / (a.dt_s / b.dt_s).log2();
        if order > 0.2 {
            let dt = b.dt_s * (tolerance / b.max_error).powf(1.0 / order);
            text.push_str(&format!(
                "; the CPU errors fall with order {order:.2} in the step, so dt ≈ {dt:.2e} s \
                 would reach it (--refinements, or a smaller [dynamics].time_step)"
            ));
        } else {
            text.push_str(&format!(
                "; the CPU errors do not fall with the step (observed order {order:.2}): the \
                 error is not the time step's — the tolerance may be below the reference's \
                 own error, or the quantity is chaotic over this duration; ask a looser \
                 --tolerance or a shorter --duration"
            ));
        }
    }
    text
}

/// A status as `variants.csv` writes it (`converged`, `step_cut`, `failed`).
fn status_name(s: Status) -> String {
    serde_json::to_value(s)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

fn with_step(case: &Case, dt: f64, duration: f64) -> Case {
    let mut c = case.clone();
    if let Some(d) = c.dynamics.as_mut() {
        d.time_step = dt;
        d.duration = duration;
        d.output_interval = d.output_interval.max(dt).min(duration);
    }
    c
}

/// One run of `case` on `path`; its result and wall time, or why the path cannot run it.
fn run_on(
    case: &Case,
    path: &str,
    gpu: Option<&'static crate::gpu::GpuContext>,
) -> Result<(VariantResult, f64), Error> {
    let variant = Variant {
        name: "study".into(),
        overrides: vec![],
    };
    let bar = indicatif::ProgressBar::hidden();
    let clock = std::time::Instant::now();
    let result = match (path, gpu) {
        ("cpu-f64", _) => crate::ensemble::qoi::dynamic_variant(case, "study", &case.model),
        ("gpu-f64", Some(ctx)) if !ctx.has_f64 => {
            return Err(Error::failed("the adapter has no f64"))
        }
        ("gpu-f64", Some(ctx)) => {
            crate::ensemble::runner::run_dynamic_gpu::<f64>(case, &[variant], ctx, &bar)
                .map_err(Error::failed)?
                .map_err(Error::failed)?
                .remove(0)
        }
        ("gpu-f32", Some(ctx)) => {
            crate::ensemble::runner::run_dynamic_gpu::<f32>(case, &[variant], ctx, &bar)
                .map_err(Error::failed)?
                .map_err(Error::failed)?
                .remove(0)
        }
        _ => return Err(Error::failed("no GPU adapter")),
    };
    if result.solved_by == crate::ensemble::qoi::SolvedBy::Cpu && path != "cpu-f64" {
        return Err(Error::failed(format!(
            "the engine failed the run ({}); not a {path} result",
            result.reason
        )));
    }
    Ok((result, clock.elapsed().as_secs_f64()))
}

/// Runs the study on `case_path`, writing `precision.csv`, `precision.png` and
/// `summary.json` into `out`.
pub fn precision(
    case_path: &Path,
    out: &Path,
    options: PrecisionOptions,
) -> Result<PrecisionSummary, Error> {
    let case = load_case(case_path)?;
    let Some(settings) = case.dynamics.clone() else {
        return Err(InputError {
            source_name: case_path.display().to_string(),
            line: 1,
            key: "dynamics".into(),
            message: "holewall study precision needs a [dynamics] table".into(),
        }
        .into());
    };
    let folder = RunFolder::prepare(out)?;
    let duration = options.duration.unwrap_or(settings.duration);
    let dt0 = settings.time_step;
    let gpu = match Backend::resolve_with(
        BackendChoice::Gpu,
        Precision::F32,
        &[Precision::F64],
        crate::backend::AutoRule::AnyAdapter,
    ) {
        Ok((Backend::Gpu(ctx), _)) => Some(ctx),
        _ => None,
    };
    let mut notes = Vec::new();
    if gpu.is_none() {
        notes.push("no GPU adapter: the GPU paths were not run".to_string());
    }
    let steps: Vec<f64> = (0..=options.refinements)
        .map(|k| dt0 / 2f64.powi(k as i32))
        .collect();
    let dt_ref = dt0 / 2f64.powi(options.refinements as i32 + 2);
    let total = 1 + 3 * steps.len();
    let bar = crate::output::progress_bar(
        options.show_progress,
        total as u64,
        "{bar:40} {pos}/{len} runs, {elapsed} elapsed  {msg}",
    );
    bar.set_message(format!("reference, dt = {dt_ref:.2e} s"));
    let (reference, reference_seconds) =
        run_on(&with_step(&case, dt_ref, duration), "cpu-f64", None)
            .map_err(|e| Error::failed(format!("reference run: {e}")))?;
    if reference.status == Status::Failed {
        return Err(Error::failed(format!(
            "the reference run (CPU f64, dt = {dt_ref:.3e} s) failed: {}",
            reference.reason
        )));
    }
    bar.inc(1);
    let mut runs = Vec::new();
    for path in ["cpu-f64", "gpu-f64", "gpu-f32"] {
        for &dt in &steps {
            bar.set_message(format!("{path}, dt = {dt:.2e} s"));
            let row = match run_on(&with_step(&case, dt, duration), path, gpu) {
                Ok((r, seconds)) => {
                    let errors = errors_of(&r, &reference);
                    let (worst, max_error) =
                        errors.iter().fold((String::new(), 0.0f64), |m, (n, e)| {
                            if *e > m.1 || e.is_nan() {
                                (n.clone(), *e)
                            } else {
                                m
                            }
                        });
                    PrecisionRow {
                        path: path.into(),
                        dt_s: dt,
                        seconds,
                        max_error,
                        worst,
                        errors: Some(errors.into_iter().collect()),
                        status: status_name(r.status),
                    }
                }
                Err(why) => {
                    if !notes.iter().any(|n| n.starts_with(path)) {
                        notes.push(format!("{path}: {why}"));
                    }
                    PrecisionRow {
                        path: path.into(),
                        dt_s: dt,
                        seconds: f64::NAN,
                        max_error: f64::NAN,
                        worst: String::new(),
                        errors: None,
                        status: format!("not run: {why}"),
                    }
                }
            };
            runs.push(row);
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let recommendation = runs
        .iter()
        .filter(|r| r.max_error <= options.tolerance && r.seconds.is_finite())
        .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
        .cloned();
    if recommendation.is_none() {
        notes.push(no_recommendation_note(&runs, options.tolerance));
    }
    for name in zero_in_reference(&reference) {
        notes.push(format!(
            "{name} is 0 in the reference run (a stabilizer that never touches the wall): \
             left out of the errors where a run has it at 0 too"
        ));
    }
    let dir = folder.path();
    crate::output::write_csv_rows(
        &dir.join("precision.csv"),
        runs.iter().map(|r| PrecisionRow {
            errors: None,
            ..r.clone()
        }),
    )?;
    let series: Vec<(String, Vec<(f64, f64)>)> = ["cpu-f64", "gpu-f64", "gpu-f32"]
        .iter()
        .map(|p| {
            (
                p.to_string(),
                runs.iter()
                    .filter(|r| r.path == *p && r.seconds.is_finite() && r.max_error.is_finite())
                    .map(|r| (r.seconds, r.max_error.max(1e-16)))
                    .collect(),
            )
        })
        .filter(|(_, pts): &(String, Vec<(f64, f64)>)| !pts.is_empty())
        .collect();
    crate::plots::loglog_plot(
        &dir.join("precision.png"),
        &format!(
            "{}: error against run time ({} s simulated; reference dt = {:.2e} s)",
            case.title, duration, dt_ref
        ),
        "run time (s)",
        "largest relative error of the quantities of interest",
        &series,
        options.tolerance,
    )?;
    let summary = PrecisionSummary {
        title: case.title.clone(),
        duration_s: duration,
        reference_dt_s: dt_ref,
        reference_seconds,
        runs,
        tolerance: options.tolerance,
        recommendation,
        notes,
    };
    folder.finish(&serde_json::to_vec_pretty(&summary)?)?;
    Ok(summary)
}

/// Options of `holewall study stability`.
#[derive(Clone, Copy, Debug)]
pub struct StabilityOptions {
    /// Simulated time of each dynamic cell (s); `None`: the smaller of the case's and 0.5 s.
    pub duration: Option<f64>,
    /// Progress on stderr.
    pub show_progress: bool,
}

/// One cell of the stability map.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityCell {
    /// The parameter varied (`k_e at m = …` cells vary both).
    pub parameter: String,
    /// Its value as written.
    pub value: String,
    /// `static` or `dynamic`.
    pub analysis: String,
    /// `converged`, `step_cut`, `failed`.
    pub status: String,
    /// Load-step (static) or time-step (dynamic) cuts.
    pub step_cuts: usize,
    /// Newton iterations per step.
    pub newton_iterations: f64,
    /// Wall time (s).
    pub seconds: f64,
    /// A non-finite state or residual.
    pub nan: bool,
    /// Dynamic cells: growth of the lateral kinetic energy, the second half's peak over the
    /// first half's minus 1 (≫ 0: blowing up; ≈ 0 steady; < 0 decaying;
    /// `crate::ensemble::qoi::dynamic_variant_tracked`). Empty for static cells.
    pub energy_growth: Option<f64>,
    /// Why it failed or was cut.
    pub reason: String,
}

/// `summary.json` of the stability study.
#[derive(Clone, Debug, Serialize)]
pub struct StabilitySummary {
    /// Case title.
    pub title: String,
    /// Cells run.
    pub cells: usize,
    /// Cells converged without a cut, with cuts, failed.
    pub converged: usize,
    /// See `converged`.
    pub step_cut: usize,
    /// See `converged`.
    pub failed: usize,
    /// Every cell.
    pub map: Vec<StabilityCell>,
}

/// A cell: (parameter, value in words, overrides (key, SI value), time-step factor).
type Cell = (String, String, Vec<(Key, f64)>, f64);

/// The override of key `name` (one of the study's own) by the SI value `x`.
fn set(name: &str, x: f64) -> (Key, f64) {
    (Key::parse(name).expect("the study's keys are keys"), x)
}

/// The cells: one parameter at a time around the case (wall stiffness 1e5 … 1e11, spring
/// exponent 2/3, 1, 3/2, ε 1e-6 … 1e-1, friction 0 … 1, the first stabilizer's clearance
/// 0 … nominal, WOB ½ … 8 × the case's, the time step 1 … 16 × the case's) and the wall
/// stiffness × exponent grid. (parameter, value, overrides, dt factor).
fn stability_cells(case: &Case) -> Vec<Cell> {
    let mut cells = Vec::new();
    let one = |p: &str, x: f64, text: String| (p.to_string(), text, vec![set(p, x)], 1.0);
    for (m, m_text) in [(0.6667, "0.6667"), (1.0, "1"), (1.5, "1.5")] {
        for k in [1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11] {
            cells.push((
                format!("k_e at m = {m_text}"),
                format!("{k:e} N/m^m"),
                vec![set("k_e", k), set("m", m)],
                1.0,
            ));
        }
    }
    for e in [1e-6, 1e-4, 1e-2, 1e-1] {
        cells.push(one("eps", e, format!("{e:e}")));
    }
    for mu in [0.0, 0.2, 0.5, 1.0] {
        cells.push(one("mu", mu, format!("{mu}")));
    }
    if let Some(site) = case.model.sites.iter().find(|s| s.stabilizer) {
        let hole = 2.0 * site.hole_radius;
        for f in [0.0, 0.25, 0.5, 1.0] {
            let blade = hole - 2.0 * f * site.params.clearance;
            cells.push((
                "stab1 clearance".into(),
                format!("{:.2} mm", 1e3 * f * site.params.clearance),
                vec![set("stab1.blade", blade)],
                1.0,
            ));
        }
    }
    let wob = case.model.weight_on_bit;
    if wob > 0.0 && !matches!(case.model.top, crate::model::TopBoundary::HookLoad(_)) {
        for f in [0.5, 1.0, 2.0, 4.0, 8.0] {
            cells.push((
                "wob".into(),
                format!("{:.0} kN", f * wob / 1e3),
                vec![set("wob", f * wob)],
                1.0,
            ));
        }
    }
    if case.dynamics.is_some() {
        for f in [1.0, 4.0, 16.0] {
            cells.push(("time step".into(), format!("{f} × case"), vec![], f));
        }
    }
    cells
}

/// Runs the stability study on `case_path`: every cell's static solve and, with a
/// `[dynamics]` table, a short dynamic run; `stability.csv`, `stability.png` (the map) and
/// `summary.json` into `out`.
pub fn stability(
    case_path: &Path,
    out: &Path,
    options: StabilityOptions,
) -> Result<StabilitySummary, Error> {
    use rayon::prelude::*;
    let case = load_case(case_path)?;
    let folder = RunFolder::prepare(out)?;
    let cells = stability_cells(&case);
    let analyses: Vec<&str> = if case.dynamics.is_some() {
        vec!["static", "dynamic"]
    } else {
        vec!["static"]
    };
    let jobs: Vec<(usize, &str)> = (0..cells.len())
        .flat_map(|c| analyses.iter().map(move |a| (c, *a)))
        .filter(|(c, a)| *a == "dynamic" || cells[*c].3 == 1.0)
        .collect();
    let bar = crate::output::progress_bar(
        options.show_progress,
        jobs.len() as u64,
        "{bar:40} {pos}/{len} cells, {elapsed} elapsed, eta {eta}",
    );
    let map: Vec<StabilityCell> = jobs
        .par_iter()
        .map(|&(c, analysis)| {
            let (parameter, value, overrides, dt_factor) = &cells[c];
            let mut this = case.clone();
            if let Some(d) = this.dynamics.as_mut() {
                let duration = options.duration.unwrap_or(d.duration.min(0.5));
                d.time_step *= dt_factor;
                d.duration = duration;
                d.output_interval = d.output_interval.max(d.time_step).min(duration);
            }
            let clock = std::time::Instant::now();
            // Each value checked against its key's range, as a variant's.
            let result = overrides
                .iter()
                .map(|(k, x)| k.si(*x).map(|v| (k.clone(), v)))
                .collect::<Result<Vec<_>, _>>()
                .map(|overrides| Variant {
                    name: "cell".into(),
                    overrides,
                })
                .map_err(|e| e.to_string())
                .and_then(|variant| {
                    crate::ensemble::apply(&this, &variant)
                        .map(|model| (variant, model))
                        .map_err(|e| e.to_string())
                })
                .map(|(variant, model)| match analysis {
                    "static" => (
                        crate::ensemble::qoi::static_variant_of(&this, &variant, &model, true),
                        None,
                    ),
                    _ => crate::ensemble::qoi::dynamic_variant_tracked(&this, "cell", &model, true),
                });
            bar.inc(1);
            let seconds = clock.elapsed().as_secs_f64();
            match result {
                Ok((r, energy_growth)) => StabilityCell {
                    parameter: parameter.clone(),
                    value: value.clone(),
                    analysis: analysis.into(),
                    status: status_name(r.status),
                    step_cuts: r.step_cuts,
                    newton_iterations: r.newton_iterations_per_step,
                    seconds,
                    nan: r.reason.contains("not finite"),
                    energy_growth,
                    reason: r.reason,
                },
                Err(e) => StabilityCell {
                    parameter: parameter.clone(),
                    value: value.clone(),
                    analysis: analysis.into(),
                    status: "refused".into(),
                    step_cuts: 0,
                    newton_iterations: 0.0,
                    seconds,
                    nan: false,
                    energy_growth: None,
                    reason: e,
                },
            }
        })
        .collect();
    bar.finish_and_clear();
    let dir = folder.path();
    crate::output::write_csv_rows(&dir.join("stability.csv"), &map)?;
    let tiles: Vec<crate::plots::Tile> = map
        .iter()
        .map(|c| crate::plots::Tile {
            row: format!("{} ({})", c.parameter, c.analysis),
            column: c.value.clone(),
            colour: match c.status.as_str() {
                "converged" => 0,
                "step_cut" => 1,
                _ => 2,
            },
            text: if c.status == "failed" || c.status == "refused" {
                "fail".into()
            } else {
                match c.energy_growth {
                    Some(g) => format!(
                        "{}c {:.1}it {:+.0}%E",
                        c.step_cuts,
                        c.newton_iterations,
                        100.0 * g
                    ),
                    None => format!("{}c {:.1}it", c.step_cuts, c.newton_iterations),
                }
            },
        })
        .collect();
    crate::plots::tile_map(
        &dir.join("stability.png"),
        &format!(
            "{}: where the solver works (green: solved; amber: with step cuts; red: failed)",
            case.title
        ),
        &tiles,
    )?;
    let count = |s: &str| map.iter().filter(|c| c.status == s).count();
    let summary = StabilitySummary {
        title: case.title.clone(),
        cells: map.len(),
        converged: count("converged"),
        step_cut: count("step_cut"),
        failed: map.len() - count("converged") - count("step_cut"),
        map,
    };
    folder.finish(&serde_json::to_vec_pretty(&summary)?)?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(path: &str, dt: f64, e: f64) -> PrecisionRow {
        PrecisionRow {
            path: path.into(),
            dt_s: dt,
            seconds: 1.0,
            max_error: e,
            worst: "hook_load_n".into(),
            errors: None,
            status: "converged".into(),
        }
    }

    #[test]
    fn no_recommendation_says_why_and_which_step_would_do() {
        // Second order: 4e-4, 1e-4 at 2 ms, 1 ms → 1e-6 needs 0.1 ms.
        let rows = [row("cpu-f64", 2e-3, 4e-4), row("cpu-f64", 1e-3, 1e-4)];
        let n = no_recommendation_note(&rows, 1e-6);
        assert!(n.contains("smallest error is 1.00e-4"), "{n}");
        assert!(
            n.contains("order 2.00") && n.contains("dt ≈ 1.00e-4 s"),
            "{n}"
        );
        // Errors that do not fall with the step.
        let rows = [row("cpu-f64", 2e-3, 1e-4), row("cpu-f64", 1e-3, 1.1e-4)];
        let n = no_recommendation_note(&rows, 1e-6);
        assert!(n.contains("do not fall with the step"), "{n}");
    }
}
