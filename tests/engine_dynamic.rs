//! The dynamic ensemble through the kernels against the CPU integrator
//! (`solve::dynamics::Dynamics`), step for step; the GPU path against the twin path; the
//! dynamic kernels against their twins.
#![allow(clippy::needless_range_loop)]

mod common;

/// Starts at rest (no initial kick) from static equilibria, as the engine takes them.
fn at_rest(
    starts: &[holewall::solve::statics::StaticState],
) -> Vec<holewall::engine::dynamic::DynamicStart> {
    starts.iter().map(|q| (q.clone(), None)).collect()
}

use holewall::engine::dynamic::{run_dynamic_ensemble, DynamicStatus};
use holewall::engine::TwinPath;
use holewall::ensemble::{apply, variants_from_csv_text};
use holewall::gpu::GpuPath;
use holewall::kernels::dynamics::DynamicBatch;
use holewall::model::Model;
use holewall::solve::dynamics::Dynamics;
use holewall::solve::statics::{solve_static, StaticOptions, StaticState};

/// Per step and variant: displacements (3n) and velocities (6n), from the CPU integrator.
fn cpu_runs(
    models: &[Model],
    starts: &[StaticState],
    density: &[f64],
    options: &holewall::solve::dynamics::DynamicOptions,
    t_end: f64,
) -> Vec<Vec<(Vec<f64>, Vec<f64>)>> {
    models
        .iter()
        .zip(starts)
        .map(|(m, q)| {
            let mut d = Dynamics::new(m, *options, &|e| density[e]);
            let mut s = d.initial_state(q.clone()).unwrap();
            let mut steps = Vec::new();
            d.run(&mut s, t_end, &mut |_, st| {
                let u: Vec<f64> = (0..m.nodes.len())
                    .flat_map(|i| (0..3).map(move |k| (i, k)))
                    .map(|(i, k)| st.q.u[i][k])
                    .collect();
                steps.push((u, st.v.clone()));
            })
            .unwrap();
            assert!(d.log.is_empty(), "the CPU run cut its step: {:?}", d.log);
            steps
        })
        .collect()
}

/// Per step and variant, from an engine run's observations.
fn engine_steps(
    steps: &[(f64, DynamicBatch<f64>)],
    v: usize,
    n: usize,
) -> Vec<Vec<(Vec<f64>, Vec<f64>)>> {
    (0..v)
        .map(|j| {
            steps
                .iter()
                .map(|(_, b)| {
                    (
                        (0..3 * n).map(|k| b.u[k * v + j]).collect(),
                        (0..6 * n).map(|k| b.vel[k * v + j]).collect(),
                    )
                })
                .collect()
        })
        .collect()
}

/// Largest difference of displacements and of velocities, each relative to the largest
/// value of the reference over the run.
fn trajectory_error(
    a: &[Vec<(Vec<f64>, Vec<f64>)>],
    b: &[Vec<(Vec<f64>, Vec<f64>)>],
) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for (ra, rb) in a.iter().zip(b) {
        assert_eq!(ra.len(), rb.len(), "step counts differ");
        let scale_u = rb
            .iter()
            .flat_map(|s| &s.0)
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let scale_v = rb
            .iter()
            .flat_map(|s| &s.1)
            .fold(0.0f64, |m, x| m.max(x.abs()));
        for (sa, sb) in ra.iter().zip(rb) {
            for (x, y) in sa.0.iter().zip(&sb.0) {
                worst.0 = worst.0.max((x - y).abs() / scale_u);
            }
            for (x, y) in sa.1.iter().zip(&sb.1) {
                worst.1 = worst.1.max((x - y).abs() / scale_v);
            }
        }
    }
    worst
}

fn bed_variants(csv: &str) -> (holewall::case::Case, Vec<Model>, Vec<StaticState>) {
    let case = common::bed_case("1");
    let (models, starts) = with_starts(&case, csv);
    (case, models, starts)
}

/// The variants of `csv` applied to `case`, each with its static equilibrium (the undeformed
/// string where that fails).
fn with_starts(case: &holewall::case::Case, csv: &str) -> (Vec<Model>, Vec<StaticState>) {
    let variants = variants_from_csv_text("v.csv", csv).unwrap();
    let models: Vec<Model> = variants.iter().map(|v| apply(case, v).unwrap()).collect();
    let starts = models
        .iter()
        .map(|m| {
            solve_static(m, &StaticOptions::default())
                .map(|s| s.state)
                .unwrap_or_else(|_| StaticState::initial(m))
        })
        .collect();
    (models, starts)
}

