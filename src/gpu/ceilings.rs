//! The device's own ceilings, measured on it, for a roofline (`holewall bench kernels`): a
//! multiply-add-chain kernel (eight independent `vec4` chains per invocation in registers,
//! f32 and f64) for the arithmetic peak, and copy kernels for the memory bandwidth at every
//! footprint from 1 MB to 256 MB (bytes read plus bytes written), so that a kernel is set
//! against the bandwidth of a copy as large as its own traffic: a kernel whose data fits the
//! caches (on this machine's 32 MB L3, the assembly at V = 64) is not measured against the
//! DRAM's bandwidth, which it can exceed (it read 101–126 % of a 64 MB copy's). At each
//! footprint the faster of two forms counts: a `vec4<f32>` an invocation and an `f32` an
//! invocation (the kernels' own access: a scalar per variant, variants adjacent). All run
//! through [`crate::gpu::dispatch`] under its timing, as the kernels do.

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

/// A copy kernel of `element`s (`vec4<f32>` or `f32`): params = [elements, invocations,
/// passes]; each pass copies the whole buffer, grid-stride (counted loops,
/// src/gpu/loops.rs), so a small footprint is timed over enough passes to dwarf the launch.
fn copy_wgsl(element: &str) -> String {
    format!(
        "@group(0) @binding(0) var<storage, read> params: array<u32>;
@group(0) @binding(1) var<storage, read> src: array<{element}>;
@group(0) @binding(2) var<storage, read_write> dst: array<{element}>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let rounds = (params[0] + params[1] - 1u) / params[1];
    for (var p = 0u; p < params[2]; p++) {{
        for (var k = 0u; k < rounds; k++) {{
            let i = gid.x + k * params[1];
            if (i < params[0]) {{
                dst[i] = src[i];
            }}
        }}
    }}
}}
"
    )
}

/// The copy forms measured at each footprint: (element type, its bytes).
const COPY_FORMS: [(&str, usize); 2] = [("vec4<f32>", 16), ("f32", 4)];

/// Footprints of the copy (bytes read plus written): 1 MB to 256 MB by doubling.
fn copy_footprints() -> impl Iterator<Item = usize> {
    (20..=28).map(|k| 1usize << k)
}

/// The copy's bandwidth at one footprint.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct CopyPoint {
    /// Bytes read plus bytes written by one pass.
    pub footprint_bytes: usize,
    /// The faster form's bandwidth (GB/s, read plus write).
    pub gbytes_per_s: f64,
    /// The faster form's element (`vec4<f32>` or `f32`).
    pub form: &'static str,
    /// Each form's bandwidth (GB/s), in `COPY_FORMS`' order: on lavapipe a storage
    /// access is a loop over the SIMD lanes (Mesa's `emit_load_mem`), which a `vec4` pays
    /// once for four elements.
    pub by_form: [f64; 2],
}

/// The measured ceilings: each the fastest of its repeats (a ceiling is the best the device
/// does; the median let a busy machine — a CI run beside it — put the ceiling under the
/// kernels' own medians: the beam at 2.4× its "ceiling").
#[derive(Clone, Debug, serde::Serialize)]
pub struct Ceilings {
    /// FMA-chain throughput, f32 (GFLOP/s, an FMA counted as two).
    pub fma_gflops_f32: f64,
    /// The same in f64, where the adapter has it.
    pub fma_gflops_f64: Option<f64>,
    /// Copy bandwidth at the largest footprint measured (GB/s, bytes read plus bytes
    /// written): the device memory's, past the caches of every device measured.
    pub copy_gbytes_per_s: f64,
    /// Copy bandwidth at each footprint, smallest first ([`Ceilings::copy_at`]).
    pub copy_curve: Vec<CopyPoint>,
}

impl Ceilings {
    /// The bandwidth ceiling of a kernel moving `bytes`: the best copy at a footprint as
    /// large as `bytes` or larger (from the footprint nearest `bytes` on a log scale up; the
    /// largest footprint where `bytes` is beyond it). Data that fits a cache moves at least as
    /// fast as data that does not, so the best of the larger footprints is a bound at this
    /// one too, and it steadies the curve's run-to-run noise (lavapipe's copy moved
    /// 3.3–6.0 GB/s across footprints without a trend). Not finite `bytes`: the best of all.
    pub fn copy_at(&self, bytes: f64) -> f64 {
        let from = if bytes.is_finite() && bytes > 0.0 {
            bytes / std::f64::consts::SQRT_2
        } else {
            0.0
        };
        self.copy_curve
            .iter()
            .filter(|p| p.footprint_bytes as f64 >= from)
            .map(|p| p.gbytes_per_s)
            .fold(self.copy_gbytes_per_s, f64::max)
    }
}

