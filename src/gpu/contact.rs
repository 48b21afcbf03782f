//! Runs `shaders/contact.wgsl` (twin: `src/kernels/contact.rs`) on the GPU for a
//! [`ContactBatch`], split into parts that fit the adapter's binding limits.

use std::collections::BTreeSet;
use std::marker::PhantomData;
use std::sync::Arc;

use wgpu::util::DeviceExt;

use crate::error::GpuError;
use crate::gpu::compose::compose;
use crate::gpu::layout::ContactDims;
use crate::gpu::readback;
use crate::gpu::GpuContext;
use crate::kernels::contact::{output_fields, ContactBatch, ContactOutputs, STATE_LEN};
use crate::physics::contact::{ContactMode, ContactTerms, FrictionModel, SpringLaw, PARAMS_LEN};
use crate::physics::Real;

/// A float type a kernel can be compiled for.
pub trait GpuReal: Real + bytemuck::Pod {
    /// Whether this is `f64` (needs `SHADER_F64`).
    const IS_F64: bool;
}

/// An error unless the adapter can run kernels in `T` (f64 needs `SHADER_F64`).
pub fn require_precision<T: GpuReal>(ctx: &GpuContext) -> Result<(), GpuError> {
    if T::IS_F64 && !ctx.has_f64 {
        return Err(GpuError::Unsupported(format!(
            "adapter {} has no SHADER_F64; use --precision f32",
            ctx.info.name
        )));
    }
    Ok(())
}

impl GpuReal for f32 {
    const IS_F64: bool = false;
}

impl GpuReal for f64 {
    const IS_F64: bool = true;
}

/// The composition flags of the contact kernel for a set of terms.
pub fn contact_flags(terms: &ContactTerms) -> BTreeSet<&'static str> {
    let mut flags = BTreeSet::new();
    if terms.spring != SpringLaw::Linear {
        flags.insert("POW");
    }
    if terms.spring == SpringLaw::PowerBlend {
        flags.insert("BLEND");
    }
    let dynamic = terms.mode == ContactMode::Dynamic;
    if dynamic {
        flags.insert("DYNAMIC");
    }
    if dynamic && terms.damping {
        flags.insert("DAMPING");
    }
    match terms.friction {
        Some(FrictionModel::Split) => {
            flags.insert("FRICTION");
            flags.insert("SPLIT");
        }
        Some(FrictionModel::Coupled) => {
            flags.insert("FRICTION");
            flags.insert("COUPLED");
        }
        None => {}
    }
    flags
}

/// The WGSL text of the contact kernel specialised to `terms` and a precision.
pub fn contact_wgsl(terms: &ContactTerms, f64: bool) -> Result<String, GpuError> {
    let mut flags = contact_flags(terms);
    if f64 {
        flags.insert("F64");
    }
    compose("contact.wgsl", &flags, f64)
}

/// The WGSL text of the contact kernel built `FORCE_ONLY` (line-search trials, static or
/// dynamic): the force and moment `g` (fields 0–5; in a dynamic scene with the wall's
/// damping and the friction of the sites' velocities) and the contact flag alone; the
/// stiffness and damping fields are not written. `masked`: one invocation per (site,
/// listed variant) of the compacted list of searching variants `[A, v_0, …]` (binding 6;
/// pairs `site · V + v`, V = `mask_variants`); the other pairs are skipped.
pub fn contact_force_wgsl(
    terms: &ContactTerms,
    f64: bool,
    masked: bool,
) -> Result<String, GpuError> {
    let mut flags = contact_flags(terms);
    flags.insert("FORCE_ONLY");
    if masked {
        flags.insert("MASKED");
    }
    if f64 {
        flags.insert("F64");
    }
    compose("contact.wgsl", &flags, f64)
}

/// The WGSL text of the contact kernel specialised to `terms` built `MASKED` (the dynamic
/// engine's Newton iterations): the whole response of the listed variants `[A, v_0, …]`
/// (binding 6; pairs `site · V + v`, V = `mask_variants`); the other pairs are skipped.
pub fn contact_masked_wgsl(terms: &ContactTerms, f64: bool) -> Result<String, GpuError> {
    let mut flags = contact_flags(terms);
    flags.insert("MASKED");
    if f64 {
        flags.insert("F64");
    }
    compose("contact.wgsl", &flags, f64)
}

/// Invocations per workgroup in `shaders/contact.wgsl`.
const WORKGROUP: usize = 64;

