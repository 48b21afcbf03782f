//! What a static profile says about buckling, and why a static solve failed: the checks a
//! drilling engineer makes before trusting (or instead of) a finite-element answer.
//!
//! Buckling loads of a string lying in an inclined hole (compression, N):
//! sinusoidal `F_s = max(2 √(EI w sin θ / r), 2.55 (EI w²)^(1/3))` (Dawson–Paslay; Lubinski's
//! vertical limit), helical `√2 F_s`, with `w` the buoyed weight per length, `θ` the
//! inclination and `r` the radial clearance. A helix of compression `F` has the pitch
//! `p = π √(8 EI / F)` (Lubinski).

use crate::case::Case;
use crate::model::Model;
use crate::solve::statics::StaticError;

mod past_yield;
mod whirl;
pub use past_yield::{past_yield, past_yield_warning, STRONGEST_API_YIELD_PA};
pub use whirl::{
    mark_span, mark_whirling_sites, rotating_whirl, rotating_whirl_of, whirl_reason, whirl_span,
    whirl_span_where_stopped, Whirl, NEAR_VERTICAL_DEG,
};

/// The sinusoidal and helical buckling loads of element `e` (N of compression) in a hole of
/// diameter `hole_diameter`.
pub fn critical_loads(model: &Model, e: usize, hole_diameter: f64) -> (f64, f64) {
    let el = &model.elements[e];
    let r = 0.5 * (hole_diameter - el.contact_diameter);
    let ei = el.section.bending_stiffness();
    let w = el.buoyed_weight_per_length.max(0.0);
    let t = model.nodes[e].hole_axis;
    let sin_i = (t[0] * t[0] + t[1] * t[1]).sqrt();
    let dawson_paslay = if r > 0.0 {
        2.0 * (ei * w * sin_i / r).sqrt()
    } else {
        f64::INFINITY
    };
    let sinusoidal = dawson_paslay.max(2.55 * (ei * w * w).cbrt());
    (sinusoidal, std::f64::consts::SQRT_2 * sinusoidal)
}

/// Sinusoidal and helical buckling flags of a profile of `model` (nodal axial forces,
/// tension +) in the case's hole: an element's compression beyond its sinusoidal (helical)
/// load anywhere. `model` may be a variant's (another depth) of the case's.
pub fn buckling(case: &Case, model: &Model, axial: &[f64]) -> (bool, bool) {
    let mut flags = (false, false);
    for e in 0..model.elements.len() {
        let f = -0.5 * (axial[e] + axial[e + 1]);
        if f <= 0.0 {
            continue;
        }
        let md = 0.5 * (model.nodes[e].md + model.nodes[e + 1].md);
        let (s, h) = critical_loads(model, e, case.hole_diameter_at(md));
        flags.0 |= f > s;
        flags.1 |= f > h;
    }
    flags
}

/// The worst ratio of compression to helical buckling load along a profile: (ratio, MD,
/// compression, helical load, helix pitch, element length) of the worst element.
fn worst_helical(case: &Case, axial: &[f64]) -> Option<(f64, f64, f64, f64, f64, f64)> {
    let model = &case.model;
    let mut worst: Option<(f64, f64, f64, f64, f64, f64)> = None;
    for e in 0..model.elements.len() {
        let f = -0.5 * (axial[e] + axial[e + 1]);
        if f <= 0.0 {
            continue;
        }
        let md = 0.5 * (model.nodes[e].md + model.nodes[e + 1].md);
        let (_, h) = critical_loads(model, e, case.hole_diameter_at(md));
        let ratio = f / h;
        if worst.is_none_or(|w| ratio > w.0) {
            let ei = model.elements[e].section.bending_stiffness();
            let pitch = std::f64::consts::PI * (8.0 * ei / f).sqrt();
            worst = Some((ratio, md, f, h, pitch, model.elements[e].length0));
        }
    }
    worst
}

/// The drag a helically buckled string adds to a soft-string profile, by Mitchell's wall
/// force of a helix `N = r F² / (4 EI)` per length (the contact a helix of compression `F`
/// presses on a wall of radial clearance `r`, beyond the weight's): `Σ μ N L` over the
/// elements whose compression passes their helical load (N). First order: `F` is the soft
/// string's, without the compression this drag adds itself (where that feedback runs away
/// the string locks up). The axial force a stiff string loses against a soft one where it
/// buckles helically is of this size.
pub fn helical_drag(case: &Case, axial: &[f64]) -> f64 {
    let model = &case.model;
    (0..model.elements.len())
        .map(|e| {
            let f = -0.5 * (axial[e] + axial[e + 1]);
            let md = 0.5 * (model.nodes[e].md + model.nodes[e + 1].md);
            let hole = case.hole_at(md);
            let (_, h) = critical_loads(model, e, hole.diameter);
            if f <= h {
                return 0.0;
            }
            let el = &model.elements[e];
            let r = 0.5 * (hole.diameter - el.contact_diameter);
            hole.friction * r * f * f / (4.0 * el.section.bending_stiffness()) * el.length0
        })
        .sum()
}

