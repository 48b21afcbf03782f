//! The stabilizer–holewall contact element (paper §2, eqs 2.1–2.39), as corrected in
//! `docs/contact-element.md`.
//!
//! This is the single source of truth for the contact law. It is generic over the float
//! type ([`Real`]: `f32` or `f64`); the CPU twin of `shaders/contact.wgsl`
//! (`src/kernels/contact.rs`) calls it, and the WGSL kernel writes the same formulas.
//!
//! Sign convention: `g` is the *internal* generalised force of the element, the negative of
//! what the wall exerts on the node, as in the residual `M q̈ + g_int(q, q̇) = g_ext`. So
//! `K = ∂g/∂x` and `C = ∂g/∂v` are the element's contributions to the tangent stiffness and
//! damping matrices (eqs 2.25, 2.26).

use crate::physics::vec3::{add, cross, dot, scale, sub, Vec3};
use crate::physics::Real;

/// Friction model over the tangent plane of the contact (eqs 2.12–2.24).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrictionModel {
    /// The paper's model: transverse and longitudinal friction regularised independently.
    Split,
    /// One regularised Coulomb cone over the tangent plane: rotation reduces axial drag.
    Coupled,
}

/// Whether `v`/`omega` are real velocities (dynamic) or the operation's virtual ones (static).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ContactMode {
    /// `v`, `omega` are the node's velocities: wall damping acts, `C` and `c_omega` are filled.
    Dynamic,
    /// `v`, `omega` only fix the friction direction (eq. 2.13 generalised); no damping force,
    /// `C = 0`, `c_omega = 0`.
    Static,
}

/// Which elastic-force branch a kernel needs (eqs 2.6, 2.7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SpringLaw {
    /// `m = 1` everywhere: `f_e = k_e·delta`, no power function.
    Linear,
    /// `m ≥ 1` everywhere (hard spring): `f_e = k_e·delta^m`.
    Power,
    /// Any `m > 0`, with the C¹ quadratic blend below `soft_blend` when `m < 1`.
    PowerBlend,
}

impl SpringLaw {
    /// The least general law that covers spring exponent `m`.
    pub fn for_exponent(m: f64) -> Self {
        if m == 1.0 {
            SpringLaw::Linear
        } else if m > 1.0 {
            SpringLaw::Power
        } else {
            SpringLaw::PowerBlend
        }
    }

    /// The least general law covering both `self` and `other`.
    pub fn join(self, other: Self) -> Self {
        self.max(other)
    }
}

/// The terms a scene needs. A term switched off is not evaluated at all; switching a term
/// off must not change the numbers for a scene that does not use it (checked in tests).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ContactTerms {
    /// Elastic-force branch.
    pub spring: SpringLaw,
    /// Wall damping `f_d = c·(v·u)` (eq. 2.9); only acts in [`ContactMode::Dynamic`].
    pub damping: bool,
    /// Friction model, or `None` for a frictionless scene (`mu_t = mu_l = 0`).
    pub friction: Option<FrictionModel>,
    /// Dynamic or static analysis.
    pub mode: ContactMode,
}

impl ContactTerms {
    /// All terms on (the general kernel) for a friction model and mode.
    pub fn all(friction: FrictionModel, mode: ContactMode) -> Self {
        ContactTerms {
            spring: SpringLaw::PowerBlend,
            damping: true,
            friction: Some(friction),
            mode,
        }
    }
}

