//! Quantities with units, as engineers write them in case files: a bare number is SI; a
//! string is `"<number> <unit>"` (`"6.5 in"`, `"20 klbf"`, `"10 ppg"`, `"120 rpm"`,
//! `"1500 ft"`). The unit must fit the key's dimension.

use thiserror::Error;

/// Physical dimension of a case-file key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dimension {
    /// m
    Length,
    /// N
    Force,
    /// kg/m³
    Density,
    /// rad/s
    AngularSpeed,
    /// m/s
    Speed,
    /// Pa
    Pressure,
    /// N·m
    Torque,
    /// rad (case files speak degrees by default: see [`parse_angle_deg`])
    Angle,
    /// N/m
    Stiffness,
    /// N·s/m
    Damping,
    /// s
    Time,
    /// kg·m (a mass imbalance)
    MassLength,
    /// dimensionless
    Ratio,
}

impl Dimension {
    /// SI unit name, for messages.
    pub fn si(&self) -> &'static str {
        match self {
            Dimension::Length => "m",
            Dimension::Force => "N",
            Dimension::Density => "kg/m3",
            Dimension::AngularSpeed => "rad/s",
            Dimension::Speed => "m/s",
            Dimension::Pressure => "Pa",
            Dimension::Torque => "N.m",
            Dimension::Angle => "rad",
            Dimension::Stiffness => "N/m",
            Dimension::Damping => "N.s/m",
            Dimension::Time => "s",
            Dimension::MassLength => "kg.m",
            Dimension::Ratio => "1",
        }
    }
}

/// One pound-force (N).
pub const LBF: f64 = 4.448_221_615_260_5;
/// One foot (m).
pub const FT: f64 = 0.3048;
const INCH: f64 = 0.0254;

/// Known units: (name, dimension, factor to SI).
const UNITS: &[(&str, Dimension, f64)] = &[
    ("m", Dimension::Length, 1.0),
    ("mm", Dimension::Length, 1e-3),
    ("cm", Dimension::Length, 1e-2),
    ("km", Dimension::Length, 1e3),
    ("in", Dimension::Length, INCH),
    ("ft", Dimension::Length, FT),
    ("N", Dimension::Force, 1.0),
    ("kN", Dimension::Force, 1e3),
    ("MN", Dimension::Force, 1e6),
    ("lbf", Dimension::Force, LBF),
    ("klbf", Dimension::Force, 1e3 * LBF),
    ("kgf", Dimension::Force, 9.806_65),
    ("tf", Dimension::Force, 9806.65),
    ("kg/m3", Dimension::Density, 1.0),
    ("g/cm3", Dimension::Density, 1e3),
    ("sg", Dimension::Density, 1e3),
    ("ppg", Dimension::Density, 119.826_427),
    ("lb/gal", Dimension::Density, 119.826_427),
    ("rad/s", Dimension::AngularSpeed, 1.0),
    ("rpm", Dimension::AngularSpeed, std::f64::consts::TAU / 60.0),
    ("m/s", Dimension::Speed, 1.0),
    ("m/h", Dimension::Speed, 1.0 / 3600.0),
    ("m/min", Dimension::Speed, 1.0 / 60.0),
    ("ft/h", Dimension::Speed, FT / 3600.0),
    ("ft/min", Dimension::Speed, FT / 60.0),
    ("Pa", Dimension::Pressure, 1.0),
    ("kPa", Dimension::Pressure, 1e3),
    ("MPa", Dimension::Pressure, 1e6),
    ("GPa", Dimension::Pressure, 1e9),
    ("psi", Dimension::Pressure, LBF / (INCH * INCH)),
    ("ksi", Dimension::Pressure, 1e3 * LBF / (INCH * INCH)),
    ("Mpsi", Dimension::Pressure, 1e6 * LBF / (INCH * INCH)),
    ("N.m", Dimension::Torque, 1.0),
    ("Nm", Dimension::Torque, 1.0),
    ("kN.m", Dimension::Torque, 1e3),
    ("ft.lbf", Dimension::Torque, FT * LBF),
    ("kft.lbf", Dimension::Torque, 1e3 * FT * LBF),
    ("rad", Dimension::Angle, 1.0),
    ("deg", Dimension::Angle, std::f64::consts::PI / 180.0),
    ("N/m", Dimension::Stiffness, 1.0),
    ("kN/m", Dimension::Stiffness, 1e3),
    ("MN/m", Dimension::Stiffness, 1e6),
    ("lbf/in", Dimension::Stiffness, LBF / INCH),
    ("N.s/m", Dimension::Damping, 1.0),
    ("kN.s/m", Dimension::Damping, 1e3),
    ("s", Dimension::Time, 1.0),
    ("ms", Dimension::Time, 1e-3),
    ("min", Dimension::Time, 60.0),
    ("h", Dimension::Time, 3600.0),
    ("kg.m", Dimension::MassLength, 1.0),
    ("g.mm", Dimension::MassLength, 1e-6),
    ("g.cm", Dimension::MassLength, 1e-5),
    ("oz.in", Dimension::MassLength, 0.028_349_523_125 * INCH),
    ("%", Dimension::Ratio, 1e-2),
];

