//! Where a rotating string cannot stand still against the wall: the circumferential
//! friction of a buckled string that nothing holds.
//!
//! A string turning against the wall feels its circumferential friction `μ N` as a side
//! force along the wall (the contact element's `N·mu_t·phi_t·t`, docs/contact-element.md).
//! Lying on the low side, it climbs the wall until the force that holds it there — the
//! weight's side component and the hole's curvature under tension, the soft string's side
//! force `H` per length — balances that friction: it stands where `μ N ≤ H` at the angle
//! `asin(μ N / H)`. A buckled string presses the wall harder than `H` by its own shape
//! (Mitchell: `N_b = r F² / (8 EI)` past the sinusoidal load, `r F² / (4 EI)` past the
//! helical, `F` the compression, `r` the radial clearance), and in a near-vertical hole
//! `H` is all but nothing. Where `μ (H + N_b) > H` no place on the wall holds the turning
//! string: it rolls round the hole (whirls), and a static solve that keeps the friction's
//! side force finds no equilibrium. Measured (docs/performance.md, stop 68): a 3,035 m
//! horizontal well drilled at 107 kN with 5 in pipe in a 13⅝ in casing above its kick-off
//! failed past 75 % of its loads; the same case with no friction in that casing, or slid
//! instead of rotated, solved.
//!
//! Since stop 69 the static solve takes such a string at the **whirl's average**: over
//! [`whirl_span`] its contacts' circumferential friction acts as torque alone — the side
//! force turns with the contact round the hole and averages to nothing over a whirl — by
//! the contact element's `side_friction` ([`mark_whirling_sites`]; the CPU solve and the
//! engine's kernels alike). The answer warns with the span; the whirl itself (its kind,
//! the torque it really costs) is `holewall run`'s.

use crate::case::Case;
use crate::model::Model;
use crate::solve::soft_string::SoftStringProfile;

/// Below this inclination (degrees) the hole is near-vertical for [`whirl_span`]: the
/// weight's hold there, under `w sin 10° = 0.17 w` per length, is less than the
/// circumferential friction `μ N_b` of a buckled string pressed with its weight's worth
/// (`N_b ≥ w`) at any μ ≥ 0.17. A choice, checked on user well 73 (docs/performance.md,
/// stop 69), not fitted.
pub const NEAR_VERTICAL_DEG: f64 = 10.0;

/// The span (MD from, to, m) over which `model`'s turning string (the case's, or a
/// variant's of it) whirls in static mode, `None` where none does: the span
/// [`rotating_whirl_of`] names on the model's soft-string profile, widened on either side
/// through the near-vertical hole next to it (inclination below [`NEAR_VERTICAL_DEG`]).
///
/// Widened because the soft string places the span too narrowly for the FE string: the FE
/// string's compression reaches higher than the soft string's (its buckled drag differs),
/// and next to a whirling span a near-vertical string has no weight to hold it either.
/// Measured (docs/performance.md, stop 69): user-style well 73, reaming 3½ in pipe buckled
/// in a vertical 6¼ in casing, fails with the rule's span alone (1,220–1,586 m), with it
/// widened to the soft string's neutral point above (1,180 m) or 64 m below, and solves
/// widened through the near-vertical hole.
pub fn whirl_span(case: &Case, model: &Model) -> Option<(f64, f64)> {
    if model.rotation_speed == 0.0 {
        return None;
    }
    let profile = case.soft_string_of(model);
    let w = rotating_whirl_of(case, model, &profile.tension, &profile.side_force)?;
    Some(widened(model, &w))
}

