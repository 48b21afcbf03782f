//! The ensemble Newton iteration through the kernels (issue 5): one static solve for V
//! variants of one mesh, every iteration made of the kernels — beam, sites, contact,
//! assembly (with constraints), block LU, norms, update — on either kernel path: the CPU
//! twins ([`TwinPath`], f64) or the WGSL kernels ([`GpuPath`], f32 or f64).
//!
//! The schedule mirrors `statics::solve_static` without its adaptivity: gravity in full
//! from the low-side start with friction and bit loads off (λ = 0), then λ = ¼, ½, ¾, 1
//! (bit loads and friction scaled by λ); Newton with the solver's line search at each λ
//! (per variant: energy slope or residual decrease, α halved at most five times). A
//! variant whose Newton fails (singular pivot, a non-finite residual, no convergence within
//! the iterations) is flagged with the reason and frozen; the caller re-runs it on the CPU
//! with step control. Converged and frozen variants get α = 0, so they stop moving while
//! the others iterate.
//!
//! States are displacements `u` from the reference positions (kept in f64 on the host):
//! positions of kilometres would lose their millimetres in f32.
//!
//! Data stay where the path keeps them ([`Ensemble`]): on the GPU the configuration, the
//! assembled systems and every intermediate live in buffers made once per chunk of
//! variants; the host reads four numbers and a status per variant per solve or trial
//! (largest residual, largest step, `Δ·r`, `r·r`) and writes one α per variant. Variants are
//! split into chunks that fit the adapter's binding limits ([`KernelPath::max_chunk`]).
//!
//! Stabilizer moves are allowed: every (site, variant) pair carries its own node and hole
//! axis, so the variants need only share the mesh and the number of sites.

use crate::kernels::assemble::{assemble, AssemblyInputs, NO_SITE};
use crate::kernels::block_lu::{block_lu, ChainBatch, SOLVED};
use crate::kernels::contact::{contact, ContactBatch, STATE_LEN};
use crate::kernels::sites::gather_sites;
use crate::kernels::update::{norms, update, ConfigBatch, Norms};
use crate::model::Model;
use crate::physics::contact::{ContactMode, ContactTerms, PARAMS_LEN};
use crate::physics::Real;
use crate::solve::statics::{
    constraint_tables, reference_force, split_loads, StaticOptions, StaticState,
};

/// The convergence tests of a kernel path in its precision, per variant.
///
/// In f64 as the CPU solvers: the residual below `tolerance`, or the step at rounding level
/// (1e-12 of the largest coordinate) with the residual below 1e-6. In f32 the residual
/// stalls near 1e-4 of the force scale (nodal sums of element forces of 1e5 N, and
/// stiffnesses of 1e8 N/m times displacements rounded at 1e-8 m) and the steps at a few
/// 1e-7 m: a variant is converged when its step is down at 100 ε₃₂ of its displacements and
/// its residual below 1e4 ε₃₂ ≈ 1.2e-3 (the error this leaves is measured against f64 in
/// tests/engine.rs and tests/engine_dynamic.rs).
pub(crate) struct Convergence {
    /// Residual (relative to the force scale) that converges on its own.
    pub tolerance: f64,
    /// Residual below which a step at `step_floor` converges.
    pub small_residual: f64,
    /// Per variant: a step (m) at rounding level.
    pub step_floor: Vec<f64>,
}

impl Convergence {
    /// For a path in `T`, `v` variants with displacements `u` from `node_ref` shifted by
    /// `base` (`3 n V`; none: the reference). The f32 floor scales with the states
    /// themselves (their rounding), the f64 one with the coordinates.
    pub(crate) fn for_path<T: Real>(
        tolerance: f64,
        node_ref: &[f64],
        base: Option<&[f64]>,
        u: &[T],
        v: usize,
    ) -> Self {
        let f32_path = std::mem::size_of::<T>() == 4;
        let unit_roundoff = if f32_path {
            f64::from(f32::EPSILON)
        } else {
            f64::EPSILON
        };
        let step_floor = (0..v)
            .map(|j| {
                let largest = |shift: bool| {
                    (0..node_ref.len()).fold(0.0f64, |m, k| {
                        let b = base.map_or(0.0, |b| b[k * v + j]);
                        let x =
                            u[k * v + j].to_f64_lossy() + if shift { node_ref[k] + b } else { 0.0 };
                        m.max(x.abs())
                    })
                };
                if f32_path {
                    100.0 * unit_roundoff * (1.0 + largest(false))
                } else {
                    1e-12 * (1.0 + largest(true))
                }
            })
            .collect();
        Convergence {
            tolerance: tolerance.max(400.0 * unit_roundoff),
            small_residual: 1e-6f64.max(1e4 * unit_roundoff),
            step_floor,
        }
    }
}

