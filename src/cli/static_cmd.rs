//! `holewall static CASE [--model fe|soft-string] --out DIR`: torque & drag, neutral point,
//! side forces (paper §3, Table 2, Figs 8, 10, 11).

use std::path::Path;

use serde::Serialize;

use crate::case::{load_case, Case};
use crate::error::Error;
use crate::model::Model;
use crate::output::RunFolder;

use crate::profile::{buckling, fe_rows, neutral_point, solve_or_stop, ProfileRow};

/// Which model computes the profile.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StaticModel {
    /// Finite elements: co-rotational beams, contact elements (stiff string).
    Fe,
    /// Johancsik soft-string torque & drag.
    SoftString,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Case title.
    pub title: String,
    /// `fe` or `soft-string`.
    pub model: String,
    /// Neutral point (effective axial force zero), from the bit (m); null if none.
    pub neutral_point_from_bit_m: Option<f64>,
    /// Neutral point from the surface (MD, m).
    pub neutral_point_from_surface_m: Option<f64>,
    /// Hook load (N).
    pub hook_load_n: f64,
    /// Surface torque (N·m).
    pub surface_torque_nm: f64,
    /// Weight on bit (N): as given, or the bit's reaction when the hook load is given.
    pub weight_on_bit_n: f64,
    /// Largest side force (N).
    pub max_side_force_n: f64,
    /// Where it acts (MD, m).
    pub max_side_force_md_m: f64,
    /// Compression beyond the sinusoidal-buckling load somewhere (Dawson–Paslay; vertical:
    /// Lubinski's 2.55·(EI w²)^(1/3)).
    pub sinusoidal_buckling: bool,
    /// Compression beyond √2 × that (helical buckling).
    pub helical_buckling: bool,
    /// The drag a helically buckled string adds to this profile, by Mitchell's wall force
    /// `r F²/4EI` at the full friction factor (N; 0 without helical buckling;
    /// [`crate::diagnose::helical_drag`]): missing from a soft string's hook load; where
    /// it is a sizeable part of the hook load, the soft string's answer is not to be trusted.
    pub helical_buckling_drag_n: f64,
    /// The bit's side force and tilt in the hole's frame (FE; [`crate::bha`] for the
    /// signs): null for the soft string, which has no bending stiffness.
    pub bit: Option<crate::bha::BitLoads>,
    /// The assembly's directional tendency at the case's weight on bit (FE;
    /// [`crate::bha::tendency`]): build and turn rates, equilibrium curvature.
    pub tendency: Option<crate::bha::tendency::Tendency>,
    /// Pipe strength along the graded components: the largest von Mises utilisation and
    /// where, the overpull margin at the surface, the largest torque against the RP 7G
    /// limit; null when no component has a grade.
    pub strength: Option<crate::strength::StrengthSummary>,
    /// The rig's side of the hook load (`[rig]`): block weight, line tensions and what the
    /// weight indicator reads while the block moves as the operation does
    /// ([`crate::rig`]); null without a `[rig]`.
    pub rig: Option<crate::rig::RigReading>,
    /// Newton iterations per completed load step (FE).
    pub newton_iterations: Vec<usize>,
    /// Load-step cuts and why (FE).
    pub solver_log: Vec<String>,
    /// What the case holds that is allowed but unusual ([`crate::case::Case::warnings`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Where the FE load path found that the string stops on its way (a lock-up): every
    /// figure above is then the string where it stands, at the fraction `load_factor` of
    /// the operation's friction and bit loads; absent where the loads were reached.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<StoppedSummary>,
}

/// `summary.json`'s `stopped` ([`crate::solve::statics::Stopped`]).
#[derive(Clone, Debug, Serialize)]
pub struct StoppedSummary {
    /// The largest fraction of the friction coefficients and bit loads (and a bent sub's
    /// bend) at which the string has an equilibrium: where it stands.
    pub load_factor: f64,
    /// The smallest fraction at which the load path found none.
    pub none_at: f64,
    /// Why the loads were not reached (the solve's failure, as the command prints it).
    pub failure: String,
}