/// [`whirl_span`] with the FE string's own compression in place of the soft string's: its
/// axial forces where it stood when its solve failed (`stopped`, at a load factor `λ` below
/// 1), carried to the full loads by the soft string's own change from `λ` to 1 (friction and
/// bit loads scaled as the FE path scales them); the soft string's side force still the
/// hold. `profile::hold_in_hole` solves again at the whirl's average over a span this names
/// and [`whirl_span`] did not.
///
/// Where the FE string carries more drag than the soft string, its neutral point sits
/// higher and its compression in a near-vertical hole is more than the soft string's by
/// that drag. Measured (docs/performance.md, stop 87): unseen user-style well 2771
/// (horizontal, 5,342 m, reaming 3½ in pipe, 2 m elements) — the soft string's neutral
/// point at 1,102 m and 10 kN of compression at the kick-off (1,170 m), short of the
/// rule's whirl; the FE string, solved at the whirl's average, has its neutral point at
/// 1,010 m and 24 kN there. Without it, the FE string wound into a helix (its lateral
/// displacement the whole clearance, turning round the hole node by node) whose relaxation
/// crawled along the helix's turn for 1,300 sub-solves, pushed by 2–3 N a node of
/// circumferential friction, and failed (110 s).
pub fn whirl_span_where_stopped(
    case: &Case,
    model: &Model,
    stopped: &crate::solve::statics::Stopped,
) -> Option<(f64, f64)> {
    use crate::solve::soft_string::{soft_string_with, Operation};
    if model.rotation_speed == 0.0 || stopped.model.nodes.len() != model.nodes.len() {
        return None;
    }
    let sol = crate::solve::statics::stopped_solution(stopped);
    let element: Vec<f64> = sol.section_forces.iter().map(|f| f.axial).collect();
    let fe = crate::profile::nodal_axial_forces(&element);
    let lambda = stopped.lambda;
    let full = case.soft_string_of(model);
    let op = case.operation_of(&stopped.model);
    let at = soft_string_with(
        &stopped.model,
        &Operation {
            friction: lambda * op.friction,
            ..op
        },
        &|md| lambda * case.hole_at(md).friction,
    );
    let axial: Vec<f64> = (0..fe.len())
        .map(|i| fe[i] + full.tension[i] - at.tension[i])
        .collect();
    let w = rotating_whirl_of(case, model, &axial, &full.side_force)?;
    Some(widened(model, &w))
}

/// The rule's span `w` on `model`, widened through the near-vertical hole on either side
/// ([`whirl_span`]).
fn widened(model: &Model, w: &Whirl) -> (f64, f64) {
    let near_vertical = |i: usize| {
        let t = model.nodes[i].hole_axis;
        (t[0] * t[0] + t[1] * t[1])
            .sqrt()
            .atan2(t[2])
            .to_degrees()
            .abs()
            < NEAR_VERTICAL_DEG
    };
    let n = model.nodes.len();
    let mut top = model
        .nodes
        .iter()
        .position(|nd| nd.md >= w.md_from)
        .unwrap_or(0);
    while top > 0 && near_vertical(top - 1) {
        top -= 1;
    }
    let mut bottom = model
        .nodes
        .iter()
        .rposition(|nd| nd.md <= w.md_to)
        .unwrap_or(n - 1);
    while bottom + 1 < n && near_vertical(bottom + 1) {
        bottom += 1;
    }
    (model.nodes[top].md, model.nodes[bottom].md)
}

/// Marks the sites of `model` in its [`whirl_span`] as whirling, the others not: their
/// circumferential friction acts as torque alone in static mode
/// ([`crate::physics::contact::ContactParams::side_friction`] 0, the others' 1) — on the
/// CPU and in the engine's contact kernel alike. Gives the span.
pub fn mark_whirling_sites(case: &Case, model: &mut Model) -> Option<(f64, f64)> {
    let span = whirl_span(case, model);
    mark_span(model, span);
    span
}

/// Marks the sites of `model` inside `span` (MD from, to) as whirling, the others not (as
/// [`mark_whirling_sites`]; for a model whose span is known: the same string with more
/// sites).
pub fn mark_span(model: &mut Model, span: Option<(f64, f64)>) {
    let nodes = &model.nodes;
    for site in &mut model.sites {
        let md = nodes[site.node].md;
        let whirls = span.is_some_and(|(a, b)| md >= a && md <= b);
        site.params.side_friction = if whirls { 0.0 } else { 1.0 };
    }
}

/// A span of the string that whirls at its soft-string profile ([`rotating_whirl`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Whirl {
    /// MD of the span's top and bottom (m): the outermost elements that whirl.
    pub md_from: f64,
    /// See `md_from`.
    pub md_to: f64,
    /// The element where the friction most exceeds its hold: its MD (m),
    pub md: f64,
    /// its compression (N),
    pub compression_n: f64,
    /// its circumferential friction per length `μ (H + N_b)` (N/m),
    pub friction_per_m: f64,
    /// and the side force per length `H` that holds the string on the wall (N/m),
    pub hold_per_m: f64,
    /// and the hole's inclination there (degrees).
    pub inclination_deg: f64,
}