/// What one chunk of variants shares and starts from, built once on the host.
#[derive(Clone, Debug)]
pub struct EnsembleTables<T> {
    /// Variants V in the chunk.
    pub num_variants: usize,
    /// Nodes n.
    pub num_nodes: usize,
    /// Sites S per variant.
    pub num_sites: usize,
    /// Translation basis per node, `9 n`.
    pub basis: Vec<T>,
    /// Fixed-DOF mask per node, `n`.
    pub fixed: Vec<u32>,
    /// Site at each (node, variant), `n V` ([`NO_SITE`] where none).
    pub node_site: Vec<u32>,
    /// Node of each pair `i = site · V + variant`, `P = S V`.
    pub pair_node: Vec<u32>,
    /// Reference position per node, `3 n` (f64: states are displacements from it).
    pub node_ref: Vec<f64>,
    /// Hole axis per pair, `3 P` (the contact kernel run with one "variant" per site).
    pub pair_normals: Vec<T>,
    /// Pair state (`d`, wall-relative velocity, spin), `7 P`, field-major.
    pub pair_state: Vec<T>,
    /// The start configuration (displacements `u` from the base and rotations).
    pub start: ConfigBatch<T>,
    /// The base the states are displacements from: its displacements from the reference,
    /// `3 n V`, in f64 — zero at the start of a static solve (the f32 engine moves it to
    /// the converged configuration at each load step); each variant's static equilibrium
    /// in a dynamic run (the top node's stays at the reference, where the hook's travel is
    /// prescribed). The states are then the motion from there — millimetres, where a
    /// kilometre string hangs metres down — so f32 keeps their digits.
    pub base: Vec<f64>,
    /// The base at every pair across its hole axis, `3 P`
    /// ([`crate::kernels::sites::pair_base`] of `base`).
    pub pair_base: Vec<T>,
    /// Base chords and stretches per element and variant, `4 (n − 1) V`
    /// ([`crate::kernels::beam::base_chords`] of `base`).
    pub chords: Vec<T>,
    /// Contact terms the scene uses (the contact kernel is compiled for these only).
    pub terms: ContactTerms,
}

impl<T: Real> EnsembleTables<T> {
    /// Moves the base to `base` (displacements from `model`'s reference, `3 n V`), with
    /// the pairs' and the elements' tables formed from it in f64.
    pub fn set_base(&mut self, model: &Model, base: Vec<f64>) {
        let t = |x: f64| T::from_f64_lossy(x);
        let v = self.num_variants;
        self.chords = crate::kernels::beam::base_chords(model, &base, v)
            .into_iter()
            .map(t)
            .collect();
        self.pair_base =
            crate::kernels::sites::pair_base(&self.pair_node, &self.pair_normals, &base, v)
                .into_iter()
                .map(t)
                .collect();
        self.base = base;
    }
}

/// A chunk of variants held by a kernel path: a current configuration with its assembled
/// system, a step `Δ`, and one trial configuration.
pub trait Ensemble<T> {
    /// Sets the external loads (`6 n V`) and the pairs' law parameters (`PARAMS_LEN · P`,
    /// field-major) of a load step.
    fn set_loads(&mut self, f_ext: &[T], pair_params: &[T]) -> Result<(), String>;
    /// Residual and constrained tangent at the current configuration.
    fn evaluate(&mut self) -> Result<(), String>;
    /// Solves the current system for `Δ`; the norms of its residual and `Δ` (α = 1) and
    /// the solve's status per variant.
    fn solve(&mut self) -> Result<(Norms<T>, Vec<u32>), String>;
    /// Trial = current + `α Δ`, evaluated; the norms of the trial's residual with `Δ`, `α`.
    fn trial(&mut self, alpha: &[T]) -> Result<Norms<T>, String>;
    /// Makes the last trial (configuration and system) the current one.
    fn accept_trial(&mut self);
    /// Current += `α Δ` (its system must be evaluated again).
    fn commit(&mut self, alpha: &[T]) -> Result<(), String>;
    /// The current configuration, read back.
    fn config(&mut self) -> Result<ConfigBatch<T>, String>;
    /// Moves the base to the current configuration, given as `tables` after
    /// [`EnsembleTables::set_base`] with the host's sum of the old base and the current
    /// displacements: the displacements from it are set to zero, the rotations kept (the
    /// system must be evaluated again).
    fn rebase(&mut self, tables: &EnsembleTables<T>) -> Result<(), String>;
}

