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
//! spatial rotation increments (`R_i ← exp([δθ]×) R_i`), written out in closed form
//! ([`element_force`], Battini & Pacoste's `f = N r + E Pᵀ T⁻ᵀ m̄` for this frame, ≈ 400
//! operations), and the consistent tangent is its derivative with respect to the Newton
//! increment applied the same way, by that force evaluated in dual numbers
//! ([`force_and_tangent_closed`], one pass, the CPU static solve; [`force_and_tangent_by_direction`],
//! one column at a time, `shaders/beam.wgsl`'s form until stop 73; `src/physics/dual.rs`),
//! or written out, each intermediate value's first variation on the values the force
//! computed ([`force_and_tangent_variation`]: equal to rounding and 1.5× faster; the GPU
//! kernel's form and its twin's since stop 73, the CPU dynamic integrator's since stop 74,
//! not the CPU static solve's — a change at rounding level moves the load paths of marginal
//! wells, docs/performance.md, stop 72; the choice: `crate::solve::statics::TangentForm`).
//! The tangent so
//! contains the
//! geometric stiffness: an axial force `N` adds `N/l` to the lateral stiffness, so
//! compression softens the string and buckling appears. The oracle is the energy itself,
//! differentiated twice by hyper-dual numbers ([`force_and_tangent_hyperdual`]).
//!
//! A **stress-free kink** (bent sub, bent motor housing) is an element whose unstrained
//! state has nodal rotations `θ̄⁰_i ≠ 0` in its frame: the energy above is written in
//! `θ̄_i − θ̄⁰_i` ([`ElementStiffness::rest`], [`kink_rest_rotation`]). The straight pipe
//! has `θ̄⁰ = 0`.

use super::dual::{Dual, DualN};
use super::rotation::{by3, cross, mat_mul, mat_tmul, norm};
pub use super::rotation::{rotation_exp, rotation_log, rotation_log_and_jacobian, Mat3, Trig};
use super::Real;

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

impl<T: Real> LocalDeformation<T> {
    /// The deformation measured from an unstrained state with nodal rotations `rest`
    /// (`θ̄_i − θ̄⁰_i`; a kink's [`kink_rest_rotation`]): what the energy and the section
    /// forces see.
    pub fn minus_rest(mut self, rest: &[[f64; 3]; 2]) -> Self {
        self.theta1 = std::array::from_fn(|k| self.theta1[k] - T::from_f64_lossy(rest[0][k]));
        self.theta2 = std::array::from_fn(|k| self.theta2[k] - T::from_f64_lossy(rest[1][k]));
        self
    }
}

/// The unstrained nodal rotations `[θ̄⁰₁, θ̄⁰₂]` of an element of length `l0` whose second
/// node's triad is turned by `angle` (rad) from the first's: a kink at the element's lower
/// end, bending the string below it towards the direction at `toolface` (rad) from the
/// first node triad's second axis, turning towards its third. Measured by
/// [`local_deformation`] on that geometry (chord along the first triad's first axis), so the
/// element's frame is the one the force uses and the kinked state is exactly force free.
pub fn kink_rest_rotation(angle: f64, toolface: f64, length0: f64) -> [[f64; 3]; 2] {
    let identity: Mat3<f64> = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    // The bend towards d = cos φ e2 + sin φ e3: a rotation about e1 × d.
    let axis = [0.0, -toolface.sin(), toolface.cos()];
    let turned = rotation_exp(&[0.0, angle * axis[1], angle * axis[2]]);
    let def = local_deformation(&[0.0; 3], &[length0, 0.0, 0.0], &identity, &turned, length0);
    [def.theta1, def.theta2]
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

/// The element's stiffnesses over its length: `EA/l0`, `GJ/l0`, `EI/l0` (the beam kernel's
/// `section` binding holds them, with `l0`), and its unstrained nodal rotations (zero but
/// for a kink).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementStiffness<T> {
    /// `EA/l0` (N/m).
    pub axial: T,
    /// `GJ/l0` (N·m).
    pub torsion: T,
    /// `EI/l0` (N·m).
    pub bending: T,
    /// Unstrained nodal rotations `θ̄⁰₁, θ̄⁰₂` in the element frame (rad;
    /// [`kink_rest_rotation`]).
    pub rest: [[T; 3]; 2],
}

