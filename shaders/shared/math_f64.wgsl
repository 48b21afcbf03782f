// f64 ln / exp / pow from +, −, ×, ÷ and sqrt only.
// Twin: f64::ln / f64::exp / f64::powf (tests/gpu_contact.rs checks pow over the range).
// Vulkan's GLSL.std.450 pow/exp/log are defined for 16/32-bit floats only: on f64 they
// compile and return garbage (platform notes), so they are written out here.

// 2^e, exact for −1074 ≤ e ≤ 1023 (binary powering of exact powers of two).
fn pow2_f64(e: i32) -> f64 {
    var base = 2.0lf;
    var k = e;
    if (k < 0) {
        base = 0.5lf;
        k = -k;
    }
    var result = 1.0lf;
    // |e| < 2^31: at most 31 rounds (every loop in a kernel is counted: src/gpu/loops.rs).
    for (var round = 0u; round < 32u; round++) {
        if (k == 0) {
            break;
        }
        if ((k & 1) == 1) {
            result = result * base;
        }
        base = base * base;
        k = k >> 1u;
    }
    return result;
}

// ln(2) split so that e·LN2_HI is exact for |e| < 2^20 (fdlibm's constants).
const LN2_HI: f64 = 6.93147180369123816490e-01lf;
const LN2_LO: f64 = 1.90821492927058770002e-10lf;

// ln(x) for finite x > 0: x = 2^e·y, y ∈ [√½, √2), ln y = 2·atanh(z), z = (y−1)/(y+1),
// |z| ≤ 0.1716, series to z^23 (truncation < 1e-18).
fn ln_f64(x_in: f64) -> f64 {
    var x = x_in;
    var e: i32 = 0;
    let up = pow2_f64(100);
    let down = pow2_f64(-100);
    // A positive finite x needs at most 10 rounds of 2^±100 (4.9e-324 → 1e-30, 1.8e308 →
    // 1e30), then at most 2 halvings or doublings; the bounds end the loops on 0, ∞ or NaN.
    for (var round = 0u; round < 16u; round++) {
        if (x >= 1.0e-30lf) {
            break;
        }
        x = x * up;
        e = e - 100;
    }
    for (var round = 0u; round < 16u; round++) {
        if (x <= 1.0e30lf) {
            break;
        }
        x = x * down;
        e = e + 100;
    }
    // f32 estimate of the exponent, then exact scaling and correction.
    let est = i32(floor(log2(f32(x))));
    x = x * pow2_f64(-est);
    e = e + est;
    for (var round = 0u; round < 8u; round++) {
        if (x < 1.4142135623730951lf) {
            break;
        }
        x = x * 0.5lf;
        e = e + 1;
    }
    for (var round = 0u; round < 8u; round++) {
        if (x >= 0.7071067811865476lf) {
            break;
        }
        x = x * 2.0lf;
        e = e - 1;
    }
    let z = (x - 1.0lf) / (x + 1.0lf);
    let z2 = z * z;
    var s = 1.0lf / 23.0lf;
    s = s * z2 + 1.0lf / 21.0lf;
    s = s * z2 + 1.0lf / 19.0lf;
    s = s * z2 + 1.0lf / 17.0lf;
    s = s * z2 + 1.0lf / 15.0lf;
    s = s * z2 + 1.0lf / 13.0lf;
    s = s * z2 + 1.0lf / 11.0lf;
    s = s * z2 + 1.0lf / 9.0lf;
    s = s * z2 + 1.0lf / 7.0lf;
    s = s * z2 + 1.0lf / 5.0lf;
    s = s * z2 + 1.0lf / 3.0lf;
    s = s * z2 + 1.0lf;
    let ln_y = 2.0lf * z * s;
    let ef = f64(e);
    return ef * LN2_HI + (ef * LN2_LO + ln_y);
}

// exp(a): a = k·ln2 + r, |r| ≤ ln2/2, Taylor to r^16 (truncation < 1e-19), times 2^k.
fn exp_f64(a: f64) -> f64 {
    if (a > 709.78lf) {
        return 1.0lf / 0.0lf;
    }
    if (a < -745.2lf) {
        return 0.0lf;
    }
    let q = a * 1.4426950408889634lf;
    var k: i32;
    if (q >= 0.0lf) {
        k = i32(q + 0.5lf);
    } else {
        k = i32(q - 0.5lf);
    }
    let kf = f64(k);
    let r = (a - kf * LN2_HI) - kf * LN2_LO;
    var p = 1.0lf / 20922789888000.0lf;
    p = p * r + 1.0lf / 1307674368000.0lf;
    p = p * r + 1.0lf / 87178291200.0lf;
    p = p * r + 1.0lf / 6227020800.0lf;
    p = p * r + 1.0lf / 479001600.0lf;
    p = p * r + 1.0lf / 39916800.0lf;
    p = p * r + 1.0lf / 3628800.0lf;
    p = p * r + 1.0lf / 362880.0lf;
    p = p * r + 1.0lf / 40320.0lf;
    p = p * r + 1.0lf / 5040.0lf;
    p = p * r + 1.0lf / 720.0lf;
    p = p * r + 1.0lf / 120.0lf;
    p = p * r + 1.0lf / 24.0lf;
    p = p * r + 1.0lf / 6.0lf;
    p = p * r + 0.5lf;
    p = p * r + 1.0lf;
    p = p * r + 1.0lf;
    // Split 2^k so neither factor over- or underflows on its own.
    let k1 = k / 2;
    return p * pow2_f64(k1) * pow2_f64(k - k1);
}

// x^m for x > 0.
fn pow_pos(x: f64, m: f64) -> f64 {
    return exp_f64(m * ln_f64(x));
}
