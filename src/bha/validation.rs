//! Closed forms the BHA outputs are checked against (issue 25, docs/validation.md), and the
//! scenes that check them: the slick pendulum in a straight hole (Williamson & Lubinski's
//! zero-WOB result, the beam-column with a constant compression in closed form, and with
//! the axial force varying along the hole by shooting), a packed assembly in a straight
//! hole, and a pinned–pinned collar span's lateral frequencies.
//!
//! The pendulum: a slick collar held on the hole axis at the bit (pinned), lying on the low
//! side of a straight hole of radial clearance `r` above its point of tangency at `L` from
//! the bit, with the lateral load `q` (buoyed weight per length across the hole). Between
//! the bit and `L`, `EI y'''' + (P y')' = q` (`y` towards the low side, `P` compression),
//! `y(0) = y''(0) = 0`, `y(L) = r`, `y'(L) = y''(L) = 0`.

use crate::bha::{bit_loads_of, BitLoads};
use crate::model::{add_sites, mesh_string, ContactSettings, Model, Tubular};
use crate::solve::statics::{solve_static, StaticOptions};
use crate::well::{SurveyStation, WellPath};

/// A pendulum's tangency length (m), the bit's side force on the formation towards the
/// high side (N, negative: dropping) and the bit's tilt towards the high side (rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pendulum {
    /// Bit to the point of tangency (m).
    pub tangency_m: f64,
    /// Side force on the formation towards the high side (N).
    pub high_side_force_n: f64,
    /// Bit tilt towards the high side (rad).
    pub tilt_rad: f64,
}

/// Zero WOB and no axial force (a horizontal hole): `L = (24 EI r / q)^(1/4)`, side force
/// `−q L / 2`, tilt `q L³ / (12 EI) = 2 r / L`.
pub fn pendulum_closed_form(ei: f64, q: f64, r: f64) -> Pendulum {
    let l = (24.0 * ei * r / q).powf(0.25);
    Pendulum {
        tangency_m: l,
        high_side_force_n: -0.5 * q * l,
        tilt_rad: 2.0 * r / l,
    }
}

