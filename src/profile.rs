//! The static profile along the string — the rows of `profile.csv` (axial force and
//! stress, torque, bending moment, side forces, lateral displacement), hook load, surface
//! torque, neutral point and buckling flags — from an FE static solution: what the
//! `static` command writes and the ensemble's quantities of interest read (the library's,
//! below the CLI).

use serde::Serialize;

use crate::case::Case;
use crate::model::Model;
use crate::physics::vec3::{dot, scale, sub};

/// One row of `profile.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct ProfileRow {
    /// Measured depth (m).
    pub md_m: f64,
    /// Position (m): north, east, TVD.
    pub x_m: f64,
    /// See `x_m`.
    pub y_m: f64,
    /// See `x_m`.
    pub z_m: f64,
    /// Effective axial force, tension positive (N).
    pub axial_force_n: f64,
    /// Effective axial stress `F_eff/A` (Pa): the effective force (buoyancy as a
    /// distributed load, the buoyed-weight model) over the steel area — not the true steel
    /// stress, which differs by the mud pressure's share.
    pub axial_stress_pa: f64,
    /// Torque (N·m).
    pub torque_nm: f64,
    /// Bending moment (N·m).
    pub bending_moment_nm: f64,
    /// Side (contact normal) force (N): FE, the node's contact force; soft string, the
    /// element's below the node.
    pub side_force_n: f64,
    /// Side force per unit length (N/m): over the node's tributary length (FE), over the
    /// element (soft string).
    pub side_force_per_length_n_per_m: f64,
    /// Lateral displacement from the hole axis (m).
    pub lateral_displacement_m: f64,
    /// In contact with the wall.
    pub in_contact: bool,
    /// Von Mises stress at the outer fibre (Pa; [`crate::strength`]), on components with a
    /// grade; empty otherwise.
    #[serde(with = "crate::output::nan_as_null")]
    pub von_mises_pa: f64,
    /// That over the grade's yield strength.
    #[serde(with = "crate::output::nan_as_null")]
    pub yield_utilisation: f64,
}

/// Neutral point: the first MD, going up from the bit, where the axial force turns from
/// compression to tension (linear interpolation between nodes).
pub fn neutral_point(rows: &[ProfileRow]) -> Option<f64> {
    let md: Vec<f64> = rows.iter().map(|r| r.md_m).collect();
    let axial: Vec<f64> = rows.iter().map(|r| r.axial_force_n).collect();
    neutral_point_of(&md, &axial)
}

/// [`neutral_point`] from nodal MDs and axial forces (tension +).
pub fn neutral_point_of(md: &[f64], axial: &[f64]) -> Option<f64> {
    for k in (1..md.len()).rev() {
        let (lo, hi) = (axial[k], axial[k - 1]);
        if lo <= 0.0 && hi > 0.0 {
            let f = lo / (lo - hi);
            return Some(md[k] + f * (md[k - 1] - md[k]));
        }
    }
    None
}

/// Nodal axial forces: the mean of the adjacent elements' (as in `profile.csv`).
pub fn nodal_axial_forces(element_axial: &[f64]) -> Vec<f64> {
    let n = element_axial.len() + 1;
    (0..n)
        .map(|i| {
            let adj: Vec<f64> = [i.checked_sub(1), (i < n - 1).then_some(i)]
                .into_iter()
                .flatten()
                .map(|e| element_axial[e])
                .collect();
            adj.iter().sum::<f64>() / adj.len() as f64
        })
        .collect()
}

/// Sinusoidal and helical buckling flags of a static profile ([`crate::diagnose::buckling`]).
pub fn buckling(case: &Case, model: &Model, rows: &[ProfileRow]) -> (bool, bool) {
    let axial: Vec<f64> = rows.iter().map(|r| r.axial_force_n).collect();
    crate::diagnose::buckling(case, model, &axial)
}

/// The hook load (N) of a string where it stops on its way
/// ([`crate::solve::statics::Stopped`]).
pub fn stopped_hook_load(stopped: &crate::solve::statics::Stopped) -> f64 {
    let sol = crate::solve::statics::stopped_solution(stopped);
    fe_rows(&stopped.model, &sol).1
}

