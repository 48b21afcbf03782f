//! `holewall bench …`: throughput benchmarks. Medians over repeats; every ratio is formed
//! from figures measured in the same run.

use std::path::Path;

use serde::Serialize;

use crate::backend::{Backend, BackendChoice, Precision};
use crate::error::Error;
use crate::gpu::contact::{GpuContactRun, GpuReal};
use crate::gpu::GpuContext;
use crate::kernels::contact::{contact as contact_twin, ContactBatch, ContactOutputs};
use crate::output::write_atomic;
use crate::physics::contact::{ContactMode, ContactTerms, FrictionModel};
use crate::selfcheck::{median_seconds, random_batch};

#[derive(Serialize)]
struct Row {
    path: String,
    median_s: f64,
    evals_per_s: f64,
    ratio_to_cpu_f64: f64,
}

#[derive(Serialize)]
struct Report {
    pairs: usize,
    repeats: usize,
    terms: String,
    cpu_threads: usize,
    adapter: String,
    rows: Vec<Row>,
}

/// Contact evaluations per second for `pairs` (variant, site) pairs with the all-terms
/// kernel (split friction, dynamic): CPU f64 and f32 twins on all cores; GPU f32 and f64
/// with the data resident (kernel + wait) and end to end (upload + kernel + read-back).
pub fn contact(
    pairs: usize,
    repeats: usize,
    backend: BackendChoice,
    json: Option<&Path>,
) -> Result<(), Error> {
    let terms = ContactTerms::all(FrictionModel::Split, ContactMode::Dynamic);
    let num_variants = 1000.min(pairs.max(1));
    let batch = random_batch(
        42,
        num_variants,
        pairs.div_ceil(num_variants),
        FrictionModel::Split,
    );
    let p = batch.num_pairs();
    let mut rows: Vec<(String, f64)> = Vec::new();
    let mut out64 = ContactOutputs::new(p);
    let t = median_seconds::<Error>(repeats, || {
        contact_twin(&terms, &batch, &mut out64);
        Ok(())
    })?;
    rows.push(("CPU f64 (twin, rayon)".into(), t));
    let b32 = batch.cast::<f32>();
    let mut out32 = ContactOutputs::new(p);
    let t = median_seconds::<Error>(repeats, || {
        contact_twin(&terms, &b32, &mut out32);
        Ok(())
    })?;
    rows.push(("CPU f32 (twin, rayon)".into(), t));
    let mut adapter = "none".to_string();
    let gpu = match backend {
        BackendChoice::Cpu => None,
        other => match Backend::resolve(other, Precision::F32)? {
            Backend::Gpu(ctx) => Some(ctx),
            Backend::Cpu => None,
        },
    };
    if let Some(ctx) = gpu {
        adapter = ctx.describe();
        gpu_rows(ctx, &terms, &b32, repeats, &mut rows)?;
        if ctx.has_f64 {
            gpu_rows(ctx, &terms, &batch, repeats, &mut rows)?;
        }
    }
    let cpu64 = rows[0].1;
    println!(
        "contact evaluations, {p} pairs, all-terms kernel (split, dynamic), median of {repeats}"
    );
    println!(
        "adapter: {adapter}; CPU threads: {}",
        rayon::current_num_threads()
    );
    println!("| path | median time (s) | evaluations/s | ratio to CPU f64 |");
    println!("|---|---|---|---|");
    let rows: Vec<Row> = rows
        .into_iter()
        .map(|(path, t)| Row {
            path,
            median_s: t,
            evals_per_s: p as f64 / t,
            ratio_to_cpu_f64: cpu64 / t,
        })
        .collect();
    for r in &rows {
        println!(
            "| {} | {:.4e} | {:.3e} | {:.2} |",
            r.path, r.median_s, r.evals_per_s, r.ratio_to_cpu_f64
        );
    }
    if let Some(path) = json {
        let report = Report {
            pairs: p,
            repeats,
            terms: format!("{terms:?}"),
            cpu_threads: rayon::current_num_threads(),
            adapter,
            rows,
        };
        let text = serde_json::to_string_pretty(&report).map_err(std::io::Error::other)?;
        write_atomic(path, text.as_bytes())?;
    }
    Ok(())
}

