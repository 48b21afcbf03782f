//! `holewall calibrate` (issue 26): friction factors from measured loads. Synthetic
//! measurements (the FE at known friction factors, Gaussian noise added) on several wells —
//! two shipped cases and a generated corpus well — are recovered within the stated 95 %
//! intervals; data from a heavier string are rejected loudly (exit code 1, the reason on
//! stderr); a bad measured file is an input error (exit code 2, line and column).

use holewall::calibrate::synthetic::{synthetic, write_measured, SyntheticPlan};
use holewall::calibrate::MeasuredMode::{PickUp, Rotating, SlackOff};

mod common;

fn manifest(p: &str) -> String {
    format!("{}/{p}", env!("CARGO_MANIFEST_DIR"))
}

/// Measures `case_path`'s well at `depths` (pick-up, slack-off, rotating) with friction
/// `mu` and noise (5 kN, 0.3 kN·m); calibrates `calibrate_path` against the file; returns
/// (exit code, summary, stderr, output folder).
fn measure_and_calibrate(
    tag: &str,
    case_path: &str,
    calibrate_path: &str,
    depths: Vec<f64>,
    mu: Vec<f64>,
    seed: u64,
) -> (i32, serde_json::Value, String, std::path::PathBuf) {
    let case = holewall::case::load_case(std::path::Path::new(case_path)).unwrap();
    let plan = SyntheticPlan {
        depths,
        modes: vec![PickUp, SlackOff, Rotating],
        mu,
        sigma_hook: 5e3,
        sigma_torque: 300.0,
        seed,
        rpm: Some(120.0 * std::f64::consts::PI / 30.0),
    };
    let rows = synthetic(&case, &plan).unwrap();
    let dir = common::scratch_dir("calibrate", tag);
    let file = dir.join("measured.csv");
    write_measured(&rows, &file).unwrap();
    let out = dir.join("out");
    let (code, stdout, stderr) = common::holewall(&[
        "calibrate",
        calibrate_path,
        "--measured",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let summary = serde_json::from_str(&stdout).unwrap_or(serde_json::Value::Null);
    (code, summary, stderr, out)
}

/// Every estimate's 95 % interval holds the truth, and is no wider than `widest`.
fn check_recovered(s: &serde_json::Value, truth: &[(&str, f64)], widest: f64) {
    let est = s["calibration"]["estimates"].as_array().unwrap();
    assert_eq!(est.len(), truth.len());
    for (e, (key, mu)) in est.iter().zip(truth) {
        assert_eq!(e["key"], *key);
        let (lo, hi) = (
            e["interval_95"][0].as_f64().unwrap(),
            e["interval_95"][1].as_f64().unwrap(),
        );
        println!(
            "{key}: truth {mu}, 95 % [{lo:.3}, {hi:.3}], MAP {}",
            e["map"]
        );
        assert!(lo <= *mu && *mu <= hi, "{key}: {mu} outside [{lo}, {hi}]");
        assert!(hi - lo < widest, "{key}: [{lo}, {hi}] wider than {widest}");
    }
    assert_eq!(s["calibration"]["accepted"], true);
    // The spline stands in for the FE to well within the noise.
    assert!(s["calibration"]["surrogate_error"][0].as_f64().unwrap() < 0.25 * 5e3);
}

#[test]
fn calibration_recovers_the_friction_factors_of_synthetic_measurements() {
    let dir = common::scratch_dir("calibrate", "corpus");
    let corpus = holewall::corpus::write_well(1, &dir).unwrap();
    let corpus_path = corpus.case_path.to_str().unwrap().to_string();
    let total = corpus.spec.total_md;
    // (tag, case, bit depths, truth (cased, open), seed, widest interval allowed):
    // 1. the shipped broomstick case (casing to 500 m, nearly vertical: the cased factor is
    //    barely constrained, its interval wide; the open hole's is);
    // 2. 2,500 m build-and-hold cased to 1,200 m through the build: both factors;
    // 3. a generated well (corpus seed 1: build and hold to 54°, 1,281 m, 8¾ in hole).
    let wells = [
        (
            "broomstick",
            manifest("cases/broomstick_tool_joints.toml"),
            vec![700.0, 900.0, 1100.0, 1300.0, 1500.0],
            (0.18, 0.32),
            1,
            0.6,
        ),
        (
            "2500",
            manifest("cases/build_and_hold_2500.toml"),
            vec![1300.0, 1600.0, 1900.0, 2200.0, 2500.0],
            (0.22, 0.35),
            2,
            0.25,
        ),
        (
            "corpus1",
            corpus_path,
            (0..5).map(|i| total - 100.0 * i as f64).collect(),
            (0.15, 0.28),
            3,
            0.6,
        ),
    ];
    for (tag, case, depths, (cased, open), seed, widest) in wells {
        let (code, s, stderr, out) =
            measure_and_calibrate(tag, &case, &case, depths, vec![cased, open], seed);
        assert_eq!(code, 0, "{tag}: {stderr}");
        check_recovered(&s, &[("mu.cased", cased), ("mu.open", open)], widest);
        for f in [
            "posterior.csv",
            "posterior.png",
            "residuals_torque.png",
            "torque.png",
        ] {
            assert!(out.join(f).is_file(), "{tag}: {f}");
        }
    }
}

#[test]
fn data_from_a_heavier_string_are_rejected() {
    // Measured on 5 in pipe of 4.0 in bore (25.6 lb/ft) but calibrated with the case's
    // 4.276 in bore (19.5 lb/ft): the hook-load residuals grow with depth, exit code 1.
    let case = manifest("cases/broomstick_tool_joints.toml");
    let heavy = std::fs::read_to_string(&case)
        .unwrap()
        .replace("id = \"4.276 in\"", "id = \"4.0 in\"");
    let dir = common::scratch_dir("calibrate", "heavy_case");
    let heavy_path = dir.join("heavy.toml");
    std::fs::write(&heavy_path, heavy).unwrap();
    let (code, s, stderr, out) = measure_and_calibrate(
        "heavy",
        heavy_path.to_str().unwrap(),
        &case,
        vec![700.0, 900.0, 1100.0, 1300.0, 1500.0],
        vec![0.18, 0.32],
        1,
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("calibration rejected") && stderr.contains("trend with depth"));
    assert_eq!(s["calibration"]["accepted"], false);
    // Every output is written all the same.
    for f in [
        "residuals.csv",
        "residuals.png",
        "broomstick.png",
        "posterior.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

#[test]
fn a_bad_measured_file_is_an_input_error() {
    let dir = common::scratch_dir("calibrate", "bad");
    let file = dir.join("bad.csv");
    // (file text, what stderr must say): an unknown mode names file and line; a row deeper
    // than the case's hole is refused.
    for (text, says) in [
        (
            "bit_md_m,mode,hook_load_kn\n900,pick_up,640\n1100,tripping,700\n",
            "bad.csv:3: mode: unknown mode",
        ),
        (
            "bit_md_m,mode,hook_load_kn\n1900,pick_up,640\n",
            "below the case's hole",
        ),
    ] {
        std::fs::write(&file, text).unwrap();
        let (code, _, stderr) = common::holewall(&[
            "calibrate",
            &manifest("cases/broomstick_tool_joints.toml"),
            "--measured",
            file.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(code, 2, "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
    }
}
