//! Case files (TOML): well, hole sections, mud, the string from the bit up, the operation,
//! contact and mesh settings. Numbers are SI; a string `"<number> <unit>"` is accepted where
//! engineers think in field units (`src/units.rs`). Every key is documented in
//! `cases/README.md`. Unknown keys and bad values are rejected naming the file, line, key
//! and allowed range.

use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::error::InputError;
use crate::model::{add_sites, mesh_string, ContactSettings, Model, TopBoundary, Tubular};
use crate::physics::contact::FrictionModel;
use crate::units::{parse_angle_deg, parse_quantity, Dimension};
use crate::well::{SurveyStation, WellPath};

/// A number (SI) or `"<number> <unit>"`.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum Quantity {
    /// SI number.
    Number(f64),
    /// Text with a unit.
    Text(String),
}

type Q = Spanned<Quantity>;

/// `[well]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WellSpec {
    /// `"vertical"`, `"build_and_hold"` or `"survey"`.
    pub profile: Spanned<String>,
    /// Total measured depth of the hole (bit depth).
    pub total_md: Q,
    /// Survey CSV (`md, inclination, azimuth`; MD in m unless the header says ft), relative
    /// to the case file.
    pub survey: Option<Spanned<String>>,
    /// Kick-off MD (build_and_hold).
    pub kickoff_md: Option<Q>,
    /// Build rate in degrees per 30 m (build_and_hold).
    pub build_rate_deg_per_30m: Option<Spanned<f64>>,
    /// Hold inclination in degrees (build_and_hold).
    pub hold_inclination: Option<Q>,
    /// Azimuth in degrees (build_and_hold).
    pub azimuth: Option<Q>,
    /// Largest dogleg severity a survey may hold, in degrees per 30 m (default
    /// [`crate::units::DOGLEG_LIMIT_DEG_PER_30M`]); raise it for a short-radius well.
    pub max_dogleg_deg_per_30m: Option<Spanned<f64>>,
}

/// `[[hole]]`: a hole section from the previous section's bottom (or the surface).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoleSpec {
    /// Bottom of the section (MD).
    pub bottom_md: Q,
    /// Hole (or casing inner) diameter.
    pub diameter: Q,
    /// Cased or open hole (for reports).
    #[serde(default)]
    pub cased: bool,
    /// Friction coefficient in the section.
    pub friction: Spanned<f64>,
}

/// `[mud]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MudSpec {
    /// Mud density.
    pub density: Q,
}

/// `[[string]]`: one component, listed from the bit up.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentSpec {
    /// `bit`, `collar`, `stabilizer`, `hwdp`, `drill_pipe`, or any name.
    pub kind: Spanned<String>,
    /// Length.
    pub length: Q,
    /// Outer diameter (body).
    pub od: Q,
    /// Inner diameter.
    pub id: Q,
    /// Stabilizer blade diameter (makes the component a contact site).
    pub blade_diameter: Option<Q>,
    /// Young's modulus (default 207 GPa).
    pub youngs_modulus: Option<Q>,
    /// Poisson ratio (default 0.3).
    pub poisson_ratio: Option<Spanned<f64>>,
    /// Steel density (default 7850 kg/m³).
    pub density: Option<Q>,
    /// Offset of the component's centre of mass from the pipe axis (dynamics: a mass
    /// imbalance turning with the string; default 0).
    pub mass_eccentricity: Option<Q>,
    /// The same as a mass imbalance of the whole component (kg·m, g·mm, oz·in): its mass
    /// times the offset.
    pub imbalance: Option<Q>,
    /// Bend angle of a bent sub or bent motor housing (degrees by default; 0 … 5°): a
    /// stress-free kink of the string in this component.
    pub bend: Option<Q>,
    /// Where the kink sits above the component's lower end (default: its middle).
    pub bend_from_bottom: Option<Q>,
    /// Direction of the bend, clockwise from the high side of the hole looking down-hole
    /// (degrees by default; default 0: the string below the kink points to the high side).
    /// In a vertical hole, from the string's reference mark.
    pub bend_toolface: Option<Q>,
}

/// `[operation]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperationSpec {
    /// `rotating`, `tripping_in`, `tripping_out`, `sliding`.
    pub mode: Spanned<String>,
    /// Weight on bit (default 0).
    pub weight_on_bit: Option<Q>,
    /// Torque on bit (default 0).
    pub torque_on_bit: Option<Q>,
    /// Rotation speed (default 0; `rotating` needs it).
    pub rpm: Option<Q>,
    /// Tripping speed (default 0.5 m/s for tripping modes).
    pub axial_speed: Option<Q>,
    /// Hook load: given instead of the weight on bit (the bit then rests on bottom and the
    /// weight on bit is what the hook load leaves).
    pub hook_load: Option<Q>,
}

/// `[contact]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// `stabilizers` (the paper) or `all_nodes` (deviated wells).
    pub sites: Option<Spanned<String>>,
    /// Wall stiffness (default 6e7 N/m, Table 1).
    pub wall_stiffness: Option<Q>,
    /// Spring exponent (default 1).
    pub exponent: Option<Spanned<f64>>,
    /// Wall damping (default 8e3 N·s/m, Table 1).
    pub damping: Option<Q>,
    /// Friction regularisation speed (default 1e-3 m/s).
    pub eps: Option<Q>,
    /// Soft-spring blend depth (default 1e-5 m).
    pub soft_blend: Option<Q>,
    /// `split` (default) or `coupled`.
    pub friction_model: Option<Spanned<String>>,
}

/// `[mesh]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Element length in the drill pipe (default 10 m).
    pub element_length: Option<Q>,
    /// Element length in the BHA (collars, stabilizers, HWDP, bit; default 1 m).
    pub bha_element_length: Option<Q>,
}

/// `[dynamics]`: the time integration (`holewall run`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicsSpec {
    /// Simulated time.
    pub duration: Q,
    /// Time step (default 1e-3 s).
    pub time_step: Option<Q>,
    /// Output interval (default 0.01 s).
    pub output_interval: Option<Q>,
    /// Rotary-table ramp time from rest to the operation's rpm (default 0: at speed).
    pub ramp_time: Option<Q>,
    /// Spectral radius at infinity ρ∞ ∈ [0, 1] (default 0.8).
    pub rho_inf: Option<Spanned<f64>>,
    /// Rayleigh damping `a0` (1/s, mass-proportional; default 0).
    pub rayleigh_mass: Option<Spanned<f64>>,
    /// Rayleigh damping `a1` (s, stiffness-proportional; default 0).
    pub rayleigh_stiffness: Option<Spanned<f64>>,
    /// Outputs to record: `bit_displacement`, `lateral`, `contact_forces`, `spin`,
    /// `surface_torque`, `axial_stress`, `energy`, `whirl` (default: all).
    pub outputs: Option<Vec<Spanned<String>>>,
    /// Mass matrix: `"lumped"` (default) or `"consistent"`.
    pub mass: Option<Spanned<String>>,
    /// Rate at which the hook (the clamped top) is lowered, e.g. `"30 m/h"` (default 0:
    /// hook fixed); ramped with the table.
    pub rop: Option<Q>,
    /// A lateral kick at the start: every BHA node (bit to the first drill pipe) moving at
    /// this speed towards its frame's first lateral axis (a whirl trigger; default 0).
    pub initial_lateral_velocity: Option<Q>,
    /// A lateral offset at the start: the BHA displaced from its static equilibrium as a
    /// half sine from the bit to the first drill pipe, this much at its middle, towards the
    /// frames' first lateral axis, and let go (a whirl trigger; default 0; at most the
    /// BHA's largest radial clearance).
    pub initial_lateral_offset: Option<Q>,
}

/// Checked `[dynamics]` settings.
#[derive(Clone, Debug)]
pub struct DynamicsSettings {
    /// Simulated time (s).
    pub duration: f64,
    /// Time step (s).
    pub time_step: f64,
    /// Output interval (s).
    pub output_interval: f64,
    /// Table ramp time (s).
    pub ramp_time: f64,
    /// ρ∞.
    pub rho_inf: f64,
    /// Rayleigh (a0, a1).
    pub rayleigh: (f64, f64),
    /// Outputs requested.
    pub outputs: Vec<String>,
    /// Mass matrix kind.
    pub mass: crate::physics::mass::MassKind,
    /// Hook lowering rate (m/s).
    pub rop: f64,
    /// Initial lateral speed of the BHA (m/s).
    pub initial_lateral_velocity: f64,
    /// Initial lateral offset of the BHA's middle (m).
    pub initial_lateral_offset: f64,
}

