// Twin: src/kernels/beam.rs (formulas: src/physics/beam.rs, `element_values` and
// src/physics/beam_tangent.rs, `force_and_tangent_variation`: the co-rotational element in
// closed form and its consistent tangent written out).
//
// One invocation per (element, variant), index = element · V + variant. The internal force
// is the closed form of physics::beam::element_force (frame: chord and the mean of the
// nodal triads' second axes; local moments through J⁻ᵀ of the rotation logs, the frame's
// spin through η and n):
//   f_x₂ = −f_x₁ = N e1 + ((η V₁ + V₂) e3 − V₃ e2)/l,  f_θᵢ = R_r v̄_i − V₁/(2n)·(b_i × e3).
// Its values are formed once (`Values`, the twin's ElementValues). The consistent tangent
// K_jk = ∂f_j/∂Δ_k is the first variation of each of those values along a direction — a
// DOF moved as a translation or a left spin (I + [ε e]×)·triad — one direction at a time
// (`variation`): nine directions give the twelve columns (node 1's translation columns are
// node 2's negated). The rotation logs' transcendentals are not differentiated: a log
// responds to a spin as δθ̄_i = J⁻¹(θ̄_i) R_rᵀ(δθ_i − δω), δω the frame's spin, and the
// coefficient c of J⁻¹ changes with θ² by dc/dθ² = (¼ − 3c + c²θ²)/(2θ²) (its series below
// θ² = 0.1). Built with FORCE_ONLY it evaluates the force alone (line-search trials: no
// tangent written). Outputs in the assembly's layout: [(12 e + j) V + v] and the tangent's
// 81 independent entries [(81 e + 9 r + d) V + v] (kernels::beam::TANGENT_LEN): rows
// j = r + 3 (θ₁, x₂, θ₂) along the nine directions d; rows 0–2 and columns 0–2 are those
// negated, which the assembly forms (tangent_at).
//
// States are displacements w from each variant's base configuration X + b (kilometres of
// string lose their millimetres in f32 otherwise; the dynamic engine's base is the static
// equilibrium, the f32 static engine's the last load step's, so w is the motion): the
// chord is c + (w₂ − w₁), with the base chord c = (X₂ + b₂) − (X₁ + b₁) and its stretch
// s = |c| − l0 given per element and variant (formed in double precision on the host). In
// double precision the element's node positions are taken as w₁ and c + w₂ (as the twin,
// physics::beam::Chord::Positions) and the elongation as l − l0; in single precision
// (Chord::Base) the elongation is s + (2 c·Δw + Δw·Δw)/(l + |c|), without the cancellation
// of l − l0 (a strain of 1e-5 would keep two digits) and without the metres the base has
// moved. Both forms have ∂ū/∂d = e1, which the translations' variation uses.
//
// Built with KINK the moments act on the rotations from each element's unstrained ones
// (a bent sub: physics::beam::ElementStiffness::rest), read per (element, variant).
#include "shared/layout.wgsl"
#include "shared/listed.wgsl"

@group(0) @binding(0) var<storage, read> dims: BeamDims;
// Node displacements, [(3 i + k) V + v]; rotations, [(9 i + 3 r + c) V + v].
@group(0) @binding(1) var<storage, read> x: array<real>;
@group(0) @binding(2) var<storage, read> rot: array<real>;
// Reference triad per node (row-major, 9 each), shared by the variants.
@group(0) @binding(3) var<storage, read> frame0: array<real>;
// Per element: EA/l0, GJ/l0, EI/l0, l0.
@group(0) @binding(4) var<storage, read> section: array<real>;
// Base chord and stretch per element and variant: [(4 e + k) V + v], k = 0–2 the chord,
// 3 the stretch |c| − l0.
@group(0) @binding(5) var<storage, read> chord: array<real>;
#if KINK
// Unstrained rotations per element and variant (a bent sub's kink; zero elsewhere):
// [(6 e + k) V + v], k = 0–2 θ̄⁰₁, 3–5 θ̄⁰₂ (kernels::beam::rest_table). Built only for a
// scene with a kink.
@group(0) @binding(6) var<storage, read> rest: array<real>;
@group(0) @binding(7) var<storage, read_write> elem_force: array<real>;
#if !FORCE_ONLY
@group(0) @binding(8) var<storage, read_write> elem_tangent: array<real>;
#if MASKED
// The variants still iterating, compacted: [A, v_0, …, v_{A−1}].
@group(0) @binding(9) var<storage, read> searching: array<u32>;
#endif
#else
#if MASKED
// The variants still searching, compacted: [A, v_0, …, v_{A−1}].
@group(0) @binding(8) var<storage, read> searching: array<u32>;
#endif
#endif
#else
@group(0) @binding(6) var<storage, read_write> elem_force: array<real>;
#if !FORCE_ONLY
@group(0) @binding(7) var<storage, read_write> elem_tangent: array<real>;
#if MASKED
// The variants still iterating, compacted: [A, v_0, …, v_{A−1}].
@group(0) @binding(8) var<storage, read> searching: array<u32>;
#endif
#else
#if MASKED
// The variants still searching, compacted: [A, v_0, …, v_{A−1}].
@group(0) @binding(7) var<storage, read> searching: array<u32>;
#endif
#endif
#endif

