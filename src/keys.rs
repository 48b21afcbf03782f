//! Variant keys (`mu`, `k_e.stab2`, `wob`, `depth`, `mode`, …): what each overrides, its
//! unit and allowed range. The table is in `src/ensemble/mod.rs`'s docs. Shared by the case
//! file (`[ensemble.grid]`, `[ensemble.uncertain]`), variant CSVs, sampling and reports, so
//! none of them imports another for it.

use crate::units::{parse_quantity, Dimension};

/// What a key overrides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Param {
    /// Both friction coefficients.
    Mu,
    /// Circumferential friction.
    MuT,
    /// Axial friction.
    MuL,
    /// Wall stiffness.
    WallStiffness,
    /// Wall damping.
    WallDamping,
    /// Spring exponent.
    Exponent,
    /// Friction regularisation speed.
    Eps,
    /// Rotary speed (rad/s).
    Rpm,
    /// Weight on bit (N).
    Wob,
    /// Torque on bit (N·m).
    Tob,
    /// Blade diameter (m).
    Blade,
    /// Distance of the stabilizer's site from the bit (m).
    FromBit,
    /// Bit depth, MD (m): the case rebuilt there.
    Depth,
    /// Operation mode (a code of [`MODES`]): the case rebuilt with it.
    Mode,
    /// Centre-of-mass offset of every BHA component (bit to the first drill pipe), m: a mass
    /// imbalance for dynamics, replacing the case's `mass_eccentricity`/`imbalance`.
    Eccentricity,
    /// Angle of every bent sub / bent housing of the case (rad; written in degrees).
    Bend,
    /// A stabilizer layout: the 1-based index of one of `ensemble.layouts` (each a set of
    /// `stabK.from_bit` / `stabK.blade` values applied together).
    Layout,
}

/// The operation modes a `mode` key takes, by code (its value is the index).
/// (Codes are stable: new modes are appended.)
pub const MODES: [&str; 6] = [
    "rotating",
    "tripping_in",
    "tripping_out",
    "sliding",
    "reaming",
    "back_reaming",
];

/// The hole sections a contact-law key is limited to (`mu.cased`, `mu.open`, `mu.hole2`):
/// the sites whose node lies in them (issue 26: friction factors per section).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HoleSelect {
    /// Sections marked `cased = true`.
    Cased,
    /// The other sections.
    Open,
    /// The `[[hole]]` section of this number (1 = the first written, from the surface).
    Section(usize),
}

/// A parsed column key.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    /// The text as written.
    pub name: String,
    /// What it overrides.
    pub param: Param,
    /// Stabilizer (1 = nearest the bit), or every site.
    pub stabilizer: Option<usize>,
    /// Hole sections (contact-law keys only), or every site.
    pub hole: Option<HoleSelect>,
}

/// Every key form, for messages.
pub const KEY_FORMS: &str = "mu, mu_t, mu_l, k_e, c, m, eps (each optionally .stabK, .cased, .open or .holeN), rpm, wob, tob, stabK.blade, stabK.from_bit, depth, mode, layout, ecc, bend";

impl Key {
    /// Parses a column key.
    pub fn parse(name: &str) -> Result<Key, String> {
        let stab_index = |s: &str| -> Result<usize, String> {
            s.strip_prefix("stab")
                .and_then(|k| k.parse::<usize>().ok())
                .filter(|&k| k >= 1)
                .ok_or_else(|| format!("unknown key {name:?}; allowed: {KEY_FORMS}"))
        };
        let (head, tail) = match name.split_once('.') {
            Some((h, t)) => (h, Some(t)),
            None => (name, None),
        };
        // `.cased`, `.open`, `.holeN` (N ≥ 1).
        let hole_select = |t: &str| match t {
            "cased" => Some(HoleSelect::Cased),
            "open" => Some(HoleSelect::Open),
            _ => t
                .strip_prefix("hole")
                .and_then(|k| k.parse::<usize>().ok())
                .filter(|&k| k >= 1)
                .map(HoleSelect::Section),
        };
        let law = |p: &str| match p {
            "mu" => Some(Param::Mu),
            "mu_t" => Some(Param::MuT),
            "mu_l" => Some(Param::MuL),
            "k_e" => Some(Param::WallStiffness),
            "c" => Some(Param::WallDamping),
            "m" => Some(Param::Exponent),
            "eps" => Some(Param::Eps),
            _ => None,
        };
        let (param, stabilizer) = match (head, tail) {
            ("rpm", None) => (Param::Rpm, None),
            ("wob", None) => (Param::Wob, None),
            ("tob", None) => (Param::Tob, None),
            ("depth", None) => (Param::Depth, None),
            ("mode", None) => (Param::Mode, None),
            ("layout", None) => (Param::Layout, None),
            ("ecc", None) => (Param::Eccentricity, None),
            ("bend", None) => (Param::Bend, None),
            (h, None) if law(h).is_some() => (law(h).unwrap_or(Param::Mu), None),
            (h, Some(t)) if law(h).is_some() && hole_select(t).is_some() => {
                return Ok(Key {
                    name: name.to_string(),
                    param: law(h).unwrap_or(Param::Mu),
                    stabilizer: None,
                    hole: hole_select(t),
                });
            }
            (h, Some(t)) if law(h).is_some() => (law(h).unwrap_or(Param::Mu), Some(stab_index(t)?)),
            (h, Some("blade")) => (Param::Blade, Some(stab_index(h)?)),
            (h, Some("from_bit")) => (Param::FromBit, Some(stab_index(h)?)),
            _ => return Err(format!("unknown key {name:?}; allowed: {KEY_FORMS}")),
        };
        Ok(Key {
            name: name.to_string(),
            param,
            stabilizer,
            hole: None,
        })
    }

