//! A minimal double-double number (≈ 32 significant digits) for finite-difference checks of
//! the analytic Jacobians: products through `mul_add` (exact with FMA), division and square
//! root by one Newton correction, `powf` as `exp(e·ln x)` with argument reduction (error ≈ 1e-30). Tests only.

use std::ops::{Add, Div, Mul, Neg, Sub};

use super::Real;

/// `hi + lo` with `|lo| ≤ ulp(hi)/2`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dd {
    hi: f64,
    lo: f64,
}

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

impl Dd {
    fn new((hi, lo): (f64, f64)) -> Dd {
        Dd { hi, lo }
    }

    fn scale_pow2(self, k: i32) -> Dd {
        let f = 2f64.powi(k);
        Dd {
            hi: self.hi * f,
            lo: self.lo * f,
        }
    }

    fn exp(self) -> Dd {
        const LN2: Dd = Dd {
            hi: std::f64::consts::LN_2,
            lo: 2.319_046_813_846_299_6e-17,
        };
        let k = (self.hi / LN2.hi).round();
        let r = (self - LN2 * Dd::from(k)).scale_pow2(-5);
        // Taylor to r^16, |r| ≤ 0.011, then five squarings.
        let mut sum = Dd::from(1.0);
        let mut term = Dd::from(1.0);
        for j in 1..=16 {
            term = term * r / Dd::from(j as f64);
            sum = sum + term;
        }
        for _ in 0..5 {
            sum = sum * sum;
        }
        sum.scale_pow2(k as i32)
    }

    fn ln(self) -> Dd {
        let mut y = Dd::from(self.hi.ln());
        for _ in 0..2 {
            y = y + self * (-y).exp() - Dd::from(1.0);
        }
        y
    }
}

impl From<f64> for Dd {
    fn from(x: f64) -> Dd {
        Dd { hi: x, lo: 0.0 }
    }
}

impl From<Dd> for f64 {
    fn from(x: Dd) -> f64 {
        x.hi + x.lo
    }
}

impl PartialOrd for Dd {
    fn partial_cmp(&self, other: &Dd) -> Option<std::cmp::Ordering> {
        match self.hi.partial_cmp(&other.hi) {
            Some(std::cmp::Ordering::Equal) => self.lo.partial_cmp(&other.lo),
            o => o,
        }
    }
}

impl Neg for Dd {
    type Output = Dd;
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Add for Dd {
    type Output = Dd;
    fn add(self, y: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, y.hi);
        let (t, f) = two_sum(self.lo, y.lo);
        let (s, e) = quick_two_sum(s, e + t);
        Dd::new(quick_two_sum(s, e + f))
    }
}

impl Sub for Dd {
    type Output = Dd;
    fn sub(self, y: Dd) -> Dd {
        self + (-y)
    }
}

impl Mul for Dd {
    type Output = Dd;
    fn mul(self, y: Dd) -> Dd {
        let p = self.hi * y.hi;
        let e = self.hi.mul_add(y.hi, -p) + (self.hi * y.lo + self.lo * y.hi);
        Dd::new(quick_two_sum(p, e))
    }
}

impl Div for Dd {
    type Output = Dd;
    fn div(self, y: Dd) -> Dd {
        let q1 = self.hi / y.hi;
        let r = self - y * Dd::from(q1);
        let q2 = r.hi / y.hi;
        let r = r - y * Dd::from(q2);
        let q3 = r.hi / y.hi;
        Dd::new(quick_two_sum(q1, q2)) + Dd::from(q3)
    }
}

impl Real for Dd {
    fn zero() -> Self {
        Dd::from(0.0)
    }
    fn one() -> Self {
        Dd::from(1.0)
    }
    fn abs(self) -> Self {
        if self.hi < 0.0 {
            -self
        } else {
            self
        }
    }
    fn sqrt(self) -> Self {
        if self.hi <= 0.0 {
            return Dd::from(0.0);
        }
        let y = Dd::from(self.hi.sqrt());
        y + (self - y * y) / (y + y)
    }
    fn powf(self, e: Self) -> Self {
        (e * self.ln()).exp()
    }
    fn from_f64_lossy(x: f64) -> Self {
        Dd::from(x)
    }
    fn to_f64_lossy(self) -> f64 {
        f64::from(self)
    }
    const UNIT_ROUNDOFF: f64 = 1.1e-32;
    const NAME: &'static str = "double-double";
}

#[test]
fn double_double_is_accurate() {
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};
    let mut rng = StdRng::seed_from_u64(5);
    for _ in 0..1000 {
        let a = Dd::from(rng.random_range(1e-9..1.0)) + Dd::from(rng.random_range(0.0..1e-25));
        let b = Dd::from(rng.random_range(1e-3..1.0));
        let rel = |x: Dd, y: Dd| f64::from(((x - y) / y).abs());
        assert!(rel(a / b * b, a) < 1e-30);
        assert!(rel(a.sqrt() * a.sqrt(), a) < 1e-30);
        let m = Dd::from(rng.random_range(0.5..2.0));
        // (a^m)^(1/m) = a
        assert!(rel(a.powf(m).powf(Dd::from(1.0) / m), a) < 1e-28);
        assert!(rel(a.powf(Dd::from(1.5)) * a.powf(Dd::from(1.5)), a * a * a) < 1e-29);
    }
}