/// Profile rows, hook load, surface torque and weight on bit of an FE static solution.
pub fn fe_rows(
    model: &Model,
    sol: &crate::solve::statics::StaticSolution,
) -> (Vec<ProfileRow>, f64, f64, f64) {
    let n = model.nodes.len();
    let mut wob = model.weight_on_bit;
    let mut side = vec![0.0; n];
    let mut in_contact = vec![false; n];
    for (site, (c, normal, _)) in model.sites.iter().zip(&sol.contact) {
        side[site.node] = *normal;
        in_contact[site.node] = *c && *normal > 0.0;
    }
    let rows: Vec<ProfileRow> = (0..n)
        .map(|i| {
            let adj: Vec<usize> = [i.checked_sub(1), (i < n - 1).then_some(i)]
                .into_iter()
                .flatten()
                .collect();
            let avg = |f: &dyn Fn(usize) -> f64| {
                adj.iter().map(|&e| f(e)).sum::<f64>() / adj.len() as f64
            };
            let axial = avg(&|e| sol.section_forces[e].axial);
            let area = avg(&|e| model.elements[e].section.area);
            let d = sol.state.u[i];
            let p = sol.state.position(model, i);
            let t = model.nodes[i].hole_axis;
            let d_t = sub(&d, &scale(&t, dot(&d, &t)));
            ProfileRow {
                von_mises_pa: f64::NAN,
                yield_utilisation: f64::NAN,
                md_m: model.nodes[i].md,
                x_m: p[0],
                y_m: p[1],
                z_m: p[2],
                axial_force_n: axial,
                axial_stress_pa: axial / area,
                torque_nm: avg(&|e| sol.section_forces[e].torque).abs(),
                bending_moment_nm: avg(&|e| {
                    sol.section_forces[e].bending[if e < i { 1 } else { 0 }]
                }),
                side_force_n: side[i],
                side_force_per_length_n_per_m: side[i] / model.tributary_length(i),
                lateral_displacement_m: dot(&d_t, &d_t).sqrt(),
                in_contact: in_contact[i],
            }
        })
        .collect();
    let t0 = model.nodes[0].hole_axis;
    let mut hook = -dot(
        &[
            sol.top_reaction[0],
            sol.top_reaction[1],
            sol.top_reaction[2],
        ],
        &t0,
    );
    if let crate::model::TopBoundary::HookLoad(h) = model.top {
        hook = h;
        let tb = model.nodes[n - 1].hole_axis;
        wob = -dot(
            &[
                sol.bit_reaction[0],
                sol.bit_reaction[1],
                sol.bit_reaction[2],
            ],
            &tb,
        );
    }
    let torque = dot(
        &[
            sol.top_reaction[3],
            sol.top_reaction[4],
            sol.top_reaction[5],
        ],
        &t0,
    )
    .abs();
    (rows, hook, torque, wob)
}

/// The words a solution's log says sites were added with ([`solve_in_hole`]).
pub const WALL_CONTACT: &str = "contact added where the string met the wall";

/// How often a static solution's load path left plain load steps, by its log: step cuts,
/// failed steps relaxed past, stage changes, the model's own sites taken where the guarded
/// solve failed — every line but [`WALL_CONTACT`]'s and the [`whirl_note`], which say what
/// the model is, not how its solve went. The step cuts of `holewall bench corpus` and of an
/// ensemble's static variants (a variant with any is `step_cut`, not `converged`).
pub fn path_events(log: &[String]) -> usize {
    log.iter()
        .filter(|l| !l.starts_with(WALL_CONTACT) && !l.starts_with(WHIRL_AVERAGED))
        .count()
}

/// The FE static solution of `model` (the case's, or a variant's of it) with the string
/// held in the hole wherever it meets the wall. Where the case has contact sites at its
/// stabilizers only (`contact.sites = "stabilizers"`), a compressed or sagging string
/// between them can bow out through the wall, which nothing there stops
/// ([`crate::diagnose::through_wall`]); so the string is solved with a **guard** site at
/// every node that has none — a pipe-body site with the case's wall law
/// ([`Case::contact`]), the disk of the wider adjacent element (tool joints included), the
/// hole section's friction — and the model keeps the guards in contact at the answer,
/// dropping the others: a site out of contact adds nothing to the residual or the tangent,
/// so the answer is, to the bit, an equilibrium of the model with only the sites kept, and
/// every node without a site lies inside its hole. The solution's log says where sites were
/// kept (every later output — profile, contact sites, a dynamic run from it — sees them).
///
/// Before stop 48 the string was solved at its own sites first and given sites where that
/// answer lay beyond the wall, up to four rounds: every stabilizer-contact corpus well left
/// the hole (a kilometre of pipe hangs as a cable), and that first solve cost up to 30×
/// the guarded one (corpus well 439: 4,237 Newton iterations, 31 s, to an answer 47 m
/// outside the hole; guarded: 119 iterations, 1.1 s, the same hook load to every digit).
///
/// Where the guarded solve fails (not for its time budget), the model with its own sites is
/// tried, and its answer is taken if it lies in the hole (the log says so). `options.
/// max_seconds` bounds all the solves together.
///
/// `add(model, nodes)` gives `model` its sites at `nodes` ([`add_wall_sites`] for a case's
/// model; a variant's applies its own overrides to them too,
/// [`crate::ensemble::apply_with_sites`]); it is called once a solve (a second time where
/// a failure is judged again for a whirl, [`hold_in_hole`]), with every node that has no
/// site.
pub fn solve_in_hole(
    case: &Case,
    model: &mut Model,
    add: &mut dyn FnMut(&mut Model, &[usize]),
    options: &crate::solve::statics::StaticOptions,
    progress: &mut dyn FnMut(&crate::solve::continuation::Progress),
) -> Result<crate::solve::statics::StaticSolution, crate::solve::statics::StaticError> {
    hold_in_hole(case, model, add, options, &mut |m, o| {
        crate::solve::statics::solve_static_started(m, o, progress)
    })
}

