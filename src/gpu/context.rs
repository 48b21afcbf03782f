//! The wgpu context: one instance, adapter, device and queue per process, made once.
//!
//! Adapter choice honours `WGPU_BACKEND` (which backends the instance opens),
//! `WGPU_ADAPTER_NAME` (a case-insensitive substring of the adapter name) and
//! `WGPU_POWER_PREF`. Pipelines are cached by their feature set
//! ([`GpuContext::pipeline`]), so each specialised kernel is compiled once per process.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use crate::error::GpuError;

/// What `gpu-info` prints about one adapter.
#[derive(Clone, Debug)]
pub struct AdapterSummary {
    /// wgpu's adapter info (name, backend, device type, driver).
    pub info: wgpu::AdapterInfo,
    /// Features the adapter offers.
    pub features: wgpu::Features,
    /// Limits the adapter offers.
    pub limits: wgpu::Limits,
}

/// Lists every adapter the instance (as `WGPU_BACKEND` sets it) can see.
pub fn list_adapters() -> Vec<AdapterSummary> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    pollster::block_on(instance.enumerate_adapters(backends))
        .into_iter()
        .map(|a| AdapterSummary {
            info: a.get_info(),
            features: a.features(),
            limits: a.limits(),
        })
        .collect()
}

/// A device and queue with the features holewall uses, and a pipeline cache.
pub struct GpuContext {
    /// The chosen adapter.
    pub adapter: wgpu::Adapter,
    /// Its device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter info, for reports.
    pub info: wgpu::AdapterInfo,
    /// The device's limits (the adapter's, requested in full).
    pub limits: wgpu::Limits,
    /// Whether `f64` kernels can run (`SHADER_F64`).
    pub has_f64: bool,
    /// Whether the device writes timestamps at the start and end of a compute pass
    /// (`TIMESTAMP_QUERY`): the benches' device-side kernel times.
    pub has_timestamps: bool,
    /// Whether the driver fuses `a·b + c` into one rounding ([`GpuContext::fuses_multiply_add`]).
    fuses: std::sync::OnceLock<Result<bool, GpuError>>,
    pipelines: Mutex<HashMap<String, Arc<wgpu::ComputePipeline>>>,
}

static SHARED: OnceLock<Result<GpuContext, GpuError>> = OnceLock::new();

