//! The BHA's directional tendency (issue 25): the equilibrium curvature and the predicted
//! build and turn rates, from the bit's side force and tilt in holes of constant curvature.
//!
//! **The BHA model.** The string's lower part — the BHA and `3 λ` of the pipe above it
//! (`λ = (EI/q)^(1/3)`, the pipe's bending length, 20…90 m), whole elements of the case's
//! mesh — is laid in a hole of constant curvature `κ = κ_b h + κ_t r` (build towards the
//! high side `h`, walk towards the right `r`, at the bit's hole frame), ending at the bit
//! with its inclination and azimuth, its top clamped on the hole axis (far enough that the
//! bit does not feel it: [`TendencySettings::pipe_bending_lengths`]), the bit held on the
//! hole axis with the weight and torque on bit, the hole sections, contact sites, bends and
//! operation of the case. This is the BHA program's classic set-up (Williamson & Lubinski):
//! the bit's side force and tilt as functions of the hole's curvature.
//!
//! **Equilibrium curvature**: the build curvature at which the bit's side force towards the
//! high side vanishes (no walk curvature): secant iterations on `F_h(κ_b)`.
//!
//! **Bit–rock model** (stated, after Ho 1987 and Lubinski & Woods 1953): the bit drills
//! along `v = W a + I_b F_s`, `a` the bit's axis, `W` the weight on bit, `F_s` the side
//! force on the formation (across the hole axis) and `I_b` the bit's **side-cutting index**
//! (lateral over axial drillability: 0 drills only along the bit's axis, 1 along the
//! resultant force). A layered formation of anisotropy index `h_f` with bedding normal `n`
//! turns it to `(1 + h_f)(v·n) n + (1 − h_f)(v − (v·n) n)`: towards the normal of the
//! bedding (up-dip) for `h_f > 0`. The **steady-state rates** are the hole curvature
//! `(κ_b, κ_t)` at which that drilling direction is the hole's own direction at the bit —
//! the curvature the assembly keeps drilling — found by Broyden iterations from zero
//! curvature on the two angles of the drilling direction from the hole axis. The build rate
//! is `κ_b`, the turn rate the azimuth's rate `κ_t / sin I`; both in °/30 m.
//!
//! A static analysis holds the string in one orientation. An assembly with a bend that
//! rotates ([`assembly_tendency`]) takes every toolface in turn in one hole: at each hole
//! curvature its bit's loads are the means over 12 toolfaces (every 30°), each a
//! sliding-style BHA model with the rotation's friction, and its rates and equilibrium
//! curvature are those of the means; a bend that slides keeps its toolface.

use serde::{Deserialize, Serialize};

use crate::bha::{bit_loads_of, BitLoads, HoleFrame};
use crate::model::{frame_from_axis, transport, Bend, Element, Model, Node};
use crate::physics::vec3::{add, dot, scale, sub, Vec3};
use crate::solve::statics::{solve_static, StaticOptions};
use crate::well::{SurveyStation, WellPath};

/// The curvature of the first secant and difference steps (°/30 m).
const PROBE: f64 = 0.25;

/// The iterations have settled when a step changes the curvature by less than this
/// (°/30 m): the resolution rates are reported to (a vertical hole's near-zero side forces
/// jitter by more than any finer one).
const SETTLE: f64 = 0.005;

/// How many times in all the equilibrium curvature's search halves a curvature whose BHA
/// model fails toward the last one solved ([`tendency_over`]). A failed BHA-model solve is
/// the dearest kind (a relaxation run out, then its bracket; twelve of them at a curvature
/// for a rotating bend): three halvings a step took the 500-well tendency corpus's
/// unsettled wells 31, 192, 199 and the rotating bend 261 from 4–84 solves to 13–372 (261:
/// 298 s → 1,857 s, with a CI run on the other core) and won none of them.
const SECANT_HALVINGS: usize = 3;

/// Radians per metre to degrees per 30 m.
pub const RAD_PER_M_TO_DEG_PER_30M: f64 = 30.0 * 180.0 / std::f64::consts::PI;

