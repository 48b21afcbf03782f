//! Case files (TOML): well, hole sections, mud, the string from the bit up, the operation,
//! contact and mesh settings. Numbers are SI; a string `"<number> <unit>"` is accepted where
//! engineers think in field units (`src/units.rs`). Every key is documented in
//! `cases/README.md`. Unknown keys and bad values are rejected naming the file, line, key
//! and allowed range.

use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::error::InputError;
use crate::model::{add_sites, ContactSettings, Model, TopBoundary, Tubular};
use crate::physics::contact::FrictionModel;
use crate::units::{parse_angle_deg, parse_quantity, Dimension};
use crate::well::{SurveyStation, WellPath};

mod ctx;
mod settings;
mod spec;
mod survey;
mod tables;

use ctx::Ctx;
use settings::{dynamics_settings, ensemble_settings, rig_settings, tendency_settings};
pub use spec::*;
use survey::read_well;
pub use survey::{survey_from_text, survey_plausibility};
use tables::{read_contact, read_hole, read_operation, read_string, Operation, StringRead};

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
    /// Mud density (kg/m³): the annulus's.
    pub mud_density: f64,
    /// Density of the fluid inside the string (kg/m³; `mud.inside_density`, else the
    /// annulus's).
    pub mud_inside_density: f64,
    /// Steel density per element (kg/m³).
    pub element_density: Vec<f64>,
    /// `[dynamics]`, if given.
    pub dynamics: Option<DynamicsSettings>,
    /// The `[contact]` wall law (stiffness, exponent, damping, ε): that of every site the
    /// case makes, and of those a static solve adds where the string meets the wall
    /// ([`crate::profile::solve_in_hole`]).
    pub contact: ContactSettings,
    /// `[ensemble]`, if given.
    pub ensemble: Option<EnsembleSettings>,
    /// `[tendency]`, with its defaults when absent.
    pub tendency: TendencyCase,
    /// Per string component (from the bit up, as `Element::component`): its grade and wear
    /// class, where the case gives one ([`crate::strength`]).
    pub strength: Vec<Option<crate::strength::PipeStrength>>,
    /// `[rig]`: block weight and the weight indicator ([`crate::rig`]), if given.
    pub rig: Option<crate::rig::Rig>,
    /// What the case holds that is allowed but unusual (a sharp dogleg …): printed by every
    /// command that reads the case and written into its `summary.json`.
    pub warnings: Vec<String>,
    /// What it was built from: a variant's case is built again from an edited copy
    /// ([`Case::rebuilt`]).
    pub source: std::sync::Arc<CaseSource>,
}

/// What a case is built from: its text (for the lines of messages), its tables as read and
/// its survey's stations with their lines (read once from the survey file).
#[derive(Clone, Debug)]
pub struct CaseSource {
    /// The case file's text.
    pub text: String,
    /// Its tables as read.
    pub spec: CaseSpec,
    /// The survey's path and stations (with their lines), where the well is a survey.
    pub survey: Option<(PathBuf, Vec<(SurveyStation, usize)>)>,
    /// Distances from the bit (m) at which the mesh is to have a node: where an ensemble
    /// places stabilizers ([`Case::with_nodes_from_bit`]); none from a case file.
    pub nodes_from_bit: Vec<f64>,
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
    /// Cased (`[[hole]] cased = true`) or open hole.
    pub cased: bool,
}

/// The one lookup of a hole section: the section holding `md` (a section includes its
/// bottom); below the last section, the last. `hole` is a case's, never empty (the parser
/// requires a section).
pub fn hole_section_at(hole: &[HoleSection], md: f64) -> HoleSection {
    hole[hole_section_index(hole, md)]
}

/// The index in `hole` of the section holding `md` ([`hole_section_at`]).
pub fn hole_section_index(hole: &[HoleSection], md: f64) -> usize {
    hole.iter()
        .position(|h| md <= h.bottom_md + 1e-9)
        .unwrap_or(hole.len().saturating_sub(1))
}

