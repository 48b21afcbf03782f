//! Soft-string torque and drag (Johancsik, Friesen & Dawson, 1984), in vector form.
//!
//! The string is a cable lying on the low (or high) side of the hole: no bending
//! stiffness, contact along its whole length. Element by element from the bit up, with the
//! effective tension `F` (tension positive) and torque `T` at its lower end, tangents `t1`
//! (top) and `t2` (bottom), buoyed weight `W` and gravity `g = (0, 0, 1)`:
//!
//! - normal force `N = |F (t2 − t1) + W g_⊥|` (`g_⊥` the part of `g` normal to the mean
//!   tangent) — Johancsik's `√((F ΔA sin Ī)² + (F ΔI + W sin Ī)²)` to first order;
//! - axial: `F_top = F + W (g·t̄) + μ N·a`, torque: `T_top = T + μ N r·c`, where the unit
//!   slip direction `(a, c) = (−v_axial, ω r)/|·|` splits friction between drag and torque
//!   (`a = 1` picking up, `−1` slacking off, `c = 1` rotating in place).

use crate::model::Model;
use crate::physics::vec3::{add, dot, scale, sub};

/// The longest sub-step (m) of [`soft_string_loaded`]'s added wall force.
pub const SUB_STEP: f64 = 0.25;

/// The operation: what moves, which sets the friction direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Operation {
    /// Axial speed, positive down-hole (m/s): slack-off > 0, pick-up < 0.
    pub axial_speed: f64,
    /// Rotation speed (rad/s).
    pub rotation_speed: f64,
    /// Weight on bit (N); 0 off bottom.
    pub weight_on_bit: f64,
    /// Torque on bit (N·m); 0 off bottom.
    pub torque_on_bit: f64,
    /// Friction coefficient.
    pub friction: f64,
}

/// Torque-and-drag profile, one value per node (surface first).
#[derive(Clone, Debug)]
pub struct SoftStringProfile {
    /// Effective tension at each node (N, tension positive).
    pub tension: Vec<f64>,
    /// Torque at each node (N·m).
    pub torque: Vec<f64>,
    /// Normal (side) force of each element (N), element `i` between nodes `i` and `i+1`.
    pub side_force: Vec<f64>,
}

impl SoftStringProfile {
    /// Hook load: tension at the surface (N).
    pub fn hook_load(&self) -> f64 {
        self.tension[0]
    }

    /// Surface torque (N·m).
    pub fn surface_torque(&self) -> f64 {
        self.torque[0]
    }
}

/// Runs the soft-string model over the model's mesh for one operation, with one friction
/// coefficient (`op.friction`) everywhere.
pub fn soft_string(model: &Model, op: &Operation) -> SoftStringProfile {
    soft_string_with(model, op, &|_| op.friction)
}

/// As [`soft_string`], with the friction coefficient a function of MD (hole sections).
pub fn soft_string_with(
    model: &Model,
    op: &Operation,
    friction_at: &dyn Fn(f64) -> f64,
) -> SoftStringProfile {
    soft_string_loaded(model, op, friction_at, None)
}

