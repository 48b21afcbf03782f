//! Torque and drag as drilling engineers use it (issue 26): reaming and back-reaming
//! (running in / pulling out while rotating), their loads between tripping and rotating off
//! bottom, the FE against the soft string.

mod common;

/// `cases/build_and_hold.toml` off bottom (no WOB, no TOB) in `mode`, `extra` added to
/// `[operation]` (rpm, axial speed).
fn off_bottom(mode: &str, extra: &str) -> holewall::case::Case {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
    )
    .unwrap();
    let start = text.find("[operation]").unwrap();
    let end = start + text[start..].find("\n\n").unwrap();
    let op = format!("[operation]\nmode = \"{mode}\"\n{extra}");
    let text = format!("{}{}{}", &text[..start], op, &text[end..]);
    holewall::case::parse_case(std::path::Path::new("off_bottom.toml"), &text).unwrap()
}

/// (FE hook load, FE surface torque, soft-string hook load, soft-string torque).
fn loads(case: &holewall::case::Case) -> (f64, f64, f64, f64) {
    let sol = holewall::solve::statics::solve_static(&case.model, &Default::default())
        .expect("the FE solve");
    let (_, hook, torque, _) = holewall::profile::fe_rows(&case.model, &sol);
    let soft = case.soft_string();
    (hook, torque, soft.hook_load(), soft.surface_torque())
}

#[test]
fn reaming_and_back_reaming_sit_between_tripping_and_rotating() {
    let speed = "axial_speed = \"0.1 m/s\"\n";
    let rpm = "rpm = \"60 rpm\"\n";
    let trip_in = loads(&off_bottom("tripping_in", speed));
    let trip_out = loads(&off_bottom("tripping_out", speed));
    let rotating = loads(&off_bottom("rotating", rpm));
    let reaming = loads(&off_bottom("reaming", &format!("{speed}{rpm}")));
    let back = loads(&off_bottom("back_reaming", &format!("{speed}{rpm}")));
    for (name, l) in [
        ("tripping in", trip_in),
        ("tripping out", trip_out),
        ("rotating", rotating),
        ("reaming", reaming),
        ("back-reaming", back),
    ] {
        println!(
            "{name}: hook load FE {:.1} kN / soft string {:.1} kN, torque FE {:.2} kN·m / soft string {:.2} kN·m",
            l.0 / 1e3,
            l.2 / 1e3,
            l.1 / 1e3,
            l.3 / 1e3
        );
    }
    // Hook load: pulling out > back-reaming > rotating > reaming > running in (the friction
    // along the axis shrinks as the rotation takes the velocity's direction), in both
    // models.
    for k in [0, 2] {
        let h = |l: (f64, f64, f64, f64)| if k == 0 { l.0 } else { l.2 };
        assert!(h(trip_out) > h(back) && h(back) > h(rotating), "{k}");
        assert!(h(rotating) > h(reaming) && h(reaming) > h(trip_in), "{k}");
    }
    // Torque: below rotating off bottom (part of the friction goes along the axis), above 0.
    for l in [reaming, back] {
        assert!(l.1 > 0.0 && l.1 < rotating.1);
        assert!(l.3 > 0.0 && l.3 < rotating.3);
        // FE and soft string agree as they do rotating and tripping (docs/validation.md).
        assert!((l.0 / l.2 - 1.0).abs() < 0.03, "hook {} vs {}", l.0, l.2);
        assert!((l.1 / l.3 - 1.0).abs() < 0.06, "torque {} vs {}", l.1, l.3);
    }
    // The split follows the velocity's direction: with v_axial = 0.1 m/s and the pipe's
    // surface speed ω r ≈ 0.2 m/s, the axial share is 0.1/√(0.1² + (ωr)²).
    let r = 0.5 * 0.127;
    let surface = 60.0 / 60.0 * std::f64::consts::TAU * r;
    let share = 0.1 / (0.1f64 * 0.1 + surface * surface).sqrt();
    let drag_reaming = rotating.2 - reaming.2;
    let drag_in = rotating.2 - trip_in.2;
    println!("soft string: reaming drag / tripping-in drag {:.3}, axial share of the velocity {share:.3}", drag_reaming / drag_in);
    assert!((drag_reaming / drag_in - share).abs() < 0.1 * share);
}

