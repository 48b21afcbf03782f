//! `holewall bench corpus`: the FE static solve on a corpus of ordinary wells drawn from
//! seeds ([`crate::corpus`]) — solved / total, load steps, cuts, iterations and time per
//! well, FE/soft-string hook-load and torque ratios — as `corpus.csv`, `summary.json` and
//! plots; a sample through the ensemble engine (twin f64, GPU f64 and f32).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::corpus::{run_well, run_well_engine, write_well, EngineOutcome, EnginePath, WellResult};
use crate::error::Error;
use crate::solve::statics::StaticOptions;

/// Options of the command.
#[derive(Clone, Debug)]
pub struct CorpusOptions {
    /// The wells' seeds, in the order they are listed ([`corpus_seeds`]).
    pub seeds: Vec<u64>,
    /// Wells of the corpus also run through the engine: the first ones with at most
    /// `engine_max_nodes` nodes (lavapipe runs the kernels on the CPU).
    pub engine_sample: usize,
    /// Largest mesh of the engine sample (nodes).
    pub engine_max_nodes: usize,
    /// Stop starting wells after this many seconds.
    pub max_seconds: Option<f64>,
    /// Progress bar.
    pub show_progress: bool,
    /// How the wells are drawn.
    pub style: crate::corpus::CorpusStyle,
}

/// The seeds of a corpus run: those listed (`--seeds`; each once, in the order first
/// listed: two runs of one seed would write the same case file), else `wells` from
/// `first_seed` on.
pub fn corpus_seeds(wells: usize, first_seed: u64, listed: Vec<u64>) -> Vec<u64> {
    if listed.is_empty() {
        return (first_seed..first_seed + wells as u64).collect();
    }
    let mut seen = std::collections::BTreeSet::new();
    listed.into_iter().filter(|s| seen.insert(*s)).collect()
}

/// Median and worst of a figure, with the seed of the worst.
#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// Largest.
    pub worst: f64,
    /// Seed of the largest.
    pub worst_seed: Option<u64>,
}

pub(crate) fn spread(values: &[(u64, f64)]) -> Spread {
    let mut v: Vec<(u64, f64)> = values.iter().copied().filter(|x| x.1.is_finite()).collect();
    v.sort_by(|a, b| a.1.total_cmp(&b.1));
    if v.is_empty() {
        return Spread {
            median: f64::NAN,
            worst: f64::NAN,
            worst_seed: None,
        };
    }
    Spread {
        median: v[v.len() / 2].1,
        worst: v[v.len() - 1].1,
        worst_seed: Some(v[v.len() - 1].0),
    }
}

