//! Tests of the load path's policy and its driver.

use super::*;

/// A path past its gravity stage, its first load step failing until it relaxes (`relax`:
/// the system's shift scale) or, where the system cannot relax, is below `min_step`.
fn stuck(relax: Option<f64>) -> (LoadPath, Next) {
    let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
    assert_eq!(p.converged(10), Next::Step);
    let mut next = Next::Step;
    while p.stage == Stage::Load {
        next = p.failed_at("no".into(), Some(100.0), relax);
    }
    (p, next)
}

#[test]
fn a_failed_load_step_relaxes_at_once_where_the_system_can_and_else_stalls_sooner() {
    let start = || {
        let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
        // Gravity, and the load steps before one has failed: the plain stall.
        assert_eq!(p.limits(), SolveLimits::default());
        assert_eq!(p.converged(10), Next::Step);
        assert_eq!(p.stage, Stage::Load);
        assert_eq!(p.limits().fold_stall, None);
        assert_eq!(p.converged(10), Next::Step);
        assert_eq!(p.limits().fold_stall, None);
        assert_eq!(p.lambda, 0.25);
        p
    };
    // Where the system can relax, the first failed load step relaxes from its start to the
    // full loads, not cut first.
    let mut p = start();
    assert_eq!(p.failed_at("no".into(), None, Some(1e6)), Next::Step);
    assert_eq!(p.stage, Stage::Relax);
    assert_eq!(p.lambda, 0.25);
    let t = p.target();
    assert_eq!((t.gravity, t.lambda, t.friction), (1.0, 1.0, 1.0));
    assert_eq!(p.shift(), 1e6);
    assert_eq!(
        p.limits(),
        SolveLimits {
            iterations: Some(RELAX_SUB_ITERATIONS),
            fold_stall: None,
            relative: Some(RELAX_SUB_REDUCTION),
            first_halving: false,
        }
    );
    // With a soft or hard law the step is cut first, and relaxes once it would go below
    // RELAX_AFTER_STEP (above `min_step`, where a system that cannot relax stops).
    let mut p = LoadPath::new(&StaticOptions::default(), true, false, false);
    assert_eq!(p.converged(10), Next::Step);
    assert_eq!(p.failed_at("no".into(), None, Some(1e6)), Next::Step);
    assert_eq!(p.stage, Stage::Load);
    while p.stage == Stage::Load {
        p.failed_at("no".into(), None, Some(1e6));
    }
    assert_eq!(p.stage, Stage::Relax);
    assert!(p.step >= RELAX_AFTER_STEP && p.step < 2.0 * RELAX_AFTER_STEP);
    assert!(RELAX_AFTER_STEP > StaticOptions::default().min_step);
    // Where it cannot, the step is cut and every later load step stalls sooner.
    let mut p = start();
    assert_eq!(p.failed_at("no".into(), None, None), Next::Step);
    assert_eq!(p.stage, Stage::Load);
    assert!(p.target().lambda < 0.5 && p.target().lambda > 0.25);
    assert_eq!(p.limits().fold_stall, Some(FOLD_STALL_ITERATIONS));
    assert_eq!(p.converged(3), Next::Step);
    assert_eq!(p.limits().fold_stall, Some(FOLD_STALL_ITERATIONS));
}

#[test]
fn without_a_shift_scale_a_step_below_the_smallest_fails() {
    let (p, next) = stuck(None);
    assert_eq!(next, Next::Failed);
    assert!(matches!(p.error, Some(StaticError::LoadStep { .. })));
    assert!(p
        .error
        .as_ref()
        .unwrap()
        .to_string()
        .contains("smallest allowed"));
    // In the load steps, not the gravity stage.
    assert!(!p.error.unwrap().in_gravity_stage());
}

#[test]
fn a_gravity_stage_that_fails_says_so() {
    let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
    let mut next = Next::Step;
    for _ in 0..100 {
        next = p.failed_at("no".into(), None, None);
        if next == Next::Failed {
            break;
        }
    }
    assert_eq!(next, Next::Failed);
    let e = p.error.unwrap();
    assert!(e.in_gravity_stage(), "{e}");
    assert!(e.to_string().starts_with(GRAVITY_STAGE), "{e}");
}

