// Twin: src/kernels/assemble.rs (static residual and block-tridiagonal tangent per variant).
//
// With DYNAMIC: the generalised-α iteration matrix M + hγ' C_t + h²β' K_t and the inertial
// residual (lumped mass, gyroscopic moments, mass-proportional Rayleigh damping); with
// UNBALANCE also each node's mass imbalance as a rigid eccentric mass
// (physics::mass::unbalance_terms). With SHIFT (static only) a relaxation's proximal shift
// (solve::continuation's Stage::Relax) on the translations and the rotations, its six
// bindings last.
//
// One invocation per (node, variant), index = node · V + variant; each gathers the halves of
// its two elements and its contact site, so no two invocations write the same entry, then
// applies the constraints to the blocks it owns. Layouts as in the twin's documentation.
#include "shared/layout.wgsl"
#include "shared/listed.wgsl"
#if SHIFT
#include "shared/rotation_log.wgsl"
#endif

@group(0) @binding(0) var<storage, read> dims: AssembleDims;
@group(0) @binding(1) var<storage, read> elem_force: array<real>;
#if FORCE_ONLY
// The static residual alone (line-search trials): no tangent read, no blocks written.
@group(0) @binding(2) var<storage, read> contact: array<real>;
@group(0) @binding(3) var<storage, read> contact_flag: array<u32>;
@group(0) @binding(4) var<storage, read> node_site: array<u32>;
@group(0) @binding(5) var<storage, read> f_ext: array<real>;
@group(0) @binding(6) var<storage, read> basis: array<real>;
@group(0) @binding(7) var<storage, read> fixed: array<u32>;
@group(0) @binding(8) var<storage, read_write> out_rhs: array<real>;
#if MASKED
// Built MASKED (the engine's trials): the variants still searching, compacted:
// [A, v_0, …, v_{A−1}]; the others are skipped.
@group(0) @binding(9) var<storage, read> searching: array<u32>;
#if SHIFT
@group(0) @binding(10) var<storage, read> shift: array<real>;
@group(0) @binding(11) var<storage, read> anchor: array<real>;
@group(0) @binding(12) var<storage, read> x_now: array<real>;
@group(0) @binding(13) var<storage, read> rot_shift: array<real>;
@group(0) @binding(14) var<storage, read> anchor_rot: array<real>;
@group(0) @binding(15) var<storage, read> rot_now: array<real>;
#endif
#if DYNAMIC
// The dynamic residual alone (the dynamic engine's trials): its inputs after the output
// and the list, as the full kernel's (no hole axes: they enter the matrix only).
@group(0) @binding(10) var<storage, read> dyn_coef: array<real>;
@group(0) @binding(11) var<storage, read> node_mass: array<real>;
@group(0) @binding(12) var<storage, read> inertia0: array<real>;
@group(0) @binding(13) var<storage, read> rot: array<real>;
@group(0) @binding(14) var<storage, read> vel: array<real>;
@group(0) @binding(15) var<storage, read> vdot: array<real>;
#if UNBALANCE
@group(0) @binding(16) var<storage, read> unbalance: array<real>;
#endif
#endif
#else
#if SHIFT
@group(0) @binding(9) var<storage, read> shift: array<real>;
@group(0) @binding(10) var<storage, read> anchor: array<real>;
@group(0) @binding(11) var<storage, read> x_now: array<real>;
@group(0) @binding(12) var<storage, read> rot_shift: array<real>;
@group(0) @binding(13) var<storage, read> anchor_rot: array<real>;
@group(0) @binding(14) var<storage, read> rot_now: array<real>;
#endif
#if DYNAMIC
@group(0) @binding(9) var<storage, read> dyn_coef: array<real>;
@group(0) @binding(10) var<storage, read> node_mass: array<real>;
@group(0) @binding(11) var<storage, read> inertia0: array<real>;
@group(0) @binding(12) var<storage, read> rot: array<real>;
@group(0) @binding(13) var<storage, read> vel: array<real>;
@group(0) @binding(14) var<storage, read> vdot: array<real>;
#if UNBALANCE
@group(0) @binding(15) var<storage, read> unbalance: array<real>;
#endif
#endif
#endif
#else
@group(0) @binding(2) var<storage, read> elem_tangent: array<real>;
@group(0) @binding(3) var<storage, read> contact: array<real>;
@group(0) @binding(4) var<storage, read> contact_flag: array<u32>;
@group(0) @binding(5) var<storage, read> node_site: array<u32>;
@group(0) @binding(6) var<storage, read> f_ext: array<real>;
// Translation basis per node (row-major, identity where none) and fixed-DOF masks.
@group(0) @binding(7) var<storage, read> basis: array<real>;
@group(0) @binding(8) var<storage, read> fixed: array<u32>;
#if DYNAMIC
// [hγ', h²β', a0].
@group(0) @binding(9) var<storage, read> dyn_coef: array<real>;
@group(0) @binding(10) var<storage, read> node_mass: array<real>;
// Rotary inertia per node at the reference orientation (row-major).
@group(0) @binding(11) var<storage, read> inertia0: array<real>;
@group(0) @binding(12) var<storage, read> rot: array<real>;
@group(0) @binding(13) var<storage, read> vel: array<real>;
@group(0) @binding(14) var<storage, read> vdot: array<real>;
// Hole axis per contact pair.
@group(0) @binding(15) var<storage, read> pair_normals: array<real>;
#if UNBALANCE
// Mass imbalance per node and variant at the reference orientation (kg·m): [(3 i + k) V + v].
@group(0) @binding(16) var<storage, read> unbalance: array<real>;
@group(0) @binding(17) var<storage, read_write> out_diag: array<real>;
@group(0) @binding(18) var<storage, read_write> out_upper: array<real>;
@group(0) @binding(19) var<storage, read_write> out_lower: array<real>;
@group(0) @binding(20) var<storage, read_write> out_rhs: array<real>;
#if MASKED
// Built MASKED (the dynamic engine's Newton iterations): the variants still iterating,
// compacted: [A, v_0, …, v_{A−1}]; the others are skipped.
@group(0) @binding(21) var<storage, read> searching: array<u32>;
#endif
#else
@group(0) @binding(16) var<storage, read_write> out_diag: array<real>;
@group(0) @binding(17) var<storage, read_write> out_upper: array<real>;
@group(0) @binding(18) var<storage, read_write> out_lower: array<real>;
@group(0) @binding(19) var<storage, read_write> out_rhs: array<real>;
#if MASKED
@group(0) @binding(20) var<storage, read> searching: array<u32>;
#endif
#endif
const OUT_C: u32 = 24u;
const OUT_C_OMEGA: u32 = 42u;
#else
@group(0) @binding(9) var<storage, read_write> out_diag: array<real>;
@group(0) @binding(10) var<storage, read_write> out_upper: array<real>;
@group(0) @binding(11) var<storage, read_write> out_lower: array<real>;
@group(0) @binding(12) var<storage, read_write> out_rhs: array<real>;
#if SHIFT
@group(0) @binding(13) var<storage, read> shift: array<real>;
@group(0) @binding(14) var<storage, read> anchor: array<real>;
@group(0) @binding(15) var<storage, read> x_now: array<real>;
@group(0) @binding(16) var<storage, read> rot_shift: array<real>;
@group(0) @binding(17) var<storage, read> anchor_rot: array<real>;
@group(0) @binding(18) var<storage, read> rot_now: array<real>;
#endif
#endif
#endif

