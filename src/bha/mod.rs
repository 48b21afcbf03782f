//! BHA design outputs (issue 25): what a BHA engineer places stabilizers for — the bit's
//! side force and tilt in the hole's frame ([`bit_loads`]), the build/turn tendency and
//! equilibrium curvature ([`tendency`]), and the critical rotary speeds of the BHA as it
//! lies in the hole ([`critical`]).
//!
//! Sign conventions, one place for every output:
//! - the **hole frame** at a point: the hole axis `t` (down-hole), the **high side** `h`
//!   (the part of "up" perpendicular to `t`) and the **right side** `r = t × h` (the right
//!   hand of an observer looking down-hole with the high side up). In a vertical hole, where
//!   "up" has no part across the axis, `h` is the node's reference axis (north for a well
//!   that starts vertical: [`crate::model::frame_from_axis`]), as a magnetic toolface.
//! - the **bit side force** is the force the bit exerts **on the formation**, positive
//!   towards the high side (a building force) and towards the right (a right-walking
//!   force) — the convention of BHA programs (Williamson & Lubinski's BHAP): a pendulum has
//!   a negative (dropping) side force.
//! - the **bit tilt** is the angle of the bit's axis, pointing down-hole, from the hole axis,
//!   positive when it points towards the high side (builds) or the right.

pub mod critical;
pub mod tendency;
pub mod validation;

use serde::{Deserialize, Serialize};

pub use crate::model::HoleFrame;
use crate::model::Model;
use crate::physics::vec3::Vec3;
use crate::solve::statics::StaticState;

/// The bit's loads and attitude in the hole's frame ([module docs](self) for the signs).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct BitLoads {
    /// Magnitude of the bit's side force across the hole axis (N).
    pub side_force_n: f64,
    /// Side force on the formation towards the high side (N): > 0 builds.
    pub high_side_force_n: f64,
    /// Side force on the formation towards the right, looking down-hole (N): > 0 walks
    /// right.
    pub right_side_force_n: f64,
    /// Tilt of the bit's axis from the hole axis towards the high side (degrees).
    pub tilt_high_side_deg: f64,
    /// Tilt towards the right side (degrees).
    pub tilt_right_side_deg: f64,
}

/// The bit's columns in `variants.csv` and the statistics, in [`BitLoads::columns`] order.
pub const BIT_COLUMNS: [&str; 5] = [
    "bit_side_force_n",
    "bit_high_side_force_n",
    "bit_right_side_force_n",
    "bit_tilt_high_side_deg",
    "bit_tilt_right_side_deg",
];

impl BitLoads {
    /// The values in [`BIT_COLUMNS`] order.
    pub fn columns(&self) -> [f64; 5] {
        [
            self.side_force_n,
            self.high_side_force_n,
            self.right_side_force_n,
            self.tilt_high_side_deg,
            self.tilt_right_side_deg,
        ]
    }
}

/// The bit's loads and attitude of a static state: `bit_reaction` is the force the bit's
/// supports exert on the string ([`crate::solve::statics::StaticSolution::bit_reaction`]);
/// the formation carries its opposite. The tilt is the bit node's rotation applied to its
/// initial axis (the hole axis there), against the hole axis.
pub fn bit_loads(model: &Model, state: &StaticState, bit_reaction: &[f64; 6]) -> BitLoads {
    let bit = model.nodes.len() - 1;
    let frame = HoleFrame::at_node(model, bit);
    let on_rock = [-bit_reaction[0], -bit_reaction[1], -bit_reaction[2]];
    let (high, right) = frame.across(&on_rock);
    let r = &state.rot[bit];
    let t0 = model.nodes[bit].hole_axis;
    let axis: Vec3<f64> = std::array::from_fn(|i| (0..3).map(|k| r[i][k] * t0[k]).sum());
    let (tilt_h, tilt_r) = frame.angles(&axis);
    BitLoads {
        side_force_n: high.hypot(right),
        high_side_force_n: high,
        right_side_force_n: right,
        tilt_high_side_deg: tilt_h.to_degrees(),
        tilt_right_side_deg: tilt_r.to_degrees(),
    }
}

/// The bit's loads of a converged static solution.
pub fn bit_loads_of(model: &Model, sol: &crate::solve::statics::StaticSolution) -> BitLoads {
    bit_loads(model, &sol.state, &sol.bit_reaction)
}
