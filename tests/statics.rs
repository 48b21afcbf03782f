//! Static solver against closed forms (f64).

mod common;

use holewall::model::{mesh_string, Model, TopBoundary, Tubular, GRAVITY};
use holewall::physics::beam::rotation_exp;
use holewall::solve::chain::BlockTridiagonal;
use holewall::solve::statics::{
    constrained_tangent, internal_forces, solve_static, StaticOptions, StaticState,
};
use holewall::well::WellPath;

const STEEL: f64 = 7850.0;
const E: f64 = 2.1e11;

fn tubular(name: &str, length: f64, od: f64, id: f64, element_length: f64) -> Tubular {
    Tubular {
        name: name.into(),
        length,
        outer_diameter: od,
        inner_diameter: id,
        youngs_modulus: E,
        poisson_ratio: 0.3,
        density: STEEL,
        element_length,
    }
}

fn model(well: &WellPath, tubulars: &[Tubular], bit_md: f64, mud: f64, wob: f64) -> Model {
    let (nodes, elements) = mesh_string(well, tubulars, bit_md, mud);
    Model {
        weight_on_bit: wob,
        ..Model::bare(nodes, elements)
    }
}

fn area(od: f64, id: f64) -> f64 {
    std::f64::consts::PI / 4.0 * (od * od - id * id)
}

fn second_moment(od: f64, id: f64) -> f64 {
    std::f64::consts::PI / 64.0 * (od.powi(4) - id.powi(4))
}

/// Neutral point: where the element axial force (at element mid-MD) crosses zero.
fn neutral_point_md(m: &Model, axial: &[f64]) -> f64 {
    let mid: Vec<f64> = (0..m.elements.len())
        .map(|i| 0.5 * (m.nodes[i].md + m.nodes[i + 1].md))
        .collect();
    for i in 0..axial.len() - 1 {
        if axial[i] > 0.0 && axial[i + 1] <= 0.0 {
            let f = axial[i] / (axial[i] - axial[i + 1]);
            return mid[i] + f * (mid[i + 1] - mid[i]);
        }
    }
    panic!("no neutral point");
}

#[test]
fn vertical_well_neutral_point_and_hook_load() {
    let well = WellPath::vertical(1000.0);
    let mud = 1200.0;
    let wob = 50e3;
    let tubs = [
        tubular("collar", 150.0, 0.165, 0.071, 2.0),
        tubular("pipe", 850.0, 0.127, 0.108, 10.0),
    ];
    let m = model(&well, &tubs, 1000.0, mud, wob);
    let sol = solve_static(&m, &StaticOptions::default()).unwrap();
    let axial: Vec<f64> = sol.section_forces.iter().map(|s| s.axial).collect();
    let bf = 1.0 - mud / STEEL;
    let w_collar = STEEL * area(0.165, 0.071) * GRAVITY;
    let expected_np = wob / (bf * w_collar);
    let np_from_bit = 1000.0 - neutral_point_md(&m, &axial);
    assert!(
        (np_from_bit - expected_np).abs() <= 5e-3 * expected_np,
        "neutral point {np_from_bit} vs {expected_np}"
    );
    let air_weight = STEEL * GRAVITY * (150.0 * area(0.165, 0.071) + 850.0 * area(0.127, 0.108));
    let expected_hook = bf * air_weight - wob;
    let hook = -sol.top_reaction[2];
    assert!(
        (hook - expected_hook).abs() <= 5e-3 * expected_hook,
        "hook load {hook} vs {expected_hook}"
    );
    eprintln!(
        "neutral point {np_from_bit:.3} m vs {expected_np:.3} m ({:.2e}); hook load {hook:.1} N vs {expected_hook:.1} N ({:.2e})",
        (np_from_bit - expected_np) / expected_np,
        (hook - expected_hook) / expected_hook
    );
}

fn positive_definite(t: &BlockTridiagonal) -> bool {
    t.symmetric_part_positive_definite()
}

