//! A dynamic run of a case (what `holewall run CASE --out DIR` and the ensemble's per-variant
//! run folders do): the string spun up from its static equilibrium and integrated in time
//! (paper §3.1, Figs 5–10), with a progress bar; writes only the outputs the case's
//! `[dynamics].outputs` asks for. Prints nothing: what a user should read (a budget spent,
//! a window not at steady state) comes back in the [`RunSummary`].

use std::path::Path;

use serde::Serialize;

use crate::case::Case;
use crate::error::{Error, InputError};
use crate::output::write_atomic;
use crate::physics::vec3::{dot, scale, sub};
use crate::plots::{line_plot, Series};
use crate::solve::dynamics::{strain_energy, DynamicState, Dynamics};

/// `summary.json` of a run.
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// Case title.
    pub title: String,
    /// Simulated time (s).
    pub duration_s: f64,
    /// Completed steps.
    pub steps: usize,
    /// Mean Newton iterations per step.
    pub mean_newton_iterations: f64,
    /// Step cuts and regrowth.
    pub log: Vec<String>,
    /// Outputs written.
    pub outputs: Vec<String>,
    /// The case's duration (s); `duration_s` is less where the budget stopped the run.
    pub requested_duration_s: f64,
    /// Why the run ended before `requested_duration_s` (the `--max-seconds` budget), if it did.
    pub stopped_early: Option<String>,
    /// Per stabilizer, its whirl over the run's second half ([`crate::whirl`]), with `whirl`.
    pub whirl: Vec<SiteWhirl>,
    /// An offset start scaled down to stay in the hole ([`crate::case::Case::offset_scale`]),
    /// and why the run's second half (where whirl is analysed) is not a steady state
    /// ([`crate::whirl::run_notes`]); also on stderr.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub analysis_notes: Vec<String>,
    /// What the case holds that is allowed but unusual ([`crate::case::Case::warnings`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// A stabilizer's whirl in `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct SiteWhirl {
    /// The stabilizer's name, `stab1` nearest the bit ([`crate::model::stabilizer_name`]).
    pub stabilizer: String,
    /// Contact site index (the `site` column of `contact_sites.csv`).
    pub site: usize,
    /// Its MD (m).
    pub md_m: f64,
    /// The analysis.
    #[serde(flatten)]
    pub whirl: crate::whirl::Whirl,
    /// Why this whirl is not to be read as steady ([`crate::whirl::window_notes`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// Options of `holewall run`.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunOptions {
    /// Progress bars on stderr.
    pub show_progress: bool,
    /// Wall-clock budget (s) for the static start and the integration together: the run
    /// stops at the next output instant once it is spent, and writes what it has.
    pub max_seconds: Option<f64>,
}

struct Recorder {
    series: Vec<[f64; 6]>, // t, bit axial displacement, surface torque, KE, SE, KE+SE
    sites: Vec<(f64, usize, [f64; 5])>, // t, site, [lateral x, lateral y, radius, normal force, spin]
    stress: Vec<(f64, f64, f64)>,       // t, md, axial stress
}

fn record(
    case: &Case,
    dynamics: &Dynamics,
    s: &DynamicState,
    rec: &mut Recorder,
    want: &dyn Fn(&str) -> bool,
) {
    let model = &case.model;
    let n = model.nodes.len();
    let bit = n - 1;
    let tb = model.nodes[bit].hole_axis;
    let bit_axial = dot(&s.q.u[bit], &tb);
    let forces = |i: usize| crate::solve::statics::element_section_forces(model, &s.q, i);
    let torque = forces(0).torque.abs();
    let ke = if want("energy") {
        dynamics.kinetic_energy(s)
    } else {
        0.0
    };
    let se = if want("energy") {
        strain_energy(model, &s.q)
    } else {
        0.0
    };
    rec.series.push([s.t, bit_axial, torque, ke, se, ke + se]);
    if want("lateral") || want("contact_forces") || want("spin") || want("whirl") {
        let contact = dynamics.contact_forces(s);
        for (k, (site, out)) in model.sites.iter().zip(contact).enumerate() {
            let node = &model.nodes[site.node];
            let d = s.q.u[site.node];
            let d_t = sub(&d, &scale(&node.hole_axis, dot(&d, &node.hole_axis)));
            let f = &node.frame0;
            let (ex, ey) = ([f[0][1], f[1][1], f[2][1]], [f[0][2], f[1][2], f[2][2]]);
            let r = dot(&d_t, &d_t).sqrt();
            let normal = if r > 0.0 {
                dot(&[out.g[0], out.g[1], out.g[2]], &d_t) / r
            } else {
                0.0
            };
            let w: [f64; 3] = std::array::from_fn(|j| s.v[6 * site.node + 3 + j]);
            rec.sites.push((
                s.t,
                k,
                [
                    dot(&d_t, &ex),
                    dot(&d_t, &ey),
                    r,
                    normal,
                    dot(&node.hole_axis, &w),
                ],
            ));
        }
    }
    if want("axial_stress") {
        for i in 0..model.elements.len() {
            let md = 0.5 * (model.nodes[i].md + model.nodes[i + 1].md);
            rec.stress
                .push((s.t, md, forces(i).axial / model.elements[i].section.area));
        }
    }
}

