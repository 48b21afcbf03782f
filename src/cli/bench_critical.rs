//! `holewall bench critical-corpus`: the critical-speed analysis
//! ([`crate::bha::critical::critical_speeds_of_case`]) on corpus wells drawn from seeds — its
//! time per well against the size of the eigenproblem, whether it found the lateral modes
//! asked for, and its frequencies against the dense eigensolve
//! ([`crate::solve::modal::modes`]) where that is small enough to run
//! (`critical_corpus.csv`, `summary.json`, `critical_corpus_time.png`).

use std::path::Path;

use serde::Serialize;

use crate::bha::critical::{
    critical_speeds_of_case, CriticalOptions, CriticalSpeeds, DEFAULT_BLADES, DEFAULT_MAX_RPM,
    DEFAULT_MODES as MODES,
};
use crate::corpus::{spread, Spread};
use crate::corpus::{write_corpus_well, CorpusStyle};
use crate::error::Error;

/// Options of the benchmark.
#[derive(Clone, Debug)]
pub struct CriticalCorpusOptions {
    /// Seeds of the wells, in order.
    pub seeds: Vec<u64>,
    /// How the wells are drawn.
    pub style: CorpusStyle,
    /// The dense oracle runs on wells of at most this many DOFs in the BHA part.
    pub dense_max_dofs: usize,
    /// Progress bar on stderr.
    pub show_progress: bool,
}

/// One well (a row of `critical_corpus.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct CriticalRow {
    /// Seed.
    pub seed: u64,
    /// Trajectory kind.
    pub trajectory: String,
    /// Operation.
    pub mode: String,
    /// Stabilizers.
    pub stabilizers: usize,
    /// BHA element length (m).
    pub bha_element_m: f64,
    /// Nodes of the whole string's mesh.
    pub nodes: usize,
    /// The static solve converged (the modes are about its state).
    pub static_solved: bool,
    /// DOFs of the BHA part's eigenproblem.
    pub part_dofs: usize,
    /// `dense` or `shift-invert block Lanczos`.
    pub method: String,
    /// Krylov basis (the free DOFs where dense).
    pub basis: usize,
    /// Largest relative residual of the modes found.
    pub worst_residual: f64,
    /// Lateral modes found (of [`MODES`] asked for).
    pub lateral_modes: usize,
    /// Lowest lateral frequency (Hz).
    pub first_hz: f64,
    /// Wall time of the critical-speed analysis, the static solve not counted (s).
    pub seconds: f64,
    /// Wall time of the same analysis solved densely (s; NaN where not run).
    pub dense_seconds: f64,
    /// Largest relative difference of a lateral frequency from the dense solve's (NaN where
    /// not run; infinite where the two found different numbers of lateral modes).
    pub dense_difference: f64,
    /// Why not, where the static solve failed.
    pub error: String,
}

/// `summary.json` of the benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct CriticalCorpusSummary {
    /// Wells drawn.
    pub wells: usize,
    /// Wells whose static solve converged (the others are not analysed).
    pub analysed: usize,
    /// Of those, the wells where every lateral mode asked for was found.
    pub all_modes_found: usize,
    /// Of those analysed, solved by the Krylov solve (the rest densely: small parts).
    pub krylov: usize,
    /// Time of the analysis per well (s).
    pub seconds: Spread,
    /// Wells compared with the dense solve.
    pub compared: usize,
    /// Largest relative difference of a lateral frequency from the dense solve's.
    pub dense_difference: Spread,
    /// Compared wells whose lateral frequencies differ by more than 1e-6.
    pub mismatched: Vec<u64>,
    /// The dense solve's time over this one's, median over the compared Krylov wells.
    pub speedup_median: f64,
    /// Total wall time (s).
    pub wall_seconds: f64,
}

impl CriticalCorpusSummary {
    /// The line the command prints.
    pub fn line(&self, out: &Path) -> String {
        format!(
            "{} of {} wells analysed (the rest: static solve failed), {} with all {MODES} lateral \
             modes; {} by the Krylov solve; time per well median {:.3} s, worst {:.3} s (seed \
             {:?}); {} compared with the dense solve: worst frequency difference {:.1e} (seed \
             {:?}), {} over 1e-6, median speed-up {:.0}×; {}",
            self.analysed,
            self.wells,
            self.all_modes_found,
            self.krylov,
            self.seconds.median,
            self.seconds.worst,
            self.seconds.worst_seed,
            self.compared,
            self.dense_difference.worst,
            self.dense_difference.worst_seed,
            self.mismatched.len(),
            self.speedup_median,
            out.join("summary.json").display()
        )
    }
}

fn timed(f: impl FnOnce() -> CriticalSpeeds) -> (CriticalSpeeds, f64) {
    let t = std::time::Instant::now();
    let cs = f();
    (cs, t.elapsed().as_secs_f64())
}

/// The largest relative difference between two lists of lateral frequencies (infinite where
/// their lengths differ).
fn difference(a: &CriticalSpeeds, b: &CriticalSpeeds) -> f64 {
    if a.modes.len() != b.modes.len() {
        return f64::INFINITY;
    }
    a.modes
        .iter()
        .zip(&b.modes)
        .map(|(p, q)| (p.frequency_hz - q.frequency_hz).abs() / q.frequency_hz.abs().max(1e-12))
        .fold(0.0, f64::max)
}

