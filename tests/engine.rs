//! The static ensemble through the kernels (beam, contact, assembly, block LU, norms,
//! update) against `solve_static` per variant; the GPU path against the twin path.

mod common;

use holewall::engine::{solve_static_ensemble, EngineStatus, TwinPath};

use holewall::ensemble::{apply, variants_from_csv_text};
use holewall::gpu::GpuPath;
use holewall::solve::statics::{solution_at, solve_static, StaticOptions};

/// Neutral point, surface torque, largest side force.
fn qoi(
    model: &holewall::model::Model,
    sol: &holewall::solve::statics::StaticSolution,
    bit_md: f64,
) -> [f64; 3] {
    let q = common::static_qois(model, sol, bit_md);
    [q[0], q[1], q[2]]
}

#[test]
fn kernel_chain_static_ensemble_matches_single_cpu_runs() {
    let case = common::bed_case("1");
    let variants = variants_from_csv_text(
        "v.csv",
        "mu,wob,k_e\n0.1,5 kN,6e7\n0.2,8 kN,1e8\n0.3,10 kN,6e7\n0.4,12 kN,3e7\n0.15,6 kN,6e7\n0.25,9 kN,2e8\n",
    )
    .unwrap();
    let models: Vec<_> = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
    let options = StaticOptions::default();
    let twin = solve_static_ensemble(&models, &TwinPath, &options).unwrap();
    let mut worst: f64 = 0.0;
    for (j, (m, r)) in models.iter().zip(&twin).enumerate() {
        assert_eq!(r.status, EngineStatus::Converged, "variant {j}");
        let cpu = solve_static(m, &options).unwrap();
        let a = qoi(m, &solution_at(m, r.state.clone()), case.bit_md);
        let b = qoi(m, &cpu, case.bit_md);
        for k in 0..3 {
            let rel = (a[k] - b[k]).abs() / b[k].abs().max(1e-300);
            worst = worst.max(rel);
        }
        eprintln!(
            "variant {j}: kernels {a:.6?} vs solve_static {b:.6?}; iterations per step {:?}",
            r.iterations
        );
    }
    eprintln!("twin path vs solve_static: worst relative QoI difference {worst:.2e}");
    assert!(worst <= 1e-9, "{worst:e}");
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let gpu = solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options).unwrap();
        let mut diff: f64 = 0.0;
        for (g, t) in gpu.iter().zip(&twin) {
            assert_eq!(g.status, t.status);
            for (xg, xt) in g.state.u.iter().zip(&t.state.u) {
                for k in 0..3 {
                    diff = diff.max((xg[k] - xt[k]).abs());
                }
            }
        }
        eprintln!("GPU f64 path vs twin path: largest position difference {diff:.2e} m");
        assert!(diff <= 1e-9);
    }
}

#[test]
fn a_failing_variant_fails_alone_in_the_engine() {
    let case = common::bed_case("1");
    // The middle variant: 9 MN on the bit and 1 MN·m on it, a 1e12 N/m hard-spring wall —
    // solve_static fails it too (Newton stalls at λ ≈ 0.68 below the smallest load step).
    let good = variants_from_csv_text(
        "v.csv",
        "mu,wob,k_e,m,tob\n0.2,8 kN,6e7,1,0\n0.3,10 kN,6e7,1,0\n",
    )
    .unwrap();
    let mixed = variants_from_csv_text(
        "v.csv",
        "mu,wob,k_e,m,tob\n0.2,8 kN,6e7,1,0\n0.3,9000 kN,1e12,3,1000 kN.m\n0.3,10 kN,6e7,1,0\n",
    )
    .unwrap();
    let models = |v: &[holewall::ensemble::Variant]| {
        v.iter()
            .map(|x| apply(&case, x).unwrap())
            .collect::<Vec<_>>()
    };
    let options = StaticOptions::default();
    let alone = solve_static_ensemble(&models(&good), &TwinPath, &options).unwrap();
    let with_bad = solve_static_ensemble(&models(&mixed), &TwinPath, &options).unwrap();
    eprintln!("bad variant: {:?}", with_bad[1].status);
    assert!(matches!(with_bad[1].status, EngineStatus::Failed(_)));
    let bits = |r: &holewall::engine::EngineResult| -> Vec<u64> {
        r.state.u.iter().flatten().map(|x| x.to_bits()).collect()
    };
    assert_eq!(bits(&alone[0]), bits(&with_bad[0]));
    assert_eq!(bits(&alone[1]), bits(&with_bad[2]));
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let alone =
            solve_static_ensemble::<f64, _>(&models(&good), &GpuPath(ctx), &options).unwrap();
        let with_bad =
            solve_static_ensemble::<f64, _>(&models(&mixed), &GpuPath(ctx), &options).unwrap();
        assert!(matches!(with_bad[1].status, EngineStatus::Failed(_)));
        assert_eq!(bits(&alone[0]), bits(&with_bad[0]));
        assert_eq!(bits(&alone[1]), bits(&with_bad[2]));
    }
}