/// Law and geometry parameters of one (variant, site) pair. SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams<T> {
    /// `ΔR = R_h − R_d` (m), ≥ 0 (eq. 2.4).
    pub clearance: T,
    /// `R_d` (m): disk (stabilizer blade) radius, lever arm of the friction moments.
    pub disk_radius: T,
    /// `k_e` (N/m^m) > 0: wall stiffness (eq. 2.6).
    pub wall_stiffness: T,
    /// `m` > 0: spring exponent, 1 linear, 3/2 hard, 2/3 soft (eq. 2.7).
    pub spring_exponent: T,
    /// `c` (N·s/m) ≥ 0: wall damping (eq. 2.9).
    pub wall_damping: T,
    /// `mu_t` ≥ 0: transverse (circumferential) friction coefficient (eq. 2.12).
    pub mu_t: T,
    /// `mu_l` ≥ 0: longitudinal (axial) friction coefficient (eq. 2.20, corrected).
    pub mu_l: T,
    /// `eps` (m/s) > 0: friction regularisation speed (eqs 2.18, 2.23); default 1e-3.
    pub eps: T,
    /// `soft_blend` (m) > 0: depth below which a soft spring is blended; default 1e-5.
    pub soft_blend: T,
    /// Static mode only: the share of the circumferential friction `N·mu_t·phi_t·t` that acts
    /// as a side force on the node — 1, the paper's element; 0 where the turning string
    /// whirls, its circumferential friction then acting as torque alone (the side force
    /// turns with the contact round the hole and averages to nothing over a whirl;
    /// `crate::diagnose::whirl_span`). The moments are the whole friction's either way;
    /// dynamic mode takes 1.
    pub side_friction: T,
}

/// Number of scalars in [`ContactParams`] (GPU layout order is the field order).
pub const PARAMS_LEN: usize = 10;

impl<T: Real> ContactParams<T> {
    /// The fields in layout order.
    pub fn to_array(&self) -> [T; PARAMS_LEN] {
        [
            self.clearance,
            self.disk_radius,
            self.wall_stiffness,
            self.spring_exponent,
            self.wall_damping,
            self.mu_t,
            self.mu_l,
            self.eps,
            self.soft_blend,
            self.side_friction,
        ]
    }

    /// Inverse of [`ContactParams::to_array`].
    pub fn from_array(a: [T; PARAMS_LEN]) -> Self {
        ContactParams {
            clearance: a[0],
            disk_radius: a[1],
            wall_stiffness: a[2],
            spring_exponent: a[3],
            wall_damping: a[4],
            mu_t: a[5],
            mu_l: a[6],
            eps: a[7],
            soft_blend: a[8],
            side_friction: a[9],
        }
    }

    /// Converts to another float type (through `f64`).
    pub fn cast<U: Real>(&self) -> ContactParams<U> {
        ContactParams::from_array(self.to_array().map(|x| U::from_f64_lossy(x.to_f64_lossy())))
    }
}

/// Result of one element evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactResponse<T> {
    /// `delta > 0`: the disk touches the wall (eq. 2.4).
    pub contact: bool,
    /// Internal generalised force `[f; m]` (force N, moment N·m).
    pub g: [T; 6],
    /// `K = ∂g/∂x` (6×3, rows of `g`, columns of `x`).
    pub k: [[T; 3]; 6],
    /// `C = ∂g/∂v` (6×3); zero in static mode.
    pub c: [[T; 3]; 6],
    /// `c_omega = ∂g/∂omega` (6); zero in static mode.
    pub c_omega: [T; 6],
}

impl<T: Real> ContactResponse<T> {
    /// No contact: everything zero.
    pub fn zero() -> Self {
        let z = T::zero();
        ContactResponse {
            contact: false,
            g: [z; 6],
            k: [[z; 3]; 6],
            c: [[z; 3]; 6],
            c_omega: [z; 6],
        }
    }
}

/// Regularised sign (eqs 2.18, 2.23 with the modulus written out) and its derivative.
///
/// `sig(s) = s/|s|` for `|s| ≥ eps`, `(2 − |s|/eps)·s/eps` otherwise: C¹ at `|s| = eps`.
#[inline]
pub fn regularised_sign<T: Real>(s: T, eps: T) -> (T, T) {
    let a = s.abs();
    if a >= eps {
        (s / a, T::zero())
    } else {
        let two = T::one() + T::one();
        ((two - a / eps) * s / eps, two * (T::one() - a / eps) / eps)
    }
}

/// `x^m` for `x > 0`.
#[inline]
fn power<T: Real>(x: T, m: T) -> T {
    x.powf(m)
}

