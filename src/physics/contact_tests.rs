//! Checks of the contact law against central differences and its physical properties.
//!
//! The finite differences are taken in double-double arithmetic (`super::double_double`), with steps
//! 1e-14 of the distance to the nearest kink, so that neither truncation nor rounding
//! of the difference quotient limits the check: what is compared is the analytic Jacobian,
//! evaluated in f64, against the derivative of `g` itself.

use super::double_double::Dd;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use super::contact::*;
use super::vec3::{cross, dot, scale, sub, Vec3};
use crate::kernels::contact::{response_fields, OUTPUT_LEN};
use crate::selfcheck::{block_errors, random_unit, sample, term_scales, Depth, Slip, BLOCK_NAMES};

fn dd3(a: &Vec3<f64>) -> Vec3<Dd> {
    a.map(Dd::from)
}

fn g_dd(
    n: &Vec3<f64>,
    d: &Vec3<Dd>,
    v: &Vec3<Dd>,
    omega: Dd,
    p: &ContactParams<f64>,
    terms: &ContactTerms,
) -> [Dd; 6] {
    evaluate(&dd3(n), d, v, omega, &p.cast::<Dd>(), terms).g
}

#[allow(clippy::too_many_arguments)]
/// K, C, c_omega by central differences of g in double-double, in output-field layout.
fn finite_difference(
    n: &Vec3<f64>,
    d: &Vec3<f64>,
    v: &Vec3<f64>,
    omega: f64,
    p: &ContactParams<f64>,
    terms: &ContactTerms,
    h_x: f64,
    h_v: f64,
    h_w: f64,
) -> [f64; OUTPUT_LEN] {
    let mut out = [0.0; OUTPUT_LEN];
    let base_d = dd3(d);
    let base_v = dd3(v);
    let w = Dd::from(omega);
    let g = g_dd(n, &base_d, &base_v, w, p, terms);
    for (k, x) in g.iter().enumerate() {
        out[k] = f64::from(*x);
    }
    // Double-double rounding of g (≈1e-32 relative per operation, a few hundred of them)
    // bounds the noise of a difference quotient by 1e-28·max|g|/h: below that it is zero.
    let g_max = out[..6].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = |plus: [Dd; 6], minus: [Dd; 6], h: f64| -> [f64; 6] {
        let two_h = Dd::from(2.0 * h);
        let noise = 1e-28 * g_max / h;
        std::array::from_fn(|r| {
            let x = f64::from((plus[r] - minus[r]) / two_h);
            if x.abs() < noise {
                0.0
            } else {
                x
            }
        })
    };
    let dynamic = terms.mode == ContactMode::Dynamic;
    let h = |x: f64| Dd::from(x);
    for j in 0..3 {
        let shift = |a: &Vec3<Dd>, by: Dd| {
            let mut b = *a;
            b[j] = b[j] + by;
            b
        };
        // Column j of K (x_j) and, in dynamic mode, of C (v_j).
        let col = diff(
            g_dd(n, &shift(&base_d, h(h_x)), &base_v, w, p, terms),
            g_dd(n, &shift(&base_d, -h(h_x)), &base_v, w, p, terms),
            h_x,
        );
        for r in 0..6 {
            out[6 + 3 * r + j] = col[r];
        }
        if dynamic {
            let col = diff(
                g_dd(n, &base_d, &shift(&base_v, h(h_v)), w, p, terms),
                g_dd(n, &base_d, &shift(&base_v, -h(h_v)), w, p, terms),
                h_v,
            );
            for r in 0..6 {
                out[24 + 3 * r + j] = col[r];
            }
        }
    }
    if dynamic {
        let col = diff(
            g_dd(n, &base_d, &base_v, w + h(h_w), p, terms),
            g_dd(n, &base_d, &base_v, w - h(h_w), p, terms),
            h_w,
        );
        out[42..48].copy_from_slice(&col);
    }
    out
}

struct Steps {
    h_x: f64,
    h_v: f64,
    h_w: f64,
}

