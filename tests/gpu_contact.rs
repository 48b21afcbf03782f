//! The contact kernel (`shaders/contact.wgsl`) against its CPU twin (`src/kernels/contact.rs`).
//!
//! Error measures (docs/contact-element.md, "Accuracy"): per pair and output quantity,
//! the normwise relative error, and the error relative to the quantity's natural scale
//! (`term_scales`), bounded by `C·u·κ` with `κ` the first-order condition number.

mod common;

use holewall::gpu::contact::{contact_gpu, contact_wgsl};
use holewall::kernels::contact::{contact, ContactBatch, ContactOutputs};
use holewall::physics::contact::{ContactMode, ContactTerms, FrictionModel, SpringLaw};
use holewall::selfcheck::{
    compare_outputs, quantity_errors, random_batch, ErrorStats, F32_BOUND, F64_BOUND,
};

const CONFIGS: [(FrictionModel, ContactMode); 4] = [
    (FrictionModel::Split, ContactMode::Dynamic),
    (FrictionModel::Split, ContactMode::Static),
    (FrictionModel::Coupled, ContactMode::Dynamic),
    (FrictionModel::Coupled, ContactMode::Static),
];

/// 50 variants × 200 sites = 10,000 (variant, site) pairs per configuration.
fn batch(friction: FrictionModel, seed: u64) -> ContactBatch<f64> {
    random_batch(seed, 50, 200, friction)
}

/// Compares and asserts the bound on every checked pair.
fn compare(
    batch: &ContactBatch<f64>,
    terms: &ContactTerms,
    reference: &ContactOutputs<f64>,
    other: &dyn Fn(usize) -> ([f64; 48], u32),
    u: f64,
    bound: f64,
    what: &str,
) -> ErrorStats {
    let st = compare_outputs(batch, terms, reference, other, u, bound);
    assert_eq!(
        st.flag_mismatches, 0,
        "{what}: contact flags differ on well-conditioned pairs"
    );
    assert_eq!(
        st.over_bound, 0,
        "{what}: {} pairs beyond {bound}·u·κ (max ratio {:.2})",
        st.over_bound, st.max_ratio
    );
    st
}

#[test]
fn f64_kernel_matches_its_twin() {
    let Some(ctx) = common::gpu() else { return };
    assert!(
        ctx.has_f64,
        "the adapter {} lacks SHADER_F64",
        ctx.info.name
    );
    for (k, (friction, mode)) in CONFIGS.into_iter().enumerate() {
        let terms = ContactTerms::all(friction, mode);
        let batch = batch(friction, 100 + k as u64);
        let mut reference = ContactOutputs::new(batch.num_pairs());
        contact(&terms, &batch, &mut reference);
        let gpu = contact_gpu(ctx, &terms, &batch).unwrap();
        // Every pair: flags equal, and where the reference has no force the GPU has none.
        for i in 0..batch.num_pairs() {
            assert_eq!(
                gpu.contact[i], reference.contact[i],
                "contact flag at pair {i}"
            );
            if reference.fields(i).iter().all(|x| *x == 0.0) && reference.contact[i] == 0 {
                assert!(gpu.fields(i).iter().all(|x| *x == 0.0));
            }
        }
        let rep = compare(
            &batch,
            &terms,
            &reference,
            &|i| (gpu.fields(i), gpu.contact[i]),
            f64::EPSILON / 2.0,
            F64_BOUND,
            "GPU f64",
        );
        // The figure: 1e-12 relative, normwise per quantity, wherever the state
        // itself is not ill-conditioned beyond κ = 1e3.
        assert!(
            rep.max_normwise_well <= 1e-12,
            "f64 normwise error {:.3e} > 1e-12 at κ ≤ 1e3",
            rep.max_normwise_well
        );
        assert!(
            rep.checked * 10 >= rep.pairs * 6,
            "too few pairs in contact: {}",
            rep.checked
        );
        eprintln!(
            "GPU f64 {friction:?}/{mode:?}: {} pairs, {} in contact; max normwise rel. error {:.2e} (κ ≤ 1e3: {:.2e}); max error/(u·κ) {:.2}",
            rep.pairs, rep.checked, rep.max_normwise, rep.max_normwise_well, rep.max_ratio
        );
    }
}