impl GpuContext {
    /// The process-wide context, made on first use.
    pub fn shared() -> Result<&'static GpuContext, GpuError> {
        SHARED
            .get_or_init(GpuContext::create)
            .as_ref()
            .map_err(Clone::clone)
    }

    /// Opens the adapter that the environment selects and a device on it.
    pub fn create() -> Result<GpuContext, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
        let adapter = match std::env::var("WGPU_ADAPTER_NAME") {
            Ok(wanted) => {
                let wanted = wanted.to_lowercase();
                let adapters = pollster::block_on(instance.enumerate_adapters(backends));
                let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
                adapters
                    .into_iter()
                    .find(|a| a.get_info().name.to_lowercase().contains(&wanted))
                    .ok_or_else(|| {
                        GpuError::NoAdapter(format!(
                            "WGPU_ADAPTER_NAME={wanted:?} matches none of {names:?}"
                        ))
                    })?
            }
            Err(_) => pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::from_env().unwrap_or_default(),
                force_fallback_adapter: false,
                compatible_surface: None,
                ..Default::default()
            }))
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?,
        };
        let info = adapter.get_info();
        let has_f64 = adapter.features().contains(wgpu::Features::SHADER_F64);
        let mut required_features = wgpu::Features::empty();
        if has_f64 {
            required_features |= wgpu::Features::SHADER_F64;
        }
        let has_timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        if has_timestamps {
            required_features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("holewall"),
            required_features,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(GpuContext {
            adapter,
            device,
            queue,
            info,
            limits,
            has_f64,
            has_timestamps,
            fuses: std::sync::OnceLock::new(),
            pipelines: Mutex::new(HashMap::new()),
        })
    }

    /// Whether the driver contracts a multiply and an add into a fused multiply-add (one
    /// rounding) — WGSL allows it and has no way to forbid it. Measured once by a probe:
    /// `a·a − b` with `a = 1 + 2⁻¹²`, `b = 1 + 2⁻¹¹` from a buffer is 2⁻²⁴ fused and 0 rounded
    /// twice. NVIDIA's Vulkan driver fuses (seen on an H100), lavapipe does not. Where it
    /// fuses, two builds of one formula (a kernel and its twin, or two forms of a kernel)
    /// agree to rounding, not to the bit, and the tests compare them so.
    pub fn fuses_multiply_add(&self) -> Result<bool, GpuError> {
        self.fuses
            .get_or_init(|| {
                let wgsl = "@group(0) @binding(0) var<storage, read> params: array<u32>;\n\
                    @group(0) @binding(1) var<storage, read> x: array<f32>;\n\
                    @group(0) @binding(2) var<storage, read_write> y: array<f32>;\n\
                    @compute @workgroup_size(64)\n\
                    fn main(@builtin(global_invocation_id) gid: vec3<u32>) {\n\
                    \x20   if (gid.x == params[0]) { y[0] = x[0] * x[1] + x[2]; }\n\
                    }\n";
                let pipeline = self.pipeline("fma_probe", wgsl)?;
                let a = 1.0f32 + 2f32.powi(-12);
                let x = [a, a, -(1.0f32 + 2f32.powi(-11))];
                let out = crate::gpu::dispatch::run_once(
                    self,
                    &pipeline,
                    "fma_probe",
                    bytemuck::cast_slice(&[0u32]),
                    &[bytemuck::cast_slice(&x)],
                    &[crate::gpu::dispatch::Out::Empty(4)],
                    1,
                )?;
                let y: Vec<f32> = crate::gpu::readback::values(&out[0]);
                Ok(y[0] != 0.0)
            })
            .clone()
    }

    /// One line naming the adapter, for reports.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            self.info.name,
            self.info.backend,
            self.info.device_type,
            self.info.driver,
            self.info.driver_info
        )
    }

    /// The largest storage binding, in bytes, that a kernel may use on this device.
    pub fn max_binding_bytes(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }

    /// The compute pipeline for `wgsl` (entry point `main`), compiled once per distinct
    /// source text and cached: the text is the feature set, assembled by
    /// [`crate::gpu::compose`].
    pub fn pipeline(
        &self,
        label: &str,
        wgsl: &str,
    ) -> Result<Arc<wgpu::ComputePipeline>, GpuError> {
        let mut cache = self
            .pipelines
            .lock()
            .map_err(|_| GpuError::Device("pipeline cache poisoned".into()))?;
        if let Some(p) = cache.get(wgsl) {
            return Ok(p.clone());
        }
        // Every loop counted (proved here, once per source text): the kernel compiles
        // without wgpu's loop bounding, whose extra exit kept the driver from unrolling the
        // loops over a block's entries (src/gpu/loops.rs). Bounds checks stay on.
        crate::gpu::loops::check(wgsl).map_err(|e| GpuError::Shader(format!("{label}: {e}")))?;
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut checks = wgpu::ShaderRuntimeChecks::checked();
        checks.force_loop_bounding = false;
        // SAFETY: `force_loop_bounding = false` requires that the shader has no loop that
        // never ends; `loops::check` has just proved every loop counted (WGSL has no
        // recursion). Every other check is kept.
        let module = unsafe {
            self.device.create_shader_module_trusted(
                wgpu::ShaderModuleDescriptor {
                    label: Some(label),
                    source: wgpu::ShaderSource::Wgsl(wgsl.into()),
                },
                checks,
            )
        };
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            });
        if let Some(err) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(format!("{label}: {err}")));
        }
        let pipeline = Arc::new(pipeline);
        cache.insert(wgsl.to_string(), pipeline.clone());
        Ok(pipeline)
    }
}
