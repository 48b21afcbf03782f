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
//! string: it rolls round the hole (whirls) and a static solve finds no equilibrium.
//! Measured (docs/performance.md, stop 68): a 3,035 m horizontal well drilled at 107 kN
//! with 5 in pipe in a 13⅝ in casing above its kick-off fails past 75 % of its loads; the
//! same case with no friction in that casing, or slid instead of rotated, solves.

use crate::case::Case;
use crate::solve::soft_string::SoftStringProfile;

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
    let model = &case.model;
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
    Some(format!(
        "\n  likely reason: turning, the buckled string presses the wall between MD {:.0} and \
         {:.0} m harder than anything holds it there — at MD {:.0} m (inclination {:.1}°, \
         compression {:.1} kN) its circumferential friction is {:.1} N/m against the {:.1} N/m \
         of weight and hole curvature that keep a turning string in place on the wall: it \
         rolls round the hole (whirls) rather than standing, and this model may have no \
         static equilibrium there; `--model soft-string` gives this case's torque and drag, \
         `holewall run` its motion; less WOB (less compression) or a smaller hole there \
         brings the string back to a place it can stand",
        w.md_from,
        w.md_to,
        w.md,
        w.inclination_deg,
        w.compression_n / 1e3,
        w.friction_per_m,
        w.hold_per_m,
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
}
