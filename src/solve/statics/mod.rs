//! Static equilibrium of the drillstring (paper §3.1): Newton on the global tangent with
//! load stepping and a backtracking line search. Rotations are updated multiplicatively
//! (`R ← exp([Δθ]×) R`). Contact elements act in `static` mode, their friction direction
//! set by the operation's virtual velocities.
//!
//! Boundary conditions: top clamped (all six DOFs); bit held laterally (the two
//! translations perpendicular to the hole axis), loaded by the weight on bit `−WOB·t` and
//! the torque on bit `−TOB·t` (`t` the down-hole axis); buoyed self-weight as nodal forces,
//! half an element's weight at each of its nodes ([`external_loads`]). All external loads
//! are scaled by the load factor `λ ∈ [0, 1]`.

use crate::model::{Model, TopBoundary};
use crate::physics::beam::{
    element_force, force_and_tangent_closed, local_deformation, rotation_exp, section_forces,
    Chord, ElementState, Mat3, SectionForces,
};
use crate::physics::contact::{evaluate, ContactMode, ContactResponse, ContactTerms, SpringLaw};
use crate::physics::vec3::{cross, dot, scale, sub, Vec3};
use crate::solve::chain::{BlockTridiagonal, ChainSolver};

pub use super::static_options::{StaticError, StaticOptions, Stopped};

mod results;
mod state;
mod system;
pub use results::{
    element_deformation, element_section_forces, loaded_model, loaded_params, model_at,
    solution_at, split_loads,
};
use results::{finish, penetration_for};
pub use state::StaticState;
pub use system::relax_scale;
use system::CpuStatic;

/// A converged static solution.
#[derive(Clone, Debug)]
pub struct StaticSolution {
    /// Configuration.
    pub state: StaticState,
    /// Section forces per element.
    pub section_forces: Vec<SectionForces>,
    /// Per contact site: (in contact, normal force N (N), internal generalised force g).
    pub contact: Vec<(bool, f64, [f64; 6])>,
    /// Newton iterations per completed load step.
    pub iterations: Vec<usize>,
    /// Messages: step cuts and why.
    pub log: Vec<String>,
    /// Force and moment the top support exerts on the string (N, N·m): the hook load is
    /// `−reaction[2]` in a vertical well.
    pub top_reaction: [f64; 6],
    /// Force and moment the bit's supports (and contact) exert on the string (N, N·m).
    pub bit_reaction: [f64; 6],
}