/// `summary.json` of the benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct CorpusSummary {
    /// Wells run.
    pub wells: usize,
    /// Wells drawn but not run (the time budget ran out).
    pub not_run: usize,
    /// Solved at full load.
    pub solved: usize,
    /// Seeds of the wells that failed, with the first line of why.
    pub failed: Vec<(u64, String)>,
    /// Solved / total per trajectory kind.
    pub by_trajectory: BTreeMap<String, (usize, usize)>,
    /// Solved / total per pipe element length (m).
    pub by_element_length: BTreeMap<String, (usize, usize)>,
    /// Solved / total per operation.
    pub by_mode: BTreeMap<String, (usize, usize)>,
    /// Solved wells whose load path cut a step or changed stage (reported, not a pass).
    pub solved_with_cuts: usize,
    /// Solved wells whose load path relaxed past a fold (of `solved_with_cuts`).
    pub solved_by_relaxation: usize,
    /// Failed wells whose load locks up by the soft string carrying its buckled wall
    /// force ([`crate::diagnose::lock_up`]): a failure the physics predicts, still a
    /// failure.
    pub failed_locking_up: usize,
    /// Solved wells whose load locks up by that soft string (the FE answer, on a mesh that
    /// may not resolve the helix, disagrees with it: read its warning).
    pub solved_locking_up: usize,
    /// Failed wells, not locking up, whose turning buckled string nothing holds on the
    /// wall ([`crate::diagnose::rotating_whirl`]: it whirls; a failure, named).
    pub failed_whirling: usize,
    /// Solved wells the same rule names: since stop 69 solved at the whirl's average over
    /// the span [`crate::diagnose::whirl_span`] widens it to (the circumferential friction
    /// there as torque alone; the solver log says so).
    pub solved_whirling: usize,
    /// Seeds of the wells solved only by a second solve at the whirl's average over the
    /// span the FE string's own compression names, where the first failed
    /// ([`crate::profile::WHIRL_FROM_FE`]; of `solved_with_cuts`).
    pub solved_whirl_from_fe: Vec<u64>,
    /// Solved wells whose relaxation reached its ceiling and shifted the rotations too
    /// ([`crate::solve::continuation::ROTATIONS_SHIFTED`]; of `solved_by_relaxation`).
    pub solved_rotations_shifted: Vec<u64>,
    /// Solved wells whose answer stresses the pipe past every API grade's yield
    /// ([`crate::diagnose::past_yield`]): counted solved, an answer no pipe carries.
    pub solved_past_yield: Vec<u64>,
    /// Failed lock-up wells: (seed, the load factor the FE reached, the factor at which
    /// the buckled soft string locks up, [`crate::diagnose::lock_up_fraction`]). Where
    /// the two agree, the FE's fold is the lock-up the physics predicts.
    pub lock_up_factors: Vec<(u64, f64, f64)>,
    /// Failed wells whose load path bracketed where the string stops and gave the string
    /// where it stands there (`corpus.csv`'s `stopped_hook_load_n`): (seed, that load
    /// factor, the FE hook load there, N).
    pub failed_stopped: Vec<(u64, f64, f64)>,
    /// Solved wells whose FE string lies outside the hole where no contact site holds it
    /// (`contact.sites = "stabilizers"`: [`crate::diagnose::through_wall`]), with how far
    /// (mm): an equilibrium of a string in no hole, counted in `solved` but not an answer.
    pub solved_through_wall: Vec<(u64, f64)>,
    /// Time per well (s), every well.
    pub seconds: Spread,
    /// Solved wells whose FE hook load is below zero: the string pushed from the surface,
    /// the equilibrium past a lock-up that [`crate::diagnose::locked_up_warning`] calls one
    /// the string does not reach by being run in. At 10 m elements every solved well that
    /// took over 1,500 Newton iterations on the unseen slices and the relaxed set of stop 81
    /// is one (docs/performance.md).
    pub solved_pushed: Vec<u64>,
    /// Time per well (s), wells meshed with pipe elements of about 10 m (9–11 m: the user
    /// style's 30 ft joints, 9.144 m, are of them).
    pub seconds_10m: Spread,
    /// Those wells over issue 22's 2 s ([`over_2s_10m`]): (seed, seconds, pushed from the
    /// surface, its load locks up by the buckled soft string).
    pub over_2s_10m: Vec<(u64, f64, bool, bool)>,
    /// Newton iterations per solved well (its completed load steps).
    pub iterations: Spread,
    /// Every Newton iteration per well, failed tries, cut steps and relaxations included,
    /// every well (what the time goes on).
    pub newton_iterations: Spread,
    /// FE / soft-string hook load, solved wells (median; worst = largest |ratio − 1|).
    pub hook_load_ratio: (f64, f64, f64),
    /// FE / soft-string surface torque, solved rotating wells (min, median, max).
    pub torque_ratio: (f64, f64, f64),
    /// The engine sample: solved / run per path (paths that cannot run here say why).
    pub engine: BTreeMap<String, String>,
    /// The engine's hook load against the CPU FE's, largest relative difference per path.
    pub engine_hook_difference: BTreeMap<String, f64>,
    /// Total wall time (s).
    pub wall_seconds: f64,
}

/// A well meshed with pipe elements of about 10 m ([`CorpusSummary::seconds_10m`]).
fn ten_m(r: &WellResult) -> bool {
    (9.0..=11.0).contains(&r.spec.element_m)
}

/// The wells at about 10 m elements that took over issue 22's 2 s
/// ([`CorpusSummary::over_2s_10m`]): whether each is pushed from the surface and whether its
/// load locks up by the buckled soft string (`lock_up_md_m`, as `failed_locking_up` and
/// `solved_locking_up` count). On the unseen corpora of stop 89 every one over 2 s alone
/// locks up so, pushed or not (docs/performance.md).
fn over_2s_10m(results: &[WellResult]) -> Vec<(u64, f64, bool, bool)> {
    results
        .iter()
        .filter(|r| ten_m(r) && r.seconds > 2.0)
        .map(|r| {
            (
                r.spec.seed,
                r.seconds,
                pushed(r),
                r.lock_up_md_m.is_finite(),
            )
        })
        .collect()
}