/// The bit–rock model and the BHA model's extent ([module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TendencySettings {
    /// The bit's side-cutting index `I_b` (lateral over axial drillability), 0…1.
    pub side_cutting_index: f64,
    /// Formation anisotropy index `h_f` (Lubinski & Woods), −0.5…0.5; 0: isotropic.
    pub formation_anisotropy: f64,
    /// Bedding dip (degrees from horizontal).
    pub dip_deg: f64,
    /// Azimuth of the dip direction (degrees from north).
    pub dip_azimuth_deg: f64,
    /// Pipe above the BHA in the BHA model, in bending lengths of the pipe.
    pub pipe_bending_lengths: f64,
    /// No BHA-model solve starts (or runs on) past this instant: the tendency then says
    /// which part the budget cut (`holewall static --max-seconds`).
    #[serde(skip)]
    pub deadline: Option<std::time::Instant>,
}

impl Default for TendencySettings {
    /// `I_b` = 0.05 (a PDC bit with an active gauge is quoted at 0.01–0.1), isotropic
    /// formation, 3 bending lengths of pipe.
    fn default() -> Self {
        TendencySettings {
            side_cutting_index: 0.05,
            formation_anisotropy: 0.0,
            dip_deg: 0.0,
            dip_azimuth_deg: 0.0,
            pipe_bending_lengths: 3.0,
            deadline: None,
        }
    }
}

/// The tendency of an assembly (`summary.json`'s `tendency`).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Tendency {
    /// Predicted (steady-state) build rate (°/30 m; < 0 drops); null if the iterations did
    /// not settle or the bit carries no weight.
    pub build_rate_deg_per_30m: Option<f64>,
    /// Predicted turn rate: the azimuth's rate (°/30 m, > 0 turns right); null as above or
    /// in a hole within 1° of vertical (see `walk_curvature_deg_per_30m`).
    pub turn_rate_deg_per_30m: Option<f64>,
    /// The predicted curvature towards the right side (°/30 m): the turn without the
    /// `1/sin I` of the azimuth.
    pub walk_curvature_deg_per_30m: Option<f64>,
    /// Build curvature at which the bit's high-side force vanishes (°/30 m); null if none
    /// within ±30°/30 m.
    pub equilibrium_curvature_deg_per_30m: Option<f64>,
    /// The bit's loads in the BHA model in a straight hole (κ = 0).
    pub bit_straight_hole: Option<BitLoads>,
    /// Length of the BHA model (m).
    pub model_length_m: f64,
    /// The bit–rock model used.
    pub settings: TendencySettings,
    /// BHA-model solves it asked for (toolfaces × curvatures; at a curvature where a
    /// toolface failed, those after it that had not begun are counted but not solved).
    pub solves: usize,
    /// What did not settle, and why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// The BHA model of `model` ([module docs](self)): the nodes from `first` to the bit in a
