//! The assembly kernel (`shaders/assemble.wgsl`, twin `src/kernels/assemble.rs`) gathers
//! exactly what the static solver scatters, constraints included; the GPU equals the twin.
#![allow(clippy::needless_range_loop)]

mod common;

use common::runners::assemble_residual_gpu;
use holewall::gpu::assemble::assemble_gpu;
use holewall::kernels::assemble::{assemble, assemble_residual, AssemblyInputs, NO_SITE};
use holewall::kernels::beam::{tangent_slot, tangent_source, TANGENT_LEN};
use holewall::kernels::contact::{response_fields, OUTPUT_LEN};
use holewall::physics::beam::{force_and_tangent, ElementState};
use holewall::physics::rotation::{mat_mul, rotation_exp};
use holewall::solve::statics::{
    assembled, constrained_system, constraint_tables, external_loads, site_response, StaticState,
};
use rand::{Rng, SeedableRng};

/// Normwise (2-norm) relative difference of `x` from `y`.
fn rel(x: &[f64], y: &[f64]) -> f64 {
    let num: f64 = x
        .iter()
        .zip(y)
        .map(|(p, q)| (p - q).powi(2))
        .sum::<f64>()
        .sqrt();
    let den: f64 = y.iter().map(|q| q * q).sum::<f64>().sqrt();
    num / den
}

/// Largest entry-wise difference over max(|y|, 1): the f32 residual's measure.
fn rel_floor1(x: &[f64], y: &[f64]) -> f64 {
    x.iter()
        .zip(y)
        .fold(0.0f64, |m, (g, t)| m.max((g - t).abs() / t.abs().max(1.0)))
}