/// A solved well whose string the surface pushes ([`CorpusSummary::solved_pushed`]).
fn pushed(r: &WellResult) -> bool {
    r.solved && r.fe_hook_load_n < 0.0
}

impl CorpusSummary {
    /// The run in one line (what `holewall bench corpus` prints), `out` its folder.
    pub fn line(&self, out: &Path) -> String {
        let over = &self.over_2s_10m;
        format!(
            "{} of {} wells solved ({} not run; {} of the solved lie outside the hole between \
             contact sites; {} pushed from the surface); time per well median {:.2} s, worst \
             {:.2} s (seed {:?}); at about 10 m elements (9–11 m) median {:.2} s, worst {:.2} s, {} over 2 s \
             ({} of them pushed, {} locking up by the soft string); engine {:?}; {}",
            self.solved,
            self.wells,
            self.not_run,
            self.solved_through_wall.len(),
            self.solved_pushed.len(),
            self.seconds.median,
            self.seconds.worst,
            self.seconds.worst_seed,
            self.seconds_10m.median,
            self.seconds_10m.worst,
            over.len(),
            over.iter().filter(|o| o.2).count(),
            over.iter().filter(|o| o.3).count(),
            self.engine,
            out.join("summary.json").display()
        )
    }
}

fn min_med_max(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    (v[0], v[v.len() / 2], v[v.len() - 1])
}

