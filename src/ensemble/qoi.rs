//! Quantities of interest of a variant (issues 5 and 14): neutral point, hook load, surface
//! torque, per stabilizer the largest side force, lateral displacement and whirl, the
//! string's side force per length, buckling flags and stick-slip severity — from a static
//! solution or observed along a dynamic run — and their columns for statistics.

use serde::{Deserialize, Serialize};

use crate::case::Case;
use crate::model::Model;
use crate::physics::vec3::{dot, scale, sub};
use crate::profile::{fe_rows, neutral_point, neutral_point_of, nodal_axial_forces};
use crate::solve::dynamics::{DynamicState, Dynamics};

/// Per-stabilizer quantities of interest.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct StabilizerQoi {
    /// Largest normal (side) force (N).
    #[serde(with = "crate::output::nan_as_null")]
    pub max_side_force_n: f64,
    /// Largest lateral displacement from the hole axis (m).
    #[serde(with = "crate::output::nan_as_null")]
    pub max_lateral_m: f64,
    /// Dominant whirl frequency over the second half of a dynamic run (Hz), signed
    /// (positive forward, with the rotation; negative backward; [`crate::whirl`]); `None`
    /// for static runs or a stabilizer that does not whirl.
    pub whirl_hz: Option<f64>,
    /// How it whirls ([`crate::whirl::WhirlClass`]); `None` for static runs.
    #[serde(default)]
    pub whirl_class: Option<crate::whirl::WhirlClass>,
    /// Share of the second half in contact with the wall; `None` for static runs.
    #[serde(default)]
    pub contact_fraction: Option<f64>,
}

/// Quantities of interest of the whole string.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct StringQoi {
    /// Largest contact (side) force per unit length along the string (N/m): a site's
    /// normal force over its node's share of the string (half of each adjacent element), so
    /// it does not depend on the mesh; over the run for dynamics.
    pub max_side_force_per_length_n_per_m: Option<f64>,
    /// Where it acts (MD, m).
    pub max_side_force_md_m: Option<f64>,
    /// Compression beyond the sinusoidal buckling load anywhere (static).
    pub sinusoidal_buckling: Option<bool>,
    /// Beyond the helical buckling load (static).
    pub helical_buckling: Option<bool>,
    /// Stick-slip severity over the second half of a dynamic run: (max − min)/mean of the
    /// bit's spin about the hole axis.
    pub stick_slip_severity: Option<f64>,
    /// How far the static equilibrium lies outside the hole where no contact site holds it
    /// (m; 0 inside it: [`crate::diagnose::through_wall`]) — with contact at the
    /// stabilizers only, an answer for a string in no hole.
    #[serde(default)]
    pub outside_hole_m: Option<f64>,
    /// A static variant that failed where its load path bracketed where the string stops
    /// (a lock-up, [`crate::solve::statics::Stopped`]): the largest fraction of its friction
    /// and bit loads at which the FE found an equilibrium.
    #[serde(default)]
    pub stopped_load_factor: Option<f64>,
    /// Such a variant's string where it stands, at `stopped_load_factor`.
    #[serde(default)]
    pub stands: Option<Stands>,
    /// A solved static variant whose equilibrium came by relaxation past a fold
    /// ([`crate::solve::continuation::relaxed`]): one of several equilibria, which the
    /// solve's path chose ([`crate::diagnose::relaxed_warning`]); for a dynamic variant,
    /// its static start's.
    #[serde(default)]
    pub relaxed: Option<bool>,
}

/// A stopped variant's string where it stands, at the loads of its last equilibrium
/// ([`StringQoi::stopped_load_factor`]; `variants.csv`'s `stopped_*` columns): what the rig
/// reads when the string stops on its way (a lock-up), and where it bears hardest.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Stands {
    /// Hook load (N).
    pub hook_load_n: f64,
    /// Surface torque (N·m).
    pub surface_torque_nm: f64,
    /// Largest side force per unit length (N/m) and where it acts (MD, m).
    pub max_side_force_per_length_n_per_m: f64,
    /// See `max_side_force_per_length_n_per_m`.
    pub max_side_force_md_m: Option<f64>,
}

