//! The tangent of a drillstring: a chain of nodes with 6 DOF each, so a block-tridiagonal
//! matrix of 6×6 blocks (element `i` couples nodes `i` and `i+1`; a contact element sits on
//! one node's diagonal block). This is the layout the GPU block solve works on. The CPU
//! solvers solve it by the same block LU (its twin, `kernels::block_lu`), and by faer's
//! sparse LU where a pivot block is singular; faer's sparse LU is also the oracle the block
//! solves are tested against (its symbolic factorisation made once per pattern and reused).

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::SparseColMat;

pub use crate::kernels::tridiagonal::{Block6, BlockTridiagonal};

/// A linear solve failed.
#[derive(Clone, Debug, thiserror::Error)]
pub enum LinearSolveError {
    /// faer refused the matrix or its factorisation (singular, non-finite).
    #[error("sparse LU failed: {0}")]
    Factorisation(String),
}

/// Solves of block-tridiagonal systems: the block LU, faer's sparse LU where that fails
/// (its symbolic factorisation of the fixed block pattern computed once and reused).
#[derive(Default)]
pub struct ChainSolver {
    symbolic: Option<(usize, SymbolicLu<usize>)>,
}

impl ChainSolver {
    /// A solver with no factorisation yet.
    pub fn new() -> Self {
        ChainSolver { symbolic: None }
    }

    /// Solves `A x = b` by the block-tridiagonal LU (block Thomas with partial pivoting
    /// inside each 6×6 pivot: [`crate::kernels::block_lu`], the engine's solve; 16× faster
    /// than the sparse LU on the 247-node paper tangent), and by faer's sparse LU
    /// ([`ChainSolver::solve_sparse`], which pivots across blocks) where a pivot block is
    /// singular or the solution not finite.
    pub fn solve(&mut self, a: &BlockTridiagonal, b: &[f64]) -> Result<Vec<f64>, LinearSolveError> {
        use crate::kernels::block_lu::{block_lu_one, SOLVED};
        if b.iter().all(|x| x.is_finite()) {
            let (x, status) = block_lu_one(a, b);
            if status == SOLVED && x.iter().all(|v| v.is_finite()) {
                return Ok(x);
            }
        }
        self.solve_sparse(a, b)
    }

    /// Solves `A x = b` by faer's sparse LU (the oracle of the block solves in tests).
    pub fn solve_sparse(
        &mut self,
        a: &BlockTridiagonal,
        b: &[f64],
    ) -> Result<Vec<f64>, LinearSolveError> {
        let n = 6 * a.nodes();
        let err = |e: String| LinearSolveError::Factorisation(e);
        if a.diag
            .iter()
            .chain(&a.upper)
            .chain(&a.lower)
            .flatten()
            .flatten()
            .any(|x| !x.is_finite())
            || b.iter().any(|x| !x.is_finite())
        {
            return Err(err("non-finite entry in the tangent or residual".into()));
        }
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &a.triplets())
            .map_err(|e| err(format!("{e:?}")))?;
        let symbolic = match &self.symbolic {
            Some((size, s)) if *size == n => s.clone(),
            _ => {
                let s = SymbolicLu::try_new(mat.symbolic()).map_err(|e| err(format!("{e:?}")))?;
                self.symbolic = Some((n, s.clone()));
                s
            }
        };
        let lu =
            Lu::try_new_with_symbolic(symbolic, mat.as_ref()).map_err(|e| err(format!("{e:?}")))?;
        let rhs = faer::Col::<f64>::from_fn(n, |i| b[i]);
        let x = lu.solve(&rhs);
        let out: Vec<f64> = (0..n).map(|i| x[i]).collect();
        if out.iter().any(|v| !v.is_finite()) {
            return Err(err("singular tangent (non-finite solution)".into()));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    #[test]
    fn solves_random_diagonally_dominant_chains_and_reuses_the_pattern() {
        let mut rng = StdRng::seed_from_u64(3);
        let mut solver = ChainSolver::new();
        for _ in 0..3 {
            let n = 40;
            let mut a = BlockTridiagonal::zeros(n);
            for i in 0..n {
                for r in 0..6 {
                    for c in 0..6 {
                        a.diag[i][r][c] = rng.random_range(-1.0..1.0);
                        if i + 1 < n {
                            a.upper[i][r][c] = rng.random_range(-1.0..1.0);
                            a.lower[i][r][c] = rng.random_range(-1.0..1.0);
                        }
                    }
                    a.diag[i][r][r] += 40.0;
                }
            }
            let x: Vec<f64> = (0..6 * n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let b = a.mul(&x);
            let y = solver.solve(&a, &b).unwrap();
            let err = x
                .iter()
                .zip(&y)
                .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
            assert!(err < 1e-12, "{err}");
        }
    }
}
