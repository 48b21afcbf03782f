//! `holewall bench kernels` (issue 27): the roofline per kernel runs on the adapter at hand
//! and its figures are consistent — the ceilings measured, every kernel timed, no kernel
//! above its precision's FMA ceiling (which would mean its FLOPs are over-counted or the
//! ceiling under-measured), bytes at least the kernel's own outputs, the files written.

mod common;

#[test]
fn the_roofline_bench_measures_every_kernel_under_its_ceilings() {
    let Some(ctx) = common::gpu() else { return };
    let out = common::scratch_dir("bench_kernels", "roofline");
    let (code, stdout, stderr) = common::holewall(&[
        "bench",
        "kernels",
        "--variants",
        "16,64",
        "--nodes",
        "11",
        "--repeats",
        "3",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
    // Both forms of the block solve, each named.
    for form in ["serial", "lanes"] {
        assert!(
            stdout.contains(&format!("| block solve ({form}) |")),
            "{stdout}"
        );
    }
    let r: serde_json::Value = common::json(&out.join("kernels.json"));
    let c = &r["ceilings"];
    let fma32 = c["fma_gflops_f32"].as_f64().unwrap();
    let copy = c["copy_gbytes_per_s"].as_f64().unwrap();
    assert!(fma32 > 0.1 && copy > 0.1, "{c}");
    // The copy at every footprint from 1 MB to 256 MB, the headline its largest.
    let curve = c["copy_curve"].as_array().unwrap();
    let footprints: Vec<u64> = curve
        .iter()
        .map(|p| p["footprint_bytes"].as_u64().unwrap())
        .collect();
    assert_eq!(footprints, (20..=28).map(|k| 1u64 << k).collect::<Vec<_>>());
    assert!(curve
        .iter()
        .all(|p| p["gbytes_per_s"].as_f64().unwrap() > 0.1));
    assert_eq!(curve[8]["gbytes_per_s"].as_f64().unwrap(), copy);
    // A kernel's bandwidth ceiling: the best copy at a footprint from the nearest to its
    // bytes (on a log scale) up.
    let ceiling = |bytes: f64| {
        curve
            .iter()
            .filter(|p| p["footprint_bytes"].as_f64().unwrap() >= bytes / 2f64.sqrt())
            .map(|p| p["gbytes_per_s"].as_f64().unwrap())
            .fold(copy, f64::max)
    };
    let rows = r["rows"].as_array().unwrap();
    let precisions = if ctx.has_f64 { 2 } else { 1 };
    assert_eq!(
        rows.len(),
        7 * 2 * precisions,
        "4 kernels (the assembly also as a relaxation past its ceiling assembles, the block \
         solve in 3 forms) × 2 sizes × precisions"
    );
    for k in rows {
        let f = |key: &str| k[key].as_f64().unwrap_or(f64::NAN);
        assert!(
            f("seconds") > 0.0 && f("flops") > 0.0 && f("bytes") > 0.0,
            "{k}"
        );
        // Above 1.2 × the FMA ceiling would be a counting error (noise allows a little).
        assert!(f("fraction_of_fma") < 1.2, "{k}");
        // Bytes are the bindings' sizes: at least the outputs the kernel writes.
        assert!(f("gbytes_per_s") > 0.0 && f("intensity") > 0.0, "{k}");
        // Set against the copy at its footprint or larger.
        let against = f("gbytes_per_s") / f("fraction_of_bandwidth");
        let expected = ceiling(f("bytes"));
        assert!((against - expected).abs() <= 1e-9 * expected, "{k} {c}");
    }
    // The block solve's counted FLOPs grow linearly in V at fixed n, in every form.
    for form in ["serial", "lanes", "cyclic"] {
        let lu: Vec<f64> = rows
            .iter()
            .filter(|k| {
                k["kernel"] == format!("block solve ({form})").as_str() && k["precision"] == "f32"
            })
            .map(|k| k["flops"].as_f64().unwrap())
            .collect();
        assert!(
            lu.len() == 2 && (lu[1] / lu[0] - 4.0).abs() < 1e-9,
            "{lu:?}"
        );
    }
    // The assembly of a relaxation past its ceiling (translations and rotations shifted,
    // the kernel built `SHIFT`) counts the shift's FLOPs and its bindings' bytes on top of
    // the plain assembly's.
    let of = |name: &str, key: &str| -> Vec<f64> {
        rows.iter()
            .filter(|k| k["kernel"] == name && k["precision"] == "f32")
            .map(|k| k[key].as_f64().unwrap())
            .collect()
    };
    for key in ["flops", "bytes"] {
        let (plain, shifted) = (
            of("assemble", key),
            of("assemble (relaxation, rotations shifted)", key),
        );
        assert!(
            shifted.len() == 2 && (0..2).all(|i| shifted[i] > plain[i]),
            "{key}: {plain:?} {shifted:?}"
        );
    }
    for f in ["kernels.md", "roofline.png"] {
        assert!(out.join(f).exists(), "{f}");
    }
}