#[test]
fn dynamic_ensemble_matches_the_cpu_integrator_step_for_step() {
    let (case, models, starts) = bed_variants(
        "mu,wob,rpm,k_e\n0.3,20 kN,120 rpm,6e7\n0.2,15 kN,90 rpm,1e8\n0.4,25 kN,150 rpm,6e7\n",
    );
    let settings = case.dynamics.clone().unwrap();
    let mut options = settings.integrator_options();
    options.rayleigh = (0.5, 0.0);
    let t_end = 0.04;
    let cpu = cpu_runs(&models, &starts, &case.element_density, &options, t_end);
    let (v, n) = (models.len(), models[0].nodes.len());
    let mut seen = Vec::new();
    let twin = run_dynamic_ensemble(
        &models,
        &at_rest(&starts),
        &case.element_density,
        &TwinPath,
        &options,
        t_end,
        1,
        &mut |_, t, s: &DynamicBatch<f64>| seen.push((t, s.clone())),
    )
    .unwrap();
    for r in &twin {
        assert_eq!(r.status, DynamicStatus::Finished);
    }
    let (eu, ev) = trajectory_error(&engine_steps(&seen, v, n), &cpu);
    eprintln!(
        "{v} variants × {} steps: twin path vs CPU integrator: displacements {eu:.2e}, velocities {ev:.2e} (relative to their largest values); iterations per step {:?}",
        seen.len(),
        &twin[0].iterations
    );
    assert!(eu <= 1e-6 && ev <= 1e-6, "{eu:e}, {ev:e}");
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let mut seen_gpu = Vec::new();
        let gpu = run_dynamic_ensemble::<f64, _>(
            &models,
            &at_rest(&starts),
            &case.element_density,
            &GpuPath(ctx),
            &options,
            t_end,
            1,
            &mut |_, t, s: &DynamicBatch<f64>| seen_gpu.push((t, s.clone())),
        )
        .unwrap();
        for r in &gpu {
            assert_eq!(r.status, DynamicStatus::Finished);
        }
        let (gu, gv) = trajectory_error(&engine_steps(&seen_gpu, v, n), &cpu);
        eprintln!("GPU f64 path vs CPU integrator: displacements {gu:.2e}, velocities {gv:.2e}");
        assert!(gu <= 1e-6 && gv <= 1e-6, "{gu:e}, {gv:e}");
    }
    // f32: the error against the f64 CPU runs, reported.
    let mut seen32 = Vec::new();
    let r32 = run_dynamic_ensemble::<f32, _>(
        &models,
        &at_rest(&starts),
        &case.element_density,
        &GpuPath(ctx),
        &options,
        t_end,
        1,
        &mut |_, t, s: &DynamicBatch<f32>| seen32.push((t, widen(s))),
    )
    .unwrap();
    let (fu, fv) = trajectory_error(&engine_steps(&seen32, v, n), &cpu);
    eprintln!(
        "GPU f32 path vs CPU integrator: displacements {fu:.2e}, velocities {fv:.2e}; statuses {:?}",
        r32.iter().map(|r| &r.status).collect::<Vec<_>>()
    );
    for r in &r32 {
        assert_eq!(r.status, DynamicStatus::Finished);
    }
    // The f32 engine accepts residuals up to 1e4 ε₃₂ ≈ 1.2e-3 of the force scale.
    assert!(fu <= 1.2e-3 && fv <= 1.2e-3, "{fu:e}, {fv:e}");
}

/// An f32 batch in f64.
fn widen(b: &DynamicBatch<f32>) -> DynamicBatch<f64> {
    let up = |x: &[f32]| x.iter().map(|&y| f64::from(y)).collect::<Vec<f64>>();
    DynamicBatch {
        num_variants: b.num_variants,
        num_nodes: b.num_nodes,
        u: up(&b.u),
        rot: up(&b.rot),
        vel: up(&b.vel),
        acc: up(&b.acc),
        vdot: up(&b.vdot),
    }
}

