// Twin: src/kernels/update.rs (Newton update of every variant's configuration, norms).
//
// `update`: one invocation per (node, variant), index = node · V + variant:
// x += α B Δu, R ← exp([α Δθ]×) R with the series exponential of the twin.
// `norms`: one invocation per variant: largest |r| and largest |α Δ|, Δ · r and r · r.
#include "shared/layout.wgsl"

// Composed twice: without NORMS the entry point `main` is the update, with NORMS the norms.
@group(0) @binding(0) var<uniform> dims: ChainDims;
@group(0) @binding(1) var<storage, read> delta: array<real>;
@group(0) @binding(2) var<storage, read> alpha: array<real>;
#if NORMS
@group(0) @binding(3) var<storage, read> residual: array<real>;
// Per variant: largest |r|, largest |α Δ|, Δ · r, r · r.
@group(0) @binding(4) var<storage, read_write> norm_out: array<real>;
#else
@group(0) @binding(3) var<storage, read> basis: array<real>;
@group(0) @binding(4) var<storage, read_write> x: array<real>;
@group(0) @binding(5) var<storage, read_write> rot: array<real>;
#endif

#if !NORMS
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

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let n = dims.num_nodes;
    if (gid.x >= n * nv) {
        return;
    }
    let i = gid.x / nv;
    let v = gid.x % nv;
    let al = alpha[v];
    let du = vec3<real>(
        al * delta[(6u * i) * nv + v],
        al * delta[(6u * i + 1u) * nv + v],
        al * delta[(6u * i + 2u) * nv + v],
    );
    for (var r = 0u; r < 3u; r = r + 1u) {
        let brow = vec3<real>(basis[9u * i + 3u * r], basis[9u * i + 3u * r + 1u], basis[9u * i + 3u * r + 2u]);
        x[(3u * i + r) * nv + v] = x[(3u * i + r) * nv + v] + dot(brow, du);
    }
    let e = rotation_exp(vec3<real>(
        al * delta[(6u * i + 3u) * nv + v],
        al * delta[(6u * i + 4u) * nv + v],
        al * delta[(6u * i + 5u) * nv + v],
    ));
    var old: array<real, 9>;
    for (var k = 0u; k < 9u; k = k + 1u) {
        old[k] = rot[(9u * i + k) * nv + v];
    }
    for (var r = 0u; r < 3u; r = r + 1u) {
        for (var c = 0u; c < 3u; c = c + 1u) {
            var s = real(0.0);
            for (var m = 0u; m < 3u; m = m + 1u) {
                // e[m][r] is row r, column m of the exponential (WGSL matrices are column-major).
                s = s + e[m][r] * old[3u * m + c];
            }
            rot[(9u * i + 3u * r + c) * nv + v] = s;
        }
    }
}

#endif
#if NORMS
// NaN-propagating maximum: bit tests, as comparisons with NaN may be folded away.
fn is_nan_or_inf(p: real) -> bool {
    return (bitcast<u32>(f32(p)) & 0x7f800000u) == 0x7f800000u;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let v = gid.x;
    if (v >= nv) {
        return;
    }
    var r = real(0.0);
    var d = real(0.0);
    var dot_dr = real(0.0);
    var square = real(0.0);
    for (var k = 0u; k < 6u * dims.num_nodes; k = k + 1u) {
        let rk = residual[k * nv + v];
        let dk = delta[k * nv + v];
        let ra = abs(rk);
        let da = abs(alpha[v] * dk);
        if (ra > r || is_nan_or_inf(ra)) {
            r = ra;
        }
        if (da > d || is_nan_or_inf(da)) {
            d = da;
        }
        dot_dr = dot_dr + dk * rk;
        square = square + rk * rk;
    }
    norm_out[4u * v] = r;
    norm_out[4u * v + 1u] = d;
    norm_out[4u * v + 2u] = dot_dr;
    norm_out[4u * v + 3u] = square;
}
#endif
