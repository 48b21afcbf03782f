// The bindings and helpers of the block solve, shared by its forms: the chain walk
// (block_lu.wgsl) and cyclic reduction (block_cr.wgsl). Layout (field-major, variant
// fastest; V = variants in this dispatch): block entry rc of node i at [(36 i + rc) V + v],
// vector entry r of node i at [(6 i + r) V + v].
@group(0) @binding(0) var<storage, read> dims: LuDims;
@group(0) @binding(1) var<storage, read> diag: array<real>;
@group(0) @binding(2) var<storage, read> upper: array<real>;
@group(0) @binding(3) var<storage, read> lower: array<real>;
@group(0) @binding(4) var<storage, read> rhs: array<real>;
// The form's workspace: the walk's X_i (36 per link) and z_i (6 per node); the reduction's
// D, WL, WU (36 per node each) and y (6 per node).
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
