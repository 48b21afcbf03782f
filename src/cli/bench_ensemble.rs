//! `holewall bench ensemble`: variant-steps per second of dynamic ensembles of V variants
//! on an n-node string, for the CPU f64 integrator (rayon over variants, faer) and the GPU
//! engine in f64 and f32 — medians over repeats, ratios from the same run — with the
//! bytes and floating-point operations of one Newton iteration, and a work-precision table
//! (error against a fine-step f64 CPU run beside the run time, at three step sizes).
//!
//! The string: the test bed's BHA (9.25 m collar, 1.5 m stabilizer, 20 m collar) and drill
//! pipe to `(n − 1) · 1.5 m`, in a hole built at 1°/m from 5 m to 60°, contact at every
//! node, 20 kN on bit, the table ramped to 120 rpm over 0.2 s; variants spread the
//! friction factor over 0.2 … 0.4.

use std::path::Path;

use serde::Serialize;

use crate::error::Error;
use crate::gpu::contact::GpuReal;
use crate::gpu::GpuContext;
use crate::model::Model;
use crate::solve::dynamics::{DynamicOptions, Dynamics};
use crate::solve::statics::{solve_static, StaticOptions, StaticState};

/// The benchmark string's case text for `n` nodes (1.5 m elements).
pub fn bench_case_text(n: usize) -> String {
    let total = 1.5 * (n.max(25) - 1) as f64;
    format!(
        r#"title = "Ensemble benchmark, {n} nodes"
[well]
profile = "build_and_hold"
total_md = "{total} m"
kickoff_md = "5 m"
build_rate_deg_per_30m = 30
hold_inclination = 60
azimuth = 0
[[hole]]
bottom_md = "{total} m"
diameter = "8.5 in"
friction = 0.3
[mud]
density = "1.2 sg"
[[string]]
kind = "collar"
length = "9.25 m"
od = "6.5 in"
id = "2.8125 in"
[[string]]
kind = "stabilizer"
length = "1.5 m"
od = "6.5 in"
id = "2.8125 in"
blade_diameter = "8.25 in"
[[string]]
kind = "collar"
length = "20 m"
od = "6.5 in"
id = "2.8125 in"
[[string]]
kind = "drill_pipe"
length = "{pipe} m"
od = "5 in"
id = "4.276 in"
[operation]
mode = "rotating"
weight_on_bit = "20 kN"
rpm = "120 rpm"
[contact]
sites = "all_nodes"
wall_stiffness = 6e7
eps = 1e-3
[mesh]
element_length = "1.5 m"
bha_element_length = "1.5 m"
[dynamics]
duration = "0.1 s"
time_step = "2 ms"
output_interval = "10 ms"
ramp_time = "0.2 s"
rho_inf = 0.8
"#,
        pipe = total - 30.75
    )
}

/// Bytes read and written by one Newton iteration of one variant: one evaluation of the
/// system (every kernel of the dynamic engine once, the beam kernel with its tangent), one
/// line-search trial (the same chain with the force-only beam kernel: no 144-value tangent
/// written) and the block solve, at `size`-byte floats, for `n` nodes and `s` contact sites.
pub fn bytes_per_iteration(n: usize, s: usize, size: usize) -> usize {
    let m = n - 1;
    let predict = 36 * n + 24 * n;
    let beam = 24 * m + 156 * m;
    let beam_force = 24 * m + 12 * m;
    let sites = 3 * s + 6 * s + 3 * s + 7 * s;
    let contact = 19 * s + 48 * s;
    let assemble = 156 * m + 48 * s + 6 * n + 21 * n + 36 * n + 72 * m + 6 * n;
    let lu = 2 * (36 * n + 72 * m + 6 * n) + 2 * (36 * m + 12 * n);
    let norms = 12 * n;
    let chain = predict + sites + contact + assemble;
    size * (2 * chain + beam + beam_force + lu + 2 * norms + 12 * n)
}

