//! Pipe strength (issue 26): a component's steel grade and wear class, the von Mises stress
//! along the string from tension, bending, torsion and the mud's pressure, and the API RP 7G
//! tension–torque envelope.
//!
//! - **Grades** (API 5DP minimum yield strength): E75 517 MPa (75 ksi), X95 655 MPa, G105
//!   724 MPa, S135 931 MPa; or a `yield_strength` given.
//! - **Wear class** (API RP 7G, uniform OD wear at the remaining wall): new 100 %, premium
//!   80 %, class 2 70 %: `OD_worn = ID + 2 · fraction · (OD − ID)/2`.
//! - **Stresses** of the worn section, triaxial: axial `σ_z = F_true/A ± M r/I` with the true
//!   axial force from the effective one, `F_true = F_eff − p_o A_o + p_i A_i` (Lubinski's
//!   effective force is `F_true + p_o A_o − p_i A_i`; `p_o = ρ_o g TVD` outside, `p_i = ρ_i g
//!   TVD` inside: `mud.density`, `mud.inside_density`), Lamé's radial and hoop stresses of a
//!   thick-walled tube under `p_i`, `p_o` (`σ_r = a − b/r²`, `σ_θ = a + b/r²`,
//!   `a = (p_i r_i² − p_o r_o²)/(r_o² − r_i²)`, `b = (p_i − p_o) r_i² r_o²/(r_o² − r_i²)`),
//!   shear `τ = T r/J`; von Mises `√(½((σ_z−σ_θ)² + (σ_θ−σ_r)² + (σ_r−σ_z)²) + 3τ²)`, the
//!   largest at the inner and outer fibre on the tension and compression side of the bend;
//!   utilisation `σ_vm / Y`. Under equal pressures inside and out the stress is the
//!   effective one's (a hanging string's bottom, `F_eff = 0`, is stress-free).
//! - **Tension–torque envelope** (API RP 7G's combined loading, von Mises at the outer fibre
//!   without bending): `Q(P) = (2J/D) √(Y² − (P/A)²) / √3`; at zero tension the torsional
//!   yield `Q = 0.57735 · 2 J Y / D` (RP 7G's `0.096167 J Y / D` in ft·lbf, in, psi).

use serde::Serialize;

/// A component's strength.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PipeStrength {
    /// Grade's name (or "custom").
    pub grade: &'static str,
    /// Minimum yield strength (Pa).
    pub yield_pa: f64,
    /// Remaining wall fraction of the wear class.
    pub wall_fraction: f64,
    /// The worn OD (m) and the ID (m).
    pub od: f64,
    /// Inner diameter (m).
    pub id: f64,
    /// The tool joint's make-up torque (N·m, `tool_joint_makeup_torque`), where the case
    /// gives it: the connection's torque limit in service (a joint made up to it must not be
    /// turned harder, or it makes up further downhole and the pin or box yields).
    pub makeup_torque_nm: Option<f64>,
}

/// The grades by name: (name, minimum yield strength in Pa).
pub const GRADES: [(&str, f64); 4] = [
    ("E75", 75_000.0 * 6_894.757),
    ("X95", 95_000.0 * 6_894.757),
    ("G105", 105_000.0 * 6_894.757),
    ("S135", 135_000.0 * 6_894.757),
];

/// The wear classes by name: (name, remaining wall fraction).
pub const WEAR: [(&str, f64); 3] = [("new", 1.0), ("premium", 0.8), ("class2", 0.7)];

impl PipeStrength {
    /// A pipe of nominal `od`, `id` of `grade` (yield `yield_pa`) worn to `wall_fraction`.
    pub fn new(grade: &'static str, yield_pa: f64, wall_fraction: f64, od: f64, id: f64) -> Self {
        PipeStrength {
            grade,
            yield_pa,
            wall_fraction,
            od: id + wall_fraction * (od - id),
            id,
            makeup_torque_nm: None,
        }
    }