// Field offsets of the contact kernel's outputs (src/kernels/contact.rs OUT_G, OUT_K).
const OUT_G: u32 = 0u;
const OUT_K: u32 = 6u;
const NO_SITE: u32 = 0xffffffffu;

#if UNBALANCE
// Rows of [x]×.
fn skew3(x: vec3<real>) -> array<vec3<real>, 3> {
    return array<vec3<real>, 3>(
        vec3<real>(real(0.0), -x.z, x.y),
        vec3<real>(x.z, real(0.0), -x.x),
        vec3<real>(-x.y, x.x, real(0.0)),
    );
}

// a · b for matrices by rows.
fn mul3(a: array<vec3<real>, 3>, b: array<vec3<real>, 3>) -> array<vec3<real>, 3> {
    var out: array<vec3<real>, 3>;
    for (var r = 0u; r < 3u; r = r + 1u) {
        out[r] = a[r].x * b[0] + a[r].y * b[1] + a[r].z * b[2];
    }
    return out;
}
#endif

#if !FORCE_ONLY
// Entry (j, k) of element e's 12×12 tangent from the beam kernel's 81 independent entries
// [(81 e + 9 r + d) V + v] (kernels::beam::tangent_slot): rows 0–2 are rows 6–8 negated,
// columns 0–2 columns 6–8 negated; the directions d are columns 6–8, 3–5 and 9–11.
fn tangent_at(e: u32, j: u32, k: u32, nv: u32, v: u32) -> real {
    let r = select(j - 3u, j + 3u, j < 3u);
    var negated = j < 3u;
    var d = k;
    if (k < 3u) {
        negated = !negated;
    } else if (k >= 9u) {
        d = k - 3u;
    } else if (k >= 6u) {
        d = k - 6u;
    }
    let x = elem_tangent[(81u * e + 9u * r + d) * nv + v];
    return select(x, -x, negated);
}

