//! The lowest modes of a long model without its whole spectrum: shift-invert block Lanczos
//! on the block-tridiagonal tangent and mass matrix, for the critical-speed analysis of a
//! BHA meshed finely ([`crate::bha::critical`]).
//!
//! [`super::modes`] solves `K φ = ω² M φ` densely: an inverse, two products and a
//! symmetric eigensolve of the free DOFs, `O(n³)` in time and `O(n²)` in memory — 4,200
//! free DOFs (a 160 m BHA at 0.25 m elements with its pipe above) take minutes and
//! 0.6 GB. The few lowest lateral modes need neither: here `A = K − σ M` is factorised once
//! (faer's sparse LU; `σ` just below zero, so rigid modes and the lowest modes lie
//! nearest it), a Krylov basis of `A⁻¹ M` is built block by block (blocks of
//! [`BLOCK`] vectors, so that the pairs of equal lateral modes of a straight hole are both
//! found), M-orthonormalised twice against every earlier vector, and the pencil is
//! projected onto it (Rayleigh–Ritz: `Vᵀ K V y = λ y`). A Ritz pair counts once its true
//! residual `‖K φ − λ M φ‖ / (‖K φ‖ + |λ| ‖M φ‖)` is below [`TOLERANCE`]; the answer is the
//! eigenpairs nearest `σ` up to the first that has not converged, so no eigenvalue inside
//! that range is missed. The basis doubles until the caller has enough modes (or falls
//! back to the dense solve where the basis would reach half the free DOFs).

use nalgebra::DMatrix;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use super::Mode;
use crate::model::Model;
use crate::solve::chain::BlockTridiagonal;
use crate::solve::statics::{constrain, constrained_tangent, constraints, StaticState};

/// Free DOFs up to which [`lowest_modes`] solves densely ([`super::modes`]). On the
/// corpus (`holewall bench critical-corpus`, docs/validation.md) the dense solve of 352–556
/// free DOFs took 0.07–0.30 s where the Krylov solve of 636 took 0.006 s; below 300 it
/// takes a few hundredths and a Krylov basis would be a large share of the space.
pub const DENSE_MAX_DOFS: usize = 300;
/// Vectors per Krylov block.
const BLOCK: usize = 3;
/// The basis before its first Rayleigh–Ritz (then doubled).
const FIRST_BASIS: usize = 48;
/// Relative residual of a converged Ritz pair.
const TOLERANCE: f64 = 1e-6;
/// The shift `σ` (rad²/s²): a mode of 0.16 Hz; rigid modes (`ω² = 0`) and the lowest
/// modes lie nearest it, and `K − σ M` is regular where `K` has a rigid mode.
const SIGMA: f64 = -1.0;

/// The lowest modes of a model and how they were found.
#[derive(Clone, Debug)]
pub struct LowestModes {
    /// The modes found, lowest first (as [`super::modes`]: a negative `ω²` at 0 Hz).
    pub modes: Vec<Mode>,
    /// `dense` or `shift-invert block Lanczos`.
    pub method: &'static str,
    /// Size of the Krylov basis (the free DOFs where dense).
    pub basis: usize,
    /// Free DOFs of the eigenproblem.
    pub free_dofs: usize,
    /// Largest relative residual of the modes returned.
    pub worst_residual: f64,
}

/// The lowest modes of `model` about `state` with mass `mass`, until `enough` says the
/// lowest ones found suffice: densely up to [`DENSE_MAX_DOFS`] free DOFs or where `dense`,
/// else by [`krylov_modes`] (module docs), densely where that does not get enough.
pub fn lowest_modes(
    model: &Model,
    state: &StaticState,
    mass: &BlockTridiagonal,
    enough: &dyn Fn(&[Mode]) -> bool,
    dense: bool,
) -> LowestModes {
    let free_dofs = free_mask(model).iter().filter(|f| **f).count();
    if free_dofs > DENSE_MAX_DOFS && !dense {
        if let Some(found) = krylov_modes(model, state, mass, enough) {
            return found;
        }
    }
    LowestModes {
        modes: super::modes(model, state, mass),
        method: "dense",
        basis: free_dofs,
        free_dofs,
        worst_residual: 0.0,
    }
}

