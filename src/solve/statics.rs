//! Static equilibrium of the drillstring (paper §3.1): Newton on the global tangent with
//! load stepping and a backtracking line search. Rotations are updated multiplicatively
//! (`R ← exp([Δθ]×) R`). Contact elements act in `static` mode, their friction direction
//! set by the operation's virtual velocities.
//!
//! Boundary conditions: top clamped (all six DOFs); bit held laterally (the two
//! translations perpendicular to the hole axis), loaded by the weight on bit `−WOB·t` and
//! the torque on bit `−TOB·t` (`t` the down-hole axis); buoyed self-weight as consistent
//! nodal loads. All external loads are scaled by the load factor `λ ∈ [0, 1]`.

use crate::model::{Model, TopBoundary};
use crate::physics::beam::{
    element_force, force_and_tangent_closed, local_deformation, rotation_exp, section_forces,
    Chord, ElementState, Mat3, SectionForces,
};
use crate::physics::contact::{evaluate, ContactMode, ContactResponse, ContactTerms, SpringLaw};
use crate::physics::vec3::{cross, dot, scale, sub, Vec3};
use crate::solve::chain::{BlockTridiagonal, ChainSolver};

pub use super::static_options::{StaticError, StaticOptions};

/// Nodal configuration.
#[derive(Clone, Debug)]
pub struct StaticState {
    /// Node positions.
    pub x: Vec<Vec3<f64>>,
    /// Nodal rotations (from the initial configuration).
    pub rot: Vec<Mat3<f64>>,
}