#[test]
fn euler_buckling_of_a_pinned_column() {
    let l = 10.0;
    let well = WellPath::vertical(l);
    let (od, id) = (0.127, 0.108);
    // Weightless (mud as dense as steel), pinned at the top, laterally held at the bit.
    let mut m = model(&well, &[tubular("pipe", l, od, id, 0.5)], l, STEEL, 0.0);
    m.top = TopBoundary::Pinned;
    let p_euler = std::f64::consts::PI.powi(2) * E * second_moment(od, id) / (l * l);
    let stable = |p: f64| {
        let mut mm = m.clone();
        mm.weight_on_bit = p;
        let sol = solve_static(&mm, &StaticOptions::default()).unwrap();
        positive_definite(&constrained_tangent(&mm, &sol.state, 1.0))
    };
    assert!(stable(0.5 * p_euler) && !stable(1.5 * p_euler));
    let (mut lo, mut hi) = (0.5 * p_euler, 1.5 * p_euler);
    while hi - lo > 1e-4 * p_euler {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p_cr = 0.5 * (lo + hi);
    eprintln!(
        "buckling load {p_cr:.1} N vs π²EI/L² = {p_euler:.1} N ({:.2e})",
        p_cr / p_euler - 1.0
    );
    assert!((p_cr / p_euler - 1.0).abs() <= 0.01);
}

#[test]
fn cantilever_tip_deflection() {
    let l = 10.0;
    let well = WellPath::vertical(l);
    let (od, id) = (0.165, 0.071);
    let mut m = model(&well, &[tubular("collar", l, od, id, 1.0)], l, STEEL, 0.0);
    m.bit_lateral_fixed = false;
    let ei = E * second_moment(od, id);
    let p = 1e-4 * 3.0 * ei / (l * l); // tip deflection 1e-4 L
    let bit = m.nodes.len() - 1;
    m.point_loads = vec![(bit, [p, 0.0, 0.0, 0.0, 0.0, 0.0])];
    let sol = solve_static(&m, &StaticOptions::default()).unwrap();
    let tip = sol.state.u[bit][0];
    let expected = p * l.powi(3) / (3.0 * ei);
    assert!(
        (tip - expected).abs() <= 1e-3 * expected,
        "tip {tip} vs {expected}"
    );
}

#[test]
fn end_moment_rolls_the_cantilever_into_a_full_circle() {
    let l = 10.0;
    let well = WellPath::vertical(l);
    let (od, id) = (0.165, 0.071);
    let mut m = model(&well, &[tubular("collar", l, od, id, 0.5)], l, STEEL, 0.0);
    m.bit_lateral_fixed = false;
    let ei = E * second_moment(od, id);
    let bit = m.nodes.len() - 1;
    m.point_loads = vec![(
        bit,
        [0.0, 0.0, 0.0, 0.0, 2.0 * std::f64::consts::PI * ei / l, 0.0],
    )];
    let options = StaticOptions {
        initial_steps: 16,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let sol = solve_static(&m, &options).unwrap();
    eprintln!(
        "roll-up solve {:?}: iterations {:?}, log {:?}",
        t0.elapsed(),
        sol.iterations,
        sol.log
    );
    let x = sol.state.positions(&m);
    let gap = ((0..3).map(|k| (x[bit][k] - x[0][k]).powi(2)).sum::<f64>()).sqrt();
    // Half way the string is a semicircle of diameter L/π.
    let mid = x[bit / 2];
    let span = ((mid[0] - x[0][0]).powi(2) + (mid[2] - x[0][2]).powi(2)).sqrt();
    eprintln!("roll-up: tip returns within {gap:.2e} m of the root; mid-length point {span:.4} m from it (L/π = {:.4})", l / std::f64::consts::PI);
    assert!(gap <= 1e-3 * l, "tip {gap} m from the root");
    // The nodes lie on the circle, the elements are its chords: the circle's diameter is
    // L/(n sin(π/n)), within π²/(6n²) of the continuum's L/π.
    let n = m.elements.len() as f64;
    let diameter = l / (n * (std::f64::consts::PI / n).sin());
    assert!((span - diameter).abs() <= 1e-6 * l, "{span} vs {diameter}");
    assert!(
        (span - l / std::f64::consts::PI).abs()
            <= std::f64::consts::PI.powi(2) / (6.0 * n * n) * 1.01 * l / std::f64::consts::PI
    );
    // The tip has turned a full circle: its triad is back to the identity.
    let r = sol.state.rot[bit];
    assert!((r[0][0] - 1.0).abs() < 1e-3 && (r[2][2] - 1.0).abs() < 1e-3);
}

#[test]
fn rigid_spin_of_1000_rad_leaves_no_internal_force() {
    let l = 30.0;
    let well = WellPath::vertical(l);
    let m = model(
        &well,
        &[tubular("pipe", l, 0.127, 0.108, 3.0)],
        l,
        1200.0,
        0.0,
    );
    let mut state = StaticState::initial(&m);
    let spin = rotation_exp(&[0.0, 0.0, 1000.0]);
    for r in &mut state.rot {
        *r = spin;
    }
    let f = internal_forces(&m, &state);
    let ea = E * area(0.127, 0.108);
    assert!(
        f.iter().all(|x| x.abs() <= 1e-9 * ea),
        "{:?}",
        f.iter().fold(0.0f64, |a, b| a.max(b.abs()))
    );
}

#[test]
fn hook_load_given_puts_the_rest_on_the_bit() {
    let well = WellPath::vertical(1000.0);
    let mud = 1200.0;
    let tubs = [
        tubular("collar", 150.0, 0.165, 0.071, 2.0),
        tubular("pipe", 850.0, 0.127, 0.108, 10.0),
    ];
    let mut m = model(&well, &tubs, 1000.0, mud, 0.0);
    let bf = 1.0 - mud / STEEL;
    let air_weight = STEEL * GRAVITY * (150.0 * area(0.165, 0.071) + 850.0 * area(0.127, 0.108));
    let hook = bf * air_weight - 50e3;
    m.top = TopBoundary::HookLoad(hook);
    let sol = solve_static(&m, &StaticOptions::default()).unwrap();
    let wob = -sol.bit_reaction[2];
    assert!((wob - 50e3).abs() <= 5e-3 * 50e3, "WOB {wob}");
    let axial: Vec<f64> = sol.section_forces.iter().map(|s| s.axial).collect();
    let np_from_bit = 1000.0 - neutral_point_md(&m, &axial);
    let expected_np = 50e3 / (bf * STEEL * area(0.165, 0.071) * GRAVITY);
    assert!(
        (np_from_bit - expected_np).abs() <= 5e-3 * expected_np,
        "{np_from_bit} vs {expected_np}"
    );
}

/// One rayon worker or two, the same answer to the bit: with one worker the main thread is
/// that worker (`holewall::threads::main_thread_in_pool`), so its parallel loops run in
/// place instead of being handed to a pool thread, and nothing waits on a thread that
/// never runs them.
#[test]
fn one_worker_or_two_give_the_same_static_answer() {
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/build_and_hold.toml");
    let profile = |workers: &str| {
        let out = common::scratch_dir("statics", &format!("workers-{workers}"));
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_holewall"))
            .args(["static", case, "--quiet", "--out", out.to_str().unwrap()])
            .env("RAYON_NUM_THREADS", workers)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "RAYON_NUM_THREADS={workers}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let csv = std::fs::read_to_string(out.join("profile.csv")).unwrap();
        let _ = std::fs::remove_dir_all(&out);
        csv
    };
    let (one, two) = (profile("1"), profile("2"));
    assert!(one.lines().count() > 100, "a profile of the whole string");
    assert_eq!(one, two);
}