#[test]
fn dynamic_kernels_equal_their_twins() {
    use common::runners::{accelerate_gpu, inertial_scale_gpu, predict_gpu};
    use holewall::gpu::assemble::assemble_gpu;
    use holewall::kernels::assemble::{
        assemble, assemble_residual, AssemblyInputs, DynamicInputs, NO_SITE,
    };
    use holewall::kernels::dynamics::{
        accelerate, inertial_scale, predict, StepCoefficients, TOP_LEN,
    };
    use holewall::kernels::sites::gather_sites_dynamic;
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(17);
    let (n, v) = (30, 5);
    let mut r = |lo: f64, hi: f64, len: usize| -> Vec<f64> {
        (0..len).map(|_| rng.random_range(lo..hi)).collect()
    };
    // Rotations: exact ones from random rotation vectors.
    let mut rot = vec![0.0; 9 * n * v];
    let angles = r(-2.0, 2.0, 3 * n * v);
    for idx in 0..n * v {
        let (i, j) = (idx / v, idx % v);
        let e = holewall::physics::beam::rotation_exp(&[
            angles[3 * idx],
            angles[3 * idx + 1],
            angles[3 * idx + 2],
        ]);
        for a in 0..3 {
            for c in 0..3 {
                rot[(9 * i + 3 * a + c) * v + j] = e[a][c];
            }
        }
    }
    let state = DynamicBatch {
        num_variants: v,
        num_nodes: n,
        u: r(-0.1, 0.1, 3 * n * v),
        rot,
        vel: r(-3.0, 3.0, 6 * n * v),
        acc: r(-50.0, 50.0, 6 * n * v),
        vdot: r(-50.0, 50.0, 6 * n * v),
    };
    let mut top = r(-1.0, 1.0, TOP_LEN * v);
    for j in 0..v {
        let e = holewall::physics::beam::rotation_exp(&[0.0, 0.0, 0.3 * j as f64]);
        for (k, x) in e.iter().flatten().enumerate() {
            top[k * v + j] = *x;
        }
    }
    let c = StepCoefficients {
        h: 2e-3,
        alpha_m: 0.33,
        alpha_f: 0.44,
        beta: 0.3,
        gamma: 0.61,
        top_fixed: 0b111011,
        driven: true,
        lowered: true,
    };
    let vdot = r(-50.0, 50.0, 6 * n * v);
    let mut twin_vdot = vdot.clone();
    let mut twin = state.clone();
    predict(&c, &top, &state, &mut twin_vdot, &mut twin);
    // The top's prescribed accelerations, vectors along its hole axis: the table's ω̇ and the
    // hook's acceleration (every DOF of the top is prescribed here, fixed or not).
    for k in 0..3 {
        assert_eq!(
            twin_vdot[(3 + k) * v],
            top[(12 + k) * v],
            "the table's ω̇ written"
        );
        assert_eq!(
            twin_vdot[k * v],
            top[(21 + k) * v],
            "the hook's acceleration written"
        );
    }
    // Neither driven nor lowered: a fixed DOF of the top is held, a free one left alone.
    let held = StepCoefficients {
        driven: false,
        lowered: false,
        ..c
    };
    let (mut held_vdot, mut held_state) = (vdot.clone(), state.clone());
    predict(&held, &top, &state, &mut held_vdot, &mut held_state);
    assert_eq!(held_vdot[v], 0.0, "a fixed DOF of the top is held");
    assert_eq!(
        held_vdot[2 * v],
        vdot[2 * v],
        "a free DOF of the top is left alone"
    );
    // The rotation part against the CPU integrator's Rodrigues exponential.
    let basis: Vec<f64> = (0..n)
        .flat_map(|i| {
            let e = holewall::physics::beam::rotation_exp(&[0.1 * i as f64, 0.2, -0.3]);
            e.into_iter().flatten().collect::<Vec<f64>>()
        })
        .collect();
    let delta = r(-1.0, 1.0, 6 * n * v);
    let alpha = r(-1.0, 1.0, v);
    let acc_twin = accelerate(&basis, &vdot, &delta, &alpha, n, v);
    let mass = r(10.0, 500.0, n);
    let scale_twin = inertial_scale(&mass, &vdot, n, v);
    for j in 0..v {
        let want = (0..n)
            .flat_map(|i| (0..3).map(move |k| (i, k)))
            .fold(0.0f64, |m, (i, k)| {
                m.max((mass[i] * vdot[(6 * i + k) * v + j]).abs())
            });
        assert_eq!(scale_twin[j], want);
    }
    // Dynamic assembly inputs (random element and contact fields: the kernel only adds).
    let s = 4;
    let p = s * v;
    let mut node_site = vec![NO_SITE; n * v];
    let pair_node: Vec<u32> = (0..p).map(|i| (3 + 5 * (i / v)) as u32).collect();
    for i in 0..p {
        node_site[pair_node[i] as usize * v + i % v] = (i / v) as u32;
    }
    let pair_normals: Vec<f64> = (0..p).flat_map(|_| [0.0, 0.6, 0.8]).collect();
    let mut pair_state = r(-1.0, 1.0, 7 * p);
    // The base the displacements are taken from (a hanging string's metres), at the pairs.
    let node_base = r(-3.0, 3.0, 3 * n * v);
    let base = holewall::kernels::sites::pair_base(&pair_node, &pair_normals, &node_base, v);
    gather_sites_dynamic(&pair_node, &pair_normals, &state, &base, &mut pair_state);
    for i in 0..p {
        let at = (3 * pair_node[i] as usize + 2) * v + i % v;
        assert_eq!(
            pair_state[2 * p + i],
            base[3 * i + 2] + state.u[at],
            "d = b + w"
        );
    }
    let a = AssemblyInputs {
        num_variants: v,
        num_nodes: n,
        num_sites: s,
        elem_force: r(-1e4, 1e4, 12 * (n - 1) * v),
        elem_tangent: r(
            -1e6,
            1e6,
            holewall::kernels::beam::TANGENT_LEN * (n - 1) * v,
        ),
        contact: r(-1e3, 1e3, 48 * p),
        contact_flag: (0..p).map(|i| (i % 3 != 0) as u32).collect(),
        node_site,
        f_ext: r(-1e3, 1e3, 6 * n * v),
        basis: basis.clone(),
        fixed: (0..n).map(|i| if i == 0 { 63 } else { 0 }).collect(),
        dynamic: Some(DynamicInputs {
            coefficients: [1.2e-3, 1.1e-6, 0.5],
            mass: mass.clone(),
            inertia0: r(0.1, 5.0, 9 * n),
            rot: state.rot.clone(),
            vel: state.vel.clone(),
            vdot: vdot.clone(),
            pair_normals: pair_normals.clone(),
            unbalance: Vec::new(),
        }),
        shift: None,
    };
    let asm_twin = assemble(&a);
    // With a mass imbalance at every other node (the kernel built UNBALANCE): the twin
    // adds exactly `physics::mass::unbalance_terms`, the GPU the same numbers.
    let mut a_u = a.clone();
    let unbalance: Vec<f64> = r(-0.5, 0.5, 3 * n * v)
        .into_iter()
        .enumerate()
        .map(|(k, x)| if (k / (3 * v)) % 2 == 0 { x } else { 0.0 })
        .collect();
    a_u.dynamic.as_mut().unwrap().unbalance = unbalance.clone();
    let asm_u = assemble(&a_u);
    {
        // One node by hand: the difference of the residuals is the imbalance's force.
        let (i, j) = (4usize, 1usize);
        let dy = a_u.dynamic.as_ref().unwrap();
        let rot = |rr: usize, c: usize| dy.rot[(9 * i + 3 * rr + c) * v + j];
        let u0: [f64; 3] = std::array::from_fn(|k| unbalance[(3 * i + k) * v + j]);
        let u: [f64; 3] = std::array::from_fn(|rr| (0..3).map(|c| rot(rr, c) * u0[c]).sum());
        let at = |k: usize| dy.vdot[(6 * i + k) * v + j];
        let w = [
            dy.vel[(6 * i + 3) * v + j],
            dy.vel[(6 * i + 4) * v + j],
            dy.vel[(6 * i + 5) * v + j],
        ];
        let (ru, _) = holewall::physics::mass::unbalance_terms(
            u,
            mass[i],
            [at(0), at(1), at(2)],
            w,
            [at(3), at(4), at(5)],
            dy.coefficients[0],
        );
        // Node 4 has no fixed DOF; its force rows are taken into its translation basis B
        // (Bᵀ f), its moment rows as they are.
        let b = &a_u.basis[9 * i..9 * i + 9];
        let want: [f64; 6] = std::array::from_fn(|k| {
            if k < 3 {
                (0..3).map(|c| b[3 * c + k] * ru[c]).sum()
            } else {
                ru[k]
            }
        });
        for k in 0..6 {
            let idx = (6 * i + k) * v + j;
            let diff = asm_u.rhs[idx] - asm_twin.rhs[idx];
            assert!(
                (diff - want[k]).abs() <= 1e-9 * want[k].abs().max(1.0),
                "{k}: {diff} vs {}",
                want[k]
            );
        }
    }
    // The trials' residual alone (twin of the kernel built FORCE_ONLY) is the full
    // assembly's residual to the bit, with and without the imbalance, without reading the
    // element tangents.
    for (inputs, full) in [(&a, &asm_twin), (&a_u, &asm_u)] {
        let mut bare = inputs.clone();
        bare.elem_tangent = Vec::new();
        assert_eq!(assemble_residual(&bare), full.rhs);
    }
    let Some(ctx) = common::gpu() else { return };
    if !ctx.has_f64 {
        return;
    }
    let rel = |x: &[f64], y: &[f64]| {
        x.iter()
            .zip(y)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs() / b.abs().max(1.0)))
    };
    let gpu = predict_gpu(ctx, &c, &top, &state, &vdot).unwrap();
    let d_pred = [
        rel(&gpu.u, &twin.u),
        rel(&gpu.rot, &twin.rot),
        rel(&gpu.vel, &twin.vel),
        rel(&gpu.acc, &twin.acc),
        rel(&gpu.vdot, &twin_vdot),
    ];
    let d_acc = rel(
        &accelerate_gpu(ctx, &basis, &vdot, &delta, &alpha, n, v).unwrap(),
        &acc_twin,
    );
    let scale_gpu = inertial_scale_gpu(ctx, &mass, &vdot, n, v).unwrap();
    let sites_gpu = common::runners::gather_sites_dynamic_gpu(
        ctx,
        &pair_node,
        &pair_normals,
        &state,
        &base,
        &r(-1.0, 1.0, 7 * p),
    )
    .unwrap();
    let asm_gpu = assemble_gpu(ctx, &a).unwrap();
    let d_asm = [
        rel(&asm_gpu.diag, &asm_twin.diag),
        rel(&asm_gpu.upper, &asm_twin.upper),
        rel(&asm_gpu.lower, &asm_twin.lower),
        rel(&asm_gpu.rhs, &asm_twin.rhs),
    ];
    eprintln!(
        "GPU f64 vs twin: predict {d_pred:?}, accelerate {d_acc:.1e}, dynamic assembly {d_asm:?}"
    );
    assert!(d_pred.iter().chain(&d_asm).all(|&d| d <= 1e-12) && d_acc <= 1e-15);
    assert_eq!(scale_gpu, scale_twin);
    common::assert_same(
        ctx,
        &sites_gpu,
        &pair_state,
        rel,
        1e-15,
        "site states = twin",
    );
    let asm_u_gpu = assemble_gpu(ctx, &a_u).unwrap();
    let d_u = [
        rel(&asm_u_gpu.diag, &asm_u.diag),
        rel(&asm_u_gpu.rhs, &asm_u.rhs),
    ];
    eprintln!("GPU f64 vs twin, dynamic assembly with a mass imbalance: {d_u:?}");
    assert!(d_u.iter().all(|&d| d <= 1e-12), "{d_u:?}");
    // The line-search trials' residual alone (built FORCE_ONLY): the full kernel's
    // residual, the same sums in the same order — to the bit where the driver does not
    // fuse multiply-adds, else within the full kernel's bound of the twin.
    for (inputs, full, twin_rhs) in [
        (&a, &asm_gpu, &asm_twin.rhs),
        (&a_u, &asm_u_gpu, &asm_u.rhs),
    ] {
        let mut bare = inputs.clone();
        bare.elem_tangent = Vec::new();
        let lean = common::runners::assemble_residual_gpu(ctx, &bare).unwrap();
        common::assert_same(
            ctx,
            &lean,
            &full.rhs,
            rel,
            1e-12,
            "GPU residual alone = full",
        );
        assert!(rel(&lean, twin_rhs) <= 1e-12);
    }
}

