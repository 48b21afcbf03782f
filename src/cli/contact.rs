//! `holewall contact`: the contact-element calculator over JSON Lines.
//!
//! One input object per line (keys in [`KEYS`]); one output object per line, in order:
//! `{"contact": bool, "g": [6], "K": [[3] ×6], "C": [[3] ×6], "c_omega": [6]}`.
//! Every line is read and checked before anything is computed or written: one bad line
//! gives messages naming the line and key, exit code 2 and no output at all.

use std::collections::BTreeMap;
use std::io::Write;

use serde::Serialize;
use serde_json::{Map, Value};

use crate::backend::{evaluate_contact, Backend, ContactResults, Precision};
use crate::error::{Error, InputError};
use crate::kernels::contact::ContactBatch;
use crate::physics::contact::{ContactMode, ContactParams, ContactResponse, FrictionModel};
use crate::physics::Real;

/// Accepted keys, with what each may hold.
pub const KEYS: &[(&str, &str)] = &[
    (
        "x0",
        "[3] finite numbers (m): the site's reference point on the hole axis",
    ),
    (
        "n",
        "[3] finite numbers, not all zero: hole axis direction (normalised on input)",
    ),
    ("hole_radius", "finite number > 0 (m)"),
    (
        "disk_radius",
        "finite number, 0 ≤ disk_radius ≤ hole_radius (m)",
    ),
    ("k_e", "finite number > 0 (N/m^m)"),
    ("m", "finite number > 0 (1 linear, 3/2 hard, 2/3 soft)"),
    ("c", "finite number ≥ 0 (N·s/m)"),
    ("mu_t", "finite number ≥ 0"),
    ("mu_l", "finite number ≥ 0"),
    ("eps", "finite number > 0 (m/s); optional, default 1e-3"),
    (
        "soft_blend",
        "finite number > 0 (m); optional, default 1e-5",
    ),
    ("friction", "\"split\" or \"coupled\""),
    ("mode", "\"dynamic\" or \"static\""),
    ("x", "[3] finite numbers (m): node position"),
    ("v", "[3] finite numbers (m/s): node velocity"),
    ("omega", "finite number (rad/s): spin rate about n"),
];

/// One validated input line.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactQuery {
    /// Site reference point.
    pub x0: [f64; 3],
    /// Hole axis (as given; normalised by the kernel batch).
    pub n: [f64; 3],
    /// Law parameters (clearance from the two radii).
    pub params: ContactParams<f64>,
    /// Friction model.
    pub friction: FrictionModel,
    /// Mode.
    pub mode: ContactMode,
    /// Node position.
    pub x: [f64; 3],
    /// Node velocity.
    pub v: [f64; 3],
    /// Spin rate.
    pub omega: f64,
}

struct LineReader<'a> {
    source_name: &'a str,
    line: usize,
    obj: &'a Map<String, Value>,
    errors: Vec<InputError>,
    f32_range: bool,
}

impl LineReader<'_> {
    fn err(&mut self, key: &str, message: String) {
        self.errors.push(InputError {
            source_name: self.source_name.to_string(),
            line: self.line,
            key: key.to_string(),
            message,
        });
    }

    fn allowed(key: &str) -> &'static str {
        KEYS.iter()
            .find(|(k, _)| *k == key)
            .map(|(_, a)| *a)
            .unwrap_or("")
    }

    fn finite(&mut self, key: &str, x: f64) -> Option<f64> {
        if !x.is_finite() {
            self.err(
                key,
                format!("{x} is not finite; allowed: {}", Self::allowed(key)),
            );
            return None;
        }
        if self.f32_range
            && x != 0.0
            && (x.abs() > f32::MAX as f64 || x.abs() < f32::MIN_POSITIVE as f64)
        {
            self.err(
                key,
                format!("{x} is outside the f32 normal range asked for by --precision f32"),
            );
            return None;
        }
        Some(x)
    }

    fn number(&mut self, key: &str, default: Option<f64>) -> Option<f64> {
        match self.obj.get(key) {
            None => match default {
                Some(d) => Some(d),
                None => {
                    self.err(key, format!("missing; allowed: {}", Self::allowed(key)));
                    None
                }
            },
            Some(Value::Number(num)) => match num.as_f64() {
                Some(x) => self.finite(key, x),
                None => {
                    self.err(
                        key,
                        format!(
                            "{num} is not representable; allowed: {}",
                            Self::allowed(key)
                        ),
                    );
                    None
                }
            },
            Some(other) => {
                self.err(
                    key,
                    format!(
                        "expected a number, got {other}; allowed: {}",
                        Self::allowed(key)
                    ),
                );
                None
            }
        }
    }

    fn ranged(&mut self, key: &str, default: Option<f64>, ok: impl Fn(f64) -> bool) -> Option<f64> {
        let x = self.number(key, default)?;
        if ok(x) {
            Some(x)
        } else {
            self.err(
                key,
                format!("{x} is out of range; allowed: {}", Self::allowed(key)),
            );
            None
        }
    }

    fn vec3(&mut self, key: &str) -> Option<[f64; 3]> {
        match self.obj.get(key) {
            Some(Value::Array(items)) if items.len() == 3 => {
                let mut out = [0.0; 3];
                let mut ok = true;
                for (k, item) in items.iter().enumerate() {
                    match item.as_f64() {
                        Some(x) => match self.finite(&format!("{key}[{k}]"), x) {
                            Some(x) => out[k] = x,
                            None => ok = false,
                        },
                        None => {
                            self.err(
                                &format!("{key}[{k}]"),
                                format!("expected a number, got {item}"),
                            );
                            ok = false;
                        }
                    }
                }
                ok.then_some(out)
            }
            Some(other) => {
                self.err(key, format!("expected an array of 3 numbers, got {other}"));
                None
            }
            None => {
                self.err(key, format!("missing; allowed: {}", Self::allowed(key)));
                None
            }
        }
    }

    fn choice<E: Copy>(&mut self, key: &str, options: &[(&str, E)]) -> Option<E> {
        match self.obj.get(key) {
            Some(Value::String(s)) => match options.iter().find(|(name, _)| name == s) {
                Some((_, e)) => Some(*e),
                None => {
                    self.err(
                        key,
                        format!("unknown value {s:?}; allowed: {}", Self::allowed(key)),
                    );
                    None
                }
            },
            Some(other) => {
                self.err(
                    key,
                    format!(
                        "expected a string, got {other}; allowed: {}",
                        Self::allowed(key)
                    ),
                );
                None
            }
            None => {
                self.err(key, format!("missing; allowed: {}", Self::allowed(key)));
                None
            }
        }
    }
}

