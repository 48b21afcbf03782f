//! Running variants: the CPU solvers (rayon over variants, f64) or the kernel engine (GPU,
//! f64 or f32; a variant it fails is re-run on the CPU and says so). The backend itself is
//! chosen by `crate::backend::Backend::resolve_with`, the one policy.

use rayon::prelude::*;

use super::qoi::*;
use crate::backend::Precision;
use crate::case::{Analysis, Case};
use crate::ensemble::{apply, Variant};
use crate::error::{Error, InputError, SystemError};
use crate::model::Model;
use crate::solve::dynamics::{DynamicState, Dynamics};
use crate::solve::statics::StaticState;

/// Static equilibria of every variant through the GPU kernels (in `T`):
/// [`run_static_engine`] on [`crate::gpu::GpuPath`].
pub fn run_static_gpu<T: crate::gpu::contact::GpuReal>(
    case: &Case,
    variants: &[Variant],
    ctx: &'static crate::gpu::GpuContext,
    bar: &indicatif::ProgressBar,
) -> Result<Result<Vec<VariantResult>, SystemError>, Error> {
    run_static_engine::<T, _>(case, variants, &crate::gpu::GpuPath(ctx), bar)
}

/// Static equilibria of every variant through the engine on `path` (in `T`), held in the
/// hole as the CPU holds them (guard sites at every node without one, those in contact kept:
/// `guarded_models`, `crate::profile::keep_touching`); the variants that fail there re-run
/// on the CPU with step control (their reason says so), but for those whose load path
/// stopped where the string does ([`crate::engine::EngineResult::stops`]: failed there, as
/// the CPU fails them). Stabilizer moves run there too (each pair carries its node). `Err`
/// with the reason when the variants do not share the number of sites, or need what only
/// the CPU has: the caller runs the CPU and says why.
pub fn run_static_engine<T, P>(
    case: &Case,
    variants: &[Variant],
    path: &P,
    bar: &indicatif::ProgressBar,
) -> Result<Result<Vec<VariantResult>, SystemError>, Error>
where
    T: crate::physics::Real + Send + Sync,
    P: crate::engine::KernelPath<T>,
{
    use crate::engine::solve_static_ensemble_with_progress;
    let models: Vec<Model> = variants
        .iter()
        .map(|v| apply(case, v))
        .collect::<Result<_, _>>()
        .map_err(Error::failed)?;
    if !models.iter().all(|m| same_mesh(case, m)) {
        return Ok(Err(SystemError::Unsupported(
            "the variants differ in their mesh or number of contact sites".into(),
        )));
    }
    let guarded = match guarded_models(case, variants, &models) {
        Ok(g) => g,
        Err(e) => return Ok(Err(e)),
    };
    let results = solve_static_ensemble_with_progress::<T, _>(
        &guarded,
        path,
        &case.settings().statics(),
        &mut |f| bar.set_position((f * variants.len() as f64) as u64),
    )
    .map_err(|e| Error::failed(format!("GPU engine: {e}")))?;
    Ok(Ok(results
        .into_par_iter()
        .zip(
            models
                .par_iter()
                .zip(guarded.par_iter().zip(variants.par_iter())),
        )
        .map(|(mut r, (m, (g, v)))| (r.stops(), r.stands.take(), r, m, g, v))
        .map(|(stops, stands, r, m, g, v)| match r.into_solution(g) {
            Ok(sol) => {
                // Held in the hole as the CPU holds it: the guards in contact kept.
                let (held, mut sol) = crate::profile::keep_touching(m, g.clone(), sol);
                // The whirl's note, as the CPU solve's log has it (`guarded_models`
                // marked the span's sites).
                crate::profile::note_whirl(&mut sol.log, crate::diagnose::whirl_span(case, m));
                let mut done = static_result(case, &v.name, &held, &sol);
                done.solved_by = SolvedBy::Engine;
                done
            }
            Err(why) => {
                let why = format!("GPU: {why}");
                let stops = stops.map(|at| (at, stands.as_deref()));
                after_engine_failure(case, &v.name, why, m, stops, false, |fs| {
                    static_variant_of(case, v, m, fs)
                })
            }
        })
        .collect()))
}