fn mat_mul(a: &Mat3<f64>, b: &Mat3<f64>) -> Mat3<f64> {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

/// Constraint data: per node the translation basis (columns) and fixed flags in it.
pub(crate) struct Constraints {
    basis: Vec<Option<Mat3<f64>>>,
    pub(crate) fixed: Vec<[bool; 6]>,
}

pub(crate) fn constraints(model: &Model) -> Constraints {
    let n = model.nodes.len();
    let mut basis = vec![None; n];
    let mut fixed = vec![[false; 6]; n];
    fixed[0] = match model.top {
        TopBoundary::Clamped => [true; 6],
        TopBoundary::Pinned => [true, true, true, false, false, false],
        // Free along global z: a well's top is vertical.
        TopBoundary::HookLoad(_) => [true, true, false, true, true, true],
        TopBoundary::Free => [false; 6],
    };
    if model.top == TopBoundary::Pinned {
        // The twist is held about global z: a well's top is vertical.
        fixed[0][5] = true;
    }
    if model.bit_lateral_fixed {
        let bit = n - 1;
        let t = model.nodes[bit].hole_axis;
        // Columns a, b ⊥ t, then t: fix the first two.
        let f = crate::model::frame_from_axis(&t);
        let b: Mat3<f64> = std::array::from_fn(|r| [f[r][1], f[r][2], f[r][0]]);
        basis[bit] = Some(b);
        fixed[bit][0] = true;
        fixed[bit][1] = true;
        if matches!(model.top, TopBoundary::HookLoad(_)) {
            fixed[bit][2] = true;
        }
    }
    Constraints { basis, fixed }
}

/// External loads at load factor 1 (6 per node).
///
/// An element's weight `q L` goes to its two nodes as forces, `q L / 2` each: it is
/// integrated by the nodal rule the wall's support is integrated by (a contact site holds
/// the string at a node and carries its tributary length). The consistent end moments of a
/// Hermite beam, `±(L²/12) e₁ × q`, are left out. They stand for the span's sag between
/// nodes, which the wall stops where the string lies on it; where the hole turns or builds
/// they no longer cancel at a node, and the string took their difference as bending and,
/// where it turns, as torsion growing as `L²`: corpus well 622 (horizontal, turning
/// 2.2°/30 m, rotating) read a surface torque of 29.0 kN·m at 30 m elements and 8.1 kN·m at
/// 2 m; with the weight at the nodes, 7.95–7.98 kN·m at every length (docs/validation.md,
/// "The weight at the nodes"). Where a span hangs free the moments cancel at every node of
/// a straight string; leaving them out moves its nodal deflections by `O(L²)` of the span's.
pub fn external_loads(model: &Model) -> Vec<f64> {
    let n = model.nodes.len();
    let mut f = vec![0.0; 6 * n];
    for (i, e) in model.elements.iter().enumerate() {
        let half = 0.5 * e.buoyed_weight_per_length * e.length0;
        f[6 * i + 2] += half;
        f[6 * (i + 1) + 2] += half;
    }
    let bit = n - 1;
    let t = model.nodes[bit].hole_axis;
    let wob = if matches!(model.top, TopBoundary::HookLoad(_)) {
        0.0
    } else {
        model.weight_on_bit
    };
    for k in 0..3 {
        f[6 * bit + k] -= wob * t[k];
        f[6 * bit + 3 + k] -= model.torque_on_bit * t[k];
    }
    if let TopBoundary::HookLoad(hook) = model.top {
        let t0 = model.nodes[0].hole_axis;
        for k in 0..3 {
            f[k] -= hook * t0[k];
        }
    }
    for (node, load) in &model.point_loads {
        for k in 0..6 {
            f[6 * node + k] += load[k];
        }
    }
    f
}

/// A site's contact response in static mode (friction direction from the operation's
/// virtual velocities, eqs 2.12–2.23 in static mode). Where the turning string whirls
/// (`site.params.side_friction` 0: [`crate::diagnose::mark_whirling_sites`]) its
/// circumferential friction acts as torque alone, the side force `N·mu_t·phi_t·t` left out.
pub fn site_response(
    model: &Model,
    state: &StaticState,
    site: &crate::model::Site,
) -> ContactResponse<f64> {
    let terms = ContactTerms {
        spring: SpringLaw::PowerBlend,
        damping: false,
        friction: Some(model.friction),
        mode: ContactMode::Static,
    };
    let node = &model.nodes[site.node];
    let d = state.u[site.node];
    let v = scale(&node.hole_axis, model.axial_speed);
    evaluate(
        &node.hole_axis,
        &d,
        &v,
        model.rotation_speed,
        &site.params,
        &terms,
    )
}

/// Residual `f_int + g_contact − λ f_ext` and (if `tangent` is given) the tangent, before
/// constraints.
fn assemble(
    model: &Model,
    state: &StaticState,
    lambda: f64,
    f_ext: &[f64],
    residual: &mut [f64],
    mut tangent: Option<&mut BlockTridiagonal>,
) {
    if let Some(t) = tangent.as_deref_mut() {
        t.clear();
    }
    for (r, f) in residual.iter_mut().zip(f_ext) {
        *r = -lambda * f;
    }
    add_element_responses(
        model,
        state,
        STATIC_TANGENT,
        residual,
        tangent.as_deref_mut(),
    );
    // The sites' responses in parallel (each its own node's), summed in site order.
    let responses: Vec<ContactResponse<f64>> = {
        use rayon::prelude::*;
        let each = |site| site_response(model, state, site);
        model.sites.par_iter().with_min_len(64).map(each).collect()
    };
    for (site, out) in model.sites.iter().zip(&responses) {
        if !out.contact {
            continue;
        }
        for r in 0..6 {
            residual[6 * site.node + r] += out.g[r];
            if let Some(t) = tangent.as_deref_mut() {
                for c in 0..3 {
                    t.diag[site.node][r][c] += out.k[r][c];
                }
            }
        }
    }
}

/// Which closed form of the element tangent a CPU solve runs; [`STATIC_TANGENT`] and
/// [`DYNAMIC_TANGENT`] below are the one place that says which solve runs which.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TangentForm {
    /// `force_and_tangent_closed`: the force's twelve first derivatives in one pass of dual
    /// numbers. The CPU static solve keeps it: which marginal (relaxed) corpus wells settle
    /// is decided at rounding level, and `tests/corpus.rs` holds seed 44, which settles
    /// with this form and not with the other (docs/performance.md, stop 72).
    OnePass,
    /// `force_and_tangent_variation`: the values once, their variation per direction —
    /// the GPU kernel's and its twin's form, 4,746 FLOP against 7,774 (`holewall bench
    /// element`: 0.50 against 0.79 µs an element). The CPU dynamic integrator runs it
    /// (stop 74): a time step's Newton solve converges from the last step's state, with
    /// no fold to cross, and its oracle role is towards the engine, which runs this form.
    WrittenOut,
}