/// Resident (kernel + wait) and end-to-end (upload, kernel, read-back) rows for one precision.
fn gpu_rows<T: GpuReal>(
    ctx: &'static GpuContext,
    terms: &ContactTerms,
    batch: &ContactBatch<T>,
    repeats: usize,
    rows: &mut Vec<(String, f64)>,
) -> Result<(), Error> {
    let run = GpuContactRun::new(ctx, terms, batch)?;
    let name = T::NAME;
    rows.push((
        format!("GPU {name} resident ({} chunks)", run.num_chunks()),
        median_seconds(repeats, || run.dispatch())?,
    ));
    rows.push((
        format!("GPU {name} end to end"),
        median_seconds(repeats, || {
            let r = GpuContactRun::new(ctx, terms, batch)?;
            r.dispatch()?;
            r.read().map(|_| ())
        })?,
    ));
    Ok(())
}

#[derive(Serialize)]
struct DynamicsReport {
    case: String,
    nodes: usize,
    elements: usize,
    contact_sites: usize,
    time_step_s: f64,
    steps: usize,
    repeats: usize,
    median_s: f64,
    steps_per_s: f64,
    newton_iterations_per_step: f64,
    ms_per_newton_iteration: f64,
    step_cuts: usize,
}

/// Steps per second and Newton iterations per step of the CPU f64 integrator on a case
/// with a `[dynamics]` table: `steps` steps from the static equilibrium, timed `repeats`
/// times (median).
pub fn dynamics(
    case_path: &Path,
    steps: usize,
    repeats: usize,
    json: Option<&Path>,
) -> Result<(), Error> {
    use crate::solve::dynamics::Dynamics;
    use crate::solve::statics::{solve_static, StaticOptions};
    let case = crate::case::load_case(case_path)?;
    let settings = case.dynamics.clone().ok_or_else(|| {
        Error::Io(std::io::Error::other(format!(
            "{}: bench dynamics needs a [dynamics] table",
            case_path.display()
        )))
    })?;
    let model = &case.model;
    let start = solve_static(model, &StaticOptions::default())
        .map_err(|e| Error::Io(std::io::Error::other(format!("static start: {e}"))))?;
    let options = super::run_cmd::options_for(&settings);
    let density = case.element_density.clone();
    let mut its = (0usize, 0usize, 0usize);
    let t = median_seconds::<Error>(repeats, || {
        let mut d = Dynamics::new(model, options, &|e| density[e]);
        let mut s = d
            .initial_state(start.state.clone())
            .map_err(|e| Error::Io(std::io::Error::other(e)))?;
        d.run(&mut s, steps as f64 * options.dt, &mut |_, _| {})
            .map_err(|e| Error::Io(std::io::Error::other(e)))?;
        its = (
            d.iterations.len(),
            d.iterations.iter().sum(),
            d.log.iter().filter(|l| l.contains("cut to")).count(),
        );
        Ok(())
    })?;
    let report = DynamicsReport {
        case: case_path.display().to_string(),
        nodes: model.nodes.len(),
        elements: model.elements.len(),
        contact_sites: model.sites.len(),
        time_step_s: options.dt,
        steps: its.0,
        repeats,
        median_s: t,
        steps_per_s: its.0 as f64 / t,
        newton_iterations_per_step: its.1 as f64 / its.0.max(1) as f64,
        ms_per_newton_iteration: 1e3 * t / its.1.max(1) as f64,
        step_cuts: its.2,
    };
    let text = serde_json::to_string_pretty(&report).unwrap_or_default();
    println!("{text}");
    if let Some(path) = json {
        write_atomic(path, text.as_bytes())?;
    }
    Ok(())
}

#[derive(Serialize)]
struct StaticsRow {
    path: String,
    median_s: f64,
    ratio_to_cpu_backend: f64,
    /// Variants this path solved itself (the engine's failures would be re-run on the CPU).
    solved: usize,
    load_steps: usize,
    newton_iterations_per_load_step_mean: f64,
    newton_iterations_per_load_step_median: usize,
    step_cuts: usize,
}

#[derive(Serialize)]
struct StaticsReport {
    case: String,
    variants: usize,
    nodes: usize,
    contact_sites: usize,
    repeats: usize,
    cpu_threads: usize,
    adapter: String,
    rows: Vec<StaticsRow>,
}

