//! One-shot dispatch of a kernel whose bindings are: its parameters (binding 0, a read-only
//! storage buffer, not a uniform: see `tests/shaders.rs`), read-only
//! storage inputs, then read-write storage outputs, in that order. Buffers are made, the
//! kernel runs once over `invocations` (workgroups of 64), and every output is read back.

use wgpu::util::DeviceExt;

use crate::error::GpuError;
use crate::gpu::GpuContext;

/// Invocations per workgroup of every kernel dispatched here.
pub const WORKGROUP: usize = 64;

/// A read-write binding: its size, or its initial contents.
#[derive(Clone, Copy, Debug)]
pub enum Out<'a> {
    /// Uninitialised, this many bytes.
    Empty(usize),
    /// Starts with these bytes (updated in place by the kernel).
    From(&'a [u8]),
}

impl Out<'_> {
    fn bytes(&self) -> usize {
        match self {
            Out::Empty(n) => *n,
            Out::From(b) => b.len(),
        }
    }
}

/// One kernel's dispatches timed by [`timed`]: the wall time of each repeat (submit to
/// finished, outputs restored to their initial contents before each, outside the clock) and
/// the bytes its bindings hold (parameters, inputs, outputs: what one run must at least read
/// or write).
#[derive(Clone, Debug)]
pub struct KernelTiming {
    /// The kernel's label.
    pub label: String,
    /// Seconds per repeat (all of the kernel's passes), on the host's clock: submission to
    /// the end of the wait.
    pub seconds: Vec<f64>,
    /// Seconds per repeat between the device's timestamps at the start and the end of the
    /// compute pass (the kernel alone, without the submission and the wait); empty where the
    /// adapter has no `TIMESTAMP_QUERY`.
    pub device_seconds: Vec<f64>,
    /// Bytes of its inputs (parameters included).
    pub bytes_in: u64,
    /// Bytes of its outputs.
    pub bytes_out: u64,
    /// Invocations of all its passes together.
    pub invocations: usize,
    /// Passes (dispatches) per run.
    pub passes: usize,
}

thread_local! {
    static TIMING: std::cell::RefCell<Option<(usize, Vec<KernelTiming>)>> =
        const { std::cell::RefCell::new(None) };
}

impl KernelTiming {
    /// The kernel's own seconds per repeat: the device's timestamps where it has them, else
    /// the host's clock.
    pub fn kernel_seconds(&self) -> &[f64] {
        if self.device_seconds.is_empty() {
            &self.seconds
        } else {
            &self.device_seconds
        }
    }
}

/// Runs `f` with every dispatch of this module timed `repeats` times after its first (the
/// results `f` gets are the first run's): `holewall bench kernels`' measurement, on this
/// thread only.
pub fn timed<R>(repeats: usize, f: impl FnOnce() -> R) -> (R, Vec<KernelTiming>) {
    let before = TIMING.with(|t| t.replace(Some((repeats.max(1), Vec::new()))));
    let r = f();
    let got = TIMING.with(|t| t.replace(before));
    (r, got.map(|g| g.1).unwrap_or_default())
}

/// Runs `pipeline` once; returns the bytes of each output, in order.
pub fn run_once(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    label: &str,
    params: &[u8],
    inputs: &[&[u8]],
    outputs: &[Out],
    invocations: usize,
) -> Result<Vec<Vec<u8>>, GpuError> {
    run_passes(
        ctx,
        pipeline,
        label,
        &[params],
        inputs,
        outputs,
        &[invocations],
    )
}