/// Steps of 1e-14 of the shortest length on which g changes: in x the penetration `|delta|`,
/// the radius `r`, the distance to `N = 0` (g has a corner there), `eps/|∂s/∂x|` and, for a
/// soft spring, `soft_blend`; in v `eps` and the distance to `N = 0`. The C¹ seams (`|s| =
/// eps`, `s = 0`, `delta = soft_blend`) are not avoided: a central difference across one
/// errs by O(h/length) ≈ 1e-14, and continuity there is checked apart. Only the corners
/// (contact onset, `N = 0`) must not be straddled, and the steps never do.
fn steps(
    n: &Vec3<f64>,
    d: &Vec3<f64>,
    v: &Vec3<f64>,
    _omega: f64,
    p: &ContactParams<f64>,
    terms: &ContactTerms,
) -> Steps {
    let d_t = sub(d, &scale(n, dot(d, n)));
    let r = dot(&d_t, &d_t).sqrt();
    let delta = r - p.clearance;
    let mut lx = vec![delta.abs(), r.max(1e-300)];
    let mut lv = vec![p.eps];
    if r > 0.0 && delta > 0.0 {
        let u = scale(&d_t, 1.0 / r);
        let t = cross(n, &u);
        let v_u = dot(v, &u);
        let v_t = dot(v, &t);
        if p.spring_exponent < 1.0 {
            lx.push(p.soft_blend);
        }
        let (f_e, df_e) = elastic_force(delta, p, SpringLaw::PowerBlend);
        let c = if terms.mode == ContactMode::Dynamic {
            p.wall_damping
        } else {
            0.0
        };
        let n_raw = f_e + c * v_u;
        lx.push(n_raw.abs() / (df_e.abs() + c * v_t.abs() / r));
        if c > 0.0 {
            lv.push(n_raw.abs() / c);
        }
        lx.push(p.eps * r / v_u.abs());
    }
    let min = |l: &[f64]| {
        l.iter()
            .copied()
            .filter(|x| *x > 0.0)
            .fold(f64::INFINITY, f64::min)
    };
    let h_x = 1e-14 * min(&lx);
    let h_v = 1e-14 * min(&lv);
    Steps {
        h_x,
        h_v,
        h_w: h_v / p.disk_radius,
    }
}