/// hole of constant curvature `(κ_b, κ_t)` (rad/m), the top clamped, the given weight on
/// bit; bends keep their toolface from the high side, or take `toolface` (rad from the high
/// side) when given.
pub fn bha_model(
    model: &Model,
    first: usize,
    curvature: (f64, f64),
    weight_on_bit: f64,
    toolface: Option<f64>,
) -> Model {
    let n = model.nodes.len();
    let bit = n - 1;
    let frame = HoleFrame::at_node(model, bit);
    let (kb, kt) = curvature;
    let kappa = kb.hypot(kt);
    let c_hat = if kappa > 0.0 {
        add(
            &scale(&frame.high, kb / kappa),
            &scale(&frame.right, kt / kappa),
        )
    } else {
        frame.high
    };
    let bit_md = model.nodes[bit].md;
    let top_md = model.nodes[first].md;
    let length = bit_md - top_md;
    // The tangent a distance s above the bit: the hole turns towards ĉ going down.
    let tangent_above = |s: f64| -> Vec3<f64> {
        sub(
            &scale(&frame.axis, (kappa * s).cos()),
            &scale(&c_hat, (kappa * s).sin()),
        )
    };
    let station = |md: f64, t: Vec3<f64>| SurveyStation {
        md,
        inclination_deg: t[2].clamp(-1.0, 1.0).acos().to_degrees(),
        azimuth_deg: t[1].atan2(t[0]).to_degrees().rem_euclid(360.0),
    };
    // One circular arc: a two-station minimum-curvature survey is exactly one.
    let path = WellPath::from_survey(
        &[
            station(top_md, tangent_above(length)),
            station(bit_md, frame.axis),
        ],
        [0.0; 3],
    )
    .expect("an arc's survey is valid");
    let mut nodes: Vec<Node> = model.nodes[first..]
        .iter()
        .map(|nd| {
            let (p, t) = path.at(nd.md);
            Node {
                md: nd.md,
                position: p,
                hole_axis: t,
                frame0: frame_from_axis(&t),
            }
        })
        .collect();
    for i in 1..nodes.len() {
        nodes[i].frame0 = transport(
            &nodes[i - 1].frame0,
            &nodes[i - 1].hole_axis,
            &nodes[i].hole_axis,
        );
    }
    let elements: Vec<Element> = model.elements[first..]
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let d = sub(&nodes[i + 1].position, &nodes[i].position);
            let l0 = dot(&d, &d).sqrt();
            Element {
                length0: l0,
                frame0: frame_from_axis(&scale(&d, 1.0 / l0)),
                ..e.clone()
            }
        })
        .collect();
    let mut sub_model = Model {
        nodes,
        elements,
        weight_on_bit,
        // The toolface of a bend is the one set (as an MWD reads it at the motor): the
        // reactive torque's twist of the string above is not the BHA model's.
        torque_on_bit: 0.0,
        unbalance: vec![],
        ..model.lower_part(first)
    };
    sub_model.bends = model
        .bends
        .iter()
        .filter(|b| b.node > first)
        .map(|b| {
            let node = b.node - first;
            let from_high =
                toolface.unwrap_or_else(|| model.toolface_to_high_side(b.node, b.toolface));
            Bend {
                node,
                angle: b.angle,
                toolface: sub_model.toolface_from_high_side(node, from_high),
            }
        })
        .collect();
    sub_model
}

/// The first node of the BHA model: `bha_length` plus the settings' bending lengths of the
/// pipe above it (20…90 m), at a node; the surface if the string is shorter.
pub fn bha_model_top(model: &Model, bha_length: f64, settings: &TendencySettings) -> usize {
    let n = model.nodes.len();
    let bit_md = model.nodes[n - 1].md;
    let bha_top = bit_md - bha_length;
    // The pipe element just above the BHA.
    let pipe = model
        .elements
        .iter()
        .enumerate()
        .rev()
        .find(|(i, _)| model.nodes[*i + 1].md <= bha_top + 1e-9)
        .map(|(_, e)| e)
        .unwrap_or(&model.elements[0]);
    let frame = HoleFrame::at_node(model, n - 1);
    let q = pipe.buoyed_weight_per_length * (1.0 - frame.axis[2] * frame.axis[2]).sqrt();
    let ei = pipe.section.youngs_modulus * pipe.section.second_moment;
    let lambda = if q > 0.0 {
        (ei / q).cbrt()
    } else {
        f64::INFINITY
    };
    // A vertical hole has no lateral load: the longest pipe.
    let extra = if lambda.is_finite() {
        (settings.pipe_bending_lengths * lambda).clamp(20.0, 90.0)
    } else {
        90.0
    };
    let top_md = bha_top - extra;
    model
        .nodes
        .iter()
        .rposition(|nd| nd.md <= top_md + 1e-9)
        .unwrap_or(0)
}