#[test]
fn a_failing_variant_fails_alone_in_the_dynamic_engine() {
    // The middle variant: a wall 1.7e4 times stiffer, started from the first variant's
    // equilibrium pushed 2 cm further into the wall (terawatts of spring energy): its
    // Newton cannot converge in a 2 ms step.
    let (case, models, mut starts) =
        bed_variants("mu,wob,k_e\n0.3,20 kN,6e7\n0.3,20 kN,1e12\n0.2,15 kN,6e7\n");
    let mut pushed = starts[0].clone();
    let m = &models[0];
    let node = m.sites[m.sites.len() / 2].node;
    let t = m.nodes[node].hole_axis;
    let d: Vec<f64> = (0..3).map(|k| pushed.u[node][k]).collect();
    let along: f64 = (0..3).map(|k| d[k] * t[k]).sum();
    let lateral: Vec<f64> = (0..3).map(|k| d[k] - along * t[k]).collect();
    let len = lateral.iter().map(|x| x * x).sum::<f64>().sqrt();
    for x in pushed.u.iter_mut() {
        for k in 0..3 {
            x[k] += 0.02 * lateral[k] / len;
        }
    }
    starts[1] = pushed;
    let settings = case.dynamics.clone().unwrap();
    let mut options = settings.integrator_options();
    // The good variants converge in 3–10 iterations; fewer for the bad one to spend (each
    // with up to 24 line-search trials) keeps the test short.
    options.max_iterations = 12;
    let t_end = 0.006;
    let keep = |m: &[Model], s: &[StaticState]| -> (Vec<Model>, Vec<StaticState>) {
        (
            vec![m[0].clone(), m[2].clone()],
            vec![s[0].clone(), s[2].clone()],
        )
    };
    let (good_models, good_starts) = keep(&models, &starts);
    let bits = |b: &DynamicBatch<f64>, j: usize| -> Vec<u64> {
        let v = b.num_variants;
        (0..b.u.len() / v)
            .map(|k| b.u[k * v + j].to_bits())
            .chain((0..b.vel.len() / v).map(|k| b.vel[k * v + j].to_bits()))
            .collect()
    };
    let check = |path_name: &str, run: &dyn Fn(&[Model], &[StaticState]) -> Outcome| {
        let (status, mixed) = run(&models, &starts);
        let (good_status, alone) = run(&good_models, &good_starts);
        eprintln!("{path_name}: failing variant: {:?}", status[1]);
        assert!(matches!(status[1], DynamicStatus::Failed(..)));
        assert_eq!(
            good_status,
            [DynamicStatus::Finished, DynamicStatus::Finished]
        );
        assert_eq!((&status[0], &status[2]), (&good_status[0], &good_status[1]));
        assert_eq!(bits(&mixed, 0), bits(&alone, 0));
        assert_eq!(bits(&mixed, 2), bits(&alone, 1));
    };
    let density = case.element_density.clone();
    check("twin", &|m, s| {
        collect(m, s, &density, &TwinPath, &options, t_end)
    });
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        check("GPU f64", &|m, s| {
            collect(m, s, &density, &GpuPath(ctx), &options, t_end)
        });
    }
}

