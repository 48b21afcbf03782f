//! Runs `shaders/beam.wgsl` (twin: `src/kernels/beam.rs`).

use crate::error::GpuError;
use crate::gpu::compose::compose_if;
use crate::gpu::contact::GpuReal;
use crate::gpu::dispatch::{run_once, Out};
use crate::gpu::layout::BeamDims;
use crate::gpu::GpuContext;
use crate::kernels::beam::{frame_table, section_table, TANGENT_LEN};
use crate::model::Model;

/// The WGSL text of the beam kernel at a precision: force and tangent, or (`force_only`)
/// the force alone, without the tangent binding; with `kink` the unstrained-rotation
/// binding (6) before the outputs (a scene with a bent sub; none otherwise).
pub fn beam_wgsl(f64: bool, force_only: bool, kink: bool) -> Result<String, GpuError> {
    compose_if(
        "beam.wgsl",
        &[("KINK", kink), ("FORCE_ONLY", force_only)],
        f64,
    )
}

/// The force-only beam kernel built `MASKED` (the engine's line-search trials): one
/// invocation per (element, listed variant) of the compacted list of searching variants
/// `[A, v_0, …]` (the last binding); the other variants are skipped.
pub fn beam_trial_wgsl(f64: bool, kink: bool) -> Result<String, GpuError> {
    beam_masked_wgsl(f64, true, kink)
}

/// The beam kernel built `MASKED`: forces and tangents (or `force_only` forces alone) of the
/// listed variants `[A, v_0, …]` (the last binding), one invocation per (element, listed
/// variant); the other variants' outputs are left as they were.
pub fn beam_masked_wgsl(f64: bool, force_only: bool, kink: bool) -> Result<String, GpuError> {
    compose_if(
        "beam.wgsl",
        &[("FORCE_ONLY", force_only), ("MASKED", true), ("KINK", kink)],
        f64,
    )
}

/// Element forces and tangents of V variants on the GPU at displacements `u` from the base
/// whose chords are `chords` ([`crate::kernels::beam::base_chords`]) and unstrained rotations
/// `rest` ([`crate::kernels::beam::rest_table`], empty: none), laid out as the twin's; with
/// `tangent` false the forces alone (an empty tangent).
#[allow(clippy::too_many_arguments)]
pub fn beam_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    model: &Model,
    num_variants: usize,
    u: &[T],
    rot: &[T],
    chords: &[f64],
    rest: &[f64],
    tangent: bool,
) -> Result<(Vec<T>, Vec<T>), GpuError> {
    crate::gpu::contact::require_precision::<T>(ctx)?;
    let ne = model.elements.len();
    let size = std::mem::size_of::<T>();
    if (TANGENT_LEN * ne * num_variants * size) as u64 > ctx.max_binding_bytes() {
        return Err(GpuError::Unsupported(
            "element tangents exceed one binding; split the variants".into(),
        ));
    }
    let kink = !rest.is_empty();
    let pipeline = ctx.pipeline("beam", &beam_wgsl(T::IS_F64, !tangent, kink)?)?;
    let cast = |v: Vec<f64>| -> Vec<T> { v.into_iter().map(T::from_f64_lossy).collect() };
    let sections = cast(section_table(model));
    let frames = cast(frame_table(model));
    let chords = cast(chords.to_vec());
    let rest = cast(rest.to_vec());
    let dims = BeamDims {
        num_variants: num_variants as u32,
        num_elements: ne as u32,
        _pad0: 0,
        _pad1: 0,
    };
    let outputs = [
        Out::Empty(12 * ne * num_variants * size),
        Out::Empty(TANGENT_LEN * ne * num_variants * size),
    ];
    let inputs: [&[u8]; 6] = [
        bytemuck::cast_slice(u),
        bytemuck::cast_slice(rot),
        bytemuck::cast_slice(&frames),
        bytemuck::cast_slice(&sections),
        bytemuck::cast_slice(&chords),
        bytemuck::cast_slice(&rest),
    ];
    let out = run_once(
        ctx,
        &pipeline,
        "beam",
        bytemuck::bytes_of(&dims),
        &inputs[..5 + usize::from(kink)],
        &outputs[..1 + usize::from(tangent)],
        ne * num_variants,
    )?;
    Ok((
        crate::gpu::readback::values(&out[0]),
        out.get(1)
            .map(|t| bytemuck::cast_slice(t).to_vec())
            .unwrap_or_default(),
    ))
}