/// A kernel path: makes the [`Ensemble`] of a chunk of variants.
pub trait KernelPath<T> {
    /// The most variants of `model` one chunk may hold.
    fn max_chunk(&self, model: &Model) -> usize;
    /// Uploads a chunk.
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
    ) -> Result<Box<dyn Ensemble<T> + 'a>, String>;
    /// Uploads a chunk for a dynamic run.
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
        dynamic: &dynamic::DynamicTables<T>,
    ) -> Result<Box<dyn dynamic::DynamicEnsemble<T> + 'a>, String>;
}

/// The CPU twins, f64.
pub struct TwinPath;

struct TwinEnsemble<'a> {
    model: &'a Model,
    tables: EnsembleTables<f64>,
    contact: ContactBatch<f64>,
    f_ext: Vec<f64>,
    config: [ConfigBatch<f64>; 2],
    system: [Option<ChainBatch<f64>>; 2],
    current: usize,
    delta: Vec<f64>,
}

impl TwinEnsemble<'_> {
    fn evaluate_slot(&mut self, slot: usize) {
        let t = &self.tables;
        let (v, n) = (t.num_variants, t.num_nodes);
        let c = &self.config[slot];
        let (elem_force, elem_tangent) =
            crate::kernels::beam::beam(self.model, v, &c.x, &c.rot, &t.chords);
        gather_sites(
            &t.pair_node,
            &c.x,
            &t.pair_base,
            v,
            &mut self.contact.pair_state,
        );
        let mut out = crate::kernels::contact::ContactOutputs::new(self.contact.num_pairs());
        contact(&t.terms, &self.contact, &mut out);
        self.system[slot] = Some(assemble(&AssemblyInputs {
            num_variants: v,
            num_nodes: n,
            num_sites: t.num_sites,
            elem_force,
            elem_tangent,
            contact: out.values,
            contact_flag: out.contact,
            node_site: t.node_site.clone(),
            f_ext: self.f_ext.clone(),
            basis: t.basis.clone(),
            fixed: t.fixed.clone(),
            dynamic: None,
        }));
    }

    fn rhs(&self, slot: usize) -> Result<&[f64], String> {
        self.system[slot]
            .as_ref()
            .map(|s| s.rhs.as_slice())
            .ok_or_else(|| "system not evaluated".to_string())
    }
}

impl Ensemble<f64> for TwinEnsemble<'_> {
    fn set_loads(&mut self, f_ext: &[f64], pair_params: &[f64]) -> Result<(), String> {
        self.f_ext = f_ext.to_vec();
        self.contact.pair_params = pair_params.to_vec();
        self.system = [None, None];
        Ok(())
    }
    fn evaluate(&mut self) -> Result<(), String> {
        self.evaluate_slot(self.current);
        Ok(())
    }
    fn solve(&mut self) -> Result<(Norms<f64>, Vec<u32>), String> {
        let sys = self.system[self.current]
            .as_ref()
            .ok_or("system not evaluated")?;
        let (delta, status) = block_lu(sys);
        self.delta = delta;
        let ones = vec![1.0; self.tables.num_variants];
        let n = norms(
            &sys.rhs,
            &self.delta,
            &ones,
            self.tables.num_nodes,
            self.tables.num_variants,
        );
        Ok((n, status))
    }
    fn trial(&mut self, alpha: &[f64]) -> Result<Norms<f64>, String> {
        let other = 1 - self.current;
        self.config[other] = self.config[self.current].clone();
        update(&mut self.config[other], &self.delta, alpha);
        self.evaluate_slot(other);
        Ok(norms(
            self.rhs(other)?,
            &self.delta,
            alpha,
            self.tables.num_nodes,
            self.tables.num_variants,
        ))
    }
    fn accept_trial(&mut self) {
        self.current = 1 - self.current;
    }
    fn commit(&mut self, alpha: &[f64]) -> Result<(), String> {
        update(&mut self.config[self.current], &self.delta, alpha);
        self.system[self.current] = None;
        Ok(())
    }
    fn config(&mut self) -> Result<ConfigBatch<f64>, String> {
        Ok(self.config[self.current].clone())
    }
    fn rebase(&mut self, tables: &EnsembleTables<f64>) -> Result<(), String> {
        self.tables = tables.clone();
        self.config[self.current].x.fill(0.0);
        self.system[self.current] = None;
        Ok(())
    }
}