/// How a variant ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Converged at the requested steps.
    Converged,
    /// Converged, with load or time steps cut on the way (see the reason column).
    StepCut,
    /// Failed (NaN, Newton divergence, step below the minimum): see the reason.
    Failed,
}

/// Which solver produced a variant's result.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolvedBy {
    /// The kernel engine (GPU, or the CPU twins of its kernels).
    Engine,
    /// The CPU solver (the CPU backend, or a re-run of a variant the engine failed).
    Cpu,
}

impl SolvedBy {
    /// The name in `variants.csv`.
    pub fn name(self) -> &'static str {
        match self {
            SolvedBy::Engine => "engine",
            SolvedBy::Cpu => "cpu",
        }
    }
}

/// One variant's result.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct VariantResult {
    /// Variant name.
    pub name: String,
    /// Status.
    pub status: Status,
    /// Who solved it (a CPU re-run of an engine failure says so in `reason`).
    pub solved_by: SolvedBy,
    /// Why it failed, or the first step cut.
    pub reason: String,
    /// Neutral point from the bit (m): static solution, or the last state of a dynamic run.
    pub neutral_point_from_bit_m: Option<f64>,
    /// Hook load (N): the top's axial reaction of a static solution; for a dynamic run the
    /// top element's axial force in the last state.
    pub hook_load_n: Option<f64>,
    /// What the rig's weight indicator reads for that load ([`crate::rig`]): static
    /// variants of a case with a `[rig]`.
    #[serde(default)]
    pub weight_indicator_n: Option<f64>,
    /// Largest surface torque (N·m).
    #[serde(with = "crate::output::nan_as_null")]
    pub max_surface_torque_nm: f64,
    /// The string's other quantities (side force per length, buckling, stick-slip).
    #[serde(default)]
    pub string: StringQoi,
    /// Per stabilizer, nearest the bit first.
    pub stabilizers: Vec<StabilizerQoi>,
    /// The bit's side force and tilt ([`crate::bha::bit_loads`]): static variants.
    #[serde(default)]
    pub bit: Option<crate::bha::BitLoads>,
    /// Mean Newton iterations per load or time step.
    #[serde(with = "crate::output::nan_as_null")]
    pub newton_iterations_per_step: f64,
    /// Step cuts.
    pub step_cuts: usize,
}

pub(crate) fn element_axial(
    model: &Model,
    q: &crate::solve::statics::StaticState,
    i: usize,
) -> (f64, f64) {
    let f = crate::solve::statics::element_section_forces(model, q, i);
    (f.axial, f.torque)
}

/// Lateral offset of a site's node from the hole axis, in the node's frame (x, y).
pub(crate) fn lateral(
    model: &Model,
    q: &crate::solve::statics::StaticState,
    node: usize,
) -> (f64, f64) {
    let nd = &model.nodes[node];
    let d = q.u[node];
    let d_t = sub(&d, &scale(&nd.hole_axis, dot(&d, &nd.hole_axis)));
    let f = &nd.frame0;
    (
        dot(&d_t, &[f[0][1], f[1][1], f[2][1]]),
        dot(&d_t, &[f[0][2], f[1][2], f[2][2]]),
    )
}

pub(crate) fn failed(name: &str, reason: String, stabs: usize) -> VariantResult {
    VariantResult {
        name: name.to_string(),
        status: Status::Failed,
        solved_by: SolvedBy::Cpu,
        reason,
        neutral_point_from_bit_m: None,
        hook_load_n: None,
        weight_indicator_n: None,
        max_surface_torque_nm: f64::NAN,
        string: StringQoi::default(),
        stabilizers: vec![StabilizerQoi::default(); stabs],
        bit: None,
        newton_iterations_per_step: f64::NAN,
        step_cuts: 0,
    }
}

