//! `holewall bench …`: throughput benchmarks. Medians over repeats; every ratio is formed
//! from figures measured in the same run.

use std::path::Path;

use serde::Serialize;

use crate::backend::{Backend, BackendChoice, Precision};
use crate::error::{Error, SystemError};
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
            (Backend::Gpu(ctx), _) => Some(ctx),
            (Backend::Cpu, note) => {
                if let Some(n) = note {
                    eprintln!("holewall: {n}");
                }
                None
            }
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
        crate::output::write_json_atomic(path, &report)?;
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
        format!("GPU {name} resident ({} parts)", run.num_parts()),
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
        Error::Input(crate::error::InputError {
            source_name: case_path.display().to_string(),
            line: 0,
            key: "dynamics".into(),
            message: "bench dynamics needs a [dynamics] table".into(),
        })
    })?;
    let model = &case.model;
    let start = solve_static(model, &StaticOptions::default())
        .map_err(|e| Error::failed(format!("static start: {e}")))?;
    let options = settings.integrator_options();
    let density = case.element_density.clone();
    let mut its = (0usize, 0usize, 0usize);
    let t = median_seconds::<Error>(repeats, || {
        let mut d = Dynamics::new(model, options, &|e| density[e]);
        let mut s = d
            .initial_state(start.state.clone())
            .map_err(Error::failed)?;
        d.run(&mut s, steps as f64 * options.dt, &mut |_, _| {})
            .map_err(Error::failed)?;
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
    /// Read-backs of device buffers (host round trips that wait on the device) per run.
    readbacks_per_run: f64,
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
    use crate::engine::{solve_static_ensemble, EngineResult, EngineStatus, TwinPath};
    use crate::gpu::GpuPath;
    use crate::solve::statics::{solve_static, StaticOptions};
    use rayon::prelude::*;
    let case = crate::case::load_case(case_path)?;
    let list = crate::ensemble::case_variants(&case, variants)?.unwrap_or_else(|| {
        vec![crate::ensemble::Variant {
            name: "case".into(),
            overrides: Vec::new(),
        }]
    });
    let models: Vec<crate::model::Model> = list
        .iter()
        .map(|v| crate::ensemble::apply(&case, v))
        .collect::<Result<_, _>>()
        .map_err(Error::failed)?;
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
    let mut rows: Vec<(String, f64, Figures, f64)> = Vec::new();
    let mut figures = None;
    let tally = crate::tally::Tally::now;
    // Read-backs per run since `before` (the mean over the warm-up and the repeats).
    let per_run = |before: &crate::tally::Tally| {
        tally().since(before).readbacks as f64 / (repeats.max(1) + 1) as f64
    };
    let before = tally();
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
        per_run(&before),
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
    let before = tally();
    let t = median_seconds::<Error>(repeats, || {
        let r = solve_static_ensemble(&models, &TwinPath, &options)?;
        figures = Some(engine_figures(&r));
        Ok(())
    })?;
    rows.push((
        "engine, CPU twins (f64)".into(),
        t,
        figures.take().unwrap_or_default(),
        per_run(&before),
    ));
    let mut adapter = "none".to_string();
    if let Ok(ctx) = GpuContext::shared() {
        adapter = format!(
            "{}; block solve: {}",
            ctx.describe(),
            crate::gpu::block_lu::LuForm::describe(ctx)
        );
        if ctx.has_f64 {
            let before = tally();
            let t = median_seconds::<Error>(repeats, || {
                let r = solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options)?;
                figures = Some(engine_figures(&r));
                Ok(())
            })?;
            rows.push((
                "engine, GPU f64".into(),
                t,
                figures.take().unwrap_or_default(),
                per_run(&before),
            ));
        }
        let before = tally();
        let t = median_seconds::<Error>(repeats, || {
            let r = solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options)?;
            figures = Some(engine_figures(&r));
            Ok(())
        })?;
        rows.push((
            "engine, GPU f32".into(),
            t,
            figures.take().unwrap_or_default(),
            per_run(&before),
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
                |(path, t, (steps, mean, median, cuts, solved), readbacks)| StaticsRow {
                    path,
                    median_s: t,
                    ratio_to_cpu_backend: cpu / t,
                    solved,
                    load_steps: steps,
                    newton_iterations_per_load_step_mean: mean,
                    newton_iterations_per_load_step_median: median,
                    step_cuts: cuts,
                    readbacks_per_run: readbacks,
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

#[derive(Serialize)]
struct ElementRow {
    method: String,
    /// Floating-point operations per element, counted (a transcendental as 20).
    flops: u64,
    counts: crate::physics::count::OpCounts,
    median_us_per_element: f64,
    /// Against the one-pass closed form in f64.
    ops_ratio_to_closed: f64,
    /// Against the one-pass closed form in f64.
    time_ratio_to_closed: f64,
}

#[derive(Serialize)]
struct ElementReport {
    states: usize,
    repeats: usize,
    /// Worst difference of the closed form from the 144-evaluation hyper-dual oracle over
    /// the states, relative to the largest entry (force, tangent).
    closed_vs_hyperdual_f64: (f64, f64),
    /// Worst difference of the closed form in f32 (base chord form) from the f64 oracle.
    closed_f32_vs_hyperdual_f64: (f64, f64),
    rows: Vec<ElementRow>,
    /// The rest of a CPU Newton iteration's linear algebra: the block solve per node.
    chain: Vec<ChainRow>,
}

/// One form of the CPU block solve, timed on a random block-diagonally dominant system.
#[derive(Serialize)]
struct ChainRow {
    method: String,
    nodes: usize,
    median_us_per_node: f64,
}

/// Nodes of the system `bench element` times the block solves on.
const CHAIN_NODES: usize = 1000;

/// The block solve per node on a random dominant `CHAIN_NODES`-node system (f64, one
/// core): the walk on the node-major system (`ChainSolver::solve` since stop 74), the same
/// walk on a packed one-variant batch through rayon (the form before, the engine twin's),
/// and faer's sparse LU (the fallback), with their largest difference.
fn chain_rows(repeats: usize) -> Result<(Vec<ChainRow>, f64), Error> {
    use crate::kernels::block_lu::{block_lu, block_lu_one, ChainBatch};
    use crate::solve::chain::{BlockTridiagonal, ChainSolver};
    use rand::SeedableRng;
    let n = CHAIN_NODES;
    let mut rng = rand::rngs::StdRng::seed_from_u64(17);
    let (a, b) = BlockTridiagonal::random_dominant(&mut rng, n, 0);
    let mut solver = ChainSolver::new();
    let (walk, packed) = (
        block_lu_one(&a, &b).0,
        block_lu(&ChainBatch::from_systems(&[(&a, &b)])).0,
    );
    let sparse = solver
        .solve_sparse(&a, &b)
        .map_err(|e| Error::System(SystemError::Linear(e.to_string())))?;
    let differ = walk
        .iter()
        .zip(&packed)
        .chain(walk.iter().zip(&sparse))
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    let sink = std::cell::Cell::new(0.0f64);
    let time = |f: &mut dyn FnMut() -> f64| -> Result<f64, Error> {
        let t = median_seconds::<Error>(repeats, || {
            sink.set(sink.get() + f());
            Ok(())
        })?;
        Ok(1e6 * t / n as f64)
    };
    let rows = [
        (
            "block LU, the walk on the node-major system (ChainSolver::solve, the CPU path)",
            time(&mut || block_lu_one(&a, &b).0[0])?,
        ),
        (
            "block LU, the same walk on a packed one-variant batch through rayon (the CPU path before stop 74; the engine twin's form)",
            time(&mut || block_lu(&ChainBatch::from_systems(&[(&a, &b)])).0[0])?,
        ),
        (
            "faer sparse LU (ChainSolver::solve_sparse: the fallback where a pivot block is singular)",
            time(&mut || solver.solve_sparse(&a, &b).map_or(0.0, |x| x[0]))?,
        ),
    ];
    std::hint::black_box(sink.get());
    let rows = rows
        .into_iter()
        .map(|(method, us)| ChainRow {
            method: method.to_string(),
            nodes: n,
            median_us_per_node: us,
        })
        .collect();
    Ok((rows, differ))
}

/// Cost per transcendental (sin, cos, atan2, powf) in the FLOP figures: a polynomial of
/// about this many operations (the f64 `atan2` written out for the GPU takes ≈ 40).
pub(crate) const TRANSCENDENTAL_FLOPS: u64 = 20;

/// Random element states of a 9 m collar: stretched, bent, twisted, spun rigidly by up to
/// 300 rad, relative rotations up to 0.5 rad (reproducible).
fn element_states(count: usize) -> Vec<crate::physics::beam::ElementState> {
    use crate::physics::beam::{rotation_exp, ElementState};
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(13);
    let l = 9.0;
    (0..count)
        .map(|_| {
            let spin = rotation_exp(&std::array::from_fn(|_| rng.random_range(-300.0..300.0)));
            let rot = |rng: &mut rand::rngs::StdRng| {
                let r = rotation_exp(&std::array::from_fn(|_| rng.random_range(-0.3..0.3)));
                std::array::from_fn(|a| {
                    std::array::from_fn(|b| (0..3).map(|m| r[a][m] * spin[m][b]).sum())
                })
            };
            let (r1, r2) = (rot(&mut rng), rot(&mut rng));
            let x1: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1e3..1e3));
            let stretch = l + rng.random_range(-0.01..0.01);
            let x2 =
                std::array::from_fn(|k| x1[k] + spin[k][0] * stretch + rng.random_range(-0.1..0.1));
            ElementState {
                x: [x1, x2],
                triad: [r1, r2],
            }
        })
        .collect()
}

/// Floating-point operations per element, counted (`TRANSCENDENTAL_FLOPS` per
/// transcendental) on a deformed element: the force and tangent one direction at a time
/// (the GPU kernel), in one 12-direction pass (the CPU), and the force alone.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ElementFlops {
    /// Force and tangent written out (the values once, their variation per direction: the
    /// GPU kernel's form and its twin's).
    pub written_out: u64,
    /// Force and tangent in one pass.
    pub one_pass: u64,
    /// Force alone.
    pub force: u64,
}

/// [`ElementFlops`], counted.
pub fn element_flops() -> ElementFlops {
    use crate::physics::beam::{
        element_force, force_and_tangent_closed, force_and_tangent_variation, BeamSection, Chord,
        ElementStiffness,
    };
    use crate::physics::count::{count, Counted};
    let s = element_states(1)[0];
    let x = s.x.map(|p| p.map(Counted));
    let t = s.triad.map(|m| m.map(|r| r.map(Counted)));
    let form = Chord::Positions { length0: 9.0 }.map(Counted);
    let k = ElementStiffness::of(&BeamSection::tube(0.165, 0.071, 2.1e11, 0.3), 9.0).map(Counted);
    let flops = |c: crate::physics::count::OpCounts| c.flops(TRANSCENDENTAL_FLOPS);
    ElementFlops {
        written_out: flops(count(|| force_and_tangent_variation(&x, &t, &form, &k)).1),
        one_pass: flops(count(|| force_and_tangent_closed(&x, &t, &form, &k)).1),
        force: flops(count(|| element_force(&x, &t, &form, &k)).1),
    }
}

/// Operations and time per element of the beam element's force and tangent: the
/// hyper-dual forms (144 evaluations of the energy: the GPU kernel and twin before the
/// closed form; 78: the CPU path before), the closed form (force only, force and tangent
/// in f64 and f32), one core, `states` random states, median of `repeats`. Operation counts
/// from running the same generic code on a counting float.
pub fn element(states: usize, repeats: usize, json: Option<&Path>) -> Result<(), Error> {
    use crate::physics::beam::{
        element_force, force_and_tangent_by_direction, force_and_tangent_closed,
        force_and_tangent_hyperdual, force_and_tangent_variation, BeamSection, Chord,
        ElementStiffness,
    };
    use crate::physics::count::{count, Counted};
    let section = BeamSection::tube(0.165, 0.071, 2.1e11, 0.3);
    let l0 = 9.0;
    let list = element_states(states.max(1));
    let k64 = ElementStiffness::of(&section, l0);
    let form = Chord::Positions { length0: l0 };
    // The f32 inputs: displacements from a base chord rounded to f32 (the engine's form).
    let f32_inputs: Vec<_> = list
        .iter()
        .map(|s| {
            let d: [f64; 3] = std::array::from_fn(|k| s.x[1][k] - s.x[0][k]);
            let c = d.map(|v| v as f32 as f64);
            let lc = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            let w2: [f32; 3] = std::array::from_fn(|k| (d[k] - c[k]) as f32);
            let base = Chord::Base {
                chord: c,
                stretch: lc - l0,
                length: lc,
            }
            .map(|v| v as f32);
            let t = s.triad.map(|m| m.map(|r| r.map(|v| v as f32)));
            ([[0.0f32; 3], w2], t, base)
        })
        .collect();
    let k32 = k64.map(|v| v as f32);
    // Agreement with the oracle.
    let worst = |f: &[f64; 12], k: &[[f64; 12]; 12], f0: &[f64; 12], k0: &[[f64; 12]; 12]| {
        let fs = f0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let ks = k0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let df = (0..12).fold(0.0f64, |m, a| m.max((f[a] - f0[a]).abs() / fs));
        let dk = (0..144).fold(0.0f64, |m, i| {
            m.max((k[i / 12][i % 12] - k0[i / 12][i % 12]).abs() / ks)
        });
        (df, dk)
    };
    let (mut agree64, mut agree32) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for (s, (x32, t32, b32)) in list.iter().zip(&f32_inputs) {
        let (f0, k0) =
            force_and_tangent_hyperdual(&s.x, &s.triad, &section, l0, &[[0.0; 3]; 2], false);
        let (f, k) = force_and_tangent_closed(&s.x, &s.triad, &form, &k64);
        let w = worst(&f, &k, &f0, &k0);
        agree64 = (agree64.0.max(w.0), agree64.1.max(w.1));
        let (f, k) = force_and_tangent_closed(x32, t32, b32, &k32);
        let up = |v: f32| v as f64;
        let w = worst(&f.map(up), &k.map(|r| r.map(up)), &f0, &k0);
        agree32 = (agree32.0.max(w.0), agree32.1.max(w.1));
    }
    // Counts on the first state (the branches taken are those of a deformed element).
    let s0 = list[0];
    let cx = s0.x.map(|p| p.map(Counted));
    let ct = s0.triad.map(|m| m.map(|r| r.map(Counted)));
    let cform = form.map(Counted);
    let ck = k64.map(Counted);
    let counts = [
        count(|| force_and_tangent_hyperdual(&cx, &ct, &section, l0, &[[0.0; 3]; 2], false)).1,
        count(|| force_and_tangent_hyperdual(&cx, &ct, &section, l0, &[[0.0; 3]; 2], true)).1,
        count(|| element_force(&cx, &ct, &cform, &ck)).1,
        count(|| force_and_tangent_by_direction(&cx, &ct, &cform, &ck)).1,
        count(|| force_and_tangent_closed(&cx, &ct, &cform, &ck)).1,
        count(|| force_and_tangent_closed(&cx, &ct, &cform, &ck)).1,
        count(|| force_and_tangent_variation(&cx, &ct, &cform, &ck)).1,
        count(|| force_and_tangent_variation(&cx, &ct, &cform, &ck)).1,
    ];
    let sink = std::cell::Cell::new(0.0f64);
    let per = |f: &mut dyn FnMut()| -> Result<f64, Error> {
        let t = median_seconds::<Error>(repeats, || {
            f();
            Ok(())
        })?;
        Ok(1e6 * t / list.len() as f64)
    };
    let times = [
        per(&mut || {
            for s in &list {
                let r = force_and_tangent_hyperdual(
                    &s.x,
                    &s.triad,
                    &section,
                    l0,
                    &[[0.0; 3]; 2],
                    false,
                );
                sink.set(sink.get() + r.1[3][4]);
            }
        })?,
        per(&mut || {
            for s in &list {
                let r =
                    force_and_tangent_hyperdual(&s.x, &s.triad, &section, l0, &[[0.0; 3]; 2], true);
                sink.set(sink.get() + r.1[3][4]);
            }
        })?,
        per(&mut || {
            for s in &list {
                let r = element_force(&s.x, &s.triad, &form, &k64);
                sink.set(sink.get() + r[4]);
            }
        })?,
        per(&mut || {
            for s in &list {
                let r = force_and_tangent_by_direction(&s.x, &s.triad, &form, &k64);
                sink.set(sink.get() + r.1[3][4]);
            }
        })?,
        per(&mut || {
            for s in &list {
                let r = force_and_tangent_closed(&s.x, &s.triad, &form, &k64);
                sink.set(sink.get() + r.1[3][4]);
            }
        })?,
        per(&mut || {
            for (x, t, b) in &f32_inputs {
                let r = force_and_tangent_closed(x, t, b, &k32);
                sink.set(sink.get() + r.1[3][4] as f64);
            }
        })?,
        per(&mut || {
            for s in &list {
                let r = force_and_tangent_variation(&s.x, &s.triad, &form, &k64);
                sink.set(sink.get() + r.1[3][4]);
            }
        })?,
        per(&mut || {
            for (x, t, b) in &f32_inputs {
                let r = force_and_tangent_variation(x, t, b, &k32);
                sink.set(sink.get() + r.1[3][4] as f64);
            }
        })?,
    ];
    std::hint::black_box(sink.get());
    let names = [
        "hyper-dual, 144 evaluations (GPU kernel and twin before)",
        "hyper-dual, 78 evaluations (CPU path before)",
        "closed form, force only (line-search trials)",
        "closed form, force and tangent one direction at a time (the GPU kernel's form until stop 73), f64",
        "closed form, force and tangent in one 12-direction pass (the CPU static solve), f64",
        "closed form, force and tangent in one 12-direction pass (the CPU static solve), f32",
        "closed form, the tangent written out (the GPU kernel's, its twin's and, since stop 74, the CPU dynamic integrator's; not the CPU static solve's: docs/performance.md, stop 72), f64",
        "closed form, the tangent written out, f32",
    ];
    let closed = (counts[4].flops(TRANSCENDENTAL_FLOPS), times[4]);
    let rows = (0..names.len())
        .map(|i| ElementRow {
            method: names[i].to_string(),
            flops: counts[i].flops(TRANSCENDENTAL_FLOPS),
            counts: counts[i],
            median_us_per_element: times[i],
            ops_ratio_to_closed: counts[i].flops(TRANSCENDENTAL_FLOPS) as f64 / closed.0 as f64,
            time_ratio_to_closed: times[i] / closed.1,
        })
        .collect();
    let (chain, chain_differ) = chain_rows(repeats)?;
    if chain_differ > 1e-12 {
        return Err(Error::failed(format!(
            "the block solves disagree by {chain_differ:e} on the benchmark system"
        )));
    }
    let report = ElementReport {
        states: list.len(),
        repeats,
        closed_vs_hyperdual_f64: agree64,
        closed_f32_vs_hyperdual_f64: agree32,
        rows,
        chain,
    };
    let text = serde_json::to_string_pretty(&report).unwrap_or_default();
    println!("{text}");
    if let Some(path) = json {
        write_atomic(path, text.as_bytes())?;
    }
    Ok(())
}