#[test]
fn a_relaxation_whose_residual_stalls_just_above_the_tolerance_settles_saying_so() {
    // Stalled at 2e-9 (f64 tolerance 1e-9, stall bound 1e-6: the residual Newton accepts
    // at its rounding floor): settles once RELAX_STALL_SUBS sub-solves have not improved it
    // by 1 %.
    let (mut p, _) = stuck(Some(1e6));
    let mut subs = 0;
    loop {
        p.shift_settled(if subs < 10 {
            1e-6 / (subs + 1) as f64
        } else {
            2e-9
        });
        subs += 1;
        p.converged(2);
        if p.shift() == 0.0 {
            break;
        }
        assert!(subs < 200, "never settled");
    }
    assert_eq!(subs, 10 + RELAX_STALL_SUBS + 1);
    // Settled: the full loads solved once more, unshifted.
    assert_eq!(p.stage, Stage::Refine);
    assert!(p.error.is_none());
    let log = p.log.last().unwrap();
    assert!(
        log.contains(RELAXED) && log.contains("stalled at 2.0e-9"),
        "{log}"
    );
    // Stalled at 8.5e-7 (unseen corpus well 1827's stall): settles as well.
    let (mut p, _) = stuck(Some(1e6));
    let mut subs = 0;
    while p.shift() > 0.0 {
        p.shift_settled(8.5e-7);
        p.converged(2);
        subs += 1;
        assert!(subs < 200, "never settled");
    }
    assert_eq!(subs, RELAX_STALL_SUBS + 1);
    assert!(p.log.last().unwrap().contains("stalled at 8.5e-7"));
    // Stalled at 2e-6 (above what Newton accepts at its floor): not an equilibrium, it
    // goes on.
    let (mut p, _) = stuck(Some(1e6));
    for _ in 0..3 * RELAX_STALL_SUBS {
        assert!(!p.shift_settled(2e-6));
        assert_eq!(p.converged(2), Next::Step);
        assert!(!p.take_back_to_best());
    }
}

/// A relaxation whose measure reached the stall level once (8.8e-7, unseen user well 0 with
/// the written-out tangent, stop 77) and then hovers above it (2e-6 – 8e-6) settles
/// [`RELAX_STALL_SUBS`] sub-solves after that best, at the best's state: the path asks the
/// system to keep each best at or below the level, and to go back to the last one.
#[test]
fn a_relaxation_that_hovers_above_its_best_settles_back_at_the_best() {
    let (mut p, _) = stuck(Some(1e6));
    let measures = [1e-4, 3e-6, 9e-7, 8.8e-7, 8.0e-7, 2e-6];
    let mut kept = Vec::new();
    let mut subs = 0;
    while p.shift() > 0.0 {
        let m = *measures
            .get(subs)
            .unwrap_or(&(2e-6 + 6e-6 * (subs % 2) as f64));
        if p.shift_settled(m) {
            kept.push(subs);
        }
        p.converged(3);
        if p.take_back_to_best() {
            // Sent back once, as it settles.
            assert_eq!(p.shift(), 0.0);
            assert!(!p.take_back_to_best());
        } else {
            assert!(p.shift() > 0.0, "settled without going back to its best");
        }
        subs += 1;
        assert!(subs < 200, "never settled");
    }
    // Kept at each 1 % gain at or below 1e-6.
    assert_eq!(kept, vec![2, 3, 4]);
    assert_eq!(subs, 4 + RELAX_STALL_SUBS + 1);
    assert_eq!(p.stage, Stage::Refine);
    let log = p.log.last().unwrap();
    assert!(
        log.contains(RELAXED) && log.contains("fell to 8.0e-7") && log.contains("hovered"),
        "{log}"
    );
    // Where the hover itself comes back to the level, the last state stands (as before).
    let (mut p, _) = stuck(Some(1e6));
    let mut subs = 0;
    while p.shift() > 0.0 {
        p.shift_settled(if subs == 0 { 8e-7 } else { 9e-7 });
        p.converged(3);
        assert!(!p.take_back_to_best());
        subs += 1;
        assert!(subs < 200, "never settled");
    }
    assert!(p.log.last().unwrap().contains("stalled at 9.0e-7"));
}

