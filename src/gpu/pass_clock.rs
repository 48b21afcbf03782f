//! The device's own time of a resident batch's compute passes: timestamps at a pass's start
//! and end, resolved and read back with the pass's other results (no round trip of its
//! own), added to [`crate::tally`]. Where the adapter has no `TIMESTAMP_QUERY` there is no
//! clock and nothing is recorded.

use crate::gpu::GpuContext;

/// Bytes of a resolved pair of timestamps.
pub const BYTES: u64 = 16;

/// A pair of timestamps and the buffer they are resolved into.
pub struct PassClock {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    period_ns: f64,
}

impl PassClock {
    /// A clock, where the adapter has timestamps.
    pub fn new(ctx: &GpuContext, label: &str) -> Option<Self> {
        ctx.has_timestamps.then(|| PassClock {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolved: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: BYTES,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            period_ns: f64::from(ctx.queue.get_timestamp_period()),
        })
    }

    /// A compute pass stamped at its start and end by `clock`, where there is one.
    pub fn pass<'e>(
        clock: Option<&PassClock>,
        encoder: &'e mut wgpu::CommandEncoder,
    ) -> wgpu::ComputePass<'e> {
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: clock.map(|c| wgpu::ComputePassTimestampWrites {
                query_set: &c.set,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: Some(1),
            }),
        })
    }

    /// Resolves the pass's stamps (after the pass) and names the buffer to read with the
    /// pass's results.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) -> (&wgpu::Buffer, u64) {
        encoder.resolve_query_set(&self.set, 0..2, &self.resolved, 0);
        (&self.resolved, BYTES)
    }

    /// Adds the pass's device time, from the stamps' bytes read back, to the tally
    /// (`trial`: a line-search trial's pass).
    pub fn record(&self, bytes: &[u8], trial: bool) {
        let ticks: Vec<u64> = crate::gpu::readback::values(bytes);
        if let [start, end] = ticks[..] {
            let ns = end.saturating_sub(start) as f64 * self.period_ns;
            crate::tally::add_device(std::time::Duration::from_nanos(ns as u64), trial);
        }
    }
}
