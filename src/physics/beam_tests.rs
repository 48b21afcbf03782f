//! Checks of the co-rotational beam: closed-form force and tangent against the hyper-dual
//! oracle and central differences, kinked elements, rigid motions.

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
        let y: [f64; 3] = std::array::from_fn(|i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2]);
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

/// Random element states: stretched, bent, twisted, spun rigidly by hundreds of
/// radians, relative rotations up to `rel` rad about random axes.
fn random_states(count: usize, rel: f64, seed: u64) -> Vec<ElementState> {
    let mut seed = seed;
    let mut rnd = |a: f64| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        a * ((seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0)
    };
    let l = 9.0;
    (0..count)
        .map(|_| {
            let spin = rotation_exp(&[rnd(300.0), rnd(300.0), rnd(300.0)]);
            let mut rot = || {
                let axis = [rnd(1.0), rnd(1.0), rnd(1.0)];
                let a = rnd(rel) / norm(&axis);
                mat_mul(&rotation_exp(&axis.map(|x| x * a)), &spin)
            };
            let (r1, r2) = (rot(), rot());
            let chord: [f64; 3] = std::array::from_fn(|k| spin[k][0] * (l + rnd(0.05)) + rnd(0.3));
            let x1 = [rnd(1e3), rnd(1e3), rnd(1e3)];
            ElementState {
                x: [x1, std::array::from_fn(|k| x1[k] + chord[k])],
                triad: [r1, r2],
            }
        })
        .collect()
}

/// Largest difference between closed form and hyper-dual oracle over `states`,
/// relative to the largest entry of each (force, tangent).
fn closed_vs_oracle(states: &[ElementState]) -> (f64, f64) {
    let (mut wf, mut wk) = (0.0f64, 0.0f64);
    for s in states {
        let (f, k) = force_and_tangent(s, &section(), 9.0);
        let (f0, k0) = force_and_tangent_full(s, &section(), 9.0);
        let kscale = k0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let fscale = f0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for a in 0..12 {
            wf = wf.max((f[a] - f0[a]).abs() / fscale);
            for b in 0..12 {
                wk = wk.max((k[a][b] - k0[a][b]).abs() / kscale);
            }
        }
        assert_eq!(
            f,
            internal_force(s, &section(), 9.0),
            "force = tangent's value part"
        );
    }
    (wf, wk)
}

#[test]
fn half_the_hyper_dual_evaluations_give_the_whole_tangent() {
    let mut worst: f64 = 0.0;
    for s in random_states(40, 2.5, 12345) {
        let (f, k) =
            force_and_tangent_hyperdual(&s.x, &s.triad, &section(), 9.0, &[[0.0; 3]; 2], true);
        let (f0, k0) = force_and_tangent_full(&s, &section(), 9.0);
        let scale = k0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let fscale = f0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for a in 0..12 {
            worst = worst.max((f[a] - f0[a]).abs() / fscale);
            for b in 0..12 {
                worst = worst.max((k[a][b] - k0[a][b]).abs() / scale);
            }
        }
    }
    assert!(
        worst <= 1e-12,
        "78 hyper-dual evaluations vs 144: {worst:e}"
    );
}

#[test]
fn closed_form_equals_the_hyper_dual_oracle() {
    // Relative rotations up to 2.5 rad, then up to 3.1 (near π), then tiny ones (the
    // series branches of the log and of J⁻¹).
    for (rel, seed) in [(2.5, 12345), (3.1, 777), (1e-4, 99), (0.3, 5)] {
        let (wf, wk) = closed_vs_oracle(&random_states(60, rel, seed));
        eprintln!("closed form vs hyper-dual, relative rotations to {rel} rad: force {wf:.1e}, tangent {wk:.1e}");
        assert!(wf <= 1e-12 && wk <= 1e-12, "rel {rel}: {wf:e} {wk:e}");
    }
}

#[test]
fn the_kernels_nine_passes_equal_the_one_pass_form_bit_for_bit() {
    // shaders/beam.wgsl's form (one seed at a time, node 1's translation columns negated
    // from node 2's) against the CPU's DualN<9> pass, f64 and f32, near π and near 0.
    for (rel, seed) in [(2.5, 12345), (3.1, 777), (1e-4, 99)] {
        for s in random_states(30, rel, seed) {
            let form = Chord::Positions { length0: 9.0 };
            let k = ElementStiffness::of(&section(), 9.0);
            let one = force_and_tangent_closed(&s.x, &s.triad, &form, &k);
            let nine = force_and_tangent_by_direction(&s.x, &s.triad, &form, &k);
            assert_eq!(one, nine, "f64, rel {rel}");
            let x32 = s.x.map(|p| p.map(|v| v as f32));
            let t32 = s.triad.map(|m| m.map(|r| r.map(|v| v as f32)));
            let (f32_form, k32) = (form.map(|v| v as f32), k.map(|v| v as f32));
            assert_eq!(
                force_and_tangent_closed(&x32, &t32, &f32_form, &k32),
                force_and_tangent_by_direction(&x32, &t32, &f32_form, &k32),
                "f32, rel {rel}"
            );
        }
    }
}

