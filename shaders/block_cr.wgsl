// Twin: src/kernels/block_cr.rs (block cyclic reduction of every variant's Newton system).
//
// The block solve in the cyclic form (src/gpu/block_lu.rs `LuForm::Cyclic`): one invocation
// per (node, variant), variant fastest, so every access is coalesced across variants. The
// chain walk of shaders/block_lu.wgsl takes n dependent node steps; here the levels
// s = 1, 2, 4, … (dims.begin) each take one dispatch whose nodes are independent:
//
//   phase 2 (level 1's odd nodes): each factored (P, Q, r) into the workspace; a chain of
//            one node solved at once.
//   phase 3 (level s, the multiples of 2s): the even update by both odd neighbours, then
//            the node factored if odd at level 2s, or solved if node 0 is alone. At s = 1
//            the node and its couplings are read from the inputs (nothing was copied).
//   phase 4 (level s, coarsest first, the odd nodes of the level): back substitution
//            x_j = r_j − P_j x_{j−s} − Q_j x_{j+s}; the last (s = 1, node 1) marks the
//            variant solved.
//
// dims.end is the number of nodes of this dispatch (invocation gid.x = k V + v, node from k).
// The 6 × 6 blocks, the coupling being applied and the right-hand side are scalars with
// constant names (written out by src/gpu/block_cr.rs), so no private array is indexed at run
// time. The operations and their order are the twin's.
//
// status: 2 running (set by the host), 1 singular (a zero or non-finite pivot: the variant's
// solution is zero), 0 solved.
//
// Layout (variant fastest; V = variants in this dispatch): input block entry rc of node i at
// [(36 i + rc) V + v]; workspace D, WL, WU (field f = 0, 1, 2) of node i at
// [(36 (f n + i) + rc) V + v] in work_x; y (then r) of node i at [(6 i + r) V + v] in work_z.
#include "shared/layout.wgsl"

#include "shared/chain_solve.wgsl"

fn wk(f: u32, i: u32, rc: u32, v: u32) -> u32 {
    return (36u * (f * dims.num_nodes + i) + rc) * dims.num_variants + v;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let n = dims.num_nodes;
    let v = gid.x % nv;
    let k = gid.x / nv;
    if (k >= dims.end) {
        return;
    }
    let s = dims.begin;
    let phase = dims.phase;
    if (phase == 4u) {
        let j = s + 2u * s * k;
        let right = j + s < n;
        if (status[v] == 1u) {
            for (var r = 0u; r < 6u; r = r + 1u) {
                x[vec_at(j, r, v)] = real(0.0);
            }
            return;
        }
        //@BACK
        if (s == 1u && j == 1u) {
            status[v] = 0u;
        }
        return;
    }
    var i = 2u * s * k;
    if (phase == 2u) {
        i = select(2u * k + 1u, 0u, n == 1u);
    }
    let from_inputs = phase == 2u || s == 1u;
    //@LOAD
    if (phase == 3u) {
        //@UPDATE
    }
    // Factored now: odd at the next level (has a left coupling), or node 0 alone (solved).
    var factor_it = false;
    var alone = false;
    var has_right = false;
    if (phase == 2u) {
        factor_it = n > 1u;
        alone = n == 1u;
        has_right = i + 1u < n;
    } else {
        factor_it = i % (4u * s) == 2u * s;
        alone = i == 0u && 2u * s >= n;
        has_right = i + 2u * s < n;
    }
    if (!factor_it && !alone) {
        //@STORE
        return;
    }
    //@FACTOR
    if (bad) {
        status[v] = 1u;
    }
    let singular = status[v] == 1u;
    if (alone && singular) {
        for (var r = 0u; r < 6u; r = r + 1u) {
            x[vec_at(0u, r, v)] = real(0.0);
        }
        return;
    }
    if (bad) {
        return;
    }
    // The columns of WL, WU (where coupled) and y, each solved with the factor.
    for (var col = 0u; col < 13u; col = col + 1u) {
        if (col < 12u && alone) {
            continue;
        }
        if (col >= 6u && col < 12u && !has_right) {
            continue;
        }
        //@SOLVE
    }
    if (alone && n == 1u) {
        status[v] = 0u;
    }
}