#[test]
fn a_relaxation_lowers_its_shift_until_its_answer_is_an_equilibrium() {
    let (mut p, next) = stuck(Some(1e6));
    assert_eq!(next, Next::Step);
    assert_eq!(p.shift(), 1e6);
    assert_eq!(p.iteration_limit(), Some(RELAX_SUB_ITERATIONS));
    let t = p.target();
    assert_eq!((t.gravity, t.lambda, t.friction), (1.0, 1.0, 1.0));
    // Easy sub-solves quarter the shift, harder ones halve it, hard ones keep it.
    p.converged(3);
    assert_eq!(p.shift(), 2.5e5);
    p.converged(10);
    assert_eq!(p.shift(), 1.25e5);
    p.converged(25);
    assert_eq!(p.shift(), 1.25e5);
    // A failed sub-solve raises it fourfold…
    assert_eq!(p.failed("no".into()), Next::Step);
    assert_eq!(p.shift(), 5e5);
    // …and the shift that failed (1.25e5) is tried again only after two easy sub-solves
    // (2.5e5, then 1.25e5), not one; from then on easy sub-solves halve it.
    p.converged(3);
    assert_eq!(p.shift(), 2.5e5);
    p.converged(3);
    assert_eq!(p.shift(), 1.25e5);
    p.converged(3);
    assert_eq!(p.shift(), 6.25e4);
    // It stays at or above RELAX_FLOOR s0 while the answers are not equilibria…
    for _ in 0..20 {
        p.shift_settled(1e-6);
        assert_eq!(p.converged(2), Next::Step);
    }
    assert_eq!(p.shift(), RELAX_FLOOR * 1e6);
    // …and ends at the first that is, which is solved once more at the full loads without
    // the shift and polished…
    p.shift_settled(1e-10);
    assert_eq!(p.converged(2), Next::Step);
    assert!(p.log.last().unwrap().contains(RELAXED));
    assert_eq!(p.stage, Stage::Refine);
    assert_eq!(p.shift(), 0.0);
    assert!(p.polish());
    assert_eq!(p.iteration_limit(), None);
    let t = p.target();
    assert_eq!((t.gravity, t.lambda, t.friction), (1.0, 1.0, 1.0));
    let mut q = p.clone();
    assert_eq!(p.converged(1), Next::Finished);
    assert!(p.error.is_none());
    assert_eq!(p.progress(), 1.0);
    // …and where that solve fails, the relaxed answer stands.
    assert_eq!(q.failed("no".into()), Next::Finished);
    assert!(q.error.is_none() && q.doubtful);
    assert!(q.log.last().unwrap().contains("the first solution kept"));
}

#[test]
fn a_relaxation_that_cannot_settle_fails_saying_so() {
    let (mut p, _) = stuck(Some(1.0));
    let mut next = Next::Step;
    for _ in 0..RELAX_MAX_SUBS {
        next = p.failed("no".into());
        if next == Next::Failed {
            break;
        }
    }
    assert_eq!(next, Next::Failed);
    let e = p.error.unwrap().to_string();
    assert!(
        e.contains("found no equilibrium at the full loads either"),
        "{e}"
    );
    assert!(e.contains("applying the bit loads"), "{e}");
    // Every relaxation to smaller loads failed too: no equilibrium past the start.
    assert!(
        e.contains(&format!("{LOCK_FOUND} λ = 0.0000 and none at λ = 0.1250")),
        "{e}"
    );
    // The step was not cut to the smallest: the message does not say it was.
    assert!(!e.contains("smallest allowed"), "{e}");
    // The failed step is named once.
    assert_eq!(e.matches("step λ").count(), 1, "{e}");
}

