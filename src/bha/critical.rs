//! Critical rotary speeds of the BHA as it lies in the hole (issue 25).
//!
//! **Modes.** The string's lower part (the BHA and the pipe above it, as in
//! [`crate::bha::tendency::bha_model_top`]) about the static equilibrium of the whole
//! string: its tangent there — the axial load's geometric stiffness, and every contact in
//! the static state as a support of the wall's stiffness — with the top of the part clamped
//! and the bit held on the hole axis, against the mass matrix with the mud's added mass
//! (inside the pipe and the displaced volume outside, added-mass coefficient 1) on the
//! translations: `K φ = ω² M φ` ([`crate::solve::modal::modes`]). A mode is **lateral**
//! when more than 80 % of its translations' squares lie across the hole axis.
//!
//! **Excitations** (the Campbell diagram), each crossing a lateral mode at `f`:
//! - 1× the rotary speed (mass imbalance, bent housing, bent pipe): `N = 60 f` rpm;
//! - blade pass, `n_b` × (a stabilizer or bit with `n_b` blades sliding round the wall):
//!   `N = 60 f / n_b`;
//! - backward whirl of a stabilizer rolling on the wall without slip, at
//!   `D_s / (D_h − D_s)` × the rotary speed (blade diameter `D_s`, hole `D_h`):
//!   `N = 60 f (D_h − D_s) / D_s`.

use serde::Serialize;

use crate::bha::HoleFrame;
use crate::model::Model;
use crate::physics::mass::MassKind;
use crate::solve::modal::{lowest_modes, mass_matrix_with_added, Mode};
use crate::solve::statics::StaticState;

/// The highest rotary speed of the map by default (rpm): `holewall critical-speeds` and
/// `holewall bench critical-corpus`.
pub const DEFAULT_MAX_RPM: f64 = 300.0;
/// Blades of the stabilizers and bit by default (blade pass).
pub const DEFAULT_BLADES: usize = 3;
/// Lateral modes reported by default.
pub const DEFAULT_MODES: usize = 6;

/// Options of the critical-speed analysis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CriticalOptions {
    /// Highest rotary speed of the map (rpm).
    pub max_rpm: f64,
    /// Blades of the stabilizers and bit (blade-pass excitation).
    pub blades: usize,
    /// Lateral modes reported (the lowest).
    pub modes: usize,
    /// Mud density (kg/m³) in the annulus for the added mass; 0: none (as the dynamics,
    /// which carries no added mass).
    pub mud_density: f64,
    /// Density of the fluid inside the string (kg/m³) for the added mass.
    pub mud_inside_density: f64,
    /// Solve the eigenproblem densely whatever its size (the oracle of
    /// [`crate::solve::modal::lowest_modes`]'s Krylov solve).
    pub dense: bool,
}

impl CriticalOptions {
    /// The options for `case`: its mud's added mass where `added_mass` (else none, as the
    /// dynamics), the other fields as given.
    pub fn for_case(
        case: &crate::case::Case,
        max_rpm: f64,
        blades: usize,
        modes: usize,
        added_mass: bool,
        dense: bool,
    ) -> Self {
        let rho = |d: f64| if added_mass { d } else { 0.0 };
        CriticalOptions {
            max_rpm,
            blades,
            modes,
            mud_density: rho(case.mud_density),
            mud_inside_density: rho(case.mud_inside_density),
            dense,
        }
    }
}

/// The critical speeds of `case`'s BHA (the part from
/// [`crate::bha::tendency::bha_model_top`] to the bit) about its static `state`: the one call
/// of `holewall critical-speeds` and `holewall bench critical-corpus`.
pub fn critical_speeds_of_case(
    case: &crate::case::Case,
    state: &StaticState,
    options: &CriticalOptions,
) -> CriticalSpeeds {
    let model = &case.model;
    let first =
        crate::bha::tendency::bha_model_top(model, case.bha_length, &case.tendency.settings);
    critical_speeds(model, state, first, &|i| case.element_density[i], options)
}

/// One lateral mode.
#[derive(Clone, Debug, Serialize)]
pub struct LateralMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Share of its translations across the hole axis.
    pub lateral_share: f64,
    /// Per node of the part (MD, m; lateral displacement across the hole axis,
    /// normalised to 1 at its largest).
    pub shape: Vec<(f64, f64)>,
}

/// A critical speed: an excitation crossing a mode.
#[derive(Clone, Debug, Serialize)]
pub struct CriticalSpeed {
    /// `1x`, `blade_pass` or `backward_whirl_stabK`.
    pub excitation: String,
    /// The mode (1 = lowest lateral).
    pub mode: usize,
    /// Its frequency (Hz).
    pub frequency_hz: f64,
    /// Rotary speed at which the excitation meets it (rpm).
    pub rpm: f64,
}

