//! `holewall tendency CASE --out DIR`: the assembly's directional tendency at the case's
//! weight on bit and its map over stab1's position (or the bend's toolface) × weight on bit
//! (issue 25): `tendency_map.csv`, `tendency_build.png`, `tendency_turn.png` (motors) or
//! `tendency_equilibrium.png` (rotary), `summary.json`.

use std::path::Path;

use serde::Serialize;

use crate::bha::tendency::{assembly_tendency, Tendency};
use crate::case::load_case;
use crate::ensemble::tendency_map::{tendency_map, MapAxis, MapCell};
use crate::error::Error;
use crate::output::RunFolder;

/// `summary.json` of `holewall tendency`.
#[derive(Clone, Debug, Serialize)]
pub struct TendencySummary {
    /// Case title.
    pub title: String,
    /// The assembly's tendency at the case's weight on bit.
    pub tendency: Tendency,
    /// What the map's first axis varies.
    pub map_axis: MapAxis,
    /// Cells of the map.
    pub cells: usize,
    /// Cells with a build rate.
    pub solved: usize,
    /// The first cells without one, and why.
    pub unsolved: Vec<String>,
    /// Files written.
    pub outputs: Vec<String>,
    /// Wall time (s).
    pub seconds: f64,
    /// The case's warnings.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Runs the command.
/// `max_seconds`: no BHA-model solve runs past this budget; the cells it cuts say so (and
/// count as unsolved).
pub fn run(
    case_path: &Path,
    out: &Path,
    show_progress: bool,
    max_seconds: Option<f64>,
) -> Result<TendencySummary, Error> {
    let start = std::time::Instant::now();
    let case = load_case(case_path)?;
    super::print_warnings(&case);
    let folder = RunFolder::prepare(out)?.with_report("tendency", case_path);
    let settings = crate::bha::tendency::TendencySettings {
        deadline: max_seconds.map(|s| start + std::time::Duration::from_secs_f64(s)),
        ..case.tendency.settings
    };
    let own = assembly_tendency(
        &case.model,
        case.bha_length,
        case.model.weight_on_bit,
        &settings,
    );
    let (_, xs, wobs) = crate::ensemble::tendency_map::map_grid(&case);
    let bar = crate::output::progress_bar(
        show_progress,
        (xs.len() * wobs.len()) as u64,
        "tendency map {bar:40} {pos}/{len} cells, {elapsed} (eta {eta})",
    );
    let (axis, cells) = tendency_map(&case, &settings, &|| bar.inc(1));
    bar.finish_and_clear();
    let dir = folder.path();
    write_csv(&dir.join("tendency_map.csv"), axis, &cells)?;
    let mut outputs = vec!["tendency_map.csv".to_string()];
    outputs.extend(write_plots(&case.title, axis, &cells, dir)?);
    let unsolved: Vec<String> = cells
        .iter()
        .filter(|c| c.tendency.build_rate_deg_per_30m.is_none())
        .take(5)
        .map(|c| {
            format!(
                "{} = {:.2}, WOB {:.0} kN: {}",
                axis.column(),
                c.x,
                c.weight_on_bit_n / 1e3,
                c.tendency.notes.join("; ")
            )
        })
        .collect();
    let summary = TendencySummary {
        title: case.title.clone(),
        tendency: own,
        map_axis: axis,
        cells: cells.len(),
        solved: cells
            .iter()
            .filter(|c| c.tendency.build_rate_deg_per_30m.is_some())
            .count(),
        unsolved,
        outputs,
        seconds: start.elapsed().as_secs_f64(),
        warnings: case.warnings.clone(),
    };
    let json = serde_json::to_vec_pretty(&summary)?;
    folder.finish(&json)?;
    Ok(summary)
}

fn write_csv(path: &Path, axis: MapAxis, cells: &[MapCell]) -> Result<(), Error> {
    let io = Error::from;
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec![axis.column().to_string(), "weight_on_bit_n".to_string()];
    header.extend(
        [
            "build_rate_deg_per_30m",
            "turn_rate_deg_per_30m",
            "walk_curvature_deg_per_30m",
            "equilibrium_curvature_deg_per_30m",
        ]
        .map(String::from),
    );
    header.extend(crate::bha::BIT_COLUMNS.map(|c| format!("straight_hole_{c}")));
    header.extend(["solves", "notes"].map(String::from));
    w.write_record(&header).map_err(io)?;
    let opt = |x: Option<f64>| x.map(|v| format!("{v}")).unwrap_or_default();
    for c in cells {
        let t = &c.tendency;
        let mut row = vec![format!("{}", c.x), format!("{}", c.weight_on_bit_n)];
        row.extend([
            opt(t.build_rate_deg_per_30m),
            opt(t.turn_rate_deg_per_30m),
            opt(t.walk_curvature_deg_per_30m),
            opt(t.equilibrium_curvature_deg_per_30m),
        ]);
        match &t.bit_straight_hole {
            Some(b) => row.extend(b.columns().map(|v| format!("{v}"))),
            None => row.extend(crate::bha::BIT_COLUMNS.map(|_| String::new())),
        }
        row.push(t.solves.to_string());
        row.push(t.notes.join("; "));
        w.write_record(&row).map_err(io)?;
    }
    let bytes = w.into_inner().map_err(Error::encode)?;
    crate::output::write_atomic(path, &bytes)?;
    Ok(())
}

/// One line per weight on bit over the axis: the build rate, and the turn rate (motors) or
/// the equilibrium curvature (rotary assemblies).
fn write_plots(
    title: &str,
    axis: MapAxis,
    cells: &[MapCell],
    dir: &Path,
) -> Result<Vec<String>, Error> {
    use crate::plots::{line_plot, Series};
    let mut wobs: Vec<f64> = cells.iter().map(|c| c.weight_on_bit_n).collect();
    wobs.sort_by(f64::total_cmp);
    wobs.dedup();
    let x_label = match axis {
        MapAxis::Stab1FromBit => "stab1 distance from the bit (m)",
        MapAxis::Toolface => "toolface from the high side (°)",
        MapAxis::None => "weight on bit (kN)",
    };
    type Field = fn(&Tendency) -> Option<f64>;
    let second: (&str, &str, Field) = match axis {
        MapAxis::Toolface => ("tendency_turn.png", "turn rate (°/30 m, + right)", |t| {
            t.turn_rate_deg_per_30m
        }),
        _ => (
            "tendency_equilibrium.png",
            "equilibrium curvature (°/30 m, + build)",
            |t| t.equilibrium_curvature_deg_per_30m,
        ),
    };
    let plots: [(&str, &str, Field); 2] = [
        (
            "tendency_build.png",
            "build rate (°/30 m, − drop)",
            |t| t.build_rate_deg_per_30m,
        ),
        second,
    ];
    let mut written = Vec::new();
    for (file, y_label, f) in plots {
        let names: Vec<String> = wobs
            .iter()
            .map(|w| format!("WOB {:.0} kN", w / 1e3))
            .collect();
        let series: Vec<Series> = if axis == MapAxis::None {
            vec![Series {
                name: "assembly",
                points: cells
                    .iter()
                    .filter_map(|c| f(&c.tendency).map(|y| (c.weight_on_bit_n / 1e3, y)))
                    .collect(),
                wide: false,
            }]
        } else {
            wobs.iter()
                .zip(&names)
                .map(|(w, name)| Series {
                    name,
                    points: cells
                        .iter()
                        .filter(|c| c.weight_on_bit_n == *w)
                        .filter_map(|c| f(&c.tendency).map(|y| (c.x, y)))
                        .collect(),
                    wide: false,
                })
                .collect()
        };
        line_plot(
            &dir.join(file),
            &format!("{title}: {y_label}"),
            x_label,
            y_label,
            &series,
            &[],
        )?;
        written.push(file.to_string());
    }
    Ok(written)
}
