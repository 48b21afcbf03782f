//! The static configuration ([`StaticState`]) and its first guesses: the string laid in the
//! hole, prestressed by the soft string's stretch and lifted off near held points (the load
//! path's start). Split from `solve/statics.rs` (issue 24: no file over 800 lines),
//! behaviour unchanged.

use super::*;

/// Nodal configuration: each node's displacement from its place on the hole axis
/// (`Model::nodes[i].position`) and its rotation.
///
/// The displacements, not the positions, are the unknowns, as in the engine (its
/// configuration is kept from the reference, `crate::engine`): a position 1,500 m from the
/// surface is rounded to 2.3e-13 m, and a contact's penetration is a difference of two
/// such positions. On a stiff soft-law wall (k_e = 1e11 N/m^m, m = 2/3; onset stiffness
/// ≈ 6e12 N/m) that rounding alone moved the contact forces by about 1 N, a residual of a
/// few 1e-6 of the force scale that no Newton update could lower; kept as displacements
/// (millimetres, rounded to 1e-19 m) the same solve converges (docs/stability.md).
#[derive(Clone, Debug)]
pub struct StaticState {
    /// Node displacements from their places on the hole axis (m).
    pub u: Vec<Vec3<f64>>,
    /// Nodal rotations (from the initial configuration).
    pub rot: Vec<Mat3<f64>>,
}

impl StaticState {
    /// Node `i`'s position (its place on the hole axis plus its displacement).
    pub fn position(&self, model: &Model, i: usize) -> Vec3<f64> {
        let p = model.nodes[i].position;
        std::array::from_fn(|k| p[k] + self.u[i][k])
    }

    /// Every node's position ([`StaticState::position`]).
    pub fn positions(&self, model: &Model) -> Vec<Vec3<f64>> {
        (0..self.u.len()).map(|i| self.position(model, i)).collect()
    }

