// Twin: src/kernels/block_lu.rs (block-tridiagonal LU of every variant's Newton system).
//
// Two forms (src/gpu/block_lu.rs picks by adapter: `lanes`).
//
// SERIAL (CPU-type adapters: lavapipe): one invocation per variant walks the chain,
// eliminating the augmented block [G_i | U_i | y_i] (6 × 13) with partial pivoting in
// private memory. lavapipe runs a workgroup's invocations as SIMD lanes of one core, so
// variants are its parallelism, and a workgroup barrier costs it more than the work it
// splits (measured: the lane form below takes 2× the time there).
//
// Otherwise (GPUs): eight lanes per variant (eight variants per workgroup of 64), lane r < 6 holding row r of
// the augmented block [G_i | U_i | y_i] (6 × 13) as the chain is walked: the Schur
// complement G_i = D_i − L_{i−1} X_{i−1} row by row, then Gauss–Jordan with partial pivoting
// with the pivot column and the pivot row passed through workgroup memory (the rows stay in
// their lanes; a permutation, the same in every lane, records the twin's row swaps, so the
// pivots and operations are the twin's). X_i = G_i⁻¹U_i and z_i = G_i⁻¹y_i are kept in the
// workspace (and X_i, z_i in workgroup memory for the next node); back substitution
// x_i = z_i − X_i x_{i+1}, a row per lane. The walk over the chain stays sequential (its
// length is the latency), the work per node is spread over six lanes, and a chunk of V
// variants occupies 8 V invocations — 4096 variants fill 512 workgroups, not 64.
//
// The walk is split into dispatches of at most 32 nodes (dims.begin … dims.end, forward
// then backward): llvmpipe (lavapipe) silently ends any loop after 65,535 iterations,
// which a whole chain of more than about 110 nodes exceeds. status starts at 2 (set by the
// host): 1 singular, 0 solved (set by the last backward dispatch), 2 left means a
// dispatch did not complete. Barriers sit in loops whose bounds are the same for the whole
// workgroup; lanes without work (rows 6, 7, variants past the end, singular variants)
// only skip the arithmetic.
// Layout (field-major, variant fastest; V = variants in this dispatch): block entry rc of
// node i at [(36 i + rc) V + v], vector entry r of node i at [(6 i + r) V + v].
#include "shared/layout.wgsl"

#include "shared/chain_solve.wgsl"

#if SERIAL
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let v = gid.x;
    if (v >= dims.num_variants || status[v] == 1u) {
        return;
    }
    let n = dims.num_nodes;
    if (dims.phase == 1u) {
        // Back substitution over [begin, end), downwards: x_i = z_i − X_i x_{i+1}, with
        // x_{i+1} carried in registers from node to node (read once, where the dispatch
        // starts below the chain's end), not read back from memory 36 times a node.
        var below = array<real, 6>();
        if (dims.end < n) {
            for (var c = 0u; c < 6u; c = c + 1u) {
                below[c] = x[vec_at(dims.end, c, v)];
            }
        }
        for (var step = dims.begin; step < dims.end; step = step + 1u) {
            let i = dims.end - 1u - (step - dims.begin);
            var here = array<real, 6>();
            for (var r = 0u; r < 6u; r = r + 1u) {
                var s = work_z[vec_at(i, r, v)];
                if (i + 1u < n) {
                    for (var c = 0u; c < 6u; c = c + 1u) {
                        s = s - work_x[blk(i, 6u * r + c, v)] * below[c];
                    }
                }
                here[r] = s;
                x[vec_at(i, r, v)] = s;
            }
            below = here;
        }
        if (dims.begin == 0u) {
            status[v] = 0u;
        }
        return;
    }
    // The forward walk, written out by src/gpu/block_lu.rs (`serial_forward`): the 6 × 13
    // block, X_{i−1} and z_{i−1} as scalars with constant names, so no private array is
    // indexed at run time (they stay in registers).
    //@FORWARD
}
#else
// Lanes per variant (src/gpu/block_lu.rs LANES) and variants per workgroup.
const LANES: u32 = 8u;
const SLOTS: u32 = 8u;

// Per variant of the workgroup: X and z of the previous node, the pivot row, the pivot
// column, and x_{i+1} during the back substitution.
var<workgroup> px: array<real, 288>;
var<workgroup> pz: array<real, 48>;
var<workgroup> prow: array<real, 104>;
var<workgroup> pcol: array<real, 48>;
var<workgroup> xs: array<real, 48>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let v = gid.x / LANES;
    let r = lid.x % LANES;
    let slot = lid.x / LANES;
    let n = dims.num_nodes;
    // This lane has a row of a variant still being solved.
    var live = v < dims.num_variants && r < 6u;
    if (live) {
        live = status[v] != 1u;
    }
    if (dims.phase == 1u) {
        // Back substitution over [begin, end), downwards: x_i = z_i − X_i x_{i+1}.
        if (live && dims.end < n) {
            xs[6u * slot + r] = x[vec_at(dims.end, r, v)];
        }
        workgroupBarrier();
        for (var step = dims.begin; step < dims.end; step = step + 1u) {
            let i = dims.end - 1u - (step - dims.begin);
            var s = real(0.0);
            if (live) {
                s = work_z[vec_at(i, r, v)];
                if (i + 1u < n) {
                    for (var c = 0u; c < 6u; c = c + 1u) {
                        s = s - work_x[blk(i, 6u * r + c, v)] * xs[6u * slot + c];
                    }
                }
            }
            workgroupBarrier();
            if (live) {
                xs[6u * slot + r] = s;
                x[vec_at(i, r, v)] = s;
            }
            workgroupBarrier();
        }
        if (live && r == 0u && dims.begin == 0u) {
            status[v] = 0u;
        }
        return;
    }
    if (live && dims.begin > 0u) {
        for (var k = 0u; k < 6u; k = k + 1u) {
            px[36u * slot + 6u * r + k] = work_x[blk(dims.begin - 1u, 6u * r + k, v)];
        }
        pz[6u * slot + r] = work_z[vec_at(dims.begin - 1u, r, v)];
    }
    workgroupBarrier();
    // The forward walk, written out by src/gpu/block_lu.rs (`lanes_forward`): this lane's
    // row of the 6 × 13 block and the permutation as scalars with constant names, every loop
    // over columns unrolled, so no private array is indexed at run time (registers).
    //@LANES_FORWARD
}
#endif
