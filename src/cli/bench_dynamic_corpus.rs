//! `holewall bench dynamic-corpus`: the dynamic run (`holewall run`'s static start and
//! generalised-α integration, CPU f64) on a corpus of BHA runs drawn from seeds
//! ([`crate::corpus::dynamic`]) — solved / total, uncut, step cuts, Newton iterations per
//! step, wall time per simulated second, the lateral energy's growth — as
//! `dynamic_corpus.csv`, `summary.json` and plots; the first `--engine-sample` cases (of at
//! most `--engine-max-nodes` nodes, lumped mass) also through the GPU engine in f64 and f32,
//! against the CPU run (`engine.csv`).

use std::path::Path;

use rayon::prelude::*;
use serde::Serialize;

use crate::corpus::dynamic::{
    run_case_dynamic, run_case_engine, run_case_perturbed, write_dynamic_case, DynamicEngineRow,
    DynamicRow,
};
use crate::corpus::{spread, Spread};
use crate::error::Error;

/// Options of the benchmark.
#[derive(Clone, Debug)]
pub struct DynamicCorpusOptions {
    /// Cases (seeds `first_seed`, `first_seed + 1`, …).
    pub cases: usize,
    /// First seed.
    pub first_seed: u64,
    /// Cases also run through the engine.
    pub engine_sample: usize,
    /// Largest mesh of the engine sample (nodes).
    pub engine_max_nodes: usize,
    /// Start no new case after this many seconds.
    pub max_seconds: Option<f64>,
    /// Progress bar.
    pub show_progress: bool,
}

/// One engine path over the sample.
#[derive(Clone, Debug, Serialize)]
pub struct EnginePathSummary {
    /// `gpu_f64` or `gpu_f32`.
    pub path: String,
    /// Cases run.
    pub cases: usize,
    /// Solved by the engine itself.
    pub by_engine: usize,
    /// Re-run on the CPU after the engine failed (seed, why).
    pub fallbacks: Vec<(u64, String)>,
    /// |Δ hook load| / CPU's.
    pub hook_load_rel: Spread,
    /// |Δ hook load| / the run's force scale
    /// ([`crate::corpus::dynamic::DynamicEngineRow::hook_load_of_force_scale`]).
    pub hook_load_of_force_scale: Spread,
    /// |Δ largest surface torque| / CPU's.
    pub torque_rel: Spread,
    /// |Δ stab1's largest side force| / CPU's.
    pub stab1_force_rel: Spread,
    /// Cases whose stab1 whirls in the CPU's class.
    pub same_whirl: usize,
    /// The CPU's own sensitivity of the hook load to a 1e-8 change of its start, over the
    /// same cases ([`crate::corpus::dynamic::run_case_perturbed`]).
    pub cpu_spread_hook_rel: Spread,
    /// Cases the engine solved whose hook load lies within the CPU's own spread: its
    /// difference from the CPU at most [`SPREAD_FACTOR`] times the two CPU runs'
    /// difference (one perturbed run samples a chaotic run's divergence to within its
    /// order, not exactly: case 261's engine runs are 2.5× and 5.8× its spread). There the
    /// engine's difference says nothing about the engine; elsewhere it does.
    pub hook_within_cpu_spread: usize,
    /// Wall time per case (s).
    pub seconds: Spread,
}

/// How many times the CPU's own spread an engine difference may be and still count as
/// within it ([`EnginePathSummary::hook_within_cpu_spread`]): an order of magnitude.
pub const SPREAD_FACTOR: f64 = 10.0;

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicCorpusSummary {
    /// Cases drawn.
    pub cases: usize,
    /// Cases run (a `--max-seconds` budget leaves the rest).
    pub run: usize,
    /// Ran to their duration with a finite state.
    pub solved: usize,
    /// Of those, with no time step cut.
    pub uncut: usize,
    /// The failures: (seed, why).
    pub failed: Vec<(u64, String)>,
    /// Cases with cuts: (seed, cuts).
    pub cut: Vec<(u64, usize)>,
    /// Newton iterations per step.
    pub iterations_per_step: Spread,
    /// Wall time per simulated second (s/s).
    pub seconds_per_simulated_s: Spread,
    /// The lateral kinetic energy's growth (second half's largest over the first's, − 1).
    pub lateral_energy_growth: Spread,
    /// stab1's largest excursion past its clearance (mm).
    pub stab1_penetration_mm: Spread,
    /// The engine sample, per path.
    pub engine: Vec<EnginePathSummary>,
    /// Engine paths that could not run here, and why.
    pub engine_unavailable: Vec<String>,
    /// Total wall time (s).
    pub wall_seconds: f64,
}

