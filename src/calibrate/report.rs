//! What `holewall calibrate` writes: the residuals and the posterior as CSV, the posterior,
//! the residuals against depth, and the broomstick at the calibrated friction factors with
//! the measurements over it.

use std::path::Path;

use super::{by_mode, model_at, modes_of, Calibration, Measurement, Station};
use crate::case::Case;
use crate::error::Error;
use crate::plots::{heat_map, line_plot, lines_and_points, Marker, Series};

/// Bit depths of the modelled broomstick's lines.
const LINE_POINTS: usize = 12;

/// Writes every output into `dir`; returns the files' names.
pub fn write(
    case: &Case,
    rows: &[Measurement],
    cal: &Calibration,
    dir: &Path,
    bar: &indicatif::ProgressBar,
) -> Result<Vec<String>, Error> {
    let mut files = Vec::new();
    crate::output::write_csv_rows(&dir.join("residuals.csv"), &cal.residuals)?;
    files.push("residuals.csv".to_string());
    files.extend(posterior(case, cal, dir)?);
    files.extend(residual_plots(case, cal, dir)?);
    files.extend(broomsticks(case, rows, cal, dir, bar)?);
    Ok(files)
}

fn label(key: &str) -> String {
    match key {
        "mu.cased" => "cased-hole friction factor".into(),
        "mu.open" => "open-hole friction factor".into(),
        k => k.to_string(),
    }
}

fn posterior(case: &Case, cal: &Calibration, dir: &Path) -> Result<Vec<String>, Error> {
    let io = Error::from;
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = cal.keys.iter().map(|k| k.name.clone()).collect();
    header.push("density".into());
    w.write_record(&header).map_err(io)?;
    let cell = (cal.fine[0][1] - cal.fine[0][0]).powi(cal.keys.len() as i32);
    if cal.keys.len() == 2 {
        for (i, x) in cal.fine[0].iter().enumerate() {
            for (j, y) in cal.fine[1].iter().enumerate() {
                w.write_record([x, y, &(cal.posterior[i][j] / cell)].map(|v| v.to_string()))
                    .map_err(io)?;
            }
        }
    } else {
        for (i, x) in cal.fine[0].iter().enumerate() {
            w.write_record([x, &(cal.posterior[0][i] / cell)].map(|v| v.to_string()))
                .map_err(io)?;
        }
    }
    let bytes = w.into_inner().map_err(Error::encode)?;
    crate::output::write_atomic(&dir.join("posterior.csv"), &bytes)?;
    let title = format!("{}: friction factors from the measured loads", case.title);
    let map_label = |e: &super::Estimate| {
        format!(
            "{:.3} [{:.3}, {:.3}]",
            e.map, e.interval_95.0, e.interval_95.1
        )
    };
    if cal.keys.len() == 2 {
        let (ex, ey) = (&cal.estimates[0], &cal.estimates[1]);
        let text = format!("MAP ({:.3}, {:.3})", ex.map, ey.map);
        heat_map(
            &dir.join("posterior.png"),
            &title,
            &format!(
                "{} (95 %: {:.3}–{:.3})",
                label(&ex.key),
                ex.interval_95.0,
                ex.interval_95.1
            ),
            &format!(
                "{} (95 %: {:.3}–{:.3})",
                label(&ey.key),
                ey.interval_95.0,
                ey.interval_95.1
            ),
            (&cal.fine[0], &cal.fine[1]),
            &cal.posterior,
            &[Marker {
                label: &text,
                x: ex.map,
                y: ey.map,
            }],
        )?;
    } else {
        let e = &cal.estimates[0];
        let points: Vec<(f64, f64)> = cal.fine[0]
            .iter()
            .zip(&cal.posterior[0])
            .map(|(x, p)| (*x, p / cell))
            .collect();
        let name = format!("posterior density; MAP and 95 % interval {}", map_label(e));
        line_plot(
            &dir.join("posterior.png"),
            &title,
            &label(&e.key),
            "posterior density (1/unit friction factor)",
            &[Series {
                name: &name,
                points,
                wide: false,
            }],
            &[],
        )?;
    }
    Ok(vec!["posterior.csv".into(), "posterior.png".into()])
}

