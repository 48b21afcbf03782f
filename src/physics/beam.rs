//! Two-node 3D co-rotational beam (6 DOF per node: displacement and spatial rotation).
//!
//! The element follows a frame that rides with it — axis `e1` along the chord, `e2`/`e3`
//! from the mean of the nodal triads — and measures in that frame only what deforms it:
//! the elongation `ū = l − l0` and the nodal rotations relative to the frame,
//! `θ̄_i = log(R_rᵀ R_i Q0)`. Rigid motions of any size leave `ū` and `θ̄` at zero exactly, so
//! a string spun hundreds of radians carries no spurious strain. In the frame the beam is
//! linear (Euler–Bernoulli, small strain):
//!
//! `E = ½ EA/l0 ū² + ½ GJ/l0 (θ̄2x − θ̄1x)² + ½ EI/l0 Σ_{y,z} (4θ̄1² + 4θ̄1θ̄2 + 4θ̄2²)`.
//!
//! The internal force is the derivative of `E` with respect to the nodal displacements and
//! spatial rotation increments (`R_i ← exp([δθ]×) R_i`), and the consistent tangent is its
//! derivative with respect to the Newton increment applied the same way; both come exactly
//! from hyper-dual evaluations of `E` (`src/physics/hyperdual.rs`): 78 of them, the other
//! half of the tangent from the commutator of two spins of one node. The tangent so contains
//! the geometric stiffness: an axial force `N` adds `N/l` to the lateral stiffness, so
//! compression softens the string and buckling appears.

use super::hyperdual::HyperDual;
use super::Real;

/// 3×3 matrix, row-major.
pub type Mat3<T> = [[T; 3]; 3];

/// Section and material of a beam element. SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamSection {
    /// Young's modulus `E` (Pa).
    pub youngs_modulus: f64,
    /// Shear modulus `G` (Pa).
    pub shear_modulus: f64,
    /// Cross-section area `A` (m²).
    pub area: f64,
    /// Second moment of area `I` about either bending axis (m⁴).
    pub second_moment: f64,
    /// Polar moment `J` (m⁴).
    pub polar_moment: f64,
}

impl BeamSection {
    /// Tube of outer/inner diameters `od`, `id` (m), Young's modulus `e`, Poisson ratio `nu`.
    pub fn tube(od: f64, id: f64, e: f64, nu: f64) -> BeamSection {
        let pi = std::f64::consts::PI;
        let i = pi / 64.0 * (od.powi(4) - id.powi(4));
        BeamSection {
            youngs_modulus: e,
            shear_modulus: e / (2.0 * (1.0 + nu)),
            area: pi / 4.0 * (od * od - id * id),
            second_moment: i,
            polar_moment: 2.0 * i,
        }
    }

    /// Bending stiffness `EI` (N·m²).
    pub fn bending_stiffness(&self) -> f64 {
        self.youngs_modulus * self.second_moment
    }
}

/// Operations the element needs beyond [`Real`].
pub trait Trig: Real {
    /// sin.
    fn sin(self) -> Self;
    /// cos.
    fn cos(self) -> Self;
    /// atan2(self, x).
    fn atan2(self, x: Self) -> Self;
}

impl Trig for f64 {
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
}

impl Trig for HyperDual {
    fn sin(self) -> Self {
        HyperDual::sin(self)
    }
    fn cos(self) -> Self {
        HyperDual::cos(self)
    }
    fn atan2(self, x: Self) -> Self {
        HyperDual::atan2(self, x)
    }
}

fn mat_mul<T: Real>(a: &Mat3<T>, b: &Mat3<T>) -> Mat3<T> {
    std::array::from_fn(|r| {
        std::array::from_fn(|c| a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c])
    })
}

fn mat_tmul<T: Real>(a: &Mat3<T>, b: &Mat3<T>) -> Mat3<T> {
    std::array::from_fn(|r| {
        std::array::from_fn(|c| a[0][r] * b[0][c] + a[1][r] * b[1][c] + a[2][r] * b[2][c])
    })
}

