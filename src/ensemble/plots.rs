//! An ensemble's plots over its inputs: the broomstick (hook load and surface torque against
//! bit depth, measurements over them) and the neutral point and stabilizer side forces against
//! the varied key each follows most — never over the variant's index where an input varies.

use std::path::Path;

use super::qoi::*;
use crate::case::Case;
use crate::ensemble::Variant;
use crate::error::Error;
use crate::plots::{line_plot, Series};

/// A variant key's unit on plots and the factor from SI (rotary speed in rpm, forces in kN,
/// torques in kN·m, lengths in m); `None` for dimensionless keys.
fn key_unit(key: &crate::keys::Key) -> (Option<&'static str>, f64) {
    use crate::ensemble::Param;
    match key.param {
        Param::Depth | Param::FromBit | Param::Blade | Param::Eccentricity => (Some("m"), 1.0),
        Param::Rpm => (Some("rpm"), 30.0 / std::f64::consts::PI),
        Param::Wob => (Some("kN"), 1e-3),
        Param::Tob => (Some("kN·m"), 1e-3),
        Param::Bend => (Some("°"), 180.0 / std::f64::consts::PI),
        Param::WallStiffness => (Some("N/m^m"), 1.0),
        Param::WallDamping => (Some("N·s/m"), 1.0),
        Param::Eps => (Some("m/s"), 1.0),
        _ => (None, 1.0),
    }
}

/// The axis of a variant key's values on a plot: its label and the factor from SI.
fn key_axis(key: &crate::keys::Key) -> (String, f64) {
    match (key.param, key_unit(key)) {
        (crate::ensemble::Param::Depth, (_, k)) => ("bit depth, MD (m)".into(), k),
        (_, (Some(u), k)) => (format!("{} ({u})", key.name), k),
        (_, (None, k)) => (key.name.clone(), k),
    }
}

/// A key's value in a legend: a mode by name, a layout by number, else `name value unit`
/// (`wob 44.5 kN`).
fn key_value_text(key: &crate::keys::Key, v: crate::keys::Value) -> String {
    use crate::keys::Value;
    match (v, key_unit(key)) {
        (Value::Mode(m), _) => m.to_string(),
        (Value::Layout(k), _) => format!("{} {k}", key.name),
        (Value::Number(v), (Some(u), k)) => {
            format!("{} {} {u}", key.name, crate::plots::tick(&(v * k)))
        }
        (Value::Number(v), (None, _)) => format!("{} {}", key.name, crate::plots::tick(&v)),
    }
}

/// A quantity of the variants as lines over one of their keys: `x` picks the key (the
/// override's position in each variant), `pick` the value (scaled by `scale`); one line per
/// combination of the other keys (named like `tripping_out, mu.open 0.3`), sorted along x.
fn lines_over(
    variants: &[Variant],
    results: &[VariantResult],
    x: usize,
    scale: f64,
    pick: &dyn Fn(&VariantResult) -> Option<f64>,
) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for (v, r) in variants.iter().zip(results) {
        let Some((label, at)) = line_place(v, x) else {
            continue;
        };
        let Some(y) = pick(r).filter(|h| h.is_finite()) else {
            continue;
        };
        let point = (at, y * scale);
        match lines.iter_mut().find(|(l, _)| *l == label) {
            Some((_, pts)) => pts.push(point),
            None => lines.push((label, vec![point])),
        }
    }
    for (_, pts) in &mut lines {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    lines
}

/// A variant's line in [`lines_over`] (named by its keys other than `x`) and its place
/// along x in the key's plot unit; `None` where it lacks key `x`.
fn line_place(v: &Variant, x: usize) -> Option<(String, f64)> {
    let (xk, xv) = v.overrides.get(x)?;
    let label = v
        .overrides
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != x)
        .map(|(_, (k, val))| key_value_text(k, *val))
        .collect::<Vec<_>>()
        .join(", ");
    Some((label, xv.si() * key_axis(xk).1))
}

