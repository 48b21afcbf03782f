//! `holewall ensemble CASE [--variants FILE] --out DIR`: one case, many variants (issue 5).
//!
//! Each variant is the case with its overrides (`src/ensemble.rs`), solved statically or
//! run dynamically from its static equilibrium. The CPU backend runs the variants in
//! parallel (rayon), each with the f64 solvers (faer for the global solves); a variant that
//! fails is reported with its reason and never touches another's numbers.
//!
//! Output: `DIR/variants.csv` (overrides, quantities of interest, status per variant),
//! `DIR/summary.json`, plots of the quantities of interest over the variants, and for the
//! variants the case names in `ensemble.series` the full `holewall run` output under
//! `DIR/series/<name>/`.

use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::backend::{BackendChoice, Precision};
use crate::case::{load_case, Analysis, Case};
use crate::cli::static_cmd::{fe_rows, neutral_point, neutral_point_of, nodal_axial_forces};
use crate::ensemble::{apply, stabilizer_sites, Variant};
use crate::error::{Error, InputError};
use crate::model::Model;
use crate::output::write_atomic;
use crate::physics::vec3::{dot, scale, sub};
use crate::plots::{line_plot, Series};
use crate::solve::dynamics::{DynamicState, Dynamics};
use crate::solve::statics::{solve_static, StaticOptions};

/// Per-stabilizer quantities of interest.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct StabilizerQoi {
    /// Largest normal (side) force (N).
    #[serde(with = "crate::output::nan_as_null")]
    pub max_side_force_n: f64,
    /// Largest lateral displacement from the hole axis (m).
    #[serde(with = "crate::output::nan_as_null")]
    pub max_lateral_m: f64,
    /// Whirl frequency over the second half of a dynamic run (Hz), signed: + forward (with
    /// the rotation), − backward; `None` for static runs or a stabilizer that stays put.
    pub whirl_hz: Option<f64>,
}

/// Quantities of interest of the whole string.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct StringQoi {
    /// Largest contact (side) force per unit length along the string (N/m): a site's
    /// normal force over its node's share of the string (half of each adjacent element), so
    /// it does not depend on the mesh; over the run for dynamics.
    pub max_side_force_per_length_n_per_m: Option<f64>,
    /// Where it acts (MD, m).
    pub max_side_force_md_m: Option<f64>,
    /// Compression beyond the sinusoidal buckling load anywhere (static).
    pub sinusoidal_buckling: Option<bool>,
    /// Beyond the helical buckling load (static).
    pub helical_buckling: Option<bool>,
    /// Stick-slip severity over the second half of a dynamic run: (max − min)/mean of the
    /// bit's spin about the hole axis.
    pub stick_slip_severity: Option<f64>,
}

/// How a variant ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Converged at the requested steps.
    Converged,
    /// Converged, with load or time steps cut on the way (see the reason column).
    StepCut,
    /// Failed (NaN, Newton divergence, step below the minimum): see the reason.
    Failed,
}

/// Which solver produced a variant's result.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolvedBy {
    /// The kernel engine (GPU, or the CPU twins of its kernels).
    Engine,
    /// The CPU solver (the CPU backend, or a re-run of a variant the engine failed).
    Cpu,
}

impl SolvedBy {
    /// The name in `variants.csv`.
    pub fn name(self) -> &'static str {
        match self {
            SolvedBy::Engine => "engine",
            SolvedBy::Cpu => "cpu",
        }
    }
}

/// One variant's result.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct VariantResult {
    /// Variant name.
    pub name: String,
    /// Status.
    pub status: Status,
    /// Who solved it (a CPU re-run of an engine failure says so in `reason`).
    pub solved_by: SolvedBy,
    /// Why it failed, or the first step cut.
    pub reason: String,
    /// Neutral point from the bit (m): static solution, or the last state of a dynamic run.
    pub neutral_point_from_bit_m: Option<f64>,
    /// Hook load (N): the top's axial reaction of a static solution; for a dynamic run the
    /// top element's axial force in the last state.
    pub hook_load_n: Option<f64>,
    /// Largest surface torque (N·m).
    #[serde(with = "crate::output::nan_as_null")]
    pub max_surface_torque_nm: f64,
    /// The string's other quantities (side force per length, buckling, stick-slip).
    #[serde(default)]
    pub string: StringQoi,
    /// Per stabilizer, nearest the bit first.
    pub stabilizers: Vec<StabilizerQoi>,
    /// Mean Newton iterations per load or time step.
    #[serde(with = "crate::output::nan_as_null")]
    pub newton_iterations_per_step: f64,
    /// Step cuts.
    pub step_cuts: usize,
}

/// The command's summary.
#[derive(Clone, Debug, Serialize)]
pub struct EnsembleSummary {
    /// Case title.
    pub title: String,
    /// `static` or `dynamic`.
    pub analysis: String,
    /// Where it ran.
    pub backend: String,
    /// Float type of the engine (`f64`, or `f32` on the GPU); failed f32 variants re-run
    /// on the CPU in f64.
    pub precision: String,
    /// Variants run.
    pub variants: usize,
    /// Converged without cuts.
    pub converged: usize,
    /// Converged with step cuts.
    pub step_cut: usize,
    /// Failed.
    pub failed: usize,
    /// Names and reasons of the failed variants.
    pub failures: Vec<(String, String)>,
    /// Variants the kernel engine solved.
    pub solved_by_engine: usize,
    /// Variants the CPU solved: all of them on the CPU backend; on the GPU backend, the
    /// engine's failures re-run there (each one's reason gives the engine's failure).
    pub solved_by_cpu: usize,
    /// Wall time of the variant runs (s).
    pub seconds: f64,
    /// Statistics and sensitivities of the quantities of interest (`--samples` runs).
    pub uncertainty: Option<crate::uq::report::UncertaintyReport>,
    /// Files written.
    pub outputs: Vec<String>,
}

fn element_axial(model: &Model, q: &crate::solve::statics::StaticState, i: usize) -> (f64, f64) {
    let f = crate::solve::statics::element_section_forces(model, q, i);
    (f.axial, f.torque)
}

/// Lateral offset of a site's node from the hole axis, in the node's frame (x, y).
fn lateral(model: &Model, q: &crate::solve::statics::StaticState, node: usize) -> (f64, f64) {
    let nd = &model.nodes[node];
    let d = sub(&q.x[node], &nd.position);
    let d_t = sub(&d, &scale(&nd.hole_axis, dot(&d, &nd.hole_axis)));
    let f = &nd.frame0;
    (
        dot(&d_t, &[f[0][1], f[1][1], f[2][1]]),
        dot(&d_t, &[f[0][2], f[1][2], f[2][2]]),
    )
}

fn failed(name: &str, reason: String, stabs: usize) -> VariantResult {
    VariantResult {
        name: name.to_string(),
        status: Status::Failed,
        solved_by: SolvedBy::Cpu,
        reason,
        neutral_point_from_bit_m: None,
        hook_load_n: None,
        max_surface_torque_nm: f64::NAN,
        string: StringQoi::default(),
        stabilizers: vec![StabilizerQoi::default(); stabs],
        newton_iterations_per_step: f64::NAN,
        step_cuts: 0,
    }
}

