//! Implicit time integration: generalised-α (Chung & Hulbert 1993) on the Lie group of the
//! nodal rotations (Arnold & Brüls 2007; the form Samcef/Mecano uses), HHT as an option.
//!
//! Per node the configuration is `(x, R)`, the velocity `v = (ẋ, ω)` with `ω` the spatial
//! angular velocity, and the rotation is advanced multiplicatively,
//! `R_{n+1} = exp([h Δθ]×) R_n`, `Δq = v_n + h(½ − β) a_n + hβ a_{n+1}`,
//! `v_{n+1} = v_n + h(1 − γ) a_n + hγ a_{n+1}`,
//! `(1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) v̇_{n+1} + α_f v̇_n`,
//! and the equations of motion hold at `t_{n+1}`:
//! `M v̇ + ω × (J ω) + C_R v + f_int(q) + g_contact(q, v, ω) = f_ext(t)`.
//! Newton solves for `v̇_{n+1}` with the iteration matrix
//! `S = M + hγ' C_t + h²β' K_t` (`β' = β(1 − α_f)/(1 − α_m)`, `γ' = γ(1 − α_f)/(1 − α_m)`),
//! where `K_t` holds the beam and contact stiffness and `C_t` the gyroscopic, Rayleigh and
//! contact damping (`C` on ẋ, `c_omega nᵀ` on ω: the spin is the node's own angular velocity
//! about the hole axis). Mass: lumped, with rotary inertia (`J = R J₀ Rᵀ`), or consistent
//! (see [`DynamicOptions::mass`]).
//!
//! The top node is clamped to the rotary table, whose rotation about the top's hole axis `n₀`
//! (vertical at a rig; inclined where a case models the bottom of a string alone) is
//! prescribed: a ramp from rest to the operation's speed over `ramp_time`; the hook holds it
//! or lowers it along `n₀` at the ROP (ramped the same way).

// Index loops over 3×3 and 6×6 blocks read like the formulas.
#![allow(clippy::needless_range_loop)]
use crate::model::Model;
use crate::physics::beam::{rotation_exp, Mat3};
use crate::physics::contact::{evaluate, ContactMode, ContactTerms, SpringLaw};
use crate::physics::mass::MassKind;
use crate::physics::vec3::{cross, dot, Vec3};
use crate::solve::chain::{BlockTridiagonal, ChainSolver};
use crate::solve::statics::{
    add_element_responses, constrain, constrain_residual, constraints, external_loads,
    reference_force, to_global, StaticState,
};

pub mod control;
mod step;
use step::CpuStep;

/// Why a time step or the run of a [`Dynamics`] failed.
#[derive(Clone, Debug, thiserror::Error)]
pub enum DynamicError {
    /// A step's Newton iteration ended without converging (why, from
    /// [`crate::solve::newton::Event::Failed`]).
    #[error("{0}")]
    Step(String),
    /// A step failed and cutting it again would go below the smallest step allowed.
    #[error(
        "t = {t:.6} s: step {step:.3e} s failed and cannot be cut below {min_dt:.1e} s: {reason}"
    )]
    Stalled {
        /// Time reached (s).
        t: f64,
        /// The step that failed (s).
        step: f64,
        /// The smallest step allowed (s).
        min_dt: f64,
        /// Why its last try failed.
        reason: String,
    },
    /// The machinery under a step failed (a linear solve, a kernel path).
    #[error(transparent)]
    System(#[from] crate::error::SystemError),
    /// The solve for the initial accelerations failed.
    #[error(transparent)]
    Linear(#[from] crate::solve::chain::LinearSolveError),
}

/// Generalised-α parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaParams {
    /// α_m.
    pub alpha_m: f64,
    /// α_f.
    pub alpha_f: f64,
    /// β.
    pub beta: f64,
    /// γ.
    pub gamma: f64,
}

