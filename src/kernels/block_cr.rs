//! Twin of `shaders/block_cr.wgsl`: the block-tridiagonal solve of every variant's Newton
//! system by block cyclic reduction (odd–even reduction), a node per invocation.
//!
//! [`crate::kernels::block_lu`] walks the chain node after node: `n` dependent steps, each
//! a 6 × 6 elimination, whatever the number of variants. On a GPU that walk is most of a
//! Newton iteration (16–20 µs a node on an H100, at V = 16 and at V = 4096 alike; issue 27).
//! Cyclic reduction takes `⌈log₂ n⌉` levels instead, each a dispatch whose nodes are
//! independent. At level `s` (1, 2, 4, …) the nodes still in the system are the multiples
//! of `s`, coupled to their neighbours `s` away by `WL_i` (row `i`, column `i − s`) and
//! `WU_i` (column `i + s`). The odd ones (`j ≡ s mod 2s`) are eliminated:
//!
//! ```text
//! P_j = D_j⁻¹ WL_j,   Q_j = D_j⁻¹ WU_j,   r_j = D_j⁻¹ y_j          (odd j, LU with partial pivoting)
//! even i, left odd neighbour j = i − s:
//!   D_i −= WL_i Q_j,   y_i −= WL_i r_j,   WL_i ← −WL_i P_j          (now coupled to i − 2s)
//! even i, right odd neighbour j = i + s:
//!   D_i −= WU_i P_j,   y_i −= WU_i r_j,   WU_i ← −WU_i Q_j          (coupled to i + 2s, if any)
//! ```
//!
//! until node 0 is alone: `x_0 = D_0⁻¹ y_0`. Back substitution, coarsest level first:
//! `x_j = r_j − P_j x_{j−s} − Q_j x_{j+s}` for the odd nodes of each level.
//!
//! Each node is factored once, at the level where it is odd (node 0 last); a node's update
//! at level `s` and its factoring at level `2s` are one invocation (`shaders/block_cr.wgsl`:
//! `⌈log₂ n⌉ + 1` forward dispatches, `⌈log₂ n⌉` back). The pivots are those of the
//! odd–even ordering, not of the chain walk, so the solution agrees with
//! [`crate::kernels::block_lu::block_lu`]'s to rounding (≈ u·κ), not to the bit; the work
//! is about twice the walk's (the couplings' products), spread over `n/2`, `n/4`, …
//! invocations a variant. Stability: the eliminated diagonal blocks are those of the
//! odd–even permuted matrix's block LU, which for the block-diagonally-dominant tangents
//! here (the mass, the constraints, a beam node's own stiffness) are as well conditioned as
//! the walk's (tests/block_lu.rs: against faer on the paper cases' static tangents and on
//! random systems spanning six decades).
//!
//! Layout: the inputs as [`ChainBatch`]; the workspace per node `D`, `WL`, `WU` (36 each,
//! field `F` = 0, 1, 2 at `[(36 (F n + i) + rc) V + v]`) and `y` (`[(6 i + r) V + v]`).

// Index loops mirror the WGSL kernel line for line.
#![allow(clippy::needless_range_loop)]
use crate::kernels::block_lu::{ChainBatch, SINGULAR, SOLVED};
use crate::physics::Real;

type Block<T> = [[T; 6]; 6];

/// A 6 × 6 block factored in place (LU with partial pivoting, Doolittle: the multipliers
/// below the diagonal, `U` on and above it), its row swaps and the reciprocals of its pivots.
struct Factored<T> {
    lu: Block<T>,
    swap: [usize; 6],
    inv: [T; 6],
}

/// Factors `d`; `None` when a pivot is zero or not finite.
fn factor<T: Real>(mut d: Block<T>) -> Option<Factored<T>> {
    let mut swap = [0usize; 6];
    let mut inv = [T::zero(); 6];
    for col in 0..6 {
        let mut p = col;
        for r in col + 1..6 {
            if d[r][col].abs() > d[p][col].abs() {
                p = r;
            }
        }
        d.swap(col, p);
        swap[col] = p;
        let pivot = d[col][col];
        let pf = pivot.to_f64_lossy();
        if pf == 0.0 || !pf.is_finite() {
            return None;
        }
        inv[col] = T::one() / pivot;
        for r in col + 1..6 {
            let f = d[r][col] * inv[col];
            d[r][col] = f;
            for c in col + 1..6 {
                d[r][c] = d[r][c] - f * d[col][c];
            }
        }
    }
    Some(Factored { lu: d, swap, inv })
}

impl<T: Real> Factored<T> {
    /// `D⁻¹ b`.
    fn solve(&self, mut b: [T; 6]) -> [T; 6] {
        for col in 0..6 {
            b.swap(col, self.swap[col]);
        }
        for r in 1..6 {
            for k in 0..r {
                b[r] = b[r] - self.lu[r][k] * b[k];
            }
        }
        for r in (0..6).rev() {
            for k in r + 1..6 {
                b[r] = b[r] - self.lu[r][k] * b[k];
            }
            b[r] = b[r] * self.inv[r];
        }
        b
    }

    /// `D⁻¹ M`, column by column.
    fn solve_block(&self, m: &Block<T>) -> Block<T> {
        let mut out = [[T::zero(); 6]; 6];
        for c in 0..6 {
            let col = self.solve(std::array::from_fn(|r| m[r][c]));
            for r in 0..6 {
                out[r][c] = col[r];
            }
        }
        out
    }
}