/// Runs the benchmark into `out` (created; `wells/` holds every well's case and survey).
pub fn run(out: &Path, options: &CorpusOptions) -> Result<CorpusSummary, Error> {
    let clock = std::time::Instant::now();
    let wells_dir = out.join("wells");
    std::fs::create_dir_all(&wells_dir)?;
    let bar = crate::output::progress_bar(
        options.show_progress,
        options.seeds.len() as u64,
        "{bar:40} {pos}/{len} wells, {elapsed} elapsed, {msg}",
    );
    // Wells in parallel (rayon, one well per core): each well's time is measured with the
    // other cores busy with other wells.
    use rayon::prelude::*;
    let static_options = StaticOptions::default();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let outcomes: Vec<Option<(crate::corpus::CorpusWell, WellResult)>> = options
        .seeds
        .par_iter()
        .map(|&seed| {
            if options
                .max_seconds
                .is_some_and(|s| clock.elapsed().as_secs_f64() > s)
            {
                return Ok(None);
            }
            let well = crate::corpus::write_corpus_well(options.style, seed, &wells_dir)?;
            let r = run_well(&well, &static_options)?;
            if r.solved {
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
            bar.set_message(format!(
                "{} solved",
                done.load(std::sync::atomic::Ordering::Relaxed)
            ));
            bar.inc(1);
            Ok(Some((well, r)))
        })
        .collect::<Result<_, Error>>()?;
    let (drawn, results): (Vec<_>, Vec<_>) = outcomes.into_iter().flatten().unzip();
    bar.finish_and_clear();

    // The engine sample.
    let mut engine_rows: Vec<EngineOutcome> = Vec::new();
    let mut engine = BTreeMap::new();
    let mut engine_hook_difference = BTreeMap::new();
    for path in [EnginePath::Twin, EnginePath::GpuF64, EnginePath::GpuF32] {
        let name = format!("{path:?}").to_lowercase();
        let mut run = 0;
        let mut ok = 0;
        let mut worst: f64 = 0.0;
        let mut why = None;
        for (well, cpu) in drawn
            .iter()
            .zip(&results)
            .filter(|(_, r)| r.nodes <= options.engine_max_nodes)
            .take(options.engine_sample)
        {
            match run_well_engine(well, path) {
                Ok(o) => {
                    run += 1;
                    if o.solved {
                        ok += 1;
                        if cpu.solved {
                            worst = worst.max(
                                ((o.hook_load_n - cpu.fe_hook_load_n) / cpu.fe_hook_load_n).abs(),
                            );
                        }
                    }
                    engine_rows.push(o);
                }
                Err(e) => {
                    why = Some(e);
                    break;
                }
            }
        }
        if !options.show_progress && options.engine_sample > 0 {
            eprintln!("engine sample, {name}: {ok} of {run} solved");
        }
        if options.engine_sample > 0 {
            engine.insert(
                name.clone(),
                match why {
                    Some(e) if run == 0 => format!("not run: {e}"),
                    _ => format!("{ok}/{run}"),
                },
            );
            engine_hook_difference.insert(name, worst);
        }
    }

    let count = |f: &dyn Fn(&WellResult) -> String| {
        let mut m: BTreeMap<String, (usize, usize)> = BTreeMap::new();
        for r in &results {
            let e = m.entry(f(r)).or_default();
            e.0 += usize::from(r.solved);
            e.1 += 1;
        }
        m
    };
    let solved: Vec<&WellResult> = results.iter().filter(|r| r.solved).collect();
    let hook: Vec<f64> = solved.iter().map(|r| r.hook_load_ratio).collect();
    let summary = CorpusSummary {
        wells: results.len(),
        not_run: options.seeds.len() - results.len(),
        solved: solved.len(),
        failed: results
            .iter()
            .filter(|r| !r.solved)
            .map(|r| {
                (
                    r.spec.seed,
                    r.error.lines().next().unwrap_or_default().to_string(),
                )
            })
            .collect(),
        by_trajectory: count(&|r| r.spec.trajectory.name().to_string()),
        by_element_length: count(&|r| format!("{:>4} m", r.spec.element_m)),
        by_mode: count(&|r| r.spec.mode.clone()),
        solved_with_cuts: solved.iter().filter(|r| r.step_cuts > 0).count(),
        solved_by_relaxation: solved.iter().filter(|r| r.relaxed).count(),
        failed_locking_up: results
            .iter()
            .filter(|r| !r.solved && r.lock_up_md_m.is_finite())
            .count(),
        solved_locking_up: solved.iter().filter(|r| r.lock_up_md_m.is_finite()).count(),
        failed_whirling: results
            .iter()
            .filter(|r| !r.solved && !r.lock_up_md_m.is_finite() && r.whirl_md_m.is_finite())
            .count(),
        solved_whirling: solved.iter().filter(|r| r.whirl_md_m.is_finite()).count(),
        solved_whirl_from_fe: solved
            .iter()
            .filter(|r| r.whirl_from_fe)
            .map(|r| r.spec.seed)
            .collect(),
        solved_rotations_shifted: solved
            .iter()
            .filter(|r| r.rotations_shifted)
            .map(|r| r.spec.seed)
            .collect(),
        solved_past_yield: solved
            .iter()
            .filter(|r| r.past_yield)
            .map(|r| r.spec.seed)
            .collect(),
        lock_up_factors: results
            .iter()
            .filter(|r| !r.solved && r.lock_up_fraction.is_finite())
            .map(|r| (r.spec.seed, r.fe_reached, r.lock_up_fraction))
            .collect(),
        failed_stopped: results
            .iter()
            .filter(|r| !r.solved && r.stopped_hook_load_n.is_finite())
            .map(|r| (r.spec.seed, r.fe_reached, r.stopped_hook_load_n))
            .collect(),
        solved_through_wall: solved
            .iter()
            .filter(|r| r.through_wall_mm > 0.0)
            .map(|r| (r.spec.seed, r.through_wall_mm))
            .collect(),
        seconds: spread(
            &results
                .iter()
                .map(|r| (r.spec.seed, r.seconds))
                .collect::<Vec<_>>(),
        ),
        solved_pushed: solved
            .iter()
            .filter(|r| pushed(r))
            .map(|r| r.spec.seed)
            .collect(),
        seconds_10m: spread(
            &results
                .iter()
                .filter(|r| ten_m(r))
                .map(|r| (r.spec.seed, r.seconds))
                .collect::<Vec<_>>(),
        ),
        over_2s_10m: over_2s_10m(&results),
        iterations: spread(
            &solved
                .iter()
                .map(|r| (r.spec.seed, r.iterations as f64))
                .collect::<Vec<_>>(),
        ),
        newton_iterations: spread(
            &results
                .iter()
                .map(|r| (r.spec.seed, r.newton_iterations as f64))
                .collect::<Vec<_>>(),
        ),
        hook_load_ratio: min_med_max(hook),
        torque_ratio: min_med_max(solved.iter().map(|r| r.torque_ratio).collect()),
        engine,
        engine_hook_difference,
        wall_seconds: clock.elapsed().as_secs_f64(),
    };

    crate::output::write_csv_rows(&out.join("corpus.csv"), results.iter().map(WellResult::row))?;
    if !engine_rows.is_empty() {
        crate::output::write_csv_rows(&out.join("engine.csv"), &engine_rows)?;
    }
    let classes = [
        "solved",
        "solved by relaxation",
        "failed",
        "solved outside the hole",
    ];
    let class = |r: &WellResult| match (r.solved, r.relaxed) {
        (true, _) if r.through_wall_mm > 0.0 => 3,
        (true, false) => 0,
        (true, true) => 1,
        (false, _) => 2,
    };
    crate::plots::class_scatter(
        &out.join("corpus_time.png"),
        &format!(
            "FE static solve, {} of {} corpus wells solved: time per well",
            summary.solved, summary.wells
        ),
        "nodes of the mesh",
        "wall time (s)",
        &results
            .iter()
            .map(|r| (r.nodes as f64, r.seconds, class(r)))
            .collect::<Vec<_>>(),
        &classes,
    )?;
    crate::plots::class_scatter(
        &out.join("corpus_map.png"),
        "Where the FE static solve fails: pipe element length against measured depth",
        "measured depth (m)",
        "pipe element length (m)",
        &results
            .iter()
            .map(|r| (r.spec.total_md, r.spec.element_m, class(r)))
            .collect::<Vec<_>>(),
        &classes,
    )?;
    crate::plots::histogram(
        &out.join("corpus_hook_ratio.png"),
        "FE / soft-string hook load, solved corpus wells",
        "hook load ratio FE / soft string (–)",
        &solved.iter().map(|r| r.hook_load_ratio).collect::<Vec<_>>(),
        &[("median", summary.hook_load_ratio.1)],
    )?;
    let json = serde_json::to_vec_pretty(&summary)?;
    crate::output::write_atomic(&out.join("summary.json"), &json)?;
    Ok(summary)
}

/// One row of the mesh-convergence table.
#[derive(Clone, Debug, Serialize)]
pub struct MeshRow {
    /// Seed of the corpus well.
    pub seed: u64,
    /// Trajectory.
    pub trajectory: String,
    /// Pipe element length (m).
    pub element_m: f64,
    /// BHA element length (m).
    pub bha_element_m: f64,
    /// Nodes.
    pub nodes: usize,
    /// Solved.
    pub solved: bool,
    /// Wall time (s).
    pub seconds: f64,
    /// Hook load (kN).
    pub hook_load_kn: f64,
    /// Surface torque (kN·m).
    pub torque_knm: f64,
    /// Largest side force (kN).
    pub max_side_force_kn: f64,
    /// Where (MD, m).
    pub max_side_force_md_m: f64,
    /// Stabilizer forces, nearest the bit first (kN), `;`-separated.
    pub stabilizer_forces_kn: String,
}

/// `holewall bench mesh`: hook load, torque, the largest side force and the stabilizer
/// forces of corpus wells as the elements shrink ([`crate::corpus::MESHES`]); `seeds`
/// default to [`crate::corpus::mesh_study_seeds`]. Writes `mesh.csv` and `mesh.md`.
pub fn mesh(
    out: &Path,
    seeds: Option<Vec<u64>>,
    show_progress: bool,
) -> Result<Vec<MeshRow>, Error> {
    use crate::corpus::{mesh_study_seeds, remesh, MESHES};
    let dir = out.join("wells");
    std::fs::create_dir_all(&dir)?;
    let seeds = match seeds {
        Some(s) => s,
        None => mesh_study_seeds(&dir)?,
    };
    let bar = crate::output::progress_bar(
        show_progress,
        (seeds.len() * MESHES.len()) as u64,
        "{bar:40} {pos}/{len} meshes, {elapsed} elapsed",
    );
    let mut rows = Vec::new();
    for &seed in &seeds {
        let well = write_well(seed, &dir)?;
        for &(el, bha) in &MESHES {
            let w = remesh(&well, el, bha)?;
            let r = run_well(&w, &StaticOptions::default())?;
            rows.push(MeshRow {
                seed,
                trajectory: w.spec.trajectory.name().to_string(),
                element_m: el,
                bha_element_m: bha,
                nodes: r.nodes,
                solved: r.solved,
                seconds: r.seconds,
                hook_load_kn: r.fe_hook_load_n / 1e3,
                torque_knm: r.fe_torque_nm / 1e3,
                max_side_force_kn: r.max_side_force_n / 1e3,
                max_side_force_md_m: r.max_side_force_md_m,
                stabilizer_forces_kn: r
                    .stabilizer_forces_n
                    .iter()
                    .map(|f| format!("{:.2}", f / 1e3))
                    .collect::<Vec<_>>()
                    .join("; "),
            });
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    crate::output::write_csv_rows(&out.join("mesh.csv"), &rows)?;
    let mut md = String::from(
        "| seed | well | pipe / BHA element (m) | nodes | solved | time (s) | hook load (kN) | torque (kN·m) | largest side force (kN) at MD (m) | stabilizer forces from the bit (kN) |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} / {} | {} | {} | {:.2} | {:.1} | {:.2} | {:.2} at {:.0} | {} |\n",
            r.seed,
            r.trajectory,
            r.element_m,
            r.bha_element_m,
            r.nodes,
            if r.solved { "yes" } else { "**no**" },
            r.seconds,
            r.hook_load_kn,
            r.torque_knm,
            r.max_side_force_kn,
            r.max_side_force_md_m,
            r.stabilizer_forces_kn
        ));
    }
    crate::output::write_atomic(&out.join("mesh.md"), md.as_bytes())?;
    print!("{md}");
    Ok(rows)
}

/// One corpus well's tendency (a row of `tendency_corpus.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct TendencyRow {
    /// Seed.
    pub seed: u64,
    /// Trajectory kind.
    pub trajectory: String,
    /// Operation.
    pub mode: String,
    /// Inclination at the bit (°).
    pub bit_inclination_deg: f64,
    /// Stabilizers.
    pub stabilizers: usize,
    /// Bend (°).
    pub bend_deg: f64,
    /// Weight on bit (N).
    pub wob_n: f64,
    /// Whether the build/turn iterations settled (wells with WOB only).
    pub settled: bool,
    /// Build rate (°/30 m).
    pub build_rate_deg_per_30m: f64,
    /// Turn rate (°/30 m).
    pub turn_rate_deg_per_30m: f64,
    /// Equilibrium curvature (°/30 m).
    pub equilibrium_curvature_deg_per_30m: f64,
    /// BHA-model solves.
    pub solves: usize,
    /// Wall time (s).
    pub seconds: f64,
    /// Why not, when not.
    pub notes: String,
}

