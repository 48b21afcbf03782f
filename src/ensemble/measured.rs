//! The measured file of `holewall calibrate` ([`super`] for its columns): hook loads and
//! surface torques against bit depth, one operation per row.

use std::path::Path;

use serde::Serialize;

use crate::error::InputError;

/// A measured operation, as the rig logs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MeasuredMode {
    /// Pulling out (tripping out).
    PickUp,
    /// Running in (tripping in).
    SlackOff,
    /// Rotating off bottom.
    Rotating,
    /// Rotating on bottom with weight on bit.
    Drilling,
    /// Running in while rotating.
    Reaming,
    /// Pulling out while rotating.
    BackReaming,
}

impl MeasuredMode {
    /// Every mode and its names in a measured file.
    pub const NAMES: [(MeasuredMode, &'static [&'static str]); 6] = [
        (MeasuredMode::PickUp, &["pick_up", "tripping_out"]),
        (MeasuredMode::SlackOff, &["slack_off", "tripping_in"]),
        (MeasuredMode::Rotating, &["rotating", "rotating_off_bottom"]),
        (MeasuredMode::Drilling, &["drilling"]),
        (MeasuredMode::Reaming, &["reaming"]),
        (MeasuredMode::BackReaming, &["back_reaming"]),
    ];

    /// The mode's first name.
    pub fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(m, _)| *m == self)
            .map_or("?", |(_, n)| n[0])
    }

    /// The model's operation (a `mode` key's value).
    pub fn model_mode(self) -> crate::keys::Mode {
        use crate::keys::Mode;
        match self {
            MeasuredMode::PickUp => Mode::TrippingOut,
            MeasuredMode::SlackOff => Mode::TrippingIn,
            MeasuredMode::Rotating | MeasuredMode::Drilling => Mode::Rotating,
            MeasuredMode::Reaming => Mode::Reaming,
            MeasuredMode::BackReaming => Mode::BackReaming,
        }
    }

    /// Whether the string rotates (a surface torque is measured).
    pub fn rotates(self) -> bool {
        self.model_mode().rotates()
    }
}

/// One measurement (SI).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// Line in the file.
    pub line: usize,
    /// Bit depth (MD, m).
    pub bit_md: f64,
    /// Operation.
    pub mode: MeasuredMode,
    /// Weight on bit (N): drilling rows.
    pub wob: f64,
    /// Rotary speed (rad/s), where the row gives one.
    pub rpm: Option<f64>,
    /// Hook load as the weight indicator read it (N).
    pub hook_load: Option<f64>,
    /// Surface torque (N·m).
    pub surface_torque: Option<f64>,
}

/// One point series per mode (named `names[k]` for `modes[k]`): the points of `items` of
/// that mode.
pub fn by_mode<'a, T>(
    modes: &[MeasuredMode],
    names: &'a [String],
    items: &[T],
    mode: impl Fn(&T) -> MeasuredMode,
    point: impl Fn(&T) -> Option<(f64, f64)>,
) -> Vec<crate::plots::Series<'a>> {
    modes
        .iter()
        .zip(names)
        .map(|(m, name)| crate::plots::Series {
            name,
            points: items
                .iter()
                .filter(|x| mode(x) == *m)
                .filter_map(&point)
                .collect(),
            wide: false,
        })
        .collect()
}

/// The modes in `rows`' order of [`MeasuredMode::NAMES`].
pub fn modes_of(modes: impl Iterator<Item = MeasuredMode> + Clone) -> Vec<MeasuredMode> {
    MeasuredMode::NAMES
        .iter()
        .map(|(m, _)| *m)
        .filter(|m| modes.clone().any(|x| x == *m))
        .collect()
}

/// Reads a measured file ([module docs](self) for its columns).
pub fn read_measured(path: &Path) -> Result<Vec<Measurement>, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError {
        source_name: path.display().to_string(),
        line: 0,
        key: "--measured".into(),
        message: format!("cannot read: {e}"),
    })?;
    parse_measured(&path.display().to_string(), &text)
}

