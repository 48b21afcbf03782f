//! One-shot runners of single kernels for the tests: each uploads its inputs, runs one
//! kernel once and reads its outputs back, to be compared with the kernel's CPU twin. (The
//! engine binds the same kernels to resident buffers, `src/gpu/batch/`; the runners that
//! `holewall bench kernels` and the contact backend use stay in `src/gpu/`.)
#![allow(dead_code)]

use holewall::error::GpuError;
use holewall::gpu::assemble::{
    assemble_force_wgsl, assemble_force_wgsl_with, assemble_shift_wgsl, shift_bindings,
    static_bindings,
};
use holewall::gpu::batch::{bind, dispatch, encoder};
use holewall::gpu::contact::{require_precision, GpuReal};
use holewall::gpu::dispatch::{run_once, Out};
use holewall::gpu::dynamics::DynamicsKernel;
use holewall::gpu::kernel::Kernel;
use holewall::gpu::layout::{ChainDims, ContactDims};
use holewall::gpu::readback::{submit_and_read, values};
use holewall::gpu::GpuContext;
use holewall::kernels::assemble::AssemblyInputs;
use holewall::kernels::dynamics::{DynamicBatch, StepCoefficients};
use holewall::kernels::update::{ConfigBatch, Norms};
use wgpu::util::DeviceExt;

fn dims(n: usize, v: usize) -> ChainDims {
    ChainDims {
        num_variants: v as u32,
        num_nodes: n as u32,
        _pad0: 0,
        _pad1: 0,
    }
}

/// [`holewall::kernels::dynamics::predict`] on the GPU: returns the trial state and `vdot`
/// with the top's prescribed accelerations.
pub fn predict_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    c: &StepCoefficients<T>,
    top: &[T],
    state: &DynamicBatch<T>,
    vdot: &[T],
) -> Result<DynamicBatch<T>, GpuError> {
    require_precision::<T>(ctx)?;
    let pipeline = Kernel::Dynamics(DynamicsKernel::Predict).pipeline(ctx, T::IS_F64)?;
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

/// [`holewall::kernels::dynamics::accelerate`] on the GPU.
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
    let pipeline = Kernel::Dynamics(DynamicsKernel::Accelerate).pipeline(ctx, T::IS_F64)?;
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
    Ok(values(&out[0]))
}

/// [`holewall::kernels::dynamics::inertial_scale`] on the GPU.
pub fn inertial_scale_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    mass: &[T],
    vdot: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Result<Vec<T>, GpuError> {
    require_precision::<T>(ctx)?;
    let pipeline = Kernel::Dynamics(DynamicsKernel::Scale).pipeline(ctx, T::IS_F64)?;
    let out = run_once(
        ctx,
        &pipeline,
        "scale",
        bytemuck::bytes_of(&dims(num_nodes, num_variants)),
        &[bytemuck::cast_slice(mass), bytemuck::cast_slice(vdot)],
        &[Out::Empty(num_variants * std::mem::size_of::<T>())],
        num_variants,
    )?;
    Ok(values(&out[0]))
}

