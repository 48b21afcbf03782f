//! `holewall bench mc-corpus`: Monte Carlo static ensembles on corpus wells. Each well drawn
//! from a seed ([`crate::corpus::write_corpus_well`]) gets uncertain inputs — the friction at
//! every contact site uniform in [`MU_RANGE`], the wall stiffness lognormal about the well's
//! own with σ = [`K_E_SIGMA`], and, where it drills, the WOB uniform within ±[`WOB_SPREAD`]
//! of its own — sampled by Latin hypercube, and the variants run on each path a user's
//! `holewall ensemble` takes ([`crate::ensemble::runner::compute`]): the CPU backend (f64, the
//! oracle), the GPU engine in f64 and in f32. Reported: variants solved / total per path,
//! those the engine solved itself (not re-run on the CPU), every variant's hook load,
//! surface torque and largest side force per length against the CPU's, the P10 / P50 / P90
//! of the hook load per path, and each path's wall time (`mc_corpus.csv`,
//! `mc_variants.csv`, `summary.json`, `mc_corpus_agreement.png`).

use std::path::Path;

use serde::Serialize;

use crate::backend::Precision;
use crate::case::{load_case, Analysis};
use crate::corpus::{spread, Spread};
use crate::corpus::{write_corpus_well, CorpusStyle};
use crate::ensemble::qoi::{SolvedBy, Status, VariantResult};
use crate::error::Error;
use crate::keys::{Param, Value};

/// The friction factor's range at every contact site (uniform).
pub const MU_RANGE: (f64, f64) = (0.15, 0.40);
/// The wall stiffness's lognormal σ about the well's own (the median).
pub const K_E_SIGMA: f64 = 0.5;
/// The WOB's spread about the well's own (uniform, a fraction), where it drills.
pub const WOB_SPREAD: f64 = 0.3;
/// Floors of the relative differences (a quantity near zero is compared against these): hook
/// load 1 kN, surface torque 100 N·m, side force per length 1 N/m.
const FLOORS: [f64; 3] = [1e3, 100.0, 1.0];

/// Options of the benchmark.
#[derive(Clone, Debug)]
pub struct McCorpusOptions {
    /// Seeds of the wells, in order.
    pub seeds: Vec<u64>,
    /// How the wells are drawn.
    pub style: CorpusStyle,
    /// Variants per well.
    pub samples: usize,
    /// Wells with more nodes are not run (reported).
    pub max_nodes: usize,
    /// Start no new well after this many seconds (the rest are reported as not run).
    pub max_seconds: Option<f64>,
    /// Progress bar on stderr.
    pub show_progress: bool,
}

/// The three paths, in the order run.
const PATHS: [(&str, bool, Precision); 3] = [
    ("cpu_f64", false, Precision::F64),
    ("gpu_f64", true, Precision::F64),
    ("gpu_f32", true, Precision::F32),
];

/// One well on one path (a row of `mc_corpus.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct McRow {
    /// Seed.
    pub seed: u64,
    /// Trajectory kind.
    pub trajectory: String,
    /// Operation.
    pub mode: String,
    /// Nodes of the mesh.
    pub nodes: usize,
    /// `cpu_f64`, `gpu_f64` or `gpu_f32`.
    pub path: String,
    /// Variants run.
    pub variants: usize,
    /// Variants solved (converged, with or without step cuts).
    pub solved: usize,
    /// Of those, solved by the engine itself (not re-run on the CPU).
    pub by_engine: usize,
    /// Of those, reached by relaxation past a fold.
    pub relaxed: usize,
    /// Wall time of the path (s).
    pub seconds: f64,
    /// Largest relative difference from the CPU's hook load, over the variants both solved.
    pub hook_load_rel: f64,
    /// The same for the largest surface torque.
    pub torque_rel: f64,
    /// The same for the largest side force per length.
    pub side_force_rel: f64,
    /// The hook load's, over the variants both solved and either reached by relaxation.
    pub hook_load_rel_relaxed: f64,
    /// Variants solved on this path or the CPU's but not on both.
    pub solved_here_only: usize,
    /// P10, P50, P90 of the hook load over the solved variants (N).
    pub hook_load_p10_n: f64,
    /// P50.
    pub hook_load_p50_n: f64,
    /// P90.
    pub hook_load_p90_n: f64,
    /// Where the path did not run, or ran on the CPU instead: why.
    pub note: String,
}