/// A variant that finished: converged, or with the step cuts its solver log records.
#[allow(clippy::too_many_arguments)]
fn finished(
    name: &str,
    log: &[String],
    iterations: &[usize],
    neutral_point_from_bit_m: Option<f64>,
    hook_load_n: f64,
    max_surface_torque_nm: f64,
    stabilizers: Vec<StabilizerQoi>,
    string: StringQoi,
) -> VariantResult {
    let cuts = log.iter().filter(|l| l.contains("cut")).count();
    VariantResult {
        name: name.to_string(),
        status: if cuts > 0 {
            Status::StepCut
        } else {
            Status::Converged
        },
        solved_by: SolvedBy::Cpu,
        reason: log.first().cloned().unwrap_or_default(),
        neutral_point_from_bit_m,
        hook_load_n: hook_load_n.is_finite().then_some(hook_load_n),
        max_surface_torque_nm,
        string,
        stabilizers,
        newton_iterations_per_step: iterations.iter().sum::<usize>() as f64
            / iterations.len().max(1) as f64,
        step_cuts: cuts,
    }
}

/// Static equilibrium of one variant's model.
pub fn static_variant(case: &Case, name: &str, model: &Model) -> VariantResult {
    match solve_static(model, &StaticOptions::default()) {
        Ok(sol) => static_result(case, name, model, &sol),
        Err(e) => failed(name, e.to_string(), stabilizer_sites(model).len()),
    }
}

/// Quantities of interest of a converged static solution.
pub fn static_result(
    case: &Case,
    name: &str,
    model: &Model,
    sol: &crate::solve::statics::StaticSolution,
) -> VariantResult {
    let stabs = stabilizer_sites(model);
    let (rows, hook, torque, _wob) = fe_rows(model, sol);
    let stabilizers = stabs
        .iter()
        .map(|&k| {
            let (x, y) = lateral(model, &sol.state, model.sites[k].node);
            StabilizerQoi {
                max_side_force_n: sol.contact[k].1.max(0.0),
                max_lateral_m: x.hypot(y),
                whirl_hz: None,
            }
        })
        .collect();
    let (per_length, md) = (0..model.sites.len())
        .map(|k| {
            let node = model.sites[k].node;
            (
                sol.contact[k].1.max(0.0) / tributary_length(model, node),
                model.nodes[node].md,
            )
        })
        .fold((0.0f64, f64::NAN), |m, x| if x.0 > m.0 { x } else { m });
    let (sinusoidal, helical) = crate::cli::static_cmd::buckling(model, &rows, case);
    let string = StringQoi {
        max_side_force_per_length_n_per_m: Some(per_length),
        max_side_force_md_m: md.is_finite().then_some(md),
        sinusoidal_buckling: Some(sinusoidal),
        helical_buckling: Some(helical),
        stick_slip_severity: None,
    };
    finished(
        name,
        &sol.log,
        &sol.iterations,
        neutral_point(&rows).map(|md| bit_md_of(case, model) - md),
        hook,
        torque,
        stabilizers,
        string,
    )
}

/// Static equilibria of every variant through the GPU kernels (in `T`), the variants that
/// fail there re-run on the CPU with step control (their reason says so). Stabilizer
/// moves run there too (each pair carries its node). `None` when the variants do not share
/// the number of sites: the caller runs the CPU.
pub fn run_static_gpu<T: crate::gpu::contact::GpuReal>(
    case: &Case,
    variants: &[Variant],
    ctx: &'static crate::gpu::GpuContext,
    bar: &indicatif::ProgressBar,
) -> Result<Option<Vec<VariantResult>>, Error> {
    use crate::engine::{solve_static_ensemble_with_progress, EngineStatus, GpuPath};
    let models: Vec<Model> = variants
        .iter()
        .map(|v| apply(case, v))
        .collect::<Result<_, _>>()
        .map_err(|e| Error::Io(std::io::Error::other(e)))?;
    if !models.iter().all(|m| same_mesh(case, m)) {
        return Ok(None);
    }
    let results = solve_static_ensemble_with_progress::<T, _>(
        &models,
        &GpuPath(ctx),
        &StaticOptions::default(),
        &mut |f| bar.set_position((f * variants.len() as f64) as u64),
    )
    .map_err(|e| Error::Io(std::io::Error::other(format!("GPU engine: {e}"))))?;
    Ok(Some(
        results
            .into_par_iter()
            .zip(models.par_iter().zip(variants.par_iter()))
            .map(|(r, (m, v))| match r.status {
                EngineStatus::Converged => {
                    let mut sol = crate::solve::statics::solution_at(m, r.state);
                    sol.iterations = r.iterations;
                    sol.log = r.log;
                    let mut done = static_result(case, &v.name, m, &sol);
                    done.solved_by = SolvedBy::Engine;
                    done
                }
                EngineStatus::Failed(why) => {
                    let mut again = static_variant(case, &v.name, m);
                    again.reason = format!("GPU: {why}; re-run on the CPU: {}", again.reason);
                    if again.status == Status::Converged {
                        again.status = Status::StepCut;
                    }
                    again
                }
            })
            .collect(),
    ))
}

/// The `[dynamics]` runs of every variant through the GPU engine (in `T`): static starts
/// through the static engine, then lockstep generalised-α steps, every step observed for
/// the quantities of interest. A variant that fails on the GPU (static start or a step)
/// re-runs on the CPU with step control (its reason says so). `Err` with the reason when
/// the case needs what only the CPU integrator has (consistent mass, stiffness-
/// proportional damping): the caller runs the CPU then.
pub fn run_dynamic_gpu<T: crate::gpu::contact::GpuReal>(
    case: &Case,
    variants: &[Variant],
    ctx: &'static crate::gpu::GpuContext,
    bar: &indicatif::ProgressBar,
) -> Result<Result<Vec<VariantResult>, String>, Error> {
    use crate::engine::dynamic::{run_dynamic_ensemble, unsupported, DynamicStatus};
    use crate::engine::{solve_static_ensemble, EngineStatus, GpuPath};
    let Some(settings) = case.dynamics.clone() else {
        return Ok(Err("no [dynamics] table".into()));
    };
    let options = super::run_cmd::options_for(&settings);
    if let Some(why) = unsupported(&options) {
        return Ok(Err(why));
    }
    let models: Vec<Model> = variants
        .iter()
        .map(|v| apply(case, v))
        .collect::<Result<_, _>>()
        .map_err(|e| Error::Io(std::io::Error::other(e)))?;
    if !models.iter().all(|m| same_mesh(case, m)) {
        return Ok(Err(
            "the variants differ in their mesh or number of contact sites".into(),
        ));
    }
    let path = GpuPath(ctx);
    let statics = solve_static_ensemble::<T, _>(&models, &path, &StaticOptions::default())
        .map_err(|e| Error::Io(std::io::Error::other(format!("GPU engine: {e}"))))?;
    // Variants whose static start failed on the GPU run wholly on the CPU.
    let on_gpu: Vec<usize> = (0..models.len())
        .filter(|&j| statics[j].status == EngineStatus::Converged)
        .collect();
    let gpu_models: Vec<Model> = on_gpu.iter().map(|&j| models[j].clone()).collect();
    let starts: Vec<_> = on_gpu.iter().map(|&j| statics[j].state.clone()).collect();
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
    for (j, (d, q)) in cpu.iter_mut().zip(&starts).enumerate() {
        if let Ok(s) = d.initial_state(q.clone()) {
            observers[j].observe(&gpu_models[j], d, &s);
            last[j] = Some(s);
        }
    }
    let results = run_dynamic_ensemble::<T, _>(
        &gpu_models,
        &starts,
        density,
        &path,
        &options,
        settings.duration,
        1,
        &mut |first, t, batch| {
            let (v, n) = (batch.num_variants, batch.num_nodes);
            for j in 0..v {
                let g = first + j;
                let Some(state) = last[g].as_mut() else {
                    continue;
                };
                let m = &gpu_models[g];
                state.t = t;
                for i in 0..n {
                    for k in 0..3 {
                        state.q.x[i][k] =
                            m.nodes[i].position[k] + batch.u[(3 * i + k) * v + j].to_f64_lossy();
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
                observers[g].observe(m, &cpu[g], state);
            }
            bar.set_position(((t / settings.duration) * variants.len() as f64) as u64);
        },
    )
    .map_err(|e| Error::Io(std::io::Error::other(format!("GPU engine: {e}"))))?;
    let mut out: Vec<Option<VariantResult>> = vec![None; models.len()];
    for (&j, ((r, obs), state)) in on_gpu
        .iter()
        .zip(results.into_iter().zip(observers).zip(last))
    {
        let name = &variants[j].name;
        out[j] = Some(match (r.status, state) {
            (DynamicStatus::Finished, Some(state)) => {
                // The engine's step cuts, as the CPU integrator's log would give them.
                let mut done = obs.finish(case, name, &models[j], &state, &r.log, &r.iterations);
                done.solved_by = SolvedBy::Engine;
                done
            }
            (status, _) => {
                let why = match status {
                    DynamicStatus::Failed(t, why) => format!("failed at t = {t:.6} s: {why}"),
                    DynamicStatus::Finished => "no initial state".into(),
                };
                let mut again = dynamic_variant(case, name, &models[j]);
                again.reason = format!("GPU: {why}; re-run on the CPU: {}", again.reason);
                if again.status == Status::Converged {
                    again.status = Status::StepCut;
                }
                again
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
                    EngineStatus::Converged => String::new(),
                };
                let mut again = dynamic_variant(case, &variants[j].name, &models[j]);
                again.reason = format!(
                    "GPU static start: {why}; re-run on the CPU: {}",
                    again.reason
                );
                if again.status == Status::Converged {
                    again.status = Status::StepCut;
                }
                again
            })
        })
        .collect()))
}