/// A run's statuses and its last state.
type Outcome = (Vec<DynamicStatus>, DynamicBatch<f64>);

/// Statuses and the last state of a dynamic engine run.
fn collect<P: holewall::engine::KernelPath<f64>>(
    models: &[Model],
    starts: &[StaticState],
    density: &[f64],
    path: &P,
    options: &holewall::solve::dynamics::DynamicOptions,
    t_end: f64,
) -> Outcome {
    let mut last = None;
    let status = run_dynamic_ensemble(
        models,
        &at_rest(starts),
        density,
        path,
        options,
        t_end,
        1,
        &mut |_, _, b: &DynamicBatch<f64>| last = Some(b.clone()),
    )
    .unwrap()
    .into_iter()
    .map(|r| r.status)
    .collect();
    (status, last.unwrap())
}

/// 16 variants (RPM × WOB) of the paper's one-stabilizer case (§3.1 dynamics: table ramped
/// over 50 s, hook lowered at the ROP) for `HOLEWALL_PAPER_SECONDS` (default 1 s) on
/// `HOLEWALL_PAPER_PATH` = `twin` (default) or `gpu` (f64 within 1e-6, then f32 within
/// 1.2e-3, the residual the f32 engine accepts; `HOLEWALL_PAPER_PRECISION=f32`: f32 only),
/// against 16 CPU integrator runs, step for step. Over much shorter runs the velocities
/// are still at the scale the Newton tolerance leaves (the table has barely started: at
/// 0.02 s the GPU path shows 1.2e-6 of the largest velocity), so the 1 s of the issue is
/// the meaningful length. Minutes on two cores (8 min on lavapipe in f64, 4.5 in f32); run
/// with `cargo test --release --test engine_dynamic -- --ignored --nocapture`.
#[test]
#[ignore]
fn paper_case_sixteen_variants_match_the_cpu_integrator() {
    let seconds: f64 = std::env::var("HOLEWALL_PAPER_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let gpu = std::env::var("HOLEWALL_PAPER_PATH").as_deref() == Ok("gpu");
    let case = holewall::case::load_case(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/paper_one_stabilizer.toml"
    )))
    .unwrap();
    let mut csv = String::from("rpm,wob\n");
    for rpm in [60, 90, 120, 150] {
        for wob in [60, 75, 89, 100] {
            csv += &format!("{rpm} rpm,{wob} kN\n");
        }
    }
    let (models, starts) = with_starts(&case, &csv);
    let options = case.dynamics.as_ref().unwrap().integrator_options();
    let t0 = std::time::Instant::now();
    let cpu = cpu_runs(&models, &starts, &case.element_density, &options, seconds);
    let t_cpu = t0.elapsed().as_secs_f64();
    let (v, n) = (models.len(), models[0].nodes.len());
    let run = |f32_too: bool| -> (f64, f64, f64) {
        let mut seen = Vec::new();
        let t0 = std::time::Instant::now();
        let r = if gpu {
            let ctx = common::gpu().unwrap();
            if f32_too {
                run_dynamic_ensemble::<f32, _>(
                    &models,
                    &at_rest(&starts),
                    &case.element_density,
                    &GpuPath(ctx),
                    &options,
                    seconds,
                    1,
                    &mut |_, t, s: &DynamicBatch<f32>| seen.push((t, widen(s))),
                )
                .unwrap()
            } else {
                run_dynamic_ensemble::<f64, _>(
                    &models,
                    &at_rest(&starts),
                    &case.element_density,
                    &GpuPath(ctx),
                    &options,
                    seconds,
                    1,
                    &mut |_, t, s: &DynamicBatch<f64>| seen.push((t, s.clone())),
                )
                .unwrap()
            }
        } else {
            run_dynamic_ensemble(
                &models,
                &at_rest(&starts),
                &case.element_density,
                &TwinPath,
                &options,
                seconds,
                1,
                &mut |_, t, s: &DynamicBatch<f64>| seen.push((t, s.clone())),
            )
            .unwrap()
        };
        let elapsed = t0.elapsed().as_secs_f64();
        // Every variant must finish, in f32 too: its states are the motion from the static
        // equilibrium, whose f32 quantum is far below the residual it accepts (with
        // displacements from the undeformed mesh, metres at the bit, a variant stalled at
        // t = 0.816 s on the f32 rounding of the BHA's axial forces).
        for (j, x) in r.iter().enumerate() {
            assert_eq!(
                x.status,
                DynamicStatus::Finished,
                "variant {j}, f32 {f32_too}"
            );
        }
        let its: Vec<usize> = r
            .iter()
            .flat_map(|x| x.iterations.iter().copied())
            .collect();
        eprintln!(
            "  {}: Newton iterations per variant-step: mean {:.2}, max {}",
            if f32_too { "f32" } else { "f64" },
            its.iter().sum::<usize>() as f64 / its.len().max(1) as f64,
            its.iter().max().unwrap_or(&0)
        );
        let engine = engine_steps(&seen, v, n);
        let (eu, ev) = trajectory_error(&engine, &cpu);
        (eu, ev, elapsed)
    };
    // `HOLEWALL_PAPER_PRECISION=f32` runs the GPU in f32 only.
    if gpu && std::env::var("HOLEWALL_PAPER_PRECISION").as_deref() == Ok("f32") {
        let (eu, ev, t32) = run(true);
        eprintln!(
            "paper case, {v} variants × {seconds} s, GPU f32: displacements {eu:.2e}, velocities {ev:.2e} relative to the f64 CPU runs; engine {t32:.1} s, CPU runs {t_cpu:.1} s"
        );
        // The f32 engine accepts residuals up to 1e4 ε₃₂ ≈ 1.2e-3 of the force scale.
        assert!(eu <= 1.2e-3 && ev <= 1.2e-3, "f32 {eu:e}, {ev:e}");
        return;
    }
    let (eu, ev, t_engine) = run(false);
    eprintln!(
        "paper case, {v} variants × {seconds} s ({} path, f64): displacements {eu:.2e}, velocities {ev:.2e} relative; engine {t_engine:.1} s, 16 CPU integrator runs {t_cpu:.1} s",
        if gpu { "GPU" } else { "twin" }
    );
    assert!(eu <= 1e-6 && ev <= 1e-6, "{eu:e}, {ev:e}");
    if gpu {
        let (eu, ev, t32) = run(true);
        eprintln!(
            "paper case, GPU f32: displacements {eu:.2e}, velocities {ev:.2e} relative to the f64 CPU runs; {t32:.1} s"
        );
        assert!(eu <= 1.2e-3 && ev <= 1.2e-3, "f32 {eu:e}, {ev:e}");
    }
}

