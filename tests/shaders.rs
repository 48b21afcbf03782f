//! Every WGSL kernel has a CPU twin, names it on its first line, and validates with naga in
//! every specialisation (no GPU needed).

use std::collections::BTreeSet;

use holewall::gpu::compose::{compose, validate, SHADERS};
use holewall::gpu::contact::contact_wgsl;
use holewall::kernels::TWINS;
use holewall::physics::contact::{ContactMode, ContactTerms, FrictionModel, SpringLaw};

#[test]
fn every_shader_has_a_twin_named_on_its_first_line() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut on_disk = BTreeSet::new();
    for entry in std::fs::read_dir(root.join("shaders")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "wgsl") {
            on_disk.insert(path.file_name().unwrap().to_string_lossy().to_string());
        }
    }
    assert!(!on_disk.is_empty());
    for name in &on_disk {
        let (_, twin) = TWINS
            .iter()
            .find(|(s, _)| s == name)
            .unwrap_or_else(|| panic!("shaders/{name} has no CPU twin in kernels::TWINS"));
        assert!(
            root.join(twin).is_file(),
            "twin {twin} of {name} is missing"
        );
        let text = std::fs::read_to_string(root.join("shaders").join(name)).unwrap();
        let first = text.lines().next().unwrap_or("");
        assert!(
            first.contains(twin),
            "first line of shaders/{name} must name its twin {twin}: {first:?}"
        );
        let twin_text = std::fs::read_to_string(root.join(twin)).unwrap();
        assert!(
            twin_text
                .lines()
                .next()
                .unwrap_or("")
                .contains(&format!("shaders/{name}")),
            "first line of {twin} must name shaders/{name}"
        );
        // The embedded copy is the file on disk.
        assert!(
            SHADERS.iter().any(|(n, s)| n == name && *s == text),
            "{name} not embedded"
        );
    }
    for (name, _) in TWINS {
        assert!(
            on_disk.contains(*name),
            "kernels::TWINS lists {name}, which is not in shaders/"
        );
    }
    // Every shared file is embedded too.
    for entry in std::fs::read_dir(root.join("shaders/shared")).unwrap() {
        let path = entry.unwrap().path();
        let rel = format!("shared/{}", path.file_name().unwrap().to_string_lossy());
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            SHADERS.iter().any(|(n, s)| *n == rel && *s == text),
            "{rel} not embedded"
        );
    }
}

#[test]
fn every_contact_specialisation_validates() {
    let mut count = 0;
    for spring in [SpringLaw::Linear, SpringLaw::Power, SpringLaw::PowerBlend] {
        for damping in [false, true] {
            for friction in [
                None,
                Some(FrictionModel::Split),
                Some(FrictionModel::Coupled),
            ] {
                for mode in [ContactMode::Dynamic, ContactMode::Static] {
                    for f64 in [false, true] {
                        let terms = ContactTerms {
                            spring,
                            damping,
                            friction,
                            mode,
                        };
                        let wgsl = contact_wgsl(&terms, f64).unwrap();
                        validate(&wgsl).unwrap_or_else(|e| panic!("{terms:?} f64={f64}: {e}"));
                        {
                            // The trials' kernels: force only, with and without the list.
                            for masked in [false, true] {
                                let lean =
                                    holewall::gpu::contact::contact_force_wgsl(&terms, f64, masked)
                                        .unwrap();
                                validate(&lean).unwrap_or_else(|e| {
                                    panic!("{terms:?} force only, masked {masked}: {e}")
                                });
                                assert_eq!(lean.contains("f64"), f64);
                                let masked_full =
                                    holewall::gpu::contact::contact_masked_wgsl(&terms, f64)
                                        .unwrap();
                                validate(&masked_full)
                                    .unwrap_or_else(|e| panic!("{terms:?} masked: {e}"));
                            }
                        }
                        assert_no_uniform(&wgsl);
                        assert_eq!(
                            wgsl.contains("f64"),
                            f64,
                            "precision leak in {terms:?} f64={f64}"
                        );
                        count += 1;
                    }
                }
            }
        }
    }
    assert_eq!(count, 72);
}

#[test]
fn composer_handles_nesting_else_and_errors() {
    let flags: BTreeSet<&str> = ["F64", "POW"].into_iter().collect();
    let text = compose("contact.wgsl", &flags, true).unwrap();
    assert!(text.starts_with("alias real = f64;"));
    assert!(
        text.contains("fn pow_pos(x: f64, m: f64) -> f64"),
        "f64 pow comes from math_f64"
    );
    assert!(
        !text.contains("return pow(x, m)"),
        "the f32 builtin pow must not reach an f64 kernel"
    );
    let flags32: BTreeSet<&str> = ["POW"].into_iter().collect();
    let text32 = compose("contact.wgsl", &flags32, false).unwrap();
    assert!(text32.contains("return pow(x, m)"));
    assert!(!text32.contains("exp_f64"));
    assert!(!text.contains("#if") && !text.contains("#endif") && !text.contains("#include"));
    assert!(compose("no_such.wgsl", &flags, false).is_err());
}