fn free_mask(model: &Model) -> Vec<bool> {
    let c = constraints(model);
    (0..6 * model.nodes.len())
        .map(|d| !c.fixed[d / 6][d % 6])
        .collect()
}

/// The symmetric part of a block-tridiagonal matrix (`(A + Aᵀ) / 2`, as the dense solve).
fn symmetric(a: &BlockTridiagonal) -> BlockTridiagonal {
    let mut s = a.clone();
    for (sd, d) in s.diag.iter_mut().zip(&a.diag) {
        for (r, row) in sd.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = 0.5 * (d[r][c] + d[c][r]);
            }
        }
    }
    for i in 0..a.upper.len() {
        for r in 0..6 {
            for c in 0..6 {
                let v = 0.5 * (a.upper[i][r][c] + a.lower[i][c][r]);
                s.upper[i][r][c] = v;
                s.lower[i][c][r] = v;
            }
        }
    }
    s
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The lowest modes by shift-invert block Lanczos (module docs); `None` where the shifted
/// matrix cannot be factorised or the basis would pass half the free DOFs before `enough`.
pub fn krylov_modes(
    model: &Model,
    state: &StaticState,
    mass: &BlockTridiagonal,
    enough: &dyn Fn(&[Mode]) -> bool,
) -> Option<LowestModes> {
    use faer::linalg::solvers::Solve;
    use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
    use faer::sparse::SparseColMat;

    let n = 6 * model.nodes.len();
    let free = free_mask(model);
    let nf = free.iter().filter(|f| **f).count();
    let c = constraints(model);
    let k = symmetric(&constrained_tangent(model, state, 1.0));
    let mut m = mass.clone();
    let mut dummy = vec![0.0; n];
    constrain(&c, &mut dummy, &mut m);
    // The fixed DOFs out of the mass (constrain set their diagonal to 1).
    for (d, f) in free.iter().enumerate() {
        if !f {
            m.diag[d / 6][d % 6][d % 6] = 0.0;
        }
    }
    let m = symmetric(&m);
    let mut a = k.clone();
    for (blk, mb) in a
        .diag
        .iter_mut()
        .chain(a.upper.iter_mut())
        .chain(a.lower.iter_mut())
        .zip(m.diag.iter().chain(&m.upper).chain(&m.lower))
    {
        for r in 0..6 {
            for col in 0..6 {
                blk[r][col] -= SIGMA * mb[r][col];
            }
        }
    }
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &a.triplets()).ok()?;
    let symbolic = SymbolicLu::try_new(mat.symbolic()).ok()?;
    let lu = Lu::try_new_with_symbolic(symbolic, mat.as_ref()).ok()?;
    // `A⁻¹ b` for each right-hand side `b` of a block, the fixed DOFs zero.
    let solve = |rhs: &[&[f64]]| -> Vec<Vec<f64>> {
        let b = faer::Mat::<f64>::from_fn(n, rhs.len(), |r, j| rhs[j][r]);
        let sol = lu.solve(&b);
        (0..rhs.len())
            .map(|j| {
                (0..n)
                    .map(|r| if free[r] { sol[(r, j)] } else { 0.0 })
                    .collect()
            })
            .collect()
    };
    // `M x` for a block of random vectors on the free DOFs.
    let random_block = |rng: &mut StdRng| -> Vec<Vec<f64>> {
        (0..BLOCK)
            .map(|_| {
                let x: Vec<f64> = (0..n)
                    .map(|r| {
                        if free[r] {
                            rng.random_range(-1.0..1.0)
                        } else {
                            0.0
                        }
                    })
                    .collect();
                m.mul(&x)
            })
            .collect()
    };
    let mut rng = StdRng::seed_from_u64(0x6d6f646573);
    let mut basis = Basis::default();
    // The first block: random vectors through the operator once (into its range).
    let first = random_block(&mut rng);
    let mut last = basis.extend(
        solve(&first.iter().map(|b| b.as_slice()).collect::<Vec<_>>()),
        &m,
        &k,
    );
    let mut target = FIRST_BASIS.min(nf);
    loop {
        while basis.v.len() < target {
            let next = if last.is_empty() {
                // The Krylov space is invariant: go on from fresh random vectors.
                let fresh = random_block(&mut rng);
                solve(&fresh.iter().map(|b| b.as_slice()).collect::<Vec<_>>())
            } else {
                // `A⁻¹ M v` of the last block, its `M v` kept with it.
                solve(
                    &last
                        .clone()
                        .map(|i| basis.mv[i].as_slice())
                        .collect::<Vec<_>>(),
                )
            };
            last = basis.extend(next, &m, &k);
        }
        let Basis { v, mv, kv } = &basis;
        let dim = v.len();
        let h = DMatrix::from_fn(dim, dim, |i, j| {
            0.5 * (dot(&v[i], &kv[j]) + dot(&v[j], &kv[i]))
        });
        let eig = nalgebra::linalg::SymmetricEigen::new(h);
        let mut order: Vec<usize> = (0..dim).collect();
        order.sort_by(|&p, &q| {
            (eig.eigenvalues[p] - SIGMA)
                .abs()
                .total_cmp(&(eig.eigenvalues[q] - SIGMA).abs())
        });
        let mut found = Vec::new();
        let mut worst = 0.0f64;
        // Ritz pairs nearest σ converge first; no more than half the basis is trusted.
        for &j in order.iter().take(dim / 2) {
            let lambda = eig.eigenvalues[j];
            let y = eig.eigenvectors.column(j);
            let mut phi = vec![0.0; n];
            let mut kphi = vec![0.0; n];
            let mut mphi = vec![0.0; n];
            for (i, &yi) in y.iter().enumerate() {
                for r in 0..n {
                    phi[r] += yi * v[i][r];
                    kphi[r] += yi * kv[i][r];
                    mphi[r] += yi * mv[i][r];
                }
            }
            let res: f64 = kphi
                .iter()
                .zip(&mphi)
                .map(|(p, q)| (p - lambda * q).powi(2))
                .sum::<f64>()
                .sqrt();
            let scale = dot(&kphi, &kphi).sqrt() + lambda.abs() * dot(&mphi, &mphi).sqrt();
            let rel = res / scale.max(f64::MIN_POSITIVE);
            if rel.is_nan() || rel >= TOLERANCE {
                break;
            }
            worst = worst.max(rel);
            found.push(Mode {
                frequency_hz: lambda.max(0.0).sqrt() / std::f64::consts::TAU,
                shape: phi,
            });
        }
        found.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
        if enough(&found) {
            return Some(LowestModes {
                modes: found,
                method: "shift-invert block Lanczos",
                basis: dim,
                free_dofs: nf,
                worst_residual: worst,
            });
        }
        if 2 * dim > nf {
            return None;
        }
        target = (2 * dim).min(nf);
    }
}