impl StaticState {
    /// A first guess near the equilibrium under gravity (the load path's first stage), from
    /// the frictionless soft-string solution without bit loads (issue 22):
    /// - **prestressed**: each node moved along its hole axis by the stretch `∫ F/EA` of
    ///   the string above it (below it where the top is free axially), so the first
    ///   tangent carries the tension's geometric stiffness — without it a vertical section
    ///   under kilometres of pipe has only its bending stiffness laterally, and the first
    ///   Newton step throws it metres through the wall;
    /// - **laid on the wall** where a cable would lie: every contact node along the
    ///   lateral load `q = F·dt/ds + w·g_⊥` (tension `F` pulls the string to the inside of a
    ///   bend, weight to the low side), at the depth where the wall carries its share;
    /// - **lifting off near held points**: within the bending length of the top, the bit
    ///   and each stabilizer, the offset grows as a pinned beam's deflection (a collar
    ///   node 0.3 m above a bit held on the axis, laid on the wall, bends the collar with
    ///   hundreds of MN).
    pub fn on_low_side(model: &Model) -> StaticState {
        use crate::physics::soft_string::{soft_string, Operation};
        let mut s = StaticState::initial(model);
        let n = model.nodes.len();
        let cable = soft_string(
            model,
            &Operation {
                axial_speed: 0.0,
                rotation_speed: 0.0,
                weight_on_bit: 0.0,
                torque_on_bit: 0.0,
                friction: 0.0,
            },
        );
        // Axial prestress: each node moved along its hole axis by the stretch of the
        // string above it (below it where the top is free axially).
        let stretch: Vec<f64> = (0..n - 1)
            .map(|e| {
                let el = &model.elements[e];
                0.5 * (cable.tension[e] + cable.tension[e + 1]) * el.length0
                    / (el.section.youngs_modulus * el.section.area)
            })
            .collect();
        let mut u = vec![0.0; n];
        if matches!(model.top, TopBoundary::Clamped | TopBoundary::Pinned) {
            for e in 0..n - 1 {
                u[e + 1] = u[e] + stretch[e];
            }
        } else {
            for e in (0..n - 1).rev() {
                u[e] = u[e + 1] - stretch[e];
            }
        }
        for ((x, ui), node) in s.x.iter_mut().zip(&u).zip(&model.nodes) {
            for (xk, tk) in x.iter_mut().zip(node.hole_axis) {
                *xk += ui * tk;
            }
        }
        // Lateral: each contact node towards its lateral load, at the depth where the wall
        // carries the node's share of it.
        let mut offset: Vec<Option<(Vec3<f64>, f64)>> = vec![None; n];
        let mut load = vec![0.0; n];
        for site in &model.sites {
            let i = site.node;
            let held = i == 0 || (model.bit_lateral_fixed && i + 1 == n);
            if held {
                continue;
            }
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let ds = model.nodes[b].md - model.nodes[a].md;
            let dt = scale(
                &sub(&model.nodes[b].hole_axis, &model.nodes[a].hole_axis),
                1.0 / ds,
            );
            let t = model.nodes[i].hole_axis;
            let g = [0.0, 0.0, 1.0];
            let g_perp = sub(&g, &scale(&t, dot(&g, &t)));
            let w = model.elements[i.min(n - 2)].buoyed_weight_per_length;
            let q = [
                cable.tension[i] * dt[0] + w * g_perp[0],
                cable.tension[i] * dt[1] + w * g_perp[1],
                cable.tension[i] * dt[2] + w * g_perp[2],
            ];
            // Lateral part only.
            let q = sub(&q, &scale(&t, dot(&q, &t)));
            let len = dot(&q, &q).sqrt();
            if len > 1e-3 * w.abs().max(1e-12) {
                // Penetration at which the wall carries the node's share of the lateral
                // load (bisection on the spring law): a fixed guess would be far too deep for
                // a stiff wall (k_e = 1e11 with a soft spring) and far too shallow for a soft one.
                let share = len * 0.5 * ds;
                let depth = site.params.clearance + penetration_for(share, &site.params);
                offset[i] = Some((scale(&q, 1.0 / len), depth));
                load[i] = len;
            }
        }
        // Bending: next to a point held on or close to the axis (the top, the bit, a
        // stabilizer) the string cannot reach the wall at once; it lifts off over its
        // bending length, the tangency length of a pinned beam under its lateral load q,
        // `L = (24 EI c / q)^¼` (c the clearance), shortened by tension T to `4 √(EI/T)`.
        let bending_length = |site: &crate::model::Site| {
            let i = site.node;
            let ei = model.elements[i.min(n - 2)].section.bending_stiffness();
            let c = site.params.clearance.max(1e-6);
            let mut l = (24.0 * ei * c / load[i].max(1e-12)).powf(0.25);
            if cable.tension[i] > 0.0 {
                l = l.min(4.0 * (ei / cable.tension[i]).sqrt());
            }
            l
        };
        // Offset `m_a + (m − m_a) g(s/L)` within L of an anchor (offset m_a), with
        // `g(x) = 2x − 2x³ + x⁴` the pinned beam's deflection (g(1) = 1, g'(1) = 0).
        let ramp = |x: f64| 2.0 * x - 2.0 * x.powi(3) + x.powi(4);
        let mut magnitude: Vec<f64> = offset.iter().map(|o| o.map_or(0.0, |o| o.1)).collect();
        let mut anchors: Vec<(usize, f64)> = vec![(0, 0.0)];
        if model.bit_lateral_fixed {
            anchors.push((n - 1, 0.0));
        }
        // First the stabilizers against the top and the bit, then every other node against
        // those and the stabilizers.
        for stabilizers in [true, false] {
            for site in model.sites.iter().filter(|s| s.stabilizer == stabilizers) {
                let i = site.node;
                let Some((_, m)) = offset[i] else { continue };
                if anchors.iter().any(|a| a.0 == i) {
                    continue;
                }
                let l = bending_length(site);
                let below = anchors.iter().filter(|a| a.0 > i).min_by_key(|a| a.0);
                let above = anchors.iter().filter(|a| a.0 < i).max_by_key(|a| a.0);
                for &(k, m_a) in below.into_iter().chain(above) {
                    let d = (model.nodes[i].md - model.nodes[k].md).abs();
                    if d < l && m_a < m {
                        magnitude[i] = magnitude[i].min(m_a + (m - m_a) * ramp(d / l));
                    }
                }
            }
            if stabilizers {
                for site in model.sites.iter().filter(|s| s.stabilizer) {
                    anchors.push((site.node, magnitude[site.node]));
                }
            }
        }
        for i in 0..n {
            if let Some((dir, _)) = offset[i] {
                for (x, d) in s.x[i].iter_mut().zip(dir) {
                    *x += magnitude[i] * d;
                }
            }
        }
        s
    }

