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
    /// Operation mode ([`Mode`]): the case rebuilt with it.
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

/// An operation mode (`[operation].mode`, the `mode` key): what the string does, hence the
/// direction of its friction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Rotating on or off bottom, no axial motion.
    Rotating,
    /// Running in without rotation.
    TrippingIn,
    /// Pulling out without rotation.
    TrippingOut,
    /// Drilling ahead without rotating the string (a motor turns the bit).
    Sliding,
    /// Running in while rotating.
    Reaming,
    /// Pulling out while rotating.
    BackReaming,
}

impl Mode {
    /// Every mode, by code: a mode's code is its index here (codes are stable: new modes
    /// are appended). A distribution over modes draws codes.
    pub const ALL: [Mode; 6] = [
        Mode::Rotating,
        Mode::TrippingIn,
        Mode::TrippingOut,
        Mode::Sliding,
        Mode::Reaming,
        Mode::BackReaming,
    ];

    /// The name a case file and `variants.csv` write.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Rotating => "rotating",
            Mode::TrippingIn => "tripping_in",
            Mode::TrippingOut => "tripping_out",
            Mode::Sliding => "sliding",
            Mode::Reaming => "reaming",
            Mode::BackReaming => "back_reaming",
        }
    }

    /// The mode named `name`.
    pub fn parse(name: &str) -> Option<Mode> {
        Mode::ALL.into_iter().find(|m| m.name() == name.trim())
    }

    /// Its code ([`Mode::ALL`]'s index).
    pub fn code(self) -> usize {
        Mode::ALL.iter().position(|m| *m == self).unwrap_or(0)
    }

    /// The names, for messages.
    pub fn names() -> String {
        Mode::ALL.map(Mode::name).join(", ")
    }

    /// Whether the string rotates in this mode (then it needs a rotary speed).
    pub fn rotates(self) -> bool {
        matches!(self, Mode::Rotating | Mode::Reaming | Mode::BackReaming)
    }

    /// The axial motion's direction: +1 running in, −1 pulling out, 0 none.
    pub fn axial_direction(self) -> f64 {
        match self {
            Mode::Rotating => 0.0,
            Mode::TrippingIn | Mode::Sliding | Mode::Reaming => 1.0,
            Mode::TrippingOut | Mode::BackReaming => -1.0,
        }
    }
}

impl<'de> serde::Deserialize<'de> for Mode {
    /// A case file's `mode = "…"`: a name of [`Mode::ALL`].
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Mode::parse(&name).ok_or_else(|| serde::de::Error::custom(KeyError::UnknownMode(name)))
    }
}

impl std::fmt::Display for Mode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A variant's value of one key, typed: a number in SI for a physical key, a mode for
/// `mode`, a layout's number for `layout`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// A quantity in SI (rad for `bend`).
    Number(f64),
    /// An operation mode.
    Mode(Mode),
    /// A stabilizer layout: the 1-based index of one of `ensemble.layouts`.
    Layout(usize),
}

impl Value {
    /// As a number: the quantity; a mode's code; a layout's number (for the numeric
    /// columns of reports and the inputs of a sensitivity analysis).
    pub fn si(self) -> f64 {
        match self {
            Value::Number(x) => x,
            Value::Mode(m) => m.code() as f64,
            Value::Layout(k) => k as f64,
        }
    }
}

impl std::fmt::Display for Value {
    /// As `variants.csv` writes it: the mode's name, else the number.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Number(x) => write!(f, "{x}"),
            Value::Mode(m) => f.write_str(m.name()),
            Value::Layout(k) => write!(f, "{k}"),
        }
    }
}

