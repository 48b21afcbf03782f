//! Twin of `shaders/assemble.wgsl`: the static residual and block-tridiagonal tangent of
//! every variant, gathered per node (one invocation per (node, variant), no atomics).
//!
//! Node `i` of variant `v` sums the halves of its two elements and its contact site, then
//! applies the constraints to the blocks it owns (as `statics::constrain`: each block
//! `(a, b)` becomes `diag(B_a, I)ᵀ · block · diag(B_b, I)`, then fixed DOFs get zero rows
//! and columns, 1 on the diagonal and a zero right-hand side):
//!
//! ```text
//! r_i   = f_{i−1}[6..12] + f_i[0..6] + g_site − f_ext,i
//! D_i   = K_{i−1}[6..12][6..12] + K_i[0..6][0..6] + [K_site | 0]
//! U_i   = K_i[0..6][6..12],   L_i = K_i[6..12][0..6]      (i < n − 1)
//! ```
//!
//! Inputs are the beam kernel's element force (12) and tangent (its 81 independent entries,
//! [`crate::kernels::beam::TANGENT_LEN`]; the 144 of `K` by [`tangent_slot`]) per (element,
//! variant) and the contact kernel's outputs per (site, variant), in their layouts; outputs
//! are in the [`crate::kernels::block_lu::ChainBatch`] layout, ready for the block solve.
//! Layout: element field `j` of element `e`, variant `v` at `[(12 e + j) V + v]` (force)
//! and `[(81 e + 9 r + d) V + v]` (tangent); contact field `k` of pair `s·V + v` at
//! `[k · S V + s V + v]`; `node_site[i V + v]` is the site at node `i` or `u32::MAX`.

// Index loops mirror the WGSL kernel line for line.
#![allow(clippy::needless_range_loop)]
use rayon::prelude::*;

use crate::kernels::beam::{tangent_slot, TANGENT_LEN};
use crate::kernels::block_lu::ChainBatch;
use crate::kernels::contact::{OUT_C, OUT_C_OMEGA, OUT_G, OUT_K};
use crate::physics::rotation::Trig;
use crate::physics::Real;

/// No contact site at a node.
pub const NO_SITE: u32 = u32::MAX;

/// Everything the assembly reads, for V variants on a chain of n nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblyInputs<T> {
    /// Variants V.
    pub num_variants: usize,
    /// Nodes n.
    pub num_nodes: usize,
    /// Contact sites S per variant.
    pub num_sites: usize,
    /// Element internal forces, `12 (n−1) V`.
    pub elem_force: Vec<T>,
    /// Element tangents, `81 (n−1) V` ([`crate::kernels::beam::TANGENT_LEN`]).
    pub elem_tangent: Vec<T>,
    /// Contact outputs (the contact kernel's `values`), `48 S V`.
    pub contact: Vec<T>,
    /// Contact flags per pair, `S V`.
    pub contact_flag: Vec<u32>,
    /// Site at each node per variant, `n V` ([`NO_SITE`] where none).
    pub node_site: Vec<u32>,
    /// External loads (already scaled by the load factor), `6 n V`.
    pub f_ext: Vec<T>,
    /// Translation basis per node (row-major, identity where none), `9 n`, shared.
    pub basis: Vec<T>,
    /// Fixed-DOF bit mask per node (bit `d`: DOF `d` in the basis), `n`, shared.
    pub fixed: Vec<u32>,
    /// The dynamic terms (`None`: the static residual and tangent).
    pub dynamic: Option<DynamicInputs<T>>,
    /// A relaxation's proximal shift (static only; `None`: none, the kernel is then built
    /// without it).
    pub shift: Option<ShiftInputs<T>>,
}

