//! `holewall gpu-info`: adapters, their features and limits, and a GPU-vs-CPU self-check
//! of the contact kernel on random states.

use crate::error::Error;
use crate::gpu::{list_adapters, GpuContext};
use crate::physics::contact::{ContactMode, ContactTerms, FrictionModel};
use crate::selfcheck::{contact_comparison, F32_BOUND, F64_BOUND};

/// Runs the command.
pub fn run(pairs: usize) -> Result<(), Error> {
    let adapters = list_adapters();
    if adapters.is_empty() {
        println!("NO GPU ADAPTER: wgpu sees no adapter (install a Vulkan driver, e.g. Mesa's lavapipe: apt-get install mesa-vulkan-drivers libvulkan1).");
    }
    for (k, a) in adapters.iter().enumerate() {
        println!(
            "adapter {k}: {} ({:?}, {:?})",
            a.info.name, a.info.backend, a.info.device_type
        );
        println!("  driver: {} {}", a.info.driver, a.info.driver_info);
        println!(
            "  SHADER_F64: {}",
            a.features.contains(wgpu::Features::SHADER_F64)
        );
        println!("  features: {:?}", a.features);
        let l = &a.limits;
        println!(
            "  limits: max_storage_buffer_binding_size {} B, max_buffer_size {} B, max_compute_workgroups_per_dimension {}, max_compute_invocations_per_workgroup {}, max_compute_workgroup_storage_size {} B",
            l.max_storage_buffer_binding_size,
            l.max_buffer_size,
            l.max_compute_workgroups_per_dimension,
            l.max_compute_invocations_per_workgroup,
            l.max_compute_workgroup_storage_size
        );
    }
    let ctx = GpuContext::shared()?;
    println!(
        "\nfused multiply-add (a·b + c contracted to one rounding): {}",
        if ctx.fuses_multiply_add()? {
            "yes — kernels agree with their twins to rounding, not to the bit"
        } else {
            "no"
        }
    );
    println!(
        "\nself-check on {} with {pairs} random (variant, site) pairs per configuration:",
        ctx.describe()
    );
    println!(
        "{:<18} {:>11} {:>11} {:>11} {:>15} {:>11} {:>11} {:>11}",
        "configuration",
        "f64 max rel",
        "f64 err/uκ",
        "f32 err/uκ",
        "f32 med/99%",
        "CPU f64/s",
        "GPU f32/s",
        "GPU f64/s"
    );
    let mut failed = false;
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        for mode in [ContactMode::Dynamic, ContactMode::Static] {
            let terms = ContactTerms::all(friction, mode);
            let c = contact_comparison(ctx, &terms, pairs, 3)?;
            let s32 = &c.f32_stats;
            let (rel64, ratio64) = match &c.f64_stats {
                Some(s) => {
                    failed |= s.over_bound > 0 || s.flag_mismatches > 0;
                    (
                        format!("{:.2e}", s.max_normwise),
                        format!("{:.2}", s.max_ratio),
                    )
                }
                None => ("n/a".into(), "n/a".into()),
            };
            failed |= s32.over_bound > 0 || s32.flag_mismatches > 0;
            println!(
                "{:<18} {:>11} {:>11} {:>11.2} {:>15} {:>11.3e} {:>11.3e} {:>11}",
                format!("{friction:?}/{mode:?}"),
                rel64,
                ratio64,
                s32.max_ratio,
                format!(
                    "{:.1e}/{:.1e}",
                    s32.scaled_quantile(0.5),
                    s32.scaled_quantile(0.99)
                ),
                c.evals_per_s_cpu_f64,
                c.evals_per_s_gpu_f32,
                c.evals_per_s_gpu_f64
                    .map(|x| format!("{x:.3e}"))
                    .unwrap_or_else(|| "n/a".into())
            );
        }
    }
    println!(
        "f64 max rel: largest normwise relative error against the CPU f64 twin over pairs in contact (per quantity, relative to\n\
         the larger of the block and its natural scale);\n\
         err/uκ: error relative to each quantity's natural scale, over unit roundoff × condition number;\n\
         bounds {F64_BOUND} (f64) and {F32_BOUND} (f32), on pairs with u·κ ≤ 1e-3 (docs/contact-element.md, Accuracy);\n\
         f32 med/99%: median and 99th percentile of the f32 error relative to the natural scale."
    );
    if failed {
        return Err(Error::Gpu(crate::error::GpuError::Device(
            "self-check FAILED: a GPU result is outside its error bound or a contact flag differs"
                .into(),
        )));
    }
    println!("self-check passed.");
    Ok(())
}