/// A quantity that cannot be read.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum UnitError {
    /// Not `<number> <unit>`.
    #[error("cannot read {text:?} as \"<number> <unit>\"")]
    Malformed {
        /// The text.
        text: String,
    },
    /// Unknown unit.
    #[error("unknown unit {unit:?} (units of {dimension:?}: {known})")]
    Unknown {
        /// The unit.
        unit: String,
        /// The key's dimension.
        dimension: Dimension,
        /// Units that would fit.
        known: String,
    },
    /// Unit of another dimension.
    #[error("unit {unit:?} is a {found:?}, but this key is a {expected:?} (e.g. {example})")]
    WrongDimension {
        /// The unit.
        unit: String,
        /// Its dimension.
        found: Dimension,
        /// The key's dimension.
        expected: Dimension,
        /// A unit that fits.
        example: String,
    },
    /// NaN or infinite.
    #[error("{text:?} is not a finite number")]
    NotFinite {
        /// The text.
        text: String,
    },
}

fn units_of(dimension: Dimension) -> String {
    UNITS
        .iter()
        .filter(|(_, d, _)| *d == dimension)
        .map(|(n, _, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Normalises the spellings engineers use: `N·m`, `N-m`, `N m` → `N.m`; `deg/30m` stays.
fn normalise(unit: &str) -> String {
    unit.trim()
        .replace(['·', '-', '*'], ".")
        .replace("ft.lb", "ft.lbf")
        .replace("ft.lbff", "ft.lbf")
        .replace("kg/m^3", "kg/m3")
        .replace("g/cc", "g/cm3")
}

/// Parses `"<number> <unit>"` (or a bare number, in SI) into SI units of `dimension`.
pub fn parse_quantity(text: &str, dimension: Dimension) -> Result<f64, UnitError> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
        .unwrap_or(t.len());
    // "1e3 m": the number may contain 'e'; a unit never starts right after a digit with 'e'
    // followed by a digit, so take the longest prefix that parses.
    let (mut number, mut unit) = (&t[..split], t[split..].trim());
    if number.parse::<f64>().is_err() {
        // e.g. "5 ft" splits fine; "2e" from "2 each" does not: back off one char at a time.
        let mut k = split;
        while k > 0 && t[..k].parse::<f64>().is_err() {
            k -= 1;
        }
        number = &t[..k];
        unit = t[k..].trim();
    }
    let value: f64 = number.parse().map_err(|_| UnitError::Malformed {
        text: text.to_string(),
    })?;
    if !value.is_finite() {
        return Err(UnitError::NotFinite {
            text: text.to_string(),
        });
    }
    if unit.is_empty() {
        return Ok(value);
    }
    let unit_n = normalise(unit);
    match UNITS.iter().find(|(n, _, _)| *n == unit_n) {
        Some((_, d, f)) if *d == dimension => Ok(value * f),
        Some((_, d, _)) => Err(UnitError::WrongDimension {
            unit: unit.to_string(),
            found: *d,
            expected: dimension,
            example: units_of(dimension),
        }),
        None => Err(UnitError::Unknown {
            unit: unit.to_string(),
            dimension,
            known: units_of(dimension),
        }),
    }
}

/// Parses an angle; a bare number is in **degrees** (the drilling convention for
/// inclination and azimuth). Returns degrees.
pub fn parse_angle_deg(text: &str) -> Result<f64, UnitError> {
    let t = text.trim();
    if let Ok(v) = t.parse::<f64>() {
        return if v.is_finite() {
            Ok(v)
        } else {
            Err(UnitError::NotFinite {
                text: text.to_string(),
            })
        };
    }
    parse_quantity(text, Dimension::Angle).map(f64::to_degrees)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    #[test]
    fn field_units_convert_to_si() {
        assert!(close(
            parse_quantity("6.5 in", Dimension::Length).unwrap(),
            0.1651
        ));
        assert!(close(
            parse_quantity("1500 ft", Dimension::Length).unwrap(),
            457.2
        ));
        assert!(close(
            parse_quantity("20 klbf", Dimension::Force).unwrap(),
            88_964.432_305_21
        ));
        assert!(close(
            parse_quantity("10 ppg", Dimension::Density).unwrap(),
            1198.26427
        ));
        assert!(close(
            parse_quantity("1.2 sg", Dimension::Density).unwrap(),
            1200.0
        ));
        assert!(close(
            parse_quantity("120 rpm", Dimension::AngularSpeed).unwrap(),
            4.0 * std::f64::consts::PI
        ));
        assert!(close(
            parse_quantity("30e6 psi", Dimension::Pressure).unwrap(),
            206_842_718_795.05
        ));
        assert!(close(
            parse_quantity("10 kft·lbf", Dimension::Torque).unwrap(),
            13_558.179_483_314
        ));
        assert!(close(
            parse_quantity("10 kft-lbf", Dimension::Torque).unwrap(),
            13_558.179_483_314
        ));
        assert!(close(
            parse_quantity("24.5 m/h", Dimension::Speed).unwrap(),
            24.5 / 3600.0
        ));
        assert!(close(
            parse_quantity("2.5e-3", Dimension::Length).unwrap(),
            2.5e-3
        ));
        assert!(close(
            parse_quantity("1e3 N", Dimension::Force).unwrap(),
            1e3
        ));
        assert!(close(parse_angle_deg("12").unwrap(), 12.0));
        assert!(close(
            parse_angle_deg("0.5 rad").unwrap(),
            0.5f64.to_degrees()
        ));
    }

    #[test]
    fn wrong_units_are_named() {
        let e = parse_quantity("20 klbf", Dimension::Length).unwrap_err();
        assert!(matches!(
            e,
            UnitError::WrongDimension {
                found: Dimension::Force,
                expected: Dimension::Length,
                ..
            }
        ));
        assert!(e.to_string().contains("in, ft"));
        assert!(matches!(
            parse_quantity("3 furlongs", Dimension::Length),
            Err(UnitError::Unknown { .. })
        ));
        assert!(matches!(
            parse_quantity("inch 3", Dimension::Length),
            Err(UnitError::Malformed { .. })
        ));
        assert!(matches!(
            parse_quantity("inf m", Dimension::Length),
            Err(UnitError::Malformed { .. }) | Err(UnitError::NotFinite { .. })
        ));
        assert!(matches!(
            parse_quantity("1e999 m", Dimension::Length),
            Err(UnitError::NotFinite { .. })
        ));
    }
}

/// The common traps of a bare number (read as SI) for a key of `dimension`, with the input
/// the user most likely meant; `None` where a bare number is plainly SI. This is the one
/// policy for bare numbers: case files and variant values both call it.
///
/// - rotary speed: any bare number but 0 is refused (90 would be 90 rad/s = 859 rpm);
/// - density: a bare number below 500 (kg/m³: lighter than any drilling fluid but gas) is
///   refused, suggesting `"1.2 sg"` (or `"10 ppg"` for 6 … 25);
/// - force: a bare number between 0 and 100 (N: the weight of 10 kg) is refused,
///   suggesting kN or klbf.
pub fn bare_number_trap(dimension: Dimension, x: f64) -> Option<String> {
    match dimension {
        Dimension::AngularSpeed if x != 0.0 => Some(format!(
            "a bare number is ambiguous for a rotary speed: write the unit, \"{} rpm\" (a bare \
             {} would be {} rad/s = {} rpm)",
            show(x),
            show(x),
            show(x),
            show(x * 60.0 / std::f64::consts::TAU)
        )),
        Dimension::Density if x > 0.0 && x < 500.0 => {
            let ppg = if (6.0..=25.0).contains(&x) {
                format!(" or \"{} ppg\"", show(x))
            } else {
                String::new()
            };
            Some(format!(
                "a bare number is kg/m3, and {} kg/m3 is lighter than any drilling fluid but \
                 gas: did you mean \"{} sg\"{ppg}?",
                show(x),
                show(x)
            ))
        }
        Dimension::Force if x > 0.0 && x < 100.0 => Some(format!(
            "a bare number is N, and {} N is the weight of {} kg: did you mean \"{} kN\" or \
             \"{} klbf\"? (write \"{} N\" if you mean it)",
            show(x),
            show(x / 9.806_65),
            show(x),
            show(x),
            show(x)
        )),
        _ => None,
    }
}

/// A value for a message: six significant digits, no trailing zeros — `0.2159`, not the
/// `0.21589999999999998` that 8.5 in converts to.
pub fn show(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (5 - x.abs().log10().floor() as i32).clamp(0, 15) as usize;
    let s = format!("{x:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod show_tests {
    #[test]
    fn six_significant_digits() {
        assert_eq!(super::show(8.5 * 0.0254), "0.2159");
        assert_eq!(super::show(1500.0), "1500");
        assert_eq!(super::show(1e-9), "0.000000001");
        assert_eq!(super::show(-2.5), "-2.5");
        assert_eq!(super::show(123456789.0), "123456789");
    }
}

/// Drilling-fluid densities a case may hold (kg/m³): 0.5 … 3.0 sg (4.2 … 25 ppg), or 0 for
/// a dry string (no buoyancy). Outside, a unit mix-up is far likelier than the fluid.
pub const FLUID_DENSITY_RANGE: (f64, f64) = (500.0, 3000.0);

/// The plausibility trap of a mud density `si` (kg/m³) written as `written`: `None` within
/// [`FLUID_DENSITY_RANGE`] (or 0), else what it is in sg and ppg and what the user likely
/// meant — the number written read as sg or as ppg, whichever is a drilling fluid. The same
/// policy as [`bare_number_trap`], for values that carry a unit (`"1.3 ppg"` is 156 kg/m³).
pub fn fluid_density_trap(si: f64, written: &str) -> Option<String> {
    let (lo, hi) = FLUID_DENSITY_RANGE;
    if si == 0.0 || (lo..=hi).contains(&si) {
        return None;
    }
    let sg = si / 1000.0;
    let ppg = si / 119.826_427;
    let number = written
        .split_whitespace()
        .next()
        .and_then(|n| n.parse::<f64>().ok());
    let intent = match number {
        Some(n) if (lo / 1000.0..=hi / 1000.0).contains(&n) => {
            format!(": did you mean \"{} sg\"?", show(n))
        }
        Some(n) if (lo / 119.826_427..=hi / 119.826_427).contains(&n) => {
            format!(": did you mean \"{} ppg\"?", show(n))
        }
        _ => String::new(),
    };
    Some(format!(
        "{} is {} kg/m3 ({} sg, {} ppg), {} any drilling fluid (0.5 … 3.0 sg, 4.2 … 25 ppg; \
         0 for a dry string){intent}",
        written.trim(),
        show(si),
        show(sg),
        show(ppg),
        if si < lo {
            "lighter than"
        } else {
            "heavier than"
        }
    ))
}

/// Dogleg severity (°/30 m) above which a survey gets a warning: sharper than motor and
/// rotary-steerable builds of long- and medium-radius wells.
pub const DOGLEG_WARNING_DEG_PER_30M: f64 = 15.0;

/// Dogleg severity (°/30 m) above which a survey is refused unless `well.max_dogleg` raises
/// the limit (short-radius wells): more likely a typo in a station than a hole.
pub const DOGLEG_LIMIT_DEG_PER_30M: f64 = 30.0;

/// A survey that ends above the bit by at most this much (m) is projected to the bit along
/// its last tangent, with a warning: an MWD survey's last station lies the sensor's offset
/// (10–25 m) above the bit, and a few metres more may be drilled since. Farther, refused: a
/// survey of another well, or a total_md in the wrong unit.
pub const SURVEY_PROJECTION_M: f64 = 30.0;

/// A survey that runs past the deepest MD of its case by more than this factor is refused:
/// the likeliest reason is MD in feet read as metres (3.28×).
pub const SURVEY_PAST_CASE_FACTOR: f64 = 1.5;

#[cfg(test)]
mod plausibility_tests {
    use super::*;

    #[test]
    fn mud_densities_outside_drilling_fluids_are_trapped_with_the_intent() {
        // "1.3 ppg" (156 kg/m3): meant 1.3 sg.
        let si = parse_quantity("1.3 ppg", Dimension::Density).unwrap();
        let m = fluid_density_trap(si, "1.3 ppg").unwrap();
        assert!(m.contains("did you mean \"1.3 sg\""), "{m}");
        assert!(m.contains("lighter than"), "{m}");
        // "12 sg" (12,000 kg/m3): meant 12 ppg.
        let m = fluid_density_trap(12_000.0, "12 sg").unwrap();
        assert!(m.contains("did you mean \"12 ppg\""), "{m}");
        // Ordinary fluids and a dry string pass.
        for t in ["1.2 sg", "10 ppg", "1500 kg/m3", "0.5 sg", "25 ppg"] {
            let si = parse_quantity(t, Dimension::Density).unwrap();
            assert_eq!(fluid_density_trap(si, t), None, "{t}");
        }
        assert_eq!(fluid_density_trap(0.0, "0 sg"), None);
    }
}