#[test]
fn jacobians_match_central_differences() {
    let mut rng = StdRng::seed_from_u64(20261122);
    let mut worst = [0.0f64; 8];
    let mut worst_f64_ratio = 0.0f64;
    let mut count = 0;
    let mut depths = std::collections::HashMap::new();
    let mut slips = std::collections::HashMap::new();
    let mut exponents = [0usize; 3];
    let mut max_stiffness: f64 = 0.0;
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        for mode in [ContactMode::Dynamic, ContactMode::Static] {
            let terms = ContactTerms::all(friction, mode);
            for _ in 0..1000 {
                let n = random_unit(&mut rng);
                let mut s = sample(&mut rng, &n, friction);
                // Static: every other state at the whirl's average (its circumferential
                // friction as torque alone, `side_friction` 0).
                if mode == ContactMode::Static && count % 2 == 0 {
                    s.params.side_friction = 0.0;
                }
                // The analytic Jacobian, in double-double too: the same generic code as the
                // f64 path, here free of f64 rounding, which near-singular states (clearance 0
                // with a large axial offset, slip within rounding of eps) would otherwise
                // mix into the check. The f64 instance is checked against it below.
                let analytic_dd = evaluate(
                    &dd3(&n),
                    &dd3(&s.d),
                    &dd3(&s.v),
                    Dd::from(s.omega),
                    &s.params.cast::<Dd>(),
                    &terms,
                );
                let analytic: ContactResponse<f64> = ContactResponse {
                    contact: analytic_dd.contact,
                    g: analytic_dd.g.map(f64::from),
                    k: analytic_dd.k.map(|r| r.map(f64::from)),
                    c: analytic_dd.c.map(|r| r.map(f64::from)),
                    c_omega: analytic_dd.c_omega.map(f64::from),
                };
                let analytic_f64 = evaluate(&n, &s.d, &s.v, s.omega, &s.params, &terms);
                if let (Some(kappa), Some(scales)) = (
                    crate::selfcheck::condition_number(&n, &s.d, &s.v, s.omega, &s.params, &terms),
                    term_scales(&n, &s.d, &s.v, &s.params, &terms),
                ) {
                    let e = crate::selfcheck::scaled_errors(
                        &response_fields(&analytic),
                        &response_fields(&analytic_f64),
                        &scales,
                    );
                    for (q, e) in e.iter().enumerate() {
                        assert!(*e <= 8.0 * f64::EPSILON * kappa, "f64 instance off its first-order bound: quantity {q}: {e:e} vs κ {kappa:e}");
                        worst_f64_ratio = worst_f64_ratio.max(e / (f64::EPSILON * kappa));
                    }
                }
                let st = steps(&n, &s.d, &s.v, s.omega, &s.params, &terms);
                let fd = finite_difference(
                    &n, &s.d, &s.v, s.omega, &s.params, &terms, st.h_x, st.h_v, st.h_w,
                );
                let a = response_fields(&analytic);
                // Floor: 1e-5 of the quantity's natural scale (the sum of its terms' sizes), for
                // blocks that vanish by cancellation, e.g. C at the seam |s| = eps, where the
                // f64 slip speed itself carries a rounding error of u·|v|/eps relative to eps:
                // such a block is held to 1e-11 of that scale instead of 1e-6 of itself.
                let floors = term_scales(&n, &s.d, &s.v, &s.params, &terms)
                    .map(|sc| sc.map(|x| 1e-5 * x))
                    .unwrap_or([0.0; 4]);
                let errs = block_errors(&fd, &a, &floors);
                for (b, e) in errs.iter().enumerate().skip(2) {
                    assert!(
                        *e <= 1e-6,
                        "{friction:?}/{mode:?}: block {} relative error {e:.3e} > 1e-6 at {s:?}\nanalytic {a:?}\nfd {fd:?}",
                        BLOCK_NAMES[b]
                    );
                    worst[b] = worst[b].max(*e);
                }
                if mode == ContactMode::Static {
                    assert!(
                        a[24..48].iter().all(|x| *x == 0.0),
                        "static mode: C and c_omega are zero"
                    );
                }
                count += 1;
                *depths.entry(format!("{:?}", s.depth)).or_insert(0usize) += 1;
                *slips.entry(format!("{:?}", s.slip_t)).or_insert(0usize) += 1;
                let m = s.params.spring_exponent;
                for (k, target) in [2.0 / 3.0, 1.0, 1.5].iter().enumerate() {
                    if m == *target {
                        exponents[k] += 1;
                    }
                }
                max_stiffness = max_stiffness.max(s.params.wall_stiffness);
            }
        }
    }
    // The sample spans every regime the issue names.
    for depth in [Depth::Outside, Depth::JustPast, Depth::Deep, Depth::AtBlend] {
        assert!(
            depths[&format!("{depth:?}")] >= 200,
            "too few {depth:?} states: {depths:?}"
        );
    }
    for slip in [Slip::Below, Slip::At, Slip::Above, Slip::Zero] {
        assert!(
            slips[&format!("{slip:?}")] >= 300,
            "too few {slip:?} states: {slips:?}"
        );
    }
    assert!(
        exponents.iter().all(|c| *c >= 300),
        "exponents {exponents:?}"
    );
    assert!(max_stiffness > 5e10);
    eprintln!("FD check over {count} states; worst relative error per block (K.f K.m C.f C.m cω.f cω.m): {:?}; f64 instance vs double-double: worst error / (ε·κ) = {worst_f64_ratio:.2}", &worst[2..]);
}

fn params(m: f64) -> ContactParams<f64> {
    ContactParams {
        clearance: 0.025,
        disk_radius: 0.1,
        wall_stiffness: 6e7,
        spring_exponent: m,
        wall_damping: 8e3,
        mu_t: 0.4,
        mu_l: 0.3,
        eps: 1e-3,
        soft_blend: 1e-5,
        side_friction: 1.0,
    }
}

const N_AXIS: Vec3<f64> = [0.0, 0.0, 1.0];

