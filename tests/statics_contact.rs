//! Static solver with contact at every node: Dawson–Paslay buckling, and the FE model
//! against soft-string torque & drag.

use holewall::model::{add_sites, mesh_string, ContactSettings, Model, Tubular};
use holewall::solve::chain::BlockTridiagonal;
use holewall::solve::soft_string::{soft_string, Operation};
use holewall::solve::statics::{
    constrained_tangent, solve_static, solve_static_from, StaticOptions, StaticState,
};
use holewall::well::{SurveyStation, WellPath};

const STEEL: f64 = 7850.0;
const MUD: f64 = 1200.0;
const E: f64 = 2.1e11;
const HOLE_RADIUS: f64 = 0.2159 / 2.0;
const OD: f64 = 0.127;
const ID: f64 = 0.108;

fn pipe(length: f64, element_length: f64) -> Tubular {
    Tubular {
        name: "drill pipe".into(),
        length,
        outer_diameter: OD,
        inner_diameter: ID,
        youngs_modulus: E,
        poisson_ratio: 0.3,
        density: STEEL,
        element_length,
    }
}

fn settings() -> ContactSettings {
    ContactSettings {
        wall_stiffness: 1e8,
        spring_exponent: 1.0,
        wall_damping: 0.0,
        eps: 1e-3,
        soft_blend: 1e-5,
    }
}

fn model_with_contact(well: &WellPath, md: f64, element_length: f64, mu: f64) -> Model {
    let (nodes, elements) = mesh_string(well, &[pipe(md, element_length)], md, MUD);
    let n = nodes.len();
    let mut m = Model {
        bit_lateral_fixed: false,
        ..Model::bare(nodes, elements)
    };
    let all: Vec<usize> = (1..n).collect();
    add_sites(
        &mut m,
        &all,
        |_| HOLE_RADIUS,
        |_| OD / 2.0,
        |_| mu,
        &settings(),
        false,
    );
    m
}

fn positive_definite(t: &BlockTridiagonal) -> bool {
    t.symmetric_part_positive_definite()
}

fn dawson_paslay_sinusoidal_buckling(inclination_deg: f64, length: f64) -> f64 {
    let well = WellPath::from_survey(
        &[
            SurveyStation {
                md: 0.0,
                inclination_deg,
                azimuth_deg: 0.0,
            },
            SurveyStation {
                md: length,
                inclination_deg,
                azimuth_deg: 0.0,
            },
        ],
        [0.0; 3],
    )
    .unwrap();
    let mut m = model_with_contact(&well, length, 1.0, 0.0);
    // Both ends held laterally where the string lies (the bit constraint holds the start
    // position): a free end under a dead axial load would buckle first, as a cantilever.
    m.bit_lateral_fixed = true;
    let w = m.elements[0].buoyed_weight_per_length;
    let clearance = HOLE_RADIUS - OD / 2.0;
    // Lay the string on the low side at its equilibrium penetration (the bit too: it is
    // held there).
    let mut start = StaticState::initial(&m);
    let t = m.nodes[0].hole_axis;
    let low = [-t[0] * t[2], -t[1] * t[2], 1.0 - t[2] * t[2]];
    let low_len = (low[0] * low[0] + low[1] * low[1] + low[2] * low[2]).sqrt();
    for x in start.u.iter_mut().skip(1) {
        for k in 0..3 {
            x[k] += (clearance + w / settings().wall_stiffness) * low[k] / low_len;
        }
    }
    let ei = E * std::f64::consts::PI / 64.0 * (OD.powi(4) - ID.powi(4));
    let f_dp = 2.0 * (ei * w * inclination_deg.to_radians().sin() / clearance).sqrt();
    let options = StaticOptions {
        initial_steps: 2,
        ..Default::default()
    };
    let mut stable = |f: f64| {
        m.weight_on_bit = f;
        let sol = solve_static_from(&m, start.clone(), &options).unwrap();
        positive_definite(&constrained_tangent(&m, &sol.state, 1.0))
    };
    let (a, b) = (stable(0.7 * f_dp), stable(1.3 * f_dp));
    assert!(a && !b, "stable at 0.7 F_DP: {a}, at 1.3 F_DP: {b}");
    let (mut lo, mut hi) = (0.7 * f_dp, 1.3 * f_dp);
    while hi - lo > 2e-3 * f_dp {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let f_cr = 0.5 * (lo + hi);
    eprintln!(
        "{inclination_deg}° hole, {length} m: sinusoidal buckling onset (compression at the bit) {f_cr:.0} N vs Dawson–Paslay {f_dp:.0} N ({:+.2} %)",
        100.0 * (f_cr / f_dp - 1.0)
    );
    f_cr / f_dp - 1.0
}

#[test]
fn dawson_paslay_sinusoidal_buckling_in_horizontal_and_inclined_holes() {
    // At 90° the axial weight component vanishes: uniform compression, the onset is the
    // Dawson–Paslay load 2·sqrt(E·I·w·sinθ/r).
    assert!(dawson_paslay_sinusoidal_buckling(90.0, 120.0).abs() <= 0.05);
    // At 60° the compression grows by w·cosθ per metre towards the bit; over 60 m that is
    // 4 % of the load, and the buckle starts at the bit.
    assert!(dawson_paslay_sinusoidal_buckling(60.0, 60.0).abs() <= 0.05);
}

#[test]
fn fe_and_soft_string_agree_in_a_build_and_hold_well() {
    // Kick-off 300 m, 2°/30 m to 30°, hold to 1500 m; 5 in drill pipe on the wall, μ = 0.25.
    let md = 1500.0;
    let well = WellPath::build_and_hold(300.0, 2.0, 30.0, 45.0, md).unwrap();
    let mu = 0.25;
    let mut m = model_with_contact(&well, md, 10.0, mu);
    let cases = [
        ("rotating off bottom", 0.0, 4.0 * std::f64::consts::PI),
        ("picking up", -0.5, 0.0),
        ("slacking off", 0.5, 0.0),
    ];
    for (name, axial, rotation) in cases {
        m.axial_speed = axial;
        m.rotation_speed = rotation;
        let sol = solve_static(&m, &StaticOptions::default()).unwrap();
        let fe_hook = -sol.top_reaction[2];
        let fe_torque = sol.top_reaction[5].abs();
        let ss = soft_string(
            &m,
            &Operation {
                axial_speed: axial,
                rotation_speed: rotation,
                weight_on_bit: 0.0,
                torque_on_bit: 0.0,
                friction: mu,
            },
        );
        let dh = fe_hook / ss.hook_load() - 1.0;
        eprintln!(
            "{name}: hook load FE {fe_hook:.0} N, soft string {:.0} N ({:+.2} %); surface torque FE {fe_torque:.0} N·m, soft string {:.0} N·m ({:+.2} %)",
            ss.hook_load(),
            100.0 * dh,
            ss.surface_torque(),
            if rotation > 0.0 { 100.0 * (fe_torque / ss.surface_torque() - 1.0) } else { 0.0 }
        );
        assert!(
            dh.abs() <= 0.05,
            "{name}: hook load differs by {:.2} %",
            100.0 * dh
        );
        if rotation > 0.0 {
            let dt = fe_torque / ss.surface_torque() - 1.0;
            assert!(
                dt.abs() <= 0.05,
                "{name}: surface torque differs by {:.2} %",
                100.0 * dt
            );
        }
    }
}
