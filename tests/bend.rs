//! Bent subs and bent housings (issue 16): a stress-free kink of the string, against closed
//! forms in statics and as a whirl trigger in dynamics.

use holewall::model::{Bend, Model};
use holewall::solve::dynamics::{AlphaParams, DynamicOptions, Dynamics};
use holewall::solve::statics::{solve_static, StaticOptions, StaticState};

#[path = "common/mod.rs"]
mod common;

/// The direction a bend at `node` with `toolface` points the string below it (the node's
/// reference second axis turned towards its third).
fn bend_direction(m: &Model, node: usize, toolface: f64) -> [f64; 3] {
    let f = &m.nodes[node].frame0;
    std::array::from_fn(|k| toolface.cos() * f[k][1] + toolface.sin() * f[k][2])
}

fn lateral(s: &StaticState, i: usize) -> [f64; 3] {
    s.u[i]
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A weightless 10 m collar clamped at the top, held laterally at the bit, with a kink of
/// `angle` at `a` metres below the top (node `a`/1 m): the kink is a relative rotation of the
/// two parts, so the clamped–pinned beam takes a bending moment `V (x − L)` with
/// `V = 3 EI α (L − a)/L³` (the bit's lateral reaction; the top moment `V L`) and the kink
/// moves by `V a² (3L − a)/(6 EI)` against the bend's direction.
#[test]
fn a_kink_in_a_clamped_pinned_collar_takes_the_closed_form_moment() {
    let l = 10.0;
    for (a_node, toolface, angle_deg) in [(4usize, 0.7f64, 0.2f64), (7, -2.0, 0.2), (4, 0.7, 1.0)] {
        let mut m = common::weightless_collar(l, 10);
        let angle = angle_deg.to_radians();
        m.bends = vec![Bend {
            node: a_node,
            angle,
            toolface,
        }];
        let a = m.nodes[a_node].md;
        let ei = m.elements[0].section.bending_stiffness();
        let v = 3.0 * ei * angle * (l - a) / l.powi(3);
        let kink_move = v * a * a * (3.0 * l - a) / (6.0 * ei);
        let sol = solve_static(&m, &StaticOptions::default()).unwrap();
        let d = bend_direction(&m, a_node, toolface);
        let bit_force = [
            sol.bit_reaction[0],
            sol.bit_reaction[1],
            sol.bit_reaction[2],
        ];
        let top_moment = [
            sol.top_reaction[3],
            sol.top_reaction[4],
            sol.top_reaction[5],
        ];
        let w = lateral(&sol.state, a_node);
        let w_along = dot(&w, &d);
        let f_len = dot(&bit_force, &bit_force).sqrt();
        let m_len = dot(&top_moment, &top_moment).sqrt();
        // The moment at the kink, from the element above it (node 2) and below (node 1).
        let m_kink = sol.section_forces[a_node - 1].bending[1];
        eprintln!(
            "kink {angle_deg}° at {a} m, toolface {toolface}: bit reaction {f_len:.3} N vs {v:.3} N, top moment {m_len:.3} vs {:.3} N·m, kink moment {m_kink:.3} vs {:.3}, kink moved {:.4} mm vs {:.4} mm",
            v * l,
            v * (l - a),
            1e3 * w_along,
            -1e3 * kink_move
        );
        // Measured: ≤ 2e-6 at 0.2°, 1.2e-5 at 1° (geometric nonlinearity, O(α²)).
        let tol = 3e-5;
        assert!((f_len / v - 1.0).abs() < tol, "bit reaction {f_len} vs {v}");
        assert!((m_len / (v * l) - 1.0).abs() < tol, "top moment {m_len}");
        assert!(
            (m_kink / (v * (l - a)) - 1.0).abs() < tol,
            "kink moment {m_kink}"
        );
        assert!(
            (w_along / -kink_move - 1.0).abs() < tol,
            "kink displacement {w_along} vs {}",
            -kink_move
        );
        // The bit is pushed back towards the bend: its reaction points against d.
        assert!(dot(&bit_force, &d) < -0.999 * f_len);
        assert!(dot(&w, &w).sqrt() < (1.0 + tol) * w_along.abs());
    }
}

/// The same collar with the bit free: a kink in a statically determinate string stresses
/// nothing; the part below turns rigidly by the angle.
#[test]
fn a_kink_in_a_cantilever_turns_the_part_below_rigidly() {
    let l = 10.0;
    let mut m = common::weightless_collar(l, 10);
    m.bit_lateral_fixed = false;
    let (node, angle, toolface) = (6usize, 2f64.to_radians(), 2.5);
    m.bends = vec![Bend {
        node,
        angle,
        toolface,
    }];
    let sol = solve_static(&m, &StaticOptions::default()).unwrap();
    let d = bend_direction(&m, node, toolface);
    let bit = m.nodes.len() - 1;
    let below = l - m.nodes[node].md;
    let w = lateral(&sol.state, bit);
    let axis = m.nodes[bit].hole_axis;
    let expect_lateral = below * angle.sin();
    let expect_axial = -below * (1.0 - angle.cos());
    eprintln!(
        "cantilever, 2° kink {below} m above the tip: tip moves {:.6} mm sideways (closed form {:.6}), {:.6} mm along (closed form {:.6}); largest moment {:.2e} N·m",
        1e3 * dot(&w, &d),
        1e3 * expect_lateral,
        1e3 * dot(&w, &axis),
        1e3 * expect_axial,
        sol.section_forces
            .iter()
            .fold(0.0f64, |a, s| a.max(s.bending[0]).max(s.bending[1]))
    );
    assert!((dot(&w, &d) - expect_lateral).abs() < 1e-9);
    assert!((dot(&w, &axis) - expect_axial).abs() < 1e-9);
    for s in &sol.section_forces {
        assert!(
            s.bending[0].abs() < 1e-3 && s.bending[1].abs() < 1e-3,
            "{s:?}"
        );
        assert!(s.axial.abs() < 1e-3 && s.torque.abs() < 1e-3, "{s:?}");
    }
}

/// The clamped–pinned collar with its kink turning at `rpm`: the kink's static offset
/// whirls forward and synchronously (the bent shape rotates with the string); the radius
/// grows with the centrifugal load as `R₀ (1 + c r²)`, so two slow speeds extrapolated to
/// r → 0 give the static closed form.
#[test]
fn a_rotating_bent_collar_whirls_forward_synchronously_with_the_kink_offset() {
    let l = 10.0;
    let (a_node, angle) = (4usize, 0.2f64.to_radians());
    let radius_at = |rpm: f64| -> (f64, holewall::whirl::Whirl) {
        let mut m = common::weightless_collar(l, 10);
        m.bends = vec![Bend {
            node: a_node,
            angle,
            toolface: 0.0,
        }];
        let omega = rpm * std::f64::consts::TAU / 60.0;
        m.rotation_speed = omega;
        let start = solve_static(&m, &StaticOptions::default()).unwrap().state;
        let period = std::f64::consts::TAU / omega;
        let options = DynamicOptions {
            dt: period / 200.0,
            alpha: AlphaParams::chung_hulbert(0.9),
            // Mass-proportional damping, ζ ≈ 0.3 at the first mode (≈ 36 rad/s): the
            // spin-up transient dies within the first revolutions.
            rayleigh: (20.0, 0.0),
            ramp_time: 2.0 * period,
            tolerance: 1e-4,
            ..Default::default()
        };
        let mut d = Dynamics::new(&m, options, &|_| common::STEEL);
        let mut s = d.initial_state(start).unwrap();
        let t_end = 10.0 * period;
        let (mut x, mut y) = (Vec::new(), Vec::new());
        d.run(&mut s, t_end, &mut |_, st| {
            if st.t > 6.0 * period {
                x.push(st.q.u[a_node][0]);
                y.push(st.q.u[a_node][1]);
            }
        })
        .unwrap();
        let radii: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a.hypot(*b)).collect();
        let mean = radii.iter().sum::<f64>() / radii.len() as f64;
        let whirl = holewall::whirl::analyse(
            &x,
            &y,
            &[],
            period / 200.0,
            omega / std::f64::consts::TAU,
            1.0,
        );
        (mean, whirl)
    };
    let m = common::weightless_collar(l, 10);
    let a = m.nodes[a_node].md;
    let ei = m.elements[0].section.bending_stiffness();
    let v = 3.0 * ei * angle * (l - a) / l.powi(3);
    let closed = v * a * a * (3.0 * l - a) / (6.0 * ei);
    let (rpm1, rpm2) = (20.0, 40.0);
    let (r1, w1) = radius_at(rpm1);
    let (r2, w2) = radius_at(rpm2);
    // R(Ω) = R₀ (1 + c Ω²): R₀ = (Ω₂² R₁ − Ω₁² R₂)/(Ω₂² − Ω₁²).
    let r0 = (rpm2 * rpm2 * r1 - rpm1 * rpm1 * r2) / (rpm2 * rpm2 - rpm1 * rpm1);
    eprintln!(
        "bent collar 0.2°: whirl radius {:.5} mm at {rpm1} rpm, {:.5} mm at {rpm2} rpm → {:.5} mm at rest vs closed form {:.5} mm ({:+.1e}); {:?} at {:.4} Hz, {:?} at {:.4} Hz",
        1e3 * r1,
        1e3 * r2,
        1e3 * r0,
        1e3 * closed,
        r0 / closed - 1.0,
        w1.class,
        w1.dominant_hz,
        w2.class,
        w2.dominant_hz
    );
    for (w, rpm) in [(&w1, rpm1), (&w2, rpm2)] {
        assert_eq!(w.class, holewall::whirl::WhirlClass::Forward, "{rpm} rpm");
        assert!(w.synchronous, "{rpm} rpm: {:?}", w);
    }
    assert!(r2 > r1, "the centrifugal load opens the orbit");
    // Measured −1.0e-5.
    assert!((r0 / closed - 1.0).abs() < 1e-4, "{r0} vs {closed}");
}