impl DynamicsSettings {
    /// `base` with these `[dynamics]` settings (time step, ρ∞, Rayleigh damping, ramp, mass,
    /// rate of penetration): one mapping for the `run` command, the ensemble and the
    /// studies.
    pub fn apply_to(
        &self,
        base: crate::solve::settings::Settings,
    ) -> crate::solve::settings::Settings {
        crate::solve::settings::Settings {
            time_step: self.time_step,
            rho_inf: self.rho_inf,
            rayleigh: self.rayleigh,
            ramp_time: self.ramp_time,
            mass: self.mass,
            rop: self.rop,
            ..base
        }
    }

    /// The integrator's options for these settings over the defaults
    /// ([`DynamicsSettings::apply_to`]).
    pub fn integrator_options(&self) -> crate::solve::dynamics::DynamicOptions {
        self.apply_to(crate::solve::settings::Settings::default())
            .dynamics()
    }
}

impl Case {
    /// The solver settings of this case: the defaults ([`crate::solve::settings::Settings`])
    /// with its `[dynamics]` table where it has one. Every run of the case (the commands, the
    /// ensemble on the CPU and the GPU) takes its static and dynamic options from here.
    pub fn settings(&self) -> crate::solve::settings::Settings {
        let base = crate::solve::settings::Settings::default();
        self.dynamics.as_ref().map_or(base, |d| d.apply_to(base))
    }

    /// The hole section at `md` ([`hole_section_at`]).
    pub fn hole_at(&self, md: f64) -> HoleSection {
        hole_section_at(&self.hole, md)
    }