/// A variant whose static solve (or a dynamic run's static start) failed (`reason`): where
/// its load path bracketed where the string stops (a lock-up), `at` is the largest load
/// factor at which it found an equilibrium (`variants.csv`'s `stopped_load_factor`; the
/// CPU solve's [`crate::solve::statics::StaticError::stopped`], the engine's
/// [`crate::engine::EngineResult::stops`]), with the string there where one was kept
/// ([`StringQoi::stands`]).
pub(crate) fn failed_stopping(
    case: &Case,
    name: &str,
    reason: String,
    stabs: usize,
    stops: Option<(f64, Option<&crate::solve::statics::Stopped>)>,
) -> VariantResult {
    let mut r = failed(name, reason, stabs);
    r.string.stopped_load_factor = stops.map(|(at, _)| at);
    if let Some(st) = stops.and_then(|(at, st)| st.filter(|st| st.lambda == at)) {
        let sol = crate::solve::statics::stopped_solution(st);
        let there = static_result(case, name, &st.model, &sol);
        r.string.stands = Some(Stands {
            hook_load_n: there.hook_load_n.unwrap_or(f64::NAN),
            surface_torque_nm: there.max_surface_torque_nm,
            max_side_force_per_length_n_per_m: there
                .string
                .max_side_force_per_length_n_per_m
                .unwrap_or(f64::NAN),
            max_side_force_md_m: there.string.max_side_force_md_m,
        });
    }
    r
}

/// How a dynamic variant's failure in its static start begins its reason.
pub(crate) const STATIC_START: &str = "static start: ";

/// A variant that finished: converged, or with `cuts` step cuts (or other departures from
/// its plain steps) that its solver log `log` records.
#[allow(clippy::too_many_arguments)]
pub(crate) fn finished(
    name: &str,
    log: &[String],
    cuts: usize,
    iterations: &[usize],
    neutral_point_from_bit_m: Option<f64>,
    hook_load_n: f64,
    max_surface_torque_nm: f64,
    stabilizers: Vec<StabilizerQoi>,
    string: StringQoi,
) -> VariantResult {
    VariantResult {
        name: name.to_string(),
        status: if cuts > 0 {
            Status::StepCut
        } else {
            Status::Converged
        },
        solved_by: SolvedBy::Cpu,
        reason: log.first().cloned().unwrap_or_default(),
        neutral_point_from_bit_m,
        hook_load_n: hook_load_n.is_finite().then_some(hook_load_n),
        weight_indicator_n: None,
        max_surface_torque_nm,
        string,
        stabilizers,
        bit: None,
        newton_iterations_per_step: iterations.iter().sum::<usize>() as f64
            / iterations.len().max(1) as f64,
        step_cuts: cuts,
    }
}

/// The time steps a dynamic run's log says were cut.
fn dynamic_cuts(log: &[String]) -> usize {
    log.iter().filter(|l| l.contains("cut to")).count()
}

/// Static equilibrium of one model of the case (its own, or one made from it), held in the
/// hole wherever it meets the wall ([`crate::profile::solve_in_hole`]: sites added there
/// take the case's wall law).
pub fn static_variant(case: &Case, name: &str, model: &Model) -> VariantResult {
    solve_held(case, name, model, true, &mut |m, nodes| {
        crate::profile::add_wall_sites(case, m, nodes)
    })
}

/// Static equilibrium of variant `v`'s model (`model`, [`crate::ensemble::apply`]), held in
/// the hole wherever it meets the wall: the sites added there get the variant's overrides
/// too ([`crate::ensemble::apply_with_sites`]). `find_stop`: a load path that fails brackets
/// where the string stops ([`crate::solve::statics::StaticOptions::find_stop`]; off where the
/// engine's path did so already, `ensemble::runner`).
pub fn static_variant_of(
    case: &Case,
    v: &crate::ensemble::Variant,
    model: &Model,
    find_stop: bool,
) -> VariantResult {
    solve_held(
        case,
        &v.name,
        model,
        find_stop,
        &mut variant_wall_sites(case, v),
    )
}