#[test]
fn f32_kernel_within_its_condition_bound() {
    let Some(ctx) = common::gpu() else { return };
    let u32_ = f32::EPSILON as f64 / 2.0;
    for (k, (friction, mode)) in CONFIGS.into_iter().enumerate() {
        let terms = ContactTerms::all(friction, mode);
        let batch = batch(friction, 200 + k as u64);
        let mut reference = ContactOutputs::new(batch.num_pairs());
        contact(&terms, &batch, &mut reference);
        let b32 = batch.cast::<f32>();
        let gpu = contact_gpu(ctx, &terms, &b32).unwrap();
        let to64 =
            |o: &ContactOutputs<f32>, i: usize| (o.fields(i).map(|x| x as f64), o.contact[i]);
        // GPU f32 against the f64 oracle: first-order bound C·u·κ with C = 32.
        let rep = compare(
            &batch,
            &terms,
            &reference,
            &|i| to64(&gpu, i),
            u32_,
            F32_BOUND,
            "GPU f32 vs f64",
        );
        // And against its own twin run in f32 (same bound: both are f32 roundings).
        let mut twin32 = ContactOutputs::new(batch.num_pairs());
        contact(&terms, &b32, &mut twin32);
        let twin_rep = compare(
            &batch,
            &terms,
            &reference,
            &|i| to64(&twin32, i),
            u32_,
            F32_BOUND,
            "CPU f32 vs f64",
        );
        // The sampler spans deliberately ill-conditioned states (1e-9 m past contact with up to
        // 0.1 m axial offset: κ ≈ 1e8), where f32 resolves nothing; 15 % must remain.
        assert!(
            rep.checked * 100 >= rep.pairs * 15,
            "too few well-conditioned pairs: {}",
            rep.checked
        );
        let pct = |q: f64| rep.scaled_quantile(q);
        eprintln!(
            "GPU f32 {friction:?}/{mode:?}: {} pairs, {} with u·κ ≤ 1e-3: max error/(u·κ) {:.2} (CPU f32 twin: {:.2}); error / natural scale: median {:.1e}, 99th pct {:.1e}, max {:.1e}",
            rep.pairs, rep.checked, rep.max_ratio, twin_rep.max_ratio, pct(0.5), pct(0.99), pct(1.0)
        );
    }
}

