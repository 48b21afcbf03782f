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
    /// Pipe-body contact sites kept where the engine's string lies on the wall (as the CPU
    /// run's `wall_sites`).
    pub wall_sites: usize,
    /// Solved by a relaxation that reached its ceiling and shifted the rotations too
    /// ([`crate::solve::continuation::ROTATIONS_SHIFTED`]).
    pub rotations_shifted: bool,
    /// Failed where its load path bracketed where the string stops: the largest load factor
    /// at which the engine found an equilibrium ([`crate::engine::EngineResult::stops`]; the
    /// CPU's is `corpus.csv`'s `fe_reached`); else NaN.
    pub stopped_load_factor: f64,
    /// Hook load (N) of the engine's string where it stands there
    /// ([`crate::engine::EngineResult::stands`]; the CPU's is `corpus.csv`'s
    /// `stopped_hook_load_n`); else NaN.
    pub stopped_hook_load_n: f64,
    /// Why it failed (empty when solved).
    pub error: String,
}

/// Solves a corpus well through the ensemble engine on `path` (the same load path and
/// Newton as the CPU solve, [`crate::solve::continuation`]), held in the hole where it meets
/// the wall by the CPU run's policy ([`crate::profile::solve_in_hole`]'s, each solve of it
/// the engine's): the engine answers on the model the CPU answers on. `Err` where the path
/// cannot run here (no adapter, no f64).
pub fn run_well_engine(well: &CorpusWell, path: EnginePath) -> Result<EngineOutcome, Error> {
    use crate::engine::{solve_static_ensemble, EngineResult, TwinPath};
    use crate::gpu::GpuPath;
    use crate::solve::statics::{StaticError, StaticOptions};
    let case = crate::case::load_case(&well.case_path)?;
    let ctx = match path {
        EnginePath::Twin => None,
        EnginePath::GpuF64 | EnginePath::GpuF32 => {
            let ctx = crate::gpu::context::GpuContext::shared()?;
            if path == EnginePath::GpuF64 && !ctx.has_f64 {
                return Err(crate::error::GpuError::Unsupported(format!(
                    "{} has no f64 in shaders",
                    ctx.describe()
                ))
                .into());
            }
            Some(ctx)
        }
    };
    let engine =
        |m: &crate::model::Model, options: &StaticOptions| -> Result<EngineResult, Error> {
            let models = [m.clone()];
            let results = match (path, ctx) {
                (EnginePath::GpuF64, Some(ctx)) => {
                    solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), options)?
                }
                (EnginePath::GpuF32, Some(ctx)) => {
                    solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), options)?
                }
                _ => solve_static_ensemble(&models, &TwinPath, options)?,
            };
            results
                .into_iter()
                .next()
                .ok_or_else(|| Error::failed("the engine returned no result"))
        };
    let mut model = case.model.clone();
    let (mut iterations, mut step_cuts, mut stopped_load_factor) = (0, 0, f64::NAN);
    let mut unavailable = None;
    let clock = std::time::Instant::now();
    let held = crate::profile::hold_in_hole(
        &case,
        &mut model,
        &mut |m, nodes| crate::profile::add_wall_sites(&case, m, nodes),
        &StaticOptions::default(),
        &mut |m, options| {
            let failed = |reason: String, stopped| StaticError::LoadStep {
                stage: "the engine's solve".into(),
                from: 0.0,
                step: 0.0,
                min: 0.0,
                reason,
                at_md: None,
                stopped,
            };
            match engine(m, options) {
                Ok(mut r) => {
                    iterations += r.iterations.iter().sum::<usize>();
                    step_cuts += r.log.len();
                    stopped_load_factor = r.stops().unwrap_or(f64::NAN);
                    let stands = r.stands.take();
                    r.into_solution(m).map_err(|why| failed(why, stands))
                }
                Err(e) => {
                    // A path that cannot run: no retry can help (the policy retries no
                    // spent budget); the error is returned below.
                    unavailable = Some(e);
                    Err(StaticError::Budget {
                        seconds: 0.0,
                        reached: 0.0,
                    })
                }
            }
        },
    );
    if let Some(e) = unavailable {
        return Err(e);
    }
    let seconds = clock.elapsed().as_secs_f64();
    let stopped_hook_load_n = held
        .as_ref()
        .err()
        .and_then(|e| e.stopped())
        .map_or(f64::NAN, crate::profile::stopped_hook_load);
    let (solved, error, hook_load_n, rotations_shifted) = match held {
        Ok(sol) => (
            true,
            String::new(),
            crate::profile::fe_rows(&model, &sol).1,
            crate::solve::continuation::rotations_shifted(&sol.log),
        ),
        Err(e) => (false, e.to_string(), f64::NAN, false),
    };

    Ok(EngineOutcome {
        seed: well.spec.seed,
        path,
        solved,
        iterations,
        step_cuts,
        seconds,
        hook_load_n,
        wall_sites: model.sites.len() - case.model.sites.len(),
        rotations_shifted,
        stopped_load_factor,
        stopped_hook_load_n,
        error,
    })
}