/// Compression beyond this many helical buckling loads ends [`lock_up`]'s profile: the
/// buckled string's wall force (quadratic in the compression) has run away there.
pub const LOCK_UP_RATIO: f64 = 100.0;

/// Where a string locks up: the soft string's compression runs away.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LockUp {
    /// MD where the compression passes [`LOCK_UP_RATIO`] helical loads (or runs out of
    /// numbers), m.
    pub md: f64,
    /// The compression at the bit end of the element where it ran away, N.
    pub compression_n: f64,
    /// That element's helical buckling load, N.
    pub helical_n: f64,
}

/// Lock-up, as a drilling engineer checks it: the soft string of the case's operation
/// carrying, beyond the weight's side force, the wall force of its own buckled shape —
/// Mitchell's `r F² / (8 EI)` per length past the sinusoidal load and `r F² / (4 EI)` past
/// the helical load (`F` the compression, `r` the radial clearance) — with the drag that
/// force adds feeding back into `F` (sub-steps of
/// [`crate::solve::soft_string::SUB_STEP`]). Pushed in or slid against friction, the
/// compression then grows like `tan`: it runs away within a finite length, and above that
/// point no push from the surface moves the string. `None` where it does not run away
/// before the surface. An FE static solve of such a load finds no equilibrium (its load
/// steps fold before the full load).
pub fn lock_up(case: &Case) -> Option<LockUp> {
    lock_up_at(case, 1.0)
}

/// [`lock_up`] with the friction coefficients and the bit loads scaled by `lambda` (the
/// FE load path's factor of its second stage,
/// [`crate::solve::continuation::LoadTarget`]).
pub fn lock_up_at(case: &Case, lambda: f64) -> Option<LockUp> {
    let model = &case.model;
    let mid = |e: usize| 0.5 * (model.nodes[e].md + model.nodes[e + 1].md);
    let friction_at = |md: f64| lambda * case.hole_at(md).friction;
    let extra = |e: usize, tension: f64| -> f64 {
        let f = -tension;
        if f <= 0.0 || !f.is_finite() {
            return if f.is_finite() { 0.0 } else { f64::INFINITY };
        }
        let hole = case.hole_at(mid(e)).diameter;
        let (s, h) = critical_loads(model, e, hole);
        let el = &model.elements[e];
        let r = 0.5 * (hole - el.contact_diameter);
        let ei = el.section.bending_stiffness();
        if r <= 0.0 || f <= s {
            0.0
        } else if f <= h {
            r * f * f / (8.0 * ei)
        } else {
            r * f * f / (4.0 * ei)
        }
    };
    let mut op = case.operation();
    op.weight_on_bit *= lambda;
    op.torque_on_bit *= lambda;
    op.friction *= lambda;
    let profile =
        crate::solve::soft_string::soft_string_loaded(model, &op, &friction_at, Some(&extra));
    (0..model.elements.len()).rev().find_map(|e| {
        let f = -profile.tension[e];
        let (_, h) = critical_loads(model, e, case.hole_at(mid(e)).diameter);
        (!f.is_finite() || f > LOCK_UP_RATIO * h).then(|| LockUp {
            md: model.nodes[e].md,
            compression_n: -profile.tension[e + 1],
            helical_n: h,
        })
    })
}

/// The load factor at which the string starts to lock up ([`lock_up_at`]): the smallest
/// `λ` in (0, 1] whose friction and bit loads run the buckled soft string away, to
/// [`LOCK_UP_FRACTION_TOLERANCE`] (bisection: more friction and more WOB only add
/// compression). `None` where it does not lock up at the full loads. An FE load path folds
/// near it where its mesh follows the helix.
pub fn lock_up_fraction(case: &Case) -> Option<f64> {
    lock_up_at(case, 1.0).map(|_| lock_up_onset(case))
}