/// Every output `holewall run` can record.
pub const DYNAMIC_OUTPUTS: &[&str] = &[
    "bit_displacement",
    "lateral",
    "contact_forces",
    "spin",
    "surface_torque",
    "axial_stress",
    "energy",
    "whirl",
];

/// A whole case file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseSpec {
    /// Free text.
    pub title: Option<String>,
    /// Well path.
    pub well: WellSpec,
    /// Hole sections.
    pub hole: Vec<HoleSpec>,
    /// Mud.
    pub mud: MudSpec,
    /// String from the bit up.
    pub string: Vec<ComponentSpec>,
    /// Operation.
    pub operation: OperationSpec,
    /// Contact settings.
    pub contact: Option<ContactSpec>,
    /// Mesh settings.
    pub mesh: Option<MeshSpec>,
    /// Time integration (`holewall run`).
    pub dynamics: Option<DynamicsSpec>,
    /// Variants (`holewall ensemble`).
    pub ensemble: Option<EnsembleSpec>,
}

/// `[ensemble]`: what each variant runs, the grid of variants, the variants whose full
/// time series are written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnsembleSpec {
    /// `"static"` (default) or `"dynamic"` (needs `[dynamics]`).
    pub analysis: Option<Spanned<String>>,
    /// Key → values; every combination is a variant (see `src/ensemble.rs` for the keys).
    pub grid: Option<std::collections::BTreeMap<String, Spanned<Vec<Quantity>>>>,
    /// Names of the variants whose full time series are written (grid variants are named
    /// by their index).
    pub series: Option<Vec<String>>,
    /// Key → distribution of an uncertain input (`holewall ensemble --samples N`).
    pub uncertain: Option<std::collections::BTreeMap<String, Spanned<UncertainSpec>>>,
    /// Rank correlations between uncertain inputs: `[["mu", "wob", 0.5], …]`.
    pub correlation: Option<Spanned<Vec<(String, String, f64)>>>,
    /// Candidate stabilizer layouts, each `{ "stab1.from_bit" = "1.5 m", "stab2.from_bit" =
    /// "14 m", … }`: the `layout` key picks one (1-based).
    pub layouts: Option<Spanned<Vec<std::collections::BTreeMap<String, Quantity>>>>,
}

/// `[ensemble.uncertain]` entry: the distribution of one variant key, values in SI or
/// `"<number> <unit>"` as the key's other values.
///
/// ```toml
/// [ensemble.uncertain]
/// mu = { dist = "uniform", min = 0.2, max = 0.4 }
/// wob = { dist = "normal", mean = "75 kN", sd = "7 kN", min = "60 kN", max = "90 kN" }
/// k_e = { dist = "lognormal", median = 6e7, sigma = 0.5 }
/// rpm = { dist = "triangular", min = "60 rpm", mode = "90 rpm", max = "120 rpm" }
/// "stab2.from_bit" = { dist = "discrete", values = ["10 m", "15 m"], weights = [1, 2] }
/// ```
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UncertainSpec {
    /// `uniform`, `normal`, `lognormal`, `triangular` or `discrete`.
    pub dist: String,
    /// Lower bound (uniform, triangular; truncation of a normal).
    pub min: Option<Quantity>,
    /// Upper bound.
    pub max: Option<Quantity>,
    /// Mean (normal).
    pub mean: Option<Quantity>,
    /// Standard deviation (normal).
    pub sd: Option<Quantity>,
    /// Median (lognormal).
    pub median: Option<Quantity>,
    /// Standard deviation of the logarithm (lognormal), a pure number.
    pub sigma: Option<f64>,
    /// Peak (triangular).
    pub mode: Option<Quantity>,
    /// Values (discrete).
    pub values: Option<Vec<Quantity>>,
    /// Weights of the values (discrete; default equal).
    pub weights: Option<Vec<f64>>,
}

/// What an ensemble runs per variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Analysis {
    /// Static equilibrium.
    Static,
    /// The `[dynamics]` run from the static equilibrium.
    Dynamic,
}

/// Checked `[ensemble]`.
#[derive(Clone, Debug)]
pub struct EnsembleSettings {
    /// What each variant runs.
    pub analysis: Analysis,
    /// Grid (key, values), in the order written (the first key varies slowest).
    pub grid: Vec<(crate::keys::Key, Vec<f64>)>,
    /// Variants with full time series.
    pub series: Vec<String>,
    /// Uncertain inputs: (key, distribution), in the order written (`[ensemble.uncertain]`).
    pub uncertain: Vec<(crate::keys::Key, crate::uq::Distribution)>,
    /// Their rank correlation matrix (identity unless `ensemble.correlation` is given).
    pub correlation: Option<nalgebra::DMatrix<f64>>,
    /// Candidate stabilizer layouts (`ensemble.layouts`), picked by the `layout` key.
    pub layouts: Vec<Vec<(crate::keys::Key, f64)>>,
}

/// A case read and checked, ready to build a model.
#[derive(Clone, Debug)]
pub struct Case {
    /// Title.
    pub title: String,
    /// The file it came from.
    pub path: PathBuf,
    /// Model (mesh, sites, loads, boundary conditions).
    pub model: Model,
    /// Hole sections: (bottom MD, diameter, friction).
    pub hole: Vec<HoleSection>,
    /// Bit depth (m).
    pub bit_md: f64,
    /// Length of the BHA (m): the components from the bit up to the first drill pipe.
    pub bha_length: f64,
    /// Mud density (kg/m³).
    pub mud_density: f64,
    /// Steel density per element (kg/m³).
    pub element_density: Vec<f64>,
    /// `[dynamics]`, if given.
    pub dynamics: Option<DynamicsSettings>,
    /// `[ensemble]`, if given.
    pub ensemble: Option<EnsembleSettings>,
    /// What the case holds that is allowed but unusual (a sharp dogleg …): printed by every
    /// command that reads the case and written into its `summary.json`.
    pub warnings: Vec<String>,
}

/// A hole section (`[[hole]]`): from the previous section's bottom (or the surface) down to
/// `bottom_md`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoleSection {
    /// Bottom of the section (MD, m).
    pub bottom_md: f64,
    /// Hole or casing inner diameter (m).
    pub diameter: f64,
    /// Friction coefficient against the string.
    pub friction: f64,
}

/// The one lookup of a hole section: the section holding `md` (a section includes its
/// bottom); below the last section, the last. `hole` is a case's, never empty (the parser
/// requires a section).
pub fn hole_section_at(hole: &[HoleSection], md: f64) -> HoleSection {
    *hole
        .iter()
        .find(|h| md <= h.bottom_md + 1e-9)
        .or(hole.last())
        .expect("a case has at least one [[hole]] section")
}

impl DynamicsSettings {
    /// The integrator's options for these settings (time step, generalised-α from
    /// `rho_inf`, Rayleigh damping, ramp, mass, rate of penetration): one mapping for the
    /// `run` command, the ensemble and the studies.
    pub fn integrator_options(&self) -> crate::solve::dynamics::DynamicOptions {
        crate::solve::dynamics::DynamicOptions {
            dt: self.time_step,
            alpha: crate::solve::dynamics::AlphaParams::chung_hulbert(self.rho_inf),
            rayleigh: self.rayleigh,
            ramp_time: self.ramp_time,
            mass: self.mass,
            rop: self.rop,
            ..Default::default()
        }
    }
}

impl Case {
    /// The hole section at `md` ([`hole_section_at`]).
    pub fn hole_at(&self, md: f64) -> HoleSection {
        hole_section_at(&self.hole, md)
    }