#[test]
fn zero_outside_contact() {
    let mut rng = StdRng::seed_from_u64(1);
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        for mode in [ContactMode::Dynamic, ContactMode::Static] {
            let terms = ContactTerms::all(friction, mode);
            for _ in 0..500 {
                let p = params(rng.random_range(0.5..2.0));
                let r = rng.random_range(0.0..p.clearance);
                let th: f64 = rng.random_range(0.0..6.3);
                let d = [r * th.cos(), r * th.sin(), rng.random_range(-1.0..1.0)];
                let v = [
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                ];
                let out = evaluate(&N_AXIS, &d, &v, rng.random_range(-20.0..20.0), &p, &terms);
                assert!(!out.contact);
                assert_eq!(out, ContactResponse::zero());
            }
        }
    }
}

/// Random in-contact states for the property checks.
type State = (Vec3<f64>, Vec3<f64>, f64, ContactParams<f64>);

fn contact_states(seed: u64, count: usize) -> Vec<State> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let mut p = params([2.0 / 3.0, 1.0, 1.5][rng.random_range(0..3)]);
            p.mu_t = rng.random_range(0.0..1.0);
            p.mu_l = rng.random_range(0.0..1.0);
            let r = p.clearance + 10f64.powf(rng.random_range(-8.0..-2.0));
            let th: f64 = rng.random_range(0.0..6.3);
            let d = [r * th.cos(), r * th.sin(), rng.random_range(-1.0..1.0)];
            let v = [
                rng.random_range(-0.1..0.1),
                rng.random_range(-0.1..0.1),
                rng.random_range(-0.01..0.01),
            ];
            (d, v, rng.random_range(-15.0..15.0), p)
        })
        .collect()
}

#[test]
fn normal_part_has_no_moment_and_wall_only_pushes() {
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        for mode in [ContactMode::Dynamic, ContactMode::Static] {
            for (d, v, omega, p) in contact_states(2, 2000) {
                let frictionless = ContactParams {
                    mu_t: 0.0,
                    mu_l: 0.0,
                    ..p
                };
                let out = evaluate(
                    &N_AXIS,
                    &d,
                    &v,
                    omega,
                    &frictionless,
                    &ContactTerms::all(friction, mode),
                );
                assert!(
                    out.g[3..].iter().all(|m| *m == 0.0),
                    "normal force makes a moment: {:?}",
                    out.g
                );
                // With friction, the moment is perpendicular to u (it comes from forces in
                // the tangent plane acting at R_d·u).
                let out = evaluate(
                    &N_AXIS,
                    &d,
                    &v,
                    omega,
                    &p,
                    &ContactTerms::all(friction, mode),
                );
                let u = scale(&[d[0], d[1], 0.0], 1.0 / (d[0] * d[0] + d[1] * d[1]).sqrt());
                let m = [out.g[3], out.g[4], out.g[5]];
                assert!(dot(&m, &u).abs() <= 1e-12 * dot(&m, &m).sqrt().max(1e-300));
                // N = g·u ≥ 0: the internal force points outward, the wall never pulls.
                let f = [out.g[0], out.g[1], out.g[2]];
                assert!(dot(&f, &u) >= 0.0);
            }
        }
    }
}

#[test]
fn wall_never_pulls_even_when_separating_fast() {
    // Damping larger than the elastic force while moving away: N clamps to 0, not negative.
    let p = params(1.0);
    let d = [p.clearance + 1e-6, 0.0, 0.0];
    let v = [-1.0, 0.0, 0.0];
    let out = evaluate(
        &N_AXIS,
        &d,
        &v,
        3.0,
        &p,
        &ContactTerms::all(FrictionModel::Split, ContactMode::Dynamic),
    );
    assert!(out.contact);
    assert_eq!(out.g, [0.0; 6]);
    // Approaching: damping adds to the force.
    let out_in = evaluate(
        &N_AXIS,
        &d,
        &[1.0, 0.0, 0.0],
        0.0,
        &ContactParams {
            mu_t: 0.0,
            mu_l: 0.0,
            ..p
        },
        &ContactTerms::all(FrictionModel::Split, ContactMode::Dynamic),
    );
    assert!((out_in.g[0] - (p.wall_stiffness * 1e-6 + p.wall_damping)).abs() < 1e-9 * out_in.g[0]);
}