/// Elastic force `f_e(delta)` and `df_e/ddelta` (eqs 2.6, 2.7, with the soft-spring blend
/// of `docs/contact-element.md`).
#[inline]
pub fn elastic_force<T: Real>(delta: T, p: &ContactParams<T>, law: SpringLaw) -> (T, T) {
    let k = p.wall_stiffness;
    let m = p.spring_exponent;
    let one = T::one();
    match law {
        SpringLaw::Linear => (k * delta, k),
        SpringLaw::Power | SpringLaw::PowerBlend => {
            if m == one {
                (k * delta, k)
            } else if law == SpringLaw::PowerBlend && m < one && delta < p.soft_blend {
                // f_e = a·δ + b·δ², a = (2−m)k sb^(m−1), b = (m−1)k sb^(m−2): C¹ at sb.
                let sb = p.soft_blend;
                let sb_m = power(sb, m);
                let two = one + one;
                let a = (two - m) * k * sb_m / sb;
                let b = (m - one) * k * sb_m / (sb * sb);
                (delta * (a + b * delta), a + two * b * delta)
            } else {
                let pw = power(delta, m);
                (k * pw, m * k * pw / delta)
            }
        }
    }
}

/// Friction factors `(phi_t, phi_l)` and their Jacobian `J[i][j] = ∂phi_i/∂s_j` over the
/// slip speeds `(s_t, s_l)` (eqs 2.18, 2.23; `coupled` is the regularised cone).
#[inline]
pub fn friction_factors<T: Real>(
    s_t: T,
    s_l: T,
    eps: T,
    model: FrictionModel,
) -> ([T; 2], [[T; 2]; 2]) {
    let z = T::zero();
    match model {
        FrictionModel::Split => {
            let (pt, dpt) = regularised_sign(s_t, eps);
            let (pl, dpl) = regularised_sign(s_l, eps);
            ([pt, pl], [[dpt, z], [z, dpl]])
        }
        FrictionModel::Coupled => {
            let w = (s_t * s_t + s_l * s_l).sqrt();
            if w >= eps {
                let pt = s_t / w;
                let pl = s_l / w;
                // ∂(s_t/w)/∂s_t = (1 − φ_t²)/w, written φ_l²/w (φ_t² + φ_l² = 1): the
                // difference of near-equal terms loses every digit in f32 where one slip
                // dominates (s_l ≪ s_t gives 0 instead of s_l²/w³).
                (
                    [pt, pl],
                    [[pl * pl / w, -pt * pl / w], [-pl * pt / w, pt * pt / w]],
                )
            } else {
                let two = T::one() + T::one();
                let h = (two - w / eps) / eps;
                // ∂h/∂s_j = −s_j / (eps² w); the outer-product term vanishes at w = 0.
                let q = if w > z { T::one() / (eps * eps * w) } else { z };
                (
                    [h * s_t, h * s_l],
                    [
                        [h - q * s_t * s_t, -q * s_t * s_l],
                        [-q * s_l * s_t, h - q * s_l * s_l],
                    ],
                )
            }
        }
    }
}

