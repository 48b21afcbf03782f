//! The dynamic ensemble through the kernels: generalised-α steps of V variants in
//! lockstep (as [`crate::solve::dynamics::Dynamics::step`], lumped mass), each Newton
//! iteration made of the predictor, beam, sites, contact, dynamic assembly, block LU and
//! norms kernels, and the per-variant residual line search of the CPU integrator.
//!
//! Every variant takes the same steps of `h` through the one Newton
//! ([`crate::solve::newton`], dynamics settings). A variant whose Newton fails at a step
//! (non-finite residual, singular matrix, no convergence in the iterations) is taken back
//! and re-tried on its own in half steps, recursively down to `min_dt`, while the others
//! wait ([`run_dynamic_ensemble`]); only below `min_dt` does it fail, as the CPU
//! integrator would. Within a step, each Newton iteration and line-search trial works on the
//! variants still iterating (searching) alone. No kernel mixes variants: the others are
//! unaffected, bit for bit.
//!
//! Supported: lumped mass, mass-proportional Rayleigh damping (`a0`), the table's spin and
//! the hook's travel at the top, every contact law. Not here (the caller runs those on the
//! CPU): consistent mass and stiffness-proportional damping (`a1`, which needs the initial
//! tangent per variant), and load factors in time.

use crate::kernels::block_lu::{block_lu, ChainBatch};
use crate::kernels::contact::ContactBatch;
use crate::kernels::dynamics::{
    accelerate, inertial_scale, predict, DynamicBatch, StepCoefficients, TOP_LEN,
};
use crate::kernels::update::{norms, Norms};
use crate::model::Model;
use crate::physics::contact::{ContactMode, PARAMS_LEN};
use crate::physics::mass::MassKind;
use crate::physics::Real;
use crate::solve::dynamics::{control, DynamicOptions, Dynamics};
use crate::solve::statics::StaticState;

use super::{columns, ensemble_tables_from, variant_fastest, BatchTables, KernelPath, TwinPath};
use crate::solve::newton::{Event, Newton, NewtonSettings};

mod step;
mod twin;
use step::DynamicStep;
pub use twin::{options_coefficients, TwinDynamic};

/// What a dynamic batch adds to [`BatchTables`].
#[derive(Clone, Debug)]
pub struct DynamicTables<T> {
    /// Lumped nodal mass, `n` (shared: the variants share the mesh and densities).
    pub mass: Vec<T>,
    /// Rotary inertia per node (reference orientation, global axes, row-major), `9 n`.
    pub inertia0: Vec<T>,
    /// Rayleigh's mass factor `a0`.
    pub a0: f64,
    /// External loads per variant, `6 n V` (constant in time).
    pub f_ext: Vec<T>,
    /// Law parameters per pair, `PARAMS_LEN · P`.
    pub pair_params: Vec<T>,
    /// Mass imbalance per node and variant at the reference orientation (kg·m), `3 n V`
    /// ([`Model::unbalance`]); empty when no variant has one (the assembly is then built
    /// without it).
    pub unbalance: Vec<T>,
    /// The state at t = 0 (displacements from the base, [`BatchTables::base`]: each
    /// variant's static equilibrium).
    pub start: DynamicBatch<T>,
}

/// What one Newton iteration reports per variant.
#[derive(Clone, Debug)]
pub struct Iteration<T> {
    /// Norms of the residual and the correction `Δ` (α = 1).
    pub norms: Norms<T>,
    /// The block solve's status.
    pub status: Vec<u32>,
    /// The inertial force scale `max_i m_i |v̇_u,i|`.
    pub inertial: Vec<T>,
    /// Where the path forms it with the iteration (no round trip of its own): the first
    /// line-search trial, at α = 1 for the variants iterating and 0 for the others, as
    /// [`crate::engine::ResidentTrials::trial`] with `first` would form it — its norms, read for those
    /// iterating.
    pub full_step: Option<Norms<T>>,
}