#[test]
fn friction_only_dissipates() {
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        for mode in [ContactMode::Dynamic, ContactMode::Static] {
            for (d, v, omega, p) in contact_states(3, 3000) {
                let out = evaluate(
                    &N_AXIS,
                    &d,
                    &v,
                    omega,
                    &p,
                    &ContactTerms::all(friction, mode),
                );
                let r = (d[0] * d[0] + d[1] * d[1]).sqrt();
                let u = [d[0] / r, d[1] / r, 0.0];
                let f = [out.g[0], out.g[1], out.g[2]];
                let normal = dot(&f, &u);
                // Friction force = f − N u; its power with the moment's: f_fr·v + m·(omega n).
                let f_fr = sub(&f, &scale(&u, normal));
                let m = [out.g[3], out.g[4], out.g[5]];
                let power = dot(&f_fr, &v) + omega * dot(&m, &N_AXIS);
                let scale_p =
                    normal * (p.mu_t + p.mu_l) * (dot(&v, &v).sqrt() + p.disk_radius * omega.abs());
                assert!(power >= -1e-12 * scale_p, "friction power {power} < 0");
            }
        }
    }
}

#[test]
fn rolling_without_slip_feels_no_circumferential_friction() {
    // Disk at the wall, spinning, centre whirling backward so that s_t = v·t + R_d·omega = 0.
    let p = params(1.0);
    let d = [p.clearance + 1e-4, 0.0, 0.0];
    let omega = 12.0;
    let whirl_speed = -p.disk_radius * omega; // v·t with t = n × u = +y
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        let v = [0.0, whirl_speed, 0.0];
        let out = evaluate(
            &N_AXIS,
            &d,
            &v,
            omega,
            &p,
            &ContactTerms::all(friction, ContactMode::Dynamic),
        );
        assert!(out.contact);
        assert_eq!(out.g[1], 0.0, "circumferential friction while rolling");
        assert_eq!(
            out.g[5], 0.0,
            "friction torque about the axis while rolling"
        );
        // Slipping (no whirl) does feel it, opposing the surface speed R_d·omega·t.
        let out = evaluate(
            &N_AXIS,
            &d,
            &[0.0; 3],
            omega,
            &p,
            &ContactTerms::all(friction, ContactMode::Dynamic),
        );
        assert!(out.g[1] > 0.0 && out.g[5] > 0.0);
    }
}

#[test]
fn g_is_continuous_at_the_soft_blend_and_the_friction_seam() {
    let mut p = params(2.0 / 3.0);
    let terms = ContactTerms::all(FrictionModel::Split, ContactMode::Dynamic);
    let at = |delta: f64, v: Vec3<f64>, omega: f64, p: &ContactParams<f64>| {
        evaluate(
            &N_AXIS,
            &[p.clearance + delta, 0.0, 0.0],
            &v,
            omega,
            p,
            &terms,
        )
    };
    for m in [0.5, 2.0 / 3.0, 0.9] {
        p.spring_exponent = m;
        let sb = p.soft_blend;
        for h in [1e-9, 1e-11, 1e-13] {
            let below = at(sb * (1.0 - h), [0.0; 3], 0.0, &p);
            let above = at(sb * (1.0 + h), [0.0; 3], 0.0, &p);
            let jump = (below.g[0] - above.g[0]).abs() / above.g[0];
            assert!(
                jump <= 4.0 * m * h + 1e-15,
                "g jumps at soft_blend: {jump:e}"
            );
            // C¹: the stiffness is continuous too.
            let kj = (below.k[0][0] - above.k[0][0]).abs() / above.k[0][0];
            assert!(kj <= 1e-6, "stiffness jumps at soft_blend: {kj:e}");
        }
    }
    // |s| = eps: s_l = v·n crossing eps.
    let p = params(1.0);
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        let terms = ContactTerms::all(friction, ContactMode::Dynamic);
        for h in [1e-8, 1e-12] {
            let g = |s: f64| {
                evaluate(
                    &N_AXIS,
                    &[p.clearance + 1e-4, 0.0, 0.0],
                    &[0.0, 0.0, s],
                    0.0,
                    &p,
                    &terms,
                )
                .g
            };
            let below = g(p.eps * (1.0 - h));
            let above = g(p.eps * (1.0 + h));
            for k in 0..6 {
                assert!(
                    (below[k] - above[k]).abs() <= 1e-12 * above[2].abs().max(1.0),
                    "g[{k}] jumps at |s| = eps"
                );
            }
        }
    }
}

