//! Stress suite of the static ensemble engine (issue 12): assemblies and wells a BHA
//! engineer meets, none of them the case the engine was built on — two and three
//! stabilizers close together, build rates of 3–10°/30 m, inclinations of 60–90°, walls up
//! to 1e10 N/m, weight on bit near the pipe's sinusoidal buckling load, a stabilizer moved
//! next to another per variant, zero clearance, friction 0 and 1.
//!
//! Every variant must be solved by the engine itself — twin path and GPU, f64 and f32 —
//! with no CPU re-run (a failed variant fails the test), wherever `solve_static` solves it;
//! its quantities of interest within the bounds the engine is held to elsewhere: 1e-9 of
//! the force scale of `solve_static`'s in f64, plus the stiffest wall's rounding floor
//! (the neutral point within its own rounding floor), the
//! residual f32 accepts (1e4 ε₃₂ ≈ 1.2e-3 of the force scale) in f32. Iterations per load
//! step are printed for the record (`cargo test --release --test engine_stress --
//! --nocapture`).

mod common;

use holewall::engine::{solve_static_ensemble, EngineResult, EngineStatus, TwinPath};

use holewall::ensemble::{apply, variants_from_csv_text};
use holewall::gpu::GpuPath;
use holewall::model::Model;
use holewall::solve::statics::{solution_at, solve_static, StaticOptions, StaticSolution};

/// A build-and-hold well: kickoff, build rate (°/30 m), hold inclination, depth; the BHA
/// as (kind, length, blade diameter) from the bit up, then drill pipe to the surface.
struct Well<'a> {
    name: &'a str,
    kickoff_m: f64,
    build_deg_per_30m: f64,
    hold_deg: f64,
    total_m: f64,
    bha: &'a [(&'a str, f64, Option<&'a str>)],
    wob: &'a str,
    k_e: &'a str,
    variants: &'a str,
}

impl Well<'_> {
    fn case_text(&self) -> String {
        let mut t = format!(
            r#"title = "{name}"
[well]
profile = "build_and_hold"
total_md = "{total} m"
kickoff_md = "{kickoff} m"
build_rate_deg_per_30m = {build}
hold_inclination = {hold}
azimuth = 30
[[hole]]
bottom_md = "{total} m"
diameter = "8.5 in"
friction = 0.3
[mud]
density = "1.2 sg"
"#,
            name = self.name,
            total = self.total_m,
            kickoff = self.kickoff_m,
            build = self.build_deg_per_30m,
            hold = self.hold_deg,
        );
        let mut used = 0.0;
        for (kind, length, blade) in self.bha {
            t += &format!(
                "[[string]]\nkind = \"{kind}\"\nlength = \"{length} m\"\nod = \"6.5 in\"\nid = \"2.8125 in\"\n"
            );
            if let Some(b) = blade {
                t += &format!("blade_diameter = \"{b}\"\n");
            }
            used += length;
        }
        t += &format!(
            "[[string]]\nkind = \"drill_pipe\"\nlength = \"{} m\"\nod = \"5 in\"\nid = \"4.276 in\"\n",
            self.total_m - used
        );
        t += &format!(
            r#"[operation]
mode = "rotating"
weight_on_bit = "{wob}"
torque_on_bit = "3 kN.m"
rpm = "100 rpm"
[contact]
sites = "all_nodes"
wall_stiffness = {k_e}
[mesh]
element_length = "15 m"
bha_element_length = "1.5 m"
"#,
            wob = self.wob,
            k_e = self.k_e,
        );
        t
    }

    fn models(&self) -> (f64, Vec<Model>) {
        let case = holewall::case::parse_case(
            std::path::Path::new(&format!("{}.toml", self.name)),
            &self.case_text(),
        )
        .unwrap();
        let variants = variants_from_csv_text("v.csv", self.variants).unwrap();
        let models = variants.iter().map(|v| apply(&case, v).unwrap()).collect();
        (case.bit_md, models)
    }
}

/// Neutral point from the bit, surface torque, largest side force, hook load.
fn qoi(model: &Model, sol: &StaticSolution, bit_md: f64) -> [f64; 4] {
    common::static_qois(model, sol, bit_md)
}

/// Largest difference per quantity: the neutral point in m, the forces and the torque
/// relative to `scale` (their own size, or the force scale where that is larger).
fn differences(a: &[[f64; 4]], b: &[[f64; 4]], scale: f64) -> [f64; 4] {
    let mut worst = [0.0f64; 4];
    for (x, y) in a.iter().zip(b) {
        for k in 0..4 {
            if x[k].is_nan() && y[k].is_nan() {
                continue;
            }
            let d = if k == 0 {
                (x[k] - y[k]).abs()
            } else {
                (x[k] - y[k]).abs() / y[k].abs().max(scale)
            };
            worst[k] = worst[k].max(if d.is_nan() { f64::INFINITY } else { d });
        }
    }
    worst
}