struct Part {
    offset: usize,
    len: usize,
    _params: wgpu::Buffer,
    state: wgpu::Buffer,
    values: wgpu::Buffer,
    contact: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// A batch resident on the GPU: buffers and bind groups made once; [`Self::dispatch`] and
/// [`Self::read`] can be repeated (benchmarks time them apart).
pub struct GpuContactRun<T: GpuReal> {
    ctx: &'static GpuContext,
    pipeline: Arc<wgpu::ComputePipeline>,
    parts: Vec<Part>,
    num_pairs: usize,
    /// Output fields the kernel writes ([`output_fields`]).
    fields: usize,
    /// Where [`Self::read`] copies every part's outputs (made once).
    staging: wgpu::Buffer,
    _real: PhantomData<T>,
}

fn bytes_of_len<T>(n: usize) -> u64 {
    (n.max(1) * std::mem::size_of::<T>()) as u64
}

impl<T: GpuReal> GpuContactRun<T> {
    /// Compiles (or fetches from the cache) the kernel for `terms` and uploads `batch`, in
    /// parts as large as the adapter's binding limits allow.
    pub fn new(
        ctx: &'static GpuContext,
        terms: &ContactTerms,
        batch: &ContactBatch<T>,
    ) -> Result<Self, GpuError> {
        Self::with_part_limit(ctx, terms, batch, usize::MAX)
    }

    /// As [`Self::new`] with the static kernel built `FORCE_ONLY` ([`contact_force_wgsl`]):
    /// the outputs' `g` fields and flags as the full kernel's; the others zero.
    pub fn force_only(
        ctx: &'static GpuContext,
        terms: &ContactTerms,
        batch: &ContactBatch<T>,
    ) -> Result<Self, GpuError> {
        Self::build(ctx, terms, batch, usize::MAX, true)
    }

    /// As [`Self::new`], with at most `max_part_pairs` pairs per part (tests use it to put
    /// part boundaries inside a site).
    pub fn with_part_limit(
        ctx: &'static GpuContext,
        terms: &ContactTerms,
        batch: &ContactBatch<T>,
        max_part_pairs: usize,
    ) -> Result<Self, GpuError> {
        Self::build(ctx, terms, batch, max_part_pairs, false)
    }

