//! Monte Carlo runs (`holewall ensemble --samples`): the shipped case on the CPU backend
//! and the GPU engine (P50/P90 within 1 %), the same seed giving the same bits, the
//! uncertain-input table's errors (file:line: key, exit 2, nothing written).

mod common;

use holewall::backend::{BackendChoice, Precision};
use holewall::cli::ensemble_cmd::monte_carlo;
use holewall::ensemble::job::run;
use holewall::ensemble::report::EnsembleSummary;
use holewall::ensemble::store::EnsembleOptions;
use holewall::uq::Sampling;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("holewall-mc-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn opts(mc: Option<holewall::uq::report::MonteCarlo>) -> EnsembleOptions {
    EnsembleOptions {
        monte_carlo: mc,
        ..Default::default()
    }
}

fn case() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/monte_carlo_two_stabilizers.toml")
}

fn mc_run(
    n: usize,
    seed: u64,
    backend: BackendChoice,
    precision: Precision,
    out: &std::path::Path,
) -> EnsembleSummary {
    let mc = monte_carlo(
        Some(n),
        seed,
        Sampling::Lhs,
        &[95.0],
        &["stab1_max_side_force_n=10000".to_string()],
        false,
    )
    .unwrap();
    run(&case(), None, backend, precision, out, false, &opts(mc)).unwrap()
}

#[test]
fn shipped_case_on_the_cpu_and_the_engine() {
    let n = 40;
    let cpu = mc_run(n, 1, BackendChoice::Cpu, Precision::F64, &tmp("cpu"));
    let u = cpu.uncertainty.as_ref().unwrap();
    assert_eq!((u.samples, u.failed, cpu.failed), (n, 0, 0));
    assert_eq!(
        u.inputs,
        vec!["mu", "wob", "k_e", "stab2.from_bit"],
        "in the order written"
    );
    for q in &u.qois {
        let s = q.stats.as_ref().unwrap();
        assert_eq!(s.n, n, "{}", q.name);
        assert!(s.p10 <= s.p50 && s.p50 <= s.p90, "{}", q.name);
        assert_eq!(s.percentiles.len(), 1);
        assert_eq!(q.sensitivity.len(), 4);
    }
    // Physics the sensitivities must show: the surface torque follows friction, the
    // neutral point follows the weight on bit.
    let top = |name: &str| {
        let q = u.qois.iter().find(|q| q.name == name).unwrap();
        q.sensitivity
            .iter()
            .max_by(|a, b| a.prcc.abs().total_cmp(&b.prcc.abs()))
            .unwrap()
            .clone()
    };
    let torque = top("max_surface_torque_nm");
    assert_eq!(torque.input, "mu");
    assert!(torque.prcc > 0.9, "{torque:?}");
    // The hook load falls one for one with the weight on bit.
    let hook = top("hook_load_n");
    assert_eq!(hook.input, "wob");
    assert!(hook.prcc < -0.9, "{hook:?}");
    let np = top("neutral_point_from_bit_m");
    assert_eq!(np.input, "wob");
    assert!(np.prcc > 0.9, "{np:?}");
    let side = u
        .qois
        .iter()
        .find(|q| q.name == "stab1_max_side_force_n")
        .unwrap();
    assert_eq!(side.stats.as_ref().unwrap().exceedance.len(), 1);
    for f in [
        "hist_stab1_max_side_force_n.png",
        "tornado_max_surface_torque_nm.png",
        "scatter_max_surface_torque_nm_vs_mu.png",
        "convergence_neutral_point_from_bit_m.png",
    ] {
        assert!(cpu.outputs.iter().any(|o| o == f), "{f} not written");
    }
    // The same seed: the same bits; another seed: other samples.
    let again = mc_run(n, 1, BackendChoice::Cpu, Precision::F64, &tmp("cpu2"));
    let stats = |s: &EnsembleSummary| serde_json::to_string(&s.uncertainty).unwrap();
    assert_eq!(stats(&cpu), stats(&again));
    let other = mc_run(n, 2, BackendChoice::Cpu, Precision::F64, &tmp("cpu3"));
    assert_ne!(stats(&cpu), stats(&other));
    // The GPU engine: P50 and P90 of every quantity within 1 % (f64); f32 reported.
    let Some(ctx) = common::gpu() else { return };
    let precisions: &[Precision] = if ctx.has_f64 {
        &[Precision::F64, Precision::F32]
    } else {
        &[Precision::F32]
    };
    let force_scale = holewall::solve::statics::reference_force(
        &holewall::case::load_case(&case()).unwrap().model,
    );
    for &p in precisions {
        let gpu = mc_run(n, 1, BackendChoice::Gpu, p, &tmp(&format!("gpu{p:?}")));
        let g = gpu.uncertainty.as_ref().unwrap();
        assert_eq!(gpu.solved_by_engine, n, "every sample solved by the engine");
        let mut worst: f64 = 0.0;
        for (a, b) in g.qois.iter().zip(&u.qois) {
            let (sa, sb) = (a.stats.as_ref().unwrap(), b.stats.as_ref().unwrap());
            let mut this: f64 = 0.0;
            // The bit's side force in f32 is a reaction: the difference of the internal and
            // external forces at the bit of the f32 equilibrium, whose residual the engine
            // accepts up to f32's floor (1e4 ε₃₂ of the force scale, checked in f64) — so
            // its error is bounded by that floor in newtons, stated in docs/validation.md.
            let reaction =
                p == Precision::F32 && a.name.starts_with("bit_") && a.name.ends_with("_force_n");
            for (x, y) in [(sa.p50, sb.p50), (sa.p90, sb.p90)] {
                // Relative to the quantity's spread or size, whichever is larger.
                let scale = if reaction {
                    100.0 * 1e4 * f32::EPSILON as f64 * force_scale
                } else {
                    sb.p90.abs().max(sb.p10.abs()).max(1e-300)
                };
                this = this.max((x - y).abs() / scale);
            }
            if reaction {
                // The check below is |error| ≤ 1 % of 100 floors: within one floor.
                eprintln!("  {p:?} {}: {:.2e} of f32's floor", a.name, 100.0 * this);
            } else {
                eprintln!("  {p:?} {}: {this:.2e}", a.name);
            }
            worst = worst.max(this);
        }
        eprintln!("GPU {p:?} vs CPU: P50/P90 of every quantity within {worst:.2e}");
        assert!(worst <= 0.01, "{p:?}: {worst:e}");
    }
}

