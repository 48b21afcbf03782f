//! Ensembles on the CPU backend: a variant's results equal a single run of the case with
//! the same values written into it; a failing variant fails alone; bad variant files are
//! refused with file, line and key.

mod common;

use holewall::backend::{BackendChoice, Precision};
use holewall::case::{parse_case, Analysis};
use holewall::ensemble::job::run;
use holewall::ensemble::qoi::{static_variant, Status};
use holewall::ensemble::runner::run_variants_cpu;
use holewall::ensemble::{apply, variants_from_csv_text};

/// The 60 m test bed of `tests/extreme.rs` with Table 1 values, written out.
fn bed(mu: &str, wob: &str) -> String {
    common::bed_text(mu, "8.25 in", "6e7", "1", "1e-3").replace(
        "weight_on_bit = \"20 kN\"",
        &format!("weight_on_bit = \"{wob}\""),
    )
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("holewall-ens-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn a_variant_equals_the_case_with_its_values_written_in() {
    let dir = tmp("equal");
    let base = parse_case(&dir.join("base.toml"), &bed("0.3", "20 kN")).unwrap();
    let variants =
        variants_from_csv_text("v.csv", "name,mu,wob\nlow,0.1,10 kN\nhigh,0.5,35 kN\n").unwrap();
    let bar = indicatif::ProgressBar::hidden();
    let results = run_variants_cpu(&base, Analysis::Static, &variants, &bar);
    for (v, r, (mu, wob)) in [
        (&variants[0], &results[0], ("0.1", "10 kN")),
        (&variants[1], &results[1], ("0.5", "35 kN")),
    ] {
        let written = parse_case(&dir.join("w.toml"), &bed(mu, wob)).unwrap();
        let single = static_variant(&written, &v.name, &written.model);
        assert_ne!(r.status, Status::Failed, "{}: {}", v.name, r.reason);
        let np = r.neutral_point_from_bit_m;
        eprintln!(
            "{}: neutral point {np:?} m, surface torque {:.1} N·m, stab1 side force {:.1} N",
            v.name, r.max_surface_torque_nm, r.stabilizers[0].max_side_force_n
        );
        // Same model, same solver: the same numbers.
        assert_eq!(r.neutral_point_from_bit_m, single.neutral_point_from_bit_m);
        assert_eq!(r.max_surface_torque_nm, single.max_surface_torque_nm);
        assert_eq!(
            r.stabilizers[0].max_side_force_n,
            single.stabilizers[0].max_side_force_n
        );
    }
    // The overrides did something: with 35 kN the whole 60 m string is in compression (no
    // neutral point), and five times the friction gives far more surface torque.
    assert!(results[1].neutral_point_from_bit_m.is_none());
    assert!(results[1].max_surface_torque_nm > 2.0 * results[0].max_surface_torque_nm);
}

#[test]
fn a_failing_variant_fails_alone_and_the_others_are_bit_identical() {
    let dir = tmp("fail");
    let case = parse_case(&dir.join("base.toml"), &bed("0.3", "20 kN")).unwrap();
    let good = variants_from_csv_text("v.csv", "name,mu,wob\na,0.2,15 kN\nb,0.4,25 kN\n").unwrap();
    // Absurd loads on an absurd spring: 9 MN and 1 MN·m on the bit, k_e at the top of its
    // range with m = 3, cannot be brought to equilibrium.
    let with_bad = variants_from_csv_text(
        "v.csv",
        "name,mu,wob,k_e,m,tob\na,0.2,15 kN,6e7,1,0\nbad,0.3,9000 kN,1e12,3,1000 kN.m\nb,0.4,25 kN,6e7,1,0\n",
    )
    .unwrap();
    let bar = indicatif::ProgressBar::hidden();
    let alone = run_variants_cpu(&case, Analysis::Static, &good, &bar);
    let mixed = run_variants_cpu(&case, Analysis::Static, &with_bad, &bar);
    assert_eq!(mixed[1].status, Status::Failed);
    eprintln!("failed variant: {}", mixed[1].reason);
    assert!(!mixed[1].reason.is_empty());
    for (a, m) in [(&alone[0], &mixed[0]), (&alone[1], &mixed[2])] {
        assert_eq!(a.status, Status::Converged);
        assert_eq!(
            a.neutral_point_from_bit_m.map(f64::to_bits),
            m.neutral_point_from_bit_m.map(f64::to_bits)
        );
        assert_eq!(
            a.max_surface_torque_nm.to_bits(),
            m.max_surface_torque_nm.to_bits()
        );
        assert_eq!(
            a.stabilizers[0].max_side_force_n.to_bits(),
            m.stabilizers[0].max_side_force_n.to_bits()
        );
    }
}

#[test]
fn stabilizer_layout_moves_the_site() {
    let dir = tmp("layout");
    let case = parse_case(&dir.join("base.toml"), &bed("0.3", "20 kN")).unwrap();
    let v = variants_from_csv_text("v.csv", "stab1.from_bit,stab1.blade\n20 m,8 in\n").unwrap();
    let m = apply(&case, &v[0]).unwrap();
    let stab = m.sites.iter().find(|s| s.stabilizer).unwrap();
    let md = m.nodes[stab.node].md;
    assert!((case.bit_md - md - 20.0).abs() <= 1.5, "stabilizer at {md}");
    assert!((stab.params.disk_radius - 0.1016).abs() < 1e-12);
    assert!((stab.params.clearance - (stab.hole_radius - 0.1016)).abs() < 1e-12);
    // Every node still carries exactly one site (the pipe-body site took the old node).
    let mut nodes: Vec<usize> = m.sites.iter().map(|s| s.node).collect();
    nodes.dedup();
    assert_eq!(nodes.len(), case.model.sites.len());
    let too_wide = variants_from_csv_text("v.csv", "stab1.blade\n9 in\n").unwrap();
    assert!(apply(&case, &too_wide[0])
        .unwrap_err()
        .to_string()
        .contains("wider than the hole"));
}

/// Stabilizers placed by an ensemble stand where they are placed, not at the case mesh's
/// nearest node: before, placements over 16–24 m from the bit on the bed's mesh ran at the
/// few nodes there, the same model for many draws.
#[test]
fn placed_stabilizers_stand_within_the_gap_of_where_they_are_placed() {
    use holewall::ensemble::placed_case;
    use holewall::model::NODE_AT_GAP;
    let dir = tmp("placed");
    let case = parse_case(&dir.join("base.toml"), &bed("0.3", "20 kN")).unwrap();
    let asked: Vec<f64> = (0..40)
        .map(|k| 16.0 + 8.0 * (k as f64 / 39.0).powi(2))
        .collect();
    let csv = asked.iter().fold("stab1.from_bit\n".to_string(), |t, d| {
        t + &format!("{d} m\n")
    });
    let variants = variants_from_csv_text("v.csv", &csv).unwrap();
    let ran = |case: &holewall::case::Case| -> Vec<f64> {
        variants
            .iter()
            .map(|v| {
                let m = apply(case, v).unwrap();
                let stab = m.sites.iter().find(|s| s.stabilizer).unwrap();
                case.bit_md - m.nodes[stab.node].md
            })
            .collect()
    };
    let distinct = |d: &[f64]| {
        let mut d = d.to_vec();
        d.sort_by(f64::total_cmp);
        d.dedup();
        d.len()
    };
    let before = ran(&case);
    let placed = placed_case(&case, &variants)
        .unwrap()
        .expect("variants place stab1");
    let after = ran(&placed);
    let worst = |r: &[f64]| {
        r.iter()
            .zip(&asked)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, f64::max)
    };
    // Within the gap (twice it beside a component's end: the bed's string is one collar
    // from its stabilizer up, so none here).
    assert!(worst(&after) <= NODE_AT_GAP + 1e-9, "placed {after:?}");
    assert!(
        worst(&before) > 2.0 * NODE_AT_GAP,
        "the bed's mesh already fine: {before:?}"
    );
    assert!(
        distinct(&after) >= 3 * distinct(&before),
        "{before:?} → {after:?}"
    );
    // No element shorter than the gap, and the nodes away from the placements unmoved.
    let mesh = &placed.model;
    assert!(mesh
        .elements
        .iter()
        .all(|e| e.length0 >= NODE_AT_GAP - 1e-9));
    let far = |md: f64| (case.bit_md - md) < 15.0 || (case.bit_md - md) > 25.0;
    let old: Vec<f64> = case
        .model
        .nodes
        .iter()
        .map(|n| n.md)
        .filter(|&m| far(m))
        .collect();
    let new: Vec<f64> = mesh
        .nodes
        .iter()
        .map(|n| n.md)
        .filter(|&m| far(m))
        .collect();
    assert_eq!(old, new);
    // No placement: the case as it was.
    let none = variants_from_csv_text("v.csv", "mu\n0.2\n").unwrap();
    assert!(placed_case(&case, &none).unwrap().is_none());
}

