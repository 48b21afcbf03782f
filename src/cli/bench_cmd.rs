//! The `holewall bench` subcommands' arguments (clap), kept beside the benchmarks they
//! run; `main.rs` dispatches them. (Moved from `main.rs`, issue 24: no file over 800 lines.)

use std::path::PathBuf;

use clap::Subcommand;

use crate::backend::BackendChoice;

/// What `holewall bench` measures.
#[derive(Subcommand)]
pub enum BenchCommand {
    /// Scene-specialised contact kernels against the all-terms kernel on the same scenes
    /// (frictionless / split friction, static / dynamic): CPU twin f64, GPU f32 and f64
    /// resident; the gain (all-terms time / specialised time) and the outputs' difference.
    Specialisation {
        /// (variant, site) pairs per evaluation.
        #[arg(long, default_value_t = 200_000)]
        pairs: usize,
        /// Timed repeats per kernel (the median is reported).
        #[arg(long, default_value_t = 7)]
        repeats: usize,
        /// Also write the results as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Contact evaluations per second: CPU f64 (all cores), GPU f32 and f64.
    Contact {
        /// (variant, site) pairs per evaluation.
        #[arg(long, default_value_t = 1_000_000)]
        pairs: usize,
        /// Timed repeats per path (the median is reported).
        #[arg(long, default_value_t = 7)]
        repeats: usize,
        /// Where to compute the GPU paths (`cpu` benchmarks the CPU only).
        #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
        backend: BackendChoice,
        /// Also write the results as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// A user's ensemble job timed whole (`holewall ensemble CASE --samples N --seed S`, or
    /// `--variants FILE`: static starts, dynamics, observations, statistics, plots, report) on the
    /// CPU backend and on the GPU engine in f64 and f32, each `--repeats` times in one
    /// process (run 1 of a GPU path compiles its kernels); job.md and job.json.
    Job {
        /// The case (a dynamic ensemble with `[ensemble.uncertain]`).
        #[arg(default_value = "cases/whirl_job.toml")]
        case: PathBuf,
        /// Variants drawn.
        #[arg(long, default_value_t = 1024)]
        samples: usize,
        /// The job's variants from this file instead (`holewall ensemble CASE --variants
        /// FILE`: its whirl maps and plots over the inputs rather than the statistics).
        #[arg(long, conflicts_with_all = ["samples", "seed"])]
        variants: Option<PathBuf>,
        /// Seed of the draw.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Jobs per path.
        #[arg(long, default_value_t = 2)]
        repeats: usize,
        /// Output folder (job.md, job.json; runs/ holds each path's last job).
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Variant-steps per second of dynamic ensembles (V variants × n nodes): CPU f64
    /// integrator, GPU engine f64 and f32; bytes and FLOPs per Newton iteration; a
    /// work-precision table.
    Ensemble {
        /// Nodes of the benchmark string (comma-separated).
        #[arg(long, value_delimiter = ',', default_value = "100,400,1000")]
        nodes: Vec<usize>,
        /// Variants per ensemble (comma-separated).
        #[arg(long, value_delimiter = ',', default_value = "1,16,256,4096")]
        variants: Vec<usize>,
        /// Time steps per run (2 ms each, from the static equilibrium).
        #[arg(long, default_value_t = 5)]
        steps: usize,
        /// Timed repeats per cell (the median is reported).
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Skip a cell whose time, estimated from smaller cells, exceeds this (s).
        #[arg(long, default_value_t = 120.0)]
        budget: f64,
        /// CPU only (no GPU rows).
        #[arg(long)]
        cpu_only: bool,
        /// Nodes of the work-precision runs (0: none).
        #[arg(long, default_value_t = 100)]
        precision_nodes: usize,
        /// The block solve's form on the GPU: the batch's choice (default:
        /// `gpu::block_lu::LuForm::for_batch`), or one forced (serial: one invocation per
        /// variant; lanes: eight; cyclic: cyclic reduction, an invocation per node), to
        /// compare them on a device.
        #[arg(long, value_enum)]
        lu_form: Option<LuFormArg>,
        /// Line-search trials the GPU engine forms in one submission at most: 1 by default
        /// (`crate::gpu::batch::trials_per_round`), or this (1–8), to compare them on a
        /// device.
        #[arg(long, value_parser = clap::value_parser!(u16).range(1..=8))]
        trial_round: Option<u16>,
        /// Also write the results as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Wall time of a static ensemble on every path in one run: CPU backend, engine on the
    /// CPU twins, engine on the GPU (f64, f32); iterations per load step and cuts of each.
    Statics {
        /// Case file.
        case: PathBuf,
        /// CSV of variants (default: the case's `[ensemble.grid]`, else the case alone).
        #[arg(long)]
        variants: Option<PathBuf>,
        /// Timed repeats per path (the median is reported).
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// The block solve's form on the GPU: the batch's choice (default:
        /// `gpu::block_lu::LuForm::for_batch`), or one forced (serial: one invocation per
        /// variant; lanes: eight; cyclic: cyclic reduction, an invocation per node), to
        /// compare them on a device.
        #[arg(long, value_enum)]
        lu_form: Option<LuFormArg>,
        /// Line-search trials the GPU engine forms in one submission at most (as `bench
        /// ensemble --trial-round`).
        #[arg(long, value_parser = clap::value_parser!(u16).range(1..=8))]
        trial_round: Option<u16>,
        /// Also write the results as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// The whole performance table of this machine in one command: contact, element,
    /// roofline per kernel, static and dynamic ensembles, each against the CPU path
    /// (device.md, device.json) — run it on a GPU and send the folder back.
    Device {
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Folder of the shipped cases (the static ensembles).
        #[arg(long, default_value = "cases")]
        cases: PathBuf,
        /// Smaller sizes and fewer repeats (a first look).
        #[arg(long)]
        quick: bool,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// A roofline per kernel (contact, beam, assembly, block solve): achieved GFLOP/s and
    /// GB/s beside this device's FMA and copy ceilings, measured here, f32 and f64
    /// (kernels.md, kernels.json, roofline.png).
    Kernels {
        /// Variants per run (comma-separated).
        #[arg(long, value_delimiter = ',', default_values_t = [16usize, 256, 4096])]
        variants: Vec<usize>,
        /// Nodes of the string each variant holds (3–2000).
        #[arg(long, default_value_t = 21)]
        nodes: usize,
        /// Timed repeats (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Operations and time per beam element: the hyper-dual forms against the closed form
    /// (force only; force and tangent in f64 and f32), one core; their agreement.
    Element {
        /// Random element states timed per repeat.
        #[arg(long, default_value_t = 2000)]
        states: usize,
        /// Timed repeats (the median is reported).
        #[arg(long, default_value_t = 7)]
        repeats: usize,
        /// Also write the results as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// The FE static solve on a corpus of ordinary wells drawn from seeds (issue 22):
    /// solved / total, load steps, cuts, iterations and time per well, FE/soft-string
    /// hook-load and torque ratios (corpus.csv, summary.json, plots); the first
    /// `--engine-sample` wells also through the ensemble engine (twin f64, GPU f64, f32).
    Corpus {
        /// Wells (seeds first-seed, first-seed + 1, …).
        #[arg(long, default_value_t = 500)]
        wells: usize,
        /// First seed.
        #[arg(long, default_value_t = 0)]
        first_seed: u64,
        /// These seeds instead of --wells from --first-seed (comma-separated: the relaxed
        /// or failed wells of an earlier run, say).
        #[arg(long, value_delimiter = ',', conflicts_with_all = ["wells", "first_seed"])]
        seeds: Vec<u64>,
        /// Wells also run through the engine (the first ones of at most --engine-max-nodes).
        #[arg(long, default_value_t = 0)]
        engine_sample: usize,
        /// Largest mesh (nodes) of the engine sample.
        #[arg(long, default_value_t = 1000)]
        engine_max_nodes: usize,
        /// Start no new well after this many seconds (the rest are reported as not run).
        #[arg(long, value_parser = positive_seconds)]
        max_seconds: Option<f64>,
        /// Output folder (created; wells/ holds each well's case and survey).
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// How the wells are drawn: `drawn` spans geometry, string, loads and mesh; `user`
        /// as users write wells (tool joints, reaming, three hole sections, tapered pipe,
        /// WOB past buckling; src/corpus/user.rs).
        #[arg(long, value_enum, default_value_t = crate::corpus::CorpusStyle::Drawn)]
        style: crate::corpus::CorpusStyle,
    },
    /// The dynamic run (`holewall run`, CPU f64) on a corpus of BHA runs drawn from seeds:
    /// solved / total, step cuts, Newton iterations per step, wall time per simulated
    /// second (dynamic_corpus.csv, summary.json, plots); the first `--engine-sample` cases
    /// also through the GPU engine in f64 and f32, against the CPU run (engine.csv).
    DynamicCorpus {
        /// Cases (seeds first-seed, first-seed + 1, …).
        #[arg(long, default_value_t = 100)]
        cases: usize,
        /// First seed.
        #[arg(long, default_value_t = 0)]
        first_seed: u64,
        /// Cases also run through the GPU engine (the first solved ones of at most
        /// --engine-max-nodes nodes with lumped mass).
        #[arg(long, default_value_t = 0)]
        engine_sample: usize,
        /// Largest mesh (nodes) of the engine sample.
        #[arg(long, default_value_t = 400)]
        engine_max_nodes: usize,
        /// Start no new case after this many seconds (the rest are reported as not run).
        #[arg(long, value_parser = positive_seconds)]
        max_seconds: Option<f64>,
        /// Output folder (created; cases/ holds each case and its survey).
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Friction calibration on corpus wells: synthetic loads at friction factors drawn
    /// from each seed, recovered within the 95 % intervals?; the same loads on a 30 %
    /// heavier drill pipe rejected? (calibrate_corpus.csv, summary.json).
    CalibrateCorpus {
        /// Wells (seeds first-seed, first-seed + 1, …).
        #[arg(long, default_value_t = 20)]
        wells: usize,
        /// First seed.
        #[arg(long, default_value_t = 0)]
        first_seed: u64,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Critical speeds on corpus wells: time per well against the eigenproblem's size,
    /// lateral modes found, frequencies against the dense eigensolve where it is small
    /// enough (critical_corpus.csv, summary.json, critical_corpus_time.png).
    CriticalCorpus {
        /// Wells (seeds first-seed, first-seed + 1, …).
        #[arg(long, default_value_t = 100)]
        wells: usize,
        /// First seed.
        #[arg(long, default_value_t = 0)]
        first_seed: u64,
        /// These seeds instead of --wells from --first-seed (comma-separated).
        #[arg(long, value_delimiter = ',')]
        seeds: Vec<u64>,
        /// How the wells are drawn.
        #[arg(long, value_enum, default_value_t)]
        style: crate::corpus::CorpusStyle,
        /// The dense oracle runs where the BHA part has at most this many DOFs.
        #[arg(long, default_value_t = 2000)]
        dense_max_dofs: usize,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// The BHA tendency (build/turn rates, equilibrium curvature) of corpus wells at their
    /// own WOB: settled / total with the unsettled and why (tendency_corpus.csv).
    TendencyCorpus {
        /// Wells (seeds first-seed, first-seed + 1, …).
        #[arg(long, default_value_t = 500)]
        wells: usize,
        /// First seed.
        #[arg(long, default_value_t = 0)]
        first_seed: u64,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Monte Carlo static ensembles on corpus wells: friction, wall stiffness and WOB
    /// uncertain, the variants on the CPU backend (f64) and the GPU engine (f64, f32) — solved
    /// / total per path, each variant's hook load, torque and side force against the CPU's,
    /// P10/P50/P90, wall time (mc_corpus.csv, mc_variants.csv, summary.json, plot).
    McCorpus(McCorpusArgs),
    /// Mesh convergence on corpus wells: hook load, torque, the largest side force and the
    /// stabilizer forces as the pipe elements shrink from 30 m to 0.5 m (mesh.csv, mesh.md).
    Mesh {
        /// Corpus seeds (default: the first build-and-hold, S-shaped and horizontal well
        /// drilling or rotating with a stabilizer).
        #[arg(long, value_delimiter = ',')]
        seeds: Option<Vec<u64>>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Time steps per second and Newton iterations per step of `holewall run` (CPU f64).
    Dynamics {
        /// Case file with a `[dynamics]` table.
        case: PathBuf,
        /// Steps per repeat (at the case's time step, from the static equilibrium).
        #[arg(long, default_value_t = 200)]
        steps: usize,
        /// Timed repeats (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Also write the results as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

/// `--max-seconds`: a finite number of seconds > 0.
pub fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("{s:?}: allowed: a number of seconds > 0")),
    }
}

/// `--lu-form`: a forced form of the GPU block solve ([`crate::gpu::block_lu::LuForm`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LuFormArg {
    /// One invocation per variant (the blocks in registers).
    Serial,
    /// Eight invocations per variant, a row per lane.
    Lanes,
    /// Block cyclic reduction: an invocation per node and variant, log₂ n levels.
    Cyclic,
}

/// Forces the GPU engine's block-solve form and trials per submission for the rest of the
/// process (`None`: the adapter's choice).
pub fn apply_forms(form: Option<LuFormArg>, trial_round: Option<u16>) {
    LuFormArg::apply(form);
    crate::gpu::batch::force_trials_per_round(trial_round.map(usize::from));
}

impl LuFormArg {
    /// Forces `form` for the rest of the process (`None`: the adapter's choice).
    pub fn apply(form: Option<LuFormArg>) {
        use crate::gpu::block_lu::{force_lu_form, LuForm};
        force_lu_form(form.map(|f| match f {
            LuFormArg::Serial => LuForm::Serial,
            LuFormArg::Lanes => LuForm::Lanes,
            LuFormArg::Cyclic => LuForm::Cyclic,
        }));
    }
}

/// `holewall bench mc-corpus`'s arguments.
#[derive(clap::Args)]
pub struct McCorpusArgs {
    /// Wells (seeds first-seed, first-seed + 1, …).
    #[arg(long, default_value_t = 12)]
    wells: usize,
    /// First seed.
    #[arg(long, default_value_t = 0)]
    first_seed: u64,
    /// These seeds instead of --wells from --first-seed (comma-separated).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["wells", "first_seed"])]
    seeds: Vec<u64>,
    /// How the wells are drawn.
    #[arg(long, value_enum, default_value_t)]
    style: crate::corpus::CorpusStyle,
    /// Monte Carlo samples (variants) per well (Latin hypercube).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u64).range(1..=4096))]
    samples: u64,
    /// Wells with more nodes are not run (lavapipe runs the kernels on the CPU).
    #[arg(long, default_value_t = 700)]
    max_nodes: usize,
    /// Start no new well after this many seconds (the rest are reported as not run).
    #[arg(long, value_parser = positive_seconds)]
    max_seconds: Option<f64>,
    /// Output folder (created; wells/ holds each well's case and survey).
    #[arg(long)]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

impl McCorpusArgs {
    /// Runs the benchmark: the line it prints.
    pub fn run(&self) -> Result<String, crate::Error> {
        let options = super::bench_mc_corpus::McCorpusOptions {
            seeds: super::bench_corpus::corpus_seeds(
                self.wells,
                self.first_seed,
                self.seeds.clone(),
            ),
            style: self.style,
            samples: self.samples as usize,
            max_nodes: self.max_nodes,
            max_seconds: self.max_seconds,
            show_progress: !self.quiet,
        };
        super::bench_mc_corpus::run(&self.out, &options).map(|s| s.line(&self.out))
    }
}
