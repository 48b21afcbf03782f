// Twin: src/kernels/beam.rs (formulas: src/physics/beam.rs, the co-rotational element).
//
// One invocation per (element, variant), index = element · V + variant. The element energy
// E (Euler–Bernoulli in the co-rotated frame) is evaluated in hyper-dual numbers
// (re, ε₁, ε₂, ε₁ε₂) — here vec4<real> — 144 times: DOF k perturbed along ε₂, DOF j along
// ε₁; f_j = ∂E/∂δ_j (the ε₁ part), K_jk = ∂²E (the ε₁ε₂ part). Rotations are perturbed as
// left spins (I + [ε e]×)·triad, as in the twin. Outputs in the assembly's layout:
// [(12 e + j) V + v] and [(144 e + 12 j + k) V + v].
//
// States are displacements w from each variant's base configuration X + b (kilometres of
// string lose their millimetres in f32 otherwise; the dynamic engine's base is the static
// equilibrium, the f32 static engine's the last load step's, so w is the motion): the
// chord is c + (w₂ − w₁), with the base chord c = (X₂ + b₂) − (X₁ + b₁) and its stretch
// s = |c| − l0 given per element and variant (formed in double precision on the host). In
// double precision the element's node positions are taken as w₁ and c + w₂ (as the twin)
// and the elongation as l − l0; in single precision the elongation is
// s + (2 c·Δw + Δw·Δw)/(l + |c|), without the cancellation of l − l0 (a strain of 1e-5
// would keep two digits) and without the metres the base has moved.
#include "shared/layout.wgsl"

@group(0) @binding(0) var<storage, read> dims: BeamDims;
// Node displacements, [(3 i + k) V + v]; rotations, [(9 i + 3 r + c) V + v].
@group(0) @binding(1) var<storage, read> x: array<real>;
@group(0) @binding(2) var<storage, read> rot: array<real>;
// Reference triad per node (row-major, 9 each), shared by the variants.
@group(0) @binding(3) var<storage, read> frame0: array<real>;
// Per element: EA/l0, GJ/l0, EI/l0, l0.
@group(0) @binding(4) var<storage, read> section: array<real>;
// Base chord and stretch per element and variant: [(4 e + k) V + v], k = 0–2 the chord,
// 3 the stretch |c| − l0.
@group(0) @binding(5) var<storage, read> chord: array<real>;
@group(0) @binding(6) var<storage, read_write> elem_force: array<real>;
@group(0) @binding(7) var<storage, read_write> elem_tangent: array<real>;

alias hd = vec4<real>;

fn hd_c(a: real) -> hd {
    return hd(a, real(0.0), real(0.0), real(0.0));
}

fn hd_mul(a: hd, b: hd) -> hd {
    return hd(a.x * b.x, a.x * b.y + a.y * b.x, a.x * b.z + a.z * b.x,
              a.x * b.w + a.y * b.z + a.z * b.y + a.w * b.x);
}

// g(a) with g', g'' at a.x.
fn hd_chain(a: hd, g: real, g1: real, g2: real) -> hd {
    return hd(g, g1 * a.y, g1 * a.z, g1 * a.w + g2 * a.y * a.z);
}

fn hd_div(a: hd, b: hd) -> hd {
    let inv = real(1.0) / b.x;
    return hd_mul(a, hd_chain(b, inv, -inv * inv, real(2.0) * inv * inv * inv));
}

fn hd_sqrt(a: hd) -> hd {
    let s = sqrt(a.x);
    return hd_chain(a, s, real(0.5) / s, real(-0.25) / (a.x * s));
}

#if F64
// atan on [0, 1] by two half-angle reductions and a Taylor series (no f64 atan on Vulkan).
fn atan_unit(t: real) -> real {
    var u = t / (real(1.0) + sqrt(real(1.0) + t * t));
    u = u / (real(1.0) + sqrt(real(1.0) + u * u));
    let u2 = u * u;
    var s = real(0.0);
    for (var step = 0u; step < 14u; step = step + 1u) {
        let k = 13u - step;
        var sign = real(1.0);
        if (k % 2u == 1u) {
            sign = real(-1.0);
        }
        s = s * u2 + sign / real(2u * k + 1u);
    }
    return real(4.0) * u * s;
}

fn atan2_real(y: real, x: real) -> real {
    let pi = real(3.141592653589793);
    let ay = abs(y);
    let ax = abs(x);
    var a: real;
    if (ay <= ax) {
        a = atan_unit(ay / ax);
    } else {
        a = real(0.5) * pi - atan_unit(ax / ay);
    }
    if (x < real(0.0)) {
        a = pi - a;
    }
    if (y < real(0.0)) {
        a = -a;
    }
    return a;
}
#else
fn atan2_real(y: real, x: real) -> real {
    return atan2(y, x);
}
#endif