/// The static start of `model` held in the hole wherever the string meets the wall
/// ([`crate::profile::solve_in_hole`], `add` giving the sites): the model with those sites,
/// and the solve. The one start of every static and dynamic variant on the CPU (the
/// engine's solves the same guarded models: `ensemble::runner`). `find_stop`: as
/// [`static_variant_of`]'s.
fn held_start(
    case: &Case,
    model: &Model,
    find_stop: bool,
    add: &mut dyn FnMut(&mut Model, &[usize]),
) -> (
    Model,
    Result<crate::solve::statics::StaticSolution, crate::solve::statics::StaticError>,
) {
    let mut held = model.clone();
    let solved = crate::profile::solve_in_hole(
        case,
        &mut held,
        add,
        &crate::solve::statics::StaticOptions {
            find_stop,
            ..case.settings().statics()
        },
        &mut |_| {},
    );
    (held, solved)
}

/// How variant `v`'s model gets sites where its string meets the wall
/// ([`crate::profile::solve_in_hole`]): the variant applied again with every node added so
/// far ([`crate::ensemble::apply_with_sites`]), so its overrides reach them.
fn variant_wall_sites<'a>(
    case: &'a Case,
    v: &'a crate::ensemble::Variant,
) -> impl FnMut(&mut Model, &[usize]) + 'a {
    let mut extra = Vec::new();
    move |m: &mut Model, nodes: &[usize]| {
        extra.extend_from_slice(nodes);
        match crate::ensemble::apply_with_sites(case, v, &extra) {
            Ok(with) => *m = with,
            // Not reached: the variant applied to this case already, and pipe-body sites
            // make none of its overrides fail; the sites then keep the case's law.
            Err(_) => crate::profile::add_wall_sites(case, m, nodes),
        }
    }
}

fn solve_held(
    case: &Case,
    name: &str,
    model: &Model,
    find_stop: bool,
    add: &mut dyn FnMut(&mut Model, &[usize]),
) -> VariantResult {
    let (model, solved) = held_start(case, model, find_stop, add);
    match solved {
        Ok(sol) => static_result(case, name, &model, &sol),
        Err(e) => failed_stopping(
            case,
            name,
            e.to_string(),
            model.stabilizer_sites().len(),
            e.stopped().map(|s| (s.lambda, Some(s))),
        ),
    }
}

/// Quantities of interest of a converged static solution.
pub fn static_result(
    case: &Case,
    name: &str,
    model: &Model,
    sol: &crate::solve::statics::StaticSolution,
) -> VariantResult {
    let stabs = model.stabilizer_sites();
    let (rows, hook, torque, _wob) = fe_rows(model, sol);
    let stabilizers = stabs
        .iter()
        .map(|&k| {
            let (x, y) = lateral(model, &sol.state, model.sites[k].node);
            StabilizerQoi {
                max_side_force_n: sol.contact[k].1.max(0.0),
                max_lateral_m: x.hypot(y),
                whirl_hz: None,
                whirl_class: None,
                contact_fraction: None,
            }
        })
        .collect();
    let (per_length, md) = (0..model.sites.len())
        .map(|k| {
            let node = model.sites[k].node;
            (
                sol.contact[k].1.max(0.0) / model.tributary_length(node),
                model.nodes[node].md,
            )
        })
        .fold((0.0f64, f64::NAN), |m, x| if x.0 > m.0 { x } else { m });
    let (sinusoidal, helical) = crate::profile::buckling(case, model, &rows);
    let string = StringQoi {
        max_side_force_per_length_n_per_m: Some(per_length),
        max_side_force_md_m: md.is_finite().then_some(md),
        sinusoidal_buckling: Some(sinusoidal),
        helical_buckling: Some(helical),
        stick_slip_severity: None,
        outside_hole_m: Some(
            crate::diagnose::through_wall(case, model, &sol.state).map_or(0.0, |t| t.excess_m),
        ),
        stopped_load_factor: None,
        stands: None,
        relaxed: Some(crate::solve::continuation::relaxed(&sol.log)),
    };
    let travel = crate::rig::Travel::of_axial_speed(model.axial_speed);
    VariantResult {
        bit: Some(crate::bha::bit_loads_of(model, sol)),
        weight_indicator_n: case
            .rig
            .filter(|_| hook.is_finite())
            .map(|r| r.reading(hook, travel).weight_indicator_n),
        ..finished(
            name,
            &sol.log,
            crate::profile::path_events(&sol.log),
            &sol.iterations,
            neutral_point(&rows).map(|md| bit_md_of(case, model) - md),
            hook,
            torque,
            stabilizers,
            string,
        )
    }
}

