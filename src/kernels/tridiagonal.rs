//! The block-tridiagonal matrix of a chain of 6-DOF nodes (element `i` couples nodes `i`
//! and `i+1`; a contact element sits on one node's diagonal block): the layout the block
//! LU ([`crate::kernels::block_lu`]) and the GPU block solve work on, and what
//! [`crate::solve::chain`] solves.

use faer::sparse::Triplet;

/// A 6×6 block.
pub type Block6 = [[f64; 6]; 6];

/// Adds the 6×6 quarter of an element matrix `k` (12×12, nodes `i` and `i+1`) that starts
/// at row `r0` and column `c0` (0 or 6) to `block`: where each of its blocks goes in the
/// chain ([`BlockTridiagonal::add_element`]; the parallel assembly's per-node gather).
pub fn add_quarter(block: &mut Block6, k: &[[f64; 12]; 12], r0: usize, c0: usize) {
    for (r, row) in block.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x += k[r0 + r][c0 + c];
        }
    }
}

/// Block-tridiagonal matrix over `n` nodes.
#[derive(Clone, Debug)]
pub struct BlockTridiagonal {
    /// Diagonal blocks (n).
    pub diag: Vec<Block6>,
    /// `upper[i]` couples row node `i` to column node `i+1` (n−1).
    pub upper: Vec<Block6>,
    /// `lower[i]` couples row node `i+1` to column node `i` (n−1).
    pub lower: Vec<Block6>,
}

impl BlockTridiagonal {
    /// Zeros for `n` nodes.
    pub fn zeros(n: usize) -> Self {
        BlockTridiagonal {
            diag: vec![[[0.0; 6]; 6]; n],
            upper: vec![[[0.0; 6]; 6]; n.saturating_sub(1)],
            lower: vec![[[0.0; 6]; 6]; n.saturating_sub(1)],
        }
    }

    /// A random block-diagonally dominant system of `n` nodes and its right-hand side
    /// (entries in −1…1, each diagonal beyond its rows' sums), scaled per node so that the
    /// entries span `2·decades` orders of magnitude (0: unscaled): what the block solves
    /// are tested (`tests/block_lu.rs`) and timed (`holewall bench element`) on.
    pub fn random_dominant(
        rng: &mut impl rand::Rng,
        n: usize,
        decades: i32,
    ) -> (BlockTridiagonal, Vec<f64>) {
        let scale = |i: usize| {
            if decades == 0 {
                1.0
            } else {
                10f64.powi((i as i32 % (2 * decades + 1)) - decades)
            }
        };
        let mut a = BlockTridiagonal::zeros(n);
        for blocks in [&mut a.upper, &mut a.lower] {
            for b in blocks.iter_mut() {
                for row in b.iter_mut() {
                    for x in row.iter_mut() {
                        *x = rng.random_range(-1.0..1.0);
                    }
                }
            }
        }
        for (i, b) in a.diag.iter_mut().enumerate() {
            for (r, row) in b.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x = rng.random_range(-1.0..1.0);
                    if r == c {
                        *x += 20.0 * scale(i);
                    }
                }
            }
            let s = scale(i);
            for (r, row) in b.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    if r != c {
                        *x *= s;
                    }
                }
            }
            if i > 0 {
                for row in a.lower[i - 1].iter_mut() {
                    for x in row.iter_mut() {
                        *x *= s;
                    }
                }
            }
            if i + 1 < n {
                for row in a.upper[i].iter_mut() {
                    for x in row.iter_mut() {
                        *x *= s;
                    }
                }
            }
        }
        let b = (0..6 * n).map(|_| rng.random_range(-1.0..1.0)).collect();
        (a, b)
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.diag.len()
    }

    /// Clears every entry.
    pub fn clear(&mut self) {
        for b in self
            .diag
            .iter_mut()
            .chain(self.upper.iter_mut())
            .chain(self.lower.iter_mut())
        {
            *b = [[0.0; 6]; 6];
        }
    }

    /// Adds a 12×12 element matrix coupling nodes `i` and `i+1`.
    pub fn add_element(&mut self, i: usize, k: &[[f64; 12]; 12]) {
        add_quarter(&mut self.diag[i], k, 0, 0);
        add_quarter(&mut self.upper[i], k, 0, 6);
        add_quarter(&mut self.lower[i], k, 6, 0);
        add_quarter(&mut self.diag[i + 1], k, 6, 6);
    }

    /// `y = A x`.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let n = self.nodes();
        let mut y = vec![0.0; 6 * n];
        for i in 0..n {
            for r in 0..6 {
                let mut s = 0.0;
                for c in 0..6 {
                    s += self.diag[i][r][c] * x[6 * i + c];
                    if i + 1 < n {
                        s += self.upper[i][r][c] * x[6 * (i + 1) + c];
                    }
                    if i > 0 {
                        s += self.lower[i - 1][r][c] * x[6 * (i - 1) + c];
                    }
                }
                y[6 * i + r] = s;
            }
        }
        y
    }

    /// Dense copy (small systems: stability checks, tests).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let n = self.nodes();
        let mut a = nalgebra::DMatrix::<f64>::zeros(6 * n, 6 * n);
        for i in 0..n {
            for r in 0..6 {
                for c in 0..6 {
                    a[(6 * i + r, 6 * i + c)] += self.diag[i][r][c];
                    if i + 1 < n {
                        a[(6 * i + r, 6 * (i + 1) + c)] += self.upper[i][r][c];
                        a[(6 * (i + 1) + r, 6 * i + c)] += self.lower[i][r][c];
                    }
                }
            }
        }
        a
    }

    /// Whether the symmetric part is positive definite (a stable equilibrium when this is
    /// a constrained tangent).
    pub fn symmetric_part_positive_definite(&self) -> bool {
        let a = self.to_dense();
        nalgebra::linalg::Cholesky::new((&a + a.transpose()) * 0.5).is_some()
    }

    pub(crate) fn triplets(&self) -> Vec<Triplet<usize, usize, f64>> {
        let n = self.nodes();
        let mut t = Vec::with_capacity(36 * (3 * n));
        for i in 0..n {
            for r in 0..6 {
                for c in 0..6 {
                    t.push(Triplet::new(6 * i + r, 6 * i + c, self.diag[i][r][c]));
                    if i + 1 < n {
                        t.push(Triplet::new(
                            6 * i + r,
                            6 * (i + 1) + c,
                            self.upper[i][r][c],
                        ));
                        t.push(Triplet::new(
                            6 * (i + 1) + r,
                            6 * i + c,
                            self.lower[i][r][c],
                        ));
                    }
                }
            }
        }
        t
    }
}
