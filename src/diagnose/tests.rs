//! Tests of [`super`]: closed forms of lock-up and buckling, the outside-the-hole check.

use super::*;

/// The case `text` parsed beside a survey file `survey.csv` holding `survey`, in a folder
/// of its own (the tests run in parallel and each removes its own); `whirl`'s tests too.
pub(super) fn with_survey(survey: &str, text: &str) -> Case {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("holewall_diagnose_{}_{call}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("survey.csv"), survey).unwrap();
    let case = crate::case::parse_case(&dir.join("case.toml"), text).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    case
}

/// A straight horizontal 8.5 in hole, 5 in drill pipe slid in with `wob` at the bit.
fn horizontal(friction: f64, wob_kn: f64) -> Case {
    with_survey(
        "md, inclination, azimuth\n0, 90, 0\n3000, 90, 0\n",
        &format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"survey.csv\"\ntotal_md = \"2500 m\"\n\
             [[hole]]\nbottom_md = \"2500 m\"\ndiameter = \"8.5 in\"\nfriction = {friction}\n\
             [mud]\ndensity = \"1.2 sg\"\n\
             [[string]]\nkind = \"drill_pipe\"\nlength = \"2500 m\"\nod = \"5 in\"\nid = \"4.276 in\"\n\
             [operation]\nmode = \"sliding\"\nweight_on_bit = \"{wob_kn} kN\"\n\
             [mesh]\nelement_length = \"2 m\"\n"
        ),
    )
}

/// Past the helical load in a horizontal hole the compression obeys
/// `dF/ds = μ w + μ r F² / (4 EI)` up from the bit (slid in: friction against the push),
/// so `F(s) = √(a/b) tan(√(ab) s + atan(F₀ √(b/a)))`, `a = μ w`, `b = μ r / (4 EI)`:
/// it reaches `LOCK_UP_RATIO` helical loads at a distance from the bit in closed form.
#[test]
fn lock_up_runs_away_where_the_helix_riccati_does() {
    let case = horizontal(0.3, 250.0);
    let model = &case.model;
    let e = model.elements.len() - 1;
    let el = &model.elements[e];
    let hole = case.hole_at(model.nodes[e].md).diameter;
    let (_, h) = critical_loads(model, e, hole);
    assert!(
        250e3 > h,
        "the WOB must start past the helical load ({h} N)"
    );
    let (mu, w) = (0.3, el.buoyed_weight_per_length);
    let r = 0.5 * (hole - el.contact_diameter);
    let (a, b) = (mu * w, mu * r / (4.0 * el.section.bending_stiffness()));
    let (k, scale) = ((a * b).sqrt(), (a / b).sqrt());
    let closed = ((LOCK_UP_RATIO * h / scale).atan() - (250e3 / scale).atan()) / k;
    let lu = lock_up(&case).expect("slid in past its helical load, the string locks up");
    let bit = model.nodes.last().unwrap().md;
    let from_bit = bit - lu.md;
    eprintln!("lock-up {from_bit:.1} m from the bit, closed form {closed:.1} m");
    assert!(
        (from_bit - closed).abs() <= 2.0 + 0.01 * closed,
        "lock-up {from_bit:.1} m from the bit; closed form {closed:.1} m"
    );
    assert!(lu.helical_n == h && lu.compression_n > h);
    // Without friction nothing resists the push: no lock-up; nor with the WOB below
    // the sinusoidal load and little friction over this length.
    assert_eq!(lock_up(&horizontal(0.0, 250.0)), None);
    assert_eq!(lock_up(&horizontal(0.05, 20.0)), None);
}

