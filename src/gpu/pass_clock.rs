//! The device's own time of a compute pass: timestamps at its start and end, resolved and
//! read back — for a resident batch with the pass's other results (no round trip of its
//! own), added to [`crate::tally`]; for `bench kernels` by [`crate::gpu::dispatch::timed`].
//! Where the adapter has no `TIMESTAMP_QUERY` there is no clock and nothing is recorded.

use crate::gpu::GpuContext;

/// Bytes of a resolved pair of timestamps.
pub const BYTES: u64 = 16;

/// Spans a clock stamps: a submission may time two parts of its passes apart (a dynamic
/// iteration and the line-search trial formed with it).
const SPANS: u32 = 2;

/// Pairs of timestamps (one pair per span) and the buffer they are resolved into.
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
                count: 2 * SPANS,
            }),
            resolved: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: BYTES * u64::from(SPANS),
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
        Self::span_pass(clock, encoder, 0, true, true)
    }

    /// A compute pass that starts span `span` (`begin`) and/or ends it (`end`): a span of
    /// several passes (with copies between them) is timed from its first pass's start to
    /// its last one's end.
    pub fn span_pass<'e>(
        clock: Option<&PassClock>,
        encoder: &'e mut wgpu::CommandEncoder,
        span: u32,
        begin: bool,
        end: bool,
    ) -> wgpu::ComputePass<'e> {
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes: clock.filter(|_| begin || end).map(|c| {
                wgpu::ComputePassTimestampWrites {
                    query_set: &c.set,
                    beginning_of_pass_write_index: begin.then_some(2 * span),
                    end_of_pass_write_index: end.then_some(2 * span + 1),
                }
            }),
        })
    }

    /// Resolves the pass's stamps (after the pass) and names the buffer to read with the
    /// pass's results.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) -> (&wgpu::Buffer, u64) {
        self.resolve_spans(encoder, 1)
    }

    /// Resolves the stamps of the first `spans` spans (each begun and ended in this
    /// submission) and names the buffer to read.
    pub fn resolve_spans(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        spans: u32,
    ) -> (&wgpu::Buffer, u64) {
        let spans = spans.clamp(1, SPANS);
        encoder.resolve_query_set(&self.set, 0..2 * spans, &self.resolved, 0);
        (&self.resolved, BYTES * u64::from(spans))
    }

    /// The pass's device time (s), from the stamps' bytes read back.
    pub fn seconds(&self, bytes: &[u8]) -> f64 {
        self.span_seconds(bytes, 0)
    }

    /// Span `span`'s device time (s), from the stamps' bytes read back.
    pub fn span_seconds(&self, bytes: &[u8], span: usize) -> f64 {
        let ticks: Vec<u64> = crate::gpu::readback::values(bytes);
        match ticks.get(2 * span..2 * span + 2) {
            Some(&[start, end]) => end.saturating_sub(start) as f64 * self.period_ns * 1e-9,
            _ => 0.0,
        }
    }

    /// Adds the pass's device time, from the stamps' bytes read back, to the tally
    /// (`trial`: a line-search trial's pass).
    pub fn record(&self, bytes: &[u8], trial: bool) {
        self.record_span(bytes, 0, u64::from(trial));
    }

    /// Adds span `span`'s device time to the tally, as that of `trials` line-search trials
    /// (0: an iteration's).
    pub fn record_span(&self, bytes: &[u8], span: usize, trials: u64) {
        let took = std::time::Duration::from_secs_f64(self.span_seconds(bytes, span));
        crate::tally::add_device(took, trials);
    }
}