/// The `[dynamics]` run of one variant's model from its static equilibrium.
pub fn dynamic_variant(case: &Case, name: &str, model: &Model) -> VariantResult {
    let stabs = stabilizer_sites(model);
    let Some(settings) = case.dynamics.clone() else {
        return failed(name, "no [dynamics] table".into(), stabs.len());
    };
    let start = match solve_static(model, &StaticOptions::default()) {
        Ok(s) => s,
        Err(e) => return failed(name, format!("static start: {e}"), stabs.len()),
    };
    let options = super::run_cmd::options_for(&settings);
    let density = &case.element_density;
    let mut dynamics = Dynamics::new(model, options, &|e| density[e]);
    let mut s = match dynamics.initial_state(start.state) {
        Ok(s) => s,
        Err(e) => return failed(name, format!("initial state: {e}"), stabs.len()),
    };
    let mut observer = DynamicObserver::new(model, settings.duration);
    let mut observe = |d: &Dynamics, st: &DynamicState| observer.observe(model, d, st);
    observe(&dynamics, &s);
    let result = dynamics.run(&mut s, settings.duration, &mut observe);
    let cuts = dynamics.log.iter().filter(|l| l.contains("cut to")).count();
    if let Err(reason) = result {
        let mut f = failed(name, reason, stabs.len());
        f.step_cuts = cuts;
        return f;
    }
    observer.finish(case, name, model, &s, &dynamics.log, &dynamics.iterations)
}

/// The quantities of interest of a dynamic run, accumulated step by step (the CPU
/// integrator's and the GPU engine's runs feed the same observer).
pub struct DynamicObserver {
    stabs: Vec<usize>,
    qoi: Vec<StabilizerQoi>,
    angles: Vec<Vec<(f64, f64)>>,
    last_angle: Vec<Option<f64>>,
    unwrapped: Vec<f64>,
    max_torque: f64,
    half: f64,
    /// Largest side force per length so far, and its MD.
    per_length: (f64, f64),
    /// The bit's spin about its hole axis over the second half.
    bit_spin: Vec<f64>,
}

impl DynamicObserver {
    /// For a run of `duration` seconds (whirl is fitted over its second half).
    pub fn new(model: &Model, duration: f64) -> Self {
        let stabs = stabilizer_sites(model);
        let k = stabs.len();
        DynamicObserver {
            stabs,
            qoi: vec![StabilizerQoi::default(); k],
            angles: vec![Vec::new(); k],
            last_angle: vec![None; k],
            unwrapped: vec![0.0; k],
            max_torque: 0.0,
            half: 0.5 * duration,
            per_length: (0.0, f64::NAN),
            bit_spin: Vec::new(),
        }
    }

    /// Takes one state in.
    pub fn observe(&mut self, model: &Model, d: &Dynamics, st: &DynamicState) {
        self.max_torque = self.max_torque.max(element_axial(model, &st.q, 0).1.abs());
        let contact = d.contact_forces(st);
        for (k, site) in model.sites.iter().enumerate() {
            let node = site.node;
            let (x, y) = lateral(model, &st.q, node);
            let r = x.hypot(y);
            if r > 0.0 {
                let g = &contact[k].g;
                let nd = &model.nodes[node];
                let dd = sub(&st.q.x[node], &nd.position);
                let d_t = sub(&dd, &scale(&nd.hole_axis, dot(&dd, &nd.hole_axis)));
                let normal = dot(&[g[0], g[1], g[2]], &d_t) / r / tributary_length(model, node);
                if normal > self.per_length.0 {
                    self.per_length = (normal, nd.md);
                }
            }
        }
        if st.t >= self.half {
            let n = model.nodes.len();
            let axis = model.nodes[n - 1].hole_axis;
            let w = [
                st.v[6 * (n - 1) + 3],
                st.v[6 * (n - 1) + 4],
                st.v[6 * (n - 1) + 5],
            ];
            self.bit_spin.push(dot(&w, &axis));
        }
        for (j, &k) in self.stabs.iter().enumerate() {
            let node = model.sites[k].node;
            let (x, y) = lateral(model, &st.q, node);
            let r = x.hypot(y);
            let qoi = &mut self.qoi[j];
            qoi.max_lateral_m = qoi.max_lateral_m.max(r);
            if r > 0.0 {
                let g = &contact[k].g;
                let nd = &model.nodes[node];
                let d = sub(&st.q.x[node], &nd.position);
                let d_t = sub(&d, &scale(&nd.hole_axis, dot(&d, &nd.hole_axis)));
                let normal = dot(&[g[0], g[1], g[2]], &d_t) / r;
                qoi.max_side_force_n = qoi.max_side_force_n.max(normal);
            }
            let a = y.atan2(x);
            if let Some(l) = self.last_angle[j] {
                let mut da = a - l;
                da -= std::f64::consts::TAU * (da / std::f64::consts::TAU).round();
                self.unwrapped[j] += da;
            }
            self.last_angle[j] = Some(a);
            if st.t >= self.half && r > 1e-6 {
                self.angles[j].push((st.t, self.unwrapped[j]));
            }
        }
    }