    /// The start of a dynamic run of `model` from its static equilibrium `q`: the BHA's
    /// initial lateral offset (`[dynamics].initial_lateral_offset`: a half sine from the bit
    /// to the first drill pipe, towards each node frame's first lateral axis) applied to
    /// `q`, and the initial velocities (6 per node) of the BHA's lateral kick
    /// (`initial_lateral_velocity`, the same direction, uniform), `None` without one. Every
    /// dynamic run (`holewall run`, the ensemble's CPU runs) starts here.
    pub fn dynamic_start(
        &self,
        model: &crate::model::Model,
        mut q: crate::solve::statics::StaticState,
    ) -> (crate::solve::statics::StaticState, Option<Vec<f64>>) {
        let Some(d) = self.dynamics.as_ref() else {
            return (q, None);
        };
        let n = model.nodes.len();
        let bit_md = model.nodes.last().map_or(self.bit_md, |nd| nd.md);
        let bha = self.bha_length.max(1e-9);
        let top = bit_md - bha;
        // Not the clamped top, nor the bit when it is held laterally.
        let last = if model.bit_lateral_fixed { n - 1 } else { n };
        let lateral = |i: usize| -> [f64; 3] {
            let f = &model.nodes[i].frame0;
            [f[0][1], f[1][1], f[2][1]]
        };
        let in_bha = |i: usize| i > 0 && i < last && model.nodes[i].md >= top - 1e-9;
        if d.initial_lateral_offset != 0.0 {
            for i in (0..n).filter(|&i| in_bha(i)) {
                let s = (bit_md - model.nodes[i].md) / bha;
                let w = d.initial_lateral_offset * (std::f64::consts::PI * s).sin();
                for (x, a) in q.x[i].iter_mut().zip(lateral(i)) {
                    *x += w * a;
                }
            }
        }
        if d.initial_lateral_velocity == 0.0 {
            return (q, None);
        }
        let mut v = vec![0.0; 6 * n];
        for i in (0..n).filter(|&i| in_bha(i)) {
            let a = lateral(i);
            for k in 0..3 {
                v[6 * i + k] = d.initial_lateral_velocity * a[k];
            }
        }
        (q, Some(v))
    }

    /// The hole diameter at `md` (m).
    pub fn hole_diameter_at(&self, md: f64) -> f64 {
        self.hole_at(md).diameter
    }

    /// The soft-string profile of the case's operation, with each hole section's friction.
    pub fn soft_string(&self) -> crate::physics::soft_string::SoftStringProfile {
        use crate::physics::soft_string::{soft_string_with, Operation};
        let model = &self.model;
        let friction_at = |md: f64| self.hole_at(md).friction;
        soft_string_with(
            model,
            &Operation {
                axial_speed: model.axial_speed,
                rotation_speed: model.rotation_speed,
                weight_on_bit: model.weight_on_bit,
                torque_on_bit: model.torque_on_bit,
                friction: friction_at(0.0),
            },
            &friction_at,
        )
    }
}

struct Ctx<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Ctx<'_> {
    fn line(&self, offset: usize) -> usize {
        self.text[..offset.min(self.text.len())]
            .matches('\n')
            .count()
            + 1
    }

    fn err(
        &self,
        span: std::ops::Range<usize>,
        key: &str,
        message: impl Into<String>,
    ) -> InputError {
        InputError {
            source_name: self.path.display().to_string(),
            line: self.line(span.start),
            key: key.into(),
            message: message.into(),
        }
    }

    fn quantity(
        &self,
        q: &Q,
        key: &str,
        dim: Dimension,
        ok: impl Fn(f64) -> bool,
        range: &str,
    ) -> Result<f64, InputError> {
        let v = match q.get_ref() {
            Quantity::Number(x) if x.is_finite() => {
                if let Some(m) = crate::units::bare_number_trap(dim, *x) {
                    return Err(self.err(q.span(), key, m));
                }
                *x
            }
            Quantity::Number(x) => {
                return Err(self.err(
                    q.span(),
                    key,
                    format!("{x} is not finite; allowed: {range}"),
                ))
            }
            Quantity::Text(t) => {
                let v = parse_quantity(t, dim)
                    .map_err(|e| self.err(q.span(), key, format!("{e}; allowed: {range}")))?;
                if t.trim().parse::<f64>().is_ok() {
                    if let Some(m) = crate::units::bare_number_trap(dim, v) {
                        return Err(self.err(q.span(), key, m));
                    }
                }
                v
            }
        };
        if ok(v) {
            Ok(v)
        } else {
            Err(self.err(
                q.span(),
                key,
                format!("{v} {} is out of range; allowed: {range}", dim.si()),
            ))
        }
    }

    fn angle(
        &self,
        q: &Q,
        key: &str,
        ok: impl Fn(f64) -> bool,
        range: &str,
    ) -> Result<f64, InputError> {
        let v = match q.get_ref() {
            Quantity::Number(x) => *x,
            Quantity::Text(t) => parse_angle_deg(t)
                .map_err(|e| self.err(q.span(), key, format!("{e}; allowed: {range}")))?,
        };
        if v.is_finite() && ok(v) {
            Ok(v)
        } else {
            Err(self.err(
                q.span(),
                key,
                format!("{v}° is out of range; allowed: {range}"),
            ))
        }
    }

    fn number(
        &self,
        q: &Spanned<f64>,
        key: &str,
        ok: impl Fn(f64) -> bool,
        range: &str,
    ) -> Result<f64, InputError> {
        let v = *q.get_ref();
        if v.is_finite() && ok(v) {
            Ok(v)
        } else {
            Err(self.err(
                q.span(),
                key,
                format!("{v} is out of range; allowed: {range}"),
            ))
        }
    }
}

fn read_survey(
    path: &Path,
    ctx: &Ctx,
    span: std::ops::Range<usize>,
) -> Result<Vec<(SurveyStation, usize)>, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        ctx.err(
            span.clone(),
            "well.survey",
            format!("{}: {e}", path.display()),
        )
    })?;
    survey_from_text(&path.display().to_string(), &text)
}

/// The stations of a survey CSV (`md, inclination, azimuth`, an optional header naming
/// `ft` for feet) with their 1-based lines; `source` names it in messages.
pub fn survey_from_text(
    source: &str,
    text: &str,
) -> Result<Vec<(SurveyStation, usize)>, InputError> {
    let mut out = Vec::new();
    let mut md_factor = 1.0;
    for (k, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if line.trim().is_empty() {
            continue;
        }
        let bad = |msg: String| InputError {
            source_name: source.to_string(),
            line: k + 1,
            key: "survey".into(),
            message: msg,
        };
        if fields.len() != 3 {
            return Err(bad(format!(
                "expected 3 columns (md, inclination, azimuth), got {}",
                fields.len()
            )));
        }
        if fields[0].parse::<f64>().is_err() {
            if k == 0 {
                if fields[0].to_ascii_lowercase().contains("ft") {
                    md_factor = 0.3048;
                }
                continue;
            }
            return Err(bad(format!("md {:?} is not a number", fields[0])));
        }
        let parse = |s: &str, what: &str| {
            s.parse::<f64>()
                .map_err(|_| bad(format!("{what} {s:?} is not a number")))
        };
        out.push((
            SurveyStation {
                md: parse(fields[0], "md")? * md_factor,
                inclination_deg: parse(fields[1], "inclination")?,
                azimuth_deg: {
                    let a = parse(fields[2], "azimuth")?;
                    if !(0.0..=360.0).contains(&a) {
                        return Err(bad(format!(
                            "azimuth {}° is outside 0 … 360° (did you mean {}°?)",
                            crate::units::show(a),
                            crate::units::show(a.rem_euclid(360.0))
                        )));
                    }
                    a
                },
            },
            k + 1,
        ));
    }
    Ok(out)
}

/// The most nodes a case's mesh may have (a 20 km string in 1 m elements).
pub const MAX_NODES: usize = 20_001;

/// Reads, validates and meshes a case file.
pub fn load_case(path: &Path) -> Result<Case, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError {
        source_name: path.display().to_string(),
        line: 0,
        key: "-".into(),
        message: e.to_string(),
    })?;
    parse_case(path, &text)
}

