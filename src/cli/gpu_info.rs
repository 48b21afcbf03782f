//! `holewall gpu-info`: adapters, their features and limits, and a GPU-vs-CPU self-check
//! of the contact kernel on random states.

use crate::error::Error;
use crate::gpu::{list_adapters, GpuContext};
use crate::physics::contact::{ContactMode, ContactTerms, FrictionModel};
use crate::selfcheck::contact_comparison;

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
        "\nself-check on {} with {pairs} random (variant, site) pairs per configuration:",
        ctx.describe()
    );
    println!(
        "{:<28} {:>14} {:>14} {:>14} {:>14} {:>14}",
        "configuration",
        "max rel f64",
        "max rel f32",
        "CPU f64 ev/s",
        "GPU f32 ev/s",
        "GPU f64 ev/s"
    );
    for friction in [FrictionModel::Split, FrictionModel::Coupled] {
        for mode in [ContactMode::Dynamic, ContactMode::Static] {
            let terms = ContactTerms::all(friction, mode);
            let c = contact_comparison(ctx, &terms, pairs, 3)?;
            let fmt = |x: Option<f64>| {
                x.map(|v| format!("{v:.3e}"))
                    .unwrap_or_else(|| "n/a".into())
            };
            println!(
                "{:<28} {:>14} {:>14} {:>14.3e} {:>14.3e} {:>14}",
                format!("{friction:?}/{mode:?}"),
                fmt(c.max_rel_f64),
                format!("{:.3e}", c.max_rel_f32),
                c.evals_per_s_cpu_f64,
                c.evals_per_s_gpu_f32,
                fmt(c.evals_per_s_gpu_f64)
            );
        }
    }
    println!("(relative error per output block against the CPU f64 twin; f32 is judged in tests against its condition-based bound, docs/contact-element.md)");
    Ok(())
}