    /// The start of a dynamic run of `model` from its static equilibrium `q`: the BHA's
    /// initial lateral offset (`[dynamics].initial_lateral_offset`: a half sine from the bit
    /// to the first drill pipe, towards each node frame's first lateral axis) applied to
    /// `q` (scaled down where it would start a node beyond its wall: [`Case::offset_scale`]),
    /// and the initial velocities (6 per node) of the BHA's lateral kick
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
        let lateral = |i: usize| -> [f64; 3] {
            let f = &model.nodes[i].frame0;
            [f[0][1], f[1][1], f[2][1]]
        };
        let in_bha = |i: usize| self.bha_half_sine(model, i).is_some();
        if d.initial_lateral_offset != 0.0 {
            let scale = self.offset_scale(model, &q);
            for i in 0..n {
                let Some(shape) = self.bha_half_sine(model, i) else {
                    continue;
                };
                let w = scale * d.initial_lateral_offset * shape;
                for (x, a) in q.u[i].iter_mut().zip(lateral(i)) {
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

    /// The half sine of the initial offset and kick at node `i`, `sin(π s)` with `s` its
    /// height above the bit over the BHA's length; `None` outside the BHA, at the clamped
    /// top, and at the bit when it is held laterally (nodes the start does not move).
    fn bha_half_sine(&self, model: &crate::model::Model, i: usize) -> Option<f64> {
        let n = model.nodes.len();
        let bit_md = model.nodes.last().map_or(self.bit_md, |nd| nd.md);
        let bha = self.bha_length.max(1e-9);
        let last = if model.bit_lateral_fixed { n - 1 } else { n };
        let md = model.nodes[i].md;
        (i > 0 && i < last && md >= bit_md - bha - 1e-9).then(|| {
            let s = (bit_md - md) / bha;
            (std::f64::consts::PI * s).sin()
        })
    }

    /// The share (−1…1) of `[dynamics].initial_lateral_offset` that [`Case::dynamic_start`]
    /// applies to the static equilibrium `q` of `model`: all of it unless it would put a
    /// node with a contact site beyond its wall (past its clearance, or deeper than it lies
    /// in `q`) — in an inclined hole the BHA rests on the low side, and an offset towards
    /// the wall would start the run millimetres deep in a stiff wall (the dynamic corpus's
    /// offset starts rang at up to 4 MN and cut their first steps). The half sine is kept,
    /// scaled down to the largest that stays in the hole; where the other way round (away
    /// from the wall it rests on) goes further, that way (a negative share): the BHA lifted
    /// off its wall and let go. 1 without an offset.
    pub fn offset_scale(
        &self,
        model: &crate::model::Model,
        q: &crate::solve::statics::StaticState,
    ) -> f64 {
        let forward = self.offset_room(model, q, 1.0);
        if forward >= 1.0 {
            return 1.0;
        }
        let back = self.offset_room(model, q, -1.0);
        if back > forward {
            -back
        } else {
            forward
        }
    }

    /// The largest share (0–1) of the offset applied with `sign` that keeps every node with
    /// a site in the hole ([`Case::offset_scale`]).
    fn offset_room(
        &self,
        model: &crate::model::Model,
        q: &crate::solve::statics::StaticState,
        sign: f64,
    ) -> f64 {
        let Some(d) = self.dynamics.as_ref() else {
            return 1.0;
        };
        let mut scale = 1.0f64;
        for site in &model.sites {
            let i = site.node;
            let nd = &model.nodes[i];
            let Some(shape) = self.bha_half_sine(model, i) else {
                continue;
            };
            let w = sign * d.initial_lateral_offset * shape;
            let f = &nd.frame0;
            // Lateral position p in the hole and the offset b (⊥ the hole axis).
            let dx: [f64; 3] = q.u[i];
            let along: f64 = (0..3).map(|k| dx[k] * nd.hole_axis[k]).sum();
            let p: [f64; 3] = std::array::from_fn(|k| dx[k] - along * nd.hole_axis[k]);
            let b: [f64; 3] = std::array::from_fn(|k| w * f[k][1]);
            let (pp, pb, bb) = (
                (0..3).map(|k| p[k] * p[k]).sum::<f64>(),
                (0..3).map(|k| p[k] * b[k]).sum::<f64>(),
                (0..3).map(|k| b[k] * b[k]).sum::<f64>(),
            );
            if bb == 0.0 {
                continue;
            }
            // The largest λ with |p + λ b| ≤ max(clearance, |p|).
            let c2 = site.params.clearance.powi(2).max(pp);
            let root = (pb * pb - bb * (pp - c2)).max(0.0).sqrt();
            scale = scale.min(((-pb + root) / bb).max(0.0));
        }
        scale.clamp(0.0, 1.0)
    }

    /// The hole diameter at `md` (m).
    pub fn hole_diameter_at(&self, md: f64) -> f64 {
        self.hole_at(md).diameter
    }

    /// The soft-string profile of the case's operation, with each hole section's friction.
    pub fn soft_string(&self) -> crate::solve::soft_string::SoftStringProfile {
        self.soft_string_of(&self.model)
    }

    /// As [`Case::soft_string`], for `model` (the case's, or a variant's of it: its speeds
    /// and bit loads) in the case's hole.
    pub fn soft_string_of(&self, model: &Model) -> crate::solve::soft_string::SoftStringProfile {
        let friction_at = |md: f64| self.hole_at(md).friction;
        crate::solve::soft_string::soft_string_with(model, &self.operation_of(model), &friction_at)
    }

    /// The case's operation for the soft string (speeds and bit loads; the friction of the
    /// hole at the surface, each section's where it has one).
    pub fn operation(&self) -> crate::solve::soft_string::Operation {
        self.operation_of(&self.model)
    }

    /// As [`Case::operation`], with the speeds and bit loads of `model`.
    pub fn operation_of(&self, model: &Model) -> crate::solve::soft_string::Operation {
        crate::solve::soft_string::Operation {
            axial_speed: model.axial_speed,
            rotation_speed: model.rotation_speed,
            weight_on_bit: model.weight_on_bit,
            torque_on_bit: model.torque_on_bit,
            friction: self.hole_at(0.0).friction,
        }
    }
}

/// The most nodes a case's mesh may have (a 20 km string in 1 m elements).
pub const MAX_NODES: usize = 20_001;

/// Reads, validates and meshes a case file.
pub fn load_case(path: &Path) -> Result<Case, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError {
        source_name: path.display().to_string(),
        line: 0,
        key: "-".into(),
        message: format!("cannot read the case file: {e}"),
    })?;
    parse_case(path, &text)
}

/// Parses a case from its text (`path` names it in messages and anchors relative paths).
pub fn parse_case(path: &Path, text: &str) -> Result<Case, InputError> {
    let spec = read_spec(path, text)?;
    build_case(
        path,
        CaseSource {
            text: text.to_string(),
            spec,
            survey: None,
            nodes_from_bit: Vec::new(),
        },
    )
}

impl Case {
    /// This case built again from its tables edited by `edit` (a variant's depth or mode):
    /// every input checked as written, the survey's stations as read before (the files are
    /// not read again).
    pub fn rebuilt(&self, edit: impl FnOnce(&mut CaseSpec)) -> Result<Case, InputError> {
        let mut source = (*self.source).clone();
        edit(&mut source.spec);
        build_case(&self.path, source)
    }