/// Parses a case from its text (`path` names it in messages and anchors relative paths).
pub fn parse_case(path: &Path, text: &str) -> Result<Case, InputError> {
    let ctx = Ctx { path, text };
    let spec: CaseSpec = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| ctx.line(s.start)).unwrap_or(0);
        // The key the error sits on: the text before `=` on its line, qualified by the
        // table header above it (`operation.rpm`), where there is one.
        let key = e
            .span()
            .and_then(|sp| {
                let start = text[..sp.start.min(text.len())]
                    .rfind('\n')
                    .map_or(0, |k| k + 1);
                let here = text[start..].lines().next()?;
                let name = here.split_once('=')?.0.trim().trim_matches('"');
                let table = text[..start]
                    .lines()
                    .rev()
                    .find(|l| l.trim_start().starts_with('['))
                    .map(|l| l.trim().trim_matches(|c| c == '[' || c == ']').to_string());
                Some(match table {
                    Some(t) if !t.is_empty() => format!("{t}.{name}"),
                    _ => name.to_string(),
                })
            })
            .unwrap_or_else(|| "-".into());
        InputError {
            source_name: path.display().to_string(),
            line,
            key,
            message: {
                let m = e.message();
                // A number written as text: say how to write it.
                if m.starts_with("invalid type: string") && m.contains("expected f64") {
                    format!("{m}: write the number without quotes (friction = 0.2), or with a unit inside them (\"0.2 m\") where the key has one")
                } else {
                    m.to_string()
                }
            },
        }
    })?;
    let pos = |x: f64| x > 0.0;
    let bit_md = ctx.quantity(
        &spec.well.total_md,
        "well.total_md",
        Dimension::Length,
        |x| x > 0.0 && x <= 20_000.0,
        "0 < total_md ≤ 20 km",
    )?;
    let mut warnings: Vec<String> = Vec::new();
    let mut survey_read: Option<(PathBuf, Vec<(SurveyStation, usize)>)> = None;
    let well = match spec.well.profile.get_ref().as_str() {
        "vertical" => WellPath::vertical(bit_md),
        "build_and_hold" => {
            let need = |q: &Option<Q>, key: &str| {
                q.clone().ok_or_else(|| {
                    ctx.err(
                        spec.well.profile.span(),
                        key,
                        "required by profile = \"build_and_hold\"",
                    )
                })
            };
            let kop = ctx.quantity(
                &need(&spec.well.kickoff_md, "well.kickoff_md")?,
                "well.kickoff_md",
                Dimension::Length,
                |x| (0.0..bit_md).contains(&x),
                "0 ≤ kickoff_md < total_md",
            )?;
            let rate = spec.well.build_rate_deg_per_30m.as_ref().ok_or_else(|| {
                ctx.err(
                    spec.well.profile.span(),
                    "well.build_rate_deg_per_30m",
                    "required by profile = \"build_and_hold\"",
                )
            })?;
            let rate = ctx.number(
                rate,
                "well.build_rate_deg_per_30m",
                |x| x > 0.0 && x <= 30.0,
                "0 < rate ≤ 30 °/30 m",
            )?;
            let inc = ctx.angle(
                &need(&spec.well.hold_inclination, "well.hold_inclination")?,
                "well.hold_inclination",
                |x| (0.0..=180.0).contains(&x),
                "0° … 180°",
            )?;
            let azi = ctx.angle(
                &need(&spec.well.azimuth, "well.azimuth")?,
                "well.azimuth",
                |x| (0.0..=360.0).contains(&x),
                "0° … 360°",
            )?;
            WellPath::build_and_hold(kop, rate, inc, azi, bit_md)
                .map_err(|e| ctx.err(spec.well.profile.span(), "well", e.to_string()))?
        }
        "survey" => {
            let file = spec.well.survey.as_ref().ok_or_else(|| {
                ctx.err(
                    spec.well.profile.span(),
                    "well.survey",
                    "required by profile = \"survey\"",
                )
            })?;
            let survey_path = path.parent().unwrap_or(Path::new(".")).join(file.get_ref());
            let read = read_survey(&survey_path, &ctx, file.span())?;
            let survey_err = |line: usize, message: String| InputError {
                source_name: survey_path.display().to_string(),
                line,
                key: "survey".into(),
                message,
            };
            let stations: Vec<SurveyStation> = read.iter().map(|(s, _)| *s).collect();
            let well_path =
                WellPath::from_survey(&stations, [0.0; 3]).map_err(|e| match e.station() {
                    Some(i) => survey_err(read[i].1, e.detail()),
                    None => survey_err(0, e.to_string()),
                })?;
            // The survey must cover the hole: from the surface (MD 0) to the string's depth.
            if let Some((first, line)) = read.first() {
                if first.md != 0.0 {
                    return Err(survey_err(
                        *line,
                        format!(
                            "the first station is at MD {} m; a survey starts at the surface \
                             (MD 0 m): add a station \"0, 0, 0\" (or the tie-in) above it",
                            crate::units::show(first.md)
                        ),
                    ));
                }
            }
            if let Some((last, line)) = read.last() {
                if read.len() >= 2 && last.md < bit_md - 1e-6 {
                    return Err(survey_err(
                        *line,
                        format!(
                            "the last station is at MD {} m, above the bit at {b} m \
                             (well.total_md); a survey must reach the bit: add stations \
                             down to {b} m",
                            crate::units::show(last.md),
                            b = crate::units::show(bit_md),
                        ),
                    ));
                }
            }
            survey_read = Some((survey_path, read));
            well_path
        }
        other => {
            return Err(ctx.err(
                spec.well.profile.span(),
                "well.profile",
                format!("unknown profile {other:?}; allowed: vertical, build_and_hold, survey"),
            ))
        }
    };
    // Below a survey's last station the path goes on along its last tangent.

    // Hole sections.
    let mut hole = Vec::new();
    let mut previous = 0.0;
    for h in &spec.hole {
        let bottom = ctx.quantity(
            &h.bottom_md,
            "hole.bottom_md",
            Dimension::Length,
            |x| x > previous,
            &format!("> the previous section's bottom ({previous} m)"),
        )?;
        let d = ctx.quantity(
            &h.diameter,
            "hole.diameter",
            Dimension::Length,
            |x| x > 0.0 && x < 2.0,
            "0 < diameter < 2 m",
        )?;
        let mu = ctx.number(
            &h.friction,
            "hole.friction",
            |x| (0.0..=2.0).contains(&x),
            "0 ≤ friction ≤ 2",
        )?;
        hole.push(HoleSection {
            bottom_md: bottom,
            diameter: d,
            friction: mu,
        });
        previous = bottom;
    }
    if hole.is_empty() {
        return Err(InputError {
            source_name: path.display().to_string(),
            line: 1,
            key: "hole".into(),
            message: "at least one [[hole]] section is required".into(),
        });
    }
    if previous + 1e-9 < bit_md {
        let last = spec.hole.last().map(|h| h.bottom_md.span()).unwrap_or(0..0);
        return Err(ctx.err(
            last,
            "hole.bottom_md",
            format!(
                "the last hole section ends at {} m, above the bit at {} m",
                crate::units::show(previous),
                crate::units::show(bit_md)
            ),
        ));
    }
    let hole_at = |md: f64| hole_section_at(&hole, md);

    if let Some((survey_path, read)) = &survey_read {
        let deepest = hole.iter().map(|h| h.bottom_md).fold(bit_md, f64::max);
        let limit = match &spec.well.max_dogleg_deg_per_30m {
            Some(q) => ctx.number(
                q,
                "well.max_dogleg_deg_per_30m",
                |x| x > 0.0 && x <= 300.0,
                "0 < max_dogleg ≤ 300 °/30 m",
            )?,
            None => crate::units::DOGLEG_LIMIT_DEG_PER_30M,
        };
        warnings.extend(survey_plausibility(
            &survey_path.display().to_string(),
            read,
            deepest,
            limit,
        )?);
    }
    let mud = ctx.quantity(
        &spec.mud.density,
        "mud.density",
        Dimension::Density,
        |x| x >= 0.0,
        "0 (a dry string) or 0.5 … 3.0 sg",
    )?;
    let written = match spec.mud.density.get_ref() {
        Quantity::Text(t) => t.clone(),
        Quantity::Number(x) => crate::units::show(*x),
    };
    if let Some(m) = crate::units::fluid_density_trap(mud, &written) {
        return Err(ctx.err(spec.mud.density.span(), "mud.density", m));
    }
    let mesh = spec.mesh.clone();
    let el_pipe = match mesh.as_ref().and_then(|m| m.element_length.clone()) {
        Some(q) => ctx.quantity(
            &q,
            "mesh.element_length",
            Dimension::Length,
            |x| x > 0.0 && x <= 100.0,
            "0 < length ≤ 100 m",
        )?,
        None => 10.0,
    };
    let el_bha = match mesh.as_ref().and_then(|m| m.bha_element_length.clone()) {
        Some(q) => ctx.quantity(
            &q,
            "mesh.bha_element_length",
            Dimension::Length,
            |x| x > 0.0 && x <= 100.0,
            "0 < length ≤ 100 m",
        )?,
        None => 1.0,
    };

    // String, from the bit up.
    if spec.string.is_empty() {
        return Err(InputError {
            source_name: path.display().to_string(),
            line: 1,
            key: "string".into(),
            message: "at least one [[string]] component is required".into(),
        });
    }
    let mut tubulars = Vec::new();
    let mut blades = Vec::new();
    let mut eccentricities: Vec<f64> = Vec::new();
    let mut bends = Vec::new();
    for c in &spec.string {
        let kind = c.kind.get_ref().clone();
        let length = ctx.quantity(&c.length, "string.length", Dimension::Length, pos, "> 0")?;
        let od = ctx.quantity(
            &c.od,
            "string.od",
            Dimension::Length,
            |x| x > 0.0 && x < 1.0,
            "0 < od < 1 m",
        )?;
        let id = ctx.quantity(
            &c.id,
            "string.id",
            Dimension::Length,
            |x| (0.0..od).contains(&x),
            &format!("0 ≤ id < od ({od} m)"),
        )?;
        let e = match &c.youngs_modulus {
            Some(q) => ctx.quantity(
                q,
                "string.youngs_modulus",
                Dimension::Pressure,
                |x| x > 1e9 && x < 1e12,
                "1 GPa … 1000 GPa",
            )?,
            None => 207e9,
        };
        let nu = match &c.poisson_ratio {
            Some(q) => ctx.number(
                q,
                "string.poisson_ratio",
                |x| (0.0..0.5).contains(&x),
                "0 ≤ ν < 0.5",
            )?,
            None => 0.3,
        };
        let rho = match &c.density {
            Some(q) => ctx.quantity(
                q,
                "string.density",
                Dimension::Density,
                |x| x > 1000.0 && x < 20000.0,
                "1000 … 20000 kg/m3",
            )?,
            None => 7850.0,
        };
        let eccentricity = match (&c.mass_eccentricity, &c.imbalance) {
            (Some(_), Some(q)) => {
                return Err(ctx.err(
                    q.span(),
                    "string.imbalance",
                    "give mass_eccentricity or imbalance, not both",
                ))
            }
            (Some(q), None) => ctx.quantity(
                q,
                "string.mass_eccentricity",
                Dimension::Length,
                |x| (0.0..=0.5 * od).contains(&x),
                &format!("0 ≤ offset ≤ od/2 ({} m)", crate::units::show(0.5 * od)),
            )?,
            (None, Some(q)) => {
                let mass = rho * std::f64::consts::FRAC_PI_4 * (od * od - id * id) * length;
                ctx.quantity(
                    q,
                    "string.imbalance",
                    Dimension::MassLength,
                    |x| (0.0..=0.5 * od * mass).contains(&x),
                    &format!(
                        "0 ≤ imbalance ≤ the component's mass × od/2 ({} kg·m)",
                        crate::units::show(0.5 * od * mass)
                    ),
                )? / mass
            }
            (None, None) => 0.0,
        };
        eccentricities.push(eccentricity);
        let bend = match &c.bend {
            Some(q) => {
                let angle = ctx.angle(q, "string.bend", |x| (0.0..=5.0).contains(&x), "0 … 5°")?;
                let at = match &c.bend_from_bottom {
                    Some(b) => ctx.quantity(
                        b,
                        "string.bend_from_bottom",
                        Dimension::Length,
                        |x| x > 0.0 && x < length,
                        &format!(
                            "0 < bend_from_bottom < the component's length ({} m)",
                            crate::units::show(length)
                        ),
                    )?,
                    None => 0.5 * length,
                };
                let toolface = match &c.bend_toolface {
                    Some(t) => ctx.angle(
                        t,
                        "string.bend_toolface",
                        |x| (-360.0..=360.0).contains(&x),
                        "-360 … 360°",
                    )?,
                    None => 0.0,
                };
                let above_bit = tubulars.iter().map(|t: &Tubular| t.length).sum::<f64>() + at;
                Some((
                    above_bit,
                    angle.to_radians(),
                    toolface.to_radians(),
                    q.span(),
                ))
            }
            None => {
                for (k, v) in [
                    ("string.bend_from_bottom", &c.bend_from_bottom),
                    ("string.bend_toolface", &c.bend_toolface),
                ] {
                    if let Some(v) = v {
                        return Err(ctx.err(v.span(), k, "needs string.bend (the bend angle)"));
                    }
                }
                None
            }
        };
        bends.extend(bend);
        let blade = match &c.blade_diameter {
            Some(q) => {
                let md_here = bit_md - tubulars.iter().map(|t: &Tubular| t.length).sum::<f64>();
                let hole_d = hole_at(md_here).diameter;
                Some(ctx.quantity(q, "string.blade_diameter", Dimension::Length, |x| x >= od && x <= hole_d, &format!("od ({} m) ≤ blade diameter ≤ hole diameter ({} m): the disk must fit the hole", crate::units::show(od), crate::units::show(hole_d)))?)
            }
            None => None,
        };
        if od > hole_at(bit_md - tubulars.iter().map(|t: &Tubular| t.length).sum::<f64>()).diameter
        {
            return Err(ctx.err(
                c.od.span(),
                "string.od",
                format!("{} m is wider than the hole", crate::units::show(od)),
            ));
        }
        let bha = kind != "drill_pipe";
        blades.push(blade);
        tubulars.push(Tubular {
            name: kind,
            length,
            outer_diameter: od,
            inner_diameter: id,
            youngs_modulus: e,
            poisson_ratio: nu,
            density: rho,
            element_length: if bha { el_bha } else { el_pipe },
        });
    }
    let string_length: f64 = tubulars.iter().map(|t| t.length).sum();
    if string_length + 1e-9 < bit_md {
        let last = spec.string.last().map(|c| c.length.span()).unwrap_or(0..0);
        return Err(ctx.err(last, "string.length", format!("the string is {} m long, shorter than the bit depth {} m: it must reach the surface", crate::units::show(string_length), crate::units::show(bit_md))));
    }

    // The mesh's size, before it is built: memory and time grow with the nodes.
    {
        let mut remaining = bit_md;
        let mut nodes = 1.0f64;
        for t in &tubulars {
            let covered = t.length.min(remaining).max(0.0);
            nodes += (covered / t.element_length).ceil();
            remaining -= covered;
        }
        if nodes > MAX_NODES as f64 {
            let (span, key) = match mesh.as_ref().and_then(|m| m.element_length.clone()) {
                Some(q) => (q.span(), "mesh.element_length"),
                None => (spec.well.total_md.span(), "well.total_md"),
            };
            return Err(ctx.err(
                span,
                key,
                format!(
                    "the mesh would have {nodes:.0} nodes, more than the {MAX_NODES} allowed \
                     (memory and run time grow with them): lengthen mesh.element_length \
                     (drill pipe) or mesh.bha_element_length"
                ),
            ));
        }
    }

    // Operation.
    let op = &spec.operation;
    let wob = op
        .weight_on_bit
        .as_ref()
        .map(|q| {
            ctx.quantity(
                q,
                "operation.weight_on_bit",
                Dimension::Force,
                |x| x >= 0.0,
                "≥ 0",
            )
        })
        .transpose()?
        .unwrap_or(0.0);
    let tob = op
        .torque_on_bit
        .as_ref()
        .map(|q| {
            ctx.quantity(
                q,
                "operation.torque_on_bit",
                Dimension::Torque,
                |x| x >= 0.0,
                "≥ 0",
            )
        })
        .transpose()?
        .unwrap_or(0.0);
    let rpm = op
        .rpm
        .as_ref()
        .map(|q| {
            ctx.quantity(
                q,
                "operation.rpm",
                Dimension::AngularSpeed,
                |x| (0.0..100.0).contains(&x),
                "0 … 955 rpm",
            )
        })
        .transpose()?
        .unwrap_or(0.0);
    let speed = op
        .axial_speed
        .as_ref()
        .map(|q| {
            ctx.quantity(
                q,
                "operation.axial_speed",
                Dimension::Speed,
                |x| (0.0..10.0).contains(&x),
                "0 ≤ speed < 10 m/s",
            )
        })
        .transpose()?
        .unwrap_or(0.5);
    let hook = op
        .hook_load
        .as_ref()
        .map(|q| {
            ctx.quantity(
                q,
                "operation.hook_load",
                Dimension::Force,
                |x| x > 0.0,
                "> 0",
            )
        })
        .transpose()?;
    if let (Some(_), Some(w)) = (hook, &op.weight_on_bit) {
        return Err(ctx.err(
            w.span(),
            "operation.weight_on_bit",
            "give either weight_on_bit (top clamped) or hook_load (bit on bottom), not both",
        ));
    }
    match (op.mode.get_ref().as_str(), &op.rpm) {
        ("rotating", None) => {
            return Err(ctx.err(
                op.mode.span(),
                "operation.rpm",
                "mode = \"rotating\" needs the rotary speed: add rpm = \"90 rpm\" (or the \
                 value you rotate at) to [operation]",
            ))
        }
        ("rotating", Some(q)) if rpm == 0.0 => {
            return Err(ctx.err(
                q.span(),
                "operation.rpm",
                "mode = \"rotating\" at 0 rpm has no rotation, hence no torque: give the \
                 rotary speed (> 0), or mode = \"sliding\" / \"tripping_in\" / \"tripping_out\"",
            ))
        }
        ("tripping_in" | "tripping_out" | "sliding", Some(q)) if rpm != 0.0 => {
            return Err(ctx.err(
                q.span(),
                "operation.rpm",
                format!(
                    "mode = {:?} does not rotate the string, so this rpm would be ignored: \
                     remove rpm, or use mode = \"rotating\"",
                    op.mode.get_ref()
                ),
            ))
        }
        _ => {}
    }
    let (axial_speed, rotation_speed) = match op.mode.get_ref().as_str() {
        "rotating" => (0.0, rpm),
        "tripping_in" => (speed, 0.0),
        "tripping_out" => (-speed, 0.0),
        "sliding" => (speed, 0.0),
        other => {
            return Err(ctx.err(
                op.mode.span(),
                "operation.mode",
                format!(
                    "unknown mode {other:?}; allowed: rotating, tripping_in, tripping_out, sliding"
                ),
            ))
        }
    };

    // Contact.
    let cs = spec.contact.clone();
    let q_or = |q: Option<Q>,
                key: &str,
                dim: Dimension,
                default: f64,
                ok: &dyn Fn(f64) -> bool,
                range: &str|
     -> Result<f64, InputError> {
        match q {
            Some(q) => ctx.quantity(&q, key, dim, ok, range),
            None => Ok(default),
        }
    };
    let settings = ContactSettings {
        wall_stiffness: q_or(
            cs.as_ref().and_then(|c| c.wall_stiffness.clone()),
            "contact.wall_stiffness",
            Dimension::Stiffness,
            6e7,
            &|x| x > 0.0 && x <= 1e12,
            "0 < k_e ≤ 1e12 N/m",
        )?,
        spring_exponent: match cs.as_ref().and_then(|c| c.exponent.clone()) {
            Some(q) => ctx.number(&q, "contact.exponent", |x| x > 0.0 && x <= 3.0, "0 < m ≤ 3")?,
            None => 1.0,
        },
        wall_damping: q_or(
            cs.as_ref().and_then(|c| c.damping.clone()),
            "contact.damping",
            Dimension::Damping,
            8e3,
            &|x| x >= 0.0,
            "≥ 0",
        )?,
        eps: q_or(
            cs.as_ref().and_then(|c| c.eps.clone()),
            "contact.eps",
            Dimension::Speed,
            1e-3,
            &|x| x > 0.0,
            "> 0",
        )?,
        soft_blend: q_or(
            cs.as_ref().and_then(|c| c.soft_blend.clone()),
            "contact.soft_blend",
            Dimension::Length,
            1e-5,
            &|x| x > 0.0,
            "> 0",
        )?,
    };
    let friction = match cs.as_ref().and_then(|c| c.friction_model.clone()) {
        None => FrictionModel::Split,
        Some(s) => match s.get_ref().as_str() {
            "split" => FrictionModel::Split,
            "coupled" => FrictionModel::Coupled,
            other => {
                return Err(ctx.err(
                    s.span(),
                    "contact.friction_model",
                    format!("unknown model {other:?}; allowed: split, coupled"),
                ))
            }
        },
    };
    let all_nodes = match cs.as_ref().and_then(|c| c.sites.clone()) {
        None => false,
        Some(s) => match s.get_ref().as_str() {
            "stabilizers" => false,
            "all_nodes" => true,
            other => {
                return Err(ctx.err(
                    s.span(),
                    "contact.sites",
                    format!("unknown value {other:?}; allowed: stabilizers, all_nodes"),
                ))
            }
        },
    };

    let (nodes, elements) = mesh_string(&well, &tubulars, bit_md, mud);
    let n = nodes.len();
    let mut model = Model {
        nodes,
        elements,
        sites: vec![],
        friction,
        weight_on_bit: wob,
        torque_on_bit: tob,
        axial_speed,
        rotation_speed,
        top: match hook {
            Some(h) => TopBoundary::HookLoad(h),
            None => TopBoundary::Clamped,
        },
        bit_lateral_fixed: true,
        point_loads: vec![],
        unbalance: vec![],
        bends: vec![],
    };
    // Stabilizers: a site at the node nearest each stabilizer's middle.
    let mut stab_nodes = Vec::new();
    let mut bottom = bit_md;
    for (t, blade) in tubulars.iter().zip(&blades) {
        if let Some(b) = blade {
            let mid = bottom - 0.5 * t.length;
            let node = (0..n)
                .min_by(|&a, &c| {
                    (model.nodes[a].md - mid)
                        .abs()
                        .total_cmp(&(model.nodes[c].md - mid).abs())
                })
                .unwrap_or(n - 1);
            stab_nodes.push((node, 0.5 * b));
        }
        bottom -= t.length;
    }
    for (node, radius) in &stab_nodes {
        add_sites(
            &mut model,
            &[*node],
            |md| 0.5 * hole_at(md).diameter,
            |_| *radius,
            |md| hole_at(md).friction,
            &settings,
            true,
        );
    }
    if all_nodes {
        let others: Vec<usize> = (1..n)
            .filter(|i| !stab_nodes.iter().any(|(s, _)| s == i))
            .collect();
        let radii: Vec<f64> = (0..n).map(|i| model.pipe_radius_at(i)).collect();
        add_sites(
            &mut model,
            &others,
            |md| 0.5 * hole_at(md).diameter,
            |i| radii[i],
            |md| hole_at(md).friction,
            &settings,
            false,
        );
    }
    model.sites.sort_by_key(|s| s.node);
    // Kinks: at the node nearest each, not the top or the bit.
    for (above_bit, angle, toolface, span) in bends {
        let md = bit_md - above_bit;
        let node = (1..n - 1)
            .min_by(|&a, &c| {
                (model.nodes[a].md - md)
                    .abs()
                    .total_cmp(&(model.nodes[c].md - md).abs())
            })
            .ok_or_else(|| ctx.err(span.clone(), "string.bend", "the mesh has no free node"))?;
        if model.bends.iter().any(|b| b.node == node) {
            return Err(ctx.err(
                span,
                "string.bend",
                format!(
                    "two bends at the node at MD {} m: refine mesh.bha_element_length",
                    crate::units::show(model.nodes[node].md)
                ),
            ));
        }
        let toolface = model.toolface_from_high_side(node, toolface);
        model.bends.push(crate::model::Bend {
            node,
            angle,
            toolface,
        });
    }
    // Mass imbalance: each component's centre-of-mass offset.
    if eccentricities.iter().any(|e| *e > 0.0) {
        model.unbalance = model
            .unbalance_from(&|e| tubulars[model.elements[e].component].density, &|e| {
                eccentricities[model.elements[e].component]
            });
    }
    let element_density = model
        .elements
        .iter()
        .map(|e| tubulars[e.component].density)
        .collect();
    let dynamics = match &spec.dynamics {
        None => None,
        Some(d) => Some(dynamics_settings(&ctx, d)?),
    };
    let ensemble = match &spec.ensemble {
        None => None,
        Some(e) => Some(ensemble_settings(&ctx, e, dynamics.is_some())?),
    };
    let bha_length = tubulars
        .iter()
        .take_while(|t| t.name != "drill_pipe")
        .map(|t| t.length)
        .sum::<f64>()
        .min(bit_md);
    if let (Some(d), Some(spec_d)) = (&dynamics, &spec.dynamics) {
        if let Some(q) = &spec_d.initial_lateral_offset {
            let bha_top = bit_md - bha_length;
            let widest = model
                .nodes
                .iter()
                .enumerate()
                .filter(|(_, nd)| nd.md >= bha_top - 1e-9)
                .map(|(i, nd)| 0.5 * hole_at(nd.md).diameter - model.pipe_radius_at(i))
                .fold(0.0f64, f64::max);
            if d.initial_lateral_offset > widest {
                return Err(ctx.err(
                    q.span(),
                    "dynamics.initial_lateral_offset",
                    format!(
                        "{} m is wider than the BHA's largest radial clearance ({} m): the \
                         string would start inside the wall",
                        crate::units::show(d.initial_lateral_offset),
                        crate::units::show(widest)
                    ),
                ));
            }
        }
    }
    Ok(Case {
        ensemble,
        title: spec.title.unwrap_or_default(),
        path: path.to_path_buf(),
        model,
        hole,
        bit_md,
        bha_length,
        mud_density: mud,
        element_density,
        dynamics,
        warnings,
    })
}

