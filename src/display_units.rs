//! The units outputs are written in (issue 26): SI (the default) or oilfield units
//! (`--units field`): ft, klbf, kft·lbf, lbf/ft, psi, ppg, °/100 ft, rpm, ft/min, in.
//!
//! The library computes in SI throughout; this module is the one place outputs change
//! units. A run's files are written in SI and translated at the end, by their names:
//! a CSV column or a JSON key ending in an SI unit suffix (`_m`, `_n`, `_nm`, `_pa`,
//! `_n_per_m`, `_deg_per_30m`, `_kg_m3`, `_m_s`, `_rad_s`, `_mm`) takes the field suffix and
//! value ([`field_key`], [`convert_csv`], [`convert_json`], [`convert_folder`]); a plot's axis
//! whose label ends in an SI unit in parentheses is redrawn in the field unit ([`axis`]), and
//! quantities with those units in titles and legends are rewritten ([`text`]). Columns and
//! keys without a unit suffix (a variant's override key such as `depth`, as the case wrote
//! it) stay as written.

use std::sync::atomic::{AtomicU8, Ordering};

use crate::units::{FT, LBF};
const PSI: f64 = 6_894.757_293_168;
const PPG: f64 = 119.826_427_316_5;

/// A unit system for outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum UnitSystem {
    /// SI: m, N, N·m, Pa, kg/m³ (plots in kN, kN·m, MPa).
    #[default]
    Si,
    /// Oilfield: ft, klbf, kft·lbf, psi, ppg, °/100 ft.
    Field,
}

static SYSTEM: AtomicU8 = AtomicU8::new(0);

/// Sets the outputs' unit system for the process (the CLI's `--units`).
pub fn set(system: UnitSystem) {
    SYSTEM.store(system as u8, Ordering::Relaxed);
}

/// The outputs' unit system.
pub fn get() -> UnitSystem {
    match SYSTEM.load(Ordering::Relaxed) {
        1 => UnitSystem::Field,
        _ => UnitSystem::Si,
    }
}

/// Name suffixes: (SI suffix, field suffix, SI value × factor = field value). Longest SI
/// suffixes first, so `_n_per_m` wins over `_m`.
const SUFFIXES: [(&str, &str, f64); 10] = [
    ("_deg_per_30m", "_deg_per_100ft", 100.0 * FT / 30.0),
    ("_n_per_m", "_lbf_per_ft", FT / LBF),
    ("_kg_m3", "_ppg", 1.0 / PPG),
    ("_rad_s", "_rpm", 30.0 / std::f64::consts::PI),
    ("_m_s", "_ft_min", 60.0 / FT),
    ("_nm", "_kftlbf", 1e-3 / (LBF * FT)),
    ("_mm", "_in", 1.0 / 25.4),
    ("_pa", "_psi", 1.0 / PSI),
    ("_n", "_klbf", 1e-3 / LBF),
    ("_m", "_ft", 1.0 / FT),
];

/// A column or key's field name and factor, if it ends in an SI unit suffix.
pub fn field_key(name: &str) -> Option<(String, f64)> {
    SUFFIXES.iter().find_map(|(si, field, k)| {
        name.strip_suffix(si)
            .filter(|stem| !stem.is_empty())
            .map(|stem| (format!("{stem}{field}"), *k))
    })
}