fn engine_qois(
    label: &str,
    models: &[Model],
    results: &[EngineResult],
    bit_md: f64,
) -> Vec<[f64; 4]> {
    let mut out = Vec::new();
    for (j, (m, r)) in models.iter().zip(results).enumerate() {
        assert_eq!(
            r.status,
            EngineStatus::Converged,
            "{label}: variant {j} not solved by the engine"
        );
        let steps = r.iterations.len();
        let mean = r.iterations.iter().sum::<usize>() as f64 / steps.max(1) as f64;
        let mut sorted = r.iterations.clone();
        sorted.sort_unstable();
        eprintln!(
            "  {label} variant {j}: {steps} load steps, iterations per step mean {mean:.1}, median {}, max {}; {} cuts",
            sorted.get(steps / 2).copied().unwrap_or(0),
            sorted.last().copied().unwrap_or(0),
            r.log.iter().filter(|l| l.contains("cut")).count()
        );
        out.push(qoi(m, &solution_at(m, r.state.clone()), bit_md));
    }
    out
}

fn check(well: &Well) {
    let (bit_md, models) = well.models();
    let options = StaticOptions::default();
    eprintln!(
        "{}: {} nodes, {} variants",
        well.name,
        models[0].nodes.len(),
        models.len()
    );
    // The oracle: every variant must be one solve_static solves.
    let cpu: Vec<[f64; 4]> = models
        .iter()
        .enumerate()
        .map(|(j, m)| {
            let sol = solve_static(m, &options)
                .unwrap_or_else(|e| panic!("{}: solve_static fails variant {j}: {e}", well.name));
            qoi(m, &sol, bit_md)
        })
        .collect();
    // The neutral point's rounding floor: axial forces carry ≈ 4 EA/l ε |x| of noise, and
    // the neutral point moves by that over the buoyed weight per length.
    let x_max = models[0]
        .nodes
        .iter()
        .flat_map(|n| n.position)
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let floor = models[0]
        .elements
        .iter()
        .map(|e| {
            4.0 * e.section.youngs_modulus * e.section.area / e.length0 * f64::EPSILON * x_max
                / e.buoyed_weight_per_length.abs()
        })
        .fold(1e-9f64, f64::max);
    // The forces' bound: the residual the solvers accept (1e-9 of the force scale) plus
    // the wall's rounding floor — a position carries ≈ 4 ε |x| of noise, which the stiffest
    // wall turns into k_e · 4 ε |x| of side force (1e-3 N at 1e10 N/m and 400 m).
    let f_ref = holewall::solve::statics::reference_force(&models[0]);
    let k_max = models
        .iter()
        .flat_map(|m| m.sites.iter().map(|s| s.params.wall_stiffness))
        .fold(0.0f64, f64::max);
    let force_bound = 1e-9 + k_max * 4.0 * f64::EPSILON * x_max / f_ref;
    let twin = solve_static_ensemble(&models, &TwinPath, &options).unwrap();
    let d = differences(
        &engine_qois("twin f64", &models, &twin, bit_md),
        &cpu,
        f_ref,
    );
    eprintln!("  twin f64 vs solve_static: neutral point {:.1e} m (floor {floor:.1e} m), torque {:.1e}, side force {:.1e}, hook load {:.1e} (of the force scale; bound {force_bound:.1e})", d[0], d[1], d[2], d[3]);
    assert!(
        d[0] <= floor && d[1..].iter().all(|&x| x <= force_bound),
        "{d:?}"
    );
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let gpu = solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options).unwrap();
        let d = differences(&engine_qois("GPU f64", &models, &gpu, bit_md), &cpu, f_ref);
        eprintln!("  GPU f64 vs solve_static: neutral point {:.1e} m, torque {:.1e}, side force {:.1e}, hook load {:.1e}", d[0], d[1], d[2], d[3]);
        assert!(
            d[0] <= floor && d[1..].iter().all(|&x| x <= force_bound),
            "{d:?}"
        );
    }
    let gpu32 = solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options).unwrap();
    let q32 = engine_qois("GPU f32", &models, &gpu32, bit_md);
    // f32 against f64, each relative to its own scale: the neutral point over the BHA's
    // length, the forces over the string's weight (the force scale of the convergence test).
    let weight = holewall::solve::statics::reference_force(&models[0]);
    let mut worst = [0.0f64; 4];
    for (a, b) in q32.iter().zip(&cpu) {
        for k in 0..4 {
            if a[k].is_nan() && b[k].is_nan() {
                continue;
            }
            let scale = if k == 0 { bit_md } else { weight };
            let e = (a[k] - b[k]).abs() / scale;
            worst[k] = worst[k].max(if e.is_nan() { f64::INFINITY } else { e });
        }
    }
    eprintln!("  GPU f32 vs solve_static (of the depth / the string's weight): neutral point {:.1e}, torque {:.1e}, side force {:.1e}, hook load {:.1e}", worst[0], worst[1], worst[2], worst[3]);
    assert!(worst.iter().all(|&w| w <= 1.2e-3), "{worst:?}");
}