    /// A first guess near the equilibrium under gravity (the load path's first stage), from
    /// the frictionless soft-string solution without bit loads (issue 22):
    /// - **prestressed**: each node moved along its hole axis by the stretch `∫ F/EA` of
    ///   the string above it (below it where the top is free axially), so the first
    ///   tangent carries the tension's geometric stiffness — without it a vertical section
    ///   under kilometres of pipe has only its bending stiffness laterally, and the first
    ///   Newton step throws it metres through the wall;
    /// - **laid on the wall** where a cable would lie: every contact node along the
    ///   lateral load `q = F·dt/ds + w·g_⊥` (tension `F` pulls the string to the inside of a
    ///   bend, weight to the low side), at the depth where the wall carries its share;
    /// - **lifting off near held points**: within the bending length of the top, the bit
    ///   and each stabilizer, the offset grows as a pinned beam's deflection (a collar
    ///   node 0.3 m above a bit held on the axis, laid on the wall, bends the collar with
    ///   hundreds of MN).
    ///
    /// - **turning around the wall** where the lateral load flips side between
    ///   neighbouring nodes (`turn_around_side_flips`).
    ///
    /// This is where every static solve with contact sites starts
    /// ([`super::static_start`]). (A second start without the turns, tried where the
    /// gravity stage failed from this one, was removed in issue 24: since the gravity stage
    /// relaxes, none of the 500 corpus wells reached it — the same wells solved with the
    /// same Newton iterations, 167,033, without it.)
    pub fn on_low_side(model: &Model) -> StaticState {
        use crate::solve::soft_string::{soft_string, Operation};
        let mut s = StaticState::initial(model);
        let n = model.nodes.len();
        let cable = soft_string(
            model,
            &Operation {
                axial_speed: 0.0,
                rotation_speed: 0.0,
                weight_on_bit: 0.0,
                torque_on_bit: 0.0,
                friction: 0.0,
            },
        );
        // Axial prestress: each node moved along its hole axis by the stretch of the
        // string above it (below it where the top is free axially).
        let stretch: Vec<f64> = (0..n - 1)
            .map(|e| {
                let el = &model.elements[e];
                0.5 * (cable.tension[e] + cable.tension[e + 1]) * el.length0
                    / (el.section.youngs_modulus * el.section.area)
            })
            .collect();
        let mut u = vec![0.0; n];
        if matches!(model.top, TopBoundary::Clamped | TopBoundary::Pinned) {
            for e in 0..n - 1 {
                u[e + 1] = u[e] + stretch[e];
            }
        } else {
            for e in (0..n - 1).rev() {
                u[e] = u[e + 1] - stretch[e];
            }
        }
        for ((x, ui), node) in s.u.iter_mut().zip(&u).zip(&model.nodes) {
            for (xk, tk) in x.iter_mut().zip(node.hole_axis) {
                *xk += ui * tk;
            }
        }
        // Lateral: each contact node towards its lateral load, at the depth where the wall
        // carries the node's share of it.
        let mut offset: Vec<Option<(Vec3<f64>, f64)>> = vec![None; n];
        let mut load = vec![0.0; n];
        for site in &model.sites {
            let i = site.node;
            let held = i == 0 || (model.bit_lateral_fixed && i + 1 == n);
            if held {
                continue;
            }
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let ds = model.nodes[b].md - model.nodes[a].md;
            let dt = scale(
                &sub(&model.nodes[b].hole_axis, &model.nodes[a].hole_axis),
                1.0 / ds,
            );
            let t = model.nodes[i].hole_axis;
            let g = [0.0, 0.0, 1.0];
            let g_perp = sub(&g, &scale(&t, dot(&g, &t)));
            let w = model.elements[i.min(n - 2)].buoyed_weight_per_length;
            let q = [
                cable.tension[i] * dt[0] + w * g_perp[0],
                cable.tension[i] * dt[1] + w * g_perp[1],
                cable.tension[i] * dt[2] + w * g_perp[2],
            ];
            // Lateral part only.
            let q = sub(&q, &scale(&t, dot(&q, &t)));
            let len = dot(&q, &q).sqrt();
            if len > 1e-3 * w.abs().max(1e-12) {
                // Penetration at which the wall carries the node's share of the lateral
                // load (bisection on the spring law): a fixed guess would be far too deep for
                // a stiff wall (k_e = 1e11 with a soft spring) and far too shallow for a soft one.
                let share = len * 0.5 * ds;
                let depth = site.params.clearance + penetration_for(share, &site.params);
                offset[i] = Some((scale(&q, 1.0 / len), depth));
                load[i] = len;
            }
        }
        // Bending: next to a point held on or close to the axis (the top, the bit, a
        // stabilizer) the string cannot reach the wall at once; it lifts off over its
        // bending length, the tangency length of a pinned beam under its lateral load q,
        // `L = (24 EI c / q)^¼` (c the clearance), shortened by tension T to `4 √(EI/T)`.
        let bending_length = |site: &crate::model::Site| {
            let i = site.node;
            let ei = model.elements[i.min(n - 2)].section.bending_stiffness();
            let c = site.params.clearance.max(1e-6);
            let mut l = (24.0 * ei * c / load[i].max(1e-12)).powf(0.25);
            if cable.tension[i] > 0.0 {
                l = l.min(4.0 * (ei / cable.tension[i]).sqrt());
            }
            l
        };
        // Whether there is a flip to turn: without the turns, found on a copy.
        let site_length = |i: usize| {
            model
                .sites
                .iter()
                .find(|s| s.node == i)
                .map_or(0.0, bending_length)
        };
        turn_around_side_flips(model, &mut offset, site_length);
        // Offset `m_a + (m − m_a) g(s/L)` within L of an anchor (offset m_a), with
        // `g(x) = 2x − 2x³ + x⁴` the pinned beam's deflection (g(1) = 1, g'(1) = 0).
        let ramp = |x: f64| 2.0 * x - 2.0 * x.powi(3) + x.powi(4);
        let mut magnitude: Vec<f64> = offset.iter().map(|o| o.map_or(0.0, |o| o.1)).collect();
        let mut anchors: Vec<(usize, f64)> = vec![(0, 0.0)];
        if model.bit_lateral_fixed {
            anchors.push((n - 1, 0.0));
        }
        // First the stabilizers against the top and the bit, then every other node against
        // those and the stabilizers.
        for stabilizers in [true, false] {
            for site in model.sites.iter().filter(|s| s.stabilizer == stabilizers) {
                let i = site.node;
                let Some((_, m)) = offset[i] else { continue };
                if anchors.iter().any(|a| a.0 == i) {
                    continue;
                }
                let l = bending_length(site);
                let below = anchors.iter().filter(|a| a.0 > i).min_by_key(|a| a.0);
                let above = anchors.iter().filter(|a| a.0 < i).max_by_key(|a| a.0);
                for &(k, m_a) in below.into_iter().chain(above) {
                    let d = (model.nodes[i].md - model.nodes[k].md).abs();
                    if d < l && m_a < m {
                        magnitude[i] = magnitude[i].min(m_a + (m - m_a) * ramp(d / l));
                    }
                }
            }
            if stabilizers {
                for site in model.sites.iter().filter(|s| s.stabilizer) {
                    anchors.push((site.node, magnitude[site.node]));
                }
            }
        }
        for i in 0..n {
            if let Some((dir, _)) = offset[i] {
                for (x, d) in s.u[i].iter_mut().zip(dir) {
                    *x += magnitude[i] * d;
                }
            }
        }
        s
    }

    /// The undeformed configuration (every node on the hole axis, no rotation).
    pub fn initial(model: &Model) -> StaticState {
        let eye = rotation_exp(&[0.0; 3]);
        StaticState {
            u: vec![[0.0; 3]; model.nodes.len()],
            rot: vec![eye; model.nodes.len()],
        }
    }
}

