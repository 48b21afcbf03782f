//! A string that stops on its way into the hole (issue 22): corpus well 242 (horizontal,
//! 2,455 m, 9⅞ in hole, tripping in, friction 0.21 cased) meshed with 5 m elements (1 m in
//! the BHA), its open-hole friction raised from 0.368 to 0.45. Its load path finds no
//! equilibrium at the full friction (best 1.3e-4 of the force scale), and relaxations up
//! from its last equilibrium in steps of 1/8 bracket where the string stops (λ 0.75 to
//! 0.875 since stop 92; 0.719 to 0.8125 when they halved the interval). At the corpus's 0.368
//! the relaxation to the full loads stalls at 8.4e-7 and settles there since stop 76
//! (`relax_stall_tolerance`): an equilibrium pushed with 212 kN from the surface, which the
//! lock-up warning calls one the string does not reach by being run in. The solve then gives the
//! string where it stands — the equilibrium at the bracket's lower end — and `holewall
//! static` writes its outputs for it before it fails; an ensemble's variant that stops gives
//! the load factor and its string there (hook load, surface torque, largest side force),
//! on the CPU and on the engine; a solved variant the surface pushes is named. About 2 min
//! on 2 cores (the tests run side by side; the engine's, on the twin, is the longest).

mod common;

use std::path::PathBuf;

/// Corpus well 242 with 5 m elements and an open-hole friction of 0.45, in a scratch folder
/// `tag`.
fn lock_up_case(tag: &str) -> PathBuf {
    lock_up_case_with(tag, "5 m", "1 m", "0.45")
}

/// Corpus well 242 with `element` long elements (`bha` in the BHA) and an open-hole
/// friction of `mu`, in a scratch folder `tag`.
fn lock_up_case_with(tag: &str, element: &str, bha: &str, mu: &str) -> PathBuf {
    let dir = common::scratch_dir("lock-up", tag);
    let well = holewall::corpus::write_well(242, &dir).unwrap();
    let text = std::fs::read_to_string(&well.case_path).unwrap();
    assert!(
        text.contains("\nfriction = 0.368\n"),
        "the corpus's open hole"
    );
    let text: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with("element_length") {
                format!("element_length = \"{element}\"")
            } else if l.starts_with("bha_element_length") {
                format!("bha_element_length = \"{bha}\"")
            } else if l == "friction = 0.368" {
                format!("friction = {mu}")
            } else {
                l.to_string()
            }
        })
        .collect();
    std::fs::write(&well.case_path, text.join("\n")).unwrap();
    well.case_path
}

/// The CPU solve of [`lock_up_case`] (the case as the solve leaves it, with the contact
/// sites it added; the failure; where the string stands), once for the tests that read it.
fn stops_on_the_cpu() -> &'static (
    holewall::case::Case,
    holewall::error::Error,
    holewall::solve::statics::Stopped,
) {
    static SOLVED: std::sync::OnceLock<(
        holewall::case::Case,
        holewall::error::Error,
        holewall::solve::statics::Stopped,
    )> = std::sync::OnceLock::new();
    SOLVED.get_or_init(|| {
        let path = lock_up_case("library");
        let mut case = holewall::case::load_case(&path).unwrap();
        let options = case.settings().statics();
        let (e, stopped) = holewall::profile::solve_or_stop(&mut case, options, false)
            .expect_err("the string stops on its way in");
        (case, e, *stopped.expect("where it stands"))
    })
}

#[test]
fn a_string_that_stops_on_its_way_in_is_given_where_it_stands() {
    let (case, e, st) = stops_on_the_cpu();
    let options = case.settings().statics();
    let solution = holewall::solve::statics::stopped_solution(st);
    eprintln!(
        "stops between λ = {} and {}; hook load {:.1} kN",
        st.lambda,
        st.none_at,
        -solution.top_reaction[2] / 1e3
    );
    // The bracket, as the message names it.
    assert!(st.lambda > 0.5 && st.lambda < 1.0, "{}", st.lambda);
    assert!(st.none_at > st.lambda && st.none_at - st.lambda <= 0.125 + 1e-12);
    let message = e.to_string();
    assert!(
        message.contains(&format!(
            "{} λ = {:.4} and none at λ = {:.4}",
            holewall::solve::continuation::LOCK_FOUND,
            st.lambda,
            st.none_at
        )),
        "{message}"
    );
    // An equilibrium of the model at those loads (a relaxation settles within what a Newton
    // solve accepts at its rounding floor), and far from one at the operation's full
    // friction.
    let at = holewall::solve::statics::residual_measure_at(&st.model, &solution.state);
    let floor = holewall::solve::continuation::relax_stall_tolerance(&options, false);
    assert!(at <= floor, "{at:e}");
    let full = holewall::solve::statics::residual_measure_at(&case.model, &solution.state);
    assert!(
        full > 1e3 * at.max(options.tolerance),
        "{full:e} against {at:e}"
    );
    // The sites' friction is the case's × λ.
    for (a, b) in st.model.sites.iter().zip(&case.model.sites) {
        assert!((a.params.mu_l - st.lambda * b.params.mu_l).abs() <= 1e-12 * b.params.mu_l);
    }
    // Pushed from the surface where it stands, and an independent check that this load
    // locks the string up: the soft string carrying Mitchell's buckled wall force runs away
    // from a friction factor near the FE's.
    let hook = solution.top_reaction[2];
    assert!(hook > 0.0, "pushed: top reaction {hook} N upward is a pull");
    let soft = holewall::diagnose::lock_up_fraction(case).expect("the soft string locks up");
    assert!(
        (soft - st.lambda).abs() < 0.2,
        "soft string {soft}, FE {}",
        st.lambda
    );
}