/// The span of a rotating string (`model.rotation_speed` ≠ 0) whose buckled shape's
/// circumferential friction exceeds what holds it on the wall (the module's rule), along
/// the soft-string profile `axial` (nodal axial forces, tension +) and `side_force`
/// (per element, N); `None` for a string that does not turn or where no element whirls.
pub fn rotating_whirl(case: &Case, axial: &[f64], side_force: &[f64]) -> Option<Whirl> {
    rotating_whirl_of(case, &case.model, axial, side_force)
}

/// As [`rotating_whirl`], for `model` (the case's, or a variant's of it) and its profile.
pub fn rotating_whirl_of(
    case: &Case,
    model: &Model,
    axial: &[f64],
    side_force: &[f64],
) -> Option<Whirl> {
    if model.rotation_speed == 0.0 {
        return None;
    }
    let mut found: Option<Whirl> = None;
    let mut worst = 1.0;
    for (e, el) in model.elements.iter().enumerate() {
        let f = -0.5 * (axial[e] + axial[e + 1]);
        let md = 0.5 * (model.nodes[e].md + model.nodes[e + 1].md);
        let hole = case.hole_at(md);
        let (sinusoidal, helical) = super::critical_loads(model, e, hole.diameter);
        let r = 0.5 * (hole.diameter - el.contact_diameter);
        if f <= sinusoidal || r <= 0.0 || el.length0 <= 0.0 {
            continue;
        }
        let ei = el.section.bending_stiffness();
        let buckled = r * f * f / if f > helical { 4.0 * ei } else { 8.0 * ei };
        let hold = side_force[e].abs() / el.length0;
        let friction = hole.friction * (hold + buckled);
        if friction <= hold {
            continue;
        }
        let t = model.nodes[e].hole_axis;
        let inclination = (t[0] * t[0] + t[1] * t[1]).sqrt().atan2(t[2]).to_degrees();
        let ratio = friction / hold.max(f64::MIN_POSITIVE);
        let span = found.map_or((model.nodes[e].md, model.nodes[e + 1].md), |w| {
            (w.md_from, model.nodes[e + 1].md)
        });
        if found.is_none() || ratio > worst {
            worst = ratio;
            found = Some(Whirl {
                md_from: span.0,
                md_to: span.1,
                md,
                compression_n: f,
                friction_per_m: friction,
                hold_per_m: hold,
                inclination_deg: inclination.abs(),
            });
        } else if let Some(w) = found.as_mut() {
            (w.md_from, w.md_to) = span;
        }
    }
    found
}

