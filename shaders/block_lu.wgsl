// Twin: src/kernels/block_lu.rs (block-tridiagonal LU of every variant's Newton system).
//
// One invocation per variant; it walks the chain: eliminates the augmented block
// [G_i | U_i | y_i] (6 × 13, partial pivoting inside the block), keeps X_i = G_i⁻¹U_i and
// z_i = G_i⁻¹y_i in the workspace, then substitutes back. The walk is split into dispatches
// of at most 32 nodes (dims.begin … dims.end, forward then backward): llvmpipe (lavapipe)
// silently ends any loop after 65,535 iterations, which a whole chain of more than about
// 110 nodes exceeds. status starts at 2 (set by the host): 1 singular, 0 solved (set by
// the last backward dispatch), 2 left means a dispatch did not complete.
// Layout (field-major, variant fastest; V = variants in this dispatch): block entry rc of
// node i at [(36 i + rc) V + v], vector entry r of node i at [(6 i + r) V + v].
#include "shared/layout.wgsl"

@group(0) @binding(0) var<storage, read> dims: LuDims;
@group(0) @binding(1) var<storage, read> diag: array<real>;
@group(0) @binding(2) var<storage, read> upper: array<real>;
@group(0) @binding(3) var<storage, read> lower: array<real>;
@group(0) @binding(4) var<storage, read> rhs: array<real>;
// X_i (36 per link) and z_i (6 per node): the factor, kept for the back substitution.
@group(0) @binding(5) var<storage, read_write> work_x: array<real>;
@group(0) @binding(6) var<storage, read_write> work_z: array<real>;
// Solution, 6 per node.
@group(0) @binding(7) var<storage, read_write> x: array<real>;
// 2 running (host), 1 singular (a zero or non-finite pivot), 0 solved.
@group(0) @binding(8) var<storage, read_write> status: array<u32>;

fn blk(i: u32, rc: u32, v: u32) -> u32 {
    return (36u * i + rc) * dims.num_variants + v;
}

fn vec_at(i: u32, r: u32, v: u32) -> u32 {
    return (6u * i + r) * dims.num_variants + v;
}

// Zero, infinite or NaN. Bit tests, not comparisons: WGSL implementations may assume no
// NaNs and fold `p != p` away (lavapipe does).
fn bad_pivot(p: real) -> bool {
#if F64
    // No f64 bitcast in WGSL: test the f32 image (NaN and ±∞ map to themselves; a pivot
    // beyond 3.4e38 in magnitude also counts as bad).
    return (bitcast<u32>(f32(p)) & 0x7f800000u) == 0x7f800000u || p == real(0.0);
#else
    return (bitcast<u32>(p) & 0x7f800000u) == 0x7f800000u || p == real(0.0);
#endif
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let v = gid.x;
    if (v >= dims.num_variants || status[v] == 1u) {
        return;
    }
    let n = dims.num_nodes;
    if (dims.phase == 1u) {
        // Back substitution over [begin, end), downwards: x_i = z_i − X_i x_{i+1}.
        for (var step = dims.begin; step < dims.end; step = step + 1u) {
            let i = dims.end - 1u - (step - dims.begin);
            for (var r = 0u; r < 6u; r = r + 1u) {
                var s = work_z[vec_at(i, r, v)];
                if (i + 1u < n) {
                    for (var c = 0u; c < 6u; c = c + 1u) {
                        s = s - work_x[blk(i, 6u * r + c, v)] * x[vec_at(i + 1u, c, v)];
                    }
                }
                x[vec_at(i, r, v)] = s;
            }
        }
        if (dims.begin == 0u) {
            status[v] = 0u;
        }
        return;
    }
    var aug: array<real, 78>; // 6 rows × 13 columns, row-major
    var prev_x: array<real, 36>;
    var prev_z: array<real, 6>;
    if (dims.begin > 0u) {
        for (var k = 0u; k < 36u; k = k + 1u) {
            prev_x[k] = work_x[blk(dims.begin - 1u, k, v)];
        }
        for (var k = 0u; k < 6u; k = k + 1u) {
            prev_z[k] = work_z[vec_at(dims.begin - 1u, k, v)];
        }
    }
    for (var i = dims.begin; i < dims.end; i = i + 1u) {
        for (var r = 0u; r < 6u; r = r + 1u) {
            for (var c = 0u; c < 6u; c = c + 1u) {
                aug[13u * r + c] = diag[blk(i, 6u * r + c, v)];
                if (i + 1u < n) {
                    aug[13u * r + 6u + c] = upper[blk(i, 6u * r + c, v)];
                } else {
                    aug[13u * r + 6u + c] = real(0.0);
                }
            }
            aug[13u * r + 12u] = rhs[vec_at(i, r, v)];
            if (i > 0u) {
                for (var k = 0u; k < 6u; k = k + 1u) {
                    let l = lower[blk(i - 1u, 6u * r + k, v)];
                    for (var c = 0u; c < 6u; c = c + 1u) {
                        aug[13u * r + c] = aug[13u * r + c] - l * prev_x[6u * k + c];
                    }
                    aug[13u * r + 12u] = aug[13u * r + 12u] - l * prev_z[k];
                }
            }
        }
        // Gauss–Jordan with partial pivoting on the 6 × 13 block.
        for (var col = 0u; col < 6u; col = col + 1u) {
            var p = col;
            for (var r = col + 1u; r < 6u; r = r + 1u) {
                if (abs(aug[13u * r + col]) > abs(aug[13u * p + col])) {
                    p = r;
                }
            }
            if (p != col) {
                for (var c = 0u; c < 13u; c = c + 1u) {
                    let t = aug[13u * col + c];
                    aug[13u * col + c] = aug[13u * p + c];
                    aug[13u * p + c] = t;
                }
            }
            let pivot = aug[13u * col + col];
            if (bad_pivot(pivot)) {
                status[v] = 1u;
                for (var k = 0u; k < 6u * n; k = k + 1u) {
                    x[k * dims.num_variants + v] = real(0.0);
                }
                return;
            }
            let inv = real(1.0) / pivot;
            for (var c = col; c < 13u; c = c + 1u) {
                aug[13u * col + c] = aug[13u * col + c] * inv;
            }
            for (var r = 0u; r < 6u; r = r + 1u) {
                if (r != col) {
                    let f = aug[13u * r + col];
                    for (var c = col; c < 13u; c = c + 1u) {
                        aug[13u * r + c] = aug[13u * r + c] - f * aug[13u * col + c];
                    }
                }
            }
        }
        for (var r = 0u; r < 6u; r = r + 1u) {
            for (var c = 0u; c < 6u; c = c + 1u) {
                prev_x[6u * r + c] = aug[13u * r + 6u + c];
                work_x[blk(i, 6u * r + c, v)] = aug[13u * r + 6u + c];
            }
            prev_z[r] = aug[13u * r + 12u];
            work_z[vec_at(i, r, v)] = aug[13u * r + 12u];
        }
    }
}