/// The 60 m test bed of `tests/extreme.rs` (contact at every node) at V perturbed states.
fn inputs(
    v: usize,
    constrained: bool,
) -> (
    holewall::model::Model,
    Vec<StaticState>,
    AssemblyInputs<f64>,
) {
    let case = common::bed_case("1.5");
    let model = case.model;
    let base = StaticState::on_low_side(&model);
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let states: Vec<StaticState> = (0..v)
        .map(|_| {
            let mut s = base.clone();
            for x in s.u.iter_mut().skip(1) {
                for c in x.iter_mut() {
                    *c += rng.random_range(-2e-3..2e-3);
                }
            }
            s
        })
        .collect();
    let n = model.nodes.len();
    let e = n - 1;
    let sites = model.sites.len();
    let mut a = AssemblyInputs {
        num_variants: v,
        num_nodes: n,
        num_sites: sites,
        elem_force: vec![0.0; 12 * e * v],
        elem_tangent: vec![0.0; TANGENT_LEN * e * v],
        contact: vec![0.0; OUTPUT_LEN * sites * v],
        contact_flag: vec![0; sites * v],
        node_site: vec![NO_SITE; n * v],
        f_ext: vec![0.0; 6 * n * v],
        basis: (0..n)
            .flat_map(|_| [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
            .collect(),
        fixed: vec![0; n],
        dynamic: None,
        shift: None,
    };
    if constrained {
        let (basis, fixed) = constraint_tables(&model);
        a.basis = basis;
        a.fixed = fixed;
        assert!(
            a.fixed[0] != 0 && a.fixed[n - 1] != 0,
            "top and bit are held"
        );
    }
    let f_ext = external_loads(&model);
    let lambda = 0.7;
    for (j, s) in states.iter().enumerate() {
        for (i, el) in model.elements.iter().enumerate() {
            let es = ElementState {
                x: [s.position(&model, i), s.position(&model, i + 1)],
                triad: [
                    mat_mul(&s.rot[i], &model.nodes[i].frame0),
                    mat_mul(&s.rot[i + 1], &model.nodes[i + 1].frame0),
                ],
            };
            let (f, k) = force_and_tangent(&es, &el.section, el.length0);
            for r in 0..12 {
                a.elem_force[(12 * i + r) * v + j] = f[r];
            }
            // The beam kernel's 81 entries hold the solver's 144 exactly: the others are
            // their negations, bit for bit.
            for r in 0..12 {
                for c in 0..12 {
                    let (slot, negated) = tangent_slot(r, c);
                    let (sr, sc) = tangent_source(slot / 9, slot % 9);
                    let held = if negated { -k[sr][sc] } else { k[sr][sc] };
                    assert_eq!(held.to_bits(), k[r][c].to_bits(), "K[{r}][{c}]");
                    a.elem_tangent[(TANGENT_LEN * i + slot) * v + j] = k[sr][sc];
                }
            }
        }
        for (k, site) in model.sites.iter().enumerate() {
            let out = site_response(&model, s, site);
            let p = k * v + j;
            a.contact_flag[p] = out.contact as u32;
            for (field, x) in response_fields(&out).into_iter().enumerate() {
                a.contact[field * sites * v + p] = x;
            }
            a.node_site[site.node * v + j] = k as u32;
        }
        for d in 0..6 * n {
            a.f_ext[d * v + j] = lambda * f_ext[d];
        }
    }
    (model, states, a)
}

#[test]
fn twin_gathers_what_the_solver_scatters_and_the_gpu_agrees() {
    let v = 6;
    // The constrained system against statics::constrain; the unconstrained one first.
    let (model, states, a0) = inputs(v, false);
    let twin0 = assemble(&a0);
    for (j, s) in states.iter().enumerate() {
        let (r, k) = assembled(&model, s, 0.7);
        for i in 0..model.nodes.len() {
            for row in 0..6 {
                assert_eq!(twin0.rhs[(6 * i + row) * v + j], r[6 * i + row]);
                for c in 0..6 {
                    assert_eq!(
                        twin0.diag[(36 * i + 6 * row + c) * v + j],
                        k.diag[i][row][c]
                    );
                }
            }
        }
    }
    let (model, states, a) = inputs(v, true);
    let twin = assemble(&a);
    let in_contact = a.contact_flag.iter().filter(|&&f| f != 0).count();
    assert!(in_contact > 10, "the bed must have contacts: {in_contact}");
    for (j, s) in states.iter().enumerate() {
        let (r, k) = constrained_system(&model, s, 0.7);
        let n = model.nodes.len();
        for i in 0..n {
            for row in 0..6 {
                assert_eq!(
                    twin.rhs[(6 * i + row) * v + j],
                    r[6 * i + row],
                    "rhs {i} {row}"
                );
                for c in 0..6 {
                    assert_eq!(twin.diag[(36 * i + 6 * row + c) * v + j], k.diag[i][row][c]);
                    if i + 1 < n {
                        assert_eq!(
                            twin.upper[(36 * i + 6 * row + c) * v + j],
                            k.upper[i][row][c]
                        );
                        assert_eq!(
                            twin.lower[(36 * i + 6 * row + c) * v + j],
                            k.lower[i][row][c]
                        );
                    }
                }
            }
        }
    }
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let gpu = assemble_gpu(ctx, &a).unwrap();
        let worst = [
            rel(&gpu.rhs, &twin.rhs),
            rel(&gpu.diag, &twin.diag),
            rel(&gpu.upper, &twin.upper),
            rel(&gpu.lower, &twin.lower),
        ];
        eprintln!("GPU f64 vs twin (rhs, diag, upper, lower): {worst:?}");
        assert!(worst.iter().all(|w| *w <= 1e-15));
    }
    // f32: the inputs rounded to f32, summed in f32; against the f64 twin.
    let a32 = a.map_static(|x| x as f32);
    let gpu32 = assemble_gpu(ctx, &a32).unwrap();
    let twin32 = assemble(&a32);
    let up = |x: &[f32]| x.iter().map(|&y| y as f64).collect::<Vec<f64>>();
    // The same sums in the same order: the same bits (to rounding where the driver fuses
    // multiply-adds; the bound against the f64 twin below holds either way).
    if !common::fuses(ctx) {
        assert_eq!(
            gpu32.diag, twin32.diag,
            "f32 GPU = f32 twin (same sums in the same order)"
        );
    }
    let e_diag = rel(&up(&gpu32.diag), &twin.diag);
    let e_rhs = rel(&up(&gpu32.rhs), &twin.rhs);
    eprintln!("f32 vs f64 twin: diag {e_diag:.2e}, rhs {e_rhs:.2e} (u32 = 6.0e-8)");
    assert!(e_diag <= 4.0 * f32::EPSILON as f64);
}

/// The line-search trials' assembly (the kernel built `FORCE_ONLY`, twin
/// `assemble_residual`) gives the full assembly's residual, constraints included, without
/// reading the element tangents: the twin to the bit, the GPU to the bit of the GPU's full
/// assembly (the same sums in the same order), f64 and f32.
#[test]
fn the_residual_only_assembly_gives_the_full_residual() {
    let v = 5;
    let (_, _, a) = inputs(v, true);
    assert!(a.fixed.iter().any(|&f| f != 0), "the bed must fix DOFs");
    let full = assemble(&a);
    let mut bare = a.clone();
    bare.elem_tangent = Vec::new();
    let twin = assemble_residual(&bare);
    assert_eq!(twin, full.rhs);
    assert!(twin.iter().filter(|r| **r != 0.0).count() > twin.len() / 2);
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let gpu_full = assemble_gpu(ctx, &a).unwrap();
        let gpu = assemble_residual_gpu(ctx, &bare).unwrap();
        assert_eq!(
            gpu, gpu_full.rhs,
            "f64: residual-only = full assembly's residual"
        );
    }
    let a32 = a.map_static(|x| x as f32);
    let gpu_full = assemble_gpu(ctx, &a32).unwrap();
    let mut bare32 = a32.clone();
    bare32.elem_tangent = Vec::new();
    assert_eq!(
        assemble_residual_gpu(ctx, &bare32).unwrap(),
        gpu_full.rhs,
        "f32: residual-only = full assembly's residual"
    );
    assert_eq!(assemble_residual(&bare32), assemble(&a32).rhs);
}

