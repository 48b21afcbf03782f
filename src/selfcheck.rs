//! Random contact states spanning the element's regimes, and the error measures used to
//! compare two evaluations (GPU against CPU twin, f32 against f64, analytic against finite
//! differences). Used by the test suite, `holewall gpu-info` and the benchmarks.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use crate::kernels::contact::{ContactBatch, OUTPUT_LEN};
use crate::physics::contact::{ContactParams, FrictionModel};
use crate::physics::vec3::{add, cross, dot, scale, Vec3};

/// The eight blocks of the output fields: (first, end) indices of g-force, g-moment,
/// K-force rows, K-moment rows, C-force rows, C-moment rows, c_omega-force, c_omega-moment.
pub const BLOCKS: [(usize, usize); 8] = [
    (0, 3),
    (3, 6),
    (6, 15),
    (15, 24),
    (24, 33),
    (33, 42),
    (42, 45),
    (45, 48),
];

/// Names of [`BLOCKS`].
pub const BLOCK_NAMES: [&str; 8] = [
    "g.f",
    "g.m",
    "K.f",
    "K.m",
    "C.f",
    "C.m",
    "c_omega.f",
    "c_omega.m",
];

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// `max|a − b|` over `lo..hi`, divided by `denom`: 0 where equal, infinity over a zero
/// denominator.
fn relative_difference(
    reference: &[f64; OUTPUT_LEN],
    other: &[f64; OUTPUT_LEN],
    (lo, hi): (usize, usize),
    denom: f64,
) -> f64 {
    let diff = (lo..hi).fold(0.0f64, |m, k| m.max((reference[k] - other[k]).abs()));
    if diff == 0.0 {
        0.0
    } else if denom == 0.0 {
        f64::INFINITY
    } else {
        diff / denom
    }
}

/// Relative error of `other` against `reference`, per block: `max|a − b| / max(max|b_block|,
/// floor_q)`, with an absolute floor per quantity (g, K, C, c_omega) for blocks that vanish
/// by cancellation (e.g. `C` without damping where the regularised sign is flat). A block
/// exactly equal in both gives 0; a non-zero difference over a zero denominator, infinity.
pub fn block_errors(
    reference: &[f64; OUTPUT_LEN],
    other: &[f64; OUTPUT_LEN],
    floors: &[f64; 4],
) -> [f64; 8] {
    std::array::from_fn(|b| {
        let (lo, hi) = BLOCKS[b];
        relative_difference(
            reference,
            other,
            BLOCKS[b],
            max_abs(&reference[lo..hi]).max(floors[b / 2]),
        )
    })
}

/// Which regime a sampled state is in (for reports and targeted checks).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Depth {
    /// `delta < 0` (or `r = 0` at zero clearance).
    Outside,
    /// `delta ∈ [1e-9, 1e-5]` m.
    JustPast,
    /// `delta ∈ [1e-5, 1e-2]` m.
    Deep,
    /// `delta` within 1e-3 relative of `soft_blend`.
    AtBlend,
}

/// Where the slip speed sits against `eps`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slip {
    /// `|s| < eps` (regularised branch).
    Below,
    /// `|s| = eps` (the C¹ seam).
    At,
    /// `|s| > eps`.
    Above,
    /// `s = 0` (rolling without slip, or no axial motion).
    Zero,
}

/// One sampled contact state.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Displacement from the site reference point.
    pub d: Vec3<f64>,
    /// Velocity.
    pub v: Vec3<f64>,
    /// Spin rate.
    pub omega: f64,
    /// Law parameters.
    pub params: ContactParams<f64>,
    /// Depth regime.
    pub depth: Depth,
    /// Circumferential slip regime (for `coupled`: of the slip speed w).
    pub slip_t: Slip,
    /// Axial slip regime (split only).
    pub slip_l: Slip,
}

fn log_uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    10f64.powf(rng.random_range(lo.log10()..hi.log10()))
}

fn slip_speed(rng: &mut StdRng, regime: Slip, eps: f64) -> f64 {
    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    sign * match regime {
        Slip::Below => rng.random_range(0.05..0.95) * eps,
        Slip::At => eps,
        Slip::Above => rng.random_range(1.05..100.0) * eps,
        Slip::Zero => 0.0,
    }
}

fn pick<T: Copy>(rng: &mut StdRng, items: &[T]) -> T {
    items[rng.random_range(0..items.len())]
}