/// A variant the engine failed (`why`), run again on the CPU (`cpu(find_stop)`: its static
/// solve, or, `dynamic`, its dynamic run from its static start). Where the engine's load
/// path bracketed where the string stops (`stops`: [`crate::engine::EngineResult::stops`],
/// the largest load factor with an equilibrium, and the string there,
/// [`crate::engine::EngineResult::stands`]), the CPU tries the loads once more on its
/// own path but brackets nothing: in another rounding it may reach an equilibrium the
/// engine's path did not (the relaxed user well 0, pushed with 678 kN: the engine stops at
/// 0.906, the CPU solves it in 1.3 s; docs/performance.md, stop 91), and where its static
/// solve fails too, the engine's bracket is the answer (failed there, `solved_by` engine) —
/// a second bracket on the CPU would cost the lock-up's relaxations below the full loads again,
/// 60–65 % of its time there.
fn after_engine_failure(
    case: &Case,
    name: &str,
    why: String,
    model: &Model,
    stops: Option<(f64, Option<&crate::solve::statics::Stopped>)>,
    dynamic: bool,
    cpu: impl FnOnce(bool) -> VariantResult,
) -> VariantResult {
    let mut again = cpu(stops.is_none());
    match stops {
        // The static solve (or the dynamic run's static start) failed on the CPU too.
        Some((at, stands))
            if again.status == Status::Failed
                && (!dynamic || again.reason.starts_with(STATIC_START)) =>
        {
            let why = format!(
                "{why}; run again on the CPU without a bracket of its own, it failed there too: {}",
                again.reason
            );
            let stabs = model.stabilizer_sites().len();
            let mut r = failed_stopping(case, name, why, stabs, Some((at, stands)));
            r.solved_by = SolvedBy::Engine;
            r
        }
        _ => {
            again.reason = format!("{why}; re-run on the CPU: {}", again.reason);
            again
        }
    }
}

