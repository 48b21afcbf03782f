//! Natural frequencies of a uniform string against closed forms (f64), including the effect
//! of axial load on the lateral ones.

use holewall::model::{mesh_string, Model, TopBoundary, Tubular};
use holewall::physics::mass::MassKind;
use holewall::solve::modal::{mass_matrix, modes, participation, Mode};
use holewall::solve::statics::{solve_static, StaticOptions};
use holewall::well::WellPath;

const RHO: f64 = 7850.0;
const E: f64 = 2.1e11;
const NU: f64 = 0.3;
const OD: f64 = 0.127;
const ID: f64 = 0.108;

fn column(
    length: f64,
    elements: usize,
    top: TopBoundary,
    bit_lateral_fixed: bool,
    wob: f64,
) -> Model {
    let well = WellPath::vertical(length);
    let t = Tubular {
        name: "pipe".into(),
        length,
        outer_diameter: OD,
        inner_diameter: ID,
        youngs_modulus: E,
        poisson_ratio: NU,
        density: RHO,
        element_length: length / elements as f64,
    };
    // Weightless: mud as dense as steel.
    let (nodes, elements) = mesh_string(&well, &[t], length, RHO);
    Model {
        weight_on_bit: wob,
        top,
        bit_lateral_fixed,
        ..Model::bare(nodes, elements)
    }
}

fn first(modes: &[Mode], component: &dyn Fn(&Mode) -> f64) -> f64 {
    modes
        .iter()
        .find(|m| component(m) > 0.9)
        .map(|m| m.frequency_hz)
        .expect("no such mode")
}

fn area() -> f64 {
    std::f64::consts::PI / 4.0 * (OD * OD - ID * ID)
}

fn second_moment() -> f64 {
    std::f64::consts::PI / 64.0 * (OD.powi(4) - ID.powi(4))
}

#[test]
fn axial_and_torsional_modes_of_a_fixed_free_string() {
    let l = 100.0;
    let m = column(l, 50, TopBoundary::Clamped, false, 0.0);
    let sol = solve_static(&m, &StaticOptions::default()).unwrap();
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let mass = mass_matrix(&m, kind, &|_| RHO);
        let all = modes(&m, &sol.state, &mass);
        let axial = first(&all, &|md| participation(md, 2));
        let torsion = first(&all, &|md| participation(md, 5));
        let f_axial = (E / RHO).sqrt() / (4.0 * l);
        let f_torsion = (E / (2.0 * (1.0 + NU)) / RHO).sqrt() / (4.0 * l);
        eprintln!("{kind:?}: axial {axial:.4} Hz vs {f_axial:.4}; torsion {torsion:.4} Hz vs {f_torsion:.4}");
        assert!((axial / f_axial - 1.0).abs() <= 0.01);
        assert!((torsion / f_torsion - 1.0).abs() <= 0.01);
    }
}

#[test]
fn lateral_modes_of_a_pinned_column_under_axial_load() {
    let l = 30.0;
    let ei = E * second_moment();
    let rho_a = RHO * area();
    let p_euler = std::f64::consts::PI.powi(2) * ei / (l * l);
    for (label, wob) in [
        ("no load", 0.0),
        ("tension 0.5 P_E", -0.5 * p_euler),
        ("compression 0.5 P_E", 0.5 * p_euler),
    ] {
        let m = column(l, 40, TopBoundary::Pinned, true, wob);
        let sol = solve_static(&m, &StaticOptions::default()).unwrap();
        let mass = mass_matrix(&m, MassKind::Consistent, &|_| RHO);
        let all = modes(&m, &sol.state, &mass);
        let lateral = first(&all, &|md| participation(md, 0) + participation(md, 1));
        // Pinned–pinned with axial tension T: ω² = (π/L)⁴ EI/ρA + (π/L)² T/ρA.
        let k = std::f64::consts::PI / l;
        let tension = -wob;
        let expected =
            (k.powi(4) * ei / rho_a + k * k * tension / rho_a).sqrt() / std::f64::consts::TAU;
        eprintln!(
            "{label}: first lateral {lateral:.5} Hz vs {expected:.5} Hz ({:+.3} %)",
            100.0 * (lateral / expected - 1.0)
        );
        assert!((lateral / expected - 1.0).abs() <= 0.01, "{label}");
    }
}

/// The Krylov solve of the lowest modes (`holewall::solve::modal::krylov_modes`, shift-invert
/// block Lanczos) against the dense one on a vertical column whose lateral modes come in
/// equal pairs (two planes): the same lowest frequencies, both members of every pair, and
/// each mode an eigenpair of the pencil.
#[test]
fn the_krylov_solve_finds_the_dense_solves_lowest_modes_pairs_included() {
    use holewall::solve::modal::krylov_modes;
    let m = column(60.0, 240, TopBoundary::Pinned, true, 0.0);
    let sol = solve_static(&m, &StaticOptions::default()).unwrap();
    let mass = mass_matrix(&m, MassKind::Consistent, &|_| RHO);
    let dense = modes(&m, &sol.state, &mass);
    let want = 16;
    let krylov = krylov_modes(&m, &sol.state, &mass, &|found: &[Mode]| found.len() >= want)
        .expect("the Krylov solve converges");
    assert_eq!(krylov.method, "shift-invert block Lanczos");
    assert!(
        krylov.basis < krylov.free_dofs / 4,
        "{} of {}",
        krylov.basis,
        krylov.free_dofs
    );
    let lateral = |md: &Mode| participation(md, 0) + participation(md, 1) > 0.9;
    // The dense eigensolve's rounding on a mode of `ω²` is about `ε ω²_max` (its largest,
    // an axial mode of one 0.25 m element), a relative error `ε ω²_max / ω²` that is 1e-6
    // on this slender column's lowest mode: the Krylov solve, which works on `(K − σ M)⁻¹`,
    // is held to that bound (with a margin of 10) and to 1e-9.
    let top = dense.last().unwrap().frequency_hz;
    for (j, (k, d)) in krylov.modes.iter().zip(&dense).take(want).enumerate() {
        let rel = (k.frequency_hz / d.frequency_hz - 1.0).abs();
        let bound = 1e-9 + 10.0 * f64::EPSILON * (top / d.frequency_hz).powi(2);
        eprintln!(
            "mode {j}: {:.6} Hz against {:.6} Hz ({rel:.1e}; the dense solve's rounding \
             {bound:.1e}), lateral {}",
            k.frequency_hz,
            d.frequency_hz,
            lateral(k)
        );
        assert!(rel < bound, "mode {j}: {rel:e} against {bound:e}");
        assert_eq!(lateral(k), lateral(d), "mode {j}");
    }
    // The lateral modes in pairs: 1–2 and 3–4 equal (two planes of a round column).
    let lat: Vec<f64> = krylov
        .modes
        .iter()
        .filter(|md| lateral(md))
        .map(|md| md.frequency_hz)
        .collect();
    assert!(lat.len() >= 4, "{lat:?}");
    assert!((lat[1] / lat[0] - 1.0).abs() < 1e-9 && (lat[3] / lat[2] - 1.0).abs() < 1e-9);
    assert!(lat[2] / lat[0] > 3.0, "{lat:?}");
    assert!(krylov.worst_residual < 1e-6);
}
