//! The ensemble Newton iteration through the kernels (issue 5): one static solve for V
//! variants of one mesh, every iteration made of the kernels — beam, sites, contact,
//! assembly (with constraints), block LU, norms, update — on either kernel path: the CPU
//! twins ([`TwinPath`], f64) or the WGSL kernels ([`crate::gpu::GpuPath`], f32 or f64).
//!
//! Each variant follows its own load path, the one `statics::solve_static` follows
//! ([`crate::solve::continuation::LoadPath`]: gravity in full from the low-side start,
//! exponent continuation where that fails, λ steps cut on failure and regrown after easy
//! ones, the polish), through the one Newton ([`crate::solve::newton`]); all variants
//! advance in the same dispatches, each at its own λ. A variant fails only where
//! `solve_static` fails (below the smallest load step); the caller then re-runs it on the
//! CPU and says so. Finished variants get α = 0, and once no more than half of a batch is
//! running the rest go on in a batch of their own (compaction, bit for bit).
//!
//! States are displacements `u` from a per-variant base (kept in f64 on the host):
//! positions of kilometres would lose their millimetres in f32.
//!
//! Data stay where the path keeps them ([`ResidentStatic`]): on the GPU the configuration, the
//! assembled systems and every intermediate live in buffers made once per batch of
//! variants; the host reads four numbers and a status per variant per solve or trial
//! (largest residual, largest step, `Δ·r`, `r·r`) and writes one α per variant. Variants are
//! split into batches that fit the adapter's binding limits ([`KernelPath::max_batch`]).
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
use crate::solve::continuation::{solve_loads_from, LoadPath, LoadTarget, StaticSystem};
use crate::solve::newton::{NewtonSettings, NewtonSystem, Probe, TrialProbe};
use crate::solve::statics::{
    constraint_tables, loaded_params, reference_force, split_loads, StaticOptions, StaticState,
};

/// What one batch of variants shares and starts from, built once on the host.
#[derive(Clone, Debug)]
pub struct BatchTables<T> {
    /// Variants V in the batch.
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
    /// Unstrained rotations per element and variant, `6 (n − 1) V`
    /// ([`crate::kernels::beam::rest_table`]: the kinks of bent subs, in full; the static
    /// engine scales each variant's with its load factor). Empty without a kink (the beam
    /// kernel is then built without it).
    pub rest: Vec<T>,
    /// Contact terms the scene uses (the contact kernel is compiled for these only).
    pub terms: ContactTerms,
}

