//! Dual numbers `a + b ε` (ε² = 0) over `f32` or `f64`: one evaluation of a function gives
//! its value and its derivative along one direction exactly (to rounding). The beam element
//! forms its consistent tangent by evaluating its closed-form internal force in dual numbers,
//! one direction per column (`src/physics/beam.rs`); `shaders/beam.wgsl` does the same on
//! `vec2<real>`.

// The product and quotient rules put `+` and `−` inside `Mul` and `Div`: that is the point.
#![allow(clippy::suspicious_arithmetic_impl)]

use std::ops::{Add, Div, Mul, Neg, Sub};

use super::rotation::Trig;
use super::Real;

/// A dual number over `T`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dual<T> {
    /// Value.
    pub re: T,
    /// Derivative along the seeded direction.
    pub d: T,
}

impl<T: Real> Dual<T> {
    /// A constant.
    pub fn constant(re: T) -> Self {
        Dual { re, d: T::zero() }
    }

    /// `re` seeded with derivative `d`.
    pub fn new(re: T, d: T) -> Self {
        Dual { re, d }
    }

    /// g(self) with value `g` and derivative `g1` at `self.re`.
    fn chain(self, g: T, g1: T) -> Self {
        Dual {
            re: g,
            d: g1 * self.d,
        }
    }
}

impl<T: Real> Add for Dual<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Dual {
            re: self.re + o.re,
            d: self.d + o.d,
        }
    }
}

impl<T: Real> Sub for Dual<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Dual {
            re: self.re - o.re,
            d: self.d - o.d,
        }
    }
}

impl<T: Real> Neg for Dual<T> {
    type Output = Self;
    fn neg(self) -> Self {
        Dual {
            re: -self.re,
            d: -self.d,
        }
    }
}

impl<T: Real> Mul for Dual<T> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Dual {
            re: self.re * o.re,
            d: self.re * o.d + self.d * o.re,
        }
    }
}

impl<T: Real> Div for Dual<T> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let q = self.re / o.re;
        Dual {
            re: q,
            d: (self.d - q * o.d) / o.re,
        }
    }
}

impl<T: Real> PartialOrd for Dual<T> {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        self.re.partial_cmp(&o.re)
    }
}

impl<T: Real> Real for Dual<T> {
    fn zero() -> Self {
        Dual::constant(T::zero())
    }
    fn one() -> Self {
        Dual::constant(T::one())
    }
    fn abs(self) -> Self {
        if self.re < T::zero() {
            -self
        } else {
            self
        }
    }
    fn sqrt(self) -> Self {
        let s = self.re.sqrt();
        self.chain(s, T::from_f64_lossy(0.5) / s)
    }
    fn powf(self, e: Self) -> Self {
        // Constant exponent (the element never differentiates one).
        let p = self.re.powf(e.re);
        self.chain(p, e.re * p / self.re)
    }
    fn from_f64_lossy(x: f64) -> Self {
        Dual::constant(T::from_f64_lossy(x))
    }
    fn to_f64_lossy(self) -> f64 {
        self.re.to_f64_lossy()
    }
    const UNIT_ROUNDOFF: f64 = T::UNIT_ROUNDOFF;
    const NAME: &'static str = "dual";
}

impl<T: Trig> Trig for Dual<T> {
    fn sin(self) -> Self {
        self.chain(self.re.sin(), self.re.cos())
    }
    fn cos(self) -> Self {
        self.chain(self.re.cos(), -self.re.sin())
    }
    fn atan2(self, x: Self) -> Self {
        let y = self;
        let r2 = x.re * x.re + y.re * y.re;
        Dual {
            re: y.re.atan2(x.re),
            d: (x.re * y.d - y.re * x.d) / r2,
        }
    }
}

/// A dual number with `N` derivative directions at once, `a + Σ b_k ε_k` (ε_j ε_k = 0): one
/// evaluation gives the value and the derivative along `N` directions, the value part and
/// every transcendental computed once (the CPU form of the element tangent: 9 directions
/// in one pass; the GPU kernel runs the same 9 one by one on [`Dual`] to keep its
/// registers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualN<T, const N: usize> {
    /// Value.
    pub re: T,
    /// Derivatives along the `N` seeded directions.
    pub d: [T; N],
}

impl<T: Real, const N: usize> Default for DualN<T, N> {
    fn default() -> Self {
        Self::constant(T::zero())
    }
}

impl<T: Real, const N: usize> DualN<T, N> {
    /// A constant.
    #[inline(always)]
    pub fn constant(re: T) -> Self {
        DualN {
            re,
            d: [T::zero(); N],
        }
    }

