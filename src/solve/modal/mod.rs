//! Natural frequencies about a static equilibrium: `K φ = ω² M φ` with the constrained
//! tangent (geometric stiffness of the axial load included) and the mass matrix, solved
//! densely (small models: closed-form checks, BHA studies).

use crate::model::Model;
use crate::physics::mass::{local_mass, to_global, MassKind};
use crate::solve::chain::BlockTridiagonal;
use crate::solve::statics::{constrain, constrained_tangent, constraints, StaticState};

/// Global mass matrix of the model in the initial element frames.
pub fn mass_matrix(
    model: &Model,
    kind: MassKind,
    density_of: &dyn Fn(usize) -> f64,
) -> BlockTridiagonal {
    mass_matrix_with_added(model, kind, density_of, &|_| 0.0)
}

/// [`mass_matrix`] with an added mass per length on the translations of element `i`
/// (`added_of(i)`, kg/m: the mud inside the pipe and entrained outside).
pub fn mass_matrix_with_added(
    model: &Model,
    kind: MassKind,
    density_of: &dyn Fn(usize) -> f64,
    added_of: &dyn Fn(usize) -> f64,
) -> BlockTridiagonal {
    let mut m = BlockTridiagonal::zeros(model.nodes.len());
    for (i, e) in model.elements.iter().enumerate() {
        let local = local_mass(&e.section, density_of(i), added_of(i), e.length0, kind);
        m.add_element(i, &to_global(&local, &e.frame0));
    }
    m
}

/// One mode.
#[derive(Clone, Debug)]
pub struct Mode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Mode shape over all 6n DOFs (constrained coordinates; fixed DOFs zero).
    pub shape: Vec<f64>,
}

/// Modes of the model about `state` (at full load), lowest first.
pub fn modes(model: &Model, state: &StaticState, mass: &BlockTridiagonal) -> Vec<Mode> {
    let c = constraints(model);
    let k = constrained_tangent(model, state, 1.0);
    let mut m = mass.clone();
    let mut dummy = vec![0.0; 6 * model.nodes.len()];
    constrain(&c, &mut dummy, &mut m);
    let free: Vec<usize> = (0..6 * model.nodes.len())
        .filter(|&d| !c.fixed[d / 6][d % 6])
        .collect();
    let kd = k.to_dense();
    let md = m.to_dense();
    let nf = free.len();
    let kf = nalgebra::DMatrix::from_fn(nf, nf, |r, col| {
        0.5 * (kd[(free[r], free[col])] + kd[(free[col], free[r])])
    });
    let mf = nalgebra::DMatrix::from_fn(nf, nf, |r, col| {
        0.5 * (md[(free[r], free[col])] + md[(free[col], free[r])])
    });
    let Some(chol) = nalgebra::linalg::Cholesky::new(mf) else {
        return Vec::new();
    };
    let l = chol.l();
    let linv = l
        .clone()
        .try_inverse()
        .unwrap_or_else(|| nalgebra::DMatrix::identity(nf, nf));
    let a = &linv * kf * linv.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let eig = nalgebra::linalg::SymmetricEigen::new(a);
    let mut out: Vec<Mode> = (0..nf)
        .map(|j| {
            let lambda = eig.eigenvalues[j];
            let y = eig.eigenvectors.column(j);
            let phi = linv.transpose() * y;
            let mut shape = vec![0.0; 6 * model.nodes.len()];
            for (r, &d) in free.iter().enumerate() {
                shape[d] = phi[r];
            }
            Mode {
                frequency_hz: lambda.max(0.0).sqrt() / std::f64::consts::TAU,
                shape,
            }
        })
        .collect();
    out.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    out
}

/// Share of a mode's squared amplitude in DOF component `k` (0..6) of every node.
pub fn participation(mode: &Mode, k: usize) -> f64 {
    let total: f64 = mode.shape.iter().map(|x| x * x).sum();
    let part: f64 = mode.shape.iter().skip(k).step_by(6).map(|x| x * x).sum();
    if total > 0.0 {
        part / total
    } else {
        0.0
    }
}

mod krylov;
pub use krylov::{krylov_modes, lowest_modes, LowestModes, DENSE_MAX_DOFS};