/// The beam-column with a constant compression `p > 0` (a horizontal hole with WOB `p`):
/// with `k = √(P/EI)`, `r = q L tan(kL/2) / (P k) − q L² / (2P)` fixes `L` (`kL < π`); the
/// side force is `−(q L / 2 − P r / L)` and the tilt `2 q tan(kL/2) / (P k) − q L / P`.
pub fn beam_column_closed_form(ei: f64, q: f64, r: f64, p: f64) -> Pendulum {
    if p <= 0.0 {
        return pendulum_closed_form(ei, q, r);
    }
    let k = (p / ei).sqrt();
    let gap = |l: f64| q * l * (0.5 * k * l).tan() / (p * k) - q * l * l / (2.0 * p) - r;
    let (mut lo, mut hi) = (1e-9, (std::f64::consts::PI - 1e-12) / k);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if gap(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let l = 0.5 * (lo + hi);
    Pendulum {
        tangency_m: l,
        high_side_force_n: -(0.5 * q * l - p * r / l),
        tilt_rad: 2.0 * q * (0.5 * k * l).tan() / (p * k) - q * l / p,
    }
}

/// The beam-column with the compression varying along the hole, `P(s) = p0 − dp · s` (`s`
/// from the bit; an inclined hole: `dp = w cos I`), by shooting: with `V = EI y''' + P y'`,
/// `V' = q`, so `y''' = (V₀ + q s − P(s) y') / EI`; RK4 in `steps` steps for the two unknown
/// starting values (`y'(0)`, `V₀`: the problem is linear in them), bisection on `L` for
/// `y(L) = r`. The side force on the formation towards the high side is `V₀`, the tilt
/// `atan y'(0)`.
pub fn beam_column_shooting(ei: f64, q: f64, r: f64, p0: f64, dp: f64, steps: usize) -> Pendulum {
    // Integrates [y, y', y''] from 0 to l with y'(0) = a, V₀ = b; returns the end state.
    let run = |l: f64, a: f64, b: f64, q: f64| -> [f64; 3] {
        let h = l / steps as f64;
        let f = |s: f64, y: &[f64; 3]| -> [f64; 3] {
            [y[1], y[2], (b + q * s - (p0 - dp * s) * y[1]) / ei]
        };
        let mut y = [0.0, a, 0.0];
        for i in 0..steps {
            let s = i as f64 * h;
            let k1 = f(s, &y);
            let y2: [f64; 3] = std::array::from_fn(|j| y[j] + 0.5 * h * k1[j]);
            let k2 = f(s + 0.5 * h, &y2);
            let y3: [f64; 3] = std::array::from_fn(|j| y[j] + 0.5 * h * k2[j]);
            let k3 = f(s + 0.5 * h, &y3);
            let y4: [f64; 3] = std::array::from_fn(|j| y[j] + h * k3[j]);
            let k4 = f(s + h, &y4);
            for j in 0..3 {
                y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
            }
        }
        y
    };
    let solve = |l: f64| -> (f64, f64, f64) {
        let p = run(l, 0.0, 0.0, q);
        let ya = run(l, 1.0, 0.0, 0.0);
        let yb = run(l, 0.0, 1.0, 0.0);
        // y'(L) = 0, y''(L) = 0.
        let det = ya[1] * yb[2] - yb[1] * ya[2];
        let a = (-p[1] * yb[2] + yb[1] * p[2]) / det;
        let b = (-ya[1] * p[2] + p[1] * ya[2]) / det;
        (p[0] + a * ya[0] + b * yb[0], a, b)
    };
    let guess = pendulum_closed_form(ei, q, r).tangency_m;
    let (mut lo, mut hi) = (0.3 * guess, 3.0 * guess);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if solve(mid).0 < r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let l = 0.5 * (lo + hi);
    let (_, a, b) = solve(l);
    Pendulum {
        tangency_m: l,
        high_side_force_n: b,
        tilt_rad: a.atan(),
    }
}

/// A pendulum scene: a slick collar string in a straight hole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PendulumScene {
    /// Hole inclination (degrees).
    pub inclination_deg: f64,
    /// Weight on bit (N).
    pub weight_on_bit: f64,
    /// Element length near the bit (m), over the first `fine_length` metres.
    pub element_length: f64,
    /// Length meshed finely (m).
    pub fine_length: f64,
    /// Collar string length (m); its top is clamped on the hole axis.
    pub length: f64,
    /// Hole diameter (m).
    pub hole_diameter: f64,
    /// Collar OD and ID (m).
    pub od: f64,
    /// Collar ID (m).
    pub id: f64,
    /// Wall stiffness (N/m, linear law).
    pub wall_stiffness: f64,
}

impl Default for PendulumScene {
    /// 6½ in × 2 13/16 in collars in an 8½ in hole, 1.2 sg mud, 60 m of collars, 5 cm
    /// elements over the 20 m above the bit.
    fn default() -> Self {
        PendulumScene {
            inclination_deg: 90.0,
            weight_on_bit: 0.0,
            element_length: 0.05,
            fine_length: 20.0,
            length: 60.0,
            hole_diameter: 0.2159,
            od: 0.1651,
            id: 0.0714,
            wall_stiffness: 1e9,
        }
    }
}

/// Steel and mud of the validation scenes (kg/m³).
const STEEL: f64 = 7850.0;
const MUD: f64 = 1200.0;