/// A batch of variants held by a kernel path for a dynamic run: the state at `t_n`, the
/// Newton unknown `v̇_{n+1}`, a trial state and its system.
pub trait ResidentDynamic<T>: crate::engine::ResidentTrials<T> {
    /// Starts a step: its coefficients and the top's kinematics per variant
    /// (`TOP_LEN · V`); the unknown starts at `v̇_n`.
    fn begin_step(
        &mut self,
        c: &StepCoefficients<T>,
        top: &[T],
    ) -> Result<(), crate::error::SystemError>;
    /// Predicts at the unknown, evaluates and solves: the norms of the residual and the
    /// correction `Δ` (α = 1), the solve's status and the inertial force scale per variant,
    /// read for the variants `running` (a path may work on those alone: the others have
    /// converged or failed, and their unknowns stay as they are).
    fn iterate(&mut self, running: &[bool]) -> Result<Iteration<T>, crate::error::SystemError>;
    /// The unknown `+= α Δ`.
    fn correct(&mut self, alpha: &[T]) -> Result<(), crate::error::SystemError>;
    /// The unknown becomes the last trial's candidate (a trial forms its residual only:
    /// the next [`ResidentDynamic::iterate`] evaluates the candidate's system).
    fn accept_trial(&mut self) -> Result<(), crate::error::SystemError>;
    /// Ends the step: the state at `t_{n+1}` from the unknown.
    fn end_step(&mut self) -> Result<(), crate::error::SystemError>;
    /// The state, read back.
    fn state(&mut self) -> Result<DynamicBatch<T>, crate::error::SystemError>;
    /// Replaces the state at `t_n` (between steps).
    fn set_state(&mut self, state: &DynamicBatch<T>) -> Result<(), crate::error::SystemError>;
}

/// How a variant's dynamic run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum DynamicStatus {
    /// Reached the end time.
    Finished,
    /// Failed at time `t`: why.
    Failed(f64, String),
}

/// Why a set of models cannot run on the dynamic engine, if it cannot.
pub fn unsupported(options: &DynamicOptions) -> Option<String> {
    if options.mass == MassKind::Consistent {
        return Some("consistent mass runs on the CPU integrator".into());
    }
    if options.rayleigh.1 != 0.0 {
        return Some("stiffness-proportional Rayleigh damping runs on the CPU integrator".into());
    }
    if options.load_factor.is_some() {
        return Some("load factors in time run on the CPU integrator".into());
    }
    None
}

/// A batch's start: its tables, each variant's force scale, and what moves the top.
struct Start<T> {
    tables: DynamicTables<T>,
    /// The base: each variant's static equilibrium ([`BatchTables::base`]).
    base: Vec<f64>,
    f_ref: Vec<f64>,
    driven: bool,
    lowered: bool,
}

/// A variant's start: its configuration (the static equilibrium, or that with the case's
/// initial offset: `crate::case::Case::dynamic_start`) and initial velocities (6 per node;
/// `None`: at rest).
pub type DynamicStart = (StaticState, Option<Vec<f64>>);

