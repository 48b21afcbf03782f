//! `holewall critical-speeds CASE --out DIR`: lateral modes of the BHA as it lies in the
//! hole and the rotary speeds that excite them (issue 25; [`crate::bha::critical`]):
//! `modes.csv`, `critical_speeds.csv`, `campbell.png`, `mode_shapes.png`, `summary.json`.

use std::path::Path;

use serde::Serialize;

use crate::bha::critical::{critical_speeds_of_case, CriticalOptions, CriticalSpeed};
use crate::case::load_case;
use crate::error::Error;
use crate::output::RunFolder;

/// `summary.json` of `holewall critical-speeds`.
#[derive(Clone, Debug, Serialize)]
pub struct CriticalSummary {
    /// Case title.
    pub title: String,
    /// Lateral natural frequencies (Hz), lowest first.
    pub lateral_frequencies_hz: Vec<f64>,
    /// Critical speeds up to `max_rpm`, lowest first.
    pub critical: Vec<CriticalSpeed>,
    /// The part analysed (MD from, to; m).
    pub part_md: (f64, f64),
    /// Options.
    pub options: CriticalOptions,
    /// How the eigenproblem was solved: `dense` or `shift-invert block Lanczos`
    /// ([`crate::solve::modal::lowest_modes`]), as (method, DOFs of the part,
    /// Krylov basis, largest relative residual of the modes).
    pub eigen: (String, usize, usize, f64),
    /// Files written.
    pub outputs: Vec<String>,
    /// Wall time (s).
    pub seconds: f64,
}

/// Options of the command.
#[derive(Clone, Copy, Debug)]
pub struct CriticalCommandOptions {
    /// Highest rpm of the map.
    pub max_rpm: f64,
    /// Blades (blade pass).
    pub blades: usize,
    /// Lateral modes.
    pub modes: usize,
    /// Progress bar on stderr (the static solve).
    pub show_progress: bool,
    /// The mud's added mass in the modes (`false`: like the dynamics, which has none).
    pub added_mass: bool,
}

/// Runs the command.
pub fn run(
    case_path: &Path,
    out: &Path,
    options: CriticalCommandOptions,
) -> Result<CriticalSummary, Error> {
    let start = std::time::Instant::now();
    let mut case = load_case(case_path)?;
    super::print_warnings(&case);
    let folder = RunFolder::prepare(out)?.with_report("critical-speeds", case_path);
    let statics = case.settings().statics();
    let sol = crate::profile::solve_with_progress(&mut case, statics, options.show_progress)?;
    let case = case;
    let model = &case.model;
    let opts = CriticalOptions::for_case(
        &case,
        options.max_rpm,
        options.blades,
        options.modes,
        options.added_mass,
        false,
    );
    let cs = critical_speeds_of_case(&case, &sol.state, &opts);
    let dir = folder.path();
    let io = Error::from;
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["mode", "frequency_hz", "lateral_share", "critical_rpm_1x"])
        .map_err(io)?;
    for (j, m) in cs.modes.iter().enumerate() {
        w.write_record([
            (j + 1).to_string(),
            format!("{}", m.frequency_hz),
            format!("{}", m.lateral_share),
            format!("{}", 60.0 * m.frequency_hz),
        ])
        .map_err(io)?;
    }
    let bytes = w.into_inner().map_err(Error::encode)?;
    crate::output::write_atomic(&dir.join("modes.csv"), &bytes)?;
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["excitation", "mode", "frequency_hz", "rpm"])
        .map_err(io)?;
    for c in &cs.critical {
        w.write_record([
            c.excitation.clone(),
            c.mode.to_string(),
            format!("{}", c.frequency_hz),
            format!("{}", c.rpm),
        ])
        .map_err(io)?;
    }
    let bytes = w.into_inner().map_err(Error::encode)?;
    crate::output::write_atomic(&dir.join("critical_speeds.csv"), &bytes)?;
    write_plots(&case.title, &cs, model.rotation_speed, &opts, dir)?;
    let summary = CriticalSummary {
        title: case.title.clone(),
        lateral_frequencies_hz: cs.modes.iter().map(|m| m.frequency_hz).collect(),
        critical: cs.critical.clone(),
        part_md: cs.part_md,
        options: opts,
        eigen: (
            cs.eigen_method.clone(),
            cs.dofs,
            cs.eigen_basis,
            cs.eigen_worst_residual,
        ),
        outputs: [
            "modes.csv",
            "critical_speeds.csv",
            "campbell.png",
            "mode_shapes.png",
        ]
        .map(String::from)
        .to_vec(),
        seconds: start.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_vec_pretty(&summary)?;
    folder.finish(&json)?;
    Ok(summary)
}