impl KernelPath<f64> for TwinPath {
    fn max_chunk(&self, _model: &Model) -> usize {
        usize::MAX
    }
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<f64>,
    ) -> Result<Box<dyn Ensemble<f64> + 'a>, String> {
        let p = tables.pair_node.len();
        let mut contact = ContactBatch::new(1, p);
        contact.site_normals = tables.pair_normals.clone();
        contact.pair_state = tables.pair_state.clone();
        Ok(Box::new(TwinEnsemble {
            model,
            tables: tables.clone(),
            contact,
            f_ext: Vec::new(),
            config: [tables.start.clone(), tables.start.clone()],
            system: [None, None],
            current: 0,
            delta: vec![0.0; 6 * tables.num_nodes * tables.num_variants],
        }))
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<f64>,
        dynamic: &dynamic::DynamicTables<f64>,
    ) -> Result<Box<dyn dynamic::DynamicEnsemble<f64> + 'a>, String> {
        Ok(Box::new(self.dynamic(model, tables, dynamic)))
    }
}

/// The WGSL kernels on the shared GPU context, resident per chunk
/// ([`crate::gpu::ensemble::GpuEnsemble`]).
pub struct GpuPath(pub &'static crate::gpu::GpuContext);

impl<T: crate::gpu::contact::GpuReal> KernelPath<T> for GpuPath {
    fn max_chunk(&self, model: &Model) -> usize {
        crate::gpu::ensemble::max_variants(self.0, model, std::mem::size_of::<T>())
    }
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
    ) -> Result<Box<dyn Ensemble<T> + 'a>, String> {
        crate::gpu::ensemble::GpuEnsemble::new(self.0, model, tables)
            .map(|e| Box::new(e) as Box<dyn Ensemble<T> + 'a>)
            .map_err(|e| e.to_string())
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
        dynamic: &dynamic::DynamicTables<T>,
    ) -> Result<Box<dyn dynamic::DynamicEnsemble<T> + 'a>, String> {
        crate::gpu::ensemble::GpuDynamic::new(self.0, model, tables, dynamic)
            .map(|e| Box::new(e) as Box<dyn dynamic::DynamicEnsemble<T> + 'a>)
            .map_err(|e| e.to_string())
    }
}

/// How a variant's engine solve ended.
#[derive(Clone, Debug, PartialEq)]
pub enum EngineStatus {
    /// Converged at λ = 1.
    Converged,
    /// Failed: why (the caller re-runs it on the CPU with step control).
    Failed(String),
}

/// One variant's result: its configuration (f64) and status.
#[derive(Clone, Debug)]
pub struct EngineResult {
    /// Final configuration (meaningful when converged).
    pub state: StaticState,
    /// Status.
    pub status: EngineStatus,
    /// Newton iterations per load step.
    pub iterations: Vec<usize>,
}

/// An error unless every model shares the first one's mesh and number of sites.
pub(crate) fn check_same_mesh(models: &[Model]) -> Result<(), String> {
    let base = models.first().ok_or("no variants")?;
    for m in models {
        if m.nodes.len() != base.nodes.len()
            || m.elements.len() != base.elements.len()
            || m.sites.len() != base.sites.len()
        {
            return Err("variants differ in mesh or number of sites; run them on the CPU".into());
        }
    }
    Ok(())
}