fn csv_bytes(header: &[&str], rows: impl Iterator<Item = Vec<f64>>) -> Result<Vec<u8>, Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header).map_err(Error::from)?;
    for r in rows {
        w.write_record(r.iter().map(|x| x.to_string()))
            .map_err(Error::from)?;
    }
    w.into_inner().map_err(Error::encode)
}

/// `summary.json` of a run, as bytes.
pub fn summary_json(summary: &RunSummary) -> Result<Vec<u8>, Error> {
    Ok(serde_json::to_vec_pretty(summary)?)
}

/// Runs a loaded case (its model may carry an ensemble variant's overrides), writing its
/// files into the folder `out` as it is (the caller checked it) and `summary.json` last.
pub fn run_case_into(case: &Case, out: &Path, show_progress: bool) -> Result<RunSummary, Error> {
    std::fs::create_dir_all(out)?;
    let summary = run_case(
        case,
        out,
        RunOptions {
            show_progress,
            max_seconds: None,
        },
    )?;
    write_atomic(&out.join("summary.json"), &summary_json(&summary)?)?;
    Ok(summary)
}

/// Runs a loaded case and writes every output but `summary.json` into the existing folder
/// `out`; returns the summary.
pub fn run_case(case: &Case, out: &Path, run_options: RunOptions) -> Result<RunSummary, Error> {
    let clock = std::time::Instant::now();
    let show_progress = run_options.show_progress;
    let case_path = &case.path;
    let settings = case.dynamics.clone().ok_or_else(|| {
        Error::Input(InputError { source_name: case_path.display().to_string(), line: 1, key: "dynamics".into(), message: "holewall run needs a [dynamics] table (duration, time_step, …); see cases/README.md".into() })
    })?;
    // The static start gives the model contact sites wherever the string meets the wall
    // (`profile::solve_in_hole`); the run is of that model.
    let mut held = case.clone();
    let start = crate::profile::solve_with_progress(
        &mut held,
        case.settings()
            .with_max_seconds(run_options.max_seconds)
            .statics(),
        show_progress,
    )
    .map_err(|e| Error::failed(format!("static start: {e}")))?;
    let case = &held;
    let model = &case.model;
    let options = case.settings().dynamics();
    let density = case.element_density.clone();
    let mut dynamics = Dynamics::new(model, options, &|e| density[e]);
    // An offset start that would put the BHA through its wall is scaled down: say so.
    let offset = settings.initial_lateral_offset;
    let share = case.offset_scale(model, &start.state);
    let offset_note = (offset != 0.0 && share < 1.0).then(|| {
        format!(
            "initial_lateral_offset: {:.2} mm would start the BHA beyond its wall from where it \
             rests; the run starts {:.2} mm off its equilibrium{} (the largest half sine that \
             stays in the hole)",
            1e3 * offset,
            1e3 * offset * share.abs(),
            if share < 0.0 {
                ", the other way (off the wall)"
            } else {
                ""
            }
        )
    });
    let (q0, v0) = case.dynamic_start(model, start.state);
    let mut s = dynamics.initial_state_with(q0, v0).map_err(Error::failed)?;
    let want = |name: &str| settings.outputs.iter().any(|o| o == name);
    let mut rec = Recorder {
        series: Vec::new(),
        sites: Vec::new(),
        stress: Vec::new(),
    };
    record(case, &dynamics, &s, &mut rec, &want);
    let bar = crate::output::progress_bar(
        show_progress,
        1000,
        "{bar:40} {percent:>3}% t = {msg} s, {elapsed} elapsed, eta {eta}",
    );
    let mut next_output = settings.output_interval;
    let mut pending: Vec<DynamicState> = Vec::new();
    let mut observe = |_: &Dynamics, st: &DynamicState| {
        bar.set_position((1000.0 * st.t / settings.duration) as u64);
        bar.set_message(format!("{:.3}", st.t));
        if st.t >= next_output - 1e-9 {
            pending.push(st.clone());
            next_output += settings.output_interval;
        }
    };
    let mut stopped_early = None;
    match run_options.max_seconds {
        // No budget: one call, the steps exactly as the case sets them.
        None => dynamics
            .run(&mut s, settings.duration, &mut observe)
            .map_err(Error::failed)?,
        // A budget: output interval by output interval, the clock read in between.
        Some(budget) => {
            while s.t < settings.duration - 1e-12 {
                if clock.elapsed().as_secs_f64() > budget {
                    stopped_early = Some(format!(
                        "the --max-seconds budget ({budget} s) was spent at t = {:.4} s of {} s",
                        s.t, settings.duration
                    ));
                    break;
                }
                // A whole number of steps (the output interval's, at least one), so that a
                // chunk ends on the steps' grid and the run takes the steps it takes
                // unbounded (`solve::dynamics::control`).
                let dt = settings.time_step;
                let steps = (settings.output_interval / dt).round().max(1.0);
                let until = (s.t + steps * dt).min(settings.duration);
                dynamics
                    .run(&mut s, until, &mut observe)
                    .map_err(Error::failed)?;
            }
        }
    }
    bar.finish_and_clear();
    for st in &pending {
        record(case, &dynamics, st, &mut rec, &want);
    }

    let mut written = Vec::new();
    let t: Vec<f64> = rec.series.iter().map(|r| r[0]).collect();
    // A time series in display units (`scale` × SI).
    let col = |k: usize, scale: f64| -> Vec<(f64, f64)> {
        rec.series.iter().map(|r| (r[0], scale * r[k])).collect()
    };
    let mut header = vec!["t_s"];
    let mut cols = vec![0usize];
    for (name, h, k) in [
        ("bit_displacement", "bit_axial_displacement_m", 1),
        ("surface_torque", "surface_torque_nm", 2),
    ] {
        if want(name) {
            header.push(h);
            cols.push(k);
        }
    }
    if want("energy") {
        header.extend(["kinetic_energy_j", "strain_energy_j", "mechanical_energy_j"]);
        cols.extend([3, 4, 5]);
    }
    write_atomic(
        &out.join("timeseries.csv"),
        &csv_bytes(
            &header,
            rec.series
                .iter()
                .map(|r| cols.iter().map(|&k| r[k]).collect()),
        )?,
    )?;
    written.push("timeseries.csv".to_string());
    let title = &case.title;
    if want("bit_displacement") {
        line_plot(
            &out.join("bit_displacement.png"),
            &format!("{title}: bit axial displacement (Fig 5)"),
            "t (s)",
            "displacement along the hole axis, down + (mm)",
            &[Series {
                name: "bit",
                points: col(1, 1e3),
                wide: false,
            }],
            &[],
        )?;
        written.push("bit_displacement.png".into());
    }
    if want("surface_torque") {
        line_plot(
            &out.join("surface_torque.png"),
            &format!("{title}: surface torque"),
            "t (s)",
            "torque (kN·m)",
            &[Series {
                name: "top",
                points: col(2, 1e-3),
                wide: false,
            }],
            &[],
        )?;
        written.push("surface_torque.png".into());
    }
    if want("energy") {
        line_plot(
            &out.join("energy.png"),
            &format!("{title}: energy"),
            "t (s)",
            "energy (kJ)",
            &[
                Series {
                    name: "kinetic",
                    points: col(3, 1e-3),
                    wide: false,
                },
                Series {
                    name: "strain",
                    points: col(4, 1e-3),
                    wide: false,
                },
                Series {
                    name: "kinetic + strain",
                    points: col(5, 1e-3),
                    wide: false,
                },
            ],
            &[],
        )?;
        written.push("energy.png".into());
    }
    if !rec.sites.is_empty() {
        let header = [
            "t_s",
            "site",
            "stabilizer",
            "md_m",
            "lateral_x_m",
            "lateral_y_m",
            "lateral_radius_m",
            "normal_force_n",
            "spin_rate_rad_s",
        ];
        let numbers = model.stabilizer_numbers();
        let rows = rec.sites.iter().map(|(t, k, v)| {
            vec![
                *t,
                *k as f64,
                numbers[*k] as f64,
                model.nodes[model.sites[*k].node].md,
                v[0],
                v[1],
                v[2],
                v[3],
                v[4],
            ]
        });
        write_atomic(&out.join("contact_sites.csv"), &csv_bytes(&header, rows)?)?;
        written.push("contact_sites.csv".into());
        for (number, &k) in model.stabilizer_sites().iter().enumerate() {
            let site = &model.sites[k];
            let stab = crate::model::stabilizer_name(number + 1);
            let pts = |j: usize, scale: f64| -> Vec<(f64, f64)> {
                rec.sites
                    .iter()
                    .filter(|r| r.1 == k)
                    .map(|r| (r.0, scale * r.2[j]))
                    .collect()
            };
            let md = model.nodes[site.node].md;
            if want("lateral") {
                line_plot(
                    &out.join(format!("lateral_{stab}.png")),
                    &format!("{title}: lateral displacement of {stab} (MD {md:.1} m, Fig 6)"),
                    "t (s)",
                    "radial displacement (mm)",
                    &[
                        Series {
                            name: "radial clearance",
                            points: vec![
                                (0.0, 1e3 * site.params.clearance),
                                (
                                    t.last().copied().unwrap_or(0.0),
                                    1e3 * site.params.clearance,
                                ),
                            ],
                            wide: true,
                        },
                        Series {
                            name: "radius",
                            points: pts(2, 1e3),
                            wide: false,
                        },
                    ],
                    &[],
                )?;
                let orbit: Vec<(f64, f64)> = rec
                    .sites
                    .iter()
                    .filter(|r| r.1 == k)
                    .map(|r| (1e3 * r.2[0], 1e3 * r.2[1]))
                    .collect();
                crate::plots::orbit_plot(
                    &out.join(format!("orbit_{stab}.png")),
                    &format!("{title}: orbit of {stab} (MD {md:.1} m, Fig 7)"),
                    &orbit,
                    1e3 * site.params.clearance,
                )?;
                written.push(format!("lateral_{stab}.png"));
                written.push(format!("orbit_{stab}.png"));
            }
            if want("contact_forces") {
                line_plot(
                    &out.join(format!("contact_force_{stab}.png")),
                    &format!("{title}: contact force on {stab} (MD {md:.1} m)"),
                    "t (s)",
                    "normal force (kN)",
                    &[Series {
                        name: "N",
                        points: pts(3, 1e-3),
                        wide: false,
                    }],
                    &[],
                )?;
                written.push(format!("contact_force_{stab}.png"));
            }
            if want("spin") {
                line_plot(
                    &out.join(format!("spin_{stab}.png")),
                    &format!("{title}: spin rate of {stab} (MD {md:.1} m)"),
                    "t (s)",
                    "spin rate (rpm)",
                    &[Series {
                        name: "spin",
                        points: pts(4, 60.0 / std::f64::consts::TAU),
                        wide: false,
                    }],
                    &[],
                )?;
                written.push(format!("spin_{stab}.png"));
            }
        }
    }
    let mut whirl = Vec::new();
    if want("whirl") {
        let t_end = t.last().copied().unwrap_or(0.0);
        let mut spectrum_rows: Vec<Vec<f64>> = Vec::new();
        for (number, &k) in model.stabilizer_sites().iter().enumerate() {
            let site = &model.sites[k];
            let stab = crate::model::stabilizer_name(number + 1);
            // The second half of the run, after the spin-up.
            let late: Vec<&(f64, usize, [f64; 5])> = rec
                .sites
                .iter()
                .filter(|r| r.1 == k && r.0 >= 0.5 * t_end)
                .collect();
            let col = |j: usize| -> Vec<f64> { late.iter().map(|r| r.2[j]).collect() };
            let spin = col(4);
            let mean_spin = spin.iter().sum::<f64>() / spin.len().max(1) as f64;
            let rotary_hz = model.rotation_speed.abs() / std::f64::consts::TAU
                * if mean_spin < 0.0 { -1.0 } else { 1.0 };
            let w = crate::whirl::analyse(
                &col(0),
                &col(1),
                &col(3),
                settings.output_interval,
                rotary_hz,
                site.params.clearance,
            );
            let md = model.nodes[site.node].md;
            for (f, a) in &w.spectrum {
                spectrum_rows.push(vec![
                    (number + 1) as f64,
                    md,
                    *f,
                    if rotary_hz != 0.0 { f / rotary_hz } else { 0.0 },
                    1e3 * a,
                ]);
            }
            if w.class != crate::whirl::WhirlClass::None && rotary_hz != 0.0 {
                // Up to 5 × the rotary frequency, or past the dominant peak (the whole
                // spectrum is in whirl_spectrum.csv).
                let span = 5.0f64.max(1.2 * w.ratio_to_rotary.abs());
                let pts: Vec<(f64, f64)> = w
                    .spectrum
                    .iter()
                    .map(|(f, a)| (f / rotary_hz, 1e3 * a))
                    .filter(|(r, _)| r.abs() <= span)
                    .collect();
                line_plot(
                    &out.join(format!("whirl_{stab}.png")),
                    &format!(
                        "{title}: whirl spectrum of {stab} (MD {md:.1} m) — {:?}, {:.2} × rotary",
                        w.class, w.ratio_to_rotary
                    ),
                    "whirl frequency / rotary frequency (+ forward, − backward)",
                    "amplitude (mm)",
                    &[Series {
                        name: "second half of the run",
                        points: pts,
                        wide: false,
                    }],
                    &[],
                )?;
                written.push(format!("whirl_{stab}.png"));
            }
            let notes = crate::whirl::window_notes(&spin, rotary_hz, 0.5 * t_end, t_end);
            whirl.push(SiteWhirl {
                stabilizer: stab.clone(),
                site: k,
                md_m: md,
                whirl: w,
                notes,
            });
        }
        write_atomic(
            &out.join("whirl_spectrum.csv"),
            &csv_bytes(
                &[
                    "stabilizer",
                    "md_m",
                    "frequency_hz",
                    "frequency_over_rotary",
                    "amplitude_mm",
                ],
                spectrum_rows.into_iter(),
            )?,
        )?;
        written.push("whirl_spectrum.csv".into());
    }
    if want("axial_stress") {
        let rows = rec.stress.iter().map(|(t, md, s)| vec![*t, *md, *s]);
        write_atomic(
            &out.join("axial_stress.csv"),
            &csv_bytes(&["t_s", "md_m", "axial_stress_pa"], rows)?,
        )?;
        written.push("axial_stress.csv".into());
        // Stress along MD at the start and at the end (Figs 8, 10).
        let at = |time: f64| -> Vec<(f64, f64)> {
            rec.stress
                .iter()
                .filter(|r| (r.0 - time).abs() < 1e-12)
                .map(|r| (r.1, r.2 / 1e6))
                .collect()
        };
        let (t0, t1) = (
            t.first().copied().unwrap_or(0.0),
            t.last().copied().unwrap_or(0.0),
        );
        line_plot(
            &out.join("axial_stress.png"),
            &format!("{title}: effective axial stress along the string (Figs 8, 10)"),
            "MD (m)",
            "effective axial stress F_eff/A, tension + (MPa)",
            &[
                Series {
                    name: &format!("t = {t0:.2} s"),
                    points: at(t0),
                    wide: false,
                },
                Series {
                    name: &format!("t = {t1:.2} s"),
                    points: at(t1),
                    wide: false,
                },
            ],
            &[],
        )?;
        written.push("axial_stress.png".into());
    }
    let steps = dynamics.iterations.len();
    let t_end = t.last().copied().unwrap_or(0.0);
    let late_torque: Vec<f64> = rec
        .series
        .iter()
        .filter(|r| r[0] >= 0.5 * t_end)
        .map(|r| r[2])
        .collect();
    let mut analysis_notes: Vec<String> = offset_note.into_iter().collect();
    analysis_notes.extend(crate::whirl::run_notes(
        settings.ramp_time,
        0.5 * t_end,
        &late_torque,
    ));
    let summary = RunSummary {
        analysis_notes,
        warnings: case.warnings.clone(),
        title: case.title.clone(),
        duration_s: s.t,
        steps,
        mean_newton_iterations: dynamics.iterations.iter().sum::<usize>() as f64
            / steps.max(1) as f64,
        log: dynamics.log.clone(),
        outputs: written,
        requested_duration_s: settings.duration,
        stopped_early,
        whirl,
    };
    Ok(summary)
}