/// One variant (a row of `mc_variants.csv`): its inputs and hook loads per path.
#[derive(Clone, Debug, Serialize)]
pub struct McVariantRow {
    /// Seed of the well.
    pub seed: u64,
    /// Variant name.
    pub variant: String,
    /// Friction factor.
    pub mu: f64,
    /// Wall stiffness (N/m).
    pub k_e: f64,
    /// WOB (N; NaN where not uncertain).
    pub wob_n: f64,
    /// Hook loads (N; NaN where not solved) on the CPU, GPU f64 and GPU f32.
    pub cpu_f64_hook_load_n: f64,
    /// GPU f64.
    pub gpu_f64_hook_load_n: f64,
    /// GPU f32.
    pub gpu_f32_hook_load_n: f64,
}

/// A path over all wells (`summary.json`).
#[derive(Clone, Debug, Serialize)]
pub struct McPathSummary {
    /// Variants run.
    pub variants: usize,
    /// Solved.
    pub solved: usize,
    /// Solved by the engine itself.
    pub by_engine: usize,
    /// Largest relative difference from the CPU's hook load, per well (worst and its seed),
    /// over the variants neither path reached by relaxation.
    pub hook_load_rel: Spread,
    /// The same over the variants either path reached by relaxation.
    pub hook_load_rel_relaxed: Spread,
    /// Variants solved on this path or the CPU's but not on both.
    pub solved_here_only: usize,
    /// Variants this path reached by relaxation.
    pub relaxed: usize,
    /// The same for the surface torque.
    pub torque_rel: Spread,
    /// The same for the largest side force per length.
    pub side_force_rel: Spread,
    /// Wall time, all wells (s).
    pub seconds: f64,
    /// Where it did not run or ran on the CPU: (seed, why).
    pub notes: Vec<(u64, String)>,
}

/// `summary.json` of the benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct McCorpusSummary {
    /// Wells drawn.
    pub wells: usize,
    /// Wells run (the rest have more than `max_nodes` nodes, or came after `max_seconds`).
    pub run: usize,
    /// Wells not run for their size (more nodes than `max_nodes`).
    pub too_large: Vec<u64>,
    /// Variants per well.
    pub samples: usize,
    /// Per path (`cpu_f64`, `gpu_f64`, `gpu_f32`).
    pub paths: std::collections::BTreeMap<String, McPathSummary>,
    /// Total wall time (s).
    pub wall_seconds: f64,
}

impl McCorpusSummary {
    /// The line the command prints.
    pub fn line(&self, out: &Path) -> String {
        let path = |name: &str| match self.paths.get(name) {
            Some(p) => format!(
                "{name} {}/{} solved ({} by the engine, {} relaxed, {} solved here or on the CPU \
                 only), hook load worst {:.1e} (seed {:?}; relaxed variants {:.1e}), {:.1} s",
                p.solved,
                p.variants,
                p.by_engine,
                p.relaxed,
                p.solved_here_only,
                p.hook_load_rel.worst,
                p.hook_load_rel.worst_seed,
                p.hook_load_rel_relaxed.worst,
                p.seconds
            ),
            None => format!("{name} not run"),
        };
        format!(
            "{} of {} wells run × {} variants: {}; {}; {}; {}",
            self.run,
            self.wells,
            self.samples,
            path("cpu_f64"),
            path("gpu_f64"),
            path("gpu_f32"),
            out.join("summary.json").display()
        )
    }
}