/// Per-variant step control in the dynamic engine: with a regularisation speed of 1e-6 m/s
/// and 10 ms steps the friction's sign is too sharp for a full step; the variant is taken
/// back and re-tried in half steps on its own (twin and GPU), keeps the cut step until an
/// easy step regrows it — the CPU integrator's policy — and so cuts where the CPU
/// integrator cuts and ends where it ends, to rounding.
#[test]
fn a_variant_whose_step_fails_is_cut_on_its_own_in_the_engine() {
    let text = common::bed_text("0.3", "8.25 in", "6e7", "1", "1e-6")
        .replace("time_step = \"2 ms\"", "time_step = \"10 ms\"");
    let case = holewall::case::parse_case(std::path::Path::new("bed.toml"), &text).unwrap();
    let (models, starts) = with_starts(&case, "eps\n1e-3\n1e-6\n");
    let options = case.dynamics.as_ref().unwrap().integrator_options();
    let density = case.element_density.clone();
    let t_end = 0.05;
    // The CPU integrator on the variant that needs cuts.
    let m = &models[1];
    let (log, s) = cpu_to_end(&models, &starts, &density, 1, &options, t_end);
    assert!(!log.is_empty(), "the CPU integrator did not cut");
    let n = m.nodes.len();
    let cpu_u: Vec<f64> = (0..n)
        .flat_map(|i| (0..3).map(move |k| (i, k)))
        .map(|(i, k)| s.q.u[i][k])
        .collect();
    let check = |label: &str,
                 path: &dyn Fn() -> Vec<holewall::engine::dynamic::DynamicResult>,
                 last: &dyn Fn() -> DynamicBatch<f64>| {
        let results = path();
        for (j, r) in results.iter().enumerate() {
            assert_eq!(r.status, DynamicStatus::Finished, "{label}: variant {j}");
        }
        eprintln!(
            "{label}: variant 1 cuts: {:?}; CPU integrator: {:?}",
            results[1].log, log
        );
        assert!(
            !results[1].log.is_empty(),
            "{label}: no cut where the CPU cuts"
        );
        let b = last();
        let v = b.num_variants;
        let scale = cpu_u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = (0..3 * n).fold(0.0f64, |m, k| m.max((b.u[k * v + 1] - cpu_u[k]).abs()));
        eprintln!(
            "{label}: end displacement vs the CPU integrator {:.2e} of the largest ({scale:.2e} m)",
            diff / scale
        );
        assert!(diff <= 1e-10 * scale, "{diff:e} of {scale:e}");
    };
    let last_state = std::cell::RefCell::new(None);
    let run_on = |path: &dyn holewall::engine::KernelPath<f64>| {
        let (r, last) = run_to_end(&models, &starts, &density, path, &options, t_end);
        *last_state.borrow_mut() = Some(last);
        r
    };
    check("twin", &|| run_on(&TwinPath), &|| {
        last_state.borrow().clone().unwrap()
    });
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        check("GPU f64", &|| run_on(&GpuPath(ctx)), &|| {
            last_state.borrow().clone().unwrap()
        });
    }
}