/// The drilling direction's angles from the hole axis (towards the high side, the right;
/// rad) of the bit–rock model, for the bit's loads `bit` under weight `wob` in the hole
/// frame `frame`.
pub fn drilling_angles(
    bit: &BitLoads,
    wob: f64,
    frame: &HoleFrame,
    settings: &TendencySettings,
) -> (f64, f64) {
    let (th, tr) = (
        bit.tilt_high_side_deg.to_radians(),
        bit.tilt_right_side_deg.to_radians(),
    );
    // The bit's axis from its two tilts.
    let a = add(
        &frame.axis,
        &add(
            &scale(&frame.high, th.tan()),
            &scale(&frame.right, tr.tan()),
        ),
    );
    let a = scale(&a, 1.0 / dot(&a, &a).sqrt());
    let side = add(
        &scale(&frame.high, bit.high_side_force_n),
        &scale(&frame.right, bit.right_side_force_n),
    );
    let v = add(&scale(&a, wob), &scale(&side, settings.side_cutting_index));
    let h = settings.formation_anisotropy;
    let v = if h != 0.0 {
        // Bedding normal, upwards (z points down): dip from horizontal towards the dip
        // azimuth.
        let (dip, az) = (
            settings.dip_deg.to_radians(),
            settings.dip_azimuth_deg.to_radians(),
        );
        let normal = [-dip.sin() * az.cos(), -dip.sin() * az.sin(), -dip.cos()];
        let vn = dot(&v, &normal);
        let along = sub(&v, &scale(&normal, vn));
        add(&scale(&normal, (1.0 + h) * vn), &scale(&along, 1.0 - h))
    } else {
        v
    };
    frame.angles(&v)
}

/// Why one BHA-model solve gave no bit loads.
#[derive(Debug, thiserror::Error)]
enum BitSolveError {
    /// The tendency's wall-clock budget was spent before the solve began.
    #[error("the time budget ran out before this BHA-model solve")]
    Budget,
    /// The static solve failed.
    #[error(transparent)]
    Static(#[from] crate::solve::statics::StaticError),
}

/// One BHA-model solve: the bit's loads in a hole of curvature `(κ_b, κ_t)`.
fn bit_at(
    model: &Model,
    first: usize,
    curvature: (f64, f64),
    wob: f64,
    toolface: Option<f64>,
    deadline: Option<std::time::Instant>,
) -> Result<(BitLoads, HoleFrame), BitSolveError> {
    let max_seconds = match deadline {
        None => None,
        Some(d) => {
            let left = d.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return Err(BitSolveError::Budget);
            }
            Some(left.as_secs_f64())
        }
    };
    let m = bha_model(model, first, curvature, wob, toolface);
    // A curvature whose model fails is halved or given up (`equilibrium_curvature`):
    // where such a model's string would stop is not needed.
    let options = StaticOptions {
        max_seconds,
        find_stop: false,
        ..StaticOptions::default()
    };
    let sol = solve_static(&m, &options)?;
    let frame = HoleFrame::at_node(&m, m.nodes.len() - 1);
    Ok((bit_loads_of(&m, &sol), frame))
}

/// `f` of every item, in parallel, in order; or the error of the first item in order whose
/// `f` fails — the one a serial sweep would meet. Once an item has failed, the items after
/// it that have not begun are not run.
fn all_in_order<I: Sync, T: Send, E: Send>(
    items: &[I],
    f: impl Fn(&I) -> Result<T, E> + Sync,
) -> Result<Vec<T>, E> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
    let failed = AtomicUsize::new(usize::MAX);
    let each: Vec<Option<Result<T, E>>> = items
        .par_iter()
        .enumerate()
        .map(|(i, x)| {
            if i > failed.load(Relaxed) {
                return None;
            }
            let r = f(x);
            if r.is_err() {
                failed.fetch_min(i, Relaxed);
            }
            Some(r)
        })
        .collect();
    // Every item before the first that failed ran (one is skipped only after an earlier
    // one failed), so the first error met in order is the first item's that failed.
    each.into_iter().flatten().collect()
}

/// The tendency of `model`'s assembly at weight on bit `wob` (N; the case's, or the
/// reaction of a hook-load solve) with `bha_length` the BHA's length (m); `toolface`
/// overrides every bend's toolface (rad from the high side).
pub fn tendency(
    model: &Model,
    bha_length: f64,
    wob: f64,
    toolface: Option<f64>,
    settings: &TendencySettings,
) -> Tendency {
    tendency_over(model, bha_length, wob, &[toolface], settings)
}