/// An orthonormal pair (u0, t0) perpendicular to the unit vector `n`.
pub fn perpendicular_basis(n: &Vec3<f64>) -> (Vec3<f64>, Vec3<f64>) {
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let a = cross(n, &helper);
    let a = scale(&a, 1.0 / dot(&a, &a).sqrt());
    (a, cross(n, &a))
}

/// Samples a state at a site with unit axis `n`, spanning: outside / just past contact
/// (1e-9…1e-5 m) / deep / at the soft blend; slip below, at, above `eps` and zero; `m` in
/// {2/3, 1, 3/2} or random in [0.5, 2]; `k_e` log-uniform up to 1e11; both signs of the
/// normal velocity (so `N = 0` by damping also occurs).
pub fn sample(rng: &mut StdRng, n: &Vec3<f64>, friction: FrictionModel) -> Sample {
    let (u0, t0) = perpendicular_basis(n);
    let theta = rng.random_range(0.0..std::f64::consts::TAU);
    let u = add(&scale(&u0, theta.cos()), &scale(&t0, theta.sin()));
    let t = cross(n, &u);

    let clearance = if rng.random_bool(0.1) {
        0.0
    } else {
        log_uniform(rng, 1e-3, 5e-2)
    };
    let random_m = rng.random_range(0.5..2.0);
    let m = pick(rng, &[2.0 / 3.0, 1.0, 1.5, random_m]);
    let soft_blend = log_uniform(rng, 1e-6, 1e-4);
    let mut depth = pick(
        rng,
        &[
            Depth::Outside,
            Depth::JustPast,
            Depth::JustPast,
            Depth::Deep,
            Depth::Deep,
            Depth::AtBlend,
        ],
    );
    if clearance == 0.0 && depth == Depth::Outside {
        // At zero clearance only the axis itself is outside, where u is undefined.
        depth = Depth::JustPast;
    }
    let delta = match depth {
        Depth::Outside => -rng.random_range(0.0..1.0) * clearance,
        Depth::JustPast => log_uniform(rng, 1e-9, 1e-5),
        Depth::Deep => log_uniform(rng, 1e-5, 1e-2),
        Depth::AtBlend => soft_blend * (1.0 + rng.random_range(-1e-3..1e-3)),
    };
    let r = clearance + delta;
    let axial = rng.random_range(-0.1..0.1);
    let d = add(&scale(&u, r), &scale(n, axial));

    let eps = log_uniform(rng, 1e-4, 1e-2);
    let disk_radius = rng.random_range(0.03..0.15);
    let slips = [Slip::Below, Slip::At, Slip::Above, Slip::Zero];
    let slip_t = pick(rng, &slips);
    let slip_l = pick(rng, &slips);
    let (s_t, s_l) = match friction {
        FrictionModel::Split => (slip_speed(rng, slip_t, eps), slip_speed(rng, slip_l, eps)),
        FrictionModel::Coupled => {
            let w = slip_speed(rng, slip_t, eps).abs();
            let phi = rng.random_range(0.0..std::f64::consts::TAU);
            (w * phi.cos(), w * phi.sin())
        }
    };
    let v_u = log_uniform(rng, 1e-4, 3.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let v_t = log_uniform(rng, 1e-4, 3.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let v = add(&add(&scale(&u, v_u), &scale(&t, v_t)), &scale(n, s_l));
    // omega sets the circumferential slip s_t = v·t + R_d·omega.
    let omega = (s_t - dot(&v, &t)) / disk_radius;

    let mu = |rng: &mut StdRng| {
        if rng.random_bool(0.1) {
            0.0
        } else {
            rng.random_range(0.0..1.0)
        }
    };
    let params = ContactParams {
        clearance,
        disk_radius,
        wall_stiffness: log_uniform(rng, 1e5, 1e11),
        spring_exponent: m,
        wall_damping: if rng.random_bool(0.2) {
            0.0
        } else {
            log_uniform(rng, 10.0, 1e5)
        },
        mu_t: mu(rng),
        mu_l: mu(rng),
        eps,
        soft_blend,
        // The paper's element: the whirl's average is checked against the twin in tests.
        side_friction: 1.0,
    };
    Sample {
        d,
        v,
        omega,
        params,
        depth,
        slip_t,
        slip_l,
    }
}

/// A random unit vector.
pub fn random_unit(rng: &mut StdRng) -> Vec3<f64> {
    loop {
        let a: Vec3<f64> = [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        let len = dot(&a, &a).sqrt();
        if len > 0.1 && len <= 1.0 {
            return scale(&a, 1.0 / len);
        }
    }
}

/// A random batch of V variants × S sites (random axes per site, [`sample`] per pair).
pub fn random_batch(
    seed: u64,
    num_variants: usize,
    num_sites: usize,
    friction: FrictionModel,
) -> ContactBatch<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut batch = ContactBatch::new(num_variants, num_sites);
    for site in 0..num_sites {
        let n = random_unit(&mut rng);
        batch.set_site_normal(site, n);
        let n = batch.site_normal(site);
        for variant in 0..num_variants {
            let s = sample(&mut rng, &n, friction);
            let i = batch.pair_index(variant, site);
            batch.set_params(i, &s.params);
            batch.set_state(i, s.d, s.v, s.omega);
        }
    }
    batch
}

/// Median wall time (s) of `repeats` calls of `f`, after one warm-up call.
pub fn median_seconds<E>(repeats: usize, mut f: impl FnMut() -> Result<(), E>) -> Result<f64, E> {
    f()?;
    let mut times = Vec::with_capacity(repeats.max(1));
    for _ in 0..repeats.max(1) {
        let start = std::time::Instant::now();
        f()?;
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(|a, b| a.total_cmp(b));
    Ok(times[times.len() / 2])
}

/// The four output quantities as (first, end) field indices: g, K, C, c_omega.
pub const QUANTITIES: [(usize, usize); 4] = [(0, 6), (6, 24), (24, 42), (42, 48)];

/// Names of [`QUANTITIES`].
pub const QUANTITY_NAMES: [&str; 4] = ["g", "K", "C", "c_omega"];

/// Normwise relative error of `other` against `reference` per quantity (g, K, C,
/// c_omega): `max|a − b| / max|b|` over the quantity's entries; 0 where both are zero,
/// infinity where only the reference is.
pub fn quantity_errors(reference: &[f64; OUTPUT_LEN], other: &[f64; OUTPUT_LEN]) -> [f64; 4] {
    QUANTITIES.map(|(lo, hi)| {
        relative_difference(reference, other, (lo, hi), max_abs(&reference[lo..hi]))
    })
}

/// The quantities of one pair in contact that the error measures need (f64 reference).
struct PairState {
    r: f64,
    delta: f64,
    f_e: f64,
    df_e: f64,
    f_d: f64,
    v_u: f64,
    normal: f64,
    speed: f64,
}

/// `None` where the pair carries no contact force.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn pair_state(
    n: &Vec3<f64>,
    d: &Vec3<f64>,
    v: &Vec3<f64>,
    p: &ContactParams<f64>,
    spring: crate::physics::contact::SpringLaw,
    damping: bool,
) -> Option<PairState> {
    use crate::physics::contact::elastic_force;
    use crate::physics::vec3::sub;
    let d_t = sub(d, &scale(n, dot(d, n)));
    let r = dot(&d_t, &d_t).sqrt();
    let delta = r - p.clearance;
    if !(delta > 0.0) {
        return None;
    }
    let u = scale(&d_t, 1.0 / r);
    let (f_e, df_e) = elastic_force(delta, p, spring);
    let v_u = dot(v, &u);
    let f_d = if damping { p.wall_damping * v_u } else { 0.0 };
    let normal = f_e + f_d;
    if !(normal > 0.0) {
        return None;
    }
    Some(PairState {
        r,
        delta,
        f_e,
        df_e,
        f_d,
        v_u,
        normal,
        speed: dot(v, v).sqrt(),
    })
}

/// First-order condition number of the element's outputs for one pair: how much a
/// relative perturbation `u` of the inputs (and of each operation) can grow in the
/// outputs, normwise. Terms (docs/contact-element.md, "Accuracy"):
/// - `|d|/r`: forming `d_t = d − (d·n)n` cancels the axial part, so `u` and `t` carry a
///   relative error `u·|d|/r`;
/// - `(1 + m)·|d|/delta`: `delta = r − ΔR` cancels, the rounding of `d` (≈ `u·|d|`, axial part
///   included) moves it, and `f_e`, `df_e` inherit it;
/// - `(f_e·(1 + m)·|d|/delta + |f_d| + c·|v|·(1 + |d|/r))/N`: the cancellation of the elastic
///   and damping parts in `N = f_e + f_d`;
/// - with friction, `(μ_t + μ_l)·S/eps · (1 + |v_u|/eps)` with `S = |v|(1 + |d|/r) + R_d|ω|`
///   the scale of the slip speeds: the regularised sign has slope `2/eps`, and `∂φ/∂s`
///   (in `K`, `C`) slope `2/eps²`.
///
/// `terms` are those the compared outputs were evaluated with; its spring law is the one that counts: a linear or hard-spring
/// build ignores `m < 1`'s blend or `m` itself, and its scales and κ must too (the power
/// law's, used for a linear build, under-estimate its force where `delta < 1` — found on an
/// H100, where a linear build's rounding then read 6e6 times its bound).
///
/// Returns `None` where the pair has no contact force (all outputs are exactly zero on
/// every path, or the contact flag itself sits within rounding of `delta = 0`).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn condition_number(
    n: &Vec3<f64>,
    d: &Vec3<f64>,
    v: &Vec3<f64>,
    omega: f64,
    p: &ContactParams<f64>,
    terms: &crate::physics::contact::ContactTerms,
) -> Option<f64> {
    let friction = terms.friction.is_some();
    let damping = terms.damping && terms.mode == crate::physics::contact::ContactMode::Dynamic;
    let spring = terms.spring;
    let PairState {
        r,
        delta,
        f_e,
        f_d,
        v_u,
        normal,
        speed,
        ..
    } = pair_state(n, d, v, p, spring, damping)?;
    let d_len = dot(d, d).sqrt();
    let axial = d_len / r;
    // The rounding of d itself (≈ u·|d| in each component) moves delta: |d|/delta, not r/delta.
    let delta_cond = (1.0 + p.spring_exponent) * d_len / delta;
    let mut kappa = 1.0 + axial + delta_cond + (f_e * delta_cond + f_d.abs()) / normal;
    if damping {
        kappa += p.wall_damping * speed * (1.0 + axial) / normal;
    }
    if friction {
        let slip_scale = speed * (1.0 + axial) + p.disk_radius * omega.abs();
        kappa += (p.mu_t + p.mu_l) * slip_scale / p.eps * (1.0 + v_u.abs() / p.eps);
    }
    Some(kappa)
}

/// Natural magnitude of each output quantity (g, K, C, c_omega) for one pair: the sum of
/// the magnitudes of the terms that build it (docs/contact-element.md, "Accuracy"). An
/// error is judged against this scale rather than against the quantity's own norm, which
/// can vanish by cancellation (a Jacobian of the regularised sign at its seam, a moment of
/// a nearly pure rolling contact) while its terms, and so its rounding errors, do not.
/// `None` where [`condition_number`] is `None`.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn term_scales(
    n: &Vec3<f64>,
    d: &Vec3<f64>,
    v: &Vec3<f64>,
    p: &ContactParams<f64>,
    terms: &crate::physics::contact::ContactTerms,
) -> Option<[f64; 4]> {
    let friction = terms.friction.is_some();
    let dynamic = terms.mode == crate::physics::contact::ContactMode::Dynamic;
    let damping = terms.damping && dynamic;
    let spring = terms.spring;
    let PairState {
        r,
        df_e,
        v_u,
        normal,
        speed,
        ..
    } = pair_state(n, d, v, p, spring, damping)?;
    let c = if damping { p.wall_damping } else { 0.0 };
    let mu = if friction { p.mu_t + p.mu_l } else { 0.0 };
    let arm = 1.0 + p.disk_radius;
    let slope = 2.0 / p.eps;
    let g = normal * (1.0 + mu) * arm;
    let k = (df_e.abs() + normal / r + c * speed / r) * (1.0 + mu) * arm
        + normal * mu * arm * (1.0 + v_u.abs() * slope) / r;
    let (cs, cw) = if dynamic {
        (
            (c + normal * mu * slope) * (1.0 + mu) * arm,
            normal * mu * p.disk_radius * slope * arm,
        )
    } else {
        (0.0, 0.0)
    };
    Some([g, k, cs, cw])
}