#[test]
fn stabilizer_moves_and_chunks_in_the_engine() {
    use holewall::engine::Batched;
    let case = common::bed_case("1");
    // The stabilizer 1.5 m, 3 m and 4.5 m further from the bit than in the case, with
    // different friction: each variant's pairs sit at other nodes.
    let variants = variants_from_csv_text(
        "v.csv",
        "stab1.from_bit,mu,wob\n6 m,0.2,8 kN\n7.5 m,0.3,8 kN\n9 m,0.25,10 kN\n4.5 m,0.3,6 kN\n6 m,0.35,9 kN\n",
    )
    .unwrap();
    let models: Vec<_> = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
    let nodes: Vec<usize> = models
        .iter()
        .map(|m| m.sites.iter().find(|s| s.stabilizer).unwrap().node)
        .collect();
    eprintln!("stabilizer nodes per variant: {nodes:?}");
    assert!(nodes.windows(2).any(|w| w[0] != w[1]));
    let options = StaticOptions::default();
    let twin = solve_static_ensemble(&models, &TwinPath, &options).unwrap();
    let mut worst: f64 = 0.0;
    for (m, r) in models.iter().zip(&twin) {
        assert_eq!(r.status, EngineStatus::Converged);
        let cpu = solve_static(m, &options).unwrap();
        let a = qoi(m, &solution_at(m, r.state.clone()), case.bit_md);
        let b = qoi(m, &cpu, case.bit_md);
        for k in 0..3 {
            worst = worst.max((a[k] - b[k]).abs() / b[k].abs().max(1e-300));
        }
    }
    eprintln!("stabilizer moves, twin path vs solve_static: worst relative QoI {worst:.2e}");
    assert!(worst <= 1e-9, "{worst:e}");
    // Chunks of two: bit-identical to one chunk (the variants never meet).
    let bits = |r: &[holewall::engine::EngineResult]| -> Vec<u64> {
        r.iter()
            .flat_map(|r| r.state.u.iter().flatten().map(|x| x.to_bits()))
            .collect()
    };
    let chunked = solve_static_ensemble(
        &models,
        &Batched {
            inner: TwinPath,
            max: 2,
        },
        &options,
    )
    .unwrap();
    assert_eq!(bits(&chunked), bits(&twin));
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let gpu = solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options).unwrap();
        let gpu_chunked = solve_static_ensemble::<f64, _>(
            &models,
            &Batched {
                inner: GpuPath(ctx),
                max: 2,
            },
            &options,
        )
        .unwrap();
        assert_eq!(bits(&gpu_chunked), bits(&gpu));
        let diff = gpu
            .iter()
            .zip(&twin)
            .flat_map(|(g, t)| g.state.u.iter().flatten().zip(t.state.u.iter().flatten()))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        eprintln!("stabilizer moves, GPU f64 vs twin: largest position difference {diff:.2e} m");
        assert!(diff <= 1e-9);
    }
}