/// What a relaxation's proximal shift adds to the static assembly
/// ([`crate::solve::continuation`]'s `Stage::Relax`): `s_v (u − a)` on each node's
/// translations' residual and `s_v I` on their diagonal block, before the constraints (as
/// the CPU solve's `add_shift`: `s I` is the same in any node basis).
#[derive(Clone, Debug, PartialEq)]
pub struct ShiftInputs<T> {
    /// The shift per variant (N/m; 0: none), `V`.
    pub shift: Vec<T>,
    /// The anchor's displacements from the base, `3 n V` (`[(3 i + k) V + v]`).
    pub anchor: Vec<T>,
    /// The configuration's displacements from the base, `3 n V`.
    pub x: Vec<T>,
    /// The rotations' shift per variant (N·m/rad; 0: none), `V`: once a relaxation's
    /// translational shift reached its ceiling, `s_r log(R R_aᵀ)` on each node's moments'
    /// residual and `s_r I` on their diagonal block (the CPU solve's `add_rotation_shift`).
    /// Empty: no variant's rotations shifted.
    pub rot_shift: Vec<T>,
    /// The anchor's rotations `R_a`, `9 n V` (`[(9 i + 3 a + k) V + v]`, as the
    /// configuration's; empty with `rot_shift`).
    pub anchor_rot: Vec<T>,
    /// The configuration's rotations `R`, `9 n V` (empty with `rot_shift`).
    pub rot: Vec<T>,
}

impl AssemblyInputs<f64> {
    /// The static inputs with every real mapped by `f` (to f32, or to a counting type);
    /// the dynamic terms are left out.
    pub fn map_static<U>(&self, f: impl Fn(f64) -> U) -> AssemblyInputs<U> {
        let c = |x: &[f64]| x.iter().map(|&y| f(y)).collect::<Vec<U>>();
        AssemblyInputs {
            num_variants: self.num_variants,
            num_nodes: self.num_nodes,
            num_sites: self.num_sites,
            elem_force: c(&self.elem_force),
            elem_tangent: c(&self.elem_tangent),
            contact: c(&self.contact),
            contact_flag: self.contact_flag.clone(),
            node_site: self.node_site.clone(),
            f_ext: c(&self.f_ext),
            basis: c(&self.basis),
            fixed: self.fixed.clone(),
            dynamic: None,
            shift: self.shift.as_ref().map(|sh| ShiftInputs {
                shift: c(&sh.shift),
                anchor: c(&sh.anchor),
                x: c(&sh.x),
                rot_shift: c(&sh.rot_shift),
                anchor_rot: c(&sh.anchor_rot),
                rot: c(&sh.rot),
            }),
        }
    }
}

/// What the dynamic assembly adds (generalised-α iteration matrix
/// `S = M + hγ' C_t + h²β' K_t` and the inertial residual; lumped mass, as
/// `solve::dynamics` with `mass = "lumped"` and mass-proportional Rayleigh damping on the
/// translations).
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicInputs<T> {
    /// `[hγ', h²β', a0]` (`γ' = γ(1−α_f)/(1−α_m)`, `β'` likewise; `a0` Rayleigh's mass
    /// factor).
    pub coefficients: [T; 3],
    /// Nodal mass, `n`.
    pub mass: Vec<T>,
    /// Nodal rotary inertia at the reference orientation (row-major), `9 n`.
    pub inertia0: Vec<T>,
    /// Rotations, `9 n V`.
    pub rot: Vec<T>,
    /// Velocities (ẋ, spatial ω), `6 n V`.
    pub vel: Vec<T>,
    /// Accelerations v̇, `6 n V`.
    pub vdot: Vec<T>,
    /// Hole axis per contact pair, `3 S V` (for the spin's damping column `c_ω nᵀ`).
    pub pair_normals: Vec<T>,
    /// Mass imbalance per node and variant at the reference orientation (kg·m),
    /// `3 n V`; empty: none (the kernel is then built without it).
    pub unbalance: Vec<T>,
}

/// `block ← diag(B_a, I)ᵀ · block · diag(B_b, I)`: rows of node `a`, then columns of node `b`.
fn transform<T: Real>(blk: &mut [T; 36], ba: &[T], bb: &[T]) {
    let rows: [[T; 6]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| blk[6 * r + c]));
    for r in 0..3 {
        for c in 0..6 {
            let mut s = T::zero();
            for k in 0..3 {
                s = s + ba[3 * k + r] * rows[k][c];
            }
            blk[6 * r + c] = s;
        }
    }
    for r in 0..6 {
        let v: [T; 3] = std::array::from_fn(|k| blk[6 * r + k]);
        for c in 0..3 {
            let mut s = T::zero();
            for k in 0..3 {
                s = s + v[k] * bb[3 * k + c];
            }
            blk[6 * r + c] = s;
        }
    }
}