    /// The same pipe with its tool joint's make-up torque (N·m).
    pub fn with_makeup_torque(mut self, makeup_torque_nm: Option<f64>) -> Self {
        self.makeup_torque_nm = makeup_torque_nm;
        self
    }

    /// Steel area, second moment and polar moment of the worn section (m², m⁴, m⁴).
    pub fn section(&self) -> (f64, f64, f64) {
        let (o, i) = (self.od, self.id);
        let area = std::f64::consts::FRAC_PI_4 * (o * o - i * i);
        let second = std::f64::consts::PI / 64.0 * (o.powi(4) - i.powi(4));
        (area, second, 2.0 * second)
    }

    /// Tensile yield load `Y A` (N).
    pub fn tensile_yield_n(&self) -> f64 {
        self.yield_pa * self.section().0
    }

    /// Torque at yield under tension `p` (N, tension positive), API RP 7G's combined form;
    /// 0 past the tensile yield.
    pub fn torque_limit_nm(&self, p: f64) -> f64 {
        let (area, _, polar) = self.section();
        let s = p / area;
        let y = self.yield_pa;
        if s.abs() >= y {
            return 0.0;
        }
        2.0 * polar / self.od * (y * y - s * s).sqrt() / 3f64.sqrt()
    }

    /// Von Mises stress at the outer fibre (Pa) under the true axial force `f_true` (N,
    /// tension positive), bending moment `m` (N·m) and torque `t` (N·m), no pressure (API
    /// RP 7G's form).
    pub fn von_mises_pa(&self, f_true: f64, m: f64, t: f64) -> f64 {
        self.von_mises_triaxial_pa(f_true, m, t, 0.0, 0.0)
    }

    /// The largest von Mises stress (Pa) over the inner and outer fibre, on both sides of
    /// the bend, with the pressures `p_i` inside and `p_o` outside (Pa) as well (Lamé; the
    /// module's doc).
    pub fn von_mises_triaxial_pa(&self, f_true: f64, m: f64, t: f64, p_i: f64, p_o: f64) -> f64 {
        let (area, second, polar) = self.section();
        let (ro, ri) = (0.5 * self.od, 0.5 * self.id);
        let d = ro * ro - ri * ri;
        let a = (p_i * ri * ri - p_o * ro * ro) / d;
        let b = (p_i - p_o) * ri * ri * ro * ro / d;
        let mut worst: f64 = 0.0;
        for r in [ro, ri] {
            if r <= 0.0 {
                continue;
            }
            let (s_r, s_t) = (a - b / (r * r), a + b / (r * r));
            let tau = t * r / polar;
            for side in [1.0, -1.0] {
                let s_z = f_true / area + side * m.abs() * r / second;
                let vm = (0.5 * ((s_z - s_t).powi(2) + (s_t - s_r).powi(2) + (s_r - s_z).powi(2))
                    + 3.0 * tau * tau)
                    .sqrt();
                worst = worst.max(vm);
            }
        }
        worst
    }
}

/// The true axial force from the effective one at TVD `tvd` (m), mud of density `rho_o`
/// outside and `rho_i` inside (kg/m³), for a pipe of outer and inner diameter `od`, `id`
/// (Lubinski: the effective force is the true one plus `p_o A_o − p_i A_i`; at the bottom of
/// a hanging string in one mud the effective force is 0 and the true one the end pressure's
/// compression `−p A_s`).
pub fn true_axial_force(f_eff: f64, tvd: f64, (rho_o, rho_i): (f64, f64), od: f64, id: f64) -> f64 {
    let (p_o, p_i) = pressures(tvd, (rho_o, rho_i));
    let q = std::f64::consts::FRAC_PI_4;
    f_eff - p_o * q * od * od + p_i * q * id * id
}

/// Hydrostatic pressures (outside, inside) at TVD `tvd` (Pa) of the two mud columns.
pub fn pressures(tvd: f64, (rho_o, rho_i): (f64, f64)) -> (f64, f64) {
    let g = crate::model::GRAVITY * tvd.max(0.0);
    (rho_o * g, rho_i * g)
}

