// Twin: src/kernels/update.rs (Newton update of every variant's configuration, norms).
//
// `update`: one invocation per (node, variant), index = node · V + variant:
// x += α B Δu, R ← exp([α Δθ]×) R with the series exponential of the twin.
// `norms`: one invocation per variant: largest |r| and largest |α Δ|, Δ · r and r · r.
#include "shared/layout.wgsl"
#include "shared/listed.wgsl"

// Composed twice: without NORMS the entry point `main` is the update, with NORMS the norms.
@group(0) @binding(0) var<storage, read> dims: ChainDims;
@group(0) @binding(1) var<storage, read> delta: array<real>;
@group(0) @binding(2) var<storage, read> alpha: array<real>;
#if NORMS
@group(0) @binding(3) var<storage, read> residual: array<real>;
// Per variant: largest |r|, largest |α Δ|, Δ · r, r · r.
@group(0) @binding(4) var<storage, read_write> norm_out: array<real>;
#if MASKED
// Built MASKED (the engine's trials): the variants still searching, compacted:
// [A, v_0, …, v_{A−1}]; the others are skipped.
@group(0) @binding(5) var<storage, read> searching: array<u32>;
#endif
#else
@group(0) @binding(3) var<storage, read> basis: array<real>;
// Site at each (node, variant), NO_SITE where none; per pair (site · V + variant) the base
// across the hole axis (3), the hole axis (3) and the law parameters (field-major,
// clearance first): a contact node near its wall steps along it.
@group(0) @binding(4) var<storage, read> node_site: array<u32>;
@group(0) @binding(5) var<storage, read> pair_base: array<real>;
@group(0) @binding(6) var<storage, read> pair_normals: array<real>;
@group(0) @binding(7) var<storage, read> pair_params: array<real>;
#if OUT_OF_PLACE
// Built OUT_OF_PLACE (the engine's trials): the configuration moved from is read here and
// the result written to x, rot (the trial's slot); without, x and rot are updated in place.
@group(0) @binding(8) var<storage, read> x_from: array<real>;
@group(0) @binding(9) var<storage, read> rot_from: array<real>;
@group(0) @binding(10) var<storage, read_write> x: array<real>;
@group(0) @binding(11) var<storage, read_write> rot: array<real>;
// Per (node, variant) the landing epoch in which the node last landed on its wall, moved
// from and to; per variant the current epoch (twin: ConfigBatch::landed, UpdateWalls::epoch).
@group(0) @binding(12) var<storage, read> landed_from: array<u32>;
@group(0) @binding(13) var<storage, read_write> landed: array<u32>;
@group(0) @binding(14) var<storage, read> epoch: array<u32>;
#if MASKED
// Built MASKED: the variants to move, compacted: [A, v_0, …, v_{A−1}]; the others' trial
// configurations are left as they were.
@group(0) @binding(15) var<storage, read> searching: array<u32>;
#endif

fn x_at(k: u32) -> real {
    return x_from[k];
}

fn rot_at(k: u32) -> real {
    return rot_from[k];
}

fn landed_at(k: u32) -> u32 {
    return landed_from[k];
}
#else
@group(0) @binding(8) var<storage, read_write> x: array<real>;
@group(0) @binding(9) var<storage, read_write> rot: array<real>;
@group(0) @binding(10) var<storage, read_write> landed: array<u32>;
@group(0) @binding(11) var<storage, read> epoch: array<u32>;

fn x_at(k: u32) -> real {
    return x[k];
}

fn rot_at(k: u32) -> real {
    return rot[k];
}

fn landed_at(k: u32) -> u32 {
    return landed[k];
}
#endif
#endif

#if !NORMS
#include "shared/rotation_exp.wgsl"

const NO_SITE: u32 = 0xffffffffu;
// physics::contact::LANDING_DEPTH (as a fraction of the clearance).
const LANDING_DEPTH = 1e-6;

// Twin: physics::contact::wall_following_step. The step `du` of a node at offset `d` from
// its hole axis point (axis `t`), its lateral part split into radial and circumferential
// parts and put back on the circle of the new radius.
fn wall_following_step(d: vec3<real>, t: vec3<real>, du: vec3<real>, min_radius: real) -> vec3<real> {
    let along = dot(d, t);
    let d_perp = d - along * t;
    let r = sqrt(dot(d_perp, d_perp));
    if (r < min_radius || r == real(0.0)) {
        return du;
    }
    let e_r = d_perp / r;
    let e_t = cross(t, e_r);
    let dr = dot(du, e_r);
    let ds = dot(du, e_t);
    let da = dot(du, t);
    let phi = ds / r;
    let scale = (r + dr) / (r * sqrt(real(1.0) + phi * phi));
    return da * t + scale * (d_perp + ds * e_t) - d_perp;
}

// Twin: physics::contact::landing_step. A step of a node off its wall (offset `d`, axis
// `t`) that would end inside it, its lateral part shortened to land the node LANDING_DEPTH
// of its clearance inside; `du` itself otherwise.
fn landing_step(d: vec3<real>, t: vec3<real>, du: vec3<real>, clearance: real) -> vec3<real> {
    let d0 = d - dot(d, t) * t;
    if (sqrt(dot(d0, d0)) > clearance) {
        return du;
    }
    return within_radius(d, t, du, clearance * (real(1.0) + real(LANDING_DEPTH)));
}