#[test]
fn grid_dynamic_ensemble_writes_variants_and_series() {
    let dir = tmp("grid");
    let text = bed("0.3", "20 kN").replace("duration = \"0.1 s\"", "duration = \"0.06 s\"")
        + "\n[ensemble]\nanalysis = \"dynamic\"\nseries = [\"1\"]\n\n[ensemble.grid]\nrpm = [\"60 rpm\", \"120 rpm\"]\n";
    let path = dir.join("grid.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.join("out");
    let s = run(
        &path,
        None,
        BackendChoice::Cpu,
        Precision::F64,
        &out,
        false,
        &Default::default(),
    )
    .unwrap();
    assert_eq!((s.variants, s.failed), (2, 0));
    let csv = std::fs::read_to_string(out.join("variants.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("stab1_whirl_hz"));
    assert_eq!(csv.lines().count(), 3);
    assert!(out.join("series/1/timeseries.csv").exists());
    assert!(out.join("whirl_map_stab1.png").exists());
    // f32 on the CPU backend is refused plainly (it is the f64 oracle), before any output.
    let out2 = dir.join("out2");
    let e = run(
        &path,
        None,
        BackendChoice::Cpu,
        Precision::F32,
        &out2,
        false,
        &Default::default(),
    )
    .unwrap_err();
    assert_eq!(e.exit_code(), 2);
    // The GPU engine: the same quantities of interest as the CPU integrator's runs.
    if common::gpu().is_some() {
        let out3 = dir.join("out3");
        let g = run(
            &path,
            None,
            BackendChoice::Gpu,
            Precision::F64,
            &out3,
            false,
            &Default::default(),
        )
        .unwrap();
        common::summary_agrees_with_csv(&g, &out3);
        assert_eq!(
            (
                g.backend.as_str(),
                g.variants,
                g.failed,
                g.step_cut,
                g.solved_by_engine
            ),
            ("gpu", 2, 0, 0, 2)
        );
        let read = |p: &std::path::Path| -> Vec<Vec<String>> {
            std::fs::read_to_string(p.join("variants.csv"))
                .unwrap()
                .lines()
                .map(|l| l.split(',').map(String::from).collect())
                .collect()
        };
        let (a, b) = (read(&out3), read(&out));
        assert_eq!(a[0], b[0]);
        let mut worst: f64 = 0.0;
        let mut compared = 0;
        for (ra, rb) in a.iter().zip(&b).skip(1) {
            for (k, (x, y)) in ra.iter().zip(rb).enumerate() {
                let name = &a[0][k];
                if name == "newton_iterations" || name == "reason" {
                    continue;
                }
                if name == "solved_by" {
                    // The engine solved every variant on the GPU backend, the CPU on its own.
                    assert_eq!((x.as_str(), y.as_str()), ("engine", "cpu"));
                    continue;
                }
                match (x.parse::<f64>(), y.parse::<f64>()) {
                    (Ok(x), Ok(y)) => {
                        worst = worst.max((x - y).abs() / y.abs().max(1e-9));
                        compared += 1;
                    }
                    _ => assert_eq!(x, y, "{name}"),
                }
            }
        }
        eprintln!("dynamic grid, GPU engine vs CPU integrator: {compared} quantities, worst relative difference {worst:.2e}");
        assert!(worst <= 1e-6, "{worst:e}");
    }
    assert!(!out2.exists());
}

#[test]
fn bad_variant_files_name_file_line_and_key() {
    let dir = tmp("bad");
    let case = dir.join("c.toml");
    std::fs::write(&case, bed("0.3", "20 kN")).unwrap();
    for (body, line, key) in [
        ("mu,wob\n0.2,10 kN\n0.3,-5 kN\n", 3, "wob"),
        ("mu,torque\n0.2,1\n", 1, "torque"),
        ("k_e.stab0\n1e8\n", 1, "k_e.stab0"),
        ("m\n0\n", 2, "m"),
    ] {
        let f = dir.join("v.csv");
        std::fs::write(&f, body).unwrap();
        let out = dir.join("o");
        let e = run(
            &case,
            Some(&f),
            BackendChoice::Cpu,
            Precision::F64,
            &out,
            false,
            &Default::default(),
        )
        .unwrap_err();
        let msg = e.to_string();
        eprintln!("{msg}");
        assert_eq!(e.exit_code(), 2);
        assert!(msg.contains(&format!("v.csv:{line}: {key}")), "{msg}");
        assert!(!out.exists());
    }
    // A stabilizer the case does not have.
    let f = dir.join("v.csv");
    std::fs::write(&f, "mu.stab3\n0.2\n").unwrap();
    let e = run(
        &case,
        Some(&f),
        BackendChoice::Cpu,
        Precision::F64,
        &dir.join("o"),
        false,
        &Default::default(),
    )
    .unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("stab3"), "{e}");
}

#[test]
fn sixty_four_variant_static_ensemble_on_the_gpu_matches_the_cpu_runs() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tmp("gpu64");
    let case = dir.join("c.toml");
    std::fs::write(&case, bed("0.3", "20 kN")).unwrap();
    let mut csv = String::from("name,mu,wob,k_e.stab1\n");
    for a in 0..8 {
        for b in 0..8 {
            csv += &format!(
                "v{a}{b},{},{} kN,{}\n",
                0.1 + 0.05 * a as f64,
                4.0 + 1.5 * b as f64,
                [3e7, 6e7, 1e8, 2e8][(a + b) % 4]
            );
        }
    }
    let f = dir.join("v.csv");
    std::fs::write(&f, csv).unwrap();
    let t0 = std::time::Instant::now();
    let gpu = run(
        &case,
        Some(&f),
        BackendChoice::Gpu,
        Precision::F64,
        &dir.join("gpu"),
        false,
        &Default::default(),
    )
    .unwrap();
    let t_gpu = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    let cpu = run(
        &case,
        Some(&f),
        BackendChoice::Cpu,
        Precision::F64,
        &dir.join("cpu"),
        false,
        &Default::default(),
    )
    .unwrap();
    let t_cpu = t0.elapsed().as_secs_f64();
    common::summary_agrees_with_csv(&gpu, &dir.join("gpu"));
    common::summary_agrees_with_csv(&cpu, &dir.join("cpu"));
    assert_eq!((gpu.backend.as_str(), cpu.backend.as_str()), ("gpu", "cpu"));
    assert_eq!(gpu.variants, 64);
    let read = |p: &std::path::Path| -> Vec<Vec<String>> {
        std::fs::read_to_string(p.join("variants.csv"))
            .unwrap()
            .lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect()
    };
    let (g, c) = (read(&dir.join("gpu")), read(&dir.join("cpu")));
    let header = &g[0];
    let cols: Vec<usize> = [
        "neutral_point_from_bit_m",
        "max_surface_torque_nm",
        "stab1_max_side_force_n",
        "stab1_max_lateral_m",
    ]
    .iter()
    .map(|name| header.iter().position(|h| h == name).unwrap())
    .collect();
    // The neutral point comes from axial forces EA/l·(l − l0), with l computed from
    // absolute positions: its rounding floor is ≈ 4·(EA/l)·ε·|x|max / w (w the buoyed
    // weight per length, the axial force's slope), ≈ 5e-8 m here. Every other quantity is
    // held to 1e-9 relative.
    let model = holewall::case::load_case(&case).unwrap().model;
    let x_max = model
        .nodes
        .iter()
        .flat_map(|nd| nd.position)
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let floor = model
        .elements
        .iter()
        .map(|e| {
            4.0 * e.section.youngs_modulus * e.section.area / e.length0 * f64::EPSILON * x_max
                / e.buoyed_weight_per_length
        })
        .fold(0.0f64, f64::max);
    let mut worst: f64 = 0.0;
    let mut worst_np: f64 = 0.0;
    let mut compared = 0;
    for (rg, rc) in g.iter().zip(&c).skip(1) {
        for (n, &k) in cols.iter().enumerate() {
            match (rg[k].parse::<f64>(), rc[k].parse::<f64>()) {
                (Ok(a), Ok(b)) => {
                    if n == 0 {
                        worst_np = worst_np.max((a - b).abs());
                    } else {
                        worst = worst.max((a - b).abs() / b.abs().max(1e-12));
                    }
                    compared += 1;
                }
                _ => assert_eq!(rg[k], rc[k], "one side empty"),
            }
        }
    }
    eprintln!(
        "64 variants: GPU {t_gpu:.1} s ({} re-run on the CPU), CPU {t_cpu:.1} s; {compared} quantities: torque, side force, lateral worst relative difference {worst:.2e}; neutral point {worst_np:.2e} m (rounding floor {floor:.1e} m)",
        gpu.solved_by_cpu
    );
    assert_eq!(gpu.solved_by_cpu, 0, "the engine must solve every variant");
    assert!(worst <= 1e-9, "{worst:e}");
    assert!(worst_np <= floor, "{worst_np:e} m");
    // f32 on the GPU engine: the error against the f64 CPU runs, reported and bounded by the
    // residual the f32 engine accepts (1e4 ε₃₂ ≈ 1.2e-3 of the string's weight).
    let t0 = std::time::Instant::now();
    let g32 = run(
        &case,
        Some(&f),
        BackendChoice::Gpu,
        Precision::F32,
        &dir.join("gpu32"),
        false,
        &Default::default(),
    )
    .unwrap();
    let t_32 = t0.elapsed().as_secs_f64();
    common::summary_agrees_with_csv(&g32, &dir.join("gpu32"));
    assert_eq!(
        (g32.backend.as_str(), g32.precision.as_str()),
        ("gpu", "f32")
    );
    let g = read(&dir.join("gpu32"));
    let mut worst32 = [0.0f64; 4];
    for (rg, rc) in g.iter().zip(&c).skip(1) {
        for (n, &k) in cols.iter().enumerate() {
            if let (Ok(a), Ok(b)) = (rg[k].parse::<f64>(), rc[k].parse::<f64>()) {
                worst32[n] = worst32[n].max((a - b).abs() / b.abs().max(1e-12));
            }
        }
    }
    eprintln!(
        "64 variants, GPU f32 {t_32:.1} s ({} re-run on the CPU): relative error against the CPU f64 runs — neutral point {:.2e}, surface torque {:.2e}, stab1 side force {:.2e}, stab1 lateral {:.2e}",
        g32.solved_by_cpu, worst32[0], worst32[1], worst32[2], worst32[3]
    );
    assert_eq!(
        g32.solved_by_cpu, 0,
        "the f32 engine must solve every variant"
    );
    assert!(worst32.iter().all(|&w| w <= 1.2e-3), "{worst32:?}");
}

/// `holewall bench job` (issue 27): a user's Monte Carlo job (`cases/whirl_job.toml`, 4
/// variants, twice each), then the job of a variants file (2 variants, once), timed whole on
/// every path at hand — every variant solved where the
/// path says (the engine on the GPU paths, the CPU on the CPU path), the engine's phases
/// given where it ran and within the job's time, the tables and the last job's outputs
/// written; `--samples 0` is an input error (exit 2).
#[test]
fn the_job_bench_times_a_users_job_on_every_path() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let case = root.join("cases/whirl_job.toml");
    let out = common::scratch_dir("ensemble", "bench_job");
    let args = |samples: &str| {
        vec![
            "bench".to_string(),
            "job".into(),
            case.to_str().unwrap().into(),
            "--samples".into(),
            samples.into(),
            "--repeats".into(),
            "2".into(),
            "--out".into(),
            out.to_str().unwrap().into(),
            "--quiet".into(),
        ]
    };
    let run = |samples: &str| {
        let a = args(samples);
        common::holewall(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let (code, stdout, stderr) = run("4");
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("| CPU f64 | 2 |"), "{stdout}");
    let r: serde_json::Value = common::json(&out.join("job.json"));
    let paths = match common::gpu() {
        Some(ctx) if ctx.has_f64 => 3,
        Some(_) => 2,
        None => 1,
    };
    let runs = r["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2 * paths, "{r}");
    for run in runs {
        let wall = run["wall_s"].as_f64().unwrap();
        let inside = run["variant_runs_s"].as_f64().unwrap();
        assert!(wall >= inside && inside > 0.0, "{run}");
        assert_eq!(run["failed"], 0, "{run}");
        if run["path"] == "CPU f64" {
            assert_eq!(run["solved_by_cpu"], 4, "{run}");
            assert!(run["engine_seconds"].is_null(), "{run}");
        } else {
            assert_eq!(run["solved_by_engine"], 4, "{run}");
            let e = &run["engine_seconds"];
            let dynamics = e["dynamics"].as_f64().unwrap();
            assert!(dynamics > 0.0 && dynamics <= inside, "{run}");
            assert!(e["observing"].as_f64().unwrap() <= dynamics, "{run}");
        }
    }
    let medians = r["medians"].as_array().unwrap();
    assert_eq!(medians.len(), paths, "{r}");
    assert_eq!(medians[0]["path"], "CPU f64", "{r}");
    assert_eq!(medians[0]["speed_vs_cpu"], 1.0, "{r}");
    assert!(
        medians.iter().all(|m| m["job_s"].as_f64().unwrap() > 0.0),
        "{r}"
    );
    assert!(out.join("job.md").is_file());
    assert!(out.join("runs/cpu_f64/variants.csv").is_file());
    let (code, _, stderr) = run("0");
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("--samples") && stderr.contains("at least 1"),
        "{stderr}"
    );
    // The job of a variants file (its whirl maps, not the statistics), once per path.
    let file = out.join("v.csv");
    std::fs::write(&file, "rpm,wob,mu\n80 rpm,12 kN,0.15\n200 rpm,30 kN,0.4\n").unwrap();
    let with_file = |extra: &[&str]| {
        let mut a = vec![
            "bench",
            "job",
            case.to_str().unwrap(),
            "--variants",
            file.to_str().unwrap(),
            "--repeats",
            "1",
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ];
        a.extend_from_slice(extra);
        common::holewall(&a)
    };
    let (code, stdout, stderr) = with_file(&[]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("--variants"), "{stdout}");
    let r: serde_json::Value = common::json(&out.join("job.json"));
    assert!(
        r["variants_file"].as_str().unwrap().ends_with("v.csv"),
        "{r}"
    );
    let runs = r["runs"].as_array().unwrap();
    assert_eq!(runs.len(), paths, "{r}");
    assert!(runs.iter().all(|run| run["failed"] == 0), "{r}");
    assert!(out
        .join("runs/cpu_f64/whirl_map_stab1_mu0.15.png")
        .is_file());
    // A file and a draw at once: a usage error (exit 2).
    let (code, _, stderr) = with_file(&["--samples", "8"]);
    assert_eq!(code, 2, "{stderr}");
}