/// The `[dynamics]` run of one variant's model from its static equilibrium.
pub fn dynamic_variant(case: &Case, name: &str, model: &Model) -> VariantResult {
    dynamic_variant_tracked(case, name, model, false).0
}

/// [`dynamic_variant`], and with `track_energy` the growth of the lateral motion's energy:
/// the largest lateral kinetic energy `Σ ½ mᵢ |vᵢ − (vᵢ·tᵢ) tᵢ|²` (translations across the
/// hole axis `tᵢ`) over the run's second half divided by the largest over its first half,
/// minus 1. The spin-up and the axial and torsional waves leave it alone (their motion is
/// along and about the axis); a run that blows up grows it by orders, a decaying transient
/// gives < 0, a steady whirl ≈ 0. `None` without tracking or when the first half has no
/// lateral motion at all.
pub fn dynamic_variant_tracked(
    case: &Case,
    name: &str,
    model: &Model,
    track_energy: bool,
) -> (VariantResult, Option<f64>) {
    dynamic_held(case, name, model, track_energy, true, &mut |m, nodes| {
        crate::profile::add_wall_sites(case, m, nodes)
    })
}

/// [`dynamic_variant`] of variant `v` (its model `model`): the sites its static start adds
/// where the string meets the wall get the variant's overrides too, as
/// [`static_variant_of`]'s (and its `find_stop`, for the static start).
pub fn dynamic_variant_of(
    case: &Case,
    v: &crate::ensemble::Variant,
    model: &Model,
    find_stop: bool,
) -> VariantResult {
    dynamic_held(
        case,
        &v.name,
        model,
        false,
        find_stop,
        &mut variant_wall_sites(case, v),
    )
    .0
}

/// A dynamic run from the static start held in the hole wherever the string meets the wall
/// ([`crate::profile::solve_in_hole`], `add` giving the sites), of the model with those
/// sites, as `holewall run` runs a case.
fn dynamic_held(
    case: &Case,
    name: &str,
    model: &Model,
    track_energy: bool,
    find_stop: bool,
    add: &mut dyn FnMut(&mut Model, &[usize]),
) -> (VariantResult, Option<f64>) {
    let Some(settings) = case.dynamics.clone() else {
        return (
            failed(
                name,
                "no [dynamics] table".into(),
                model.stabilizer_sites().len(),
            ),
            None,
        );
    };
    let (held, solved) = held_start(case, model, find_stop, add);
    let model = &held;
    let stabs = model.stabilizer_sites();
    let start = match solved {
        Ok(s) => s,
        Err(e) => {
            let why = format!("{STATIC_START}{e}");
            let stops = e.stopped().map(|s| (s.lambda, Some(s)));
            return (failed_stopping(case, name, why, stabs.len(), stops), None);
        }
    };
    let relaxed_start = crate::solve::continuation::relaxed(&start.log);
    let mass = track_energy
        .then(|| crate::solve::dynamics::lumped_mass(model, &|e| case.element_density[e]).0);
    let options = case.settings().dynamics();
    let density = &case.element_density;
    let mut dynamics = Dynamics::new(model, options, &|e| density[e]);
    let (q0, v0) = case.dynamic_start(model, start.state);
    let mut s = match dynamics.initial_state_with(q0, v0) {
        Ok(s) => s,
        Err(e) => {
            return (
                failed(name, format!("initial state: {e}"), stabs.len()),
                None,
            )
        }
    };
    let mut observer = DynamicObserver::new(model, settings.duration);
    let half = 0.5 * settings.duration;
    let (mut first, mut second) = (0.0f64, 0.0f64);
    let mut observe = |d: &Dynamics, st: &DynamicState| {
        observer.observe(model, d, st);
        if let Some(m) = &mass {
            let k: f64 = model
                .nodes
                .iter()
                .enumerate()
                .map(|(i, nd)| {
                    let v = [st.v[6 * i], st.v[6 * i + 1], st.v[6 * i + 2]];
                    let along = dot(&v, &nd.hole_axis);
                    let across = sub(&v, &scale(&nd.hole_axis, along));
                    0.5 * m[i] * dot(&across, &across)
                })
                .sum();
            if st.t < half {
                first = first.max(k);
            } else {
                second = second.max(k);
            }
        }
    };
    observe(&dynamics, &s);
    let result = dynamics.run(&mut s, settings.duration, &mut observe);
    let energy_growth = (mass.is_some() && first > 0.0).then(|| second / first - 1.0);
    let cuts = dynamic_cuts(&dynamics.log);
    if let Err(reason) = result {
        let mut f = failed(name, reason.to_string(), stabs.len());
        f.step_cuts = cuts;
        return (f, energy_growth);
    }
    let mut done = observer.finish(case, name, model, &s, &dynamics.log, &dynamics.iterations);
    done.string.relaxed = Some(relaxed_start);
    (done, energy_growth)
}

