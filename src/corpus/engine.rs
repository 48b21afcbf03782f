//! A corpus well through the ensemble engine (the kernels' twins, the GPU in f64 or f32), for
//! `bench corpus --engine-sample`. Split from `corpus.rs` (issue 24: no file over 800
//! lines), behaviour unchanged.

use super::*;

/// Which engine path [`run_well_engine`] takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EnginePath {
    /// The kernels' CPU twins (f64).
    Twin,
    /// The WGSL kernels in f64.
    GpuF64,
    /// The WGSL kernels in f32.
    GpuF32,
}

/// One well through the ensemble engine (a chunk of one variant).
#[derive(Clone, Debug, Serialize)]
pub struct EngineOutcome {
    /// Seed of the well.
    pub seed: u64,
    /// Path.
    pub path: EnginePath,
    /// Converged at full load.
    pub solved: bool,
    /// Newton iterations over all steps.
    pub iterations: usize,
    /// Load-step cuts and stage changes.
    pub step_cuts: usize,
    /// Wall time (s).
    pub seconds: f64,
    /// Engine hook load (N).
    pub hook_load_n: f64,
    /// Why it failed (empty when solved).
    pub error: String,
}

/// Solves a corpus well through the ensemble engine on `path` (the same load path and
/// Newton as the CPU solve, [`crate::solve::continuation`]). `Err` where the path cannot
/// run here (no adapter, no f64).
pub fn run_well_engine(well: &CorpusWell, path: EnginePath) -> Result<EngineOutcome, Error> {
    use crate::engine::{solve_static_ensemble, EngineStatus, TwinPath};
    use crate::gpu::GpuPath;
    let case = crate::case::load_case(&well.case_path)?;
    let models = [case.model.clone()];
    let options = crate::solve::statics::StaticOptions::default();
    let clock = std::time::Instant::now();
    let results = match path {
        EnginePath::Twin => solve_static_ensemble(&models, &TwinPath, &options)?,
        EnginePath::GpuF64 | EnginePath::GpuF32 => {
            let ctx = crate::gpu::context::GpuContext::shared()?;
            if path == EnginePath::GpuF64 {
                if !ctx.has_f64 {
                    return Err(crate::error::GpuError::Unsupported(format!(
                        "{} has no f64 in shaders",
                        ctx.describe()
                    ))
                    .into());
                }
                solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options)?
            } else {
                solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options)?
            }
        }
    };
    let seconds = clock.elapsed().as_secs_f64();
    let r = results
        .into_iter()
        .next()
        .ok_or_else(|| Error::failed("the engine returned no result"))?;
    let (solved, error) = match &r.status {
        EngineStatus::Converged => (true, String::new()),
        EngineStatus::Failed(why) => (false, why.clone()),
    };
    let hook_load_n = if solved {
        let sol = crate::solve::statics::solution_at(&case.model, r.state.clone());
        crate::profile::fe_rows(&case.model, &sol).1
    } else {
        f64::NAN
    };
    Ok(EngineOutcome {
        seed: well.spec.seed,
        path,
        solved,
        iterations: r.iterations.iter().sum(),
        step_cuts: r.log.len(),
        seconds,
        hook_load_n,
        error,
    })
}
