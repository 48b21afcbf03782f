//! Runs `shaders/update.wgsl` (twin: `src/kernels/update.rs`): the update and the norms.

use crate::error::GpuError;
use crate::gpu::compose::compose_if;
use crate::gpu::contact::GpuReal;
use crate::gpu::dispatch::{run_once, Out};
use crate::gpu::layout::ChainDims;
use crate::gpu::GpuContext;
use crate::kernels::update::{ConfigBatch, Norms};

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

fn dims(b_nodes: usize, nv: usize) -> ChainDims {
    ChainDims {
        num_variants: nv as u32,
        num_nodes: b_nodes as u32,
        _pad0: 0,
        _pad1: 0,
    }
}

/// Applies `α_v Δ_v` to every variant on the GPU, as [`crate::kernels::update::update`].
pub fn update_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    b: &mut ConfigBatch<T>,
    walls: &crate::kernels::update::UpdateWalls<T>,
    delta: &[T],
    alpha: &[T],
) -> Result<(), GpuError> {
    crate::gpu::contact::require_precision::<T>(ctx)?;
    let pipeline = ctx.pipeline("update", &update_wgsl(false, T::IS_F64)?)?;
    let d = dims(b.num_nodes, b.num_variants);
    let node_site = if walls.node_site.is_empty() {
        vec![crate::kernels::assemble::NO_SITE; b.num_nodes * b.num_variants]
    } else {
        walls.node_site.clone()
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
        ],
        b.num_nodes * b.num_variants,
    )?;
    b.x = crate::gpu::readback::values(&out[0]);
    b.rot = crate::gpu::readback::values(&out[1]);
    Ok(())
}

/// Per variant the largest `|r|` and `|α Δ|`, `Δ · r` and `r · r` on the GPU, as
/// [`crate::kernels::update::norms`].
pub fn norms_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    residual: &[T],
    delta: &[T],
    alpha: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Result<Norms<T>, GpuError> {
    crate::gpu::contact::require_precision::<T>(ctx)?;
    // One invocation loops over the 6n entries of its variant: keep it under llvmpipe's
    // silent 65,535-iteration cut-off (see shaders/block_lu.wgsl).
    if 6 * num_nodes > 60_000 {
        return Err(GpuError::Unsupported(format!(
            "norms of {num_nodes} nodes exceed one invocation's loop budget"
        )));
    }
    let pipeline = ctx.pipeline("norms", &update_wgsl(true, T::IS_F64)?)?;
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
    let rows: Vec<T> = crate::gpu::readback::values(&out[0]);
    let rows: Vec<[T; 4]> = rows
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Ok(Norms::from_rows(&rows))
}