/// The start of every variant: the CPU integrator's initial state (consistent
/// accelerations) from its start configuration and velocities, its force scale, and the
/// integrator set up for it (the batch's top drive).
fn dynamic_tables<'a, T: Real>(
    models: &'a [Model],
    starts: &[DynamicStart],
    density: &[f64],
    options: &DynamicOptions,
) -> Result<(Start<T>, Vec<Dynamics<'a>>), crate::error::SystemError> {
    let t = |x: f64| T::from_f64_lossy(x);
    let (v, n) = (models.len(), models[0].nodes.len());
    let s_count = models[0].sites.len();
    // Each variant's consistent initial state (a solve with its mass), in parallel: on the
    // host, before any kernel, this was the largest serial part of a large batch (issue 27).
    use rayon::prelude::*;
    type Initial<'a> = (
        Dynamics<'a>,
        crate::solve::dynamics::DynamicState,
        Vec<f64>,
        Vec<[f64; PARAMS_LEN]>,
    );
    let initial: Vec<Initial<'a>> = models
        .par_iter()
        .zip(starts)
        .map(|(m, (q, vel))| {
            let mut d = Dynamics::new(m, *options, &|e| density[e]);
            let s = d.initial_state_with(q.clone(), vel.clone()).map_err(|e| {
                crate::error::SystemError::Linear(format!("the initial state: {e}"))
            })?;
            let loads = crate::solve::statics::external_loads(m);
            let params = m.sites.iter().map(|x| x.params.to_array()).collect();
            Ok((d, s, loads, params))
        })
        .collect::<Result<_, crate::error::SystemError>>()?;
    // The tables, variant-fastest, filled a node (or a field) at a time in parallel.
    let from_reference = |i: usize, k: usize, j: usize| initial[j].1.q.u[i][k];
    // The base: each node's start, the top's reference (its motion is the top drive's).
    let base = variant_fastest(3 * n, v, 3, |r, j| {
        if r < 3 {
            0.0
        } else {
            from_reference(r / 3, r % 3, j)
        }
    });
    let state =
        |rows: usize, f: &(dyn Fn(&crate::solve::dynamics::DynamicState, usize) -> f64 + Sync)| {
            variant_fastest(rows, v, rows / n, |r, j| t(f(&initial[j].1, r)))
        };
    let start = DynamicBatch {
        num_variants: v,
        num_nodes: n,
        u: variant_fastest(3 * n, v, 3, |r, j| {
            t(from_reference(r / 3, r % 3, j) - base[r * v + j])
        }),
        rot: state(9 * n, &|s, r| s.q.rot[r / 9][(r % 9) / 3][r % 3]),
        vel: state(6 * n, &|s, r| s.v[r]),
        acc: state(6 * n, &|s, r| s.a[r]),
        vdot: state(6 * n, &|s, r| s.vdot[r]),
    };
    let f_ext = variant_fastest(6 * n, v, 6, |r, j| t(initial[j].2[r]));
    // Law parameters per pair, field-major: row `f S + k` is field f of site k.
    let pair_params = variant_fastest(PARAMS_LEN * s_count, v, s_count, |r, j| {
        t(initial[j].3[r % s_count][r / s_count])
    });
    let unbalance = if models.iter().any(Model::has_unbalance) {
        variant_fastest(3 * n, v, 3, |r, j| {
            models[j]
                .unbalance
                .get(r / 3)
                .map_or(T::zero(), |u| t(u[r % 3]))
        })
    } else {
        Vec::new()
    };
    let d0 = &initial[0].0;
    let (ms, js) = d0.lumped();
    let top = d0.top_motion();
    let tables = DynamicTables {
        mass: ms.iter().map(|&x| t(x)).collect(),
        inertia0: js.iter().flatten().flatten().map(|&x| t(x)).collect(),
        a0: options.rayleigh.0,
        f_ext,
        pair_params,
        unbalance,
        start,
    };
    let f_ref = initial.iter().map(|x| x.0.reference_force()).collect();
    let drives = initial.into_iter().map(|x| x.0).collect();
    let start = Start {
        tables,
        base,
        f_ref,
        driven: top.0,
        lowered: top.1,
    };
    Ok((start, drives))
}

/// One variant's dynamic result.
#[derive(Clone, Debug)]
pub struct DynamicResult {
    /// Status.
    pub status: DynamicStatus,
    /// Newton iterations of every step taken (sub-steps included).
    pub iterations: Vec<usize>,
    /// Step cuts, with why.
    pub log: Vec<String>,
}