/// [`lock_up_fraction`] of a case known to lock up at the full loads.
fn lock_up_onset(case: &Case) -> f64 {
    let (mut free, mut locked) = (0.0, 1.0);
    while locked - free > LOCK_UP_FRACTION_TOLERANCE {
        let mid = 0.5 * (free + locked);
        if lock_up_at(case, mid).is_some() {
            locked = mid;
        } else {
            free = mid;
        }
    }
    locked
}

/// The width of the interval [`lock_up_fraction`] returns the top of.
pub const LOCK_UP_FRACTION_TOLERANCE: f64 = 1e-3;

/// The largest WOB that keeps every element below its helical buckling load, if the
/// compression of each element falls one for one with the WOB (soft string, top clamped).
fn helical_free_wob(case: &Case, axial: &[f64]) -> f64 {
    let model = &case.model;
    (0..model.elements.len())
        .map(|e| {
            let f = -0.5 * (axial[e] + axial[e + 1]);
            let md = 0.5 * (model.nodes[e].md + model.nodes[e + 1].md);
            let (_, h) = critical_loads(model, e, case.hole_diameter_at(md));
            model.weight_on_bit - f + h
        })
        .fold(f64::INFINITY, f64::min)
        .max(0.0)
}

/// A warning for a solved FE profile of a load that locks up ([`lock_up`]): the FE found
/// an equilibrium at the full load (often on a mesh too coarse for the helix, which
/// [`unresolved_helix`] says), but the buckled soft string runs away from the load factor
/// [`lock_up_fraction`] on; `hook_load` is the FE's (N; below zero, the push the surface
/// must give). `None` where the load does not lock up.
pub fn locked_up_warning(case: &Case, hook_load: f64) -> Option<String> {
    let lu = lock_up(case)?;
    let from = lock_up_onset(case);
    Some(format!(
        "the load locks up: a soft string carrying its buckled shape's wall force (Mitchell) \
         runs away at MD {:.0} m, from {:.0} % of the friction and bit loads on; this \
         equilibrium (hook load {:.1} kN{}) is one the string does not reach by being run in",
        lu.md,
        100.0 * from,
        hook_load / 1e3,
        if hook_load < 0.0 {
            ": pushed from the surface"
        } else {
            ""
        }
    ))
}

/// A warning for an FE answer that came by relaxation past a fold (its solver `log` says so,
/// [`crate::solve::continuation::relaxed`]): a string buckled or held by its friction past
/// a fold has several equilibria, and which one the solve reaches depends on its path.
/// Measured (docs/performance.md, stops 72 and 89; docs/validation.md, stop 86): the beam
/// tangent changed at rounding level left every unrelaxed hook load within 1.4e-7 and moved
/// relaxed ones by up to 6.5 % (user seeds 0–289) and 8.1 % (drawn 283's −6.70 MN push to
/// −7.24 MN); the engine against the CPU, up to 6.7 % (drawn 3740) and 3.9 kN of 11.7 kN
/// (user 4386, friction-held near a lock-up). `None` where it did not relax.
pub fn relaxed_warning(log: &[String]) -> Option<String> {
    crate::solve::continuation::relaxed(log).then(|| {
        format!(
            "this equilibrium was reached by relaxation past a fold (a buckled or \
             friction-held string): {RELAXED_MEANS}"
        )
    })
}

/// What a relaxed answer means for its reader ([`relaxed_warning`]).
const RELAXED_MEANS: &str = "such a string has several equilibria, and which one a solve \
     reaches depends on its path — on the test corpora, rounding-level changes (the tangent \
     written another way, the GPU engine against the CPU) moved such answers' hook loads by \
     up to 8 % (a string pushed with 6.7 MN) and by 3.9 kN where the hook load was 11.7 kN \
     (33 %: near a lock-up the hook load is a small difference of weight and drag); read \
     hook load, torque and side forces as one equilibrium of several, to a few percent at \
     best, and a small hook load to a few kN";

/// The ensemble's form of [`relaxed_warning`]: `relaxed` of `variants` variants reached
/// their equilibria (`dynamic`: their dynamic runs' static starts) by relaxation past a
/// fold. `None` where none did.
pub fn relaxed_variants(relaxed: usize, variants: usize, dynamic: bool) -> Option<String> {
    (relaxed > 0).then(|| {
        let what = if dynamic {
            "started their dynamic runs from static equilibria reached"
        } else {
            "reached their equilibria"
        };
        format!(
            "{relaxed} of {variants} variants {what} by relaxation past a fold (variants.csv: \
             relaxed): {RELAXED_MEANS}"
        )
    })
}