/// Error of `other` against `reference` per quantity, relative to [`term_scales`].
pub fn scaled_errors(
    reference: &[f64; OUTPUT_LEN],
    other: &[f64; OUTPUT_LEN],
    scales: &[f64; 4],
) -> [f64; 4] {
    std::array::from_fn(|q| relative_difference(reference, other, QUANTITIES[q], scales[q]))
}

/// Statistics of one output set against the f64 reference, from [`compare_outputs`].
#[derive(Clone, Debug, Default)]
pub struct ErrorStats {
    /// Pairs compared.
    pub pairs: usize,
    /// Pairs with a contact force and `u·κ ≤ 1e-3`, where the bound is applied.
    pub checked: usize,
    /// Largest normwise relative error per quantity over the checked pairs: relative to the
    /// larger of the reference block's magnitude and the quantity's natural scale.
    pub max_normwise: f64,
    /// The same over checked pairs with `κ ≤ 1e3`.
    pub max_normwise_well: f64,
    /// Largest (error / natural scale) / (u·κ) over the checked pairs.
    pub max_ratio: f64,
    /// Every (error / natural scale) of the checked pairs, for percentiles.
    pub scaled: Vec<f64>,
    /// Pairs whose contact flag differs from the reference.
    pub flag_mismatches: usize,
    /// Checked pairs whose error exceeds `bound·u·κ` (bound given to [`compare_outputs`]).
    pub over_bound: usize,
}