impl<T: Real> BatchTables<T> {
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

/// A batch's line-search trials on a kernel path ([`ResidentStatic`]'s and
/// [`dynamic::ResidentDynamic`]'s). A trial is the current point `+ α Δ` (the static
/// configuration, or the dynamic step's unknown `v̇`) with its residual alone evaluated (not
/// its tangent: a rejected trial's tangent would be wasted, and the tangent is most of an
/// evaluation), and the norms of that residual with `Δ`, `α`.
pub trait ResidentTrials<T> {
    /// One trial. Masked as [`NewtonSystem::trial`]: the variants in `search` are moved and
    /// evaluated (their norms are read); on the `first` trial of a search every variant's
    /// trial is set (α = 0: the current point), later ones keep the others' trials as they
    /// are, and a path may evaluate only the searching ones.
    fn trial(
        &mut self,
        alpha: &[T],
        search: &[bool],
        first: bool,
    ) -> Result<Norms<T>, crate::error::SystemError>;
    /// Trials the path forms in one round trip ([`ResidentTrials::trials`]).
    fn trials_per_round(&self) -> usize {
        1
    }
    /// The trials at `alphas[0]`, `alphas[1]`, … in order, each as
    /// [`ResidentTrials::trial`] (`first` for the first of them), for the same variants
    /// `search`; the trial left is the last one's. The default forms them one at a time.
    fn trials(
        &mut self,
        alphas: &[Vec<T>],
        search: &[bool],
        first: bool,
    ) -> Result<Vec<Norms<T>>, crate::error::SystemError> {
        alphas
            .iter()
            .enumerate()
            .map(|(k, a)| self.trial(a, search, first && k == 0))
            .collect()
    }
}

/// A solve's norms and statuses ([`ResidentStatic::solve`]) and, where the path forms it
/// with the solve, the first trial's norms ([`ResidentStatic::solve_with_trial`]).
pub type SolvedWithTrial<T> = (Norms<T>, Vec<u32>, Option<Norms<T>>);

/// A batch of variants held by a kernel path: a current configuration with its assembled
/// system, a step `Δ`, and one trial configuration.
pub trait ResidentStatic<T>: ResidentTrials<T> {
    /// Sets the external loads (`6 n V`), the pairs' law parameters (`PARAMS_LEN · P`,
    /// field-major) and the elements' unstrained rotations (`6 (n − 1) V`, empty without a
    /// kink) of a load step.
    fn set_loads(
        &mut self,
        f_ext: &[T],
        pair_params: &[T],
        rest: &[T],
    ) -> Result<(), crate::error::SystemError>;
    /// Residual and constrained tangent at the current configuration.
    fn evaluate(&mut self) -> Result<(), crate::error::SystemError>;
    /// Solves the current system for `Δ`; the norms of its residual and `Δ` (α = 1) and
    /// the solve's status per variant.
    fn solve(&mut self) -> Result<(Norms<T>, Vec<u32>), crate::error::SystemError>;
    /// [`ResidentStatic::solve`], and where the path forms it in the same round trip, the
    /// first line-search trial at `α = 1` for every variant ([`ResidentTrials::trial`] with
    /// `first` and every variant searching): its norms.
    fn solve_with_trial(&mut self) -> Result<SolvedWithTrial<T>, crate::error::SystemError> {
        self.solve().map(|(norms, status)| (norms, status, None))
    }
    /// Makes the last trial (configuration and residual) the current one; its tangent is
    /// formed by the next [`ResidentStatic::evaluate`].
    fn accept_trial(&mut self);
    /// Current += `α Δ` (its system must be evaluated again).
    fn commit(&mut self, alpha: &[T]) -> Result<(), crate::error::SystemError>;
    /// The current configuration, read back.
    fn config(&mut self) -> Result<ConfigBatch<T>, crate::error::SystemError>;
    /// Replaces the current configuration (displacements from the base and rotations;
    /// its system must be evaluated again).
    fn set_config(&mut self, config: &ConfigBatch<T>) -> Result<(), crate::error::SystemError>;
    /// Sets a relaxation's proximal shift (`None`: none; [`Shift`]): every evaluation from
    /// now on adds `s_v (u − a_v)` to each node's translations' residual and `s_v I` to their
    /// diagonal block, and `r_v log(R R_aᵀ)` and `r_v I` to its rotations' (the systems must
    /// be evaluated again).
    fn set_shift(&mut self, shift: Option<&Shift<T>>) -> Result<(), crate::error::SystemError>;
    /// Sets each variant's landing epoch (`V`; [`crate::kernels::update::UpdateWalls::epoch`]:
    /// a contact node lands on its wall once an epoch, none in epoch 0).
    fn set_landing_epochs(&mut self, epochs: &[u32]) -> Result<(), crate::error::SystemError>;
    /// Moves the base to the current configuration, given as `tables` after
    /// [`BatchTables::set_base`] with the host's sum of the old base and the current
    /// displacements: the displacements from it are set to zero, the rotations kept (the
    /// system must be evaluated again).
    fn rebase(&mut self, tables: &BatchTables<T>) -> Result<(), crate::error::SystemError>;
}

/// A relaxation's proximal shift on a batch ([`crate::solve::continuation`]'s
/// `Stage::Relax`, as the CPU solve's): the shift per variant and its anchor.
#[derive(Clone, Debug, PartialEq)]
pub struct Shift<T> {
    /// The shift per variant (N/m on the translations; 0: none), `V`.
    pub shift: Vec<T>,
    /// Each variant's anchor as displacements from the current base, `3 n V`
    /// (`[(3 i + k) V + v]`; zero where the variant has no shift).
    pub anchor: Vec<T>,
    /// The rotations' shift per variant (N·m/rad; 0: none), `V`: that of a relaxation
    /// whose translational shift reached its ceiling (`LoadPath::rotation_shift`). Empty:
    /// no variant has one.
    pub rot_shift: Vec<T>,
    /// Each variant's anchor rotations, `9 n V` (`[(9 i + 3 a + k) V + v]`; zero where the
    /// variant has no rotational shift; empty with `rot_shift`).
    pub anchor_rot: Vec<T>,
}

/// A kernel path: makes the [`ResidentStatic`] of a batch of variants.
pub trait KernelPath<T> {
    /// The most variants of `model` one batch may hold.
    fn max_batch(&self, model: &Model) -> usize;
    /// Uploads a batch.
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<T>,
    ) -> Result<Box<dyn ResidentStatic<T> + 'a>, crate::error::SystemError>;
    /// Uploads a batch for a dynamic run.
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<T>,
        dynamic: &dynamic::DynamicTables<T>,
    ) -> Result<Box<dyn dynamic::ResidentDynamic<T> + 'a>, crate::error::SystemError>;
}

