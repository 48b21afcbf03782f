//! `holewall`: argument parsing only; the work is in the library.

use std::io::Read;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use holewall::backend::{Backend, BackendChoice, Precision};
use holewall::bha::critical;
use holewall::cli;
use holewall::cli::bench_cmd::{positive_seconds, BenchCommand};

#[derive(Parser)]
#[command(
    name = "holewall",
    version,
    about = "Drillstring–holewall contact simulation for many variants at once"
)]
struct Args {
    #[command(subcommand)]
    command: Command,
    /// Units of the outputs (CSV columns, summary.json, plot axes): SI, or oilfield (ft,
    /// klbf, kft·lbf, lbf/ft, psi, ppg, °/100 ft). Inputs take either, as written.
    #[arg(long, value_enum, global = true, default_value_t = holewall::display_units::UnitSystem::Si)]
    units: holewall::display_units::UnitSystem,
}

#[derive(Subcommand)]
enum Command {
    /// Contact-element calculator: JSON Lines in (FILE or stdin), JSON Lines out.
    Contact {
        /// Where to compute.
        #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
        backend: BackendChoice,
        /// Float type of the computation.
        #[arg(long, value_enum, default_value_t = Precision::F64)]
        precision: Precision,
        /// Input file (JSON Lines); stdin when absent.
        file: Option<PathBuf>,
    },
    /// Lists GPU adapters and self-checks the contact kernel against its CPU twin.
    GpuInfo {
        /// (variant, site) pairs in the self-check.
        #[arg(long, default_value_t = 20_000)]
        pairs: usize,
    },
    /// Static analysis: torque & drag, neutral point, side forces (CSV, JSON).
    Static {
        /// Case file (TOML; see cases/README.md).
        case: PathBuf,
        /// Finite elements (stiff string) or soft-string torque & drag.
        #[arg(long, value_enum, default_value_t = cli::static_cmd::StaticModel::Fe)]
        model: cli::static_cmd::StaticModel,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Stop the FE solve after this many seconds of wall time (it then fails, saying
        /// how far it got and why it was slow).
        #[arg(long, value_parser = positive_seconds)]
        max_seconds: Option<f64>,
    },
    /// Dynamic analysis: spin-up from the static equilibrium, implicit time integration
    /// (time series CSV and plots).
    Run {
        /// Case file with a [dynamics] table.
        case: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Wall-time budget (s): the run stops at the next output instant once it is
        /// spent, writes the outputs of the time it simulated, and says so in summary.json.
        #[arg(long, value_parser = positive_seconds)]
        max_seconds: Option<f64>,
    },
    /// Directional tendency of the BHA: build/turn rates and equilibrium curvature at the
    /// case's WOB, and their map over stab1's position (or the bend's toolface) × WOB
    /// (CSV, plots; the grid from the case's [tendency] table).
    Tendency {
        /// Case file (TOML).
        case: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// No BHA-model solve runs past this many seconds (the cells cut say so).
        #[arg(long, value_parser = positive_seconds)]
        max_seconds: Option<f64>,
    },
    /// Critical rotary speeds: lateral modes of the BHA as it lies in the hole (the static
    /// state's contacts as supports) and the rpm at which 1×, blade pass and backward whirl
    /// excite them (CSV, Campbell diagram, mode shapes).
    CriticalSpeeds {
        /// Case file (TOML).
        case: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Highest rotary speed of the map (rpm).
        #[arg(long, default_value_t = critical::DEFAULT_MAX_RPM)]
        max_rpm: f64,
        /// Blades of the stabilizers and bit (blade-pass excitation).
        #[arg(long, default_value_t = critical::DEFAULT_BLADES)]
        blades: usize,
        /// Lateral modes reported.
        #[arg(long, default_value_t = critical::DEFAULT_MODES)]
        modes: usize,
        /// Leave the mud's added mass out of the modes (as the dynamics does).
        #[arg(long)]
        no_added_mass: bool,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Friction factors from measured loads: the cased- and open-hole friction factors that
    /// best explain a CSV of hook loads and surface torques against bit depth (a Bayesian
    /// grid over the FE model), their 95 % intervals, the residuals against depth and the
    /// broomstick with the measurements over it. Exit code 1 when the residuals say the
    /// string or survey is wrong rather than the friction (every output still written).
    Calibrate {
        /// Case file (TOML).
        case: PathBuf,
        /// CSV of measurements: bit_md_m (or _ft), mode, hook_load_kn (or _n, _klbf) and/or
        /// surface_torque_knm (or _nm, _kftlbf); wob_kn for drilling rows; rpm.
        #[arg(long)]
        measured: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Grid nodes per friction factor (FE runs at each, for every measured station).
        #[arg(long, default_value_t = 9)]
        nodes: usize,
        /// Range of the friction factors: low,high.
        #[arg(long, value_parser = mu_range, default_value = "0.05,0.6")]
        mu_range: (f64, f64),
        /// Standard deviation of the hook-load noise (kN); unknown (integrated out) if not
        /// given.
        #[arg(long)]
        sigma_hook_kn: Option<f64>,
        /// Standard deviation of the torque noise (kN·m); unknown if not given.
        #[arg(long)]
        sigma_torque_knm: Option<f64>,
        /// No model run starts past this many seconds (the run then stops, exit code 3).
        #[arg(long, value_parser = positive_seconds)]
        max_seconds: Option<f64>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// One case, many variants (CSV of overrides or the case's [ensemble] grid): statics
    /// or dynamics per variant, quantities of interest and status in variants.csv.
    Ensemble {
        /// Case file (with an [ensemble] table for a grid, analysis and series).
        case: PathBuf,
        /// CSV of variants: a header of keys (mu, k_e, rpm, wob, stab1.blade, …), a row each.
        #[arg(long)]
        variants: Option<PathBuf>,
        /// Where the variants run.
        #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
        backend: BackendChoice,
        /// Float type.
        #[arg(long, value_enum, default_value_t = Precision::F64)]
        precision: Precision,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Monte Carlo: draw this many samples of the case's `[ensemble.uncertain]` inputs.
        #[arg(long)]
        samples: Option<usize>,
        /// Seed of the samples (the same seed gives the same samples, bit for bit).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// How the samples are drawn.
        #[arg(long, value_enum, default_value_t = holewall::uq::Sampling::Lhs)]
        sampling: holewall::uq::Sampling,
        /// Further percentiles to report (comma-separated, 0–100), beside P10/P50/P90.
        #[arg(long, value_delimiter = ',')]
        percentile: Vec<f64>,
        /// Exceedance probability of a threshold, QOI=VALUE in SI (repeatable), e.g.
        /// `--exceed stab1_max_side_force_n=20000`.
        #[arg(long)]
        exceed: Vec<String>,
        /// First-order and total Sobol indices (a Saltelli design: --samples base points,
        /// samples × (inputs + 2) runs; needs --sampling sobol).
        #[arg(long)]
        sobol_indices: bool,
        /// Variants per result chunk (each written atomically; a killed run resumes from
        /// its chunks when started again with the same command).
        #[arg(long, default_value_t = holewall::ensemble::store::DEFAULT_CHUNK)]
        chunk_size: usize,
        /// Run only the K-th of N slices of the variants (`holewall merge` joins them).
        #[arg(long)]
        shard: Option<String>,
        /// Replace an earlier run's outputs in --out.
        #[arg(long)]
        force: bool,
        /// Wall-time budget (s): no further chunk starts once it is spent (at least one
        /// runs); the run stops with exit code 3, and the same command continues from its
        /// chunks.
        #[arg(long, value_parser = positive_seconds)]
        max_seconds: Option<f64>,
        /// Measured hook loads and surface torques against bit depth (the CSV of
        /// `holewall calibrate`), drawn over the broomstick as points.
        #[arg(long)]
        measured: Option<PathBuf>,
    },
    /// Studies of a case: `precision` (error against run time per path and step),
    /// `stability` (where the solver works).
    Study {
        #[command(subcommand)]
        what: StudyCommand,
    },
    /// Joins the folders of a run's `--shard K/N` runs into what the run without shards
    /// would write.
    Merge {
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// The shard folders.
        dirs: Vec<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Benchmarks (medians over repeats; GPU/CPU ratios from the same run).
    Bench {
        #[command(subcommand)]
        what: BenchCommand,
    },
}

#[derive(Subcommand)]
enum StudyCommand {
    /// Work-precision diagram of a dynamic case: for the case's time step halved
    /// `--refinements` times, each path's (CPU f64, GPU f64, GPU f32) largest relative error
    /// of the quantities of interest against a CPU f64 reference at a 4× finer step than
    /// the finest tried, beside its run time; precision.csv, precision.png (log–log),
    /// summary.json with the cheapest run within `--tolerance`.
    Precision {
        /// Case file with a [dynamics] table.
        case: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Halvings of the case's time step tried.
        #[arg(long, default_value_t = 2)]
        refinements: usize,
        /// Simulated time (s) of every run (default: the case's duration).
        #[arg(long, value_parser = positive_seconds)]
        duration: Option<f64>,
        /// Largest acceptable relative error, for the recommendation.
        #[arg(long, default_value_t = 1e-3)]
        tolerance: f64,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Where the solver works on a case: one parameter at a time around it (wall stiffness
    /// 1e5…1e11, spring exponent, ε, friction, the first stabilizer's clearance, WOB to 8×,
    /// time step to 16×) and the wall stiffness × exponent grid; per cell the static solve
    /// and, with [dynamics], a short run: solved, step cuts, Newton iterations, NaN;
    /// stability.csv, stability.png (the map), summary.json.
    Stability {
        /// Case file.
        case: PathBuf,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Simulated time of each dynamic cell (s; default the smaller of the case's and 0.5 s).
        #[arg(long, value_parser = positive_seconds)]
        duration: Option<f64>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
}

fn fail(errors: &[holewall::Error]) -> ExitCode {
    for e in errors {
        eprintln!("holewall: {e}");
    }
    let code = errors.iter().map(|e| e.exit_code()).max().unwrap_or(1);
    ExitCode::from(code as u8)
}

/// Prints a command's JSON summary on success; reports the error otherwise.
/// A summary as printed: JSON in the outputs' units (`--units`).
fn summary_text<T: serde::Serialize>(summary: &T) -> String {
    match holewall::display_units::get() {
        holewall::display_units::UnitSystem::Field => {
            serde_json::to_string_pretty(&holewall::display_units::convert_json(
                &serde_json::to_value(summary).unwrap_or_default(),
            ))
            .unwrap_or_default()
        }
        holewall::display_units::UnitSystem::Si => {
            serde_json::to_string_pretty(summary).unwrap_or_default()
        }
    }
}

fn print_summary<T: serde::Serialize>(result: Result<T, holewall::Error>) -> ExitCode {
    print_line(result.map(|s| summary_text(&s)))
}

/// A command's exit code: success, or its error reported.
fn done<T>(result: Result<T, holewall::Error>) -> ExitCode {
    result.map_or_else(|e| fail(&[e]), |_| ExitCode::SUCCESS)
}

/// A command's one line on stdout, or its error.
fn print_line(result: Result<String, holewall::Error>) -> ExitCode {
    match result {
        Ok(line) => {
            println!("{line}");
            ExitCode::SUCCESS
        }
        Err(e) => fail(&[e]),
    }
}

/// An ensemble's outcome on stdout: a few lines (the whole of it is `OUT/summary.json`,
/// tens of kB for a Monte Carlo run), nothing with `--quiet`.
fn print_ensemble_summary(
    result: Result<holewall::ensemble::report::EnsembleSummary, holewall::Error>,
    out: &std::path::Path,
    quiet: bool,
) -> ExitCode {
    match result {
        Ok(s) => {
            // The library prints nothing: its notices come back in the summary.
            for n in s.notices() {
                eprintln!("holewall: {n}");
            }
            if !quiet {
                println!("{}", s.digest(out));
            }
            ExitCode::SUCCESS
        }
        Err(e) => fail(&[e]),
    }
}

fn main() -> ExitCode {
    holewall::allocator::keep_freed_memory();
    holewall::threads::main_thread_in_pool();
    let args = Args::parse();
    holewall::display_units::set(args.units);
    match args.command {
        Command::Contact {
            backend,
            precision,
            file,
        } => {
            let (name, text) = match &file {
                Some(path) => match std::fs::read_to_string(path) {
                    Ok(t) => (path.display().to_string(), t),
                    Err(e) => {
                        eprintln!("holewall: {}: {e}", path.display());
                        return ExitCode::from(2);
                    }
                },
                None => {
                    let mut t = String::new();
                    if let Err(e) = std::io::stdin().read_to_string(&mut t) {
                        eprintln!("holewall: <stdin>: {e}");
                        return ExitCode::from(2);
                    }
                    ("<stdin>".to_string(), t)
                }
            };
            // Validate before choosing a backend, so bad input never waits on a GPU.
            if let Err(errs) = cli::contact::parse_all(&name, &text, precision == Precision::F32) {
                return fail(
                    &errs
                        .into_iter()
                        .map(holewall::Error::Input)
                        .collect::<Vec<_>>(),
                );
            }
            let backend = match Backend::resolve(backend, precision) {
                Ok((b, note)) => {
                    if let Some(n) = note {
                        eprintln!("holewall: {n}");
                    }
                    b
                }
                Err(e) => return fail(&[e.into()]),
            };
            let stdout = std::io::stdout();
            let mut lock = stdout.lock();
            match cli::contact::run(backend, precision, &name, &text, &mut lock) {
                Ok(()) => ExitCode::SUCCESS,
                Err(errs) => fail(&errs),
            }
        }
        Command::Static {
            case,
            model,
            out,
            quiet,
            max_seconds,
        } => print_summary(cli::static_cmd::run(
            &case,
            model,
            &out,
            cli::static_cmd::StaticCommandOptions {
                show_progress: !quiet,
                max_seconds,
            },
        )),
        Command::CriticalSpeeds {
            case,
            out,
            max_rpm,
            blades,
            modes,
            no_added_mass,
            quiet,
        } => print_summary(cli::critical_cmd::run(
            &case,
            &out,
            cli::critical_cmd::CriticalCommandOptions {
                max_rpm,
                blades,
                modes,
                show_progress: !quiet,
                added_mass: !no_added_mass,
            },
        )),
        Command::Calibrate {
            case,
            measured,
            out,
            nodes,
            mu_range,
            sigma_hook_kn,
            sigma_torque_knm,
            max_seconds,
            quiet,
        } => {
            let start = std::time::Instant::now();
            let options = holewall::calibrate::CalibrateOptions {
                nodes,
                range: mu_range,
                sigma_hook: sigma_hook_kn.map(|s| s * 1e3),
                sigma_torque: sigma_torque_knm.map(|s| s * 1e3),
                deadline: max_seconds.map(|s| start + std::time::Duration::from_secs_f64(s)),
            };
            match cli::calibrate_cmd::run(&case, &measured, &out, options, !quiet) {
                Ok(s) if !s.calibration.accepted => {
                    println!("{}", summary_text(&s));
                    for why in &s.calibration.rejected_because {
                        eprintln!("holewall: calibration rejected: {why}");
                    }
                    ExitCode::from(1)
                }
                other => print_summary(other),
            }
        }
        Command::Tendency {
            case,
            out,
            quiet,
            max_seconds,
        } => print_summary(cli::tendency_cmd::run(&case, &out, !quiet, max_seconds)),
        Command::Run {
            case,
            out,
            quiet,
            max_seconds,
        } => print_summary(cli::run_cmd::run(
            &case,
            &out,
            cli::run_cmd::RunOptions {
                show_progress: !quiet,
                max_seconds,
            },
        )),
        Command::Ensemble {
            case,
            variants,
            backend,
            precision,
            out,
            quiet,
            samples,
            seed,
            sampling,
            percentile,
            exceed,
            sobol_indices,
            chunk_size,
            shard,
            force,
            max_seconds,
            measured,
        } => {
            let mc = match cli::ensemble_cmd::monte_carlo(
                samples,
                seed,
                sampling,
                &percentile,
                &exceed,
                sobol_indices,
            ) {
                Ok(mc) => mc,
                Err(e) => return fail(&[e]),
            };
            let shard = match shard
                .as_deref()
                .map(cli::ensemble_cmd::parse_shard)
                .transpose()
            {
                Ok(s) => s,
                Err(e) => return fail(&[e]),
            };
            let options = holewall::ensemble::store::EnsembleOptions {
                monte_carlo: mc,
                chunk_size,
                shard,
                force,
                max_seconds,
                measured,
            };
            print_ensemble_summary(
                holewall::ensemble::job::run(
                    &case,
                    variants.as_deref(),
                    backend,
                    precision,
                    &out,
                    !quiet,
                    &options,
                ),
                &out,
                quiet,
            )
        }
        Command::Study { what } => match what {
            StudyCommand::Precision {
                case,
                out,
                refinements,
                duration,
                tolerance,
                quiet,
            } => print_summary(holewall::study::precision(
                &case,
                &out,
                holewall::study::PrecisionOptions {
                    refinements,
                    duration,
                    tolerance,
                    show_progress: !quiet,
                },
            )),
            StudyCommand::Stability {
                case,
                out,
                duration,
                quiet,
            } => print_summary(holewall::study::stability(
                &case,
                &out,
                holewall::study::StabilityOptions {
                    duration,
                    show_progress: !quiet,
                },
            )),
        },
        Command::Merge { out, dirs, quiet } => print_ensemble_summary(
            holewall::ensemble::job::merge(&out, &dirs, !quiet),
            &out,
            quiet,
        ),
        Command::GpuInfo { pairs } => done(cli::gpu_info::run(pairs)),
        Command::Bench { what } => match what {
            BenchCommand::Specialisation {
                pairs,
                repeats,
                json,
            } => done(cli::bench_specialisation::specialisation(
                pairs,
                repeats,
                json.as_deref(),
            )),
            BenchCommand::Contact {
                pairs,
                repeats,
                backend,
                json,
            } => done(cli::bench::contact(
                pairs,
                repeats,
                backend,
                json.as_deref(),
            )),
            BenchCommand::Ensemble {
                nodes,
                variants,
                steps,
                repeats,
                budget,
                cpu_only,
                precision_nodes,
                lu_form,
                trial_round,
                json,
            } => {
                cli::bench_cmd::apply_forms(lu_form, trial_round);
                let r = cli::bench_ensemble::run(
                    &nodes,
                    &variants,
                    steps,
                    repeats,
                    budget,
                    !cpu_only,
                    precision_nodes,
                    json.as_deref(),
                );
                done(r)
            }
            BenchCommand::Statics {
                case,
                variants,
                repeats,
                lu_form,
                trial_round,
                json,
            } => {
                cli::bench_cmd::apply_forms(lu_form, trial_round);
                done(cli::bench::statics(
                    &case,
                    variants.as_deref(),
                    repeats,
                    json.as_deref(),
                ))
            }
            BenchCommand::Device {
                out,
                cases,
                quick,
                quiet,
            } => done(cli::bench_device::run(
                &out,
                &cases,
                cli::bench_device::DeviceOptions {
                    quick,
                    show_progress: !quiet,
                },
            )),
            BenchCommand::Kernels {
                variants,
                nodes,
                repeats,
                out,
                quiet,
            } => done(cli::bench_kernels::run(
                &variants, nodes, repeats, &out, !quiet,
            )),
            BenchCommand::Job {
                case,
                samples,
                seed,
                variants,
                repeats,
                out,
                quiet,
            } => done(
                cli::bench_job::run(
                    &case,
                    variants.as_deref(),
                    samples,
                    seed,
                    repeats,
                    &out,
                    !quiet,
                )
                .map(|b| print!("{}", cli::bench_job::markdown(&b))),
            ),
            BenchCommand::Element {
                states,
                repeats,
                json,
            } => done(cli::bench::element(states, repeats, json.as_deref())),
            BenchCommand::CalibrateCorpus {
                wells,
                first_seed,
                out,
                quiet,
            } => print_summary(cli::bench_calibrate::run(&out, wells, first_seed, !quiet)),
            BenchCommand::DynamicCorpus {
                cases,
                first_seed,
                engine_sample,
                engine_max_nodes,
                max_seconds,
                out,
                quiet,
            } => print_summary(cli::bench_dynamic_corpus::run(
                &out,
                &cli::bench_dynamic_corpus::DynamicCorpusOptions {
                    cases,
                    first_seed,
                    engine_sample,
                    engine_max_nodes,
                    max_seconds,
                    show_progress: !quiet,
                },
            )),
            BenchCommand::CriticalCorpus {
                wells,
                first_seed,
                seeds,
                style,
                dense_max_dofs,
                out,
                quiet,
            } => print_line(
                cli::bench_critical::run(
                    &out,
                    &cli::bench_critical::CriticalCorpusOptions {
                        seeds: cli::bench_corpus::corpus_seeds(wells, first_seed, seeds),
                        style,
                        dense_max_dofs,
                        show_progress: !quiet,
                    },
                )
                .map(|s| s.line(&out)),
            ),
            BenchCommand::McCorpus(a) => print_line(a.run()),
            BenchCommand::TendencyCorpus {
                wells,
                first_seed,
                out,
                quiet,
            } => print_summary(cli::bench_corpus::tendency(&out, wells, first_seed, !quiet)),
            BenchCommand::Corpus {
                wells,
                first_seed,
                seeds,
                engine_sample,
                engine_max_nodes,
                max_seconds,
                out,
                quiet,
                style,
            } => print_line(
                cli::bench_corpus::run(
                    &out,
                    &cli::bench_corpus::CorpusOptions {
                        seeds: cli::bench_corpus::corpus_seeds(wells, first_seed, seeds),
                        engine_sample,
                        engine_max_nodes,
                        max_seconds,
                        show_progress: !quiet,
                        style,
                    },
                )
                .map(|s| s.line(&out)),
            ),
            BenchCommand::Mesh { seeds, out, quiet } => {
                done(cli::bench_corpus::mesh(&out, seeds, !quiet))
            }
            BenchCommand::Dynamics {
                case,
                steps,
                repeats,
                json,
            } => done(cli::bench::dynamics(&case, steps, repeats, json.as_deref())),
        },
    }
}

/// `--mu-range`: low,high with 0 ≤ low < high ≤ 2.
fn mu_range(s: &str) -> Result<(f64, f64), String> {
    let bad = || format!("{s:?}: allowed: low,high with 0 ≤ low < high ≤ 2");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let (a, b): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a >= 0.0 && b > a && b <= 2.0 {
        Ok((a, b))
    } else {
        Err(bad())
    }
}