/// `summary.json` of the tendency benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct TendencyCorpusSummary {
    /// Wells drawn.
    pub wells: usize,
    /// Wells with weight on bit (the tendency applies).
    pub with_wob: usize,
    /// Of those, settled build/turn rates.
    pub settled: usize,
    /// Of those, an equilibrium curvature within ±30°/30 m.
    pub equilibrium_found: usize,
    /// The unsettled: seed and why.
    pub unsettled: Vec<(u64, String)>,
    /// Time per well (s).
    pub seconds: Spread,
    /// Build rates (°/30 m): min, median, max over the settled.
    pub build_rate: (f64, f64, f64),
    /// Total wall time (s).
    pub wall_seconds: f64,
}

/// The tendency ([`crate::bha::tendency::assembly_tendency`]) of `wells` corpus wells from
/// `first_seed` at their own weight on bit: `tendency_corpus.csv`, `summary.json` in `out`.
pub fn tendency(
    out: &Path,
    wells: usize,
    first_seed: u64,
    show_progress: bool,
) -> Result<TendencyCorpusSummary, Error> {
    use rayon::prelude::*;
    let clock = std::time::Instant::now();
    let dir = out.join("wells");
    std::fs::create_dir_all(&dir)?;
    let bar = crate::output::progress_bar(
        show_progress,
        wells as u64,
        "{bar:40} {pos}/{len} wells, {elapsed} elapsed",
    );
    let rows: Result<Vec<TendencyRow>, Error> = (first_seed..first_seed + wells as u64)
        .into_par_iter()
        .map(|seed| {
            let well = crate::corpus::write_well(seed, &dir)?;
            let case = crate::case::load_case(&well.case_path)?;
            let m = &case.model;
            let t0 = std::time::Instant::now();
            let t = crate::bha::tendency::assembly_tendency(
                m,
                case.bha_length,
                m.weight_on_bit,
                &case.tendency.settings,
            );
            let axis = m.nodes[m.nodes.len() - 1].hole_axis;
            bar.inc(1);
            Ok(TendencyRow {
                seed,
                trajectory: well.spec.trajectory.name().to_string(),
                mode: well.spec.mode.clone(),
                bit_inclination_deg: axis[2].clamp(-1.0, 1.0).acos().to_degrees(),
                stabilizers: well.spec.stabilizers,
                bend_deg: well.spec.bend_deg,
                wob_n: m.weight_on_bit,
                settled: t.build_rate_deg_per_30m.is_some(),
                build_rate_deg_per_30m: t.build_rate_deg_per_30m.unwrap_or(f64::NAN),
                turn_rate_deg_per_30m: t.turn_rate_deg_per_30m.unwrap_or(f64::NAN),
                equilibrium_curvature_deg_per_30m: t
                    .equilibrium_curvature_deg_per_30m
                    .unwrap_or(f64::NAN),
                solves: t.solves,
                seconds: t0.elapsed().as_secs_f64(),
                notes: t.notes.join("; "),
            })
        })
        .collect();
    bar.finish_and_clear();
    let rows = rows?;
    crate::output::write_csv_rows(&out.join("tendency_corpus.csv"), &rows)?;
    let with_wob: Vec<&TendencyRow> = rows.iter().filter(|r| r.wob_n > 0.0).collect();
    let summary = TendencyCorpusSummary {
        wells: rows.len(),
        with_wob: with_wob.len(),
        settled: with_wob.iter().filter(|r| r.settled).count(),
        equilibrium_found: with_wob
            .iter()
            .filter(|r| r.equilibrium_curvature_deg_per_30m.is_finite())
            .count(),
        unsettled: with_wob
            .iter()
            .filter(|r| !r.settled)
            .map(|r| (r.seed, r.notes.chars().take(300).collect()))
            .collect(),
        seconds: spread(&rows.iter().map(|r| (r.seed, r.seconds)).collect::<Vec<_>>()),
        build_rate: min_med_max(with_wob.iter().map(|r| r.build_rate_deg_per_30m).collect()),
        wall_seconds: clock.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_vec_pretty(&summary)?;
    crate::output::write_atomic(&out.join("summary.json"), &json)?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::{corpus_seeds, over_2s_10m};

    /// A 10 m well over 2 s is listed with whether it is pushed and whether the soft string
    /// locks it up; one meshed otherwise, or faster, is not.
    #[test]
    fn a_slow_10_m_well_is_listed_pushed_and_locking_up_or_not() {
        let dir = std::env::temp_dir().join(format!("holewall_over2s_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let well = crate::corpus::write_well(1, &dir).unwrap();
        let r = crate::corpus::run_well(&well, &Default::default()).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert!(r.solved && r.fe_hook_load_n > 0.0 && !r.lock_up_md_m.is_finite());
        let mut slow = r.clone();
        (slow.spec.element_m, slow.seconds) = (10.0, 2.5);
        let mut pushed_locking = slow.clone();
        pushed_locking.spec.seed = 7;
        (pushed_locking.fe_hook_load_n, pushed_locking.lock_up_md_m) = (-5e4, 1500.0);
        let mut fast = slow.clone();
        fast.seconds = 1.5;
        let mut coarse = slow.clone();
        coarse.spec.element_m = 30.0;
        let listed = over_2s_10m(&[r, slow, pushed_locking, fast, coarse]);
        assert_eq!(listed, vec![(1, 2.5, false, false), (7, 2.5, true, true)]);
    }

    #[test]
    fn listed_seeds_run_once_each_in_their_order_else_a_range() {
        assert_eq!(corpus_seeds(3, 5, Vec::new()), vec![5, 6, 7]);
        assert_eq!(corpus_seeds(3, 5, vec![9, 2, 9, 4, 2]), vec![9, 2, 4]);
    }
}