    /// The undeformed configuration (every node on the hole axis, no rotation).
    pub fn initial(model: &Model) -> StaticState {
        let eye = rotation_exp(&[0.0; 3]);
        StaticState {
            x: model.nodes.iter().map(|n| n.position).collect(),
            rot: vec![eye; model.nodes.len()],
        }
    }
}

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
pub fn external_loads(model: &Model) -> Vec<f64> {
    let n = model.nodes.len();
    let mut f = vec![0.0; 6 * n];
    for (i, e) in model.elements.iter().enumerate() {
        let q = [0.0, 0.0, e.buoyed_weight_per_length];
        let l = e.length0;
        let e1 = [e.frame0[0][0], e.frame0[1][0], e.frame0[2][0]];
        let m = scale(&cross(&e1, &q), l * l / 12.0);
        for k in 0..3 {
            f[6 * i + k] += q[k] * l / 2.0;
            f[6 * (i + 1) + k] += q[k] * l / 2.0;
            f[6 * i + 3 + k] += m[k];
            f[6 * (i + 1) + 3 + k] -= m[k];
        }
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

/// The static contact element at a site for a configuration (friction direction from the
/// operation's virtual velocities).
/// A site's contact response in static mode (friction direction from the operation).
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
    let d = sub(&state.x[site.node], &node.position);
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
    let with_tangent = tangent.is_some();
    for (i, (f, k)) in element_responses(model, state, with_tangent)
        .into_iter()
        .enumerate()
    {
        if let (Some(t), Some(k)) = (tangent.as_deref_mut(), k) {
            t.add_element(i, &k);
        }
        for j in 0..12 {
            residual[6 * i + j] += f[j];
        }
    }
    for site in &model.sites {
        let out = site_response(model, state, site);
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

/// An element's internal force and, if asked for, its tangent.
pub(crate) type ElementResponse = ([f64; 12], Option<[[f64; 12]; 12]>);

/// Internal force (12) and, if asked, tangent (12×12) of every element at a
/// configuration, computed in parallel over elements (rayon); summed by the caller in
/// element order, so the result does not depend on the thread count.
pub(crate) fn element_responses(
    model: &Model,
    state: &StaticState,
    with_tangent: bool,
) -> Vec<ElementResponse> {
    use rayon::prelude::*;
    model
        .elements
        .par_iter()
        .enumerate()
        .map(|(i, e)| {
            let es = ElementState {
                x: [state.x[i], state.x[i + 1]],
                triad: [
                    mat_mul(&state.rot[i], &model.nodes[i].frame0),
                    mat_mul(&state.rot[i + 1], &model.nodes[i + 1].frame0),
                ],
            };
            let k = model.element_stiffness(i);
            let form = Chord::Positions { length0: e.length0 };
            if with_tangent {
                let (f, t) = force_and_tangent_closed(&es.x, &es.triad, &form, &k);
                (f, Some(t))
            } else {
                (element_force(&es.x, &es.triad, &form, &k), None)
            }
        })
        .collect()
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
/// along it ([`crate::physics::contact::wall_following_step`]).
fn update(
    c: &Constraints,
    walls: &[Option<Wall>],
    state: &StaticState,
    delta: &[f64],
    alpha: f64,
) -> StaticState {
    let mut s = state.clone();
    for i in 0..s.x.len() {
        let mut du: Vec3<f64> = std::array::from_fn(|k| alpha * delta[6 * i + k]);
        if let Some(b) = &c.basis[i] {
            du = std::array::from_fn(|r| (0..3).map(|k| b[r][k] * du[k]).sum());
        }
        if let Some(w) = &walls[i] {
            let d = sub(&s.x[i], &w.origin);
            du = crate::physics::contact::wall_following_step(&d, &w.axis, &du, w.min_radius);
        }
        for (x, d) in s.x[i].iter_mut().zip(du) {
            *x += d;
        }
        let dth: Vec3<f64> = std::array::from_fn(|k| alpha * delta[6 * i + 3 + k]);
        s.rot[i] = mat_mul(&rotation_exp(&dth), &s.rot[i]);
    }
    s
}

/// A contact node's hole: its point on the axis, the axis, and the lateral offset from
/// which its steps follow the wall.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Wall {
    origin: Vec3<f64>,
    axis: Vec3<f64>,
    min_radius: f64,
}

/// Per node, the hole its contact site sits in (none where no site).
pub(crate) fn walls(model: &Model) -> Vec<Option<Wall>> {
    let mut w = vec![None; model.nodes.len()];
    for site in &model.sites {
        let node = &model.nodes[site.node];
        w[site.node] = Some(Wall {
            origin: node.position,
            axis: node.hole_axis,
            min_radius: crate::physics::contact::wall_following_radius(site.params.clearance),
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
/// contact sites from [`StaticState::on_low_side`].
pub fn solve_static(model: &Model, options: &StaticOptions) -> Result<StaticSolution, StaticError> {
    let start = if model.sites.is_empty() {
        StaticState::initial(model)
    } else {
        StaticState::on_low_side(model)
    };
    solve_static_from(model, start, options)
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

/// As [`solve_static_from`], calling `progress` with the load factor reached (0 … 1) after
/// every Newton iteration, and stopping once `options.max_seconds` are spent.
pub fn solve_static_monitored(
    model: &Model,
    start: StaticState,
    options: &StaticOptions,
    progress: &mut dyn FnMut(f64),
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
            reason,
            at_md: None,
        });
    }
    let [path] = paths;
    if let Some(e) = path.error {
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
            reason,
            at_md: None,
        }
    })?;
    let [path] = paths;
    if let Some(e) = path.error {
        return Err(e);
    }
    Ok(finish(model, sys.state, path.iterations, path.log))
}

/// One model's static Newton system on the CPU (faer), for [`solve_static_from`].
struct CpuStatic<'a> {
    model: &'a Model,
    c: Constraints,
    walls: Vec<Option<Wall>>,
    f_gravity: Vec<f64>,
    f_other: Vec<f64>,
    f_ref: f64,
    /// The model with the target's friction and spring exponents.
    loaded: Model,
    /// External loads of the target.
    f_step: Vec<f64>,
    state: StaticState,
    saved: StaticState,
    solver: ChainSolver,
    residual: Vec<f64>,
    tangent: BlockTridiagonal,
    trial: Vec<f64>,
    delta: Vec<f64>,
    trial_state: Option<(f64, StaticState)>,
    evaluated: bool,
}

impl<'a> CpuStatic<'a> {
    fn new(model: &'a Model, start: StaticState) -> Self {
        let (f_gravity, f_other) = split_loads(model);
        let n = model.nodes.len();
        CpuStatic {
            model,
            c: constraints(model),
            walls: walls(model),
            f_ref: reference_force(model),
            f_step: vec![0.0; 6 * n],
            f_gravity,
            f_other,
            loaded: model.clone(),
            saved: start.clone(),
            state: start,
            solver: ChainSolver::new(),
            residual: vec![0.0; 6 * n],
            tangent: BlockTridiagonal::zeros(n),
            trial: vec![0.0; 6 * n],
            delta: vec![0.0; 6 * n],
            trial_state: None,
            evaluated: false,
        }
    }
}

impl crate::solve::newton::NewtonSystem for CpuStatic<'_> {
    fn variants(&self) -> usize {
        1
    }
    fn solve(&mut self) -> Result<crate::solve::newton::Probe, String> {
        if !self.evaluated {
            assemble(
                &self.loaded,
                &self.state,
                1.0,
                &self.f_step,
                &mut self.residual,
                Some(&mut self.tangent),
            );
            constrain(&self.c, &mut self.residual, &mut self.tangent);
            self.evaluated = true;
        }
        let rhs: Vec<f64> = self.residual.iter().map(|x| -x).collect();
        let solved = match self.solver.solve(&self.tangent, &rhs) {
            Ok(d) => {
                self.delta = d;
                true
            }
            Err(_) => {
                self.delta.fill(0.0);
                false
            }
        };
        Ok(crate::solve::newton::Probe {
            measure: vec![residual_measure(&self.residual, self.f_ref)],
            step: vec![self.delta.iter().fold(0.0f64, |m, x| m.max(x.abs()))],
            slope: vec![dot_n(&self.delta, &self.residual)],
            norm: vec![dot_n(&self.residual, &self.residual).sqrt()],
            solved: vec![solved],
        })
    }
    fn trial(&mut self, alpha: &[f64]) -> Result<crate::solve::newton::TrialProbe, String> {
        let s = update(&self.c, &self.walls, &self.state, &self.delta, alpha[0]);
        assemble(&self.loaded, &s, 1.0, &self.f_step, &mut self.trial, None);
        constrain_residual(&self.c, &mut self.trial);
        self.trial_state = Some((alpha[0], s));
        Ok(crate::solve::newton::TrialProbe {
            slope: vec![dot_n(&self.delta, &self.trial)],
            norm: vec![dot_n(&self.trial, &self.trial).sqrt()],
        })
    }
    fn accept(&mut self, alpha: &[f64], trial_matches: bool) -> Result<(), String> {
        if alpha[0] == 0.0 {
            return Ok(());
        }
        self.state = match self.trial_state.take() {
            Some((a, s)) if trial_matches && a == alpha[0] => s,
            _ => update(&self.c, &self.walls, &self.state, &self.delta, alpha[0]),
        };
        self.evaluated = false;
        Ok(())
    }
}

impl crate::solve::continuation::StaticSystem for CpuStatic<'_> {
    fn set_target(
        &mut self,
        _j: usize,
        target: &crate::solve::continuation::LoadTarget,
    ) -> Result<(), String> {
        self.loaded = loaded_model(self.model, target);
        for (f, (g, o)) in self
            .f_step
            .iter_mut()
            .zip(self.f_gravity.iter().zip(&self.f_other))
        {
            *f = target.gravity * g + target.lambda * o;
        }
        self.evaluated = false;
        Ok(())
    }
    fn save(&mut self, _j: usize) -> Result<(), String> {
        self.saved = self.state.clone();
        Ok(())
    }
    fn restore(&mut self, _j: usize) -> Result<(), String> {
        self.state = self.saved.clone();
        self.evaluated = false;
        Ok(())
    }
    fn worst_residual_md(&mut self, _j: usize) -> Option<f64> {
        let k = (0..self.residual.len())
            .filter(|k| k % 6 < 3)
            .max_by(|&a, &b| self.residual[a].abs().total_cmp(&self.residual[b].abs()))?;
        Some(self.model.nodes[k / 6].md)
    }
    fn step_floor(&mut self, _j: usize) -> Result<f64, String> {
        let largest = self
            .state
            .x
            .iter()
            .flatten()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        Ok(crate::solve::newton::NewtonSettings::step_floor(8, largest))
    }
}