/// Applies `α_v Δ_v` to every variant on the GPU, as [`holewall::kernels::update::update`].
pub fn update_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    b: &mut ConfigBatch<T>,
    walls: &holewall::kernels::update::UpdateWalls<T>,
    delta: &[T],
    alpha: &[T],
) -> Result<(), GpuError> {
    require_precision::<T>(ctx)?;
    let pipeline = Kernel::Update { trial: false }.pipeline(ctx, T::IS_F64)?;
    let d = dims(b.num_nodes, b.num_variants);
    let node_site = if walls.node_site.is_empty() {
        vec![holewall::kernels::assemble::NO_SITE; b.num_nodes * b.num_variants]
    } else {
        walls.node_site.clone()
    };
    // No landing state or epoch: every node's mark equals its variant's epoch (no landing),
    // as the twin's empty `landed` or `epoch`.
    let (landed, epoch) = if b.landed.is_empty() || walls.epoch.is_empty() {
        (
            vec![0u32; b.num_nodes * b.num_variants],
            vec![0u32; b.num_variants],
        )
    } else {
        (b.landed.clone(), walls.epoch.clone())
    };
    // Bindings must not be empty.
    let pad = |v: &[T]| -> Vec<T> {
        if v.is_empty() {
            vec![T::zero()]
        } else {
            v.to_vec()
        }
    };
    let out = run_once(
        ctx,
        &pipeline,
        "update",
        bytemuck::bytes_of(&d),
        &[
            bytemuck::cast_slice(delta),
            bytemuck::cast_slice(alpha),
            bytemuck::cast_slice(&b.basis),
            bytemuck::cast_slice(&node_site),
            bytemuck::cast_slice(&pad(&walls.pair_base)),
            bytemuck::cast_slice(&pad(&walls.pair_normals)),
            bytemuck::cast_slice(&pad(&walls.pair_params)),
        ],
        &[
            Out::From(bytemuck::cast_slice(&b.x)),
            Out::From(bytemuck::cast_slice(&b.rot)),
            Out::From(bytemuck::cast_slice(&landed)),
            Out::From(bytemuck::cast_slice(&epoch)),
        ],
        b.num_nodes * b.num_variants,
    )?;
    b.x = values(&out[0]);
    b.rot = values(&out[1]);
    if !b.landed.is_empty() {
        b.landed = values(&out[2]);
    }
    Ok(())
}

/// Per variant the largest `|r|` and `|α Δ|`, `Δ · r` and `r · r` on the GPU, as
/// [`holewall::kernels::update::norms`].
pub fn norms_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    residual: &[T],
    delta: &[T],
    alpha: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Result<Norms<T>, GpuError> {
    require_precision::<T>(ctx)?;
    // One invocation loops over the 6n entries of its variant: keep it under llvmpipe's
    // silent 65,535-iteration cut-off (see shaders/block_lu.wgsl).
    if 6 * num_nodes > 60_000 {
        return Err(GpuError::Unsupported(format!(
            "norms of {num_nodes} nodes exceed one invocation's loop budget"
        )));
    }
    let pipeline = Kernel::Norms { trial: false }.pipeline(ctx, T::IS_F64)?;
    let d = dims(num_nodes, num_variants);
    let size = std::mem::size_of::<T>();
    let out = run_once(
        ctx,
        &pipeline,
        "norms",
        bytemuck::bytes_of(&d),
        &[
            bytemuck::cast_slice(delta),
            bytemuck::cast_slice(alpha),
            bytemuck::cast_slice(residual),
        ],
        &[Out::Empty(4 * num_variants * size)],
        num_variants,
    )?;
    let rows: Vec<T> = values(&out[0]);
    let rows: Vec<[T; 4]> = rows
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Ok(Norms::from_rows(&rows))
}

/// The residual of every variant on the GPU (the kernel built `FORCE_ONLY`, static or
/// dynamic), laid out as the twin's `rhs`.
pub fn assemble_residual_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    a: &AssemblyInputs<T>,
) -> Result<Vec<T>, GpuError> {
    require_precision::<T>(ctx)?;
    let (n, nv) = (a.num_nodes, a.num_variants);
    let size = std::mem::size_of::<T>();
    let wgsl = match (&a.shift, &a.dynamic) {
        (Some(_), _) => assemble_shift_wgsl(T::IS_F64, true, false)?,
        (None, Some(dy)) => {
            assemble_force_wgsl_with(true, !dy.unbalance.is_empty(), T::IS_F64, false)?
        }
        (None, None) => assemble_force_wgsl(T::IS_F64, false)?,
    };
    let pipeline = ctx.pipeline("assemble_force", &wgsl)?;
    let (dims, inputs) = static_bindings(a, false);
    // The shift's or the dynamic inputs follow the output in the kernel: passed after it
    // (read only).
    let mut outputs = vec![Out::Empty(6 * n * nv * size)];
    outputs.extend(shift_bindings(a));
    if let Some(dy) = &a.dynamic {
        outputs.extend(
            [
                &dy.coefficients[..],
                &dy.mass,
                &dy.inertia0,
                &dy.rot,
                &dy.vel,
                &dy.vdot,
            ]
            .into_iter()
            .map(|x| Out::From(bytemuck::cast_slice(x))),
        );
        if !dy.unbalance.is_empty() {
            outputs.push(Out::From(bytemuck::cast_slice(&dy.unbalance)));
        }
    }
    let out = run_once(
        ctx,
        &pipeline,
        "assemble_force",
        bytemuck::bytes_of(&dims),
        &inputs,
        &outputs,
        n * nv,
    )?;
    Ok(values(&out[0]))
}

