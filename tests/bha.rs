//! BHA outputs (issue 25) against closed forms: the pendulum's bit side force, tilt and
//! point of tangency (zero WOB; the beam-column with WOB; an inclined hole's varying axial
//! force by shooting), and the signs of the hole frame (a bent housing's toolface).

mod common;

use holewall::bha::validation::{
    beam_column_closed_form, beam_column_shooting, pendulum_closed_form, PendulumScene,
};

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn shooting_oracle_agrees_with_the_closed_forms() {
    // 6½ in collar in an 8½ in hole, horizontal: the shooting solution without an axial
    // gradient is the closed form's, at zero and at a constant compression.
    let (ei, q, r) = (7.2e6, 1100.0, 0.0254);
    let zero = pendulum_closed_form(ei, q, r);
    assert!(rel(zero.high_side_force_n, -0.5 * q * zero.tangency_m) < 1e-12);
    for p in [0.0, 4e4, 1.5e5] {
        let a = beam_column_closed_form(ei, q, r, p);
        let b = beam_column_shooting(ei, q, r, p, 0.0, 20_000);
        assert!(rel(b.tangency_m, a.tangency_m) < 1e-9, "{p}: {a:?} {b:?}");
        assert!(rel(b.high_side_force_n, a.high_side_force_n) < 1e-9);
        assert!(rel(b.tilt_rad, a.tilt_rad) < 1e-4, "{p}: {a:?} {b:?}");
    }
    // WOB lowers the pendulum force (−(qL/2 − P r/L)).
    let w = beam_column_closed_form(ei, q, r, 1.5e5);
    assert!(w.high_side_force_n > zero.high_side_force_n);
}

#[test]
fn pendulum_matches_its_closed_forms() {
    // (inclination, WOB, element length): tolerance 0.05 % on the side force and tilt,
    // 0.5 % on the point of tangency.
    for (inc, wob, h) in [
        (90.0, 0.0, 0.1),
        (90.0, 0.0, 0.2),
        (90.0, 60e3, 0.1),
        (30.0, 0.0, 0.1),
        (60.0, 40e3, 0.1),
    ] {
        let scene = PendulumScene {
            inclination_deg: inc,
            weight_on_bit: wob,
            element_length: h,
            ..Default::default()
        };
        let reference = scene.reference();
        let (bit, tangency) = scene.solve().expect("the pendulum solves");
        let line = format!(
            "pendulum {inc}° WOB {:.0} kN, {h} m: side force {:.1} N vs {:.1} N, tilt {:.5}° vs {:.5}°, tangency {:.3} m vs {:.3} m",
            wob / 1e3,
            bit.high_side_force_n,
            reference.high_side_force_n,
            bit.tilt_high_side_deg,
            reference.tilt_rad.to_degrees(),
            tangency,
            reference.tangency_m
        );
        println!("{line}");
        assert!(
            rel(bit.high_side_force_n, reference.high_side_force_n) < 5e-4,
            "{line}"
        );
        assert!(
            rel(bit.tilt_high_side_deg, reference.tilt_rad.to_degrees()) < 5e-4,
            "{line}"
        );
        assert!(rel(tangency, reference.tangency_m) < 5e-3, "{line}");
        // A pendulum drops: the force on the formation points to the low side, the tilt to
        // the high side; nothing sideways in a frictionless vertical plane.
        assert!(bit.high_side_force_n < 0.0 && bit.tilt_high_side_deg > 0.0);
        assert!(bit.right_side_force_n.abs() < 1e-6 * bit.side_force_n);
    }
}

/// A 30° straight hole of 600 m with a sliding motor: 1.5° bend 2 m above the bit, a
/// bearing-section sleeve below it; `toolface` from the high side.
fn motor_case(toolface_deg: f64) -> String {
    format!(
        r#"title = "motor"
[well]
profile = "build_and_hold"
total_md = "600 m"
kickoff_md = "0 m"
build_rate_deg_per_30m = 3.0
hold_inclination = 30
azimuth = 45
[[hole]]
bottom_md = "600 m"
diameter = "8.5 in"
friction = 0.0
[mud]
density = "1.2 sg"
[[string]]
kind = "bit"
length = "0.3 m"
od = "6.5 in"
id = "2.8125 in"
[[string]]
kind = "motor"
length = "0.7 m"
od = "6.75 in"
id = "2.8125 in"
[[string]]
kind = "stabilizer"
length = "0.5 m"
od = "6.75 in"
id = "2.8125 in"
blade_diameter = "8.25 in"
[[string]]
kind = "motor"
length = "7 m"
od = "6.75 in"
id = "2.8125 in"
bend = "1.5 deg"
bend_from_bottom = "0.5 m"
bend_toolface = "{toolface_deg} deg"
[[string]]
kind = "collar"
length = "60 m"
od = "6.5 in"
id = "2.8125 in"
[[string]]
kind = "drill_pipe"
length = "531.5 m"
od = "5 in"
id = "4.276 in"
[operation]
mode = "sliding"
weight_on_bit = "40 kN"
[contact]
sites = "all_nodes"
[mesh]
element_length = "10 m"
bha_element_length = "0.25 m"
"#
    )
}

#[test]
fn a_bent_housing_pushes_the_bit_towards_its_toolface() {
    // Toolface measured from the high side, clockwise looking down-hole: 0° builds, 90°
    // walks right, 180° drops, 270° walks left — in an inclined hole (the high side was
    // mirrored before issue 25: `toolface_from_high_side` took −z·t for the high side).
    for (tf, expect_high, expect_right) in [
        (0.0f64, 1.0f64, 0.0f64),
        (90.0, 0.0, 1.0),
        (180.0, -1.0, 0.0),
        (270.0, 0.0, -1.0),
    ] {
        let dir = common::scratch_dir("bha", &format!("motor_{tf}"));
        let path = dir.join("motor.toml");
        std::fs::write(&path, motor_case(tf)).unwrap();
        let case = holewall::case::load_case(&path).unwrap();
        let sol = holewall::solve::statics::solve_static(
            &case.model,
            &holewall::solve::statics::StaticOptions::default(),
        )
        .expect("the motor case solves");
        let bit = holewall::bha::bit_loads_of(&case.model, &sol);
        let angle = bit
            .right_side_force_n
            .atan2(bit.high_side_force_n)
            .to_degrees();
        let expected = expect_right.atan2(expect_high).to_degrees();
        let off = (angle - expected + 540.0).rem_euclid(360.0) - 180.0;
        println!("toolface {tf}°: bit side force {bit:?}, direction {angle:.1}°");
        // Gravity adds a drop (a pendulum share): within 30° of the toolface.
        assert!(off.abs() < 30.0, "toolface {tf}: side force at {angle:.1}°");
        assert!(bit.side_force_n > 5e3);
    }
}