#[test]
fn uncertain_table_errors_name_file_line_and_key() {
    let dir = tmp("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(case()).unwrap();
    let table_line = text
        .lines()
        .position(|l| l.starts_with("mu = { dist"))
        .unwrap()
        + 1;
    for (bad, needle) in [
        (
            "mu = { dist = \"gamma\", min = 0.2, max = 0.4 }",
            "unknown distribution",
        ),
        (
            "mu = { dist = \"uniform\", min = 0.4, max = 0.2 }",
            "below max",
        ),
        (
            "mu = { dist = \"uniform\", min = 0.2, max = 3.0 }",
            "out of range",
        ),
        ("mu = { dist = \"normal\", mean = 0.3 }", "needs sd"),
        (
            "mu = { dist = \"uniform\", min = 0.2, max = 0.4, sd = 1 }",
            "takes no sd",
        ),
        (
            "mu = { dist = \"discrete\", values = [0.1, 0.2], weights = [1] }",
            "1 weights for 2 values",
        ),
    ] {
        let bad_text = text.replace("mu = { dist = \"uniform\", min = 0.2, max = 0.4 }", bad);
        let path = dir.join("bad.toml");
        std::fs::write(&path, bad_text).unwrap();
        let out = dir.join("out");
        let mc = monte_carlo(Some(4), 1, Sampling::Random, &[], &[], false).unwrap();
        let e = run(
            &path,
            None,
            BackendChoice::Cpu,
            Precision::F64,
            &out,
            false,
            &opts(mc),
        )
        .unwrap_err();
        let msg = e.to_string();
        assert_eq!(e.exit_code(), 2, "{msg}");
        assert!(
            msg.contains(&format!("bad.toml:{table_line}: ensemble.uncertain.mu")),
            "{msg}"
        );
        assert!(msg.contains(needle), "{msg}");
        assert!(!out.exists());
    }
    // A normal law that reaches outside the key's range must be truncated.
    let wide = text.replace(
        "mu = { dist = \"uniform\", min = 0.2, max = 0.4 }",
        "mu = { dist = \"normal\", mean = 0.3, sd = 0.5 }",
    );
    let path = dir.join("wide.toml");
    std::fs::write(&path, wide).unwrap();
    let mc = monte_carlo(Some(50), 1, Sampling::Random, &[], &[], false).unwrap();
    let e = run(
        &path,
        None,
        BackendChoice::Cpu,
        Precision::F64,
        &dir.join("o"),
        false,
        &opts(mc),
    )
    .unwrap_err();
    assert!(e.to_string().contains("truncate"), "{e}");
    // Command-line errors.
    assert!(monte_carlo(None, 1, Sampling::Lhs, &[95.0], &[], false).is_err());
    assert!(monte_carlo(Some(10), 1, Sampling::Lhs, &[120.0], &[], false).is_err());
    assert!(monte_carlo(Some(10), 1, Sampling::Lhs, &[], &["x".into()], false).is_err());
    let mc = monte_carlo(Some(4), 1, Sampling::Lhs, &[], &["nope=1".into()], false).unwrap();
    let e = run(
        &case(),
        None,
        BackendChoice::Cpu,
        Precision::F64,
        &dir.join("o2"),
        false,
        &opts(mc),
    )
    .unwrap_err();
    assert!(e.to_string().contains("no quantity \"nope\""), "{e}");
}

#[test]
fn broomstick_of_the_shipped_case() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/broomstick.toml");
    let out = tmp("broom");
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
    assert_eq!((s.variants, s.failed), (54, 0));
    assert!(s.outputs.iter().any(|o| o == "broomstick.png"));
    // variants.csv: per depth, tripping out above rotating above tripping in (μ > 0), and
    // every hook load grows with depth.
    let csv = std::fs::read_to_string(out.join("variants.csv")).unwrap();
    let mut rdr = csv::Reader::from_reader(csv.as_bytes());
    let h = rdr.headers().unwrap().clone();
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    let (cd, cm, cmu, ch) = (col("depth"), col("mode"), col("mu"), col("hook_load_n"));
    let rows: Vec<(f64, String, f64, f64)> = rdr
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[cd].parse().unwrap(),
                r[cm].to_string(),
                r[cmu].parse().unwrap(),
                r[ch].parse().unwrap(),
            )
        })
        .collect();
    let hook = |d: f64, m: &str, mu: f64| {
        rows.iter()
            .find(|r| r.0 == d && r.1 == m && r.2 == mu)
            .unwrap_or_else(|| panic!("{d} {m} {mu}"))
            .3
    };
    for d in [600.0, 1000.0, 1500.0] {
        for mu in [0.15, 0.35] {
            let (i, r, o) = (
                hook(d, "tripping_in", mu),
                hook(d, "rotating", mu),
                hook(d, "tripping_out", mu),
            );
            assert!(o > r && r > i, "depth {d}, mu {mu}: {o} {r} {i}");
        }
        assert!(hook(d, "tripping_out", 0.35) > hook(d, "tripping_out", 0.15));
    }
    assert!(hook(1500.0, "rotating", 0.25) > hook(600.0, "rotating", 0.25));
    // A depth variant is the case with its depth written in.
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("total_md = \"1500 m\"", "total_md = \"1000 m\"")
        .replace("mode = \"rotating\"", "mode = \"tripping_out\"")
        .replace("rpm = \"120 rpm\"", "");
    let single = holewall::case::parse_case(&path, &text).unwrap();
    let via = hook(1000.0, "tripping_out", 0.25);
    // The variant's model is the case with its depth and mode written in (same mesh, same
    // nodes), and its result is the ensemble's row.
    let case = holewall::case::load_case(&path).unwrap();
    let v = holewall::ensemble::variants_from_csv_text(
        "v.csv",
        "depth,mode,mu\n1000 m,tripping_out,0.25\n",
    )
    .unwrap();
    let m = holewall::ensemble::apply(&case, &v[0]).unwrap();
    assert_eq!(m.nodes.len(), single.model.nodes.len());
    assert!(m
        .nodes
        .iter()
        .zip(&single.model.nodes)
        .all(|(a, b)| a.position == b.position));
    assert_eq!(m.axial_speed, single.model.axial_speed);
    assert_eq!(m.nodes.last().unwrap().md, 1000.0);
    let sol2 = holewall::solve::statics::solve_static(&m, &Default::default()).unwrap();
    let r = holewall::ensemble::qoi::static_result(&case, "v", &m, &sol2);
    assert_eq!(r.hook_load_n.unwrap(), via);
    // The grid's keys in the order written: the first varies slowest.
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "depth = [\"600 m\", \"800 m\", \"1000 m\", \"1200 m\", \"1400 m\", \"1500 m\"]\nmode = [\"tripping_in\", \"tripping_out\", \"rotating\"]\nmu = [0.15, 0.25, 0.35]",
        "mu = [0.15, 0.25]\ndepth = [\"600 m\", \"800 m\"]",
    );
    let grid_case = holewall::case::parse_case(&path, &text).unwrap();
    let grid = &grid_case.ensemble.as_ref().unwrap().grid;
    assert_eq!(
        (grid[0].0.name.as_str(), grid[1].0.name.as_str()),
        ("mu", "depth")
    );
    let v = holewall::ensemble::variants_from_grid(grid);
    assert_eq!(
        (v[0].overrides[0].1.si(), v[1].overrides[0].1.si()),
        (0.15, 0.15),
        "mu slowest"
    );
    assert_eq!(
        (v[0].overrides[1].1.si(), v[1].overrides[1].1.si()),
        (600.0, 800.0)
    );
    // Bad modes and depths are refused with file, line and key.
    let e = holewall::ensemble::variants_from_csv_text("v.csv", "mode\nspinning\n").unwrap_err();
    assert_eq!((e.line, e.key.as_str()), (2, "mode"));
    let e = holewall::ensemble::variants_from_csv_text("v.csv", "depth\n-5 m\n").unwrap_err();
    assert_eq!((e.line, e.key.as_str()), (2, "depth"));
    let deep = holewall::ensemble::variants_from_csv_text("v.csv", "depth\n1600 m\n").unwrap();
    assert!(
        holewall::ensemble::apply(&case, &deep[0]).is_err(),
        "below the hole"
    );
}

