// Twin: src/kernels/dynamics.rs (generalised-α predictor, Newton correction, force scale).
//
// Composed three ways (flags): PREDICT, one invocation per (node, variant): the trial state
// at t_{n+1} from the state at t_n and the Newton unknown v̇_{n+1} (top node: prescribed
// accelerations written into v̇ first, the table's and hook's kinematics after);
// ACCEL, one invocation per (node, variant): v̇_out = v̇ + α (B Δv_u, Δv_θ);
// SCALE, one invocation per variant: max_i m_i |v̇_u,i|. Layouts as in the twin. Built
// MASKED (the dynamic engine's trials and iterations) each runs for the listed variants
// [A, v_0, …] alone (its last binding).
#include "shared/layout.wgsl"
#include "shared/listed.wgsl"

@group(0) @binding(0) var<storage, read> dims: ChainDims;
#if PREDICT
// [h, α_m, α_f, β, γ].
@group(0) @binding(1) var<storage, read> coef: array<real>;
// [top_fixed | driven << 8 | lowered << 9].
@group(0) @binding(2) var<storage, read> step_flags: array<u32>;
// Per variant [f · V + v]: table rotation (9), its angular velocity and acceleration (3
// each, about the top's hole axis), the hook's travel, speed and acceleration (3 each).
@group(0) @binding(3) var<storage, read> top: array<real>;
@group(0) @binding(4) var<storage, read> u_n: array<real>;
@group(0) @binding(5) var<storage, read> rot_n: array<real>;
@group(0) @binding(6) var<storage, read> vel_n: array<real>;
@group(0) @binding(7) var<storage, read> acc_n: array<real>;
@group(0) @binding(8) var<storage, read> vdot_n: array<real>;
@group(0) @binding(9) var<storage, read_write> vdot: array<real>;
@group(0) @binding(10) var<storage, read_write> u_1: array<real>;
@group(0) @binding(11) var<storage, read_write> rot_1: array<real>;
@group(0) @binding(12) var<storage, read_write> vel_1: array<real>;
@group(0) @binding(13) var<storage, read_write> acc_1: array<real>;
#if MASKED
// Built MASKED (the engine's line-search trials): the variants still searching, compacted:
// [A, v_0, …, v_{A−1}]; one invocation per (node, listed variant), the others untouched.
@group(0) @binding(14) var<storage, read> searching: array<u32>;
#endif
#endif
#if ACCEL
@group(0) @binding(1) var<storage, read> basis: array<real>;
@group(0) @binding(2) var<storage, read> vdot_in: array<real>;
@group(0) @binding(3) var<storage, read> delta: array<real>;
@group(0) @binding(4) var<storage, read> alpha: array<real>;
@group(0) @binding(5) var<storage, read_write> vdot_out: array<real>;
#if MASKED
@group(0) @binding(6) var<storage, read> searching: array<u32>;
#endif
#endif
#if SCALE
@group(0) @binding(1) var<storage, read> node_mass: array<real>;
@group(0) @binding(2) var<storage, read> vdot_in: array<real>;
@group(0) @binding(3) var<storage, read_write> scale_out: array<real>;
#if MASKED
@group(0) @binding(4) var<storage, read> searching: array<u32>;
#endif
#endif