impl AlphaParams {
    /// Chung–Hulbert with spectral radius at infinity `rho_inf` ∈ [0, 1]: second order,
    /// unconditionally stable, optimal high-frequency dissipation.
    pub fn chung_hulbert(rho_inf: f64) -> Self {
        let alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
        let alpha_f = rho_inf / (rho_inf + 1.0);
        let gamma = 0.5 + alpha_f - alpha_m;
        AlphaParams {
            alpha_m,
            alpha_f,
            beta: 0.25 * (gamma + 0.5).powi(2),
            gamma,
        }
    }

    /// Hilber–Hughes–Taylor with `alpha` ∈ [0, 1/3] (α_m = 0).
    pub fn hht(alpha: f64) -> Self {
        AlphaParams {
            alpha_m: 0.0,
            alpha_f: alpha,
            beta: 0.25 * (1.0 + alpha).powi(2),
            gamma: 0.5 + alpha,
        }
    }
}

/// Integrator settings.
#[derive(Clone, Copy, Debug)]
pub struct DynamicOptions {
    /// Time step (s).
    pub dt: f64,
    /// Smallest step before giving up (s).
    pub min_dt: f64,
    /// Scheme parameters.
    pub alpha: AlphaParams,
    /// Newton iterations per step.
    pub max_iterations: usize,
    /// Converged when the residual is below `tolerance` × the reference force.
    pub tolerance: f64,
    /// Rayleigh damping `C = a0 M + a1 K₀` (K₀: the tangent at the start).
    pub rayleigh: (f64, f64),
    /// Time to ramp the rotary table from rest to the operation's speed (s).
    pub ramp_time: f64,
    /// Factor on the external loads as a function of time (default: 1).
    pub load_factor: Option<fn(f64) -> f64>,
    /// Lumped (diagonal, rotary inertia rotated with each node) or consistent mass. The
    /// consistent matrix is assembled once in the initial element frames: exact for the
    /// spin about the pipe axis (axisymmetric sections), first order in the bending
    /// rotations, which stay small in a hole. Gyroscopic moments come from the nodal
    /// rotary inertia in both cases (they do no work, so the energy stays that of the
    /// chosen mass).
    pub mass: MassKind,
    /// Rate at which the hook lowers a clamped top along the hole axis (m/s, ROP), ramped
    /// like the table; 0: hook fixed.
    pub rop: f64,
}

impl Default for DynamicOptions {
    /// [`crate::solve::settings::Settings`]' defaults (each documented there).
    fn default() -> Self {
        crate::solve::settings::Settings::default().dynamics()
    }
}

impl crate::solve::settings::Settings {
    /// The integrator's options (no load factor over time: a study sets its own).
    pub fn dynamics(&self) -> DynamicOptions {
        DynamicOptions {
            dt: self.time_step,
            min_dt: self.min_time_step,
            alpha: AlphaParams::chung_hulbert(self.rho_inf),
            max_iterations: self.dynamic_max_iterations,
            tolerance: self.dynamic_tolerance,
            rayleigh: self.rayleigh,
            ramp_time: self.ramp_time,
            load_factor: None,
            mass: self.mass,
            rop: self.rop,
        }
    }
}

/// Dynamic state.
#[derive(Clone, Debug)]
pub struct DynamicState {
    /// Time (s).
    pub t: f64,
    /// Configuration.
    pub q: StaticState,
    /// Velocities (6 per node: ẋ, ω spatial).
    pub v: Vec<f64>,
    /// True accelerations v̇.
    pub vdot: Vec<f64>,
    /// Generalised-α pseudo-accelerations.
    pub a: Vec<f64>,
}

/// Lumped nodal mass: translational mass and rotary inertia (initial orientation, global
/// axes) per node.
pub fn lumped_mass(model: &Model, density_of: &dyn Fn(usize) -> f64) -> (Vec<f64>, Vec<Mat3<f64>>) {
    let n = model.nodes.len();
    let mut m = vec![0.0; n];
    let mut j = vec![[[0.0; 3]; 3]; n];
    for (i, e) in model.elements.iter().enumerate() {
        let rho = density_of(i);
        let half = 0.5 * e.length0;
        let diag = [
            rho * e.section.polar_moment * half,
            rho * e.section.second_moment * half,
            rho * e.section.second_moment * half,
        ];
        let q = &e.frame0;
        let local: Mat3<f64> = std::array::from_fn(|r| {
            std::array::from_fn(|c| (0..3).map(|k| q[r][k] * diag[k] * q[c][k]).sum())
        });
        for node in [i, i + 1] {
            m[node] += rho * e.section.area * half;
            for r in 0..3 {
                for c in 0..3 {
                    j[node][r][c] += local[r][c];
                }
            }
        }
    }
    (m, j)
}