#[test]
fn sobol_indices_of_the_shipped_case() {
    // 32 base points × (4 inputs + 2) = 192 runs: friction drives the surface torque, the
    // weight on bit the hook load — by their total indices too.
    let mc = monte_carlo(Some(32), 1, Sampling::Sobol, &[], &[], true).unwrap();
    let out = tmp("sobol");
    let s = run(
        &case(),
        None,
        BackendChoice::Cpu,
        Precision::F64,
        &out,
        false,
        &opts(mc),
    )
    .unwrap();
    assert_eq!(s.variants, 192);
    let u = s.uncertainty.unwrap();
    assert_eq!(u.base_samples, 64);
    let top = |name: &str| {
        let q = u.qois.iter().find(|q| q.name == name).unwrap();
        let sob = q.sobol.as_ref().unwrap();
        for x in sob {
            eprintln!(
                "{name}: {} S {:.3} S_T {:.3} [{:.3}, {:.3}]",
                x.input, x.first, x.total, x.total_ci95.0, x.total_ci95.1
            );
        }
        sob.iter()
            .max_by(|a, b| a.total.total_cmp(&b.total))
            .unwrap()
            .input
            .clone()
    };
    assert_eq!(top("max_surface_torque_nm"), "mu");
    assert_eq!(top("hook_load_n"), "wob");
    assert!(s.outputs.iter().any(|o| o == "sobol_hook_load_n.png"));
    // --sobol-indices without Sobol sampling is refused.
    assert!(monte_carlo(Some(32), 1, Sampling::Lhs, &[], &[], true).is_err());
}

