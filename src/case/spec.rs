//! The case file's tables as read by serde (spans kept for messages), and the settings
//! types the readers produce.

use super::*;

/// A number (SI) or `"<number> <unit>"`.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum Quantity {
    /// SI number.
    Number(f64),
    /// Text with a unit.
    Text(String),
    /// A value already in SI set by the program, not read from a file (a variant's rotary
    /// speed, [`crate::ensemble::variant_case`]): no unit to read, no bare-number trap.
    #[serde(skip)]
    Si(f64),
}

pub(crate) type Q = Spanned<Quantity>;

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
    /// Mud density (the annulus, and inside the string unless `inside_density` is given).
    pub density: Q,
    /// Density of the fluid inside the string, when it differs from the annulus's (a heavy
    /// pill, a displacement; issue 26): buoyancy from the two columns.
    pub inside_density: Option<Q>,
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
    /// Tool joints' outer diameter (drill pipe, HWDP; issue 26): the joints are where the
    /// pipe touches the wall — the component is meshed a node per joint, each a contact site
    /// of this diameter (with `contact.sites = "all_nodes"`), the soft string's torque arm.
    pub tool_joint_od: Option<Q>,
    /// Length of a tool joint (box and pin; default 0.45 m): its steel adds to the weight.
    pub tool_joint_length: Option<Q>,
    /// Distance between tool joints (one joint of pipe; default 30 ft = 9.144 m).
    pub joint_spacing: Option<Q>,
    /// The tool joints' make-up torque (the connection's datasheet, e.g. NC50 6⅝ in × 3¼ in:
    /// ≈ 38,000 ft·lbf): the connection's torque limit, checked along the string and drawn
    /// on the tension–torque envelope and the torque broomstick. Needs `tool_joint_od` and a
    /// grade.
    pub tool_joint_makeup_torque: Option<Q>,
    /// Steel grade (`E75`, `X95`, `G105`, `S135`; [`crate::strength`]): the component's
    /// stresses are then checked against its yield.
    pub grade: Option<Spanned<String>>,
    /// Minimum yield strength instead of a grade.
    pub yield_strength: Option<Q>,
    /// Wear class: `new` (default), `premium` (80 % wall), `class2` (70 %).
    pub wear: Option<Spanned<String>>,
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
    /// `rotating`, `tripping_in`, `tripping_out`, `sliding`, `reaming`, `back_reaming`.
    pub mode: Spanned<crate::keys::Mode>,
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
    /// Directional tendency: the bit–rock model and the map of `holewall tendency`.
    pub tendency: Option<TendencySpec>,
    /// The rig's hoisting system: block weight and what the weight indicator reads.
    pub rig: Option<RigSpec>,
}

/// `[rig]`: block weight, reeving and the weight indicator ([`crate::rig`]).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigSpec {
    /// Travelling block, hook and top drive.
    pub block_weight: Option<Q>,
    /// Lines strung between crown and travelling block.
    pub lines: Option<Spanned<f64>>,
    /// Sheave efficiency.
    pub sheave_efficiency: Option<Spanned<f64>>,
    /// `dead_line` or `hook`.
    pub weight_indicator: Option<Spanned<String>>,
    /// Indicator zeroed with the block hanging.
    pub tared: Option<bool>,
}

/// `[tendency]`: the bit–rock model of the directional tendency
/// ([`crate::bha::tendency`]) and the map `holewall tendency` draws (issue 25).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TendencySpec {
    /// The bit's side-cutting index: lateral over axial drillability, 0…1 (default 0.05).
    pub side_cutting_index: Option<Spanned<f64>>,
    /// Formation anisotropy index (Lubinski & Woods), −0.5…0.5 (default 0: isotropic).
    pub formation_anisotropy: Option<Spanned<f64>>,
    /// Bedding dip from horizontal, 0…90° (default 0).
    pub dip: Option<Q>,
    /// Azimuth of the dip direction, 0…360° (default 0).
    pub dip_azimuth: Option<Q>,
    /// The map's distances of stab1 (nearest the bit) from the bit (rotary assemblies;
    /// default: 12 from 1 m to the BHA's length, at most 40 m).
    pub from_bit: Option<Spanned<Vec<Quantity>>>,
    /// The map's weights on bit (default: 0.25, 0.5, 1, 1.5 and 2 × the case's).
    pub weight_on_bit: Option<Spanned<Vec<Quantity>>>,
    /// The map's toolfaces from the high side (assemblies with a bend; default every 30°).
    pub toolface: Option<Spanned<Vec<Quantity>>>,
}

/// Checked `[tendency]` settings (defaults where the table or a key is absent).
#[derive(Clone, Debug, PartialEq)]
pub struct TendencyCase {
    /// The bit–rock model.
    pub settings: crate::bha::tendency::TendencySettings,
    /// stab1's distances from the bit for the map (m); empty: the default.
    pub from_bit: Vec<f64>,
    /// Weights on bit for the map (N); empty: the default.
    pub weight_on_bit: Vec<f64>,
    /// Toolfaces from the high side for the map (rad); empty: the default.
    pub toolface: Vec<f64>,
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
    pub grid: Vec<(crate::keys::Key, Vec<crate::keys::Value>)>,
    /// Variants with full time series.
    pub series: Vec<String>,
    /// Uncertain inputs: (key, distribution), in the order written (`[ensemble.uncertain]`).
    pub uncertain: Vec<(crate::keys::Key, crate::uq::Distribution)>,
    /// Their rank correlation matrix (identity unless `ensemble.correlation` is given).
    pub correlation: Option<nalgebra::DMatrix<f64>>,
    /// Candidate stabilizer layouts (`ensemble.layouts`), picked by the `layout` key.
    pub layouts: Vec<Vec<(crate::keys::Key, crate::keys::Value)>>,
}