const NEAR_BIT: (&str, f64, Option<&str>) = ("stabilizer", 1.5, Some("8.375 in"));
const BIT: (&str, f64, Option<&str>) = ("bit", 0.3, None);

#[test]
fn two_stabilizers_close_together_steep_build_stiff_wall() {
    check(&Well {
        name: "two stabilizers 3 m apart, 6°/30 m to 60°",
        kickoff_m: 60.0,
        build_deg_per_30m: 6.0,
        hold_deg: 60.0,
        total_m: 420.0,
        bha: &[
            BIT,
            NEAR_BIT,
            ("collar", 3.0, None),
            ("stabilizer", 1.5, Some("8.25 in")),
            ("collar", 27.0, None),
        ],
        wob: "40 kN",
        k_e: "6e7",
        variants: "mu,k_e,wob\n0,1e10,20 kN\n1,6e7,80 kN\n0.5,1e9,50 kN\n1,1e10,80 kN\n",
    });
}

#[test]
fn three_stabilizers_horizontal_after_ten_degrees_per_30_m() {
    check(&Well {
        name: "three stabilizers, 10°/30 m to 90°",
        kickoff_m: 30.0,
        build_deg_per_30m: 10.0,
        hold_deg: 90.0,
        total_m: 450.0,
        bha: &[
            BIT,
            NEAR_BIT,
            ("collar", 4.5, None),
            ("stabilizer", 1.5, Some("8.375 in")),
            ("collar", 4.5, None),
            ("stabilizer", 1.5, Some("8.25 in")),
            ("collar", 18.0, None),
        ],
        wob: "30 kN",
        k_e: "1e8",
        variants: "mu,k_e\n0,1e8\n1,1e8\n0.3,1e10\n",
    });
}

#[test]
fn weight_on_bit_near_sinusoidal_buckling_and_a_stabilizer_moved_next_to_another() {
    // 5 in pipe in an 8.5 in hole at 75°: Dawson–Paslay F_s = 2 √(EI w sinθ / r_c)
    // ≈ 170 kN (EI 1.2e6 N·m², buoyed 240 N/m, r_c 44 mm); 150 kN on the bit puts the
    // pipe above the short BHA at ≈ 0.85 F_s. stab2 moves from 20 m to 3 m (beside the
    // near-bit stabilizer).
    check(&Well {
        name: "75° hold, WOB near buckling, stabilizer moves",
        kickoff_m: 100.0,
        build_deg_per_30m: 3.0,
        hold_deg: 75.0,
        total_m: 1000.0,
        bha: &[
            BIT,
            NEAR_BIT,
            ("collar", 12.0, None),
            ("stabilizer", 1.5, Some("8.25 in")),
            ("collar", 15.0, None),
        ],
        wob: "100 kN",
        k_e: "6e7",
        variants: "wob,stab2.from_bit,mu\n150 kN,20,0.3\n150 kN,3,0.3\n100 kN,9,1\n",
    });
}

#[test]
fn zero_clearance_stabilizer_at_sixty_degrees() {
    check(&Well {
        name: "full-gauge stabilizer (zero clearance), 4°/30 m to 60°",
        kickoff_m: 50.0,
        build_deg_per_30m: 4.0,
        hold_deg: 60.0,
        total_m: 600.0,
        bha: &[
            BIT,
            ("stabilizer", 1.5, Some("8.5 in")),
            ("collar", 9.0, None),
            ("stabilizer", 1.5, Some("8.375 in")),
            ("collar", 27.0, None),
        ],
        wob: "60 kN",
        k_e: "6e7",
        variants: "mu,k_e\n0,6e7\n1,1e10\n0.3,1e9\n",
    });
}