fn well_row(seed: u64, options: &CriticalCorpusOptions, dir: &Path) -> Result<CriticalRow, Error> {
    let well = write_corpus_well(options.style, seed, dir)?;
    let mut case = crate::case::load_case(&well.case_path)?;
    let bha_element_m = case.model.elements.last().map_or(f64::NAN, |e| e.length0);
    let mut row = CriticalRow {
        seed,
        trajectory: well.spec.trajectory.name().to_string(),
        mode: well.spec.mode.clone(),
        stabilizers: well.spec.stabilizers,
        bha_element_m,
        nodes: case.model.nodes.len(),
        static_solved: false,
        part_dofs: 0,
        method: String::new(),
        basis: 0,
        worst_residual: f64::NAN,
        lateral_modes: 0,
        first_hz: f64::NAN,
        seconds: f64::NAN,
        dense_seconds: f64::NAN,
        dense_difference: f64::NAN,
        error: String::new(),
    };
    let statics = case.settings().statics();
    let sol = match crate::profile::solve_with_progress(&mut case, statics, false) {
        Ok(s) => s,
        Err(e) => {
            row.error = e.to_string().chars().take(300).collect();
            return Ok(row);
        }
    };
    let opts =
        CriticalOptions::for_case(&case, DEFAULT_MAX_RPM, DEFAULT_BLADES, MODES, true, false);
    let (cs, seconds) = timed(|| critical_speeds_of_case(&case, &sol.state, &opts));
    row.static_solved = true;
    row.part_dofs = cs.dofs;
    row.method = cs.eigen_method.clone();
    row.basis = cs.eigen_basis;
    row.worst_residual = cs.eigen_worst_residual;
    row.lateral_modes = cs.modes.len();
    row.first_hz = cs.modes.first().map_or(f64::NAN, |m| m.frequency_hz);
    row.seconds = seconds;
    if cs.dofs <= options.dense_max_dofs {
        let dense = CriticalOptions {
            dense: true,
            ..opts
        };
        let (oracle, dense_seconds) = timed(|| critical_speeds_of_case(&case, &sol.state, &dense));
        row.dense_seconds = dense_seconds;
        row.dense_difference = difference(&cs, &oracle);
    }
    Ok(row)
}

/// Runs the benchmark into `out` (created; `wells/` holds every well's case and survey).
pub fn run(out: &Path, options: &CriticalCorpusOptions) -> Result<CriticalCorpusSummary, Error> {
    let clock = std::time::Instant::now();
    let dir = out.join("wells");
    std::fs::create_dir_all(&dir)?;
    let bar = crate::output::progress_bar(
        options.show_progress,
        options.seeds.len() as u64,
        "{bar:40} {pos}/{len} wells, {elapsed} elapsed",
    );
    // One well at a time: the times are each well's own.
    let mut rows = Vec::with_capacity(options.seeds.len());
    for &seed in &options.seeds {
        rows.push(well_row(seed, options, &dir)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    crate::output::write_csv_rows(&out.join("critical_corpus.csv"), &rows)?;
    let analysed: Vec<&CriticalRow> = rows.iter().filter(|r| r.static_solved).collect();
    let compared: Vec<&CriticalRow> = analysed
        .iter()
        .copied()
        .filter(|r| !r.dense_difference.is_nan())
        .collect();
    let mut speedups: Vec<f64> = compared
        .iter()
        .filter(|r| r.method != "dense")
        .map(|r| r.dense_seconds / r.seconds)
        .collect();
    speedups.sort_by(f64::total_cmp);
    let summary = CriticalCorpusSummary {
        wells: rows.len(),
        analysed: analysed.len(),
        all_modes_found: analysed.iter().filter(|r| r.lateral_modes >= MODES).count(),
        krylov: analysed.iter().filter(|r| r.method != "dense").count(),
        seconds: spread(
            &analysed
                .iter()
                .map(|r| (r.seed, r.seconds))
                .collect::<Vec<_>>(),
        ),
        compared: compared.len(),
        dense_difference: spread(
            &compared
                .iter()
                .map(|r| (r.seed, r.dense_difference))
                .collect::<Vec<_>>(),
        ),
        mismatched: compared
            .iter()
            .filter(|r| r.dense_difference.is_nan() || r.dense_difference > 1e-6)
            .map(|r| r.seed)
            .collect(),
        speedup_median: speedups
            .get(speedups.len() / 2)
            .copied()
            .unwrap_or(f64::NAN),
        wall_seconds: clock.elapsed().as_secs_f64(),
    };
    let mut points: Vec<(f64, f64, usize)> = analysed
        .iter()
        .map(|r| {
            let class = usize::from(r.method == "dense");
            (r.part_dofs as f64, r.seconds, class)
        })
        .collect();
    points.extend(
        compared
            .iter()
            .map(|r| (r.part_dofs as f64, r.dense_seconds, 2)),
    );
    crate::plots::class_scatter(
        &out.join("critical_corpus_time.png"),
        &format!(
            "Critical speeds of {} corpus BHAs: time per well against the eigenproblem's size",
            summary.analysed
        ),
        "degrees of freedom of the BHA part",
        "wall time (s)",
        &points,
        &[
            "Krylov (shift-invert block Lanczos)",
            "dense (small part)",
            "dense oracle, same well",
        ],
    )?;
    let json = serde_json::to_vec_pretty(&summary)?;
    crate::output::write_atomic(&out.join("summary.json"), &json)?;
    Ok(summary)
}