#[test]
fn sites_kernel_equals_its_twin() {
    use holewall::kernels::sites::{gather_sites, pair_base};
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let (n, v, s) = (40, 7, 5);
    let p = s * v;
    let pair_node: Vec<u32> = (0..p).map(|_| rng.random_range(0..n as u32)).collect();
    let x: Vec<f64> = (0..3 * n * v)
        .map(|_| rng.random_range(-1e3..1e3))
        .collect();
    // A base of metres per node, and a hole axis per pair (deviated).
    let base: Vec<f64> = (0..3 * n * v)
        .map(|_| rng.random_range(-3.0..3.0))
        .collect();
    let normals: Vec<f64> = (0..p)
        .flat_map(|_| {
            let a: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            a.map(|c| c / l)
        })
        .collect();
    let at_pairs = pair_base(&pair_node, &normals, &base, v);
    let mut twin: Vec<f64> = (0..7 * p).map(|k| k as f64).collect();
    let before = twin.clone();
    gather_sites(&pair_node, &x, &at_pairs, v, &mut twin);
    let across = |d: [f64; 3], i: usize| -> [f64; 3] {
        let n = &normals[3 * i..3 * i + 3];
        let along: f64 = (0..3).map(|k| d[k] * n[k]).sum();
        std::array::from_fn(|k| d[k] - n[k] * along)
    };
    for i in 0..p {
        let (node, j) = (pair_node[i] as usize, i % v);
        for k in 0..3 {
            let at = (3 * node + k) * v + j;
            assert_eq!(twin[k * p + i], at_pairs[3 * i + k] + x[at]);
        }
        // Across the hole axis (all the contact uses) d is the whole b + w.
        let full: [f64; 3] = std::array::from_fn(|k| {
            let at = (3 * node + k) * v + j;
            base[at] + x[at]
        });
        let d: [f64; 3] = std::array::from_fn(|k| twin[k * p + i]);
        let (a, b) = (across(d, i), across(full, i));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-12 * 1e3, "{a:?} vs {b:?}");
        }
        for k in 3..7 {
            assert_eq!(
                twin[k * p + i],
                before[k * p + i],
                "velocity fields untouched"
            );
        }
    }
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let gpu =
            common::runners::gather_sites_gpu(ctx, &pair_node, &x, &at_pairs, v, &before).unwrap();
        assert_eq!(gpu, twin);
    }
}

#[test]
fn f32_engine_error_against_f64() {
    let Some(ctx) = common::gpu() else { return };
    let case = common::bed_case("1");
    let variants = variants_from_csv_text(
        "v.csv",
        "mu,wob,k_e\n0.1,5 kN,6e7\n0.2,8 kN,1e8\n0.3,10 kN,6e7\n0.4,12 kN,3e7\n",
    )
    .unwrap();
    let models: Vec<_> = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
    let options = StaticOptions::default();
    let exact = solve_static_ensemble(&models, &TwinPath, &options).unwrap();
    let f32_run = solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options).unwrap();
    let mut worst = [0.0f64; 3];
    for (j, (m, (a, b))) in models.iter().zip(f32_run.iter().zip(&exact)).enumerate() {
        eprintln!(
            "f32 variant {j}: {:?}, iterations {:?}",
            a.status, a.iterations
        );
        assert_eq!(a.status, EngineStatus::Converged);
        let qa = qoi(m, &solution_at(m, a.state.clone()), case.bit_md);
        let qb = qoi(m, &solution_at(m, b.state.clone()), case.bit_md);
        for k in 0..3 {
            worst[k] = worst[k].max((qa[k] - qb[k]).abs() / qb[k].abs());
        }
    }
    eprintln!(
        "GPU f32 vs f64: neutral point {:.2e}, surface torque {:.2e}, max side force {:.2e} (relative)",
        worst[0], worst[1], worst[2]
    );
    // The f32 engine accepts a residual up to 1e4 ε₃₂ ≈ 1.2e-3 of the reference force (the
    // string's weight): no quantity of interest can be held closer than that.
    assert!(worst.iter().all(|&w| w <= 1.2e-3), "{worst:?}");
}

