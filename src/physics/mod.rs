//! The physics, written once in plain Rust and generic over the float type.
//!
//! The CPU twins in `src/kernels/` call these functions; the WGSL kernels in `shaders/`
//! write the same formulas.

pub mod beam;
pub mod contact;
pub mod count;
pub mod dual;
pub mod mass;
pub mod rotation;
pub mod vec3;

/// Float type the physics is generic over: `f32` (what a GPU f32 run computes) or `f64`
/// (the oracle).
pub trait Real:
    Copy
    + Default
    + Send
    + Sync
    + std::fmt::Debug
    + PartialOrd
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + std::ops::Neg<Output = Self>
    + 'static
{
    /// 0.
    fn zero() -> Self;
    /// 1.
    fn one() -> Self;
    /// |x|.
    fn abs(self) -> Self;
    /// √x.
    fn sqrt(self) -> Self;
    /// x^e for x > 0.
    fn powf(self, e: Self) -> Self;
    /// Rounds an `f64` to this type.
    fn from_f64_lossy(x: f64) -> Self;
    /// Widens (or keeps) this value as `f64`.
    fn to_f64_lossy(self) -> f64;
    /// Unit roundoff of this type (half the machine epsilon).
    const UNIT_ROUNDOFF: f64;
    /// Name used in reports: `"f32"` or `"f64"`.
    const NAME: &'static str;
}

impl Real for f32 {
    fn zero() -> Self {
        0.0
    }
    fn one() -> Self {
        1.0
    }
    fn abs(self) -> Self {
        f32::abs(self)
    }
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    fn powf(self, e: Self) -> Self {
        f32::powf(self, e)
    }
    fn from_f64_lossy(x: f64) -> Self {
        x as f32
    }
    fn to_f64_lossy(self) -> f64 {
        self as f64
    }
    const UNIT_ROUNDOFF: f64 = f32::EPSILON as f64 / 2.0;
    const NAME: &'static str = "f32";
}

impl Real for f64 {
    fn zero() -> Self {
        0.0
    }
    fn one() -> Self {
        1.0
    }
    fn abs(self) -> Self {
        f64::abs(self)
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn powf(self, e: Self) -> Self {
        f64::powf(self, e)
    }
    fn from_f64_lossy(x: f64) -> Self {
        x
    }
    fn to_f64_lossy(self) -> f64 {
        self
    }
    const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;
    const NAME: &'static str = "f64";
}

#[cfg(test)]
mod contact_tests;
#[cfg(test)]
mod double_double;