#[test]
fn rank_correlated_inputs() {
    // ensemble.correlation: friction and WOB correlated at 0.6 (Iman–Conover on the Latin
    // hypercube); the drawn inputs show it, and a bad table is refused with file:line: key.
    let text = std::fs::read_to_string(case()).unwrap().replace(
        "analysis = \"static\"",
        "analysis = \"static\"\ncorrelation = [[\"mu\", \"wob\", 0.6]]",
    );
    let dir = tmp("corr");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("corr.toml");
    std::fs::write(&path, &text).unwrap();
    let case = holewall::case::load_case(&path).unwrap();
    let settings = case.ensemble.unwrap();
    let variants = holewall::ensemble::sample_variants(
        &settings.uncertain,
        400,
        1,
        Sampling::Lhs,
        false,
        settings.correlation.as_ref(),
    )
    .unwrap();
    let col = |name: &str| -> Vec<f64> {
        variants
            .iter()
            .map(|v| {
                v.overrides
                    .iter()
                    .find(|(k, _)| k.name == name)
                    .unwrap()
                    .1
                    .si()
            })
            .collect()
    };
    let rho = holewall::uq::sensitivity::spearman(&col("mu"), &col("wob"));
    let other = holewall::uq::sensitivity::spearman(&col("mu"), &col("k_e"));
    eprintln!("rank correlation mu–wob {rho:.3} (asked 0.6), mu–k_e {other:.3}");
    assert!((rho - 0.6).abs() < 0.07 && other.abs() < 0.1);
    assert!(holewall::ensemble::sample_variants(
        &settings.uncertain,
        64,
        1,
        Sampling::Sobol,
        false,
        settings.correlation.as_ref()
    )
    .is_err());
    for (bad, needle) in [
        ("[[\"mu\", \"nope\", 0.5]]", "not in [ensemble.uncertain]"),
        ("[[\"mu\", \"wob\", 1.2]]", "outside"),
        (
            "[[\"mu\", \"wob\", 0.9], [\"mu\", \"k_e\", 0.9], [\"wob\", \"k_e\", -0.9]]",
            "not positive definite",
        ),
    ] {
        let t = std::fs::read_to_string(case_path()).unwrap().replace(
            "analysis = \"static\"",
            &format!("analysis = \"static\"\ncorrelation = {bad}"),
        );
        std::fs::write(&path, t).unwrap();
        let e = holewall::case::load_case(&path).unwrap_err();
        assert!(
            e.to_string().contains("ensemble.correlation") && e.to_string().contains(needle),
            "{e}"
        );
    }
}