/// Options of `holewall static`.
#[derive(Clone, Copy, Debug, Default)]
pub struct StaticCommandOptions {
    /// Progress bar on stderr.
    pub show_progress: bool,
    /// Wall-clock budget of the FE solve (s).
    pub max_seconds: Option<f64>,
}

/// Runs the command; returns the summary.
pub fn run(
    case_path: &Path,
    which: StaticModel,
    out: &Path,
    options: StaticCommandOptions,
) -> Result<Summary, Error> {
    let start = std::time::Instant::now();
    let mut case = load_case(case_path)?;
    super::print_warnings(&case);
    let folder = RunFolder::prepare(out)?.with_report("static", case_path);
    // The FE solve first: it gives the case's model contact sites wherever the string meets
    // the wall (`profile::solve_in_hole`), and every output below reads that model.
    // Where the string stops on its way (a lock-up): the outputs are written for the string
    // where it stands, then the command fails with the solve's message.
    let mut stopped: Option<(StoppedSummary, Error)> = None;
    let fe = match which {
        StaticModel::Fe => {
            let statics = case
                .settings()
                .with_max_seconds(options.max_seconds)
                .statics();
            match solve_or_stop(&mut case, statics, options.show_progress) {
                Ok(sol) => Some(sol),
                Err((e, Some(st))) => {
                    let solution = crate::solve::statics::stopped_solution(&st);
                    let st = *st;
                    case.model = st.model;
                    case.title = format!(
                        "{} — {}: friction and bit loads × {:.3}, none found at × {:.3}",
                        case.title,
                        if crate::diagnose::stops(&case.model) {
                            "where it stops"
                        } else {
                            "the largest loads with an equilibrium"
                        },
                        st.lambda,
                        st.none_at
                    );
                    stopped = Some((
                        StoppedSummary {
                            load_factor: st.lambda,
                            none_at: st.none_at,
                            failure: e.to_string(),
                        },
                        e,
                    ));
                    Some(solution)
                }
                Err((e, None)) => return Err(e),
            }
        }
        StaticModel::SoftString => None,
    };
    let load_factor = stopped.as_ref().map_or(1.0, |(s, _)| s.load_factor);
    let (stopped, failure) = match stopped {
        Some((note, e)) => (Some(note), Some(e)),
        None => (None, None),
    };
    let case = case;
    let model = &case.model;
    let n = model.nodes.len();
    let mut wob = model.weight_on_bit;
    let mut solver_log = Vec::new();
    let mut bit = None;
    let mut tendency = None;
    let mut through_wall = None;
    let mut span_sag = None;
    let (rows, hook, torque, its) = match which {
        StaticModel::Fe => {
            let sol = fe.ok_or(Error::failed("no FE solution"))?;
            let (rows, hook, torque, w) = fe_rows(model, &sol);
            through_wall = crate::diagnose::through_wall_warning(&case, model, &sol.state);
            let element_axial: Vec<f64> = sol.section_forces.iter().map(|f| f.axial).collect();
            span_sag = crate::diagnose::span_through_wall_warning(
                &case,
                model,
                &sol.state,
                &element_axial,
            );
            wob = w;
            solver_log = sol.log.clone();
            bit = Some(crate::bha::bit_loads_of(model, &sol));
            // The tendency's BHA-model solves share the run's time budget.
            let settings = crate::bha::tendency::TendencySettings {
                deadline: options
                    .max_seconds
                    .map(|s| start + std::time::Duration::from_secs_f64(s)),
                ..case.tendency.settings
            };
            if options.show_progress {
                eprintln!("holewall: the BHA's tendency (BHA models in curved holes)…");
            }
            tendency = Some(crate::bha::tendency::assembly_tendency(
                model,
                case.bha_length,
                w,
                &settings,
            ));
            (rows, hook, torque, sol.iterations)
        }
        StaticModel::SoftString => {
            if let crate::model::TopBoundary::HookLoad(_) = model.top {
                return Err(crate::error::InputError {
                    source_name: case_path.display().to_string(),
                    line: 0,
                    key: "operation.hook_load".into(),
                    message: "the soft-string model needs the weight on bit: give \
                              operation.weight_on_bit instead of hook_load (or --model fe)"
                        .into(),
                }
                .into());
            }
            let prof = case.soft_string();
            let rows: Vec<ProfileRow> = (0..n)
                .map(|i| {
                    let e = i.min(n - 2);
                    let area = model.elements[e].section.area;
                    let side = if i < n - 1 { prof.side_force[i] } else { 0.0 };
                    ProfileRow {
                        von_mises_pa: f64::NAN,
                        yield_utilisation: f64::NAN,
                        md_m: model.nodes[i].md,
                        x_m: model.nodes[i].position[0],
                        y_m: model.nodes[i].position[1],
                        z_m: model.nodes[i].position[2],
                        axial_force_n: prof.tension[i],
                        axial_stress_pa: prof.tension[i] / area,
                        torque_nm: prof.torque[i],
                        bending_moment_nm: 0.0,
                        side_force_n: side,
                        side_force_per_length_n_per_m: side / model.elements[e].length0,
                        lateral_displacement_m: 0.0,
                        in_contact: side > 0.0,
                    }
                })
                .collect();
            (rows, prof.hook_load(), prof.surface_torque(), vec![])
        }
    };
    let mut rows = rows;
    // Pipe strength along the graded components (issue 26).
    let loads: Vec<crate::strength::Loads> = rows
        .iter()
        .map(|r| crate::strength::Loads {
            md: r.md_m,
            tvd: r.z_m,
            axial_force: r.axial_force_n,
            bending_moment: r.bending_moment_nm,
            torque: r.torque_nm,
        })
        .collect();
    let (stresses, strength) = crate::strength::assess(
        &loads,
        &case.strength,
        &|i| model.elements[i.min(n - 2)].component,
        &|i| {
            let e = &model.elements[i.min(n - 2)];
            (e.outer_diameter, e.inner_diameter())
        },
        (case.mud_density, case.mud_inside_density),
        hook,
    );
    for (r, (vm, u)) in rows.iter_mut().zip(&stresses) {
        r.von_mises_pa = *vm;
        r.yield_utilisation = *u;
    }
    let np = neutral_point(&rows);
    let (k_max, max_side) = rows
        .iter()
        .enumerate()
        .fold((0, 0.0f64), |(bk, bv), (k, r)| {
            if r.side_force_n > bv {
                (k, r.side_force_n)
            } else {
                (bk, bv)
            }
        });
    let (sinusoidal, helical) = buckling(&case, model, &rows);
    let axial: Vec<f64> = rows.iter().map(|r| r.axial_force_n).collect();
    let mut warnings = case.warnings.clone();
    // Either model: an answer past every grade's yield is no answer (stop 68).
    if let Some(w) = crate::diagnose::past_yield_warning(&case, &axial) {
        eprintln!("holewall: warning: {w}");
        warnings.push(w);
    }
    if let StaticModel::Fe = which {
        if let Some(w) = crate::diagnose::unresolved_helix(&case, &axial) {
            eprintln!("holewall: warning: {w}");
            warnings.push(w);
        }
        // (Not for the string where it stops: that equilibrium is the one it reaches.)
        if let Some(w) =
            crate::diagnose::locked_up_warning(&case, hook).filter(|_| stopped.is_none())
        {
            eprintln!("holewall: warning: {w}");
            warnings.push(w);
        }
        // A turning string that whirls, taken at the whirl's average (stop 69).
        let whirl = solver_log
            .iter()
            .find(|l| l.starts_with(crate::profile::WHIRL_AVERAGED))
            .cloned();
        let relaxed = crate::diagnose::relaxed_warning(&solver_log);
        for w in [through_wall, span_sag, whirl, relaxed]
            .into_iter()
            .flatten()
        {
            eprintln!("holewall: warning: {w}");
            warnings.push(w);
        }
    }
    let summary = Summary {
        warnings,
        title: case.title.clone(),
        model: match which {
            StaticModel::Fe => "fe".into(),
            StaticModel::SoftString => "soft-string".into(),
        },
        neutral_point_from_bit_m: np.map(|md| case.bit_md - md),
        neutral_point_from_surface_m: np,
        hook_load_n: hook,
        surface_torque_nm: torque,
        weight_on_bit_n: wob,
        max_side_force_n: max_side,
        max_side_force_md_m: rows[k_max].md_m,
        sinusoidal_buckling: sinusoidal,
        helical_buckling: helical,
        // Linear in the friction factor, which is the case's × `load_factor` here.
        helical_buckling_drag_n: load_factor * crate::diagnose::helical_drag(&case, &axial),
        bit,
        tendency,
        strength,
        rig: case.rig.map(|r| {
            r.reading(
                hook,
                crate::rig::Travel::of_axial_speed(case.model.axial_speed),
            )
        }),
        newton_iterations: its,
        solver_log,
        stopped,
    };
    let dir = folder.path();
    crate::output::write_csv_rows(&dir.join("profile.csv"), &rows)?;
    write_plots(&case, which, &rows, np, summary.bit.as_ref(), dir)?;
    if summary.strength.is_some() {
        tension_torque_plot(&case, &rows, dir)?;
    }
    let json = serde_json::to_vec_pretty(&summary)?;
    folder.finish(&json)?;
    match failure {
        Some(e) => Err(Error::Failed(format!(
            "{e}\n  written to {}: the string {}at {:.1} % of the friction and bit loads, \
             the largest fraction with an equilibrium found (summary.json's `stopped`)",
            out.display(),
            // Not run in or out, a string does not stop (crate::diagnose::static_failure).
            if crate::diagnose::stops(&case.model) {
                "where it stops, "
            } else {
                ""
            },
            100.0 * load_factor
        ))),
        None => Ok(summary),
    }
}

