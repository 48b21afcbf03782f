//! Mass of a beam element: consistent (Euler–Bernoulli cubic bending, linear axial and
//! torsional shape functions, with rotary inertia) or lumped (half the mass and rotary
//! inertia to each node), in the element frame, then rotated to global axes.

use super::beam::{BeamSection, Mat3};

/// Mass matrix kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MassKind {
    /// Consistent: the shape functions of the stiffness.
    Consistent,
    /// Lumped: `ρAl/2` and `ρI_p l/2`, `ρI l/2` at each node (diagonal).
    Lumped,
}

/// Element mass matrix (12×12, DOFs `[u1, θ1, u2, θ2]`) in the element frame `e1` (axis),
/// `e2`, `e3`. `density` in kg/m³; `added_mass_per_length` (kg/m, e.g. mud inside the pipe
/// and entrained outside) adds to the translational mass only.
pub fn local_mass(
    section: &BeamSection,
    density: f64,
    added_mass_per_length: f64,
    l: f64,
    kind: MassKind,
) -> [[f64; 12]; 12] {
    let mut m = [[0.0; 12]; 12];
    let mt = density * section.area + added_mass_per_length; // kg/m, translational
    let ip = density * section.polar_moment; // kg·m, torsional
    let ib = density * section.second_moment; // kg·m, rotary (bending)
    match kind {
        MassKind::Lumped => {
            for node in 0..2 {
                let o = 6 * node;
                for k in 0..3 {
                    m[o + k][o + k] = 0.5 * mt * l;
                }
                m[o + 3][o + 3] = 0.5 * ip * l;
                m[o + 4][o + 4] = 0.5 * ib * l;
                m[o + 5][o + 5] = 0.5 * ib * l;
            }
        }
        MassKind::Consistent => {
            // Axial (u_x) and torsion (θ_x): linear shape functions, (l/6)[2 1; 1 2].
            for (dof, rho) in [(0usize, mt), (3usize, ip)] {
                m[dof][dof] = rho * l / 3.0;
                m[dof + 6][dof + 6] = rho * l / 3.0;
                m[dof][dof + 6] = rho * l / 6.0;
                m[dof + 6][dof] = rho * l / 6.0;
            }
            // Bending: translation w with rotation θ, for (w, θ) = (u_y, θ_z) and (u_z, −θ_y).
            for (w, th, sign) in [(1usize, 5usize, 1.0), (2usize, 4usize, -1.0)] {
                let c = mt * l / 420.0;
                let idx = [w, th, w + 6, th + 6];
                let s = [1.0, sign, 1.0, sign];
                let base = [
                    [156.0, 22.0 * l, 54.0, -13.0 * l],
                    [22.0 * l, 4.0 * l * l, 13.0 * l, -3.0 * l * l],
                    [54.0, 13.0 * l, 156.0, -22.0 * l],
                    [-13.0 * l, -3.0 * l * l, -22.0 * l, 4.0 * l * l],
                ];
                // Rotary inertia (ρI/(30 l)).
                let r = ib / (30.0 * l);
                let rot = [
                    [36.0, 3.0 * l, -36.0, 3.0 * l],
                    [3.0 * l, 4.0 * l * l, -3.0 * l, -l * l],
                    [-36.0, -3.0 * l, 36.0, -3.0 * l],
                    [3.0 * l, -l * l, -3.0 * l, 4.0 * l * l],
                ];
                for a in 0..4 {
                    for b in 0..4 {
                        m[idx[a]][idx[b]] += s[a] * s[b] * (c * base[a][b] + r * rot[a][b]);
                    }
                }
            }
        }
    }
    m
}

/// Rotates a 12×12 element matrix from the element frame (columns of `frame`) to global axes.
pub fn to_global(local: &[[f64; 12]; 12], frame: &Mat3<f64>) -> [[f64; 12]; 12] {
    // T = blockdiag(Q, Q, Q, Q), global = T · local · Tᵀ.
    let q = |r: usize, c: usize| -> f64 {
        if r / 3 == c / 3 {
            frame[r % 3][c % 3]
        } else {
            0.0
        }
    };
    let tmp: [[f64; 12]; 12] = std::array::from_fn(|r| {
        std::array::from_fn(|c| (0..12).map(|k| q(r, k) * local[k][c]).sum())
    });
    let out: [[f64; 12]; 12] = std::array::from_fn(|r| {
        std::array::from_fn(|c| (0..12).map(|k| tmp[r][k] * q(c, k)).sum())
    });
    out
}