#[test]
fn frictionless_undamped_linear_scene_compiles_lean_kernel_with_same_numbers() {
    // Scene: μ = 0, c = 0, m = 1 everywhere.
    let mut batch = random_batch(7, 40, 50, FrictionModel::Split);
    for i in 0..batch.num_pairs() {
        let mut p = batch.params(i);
        p.mu_t = 0.0;
        p.mu_l = 0.0;
        p.wall_damping = 0.0;
        p.spring_exponent = 1.0;
        batch.set_params(i, &p);
    }
    for mode in [ContactMode::Dynamic, ContactMode::Static] {
        let lean = batch.required_terms(FrictionModel::Coupled, mode);
        assert_eq!(
            lean,
            ContactTerms {
                spring: SpringLaw::Linear,
                damping: false,
                friction: None,
                mode
            }
        );
        for f64 in [false, true] {
            // Code only: comments name every parameter.
            let code = |w: String| {
                w.lines()
                    .map(|l| l.split("//").next().unwrap_or(""))
                    .collect::<Vec<_>>()
                    .join("\n")
            };
            let wgsl = code(contact_wgsl(&lean, f64).unwrap());
            for absent in [
                "regularised_sign",
                "friction_factors",
                "mu_t",
                "mu_l",
                "c_wall",
                "pow",
                "exp_f64",
                "ln_f64",
                "soft_blend",
                "param(8u",
            ] {
                assert!(!wgsl.contains(absent), "lean kernel contains {absent:?}");
            }
            let full =
                code(contact_wgsl(&ContactTerms::all(FrictionModel::Coupled, mode), f64).unwrap());
            for present in ["regularised_sign", "mu_t", "pow_pos"] {
                assert!(full.contains(present), "all-terms kernel lacks {present:?}");
            }
            // Wall damping acts only in dynamic analysis.
            assert_eq!(full.contains("c_wall"), mode == ContactMode::Dynamic);
            assert!(wgsl.len() < full.len());
            eprintln!(
                "contact kernel, {mode:?}, f64 = {f64}: lean {} bytes of code, all terms {} bytes",
                wgsl.len(),
                full.len()
            );
        }
        // Same numbers: CPU twin lean vs all terms, and on the GPU.
        let all = ContactTerms::all(FrictionModel::Coupled, mode);
        let mut a = ContactOutputs::new(batch.num_pairs());
        let mut b = ContactOutputs::new(batch.num_pairs());
        contact(&lean, &batch, &mut a);
        contact(&all, &batch, &mut b);
        assert_eq!(a, b);
        if let Some(ctx) = common::gpu() {
            let ga = contact_gpu(ctx, &lean, &batch).unwrap();
            let gb = contact_gpu(ctx, &all, &batch).unwrap();
            assert_eq!(ga.contact, gb.contact);
            for i in 0..batch.num_pairs() {
                let e = quantity_errors(&ga.fields(i), &gb.fields(i));
                assert!(
                    e.iter().all(|x| *x <= 1e-15),
                    "lean vs all-terms GPU kernel at pair {i}: {e:?}"
                );
            }
            let b32 = batch.cast::<f32>();
            let ga = contact_gpu(ctx, &lean, &b32).unwrap();
            let gb = contact_gpu(ctx, &all, &b32).unwrap();
            for i in 0..batch.num_pairs() {
                let e = quantity_errors(
                    &ga.fields(i).map(|x| x as f64),
                    &gb.fields(i).map(|x| x as f64),
                );
                assert!(
                    e.iter().all(|x| *x <= 1e-6),
                    "lean vs all-terms GPU f32 kernel at pair {i}: {e:?}"
                );
            }
        }
    }
}

#[test]
fn f64_pow_ln_exp_match_the_cpu_over_the_whole_range() {
    use wgpu::util::DeviceExt;
    let Some(ctx) = common::gpu() else { return };
    let math = holewall::gpu::compose::source("shared/math_f64.wgsl").unwrap();
    let wgsl = format!(
        "{math}\n@group(0) @binding(0) var<storage, read> xs: array<f64>;\n@group(0) @binding(1) var<storage, read_write> out: array<f64>;\n@compute @workgroup_size(64)\nfn main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n  let i = gid.x;\n  if (i >= arrayLength(&xs) / 2u) {{ return; }}\n  let x = xs[2u * i];\n  let m = xs[2u * i + 1u];\n  out[3u * i] = pow_pos(x, m);\n  out[3u * i + 1u] = ln_f64(x);\n  out[3u * i + 2u] = exp_f64(m * 10.0lf);\n}}\n"
    );
    let pipeline = ctx.pipeline("math_f64_test", &wgsl).unwrap();
    let count = 4096;
    let mut inputs = Vec::with_capacity(2 * count);
    for k in 0..count {
        // x log-uniform over 1e-300 … 1e300, m over 0.3 … 3 (the spring exponents of use),
        // m·10 over 3 … 30 for exp, and exact powers of two.
        let x = if k % 64 == 0 {
            2f64.powi((k as i32 / 64) - 32)
        } else {
            10f64.powf(-300.0 + 600.0 * (k as f64 * 0.618_033_988_75).fract())
        };
        let m = 0.3 + 2.7 * (k as f64 * 0.414_213_562_37).fract();
        inputs.push(x);
        inputs.push(m);
    }
    let xs = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(&inputs),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let size = (3 * count * 8) as u64;
    let out = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bg = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: xs.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups((count as u32).div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&out, 0, &staging, 0, size);
    ctx.queue.submit([enc.finish()]);
    staging.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
    let view = staging.slice(..).get_mapped_range().unwrap();
    let got: &[f64] = bytemuck::cast_slice(&view);
    let (mut worst_pow, mut worst_ln, mut worst_exp) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..count {
        let (x, m) = (inputs[2 * k], inputs[2 * k + 1]);
        let want = x.powf(m);
        if want.is_normal() {
            // Relative error of exp(m·ln x) grows with |m·ln x| (the absolute error of the
            // exponent becomes a relative error of the result).
            let e = ((got[3 * k] - want) / want).abs() / (1.0 + (m * x.ln()).abs());
            worst_pow = worst_pow.max(e);
        }
        let ln_want = x.ln();
        worst_ln = worst_ln.max((got[3 * k + 1] - ln_want).abs() / ln_want.abs().max(1.0));
        let exp_want = (m * 10.0).exp();
        worst_exp = worst_exp.max(((got[3 * k + 2] - exp_want) / exp_want).abs());
    }
    eprintln!("f64 WGSL math: pow rel/(1+|m ln x|) {worst_pow:.2e}, ln {worst_ln:.2e}, exp {worst_exp:.2e}");
    assert!(worst_pow <= 4.0 * f64::EPSILON, "pow {worst_pow:e}");
    assert!(worst_ln <= 4.0 * f64::EPSILON, "ln {worst_ln:e}");
    assert!(worst_exp <= 8.0 * f64::EPSILON, "exp {worst_exp:e}");
}