/// Drives `p`'s relaxations with `sub` (the sub-solve's outcome, given how many the
/// relaxation to the full loads has had) until the path ends; returns how many sub-solves
/// that first relaxation had (the ones after it bracket where the string stops).
fn relax_to_the_end(p: &mut LoadPath, mut sub: impl FnMut(&mut LoadPath, usize) -> Next) -> usize {
    let mut first = 0;
    let mut next = Next::Step;
    while next == Next::Step {
        let at_full = p.target().lambda == 1.0;
        next = sub(p, first);
        if at_full {
            first += 1;
        }
    }
    assert_eq!(next, Next::Failed);
    first
}

#[test]
fn a_relaxation_stops_when_its_iteration_budget_is_spent() {
    // Hard sub-solves: the shift stays, the iterations add up.
    let (mut p, _) = stuck(Some(1e6));
    let subs = relax_to_the_end(&mut p, |p, _| p.converged(150));
    assert_eq!(subs, (RELAX_MAX_BUDGET * 200).div_ceil(150));
    let e = p.error.unwrap().to_string();
    assert!(
        e.contains(&format!(
            "budget of {} Newton iterations or {RELAX_MAX_SUBS} sub-solves ran out",
            RELAX_MAX_BUDGET * 200
        )),
        "{e}"
    );
    // Easy sub-solves at the smallest shift that never settle, their unshifted measure
    // still falling (halving every 400 sub-solves, far above the tolerance): the sub-solve
    // count.
    let (mut p, _) = stuck(Some(1e6));
    let mut all = 0;
    let subs = relax_to_the_end(&mut p, |p, _| {
        p.shift_settled(1e-2 * 0.5f64.powf(all as f64 / 400.0));
        all += 1;
        p.converged(2)
    });
    assert_eq!(subs, RELAX_MAX_SUBS);
    let e = p.error.unwrap().to_string();
    assert!(e.contains("sub-solves ran out"), "{e}");
}

/// A relaxation whose unshifted measure stops falling fails after [`RELAX_STAGNANT_SUBS`]
/// sub-solves without a 1 % gain, counted from its best, failed sub-solves included; the
/// message says so whether the last sub-solve converged or failed.
#[test]
fn a_relaxation_whose_residual_stops_falling_fails_saying_so() {
    // `falls`: sub-solves in which the measure falls by 10 % each (the best comes at the
    // last of them), then it stays within 1 % of its best, a failed sub-solve every tenth
    // (counted within each relaxation).
    for falls in [40, 42] {
        let (mut p, _) = stuck(Some(1e6));
        let mut last_failed = false;
        let (mut k, mut target) = (0, 1.0);
        let subs = relax_to_the_end(&mut p, |p, _| {
            if p.target().lambda != target {
                (k, target) = (0, p.target().lambda);
            }
            let measure = 0.9f64.powi(k.min(falls - 1) as i32)
                * if k < falls {
                    1.0
                } else {
                    1.0 - 0.005 * (k % 2) as f64
                };
            let failed = k >= falls && k % 10 == 0;
            if target == 1.0 {
                last_failed = failed;
            }
            k += 1;
            if failed {
                p.failed("no".into())
            } else {
                p.shift_settled(measure);
                p.converged(3)
            }
        });
        // The best at sub-solve `falls − 1`; the 500th after it ends the relaxation (a
        // converged sub-solve for 40, a failed one for 42).
        assert_eq!(subs, falls - 1 + RELAX_STAGNANT_SUBS);
        assert_eq!(last_failed, falls == 42);
        let e = p.error.unwrap().to_string();
        let said = format!("has not fallen by 1 % in {RELAX_STAGNANT_SUBS} sub-solves");
        assert!(e.contains(&said), "{e}");
        assert!(
            e.contains("found no equilibrium at the full loads either"),
            "{e}"
        );
    }
}

#[test]
fn a_gravity_stage_that_fails_relaxes_under_gravity_alone() {
    let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
    let mut next = Next::Step;
    while p.shift() == 0.0 && next == Next::Step {
        next = p.failed_at("no".into(), None, Some(1e4));
    }
    assert_eq!(next, Next::Step);
    let t = p.target();
    assert_eq!((t.gravity, t.lambda, t.friction), (1.0, 0.0, 0.0));
    p.converged(2);
    // An equilibrium under gravity: the load steps follow from λ = 0.
    p.shift_settled(0.0);
    assert_eq!(p.converged(4), Next::Step);
    assert_eq!(p.shift(), 0.0);
    assert_eq!(p.stage, Stage::Load);
    assert!(p.target().lambda > 0.0 && p.target().lambda < 1.0);
}

