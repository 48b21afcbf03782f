//! `holewall bench kernels`: a roofline per kernel (issue 27). The device's own ceilings
//! ([`crate::gpu::ceilings`]: FMA chains in f32 and f64, a copy) beside each engine kernel's
//! achieved GFLOP/s and GB/s — contact (every term, split friction, dynamic), the beam
//! element (force and tangent), the assembly and the block-tridiagonal solve — at V variants
//! of an n-node string, in f32 and f64. Times are the kernel's dispatches alone (inputs
//! resident, outputs restored outside the clock; [`crate::gpu::dispatch::timed`]), medians of
//! the repeats. FLOPs are counted by running each kernel's CPU twin — the same formulas — on a
//! counting float ([`crate::physics::count`]); bytes are what the kernel's bindings hold (a
//! lower bound on its traffic: the compulsory reads and writes).

use std::path::Path;

use serde::Serialize;

use crate::error::Error;
use crate::gpu::block_lu::LuForm;
use crate::gpu::contact::GpuReal;
use crate::gpu::dispatch::KernelTiming;
use crate::gpu::GpuContext;
use crate::kernels::assemble::AssemblyInputs;
use crate::kernels::block_lu::ChainBatch;
use crate::physics::count::{count, Counted};

/// One kernel at one size and precision.
#[derive(Clone, Debug, Serialize)]
pub struct KernelRow {
    /// Kernel.
    pub kernel: String,
    /// `f32` or `f64`.
    pub precision: String,
    /// Variants.
    pub variants: usize,
    /// Nodes per variant.
    pub nodes: usize,
    /// Median seconds per run (all its passes): between the device's timestamps at the start
    /// and end of the compute pass where the adapter has them (`timed_by`), else from the
    /// submission to the end of the wait on the host's clock.
    pub seconds: f64,
    /// Median seconds per run on the host's clock (submission to the end of the wait): the
    /// kernel plus the round trip.
    pub host_seconds: f64,
    /// "device" (timestamps) or "host" (clock): what `seconds` is.
    pub timed_by: String,
    /// Floating-point operations per run (counted on the twin).
    pub flops: f64,
    /// Bytes its bindings hold.
    pub bytes: f64,
    /// Achieved GFLOP/s.
    pub gflops: f64,
    /// Achieved GB/s.
    pub gbytes_per_s: f64,
    /// FLOP per byte.
    pub intensity: f64,
    /// Fraction of the FMA ceiling of its precision.
    pub fraction_of_fma: f64,
    /// Fraction of the copy bandwidth.
    pub fraction_of_bandwidth: f64,
    /// The roofline's bound at its intensity, GFLOP/s: min(FMA, bandwidth × intensity).
    pub roof_gflops: f64,
    /// Why it did not run, if it did not.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub note: String,
}

/// `kernels.json`.
#[derive(Clone, Debug, Serialize)]
pub struct KernelsReport {
    /// The adapter.
    pub device: String,
    /// Its ceilings.
    pub ceilings: crate::gpu::ceilings::Ceilings,
    /// Every kernel, size and precision.
    pub rows: Vec<KernelRow>,
}

/// FLOPs of a twin run on counting floats, on one thread (the twins run on rayon; the count
/// is per thread).
fn counted<R: Send>(f: impl FnOnce() -> R + Send) -> f64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    pool.install(|| count(f).1.flops(super::bench::TRANSCENDENTAL_FLOPS) as f64)
}

/// A vertical collar string of `n` nodes: the mesh the kernels run over.
fn string_model(n: usize) -> crate::model::Model {
    crate::model::vertical_collar(9.0 * (n - 1) as f64, n - 1, 1200.0)
}