/// Runs every variant from its start `starts[j]` (configuration and velocities) to `t_end` in steps of
/// `options.dt` on `path`, calling `observe(first_variant, t, state)` for each batch after
/// every `every`-th step (0: never). `density` gives each element's steel density.
///
/// Step control per variant: a variant whose Newton fails on `t → t + h` is taken back to
/// `t` and re-tried alone with the others that failed there — in a batch of their own, in
/// two steps of `h/2` (cut again where those fail, down to `options.min_dt`) — while the
/// rest wait; at `t + h` its state rejoins the batch, which goes on with `h`. So the
/// ensemble stays in lockstep at every step of `h` and no variant needs the CPU integrator
/// unless a step below `min_dt` would be needed there too.
#[allow(clippy::too_many_arguments)]
pub fn run_dynamic_ensemble<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    starts: &[DynamicStart],
    density: &[f64],
    path: &P,
    options: &DynamicOptions,
    t_end: f64,
    every: usize,
    observe: &mut dyn FnMut(usize, f64, &DynamicBatch<T>),
) -> Result<Vec<DynamicResult>, crate::error::SystemError> {
    if let Some(why) = unsupported(options) {
        return Err(crate::error::SystemError::Unsupported(why));
    }
    super::check_same_mesh(models)?;
    let batch = path.max_batch(&models[0]).max(1);
    let mut results = Vec::with_capacity(models.len());
    for (c, (group, group_starts)) in models.chunks(batch).zip(starts.chunks(batch)).enumerate() {
        let first = c * batch;
        let mut obs = |t: f64, s: &DynamicBatch<T>| observe(first, t, s);
        results.extend(run_batch(
            group,
            group_starts,
            density,
            path,
            options,
            t_end,
            every,
            &mut obs,
        )?);
    }
    Ok(results)
}

/// Writes `src` (the columns `pick`, variant-fastest) into `dst` of `v` variants.
fn put_columns<T: Copy>(dst: &mut [T], v: usize, pick: &[usize], src: &[T]) {
    for (row, from) in dst.chunks_exact_mut(v).zip(src.chunks_exact(pick.len())) {
        for (&j, &x) in pick.iter().zip(from) {
            row[j] = x;
        }
    }
}

fn batch_columns<T: Copy>(b: &DynamicBatch<T>, pick: &[usize]) -> DynamicBatch<T> {
    let v = b.num_variants;
    DynamicBatch {
        num_variants: pick.len(),
        num_nodes: b.num_nodes,
        u: columns(&b.u, v, pick),
        rot: columns(&b.rot, v, pick),
        vel: columns(&b.vel, v, pick),
        acc: columns(&b.acc, v, pick),
        vdot: columns(&b.vdot, v, pick),
    }
}

fn put_batch_columns<T: Copy>(dst: &mut DynamicBatch<T>, pick: &[usize], src: &DynamicBatch<T>) {
    let v = dst.num_variants;
    put_columns(&mut dst.u, v, pick, &src.u);
    put_columns(&mut dst.rot, v, pick, &src.rot);
    put_columns(&mut dst.vel, v, pick, &src.vel);
    put_columns(&mut dst.acc, v, pick, &src.acc);
    put_columns(&mut dst.vdot, v, pick, &src.vdot);
}

/// What every span of a batch shares: the batch's tables, per variant its force scale,
/// step floor and top drive, and the outcome so far.
struct Batch<'a, T, P> {
    models: &'a [Model],
    path: &'a P,
    options: &'a DynamicOptions,
    tables: BatchTables<T>,
    dynamic: DynamicTables<T>,
    f_ref: Vec<f64>,
    floors: Vec<f64>,
    driven: bool,
    lowered: bool,
    drives: Vec<Dynamics<'a>>,
    status: Vec<DynamicStatus>,
    /// Per variant its own step: `dt`, or cut and not yet regrown.
    step: Vec<f64>,
    iterations: Vec<Vec<usize>>,
    log: Vec<Vec<String>>,
}

