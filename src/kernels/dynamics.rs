//! Twin of `shaders/dynamics.wgsl`: the generalised-α step of every variant on the
//! rotation group (as [`crate::solve::dynamics::Dynamics::step`]), in three kernels.
//!
//! `predict`, one invocation per (node, variant): from the state at `t_n` (`u`, `R`, `v`,
//! `a`, `v̇`) and the Newton unknown `v̇_{n+1}`, the trial state at `t_{n+1}`:
//!
//! ```text
//! a_{n+1} = (1−α_f)/(1−α_m) v̇_{n+1} + (α_f v̇_n − α_m a_n)/(1−α_m)
//! v_{n+1} = v_n + h((1−γ) a_n + γ a_{n+1})
//! Δq      = h (v_n + h((½−β) a_n + β a_{n+1}))
//! u_{n+1} = u_n + Δq_u,   R_{n+1} = exp([Δq_θ]×) R_n
//! ```
//!
//! At the top node the prescribed accelerations are written into `v̇` first (fixed DOFs 0,
//! the table's φ̈ about z, the hook's z̈), and the table's kinematics replace the result
//! (rotation about z by φ, spin φ̇; the hook's travel and speed along z).
//!
//! `accelerate`, one invocation per (node, variant): `v̇_out = v̇ + α_v (B Δv_u, Δv_θ)`
//! (the Newton correction, solved in each node's constrained basis, back to global axes).
//!
//! `inertial_scale`, one invocation per variant: `max_i m_i |v̇_u,i|` (the convergence
//! test's force scale for a whirling string).
//!
//! Layout: node vector entry `k` of node `i`, variant `v` at `[(6 i + k) V + v]`
//! (velocities, accelerations), `[(3 i + k) V + v]` (displacements), `[(9 i + 3 r + c) V + v]`
//! (rotations); per-variant top kinematics `[f · V + v]` ([`TOP_LEN`] fields).

// Index loops mirror the WGSL kernel line for line.
#![allow(clippy::needless_range_loop)]
use rayon::prelude::*;

use crate::kernels::update::rotation_exp_series;
use crate::physics::Real;

/// Per-variant top kinematics fields: the table's rotation (9, row-major), its angular
/// velocity and acceleration (3 each: `φ̇ n₀`, `φ̈ n₀`, about the top's hole axis `n₀`), the
/// hook's travel, speed and acceleration (3 each, along `n₀`).
pub const TOP_LEN: usize = 24;

/// Generalised-α coefficients of one step, and what drives the top node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepCoefficients<T> {
    /// Step h (s).
    pub h: T,
    /// α_m.
    pub alpha_m: T,
    /// α_f.
    pub alpha_f: T,
    /// β.
    pub beta: T,
    /// γ.
    pub gamma: T,
    /// Fixed-DOF mask of the top node.
    pub top_fixed: u32,
    /// The table turns the top node (clamped or hook-load tops).
    pub driven: bool,
    /// The hook lowers the top node along its hole axis.
    pub lowered: bool,
}

impl<T: Real> StepCoefficients<T> {
    /// `[h, α_m, α_f, β, γ]` for the kernel's coefficient buffer.
    pub fn reals(&self) -> [T; 5] {
        [self.h, self.alpha_m, self.alpha_f, self.beta, self.gamma]
    }

    /// `top_fixed | driven << 8 | lowered << 9`.
    pub fn flags(&self) -> u32 {
        self.top_fixed | (u32::from(self.driven) << 8) | (u32::from(self.lowered) << 9)
    }
}

/// The dynamic state of V variants on a chain of n nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicBatch<T> {
    /// Variants V.
    pub num_variants: usize,
    /// Nodes n.
    pub num_nodes: usize,
    /// Displacements, `3 n V`.
    pub u: Vec<T>,
    /// Rotations, `9 n V`.
    pub rot: Vec<T>,
    /// Velocities (ẋ, spatial ω), `6 n V`.
    pub vel: Vec<T>,
    /// Generalised-α pseudo-accelerations, `6 n V`.
    pub acc: Vec<T>,
    /// True accelerations v̇, `6 n V`.
    pub vdot: Vec<T>,
}

/// Writes the top's prescribed accelerations into `vdot` (variant `v`).
fn prescribe_top<T: Real>(c: &StepCoefficients<T>, top: &[T], vdot: &mut [T], nv: usize, v: usize) {
    for k in 0..6 {
        if c.top_fixed & (1 << k) != 0 {
            vdot[k * nv + v] = T::zero();
        }
    }
    for k in 0..3 {
        if c.driven {
            vdot[(3 + k) * nv + v] = top[(12 + k) * nv + v];
        }
        if c.lowered {
            vdot[k * nv + v] = top[(21 + k) * nv + v];
        }
    }
}