/// Parses and validates one line. `f32_range` also rejects numbers f32 cannot hold.
pub fn parse_line(
    source_name: &str,
    line: usize,
    text: &str,
    f32_range: bool,
) -> Result<ContactQuery, Vec<InputError>> {
    let fail = |key: &str, message: String| {
        vec![InputError {
            source_name: source_name.to_string(),
            line,
            key: key.to_string(),
            message,
        }]
    };
    let value: Value = match serde_json::from_str(text) {
        Ok(v) => v,
        Err(e) => {
            let lower = text.to_ascii_lowercase();
            let message = if lower.contains("nan") || lower.contains("inf") {
                format!("not valid JSON ({e}); NaN and Infinity are not allowed: every value must be a finite number")
            } else if e.to_string().contains("number out of range") {
                format!(
                    "a number is out of the f64 range ({e}); every value must be a finite number"
                )
            } else {
                format!("not valid JSON: {e}")
            };
            return Err(fail("-", message));
        }
    };
    let Value::Object(obj) = &value else {
        return Err(fail("-", format!("expected a JSON object, got {value}")));
    };
    let mut r = LineReader {
        source_name,
        line,
        obj,
        errors: Vec::new(),
        f32_range,
    };
    for key in obj.keys() {
        if !KEYS.iter().any(|(k, _)| k == key) {
            let names: Vec<&str> = KEYS.iter().map(|(k, _)| *k).collect();
            r.err(
                key,
                format!("unknown key; allowed keys: {}", names.join(", ")),
            );
        }
    }
    let x0 = r.vec3("x0");
    let n = r.vec3("n");
    if let Some(n) = n {
        if n.iter().all(|c| *c == 0.0) {
            r.err(
                "n",
                "is the zero vector; the hole axis needs a direction".to_string(),
            );
        }
    }
    let hole_radius = r.ranged("hole_radius", None, |x| x > 0.0);
    let disk_radius = r.ranged("disk_radius", None, |x| x >= 0.0);
    if let (Some(rh), Some(rd)) = (hole_radius, disk_radius) {
        if rd > rh {
            r.err(
                "disk_radius",
                format!("{rd} exceeds hole_radius {rh}: the clearance ΔR = R_h − R_d must be ≥ 0"),
            );
        }
    }
    let k_e = r.ranged("k_e", None, |x| x > 0.0);
    let m = r.ranged("m", None, |x| x > 0.0);
    let c = r.ranged("c", None, |x| x >= 0.0);
    let mu_t = r.ranged("mu_t", None, |x| x >= 0.0);
    let mu_l = r.ranged("mu_l", None, |x| x >= 0.0);
    let eps = r.ranged("eps", Some(1e-3), |x| x > 0.0);
    let soft_blend = r.ranged("soft_blend", Some(1e-5), |x| x > 0.0);
    let friction = r.choice(
        "friction",
        &[
            ("split", FrictionModel::Split),
            ("coupled", FrictionModel::Coupled),
        ],
    );
    let mode = r.choice(
        "mode",
        &[
            ("dynamic", ContactMode::Dynamic),
            ("static", ContactMode::Static),
        ],
    );
    let x = r.vec3("x");
    let v = r.vec3("v");
    let omega = r.number("omega", None);
    if !r.errors.is_empty() {
        return Err(r.errors);
    }
    // All present: the error list is empty only when every field parsed.
    let (Some(x0), Some(n), Some(hole_radius), Some(disk_radius), Some(k_e), Some(m), Some(c)) =
        (x0, n, hole_radius, disk_radius, k_e, m, c)
    else {
        return Err(fail("-", "internal: incomplete line".into()));
    };
    let (
        Some(mu_t),
        Some(mu_l),
        Some(eps),
        Some(soft_blend),
        Some(friction),
        Some(mode),
        Some(x),
        Some(v),
        Some(omega),
    ) = (mu_t, mu_l, eps, soft_blend, friction, mode, x, v, omega)
    else {
        return Err(fail("-", "internal: incomplete line".into()));
    };
    Ok(ContactQuery {
        x0,
        n,
        params: ContactParams {
            clearance: hole_radius - disk_radius,
            disk_radius,
            wall_stiffness: k_e,
            spring_exponent: m,
            wall_damping: c,
            mu_t,
            mu_l,
            eps,
            soft_blend,
            side_friction: 1.0,
        },
        friction,
        mode,
        x,
        v,
        omega,
    })
}