impl ErrorStats {
    /// The `q`-quantile (0…1) of the scaled errors; 0 when none.
    pub fn scaled_quantile(&self, q: f64) -> f64 {
        if self.scaled.is_empty() {
            return 0.0;
        }
        let mut v = self.scaled.clone();
        v.sort_by(|a, b| a.total_cmp(b));
        v[((v.len() - 1) as f64 * q.clamp(0.0, 1.0)) as usize]
    }
}

/// Compares `other` (its fields and contact flag per pair, at unit roundoff `u`) with the
/// f64 `reference` of the same batch. Pairs with a contact force and `u·κ ≤ 1e-3` are
/// checked: their error relative to the quantity's natural scale ([`term_scales`]) is
/// compared with `bound·u·κ` ([`condition_number`]); the rest sit within rounding of a
/// corner (contact onset, `N = 0`) at this precision and are only counted.
pub fn compare_outputs(
    batch: &ContactBatch<f64>,
    terms: &crate::physics::contact::ContactTerms,
    reference: &crate::kernels::contact::ContactOutputs<f64>,
    other: &dyn Fn(usize) -> ([f64; OUTPUT_LEN], u32),
    unit_roundoff: f64,
    bound: f64,
) -> ErrorStats {
    let mut st = ErrorStats {
        pairs: batch.num_pairs(),
        ..Default::default()
    };
    for i in 0..batch.num_pairs() {
        let (d, v, omega) = batch.state(i);
        let p = batch.params(i);
        let n = batch.site_normal(i / batch.num_variants);
        let (fields, flag) = other(i);
        let Some(kappa) =
            condition_number(&n, &d, &v, omega, &p, terms).filter(|k| unit_roundoff * k <= 1e-3)
        else {
            continue;
        };
        st.checked += 1;
        if flag != reference.contact[i] {
            st.flag_mismatches += 1;
        }
        let Some(scales) = term_scales(&n, &d, &v, &p, terms) else {
            continue;
        };
        let reference_fields = reference.fields(i);
        let scaled = scaled_errors(&reference_fields, &fields, &scales);
        let mut over = false;
        for q in 0..4 {
            let ratio = scaled[q] / (unit_roundoff * kappa);
            over |= ratio > bound;
            st.max_ratio = st.max_ratio.max(ratio);
            // Normwise relative to the block, or to the quantity's natural scale where the
            // block is smaller (cancellation: C of a pair at rest, a cross product of nearly
            // parallel vectors). A driver that fuses multiply-adds leaves rounding of the
            // natural scale there, which relative to the block alone reads 1e4 or infinite
            // (seen on an H100).
            let (lo, hi) = QUANTITIES[q];
            let block = max_abs(&reference_fields[lo..hi]);
            let normwise =
                relative_difference(&reference_fields, &fields, (lo, hi), block.max(scales[q]));
            st.max_normwise = st.max_normwise.max(normwise);
            if kappa <= 1e3 {
                st.max_normwise_well = st.max_normwise_well.max(normwise);
            }
            st.scaled.push(scaled[q]);
        }
        st.over_bound += usize::from(over);
    }
    st
}