// Twin: physics::contact::within_radius. The step `du` of a node at offset `d` (axis `t`),
// its lateral part shortened to end `limit` from the axis where it would end farther.
fn within_radius(d: vec3<real>, t: vec3<real>, du: vec3<real>, limit: real) -> vec3<real> {
    let e = d + du;
    let d1 = e - dot(e, t) * t;
    let r1 = sqrt(dot(d1, d1));
    if (!(r1 > limit)) {
        return du;
    }
    let s = limit / r1;
    return s * d1 + (e - d1) - d;
}

// physics::contact::DEEPENING_FACTOR.
const DEEPENING_FACTOR = 4.0;

// Twin: physics::contact::deepening_step (soft laws, every precision: physics::contact::deepens).
// A step of a node that would take its depth from δ₀ beyond max(DEEPENING_FACTOR δ₀,
// LANDING_DEPTH · clearance), its lateral part shortened to end there; `du` otherwise.
fn deepening_step(d: vec3<real>, t: vec3<real>, du: vec3<real>, clearance: real) -> vec3<real> {
    let floor = clearance * real(LANDING_DEPTH);
    let d0 = d - dot(d, t) * t;
    let depth0 = sqrt(dot(d0, d0)) - clearance;
    let deeper = real(DEEPENING_FACTOR) * depth0;
    var cap = floor;
    if (deeper > floor) {
        cap = deeper;
    }
    return within_radius(d, t, du, clearance + cap);
}

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
    let al = alpha[v];
    let du = vec3<real>(
        al * delta[(6u * i) * nv + v],
        al * delta[(6u * i + 1u) * nv + v],
        al * delta[(6u * i + 2u) * nv + v],
    );
    var step = vec3<real>(real(0.0), real(0.0), real(0.0));
    for (var r = 0u; r < 3u; r = r + 1u) {
        let brow = vec3<real>(basis[9u * i + 3u * r], basis[9u * i + 3u * r + 1u], basis[9u * i + 3u * r + 2u]);
        step[r] = dot(brow, du);
    }
    let x_old = vec3<real>(x_at((3u * i) * nv + v), x_at((3u * i + 1u) * nv + v), x_at((3u * i + 2u) * nv + v));
    var mark = landed_at(i * nv + v);
    let site = node_site[i * nv + v];
    if (site != NO_SITE) {
        let pair = site * nv + v;
        let d = vec3<real>(pair_base[3u * pair], pair_base[3u * pair + 1u], pair_base[3u * pair + 2u]) + x_old;
        let t = vec3<real>(pair_normals[3u * pair], pair_normals[3u * pair + 1u], pair_normals[3u * pair + 2u]);
        // physics::contact::wall_following_radius: half the clearance.
        step = wall_following_step(d, t, step, real(0.5) * pair_params[pair]);
        // Once an epoch (none in epoch 0), a node off its wall whose step ends inside it
        // lands on it.
        if (epoch[v] != 0u && mark != epoch[v]) {
            let l = landing_step(d, t, step, pair_params[pair]);
            if (any(l != step)) {
                step = l;
                mark = epoch[v];
            }
        }
        // A soft-law node (spring exponent, field 3 of the pair's parameters, below 1)
        // goes no deeper than its bound.
        let pairs = arrayLength(&pair_normals) / 3u;
        if (pair_params[3u * pairs + pair] < real(1.0)) {
            step = deepening_step(d, t, step, pair_params[pair]);
        }
    }
    landed[i * nv + v] = mark;
    for (var r = 0u; r < 3u; r = r + 1u) {
        x[(3u * i + r) * nv + v] = x_old[r] + step[r];
    }
    let e = rotation_exp(vec3<real>(
        al * delta[(6u * i + 3u) * nv + v],
        al * delta[(6u * i + 4u) * nv + v],
        al * delta[(6u * i + 5u) * nv + v],
    ));
    var old: array<real, 9>;
    for (var k = 0u; k < 9u; k = k + 1u) {
        old[k] = rot_at((9u * i + k) * nv + v);
    }
    for (var r = 0u; r < 3u; r = r + 1u) {
        for (var c = 0u; c < 3u; c = c + 1u) {
            var s = real(0.0);
            for (var m = 0u; m < 3u; m = m + 1u) {
                // e[m][r] is row r, column m of the exponential (WGSL matrices are column-major).
                s = s + e[m][r] * old[3u * m + c];
            }
            rot[(9u * i + 3u * r + c) * nv + v] = s;
        }
    }
}

#endif
#if NORMS
#include "shared/finite.wgsl"

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    let at = item_of(gid.x, 1u, nv);
    if (at.x >= 1u) {
        return;
    }
    let v = at.y;
    var r = real(0.0);
    var d = real(0.0);
    var dot_dr = real(0.0);
    var square = real(0.0);
    for (var k = 0u; k < 6u * dims.num_nodes; k = k + 1u) {
        let rk = residual[k * nv + v];
        let dk = delta[k * nv + v];
        let ra = abs(rk);
        let da = abs(alpha[v] * dk);
        if (ra > r || is_nan_or_inf(ra)) {
            r = ra;
        }
        if (da > d || is_nan_or_inf(da)) {
            d = da;
        }
        dot_dr = dot_dr + dk * rk;
        square = square + rk * rk;
    }
    norm_out[4u * v] = r;
    norm_out[4u * v + 1u] = d;
    norm_out[4u * v + 2u] = dot_dr;
    norm_out[4u * v + 3u] = square;
}
#endif
