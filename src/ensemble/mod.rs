//! Ensembles: one case, many parameter variants (issue 5). A variant is a list of
//! overrides of the case — contact-law parameters (all sites, or one stabilizer's), the
//! stabilizer layout (blade diameter, distance from the bit), RPM, WOB and TOB — given as
//! a CSV (one row per variant, one column per key) or as a grid in the case's
//! `[ensemble]` table (every combination).
//!
//! Keys (values in SI, or `"<number> <unit>"`):
//!
//! | key | meaning | unit | allowed |
//! |---|---|---|---|
//! | `mu`, `mu_t`, `mu_l` (`.stabK`) | friction (both, circumferential, axial) | – | 0 … 2 |
//! | `k_e` (`.stabK`) | wall stiffness | N/m^m | 0 < … ≤ 1e12 |
//! | `c` (`.stabK`) | wall damping | N·s/m | ≥ 0 |
//! | `m` (`.stabK`) | spring exponent | – | 0 < … ≤ 3 |
//! | `eps` (`.stabK`) | friction regularisation speed | m/s | > 0 |
//! | `rpm` | rotary speed | rad/s | 0 … 1000 rpm |
//! | `wob`, `tob` | weight and torque on bit | N, N·m | ≥ 0 |
//! | `stabK.blade` | blade diameter of stabilizer K | m | ≤ hole diameter |
//! | `stabK.from_bit` | distance of stabilizer K's site from the bit | m | 0 < … < bit MD |
//! | `depth` | bit depth (MD): the case rebuilt with `well.total_md` there (the string cut at the surface, the hole sections kept) | m | 0 < … ≤ 20 km, within the hole |
//! | `mode` | operation: `rotating`, `tripping_in`, `tripping_out`, `sliding` (the case rebuilt with it) | – | one of those |
//!
//! Stabilizers are numbered from the bit up (`stab1` nearest the bit); a key without
//! `.stabK` applies to every contact site.

pub mod job;
pub mod qoi;
pub mod report;
pub mod runner;
pub mod store;

use std::path::Path;

use crate::case::Case;
use crate::error::InputError;
use crate::model::Model;
use crate::units::{parse_quantity, Dimension};

/// What a key overrides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Param {
    /// Both friction coefficients.
    Mu,
    /// Circumferential friction.
    MuT,
    /// Axial friction.
    MuL,
    /// Wall stiffness.
    WallStiffness,
    /// Wall damping.
    WallDamping,
    /// Spring exponent.
    Exponent,
    /// Friction regularisation speed.
    Eps,
    /// Rotary speed (rad/s).
    Rpm,
    /// Weight on bit (N).
    Wob,
    /// Torque on bit (N·m).
    Tob,
    /// Blade diameter (m).
    Blade,
    /// Distance of the stabilizer's site from the bit (m).
    FromBit,
    /// Bit depth, MD (m): the case rebuilt there.
    Depth,
    /// Operation mode (a code of [`MODES`]): the case rebuilt with it.
    Mode,
}

/// The operation modes a `mode` key takes, by code (its value is the index).
pub const MODES: [&str; 4] = ["rotating", "tripping_in", "tripping_out", "sliding"];

/// A parsed column key.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    /// The text as written.
    pub name: String,
    /// What it overrides.
    pub param: Param,
    /// Stabilizer (1 = nearest the bit), or every site.
    pub stabilizer: Option<usize>,
}

/// Every key form, for messages.
pub const KEY_FORMS: &str = "mu, mu_t, mu_l, k_e, c, m, eps (each optionally .stabK), rpm, wob, tob, stabK.blade, stabK.from_bit, depth, mode";

