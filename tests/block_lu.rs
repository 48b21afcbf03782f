//! The block-tridiagonal solve (`shaders/block_lu.wgsl`, twin `src/kernels/block_lu.rs`)
//! against faer's sparse LU on real tangents of the paper cases and on random
//! block-diagonally-dominant systems; GPU against the twin; a singular variant fails alone.

mod common;

use holewall::gpu::block_lu::{block_lu_gpu, block_lu_gpu_chunked, block_lu_gpu_form, LuForm};
use holewall::kernels::block_cr::block_cr;
use holewall::kernels::block_lu::{block_lu, block_lu_one, ChainBatch, SINGULAR, SOLVED};
use holewall::solve::chain::{BlockTridiagonal, ChainSolver};
use rand::{Rng, SeedableRng};

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

fn relative_residual(a: &BlockTridiagonal, x: &[f64], b: &[f64]) -> f64 {
    let ax = a.mul(x);
    let r: Vec<f64> = ax.iter().zip(b).map(|(p, q)| p - q).collect();
    norm(&r) / norm(b)
}

fn relative_error(x: &[f64], reference: &[f64]) -> f64 {
    let d: Vec<f64> = x.iter().zip(reference).map(|(p, q)| p - q).collect();
    norm(&d) / norm(reference)
}

/// Constrained static tangents of the paper cases at their equilibria.
fn paper_tangents() -> Vec<(String, BlockTridiagonal)> {
    use holewall::solve::statics::{constrained_tangent, solve_static, StaticOptions};
    ["paper_one_stabilizer.toml", "paper_three_stabilizers.toml"]
        .iter()
        .map(|name| {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("cases")
                .join(name);
            let case = holewall::case::load_case(&path).unwrap();
            let sol = solve_static(&case.model, &StaticOptions::default()).unwrap();
            (
                name.to_string(),
                constrained_tangent(&case.model, &sol.state, 1.0),
            )
        })
        .collect()
}

/// The paper tangents, each with a random right-hand side.
fn paper_systems(rng: &mut rand::rngs::StdRng) -> Vec<(String, BlockTridiagonal, Vec<f64>)> {
    paper_tangents()
        .into_iter()
        .map(|(name, a)| {
            let b = (0..6 * a.nodes())
                .map(|_| rng.random_range(-1e4..1e4))
                .collect();
            (name, a, b)
        })
        .collect()
}

#[test]
fn twin_matches_faer_on_paper_tangents_and_random_systems() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let mut systems = paper_systems(&mut rng);
    for k in 0..8 {
        let (a, b) = BlockTridiagonal::random_dominant(&mut rng, 40, 3);
        systems.push((format!("random {k}"), a, b));
    }
    for (name, a, b) in &systems {
        let reference = ChainSolver::new().solve_sparse(a, b).unwrap();
        let batch = ChainBatch::<f64>::from_systems(&[(a, b.as_slice())]);
        let (x, status) = block_lu(&batch);
        assert_eq!(status, vec![SOLVED]);
        let res = relative_residual(a, &x, b);
        let res_faer = relative_residual(a, &reference, b);
        let err = relative_error(&x, &reference);
        eprintln!(
            "{name}: {} nodes, relative residual {res:.2e} (faer {res_faer:.2e}), difference from faer {err:.2e}",
            a.nodes()
        );
        assert!(res <= 1e-10, "{name}: residual {res:e}");
        assert!(err <= 1e-8, "{name}: differs from faer by {err:e}");
        // The CPU solvers' walk on the node-major system (no packing, no other thread):
        // the twin's numbers bit for bit, and a singular system singular.
        let (one, one_status) = block_lu_one(a, b);
        assert_eq!(one_status, SOLVED, "{name}");
        assert!(
            one.iter().zip(&x).all(|(p, q)| p.to_bits() == q.to_bits()),
            "{name}: block_lu_one differs from the twin"
        );
        let cpu = ChainSolver::new().solve(a, b).unwrap();
        assert!(cpu.iter().zip(&x).all(|(p, q)| p.to_bits() == q.to_bits()));
        let mut singular = a.clone();
        singular.diag[a.nodes() / 2] = [[0.0; 6]; 6];
        singular.lower[a.nodes() / 2 - 1] = [[0.0; 6]; 6];
        assert_eq!(block_lu_one(&singular, b).1, SINGULAR, "{name}");
    }
}

