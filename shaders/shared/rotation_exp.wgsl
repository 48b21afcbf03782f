// The series exponential map of src/kernels/update.rs (rotation_exp_series): included by
// update.wgsl and dynamics.wgsl (no double-precision trigonometry on Vulkan).
const PI: f32 = 3.14159265358979;

// (sinc h, cos h) for 0 ≤ h ≤ π/2: Horner in h² over k = 11 … 0 with the coefficients
// (−1)^k/(2k+1)! and (−1)^k/(2k)! written out, those of src/kernels/update.rs
// (SERIES_COEFFICIENTS; its tests read every literal here back and compare it bit for bit),
// so no factorial is formed at run time.
fn sinc_cos(h: real) -> vec2<real> {
    let h2 = h * h;
    var s = real(-3.8681701706306835e-23); // sinc 11
    var c = real(-8.896791392450574e-22); // cos 11
    s = s * h2 + real(1.9572941063391263e-20); // sinc 10
    c = c * h2 + real(4.110317623312165e-19); // cos 10
    s = s * h2 + real(-8.22063524662433e-18); // sinc 9
    c = c * h2 + real(-1.5619206968586225e-16); // cos 9
    s = s * h2 + real(2.8114572543455206e-15); // sinc 8
    c = c * h2 + real(4.779477332387385e-14); // cos 8
    s = s * h2 + real(-7.647163731819816e-13); // sinc 7
    c = c * h2 + real(-1.1470745597729725e-11); // cos 7
    s = s * h2 + real(1.6059043836821613e-10); // sinc 6
    c = c * h2 + real(2.08767569878681e-09); // cos 6
    s = s * h2 + real(-2.505210838544172e-08); // sinc 5
    c = c * h2 + real(-2.755731922398589e-07); // cos 5
    s = s * h2 + real(2.7557319223985893e-06); // sinc 4
    c = c * h2 + real(2.48015873015873e-05); // cos 4
    s = s * h2 + real(-0.0001984126984126984); // sinc 3
    c = c * h2 + real(-0.001388888888888889); // cos 3
    s = s * h2 + real(0.008333333333333333); // sinc 2
    c = c * h2 + real(0.041666666666666664); // cos 2
    s = s * h2 + real(-0.16666666666666666); // sinc 1
    c = c * h2 + real(-0.5); // cos 1
    s = s * h2 + real(1.0); // sinc 0
    c = c * h2 + real(1.0); // cos 0
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