/// Result of [`contact_comparison`].
#[derive(Clone, Debug)]
pub struct ContactComparison {
    /// GPU f64 against the CPU f64 twin (None without SHADER_F64).
    pub f64_stats: Option<ErrorStats>,
    /// GPU f32 against the CPU f64 twin.
    pub f32_stats: ErrorStats,
    /// Median evaluations per second, CPU f64 twin on all cores.
    pub evals_per_s_cpu_f64: f64,
    /// Median evaluations per second, GPU f32 (data resident, kernel and wait).
    pub evals_per_s_gpu_f32: f64,
    /// Median evaluations per second, GPU f64.
    pub evals_per_s_gpu_f64: Option<f64>,
}

/// The f32 error bound constant: f32 results are within `F32_BOUND·u·κ` (see
/// docs/contact-element.md, "Accuracy").
pub const F32_BOUND: f64 = 8.0;
/// The f64 error bound constant (GPU against the CPU twin).
pub const F64_BOUND: f64 = 8.0;

/// Evaluates `pairs` random pairs with `terms` on the CPU twin (f64) and on the GPU (f32,
/// and f64 where the adapter has it): error statistics and evaluation rates.
pub fn contact_comparison(
    ctx: &'static crate::gpu::GpuContext,
    terms: &crate::physics::contact::ContactTerms,
    pairs: usize,
    repeats: usize,
) -> Result<ContactComparison, crate::error::GpuError> {
    use crate::gpu::contact::GpuContactRun;
    use crate::kernels::contact::{contact, ContactOutputs};
    let num_variants = 100.min(pairs.max(1));
    let num_sites = pairs.div_ceil(num_variants);
    let friction = terms.friction.unwrap_or(FrictionModel::Split);
    let batch = random_batch(0x5eed ^ pairs as u64, num_variants, num_sites, friction);
    let p = batch.num_pairs();
    let mut reference = ContactOutputs::new(p);
    let cpu_time = median_seconds::<std::convert::Infallible>(repeats, || {
        contact(terms, &batch, &mut reference);
        Ok(())
    })
    .unwrap_or(f64::NAN);
    let b32 = batch.cast::<f32>();
    let run32 = GpuContactRun::new(ctx, terms, &b32)?;
    let t32 = median_seconds(repeats, || run32.dispatch())?;
    let o32 = run32.read()?;
    let f32_stats = compare_outputs(
        &batch,
        terms,
        &reference,
        &|i| (o32.fields(i).map(f64::from), o32.contact[i]),
        f32::EPSILON as f64 / 2.0,
        F32_BOUND,
    );
    let (f64_stats, t64) = if ctx.has_f64 {
        let run64 = GpuContactRun::new(ctx, terms, &batch)?;
        let t = median_seconds(repeats, || run64.dispatch())?;
        let o64 = run64.read()?;
        (
            Some(compare_outputs(
                &batch,
                terms,
                &reference,
                &|i| (o64.fields(i), o64.contact[i]),
                f64::EPSILON / 2.0,
                F64_BOUND,
            )),
            Some(t),
        )
    } else {
        (None, None)
    };
    Ok(ContactComparison {
        f64_stats,
        f32_stats,
        evals_per_s_cpu_f64: p as f64 / cpu_time,
        evals_per_s_gpu_f32: p as f64 / t32,
        evals_per_s_gpu_f64: t64.map(|t| p as f64 / t),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::contact::{ContactMode, ContactTerms, SpringLaw};

    /// The error measures follow the law the outputs were evaluated with: the twin's outputs of
    /// a linear, a hard and a blended build, each perturbed by a few roundings (as a driver that
    /// fuses multiply-adds leaves them), are within the bound of their own law. Measured with
    /// the power law's scales, the linear build read 6e6 times its bound (an H100 run).
    #[test]
    fn a_builds_rounding_is_within_the_bound_of_its_own_law() {
        let batch = random_batch(11, 40, 60, FrictionModel::Split);
        for spring in [SpringLaw::Linear, SpringLaw::Power, SpringLaw::PowerBlend] {
            let mut terms = ContactTerms::all(FrictionModel::Split, ContactMode::Static);
            terms.spring = spring;
            terms.damping = false;
            let mut reference = crate::kernels::contact::ContactOutputs::new(batch.num_pairs());
            crate::kernels::contact::contact(&terms, &batch, &mut reference);
            let u = f64::EPSILON / 2.0;
            let st = compare_outputs(
                &batch,
                &terms,
                &reference,
                &|i| {
                    let f = reference.fields(i).map(|x| x * (1.0 + 4.0 * u));
                    (f, reference.contact[i])
                },
                u,
                F64_BOUND,
            );
            assert!(st.checked > 100, "{spring:?}: {} checked", st.checked);
            assert_eq!(
                st.over_bound, 0,
                "{spring:?}: max ratio {:.3e}",
                st.max_ratio
            );
        }
    }
}