/// `D −= A B` (column by column, each entry's products subtracted in order).
fn sub_product<T: Real>(d: &mut Block<T>, a: &Block<T>, b: &Block<T>) {
    for c in 0..6 {
        for r in 0..6 {
            for k in 0..6 {
                d[r][c] = d[r][c] - a[r][k] * b[k][c];
            }
        }
    }
}

/// `−A B` (each entry's products subtracted from zero in order).
fn neg_product<T: Real>(a: &Block<T>, b: &Block<T>) -> Block<T> {
    let mut out = [[T::zero(); 6]; 6];
    for c in 0..6 {
        for r in 0..6 {
            let mut t = T::zero();
            for k in 0..6 {
                t = t - a[r][k] * b[k][c];
            }
            out[r][c] = t;
        }
    }
    out
}

/// `y −= A r`.
fn sub_vec<T: Real>(y: &mut [T; 6], a: &Block<T>, r: &[T; 6]) {
    for i in 0..6 {
        for k in 0..6 {
            y[i] = y[i] - a[i][k] * r[k];
        }
    }
}

/// The strides of the reduction's levels for `n` nodes: 1, 2, 4, … while below `n`.
pub fn levels(n: usize) -> Vec<usize> {
    std::iter::successors(Some(1usize), |s| s.checked_mul(2))
        .take_while(|&s| s < n)
        .collect()
}

/// Solves variant `j` (the work of the WGSL kernel's invocations of variant `j`).
fn solve_one<T: Real>(b: &ChainBatch<T>, j: usize) -> (Vec<T>, u32) {
    let (n, v) = (b.num_nodes, b.num_variants);
    let block = |data: &[T], i: usize| -> Block<T> {
        std::array::from_fn(|r| std::array::from_fn(|c| data[(36 * i + 6 * r + c) * v + j]))
    };
    let zero = [[T::zero(); 6]; 6];
    let mut d: Vec<Block<T>> = (0..n).map(|i| block(&b.diag, i)).collect();
    let mut wl: Vec<Block<T>> = (0..n)
        .map(|i| if i > 0 { block(&b.lower, i - 1) } else { zero })
        .collect();
    let mut wu: Vec<Block<T>> = (0..n)
        .map(|i| if i + 1 < n { block(&b.upper, i) } else { zero })
        .collect();
    let mut y: Vec<[T; 6]> = (0..n)
        .map(|i| std::array::from_fn(|r| b.rhs[(6 * i + r) * v + j]))
        .collect();
    let singular = (vec![T::zero(); 6 * n], SINGULAR);
    // Factors node i in place: WL, WU (where coupled) and y become P, Q and r.
    let eliminate = |i: usize,
                     left: bool,
                     right: bool,
                     d: &[Block<T>],
                     wl: &mut [Block<T>],
                     wu: &mut [Block<T>],
                     y: &mut [[T; 6]]|
     -> bool {
        let Some(f) = factor(d[i]) else { return false };
        y[i] = f.solve(y[i]);
        if left {
            wl[i] = f.solve_block(&wl[i]);
        }
        if right {
            wu[i] = f.solve_block(&wu[i]);
        }
        true
    };
    // Level 1's odd nodes (the first dispatch).
    for i in (1..n).step_by(2) {
        if !eliminate(i, true, i + 1 < n, &d, &mut wl, &mut wu, &mut y) {
            return singular;
        }
    }
    let levels = levels(n);
    for &s in &levels {
        for i in (0..n).step_by(2 * s) {
            if i >= 2 * s {
                let j = i - s;
                let a = wl[i];
                sub_product(&mut d[i], &a, &wu[j]);
                let rj = y[j];
                sub_vec(&mut y[i], &a, &rj);
                wl[i] = neg_product(&a, &wl[j]);
            }
            if i + s < n {
                let j = i + s;
                let a = wu[i];
                sub_product(&mut d[i], &a, &wl[j]);
                let rj = y[j];
                sub_vec(&mut y[i], &a, &rj);
                if j + s < n {
                    wu[i] = neg_product(&a, &wu[j]);
                }
            }
            // Odd at the next level: factored now.
            if i % (4 * s) == 2 * s
                && !eliminate(i, true, i + 2 * s < n, &d, &mut wl, &mut wu, &mut y)
            {
                return singular;
            }
        }
    }
    // Node 0 alone.
    let Some(f0) = factor(d[0]) else {
        return singular;
    };
    let mut x = vec![[T::zero(); 6]; n];
    x[0] = f0.solve(y[0]);
    for &s in levels.iter().rev() {
        for jn in (s..n).step_by(2 * s) {
            let mut xj = y[jn];
            for r in 0..6 {
                for c in 0..6 {
                    xj[r] = xj[r] - wl[jn][r][c] * x[jn - s][c];
                }
                if jn + s < n {
                    for c in 0..6 {
                        xj[r] = xj[r] - wu[jn][r][c] * x[jn + s][c];
                    }
                }
            }
            x[jn] = xj;
        }
    }
    (x.into_iter().flatten().collect(), SOLVED)
}

/// Solves every variant's system by cyclic reduction (rayon over variants). Returns the
/// field-major solution (`6 n V`) and a status per variant, as
/// [`crate::kernels::block_lu::block_lu`] (a singular variant: zero, alone).
pub fn block_cr<T: Real + Send + Sync>(b: &ChainBatch<T>) -> (Vec<T>, Vec<u32>) {
    crate::kernels::block_lu::per_variant(b, solve_one)
}