impl Key {
    /// Parses a column key.
    pub fn parse(name: &str) -> Result<Key, String> {
        let stab_index = |s: &str| -> Result<usize, String> {
            s.strip_prefix("stab")
                .and_then(|k| k.parse::<usize>().ok())
                .filter(|&k| k >= 1)
                .ok_or_else(|| format!("unknown key {name:?}; allowed: {KEY_FORMS}"))
        };
        let (head, tail) = match name.split_once('.') {
            Some((h, t)) => (h, Some(t)),
            None => (name, None),
        };
        let law = |p: &str| match p {
            "mu" => Some(Param::Mu),
            "mu_t" => Some(Param::MuT),
            "mu_l" => Some(Param::MuL),
            "k_e" => Some(Param::WallStiffness),
            "c" => Some(Param::WallDamping),
            "m" => Some(Param::Exponent),
            "eps" => Some(Param::Eps),
            _ => None,
        };
        let (param, stabilizer) = match (head, tail) {
            ("rpm", None) => (Param::Rpm, None),
            ("wob", None) => (Param::Wob, None),
            ("tob", None) => (Param::Tob, None),
            ("depth", None) => (Param::Depth, None),
            ("mode", None) => (Param::Mode, None),
            (h, None) if law(h).is_some() => (law(h).unwrap_or(Param::Mu), None),
            (h, Some(t)) if law(h).is_some() => (law(h).unwrap_or(Param::Mu), Some(stab_index(t)?)),
            (h, Some("blade")) => (Param::Blade, Some(stab_index(h)?)),
            (h, Some("from_bit")) => (Param::FromBit, Some(stab_index(h)?)),
            _ => return Err(format!("unknown key {name:?}; allowed: {KEY_FORMS}")),
        };
        Ok(Key {
            name: name.to_string(),
            param,
            stabilizer,
        })
    }

    /// A value as `variants.csv` writes it: the mode's name, else the number.
    pub fn format(&self, v: f64) -> String {
        match self.param {
            Param::Mode => MODES
                .get(v as usize)
                .map(|m| m.to_string())
                .unwrap_or_else(|| format!("{v}")),
            _ => format!("{v}"),
        }
    }

    /// Parses and range-checks a value of this key (SI number or `"<number> <unit>"`; a
    /// mode's name, or its code).
    pub fn value(&self, text: &str) -> Result<f64, String> {
        if self.param == Param::Mode {
            let t = text.trim();
            return MODES
                .iter()
                .position(|m| *m == t)
                .map(|k| k as f64)
                .or_else(|| {
                    t.parse::<f64>()
                        .ok()
                        .filter(|x| x.fract() == 0.0 && (0.0..MODES.len() as f64).contains(x))
                })
                .ok_or_else(|| format!("unknown mode {t:?}; allowed: {}", MODES.join(", ")));
        }
        let (dim, ok, range): (Option<Dimension>, fn(f64) -> bool, &str) = match self.param {
            Param::Mu | Param::MuT | Param::MuL => (None, |x| (0.0..=2.0).contains(&x), "0 … 2"),
            Param::WallStiffness => (None, |x| x > 0.0 && x <= 1e12, "0 < k_e ≤ 1e12 N/m^m"),
            Param::WallDamping => (Some(Dimension::Damping), |x| x >= 0.0, "≥ 0 N·s/m"),
            Param::Exponent => (None, |x| x > 0.0 && x <= 3.0, "0 < m ≤ 3"),
            Param::Eps => (
                Some(Dimension::Speed),
                |x| x > 0.0 && x <= 10.0,
                "0 < eps ≤ 10 m/s",
            ),
            Param::Rpm => (
                Some(Dimension::AngularSpeed),
                |x| (0.0..=1000.0 * std::f64::consts::TAU / 60.0).contains(&x),
                "0 … 1000 rpm",
            ),
            Param::Wob => (
                Some(Dimension::Force),
                |x| (0.0..=1e7).contains(&x),
                "0 … 1e7 N",
            ),
            Param::Tob => (
                Some(Dimension::Torque),
                |x| (0.0..=1e6).contains(&x),
                "0 … 1e6 N·m",
            ),
            Param::Blade => (
                Some(Dimension::Length),
                |x| x > 0.0 && x < 2.0,
                "0 < blade < 2 m",
            ),
            Param::FromBit => (
                Some(Dimension::Length),
                |x| x > 0.0 && x < 2e4,
                "0 < from_bit < 20 km",
            ),
            Param::Depth => (
                Some(Dimension::Length),
                |x| x > 0.0 && x <= 2e4,
                "0 < depth ≤ 20 km",
            ),
            Param::Mode => unreachable!("parsed above"),
        };
        let t = text.trim();
        let v = match (t.parse::<f64>(), dim) {
            (Ok(x), _) => x,
            (Err(_), Some(d)) => parse_quantity(t, d).map_err(|e| e.to_string())?,
            (Err(_), None) => return Err(format!("{t:?} is not a number")),
        };
        if !v.is_finite() || !ok(v) {
            return Err(format!("{t} out of range; allowed: {range}"));
        }
        Ok(v)
    }
}