/// The strength check of a static profile (`holewall static`).
#[derive(Clone, Debug, Serialize)]
pub struct StrengthSummary {
    /// Largest von Mises stress over yield along the graded components.
    pub max_utilisation: f64,
    /// Where (MD, m).
    pub max_utilisation_md_m: f64,
    /// Tensile yield load of the component at the surface (N), when it is graded.
    pub top_tensile_yield_n: Option<f64>,
    /// Overpull margin at the surface: 90 % of that yield less the hook load (N).
    pub overpull_margin_n: Option<f64>,
    /// Largest torque over the RP 7G limit at the local tension, along the graded
    /// components.
    pub max_torque_utilisation: f64,
    /// Largest torque over the tool joint's make-up torque, along the components that give
    /// one (the connection's limit; above 1 the joints make up further downhole).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_makeup_torque_utilisation: Option<f64>,
}

/// One node of a profile as the strength check reads it.
#[derive(Clone, Copy, Debug)]
pub struct Loads {
    /// MD (m).
    pub md: f64,
    /// TVD (m).
    pub tvd: f64,
    /// Effective axial force, tension + (N).
    pub axial_force: f64,
    /// Bending moment (N·m).
    pub bending_moment: f64,
    /// Torque (N·m).
    pub torque: f64,
}

/// Von Mises stress and utilisation per node (NaN on ungraded components), and the
/// summary; `None` when no component is graded. `component_of(i)` is node `i`'s component,
/// `nominal(i)` its body's OD and ID, `rho` the mud densities (outside, inside), `hook_load`
/// the hook load (N).
pub fn assess(
    rows: &[Loads],
    strength: &[Option<PipeStrength>],
    component_of: &dyn Fn(usize) -> usize,
    nominal: &dyn Fn(usize) -> (f64, f64),
    rho: (f64, f64),
    hook_load: f64,
) -> (Vec<(f64, f64)>, Option<StrengthSummary>) {
    let mut out = Vec::with_capacity(rows.len());
    let mut worst = (f64::NAN, f64::NAN);
    let mut worst_torque: f64 = 0.0;
    let mut worst_makeup: Option<f64> = None;
    for (i, r) in rows.iter().enumerate() {
        let Some(s) = strength.get(component_of(i)).copied().flatten() else {
            out.push((f64::NAN, f64::NAN));
            continue;
        };
        let (od, id) = nominal(i);
        let f_true = true_axial_force(r.axial_force, r.tvd, rho, od, id);
        let (p_o, p_i) = pressures(r.tvd, rho);
        let vm = s.von_mises_triaxial_pa(f_true, r.bending_moment, r.torque, p_i, p_o);
        let u = vm / s.yield_pa;
        if worst.0.is_nan() || u > worst.0 {
            worst = (u, r.md);
        }
        let limit = s.torque_limit_nm(f_true);
        let tu = if limit > 0.0 {
            r.torque.abs() / limit
        } else {
            f64::INFINITY
        };
        worst_torque = worst_torque.max(tu);
        if let Some(m) = s.makeup_torque_nm {
            let mu = r.torque.abs() / m;
            worst_makeup = Some(worst_makeup.map_or(mu, |w| w.max(mu)));
        }
        out.push((vm, u));
    }
    if worst.0.is_nan() {
        return (out, None);
    }
    let top = strength.get(component_of(0)).copied().flatten();
    let summary = StrengthSummary {
        max_utilisation: worst.0,
        max_utilisation_md_m: worst.1,
        top_tensile_yield_n: top.map(|s| s.tensile_yield_n()),
        overpull_margin_n: top.map(|s| 0.9 * s.tensile_yield_n() - hook_load),
        max_torque_utilisation: worst_torque,
        max_makeup_torque_utilisation: worst_makeup,
    };
    (out, Some(summary))
}