/// A warning for a solved FE profile (nodal axial forces, tension +) whose compression
/// passes the helical buckling load where the elements are too long for the helix (fewer
/// than 4 per pitch): the answer is an equilibrium of the mesh, which carries less of the
/// helix's wall force and drag than the string does. `None` where no such element.
pub fn unresolved_helix(case: &Case, axial: &[f64]) -> Option<String> {
    let (ratio, md, f, h, pitch, length) = worst_helical(case, axial)?;
    (ratio > 1.0 && pitch < 4.0 * length).then(|| {
        format!(
            "the compression reaches {:.1} kN at MD {md:.0} m, {ratio:.1}× the helical buckling \
             load there ({:.1} kN): the string winds into a helix of pitch ≈ {pitch:.1} m, which \
             elements of {length:.1} m cannot follow (≥ 4 per pitch: mesh.element_length ≤ \
             {:.1} m); this answer carries less of the helix's drag than the string does \
             (Mitchell's estimate of that drag: {:.1} kN)",
            f / 1e3,
            h / 1e3,
            pitch / 4.0,
            helical_drag(case, axial) / 1e3
        )
    })
}

/// Lubinski's first-order buckling coefficient: a vertical column standing on its lower end
/// under its own weight `w` per length buckles once the load there passes `1.94 m w`, with
/// `m = (EI / w)^⅓` (Lubinski 1950, "A study of the buckling of rotary drilling strings").
pub const LUBINSKI_FIRST_ORDER: f64 = 1.94;

/// With contact at the stabilizers only (`contact.sites = "stabilizers"`), the string just
/// above the top stabilizer has nothing to hold it laterally: where the compression there
/// (`tension`, a soft-string profile, tension positive) passes its first-order buckling load
/// as a column under its own weight, `1.94 (EI w²)^⅓` ([`LUBINSKI_FIRST_ORDER`]; `w` the
/// axial part of the buoyed weight of the element above the stabilizer), the model lets it
/// bow out through the wall. Returns (MD of the stabilizer (m), compression (N), that load
/// (N)); `None` where it does not apply or is not passed.
pub fn unsupported_buckling(case: &Case, tension: &[f64]) -> Option<(f64, f64, f64)> {
    let model = &case.model;
    if model.sites.is_empty() || !model.sites.iter().all(|s| s.stabilizer) {
        return None;
    }
    let top = model.sites.iter().map(|s| s.node).min()?;
    if top == 0 || top >= tension.len() {
        return None;
    }
    let compression = -tension[top];
    let el = &model.elements[top - 1];
    let w = el.buoyed_weight_per_length * model.nodes[top].hole_axis[2].abs();
    if compression <= 0.0 || w <= 0.0 {
        return None;
    }
    let critical = LUBINSKI_FIRST_ORDER * (el.section.bending_stiffness() * w * w).cbrt();
    (compression > critical).then_some((model.nodes[top].md, compression, critical))
}

/// A node of a solved string is reported as through the wall when its lateral offset
/// passes its radial clearance by more than this (m): 1 mm, under a tenth of the smallest
/// clearance a corpus well draws, above the microns a wall spring lets a contact node in.
pub const THROUGH_WALL_TOLERANCE: f64 = 1e-3;

/// Where a solved string lies outside the hole at nodes that have no contact site
/// ([`through_wall`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThroughWall {
    /// MD of the node furthest outside (m).
    pub md: f64,
    /// How far it is outside: lateral offset less radial clearance (m).
    pub excess_m: f64,
    /// Nodes outside by more than [`THROUGH_WALL_TOLERANCE`].
    pub nodes: usize,
    /// MD of the shallowest and the deepest of them (m).
    pub first_md: f64,
    /// See `first_md`.
    pub last_md: f64,
}

/// The nodes of a solved configuration `x` of `model` (a case's, or a variant's of it)
/// that lie outside the hole of `case` and have no contact site to hold them: each node's
/// lateral offset — its displacement from the hole axis with the part along the axis
/// removed, as a contact site measures it — against the radial clearance of the wider of
/// its two elements (tool joints included). With `contact.sites = "stabilizers"` only
/// the stabilizers meet the wall; a string compressed past its buckling load between them
/// bows out through the wall, and the FE answer (its side forces above all) is then an
/// equilibrium of a string in no hole. `None` where no node is outside by more than
/// [`THROUGH_WALL_TOLERANCE`].
pub fn through_wall(
    case: &Case,
    model: &Model,
    state: &crate::solve::statics::StaticState,
) -> Option<ThroughWall> {
    let mut out: Option<ThroughWall> = None;
    for (i, excess) in beyond_wall(case, model, state) {
        if excess <= THROUGH_WALL_TOLERANCE {
            continue;
        }
        let md = model.nodes[i].md;
        let t = out.get_or_insert(ThroughWall {
            md,
            excess_m: excess,
            nodes: 0,
            first_md: md,
            last_md: md,
        });
        t.nodes += 1;
        t.last_md = md;
        if excess > t.excess_m {
            t.excess_m = excess;
            t.md = md;
        }
    }
    out
}