#[test]
fn engine_kernels_validate_in_both_precisions() {
    use holewall::gpu::block_lu::LuForm;
    use holewall::gpu::dynamics::DynamicsKernel;
    use holewall::gpu::kernel::Kernel;
    for f64 in [false, true] {
        for wgsl in [
            holewall::gpu::block_lu::block_lu_wgsl(f64, LuForm::Serial).unwrap(),
            holewall::gpu::block_lu::block_lu_wgsl(f64, LuForm::Lanes).unwrap(),
            holewall::gpu::assemble::assemble_wgsl(f64).unwrap(),
            holewall::gpu::update::update_wgsl(false, f64).unwrap(),
            holewall::gpu::update::update_wgsl(true, f64).unwrap(),
            holewall::gpu::beam::beam_wgsl(f64, false, false).unwrap(),
            holewall::gpu::beam::beam_wgsl(f64, true, false).unwrap(),
            holewall::gpu::beam::beam_wgsl(f64, false, true).unwrap(),
            holewall::gpu::beam::beam_wgsl(f64, true, true).unwrap(),
            holewall::gpu::beam::beam_trial_wgsl(f64, false).unwrap(),
            holewall::gpu::beam::beam_trial_wgsl(f64, true).unwrap(),
            holewall::gpu::assemble::assemble_force_wgsl(f64, false).unwrap(),
            holewall::gpu::assemble::assemble_force_wgsl(f64, true).unwrap(),
            holewall::gpu::update::update_wgsl_with(false, f64, true, false).unwrap(),
            holewall::gpu::update::update_wgsl_with(false, f64, true, true).unwrap(),
            holewall::gpu::update::update_wgsl_with(true, f64, false, true).unwrap(),
            holewall::gpu::batch::sites_wgsl(f64).unwrap(),
            holewall::gpu::batch::sites_trial_wgsl(f64).unwrap(),
            holewall::gpu::batch::sites_wgsl_for(true, f64).unwrap(),
            holewall::gpu::assemble::assemble_wgsl_for(true, f64).unwrap(),
            holewall::gpu::dynamics::dynamics_wgsl(DynamicsKernel::Predict, f64).unwrap(),
            holewall::gpu::dynamics::dynamics_wgsl(DynamicsKernel::Accelerate, f64).unwrap(),
            holewall::gpu::dynamics::dynamics_wgsl(DynamicsKernel::Scale, f64).unwrap(),
            // The dynamic trials' kernels (listed variants, residual alone).
            Kernel::DynamicsMasked(DynamicsKernel::Predict)
                .wgsl(f64)
                .unwrap(),
            Kernel::DynamicsMasked(DynamicsKernel::Accelerate)
                .wgsl(f64)
                .unwrap(),
            Kernel::SitesTrial { dynamic: true }.wgsl(f64).unwrap(),
            Kernel::AssembleTrial {
                dynamic: true,
                unbalance: false,
            }
            .wgsl(f64)
            .unwrap(),
            Kernel::AssembleTrial {
                dynamic: true,
                unbalance: true,
            }
            .wgsl(f64)
            .unwrap(),
            holewall::gpu::assemble::assemble_force_wgsl_with(true, false, f64, false).unwrap(),
            holewall::gpu::assemble::assemble_force_wgsl_with(true, true, f64, false).unwrap(),
            holewall::gpu::assemble::assemble_wgsl_with(true, true, f64).unwrap(),
            // The dynamic iterations' kernels (listed variants, the whole system).
            Kernel::DynamicsMasked(DynamicsKernel::Scale)
                .wgsl(f64)
                .unwrap(),
            Kernel::BeamMasked { kink: false }.wgsl(f64).unwrap(),
            Kernel::BeamMasked { kink: true }.wgsl(f64).unwrap(),
            Kernel::AssembleMasked { unbalance: false }
                .wgsl(f64)
                .unwrap(),
            Kernel::AssembleMasked { unbalance: true }
                .wgsl(f64)
                .unwrap(),
        ] {
            validate(&wgsl).unwrap_or_else(|e| panic!("f64={f64}: {e}"));
            assert_eq!(wgsl.contains("f64"), f64, "precision leak, f64={f64}");
            assert_no_uniform(&wgsl);
        }
    }
}

/// Kernel parameters travel in read-only storage buffers, never in uniforms: lavapipe
/// (Mesa 22.3) inlines uniform values that steer loops and branches into the shader and
/// recompiles it at every dispatch whose uniform changes, leaking ≈ 1.3 MB of host memory
/// each time (a 165-node block solve took 0.29 s instead of 0.02 s; see
/// docs/performance.md).
fn assert_no_uniform(wgsl: &str) {
    assert!(
        !wgsl.contains("var<uniform>"),
        "a kernel binds a uniform; use var<storage, read> (lavapipe recompiles per dispatch)"
    );
}