#[test]
fn a_failed_gravity_step_relaxes_at_once_where_the_system_can_and_ramps_where_it_cannot() {
    let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
    assert_eq!(p.failed_at("no".into(), None, Some(1e4)), Next::Step);
    assert_eq!(p.stage, Stage::Relax);
    assert_eq!(p.shift(), 1e4);
    let t = p.target();
    assert_eq!((t.gravity, t.lambda), (1.0, 0.0));
    let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
    assert_eq!(p.failed_at("no".into(), None, None), Next::Step);
    assert_eq!(p.stage, Stage::GravityRamp);
    assert!(p.target().gravity < 1.0);
}

/// Where the relaxation to the full loads fails, relaxations up from the last equilibrium in
/// steps of [`LOCK_BRACKET`] bracket where the string stops: each from the equilibrium the
/// last one reached, until one finds none; the message names the bracket and the failure's
/// load factor is its lower end.
#[test]
fn a_failed_full_load_relaxation_brackets_where_the_string_stops() {
    let (mut p, next) = stuck(Some(1e6));
    assert_eq!(next, Next::Step);
    assert_eq!(
        (p.stage, p.lambda, p.target().lambda),
        (Stage::Relax, 0.0, 1.0)
    );
    // Ends a relaxation without an equilibrium (its shift raised past the ceiling).
    let fail_relaxation = |p: &mut LoadPath| {
        let mut next = Next::Step;
        let target = p.target().lambda;
        while p.stage == Stage::Relax && p.target().lambda == target {
            next = p.failed("no".into());
        }
        next
    };
    // Settles a relaxation at once: an equilibrium at its target, to be kept.
    let settle = |p: &mut LoadPath| {
        let target = p.target();
        p.shift_settled(1e-12);
        let next = p.converged(3);
        assert_eq!(p.take_equilibrium(), Some(target));
        assert_eq!(p.take_equilibrium(), None, "taken once");
        next
    };
    // A sub-solve that converges unsettled leaves no equilibrium to keep.
    p.shift_settled(1.0);
    assert_eq!(p.converged(3), Next::Step);
    assert_eq!(p.take_equilibrium(), None);
    assert_eq!(p.stopped_between(), None);
    assert!(
        !p.take_back_to_equilibrium(),
        "the relaxation to the full loads goes on"
    );
    // The full loads fail: a relaxation to 0.125 from the equilibrium at 0.
    assert_eq!(fail_relaxation(&mut p), Next::Step);
    assert_eq!((p.stage, p.lambda), (Stage::Relax, 0.0));
    assert!(p.take_back_to_equilibrium());
    assert!(!p.take_back_to_equilibrium(), "taken once");
    let t = p.target();
    assert_eq!((t.lambda, t.friction, t.gravity), (0.125, 0.125, 1.0));
    // 0.125 and 0.25 settle: on to 0.375, each from the equilibrium the last reached.
    for lambda in [0.125, 0.25] {
        assert_eq!(settle(&mut p), Next::Step);
        assert_eq!(
            (p.stage, p.lambda, p.target().lambda),
            (Stage::Relax, lambda, lambda + 0.125)
        );
        assert!(p.take_back_to_equilibrium());
    }
    // 0.375 fails: the bracket [0.25, 0.375] is closed; the path fails there.
    assert_eq!(p.stopped_between(), None);
    assert_eq!(fail_relaxation(&mut p), Next::Failed);
    assert!(!p.take_back_to_equilibrium(), "no relaxation follows");
    assert_eq!(p.stopped_between(), Some((0.25, 0.375)));
    let e = p.error.clone().unwrap();
    assert_eq!(e.reached(), 0.25);
    let e = e.to_string();
    // The step that failed is named once, the bracket after it.
    assert!(
        e.contains("load step λ 0.000000 → 0.250000 failed (no)"),
        "{e}"
    );
    assert!(
        e.contains(&format!("{LOCK_FOUND} λ = 0.2500 and none at λ = 0.3750")),
        "{e}"
    );
    assert!(
        e.contains("found no equilibrium at the full loads either"),
        "{e}"
    );
    assert!(p.log.last().unwrap().contains("where the load path stops"));
    // Up to 0.875 and no further: the full loads' failure closes the bracket.
    let (mut r, _) = stuck(Some(1e6));
    assert_eq!(fail_relaxation(&mut r), Next::Step);
    let mut next = Next::Step;
    let mut relaxations = 0;
    while next == Next::Step {
        next = settle(&mut r);
        relaxations += 1;
    }
    assert_eq!((next, relaxations), (Next::Failed, 7));
    assert_eq!(r.stopped_between(), Some((0.875, 1.0)));
    // From a failed step at λ 0.75: one relaxation, to 0.875, which fails there too.
    let mut q = LoadPath::new(&StaticOptions::default(), true, true, false);
    assert_eq!(q.converged(10), Next::Step);
    assert_eq!(q.take_equilibrium().map(|t| t.lambda), Some(0.0), "gravity");
    while q.lambda < 0.75 {
        let target = q.target();
        assert_eq!(q.converged(10), Next::Step);
        assert_eq!(q.take_equilibrium(), Some(target), "a load step");
    }
    assert_eq!(q.failed_at("no".into(), None, Some(1e6)), Next::Step);
    assert_eq!(fail_relaxation(&mut q), Next::Step);
    assert_eq!(q.target().lambda, 0.875);
    assert_eq!(fail_relaxation(&mut q), Next::Failed);
    assert_eq!(q.stopped_between(), Some((0.75, 0.875)));
    let e = q.error.unwrap();
    assert_eq!(e.reached(), 0.75);
    assert!(e.to_string().contains("none at λ = 0.8750"), "{e}");
}

