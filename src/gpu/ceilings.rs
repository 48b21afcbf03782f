//! The device's own ceilings, measured on it, for a roofline (`holewall bench kernels`): a
//! multiply-add-chain kernel (eight independent `vec4` chains per invocation in registers,
//! f32 and f64) for the arithmetic peak, and a copy kernel (`vec4<f32>` read and written once) for the memory
//! bandwidth. Both run through [`crate::gpu::dispatch`] under its timing, as the kernels do.

use crate::error::GpuError;
use crate::gpu::dispatch::{run_once, timed, Out};
use crate::gpu::GpuContext;

/// Chains per invocation of the FMA kernel.
const CHAINS: usize = 8;

/// Lanes of each chain (`vec4`: SIMD within an invocation where the driver runs
/// invocations one at a time).
const LANES: usize = 4;

fn fma_wgsl(f64: bool) -> String {
    let (t, s) = if f64 { ("f64", "lf") } else { ("f32", "f") };
    let mut body = String::new();
    for c in 0..CHAINS {
        body.push_str(&format!(
            "    var a{c} = vec4<{t}>({t}(gid.x) * 1.0e-9{s} + {c}.0{s}, 1.0{s}, 2.0{s}, 3.0{s});\n"
        ));
    }
    body.push_str("    for (var k = 0u; k < params[0]; k++) {\n");
    for c in 0..CHAINS {
        // A multiply and an add, as the kernels write them (the driver may fuse them): the
        // `fma` builtin is a library call per lane where the driver's target lacks FMA
        // (lavapipe in a VM measured 3.6 GFLOP/s with it, below the beam kernel's 4.4).
        body.push_str(&format!("        a{c} = a{c} * b + c;\n"));
    }
    body.push_str("    }\n    out[gid.x] = dot(");
    body.push_str(
        &(0..CHAINS)
            .map(|c| format!("a{c}"))
            .collect::<Vec<_>>()
            .join(" + "),
    );
    body.push_str(&format!(", vec4<{t}>(1.0{s}));\n"));
    format!(
        "@group(0) @binding(0) var<storage, read> params: array<u32>;\n\
         @group(0) @binding(1) var<storage, read_write> out: array<{t}>;\n\
         @compute @workgroup_size(64)\n\
         fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
         \x20   let b = {t}(params[1]) * 1.0e-9{s} + 0.999999{s};\n\
         \x20   let c = {t}(params[1]) * 1.0e-9{s} + 1.0e-7{s};\n\
         {body}}}\n"
    )
}

const COPY_WGSL: &str = "@group(0) @binding(0) var<storage, read> params: array<u32>;
@group(0) @binding(1) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> dst: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    // Grid-stride, counted (src/gpu/loops.rs): rounds of params[1] invocations.
    let rounds = (params[0] + params[1] - 1u) / params[1];
    for (var k = 0u; k < rounds; k++) {
        let i = gid.x + k * params[1];
        if (i < params[0]) {
            dst[i] = src[i];
        }
    }
}
";

/// The measured ceilings: each the fastest of its repeats (a ceiling is the best the device
/// does; the median let a busy machine — a CI run beside it — put the ceiling under the
/// kernels' own medians: the beam at 2.4× its "ceiling").
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Ceilings {
    /// FMA-chain throughput, f32 (GFLOP/s, an FMA counted as two).
    pub fma_gflops_f32: f64,
    /// The same in f64, where the adapter has it.
    pub fma_gflops_f64: Option<f64>,
    /// Copy bandwidth (GB/s, bytes read plus bytes written).
    pub copy_gbytes_per_s: f64,
}

fn fastest(x: Vec<f64>) -> f64 {
    x.into_iter().fold(f64::NAN, f64::min)
}

/// The shortest run a ceiling is read from: long enough that the submission and the wait
/// (tens of microseconds on a real GPU) are a percent of it.
const MIN_SECONDS: f64 = 0.01;

/// Measures the ceilings on `ctx`: `repeats` timed runs each, at a size grown by doubling
/// until the fastest run takes [`MIN_SECONDS`] — a fixed size that suits lavapipe
/// (seconds) is over in microseconds on an H100, where the launch then dominates (the first
/// H100 run read 4.9 TFLOP/s and 0.5 TB/s at the old fixed sizes).
pub fn measure(ctx: &GpuContext, repeats: usize) -> Result<Ceilings, GpuError> {
    let invocations: usize = 1 << 18;
    let fma = |f64: bool| -> Result<f64, GpuError> {
        let pipeline = ctx.pipeline("ceiling_fma", &fma_wgsl(f64))?;
        let size = if f64 { 8 } else { 4 };
        let mut iterations: u32 = 64;
        loop {
            let params = [iterations, 1u32];
            let (r, t) = timed(repeats, || {
                run_once(
                    ctx,
                    &pipeline,
                    "ceiling_fma",
                    bytemuck::cast_slice(&params),
                    &[],
                    &[Out::Empty(invocations * size)],
                    invocations,
                )
            });
            r?;
            let seconds = fastest(t.iter().flat_map(|k| k.kernel_seconds().to_vec()).collect());
            if seconds >= MIN_SECONDS || iterations >= 1 << 15 {
                let flops = (invocations * iterations as usize * CHAINS * LANES * 2) as f64;
                return Ok(flops / seconds / 1e9);
            }
            iterations *= 2;
        }
    };
    let fma_gflops_f32 = fma(false)?;
    let fma_gflops_f64 = if ctx.has_f64 { Some(fma(true)?) } else { None };
    let pipeline = ctx.pipeline("ceiling_copy", COPY_WGSL)?;
    let largest = (ctx.max_binding_bytes() as usize).min(1 << 30) / 16 * 16;
    let mut bytes = largest.min(32 << 20);
    loop {
        let words = bytes / 16;
        let src = vec![1u8; bytes];
        // Grid-stride: a GPU's one-dimensional dispatch holds 65,535 workgroups.
        let threads = words.min(65_535 * 64);
        let params = [words as u32, threads as u32];
        let (r, t) = timed(repeats, || {
            run_once(
                ctx,
                &pipeline,
                "ceiling_copy",
                bytemuck::cast_slice(&params),
                &[&src],
                &[Out::Empty(bytes)],
                threads,
            )
        });
        r?;
        let seconds = fastest(t.iter().flat_map(|k| k.kernel_seconds().to_vec()).collect());
        if seconds >= MIN_SECONDS || bytes * 2 > largest {
            return Ok(Ceilings {
                fma_gflops_f32,
                fma_gflops_f64,
                copy_gbytes_per_s: 2.0 * bytes as f64 / seconds / 1e9,
            });
        }
        bytes *= 2;
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_ceiling_kernels_are_valid_wgsl() {
        for f64 in [false, true] {
            crate::gpu::compose::validate(&super::fma_wgsl(f64)).unwrap();
        }
        crate::gpu::compose::validate(super::COPY_WGSL).unwrap();
    }
}