/// What a static solve of a model is to [`hold_in_hole`].
pub(crate) type StaticSolve<'s> = dyn FnMut(
        &Model,
        &crate::solve::statics::StaticOptions,
    ) -> Result<crate::solve::statics::StaticSolution, crate::solve::statics::StaticError>
    + 's;

/// The nodes of `model` without a contact site, the clamped top (node 0) aside: where
/// [`solve_in_hole`] puts its guards.
pub(crate) fn unheld_nodes(model: &Model) -> Vec<usize> {
    let held = model.site_nodes();
    (1..model.nodes.len()).filter(|&i| !held[i]).collect()
}

/// [`solve_in_hole`]'s answer from a solve `sol` of `guarded` (`own`, the model solved for,
/// with a guard site at each of its nodes without one): `guarded` with `own`'s sites and
/// the guards in contact at the answer, the others dropped (with their entries of
/// `sol.contact`), and `sol`, its log saying where sites were kept. A site out of contact
/// adds nothing to the residual or the tangent: `sol.state` is, to the bit, as much an
/// equilibrium of the model returned as of `guarded`. The static and dynamic ensembles'
/// engine starts take their answers here too.
pub(crate) fn keep_touching(
    own: &Model,
    mut guarded: Model,
    mut sol: crate::solve::statics::StaticSolution,
) -> (Model, crate::solve::statics::StaticSolution) {
    let mut held = vec![false; own.nodes.len()];
    for s in &own.sites {
        held[s.node] = true;
    }
    let keep: Vec<bool> = guarded
        .sites
        .iter()
        .zip(&sol.contact)
        .map(|(s, c)| held[s.node] || c.0)
        .collect();
    let kept: Vec<usize> = guarded
        .sites
        .iter()
        .zip(&keep)
        .filter(|(s, k)| **k && !held[s.node])
        .map(|(s, _)| s.node)
        .collect();
    let guards = guarded.sites.len() - own.sites.len();
    let mut k = keep.iter();
    guarded.sites.retain(|_| *k.next().expect("a flag a site"));
    let mut k = keep.iter();
    sol.contact.retain(|_| *k.next().expect("a flag a site"));
    if let (Some(first), Some(last)) = (kept.first(), kept.last()) {
        sol.log.push(format!(
            "{WALL_CONTACT}: {} pipe-body nodes between MD {:.0} m and {:.0} m (the string \
             solved with a guard site at each of its {guards} nodes without one; those out \
             of contact dropped)",
            kept.len(),
            guarded.nodes[*first].md,
            guarded.nodes[*last].md,
        ));
    }
    (guarded, sol)
}

