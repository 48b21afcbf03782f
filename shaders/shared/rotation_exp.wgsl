// The series exponential map of src/kernels/update.rs (rotation_exp_series): included by
// update.wgsl and dynamics.wgsl (no double-precision trigonometry on Vulkan).
const SERIES_TERMS: u32 = 12u;
const PI: f32 = 3.14159265358979;

// 1/(2k+1)! and 1/(2k)! for k = 0 … 11.
fn inv_odd_factorial(k: u32) -> real {
    var f = real(1.0);
    for (var j = 2u; j <= 2u * k + 1u; j = j + 1u) {
        f = f * real(j);
    }
    return real(1.0) / f;
}

fn inv_even_factorial(k: u32) -> real {
    var f = real(1.0);
    for (var j = 2u; j <= 2u * k; j = j + 1u) {
        f = f * real(j);
    }
    return real(1.0) / f;
}

// (sinc h, cos h) for 0 ≤ h ≤ π/2.
fn sinc_cos(h: real) -> vec2<real> {
    let h2 = h * h;
    var s = real(0.0);
    var c = real(0.0);
    for (var step = 0u; step < SERIES_TERMS; step = step + 1u) {
        let k = SERIES_TERMS - 1u - step;
        var sign = real(1.0);
        if (k % 2u == 1u) {
            sign = real(-1.0);
        }
        s = s * h2 + sign * inv_odd_factorial(k);
        c = c * h2 + sign * inv_even_factorial(k);
    }
    return vec2<real>(s, c);
}

fn rotation_exp(theta_in: vec3<real>) -> mat3x3<real> {
    var t = theta_in;
    let phi0 = sqrt(dot(t, t));
    if (f32(phi0) > PI) {
        // φ − 2π·round(φ/2π), along the same axis.
        let turns = real(round(f32(phi0) / (2.0 * PI)));
#if F64
        t = t * ((phi0 - turns * real(6.283185307179586)) / phi0);
#else
        t = t * ((phi0 - turns * real(6.2831855)) / phi0);
#endif
    }
    let phi = sqrt(dot(t, t));
    let sc = sinc_cos(phi * real(0.5));
    let a = sc.x * sc.y;
    let b = real(0.5) * sc.x * sc.x;
    // Columns of [t]×.
    let k = mat3x3<real>(
        vec3<real>(real(0.0), t.z, -t.y),
        vec3<real>(-t.z, real(0.0), t.x),
        vec3<real>(t.y, -t.x, real(0.0)),
    );
    let eye = mat3x3<real>(
        vec3<real>(real(1.0), real(0.0), real(0.0)),
        vec3<real>(real(0.0), real(1.0), real(0.0)),
        vec3<real>(real(0.0), real(0.0), real(1.0)),
    );
    return eye + k * a + (k * k) * b;
}
