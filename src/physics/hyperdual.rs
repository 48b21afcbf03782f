//! Hyper-dual numbers `a + b ε₁ + c ε₂ + d ε₁ε₂` (ε₁² = ε₂² = 0): one evaluation of a
//! function gives its value, two first derivatives and the mixed second derivative
//! exactly (to rounding). The beam element uses them to get its internal force and its
//! consistent tangent from its strain energy (`src/physics/beam.rs`).

use std::ops::{Add, Div, Mul, Neg, Sub};

use super::Real;

/// A hyper-dual number.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HyperDual {
    /// Value.
    pub re: f64,
    /// ε₁ part (first derivative along direction 1).
    pub e1: f64,
    /// ε₂ part (first derivative along direction 2).
    pub e2: f64,
    /// ε₁ε₂ part (mixed second derivative).
    pub e12: f64,
}

impl HyperDual {
    /// A constant.
    pub const fn constant(re: f64) -> HyperDual {
        HyperDual {
            re,
            e1: 0.0,
            e2: 0.0,
            e12: 0.0,
        }
    }

    /// Applies a scalar function with value `f`, derivative `df`, second derivative `ddf`.
    fn chain(self, f: f64, df: f64, ddf: f64) -> HyperDual {
        HyperDual {
            re: f,
            e1: df * self.e1,
            e2: df * self.e2,
            e12: df * self.e12 + ddf * self.e1 * self.e2,
        }
    }

    /// sin.
    pub fn sin(self) -> HyperDual {
        let (s, c) = self.re.sin_cos();
        self.chain(s, c, -s)
    }

    /// cos.
    pub fn cos(self) -> HyperDual {
        let (s, c) = self.re.sin_cos();
        self.chain(c, -s, -c)
    }

    /// atan2(self, x).
    pub fn atan2(self, x: HyperDual) -> HyperDual {
        let y = self;
        let r2 = x.re * x.re + y.re * y.re;
        let r4 = r2 * r2;
        let (tx, ty) = (-y.re / r2, x.re / r2);
        let txx = 2.0 * x.re * y.re / r4;
        let tyy = -txx;
        let txy = (y.re * y.re - x.re * x.re) / r4;
        HyperDual {
            re: y.re.atan2(x.re),
            e1: tx * x.e1 + ty * y.e1,
            e2: tx * x.e2 + ty * y.e2,
            e12: tx * x.e12
                + ty * y.e12
                + txx * x.e1 * x.e2
                + txy * (x.e1 * y.e2 + y.e1 * x.e2)
                + tyy * y.e1 * y.e2,
        }
    }
}

impl Add for HyperDual {
    type Output = HyperDual;
    fn add(self, o: HyperDual) -> HyperDual {
        HyperDual {
            re: self.re + o.re,
            e1: self.e1 + o.e1,
            e2: self.e2 + o.e2,
            e12: self.e12 + o.e12,
        }
    }
}

impl Sub for HyperDual {
    type Output = HyperDual;
    fn sub(self, o: HyperDual) -> HyperDual {
        HyperDual {
            re: self.re - o.re,
            e1: self.e1 - o.e1,
            e2: self.e2 - o.e2,
            e12: self.e12 - o.e12,
        }
    }
}

impl Neg for HyperDual {
    type Output = HyperDual;
    fn neg(self) -> HyperDual {
        HyperDual {
            re: -self.re,
            e1: -self.e1,
            e2: -self.e2,
            e12: -self.e12,
        }
    }
}

impl Mul for HyperDual {
    type Output = HyperDual;
    fn mul(self, o: HyperDual) -> HyperDual {
        HyperDual {
            re: self.re * o.re,
            e1: self.re * o.e1 + self.e1 * o.re,
            e2: self.re * o.e2 + self.e2 * o.re,
            e12: self.re * o.e12 + self.e1 * o.e2 + self.e2 * o.e1 + self.e12 * o.re,
        }
    }
}

impl Div for HyperDual {
    type Output = HyperDual;
    fn div(self, o: HyperDual) -> HyperDual {
        let inv = o.re.recip();
        self * o.chain(inv, -inv * inv, 2.0 * inv * inv * inv)
    }
}

impl PartialOrd for HyperDual {
    fn partial_cmp(&self, o: &HyperDual) -> Option<std::cmp::Ordering> {
        self.re.partial_cmp(&o.re)
    }
}

impl Real for HyperDual {
    fn zero() -> Self {
        HyperDual::constant(0.0)
    }
    fn one() -> Self {
        HyperDual::constant(1.0)
    }
    fn abs(self) -> Self {
        if self.re < 0.0 {
            -self
        } else {
            self
        }
    }
    fn sqrt(self) -> Self {
        let s = self.re.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * self.re))
    }
    fn powf(self, e: Self) -> Self {
        // Exponent constant (the element never differentiates one).
        let m = e.re;
        let p = self.re.powf(m);
        self.chain(p, m * p / self.re, m * (m - 1.0) * p / (self.re * self.re))
    }
    fn from_f64_lossy(x: f64) -> Self {
        HyperDual::constant(x)
    }
    fn to_f64_lossy(self) -> f64 {
        self.re
    }
    const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;
    const NAME: &'static str = "hyper-dual";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_are_exact() {
        // f(x, y) = sin(x y) / sqrt(x) + atan2(y, x): check ∂f/∂x, ∂f/∂y, ∂²f/∂x∂y.
        let f = |x: HyperDual, y: HyperDual| (x * y).sin() / x.sqrt() + y.atan2(x);
        let (x0, y0) = (0.7, -1.3);
        let x = HyperDual {
            re: x0,
            e1: 1.0,
            e2: 0.0,
            e12: 0.0,
        };
        let y = HyperDual {
            re: y0,
            e1: 0.0,
            e2: 1.0,
            e12: 0.0,
        };
        let v = f(x, y);
        let fx = |x: f64, y: f64| (x * y).sin() / x.sqrt() + y.atan2(x);
        let h = 1e-5;
        let dx = (fx(x0 + h, y0) - fx(x0 - h, y0)) / (2.0 * h);
        let dy = (fx(x0, y0 + h) - fx(x0, y0 - h)) / (2.0 * h);
        let dxy = (fx(x0 + h, y0 + h) - fx(x0 + h, y0 - h) - fx(x0 - h, y0 + h)
            + fx(x0 - h, y0 - h))
            / (4.0 * h * h);
        assert!((v.re - fx(x0, y0)).abs() < 1e-15);
        assert!((v.e1 - dx).abs() < 1e-9, "{} {}", v.e1, dx);
        assert!((v.e2 - dy).abs() < 1e-9);
        assert!((v.e12 - dxy).abs() < 1e-5, "{} {}", v.e12, dxy);
        // Same direction twice: second derivative.
        let xx = HyperDual {
            re: x0,
            e1: 1.0,
            e2: 1.0,
            e12: 0.0,
        };
        let g = (xx * xx * xx).cos();
        let exact = -(9.0 * x0.powi(4)) * (x0.powi(3)).cos() - 6.0 * x0 * (x0.powi(3)).sin();
        assert!((g.e12 - exact).abs() < 1e-12);
    }
}
