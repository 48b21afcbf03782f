//! Rotation algebra of the co-rotational beam: 3×3 matrices, the trigonometry a float type
//! (or a dual number) must offer, and the rotation vector's log and exp (Rodrigues).

use super::Real;

/// 3×3 matrix, row-major.
pub type Mat3<T> = [[T; 3]; 3];

/// Operations the element needs beyond [`Real`].
pub trait Trig: Real {
    /// sin.
    fn sin(self) -> Self;
    /// cos.
    fn cos(self) -> Self;
    /// atan2(self, x).
    fn atan2(self, x: Self) -> Self;
}

impl Trig for f64 {
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
    fn atan2(self, x: Self) -> Self {
        f64::atan2(self, x)
    }
}

impl Trig for f32 {
    fn sin(self) -> Self {
        f32::sin(self)
    }
    fn cos(self) -> Self {
        f32::cos(self)
    }
    fn atan2(self, x: Self) -> Self {
        f32::atan2(self, x)
    }
}

/// `[f(0), f(1), f(2)]`: `std::array::from_fn` for three, written out and inlined (a
/// static solve spent 5–8 % of its samples in `from_fn`'s machinery over `DualN`'s 80-byte
/// values). The same operations in the same order.
#[inline(always)]
pub(crate) fn by3<T>(f: impl Fn(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

/// `a b`.
#[inline(always)]
pub fn mat_mul<T: Real>(a: &Mat3<T>, b: &Mat3<T>) -> Mat3<T> {
    by3(|r| by3(|c| a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c]))
}

/// `aᵀ b`.
#[inline(always)]
pub fn mat_tmul<T: Real>(a: &Mat3<T>, b: &Mat3<T>) -> Mat3<T> {
    by3(|r| by3(|c| a[0][r] * b[0][c] + a[1][r] * b[1][c] + a[2][r] * b[2][c]))
}

/// `a × b`.
#[inline(always)]
pub fn cross<T: Real>(a: &[T; 3], b: &[T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `|a|`.
#[inline(always)]
pub fn norm<T: Real>(a: &[T; 3]) -> T {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The rotation vector of a rotation matrix (`log`, |θ| < π), smooth through θ = 0.
pub fn rotation_log<T: Trig>(r: &Mat3<T>) -> [T; 3] {
    rotation_log_and_jacobian(r).0
}

/// [`rotation_log`] and the coefficient `c(θ) = (1 − (θ/2)·cot(θ/2))/θ²` of the inverse of
/// the rotation's left Jacobian, `J⁻¹(θ) = I − ½[θ]× + c(θ)[θ]×²` (`exp(θ + δθ) =
/// exp([J(θ)δθ]×)·exp(θ)`): the rotation log's response to a spin. `c` comes from the sine
/// and cosine the log has at hand (`cot(θ/2) = (1 + cos θ)/sin θ`) and, for θ² < 0.1, from
/// its series `Σ |B₂ₙ| θ²ⁿ⁻²/(2n)!` to θ⁸ (the next term is < 1e-14 of it), so it is smooth
/// through θ = 0 and keeps its digits in f32.
#[inline(always)]
pub fn rotation_log_and_jacobian<T: Trig>(r: &Mat3<T>) -> ([T; 3], T) {
    let half = T::from_f64_lossy(0.5);
    let w = [
        half * (r[2][1] - r[1][2]),
        half * (r[0][2] - r[2][0]),
        half * (r[1][0] - r[0][1]),
    ];
    let s2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    let c = half * (r[0][0] + r[1][1] + r[2][2] - T::one());
    // θ/sin θ; near θ = 0 by its series in s² = sin²θ (asin(s)/s), avoiding √0.
    let (factor, s) = if s2.to_f64_lossy() < 1e-6 && c.to_f64_lossy() > 0.0 {
        let f = T::one() + s2 * (T::from_f64_lossy(1.0 / 6.0) + s2 * T::from_f64_lossy(3.0 / 40.0));
        (f, None)
    } else {
        let s = s2.sqrt();
        (s.atan2(c) / s, Some(s))
    };
    let theta2 = factor * factor * s2;
    let coefficient = match s {
        Some(s) if theta2.to_f64_lossy() >= 0.1 => {
            let theta = factor * s;
            (T::one() - theta * (T::one() + c) / (s + s)) / theta2
        }
        _ => {
            let k = |x: f64| T::from_f64_lossy(x);
            k(1.0 / 12.0)
                + theta2
                    * (k(1.0 / 720.0)
                        + theta2
                            * (k(1.0 / 30240.0)
                                + theta2 * (k(1.0 / 1209600.0) + theta2 * k(1.0 / 47900160.0))))
        }
    };
    ([factor * w[0], factor * w[1], factor * w[2]], coefficient)
}

/// `exp([θ]×)` (Rodrigues), f64.
pub fn rotation_exp(theta: &[f64; 3]) -> Mat3<f64> {
    let a = norm(theta);
    let k: Mat3<f64> = [
        [0.0, -theta[2], theta[1]],
        [theta[2], 0.0, -theta[0]],
        [-theta[1], theta[0], 0.0],
    ];
    let (s, c) = if a < 1e-8 {
        (1.0 - a * a / 6.0, 0.5 - a * a / 24.0)
    } else {
        (a.sin() / a, (1.0 - a.cos()) / (a * a))
    };
    let kk = mat_mul(&k, &k);
    std::array::from_fn(|r| {
        std::array::from_fn(|col| f64::from(r == col) + s * k[r][col] + c * kk[r][col])
    })
}