// atan2 of hyper-duals (second order in both arguments), as HyperDual::atan2.
fn hd_atan2(y: hd, x: hd) -> hd {
    let r2 = x.x * x.x + y.x * y.x;
    let r4 = r2 * r2;
    let tx = -y.x / r2;
    let ty = x.x / r2;
    let txx = real(2.0) * x.x * y.x / r4;
    let tyy = -txx;
    let txy = (y.x * y.x - x.x * x.x) / r4;
    return hd(
        atan2_real(y.x, x.x),
        tx * x.y + ty * y.y,
        tx * x.z + ty * y.z,
        tx * x.w + ty * y.w + txx * x.y * x.z + txy * (x.y * y.z + y.y * x.z) + tyy * y.y * y.z,
    );
}

struct Tri {
    m: array<hd, 9>,
}

fn hd_cross(a: array<hd, 3>, b: array<hd, 3>) -> array<hd, 3> {
    return array<hd, 3>(
        hd_mul(a[1], b[2]) - hd_mul(a[2], b[1]),
        hd_mul(a[2], b[0]) - hd_mul(a[0], b[2]),
        hd_mul(a[0], b[1]) - hd_mul(a[1], b[0]),
    );
}

fn hd_norm(a: array<hd, 3>) -> hd {
    return hd_sqrt(hd_mul(a[0], a[0]) + hd_mul(a[1], a[1]) + hd_mul(a[2], a[2]));
}

// log of the rotation Rrᵀ·t (Rr columns e1, e2, e3), as physics::beam::rotation_log.
fn rel_log(e: array<array<hd, 3>, 3>, t: Tri) -> array<hd, 3> {
    // r[a][b] = Σ_k e[a][k] t[k][b]  (e[a] is column a of Rr, i.e. row a of Rrᵀ).
    var r: array<hd, 9>;
    for (var a = 0u; a < 3u; a = a + 1u) {
        for (var b = 0u; b < 3u; b = b + 1u) {
            r[3u * a + b] = hd_mul(e[a][0], t.m[b]) + hd_mul(e[a][1], t.m[3u + b]) + hd_mul(e[a][2], t.m[6u + b]);
        }
    }
    let half = hd_c(real(0.5));
    let w0 = hd_mul(half, r[7] - r[5]);
    let w1 = hd_mul(half, r[2] - r[6]);
    let w2 = hd_mul(half, r[3] - r[1]);
    let s2 = hd_mul(w0, w0) + hd_mul(w1, w1) + hd_mul(w2, w2);
    let c = hd_mul(half, r[0] + r[4] + r[8] - hd_c(real(1.0)));
    var factor: hd;
    if (s2.x < real(1e-6) && c.x > real(0.0)) {
        factor = hd_c(real(1.0)) + hd_mul(s2, hd_c(real(1.0) / real(6.0)) + hd_mul(s2, hd_c(real(3.0) / real(40.0))));
    } else {
        let s = hd_sqrt(s2);
        factor = hd_div(hd_atan2(s, c), s);
    }
    return array<hd, 3>(hd_mul(factor, w0), hd_mul(factor, w1), hd_mul(factor, w2));
}

// `base`: the element's base chord (xyz) and stretch (w), `lc` the chord's length — read
// and formed once per invocation, not per evaluation (single precision uses them).
fn energy(p1: array<hd, 3>, p2: array<hd, 3>, t1: Tri, t2: Tri, e: u32, base: vec4<real>, lc: real) -> hd {
    let ea = section[4u * e];
    let gj = section[4u * e + 1u];
    let ei = section[4u * e + 2u];
    let l0 = section[4u * e + 3u];
#if F64
    let d = array<hd, 3>(p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]);
    let l = hd_norm(d);
    let u = l - hd_c(l0);
#else
    let c = array<hd, 3>(hd_c(base.x), hd_c(base.y), hd_c(base.z));
    let du = array<hd, 3>(p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]);
    let d = array<hd, 3>(c[0] + du[0], c[1] + du[1], c[2] + du[2]);
    let l = hd_norm(d);
    let two_c_du = hd_mul(hd_c(real(2.0)), hd_mul(c[0], du[0]) + hd_mul(c[1], du[1]) + hd_mul(c[2], du[2]));
    let du_du = hd_mul(du[0], du[0]) + hd_mul(du[1], du[1]) + hd_mul(du[2], du[2]);
    let u = hd_c(base.w) + hd_div(two_c_du + du_du, l + hd_c(lc));