/// Evaluates the contact element from the node displacement `d = x − x0` (eq. 2.1).
///
/// - `n`: unit hole axis at the site (eq. 2.2);
/// - `d`: displacement of the node from the site's reference point;
/// - `v`: node velocity; `omega`: spin rate about `n` (rad/s). In static mode both are the
///   operation's virtual velocities and only fix the friction direction.
///
/// Kinematics (eqs 2.1–2.5): `d_t = (I − n nᵀ) d`, `r = |d_t|`, `delta = r − ΔR`,
/// `u = d_t/r`, `t = n × u`. Since `u, t, n` are orthonormal, `∂u/∂x = (I − nnᵀ − uuᵀ)/r
/// = t tᵀ/r` and `∂t/∂x = n × ∂u/∂x = −u tᵀ/r`; every x-derivative is a column vector
/// times `tᵀ` or `uᵀ`.
///
/// A NaN penetration or normal force counts as no contact (the negated comparisons).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn evaluate<T: Real>(
    n: &Vec3<T>,
    d: &Vec3<T>,
    v: &Vec3<T>,
    omega: T,
    p: &ContactParams<T>,
    terms: &ContactTerms,
) -> ContactResponse<T> {
    let zero = T::zero();
    let mut out = ContactResponse::zero();

    // Kinematics, eqs 2.1–2.5 (2.3 corrected: d_t = d − (d·n) n).
    let dn = dot(d, n);
    let d_t = sub(d, &scale(n, dn));
    let r = dot(&d_t, &d_t).sqrt();
    let delta = r - p.clearance;
    if !(delta > zero) {
        return out;
    }
    out.contact = true;
    let u = scale(&d_t, T::one() / r);
    let t = cross(n, &u);
    let dynamic = terms.mode == ContactMode::Dynamic;

    // Normal force, eqs 2.6–2.11: N = max(f_e + f_d, 0).
    let (f_e, df_e) = elastic_force(delta, p, terms.spring);
    let damping = dynamic && terms.damping;
    let v_u = dot(v, &u);
    let v_t = dot(v, &t);
    let mut n_raw = f_e;
    // ∂N/∂x = a_u uᵀ + a_t tᵀ, ∂N/∂v = b_u uᵀ.
    let dn_dx_u = df_e;
    let mut dn_dx_t = zero;
    let mut dn_dv_u = zero;
    if damping {
        let c = p.wall_damping;
        n_raw = n_raw + c * v_u;
        dn_dx_t = c * v_t / r;
        dn_dv_u = c;
    }
    if !(n_raw > zero) {
        // The wall pushes, never pulls: separated in force, still touching in geometry.
        return out;
    }
    let normal = n_raw;

    // Force direction A = u + a_t t + a_l n and moment arm B = R_d(a_t n − a_l t).
    let mut dir_f = u;
    let mut dir_m = [zero; 3];
    // x-derivative columns multiplying tᵀ (apart from the N-gradient part).
    let mut kf_t = scale(&t, normal / r);
    let mut km_t = [zero; 3];
    // v- and omega-derivatives of the friction factors.
    let mut cf = [[zero; 3]; 3];
    let mut cm = [[zero; 3]; 3];
    let mut cw_f = [zero; 3];
    let mut cw_m = [zero; 3];

    if let Some(model) = terms.friction {
        // Slip speeds at the contact point x + R_d u (eq. 2.14 corrected: ω × R_d u = R_d ω t;
        // eq. 2.21 corrected: s_l = v·n).
        let rd = p.disk_radius;
        let s_t = v_t + rd * omega;
        let s_l = dot(v, n);
        let (phi, jac) = friction_factors(s_t, s_l, p.eps, model);
        let a_t = p.mu_t * phi[0];
        let a_l = p.mu_l * phi[1];
        // The circumferential friction's share as a side force (static mode; 1 in dynamics).
        let side = |x: T| if dynamic { x } else { x * p.side_friction };
        let a_t_f = side(a_t);
        dir_f = add(&add(&u, &scale(&t, a_t_f)), &scale(n, a_l));
        dir_m = scale(&sub(&scale(n, a_t), &scale(&t, a_l)), rd);

        // ∂s_t/∂x = v·∂t/∂x = −(v·u)/r tᵀ =: sigma tᵀ;  ∂s_l/∂x = 0.
        let sigma = -v_u / r;
        // ∂f/∂x (friction part) columns for tᵀ:
        //   N[ −a_t u/r + sigma (mu_t J_tt t + mu_l J_lt n) ]
        let dphi_t_dst = jac[0][0];
        let dphi_l_dst = jac[1][0];
        let fric_f = add(
            &scale(&t, side(p.mu_t * dphi_t_dst)),
            &scale(n, p.mu_l * dphi_l_dst),
        );
        let fric_m = scale(
            &sub(
                &scale(n, p.mu_t * dphi_t_dst),
                &scale(&t, p.mu_l * dphi_l_dst),
            ),
            rd,
        );
        kf_t = add(
            &kf_t,
            &scale(&sub(&scale(&fric_f, sigma), &scale(&u, a_t_f / r)), normal),
        );
        km_t = scale(
            &add(&scale(&fric_m, sigma), &scale(&u, rd * a_l / r)),
            normal,
        );

        if dynamic {
            // ∂phi/∂v = J [tᵀ; nᵀ];  ∂phi/∂omega = J [R_d; 0].
            let dphi_t_dsl = jac[0][1];
            let dphi_l_dsl = jac[1][1];
            let fric_f_l = add(
                &scale(&t, p.mu_t * dphi_t_dsl),
                &scale(n, p.mu_l * dphi_l_dsl),
            );
            let fric_m_l = scale(
                &sub(
                    &scale(n, p.mu_t * dphi_t_dsl),
                    &scale(&t, p.mu_l * dphi_l_dsl),
                ),
                rd,
            );
            for i in 0..3 {
                for j in 0..3 {
                    cf[i][j] = normal * (fric_f[i] * t[j] + fric_f_l[i] * n[j]);
                    cm[i][j] = normal * (fric_m[i] * t[j] + fric_m_l[i] * n[j]);
                }
                cw_f[i] = normal * rd * fric_f[i];
                cw_m[i] = normal * rd * fric_m[i];
            }
        }
    }

    for i in 0..3 {
        out.g[i] = normal * dir_f[i];
        out.g[i + 3] = normal * dir_m[i];
        for j in 0..3 {
            let dn_dx_j = dn_dx_u * u[j] + dn_dx_t * t[j];
            out.k[i][j] = dir_f[i] * dn_dx_j + kf_t[i] * t[j];
            out.k[i + 3][j] = dir_m[i] * dn_dx_j + km_t[i] * t[j];
        }
    }
    if dynamic {
        for i in 0..3 {
            for j in 0..3 {
                let dn_dv_j = dn_dv_u * u[j];
                out.c[i][j] = dir_f[i] * dn_dv_j + cf[i][j];
                out.c[i + 3][j] = dir_m[i] * dn_dv_j + cm[i][j];
            }
            out.c_omega[i] = cw_f[i];
            out.c_omega[i + 3] = cw_m[i];
        }
    }
    out
}