fn write_plots(
    case: &Case,
    which: StaticModel,
    rows: &[ProfileRow],
    np: Option<f64>,
    bit: Option<&crate::bha::BitLoads>,
    out: &Path,
) -> std::io::Result<()> {
    use crate::plots::{line_plot, Marker, Series};
    let model = &case.model;
    let name = match which {
        StaticModel::Fe => "FE",
        StaticModel::SoftString => "soft string",
    };
    let col = |f: &dyn Fn(&ProfileRow) -> f64| -> Vec<(f64, f64)> {
        rows.iter().map(|r| (r.md_m, f(r))).collect()
    };
    let np_marker: Vec<Marker> = np
        .map(|md| Marker {
            label: "neutral point",
            x: md,
            y: 0.0,
        })
        .into_iter()
        .collect();
    // The profiles along the string in engineering units: (file, title, y label, column,
    // neutral point marked).
    type Column = fn(&ProfileRow) -> f64;
    let profiles: [(&str, &str, &str, Column, bool); 3] = [
        (
            "axial_force.png",
            "axial force",
            "effective axial force, tension + (kN)",
            |r| r.axial_force_n / 1e3,
            true,
        ),
        (
            "axial_stress.png",
            "effective axial stress",
            "effective axial stress F_eff/A, tension + (MPa)",
            |r| r.axial_stress_pa / 1e6,
            true,
        ),
        (
            "torque.png",
            "torque",
            "torque (kN·m)",
            |r| r.torque_nm / 1e3,
            false,
        ),
    ];
    for (file, what, y_label, f, marked) in profiles {
        line_plot(
            &out.join(file),
            &format!("{}: {what} ({name})", case.title),
            "MD (m)",
            y_label,
            &[Series {
                name,
                points: col(&f),
                wide: false,
            }],
            if marked { &np_marker } else { &[] },
        )?;
    }
    // Side force per unit length; each stabilizer's force (a point load) marked.
    let stab_labels = stabilizer_labels(model, rows);
    let stab_markers: Vec<Marker> = stab_labels
        .iter()
        .map(|(label, x, y)| Marker {
            label,
            x: *x,
            y: *y,
        })
        .collect();
    line_plot(
        &out.join("side_force.png"),
        &format!("{}: side force per unit length ({name})", case.title),
        "MD (m)",
        "side force per length (kN/m)",
        &[Series {
            name,
            points: col(&|r| r.side_force_per_length_n_per_m / 1e3),
            wide: false,
        }],
        &stab_markers,
    )?;
    // The BHA (bit up to the first drill pipe): lateral displacement against the radial
    // clearance it has there.
    let bha_top = case.bit_md - case.bha_length;
    let in_bha = |k: usize| rows[k].md_m >= bha_top - 1e-9;
    let bha: Vec<(f64, f64)> = (0..rows.len())
        .filter(|&k| in_bha(k))
        .map(|k| (rows[k].md_m, 1e3 * rows[k].lateral_displacement_m))
        .collect();
    let clearance = bha_clearance_band(case, model, bha_top);
    // The bit's side force on the formation and its tilt, at the bit (issue 25).
    let bit_label: Option<String> = bit.map(|b| {
        format!(
            "bit: {:+.2} kN high side, {:+.2} kN right; tilt {:+.3}° high side, {:+.3}° right",
            b.high_side_force_n / 1e3,
            b.right_side_force_n / 1e3,
            b.tilt_high_side_deg,
            b.tilt_right_side_deg
        )
    });
    line_plot(
        &out.join("bha_deflection.png"),
        &format!(
            "{}: BHA lateral deflection, {:.0} m above the bit ({name})",
            case.title, case.bha_length
        ),
        "MD (m)",
        "lateral displacement from the hole axis (mm)",
        &[
            Series {
                name: "radial clearance",
                points: clearance,
                wide: true,
            },
            Series {
                name,
                points: bha,
                wide: false,
            },
        ],
        &bit_label
            .iter()
            .map(|l| Marker {
                label: l,
                x: case.bit_md,
                y: 0.0,
            })
            .collect::<Vec<_>>(),
    )?;
    if which == StaticModel::Fe {
        let ss = case.soft_string();
        let ss_pts: Vec<(f64, f64)> = model
            .nodes
            .iter()
            .zip(&ss.tension)
            .map(|(n, t)| (n.md, *t / 1e3))
            .collect();
        line_plot(
            &out.join("fe_vs_soft_string.png"),
            &format!("{}: axial force, FE vs soft string", case.title),
            "MD (m)",
            "effective axial force, tension + (kN)",
            &[
                Series {
                    name: "FE",
                    points: col(&|r| r.axial_force_n / 1e3),
                    wide: false,
                },
                Series {
                    name: "soft string",
                    points: ss_pts,
                    wide: true,
                },
            ],
            &np_marker,
        )?;
    }
    Ok(())
}