/// Where [`lines_over`]'s lines end because their string stops on its way (a lock-up: the
/// variant's `stopped_load_factor`, no equilibrium at its full friction and bit loads): a
/// point per such variant at its place along x, at the height of its line's nearest point
/// (the reading before the string stops, or after it where the line has none before).
/// Nothing for a variant whose line has no point at all.
fn stop_marks(
    variants: &[Variant],
    results: &[VariantResult],
    x: usize,
    lines: &[(String, Vec<(f64, f64)>)],
) -> Vec<(f64, f64)> {
    let mut marks = Vec::new();
    for (v, r) in variants.iter().zip(results) {
        if r.string.stopped_load_factor.is_none() {
            continue;
        }
        let Some((label, at)) = line_place(v, x) else {
            continue;
        };
        let Some((_, pts)) = lines.iter().find(|(l, _)| *l == label) else {
            continue;
        };
        // The nearest point, one before `at` on a tie.
        let nearest = pts.iter().min_by(|a, b| {
            let (da, db) = ((a.0 - at).abs(), (b.0 - at).abs());
            da.total_cmp(&db).then(a.0.total_cmp(&b.0))
        });
        if let Some(p) = nearest {
            marks.push((at, p.1));
        }
    }
    marks
}

/// Where each of [`lines_over`]'s `loads` lines (the string's hook load, any scale) first
/// falls from above zero to zero or below — the weight indicator's lock-up: past it the
/// surface must push the string in — interpolated linearly along x; a point per such line at
/// that x and at the height of the line of the same name in `drawn` (what the plot draws:
/// the indicator's reading where the case has a rig), interpolated the same way.
fn zero_crossings(
    loads: &[(String, Vec<(f64, f64)>)],
    drawn: &[(String, Vec<(f64, f64)>)],
) -> Vec<(f64, f64)> {
    let at = |pts: &[(f64, f64)], x: f64| -> Option<f64> {
        let w = pts.windows(2).find(|w| w[0].0 <= x && x <= w[1].0)?;
        let t = if w[1].0 > w[0].0 {
            (x - w[0].0) / (w[1].0 - w[0].0)
        } else {
            0.0
        };
        Some(w[0].1 + t * (w[1].1 - w[0].1))
    };
    let mut marks = Vec::new();
    for (label, pts) in loads {
        let Some(w) = pts.windows(2).find(|w| w[0].1 > 0.0 && w[1].1 <= 0.0) else {
            continue;
        };
        let x = w[0].0 + (w[1].0 - w[0].0) * w[0].1 / (w[0].1 - w[1].1);
        let Some((_, line)) = drawn.iter().find(|(l, _)| l == label) else {
            continue;
        };
        if let Some(y) = at(line, x) {
            marks.push((x, y));
        }
    }
    marks
}

/// The numeric keys the variants vary (positions in each variant's overrides; not `mode` or
/// `layout`).
fn varied_keys(variants: &[Variant]) -> Vec<usize> {
    let Some(first) = variants.first() else {
        return Vec::new();
    };
    (0..first.overrides.len())
        .filter(|&i| {
            let numeric = matches!(first.overrides[i].1, crate::keys::Value::Number(_));
            numeric
                && variants
                    .iter()
                    .any(|v| v.overrides.get(i).map(|o| o.1) != Some(first.overrides[i].1))
        })
        .collect()
}

/// Of the varied keys, the one a quantity depends on most: the largest main effect (the
/// spread of the quantity's mean over each of the key's values); the first on a tie.
fn strongest_key(
    variants: &[Variant],
    results: &[VariantResult],
    keys: &[usize],
    pick: &dyn Fn(&VariantResult) -> Option<f64>,
) -> Option<usize> {
    let effect = |i: usize| -> f64 {
        let mut means: Vec<(f64, f64, usize)> = Vec::new();
        for (v, r) in variants.iter().zip(results) {
            let (Some(x), Some(y)) = (v.overrides.get(i).map(|o| o.1.si()), pick(r)) else {
                continue;
            };
            if !y.is_finite() {
                continue;
            }
            match means.iter_mut().find(|m| m.0 == x) {
                Some(m) => {
                    m.1 += y;
                    m.2 += 1;
                }
                None => means.push((x, y, 1)),
            }
        }
        let m = means.iter().map(|(_, s, n)| s / *n as f64);
        m.clone().fold(f64::NEG_INFINITY, f64::max) - m.fold(f64::INFINITY, f64::min)
    };
    let mut best: Option<(usize, f64)> = None;
    for &i in keys {
        let e = effect(i);
        if e.is_finite() && best.is_none_or(|(_, b)| e > b) {
            best = Some((i, e));
        }
    }
    best.map(|(i, _)| i).or_else(|| keys.first().copied())
}