/// The load factor at which the string starts to lock up: where the helix's Riccati
/// runaway (friction and WOB both scaled by `λ`: `a = λ μ w`, `b = λ μ r / (4 EI)`,
/// `F₀ = λ WOB`, WOB 600 kN) reaches the surface, 2,500 m from the bit — solved here by bisection on
/// the closed form, against [`lock_up_fraction`]'s bisection on the soft string.
#[test]
fn lock_up_fraction_is_where_the_riccati_runaway_reaches_the_surface() {
    let wob = 600e3;
    let case = horizontal(0.3, wob / 1e3);
    let model = &case.model;
    let e = model.elements.len() - 1;
    let el = &model.elements[e];
    let hole = case.hole_at(model.nodes[e].md).diameter;
    let (_, h) = critical_loads(model, e, hole);
    let (mu, w) = (0.3, el.buoyed_weight_per_length);
    let r = 0.5 * (hole - el.contact_diameter);
    let ei = el.section.bending_stiffness();
    let length = model.nodes.last().unwrap().md - model.nodes[0].md;
    let runaway = |lambda: f64| {
        let (a, b) = (lambda * mu * w, lambda * mu * r / (4.0 * ei));
        let (k, scale) = ((a * b).sqrt(), (a / b).sqrt());
        ((LOCK_UP_RATIO * h / scale).atan() - (lambda * wob / scale).atan()) / k
    };
    let (mut lo, mut hi) = (1e-3, 1.0);
    assert!(runaway(hi) < length && runaway(lo) > length);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if runaway(mid) < length {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let closed = hi;
    assert!(
        closed * wob > h,
        "the closed form needs the WOB past the helical load at λ = {closed}"
    );
    let fraction = lock_up_fraction(&case).expect("locks up at full load");
    eprintln!("lock-up from λ = {fraction:.4}; closed form {closed:.4}");
    assert!(
        (fraction - closed).abs() <= 0.02 * closed,
        "lock-up from λ = {fraction:.4}; closed form {closed:.4}"
    );
    assert!(lock_up_at(&case, fraction).is_some());
    assert!(lock_up_at(&case, fraction - 2.0 * LOCK_UP_FRACTION_TOLERANCE).is_none());
    assert_eq!(lock_up_fraction(&horizontal(0.05, 20.0)), None);
}

/// A solved string is outside the hole where a node without a contact site lies
/// further from the axis than its clearance, and only there.
#[test]
fn through_wall_finds_a_node_past_its_clearance() {
    let case = vertical_bha(50.0, "stabilizers");
    let model = &case.model;
    let mut x = crate::solve::statics::StaticState::initial(model);
    assert_eq!(through_wall(&case, model, &x), None);
    let held: Vec<usize> = model.sites.iter().map(|s| s.node).collect();
    let free = (1..model.nodes.len() - 1)
        .rev()
        .find(|i| !held.contains(i) && !held.contains(&(i + 1)) && !held.contains(&(i - 1)))
        .expect("a free node");
    let node = &model.nodes[free];
    let diameter = model.elements[free - 1]
        .contact_diameter
        .max(model.elements[free].contact_diameter);
    let clearance = 0.5 * (case.hole_at(node.md).diameter - diameter);
    // A lateral axis: across the hole axis.
    let t = node.hole_axis;
    let across = if t[0].abs() < 0.9 {
        [0.0, -t[2], t[1]]
    } else {
        [-t[2], 0.0, t[0]]
    };
    let norm = across.iter().map(|a| a * a).sum::<f64>().sqrt();
    let place = |x: &mut crate::solve::statics::StaticState, offset: f64, along: f64| {
        x.u[free] = std::array::from_fn(|k| offset * across[k] / norm + along * t[k]);
    };
    // At the wall, and metres along the axis: inside.
    place(&mut x, clearance + 0.5 * THROUGH_WALL_TOLERANCE, 3.0);
    assert_eq!(through_wall(&case, model, &x), None);
    place(&mut x, clearance + 0.02, 0.0);
    let t = through_wall(&case, model, &x).expect("20 mm outside");
    assert_eq!(
        (t.nodes, t.md, t.first_md, t.last_md),
        (1, node.md, node.md, node.md)
    );
    assert!((t.excess_m - 0.02).abs() < 1e-9, "{}", t.excess_m);
    // A site's node is held by the wall: never reported.
    let site = held[0];
    x.u[free] = [0.0; 3];
    x.u[site][0] += 1.0;
    assert_eq!(through_wall(&case, model, &x), None);
}

/// A string held by the wall at its stabilizer only, in a straight hole 1° off
/// vertical: above the stabilizer 870 m of pipe hang as a cable from the top (clamped
/// on the axis), and the weight's component across the hole, `w sin 1°`, sags it by
/// `w sin θ L² / (8 T)` ≈ metres — through the wall, which [`through_wall`] reports.
/// With contact at every node the wall holds it; in a vertical hole nothing pushes it
/// off the axis.
#[test]
fn a_string_held_only_at_its_stabilizer_sags_through_the_wall() {
    let solve = |case: &Case| {
        let sol = crate::solve::statics::solve_static(
            &case.model,
            &crate::solve::statics::StaticOptions::default(),
        )
        .expect("solves");
        let t = through_wall(case, &case.model, &sol.state);
        // The ensemble's QoI of the same equilibrium.
        let q = crate::ensemble::qoi::static_result(case, "v", &case.model, &sol);
        assert_eq!(q.string.outside_hole_m, Some(t.map_or(0.0, |t| t.excess_m)));
        t
    };
    assert_eq!(solve(&vertical_bha(15.0, "stabilizers")), None);
    let t = solve(&inclined_bha("stabilizers")).expect("sags through the wall");
    eprintln!(
        "{} nodes outside, up to {:.0} mm at MD {:.0} m",
        t.nodes,
        1e3 * t.excess_m,
        t.md
    );
    assert!(t.excess_m > 0.5, "{} m", t.excess_m);
    assert!(t.md > 100.0 && t.md < 873.0, "in the pipe: MD {}", t.md);
    assert_eq!(solve(&inclined_bha("all_nodes")), None);
}

/// The same string solved as every command solves it (`profile::solve_in_hole`): with a
/// guard site at every node, keeping those in contact — in the hole, at the equilibrium of
/// contact at every node (hook load to 1e-9, every node's position to 1e-6 m), and, to the
/// solve's tolerance, an equilibrium of the model with only the sites kept (a guard in
/// contact dropped would leave its force out); the log says where. A string that stays in
/// the hole keeps no guard and has the equilibrium of its own sites.
#[test]
fn a_string_that_meets_the_wall_is_held_there() {
    let held = |case: &Case| {
        let mut model = case.model.clone();
        let sol = crate::profile::solve_in_hole(
            case,
            &mut model,
            &mut |m, nodes| crate::profile::add_wall_sites(case, m, nodes),
            &crate::solve::statics::StaticOptions::default(),
            &mut |_| {},
        )
        .expect("solves");
        (model, sol)
    };
    let case = inclined_bha("stabilizers");
    let (model, sol) = held(&case);
    let added = model.sites.len() - case.model.sites.len();
    eprintln!("{added} sites kept; log {:?}", sol.log);
    assert!(added > 10, "{added}");
    assert!(
        added < model.nodes.len() - 1 - case.model.sites.len(),
        "every guard kept"
    );
    assert_eq!(sol.contact.len(), model.sites.len());
    assert!(sol.contact[..]
        .iter()
        .zip(&model.sites)
        .all(|(c, s)| c.0 || s.stabilizer));
    assert_eq!(through_wall(&case, &model, &sol.state), None);
    assert!(crate::diagnose::beyond_wall(&case, &model, &sol.state).is_empty());
    let measure = crate::solve::statics::residual_measure_at(&model, &sol.state);
    assert!(
        measure < 1e-8,
        "residual of the kept sites' model {measure:e}"
    );
    assert!(sol
        .log
        .iter()
        .any(|l| l.starts_with(crate::profile::WALL_CONTACT)));
    let every = inclined_bha("all_nodes");
    let reference = crate::solve::statics::solve_static(
        &every.model,
        &crate::solve::statics::StaticOptions::default(),
    )
    .expect("solves");
    let hook = |m: &Model, s| crate::profile::fe_rows(m, s).1;
    let (a, b) = (hook(&model, &sol), hook(&every.model, &reference));
    assert!((a / b - 1.0).abs() < 1e-9, "{a} vs {b}");
    let far = sol
        .state
        .u
        .iter()
        .zip(&reference.state.u)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    assert!(far < 1e-6, "{far} m");
    let vertical = vertical_bha(15.0, "stabilizers");
    let (model, sol) = held(&vertical);
    assert_eq!(model.sites.len(), vertical.model.sites.len());
    assert!(!sol
        .log
        .iter()
        .any(|l| l.starts_with(crate::profile::WALL_CONTACT)));
    let own = crate::solve::statics::solve_static(
        &vertical.model,
        &crate::solve::statics::StaticOptions::default(),
    )
    .expect("solves");
    let (a, b) = (hook(&model, &sol), hook(&vertical.model, &own));
    assert!((a / b - 1.0).abs() < 1e-9, "{a} vs {b}");
}

/// A guarded solve that fails (`profile::hold_in_hole`) is tried with the model's own sites,
/// whose answer is taken where it lies in the hole, saying so; where it lies beyond the
/// wall, or fails too, the guarded solve's error is the answer. A solve that runs out of
/// its time budget is not tried again.
#[test]
fn a_guarded_solve_that_fails_is_tried_with_the_models_own_sites() {
    use crate::solve::statics::{StaticError, StaticOptions};
    let failure = |why: &str| StaticError::LoadStep {
        stage: "a load step".into(),
        from: 0.5,
        step: 0.0,
        min: 0.0,
        reason: why.into(),
        at_md: None,
        stopped: None,
    };
    let held_everywhere =
        |m: &Model| (1..m.nodes.len()).all(|i| m.sites.iter().any(|s| s.node == i));
    let run = |case: &Case, fails: &dyn Fn(&Model) -> Option<StaticError>| {
        let mut model = case.model.clone();
        let mut calls = Vec::new();
        let out = crate::profile::hold_in_hole(
            case,
            &mut model,
            &mut |m, nodes| crate::profile::add_wall_sites(case, m, nodes),
            &StaticOptions::default(),
            &mut |m, o| {
                calls.push(held_everywhere(m));
                match fails(m) {
                    Some(e) => Err(e),
                    None => crate::solve::statics::solve_static(m, o),
                }
            },
        );
        (model, out, calls)
    };
    let case = vertical_bha(15.0, "stabilizers");
    assert!(
        case.model.sites.len() < case.model.nodes.len() - 1,
        "the case must lack sites"
    );
    // The guarded solve first, and only it where it solves.
    let (model, out, calls) = run(&case, &|_| None);
    out.expect("solves");
    assert_eq!(calls, [true]);
    assert_eq!(model.sites.len(), case.model.sites.len());
    // Guarded fails; the string at its own sites stays in the hole: taken, said.
    let (model, out, calls) = run(&case, &|m| {
        held_everywhere(m).then(|| failure("guards made to fail"))
    });
    let sol = out.expect("the model's own sites solve, in the hole");
    assert_eq!(calls, [true, false]);
    assert_eq!(model.sites.len(), case.model.sites.len());
    assert!(sol.log.iter().any(
        |l| l.contains("guard site at every node failed") && l.contains("guards made to fail")
    ));
    // Both fail: the guarded solve's error.
    let (_, out, calls) = run(&case, &|m| {
        Some(failure(if held_everywhere(m) { "guarded" } else { "own" }))
    });
    assert!(matches!(out, Err(StaticError::LoadStep { ref reason, .. }) if reason == "guarded"));
    assert_eq!(calls, [true, false]);
    // Both fail, the guarded one where the string stops: where it stands keeps the sites an
    // answer would (its own and the guards in contact), as the guarded solve's answer did.
    let (solved_model, _, _) = run(&case, &|_| None);
    let (_, out, _) = run(&case, &|m| {
        let sol = crate::solve::statics::solve_static(m, &StaticOptions::default()).unwrap();
        let stopped = crate::solve::statics::Stopped {
            lambda: 1.0,
            none_at: 1.0,
            model: m.clone(),
            u: sol.state.u,
            rot: sol.state.rot,
        };
        let mut e = failure("stops");
        if let StaticError::LoadStep { stopped: s, .. } = &mut e {
            *s = Some(Box::new(stopped));
        }
        Some(e)
    });
    let e = out.expect_err("fails");
    let st = e.stopped().expect("where it stands");
    assert!(
        st.model.sites.len() < case.model.nodes.len() - 1,
        "guards dropped"
    );
    assert_eq!(
        st.model.sites.iter().map(|s| s.node).collect::<Vec<_>>(),
        solved_model
            .sites
            .iter()
            .map(|s| s.node)
            .collect::<Vec<_>>()
    );
    // The own sites' answer lies beyond the wall (the inclined string): the error.
    let inclined = inclined_bha("stabilizers");
    let (model, out, calls) = run(&inclined, &|m| {
        held_everywhere(m).then(|| failure("guarded"))
    });
    assert!(matches!(out, Err(StaticError::LoadStep { .. })));
    assert_eq!(calls, [true, false]);
    assert_eq!(model.sites.len(), inclined.model.sites.len());
    // The time budget spent: no retry.
    let (model, out, calls) = run(&case, &|_| {
        Some(StaticError::Budget {
            seconds: 1.0,
            reached: 0.3,
        })
    });
    assert!(matches!(out, Err(StaticError::Budget { .. })));
    assert_eq!(calls, [true]);
    assert_eq!(model.sites.len(), case.model.sites.len());
}

/// A solved profile of a load that locks up warns, with where and from which load factor;
/// one that does not lock up does not.
#[test]
fn a_solved_load_that_locks_up_warns() {
    let case = horizontal(0.3, 600.0);
    let lu = lock_up(&case).unwrap();
    let from = lock_up_fraction(&case).unwrap();
    let w = locked_up_warning(&case, -7.0e6).expect("locks up");
    assert!(
        w.contains(&format!("MD {:.0} m", lu.md))
            && w.contains(&format!("from {:.0} %", 100.0 * from))
            && w.contains("-7000.0 kN: pushed from the surface"),
        "{w}"
    );
    assert_eq!(locked_up_warning(&horizontal(0.05, 20.0), 1e5), None);
}

/// A failed solve of a load that locks up says so, with where.
#[test]
fn a_failure_that_locks_up_says_so() {
    let error = StaticError::LoadStep {
        stage: "applying the bit loads and friction (stage 2)".into(),
        from: 0.5,
        step: 1e-4,
        min: 1e-4,
        reason: "Newton did not converge".into(),
        at_md: Some(1200.0),
        stopped: None,
    };
    let case = horizontal(0.3, 250.0);
    let lu = lock_up(&case).unwrap();
    let msg = static_failure(&case, &error);
    assert!(
        msg.contains("lock-up: a soft string") && msg.contains(&format!("MD {:.0} m", lu.md)),
        "{msg}"
    );
    // Below the runaway: no lock-up line (a hole horizontal from the surface has no
    // weight to push with, which the weight indicator's line says).
    let weak = static_failure(&horizontal(0.05, 20.0), &error);
    assert!(!weak.contains("lock-up: a soft string"), "{weak}");
    assert!(weak.contains("must be pushed from the surface"), "{weak}");
}

/// A failure names its stage by the stage's name: a load step whose relaxation failed (no
/// smallest step, `step` 0) says how far the loads got, not that the string found no
/// equilibrium under its own weight (what corpus well 419's message said at stop 56).
#[test]
fn a_failed_load_step_is_not_reported_as_the_gravity_stage() {
    let case = horizontal(0.3, 250.0);
    let relaxed = StaticError::LoadStep {
        stage: "applying the bit loads and friction (stage 2), the step λ 0.2500 → 0.5000".into(),
        from: 0.25,
        step: 0.0,
        min: 1e-4,
        reason: "relaxation by proximal points found no equilibrium past it either".into(),
        at_md: Some(306.0),
        stopped: None,
    };
    let msg = static_failure(&case, &relaxed);
    assert!(!msg.contains("under its own weight"), "{msg}");
    assert!(msg.contains("it reached 25.0 % of the"), "{msg}");
    assert!(
        msg.contains("the last equilibrium on this load path"),
        "{msg}"
    );
    // A path that bracketed where the string stops says that instead.
    let bracketed = StaticError::LoadStep {
        stage: "applying the bit loads and friction (stage 2)".into(),
        from: 0.625,
        step: 0.0,
        min: 1e-4,
        reason: format!(
            "load step λ 0 → 0.25 failed (no); {} λ = 0.6250 and none at λ = 0.7500",
            crate::solve::continuation::LOCK_FOUND
        ),
        at_md: None,
        stopped: None,
    };
    let msg = static_failure(&case, &bracketed);
    assert!(msg.contains("it reached 62.5 % of the"), "{msg}");
    assert!(
        msg.contains("where the string stops on this model"),
        "{msg}"
    );
    assert!(
        !msg.contains("the last equilibrium on this load path"),
        "{msg}"
    );
    let gravity = StaticError::LoadStep {
        stage: format!(
            "{} (stage 1 of the load path)",
            crate::solve::static_options::GRAVITY_STAGE
        ),
        from: 0.0,
        step: 0.0,
        min: 1e-4,
        reason: "Newton stalled".into(),
        at_md: Some(306.0),
        stopped: None,
    };
    let msg = static_failure(&case, &gravity);
    assert!(
        msg.contains("found no equilibrium under its own weight"),
        "{msg}"
    );
    assert!(!msg.contains("it reached"), "{msg}");
    assert!(
        !msg.contains("the last equilibrium on this load path"),
        "{msg}"
    );
}

/// A vertical 6⅛ in hole drilled at `wob_kn` on a near-bit stabilizer and 5 × 2¼ in
/// collars (corpus well 439's BHA), contact at `sites`.
fn vertical_bha(wob_kn: f64, sites: &str) -> Case {
    crate::case::parse_case(
        std::path::Path::new("v.toml"),
        &vertical_bha_text(wob_kn, sites),
    )
    .unwrap()
}

/// [`vertical_bha`]'s case file.
fn vertical_bha_text(wob_kn: f64, sites: &str) -> String {
    format!(
        "[well]\nprofile = \"vertical\"\ntotal_md = \"1000 m\"\n\
         [[hole]]\nbottom_md = \"1000 m\"\ndiameter = \"6.125 in\"\nfriction = 0.25\n\
         [mud]\ndensity = \"1.278 sg\"\n\
         [[string]]\nkind = \"bit\"\nlength = \"0.3 m\"\nod = \"5 in\"\nid = \"2.25 in\"\n\
         [[string]]\nkind = \"stabilizer\"\nlength = \"1.5 m\"\nod = \"5 in\"\nid = \"2.25 in\"\nblade_diameter = \"6 in\"\n\
         [[string]]\nkind = \"collar\"\nlength = \"126.2 m\"\nod = \"5 in\"\nid = \"2.25 in\"\n\
         [[string]]\nkind = \"drill_pipe\"\nlength = \"872 m\"\nod = \"4 in\"\nid = \"3.34 in\"\n\
         [operation]\nmode = \"rotating\"\nrpm = \"120 rpm\"\nweight_on_bit = \"{wob_kn} kN\"\n\
         [contact]\nsites = \"{sites}\"\n[mesh]\nelement_length = \"10 m\"\nbha_element_length = \"0.5 m\"\n"
    )
}

/// [`vertical_bha`]'s string at 15 kN in a straight hole 1° off vertical.
fn inclined_bha(sites: &str) -> Case {
    with_survey(
        "md, inclination, azimuth\n0, 1, 0\n1000, 1, 0\n",
        &vertical_bha_text(15.0, sites).replace(
            "profile = \"vertical\"",
            "profile = \"survey\"\nsurvey = \"survey.csv\"",
        ),
    )
}

/// Lubinski's first-order load of the collars, from their sizes alone (E 207 GPa, steel
/// 7850 kg/m³ — the case defaults — in 1.278 sg mud): `1.94 (EI w²)^⅓` ≈ 19.9 kN. The
/// check fires at 28.8 kN (well 439) with contact at the stabilizers only, not at 15 kN,
/// and not with contact at every node.
#[test]
fn unsupported_collars_past_lubinskis_load_are_named() {
    let (od, id): (f64, f64) = (5.0 * 0.0254, 2.25 * 0.0254);
    let ei = 207e9 * std::f64::consts::PI / 64.0 * (od.powi(4) - id.powi(4));
    let w = std::f64::consts::PI / 4.0 * (od * od - id * id) * 9.80665 * (7850.0 - 1278.0);
    let hand = 1.94 * (ei * w * w).cbrt();
    let case = vertical_bha(28.8, "stabilizers");
    let (md, f, critical) = unsupported_buckling(&case, &case.soft_string().tension)
        .expect("28.8 kN on unsupported collars passes Lubinski's load");
    eprintln!("stabilizer at MD {md:.1} m: {f:.0} N against {critical:.0} N (hand {hand:.0} N)");
    assert!(
        (critical - hand).abs() <= 1e-3 * hand,
        "{critical} vs {hand}"
    );
    assert!((19e3..21e3).contains(&critical), "{critical}");
    // The compression at the stabilizer: the WOB less the bit's and stabilizer's weight.
    assert!(f < 28.8e3 && f > 28.8e3 - 1.9 * w * 1.1, "{f}");
    let error = StaticError::LoadStep {
        stage: "applying the bit loads and friction (stage 2)".into(),
        from: 0.5,
        step: 1e-4,
        min: 1e-4,
        reason: "r".into(),
        at_md: None,
        stopped: None,
    };
    let msg = static_failure(&case, &error);
    assert!(
        msg.contains("Lubinski") && msg.contains("all_nodes"),
        "{msg}"
    );
    let light = vertical_bha(15.0, "stabilizers");
    assert!(unsupported_buckling(&light, &light.soft_string().tension).is_none());
    let walled = vertical_bha(28.8, "all_nodes");
    assert!(unsupported_buckling(&walled, &walled.soft_string().tension).is_none());
    assert!(!static_failure(&walled, &error).contains("Lubinski"));
}

/// 5 in drill pipe, `md` metres of it, rotating off bottom at 60 rpm in an 8½ in hole
/// along `survey` (μ 0.25, 1.2 sg), meshed at `element_m`.
fn rotating_pipe(survey: &str, md: f64, element_m: f64) -> Case {
    with_survey(
        survey,
        &format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"survey.csv\"\ntotal_md = \"{md} m\"\n\
             [[hole]]\nbottom_md = \"{md} m\"\ndiameter = \"8.5 in\"\nfriction = 0.25\n\
             [mud]\ndensity = \"1.2 sg\"\n\
             [[string]]\nkind = \"drill_pipe\"\nlength = \"{md} m\"\nod = \"5 in\"\nid = \"4.276 in\"\n\
             [operation]\nmode = \"rotating\"\nrpm = \"60 rpm\"\n\
             [contact]\nsites = \"all_nodes\"\n\
             [mesh]\nelement_length = \"{element_m} m\"\n"
        ),
    )
}

