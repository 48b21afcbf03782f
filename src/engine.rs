//! The ensemble Newton iteration through the kernels (issue 5): one static solve for V
//! variants of one mesh, every iteration made of the six kernels — beam, contact, assembly
//! (with constraints), block LU, norms, update — on either kernel path: the CPU twins
//! ([`TwinPath`], f64) or the WGSL kernels ([`GpuPath`], f32 or f64).
//!
//! The schedule mirrors `statics::solve_static` without its adaptivity: gravity in full
//! from the low-side start with friction and bit loads off (λ = 0), then λ = ¼, ½, ¾, 1
//! (bit loads and friction scaled by λ); Newton with the solver's line search at each λ
//! (per variant: energy slope or residual decrease, α halved at most five times). A
//! variant whose Newton
//! fails (singular pivot, a non-finite residual, no convergence within the iterations) is
//! flagged with the reason and frozen; the caller re-runs it on the CPU with step control.
//! Converged and frozen variants get α = 0, so they stop moving while the others iterate.
//!
//! Today [`GpuPath`] dispatches each kernel with its own buffers and reads every result
//! back (one-shot runners): the data flow and the numbers are the engine's, the residency
//! (buffers made once, only the norms read per iteration) is the next step.

use crate::kernels::assemble::{assemble, AssemblyInputs, NO_SITE};
use crate::kernels::block_lu::{block_lu, ChainBatch, SOLVED};
use crate::kernels::contact::{contact, ContactBatch, ContactOutputs};
use crate::kernels::update::{norms, update, ConfigBatch};
use crate::model::Model;
use crate::physics::contact::{ContactMode, ContactTerms, SpringLaw};
use crate::physics::Real;
use crate::solve::statics::{
    constraint_tables, reference_force, split_loads, StaticOptions, StaticState,
};

/// One kernel path: the six kernels of a Newton iteration over V variants.
pub trait KernelPath<T> {
    /// Element forces and tangents (`shaders/beam.wgsl`).
    fn beam(
        &mut self,
        model: &Model,
        v: usize,
        x: &[T],
        rot: &[T],
    ) -> Result<(Vec<T>, Vec<T>), String>;
    /// Contact responses (`shaders/contact.wgsl`).
    fn contact(
        &mut self,
        terms: &ContactTerms,
        batch: &ContactBatch<T>,
    ) -> Result<ContactOutputs<T>, String>;
    /// Residual and constrained tangent (`shaders/assemble.wgsl`).
    fn assemble(&mut self, a: &AssemblyInputs<T>) -> Result<ChainBatch<T>, String>;
    /// Block-tridiagonal solve (`shaders/block_lu.wgsl`).
    fn solve(&mut self, b: &ChainBatch<T>) -> Result<(Vec<T>, Vec<u32>), String>;
    /// Largest residual and step per variant (`shaders/update.wgsl`, NORMS).
    fn norms(
        &mut self,
        r: &[T],
        d: &[T],
        alpha: &[T],
        n: usize,
        v: usize,
    ) -> Result<(Vec<T>, Vec<T>), String>;
    /// Configuration update (`shaders/update.wgsl`).
    fn update(&mut self, c: &mut ConfigBatch<T>, d: &[T], alpha: &[T]) -> Result<(), String>;
}

/// The CPU twins, f64.
pub struct TwinPath;

impl KernelPath<f64> for TwinPath {
    fn beam(
        &mut self,
        model: &Model,
        v: usize,
        x: &[f64],
        rot: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        Ok(crate::kernels::beam::beam(model, v, x, rot))
    }
    fn contact(
        &mut self,
        terms: &ContactTerms,
        batch: &ContactBatch<f64>,
    ) -> Result<ContactOutputs<f64>, String> {
        let mut out = ContactOutputs::new(batch.num_pairs());
        contact(terms, batch, &mut out);
        Ok(out)
    }
    fn assemble(&mut self, a: &AssemblyInputs<f64>) -> Result<ChainBatch<f64>, String> {
        Ok(assemble(a))
    }
    fn solve(&mut self, b: &ChainBatch<f64>) -> Result<(Vec<f64>, Vec<u32>), String> {
        Ok(block_lu(b))
    }
    fn norms(
        &mut self,
        r: &[f64],
        d: &[f64],
        alpha: &[f64],
        n: usize,
        v: usize,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        Ok(norms(r, d, alpha, n, v))
    }
    fn update(&mut self, c: &mut ConfigBatch<f64>, d: &[f64], alpha: &[f64]) -> Result<(), String> {
        update(c, d, alpha);
        Ok(())
    }
}

