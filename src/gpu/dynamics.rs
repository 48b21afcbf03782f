//! The kernels of `shaders/dynamics.wgsl` (twin: `src/kernels/dynamics.rs`): the engine
//! binds them to resident buffers (`src/gpu/batch/`); the tests' one-shot runners are in
//! `tests/common/runners.rs`.

use std::collections::BTreeSet;

use crate::error::GpuError;
use crate::gpu::compose::compose;

/// Which of the three kernels of `dynamics.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DynamicsKernel {
    /// The generalised-α predictor.
    Predict,
    /// The Newton correction of the accelerations.
    Accelerate,
    /// The inertial force scale.
    Scale,
}

/// The WGSL text of one kernel at a precision.
pub fn dynamics_wgsl(kernel: DynamicsKernel, f64: bool) -> Result<String, GpuError> {
    dynamics_wgsl_with(kernel, f64, false)
}

/// The WGSL text of one kernel at a precision; `masked` (the dynamic engine's trials and
/// iterations): one invocation per item and listed variant of the compacted list
/// `[A, v_0, …]`, its last binding; the other variants are left as they are.
pub fn dynamics_wgsl_with(
    kernel: DynamicsKernel,
    f64: bool,
    masked: bool,
) -> Result<String, GpuError> {
    let mut flags = BTreeSet::new();
    if f64 {
        flags.insert("F64");
    }
    if masked {
        flags.insert("MASKED");
    }
    flags.insert(match kernel {
        DynamicsKernel::Predict => "PREDICT",
        DynamicsKernel::Accelerate => "ACCEL",
        DynamicsKernel::Scale => "SCALE",
    });
    compose("dynamics.wgsl", &flags, f64)
}