/// Why a key or one of its values cannot be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum KeyError {
    /// Not a key of [`KEY_FORMS`].
    #[error("unknown key {0:?}; allowed: {KEY_FORMS}")]
    UnknownKey(String),
    /// Not a mode of [`Mode::ALL`].
    #[error("unknown mode {0:?}; allowed: {names}", names = Mode::names())]
    UnknownMode(String),
    /// Not a number, and the key has no unit to read it with.
    #[error("{0:?} is not a number")]
    NotANumber(String),
    /// A quantity whose unit cannot be read.
    #[error(transparent)]
    Unit(#[from] crate::units::UnitError),
    /// A bare number the user most likely did not mean ([`crate::units::bare_number_trap`]).
    #[error("{0}")]
    BareNumber(String),
    /// Outside the key's allowed range.
    #[error("{value} out of range; allowed: {range}")]
    OutOfRange {
        /// The value as written (or drawn, in SI).
        value: String,
        /// The allowed range in words.
        range: &'static str,
    },
}

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
    pub fn parse(name: &str) -> Result<Key, KeyError> {
        let stab_index = |s: &str| -> Result<usize, KeyError> {
            s.strip_prefix("stab")
                .and_then(|k| k.parse::<usize>().ok())
                .filter(|&k| k >= 1)
                .ok_or_else(|| KeyError::UnknownKey(name.to_string()))
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
            _ => return Err(KeyError::UnknownKey(name.to_string())),
        };
        Ok(Key {
            name: name.to_string(),
            param,
            stabilizer,
            hole: None,
        })
    }

    /// The value of `text` for this key (a number with its unit, a mode name, a bend in
    /// degrees), checked against the key's range.
    pub fn value(&self, text: &str) -> Result<Value, KeyError> {
        let t = text.trim();
        let out_of_range = || KeyError::OutOfRange {
            value: t.to_string(),
            range: self.range().2,
        };
        match self.param {
            Param::Mode => match (Mode::parse(t), t.parse::<f64>()) {
                (Some(m), _) => Ok(Value::Mode(m)),
                (None, Ok(code)) => self.typed(code).ok_or_else(out_of_range),
                (None, Err(_)) => Err(KeyError::UnknownMode(t.to_string())),
            },
            // Degrees unless a unit says otherwise, as the case file's angles.
            Param::Bend => self
                .typed(crate::units::parse_angle_deg(t)?.to_radians())
                .ok_or_else(out_of_range),
            _ => match (t.parse::<f64>(), self.range().0) {
                (Ok(x), _) => self.number(x).map_err(|e| match e {
                    KeyError::OutOfRange { .. } => out_of_range(),
                    e => e,
                }),
                (Err(_), Some(d)) => self.typed(parse_quantity(t, d)?).ok_or_else(out_of_range),
                (Err(_), None) => Err(KeyError::NotANumber(t.to_string())),
            },
        }
    }

    /// A bare number as a case file writes it (`mu = [0.2, 0.3]`; a mode's code; a bend in
    /// degrees), refused where the key's unit makes a bare number ambiguous
    /// ([`crate::units::bare_number_trap`]) and checked against the key's range.
    pub fn number(&self, x: f64) -> Result<Value, KeyError> {
        if let Some(m) = self
            .range()
            .0
            .and_then(|d| crate::units::bare_number_trap(d, x))
        {
            return Err(KeyError::BareNumber(m));
        }
        let si = match self.param {
            Param::Bend => x.to_radians(),
            _ => x,
        };
        self.typed(si).ok_or_else(|| KeyError::OutOfRange {
            value: crate::units::show(x),
            range: self.range().2,
        })
    }

    /// An SI value (a sample drawn from a distribution, already in SI; a mode's or a
    /// layout's code) checked against the key's range, with no text in between.
    pub fn si(&self, x: f64) -> Result<Value, KeyError> {
        self.typed(x).ok_or_else(|| KeyError::OutOfRange {
            value: crate::units::show(x),
            range: self.range().2,
        })
    }

    /// The key's allowed range in words.
    pub fn range_words(&self) -> &'static str {
        self.range().2
    }

    /// `x` (SI or a code) as this key's value, if it lies in the key's range.
    fn typed(&self, x: f64) -> Option<Value> {
        let (_, ok, _) = self.range();
        if !(x.is_finite() && ok(x)) {
            return None;
        }
        Some(match self.param {
            Param::Mode => Value::Mode(Mode::ALL[x as usize]),
            Param::Layout => Value::Layout(x as usize),
            _ => Value::Number(x),
        })
    }

    /// The key's unit dimension (for parsing a number written with a unit), its range in SI
    /// and the range in words ([`Param::range`]).
    fn range(&self) -> (Option<Dimension>, fn(f64) -> bool, &'static str) {
        self.param.range()
    }
}

impl Param {
    /// The parameter's unit dimension, its range in SI (or of its codes) and the range in
    /// words: the one range an ensemble's override and the case file's own key
    /// (`operation.weight_on_bit`, `contact.exponent`, … : `crate::case`) are checked
    /// against.
    pub fn range(self) -> (Option<Dimension>, fn(f64) -> bool, &'static str) {
        match self {
            Param::Mode => (
                None,
                |x| x.fract() == 0.0 && (0.0..Mode::ALL.len() as f64).contains(&x),
                "rotating, tripping_in, tripping_out, sliding, reaming, back_reaming (or their codes 0 … 5)",
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_and_layouts_are_typed_values() {
        let mode = Key::parse("mode").unwrap();
        assert_eq!(mode.value("reaming").unwrap(), Value::Mode(Mode::Reaming));
        // A code, as a distribution over modes draws it.
        assert_eq!(mode.value("5").unwrap(), Value::Mode(Mode::BackReaming));
        assert_eq!(mode.si(2.0).unwrap(), Value::Mode(Mode::TrippingOut));
        assert_eq!(Value::Mode(Mode::Sliding).si(), 3.0);
        assert_eq!(Value::Mode(Mode::TrippingIn).to_string(), "tripping_in");
        assert!(matches!(
            mode.value("spinning"),
            Err(KeyError::UnknownMode(_))
        ));
        assert!(matches!(mode.value("6"), Err(KeyError::OutOfRange { .. })));
        assert!(mode.si(1.5).is_err());
        for m in Mode::ALL {
            assert_eq!(Mode::parse(m.name()), Some(m));
            assert_eq!(Mode::ALL[m.code()], m);
        }
        let layout = Key::parse("layout").unwrap();
        assert_eq!(layout.number(2.0).unwrap(), Value::Layout(2));
        assert!(layout.number(0.0).is_err());
        // A bare number is the value as written: degrees for a bend, SI else.
        let bend = Key::parse("bend").unwrap();
        assert_eq!(bend.number(2.0).unwrap(), bend.value("2").unwrap());
        assert_eq!(bend.value("2 deg").unwrap().si(), 2f64.to_radians());
        let e = bend.number(7.0).unwrap_err().to_string();
        assert!(e.starts_with("7 out of range"), "{e}");
        // A bare rotary speed is refused, a sampled SI one is not.
        let rpm = Key::parse("rpm").unwrap();
        assert!(matches!(rpm.number(90.0), Err(KeyError::BareNumber(_))));
        assert_eq!(rpm.si(9.0).unwrap(), Value::Number(9.0));
    }

    #[test]
    fn a_case_files_mode_reads_as_a_mode() {
        #[derive(serde::Deserialize)]
        struct Op {
            mode: Mode,
        }
        let op: Op = toml::from_str("mode = \"back_reaming\"").unwrap();
        assert_eq!(op.mode, Mode::BackReaming);
        let e = toml::from_str::<Op>("mode = \"spinning\"")
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("unknown mode \"spinning\"; allowed: rotating"),
            "{e}"
        );
    }
}