/// Where the lateral load turns by more than a right angle between neighbouring nodes —
/// at a survey station of a near-vertical section, where the dogleg's direction changes
/// and the tension pulls the string the other way — a start laid towards each node's own
/// load jumps across the hole within one element (corpus well 464, 1 m elements: 0.18 m
/// in 1 m at MD 30 m, a residual of 1.2e7 N against a force scale of 1e6). A string turns
/// around the wall instead: over its bending length `l` about the flip (half each side,
/// at least the neighbours) the direction rotates about the hole axis at a constant rate
/// per metre from the one before the window to the one after it. The magnitudes (the
/// depth on the wall) are the nodes' own; a node without an offset ends a window.
fn turn_around_side_flips(
    model: &Model,
    offset: &mut [Option<(Vec3<f64>, f64)>],
    bending_length: impl Fn(usize) -> f64,
) {
    let n = offset.len();
    let md = |i: usize| model.nodes[i].md;
    let lateral = |v: &Vec3<f64>, t: &Vec3<f64>| {
        let p = sub(v, &scale(t, dot(v, t)));
        let len = dot(&p, &p).sqrt();
        (len > 0.0).then(|| scale(&p, 1.0 / len))
    };
    let mut i = 0;
    while i + 1 < n {
        let (Some((d0, _)), Some((d1, _))) = (offset[i], offset[i + 1]) else {
            i += 1;
            continue;
        };
        if dot(&d0, &d1) >= 0.0 {
            i += 1;
            continue;
        }
        let mid = 0.5 * (md(i) + md(i + 1));
        let half = 0.5 * bending_length(i).max(bending_length(i + 1));
        let mut a = i;
        while a > 0 && offset[a - 1].is_some() && md(a) > mid - half {
            a -= 1;
        }
        let mut b = i + 1;
        while b + 1 < n && offset[b + 1].is_some() && md(b) < mid + half {
            b += 1;
        }
        let t = model.nodes[i].hole_axis;
        let (Some((da, _)), Some((db, _))) = (offset[a], offset[b]) else {
            i = b;
            continue;
        };
        let (Some(pa), Some(pb)) = (lateral(&da, &t), lateral(&db, &t)) else {
            i = b;
            continue;
        };
        let phi = dot(&t, &cross(&pa, &pb)).atan2(dot(&pa, &pb));
        // Rodrigues about the hole axis, `pa` being across it: `pa cos α + (t × pa) sin α`.
        let quarter = cross(&t, &pa);
        for (k, slot) in offset.iter_mut().enumerate().take(b).skip(a + 1) {
            let tk = model.nodes[k].hole_axis;
            let angle = phi * (md(k) - md(a)) / (md(b) - md(a));
            let (sn, cs) = angle.sin_cos();
            let turned: Vec3<f64> = std::array::from_fn(|r| pa[r] * cs + quarter[r] * sn);
            if let (Some(dir), Some(o)) = (lateral(&turned, &tk), slot.as_mut()) {
                o.0 = dir;
            }
        }
        i = b;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A string laid on one side and, from node 20 on, on the other: the start turns
    /// around the wall over the bending length, by less than a right angle per element,
    /// across the axis, and leaves the nodes outside the window as they were.
    #[test]
    fn a_side_flip_turns_around_the_wall_over_the_bending_length() {
        let model = crate::model::vertical_collar(40.0, 40, 1200.0);
        let n = model.nodes.len();
        let (x, y) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let flipped = |i: usize| if i < 20 { x } else { scale(&x, -1.0) };
        let mut offset: Vec<Option<(Vec3<f64>, f64)>> =
            (0..n).map(|i| Some((flipped(i), 0.05))).collect();
        offset[0] = None;
        let before = offset.clone();
        turn_around_side_flips(&model, &mut offset, |_| 8.0);
        let dirs: Vec<Vec3<f64>> = offset[1..].iter().map(|o| o.unwrap().0).collect();
        for d in &dirs {
            assert!((dot(d, d).sqrt() - 1.0).abs() < 1e-12);
            assert!(dot(d, &model.nodes[1].hole_axis).abs() < 1e-12);
        }
        let largest_turn = dirs
            .windows(2)
            .map(|w| dot(&w[0], &w[1]).clamp(-1.0, 1.0).acos())
            .fold(0.0f64, f64::max);
        // π over the window from MD 15 to 24 m (9 elements): 20° per element.
        assert!(
            (largest_turn - std::f64::consts::PI / 9.0).abs() < 1e-9,
            "{largest_turn}"
        );
        // Halfway round, the string is across the axis: along y (or −y).
        let mid = offset[19].unwrap().0;
        assert!(dot(&mid, &y).abs() > 0.9, "{mid:?}");
        for i in (1..15).chain(25..n) {
            assert_eq!(offset[i], before[i], "node {i}");
        }
        for o in &offset[15..25] {
            assert_eq!(o.unwrap().1, 0.05);
        }
        // No flip, no change.
        let mut same: Vec<Option<(Vec3<f64>, f64)>> = (0..n).map(|_| Some((x, 0.05))).collect();
        let copy = same.clone();
        turn_around_side_flips(&model, &mut same, |_| 8.0);
        assert_eq!(same, copy);
    }
}