/// Runs `pipeline` once per parameter block, in order, on the same storage buffers (each dispatch
/// sees the previous one's writes), with `invocations[k]` invocations for block `k`; returns
/// the bytes of each output after the last.
pub fn run_passes(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    label: &str,
    params: &[&[u8]],
    inputs: &[&[u8]],
    outputs: &[Out],
    invocations: &[usize],
) -> Result<Vec<Vec<u8>>, GpuError> {
    assert_eq!(
        invocations.len(),
        params.len(),
        "one invocation count per pass"
    );
    let output_bytes: Vec<usize> = outputs.iter().map(Out::bytes).collect();
    let input_bytes: usize = inputs.iter().map(|b| b.len()).sum();
    // The outputs' initial contents (for a timed run's restore).
    let initial: Vec<Option<&[u8]>> = outputs
        .iter()
        .map(|o| match o {
            Out::From(b) if !b.is_empty() => Some(*b),
            _ => None,
        })
        .collect();
    let device = &ctx.device;
    let dims: Vec<wgpu::Buffer> = params
        .iter()
        .map(|u| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: u,
                usage: wgpu::BufferUsages::STORAGE,
            })
        })
        .collect();
    let inputs: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|bytes| {
            // Empty bindings are not allowed: pad to one word.
            let padded: &[u8] = if bytes.is_empty() { &[0u8; 4] } else { bytes };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: padded,
                usage: wgpu::BufferUsages::STORAGE,
            })
        })
        .collect();
    // COPY_DST: a timed run restores the outputs' first contents before each repeat.
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let outputs: Vec<wgpu::Buffer> = outputs
        .iter()
        .map(|out| match out {
            Out::From(bytes) if !bytes.is_empty() => {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytes,
                    usage,
                })
            }
            _ => device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: out.bytes().max(4) as u64,
                usage,
                mapped_at_creation: false,
            }),
        })
        .collect();
    let layout = pipeline.get_bind_group_layout(0);
    let bind_groups: Vec<wgpu::BindGroup> = dims
        .iter()
        .map(|d| {
            let entries: Vec<wgpu::BindGroupEntry> = std::iter::once(d)
                .chain(inputs.iter())
                .chain(outputs.iter())
                .enumerate()
                .map(|(k, b)| wgpu::BindGroupEntry {
                    binding: k as u32,
                    resource: b.as_entire_binding(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &layout,
                entries: &entries,
            })
        })
        .collect();
    // An encoder holding every pass of the kernel (the first run, and each timed repeat,
    // then with timestamps at the compute pass's start and end where the device has them).
    let passes = |clock: Option<&crate::gpu::pass_clock::PassClock>| {
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        {
            let mut pass = crate::gpu::pass_clock::PassClock::pass(clock, &mut encoder);
            pass.set_pipeline(pipeline);
            for (bg, k) in bind_groups.iter().zip(invocations) {
                pass.set_bind_group(0, bg, &[]);
                pass.dispatch_workgroups(k.div_ceil(WORKGROUP) as u32, 1, 1);
            }
        }
        encoder
    };
    let reads: Vec<(&wgpu::Buffer, u64)> = outputs
        .iter()
        .zip(&output_bytes)
        .map(|(b, &bytes)| (b, bytes as u64))
        .collect();
    let result = crate::gpu::readback::submit_and_read(ctx, passes(None), &reads)?;
    if let Some(repeats) = TIMING.with(|t| t.borrow().as_ref().map(|t| t.0)) {
        // The outputs' first contents, to restore before each timed run.
        let pristine: Vec<(usize, wgpu::Buffer)> = initial
            .iter()
            .enumerate()
            .filter_map(|(k, b)| b.map(|b| (k, b)))
            .map(|(k, b)| {
                (
                    k,
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents: b,
                        usage: wgpu::BufferUsages::COPY_SRC,
                    }),
                )
            })
            .collect();
        let wait = || {
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map(|_| ())
                .map_err(|e| GpuError::Device(e.to_string()))
        };
        let clock = crate::gpu::pass_clock::PassClock::new(ctx, label);
        let mut seconds = Vec::with_capacity(repeats);
        let mut device_seconds = Vec::new();
        for _ in 0..repeats {
            if !pristine.is_empty() {
                let mut e = device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
                for (k, b) in &pristine {
                    e.copy_buffer_to_buffer(b, 0, &outputs[*k], 0, b.size());
                }
                ctx.queue.submit([e.finish()]);
                wait()?;
            }
            let e = passes(clock.as_ref());
            let started = std::time::Instant::now();
            ctx.queue.submit([e.finish()]);
            wait()?;
            seconds.push(started.elapsed().as_secs_f64());
            if let Some(clock) = &clock {
                let mut e = device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
                let read = clock.resolve(&mut e);
                let got = crate::gpu::readback::submit_and_read(ctx, e, &[read])?;
                device_seconds.push(clock.seconds(&got[0]));
            }
        }
        let timing = KernelTiming {
            label: label.to_string(),
            seconds,
            device_seconds,
            bytes_in: (params.iter().map(|p| p.len()).sum::<usize>() + input_bytes) as u64,
            bytes_out: output_bytes.iter().sum::<usize>() as u64,
            invocations: invocations.iter().sum(),
            passes: params.len(),
        };
        TIMING.with(|t| {
            if let Some(t) = t.borrow_mut().as_mut() {
                t.1.push(timing)
            }
        });
    }
    Ok(result)
}