/// Compaction of the static engine: once no more than half of the variants are running,
/// the rest go on in a chunk of their own exactly where they stand — every variant of a
/// 6-variant run ends bit-identical to its run alone, and the run did compact.
#[test]
fn compacted_static_variants_go_on_bit_for_bit() {
    let case = common::bed_case("1");
    let variants = variants_from_csv_text(
        "v.csv",
        "mu,wob,k_e\n0.1,5 kN,6e7\n0.6,30 kN,1e9\n0.2,8 kN,3e7\n0.9,25 kN,1e10\n0.3,12 kN,6e7\n0.05,2 kN,1e8\n",
    )
    .unwrap();
    let models: Vec<_> = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
    let options = StaticOptions::default();
    let bits = |r: &holewall::engine::EngineResult| -> Vec<u64> {
        r.state
            .u
            .iter()
            .flatten()
            .chain(r.state.rot.iter().flatten().flatten())
            .map(|x| x.to_bits())
            .collect()
    };
    let counting = common::Counting::new(&TwinPath);
    let together = solve_static_ensemble(&models, &counting, &options).unwrap();
    eprintln!(
        "{} chunks opened for 6 variants; iterations per load step {:?}",
        counting.opens.get(),
        together
            .iter()
            .map(|r| r.iterations.clone())
            .collect::<Vec<_>>()
    );
    assert!(counting.opens.get() > 1, "no compaction happened");
    for (j, r) in together.iter().enumerate() {
        assert_eq!(r.status, EngineStatus::Converged, "variant {j}");
        let alone = solve_static_ensemble(&models[j..j + 1], &TwinPath, &options).unwrap();
        assert_eq!(bits(r), bits(&alone[0]), "variant {j}");
    }
}

/// A stiff soft-law wall (k_e = 1e11 N/m^m, m = 2/3; its onset stiffness is about 6e12
/// N/m) on the shipped build-and-hold well, the stability map's cell that failed: a contact's
/// penetration there is about 1e-12 m, a few ulps of a position 1,500 m from the surface.
/// The CPU solve keeps its unknowns as displacements from the hole axis, as the engine
/// does, so it solves to the tolerance, and the engine's twin reaches the same equilibrium.
/// With positions as the unknowns the CPU stalled at λ 0.22 with a residual of 6e-7 of the
/// force scale (its rounding floor), while the engine solved. Its load steps still stall at
/// a contact onset near λ 0.22, and a relaxation takes it to the full loads, settling where
/// its residual stalls below the residual a Newton solve accepts at its rounding floor
/// (`relax_stall_tolerance`: `NewtonSettings::small_residual`, 1e-6; measured 5.7e-9; the
/// log says so).
#[test]
fn a_stiff_soft_law_wall_solves_on_the_cpu_as_in_the_engine() {
    let text = common::shipped_case_text("build_and_hold.toml").replace(
        "sites = \"all_nodes\"",
        "sites = \"all_nodes\"\nwall_stiffness = 1e11\nexponent = 0.6666667",
    );
    assert!(text.contains("wall_stiffness = 1e11"));
    let case = holewall::case::parse_case(std::path::Path::new("stiff.toml"), &text).unwrap();
    let model = &case.model;
    let options = StaticOptions::default();
    let cpu = solve_static(model, &options).expect("the CPU solve reaches the full loads");
    let measure = holewall::solve::statics::residual_measure_at(model, &cpu.state);
    eprintln!(
        "CPU: residual {measure:.2e} of the force scale, log {:?}",
        cpu.log
    );
    let settled = holewall::solve::continuation::relax_stall_tolerance(&options, false);
    assert!(measure <= settled, "{measure:e}");
    let twin = solve_static_ensemble(std::slice::from_ref(model), &TwinPath, &options).unwrap();
    assert_eq!(twin[0].status, EngineStatus::Converged);
    let a = qoi(model, &cpu, case.bit_md);
    let b = qoi(
        model,
        &solution_at(model, twin[0].state.clone()),
        case.bit_md,
    );
    eprintln!("CPU {a:?}, twin {b:?}");
    // Both settle within `settled` of the force scale, not the tolerance, so they agree to
    // that (measured: 3.8e-10, 3.3e-14 and 6.3e-9 relative).
    for k in 0..3 {
        assert!(
            (a[k] - b[k]).abs() <= settled * b[k].abs(),
            "quantity {k}: {} against {}",
            a[k],
            b[k]
        );
    }
}