/// One kernel of the evaluation chain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Generalised-α predictor: the trial state from the unknown accelerations (dynamic).
    Predict,
    /// Co-rotational beam element force and tangent, per (element, variant).
    Beam,
    /// Each contact pair's state (displacement; dynamic: velocity, spin) from its node.
    Sites,
    /// The contact element, per pair.
    Contact,
    /// Residual and block-tridiagonal tangent per (node, variant), constraints applied.
    Assemble,
}

/// The evaluation chain of a Newton iteration, described once: the kernels, in order,
/// that turn a configuration into its constrained residual and tangent — static, or
/// dynamic (predictor first, and dynamic sites and assembly). The twin path runs it in
/// `twin_evaluate`, the GPU path records it (`gpu::batch`), both from this list.
pub fn evaluation(dynamic: bool) -> &'static [Stage] {
    if dynamic {
        &[
            Stage::Predict,
            Stage::Beam,
            Stage::Sites,
            Stage::Contact,
            Stage::Assemble,
        ]
    } else {
        &[Stage::Beam, Stage::Sites, Stage::Contact, Stage::Assemble]
    }
}

/// Invocations of a stage for `n` nodes, `v` variants and `p` contact pairs.
pub fn invocations(stage: Stage, n: usize, v: usize, p: usize) -> usize {
    match stage {
        Stage::Predict | Stage::Assemble => n * v,
        Stage::Beam => n.saturating_sub(1) * v,
        Stage::Sites | Stage::Contact => p,
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
    /// Step cuts and stage changes of its load path, with why.
    pub log: Vec<String>,
    /// Its load path's answer is doubtful ([`LoadPath::doubtful`]: relaxed past a fold, or
    /// f32's second solve failed from it).
    pub doubtful: bool,
    /// Where its failed load path stops (a lock-up): the largest load factor at which it
    /// found an equilibrium and the smallest at which it found none
    /// ([`LoadPath::stopped_between`]); `None` for every other end.
    pub stopped: Option<(f64, f64)>,
    /// Where its string stands at the lower end of that bracket: the equilibrium the
    /// engine kept there, as the CPU solve's [`crate::solve::statics::StaticError::stopped`]
    /// (`None` where no bracket, and in f32: [`verify_f32`]).
    pub stands: Option<Box<crate::solve::statics::Stopped>>,
}

impl EngineResult {
    /// The converged answer as the CPU solve gives one, for `model` (the variant it was
    /// solved for), with its iterations per load step and log; `Err` with why it failed.
    pub fn into_solution(
        self,
        model: &Model,
    ) -> Result<crate::solve::statics::StaticSolution, String> {
        match self.status {
            EngineStatus::Converged => {
                let mut sol = crate::solve::statics::solution_at(model, self.state);
                sol.iterations = self.iterations;
                sol.log = self.log;
                Ok(sol)
            }
            EngineStatus::Failed(why) => Err(why),
        }
    }

    /// Where its load path bracketed where the string stops ([`EngineResult::stopped`]), as
    /// the CPU solve's does for a lock-up: the largest load factor with an equilibrium. The
    /// engine runs the CPU's load path ([`LoadPath`]: the same steps, relaxations and
    /// bracket), so an ensemble's CPU re-run of such a variant brackets nothing again — the
    /// relaxations below the full loads, 60–65 % of a lock-up's time there — and where it fails
    /// too, this is the variant's answer (`ensemble::runner`; docs/performance.md, stop 91).
    /// In f64 only: f32's bracket is cleared (`verify_f32`).
    pub fn stops(&self) -> Option<f64> {
        match self.status {
            EngineStatus::Failed(_) => self.stopped.map(|(lo, _)| lo),
            EngineStatus::Converged => None,
        }
    }
}

/// Static equilibrium of every variant through `path`. All models share the mesh and the
/// number of sites; stabilizers may sit at other nodes per variant.
pub fn solve_static_ensemble<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &P,
    options: &StaticOptions,
) -> Result<Vec<EngineResult>, crate::error::SystemError> {
    solve_static_ensemble_with_progress(models, path, options, &mut |_| {})
}