    /// The variant's result from its final state.
    pub fn finish(
        mut self,
        case: &Case,
        name: &str,
        model: &Model,
        last: &DynamicState,
        log: &[String],
        iterations: &[usize],
    ) -> VariantResult {
        if last.v.iter().any(|x| !x.is_finite()) {
            return failed(name, "state is not finite".into(), self.stabs.len());
        }
        let sign = if model.rotation_speed < 0.0 {
            -1.0
        } else {
            1.0
        };
        for (j, pts) in self.angles.iter().enumerate() {
            if pts.len() >= 3 {
                let nm = pts.len() as f64;
                let (mt, ma) = pts
                    .iter()
                    .fold((0.0, 0.0), |(a, b), (t, x)| (a + t / nm, b + x / nm));
                let den: f64 = pts.iter().map(|(t, _)| (t - mt).powi(2)).sum();
                if den > 0.0 {
                    let rate = pts.iter().map(|(t, x)| (t - mt) * (x - ma)).sum::<f64>() / den;
                    // Lateral angles are measured about the node's frame0 (e2, e3) = about
                    // the hole axis, the direction of a positive rotation speed.
                    self.qoi[j].whirl_hz = Some(sign * rate / std::f64::consts::TAU);
                }
            }
        }
        let axial: Vec<f64> = (0..model.elements.len())
            .map(|i| element_axial(model, &last.q, i).0)
            .collect();
        let md: Vec<f64> = model.nodes.iter().map(|n| n.md).collect();
        let np = neutral_point_of(&md, &nodal_axial_forces(&axial));
        let severity = if self.bit_spin.len() >= 2 {
            let mean = self.bit_spin.iter().sum::<f64>() / self.bit_spin.len() as f64;
            let (lo, hi) = self
                .bit_spin
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(*x), b.max(*x))
                });
            (mean.abs() > 1e-9).then(|| (hi - lo) / mean.abs())
        } else {
            None
        };
        let string = StringQoi {
            max_side_force_per_length_n_per_m: Some(self.per_length.0),
            max_side_force_md_m: self.per_length.1.is_finite().then_some(self.per_length.1),
            sinusoidal_buckling: None,
            helical_buckling: None,
            stick_slip_severity: severity,
        };
        finished(
            name,
            log,
            iterations,
            np.map(|x| bit_md_of(case, model) - x),
            axial.first().copied().unwrap_or(f64::NAN),
            self.max_torque,
            self.qoi,
            string,
        )
    }
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
            let stabs = stabilizer_sites(&case.model).len();
            let r = match apply(case, v) {
                Err(e) => failed(&v.name, format!("variant: {e}"), stabs),
                Ok(model) => match analysis {
                    Analysis::Static => static_variant(case, &v.name, &model),
                    Analysis::Dynamic => dynamic_variant(case, &v.name, &model),
                },
            };
            bar.inc(1);
            r
        })
        .collect()
}

fn fmt(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

fn variants_csv(
    variants: &[Variant],
    results: &[VariantResult],
    stabs: usize,
    whirl_threshold: Option<f64>,
) -> Result<Vec<u8>, Error> {
    let dynamic = whirl_threshold.is_some();
    let io = |e: csv::Error| Error::Io(std::io::Error::other(e));
    let mut keys: Vec<String> = Vec::new();
    for v in variants {
        for (k, _) in &v.overrides {
            if !keys.contains(&k.name) {
                keys.push(k.name.clone());
            }
        }
    }
    let mut header: Vec<String> = vec!["index".into(), "name".into()];
    header.extend(keys.iter().cloned());
    header.extend(
        [
            "status",
            "solved_by",
            "reason",
            "neutral_point_from_bit_m",
            "hook_load_n",
            "max_surface_torque_nm",
            "max_side_force_per_length_n_per_m",
            "max_side_force_md_m",
        ]
        .map(String::from),
    );
    if dynamic {
        header.push("stick_slip_severity".into());
    } else {
        header.extend(["sinusoidal_buckling", "helical_buckling"].map(String::from));
    }
    for k in 1..=stabs {
        header.push(format!("stab{k}_max_side_force_n"));
        header.push(format!("stab{k}_max_lateral_m"));
        if dynamic {
            header.push(format!("stab{k}_whirl_hz"));
            header.push(format!("stab{k}_whirl"));
        }
    }
    header.extend(["newton_iterations_per_step", "step_cuts"].map(String::from));
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&header).map_err(io)?;
    for (i, (v, r)) in variants.iter().zip(results).enumerate() {
        let mut row = vec![i.to_string(), v.name.clone()];
        for k in &keys {
            row.push(
                v.overrides
                    .iter()
                    .find(|(key, _)| &key.name == k)
                    .map(|(key, x)| {
                        if x.is_finite() {
                            key.format(*x)
                        } else {
                            String::new()
                        }
                    })
                    .unwrap_or_default(),
            );
        }
        row.push(
            match r.status {
                Status::Converged => "converged",
                Status::StepCut => "step_cut",
                Status::Failed => "failed",
            }
            .into(),
        );
        row.push(r.solved_by.name().into());
        row.push(r.reason.clone());
        row.push(r.neutral_point_from_bit_m.map(fmt).unwrap_or_default());
        row.push(r.hook_load_n.map(fmt).unwrap_or_default());
        row.push(fmt(r.max_surface_torque_nm));
        let opt = |x: Option<f64>| x.map(fmt).unwrap_or_default();
        let flag = |x: Option<bool>| x.map(|b| b.to_string()).unwrap_or_default();
        row.push(opt(r.string.max_side_force_per_length_n_per_m));
        row.push(opt(r.string.max_side_force_md_m));
        if dynamic {
            row.push(opt(r.string.stick_slip_severity));
        } else {
            row.push(flag(r.string.sinusoidal_buckling));
            row.push(flag(r.string.helical_buckling));
        }
        for q in &r.stabilizers {
            row.push(fmt(q.max_side_force_n));
            row.push(fmt(q.max_lateral_m));
            if dynamic {
                row.push(q.whirl_hz.map(fmt).unwrap_or_default());
                row.push(
                    match (q.whirl_hz, whirl_threshold) {
                        (Some(h), Some(t)) if h.abs() < t => "none",
                        (Some(h), _) if h > 0.0 => "forward",
                        (Some(h), _) if h < 0.0 => "backward",
                        _ => "",
                    }
                    .into(),
                );
            }
        }
        row.push(fmt(r.newton_iterations_per_step));
        row.push(r.step_cuts.to_string());
        w.write_record(&row).map_err(io)?;
    }
    w.into_inner()
        .map_err(|e| Error::Io(std::io::Error::other(e.to_string())))
}

