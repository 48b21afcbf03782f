//! The reading context: the file's path and text, and the checked readers of a value
//! (quantity with units, number, angle) that name the file, line, key and allowed range.

use super::*;

pub(super) struct Ctx<'a> {
    pub(super) path: &'a Path,
    pub(super) text: &'a str,
}

impl Ctx<'_> {
    pub(super) fn line(&self, offset: usize) -> usize {
        self.text[..offset.min(self.text.len())]
            .matches('\n')
            .count()
            + 1
    }

    pub(super) fn err(
        &self,
        span: std::ops::Range<usize>,
        key: &str,
        message: impl Into<String>,
    ) -> InputError {
        InputError {
            source_name: self.path.display().to_string(),
            line: self.line(span.start),
            key: key.into(),
            message: message.into(),
        }
    }

    pub(super) fn quantity(
        &self,
        q: &Q,
        key: &str,
        dim: Dimension,
        ok: impl Fn(f64) -> bool,
        range: &str,
    ) -> Result<f64, InputError> {
        let v = match q.get_ref() {
            Quantity::Number(x) if x.is_finite() => {
                if let Some(m) = crate::units::bare_number_trap(dim, *x) {
                    return Err(self.err(q.span(), key, m));
                }
                *x
            }
            Quantity::Si(x) if x.is_finite() => *x,
            Quantity::Number(x) | Quantity::Si(x) => {
                return Err(self.err(
                    q.span(),
                    key,
                    format!("{x} is not finite; allowed: {range}"),
                ))
            }
            Quantity::Text(t) => {
                let v = parse_quantity(t, dim)
                    .map_err(|e| self.err(q.span(), key, format!("{e}; allowed: {range}")))?;
                if t.trim().parse::<f64>().is_ok() {
                    if let Some(m) = crate::units::bare_number_trap(dim, v) {
                        return Err(self.err(q.span(), key, m));
                    }
                }
                v
            }
        };
        if ok(v) {
            Ok(v)
        } else {
            Err(self.err(
                q.span(),
                key,
                format!("{v} {} is out of range; allowed: {range}", dim.si()),
            ))
        }
    }

    /// A fluid's density (kg/m³): ≥ 0, with the unit trap of
    /// [`crate::units::fluid_density_trap`] ("1.3 ppg … did you mean 1.3 sg?"); `zero` says
    /// what 0 means there.
    pub(super) fn fluid_density(&self, q: &Q, key: &str, zero: &str) -> Result<f64, InputError> {
        let v = self.quantity(
            q,
            key,
            Dimension::Density,
            |x| x >= 0.0,
            &format!("{zero} or 0.5 … 3.0 sg"),
        )?;
        let written = match q.get_ref() {
            Quantity::Text(t) => t.clone(),
            Quantity::Number(x) => crate::units::show(*x),
            Quantity::Si(x) => format!("{} kg/m3", crate::units::show(*x)),
        };
        match crate::units::fluid_density_trap(v, &written) {
            Some(m) => Err(self.err(q.span(), key, m)),
            None => Ok(v),
        }
    }

    pub(super) fn angle(
        &self,
        q: &Q,
        key: &str,
        ok: impl Fn(f64) -> bool,
        range: &str,
    ) -> Result<f64, InputError> {
        let v = match q.get_ref() {
            Quantity::Number(x) => *x,
            Quantity::Si(x) => x.to_degrees(),
            Quantity::Text(t) => parse_angle_deg(t)
                .map_err(|e| self.err(q.span(), key, format!("{e}; allowed: {range}")))?,
        };
        self.in_range(v, q.span(), key, ok, range, "°")
    }

    pub(super) fn number(
        &self,
        q: &Spanned<f64>,
        key: &str,
        ok: impl Fn(f64) -> bool,
        range: &str,
    ) -> Result<f64, InputError> {
        self.in_range(*q.get_ref(), q.span(), key, ok, range, "")
    }

    /// `v` if finite and `ok`, else the out-of-range error (`unit` written after the value).
    fn in_range(
        &self,
        v: f64,
        span: std::ops::Range<usize>,
        key: &str,
        ok: impl Fn(f64) -> bool,
        range: &str,
        unit: &str,
    ) -> Result<f64, InputError> {
        if v.is_finite() && ok(v) {
            Ok(v)
        } else {
            Err(self.err(
                span,
                key,
                format!("{v}{unit} is out of range; allowed: {range}"),
            ))
        }
    }
}