#[test]
fn batches_larger_than_one_binding_are_chunked_and_exact() {
    let Some(ctx) = common::gpu() else { return };
    // Force several chunks by a batch above the per-binding capacity? That needs > 128 MiB
    // here; instead check the chunk arithmetic on a batch whose pairs do not divide evenly
    // by the variants (a chunk boundary inside a site) with the real kernel.
    let terms = ContactTerms::all(FrictionModel::Split, ContactMode::Dynamic);
    let batch = random_batch(11, 7, 13, FrictionModel::Split);
    let run =
        holewall::gpu::contact::GpuContactRun::with_part_limit(ctx, &terms, &batch, 10).unwrap();
    assert_eq!(run.num_parts(), 10);
    run.dispatch().unwrap();
    let chunked = run.read().unwrap();
    let whole = contact_gpu(ctx, &terms, &batch).unwrap();
    assert_eq!(chunked, whole);
}

/// A static scene's kernel writes `g` and `K` only and its output buffers hold just those
/// 24 of the 48 fields (no memory for the damping matrices it never uses), chunked or not;
/// read back, the missing fields are zero and everything equals the CPU twin's.
#[test]
fn static_scenes_allocate_no_damping_outputs() {
    let Some(ctx) = common::gpu() else { return };
    let batch = random_batch(5, 9, 13, FrictionModel::Split);
    let p = batch.num_pairs();
    for (mode, fields) in [(ContactMode::Static, 24), (ContactMode::Dynamic, 48)] {
        let terms = ContactTerms::all(FrictionModel::Split, mode);
        assert_eq!(holewall::kernels::contact::output_fields(&terms), fields);
        for limit in [usize::MAX, 10] {
            let run =
                holewall::gpu::contact::GpuContactRun::with_part_limit(ctx, &terms, &batch, limit)
                    .unwrap();
            assert_eq!(run.output_bytes(), (fields * p * 8) as u64, "{mode:?}");
            run.dispatch().unwrap();
            let gpu = run.read().unwrap();
            let mut twin = ContactOutputs::new(p);
            contact(&terms, &batch, &mut twin);
            assert_eq!(gpu.contact, twin.contact);
            for i in 0..p {
                let (g, t) = (gpu.fields(i), twin.fields(i));
                if mode == ContactMode::Static {
                    assert!(t[24..].iter().all(|x| *x == 0.0), "twin's static C is zero");
                    assert!(g[24..].iter().all(|x| *x == 0.0));
                }
                if !common::fuses(ctx) {
                    let e = quantity_errors(&g, &t);
                    assert!(e.iter().all(|x| *x <= 1e-12), "{mode:?} pair {i}: {e:?}");
                }
            }
            if common::fuses(ctx) {
                // Contracted multiply-adds: the kernel's bound against the twin, by κ.
                compare(
                    &batch,
                    &terms,
                    &twin,
                    &|i| (gpu.fields(i), gpu.contact[i]),
                    f64::EPSILON / 2.0,
                    F64_BOUND,
                    "static scene",
                );
            }
        }
    }
}