/// The quantities of interest of a dynamic run, accumulated step by step (the CPU
/// integrator's and the GPU engine's runs feed the same observer).
pub struct DynamicObserver {
    stabs: Vec<usize>,
    qoi: Vec<StabilizerQoi>,
    /// Per stabilizer over the second half: (t, x, y, in contact).
    samples: Vec<Vec<(f64, f64, f64, bool)>>,
    max_torque: f64,
    half: f64,
    /// Largest side force per length so far, and its MD.
    per_length: (f64, f64),
    /// The bit's spin about its hole axis over the second half.
    bit_spin: Vec<f64>,
}

impl DynamicObserver {
    /// For a run of `duration` seconds (whirl is fitted over its second half).
    pub fn new(model: &Model, duration: f64) -> Self {
        let stabs = model.stabilizer_sites();
        let k = stabs.len();
        DynamicObserver {
            stabs,
            qoi: vec![StabilizerQoi::default(); k],
            samples: vec![Vec::new(); k],
            max_torque: 0.0,
            half: 0.5 * duration,
            per_length: (0.0, f64::NAN),
            bit_spin: Vec::new(),
        }
    }

    /// Takes one state in.
    pub fn observe(&mut self, model: &Model, d: &Dynamics, st: &DynamicState) {
        self.max_torque = self.max_torque.max(element_axial(model, &st.q, 0).1.abs());
        let contact = d.contact_forces(st);
        for (k, site) in model.sites.iter().enumerate() {
            let node = site.node;
            let (x, y) = lateral(model, &st.q, node);
            let r = x.hypot(y);
            if r > 0.0 {
                let g = &contact[k].g;
                let nd = &model.nodes[node];
                let dd = st.q.u[node];
                let d_t = sub(&dd, &scale(&nd.hole_axis, dot(&dd, &nd.hole_axis)));
                let normal = dot(&[g[0], g[1], g[2]], &d_t) / r / model.tributary_length(node);
                if normal > self.per_length.0 {
                    self.per_length = (normal, nd.md);
                }
            }
        }
        if st.t >= self.half {
            let n = model.nodes.len();
            let axis = model.nodes[n - 1].hole_axis;
            let w = [
                st.v[6 * (n - 1) + 3],
                st.v[6 * (n - 1) + 4],
                st.v[6 * (n - 1) + 5],
            ];
            self.bit_spin.push(dot(&w, &axis));
        }
        for (j, &k) in self.stabs.iter().enumerate() {
            let node = model.sites[k].node;
            let (x, y) = lateral(model, &st.q, node);
            let r = x.hypot(y);
            let qoi = &mut self.qoi[j];
            qoi.max_lateral_m = qoi.max_lateral_m.max(r);
            if r > 0.0 {
                let g = &contact[k].g;
                let nd = &model.nodes[node];
                let d = st.q.u[node];
                let d_t = sub(&d, &scale(&nd.hole_axis, dot(&d, &nd.hole_axis)));
                let normal = dot(&[g[0], g[1], g[2]], &d_t) / r;
                qoi.max_side_force_n = qoi.max_side_force_n.max(normal);
            }
            if st.t >= self.half {
                self.samples[j].push((st.t, x, y, contact[k].contact));
            }
        }
    }