/// The clamped span's sag ([`clamped_span_sag`]) against a finite-difference solution of
/// `EI w⁗ − T w″ = q` with clamped ends, from no tension to a cable's, and continuous where
/// it changes from the series to the closed form.
#[test]
fn a_clamped_span_sags_as_the_beam_column_equation_says() {
    let (q, l, ei) = (180.0, 12.0, 1.2e6);
    let n = 400usize;
    let h = l / n as f64;
    for t in [0.0, 1e3, 5e4, 1e6] {
        // w_1 … w_{n−1}; w_0 = w_n = 0 and zero slopes (ghosts w_{−1} = w_1, w_{n+1} = w_{n−1}).
        let m = n - 1;
        let mut a = nalgebra::DMatrix::<f64>::zeros(m, m);
        let b = nalgebra::DVector::<f64>::from_element(m, q);
        let (c4, c2) = (ei / h.powi(4), t / (h * h));
        for i in 0..m {
            let j = i as isize + 1;
            for (off, w4, w2) in [
                (-2isize, 1.0, 0.0),
                (-1, -4.0, 1.0),
                (0, 6.0, -2.0),
                (1, -4.0, 1.0),
                (2, 1.0, 0.0),
            ] {
                let mut k = j + off;
                if k < 0 {
                    k = -k;
                }
                if k > n as isize {
                    k = 2 * n as isize - k;
                }
                if k == 0 || k == n as isize {
                    continue;
                }
                a[(i, (k - 1) as usize)] += c4 * w4 - c2 * w2;
            }
        }
        let w = a.lu().solve(&b).expect("a regular system");
        let (fd, closed) = (w[n / 2 - 1], clamped_span_sag(q, l, ei, t));
        eprintln!("T = {t:.0} N: sag {closed:.6e} m, finite differences {fd:.6e} m");
        assert!(
            (fd - closed).abs() <= 1e-3 * closed,
            "T = {t}: {closed} against {fd}"
        );
    }
    assert_eq!(
        clamped_span_sag(q, l, ei, -5e4),
        q * l.powi(4) / (384.0 * ei)
    );
    // The series below z = λl/4 = 0.05 meets the closed form above it.
    let t = ei * (0.2 / l).powi(2);
    let (below, above) = (
        clamped_span_sag(q, l, ei, t * (1.0 - 1e-9)),
        clamped_span_sag(q, l, ei, t * (1.0 + 1e-9)),
    );
    assert!(
        (below - above).abs() <= 1e-8 * below,
        "{below} against {above}"
    );
}

