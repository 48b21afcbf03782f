// Twin: src/kernels/assemble.rs (static residual and block-tridiagonal tangent per variant).
//
// One invocation per (node, variant), index = node · V + variant; each gathers the halves of
// its two elements and its contact site, so no two invocations write the same entry. Layouts
// as in the twin's module documentation.
#include "shared/layout.wgsl"

@group(0) @binding(0) var<uniform> dims: AssembleDims;
@group(0) @binding(1) var<storage, read> elem_force: array<real>;
@group(0) @binding(2) var<storage, read> elem_tangent: array<real>;
@group(0) @binding(3) var<storage, read> contact: array<real>;
@group(0) @binding(4) var<storage, read> contact_flag: array<u32>;
@group(0) @binding(5) var<storage, read> node_site: array<u32>;
@group(0) @binding(6) var<storage, read> f_ext: array<real>;
@group(0) @binding(7) var<storage, read_write> out_diag: array<real>;
@group(0) @binding(8) var<storage, read_write> out_upper: array<real>;
@group(0) @binding(9) var<storage, read_write> out_lower: array<real>;
@group(0) @binding(10) var<storage, read_write> out_rhs: array<real>;

// Field offsets of the contact kernel's outputs (src/kernels/contact.rs OUT_G, OUT_K).
const OUT_G: u32 = 0u;
const OUT_K: u32 = 6u;
const NO_SITE: u32 = 0xffffffffu;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let n = dims.num_nodes;
    if (gid.x >= n * nv) {
        return;
    }
    let i = gid.x / nv;
    let v = gid.x % nv;
    let pairs = dims.num_sites * nv;
    var r: array<real, 6>;
    var d: array<real, 36>;
    for (var k = 0u; k < 6u; k = k + 1u) {
        r[k] = -f_ext[(6u * i + k) * nv + v];
    }
    for (var k = 0u; k < 36u; k = k + 1u) {
        d[k] = real(0.0);
    }
    if (i > 0u) {
        let e = i - 1u;
        for (var k = 0u; k < 6u; k = k + 1u) {
            r[k] = r[k] + elem_force[(12u * e + 6u + k) * nv + v];
            for (var c = 0u; c < 6u; c = c + 1u) {
                d[6u * k + c] = d[6u * k + c] + elem_tangent[(144u * e + 12u * (6u + k) + 6u + c) * nv + v];
            }
        }
    }
    if (i + 1u < n) {
        let e = i;
        for (var k = 0u; k < 6u; k = k + 1u) {
            r[k] = r[k] + elem_force[(12u * e + k) * nv + v];
            for (var c = 0u; c < 6u; c = c + 1u) {
                d[6u * k + c] = d[6u * k + c] + elem_tangent[(144u * e + 12u * k + c) * nv + v];
                out_upper[(36u * i + 6u * k + c) * nv + v] = elem_tangent[(144u * e + 12u * k + 6u + c) * nv + v];
                out_lower[(36u * i + 6u * k + c) * nv + v] = elem_tangent[(144u * e + 12u * (6u + k) + c) * nv + v];
            }
        }
    }
    let s = node_site[i * nv + v];
    if (s != NO_SITE) {
        let p = s * nv + v;
        if (contact_flag[p] != 0u) {
            for (var k = 0u; k < 6u; k = k + 1u) {
                r[k] = r[k] + contact[(OUT_G + k) * pairs + p];
                for (var c = 0u; c < 3u; c = c + 1u) {
                    d[6u * k + c] = d[6u * k + c] + contact[(OUT_K + 3u * k + c) * pairs + p];
                }
            }
        }
    }
    for (var k = 0u; k < 6u; k = k + 1u) {
        out_rhs[(6u * i + k) * nv + v] = r[k];
    }
    for (var k = 0u; k < 36u; k = k + 1u) {
        out_diag[(36u * i + k) * nv + v] = d[k];
    }
}