/// The BHA plot's radial-clearance band (MD, mm) from `bha_top` to the bit, as steps: each
/// element's body clearance over its length, a stabilizer's blade clearance over the half
/// elements either side of its node — vertical edges where the diameter changes, not
/// sloped lines from a stabilizer node to the collar nodes beside it.
pub fn bha_clearance_band(case: &Case, model: &Model, bha_top: f64) -> Vec<(f64, f64)> {
    let md = |k: usize| model.nodes[k].md;
    let clearance = |at: f64, od: f64| 1e3 * 0.5 * (case.hole_diameter_at(at) - od);
    // Blade diameter per node, looked up once (not a search over the sites per element).
    let mut blades: Vec<Option<f64>> = vec![None; model.nodes.len()];
    for s in model.sites.iter().filter(|s| s.stabilizer) {
        blades[s.node] = Some(2.0 * s.params.disk_radius);
    }
    let blade = |k: usize| blades[k];
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (e, el) in model.elements.iter().enumerate() {
        let (a, b) = (md(e), md(e + 1));
        if a < bha_top - 1e-9 {
            continue;
        }
        let mid = 0.5 * (a + b);
        let body = clearance(mid, el.outer_diameter);
        // The element's halves: the blade's clearance on the half at a stabilizer node.
        let first = blade(e).map_or(body, |d| clearance(a, d));
        let second = blade(e + 1).map_or(body, |d| clearance(b, d));
        for p in [(a, first), (mid, first), (mid, second), (b, second)] {
            // A point on a level run is left out: one segment per level, so the wide band
            // has no joints along it.
            let n = out.len();
            if n >= 2 && out[n - 1].1 == p.1 && out[n - 2].1 == p.1 {
                out[n - 1] = p;
            } else {
                out.push(p);
            }
        }
    }
    out
}

