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