impl ElementStiffness<f64> {
    /// Of a straight section over a length `l0`.
    pub fn of(section: &BeamSection, length0: f64) -> Self {
        ElementStiffness {
            axial: section.youngs_modulus * section.area / length0,
            torsion: section.shear_modulus * section.polar_moment / length0,
            bending: section.bending_stiffness() / length0,
            rest: [[0.0; 3]; 2],
        }
    }

    /// The same element unstrained at the nodal rotations `rest` (a kink).
    pub fn with_rest(mut self, rest: [[f64; 3]; 2]) -> Self {
        self.rest = rest;
        self
    }
}

impl<T: Copy> ElementStiffness<T> {
    /// Each value mapped (rounding to f32, lifting to dual numbers).
    pub fn map<S>(&self, f: impl Fn(T) -> S) -> ElementStiffness<S> {
        ElementStiffness {
            axial: f(self.axial),
            torsion: f(self.torsion),
            bending: f(self.bending),
            rest: self.rest.map(|r| r.map(&f)),
        }
    }
}

/// How an element's chord `d` and elongation `ū` are formed from its two node vectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Chord<T> {
    /// The node vectors are positions: `d = x₂ − x₁`, `ū = |d| − l0`.
    Positions {
        /// Length `l0` (m).
        length0: T,
    },
    /// The node vectors are displacements `w` from a base whose chord is `c`, stretch
    /// `s = |c| − l0` and length `|c|`: `d = c + Δw` (`Δw = w₂ − w₁`) and
    /// `ū = s + (2c·Δw + Δw·Δw)/(|d| + |c|)` — `l − l0` without its cancellation (a strain of
    /// 1e-5 keeps two digits of `l − l0` in f32) and without the metres the base has moved.
    Base {
        /// Base chord `c` (m).
        chord: [T; 3],
        /// `|c| − l0` (m), formed in f64.
        stretch: T,
        /// `|c|` (m).
        length: T,
    },
}

impl<T: Copy> Chord<T> {
    /// Each value mapped.
    pub fn map<S>(&self, f: impl Fn(T) -> S) -> Chord<S> {
        match *self {
            Chord::Positions { length0 } => Chord::Positions {
                length0: f(length0),
            },
            Chord::Base {
                chord,
                stretch,
                length,
            } => Chord::Base {
                chord: chord.map(&f),
                stretch: f(stretch),
                length: f(length),
            },
        }
    }
}

impl<T: Real> Chord<T> {
    /// Chord `d`, its length `l` and the elongation `ū` of nodes at `x`.
    pub fn resolve(&self, x: &[[T; 3]; 2]) -> ([T; 3], T, T) {
        match *self {
            Chord::Positions { length0 } => {
                let d = std::array::from_fn(|k| x[1][k] - x[0][k]);
                let l = norm(&d);
                (d, l, l - length0)
            }
            Chord::Base {
                chord,
                stretch,
                length,
            } => {
                let dw: [T; 3] = std::array::from_fn(|k| x[1][k] - x[0][k]);
                let d = std::array::from_fn(|k| chord[k] + dw[k]);
                let l = norm(&d);
                let two = T::from_f64_lossy(2.0);
                let num = two * dot(&chord, &dw) + dot(&dw, &dw);
                (d, l, stretch + num / (l + length))
            }
        }
    }
}