#[test]
fn closed_form_in_f32_keeps_the_f64_digits() {
    // The same states as displacements from a base chord (the f32 engine's form):
    // the f32 force and tangent against the f64 ones, relative to their largest entry.
    let mut worst = (0.0f64, 0.0f64);
    for s in random_states(60, 1.0, 4242) {
        // Base: the chord rounded to f32 and its stretch in f64; w = the rest.
        let d: [f64; 3] = std::array::from_fn(|k| s.x[1][k] - s.x[0][k]);
        let c = d.map(|v| v as f32 as f64);
        let lc = norm(&c);
        let w2: [f64; 3] = std::array::from_fn(|k| d[k] - c[k]);
        let k64 = ElementStiffness::of(&section(), 9.0);
        let base = Chord::Base {
            chord: c,
            stretch: lc - 9.0,
            length: lc,
        };
        let (f, k) = force_and_tangent_closed(&[[0.0; 3], w2], &s.triad, &base, &k64);
        let (f0, k0) = force_and_tangent(&s, &section(), 9.0);
        let to32 = |v: f64| v as f32;
        let (f32_, k32) = force_and_tangent_closed(
            &[[0.0f32; 3], w2.map(to32)],
            &s.triad.map(|m| m.map(|r| r.map(to32))),
            &base.map(to32),
            &k64.map(to32),
        );
        let fs = f0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let ks = k0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        for a in 0..12 {
            // The base form in f64 is the same element.
            assert!((f[a] - f0[a]).abs() <= 1e-12 * fs);
            worst.0 = worst.0.max((f32_[a] as f64 - f0[a]).abs() / fs);
            for b in 0..12 {
                assert!((k[a][b] - k0[a][b]).abs() <= 1e-12 * ks);
                worst.1 = worst.1.max((k32[a][b] as f64 - k0[a][b]).abs() / ks);
            }
        }
    }
    eprintln!(
        "closed form f32 vs f64: force {:.1e}, tangent {:.1e}",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-3 && worst.1 < 1e-4, "{worst:?}");
}