    fn build(
        ctx: &'static GpuContext,
        terms: &ContactTerms,
        batch: &ContactBatch<T>,
        max_part_pairs: usize,
        force_only: bool,
    ) -> Result<Self, GpuError> {
        require_precision::<T>(ctx)?;
        let (label, wgsl) = if force_only {
            (
                "contact_force",
                contact_force_wgsl(terms, T::IS_F64, false)?,
            )
        } else {
            ("contact", contact_wgsl(terms, T::IS_F64)?)
        };
        let pipeline = ctx.pipeline(label, &wgsl)?;
        let device = &ctx.device;
        let size = std::mem::size_of::<T>();
        let max_binding = ctx.max_binding_bytes() as usize;
        let max_groups = ctx.limits.max_compute_workgroups_per_dimension as usize;
        let fields = output_fields(terms);
        let cap = (max_binding / (fields * size))
            .min(max_groups * WORKGROUP)
            .min(max_part_pairs)
            .max(1);
        let num_pairs = batch.num_pairs();
        if batch.site_normals.len() * size > max_binding {
            return Err(GpuError::Unsupported(
                "too many sites for one binding".into(),
            ));
        }
        let normals = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("site_normals"),
            contents: bytemuck::cast_slice(if batch.site_normals.is_empty() {
                &[0u32; 4][..]
            } else {
                bytemuck::cast_slice(&batch.site_normals)
            }),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let layout = pipeline.get_bind_group_layout(0);
        let mut parts = Vec::new();
        let mut offset = 0;
        while offset < num_pairs {
            let len = cap.min(num_pairs - offset);
            let gather = |data: &[T], fields: usize| -> Vec<T> {
                let mut out = Vec::with_capacity(fields * len);
                for k in 0..fields {
                    out.extend_from_slice(
                        &data[k * num_pairs + offset..k * num_pairs + offset + len],
                    );
                }
                out
            };
            let storage = |label: &str, contents: &[T]| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytemuck::cast_slice(contents),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                })
            };
            let params = storage("pair_params", &gather(&batch.pair_params, PARAMS_LEN));
            let state = storage("pair_state", &gather(&batch.pair_state, STATE_LEN));
            let values_bytes = bytes_of_len::<T>(fields * len);
            let contact_bytes = bytes_of_len::<u32>(len);
            let values = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("out_values"),
                size: values_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let contact = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("out_contact"),
                size: contact_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let dims = ContactDims {
                num_pairs: len as u32,
                num_variants: batch.num_variants as u32,
                pair_offset: offset as u32,
                mask_variants: 0,
            };
            let dims = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("contact_dims"),
                contents: bytemuck::bytes_of(&dims),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("contact"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: dims.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: normals.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: state.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: values.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: contact.as_entire_binding(),
                    },
                ],
            });
            parts.push(Part {
                offset,
                len,
                _params: params,
                state,
                values,
                contact,
                bind_group,
            });
            offset += len;
        }
        let reads: Vec<u64> = parts
            .iter()
            .flat_map(|c| {
                [
                    bytes_of_len::<T>(fields * c.len),
                    bytes_of_len::<u32>(c.len),
                ]
            })
            .collect();
        let staging = readback::staging_buffer(ctx, "contact_staging", &reads);
        Ok(GpuContactRun {
            ctx,
            pipeline,
            parts,
            num_pairs,
            fields,
            staging,
            _real: PhantomData,
        })
    }

    /// Bytes of the output buffers on the device (every part): `fields × pairs × size`,
    /// with [`output_fields`] of the scene — half for a static scene.
    pub fn output_bytes(&self) -> u64 {
        self.parts
            .iter()
            .map(|c| bytes_of_len::<T>(self.fields * c.len))
            .sum()
    }

    /// Number of parts the batch was split into.
    pub fn num_parts(&self) -> usize {
        self.parts.len()
    }

    /// Re-uploads the state (`d`, `v`, `omega`) of every pair; parameters stay.
    pub fn write_state(&self, batch: &ContactBatch<T>) {
        let p = self.num_pairs;
        for part in &self.parts {
            let mut data = Vec::with_capacity(STATE_LEN * part.len);
            for k in 0..STATE_LEN {
                data.extend_from_slice(
                    &batch.pair_state[k * p + part.offset..k * p + part.offset + part.len],
                );
            }
            self.ctx
                .queue
                .write_buffer(&part.state, 0, bytemuck::cast_slice(&data));
        }
    }

    /// Runs the kernel over every part and waits for it to finish.
    pub fn dispatch(&self) -> Result<(), GpuError> {
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("contact"),
            });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("contact"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            for part in &self.parts {
                pass.set_bind_group(0, &part.bind_group, &[]);
                pass.dispatch_workgroups(part.len.div_ceil(WORKGROUP) as u32, 1, 1);
            }
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.wait()
    }

    fn wait(&self) -> Result<(), GpuError> {
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Device(e.to_string()))
    }

    /// Copies the results back into the CPU twin's layout (the fields a static scene does
    /// not write are zero there).
    pub fn read(&self) -> Result<ContactOutputs<T>, GpuError> {
        let p = self.num_pairs;
        let mut out = ContactOutputs::new(p);
        let encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("contact_read"),
            });
        let reads: Vec<(&wgpu::Buffer, u64)> = self
            .parts
            .iter()
            .flat_map(|c| {
                [
                    (&c.values, bytes_of_len::<T>(self.fields * c.len)),
                    (&c.contact, bytes_of_len::<u32>(c.len)),
                ]
            })
            .collect();
        let bytes = readback::submit_and_read_into(self.ctx, encoder, &self.staging, &reads)?;
        for (part, pair) in self.parts.iter().zip(bytes.chunks_exact(2)) {
            let values: Vec<T> = readback::values(&pair[0]);
            let flags: Vec<u32> = readback::values(&pair[1]);
            // Fields a static scene leaves out stay zero, as the twin's.
            for k in 0..self.fields {
                out.values[k * p + part.offset..k * p + part.offset + part.len]
                    .copy_from_slice(&values[k * part.len..(k + 1) * part.len]);
            }
            out.contact[part.offset..part.offset + part.len].copy_from_slice(&flags[..part.len]);
        }
        Ok(out)
    }
}

/// Evaluates `batch` on the GPU with the kernel specialised to `terms`.
pub fn contact_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    terms: &ContactTerms,
    batch: &ContactBatch<T>,
) -> Result<ContactOutputs<T>, GpuError> {
    let run = GpuContactRun::new(ctx, terms, batch)?;
    run.dispatch()?;
    run.read()
}