/// A node's mass imbalance as a rigid eccentric mass: its centre of mass at `x + d`,
/// `d = U/M` with `U = R U₀` the imbalance (kg·m) turned with the node. The inertial force
/// and moment it adds to the node's equations, `M (ω̇ × d + ω × (ω × d))` and
/// `U × (ẍ + ω̇ × d + ω × (ω × d))` (second order in `d` kept), and their derivatives with
/// respect to `v̇ = (ẍ, ω̇)` (the mass coupling) and, times `hg`, to `ω`. The rotation's own
/// derivative is left out of the iteration matrix (first order in a small `d`; Newton
/// converges without it). One formula for the CPU integrator, the assembly twin and
/// `shaders/assemble.wgsl` (`UNBALANCE`).
pub fn unbalance_terms<T: crate::physics::Real>(
    u: [T; 3],
    mass: T,
    xdd: [T; 3],
    w: [T; 3],
    wd: [T; 3],
    hg: T,
) -> ([T; 6], [[T; 6]; 6]) {
    let cross = |a: [T; 3], b: [T; 3]| -> [T; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let skew = |x: [T; 3]| -> [[T; 3]; 3] {
        let z = T::zero();
        [[z, -x[2], x[1]], [x[2], z, -x[0]], [-x[1], x[0], z]]
    };
    let mul = |a: &[[T; 3]; 3], b: &[[T; 3]; 3]| -> [[T; 3]; 3] {
        std::array::from_fn(|r| {
            std::array::from_fn(|c| a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c])
        })
    };
    let d = u.map(|x| x / mass);
    let wxd = cross(w, d);
    let t = cross(wd, d);
    let c = cross(w, wxd);
    let a_rel: [T; 3] = std::array::from_fn(|k| t[k] + c[k]);
    let a_cm: [T; 3] = std::array::from_fn(|k| xdd[k] + a_rel[k]);
    let moment = cross(u, a_cm);
    let mut r = [T::zero(); 6];
    for k in 0..3 {
        r[k] = mass * a_rel[k];
        r[3 + k] = moment[k];
    }
    let (su, sd) = (skew(u), skew(d));
    // ∂(ω × (ω × d))/∂ω = −[ω × d]× − [ω]×[d]×.
    let swd = skew(wxd);
    let sw_sd = mul(&skew(w), &sd);
    let dw: [[T; 3]; 3] =
        std::array::from_fn(|a| std::array::from_fn(|b| -swd[a][b] - sw_sd[a][b]));
    let su_sd = mul(&su, &sd);
    let su_dw = mul(&su, &dw);
    let mut jac = [[T::zero(); 6]; 6];
    for a in 0..3 {
        for b in 0..3 {
            // Translations: ∂/∂ω̇ = −M [d]× = −[U]×; ∂/∂ω = M dw.
            jac[a][3 + b] = -su[a][b] + hg * mass * dw[a][b];
            // Moments: ∂/∂ẍ = [U]×, ∂/∂ω̇ = −[U]×[d]×, ∂/∂ω = [U]× dw.
            jac[3 + a][b] = su[a][b];
            jac[3 + a][3 + b] = -su_sd[a][b] + hg * su_dw[a][b];
        }
    }
    (r, jac)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    #[test]
    fn total_mass_and_rigid_body_kinetic_energy() {
        let s = BeamSection::tube(0.165, 0.071, 2.1e11, 0.3);
        let l = 3.0;
        for kind in [MassKind::Consistent, MassKind::Lumped] {
            let m = local_mass(&s, 7850.0, 0.0, l, kind);
            // A rigid translation along each axis carries the element's whole mass.
            let mass = 7850.0 * s.area * l;
            for axis in 0..3 {
                let mut v = [0.0; 12];
                v[axis] = 1.0;
                v[axis + 6] = 1.0;
                let ke: f64 = (0..12)
                    .map(|r| (0..12).map(|c| v[r] * m[r][c] * v[c]).sum::<f64>())
                    .sum();
                assert!(
                    (ke - mass).abs() < 1e-9 * mass,
                    "{kind:?} axis {axis}: {ke} vs {mass}"
                );
            }
            // A rigid spin about the axis carries ρ I_p l.
            let mut v = [0.0; 12];
            v[3] = 1.0;
            v[9] = 1.0;
            let ke: f64 = (0..12)
                .map(|r| (0..12).map(|c| v[r] * m[r][c] * v[c]).sum::<f64>())
                .sum();
            let ip = 7850.0 * s.polar_moment * l;
            assert!((ke - ip).abs() < 1e-9 * ip);
            // Symmetric.
            for r in 0..12 {
                for c in 0..12 {
                    assert!((m[r][c] - m[c][r]).abs() < 1e-12 * mass);
                }
            }
        }
    }
}
