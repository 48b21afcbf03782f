//! `holewall bench job`: a user's ensemble job timed whole (issue 27) — the static starts,
//! the dynamic runs, the observations, the statistics, the plots and the report, as
//! `holewall ensemble CASE --samples N --seed S` (or `--variants FILE`) runs them — on the
//! CPU backend and on the GPU engine in f64 and f32, each run `repeats` times in one
//! process (the first GPU run compiles the kernels; the later ones are what a user's next
//! job costs). Stop 49
//! found on an H100 that the engine's own steps ran 8–9× the CPU's while the user's job ran
//! 1.3×: what lies around the engine only a benchmark of the whole job shows.

use std::path::Path;
use std::time::Instant;

use crate::backend::{BackendChoice, Precision};
use crate::error::Error;

/// One timed job.
#[derive(Clone, Debug, serde::Serialize)]
pub struct JobRun {
    /// `CPU f64`, `GPU f64` or `GPU f32`.
    pub path: String,
    /// 1-based; run 1 of a GPU path includes compiling its kernels.
    pub repeat: usize,
    /// The whole job, from reading the case to the report (s).
    pub wall_s: f64,
    /// Of it, the variants' runs (`summary.json` `seconds`).
    pub variant_runs_s: f64,
    /// The engine's phases (`summary.json` `engine_seconds`), where the engine ran.
    pub engine_seconds: Option<crate::ensemble::report::EngineSeconds>,
    /// Variants the engine solved.
    pub solved_by_engine: usize,
    /// Variants the CPU solved (all on the CPU path; the engine's failures re-run there).
    pub solved_by_cpu: usize,
    /// Variants that failed.
    pub failed: usize,
}

/// The benchmark's result (`job.json`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct JobBench {
    /// The case file.
    pub case: String,
    /// The variants file, where the job ran one (else `samples` were drawn).
    pub variants_file: Option<String>,
    /// Variants drawn (without a variants file).
    pub samples: usize,
    /// Seed of the draw.
    pub seed: u64,
    /// The GPU adapter, or why there is none.
    pub device: String,
    /// Threads of the CPU path.
    pub cpu_threads: usize,
    /// Every job, in order.
    pub runs: Vec<JobRun>,
    /// Per path, its warm job time and speed against the CPU path.
    pub medians: Vec<JobMedian>,
}

/// A path's warm job time ([`JobBench::medians`]).
#[derive(Clone, Debug, serde::Serialize)]
pub struct JobMedian {
    /// `CPU f64`, `GPU f64` or `GPU f32`.
    pub path: String,
    /// The median wall time of its runs after the first (the first where it ran once), s.
    pub job_s: f64,
    /// The CPU path's over it (above 1: faster than the CPU).
    pub speed_vs_cpu: f64,
}

/// The median (NaN of none), by the statistics' one percentile.
fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    crate::uq::stats::percentile(&x, 50.0)
}

