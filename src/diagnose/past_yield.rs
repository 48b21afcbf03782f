//! An answer past the steel's yield: the static models are linear elastic, so a profile
//! that stresses the pipe beyond every API grade's yield is an equilibrium no pipe carries.

use crate::case::Case;

/// The strongest API drill-pipe grade's minimum yield strength (S135: 135 ksi), Pa: the
/// last of [`crate::strength::GRADES`].
pub const STRONGEST_API_YIELD_PA: f64 =
    crate::strength::GRADES[crate::strength::GRADES.len() - 1].1;

/// Where a static profile (axial forces `axial`, tension +: one per node, or one per
/// element — the section forces — taken at its upper node) stresses the pipe's
/// steel along its axis past [`STRONGEST_API_YIELD_PA`]: (MD, the effective axial stress
/// `F / A` there, Pa, signed) at the largest magnitude; `None` where it stays below. The
/// models are linear elastic: such an answer — a locked-up string relaxed to a push of
/// meganewtons (drawn corpus well 283: −6.7 MN on 5½ in pipe, 1.8 GPa) — is an equilibrium
/// no pipe of any grade carries.
pub fn past_yield(case: &Case, axial: &[f64]) -> Option<(f64, f64)> {
    let model = &case.model;
    let n = model.nodes.len();
    axial
        .iter()
        .take(n)
        .enumerate()
        .map(|(i, f)| {
            let area = model.elements[i.min(n - 2)].section.area;
            (model.nodes[i].md, f / area)
        })
        .filter(|(_, s)| s.abs() > STRONGEST_API_YIELD_PA)
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
}

/// The warning of [`past_yield`], where it finds one.
pub fn past_yield_warning(case: &Case, axial: &[f64]) -> Option<String> {
    let (md, stress) = past_yield(case, axial)?;
    Some(format!(
        "the effective axial stress reaches {:.0} MPa ({}) at MD {md:.0} m, past the yield of \
         every API drill-pipe grade (S135: {:.0} MPa): this linear-elastic answer is one no \
         pipe carries — the string yields (or, pushed, locks up) before it stands so",
        stress.abs() / 1e6,
        if stress < 0.0 {
            "compression"
        } else {
            "tension"
        },
        STRONGEST_API_YIELD_PA / 1e6
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The past-yield check at its threshold: a profile just below S135's yield passes, one
    /// just above is named where its stress is largest, in either sign.
    #[test]
    fn past_yield_names_the_largest_stress_beyond_every_grade() {
        let case = crate::case::parse_case(
            std::path::Path::new("vertical.toml"),
            "[well]\nprofile = \"vertical\"\ntotal_md = \"300 m\"\n\
             [[hole]]\nbottom_md = \"300 m\"\ndiameter = \"8.5 in\"\nfriction = 0.2\n\
             [mud]\ndensity = \"1.2 sg\"\n\
             [[string]]\nkind = \"drill_pipe\"\nlength = \"300 m\"\nod = \"5 in\"\nid = \"4.276 in\"\n\
             [operation]\nmode = \"rotating\"\nrpm = \"60 rpm\"\n\
             [mesh]\nelement_length = \"10 m\"\n",
        )
        .unwrap();
        let model = &case.model;
        let n = model.nodes.len();
        let area = |i: usize| model.elements[i.min(n - 2)].section.area;
        let mut axial: Vec<f64> = (0..n)
            .map(|i| 0.99 * STRONGEST_API_YIELD_PA * area(i))
            .collect();
        assert_eq!(past_yield(&case, &axial), None);
        assert_eq!(past_yield_warning(&case, &axial), None);
        axial[7] = -1.2 * STRONGEST_API_YIELD_PA * area(7);
        axial[9] = 1.1 * STRONGEST_API_YIELD_PA * area(9);
        let (md, stress) = past_yield(&case, &axial).unwrap();
        assert_eq!(md, model.nodes[7].md);
        assert!((stress / STRONGEST_API_YIELD_PA + 1.2).abs() < 1e-12);
        // One per element (the section forces, n − 1 of them) reads the same.
        assert_eq!(past_yield(&case, &axial[..n - 1]), Some((md, stress)));
        let w = past_yield_warning(&case, &axial).unwrap();
        assert!(w.contains("compression") && w.contains("931 MPa"), "{w}");
    }
}