    /// This case meshed again with a node at each distance from the bit in `from_bit` (m;
    /// [`crate::model::NODE_AT_GAP`] apart at least, each more than the gap inside a
    /// component), besides the ones it had: where an ensemble places its stabilizers
    /// (`stabK.from_bit`), so each stands where its variant puts it rather than at the
    /// case mesh's nearest node. A rebuilt case ([`Case::rebuilt`]: another depth) keeps
    /// them.
    pub fn with_nodes_from_bit(&self, from_bit: &[f64]) -> Result<Case, InputError> {
        let mut source = (*self.source).clone();
        source.nodes_from_bit.extend_from_slice(from_bit);
        build_case(&self.path, source)
    }
}

/// The case file's tables (serde), an error naming the line and key where they do not read.
fn read_spec(path: &Path, text: &str) -> Result<CaseSpec, InputError> {
    let ctx = Ctx { path, text };
    toml::from_str(text).map_err(|e| {
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
    })
}

/// The case from its tables ([`CaseSource`]): values checked, the well, hole and string
/// read, the mesh and the contact sites built.
fn build_case(path: &Path, mut source: CaseSource) -> Result<Case, InputError> {
    let text = std::mem::take(&mut source.text);
    let ctx = Ctx { path, text: &text };
    let spec = &source.spec;
    let bit_md = ctx.quantity(
        &spec.well.total_md,
        "well.total_md",
        Dimension::Length,
        |x| x > 0.0 && x <= 20_000.0,
        "0 < total_md ≤ 20 km",
    )?;
    let mut warnings: Vec<String> = Vec::new();
    let (well, survey_read) = read_well(&ctx, spec, path, bit_md, source.survey.take())?;
    // Below a survey's last station the path goes on along its last tangent.

    let hole = read_hole(&ctx, spec, path, bit_md)?;
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
        warnings.extend(survey::survey_projection_warning(
            &survey_path.display().to_string(),
            read,
            bit_md,
        ));
    }
    let mud = ctx.fluid_density(&spec.mud.density, "mud.density", "0 (a dry string)")?;
    let mud_inside = match &spec.mud.inside_density {
        None => mud,
        Some(q) => ctx.fluid_density(q, "mud.inside_density", "0 (empty)")?,
    };
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

    let StringRead {
        tubulars,
        blades,
        tool_joints,
        strength,
        eccentricities,
        bends,
        warnings: string_warnings,
    } = read_string(&ctx, spec, &hole, bit_md, (el_pipe, el_bha))?;
    warnings.extend(string_warnings);

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