/// The plausibility of a survey's stations (issue 23), one policy with
/// [`crate::units::bare_number_trap`]'s: an error where a unit mix-up or a typo is far
/// likelier than the well, a warning where the well is merely unusual.
/// - the last station past `SURVEY_PAST_CASE_FACTOR` × the deepest MD the case uses
///   (`deepest`: the bit, the hole sections): MD in feet read as metres, most likely;
/// - a dogleg severity between two stations above `limit` °/30 m: refused (a typo in a
///   station); above [`crate::units::DOGLEG_WARNING_DEG_PER_30M`]: a warning.
pub fn survey_plausibility(
    source: &str,
    read: &[(SurveyStation, usize)],
    deepest: f64,
    limit: f64,
) -> Result<Vec<String>, InputError> {
    use crate::units::show;
    let err = |line: usize, message: String| InputError {
        source_name: source.to_string(),
        line,
        key: "survey".into(),
        message,
    };
    let mut warnings = Vec::new();
    if let Some((last, line)) = read.last() {
        let ratio = last.md / deepest;
        if ratio > crate::units::SURVEY_PAST_CASE_FACTOR {
            let feet = if (3.0..=3.6).contains(&ratio) {
                " — that is the ratio of a foot to a metre: is the survey's MD in feet? \
                 Name the unit in the header (`md_ft, inclination_deg, azimuth_deg`)"
                    .to_string()
            } else {
                String::new()
            };
            return Err(err(
                *line,
                format!(
                    "the survey runs to MD {} m, {:.2}× the deepest MD of the case ({} m: \
                     well.total_md and the [[hole]] sections){feet}; a survey longer than \
                     the hole on purpose: end it within {}× of it",
                    show(last.md),
                    ratio,
                    show(deepest),
                    crate::units::SURVEY_PAST_CASE_FACTOR
                ),
            ));
        }
    }
    for w in read.windows(2) {
        let ((a, _), (b, line)) = (&w[0], &w[1]);
        let (i1, i2) = (
            a.inclination_deg.to_radians(),
            b.inclination_deg.to_radians(),
        );
        let da = (b.azimuth_deg - a.azimuth_deg).to_radians();
        let cos = (i1.cos() * i2.cos() + i1.sin() * i2.sin() * da.cos()).clamp(-1.0, 1.0);
        let dogleg = cos.acos().to_degrees();
        let dls = dogleg / (b.md - a.md) * 30.0;
        let what = format!(
            "a dogleg of {:.1}° over {} m (MD {} → {} m, inclination {} → {}°, azimuth {} → \
             {}°) is {:.1}°/30 m",
            dogleg,
            show(b.md - a.md),
            show(a.md),
            show(b.md),
            show(a.inclination_deg),
            show(b.inclination_deg),
            show(a.azimuth_deg),
            show(b.azimuth_deg),
            dls
        );
        if dls > limit {
            return Err(err(
                *line,
                format!(
                    "{what}, above the limit of {}°/30 m: a typo in a station? (for a \
                     short-radius well, raise well.max_dogleg_deg_per_30m)",
                    show(limit)
                ),
            ));
        }
        if dls > crate::units::DOGLEG_WARNING_DEG_PER_30M {
            warnings.push(format!(
                "{source}:{line}: {what}, sharper than long- and medium-radius builds \
                 ({}°/30 m): check the station",
                show(crate::units::DOGLEG_WARNING_DEG_PER_30M)
            ));
        }
    }
    Ok(warnings)
}