#endif
    let e1 = array<hd, 3>(hd_div(d[0], l), hd_div(d[1], l), hd_div(d[2], l));
    let half = hd_c(real(0.5));
    let p = array<hd, 3>(hd_mul(half, t1.m[1] + t2.m[1]), hd_mul(half, t1.m[4] + t2.m[4]), hd_mul(half, t1.m[7] + t2.m[7]));
    let e3u = hd_cross(e1, p);
    let n3 = hd_norm(e3u);
    let e3 = array<hd, 3>(hd_div(e3u[0], n3), hd_div(e3u[1], n3), hd_div(e3u[2], n3));
    let e2 = hd_cross(e3, e1);
    let frame = array<array<hd, 3>, 3>(e1, e2, e3);
    let th1 = rel_log(frame, t1);
    let th2 = rel_log(frame, t2);
    let twist = th2[0] - th1[0];
    let two = hd_c(real(2.0));
    let by = hd_mul(two, hd_mul(th1[1], th1[1]) + hd_mul(th1[1], th2[1]) + hd_mul(th2[1], th2[1]));
    let bz = hd_mul(two, hd_mul(th1[2], th1[2]) + hd_mul(th1[2], th2[2]) + hd_mul(th2[2], th2[2]));
    return hd_mul(half, hd_mul(hd_c(ea), hd_mul(u, u))) + hd_mul(half, hd_mul(hd_c(gj), hd_mul(twist, twist)))
        + hd_mul(hd_c(ei), by + bz);
}

// Perturbs DOF `dof` (node·6 + [u, θ]) by `unit`: translation, or left spin of the triad.
fn perturb(p: ptr<function, array<array<hd, 3>, 2>>, t: ptr<function, array<Tri, 2>>, dof: u32, unit: hd) {
    let node = dof / 6u;
    let k = dof % 6u;
    if (k < 3u) {
        (*p)[node][k] = (*p)[node][k] + unit;
    } else {
        let axis = k - 3u;
        let a = (axis + 1u) % 3u;
        let b = (axis + 2u) % 3u;
        // spin = I + unit·(E_ba − E_ab): rows a and b of the triad mix.
        let old = (*t)[node];
        for (var c = 0u; c < 3u; c = c + 1u) {
            (*t)[node].m[3u * b + c] = old.m[3u * b + c] + hd_mul(unit, old.m[3u * a + c]);
            (*t)[node].m[3u * a + c] = old.m[3u * a + c] - hd_mul(unit, old.m[3u * b + c]);
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    if (gid.x >= dims.num_elements * nv) {
        return;
    }
    let e = gid.x / nv;
    let v = gid.x % nv;
    let base = vec4<real>(chord[(4u * e) * nv + v], chord[(4u * e + 1u) * nv + v], chord[(4u * e + 2u) * nv + v],
                          chord[(4u * e + 3u) * nv + v]);
    let lc = sqrt(base.x * base.x + base.y * base.y + base.z * base.z);
    var p0: array<array<hd, 3>, 2>;
    var t0: array<Tri, 2>;
    for (var node = 0u; node < 2u; node = node + 1u) {
        let i = e + node;
        for (var k = 0u; k < 3u; k = k + 1u) {
#if F64
            // Node 2 at c + w₂ (the twin's positions).
            p0[node][k] = hd_c(real(node) * base[k] + x[(3u * i + k) * nv + v]);
#else
            p0[node][k] = hd_c(x[(3u * i + k) * nv + v]);
#endif
        }
        // triad = R_i · frame0_i
        for (var r = 0u; r < 3u; r = r + 1u) {
            for (var c = 0u; c < 3u; c = c + 1u) {
                var s = real(0.0);
                for (var m = 0u; m < 3u; m = m + 1u) {
                    s = s + rot[(9u * i + 3u * r + m) * nv + v] * frame0[9u * i + 3u * m + c];
                }
                t0[node].m[3u * r + c] = hd_c(s);
            }
        }
    }
    let eps1 = hd(real(0.0), real(1.0), real(0.0), real(0.0));
    let eps2 = hd(real(0.0), real(0.0), real(1.0), real(0.0));
    for (var k = 0u; k < 12u; k = k + 1u) {
        var pk = p0;
        var tk = t0;
        perturb(&pk, &tk, k, eps2);
        for (var j = 0u; j < 12u; j = j + 1u) {
            var pj = pk;
            var tj = tk;
            perturb(&pj, &tj, j, eps1);
            let en = energy(pj[0], pj[1], tj[0], tj[1], e, base, lc);
            elem_tangent[(144u * e + 12u * j + k) * nv + v] = en.w;
            if (k == 0u) {
                elem_force[(12u * e + j) * nv + v] = en.y;
            }
        }
    }
}