/// Runs `shaders/sites.wgsl` once (tests against its twin,
/// [`holewall::kernels::sites::gather_sites`]): `pair_state` with `d` of every pair written
/// from the displacements `u` off the base (at the pairs, `pair_base`).
pub fn gather_sites_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    pair_node: &[u32],
    u: &[T],
    pair_base: &[T],
    num_variants: usize,
    pair_state: &[T],
) -> Result<Vec<T>, GpuError> {
    require_precision::<T>(ctx)?;
    let pipeline = Kernel::Sites { dynamic: false }.pipeline(ctx, T::IS_F64)?;
    let dims = ContactDims {
        num_pairs: pair_node.len() as u32,
        num_variants: num_variants as u32,
        pair_offset: 0,
        mask_variants: 0,
    };
    let out = run_once(
        ctx,
        &pipeline,
        "sites",
        bytemuck::bytes_of(&dims),
        &[
            bytemuck::cast_slice(pair_node),
            bytemuck::cast_slice(u),
            bytemuck::cast_slice(pair_base),
        ],
        &[Out::From(bytemuck::cast_slice(pair_state))],
        pair_node.len(),
    )?;
    Ok(values(&out[0]))
}

/// Runs the DYNAMIC form of `shaders/sites.wgsl` once (tests against
/// [`holewall::kernels::sites::gather_sites_dynamic`]).
pub fn gather_sites_dynamic_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    pair_node: &[u32],
    pair_normals: &[T],
    state: &holewall::kernels::dynamics::DynamicBatch<T>,
    pair_base: &[T],
    pair_state: &[T],
) -> Result<Vec<T>, GpuError> {
    let (u, vel, num_variants) = (&state.u, &state.vel, state.num_variants);
    require_precision::<T>(ctx)?;
    let pipeline = Kernel::Sites { dynamic: true }.pipeline(ctx, T::IS_F64)?;
    let dims = ContactDims {
        num_pairs: pair_node.len() as u32,
        num_variants: num_variants as u32,
        pair_offset: 0,
        mask_variants: 0,
    };
    // Bindings: dims, pair_node, u, pair_base, pair_state (read-write), vel, pair_normals — the
    // read-write one sits between inputs, so bind by hand.
    let device = &ctx.device;
    let buf = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage,
        })
    };
    let st = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let dims_b = buf(
        "dims",
        bytemuck::bytes_of(&dims),
        wgpu::BufferUsages::STORAGE,
    );
    let nodes_b = buf("pair_node", bytemuck::cast_slice(pair_node), st);
    let u_b = buf("u", bytemuck::cast_slice(u), st);
    let state_b = buf("pair_state", bytemuck::cast_slice(pair_state), st);
    let vel_b = buf("vel", bytemuck::cast_slice(vel), st);
    let normals_b = buf("pair_normals", bytemuck::cast_slice(pair_normals), st);
    let base_b = buf("pair_base", bytemuck::cast_slice(pair_base), st);
    let group = bind(
        ctx,
        &pipeline,
        "sites",
        &[
            &dims_b, &nodes_b, &u_b, &base_b, &state_b, &vel_b, &normals_b,
        ],
    );
    let mut e = encoder(ctx, "sites");
    {
        let mut pass = e.begin_compute_pass(&Default::default());
        dispatch(&mut pass, &pipeline, &group, pair_node.len());
    }
    let out = submit_and_read(
        ctx,
        e,
        &[(&state_b, std::mem::size_of_val(pair_state) as u64)],
    )?;
    Ok(values(&out[0]))
}