/// The analysis's result.
#[derive(Clone, Debug, Serialize)]
pub struct CriticalSpeeds {
    /// Lateral modes, lowest first.
    pub modes: Vec<LateralMode>,
    /// Excitations as (name, frequency per rotary frequency).
    pub excitations: Vec<(String, f64)>,
    /// Critical speeds up to the options' highest rpm, lowest first.
    pub critical: Vec<CriticalSpeed>,
    /// The part's top (MD, m) and bit (MD, m).
    pub part_md: (f64, f64),
    /// Degrees of freedom of the eigenproblem.
    pub dofs: usize,
    /// How the modes were found: `dense` or `shift-invert block Lanczos`
    /// ([`crate::solve::modal::lowest_modes`]).
    pub eigen_method: String,
    /// The Krylov basis (the free DOFs where dense).
    pub eigen_basis: usize,
    /// The largest relative residual `‖K φ − ω² M φ‖ / (‖K φ‖ + ω² ‖M φ‖)` of the modes
    /// found (0 where dense).
    pub eigen_worst_residual: f64,
}

/// A mode's share of its translations across the hole axis and its lateral shape (per node
/// of the part: MD, lateral displacement across the axis).
fn lateral_share(part: &Model, frames: &[HoleFrame], m: &Mode) -> (f64, Vec<(f64, f64)>) {
    let (mut across, mut total) = (0.0, 0.0);
    let mut shape = Vec::with_capacity(frames.len());
    for (i, f) in frames.iter().enumerate() {
        let u = [m.shape[6 * i], m.shape[6 * i + 1], m.shape[6 * i + 2]];
        let (h, r) = f.across(&u);
        across += h * h + r * r;
        total += u.iter().map(|x| x * x).sum::<f64>();
        shape.push((part.nodes[i].md, h.hypot(r)));
    }
    let share = if total > 0.0 { across / total } else { 0.0 };
    (share, shape)
}

/// A mode is lateral: more than 80 % of its translations' squares across the hole axis,
/// and a positive frequency.
fn is_lateral(share: f64, m: &Mode) -> bool {
    share > 0.8 && m.frequency_hz > 0.0
}

/// The part of `model` from node `first` to the bit ([`Model::lower_part`]) and its
/// piece of `state`.
pub fn lower_part(model: &Model, state: &StaticState, first: usize) -> (Model, StaticState) {
    let st = StaticState {
        u: state.u[first..].to_vec(),
        rot: state.rot[first..].to_vec(),
    };
    (model.lower_part(first), st)
}

/// The critical speeds of `model`'s lower part from node `first`, about the static
/// `state`; `density_of(i)` is element `i`'s steel density.
pub fn critical_speeds(
    model: &Model,
    state: &StaticState,
    first: usize,
    density_of: &dyn Fn(usize) -> f64,
    options: &CriticalOptions,
) -> CriticalSpeeds {
    let (part, st) = lower_part(model, state, first);
    let added = |i: usize| {
        let e = &part.elements[i];
        let outer = std::f64::consts::FRAC_PI_4 * e.outer_diameter * e.outer_diameter;
        let inner = (outer - e.section.area).max(0.0);
        options.mud_inside_density * inner + options.mud_density * outer
    };
    let mass = mass_matrix_with_added(
        &part,
        MassKind::Consistent,
        &|i| density_of(i + first),
        &added,
    );
    let n = part.nodes.len();
    let frames: Vec<HoleFrame> = (0..n).map(|i| HoleFrame::at_node(&part, i)).collect();
    // The lowest modes, until they hold the lateral modes asked for.
    let enough = |found: &[Mode]| {
        found
            .iter()
            .filter(|m| is_lateral(lateral_share(&part, &frames, m).0, m))
            .count()
            >= options.modes
    };
    let all = lowest_modes(&part, &st, &mass, &enough, options.dense);
    let mut lateral = Vec::new();
    for m in &all.modes {
        let (share, mut shape) = lateral_share(&part, &frames, m);
        if is_lateral(share, m) {
            let peak = shape.iter().map(|s| s.1).fold(0.0f64, f64::max).max(1e-300);
            for s in &mut shape {
                s.1 /= peak;
            }
            lateral.push(LateralMode {
                frequency_hz: m.frequency_hz,
                lateral_share: share,
                shape,
            });
        }
        if lateral.len() >= options.modes {
            break;
        }
    }
    let mut excitations = vec![
        ("1x".to_string(), 1.0),
        ("blade_pass".to_string(), options.blades as f64),
    ];
    for (k, &site) in part.stabilizer_sites().iter().enumerate() {
        let s = &part.sites[site];
        let (dh, ds) = (2.0 * s.hole_radius, 2.0 * s.params.disk_radius);
        if dh - ds > 1e-6 {
            excitations.push((
                format!("backward_whirl_{}", crate::model::stabilizer_name(k + 1)),
                ds / (dh - ds),
            ));
        }
    }
    let mut critical: Vec<CriticalSpeed> = Vec::new();
    for (name, ratio) in &excitations {
        for (j, m) in lateral.iter().enumerate() {
            let rpm = 60.0 * m.frequency_hz / ratio;
            if rpm <= options.max_rpm {
                critical.push(CriticalSpeed {
                    excitation: name.clone(),
                    mode: j + 1,
                    frequency_hz: m.frequency_hz,
                    rpm,
                });
            }
        }
    }
    critical.sort_by(|a, b| a.rpm.total_cmp(&b.rpm));
    CriticalSpeeds {
        modes: lateral,
        excitations,
        critical,
        part_md: (part.nodes[0].md, part.nodes[n - 1].md),
        dofs: 6 * n,
        eigen_method: all.method.to_string(),
        eigen_basis: all.basis,
        eigen_worst_residual: all.worst_residual,
    }
}
