//! The dynamic ensemble through the kernels against the CPU integrator
//! (`solve::dynamics::Dynamics`), step for step; the GPU path against the twin path; the
//! dynamic kernels against their twins.
#![allow(clippy::needless_range_loop)]

mod common;

use holewall::engine::dynamic::{run_dynamic_ensemble, DynamicStatus};
use holewall::engine::{GpuPath, TwinPath};
use holewall::ensemble::{apply, variants_from_csv_text};
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
                    .map(|(i, k)| st.q.x[i][k] - m.nodes[i].position[k])
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
    let variants = variants_from_csv_text("v.csv", csv).unwrap();
    let models: Vec<Model> = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
    let starts = models
        .iter()
        .map(|m| solve_static(m, &StaticOptions::default()).unwrap().state)
        .collect();
    (case, models, starts)
}

#[test]
fn dynamic_ensemble_matches_the_cpu_integrator_step_for_step() {
    let (case, models, starts) = bed_variants(
        "mu,wob,rpm,k_e\n0.3,20 kN,120 rpm,6e7\n0.2,15 kN,90 rpm,1e8\n0.4,25 kN,150 rpm,6e7\n",
    );
    let settings = case.dynamics.clone().unwrap();
    let mut options = holewall::cli::run_cmd::options_for(&settings);
    options.rayleigh = (0.5, 0.0);
    let t_end = 0.04;
    let cpu = cpu_runs(&models, &starts, &case.element_density, &options, t_end);
    let (v, n) = (models.len(), models[0].nodes.len());
    let mut seen = Vec::new();
    let twin = run_dynamic_ensemble(
        &models,
        &starts,
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
            &starts,
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
}