/// Evaluates the element from absolute positions: `x0` is the site's reference point on the
/// hole axis, `x` the node position (eq. 2.1). `n` need not be normalised.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_at<T: Real>(
    x0: &Vec3<T>,
    n: &Vec3<T>,
    x: &Vec3<T>,
    v: &Vec3<T>,
    omega: T,
    p: &ContactParams<T>,
    terms: &ContactTerms,
) -> ContactResponse<T> {
    let len = dot(n, n).sqrt();
    let n_unit = scale(n, T::one() / len);
    evaluate(&n_unit, &sub(x, x0), v, omega, p, terms)
}

/// The lateral offset (m) from which a contact node's Newton steps follow the wall: half
/// its clearance (nearer the axis the polar split of [`wall_following_step`] is ill-posed,
/// and the wall too far to matter).
pub fn wall_following_radius(clearance: f64) -> f64 {
    0.5 * clearance
}

/// How far inside its wall a node lands ([`landing_step`]), as a fraction of its clearance.
pub const LANDING_DEPTH: f64 = 1e-6;

/// Whether static solves in a precision of `size` bytes land nodes on their walls
/// ([`landing_step`]): in f64 only. In f32 the landing depth (60 nm on a 6 cm clearance)
/// is a few ulps of the node's offset, and the solve, which converges at its rounding floor
/// with a residual up to 1.2e-3 of the force scale, stopped there further from the
/// equilibrium: the dynamic corpus's case 290 started its f32 run 1.5e-3 of the force scale
/// off the CPU's hook load instead of 5.6e-7.
pub fn lands_in(size: usize) -> bool {
    size == 8
}