/// What the iterations read of a curvature's BHA-model solves: the bit's high-side force
/// and its drilling direction's two angles from the hole axis ([`drilling_angles`]), each
/// the mean over the toolfaces solved; and the first toolface's bit loads.
#[derive(Clone, Copy, Debug)]
struct AtCurvature {
    high_side_force_n: f64,
    angles: (f64, f64),
    first: BitLoads,
}

/// [`tendency`] with every curvature's bit loads the means over `toolfaces` (one entry:
/// that toolface, or the bends' own for `None`): an assembly with a bend that rotates
/// takes every toolface in turn in one hole, so its steady state is the curvature at which
/// the drilling direction averaged over a revolution follows the hole, and its equilibrium
/// curvature the one at which the high-side force averaged over a revolution vanishes
/// ([`assembly_tendency`]).
fn tendency_over(
    model: &Model,
    bha_length: f64,
    wob: f64,
    toolfaces: &[Option<f64>],
    settings: &TendencySettings,
) -> Tendency {
    let first = bha_model_top(model, bha_length, settings);
    let bit_md = model.nodes[model.nodes.len() - 1].md;
    let mut out = Tendency {
        model_length_m: bit_md - model.nodes[first].md,
        settings: *settings,
        ..Default::default()
    };
    // A curvature asked again (the rates' first difference is the equilibrium's first
    // secant step, (PROBE, 0)) is not solved again: the same solve gives the same loads.
    let mut solved: Vec<((f64, f64), AtCurvature)> = Vec::new();
    let mut solve = |k: (f64, f64)| {
        if let Some((_, s)) = solved.iter().find(|s| s.0 == k) {
            return Ok(*s);
        }
        out.solves += toolfaces.len();
        // The toolfaces are independent solves: in parallel (rayon keeps their order, so
        // the means are summed in it). A curvature fails with its first toolface in order
        // that fails, so once one has failed, the toolfaces after it that have not begun
        // are not solved (a failed BHA model is the dearest solve: tendency-corpus well
        // 5442, a rotating bend, 127 → 30 s alone; the same row).
        let each = all_in_order(toolfaces, |&tf| {
            bit_at(model, first, k, wob, tf, settings.deadline)
        })?;
        let n = each.len() as f64;
        let mut at = AtCurvature {
            high_side_force_n: 0.0,
            angles: (0.0, 0.0),
            first: each[0].0,
        };
        for (bit, frame) in &each {
            let (x, y) = drilling_angles(bit, wob, frame, settings);
            at.high_side_force_n += bit.high_side_force_n / n;
            at.angles.0 += x / n;
            at.angles.1 += y / n;
        }
        solved.push((k, at));
        Ok::<_, BitSolveError>(at)
    };
    let to_rate = RAD_PER_M_TO_DEG_PER_30M;
    let limit = 30.0 / to_rate;
    let straight = match solve((0.0, 0.0)) {
        Ok(s) => s,
        Err(e) => {
            out.notes
                .push(format!("the BHA model in a straight hole: {e}"));
            return out;
        }
    };
    out.bit_straight_hole = Some(straight.first);
    // Equilibrium curvature: secant on the high-side force, from 0 and PROBE.
    let mut a = (0.0, straight.high_side_force_n);
    // A curvature whose BHA model fails is halved toward the last one solved, at most
    // [`SECANT_HALVINGS`] times in the search: a secant step can overshoot into a hole the
    // model does not stand in (unseen corpus well 5059, a slick BHA at 91°, 33.6 kN: the
    // step to −5.32°/30 m and its first halving, −4.50, fail; the second solves and the
    // search settles at −4.32); what failed is noted, and a search that ends there says so.
    let mut stopped = false;
    let mut halvings = SECANT_HALVINGS;
    let mut toward = |from: f64, mut k: f64, notes: &mut Vec<String>| loop {
        match solve((k, 0.0)) {
            Ok(s) => return Some((k, s.high_side_force_n)),
            Err(e) => {
                notes.push(format!(
                    "equilibrium curvature at {:.2}°/30 m: {e}",
                    k * to_rate
                ));
                if halvings == 0 {
                    return None;
                }
                halvings -= 1;
                k = from + 0.5 * (k - from);
            }
        }
    };
    let mut b = match toward(0.0, PROBE / to_rate, &mut out.notes) {
        Some(b) => b,
        None => {
            stopped = true;
            (f64::NAN, f64::NAN)
        }
    };
    let mut equilibrium = None;
    for _ in 0..12 {
        if !b.1.is_finite() || b.1 == a.1 {
            break;
        }
        let k = (b.0 - b.1 * (b.0 - a.0) / (b.1 - a.1)).clamp(-limit, limit);
        if (k - b.0).abs() < SETTLE / to_rate {
            equilibrium = Some(k);
            break;
        }
        match toward(b.0, k, &mut out.notes) {
            Some(next) => {
                a = b;
                b = next;
            }
            None => {
                stopped = true;
                break;
            }
        }
        if b.1.abs() < 1e-6 * (1.0 + straight.first.side_force_n) {
            equilibrium = Some(b.0);
            break;
        }
    }
    match equilibrium {
        Some(k) if k.abs() < limit => out.equilibrium_curvature_deg_per_30m = Some(k * to_rate),
        _ if stopped => out.notes.push(
            "no equilibrium curvature: its search stopped where the BHA model failed (above)"
                .to_string(),
        ),
        _ => out
            .notes
            .push("no equilibrium curvature within ±30°/30 m".to_string()),
    }
    // Steady-state rates: Broyden on the drilling direction's two angles.
    if wob <= 0.0 {
        out.notes
            .push("no weight on bit: the bit does not drill, no build or turn rate".into());
        return out;
    }
    let mut k = [0.0, 0.0];
    let mut g = {
        let (x, y) = straight.angles;
        [x, y]
    };
    // Jacobian by differences of PROBE.
    let d = PROBE / to_rate;
    let mut jac = [[0.0; 2]; 2];
    for (j, kk) in [(d, 0.0), (0.0, d)].into_iter().enumerate() {
        match solve(kk) {
            Ok(s) => {
                let (x, y) = s.angles;
                jac[0][j] = (x - g[0]) / d;
                jac[1][j] = (y - g[1]) / d;
            }
            Err(e) => {
                out.notes.push(format!("build/turn rates: {e}"));
                return out;
            }
        }
    }
    let mut settled = false;
    for _ in 0..10 {
        let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        if det.abs() < 1e-300 {
            break;
        }
        let dk = [
            -(jac[1][1] * g[0] - jac[0][1] * g[1]) / det,
            -(-jac[1][0] * g[0] + jac[0][0] * g[1]) / det,
        ];
        let next = [
            (k[0] + dk[0]).clamp(-limit, limit),
            (k[1] + dk[1]).clamp(-limit, limit),
        ];
        let step = [next[0] - k[0], next[1] - k[1]];
        let s = match solve((next[0], next[1])) {
            Ok(s) => s,
            Err(e) => {
                out.notes.push(format!("build/turn rates: {e}"));
                break;
            }
        };
        let (x, y) = s.angles;
        let gn = [x, y];
        // Broyden's update of the Jacobian.
        let dg = [gn[0] - g[0], gn[1] - g[1]];
        let ss = step[0] * step[0] + step[1] * step[1];
        if ss > 0.0 {
            for r in 0..2 {
                let jd = jac[r][0] * step[0] + jac[r][1] * step[1];
                for c in 0..2 {
                    jac[r][c] += (dg[r] - jd) * step[c] / ss;
                }
            }
        }
        k = next;
        g = gn;
        if step[0].abs().max(step[1].abs()) < SETTLE / to_rate || g[0].abs().max(g[1].abs()) < 1e-9
        {
            settled = true;
            break;
        }
    }
    if settled && k[0].abs() < limit && k[1].abs() < limit {
        out.build_rate_deg_per_30m = Some(k[0] * to_rate);
        out.walk_curvature_deg_per_30m = Some(k[1] * to_rate);
        let sin_i = (1.0 - model.nodes[model.nodes.len() - 1].hole_axis[2].powi(2)).sqrt();
        if sin_i > 1f64.to_radians().sin() {
            out.turn_rate_deg_per_30m = Some(k[1] * to_rate / sin_i);
        }
    } else {
        let inclination = model.nodes[model.nodes.len() - 1].hole_axis[2]
            .clamp(-1.0, 1.0)
            .acos();
        out.notes.push(if inclination < 1f64.to_radians() {
            "the build/turn iterations did not settle: a near-vertical hole, whose near-zero side \
             forces jitter more than the rates' resolution"
                .into()
        } else {
            "the build/turn iterations did not settle within ±30°/30 m".into()
        });
    }
    out
}