fn case_path() -> std::path::PathBuf {
    case()
}

#[test]
fn candidate_stabilizer_layouts() {
    // Two candidate layouts of both stabilizers, drawn as a discrete input: each sample runs
    // with one layout's places, applied together.
    let text = std::fs::read_to_string(case()).unwrap().replace(
        "analysis = \"static\"",
        "analysis = \"static\"\nlayouts = [{ \"stab1.from_bit\" = \"1.8 m\", \"stab2.from_bit\" = \"14 m\" }, { \"stab1.from_bit\" = \"4.8 m\", \"stab2.from_bit\" = \"20 m\" }]",
    ).replace(
        "\"stab2.from_bit\" = { dist = \"discrete\", values = [\"10 m\", \"14 m\", \"20 m\"], weights = [1, 2, 1] }",
        "layout = { dist = \"discrete\", values = [1, 2] }",
    );
    let dir = tmp("layouts");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("layouts.toml");
    std::fs::write(&path, &text).unwrap();
    let mc = monte_carlo(Some(16), 1, Sampling::Lhs, &[], &[], false).unwrap();
    let out = dir.join("out");
    let s = run(
        &path,
        None,
        BackendChoice::Cpu,
        Precision::F64,
        &out,
        false,
        &opts(mc),
    )
    .unwrap();
    assert_eq!((s.variants, s.failed), (16, 0));
    let csv = std::fs::read_to_string(out.join("variants.csv")).unwrap();
    let mut rdr = csv::Reader::from_reader(csv.as_bytes());
    let h = rdr.headers().unwrap().clone();
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    let (cl, c1, c2) = (
        col("layout"),
        col("ran.stab1.from_bit_m"),
        col("ran.stab2.from_bit_m"),
    );
    let mut seen = std::collections::BTreeSet::new();
    for r in rdr.records() {
        let r = r.unwrap();
        let (l, s1, s2): (f64, f64, f64) = (
            r[cl].parse().unwrap(),
            r[c1].parse().unwrap(),
            r[c2].parse().unwrap(),
        );
        // Layout 1 puts stab1 near 1.8 m and stab2 near 14 m; layout 2 near 4.8 and 20 m
        // (to the nearest node of the 1.5 m BHA mesh).
        let (e1, e2) = if l == 1.0 { (1.8, 14.0) } else { (4.8, 20.0) };
        assert!(
            (s1 - e1).abs() <= 0.8 && (s2 - e2).abs() <= 0.8,
            "layout {l}: {s1} {s2}"
        );
        seen.insert(l as i64);
    }
    assert_eq!(seen.len(), 2, "both layouts drawn");
    // A layout number beyond the list, and a layout setting another key, are refused.
    let case = holewall::case::load_case(&path).unwrap();
    let v = holewall::ensemble::variants_from_csv_text("v.csv", "layout\n3\n").unwrap();
    assert!(holewall::ensemble::apply(&case, &v[0])
        .unwrap_err()
        .to_string()
        .contains("layout 3"));
    let bad = text.replace("\"stab1.from_bit\" = \"1.8 m\"", "mu = 0.3");
    std::fs::write(&path, bad).unwrap();
    let e = holewall::case::load_case(&path).unwrap_err();
    assert!(e.to_string().contains("ensemble.layouts[1]"), "{e}");
}