// block ← diag(B_a, I)ᵀ · block · diag(B_b, I): rows of node a, then columns of node b.
fn transform(blk: ptr<function, array<real, 36>>, a: u32, b: u32) {
    var rows: array<real, 18>;
    for (var k = 0u; k < 18u; k = k + 1u) {
        rows[k] = (*blk)[k];
    }
    for (var r = 0u; r < 3u; r = r + 1u) {
        for (var c = 0u; c < 6u; c = c + 1u) {
            var s = real(0.0);
            for (var k = 0u; k < 3u; k = k + 1u) {
                s = s + basis[9u * a + 3u * k + r] * rows[6u * k + c];
            }
            (*blk)[6u * r + c] = s;
        }
    }
    for (var r = 0u; r < 6u; r = r + 1u) {
        let v = vec3<real>((*blk)[6u * r], (*blk)[6u * r + 1u], (*blk)[6u * r + 2u]);
        for (var c = 0u; c < 3u; c = c + 1u) {
            var s = real(0.0);
            for (var k = 0u; k < 3u; k = k + 1u) {
                s = s + v[k] * basis[9u * b + 3u * k + c];
            }
            (*blk)[6u * r + c] = s;
        }
    }
}

fn clear_fixed(blk: ptr<function, array<real, 36>>, row_mask: u32, col_mask: u32) {
    for (var d = 0u; d < 6u; d = d + 1u) {
        for (var c = 0u; c < 6u; c = c + 1u) {
            if ((row_mask & (1u << d)) != 0u) {
                (*blk)[6u * d + c] = real(0.0);
            }
            if ((col_mask & (1u << d)) != 0u) {
                (*blk)[6u * c + d] = real(0.0);
            }
        }
    }
}

#endif

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let n = dims.num_nodes;
    // One invocation per (node, variant), or built MASKED per (node, listed variant).
    let at = item_of(gid.x, n, nv);
    if (at.x >= n) {
        return;
    }
    let i = at.x;
    let v = at.y;
    let pairs = dims.num_sites * nv;
    var r: array<real, 6>;
#if !FORCE_ONLY
    var d: array<real, 36>;
    var u: array<real, 36>;
    var l: array<real, 36>;
#endif
    for (var k = 0u; k < 6u; k = k + 1u) {
        r[k] = -f_ext[(6u * i + k) * nv + v];
    }
#if !FORCE_ONLY
    for (var k = 0u; k < 36u; k = k + 1u) {
        d[k] = real(0.0);
    }