/// Parses a whole JSON Lines text (blank lines skipped). All errors are collected.
pub fn parse_all(
    source_name: &str,
    text: &str,
    f32_range: bool,
) -> Result<Vec<ContactQuery>, Vec<InputError>> {
    let mut queries = Vec::new();
    let mut errors = Vec::new();
    for (k, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match parse_line(source_name, k + 1, line, f32_range) {
            Ok(q) => queries.push(q),
            Err(mut e) => errors.append(&mut e),
        }
    }
    if errors.is_empty() {
        Ok(queries)
    } else {
        Err(errors)
    }
}

#[derive(Serialize)]
struct OutputLine<T> {
    contact: bool,
    g: [T; 6],
    #[serde(rename = "K")]
    k: [[T; 3]; 6],
    #[serde(rename = "C")]
    c: [[T; 3]; 6],
    c_omega: [T; 6],
}

impl<T: Real> From<ContactResponse<T>> for OutputLine<T> {
    fn from(r: ContactResponse<T>) -> Self {
        OutputLine {
            contact: r.contact,
            g: r.g,
            k: r.k,
            c: r.c,
            c_omega: r.c_omega,
        }
    }
}

/// Evaluates the queries, grouped by (friction, mode) so each group runs one specialised
/// kernel; returns one JSON text per query, in input order.
pub fn evaluate_queries(
    backend: Backend,
    precision: Precision,
    queries: &[ContactQuery],
) -> Result<Vec<String>, Error> {
    let mut groups: BTreeMap<(u8, u8), Vec<usize>> = BTreeMap::new();
    for (k, q) in queries.iter().enumerate() {
        let key = (q.friction as u8, q.mode as u8);
        groups.entry(key).or_default().push(k);
    }
    let mut lines = vec![String::new(); queries.len()];
    for members in groups.values() {
        let first = &queries[members[0]];
        // One site per line, one variant: each line has its own axis and reference point.
        let mut batch = ContactBatch::<f64>::new(1, members.len());
        for (site, &k) in members.iter().enumerate() {
            let q = &queries[k];
            batch.set_site_normal(site, q.n);
            batch.set_params(site, &q.params);
            let d = [q.x[0] - q.x0[0], q.x[1] - q.x0[1], q.x[2] - q.x0[2]];
            batch.set_state(site, d, q.v, q.omega);
        }
        let terms = batch.required_terms(first.friction, first.mode);
        let results = evaluate_contact(backend, precision, &terms, &batch)?;
        for (site, &k) in members.iter().enumerate() {
            let text = match &results {
                ContactResults::F64(o) => {
                    serde_json::to_string(&OutputLine::from(o.response(site)))
                }
                ContactResults::F32(o) => {
                    serde_json::to_string(&OutputLine::from(o.response(site)))
                }
            };
            lines[k] = text.map_err(Error::from)?;
        }
    }
    Ok(lines)
}

/// Runs the command: reads `input`, writes all output lines to `out` only if every line
/// is valid.
pub fn run(
    backend: Backend,
    precision: Precision,
    source_name: &str,
    input: &str,
    out: &mut dyn Write,
) -> Result<(), Vec<Error>> {
    let queries = parse_all(source_name, input, precision == Precision::F32)
        .map_err(|errs| errs.into_iter().map(Error::Input).collect::<Vec<_>>())?;
    let lines = evaluate_queries(backend, precision, &queries).map_err(|e| vec![e])?;
    let mut text = String::with_capacity(lines.iter().map(|l| l.len() + 1).sum());
    for l in lines {
        text.push_str(&l);
        text.push('\n');
    }
    out.write_all(text.as_bytes())
        .map_err(|e| vec![Error::Io(e)])?;
    Ok(())
}