/// Runs the command.
pub fn run(
    case_path: &Path,
    variants_file: Option<&Path>,
    backend: BackendChoice,
    precision: Precision,
    out: &Path,
    show_progress: bool,
    options: &EnsembleOptions,
) -> Result<EnsembleSummary, Error> {
    let monte_carlo = options.monte_carlo.as_ref();
    let case = load_case(case_path)?;
    let settings = case.ensemble.clone();
    let cli_error = |key: &str, message: String| -> Error {
        InputError {
            source_name: case_path.display().to_string(),
            line: 0,
            key: key.into(),
            message,
        }
        .into()
    };
    let variants = match monte_carlo {
        Some(mc) => {
            if variants_file.is_some() {
                return Err(cli_error(
                    "--samples",
                    "give --variants FILE or --samples N, not both".into(),
                ));
            }
            let uncertain = settings
                .as_ref()
                .map(|s| s.uncertain.clone())
                .unwrap_or_default();
            let correlation = settings.as_ref().and_then(|s| s.correlation.clone());
            crate::uq::sample_variants(
                &uncertain,
                mc.samples,
                mc.seed,
                mc.sampling,
                mc.sobol_indices,
                correlation.as_ref(),
            )
                .map_err(|m| cli_error("ensemble.uncertain", m))?
        }
        None => match crate::ensemble::case_variants(&case, variants_file)? {
            Some(v) => v,
            None => {
                return Err(InputError {
                    source_name: case_path.display().to_string(),
                    line: 1,
                    key: "ensemble.grid".into(),
                    message:
                        "no variants: give --variants FILE, an [ensemble.grid] table, or --samples N with an [ensemble.uncertain] table"
                            .into(),
                }
                .into())
            }
        },
    };
    let analysis = settings
        .as_ref()
        .map(|s| s.analysis)
        .unwrap_or(Analysis::Static);
    let series: Vec<String> = settings
        .as_ref()
        .map(|s| s.series.clone())
        .unwrap_or_default();
    for name in &series {
        if !variants.iter().any(|v| &v.name == name) {
            return Err(InputError {
                source_name: case_path.display().to_string(),
                line: 1,
                key: "ensemble.series".into(),
                message: format!("no variant named {name:?}"),
            }
            .into());
        }
        if analysis == Analysis::Static {
            return Err(InputError {
                source_name: case_path.display().to_string(),
                line: 1,
                key: "ensemble.series".into(),
                message: "time series need analysis = \"dynamic\"".into(),
            }
            .into());
        }
    }
    if precision == Precision::F32 {
        let why = match (backend, analysis) {
            (BackendChoice::Cpu, _) => Some("the CPU backend computes in f64 (it is the oracle the GPU is tested against); f32 runs on --backend gpu or auto"),
            _ => None,
        };
        if let Some(message) = why {
            return Err(InputError {
                source_name: "--precision".into(),
                line: 0,
                key: "precision".into(),
                message: message.into(),
            }
            .into());
        }
    }
    // The GPU engine, where asked for (or, with auto, where a hardware adapter has f64).
    // The GPU engine where asked for; `auto` takes it on a hardware adapter (the CPU
    // backend computes in f64 only, so f32 always runs on the engine).
    let gpu = match crate::backend::Backend::resolve_with(
        backend,
        precision,
        &[Precision::F64],
        crate::backend::AutoRule::FasterPath,
    )? {
        crate::backend::Backend::Gpu(ctx) => Some(ctx),
        crate::backend::Backend::Cpu => None,
    };
    // Thresholds must name a quantity this case reports (checked before any work).
    if let Some(mc) = monte_carlo {
        let names: Vec<String> = qoi_columns(
            &[],
            stabilizer_sites(&case.model).len(),
            analysis == Analysis::Dynamic,
        )
        .into_iter()
        .map(|q| q.name)
        .collect();
        for (name, _) in &mc.thresholds {
            if !names.contains(name) {
                return Err(InputError {
                    source_name: "--exceed".into(),
                    line: 0,
                    key: name.clone(),
                    message: format!("no quantity {name:?}; allowed: {}", names.join(", ")),
                }
                .into());
            }
        }
    }
    // Check every variant against the case before any work.
    for v in &variants {
        if let Err(e) = apply(&case, v) {
            return Err(InputError {
                source_name: variants_file
                    .map(|p| p.display().to_string())
                    .unwrap_or_else(|| case_path.display().to_string()),
                line: 0,
                key: format!("variant {}", v.name),
                message: e,
            }
            .into());
        }
    }
    // The output folder, checked (and the run's manifest written) before any work.
    let chunk_size = if options.chunk_size == 0 {
        DEFAULT_CHUNK
    } else {
        options.chunk_size
    };
    let manifest = Manifest::new(
        case_path,
        variants_file,
        backend,
        precision,
        options,
        chunk_size,
        variants.len(),
    )?;
    prepare_out(out, &manifest, options.force)?;
    let nchunks = manifest.chunks;
    let range = match options.shard {
        Some((k, n)) => (k - 1) * nchunks / n..k * nchunks / n,
        None => 0..nchunks,
    };
    let chunk_of = |c: usize| c * chunk_size..((c + 1) * chunk_size).min(variants.len());
    let in_range: usize = range.clone().map(|c| chunk_of(c).len()).sum();
    let bar = if show_progress {
        indicatif::ProgressBar::new(in_range as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} variants, {elapsed} elapsed, eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    for c in range.clone() {
        let path = chunk_path(out, c);
        if path.exists() {
            bar.inc(chunk_of(c).len() as u64);
            continue;
        }
        let start = std::time::Instant::now();
        let slice = &variants[chunk_of(c)];
        let before = bar.position();
        let (results, backend_name) = compute(&case, analysis, slice, gpu, precision, &bar)?;
        bar.set_position(before + slice.len() as u64);
        let chunk = Chunk {
            first: chunk_of(c).start,
            backend: backend_name.to_string(),
            seconds: start.elapsed().as_secs_f64(),
            results,
        };
        let text = serde_json::to_vec(&chunk).map_err(|e| Error::Io(std::io::Error::other(e)))?;
        write_atomic(&path, &text)?;
    }
    bar.finish_and_clear();
    if let Some((k, n)) = options.shard {
        return Ok(EnsembleSummary {
            title: case.title.clone(),
            analysis: format!("{analysis:?}").to_lowercase(),
            backend: format!("{backend:?}").to_lowercase(),
            precision: format!("{precision:?}").to_lowercase(),
            variants: in_range,
            converged: 0,
            step_cut: 0,
            failed: 0,
            failures: Vec::new(),
            solved_by_engine: 0,
            solved_by_cpu: 0,
            seconds: 0.0,
            uncertainty: None,
            outputs: vec![format!(
                "shard {k}/{n}: chunks {}..{} in {}/chunks; `holewall merge` gives the whole run",
                range.start,
                range.end,
                out.display()
            )],
        });
    }
    // Every chunk, read back (so a resumed or merged run has exactly these bits).
    let mut results = Vec::with_capacity(variants.len());
    let mut backend_name = "cpu";
    let mut seconds = 0.0;
    for c in 0..nchunks {
        let chunk = read_chunk(&chunk_path(out, c))?;
        if chunk.first != chunk_of(c).start || chunk.results.len() != chunk_of(c).len() {
            return Err(Error::Io(std::io::Error::other(format!(
                "{}: holds variants {}.. ({}), not the chunk's {:?}",
                chunk_path(out, c).display(),
                chunk.first,
                chunk.results.len(),
                chunk_of(c)
            ))));
        }
        if chunk.backend == "gpu" {
            backend_name = "gpu";
        }
        seconds += chunk.seconds;
        results.extend(chunk.results);
    }
    let stabs = stabilizer_sites(&case.model).len();
    let dynamic = analysis == Analysis::Dynamic;
    let mut outputs = vec!["variants.csv".to_string()];
    write_atomic(
        &out.join("variants.csv"),
        &variants_csv(
            &variants,
            &results,
            stabs,
            dynamic.then(|| whirl_threshold_hz(case.dynamics.as_ref().map_or(0.0, |d| d.duration))),
        )?,
    )?;
    let uncertainty = match monte_carlo {
        Some(mc) => {
            let (report, files) =
                uncertainty_report(mc, &case, &variants, &results, stabs, dynamic, out)?;
            outputs.extend(files);
            Some(report)
        }
        None => None,
    };
    let idx = |f: &dyn Fn(&VariantResult) -> Option<f64>| -> Vec<(f64, f64)> {
        results
            .iter()
            .enumerate()
            .filter_map(|(i, r)| f(r).filter(|x| x.is_finite()).map(|y| (i as f64, y)))
            .collect()
    };
    if let Some(file) = broomstick(&case, &variants, &results, out)? {
        outputs.push(file);
    }
    if monte_carlo.is_none() {
        line_plot(
            &out.join("neutral_point.png"),
            &format!("{}: neutral point over the variants", case.title),
            "variant",
            "neutral point from the bit (m)",
            &[Series {
                name: "neutral point",
                points: idx(&|r| r.neutral_point_from_bit_m),
            }],
            &[],
        )?;
        outputs.push("neutral_point.png".into());
        let names: Vec<String> = (1..=stabs).map(|k| format!("stab{k}")).collect();
        // One line per stabilizer of a per-stabilizer quantity over the variants.
        let per_stabilizer = |file: &str,
                              title: &str,
                              y_label: &str,
                              f: &dyn Fn(&StabilizerQoi) -> Option<f64>|
         -> Result<(), Error> {
            let series: Vec<Series> = (0..stabs)
                .map(|k| Series {
                    name: &names[k],
                    points: idx(&|r| r.stabilizers.get(k).and_then(f)),
                })
                .collect();
            line_plot(
                &out.join(file),
                &format!("{}: {title}", case.title),
                "variant",
                y_label,
                &series,
                &[],
            )?;
            Ok(())
        };
        per_stabilizer(
            "side_force.png",
            "largest side force per stabilizer",
            "side force (N)",
            &|q| Some(q.max_side_force_n),
        )?;
        outputs.push("side_force.png".into());
        if dynamic {
            per_stabilizer(
                "whirl.png",
                "whirl frequency (+ forward, − backward)",
                "whirl (Hz)",
                &|q| q.whirl_hz,
            )?;
            outputs.push("whirl.png".into());
        }
        for name in &series {
            let v = variants
                .iter()
                .find(|v| &v.name == name)
                .ok_or_else(|| Error::Io(std::io::Error::other(format!("no variant {name}"))))?;
            let mut c = case.clone();
            c.model = apply(&case, v).map_err(|e| Error::Io(std::io::Error::other(e)))?;
            let dir = out.join("series").join(name);
            super::run_cmd::run_case(&c, &dir, false)?;
            outputs.push(format!("series/{name}/"));
        }
    }
    let count = |s: Status| results.iter().filter(|r| r.status == s).count();
    let summary = EnsembleSummary {
        title: case.title.clone(),
        analysis: if dynamic { "dynamic" } else { "static" }.into(),
        backend: backend_name.into(),
        precision: if backend_name == "gpu" && precision == Precision::F32 {
            "f32"
        } else {
            "f64"
        }
        .into(),
        variants: variants.len(),
        converged: count(Status::Converged),
        step_cut: count(Status::StepCut),
        failed: count(Status::Failed),
        failures: results
            .iter()
            .filter(|r| r.status == Status::Failed)
            .map(|r| (r.name.clone(), r.reason.clone()))
            .collect(),
        solved_by_engine: results
            .iter()
            .filter(|r| r.status != Status::Failed && r.solved_by == SolvedBy::Engine)
            .count(),
        solved_by_cpu: results
            .iter()
            .filter(|r| r.status != Status::Failed && r.solved_by == SolvedBy::Cpu)
            .count(),
        seconds,
        uncertainty,
        outputs,
    };
    write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .unwrap_or_default()
            .as_bytes(),
    )?;
    Ok(summary)
}

