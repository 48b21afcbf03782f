//! The dynamic ensemble through the kernels: generalised-α steps of V variants in
//! lockstep (as [`crate::solve::dynamics::Dynamics::step`], lumped mass), each Newton
//! iteration made of the predictor, beam, sites, contact, dynamic assembly, block LU and
//! norms kernels, and the per-variant residual line search of the CPU integrator.
//!
//! Every variant takes the same steps. A variant whose Newton fails at a step (non-finite
//! residual, singular matrix, no convergence in the iterations) is frozen with the reason
//! and the time; the caller re-runs it on the CPU, whose integrator cuts the step. The
//! others go on, unaffected: no kernel mixes variants.
//!
//! Supported: lumped mass, mass-proportional Rayleigh damping (`a0`), the table's spin and
//! the hook's travel at the top, every contact law. Not here (the caller runs those on the
//! CPU): consistent mass and stiffness-proportional damping (`a1`, which needs the initial
//! tangent per variant), and load factors in time.

use crate::kernels::assemble::{assemble, AssemblyInputs, DynamicInputs};
use crate::kernels::block_lu::{block_lu, ChainBatch, SOLVED};
use crate::kernels::contact::{contact, ContactBatch, ContactOutputs};
use crate::kernels::dynamics::{
    accelerate, inertial_scale, predict, DynamicBatch, StepCoefficients, TOP_LEN,
};
use crate::kernels::sites::gather_sites_dynamic;
use crate::kernels::update::{norms, Norms};
use crate::model::Model;
use crate::physics::contact::{ContactMode, PARAMS_LEN};
use crate::physics::mass::MassKind;
use crate::physics::Real;
use crate::solve::dynamics::{DynamicOptions, Dynamics};
use crate::solve::statics::StaticState;

use super::{ensemble_tables, Convergence, EnsembleTables, KernelPath, TwinPath};

/// What a dynamic chunk adds to [`EnsembleTables`].
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
    /// The state at t = 0 (displacements from the base, [`EnsembleTables::base`]: each
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
}