fn ensemble_settings(
    ctx: &Ctx,
    e: &EnsembleSpec,
    has_dynamics: bool,
) -> Result<EnsembleSettings, InputError> {
    let analysis = match &e.analysis {
        None => Analysis::Static,
        Some(a) => match a.get_ref().as_str() {
            "static" => Analysis::Static,
            "dynamic" if has_dynamics => Analysis::Dynamic,
            "dynamic" => {
                return Err(ctx.err(
                    a.span(),
                    "ensemble.analysis",
                    "\"dynamic\" needs a [dynamics] table",
                ))
            }
            other => {
                return Err(ctx.err(
                    a.span(),
                    "ensemble.analysis",
                    format!("unknown analysis {other:?}; allowed: static, dynamic"),
                ))
            }
        },
    };
    let mut grid = Vec::new();
    // In the order written (the first key varies slowest), not the map's alphabetical one.
    let mut written: Vec<_> = e.grid.iter().flatten().collect();
    written.sort_by_key(|(_, v)| v.span().start);
    for (name, values) in written {
        let key_name = format!("ensemble.grid.{name}");
        let key =
            crate::keys::Key::parse(name).map_err(|m| ctx.err(values.span(), &key_name, m))?;
        if values.get_ref().is_empty() {
            return Err(ctx.err(values.span(), &key_name, "no values"));
        }
        let mut list = Vec::new();
        for q in values.get_ref() {
            let text = match q {
                Quantity::Number(x) => x.to_string(),
                Quantity::Text(t) => t.clone(),
            };
            list.push(
                key.value(&text)
                    .map_err(|m| ctx.err(values.span(), &key_name, m))?,
            );
        }
        grid.push((key, list));
    }
    let mut uncertain = Vec::new();
    // In the order written: input k takes the sampler's dimension k.
    let mut written: Vec<_> = e.uncertain.iter().flatten().collect();
    written.sort_by_key(|(_, v)| v.span().start);
    for (name, spec) in written {
        let key_name = format!("ensemble.uncertain.{name}");
        let err = |m: String| ctx.err(spec.span(), &key_name, m);
        let key = crate::keys::Key::parse(name).map_err(err)?;
        uncertain.push((
            key.clone(),
            uncertain_distribution(&key, spec.get_ref()).map_err(err)?,
        ));
    }
    let correlation = match &e.correlation {
        None => None,
        Some(pairs) => {
            let err = |m: String| ctx.err(pairs.span(), "ensemble.correlation", m);
            let d = uncertain.len();
            let mut c = nalgebra::DMatrix::identity(d, d);
            let index = |name: &str| {
                uncertain
                    .iter()
                    .position(|(k, _)| k.name == name)
                    .ok_or_else(|| err(format!("{name:?} is not in [ensemble.uncertain]")))
            };
            for (a, b, rho) in pairs.get_ref() {
                let (i, j) = (index(a)?, index(b)?);
                if i == j {
                    return Err(err(format!("{a:?} with itself")));
                }
                if !(rho.is_finite() && rho.abs() < 1.0) {
                    return Err(err(format!("{a} with {b}: {rho} is outside (−1, 1)")));
                }
                c[(i, j)] = *rho;
                c[(j, i)] = *rho;
            }
            if c.clone().cholesky().is_none() {
                return Err(err(
                    "the correlations are inconsistent (the matrix is not positive definite)"
                        .into(),
                ));
            }
            Some(c)
        }
    };
    let mut layouts = Vec::new();
    if let Some(list) = &e.layouts {
        for (n, layout) in list.get_ref().iter().enumerate() {
            let key_name = format!("ensemble.layouts[{}]", n + 1);
            let err = |m: String| ctx.err(list.span(), &key_name, m);
            let mut set = Vec::new();
            for (name, q) in layout {
                let key = crate::keys::Key::parse(name).map_err(err)?;
                if !matches!(
                    key.param,
                    crate::keys::Param::FromBit | crate::keys::Param::Blade
                ) {
                    return Err(err(format!(
                        "{name}: a layout sets stabK.from_bit and stabK.blade only"
                    )));
                }
                let text = match q {
                    Quantity::Number(x) => x.to_string(),
                    Quantity::Text(t) => t.clone(),
                };
                set.push((
                    key.clone(),
                    key.value(&text).map_err(|m| err(format!("{name}: {m}")))?,
                ));
            }
            if set.is_empty() {
                return Err(err("an empty layout".into()));
            }
            layouts.push(set);
        }
    }
    Ok(EnsembleSettings {
        analysis,
        grid,
        series: e.series.clone().unwrap_or_default(),
        uncertain,
        correlation,
        layouts,
    })
}