/// Runs the job `repeats` times per path into `out/runs/` (each run's folder replaced by
/// the next; the last stays for a look) and writes `job.json` and `job.md` into `out`.
pub fn run(
    case: &Path,
    variants_file: Option<&Path>,
    samples: usize,
    seed: u64,
    repeats: usize,
    out: &Path,
    show_progress: bool,
) -> Result<JobBench, Error> {
    for (key, n) in [("--samples", samples), ("--repeats", repeats)] {
        if n == 0 {
            return Err(crate::error::InputError {
                source_name: key.into(),
                line: 0,
                key: key.trim_start_matches('-').into(),
                message: "at least 1".into(),
            }
            .into());
        }
    }
    std::fs::create_dir_all(out)?;
    let gpu = crate::gpu::GpuContext::shared();
    let device = match &gpu {
        Ok(c) => c.describe(),
        Err(e) => format!("no GPU adapter ({e}): the CPU path only"),
    };
    let mut paths = vec![("CPU f64", BackendChoice::Cpu, Precision::F64)];
    if let Ok(c) = &gpu {
        if c.has_f64 {
            paths.push(("GPU f64", BackendChoice::Gpu, Precision::F64));
        }
        paths.push(("GPU f32", BackendChoice::Gpu, Precision::F32));
    }
    let options = crate::ensemble::store::EnsembleOptions {
        monte_carlo: variants_file
            .is_none()
            .then(|| crate::uq::report::MonteCarlo {
                samples,
                seed,
                sampling: crate::uq::Sampling::Random,
                percentiles: Vec::new(),
                thresholds: Vec::new(),
                sobol_indices: false,
            }),
        ..Default::default()
    };
    let bar = crate::output::progress_bar(
        show_progress,
        (paths.len() * repeats) as u64,
        "{bar:30} {pos}/{len} jobs, {elapsed} elapsed: {msg}",
    );
    let mut runs = Vec::new();
    for (name, backend, precision) in &paths {
        let dir = out.join("runs").join(name.to_lowercase().replace(' ', "_"));
        for repeat in 1..=repeats {
            bar.set_message(format!("{name}, run {repeat}"));
            if dir.exists() {
                std::fs::remove_dir_all(&dir)?;
            }
            let clock = Instant::now();
            let s = crate::ensemble::job::run(
                case,
                variants_file,
                *backend,
                *precision,
                &dir,
                false,
                &options,
            )?;
            runs.push(JobRun {
                path: name.to_string(),
                repeat,
                wall_s: clock.elapsed().as_secs_f64(),
                variant_runs_s: s.seconds,
                engine_seconds: s.engine_seconds,
                solved_by_engine: s.solved_by_engine,
                solved_by_cpu: s.solved_by_cpu,
                failed: s.failed,
            });
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let warm = |name: &str| {
        let all: Vec<&JobRun> = runs.iter().filter(|r| r.path == name).collect();
        let later: Vec<f64> = all
            .iter()
            .filter(|r| r.repeat > 1)
            .map(|r| r.wall_s)
            .collect();
        if later.is_empty() {
            median(all.iter().map(|r| r.wall_s).collect())
        } else {
            median(later)
        }
    };
    let cpu = warm("CPU f64");
    let medians: Vec<JobMedian> = paths
        .iter()
        .map(|(n, _, _)| JobMedian {
            path: n.to_string(),
            job_s: warm(n),
            speed_vs_cpu: cpu / warm(n),
        })
        .collect();
    let bench = JobBench {
        case: case.display().to_string(),
        variants_file: variants_file.map(|p| p.display().to_string()),
        samples,
        seed,
        device,
        cpu_threads: rayon::current_num_threads(),
        runs,
        medians,
    };
    crate::output::write_json_atomic(&out.join("job.json"), &bench)?;
    crate::output::write_atomic(&out.join("job.md"), markdown(&bench).as_bytes())?;
    Ok(bench)
}

/// The tables of `job.md`.
pub fn markdown(b: &JobBench) -> String {
    let inputs = match &b.variants_file {
        Some(f) => format!("--variants {f}"),
        None => format!("--samples {} --seed {}", b.samples, b.seed),
    };
    let mut md = format!(
        "# A user's job: `holewall ensemble {} {inputs}`\n\n{}; CPU threads: {}. \
         Each job timed whole; run 1 of a GPU path compiles its kernels.\n\n\
         | path | run | job (s) | variants' runs (s) | outside them (s) | engine: static starts (s) | engine: dynamics (s) | of it, observing (s) | engine / CPU / failed |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        b.case, b.device, b.cpu_threads
    );
    let f = |x: Option<f64>| x.map_or("–".to_string(), |x| format!("{x:.3}"));
    for r in &b.runs {
        let e = r.engine_seconds.as_ref();
        md.push_str(&format!(
            "| {} | {} | {:.3} | {:.3} | {:.3} | {} | {} | {} | {} / {} / {} |\n",
            r.path,
            r.repeat,
            r.wall_s,
            r.variant_runs_s,
            r.wall_s - r.variant_runs_s,
            f(e.map(|e| e.static_starts)),
            f(e.map(|e| e.dynamics)),
            f(e.map(|e| e.observing)),
            r.solved_by_engine,
            r.solved_by_cpu,
            r.failed
        ));
    }
    md.push_str("\n| path | job, median of the runs after the first (s) | speed vs CPU f64 (its job time ÷ this one's) |\n|---|---|---|\n");
    for m in &b.medians {
        md.push_str(&format!(
            "| {} | {:.3} | {:.2} |\n",
            m.path, m.job_s, m.speed_vs_cpu
        ));
    }
    md
}
