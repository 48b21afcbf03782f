//! A float that counts the operations done on it: the operation counts of the element
//! formulas (`holewall bench element`) come from running the same generic code the solvers
//! run, not from reading it. `Dual<Counted>` counts the real operations of a dual-number
//! evaluation exactly.

// The operators count with `+=` inside `Sub`, `Mul`, `Div`: that is the point.
#![allow(clippy::suspicious_arithmetic_impl)]

use std::cell::Cell;
use std::ops::{Add, Div, Mul, Neg, Sub};

use super::rotation::Trig;
use super::Real;

/// Operations counted, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct OpCounts {
    /// Additions and subtractions.
    pub add: u64,
    /// Multiplications.
    pub mul: u64,
    /// Divisions.
    pub div: u64,
    /// Square roots.
    pub sqrt: u64,
    /// sin, cos, atan2, powf.
    pub transcendental: u64,
    /// Comparisons and negations (not floating-point operations; listed for completeness).
    pub other: u64,
}

impl OpCounts {
    /// Floating-point operations: additions, multiplications, divisions and square roots
    /// count one each; a transcendental counts `transcendental_cost`.
    pub fn flops(&self, transcendental_cost: u64) -> u64 {
        self.add + self.mul + self.div + self.sqrt + transcendental_cost * self.transcendental
    }
}

thread_local! {
    static COUNTS: Cell<OpCounts> = Cell::new(OpCounts::default());
}

fn bump(f: impl FnOnce(&mut OpCounts)) {
    COUNTS.with(|c| {
        let mut v = c.get();
        f(&mut v);
        c.set(v);
    });
}

/// Runs `f` and returns its result with the operations it did on [`Counted`] values (this
/// thread's).
pub fn count<R>(f: impl FnOnce() -> R) -> (R, OpCounts) {
    let before = COUNTS.with(|c| c.replace(OpCounts::default()));
    let r = f();
    let counted = COUNTS.with(|c| c.replace(before));
    (r, counted)
}

/// An `f64` that counts the operations done on it.
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct Counted(pub f64);

impl Add for Counted {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        bump(|c| c.add += 1);
        Counted(self.0 + o.0)
    }
}

impl Sub for Counted {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        bump(|c| c.add += 1);
        Counted(self.0 - o.0)
    }
}

impl Mul for Counted {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        bump(|c| c.mul += 1);
        Counted(self.0 * o.0)
    }
}

impl Div for Counted {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        bump(|c| c.div += 1);
        Counted(self.0 / o.0)
    }
}

impl Neg for Counted {
    type Output = Self;
    fn neg(self) -> Self {
        bump(|c| c.other += 1);
        Counted(-self.0)
    }
}

impl Real for Counted {
    fn zero() -> Self {
        Counted(0.0)
    }
    fn one() -> Self {
        Counted(1.0)
    }
    fn abs(self) -> Self {
        bump(|c| c.other += 1);
        Counted(self.0.abs())
    }
    fn sqrt(self) -> Self {
        bump(|c| c.sqrt += 1);
        Counted(self.0.sqrt())
    }
    fn powf(self, e: Self) -> Self {
        bump(|c| c.transcendental += 1);
        Counted(self.0.powf(e.0))
    }
    fn from_f64_lossy(x: f64) -> Self {
        Counted(x)
    }
    fn to_f64_lossy(self) -> f64 {
        self.0
    }
    const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;
    const NAME: &'static str = "counted";
}

impl Trig for Counted {
    fn sin(self) -> Self {
        bump(|c| c.transcendental += 1);
        Counted(self.0.sin())
    }
    fn cos(self) -> Self {
        bump(|c| c.transcendental += 1);
        Counted(self.0.cos())
    }
    fn atan2(self, x: Self) -> Self {
        bump(|c| c.transcendental += 1);
        Counted(self.0.atan2(x.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::dual::Dual;

    #[test]
    fn counts_what_is_done() {
        let (v, c) = count(|| {
            let a = Counted(2.0);
            (a * a + a / Counted(4.0)).sqrt() - a
        });
        assert_eq!(v.0, (4.5f64).sqrt() - 2.0);
        assert_eq!((c.add, c.mul, c.div, c.sqrt), (2, 1, 1, 1));
        // A dual multiplication: one product for the value, two and a sum for the
        // derivative.
        let (_, c) =
            count(|| Dual::new(Counted(1.0), Counted(1.0)) * Dual::new(Counted(2.0), Counted(0.0)));
        assert_eq!((c.add, c.mul), (1, 3));
    }
}
