//! The relaxation past a fold (issue 22, `solve::continuation`'s `Stage::Relax`) through
//! the ensemble engine: the proximal shift in the assembly kernel (built `SHIFT`) against
//! its twin, and whole solves that relax on every engine path against the CPU solve.
//!
//! A fold is forced on the 60 m test bed by a load path that may not cut its steps (one
//! step, smallest step 1) with few Newton iterations per step: the gravity stage and the
//! load step fail where the CPU solve and the engine would otherwise take them in steps,
//! and both relax to the same equilibrium.

mod common;

use holewall::engine::{solve_static_ensemble, EngineStatus, TwinPath};
use holewall::gpu::GpuPath;
use holewall::model::Model;
use holewall::solve::continuation::RELAXED;
use holewall::solve::statics::{residual_measure_at, solve_static, StaticOptions, StaticState};

/// A load path that relaxes where a step takes more than `iterations` Newton iterations.
fn forced(iterations: usize) -> StaticOptions {
    StaticOptions {
        initial_steps: 1,
        min_step: 1.0,
        max_iterations: iterations,
        ..Default::default()
    }
}

/// Three variants of the test bed: friction 0.3, 0.1 and 0.5 (the engine's chunks share
/// the mesh).
fn models() -> Vec<Model> {
    ["0.3", "0.1", "0.5"]
        .iter()
        .map(|mu| {
            holewall::case::parse_case(
                std::path::Path::new("bed.toml"),
                &common::bed_text(mu, "8.25 in", "6e7", "1.5", "1e-3"),
            )
            .unwrap()
            .model
        })
        .collect()
}

/// Largest translation difference between two states (m).
fn largest_difference(a: &StaticState, b: &StaticState) -> f64 {
    a.u.iter()
        .zip(&b.u)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn forced_folds_relax_on_every_engine_path_to_the_cpu_equilibrium() {
    let models = models();
    let options = forced(6);
    let cpu: Vec<_> = models
        .iter()
        .map(|m| solve_static(m, &options).expect("the CPU solve relaxes past the forced fold"))
        .collect();
    for (j, sol) in cpu.iter().enumerate() {
        assert!(
            sol.log.iter().any(|l| l.contains(RELAXED)),
            "variant {j}: the forced path should relax on the CPU: {:?}",
            sol.log
        );
    }
    // Per path: the largest difference from the CPU's state (m) and the f64 residual the
    // answer may keep (f64: the solve's tolerance; f32: the floor `engine::verify_f32`
    // holds it to, `1e4 ε₃₂`).
    let f32_floor = 1e4 * holewall::solve::newton::unit_roundoff(4);
    let mut paths: Vec<(&str, f64, f64)> = vec![("twin", 1e-9, options.tolerance)];
    let gpu = common::gpu();
    if let Some(ctx) = gpu {
        if ctx.has_f64 {
            paths.push(("gpu f64", 1e-9, options.tolerance));
        }
        paths.push(("gpu f32", 1e-5, f32_floor));
    }
    for (name, tol, floor) in paths {
        let results = match (name, gpu) {
            ("twin", _) => solve_static_ensemble(&models, &TwinPath, &options),
            ("gpu f64", Some(ctx)) => {
                solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options)
            }
            (_, Some(ctx)) => solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options),
            _ => unreachable!(),
        }
        .unwrap();
        for (j, (r, sol)) in results.iter().zip(&cpu).enumerate() {
            assert_eq!(
                r.status,
                EngineStatus::Converged,
                "{name} variant {j}: {:?}",
                r.log
            );
            assert!(
                r.log.iter().any(|l| l.contains(RELAXED)),
                "{name} variant {j}: the engine should relax as the CPU does: {:?}",
                r.log
            );
            let measure = residual_measure_at(&models[j], &r.state);
            let diff = largest_difference(&r.state, &sol.state);
            eprintln!(
                "{name} variant {j}: {} iterations (CPU {}), f64 residual {measure:.2e}, largest difference from the CPU {diff:.2e} m; {}",
                r.iterations.iter().sum::<usize>(),
                sol.iterations.iter().sum::<usize>(),
                r.log.last().map(String::as_str).unwrap_or_default()
            );
            assert!(
                measure <= floor,
                "{name} variant {j}: f64 residual {measure:e} above {floor:e}"
            );
            assert!(diff <= tol, "{name} variant {j}: {diff:e} m from the CPU's");
        }
    }
}

/// A relaxation whose translational shift passes its ceiling starts again with the
/// rotations shifted too on the engine as on the CPU (the assembly built `SHIFT` adds
/// `s_r log(R R_aᵀ)` to the moments; `solve::continuation`'s `RELAX_ROTATION_SHIFT`).
/// Unseen user well 3163 (horizontal, 4,767 m, a 1.66° motor 1.4 m above the bit, 1 m BHA
/// elements) ends its relaxation at the ceiling after 12 sub-solves at 30 and 35 m pipe
/// elements without it (docs/performance.md, stops 87 and 90); the CPU solves both so.
/// Which path reaches the ceiling at which mesh is the rounding's: measured, the twin does
/// at 30 m (it failed there before) and lavapipe's GPU f64 at 35 m (it failed there
/// before). Each must solve to the CPU's hook load; the twin (f64 on the CPU, as the CPU
/// solve) and lavapipe must say they shifted the rotations (another device's rounding
/// may take another path: reported).
#[test]
fn a_relaxation_at_its_ceiling_shifts_the_rotations_on_the_engine_too() {
    use holewall::solve::continuation::rotations_shifted;
    let dir = common::scratch_dir("rotations", "3163");
    let drawn =
        holewall::corpus::write_corpus_well(holewall::corpus::CorpusStyle::User, 3163, &dir)
            .unwrap();
    let options = StaticOptions::default();
    let gpu = common::gpu();
    let mut paths = vec![("twin", 30.0)];
    if gpu.is_some_and(|ctx| ctx.has_f64) {
        paths.push(("gpu f64", 35.0));
    }
    for (name, element) in paths {
        let well = holewall::corpus::remesh(&drawn, element, 1.0).unwrap();
        let model = holewall::case::load_case(&well.case_path).unwrap().model;
        let cpu = solve_static(&model, &options).expect("the CPU solve shifts the rotations");
        assert!(
            rotations_shifted(&cpu.log),
            "{element} m: the CPU should shift the rotations: {:?}",
            cpu.log
        );
        let want = holewall::profile::fe_rows(&model, &cpu).1;
        let models = [model.clone()];
        let results = match (name, gpu) {
            ("gpu f64", Some(ctx)) => {
                solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options)
            }
            _ => solve_static_ensemble(&models, &TwinPath, &options),
        }
        .unwrap();
        let r = results.into_iter().next().unwrap();
        assert_eq!(r.status, EngineStatus::Converged, "{name}: {:?}", r.log);
        let shifted = rotations_shifted(&r.log);
        let iterations = r.iterations.iter().sum::<usize>();
        let log = r.log.clone();
        let sol = r.into_solution(&model).unwrap();
        let got = holewall::profile::fe_rows(&model, &sol).1;
        eprintln!(
            "{name} at {element} m: hook load {got:.3} N (CPU {want:.3} N), rotations shifted: {shifted}, {iterations} Newton iterations"
        );
        let lavapipe = gpu.is_some_and(|c| c.describe().contains("llvmpipe"));
        if name == "twin" || lavapipe {
            assert!(shifted, "{name} should shift the rotations: {log:?}");
        }
        assert!(
            (got - want).abs() <= 1e-6 * want.abs(),
            "{name}: hook load {got} N against the CPU's {want} N"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