/// The line-search trials' contact kernel (built `FORCE_ONLY`) gives the full kernel's
/// force and moment `g` and contact flags to the bit, on every law and friction model, in
/// static scenes and in dynamic ones (the wall's damping and the friction of the sites'
/// velocities), f64 and f32, and writes no stiffness or damping fields.
#[test]
fn force_only_kernel_gives_the_full_kernels_forces() {
    use holewall::gpu::contact::GpuContactRun;
    let Some(ctx) = common::gpu() else { return };
    let mut checked = 0;
    for (friction, mode) in [
        (FrictionModel::Split, ContactMode::Static),
        (FrictionModel::Coupled, ContactMode::Static),
        (FrictionModel::Split, ContactMode::Dynamic),
        (FrictionModel::Coupled, ContactMode::Dynamic),
    ] {
        let b64 = random_batch(11, 40, 60, friction);
        let b32 = b64.cast::<f32>();
        for spring in [SpringLaw::Linear, SpringLaw::PowerBlend] {
            for frictionless in [false, true] {
                let mut terms = ContactTerms::all(friction, mode);
                terms.spring = spring;
                terms.damping = mode == ContactMode::Dynamic;
                if frictionless {
                    terms.friction = None;
                }
                let fuses = common::fuses(ctx);
                let mut twin64 = ContactOutputs::new(b64.num_pairs());
                contact(&terms, &b64, &mut twin64);
                if ctx.has_f64 {
                    let full = contact_gpu(ctx, &terms, &b64).unwrap();
                    let run = GpuContactRun::force_only(ctx, &terms, &b64).unwrap();
                    run.dispatch().unwrap();
                    let lean = run.read().unwrap();
                    assert_eq!(lean.contact, full.contact);
                    for i in 0..b64.num_pairs() {
                        let (a, b) = (lean.fields(i), full.fields(i));
                        if !fuses {
                            assert_eq!(a[..6], b[..6], "f64 {terms:?} pair {i}");
                        }
                        assert!(a[6..].iter().all(|x| *x == 0.0), "no K written");
                    }
                    if fuses {
                        // The full kernel on these terms first (the diagnosis, if the lean
                        // one is off: is the full kernel off too?).
                        let st = compare_outputs(
                            &b64,
                            &terms,
                            &twin64,
                            &|i| (full.fields(i), full.contact[i]),
                            f64::EPSILON / 2.0,
                            F64_BOUND,
                        );
                        eprintln!(
                            "{terms:?}: full kernel f64 against the twin: max ratio {:.3e}, {} over",
                            st.max_ratio, st.over_bound
                        );
                        // Two builds of one formula, each contracted its own way: the lean
                        // `g` (with the full kernel's K) within the kernel's bound of the twin.
                        compare(
                            &b64,
                            &terms,
                            &twin64,
                            &|i| {
                                let mut f = full.fields(i);
                                f[..6].copy_from_slice(&lean.fields(i)[..6]);
                                (f, lean.contact[i])
                            },
                            f64::EPSILON / 2.0,
                            F64_BOUND,
                            "f64 force-only",
                        );
                    }
                }
                let full = contact_gpu(ctx, &terms, &b32).unwrap();
                let run = GpuContactRun::force_only(ctx, &terms, &b32).unwrap();
                run.dispatch().unwrap();
                let lean = run.read().unwrap();
                assert_eq!(lean.contact, full.contact);
                let touching = lean.contact.iter().filter(|c| **c != 0).count();
                assert!(touching > b32.num_pairs() / 10, "{touching} in contact");
                if fuses {
                    compare(
                        &b64,
                        &terms,
                        &twin64,
                        &|i| {
                            let mut f = full.fields(i).map(f64::from);
                            for (k, x) in lean.fields(i)[..6].iter().enumerate() {
                                f[k] = f64::from(*x);
                            }
                            (f, lean.contact[i])
                        },
                        f64::from(f32::EPSILON) / 2.0,
                        F32_BOUND,
                        "f32 force-only",
                    );
                } else {
                    for i in 0..b32.num_pairs() {
                        assert_eq!(
                            lean.fields(i)[..6],
                            full.fields(i)[..6],
                            "f32 {terms:?} pair {i}"
                        );
                    }
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 16);
}

/// The whirl's average (`side_friction` 0: a turning string's circumferential friction as
/// torque alone, static mode) in the kernel: every other pair of a random static batch
/// takes it; the GPU in f64 matches the twin to its bound, and on the twin those pairs'
/// force rows are the element's with `mu_t = 0`, their moment rows the whole element's.
/// Dynamic mode ignores it.
#[test]
fn the_whirls_average_in_the_kernel_matches_its_twin() {
    let ctx = common::gpu();
    for (k, friction) in [FrictionModel::Split, FrictionModel::Coupled]
        .into_iter()
        .enumerate()
    {
        let mut batch = batch(friction, 300 + k as u64);
        let full = batch.clone();
        let mut bare = batch.clone();
        for i in 0..batch.num_pairs() {
            let mut p = batch.params(i);
            if i % 2 == 0 {
                p.side_friction = 0.0;
            }
            batch.set_params(i, &p);
            let mut q = full.params(i);
            q.mu_t = 0.0;
            bare.set_params(i, &q);
        }
        let terms = ContactTerms::all(friction, ContactMode::Static);
        let eval = |b: &ContactBatch<f64>, terms: &ContactTerms| {
            let mut out = ContactOutputs::new(b.num_pairs());
            contact(terms, b, &mut out);
            out
        };
        let (avg, with, without) = (
            eval(&batch, &terms),
            eval(&full, &terms),
            eval(&bare, &terms),
        );
        let mut averaged = 0;
        for i in 0..batch.num_pairs() {
            let (a, w, b) = (avg.fields(i), with.fields(i), without.fields(i));
            if i % 2 == 1 {
                assert_eq!(a, w, "pair {i}: side_friction 1 is the paper's element");
                continue;
            }
            // g rows 0–2 and K rows 0–2 (fields 6–14) from the bare element; the moments
            // (g rows 3–5, K rows 3–5: fields 3–5, 15–23) from the whole one.
            for f in (0..3).chain(6..15) {
                assert_eq!(a[f], b[f], "pair {i} field {f}");
            }
            for f in (3..6).chain(15..24) {
                assert_eq!(a[f], w[f], "pair {i} field {f}");
            }
            averaged += usize::from(avg.contact[i] == 1 && a[..3] != w[..3]);
        }
        assert!(averaged * 4 >= batch.num_pairs() / 2, "{averaged}");
        // Dynamic mode: side_friction has no effect.
        let dynamic = ContactTerms::all(friction, ContactMode::Dynamic);
        let (d_avg, d_full) = (eval(&batch, &dynamic), eval(&full, &dynamic));
        for i in 0..batch.num_pairs() {
            assert_eq!(d_avg.fields(i), d_full.fields(i), "dynamic pair {i}");
        }
        let Some(ctx) = ctx else { continue };
        let gpu = contact_gpu(ctx, &terms, &batch).unwrap();
        let rep = compare(
            &batch,
            &terms,
            &avg,
            &|i| (gpu.fields(i), gpu.contact[i]),
            f64::EPSILON / 2.0,
            F64_BOUND,
            "GPU f64, the whirl's average",
        );
        assert!(rep.max_normwise_well <= 1e-12, "{}", rep.max_normwise_well);
    }
}