/// Samples are SI numbers checked against each key's range with no text in between (issue
/// 24): an uncertain rpm was refused ("a bare number is ambiguous for a rotary speed") and
/// an uncertain bend was read as degrees a second time (2° became 0.035°).
#[test]
fn sampled_rpm_and_bend_stay_in_si() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/bent_housing.toml"),
    )
    .unwrap();
    let dir = tmp("si-samples");
    std::fs::create_dir_all(&dir).unwrap();
    let text = format!(
        "{base}\n[ensemble]\nanalysis = \"static\"\n[ensemble.uncertain]\n\
         rpm = {{ dist = \"uniform\", min = \"80 rpm\", max = \"120 rpm\" }}\n\
         bend = {{ dist = \"uniform\", min = \"1 deg\", max = \"2 deg\" }}\n"
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).unwrap();
    let case = holewall::case::load_case(&path).unwrap();
    let uncertain = &case.ensemble.as_ref().unwrap().uncertain;
    let variants =
        holewall::ensemble::sample_variants(uncertain, 64, 7, Sampling::Lhs, false, None).unwrap();
    let rpm = std::f64::consts::TAU / 60.0;
    for v in &variants {
        for (key, value) in &v.overrides {
            let value = &value.si();
            match key.name.as_str() {
                "rpm" => assert!((80.0 * rpm..=120.0 * rpm).contains(value), "{value}"),
                "bend" => assert!(
                    (1f64.to_radians()..=2f64.to_radians()).contains(value),
                    "{value} rad"
                ),
                other => panic!("{other}"),
            }
        }
        holewall::ensemble::apply(&case, v).unwrap();
    }
}