/// Every node of `state` without a contact site that lies beyond the wall of `case`'s hole at
/// all, with how far (m), measured as [`through_wall`] measures it (there: only those
/// beyond [`THROUGH_WALL_TOLERANCE`] count). The nodes a static solve gives contact sites
/// ([`crate::profile::solve_in_hole`]).
pub fn beyond_wall(
    case: &Case,
    model: &Model,
    state: &crate::solve::statics::StaticState,
) -> Vec<(usize, f64)> {
    let held = model.site_nodes();
    let mut out = Vec::new();
    for (i, node) in model.nodes.iter().enumerate() {
        if held[i] {
            continue;
        }
        let excess = lateral_offset(model, state, i)
            - (0.5 * case.hole_at(node.md).diameter - model.pipe_radius_at(i));
        if excess > 0.0 {
            out.push((i, excess));
        }
    }
    out
}

/// Node `i`'s lateral offset in `state` (m): its displacement from its hole axis with the
/// part along the axis removed, as a contact site measures it.
fn lateral_offset(model: &Model, state: &crate::solve::statics::StaticState, i: usize) -> f64 {
    use crate::physics::vec3::{dot, scale, sub};
    let node = &model.nodes[i];
    let d = state.u[i];
    let d_t = sub(&d, &scale(&node.hole_axis, dot(&d, &node.hole_axis)));
    dot(&d_t, &d_t).sqrt()
}

/// [`through_wall`]'s warning for a solved FE profile, `None` where the string is in the
/// hole.
pub fn through_wall_warning(
    case: &Case,
    model: &Model,
    state: &crate::solve::statics::StaticState,
) -> Option<String> {
    let t = through_wall(case, model, state)?;
    Some(format!(
        "the string lies outside the hole at {} nodes without a contact site between MD \
         {:.0} m and {:.0} m, up to {:.0} mm beyond the wall (at MD {:.0} m): this is the equilibrium of a string partly \
         in no hole — its side forces and bending above all; use contact.sites = \"all_nodes\"",
        t.nodes,
        t.first_md,
        t.last_md,
        1e3 * t.excess_m,
        t.md,
    ))
}

/// The fraction of its clearance by which a span's middle sags beyond the wall before
/// `holewall static` warns ([`span_through_wall_warning`]; `corpus.csv` reports every sag
/// past [`THROUGH_WALL_TOLERANCE`]).
pub const SPAN_SAG_WARNING: f64 = 0.25;

/// Where a solved string's pipe sags through the wall between its nodes
/// ([`span_through_wall`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpanSag {
    /// MD of the middle of the element that sags furthest (m).
    pub md: f64,
    /// How far its middle lies beyond the wall (m).
    pub excess_m: f64,
    /// Elements beyond the wall by more than [`THROUGH_WALL_TOLERANCE`].
    pub elements: usize,
    /// MD of the middle of the shallowest and the deepest of them (m).
    pub first_md: f64,
    /// See `first_md`.
    pub last_md: f64,
    /// Length of the element that sags furthest (m).
    pub element_m: f64,
    /// The pipe body's radial clearance at its middle (m).
    pub clearance_m: f64,
    /// The length at which that element's own weight would bend it
    /// [`THROUGH_WALL_TOLERANCE`] between clamped ends (m): `(384 EI · tol / q)^¼`.
    pub suggested_m: f64,
}