/// Parses a measured file's text; errors name the file, line, column and what is allowed.
pub fn parse_measured(source: &str, text: &str) -> Result<Vec<Measurement>, InputError> {
    let err = |line: usize, key: &str, message: String| InputError {
        source_name: source.to_string(),
        line,
        key: key.to_string(),
        message,
    };
    use crate::units::{FT, LBF};
    let mut reader = crate::ensemble::input_csv(text);
    let header = reader
        .headers()
        .map_err(|e| err(1, "-", format!("not a CSV: {e}")))?
        .clone();
    // (column, scale to SI) of the first header that names a quantity.
    let find = |names: &[(&str, f64)]| -> Option<(usize, f64)> {
        names.iter().find_map(|(n, s)| {
            header
                .iter()
                .position(|h| h.eq_ignore_ascii_case(n))
                .map(|c| (c, *s))
        })
    };
    let depth = find(&[
        ("bit_md_m", 1.0),
        ("bit_md_ft", FT),
        ("depth_m", 1.0),
        ("depth_ft", FT),
    ])
    .ok_or_else(|| {
        err(
            1,
            "bit_md_m",
            "no bit-depth column: bit_md_m or bit_md_ft".into(),
        )
    })?;
    let mode = find(&[("mode", 1.0)])
        .ok_or_else(|| err(1, "mode", "no mode column".into()))?
        .0;
    let hook = find(&[
        ("hook_load_n", 1.0),
        ("hook_load_kn", 1e3),
        ("hook_load_klbf", 1e3 * LBF),
    ]);
    let torque = find(&[
        ("surface_torque_nm", 1.0),
        ("surface_torque_knm", 1e3),
        ("surface_torque_kftlbf", 1e3 * LBF * FT),
    ]);
    let wob = find(&[("wob_n", 1.0), ("wob_kn", 1e3), ("wob_klbf", 1e3 * LBF)]);
    let rpm = find(&[("rpm", std::f64::consts::PI / 30.0)]);
    if hook.is_none() && torque.is_none() {
        return Err(err(
            1,
            "hook_load_kn",
            "neither a hook-load column (hook_load_n, hook_load_kn, hook_load_klbf) nor a \
             torque column (surface_torque_nm, surface_torque_knm, surface_torque_kftlbf)"
                .into(),
        ));
    }
    let mut out = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line() as usize);
            err(line, "-", e.to_string())
        })?;
        let line = record.position().map_or(0, |p| p.line() as usize);
        let cell = |c: usize| record.get(c).unwrap_or("").trim();
        let number = |col: Option<(usize, f64)>,
                      ok: &dyn Fn(f64) -> bool,
                      range: &str|
         -> Result<Option<f64>, InputError> {
            let Some((c, scale)) = col else {
                return Ok(None);
            };
            let t = cell(c);
            if t.is_empty() {
                return Ok(None);
            }
            let name = &header[c];
            let x: f64 = t
                .parse()
                .map_err(|_| err(line, name, format!("{t:?} is not a number")))?;
            if !x.is_finite() || !ok(x) {
                return Err(err(
                    line,
                    name,
                    format!("{t} out of range; allowed: {range}"),
                ));
            }
            Ok(Some(x * scale))
        };
        let md = number(Some(depth), &|x| x > 0.0, "> 0")?
            .ok_or_else(|| err(line, &header[depth.0], "empty bit depth".into()))?;
        let name = cell(mode);
        let m = MeasuredMode::NAMES
            .iter()
            .find(|(_, n)| n.contains(&name))
            .map(|(m, _)| *m)
            .ok_or_else(|| {
                err(
                    line,
                    "mode",
                    format!(
                        "unknown mode {name:?}; allowed: pick_up (tripping_out), slack_off \
                         (tripping_in), rotating, drilling, reaming, back_reaming"
                    ),
                )
            })?;
        let h = number(hook, &|x| x > 0.0, "> 0")?;
        let t = number(torque, &|x| x >= 0.0, "≥ 0")?;
        let w = number(wob, &|x| x >= 0.0, "≥ 0")?;
        let r = number(rpm, &|x| x > 0.0 && x <= 1000.0, "0 < rpm ≤ 1000")?;
        if h.is_none() && t.is_none() {
            return Err(err(
                line,
                "-",
                "a row needs a hook load or a surface torque".into(),
            ));
        }
        if t.is_some() && !m.rotates() {
            return Err(err(
                line,
                &header[torque.map_or(0, |c| c.0)],
                format!(
                    "a surface torque in a {} row: the string does not rotate there (give \
                     torques in rotating, drilling, reaming or back_reaming rows)",
                    m.name()
                ),
            ));
        }
        if m == MeasuredMode::Drilling && w.is_none() {
            return Err(err(
                line,
                "wob_kn",
                "a drilling row needs its weight on bit (wob_n, wob_kn or wob_klbf)".into(),
            ));
        }
        if r.is_some() && !m.rotates() {
            return Err(err(
                line,
                "rpm",
                format!("an rpm in a {} row, which does not rotate", m.name()),
            ));
        }
        out.push(Measurement {
            line,
            bit_md: md,
            mode: m,
            wob: w.unwrap_or(0.0),
            rpm: r,
            hook_load: h,
            surface_torque: t,
        });
    }
    if out.is_empty() {
        return Err(err(1, "-", "no measurements".into()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_files_are_checked() {
        let ok = "bit_md_ft,mode,hook_load_klbf,surface_torque_kftlbf\n\
                  3000,pick_up,150,\n3000,rotating,130,8.5\n";
        let rows = parse_measured("m.csv", ok).unwrap();
        assert_eq!(rows.len(), 2);
        assert!((rows[0].bit_md - 914.4).abs() < 1e-9);
        assert!((rows[0].hook_load.unwrap() - 150e3 * 4.448_221_615_260_5).abs() < 1e-6);
        assert!((rows[1].surface_torque.unwrap() - 8.5e3 * 1.355_817_948_331_4).abs() < 1e-6);
        for (text, line, key) in [
            ("bit_md_m,mode,hook_load_kn\n1000,tripping,500\n", 2, "mode"),
            (
                "bit_md_m,mode,hook_load_kn\n1000,pick_up,-5\n",
                2,
                "hook_load_kn",
            ),
            (
                "bit_md_m,mode,hook_load_kn,surface_torque_knm\n1000,pick_up,500,10\n",
                2,
                "surface_torque_knm",
            ),
            (
                "bit_md_m,mode,hook_load_kn\n1000,drilling,500\n",
                2,
                "wob_kn",
            ),
            ("mode,hook_load_kn\npick_up,500\n", 1, "bit_md_m"),
            ("bit_md_m,mode\n1000,pick_up\n", 1, "hook_load_kn"),
            (
                "bit_md_m,mode,hook_load_kn\n1000,pick_up,abc\n",
                2,
                "hook_load_kn",
            ),
        ] {
            let e = parse_measured("m.csv", text).unwrap_err();
            assert_eq!((e.line, e.key.as_str()), (line, key), "{e}");
        }
    }
}