/// [`solve_in_hole`]'s policy with the static solve given (`solve`; the tests give one that
/// fails where they want).
///
/// A turning string whose solve fails (not for its time budget) where the FE string stood
/// is judged again by the whirl's rule on its own axial forces there, carried to the full
/// loads ([`crate::diagnose::whirl_span_where_stopped`]): where that names a span the soft
/// string's compression did not (the FE string's neutral point higher, its drag more), the
/// model is solved once more at the whirl's average over both spans, and an answer says so
/// in its log ([`WHIRL_FROM_FE`]); where that solve fails too, the first failure is the
/// answer and says what was tried.
pub(crate) fn hold_in_hole(
    case: &Case,
    model: &mut Model,
    add: &mut dyn FnMut(&mut Model, &[usize]),
    options: &crate::solve::statics::StaticOptions,
    solve: &mut StaticSolve<'_>,
) -> Result<crate::solve::statics::StaticSolution, crate::solve::statics::StaticError> {
    let clock = std::time::Instant::now();
    let span = crate::diagnose::mark_whirling_sites(case, model);
    let mut failed = match hold_in_hole_at(case, model, add, options, solve, span) {
        Err(e) if !matches!(e, crate::solve::statics::StaticError::Budget { .. }) => e,
        done => return done,
    };
    let Some(stopped) = failed.stopped_mut() else {
        return Err(failed);
    };
    let Some(fe) = crate::diagnose::whirl_span_where_stopped(case, model, stopped) else {
        return Err(failed);
    };
    let both = span.map_or(fe, |(a, b)| (a.min(fe.0), b.max(fe.1)));
    if Some(both) == span {
        return Err(failed);
    }
    crate::diagnose::mark_span(model, Some(both));
    let mut options = *options;
    options.max_seconds = options
        .max_seconds
        .map(|s| (s - clock.elapsed().as_secs_f64()).max(0.0));
    match hold_in_hole_at(case, model, add, &options, solve, Some(both)) {
        Ok(mut sol) => {
            sol.log.push(format!(
                "{WHIRL_FROM_FE} ({}); the FE string's compression where it stopped, \
                 carried to the full loads, whirls between MD {:.0} and {:.0} m, where the \
                 soft string's did not: solved again at the whirl's average there",
                failed.to_string().lines().next().unwrap_or_default(),
                fe.0,
                fe.1
            ));
            Ok(sol)
        }
        Err(again) => {
            crate::diagnose::mark_span(model, span);
            if let crate::solve::statics::StaticError::LoadStep { reason, .. } = &mut failed {
                reason.push_str(&format!(
                    "; solved again at the whirl's average between MD {:.0} and {:.0} m, \
                     where the FE string's compression whirls: that failed too ({})",
                    both.0,
                    both.1,
                    again.to_string().lines().next().unwrap_or_default()
                ));
            }
            Err(failed)
        }
    }
}

/// The words that open the log line of an answer [`hold_in_hole`] found by the whirl's rule
/// on the FE string's own compression after a first solve failed (the corpus counts them).
pub const WHIRL_FROM_FE: &str = "the first solve failed";

/// [`hold_in_hole`] with the sites of the whirl's `span` marked: the solve with a guard
/// site at each node without one, then the model's own sites where that fails.
fn hold_in_hole_at(
    case: &Case,
    model: &mut Model,
    add: &mut dyn FnMut(&mut Model, &[usize]),
    options: &crate::solve::statics::StaticOptions,
    solve: &mut StaticSolve<'_>,
    span: Option<(f64, f64)>,
) -> Result<crate::solve::statics::StaticSolution, crate::solve::statics::StaticError> {
    let said = |mut sol: crate::solve::statics::StaticSolution| {
        note_whirl(&mut sol.log, span);
        sol
    };
    let free = unheld_nodes(model);
    if free.is_empty() {
        return solve(model, options).map(said);
    }
    let clock = std::time::Instant::now();
    let mut guarded = model.clone();
    add(&mut guarded, &free);
    // The same string with more sites: the same span (the soft string has no sites).
    crate::diagnose::mark_span(&mut guarded, span);
    let failed = match solve(&guarded, options) {
        Ok(sol) => {
            let (kept, sol) = keep_touching(model, guarded, sol);
            *model = kept;
            return Ok(said(sol));
        }
        Err(mut e) => {
            // Where the string stops, with the sites kept as for an answer.
            if let Some(st) = e.stopped_mut() {
                let sol = crate::solve::statics::stopped_solution(st);
                st.model = keep_touching(model, st.model.clone(), sol).0;
            }
            e
        }
    };
    if matches!(failed, crate::solve::statics::StaticError::Budget { .. }) {
        return Err(failed);
    }
    // The model with its own sites only: taken where its answer lies in the hole.
    let mut options = *options;
    options.max_seconds = options
        .max_seconds
        .map(|s| (s - clock.elapsed().as_secs_f64()).max(0.0));
    match solve(model, &options) {
        Ok(sol) if crate::diagnose::beyond_wall(case, model, &sol.state).is_empty() => {
            let mut sol = said(sol);
            sol.log.push(format!(
                "the solve with a guard site at every node failed ({}); the string solved at \
                 its own {} sites lies in the hole",
                failed.to_string().lines().next().unwrap_or_default(),
                model.sites.len()
            ));
            Ok(sol)
        }
        _ => Err(failed),
    }
}