/// Mid-span deflection (m) of a span of length `l` clamped at both ends under a uniform
/// lateral load `q` (N/m), bending stiffness `ei`, axial tension `t` (N; compression and
/// zero: the bending beam's `q l⁴ / 384 EI`, which compression would only raise):
/// `EI w⁗ − T w″ = q` gives `q l / (2 T λ) (z − tanh z)`, `λ = √(T/EI)`, `z = λ l / 4`.
pub fn clamped_span_sag(q: f64, l: f64, ei: f64, t: f64) -> f64 {
    let bending = q * l.powi(4) / (384.0 * ei);
    if t <= 0.0 {
        return bending;
    }
    let lambda = (t / ei).sqrt();
    let z = 0.25 * lambda * l;
    if z < 0.05 {
        // z − tanh z = z³/3 − 2z⁵/15 + 17z⁷/315 − …
        bending * (1.0 - 0.4 * z * z + 17.0 / 105.0 * z.powi(4))
    } else {
        q * l / (2.0 * t * lambda) * (z - z.tanh())
    }
}

/// The elements of a solved configuration (`x`, nodal rotations `rot`; `axial` each
/// element's axial force, tension positive) of `model` whose pipe passes through the wall
/// of `case`'s hole between the nodes, where nothing holds it there. An element whose two
/// nodes are contact sites is not checked: its span's wall support is integrated at the
/// nodes, as its weight is ([`crate::solve::statics::external_loads`]), so a span that
/// would sag onto the wall between them is one the wall carries. Between nodes without a
/// site on both ends the FE's pipe is the element's cubic (from the nodes' positions and
/// tangents) plus the sag of its own weight across the span ([`clamped_span_sag`] of the
/// weight's part across the hole), and the wall is not there for it. Each element's middle
/// is measured as [`through_wall`] measures a node, against the hole's axis at its MD (the
/// cubic through the nodes' axis points and tangents) and the pipe body's clearance, or
/// the nodes' own offsets where a soft wall lets them further. `None` where no such
/// element's middle is beyond the wall by more than [`THROUGH_WALL_TOLERANCE`].
pub fn span_through_wall(
    case: &Case,
    model: &Model,
    state: &crate::solve::statics::StaticState,
    axial: &[f64],
) -> Option<SpanSag> {
    use crate::physics::vec3::{add, dot, scale, sub};
    let turn = |r: &crate::physics::rotation::Mat3<f64>, v: &[f64; 3]| -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|k| r[i][k] * v[k]).sum())
    };
    // The cubic's middle from end points and unit tangents over a length `l`.
    let middle = |a: &[f64; 3], b: &[f64; 3], ta: &[f64; 3], tb: &[f64; 3], l: f64| {
        add(&scale(&add(a, b), 0.5), &scale(&sub(ta, tb), l / 8.0))
    };
    let mut out: Option<SpanSag> = None;
    let site = model.site_nodes();
    for (i, e) in model.elements.iter().enumerate() {
        if site[i] && site[i + 1] {
            continue;
        }
        let (na, nb) = (&model.nodes[i], &model.nodes[i + 1]);
        let l = e.length0;
        let axis_mid = middle(&na.position, &nb.position, &na.hole_axis, &nb.hole_axis, l);
        let ta = turn(&state.rot[i], &na.hole_axis);
        let tb = turn(&state.rot[i + 1], &nb.hole_axis);
        let pipe_mid = middle(
            &state.position(model, i),
            &state.position(model, i + 1),
            &ta,
            &tb,
            l,
        );
        let sum = add(&na.hole_axis, &nb.hole_axis);
        let t = scale(&sum, 1.0 / dot(&sum, &sum).sqrt());
        let across = |v: &[f64; 3]| sub(v, &scale(&t, dot(v, &t)));
        // The weight's part across the hole (gravity along +z) sags the span.
        let g_across = across(&[0.0, 0.0, 1.0]);
        let s = dot(&g_across, &g_across).sqrt();
        let q = e.buoyed_weight_per_length.max(0.0) * s;
        let ei = e.section.bending_stiffness();
        let sag = if s > 0.0 {
            let tension = axial.get(i).copied().unwrap_or(0.0);
            scale(&g_across, clamped_span_sag(q, l, ei, tension) / s)
        } else {
            [0.0; 3]
        };
        let d = across(&add(&sub(&pipe_mid, &axis_mid), &sag));
        let md = 0.5 * (na.md + nb.md);
        // Beyond the wall, or beyond the nodes where their springs let them into it: the
        // span's own sag, not the wall's give.
        let clearance = 0.5 * (case.hole_at(md).diameter - e.outer_diameter);
        let allowed = clearance
            .max(lateral_offset(model, state, i))
            .max(lateral_offset(model, state, i + 1));
        let excess = dot(&d, &d).sqrt() - allowed;
        if excess <= THROUGH_WALL_TOLERANCE {
            continue;
        }
        let suggested = if q > 0.0 {
            (384.0 * ei * THROUGH_WALL_TOLERANCE / q).powf(0.25)
        } else {
            l
        };
        let w = out.get_or_insert(SpanSag {
            md,
            excess_m: excess,
            elements: 0,
            first_md: md,
            last_md: md,
            element_m: l,
            clearance_m: clearance,
            suggested_m: suggested,
        });
        w.elements += 1;
        w.last_md = md;
        if excess > w.excess_m {
            w.excess_m = excess;
            w.md = md;
            w.element_m = l;
            w.clearance_m = clearance;
            w.suggested_m = suggested;
        }
    }
    out
}