/// A string laid on the low side of a straight horizontal hole, its nodes at the wall.
/// Held only at its nodes (no sites), each span's own weight carries its middle through the
/// wall by the clamped span's sag: reported in every element with 20 m elements and in none
/// with 2 m ones. With a site at every node but the clamped top, the wall carries the spans
/// between sites (their weight is integrated at the nodes too): only the top element is
/// reported.
#[test]
fn a_long_span_laid_on_the_wall_sags_through_it_by_its_weight() {
    let case_for = |element_m: f64| {
        rotating_pipe(
            "md, inclination, azimuth\n0, 90, 0\n500, 90, 0\n",
            400.0,
            element_m,
        )
    };
    for (element_m, sites, flagged) in [
        (20.0, false, Some(20)),
        (2.0, false, None),
        (20.0, true, Some(1)),
        (2.0, true, None),
    ] {
        let mut case = case_for(element_m);
        assert_eq!(case.model.sites.len() + 1, case.model.nodes.len());
        if !sites {
            case.model.sites.clear();
        }
        let model = &case.model;
        let e = &model.elements[1];
        let clearance = 0.5 * (case.hole_at(model.nodes[1].md).diameter - e.outer_diameter);
        // Every node `clearance` below its axis, unrotated.
        let mut x = crate::solve::statics::StaticState::initial(model);
        for u in x.u.iter_mut() {
            *u = [0.0, 0.0, clearance];
        }
        let axial = vec![0.0; model.elements.len()];
        let found = span_through_wall(&case, model, &x, &axial);
        let sag = e.buoyed_weight_per_length * e.length0.powi(4)
            / (384.0 * e.section.bending_stiffness());
        eprintln!("{element_m} m elements, sites {sites}: sag {sag:.3e} m, found {found:?}");
        assert_eq!(
            found.map(|w| w.elements),
            flagged,
            "{element_m} m: {found:?}"
        );
        let warning = span_through_wall_warning(&case, model, &x, &axial);
        assert_eq!(warning.is_some(), flagged.is_some(), "{warning:?}");
        if let Some(w) = found {
            assert!(
                (w.excess_m - sag).abs() <= 1e-9 + 1e-6 * sag,
                "{} against {sag}",
                w.excess_m
            );
            let at = (384.0 * e.section.bending_stiffness() * THROUGH_WALL_TOLERANCE
                / e.buoyed_weight_per_length)
                .powf(0.25);
            assert!((w.suggested_m - at).abs() <= 1e-9 * at);
        }
    }
}