#[allow(clippy::too_many_arguments)]
fn run_batch<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    starts: &[DynamicStart],
    density: &[f64],
    path: &P,
    options: &DynamicOptions,
    t_end: f64,
    every: usize,
    observe: &mut dyn FnMut(f64, &DynamicBatch<T>),
) -> Result<Vec<DynamicResult>, crate::error::SystemError> {
    super::check_same_mesh(models)?;
    let setup = std::time::Instant::now();
    let (
        Start {
            tables: dynamic,
            base,
            f_ref,
            driven,
            lowered,
        },
        drives,
    ) = dynamic_tables::<T>(models, starts, density, options)?;
    // The batch's state is the dynamic start; the static tables need no start of their own.
    let static_start = (dynamic.start.u.clone(), dynamic.start.rot.clone());
    let mut tables = ensemble_tables_from::<T>(models, Some(static_start))?;
    // The contact terms of the dynamic scene (damping where some c > 0).
    let mut batch = ContactBatch::<T>::new(1, tables.pair_node.len());
    batch.pair_params = dynamic.pair_params.clone();
    tables.terms = batch.required_terms(models[0].friction, ContactMode::Dynamic);
    let v = tables.num_variants;
    tables.set_base(&models[0], base);
    let size = std::mem::size_of::<T>();
    // Step floors: f64 from the positions, f32 from the motion off the base.
    // (Row by row: the rows are variant-fastest.)
    let mut largest = vec![0.0f64; v];
    for (k, (row, base)) in dynamic
        .start
        .u
        .chunks_exact(v)
        .zip(tables.base.chunks_exact(v))
        .enumerate()
    {
        for ((m, w), b) in largest.iter_mut().zip(row).zip(base) {
            let w = w.to_f64_lossy();
            let x = if size == 4 {
                w
            } else {
                tables.node_ref[k] + b + w
            };
            *m = m.max(x.abs());
        }
    }
    let floors = largest
        .into_iter()
        .map(|l| NewtonSettings::step_floor(size, l))
        .collect();
    let opening = std::time::Instant::now();
    let mut ensemble = path.open_dynamic(&models[0], &tables, &dynamic)?;
    crate::tally::add_setup(setup.elapsed(), opening.elapsed());
    let mut batch = Batch {
        models,
        path,
        options,
        drives,
        tables,
        dynamic,
        f_ref,
        floors,
        driven,
        lowered,
        status: vec![DynamicStatus::Finished; v],
        step: vec![options.dt; v],
        iterations: vec![Vec::new(); v],
        log: vec![Vec::new(); v],
    };
    let members: Vec<usize> = (0..v).collect();
    run_span(
        &mut batch,
        ensemble.as_mut(),
        &members,
        0.0,
        t_end,
        options.dt,
        Some((every, observe)),
    )?;
    Ok(batch
        .status
        .into_iter()
        .zip(batch.iterations)
        .zip(batch.log)
        .map(|((status, iterations), log)| DynamicResult {
            status,
            iterations,
            log,
        })
        .collect())
}