/// A grid's or CSV's quantities against what the variants vary (`neutral_point.png`;
/// where a variant stops on its way, `loads_reached.png`; and `side_force.png` with a line
/// per stabilizer): over the numeric key the quantity depends on
/// most ([`strongest_key`]), a line per combination of the other keys; where the lines would
/// hold single points (a CSV's scattered rows) or be more than [`MAX_LINES`], the variants as
/// points against that key; where only categories (`mode`, `layout`) vary, as points over
/// the variant's number (the axis says so).
pub(crate) fn over_the_inputs(
    case: &Case,
    variants: &[Variant],
    results: &[VariantResult],
    stabs: usize,
    out: &Path,
) -> Result<Vec<String>, Error> {
    let keys = varied_keys(variants);
    // One plot: `picks` are (name prefix, quantity) drawn together (a stabilizer each);
    // `points`: as points always (a quantity that no line between variants describes).
    let plot = |file: &str,
                title: &str,
                y_label: &str,
                picks: &[(String, &Pick)],
                points: bool|
     -> Result<(), Error> {
        let title = format!("{}: {title}", case.title);
        let largest = |r: &VariantResult| {
            picks
                .iter()
                .filter_map(|(_, p)| p(r))
                .fold(None, |a: Option<f64>, y| Some(a.map_or(y, |a| a.max(y))))
        };
        let Some(x) = strongest_key(variants, results, &keys, &largest) else {
            // Only categories vary: points over the variant's number.
            let series: Vec<Series> = picks
                .iter()
                .map(|(name, pick)| Series {
                    name,
                    points: results
                        .iter()
                        .enumerate()
                        .filter_map(|(i, r)| {
                            pick(r).filter(|y| y.is_finite()).map(|y| (i as f64, y))
                        })
                        .collect(),
                    wide: false,
                })
                .collect();
            crate::plots::lines_and_points(
                &out.join(file),
                &title,
                "variant (only categories vary: see variants.csv)",
                y_label,
                &[],
                &series,
            )?;
            return Ok(());
        };
        let x_label = key_axis(&variants[0].overrides[x].0).0;
        let groups: Vec<(String, Vec<(f64, f64)>)> = picks
            .iter()
            .flat_map(|(prefix, pick)| {
                lines_over(variants, results, x, 1.0, *pick)
                    .into_iter()
                    .map(move |(l, p)| {
                        let name = match (prefix.is_empty(), l.is_empty()) {
                            (true, _) => l,
                            (false, true) => prefix.clone(),
                            (false, false) => format!("{prefix}, {l}"),
                        };
                        (name, p)
                    })
            })
            .collect();
        if !points && groups.len() <= MAX_LINES && groups.iter().all(|(_, p)| p.len() > 1) {
            let series: Vec<Series> = crate::plots::named_series(&groups);
            line_plot(&out.join(file), &title, &x_label, y_label, &series, &[])?;
        } else {
            // Scattered rows or too many lines: the points of each pick against the key.
            let sets: Vec<(String, Vec<(f64, f64)>)> = picks
                .iter()
                .map(|(prefix, pick)| {
                    let pts = lines_over(variants, results, x, 1.0, *pick)
                        .into_iter()
                        .flat_map(|(_, p)| p)
                        .collect();
                    (
                        if prefix.is_empty() {
                            "variants".to_string()
                        } else {
                            prefix.clone()
                        },
                        pts,
                    )
                })
                .collect();
            let series: Vec<Series> = crate::plots::named_series(&sets);
            crate::plots::lines_and_points(
                &out.join(file),
                &title,
                &x_label,
                y_label,
                &[],
                &series,
            )?;
        }
        Ok(())
    };
    plot(
        "neutral_point.png",
        "neutral point",
        "neutral point from the bit (m)",
        &[(String::new(), &|r: &VariantResult| {
            r.neutral_point_from_bit_m
        })],
        false,
    )?;
    let mut files = vec!["neutral_point.png".to_string()];
    if results
        .iter()
        .any(|r| r.string.stopped_load_factor.is_some())
    {
        // Where variants stop on their way (a lock-up): how far each got, 1 for those
        // that reach their loads; the other failures drawn at none. As points: the load
        // factor between two variants is not a line's.
        plot(
            "loads_reached.png",
            "how far the loads get (below 1: the string stops on its way)",
            "fraction of the friction and bit loads with an equilibrium",
            &[(String::new(), &|r: &VariantResult| {
                Some(super::report::loads_reached(r)).filter(|x| x.is_finite())
            })],
            true,
        )?;
        files.push("loads_reached.png".into());
    }
    if stabs == 0 {
        return Ok(files);
    }
    let per_stab: Vec<Box<Pick>> = (0..stabs)
        .map(|k| {
            Box::new(move |r: &VariantResult| {
                r.stabilizers.get(k).map(|q| q.max_side_force_n * 1e-3)
            }) as Box<Pick>
        })
        .collect();
    let picks: Vec<(String, &Pick)> = per_stab
        .iter()
        .enumerate()
        .map(|(k, f)| (crate::model::stabilizer_name(k + 1), f.as_ref()))
        .collect();
    plot(
        "side_force.png",
        "largest side force per stabilizer",
        "side force (kN)",
        &picks,
        false,
    )?;
    files.push("side_force.png".into());
    Ok(files)
}