/// As [`solve_static_ensemble`], reporting the fraction done (0 … 1) after every iteration
/// (for a progress bar). Batches of [`KernelPath::max_batch`] variants run one after another.
pub fn solve_static_ensemble_with_progress<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &P,
    options: &StaticOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Vec<EngineResult>, crate::error::SystemError> {
    check_same_mesh(models)?;
    let batch = path.max_batch(&models[0]).max(1);
    let total = models.len();
    let mut results = Vec::with_capacity(total);
    for (c, group) in models.chunks(batch).enumerate() {
        let done_before = (c * batch) as f64 / total as f64;
        let share = group.len() as f64 / total as f64;
        let mut report = |f: f64| progress(done_before + share * f);
        results.extend(solve_batch(group, path, options, &mut report)?);
    }
    Ok(results)
}

fn solve_batch<T: Real + Send + Sync, P: KernelPath<T>>(
    models: &[Model],
    path: &P,
    options: &StaticOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Vec<EngineResult>, crate::error::SystemError> {
    let setup = std::time::Instant::now();
    let tables = ensemble_tables::<T>(models)?;
    let v = tables.num_variants;
    // The mesh every variant shares (the kernels read sections and frames from it).
    let mesh = &models[0];
    let size = std::mem::size_of::<T>();
    let opening = std::time::Instant::now();
    let ensemble = path.open(mesh, &tables)?;
    crate::tally::add_setup(setup.elapsed(), opening.elapsed());
    let mut sys = EngineStatic::new(models.iter().collect(), ensemble, tables, None, None);
    // f32 solves full load a second time from its own converged state as base: the
    // answer's last digits are then f32's rounding of millimetres, not of the string's
    // whole sag (`docs/validation.md`).
    let mut paths: Vec<LoadPath> = models
        .iter()
        .map(|m| LoadPath::for_model(options, m, size == 4))
        .collect();
    let settings = options.newton(size, models);
    // Compaction: once no more than half of a batch's variants are still running, the
    // others (finished) leave it — the running ones go on in a batch of their own, each
    // exactly where it stands (state, restart point, Newton state), so no kernel works on
    // a finished variant for long and the answers do not depend on the compaction.
    let stop = |running: usize, total: usize| total >= COMPACT_MIN && 2 * running <= total;
    let mut members: Vec<usize> = (0..v).collect();
    let mut finals: Vec<Option<StaticState>> = vec![None; v];
    let mut stands: Vec<Option<Box<crate::solve::statics::Stopped>>> = vec![None; v];
    let mut resume = None;
    let mut solves = 0;
    loop {
        let m = members.len();
        let mut sub: Vec<LoadPath> = members.iter().map(|&j| paths[j].clone()).collect();
        let done_before = (v - m) as f64;
        let mut report = |p: &crate::solve::continuation::Progress| {
            progress((done_before + p.fraction() * m as f64) / v as f64)
        };
        let states = solve_loads_from(
            &mut sys,
            &mut sub,
            settings,
            resume.as_deref(),
            &stop,
            &mut solves,
            &mut report,
        )?;
        sys.flush()?;
        let config = sys.ensemble.config()?;
        let keep: Vec<usize> = (0..m).filter(|&i| !sub[i].finished()).collect();
        for (i, path) in sub.into_iter().enumerate() {
            let j = members[i];
            if path.finished() {
                finals[j] = Some(state_of(mesh, &sys.tables, &config, i));
            }
            // Stopped on its way: where it stands is the equilibrium it kept last.
            if let Some(between) = path.stopped_between().filter(|_| path.finished()) {
                if let Some((state, Some(at))) = sys.equilibrium.take_state(i, mesh) {
                    stands[j] =
                        crate::solve::statics::Stopped::at_kept(&models[j], between, state, &at)
                            .map(Box::new);
                }
            }
            paths[j] = path;
        }
        if keep.is_empty() {
            break;
        }
        let sub_models: Vec<Model> = keep.iter().map(|&i| sys.models[i].clone()).collect();
        let start = (columns(&config.x, m, &keep), columns(&config.rot, m, &keep));
        let mut tables = ensemble_tables_from::<T>(&sub_models, Some(start))?;
        tables.set_base(mesh, columns(&sys.tables.base, m, &keep));
        let saved = keep.iter().map(|&i| sys.saved[i].clone()).collect();
        let shifts = keep.iter().map(|&i| sys.shifts[i].clone()).collect();
        let best = sys.best.take_columns(&keep);
        let equilibrium = sys.equilibrium.take_columns(&keep);
        let anchor_base = keep
            .iter()
            .map(|&i| std::mem::take(&mut sys.anchor_base[i]))
            .collect();
        let kept_models = keep.iter().map(|&i| sys.models[i]).collect();
        let ensemble = path.open(mesh, &tables)?;
        sys = EngineStatic::new(kept_models, ensemble, tables, Some(saved), Some(shifts));
        sys.best = best;
        sys.equilibrium = equilibrium;
        sys.anchor_base = anchor_base;
        resume = Some(keep.iter().map(|&i| states[i].clone()).collect::<Vec<_>>());
        members = keep.iter().map(|&i| members[i]).collect();
    }
    let results: Vec<EngineResult> = paths
        .into_iter()
        .zip(finals)
        .zip(stands)
        .map(|((path, state), stands)| EngineResult {
            state: state.unwrap_or_else(|| StaticState::initial(mesh)),
            status: match &path.error {
                None => EngineStatus::Converged,
                Some(e) => EngineStatus::Failed(e.to_string()),
            },
            stopped: path.stopped_between(),
            stands,
            iterations: path.iterations,
            log: path.log,
            doubtful: path.doubtful,
        })
        .collect();
    if size == 4 {
        return Ok(verify_f32(models, results, options));
    }
    Ok(results)
}

/// The f32 engine's equilibria checked in f64: a converged variant whose f64 residual
/// exceeds f32's floor (`1e4 ε₃₂` of the force scale), or whose answer is doubtful
/// ([`EngineResult::doubtful`]: near a fold a residual at f32's floor can sit far from the
/// equilibrium), is polished by Newton in f64 on the CPU from where it stands
/// ([`crate::solve::statics::polish_static`]), and its log says so. Measured (issue 22): on
/// `tests/engine_stress.rs`'s full-gauge stabilizer well the μ = 1, k_e = 1e10 variant
/// converged in f32 to a state whose f64 residual is 4.8× the force scale (a 740 kN contact
/// force at one pipe node); corpus well 126 (horizontal, sliding, 634 nodes) relaxed in f32
/// to a state of f64 residual 1.6e-4 (below the floor) whose hook load was 155 kN against
/// the f64 engine's 127.5 kN, and whose second f32 solve diverged.
///
/// A variant whose f32 path stopped where its string does keeps no bracket
/// ([`EngineResult::stopped`] cleared): the equilibrium at its lower end is f32's, unchecked
/// in f64 (the engine keeps no state there to polish), and an f32 relaxation can settle at
/// f32's floor where f64 finds none — the lock-up variant of `tests/lock_up.rs`'s engine
/// case "converged" at the full loads in f32 (f64 residual 1.2e-3 of the force scale). Its
/// failure re-runs on the CPU as any other's.
fn verify_f32(
    models: &[Model],
    results: Vec<EngineResult>,
    options: &StaticOptions,
) -> Vec<EngineResult> {
    use crate::solve::statics::{polish_static, residual_measure_at};
    use rayon::prelude::*;
    let floor = 1e4 * crate::solve::newton::unit_roundoff(4);
    let doubt = |measure: f64| {
        if measure > floor {
            "failed the f64 check"
        } else {
            "came past a fold or its second solve failed, and is confirmed in f64"
        }
    };
    results
        .into_par_iter()
        .zip(models.par_iter())
        .map(|(mut r, m)| {
            if r.status != EngineStatus::Converged {
                r.stopped = None;
                r.stands = None;
                return r;
            }
            let measure = residual_measure_at(m, &r.state);
            if measure <= floor && !r.doubtful {
                return r;
            }
            match polish_static(m, r.state.clone(), options) {
                Ok(sol) => {
                    r.log.push(format!(
                        "the f32 equilibrium {} (residual {measure:.2e} of the force scale, f32's \
                         floor {floor:.1e}); polished in f64 on the CPU in {} iterations",
                        doubt(measure),
                        sol.iterations.iter().sum::<usize>()
                    ));
                    r.iterations.extend(sol.iterations);
                    r.state = sol.state;
                }
                Err(e) => {
                    r.status = EngineStatus::Failed(format!(
                        "the f32 equilibrium {} (residual {measure:.2e} of the force scale) and \
                         its polish in f64 failed: {e}",
                        doubt(measure)
                    ));
                }
            }
            r
        })
        .collect()
}

/// Batches of fewer variants are not compacted (a new batch costs more than it saves).
pub(crate) const COMPACT_MIN: usize = 4;

/// Variant `j`'s configuration (f64, from the reference) in a batch of `tables`.
fn state_of<T: Real>(
    mesh: &Model,
    tables: &BatchTables<T>,
    config: &ConfigBatch<T>,
    j: usize,
) -> StaticState {
    let v = tables.num_variants;
    state_from(
        mesh,
        |k| tables.base[k * v + j] + config.x[k * v + j].to_f64_lossy(),
        |k| config.rot[k * v + j].to_f64_lossy(),
    )
}

/// A configuration of `mesh`'s nodes from its flat entries: `x(3 i + k)`, node `i`'s
/// displacement from the reference along `k`; `rot(9 i + 3 r + c)`, its rotation's entry
/// `(r, c)`.
pub(super) fn state_from(
    mesh: &Model,
    x: impl Fn(usize) -> f64,
    rot: impl Fn(usize) -> f64,
) -> StaticState {
    let mut s = StaticState::initial(mesh);
    for (i, (u, q)) in s.u.iter_mut().zip(s.rot.iter_mut()).enumerate() {
        for (r, (u, q)) in u.iter_mut().zip(q.iter_mut()).enumerate() {
            *u = x(3 * i + r);
            for (c, q) in q.iter_mut().enumerate() {
                *q = rot(9 * i + 3 * r + c);
            }
        }
    }
    s
}

/// The columns `pick` of a variant-fastest array of `v` variants.
pub(crate) fn columns<X: Copy>(data: &[X], v: usize, pick: &[usize]) -> Vec<X> {
    data.chunks_exact(v)
        .flat_map(|row| pick.iter().map(move |&j| row[j]))
        .collect()
}

/// `−α` in the path's float type (the kernels' `Δ` is the negative Newton step).
pub(crate) fn negated<T: Real>(alpha: &[f64]) -> Vec<T> {
    alpha.iter().map(|&a| T::from_f64_lossy(-a)).collect()
}

/// A trial's slope `Δ·r(α)` and `‖r(α)‖₂` per variant from the norms kernel's output.
pub(crate) fn trial_probe<T: Real>(r: &Norms<T>) -> TrialProbe {
    TrialProbe {
        slope: r
            .step_dot_residual
            .iter()
            .map(|x| x.to_f64_lossy())
            .collect(),
        norm: r
            .residual_square
            .iter()
            .map(|x| x.to_f64_lossy().sqrt())
            .collect(),
    }
}

/// The line search's first trial formed with a solve (issue 27, item 3: no round trip of
/// its own), kept by a batch's Newton system — the static engine's and the dynamic
/// engine's, one policy — until a search takes it, and whether the candidates the path
/// holds are at the α Newton accepts.
pub(crate) struct KeptTrial<T> {
    /// The trial's norms and the α each variant's candidate was formed at.
    kept: Option<(Norms<T>, Vec<f64>)>,
    /// Some variant's candidate is not at its α (the search's first trial was taken from
    /// the kept one): an accepted step is committed, not taken from the trial.
    stale: bool,
}

impl<T: Real> KeptTrial<T> {
    pub(crate) fn new() -> Self {
        KeptTrial {
            kept: None,
            stale: false,
        }
    }

    /// Keeps the trial a solve formed at `alpha` per variant (`None`: none formed).
    pub(crate) fn keep(&mut self, norms: Option<Norms<T>>, alpha: Vec<f64>) {
        self.kept = norms.map(|n| (n, alpha));
    }

    /// Drops the kept trial (the states it was formed from changed for every variant).
    pub(crate) fn drop_kept(&mut self) {
        self.kept = None;
    }

    /// The trial at `alpha` for the variants `search` (`first`: a search's first trial),
    /// where the kept one is that trial for every one of them (formed at its α, and
    /// `changed(j)` false: not restored or reloaded since; the kernels read each variant's
    /// own columns alone, so the others' changes leave its trial as it was). The kept trial
    /// is gone after this call.
    pub(crate) fn take(
        &mut self,
        alpha: &[f64],
        search: &[bool],
        first: bool,
        changed: &dyn Fn(usize) -> bool,
    ) -> Option<TrialProbe> {
        let (norms, formed) = self.kept.take()?;
        let fits = |j: usize| alpha[j] == formed[j] && !changed(j);
        if first && (0..alpha.len()).all(|j| !search[j] || fits(j)) {
            self.stale = (0..alpha.len()).any(|j| !fits(j));
            return Some(trial_probe(&norms));
        }
        None
    }

    /// A trial the path forms now (`first`: it sets every variant's candidate).
    pub(crate) fn forming(&mut self, first: bool) {
        self.kept = None;
        if first {
            self.stale = false;
        }
    }

    /// At an accepted step: whether the path's trial may be taken as it stands (Newton's
    /// `trial_matches`, and no candidate stale). Ends the search.
    pub(crate) fn take_trial(&mut self, trial_matches: bool) -> bool {
        self.kept = None;
        trial_matches && !std::mem::take(&mut self.stale)
    }
}

/// Rounds of trials' `α` for a kernel path (negated: the kernels take `x − α Δ`).
pub(crate) fn negated_rounds<T: Real>(alphas: &[Vec<f64>]) -> Vec<Vec<T>> {
    alphas.iter().map(|a| negated::<T>(a)).collect()
}

/// A batch's Newton system's trial ([`NewtonSystem::trial`]) on `path`: the kept first
/// trial where it is this one ([`KeptTrial::take`]), else formed on the path.
pub(crate) fn trial_on<T: Real>(
    path: &mut dyn ResidentTrials<T>,
    kept: &mut KeptTrial<T>,
    (alpha, search, first): (&[f64], &[bool], bool),
    changed: &dyn Fn(usize) -> bool,
) -> Result<TrialProbe, crate::error::SystemError> {
    if let Some(r) = kept.take(alpha, search, first, changed) {
        return Ok(r);
    }
    kept.forming(first);
    Ok(trial_probe(&path.trial(
        &negated::<T>(alpha),
        search,
        first,
    )?))
}

/// A batch's Newton system's round of trials ([`NewtonSystem::trials`]) on `path`.
pub(crate) fn trials_on<T: Real>(
    path: &mut dyn ResidentTrials<T>,
    kept: &mut KeptTrial<T>,
    (alphas, search, first): (&[Vec<f64>], &[bool], bool),
) -> Result<Vec<TrialProbe>, crate::error::SystemError> {
    kept.forming(first);
    let r = path.trials(&negated_rounds::<T>(alphas), search, first)?;
    Ok(r.iter().map(trial_probe).collect())
}

/// A kernel path with batches of at most `max` variants (to test batch boundaries, or to
/// bound the memory a run takes).
pub struct Batched<P> {
    /// The path.
    pub inner: P,
    /// Most variants per batch.
    pub max: usize,
}

impl<T, P: KernelPath<T>> KernelPath<T> for Batched<P> {
    fn max_batch(&self, model: &Model) -> usize {
        self.inner.max_batch(model).min(self.max)
    }
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<T>,
    ) -> Result<Box<dyn ResidentStatic<T> + 'a>, crate::error::SystemError> {
        self.inner.open(model, tables)
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<T>,
        dynamic: &dynamic::DynamicTables<T>,
    ) -> Result<Box<dyn dynamic::ResidentDynamic<T> + 'a>, crate::error::SystemError> {
        self.inner.open_dynamic(model, tables, dynamic)
    }
}

pub mod dynamic;
mod statics;
mod tables;
mod twin;
use statics::EngineStatic;
pub(crate) use tables::{check_same_mesh, variant_fastest};
pub use tables::{ensemble_tables, ensemble_tables_from};
pub use twin::TwinPath;
pub(crate) use twin::{twin_evaluate, AssemblyDynamic};