#[test]
fn gpu_matches_the_twin_on_the_paper_tangents() {
    // 247 and 255 nodes: more than one dispatch pass (llvmpipe ends loops after 65,535
    // iterations; a single-pass kernel returned zeros beyond ≈ 110 nodes).
    let Some(ctx) = common::gpu() else { return };
    if !ctx.has_f64 {
        return;
    }
    for (name, a) in paper_tangents() {
        let b: Vec<f64> = (0..6 * a.nodes())
            .map(|k| (k as f64 * 0.37).sin() * 1e4)
            .collect();
        let batch = ChainBatch::<f64>::from_systems(&[(&a, b.as_slice()), (&a, b.as_slice())]);
        let (cpu, st) = block_lu(&batch);
        let (gpu, gst) = block_lu_gpu(ctx, &batch).unwrap();
        assert_eq!((st.clone(), gst), (vec![SOLVED; 2], st));
        let err = relative_error(&batch.unpack(&gpu, 1), &batch.unpack(&cpu, 1));
        eprintln!("{name}: GPU f64 vs twin {err:.2e}");
        assert!(err <= 1e-12, "{name}: {err:e}");
    }
}

#[test]
fn gpu_matches_the_twin_and_a_singular_variant_fails_alone() {
    let Some(ctx) = common::gpu() else { return };
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let n = 30;
    let sys: Vec<(BlockTridiagonal, Vec<f64>)> = (0..64)
        .map(|_| BlockTridiagonal::random_dominant(&mut rng, n, 0))
        .collect();
    let refs: Vec<(&BlockTridiagonal, &[f64])> =
        sys.iter().map(|(a, b)| (a, b.as_slice())).collect();
    let b64 = ChainBatch::<f64>::from_systems(&refs);
    let (cpu, st) = block_lu(&b64);
    assert!(st.iter().all(|&s| s == SOLVED));
    if ctx.has_f64 {
        let (gpu, gst) = block_lu_gpu(ctx, &b64).unwrap();
        assert_eq!(gst, st);
        let mut worst: f64 = 0.0;
        for j in 0..64 {
            worst = worst.max(relative_error(&b64.unpack(&gpu, j), &b64.unpack(&cpu, j)));
        }
        eprintln!("GPU f64 vs twin: worst relative difference {worst:.2e}");
        assert!(worst <= 1e-12);
        // Both forms (serial, six lanes per variant) are the twin's operations: the same
        // bits, also chunked (to the twin's bound where the driver fuses multiply-adds).
        for form in [LuForm::Serial, LuForm::Lanes] {
            let (x, s) = block_lu_gpu_form(ctx, &b64, usize::MAX, form).unwrap();
            assert_eq!(s, gst, "{form:?}");
            common::assert_same(ctx, &x, &gpu, relative_error, 1e-12, &format!("{form:?}"));
            let (x, _) = block_lu_gpu_form(ctx, &b64, 5, form).unwrap();
            common::assert_same(
                ctx,
                &x,
                &gpu,
                relative_error,
                1e-12,
                &format!("{form:?} in chunks of 5"),
            );
        }
        // Batched dispatches (7 variants each) give the same numbers: the same kernel on the
        // same data, so the same bits on any driver.
        let (chunked, _) = block_lu_gpu_chunked(ctx, &b64, 7).unwrap();
        assert_eq!(chunked, gpu);
    }
    // f32: error against the f64 solution, bounded by the conditioning.
    let b32 = ChainBatch::<f32>::from_systems(&refs);
    let (gpu32, st32) = block_lu_gpu(ctx, &b32).unwrap();
    let (cpu32, _) = block_lu(&b32);
    assert!(st32.iter().all(|&s| s == SOLVED));
    let mut worst_gpu: f64 = 0.0;
    let mut worst_cpu: f64 = 0.0;
    let mut worst_bound: f64 = 0.0;
    let mut bounds = Vec::new();
    for (j, (a, _)) in sys.iter().enumerate() {
        let exact = b64.unpack(&cpu, j);
        let g: Vec<f64> = b32.unpack(&gpu32, j).iter().map(|&x| x as f64).collect();
        let c: Vec<f64> = b32.unpack(&cpu32, j).iter().map(|&x| x as f64).collect();
        let dense = a.to_dense();
        let kappa = dense.norm() * dense.clone().try_inverse().unwrap().norm();
        let bound = 8.0 * f32::EPSILON as f64 * kappa;
        let eg = relative_error(&g, &exact);
        worst_gpu = worst_gpu.max(eg / bound);
        worst_cpu = worst_cpu.max(relative_error(&c, &exact) / bound);
        worst_bound = worst_bound.max(bound);
        bounds.push(bound);
        assert!(
            eg <= bound,
            "variant {j}: f32 error {eg:e} beyond 8·u·κ_F = {bound:e}"
        );
    }
    eprintln!(
        "f32: worst error / (8·u₃₂·κ_F): GPU {worst_gpu:.2e}, CPU twin {worst_cpu:.2e} (largest bound {worst_bound:.2e})"
    );
    // A singular variant (a zero diagonal block row) and a NaN one fail alone.
    let mut bad = sys.clone();
    bad[5].0.diag[3] = [[0.0; 6]; 6];
    bad[5].0.upper[3] = [[0.0; 6]; 6];
    bad[5].0.lower[2] = [[0.0; 6]; 6];
    bad[9].0.diag[0][0][0] = f64::NAN;
    let refs_bad: Vec<(&BlockTridiagonal, &[f64])> =
        bad.iter().map(|(a, b)| (a, b.as_slice())).collect();
    let bb = ChainBatch::<f64>::from_systems(&refs_bad);
    let (cpu_bad, st_bad) = block_lu(&bb);
    assert_eq!((st_bad[5], st_bad[9]), (SINGULAR, SINGULAR));
    for j in (0..64).filter(|j| *j != 5 && *j != 9) {
        assert_eq!(st_bad[j], SOLVED);
        assert_eq!(
            bb.unpack(&cpu_bad, j),
            b64.unpack(&cpu, j),
            "twin variant {j}"
        );
    }
    for form in [LuForm::Serial, LuForm::Lanes] {
        if !ctx.has_f64 {
            break;
        }
        let (gpu_bad64, gst64) = block_lu_gpu_form(ctx, &bb, usize::MAX, form).unwrap();
        assert_eq!(gst64, st_bad, "GPU f64 ({form:?}) flags the same variants");
        for j in (0..64).filter(|j| *j != 5 && *j != 9) {
            common::assert_same(
                ctx,
                &bb.unpack(&gpu_bad64, j),
                &bb.unpack(&cpu_bad, j),
                relative_error,
                1e-12,
                &format!("GPU f64 variant {j}"),
            );
        }
    }
    let bb32 = ChainBatch::<f32>::from_systems(&refs_bad);
    // f32: the two forms give the same bits (where the driver fuses multiply-adds, each
    // within the f32 bound 8·u·κ_F of the f64 solution, as the adapter's form above).
    for form in [LuForm::Serial, LuForm::Lanes] {
        let (x, s) = block_lu_gpu_form(ctx, &b32, usize::MAX, form).unwrap();
        assert_eq!(s, st32, "f32 {form:?}");
        if common::fuses(ctx) {
            for (j, bound) in bounds.iter().enumerate() {
                let g: Vec<f64> = b32.unpack(&x, j).iter().map(|&y| y as f64).collect();
                let e = relative_error(&g, &b64.unpack(&cpu, j));
                assert!(e <= *bound, "f32 {form:?} variant {j}: {e:e} > {bound:e}");
            }
        } else {
            assert_eq!(x, gpu32, "f32 {form:?}");
        }
        let (xb, sb) = block_lu_gpu_form(ctx, &bb32, usize::MAX, form).unwrap();
        assert_eq!((sb[5], sb[9]), (SINGULAR, SINGULAR), "f32 {form:?}");
        assert_eq!(
            bb32.unpack(&xb, 0),
            b32.unpack(&x, 0),
            "f32 {form:?}: a good variant beside singular ones"
        );
    }
    let (gpu_bad, gst_bad) = block_lu_gpu(ctx, &bb32).unwrap();
    assert_eq!((gst_bad[5], gst_bad[9]), (SINGULAR, SINGULAR));
    for j in (0..64).filter(|j| *j != 5 && *j != 9) {
        assert_eq!(gst_bad[j], SOLVED);
        assert_eq!(
            bb32.unpack(&gpu_bad, j),
            b32.unpack(&gpu32, j),
            "GPU variant {j}"
        );
    }
}