/// The tangent form of the CPU static solve ([`TangentForm`]).
pub(crate) const STATIC_TANGENT: TangentForm = TangentForm::OnePass;
/// The tangent form of the CPU dynamic integrator ([`TangentForm`]).
pub(crate) const DYNAMIC_TANGENT: TangentForm = TangentForm::WrittenOut;

/// Adds every element's internal force (12) to `residual` and, where `tangent` is given,
/// its tangent (12×12, in `form`) to the blocks: the elements are computed in parallel
/// (rayon, in tasks of 32), then each node gathers from its two elements in parallel, the
/// element before it first, as a scatter in element order adds them — the same sums to
/// the bit whatever the thread count. A force-only call (a line search's trial) forms no
/// tangent storage at all.
pub(crate) fn add_element_responses(
    model: &Model,
    state: &StaticState,
    form: TangentForm,
    residual: &mut [f64],
    tangent: Option<&mut BlockTridiagonal>,
) {
    use crate::kernels::tridiagonal::add_quarter;
    use rayon::prelude::*;
    let element = |i: usize| {
        let e = &model.elements[i];
        let es = ElementState {
            x: [state.position(model, i), state.position(model, i + 1)],
            triad: [
                mat_mul(&state.rot[i], &model.nodes[i].frame0),
                mat_mul(&state.rot[i + 1], &model.nodes[i + 1].frame0),
            ],
        };
        (
            es,
            model.element_stiffness(i),
            Chord::Positions { length0: e.length0 },
        )
    };
    // Every element in parallel, in tasks of 32 (a few hundred microseconds of work, not
    // one element's), in element order.
    fn each<R: Send>(count: usize, f: impl Fn(usize) -> R + Sync + Send) -> Vec<R> {
        (0..count).into_par_iter().with_min_len(32).map(f).collect()
    }
    let count = model.elements.len();
    // Node `i`'s residual: from element `i − 1`'s second half, then element `i`'s first.
    fn gather(i: usize, count: usize, r: &mut [f64], force: impl Fn(usize) -> [f64; 12]) {
        if i > 0 {
            let f = force(i - 1);
            for a in 0..6 {
                r[a] += f[6 + a];
            }
        }
        if i < count {
            let f = force(i);
            for a in 0..6 {
                r[a] += f[a];
            }
        }
    }
    let Some(t) = tangent else {
        let out = each(count, |i| {
            let (es, k, form) = element(i);
            element_force(&es.x, &es.triad, &form, &k)
        });
        residual
            .par_chunks_mut(6)
            .with_min_len(64)
            .enumerate()
            .for_each(|(i, r)| gather(i, count, r, |e| out[e]));
        return;
    };
    let out = each(count, |i| {
        let (es, k, chord) = element(i);
        match form {
            TangentForm::OnePass => force_and_tangent_closed(&es.x, &es.triad, &chord, &k),
            TangentForm::WrittenOut => {
                crate::physics::beam::force_and_tangent_variation(&es.x, &es.triad, &chord, &k)
            }
        }
    });
    residual
        .par_chunks_mut(6)
        .zip(t.diag.par_iter_mut())
        .with_min_len(64)
        .enumerate()
        .for_each(|(i, (r, d))| {
            gather(i, count, r, |e| out[e].0);
            if i > 0 {
                add_quarter(d, &out[i - 1].1, 6, 6);
            }
            if i < count {
                add_quarter(d, &out[i].1, 0, 0);
            }
        });
    t.upper
        .par_iter_mut()
        .zip(t.lower.par_iter_mut())
        .with_min_len(64)
        .enumerate()
        .for_each(|(i, (u, l))| {
            add_quarter(u, &out[i].1, 0, 6);
            add_quarter(l, &out[i].1, 6, 0);
        });
}