/// Wall time of a static ensemble — the case's variants (`variants` CSV, or its
/// `[ensemble.grid]`) — on every path in one run: the CPU backend (`solve_static` per
/// variant, rayon), the engine on the CPU twins (f64) and on the GPU (f64, f32) where an
/// adapter is; medians over `repeats`, with each path's own solves, iterations per load
/// step and cuts.
pub fn statics(
    case_path: &Path,
    variants: Option<&Path>,
    repeats: usize,
    json: Option<&Path>,
) -> Result<(), Error> {
    use crate::engine::{solve_static_ensemble, EngineResult, EngineStatus, GpuPath, TwinPath};
    use crate::solve::statics::{solve_static, StaticOptions};
    use rayon::prelude::*;
    let case = crate::case::load_case(case_path)?;
    let list = crate::ensemble::case_variants(&case, variants)?.unwrap_or_else(|| {
        vec![crate::ensemble::Variant {
            name: "case".into(),
            overrides: Vec::new(),
        }]
    });
    let io = |e: String| Error::Io(std::io::Error::other(e));
    let models: Vec<crate::model::Model> = list
        .iter()
        .map(|v| crate::ensemble::apply(&case, v))
        .collect::<Result<_, _>>()
        .map_err(io)?;
    let options = StaticOptions::default();
    let summary = |its: Vec<Vec<usize>>, cuts: usize, solved: usize| {
        let mut all: Vec<usize> = its.into_iter().flatten().collect();
        all.sort_unstable();
        (
            all.len(),
            all.iter().sum::<usize>() as f64 / all.len().max(1) as f64,
            all.get(all.len() / 2).copied().unwrap_or(0),
            cuts,
            solved,
        )
    };
    type Figures = (usize, f64, usize, usize, usize);
    let mut rows: Vec<(String, f64, Figures)> = Vec::new();
    let mut figures = None;
    let t = median_seconds::<Error>(repeats, || {
        let out: Vec<_> = models
            .par_iter()
            .map(|m| solve_static(m, &options))
            .collect();
        let cuts = out
            .iter()
            .flatten()
            .map(|s| s.log.iter().filter(|l| l.contains("cut")).count())
            .sum();
        let solved = out.iter().filter(|s| s.is_ok()).count();
        let its = out.into_iter().flatten().map(|s| s.iterations).collect();
        figures = Some(summary(its, cuts, solved));
        Ok(())
    })?;
    rows.push((
        "cpu backend (solve_static per variant, f64)".into(),
        t,
        figures.take().unwrap_or_default(),
    ));
    let engine_figures = |r: &[EngineResult]| {
        let cuts = r
            .iter()
            .map(|x| x.log.iter().filter(|l| l.contains("cut")).count())
            .sum();
        let solved = r
            .iter()
            .filter(|x| x.status == EngineStatus::Converged)
            .count();
        summary(
            r.iter().map(|x| x.iterations.clone()).collect(),
            cuts,
            solved,
        )
    };
    let t = median_seconds::<Error>(repeats, || {
        let r = solve_static_ensemble(&models, &TwinPath, &options).map_err(io)?;
        figures = Some(engine_figures(&r));
        Ok(())
    })?;
    rows.push((
        "engine, CPU twins (f64)".into(),
        t,
        figures.take().unwrap_or_default(),
    ));
    let mut adapter = "none".to_string();
    if let Ok(ctx) = GpuContext::shared() {
        adapter = ctx.describe();
        if ctx.has_f64 {
            let t = median_seconds::<Error>(repeats, || {
                let r = solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options)
                    .map_err(io)?;
                figures = Some(engine_figures(&r));
                Ok(())
            })?;
            rows.push((
                "engine, GPU f64".into(),
                t,
                figures.take().unwrap_or_default(),
            ));
        }
        let t = median_seconds::<Error>(repeats, || {
            let r =
                solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options).map_err(io)?;
            figures = Some(engine_figures(&r));
            Ok(())
        })?;
        rows.push((
            "engine, GPU f32".into(),
            t,
            figures.take().unwrap_or_default(),
        ));
    }
    let cpu = rows[0].1;
    let report = StaticsReport {
        case: case_path.display().to_string(),
        variants: models.len(),
        nodes: models[0].nodes.len(),
        contact_sites: models[0].sites.len(),
        repeats,
        cpu_threads: rayon::current_num_threads(),
        adapter,
        rows: rows
            .into_iter()
            .map(
                |(path, t, (steps, mean, median, cuts, solved))| StaticsRow {
                    path,
                    median_s: t,
                    ratio_to_cpu_backend: cpu / t,
                    solved,
                    load_steps: steps,
                    newton_iterations_per_load_step_mean: mean,
                    newton_iterations_per_load_step_median: median,
                    step_cuts: cuts,
                },
            )
            .collect(),
    };
    let text = serde_json::to_string_pretty(&report).unwrap_or_default();
    println!("{text}");
    if let Some(path) = json {
        write_atomic(path, text.as_bytes())?;
    }
    Ok(())
}