fn cr(a: vec3<real>, b: vec3<real>) -> vec3<real> {
    return a.yzx * b.zxy - a.zxy * b.yzx;
}

fn dt(a: vec3<real>, b: vec3<real>) -> real {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

#include "shared/rotation_log.wgsl"

// A nodal triad by its columns (the element's initial axes carried by the node).
struct Triad {
    c0: vec3<real>,
    c1: vec3<real>,
    c2: vec3<real>,
}

// The rotation vector of Rrᵀ·t (Rr = [e1 e2 e3]) and the coefficient c(θ) of J⁻¹(θ),
// as physics::rotation::rotation_log_and_jacobian.
struct LogJ {
    th: vec3<real>,
    c: real,
}

fn rel_log(e1: vec3<real>, e2: vec3<real>, e3: vec3<real>, t: Triad) -> LogJ {
    let half = real(0.5);
    // r[a][b] = e_a · t_b.
    let w = half * vec3<real>(dt(e3, t.c1) - dt(e2, t.c2), dt(e1, t.c2) - dt(e3, t.c0),
                              dt(e2, t.c0) - dt(e1, t.c1));
    let s2 = dt(w, w);
    let c = half * (dt(e1, t.c0) + dt(e2, t.c1) + dt(e3, t.c2) - real(1.0));
    // θ / sin θ and sin θ (0 where the series is taken), shared with the assembly's log.
    let fs = log_factor(s2, c);
    let factor = fs.x;
    let s = fs.y;
    let series = s2 < real(1e-6) && c > real(0.0);
    let theta2 = factor * factor * s2;
    var coefficient: real;
    if (!series && theta2 >= real(0.1)) {
        let theta = factor * s;
        coefficient = (real(1.0) - theta * (real(1.0) + c) / (s + s)) / theta2;
    } else {
        coefficient = real(1.0) / real(12.0) + theta2 * (real(1.0) / real(720.0)
            + theta2 * (real(1.0) / real(30240.0) + theta2 * (real(1.0) / real(1209600.0)
            + theta2 * (real(1.0) / real(47900160.0)))));
    }
    return LogJ(w * factor, coefficient);
}

// dc/d(θ²) of J⁻¹'s coefficient, from c itself (physics::beam::tangent::
// jacobian_coefficient_slope): (¼ − 3c + c²θ²)/(2θ²); below θ² = 0.1 the series'.
fn coefficient_slope(theta2: real, c: real) -> real {
    if (theta2 < real(0.1)) {
        return real(1.0) / real(720.0) + theta2 * (real(2.0) / real(30240.0)
            + theta2 * (real(3.0) / real(1209600.0) + theta2 * (real(4.0) / real(47900160.0))));
    }
    return (real(0.25) - real(3.0) * c + c * c * theta2) / (theta2 + theta2);
}

// The closed form's values (the twin's ElementValues), with what the tangent reuses:
// θ̄_i × m̄_i, θ̄_i × (θ̄_i × m̄_i) and dc/dθ² per node.
struct Values {
    l: real,
    e1: vec3<real>,
    e2: vec3<real>,
    e3: vec3<real>,
    b1: vec3<real>,
    b2: vec3<real>,
    p: vec3<real>,
    n: real,
    eta: real,
    th1: vec3<real>,
    th2: vec3<real>,
    c1: real,
    c2: real,
    m1: vec3<real>,
    m2: vec3<real>,
    v1: vec3<real>,
    v2: vec3<real>,
    vs: vec3<real>,
    axial: real,
    g3: real,
    g2: real,
    q: real,
    be1: vec3<real>,
    be2: vec3<real>,
    tm1: vec3<real>,
    tm2: vec3<real>,
    ttm1: vec3<real>,
    ttm2: vec3<real>,
    slope1: real,
    slope2: real,
    // 1/n and 1/l, once for the nine directions.
    inv_n: real,
    inv_l: real,
}

// The element's twelve forces or one direction's twelve variations: (x₁, θ₁, x₂, θ₂).
struct Twelve {
    x1: vec3<real>,
    t1: vec3<real>,
    x2: vec3<real>,
    t2: vec3<real>,
}

// The values of the element with chord d (length l), elongation u and triads t1, t2;
// stiffness k = (EA/l0, GJ/l0, EI/l0); unstrained rotations r1, r2 (the moments act on
// θ̄ − θ̄⁰). The force: (−g, f₁, g, f₂).
fn element_values(d: vec3<real>, l: real, u: real, t1: Triad, t2: Triad, k: vec3<real>, r1: vec3<real>, r2: vec3<real>) -> Values {
    let half = real(0.5);
    let e1 = d / l;
    let b1 = t1.c1;
    let b2 = t2.c1;
    let p = half * (b1 + b2);
    let a = cr(e1, p);
    let n = sqrt(dt(a, a));
    let e3 = a / n;
    let e2 = cr(e3, e1);
    let eta = dt(p, e1) / n;
    let l1 = rel_log(e1, e2, e3, t1);
    let l2 = rel_log(e1, e2, e3, t2);
    let s1 = l1.th - r1;
    let s2 = l2.th - r2;
    let twist = k.y * (s2.x - s1.x);
    let m1 = vec3<real>(-twist, k.z * (real(4.0) * s1.y + real(2.0) * s2.y), k.z * (real(4.0) * s1.z + real(2.0) * s2.z));
    let m2 = vec3<real>(twist, k.z * (real(4.0) * s2.y + real(2.0) * s1.y), k.z * (real(4.0) * s2.z + real(2.0) * s1.z));
    // v̄ = J⁻ᵀ(θ) m̄ = m̄ + ½ θ × m̄ + c θ × (θ × m̄).
    let tm1 = cr(l1.th, m1);
    let ttm1 = cr(l1.th, tm1);
    let tm2 = cr(l2.th, m2);
    let ttm2 = cr(l2.th, tm2);
    let v1 = m1 + half * tm1 + l1.c * ttm1;
    let v2 = m2 + half * tm2 + l2.c * ttm2;
    let vs = v1 + v2;
    let axial = k.x * u;
    let g3 = (eta * vs.x + vs.y) / l;
    let g2 = vs.z / l;
    let q = vs.x / (n + n);
    let be1 = cr(b1, e3);
    let be2 = cr(b2, e3);
    return Values(l, e1, e2, e3, b1, b2, p, n, eta, l1.th, l2.th, l1.c, l2.c, m1, m2, v1, v2, vs,
                  axial, g3, g2, q, be1, be2, tm1, tm2, ttm1, ttm2,
                  coefficient_slope(dt(l1.th, l1.th), l1.c), coefficient_slope(dt(l2.th, l2.th), l2.c),
                  real(1.0) / n, real(1.0) / l);
}

fn element_force(v: Values) -> Twelve {
    let g = v.axial * v.e1 + v.g3 * v.e3 - v.g2 * v.e2;
    // R_r v̄ − q (b × e3).
    let f1 = v.e1 * v.v1.x + v.e2 * v.v1.y + v.e3 * v.v1.z - v.q * v.be1;
    let f2 = v.e1 * v.v2.x + v.e2 * v.v2.y + v.e3 * v.v2.z - v.q * v.be2;
    return Twelve(-g, f1, g, f2);
}

// δθ̄ = J⁻¹(θ̄) x, J⁻¹x = x − ½ θ × x + c θ × (θ × x).
fn jinv(th: vec3<real>, c: real, x: vec3<real>) -> vec3<real> {
    let tx = cr(th, x);
    return x - real(0.5) * tx + c * cr(th, tx);
}

// δv̄ of v̄ = J⁻ᵀ(θ̄) m̄ (c a function of θ²).
fn dvbar(th: vec3<real>, c: real, slope: real, m: vec3<real>, tm: vec3<real>, ttm: vec3<real>, dth: vec3<real>, dm: vec3<real>) -> vec3<real> {
    let dtm = cr(dth, m) + cr(th, dm);
    let dttm = cr(dth, tm) + cr(th, dtm);
    let dc = dt(th, dth) * (slope * real(2.0));
    return (dm + real(0.5) * dtm) + (dc * ttm + c * dttm);
}

// The variation of the force along one direction (physics::beam::tangent::variation): the
// chord's unit vector and length changing by de1, dl (moved, a translation of node 2), or
// node `node`'s triad spun by the global spin s (not moved).
fn variation(v: Values, k: vec3<real>, moved: bool, de1: vec3<real>, dl: real, node: u32, s: vec3<real>) -> Twelve {
    let half = real(0.5);
    let zero = vec3<real>(real(0.0));
    let inv_n = v.inv_n;
    let inv_l = v.inv_l;
    // δb_i = δθ_i × b_i for the spun node.
    var db1 = zero;
    var db2 = zero;
    var da: vec3<real>;
    var dp = zero;
    if (moved) {
        da = cr(de1, v.p);
    } else {
        if (node == 0u) {
            db1 = cr(s, v.b1);
        } else {
            db2 = cr(s, v.b2);
        }
        dp = half * (db1 + db2);
        da = cr(v.e1, dp);
    }
    // a = e1 × p, n = |a|, e3 = a/n, e2 = e3 × e1, η = p·e1/n.
    let dn = dt(v.e3, da);
    let de3 = (da - dn * v.e3) * inv_n;
    var de2 = cr(de3, v.e1);
    var deta: real;
    var w3 = real(0.0);
    if (moved) {
        de2 = de2 + cr(v.e3, de1);
        deta = (dt(v.p, de1) - dn * v.eta) * inv_n;
        w3 = dt(v.e2, de1);
    } else {
        deta = (dt(v.e1, dp) - dn * v.eta) * inv_n;
    }
    // The frame's spin in its own components: δe_k = δω × e_k.
    let omega = vec3<real>(dt(v.e3, de2), dt(v.e1, de3), w3);
    // R_rᵀ δθ_i − ω.
    var x1 = -omega;
    var x2 = -omega;
    if (!moved) {
        let local = vec3<real>(dt(v.e1, s), dt(v.e2, s), dt(v.e3, s)) - omega;
        if (node == 0u) {
            x1 = local;
        } else {
            x2 = local;
        }
    }
    let dth1 = jinv(v.th1, v.c1, x1);
    let dth2 = jinv(v.th2, v.c2, x2);
    let dtwist = (dth2.x - dth1.x) * k.y;
    let dm1 = vec3<real>(-dtwist, (dth1.y * real(4.0) + dth2.y * real(2.0)) * k.z, (dth1.z * real(4.0) + dth2.z * real(2.0)) * k.z);
    let dm2 = vec3<real>(dtwist, (dth2.y * real(4.0) + dth1.y * real(2.0)) * k.z, (dth2.z * real(4.0) + dth1.z * real(2.0)) * k.z);
    let dv1 = dvbar(v.th1, v.c1, v.slope1, v.m1, v.tm1, v.ttm1, dth1, dm1);
    let dv2 = dvbar(v.th2, v.c2, v.slope2, v.m2, v.tm2, v.ttm2, dth2, dm2);
    let dvs = dv1 + dv2;
    var dg3 = deta * v.vs.x + dvs.x * v.eta + dvs.y;
    var dg2 = dvs.z;
    if (moved) {
        dg3 = dg3 - dl * v.g3;
        dg2 = dg2 - dl * v.g2;
    }
    dg3 = dg3 * inv_l;
    dg2 = dg2 * inv_l;
    var dg = (dg3 * v.e3 + v.g3 * de3) - (dg2 * v.e2 + v.g2 * de2);
    if (moved) {
        dg = dg + ((dl * k.x) * v.e1 + v.axial * de1);
    }
    let dq = (dvs.x * half - dn * v.q) * inv_n;
    // f_θi = R_r v̄_i − q (b_i × e3).
    var turned1 = v.v1.y * de2 + v.v1.z * de3;
    var turned2 = v.v2.y * de2 + v.v2.z * de3;
    if (moved) {
        turned1 = turned1 + v.v1.x * de1;
        turned2 = turned2 + v.v2.x * de1;
    }
    let own1 = dv1.x * v.e1 + dv1.y * v.e2 + dv1.z * v.e3;
    let own2 = dv2.x * v.e1 + dv2.y * v.e2 + dv2.z * v.e3;
    var dbe1 = cr(v.b1, de3);
    var dbe2 = cr(v.b2, de3);
    if (!moved) {
        if (node == 0u) {
            dbe1 = dbe1 + cr(db1, v.e3);
        } else {
            dbe2 = dbe2 + cr(db2, v.e3);
        }
    }
    let df1 = (turned1 + own1) - (dq * v.be1 + v.q * dbe1);
    let df2 = (turned2 + own2) - (dq * v.be2 + v.q * dbe2);
    return Twelve(-dg, df1, dg, df2);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let nv = dims.num_variants;
    // One invocation per (element, variant); built MASKED (the engines' line-search trials,
    // with FORCE_ONLY; the dynamic engine's Newton iterations, with the tangent) per
    // (element, listed variant), the other variants' outputs left as they were.
    let at = item_of(gid.x, dims.num_elements, nv);
    if (at.x >= dims.num_elements) {
        return;
    }
    let e = at.x;
    let v = at.y;
    let base = vec3<real>(chord[(4u * e) * nv + v], chord[(4u * e + 1u) * nv + v], chord[(4u * e + 2u) * nv + v]);
    let stretch = chord[(4u * e + 3u) * nv + v];
    let k = vec3<real>(section[4u * e], section[4u * e + 1u], section[4u * e + 2u]);
    let l0 = section[4u * e + 3u];
#if KINK
    let r1 = vec3<real>(rest[(6u * e) * nv + v], rest[(6u * e + 1u) * nv + v], rest[(6u * e + 2u) * nv + v]);
    let r2 = vec3<real>(rest[(6u * e + 3u) * nv + v], rest[(6u * e + 4u) * nv + v], rest[(6u * e + 5u) * nv + v]);
#else
    let r1 = vec3<real>(real(0.0));
    let r2 = r1;
#endif
    var w: array<vec3<real>, 2>;
    var tri: array<Triad, 2>;
    for (var node = 0u; node < 2u; node = node + 1u) {
        let i = e + node;
        w[node] = vec3<real>(x[(3u * i) * nv + v], x[(3u * i + 1u) * nv + v], x[(3u * i + 2u) * nv + v]);
        // triad = R_i · frame0_i, by columns; R_i read once (a read is a loop over the
        // lanes on lavapipe, which does not merge repeated ones).
        var rm: array<real, 9>;
        for (var k = 0u; k < 9u; k = k + 1u) {
            rm[k] = rot[(9u * i + k) * nv + v];
        }
        var cols: array<vec3<real>, 3>;
        for (var c = 0u; c < 3u; c = c + 1u) {
            for (var r = 0u; r < 3u; r = r + 1u) {
                var s = real(0.0);
                for (var m = 0u; m < 3u; m = m + 1u) {
                    s = s + rm[3u * r + m] * frame0[9u * i + 3u * m + c];
                }
                cols[c][r] = s;
            }
        }
        tri[node] = Triad(cols[0], cols[1], cols[2]);
    }
#if F64
    // Node 2 at c + w₂ (the twin's positions): d = (c + w₂) − w₁, ū = |d| − l0.
    let d = (base + w[1]) - w[0];
    let l = sqrt(dt(d, d));
    let u = l - l0;
#else
    let dw = w[1] - w[0];
    let d = base + dw;
    let l = sqrt(dt(d, d));
    let lc = sqrt(dt(base, base));
    let u = stretch + (real(2.0) * dt(base, dw) + dt(dw, dw)) / (l + lc);
#endif
    let vals = element_values(d, l, u, tri[0], tri[1], k, r1, r2);
    let f = element_force(vals);
    let out = array<vec3<real>, 4>(f.x1, f.t1, f.x2, f.t2);
    for (var j = 0u; j < 12u; j = j + 1u) {
        elem_force[(12u * e + j) * nv + v] = out[j / 3u][j % 3u];
    }
#if !FORCE_ONLY
    // Nine directions, not twelve: the element sees the translations only through x₂ − x₁,
    // so node 1's translation columns are node 2's negated; and of the twelve rows nine, as
    // f_x₁ = −f_x₂.
    let zero = vec3<real>(real(0.0));
    for (var dir = 0u; dir < 9u; dir++) {
        // d: 0–2 node 2's translations (columns 6–8), 3–5 node 1's spins (columns 3–5),
        // 6–8 node 2's spins (columns 9–11).
        var unit = zero;
        unit[dir % 3u] = real(1.0);
        let moved = dir < 3u;
        let node = select(1u, 0u, dir < 6u);
        // Node 2's translation along e_a: δl = e1[a], δe1 = (e_a − e1 e1[a])/l (the spins
        // leave the chord alone).
        var de1 = zero;
        if (moved) {
            de1 = (unit - vals.e1 * vals.e1[dir % 3u]) / vals.l;
        }
        let dv = variation(vals, k, moved, de1, vals.e1[dir % 3u], node, unit);
        let rows = array<vec3<real>, 3>(dv.t1, dv.x2, dv.t2);
        for (var r = 0u; r < 9u; r = r + 1u) {
            elem_tangent[(81u * e + 9u * r + dir) * nv + v] = rows[r / 3u][r % 3u];
        }
    }
#endif
}
