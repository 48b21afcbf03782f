//! A load step's model and parameters, and a converged configuration's solution (section
//! forces, contact forces and penetrations, reactions). Split from `solve/statics.rs`
//! (issue 24: no file over 800 lines), behaviour unchanged.

use super::*;

/// The model with a load target's friction factor and spring-exponent blend applied to
/// every site (the parameters the contact elements of that step use).
pub fn loaded_model(model: &Model, target: &crate::solve::continuation::LoadTarget) -> Model {
    let mut m = model.clone();
    for site in &mut m.sites {
        site.params = loaded_params(&site.params, target);
    }
    // Kinks grow with the bit loads (from the straight string laid in the hole).
    for b in &mut m.bends {
        b.angle *= target.lambda;
    }
    m
}

/// The model at a target of its load path with gravity in full: [`loaded_model`]'s
/// friction, spring exponents and bends, and the bit loads and point loads at the fraction
/// `target.lambda` (the loads [`crate::solve::continuation`] solves a step for), so that a
/// state the path reached there is an equilibrium of this model.
pub fn model_at(model: &Model, target: &crate::solve::continuation::LoadTarget) -> Model {
    let mut m = loaded_model(model, target);
    m.weight_on_bit *= target.lambda;
    m.torque_on_bit *= target.lambda;
    for (_, load) in &mut m.point_loads {
        for f in load.iter_mut() {
            *f *= target.lambda;
        }
    }
    m
}

/// A site's law parameters at a load target: friction scaled, exponent blended from 1.
pub fn loaded_params(
    p: &crate::physics::contact::ContactParams<f64>,
    target: &crate::solve::continuation::LoadTarget,
) -> crate::physics::contact::ContactParams<f64> {
    let mut q = *p;
    q.mu_t *= target.friction;
    q.mu_l *= target.friction;
    if target.exponent != 1.0 {
        q.spring_exponent = 1.0 + target.exponent * (p.spring_exponent - 1.0);
    }
    q
}

/// Gravity loads and the other external loads (bit, point loads), at full value.
pub fn split_loads(model: &Model) -> (Vec<f64>, Vec<f64>) {
    let mut bare = model.clone();
    bare.weight_on_bit = 0.0;
    bare.torque_on_bit = 0.0;
    bare.point_loads.clear();
    let gravity = external_loads(&bare);
    let all = external_loads(model);
    let other = all.iter().zip(&gravity).map(|(a, g)| a - g).collect();
    (gravity, other)
}

/// Local deformation of element `i` at a configuration (its nodal triads `R_i · frame0_i`).
pub fn element_deformation(
    model: &Model,
    state: &StaticState,
    i: usize,
) -> crate::physics::beam::LocalDeformation<f64> {
    let t1 = mat_mul(&state.rot[i], &model.nodes[i].frame0);
    let t2 = mat_mul(&state.rot[i + 1], &model.nodes[i + 1].frame0);
    local_deformation(
        &state.position(model, i),
        &state.position(model, i + 1),
        &t1,
        &t2,
        model.elements[i].length0,
    )
    .minus_rest(&model.element_rest(i))
}

/// Section forces of element `i` at a configuration.
pub fn element_section_forces(
    model: &Model,
    state: &StaticState,
    i: usize,
) -> crate::physics::beam::SectionForces {
    let e = &model.elements[i];
    section_forces(&element_deformation(model, state, i), &e.section, e.length0)
}

/// The solution (section forces, contact, reactions) at a converged configuration.
pub fn solution_at(model: &Model, state: StaticState) -> StaticSolution {
    finish(model, state, vec![], vec![])
}

pub(super) fn finish(
    model: &Model,
    state: StaticState,
    iterations: Vec<usize>,
    log: Vec<String>,
) -> StaticSolution {
    let section_forces = model
        .elements
        .iter()
        .enumerate()
        .map(|(i, e)| {
            section_forces(
                &element_deformation(model, &state, i),
                &e.section,
                e.length0,
            )
        })
        .collect();
    let contact = model
        .sites
        .iter()
        .map(|site| {
            let node = &model.nodes[site.node];
            let d = state.u[site.node];
            let out = site_response(model, &state, site);
            // Normal force: the radial part of the internal force.
            let d_t = sub(&d, &scale(&node.hole_axis, dot(&d, &node.hole_axis)));
            let r = dot(&d_t, &d_t).sqrt();
            let normal = if r > 0.0 {
                dot(&[out.g[0], out.g[1], out.g[2]], &d_t) / r
            } else {
                0.0
            };
            (out.contact, normal, out.g)
        })
        .collect();
    let f_int = internal_forces(model, &state);
    let f_ext = external_loads(model);
    let top_reaction = std::array::from_fn(|k| f_int[k] - f_ext[k]);
    let b = 6 * (model.nodes.len() - 1);
    let bit_reaction = std::array::from_fn(|k| f_int[b + k] - f_ext[b + k]);
    StaticSolution {
        state,
        section_forces,
        contact,
        iterations,
        log,
        top_reaction,
        bit_reaction,
    }
}

/// Penetration `delta ≥ 0` at which the elastic wall force equals `force` (bisection).
pub(super) fn penetration_for(force: f64, p: &crate::physics::contact::ContactParams<f64>) -> f64 {
    use crate::physics::contact::{elastic_force, SpringLaw};
    if force <= 0.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 1e-12);
    while elastic_force(hi, p, SpringLaw::PowerBlend).0 < force && hi < 1.0 {
        hi *= 10.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if elastic_force(mid, p, SpringLaw::PowerBlend).0 < force {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}