/// As [`soft_string_with`], with (`extra`, where given) a normal force per length added to
/// each element's (`extra(e, F)`, N/m, for element `e` at effective tension `F`: a buckled
/// string's wall force), integrated from the element's lower end up in sub-steps of at most
/// [`SUB_STEP`] m (the added force may grow fast with the compression). Where the tension
/// turns non-finite the profile keeps it so from there up (the caller's lock-up).
pub fn soft_string_loaded(
    model: &Model,
    op: &Operation,
    friction_at: &dyn Fn(f64) -> f64,
    extra: Option<&dyn Fn(usize, f64) -> f64>,
) -> SoftStringProfile {
    let n = model.nodes.len();
    let mut tension = vec![0.0; n];
    let mut torque = vec![0.0; n];
    let mut side_force = vec![0.0; n - 1];
    tension[n - 1] = -op.weight_on_bit;
    torque[n - 1] = op.torque_on_bit;
    let g = [0.0, 0.0, 1.0];
    for i in (0..n - 1).rev() {
        let e = &model.elements[i];
        let t1 = model.nodes[i].hole_axis;
        let t2 = model.nodes[i + 1].hole_axis;
        let mean = add(&t1, &t2);
        let mean = scale(&mean, 1.0 / dot(&mean, &mean).sqrt());
        // Weight of the pipe between the two MDs (the arc, not the chord).
        let weight = e.buoyed_weight_per_length * (model.nodes[i + 1].md - model.nodes[i].md);
        let f = tension[i + 1];
        let g_perp = sub(&g, &scale(&mean, dot(&g, &mean)));
        let lateral = add(&scale(&sub(&t2, &t1), f), &scale(&g_perp, weight));
        let normal = dot(&lateral, &lateral).sqrt();
        // The torque arm: where the string touches the wall (tool joints where it has them).
        let radius = 0.5 * e.contact_diameter;
        let (axial_share, torque_share) = {
            let a = -op.axial_speed;
            let c = op.rotation_speed * radius;
            let len = (a * a + c * c).sqrt();
            if len > 0.0 {
                (a / len, c / len)
            } else {
                (0.0, 0.0)
            }
        };
        let mu = friction_at(0.5 * (model.nodes[i].md + model.nodes[i + 1].md));
        let length = model.nodes[i + 1].md - model.nodes[i].md;
        // The added wall force, stepped up the element with the tension it changes.
        let mut added = 0.0;
        if let Some(extra) = extra {
            let subs = (length / SUB_STEP).ceil().max(1.0);
            let h = length / subs;
            let mut t = f;
            for _ in 0..subs as usize {
                let q = extra(i, t) * h;
                added += q;
                t += (weight * dot(&g, &mean) + mu * normal * axial_share) * h / length.max(1e-12)
                    + mu * q * axial_share;
            }
        }
        side_force[i] = normal + added;
        tension[i] = f + weight * dot(&g, &mean) + mu * (normal + added) * axial_share;
        torque[i] = torque[i + 1] + mu * (normal + added) * radius * torque_share;
    }
    SoftStringProfile {
        tension,
        torque,
        side_force,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{mesh_string, Model, Tubular};

    use crate::well::{SurveyStation, WellPath};

    fn model_for(well: &WellPath, md: f64, element_length: f64) -> Model {
        let t = Tubular {
            name: "pipe".into(),
            length: md,
            outer_diameter: 0.127,
            inner_diameter: 0.108,
            youngs_modulus: 2.1e11,
            poisson_ratio: 0.3,
            density: 7850.0,
            element_length,
        };
        let (nodes, elements) = mesh_string(well, &[t], md, 1200.0);
        Model::bare(nodes, elements)
    }

    #[test]
    fn two_station_well_by_hand() {
        // One 100 m element, straight at 30° inclination: t1 = t2, N = W sin 30°.
        let well = WellPath::from_survey(
            &[
                SurveyStation {
                    md: 0.0,
                    inclination_deg: 30.0,
                    azimuth_deg: 0.0,
                },
                SurveyStation {
                    md: 100.0,
                    inclination_deg: 30.0,
                    azimuth_deg: 0.0,
                },
            ],
            [0.0; 3],
        )
        .unwrap();
        let m = model_for(&well, 100.0, 100.0);
        let w = m.elements[0].buoyed_weight_per_length * 100.0;
        let mu = 0.3;
        let pick_up = soft_string(
            &m,
            &Operation {
                axial_speed: -0.5,
                rotation_speed: 0.0,
                weight_on_bit: 0.0,
                torque_on_bit: 0.0,
                friction: mu,
            },
        );
        let (s, c) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
        assert!((pick_up.side_force[0] - w * s).abs() < 1e-9 * w);
        assert!((pick_up.hook_load() - w * (c + mu * s)).abs() < 1e-9 * w);
        let slack = soft_string(
            &m,
            &Operation {
                axial_speed: 0.5,
                rotation_speed: 0.0,
                weight_on_bit: 0.0,
                torque_on_bit: 0.0,
                friction: mu,
            },
        );
        assert!((slack.hook_load() - w * (c - mu * s)).abs() < 1e-9 * w);
        let rot = soft_string(
            &m,
            &Operation {
                axial_speed: 0.0,
                rotation_speed: 12.0,
                weight_on_bit: 0.0,
                torque_on_bit: 0.0,
                friction: mu,
            },
        );
        assert!((rot.hook_load() - w * c).abs() < 1e-9 * w);
        assert!((rot.surface_torque() - mu * w * s * 0.0635).abs() < 1e-9 * w);

        // Curved: 10° → 20° inclination, 30° → 40° azimuth over 100 m, one element, 50 kN
        // tension at the bottom, picking up. By hand (t from (sin I cos A, sin I sin A, cos I)):
        // t1 = (0.150384, 0.086824, 0.984808), t2 = (0.262003, 0.219846, 0.939693)
        // t2 − t1 = (0.111619, 0.133022, −0.045115); t̄ = (t1 + t2)/|t1 + t2| = (0.207028, 0.153956, 0.966145)
        // W = 100 m · 22.82 N/m ... computed below from the model; g·t̄ = 0.966145.
        let well = WellPath::from_survey(
            &[
                SurveyStation {
                    md: 0.0,
                    inclination_deg: 10.0,
                    azimuth_deg: 30.0,
                },
                SurveyStation {
                    md: 100.0,
                    inclination_deg: 20.0,
                    azimuth_deg: 40.0,
                },
            ],
            [0.0; 3],
        )
        .unwrap();
        let m = model_for(&well, 100.0, 100.0);
        let w = m.elements[0].buoyed_weight_per_length * 100.0;
        let f = 50e3;
        let op = Operation {
            axial_speed: -0.5,
            rotation_speed: 0.0,
            weight_on_bit: -f,
            torque_on_bit: 0.0,
            friction: mu,
        };
        let prof = soft_string(&m, &op);
        let dt = [0.111619, 0.133022, -0.045115];
        let tb = [0.207028, 0.153956, 0.966145];
        let gp = [-0.966145 * tb[0], -0.966145 * tb[1], 1.0 - 0.966145 * tb[2]];
        let lat: Vec<f64> = (0..3).map(|k| f * dt[k] + w * gp[k]).collect();
        let n_hand = (lat[0] * lat[0] + lat[1] * lat[1] + lat[2] * lat[2]).sqrt();
        assert!(
            (prof.side_force[0] - n_hand).abs() < 1e-4 * n_hand,
            "{} vs {n_hand}",
            prof.side_force[0]
        );
        let hook_hand = f + w * 0.966145 + mu * n_hand;
        assert!((prof.hook_load() - hook_hand).abs() < 1e-5 * hook_hand);
    }
}