/// A chunk of variants held by a kernel path for a dynamic run: the state at `t_n`, the
/// Newton unknown `v̇_{n+1}`, a trial state and its system.
pub trait DynamicEnsemble<T> {
    /// Starts a step: its coefficients and the top's kinematics per variant
    /// (`TOP_LEN · V`); the unknown starts at `v̇_n`.
    fn begin_step(&mut self, c: &StepCoefficients<T>, top: &[T]) -> Result<(), String>;
    /// Predicts at the unknown, evaluates and solves: the norms of the residual and the
    /// correction `Δ` (α = 1), the solve's status and the inertial force scale per variant.
    fn iterate(&mut self) -> Result<Iteration<T>, String>;
    /// The residual at `v̇ + α Δ` (line search): its norms with `Δ`, `α`.
    fn trial(&mut self, alpha: &[T]) -> Result<Norms<T>, String>;
    /// The unknown `+= α Δ`.
    fn correct(&mut self, alpha: &[T]) -> Result<(), String>;
    /// Ends the step: the state at `t_{n+1}` from the unknown.
    fn end_step(&mut self) -> Result<(), String>;
    /// The state, read back.
    fn state(&mut self) -> Result<DynamicBatch<T>, String>;
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

/// A chunk's start: its tables, each variant's force scale, and what moves the top.
struct Start<T> {
    tables: DynamicTables<T>,
    /// The base: each variant's static equilibrium ([`EnsembleTables::base`]).
    base: Vec<f64>,
    f_ref: Vec<f64>,
    driven: bool,
    lowered: bool,
}

/// The start of every variant: the CPU integrator's initial state (consistent
/// accelerations) from its static equilibrium, and its force scale.
fn dynamic_tables<T: Real>(
    models: &[Model],
    starts: &[StaticState],
    density: &[f64],
    options: &DynamicOptions,
) -> Result<Start<T>, String> {
    let t = |x: f64| T::from_f64_lossy(x);
    let (v, n) = (models.len(), models[0].nodes.len());
    let p = models[0].sites.len() * v;
    let mut start = DynamicBatch {
        num_variants: v,
        num_nodes: n,
        u: vec![T::zero(); 3 * n * v],
        rot: vec![T::zero(); 9 * n * v],
        vel: vec![T::zero(); 6 * n * v],
        acc: vec![T::zero(); 6 * n * v],
        vdot: vec![T::zero(); 6 * n * v],
    };
    let mut base = vec![0.0; 3 * n * v];
    let mut f_ref = Vec::with_capacity(v);
    let mut f_ext = vec![T::zero(); 6 * n * v];
    let mut pair_params = vec![T::zero(); PARAMS_LEN * p];
    let mut mass = Vec::new();
    let mut inertia0 = Vec::new();
    let mut top = (false, false);
    for (j, (m, q)) in models.iter().zip(starts).enumerate() {
        let mut d = Dynamics::new(m, *options, &|e| density[e]);
        let s = d.initial_state(q.clone())?;
        f_ref.push(d.reference_force());
        if j == 0 {
            let (ms, js) = d.lumped();
            mass = ms.iter().map(|&x| t(x)).collect();
            inertia0 = js.iter().flatten().flatten().map(|&x| t(x)).collect();
            top = d.top_motion();
        }
        for i in 0..n {
            for k in 0..3 {
                let at = (3 * i + k) * v + j;
                let from_reference = s.q.x[i][k] - m.nodes[i].position[k];
                if i > 0 {
                    base[at] = from_reference;
                }
                start.u[at] = t(from_reference - base[at]);
            }
            for r in 0..3 {
                for c in 0..3 {
                    start.rot[(9 * i + 3 * r + c) * v + j] = t(s.q.rot[i][r][c]);
                }
            }
            for k in 0..6 {
                let idx = (6 * i + k) * v + j;
                start.vel[idx] = t(s.v[6 * i + k]);
                start.acc[idx] = t(s.a[6 * i + k]);
                start.vdot[idx] = t(s.vdot[6 * i + k]);
            }
        }
        let loads = crate::solve::statics::external_loads(m);
        for dof in 0..6 * n {
            f_ext[dof * v + j] = t(loads[dof]);
        }
        for (k, site) in m.sites.iter().enumerate() {
            for (f, x) in site.params.to_array().into_iter().enumerate() {
                pair_params[f * p + k * v + j] = t(x);
            }
        }
    }
    Ok(Start {
        tables: DynamicTables {
            mass,
            inertia0,
            a0: options.rayleigh.0,
            f_ext,
            pair_params,
            start,
        },
        base,
        f_ref,
        driven: top.0,
        lowered: top.1,
    })
}

/// One variant's dynamic result.
#[derive(Clone, Debug)]
pub struct DynamicResult {
    /// Status.
    pub status: DynamicStatus,
    /// Newton iterations of every step taken.
    pub iterations: Vec<usize>,
}

/// Runs every variant from its static equilibrium `starts[j]` to `t_end` in steps of
/// `options.dt` on `path`, calling `observe(first_variant, t, state)` for each chunk after
/// every `every`-th step (0: never). `density` gives each element's steel density.
#[allow(clippy::too_many_arguments)]
pub fn run_dynamic_ensemble<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    starts: &[StaticState],
    density: &[f64],
    path: &P,
    options: &DynamicOptions,
    t_end: f64,
    every: usize,
    observe: &mut dyn FnMut(usize, f64, &DynamicBatch<T>),
) -> Result<Vec<DynamicResult>, String> {
    if let Some(why) = unsupported(options) {
        return Err(why);
    }
    super::check_same_mesh(models)?;
    let chunk = path.max_chunk(&models[0]).max(1);
    let mut results = Vec::with_capacity(models.len());
    for (c, (group, group_starts)) in models.chunks(chunk).zip(starts.chunks(chunk)).enumerate() {
        let first = c * chunk;
        let mut obs = |t: f64, s: &DynamicBatch<T>| observe(first, t, s);
        results.extend(run_chunk(
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

#[allow(clippy::too_many_arguments)]
fn run_chunk<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    starts: &[StaticState],
    density: &[f64],
    path: &P,
    options: &DynamicOptions,
    t_end: f64,
    every: usize,
    observe: &mut dyn FnMut(f64, &DynamicBatch<T>),
) -> Result<Vec<DynamicResult>, String> {
    let t = |x: f64| T::from_f64_lossy(x);
    let mut tables = ensemble_tables::<T>(models)?;
    // The contact terms of the dynamic scene (damping where some c > 0).
    let mut batch = ContactBatch::<T>::new(1, tables.pair_node.len());
    let Start {
        tables: dynamic,
        base,
        f_ref,
        driven,
        lowered,
    } = dynamic_tables::<T>(models, starts, density, options)?;
    batch.pair_params = dynamic.pair_params.clone();
    tables.terms = batch.required_terms(models[0].friction, ContactMode::Dynamic);
    let v = tables.num_variants;
    tables.set_base(&models[0], base);
    let Convergence {
        tolerance,
        small_residual,
        step_floor,
    } = Convergence::for_path::<T>(
        options.tolerance,
        &tables.node_ref,
        Some(&tables.base),
        &dynamic.start.u,
        v,
    );
    let f32_path = std::mem::size_of::<T>() == 4;
    let mut ensemble = path.open_dynamic(&models[0], &tables, &dynamic)?;
    let p = options.alpha;
    let ratio = (1.0 - p.alpha_f) / (1.0 - p.alpha_m);
    let mut status = vec![DynamicStatus::Finished; v];
    let mut iterations = vec![Vec::new(); v];
    let mut time = 0.0;
    let mut step = 0usize;
    let minus_one = T::zero() - T::one();
    // The CPU integrator's table and hook, per variant.
    let cpu: Vec<Dynamics> = models
        .iter()
        .map(|m| Dynamics::new(m, *options, &|e| density[e]))
        .collect();
    let top_z: Vec<f64> = models.iter().map(|m| m.nodes[0].position[2]).collect();
    while time < t_end - 1e-12 {
        let h = options.dt.min(t_end - time);
        let t1 = time + h;
        let hhb = h * h * p.beta * ratio;
        let coefficients = StepCoefficients {
            h: t(h),
            alpha_m: t(p.alpha_m),
            alpha_f: t(p.alpha_f),
            beta: t(p.beta),
            gamma: t(p.gamma),
            top_fixed: tables.fixed[0],
            driven,
            lowered,
        };
        let mut top = vec![T::zero(); TOP_LEN * v];
        for (j, d) in cpu.iter().enumerate() {
            let (phi, phidot, phiddot) = d.table(t1);
            let (zh, zhdot, zhddot) = d.hook(t1);
            let r = crate::physics::beam::rotation_exp(&[0.0, 0.0, phi]);
            for (k, x) in r.iter().flatten().enumerate() {
                top[k * v + j] = t(*x);
            }
            // The hook's travel as a displacement of the top node: (z0 + z_h) − z0.
            let travel = (top_z[j] + zh) - top_z[j];
            for (k, x) in [phidot, phiddot, travel, zhdot, zhddot]
                .into_iter()
                .enumerate()
            {
                top[(9 + k) * v + j] = t(x);
            }
        }
        ensemble.begin_step(&coefficients, &top)?;
        let mut done: Vec<bool> = status
            .iter()
            .map(|s| *s != DynamicStatus::Finished)
            .collect();
        let mut its = vec![0usize; v];
        for it in 1..=options.max_iterations {
            if done.iter().all(|&d| d) {
                break;
            }
            let Iteration {
                norms: now,
                status: st,
                inertial,
            } = ensemble.iterate()?;
            let mut alpha = vec![T::zero(); v];
            let mut converged = vec![false; v];
            let mut at_floor = vec![false; v];
            for j in 0..v {
                if done[j] {
                    continue;
                }
                let measure =
                    now.residual_max[j].to_f64_lossy() / f_ref[j].max(inertial[j].to_f64_lossy());
                if !measure.is_finite() {
                    status[j] = DynamicStatus::Failed(t1, "residual is not finite".into());
                    done[j] = true;
                    continue;
                }
                if st[j] != SOLVED {
                    status[j] = DynamicStatus::Failed(t1, "singular iteration matrix".into());
                    done[j] = true;
                    continue;
                }
                let step_norm = now.step_max[j].to_f64_lossy() * hhb;
                converged[j] = measure <= tolerance
                    || (step_norm <= step_floor[j] && measure <= small_residual);
                at_floor[j] = f32_path && measure <= small_residual;
                alpha[j] = minus_one;
                its[j] = it;
            }
            // Backtracking on the residual's 2-norm for the variants not converged (as the
            // CPU integrator): α halved up to 24 times; the full step kept when nothing
            // shorter lowers the residual. In f32 a variant whose residual is already at the
            // precision's floor takes the full step: there its residual norm is rounding
            // noise, which halving cannot lower, and each halving costs an evaluation.
            let norm0: Vec<f64> = now
                .residual_square
                .iter()
                .map(|x| x.to_f64_lossy().sqrt())
                .collect();
            let mut pending: Vec<bool> = (0..v)
                .map(|j| {
                    !done[j] && !converged[j] && !at_floor[j] && alpha[j].to_f64_lossy() != 0.0
                })
                .collect();
            let mut accepted = vec![false; v];
            let mut trials = 0;
            for _ in 0..24 {
                if !pending.iter().any(|&q| q) {
                    break;
                }
                trials += 1;
                let r = ensemble.trial(&alpha)?;
                for j in 0..v {
                    if !pending[j] {
                        continue;
                    }
                    let a = -alpha[j].to_f64_lossy();
                    let norm = r.residual_square[j].to_f64_lossy().sqrt();
                    if norm.is_finite() && norm <= (1.0 - 1e-4 * a) * norm0[j] {
                        pending[j] = false;
                        accepted[j] = true;
                    } else {
                        alpha[j] = alpha[j] * t(0.5);
                    }
                }
            }
            for j in 0..v {
                if !done[j] && !converged[j] && !accepted[j] {
                    alpha[j] = minus_one;
                }
            }
            ensemble.correct(&alpha)?;
            if std::env::var("HOLEWALL_DEBUG_NEWTON").is_ok() {
                eprintln!(
                    "  engine dyn t {t1:.6} it {it}: variant 0 residual {:.3e} α {:.4}; {} variants open, {trials} line-search trials",
                    now.residual_max[0].to_f64_lossy() / f_ref[0],
                    alpha[0].to_f64_lossy().abs(),
                    done.iter().filter(|&&d| !d).count()
                );
            }
            for j in 0..v {
                if converged[j] {
                    done[j] = true;
                    iterations[j].push(its[j]);
                }
            }
        }
        for j in 0..v {
            if !done[j] {
                status[j] = DynamicStatus::Failed(
                    t1,
                    format!(
                        "Newton did not converge in {} iterations",
                        options.max_iterations
                    ),
                );
            }
        }
        ensemble.end_step()?;
        time = t1;
        step += 1;
        if every > 0 && step.is_multiple_of(every) {
            let mut s = ensemble.state()?;
            // Displacements from the reference for the observer (summed in f64).
            for (w, b) in s.u.iter_mut().zip(&tables.base) {
                *w = t(b + w.to_f64_lossy());
            }
            observe(time, &s);
        }
    }
    Ok(status
        .into_iter()
        .zip(iterations)
        .map(|(status, iterations)| DynamicResult { status, iterations })
        .collect())
}

/// The twins' dynamic chunk (f64).
pub struct TwinDynamic<'a> {
    model: &'a Model,
    tables: EnsembleTables<f64>,
    dynamic: DynamicTables<f64>,
    contact: ContactBatch<f64>,
    coefficients: Option<StepCoefficients<f64>>,
    top: Vec<f64>,
    state: DynamicBatch<f64>,
    unknown: Vec<f64>,
    trial: DynamicBatch<f64>,
    delta: Vec<f64>,
}

impl<'a> TwinDynamic<'a> {
    /// Holds a chunk on the CPU twins.
    pub fn new(
        model: &'a Model,
        tables: &EnsembleTables<f64>,
        dynamic: &DynamicTables<f64>,
    ) -> Self {
        let p = tables.pair_node.len();
        let mut contact = ContactBatch::new(1, p);
        contact.site_normals = tables.pair_normals.clone();
        contact.pair_state = tables.pair_state.clone();
        contact.pair_params = dynamic.pair_params.clone();
        TwinDynamic {
            model,
            tables: tables.clone(),
            dynamic: dynamic.clone(),
            contact,
            coefficients: None,
            top: Vec::new(),
            state: dynamic.start.clone(),
            unknown: dynamic.start.vdot.clone(),
            trial: dynamic.start.clone(),
            delta: vec![0.0; 6 * tables.num_nodes * tables.num_variants],
        }
    }

    /// Predicts the trial at `vdot` and assembles its system.
    fn evaluate_at(&mut self, mut vdot: Vec<f64>) -> Result<ChainBatch<f64>, String> {
        let c = self.coefficients.ok_or("no step begun")?;
        predict(&c, &self.top, &self.state, &mut vdot, &mut self.trial);
        let t = &self.tables;
        let (v, n) = (t.num_variants, t.num_nodes);
        let tr = &self.trial;
        let (elem_force, elem_tangent) =
            crate::kernels::beam::beam(self.model, v, &tr.u, &tr.rot, &t.chords);
        gather_sites_dynamic(
            &t.pair_node,
            &t.pair_normals,
            tr,
            &t.pair_base,
            &mut self.contact.pair_state,
        );
        let mut out = ContactOutputs::new(self.contact.num_pairs());
        contact(&t.terms, &self.contact, &mut out);
        let p = options_coefficients(&c);
        Ok(assemble(&AssemblyInputs {
            num_variants: v,
            num_nodes: n,
            num_sites: t.num_sites,
            elem_force,
            elem_tangent,
            contact: out.values,
            contact_flag: out.contact,
            node_site: t.node_site.clone(),
            f_ext: self.dynamic.f_ext.clone(),
            basis: t.basis.clone(),
            fixed: t.fixed.clone(),
            dynamic: Some(DynamicInputs {
                coefficients: [p.0, p.1, self.dynamic.a0],
                mass: self.dynamic.mass.clone(),
                inertia0: self.dynamic.inertia0.clone(),
                rot: tr.rot.clone(),
                vel: tr.vel.clone(),
                vdot: tr.vdot.clone(),
                pair_normals: t.pair_normals.clone(),
            }),
        }))
    }
}

/// `(hγ', h²β')` of a step.
pub fn options_coefficients<T: Real>(c: &StepCoefficients<T>) -> (T, T) {
    let one = T::one();
    let ratio = (one - c.alpha_f) / (one - c.alpha_m);
    (c.h * c.gamma * ratio, c.h * c.h * c.beta * ratio)
}

impl DynamicEnsemble<f64> for TwinDynamic<'_> {
    fn begin_step(&mut self, c: &StepCoefficients<f64>, top: &[f64]) -> Result<(), String> {
        self.coefficients = Some(*c);
        self.top = top.to_vec();
        self.unknown = self.state.vdot.clone();
        Ok(())
    }
    fn iterate(&mut self) -> Result<Iteration<f64>, String> {
        let sys = self.evaluate_at(self.unknown.clone())?;
        // The top's prescribed accelerations, as the predictor wrote them.
        self.unknown = self.trial.vdot.clone();
        let (delta, status) = block_lu(&sys);
        self.delta = delta;
        let (v, n) = (self.tables.num_variants, self.tables.num_nodes);
        let norms = norms(&sys.rhs, &self.delta, &vec![1.0; v], n, v);
        let inertial = inertial_scale(&self.dynamic.mass, &self.unknown, n, v);
        Ok(Iteration {
            norms,
            status,
            inertial,
        })
    }
    fn trial(&mut self, alpha: &[f64]) -> Result<Norms<f64>, String> {
        let (v, n) = (self.tables.num_variants, self.tables.num_nodes);
        let cand = accelerate(&self.tables.basis, &self.unknown, &self.delta, alpha, n, v);
        let sys = self.evaluate_at(cand)?;
        Ok(norms(&sys.rhs, &self.delta, alpha, n, v))
    }
    fn correct(&mut self, alpha: &[f64]) -> Result<(), String> {
        let (v, n) = (self.tables.num_variants, self.tables.num_nodes);
        self.unknown = accelerate(&self.tables.basis, &self.unknown, &self.delta, alpha, n, v);
        Ok(())
    }
    fn end_step(&mut self) -> Result<(), String> {
        let c = self.coefficients.ok_or("no step begun")?;
        let mut vdot = self.unknown.clone();
        let mut next = self.state.clone();
        predict(&c, &self.top, &self.state, &mut vdot, &mut next);
        self.state = next;
        Ok(())
    }
    fn state(&mut self) -> Result<DynamicBatch<f64>, String> {
        Ok(self.state.clone())
    }
}

impl TwinPath {
    /// The twins' dynamic chunk.
    pub fn dynamic<'a>(
        &self,
        model: &'a Model,
        tables: &EnsembleTables<f64>,
        dynamic: &DynamicTables<f64>,
    ) -> TwinDynamic<'a> {
        TwinDynamic::new(model, tables, dynamic)
    }
}