fn dot_n(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The model with a load target's friction factor and spring-exponent blend applied to
/// every site (the parameters the contact elements of that step use).
pub fn loaded_model(model: &Model, target: &crate::solve::continuation::LoadTarget) -> Model {
    let mut m = model.clone();
    for site in &mut m.sites {
        site.params = loaded_params(&site.params, target);
    }
    // Kinks grow with the bit loads (from the straight string laid in the hole).
    for b in &mut m.bends {
        b.angle *= target.lambda;
    }
    m
}

/// A site's law parameters at a load target: friction scaled, exponent blended from 1.
pub fn loaded_params(
    p: &crate::physics::contact::ContactParams<f64>,
    target: &crate::solve::continuation::LoadTarget,
) -> crate::physics::contact::ContactParams<f64> {
    let mut q = *p;
    q.mu_t *= target.friction;
    q.mu_l *= target.friction;
    if target.exponent != 1.0 {
        q.spring_exponent = 1.0 + target.exponent * (p.spring_exponent - 1.0);
    }
    q
}

/// Gravity loads and the other external loads (bit, point loads), at full value.
pub fn split_loads(model: &Model) -> (Vec<f64>, Vec<f64>) {
    let mut bare = model.clone();
    bare.weight_on_bit = 0.0;
    bare.torque_on_bit = 0.0;
    bare.point_loads.clear();
    let gravity = external_loads(&bare);
    let all = external_loads(model);
    let other = all.iter().zip(&gravity).map(|(a, g)| a - g).collect();
    (gravity, other)
}

/// Local deformation of element `i` at a configuration (its nodal triads `R_i · frame0_i`).
pub fn element_deformation(
    model: &Model,
    state: &StaticState,
    i: usize,
) -> crate::physics::beam::LocalDeformation<f64> {
    let t1 = mat_mul(&state.rot[i], &model.nodes[i].frame0);
    let t2 = mat_mul(&state.rot[i + 1], &model.nodes[i + 1].frame0);
    local_deformation(
        &state.x[i],
        &state.x[i + 1],
        &t1,
        &t2,
        model.elements[i].length0,
    )
    .minus_rest(&model.element_rest(i))
}

/// Section forces of element `i` at a configuration.
pub fn element_section_forces(
    model: &Model,
    state: &StaticState,
    i: usize,
) -> crate::physics::beam::SectionForces {
    let e = &model.elements[i];
    section_forces(&element_deformation(model, state, i), &e.section, e.length0)
}

/// The solution (section forces, contact, reactions) at a converged configuration.
pub fn solution_at(model: &Model, state: StaticState) -> StaticSolution {
    finish(model, state, vec![], vec![])
}

fn finish(
    model: &Model,
    state: StaticState,
    iterations: Vec<usize>,
    log: Vec<String>,
) -> StaticSolution {
    let section_forces = model
        .elements
        .iter()
        .enumerate()
        .map(|(i, e)| {
            section_forces(
                &element_deformation(model, &state, i),
                &e.section,
                e.length0,
            )
        })
        .collect();
    let contact = model
        .sites
        .iter()
        .map(|site| {
            let node = &model.nodes[site.node];
            let d = sub(&state.x[site.node], &node.position);
            let out = site_response(model, &state, site);
            // Normal force: the radial part of the internal force.
            let d_t = sub(&d, &scale(&node.hole_axis, dot(&d, &node.hole_axis)));
            let r = dot(&d_t, &d_t).sqrt();
            let normal = if r > 0.0 {
                dot(&[out.g[0], out.g[1], out.g[2]], &d_t) / r
            } else {
                0.0
            };
            (out.contact, normal, out.g)
        })
        .collect();
    let f_int = internal_forces(model, &state);
    let f_ext = external_loads(model);
    let top_reaction = std::array::from_fn(|k| f_int[k] - f_ext[k]);
    let b = 6 * (model.nodes.len() - 1);
    let bit_reaction = std::array::from_fn(|k| f_int[b + k] - f_ext[b + k]);
    StaticSolution {
        state,
        section_forces,
        contact,
        iterations,
        log,
        top_reaction,
        bit_reaction,
    }
}

/// Penetration `delta ≥ 0` at which the elastic wall force equals `force` (bisection).
fn penetration_for(force: f64, p: &crate::physics::contact::ContactParams<f64>) -> f64 {
    use crate::physics::contact::{elastic_force, SpringLaw};
    if force <= 0.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 1e-12);
    while elastic_force(hi, p, SpringLaw::PowerBlend).0 < force && hi < 1.0 {
        hi *= 10.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if elastic_force(mid, p, SpringLaw::PowerBlend).0 < force {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}
