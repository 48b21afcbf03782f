//! Backend and precision choice shared by every command that computes.

use crate::error::GpuError;
use crate::gpu::contact::contact_gpu;
use crate::gpu::GpuContext;
use crate::kernels::contact::{contact, ContactBatch, ContactOutputs};
use crate::physics::contact::ContactTerms;

/// `--backend`: where the kernels run.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum BackendChoice {
    /// The CPU twins (rayon over pairs / variants).
    Cpu,
    /// The WGSL kernels; an error if no adapter exists.
    Gpu,
    /// The GPU where an adapter exists, else the CPU with a one-line notice.
    Auto,
}

/// `--precision`: the float type of the computation.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// 64-bit (the oracle's precision).
    F64,
    /// 32-bit.
    F32,
}

/// A resolved backend.
#[derive(Clone, Copy)]
pub enum Backend {
    /// CPU twins.
    Cpu,
    /// GPU kernels on the shared context.
    Gpu(&'static GpuContext),
}

/// What `--backend auto` optimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AutoRule {
    /// Any adapter that can run the precision (benchmarks and kernel checks, which are
    /// there to exercise the GPU path).
    AnyAdapter,
    /// The faster path for results: a software renderer (lavapipe: `DeviceType::Cpu`) runs
    /// the kernels on the same cores, slower than the CPU path, so the CPU runs them.
    FasterPath,
}

impl Backend {
    /// Resolves `--backend` for a run at `precision`. `auto` falls back to the CPU, with a
    /// one-line notice (returned: the caller shows it), when no adapter exists or it cannot
    /// run `precision`.
    pub fn resolve(
        choice: BackendChoice,
        precision: Precision,
    ) -> Result<(Backend, Option<String>), GpuError> {
        Backend::resolve_with(
            choice,
            precision,
            &[Precision::F64, Precision::F32],
            AutoRule::AnyAdapter,
        )
    }

    /// The one backend policy: `choice` at `precision` for a computation whose CPU path
    /// computes in `cpu_precisions`, `auto` by `rule`. `auto` at a precision only the GPU
    /// computes needs an adapter that has it (an error otherwise); else it falls back to
    /// the CPU with a one-line notice, returned beside the backend (the library prints
    /// nothing: the command or the run's summary shows it).
    pub fn resolve_with(
        choice: BackendChoice,
        precision: Precision,
        cpu_precisions: &[Precision],
        rule: AutoRule,
    ) -> Result<(Backend, Option<String>), GpuError> {
        let gpu_can = |ctx: &GpuContext| precision == Precision::F32 || ctx.has_f64;
        match choice {
            BackendChoice::Cpu => Ok((Backend::Cpu, None)),
            BackendChoice::Gpu => {
                let ctx = GpuContext::shared()?;
                if !gpu_can(ctx) {
                    return Err(GpuError::Unsupported(format!(
                        "adapter {} has no SHADER_F64; use --precision f32 or --backend cpu",
                        ctx.info.name
                    )));
                }
                Ok((Backend::Gpu(ctx), None))
            }
            BackendChoice::Auto if !cpu_precisions.contains(&precision) => {
                // Only the GPU computes at this precision, whatever the adapter.
                let ctx = GpuContext::shared()?;
                if !gpu_can(ctx) {
                    return Err(GpuError::Unsupported(format!(
                        "adapter {} cannot run {precision:?}",
                        ctx.info.name
                    )));
                }
                Ok((Backend::Gpu(ctx), None))
            }
            BackendChoice::Auto => match GpuContext::shared() {
                Ok(ctx)
                    if rule == AutoRule::FasterPath
                        && ctx.info.device_type == wgpu::DeviceType::Cpu =>
                {
                    Ok((
                        Backend::Cpu,
                        Some(format!(
                            "the only adapter ({}) is a software renderer; using the CPU \
                             backend, which is faster there",
                            ctx.info.name
                        )),
                    ))
                }
                Ok(ctx) if gpu_can(ctx) => Ok((Backend::Gpu(ctx), None)),
                Ok(ctx) => Ok((
                    Backend::Cpu,
                    Some(format!(
                        "adapter {} has no SHADER_F64; using the CPU backend",
                        ctx.info.name
                    )),
                )),
                Err(e) => Ok((Backend::Cpu, Some(format!("{e}; using the CPU backend")))),
            },
        }
    }

    /// Name for reports.
    pub fn describe(&self) -> String {
        match self {
            Backend::Cpu => "cpu".to_string(),
            Backend::Gpu(ctx) => format!("gpu: {}", ctx.describe()),
        }
    }
}

/// Contact outputs at the precision that was asked for.
#[derive(Clone, Debug)]
pub enum ContactResults {
    /// f64 run.
    F64(ContactOutputs<f64>),
    /// f32 run.
    F32(ContactOutputs<f32>),
}

/// Evaluates the contact element for `batch` on `backend` at `precision`, with the kernel
/// specialised to `terms`. An f32 run converts the inputs once and computes in f32
/// throughout, on either backend.
pub fn evaluate_contact(
    backend: Backend,
    precision: Precision,
    terms: &ContactTerms,
    batch: &ContactBatch<f64>,
) -> Result<ContactResults, GpuError> {
    Ok(match (backend, precision) {
        (Backend::Cpu, Precision::F64) => {
            let mut out = ContactOutputs::new(batch.num_pairs());
            contact(terms, batch, &mut out);
            ContactResults::F64(out)
        }
        (Backend::Cpu, Precision::F32) => {
            let b32 = batch.cast::<f32>();
            let mut out = ContactOutputs::new(b32.num_pairs());
            contact(terms, &b32, &mut out);
            ContactResults::F32(out)
        }
        (Backend::Gpu(ctx), Precision::F64) => ContactResults::F64(contact_gpu(ctx, terms, batch)?),
        (Backend::Gpu(ctx), Precision::F32) => {
            ContactResults::F32(contact_gpu(ctx, terms, &batch.cast::<f32>())?)
        }
    })
}