/// Zeroes the rows of `blk` fixed in `row_mask` and the columns fixed in `col_mask`.
fn clear_fixed<T: Real>(blk: &mut [T; 36], row_mask: u32, col_mask: u32) {
    for d in 0..6 {
        for c in 0..6 {
            if row_mask & (1 << d) != 0 {
                blk[6 * d + c] = T::zero();
            }
            if col_mask & (1 << d) != 0 {
                blk[6 * c + d] = T::zero();
            }
        }
    }
}

/// One (node, variant) invocation: residual (6), diagonal (36), and, below the last node,
/// upper and lower (36 each). With `tangent` false (the kernel built `FORCE_ONLY`, static
/// or dynamic) the residual alone: the element tangents are not read and the blocks stay
/// zero.
fn node_blocks<T: Trig>(
    a: &AssemblyInputs<T>,
    i: usize,
    v: usize,
    tangent: bool,
) -> ([T; 6], [T; 36], [T; 36], [T; 36]) {
    let nv = a.num_variants;
    let n = a.num_nodes;
    let pairs = a.num_sites * nv;
    let mut r = [T::zero(); 6];
    let mut d = [T::zero(); 36];
    let mut u = [T::zero(); 36];
    let mut l = [T::zero(); 36];
    // Entry (j, k) of element e's tangent.
    let tan = |e: usize, j: usize, k: usize| -> T {
        let (slot, negated) = tangent_slot(j, k);
        let x = a.elem_tangent[(TANGENT_LEN * e + slot) * nv + v];
        if negated {
            -x
        } else {
            x
        }
    };
    for k in 0..6 {
        r[k] = T::zero() - a.f_ext[(6 * i + k) * nv + v];
    }
    if i > 0 {
        let e = i - 1;
        for k in 0..6 {
            r[k] = r[k] + a.elem_force[(12 * e + 6 + k) * nv + v];
            if !tangent {
                continue;
            }
            for c in 0..6 {
                d[6 * k + c] = d[6 * k + c] + tan(e, 6 + k, 6 + c);
            }
        }
    }
    if i + 1 < n {
        let e = i;
        for k in 0..6 {
            r[k] = r[k] + a.elem_force[(12 * e + k) * nv + v];
            if !tangent {
                continue;
            }
            for c in 0..6 {
                d[6 * k + c] = d[6 * k + c] + tan(e, k, c);
                u[6 * k + c] = tan(e, k, 6 + c);
                l[6 * k + c] = tan(e, 6 + k, c);
            }
        }
    }
    let s = a.node_site[i * nv + v];
    if s != NO_SITE {
        let p = s as usize * nv + v;
        if a.contact_flag[p] != 0 {
            for k in 0..6 {
                r[k] = r[k] + a.contact[(OUT_G + k) * pairs + p];
                if !tangent {
                    continue;
                }
                for c in 0..3 {
                    d[6 * k + c] = d[6 * k + c] + a.contact[(OUT_K + 3 * k + c) * pairs + p];
                }
            }
        }
    }
    if let Some(dy) = a.dynamic.as_ref() {
        let [hg, hhb, a0] = dy.coefficients;
        if tangent {
            for k in 0..36 {
                d[k] = hhb * d[k];
                u[k] = hhb * u[k];
                l[k] = hhb * l[k];
            }
        }
        if tangent && s != NO_SITE {
            let p = s as usize * nv + v;
            if a.contact_flag[p] != 0 {
                for k in 0..6 {
                    for c in 0..3 {
                        d[6 * k + c] =
                            d[6 * k + c] + hg * a.contact[(OUT_C + 3 * k + c) * pairs + p];
                        d[6 * k + 3 + c] = d[6 * k + 3 + c]
                            + hg * a.contact[(OUT_C_OMEGA + k) * pairs + p]
                                * dy.pair_normals[3 * p + c];
                    }
                }
            }
        }
        // J = R J0 Rᵀ.
        let rot = |r: usize, c: usize| dy.rot[(9 * i + 3 * r + c) * nv + v];
        let mut rj = [[T::zero(); 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                for k in 0..3 {
                    rj[r][c] = rj[r][c] + rot(r, k) * dy.inertia0[9 * i + 3 * k + c];
                }
            }
        }
        let mut j = [[T::zero(); 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                for k in 0..3 {
                    j[r][c] = j[r][c] + rj[r][k] * rot(c, k);
                }
            }
        }
        let m = dy.mass[i];
        let vel = |k: usize| dy.vel[(6 * i + k) * nv + v];
        let acc = |k: usize| dy.vdot[(6 * i + k) * nv + v];
        let w = [vel(3), vel(4), vel(5)];
        let mut jw = [T::zero(); 3];
        let mut jwd = [T::zero(); 3];
        for r in 0..3 {
            for k in 0..3 {
                jw[r] = jw[r] + j[r][k] * w[k];
                jwd[r] = jwd[r] + j[r][k] * acc(3 + k);
            }
        }
        let gyro = [
            w[1] * jw[2] - w[2] * jw[1],
            w[2] * jw[0] - w[0] * jw[2],
            w[0] * jw[1] - w[1] * jw[0],
        ];
        let skew = |x: [T; 3]| -> [[T; 3]; 3] {
            let z = T::zero();
            [
                [z, z - x[2], x[1]],
                [x[2], z, z - x[0]],
                [z - x[1], x[0], z],
            ]
        };
        let (sw, sjw) = (skew(w), skew(jw));
        for k in 0..3 {
            r[k] = r[k] + m * acc(k) + a0 * m * vel(k);
            r[3 + k] = r[3 + k] + jwd[k] + gyro[k];
            if !tangent {
                continue;
            }
            d[6 * k + k] = d[6 * k + k] + m + hg * a0 * m;
            for c in 0..3 {
                // ∂(ω × Jω)/∂ω = [ω]× J − [Jω]×.
                let mut swj = T::zero();
                for q in 0..3 {
                    swj = swj + sw[k][q] * j[q][c];
                }
                d[6 * (3 + k) + 3 + c] = d[6 * (3 + k) + 3 + c] + j[k][c] + hg * (swj - sjw[k][c]);
            }
        }
        // Mass imbalance: a rigid eccentric mass turning with the node.
        if !dy.unbalance.is_empty() {
            let u0: [T; 3] = std::array::from_fn(|k| dy.unbalance[(3 * i + k) * nv + v]);
            if m > T::zero() && u0.iter().any(|x| *x != T::zero()) {
                let u: [T; 3] = std::array::from_fn(|r| {
                    rot(r, 0) * u0[0] + rot(r, 1) * u0[1] + rot(r, 2) * u0[2]
                });
                let (ru, ju) = crate::physics::mass::unbalance_terms(
                    u,
                    m,
                    [acc(0), acc(1), acc(2)],
                    w,
                    [acc(3), acc(4), acc(5)],
                    hg,
                );
                for a in 0..6 {
                    r[a] = r[a] + ru[a];
                    if !tangent {
                        continue;
                    }
                    for b in 0..6 {
                        d[6 * a + b] = d[6 * a + b] + ju[a][b];
                    }
                }
            }
        }
    }
    if let Some(sh) = &a.shift {
        let s_v = sh.shift[v];
        if s_v != T::zero() {
            for k in 0..3 {
                let at = (3 * i + k) * nv + v;
                r[k] = r[k] + s_v * (sh.x[at] - sh.anchor[at]);
                if tangent {
                    d[7 * k] = d[7 * k] + s_v;
                }
            }
        }
        if let Some(&s_r) = sh.rot_shift.get(v).filter(|s| **s != T::zero()) {
            let at = |m: &[T], a: usize, k: usize| m[(9 * i + 3 * a + k) * nv + v];
            let rel: crate::physics::rotation::Mat3<T> = std::array::from_fn(|a| {
                std::array::from_fn(|b| {
                    (0..3).fold(T::zero(), |acc, k| {
                        acc + at(&sh.rot, a, k) * at(&sh.anchor_rot, b, k)
                    })
                })
            });
            let theta = crate::physics::rotation::rotation_log(&rel);
            for k in 0..3 {
                r[3 + k] = r[3 + k] + s_r * theta[k];
                if tangent {
                    d[7 * (3 + k)] = d[7 * (3 + k)] + s_r;
                }
            }
        }
    }
    // Constraints (as statics::constrain): bases, then fixed DOFs.
    let b_i = &a.basis[9 * i..9 * i + 9];
    if tangent {
        transform(&mut d, b_i, b_i);
    }
    let rv = r;
    for row in 0..3 {
        let mut s = T::zero();
        for k in 0..3 {
            s = s + b_i[3 * k + row] * rv[k];
        }
        r[row] = s;
    }
    let f_i = a.fixed[i];
    if !tangent {
        for k in 0..6 {
            if f_i & (1 << k) != 0 {
                r[k] = T::zero();
            }
        }
        return (r, d, u, l);
    }
    clear_fixed(&mut d, f_i, f_i);
    for k in 0..6 {
        if f_i & (1 << k) != 0 {
            r[k] = T::zero();
            d[6 * k + k] = T::one();
        }
    }
    if i + 1 < n {
        let b_j = &a.basis[9 * (i + 1)..9 * (i + 1) + 9];
        transform(&mut u, b_i, b_j);
        transform(&mut l, b_j, b_i);
        let f_j = a.fixed[i + 1];
        clear_fixed(&mut u, f_i, f_j);
        clear_fixed(&mut l, f_j, f_i);
    }
    (r, d, u, l)
}