/// Applies the translation bases and fixed DOFs to a residual (only).
pub(crate) fn constrain_residual(c: &Constraints, residual: &mut [f64]) {
    for (i, b) in c.basis.iter().enumerate() {
        if let Some(b) = b {
            let v: [f64; 3] = std::array::from_fn(|k| residual[6 * i + k]);
            for r in 0..3 {
                residual[6 * i + r] = (0..3).map(|k| b[k][r] * v[k]).sum();
            }
        }
    }
    for (i, fixed) in c.fixed.iter().enumerate() {
        for (d, &is_fixed) in fixed.iter().enumerate() {
            if is_fixed {
                residual[6 * i + d] = 0.0;
            }
        }
    }
}

/// Applies the translation bases and fixed DOFs to a residual and tangent.
pub(crate) fn constrain(c: &Constraints, residual: &mut [f64], tangent: &mut BlockTridiagonal) {
    let n = tangent.nodes();
    for (i, b) in c.basis.iter().enumerate() {
        let Some(b) = b else { continue };
        // Rows of node i: Bᵀ·; columns of node i: ·B (translations only).
        let rot_rows = |blk: &mut [[f64; 6]; 6]| {
            let v: [[f64; 6]; 3] = [blk[0], blk[1], blk[2]];
            for (r, row) in blk.iter_mut().take(3).enumerate() {
                for (col, x) in row.iter_mut().enumerate() {
                    *x = (0..3).map(|k| b[k][r] * v[k][col]).sum();
                }
            }
        };
        let rot_cols = |blk: &mut [[f64; 6]; 6]| {
            for row in blk.iter_mut() {
                let v: [f64; 3] = [row[0], row[1], row[2]];
                for c in 0..3 {
                    row[c] = (0..3).map(|k| v[k] * b[k][c]).sum();
                }
            }
        };
        rot_rows(&mut tangent.diag[i]);
        rot_cols(&mut tangent.diag[i]);
        if i > 0 {
            rot_rows(&mut tangent.lower[i - 1]);
            rot_cols(&mut tangent.upper[i - 1]);
        }
        if i + 1 < n {
            rot_rows(&mut tangent.upper[i]);
            rot_cols(&mut tangent.lower[i]);
        }
        let v: [f64; 3] = std::array::from_fn(|k| residual[6 * i + k]);
        for r in 0..3 {
            residual[6 * i + r] = (0..3).map(|k| b[k][r] * v[k]).sum();
        }
    }
    for (i, fixed) in c.fixed.iter().enumerate() {
        for (d, &is_fixed) in fixed.iter().enumerate() {
            if !is_fixed {
                continue;
            }
            residual[6 * i + d] = 0.0;
            for c2 in 0..6 {
                tangent.diag[i][d][c2] = 0.0;
                tangent.diag[i][c2][d] = 0.0;
                if i > 0 {
                    tangent.lower[i - 1][d][c2] = 0.0;
                    tangent.upper[i - 1][c2][d] = 0.0;
                }
                if i + 1 < n {
                    tangent.upper[i][d][c2] = 0.0;
                    tangent.lower[i][c2][d] = 0.0;
                }
            }
            tangent.diag[i][d][d] = 1.0;
        }
    }
}

/// Takes a correction from constrained coordinates (translations in each node's basis) to
/// global ones, in place: `Δu ← B Δu` where a node has a basis.
pub(crate) fn to_global(c: &Constraints, delta: &mut [f64]) {
    for (i, b) in c.basis.iter().enumerate() {
        if let Some(b) = b {
            let d: Vec3<f64> = std::array::from_fn(|k| delta[6 * i + k]);
            for r in 0..3 {
                delta[6 * i + r] = (0..3).map(|k| b[r][k] * d[k]).sum();
            }
        }
    }
}