/// The cyclic reduction's twin against faer and the chain walk: the paper tangents, random
/// systems spanning six decades, and every chain length around the powers of two (the
/// levels' edge cases: a node without a right neighbour, node 0 alone).
#[test]
fn cyclic_reduction_twin_matches_faer_at_every_length() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(17);
    let mut systems = paper_systems(&mut rng);
    for n in [1, 2, 3, 4, 5, 7, 8, 9, 15, 16, 17, 31, 33, 64, 65, 100, 129] {
        let (a, b) = BlockTridiagonal::random_dominant(&mut rng, n, 3);
        systems.push((format!("random, {n} nodes"), a, b));
    }
    for (name, a, b) in &systems {
        let reference = ChainSolver::new().solve_sparse(a, b).unwrap();
        let batch = ChainBatch::<f64>::from_systems(&[(a, b.as_slice())]);
        let (x, status) = block_cr(&batch);
        assert_eq!(status, vec![SOLVED], "{name}");
        let (walk, _) = block_lu(&batch);
        let res = relative_residual(a, &x, b);
        let err = relative_error(&x, &reference);
        let err_walk = relative_error(&walk, &reference);
        eprintln!(
            "{name}: cyclic residual {res:.2e}, from faer {err:.2e} (the walk {err_walk:.2e})"
        );
        assert!(res <= 1e-10, "{name}: residual {res:e}");
        assert!(err <= 1e-8, "{name}: differs from faer by {err:e}");
    }
}

