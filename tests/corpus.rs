//! The corpus of ordinary wells (issue 22) in CI: the first 50 seeds of
//! `holewall bench corpus` (500 wells there), solved on the CPU, and the smallest of them
//! through the ensemble engine (CPU twins, GPU f64 and f32).
//!
//! What fails here is a result, not noise: the count of solved wells may only rise (raise
//! `SOLVED_AT_LEAST` with the solver), and every solved well must agree with the soft string
//! on the hook load as a stiff string does.

mod common;

use holewall::corpus::{run_well, run_well_engine, write_well, EnginePath, WellResult};

/// Solved of the first 50 seeds, measured when the test was written (46 of 50 with the
/// prestressed start and 200 Newton iterations per step; 42 with 100, the old start at
/// 40 iterations solved fewer).
const SOLVED_AT_LEAST: usize = 46;
const WELLS: u64 = 50;

fn corpus() -> (
    tempdir::Dir,
    Vec<(holewall::corpus::CorpusWell, WellResult)>,
) {
    let dir = tempdir::Dir::new("corpus");
    let rows = (0..WELLS)
        .map(|seed| {
            let well = write_well(seed, dir.path()).unwrap_or_else(|e| {
                panic!("seed {seed}: the generator wrote a case the parser refuses: {e}")
            });
            let r = run_well(&well, &Default::default()).unwrap();
            (well, r)
        })
        .collect();
    (dir, rows)
}

/// A folder removed when dropped.
mod tempdir {
    pub struct Dir(std::path::PathBuf);
    impl Dir {
        pub fn new(name: &str) -> Dir {
            let p = std::env::temp_dir().join(format!("holewall_{name}_{}", std::process::id()));
            std::fs::create_dir_all(&p).unwrap();
            Dir(p)
        }
        pub fn path(&self) -> &std::path::Path {
            &self.0
        }
    }
    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

#[test]
fn corpus_sample_solves_and_agrees_with_the_soft_string() {
    let (_dir, rows) = corpus();
    let mut solved = 0;
    for (_, r) in &rows {
        let s = &r.spec;
        eprintln!(
            "seed {:>3} {:<14} {:<12} {:>5} m, {:>4}/{:<4} m elements, {:>5} nodes: {} in {:.2} s, {} its, {} cuts, hook FE/soft {:.3}, torque {:.3} {}",
            s.seed,
            s.trajectory.name(),
            s.mode,
            s.total_md,
            s.element_m,
            s.bha_element_m,
            r.nodes,
            if r.solved { "solved" } else { "FAILED" },
            r.seconds,
            r.iterations,
            r.step_cuts,
            r.hook_load_ratio,
            r.torque_ratio,
            r.error.lines().next().unwrap_or_default()
        );
        if !r.solved {
            // A failure must say where and what to change.
            assert!(
                r.error.contains("MD") && !r.error.contains("0.0 % of 0.0 kN"),
                "seed {}: {}",
                s.seed,
                r.error
            );
            continue;
        }
        solved += 1;
        // A stiff string carries the hook load a cable does, to a few per cent (side forces
        // differ where the pipe spans a bend; the wells agreed within 2.2 %).
        assert!(
            (0.93..=1.07).contains(&r.hook_load_ratio),
            "seed {}: FE/soft-string hook load {}",
            s.seed,
            r.hook_load_ratio
        );
        // Torque: in a deviated hole (the pipe on the wall along most of its length) within
        // 40 %; near-vertical holes touch the wall only at survey noise, which a soft string
        // counts in full and a stiff string spans.
        if s.max_inclination_deg > 10.0 && r.torque_ratio.is_finite() {
            assert!(
                (0.6..=1.4).contains(&r.torque_ratio),
                "seed {}: FE/soft-string torque {}",
                s.seed,
                r.torque_ratio
            );
        }
    }
    eprintln!("corpus sample: {solved} of {WELLS} solved");
    assert!(
        solved >= SOLVED_AT_LEAST,
        "{solved} of {WELLS} corpus wells solved; {SOLVED_AT_LEAST} did when this was written"
    );
}

#[test]
fn corpus_wells_through_the_engine_match_the_cpu() {
    let dir = tempdir::Dir::new("corpus_engine");
    // The three smallest meshes of the first 50 seeds that the CPU solves: lavapipe runs
    // every kernel on the CPU.
    let mut rows: Vec<_> = (0..WELLS)
        .map(|seed| {
            let well = write_well(seed, dir.path()).unwrap();
            let nodes = holewall::case::load_case(&well.case_path)
                .unwrap()
                .model
                .nodes
                .len();
            (nodes, well)
        })
        .collect();
    rows.sort_by_key(|r| r.0);
    let mut checked = 0;
    for (_, well) in rows {
        let cpu = run_well(&well, &Default::default()).unwrap();
        if !cpu.solved {
            continue;
        }
        let mut paths = vec![EnginePath::Twin];
        if let Some(ctx) = common::gpu() {
            if ctx.has_f64 {
                paths.push(EnginePath::GpuF64);
            }
            paths.push(EnginePath::GpuF32);
        }
        for path in paths {
            let e = run_well_engine(&well, path).unwrap();
            let diff = ((e.hook_load_n - cpu.fe_hook_load_n) / cpu.fe_hook_load_n).abs();
            eprintln!(
                "seed {} {path:?}: solved {} in {} iterations, {} cuts, hook load vs CPU {diff:.2e} {}",
                well.spec.seed, e.solved, e.iterations, e.step_cuts, e.error
            );
            assert!(e.solved, "seed {} {path:?}: {}", well.spec.seed, e.error);
            let tol = if path == EnginePath::GpuF32 {
                1e-4
            } else {
                1e-9
            };
            assert!(
                diff <= tol,
                "seed {} {path:?}: hook load off by {diff:e}",
                well.spec.seed
            );
        }
        checked += 1;
        if checked == 3 {
            break;
        }
    }
    assert_eq!(checked, 3);
}