/// A CSV's text in field units: every column with an SI suffix renamed and its numbers
/// scaled (empty and non-numeric cells kept).
pub fn convert_csv(text: &str) -> Result<String, csv::Error> {
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes());
    let header = reader.headers()?.clone();
    let map: Vec<Option<(String, f64)>> = header.iter().map(field_key).collect();
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(
        header
            .iter()
            .zip(&map)
            .map(|(h, m)| m.as_ref().map_or(h.to_string(), |(n, _)| n.clone())),
    )?;
    for record in reader.records() {
        let record = record?;
        w.write_record(record.iter().enumerate().map(|(c, cell)| {
            match (map.get(c).and_then(|m| m.as_ref()), cell.parse::<f64>()) {
                (Some((_, k)), Ok(x)) => format!("{}", x * k),
                _ => cell.to_string(),
            }
        }))?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// A JSON value in field units: every object key with an SI suffix renamed, the numbers
/// under it (a number, or an array of numbers, nested) scaled.
pub fn convert_json(v: &serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    fn scale(v: &Value, k: f64) -> Value {
        match v {
            Value::Number(n) => n
                .as_f64()
                .and_then(|x| serde_json::Number::from_f64(x * k))
                .map_or(v.clone(), Value::Number),
            Value::Array(a) => Value::Array(a.iter().map(|x| scale(x, k)).collect()),
            other => other.clone(),
        }
    }
    match v {
        Value::Object(o) => Value::Object(
            o.iter()
                .map(|(key, x)| match field_key(key) {
                    Some((name, k)) if !x.is_object() => (name, scale(x, k)),
                    _ => (key.clone(), convert_json(x)),
                })
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.iter().map(convert_json).collect()),
        other => other.clone(),
    }
}

/// Translates a finished output folder's `.csv` files and `summary.json` into field units
/// in place (each file replaced atomically); nothing in SI mode.
pub fn convert_folder(dir: &std::path::Path) -> std::io::Result<()> {
    if get() == UnitSystem::Si {
        return Ok(());
    }
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !path.is_file() {
            continue;
        }
        if name.ends_with(".csv") {
            let text = std::fs::read_to_string(&path)?;
            let out = convert_csv(&text).map_err(std::io::Error::other)?;
            crate::atomic_file::write_atomic(&path, out.as_bytes())?;
        } else if name == "summary.json" {
            let text = std::fs::read_to_string(&path)?;
            let v: serde_json::Value =
                serde_json::from_str(&text).map_err(std::io::Error::other)?;
            let out =
                serde_json::to_vec_pretty(&convert_json(&v)).map_err(std::io::Error::other)?;
            crate::atomic_file::write_atomic(&path, &out)?;
        }
    }
    Ok(())
}

/// Plot units: (SI unit as a label writes it, field unit, factor from the plotted value).
const LABEL_UNITS: [(&str, &str, f64); 11] = [
    ("kN·m", "kft·lbf", 1.0 / (LBF * FT)),
    ("N·m", "ft·lbf", 1.0 / (LBF * FT)),
    ("kN/m", "lbf/ft", 1e3 * FT / LBF),
    ("N/m", "lbf/ft", FT / LBF),
    ("°/30 m", "°/100 ft", 100.0 * FT / 30.0),
    ("kN", "klbf", 1.0 / LBF),
    ("MPa", "ksi", 1e6 / PSI / 1e3),
    ("kg/m³", "ppg", 1.0 / PPG),
    ("m/s", "ft/min", 60.0 / FT),
    ("mm", "in", 1.0 / 25.4),
    ("m", "ft", 1.0 / FT),
];

/// A plot axis's label and the factor its values take: in field units, a label ending in
/// `(<SI unit>)` (or `(<SI unit>, …)`) gets the field unit; otherwise as it is, factor 1.
pub fn axis(label: &str) -> (String, f64) {
    axis_in(get(), label)
}

/// [`axis`] in `system`.
pub fn axis_in(system: UnitSystem, label: &str) -> (String, f64) {
    if system == UnitSystem::Si {
        return (label.to_string(), 1.0);
    }
    let Some(open) = label.rfind('(') else {
        return (label.to_string(), 1.0);
    };
    let inside = &label[open + 1..];
    for (si, field, k) in LABEL_UNITS {
        if let Some(rest) = inside.strip_prefix(si) {
            if rest.starts_with(')') || rest.starts_with(',') {
                let head = text_in(system, &label[..open + 1]);
                return (format!("{head}{field}{rest}"), k);
            }
        }
    }
    (label.to_string(), 1.0)
}

/// Titles and legends in field units: every `<number> <SI unit>` (kN·m, kN, MPa, m, mm)
/// rewritten as the field quantity; SI mode returns the text.
pub fn text(s: &str) -> String {
    text_in(get(), s)
}

