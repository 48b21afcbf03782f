//! Twin of `shaders/block_lu.wgsl`: the block-tridiagonal solve of every variant's
//! Newton system, one variant per invocation (here: per rayon task).
//!
//! A chain of `n` nodes gives `A = tridiag(L_{i-1}, D_i, U_i)` with 6×6 blocks
//! ([`crate::kernels::tridiagonal::BlockTridiagonal`]). Block LU without pivoting between blocks
//! (the tangents are block-diagonally dominant once the mass or the constraints enter),
//! with partial pivoting inside each 6×6 block:
//!
//! ```text
//! G_0 = D_0,                       y_0 = b_0
//! X_i = G_i⁻¹ U_i,  z_i = G_i⁻¹ y_i
//! G_{i+1} = D_{i+1} − L_i X_i,     y_{i+1} = b_{i+1} − L_i z_i
//! x_{n−1} = z_{n−1},  x_i = z_i − X_i x_{i+1}
//! ```
//!
//! Each `G_i` is eliminated once on the augmented block `[G_i | U_i | y_i]` (6 × 13).
//! Layout (field-major, variant fastest): entry `rc = 6r + c` of block `i` of variant `v`
//! at `[(36 i + rc) · V + v]`; vector entry `r` of node `i` at `[(6 i + r) · V + v]`.

// Index loops mirror the WGSL kernel line for line.
#![allow(clippy::needless_range_loop)]
use rayon::prelude::*;

use crate::kernels::tridiagonal::BlockTridiagonal;
use crate::physics::Real;

/// Status of a variant's solve: solved.
pub const SOLVED: u32 = 0;
/// Status: a pivot was zero or not finite (singular or NaN system).
pub const SINGULAR: u32 = 1;

/// The systems of `V` variants on the same chain.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainBatch<T> {
    /// Variants `V`.
    pub num_variants: usize,
    /// Nodes `n`.
    pub num_nodes: usize,
    /// Diagonal blocks, `36 n V`.
    pub diag: Vec<T>,
    /// Upper blocks (row node i, column node i+1), `36 (n−1) V`.
    pub upper: Vec<T>,
    /// Lower blocks (row node i+1, column node i), `36 (n−1) V`.
    pub lower: Vec<T>,
    /// Right-hand sides, `6 n V`.
    pub rhs: Vec<T>,
}

impl ChainBatch<f64> {
    /// The batch with every real mapped by `f` (to f32 or a FLOP counter, as
    /// [`crate::kernels::update::ConfigBatch::map`]).
    pub fn map<U>(&self, f: impl Fn(f64) -> U) -> ChainBatch<U> {
        let c = |x: &[f64]| x.iter().map(|&y| f(y)).collect::<Vec<U>>();
        ChainBatch {
            num_variants: self.num_variants,
            num_nodes: self.num_nodes,
            diag: c(&self.diag),
            upper: c(&self.upper),
            lower: c(&self.lower),
            rhs: c(&self.rhs),
        }
    }
}

impl<T: Real> ChainBatch<T> {
    /// Packs one system per variant.
    pub fn from_systems(systems: &[(&BlockTridiagonal, &[f64])]) -> Self {
        let v = systems.len();
        let n = systems.first().map(|s| s.0.nodes()).unwrap_or(0);
        let m = n.saturating_sub(1);
        let mut b = ChainBatch {
            num_variants: v,
            num_nodes: n,
            diag: vec![T::zero(); 36 * n * v],
            upper: vec![T::zero(); 36 * m * v],
            lower: vec![T::zero(); 36 * m * v],
            rhs: vec![T::zero(); 6 * n * v],
        };
        for (j, (a, rhs)) in systems.iter().enumerate() {
            assert_eq!(a.nodes(), n, "every variant has the same chain");
            for i in 0..n {
                for r in 0..6 {
                    b.rhs[(6 * i + r) * v + j] = T::from_f64_lossy(rhs[6 * i + r]);
                    for c in 0..6 {
                        let at = (36 * i + 6 * r + c) * v + j;
                        b.diag[at] = T::from_f64_lossy(a.diag[i][r][c]);
                        if i < m {
                            b.upper[at] = T::from_f64_lossy(a.upper[i][r][c]);
                            b.lower[at] = T::from_f64_lossy(a.lower[i][r][c]);
                        }
                    }
                }
            }
        }
        b
    }

    /// Variant `j`'s solution out of a field-major vector.
    pub fn unpack(&self, x: &[T], j: usize) -> Vec<T> {
        let v = self.num_variants;
        (0..6 * self.num_nodes).map(|k| x[k * v + j]).collect()
    }
}

/// Eliminates the augmented 6 × 13 block `[G | U | y]` in place with partial pivoting:
/// afterwards columns 6..13 hold `G⁻¹[U | y]`. `false` when a pivot is zero or not finite.
pub fn eliminate<T: Real>(aug: &mut [[T; 13]; 6]) -> bool {
    for col in 0..6 {
        let mut p = col;
        for r in col + 1..6 {
            if aug[r][col].abs() > aug[p][col].abs() {
                p = r;
            }
        }
        aug.swap(col, p);
        let pivot = aug[col][col];
        let pivot_f = pivot.to_f64_lossy();
        if pivot_f == 0.0 || !pivot_f.is_finite() {
            return false;
        }
        let inv = T::one() / pivot;
        for c in col..13 {
            aug[col][c] = aug[col][c] * inv;
        }
        for r in 0..6 {
            if r != col {
                let f = aug[r][col];
                for c in col..13 {
                    aug[r][c] = aug[r][c] - f * aug[col][c];
                }
            }
        }
    }
    true
}