#[test]
fn reaming_needs_the_rotary_speed() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
    )
    .unwrap();
    let bad = text.replacen("mode = \"rotating\"", "mode = \"reaming\"", 1);
    let bad = bad.replacen("rpm = \"120 rpm\"", "", 1);
    let e = holewall::case::parse_case(std::path::Path::new("r.toml"), &bad).unwrap_err();
    assert!(e.to_string().contains("operation.rpm"), "{e}");
    // Reaming takes the coupled friction unless told; told split, it warns.
    let reaming = text.replacen("mode = \"rotating\"", "mode = \"reaming\"", 1);
    let case = holewall::case::parse_case(std::path::Path::new("r.toml"), &reaming).unwrap();
    assert_eq!(
        case.model.friction,
        holewall::physics::contact::FrictionModel::Coupled
    );
    assert!(case.warnings.is_empty());
    let split = reaming.replacen("[contact]", "[contact]\nfriction_model = \"split\"", 1);
    let case = holewall::case::parse_case(std::path::Path::new("r.toml"), &split).unwrap();
    assert_eq!(
        case.model.friction,
        holewall::physics::contact::FrictionModel::Split
    );
    assert!(
        case.warnings.iter().any(|w| w.contains("coupled")),
        "{:?}",
        case.warnings
    );
    let unknown = text.replacen("mode = \"rotating\"", "mode = \"washing\"", 1);
    let e = holewall::case::parse_case(std::path::Path::new("r.toml"), &unknown).unwrap_err();
    assert!(e.to_string().contains("back_reaming"), "{e}");
}