fn mat_mul(a: &Mat3<f64>, b: &Mat3<f64>) -> Mat3<f64> {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

fn mat_vec(a: &Mat3<f64>, x: &Vec3<f64>) -> Vec3<f64> {
    std::array::from_fn(|r| (0..3).map(|k| a[r][k] * x[k]).sum())
}

fn skew(w: &Vec3<f64>) -> Mat3<f64> {
    [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]
}

/// The dynamic model: the static model, its masses and the integrator.
pub struct Dynamics<'a> {
    model: &'a Model,
    mass: Vec<f64>,
    inertia0: Vec<Mat3<f64>>,
    f_ext: Vec<f64>,
    f_ref: f64,
    options: DynamicOptions,
    solver: ChainSolver,
    k0: Option<BlockTridiagonal>,
    /// The consistent mass matrix (global, initial frames) when asked for.
    consistent: Option<BlockTridiagonal>,
    /// Messages: step cuts and regrowth.
    pub log: Vec<String>,
    /// Newton iterations of every completed step.
    pub iterations: Vec<usize>,
    /// The run's own step ([`control`]): `dt`, or cut and not yet regrown.
    own_step: f64,
}

impl<'a> Dynamics<'a> {
    /// Sets up the integrator; `density_of(element)` gives the steel density.
    pub fn new(
        model: &'a Model,
        options: DynamicOptions,
        density_of: &dyn Fn(usize) -> f64,
    ) -> Self {
        let (mass, inertia0) = lumped_mass(model, density_of);
        let consistent = (options.mass == MassKind::Consistent)
            .then(|| crate::solve::modal::mass_matrix(model, MassKind::Consistent, density_of));
        Dynamics {
            consistent,
            model,
            mass,
            inertia0,
            f_ext: external_loads(model),
            f_ref: reference_force(model),
            own_step: options.dt,
            options,
            solver: ChainSolver::new(),
            k0: None,
            log: Vec::new(),
            iterations: Vec::new(),
        }
    }

    /// The force scale of the convergence test (the loads, or the internal forces of the
    /// initial state if larger; set by [`Self::initial_state`]).
    pub fn reference_force(&self) -> f64 {
        self.f_ref
    }

    /// Lumped nodal masses and rotary inertias (reference orientation, global axes).
    pub fn lumped(&self) -> (&[f64], &[Mat3<f64>]) {
        (&self.mass, &self.inertia0)
    }

    /// Whether the table turns the top node, and whether the hook lowers it.
    pub fn top_motion(&self) -> (bool, bool) {
        (
            self.table_driven(),
            self.options.rop != 0.0 && matches!(self.model.top, crate::model::TopBoundary::Clamped),
        )
    }

    /// Rotary-table angle, speed and acceleration at `t` (ramp from rest).
    pub fn table(&self, t: f64) -> (f64, f64, f64) {
        ramp(self.model.rotation_speed, self.options.ramp_time, t)
    }

    /// Hook travel down the hole axis, its speed and acceleration at `t` (lowered at the
    /// ROP, ramped like the table; zero unless the top is clamped).
    pub fn hook(&self, t: f64) -> (f64, f64, f64) {
        if matches!(self.model.top, crate::model::TopBoundary::Clamped) {
            ramp(self.options.rop, self.options.ramp_time, t)
        } else {
            (0.0, 0.0, 0.0)
        }
    }

    /// Whether the rotary table drives the top node (clamped or hook-load tops; a pinned top
    /// only holds its displacements and twist, a free one nothing).
    fn table_driven(&self) -> bool {
        matches!(
            self.model.top,
            crate::model::TopBoundary::Clamped | crate::model::TopBoundary::HookLoad(_)
        )
    }