#[test]
fn soft_spring_has_finite_onset_stiffness() {
    let p = params(2.0 / 3.0);
    let (_, k0) = elastic_force(1e-15, &p, SpringLaw::PowerBlend);
    let a =
        (2.0 - p.spring_exponent) * p.wall_stiffness * p.soft_blend.powf(p.spring_exponent - 1.0);
    assert!((k0 - a).abs() <= 1e-9 * a);
    let (_, k_unblended) = elastic_force(1e-15, &p, SpringLaw::Power);
    assert!(
        k_unblended > 1e3 * k0,
        "k_e·delta^m with m < 1 stiffens without bound at onset"
    );
}

#[test]
fn specialised_terms_give_the_same_numbers() {
    // A frictionless, undamped, linear scene through the least general path equals the
    // all-terms path bit for bit.
    let mut rng = StdRng::seed_from_u64(9);
    for mode in [ContactMode::Dynamic, ContactMode::Static] {
        let lean = ContactTerms {
            spring: SpringLaw::Linear,
            damping: false,
            friction: None,
            mode,
        };
        for _ in 0..2000 {
            let n = random_unit(&mut rng);
            let mut s = sample(&mut rng, &n, FrictionModel::Split);
            s.params.mu_t = 0.0;
            s.params.mu_l = 0.0;
            s.params.wall_damping = 0.0;
            s.params.spring_exponent = 1.0;
            let a = evaluate(&n, &s.d, &s.v, s.omega, &s.params, &lean);
            let b = evaluate(
                &n,
                &s.d,
                &s.v,
                s.omega,
                &s.params,
                &ContactTerms::all(FrictionModel::Coupled, mode),
            );
            assert_eq!(a, b);
        }
    }
}

#[test]
fn coupled_friction_derivatives_keep_their_digits_in_f32() {
    // Circumferential slip far above ε, a tiny axial slip: ∂φ_t/∂s_t = s_l²/|s|³ exactly. As
    // (1 − φ_t²)/|s| it cancelled to 0 in f32 (and `c_omega`, N μ_t R_d s_l²/|s|³, with it).
    let (st, sl, eps) = (1.0f64, 1e-5f64, 1e-3f64);
    let (_, j64) = friction_factors(st, sl, eps, FrictionModel::Coupled);
    let (_, j32) = friction_factors(st as f32, sl as f32, eps as f32, FrictionModel::Coupled);
    let w = (st * st + sl * sl).sqrt();
    let exact = sl * sl / w.powi(3);
    assert!((j64[0][0] - exact).abs() <= 1e-15 * exact);
    let rel = (j32[0][0] as f64 - exact).abs() / exact;
    eprintln!(
        "f32 ∂φ_t/∂s_t: {:e} against {exact:e} (relative {rel:.1e})",
        j32[0][0]
    );
    assert!(rel < 1e-6, "{rel:e}");
    // The same through the element: a node on the wall spinning at 10 rad/s (s_t ≈ 1 m/s at
    // R_d = 0.1 m) while moving 10 µm/s axially; c_omega in f32 against f64.
    let p = params(1.0);
    let d = [p.clearance + 1e-4, 0.0, 0.0];
    let v = [0.0, 0.0, 1e-5];
    let terms = ContactTerms::all(FrictionModel::Coupled, ContactMode::Dynamic);
    let r64 = evaluate(&N_AXIS, &d, &v, 10.0, &p, &terms);
    let p32: ContactParams<f32> = p.cast();
    let to32 = |x: [f64; 3]| x.map(|y| y as f32);
    let r32 = evaluate(&to32(N_AXIS), &to32(d), &to32(v), 10.0f32, &p32, &terms);
    // Entry 1: the circumferential (t = n × u = y) force's response to the spin, the tiny
    // N μ_t R_d s_l²/|s|³ itself, to its own size.
    let (a, b) = (r64.c_omega[1], r32.c_omega[1] as f64);
    eprintln!("c_omega, circumferential: f32 {b:e} against f64 {a:e}");
    assert!(
        a.abs() > 0.0 && (a - b).abs() <= 1e-3 * a.abs(),
        "{b:e} vs {a:e}"
    );
}