/// A polish's path ([`LoadPath::at_full_load`]) has no equilibrium to step up from: where
/// its relaxation to the full loads fails, it fails at once, without a bracket.
#[test]
fn a_polish_whose_relaxation_fails_fails_without_a_bracket() {
    let mut p = LoadPath::at_full_load(&StaticOptions::default());
    assert_eq!(p.target().lambda, 1.0);
    assert_eq!(p.failed_at("no".into(), None, Some(1e6)), Next::Step);
    assert_eq!((p.stage, p.target().lambda), (Stage::Relax, 1.0));
    let mut next = Next::Step;
    while next == Next::Step {
        assert_eq!(p.target().lambda, 1.0, "no relaxation to smaller loads");
        next = p.failed("no".into());
    }
    assert_eq!(next, Next::Failed);
    assert!(!p.take_back_to_equilibrium());
    assert_eq!(p.stopped_between(), None);
    let e = p.error.unwrap().to_string();
    assert!(!e.contains(LOCK_FOUND), "{e}");
    assert!(
        e.contains("found no equilibrium at the full loads either"),
        "{e}"
    );
}

/// Without [`StaticOptions::find_stop`] the failed relaxation to the full loads is the
/// failure: no relaxation to smaller loads, no bracket, the step that failed named.
#[test]
fn without_find_stop_a_failed_full_load_relaxation_fails_at_once() {
    let options = StaticOptions {
        find_stop: false,
        ..StaticOptions::default()
    };
    let mut p = LoadPath::new(&options, true, true, false);
    assert_eq!(p.converged(10), Next::Step);
    assert_eq!(p.converged(10), Next::Step);
    assert_eq!(p.lambda, 0.25);
    assert_eq!(p.failed_at("no".into(), None, Some(1e6)), Next::Step);
    assert_eq!((p.stage, p.target().lambda), (Stage::Relax, 1.0));
    let mut next = Next::Step;
    let mut subs = 0;
    while next == Next::Step {
        assert_eq!(p.target().lambda, 1.0, "no relaxation to smaller loads");
        next = p.failed("no".into());
        subs += 1;
        assert!(subs < 1000, "the relaxation ends");
    }
    assert_eq!(next, Next::Failed);
    assert_eq!(p.stage, Stage::Failed);
    assert_eq!(p.stopped_between(), None);
    assert!(!p.take_back_to_equilibrium());
    let e = p.error.clone().unwrap();
    assert_eq!(e.reached(), 0.25);
    let e = e.to_string();
    assert!(
        e.contains("load step λ 0.250000 → 0.500000 failed (no)"),
        "{e}"
    );
    assert!(
        e.contains("found no equilibrium at the full loads either"),
        "{e}"
    );
    assert!(!e.contains(LOCK_FOUND), "{e}");
}