    /// Kinetic energy (translational + rotational).
    pub fn kinetic_energy(&self, s: &DynamicState) -> f64 {
        if let Some(mc) = &self.consistent {
            return 0.5 * dot_n(&s.v, &mc.mul(&s.v));
        }
        let mut e = 0.0;
        for i in 0..self.model.nodes.len() {
            let v: Vec3<f64> = std::array::from_fn(|k| s.v[6 * i + k]);
            let w: Vec3<f64> = std::array::from_fn(|k| s.v[6 * i + 3 + k]);
            let j = self.spatial_inertia(&s.q, i);
            e += 0.5 * self.mass[i] * dot(&v, &v) + 0.5 * dot(&w, &mat_vec(&j, &w));
            // An imbalance: ½ M |ẋ + ω × d|² in place of ½ M |ẋ|².
            if let Some(u0) = self.model.unbalance.get(i).filter(|_| self.mass[i] > 0.0) {
                let u = mat_vec(&s.q.rot[i], u0);
                let wxu = cross(&w, &u);
                e += dot(&v, &wxu) + 0.5 * dot(&wxu, &wxu) / self.mass[i];
            }
        }
        e
    }

    /// Node `i`'s mass imbalance as a rigid eccentric mass
    /// ([`crate::physics::mass::unbalance_terms`]); `None` where the node has none.
    fn unbalance_terms(
        &self,
        s: &DynamicState,
        i: usize,
        hg: f64,
    ) -> Option<([f64; 6], [[f64; 6]; 6])> {
        let u0 = self.model.unbalance.get(i)?;
        if u0.iter().all(|x| *x == 0.0) || self.mass[i] <= 0.0 {
            return None;
        }
        let at = |k: usize| -> Vec3<f64> { std::array::from_fn(|c| s.vdot[6 * i + k + c]) };
        Some(crate::physics::mass::unbalance_terms(
            mat_vec(&s.q.rot[i], u0),
            self.mass[i],
            at(0),
            std::array::from_fn(|c| s.v[6 * i + 3 + c]),
            at(3),
            hg,
        ))
    }

    fn spatial_inertia(&self, q: &StaticState, i: usize) -> Mat3<f64> {
        let r = &q.rot[i];
        let rj = mat_mul(r, &self.inertia0[i]);
        std::array::from_fn(|a| std::array::from_fn(|b| (0..3).map(|k| rj[a][k] * r[b][k]).sum()))
    }

    /// The initial state: at rest in configuration `q` (e.g. the static equilibrium), with
    /// consistent accelerations.
    pub fn initial_state(&mut self, q: StaticState) -> Result<DynamicState, DynamicError> {
        let n = self.model.nodes.len();
        self.initial_state_moving(q, vec![0.0; 6 * n])
    }

    /// The initial state in `q`, at rest or, with `v`, moving ([`Self::initial_state`],
    /// [`Self::initial_state_moving`]).
    pub fn initial_state_with(
        &mut self,
        q: StaticState,
        v: Option<Vec<f64>>,
    ) -> Result<DynamicState, DynamicError> {
        match v {
            Some(v) => self.initial_state_moving(q, v),
            None => self.initial_state(q),
        }
    }