fn write_plots(
    title: &str,
    cs: &crate::bha::critical::CriticalSpeeds,
    rotation_speed: f64,
    options: &CriticalOptions,
    dir: &Path,
) -> std::io::Result<()> {
    use crate::plots::{line_plot, Marker, Series};
    let top = cs
        .modes
        .iter()
        .map(|m| m.frequency_hz)
        .fold(1.0f64, f64::max)
        * 1.15;
    let names: Vec<String> = cs
        .modes
        .iter()
        .enumerate()
        .map(|(j, m)| format!("mode {}: {:.2} Hz", j + 1, m.frequency_hz))
        .collect();
    let mut series: Vec<Series> = cs
        .modes
        .iter()
        .zip(&names)
        .map(|(m, name)| Series {
            name,
            points: vec![(0.0, m.frequency_hz), (options.max_rpm, m.frequency_hz)],
            wide: true,
        })
        .collect();
    let ray_names: Vec<String> = cs
        .excitations
        .iter()
        .map(|(n, r)| format!("{n} ({r:.2}× rotary)"))
        .collect();
    for ((_, ratio), name) in cs.excitations.iter().zip(&ray_names) {
        // The ray f = ratio · N/60, clipped at the plot's top.
        let end = options.max_rpm.min(60.0 * top / ratio);
        series.push(Series {
            name,
            points: vec![(0.0, 0.0), (end, ratio * end / 60.0)],
            wide: false,
        });
    }
    let labels: Vec<String> = cs
        .critical
        .iter()
        .map(|c| format!("{:.0} rpm", c.rpm))
        .collect();
    let markers: Vec<Marker> = cs
        .critical
        .iter()
        .zip(&labels)
        .map(|(c, l)| Marker {
            label: l,
            x: c.rpm,
            y: c.frequency_hz,
        })
        .collect();
    let operating_rpm = rotation_speed * 60.0 / std::f64::consts::TAU;
    let operating = format!("operating {operating_rpm:.0} rpm");
    if rotation_speed > 0.0 {
        series.push(Series {
            name: &operating,
            points: vec![(operating_rpm, 0.0), (operating_rpm, top)],
            wide: true,
        });
    }
    line_plot(
        &dir.join("campbell.png"),
        &format!("{title}: critical speeds (Campbell diagram)"),
        "rotary speed (rpm)",
        "frequency (Hz)",
        &series,
        &markers,
    )?;
    let shape_names: Vec<String> = cs
        .modes
        .iter()
        .enumerate()
        .take(4)
        .map(|(j, m)| {
            format!(
                "mode {}: {:.2} Hz ({:.0} rpm at 1×)",
                j + 1,
                m.frequency_hz,
                60.0 * m.frequency_hz
            )
        })
        .collect();
    let shapes: Vec<Series> = cs
        .modes
        .iter()
        .zip(&shape_names)
        .map(|(m, name)| Series {
            name,
            points: m.shape.clone(),
            wide: false,
        })
        .collect();
    line_plot(
        &dir.join("mode_shapes.png"),
        &format!("{title}: lateral mode shapes of the BHA in the hole"),
        "MD (m)",
        "lateral displacement across the hole axis (normalised)",
        &shapes,
        &[],
    )
}
