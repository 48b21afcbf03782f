//! The physics, written once in plain Rust and generic over the float type.
//!
//! The CPU twins in `src/kernels/` call these functions; the WGSL kernels in `shaders/`
//! write the same formulas.

pub mod contact;
pub mod vec3;

/// Float type the physics is generic over: `f32` (what a GPU f32 run computes) or `f64`
/// (the oracle).
pub trait Real: num_traits::Float + Default + Send + Sync + std::fmt::Debug + 'static {
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
    fn from_f64_lossy(x: f64) -> Self {
        x
    }
    fn to_f64_lossy(self) -> f64 {
        self
    }
    const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;
    const NAME: &'static str = "f64";
}