fn cross<T: Real>(a: &[T; 3], b: &[T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm<T: Real>(a: &[T; 3]) -> T {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The rotation vector of a rotation matrix (`log`, |θ| < π), smooth through θ = 0.
pub fn rotation_log<T: Trig>(r: &Mat3<T>) -> [T; 3] {
    let half = T::from_f64_lossy(0.5);
    let w = [
        half * (r[2][1] - r[1][2]),
        half * (r[0][2] - r[2][0]),
        half * (r[1][0] - r[0][1]),
    ];
    let s2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    let c = half * (r[0][0] + r[1][1] + r[2][2] - T::one());
    // θ/sin θ; near θ = 0 by its series in s² = sin²θ (asin(s)/s), avoiding √0.
    let factor = if s2.to_f64_lossy() < 1e-6 && c.to_f64_lossy() > 0.0 {
        T::one() + s2 * (T::from_f64_lossy(1.0 / 6.0) + s2 * T::from_f64_lossy(3.0 / 40.0))
    } else {
        let s = s2.sqrt();
        s.atan2(c) / s
    };
    [factor * w[0], factor * w[1], factor * w[2]]
}

/// `exp([θ]×)` (Rodrigues), f64.
pub fn rotation_exp(theta: &[f64; 3]) -> Mat3<f64> {
    let a = norm(theta);
    let k: Mat3<f64> = [
        [0.0, -theta[2], theta[1]],
        [theta[2], 0.0, -theta[0]],
        [-theta[1], theta[0], 0.0],
    ];
    let (s, c) = if a < 1e-8 {
        (1.0 - a * a / 6.0, 0.5 - a * a / 24.0)
    } else {
        (a.sin() / a, (1.0 - a.cos()) / (a * a))
    };
    let kk = mat_mul(&k, &k);
    std::array::from_fn(|r| {
        std::array::from_fn(|col| f64::from(r == col) + s * k[r][col] + c * kk[r][col])
    })
}

/// Deformation measures of the element in its co-rotated frame.
#[derive(Clone, Copy, Debug)]
pub struct LocalDeformation<T> {
    /// Elongation `ū = l − l0` (m).
    pub elongation: T,
    /// Relative rotation vectors at the two nodes, in the element frame (rad).
    pub theta1: [T; 3],
    /// See `theta1`.
    pub theta2: [T; 3],
}

/// Local deformation of an element with nodes at `x1`, `x2` and nodal triads `t1 = R1 Q0`,
/// `t2 = R2 Q0` (columns: the element's initial axes carried by each node's rotation).
pub fn local_deformation<T: Trig>(
    x1: &[T; 3],
    x2: &[T; 3],
    t1: &Mat3<T>,
    t2: &Mat3<T>,
    length0: f64,
) -> LocalDeformation<T> {
    let d = [x2[0] - x1[0], x2[1] - x1[1], x2[2] - x1[2]];
    let l = norm(&d);
    let e1 = [d[0] / l, d[1] / l, d[2] / l];
    // Mean of the nodal second axes fixes the frame's twist about the chord.
    let half = T::from_f64_lossy(0.5);
    let p = [
        half * (t1[0][1] + t2[0][1]),
        half * (t1[1][1] + t2[1][1]),
        half * (t1[2][1] + t2[2][1]),
    ];
    let e3 = cross(&e1, &p);
    let n3 = norm(&e3);
    let e3 = [e3[0] / n3, e3[1] / n3, e3[2] / n3];
    let e2 = cross(&e3, &e1);
    let rr: Mat3<T> = [
        [e1[0], e2[0], e3[0]],
        [e1[1], e2[1], e3[1]],
        [e1[2], e2[2], e3[2]],
    ];
    LocalDeformation {
        elongation: l - T::from_f64_lossy(length0),
        theta1: rotation_log(&mat_tmul(&rr, t1)),
        theta2: rotation_log(&mat_tmul(&rr, t2)),
    }
}

/// Strain energy of the element (see the module docs).
pub fn strain_energy<T: Trig>(def: &LocalDeformation<T>, section: &BeamSection, length0: f64) -> T {
    let c = |x: f64| T::from_f64_lossy(x);
    let ea = c(section.youngs_modulus * section.area / length0);
    let gj = c(section.shear_modulus * section.polar_moment / length0);
    let ei = c(section.bending_stiffness() / length0);
    let twist = def.theta2[0] - def.theta1[0];
    let bend = |a: T, b: T| c(2.0) * (a * a + a * b + b * b);
    c(0.5) * ea * def.elongation * def.elongation
        + c(0.5) * gj * twist * twist
        + ei * (bend(def.theta1[1], def.theta2[1]) + bend(def.theta1[2], def.theta2[2]))
}

/// Section forces of a deformed element (from its local deformation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionForces {
    /// Axial force, tension positive (N).
    pub axial: f64,
    /// Torque (N·m).
    pub torque: f64,
    /// Bending moment magnitude at node 1 and node 2 (N·m).
    pub bending: [f64; 2],
}

/// Section forces from a local deformation.
pub fn section_forces(
    def: &LocalDeformation<f64>,
    section: &BeamSection,
    length0: f64,
) -> SectionForces {
    let ei = section.bending_stiffness() / length0;
    let m = |a: f64, b: f64| ei * (4.0 * a + 2.0 * b);
    let (m1y, m1z) = (
        m(def.theta1[1], def.theta2[1]),
        m(def.theta1[2], def.theta2[2]),
    );
    let (m2y, m2z) = (
        m(def.theta2[1], def.theta1[1]),
        m(def.theta2[2], def.theta1[2]),
    );
    SectionForces {
        axial: section.youngs_modulus * section.area / length0 * def.elongation,
        torque: section.shear_modulus * section.polar_moment / length0
            * (def.theta2[0] - def.theta1[0]),
        bending: [m1y.hypot(m1z), m2y.hypot(m2z)],
    }
}

/// Current configuration of one element: node positions and nodal triads `R_i Q0`.
#[derive(Clone, Copy, Debug)]
pub struct ElementState {
    /// Node positions.
    pub x: [[f64; 3]; 2],
    /// Nodal triads `R_i Q0`.
    pub triad: [Mat3<f64>; 2],
}

/// Perturbs the element state along DOF `dof` (0..12: node·6 + [u(3), θ(3)]) by the
/// hyper-dual unit `unit`, applying a rotation as a left spin `(I + [unit·e]×)·triad`.
fn perturb(
    x: &mut [[HyperDual; 3]; 2],
    triad: &mut [Mat3<HyperDual>; 2],
    dof: usize,
    unit: HyperDual,
) {
    let node = dof / 6;
    let k = dof % 6;
    if k < 3 {
        x[node][k] = x[node][k] + unit;
    } else {
        let axis = k - 3;
        let mut spin: Mat3<HyperDual> = std::array::from_fn(|r| {
            std::array::from_fn(|c| HyperDual::constant(f64::from(r == c)))
        });
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        spin[b][a] = unit;
        spin[a][b] = -unit;
        triad[node] = mat_mul(&spin, &triad[node]);
    }
}

/// ε₁ (the virtual variation δ) and ε₂ (the Newton increment Δ) as hyper-dual units.
const EPS1: HyperDual = HyperDual {
    re: 0.0,
    e1: 1.0,
    e2: 0.0,
    e12: 0.0,
};
const EPS2: HyperDual = HyperDual {
    re: 0.0,
    e1: 0.0,
    e2: 1.0,
    e12: 0.0,
};

type LiftedState = ([[HyperDual; 3]; 2], [Mat3<HyperDual>; 2]);

fn lift(state: &ElementState) -> LiftedState {
    let x = state.x.map(|p| p.map(HyperDual::constant));
    let t = state.triad.map(|m| m.map(|r| r.map(HyperDual::constant)));
    (x, t)
}

/// Strain energy with DOF `j` varied along ε₁ from a (possibly ε₂-perturbed) state.
fn energy_varied(base: &LiftedState, j: usize, section: &BeamSection, length0: f64) -> HyperDual {
    let (mut x, mut t) = *base;
    perturb(&mut x, &mut t, j, EPS1);
    let def = local_deformation(&x[0], &x[1], &t[0], &t[1], length0);
    strain_energy(&def, section, length0)
}

/// Internal force (12) only: 12 evaluations of `E` instead of 144 (line searches).
pub fn internal_force(state: &ElementState, section: &BeamSection, length0: f64) -> [f64; 12] {
    let base = lift(state);
    std::array::from_fn(|j| energy_varied(&base, j, section, length0).e1)
}

/// Internal force (12) and consistent tangent (12×12) of the element: `f_j = ∂E/∂δ_j`,
/// `K_jk = ∂f_j/∂Δ_k` with rotations updated multiplicatively (`exp(δ)·exp(Δ)·R`).
///
/// 78 hyper-dual evaluations (`j ≤ k`) instead of 144: the perturbations commute except
/// two spins of one node, whose products differ by their commutator,
/// `(I + ε₁A_k)(I + ε₂A_j) − (I + ε₁A_j)(I + ε₂A_k) = ε₁ε₂ [e_k × e_j]×` — a spin, whose
/// effect on `E` is the node's moment along it. So `K_kj = K_jk + m·(e_k × e_j)` for the
/// rotations of one node (`m` that node's moment `f_{3..6}`), `K_kj = K_jk` otherwise —
/// exactly ([`force_and_tangent_full`], all 144, is the test oracle).
#[allow(clippy::needless_range_loop)]
pub fn force_and_tangent(
    state: &ElementState,
    section: &BeamSection,
    length0: f64,
) -> ([f64; 12], [[f64; 12]; 12]) {
    let mut force = [0.0; 12];
    let mut tangent = [[0.0; 12]; 12];
    for k in 0..12 {
        for_each_second_derivative(state, section, length0, k, 0..k + 1, |j, e| {
            tangent[j][k] = e.e12;
            if k == 11 {
                force[j] = e.e1;
            }
        });
    }
    for k in 0..12 {
        for j in 0..k {
            tangent[k][j] = tangent[j][k] + spin_commutator(&force, j, k);
        }
    }
    (force, tangent)
}

/// `K_kj − K_jk` for `j < k`: the moment of their node along `e_k × e_j` when both are
/// rotations of one node, else 0 ([`force_and_tangent`]).
pub fn spin_commutator<T: Real>(force: &[T; 12], j: usize, k: usize) -> T {
    let (nj, nk) = (j / 6, k / 6);
    let (aj, ak) = (j % 6, k % 6);
    if nj != nk || aj < 3 || ak < 3 || aj == ak {
        return T::zero();
    }
    let (a, b) = (ak - 3, aj - 3);
    // e_a × e_b = ±e_c (c the third axis): + when (a, b) is cyclic.
    let c = 3 - a - b;
    let moment = force[6 * nk + 3 + c];
    if (a + 1) % 3 == b {
        moment
    } else {
        T::zero() - moment
    }
}

/// As [`force_and_tangent`], from all 144 hyper-dual evaluations: the test oracle, and
/// the beam kernel's formula (`shaders/beam.wgsl` keeps 144: with the 78-evaluation form
/// the f32 static engine lost one stress variant — μ = 1 on a 1e10 N/m wall at a
/// full-gauge stabilizer, which needs 4 load-step cuts in f32 already — to the different
/// rounding of its tangent).
#[allow(clippy::needless_range_loop)]
pub fn force_and_tangent_full(
    state: &ElementState,
    section: &BeamSection,
    length0: f64,
) -> ([f64; 12], [[f64; 12]; 12]) {
    let mut force = [0.0; 12];
    let mut tangent = [[0.0; 12]; 12];
    for k in 0..12 {
        for_each_second_derivative(state, section, length0, k, 0..12, |j, e| {
            tangent[j][k] = e.e12;
            if k == 0 {
                force[j] = e.e1;
            }
        });
    }
    (force, tangent)
}

/// The energy with `Δ_k` (ε₂) applied first and each `δ_j`, `j` in `js`, (ε₁) on top:
/// `visit(j, E)` gets `∂E/∂δ_j` (ε₁ part) and `∂²E/∂δ_j∂Δ_k` (ε₁ε₂ part).
fn for_each_second_derivative(
    state: &ElementState,
    section: &BeamSection,
    length0: f64,
    k: usize,
    js: std::ops::Range<usize>,
    mut visit: impl FnMut(usize, HyperDual),
) {
    let mut base = lift(state);
    perturb(&mut base.0, &mut base.1, k, EPS2);
    for j in js {
        visit(j, energy_varied(&base, j, section, length0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn section() -> BeamSection {
        BeamSection::tube(0.165, 0.071, 2.1e11, 0.3)
    }

    fn straight(l: f64) -> ElementState {
        ElementState {
            x: [[0.0; 3], [l, 0.0, 0.0]],
            triad: [rotation_exp(&[0.0; 3]); 2],
        }
    }

    fn apply(state: &ElementState, dq: &[f64; 12]) -> ElementState {
        let mut s = *state;
        for n in 0..2 {
            for k in 0..3 {
                s.x[n][k] += dq[6 * n + k];
            }
            let r = rotation_exp(&[dq[6 * n + 3], dq[6 * n + 4], dq[6 * n + 5]]);
            s.triad[n] = mat_mul(&r, &s.triad[n]);
        }
        s
    }

    #[test]
    fn rigid_motions_leave_no_strain() {
        let l = 9.0;
        let s0 = straight(l);
        // A spin of 1000 rad about the axis, a tilt, and a translation.
        let spin = rotation_exp(&[1000.0, 0.0, 0.0]);
        let tilt = rotation_exp(&[0.3, -1.1, 2.0]);
        let r = mat_mul(&tilt, &spin);
        let mv = |x: &[f64; 3]| {
            let y: [f64; 3] =
                std::array::from_fn(|i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2]);
            [y[0] + 5.0, y[1] - 3.0, y[2] + 1000.0]
        };
        let s = ElementState {
            x: [mv(&s0.x[0]), mv(&s0.x[1])],
            triad: [mat_mul(&r, &s0.triad[0]), mat_mul(&r, &s0.triad[1])],
        };
        let def = local_deformation(&s.x[0], &s.x[1], &s.triad[0], &s.triad[1], l);
        assert!(def.elongation.abs() < 1e-11);
        assert!(
            def.theta1
                .iter()
                .chain(&def.theta2)
                .all(|t| t.abs() < 1e-12),
            "{def:?}"
        );
        let (f, _) = force_and_tangent(&s, &section(), l);
        let scale = section().youngs_modulus * section().area;
        assert!(f.iter().all(|x| x.abs() < 1e-10 * scale), "{f:?}");
    }

    #[test]
    fn small_strain_stiffness_is_the_linear_beam() {
        let l = 2.0;
        let sec = section();
        let (_, k) = force_and_tangent(&straight(l), &sec, l);
        let ea = sec.youngs_modulus * sec.area / l;
        let ei = sec.bending_stiffness();
        assert!((k[0][0] - ea).abs() < 1e-9 * ea && (k[0][6] + ea).abs() < 1e-9 * ea);
        // Lateral y (bending about z): 12EI/l³, 6EI/l², 4EI/l, 2EI/l.
        assert!((k[1][1] - 12.0 * ei / l.powi(3)).abs() < 1e-8 * ei);
        assert!((k[1][5] - 6.0 * ei / l.powi(2)).abs() < 1e-8 * ei);
        assert!((k[5][5] - 4.0 * ei / l).abs() < 1e-8 * ei);
        assert!((k[5][11] - 2.0 * ei / l).abs() < 1e-8 * ei);
        let gj = sec.shear_modulus * sec.polar_moment / l;
        assert!((k[3][3] - gj).abs() < 1e-8 * gj);
    }

    #[test]
    fn tangent_is_the_derivative_of_the_force() {
        // A deformed, rotated element: K against central differences of f under the
        // multiplicative update.
        let l = 3.0;
        let sec = section();
        let dq0 = [
            0.01, -0.02, 0.03, 0.05, -0.04, 0.1, 0.02, 0.05, -0.03, -0.08, 0.06, 0.2,
        ];
        let s = apply(
            &apply(
                &straight(l),
                &[0.0, 0.0, 0.0, 0.7, 0.0, 0.0, 0.0, 0.0, 0.0, 0.7, 0.0, 0.0],
            ),
            &dq0,
        );
        let (_, k) = force_and_tangent(&s, &sec, l);
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        let kmax = k.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        for c in 0..12 {
            let mut dp = [0.0; 12];
            dp[c] = h;
            let mut dm = [0.0; 12];
            dm[c] = -h;
            let (fp, _) = force_and_tangent(&apply(&s, &dp), &sec, l);
            let (fm, _) = force_and_tangent(&apply(&s, &dm), &sec, l);
            for r in 0..12 {
                let fd = (fp[r] - fm[r]) / (2.0 * h);
                worst = worst.max((fd - k[r][c]).abs() / kmax);
            }
        }
        assert!(worst < 1e-7, "tangent vs FD of the force: {worst:e}");
    }

    #[test]
    fn compression_softens_lateral_stiffness() {
        let l = 1.0;
        let sec = section();
        let ea = sec.youngs_modulus * sec.area / l;
        let strain = 1e-4;
        let compressed = ElementState {
            x: [[0.0; 3], [l * (1.0 - strain), 0.0, 0.0]],
            triad: [rotation_exp(&[0.0; 3]); 2],
        };
        let (_, k0) = force_and_tangent(&straight(l), &sec, l);
        let (f, k) = force_and_tangent(&compressed, &sec, l);
        let n = -ea * l * strain; // axial force (compression < 0)
        assert!((f[6] - n).abs() < 1e-6 * n.abs(), "{}", f[6]);
        // Geometric stiffness N/l on the lateral translations (bending with the current
        // chord l: 12EI/(l0·l²)).
        let lc = l * (1.0 - strain);
        let expected = 12.0 * sec.bending_stiffness() / (l * lc * lc) + n / lc;
        assert!(k[1][1] < k0[1][1]);
        assert!(
            (k[1][1] - expected).abs() < 1e-3 * (n / l).abs(),
            "{} vs {}",
            k[1][1],
            expected
        );
    }

    #[test]
    fn half_the_evaluations_give_the_whole_tangent() {
        // Random states: stretched, bent, twisted, spun by hundreds of radians, relative
        // rotations up to 2.5 rad.
        let mut seed = 12345u64;
        let mut rnd = |a: f64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            a * ((seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0)
        };
        let l = 9.0;
        let mut worst: f64 = 0.0;
        for _ in 0..40 {
            let spin = rotation_exp(&[rnd(300.0), rnd(300.0), rnd(300.0)]);
            let r1 = mat_mul(&rotation_exp(&[rnd(1.2), rnd(1.2), rnd(1.2)]), &spin);
            let r2 = mat_mul(&rotation_exp(&[rnd(1.2), rnd(1.2), rnd(1.2)]), &spin);
            let x2: [f64; 3] = std::array::from_fn(|k| spin[k][0] * (l + rnd(0.05)) + rnd(0.3));
            let s = ElementState {
                x: [[rnd(1e3), rnd(1e3), rnd(1e3)], [0.0; 3]],
                triad: [r1, r2],
            };
            let s = ElementState {
                x: [s.x[0], std::array::from_fn(|k| s.x[0][k] + x2[k])],
                ..s
            };
            let (f, k) = force_and_tangent(&s, &section(), l);
            let (f0, k0) = force_and_tangent_full(&s, &section(), l);
            let scale = k0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            let fscale = f0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for a in 0..12 {
                worst = worst.max((f[a] - f0[a]).abs() / fscale);
                for b in 0..12 {
                    worst = worst.max((k[a][b] - k0[a][b]).abs() / scale);
                }
            }
        }
        eprintln!("78-evaluation tangent vs 144: {worst:.2e} of the largest entry");
        assert!(worst <= 1e-12, "{worst:e}");
    }
}