/// A run of some variants with the number of dynamic chunks it opened.
type CountedRun = Box<dyn Fn(&[Model], &[StaticState]) -> (Outcome, usize)>;

/// Within a time step only the variants still iterating are worked on (on the GPU the
/// kernels built `MASKED`, the list of those variants; no batch of stragglers is opened on
/// the host): every variant of a 6-variant run, whose variants converge after different
/// numbers of iterations, ends bit-identical to its run alone (twin and GPU), and the run
/// opened one batch.
#[test]
fn variants_still_iterating_go_on_alone_bit_for_bit() {
    let (case, models, starts) = bed_variants(
        "mu,wob,rpm\n0.1,10 kN,60 rpm\n0.4,25 kN,150 rpm\n0.2,15 kN,90 rpm\n0.5,30 kN,180 rpm\n0.3,20 kN,120 rpm\n0.05,5 kN,30 rpm\n",
    );
    let settings = case.dynamics.clone().unwrap();
    let options = settings.integrator_options();
    let density = case.element_density.clone();
    let t_end = 0.02;
    let bits = |b: &DynamicBatch<f64>, j: usize| -> Vec<u64> {
        let v = b.num_variants;
        (0..b.u.len() / v)
            .map(|k| b.u[k * v + j].to_bits())
            .chain((0..b.vel.len() / v).map(|k| b.vel[k * v + j].to_bits()))
            .collect()
    };
    // The variants converge after different numbers of iterations in some step (so some
    // iterations work on part of the batch).
    let r = run_dynamic_ensemble(
        &models,
        &at_rest(&starts),
        &density,
        &TwinPath,
        &options,
        t_end,
        0,
        &mut |_, _, _: &DynamicBatch<f64>| {},
    )
    .unwrap();
    let steps = r[0].iterations.len();
    assert!(
        (0..steps).any(|k| r
            .iter()
            .any(|x| x.iterations.get(k) != r[0].iterations.get(k))),
        "every variant took the same iterations in every step"
    );
    let check = |label: &str, path: &dyn Fn() -> CountedRun| {
        let run = path();
        let ((status, together), opens) = run(&models, &starts);
        eprintln!("{label}: {opens} dynamic chunks opened for 6 variants × 10 steps");
        assert_eq!(opens, 1, "{label}: a batch of stragglers was opened");
        for j in 0..models.len() {
            assert_eq!(status[j], DynamicStatus::Finished);
            let ((_, alone), _) = run(&models[j..j + 1], &starts[j..j + 1]);
            assert_eq!(bits(&together, j), bits(&alone, 0), "{label}: variant {j}");
        }
    };
    let twin = || -> CountedRun {
        let density = density.clone();
        Box::new(move |m: &[Model], s: &[StaticState]| {
            let path = common::Counting::new(&TwinPath);
            let out = collect(m, s, &density, &path, &options, t_end);
            (out, path.dynamic_opens.get())
        })
    };
    check("twin", &twin);
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let gpu = || -> CountedRun {
            let density = density.clone();
            Box::new(move |m: &[Model], s: &[StaticState]| {
                let gpu = GpuPath(ctx);
                let path = common::Counting::new(&gpu);
                let out = collect(m, s, &density, &path, &options, t_end);
                (out, path.dynamic_opens.get())
            })
        };
        check("GPU f64", &gpu);
    }
}

/// A site the dynamic engine's batch holds only for another variant (a variant whose static
/// start added it at the wall: `ensemble::runner`'s batch of wall sites) lies beyond any wall
/// (`ABSENT_SITE_CLEARANCE`): the run is bit for bit the run without the site, twin and GPU
/// f64. The site is the pipe-body site bearing hardest at the start, so the same site with
/// its own clearance changes the run (checked: the comparison would see a site that acts).
#[test]
fn a_site_held_for_another_variant_adds_nothing() {
    use holewall::ensemble::runner::ABSENT_SITE_CLEARANCE;
    let (case, models, starts) = bed_variants("mu,wob\n0.3,20 kN\n");
    let settings = case.dynamics.clone().unwrap();
    let options = settings.integrator_options();
    let t_end = 0.01;
    let full = &models[0];
    // The pipe-body site bearing hardest at the start: the one whose absence shows.
    let sol = solve_static(full, &StaticOptions::default()).unwrap();
    let (bearing, _) = sol
        .contact
        .iter()
        .enumerate()
        .filter(|(k, c)| c.0 && !full.sites[*k].stabilizer)
        .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .unwrap();
    let node = full.sites[bearing].node;
    let mut without = full.clone();
    without.sites.retain(|s| s.node != node);
    let mut absent = full.clone();
    absent.sites[bearing].params.clearance = ABSENT_SITE_CLEARANCE;
    let start = std::slice::from_ref(&starts[0]);
    let density = &case.element_density;
    // Without the site, with it absent, with it present: on one kernel path.
    let runs = |path: &dyn Fn(&[Model]) -> Outcome, label: &str| {
        let run = |m: &Model| path(std::slice::from_ref(m));
        let (a, b, c) = (run(&without), run(&absent), run(full));
        assert_eq!(a.0, b.0);
        assert_eq!(
            (&a.1.u, &a.1.vel),
            (&b.1.u, &b.1.vel),
            "{label}: an absent site changed the run"
        );
        assert_ne!(a.1.u, c.1.u, "{label}: the site chosen does not bear");
    };
    runs(
        &|m| collect(m, start, density, &TwinPath, &options, t_end),
        "twin",
    );
    if let Some(ctx) = common::gpu() {
        runs(
            &|m| collect(m, start, density, &GpuPath(ctx), &options, t_end),
            "GPU f64",
        );
    }
}

