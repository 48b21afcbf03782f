//! The engines' line-search trials formed several to a submission (issue 27, item 3:
//! `gpu::batch::trials_per_round`, 1 by default), forced on whatever adapter
//! there is, against one trial at a time: the same dynamic run and the same static solve
//! to the bit, with fewer read-backs. Its own test binary, as the forced round holds for
//! the whole process.

mod common;

use holewall::engine::dynamic::{run_dynamic_ensemble, DynamicStatus};
use holewall::ensemble::{apply, variants_from_csv_text};
use holewall::gpu::batch::{force_trials_per_round, trials_per_round};
use holewall::gpu::GpuPath;
use holewall::kernels::dynamics::DynamicBatch;
use holewall::model::Model;
use holewall::solve::statics::{solve_static, StaticOptions};
use holewall::tally::Tally;

/// The forced round and the read-back counts are the process's: one test at a time.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Every variant's state at every output step, bit for bit, and what the run cost.
type Run = (Vec<Vec<u64>>, Vec<DynamicStatus>, Tally);

fn run<T: holewall::physics::Real + holewall::gpu::contact::GpuReal>(
    ctx: &'static holewall::gpu::GpuContext,
    models: &[Model],
    starts: &[holewall::engine::dynamic::DynamicStart],
    density: &[f64],
    options: &holewall::solve::dynamics::DynamicOptions,
    round: usize,
) -> Run {
    force_trials_per_round(Some(round));
    assert_eq!(trials_per_round(), round);
    let before = Tally::now();
    let mut states = Vec::new();
    let status = run_dynamic_ensemble::<T, _>(
        models,
        starts,
        density,
        &GpuPath(ctx),
        options,
        0.03,
        1,
        &mut |_, _, b: &DynamicBatch<T>| {
            states.push(
                b.u.iter()
                    .chain(&b.vel)
                    .chain(&b.vdot)
                    .map(|x| x.to_f64_lossy().to_bits())
                    .collect(),
            )
        },
    )
    .unwrap()
    .into_iter()
    .map(|r| r.status)
    .collect();
    (states, status, Tally::now().since(&before))
}

#[test]
fn trials_formed_in_rounds_give_the_run_of_trials_one_at_a_time() {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = common::gpu() else { return };
    let case = common::bed_case("1");
    // Stiff walls and high speeds: searches that halve (a variant's full Newton step
    // often overshoots its contact's onset).
    let variants = variants_from_csv_text(
        "v.csv",
        "mu,wob,rpm,k_e\n0.1,10 kN,60 rpm,6e7\n0.4,25 kN,150 rpm,1e9\n0.2,15 kN,90 rpm,3e8\n0.5,30 kN,180 rpm,1e9\n0.3,20 kN,120 rpm,6e8\n0.05,5 kN,30 rpm,1e8\n",
    )
    .unwrap();
    let models: Vec<Model> = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
    let starts: Vec<_> = models
        .iter()
        .map(|m| {
            (
                solve_static(m, &StaticOptions::default()).unwrap().state,
                None,
            )
        })
        .collect();
    let options = case.dynamics.clone().unwrap().integrator_options();
    let density = case.element_density.clone();
    let precisions: &[bool] = if ctx.has_f64 {
        &[true, false]
    } else {
        &[false]
    };
    for &f64_path in precisions {
        let go = |round| {
            if f64_path {
                run::<f64>(ctx, &models, &starts, &density, &options, round)
            } else {
                run::<f32>(ctx, &models, &starts, &density, &options, round)
            }
        };
        let (one, status, t1) = go(1);
        assert!(status.iter().all(|s| *s == DynamicStatus::Finished));
        for round in [2, 8] {
            let (states, status_r, t) = go(round);
            eprintln!(
                "f64 {f64_path}, trials per submission 1 → {round}: read-backs {} → {}, trials {} → {}",
                t1.readbacks, t.readbacks, t1.trials, t.trials
            );
            assert_eq!(status_r, status, "f64 {f64_path}, round {round}");
            assert_eq!(states.len(), one.len());
            for (k, (a, b)) in states.iter().zip(&one).enumerate() {
                assert!(
                    a == b,
                    "f64 {f64_path}, round {round}: output step {k} differs"
                );
            }
            // Fewer round trips where some variant searched past the full step; the
            // speculative trials are counted where the adapter stamps its passes.
            assert!(
                t.readbacks < t1.readbacks,
                "{} ≥ {}",
                t.readbacks,
                t1.readbacks
            );
            if ctx.has_timestamps {
                assert!(t.trials > t1.trials);
            }
        }
    }
    force_trials_per_round(None);
}

#[test]
fn static_trials_formed_in_rounds_give_the_solve_of_trials_one_at_a_time() {
    use holewall::engine::{solve_static_ensemble, EngineStatus};
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let Some(ctx) = common::gpu() else { return };
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let case = holewall::case::load_case(&dir.join("stress_two_stabilizers.toml")).unwrap();
    let list =
        holewall::ensemble::case_variants(&case, Some(&dir.join("stress_two_stabilizers.csv")))
            .unwrap()
            .unwrap();
    let models: Vec<Model> = list.iter().map(|v| apply(&case, v).unwrap()).collect();
    let options = StaticOptions::default();
    let precisions: &[bool] = if ctx.has_f64 {
        &[true, false]
    } else {
        &[false]
    };
    for &f64_path in precisions {
        let go = |round| {
            force_trials_per_round(Some(round));
            let before = Tally::now();
            let out: Vec<(EngineStatus, Vec<u64>, Vec<usize>)> = if f64_path {
                solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options)
            } else {
                solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options)
            }
            .unwrap()
            .into_iter()
            .map(|r| {
                let bits = r.state.u.iter().flatten().map(|x| x.to_bits()).collect();
                (r.status, bits, r.iterations)
            })
            .collect();
            (out, Tally::now().since(&before).readbacks)
        };
        let (one, readbacks_one) = go(1);
        assert!(one.iter().all(|r| r.0 == EngineStatus::Converged));
        let (eight, readbacks_eight) = go(8);
        eprintln!(
            "static, f64 {f64_path}: read-backs {readbacks_one} (one trial a submission) → {readbacks_eight} (rounds up to 8)"
        );
        assert!(eight == one, "f64 {f64_path}: the rounds changed the solve");
        assert!(readbacks_eight < readbacks_one);
    }
    force_trials_per_round(None);
}