/// An M-orthonormal Krylov basis with `M v` and `K v` of each vector.
#[derive(Default)]
struct Basis {
    v: Vec<Vec<f64>>,
    mv: Vec<Vec<f64>>,
    kv: Vec<Vec<f64>>,
}

impl Basis {
    /// M-orthonormalises each of `block` against the basis (twice) and appends it, where it
    /// does not lie in the basis already; returns the indices of those appended.
    fn extend(
        &mut self,
        block: Vec<Vec<f64>>,
        m: &BlockTridiagonal,
        k: &BlockTridiagonal,
    ) -> std::ops::Range<usize> {
        let first = self.v.len();
        for mut w in block {
            let before = dot(&w, &m.mul(&w)).sqrt();
            for _ in 0..2 {
                for (v, mv) in self.v.iter().zip(&self.mv) {
                    let h = dot(&w, mv);
                    for (x, y) in w.iter_mut().zip(v) {
                        *x -= h * y;
                    }
                }
            }
            let mw = m.mul(&w);
            let norm = dot(&w, &mw).sqrt();
            if norm.is_nan() || norm <= 1e-10 * before || !norm.is_finite() {
                continue;
            }
            let v: Vec<f64> = w.iter().map(|x| x / norm).collect();
            self.kv.push(k.mul(&v));
            self.mv.push(mw.iter().map(|x| x / norm).collect());
            self.v.push(v);
        }
        first..self.v.len()
    }
}