/// A case's variants: the CSV `file` if given, else its `[ensemble.grid]`; `None` when it
/// has neither.
pub fn case_variants(case: &Case, file: Option<&Path>) -> Result<Option<Vec<Variant>>, InputError> {
    Ok(match (file, case.ensemble.as_ref()) {
        (Some(f), _) => Some(variants_from_csv(f)?),
        (None, Some(s)) if !s.grid.is_empty() => Some(variants_from_grid(&s.grid)),
        _ => None,
    })
}

/// One variant: a name and its overrides (SI).
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// Name (the CSV's `name` column, or the row/grid index).
    pub name: String,
    /// Overrides in column order.
    pub overrides: Vec<(Key, f64)>,
}

fn input_error(source: &str, line: usize, key: &str, message: impl Into<String>) -> InputError {
    InputError {
        source_name: source.to_string(),
        line,
        key: key.to_string(),
        message: message.into(),
    }
}

/// Reads variants from a CSV: a header of keys (and optionally `name`), one row per
/// variant. Every cell is checked; the first error names the file, line and key.
pub fn variants_from_csv(path: &Path) -> Result<Vec<Variant>, InputError> {
    let source = path.display().to_string();
    let text =
        std::fs::read_to_string(path).map_err(|e| input_error(&source, 0, "-", e.to_string()))?;
    variants_from_csv_text(&source, &text)
}

/// As [`variants_from_csv`], from text.
pub fn variants_from_csv_text(source: &str, text: &str) -> Result<Vec<Variant>, InputError> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let header = reader
        .headers()
        .map_err(|e| input_error(source, 1, "-", e.to_string()))?
        .clone();
    let mut keys: Vec<Option<Key>> = Vec::new();
    for h in header.iter() {
        if h == "name" {
            keys.push(None);
        } else {
            let key = Key::parse(h).map_err(|m| input_error(source, 1, h, m))?;
            if keys.iter().flatten().any(|k| k.name == key.name) {
                return Err(input_error(source, 1, h, "column given twice"));
            }
            keys.push(Some(key));
        }
    }
    if keys.iter().all(|k| k.is_none()) {
        return Err(input_error(
            source,
            1,
            "-",
            format!("no parameter columns; allowed: {KEY_FORMS}"),
        ));
    }
    let mut out = Vec::new();
    for (row, record) in reader.records().enumerate() {
        let line = record
            .as_ref()
            .ok()
            .and_then(|r| r.position().map(|p| p.line() as usize))
            .unwrap_or(row + 2);
        let record = record.map_err(|e| input_error(source, line, "-", e.to_string()))?;
        if record.len() != keys.len() {
            return Err(input_error(
                source,
                line,
                "-",
                format!("{} fields, the header has {}", record.len(), keys.len()),
            ));
        }
        let mut v = Variant {
            name: row.to_string(),
            overrides: Vec::new(),
        };
        for (cell, key) in record.iter().zip(&keys) {
            match key {
                None => v.name = cell.to_string(),
                Some(k) => {
                    let x = k
                        .value(cell)
                        .map_err(|m| input_error(source, line, &k.name, m))?;
                    v.overrides.push((k.clone(), x));
                }
            }
        }
        out.push(v);
    }
    if out.is_empty() {
        return Err(input_error(source, 1, "-", "no variant rows"));
    }
    Ok(out)
}

/// Every combination of the grid's values (the first key varies slowest).
pub fn variants_from_grid(grid: &[(Key, Vec<f64>)]) -> Vec<Variant> {
    let total: usize = grid.iter().map(|(_, v)| v.len()).product();
    (0..total)
        .map(|index| {
            let mut rest = index;
            let mut overrides = vec![];
            for (key, values) in grid.iter().rev() {
                overrides.push((key.clone(), values[rest % values.len()]));
                rest /= values.len();
            }
            overrides.reverse();
            Variant {
                name: index.to_string(),
                overrides,
            }
        })
        .collect()
}

/// Indices into `model.sites` of the stabilizers, nearest the bit first.
pub fn stabilizer_sites(model: &Model) -> Vec<usize> {
    let mut s: Vec<usize> = (0..model.sites.len())
        .filter(|&k| model.sites[k].stabilizer)
        .collect();
    s.sort_by_key(|&k| std::cmp::Reverse(model.sites[k].node));
    s
}