/// A relaxation's anchor carries no momentum for its first [`RELAX_MOMENTUM_AFTER`]
/// sub-solves (converged or failed), [`RELAX_MOMENTUM`] from there; a path that is not
/// relaxing carries none.
#[test]
fn a_relaxation_carries_its_anchor_on_once_it_has_crawled_a_while() {
    let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
    assert_eq!(p.momentum(), 0.0);
    let (mut p2, next) = stuck(Some(1e6));
    assert_eq!(next, Next::Step);
    assert_eq!(p2.stage, Stage::Relax);
    for k in 0..RELAX_MOMENTUM_AFTER {
        assert_eq!(p2.momentum(), 0.0, "sub-solve {k}");
        p2.shift_settled(1e-3);
        if k % 3 == 1 {
            p2.failed_at("no".into(), None, Some(1e6));
        } else {
            p2.converged(8);
        }
    }
    assert_eq!(p2.momentum(), RELAX_MOMENTUM);
    p2.failed_at("no".into(), None, Some(1e6));
    assert_eq!(p2.momentum(), RELAX_MOMENTUM);
    // Once settled, the path refines without a shift and without momentum.
    p2.shift_settled(1e-12);
    p2.converged(3);
    assert_eq!(p2.stage, Stage::Refine);
    assert_eq!((p2.shift(), p2.momentum()), (0.0, 0.0));
    p.converged(5);
    assert_eq!(p.momentum(), 0.0);
}

/// The anchor `x + β (x − x₋)`: at `x` without momentum or without an earlier anchor
/// state.
#[test]
fn a_carried_anchor_moves_on_by_the_momentum_times_the_last_move() {
    let x = [1.0, -2.0, 0.5];
    let base = [0.5, -1.0, 0.5];
    let carried = |base: &[f64], beta: f64| {
        let mut a = x;
        carry_anchor(&mut a, base, beta);
        a
    };
    assert_eq!(carried(&base, 0.9), [1.45, -2.9, 0.5]);
    assert_eq!(carried(&base, 0.0), x);
    assert_eq!(carried(&[], 0.9), x);
}

#[test]
fn only_a_path_that_cuts_its_load_steps_fails_one_that_has_not_halved_its_residual_soon() {
    // Linear laws relax at the first failed load step: no early failure there.
    let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
    assert!(!p.limits().first_halving);
    assert_eq!(p.converged(10), Next::Step);
    assert_eq!(p.stage, Stage::Load);
    assert!(!p.limits().first_halving);
    // A soft or hard law cuts them: its load steps carry the limit, not its gravity stage
    // nor its relaxation's sub-solves.
    let mut p = LoadPath::new(&StaticOptions::default(), true, false, false);
    assert!(!p.limits().first_halving);
    assert_eq!(p.converged(10), Next::Step);
    assert_eq!(p.stage, Stage::Load);
    assert!(p.limits().first_halving);
    while p.stage == Stage::Load {
        p.failed_at("no".into(), None, Some(1e6));
    }
    assert_eq!(p.stage, Stage::Relax);
    assert!(!p.limits().first_halving);
}