/// The `[ensemble]` tables appended to a corpus well's case: its uncertain inputs.
pub fn uncertain_tables(wall_stiffness: f64, wob_n: f64) -> String {
    let mut t = format!(
        "\n[ensemble]\nanalysis = \"static\"\n[ensemble.uncertain]\n\
         mu = {{ dist = \"uniform\", min = {}, max = {} }}\n\
         k_e = {{ dist = \"lognormal\", median = {wall_stiffness:e}, sigma = {K_E_SIGMA} }}\n",
        MU_RANGE.0, MU_RANGE.1
    );
    if wob_n > 0.0 {
        t.push_str(&format!(
            "wob = {{ dist = \"uniform\", min = \"{} N\", max = \"{} N\" }}\n",
            (wob_n * (1.0 - WOB_SPREAD)).round(),
            (wob_n * (1.0 + WOB_SPREAD)).round()
        ));
    }
    t
}

fn solved(r: &VariantResult) -> bool {
    r.status != Status::Failed
}

/// The three quantities compared, as numbers (NaN where absent).
fn quantities(r: &VariantResult) -> [f64; 3] {
    [
        r.hook_load_n.unwrap_or(f64::NAN),
        r.max_surface_torque_nm,
        r.string
            .max_side_force_per_length_n_per_m
            .unwrap_or(f64::NAN),
    ]
}

fn relaxed(r: &VariantResult) -> bool {
    r.string.relaxed == Some(true)
}

/// Largest relative differences of `rs` from `cpu` over the variants both solved: those
/// neither reached by relaxation (`of_relaxed` false), or those either did — an answer
/// past a fold is one of several equilibria, which the path chose
/// ([`crate::diagnose::relaxed_warning`]), so the paths may part there by more than rounding.
/// NaN where no variant is of the kind.
fn differences(rs: &[VariantResult], cpu: &[VariantResult], of_relaxed: bool) -> [f64; 3] {
    let mut worst = [f64::NAN; 3];
    for (r, c) in rs.iter().zip(cpu) {
        if !(solved(r) && solved(c)) || (relaxed(r) || relaxed(c)) != of_relaxed {
            continue;
        }
        worst = worst.map(|w| if w.is_nan() { 0.0 } else { w });
        let (a, b) = (quantities(r), quantities(c));
        for k in 0..3 {
            let d = (a[k] - b[k]).abs() / b[k].abs().max(FLOORS[k]);
            // NaN on one side only counts as a difference; on both, as none.
            worst[k] = match (a[k].is_nan(), b[k].is_nan()) {
                (false, false) => worst[k].max(d),
                (true, true) => worst[k],
                _ => f64::INFINITY,
            };
        }
    }
    worst
}

/// P10, P50, P90 of the solved variants' hook loads (nearest rank).
fn percentiles(rs: &[VariantResult]) -> [f64; 3] {
    let mut h: Vec<f64> = rs
        .iter()
        .filter(|r| solved(r))
        .filter_map(|r| r.hook_load_n)
        .collect();
    h.sort_by(f64::total_cmp);
    if h.is_empty() {
        return [f64::NAN; 3];
    }
    [0.1, 0.5, 0.9].map(|p| h[((p * h.len() as f64).ceil() as usize).clamp(1, h.len()) - 1])
}

fn number(v: Option<Value>) -> f64 {
    match v {
        Some(Value::Number(x)) => x,
        _ => f64::NAN,
    }
}