/// An ensemble of a string held by the wall at its stabilizer only (`contact.sites =
/// "stabilizers"`) in a straight hole 1° off vertical: its 870 m of pipe would sag metres
/// through the wall (`diagnose::tests`), so each variant's solve adds contact where the
/// string meets the wall (`profile::solve_in_hole`), with the variant's own friction. No
/// variant is left outside the hole; hook load and torque are those of the same ensemble
/// with contact at every node, within 2 %, and the torque follows each variant's μ.
#[test]
fn variants_are_held_in_the_hole_with_their_own_friction() {
    let dir = tmp("outside");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("s.csv"),
        "md, inclination, azimuth\n0, 1, 0\n1000, 1, 0\n",
    )
    .unwrap();
    let mut runs = Vec::new();
    for sites in ["stabilizers", "all_nodes"] {
        let text = format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"s.csv\"\ntotal_md = \"1000 m\"\n\
             [[hole]]\nbottom_md = \"1000 m\"\ndiameter = \"6.125 in\"\nfriction = 0.25\n\
             [mud]\ndensity = \"1.278 sg\"\n\
             [[string]]\nkind = \"bit\"\nlength = \"0.3 m\"\nod = \"5 in\"\nid = \"2.25 in\"\n\
             [[string]]\nkind = \"stabilizer\"\nlength = \"1.5 m\"\nod = \"5 in\"\nid = \"2.25 in\"\nblade_diameter = \"6 in\"\n\
             [[string]]\nkind = \"collar\"\nlength = \"126.2 m\"\nod = \"5 in\"\nid = \"2.25 in\"\n\
             [[string]]\nkind = \"drill_pipe\"\nlength = \"872 m\"\nod = \"4 in\"\nid = \"3.34 in\"\n\
             [operation]\nmode = \"rotating\"\nrpm = \"120 rpm\"\nweight_on_bit = \"15 kN\"\n\
             [contact]\nsites = \"{sites}\"\n[mesh]\nelement_length = \"10 m\"\nbha_element_length = \"0.5 m\"\n\
             [ensemble]\nanalysis = \"static\"\n[ensemble.grid]\nmu = [0.2, 0.4]\n"
        );
        let case = dir.join(format!("{sites}.toml"));
        std::fs::write(&case, text).unwrap();
        let out = dir.join(sites);
        let s = run(
            &case,
            None,
            BackendChoice::Cpu,
            Precision::F64,
            &out,
            false,
            &opts(None),
        )
        .unwrap();
        assert_eq!((s.variants, s.failed, s.outside_hole), (2, 0, 0), "{sites}");
        assert!(!s.notices().iter().any(|n| n.contains("outside the hole")));
        let mut csv = csv::Reader::from_path(out.join("variants.csv")).unwrap();
        let headers = csv.headers().unwrap().clone();
        let col = |name: &str| headers.iter().position(|h| h == name).unwrap();
        let (outside, hook, torque) = (
            col("outside_hole_m"),
            col("hook_load_n"),
            col("max_surface_torque_nm"),
        );
        let rows: Vec<(f64, f64)> = csv
            .records()
            .map(|row| {
                let row = row.unwrap();
                assert_eq!(row[outside].parse::<f64>().unwrap(), 0.0, "{sites}");
                (row[hook].parse().unwrap(), row[torque].parse().unwrap())
            })
            .collect();
        assert_eq!(rows.len(), 2);
        eprintln!("{sites}: (hook load N, torque N·m) at mu 0.2, 0.4: {rows:?}");
        runs.push(rows);
    }
    for (held, every) in runs[0].iter().zip(&runs[1]) {
        assert!(
            (held.0 / every.0 - 1.0).abs() < 0.02,
            "{held:?} vs {every:?}"
        );
        assert!(
            (held.1 / every.1 - 1.0).abs() < 0.02,
            "{held:?} vs {every:?}"
        );
    }
    // Twice the friction, about twice the torque: μ reached the sites added at the wall.
    let ratio = runs[0][1].1 / runs[0][0].1;
    assert!((1.8..2.2).contains(&ratio), "torque ratio {ratio}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `holewall bench mc-corpus` on a sample of corpus wells (the benchmark's CI sample):
/// friction, wall stiffness and WOB uncertain, 4 Latin-hypercube variants a well, on the
/// CPU backend and the GPU engine in f64 and f32. Every variant solves on every path, the
/// engine solves them itself (no CPU re-run), and each variant's hook load, surface torque
/// and largest side force per length agree with the CPU's: f64 to 1e-9, f32 to 1e-4.
/// Drawn seeds 3676 (build and hold, drilling, 389 nodes), 3780 (build and hold, drilling,
/// 365) and 3825 (horizontal, drilling, 30 m elements).
#[test]
fn monte_carlo_on_corpus_wells_agrees_across_paths() {
    if common::gpu().is_none() {
        return;
    }
    let out = common::scratch_dir("mc-corpus", "sample");
    let o = out.to_str().unwrap();
    let (code, stdout, stderr) = common::holewall(&[
        "bench",
        "mc-corpus",
        "--seeds",
        "3676,3780,3825",
        "--samples",
        "4",
        "--quiet",
        "--out",
        o,
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let s = common::json(&out.join("summary.json"));
    assert_eq!(s["run"], 3, "{s}");
    for (path, tolerance) in [("cpu_f64", 0.0), ("gpu_f64", 1e-9), ("gpu_f32", 1e-4)] {
        let p = &s["paths"][path];
        assert_eq!(p["variants"], 12, "{path}: {p}");
        assert_eq!(p["solved"], 12, "{path}: {p}");
        assert_eq!(p["solved_here_only"], 0, "{path}: {p}");
        if path != "cpu_f64" {
            assert_eq!(p["by_engine"], 12, "{path}: {p}");
        }
        for q in ["hook_load_rel", "torque_rel", "side_force_rel"] {
            let worst = p[q]["worst"].as_f64().unwrap();
            assert!(
                worst <= tolerance,
                "{path} {q}: {worst:e} over {tolerance:e}: {p}"
            );
        }
    }
    // The inputs were drawn in their ranges, and every hook load is in the CSV.
    let text = std::fs::read_to_string(out.join("mc_variants.csv")).unwrap();
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let header = rows.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let mut n = 0;
    for r in rows.records() {
        let r = r.unwrap();
        let mu: f64 = r[col("mu")].parse().unwrap();
        assert!((0.15..=0.40).contains(&mu), "mu {mu}");
        for p in ["cpu_f64", "gpu_f64", "gpu_f32"] {
            let h: f64 = r[col(&format!("{p}_hook_load_n"))].parse().unwrap();
            assert!(h.is_finite(), "{p}: {h}");
        }
        n += 1;
    }
    assert_eq!(n, 12);
    assert!(out.join("mc_corpus_agreement.png").is_file());
}
