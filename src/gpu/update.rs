//! The kernels of `shaders/update.wgsl` (twin: `src/kernels/update.rs`): the update and the
//! norms (the tests' one-shot runners are in `tests/common/runners.rs`).

use crate::error::GpuError;
use crate::gpu::compose::compose_if;

/// The WGSL text of the update (`norms = false`) or of the norms, at a precision.
pub fn update_wgsl(norms: bool, f64: bool) -> Result<String, GpuError> {
    update_wgsl_with(norms, f64, false, false)
}

/// [`update_wgsl`] for the engine's line-search trials: `out_of_place`, the update reads
/// the configuration it moves from (bindings 8, 9) and writes the trial's (10, 11);
/// `masked`, one invocation per (node, listed variant) — per listed variant for the norms —
/// of a compacted list `[A, v_0, …]` (the last binding); the others are skipped.
pub fn update_wgsl_with(
    norms: bool,
    f64: bool,
    out_of_place: bool,
    masked: bool,
) -> Result<String, GpuError> {
    compose_if(
        "update.wgsl",
        &[
            ("OUT_OF_PLACE", out_of_place && !norms),
            ("MASKED", masked),
            ("NORMS", norms),
        ],
        f64,
    )
}
