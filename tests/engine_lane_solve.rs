//! The engines with the GPU forms of the block solve — the lane walk (`shaders/block_lu.wgsl`,
//! six lanes per variant) and cyclic reduction (`shaders/block_cr.wgsl`, an invocation per
//! node), what real GPUs run (`LuForm::for_batch`) — forced on whatever adapter there is
//! (lavapipe runs the serial walk by default), against the twin path: the static and the
//! dynamic ensemble. Its own test binary, as the forced form holds for the whole process.

mod common;

use holewall::engine::dynamic::{run_dynamic_ensemble, DynamicStatus};
use holewall::engine::{solve_static_ensemble, EngineStatus, TwinPath};
use holewall::ensemble::{apply, variants_from_csv_text};
use holewall::gpu::block_lu::{force_lu_form, LuForm};
use holewall::gpu::GpuPath;
use holewall::kernels::dynamics::DynamicBatch;
use holewall::solve::statics::{solve_static, StaticOptions};

#[test]
fn engines_with_the_gpu_forms_of_the_block_solve_match_the_twin_path() {
    let Some(ctx) = common::gpu() else { return };
    for form in [LuForm::Lanes, LuForm::Cyclic] {
        force_lu_form(Some(form));
        engines_match_the_twin_path(ctx, form);
    }
    force_lu_form(None);
}

fn engines_match_the_twin_path(ctx: &'static holewall::gpu::GpuContext, form: LuForm) {
    let case = common::bed_case("1");
    let variants = variants_from_csv_text(
        "v.csv",
        "mu,wob,k_e\n0.1,5 kN,6e7\n0.3,10 kN,1e8\n0.25,9 kN,2e8\n",
    )
    .unwrap();
    let models: Vec<_> = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
    assert_eq!(LuForm::for_batch(ctx, models[0].nodes.len(), 3), form);
    let options = StaticOptions::default();
    let twin = solve_static_ensemble(&models, &TwinPath, &options).unwrap();
    let precisions: &[bool] = if ctx.has_f64 {
        &[true, false]
    } else {
        &[false]
    };
    for &f64_path in precisions {
        let states: Vec<_> = if f64_path {
            solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options)
                .unwrap()
                .into_iter()
                .map(|r| (r.status, r.state))
                .collect()
        } else {
            solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options)
                .unwrap()
                .into_iter()
                .map(|r| (r.status, r.state))
                .collect()
        };
        let mut diff: f64 = 0.0;
        for ((status, state), t) in states.iter().zip(&twin) {
            assert_eq!(*status, EngineStatus::Converged);
            for (xg, xt) in state.u.iter().zip(&t.state.u) {
                for k in 0..3 {
                    diff = diff.max((xg[k] - xt[k]).abs());
                }
            }
        }
        eprintln!("static, {form:?} form, f64 {f64_path}: largest position difference from the twin path {diff:.2e} m");
        // f32: 3.7e-7 m measured on lavapipe (sag of metres in f32).
        assert!(diff <= if f64_path { 1e-9 } else { 1e-5 }, "{diff:e}");
    }
    // Dynamic: 10 steps of the first two variants from their static equilibria.
    let starts: Vec<_> = models[..2]
        .iter()
        .map(|m| (solve_static(m, &options).unwrap().state, None))
        .collect();
    let settings = case.dynamics.clone().unwrap();
    let dyn_options = settings.integrator_options();
    let t_end = 10.0 * dyn_options.dt;
    let run = |path_f64: bool| -> Vec<DynamicBatch<f64>> {
        let mut seen = Vec::new();
        let results = if path_f64 {
            run_dynamic_ensemble::<f64, _>(
                &models[..2],
                &starts,
                &case.element_density,
                &GpuPath(ctx),
                &dyn_options,
                t_end,
                1,
                &mut |_, _, s: &DynamicBatch<f64>| seen.push(s.clone()),
            )
            .unwrap()
        } else {
            run_dynamic_ensemble(
                &models[..2],
                &starts,
                &case.element_density,
                &TwinPath,
                &dyn_options,
                t_end,
                1,
                &mut |_, _, s: &DynamicBatch<f64>| seen.push(s.clone()),
            )
            .unwrap()
        };
        for r in &results {
            assert_eq!(r.status, DynamicStatus::Finished);
        }
        seen
    };
    if ctx.has_f64 {
        let (gpu, twin) = (run(true), run(false));
        assert_eq!(gpu.len(), twin.len());
        let scale = twin
            .iter()
            .flat_map(|b| &b.u)
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = gpu
            .iter()
            .zip(&twin)
            .flat_map(|(a, b)| a.u.iter().zip(&b.u))
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        eprintln!(
            "dynamic, {form:?} form, f64: displacements {:.2e} of their largest",
            diff / scale
        );
        assert!(diff <= 1e-9 * scale, "{diff:e}");
    }
}