/// Applies `α·Δ` (constrained coordinates) to a state; contact nodes near the wall move
/// along it ([`crate::physics::contact::wall_following_step`]), those off it that may land
/// land on it ([`crate::physics::contact::landing_step`]), and soft-law ones go no deeper
/// than their bound ([`crate::physics::contact::deepening_step`]).
fn update(
    c: &Constraints,
    walls: &[Option<Wall>],
    state: &StaticState,
    delta: &[f64],
    alpha: f64,
    may_land: &[bool],
    landed: &mut Vec<usize>,
) -> StaticState {
    use rayon::prelude::*;
    // Every node in parallel (each moves alone, in place), the landings listed in node order.
    let mut s = state.clone();
    let lands: Vec<usize> = (s.u.par_iter_mut(), s.rot.par_iter_mut())
        .into_par_iter()
        .enumerate()
        .with_min_len(64)
        .filter_map(|(i, (u, rot))| {
            let mut du: Vec3<f64> = std::array::from_fn(|k| alpha * delta[6 * i + k]);
            let mut lands = false;
            if let Some(b) = &c.basis[i] {
                du = std::array::from_fn(|r| (0..3).map(|k| b[r][k] * du[k]).sum());
            }
            if let Some(w) = &walls[i] {
                let d = *u;
                du = crate::physics::contact::wall_following_step(&d, &w.axis, &du, w.min_radius);
                if may_land.get(i).copied().unwrap_or(false) {
                    let l = crate::physics::contact::landing_step(&d, &w.axis, &du, w.clearance);
                    if l != du {
                        lands = true;
                        du = l;
                    }
                }
                if w.deepens {
                    du = crate::physics::contact::deepening_step(&d, &w.axis, &du, w.clearance);
                }
            }
            for (x, d) in u.iter_mut().zip(du) {
                *x += d;
            }
            let dth: Vec3<f64> = std::array::from_fn(|k| alpha * delta[6 * i + 3 + k]);
            *rot = mat_mul(&rotation_exp(&dth), rot);
            lands.then_some(i)
        })
        .collect();
    landed.extend(lands);
    s
}

/// A contact node's hole: its axis and the lateral offset from which its steps follow the
/// wall (the node's displacement is its offset from the axis point it was placed at).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Wall {
    axis: Vec3<f64>,
    min_radius: f64,
    clearance: f64,
    /// Its steps are bounded in depth ([`crate::physics::contact::deepens`]).
    deepens: bool,
}

/// Per node, the hole its contact site sits in (none where no site).
pub(crate) fn walls(model: &Model) -> Vec<Option<Wall>> {
    let mut w = vec![None; model.nodes.len()];
    for site in &model.sites {
        let node = &model.nodes[site.node];
        w[site.node] = Some(Wall {
            axis: node.hole_axis,
            min_radius: crate::physics::contact::wall_following_radius(site.params.clearance),
            clearance: site.params.clearance,
            deepens: crate::physics::contact::deepens(site.params.spring_exponent),
        });
    }
    w
}

/// Residual measure: max(|force| / F_ref, |moment| / (F_ref·1 m)).
fn residual_measure(r: &[f64], f_ref: f64) -> f64 {
    r.iter().fold(0.0f64, |m, x| m.max(x.abs())) / f_ref
}