    /// g(self) with value `g` and derivative `g1` at `self.re`.
    #[inline(always)]
    fn chain(mut self, g: T, g1: T) -> Self {
        self.re = g;
        for x in self.d.iter_mut() {
            *x = g1 * *x;
        }
        self
    }
}

// The operations update the left operand's derivative array in place (loops, not
// `array::from_fn`): the same arithmetic in the same order, without the temporaries that
// cost the element tangent a third of its time in copies.

impl<T: Real, const N: usize> Add for DualN<T, N> {
    type Output = Self;
    #[inline(always)]
    fn add(mut self, o: Self) -> Self {
        self.re = self.re + o.re;
        for (a, b) in self.d.iter_mut().zip(&o.d) {
            *a = *a + *b;
        }
        self
    }
}

impl<T: Real, const N: usize> Sub for DualN<T, N> {
    type Output = Self;
    #[inline(always)]
    fn sub(mut self, o: Self) -> Self {
        self.re = self.re - o.re;
        for (a, b) in self.d.iter_mut().zip(&o.d) {
            *a = *a - *b;
        }
        self
    }
}

impl<T: Real, const N: usize> Neg for DualN<T, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(mut self) -> Self {
        self.re = -self.re;
        for a in self.d.iter_mut() {
            *a = -*a;
        }
        self
    }
}

impl<T: Real, const N: usize> Mul for DualN<T, N> {
    type Output = Self;
    #[inline(always)]
    fn mul(mut self, o: Self) -> Self {
        let (a, b) = (self.re, o.re);
        self.re = a * b;
        for (x, y) in self.d.iter_mut().zip(&o.d) {
            *x = a * *y + *x * b;
        }
        self
    }
}

impl<T: Real, const N: usize> Div for DualN<T, N> {
    type Output = Self;
    #[inline(always)]
    fn div(mut self, o: Self) -> Self {
        let q = self.re / o.re;
        self.re = q;
        for (x, y) in self.d.iter_mut().zip(&o.d) {
            *x = (*x - q * *y) / o.re;
        }
        self
    }
}

impl<T: Real, const N: usize> PartialOrd for DualN<T, N> {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        self.re.partial_cmp(&o.re)
    }
}

impl<T: Real, const N: usize> Real for DualN<T, N> {
    #[inline(always)]
    fn zero() -> Self {
        Self::constant(T::zero())
    }
    #[inline(always)]
    fn one() -> Self {
        Self::constant(T::one())
    }
    #[inline(always)]
    fn abs(self) -> Self {
        if self.re < T::zero() {
            -self
        } else {
            self
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let s = self.re.sqrt();
        self.chain(s, T::from_f64_lossy(0.5) / s)
    }
    #[inline(always)]
    fn powf(self, e: Self) -> Self {
        let p = self.re.powf(e.re);
        self.chain(p, e.re * p / self.re)
    }
    #[inline(always)]
    fn from_f64_lossy(x: f64) -> Self {
        Self::constant(T::from_f64_lossy(x))
    }
    #[inline(always)]
    fn to_f64_lossy(self) -> f64 {
        self.re.to_f64_lossy()
    }
    const UNIT_ROUNDOFF: f64 = T::UNIT_ROUNDOFF;
    const NAME: &'static str = "dual-n";
}

impl<T: Trig, const N: usize> Trig for DualN<T, N> {
    #[inline(always)]
    fn sin(self) -> Self {
        self.chain(self.re.sin(), self.re.cos())
    }
    #[inline(always)]
    fn cos(self) -> Self {
        self.chain(self.re.cos(), -self.re.sin())
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        let y = self;
        let r2 = x.re * x.re + y.re * y.re;
        DualN {
            re: y.re.atan2(x.re),
            d: std::array::from_fn(|k| (x.re * y.d[k] - y.re * x.d[k]) / r2),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_central_differences() {
        // f(x) = sin(x²)/√x + atan2(x, 1 − x) + cos(x)·x^1.5 at x0 in f64 and f32.
        fn f<T: Trig>(x: T) -> T {
            let one = T::one();
            (x * x).sin() / x.sqrt() + x.atan2(one - x) + x.cos() * x.powf(T::from_f64_lossy(1.5))
        }
        let x0 = 0.7;
        let v = f(Dual::new(x0, 1.0));
        let h = 1e-5;
        let fd = (f(x0 + h) - f(x0 - h)) / (2.0 * h);
        assert_eq!(v.re, f(x0));
        assert!((v.d - fd).abs() < 1e-9, "{} vs {fd}", v.d);
        let v32 = f(Dual::new(x0 as f32, 1.0f32));
        assert!((v32.d as f64 - v.d).abs() < 1e-5 * v.d.abs());
    }
}
