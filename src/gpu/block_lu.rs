//! Runs `shaders/block_lu.wgsl` (twin: `src/kernels/block_lu.rs`): every variant's
//! block-tridiagonal system solved by one invocation, variants split into chunks that fit
//! the adapter's binding limits.

use std::collections::BTreeSet;

use wgpu::util::DeviceExt;

use crate::error::GpuError;
use crate::gpu::compose::compose;
use crate::gpu::contact::GpuReal;
use crate::gpu::layout::ChainDims;
use crate::gpu::GpuContext;
use crate::kernels::block_lu::ChainBatch;

/// Invocations per workgroup in `shaders/block_lu.wgsl`.
const WORKGROUP: usize = 64;

/// The WGSL text of the block solve at a precision.
pub fn block_lu_wgsl(f64: bool) -> Result<String, GpuError> {
    let mut flags = BTreeSet::new();
    if f64 {
        flags.insert("F64");
    }
    compose("block_lu.wgsl", &flags, f64)
}

/// Bytes per variant on the GPU for a chain of `n` nodes at `size`-byte floats: the
/// matrix (3 block rows), right-hand side, factor workspace, solution and status.
pub fn bytes_per_variant(n: usize, size: usize) -> usize {
    let m = n.saturating_sub(1);
    size * (36 * n + 2 * 36 * m + 6 * n + 36 * m + 6 * n + 6 * n) + 4
}

/// Solves every variant of `batch` on the GPU. Returns the field-major solution and a
/// status per variant, as [`crate::kernels::block_lu::block_lu`].
pub fn block_lu_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    batch: &ChainBatch<T>,
) -> Result<(Vec<T>, Vec<u32>), GpuError> {
    block_lu_gpu_chunked(ctx, batch, usize::MAX)
}

/// As [`block_lu_gpu`] with at most `max_chunk` variants per dispatch (tests).
pub fn block_lu_gpu_chunked<T: GpuReal>(
    ctx: &'static GpuContext,
    batch: &ChainBatch<T>,
    max_chunk: usize,
) -> Result<(Vec<T>, Vec<u32>), GpuError> {
    if T::IS_F64 && !ctx.has_f64 {
        return Err(GpuError::Unsupported(format!(
            "adapter {} has no SHADER_F64; use --precision f32",
            ctx.info.name
        )));
    }
    let wgsl = block_lu_wgsl(T::IS_F64)?;
    let pipeline = ctx.pipeline("block_lu", &wgsl)?;
    let device = &ctx.device;
    let size = std::mem::size_of::<T>();
    let (n, v) = (batch.num_nodes, batch.num_variants);
    let m = n.saturating_sub(1);
    let max_binding = ctx.max_binding_bytes() as usize;
    // The largest array per variant is a 36-float block field over n nodes.
    let cap = (max_binding / (36 * n.max(1) * size))
        .min(ctx.limits.max_compute_workgroups_per_dimension as usize * WORKGROUP)
        .min(max_chunk)
        .max(1);
    let layout = pipeline.get_bind_group_layout(0);
    let mut x = vec![T::zero(); 6 * n * v];
    let mut status = vec![0u32; v];
    let mut offset = 0;
    while offset < v {
        let len = cap.min(v - offset);
        let gather = |data: &[T], rows: usize| -> Vec<T> {
            let mut out = Vec::with_capacity(rows * len.max(1));
            for k in 0..rows {
                out.extend_from_slice(&data[k * v + offset..k * v + offset + len]);
            }
            if out.is_empty() {
                out.push(T::zero());
            }
            out
        };
        let input = |label: &str, contents: &[T]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(contents),
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let output = |label: &str, bytes: usize| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(4) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let diag = input("lu_diag", &gather(&batch.diag, 36 * n));
        let upper = input("lu_upper", &gather(&batch.upper, 36 * m));
        let lower = input("lu_lower", &gather(&batch.lower, 36 * m));
        let rhs = input("lu_rhs", &gather(&batch.rhs, 6 * n));
        let work_x = output("lu_work_x", 36 * m.max(1) * len * size);
        let work_z = output("lu_work_z", 6 * n * len * size);
        let x_bytes = 6 * n * len * size;
        let x_buf = output("lu_x", x_bytes);
        let status_buf = output("lu_status", 4 * len);
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lu_staging"),
            size: (x_bytes + 4 * len) as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let dims = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lu_dims"),
            contents: bytemuck::bytes_of(&ChainDims {
                num_variants: len as u32,
                num_nodes: n as u32,
                _pad0: 0,
                _pad1: 0,
            }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let buffers = [
            &dims,
            &diag,
            &upper,
            &lower,
            &rhs,
            &work_x,
            &work_z,
            &x_buf,
            &status_buf,
        ];
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(k, b)| wgpu::BindGroupEntry {
                binding: k as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("block_lu"),
            layout: &layout,
            entries: &entries,
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("block_lu"),
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("block_lu"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(len.div_ceil(WORKGROUP) as u32, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&x_buf, 0, &staging, 0, x_bytes as u64);
        encoder.copy_buffer_to_buffer(&status_buf, 0, &staging, x_bytes as u64, 4 * len as u64);
        ctx.queue.submit([encoder.finish()]);
        staging.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device(e.to_string()))?;
        {
            let view = staging
                .slice(..)
                .get_mapped_range()
                .map_err(|e| GpuError::Device(format!("map: {e}")))?;
            let xs: &[T] = bytemuck::cast_slice(&view[..x_bytes]);
            let st: &[u32] = bytemuck::cast_slice(&view[x_bytes..x_bytes + 4 * len]);
            for k in 0..6 * n {
                x[k * v + offset..k * v + offset + len]
                    .copy_from_slice(&xs[k * len..(k + 1) * len]);
            }
            status[offset..offset + len].copy_from_slice(st);
        }
        staging.unmap();
        offset += len;
    }
    Ok((x, status))
}
