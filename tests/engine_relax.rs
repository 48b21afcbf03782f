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