/// The quantities of interest of every variant as columns (NaN where a variant has none).
pub fn qoi_columns(
    results: &[VariantResult],
    stabs: usize,
    dynamic: bool,
) -> Vec<crate::uq::report::Qoi> {
    use crate::uq::report::{Qoi, Unit};
    let col = |name: String, unit: Unit, f: &dyn Fn(&VariantResult) -> Option<f64>| Qoi {
        name,
        unit,
        values: results.iter().map(|r| f(r).unwrap_or(f64::NAN)).collect(),
    };
    let mut q = vec![
        col("neutral_point_from_bit_m".into(), Unit::Length, &|r| {
            r.neutral_point_from_bit_m
        }),
        col("hook_load_n".into(), Unit::Force, &|r| r.hook_load_n),
        col("max_surface_torque_nm".into(), Unit::Torque, &|r| {
            Some(r.max_surface_torque_nm)
        }),
        col(
            "max_side_force_per_length_n_per_m".into(),
            Unit::ForcePerLength,
            &|r| r.string.max_side_force_per_length_n_per_m,
        ),
    ];
    // Flags as 0/1: their mean is the probability (e.g. that the string buckles).
    let as_number = |b: Option<bool>| b.map(|b| if b { 1.0 } else { 0.0 });
    if dynamic {
        q.push(col("stick_slip_severity".into(), Unit::Ratio, &|r| {
            r.string.stick_slip_severity
        }));
    } else {
        q.push(col("sinusoidal_buckling".into(), Unit::Ratio, &|r| {
            as_number(r.string.sinusoidal_buckling)
        }));
        q.push(col("helical_buckling".into(), Unit::Ratio, &|r| {
            as_number(r.string.helical_buckling)
        }));
    }
    for k in 0..stabs {
        q.push(col(
            format!("stab{}_max_side_force_n", k + 1),
            Unit::Force,
            &|r| r.stabilizers.get(k).map(|s| s.max_side_force_n),
        ));
        q.push(col(
            format!("stab{}_max_lateral_m", k + 1),
            Unit::Length,
            &|r| r.stabilizers.get(k).map(|s| s.max_lateral_m),
        ));
        if dynamic {
            q.push(col(
                format!("stab{}_whirl_hz", k + 1),
                Unit::Frequency,
                &|r| r.stabilizers.get(k).and_then(|s| s.whirl_hz),
            ));
        }
    }
    q
}

/// Statistics, sensitivities and plots of a `--samples` run.
fn uncertainty_report(
    mc: &crate::uq::report::MonteCarlo,
    case: &Case,
    variants: &[Variant],
    results: &[VariantResult],
    stabs: usize,
    dynamic: bool,
    out: &Path,
) -> Result<(crate::uq::report::UncertaintyReport, Vec<String>), Error> {
    let qois = qoi_columns(results, stabs, dynamic);
    let keys: Vec<crate::ensemble::Key> = variants
        .first()
        .map(|v| v.overrides.iter().map(|(k, _)| k.clone()).collect())
        .unwrap_or_default();
    let inputs: Vec<(crate::ensemble::Key, Vec<f64>)> = keys
        .iter()
        .enumerate()
        .map(|(k, key)| {
            (
                key.clone(),
                variants.iter().map(|v| v.overrides[k].1).collect(),
            )
        })
        .collect();
    let failed: Vec<bool> = results.iter().map(|r| r.status == Status::Failed).collect();
    let report = crate::uq::report::analyse(mc, &inputs, &qois, &failed);
    let files = crate::uq::report::plot(&report, &inputs, &qois, out, &case.title)?;
    Ok((report, files))
}

