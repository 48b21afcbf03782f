//! `holewall bench corpus`: the FE static solve on a corpus of ordinary wells drawn from
//! seeds ([`crate::corpus`]) — solved / total, load steps, cuts, iterations and time per
//! well, FE/soft-string hook-load and torque ratios — as `corpus.csv`, `summary.json` and
//! plots; a sample through the ensemble engine (twin f64, GPU f64 and f32). The summary is
//! the library's ([`crate::corpus::CorpusSummary::of`]); this runs the wells and writes.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::corpus::{
    min_med_max, run_well, run_well_engine, spread, write_well, CorpusSummary, EngineOutcome,
    EnginePath, Spread, WellResult,
};
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

    let summary = CorpusSummary::of(
        &results,
        options.seeds.len() - results.len(),
        engine,
        engine_hook_difference,
        clock.elapsed().as_secs_f64(),
    );
    let solved: Vec<&WellResult> = results.iter().filter(|r| r.solved).collect();

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
    use super::corpus_seeds;

    #[test]
    fn listed_seeds_run_once_each_in_their_order_else_a_range() {
        assert_eq!(corpus_seeds(3, 5, Vec::new()), vec![5, 6, 7]);
        assert_eq!(corpus_seeds(3, 5, vec![9, 2, 9, 4, 2]), vec![9, 2, 4]);
    }
}