/// Floating-point operations of one Newton iteration of one variant: one evaluation with
/// the element tangent (`tangent_flops` per element: counted, `cli::bench::element_flops`),
/// one line-search trial (`force_flops` per element), the contact element and assembly
/// (estimates from the kernels' text: ≈ 400 per site, ≈ 1200 per node, twice) and the
/// block solve.
pub fn flops_per_iteration(n: usize, s: usize, tangent_flops: u64, force_flops: u64) -> f64 {
    let m = (n - 1) as f64;
    let beam = (tangent_flops + force_flops) as f64 * m;
    let contact = 2.0 * 400.0 * s as f64;
    let assemble = 2.0 * 1200.0 * n as f64;
    // Block LU per node: a 6×6 factorisation with 12 right-hand columns, two block
    // products and two solves.
    let lu = (2.0 / 3.0 * 216.0 + 2.0 * 216.0 * 2.0 + 2.0 * 432.0 + 4.0 * 36.0) * n as f64;
    beam + contact + assemble + lu
}

#[derive(Serialize, Clone)]
struct Cell {
    nodes: usize,
    variants: usize,
    path: String,
    median_s: Option<f64>,
    variant_steps_per_s: Option<f64>,
    ratio_to_cpu_f64: Option<f64>,
    newton_iterations_per_step: Option<f64>,
    effective_gflops: Option<f64>,
    effective_gbytes_per_s: Option<f64>,
    /// Where a GPU run's time went: the median run's ([`crate::tally`]; in the report's
    /// `splits`, a table of its own).
    #[serde(skip)]
    split: Option<Split>,
    note: String,
}

/// A GPU run's wall time split ([`crate::tally`]): the batches' setup, the host's waits on
/// read-backs (the device's work, the copies and the round trips), and the host's own
/// work between them; with the read-backs per time step.
#[derive(Serialize, Clone, Copy)]
struct Split {
    nodes: usize,
    variants: usize,
    path: &'static str,
    setup_s: f64,
    /// Of the setup, opening the batches on the GPU (buffers made, tables and state uploaded).
    open_s: f64,
    wait_s: f64,
    /// Of the waits, the device's own time in the stamped passes (None: no timestamps).
    device_s: Option<f64>,
    /// Of the device's time, the line-search trials'.
    trial_device_s: Option<f64>,
    /// Line-search trial passes per time step.
    trials_per_step: f64,
    host_s: f64,
    readbacks_per_step: f64,
    kbytes_read_per_step: f64,
}

#[derive(Serialize)]
struct Precision {
    path: String,
    time_step_s: f64,
    seconds: f64,
    max_relative_error: f64,
}

#[derive(Serialize)]
struct Report {
    adapter: String,
    cpu_threads: usize,
    steps: usize,
    repeats: usize,
    budget_s: f64,
    cells: Vec<Cell>,
    /// Where each GPU cell's median run spent its time.
    splits: Vec<Split>,
    work_precision: Vec<Precision>,
}

/// Positions per node of one variant.
type Positions = Vec<[f64; 3]>;

