//! The element's consistent tangent written out: the first variation of each intermediate
//! value of [`super::element_force`], a group of directions at a time (the translations,
//! the spins), on the values the force computed once ([`ElementValues`]). It is the
//! derivative the dual numbers of [`super::force_and_tangent_closed`] take, without carrying
//! nine derivatives through the rotation log, its transcendentals and the two 3×3 products
//! `R_rᵀ t_i`: those are replaced by the log's known response to a spin,
//! `δθ̄_i = J⁻¹(θ̄_i) R_rᵀ(δθ_i − δω)` (`δω` the frame's spin). The oracles are that
//! dual-number form and the energy's hyper-dual derivatives (`beam_tests.rs`). The GPU beam
//! kernel (`shaders/beam.wgsl`) runs this form one direction at a time, and its twin
//! (`crate::kernels::beam`) calls [`force_and_tangent_variation`].

use std::ops::{Add, Mul, Sub};

use super::{element_values, Chord, ElementStiffness, ElementValues, Mat3};
use crate::physics::rotation::{cross, Trig};

/// One derivative per direction of a group: node 2's three translations, or the six
/// spins. The derivatives are linear in the direction, so lanes only add, subtract and
/// scale by values; a group's lanes are computed together (vector instructions).
#[derive(Clone, Copy, Debug)]
struct Lanes<T, const N: usize>([T; N]);

impl<T: Trig, const N: usize> Add for Lanes<T, N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Lanes(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }
}

impl<T: Trig, const N: usize> Sub for Lanes<T, N> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Lanes(std::array::from_fn(|i| self.0[i] - o.0[i]))
    }
}

impl<T: Trig, const N: usize> Mul<T> for Lanes<T, N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: T) -> Self {
        Lanes(self.0.map(|x| x * s))
    }
}

impl<T: Trig, const N: usize> Lanes<T, N> {
    #[inline(always)]
    fn zero() -> Self {
        Lanes([T::zero(); N])
    }
}

type V3<T> = [T; 3];

