//! The beam kernel (`shaders/beam.wgsl`, twin `src/kernels/beam.rs`): GPU against the twin
//! on perturbed configurations of a real string (bent, twisted, stretched).
#![allow(clippy::needless_range_loop)]

mod common;

use holewall::gpu::beam::beam_gpu;
use holewall::kernels::beam::{base_chords, beam, tangent_slot, TANGENT_LEN};
use holewall::physics::beam::rotation_exp;
use holewall::solve::statics::StaticState;
use rand::{Rng, SeedableRng};

#[test]
fn gpu_beam_matches_the_twin() {
    let case = common::bed_case("1");
    let model = case.model;
    let n = model.nodes.len();
    let v = 8;
    let base = StaticState::on_low_side(&model).positions(&model);
    let mut rng = rand::rngs::StdRng::seed_from_u64(21);
    let mut x = vec![0.0; 3 * n * v];
    // The spun configuration without the small deformations: a base for the states.
    let mut spun = vec![0.0; 3 * n * v];
    let mut rot = vec![0.0; 9 * n * v];
    for j in 0..v {
        // A rigid spin of up to 50 rad about the vertical (large rotation) on top of small
        // deformations.
        let spin = rotation_exp(&[0.0, 0.0, rng.random_range(-50.0..50.0)]);
        for i in 0..n {
            let p: [f64; 3] = std::array::from_fn(|k| base[i][k] + rng.random_range(-3e-3..3e-3));
            let th: [f64; 3] = std::array::from_fn(|_| rng.random_range(-0.02..0.02));
            let r = rotation_exp(&th);
            for a in 0..3 {
                x[(3 * i + a) * v + j] = (0..3).map(|b| spin[a][b] * p[b]).sum();
                spun[(3 * i + a) * v + j] = (0..3).map(|b| spin[a][b] * base[i][b]).sum();
                for c in 0..3 {
                    rot[(9 * i + 3 * a + c) * v + j] = (0..3).map(|m| spin[a][m] * r[m][c]).sum();
                }
            }
        }
    }
    // States are displacements from the reference positions.
    for j in 0..v {
        for i in 0..n {
            for a in 0..3 {
                x[(3 * i + a) * v + j] -= model.nodes[i].position[a];
                spun[(3 * i + a) * v + j] -= model.nodes[i].position[a];
            }
        }
    }
    let reference = base_chords(&model, &vec![0.0; 3 * n * v], v);
    let (f_exact, k_exact) = beam(&model, v, &x, &rot, &reference, &[], true);
    // The same configurations as displacements `w` from the spun base (millimetres).
    let w: Vec<f64> = x.iter().zip(&spun).map(|(a, b)| a - b).collect();
    let based = base_chords(&model, &spun, v);
    let ne = model.elements.len();
    // Normwise relative difference per (element, variant), worst over all.
    let worst = |f: &[f64], k: &[f64], f_twin: &[f64], k_twin: &[f64]| {
        let mut w: (f64, f64) = (0.0, 0.0);
        for e in 0..ne {
            for j in 0..v {
                let (mut df, mut nf, mut dk, mut nk) = (0.0, 0.0, 0.0, 0.0);
                for a in 0..12 {
                    let i = (12 * e + a) * v + j;
                    df += (f[i] - f_twin[i]).powi(2);
                    nf += f_twin[i].powi(2);
                }
                for b in 0..TANGENT_LEN {
                    let i = (TANGENT_LEN * e + b) * v + j;
                    dk += (k[i] - k_twin[i]).powi(2);
                    nk += k_twin[i].powi(2);
                }
                w.0 = w.0.max((df / nf.max(1e-300)).sqrt());
                w.1 = w.1.max((dk / nk).sqrt());
            }
        }
        w
    };
    // The twin from the base: the same element forces (the chord formed in another order).
    let (f_based, k_based) = beam(&model, v, &w, &rot, &based, &[], true);
    let (bf, bk) = worst(&f_based, &k_based, &f_exact, &k_exact);
    eprintln!("twin from the spun base vs from the reference: force {bf:.2e}, tangent {bk:.2e}");
    assert!(bf <= 1e-8 && bk <= 1e-12, "force {bf:e}, tangent {bk:e}");
    // The force alone (line-search trials): the same numbers as the force of the full run.
    let (f_only, k_none) = beam(&model, v, &x, &rot, &reference, &[], false);
    assert_eq!(
        f_only, f_exact,
        "twin force-only = the tangent run's force, bit for bit"
    );
    assert!(k_none.is_empty(), "a force-only run forms no tangent");
    let Some(ctx) = common::gpu() else { return };
    let close = |a: &[f64], b: &[f64]| {
        let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            / scale
    };
    if ctx.has_f64 {
        let (f_full, _) = beam_gpu(ctx, &model, v, &w, &rot, &based, &[], true).unwrap();
        let (f_force, k_empty) = beam_gpu(ctx, &model, v, &w, &rot, &based, &[], false).unwrap();
        let d = close(&f_force, &f_full);
        eprintln!("GPU f64 force-only vs full kernel's force: {d:.1e}");
        assert!(k_empty.is_empty() && d <= 1e-14, "{d:e}");
    }
    {
        let (w32, r32) = (
            w.iter().map(|&a| a as f32).collect::<Vec<f32>>(),
            rot.iter().map(|&a| a as f32).collect::<Vec<f32>>(),
        );
        let up = |a: &[f32]| a.iter().map(|&b| b as f64).collect::<Vec<f64>>();
        let (f_full, _) = beam_gpu(ctx, &model, v, &w32, &r32, &based, &[], true).unwrap();
        let (f_force, _) = beam_gpu(ctx, &model, v, &w32, &r32, &based, &[], false).unwrap();
        let d = close(&up(&f_force), &up(&f_full));
        eprintln!("GPU f32 force-only vs full kernel's force: {d:.1e}");
        assert!(d <= 1e-6, "{d:e}");
    }
    if ctx.has_f64 {
        for (label, u, chords, f_twin, k_twin) in [
            ("reference", &x, &reference, &f_exact, &k_exact),
            ("base", &w, &based, &f_based, &k_based),
        ] {
            let (f, k) = beam_gpu(ctx, &model, v, u, &rot, chords, &[], true).unwrap();
            let (wf, wk) = worst(&f, &k, f_twin, k_twin);
            eprintln!("GPU f64 vs twin ({label}): force {wf:.2e}, tangent {wk:.2e}");
            assert!(wf <= 1e-9 && wk <= 1e-12, "force {wf:e}, tangent {wk:e}");
        }
    }
    let to32 = |a: &[f64]| a.iter().map(|&b| b as f32).collect::<Vec<f32>>();
    let up = |a: &[f32]| a.iter().map(|&b| b as f64).collect::<Vec<f64>>();
    let r32 = to32(&rot);
    // Two parts: rounding the inputs to f32, and the kernel's f32 arithmetic (against the
    // twin fed the same rounded inputs). From the reference the rigid spins move nodes by
    // up to 60 m, whose displacements carry 4e-6 m against deformations of a few mm: the
    // internal force, a difference, loses ≈ 3 digits. From the spun base the states are the
    // millimetres and the chords come in f64: the rounding of the inputs must drop by
    // orders of magnitude.
    let mut errors = Vec::new();
    for (label, u, chords) in [("reference", &x, &reference), ("base", &w, &based)] {
        let u32 = to32(u);
        // The chords go in f64 to both (the kernel takes them in f32 with the stretch
        // formed in f64: part of its arithmetic here).
        let (f, k) = beam_gpu(ctx, &model, v, &u32, &r32, chords, &[], true).unwrap();
        let (f_rounded, k_rounded) = beam(&model, v, &up(&u32), &up(&r32), chords, &[], true);
        let (input_f, input_k) = worst(&f_rounded, &k_rounded, &f_exact, &k_exact);
        let (kernel_f, kernel_k) = worst(&up(&f), &up(&k), &f_rounded, &k_rounded);
        let (total_f, total_k) = worst(&up(&f), &up(&k), &f_exact, &k_exact);
        eprintln!(
            "f32 from the {label}: input rounding → force {input_f:.2e}, tangent {input_k:.2e}; kernel arithmetic → force {kernel_f:.2e}, tangent {kernel_k:.2e}; in all → force {total_f:.2e}, tangent {total_k:.2e}"
        );
        assert!(kernel_k <= 1e-4, "f32 tangent {kernel_k:e}");
        assert!(
            kernel_f <= 4.0 * input_f.max(1e-4),
            "f32 force {kernel_f:e}"
        );
        errors.push((input_f, total_f));
    }
    let (from_reference, from_base) = (errors[0], errors[1]);
    assert!(
        from_base.0 <= 1e-2 * from_reference.0 && from_base.1 <= 1e-2 * from_reference.1,
        "f32 force errors from the base {from_base:?} (input rounding, in all) against from the reference {from_reference:?}"
    );
}