#if PREDICT
#include "shared/rotation_exp.wgsl"

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let n = dims.num_nodes;
    let at = item_of(gid.x, n, nv);
    if (at.x >= n) {
        return;
    }
    let i = at.x;
    let v = at.y;
    let h = coef[0];
    let alpha_m = coef[1];
    let alpha_f = coef[2];
    let beta = coef[3];
    let gamma = coef[4];
    let flags = step_flags[0];
    let driven = (flags & 256u) != 0u;
    let lowered = (flags & 512u) != 0u;
    if (i == 0u) {
        for (var k = 0u; k < 6u; k = k + 1u) {
            if ((flags & (1u << k)) != 0u) {
                vdot[k * nv + v] = real(0.0);
            }
        }
        for (var k = 0u; k < 3u; k = k + 1u) {
            if (driven) {
                vdot[(3u + k) * nv + v] = top[(12u + k) * nv + v];
            }
            if (lowered) {
                vdot[k * nv + v] = top[(21u + k) * nv + v];
            }
        }
    }
    let one = real(1.0);
    let ratio = (one - alpha_f) / (one - alpha_m);
    var a1: array<real, 6>;
    var v1: array<real, 6>;
    var dq: array<real, 6>;
    for (var k = 0u; k < 6u; k = k + 1u) {
        let idx = (6u * i + k) * nv + v;
        a1[k] = ratio * vdot[idx] + (alpha_f * vdot_n[idx] - alpha_m * acc_n[idx]) / (one - alpha_m);
        v1[k] = vel_n[idx] + h * ((one - gamma) * acc_n[idx] + gamma * a1[k]);
        dq[k] = h * (vel_n[idx] + h * ((real(0.5) - beta) * acc_n[idx] + beta * a1[k]));
    }
    var u1: array<real, 3>;
    for (var k = 0u; k < 3u; k = k + 1u) {
        u1[k] = u_n[(3u * i + k) * nv + v] + dq[k];
    }
    let e = rotation_exp(vec3<real>(dq[3], dq[4], dq[5]));
    var r1: array<real, 9>;
    for (var r = 0u; r < 3u; r = r + 1u) {
        for (var c = 0u; c < 3u; c = c + 1u) {
            var s = real(0.0);
            for (var m = 0u; m < 3u; m = m + 1u) {
                // e[m][r]: row r, column m (WGSL matrices are column-major).
                s = s + e[m][r] * rot_n[(9u * i + 3u * m + c) * nv + v];
            }
            r1[3u * r + c] = s;
        }
    }
    if (i == 0u) {
        if (driven) {
            for (var k = 0u; k < 9u; k = k + 1u) {
                r1[k] = top[k * nv + v];
            }
            for (var k = 0u; k < 3u; k = k + 1u) {
                v1[3u + k] = top[(9u + k) * nv + v];
            }
        }
        if (lowered) {
            for (var k = 0u; k < 3u; k = k + 1u) {
                u1[k] = top[(15u + k) * nv + v];
                v1[k] = top[(18u + k) * nv + v];
            }
        }
    }
    for (var k = 0u; k < 3u; k = k + 1u) {
        u_1[(3u * i + k) * nv + v] = u1[k];
    }
    for (var k = 0u; k < 9u; k = k + 1u) {
        rot_1[(9u * i + k) * nv + v] = r1[k];
    }
    for (var k = 0u; k < 6u; k = k + 1u) {
        vel_1[(6u * i + k) * nv + v] = v1[k];
        acc_1[(6u * i + k) * nv + v] = a1[k];
    }
}
#endif

#if ACCEL
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let n = dims.num_nodes;
    let at = item_of(gid.x, n, nv);
    if (at.x >= n) {
        return;
    }
    let i = at.x;
    let v = at.y;
    for (var r = 0u; r < 3u; r = r + 1u) {
        var s = real(0.0);
        for (var k = 0u; k < 3u; k = k + 1u) {
            s = s + basis[9u * i + 3u * r + k] * delta[(6u * i + k) * nv + v];
        }
        vdot_out[(6u * i + r) * nv + v] = vdot_in[(6u * i + r) * nv + v] + alpha[v] * s;
    }
    for (var k = 3u; k < 6u; k = k + 1u) {
        let idx = (6u * i + k) * nv + v;
        vdot_out[idx] = vdot_in[idx] + alpha[v] * delta[idx];
    }
}
#endif

#if SCALE
#include "shared/finite.wgsl"

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let at = item_of(gid.x, 1u, nv);
    if (at.x >= 1u) {
        return;
    }
    let v = at.y;
    var s = real(0.0);
    for (var i = 0u; i < dims.num_nodes; i = i + 1u) {
        for (var k = 0u; k < 3u; k = k + 1u) {
            let f = abs(node_mass[i] * vdot_in[(6u * i + k) * nv + v]);
            if (f > s || is_nan_or_inf(f)) {
                s = f;
            }
        }
    }
    scale_out[v] = s;
}
#endif
