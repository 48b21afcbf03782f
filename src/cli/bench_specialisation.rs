//! `holewall bench specialisation`: the scene-specialised contact kernels against the
//! all-terms kernel on the same scenes. (Moved from `cli/bench.rs`, issue 24: no file over
//! 800 lines.)

use crate::backend::{Backend, BackendChoice, Precision};
use crate::error::Error;
use crate::gpu::contact::{GpuContactRun, GpuReal};
use crate::gpu::GpuContext;
use crate::kernels::contact::{contact as contact_twin, ContactBatch, ContactOutputs};
use crate::physics::contact::{ContactMode, ContactTerms, FrictionModel};
use crate::selfcheck::{median_seconds, random_batch};
use serde::Serialize;
use std::path::Path;

/// One scene of `holewall bench specialisation`.
#[derive(Serialize)]
struct SpecialisationRow {
    scene: String,
    path: String,
    specialised_s: f64,
    all_terms_s: f64,
    gain: f64,
    max_abs_difference: f64,
}

/// The scene-specialised contact kernels against the all-terms kernel on the same scenes
/// (issue 16, part 5): per scene the inputs the scene allows (frictionless: μ = 0; linear:
/// m = 1; static: no wall damping), the kernel its terms select
/// ([`ContactBatch::required_terms`]) and the all-terms kernel, timed in the same run
/// (medians), on the CPU twin (f64) and the GPU (f32 and f64, data resident), and the
/// largest difference of their outputs.
pub fn specialisation(pairs: usize, repeats: usize, json: Option<&Path>) -> Result<(), Error> {
    let num_variants = 1000.min(pairs.max(1));
    let scenes: [(&str, ContactMode, Option<FrictionModel>); 4] = [
        ("frictionless, linear, static", ContactMode::Static, None),
        ("frictionless, linear, dynamic", ContactMode::Dynamic, None),
        (
            "split friction, linear, static",
            ContactMode::Static,
            Some(FrictionModel::Split),
        ),
        (
            "split friction, linear, dynamic",
            ContactMode::Dynamic,
            Some(FrictionModel::Split),
        ),
    ];
    let gpu = match Backend::resolve(BackendChoice::Auto, Precision::F32)? {
        (Backend::Gpu(ctx), _) => Some(ctx),
        (Backend::Cpu, note) => {
            if let Some(n) = note {
                eprintln!("holewall: {n}");
            }
            None
        }
    };
    let mut rows = Vec::new();
    for (scene, mode, friction) in scenes {
        let mut batch = random_batch(
            7,
            num_variants,
            pairs.div_ceil(num_variants),
            friction.unwrap_or(FrictionModel::Split),
        );
        for i in 0..batch.num_pairs() {
            let mut p = batch.params(i);
            p.spring_exponent = 1.0;
            if friction.is_none() {
                p.mu_t = 0.0;
                p.mu_l = 0.0;
            }
            if mode == ContactMode::Static {
                p.wall_damping = 0.0;
            }
            batch.set_params(i, &p);
        }
        let lean = batch.required_terms(friction.unwrap_or(FrictionModel::Split), mode);
        let all = ContactTerms::all(friction.unwrap_or(FrictionModel::Split), mode);
        let p = batch.num_pairs();
        let (mut a, mut b) = (ContactOutputs::new(p), ContactOutputs::new(p));
        let ts = median_seconds::<Error>(repeats, || {
            contact_twin(&lean, &batch, &mut a);
            Ok(())
        })?;
        let ta = median_seconds::<Error>(repeats, || {
            contact_twin(&all, &batch, &mut b);
            Ok(())
        })?;
        let diff = (0..p).fold(0.0f64, |m, i| {
            a.fields(i)
                .iter()
                .zip(b.fields(i))
                .fold(m, |m, (x, y)| m.max((x - y).abs()))
        });
        rows.push(SpecialisationRow {
            scene: scene.into(),
            path: "CPU f64 (twin)".into(),
            specialised_s: ts,
            all_terms_s: ta,
            gain: ta / ts,
            max_abs_difference: diff,
        });
        if let Some(ctx) = gpu {
            rows.push(gpu_specialisation(
                ctx,
                scene,
                &lean,
                &all,
                &batch.cast::<f32>(),
                repeats,
            )?);
            if ctx.has_f64 {
                rows.push(gpu_specialisation(
                    ctx, scene, &lean, &all, &batch, repeats,
                )?);
            }
        }
    }
    println!(
        "scene-specialised contact kernels against the all-terms kernel, {} pairs, median of {repeats}; adapter: {}",
        pairs,
        gpu.map_or("none".into(), |c| c.describe())
    );
    println!(
        "| scene | path | specialised (s) | all terms (s) | gain | largest output difference |"
    );
    println!("|---|---|---|---|---|---|");
    for r in &rows {
        println!(
            "| {} | {} | {:.3e} | {:.3e} | {:.2}× | {:.1e} |",
            r.scene, r.path, r.specialised_s, r.all_terms_s, r.gain, r.max_abs_difference
        );
    }
    if let Some(path) = json {
        crate::output::write_json_atomic(path, &rows)?;
    }
    Ok(())
}

fn gpu_specialisation<T: GpuReal>(
    ctx: &'static GpuContext,
    scene: &str,
    lean: &ContactTerms,
    all: &ContactTerms,
    batch: &ContactBatch<T>,
    repeats: usize,
) -> Result<SpecialisationRow, Error> {
    let rs = GpuContactRun::new(ctx, lean, batch)?;
    let ra = GpuContactRun::new(ctx, all, batch)?;
    let ts = median_seconds(repeats, || rs.dispatch())?;
    let ta = median_seconds(repeats, || ra.dispatch())?;
    let (a, b) = (rs.read()?, ra.read()?);
    let diff = (0..batch.num_pairs()).fold(0.0f64, |m, i| {
        a.fields(i).iter().zip(b.fields(i)).fold(m, |m, (x, y)| {
            m.max((x.to_f64_lossy() - y.to_f64_lossy()).abs())
        })
    });
    Ok(SpecialisationRow {
        scene: scene.into(),
        path: format!("GPU {} resident", T::NAME),
        specialised_s: ts,
        all_terms_s: ta,
        gain: ta / ts,
        max_abs_difference: diff,
    })
}