/// The tables of a chunk of variants (all on the first one's mesh).
pub fn ensemble_tables<T: Real>(models: &[Model]) -> Result<EnsembleTables<T>, String> {
    check_same_mesh(models)?;
    let t = |x: f64| T::from_f64_lossy(x);
    let base = &models[0];
    let (v, n, s_count) = (models.len(), base.nodes.len(), base.sites.len());
    let (basis, fixed) = constraint_tables(base);
    let mut start = ConfigBatch {
        num_variants: v,
        num_nodes: n,
        x: vec![T::zero(); 3 * n * v],
        rot: vec![T::zero(); 9 * n * v],
        basis: basis.iter().map(|&b| t(b)).collect(),
    };
    for (j, m) in models.iter().enumerate() {
        let s = if m.sites.is_empty() {
            StaticState::initial(m)
        } else {
            StaticState::on_low_side(m)
        };
        for i in 0..n {
            for k in 0..3 {
                start.x[(3 * i + k) * v + j] = t(s.x[i][k] - base.nodes[i].position[k]);
            }
            for r in 0..3 {
                for c in 0..3 {
                    start.rot[(9 * i + 3 * r + c) * v + j] = t(s.rot[i][r][c]);
                }
            }
        }
    }
    let p = s_count * v;
    let mut node_site = vec![NO_SITE; n * v];
    let mut pair_node = vec![0u32; p];
    let mut pair_normals = vec![T::zero(); 3 * p];
    let mut pair_state = vec![T::zero(); STATE_LEN * p];
    let mut params = vec![T::zero(); PARAMS_LEN * p];
    for (j, m) in models.iter().enumerate() {
        for (k, site) in m.sites.iter().enumerate() {
            let i = k * v + j;
            node_site[site.node * v + j] = k as u32;
            pair_node[i] = site.node as u32;
            let axis = m.nodes[site.node].hole_axis;
            let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
            for a in 0..3 {
                pair_normals[3 * i + a] = t(axis[a] / len);
                pair_state[(3 + a) * p + i] = t(axis[a] * m.axial_speed);
            }
            pair_state[6 * p + i] = t(m.rotation_speed);
            for (f, x) in site.params.to_array().into_iter().enumerate() {
                params[f * p + i] = t(x);
            }
        }
    }
    let mut batch = ContactBatch::<T>::new(1, p);
    batch.pair_params = params;
    let terms = batch.required_terms(base.friction, ContactMode::Static);
    let node_ref: Vec<f64> = base.nodes.iter().flat_map(|nd| nd.position).collect();
    let mut tables = EnsembleTables {
        num_variants: v,
        num_nodes: n,
        num_sites: s_count,
        basis: start.basis.clone(),
        fixed,
        node_site,
        pair_node,
        node_ref,
        pair_normals,
        pair_state,
        start,
        base: Vec::new(),
        pair_base: Vec::new(),
        chords: Vec::new(),
        terms,
    };
    // The static solve starts from the reference as base.
    tables.set_base(base, vec![0.0; 3 * n * v]);
    Ok(tables)
}

/// Static equilibrium of every variant through `path`. All models share the mesh and the
/// number of sites; stabilizers may sit at other nodes per variant.
pub fn solve_static_ensemble<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &P,
    options: &StaticOptions,
) -> Result<Vec<EngineResult>, String> {
    solve_static_ensemble_with_progress(models, path, options, &mut |_| {})
}

/// As [`solve_static_ensemble`], reporting the fraction done (0 … 1) after every iteration
/// (for a progress bar). Chunks of [`KernelPath::max_chunk`] variants run one after another.
pub fn solve_static_ensemble_with_progress<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &P,
    options: &StaticOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Vec<EngineResult>, String> {
    check_same_mesh(models)?;
    let chunk = path.max_chunk(&models[0]).max(1);
    let total = models.len();
    let mut results = Vec::with_capacity(total);
    for (c, group) in models.chunks(chunk).enumerate() {
        let done_before = (c * chunk) as f64 / total as f64;
        let share = group.len() as f64 / total as f64;
        let mut report = |f: f64| progress(done_before + share * f);
        results.extend(solve_chunk(group, path, options, &mut report)?);
    }
    Ok(results)
}