    /// A value as `variants.csv` writes it: the mode's name, else the number.
    pub fn format(&self, v: f64) -> String {
        match self.param {
            Param::Mode => MODES
                .get(v as usize)
                .map(|m| m.to_string())
                .unwrap_or_else(|| format!("{v}")),
            _ => format!("{v}"),
        }
    }

    /// The SI value of `text` for this key (a number with its unit, a mode name, a bend in
    /// degrees), checked against the key's range ([`Key::check`]).
    pub fn value(&self, text: &str) -> Result<f64, String> {
        let t = text.trim();
        let v = match self.param {
            Param::Mode => MODES
                .iter()
                .position(|m| *m == t)
                .map(|k| k as f64)
                .or_else(|| t.parse::<f64>().ok())
                .ok_or_else(|| format!("unknown mode {t:?}; allowed: {}", MODES.join(", ")))?,
            // Degrees unless a unit says otherwise, as the case file's angles.
            Param::Bend => crate::units::parse_angle_deg(t)
                .map_err(|e| e.to_string())?
                .to_radians(),
            _ => match (t.parse::<f64>(), self.range().0) {
                (Ok(x), Some(d)) => match crate::units::bare_number_trap(d, x) {
                    Some(m) => return Err(m),
                    None => x,
                },
                (Ok(x), None) => x,
                (Err(_), Some(d)) => parse_quantity(t, d).map_err(|e| e.to_string())?,
                (Err(_), None) => return Err(format!("{t:?} is not a number")),
            },
        };
        self.check(v)
            .map_err(|range| format!("{t} out of range; allowed: {range}"))
    }

    /// An SI value (a sample drawn from a distribution, already in SI) checked against the
    /// key's range, with no text in between: `Err` names the allowed range.
    pub fn check(&self, v: f64) -> Result<f64, String> {
        let (_, ok, range) = self.range();
        if v.is_finite() && ok(v) {
            Ok(v)
        } else {
            Err(range.to_string())
        }
    }

    /// The key's unit dimension (for parsing a number written with a unit), its range in SI
    /// and the range in words.
    fn range(&self) -> (Option<Dimension>, fn(f64) -> bool, &'static str) {
        match self.param {
            Param::Mode => (
                None,
                |x| x.fract() == 0.0 && (0.0..MODES.len() as f64).contains(&x),
                "rotating, tripping_in, tripping_out, sliding",
            ),
            Param::Bend => (None, |x| (0.0..=5f64.to_radians()).contains(&x), "0 … 5°"),
            Param::Mu | Param::MuT | Param::MuL => (None, |x| (0.0..=2.0).contains(&x), "0 … 2"),
            Param::WallStiffness => (None, |x| x > 0.0 && x <= 1e12, "0 < k_e ≤ 1e12 N/m^m"),
            Param::WallDamping => (Some(Dimension::Damping), |x| x >= 0.0, "≥ 0 N·s/m"),
            Param::Exponent => (None, |x| x > 0.0 && x <= 3.0, "0 < m ≤ 3"),
            Param::Eps => (
                Some(Dimension::Speed),
                |x| x > 0.0 && x <= 10.0,
                "0 < eps ≤ 10 m/s",
            ),
            Param::Rpm => (
                Some(Dimension::AngularSpeed),
                |x| (0.0..=1000.0 * std::f64::consts::TAU / 60.0).contains(&x),
                "0 … 1000 rpm",
            ),
            Param::Wob => (
                Some(Dimension::Force),
                |x| (0.0..=1e7).contains(&x),
                "0 … 1e7 N",
            ),
            Param::Tob => (
                Some(Dimension::Torque),
                |x| (0.0..=1e6).contains(&x),
                "0 … 1e6 N·m",
            ),
            Param::Blade => (
                Some(Dimension::Length),
                |x| x > 0.0 && x < 2.0,
                "0 < blade < 2 m",
            ),
            Param::FromBit => (
                Some(Dimension::Length),
                |x| x > 0.0 && x < 2e4,
                "0 < from_bit < 20 km",
            ),
            Param::Depth => (
                Some(Dimension::Length),
                |x| x > 0.0 && x <= 2e4,
                "0 < depth ≤ 20 km",
            ),
            Param::Eccentricity => (
                Some(Dimension::Length),
                |x| (0.0..=0.05).contains(&x),
                "0 … 50 mm",
            ),
            Param::Layout => (
                None,
                |x| x >= 1.0 && x.fract() == 0.0 && x <= 1e6,
                "a layout number 1, 2, … of ensemble.layouts",
            ),
        }
    }
}