#endif
    if (i > 0u) {
        let e = i - 1u;
        for (var k = 0u; k < 6u; k = k + 1u) {
            r[k] = r[k] + elem_force[(12u * e + 6u + k) * nv + v];
#if !FORCE_ONLY
            for (var c = 0u; c < 6u; c = c + 1u) {
                d[6u * k + c] = d[6u * k + c] + tangent_at(e, 6u + k, 6u + c, nv, v);
            }
#endif
        }
    }
    if (i + 1u < n) {
        let e = i;
        for (var k = 0u; k < 6u; k = k + 1u) {
            r[k] = r[k] + elem_force[(12u * e + k) * nv + v];
#if !FORCE_ONLY
            for (var c = 0u; c < 6u; c = c + 1u) {
                d[6u * k + c] = d[6u * k + c] + tangent_at(e, k, c, nv, v);
                u[6u * k + c] = tangent_at(e, k, 6u + c, nv, v);
                l[6u * k + c] = tangent_at(e, 6u + k, c, nv, v);
            }
#endif
        }
    }
    let s = node_site[i * nv + v];
    if (s != NO_SITE) {
        let p = s * nv + v;
        if (contact_flag[p] != 0u) {
            for (var k = 0u; k < 6u; k = k + 1u) {
                r[k] = r[k] + contact[(OUT_G + k) * pairs + p];
#if !FORCE_ONLY
                for (var c = 0u; c < 3u; c = c + 1u) {
                    d[6u * k + c] = d[6u * k + c] + contact[(OUT_K + 3u * k + c) * pairs + p];
                }
#endif
            }
        }
    }
#if DYNAMIC
    let hg = dyn_coef[0];
    let a0 = dyn_coef[2];
#if !FORCE_ONLY
    let hhb = dyn_coef[1];
    for (var k = 0u; k < 36u; k = k + 1u) {
        d[k] = hhb * d[k];
        u[k] = hhb * u[k];
        l[k] = hhb * l[k];
    }
    if (s != NO_SITE) {
        let p = s * nv + v;
        if (contact_flag[p] != 0u) {
            // Each input read once (a read is a loop over the lanes on lavapipe).
            let normal = vec3<real>(pair_normals[3u * p], pair_normals[3u * p + 1u], pair_normals[3u * p + 2u]);
            for (var k = 0u; k < 6u; k = k + 1u) {
                let c_omega = contact[(OUT_C_OMEGA + k) * pairs + p];
                for (var c = 0u; c < 3u; c = c + 1u) {
                    d[6u * k + c] = d[6u * k + c] + hg * contact[(OUT_C + 3u * k + c) * pairs + p];
                    d[6u * k + 3u + c] = d[6u * k + 3u + c] + hg * c_omega * normal[c];
                }
            }
        }
    }
#endif
    // The node's rotation, read once: R[a][k] = rot[(9 i + 3 a + k) V + v].
    var rm: array<array<real, 3>, 3>;
    for (var a = 0u; a < 3u; a = a + 1u) {
        for (var k = 0u; k < 3u; k = k + 1u) {
            rm[a][k] = rot[(9u * i + 3u * a + k) * nv + v];
        }
    }
    // J = R J0 Rᵀ.
    var rj: array<array<real, 3>, 3>;
    for (var a = 0u; a < 3u; a = a + 1u) {
        for (var c = 0u; c < 3u; c = c + 1u) {
            var acc_rj = real(0.0);
            for (var k = 0u; k < 3u; k = k + 1u) {
                acc_rj = acc_rj + rm[a][k] * inertia0[9u * i + 3u * k + c];
            }
            rj[a][c] = acc_rj;
        }
    }
    var jm: array<array<real, 3>, 3>;
    for (var a = 0u; a < 3u; a = a + 1u) {
        for (var c = 0u; c < 3u; c = c + 1u) {
            var acc_j = real(0.0);
            for (var k = 0u; k < 3u; k = k + 1u) {
                acc_j = acc_j + rj[a][k] * rm[c][k];
            }
            jm[a][c] = acc_j;
        }
    }
    let m = node_mass[i];
    let w = vec3<real>(vel[(6u * i + 3u) * nv + v], vel[(6u * i + 4u) * nv + v], vel[(6u * i + 5u) * nv + v]);
    let wdot = vec3<real>(vdot[(6u * i + 3u) * nv + v], vdot[(6u * i + 4u) * nv + v], vdot[(6u * i + 5u) * nv + v]);
    var jw = vec3<real>(real(0.0), real(0.0), real(0.0));
    var jwd = vec3<real>(real(0.0), real(0.0), real(0.0));
    for (var a = 0u; a < 3u; a = a + 1u) {
        var s1 = real(0.0);
        var s2 = real(0.0);
        for (var k = 0u; k < 3u; k = k + 1u) {
            s1 = s1 + jm[a][k] * w[k];
            s2 = s2 + jm[a][k] * wdot[k];
        }
        jw[a] = s1;
        jwd[a] = s2;
    }
    let gyro = vec3<real>(w.y * jw.z - w.z * jw.y, w.z * jw.x - w.x * jw.z, w.x * jw.y - w.y * jw.x);
    for (var k = 0u; k < 3u; k = k + 1u) {
        r[k] = r[k] + m * vdot[(6u * i + k) * nv + v] + a0 * m * vel[(6u * i + k) * nv + v];
        r[3u + k] = r[3u + k] + jwd[k] + gyro[k];
    }