/// The Monte Carlo request from the command line (`None` without `--samples`); percentiles
/// in 0–100 and `QOI=VALUE` thresholds, else an input error (exit 2).
pub fn monte_carlo(
    samples: Option<usize>,
    seed: u64,
    sampling: crate::uq::Sampling,
    percentiles: &[f64],
    exceed: &[String],
    sobol_indices: bool,
) -> Result<Option<crate::uq::report::MonteCarlo>, Error> {
    let err = |key: &str, message: String| -> Error {
        InputError {
            source_name: "command line".into(),
            line: 0,
            key: key.into(),
            message,
        }
        .into()
    };
    let Some(samples) = samples else {
        if !percentiles.is_empty() || !exceed.is_empty() {
            return Err(err(
                "--samples",
                "--percentile and --exceed need --samples N".into(),
            ));
        }
        return Ok(None);
    };
    if samples == 0 {
        return Err(err("--samples", "at least 1".into()));
    }
    if sobol_indices && sampling != crate::uq::Sampling::Sobol {
        return Err(err(
            "--sobol-indices",
            "needs --sampling sobol (the Saltelli design is built on Sobol points)".into(),
        ));
    }
    if let Some(p) = percentiles.iter().find(|p| !(0.0..=100.0).contains(*p)) {
        return Err(err("--percentile", format!("{p} is outside 0 … 100")));
    }
    let thresholds = exceed
        .iter()
        .map(|e| {
            let (name, value) = e
                .split_once('=')
                .ok_or_else(|| err("--exceed", format!("{e:?}: expected QOI=VALUE")))?;
            let v: f64 = value.trim().parse().map_err(|_| {
                err(
                    "--exceed",
                    format!("{e:?}: {value:?} is not a number (SI units)"),
                )
            })?;
            Ok((name.trim().to_string(), v))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    Ok(Some(crate::uq::report::MonteCarlo {
        samples,
        seed,
        sampling,
        percentiles: percentiles.to_vec(),
        thresholds,
        sobol_indices,
    }))
}

/// Variants per result chunk unless `--chunk-size` says otherwise.
pub const DEFAULT_CHUNK: usize = 256;

/// Options of an ensemble run beyond the case, the variants file and the backend.
#[derive(Clone, Debug, Default)]
pub struct EnsembleOptions {
    /// Monte Carlo sampling of `[ensemble.uncertain]` (`--samples`).
    pub monte_carlo: Option<crate::uq::report::MonteCarlo>,
    /// Variants per result chunk (0: [`DEFAULT_CHUNK`]).
    pub chunk_size: usize,
    /// Run only the K-th (1-based) of N slices of the chunks (`--shard K/N`).
    pub shard: Option<(usize, usize)>,
    /// Replace the outputs of another run in the output folder (`--force`).
    pub force: bool,
}

/// `run.json`: what a run was asked, to resume it, refuse another run's folder, and merge
/// shards.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// FNV-1a 64 of the case text, the variants file's text and every option that changes
    /// results or the report (hex).
    pub identity: String,
    /// The case file.
    pub case: std::path::PathBuf,
    /// The variants file, if any.
    pub variants_file: Option<std::path::PathBuf>,
    /// `cpu`, `gpu` or `auto`.
    pub backend: BackendChoice,
    /// Precision asked for.
    pub precision: Precision,
    /// Monte Carlo request.
    pub monte_carlo: Option<crate::uq::report::MonteCarlo>,
    /// Variants per chunk.
    pub chunk_size: usize,
    /// Variants in the whole run.
    pub variants: usize,
    /// Chunks in the whole run.
    pub chunks: usize,
    /// This folder's shard (K, N), or the whole run.
    pub shard: Option<(usize, usize)>,
}

fn fnv1a(bytes: &[u8], mut h: u64) -> u64 {
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

impl Manifest {
    fn new(
        case_path: &Path,
        variants_file: Option<&Path>,
        backend: BackendChoice,
        precision: Precision,
        options: &EnsembleOptions,
        chunk_size: usize,
        variants: usize,
    ) -> Result<Manifest, Error> {
        let mut h = 0xcbf29ce484222325u64;
        h = fnv1a(&std::fs::read(case_path)?, h);
        if let Some(f) = variants_file {
            h = fnv1a(b"\0variants\0", h);
            h = fnv1a(&std::fs::read(f)?, h);
        }
        let tail = format!(
            "\0{backend:?}\0{precision:?}\0{:?}\0{chunk_size}\0{variants}",
            options.monte_carlo
        );
        h = fnv1a(tail.as_bytes(), h);
        let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        Ok(Manifest {
            identity: format!("{h:016x}"),
            case: abs(case_path),
            variants_file: variants_file.map(abs),
            backend,
            precision,
            monte_carlo: options.monte_carlo.clone(),
            chunk_size,
            variants,
            chunks: variants.div_ceil(chunk_size),
            shard: options.shard,
        })
    }
}

/// One chunk of results, `chunks/chunk_NNNNNN.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Chunk {
    /// Index of its first variant.
    first: usize,
    /// Where it ran.
    backend: String,
    /// Wall time (s).
    seconds: f64,
    /// Results in variant order.
    results: Vec<VariantResult>,
}

fn chunk_path(out: &Path, c: usize) -> std::path::PathBuf {
    out.join("chunks").join(format!("chunk_{c:06}.json"))
}

fn read_chunk(path: &Path) -> Result<Chunk, Error> {
    let text = std::fs::read(path)
        .map_err(|e| Error::Io(std::io::Error::other(format!("{}: {e}", path.display()))))?;
    serde_json::from_slice(&text)
        .map_err(|e| Error::Io(std::io::Error::other(format!("{}: {e}", path.display()))))
}

/// The files a run writes into its folder (what `--force` clears).
fn is_run_output(name: &str) -> bool {
    matches!(
        name,
        "run.json" | "summary.json" | "variants.csv" | "chunks" | "series"
    ) || name.ends_with(".png")
}

fn out_error(out: &Path, message: String) -> Error {
    InputError {
        source_name: "--out".into(),
        line: 0,
        key: out.display().to_string(),
        message,
    }
    .into()
}

/// Checks the output folder before any work: a fresh or empty folder, or one holding this
/// very run (resumed: its chunks are kept); another run's folder, or a folder with other
/// files, is refused unless `force` (which removes the earlier run's files, never others).
/// Writes `run.json`.
pub fn prepare_out(out: &Path, manifest: &Manifest, force: bool) -> Result<(), Error> {
    if out.exists() && !out.is_dir() {
        return Err(out_error(out, "is a file, not a folder".into()));
    }
    if out.is_dir() {
        let run_json = out.join("run.json");
        let same = std::fs::read(&run_json)
            .ok()
            .and_then(|t| serde_json::from_slice::<Manifest>(&t).ok())
            .is_some_and(|m| m.identity == manifest.identity && m.shard == manifest.shard);
        let entries: Vec<String> = std::fs::read_dir(out)?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        if !same && !entries.is_empty() {
            let ours = entries.iter().all(|n| is_run_output(n));
            if !force {
                return Err(out_error(
                    out,
                    if run_json.exists() {
                        "holds a run of other inputs; give another --out, or --force to replace it"
                            .into()
                    } else {
                        "is not empty; give an empty or new folder, or --force to replace a run's files there".into()
                    },
                ));
            }
            if !ours && !run_json.exists() {
                return Err(out_error(
                    out,
                    "holds files that are not a run's outputs; --force replaces only a run's, give an empty folder".into(),
                ));
            }
            for n in entries.iter().filter(|n| is_run_output(n)) {
                let p = out.join(n);
                if p.is_dir() {
                    std::fs::remove_dir_all(&p)?;
                } else {
                    std::fs::remove_file(&p)?;
                }
            }
        }
    }
    std::fs::create_dir_all(out.join("chunks"))
        .map_err(|e| out_error(out, format!("cannot create it: {e}")))?;
    let text =
        serde_json::to_vec_pretty(manifest).map_err(|e| Error::Io(std::io::Error::other(e)))?;
    write_atomic(&out.join("run.json"), &text)
        .map_err(|e| out_error(out, format!("cannot write into it: {e}")))?;
    Ok(())
}

/// Runs `variants` on the GPU engine (`gpu`) or the CPU: their results, and where they ran.
fn compute(
    case: &Case,
    analysis: Analysis,
    variants: &[Variant],
    gpu: Option<&'static crate::gpu::GpuContext>,
    precision: Precision,
    bar: &indicatif::ProgressBar,
) -> Result<(Vec<VariantResult>, &'static str), Error> {
    let mut backend_name = "cpu";
    let results = match (gpu, analysis) {
        (Some(ctx), Analysis::Static) => match if precision == Precision::F32 {
            run_static_gpu::<f32>(case, variants, ctx, bar)?
        } else {
            run_static_gpu::<f64>(case, variants, ctx, bar)?
        } {
            Some(r) => {
                backend_name = "gpu";
                r
            }
            None => {
                eprintln!("holewall: the variants differ in their mesh or number of contact sites; running them on the CPU");
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
                eprintln!("holewall: {why}; running the variants on the CPU");
                run_variants_cpu(case, analysis, variants, bar)
            }
        },
        (None, _) => run_variants_cpu(case, analysis, variants, bar),
    };
    if backend_name == "gpu" {
        let rerun = results
            .iter()
            .filter(|r| r.solved_by == SolvedBy::Cpu)
            .count();
        if rerun > 0 {
            eprintln!(
                "holewall: the engine failed {rerun} of {} variants; they were re-run on the CPU (variants.csv: solved_by, reason)",
                results.len()
            );
        }
    }
    Ok((results, backend_name))
}

/// `holewall merge`: the shards in `dirs` (one run's `--shard K/N` folders, every K once)
/// into `out`, which then holds exactly what the run without shards would write.
pub fn merge(
    out: &Path,
    dirs: &[std::path::PathBuf],
    show_progress: bool,
) -> Result<EnsembleSummary, Error> {
    let read = |d: &std::path::PathBuf| -> Result<Manifest, Error> {
        let p = d.join("run.json");
        let t = std::fs::read(&p)
            .map_err(|e| out_error(d, format!("no run.json ({e}): not a holewall run folder")))?;
        serde_json::from_slice(&t).map_err(|e| out_error(d, format!("run.json: {e}")))
    };
    let manifests = dirs.iter().map(read).collect::<Result<Vec<_>, Error>>()?;
    let first = manifests
        .first()
        .ok_or_else(|| out_error(out, "no shard folders given".into()))?;
    let n = match first.shard {
        Some((_, n)) => n,
        None => return Err(out_error(&dirs[0], "is a whole run, not a shard".into())),
    };
    let mut seen = vec![false; n];
    for (d, m) in dirs.iter().zip(&manifests) {
        if m.identity != first.identity {
            return Err(out_error(
                d,
                format!(
                    "is a shard of another run (identity {} against {})",
                    m.identity, first.identity
                ),
            ));
        }
        match m.shard {
            Some((k, nn)) if nn == n && (1..=n).contains(&k) && !seen[k - 1] => seen[k - 1] = true,
            other => {
                return Err(out_error(
                    d,
                    format!("shard {other:?} does not fit {n} shards given once each"),
                ))
            }
        }
    }
    if let Some(k) = seen.iter().position(|s| !s) {
        return Err(out_error(out, format!("shard {}/{n} is missing", k + 1)));
    }
    let mut whole = first.clone();
    whole.shard = None;
    prepare_out(out, &whole, false)?;
    for (d, m) in dirs.iter().zip(&manifests) {
        let (k, _) = m.shard.unwrap_or((1, 1));
        for c in (k - 1) * whole.chunks / n..k * whole.chunks / n {
            let from = chunk_path(d, c);
            if !from.exists() {
                return Err(out_error(
                    d,
                    format!("chunk {c} is missing: the shard did not finish; run it again"),
                ));
            }
            let text = std::fs::read(&from)?;
            write_atomic(&chunk_path(out, c), &text)?;
        }
    }
    let options = EnsembleOptions {
        monte_carlo: whole.monte_carlo.clone(),
        chunk_size: whole.chunk_size,
        shard: None,
        force: false,
    };
    run(
        &whole.case,
        whole.variants_file.as_deref(),
        whole.backend,
        whole.precision,
        out,
        show_progress,
        &options,
    )
}

/// `--shard K/N` (1 ≤ K ≤ N), else an input error.
pub fn parse_shard(text: &str) -> Result<(usize, usize), Error> {
    let bad = || -> Error {
        InputError {
            source_name: "command line".into(),
            line: 0,
            key: "--shard".into(),
            message: format!("{text:?}: expected K/N with 1 ≤ K ≤ N"),
        }
        .into()
    };
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// The bit's MD of a variant's model (its own with a `depth` key).
fn bit_md_of(case: &Case, model: &Model) -> f64 {
    model.nodes.last().map_or(case.bit_md, |n| n.md)
}

/// Whether a variant's model shares the case's mesh and number of contact sites (what the
/// engine needs: a `depth` variant has a mesh of its own).
fn same_mesh(case: &Case, m: &Model) -> bool {
    m.sites.len() == case.model.sites.len()
        && m.nodes.len() == case.model.nodes.len()
        && m.nodes
            .iter()
            .zip(&case.model.nodes)
            .all(|(a, b)| a.md == b.md)
}

/// The classic T&D "broomstick" when the variants vary `depth`: hook load against bit
/// depth, one line per combination of the other keys (mode, friction, …). `None` without a
/// `depth` key.
fn broomstick(
    case: &Case,
    variants: &[Variant],
    results: &[VariantResult],
    out: &Path,
) -> Result<Option<String>, Error> {
    use crate::ensemble::Param;
    let has_depth = |v: &Variant| v.overrides.iter().any(|(k, _)| k.param == Param::Depth);
    if variants.is_empty() || !variants.iter().all(has_depth) {
        return Ok(None);
    }
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for (v, r) in variants.iter().zip(results) {
        let depth = v
            .overrides
            .iter()
            .find(|(k, _)| k.param == Param::Depth)
            .map(|(_, d)| *d)
            .unwrap_or(f64::NAN);
        let label = v
            .overrides
            .iter()
            .filter(|(k, _)| k.param != Param::Depth)
            .map(|(k, x)| match k.param {
                Param::Mode => k.format(*x),
                _ => format!("{} {}", k.name, crate::plots::tick(x)),
            })
            .collect::<Vec<_>>()
            .join(", ");
        let Some(hook) = r.hook_load_n.filter(|h| h.is_finite()) else {
            continue;
        };
        match lines.iter_mut().find(|(l, _)| *l == label) {
            Some((_, pts)) => pts.push((depth, hook * 1e-3)),
            None => lines.push((label, vec![(depth, hook * 1e-3)])),
        }
    }
    for (_, pts) in &mut lines {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let series: Vec<Series> = lines
        .iter()
        .map(|(l, pts)| Series {
            name: l,
            points: pts.clone(),
        })
        .collect();
    line_plot(
        &out.join("broomstick.png"),
        &format!("{}: hook load against bit depth", case.title),
        "bit depth, MD (m)",
        "hook load (kN)",
        &series,
        &[],
    )?;
    Ok(Some("broomstick.png".into()))
}

/// A node's share of the string: half of each element beside it (m).
fn tributary_length(model: &Model, node: usize) -> f64 {
    let n = model.nodes.len();
    let mut l = 0.0;
    if node > 0 {
        l += 0.5 * model.elements[node - 1].length0;
    }
    if node + 1 < n {
        l += 0.5 * model.elements[node].length0;
    }
    l.max(1e-9)
}

/// A whirl slower than one orbit over the fit window (the second half of the run) is no
/// whirl: `None` direction below this frequency (Hz).
pub fn whirl_threshold_hz(duration: f64) -> f64 {
    1.0 / (0.5 * duration).max(1e-9)
}
