// Twin: src/kernels/sites.rs (each contact pair's displacement d = b + w of its node).
//
// One invocation per (site, variant) pair i = site · V + variant; writes fields 0–2 of the
// pair state, d = b + w (the base's displacement from the reference across the hole axis —
// the contact uses no other part of d — plus the state's from the base), leaving the
// velocity and spin fields (3–6) as the host wrote them; with DYNAMIC also those, from the
// node's velocity and its spin about the hole axis.
#include "shared/layout.wgsl"
#include "shared/listed.wgsl"

@group(0) @binding(0) var<storage, read> dims: ContactDims;
// Node of each pair.
@group(0) @binding(1) var<storage, read> pair_node: array<u32>;
// Displacements from the base, w: [(3 · node + k) · V + variant]; the base's from the
// reference at each pair, across its hole axis (formed in double precision on the host),
// b: [3 i + k].
@group(0) @binding(2) var<storage, read> u: array<real>;
@group(0) @binding(3) var<storage, read> pair_base: array<real>;
@group(0) @binding(4) var<storage, read_write> pair_state: array<real>;
#if DYNAMIC
// Node velocities [(6 · node + k) · V + variant] (ẋ, ω) and the pairs' hole axes.
@group(0) @binding(5) var<storage, read> vel: array<real>;
@group(0) @binding(6) var<storage, read> pair_normals: array<real>;
#if MASKED
// Built MASKED (the engine's line-search trials, static or dynamic): the variants still
// searching, compacted: [A, v_0, …, v_{A−1}]; one invocation per (site, searching variant).
@group(0) @binding(7) var<storage, read> searching: array<u32>;
#endif
#else
#if MASKED
@group(0) @binding(5) var<storage, read> searching: array<u32>;
#endif
#endif

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = dims.num_pairs;
    let nv = dims.num_variants;
    let at = item_of(gid.x, p / nv, nv);
    if (at.x >= p / nv) {
        return;
    }
    let v = at.y;
    let i = at.x * nv + v;
    let node = pair_node[i];
    for (var k = 0u; k < 3u; k = k + 1u) {
        pair_state[k * p + i] = pair_base[3u * i + k] + u[(3u * node + k) * nv + v];
    }
#if DYNAMIC
    // Velocity and spin about the hole axis, n · ω.
    var spin = real(0.0);
    for (var k = 0u; k < 3u; k = k + 1u) {
        pair_state[(3u + k) * p + i] = vel[(6u * node + k) * nv + v];
        spin = spin + pair_normals[3u * i + k] * vel[(6u * node + 3u + k) * nv + v];
    }
    pair_state[6u * p + i] = spin;
#endif
}