/// The `[dynamics]` runs of every variant through the GPU engine (in `T`): static starts
/// through the static engine, then lockstep generalised-α steps, every step observed for
/// the quantities of interest. Each static start is held in the hole as the CPU holds it
/// (guards at every node without a site, those in contact kept), and a variant that kept
/// sites runs on the engine with them (`wall_batch`). A variant that fails on the GPU
/// (static start or a step)
/// re-runs on the CPU with step control (its reason says so). `Err` with the reason when
/// the case needs what only the CPU integrator has (consistent mass, stiffness-
/// proportional damping): the caller runs the CPU then.
pub fn run_dynamic_gpu<T: crate::gpu::contact::GpuReal>(
    case: &Case,
    variants: &[Variant],
    ctx: &'static crate::gpu::GpuContext,
    bar: &indicatif::ProgressBar,
) -> Result<Result<Vec<VariantResult>, SystemError>, Error> {
    use crate::engine::dynamic::{run_dynamic_ensemble, unsupported, DynamicStatus};
    use crate::engine::{solve_static_ensemble, EngineStatus};
    use crate::gpu::GpuPath;
    let Some(settings) = case.dynamics.clone() else {
        return Ok(Err(SystemError::Unsupported("no [dynamics] table".into())));
    };
    let options = case.settings().dynamics();
    if let Some(why) = unsupported(&options) {
        return Ok(Err(SystemError::Unsupported(why)));
    }
    let models: Vec<Model> = variants
        .iter()
        .map(|v| apply(case, v))
        .collect::<Result<_, _>>()
        .map_err(Error::failed)?;
    if !models.iter().all(|m| same_mesh(case, m)) {
        return Ok(Err(SystemError::Unsupported(
            "the variants differ in their mesh or number of contact sites".into(),
        )));
    }
    let guarded = match guarded_models(case, variants, &models) {
        Ok(g) => g,
        Err(e) => return Ok(Err(e)),
    };
    let path = GpuPath(ctx);
    let starts_clock = std::time::Instant::now();
    let statics = solve_static_ensemble::<T, _>(&guarded, &path, &case.settings().statics())
        .map_err(|e| Error::failed(format!("GPU engine: {e}")))?;
    // Each variant's static start held in the hole as the CPU run holds it (the guards in
    // contact kept, with the variant's overrides); one whose start failed on the GPU runs
    // wholly on the CPU.
    let held: Vec<Option<Model>> = statics
        .par_iter()
        .zip(models.par_iter().zip(guarded.par_iter()))
        .map(|(r, (m, g))| match r.status {
            EngineStatus::Converged => {
                let sol = crate::solve::statics::solution_at(g, r.state.clone());
                Some(crate::profile::keep_touching(m, g.clone(), sol).0)
            }
            EngineStatus::Failed(_) => None,
        })
        .collect();
    crate::tally::add_phase(crate::tally::Phase::StaticStarts, starts_clock.elapsed());
    let on_gpu: Vec<usize> = (0..models.len()).filter(|&j| held[j].is_some()).collect();
    // Each variant's own model (with the sites kept at the wall) and start.
    let (gpu_models, static_starts): (Vec<Model>, Vec<StaticState>) = on_gpu
        .iter()
        .map(|&j| {
            let m = held[j].clone().expect("on the GPU: held");
            (m, statics[j].state.clone())
        })
        .unzip();
    // The case's initial offset and kick on each static equilibrium, as the CPU runs do.
    let starts: Vec<_> = gpu_models
        .iter()
        .zip(static_starts)
        .map(|(m, state)| case.dynamic_start(m, state))
        .collect();
    let batch_models = wall_batch(case, variants, &on_gpu, &models, &gpu_models)?;
    let density = &case.element_density;
    let mut cpu: Vec<Dynamics> = gpu_models
        .iter()
        .map(|m| Dynamics::new(m, options, &|e| density[e]))
        .collect();
    let mut observers: Vec<DynamicObserver> = gpu_models
        .iter()
        .map(|m| DynamicObserver::new(m, settings.duration))
        .collect();
    let mut last: Vec<Option<DynamicState>> = vec![None; gpu_models.len()];
    // Each variant's initial state and first observation, in parallel (each its own).
    cpu.par_iter_mut()
        .zip(starts.par_iter())
        .zip(observers.par_iter_mut().zip(last.par_iter_mut()))
        .zip(gpu_models.par_iter())
        .for_each(|(((d, (q, vel)), (observer, last)), m)| {
            if let Ok(s) = d.initial_state_with(q.clone(), vel.clone()) {
                observer.observe(m, d, &s);
                *last = Some(s);
            }
        });
    // None left for the engine: every variant runs on the CPU below.
    let dynamics_clock = std::time::Instant::now();
    let results = if gpu_models.is_empty() {
        Vec::new()
    } else {
        run_dynamic_ensemble::<T, _>(
            &batch_models,
            &starts,
            density,
            &path,
            &options,
            settings.duration,
            1,
            &mut |first, t, batch| {
                let observing = std::time::Instant::now();
                let (v, n) = (batch.num_variants, batch.num_nodes);
                // Every variant of the batch observed in parallel: each reads its own
                // column of the variant-fastest state and writes its own observer.
                let range = first..first + v;
                last[range.clone()]
                    .par_iter_mut()
                    .zip(observers[range.clone()].par_iter_mut())
                    .zip(gpu_models[range.clone()].par_iter().zip(&cpu[range]))
                    .enumerate()
                    .for_each(|(j, ((state, observer), (m, d)))| {
                        let Some(state) = state.as_mut() else {
                            return;
                        };
                        state.t = t;
                        for i in 0..n {
                            for k in 0..3 {
                                state.q.u[i][k] = batch.u[(3 * i + k) * v + j].to_f64_lossy();
                            }
                            for r in 0..3 {
                                for c in 0..3 {
                                    state.q.rot[i][r][c] =
                                        batch.rot[(9 * i + 3 * r + c) * v + j].to_f64_lossy();
                                }
                            }
                            for k in 0..6 {
                                let idx = (6 * i + k) * v + j;
                                state.v[6 * i + k] = batch.vel[idx].to_f64_lossy();
                                state.a[6 * i + k] = batch.acc[idx].to_f64_lossy();
                                state.vdot[6 * i + k] = batch.vdot[idx].to_f64_lossy();
                            }
                        }
                        observer.observe(m, d, state);
                    });
                bar.set_position(((t / settings.duration) * variants.len() as f64) as u64);
                crate::tally::add_phase(crate::tally::Phase::Observing, observing.elapsed());
            },
        )
        .map_err(|e| Error::failed(format!("GPU engine: {e}")))?
    };
    crate::tally::add_phase(crate::tally::Phase::Dynamics, dynamics_clock.elapsed());
    let mut out: Vec<Option<VariantResult>> = vec![None; models.len()];
    for (&j, ((r, obs), state)) in on_gpu
        .iter()
        .zip(results.into_iter().zip(observers).zip(last))
    {
        let name = &variants[j].name;
        out[j] = Some(match (r.status, state) {
            (DynamicStatus::Finished, Some(state)) => {
                // The engine's step cuts, as the CPU integrator's log would give them.
                let model = held[j].as_ref().unwrap_or(&models[j]);
                let mut done = obs.finish(case, name, model, &state, &r.log, &r.iterations);
                done.solved_by = SolvedBy::Engine;
                done.string.relaxed = Some(crate::solve::continuation::relaxed(&statics[j].log));
                let kept = model.sites.len() - models[j].sites.len();
                if kept > 0 {
                    done.reason = format!(
                        "static start held where the string met the wall between the contact \
                         sites ({kept} sites kept); dynamics on the engine{}",
                        if done.reason.is_empty() {
                            String::new()
                        } else {
                            format!("; {}", done.reason)
                        }
                    );
                }
                done
            }
            (status, _) => {
                let why = match status {
                    DynamicStatus::Failed(t, why) => format!("failed at t = {t:.6} s: {why}"),
                    DynamicStatus::Finished => "no initial state".into(),
                };
                let why = format!("GPU: {why}");
                after_engine_failure(case, name, why, &models[j], None, true, |fs| {
                    dynamic_variant_of(case, &variants[j], &models[j], fs)
                })
            }
        });
    }
    Ok(Ok(out
        .into_iter()
        .enumerate()
        .map(|(j, r)| {
            r.unwrap_or_else(|| {
                let why = match &statics[j].status {
                    EngineStatus::Failed(w) => w.clone(),
                    // Not reached: a converged start is held and runs on the engine.
                    EngineStatus::Converged => "not run on the engine".into(),
                };
                after_engine_failure(
                    case,
                    &variants[j].name,
                    format!("GPU static start: {why}"),
                    &models[j],
                    statics[j]
                        .stops()
                        .map(|at| (at, statics[j].stands.as_deref())),
                    true,
                    |fs| dynamic_variant_of(case, &variants[j], &models[j], fs),
                )
            })
        })
        .collect()))
}

