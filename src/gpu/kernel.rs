//! Every kernel the GPU batches run, declared once ([`Kernel`]): its label and its WGSL
//! source (the shader file and the features it is built with) for a precision. The static
//! and the dynamic batch ask for their pipelines here, and bind each kernel's buffers through
//! the one binding list per kernel of `gpu/batch/common.rs`.

use std::sync::Arc;

use crate::error::GpuError;
use crate::gpu::block_lu::LuForm;
use crate::gpu::dynamics::DynamicsKernel;
use crate::gpu::GpuContext;
use crate::physics::contact::ContactTerms;

/// A kernel of the evaluation chain (beam → sites → contact → assembly → block solve →
/// norms, the update, the dynamic integrator's), as a batch builds it.
#[derive(Clone, Copy, Debug)]
pub enum Kernel<'a> {
    /// Element forces and tangents of every variant; `kink`: a scene with a bent sub (the
    /// unstrained rotations bound).
    Beam {
        /// A scene with a kink.
        kink: bool,
    },
    /// The line-search trials' beam kernel: forces alone, for the listed variants.
    BeamTrial {
        /// A scene with a kink.
        kink: bool,
    },
    /// The dynamic iterations' beam kernel: forces and tangents of the listed variants.
    BeamMasked {
        /// A scene with a kink.
        kink: bool,
    },
    /// The sites gather: static, or dynamic (with the sites' velocities).
    Sites {
        /// The dynamic form.
        dynamic: bool,
    },
    /// The line-search trials' sites gather (listed variants): static, or dynamic.
    SitesTrial {
        /// The dynamic form.
        dynamic: bool,
    },
    /// The contact kernel specialised to the scene's terms.
    Contact(&'a ContactTerms),
    /// The line-search trials' contact kernel: forces alone, listed variants.
    ContactTrial(&'a ContactTerms),
    /// The dynamic iterations' contact kernel: the whole response, listed variants.
    ContactMasked(&'a ContactTerms),
    /// The assembly: static, or dynamic with (`unbalance`) the mass-imbalance terms.
    Assemble {
        /// The dynamic form.
        dynamic: bool,
        /// The mass-imbalance terms (dynamic only).
        unbalance: bool,
    },
    /// The line-search trials' assembly: the residual alone, listed variants; static, or
    /// dynamic with (`unbalance`) the mass-imbalance terms.
    AssembleTrial {
        /// The dynamic form.
        dynamic: bool,
        /// The mass-imbalance terms (dynamic only).
        unbalance: bool,
    },
    /// The dynamic iterations' assembly (system and residual) of the listed variants, with
    /// (`unbalance`) the mass-imbalance terms.
    AssembleMasked {
        /// The mass-imbalance terms.
        unbalance: bool,
    },
    /// The assembly with a relaxation's proximal shift: the full system, or (`trial`) the
    /// trials' residual.
    AssembleShift {
        /// The trials' form.
        trial: bool,
    },
    /// The block-tridiagonal solve in the adapter's form.
    BlockLu(LuForm),
    /// The residual and step norms; `trial`: for the listed variants.
    Norms {
        /// The trials' form.
        trial: bool,
    },
    /// The configuration update; `trial`: out of place, for the listed variants.
    Update {
        /// The trials' form.
        trial: bool,
    },
    /// One of the generalised-α integrator's kernels.
    Dynamics(DynamicsKernel),
    /// One of the integrator's kernels for the listed variants (the dynamic engine's trials
    /// and iterations).
    DynamicsMasked(DynamicsKernel),
}

impl Kernel<'_> {
    /// The pipeline's label (in messages and GPU captures).
    pub fn label(&self) -> &'static str {
        match self {
            Kernel::Beam { .. } => "beam",
            Kernel::BeamTrial { .. } => "beam_trial",
            Kernel::BeamMasked { .. } => "beam_masked",
            Kernel::Sites { .. } => "sites",
            Kernel::SitesTrial { dynamic: false } => "sites_trial",
            Kernel::SitesTrial { dynamic: true } => "sites_dynamic_trial",
            Kernel::Contact(_) => "contact",
            Kernel::ContactTrial(_) => "contact_trial",
            Kernel::ContactMasked(_) => "contact_masked",
            Kernel::Assemble { .. } => "assemble",
            Kernel::AssembleTrial { dynamic: false, .. } => "assemble_trial",
            Kernel::AssembleTrial { dynamic: true, .. } => "assemble_dynamic_trial",
            Kernel::AssembleMasked { .. } => "assemble_masked",
            Kernel::AssembleShift { trial: false } => "assemble_shift",
            Kernel::AssembleShift { trial: true } => "assemble_trial_shift",
            Kernel::BlockLu(_) => "block_lu",
            Kernel::Norms { trial: false } => "norms",
            Kernel::Norms { trial: true } => "norms_trial",
            Kernel::Update { trial: false } => "update",
            Kernel::Update { trial: true } => "update_trial",
            Kernel::Dynamics(DynamicsKernel::Predict) => "predict",
            Kernel::Dynamics(DynamicsKernel::Accelerate) => "accelerate",
            Kernel::Dynamics(DynamicsKernel::Scale) => "scale",
            Kernel::DynamicsMasked(DynamicsKernel::Predict) => "predict_masked",
            Kernel::DynamicsMasked(DynamicsKernel::Accelerate) => "accelerate_masked",
            Kernel::DynamicsMasked(DynamicsKernel::Scale) => "scale_masked",
        }
    }

    /// The WGSL text at a precision.
    pub fn wgsl(&self, f64: bool) -> Result<String, GpuError> {
        use crate::gpu::{assemble, beam, block_lu, contact, dynamics, update};
        let sites = |dynamic: bool, masked: bool| {
            crate::gpu::compose::compose_if(
                "sites.wgsl",
                &[("DYNAMIC", dynamic), ("MASKED", masked)],
                f64,
            )
        };
        match *self {
            Kernel::Beam { kink } => beam::beam_wgsl(f64, false, kink),
            Kernel::BeamTrial { kink } => beam::beam_trial_wgsl(f64, kink),
            Kernel::BeamMasked { kink } => beam::beam_masked_wgsl(f64, false, kink),
            Kernel::Sites { dynamic } => sites(dynamic, false),
            Kernel::SitesTrial { dynamic } => sites(dynamic, true),
            Kernel::Contact(terms) => contact::contact_wgsl(terms, f64),
            Kernel::ContactTrial(terms) => contact::contact_force_wgsl(terms, f64, true),
            Kernel::ContactMasked(terms) => contact::contact_masked_wgsl(terms, f64),
            Kernel::Assemble { dynamic, unbalance } => {
                assemble::assemble_wgsl_with(dynamic, unbalance, f64)
            }
            Kernel::AssembleTrial { dynamic, unbalance } => {
                assemble::assemble_force_wgsl_with(dynamic, unbalance, f64, true)
            }
            Kernel::AssembleMasked { unbalance } => {
                assemble::assemble_dynamic_masked_wgsl(unbalance, f64)
            }
            Kernel::AssembleShift { trial } => assemble::assemble_shift_wgsl(f64, trial, trial),
            Kernel::BlockLu(form) => block_lu::block_lu_wgsl(f64, form),
            Kernel::Norms { trial } => update::update_wgsl_with(true, f64, false, trial),
            Kernel::Update { trial } => update::update_wgsl_with(false, f64, trial, trial),
            Kernel::Dynamics(k) => dynamics::dynamics_wgsl(k, f64),
            Kernel::DynamicsMasked(k) => dynamics::dynamics_wgsl_with(k, f64, true),
        }
    }

    /// Its compute pipeline on `ctx` at a precision (compiled once per source text:
    /// [`GpuContext::pipeline`]).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        f64: bool,
    ) -> Result<Arc<wgpu::ComputePipeline>, GpuError> {
        ctx.pipeline(self.label(), &self.wgsl(f64)?)
    }
}