/// The distribution of `[ensemble.uncertain]` entry `u` of key `key`; every value given is
/// parsed and range-checked as the key's own values.
fn uncertain_distribution(
    key: &crate::keys::Key,
    u: &UncertainSpec,
) -> Result<crate::uq::Distribution, String> {
    use crate::uq::Distribution;
    let text = |q: &Quantity| match q {
        Quantity::Number(x) => x.to_string(),
        Quantity::Text(t) => t.clone(),
    };
    let value = |q: &Option<Quantity>, field: &str| -> Result<Option<f64>, String> {
        q.as_ref()
            .map(|q| key.value(&text(q)).map_err(|m| format!("{field}: {m}")))
            .transpose()
    };
    let need = |x: Option<f64>, field: &str| x.ok_or_else(|| format!("{} needs {field}", u.dist));
    let (min, max) = (value(&u.min, "min")?, value(&u.max, "max")?);
    let unused = |fields: &[(&str, bool)]| -> Result<(), String> {
        match fields.iter().find(|(_, given)| *given) {
            Some((f, _)) => Err(format!("{} takes no {f}", u.dist)),
            None => Ok(()),
        }
    };
    let d = match u.dist.as_str() {
        "uniform" => {
            unused(&[("mean", u.mean.is_some()), ("sd", u.sd.is_some()), ("median", u.median.is_some()), ("sigma", u.sigma.is_some()), ("mode", u.mode.is_some()), ("values", u.values.is_some()), ("weights", u.weights.is_some())])?;
            Distribution::Uniform {
                min: need(min, "min")?,
                max: need(max, "max")?,
            }
        }
        "normal" => {
            unused(&[("median", u.median.is_some()), ("sigma", u.sigma.is_some()), ("mode", u.mode.is_some()), ("values", u.values.is_some()), ("weights", u.weights.is_some())])?;
            let sd = match &u.sd {
                // A spread: the key's unit, but not its range (σ of a friction factor
                // may be 0.05, of a WOB 7 kN).
                Some(q) => {
                    let t = text(q);
                    match t.trim().parse::<f64>() {
                        Ok(x) => x,
                        Err(_) => key.value(&t).map_err(|m| format!("sd: {m}"))?,
                    }
                }
                None => return Err("normal needs sd".into()),
            };
            Distribution::Normal {
                mean: need(value(&u.mean, "mean")?, "mean")?,
                sd,
                min: min.unwrap_or(f64::NEG_INFINITY),
                max: max.unwrap_or(f64::INFINITY),
            }
        }
        "lognormal" => {
            unused(&[("min", u.min.is_some()), ("max", u.max.is_some()), ("mean", u.mean.is_some()), ("sd", u.sd.is_some()), ("mode", u.mode.is_some()), ("values", u.values.is_some()), ("weights", u.weights.is_some())])?;
            Distribution::LogNormal {
                median: need(value(&u.median, "median")?, "median")?,
                sigma: u.sigma.ok_or("lognormal needs sigma (of the logarithm)")?,
            }
        }
        "triangular" => {
            unused(&[("mean", u.mean.is_some()), ("sd", u.sd.is_some()), ("median", u.median.is_some()), ("sigma", u.sigma.is_some()), ("values", u.values.is_some()), ("weights", u.weights.is_some())])?;
            Distribution::Triangular {
                min: need(min, "min")?,
                mode: need(value(&u.mode, "mode")?, "mode")?,
                max: need(max, "max")?,
            }
        }
        "discrete" => {
            unused(&[("min", u.min.is_some()), ("max", u.max.is_some()), ("mean", u.mean.is_some()), ("sd", u.sd.is_some()), ("median", u.median.is_some()), ("sigma", u.sigma.is_some()), ("mode", u.mode.is_some())])?;
            let values = u
                .values
                .as_ref()
                .ok_or("discrete needs values")?
                .iter()
                .map(|q| key.value(&text(q)))
                .collect::<Result<Vec<f64>, String>>()
                .map_err(|m| format!("values: {m}"))?;
            let weights = u.weights.clone().unwrap_or_else(|| vec![1.0; values.len()]);
            Distribution::Discrete { values, weights }
        }
        other => {
            return Err(format!(
                "unknown distribution {other:?}; allowed: uniform, normal, lognormal, triangular, discrete"
            ))
        }
    };
    d.check()?;
    Ok(d)
}