    /// The initial state in configuration `q` with velocities `v` (6 per node: ẋ, spatial
    /// ω), with consistent accelerations.
    pub fn initial_state_moving(
        &mut self,
        q: StaticState,
        v: Vec<f64>,
    ) -> Result<DynamicState, DynamicError> {
        let n = self.model.nodes.len();
        let mut s = DynamicState {
            t: 0.0,
            q,
            v,
            vdot: vec![0.0; 6 * n],
            a: vec![0.0; 6 * n],
        };
        let n0 = self.model.nodes[0].hole_axis;
        for k in 0..3 {
            if self.table_driven() {
                s.vdot[3 + k] = self.table(0.0).2 * n0[k];
            }
            s.vdot[k] = self.hook(0.0).2 * n0[k];
        }
        // M v̇ = f_ext − f_int − g: one linear solve with the mass as the matrix.
        let (r, _) = self.residual_and_matrix(&s, 0.0, 0.0, false);
        // Convergence is judged against the larger of the loads and the initial internal
        // forces (a string released from a deflected shape carries no external load).
        let lambda = self.options.load_factor.map(|f| f(0.0)).unwrap_or(1.0);
        let f_int = r
            .iter()
            .zip(&self.f_ext)
            .fold(0.0f64, |m, (ri, fe)| m.max((ri + lambda * fe).abs()));
        self.f_ref = self.f_ref.max(f_int);
        let mut mass = BlockTridiagonal::zeros(n);
        if let Some(mc) = &self.consistent {
            mass = mc.clone();
        } else {
            for i in 0..n {
                let j = self.spatial_inertia(&s.q, i);
                for k in 0..3 {
                    mass.diag[i][k][k] = self.mass[i];
                    for c in 0..3 {
                        mass.diag[i][3 + k][3 + c] = j[k][c];
                    }
                }
            }
        }
        for i in 0..n {
            if let Some((_, ju)) = self.unbalance_terms(&s, i, 0.0) {
                for a in 0..6 {
                    for b in 0..6 {
                        mass.diag[i][a][b] += ju[a][b];
                    }
                }
            }
        }
        let c = constraints(self.model);
        let mut rhs: Vec<f64> = r.iter().map(|x| -x).collect();
        constrain(&c, &mut rhs, &mut mass);
        let mut dv = self.solver.solve(&mass, &rhs)?;
        // Held nodes (the bit) solve in their hole frame: back to global axes.
        to_global(&c, &mut dv);
        for (x, d) in s.vdot.iter_mut().zip(&dv) {
            *x += d;
        }
        s.a = s.vdot.clone();
        Ok(s)
    }

