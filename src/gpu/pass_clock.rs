//! The device's own time of a compute pass: timestamps at its start and end, resolved and
//! read back — for a resident batch with the pass's other results (no round trip of its
//! own), added to [`crate::tally`]; for `bench kernels` by [`crate::gpu::dispatch::timed`].
//! Where the adapter has no `TIMESTAMP_QUERY` there is no clock and nothing is recorded.

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

    /// The pass's device time (s), from the stamps' bytes read back.
    pub fn seconds(&self, bytes: &[u8]) -> f64 {
        let ticks: Vec<u64> = crate::gpu::readback::values(bytes);
        match ticks[..] {
            [start, end, ..] => end.saturating_sub(start) as f64 * self.period_ns * 1e-9,
            _ => 0.0,
        }
    }

    /// Adds the pass's device time, from the stamps' bytes read back, to the tally
    /// (`trial`: a line-search trial's pass).
    pub fn record(&self, bytes: &[u8], trial: bool) {
        let took = std::time::Duration::from_secs_f64(self.seconds(bytes));
        crate::tally::add_device(took, trial);
    }
}