/// A well-conditioned block-tridiagonal batch (diagonally dominant blocks).
fn chain_batch(n: usize, v: usize) -> ChainBatch<f64> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let m = n - 1;
    let mut r = |len: usize, diag: bool| -> Vec<f64> {
        (0..len)
            .map(|k| {
                // Field-major: entry (k / v) % 36 of a 6 × 6 block; its diagonal is every 7th.
                let on = diag && (k / v % 36).is_multiple_of(7);
                rng.random_range(-0.1..0.1) + if on { 10.0 } else { 0.0 }
            })
            .collect()
    };
    ChainBatch {
        num_variants: v,
        num_nodes: n,
        diag: r(36 * n * v, true),
        upper: r(36 * m * v, false),
        lower: r(36 * m * v, false),
        rhs: r(6 * n * v, false),
    }
}

/// Every node of every variant at the rotation `m`, laid out as the kernels read rotations
/// (`[(9 i + 3 a + k) V + v]`).
fn rotations(m: &crate::physics::rotation::Mat3<f64>, n: usize, v: usize) -> Vec<f64> {
    (0..9 * n * v)
        .map(|k| m[k / v % 9 / 3][k / v % 3])
        .collect()
}

/// The assembly inputs of [`assembly_inputs`] as a relaxation's sub-solve past its ceiling
/// assembles them (the kernel built `SHIFT`, [`crate::kernels::assemble::ShiftInputs`]):
/// every variant's translations and rotations shifted, each node 1 mm and about 0.01 rad
/// (about the string's axis and a lateral one) from its anchor.
fn shifted_assembly_inputs(n: usize, v: usize) -> AssemblyInputs<f64> {
    use crate::kernels::assemble::ShiftInputs;
    use crate::physics::rotation::rotation_exp;
    AssemblyInputs {
        shift: Some(ShiftInputs {
            shift: vec![1e6; v],
            anchor: vec![0.0; 3 * n * v],
            x: vec![1e-3; 3 * n * v],
            rot_shift: vec![1e4; v],
            anchor_rot: rotations(&rotation_exp(&[0.0; 3]), n, v),
            rot: rotations(&rotation_exp(&[0.01, 0.0, 0.01]), n, v),
        }),
        ..assembly_inputs(n, v)
    }
}