/// A limit line further above the loads than this (× the largest) is named in the legend
/// with its distance, not drawn: the loads stay readable.
const OFF_SCALE: f64 = 3.0;

/// The legend of [`stop_marks`] on the broomstick.
const STOP_MARK: &str = "lock-up: the string stops at this depth (no equilibrium found)";

/// The legend of [`zero_crossings`] on the broomstick.
const PUSHED_MARK: &str =
    "the hook load falls to zero (weight-indicator lock-up): deeper, the surface must push";

/// A quantity of a variant's result.
type Pick = dyn Fn(&VariantResult) -> Option<f64>;

/// Lines a plot over the inputs draws before it shows points instead.
const MAX_LINES: usize = 24;

/// The classic T&D "broomstick" when the variants vary `depth`: hook load against bit
/// depth, one line per combination of the other keys (mode, friction, …), and the string's
/// tensile limit (90 % of the surface component's yield) where it has a grade
/// (`broomstick.png`); where a variant rotates, the surface torque the same way
/// (`broomstick_torque.png`). `measured` (a `--measured` file, [`crate::ensemble::measured`])
/// is drawn over them as points, a shape per mode. Nothing without a `depth` key.
pub(crate) fn broomstick(
    case: &Case,
    variants: &[Variant],
    results: &[VariantResult],
    measured: &[crate::ensemble::measured::Measurement],
    out: &Path,
) -> Result<Vec<String>, Error> {
    use crate::ensemble::Param;
    let has_depth = |v: &Variant| v.overrides.iter().any(|(k, _)| k.param == Param::Depth);
    if variants.is_empty() || !variants.iter().all(has_depth) {
        return Ok(Vec::new());
    }
    let Some(x) = variants[0]
        .overrides
        .iter()
        .position(|(k, _)| k.param == Param::Depth)
    else {
        return Ok(Vec::new());
    };
    // One line per combination of the keys other than depth (kN or kN·m).
    let lines_of =
        |pick: &dyn Fn(&VariantResult) -> Option<f64>| lines_over(variants, results, x, 1e-3, pick);
    // What the rig reads where the case has a `[rig]`, else the string's load.
    let hook_lines = lines_of(&|r| r.weight_indicator_n.or(r.hook_load_n));
    let mut series: Vec<Series> = crate::plots::named_series(&hook_lines);
    // The string's tensile limit: 90 % of the surface component's yield, where it has a grade.
    let top = case
        .model
        .elements
        .first()
        .and_then(|e| case.strength.get(e.component).copied().flatten());
    let limit_name;
    if let Some(s) = top {
        let (lo, hi) = hook_lines
            .iter()
            .flat_map(|(_, p)| p.iter().map(|x| x.0))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
                (a.min(d), b.max(d))
            });
        limit_name = format!(
            "90 % of the tensile yield ({}, {:.0} % wall)",
            s.grade,
            100.0 * s.wall_fraction
        );
        if lo.is_finite() {
            // On the indicator's scale: at rest it adds the block weight unless tared.
            let block = case
                .rig
                .map_or(0.0, |r| if r.tared { 0.0 } else { r.block_weight_n });
            let y = (0.9 * s.tensile_yield_n() + block) * 1e-3;
            series.push(Series {
                name: &limit_name,
                points: vec![(lo, y), (hi, y)],
                wide: true,
            });
        }
    }
    // The measurements, a point set per mode that has the quantity.
    let modes = crate::ensemble::measured::modes_of(measured.iter().map(|m| m.mode));
    let names: Vec<String> = modes
        .iter()
        .map(|m| format!("{} (measured)", m.name().replace('_', " ")))
        .collect();
    let measured_of = |pick: fn(&crate::ensemble::measured::Measurement) -> Option<f64>| {
        let sets = crate::ensemble::measured::by_mode(
            &modes,
            &names,
            measured,
            |m| m.mode,
            |m| pick(m).map(|y| (m.bit_md, y * 1e-3)),
        );
        sets.into_iter()
            .filter(|s| !s.points.is_empty())
            .collect::<Vec<_>>()
    };
    let title = |what: &str| {
        format!(
            "{}: {what} against bit depth{}",
            case.title,
            if measured.is_empty() {
                ""
            } else {
                ", measured as points"
            }
        )
    };
    let draw = |file: &str, what: &str, y_label: &str, lines: &[Series], points: &[Series]| {
        if points.is_empty() {
            line_plot(
                &out.join(file),
                &title(what),
                "bit depth, MD (m)",
                y_label,
                lines,
                &[],
            )
        } else {
            crate::plots::lines_and_measured(
                &out.join(file),
                &title(what),
                "bit depth, MD (m)",
                y_label,
                lines,
                points,
            )
        }
    };
    // Where a line ends because its string stops on the way, a mark of its own.
    let mut hook_points = measured_of(|m| m.hook_load);
    let pushed = zero_crossings(&lines_of(&|r| r.hook_load_n), &hook_lines);
    if !pushed.is_empty() {
        hook_points.push(Series {
            name: PUSHED_MARK,
            points: pushed,
            wide: false,
        });
    }
    let stops = stop_marks(variants, results, x, &hook_lines);
    if !stops.is_empty() {
        hook_points.push(Series {
            name: STOP_MARK,
            points: stops,
            wide: false,
        });
    }
    let mut files = Vec::new();
    draw(
        "broomstick.png",
        "hook load",
        &crate::rig::hook_load_axis(case.rig),
        &series,
        &hook_points,
    )?;
    files.push("broomstick.png".to_string());
    // Surface torque of the lines that rotate (a sliding or tripping line reads 0).
    let torque_lines: Vec<(String, Vec<(f64, f64)>)> = lines_of(&|r| Some(r.max_surface_torque_nm))
        .into_iter()
        .filter(|(_, p)| p.iter().any(|q| q.1.abs() > 1e-3))
        .collect();
    let torques = measured_of(|m| m.surface_torque);
    if !torque_lines.is_empty() || !torques.is_empty() {
        let mut series: Vec<Series> = crate::plots::named_series(&torque_lines);
        // The surface connection's make-up torque, where the case gives it.
        // Drawn where it is within OFF_SCALE of the largest torque; named (in the legend)
        // with how far off the scale it is otherwise, so the loads stay readable.
        let makeup = top.and_then(|s| s.makeup_torque_nm).map(|m| m / 1e3);
        let largest = torque_lines
            .iter()
            .flat_map(|(_, p)| p.iter().map(|x| x.1))
            .fold(0.0f64, f64::max);
        let makeup_name = makeup.map(|m| {
            let off = m > OFF_SCALE * largest && largest > 0.0;
            format!(
                "tool-joint make-up torque {m:.1} kN·m (the connection's limit){}",
                if off {
                    format!(": off the scale, {:.1}× the largest torque", m / largest)
                } else {
                    String::new()
                }
            )
        });
        if let (Some(m), Some(name)) = (makeup, &makeup_name) {
            let (lo, hi) = torque_lines
                .iter()
                .flat_map(|(_, p)| p.iter().map(|x| x.0))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
                    (a.min(d), b.max(d))
                });
            let drawn = lo.is_finite() && m <= OFF_SCALE * largest;
            series.push(Series {
                name,
                points: if drawn {
                    vec![(lo, m), (hi, m)]
                } else {
                    vec![]
                },
                wide: true,
            });
        }
        draw(
            "broomstick_torque.png",
            "surface torque",
            "surface torque (kN·m)",
            &series,
            &torques,
        )?;
        files.push("broomstick_torque.png".to_string());
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::keys::{Key, Value};

    /// A 3 × 3 grid of `mu` and `wob` whose neutral point follows the WOB alone.
    fn grid() -> (Vec<Variant>, Vec<VariantResult>) {
        let (mu, wob) = (Key::parse("mu").unwrap(), Key::parse("wob").unwrap());
        let mut variants = Vec::new();
        let mut results = Vec::new();
        for m in [0.2, 0.3, 0.4] {
            for w in [40e3, 60e3, 80e3] {
                variants.push(Variant {
                    name: format!("{}", variants.len()),
                    overrides: vec![
                        (mu.clone(), Value::Number(m)),
                        (wob.clone(), Value::Number(w)),
                    ],
                });
                let mut r = crate::ensemble::qoi::failed("v", String::new(), 0);
                r.neutral_point_from_bit_m = Some(w / 1e3 + 0.01 * m);
                results.push(r);
            }
        }
        (variants, results)
    }

    #[test]
    fn the_axis_is_the_key_the_quantity_follows() {
        let (variants, results) = grid();
        let keys = varied_keys(&variants);
        assert_eq!(keys, vec![0, 1]);
        let np = |r: &VariantResult| r.neutral_point_from_bit_m;
        assert_eq!(strongest_key(&variants, &results, &keys, &np), Some(1));
        // Over the WOB in kN, a line per friction value, three points each, sorted.
        let lines = lines_over(&variants, &results, 1, 1.0, &np);
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0].0, "mu 0.2");
        let xs: Vec<f64> = lines[0].1.iter().map(|p| p.0).collect();
        assert_eq!(xs, vec![40.0, 60.0, 80.0]);
        assert_eq!(key_axis(&variants[0].overrides[1].0).0, "wob (kN)");
        assert_eq!(
            key_value_text(&variants[0].overrides[1].0, Value::Number(44_482.0)),
            "wob 44.48 kN"
        );
    }

    #[test]
    fn a_line_that_stops_is_marked_at_the_depth_it_stops() {
        // Hook loads at 1,000–4,000 m for two friction factors; with 0.4 the string stops
        // at 3,000 and 4,000 m, with 0.2 at none.
        let (depth, mu) = (Key::parse("depth").unwrap(), Key::parse("mu").unwrap());
        let mut variants = Vec::new();
        let mut results = Vec::new();
        for m in [0.2, 0.4] {
            for d in [1000.0, 2000.0, 3000.0, 4000.0] {
                variants.push(Variant {
                    name: format!("{}", variants.len()),
                    overrides: vec![
                        (mu.clone(), Value::Number(m)),
                        (depth.clone(), Value::Number(d)),
                    ],
                });
                let mut r = crate::ensemble::qoi::failed("v", String::new(), 0);
                if m > 0.3 && d > 2500.0 {
                    r.string.stopped_load_factor = Some(0.875);
                } else {
                    r.hook_load_n = Some(1e6 - 100.0 * d - 1e5 * m);
                }
                results.push(r);
            }
        }
        let pick = |r: &VariantResult| r.hook_load_n;
        let lines = lines_over(&variants, &results, 1, 1e-3, &pick);
        assert_eq!(lines.len(), 2);
        assert_eq!(lines[1].1.len(), 2, "the 0.4 line ends at 2,000 m");
        // Each stopped depth is marked at the 0.4 line's last reading (2,000 m).
        let marks = stop_marks(&variants, &results, 1, &lines);
        assert_eq!(marks, vec![(3000.0, 760.0), (4000.0, 760.0)]);
        // No stop, no mark.
        let solved: Vec<VariantResult> = results
            .iter()
            .map(|r| {
                let mut r = r.clone();
                r.string.stopped_load_factor = None;
                r
            })
            .collect();
        assert!(stop_marks(&variants, &solved, 1, &lines).is_empty());
        // The weight indicator's lock-up: the 0.2 line's 760 → 660 → … never crosses zero;
        // one falling from 200 to −200 between 1,000 and 2,000 m crosses at 1,500 m, and its
        // drawn twin (a rig's reading, 50 more) is read there.
        let loads = vec![
            (
                "a".to_string(),
                vec![(1000.0, 200.0), (2000.0, -200.0), (3000.0, -600.0)],
            ),
            ("b".to_string(), vec![(1000.0, 760.0), (2000.0, 660.0)]),
        ];
        let drawn = vec![(
            "a".to_string(),
            vec![(1000.0, 250.0), (2000.0, -150.0), (3000.0, -550.0)],
        )];
        assert_eq!(zero_crossings(&loads, &drawn), vec![(1500.0, 50.0)]);
    }
}