fn dynamics_settings(ctx: &Ctx, d: &DynamicsSpec) -> Result<DynamicsSettings, InputError> {
    let duration = ctx.quantity(
        &d.duration,
        "dynamics.duration",
        Dimension::Time,
        |x| x > 0.0 && x <= 1e5,
        "0 < duration ≤ 1e5 s",
    )?;
    let opt = |q: &Option<Q>,
               key: &str,
               default: f64,
               ok: &dyn Fn(f64) -> bool,
               range: &str|
     -> Result<f64, InputError> {
        match q {
            Some(q) => ctx.quantity(q, key, Dimension::Time, ok, range),
            None => Ok(default),
        }
    };
    let time_step = opt(
        &d.time_step,
        "dynamics.time_step",
        1e-3,
        &|x| x > 0.0 && x <= duration,
        "0 < time_step ≤ duration",
    )?;
    let output_interval = opt(
        &d.output_interval,
        "dynamics.output_interval",
        1e-2_f64.max(time_step),
        &|x| x >= time_step && x <= duration,
        "time_step ≤ interval ≤ duration",
    )?;
    let ramp_time = opt(
        &d.ramp_time,
        "dynamics.ramp_time",
        0.0,
        &|x| x >= 0.0,
        "≥ 0",
    )?;
    let rho_inf = match &d.rho_inf {
        Some(q) => ctx.number(
            q,
            "dynamics.rho_inf",
            |x| (0.0..=1.0).contains(&x),
            "0 ≤ ρ∞ ≤ 1",
        )?,
        None => 0.8,
    };
    let a0 = match &d.rayleigh_mass {
        Some(q) => ctx.number(q, "dynamics.rayleigh_mass", |x| x >= 0.0, "≥ 0 (1/s)")?,
        None => 0.0,
    };
    let a1 = match &d.rayleigh_stiffness {
        Some(q) => ctx.number(q, "dynamics.rayleigh_stiffness", |x| x >= 0.0, "≥ 0 (s)")?,
        None => 0.0,
    };
    let outputs = match &d.outputs {
        None => DYNAMIC_OUTPUTS.iter().map(|s| s.to_string()).collect(),
        Some(list) => {
            let mut out = Vec::new();
            for o in list {
                if !DYNAMIC_OUTPUTS.contains(&o.get_ref().as_str()) {
                    return Err(ctx.err(
                        o.span(),
                        "dynamics.outputs",
                        format!(
                            "unknown output {:?}; allowed: {}",
                            o.get_ref(),
                            DYNAMIC_OUTPUTS.join(", ")
                        ),
                    ));
                }
                out.push(o.get_ref().clone());
            }
            out
        }
    };
    let mass = match &d.mass {
        None => crate::physics::mass::MassKind::Lumped,
        Some(m) => match m.get_ref().as_str() {
            "lumped" => crate::physics::mass::MassKind::Lumped,
            "consistent" => crate::physics::mass::MassKind::Consistent,
            other => {
                return Err(ctx.err(
                    m.span(),
                    "dynamics.mass",
                    format!("unknown mass {other:?}; allowed: lumped, consistent"),
                ))
            }
        },
    };
    let rop = match &d.rop {
        Some(q) => ctx.quantity(
            q,
            "dynamics.rop",
            Dimension::Speed,
            |x| (0.0..=0.1).contains(&x),
            "0 ≤ rop ≤ 0.1 m/s (360 m/h)",
        )?,
        None => 0.0,
    };
    let initial_lateral_velocity = match &d.initial_lateral_velocity {
        Some(q) => ctx.quantity(
            q,
            "dynamics.initial_lateral_velocity",
            Dimension::Speed,
            |x| (0.0..=10.0).contains(&x),
            "0 ≤ speed ≤ 10 m/s",
        )?,
        None => 0.0,
    };
    let initial_lateral_offset = match &d.initial_lateral_offset {
        Some(q) => ctx.quantity(
            q,
            "dynamics.initial_lateral_offset",
            Dimension::Length,
            |x| (0.0..=0.5).contains(&x),
            "0 ≤ offset ≤ 0.5 m (and within the BHA's clearance)",
        )?,
        None => 0.0,
    };
    Ok(DynamicsSettings {
        duration,
        time_step,
        output_interval,
        ramp_time,
        rho_inf,
        rayleigh: (a0, a1),
        outputs,
        mass,
        rop,
        initial_lateral_velocity,
        initial_lateral_offset,
    })
}