/// A Newton step `du` of a contact node at offset `d` from its point on the hole axis `t`
/// that is off its wall (`δ ≤ 0`) and would end inside it: its lateral part shortened so
/// that the node lands on the wall, [`LANDING_DEPTH`] × `clearance` inside (where its
/// contact, and so the wall's stiffness, is in the next tangent); the axial part unchanged.
/// Returns `du` itself where the node is on the wall already or stays off it.
///
/// Why: the tangent of a node off its wall has no wall in it, so a Newton step that carries
/// the node through the wall ends millimetres deep, with forces of 1e5 N (corpus well 221:
/// a node 0.3 mm off moved 3.2 mm out). The line search can only shorten the whole step:
/// it halves until the node stops short of the wall, and the next iteration does the same
/// from halfway closer — the solve crawls toward the wall and stalls there with the node's
/// residual unresolved. The static solves land a node this way once per load step and not
/// in a relaxation's shifted sub-solves (`crate::solve::statics`, the engine's update
/// kernel): shortening one node's step breaks the step's consistency with its neighbours'
/// rotations, and a node landed again and again can cycle with them (corpus wells 27 and
/// 110 did); a relaxation follows an overdamped string's path across a fold, which a jump
/// to the wall leaves (corpus well 90 failed its relaxation with it).
pub fn landing_step<T: Real>(d: &Vec3<T>, t: &Vec3<T>, du: &Vec3<T>, clearance: T) -> Vec3<T> {
    let d0 = perp(d, t);
    if dot(&d0, &d0).sqrt().to_f64_lossy() > clearance.to_f64_lossy() {
        return *du;
    }
    let land = clearance * (T::one() + T::from_f64_lossy(LANDING_DEPTH));
    within_radius(d, t, du, land)
}

/// `v` less its part along the unit axis `t`.
fn perp<T: Real>(v: &Vec3<T>, t: &Vec3<T>) -> Vec3<T> {
    let a = dot(v, t);
    std::array::from_fn(|k| v[k] - a * t[k])
}

/// The step `du` of a node at offset `d` from its point on the hole axis `t`, its lateral
/// part shortened where it would end farther than `limit` from the axis: to end at `limit`,
/// along the same direction across the axis, the axial part unchanged ([`landing_step`],
/// [`deepening_step`]).
fn within_radius<T: Real>(d: &Vec3<T>, t: &Vec3<T>, du: &Vec3<T>, limit: T) -> Vec3<T> {
    let e: Vec3<T> = std::array::from_fn(|k| d[k] + du[k]);
    let d1 = perp(&e, t);
    let r1 = dot(&d1, &d1).sqrt();
    let r1_f = r1.to_f64_lossy();
    if r1_f.is_nan() || r1_f <= limit.to_f64_lossy() {
        return *du;
    }
    let s = limit / r1;
    std::array::from_fn(|k| s * d1[k] + (e[k] - d1[k]) - d[k])
}

/// How much deeper a soft-law contact node may go in one Newton step ([`deepening_step`]):
/// to this multiple of its depth.
pub const DEEPENING_FACTOR: f64 = 4.0;

/// Whether the Newton steps of a contact node on a wall of spring exponent `m` (eq. 2.7)
/// are bounded in depth ([`deepening_step`]): soft laws (m < 1), in every precision.
/// Measured on the 46 soft-law wells of the 500 (`holewall static` on each, the session
/// start's binary then this rule): 50.6 → 42.2 s, 7,553 → 5,828 Newton iterations of
/// converged steps; the relaxed 221 3.2 → 2.2 s, 134 3.4 → 2.0 s, 283 21.5 → 13.9 s. On the
/// 51 hard-law wells (m = 3/2) the same bound cost 42.1 → 65.0 s, and 388 and 403 had to
/// relax: a hard law has no stiffness at onset, so from the floor each step overshoots to
/// the bound, ×4 an iteration to a millimetre's depth; a soft law is stiffest at onset (its
/// blend), so once a node is in, Newton undershoots and the bound seldom binds. A linear
/// law's tangent is exact in the wall.
///
/// In f32 too (stop 63), unlike landing ([`lands_in`]): its floor is the landing depth, a
/// few ulps of an f32 offset, but the bound's work is the factor on the depth a node has.
/// The 38 soft-law wells of at most 1,000 nodes through the engine's GPU f32 path
/// (`holewall bench corpus --wells 1 --first-seed S --engine-sample 1`): 5,118 → 4,226
/// Newton iterations, 68 → 47 step cuts, 136 → 86 s on lavapipe, all solved either way
/// (wells 5 and 88: 8 and 13 cuts → none); the hook load of every well that does not relax
/// within 9.6e-6 of the CPU's f64 either way. Not every well gains: the unseen 775 (5 m
/// elements) 153 → 462 iterations, 4 → 13 cuts (docs/performance.md, stop 63). The
/// soft-law dynamic corpus cases of at most 400 nodes (8, 27, 48, 56, 72, 85) through the
/// engine in f32: the same cuts and whirl class, the hook load as far from the CPU's as
/// before (within 2e-5).
pub fn deepens(m: f64) -> bool {
    m < 1.0
}