#[inline(always)]
fn dot<T: Trig>(a: &V3<T>, b: &V3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `δ · v`.
#[inline(always)]
fn vd<T: Trig, const N: usize>(v: &V3<T>, d: &V3<Lanes<T, N>>) -> Lanes<T, N> {
    d[0] * v[0] + d[1] * v[1] + d[2] * v[2]
}

/// `δ × v`.
#[inline(always)]
fn dxv<T: Trig, const N: usize>(d: &V3<Lanes<T, N>>, v: &V3<T>) -> V3<Lanes<T, N>> {
    [
        d[1] * v[2] - d[2] * v[1],
        d[2] * v[0] - d[0] * v[2],
        d[0] * v[1] - d[1] * v[0],
    ]
}

/// `v × δ`.
#[inline(always)]
fn vxd<T: Trig, const N: usize>(v: &V3<T>, d: &V3<Lanes<T, N>>) -> V3<Lanes<T, N>> {
    [
        d[2] * v[1] - d[1] * v[2],
        d[0] * v[2] - d[2] * v[0],
        d[1] * v[0] - d[0] * v[1],
    ]
}

#[inline(always)]
fn add<T: Trig, const N: usize>(a: &V3<Lanes<T, N>>, b: &V3<Lanes<T, N>>) -> V3<Lanes<T, N>> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
fn sub<T: Trig, const N: usize>(a: &V3<Lanes<T, N>>, b: &V3<Lanes<T, N>>) -> V3<Lanes<T, N>> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `δ s` for a value `s`.
#[inline(always)]
fn scale<T: Trig, const N: usize>(d: &V3<Lanes<T, N>>, s: T) -> V3<Lanes<T, N>> {
    [d[0] * s, d[1] * s, d[2] * s]
}

/// `δs v` for a scalar derivative `δs` and a value `v`.
#[inline(always)]
fn outer<T: Trig, const N: usize>(ds: Lanes<T, N>, v: &V3<T>) -> V3<Lanes<T, N>> {
    [ds * v[0], ds * v[1], ds * v[2]]
}

/// `a + b` where either may be structurally zero (`None`: that group of directions does
/// not move it); one of them is not.
#[inline(always)]
fn either<X: Copy>(a: Option<X>, b: Option<X>, add: impl Fn(X, X) -> X) -> X {
    match (a, b) {
        (Some(a), Some(b)) => add(a, b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => unreachable!("a variation with no direction"),
    }
}

/// `dc/d(θ²)` of the coefficient `c(θ) = (1 − (θ/2)·cot(θ/2))/θ²` of `J⁻¹(θ)`, from `c`
/// itself: with `g = (θ/2)·cot(θ/2) = 1 − c θ²`, `g' = g/θ − θ/4 − g²/θ`, so
/// `dc/dθ = (¼ − 3c + c²θ²)/θ` and `dc/d(θ²) = (¼ − 3c + c²θ²)/(2θ²)`; below θ² = 0.1 (the
/// branch [`super::rotation_log_and_jacobian`] takes its series on) the series' derivative,
/// `1/720 + 2θ²/30240 + 3θ⁴/1209600 + 4θ⁶/47900160`.
#[inline(always)]
pub(crate) fn jacobian_coefficient_slope<T: Trig>(theta2: T, c: T) -> T {
    let k = |x: f64| T::from_f64_lossy(x);
    if theta2.to_f64_lossy() < 0.1 {
        k(1.0 / 720.0)
            + theta2
                * (k(2.0 / 30240.0) + theta2 * (k(3.0 / 1209600.0) + theta2 * k(4.0 / 47900160.0)))
    } else {
        (k(0.25) - k(3.0) * c + c * c * theta2) / (theta2 + theta2)
    }
}

/// The variation of the internal force along a group of directions: the chord's unit
/// vector and length changing by `de1`, `dl` (the translations; `None` for the spins), and
/// the triads spun by `spin` (global spins `δθ_i`, which turn each second axis by
/// `δb_i = δθ_i × b_i`; `None` for the translations). `slope` is
/// [`jacobian_coefficient_slope`] at each node, `tm`/`ttm` are `θ̄_i × m̄_i` and
/// `θ̄_i × (θ̄_i × m̄_i)`. A `None` drops its terms when the function is inlined.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn variation<T: Trig, const N: usize>(
    v: &ElementValues<T>,
    k: &ElementStiffness<T>,
    slope: &[T; 2],
    tm: &[V3<T>; 2],
    ttm: &[V3<T>; 2],
    translation: Option<(V3<Lanes<T, N>>, Lanes<T, N>)>,
    spin: [Option<V3<Lanes<T, N>>>; 2],
) -> [Lanes<T, N>; 12] {
    let c = |x: f64| T::from_f64_lossy(x);
    let (half, two, four) = (c(0.5), c(2.0), c(4.0));
    let [e1, e2, e3] = &v.e;
    let (inv_n, inv_l) = (T::one() / v.n, T::one() / v.l);
    let de1 = translation.map(|t| t.0);
    let dl = translation.map(|t| t.1);
    let db = [0, 1].map(|i| spin[i].map(|s| dxv(&s, &v.b[i])));
    let dp = match (db[0], db[1]) {
        (None, None) => None,
        (a, b) => Some(scale(&either(a, b, |a, b| add(&a, &b)), half)),
    };
    // a = e1 × p, n = |a|, e3 = a/n, e2 = e3 × e1, η = p·e1/n.
    let da = either(
        de1.map(|d| dxv(&d, &v.p)),
        dp.map(|d| vxd(e1, &d)),
        |a, b| add(&a, &b),
    );
    let dn = vd(e3, &da);
    let de3 = scale(&sub(&da, &outer(dn, e3)), inv_n);
    let de2 = match de1 {
        Some(d) => add(&dxv(&de3, e1), &vxd(e3, &d)),
        None => dxv(&de3, e1),
    };
    let deta = (either(dp.map(|d| vd(e1, &d)), de1.map(|d| vd(&v.p, &d)), |a, b| {
        a + b
    }) - dn * v.eta)
        * inv_n;
    // The frame's spin in its own components: δe_k = δω × e_k.
    let omega = [
        vd(e3, &de2),
        vd(e1, &de3),
        match de1 {
            Some(d) => vd(e2, &d),
            None => Lanes::zero(),
        },
    ];
    // δθ̄_i = J⁻¹(θ̄_i) (R_rᵀ δθ_i − ω), J⁻¹x = x − ½ θ × x + c θ × (θ × x).
    let dtheta: [V3<Lanes<T, N>>; 2] = std::array::from_fn(|i| {
        let th = &v.theta[i];
        let x = match spin[i] {
            Some(s) => [
                vd(e1, &s) - omega[0],
                vd(e2, &s) - omega[1],
                vd(e3, &s) - omega[2],
            ],
            None => [
                Lanes::zero() - omega[0],
                Lanes::zero() - omega[1],
                Lanes::zero() - omega[2],
            ],
        };
        let tx = vxd(th, &x);
        let ttx = vxd(th, &tx);
        add(&sub(&x, &scale(&tx, half)), &scale(&ttx, v.c[i]))
    });
    let bend = |a: Lanes<T, N>, b: Lanes<T, N>| (a * four + b * two) * k.bending;
    let dtwist = (dtheta[1][0] - dtheta[0][0]) * k.torsion;
    let dm = [
        [
            dtwist * c(-1.0),
            bend(dtheta[0][1], dtheta[1][1]),
            bend(dtheta[0][2], dtheta[1][2]),
        ],
        [
            dtwist,
            bend(dtheta[1][1], dtheta[0][1]),
            bend(dtheta[1][2], dtheta[0][2]),
        ],
    ];
    // v̄ = m̄ + ½ θ × m̄ + c θ × (θ × m̄), c a function of θ².
    let dv: [V3<Lanes<T, N>>; 2] = std::array::from_fn(|i| {
        let (th, m, dth) = (&v.theta[i], &v.m[i], &dtheta[i]);
        let dtm = add(&dxv(dth, m), &vxd(th, &dm[i]));
        let dttm = add(&dxv(dth, &tm[i]), &vxd(th, &dtm));
        let dc = vd(th, dth) * (slope[i] * two);
        add(
            &add(&dm[i], &scale(&dtm, half)),
            &add(&outer(dc, &ttm[i]), &scale(&dttm, v.c[i])),
        )
    });
    let dvs = add(&dv[0], &dv[1]);
    let along = |x: Lanes<T, N>, g: T| match dl {
        Some(dl) => x - dl * g,
        None => x,
    };
    let dg3 = along(deta * v.vs[0] + dvs[0] * v.eta + dvs[1], v.g3) * inv_l;
    let dg2 = along(dvs[2], v.g2) * inv_l;
    let mut dg = sub(
        &add(&outer(dg3, e3), &scale(&de3, v.g3)),
        &add(&outer(dg2, e2), &scale(&de2, v.g2)),
    );
    if let (Some(dl), Some(d)) = (dl, de1) {
        dg = add(&dg, &add(&outer(dl * k.axial, e1), &scale(&d, v.axial)));
    }
    let dq = (dvs[0] * half - dn * v.q) * inv_n;
    // f_θi = R_r v̄_i − q (b_i × e3).
    let df: [V3<Lanes<T, N>>; 2] = std::array::from_fn(|i| {
        let vi = &v.v[i];
        let mut turned = add(&scale(&de2, vi[1]), &scale(&de3, vi[2]));
        if let Some(d) = de1 {
            turned = add(&turned, &scale(&d, vi[0]));
        }
        let own = add(
            &add(&outer(dv[i][0], e1), &outer(dv[i][1], e2)),
            &outer(dv[i][2], e3),
        );
        let mut dbe = vxd(&v.b[i], &de3);
        if let Some(d) = db[i] {
            dbe = add(&dbe, &dxv(&d, e3));
        }
        sub(
            &add(&turned, &own),
            &add(&outer(dq, &v.be[i]), &scale(&dbe, v.q)),
        )
    });
    let neg = |x: Lanes<T, N>| x * c(-1.0);
    [
        neg(dg[0]),
        neg(dg[1]),
        neg(dg[2]),
        df[0][0],
        df[0][1],
        df[0][2],
        dg[0],
        dg[1],
        dg[2],
        df[1][0],
        df[1][1],
        df[1][2],
    ]
}

/// Internal force (12) and consistent tangent (12×12), the tangent written out
/// (`variation`, the translations and the spins each as one group) — the same
/// `K_jk = ∂f_j/∂Δ_k` as [`super::force_and_tangent_closed`] (translations, and left spins
/// `(I + [ε e]×)·t`), to rounding; the force is [`super::element_force`]'s bit for bit.
/// Nine directions as there: node 2's translations (node 1's columns their negation), node
/// 1's spins, node 2's spins. Both chord forms have `∂ū/∂d = e1` (exactly,
/// [`Chord::resolve`]'s two expressions of `l − l0`), which is what the translations use.
pub fn force_and_tangent_variation<T: Trig>(
    x: &[[T; 3]; 2],
    triad: &[Mat3<T>; 2],
    chord: &Chord<T>,
    k: &ElementStiffness<T>,
) -> ([T; 12], [[T; 12]; 12]) {
    let v = element_values(x, triad, chord, k);
    let slope = [0, 1].map(|i| jacobian_coefficient_slope(dot(&v.theta[i], &v.theta[i]), v.c[i]));
    let tm = [0, 1].map(|i| cross(&v.theta[i], &v.m[i]));
    let ttm = [0, 1].map(|i| cross(&v.theta[i], &tm[i]));
    let e1 = v.e[0];
    let unit = |r: usize, a: usize| if r == a { T::one() } else { T::zero() };
    // Node 2's translations δd = e_a: δl = e1[a], δe1 = (e_a − e1 e1[a])/l.
    let de1: V3<Lanes<T, 3>> =
        std::array::from_fn(|r| Lanes(std::array::from_fn(|a| (unit(r, a) - e1[r] * e1[a]) / v.l)));
    let moved = variation(
        &v,
        k,
        &slope,
        &tm,
        &ttm,
        Some((de1, Lanes(e1))),
        [None, None],
    );
    // Spins: lanes 0–2 node 1's about e_a, lanes 3–5 node 2's.
    let spin = [0, 1].map(|node| {
        Some(std::array::from_fn(|r| {
            Lanes(std::array::from_fn(|lane| {
                if lane / 3 == node {
                    unit(r, lane % 3)
                } else {
                    T::zero()
                }
            }))
        }))
    });
    let spun = variation::<T, 6>(&v, k, &slope, &tm, &ttm, None, spin);
    let mut tangent = [[T::zero(); 12]; 12];
    for j in 0..12 {
        for a in 0..3 {
            tangent[j][6 + a] = moved[j].0[a];
            tangent[j][a] = T::zero() - moved[j].0[a];
            tangent[j][3 + a] = spun[j].0[a];
            tangent[j][9 + a] = spun[j].0[3 + a];
        }
    }
    (v.force, tangent)
}