/// A cycle is a measure that repeats itself with a period over a span of values; a crawl
/// (near-constant or slowly falling), noise without a period, and too few repeats are not.
#[test]
fn a_cycle_is_a_measure_that_repeats_itself_over_a_span() {
    // User well 2047's shape: eight values from 1.6e-5 to 1.1e-4, growing 1 % a cycle.
    let shape = [
        1.6e-5, 4.0e-5, 2.1e-5, 4.2e-5, 1.1e-4, 7.0e-5, 8.6e-5, 3.4e-5,
    ];
    let cycle: Vec<f64> = (0..40)
        .map(|k| shape[k % 8] * 1.01f64.powi((k / 8) as i32))
        .collect();
    let needed = (RELAX_CYCLE_REPEATS + 1) * 8;
    assert!(!goes_round(&cycle[..needed - 1]));
    assert!(goes_round(&cycle[..needed]));
    // A crawl: within a few percent, falling slowly.
    let crawl: Vec<f64> = (0..200)
        .map(|k| 1e-4 * (1.0 - 1e-4 * k as f64) * (1.0 + 0.02 * ((k * 7) % 5) as f64))
        .collect();
    assert!(!goes_round(&crawl));
    // Noise over a span, without a period.
    let mut x = 0.3f64;
    let noise: Vec<f64> = (0..200)
        .map(|_| {
            x = 3.9 * x * (1.0 - x);
            1e-5 * (1.0 + 9.0 * x)
        })
        .collect();
    assert!(!goes_round(&noise));
}

/// While its measure goes round a cycle, a relaxation solves its sub-solves exactly; its
/// next 1 % gain makes them inexact again. A load step is never solved inexactly.
#[test]
fn a_relaxation_that_goes_round_a_cycle_solves_its_sub_solves_exactly() {
    let p = LoadPath::new(&StaticOptions::default(), true, true, false);
    assert_eq!(p.limits().relative, None);
    let (mut p, _) = stuck(Some(1e6));
    assert_eq!(p.stage, Stage::Relax);
    p.shift_settled(1e-5);
    p.converged(4);
    let shape = [2e-5, 6e-5, 1.1e-4, 4e-5];
    let mut k = 0;
    while p.limits().relative.is_some() {
        assert!(
            k < (RELAX_CYCLE_REPEATS + 1) * 4,
            "no cycle found after {k}"
        );
        p.shift_settled(shape[k % 4]);
        p.converged(4);
        k += 1;
    }
    assert_eq!(k, (RELAX_CYCLE_REPEATS + 1) * 4);
    assert_eq!(p.stage, Stage::Relax);
    // A failed sub-solve does not end it; a new best does.
    p.failed_at("no".into(), None, Some(1e6));
    assert_eq!(p.limits().relative, None);
    p.shift_settled(0.98e-5);
    p.converged(4);
    assert_eq!(p.limits().relative, Some(RELAX_SUB_REDUCTION));
}

/// A relaxation whose sub-solves fail until its shift passes [`RELAX_CEILING`] starts again
/// from its first shift with the rotations shifted too ([`RELAX_ROTATION_SHIFT`] of the
/// translations' shift), once, where the system shifts rotations; where it does not, the
/// relaxation ends at the ceiling as before.
#[test]
fn a_relaxation_at_its_ceiling_shifts_the_rotations_too_once() {
    // 4¹⁰ > 1e6: the tenth failed sub-solve passes the ceiling from a shift scale of 1.
    for (rotations, subs) in [(false, 10), (true, 20)] {
        let (mut p, _) = stuck(Some(1.0));
        p.allow_rotation_shift(rotations);
        assert_eq!((p.shift(), p.rotation_shift()), (1.0, 0.0));
        let mut failed = 0;
        while p.stage == Stage::Relax && p.target().lambda == 1.0 {
            p.failed("no".into());
            failed += 1;
            if failed < 10 {
                assert_eq!(p.rotation_shift(), 0.0);
            } else if failed < 20 && rotations {
                // From its first shift again, the rotations shifted with it.
                assert_eq!(p.shift(), 4f64.powi(failed - 10));
                assert_eq!(p.rotation_shift(), RELAX_ROTATION_SHIFT * p.shift());
            }
        }
        assert_eq!(failed, subs, "rotations {rotations}");
        // The words the corpus counts it by ([`super::rotations_shifted`]).
        assert_eq!(super::rotations_shifted(&p.log), rotations);
    }
}