/// Solves variant `j` (the body of the WGSL kernel's invocation `j`).
fn solve_one<T: Real>(b: &ChainBatch<T>, j: usize) -> (Vec<T>, u32) {
    let (n, v) = (b.num_nodes, b.num_variants);
    let at = |i: usize, r: usize, c: usize| (36 * i + 6 * r + c) * v + j;
    walk(
        n,
        |i, r, c| b.diag[at(i, r, c)],
        |i, r, c| b.upper[at(i, r, c)],
        |i, r, c| b.lower[at(i, r, c)],
        |i, r| b.rhs[(6 * i + r) * v + j],
    )
}

/// The chain walk of one system of `n` nodes, its blocks' entries `(i, r, c)` and its
/// right-hand side's `(i, r)` read through the accessors: the one form of the block LU,
/// for a variant of a field-major batch ([`block_lu`], the GPU kernel's twin) and for the
/// CPU solvers' node-major [`BlockTridiagonal`] ([`block_lu_one`]) alike, so the two give
/// the same numbers. Returns the node-major solution and the status.
pub fn walk<T: Real>(
    n: usize,
    diag: impl Fn(usize, usize, usize) -> T,
    upper: impl Fn(usize, usize, usize) -> T,
    lower: impl Fn(usize, usize, usize) -> T,
    rhs: impl Fn(usize, usize) -> T,
) -> (Vec<T>, u32) {
    let mut xs = vec![[[T::zero(); 6]; 6]; n.saturating_sub(1)];
    let mut zs = vec![[T::zero(); 6]; n];
    let mut prev_x = [[T::zero(); 6]; 6];
    let mut prev_z = [T::zero(); 6];
    for i in 0..n {
        let mut aug = [[T::zero(); 13]; 6];
        for r in 0..6 {
            for c in 0..6 {
                aug[r][c] = diag(i, r, c);
                if i + 1 < n {
                    aug[r][6 + c] = upper(i, r, c);
                }
            }
            aug[r][12] = rhs(i, r);
            if i > 0 {
                for k in 0..6 {
                    let l = lower(i - 1, r, k);
                    for c in 0..6 {
                        aug[r][c] = aug[r][c] - l * prev_x[k][c];
                    }
                    aug[r][12] = aug[r][12] - l * prev_z[k];
                }
            }
        }
        if !eliminate(&mut aug) {
            return (vec![T::zero(); 6 * n], SINGULAR);
        }
        for r in 0..6 {
            for c in 0..6 {
                prev_x[r][c] = aug[r][6 + c];
            }
            prev_z[r] = aug[r][12];
        }
        if i + 1 < n {
            xs[i] = prev_x;
        }
        zs[i] = prev_z;
    }
    let mut x = vec![T::zero(); 6 * n];
    for i in (0..n).rev() {
        for r in 0..6 {
            let mut s = zs[i][r];
            if i + 1 < n {
                for c in 0..6 {
                    s = s - xs[i][r][c] * x[6 * (i + 1) + c];
                }
            }
            x[6 * i + r] = s;
        }
    }
    (x, SOLVED)
}

/// Solves one node-major system `A x = b` by [`walk`] on the calling thread (the CPU
/// solvers' block LU, [`crate::solve::chain::ChainSolver::solve`]): the numbers of
/// [`block_lu`] on a batch of that one system, without packing it field-major or handing it
/// to another thread. Returns the solution and the status.
pub fn block_lu_one(a: &BlockTridiagonal, b: &[f64]) -> (Vec<f64>, u32) {
    walk(
        a.nodes(),
        |i, r, c| a.diag[i][r][c],
        |i, r, c| a.upper[i][r][c],
        |i, r, c| a.lower[i][r][c],
        |i, r| b[6 * i + r],
    )
}

/// Solves every variant's system (rayon over variants). Returns the field-major solution
/// (`6 n V`) and a status per variant ([`SOLVED`] or [`SINGULAR`]; a singular variant's
/// solution is zero and no other variant is affected).
pub fn block_lu<T: Real + Send + Sync>(b: &ChainBatch<T>) -> (Vec<T>, Vec<u32>) {
    per_variant(b, solve_one)
}

/// Solves every variant with `solve` (rayon over variants; `solve(b, j)` gives variant `j`'s
/// solution, node-major, and status) into the field-major solution and the statuses.
pub fn per_variant<T: Real + Send + Sync>(
    b: &ChainBatch<T>,
    solve: impl Fn(&ChainBatch<T>, usize) -> (Vec<T>, u32) + Sync,
) -> (Vec<T>, Vec<u32>) {
    let v = b.num_variants;
    let per: Vec<(Vec<T>, u32)> = (0..v).into_par_iter().map(|j| solve(b, j)).collect();
    let mut x = vec![T::zero(); 6 * b.num_nodes * v];
    let mut status = vec![SOLVED; v];
    for (j, (xj, s)) in per.into_iter().enumerate() {
        status[j] = s;
        for (k, val) in xj.into_iter().enumerate() {
            x[k * v + j] = val;
        }
    }
    (x, status)
}