/// Total weight and WOB scale — and a kink's moment held straight, `6 EI α / l0` (N·m per
/// m) — : the reference force of the convergence test.
pub fn reference_force(model: &Model) -> f64 {
    let kink = model
        .bends
        .iter()
        .map(|b| {
            let e = &model.elements[b.node - 1];
            6.0 * e.section.bending_stiffness() / e.length0 * b.angle.abs()
        })
        .fold(0.0f64, f64::max);
    let weight: f64 = model
        .elements
        .iter()
        .map(|e| e.buoyed_weight_per_length.abs() * e.length0)
        .sum();
    let point = model
        .point_loads
        .iter()
        .flat_map(|(_, l)| l.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    weight
        .max(model.weight_on_bit.abs())
        .max(model.torque_on_bit.abs())
        .max(point)
        .max(kink)
        .max(1.0)
}

/// Solves for static equilibrium at full load, from the undeformed configuration, or with
/// contact sites from [`StaticState::on_low_side`] ([`static_start`]).
pub fn solve_static(model: &Model, options: &StaticOptions) -> Result<StaticSolution, StaticError> {
    solve_static_started(model, options, &mut |_| {})
}

/// [`solve_static_monitored`] from [`static_start`]; `progress` sees the load path
/// ([`crate::solve::continuation::Progress`]).
pub fn solve_static_started(
    model: &Model,
    options: &StaticOptions,
    progress: &mut dyn FnMut(&crate::solve::continuation::Progress),
) -> Result<StaticSolution, StaticError> {
    solve_static_monitored(model, static_start(model), options, progress)
}

/// Where every static solve starts ([`solve_static`], the static command, the engine): the
/// string laid on the low side of the hole where it has contact sites, on the hole's axis
/// where it has none.
pub fn static_start(model: &Model) -> StaticState {
    if model.sites.is_empty() {
        StaticState::initial(model)
    } else {
        StaticState::on_low_side(model)
    }
}

/// The constrained tangent at a configuration and load factor (for stability checks:
/// it is positive definite exactly while the equilibrium is stable).
pub fn constrained_tangent(model: &Model, state: &StaticState, lambda: f64) -> BlockTridiagonal {
    constrained_system(model, state, lambda).1
}

/// The constraints as tables for the GPU assembly: per node the translation basis
/// (row-major, identity where the node has none) and a bit mask of fixed DOFs (bit `d` for
/// DOF `d` in that basis).
pub fn constraint_tables(model: &Model) -> (Vec<f64>, Vec<u32>) {
    let c = constraints(model);
    let mut basis = Vec::with_capacity(9 * model.nodes.len());
    for b in &c.basis {
        let m = b.unwrap_or_else(|| rotation_exp(&[0.0; 3]));
        basis.extend(m.iter().flatten());
    }
    let fixed = c
        .fixed
        .iter()
        .map(|f| (0..6).filter(|&d| f[d]).fold(0u32, |m, d| m | (1 << d)))
        .collect();
    (basis, fixed)
}

/// Residual and tangent with the constraints applied (the Newton system), at a
/// configuration and load factor.
pub fn constrained_system(
    model: &Model,
    state: &StaticState,
    lambda: f64,
) -> (Vec<f64>, BlockTridiagonal) {
    let (mut residual, mut tangent) = assembled(model, state, lambda);
    constrain(&constraints(model), &mut residual, &mut tangent);
    (residual, tangent)
}

/// Residual `f_int + g − λ f_ext` and tangent at a configuration, before constraints (the
/// oracle of `shaders/assemble.wgsl`).
pub fn assembled(model: &Model, state: &StaticState, lambda: f64) -> (Vec<f64>, BlockTridiagonal) {
    let n = model.nodes.len();
    let mut residual = vec![0.0; 6 * n];
    let mut tangent = BlockTridiagonal::zeros(n);
    let f_ext = external_loads(model);
    assemble(
        model,
        state,
        lambda,
        &f_ext,
        &mut residual,
        Some(&mut tangent),
    );
    (residual, tangent)
}

/// Internal force vector (elements and contacts) at a configuration, unconstrained.
pub fn internal_forces(model: &Model, state: &StaticState) -> Vec<f64> {
    let n = model.nodes.len();
    let mut residual = vec![0.0; 6 * n];
    assemble(model, state, 0.0, &vec![0.0; 6 * n], &mut residual, None);
    residual
}

/// As [`solve_static`], from a given starting configuration (e.g. a string laid on the
/// low side of the hole). The load path and Newton are the ensemble engine's
/// ([`crate::solve::continuation`], [`crate::solve::newton`]), run for one variant.
pub fn solve_static_from(
    model: &Model,
    start: StaticState,
    options: &StaticOptions,
) -> Result<StaticSolution, StaticError> {
    solve_static_monitored(model, start, options, &mut |_| {})
}

/// As [`solve_static_from`], calling `progress` with the load path after every Newton
/// iteration ([`crate::solve::continuation::Progress`]: the load factor reached, the
/// stage), and stopping once `options.max_seconds` are spent.
pub fn solve_static_monitored(
    model: &Model,
    start: StaticState,
    options: &StaticOptions,
    progress: &mut dyn FnMut(&crate::solve::continuation::Progress),
) -> Result<StaticSolution, StaticError> {
    use crate::solve::continuation::{solve_loads_from, LoadPath};
    let clock = std::time::Instant::now();
    let mut sys = CpuStatic::new(model, start);
    let mut paths = [LoadPath::for_model(options, model, false)];
    let settings = options.newton(8, [model]);
    let budget = options.max_seconds.unwrap_or(f64::INFINITY);
    let over = || clock.elapsed().as_secs_f64() > budget;
    let mut solves = 0;
    if let Err(reason) = solve_loads_from(
        &mut sys,
        &mut paths,
        settings,
        None,
        &|_, _| over(),
        &mut solves,
        progress,
    ) {
        return Err(StaticError::LoadStep {
            stage: "the static solve".into(),
            from: 0.0,
            step: 0.0,
            min: options.min_step,
            reason: reason.to_string(),
            at_md: None,
            stopped: None,
        });
    }
    let [mut path] = paths;
    let stopped_between = path.stopped_between();
    if let Some(mut e) = path.error.take() {
        if let (Some(between), Some((state, target))) = (stopped_between, sys.kept) {
            // The string stops on its way: where it stands is the equilibrium kept at the
            // bracket's lower end (a relaxation's end, or the last load step).
            if let StaticError::LoadStep { stopped, .. } = &mut e {
                *stopped = Stopped::at_kept(model, between, state, &target).map(Box::new);
            }
        }
        return Err(e);
    }
    if !path.finished() {
        return Err(StaticError::Budget {
            seconds: clock.elapsed().as_secs_f64(),
            reached: path.progress(),
        });
    }
    Ok(finish(model, sys.state, path.iterations, path.log))
}

impl Stopped {
    /// Where `model`'s string stands when its load path bracketed where it stops
    /// (`between`: [`crate::solve::continuation::LoadPath::stopped_between`]), from the
    /// equilibrium its system kept last (`state` at the loads `at`); `None` where that is
    /// not the bracket's lower end at full gravity and spring laws. The CPU solve's and the
    /// engine's, one rule.
    pub fn at_kept(
        model: &Model,
        between: (f64, f64),
        state: StaticState,
        at: &crate::solve::continuation::LoadTarget,
    ) -> Option<Self> {
        let (lambda, none_at) = between;
        (at.lambda == lambda && at.gravity == 1.0 && at.exponent == 1.0).then(|| Stopped {
            lambda,
            none_at,
            model: model_at(model, at),
            u: state.u,
            rot: state.rot,
        })
    }
}

/// The solution (section forces, contact, reactions) of the string where it stops
/// ([`Stopped`]), in its model at those loads.
pub fn stopped_solution(stopped: &Stopped) -> StaticSolution {
    let state = StaticState {
        u: stopped.u.clone(),
        rot: stopped.rot.clone(),
    };
    solution_at(&stopped.model, state)
}

/// The largest residual of a configuration at full load over the force scale (the
/// convergence test's measure), in f64.
pub fn residual_measure_at(model: &Model, state: &StaticState) -> f64 {
    let mut r = vec![0.0; 6 * model.nodes.len()];
    assemble(model, state, 1.0, &external_loads(model), &mut r, None);
    constrain_residual(&constraints(model), &mut r);
    residual_measure(&r, reference_force(model))
}

/// Newton at full load from `state` (an equilibrium found in another precision, say), on
/// the CPU in f64, with the load path's step cuts where the full step fails.
pub fn polish_static(
    model: &Model,
    state: StaticState,
    options: &StaticOptions,
) -> Result<StaticSolution, StaticError> {
    use crate::solve::continuation::{solve_loads, LoadPath};
    let mut sys = CpuStatic::new(model, state);
    let mut paths = [LoadPath::at_full_load(options)];
    let settings = options.newton(8, [model]);
    solve_loads(&mut sys, &mut paths, settings, &mut |_| {}).map_err(|reason| {
        StaticError::LoadStep {
            stage: "the f64 polish".into(),
            from: 0.0,
            step: 0.0,
            min: options.min_step,
            reason: reason.to_string(),
            at_md: None,
            stopped: None,
        }
    })?;
    let [path] = paths;
    if let Some(e) = path.error {
        return Err(e);
    }
    Ok(finish(model, sys.state, path.iterations, path.log))
}