    let Operation {
        wob,
        tob,
        hook,
        axial_speed,
        rotation_speed,
    } = read_operation(&ctx, spec)?;
    let (settings, friction, all_nodes) = read_contact(&ctx, spec)?;
    // Reaming and back-reaming move the pipe along and around the hole at once: the
    // friction is split by the velocity's direction (the coupled model) unless the case
    // says otherwise — the split model (the paper's) charges full friction both ways.
    let both_ways = axial_speed != 0.0 && rotation_speed != 0.0;
    let friction = match friction {
        Some(f) => {
            if both_ways && f == FrictionModel::Split {
                warnings.push(
                    "contact.friction_model = \"split\" with a mode that moves the pipe along \
                     and around the hole at once (reaming, back-reaming): each direction takes \
                     full friction, up to √2 × the coupled model's; \"coupled\" splits it by \
                     the velocity's direction"
                        .to_string(),
                );
            }
            f
        }
        None if both_ways => FrictionModel::Coupled,
        None => FrictionModel::Split,
    };
    let (nodes, mut elements) = crate::model::mesh_string_two_fluids(
        &well,
        &tubulars,
        bit_md,
        mud,
        mud_inside,
        &source
            .nodes_from_bit
            .iter()
            .map(|d| bit_md - d)
            .collect::<Vec<_>>(),
    );
    let n = nodes.len();
    // Tool joints: the contact diameter, and the joints' steel (beyond the body's OD, over
    // their share of a joint) in the weight, buoyed by the annulus.
    for e in elements.iter_mut() {
        if let Some((tj, tj_length, spacing)) = tool_joints[e.component] {
            let extra = std::f64::consts::FRAC_PI_4
                * (tj * tj - e.outer_diameter * e.outer_diameter)
                * (tj_length / spacing);
            let rho = tubulars[e.component].density;
            e.contact_diameter = tj;
            e.air_weight_per_length += crate::model::GRAVITY * rho * extra;
            e.buoyed_weight_per_length += crate::model::GRAVITY * (rho - mud) * extra;
        }
    }
    // The joints' nodes (a component with joints meshed finer than a joint has body nodes
    // between them): MD of every joint from each such component's bottom.
    let joint_node = |md: f64| -> bool {
        let mut bottom = bit_md;
        for (t, j) in tubulars.iter().zip(&tool_joints) {
            let top = bottom - t.length;
            if md <= bottom + 1e-9 && md >= top - 1e-9 {
                if let Some((_, _, spacing)) = j {
                    let joints = (t.length / spacing).round().max(1.0);
                    let x = (bottom - md) / (t.length / joints);
                    return (x - x.round()).abs() < 1e-6;
                }
            }
            bottom = top;
        }
        true
    };
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
    // A hook-load top moves along global z (`solve::statics::constraints`): the well's top
    // must be vertical. (A clamped top may lie in an inclined hole — the bottom of a string
    // modelled alone: the table then turns it about its own hole axis.)
    if let (Some(_), Some(q)) = (hook, &spec.operation.hook_load) {
        let tilt = model.nodes[0].hole_axis[2]
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        if tilt > 1.0 {
            return Err(ctx.err(
                q.span(),
                "operation.hook_load",
                format!(
                    "a hook load moves the top along the vertical, but the well's top is \
                     inclined {tilt:.1}° (the survey's first station): start the survey \
                     vertical at MD 0, or give weight_on_bit instead (the top is then clamped)"
                ),
            ));
        }
    }
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
        // A body node between two joints touches with the body's radius.
        let radii: Vec<f64> = (0..n)
            .map(|i| {
                if joint_node(model.nodes[i].md) {
                    model.pipe_radius_at(i)
                } else {
                    let body = |e: usize| 0.5 * model.elements[e].outer_diameter;
                    body(i.min(model.elements.len() - 1)).max(body(i.saturating_sub(1)))
                }
            })
            .collect();
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
    let tendency = tendency_settings(&ctx, spec.tendency.as_ref())?;
    let rig = rig_settings(&ctx, spec.rig.as_ref())?;
    let title = spec.title.clone().unwrap_or_default();
    source.survey = survey_read;
    source.text = text;
    Ok(Case {
        rig,
        ensemble,
        tendency,
        strength,
        title,
        source: std::sync::Arc::new(source),
        path: path.to_path_buf(),
        model,
        hole,
        bit_md,
        bha_length,
        mud_density: mud,
        mud_inside_density: mud_inside,
        element_density,
        dynamics,
        contact: settings,
        warnings,
    })
}
