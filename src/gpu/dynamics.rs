//! Runs `shaders/dynamics.wgsl` (twin: `src/kernels/dynamics.rs`) one-shot, for tests; the
//! engine binds the same kernels to resident buffers (`src/gpu/batch/`).

use std::collections::BTreeSet;

use crate::error::GpuError;
use crate::gpu::compose::compose;
use crate::gpu::contact::{require_precision, GpuReal};
use crate::gpu::dispatch::{run_once, Out};
use crate::gpu::layout::ChainDims;
use crate::gpu::GpuContext;
use crate::kernels::dynamics::{DynamicBatch, StepCoefficients};

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
    let mut flags = BTreeSet::new();
    if f64 {
        flags.insert("F64");
    }
    flags.insert(match kernel {
        DynamicsKernel::Predict => "PREDICT",
        DynamicsKernel::Accelerate => "ACCEL",
        DynamicsKernel::Scale => "SCALE",
    });
    compose("dynamics.wgsl", &flags, f64)
}

fn dims(n: usize, v: usize) -> ChainDims {
    ChainDims {
        num_variants: v as u32,
        num_nodes: n as u32,
        _pad0: 0,
        _pad1: 0,
    }
}

/// [`crate::kernels::dynamics::predict`] on the GPU: returns the trial state and `vdot`
/// with the top's prescribed accelerations.
pub fn predict_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    c: &StepCoefficients<T>,
    top: &[T],
    state: &DynamicBatch<T>,
    vdot: &[T],
) -> Result<DynamicBatch<T>, GpuError> {
    require_precision::<T>(ctx)?;
    let pipeline = ctx.pipeline(
        "predict",
        &dynamics_wgsl(DynamicsKernel::Predict, T::IS_F64)?,
    )?;
    let (n, v) = (state.num_nodes, state.num_variants);
    let size = std::mem::size_of::<T>();
    let reals = c.reals();
    let flags = [c.flags()];
    let out = run_once(
        ctx,
        &pipeline,
        "predict",
        bytemuck::bytes_of(&dims(n, v)),
        &[
            bytemuck::cast_slice(&reals[..]),
            bytemuck::cast_slice(&flags[..]),
            bytemuck::cast_slice(top),
            bytemuck::cast_slice(&state.u),
            bytemuck::cast_slice(&state.rot),
            bytemuck::cast_slice(&state.vel),
            bytemuck::cast_slice(&state.acc),
            bytemuck::cast_slice(&state.vdot),
        ],
        &[
            Out::From(bytemuck::cast_slice(vdot)),
            Out::Empty(3 * n * v * size),
            Out::Empty(9 * n * v * size),
            Out::Empty(6 * n * v * size),
            Out::Empty(6 * n * v * size),
        ],
        n * v,
    )?;
    let cast = |b: &Vec<u8>| -> Vec<T> { bytemuck::cast_slice(b).to_vec() };
    Ok(DynamicBatch {
        num_variants: v,
        num_nodes: n,
        vdot: cast(&out[0]),
        u: cast(&out[1]),
        rot: cast(&out[2]),
        vel: cast(&out[3]),
        acc: cast(&out[4]),
    })
}

/// [`crate::kernels::dynamics::accelerate`] on the GPU.
pub fn accelerate_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    basis: &[T],
    vdot: &[T],
    delta: &[T],
    alpha: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Result<Vec<T>, GpuError> {
    require_precision::<T>(ctx)?;
    let pipeline = ctx.pipeline(
        "accelerate",
        &dynamics_wgsl(DynamicsKernel::Accelerate, T::IS_F64)?,
    )?;
    let out = run_once(
        ctx,
        &pipeline,
        "accelerate",
        bytemuck::bytes_of(&dims(num_nodes, num_variants)),
        &[
            bytemuck::cast_slice(basis),
            bytemuck::cast_slice(vdot),
            bytemuck::cast_slice(delta),
            bytemuck::cast_slice(alpha),
        ],
        &[Out::Empty(std::mem::size_of_val(vdot))],
        num_nodes * num_variants,
    )?;
    Ok(crate::gpu::readback::values(&out[0]))
}

/// [`crate::kernels::dynamics::inertial_scale`] on the GPU.
pub fn inertial_scale_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    mass: &[T],
    vdot: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Result<Vec<T>, GpuError> {
    require_precision::<T>(ctx)?;
    let pipeline = ctx.pipeline("scale", &dynamics_wgsl(DynamicsKernel::Scale, T::IS_F64)?)?;
    let out = run_once(
        ctx,
        &pipeline,
        "scale",
        bytemuck::bytes_of(&dims(num_nodes, num_variants)),
        &[bytemuck::cast_slice(mass), bytemuck::cast_slice(vdot)],
        &[Out::Empty(num_variants * std::mem::size_of::<T>())],
        num_variants,
    )?;
    Ok(crate::gpu::readback::values(&out[0]))
}
