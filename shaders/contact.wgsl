// Twin: src/kernels/contact.rs (formulas: src/physics/contact.rs, paper eqs 2.1–2.39 as
// corrected in docs/contact-element.md).
//
// One invocation per (variant, site) pair; pair i = site · num_variants + variant (variant
// index fastest). Per-pair fields are stored field-major: field k of pair i at
// [k · num_pairs + i]. Flags set by src/gpu/contact.rs select the terms a scene uses:
//   F64, POW (m ≠ 1 somewhere), BLEND (m < 1 somewhere), DAMPING (dynamic and c > 0
//   somewhere), DYNAMIC, FRICTION, SPLIT / COUPLED.
#include "shared/layout.wgsl"
#include "shared/listed.wgsl"
#if F64
#if POW
#include "shared/math_f64.wgsl"
#endif
#else
#if POW
fn pow_pos(x: f32, m: f32) -> f32 {
    return pow(x, m);
}
#endif
#endif

@group(0) @binding(0) var<storage, read> dims: ContactDims;
// Hole axis n per site: [3 · site + k].
@group(0) @binding(1) var<storage, read> site_normals: array<real>;
// clearance, disk_radius, k_e, m, c, mu_t, mu_l, eps, soft_blend, side_friction.
@group(0) @binding(2) var<storage, read> pair_params: array<real>;
// d (3) = x − x0, v (3), omega.
@group(0) @binding(3) var<storage, read> pair_state: array<real>;
// g (6), K (6×3 row-major), and in dynamics C (6×3), c_omega (6): OUT_FIELDS fields.
@group(0) @binding(4) var<storage, read_write> out_values: array<real>;
// 1 where delta > 0.
@group(0) @binding(5) var<storage, read_write> out_contact: array<u32>;
#if MASKED
// Built MASKED (with FORCE_ONLY: the engine's line-search trials): the variants still
// searching, compacted: [A, v_0, …, v_{A−1}]; the other pairs' outputs are left as they were.
@group(0) @binding(6) var<storage, read> searching: array<u32>;
#endif

fn param(field: u32, i: u32) -> real {
    return pair_params[field * dims.num_pairs + i];
}

fn state(field: u32, i: u32) -> real {
    return pair_state[field * dims.num_pairs + i];
}

fn put(field: u32, i: u32, x: real) {
    out_values[field * dims.num_pairs + i] = x;
}

fn put3(field: u32, i: u32, x: vec3<real>) {
    put(field, i, x.x);
    put(field + 1u, i, x.y);
    put(field + 2u, i, x.z);
}

// Output fields of the scene: g (6), K (18) and, in dynamics, C (18), c_omega (6). A
// static scene's buffer holds only the first 24 (src/kernels/contact.rs `output_fields`).
// Built FORCE_ONLY (the line-search trials, static or dynamic): g alone; the K, C and
// c_omega fields are not written.
#if FORCE_ONLY
const OUT_FIELDS: u32 = 6u;
#else
#if DYNAMIC
const OUT_FIELDS: u32 = 48u;
#else
const OUT_FIELDS: u32 = 24u;
#endif
#endif

// Zero outputs (no contact, or no force). Every output is written exactly once per pair.
fn clear(i: u32) {
    for (var k = 0u; k < OUT_FIELDS; k = k + 1u) {
        put(k, i, real(0.0));
    }
}