fn fastest(x: Vec<f64>) -> f64 {
    x.into_iter().fold(f64::NAN, f64::min)
}

/// The shortest run a ceiling is read from: long enough that the submission and the wait
/// (tens of microseconds on a real GPU) are a percent of it.
const MIN_SECONDS: f64 = 0.01;

/// Measures the ceilings on `ctx`: `repeats` timed runs each, at a size grown by doubling
/// until the fastest run takes `MIN_SECONDS` — a fixed size that suits lavapipe
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
    let largest = (ctx.max_binding_bytes() as usize).min(1 << 30) / 16 * 16;
    // Each form's kernel, made once for every footprint.
    let forms = COPY_FORMS
        .iter()
        .map(|&(element, size)| {
            let label = format!("ceiling_copy_{size}");
            let pipeline = ctx.pipeline(&label, &copy_wgsl(element))?;
            Ok((element, size, label, pipeline))
        })
        .collect::<Result<Vec<_>, GpuError>>()?;
    let mut copy_curve = Vec::new();
    for footprint in copy_footprints().filter(|&f| f / 2 <= largest) {
        let bytes = footprint / 2;
        let src = vec![1u8; bytes];
        let mut by_form = [f64::NAN; 2];
        for (slot, (_, size, label, pipeline)) in forms.iter().enumerate() {
            let size = *size;
            let words = bytes / size;
            // Grid-stride: a GPU's one-dimensional dispatch holds 65,535 workgroups.
            let threads = words.min(65_535 * 64);
            let mut passes: u32 = 1;
            let seconds = loop {
                let params = [words as u32, threads as u32, passes];
                let (r, t) = timed(repeats, || {
                    run_once(
                        ctx,
                        pipeline,
                        label,
                        bytemuck::cast_slice(&params),
                        &[&src],
                        &[Out::Empty(bytes)],
                        threads,
                    )
                });
                r?;
                let seconds = fastest(t.iter().flat_map(|k| k.kernel_seconds().to_vec()).collect());
                if seconds >= MIN_SECONDS || passes >= 1 << 12 {
                    break seconds / passes as f64;
                }
                passes *= 2;
            };
            let gbytes_per_s = footprint as f64 / seconds / 1e9;
            by_form[slot] = gbytes_per_s;
        }
        // The faster form (the first where they tie).
        let best = (0..forms.len()).fold(0, |b, k| if by_form[k] > by_form[b] { k } else { b });
        copy_curve.push(CopyPoint {
            footprint_bytes: footprint,
            gbytes_per_s: by_form[best],
            form: forms[best].0,
            by_form,
        });
    }
    Ok(Ceilings {
        fma_gflops_f32,
        fma_gflops_f64,
        copy_gbytes_per_s: copy_curve.last().map_or(f64::NAN, |p| p.gbytes_per_s),
        copy_curve,
    })
}

#[cfg(test)]
mod tests {
    use super::{Ceilings, CopyPoint};

    #[test]
    fn a_kernels_bandwidth_ceiling_is_the_best_copy_at_its_footprint_or_larger() {
        let point = |mb: usize, g: f64| CopyPoint {
            footprint_bytes: mb << 20,
            gbytes_per_s: g,
            form: "f32",
            by_form: [g, g],
        };
        let c = Ceilings {
            fma_gflops_f32: 1.0,
            fma_gflops_f64: None,
            copy_gbytes_per_s: 4.0,
            copy_curve: vec![point(1, 20.0), point(2, 9.0), point(4, 6.0), point(8, 4.0)],
        };
        let mb = |x: f64| x * (1 << 20) as f64;
        assert_eq!(c.copy_at(mb(1.0)), 20.0);
        // 1.3 MB is nearest 1 MB on a log scale: the cache's bandwidth still applies.
        assert_eq!(c.copy_at(mb(1.3)), 20.0);
        assert_eq!(c.copy_at(mb(1.5)), 9.0);
        assert_eq!(c.copy_at(mb(3.5)), 6.0);
        // Beyond the largest footprint: the largest's.
        assert_eq!(c.copy_at(mb(100.0)), 4.0);
        assert_eq!(c.copy_at(f64::NAN), 20.0);
    }

    #[test]
    fn the_ceiling_kernels_are_valid_wgsl() {
        for f64 in [false, true] {
            crate::gpu::compose::validate(&super::fma_wgsl(f64)).unwrap();
        }
        for (element, _) in super::COPY_FORMS {
            crate::gpu::compose::validate(&super::copy_wgsl(element)).unwrap();
        }
    }
}