/// Advances the batch's variants `members` (the ensemble's variants, in order) from `t0`
/// to `t_end` in steps of `h`; variants that fail a step are re-tried in a batch of their
/// own with half the step (recursively) and rejoin at its end.
#[allow(clippy::type_complexity)]
fn run_span<T: Real + Send + Sync, P: KernelPath<T>>(
    batch: &mut Batch<'_, T, P>,
    ensemble: &mut dyn ResidentDynamic<T>,
    members: &[usize],
    t0: f64,
    t_end: f64,
    h: f64,
    mut observe: Option<(usize, &mut dyn FnMut(f64, &DynamicBatch<T>))>,
) -> Result<(), crate::error::SystemError> {
    let t = |x: f64| T::from_f64_lossy(x);
    let m = members.len();
    let size = std::mem::size_of::<T>();
    let options = batch.options;
    let p = options.alpha;
    let ratio = (1.0 - p.alpha_f) / (1.0 - p.alpha_m);
    let settings = NewtonSettings::dynamics(options.max_iterations, options.tolerance, size);
    let mut time = t0;
    let mut step = 0usize;
    while let Some((hh, t1)) = control::next_step(time, t_end, h) {
        let coefficients = StepCoefficients {
            h: t(hh),
            alpha_m: t(p.alpha_m),
            alpha_f: t(p.alpha_f),
            beta: t(p.beta),
            gamma: t(p.gamma),
            top_fixed: batch.tables.fixed[0],
            driven: batch.driven,
            lowered: batch.lowered,
        };
        let mut top = vec![T::zero(); TOP_LEN * m];
        for (i, &j) in members.iter().enumerate() {
            let d = &batch.drives[j];
            let (phi, phidot, phiddot) = d.table(t1);
            let (zh, zhdot, zhddot) = d.hook(t1);
            let top0 = &batch.models[j].nodes[0];
            let n0 = top0.hole_axis;
            let r = crate::physics::beam::rotation_exp(&crate::physics::vec3::scale(&n0, phi));
            for (k, x) in r.iter().flatten().enumerate() {
                top[k * m + i] = t(*x);
            }
            for k in 0..3 {
                // The hook's travel as a displacement of the top node: (x₀ + z_h n₀) − x₀.
                let x0 = top0.position[k];
                let travel = (x0 + zh * n0[k]) - x0;
                for (f, x) in [phidot, phiddot].into_iter().enumerate() {
                    top[(9 + 3 * f + k) * m + i] = t(x * n0[k]);
                }
                top[(15 + k) * m + i] = t(travel);
                for (f, x) in [zhdot, zhddot].into_iter().enumerate() {
                    top[(18 + 3 * f + k) * m + i] = t(x * n0[k]);
                }
            }
        }
        ensemble.begin_step(&coefficients, &top)?;
        // Variants whose own step is shorter than this one (cut before, not yet regrown,
        // as the CPU integrator keeps it) take this step in sub-steps of their own.
        let deferred: Vec<usize> = (0..m)
            .filter(|&i| {
                let j = members[i];
                batch.status[j] == DynamicStatus::Finished && control::defers(batch.step[j], hh)
            })
            .collect();
        let at_n = if deferred.is_empty() {
            None
        } else {
            Some(ensemble.state()?)
        };
        let mut newton = Newton::new(settings, m);
        for (i, &j) in members.iter().enumerate() {
            if batch.status[j] == DynamicStatus::Finished && !deferred.contains(&i) {
                newton.start(i, batch.floors[j], false);
            }
        }
        let hhb = hh * hh * p.beta * ratio;
        let (failed, before) = solve_step(batch, ensemble, members, newton, hhb)?;
        // (local index, its sub-step) of every variant to take this step in sub-steps.
        let mut retry: Vec<(usize, f64)> = deferred
            .iter()
            .map(|&i| (i, batch.step[members[i]]))
            .collect();
        for (i, reason) in failed {
            let j = members[i];
            let Some(cut) = control::cut(hh, options.min_dt) else {
                batch.status[j] = DynamicStatus::Failed(
                    t1,
                    format!(
                        "step {hh:.3e} s failed and cannot be cut below {:.1e} s: {reason}",
                        options.min_dt
                    ),
                );
                continue;
            };
            batch.log[j].push(format!(
                "t = {time:.6} s: step {hh:.3e} s failed ({reason}); cut to {cut:.3e} s"
            ));
            batch.step[j] = cut;
            retry.push((i, cut));
        }
        if !retry.is_empty() {
            let at_n = before.or(at_n).ok_or(crate::error::SystemError::Order(
                "no state at the step's start",
            ))?;
            let mut now = ensemble.state()?;
            let mut steps: Vec<f64> = retry.iter().map(|r| r.1).collect();
            steps.sort_by(|a, b| b.total_cmp(a));
            steps.dedup();
            for h_sub in steps {
                let group: Vec<usize> =
                    retry.iter().filter(|r| r.1 == h_sub).map(|r| r.0).collect();
                let again: Vec<usize> = group.iter().map(|&i| members[i]).collect();
                let after = retry_alone(
                    batch,
                    &again,
                    &batch_columns(&at_n, &group),
                    time,
                    t1,
                    h_sub,
                )?;
                put_batch_columns(&mut now, &group, &after);
            }
            ensemble.set_state(&now)?;
        }
        time = t1;
        step += 1;
        if let Some((every, observe)) = observe.as_mut() {
            if *every > 0 && step.is_multiple_of(*every) {
                let mut s = ensemble.state()?;
                // Displacements from the reference for the observer (summed in f64).
                let v = batch.tables.num_variants;
                for (w, b) in s.u.iter_mut().zip(&batch.tables.base) {
                    *w = t(b + w.to_f64_lossy());
                }
                debug_assert_eq!(v, m);
                observe(time, &s);
            }
        }
    }
    Ok(())
}

