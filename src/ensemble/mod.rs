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
//! | `ecc` | centre-of-mass offset of every BHA component (dynamics: a mass imbalance; replaces the case's) | m | 0 … 50 mm |
//! | `bend` | angle of every bent sub / bent housing of the case (`[[string]].bend`) | degrees unless a unit is given | 0 … 5° |
//! | `layout` | one of the case's `ensemble.layouts` (1, 2, …): its `stabK.from_bit` / `stabK.blade` values together | – | 1 … number of layouts |
//!
//! Stabilizers are numbered from the bit up (`stab1` nearest the bit); a key without
//! `.stabK` applies to every contact site.

pub mod job;
pub mod measured;
pub mod plots;
pub mod qoi;
pub mod report;
pub mod runner;
pub mod store;
pub mod tendency_map;

use std::path::Path;

use crate::case::Case;
use crate::error::InputError;
pub use crate::keys::{Key, Param, KEY_FORMS, MODES};
use crate::model::Model;

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

/// The reader of a user's CSV (variants, measurements): cells trimmed, `#` lines comments.
pub(crate) fn input_csv(text: &str) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes())
}

/// As [`variants_from_csv`], from text.
pub fn variants_from_csv_text(source: &str, text: &str) -> Result<Vec<Variant>, InputError> {
    let mut reader = input_csv(text);
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
    // A layout expands into its stabilizer values, ahead of the variant's own overrides
    // (which so win over it).
    let expanded;
    let variant = match variant
        .overrides
        .iter()
        .find(|(k, _)| k.param == Param::Layout)
    {
        None => variant,
        Some((_, index)) => {
            let layouts = case
                .ensemble
                .as_ref()
                .map(|e| e.layouts.as_slice())
                .unwrap_or(&[]);
            let layout = layouts.get(*index as usize - 1).ok_or_else(|| {
                format!(
                    "layout {index}: the case has {} in ensemble.layouts",
                    layouts.len()
                )
            })?;
            let mut overrides = layout.clone();
            overrides.extend(
                variant
                    .overrides
                    .iter()
                    .filter(|(k, _)| k.param != Param::Layout)
                    .cloned(),
            );
            expanded = Variant {
                name: variant.name.clone(),
                overrides,
            };
            &expanded
        }
    };
    let mut model = case.model.clone();
    let stabs = case.model.stabilizer_sites();
    let stab = |k: usize| -> Result<usize, String> {
        stabs.get(k - 1).copied().ok_or_else(|| {
            format!(
                "{}: the case has {} stabilizer site(s)",
                crate::model::stabilizer_name(k),
                stabs.len()
            )
        })
    };
    let hole_radius_at = |md: f64| 0.5 * case.hole_diameter_at(md);
    for (key, value) in &variant.overrides {
        if key.param != Param::FromBit {
            continue;
        }
        let k = stab(key.stabilizer.unwrap_or(1))?;
        let string_length = case.bit_md - model.nodes[0].md;
        if !(*value > 0.0 && *value < string_length) {
            return Err(format!(
                "{}: {} m from the bit is off the string, which is {} m long; allowed: \
                 0 < from_bit < {} m",
                key.name,
                crate::units::show(*value),
                crate::units::show(string_length),
                crate::units::show(string_length)
            ));
        }
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
        let sites: Vec<usize> = match (key.stabilizer, key.hole) {
            (Some(k), _) => vec![stab(k)?],
            (None, Some(select)) => sites_in_sections(case, &model, select, &key.name)?,
            (None, None) => (0..model.sites.len()).collect(),
        };
        match key.param {
            Param::FromBit | Param::Depth | Param::Mode | Param::Layout => {}
            Param::Eccentricity => {
                let bha_top = bit_md_of_model(&model) - case.bha_length;
                let density = &case.element_density;
                let nodes = &model.nodes;
                let in_bha = |e: usize| 0.5 * (nodes[e].md + nodes[e + 1].md) >= bha_top;
                model.unbalance =
                    model.unbalance_from(&|e| density.get(e).copied().unwrap_or(7850.0), &|e| {
                        if in_bha(e) {
                            v
                        } else {
                            0.0
                        }
                    });
            }
            Param::Bend => {
                if model.bends.is_empty() {
                    return Err(format!(
                        "{}: the case has no bent sub or bent housing (give [[string]].bend)",
                        key.name
                    ));
                }
                for b in &mut model.bends {
                    b.angle = v;
                }
            }
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

/// The sites of `model` whose node lies in the hole sections `select` names (a section
/// holds its bottom: [`crate::case::hole_section_index`]); an error when the case has no such
/// section.
fn sites_in_sections(
    case: &Case,
    model: &Model,
    select: crate::keys::HoleSelect,
    key: &str,
) -> Result<Vec<usize>, String> {
    use crate::keys::HoleSelect;
    let in_section = |md: f64| -> bool {
        let k = crate::case::hole_section_index(&case.hole, md);
        match select {
            HoleSelect::Cased => case.hole[k].cased,
            HoleSelect::Open => !case.hole[k].cased,
            HoleSelect::Section(n) => k + 1 == n,
        }
    };
    let exists = match select {
        HoleSelect::Cased => case.hole.iter().any(|h| h.cased),
        HoleSelect::Open => case.hole.iter().any(|h| !h.cased),
        HoleSelect::Section(n) => n <= case.hole.len(),
    };
    if !exists {
        return Err(format!(
            "{key}: the case has no such hole section ({} [[hole]] sections, {} cased)",
            case.hole.len(),
            case.hole.iter().filter(|h| h.cased).count()
        ));
    }
    Ok((0..model.sites.len())
        .filter(|&k| in_section(model.nodes[model.sites[k].node].md))
        .collect())
}

fn bit_md_of_model(model: &Model) -> f64 {
    model.nodes.last().map_or(0.0, |n| n.md)
}

/// The case rebuilt for a variant's `depth` and `mode`, if it has either: its tables with
/// `well.total_md` and `operation.mode` replaced (every other input and check as written;
/// the files are not read again: [`Case::rebuilt`]).
pub fn variant_case(case: &Case, variant: &Variant) -> Result<Option<Case>, String> {
    use crate::case::Quantity;
    use toml::Spanned;
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
    let rpm = variant
        .overrides
        .iter()
        .find(|(k, _)| k.param == Param::Rpm)
        .map(|(_, v)| *v);
    case.rebuilt(|spec| {
        if let Some(d) = depth {
            let span = spec.well.total_md.span();
            spec.well.total_md = Spanned::new(span, Quantity::Number(d));
        }
        if let Some(m) = mode {
            let op = &mut spec.operation;
            // The variant chooses the operation: a tripping or sliding variant does not
            // rotate (the case's rpm belongs to its rotating variants), and a rotating,
            // reaming or back-reaming one rotates at the variant's rpm where it gives one
            // (applied again with the other overrides).
            if matches!(m.as_str(), "rotating" | "reaming" | "back_reaming") {
                if let Some(rpm) = rpm {
                    let span = op.rpm.as_ref().map_or(op.mode.span(), |q| q.span());
                    op.rpm = Some(Spanned::new(span, Quantity::Text(format!("{rpm} rad/s"))));
                }
            } else {
                op.rpm = None;
            }
            let span = op.mode.span();
            op.mode = Spanned::new(span, m);
        }
    })
    .map(Some)
    .map_err(|e| format!("depth/mode: {}: {}", e.key, e.message))
}

/// `n` samples of the uncertain inputs as variants named `s00001`, … (each overriding every
/// uncertain key), drawn by `sampling` with `seed`: the unit-cube points mapped through each
/// input's quantile function. Sample `i` is the same whatever `n`'s other samples, the
/// chunking or the machine (for `random`; `lhs` and `sobol` depend on `n` as a whole). A
/// sampled value outside the key's allowed range is an error naming it.
///
/// With `sobol_indices` the points are a Saltelli design for `n` base samples
/// ([`crate::uq::sensitivity::saltelli_design`]): `n (d + 2)` variants, the first `2n` of them
/// independent samples of the inputs (`A` and `B`), the rest `A` with one input from `B`.
pub fn sample_variants(
    uncertain: &[(Key, crate::uq::Distribution)],
    n: usize,
    seed: u64,
    sampling: crate::uq::Sampling,
    sobol_indices: bool,
    correlation: Option<&nalgebra::DMatrix<f64>>,
) -> Result<Vec<Variant>, String> {
    if uncertain.is_empty() {
        return Err("no uncertain inputs: add an [ensemble.uncertain] table".into());
    }
    if n == 0 {
        return Err("--samples must be at least 1".into());
    }
    let mut u = if sobol_indices {
        if sampling != crate::uq::Sampling::Sobol {
            return Err("Sobol indices need --sampling sobol (the Saltelli design is built on Sobol points)".into());
        }
        crate::uq::sensitivity::saltelli_design(n, uncertain.len(), seed)?
    } else {
        crate::uq::unit_samples(n, uncertain.len(), seed, sampling)?
    };
    if let Some(c) = correlation {
        if sampling == crate::uq::Sampling::Sobol {
            return Err("ensemble.correlation reorders the samples, which breaks Sobol points' structure: use --sampling lhs or random".into());
        }
        crate::uq::sampling::iman_conover(&mut u, c, seed)?;
    }
    let width = u.len().to_string().len().max(5);
    u.iter()
        .enumerate()
        .map(|(i, p)| {
            let overrides = uncertain
                .iter()
                .zip(p)
                .map(|((key, dist), &ui)| {
                    let v = dist.quantile(ui);
                    key.check(v)
                        .map(|v| (key.clone(), v))
                        .map_err(|m| {
                            format!(
                                "sample {i}: {} drew {v} from a {dist}, outside the key's range ({m}); truncate the distribution",
                                key.name
                            )
                        })
                })
                .collect::<Result<Vec<_>, String>>()?;
            Ok(Variant {
                name: format!("s{:0width$}", i + 1),
                overrides,
            })
        })
        .collect()
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