    /// Residual of the equations of motion at a trial state and, if `with_matrix`, the
    /// iteration matrix `M + hγ' C_t + h²β' K_t` (unconstrained; without it, an empty
    /// matrix: a trial's residual forms and zeroes no blocks).
    fn residual_and_matrix(
        &mut self,
        s: &DynamicState,
        hg: f64,
        hhb: f64,
        with_matrix: bool,
    ) -> (Vec<f64>, BlockTridiagonal) {
        let model = self.model;
        let n = model.nodes.len();
        let lambda = self.options.load_factor.map(|f| f(s.t)).unwrap_or(1.0);
        let mut r: Vec<f64> = self.f_ext.iter().map(|f| -lambda * f).collect();
        // The initial tangent `K₀` (stiffness-proportional damping's, at the first call) is
        // formed only where that damping is asked for (`a1 ≠ 0`).
        let first_k0 = self.k0.is_none() && self.options.rayleigh.1 != 0.0;
        let with_tangent = with_matrix || first_k0;
        let blocks = |on: bool| BlockTridiagonal::zeros(if on { n } else { 0 });
        let mut k_t = blocks(with_tangent);
        let mut s_mat = blocks(with_matrix);
        let form = crate::solve::statics::DYNAMIC_TANGENT;
        add_element_responses(model, &s.q, form, &mut r, with_tangent.then_some(&mut k_t));
        if first_k0 {
            self.k0 = Some(k_t.clone());
        }
        // Inertia and gyroscopic moments.
        if let Some(mc) = &self.consistent {
            for (ri, fi) in r.iter_mut().zip(mc.mul(&s.vdot)) {
                *ri += fi;
            }
            if with_matrix {
                add_scaled(&mut s_mat, mc, 1.0);
            }
        }
        let lumped = self.consistent.is_none();
        for i in 0..n {
            let j = self.spatial_inertia(&s.q, i);
            let w: Vec3<f64> = std::array::from_fn(|k| s.v[6 * i + 3 + k]);
            let wdot: Vec3<f64> = std::array::from_fn(|k| s.vdot[6 * i + 3 + k]);
            let jw = mat_vec(&j, &w);
            let gyro = cross(&w, &jw);
            let jwd = mat_vec(&j, &wdot);
            for k in 0..3 {
                if lumped {
                    r[6 * i + k] += self.mass[i] * s.vdot[6 * i + k];
                    r[6 * i + 3 + k] += jwd[k];
                }
                r[6 * i + 3 + k] += gyro[k];
            }
            if with_matrix {
                // ∂(ω × Jω)/∂ω = [ω]× J − [Jω]×.
                let sw = mat_mul(&skew(&w), &j);
                let sjw = skew(&jw);
                for a in 0..3 {
                    if lumped {
                        s_mat.diag[i][a][a] += self.mass[i];
                    }
                    for b in 0..3 {
                        let inertia = if lumped { j[a][b] } else { 0.0 };
                        s_mat.diag[i][3 + a][3 + b] += inertia + hg * (sw[a][b] - sjw[a][b]);
                    }
                }
            }
        }
        // Mass imbalance (eccentric centres of mass turning with their nodes).
        if !self.model.unbalance.is_empty() {
            for i in 0..n {
                if let Some((ru, ju)) = self.unbalance_terms(s, i, hg) {
                    for a in 0..6 {
                        r[6 * i + a] += ru[a];
                    }
                    if with_matrix {
                        for a in 0..6 {
                            for b in 0..6 {
                                s_mat.diag[i][a][b] += ju[a][b];
                            }
                        }
                    }
                }
            }
        }
        // Rayleigh damping.
        let (a0, a1) = self.options.rayleigh;
        if a0 != 0.0 || a1 != 0.0 {
            let k0v = self
                .k0
                .as_ref()
                .map(|k0| k0.mul(&s.v))
                .unwrap_or_else(|| vec![0.0; 6 * n]);
            // Mass-proportional part on the translations (a rigid spin is not damped).
            let mut mv = vec![0.0; 6 * n];
            match &self.consistent {
                Some(mc) => {
                    let mut vt = s.v.clone();
                    for i in 0..n {
                        vt[6 * i + 3..6 * i + 6].fill(0.0);
                    }
                    mv = mc.mul(&vt);
                    for i in 0..n {
                        mv[6 * i + 3..6 * i + 6].fill(0.0);
                    }
                }
                None => {
                    for d in 0..6 * n {
                        if d % 6 < 3 {
                            mv[d] = self.mass[d / 6] * s.v[d];
                        }
                    }
                }
            }
            for d in 0..6 * n {
                r[d] += a0 * mv[d] + a1 * k0v[d];
            }
            if with_matrix {
                match &self.consistent {
                    Some(mc) => {
                        let mut mt = mc.clone();
                        for blk in mt.diag.iter_mut().chain(&mut mt.upper).chain(&mut mt.lower) {
                            for r in 0..6 {
                                for c in 0..6 {
                                    if r >= 3 || c >= 3 {
                                        blk[r][c] = 0.0;
                                    }
                                }
                            }
                        }
                        add_scaled(&mut s_mat, &mt, hg * a0);
                    }
                    None => {
                        for i in 0..n {
                            for k in 0..3 {
                                s_mat.diag[i][k][k] += hg * a0 * self.mass[i];
                            }
                        }
                    }
                }
            }
            if with_matrix {
                if let Some(k0) = &self.k0 {
                    add_scaled(&mut s_mat, k0, hg * a1);
                }
            }
        }
        // Contact, dynamic mode: spin = n·ω ([`Self::contact_forces`]).
        for (site, out) in model.sites.iter().zip(self.contact_forces(s)) {
            let i = site.node;
            let node = &model.nodes[i];
            if !out.contact {
                continue;
            }
            for a in 0..6 {
                r[6 * i + a] += out.g[a];
                if with_matrix {
                    for b in 0..3 {
                        k_t.diag[i][a][b] += out.k[a][b];
                        s_mat.diag[i][a][b] += hg * out.c[a][b];
                        s_mat.diag[i][a][3 + b] += hg * out.c_omega[a] * node.hole_axis[b];
                    }
                }
            }
        }
        if with_matrix {
            add_scaled(&mut s_mat, &k_t, hhb);
        }
        (r, s_mat)
    }