/// The trial state of node `i`, variant `v`: `(u, R, v, a)`.
fn predict_node<T: Real>(
    c: &StepCoefficients<T>,
    top: &[T],
    state: &DynamicBatch<T>,
    vdot: &[T],
    i: usize,
    v: usize,
) -> ([T; 3], [T; 9], [T; 6], [T; 6]) {
    let nv = state.num_variants;
    let one = T::one();
    let half = T::from_f64_lossy(0.5);
    let ratio = (one - c.alpha_f) / (one - c.alpha_m);
    let mut a1 = [T::zero(); 6];
    let mut v1 = [T::zero(); 6];
    let mut dq = [T::zero(); 6];
    for k in 0..6 {
        let idx = (6 * i + k) * nv + v;
        a1[k] = ratio * vdot[idx]
            + (c.alpha_f * state.vdot[idx] - c.alpha_m * state.acc[idx]) / (one - c.alpha_m);
        v1[k] = state.vel[idx] + c.h * ((one - c.gamma) * state.acc[idx] + c.gamma * a1[k]);
        dq[k] = c.h * (state.vel[idx] + c.h * ((half - c.beta) * state.acc[idx] + c.beta * a1[k]));
    }
    let mut u1 = [T::zero(); 3];
    for k in 0..3 {
        u1[k] = state.u[(3 * i + k) * nv + v] + dq[k];
    }
    let e = rotation_exp_series([dq[3], dq[4], dq[5]]);
    let mut r1 = [T::zero(); 9];
    for r in 0..3 {
        for col in 0..3 {
            let mut s = T::zero();
            for m in 0..3 {
                s = s + e[r][m] * state.rot[(9 * i + 3 * m + col) * nv + v];
            }
            r1[3 * r + col] = s;
        }
    }
    if i == 0 {
        if c.driven {
            for k in 0..9 {
                r1[k] = top[k * nv + v];
            }
            for k in 0..3 {
                v1[3 + k] = top[(9 + k) * nv + v];
            }
        }
        if c.lowered {
            for k in 0..3 {
                u1[k] = top[(15 + k) * nv + v];
                v1[k] = top[(18 + k) * nv + v];
            }
        }
    }
    (u1, r1, v1, a1)
}

/// The trial state of every variant at `vdot` (the top's prescribed accelerations written
/// into `vdot` first), into `trial` (its `vdot` set to `vdot`).
pub fn predict<T: Real + Send + Sync>(
    c: &StepCoefficients<T>,
    top: &[T],
    state: &DynamicBatch<T>,
    vdot: &mut [T],
    trial: &mut DynamicBatch<T>,
) {
    let (n, nv) = (state.num_nodes, state.num_variants);
    for v in 0..nv {
        prescribe_top(c, top, vdot, nv, v);
    }
    let vdot_ro: &[T] = vdot;
    let per: Vec<_> = (0..n * nv)
        .into_par_iter()
        .map(|idx| predict_node(c, top, state, vdot_ro, idx / nv, idx % nv))
        .collect();
    for (idx, (u1, r1, v1, a1)) in per.into_iter().enumerate() {
        let (i, v) = (idx / nv, idx % nv);
        for k in 0..3 {
            trial.u[(3 * i + k) * nv + v] = u1[k];
        }
        for k in 0..9 {
            trial.rot[(9 * i + k) * nv + v] = r1[k];
        }
        for k in 0..6 {
            trial.vel[(6 * i + k) * nv + v] = v1[k];
            trial.acc[(6 * i + k) * nv + v] = a1[k];
        }
    }
    trial.vdot.copy_from_slice(vdot_ro);
}

/// `out = vdot + α_v (B Δv_u, Δv_θ)` for every (node, variant).
pub fn accelerate<T: Real + Send + Sync>(
    basis: &[T],
    vdot: &[T],
    delta: &[T],
    alpha: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Vec<T> {
    let nv = num_variants;
    let mut out = vdot.to_vec();
    for i in 0..num_nodes {
        for v in 0..nv {
            for r in 0..3 {
                let mut s = T::zero();
                for k in 0..3 {
                    s = s + basis[9 * i + 3 * r + k] * delta[(6 * i + k) * nv + v];
                }
                out[(6 * i + r) * nv + v] = vdot[(6 * i + r) * nv + v] + alpha[v] * s;
            }
            for k in 3..6 {
                let idx = (6 * i + k) * nv + v;
                out[idx] = vdot[idx] + alpha[v] * delta[idx];
            }
        }
    }
    out
}

/// Per variant `max_i m_i |v̇_u,i|`.
pub fn inertial_scale<T: Real>(
    mass: &[T],
    vdot: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Vec<T> {
    (0..num_variants)
        .map(|v| {
            let mut s = T::zero();
            for i in 0..num_nodes {
                for k in 0..3 {
                    let f = (mass[i] * vdot[(6 * i + k) * num_variants + v]).abs();
                    if f.to_f64_lossy() > s.to_f64_lossy() || !f.to_f64_lossy().is_finite() {
                        s = f;
                    }
                }
            }
            s
        })
        .collect()
}