/// [`text`] in `system`.
pub fn text_in(system: UnitSystem, s: &str) -> String {
    if system == UnitSystem::Si {
        return s.to_string();
    }
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    'outer: while !rest.is_empty() {
        // A number starts where a digit is not preceded by a letter or digit.
        if let Some(pos) = rest.find(|c: char| c.is_ascii_digit()) {
            let before = &rest[..pos];
            let prev = before.chars().last();
            let attached = prev.is_some_and(|c| c.is_alphanumeric() || c == '.' || c == '_');
            let num_len = rest[pos..]
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == ','))
                .unwrap_or(rest.len() - pos);
            let num_text = &rest[pos..pos + num_len];
            let after = &rest[pos + num_len..];
            if !attached {
                if let (Ok(x), Some(unit_text)) = (
                    num_text.replace(',', "").parse::<f64>(),
                    after.strip_prefix(' '),
                ) {
                    for (si, field, k) in LABEL_UNITS {
                        if si.contains('/') || si == "N·m" {
                            continue;
                        }
                        if let Some(tail) = unit_text.strip_prefix(si) {
                            if tail.chars().next().is_none_or(|c| !c.is_alphanumeric()) {
                                // As many significant digits as the number had.
                                let sig = num_text
                                    .chars()
                                    .filter(|c| c.is_ascii_digit())
                                    .skip_while(|c| *c == '0')
                                    .count()
                                    .clamp(2, 6) as i32;
                                let v = x * k;
                                let mag = v.abs().max(1e-300).log10().floor() as i32;
                                let decimals = (sig - 1 - mag).max(0) as usize;
                                let shown = format!("{v:.decimals$}");
                                out.push_str(before);
                                out.push_str(&format!("{shown} {field}"));
                                rest = tail;
                                continue 'outer;
                            }
                        }
                    }
                }
            }
            out.push_str(&rest[..pos + num_len.max(1)]);
            rest = &rest[pos + num_len.max(1)..];
        } else {
            out.push_str(rest);
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_values_translate() {
        assert_eq!(field_key("md_m").unwrap().0, "md_ft");
        assert_eq!(field_key("hook_load_n").unwrap().0, "hook_load_klbf");
        assert_eq!(field_key("torque_nm").unwrap().0, "torque_kftlbf");
        assert_eq!(
            field_key("side_force_per_length_n_per_m").unwrap().0,
            "side_force_per_length_lbf_per_ft"
        );
        assert_eq!(
            field_key("build_rate_deg_per_30m").unwrap().0,
            "build_rate_deg_per_100ft"
        );
        assert!(field_key("status").is_none() && field_key("_m").is_none());
        // 1000 m = 3280.84 ft; 4448.22 N = 1 klbf… of 1000 lbf; 1355.82 N·m = 1 kft·lbf.
        let csv =
            "md_m,hook_load_n,torque_nm,mode\n1000,4448.221615260505,1355.8179483314,pick_up\n";
        let out = convert_csv(csv).unwrap();
        let mut lines = out.lines();
        assert_eq!(
            lines.next().unwrap(),
            "md_ft,hook_load_klbf,torque_kftlbf,mode"
        );
        let row: Vec<f64> = lines
            .next()
            .unwrap()
            .split(',')
            .take(3)
            .map(|x| x.parse().unwrap())
            .collect();
        assert!((row[0] - 3_280.839_895).abs() < 1e-5);
        assert!((row[1] - 1.0).abs() < 1e-12 && (row[2] - 1.0).abs() < 1e-9);
        let j = serde_json::json!({"hook_load_n": 4448.221615260505, "interval": [1, 2],
            "rig": {"dead_line_n": 44482.21615260505, "travel": "hoisting"},
            "range_m": [304.8, 609.6]});
        let f = convert_json(&j);
        assert!((f["hook_load_klbf"].as_f64().unwrap() - 1.0).abs() < 1e-12);
        assert!((f["rig"]["dead_line_klbf"].as_f64().unwrap() - 10.0).abs() < 1e-12);
        assert_eq!(f["interval"], serde_json::json!([1, 2]));
        assert!((f["range_ft"][1].as_f64().unwrap() - 2000.0).abs() < 1e-9);
    }

    #[test]
    fn plot_labels_and_legends_translate() {
        let f = UnitSystem::Field;
        let (l, k) = axis_in(f, "bit depth, MD (m)");
        assert_eq!(l, "bit depth, MD (ft)");
        assert!((k - 1.0 / 0.3048).abs() < 1e-12);
        assert_eq!(
            axis_in(f, "surface torque (kN·m)").0,
            "surface torque (kft·lbf)"
        );
        assert_eq!(axis_in(f, "hook load (kN)").0, "hook load (klbf)");
        assert_eq!(
            axis_in(f, "build rate (°/30 m, − drop)").0,
            "build rate (°/100 ft, − drop)"
        );
        assert_eq!(axis_in(f, "frequency (Hz)").0, "frequency (Hz)");
        assert_eq!(
            axis_in(f, "weight indicator, incl. 356 kN block (kN)").0,
            "weight indicator, incl. 80.0 klbf block (klbf)"
        );
        assert_eq!(
            axis_in(UnitSystem::Si, "hook load (kN)").0,
            "hook load (kN)"
        );
        assert_eq!(
            text_in(
                f,
                "weight indicator, incl. 356 kN block, 1500 m, stab1 2.5 m"
            ),
            "weight indicator, incl. 80.0 klbf block, 4921 ft, stab1 8.2 ft"
        );
        assert_eq!(
            text_in(f, "mu.open 0.3, G105, 90 %"),
            "mu.open 0.3, G105, 90 %"
        );
    }
}