/// The WGSL kernels on the shared GPU context.
pub struct GpuPath(pub &'static crate::gpu::GpuContext);

impl<T: crate::gpu::contact::GpuReal> KernelPath<T> for GpuPath {
    fn beam(
        &mut self,
        model: &Model,
        v: usize,
        x: &[T],
        rot: &[T],
    ) -> Result<(Vec<T>, Vec<T>), String> {
        crate::gpu::beam::beam_gpu(self.0, model, v, x, rot).map_err(|e| e.to_string())
    }
    fn contact(
        &mut self,
        terms: &ContactTerms,
        batch: &ContactBatch<T>,
    ) -> Result<ContactOutputs<T>, String> {
        crate::gpu::contact::contact_gpu(self.0, terms, batch).map_err(|e| e.to_string())
    }
    fn assemble(&mut self, a: &AssemblyInputs<T>) -> Result<ChainBatch<T>, String> {
        crate::gpu::assemble::assemble_gpu(self.0, a).map_err(|e| e.to_string())
    }
    fn solve(&mut self, b: &ChainBatch<T>) -> Result<(Vec<T>, Vec<u32>), String> {
        crate::gpu::block_lu::block_lu_gpu(self.0, b).map_err(|e| e.to_string())
    }
    fn norms(
        &mut self,
        r: &[T],
        d: &[T],
        alpha: &[T],
        n: usize,
        v: usize,
    ) -> Result<(Vec<T>, Vec<T>), String> {
        crate::gpu::update::norms_gpu(self.0, r, d, alpha, n, v).map_err(|e| e.to_string())
    }
    fn update(&mut self, c: &mut ConfigBatch<T>, d: &[T], alpha: &[T]) -> Result<(), String> {
        crate::gpu::update::update_gpu(self.0, c, d, alpha).map_err(|e| e.to_string())
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

/// Residual and constrained tangent of every variant at `config` (beam, contact and
/// assembly kernels).
#[allow(clippy::too_many_arguments)]
fn evaluate<T: Real, P: KernelPath<T>>(
    path: &mut P,
    models: &[Model],
    config: &ConfigBatch<T>,
    contact_batch: &mut ContactBatch<T>,
    terms: &ContactTerms,
    node_site: &[u32],
    f_ext: &[T],
    fixed: &[u32],
) -> Result<ChainBatch<T>, String> {
    let t = |x: f64| T::from_f64_lossy(x);
    let base = &models[0];
    let (v, n) = (models.len(), base.nodes.len());
    let (elem_force, elem_tangent) = path.beam(base, v, &config.x, &config.rot)?;
    for (k, site) in base.sites.iter().enumerate() {
        let x0 = base.nodes[site.node].position;
        let axis = base.nodes[site.node].hole_axis;
        for (j, m) in models.iter().enumerate() {
            let d: [T; 3] =
                std::array::from_fn(|a| config.x[(3 * site.node + a) * v + j] - t(x0[a]));
            let vel: [T; 3] = std::array::from_fn(|a| t(axis[a] * m.axial_speed));
            contact_batch.set_state(k * v + j, d, vel, t(m.rotation_speed));
        }
    }
    let out = path.contact(terms, contact_batch)?;
    path.assemble(&AssemblyInputs {
        num_variants: v,
        num_nodes: n,
        num_sites: base.sites.len(),
        elem_force,
        elem_tangent,
        contact: out.values,
        contact_flag: out.contact,
        node_site: node_site.to_vec(),
        f_ext: f_ext.to_vec(),
        basis: config.basis.clone(),
        fixed: fixed.to_vec(),
    })
}

/// Copies variant `j`'s entries of `from` into `to` (field-major, variant fastest).
fn copy_variant<T: Copy>(to: &mut ChainBatch<T>, from: &ChainBatch<T>, j: usize) {
    let v = to.num_variants;
    for (a, b) in [
        (&mut to.diag, &from.diag),
        (&mut to.upper, &from.upper),
        (&mut to.lower, &from.lower),
        (&mut to.rhs, &from.rhs),
    ] {
        for f in 0..a.len() / v {
            a[f * v + j] = b[f * v + j];
        }
    }
}

/// Static equilibrium of every variant through `path`. All models share the mesh and the
/// site→node map (stabilizer moves go to the CPU path).
pub fn solve_static_ensemble<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &mut P,
    options: &StaticOptions,
) -> Result<Vec<EngineResult>, String> {
    solve_static_ensemble_with_progress(models, path, options, &mut |_| {})
}

/// As [`solve_static_ensemble`], reporting the fraction of the load schedule done (0 … 1)
/// after every iteration (for a progress bar).
pub fn solve_static_ensemble_with_progress<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &mut P,
    options: &StaticOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Vec<EngineResult>, String> {
    let v = models.len();
    let base = models.first().ok_or("no variants")?;
    let n = base.nodes.len();
    let s_count = base.sites.len();
    for m in models {
        if m.nodes.len() != n
            || m.sites.len() != s_count
            || m.sites
                .iter()
                .zip(&base.sites)
                .any(|(a, b)| a.node != b.node)
        {
            return Err("variants differ in mesh or site layout; run them on the CPU".into());
        }
    }
    let t = |x: f64| T::from_f64_lossy(x);
    let (basis, fixed) = constraint_tables(base);
    let starts: Vec<StaticState> = models
        .iter()
        .map(|m| {
            if m.sites.is_empty() {
                StaticState::initial(m)
            } else {
                StaticState::on_low_side(m)
            }
        })
        .collect();
    let mut config = ConfigBatch {
        num_variants: v,
        num_nodes: n,
        x: vec![T::zero(); 3 * n * v],
        rot: vec![T::zero(); 9 * n * v],
        basis: basis.iter().map(|&b| t(b)).collect(),
    };
    for (j, s) in starts.iter().enumerate() {
        for i in 0..n {
            for k in 0..3 {
                config.x[(3 * i + k) * v + j] = t(s.x[i][k]);
            }
            for r in 0..3 {
                for c in 0..3 {
                    config.rot[(9 * i + 3 * r + c) * v + j] = t(s.rot[i][r][c]);
                }
            }
        }
    }
    let loads: Vec<(Vec<f64>, Vec<f64>)> = models.iter().map(split_loads).collect();
    let length_scale: Vec<f64> = starts
        .iter()
        .map(|s| 1.0 + s.x.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs())))
        .collect();
    let f_ref: Vec<f64> = models.iter().map(reference_force).collect();
    let terms = ContactTerms {
        spring: SpringLaw::PowerBlend,
        damping: false,
        friction: Some(base.friction),
        mode: ContactMode::Static,
    };
    let mut node_site = vec![NO_SITE; n * v];
    let mut contact_batch = ContactBatch::<T>::new(v, s_count);
    for (k, site) in base.sites.iter().enumerate() {
        let axis = base.nodes[site.node].hole_axis;
        contact_batch.set_site_normal(k, [t(axis[0]), t(axis[1]), t(axis[2])]);
        for j in 0..v {
            node_site[site.node * v + j] = k as u32;
        }
    }
    let mut status = vec![EngineStatus::Converged; v];
    let mut iterations = vec![Vec::new(); v];
    let schedule = [0.0, 0.25, 0.5, 0.75, 1.0];
    for (step, &lambda) in schedule.iter().enumerate() {
        // Loads and friction of this step.
        let mut f_ext = vec![T::zero(); 6 * n * v];
        for (j, m) in models.iter().enumerate() {
            let gamma = if m.sites.is_empty() { lambda } else { 1.0 };
            for d in 0..6 * n {
                f_ext[d * v + j] = t(gamma * loads[j].0[d] + lambda * loads[j].1[d]);
            }
            for (k, site) in m.sites.iter().enumerate() {
                let mut p = site.params;
                p.mu_t *= lambda;
                p.mu_l *= lambda;
                contact_batch.set_params(k * v + j, &p.cast());
            }
        }
        let mut done = vec![false; v];
        let mut polished = vec![false; v];
        let mut last_step = vec![f64::INFINITY; v];
        // The system at the configuration the line search accepted, when it has been
        // evaluated there already (it has, unless a variant took the untested α = 1/32).
        let mut carried: Option<ChainBatch<T>> = None;
        for it in 1..=options.max_iterations {
            let sys = match carried.take() {
                Some(s) => s,
                None => evaluate(
                    path,
                    models,
                    &config,
                    &mut contact_batch,
                    &terms,
                    &node_site,
                    &f_ext,
                    &fixed,
                )?,
            };
            let (sol, st) = path.solve(&sys)?;
            let minus = vec![T::zero() - T::one(); v];
            let (rmax, dmax) = path.norms(&sys.rhs, &sol, &minus, n, v)?;
            let mut alpha = vec![T::zero(); v];
            for j in 0..v {
                if done[j] || status[j] != EngineStatus::Converged {
                    continue;
                }
                let measure = rmax[j].to_f64_lossy() / f_ref[j];
                if !measure.is_finite() {
                    status[j] =
                        EngineStatus::Failed(format!("λ = {lambda}: residual is not finite"));
                } else if (measure <= options.tolerance && last_step[j] <= 1e-6)
                    || (last_step[j] <= 1e-12 * length_scale[j] && measure <= 1e-6)
                {
                    // As statics::newton: converged, or the step is down at rounding level
                    // (positions carry ≈1e-16·|x| of noise) with the residual small anyway.
                    // At full load one more full step polishes it (as solve_static).
                    if lambda == 1.0 && !polished[j] {
                        polished[j] = true;
                        alpha[j] = T::zero() - T::one();
                        continue;
                    }
                    done[j] = true;
                    iterations[j].push(it - 1);
                } else if st[j] != SOLVED {
                    status[j] = EngineStatus::Failed(format!("λ = {lambda}: singular tangent"));
                } else {
                    alpha[j] = T::zero() - T::one();
                }
            }
            if (0..v).all(|j| done[j] || status[j] != EngineStatus::Converged) {
                break;
            }
            // Line search per variant, as statics::newton: the full step unless it
            // overshoots (|s(α)| > |s(0)|, s = Δ·r) and does not lower ‖r‖₂; halved at most
            // five times (the last, α = 1/32, is taken anyway).
            let dot = |a: &[T], b: &[T], j: usize| -> f64 {
                (0..6 * n)
                    .map(|k| a[k * v + j].to_f64_lossy() * b[k * v + j].to_f64_lossy())
                    .sum()
            };
            let s0: Vec<f64> = (0..v).map(|j| -dot(&sol, &sys.rhs, j)).collect();
            let norm0: Vec<f64> = (0..v).map(|j| dot(&sys.rhs, &sys.rhs, j).sqrt()).collect();
            let mut pending: Vec<bool> = alpha.iter().map(|a| a.to_f64_lossy() != 0.0).collect();
            let mut next: Option<ChainBatch<T>> = None;
            for _ in 0..5 {
                if !pending.iter().any(|&p| p) {
                    break;
                }
                let mut trial = config.clone();
                path.update(&mut trial, &sol, &alpha)?;
                let r = evaluate(
                    path,
                    models,
                    &trial,
                    &mut contact_batch,
                    &terms,
                    &node_site,
                    &f_ext,
                    &fixed,
                )?;
                for j in 0..v {
                    if !pending[j] {
                        continue;
                    }
                    let a = -alpha[j].to_f64_lossy();
                    let s_a = -dot(&sol, &r.rhs, j);
                    let norm = dot(&r.rhs, &r.rhs, j).sqrt();
                    let finite = s_a.is_finite() && norm.is_finite();
                    if finite && (s_a.abs() <= s0[j].abs() || norm <= (1.0 - 1e-4 * a) * norm0[j]) {
                        pending[j] = false;
                        if let Some(nx) = next.as_mut() {
                            copy_variant(nx, &r, j);
                        }
                    } else {
                        alpha[j] = alpha[j] * T::from_f64_lossy(0.5);
                    }
                }
                // The first trial also holds every variant that does not move (α = 0).
                if next.is_none() {
                    next = Some(r);
                }
            }
            if !pending.iter().any(|&p| p) {
                carried = next;
            }
            for j in 0..v {
                last_step[j] = dmax[j].to_f64_lossy() * alpha[j].to_f64_lossy().abs();
            }
            if std::env::var("HOLEWALL_DEBUG_NEWTON").is_ok() {
                eprintln!(
                    "  engine λ {lambda:.4} it {it}: variant 0 residual {:.3e} α {:.4} step {:.3e}",
                    rmax[0].to_f64_lossy() / f_ref[0],
                    alpha[0].to_f64_lossy().abs(),
                    last_step[0]
                );
            }
            path.update(&mut config, &sol, &alpha)?;
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
    Ok((0..v)
        .map(|j| {
            let mut s = StaticState::initial(base);
            for i in 0..n {
                for k in 0..3 {
                    s.x[i][k] = config.x[(3 * i + k) * v + j].to_f64_lossy();
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