/// Assembles every variant (rayon over nodes × variants). Returns the tangents with the
/// residuals as right-hand sides (`rhs = r`; the Newton step solves `K Δ = −r`).
pub fn assemble<T: Trig + Send + Sync>(a: &AssemblyInputs<T>) -> ChainBatch<T> {
    let (n, nv) = (a.num_nodes, a.num_variants);
    let per: Vec<_> = (0..n * nv)
        .into_par_iter()
        .map(|idx| node_blocks(a, idx / nv, idx % nv, true))
        .collect();
    let m = n.saturating_sub(1);
    let mut out = ChainBatch {
        num_variants: nv,
        num_nodes: n,
        diag: vec![T::zero(); 36 * n * nv],
        upper: vec![T::zero(); 36 * m * nv],
        lower: vec![T::zero(); 36 * m * nv],
        rhs: vec![T::zero(); 6 * n * nv],
    };
    for (idx, (r, d, u, l)) in per.into_iter().enumerate() {
        let (i, v) = (idx / nv, idx % nv);
        for k in 0..6 {
            out.rhs[(6 * i + k) * nv + v] = r[k];
        }
        for k in 0..36 {
            out.diag[(36 * i + k) * nv + v] = d[k];
            if i + 1 < n {
                out.upper[(36 * i + k) * nv + v] = u[k];
                out.lower[(36 * i + k) * nv + v] = l[k];
            }
        }
    }
    out
}

/// The residual alone of every variant, static or dynamic (twin of the kernel built
/// `FORCE_ONLY`, the line-search trials'): `rhs` as [`assemble`] gives it, the same sums in
/// the same order, without reading the element tangents (`a.elem_tangent` may be empty)
/// or forming a block.
pub fn assemble_residual<T: Trig + Send + Sync>(a: &AssemblyInputs<T>) -> Vec<T> {
    let (n, nv) = (a.num_nodes, a.num_variants);
    let per: Vec<[T; 6]> = (0..n * nv)
        .into_par_iter()
        .map(|idx| node_blocks(a, idx / nv, idx % nv, false).0)
        .collect();
    let mut rhs = vec![T::zero(); 6 * n * nv];
    for (idx, r) in per.into_iter().enumerate() {
        let (i, v) = (idx / nv, idx % nv);
        for k in 0..6 {
            rhs[(6 * i + k) * nv + v] = r[k];
        }
    }
    rhs
}