    /// The variant's result from its final state.
    pub fn finish(
        mut self,
        case: &Case,
        name: &str,
        model: &Model,
        last: &DynamicState,
        log: &[String],
        iterations: &[usize],
    ) -> VariantResult {
        if last.v.iter().any(|x| !x.is_finite()) {
            return failed(name, "state is not finite".into(), self.stabs.len());
        }
        for (j, pts) in self.samples.iter().enumerate() {
            let w = whirl_of(model, self.stabs[j], pts);
            self.qoi[j].whirl_hz =
                (w.class != crate::whirl::WhirlClass::None).then_some(w.dominant_hz);
            self.qoi[j].whirl_class = Some(w.class);
            self.qoi[j].contact_fraction = Some(w.contact_fraction);
        }
        let axial: Vec<f64> = (0..model.elements.len())
            .map(|i| element_axial(model, &last.q, i).0)
            .collect();
        let md: Vec<f64> = model.nodes.iter().map(|n| n.md).collect();
        let np = neutral_point_of(&md, &nodal_axial_forces(&axial));
        let severity = if self.bit_spin.len() >= 2 {
            let mean = self.bit_spin.iter().sum::<f64>() / self.bit_spin.len() as f64;
            let (lo, hi) = self
                .bit_spin
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(*x), b.max(*x))
                });
            (mean.abs() > 1e-9).then(|| (hi - lo) / mean.abs())
        } else {
            None
        };
        let string = StringQoi {
            max_side_force_per_length_n_per_m: Some(self.per_length.0),
            max_side_force_md_m: self.per_length.1.is_finite().then_some(self.per_length.1),
            sinusoidal_buckling: None,
            helical_buckling: None,
            stick_slip_severity: severity,
            outside_hole_m: None,
            stopped_load_factor: None,
            stands: None,
            relaxed: None,
        };
        finished(
            name,
            log,
            dynamic_cuts(log),
            iterations,
            np.map(|x| bit_md_of(case, model) - x),
            axial.first().copied().unwrap_or(f64::NAN),
            self.max_torque,
            self.qoi,
            string,
        )
    }
}

/// The bit's MD of a variant's model (its own with a `depth` key).
pub(crate) fn bit_md_of(case: &Case, model: &Model) -> f64 {
    model.nodes.last().map_or(case.bit_md, |n| n.md)
}

/// A node's share of the string: half of each element beside it (m).
/// The whirl of contact site `site` from the second half's samples (t, x, y, in contact)
/// taken at the integrator's steps: resampled onto a uniform grid (linear, the mean step)
/// for [`crate::whirl::analyse`].
fn whirl_of(model: &Model, site: usize, pts: &[(f64, f64, f64, bool)]) -> crate::whirl::Whirl {
    let n = pts.len();
    let rotary_hz = model.rotation_speed / std::f64::consts::TAU;
    let clearance = model.sites[site].params.clearance;
    if n < 2 {
        return crate::whirl::analyse(&[], &[], &[], 1.0, rotary_hz, clearance);
    }
    let (t0, t1) = (pts[0].0, pts[n - 1].0);
    let dt = (t1 - t0) / (n - 1) as f64;
    let (mut x, mut y, mut c) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    let mut k = 0;
    for i in 0..n {
        let t = t0 + i as f64 * dt;
        while k + 2 < n && pts[k + 1].0 < t {
            k += 1;
        }
        let (a, b) = (&pts[k], &pts[(k + 1).min(n - 1)]);
        let f = if b.0 > a.0 {
            ((t - a.0) / (b.0 - a.0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        x.push(a.1 + f * (b.1 - a.1));
        y.push(a.2 + f * (b.2 - a.2));
        c.push(if a.3 { 1.0 } else { 0.0 });
    }
    crate::whirl::analyse(&x, &y, &c, dt, rotary_hz, clearance)
}