#[test]
fn the_static_command_writes_the_string_where_it_stops_and_fails() {
    let path = lock_up_case("command");
    let out = path.parent().unwrap().join("out");
    let (code, _, stderr) = common::holewall(&[
        "static",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        path.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("the string where it stops"), "{stderr}");
    let summary: serde_json::Value = common::json(&out.join("summary.json"));
    let stopped = &summary["stopped"];
    let lambda = stopped["load_factor"].as_f64().unwrap();
    assert!(lambda > 0.5 && lambda < 1.0, "{stopped}");
    assert!(stopped["none_at"].as_f64().unwrap() > lambda);
    assert!(stopped["failure"].as_str().unwrap().contains(&format!(
        "{} λ = {lambda:.4}",
        holewall::solve::continuation::LOCK_FOUND
    )));
    assert!(summary["title"]
        .as_str()
        .unwrap()
        .contains("where it stops"));
    assert!(summary["hook_load_n"].as_f64().unwrap() < 0.0, "pushed");
    let profile = std::fs::read_to_string(out.join("profile.csv")).unwrap();
    assert!(profile.lines().count() > 400, "a row per node");
    for plot in ["axial_force.png", "side_force.png"] {
        assert!(out.join(plot).is_file(), "{plot}");
    }
}

#[test]
fn an_ensemble_variant_that_stops_says_where() {
    let path = lock_up_case("ensemble");
    // The case's open-hole friction (0.45) stops the string; 0.2 lets it in.
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push_str(
        "\n[ensemble]\nanalysis = \"static\"\n[ensemble.grid]\n\"mu.open\" = [0.2, 0.45]\n",
    );
    std::fs::write(&path, text).unwrap();
    let out = path.parent().unwrap().join("out");
    let s = common::ensemble_on_cpu(&path, None, &out);
    assert_eq!((s.variants, s.failed, s.stopped), (2, 1, 1), "{s:?}");
    assert!(s.notices().iter().any(|n| n.contains("stop on their way")
        && n.contains("1 of them stand pushed from the surface")));
    assert_eq!(s.stopped_pushed, 1);
    // How far each variant's loads get, against the friction: drawn where one stops.
    assert!(
        s.outputs.iter().any(|o| o == "loads_reached.png"),
        "{:?}",
        s.outputs
    );
    assert!(out.join("loads_reached.png").is_file());
    let mut csv = csv::Reader::from_path(out.join("variants.csv")).unwrap();
    let headers = csv.headers().unwrap().clone();
    let col = |name: &str| headers.iter().position(|h| h == name).unwrap();
    let (status, stopped, cuts) = (col("status"), col("stopped_load_factor"), col("step_cuts"));
    let rows: Vec<(String, String, String)> = csv
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[status].to_string(),
                r[stopped].to_string(),
                r[cuts].to_string(),
            )
        })
        .collect();
    // The first converges on its load steps. (Until stop 70 its last step stalled and a
    // relaxation ended at 1.8e-9 of the force scale, the rounding floor of positions kept
    // from the surface: a step cut. The hook load is the same to every digit.)
    assert_eq!(
        rows[0],
        ("converged".into(), String::new(), "0".into()),
        "{rows:?}"
    );
    assert_eq!((s.converged, s.step_cut), (1, 0));
    assert_eq!(rows[1].0, "failed");
    let lambda: f64 = rows[1].1.parse().unwrap();
    assert!(lambda > 0.5 && lambda < 1.0, "{rows:?}");
    // The string where it stands: the variant's solve is the case's, so its bracket and
    // hook load are the plain solve's to every digit; tripping in, no torque; the side
    // force the plain solve's largest per length, where it acts.
    let (_, _, st) = stops_on_the_cpu();
    assert_eq!(lambda, st.lambda);
    let stands = |name: &str| common::variants_column(&out, name)[1];
    let hook = holewall::profile::stopped_hook_load(st);
    assert_eq!(stands("stopped_hook_load_n"), hook);
    assert!(hook < 0.0, "pushed: hook load {hook} N");
    let solution = holewall::solve::statics::stopped_solution(st);
    let torque = holewall::profile::fe_rows(&st.model, &solution).2;
    assert_eq!(stands("stopped_surface_torque_nm"), torque);
    // Tripping in, not rotating: the torque is the regularised friction's rounding.
    assert!(torque.abs() < 1.0, "{torque} N·m");
    let (largest, md) = st
        .model
        .sites
        .iter()
        .zip(&solution.contact)
        .map(|(site, c)| {
            let node = site.node;
            (
                c.1.max(0.0) / st.model.tributary_length(node),
                st.model.nodes[node].md,
            )
        })
        .fold((0.0, f64::NAN), |m, x| if x.0 > m.0 { x } else { m });
    assert!(largest > 0.0);
    assert_eq!(stands("stopped_max_side_force_per_length_n_per_m"), largest);
    assert_eq!(stands("stopped_max_side_force_md_m"), md);
    // The converged variant has none of them.
    assert!(common::variants_column(&out, "stopped_hook_load_n")[0].is_nan());
}