/// The case's model with a variant's overrides applied. Layout moves come first (a
/// stabilizer's site goes to the node nearest its new distance from the bit; a pipe-body
/// site there, if any, takes the old node), then values, in column order.
pub fn apply(case: &Case, variant: &Variant) -> Result<Model, String> {
    let rebuilt;
    let case = match variant_case(case, variant)? {
        Some(c) => {
            rebuilt = c;
            &rebuilt
        }
        None => case,
    };
    let mut model = case.model.clone();
    let stabs = stabilizer_sites(&case.model);
    let stab = |k: usize| -> Result<usize, String> {
        stabs
            .get(k - 1)
            .copied()
            .ok_or_else(|| format!("stab{k}: the case has {} stabilizer site(s)", stabs.len()))
    };
    let hole_radius_at = |md: f64| {
        0.5 * case
            .hole
            .iter()
            .find(|h| md <= h.0 + 1e-9)
            .or(case.hole.last())
            .map(|h| h.1)
            .unwrap_or(0.0)
    };
    for (key, value) in &variant.overrides {
        if key.param != Param::FromBit {
            continue;
        }
        let k = stab(key.stabilizer.unwrap_or(1))?;
        let md = case.bit_md - value;
        let n = model.nodes.len();
        // Not the clamped top or the laterally held bit.
        let node = (1..n - 1)
            .min_by(|&a, &b| {
                (model.nodes[a].md - md)
                    .abs()
                    .total_cmp(&(model.nodes[b].md - md).abs())
            })
            .ok_or("the mesh has no free node")?;
        let old = model.sites[k].node;
        if node == old {
            continue;
        }
        if let Some(j) = (0..model.sites.len()).find(|&j| j != k && model.sites[j].node == node) {
            if model.sites[j].stabilizer {
                return Err(format!(
                    "{}: two stabilizers at MD {:.2} m",
                    key.name, model.nodes[node].md
                ));
            }
            let (pipe_radius, hole_radius) = (
                model.pipe_radius_at(old),
                hole_radius_at(model.nodes[old].md),
            );
            let other = &mut model.sites[j];
            other.node = old;
            other.hole_radius = hole_radius;
            other.params.disk_radius = pipe_radius;
            other.params.clearance = other.hole_radius - other.params.disk_radius;
        }
        let site = &mut model.sites[k];
        site.node = node;
        site.hole_radius = hole_radius_at(model.nodes[node].md);
        site.params.clearance = site.hole_radius - site.params.disk_radius;
        if site.params.clearance < 0.0 {
            return Err(format!(
                "{}: the blade is wider than the hole there",
                key.name
            ));
        }
    }
    for (key, value) in &variant.overrides {
        let v = *value;
        let sites: Vec<usize> = match key.stabilizer {
            Some(k) => vec![stab(k)?],
            None => (0..model.sites.len()).collect(),
        };
        match key.param {
            Param::FromBit | Param::Depth | Param::Mode => {}
            Param::Rpm => model.rotation_speed = v,
            Param::Wob => {
                if let crate::model::TopBoundary::HookLoad(_) = model.top {
                    return Err("wob: the case gives the hook load; give operation.weight_on_bit to vary the WOB".into());
                }
                model.weight_on_bit = v;
            }
            Param::Tob => model.torque_on_bit = v,
            Param::Blade => {
                let site = &mut model.sites[sites[0]];
                site.params.disk_radius = 0.5 * v;
                site.params.clearance = site.hole_radius - 0.5 * v;
                if site.params.clearance < 0.0 {
                    return Err(format!(
                        "{}: blade {v} m is wider than the hole ({} m)",
                        key.name,
                        2.0 * site.hole_radius
                    ));
                }
            }
            _ => {
                for &k in &sites {
                    let p = &mut model.sites[k].params;
                    match key.param {
                        Param::Mu => {
                            p.mu_t = v;
                            p.mu_l = v;
                        }
                        Param::MuT => p.mu_t = v,
                        Param::MuL => p.mu_l = v,
                        Param::WallStiffness => p.wall_stiffness = v,
                        Param::WallDamping => p.wall_damping = v,
                        Param::Exponent => p.spring_exponent = v,
                        Param::Eps => p.eps = v,
                        _ => {}
                    }
                }
            }
        }
    }
    model.sites.sort_by_key(|s| s.node);
    Ok(model)
}