/// The tendency of the case's assembly as it is operated: [`tendency`] at the bends'
/// toolfaces, or — for an assembly with a bend that rotates — `tendency_over` the 12
/// toolfaces every 30°: at each hole curvature the bit's high-side force and drilling
/// direction are the means over a revolution, and the rates are where that mean direction
/// follows the hole (the bit's straight-hole loads are the first toolface's; the notes say
/// so). The one policy `holewall static` and `holewall tendency` report.
///
/// One hole, one curvature: a rotating assembly cannot drill each toolface's own steady
/// curvature, so the mean of 12 sliding steady states (the rule until stop 71) answered
/// another question, and it needed all 12 of them to settle — a sliding bend's steady state
/// lies far from a straight hole (±10–30°/30 m), where the rates' iterations from κ = 0
/// strayed: 8 of the tendency corpus's 22 rotating bends got no rate (docs/validation.md).
pub fn assembly_tendency(
    model: &Model,
    bha_length: f64,
    wob: f64,
    settings: &TendencySettings,
) -> Tendency {
    if model.bends.is_empty() || model.rotation_speed == 0.0 {
        return tendency(model, bha_length, wob, None, settings);
    }
    let toolfaces: Vec<Option<f64>> = (0..ROTATING_TOOLFACES)
        .map(|k| Some((360.0 * k as f64 / ROTATING_TOOLFACES as f64).to_radians()))
        .collect();
    let mut t = tendency_over(model, bha_length, wob, &toolfaces, settings);
    t.notes.insert(
        0,
        format!(
            "a rotating bend: at each hole curvature the bit's loads are the means over \
             {ROTATING_TOOLFACES} toolfaces (the straight-hole loads are toolface 0°'s)"
        ),
    );
    t
}