/// The solver log's line (and the static command's note) for a turning string that
/// whirls between MD `from` and `to` (m) ([`crate::diagnose::whirl_span`]).
pub fn whirl_note(from: f64, to: f64) -> String {
    format!(
        "{WHIRL_AVERAGED} between MD {from:.0} and {to:.0} m: no weight holds the turning \
         string on the wall there, and it rolls round the hole; the circumferential friction \
         there acts as torque alone (its side force averages to nothing over a whirl; \
         `holewall run` gives the motion)"
    )
}

/// Adds the [`whirl_note`] of a string that whirls over `span` (MD from, to;
/// [`crate::diagnose::whirl_span`]) to its static solution's `log`: the CPU solve's
/// ([`solve_in_hole`]) and the engine's variants' alike.
pub fn note_whirl(log: &mut Vec<String>, span: Option<(f64, f64)>) {
    if let Some((from, to)) = span {
        log.push(whirl_note(from, to));
    }
}

/// The words that open [`whirl_note`] (`holewall static` finds the note by them to warn).
pub const WHIRL_AVERAGED: &str = "the string whirls, taken at the whirl's average,";

/// Pipe-body contact sites at `nodes` of `model` (the case's or a variant's of it), as
/// [`solve_in_hole`] adds them where the string meets the wall: the case's wall law, the
/// disk of the wider adjacent element (tool joints included: the radius
/// [`crate::diagnose::beyond_wall`] measures the clearance with), the hole section's
/// diameter and friction.
pub fn add_wall_sites(case: &Case, model: &mut Model, nodes: &[usize]) {
    let radii: Vec<f64> = (0..model.nodes.len())
        .map(|i| model.pipe_radius_at(i))
        .collect();
    crate::model::add_sites(
        model,
        nodes,
        |md| 0.5 * case.hole_at(md).diameter,
        |i| radii[i],
        |md| case.hole_at(md).friction,
        &case.contact,
        false,
    );
    model.sites.sort_by_key(|s| s.node);
}

/// The FE static solution of a case, with a progress bar (load factor reached) when
/// `show_progress`, within `options.max_seconds`, with the string held in the hole wherever
/// it meets the wall ([`solve_in_hole`]: the case's model keeps the sites added); a failure
/// says why ([`crate::diagnose::static_failure`]).
pub fn solve_with_progress(
    case: &mut Case,
    options: crate::solve::statics::StaticOptions,
    show_progress: bool,
) -> Result<crate::solve::statics::StaticSolution, crate::error::Error> {
    solve_or_stop(case, options, show_progress).map_err(|(e, _)| e)
}

/// As [`solve_with_progress`]; a failure also gives where the string stands if its load path
/// bracketed where it stops ([`crate::solve::statics::Stopped`], with the model's sites as
/// [`solve_in_hole`] keeps them).
pub fn solve_or_stop(
    case: &mut Case,
    options: crate::solve::statics::StaticOptions,
    show_progress: bool,
) -> Result<
    crate::solve::statics::StaticSolution,
    (
        crate::error::Error,
        Option<Box<crate::solve::statics::Stopped>>,
    ),
> {
    let bar = crate::output::progress_bar(
        show_progress,
        1000,
        "{bar:40} {percent:>3}% of the loads (static), {elapsed} elapsed\n{wide_msg}",
    );
    let mut model = case.model.clone();
    let solved = solve_in_hole(
        case,
        &mut model,
        &mut |m, nodes| add_wall_sites(case, m, nodes),
        &options,
        &mut |p| {
            bar.set_position((1000.0 * p.fraction()) as u64);
            if bar.is_hidden() {
                return;
            }
            if let Some(note) = p.note() {
                bar.set_message(note);
            }
        },
    );
    bar.finish_and_clear();
    case.model = model;
    solved.map_err(|mut e| {
        let stopped = e.take_stopped();
        (
            crate::error::Error::Failed(crate::diagnose::static_failure(case, &e)),
            stopped,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_model_s_own_notes_are_not_load_path_events() {
        let mut log = vec![format!("{WALL_CONTACT} at 3 nodes")];
        note_whirl(&mut log, Some((2400.0, 2500.0)));
        note_whirl(&mut log, None);
        assert_eq!(log.len(), 2, "a span-less string gets no note");
        assert_eq!(path_events(&log), 0);
        log.push("load step λ 0.5 → 1 cut to 0.75".into());
        assert_eq!(path_events(&log), 1);
    }
}
