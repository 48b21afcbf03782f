//! The commands behind the `holewall` binary (argument parsing stays in `src/main.rs`).

pub mod bench;
pub mod bench_calibrate;
pub mod bench_cmd;
pub mod bench_corpus;
pub mod bench_critical;
pub mod bench_device;
pub mod bench_dynamic_corpus;
pub mod bench_ensemble;
pub mod bench_job;
pub mod bench_kernels;
pub mod bench_mc_corpus;
pub mod bench_specialisation;
pub mod calibrate_cmd;
pub mod contact;
pub mod critical_cmd;
pub mod ensemble_cmd;
pub mod gpu_info;
pub mod run_cmd;
pub mod static_cmd;
pub mod tendency_cmd;

/// Prints a case's warnings ([`crate::case::Case::warnings`]) on stderr, one a line.
pub fn print_warnings(case: &crate::case::Case) {
    for w in &case.warnings {
        eprintln!("holewall: warning: {w}");
    }
}