/// A Newton step `du` of a soft-law contact node ([`deepens`]) at offset `d` from its point
/// on the hole axis `t` that would take its depth from `δ₀` to more than `max(
/// DEEPENING_FACTOR · δ₀, LANDING_DEPTH · clearance)`: its lateral part shortened to end at
/// that depth (along the same direction across the axis), its axial part unchanged.
/// Returns `du` itself otherwise.
///
/// Why: a node off its wall has no wall in its tangent, and its step ends millimetres deep
/// (corpus well 221, m = 2/3, 2.6e7 N/m^⅔: node 182, 0.7 mm off, stepped 4.4 mm in, 7e5 N of
/// residual). The line search can only shorten the whole step: it halves until that node
/// stops short of the wall, and the solve crawls toward it, half the gap an iteration.
/// [`landing_step`] lands such a node once a load step and not in a relaxation's shifted
/// sub-solves; this bound holds in every step, relaxations included — where well 221's
/// crawl was (its relaxation: 88 sub-solves and 1,160 Newton iterations → 69 and 720). For
/// a node in the wall it is Newton's own error: the linearisation of `f ∝ δ^m` at `δ₀`
/// is off at `δ₁` by a function of `δ₁/δ₀` alone, 32 % at 4 for m = 2/3. Without the bound
/// inside the wall (the floor alone, every step) well 27's load steps cycled and were cut.
pub fn deepening_step<T: Real>(d: &Vec3<T>, t: &Vec3<T>, du: &Vec3<T>, clearance: T) -> Vec3<T> {
    let floor = clearance * T::from_f64_lossy(LANDING_DEPTH);
    let d0 = perp(d, t);
    let depth0 = dot(&d0, &d0).sqrt() - clearance;
    let deeper = T::from_f64_lossy(DEEPENING_FACTOR) * depth0;
    let cap = if deeper.to_f64_lossy() > floor.to_f64_lossy() {
        deeper
    } else {
        floor
    };
    within_radius(d, t, du, clearance + cap)
}

/// A Newton step `du` of a node at offset `d` from its point on the hole axis `t`, taken
/// along the wall: the lateral part split into a radial part `dr` and a circumferential
/// part `ds` about the axis, the node put at radius `r + dr` in the direction
/// `e_r + (ds/r) e_t` (the axial part unchanged). To first order this is `du` itself, so
/// Newton keeps its rate; but a Cartesian step of `ds` along the wall would push the node
/// `ds²/2r` into it — with a 1e10 N/m wall, a hundred newtons for 30 µm, more than the
/// residual Newton is closing, and the line search then crawls at α ≈ 1/16. Below the
/// offset `min_radius` the step is returned unchanged.
pub fn wall_following_step<T: Real>(
    d: &Vec3<T>,
    t: &Vec3<T>,
    du: &Vec3<T>,
    min_radius: T,
) -> Vec3<T> {
    let d_perp = perp(d, t);
    let r = dot(&d_perp, &d_perp).sqrt();
    if r.to_f64_lossy() < min_radius.to_f64_lossy() || r.to_f64_lossy() == 0.0 {
        return *du;
    }
    let e_r: Vec3<T> = std::array::from_fn(|k| d_perp[k] / r);
    let e_t = crate::physics::vec3::cross(t, &e_r);
    let (dr, ds, da) = (dot(du, &e_r), dot(du, &e_t), dot(du, t));
    let phi = ds / r;
    let one = T::one();
    let scale = (r + dr) / (r * (one + phi * phi).sqrt());
    std::array::from_fn(|k| da * t[k] + scale * (d_perp[k] + ds * e_t[k]) - d_perp[k])
}