/// Runs the benchmark into `out` (created; `wells/` holds every well's case and survey).
pub fn run(out: &Path, options: &McCorpusOptions) -> Result<McCorpusSummary, Error> {
    let clock = std::time::Instant::now();
    let dir = out.join("wells");
    std::fs::create_dir_all(&dir)?;
    let bar = crate::output::progress_bar(
        options.show_progress,
        (options.seeds.len() * PATHS.len()) as u64,
        "{bar:40} {pos}/{len} wells × paths, {elapsed} elapsed",
    );
    // The GPU once: where there is none, its paths are reported as not run.
    let gpu = crate::gpu::context::GpuContext::shared().map_err(|e| e.to_string());
    let quiet = indicatif::ProgressBar::hidden();
    let (mut rows, mut variant_rows, mut run_wells) = (Vec::new(), Vec::new(), 0);
    let mut points: Vec<(f64, f64, usize)> = Vec::new();
    let mut too_large = Vec::new();
    for &seed in &options.seeds {
        if options
            .max_seconds
            .is_some_and(|s| clock.elapsed().as_secs_f64() > s)
        {
            break;
        }
        let well = write_corpus_well(options.style, seed, &dir)?;
        let text = std::fs::read_to_string(&well.case_path)?;
        let case_path = dir.join(format!("mc_{seed}.toml"));
        crate::output::write_atomic(
            &case_path,
            (text + &uncertain_tables(well.spec.wall_stiffness, well.spec.wob_n)).as_bytes(),
        )?;
        let case = load_case(&case_path)?;
        if case.model.nodes.len() > options.max_nodes {
            too_large.push(seed);
            bar.inc(PATHS.len() as u64);
            continue;
        }
        run_wells += 1;
        let uncertain = case.ensemble.as_ref().map(|e| e.uncertain.clone());
        let variants = crate::ensemble::sample_variants(
            &uncertain.unwrap_or_default(),
            options.samples,
            seed,
            crate::uq::Sampling::Lhs,
            false,
            None,
        )
        .map_err(|e| Error::failed(format!("well {seed}: {e}")))?;
        let mut results: Vec<Option<Vec<VariantResult>>> = Vec::new();
        for (i, &(name, on_gpu, precision)) in PATHS.iter().enumerate() {
            let t = std::time::Instant::now();
            let ran = match (&gpu, on_gpu) {
                (_, false) => Ok(crate::ensemble::runner::compute(
                    &case,
                    Analysis::Static,
                    &variants,
                    None,
                    precision,
                    &quiet,
                )?),
                (Ok(ctx), true) => crate::ensemble::runner::compute(
                    &case,
                    Analysis::Static,
                    &variants,
                    Some(*ctx),
                    precision,
                    &quiet,
                )
                .map_err(|e| e.to_string()),
                (Err(e), true) => Err(format!("no GPU: {e}")),
            };
            let seconds = t.elapsed().as_secs_f64();
            bar.inc(1);
            // A path that did not run (no GPU, or the engine refused the case) has a row
            // with its reason and no results.
            let (rs, note, ran) = match ran {
                Ok((rs, _, note)) => (rs, note.unwrap_or_default(), true),
                Err(why) => (Vec::new(), why, false),
            };
            let cpu = results.first().and_then(Option::as_ref).unwrap_or(&rs);
            let nan = [f64::NAN; 3];
            let diff = if ran {
                differences(&rs, cpu, false)
            } else {
                nan
            };
            let diff_relaxed = if ran {
                differences(&rs, cpu, true)
            } else {
                nan
            };
            let one_sided = rs
                .iter()
                .zip(cpu)
                .filter(|(r, c)| solved(r) != solved(c))
                .count();
            if i > 0 {
                for (r, c) in rs.iter().zip(cpu) {
                    if solved(r) && solved(c) {
                        let (a, b) = (quantities(r)[0], quantities(c)[0]);
                        let d = (a - b).abs() / b.abs().max(FLOORS[0]);
                        let mu = variants
                            .iter()
                            .find(|v| v.name == r.name)
                            .map_or(f64::NAN, |v| number(v.value_of(Param::Mu)));
                        let class = i - 1 + 2 * usize::from(relaxed(r) || relaxed(c));
                        points.push((mu, d.max(1e-16).log10(), class));
                    }
                }
            }
            let p = percentiles(&rs);
            rows.push(McRow {
                seed,
                trajectory: well.spec.trajectory.name().to_string(),
                mode: well.spec.mode.clone(),
                nodes: case.model.nodes.len(),
                path: name.into(),
                variants: variants.len(),
                solved: rs.iter().filter(|r| solved(r)).count(),
                by_engine: rs
                    .iter()
                    .filter(|r| solved(r) && r.solved_by == SolvedBy::Engine)
                    .count(),
                relaxed: rs.iter().filter(|r| relaxed(r)).count(),
                seconds: if ran { seconds } else { f64::NAN },
                hook_load_rel: diff[0],
                torque_rel: diff[1],
                side_force_rel: diff[2],
                hook_load_rel_relaxed: diff_relaxed[0],
                solved_here_only: one_sided,
                hook_load_p10_n: p[0],
                hook_load_p50_n: p[1],
                hook_load_p90_n: p[2],
                note,
            });
            results.push(ran.then_some(rs));
        }
        let hook = |k: usize, j: usize| -> f64 {
            results[k]
                .as_ref()
                .and_then(|rs| rs.get(j))
                .filter(|r| solved(r))
                .and_then(|r| r.hook_load_n)
                .unwrap_or(f64::NAN)
        };
        for (j, v) in variants.iter().enumerate() {
            variant_rows.push(McVariantRow {
                seed,
                variant: v.name.clone(),
                mu: number(v.value_of(Param::Mu)),
                k_e: number(v.value_of(Param::WallStiffness)),
                wob_n: number(v.value_of(Param::Wob)),
                cpu_f64_hook_load_n: hook(0, j),
                gpu_f64_hook_load_n: hook(1, j),
                gpu_f32_hook_load_n: hook(2, j),
            });
        }
    }
    bar.finish_and_clear();
    crate::output::write_csv_rows(&out.join("mc_corpus.csv"), &rows)?;
    crate::output::write_csv_rows(&out.join("mc_variants.csv"), &variant_rows)?;
    let mut paths = std::collections::BTreeMap::new();
    for (name, _, _) in PATHS {
        let of: Vec<&McRow> = rows.iter().filter(|r| r.path == name).collect();
        let ran: Vec<&McRow> = of
            .iter()
            .copied()
            .filter(|r| r.seconds.is_finite())
            .collect();
        if ran.is_empty() {
            continue;
        }
        let per =
            |f: fn(&McRow) -> f64| spread(&ran.iter().map(|r| (r.seed, f(r))).collect::<Vec<_>>());
        paths.insert(
            name.to_string(),
            McPathSummary {
                variants: ran.iter().map(|r| r.variants).sum(),
                solved: ran.iter().map(|r| r.solved).sum(),
                by_engine: ran.iter().map(|r| r.by_engine).sum(),
                hook_load_rel: per(|r| r.hook_load_rel),
                hook_load_rel_relaxed: per(|r| r.hook_load_rel_relaxed),
                solved_here_only: ran.iter().map(|r| r.solved_here_only).sum(),
                relaxed: ran.iter().map(|r| r.relaxed).sum(),
                torque_rel: per(|r| r.torque_rel),
                side_force_rel: per(|r| r.side_force_rel),
                seconds: ran.iter().map(|r| r.seconds).sum(),
                notes: of
                    .iter()
                    .filter(|r| !r.note.is_empty())
                    .map(|r| (r.seed, r.note.clone()))
                    .collect(),
            },
        );
    }
    let summary = McCorpusSummary {
        wells: options.seeds.len(),
        run: run_wells,
        too_large,
        samples: options.samples,
        paths,
        wall_seconds: clock.elapsed().as_secs_f64(),
    };
    if !points.is_empty() {
        crate::plots::class_scatter(
            &out.join("mc_corpus_agreement.png"),
            &format!(
                "Monte Carlo on {} corpus wells: each variant's hook load on the GPU against the CPU's",
                summary.run
            ),
            "friction factor μ",
            "log10 relative difference of the hook load",
            &points,
            &[
                "GPU f64",
                "GPU f32",
                "GPU f64, relaxed past a fold (either path)",
                "GPU f32, relaxed past a fold (either path)",
            ],
        )?;
    }
    let json = serde_json::to_vec_pretty(&summary)?;
    crate::output::write_atomic(&out.join("summary.json"), &json)?;
    Ok(summary)
}