/// The side-force plot's stabilizer labels: `(label, MD, side force per length kN/m)`, in
/// the one numbering ([`Model::stabilizer_sites`]: stab1 nearest the bit), e.g.
/// `stab1: 4.2 kN`.
pub fn stabilizer_labels(model: &Model, rows: &[ProfileRow]) -> Vec<(String, f64, f64)> {
    model
        .stabilizer_sites()
        .iter()
        .enumerate()
        .filter_map(|(k, &site)| {
            let r = rows.get(model.sites[site].node)?;
            Some((
                format!(
                    "{}: {:.1} kN",
                    crate::model::stabilizer_name(k + 1),
                    r.side_force_n / 1e3
                ),
                r.md_m,
                r.side_force_per_length_n_per_m / 1e3,
            ))
        })
        .collect()
}

/// The tension–torque envelope (API RP 7G) of the surface's component, if graded, with the
/// string's operating points (true axial force, torque) along its graded components.
fn tension_torque_plot(case: &Case, rows: &[ProfileRow], out: &Path) -> std::io::Result<()> {
    use crate::plots::{line_plot, Series};
    let model = &case.model;
    let n = model.nodes.len();
    let component = |i: usize| model.elements[i.min(n - 2)].component;
    let Some(top) = case.strength.get(component(0)).copied().flatten() else {
        return Ok(());
    };
    let yield_n = top.tensile_yield_n();
    let envelope: Vec<(f64, f64)> = (0..=60)
        .map(|k| {
            let p = yield_n * k as f64 / 60.0;
            (p / 1e3, top.torque_limit_nm(p) / 1e3)
        })
        .collect();
    let points: Vec<(f64, f64)> = rows
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            case.strength
                .get(component(*i))
                .copied()
                .flatten()
                .is_some()
        })
        .map(|(i, r)| {
            let e = &model.elements[i.min(n - 2)];
            let (od, id) = (e.outer_diameter, e.inner_diameter());
            let f = crate::strength::true_axial_force(
                r.axial_force_n,
                r.z_m,
                (case.mud_density, case.mud_inside_density),
                od,
                id,
            );
            (f / 1e3, r.torque_nm.abs() / 1e3)
        })
        .collect();
    let name = format!(
        "{} {:.3} in envelope ({:.0} % wall)",
        top.grade,
        model.elements[0].outer_diameter / 0.0254,
        100.0 * top.wall_fraction
    );
    let mut series = vec![
        Series {
            name: &name,
            points: envelope,
            wide: true,
        },
        Series {
            name: "along the string (graded components)",
            points,
            wide: false,
        },
    ];
    let makeup_name;
    if let Some(m) = top.makeup_torque_nm {
        makeup_name = format!(
            "tool-joint make-up torque {:.1} kN·m (the connection's limit)",
            m / 1e3
        );
        series.push(Series {
            name: &makeup_name,
            points: vec![(0.0, m / 1e3), (yield_n / 1e3, m / 1e3)],
            wide: false,
        });
    }
    line_plot(
        &out.join("tension_torque.png"),
        &format!("{}: tension–torque envelope (API RP 7G)", case.title),
        "true axial force, tension + (kN)",
        "torque (kN·m)",
        &series,
        &[],
    )
}