/// [`span_through_wall`]'s warning for a solved FE profile where a span sags beyond the
/// wall by more than [`SPAN_SAG_WARNING`] of its clearance, `None` elsewhere.
pub fn span_through_wall_warning(
    case: &Case,
    model: &Model,
    state: &crate::solve::statics::StaticState,
    axial: &[f64],
) -> Option<String> {
    let w = span_through_wall(case, model, state, axial)?;
    if w.excess_m <= SPAN_SAG_WARNING * w.clearance_m {
        return None;
    }
    Some(format!(
        "between its nodes, where no contact site holds it, the pipe sags through the wall \
         in {} elements (MD {:.0}–{:.0} m), up to {:.0} mm at MD {:.0} m (its {:.1} m \
         element): the FE does not see that contact, so the side forces and the drag there \
         are missing; contact at every node (`contact.sites = \"all_nodes\"`) would hold it, or \
         elements of {:.1} m or less there (a sag within {:.0} mm) put a node where it meets \
         the wall",
        w.elements,
        w.first_md,
        w.last_md,
        1e3 * w.excess_m,
        w.md,
        w.element_m,
        w.suggested_m,
        1e3 * THROUGH_WALL_TOLERANCE,
    ))
}

/// Whether the operation runs the string in or out (tripping, sliding, reaming): only then
/// has a failed load path's bracket a place where the string stops; a string turning on
/// or off bottom has an equilibrium up to some load and none found past it.
pub fn stops(model: &Model) -> bool {
    model.axial_speed != 0.0
}