#[test]
fn a_kinked_element_is_force_free_in_its_kinked_state() {
    // 1.5° at toolfaces 0, 70°, 200°: the geometry the rest rotations came from, then
    // spun and moved rigidly, carries no force; the straight element does.
    let l = 2.0;
    for toolface in [0.0f64, 70f64.to_radians(), 200f64.to_radians()] {
        let angle = 1.5f64.to_radians();
        let rest = kink_rest_rotation(angle, toolface, l);
        let k = ElementStiffness::of(&section(), l).with_rest(rest);
        let r = mat_mul(
            &rotation_exp(&[0.4, -0.9, 1.7]),
            &rotation_exp(&[250.0, 0.0, 0.0]),
        );
        let turned = rotation_exp(&[0.0, -angle * toolface.sin(), angle * toolface.cos()]);
        let x2 = [r[0][0] * l + 3.0, r[1][0] * l - 1.0, r[2][0] * l + 900.0];
        let x = [[3.0, -1.0, 900.0], x2];
        let triad = [r, mat_mul(&r, &turned)];
        let f = element_force(&x, &triad, &Chord::Positions { length0: l }, &k);
        let scale = k.bending * angle;
        let worst = f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            worst <= 1e-9 * scale,
            "toolface {toolface}: {worst:e} vs {scale:e}"
        );
        let straight = element_force(
            &x,
            &triad,
            &Chord::Positions { length0: l },
            &ElementStiffness::of(&section(), l),
        );
        let bent = straight.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(bent > scale, "a straight element there is bent: {bent:e}");
        // The rest rotation is the angle, split as the frame sees it, nearly all bending.
        let total: f64 = (0..3)
            .map(|c| (rest[1][c] - rest[0][c]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((total - angle).abs() < 1e-6 * angle, "{total} vs {angle}");
    }
}

#[test]
fn a_kinked_elements_force_and_tangent_are_the_energys_derivatives() {
    // Force and tangent of kinked elements against the hyper-dual oracle of the energy
    // in θ̄ − θ̄⁰, and the tangent against central differences of the force.
    let l = 9.0;
    let rest = kink_rest_rotation(2f64.to_radians(), 1.1, l);
    let k = ElementStiffness::of(&section(), l).with_rest(rest);
    let (mut wf, mut wk, mut wd) = (0.0f64, 0.0f64, 0.0f64);
    for s in random_states(20, 0.5, 31) {
        let form = Chord::Positions { length0: l };
        let (f, kk) = force_and_tangent_closed(&s.x, &s.triad, &form, &k);
        let (f0, k0) = force_and_tangent_hyperdual(&s.x, &s.triad, &section(), l, &rest, false);
        let fs = f0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let ks = k0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        for a in 0..12 {
            wf = wf.max((f[a] - f0[a]).abs() / fs);
            for b in 0..12 {
                wk = wk.max((kk[a][b] - k0[a][b]).abs() / ks);
            }
        }
        let h = 1e-6;
        for col in 0..12 {
            let mut dq = [0.0; 12];
            dq[col] = h;
            let p = apply(&s, &dq);
            dq[col] = -h;
            let m = apply(&s, &dq);
            let fp = element_force(&p.x, &p.triad, &form, &k);
            let fm = element_force(&m.x, &m.triad, &form, &k);
            for a in 0..12 {
                wd = wd.max(((fp[a] - fm[a]) / (2.0 * h) - kk[a][col]).abs() / ks);
            }
        }
    }
    eprintln!("kinked element: force {wf:.1e}, tangent {wk:.1e} vs hyper-dual; {wd:.1e} vs central differences");
    assert!(wf <= 1e-12 && wk <= 1e-12, "{wf:e} {wk:e}");
    assert!(wd <= 1e-6, "{wd:e}");
}

#[test]
fn the_written_out_tangent_is_the_dual_numbers_tangent() {
    // Straight and kinked, positions and base-chord forms, relative rotations near π,
    // through the series branches (1e-4, 0.3 rad) and between; f64 to 1e-12 of the
    // largest entry against the dual-number form and the hyper-dual oracle, f32 to its own
    // rounding; the force bit for bit the closed form's.
    let l = 9.0;
    let kinked = kink_rest_rotation(2f64.to_radians(), 1.1, l);
    let (mut wd, mut wo, mut w32) = (0.0f64, 0.0f64, 0.0f64);
    for (rel, seed) in [(2.5, 12345), (3.1, 777), (1e-4, 99), (0.3, 5), (0.6, 8)] {
        for (i, s) in random_states(40, rel, seed).iter().enumerate() {
            let rest = if i % 2 == 0 { [[0.0; 3]; 2] } else { kinked };
            let k = ElementStiffness::of(&section(), l).with_rest(rest);
            let d: [f64; 3] = std::array::from_fn(|c| s.x[1][c] - s.x[0][c]);
            let c = d.map(|v| v as f32 as f64);
            let lc = norm(&c);
            let base = Chord::Base {
                chord: c,
                stretch: lc - l,
                length: lc,
            };
            let w2: [f64; 3] = std::array::from_fn(|j| d[j] - c[j]);
            let forms = [
                (s.x, Chord::Positions { length0: l }),
                ([[0.0; 3], w2], base),
            ];
            let (_, k0) = force_and_tangent_hyperdual(&s.x, &s.triad, &section(), l, &rest, false);
            let ks = k0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            for (x, form) in forms {
                let (f, kk) = force_and_tangent_variation(&x, &s.triad, &form, &k);
                let (fd, kd) = force_and_tangent_closed(&x, &s.triad, &form, &k);
                assert_eq!(f, fd, "the force is the closed form's");
                assert_eq!(f, element_force(&x, &s.triad, &form, &k));
                for a in 0..12 {
                    for b in 0..12 {
                        wd = wd.max((kk[a][b] - kd[a][b]).abs() / ks);
                        wo = wo.max((kk[a][b] - k0[a][b]).abs() / ks);
                    }
                }
                let x32 = x.map(|p| p.map(|v| v as f32));
                let t32 = s.triad.map(|m| m.map(|r| r.map(|v| v as f32)));
                let (form32, k32) = (form.map(|v| v as f32), k.map(|v| v as f32));
                let (_, ka) = force_and_tangent_variation(&x32, &t32, &form32, &k32);
                let (_, kb) = force_and_tangent_closed(&x32, &t32, &form32, &k32);
                for a in 0..12 {
                    for b in 0..12 {
                        w32 = w32.max((ka[a][b] as f64 - kb[a][b] as f64).abs() / ks);
                    }
                }
            }
        }
    }
    eprintln!("written-out tangent: {wd:.1e} vs dual numbers, {wo:.1e} vs hyper-dual; f32 {w32:.1e} vs f32 dual numbers");
    assert!(wd <= 1e-12 && wo <= 1e-12, "{wd:e} {wo:e}");
    assert!(w32 <= 1e-4, "{w32:e}");
}

#[test]
fn the_jacobian_coefficients_slope_is_its_derivative() {
    // dc/d(θ²) against central differences of c on both sides of the series' edge.
    let c_of = |t: f64| rotation_log_and_jacobian(&rotation_exp(&[t, 0.0, 0.0])).1;
    for t in [1e-3, 0.05, 0.2, 0.31, 0.32, 0.5, 1.0, 2.0, 3.0] {
        let h = 1e-4 * f64::max(t, 0.1);
        let fd = (c_of(t + h) - c_of(t - h)) / (2.0 * h) / (2.0 * t);
        let slope = super::tangent::jacobian_coefficient_slope(t * t, c_of(t));
        assert!(
            (slope - fd).abs() <= 1e-6 * slope.abs(),
            "θ = {t}: {slope:e} vs {fd:e}"
        );
    }
}