/// The cyclic form on the GPU against its twin (f64: to rounding; f32: the twin's bits, or
/// within 8·u·κ of the f64 solution where the driver fuses), chunked, on the paper tangents
/// (247 and 255 nodes: eight levels), and a singular or NaN variant failing alone.
#[test]
fn cyclic_reduction_on_the_gpu_matches_its_twin_and_a_singular_variant_fails_alone() {
    let Some(ctx) = common::gpu() else { return };
    let mut rng = rand::rngs::StdRng::seed_from_u64(23);
    for n in [1, 2, 3, 6, 30, 33] {
        let sys: Vec<(BlockTridiagonal, Vec<f64>)> = (0..64)
            .map(|_| BlockTridiagonal::random_dominant(&mut rng, n, 0))
            .collect();
        let refs: Vec<(&BlockTridiagonal, &[f64])> =
            sys.iter().map(|(a, b)| (a, b.as_slice())).collect();
        let b64 = ChainBatch::<f64>::from_systems(&refs);
        let (twin, st) = block_cr(&b64);
        assert!(st.iter().all(|&s| s == SOLVED));
        if ctx.has_f64 {
            let (x, s) = block_lu_gpu_form(ctx, &b64, usize::MAX, LuForm::Cyclic).unwrap();
            assert_eq!(s, st, "{n} nodes");
            common::assert_same(
                ctx,
                &x,
                &twin,
                relative_error,
                1e-12,
                &format!("f64, {n} nodes"),
            );
            let (xc, _) = block_lu_gpu_form(ctx, &b64, 5, LuForm::Cyclic).unwrap();
            assert_eq!(xc, x, "f64, {n} nodes, in chunks of 5");
        }
        let b32 = ChainBatch::<f32>::from_systems(&refs);
        let (twin32, _) = block_cr(&b32);
        let (x32, s32) = block_lu_gpu_form(ctx, &b32, usize::MAX, LuForm::Cyclic).unwrap();
        assert!(s32.iter().all(|&s| s == SOLVED), "f32, {n} nodes");
        if common::fuses(ctx) {
            for (j, (a, _)) in sys.iter().enumerate() {
                let dense = a.to_dense();
                let kappa = dense.norm() * dense.clone().try_inverse().unwrap().norm();
                let bound = 8.0 * f32::EPSILON as f64 * kappa;
                let g: Vec<f64> = b32.unpack(&x32, j).iter().map(|&y| y as f64).collect();
                let e = relative_error(&g, &b64.unpack(&twin, j));
                assert!(e <= bound, "f32, {n} nodes, variant {j}: {e:e} > {bound:e}");
            }
        } else {
            assert_eq!(x32, twin32, "f32, {n} nodes");
        }
    }
    if ctx.has_f64 {
        for (name, a) in paper_tangents() {
            let b: Vec<f64> = (0..6 * a.nodes())
                .map(|k| (k as f64 * 0.37).sin() * 1e4)
                .collect();
            let batch = ChainBatch::<f64>::from_systems(&[(&a, b.as_slice()), (&a, b.as_slice())]);
            let (twin, _) = block_cr(&batch);
            let (gpu, st) = block_lu_gpu_form(ctx, &batch, usize::MAX, LuForm::Cyclic).unwrap();
            assert_eq!(st, vec![SOLVED; 2]);
            let err = relative_error(&batch.unpack(&gpu, 1), &batch.unpack(&twin, 1));
            eprintln!("{name}: cyclic GPU f64 vs its twin {err:.2e}");
            assert!(err <= 1e-12, "{name}: {err:e}");
        }
    }
    // A zero block row at node 3 (odd: eliminated at the first level) and a NaN at node 0
    // (solved last): those two variants fail, with a zero solution; the others keep their bits.
    let n = 30;
    let sys: Vec<(BlockTridiagonal, Vec<f64>)> = (0..16)
        .map(|_| BlockTridiagonal::random_dominant(&mut rng, n, 0))
        .collect();
    let mut bad = sys.clone();
    bad[5].0.diag[3] = [[0.0; 6]; 6];
    bad[5].0.upper[3] = [[0.0; 6]; 6];
    bad[5].0.lower[2] = [[0.0; 6]; 6];
    bad[9].0.diag[0][0][0] = f64::NAN;
    let refs: Vec<(&BlockTridiagonal, &[f64])> =
        sys.iter().map(|(a, b)| (a, b.as_slice())).collect();
    let refs_bad: Vec<(&BlockTridiagonal, &[f64])> =
        bad.iter().map(|(a, b)| (a, b.as_slice())).collect();
    fn check<T: holewall::gpu::contact::GpuReal + holewall::physics::Real>(
        ctx: &'static holewall::gpu::GpuContext,
        good: &ChainBatch<T>,
        bad: &ChainBatch<T>,
    ) {
        let (twin, _) = block_cr(bad);
        let (x, st) = block_lu_gpu_form(ctx, bad, usize::MAX, LuForm::Cyclic).unwrap();
        let (xg, _) = block_lu_gpu_form(ctx, good, usize::MAX, LuForm::Cyclic).unwrap();
        assert_eq!(block_cr(bad).1, st, "the twin flags the same variants");
        for (j, &sj) in st.iter().enumerate() {
            if j == 5 || j == 9 {
                assert_eq!(sj, SINGULAR, "variant {j}");
                assert!(bad.unpack(&x, j).iter().all(|&y| y == T::zero()));
                assert!(bad.unpack(&twin, j).iter().all(|&y| y == T::zero()));
            } else {
                assert_eq!(sj, SOLVED, "variant {j}");
                assert_eq!(bad.unpack(&x, j), good.unpack(&xg, j), "variant {j}");
            }
        }
    }
    if ctx.has_f64 {
        check(
            ctx,
            &ChainBatch::<f64>::from_systems(&refs),
            &ChainBatch::<f64>::from_systems(&refs_bad),
        );
    }
    check(
        ctx,
        &ChainBatch::<f32>::from_systems(&refs),
        &ChainBatch::<f32>::from_systems(&refs_bad),
    );
}