/// Toolfaces a rotating bend's revolution is averaged over (every 30°).
pub const ROTATING_TOOLFACES: usize = 12;

#[cfg(test)]
mod tests {
    use super::all_in_order;
    use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

    /// The first item in order that fails is the error, whichever fails first in time; the
    /// items after a failure that have not begun are not run; without a failure every
    /// result comes back in order.
    #[test]
    fn all_in_order_gives_the_first_failure_in_order_and_skips_the_rest() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let items: Vec<usize> = (0..12).collect();
        let ok = pool.install(|| all_in_order(&items, |&i| Ok::<_, usize>(10 * i)));
        assert_eq!(ok, Ok((0..12).map(|i| 10 * i).collect()));
        // Item 3 fails late, item 9 at once: the answer is item 3's.
        let calls = AtomicUsize::new(0);
        let r = pool.install(|| {
            all_in_order(&items, |&i| {
                calls.fetch_add(1, Relaxed);
                match i {
                    3 => {
                        std::thread::sleep(std::time::Duration::from_millis(50));
                        Err(3)
                    }
                    9 => Err(9),
                    _ => Ok(i),
                }
            })
        });
        assert_eq!(r, Err(3));
        assert!(calls.load(Relaxed) >= 4, "items 0–3 ran");
        // Item 0 fails at once: the others wait 10 ms each, and those not yet begun are
        // skipped (two threads: at most one other is in flight).
        let calls = AtomicUsize::new(0);
        let r = pool.install(|| {
            all_in_order(&items, |&i| {
                calls.fetch_add(1, Relaxed);
                if i == 0 {
                    return Err(0);
                }
                std::thread::sleep(std::time::Duration::from_millis(10));
                Ok(i)
            })
        });
        assert_eq!(r, Err(0));
        let ran = calls.load(Relaxed);
        assert!(ran <= 3, "{ran} of 12 items ran after item 0 failed");
    }
}