/// The split of the run of median wall time among `runs` (wall seconds, tally).
fn median_split(
    cell: (usize, usize, &'static str),
    runs: &[(f64, crate::tally::Tally)],
    steps: usize,
) -> Option<Split> {
    let mut sorted: Vec<_> = runs.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let &(wall, d) = sorted.get(sorted.len() / 2)?;
    let steps = steps.max(1) as f64;
    Some(Split {
        nodes: cell.0,
        variants: cell.1,
        path: cell.2,
        setup_s: d.setup_s,
        open_s: d.open_s,
        wait_s: d.wait_s,
        device_s: (d.device_s > 0.0).then_some(d.device_s),
        trial_device_s: (d.device_s > 0.0).then_some(d.trial_device_s),
        trials_per_step: d.trials as f64 / steps,
        host_s: wall - d.setup_s - d.wait_s,
        readbacks_per_step: d.readbacks as f64 / steps,
        kbytes_read_per_step: d.bytes_read as f64 / 1e3 / steps,
    })
}

/// Newton iterations of a run, and every variant's final positions.
type RunOutcome = (usize, Vec<Positions>);

fn failed(e: impl std::fmt::Display) -> Error {
    Error::failed(e)
}

/// `v` variants of the benchmark string, friction spread over 0.2 … 0.4.
fn variants(base: &Model, v: usize) -> Vec<Model> {
    (0..v)
        .map(|j| {
            let mut m = base.clone();
            let mu = 0.2 + 0.2 * j as f64 / (v.max(2) - 1) as f64;
            for s in &mut m.sites {
                s.params.mu_t = mu;
                s.params.mu_l = mu;
            }
            m
        })
        .collect()
}

/// The CPU f64 integrator on every variant (rayon over variants): Newton iterations.
fn run_cpu(
    models: &[Model],
    start: &StaticState,
    density: &[f64],
    options: &DynamicOptions,
    t_end: f64,
) -> Result<RunOutcome, Error> {
    use rayon::prelude::*;
    let out: Vec<Result<(usize, Positions), String>> = models
        .par_iter()
        .map(|m| {
            let mut d = Dynamics::new(m, *options, &|e| density[e]);
            let mut s = d.initial_state(start.clone()).map_err(|e| e.to_string())?;
            d.run(&mut s, t_end, &mut |_, _| {})
                .map_err(|e| e.to_string())?;
            Ok((d.iterations.iter().sum(), s.q.positions(m)))
        })
        .collect();
    let mut its = 0;
    let mut xs = Vec::new();
    for r in out {
        let (i, x) = r.map_err(failed)?;
        its += i;
        xs.push(x);
    }
    Ok((its, xs))
}

/// The GPU engine in `T`: Newton iterations and final positions.
fn run_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    models: &[Model],
    start: &StaticState,
    density: &[f64],
    options: &DynamicOptions,
    t_end: f64,
) -> Result<RunOutcome, Error> {
    use crate::engine::dynamic::run_dynamic_ensemble;
    let starts = vec![(start.clone(), None); models.len()];
    let steps = (t_end / options.dt).round() as usize;
    let mut last = None;
    let r = run_dynamic_ensemble::<T, _>(
        models,
        &starts,
        density,
        &crate::gpu::GpuPath(ctx),
        options,
        t_end,
        steps,
        &mut |first, _, b| {
            if first == 0 {
                last = Some(b.clone());
            }
        },
    )
    .map_err(failed)?;
    let its = r.iter().map(|x| x.iterations.iter().sum::<usize>()).sum();
    let n = models[0].nodes.len();
    let xs = match last {
        Some(b) if b.num_variants == models.len() => (0..models.len())
            .map(|j| {
                (0..n)
                    .map(|i| {
                        std::array::from_fn(|k| {
                            models[j].nodes[i].position[k]
                                + b.u[(3 * i + k) * b.num_variants + j].to_f64_lossy()
                        })
                    })
                    .collect()
            })
            .collect(),
        _ => Vec::new(),
    };
    Ok((its, xs))
}

/// Largest displacement error of `xs` against `reference`, relative to the reference's
/// largest displacement from `x0`.
fn relative_error(xs: &[Positions], reference: &[Positions], x0: &[[f64; 3]]) -> f64 {
    let mut scale: f64 = 0.0;
    let mut err: f64 = 0.0;
    for (a, b) in xs.iter().zip(reference) {
        for ((p, q), o) in a.iter().zip(b).zip(x0) {
            for k in 0..3 {
                scale = scale.max((q[k] - o[k]).abs());
                err = err.max((p[k] - q[k]).abs());
            }
        }
    }
    err / scale
}