/// The engine runs the CPU's load path, bracket and all: the well above meshed coarser (10 m
/// elements, 2 m in the BHA) with open-hole friction 0.2 and 0.7, an ensemble through the
/// engine on its twin (the kernels' CPU twins, f64; the GPU's runner,
/// `ensemble::runner::run_static_engine`). At 0.7 the string stops on its way in, and the
/// engine's path says where (`EngineResult::stops`), as the CPU solve's does: the CPU tries
/// the full loads once more without a bracket of its own, fails too, and the variant fails
/// with the engine's `stopped_load_factor` and its string there (`stands`).
#[test]
fn the_engine_says_where_the_string_stops_as_the_cpu_does() {
    use holewall::ensemble::qoi::{SolvedBy, Status};
    let path = lock_up_case_with("engine", "10 m", "2 m", "0.7");
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push_str(
        "\n[ensemble]\nanalysis = \"static\"\n[ensemble.grid]\n\"mu.open\" = [0.2, 0.7]\n",
    );
    std::fs::write(&path, text).unwrap();
    let mut case = holewall::case::load_case(&path).unwrap();
    let variants = holewall::ensemble::case_variants(&case, None)
        .unwrap()
        .expect("a grid");
    let bar = indicatif::ProgressBar::hidden();
    let results = holewall::ensemble::runner::run_static_engine::<f64, _>(
        &case,
        &variants,
        &holewall::engine::TwinPath,
        &bar,
    )
    .unwrap()
    .expect("the engine runs this ensemble");
    assert_eq!(
        results[0].status,
        Status::Converged,
        "{}",
        results[0].reason
    );
    assert_eq!(results[0].solved_by, SolvedBy::Engine);
    let stops = &results[1];
    assert_eq!(
        (stops.status, stops.solved_by),
        (Status::Failed, SolvedBy::Engine),
        "{}",
        stops.reason
    );
    // The CPU tried the full loads once more without a bracket of its own and failed too.
    assert!(
        !stops.reason.contains("re-run on the CPU"),
        "{}",
        stops.reason
    );
    assert!(
        stops
            .reason
            .contains("without a bracket of its own, it failed there too"),
        "{}",
        stops.reason
    );
    let lo = stops.string.stopped_load_factor.expect("where it stops");
    assert!(
        stops.reason.contains(&format!(
            "{} λ = {lo:.4} and none at λ = ",
            holewall::solve::continuation::LOCK_FOUND
        )),
        "{}",
        stops.reason
    );
    assert!(lo > 0.0 && lo < 1.0, "{lo}");
    // The CPU solve of the case at 0.7: the same bracket, or one beside it (the two paths
    // round apart).
    let options = case.settings().statics();
    let (_, stopped) = holewall::profile::solve_or_stop(&mut case, options, false)
        .expect_err("the string stops on the CPU too");
    let st = stopped.expect("where it stands");
    eprintln!(
        "engine's twin: stops above λ {lo}; CPU: λ {} to {}",
        st.lambda, st.none_at
    );
    assert!(
        (st.lambda - lo).abs() <= 0.125 + 1e-12,
        "{} against {lo}",
        st.lambda
    );
    // Where the engine's string stands (the equilibrium it kept at the bracket's lower
    // end): where the two brackets meet, its hook load is the CPU's to the spread of a
    // relaxed string's equilibria between two paths that round apart (up to 8 % on the
    // corpora, `diagnose::relaxed_warning`; measured here: −2,802.5 kN against −2,779.2 kN,
    // 0.8 %, both at λ = 0.875). Pushed with 2.8 MN, it stands far past the weight
    // indicator's lock-up.
    let stands = stops
        .string
        .stands
        .expect("the engine's string where it stops");
    let cpu = holewall::profile::stopped_hook_load(&st);
    eprintln!(
        "hook load where it stands: engine {:.3} kN at λ {lo}, CPU {:.3} kN at λ {}",
        stands.hook_load_n / 1e3,
        cpu / 1e3,
        st.lambda
    );
    assert!(stands.hook_load_n < 0.0 && cpu < 0.0, "pushed");
    if st.lambda == lo {
        assert!(
            (stands.hook_load_n - cpu).abs() <= 0.03 * cpu.abs(),
            "{} against {cpu}",
            stands.hook_load_n
        );
    }
    assert!(stands.max_side_force_per_length_n_per_m > 0.0);
}