/// A failed static solve's message with the likely reason, from the case's soft-string
/// profile at full load: compression beyond the helical buckling load (the string winds
/// into a helix the mesh may not resolve), or the load factor it stopped at.
pub fn static_failure(case: &Case, error: &StaticError) -> String {
    use crate::solve::continuation::LOCK_FOUND;
    let mut msg = format!("the static solve failed: {error}");
    let from = error.reached();
    let model = &case.model;
    // The stage, by its name: a load step whose relaxation failed has no smallest step to
    // name either (`step` 0, since stop 56), and was read as the gravity stage here.
    let gravity = error.in_gravity_stage();
    if gravity {
        msg.push_str(
            "\n  the string found no equilibrium under its own weight: the bit loads and \
             friction were not applied yet",
        );
    } else if model.weight_on_bit > 0.0 {
        msg.push_str(&format!(
            "\n  it reached {:.1} % of the bit loads and friction (WOB {:.1} kN of {:.1} kN)",
            100.0 * from,
            from * model.weight_on_bit / 1e3,
            model.weight_on_bit / 1e3
        ));
    } else {
        msg.push_str(&format!(
            "\n  it reached {:.1} % of the friction (and other loads) of the operation",
            100.0 * from
        ));
    }
    match error {
        StaticError::LoadStep { reason, .. } if reason.contains(LOCK_FOUND) && stops(model) => {
            msg.push_str(
                "\n  that is where the string stops on this model, to within the loads named \
                 above: an equilibrium there, none found at the larger one",
            );
        }
        StaticError::LoadStep { reason, .. } if reason.contains(LOCK_FOUND) => {
            // Not run in or out, the string has nowhere to stop: past the bracket this
            // model has no static answer (probe well 24 of stop 68: drilling, it whirls).
            msg.push_str(
                "\n  this model has an equilibrium there and none found at the larger load (to \
                 within the loads named above); a string not run in or out does not stop, so \
                 past that load it has no static answer on this model",
            );
        }
        StaticError::LoadStep { .. } if !gravity => {
            // Corpus well 419 (tripping in, 2 m elements) failed past 25 % of its loads
            // before its path bracketed, yet the case with its friction scaled to 0.4–0.7
            // solves from its own load path.
            msg.push_str(
                "\n  that is the last equilibrium on this load path, not where the string \
                 stops: equilibria at larger loads may exist (the case with its hole \
                 friction scaled down solves on a path of its own and shows how far the \
                 string runs in)",
            );
        }
        _ => {}
    }
    if matches!(error, StaticError::LoadStep { .. }) {
        let top_element = model
            .elements
            .iter()
            .filter(|e| {
                model
                    .elements
                    .first()
                    .is_some_and(|f| f.component == e.component)
            })
            .map(|e| e.length0)
            .fold(f64::INFINITY, f64::min);
        msg.push_str(&format!(
            "\n  what to try: another mesh.element_length (now {:.1} m at the top; contacts \
             that change along many short elements take the Newton one node per iteration), \
             a softer contact.wall_stiffness, or `--model soft-string` for torque and drag \
             alone",
            top_element
        ));
    }
    // The stiffest wall against the string's own lateral stiffness at that site (a beam
    // of the adjacent element's length, centrally loaded: 48 EI / L³).
    let ratio = model
        .sites
        .iter()
        .map(|site| {
            let e = site.node.min(model.elements.len() - 1);
            let el = &model.elements[e];
            let lateral = 48.0 * el.section.bending_stiffness() / el.length0.powi(3);
            (
                site.params.wall_stiffness / lateral,
                site.params.spring_exponent,
            )
        })
        .fold((0.0f64, 1.0f64), |a, b| if b.0 > a.0 { b } else { a });
    if ratio.0 > 1e6 || ratio.1 < 1.0 {
        msg.push_str(&format!(
            "\n  the wall is stiff against the string: k_e / (48 EI / L³) up to {:.1e}{}; \
             contacts switching at that stiffness need many small load steps",
            ratio.0,
            if ratio.1 < 1.0 {
                format!(
                    ", with a soft law (m = {}) stiffer still at first contact",
                    ratio.1
                )
            } else {
                String::new()
            }
        ));
    }
    let profile = case.soft_string();
    if let Some((md, f, critical)) = unsupported_buckling(case, &profile.tension) {
        msg.push_str(&format!(
            "\n  likely reason: with contact.sites = \"stabilizers\" nothing holds the string \
             above the top stabilizer (MD {md:.0} m) laterally, and its compression there at \
             full load, {:.1} kN, passes its first-order buckling load as a column under its \
             own weight ({:.1} kN, Lubinski: 1.94 (EI w²)^⅓): it bows out through the wall; \
             use contact.sites = \"all_nodes\"",
            f / 1e3,
            critical / 1e3
        ));
    }
    if let Some(reason) = whirl_reason(case, &profile) {
        msg.push_str(&reason);
    }
    if let crate::model::TopBoundary::Clamped = model.top {
        if let Some((ratio, md, f, h, pitch, length)) = worst_helical(case, &profile.tension) {
            if ratio > 1.0 {
                msg.push_str(&format!(
                    "\n  likely reason: at full load the compression reaches {:.1} kN at MD {:.0} m, \
                     {ratio:.1}× the helical buckling load there ({:.1} kN, Dawson–Paslay × √2): \
                     the string winds into a helix of pitch ≈ {pitch:.1} m against the wall",
                    f / 1e3,
                    md,
                    h / 1e3
                ));
                if pitch < 4.0 * length {
                    msg.push_str(&format!(
                        ", which elements of {length:.1} m cannot follow (a helix needs ≥ 4 per \
                         pitch: mesh.element_length ≤ {:.1} m)",
                        pitch / 4.0
                    ));
                }
                msg.push_str(&format!(
                    "; a WOB below ≈ {:.0} kN keeps the string out of helical buckling \
                     (soft string: compression falls with the WOB one for one)",
                    helical_free_wob(case, &profile.tension) / 1e3
                ));
            }
        }
        if let Some(lu) = lock_up(case) {
            msg.push_str(&format!(
                "\n  lock-up: a soft string carrying its buckled shape's wall force (Mitchell) \
                 runs away at MD {:.0} m (compression past {LOCK_UP_RATIO}× the helical load \
                 of {:.1} kN): above it no push from the surface moves the string, and this \
                 load may have no equilibrium",
                lu.md,
                lu.helical_n / 1e3
            ));
        } else if model.axial_speed > 0.0 && profile.hook_load() < 0.0 {
            msg.push_str(&format!(
                "\n  the soft string's hook load is {:.1} kN: running in, the string must be \
                 pushed from the surface (the weight indicator's lock-up)",
                profile.hook_load() / 1e3
            ));
        }
    }
    msg
}

#[cfg(test)]
mod tests;