#[test]
fn an_ensemble_mixing_reaming_and_rotating_runs_each_with_its_friction() {
    // The engine serves one friction model; a grid of rotating (split) and reaming
    // (coupled) variants goes to the CPU, saying why, with the results of single runs.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
    )
    .unwrap();
    let text = text.replacen(
        "rpm = \"120 rpm\"",
        "rpm = \"120 rpm\"\naxial_speed = \"0.1 m/s\"",
        1,
    );
    let text = format!("{text}\n[ensemble]\n[ensemble.grid]\nmode = [\"rotating\", \"reaming\"]\n");
    let dir = common::scratch_dir("torque_drag", "mixed");
    let path = dir.join("mixed.toml");
    std::fs::write(&path, &text).unwrap();
    let out = dir.join("out");
    let (code, _, stderr) = common::holewall(&[
        "ensemble",
        path.to_str().unwrap(),
        "--backend",
        "gpu",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    if code != 0 && stderr.contains("no GPU adapter") {
        eprintln!("NO GPU ADAPTER: the engine half of this test did not run");
        return;
    }
    assert_eq!(code, 0, "{stderr}");
    let hooks = common::variants_column(&out, "hook_load_n");
    let case = holewall::case::load_case(&path).unwrap();
    for (k, mode) in ["rotating", "reaming"].iter().enumerate() {
        let single = off_bottom_like(&case, mode);
        assert!(
            (hooks[k] / single - 1.0).abs() < 1e-9,
            "{mode}: {} vs {single}",
            hooks[k]
        );
    }
}

/// The case's hook load solved alone in `mode` (its own friction model by default).
fn off_bottom_like(case: &holewall::case::Case, mode: &str) -> f64 {
    let text = std::fs::read_to_string(&case.path).unwrap();
    let text = text.replacen("mode = \"rotating\"", &format!("mode = \"{mode}\""), 1);
    let c = holewall::case::parse_case(&case.path, &text).unwrap();
    let sol = holewall::solve::statics::solve_static(&c.model, &Default::default()).unwrap();
    holewall::profile::fe_rows(&c.model, &sol).1
}

#[test]
fn friction_per_hole_section_as_variant_keys() {
    use holewall::ensemble::{apply, Key, Value, Variant};
    // build_and_hold: 9⅝ in casing to 500 m (μ 0.2), 8½ in open hole below (μ 0.3).
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml");
    let case = holewall::case::load_case(&path).unwrap();
    let variant = Variant {
        name: "v".into(),
        overrides: vec![
            (Key::parse("mu.cased").unwrap(), Value::Number(0.1)),
            (Key::parse("mu.open").unwrap(), Value::Number(0.45)),
        ],
    };
    let m = apply(&case, &variant).unwrap();
    for s in &m.sites {
        let md = m.nodes[s.node].md;
        let want = if md <= 500.0 + 1e-9 { 0.1 } else { 0.45 };
        assert_eq!((s.params.mu_t, s.params.mu_l), (want, want), "MD {md}");
    }
    // The same as the case written with those friction factors.
    let text = std::fs::read_to_string(&path).unwrap();
    let edited = text
        .replacen("friction = 0.2", "friction = 0.1", 1)
        .replacen("friction = 0.3", "friction = 0.45", 1);
    let written = holewall::case::parse_case(&path, &edited).unwrap();
    let hook = |m: &holewall::model::Model| {
        let sol = holewall::solve::statics::solve_static(m, &Default::default()).unwrap();
        holewall::profile::fe_rows(m, &sol).1
    };
    let (a, b) = (hook(&m), hook(&written.model));
    assert!((a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
    // By section number: hole2 is the open hole here; a third section does not exist.
    let v2 = Variant {
        name: "v2".into(),
        overrides: vec![(Key::parse("mu_l.hole2").unwrap(), Value::Number(0.05))],
    };
    let m2 = apply(&case, &v2).unwrap();
    assert!(m2
        .sites
        .iter()
        .all(|s| (m2.nodes[s.node].md > 500.0) == (s.params.mu_l == 0.05)));
    let v3 = Variant {
        name: "v3".into(),
        overrides: vec![(Key::parse("mu.hole3").unwrap(), Value::Number(0.2))],
    };
    let e = apply(&case, &v3).unwrap_err().to_string();
    assert!(
        e.contains("mu.hole3") && e.contains("2 [[hole]] sections"),
        "{e}"
    );
    // Malformed section keys are refused with the key forms.
    for bad in ["mu.hole0", "mu.casing", "wob.cased"] {
        let e = Key::parse(bad).unwrap_err().to_string();
        assert!(e.contains(".cased"), "{bad}: {e}");
    }
}

#[test]
fn two_fluid_columns_buoy_the_string_by_their_own_densities() {
    // 1,000 m vertical: 900 m of 5 in × 4.276 in pipe on 100 m of 6½ × 2 13/16 in collars,
    // frictionless, off bottom: the hook load is the string's weight in the two fluids,
    // g Σ L (ρ_s A_s + ρ_i A_i − ρ_o A_o) — a heavy pill inside (1.8 sg) against 1.2 sg
    // outside weighs more than 1.2 sg throughout.
    let case = |inside: &str| {
        let text = format!(
            r#"title = "two fluids"
[well]
profile = "vertical"
total_md = "1000 m"
[[hole]]
bottom_md = "1000 m"
diameter = "8.5 in"
friction = 0.0
[mud]
density = "1.2 sg"
{inside}
[[string]]
kind = "collar"
length = "100 m"
od = "6.5 in"
id = "2.8125 in"
[[string]]
kind = "drill_pipe"
length = "900 m"
od = "5 in"
id = "4.276 in"
[operation]
mode = "tripping_out"
"#
        );
        holewall::case::parse_case(std::path::Path::new("two.toml"), &text).unwrap()
    };
    let g = holewall::model::GRAVITY;
    let area = |od: f64, id: f64| std::f64::consts::FRAC_PI_4 * (od * od - id * id);
    let weight = |rho_i: f64, rho_o: f64| {
        let part = |l: f64, od: f64, id: f64| {
            let (bore, outer) = (
                std::f64::consts::FRAC_PI_4 * id * id,
                std::f64::consts::FRAC_PI_4 * od * od,
            );
            g * l * (7850.0 * area(od, id) + rho_i * bore - rho_o * outer)
        };
        part(100.0, 0.1651, 0.0714375) + part(900.0, 0.127, 0.1086104)
    };
    for (inside, rho_i) in [("", 1200.0), ("inside_density = \"1.8 sg\"", 1800.0)] {
        let c = case(inside);
        let expected = weight(rho_i, 1200.0);
        let sol = holewall::solve::statics::solve_static(&c.model, &Default::default()).unwrap();
        let fe = holewall::profile::fe_rows(&c.model, &sol).1;
        let soft = c.soft_string().hook_load();
        println!(
            "inside {rho_i}: FE {fe:.1} N, soft string {soft:.1} N, closed form {expected:.1} N"
        );
        assert!((fe / expected - 1.0).abs() < 1e-6, "FE {fe} vs {expected}");
        assert!(
            (soft / expected - 1.0).abs() < 1e-6,
            "soft {soft} vs {expected}"
        );
    }
    // A bare number in the wrong unit is caught like mud.density.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
    )
    .unwrap();
    let bad = text.replacen("[mud]\n", "[mud]\ninside_density = \"12 sg\"\n", 1);
    let e = holewall::case::parse_case(std::path::Path::new("b.toml"), &bad).unwrap_err();
    assert!(e.to_string().contains("mud.inside_density"), "{e}");
}

/// A straight 30° hole of 2,000 m from the surface (8½ in, μ 0.25), 5 in × 4.276 in drill pipe to the
/// surface from the bit, rotating off bottom at 60 rpm; `joints` adds to the pipe.
fn straight_pipe(joints: &str, element: &str) -> holewall::case::Case {
    let text = format!(
        r#"title = "straight pipe"
[[hole]]
bottom_md = "2000 m"
diameter = "8.5 in"
friction = 0.25
[well]
profile = "survey"
total_md = "2000 m"
survey = "straight.csv"
[mud]
density = "1.2 sg"
[[string]]
kind = "drill_pipe"
length = "2000 m"
od = "5 in"
id = "4.276 in"
{joints}
[operation]
mode = "rotating"
rpm = "60 rpm"
[contact]
sites = "all_nodes"
[mesh]
element_length = "{element}"
"#
    );
    let dir = common::scratch_dir("torque_drag", "straight");
    std::fs::write(
        dir.join("straight.csv"),
        "md,inclination,azimuth\n0,30,0\n2000,30,0\n",
    )
    .unwrap();
    holewall::case::parse_case(&dir.join("straight.toml"), &text).unwrap()
}

#[test]
fn tool_joints_carry_the_contact_and_the_torque_arm() {
    let joints = "tool_joint_od = \"6.625 in\"\ntool_joint_length = \"0.45 m\"";
    let body = straight_pipe("", "9.144 m");
    let tj = straight_pipe(joints, "10 m");
    // A node at every joint (2000 m in 219 joints of 9.13 m), each a contact site of the
    // joint's diameter.
    let m = &tj.model;
    assert_eq!(m.elements.len(), 219);
    assert!(m
        .sites
        .iter()
        .all(|s| (2.0 * s.params.disk_radius - 0.168275).abs() < 1e-9));
    // The joints' steel: π/4 (6⅝² − 5²) in² × 0.45/9.144 of the body's length, buoyed.
    let e = &m.elements[0];
    let extra =
        std::f64::consts::FRAC_PI_4 * (0.168275f64.powi(2) - 0.127f64.powi(2)) * (0.45 / 9.144);
    let w_body = body.model.elements[0].buoyed_weight_per_length;
    let expected_w = w_body + holewall::model::GRAVITY * (7850.0 - 1200.0) * extra;
    assert!((e.buoyed_weight_per_length / expected_w - 1.0).abs() < 1e-12);
    // Rotating off bottom in a straight hole: torque = μ w sin I L r (the soft string exactly;
    // the arm is the joint's radius). The FE's rotating pipe climbs the wall until friction
    // and the normal force balance the weight, N = w sin I / √(1 + μ²): its torque is that
    // much lower, within 2 % (the lift-off at the clamped top and the held bit).
    for (case, r) in [(&body, 0.0635), (&tj, 0.5 * 0.168275)] {
        let w = case.model.elements[0].buoyed_weight_per_length;
        let closed = 0.25 * w * 0.5 * 2000.0 * r;
        let soft = case.soft_string().surface_torque();
        let sol = holewall::solve::statics::solve_static(&case.model, &Default::default()).unwrap();
        let fe = holewall::profile::fe_rows(&case.model, &sol).2;
        println!(
            "arm {r} m: torque closed form {closed:.1}, soft string {soft:.1}, FE {fe:.1} N·m"
        );
        assert!(
            (soft / closed - 1.0).abs() < 1e-3,
            "soft {soft} vs {closed}"
        );
        let climbing = closed / (1.0f64 + 0.25 * 0.25).sqrt();
        assert!((fe / climbing - 1.0).abs() < 0.02, "FE {fe} vs {climbing}");
    }
    // Finer than a joint: body nodes between the joints touch with the body's radius.
    let fine = straight_pipe(joints, "3 m");
    let m = &fine.model;
    assert_eq!(m.elements.len(), 219 * 3);
    let radii: Vec<f64> = m.sites.iter().map(|s| 2.0 * s.params.disk_radius).collect();
    let at_joints = radii
        .iter()
        .filter(|d| (**d - 0.168275).abs() < 1e-9)
        .count();
    assert_eq!(at_joints, 219, "{at_joints}");
    assert_eq!(
        radii.iter().filter(|d| (**d - 0.127).abs() < 1e-9).count(),
        219 * 2
    );
}

#[test]
fn tool_joint_keys_are_checked() {
    let cases = [
        ("tool_joint_od = \"4.5 in\"", "string.tool_joint_od"),
        ("tool_joint_od = \"9 in\"", "string.tool_joint_od"),
        ("joint_spacing = \"9 m\"", "string.joint_spacing"),
        (
            "tool_joint_od = \"6.625 in\"\njoint_spacing = \"40 m\"",
            "string.joint_spacing",
        ),
    ];
    for (keys, key) in cases {
        let text = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
        )
        .unwrap();
        let text = text.replacen(
            "kind = \"drill_pipe\"",
            &format!("kind = \"drill_pipe\"\n{keys}"),
            1,
        );
        let e = holewall::case::parse_case(std::path::Path::new("tj.toml"), &text).unwrap_err();
        assert!(e.to_string().contains(key) && e.line > 0, "{e}");
    }
}

#[test]
fn the_tool_joint_broomstick_orders_its_modes() {
    // cases/broomstick_tool_joints.toml: 6 depths × 5 modes × 3 open-hole friction factors,
    // every variant converged; at every depth and friction the hook load runs tripping out
    // > back-reaming > rotating > reaming > tripping in.
    let case = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/broomstick_tool_joints.toml"
    );
    let out = common::scratch_dir("torque_drag", "broomstick");
    let measured = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/broomstick_measured.csv");
    // A bad measured file is refused (exit 2, file and line) before anything is written.
    let bad = common::scratch_dir("torque_drag", "broomstick_bad").with_extension("csv");
    std::fs::write(
        &bad,
        "bit_md_m,mode,hook_load_kn\n700,pick_up,600\n900,spinning,640\n",
    )
    .unwrap();
    std::fs::remove_dir_all(&out).unwrap();
    let (code, _, stderr) = common::holewall(&[
        "ensemble",
        case,
        "--measured",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains(&format!("{}:3", bad.display())) && stderr.contains("spinning"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing is written for a refused run");
    let (code, _, stderr) = common::holewall(&[
        "ensemble",
        case,
        "--backend",
        "cpu",
        "--measured",
        measured,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
    // The measurements over the hook-load and torque broomsticks.
    let summary: serde_json::Value = common::json(&out.join("summary.json"));
    for f in ["broomstick.png", "broomstick_torque.png"] {
        assert!(summary["outputs"]
            .as_array()
            .unwrap()
            .iter()
            .any(|o| o == f));
        assert!(out.join(f).exists(), "{f}");
    }
    let text = std::fs::read_to_string(out.join("variants.csv")).unwrap();
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let header = rows.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (depth, mode, mu, status, hook, reading) = (
        col("depth"),
        col("mode"),
        col("mu.open"),
        col("status"),
        col("hook_load_n"),
        col("weight_indicator_n"),
    );
    // The case's rig: an 80 klbf block on 10 lines, K = 0.99, a dead-line indicator.
    let rig = holewall::rig::Rig {
        block_weight_n: 80e3 * 4.448_221_615_260_5,
        lines: 10,
        sheave_efficiency: 0.99,
        ..Default::default()
    };
    let mut loads = std::collections::BTreeMap::new();
    for r in rows.records() {
        let r = r.unwrap();
        assert_eq!(&r[status], "converged");
        let (h, w): (f64, f64) = (r[hook].parse().unwrap(), r[reading].parse().unwrap());
        let travel = match &r[mode] {
            "tripping_out" | "back_reaming" => holewall::rig::Travel::Hoisting,
            "tripping_in" | "reaming" => holewall::rig::Travel::Lowering,
            _ => holewall::rig::Travel::AtRest,
        };
        let want = rig.reading(h, travel).weight_indicator_n;
        assert!(
            (w - want).abs() < 1e-6 * want,
            "{}: {w} vs {want}",
            &r[mode]
        );
        match travel {
            holewall::rig::Travel::Hoisting => assert!(w < h + rig.block_weight_n),
            holewall::rig::Travel::Lowering => assert!(w > h + rig.block_weight_n),
            holewall::rig::Travel::AtRest => {
                assert!((w - h - rig.block_weight_n).abs() < 1e-6 * w)
            }
        }
        loads.insert(
            (r[depth].to_string(), r[mu].to_string(), r[mode].to_string()),
            r[hook].parse::<f64>().unwrap(),
        );
    }
    assert_eq!(loads.len(), 90);
    let order = [
        "tripping_out",
        "back_reaming",
        "rotating",
        "reaming",
        "tripping_in",
    ];
    for ((d, m, _), _) in loads.iter().filter(|((_, _, mode), _)| mode == "rotating") {
        let h: Vec<f64> = order
            .iter()
            .map(|o| loads[&(d.clone(), m.clone(), o.to_string())])
            .collect();
        assert!(h.windows(2).all(|w| w[0] > w[1]), "depth {d}, μ {m}: {h:?}");
    }
}

#[test]
fn pipe_strength_matches_api_rp_7g_tables() {
    use holewall::strength::{PipeStrength, GRADES};
    // 5 in 19.50 lb/ft drill pipe (ID 4.276 in), G-105: API RP 7G's tables give a tensile
    // yield of 553,833 lbf new and 436,150 lbf premium (80 % wall), a torsional yield of
    // 57,633 ft·lbf new (E-75: 41,167).
    let (lbf, ftlbf, inch) = (4.448_221_615, 1.355_817_948, 0.0254);
    let grade = |name: &str| GRADES.iter().find(|g| g.0 == name).unwrap().1;
    let new = PipeStrength::new("G105", grade("G105"), 1.0, 5.0 * inch, 4.276 * inch);
    let premium = PipeStrength::new("G105", grade("G105"), 0.8, 5.0 * inch, 4.276 * inch);
    let e75 = PipeStrength::new("E75", grade("E75"), 1.0, 5.0 * inch, 4.276 * inch);
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    assert!(
        rel(new.tensile_yield_n() / lbf, 553_833.0) < 1e-3,
        "{}",
        new.tensile_yield_n() / lbf
    );
    assert!(
        rel(premium.tensile_yield_n() / lbf, 436_150.0) < 1e-3,
        "{}",
        premium.tensile_yield_n() / lbf
    );
    assert!(
        rel(new.torque_limit_nm(0.0) / ftlbf, 57_633.0) < 2e-3,
        "{}",
        new.torque_limit_nm(0.0) / ftlbf
    );
    assert!(rel(e75.torque_limit_nm(0.0) / ftlbf, 41_167.0) < 2e-3);
    // The envelope closes at the tensile yield; von Mises of pure tension is F/A.
    assert_eq!(new.torque_limit_nm(new.tensile_yield_n()), 0.0);
    let (area, _, _) = new.section();
    assert!(rel(new.von_mises_pa(1e6, 0.0, 0.0), 1e6 / area) < 1e-12);
    // At the torque limit under tension P, von Mises equals the yield.
    let p = 0.5 * new.tensile_yield_n();
    let q = new.torque_limit_nm(p);
    assert!(rel(new.von_mises_pa(p, 0.0, q), new.yield_pa) < 1e-12);
}

#[test]
fn pressure_enters_the_von_mises_stress_by_lame() {
    use holewall::strength::{true_axial_force, PipeStrength};
    let (od, id) = (5.0 * 0.0254, 4.276 * 0.0254);
    let pipe = PipeStrength::new("G105", 105_000.0 * 6_894.757, 1.0, od, id);
    let (area, _, _) = pipe.section();
    // The bottom of a string hanging in one mud (F_eff = 0) at 3,000 m TVD: true force
    // −p A_s, radial and hoop stresses −p: a hydrostatic state, no von Mises stress.
    let rho = 1200.0;
    let p = rho * holewall::model::GRAVITY * 3000.0;
    let f = true_axial_force(0.0, 3000.0, (rho, rho), od, id);
    assert!((f + p * area).abs() < 1e-9 * p * area);
    assert!(pipe.von_mises_triaxial_pa(f, 0.0, 0.0, p, p) < 1e-6 * p);
    // 30 MPa inside, nothing outside, no axial stress: the inner fibre's hoop stress
    // p (r_o² + r_i²)/(r_o² − r_i²) and radial −p (Lamé) give
    // σ_vm = √(½((σ_θ)² + (σ_θ + p)² + p²)).
    let pi = 30e6;
    let (ro, ri) = (0.5 * od, 0.5 * id);
    let hoop = pi * (ro * ro + ri * ri) / (ro * ro - ri * ri);
    let want = (0.5 * (hoop * hoop + (hoop + pi).powi(2) + pi * pi)).sqrt();
    let got = pipe.von_mises_triaxial_pa(0.0, 0.0, 0.0, pi, 0.0);
    assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
    // Two fluid columns: 1.8 sg inside, 1.2 sg outside, F_eff = 0 at 2,000 m: the true force
    // −p_o A_o + p_i A_i.
    let (po, pin) = (1200.0 * 9.80665 * 2000.0, 1800.0 * 9.80665 * 2000.0);
    let q = std::f64::consts::FRAC_PI_4;
    let f2 = true_axial_force(0.0, 2000.0, (1200.0, 1800.0), od, id);
    assert!((f2 - (-po * q * od * od + pin * q * id * id)).abs() < 1e-6 * po * area);
}

#[test]
fn static_reports_the_strength_of_graded_pipe() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
    )
    .unwrap();
    let graded = text.replacen(
        "kind = \"drill_pipe\"",
        "kind = \"drill_pipe\"\ngrade = \"G105\"\nwear = \"premium\"",
        1,
    );
    let dir = common::scratch_dir("torque_drag", "strength");
    let path = dir.join("graded.toml");
    std::fs::write(&path, graded).unwrap();
    let out = dir.join("out");
    let (code, stdout, stderr) = common::holewall(&[
        "static",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let s: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let st = &s["strength"];
    let u = st["max_utilisation"].as_f64().unwrap();
    let hook = s["hook_load_n"].as_f64().unwrap();
    let yield_n = st["top_tensile_yield_n"].as_f64().unwrap();
    println!("{st}");
    // The hook load over the premium pipe's yield bounds the utilisation from below (the
    // top carries the largest tension; bending and torque add).
    assert!(
        u >= hook / yield_n * 0.999 && u < 1.0,
        "{u} vs {}",
        hook / yield_n
    );
    assert!((st["overpull_margin_n"].as_f64().unwrap() - (0.9 * yield_n - hook)).abs() < 1e-6);
    assert!(out.join("tension_torque.png").is_file());
    let profile = std::fs::read_to_string(out.join("profile.csv")).unwrap();
    assert!(profile
        .lines()
        .next()
        .unwrap()
        .contains("yield_utilisation"));
    // An unknown grade names the key.
    let bad = text.replacen(
        "kind = \"drill_pipe\"",
        "kind = \"drill_pipe\"\ngrade = \"P110\"",
        1,
    );
    let e = holewall::case::parse_case(&path, &bad).unwrap_err();
    assert!(e.to_string().contains("string.grade"), "{e}");
}

#[test]
fn the_rig_reads_block_weight_and_dead_line_and_checks_its_keys() {
    // Tripping out of cases/build_and_hold.toml with a 350 kN block on 8 lines: summary.json
    // carries the line tensions and the dead-line reading of `holewall::rig`.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/build_and_hold.toml"),
    )
    .unwrap();
    let start = text.find("[operation]").unwrap();
    let end = start + text[start..].find("\n\n").unwrap();
    let op = "[operation]\nmode = \"tripping_out\"\naxial_speed = \"0.3 m/s\"\n\n[rig]\n\
              block_weight = \"350 kN\"\nlines = 8\n";
    let with_rig = format!("{}{}{}", &text[..start], op, &text[end..]);
    let dir = common::scratch_dir("torque_drag", "rig");
    let path = dir.join("rig.toml");
    std::fs::write(&path, &with_rig).unwrap();
    let (code, stdout, stderr) = common::holewall(&[
        "static",
        path.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let s: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let rig = &s["rig"];
    let hook = s["hook_load_n"].as_f64().unwrap();
    assert_eq!(rig["travel"], "hoisting");
    assert!((rig["hook_load_n"].as_f64().unwrap() - (hook + 350e3)).abs() < 1e-6 * hook);
    // Hoisting on 8 lines at K = 0.9615: the fast line is W/(E n), E = 0.842 (Bourgoyne et
    // al. Table 1.2); the dead line reads 8 K^7 (1 − K)/(1 − K^8) W.
    let w = hook + 350e3;
    let fast = rig["fast_line_n"].as_f64().unwrap();
    assert!((fast - w / (0.842 * 8.0)).abs() < 1e-3 * fast, "{fast}");
    let k: f64 = 0.9615;
    let closed = 8.0 * k.powi(7) * (1.0 - k) / (1.0 - k.powi(8)) * w;
    let reads = rig["weight_indicator_n"].as_f64().unwrap();
    assert!((reads - closed).abs() < 1e-9 * w, "{reads} vs {closed}");
    // Bad keys name the key and the line.
    for (bad, key) in [
        ("lines = 7", "rig.lines"),
        ("sheave_efficiency = 0.5", "rig.sheave_efficiency"),
        ("weight_indicator = \"drum\"", "rig.weight_indicator"),
        ("block_weight = \"-1 kN\"", "rig.block_weight"),
    ] {
        let text = match bad.split(' ').next().unwrap() {
            "lines" => with_rig.replace("lines = 8\n", &format!("{bad}\n")),
            "block_weight" => with_rig.replace("block_weight = \"350 kN\"", bad),
            _ => with_rig.replace("[rig]\n", &format!("[rig]\n{bad}\n")),
        };
        let e = holewall::case::parse_case(&path, &text).unwrap_err();
        assert!(e.to_string().contains(key) && e.line > 0, "{e}");
    }
}

#[test]
fn field_units_translate_every_output() {
    // `holewall static --units field` against the SI run: the same numbers in ft, klbf,
    // kft·lbf; profile.csv's columns renamed and scaled; `--units si` is the default.
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/build_and_hold.toml");
    let dir = common::scratch_dir("torque_drag", "units");
    let run = |units: &str, out: &str| {
        let (code, stdout, stderr) = common::holewall(&[
            "static",
            case,
            "--out",
            dir.join(out).to_str().unwrap(),
            "--quiet",
            "--units",
            units,
        ]);
        assert_eq!(code, 0, "{stderr}");
        serde_json::from_str::<serde_json::Value>(&stdout).unwrap()
    };
    let si = run("si", "si");
    let field = run("field", "field");
    let lbf = 4.448_221_615_260_5;
    let ft = 0.3048;
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
    assert!(close(
        field["hook_load_klbf"].as_f64().unwrap() * 1e3 * lbf,
        si["hook_load_n"].as_f64().unwrap()
    ));
    assert!(close(
        field["surface_torque_kftlbf"].as_f64().unwrap() * 1e3 * lbf * ft,
        si["surface_torque_nm"].as_f64().unwrap()
    ));
    assert!(close(
        field["neutral_point_from_bit_ft"].as_f64().unwrap() * ft,
        si["neutral_point_from_bit_m"].as_f64().unwrap()
    ));
    // summary.json on disk as printed.
    let on_disk: serde_json::Value = common::json(&dir.join("field/summary.json"));
    assert_eq!(on_disk["hook_load_klbf"], field["hook_load_klbf"]);
    let read = |out: &str| {
        let text = std::fs::read_to_string(dir.join(out).join("profile.csv")).unwrap();
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let h: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
        let last: Vec<String> = r
            .records()
            .last()
            .unwrap()
            .unwrap()
            .iter()
            .map(String::from)
            .collect();
        (h, last)
    };
    let ((hs, rs), (hf, rf)) = (read("si"), read("field"));
    assert_eq!(hf[0], "md_ft");
    assert!(hf.contains(&"axial_force_klbf".to_string()));
    assert!(hf.contains(&"side_force_per_length_lbf_per_ft".to_string()));
    let col = |h: &[String], name: &str| h.iter().position(|x| x == name).unwrap();
    let md_si: f64 = rs[col(&hs, "md_m")].parse().unwrap();
    let md_f: f64 = rf[col(&hf, "md_ft")].parse().unwrap();
    assert!(close(md_f * ft, md_si));
    let t_si: f64 = rs[col(&hs, "torque_nm")].parse().unwrap();
    let t_f: f64 = rf[col(&hf, "torque_kftlbf")].parse().unwrap();
    assert!((t_f * 1e3 * lbf * ft - t_si).abs() <= 1e-9 * t_si.abs().max(1.0));
    // A bad unit system is refused by the argument parser (exit code 2).
    let (code, _, _) = common::holewall(&["static", case, "--out", "x", "--units", "imperial"]);
    assert_eq!(code, 2);
}

#[test]
fn the_tool_joint_make_up_torque_is_checked_along_the_string() {
    // The shipped broomstick case's pipe has NC50 joints made up to 36,000 ft·lbf: the
    // summary's utilisation is the largest |torque| along the pipe over that torque (the
    // profile's torque column; the collars below carry no make-up torque), and bad keys are
    // refused with their line.
    let case = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/broomstick_tool_joints.toml"
    );
    let out = common::scratch_dir("torque_drag", "makeup");
    let (code, _, stderr) =
        common::holewall(&["static", case, "--out", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 0, "{stderr}");
    let summary: serde_json::Value = common::json(&out.join("summary.json"));
    let u = summary["strength"]["max_makeup_torque_utilisation"]
        .as_f64()
        .unwrap();
    let makeup = 36_000.0 * 4.448_221_615_260_5 * 0.3048;
    let text = std::fs::read_to_string(out.join("profile.csv")).unwrap();
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let header = rows.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (md, torque) = (col("md_m"), col("torque_nm"));
    // The pipe is the top 1,410 m of the 1,500 m string.
    let worst = rows
        .records()
        .map(|r| r.unwrap())
        .filter(|r| r[md].parse::<f64>().unwrap() <= 1410.0 - 1e-6)
        .map(|r| r[torque].parse::<f64>().unwrap().abs())
        .fold(0.0f64, f64::max);
    assert!(worst > 0.0);
    assert!(
        (u - worst / makeup).abs() < 1e-9 * u.max(1e-12),
        "{u} vs {}",
        worst / makeup
    );
    // Refused: without a grade, without tool joints, out of range.
    let base = std::fs::read_to_string(case).unwrap();
    for (edit, key) in [
        (
            base.replace("grade = \"G105\"\nwear = \"premium\"\n", ""),
            "string.tool_joint_makeup_torque",
        ),
        (
            base.replace("tool_joint_od = \"6.625 in\"     # NC50\n", "")
                .replace("tool_joint_length = \"0.45 m\"\n", "")
                .replace("joint_spacing = \"30 ft\"\n", ""),
            "string.tool_joint_makeup_torque",
        ),
        (
            base.replace("\"36000 ft.lbf\"", "\"10 N.m\""),
            "string.tool_joint_makeup_torque",
        ),
    ] {
        let e = holewall::case::parse_case(std::path::Path::new("tj.toml"), &edit).unwrap_err();
        assert!(e.key == key && e.line > 0, "{e}");
    }
}

/// A depth and mode variant's case is built from the case's tables edited in place (no file
/// read again): the same model, to the bit, as the case file with `total_md` and `mode`
/// rewritten by hand; a depth past the hole is refused with the key.
#[test]
fn a_depth_and_mode_variant_is_the_case_file_edited() {
    use holewall::ensemble::{variant_case, Variant};
    use holewall::keys::Key;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/broomstick.toml");
    let case = holewall::case::load_case(&path).unwrap();
    let key = |name: &str, text: &str| {
        let k = Key::parse(name).unwrap();
        let v = k.value(text).unwrap();
        (k, v)
    };
    let variant = Variant {
        name: "v".into(),
        overrides: vec![key("depth", "1200 m"), key("mode", "tripping_in")],
    };
    let rebuilt = variant_case(&case, &variant)
        .unwrap()
        .expect("a rebuilt case");
    let text = std::fs::read_to_string(&path).unwrap();
    let edited = text
        .replace("total_md = \"1500 m\"", "total_md = \"1200 m\"")
        .replace("mode = \"rotating\"", "mode = \"tripping_in\"")
        .replace("rpm = \"120 rpm\"\n", "");
    assert_ne!(edited, text);
    let by_hand = holewall::case::parse_case(&path, &edited).unwrap();
    let (a, b) = (&rebuilt.model, &by_hand.model);
    assert_eq!(a.nodes.len(), b.nodes.len());
    assert_eq!(a.sites.len(), b.sites.len());
    for (p, q) in a.nodes.iter().zip(&b.nodes) {
        assert_eq!(p.md, q.md);
        assert_eq!(p.position, q.position);
    }
    assert_eq!(rebuilt.bit_md, 1200.0);
    assert_eq!(
        (a.axial_speed, a.rotation_speed, a.weight_on_bit),
        (b.axial_speed, b.rotation_speed, b.weight_on_bit)
    );
    assert!(a.axial_speed != 0.0, "tripping moves the pipe");
    assert_eq!(a.rotation_speed, 0.0, "a tripping variant does not rotate");
    // Deeper than the survey/hole allows: the variant is refused, naming the key.
    let deep = Variant {
        name: "deep".into(),
        overrides: vec![key("depth", "1600 m")],
    };
    let e = variant_case(&case, &deep).unwrap_err().to_string();
    assert!(e.contains("above the bit at 1600 m"), "{e}");
    println!("{e}");
}