#if !FORCE_ONLY
    // Rows of [ω]× and [Jω]×.
    let sw = array<vec3<real>, 3>(
        vec3<real>(real(0.0), -w.z, w.y),
        vec3<real>(w.z, real(0.0), -w.x),
        vec3<real>(-w.y, w.x, real(0.0)),
    );
    let sjw = array<vec3<real>, 3>(
        vec3<real>(real(0.0), -jw.z, jw.y),
        vec3<real>(jw.z, real(0.0), -jw.x),
        vec3<real>(-jw.y, jw.x, real(0.0)),
    );
    for (var k = 0u; k < 3u; k = k + 1u) {
        d[6u * k + k] = d[6u * k + k] + m + hg * a0 * m;
        for (var c = 0u; c < 3u; c = c + 1u) {
            // ∂(ω × Jω)/∂ω = [ω]× J − [Jω]×.
            var swj = real(0.0);
            for (var q = 0u; q < 3u; q = q + 1u) {
                swj = swj + sw[k][q] * jm[q][c];
            }
            d[6u * (3u + k) + 3u + c] = d[6u * (3u + k) + 3u + c] + jm[k][c] + hg * (swj - sjw[k][c]);
        }
    }
#endif
#if UNBALANCE
    // U = R U0; d = U/M: M (ω̇ × d + ω × (ω × d)) and U × (ẍ + ω̇ × d + ω × (ω × d)), with
    // their derivatives by v̇ and (times hγ') by ω.
    let u0 = vec3<real>(unbalance[(3u * i) * nv + v], unbalance[(3u * i + 1u) * nv + v],
                        unbalance[(3u * i + 2u) * nv + v]);
    if (m > real(0.0) && (u0.x != real(0.0) || u0.y != real(0.0) || u0.z != real(0.0))) {
        var uu = vec3<real>(real(0.0), real(0.0), real(0.0));
        for (var a = 0u; a < 3u; a = a + 1u) {
            uu[a] = rm[a][0] * u0.x + rm[a][1] * u0.y + rm[a][2] * u0.z;
        }
        let dd = uu / m;
        let xdd = vec3<real>(vdot[(6u * i) * nv + v], vdot[(6u * i + 1u) * nv + v], vdot[(6u * i + 2u) * nv + v]);
        let wd = wdot;
        let wxd = cross(w, dd);
        let a_rel = cross(wd, dd) + cross(w, wxd);
        let moment = cross(uu, xdd + a_rel);
        for (var a = 0u; a < 3u; a = a + 1u) {
            r[a] = r[a] + m * a_rel[a];
            r[3u + a] = r[3u + a] + moment[a];
        }
#if !FORCE_ONLY
        let su = skew3(uu);
        let sd = skew3(dd);
        let swd = skew3(wxd);
        let sw_sd = mul3(skew3(w), sd);
        var dw: array<vec3<real>, 3>;
        for (var a = 0u; a < 3u; a = a + 1u) {
            dw[a] = -swd[a] - sw_sd[a];
        }
        let su_sd = mul3(su, sd);
        let su_dw = mul3(su, dw);
        for (var a = 0u; a < 3u; a = a + 1u) {
            for (var b = 0u; b < 3u; b = b + 1u) {
                d[6u * a + 3u + b] = d[6u * a + 3u + b] - su[a][b] + hg * m * dw[a][b];
                d[6u * (3u + a) + b] = d[6u * (3u + a) + b] + su[a][b];
                d[6u * (3u + a) + 3u + b] = d[6u * (3u + a) + 3u + b] - su_sd[a][b] + hg * su_dw[a][b];
            }
        }
#endif
    }