fn residual_plots(case: &Case, cal: &Calibration, dir: &Path) -> Result<Vec<String>, Error> {
    let modes = modes_of(cal.residuals.iter().map(|r| r.mode));
    let mut files = Vec::new();
    for (file, what, unit, pick) in [
        (
            "residuals.png",
            "hook load",
            "kN",
            (|r: &super::Residual| r.hook_load_residual_n) as fn(&super::Residual) -> Option<f64>,
        ),
        ("residuals_torque.png", "surface torque", "kN·m", |r| {
            r.torque_residual_nm
        }),
    ] {
        let names: Vec<String> = modes.iter().map(|m| m.name().replace('_', " ")).collect();
        let sets = by_mode(
            &modes,
            &names,
            &cal.residuals,
            |r| r.mode,
            |r| pick(r).map(|x| (r.bit_md_m, x * 1e-3)),
        );
        if sets.iter().all(|s| s.points.is_empty()) {
            continue;
        }
        let (lo, hi) = cal
            .residuals
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                (a.min(r.bit_md_m), b.max(r.bit_md_m))
            });
        lines_and_points(
            &dir.join(file),
            &format!(
                "{}: {what} residuals (measured − modelled) at the calibrated friction",
                case.title
            ),
            "bit depth, MD (m)",
            &format!("{what} residual ({unit})"),
            &[Series {
                name: "zero",
                points: vec![(lo, 0.0), (hi, 0.0)],
                wide: true,
            }],
            &sets,
        )?;
        files.push(file.to_string());
    }
    Ok(files)
}

fn broomsticks(
    case: &Case,
    rows: &[Measurement],
    cal: &Calibration,
    dir: &Path,
    bar: &indicatif::ProgressBar,
) -> Result<Vec<String>, Error> {
    let modes = modes_of(rows.iter().map(|r| r.mode));
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
            (a.min(r.bit_md), b.max(r.bit_md))
        });
    let depths: Vec<f64> = (0..LINE_POINTS)
        .map(|i| lo + (hi - lo) * i as f64 / (LINE_POINTS - 1) as f64)
        .collect();
    // One line per mode at the MAP (drilling at its rows' mean WOB, every rotating mode at
    // the case's rpm or its rows' first).
    let stations: Vec<Station> = modes
        .iter()
        .flat_map(|&m| {
            let of_mode: Vec<&Measurement> = rows.iter().filter(|r| r.mode == m).collect();
            let wob = of_mode.iter().map(|r| r.wob).sum::<f64>() / of_mode.len() as f64;
            let rpm = of_mode.iter().find_map(|r| r.rpm);
            depths.iter().map(move |&d| Station {
                bit_md: d,
                mode: m,
                wob,
                rpm,
            })
        })
        .collect();
    let mu: Vec<f64> = cal.estimates.iter().map(|e| e.map).collect();
    bar.inc_length(stations.len() as u64);
    let modelled = model_at(case, &stations, &cal.keys, &mu, bar)?;
    let mu_text = cal
        .estimates
        .iter()
        .map(|e| format!("{} {:.3}", e.key, e.map))
        .collect::<Vec<_>>()
        .join(", ");
    let names: Vec<String> = modes
        .iter()
        .map(|m| format!("{} (model, {mu_text})", m.name().replace('_', " ")))
        .collect();
    let measured_names: Vec<String> = modes
        .iter()
        .map(|m| format!("{} (measured)", m.name().replace('_', " ")))
        .collect();
    let hook_label = crate::rig::hook_load_axis(case.rig);
    let mut files = Vec::new();
    for (file, what, y_label, pick_model, pick_measured) in [
        (
            "broomstick.png",
            "hook load",
            hook_label,
            (|m: &(f64, f64)| m.0) as fn(&(f64, f64)) -> f64,
            (|r: &Measurement| r.hook_load) as fn(&Measurement) -> Option<f64>,
        ),
        (
            "torque.png",
            "surface torque",
            "surface torque (kN·m)".to_string(),
            |m| m.1,
            |r| r.surface_torque,
        ),
    ] {
        let measured = by_mode(
            &modes,
            &measured_names,
            rows,
            |r| r.mode,
            |r| pick_measured(r).map(|x| (r.bit_md, x * 1e-3)),
        );
        if measured.iter().all(|s| s.points.is_empty()) {
            continue;
        }
        let lines: Vec<Series> = modes
            .iter()
            .enumerate()
            .zip(&names)
            .map(|((k, m), n)| Series {
                name: n,
                points: if what == "surface torque" && !m.rotates() {
                    vec![]
                } else {
                    depths
                        .iter()
                        .enumerate()
                        .map(|(i, &d)| (d, pick_model(&modelled[k * LINE_POINTS + i]) * 1e-3))
                        .collect()
                },
                wide: false,
            })
            .collect();
        lines_and_points(
            &dir.join(file),
            &format!("{}: {what}, measured and modelled", case.title),
            "bit depth, MD (m)",
            &y_label,
            &lines,
            &measured,
        )?;
        files.push(file.to_string());
    }
    Ok(files)
}