/// Assembly inputs of `n` nodes, a contact site at every node, every site in contact.
fn assembly_inputs(n: usize, v: usize) -> AssemblyInputs<f64> {
    use crate::kernels::contact::OUTPUT_LEN;
    let e = n - 1;
    let mut fixed = vec![0u32; n];
    fixed[0] = 0b111111;
    fixed[n - 1] = 0b000011;
    AssemblyInputs {
        num_variants: v,
        num_nodes: n,
        num_sites: n,
        elem_force: vec![1.0; 12 * e * v],
        elem_tangent: vec![1.0; crate::kernels::beam::TANGENT_LEN * e * v],
        contact: vec![1.0; OUTPUT_LEN * n * v],
        contact_flag: vec![1; n * v],
        node_site: (0..n).flat_map(|i| vec![i as u32; v]).collect(),
        f_ext: vec![1.0; 6 * n * v],
        basis: (0..n)
            .flat_map(|_| [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
            .collect(),
        fixed,
        dynamic: None,
        shift: None,
    }
}

/// FLOPs per variant of each kernel on an `n`-node string (counted on the twins).
struct Counts {
    contact_per_pair: f64,
    beam_per_element: f64,
    assemble: f64,
    /// The assembly of a relaxation past its ceiling ([`shifted_assembly_inputs`]).
    assemble_shifted: f64,
    block_lu: f64,
    block_cr: f64,
}

fn counts(n: usize) -> Counts {
    use crate::kernels::contact::ContactOutputs;
    use crate::physics::contact::{ContactMode, ContactTerms, FrictionModel};
    let terms = ContactTerms::all(FrictionModel::Split, ContactMode::Dynamic);
    let pairs = 256;
    let batch =
        crate::selfcheck::random_batch(42, 1, pairs, FrictionModel::Split).cast::<Counted>();
    let contact = counted(|| {
        let mut out = ContactOutputs::new(pairs);
        crate::kernels::contact::contact(&terms, &batch, &mut out);
    }) / pairs as f64;
    let a = assembly_inputs(n, 1).map_static(Counted);
    let assemble = counted(|| crate::kernels::assemble::assemble(&a));
    let a = shifted_assembly_inputs(n, 1).map_static(Counted);
    let assemble_shifted = counted(|| crate::kernels::assemble::assemble(&a));
    let b = chain_batch(n, 1).map(Counted);
    let block_lu = counted(|| crate::kernels::block_lu::block_lu(&b));
    let block_cr = counted(|| crate::kernels::block_cr::block_cr(&b));
    Counts {
        contact_per_pair: contact,
        // The kernel's form: the closed form's values once and their variation along each
        // of 9 directions (physics::beam::tangent, the twin's).
        beam_per_element: super::bench::element_flops().written_out as f64,
        assemble,
        assemble_shifted,
        block_lu,
        block_cr,
    }
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    x.get(x.len() / 2).copied().unwrap_or(f64::NAN)
}

/// A kernel's median seconds per run (kernel, host clock), whether the first is the device's
/// timestamps, and its bytes.
struct Timed {
    seconds: f64,
    host_seconds: f64,
    by_device: bool,
    bytes: f64,
}

/// A kernel's name, its FLOPs per run and its times, or why it did not run.
type Measured = (String, f64, Result<Timed, String>);

/// The kernels at one size and precision.
fn run_size<T: GpuReal>(
    ctx: &'static GpuContext,
    n: usize,
    v: usize,
    repeats: usize,
    c: &Counts,
) -> Vec<Measured> {
    use crate::physics::contact::{ContactMode, ContactTerms, FrictionModel};
    let of = |t: Vec<KernelTiming>| -> Result<Timed, String> {
        let total = |f: &dyn Fn(&KernelTiming) -> &[f64]| {
            median(
                (0..repeats)
                    .map(|r| t.iter().map(|k| f(k).get(r).copied().unwrap_or(0.0)).sum())
                    .collect(),
            )
        };
        let bytes: u64 = t.iter().map(|k| k.bytes_in + k.bytes_out).sum();
        if t.is_empty() {
            Err("no dispatch".into())
        } else {
            Ok(Timed {
                seconds: total(&|k| k.kernel_seconds()),
                host_seconds: total(&|k| &k.seconds),
                by_device: t.iter().all(|k| !k.device_seconds.is_empty()),
                bytes: bytes as f64,
            })
        }
    };
    let to_t = |x: f64| T::from_f64_lossy(x);
    let mut rows = Vec::new();
    // Contact: resident, timed here (its run is not a one-shot dispatch).
    let terms = ContactTerms::all(FrictionModel::Split, ContactMode::Dynamic);
    let batch = crate::selfcheck::random_batch(42, v, n, FrictionModel::Split);
    let cast = batch.cast::<T>();
    let contact = crate::gpu::contact::GpuContactRun::<T>::new(ctx, &terms, &cast)
        .map_err(|e| e.to_string())
        .and_then(|run| {
            run.dispatch().map_err(|e| e.to_string())?;
            let mut s = Vec::new();
            for _ in 0..repeats {
                let clock = std::time::Instant::now();
                run.dispatch().map_err(|e| e.to_string())?;
                s.push(clock.elapsed().as_secs_f64());
            }
            let size = std::mem::size_of::<T>();
            let input =
                (cast.site_normals.len() + cast.pair_params.len() + cast.pair_state.len()) * size;
            let seconds = median(s);
            Ok(Timed {
                seconds,
                host_seconds: seconds,
                by_device: false,
                bytes: (input as u64 + run.output_bytes()) as f64,
            })
        });
    rows.push((
        "contact".into(),
        c.contact_per_pair * (n * v) as f64,
        contact,
    ));
    // The beam element, force and tangent.
    let model = string_model(n);
    let u = vec![T::zero(); 3 * n * v];
    let identity = crate::physics::rotation::rotation_exp(&[0.0; 3]);
    let rot: Vec<T> = rotations(&identity, n, v).into_iter().map(to_t).collect();
    let chords = crate::kernels::beam::base_chords(&model, &vec![0.0; 3 * n * v], v);
    let (r, t) = crate::gpu::dispatch::timed(repeats, || {
        crate::gpu::beam::beam_gpu::<T>(ctx, &model, v, &u, &rot, &chords, &[], true)
    });
    rows.push((
        "beam (force + tangent)".into(),
        c.beam_per_element * ((n - 1) * v) as f64,
        r.map_err(|e| e.to_string()).and_then(|_| of(t)),
    ));
    // The assembly, plain and as a relaxation past its ceiling assembles.
    for (a, name, flops) in [
        (assembly_inputs(n, v), "assemble", c.assemble),
        (
            shifted_assembly_inputs(n, v),
            "assemble (relaxation, rotations shifted)",
            c.assemble_shifted,
        ),
    ] {
        let a = a.map_static(to_t);
        let (r, t) = crate::gpu::dispatch::timed(repeats, || {
            crate::gpu::assemble::assemble_gpu::<T>(ctx, &a)
        });
        rows.push((
            name.into(),
            flops * v as f64,
            r.map_err(|e| e.to_string()).and_then(|_| of(t)),
        ));
    }
    // The block-tridiagonal solve, in every form (the engine runs the adapter's:
    // `LuForm::for_batch`); the names say which. The cyclic form's FLOPs are its twin's.
    let b = chain_batch(n, v).map(to_t);
    for (form, name, flops) in [
        (LuForm::Serial, "block solve (serial)", c.block_lu),
        (LuForm::Lanes, "block solve (lanes)", c.block_lu),
        (LuForm::Cyclic, "block solve (cyclic)", c.block_cr),
    ] {
        let (r, t) = crate::gpu::dispatch::timed(repeats, || {
            crate::gpu::block_lu::block_lu_gpu_form::<T>(ctx, &b, usize::MAX, form)
        });
        rows.push((
            name.into(),
            flops * v as f64,
            r.map_err(|e| e.to_string()).and_then(|_| of(t)),
        ));
    }
    rows
}

/// Runs the benchmark: ceilings, then every kernel at each of `variants`, f32 and (where the
/// adapter has it) f64, on an `nodes`-node string; writes `kernels.json`, `kernels.md` and
/// `roofline.png` into `out` and prints the table.
pub fn run(
    variants: &[usize],
    nodes: usize,
    repeats: usize,
    out: &Path,
    show_progress: bool,
) -> Result<KernelsReport, Error> {
    if !(3..=2000).contains(&nodes) {
        return Err(Error::Input(crate::error::InputError {
            source_name: "--nodes".into(),
            line: 0,
            key: "nodes".into(),
            message: format!("{nodes}; allowed: 3 … 2000"),
        }));
    }
    let ctx = GpuContext::shared().map_err(Error::Gpu)?;
    std::fs::create_dir_all(out)?;
    let precisions: Vec<bool> = if ctx.has_f64 {
        vec![false, true]
    } else {
        vec![false]
    };
    let bar = crate::output::progress_bar(
        show_progress,
        (1 + precisions.len() * variants.len()) as u64,
        "{bar:40} {pos}/{len} (ceilings, then precision × V), {elapsed} elapsed",
    );
    let ceilings = crate::gpu::ceilings::measure(ctx, repeats).map_err(Error::Gpu)?;
    bar.inc(1);
    let c = counts(nodes);
    let mut rows = Vec::new();
    for &f64 in &precisions {
        for &v in variants {
            let got = if f64 {
                run_size::<f64>(ctx, nodes, v, repeats, &c)
            } else {
                run_size::<f32>(ctx, nodes, v, repeats, &c)
            };
            let fma = if f64 {
                ceilings.fma_gflops_f64.unwrap_or(f64::NAN)
            } else {
                ceilings.fma_gflops_f32
            };
            for (kernel, flops, r) in got {
                let (t, note) = match r {
                    Ok(t) => (t, String::new()),
                    Err(e) => (
                        Timed {
                            seconds: f64::NAN,
                            host_seconds: f64::NAN,
                            by_device: false,
                            bytes: f64::NAN,
                        },
                        e,
                    ),
                };
                let (seconds, bytes) = (t.seconds, t.bytes);
                let gflops = flops / seconds / 1e9;
                let intensity = flops / bytes;
                rows.push(KernelRow {
                    kernel,
                    precision: if f64 { "f64" } else { "f32" }.into(),
                    variants: v,
                    nodes,
                    seconds,
                    host_seconds: t.host_seconds,
                    timed_by: if t.by_device { "device" } else { "host" }.into(),
                    flops,
                    bytes,
                    gflops,
                    gbytes_per_s: bytes / seconds / 1e9,
                    intensity,
                    fraction_of_fma: gflops / fma,
                    fraction_of_bandwidth: bytes / seconds / 1e9 / ceilings.copy_at(bytes),
                    roof_gflops: fma.min(ceilings.copy_at(bytes) * intensity),
                    note,
                });
            }
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let report = KernelsReport {
        device: ctx.describe(),
        ceilings,
        rows,
    };
    let md = markdown(&report);
    crate::output::write_atomic(&out.join("kernels.md"), md.as_bytes())?;
    crate::output::write_json_atomic(&out.join("kernels.json"), &report)?;
    roofline(&out.join("roofline.png"), &report)?;
    println!("{md}");
    Ok(report)
}

/// `roofline.png`: the ceilings of each precision and every kernel's points (a set per
/// kernel and precision, its V values together; a colour per kernel, circles f32 and
/// triangles f64).
fn roofline(path: &Path, r: &KernelsReport) -> std::io::Result<()> {
    let c = &r.ceilings;
    let intensities: Vec<f64> = (0..=60)
        .map(|k| 10f64.powf(-3.0 + k as f64 * 0.1))
        .collect();
    let roof = |peak: f64| -> Vec<(f64, f64)> {
        intensities
            .iter()
            .map(|&i| (i, peak.min(c.copy_gbytes_per_s * i)))
            .collect()
    };
    let mut roofs = vec![(
        format!(
            "f32 roof: FMA {:.1} GFLOP/s, copy {:.1} GB/s (its largest footprint)",
            c.fma_gflops_f32, c.copy_gbytes_per_s
        ),
        roof(c.fma_gflops_f32),
    )];
    if let Some(p) = c.fma_gflops_f64 {
        roofs.push((format!("f64 roof: FMA {p:.1} GFLOP/s"), roof(p)));
    }
    let mut kernels: Vec<&str> = Vec::new();
    let mut sets: Vec<crate::plots::RooflineSet> = Vec::new();
    for k in &r.rows {
        let colour = kernels
            .iter()
            .position(|n| *n == k.kernel)
            .unwrap_or_else(|| {
                kernels.push(&k.kernel);
                kernels.len() - 1
            });
        let name = format!("{} {}", k.kernel, k.precision);
        let point = (k.intensity, k.gflops);
        match sets.iter_mut().find(|(n, _, _)| *n == name) {
            Some((_, _, p)) => p.push(point),
            None => sets.push((
                name,
                (colour, usize::from(k.precision == "f64")),
                vec![point],
            )),
        }
    }
    let vs = r
        .rows
        .iter()
        .map(|k| k.variants)
        .fold(Vec::<usize>::new(), |mut a, v| {
            if !a.contains(&v) {
                a.push(v);
            }
            a
        });
    crate::plots::roofline_plot(
        path,
        &format!(
            "Roofline on {}: kernels at V = {:?} ({} nodes)",
            r.device,
            vs,
            r.rows.first().map_or(0, |k| k.nodes)
        ),
        &roofs,
        &sets,
    )
}

/// An NVIDIA H100 SXM5's datasheet peaks (non-tensor): FP32 and FP64 GFLOP/s, HBM3 GB/s.
/// Used only for the labelled estimate in `kernels.md`.
const H100: (f64, f64, f64) = (66_900.0, 33_500.0, 3_350.0);

/// The roofline bound of a row on an H100 (s): max(FLOPs / peak, bytes / bandwidth) — the
/// fastest the kernel could run there by its counts; an estimate, not a measurement.
pub fn h100_estimate_seconds(k: &KernelRow) -> f64 {
    let peak = if k.precision == "f64" { H100.1 } else { H100.0 };
    (k.flops / (peak * 1e9)).max(k.bytes / (H100.2 * 1e9))
}

/// The table as markdown.
pub fn markdown(r: &KernelsReport) -> String {
    let c = &r.ceilings;
    let curve = c
        .copy_curve
        .iter()
        .map(|p| {
            format!(
                "{} MB {:.1} (vec4 {:.1}, f32 {:.1})",
                p.footprint_bytes >> 20,
                p.gbytes_per_s,
                p.by_form[0],
                p.by_form[1]
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    let mut s = format!(
        "Device: {}\n\nCeilings measured here: FMA f32 {:.1} GFLOP/s, FMA f64 {}; copy (GB/s, read + \
         write, at each footprint of bytes read plus written; the faster of a `vec4<f32>` and an \
         `f32` an invocation, each given): {curve}. \"of copy\" sets a kernel's bandwidth against the best \
         copy at a footprint from the one nearest its bytes up (\"copy there\"), so a kernel whose data \
         fits a cache is held to the cache's bandwidth. \"median\": the kernel's time, by the device's timestamps \
         at the compute pass's start and end where \"timed by\" says device, else by the host's \
         clock; \"host\": from submission to the end of the wait (kernel and round trip).\n\n\
         | kernel | precision | V | nodes | median (ms) | timed by | host (ms) | GFLOP/s | of FMA | GB/s | copy there (GB/s) | of copy | FLOP/B | roof (GFLOP/s) | note |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        r.device,
        c.fma_gflops_f32,
        c.fma_gflops_f64
            .map_or("—".to_string(), |x| format!("{x:.1} GFLOP/s")),
    );
    for k in &r.rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {:.3} | {} | {:.3} | {:.2} | {:.0} % | {:.2} | {:.1} | {:.0} % | {:.2} | {:.1} | {} |\n",
            k.kernel,
            k.precision,
            k.variants,
            k.nodes,
            k.seconds * 1e3,
            k.timed_by,
            k.host_seconds * 1e3,
            k.gflops,
            100.0 * k.fraction_of_fma,
            k.gbytes_per_s,
            c.copy_at(k.bytes),
            100.0 * k.fraction_of_bandwidth,
            k.intensity,
            k.roof_gflops,
            k.note
        ));
    }
    s.push_str(&format!(
        "\n**Estimate, not a measurement**: the same FLOP and byte counts on an NVIDIA H100 SXM5 \
         (datasheet, non-tensor: FP32 {:.1} TFLOP/s, FP64 {:.1} TFLOP/s, HBM3 {:.2} TB/s), each \
         kernel's roofline bound max(FLOPs / peak, bytes / bandwidth) — the fastest it could \
         run there, before occupancy, latency and launch overhead (≈ 5 µs a dispatch):\n\n\
         | kernel | precision | V | bound on H100 (µs) | bound by | speed-up over this device at the bound |\n\
         |---|---|---|---|---|---|\n",
        H100.0 / 1e3,
        H100.1 / 1e3,
        H100.2 / 1e3
    ));
    for k in r.rows.iter().filter(|k| k.seconds.is_finite()) {
        let t = h100_estimate_seconds(k);
        let peak = if k.precision == "f64" { H100.1 } else { H100.0 };
        let by = if k.flops / (peak * 1e9) >= k.bytes / (H100.2 * 1e9) {
            "FLOPs"
        } else {
            "bytes"
        };
        s.push_str(&format!(
            "| {} | {} | {} | {:.2} | {by} | {:.0}× |\n",
            k.kernel,
            k.precision,
            k.variants,
            t * 1e6,
            k.seconds / t
        ));
    }
    s
}