/// The case rebuilt for a variant's `depth` and `mode`, if it has either: the case file
/// read again with `well.total_md` and `operation.mode` replaced (every other input and
/// check as written).
pub fn variant_case(case: &Case, variant: &Variant) -> Result<Option<Case>, String> {
    let depth = variant
        .overrides
        .iter()
        .find(|(k, _)| k.param == Param::Depth)
        .map(|(_, v)| *v);
    let mode = variant
        .overrides
        .iter()
        .find(|(k, _)| k.param == Param::Mode)
        .map(|(k, v)| k.format(*v));
    if depth.is_none() && mode.is_none() {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(&case.path).map_err(|e| format!("{}: {e}", case.path.display()))?;
    let mut table: toml::Table = text
        .parse()
        .map_err(|e| format!("{}: {e}", case.path.display()))?;
    let section = |t: &mut toml::Table, name: &str| -> Result<toml::Table, String> {
        match t.get(name) {
            Some(toml::Value::Table(s)) => Ok(s.clone()),
            _ => Err(format!("the case has no [{name}] table")),
        }
    };
    if let Some(d) = depth {
        let mut well = section(&mut table, "well")?;
        well.insert("total_md".into(), toml::Value::Float(d));
        table.insert("well".into(), toml::Value::Table(well));
    }
    if let Some(m) = mode {
        let mut op = section(&mut table, "operation")?;
        op.insert("mode".into(), toml::Value::String(m));
        table.insert("operation".into(), toml::Value::Table(op));
    }
    let edited = toml::to_string(&table).map_err(|e| e.to_string())?;
    crate::case::parse_case(&case.path, &edited)
        .map(Some)
        .map_err(|e| format!("depth/mode: {}", e.message))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_parse_and_reject() {
        let k = Key::parse("k_e.stab2").unwrap();
        assert_eq!((k.param, k.stabilizer), (Param::WallStiffness, Some(2)));
        let k = Key::parse("stab1.from_bit").unwrap();
        assert_eq!((k.param, k.stabilizer), (Param::FromBit, Some(1)));
        assert_eq!(Key::parse("rpm").unwrap().param, Param::Rpm);
        for bad in [
            "rpm.stab1",
            "stab0.blade",
            "kappa",
            "mu.stabx",
            "stab1.width",
        ] {
            assert!(Key::parse(bad).is_err(), "{bad}");
        }
        let rpm = Key::parse("rpm").unwrap();
        assert!((rpm.value("120 rpm").unwrap() - 4.0 * std::f64::consts::PI).abs() < 1e-12);
        assert!(rpm.value("2000 rpm").is_err());
        assert!(Key::parse("mu").unwrap().value("-0.1").is_err());
        assert!(Key::parse("wob").unwrap().value("20 kN").unwrap() == 20_000.0);
        assert!(Key::parse("m").unwrap().value("20 kN").is_err());
    }

    #[test]
    fn grid_enumerates_every_combination() {
        let grid = vec![
            (Key::parse("mu").unwrap(), vec![0.1, 0.2]),
            (Key::parse("wob").unwrap(), vec![1.0, 2.0, 3.0]),
        ];
        let v = variants_from_grid(&grid);
        assert_eq!(v.len(), 6);
        assert_eq!(v[0].overrides[0].1, 0.1);
        assert_eq!(v[0].overrides[1].1, 1.0);
        assert_eq!(v[1].overrides[1].1, 2.0);
        assert_eq!(v[5].overrides[0].1, 0.2);
        assert_eq!(v[5].overrides[1].1, 3.0);
    }

    #[test]
    fn csv_errors_name_line_and_key() {
        let e =
            variants_from_csv_text("v.csv", "name,mu,wob\na,0.2,10 kN\nb,3,10 kN\n").unwrap_err();
        assert_eq!((e.line, e.key.as_str()), (3, "mu"));
        let e = variants_from_csv_text("v.csv", "mu,speed\n0.2,1\n").unwrap_err();
        assert_eq!((e.line, e.key.as_str()), (1, "speed"));
        let e = variants_from_csv_text("v.csv", "mu,wob\n0.2\n").unwrap_err();
        assert_eq!(e.line, 2);
        let ok = variants_from_csv_text("v.csv", "name,mu,wob\na,0.2,10 kN\n").unwrap();
        assert_eq!(ok[0].name, "a");
        assert_eq!(ok[0].overrides[1].1, 10_000.0);
    }
}