/// The models the engine solves for `variants` (`own`: each variant's model): each with a
/// guard site at every node it has none at, with the variant's overrides, as
/// [`crate::profile::solve_in_hole`] solves a model on the CPU (its answer then kept by
/// `crate::profile::keep_touching`); `own` where every node has a site. `Err` where the
/// guarded models do not share a mesh (the caller runs the CPU).
fn guarded_models(
    case: &Case,
    variants: &[Variant],
    own: &[Model],
) -> Result<Vec<Model>, SystemError> {
    let guarded: Vec<Model> = variants
        .iter()
        .zip(own)
        .map(|(v, m)| {
            let free = crate::profile::unheld_nodes(m);
            if free.is_empty() {
                Ok(m.clone())
            } else {
                crate::ensemble::apply_with_sites(case, v, &free)
            }
        })
        .collect::<Result<_, _>>()
        .map_err(|e| SystemError::Unsupported(format!("variant: {e}")))?;
    // A turning string that whirls, at the whirl's average, as the CPU solve takes it
    // (`profile::hold_in_hole`).
    let mut guarded = guarded;
    for g in &mut guarded {
        crate::diagnose::mark_whirling_sites(case, g);
    }
    crate::engine::check_same_mesh(&guarded)?;
    Ok(guarded)
}

/// Runs every variant on the CPU (rayon over variants); results in variant order.
pub fn run_variants_cpu(
    case: &Case,
    analysis: Analysis,
    variants: &[Variant],
    bar: &indicatif::ProgressBar,
) -> Vec<VariantResult> {
    variants
        .par_iter()
        .map(|v| {
            let stabs = case.model.stabilizer_sites().len();
            let r = match apply(case, v) {
                Err(e) => failed(&v.name, format!("variant: {e}"), stabs),
                Ok(model) => match analysis {
                    Analysis::Static => static_variant_of(case, v, &model, true),
                    Analysis::Dynamic => dynamic_variant_of(case, v, &model, true),
                },
            };
            bar.inc(1);
            r
        })
        .collect()
}

