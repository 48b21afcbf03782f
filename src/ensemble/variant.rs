//! Variants: reading them (a CSV, the case's grid, samples of its uncertain inputs) and
//! applying one to the case's model ([`apply`]). The keys are in the module docs of
//! [`crate::ensemble`].

use std::path::Path;

use crate::case::Case;
use crate::error::InputError;
use crate::keys::{Key, Param, Value, KEY_FORMS};
use crate::model::Model;
use crate::uq::SamplingError;

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
    pub overrides: Vec<(Key, Value)>,
}

impl Variant {
    /// The value this variant gives `param` (the last override of it), if any.
    pub fn value_of(&self, param: Param) -> Option<Value> {
        self.overrides
            .iter()
            .rev()
            .find(|(k, _)| k.param == param)
            .map(|(_, v)| *v)
    }
}

/// Why a variant cannot be applied to its case ([`apply`], [`variant_case`]).
#[derive(Clone, Debug, thiserror::Error)]
pub enum VariantError {
    /// A stabilizer key beyond the case's stabilizers.
    #[error("{stabilizer}: the case has {count} stabilizer site(s)")]
    NoStabilizer {
        /// The stabilizer's name (`stab3`).
        stabilizer: String,
        /// The case's stabilizer sites.
        count: usize,
    },
    /// A `from_bit` off the string.
    #[error(
        "{key}: {} m from the bit is off the string, which is {} m long; allowed: 0 < from_bit < {} m",
        crate::units::show(*from_bit),
        crate::units::show(*length),
        crate::units::show(*length)
    )]
    OffString {
        /// The key as written.
        key: String,
        /// The distance given (m).
        from_bit: f64,
        /// The string's length (m).
        length: f64,
    },
    /// A mesh with no node between the clamped top and the bit.
    #[error("the mesh has no free node")]
    NoFreeNode,
    /// Two stabilizers moved onto one node.
    #[error("{key}: two stabilizers at MD {md:.2} m")]
    TwoStabilizers {
        /// The key as written.
        key: String,
        /// The node's MD (m).
        md: f64,
    },
    /// A blade (given, or moved to a narrower section) wider than the hole.
    #[error("{key}: blade {blade} m is wider than the hole ({hole} m)")]
    BladeWiderThanHole {
        /// The key as written.
        key: String,
        /// The blade's diameter (m).
        blade: f64,
        /// The hole's diameter there (m).
        hole: f64,
    },
    /// `bend` on a case without a bend.
    #[error("{key}: the case has no bent sub or bent housing (give [[string]].bend)")]
    NoBend {
        /// The key as written.
        key: String,
    },
    /// `wob` on a case that gives the hook load.
    #[error("wob: the case gives the hook load; give operation.weight_on_bit to vary the WOB")]
    WobWithHookLoad,
    /// A contact-law key limited to hole sections the case does not have.
    #[error(
        "{key}: the case has no such hole section ({sections} [[hole]] sections, {cased} cased)"
    )]
    NoSection {
        /// The key as written.
        key: String,
        /// The case's hole sections.
        sections: usize,
        /// Of which cased.
        cased: usize,
    },
    /// A layout number beyond `ensemble.layouts`.
    #[error("layout {index}: the case has {count} in ensemble.layouts")]
    NoLayout {
        /// The layout asked for.
        index: usize,
        /// The case's layouts.
        count: usize,
    },
    /// The case rebuilt at the variant's depth or mode is not a valid case.
    #[error("depth/mode: {}: {}", .0.key, .0.message)]
    Rebuild(InputError),
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
            let key = Key::parse(h).map_err(|m| input_error(source, 1, h, m.to_string()))?;
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
                        .map_err(|m| input_error(source, line, &k.name, m.to_string()))?;
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
pub fn variants_from_grid(grid: &[(Key, Vec<Value>)]) -> Vec<Variant> {
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

/// The case the variants run on: `case` meshed again with nodes where the variants place
/// stabilizers (`stabK.from_bit`; [`Case::with_nodes_from_bit`]: a node within
/// [`crate::model::NODE_AT_GAP`] of each distance asked — twice that next to a component's
/// end —, none closer to another than that), so a stabilizer stands there, not at the case
/// mesh's nearest node: with 1 m BHA elements, placements drawn uniformly over 1–3 m from
/// the bit ran at 1.05, 1.8 and 2.8 m. Every variant runs on the one mesh, so the engine
/// takes them together. `None` where no variant places a stabilizer.
pub fn placed_case(case: &Case, variants: &[Variant]) -> Result<Option<Case>, InputError> {
    let from_bit: Vec<f64> = variants
        .iter()
        .flat_map(|v| &v.overrides)
        .filter_map(|(key, value)| match (key.param, value) {
            (Param::FromBit, Value::Number(x)) if *x > 0.0 && *x < case.bit_md => Some(*x),
            _ => None,
        })
        .collect();
    if from_bit.is_empty() {
        return Ok(None);
    }
    case.with_nodes_from_bit(&from_bit).map(Some)
}

/// The case's model with a variant's overrides applied. Layout moves come first (a
/// stabilizer's site goes to the node nearest its new distance from the bit; a pipe-body
/// site there, if any, takes the old node), then values, in column order.
pub fn apply(case: &Case, variant: &Variant) -> Result<Model, VariantError> {
    apply_with_sites(case, variant, &[])
}

/// As [`apply`], with pipe-body contact sites at the nodes `extra` too
/// ([`crate::profile::add_wall_sites`], where a solve found the variant's string beyond the
/// wall: [`crate::profile::solve_in_hole`]) before the overrides, which so reach them.
pub fn apply_with_sites(
    case: &Case,
    variant: &Variant,
    extra: &[usize],
) -> Result<Model, VariantError> {
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
    let variant = match variant.value_of(Param::Layout) {
        Some(Value::Layout(index)) => {
            let layouts = case
                .ensemble
                .as_ref()
                .map(|e| e.layouts.as_slice())
                .unwrap_or(&[]);
            let layout = layouts
                .get(index.wrapping_sub(1))
                .ok_or(VariantError::NoLayout {
                    index,
                    count: layouts.len(),
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
        _ => variant,
    };
    let mut model = case.model.clone();
    crate::profile::add_wall_sites(case, &mut model, extra);
    let stabs = model.stabilizer_sites();
    let stab = |k: usize| -> Result<usize, VariantError> {
        stabs
            .get(k - 1)
            .copied()
            .ok_or_else(|| VariantError::NoStabilizer {
                stabilizer: crate::model::stabilizer_name(k),
                count: stabs.len(),
            })
    };
    let hole_radius_at = |md: f64| 0.5 * case.hole_diameter_at(md);
    for (key, value) in &variant.overrides {
        let (Param::FromBit, Value::Number(value)) = (key.param, *value) else {
            continue;
        };
        let k = stab(key.stabilizer.unwrap_or(1))?;
        let string_length = case.bit_md - model.nodes[0].md;
        if !(value > 0.0 && value < string_length) {
            return Err(VariantError::OffString {
                key: key.name.clone(),
                from_bit: value,
                length: string_length,
            });
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
            .ok_or(VariantError::NoFreeNode)?;
        let old = model.sites[k].node;
        if node == old {
            continue;
        }
        if let Some(j) = (0..model.sites.len()).find(|&j| j != k && model.sites[j].node == node) {
            if model.sites[j].stabilizer {
                return Err(VariantError::TwoStabilizers {
                    key: key.name.clone(),
                    md: model.nodes[node].md,
                });
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
            return Err(VariantError::BladeWiderThanHole {
                key: key.name.clone(),
                blade: 2.0 * site.params.disk_radius,
                hole: 2.0 * site.hole_radius,
            });
        }
    }
    for (key, value) in &variant.overrides {
        let Value::Number(v) = *value else {
            continue;
        };
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
                    return Err(VariantError::NoBend {
                        key: key.name.clone(),
                    });
                }
                for b in &mut model.bends {
                    b.angle = v;
                }
            }
            Param::Rpm => model.rotation_speed = v,
            Param::Wob => {
                if let crate::model::TopBoundary::HookLoad(_) = model.top {
                    return Err(VariantError::WobWithHookLoad);
                }
                model.weight_on_bit = v;
            }
            Param::Tob => model.torque_on_bit = v,
            Param::Blade => {
                let site = &mut model.sites[sites[0]];
                site.params.disk_radius = 0.5 * v;
                site.params.clearance = site.hole_radius - 0.5 * v;
                if site.params.clearance < 0.0 {
                    return Err(VariantError::BladeWiderThanHole {
                        key: key.name.clone(),
                        blade: v,
                        hole: 2.0 * site.hole_radius,
                    });
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
) -> Result<Vec<usize>, VariantError> {
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
        return Err(VariantError::NoSection {
            key: key.to_string(),
            sections: case.hole.len(),
            cased: case.hole.iter().filter(|h| h.cased).count(),
        });
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
pub fn variant_case(case: &Case, variant: &Variant) -> Result<Option<Case>, VariantError> {
    use crate::case::Quantity;
    use toml::Spanned;
    let depth = variant.value_of(Param::Depth).map(Value::si);
    let mode = match variant.value_of(Param::Mode) {
        Some(Value::Mode(m)) => Some(m),
        _ => None,
    };
    if depth.is_none() && mode.is_none() {
        return Ok(None);
    }
    let rpm = variant.value_of(Param::Rpm).map(Value::si);
    case.rebuilt(|spec| {
        if let Some(d) = depth {
            let span = spec.well.total_md.span();
            spec.well.total_md = Spanned::new(span, Quantity::Si(d));
        }
        if let Some(m) = mode {
            let op = &mut spec.operation;
            // The variant chooses the operation: a tripping or sliding variant does not
            // rotate (the case's rpm belongs to its rotating variants), and a rotating,
            // reaming or back-reaming one rotates at the variant's rpm where it gives one
            // (applied again with the other overrides).
            if m.rotates() {
                if let Some(rpm) = rpm {
                    let span = op.rpm.as_ref().map_or(op.mode.span(), |q| q.span());
                    op.rpm = Some(Spanned::new(span, Quantity::Si(rpm)));
                }
            } else {
                op.rpm = None;
            }
            let span = op.mode.span();
            op.mode = Spanned::new(span, m);
        }
    })
    .map(Some)
    .map_err(VariantError::Rebuild)
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
) -> Result<Vec<Variant>, SamplingError> {
    if uncertain.is_empty() {
        return Err(SamplingError::NoInputs);
    }
    if n == 0 {
        return Err(SamplingError::NoSamples);
    }
    let mut u = if sobol_indices {
        if sampling != crate::uq::Sampling::Sobol {
            return Err(SamplingError::IndicesNeedSobol);
        }
        crate::uq::sensitivity::saltelli_design(n, uncertain.len(), seed)?
    } else {
        crate::uq::unit_samples(n, uncertain.len(), seed, sampling)?
    };
    if let Some(c) = correlation {
        if sampling == crate::uq::Sampling::Sobol {
            return Err(SamplingError::CorrelationBreaksSobol);
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
                    key.si(v)
                        .map(|v| (key.clone(), v))
                        .map_err(|_| SamplingError::OutOfRange {
                            sample: i,
                            key: key.name.clone(),
                            value: v,
                            dist: dist.to_string(),
                            range: key.range_words(),
                        })
                })
                .collect::<Result<Vec<_>, SamplingError>>()?;
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
        assert!((rpm.value("120 rpm").unwrap().si() - 4.0 * std::f64::consts::PI).abs() < 1e-12);
        assert!(rpm.value("2000 rpm").is_err());
        assert!(Key::parse("mu").unwrap().value("-0.1").is_err());
        assert!(Key::parse("wob").unwrap().value("20 kN").unwrap() == Value::Number(20_000.0));
        assert!(Key::parse("m").unwrap().value("20 kN").is_err());
    }

    #[test]
    fn grid_enumerates_every_combination() {
        let grid = vec![
            (
                Key::parse("mu").unwrap(),
                [0.1, 0.2].map(Value::Number).to_vec(),
            ),
            (
                Key::parse("wob").unwrap(),
                [1.0, 2.0, 3.0].map(Value::Number).to_vec(),
            ),
        ];
        let v = variants_from_grid(&grid);
        assert_eq!(v.len(), 6);
        assert_eq!(v[0].overrides[0].1, Value::Number(0.1));
        assert_eq!(v[0].overrides[1].1, Value::Number(1.0));
        assert_eq!(v[1].overrides[1].1, Value::Number(2.0));
        assert_eq!(v[5].overrides[0].1, Value::Number(0.2));
        assert_eq!(v[5].overrides[1].1, Value::Number(3.0));
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
        assert_eq!(ok[0].overrides[1].1, Value::Number(10_000.0));
    }
}