/// Runs the benchmark into `out` (created; `cases/` holds every case and its survey).
pub fn run(out: &Path, options: &DynamicCorpusOptions) -> Result<DynamicCorpusSummary, Error> {
    let clock = std::time::Instant::now();
    let dir = out.join("cases");
    std::fs::create_dir_all(&dir)?;
    let bar = crate::output::progress_bar(
        options.show_progress,
        options.cases as u64,
        "{bar:40} {pos}/{len} dynamic cases, {elapsed} elapsed, eta {eta}",
    );
    let seeds: Vec<u64> = (options.first_seed..options.first_seed + options.cases as u64).collect();
    let outcomes: Result<Vec<Option<(crate::corpus::dynamic::DynamicCase, DynamicRow)>>, Error> =
        seeds
            .par_iter()
            .map(|&seed| {
                if options
                    .max_seconds
                    .is_some_and(|b| clock.elapsed().as_secs_f64() > b)
                {
                    bar.inc(1);
                    return Ok(None);
                }
                let case = write_dynamic_case(seed, &dir)?;
                let row = run_case_dynamic(&case)?;
                bar.inc(1);
                Ok(Some((case, row)))
            })
            .collect();
    bar.finish_and_clear();
    let outcomes: Vec<(crate::corpus::dynamic::DynamicCase, DynamicRow)> =
        outcomes?.into_iter().flatten().collect();
    let rows: Vec<&DynamicRow> = outcomes.iter().map(|o| &o.1).collect();
    crate::output::write_csv_rows(
        &out.join("dynamic_corpus.csv"),
        rows.iter().map(|r| r.pair()),
    )?;

    // The engine sample: one case at a time (each a batch of one variant).
    let mut engine_rows: Vec<DynamicEngineRow> = Vec::new();
    let mut unavailable = Vec::new();
    let sample: Vec<&(crate::corpus::dynamic::DynamicCase, DynamicRow)> = outcomes
        .iter()
        .filter(|(c, r)| r.solved && r.nodes <= options.engine_max_nodes && c.spec.mass == "lumped")
        .take(options.engine_sample)
        .collect();
    // The CPU's own sensitivity to its start, for each sampled case (in parallel).
    let perturbed: Vec<DynamicRow> = sample
        .par_iter()
        .map(|(case, _)| run_case_perturbed(case))
        .collect::<Result<_, _>>()?;
    for f32 in [false, true] {
        for ((case, cpu), again) in sample.iter().zip(&perturbed) {
            match run_case_engine(case, cpu, again, f32) {
                Ok(r) => engine_rows.push(r),
                Err(e) => {
                    unavailable.push(format!("{}: {e}", if f32 { "gpu_f32" } else { "gpu_f64" }));
                    break;
                }
            }
        }
    }
    if !engine_rows.is_empty() {
        crate::output::write_csv_rows(&out.join("engine.csv"), &engine_rows)?;
    }
    let engine = ["gpu_f64", "gpu_f32"]
        .iter()
        .filter_map(|&path| {
            let e: Vec<&DynamicEngineRow> = engine_rows.iter().filter(|r| r.path == path).collect();
            // A measure's spread over the cases the engine solved itself.
            let solved = |f: fn(&DynamicEngineRow) -> f64| {
                spread(
                    &e.iter()
                        .filter(|r| r.by_engine)
                        .map(|r| (r.seed, f(r)))
                        .collect::<Vec<_>>(),
                )
            };
            (!e.is_empty()).then(|| EnginePathSummary {
                path: path.into(),
                cases: e.len(),
                by_engine: e.iter().filter(|r| r.by_engine).count(),
                fallbacks: e
                    .iter()
                    .filter(|r| !r.by_engine)
                    .map(|r| (r.seed, r.reason.chars().take(300).collect()))
                    .collect(),
                hook_load_rel: solved(|r| r.hook_load_rel),
                hook_load_of_force_scale: solved(|r| r.hook_load_of_force_scale),
                torque_rel: solved(|r| r.torque_rel),
                stab1_force_rel: solved(|r| r.stab1_force_rel),
                same_whirl: e.iter().filter(|r| r.by_engine && r.same_whirl).count(),
                cpu_spread_hook_rel: solved(|r| r.cpu_spread_hook_rel),
                hook_within_cpu_spread: e
                    .iter()
                    .filter(|r| {
                        r.by_engine && r.hook_load_rel <= SPREAD_FACTOR * r.cpu_spread_hook_rel
                    })
                    .count(),
                seconds: spread(&e.iter().map(|r| (r.seed, r.seconds)).collect::<Vec<_>>()),
            })
        })
        .collect();
    let solved: Vec<&&DynamicRow> = rows.iter().filter(|r| r.solved).collect();
    let summary = DynamicCorpusSummary {
        cases: options.cases,
        run: rows.len(),
        solved: solved.len(),
        uncut: rows.iter().filter(|r| r.uncut).count(),
        failed: rows
            .iter()
            .filter(|r| !r.solved)
            .map(|r| (r.spec.seed, r.reason.chars().take(300).collect()))
            .collect(),
        cut: rows
            .iter()
            .filter(|r| r.step_cuts > 0)
            .map(|r| (r.spec.seed, r.step_cuts))
            .collect(),
        iterations_per_step: spread(
            &solved
                .iter()
                .map(|r| (r.spec.seed, r.iterations_per_step))
                .collect::<Vec<_>>(),
        ),
        seconds_per_simulated_s: spread(
            &rows
                .iter()
                .map(|r| (r.spec.seed, r.seconds_per_simulated_s))
                .collect::<Vec<_>>(),
        ),
        lateral_energy_growth: spread(
            &solved
                .iter()
                .map(|r| (r.spec.seed, r.lateral_energy_growth))
                .collect::<Vec<_>>(),
        ),
        stab1_penetration_mm: spread(
            &solved
                .iter()
                .map(|r| (r.spec.seed, r.stab1_penetration_mm))
                .collect::<Vec<_>>(),
        ),
        engine,
        engine_unavailable: unavailable,
        wall_seconds: clock.elapsed().as_secs_f64(),
    };
    let classes = ["solved", "solved with step cuts", "failed"];
    let class = |r: &DynamicRow| match (r.solved, r.uncut) {
        (true, true) => 0,
        (true, false) => 1,
        (false, _) => 2,
    };
    crate::plots::class_scatter(
        &out.join("dynamic_corpus_time.png"),
        &format!(
            "Dynamic runs, {} of {} solved ({} without a step cut): wall time per simulated second",
            summary.solved, summary.run, summary.uncut
        ),
        "nodes of the mesh",
        "wall time per simulated second (s/s)",
        &rows
            .iter()
            .map(|r| (r.nodes as f64, r.seconds_per_simulated_s, class(r)))
            .collect::<Vec<_>>(),
        &classes,
    )?;
    crate::plots::class_scatter(
        &out.join("dynamic_corpus_map.png"),
        "Where the dynamic run cuts or fails: time step against wall stiffness",
        "linear-equivalent wall stiffness, log10 (N/m)",
        "time step (ms)",
        &rows
            .iter()
            .map(|r| {
                let k1 = r.spec.wall_stiffness * 1e-3f64.powf(r.spec.exponent - 1.0);
                (k1.log10(), 1e3 * r.spec.time_step_s, class(r))
            })
            .collect::<Vec<_>>(),
        &classes,
    )?;
    crate::plots::histogram(
        &out.join("dynamic_corpus_iterations.png"),
        "Newton iterations per time step, solved dynamic runs",
        "mean Newton iterations per step (–)",
        &solved
            .iter()
            .map(|r| r.iterations_per_step)
            .collect::<Vec<_>>(),
        &[("median", summary.iterations_per_step.median)],
    )?;
    let json = serde_json::to_vec_pretty(&summary)?;
    crate::output::write_atomic(&out.join("summary.json"), &json)?;
    Ok(summary)
}