/// Runs `variants` on the GPU engine (`gpu`) or the CPU: their results, where they ran,
/// and why on the CPU when the engine was chosen but could not take them.
pub(crate) fn compute(
    case: &Case,
    analysis: Analysis,
    variants: &[Variant],
    gpu: Option<&'static crate::gpu::GpuContext>,
    precision: Precision,
    bar: &indicatif::ProgressBar,
) -> Result<(Vec<VariantResult>, &'static str, Option<String>), Error> {
    let mut backend_name = "cpu";
    let mut note = None;
    let results = match (gpu, analysis) {
        (Some(ctx), Analysis::Static) => match if precision == Precision::F32 {
            run_static_gpu::<f32>(case, variants, ctx, bar)?
        } else {
            run_static_gpu::<f64>(case, variants, ctx, bar)?
        } {
            Ok(r) => {
                backend_name = "gpu";
                r
            }
            Err(why) => {
                note = Some(format!("{why}: run on the CPU"));
                run_variants_cpu(case, analysis, variants, bar)
            }
        },
        (Some(ctx), Analysis::Dynamic) => match if precision == Precision::F32 {
            run_dynamic_gpu::<f32>(case, variants, ctx, bar)?
        } else {
            run_dynamic_gpu::<f64>(case, variants, ctx, bar)?
        } {
            Ok(r) => {
                backend_name = "gpu";
                r
            }
            Err(why) => {
                if precision == Precision::F32 {
                    return Err(InputError {
                        source_name: "--precision".into(),
                        line: 0,
                        key: "precision".into(),
                        message: format!("f32 runs on the GPU engine, which cannot run this case: {why}; use --precision f64"),
                    }
                    .into());
                }
                note = Some(format!("{why}: run on the CPU"));
                run_variants_cpu(case, analysis, variants, bar)
            }
        },
        (None, _) => run_variants_cpu(case, analysis, variants, bar),
    };
    Ok((results, backend_name, note))
}

/// Whether a variant's model shares the case's mesh and number of contact sites (what the
/// engine needs: a `depth` variant has a mesh of its own).
pub(crate) fn same_mesh(case: &Case, m: &Model) -> bool {
    m.sites.len() == case.model.sites.len()
        && m.nodes.len() == case.model.nodes.len()
        && m.nodes
            .iter()
            .zip(&case.model.nodes)
            .all(|(a, b)| a.md == b.md)
}

/// A site the batch holds for another variant: a clearance no string reaches, so it never
/// touches the wall and adds nothing — as if the variant had no site there (m).
pub const ABSENT_SITE_CLEARANCE: f64 = 1e3;

/// The models the dynamic engine runs for the variants `on_gpu` (their own models
/// `own`, with the sites each static start added where it met the wall): one set of sites
/// for the batch — the case's and every variant's added ones, each with the variant's
/// overrides ([`crate::ensemble::apply_with_sites`]) — where a variant's sites that are not
/// its own lie beyond any wall ([`ABSENT_SITE_CLEARANCE`]). No site added: the own models.
fn wall_batch(
    case: &Case,
    variants: &[Variant],
    on_gpu: &[usize],
    models: &[Model],
    own: &[Model],
) -> Result<Vec<Model>, Error> {
    let nodes_of = |m: &Model| {
        m.sites
            .iter()
            .map(|s| s.node)
            .collect::<std::collections::BTreeSet<_>>()
    };
    let mut added = std::collections::BTreeSet::new();
    for (&j, m) in on_gpu.iter().zip(own) {
        added.extend(nodes_of(m).difference(&nodes_of(&models[j])).copied());
    }
    if added.is_empty() {
        return Ok(own.to_vec());
    }
    let added: Vec<usize> = added.into_iter().collect();
    on_gpu
        .iter()
        .zip(own)
        .map(|(&j, m)| {
            let mine = nodes_of(m);
            let mut batch = crate::ensemble::apply_with_sites(case, &variants[j], &added)
                .map_err(Error::failed)?;
            for site in &mut batch.sites {
                if !mine.contains(&site.node) {
                    site.params.clearance = ABSENT_SITE_CLEARANCE;
                }
            }
            Ok(batch)
        })
        .collect()
}