/// A relaxation's proximal shift (the kernel built `SHIFT`, twin `ShiftInputs`): the twin
/// adds `s_v (u − a)` to each node's translations' residual and `s_v` to their diagonal,
/// and, where the rotations are shifted too, `s_r θ` to its moments' residual for
/// `R = exp(θ) R_a` and `s_r` to their diagonal, before the constraints (without
/// constraints: exactly that difference from the plain assembly, the log's to its
/// rounding; a variant with `s_v = 0` unchanged to the bit); the GPU, full and
/// residual-only, f64 and f32, agrees with the twin.
#[test]
fn the_proximal_shift_adds_its_spring_before_the_constraints_and_the_gpu_agrees() {
    use holewall::kernels::assemble::ShiftInputs;
    use rand::{Rng, SeedableRng};
    let v = 5;
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let with_shift = |a: &AssemblyInputs<f64>, rng: &mut rand::rngs::StdRng| {
        let n = a.num_nodes;
        let mut b = a.clone();
        b.shift = Some(ShiftInputs {
            // Variant 2 without a shift.
            shift: (0..v)
                .map(|j| {
                    if j == 2 {
                        0.0
                    } else {
                        rng.random_range(1e3..1e7)
                    }
                })
                .collect(),
            anchor: (0..3 * n * v)
                .map(|_| rng.random_range(-0.1..0.1))
                .collect(),
            x: (0..3 * n * v)
                .map(|_| rng.random_range(-0.1..0.1))
                .collect(),
            // The rotations shifted too in variants 0 and 3 (a relaxation past its
            // ceiling): R = exp(θ) R_a, θ kept to check the moments by.
            rot_shift: (0..v)
                .map(|j| {
                    if j % 3 == 0 {
                        rng.random_range(1e1..1e5)
                    } else {
                        0.0
                    }
                })
                .collect(),
            anchor_rot: vec![0.0; 9 * n * v],
            rot: vec![0.0; 9 * n * v],
        });
        let sh = b.shift.as_mut().unwrap();
        let mut thetas = vec![[0.0; 3]; n * v];
        for i in 0..n {
            for j in 0..v {
                let mut draw = |r: f64| std::array::from_fn(|_| rng.random_range(-r..r));
                let theta_a = draw(1.0);
                let theta = draw(0.05);
                let anchor = rotation_exp(&theta_a);
                let rot = mat_mul(&rotation_exp(&theta), &anchor);
                for a in 0..3 {
                    for k in 0..3 {
                        sh.anchor_rot[(9 * i + 3 * a + k) * v + j] = anchor[a][k];
                        sh.rot[(9 * i + 3 * a + k) * v + j] = rot[a][k];
                    }
                }
                thetas[i * v + j] = theta;
            }
        }
        (b, thetas)
    };
    let (_, _, a0) = inputs(v, false);
    let (s0, thetas) = with_shift(&a0, &mut rng);
    let (plain, shifted) = (assemble(&a0), assemble(&s0));
    let sh = s0.shift.as_ref().unwrap();
    let n = a0.num_nodes;
    for i in 0..n {
        for j in 0..v {
            for k in 0..6 {
                let at = (6 * i + k) * v + j;
                if k < 3 {
                    let x = (3 * i + k) * v + j;
                    let want = plain.rhs[at] + sh.shift[j] * (sh.x[x] - sh.anchor[x]);
                    assert_eq!(shifted.rhs[at], want, "rhs node {i} variant {j} dof {k}");
                } else {
                    // s_r log(R R_aᵀ) = s_r θ, to the log's rounding.
                    let add = sh.rot_shift[j] * thetas[i * v + j][k - 3];
                    let want = plain.rhs[at] + add;
                    let err = (shifted.rhs[at] - want).abs();
                    assert!(
                        err <= 1e-13 * want.abs().max(add.abs()).max(1.0),
                        "moment rhs node {i} variant {j} dof {k}: {} against {want}",
                        shifted.rhs[at]
                    );
                    if sh.rot_shift[j] == 0.0 {
                        assert_eq!(shifted.rhs[at], plain.rhs[at]);
                    }
                }
                for c in 0..6 {
                    let d = (36 * i + 6 * k + c) * v + j;
                    let add = match (k == c, k < 3) {
                        (true, true) => sh.shift[j],
                        (true, false) => sh.rot_shift[j],
                        _ => 0.0,
                    };
                    assert_eq!(shifted.diag[d], plain.diag[d] + add);
                }
            }
        }
    }
    assert_eq!(shifted.upper, plain.upper);
    // With the constraints: the GPU against the twin.
    let (_, _, a) = inputs(v, true);
    let (s, _) = with_shift(&a, &mut rng);
    let twin = assemble(&s);
    let mut bare = s.clone();
    bare.elem_tangent = Vec::new();
    assert_eq!(assemble_residual(&bare), twin.rhs);
    let plain = assemble(&a);
    for i in 0..n {
        for k in 0..6 {
            let at = (6 * i + k) * v + 2;
            assert_eq!(
                twin.rhs[at], plain.rhs[at],
                "an unshifted variant is unchanged"
            );
        }
    }
    let Some(ctx) = common::gpu() else { return };
    // The moments of the variants whose rotations are shifted hold `s_r log(R R_aᵀ)`: the
    // kernel's atan (in f64 a series: Vulkan has none) against the twin's libm atan2. Those
    // rows agree to the sum's rounding (`sum_ulps` of the entry) plus `s_r |δθ|`, δθ the
    // logs' difference, measured here (`excess`, rad); every other row as before. The rows
    // apart are zeroed in copies for the rest of the check.
    let rot_shift = s.shift.as_ref().unwrap().rot_shift.clone();
    let apart = |g: &[f64], t: &[f64], sum_ulps: f64| {
        let (mut g, mut t) = (g.to_vec(), t.to_vec());
        let mut excess = 0.0f64;
        for at in 0..g.len() {
            let (row, j) = (at / v, at % v);
            if row % 6 >= 3 && rot_shift[j] != 0.0 {
                let d = (g[at] - t[at]).abs() - sum_ulps * t[at].abs().max(1.0);
                excess = excess.max(d.max(0.0) / rot_shift[j]);
                (g[at], t[at]) = (0.0, 0.0);
            }
        }
        (g, t, excess)
    };
    if ctx.has_f64 {
        let gpu = assemble_gpu(ctx, &s).unwrap();
        let (g, t, excess) = apart(&gpu.rhs, &twin.rhs, f64::EPSILON);
        eprintln!("f64 GPU vs twin, rotation-shifted moments: |δθ| ≤ {excess:.1e} rad");
        assert!(excess <= 1e-15, "f64 log {excess:e} rad");
        common::assert_same(ctx, &g, &t, rel, 1e-15, "f64 GPU rhs = twin");
        common::assert_same(
            ctx,
            &gpu.diag,
            &twin.diag,
            rel,
            1e-15,
            "f64 GPU diag = twin",
        );
        let residual = assemble_residual_gpu(ctx, &bare).unwrap();
        let (g, t, excess) = apart(&residual, &twin.rhs, f64::EPSILON);
        assert!(excess <= 1e-15, "f64 residual-only log {excess:e} rad");
        common::assert_same(ctx, &g, &t, rel, 1e-15, "f64 GPU residual = twin");
    }
    let s32 = s.map_static(|x| x as f32);
    let gpu32 = assemble_gpu(ctx, &s32).unwrap();
    let twin32 = assemble(&s32);
    // The f32 bound of the rhs check below, where the driver fuses multiply-adds.
    let u8 = 8.0 * f32::EPSILON as f64;
    common::assert_same(
        ctx,
        &gpu32.diag,
        &twin32.diag,
        rel_floor1,
        u8,
        "f32 GPU diag = f32 twin",
    );
    let mut bare32 = s32.clone();
    bare32.elem_tangent = Vec::new();
    common::assert_same(
        ctx,
        &assemble_residual_gpu(ctx, &bare32).unwrap(),
        &gpu32.rhs,
        rel_floor1,
        u8,
        "f32: residual-only = full",
    );
    let up = |x: &[f32]| x.iter().map(|&y| y as f64).collect::<Vec<f64>>();
    let (g32, t32, excess) = apart(&up(&gpu32.rhs), &up(&twin32.rhs), u8);
    eprintln!("f32 GPU vs f32 twin, rotation-shifted moments: |δθ| ≤ {excess:.1e} rad");
    // Vulkan holds an f32 atan to 4096 ulp (the SPIR-V environment's precision table), of
    // an angle here below √3 · 0.05 < 0.0867 rad, whose ulp is 2⁻²⁷: 3.1e-5 rad (lavapipe,
    // measured: 8.7e-7).
    assert!(excess <= 4096.0 * 2f64.powi(-27), "f32 log {excess:e} rad");
    let worst = rel_floor1(&g32, &t32);
    eprintln!("f32 GPU vs f32 twin, shifted rhs: {worst:.2e}");
    assert!(worst <= u8, "f32 rhs {worst:e}");
}