    /// Force and moment the rotary table exerts on the string's top node (N, N·m).
    pub fn top_reaction(&mut self, s: &DynamicState) -> [f64; 6] {
        let (r, _) = self.residual_and_matrix(s, 0.0, 0.0, false);
        std::array::from_fn(|k| r[k])
    }

    /// The contact response of each site at a state (dynamic mode).
    pub fn contact_forces(
        &self,
        s: &DynamicState,
    ) -> Vec<crate::physics::contact::ContactResponse<f64>> {
        let model = self.model;
        let terms = ContactTerms {
            spring: SpringLaw::PowerBlend,
            damping: true,
            friction: Some(model.friction),
            mode: ContactMode::Dynamic,
        };
        // In parallel (each site its own node's), in site order.
        use rayon::prelude::*;
        model
            .sites
            .par_iter()
            .with_min_len(64)
            .map(|site| {
                let i = site.node;
                let node = &model.nodes[i];
                let d = s.q.u[i];
                let v: Vec3<f64> = std::array::from_fn(|k| s.v[6 * i + k]);
                let w: Vec3<f64> = std::array::from_fn(|k| s.v[6 * i + 3 + k]);
                evaluate(
                    &node.hole_axis,
                    &d,
                    &v,
                    dot(&node.hole_axis, &w),
                    &site.params,
                    &terms,
                )
            })
            .collect()
    }

    /// Advances `s` by one step of size `h`; on failure `s` is unchanged. Newton on the
    /// accelerations `v̇_{n+1}` ([`crate::solve::newton`], dynamics settings).
    pub fn step(&mut self, s: &mut DynamicState, h: f64) -> Result<usize, DynamicError> {
        use crate::solve::newton::{Event, Newton, NewtonSettings};
        let settings =
            NewtonSettings::dynamics(self.options.max_iterations, self.options.tolerance, 8);
        let largest = (0..s.q.u.len())
            .flat_map(|i| s.q.position(self.model, i))
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let floor = NewtonSettings::step_floor(8, largest);
        let mut sys = CpuStep::new(self, s, h);
        let mut newton = Newton::new(settings, 1);
        newton.start(0, floor, false);
        loop {
            // One variant: its first event ends the step.
            if let Some((_, event)) = newton.iterate(&mut sys)?.into_iter().next() {
                return match event {
                    Event::Converged(its) => {
                        let vdot = sys.vdot.clone();
                        let mut next = sys.trial.clone();
                        sys.predict(&mut next, &vdot);
                        *s = next;
                        Ok(its)
                    }
                    Event::Failed(reason) => Err(DynamicError::Step(reason)),
                };
            }
        }
    }
}

/// Position, rate and acceleration of a motion ramped linearly from rest to `rate` over
/// `ramp_time`.
fn ramp(rate: f64, ramp_time: f64, t: f64) -> (f64, f64, f64) {
    if ramp_time <= 0.0 {
        (rate * t, rate, 0.0)
    } else if t < ramp_time {
        (
            0.5 * rate * t * t / ramp_time,
            rate * t / ramp_time,
            rate / ramp_time,
        )
    } else {
        (0.5 * rate * ramp_time + rate * (t - ramp_time), rate, 0.0)
    }
}

fn dot_n(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn add_scaled(a: &mut BlockTridiagonal, b: &BlockTridiagonal, s: f64) {
    for (x, y) in a
        .diag
        .iter_mut()
        .zip(&b.diag)
        .chain(a.upper.iter_mut().zip(&b.upper))
        .chain(a.lower.iter_mut().zip(&b.lower))
    {
        for r in 0..6 {
            for c in 0..6 {
                x[r][c] += s * y[r][c];
            }
        }
    }
}

/// Strain energy of the beams at a configuration (for energy balances).
pub fn strain_energy(model: &Model, q: &StaticState) -> f64 {
    use crate::physics::beam::strain_energy as element_energy;
    model
        .elements
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let def = crate::solve::statics::element_deformation(model, q, i);
            element_energy(&def, &e.section, e.length0)
        })
        .sum()
}