/// The failure message's line for [`rotating_whirl`] at the case's soft-string profile
/// (`case.soft_string()`).
pub fn whirl_reason(case: &Case, profile: &SoftStringProfile) -> Option<String> {
    let w = rotating_whirl(case, &profile.tension, &profile.side_force)?;
    let span = widened(&case.model, &w);
    Some(format!(
        "\n  likely reason: turning, the buckled string presses the wall between MD {:.0} and \
         {:.0} m harder than anything holds it there — at MD {:.0} m (inclination {:.1}°, \
         compression {:.1} kN) its circumferential friction is {:.1} N/m against the {:.1} N/m \
         of weight and hole curvature that keep a turning string in place on the wall: it \
         rolls round the hole (whirls) rather than standing; the static solve took the \
         circumferential friction between MD {:.0} and {:.0} m as torque alone (the whirl's \
         average) and found no equilibrium even so; `--model soft-string` gives this case's \
         torque and drag, `holewall run` its motion; less WOB (less compression) or a \
         smaller hole there brings the string back to a place it can stand",
        w.md_from,
        w.md_to,
        w.md,
        w.inclination_deg,
        w.compression_n / 1e3,
        w.friction_per_m,
        w.hold_per_m,
        span.0,
        span.1,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1,500 m well, vertical to `kickoff` m and then built at 3°/30 m to 60°, 5 in pipe
    /// in a 12¼ in hole, `mode` (`rotating` with 120 rpm or `sliding`) with `wob` kN.
    fn well(kickoff: f64, mode: &str, wob: f64, friction: f64) -> Case {
        let survey = (0..=60)
            .map(|k| {
                let md = 30.0 * f64::from(k);
                let inc = ((md - kickoff).max(0.0) / 10.0).min(60.0);
                format!("{md}, {inc}, 0\n")
            })
            .collect::<String>();
        let rpm = if mode == "rotating" {
            "rpm = \"120 rpm\"\n"
        } else {
            ""
        };
        let text = format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"survey.csv\"\ntotal_md = \"1500 m\"\n\
             [[hole]]\nbottom_md = \"1500 m\"\ndiameter = \"12.25 in\"\nfriction = {friction}\n\
             [mud]\ndensity = \"1.2 sg\"\n\
             [[string]]\nkind = \"collar\"\nlength = \"30 m\"\nod = \"8 in\"\nid = \"2.8125 in\"\n\
             [[string]]\nkind = \"drill_pipe\"\nlength = \"1470 m\"\nod = \"5 in\"\nid = \"4.276 in\"\n\
             [operation]\nmode = \"{mode}\"\n{rpm}weight_on_bit = \"{wob} kN\"\n\
             [mesh]\nelement_length = \"10 m\"\n"
        );
        crate::diagnose::tests::with_survey(&format!("md, inc, az\n{survey}"), &text)
    }

    /// The rule by hand at the element the function names: its numbers are the module's
    /// formula at that element's soft-string compression and side force.
    #[test]
    fn a_buckled_string_turning_in_a_vertical_hole_whirls_where_the_rule_says() {
        // Kicked off at 1,200 m: 1,200 m of vertical hole above 300 m of build, drilled
        // with enough WOB to buckle the vertical pipe.
        let case = well(1200.0, "rotating", 150.0, 0.25);
        let profile = case.soft_string();
        let w = rotating_whirl(&case, &profile.tension, &profile.side_force)
            .expect("a buckled turning string in a vertical hole whirls");
        assert!(w.inclination_deg < 1.0, "{w:?}");
        assert!(
            w.md_from < w.md && w.md <= w.md_to && w.md_to <= 1200.0 + 10.0,
            "{w:?}"
        );
        // Recomputed from the closed forms at the named element.
        let model = &case.model;
        let e = (0..model.elements.len())
            .position(|e| 0.5 * (model.nodes[e].md + model.nodes[e + 1].md) == w.md)
            .unwrap();
        let el = &model.elements[e];
        let f = -0.5 * (profile.tension[e] + profile.tension[e + 1]);
        let r = 0.5 * (0.31115 - el.contact_diameter);
        let (_, helical) = crate::diagnose::critical_loads(model, e, 0.31115);
        let n_b =
            r * f * f / (if f > helical { 4.0 } else { 8.0 } * el.section.bending_stiffness());
        let hold = profile.side_force[e] / el.length0;
        assert!((w.compression_n - f).abs() <= 1e-9 * f);
        assert!((w.friction_per_m - 0.25 * (hold + n_b)).abs() <= 1e-9 * w.friction_per_m);
        assert!(w.friction_per_m > w.hold_per_m);
        let reason = whirl_reason(&case, &profile).unwrap();
        assert!(
            reason.contains("whirls") && reason.contains("--model soft-string"),
            "{reason}"
        );
    }

    /// No whirl where the string does not turn, where it is not buckled, or where the
    /// buckled part lies in an inclined hole whose weight holds it against its friction.
    #[test]
    fn no_whirl_without_rotation_buckling_or_with_a_hold() {
        let none = |case: &Case| {
            let p = case.soft_string();
            rotating_whirl(case, &p.tension, &p.side_force)
        };
        assert_eq!(none(&well(1200.0, "sliding", 150.0, 0.25)), None);
        assert_eq!(none(&well(1200.0, "rotating", 20.0, 0.25)), None);
        // Kicked off at 100 m: the compressed pipe lies at 60° where its weight holds it.
        assert_eq!(none(&well(100.0, "rotating", 150.0, 0.25)), None);
        // Frictionless: nothing pushes it round.
        assert_eq!(none(&well(1200.0, "rotating", 150.0, 0.0)), None);
    }

    /// The span widens from the rule's through the vertical hole above it and down the
    /// build to 10°; exactly the sites in it are marked.
    #[test]
    fn the_whirl_span_widens_through_the_near_vertical_hole_and_marks_its_sites() {
        let case = well(1200.0, "rotating", 150.0, 0.25);
        let p = case.soft_string();
        let rule = rotating_whirl(&case, &p.tension, &p.side_force).unwrap();
        let (from, to) = whirl_span(&case, &case.model).unwrap();
        assert!(
            from == 0.0 && from < rule.md_from && to >= rule.md_to,
            "{from} {to} {rule:?}"
        );
        // Built at 1°/10 m from 1,200 m: 10° at 1,300 m.
        let inclination = |i: usize| {
            let t = case.model.nodes[i].hole_axis;
            (t[0] * t[0] + t[1] * t[1]).sqrt().atan2(t[2]).to_degrees()
        };
        let last = case.model.nodes.iter().position(|n| n.md == to).unwrap();
        assert!(
            inclination(last) < NEAR_VERTICAL_DEG && inclination(last + 1) >= NEAR_VERTICAL_DEG
        );
        assert!((1280.0..1300.0).contains(&to), "{to}");
        let mut model = case.model.clone();
        let nodes: Vec<usize> = (1..model.nodes.len()).collect();
        model.sites.clear();
        crate::profile::add_wall_sites(&case, &mut model, &nodes);
        assert_eq!(mark_whirling_sites(&case, &mut model), Some((from, to)));
        for s in &model.sites {
            let md = model.nodes[s.node].md;
            assert_eq!(s.whirls(), md <= to, "site at MD {md}");
        }
        // Slid, nothing whirls and nothing is marked.
        let slid = well(1200.0, "sliding", 150.0, 0.25);
        let mut m = slid.model.clone();
        m.sites.clear();
        crate::profile::add_wall_sites(&slid, &mut m, &nodes);
        m.sites
            .iter_mut()
            .for_each(|s| s.params.side_friction = 0.0);
        assert_eq!(mark_whirling_sites(&slid, &mut m), None);
        assert!(m.sites.iter().all(|s| !s.whirls()));
    }

    /// A whirling site's response: the force rows are the element's without circumferential
    /// friction, the moment rows the whole element's (its torque `R_d μ N` kept), and its
    /// `K` is the derivative of that response (central differences).
    #[test]
    fn a_whirling_site_keeps_its_torque_drops_its_side_force_and_its_tangent_is_exact() {
        use crate::solve::statics::{site_response, static_start};
        let case = well(1200.0, "rotating", 150.0, 0.25);
        let mut model = case.model.clone();
        model.sites.clear();
        crate::profile::add_wall_sites(&case, &mut model, &[50]);
        let mut state = static_start(&model);
        let node = model.nodes[50].clone();
        let site = model.sites[0].clone();
        // Pressed 2 mm into the wall, off both axes of the hole's frame.
        let (a, b) = (1.0f64, 0.6f64);
        let e1 = [a / (a * a + b * b).sqrt(), b / (a * a + b * b).sqrt(), 0.0];
        let depth = site.params.clearance + 2e-3;
        state.u[50] = [depth * e1[0], depth * e1[1], 0.1];
        let mut whirling = model.clone();
        whirling.sites[0].params.side_friction = 0.0;
        let full = site_response(&model, &state, &model.sites[0]);
        let avg = site_response(&whirling, &state, &whirling.sites[0]);
        let mut bare_model = model.clone();
        bare_model.sites[0].params.mu_t = 0.0;
        let bare = site_response(&bare_model, &state, &bare_model.sites[0]);
        assert!(full.contact && avg.contact);
        assert_eq!(avg.g[..3], bare.g[..3]);
        assert_eq!(avg.g[3..], full.g[3..]);
        // The side force it drops is μ N, and the torque about the hole axis is R_d μ N.
        let normal = (0..3).map(|i| bare.g[i] * e1[i]).sum::<f64>();
        let side: f64 = (0..3)
            .map(|i| (full.g[i] - avg.g[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(
            (side - 0.25 * normal.abs()).abs() <= 1e-9 * side,
            "{side} {normal}"
        );
        let torque: f64 = (0..3).map(|i| avg.g[3 + i] * node.hole_axis[i]).sum();
        assert!(
            (torque.abs() - site.params.disk_radius * side).abs() <= 1e-9 * torque.abs(),
            "{torque}"
        );
        for c in 0..3 {
            let h = 1e-7;
            let at = |d: f64| {
                let mut s2 = state.clone();
                s2.u[50][c] += d;
                site_response(&whirling, &s2, &whirling.sites[0]).g
            };
            let (gp, gm) = (at(h), at(-h));
            for r in 0..6 {
                let fd = (gp[r] - gm[r]) / (2.0 * h);
                let scale = avg.k.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
                assert!(
                    (fd - avg.k[r][c]).abs() <= 1e-6 * scale,
                    "K[{r}][{c}] {} against {fd}",
                    avg.k[r][c]
                );
            }
        }
    }

    /// The buckled string turning in the vertical hole solves at the whirl's average, the
    /// log says so, and its hook load and surface torque agree with the soft string's (the
    /// torque within 25 %: the soft string adds Mitchell's buckled contact, the FE its own).
    /// Before stop 69 it failed at 87.5 % of its loads (`holewall static`, this case).
    #[test]
    fn a_turning_string_buckled_in_a_vertical_hole_solves_at_the_whirls_average() {
        let case = well(1200.0, "rotating", 150.0, 0.25);
        let mut model = case.model.clone();
        let sol = crate::profile::solve_in_hole(
            &case,
            &mut model,
            &mut |m, nodes| crate::profile::add_wall_sites(&case, m, nodes),
            &crate::solve::statics::StaticOptions::default(),
            &mut |_| {},
        )
        .expect("solved at the whirl's average");
        assert!(
            sol.log
                .iter()
                .any(|l| l.starts_with(crate::profile::WHIRL_AVERAGED)),
            "{:?}",
            sol.log
        );
        assert!(model.sites.iter().any(|s| s.whirls()));
        let (_, hook, torque, _) = crate::profile::fe_rows(&model, &sol);
        let soft = case.soft_string();
        let (soft_hook, soft_torque) = (soft.tension[0], soft.torque[0]);
        eprintln!("hook {hook} soft {soft_hook}; torque {torque} soft {soft_torque}");
        assert!((hook / soft_hook - 1.0).abs() < 0.02, "{hook} {soft_hook}");
        assert!(
            (torque / soft_torque - 1.0).abs() < 0.25,
            "{torque} {soft_torque}"
        );
    }

    /// A turning string whose solve fails where the FE string, standing more compressed than
    /// the soft string says, whirls by the rule on its own compression
    /// ([`whirl_span_where_stopped`]) is solved once more at the whirl's average over that
    /// span, and its log says so; where the FE string's compression names no span, the first
    /// failure is the answer and nothing is solved again.
    #[test]
    fn a_failed_solve_whose_own_compression_whirls_is_solved_again_at_the_whirls_average() {
        use crate::solve::statics::{StaticError, StaticOptions, Stopped};
        // Off bottom the vertical pipe hangs in tension: the soft string names no whirl.
        let case = well(1200.0, "rotating", 0.0, 0.25);
        assert_eq!(whirl_span(&case, &case.model), None);
        let solve_in_hole = |case: &Case| {
            let mut model = case.model.clone();
            let add = &mut |m: &mut Model, nodes: &[usize]| {
                crate::profile::add_wall_sites(case, m, nodes)
            };
            let options = StaticOptions::default();
            let sol = crate::profile::solve_in_hole(case, &mut model, add, &options, &mut |_| {});
            (model, sol.expect("solves"))
        };
        // Where a string drilled at 150 kN stands: buckled in the vertical hole.
        let (_, heavy) = solve_in_hole(&well(1200.0, "rotating", 150.0, 0.25));
        let (_, light) = solve_in_hole(&case);
        let run = |stood: &crate::solve::statics::StaticSolution, again: bool| {
            let stopped = Stopped {
                lambda: 1.0,
                none_at: 1.0,
                model: case.model.clone(),
                u: stood.state.u.clone(),
                rot: stood.state.rot.clone(),
            };
            let span = whirl_span_where_stopped(&case, &case.model, &stopped);
            let failure = |stopped| StaticError::LoadStep {
                stage: "a load step".into(),
                from: 0.5,
                step: 0.0,
                min: 0.0,
                reason: "stalled".into(),
                at_md: None,
                stopped,
            };
            let mut first = Some(failure(Some(Box::new(stopped))));
            let mut model = case.model.clone();
            let mut calls = Vec::new();
            let out = crate::profile::hold_in_hole(
                &case,
                &mut model,
                &mut |m, nodes| crate::profile::add_wall_sites(&case, m, nodes),
                &StaticOptions::default(),
                &mut |m, o| {
                    calls.push(m.sites.iter().any(|s| s.whirls()));
                    match first.take() {
                        Some(e) => Err(e),
                        None if again => Err(failure(None)),
                        None => crate::solve::statics::solve_static(m, o),
                    }
                },
            );
            (span, model, out, calls)
        };
        let (span, model, out, calls) = run(&heavy, false);
        let (from, to) = span.expect("the buckled FE string whirls");
        // The vertical hole in it (and the build below, held by the light string's side
        // force only, by this test's construction).
        assert!(from < 1000.0 && to > 1200.0, "{span:?}");
        // The guarded solve (fails), the model's own sites (none: its answer lies beyond the
        // wall), then the guarded solve at the whirl's average.
        assert_eq!(calls, [false, false, true]);
        let sol = out.expect("solved again at the whirl's average");
        let said = sol
            .log
            .iter()
            .find(|l| l.starts_with(crate::profile::WHIRL_FROM_FE))
            .expect("the log says so");
        assert!(
            said.contains(&format!("between MD {from:.0} and {to:.0} m")),
            "{said}"
        );
        assert!(model.sites.iter().any(|s| s.whirls()));
        // Its own tension names no span: the first failure stands, nothing marked.
        let (span, model, out, calls) = run(&light, false);
        assert_eq!(span, None);
        assert_eq!(calls, [false, false]);
        assert!(matches!(out, Err(StaticError::LoadStep { .. })));
        assert!(!model.sites.iter().any(|s| s.whirls()));
        // Solved again and failed again: the first failure, saying what was tried, nothing
        // left marked.
        let (_, model, out, calls) = run(&heavy, true);
        assert_eq!(calls, [false, false, true, false]);
        let said = out.expect_err("fails").to_string();
        assert!(
            said.contains("stalled; solved again at the whirl's average between MD")
                && said.contains("that failed too (a load step failed: stalled)"),
            "{said}"
        );
        assert!(!model.sites.iter().any(|s| s.whirls()));
    }

    /// A turning string whose load path brackets an equilibrium has nowhere to stop: its
    /// failure says so and names the whirl's average taken. (Stop 68 checked these words end
    /// to end on 1 MN turning in `cases/build_and_hold.toml`, which now solves.) Slid in, the
    /// same bracket is where the string stops.
    #[test]
    fn a_turning_strings_bracketed_failure_says_it_does_not_stop() {
        use crate::solve::statics::StaticError;
        let error = StaticError::LoadStep {
            stage: "applying the bit loads and friction (stage 2)".into(),
            from: 0.5,
            step: 0.0,
            min: 1e-3,
            reason: format!(
                "Newton stalled; {} λ = 0.5000 and none at λ = 0.6250",
                crate::solve::continuation::LOCK_FOUND
            ),
            at_md: None,
            stopped: None,
        };
        let turning = well(1200.0, "rotating", 150.0, 0.25);
        let m = crate::diagnose::static_failure(&turning, &error);
        assert!(
            m.contains("a string not run in or out does not stop")
                && !m.contains("where the string stops")
                && m.contains("it reached 50.0 % of the bit loads")
                && m.contains("as torque alone (the whirl's average) and found no equilibrium"),
            "{m}"
        );
        let mut slid = well(1200.0, "rotating", 150.0, 0.25);
        slid.model.rotation_speed = 0.0;
        slid.model.axial_speed = 0.3;
        let m = crate::diagnose::static_failure(&slid, &error);
        assert!(
            m.contains("that is where the string stops") && !m.contains("whirl"),
            "{m}"
        );
    }
}