/// Runs the benchmark: every (n, V) cell for each path, skipping cells whose time,
/// estimated from the path's rate on smaller cells, exceeds `budget_s`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    node_counts: &[usize],
    variant_counts: &[usize],
    steps: usize,
    repeats: usize,
    budget_s: f64,
    gpu: bool,
    precision_nodes: usize,
    json: Option<&Path>,
) -> Result<(), Error> {
    use crate::selfcheck::median_seconds;
    let ctx = if gpu {
        Some(GpuContext::shared()?)
    } else {
        None
    };
    let adapter = ctx
        .map(|c| {
            format!(
                "{}; block solve: {}",
                c.describe(),
                crate::gpu::block_lu::LuForm::describe(c)
            )
        })
        .unwrap_or_else(|| "none".into());
    let mut cells: Vec<Cell> = Vec::new();
    // Counted once: the element's operations do not depend on the cell.
    let e = super::bench::element_flops();
    let paths: Vec<&str> = if ctx.is_some_and(|c| c.has_f64) {
        vec!["CPU f64", "GPU f64", "GPU f32"]
    } else if ctx.is_some() {
        vec!["CPU f64", "GPU f32"]
    } else {
        vec!["CPU f64"]
    };
    for &n in node_counts {
        let case = crate::case::parse_case(Path::new("bench.toml"), &bench_case_text(n))?;
        let base = &case.model;
        let nodes = base.nodes.len();
        let start = solve_static(base, &StaticOptions::default())
            .map_err(failed)?
            .state;
        let options = case
            .dynamics
            .as_ref()
            .ok_or_else(|| failed("no [dynamics]"))?
            .integrator_options();
        let t_end = steps as f64 * options.dt;
        let density = case.element_density.clone();
        let mut rate: std::collections::HashMap<&str, f64> = Default::default();
        for &v in variant_counts {
            let models = variants(base, v);
            let mut cpu_time = None;
            for &path in &paths {
                let mut cell = Cell {
                    nodes,
                    variants: v,
                    path: path.to_string(),
                    median_s: None,
                    variant_steps_per_s: None,
                    ratio_to_cpu_f64: None,
                    newton_iterations_per_step: None,
                    effective_gflops: None,
                    effective_gbytes_per_s: None,
                    split: None,
                    note: String::new(),
                };
                if let Some(r) = rate.get(path) {
                    let estimate = (v * steps) as f64 / r;
                    if estimate > budget_s {
                        cell.note =
                            format!("skipped: ≈ {estimate:.0} s at the rate of smaller cells");
                        cells.push(cell);
                        continue;
                    }
                }
                let mut its = 0;
                // Each run's wall time and tally (the first is median_seconds' warm-up).
                let mut tallies = Vec::new();
                let t = median_seconds::<Error>(repeats, || {
                    let (before, wall) = (crate::tally::Tally::now(), std::time::Instant::now());
                    its = match (path, ctx) {
                        ("GPU f64", Some(c)) => {
                            run_gpu::<f64>(c, &models, &start, &density, &options, t_end)?.0
                        }
                        ("GPU f32", Some(c)) => {
                            run_gpu::<f32>(c, &models, &start, &density, &options, t_end)?.0
                        }
                        _ => run_cpu(&models, &start, &density, &options, t_end)?.0,
                    };
                    let d = crate::tally::Tally::now().since(&before);
                    tallies.push((wall.elapsed().as_secs_f64(), d));
                    Ok(())
                })?;
                if path.starts_with("GPU") {
                    cell.split = median_split((nodes, v, path), &tallies[1..], steps);
                }
                let size = if path.ends_with("f32") { 4 } else { 8 };
                let per_it = its as f64 / (v * steps) as f64;
                let s = base.sites.len();
                cell.median_s = Some(t);
                cell.variant_steps_per_s = Some((v * steps) as f64 / t);
                cell.newton_iterations_per_step = Some(per_it);
                let tangent = if path.starts_with("GPU") {
                    e.written_out
                } else {
                    e.one_pass
                };
                cell.effective_gflops =
                    Some(flops_per_iteration(nodes, s, tangent, e.force) * its as f64 / t / 1e9);
                cell.effective_gbytes_per_s =
                    Some(bytes_per_iteration(nodes, s, size) as f64 * its as f64 / t / 1e9);
                if path == "CPU f64" {
                    cpu_time = Some(t);
                }
                cell.ratio_to_cpu_f64 = cpu_time.map(|c| c / t);
                rate.insert(path, (v * steps) as f64 / t);
                eprintln!(
                    "n {nodes}, V {v}, {path}: {t:.3} s, {:.1} variant-steps/s",
                    (v * steps) as f64 / t
                );
                cells.push(cell);
            }
        }
    }
    // Work-precision: 16 variants of the n-node string over 20 ms at three steps, against
    // the CPU integrator at an eighth of the finest.
    let mut work_precision = Vec::new();
    if precision_nodes > 0 {
        let case =
            crate::case::parse_case(Path::new("bench.toml"), &bench_case_text(precision_nodes))?;
        let base = &case.model;
        let start = solve_static(base, &StaticOptions::default())
            .map_err(failed)?
            .state;
        let models = variants(base, 16);
        let density = case.element_density.clone();
        let mut options = case
            .dynamics
            .as_ref()
            .ok_or_else(|| failed("no [dynamics]"))?
            .integrator_options();
        let t_end = 0.02;
        options.dt = 0.5e-3 / 8.0;
        let (_, reference) = run_cpu(&models, &start, &density, &options, t_end)?;
        let x0: Vec<[f64; 3]> = start.positions(&models[0]);
        for dt in [2e-3, 1e-3, 0.5e-3] {
            options.dt = dt;
            for &path in &paths {
                let t0 = std::time::Instant::now();
                let xs = match (path, ctx) {
                    ("GPU f64", Some(c)) => {
                        run_gpu::<f64>(c, &models, &start, &density, &options, t_end)?.1
                    }
                    ("GPU f32", Some(c)) => {
                        run_gpu::<f32>(c, &models, &start, &density, &options, t_end)?.1
                    }
                    _ => run_cpu(&models, &start, &density, &options, t_end)?.1,
                };
                let seconds = t0.elapsed().as_secs_f64();
                let e = relative_error(&xs, &reference, &x0);
                eprintln!("work-precision: {path}, h = {dt:e} s: error {e:.2e}, {seconds:.2} s");
                work_precision.push(Precision {
                    path: path.to_string(),
                    time_step_s: dt,
                    seconds,
                    max_relative_error: e,
                });
            }
        }
    }
    println!(
        "adapter: {adapter}; CPU threads: {}",
        rayon::current_num_threads()
    );
    println!("| nodes | variants | path | median (s) | variant-steps/s | vs CPU f64 | Newton its/step | GFLOP/s (est.) | GB/s | note |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let f = |x: Option<f64>, p: usize| x.map(|y| format!("{y:.p$}")).unwrap_or_else(|| "–".into());
    for c in &cells {
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.nodes,
            c.variants,
            c.path,
            f(c.median_s, 3),
            f(c.variant_steps_per_s, 1),
            f(c.ratio_to_cpu_f64, 2),
            f(c.newton_iterations_per_step, 2),
            f(c.effective_gflops, 2),
            f(c.effective_gbytes_per_s, 2),
            c.note
        );
    }
    if cells.iter().any(|c| c.split.is_some()) {
        println!(
            "\nWhere a GPU run's time goes (the median run): setup of the batches, the host \
             waiting on read-backs (the device's work, copies, round trips), the host's own \
             work between them"
        );
        println!(
            "| nodes | variants | path | run (s) | setup (s) | of it, opening on the GPU (s) | waiting (s) | of it, passes on \
             the device (s) | of those, trials (s) | host (s) | read-backs/step | \
             trials/step | kB read/step |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for c in &cells {
            if let Some(s) = c.split {
                println!(
                    "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {} | {:.3} | {:.1} | {:.1} | {:.1} |",
                    c.nodes,
                    c.variants,
                    c.path,
                    s.setup_s + s.wait_s + s.host_s,
                    s.setup_s,
                    s.open_s,
                    s.wait_s,
                    s.device_s.map_or("–".into(), |d| format!("{d:.3}")),
                    s.trial_device_s.map_or("–".into(), |d| format!("{d:.3}")),
                    s.host_s,
                    s.readbacks_per_step,
                    s.trials_per_step,
                    s.kbytes_read_per_step
                );
            }
        }
    }
    if !work_precision.is_empty() {
        println!("\n| path | step (s) | run time (s) | max relative error |");
        println!("|---|---|---|---|");
        for w in &work_precision {
            println!(
                "| {} | {:e} | {:.2} | {:.2e} |",
                w.path, w.time_step_s, w.seconds, w.max_relative_error
            );
        }
    }
    if let Some(p) = json {
        let report = Report {
            adapter,
            cpu_threads: rayon::current_num_threads(),
            steps,
            repeats,
            budget_s,
            splits: cells.iter().filter_map(|c| c.split).collect(),
            cells,
            work_precision,
        };
        crate::output::write_json_atomic(p, &report)?;
    }
    Ok(())
}