/// `cases/stress_two_stabilizers.toml` (45° well, two stabilizers) with a 1.5° bend in its
/// 12 m collar 2 m above its lower end, toolface 90°, without its `[ensemble]` table.
fn two_stabilizer_bent_text() -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("cases/stress_two_stabilizers.toml")).unwrap();
    let text = text.replacen(
        "length = \"12 m\"\nod = \"6.5 in\"\nid = \"2.8125 in\"",
        "length = \"12 m\"\nod = \"6.5 in\"\nid = \"2.8125 in\"\nbend = \"1.5 deg\"\nbend_from_bottom = \"2 m\"\nbend_toolface = \"90 deg\"",
        1,
    );
    assert!(text.contains("bend ="));
    text[..text.find("[ensemble]").unwrap()].to_string()
}

/// The `bend` ensemble key on a case it was not built around (the two-stabilizer 45° well):
/// 0 … 5° × two frictions all solve, load-step cuts counted, never silently; the GPU engine
/// (kernel built `KINK`, each variant's kink ramped with its own load factor) gives the CPU's
/// answers to solver tolerance; a case without a bend refuses the key.
#[test]
fn bend_ensembles_on_a_two_stabilizer_well() {
    let base = two_stabilizer_bent_text();
    let grid = "[ensemble]\nanalysis = \"static\"\n\n[ensemble.grid]\nbend = [0, 0.5, 1, 2, 3, 5]\nmu = [0.2, 0.5]\n";
    let dir = std::env::temp_dir().join(format!("holewall-bend-ens-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let case = dir.join("bent.toml");
    std::fs::write(&case, format!("{base}{grid}")).unwrap();
    let run = |backend, out: &str| {
        holewall::ensemble::job::run(
            &case,
            None,
            backend,
            holewall::backend::Precision::F64,
            &dir.join(out),
            false,
            &Default::default(),
        )
        .unwrap()
    };
    let cpu = run(holewall::backend::BackendChoice::Cpu, "cpu");
    eprintln!(
        "bend ensemble on the CPU: {} variants, {} converged, {} with step cuts, {} failed",
        cpu.variants, cpu.converged, cpu.step_cut, cpu.failed
    );
    assert_eq!((cpu.variants, cpu.failed), (12, 0));
    assert_eq!(cpu.converged + cpu.step_cut, 12);
    assert!(cpu.backend_note.is_none());
    let column = |out: &str, name: &str| common::variants_column(&dir.join(out), name);
    if common::gpu().is_some() {
        let gpu = run(holewall::backend::BackendChoice::Gpu, "gpu");
        eprintln!(
            "bend ensemble on the GPU engine: backend {}, {} by the engine, {} re-run on the CPU, {} with step cuts",
            gpu.backend, gpu.solved_by_engine, gpu.solved_by_cpu, gpu.step_cut
        );
        assert_eq!(gpu.backend, "gpu");
        assert!(gpu.backend_note.is_none());
        assert_eq!(gpu.failed, 0);
        let mut worst: f64 = 0.0;
        for q in [
            "stab1_max_side_force_n",
            "stab2_max_side_force_n",
            "hook_load_n",
        ] {
            for (a, b) in column("gpu", q).iter().zip(column("cpu", q)) {
                worst = worst.max((a - b).abs() / b.abs().max(1.0));
            }
        }
        eprintln!(
            "GPU engine vs CPU, side forces and hook load: worst relative difference {worst:.1e}"
        );
        assert!(worst <= 1e-6, "{worst:e}");
    }
    // Without a bend in the case, the key is refused by name.
    let plain = dir.join("plain.toml");
    let straight = base.replace(
        "bend = \"1.5 deg\"\nbend_from_bottom = \"2 m\"\nbend_toolface = \"90 deg\"\n",
        "",
    );
    std::fs::write(&plain, format!("{straight}{grid}")).unwrap();
    let s = holewall::ensemble::job::run(
        &plain,
        None,
        holewall::backend::BackendChoice::Cpu,
        holewall::backend::Precision::F64,
        &dir.join("plain"),
        false,
        &Default::default(),
    );
    let message = match s {
        Err(e) => e.to_string(),
        Ok(s) => format!("{:?}", s.failures),
    };
    assert!(message.contains("no bent sub"), "{message}");
}

/// The static engine on bent strings against `solve_static` per variant: the twin path to
/// 1e-9, the GPU f64 path against the twin to 1e-9 m, f32 to a few µm; six bend angles
/// (chunk compaction included: variants finish at different load steps).
#[test]
fn the_engine_solves_bent_strings_as_the_cpu_does() {
    use holewall::engine::{solve_static_ensemble, EngineStatus, TwinPath};
    use holewall::gpu::GpuPath;
    let path = std::path::Path::new("bent.toml");
    let case = holewall::case::parse_case(path, &two_stabilizer_bent_text()).unwrap();
    let models: Vec<_> = [0.0, 0.5, 1.0, 1.5, 2.0, 3.0]
        .iter()
        .map(|deg: &f64| {
            let mut m = case.model.clone();
            m.bends[0].angle = deg.to_radians();
            m
        })
        .collect();
    let options = StaticOptions::default();
    let twin = solve_static_ensemble(&models, &TwinPath, &options).unwrap();
    let mut worst: f64 = 0.0;
    for (j, (m, r)) in models.iter().zip(&twin).enumerate() {
        assert_eq!(r.status, EngineStatus::Converged, "variant {j}");
        let cpu = solve_static(m, &options).unwrap();
        for (a, b) in r.state.u.iter().zip(&cpu.state.u) {
            for k in 0..3 {
                worst = worst.max((a[k] - b[k]).abs());
            }
        }
    }
    eprintln!(
        "bent strings, twin engine vs solve_static: largest position difference {worst:.1e} m"
    );
    assert!(worst <= 1e-9, "{worst:e}");
    let Some(ctx) = common::gpu() else { return };
    let diff = |r: &[holewall::engine::EngineResult]| {
        r.iter()
            .zip(&twin)
            .flat_map(|(g, t)| g.state.u.iter().flatten().zip(t.state.u.iter().flatten()))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
    };
    if ctx.has_f64 {
        let gpu = solve_static_ensemble::<f64, _>(&models, &GpuPath(ctx), &options).unwrap();
        assert!(gpu.iter().all(|r| r.status == EngineStatus::Converged));
        let d = diff(&gpu);
        eprintln!("bent strings, GPU f64 engine vs twin: {d:.1e} m");
        assert!(d <= 1e-9, "{d:e}");
    }
    let f32_run = solve_static_ensemble::<f32, _>(&models, &GpuPath(ctx), &options).unwrap();
    let converged = f32_run
        .iter()
        .filter(|r| r.status == EngineStatus::Converged)
        .count();
    let d = f32_run
        .iter()
        .zip(&twin)
        .filter(|(g, _)| g.status == EngineStatus::Converged)
        .flat_map(|(g, t)| g.state.u.iter().flatten().zip(t.state.u.iter().flatten()))
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!("bent strings, GPU f32 engine: {converged} of 6 converged, largest position difference {d:.1e} m");
    // Measured 1.2e-5 m (f32's rounding of the 45° well's metres of sag, as unbent strings).
    assert_eq!(converged, 6);
    assert!(d <= 5e-5, "{d:e}");
}

/// The dynamic engine with a kink (the beam kernel built `KINK`, the kinks in full): the
/// short spin-up with a 1° bent collar below its stabilizer, 0.3 s, on the GPU engine in
/// f64 against the CPU integrator — the stabilizer's whirl and side force to solver
/// tolerance.
#[test]
fn the_dynamic_engine_runs_a_bent_collar_as_the_cpu_does() {
    if common::gpu().is_none() {
        return;
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("cases/spinup_short.toml")).unwrap();
    // Contact at every node: with the stabilizers' alone the bent collar meets the wall
    // between them (7 and 43 mm beyond it at 0.5° and 1°), and its static start is held
    // there on the CPU (`profile::solve_in_hole`), which the engine's own sites cannot.
    let text = text
        .replacen(
            "length = \"9.25 m\"",
            "length = \"9.25 m\"\nbend = \"1 deg\"\nbend_toolface = \"30 deg\"",
            1,
        )
        .replace("duration = \"1 s\"", "duration = \"0.3 s\"")
        .replace("ramp_time = \"0.5 s\"", "ramp_time = \"0.1 s\"")
        .replace("sites = \"stabilizers\"", "sites = \"all_nodes\"");
    assert!(text.contains("bend =") && text.contains("all_nodes"));
    let grid = "\n[ensemble]\nanalysis = \"dynamic\"\n\n[ensemble.grid]\nbend = [0.5, 1]\n";
    let (dir, worst) = common::engine_against_cpu("bend-dyn", &format!("{text}{grid}"));
    // The bend acts: the stabilizer's side force at 1° is not that at 0.5° (14.8 and 9.7 kN).
    let side = common::variants_column(&dir.join("cpu"), "stab1_max_side_force_n");
    assert!(
        (side[1] / side[0] - 1.0).abs() > 0.1 && side[0] > 0.0,
        "the bend changes the stabilizer's side force: {side:?}"
    );
    eprintln!(
        "bent spin-up, GPU dynamic engine vs CPU integrator: worst relative difference {worst:.1e}"
    );
    assert!(worst <= 1e-6, "{worst:e}");
}

/// The same bent spin-up with contact at the stabilizers only: each variant's bent collar
/// meets the wall between its sites (7 and 43 mm beyond it unheld). The GPU run solves each
/// variant's static start on the engine with guard sites at every node, keeping those in
/// contact (`ensemble::runner`, as `profile::solve_in_hole` on the CPU), and runs both on
/// the engine, in one batch holding both variants' kept sites (each the other's as absent
/// ones); the results are the CPU run's within 1e-6. (Before stop 47 the engine gave both
/// variants to the CPU; stops 47–48 solved their starts on the CPU.)
#[test]
fn a_bent_collar_that_meets_the_wall_runs_on_the_engine_held_there() {
    if common::gpu().is_none() {
        return;
    }
    let text = common::shipped_case_text("spinup_short.toml")
        .replacen(
            "length = \"9.25 m\"",
            "length = \"9.25 m\"\nbend = \"1 deg\"\nbend_toolface = \"30 deg\"",
            1,
        )
        .replace("duration = \"1 s\"", "duration = \"0.1 s\"")
        .replace("ramp_time = \"0.5 s\"", "ramp_time = \"0.05 s\"");
    let grid = "\n[ensemble]\nanalysis = \"dynamic\"\n\n[ensemble.grid]\nbend = [0.5, 1]\n";
    let (dir, cpu, gpu) = common::on_cpu_and_gpu("bend-wall", &format!("{text}{grid}"));
    assert_eq!((cpu.failed, gpu.failed), (0, 0));
    assert_eq!(
        gpu.solved_by_engine, 2,
        "both held at the wall, both on the engine"
    );
    for name in [
        "stab1_max_side_force_n",
        "max_surface_torque_nm",
        "hook_load_n",
    ] {
        let (c, g) = (
            common::variants_column(&dir.join("cpu"), name),
            common::variants_column(&dir.join("gpu"), name),
        );
        for (c, g) in c.iter().zip(&g) {
            let rel = (c - g).abs() / c.abs();
            eprintln!("{name}: CPU {c}, engine {g}, {rel:.1e}");
            assert!(rel <= 1e-6, "{name}: {c} vs {g}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