#endif
#endif
#if SHIFT
    // A relaxation's proximal shift (static only; twin: kernels::assemble's ShiftInputs):
    // s_v (u − a) on the translations' residual, s_v I on their diagonal block, before the
    // constraints. Laid out [(3 i + k) V + v], as the configuration.
    let s_v = shift[v];
    if (s_v != real(0.0)) {
        for (var k = 0u; k < 3u; k = k + 1u) {
            let at = (3u * i + k) * nv + v;
            r[k] = r[k] + s_v * (x_now[at] - anchor[at]);
#if !FORCE_ONLY
            d[7u * k] = d[7u * k] + s_v;
#endif
        }
    }
    // Once the translations' shift reached its ceiling, the rotations' too: s_r log(R R_aᵀ)
    // on the moments' residual (R the node's rotation, R_a its anchor's; rows of both
    // [(9 i + 3 a + k) V + v]) and s_r I on their diagonal block (the CPU solve's
    // add_rotation_shift).
    let s_r = rot_shift[v];
    if (s_r != real(0.0)) {
        var rel: array<vec3<real>, 3>;
        for (var a = 0u; a < 3u; a = a + 1u) {
            var row = vec3<real>(real(0.0), real(0.0), real(0.0));
            for (var k = 0u; k < 3u; k = k + 1u) {
                let r_ak = rot_now[(9u * i + 3u * a + k) * nv + v];
                row = row + r_ak * vec3<real>(anchor_rot[(9u * i + k) * nv + v],
                    anchor_rot[(9u * i + 3u + k) * nv + v], anchor_rot[(9u * i + 6u + k) * nv + v]);
            }
            rel[a] = row;
        }
        let theta = rotation_log(rel);
        for (var k = 0u; k < 3u; k = k + 1u) {
            r[3u + k] = r[3u + k] + s_r * theta[k];
#if !FORCE_ONLY
            d[7u * (3u + k)] = d[7u * (3u + k)] + s_r;
#endif
        }
    }
#endif
    // Constraints (as statics::constrain): bases, then fixed DOFs.
#if !FORCE_ONLY
    transform(&d, i, i);
#endif
    let rv = vec3<real>(r[0], r[1], r[2]);
    for (var row = 0u; row < 3u; row = row + 1u) {
        var s = real(0.0);
        for (var k = 0u; k < 3u; k = k + 1u) {
            s = s + basis[9u * i + 3u * k + row] * rv[k];
        }
        r[row] = s;
    }
    let f_i = fixed[i];
#if !FORCE_ONLY
    clear_fixed(&d, f_i, f_i);
#endif
    for (var k = 0u; k < 6u; k = k + 1u) {
        if ((f_i & (1u << k)) != 0u) {
            r[k] = real(0.0);
#if !FORCE_ONLY
            d[6u * k + k] = real(1.0);
#endif
        }
    }
    for (var k = 0u; k < 6u; k = k + 1u) {
        out_rhs[(6u * i + k) * nv + v] = r[k];
    }
#if !FORCE_ONLY
    for (var k = 0u; k < 36u; k = k + 1u) {
        out_diag[(36u * i + k) * nv + v] = d[k];
    }
    if (i + 1u < n) {
        transform(&u, i, i + 1u);
        transform(&l, i + 1u, i);
        let f_j = fixed[i + 1u];
        clear_fixed(&u, f_i, f_j);
        clear_fixed(&l, f_j, f_i);
        for (var k = 0u; k < 36u; k = k + 1u) {
            out_upper[(36u * i + k) * nv + v] = u[k];
            out_lower[(36u * i + k) * nv + v] = l[k];
        }
    }
#endif
}
