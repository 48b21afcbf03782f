//! The one read-back of device buffers: every runner (one-shot dispatches, the contact
//! batch, the static and dynamic ensembles) copies what it reads into one staging buffer,
//! submits, waits and takes the bytes here.

use crate::error::GpuError;
use crate::gpu::GpuContext;

/// The bytes each read takes in a staging buffer: at least one word (a copy of zero bytes
/// still holds its place).
fn slot(bytes: u64) -> u64 {
    bytes.max(4)
}

/// A staging buffer to hold `reads` (sizes in bytes) end to end, for a runner that reads the
/// same buffers many times ([`submit_and_read_into`]).
pub fn staging_buffer(ctx: &GpuContext, label: &str, reads: &[u64]) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: reads.iter().map(|&b| slot(b)).sum::<u64>().max(4),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Submits `encoder` with copies of the first `bytes` of each buffer appended into a
/// staging buffer made for them, waits, and returns the bytes of each.
pub fn submit_and_read(
    ctx: &GpuContext,
    encoder: wgpu::CommandEncoder,
    reads: &[(&wgpu::Buffer, u64)],
) -> Result<Vec<Vec<u8>>, GpuError> {
    let sizes: Vec<u64> = reads.iter().map(|r| r.1).collect();
    let staging = staging_buffer(ctx, "read", &sizes);
    submit_and_read_into(ctx, encoder, &staging, reads)
}

/// As [`submit_and_read`], into a staging buffer the caller keeps (from [`staging_buffer`]
/// with at least these reads' sizes).
pub fn submit_and_read_into(
    ctx: &GpuContext,
    mut encoder: wgpu::CommandEncoder,
    staging: &wgpu::Buffer,
    reads: &[(&wgpu::Buffer, u64)],
) -> Result<Vec<Vec<u8>>, GpuError> {
    let total: u64 = reads.iter().map(|r| slot(r.1)).sum::<u64>().max(4);
    let mut offset = 0;
    for &(buffer, bytes) in reads {
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(buffer, 0, staging, offset, bytes);
        }
        offset += slot(bytes);
    }
    let submitted = std::time::Instant::now();
    ctx.queue.submit([encoder.finish()]);
    staging
        .slice(..total)
        .map_async(wgpu::MapMode::Read, |_| {});
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| GpuError::Device(e.to_string()))?;
    let mut out = Vec::with_capacity(reads.len());
    {
        let view = staging
            .slice(..total)
            .get_mapped_range()
            .map_err(|e| GpuError::Device(format!("map: {e}")))?;
        let mut offset = 0usize;
        for &(_, bytes) in reads {
            out.push(view[offset..offset + bytes as usize].to_vec());
            offset += slot(bytes) as usize;
        }
    }
    staging.unmap();
    crate::tally::add_readback(total, submitted.elapsed());
    Ok(out)
}

/// The values in bytes read back (copied: a byte vector need not be aligned for `T`).
pub fn values<T: bytemuck::Pod>(bytes: &[u8]) -> Vec<T> {
    bytemuck::pod_collect_to_vec(bytes)
}

/// A staging buffer kept by a runner that reads back at every iteration (the resident
/// batches), made at the first read and grown when a read needs more: no buffer is made
/// per read.
#[derive(Default)]
pub struct Staging(std::sync::Mutex<Option<wgpu::Buffer>>);

impl Staging {
    /// [`submit_and_read_into`] this buffer.
    pub fn read(
        &self,
        ctx: &GpuContext,
        encoder: wgpu::CommandEncoder,
        reads: &[(&wgpu::Buffer, u64)],
    ) -> Result<Vec<Vec<u8>>, GpuError> {
        let sizes: Vec<u64> = reads.iter().map(|r| r.1).collect();
        let need = sizes.iter().map(|&b| slot(b)).sum::<u64>().max(4);
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if kept.as_ref().is_none_or(|b| b.size() < need) {
            *kept = Some(staging_buffer(ctx, "read", &sizes));
        }
        let staging = kept.as_ref().expect("made above");
        submit_and_read_into(ctx, encoder, staging, reads)
    }
}