fn cross3(a: vec3<real>, b: vec3<real>) -> vec3<real> {
    return vec3<real>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

#if FRICTION
// Regularised sign and its derivative (eqs 2.18, 2.23, modulus written out).
fn regularised_sign(s: real, eps: real) -> vec2<real> {
    let a = abs(s);
    if (a >= eps) {
        return vec2<real>(s / a, real(0.0));
    }
    return vec2<real>((real(2.0) - a / eps) * s / eps, real(2.0) * (real(1.0) - a / eps) / eps);
}

struct Friction {
    phi: vec2<real>,
    // Columns of ∂phi/∂s: d_dst = ∂(phi_t, phi_l)/∂s_t, d_dsl = ∂(phi_t, phi_l)/∂s_l.
    d_dst: vec2<real>,
    d_dsl: vec2<real>,
}

fn friction_factors(s_t: real, s_l: real, eps: real) -> Friction {
    var f: Friction;
#if SPLIT
    let pt = regularised_sign(s_t, eps);
    let pl = regularised_sign(s_l, eps);
    f.phi = vec2<real>(pt.x, pl.x);
    f.d_dst = vec2<real>(pt.y, real(0.0));
    f.d_dsl = vec2<real>(real(0.0), pl.y);
#endif
#if COUPLED
    let w = sqrt(s_t * s_t + s_l * s_l);
    if (w >= eps) {
        let pt = s_t / w;
        let pl = s_l / w;
        f.phi = vec2<real>(pt, pl);
        // (1 − φ_t²)/w written φ_l²/w: no cancellation where one slip dominates (f32).
        f.d_dst = vec2<real>(pl * pl / w, -pl * pt / w);
        f.d_dsl = vec2<real>(-pt * pl / w, pt * pt / w);
    } else {
        let h = (real(2.0) - w / eps) / eps;
        var q = real(0.0);
        if (w > real(0.0)) {
            q = real(1.0) / (eps * eps * w);
        }
        f.phi = vec2<real>(h * s_t, h * s_l);
        f.d_dst = vec2<real>(h - q * s_t * s_t, -q * s_l * s_t);
        f.d_dsl = vec2<real>(-q * s_t * s_l, h - q * s_l * s_l);
    }
#endif
    return f;
}
#endif

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
#if MASKED
    // One invocation per (site, searching variant): pair site · V + v (the engine's pairs,
    // pair_offset 0).
    let sites = dims.num_pairs / dims.mask_variants;
    let at = item_of(gid.x, sites, dims.mask_variants);
    if (at.x >= sites) {
        return;
    }
    let i = at.x * dims.mask_variants + at.y;
#else
    let i = gid.x;
    if (i >= dims.num_pairs) {
        return;
    }
#endif
    out_contact[i] = 0u;

    let site = (dims.pair_offset + i) / dims.num_variants;
    let n = vec3<real>(site_normals[3u * site], site_normals[3u * site + 1u], site_normals[3u * site + 2u]);
    let clearance = param(0u, i);
    let k_e = param(2u, i);
    let d = vec3<real>(state(0u, i), state(1u, i), state(2u, i));
    let v = vec3<real>(state(3u, i), state(4u, i), state(5u, i));

    // Kinematics, eqs 2.1–2.5.
    let dn = dot(d, n);
    let d_t = d - n * dn;
    let r = sqrt(dot(d_t, d_t));
    let delta = r - clearance;
    if (!(delta > real(0.0))) {
        clear(i);
        return;
    }
    out_contact[i] = 1u;
    let u = d_t * (real(1.0) / r);
    let t = cross3(n, u);
    let v_u = dot(v, u);
    let v_t = dot(v, t);

    // Elastic force, eqs 2.6–2.8.
#if POW
    let m = param(3u, i);
    var f_e: real;
    var df_e: real;
    if (m == real(1.0)) {
        f_e = k_e * delta;
        df_e = k_e;
    }
#if BLEND
    else if (m < real(1.0) && delta < param(8u, i)) {
        let sb = param(8u, i);
        let sb_m = pow_pos(sb, m);
        let a = (real(2.0) - m) * k_e * sb_m / sb;
        let b = (m - real(1.0)) * k_e * sb_m / (sb * sb);
        f_e = delta * (a + b * delta);
        df_e = a + real(2.0) * b * delta;
    }
#endif
    else {
        let pw = pow_pos(delta, m);
        f_e = k_e * pw;
        df_e = m * k_e * pw / delta;
    }
#else
    let f_e = k_e * delta;
    let df_e = k_e;
#endif

    // Normal force N = max(f_e + f_d, 0), eqs 2.9–2.11; ∂N/∂x = dn_dx_u uᵀ + dn_dx_t tᵀ.
    var n_raw = f_e;
    let dn_dx_u = df_e;
    var dn_dx_t = real(0.0);
    var dn_dv_u = real(0.0);
#if DAMPING
    let c_wall = param(4u, i);
    n_raw = n_raw + c_wall * v_u;
    dn_dx_t = c_wall * v_t / r;
    dn_dv_u = c_wall;
#endif
    if (!(n_raw > real(0.0))) {
        clear(i);
        return;
    }
    let normal = n_raw;

    var dir_f = u;
    var dir_m = vec3<real>(real(0.0));
    var kf_t = t * (normal / r);
    var km_t = vec3<real>(real(0.0));
#if DYNAMIC
    // C (friction part) = N (cf_t tᵀ + cf_n nᵀ) for the force rows, N (cm_t tᵀ + cm_n nᵀ)
    // for the moment rows; c_omega = N R_d (cf_t; cm_t).
    var cf_t = vec3<real>(real(0.0));
    var cf_n = vec3<real>(real(0.0));
    var cm_t = vec3<real>(real(0.0));
    var cm_n = vec3<real>(real(0.0));
#endif

#if FRICTION
    // Slip speeds at the contact point (eqs 2.14, 2.21 corrected).
    let rd = param(1u, i);
    let mu_t = param(5u, i);
    let mu_l = param(6u, i);
    let omega = state(6u, i);
    let s_t = v_t + rd * omega;
    let s_l = dot(v, n);
    let fr = friction_factors(s_t, s_l, param(7u, i));
    let a_t = mu_t * fr.phi.x;
    let a_l = mu_l * fr.phi.y;
#if DYNAMIC
    let a_t_f = a_t;
    let mu_t_f = mu_t * fr.d_dst.x;
#else
    // Static: the circumferential friction's share as a side force (0 where the turning
    // string whirls: its friction as torque alone).
    let side = param(9u, i);
    let a_t_f = a_t * side;
    let mu_t_f = mu_t * fr.d_dst.x * side;
#endif
    dir_f = u + t * a_t_f + n * a_l;
    dir_m = (n * a_t - t * a_l) * rd;
    let sigma = -v_u / r;
    let fric_f = t * mu_t_f + n * (mu_l * fr.d_dst.y);
    let fric_m = (n * (mu_t * fr.d_dst.x) - t * (mu_l * fr.d_dst.y)) * rd;
    kf_t = kf_t + (fric_f * sigma - u * (a_t_f / r)) * normal;
    km_t = (fric_m * sigma + u * (rd * a_l / r)) * normal;
#if DYNAMIC
#if !FORCE_ONLY
    let fric_f_l = t * (mu_t * fr.d_dsl.x) + n * (mu_l * fr.d_dsl.y);
    let fric_m_l = (n * (mu_t * fr.d_dsl.x) - t * (mu_l * fr.d_dsl.y)) * rd;
    cf_t = fric_f;
    cf_n = fric_f_l;
    cm_t = fric_m;
    cm_n = fric_m_l;
#endif
#endif
#endif

    // Rows written as vectors (no dynamic indexing): K row r = dir[r]·∂N/∂x + kf_t[r]·tᵀ.
    put3(0u, i, dir_f * normal);
    put3(3u, i, dir_m * normal);
#if !FORCE_ONLY
    let dn_dx = u * dn_dx_u + t * dn_dx_t;
    put3(6u, i, dn_dx * dir_f.x + t * kf_t.x);
    put3(9u, i, dn_dx * dir_f.y + t * kf_t.y);
    put3(12u, i, dn_dx * dir_f.z + t * kf_t.z);
    put3(15u, i, dn_dx * dir_m.x + t * km_t.x);
    put3(18u, i, dn_dx * dir_m.y + t * km_t.y);
    put3(21u, i, dn_dx * dir_m.z + t * km_t.z);
#endif
#if DYNAMIC
#if !FORCE_ONLY
    let dn_dv = u * dn_dv_u;
    put3(24u, i, dn_dv * dir_f.x + (t * cf_t.x + n * cf_n.x) * normal);
    put3(27u, i, dn_dv * dir_f.y + (t * cf_t.y + n * cf_n.y) * normal);
    put3(30u, i, dn_dv * dir_f.z + (t * cf_t.z + n * cf_n.z) * normal);
    put3(33u, i, dn_dv * dir_m.x + (t * cm_t.x + n * cm_n.x) * normal);
    put3(36u, i, dn_dv * dir_m.y + (t * cm_t.y + n * cm_n.y) * normal);
    put3(39u, i, dn_dv * dir_m.z + (t * cm_t.z + n * cm_n.z) * normal);
#if FRICTION
    put3(42u, i, cf_t * (normal * rd));
    put3(45u, i, cm_t * (normal * rd));
#else
    put3(42u, i, vec3<real>(real(0.0)));
    put3(45u, i, vec3<real>(real(0.0)));
#endif
#endif
#endif
}