impl PendulumScene {
    /// The model: collars from the bit up (fine, then 0.5 m elements), contact at every
    /// node, frictionless, top clamped, bit held on the hole axis with the WOB on it.
    pub fn model(&self) -> Model {
        let inc = self.inclination_deg;
        let md = self.length;
        let well = WellPath::from_survey(
            &[
                SurveyStation {
                    md: 0.0,
                    inclination_deg: inc,
                    azimuth_deg: 0.0,
                },
                SurveyStation {
                    md,
                    inclination_deg: inc,
                    azimuth_deg: 0.0,
                },
            ],
            [0.0; 3],
        )
        .expect("a straight survey is valid");
        let collar = |length: f64, element_length: f64| Tubular {
            name: "collar".into(),
            length,
            outer_diameter: self.od,
            inner_diameter: self.id,
            youngs_modulus: 2.1e11,
            poisson_ratio: 0.3,
            density: STEEL,
            element_length,
        };
        let (nodes, elements) = mesh_string(
            &well,
            &[
                collar(self.fine_length, self.element_length),
                collar(self.length - self.fine_length, 0.5),
            ],
            md,
            MUD,
        );
        let n = nodes.len();
        let mut m = Model {
            weight_on_bit: self.weight_on_bit,
            ..Model::bare(nodes, elements)
        };
        let settings = ContactSettings {
            wall_stiffness: self.wall_stiffness,
            spring_exponent: 1.0,
            wall_damping: 0.0,
            eps: 1e-3,
            soft_blend: 1e-6,
        };
        let sites: Vec<usize> = (1..n - 1).collect();
        add_sites(
            &mut m,
            &sites,
            |_| 0.5 * self.hole_diameter,
            |_| 0.5 * self.od,
            |_| 0.0,
            &settings,
            false,
        );
        m
    }

    /// `(EI, q, r, w cos I)`: bending stiffness, lateral load per length, radial clearance
    /// and the axial gradient of the weight.
    pub fn constants(&self, model: &Model) -> (f64, f64, f64, f64) {
        let e = &model.elements[0];
        let w = e.buoyed_weight_per_length;
        let inc = self.inclination_deg.to_radians();
        (
            e.section.youngs_modulus * e.section.second_moment,
            w * inc.sin(),
            0.5 * (self.hole_diameter - self.od),
            w * inc.cos(),
        )
    }

    /// The reference solution: the closed form at zero axial force and zero WOB, the
    /// constant-compression closed form in a horizontal hole, shooting otherwise.
    pub fn reference(&self) -> Pendulum {
        let m = self.model();
        let (ei, q, r, dp) = self.constants(&m);
        if dp.abs() < 1e-9 * q {
            beam_column_closed_form(ei, q, r, self.weight_on_bit)
        } else {
            beam_column_shooting(ei, q, r, self.weight_on_bit, dp, 20_000)
        }
    }

    /// The FE result: the bit's loads and the point of tangency (m from the bit): the
    /// centroid of the contact forces in excess of the distributed load `q` over the 2 m
    /// from the first node in contact — the closed form's point force `q L / 2 − …` at `L`,
    /// which a stiff wall spreads over the few nodes around it.
    pub fn solve(&self) -> Result<(BitLoads, f64), crate::solve::statics::StaticError> {
        let m = self.model();
        let (_, q, _, _) = self.constants(&m);
        let sol = solve_static(&m, &StaticOptions::default())?;
        let bit_md = m.nodes.last().map_or(0.0, |n| n.md);
        let contacts: Vec<(f64, f64)> = m
            .sites
            .iter()
            .zip(&sol.contact)
            .filter(|(_, c)| c.0 && c.1 > 0.0)
            .map(|(s, c)| {
                (
                    bit_md - m.nodes[s.node].md,
                    c.1 - q * m.tributary_length(s.node),
                )
            })
            .collect();
        let first = contacts.iter().map(|c| c.0).fold(f64::INFINITY, f64::min);
        let near = contacts.iter().filter(|c| c.0 <= first + 2.0);
        let (moment, force) = near.fold((0.0, 0.0), |(a, b), c| (a + c.0 * c.1, b + c.1));
        Ok((bit_loads_of(&m, &sol), moment / force))
    }
}