/// The Newton of one time step for the ensemble's running variants (started in `newton`),
/// then the step's end (the state at `t_n + h`). Each iteration is asked of the variants
/// still running alone ([`ResidentDynamic::iterate`]): on the GPU the kernels work on those
/// (built `MASKED`), so a converged variant costs no more kernel work and nothing leaves
/// the device (issue 27; a batch of the stragglers was opened on the host before, their
/// state read back and written again). Returns the variants whose Newton failed (local
/// index, reason) and, if any failed, every variant's state at `t_n`.
#[allow(clippy::type_complexity)]
fn solve_step<T: Real + Send + Sync, P: KernelPath<T>>(
    batch: &mut Batch<'_, T, P>,
    ensemble: &mut dyn ResidentDynamic<T>,
    members: &[usize],
    mut newton: Newton,
    hhb: f64,
) -> Result<(Vec<(usize, String)>, Option<DynamicBatch<T>>), crate::error::SystemError> {
    let m = members.len();
    let mut failed = Vec::new();
    {
        let mut sys = DynamicStep {
            ensemble: &mut *ensemble,
            f_ref: members.iter().map(|&j| batch.f_ref[j]).collect(),
            hhb,
            running: vec![true; m],
            full_step: crate::engine::KeptTrial::new(),
        };
        while newton.any_running() {
            sys.running = (0..m).map(|i| newton.is_running(i)).collect();
            for (i, event) in newton.iterate(&mut sys)? {
                match event {
                    Event::Converged(its) => {
                        let j = members[i];
                        batch.iterations[j].push(its);
                        // As the CPU integrator: a cut step doubles after an easy one.
                        if let Some(h) = control::regrown(batch.step[j], its, batch.options.dt) {
                            batch.step[j] = h;
                            batch.log[j].push(format!("step regrown to {h:.3e} s"));
                        }
                    }
                    Event::Failed(reason) => failed.push((i, reason)),
                }
            }
        }
    }
    // Every variant's state at t_n, where one failed.
    let before = if failed.is_empty() {
        None
    } else {
        Some(ensemble.state()?)
    };
    ensemble.end_step()?;
    Ok((failed, before))
}

/// A batch of the batch's variants `members` (each with its tables, loads and base) at the
/// state `start`.
fn open_subset<'c, T: Real + Send + Sync, P: KernelPath<T>>(
    batch: &Batch<'c, T, P>,
    members: &[usize],
    start: &DynamicBatch<T>,
) -> Result<Box<dyn ResidentDynamic<T> + 'c>, crate::error::SystemError> {
    let v = batch.tables.num_variants;
    let models: Vec<Model> = members.iter().map(|&j| batch.models[j].clone()).collect();
    // The static start is not used by a dynamic batch: the state is `start`.
    let mut tables =
        ensemble_tables_from::<T>(&models, Some((start.u.clone(), start.rot.clone())))?;
    tables.terms = batch.tables.terms;
    tables.set_base(&models[0], columns(&batch.tables.base, v, members));
    let d = &batch.dynamic;
    let dynamic = DynamicTables {
        mass: d.mass.clone(),
        inertia0: d.inertia0.clone(),
        a0: d.a0,
        f_ext: columns(&d.f_ext, v, members),
        pair_params: columns(&d.pair_params, v, members),
        unbalance: columns(&d.unbalance, v, members),
        start: start.clone(),
    };
    let path: &'c P = batch.path;
    path.open_dynamic(&batch.models[members[0]], &tables, &dynamic)
}

/// The batch's variants `again`, at `start` (their state at `t0`), taken to `t1` in a batch
/// of their own with steps of `h`; their state at `t1`.
fn retry_alone<T: Real + Send + Sync, P: KernelPath<T>>(
    batch: &mut Batch<'_, T, P>,
    again: &[usize],
    start: &DynamicBatch<T>,
    t0: f64,
    t1: f64,
    h: f64,
) -> Result<DynamicBatch<T>, crate::error::SystemError> {
    let mut sub = open_subset(batch, again, start)?;
    run_span(batch, sub.as_mut(), again, t0, t1, h, None)?;
    sub.state()
}
