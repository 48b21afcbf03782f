//! `holewall run CASE --out DIR`: a dynamic run ([`crate::run`]) into a checked output
//! folder, its notices on stderr.

use std::path::Path;

use crate::case::load_case;
use crate::error::Error;
use crate::output::RunFolder;
pub use crate::run::{RunOptions, RunSummary, SiteWhirl};

/// Runs the command.
pub fn run(case_path: &Path, out: &Path, options: RunOptions) -> Result<RunSummary, Error> {
    let case = load_case(case_path)?;
    super::print_warnings(&case);
    let folder = RunFolder::prepare(out)?.with_report("run", case_path);
    let summary = crate::run::run_case(&case, folder.path(), options)?;
    folder.finish(&crate::run::summary_json(&summary)?)?;
    print_notices(&summary);
    Ok(summary)
}

/// A run's notices on stderr: the budget spent, whirl read off a window that is not at
/// steady state.
pub fn print_notices(summary: &RunSummary) {
    if let Some(why) = &summary.stopped_early {
        eprintln!("holewall: {why}; the outputs cover the time simulated");
    }
    for w in &summary.whirl {
        for n in &w.notes {
            eprintln!("holewall: note: {}: {n}", w.stabilizer);
        }
    }
    for n in &summary.analysis_notes {
        eprintln!("holewall: note: {n}");
    }
}