/// Solves `rotating_pipe` on a survey: the surface torque, the span check and the pipe's
/// element.
fn solve_rotating_pipe(
    survey: &str,
    md: f64,
    element_m: f64,
) -> (f64, Option<SpanSag>, crate::model::Element) {
    let mut case = rotating_pipe(survey, md, element_m);
    let statics = case.settings().statics();
    let sol = crate::profile::solve_with_progress(&mut case, statics, false).expect("solved");
    let model = &case.model;
    let (_, _, torque, _) = crate::profile::fe_rows(model, &sol);
    let axial: Vec<f64> = sol.section_forces.iter().map(|f| f.axial).collect();
    let span = span_through_wall(&case, model, &sol.state, &axial);
    (torque.abs(), span, model.elements[1].clone())
}

/// Rotating off bottom in a horizontal hole that turns 1°/30 m: the surface torque is the
/// closed form's `μ w cos(atan μ) r L` (the string on the low side, climbed up the wall by
/// the friction angle, no tension) with 2 m elements and with 20 m ones. With the consistent
/// end moments of the spans' weight at nodes held by the wall, 20 m elements gave 563 N·m
/// against 2,051 (stop 54, the string held by guard sites): the moments no longer cancel
/// where the chords turn and twist the string, as a horizontally curved girder under its
/// own weight. The spans between sites are carried by the wall and not reported; at 20 m
/// only the top element, from the top clamped on the axis to the wall, passes it between
/// its nodes.
#[test]
fn long_elements_in_a_turning_hole_give_the_converged_torque() {
    let survey = "md, inclination, azimuth\n0, 90, 0\n600, 90, 20\n";
    let (coarse, coarse_span, e) = solve_rotating_pipe(survey, 600.0, 20.0);
    let (fine, fine_span, _) = solve_rotating_pipe(survey, 600.0, 2.0);
    // The rotating pipe climbs the wall by the friction angle: N = w cos(atan μ).
    let mu: f64 = 0.25;
    let closed =
        mu * e.buoyed_weight_per_length * mu.atan().cos() * 600.0 * 0.5 * e.contact_diameter;
    eprintln!(
        "surface torque {coarse:.0} N·m at 20 m elements, {fine:.0} N·m at 2 m; \
         μ w cos(atan μ) r L = {closed:.0} N·m"
    );
    for (what, torque) in [("2 m", fine), ("20 m", coarse)] {
        assert!(
            (torque - closed).abs() <= 0.05 * closed,
            "{what}: {torque} against {closed}"
        );
    }
    assert!(
        (coarse - fine).abs() <= 0.02 * fine,
        "{coarse} against {fine}"
    );
    assert_eq!(fine_span, None);
    assert_eq!(
        coarse_span.map(|w| (w.elements, w.first_md, w.last_md)),
        Some((1, 10.0, 10.0))
    );
}