fn solve_chunk<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &P,
    options: &StaticOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Vec<EngineResult>, String> {
    let tables = ensemble_tables::<T>(models)?;
    let (v, n) = (tables.num_variants, tables.num_nodes);
    let base = &models[0];
    let t = |x: f64| T::from_f64_lossy(x);
    let loads: Vec<(Vec<f64>, Vec<f64>)> = models.iter().map(split_loads).collect();
    let f_ref: Vec<f64> = models.iter().map(reference_force).collect();
    let p = tables.pair_node.len();
    let Convergence {
        tolerance,
        small_residual,
        step_floor,
    } = Convergence::for_path::<T>(
        options.tolerance,
        &tables.node_ref,
        None,
        &tables.start.x,
        v,
    );
    let mut ensemble = path.open(base, &tables)?;
    let mut status = vec![EngineStatus::Converged; v];
    let mut iterations = vec![Vec::new(); v];
    // In f32 each load step starts by moving the base to the configuration reached (its
    // displacements summed in f64 on the host), so the states are the step's motion, not
    // the metres from the reference; and full load is solved twice, the second time from
    // its own converged configuration as base: the answer's last digits are then f32's
    // rounding of millimetres, not of the string's whole sag (the neutral point, from
    // axial forces of EA·Δl/l, gains ≈ 2 digits; `docs/validation.md`).
    let f32_path = std::mem::size_of::<T>() == 4;
    let schedule: &[f64] = if f32_path {
        &[0.0, 0.25, 0.5, 0.75, 1.0, 1.0]
    } else {
        &[0.0, 0.25, 0.5, 0.75, 1.0]
    };
    let mut tables = tables;
    let minus_one = T::zero() - T::one();
    for (step, &lambda) in schedule.iter().enumerate() {
        if f32_path && step > 0 {
            let config = ensemble.config()?;
            let mut moved = tables.base.clone();
            for (b, w) in moved.iter_mut().zip(&config.x) {
                *b += w.to_f64_lossy();
            }
            tables.set_base(base, moved);
            ensemble.rebase(&tables)?;
        }
        // Loads and friction of this step.
        let mut f_ext = vec![T::zero(); 6 * n * v];
        let mut params = vec![T::zero(); PARAMS_LEN * p];
        for (j, m) in models.iter().enumerate() {
            let gamma = if m.sites.is_empty() { lambda } else { 1.0 };
            for d in 0..6 * n {
                f_ext[d * v + j] = t(gamma * loads[j].0[d] + lambda * loads[j].1[d]);
            }
            for (k, site) in m.sites.iter().enumerate() {
                let mut q = site.params;
                q.mu_t *= lambda;
                q.mu_l *= lambda;
                for (f, x) in q.to_array().into_iter().enumerate() {
                    params[f * p + k * v + j] = t(x);
                }
            }
        }
        ensemble.set_loads(&f_ext, &params)?;
        let mut done = vec![false; v];
        let mut polished = vec![false; v];
        let mut last_step = vec![f64::INFINITY; v];
        // Whether the current configuration's system is evaluated (the accepted trial's).
        let mut evaluated = false;
        for it in 1..=options.max_iterations {
            if !evaluated {
                ensemble.evaluate()?;
            }
            let (now, st) = ensemble.solve()?;
            let mut alpha = vec![T::zero(); v];
            for j in 0..v {
                if done[j] || status[j] != EngineStatus::Converged {
                    continue;
                }
                let measure = now.residual_max[j].to_f64_lossy() / f_ref[j];
                if !measure.is_finite() {
                    status[j] =
                        EngineStatus::Failed(format!("λ = {lambda}: residual is not finite"));
                } else if (measure <= tolerance && last_step[j] <= 1e-6)
                    || (last_step[j] <= step_floor[j] && measure <= small_residual)
                {
                    // As statics::newton: converged, or the step is down at rounding level
                    // (positions carry ≈1e-16·|x| of noise) with the residual small anyway.
                    // At full load one more full step polishes it (as solve_static).
                    if lambda == 1.0 && !polished[j] {
                        polished[j] = true;
                        alpha[j] = minus_one;
                        continue;
                    }
                    done[j] = true;
                    iterations[j].push(it - 1);
                } else if st[j] != SOLVED {
                    status[j] = EngineStatus::Failed(format!("λ = {lambda}: singular tangent"));
                } else {
                    alpha[j] = minus_one;
                }
            }
            if (0..v).all(|j| done[j] || status[j] != EngineStatus::Converged) {
                break;
            }
            // Line search per variant, as statics::newton: the full step unless it
            // overshoots (|s(α)| > |s(0)|, s = −Δ·r) and does not lower ‖r‖₂; halved at most
            // five times (the last, α = 1/32, is taken anyway).
            let s0: Vec<f64> = now
                .step_dot_residual
                .iter()
                .map(|x| -x.to_f64_lossy())
                .collect();
            let norm0: Vec<f64> = now
                .residual_square
                .iter()
                .map(|x| x.to_f64_lossy().sqrt())
                .collect();
            let mut pending: Vec<bool> = alpha.iter().map(|a| a.to_f64_lossy() != 0.0).collect();
            // The last trial evaluated holds every variant at its final α.
            let mut trial_is_final = false;
            for _ in 0..5 {
                if !pending.iter().any(|&q| q) {
                    break;
                }
                let r = ensemble.trial(&alpha)?;
                trial_is_final = true;
                for j in 0..v {
                    if !pending[j] {
                        continue;
                    }
                    let a = -alpha[j].to_f64_lossy();
                    let s_a = -r.step_dot_residual[j].to_f64_lossy();
                    let norm = r.residual_square[j].to_f64_lossy().sqrt();
                    let finite = s_a.is_finite() && norm.is_finite();
                    if finite && (s_a.abs() <= s0[j].abs() || norm <= (1.0 - 1e-4 * a) * norm0[j]) {
                        pending[j] = false;
                    } else {
                        alpha[j] = alpha[j] * t(0.5);
                        trial_is_final = false;
                    }
                }
            }
            for j in 0..v {
                last_step[j] = now.step_max[j].to_f64_lossy() * alpha[j].to_f64_lossy().abs();
            }
            if std::env::var("HOLEWALL_DEBUG_NEWTON").is_ok() {
                eprintln!(
                    "  engine λ {lambda:.4} it {it}: variant 0 residual {:.3e} α {:.4} step {:.3e}",
                    now.residual_max[0].to_f64_lossy() / f_ref[0],
                    alpha[0].to_f64_lossy().abs(),
                    last_step[0]
                );
            }
            if trial_is_final {
                ensemble.accept_trial();
                evaluated = true;
            } else {
                ensemble.commit(&alpha)?;
                evaluated = false;
            }
            progress(
                (step as f64 + it as f64 / options.max_iterations as f64) / schedule.len() as f64,
            );
        }
        progress((step + 1) as f64 / schedule.len() as f64);
        for j in 0..v {
            if !done[j] && status[j] == EngineStatus::Converged {
                status[j] = EngineStatus::Failed(format!(
                    "λ = {lambda}: Newton did not converge in {} iterations",
                    options.max_iterations
                ));
            }
        }
    }
    let config = ensemble.config()?;
    Ok((0..v)
        .map(|j| {
            let mut s = StaticState::initial(base);
            for i in 0..n {
                for k in 0..3 {
                    let at = (3 * i + k) * v + j;
                    s.x[i][k] =
                        tables.node_ref[3 * i + k] + tables.base[at] + config.x[at].to_f64_lossy();
                }
                for r in 0..3 {
                    for c in 0..3 {
                        s.rot[i][r][c] = config.rot[(9 * i + 3 * r + c) * v + j].to_f64_lossy();
                    }
                }
            }
            EngineResult {
                state: s,
                status: status[j].clone(),
                iterations: iterations[j].clone(),
            }
        })
        .collect())
}

/// A kernel path with chunks of at most `max` variants (to test chunk boundaries, or to
/// bound the memory a run takes).
pub struct Chunked<P> {
    /// The path.
    pub inner: P,
    /// Most variants per chunk.
    pub max: usize,
}

impl<T, P: KernelPath<T>> KernelPath<T> for Chunked<P> {
    fn max_chunk(&self, model: &Model) -> usize {
        self.inner.max_chunk(model).min(self.max)
    }
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
    ) -> Result<Box<dyn Ensemble<T> + 'a>, String> {
        self.inner.open(model, tables)
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &EnsembleTables<T>,
        dynamic: &dynamic::DynamicTables<T>,
    ) -> Result<Box<dyn dynamic::DynamicEnsemble<T> + 'a>, String> {
        self.inner.open_dynamic(model, tables, dynamic)
    }
}

pub mod dynamic;