#[inline(always)]
fn dot<T: Real>(a: &[T; 3], b: &[T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Internal force of the element in closed form: `f_j = ∂E/∂δ_j` for translations of the
/// nodes and spins of their triads (`t_i ← (I + [δθ]×) t_i`), the same force the hyper-dual
/// derivatives of [`strain_energy`] give (Battini & Pacoste 2002, `f = N r + E Pᵀ T⁻ᵀ m̄` in
/// their notation, written out for this frame).
///
/// With the frame `e1 = d/l`, `p = ½(b₁ + b₂)` (`b_i` the triads' second axes),
/// `e3 = e1 × p/n` (`n = |e1 × p| = p·e2`), `e2 = e3 × e1`, `R_r = [e1 e2 e3]`, the local
/// moments `m̄_i = ∂E/∂θ̄_i` act through `θ̄_i = log(R_rᵀ t_i)`, whose response to a spin is
/// `δθ̄_i = J⁻¹(θ̄_i) R_rᵀ(δθ_i − δω)` ([`rotation_log_and_jacobian`]); the frame's spin
/// `δω` has the components `ω₂ = −e3·δd/l`, `ω₃ = e2·δd/l` and
/// `ω₁ = η ω₂ + e3·δp/n` (`η = p·e1/n`). With `v̄_i = J⁻ᵀ(θ̄_i) m̄_i`, `V = v̄₁ + v̄₂`
/// (local components) and `N = EA/l0·ū`:
///
/// `f_x₂ = −f_x₁ = N e1 + ((η V₁ + V₂) e3 − V₃ e2)/l`,
/// `f_θᵢ = R_r v̄_i − V₁/(2n)·(b_i × e3)`.
///
/// About 400 operations; generic over `f32`, `f64` and dual numbers (the tangent,
/// [`force_and_tangent_closed`]).
pub fn element_force<T: Trig>(
    x: &[[T; 3]; 2],
    triad: &[Mat3<T>; 2],
    chord: &Chord<T>,
    k: &ElementStiffness<T>,
) -> [T; 12] {
    element_values(x, triad, chord, k).force
}

/// The closed form's intermediate values ([`element_force`]'s notation): what the force is
/// made of, and what its hand-written derivative ([`force_and_tangent_variation`]) reuses.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ElementValues<T> {
    /// Chord length `l`.
    pub l: T,
    /// Frame axes `e1, e2, e3` (the columns of `R_r`).
    pub e: [[T; 3]; 3],
    /// The triads' second axes `b_i`.
    pub b: [[T; 3]; 2],
    /// `p = ½(b₁ + b₂)`.
    pub p: [T; 3],
    /// `n = |e1 × p|`.
    pub n: T,
    /// `η = p·e1/n`.
    pub eta: T,
    /// Local rotations `θ̄_i`.
    pub theta: [[T; 3]; 2],
    /// `c(θ̄_i)` of `J⁻¹(θ̄_i)` ([`rotation_log_and_jacobian`]).
    pub c: [T; 2],
    /// Local moments `m̄_i`.
    pub m: [[T; 3]; 2],
    /// `v̄_i = J⁻ᵀ(θ̄_i) m̄_i`.
    pub v: [[T; 3]; 2],
    /// `V = v̄₁ + v̄₂`.
    pub vs: [T; 3],
    /// `N = EA/l0·ū`.
    pub axial: T,
    /// `(η V₁ + V₂)/l`.
    pub g3: T,
    /// `V₃/l`.
    pub g2: T,
    /// `q = V₁/(2n)`.
    pub q: T,
    /// `b_i × e3`.
    pub be: [[T; 3]; 2],
    /// The internal force.
    pub force: [T; 12],
}

/// [`element_force`]'s computation, keeping its intermediate values.
#[inline(always)]
pub(crate) fn element_values<T: Trig>(
    x: &[[T; 3]; 2],
    triad: &[Mat3<T>; 2],
    chord: &Chord<T>,
    k: &ElementStiffness<T>,
) -> ElementValues<T> {
    let (d, l, elongation) = chord.resolve(x);
    let e1 = [d[0] / l, d[1] / l, d[2] / l];
    let half = T::from_f64_lossy(0.5);
    let b = [0, 1].map(|i| [triad[i][0][1], triad[i][1][1], triad[i][2][1]]);
    let p: [T; 3] = by3(|r| half * (b[0][r] + b[1][r]));
    let a = cross(&e1, &p);
    let n = norm(&a);
    let e3 = [a[0] / n, a[1] / n, a[2] / n];
    let e2 = cross(&e3, &e1);
    let eta = dot(&p, &e1) / n;
    let rr: Mat3<T> = [
        [e1[0], e2[0], e3[0]],
        [e1[1], e2[1], e3[1]],
        [e1[2], e2[2], e3[2]],
    ];
    let (th1, c1) = rotation_log_and_jacobian(&mat_tmul(&rr, &triad[0]));
    let (th2, c2) = rotation_log_and_jacobian(&mat_tmul(&rr, &triad[1]));
    // Local moments m̄_i = ∂E/∂θ̄_i, of the rotations from the unstrained state.
    let s1: [T; 3] = by3(|r| th1[r] - k.rest[0][r]);
    let s2: [T; 3] = by3(|r| th2[r] - k.rest[1][r]);
    let twist = k.torsion * (s2[0] - s1[0]);
    let (two, four) = (T::from_f64_lossy(2.0), T::from_f64_lossy(4.0));
    let bend = |a: T, b: T| k.bending * (four * a + two * b);
    let m1 = [-twist, bend(s1[1], s2[1]), bend(s1[2], s2[2])];
    let m2 = [twist, bend(s2[1], s1[1]), bend(s2[2], s1[2])];
    // v̄ = J⁻ᵀ(θ) m̄ = m̄ + ½ θ × m̄ + c θ × (θ × m̄).
    let jt = |th: &[T; 3], c: T, m: &[T; 3]| -> [T; 3] {
        let tm = cross(th, m);
        let ttm = cross(th, &tm);
        by3(|r| m[r] + half * tm[r] + c * ttm[r])
    };
    let v1 = jt(&th1, c1, &m1);
    let v2 = jt(&th2, c2, &m2);
    let vs: [T; 3] = by3(|r| v1[r] + v2[r]);
    let axial = k.axial * elongation;
    let (g3, g2) = ((eta * vs[0] + vs[1]) / l, vs[2] / l);
    let g: [T; 3] = by3(|r| axial * e1[r] + g3 * e3[r] - g2 * e2[r]);
    let q = vs[0] / (n + n);
    let be = [cross(&b[0], &e3), cross(&b[1], &e3)];
    let spin = |v: &[T; 3], be: &[T; 3]| -> [T; 3] {
        by3(|r| rr[r][0] * v[0] + rr[r][1] * v[1] + rr[r][2] * v[2] - q * be[r])
    };
    let f1 = spin(&v1, &be[0]);
    let f2 = spin(&v2, &be[1]);
    ElementValues {
        l,
        e: [e1, e2, e3],
        b,
        p,
        n,
        eta,
        theta: [th1, th2],
        c: [c1, c2],
        m: [m1, m2],
        v: [v1, v2],
        vs,
        axial,
        g3,
        g2,
        q,
        be,
        force: [
            -g[0], -g[1], -g[2], f1[0], f1[1], f1[2], g[0], g[1], g[2], f2[0], f2[1], f2[2],
        ],
    }
}

/// Internal force (12) and consistent tangent (12×12) from the closed form: the force
/// [`element_force`] evaluated once in dual numbers ([`DualN`]), direction `k` seeded with
/// DOF `k` as a translation or a left spin `(I + [ε e]×)·t` — `K_jk = ∂f_j/∂Δ_k`, the
/// derivative under the multiplicative update, with the geometric stiffness (`N/l` on the
/// lateral translations) and the non-symmetric part of spatial spins. ≈ 1.5e4 operations
/// counted as 12 single-direction passes (the GPU kernel's form: each direction gives the
/// same numbers); one pass shares the value part and the transcendentals. The hyper-dual
/// form ([`force_and_tangent_hyperdual`]) is the oracle. The force is the value part, bit
/// for bit [`element_force`]'s.
///
/// Nine directions are carried, not twelve: both chord forms see the nodes' translations
/// only through `x₂ − x₁` ([`Chord::resolve`]), so node 1's translation columns are node 2's
/// negated — exactly, since a seed of −1 instead of +1 negates every derivative the dual
/// arithmetic forms without changing a rounding.
#[allow(clippy::needless_range_loop)]
pub fn force_and_tangent_closed<T: Trig>(
    x: &[[T; 3]; 2],
    triad: &[Mat3<T>; 2],
    chord: &Chord<T>,
    k: &ElementStiffness<T>,
) -> ([T; 12], [[T; 12]; 12]) {
    // Directions: 0..3 node 2's translations, 3..6 node 1's spins, 6..9 node 2's spins.
    type D<T> = DualN<T, 9>;
    let mut xs: [[D<T>; 3]; 2] = x.map(|p| p.map(D::constant));
    let mut ts: [Mat3<D<T>>; 2] = triad.map(|m| m.map(|r| r.map(D::constant)));
    for axis in 0..3 {
        xs[1][axis].d[axis] = T::one();
    }
    for node in 0..2 {
        for axis in 0..3 {
            // Spin about e_axis: d t = [e]× t, rows a and b of the triad mix.
            let dir = 3 + 3 * node + axis;
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            for c in 0..3 {
                ts[node][b][c].d[dir] = triad[node][a][c];
                ts[node][a][c].d[dir] = T::zero() - triad[node][b][c];
            }
        }
    }
    let f = element_force(&xs, &ts, &chord.map(D::constant), &k.map(D::constant));
    let force = f.map(|v| v.re);
    let tangent = f.map(|v| {
        let d = v.d;
        [
            -d[0], -d[1], -d[2], d[3], d[4], d[5], d[0], d[1], d[2], d[6], d[7], d[8],
        ]
    });
    (force, tangent)
}

/// [`force_and_tangent_closed`] one direction at a time, as `shaders/beam.wgsl` ran it until
/// stop 73 (9 passes of [`element_force`] on [`Dual`], one per seed — node 2's translations, node
/// 1's spins, node 2's spins — and node 1's translation columns as node 2's negated: fewer
/// registers, the value part computed 9 times); the same numbers. For the benchmark's
/// comparison and the test of that identity.
#[allow(clippy::needless_range_loop)]
pub fn force_and_tangent_by_direction<T: Trig>(
    x: &[[T; 3]; 2],
    triad: &[Mat3<T>; 2],
    chord: &Chord<T>,
    k: &ElementStiffness<T>,
) -> ([T; 12], [[T; 12]; 12]) {
    let cd = chord.map(Dual::constant);
    let kd = k.map(Dual::constant);
    let mut force = [T::zero(); 12];
    let mut tangent = [[T::zero(); 12]; 12];
    for seed in 0..9 {
        let mut xs = x.map(|p| p.map(Dual::constant));
        let mut ts = triad.map(|m| m.map(|r| r.map(Dual::constant)));
        // The kernel's columns: seed 0–2 → 6–8, 3–5 → 3–5, 6–8 → 9–11.
        let col = match seed {
            0..3 => seed + 6,
            3..6 => seed,
            _ => seed + 3,
        };
        let (node, axis) = (col / 6, col % 6);
        if axis < 3 {
            xs[node][axis].d = T::one();
        } else {
            let (a, b) = ((axis - 3 + 1) % 3, (axis - 3 + 2) % 3);
            for c in 0..3 {
                ts[node][b][c].d = triad[node][a][c];
                ts[node][a][c].d = T::zero() - triad[node][b][c];
            }
        }
        let f = element_force(&xs, &ts, &cd, &kd);
        for j in 0..12 {
            tangent[j][col] = f[j].d;
            if seed < 3 {
                tangent[j][seed] = T::zero() - f[j].d;
            }
        }
        force = f.map(|v| v.re);
    }
    (force, tangent)
}

/// Current configuration of one element: node positions and nodal triads `R_i Q0`.
#[derive(Clone, Copy, Debug)]
pub struct ElementState {
    /// Node positions.
    pub x: [[f64; 3]; 2],
    /// Nodal triads `R_i Q0`.
    pub triad: [Mat3<f64>; 2],
}

/// Internal force (12) of an element state, closed form ([`element_force`]).
pub fn internal_force(state: &ElementState, section: &BeamSection, length0: f64) -> [f64; 12] {
    element_force(
        &state.x,
        &state.triad,
        &Chord::Positions { length0 },
        &ElementStiffness::of(section, length0),
    )
}

/// Internal force (12) and consistent tangent (12×12) of an element state, closed form
/// ([`force_and_tangent_closed`]); the force is bit for bit [`internal_force`]'s.
pub fn force_and_tangent(
    state: &ElementState,
    section: &BeamSection,
    length0: f64,
) -> ([f64; 12], [[f64; 12]; 12]) {
    force_and_tangent_closed(
        &state.x,
        &state.triad,
        &Chord::Positions { length0 },
        &ElementStiffness::of(section, length0),
    )
}

/// Hyper-dual numbers `a + b ε₁ + c ε₂ + d ε₁ε₂` as dual numbers of dual numbers (ε₁ the
/// inner unit, ε₂ the outer): one evaluation of the element energy gives a first derivative
/// along each and the mixed second derivative exactly.
pub type HyperDual<T> = Dual<Dual<T>>;

/// Perturbs node vectors and triads along DOF `dof` (0..12: node·6 + [u(3), θ(3)]) by the
/// unit `unit`, a rotation as a left spin `(I + [unit·e]×)·triad`.
fn perturb<S: Real>(x: &mut [[S; 3]; 2], triad: &mut [Mat3<S>; 2], dof: usize, unit: S) {
    let node = dof / 6;
    let k = dof % 6;
    if k < 3 {
        x[node][k] = x[node][k] + unit;
    } else {
        let axis = k - 3;
        let mut spin: Mat3<S> = std::array::from_fn(|r| {
            std::array::from_fn(|c| if r == c { S::one() } else { S::zero() })
        });
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        spin[b][a] = unit;
        spin[a][b] = S::zero() - unit;
        triad[node] = mat_mul(&spin, &triad[node]);
    }
}

/// Internal force and consistent tangent from the strain energy by hyper-dual evaluations —
/// `f_j = ∂E/∂δ_j` (ε₁ part), `K_jk = ∂²E/∂δ_j∂Δ_k` (ε₁ε₂ part) with `Δ_k` applied first and
/// `δ_j` on top (`exp(δ)·exp(Δ)·R`): the test oracle of the closed form, generic so that
/// `holewall bench element` counts its operations. All 144 evaluations, or (`symmetric`)
/// the 78 with `j ≤ k` and the rest from [`spin_commutator`] (what the CPU path ran before
/// the closed form).
#[allow(clippy::needless_range_loop)]
pub fn force_and_tangent_hyperdual<T: Trig>(
    x: &[[T; 3]; 2],
    triad: &[Mat3<T>; 2],
    section: &BeamSection,
    length0: f64,
    rest: &[[f64; 3]; 2],
    symmetric: bool,
) -> ([T; 12], [[T; 12]; 12]) {
    let lift = |v: T| Dual::constant(Dual::constant(v));
    let xh: [[HyperDual<T>; 3]; 2] = x.map(|p| p.map(lift));
    let th: [Mat3<HyperDual<T>>; 2] = triad.map(|m| m.map(|r| r.map(lift)));
    let eps1: HyperDual<T> = Dual::constant(Dual::new(T::zero(), T::one()));
    let eps2: HyperDual<T> = Dual::new(Dual::constant(T::zero()), Dual::constant(T::one()));
    let mut force = [T::zero(); 12];
    let mut tangent = [[T::zero(); 12]; 12];
    for k in 0..12 {
        let (mut xk, mut tk) = (xh, th);
        perturb(&mut xk, &mut tk, k, eps2);
        let js = if symmetric { 0..k + 1 } else { 0..12 };
        for j in js {
            let (mut xj, mut tj) = (xk, tk);
            perturb(&mut xj, &mut tj, j, eps1);
            let def = local_deformation(&xj[0], &xj[1], &tj[0], &tj[1], length0).minus_rest(rest);
            let e = strain_energy(&def, section, length0);
            tangent[j][k] = e.d.d;
            if k == 11 || (!symmetric && k == 0) {
                force[j] = e.re.d;
            }
        }
    }
    if symmetric {
        for k in 0..12 {
            for j in 0..k {
                tangent[k][j] = tangent[j][k] + spin_commutator(&force, j, k);
            }
        }
    }
    (force, tangent)
}

/// `K_kj − K_jk` for `j < k` in the hyper-dual form: the perturbations commute except two
/// spins of one node, whose products differ by their commutator,
/// `(I + ε₁A_k)(I + ε₂A_j) − (I + ε₁A_j)(I + ε₂A_k) = ε₁ε₂ [e_k × e_j]×` — a spin, whose
/// effect on `E` is the node's moment along it; 0 for any other pair.
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

/// [`force_and_tangent_hyperdual`] with all 144 evaluations, of an element state: the oracle.
pub fn force_and_tangent_full(
    state: &ElementState,
    section: &BeamSection,
    length0: f64,
) -> ([f64; 12], [[f64; 12]; 12]) {
    force_and_tangent_hyperdual(
        &state.x,
        &state.triad,
        section,
        length0,
        &[[0.0; 3]; 2],
        false,
    )
}

#[path = "beam_tangent.rs"]
mod tangent;
pub use tangent::force_and_tangent_variation;

#[cfg(test)]
#[path = "beam_tests.rs"]
mod tests;