/// A run that cuts its step to a quarter and regrows it inside a 10 ms step (ε = 1e-6 m/s,
/// μ = 1 at 30 rpm, near stick-slip) takes the same steps on the engine as on the CPU
/// integrator — both step by `solve::dynamics::control` — and ends where it ends, to
/// rounding as the run amplifies it (twin and GPU f64). Before the two shared that module,
/// the integrator took a regrown step at once, off the engine's grid: 24 cuts on the CPU
/// against 18 on the twin, the end displacements 8.8e-3 of the largest apart.
#[test]
fn a_run_that_cuts_and_regrows_takes_the_cpu_integrators_steps_in_the_engine() {
    let text = common::stick_slip_bed_text();
    let case = holewall::case::parse_case(std::path::Path::new("bed.toml"), &text).unwrap();
    // The second variant, ε changed by 1e-13, measures the run's own sensitivity.
    let (models, starts) = with_starts(&case, "eps\n1e-6\n1.0000000000001e-6\n");
    let options = case.dynamics.as_ref().unwrap().integrator_options();
    let density = case.element_density.clone();
    let t_end = 0.15;
    let m = &models[0];
    let (log, s) = cpu_to_end(&models, &starts, &density, 0, &options, t_end);
    let (_, perturbed) = cpu_to_end(&models, &starts, &density, 1, &options, t_end);
    let cuts = |log: &[String]| log.iter().filter(|l| l.contains("cut to")).count();
    let quarter = log.iter().any(|l| l.contains("cut to 2.500e-3"));
    let regrown = log.iter().filter(|l| l.contains("regrown")).count();
    eprintln!(
        "CPU integrator: {} cuts, {regrown} regrowths, to a quarter: {quarter}",
        cuts(&log)
    );
    assert!(
        quarter && regrown > 0,
        "the case no longer cuts to a quarter and regrows"
    );
    let n = m.nodes.len();
    let cpu_u: Vec<f64> = (0..n)
        .flat_map(|i| (0..3).map(move |k| (i, k)))
        .map(|(i, k)| s.q.u[i][k])
        .collect();
    let scale = cpu_u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let spread = (0..3 * n).fold(0.0f64, |m, k| {
        let (i, c) = (k / 3, k % 3);
        m.max((perturbed.q.u[i][c] - s.q.u[i][c]).abs())
    });
    eprintln!(
        "CPU integrator alone, ε changed by 1e-13: ends {:.2e} of the largest apart",
        spread / scale
    );
    // Rounding apart, amplified as the run's own sensitivity amplifies a 1e-13 change (the
    // policy of before: 8.8e-3 of the largest, with 24 cuts on the CPU against 18).
    let bound = (10.0 * spread).max(1e-10 * scale).min(1e-6 * scale);
    let check = |label: &str, path: &dyn holewall::engine::KernelPath<f64>| {
        let (r, b) = run_to_end(&models, &starts, &density, path, &options, t_end);
        assert_eq!(r[0].status, DynamicStatus::Finished, "{label}");
        let v = b.num_variants;
        let diff = (0..3 * n).fold(0.0f64, |m, k| m.max((b.u[k * v] - cpu_u[k]).abs()));
        eprintln!(
            "{label}: {} cuts; end displacement vs the CPU integrator {:.2e} of the largest ({scale:.2e} m)",
            cuts(&r[0].log),
            diff / scale
        );
        assert_eq!(cuts(&r[0].log), cuts(&log), "{label}: cuts");
        assert!(
            diff <= bound,
            "{label}: {diff:e} of {scale:e} (bound {bound:e})"
        );
    };
    check("twin", &TwinPath);
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        check("GPU f64", &GpuPath(ctx));
    }
}

/// The engine's dynamic run of `models` from rest at `starts` to `t_end` on `path`
/// (observed every step): the results and the batch's last state.
fn run_to_end(
    models: &[Model],
    starts: &[StaticState],
    density: &[f64],
    path: &dyn holewall::engine::KernelPath<f64>,
    options: &holewall::solve::dynamics::DynamicOptions,
    t_end: f64,
) -> (
    Vec<holewall::engine::dynamic::DynamicResult>,
    DynamicBatch<f64>,
) {
    let mut last = None;
    let r = run_dynamic_ensemble(
        models,
        &at_rest(starts),
        density,
        &common::Counting::new(path),
        options,
        t_end,
        1,
        &mut |_, _, b: &DynamicBatch<f64>| last = Some(b.clone()),
    )
    .unwrap();
    (r, last.unwrap())
}

/// The CPU integrator's run of variant `j` from rest at its start to `t_end`: its log and
/// its last state.
fn cpu_to_end(
    models: &[Model],
    starts: &[StaticState],
    density: &[f64],
    j: usize,
    options: &holewall::solve::dynamics::DynamicOptions,
    t_end: f64,
) -> (Vec<String>, holewall::solve::dynamics::DynamicState) {
    let mut d = Dynamics::new(&models[j], *options, &|e| density[e]);
    let mut s = d.initial_state(starts[j].clone()).unwrap();
    d.run(&mut s, t_end, &mut |_, _| {}).unwrap();
    (d.log, s)
}