/// A solved variant the surface pushes (hook load below zero: past the weight indicator's
/// lock-up) is counted and warned of, as the corpus names such wells: corpus well 2256
/// (horizontal, 1,301 m, tripping in, 20 m elements) with open-hole friction 0.1 hangs from
/// the hook (78.2 kN) and with its own 0.264 is pushed with 9.7 kN. Under a second.
#[test]
fn an_ensemble_names_the_variants_the_surface_pushes() {
    let dir = common::scratch_dir("lock-up", "pushed");
    let well = holewall::corpus::write_well(2256, &dir).unwrap();
    let mut text = std::fs::read_to_string(&well.case_path).unwrap();
    assert!(
        text.contains("\nfriction = 0.264\n"),
        "the corpus's open hole"
    );
    text.push_str(
        "\n[ensemble]\nanalysis = \"static\"\n[ensemble.grid]\n\"mu.open\" = [0.1, 0.264]\n",
    );
    std::fs::write(&well.case_path, text).unwrap();
    let out = dir.join("out");
    let s = common::ensemble_on_cpu(&well.case_path, None, &out);
    assert_eq!((s.converged, s.stopped, s.pushed), (2, 0, 1), "{s:?}");
    let hook = common::variants_column(&out, "hook_load_n");
    assert!(hook[0] > 0.0 && hook[1] < 0.0, "{hook:?}");
    assert!(
        s.notices()
            .iter()
            .any(|n| n.contains("1 of 2 variants solved pushed from the surface")),
        "{:?}",
        s.notices()
    );
}

/// A Monte Carlo run says how likely the string stops, and how likely it needs a push:
/// the well above at 15 m elements (3 m in the BHA), its open-hole friction uniform on
/// 0.1–0.9, eight Latin-hypercube samples (seed 1). One stops (μ 0.885, at λ 0.875); five of
/// the seven solved are pushed from the surface; the proportions carry Wilson intervals,
/// and the loads reached are drawn against the friction. About 5 s.
#[test]
fn a_monte_carlo_run_gives_the_chance_the_string_stops() {
    use holewall::backend::BackendChoice;
    let path = lock_up_case_with("monte-carlo", "15 m", "3 m", "0.368");
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push_str(
        "\n[ensemble]\nanalysis = \"static\"\n[ensemble.uncertain]\n\
         \"mu.open\" = { dist = \"uniform\", min = 0.1, max = 0.9 }\n",
    );
    std::fs::write(&path, text).unwrap();
    let mc = holewall::cli::ensemble_cmd::monte_carlo(
        Some(8),
        1,
        holewall::uq::Sampling::Lhs,
        &[],
        &[],
        false,
    )
    .unwrap();
    let out = path.parent().unwrap().join("out");
    let options = holewall::ensemble::store::EnsembleOptions {
        monte_carlo: mc,
        ..Default::default()
    };
    let s = common::ensemble_with(&path, None, BackendChoice::Cpu, &out, &options);
    let u = s.uncertainty.as_ref().expect("a Monte Carlo report");
    let stopped = common::variants_column(&out, "stopped_load_factor");
    let hook = common::variants_column(&out, "hook_load_n");
    let stops = stopped.iter().filter(|x| x.is_finite()).count();
    let pushed = hook.iter().filter(|&&h| h < 0.0).count();
    eprintln!("stops {stops}, pushed {pushed}; {:?}", u.stops);
    assert!(stops > 0 && pushed > 0, "{stopped:?} {hook:?}");
    let p = u.stops.as_ref().expect("runs stop");
    assert_eq!((p.count, p.of), (stops, 8));
    assert_eq!(p.probability, stops as f64 / 8.0);
    assert_eq!(p.ci95, holewall::uq::stats::wilson(stops, 8));
    let w = u.past_weight_lock_up.as_ref().expect("runs past it");
    assert_eq!((w.count, w.of), (stops + pushed, 8));
    assert!(s.digest(&out).contains(&format!(
        "stops on its way (a lock-up): {stops} of 8 runs, probability {:.3}",
        p.probability
    )));
    assert!(out.join("scatter_loads_reached_vs_mu.open.png").is_file());
}