/// Kinks (bent subs) in the beam kernel: each element's unstrained rotations per variant
/// (`rest`, the kernel built `KINK`) — the twin against the physics (the model's kinked
/// element, `Model::element_stiffness`), and the GPU against the twin in f64 and f32, with
/// the kinks at other angles per variant (the static engine's load factors).
#[test]
fn gpu_beam_with_kinks_matches_the_twin() {
    use holewall::kernels::beam::rest_table;
    let case = common::bed_case("1");
    let mut model = case.model;
    let n = model.nodes.len();
    model.bends = vec![
        holewall::model::Bend {
            node: n - 3,
            angle: 1.5f64.to_radians(),
            toolface: 0.4,
        },
        holewall::model::Bend {
            node: n - 8,
            angle: 0.7f64.to_radians(),
            toolface: -2.0,
        },
    ];
    let v = 6;
    let models = vec![model.clone(); v];
    let scales = [1.0, 0.0, 0.25, 0.5, 0.75, 1.0];
    let rest = rest_table(&models, &|j| scales[j]);
    assert_eq!(rest.len(), 6 * (n - 1) * v);
    assert!(rest_table(&[common::bed_case("1").model], &|_| 1.0).is_empty());
    let base = StaticState::on_low_side(&model);
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let mut x = vec![0.0; 3 * n * v];
    let mut rot = vec![0.0; 9 * n * v];
    for j in 0..v {
        for i in 0..n {
            let th: [f64; 3] = std::array::from_fn(|_| rng.random_range(-0.02..0.02));
            let r = rotation_exp(&th);
            for a in 0..3 {
                x[(3 * i + a) * v + j] = base.u[i][a] + rng.random_range(-3e-3..3e-3);
                for c in 0..3 {
                    rot[(9 * i + 3 * a + c) * v + j] = r[a][c];
                }
            }
        }
    }
    let chords = base_chords(&model, &vec![0.0; 3 * n * v], v);
    let (f, k) = beam(&model, v, &x, &rot, &chords, &rest, true);
    // Variant 0 (kinks in full) element by element against the physics.
    let ne = n - 1;
    let (mut worst_phys, mut worst_tangent): (f64, f64) = (0.0, 0.0);
    for e in 0..ne {
        let pos = |i: usize| -> [f64; 3] {
            std::array::from_fn(|a| model.nodes[i].position[a] + x[(3 * i + a) * v])
        };
        let triad = |i: usize| -> holewall::physics::beam::Mat3<f64> {
            let f0 = &model.nodes[i].frame0;
            std::array::from_fn(|r| {
                std::array::from_fn(|c| {
                    (0..3)
                        .map(|m| rot[(9 * i + 3 * r + m) * v] * f0[m][c])
                        .sum()
                })
            })
        };
        let (fp, kp) = holewall::physics::beam::force_and_tangent_closed(
            &[pos(e), pos(e + 1)],
            &[triad(e), triad(e + 1)],
            &holewall::physics::beam::Chord::Positions {
                length0: model.elements[e].length0,
            },
            &model.element_stiffness(e),
        );
        let scale = fp.iter().fold(1.0f64, |m, y| m.max(y.abs()));
        for a in 0..12 {
            worst_phys = worst_phys.max((f[(12 * e + a) * v] - fp[a]).abs() / scale);
        }
        // The tangent's 144 entries from the kernel's 81 (`tangent_slot`).
        let k_scale = kp.iter().flatten().fold(0.0f64, |m, y| m.max(y.abs()));
        for a in 0..12 {
            for b in 0..12 {
                let (slot, negated) = tangent_slot(a, b);
                let held = k[(TANGENT_LEN * e + slot) * v];
                let entry = if negated { -held } else { held };
                worst_tangent = worst_tangent.max((entry - kp[a][b]).abs() / k_scale);
            }
        }
    }
    eprintln!(
        "kinked twin vs physics (variant 0): force {worst_phys:.1e}, tangent {worst_tangent:.1e}"
    );
    assert!(worst_phys <= 1e-9, "{worst_phys:e}");
    assert!(worst_tangent <= 1e-9, "{worst_tangent:e}");
    let Some(ctx) = common::gpu() else { return };
    let rel = |a: &[f64], b: &[f64]| {
        let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            / scale
    };
    if ctx.has_f64 {
        let (fg, kg) = beam_gpu(ctx, &model, v, &x, &rot, &chords, &rest, true).unwrap();
        let (df, dk) = (rel(&fg, &f), rel(&kg, &k));
        eprintln!("kinked GPU f64 vs twin: force {df:.1e}, tangent {dk:.1e}");
        assert!(df <= 1e-9 && dk <= 1e-12, "{df:e} {dk:e}");
        let (ff, ke) = beam_gpu(ctx, &model, v, &x, &rot, &chords, &rest, false).unwrap();
        assert!(ke.is_empty() && rel(&ff, &fg) <= 1e-14);
    }
    let to32 = |a: &[f64]| a.iter().map(|&b| b as f32).collect::<Vec<f32>>();
    let up = |a: &[f32]| a.iter().map(|&b| b as f64).collect::<Vec<f64>>();
    let (x32, r32) = (to32(&x), to32(&rot));
    let (fg, kg) = beam_gpu(ctx, &model, v, &x32, &r32, &chords, &rest, true).unwrap();
    let (f_rounded, k_rounded) = beam(
        &model,
        v,
        &up(&x32),
        &up(&r32),
        &chords,
        &up(&to32(&rest)),
        true,
    );
    let (df, dk) = (rel(&up(&fg), &f_rounded), rel(&up(&kg), &k_rounded));
    eprintln!(
        "kinked GPU f32 vs twin on the same rounded inputs: force {df:.1e}, tangent {dk:.1e}"
    );
    assert!(df <= 1e-3 && dk <= 1e-4, "{df:e} {dk:e}");
}
