// Twin: src/kernels/beam.rs (formulas: src/physics/beam.rs, `element_force` and
// `force_and_tangent_closed`, the co-rotational element in closed form).
//
// One invocation per (element, variant), index = element · V + variant. The internal force
// is the closed form of physics::beam::element_force (frame: chord and the mean of the
// nodal triads' second axes; local moments through J⁻ᵀ of the rotation logs, the frame's
// spin through η and n):
//   f_x₂ = −f_x₁ = N e1 + ((η V₁ + V₂) e3 − V₃ e2)/l,  f_θᵢ = R_r v̄_i − V₁/(2n)·(b_i × e3).
// The consistent tangent is that force in dual numbers (value, derivative) — here
// vec2<real>, vectors as (value, derivative) pairs of vec3<real> — once per seed: a DOF
// seeded as a translation or a left spin (I + [ε e]×)·triad. K_jk = ∂f_j/∂Δ_k; nine seeds
// give the twelve columns (node 1's translation columns are node 2's negated). Built with
// FORCE_ONLY it evaluates the force alone (line-search trials: 1/9 of the work and no
// tangent written). Outputs in the assembly's layout: [(12 e + j) V + v] and
// [(144 e + 12 j + k) V + v].
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
// moved.
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

// A dual number (value, derivative) and a dual 3-vector.
alias dl = vec2<real>;
struct DV {
    v: vec3<real>,
    d: vec3<real>,
}

fn dmul(a: dl, b: dl) -> dl {
    return dl(a.x * b.x, a.x * b.y + a.y * b.x);
}

fn ddiv(a: dl, b: dl) -> dl {
    let q = a.x / b.x;
    return dl(q, (a.y - q * b.y) / b.x);
}

fn dsqrt(a: dl) -> dl {
    let s = sqrt(a.x);
    return dl(s, real(0.5) * a.y / s);
}

fn dc(a: real) -> dl {
    return dl(a, real(0.0));
}

fn cr(a: vec3<real>, b: vec3<real>) -> vec3<real> {
    return a.yzx * b.zxy - a.zxy * b.yzx;
}

fn dt(a: vec3<real>, b: vec3<real>) -> real {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn vdot(a: DV, b: DV) -> dl {
    return dl(dt(a.v, b.v), dt(a.d, b.v) + dt(a.v, b.d));
}

fn vcross(a: DV, b: DV) -> DV {
    return DV(cr(a.v, b.v), cr(a.d, b.v) + cr(a.v, b.d));
}

fn vscale(a: DV, s: dl) -> DV {
    return DV(a.v * s.x, a.d * s.x + a.v * s.y);
}

fn vdivs(a: DV, s: dl) -> DV {
    let q = a.v / s.x;
    return DV(q, (a.d - q * s.y) / s.x);
}

fn vadd(a: DV, b: DV) -> DV {
    return DV(a.v + b.v, a.d + b.d);
}

fn vsub(a: DV, b: DV) -> DV {
    return DV(a.v - b.v, a.d - b.d);
}

fn vnorm(a: DV) -> dl {
    return dsqrt(vdot(a, a));
}

#if F64
// atan on [0, 1] by two half-angle reductions and a Taylor series (no f64 atan on Vulkan).
fn atan_unit(t: real) -> real {
    var u = t / (real(1.0) + sqrt(real(1.0) + t * t));
    u = u / (real(1.0) + sqrt(real(1.0) + u * u));
    let u2 = u * u;
    var s = real(0.0);
    for (var step = 0u; step < 14u; step = step + 1u) {
        let k = 13u - step;
        var sign = real(1.0);
        if (k % 2u == 1u) {
            sign = real(-1.0);
        }
        s = s * u2 + sign / real(2u * k + 1u);
    }
    return real(4.0) * u * s;
}

fn atan2_real(y: real, x: real) -> real {
    let pi = real(3.141592653589793);
    let ay = abs(y);
    let ax = abs(x);
    var a: real;
    if (ay <= ax) {
        a = atan_unit(ay / ax);
    } else {
        a = real(0.5) * pi - atan_unit(ax / ay);
    }
    if (x < real(0.0)) {
        a = pi - a;
    }
    if (y < real(0.0)) {
        a = -a;
    }
    return a;
}
#else
fn atan2_real(y: real, x: real) -> real {
    return atan2(y, x);
}
#endif

fn datan2(y: dl, x: dl) -> dl {
    return dl(atan2_real(y.x, x.x), (x.x * y.y - y.x * x.y) / (x.x * x.x + y.x * y.x));
}

// A nodal triad by its columns (the element's initial axes carried by the node).
struct Triad {
    c0: DV,
    c1: DV,
    c2: DV,
}

// The rotation vector of Rrᵀ·t (Rr = [e1 e2 e3]) and the coefficient c(θ) of J⁻¹(θ),
// as physics::beam::rotation_log_and_jacobian.
struct LogJ {
    th: DV,
    c: dl,
}

fn rel_log(e1: DV, e2: DV, e3: DV, t: Triad) -> LogJ {
    let half = real(0.5);
    // r[a][b] = e_a · t_b.
    let w = DV(
        half * vec3<real>(vdot(e3, t.c1).x - vdot(e2, t.c2).x, vdot(e1, t.c2).x - vdot(e3, t.c0).x,
                          vdot(e2, t.c0).x - vdot(e1, t.c1).x),
        half * vec3<real>(vdot(e3, t.c1).y - vdot(e2, t.c2).y, vdot(e1, t.c2).y - vdot(e3, t.c0).y,
                          vdot(e2, t.c0).y - vdot(e1, t.c1).y),
    );
    let s2 = vdot(w, w);
    let c = half * (vdot(e1, t.c0) + vdot(e2, t.c1) + vdot(e3, t.c2) - dc(real(1.0)));
    var factor: dl;
    var s = dc(real(0.0));
    let series = s2.x < real(1e-6) && c.x > real(0.0);
    if (series) {
        factor = dc(real(1.0)) + dmul(s2, dc(real(1.0) / real(6.0)) + dmul(s2, dc(real(3.0) / real(40.0))));
    } else {
        s = dsqrt(s2);
        factor = ddiv(datan2(s, c), s);
    }
    let theta2 = dmul(dmul(factor, factor), s2);
    var coefficient: dl;
    if (!series && theta2.x >= real(0.1)) {
        let theta = dmul(factor, s);
        coefficient = ddiv(dc(real(1.0)) - ddiv(dmul(theta, dc(real(1.0)) + c), s + s), theta2);
    } else {
        coefficient = dc(real(1.0) / real(12.0)) + dmul(theta2, dc(real(1.0) / real(720.0))
            + dmul(theta2, dc(real(1.0) / real(30240.0)) + dmul(theta2, dc(real(1.0) / real(1209600.0))
            + dmul(theta2, dc(real(1.0) / real(47900160.0))))));
    }
    return LogJ(vscale(w, factor), coefficient);
}

// v̄ = J⁻ᵀ(θ) m̄ = m̄ + ½ θ × m̄ + c θ × (θ × m̄).
fn jt(l: LogJ, m: DV) -> DV {
    let tm = vcross(l.th, m);
    let ttm = vcross(l.th, tm);
    return vadd(vadd(m, vscale(tm, dc(real(0.5)))), vscale(ttm, l.c));
}

// The force (12, as dual numbers) of the element with chord d, elongation u and triads t1,
// t2; stiffness k = (EA/l0, GJ/l0, EI/l0); unstrained rotations r1, r2 (the moments act on
// θ̄ − θ̄⁰: constants, so the derivative parts are θ̄'s).
struct Force {
    x1: DV,
    t1: DV,
    x2: DV,
    t2: DV,
}

fn element_force(d: DV, u: dl, t1: Triad, t2: Triad, k: vec3<real>, r1: vec3<real>, r2: vec3<real>) -> Force {
    let half = dc(real(0.5));
    let l = vnorm(d);
    let e1 = vdivs(d, l);
    let p = vscale(vadd(t1.c1, t2.c1), half);
    let a = vcross(e1, p);
    let n = vnorm(a);
    let e3 = vdivs(a, n);
    let e2 = vcross(e3, e1);
    let eta = ddiv(vdot(p, e1), n);
    let l1 = rel_log(e1, e2, e3, t1);
    let l2 = rel_log(e1, e2, e3, t2);
    let s1 = l1.th.v - r1;
    let s2 = l2.th.v - r2;
    let twist = dmul(dc(k.y), dl(s2.x - s1.x, l2.th.d.x - l1.th.d.x));
    let four = dc(real(4.0) * k.z);
    let two = dc(real(2.0) * k.z);
    let t1y = dl(s1.y, l1.th.d.y);
    let t1z = dl(s1.z, l1.th.d.z);
    let t2y = dl(s2.y, l2.th.d.y);
    let t2z = dl(s2.z, l2.th.d.z);
    let m1y = dmul(four, t1y) + dmul(two, t2y);
    let m1z = dmul(four, t1z) + dmul(two, t2z);
    let m2y = dmul(four, t2y) + dmul(two, t1y);
    let m2z = dmul(four, t2z) + dmul(two, t1z);
    let m1 = DV(vec3<real>(-twist.x, m1y.x, m1z.x), vec3<real>(-twist.y, m1y.y, m1z.y));
    let m2 = DV(vec3<real>(twist.x, m2y.x, m2z.x), vec3<real>(twist.y, m2y.y, m2z.y));
    let v1 = jt(l1, m1);
    let v2 = jt(l2, m2);
    let vs = vadd(v1, v2);
    let vs0 = dl(vs.v.x, vs.d.x);
    let vs1 = dl(vs.v.y, vs.d.y);
    let vs2 = dl(vs.v.z, vs.d.z);
    let axial = dmul(dc(k.x), u);
    let g3 = ddiv(dmul(eta, vs0) + vs1, l);
    let g2 = ddiv(vs2, l);
    let g = vsub(vadd(vscale(e1, axial), vscale(e3, g3)), vscale(e2, g2));
    let q = ddiv(vs0, n + n);
    // R_r v̄ − q (b × e3).
    let f1 = vsub(vadd(vadd(vscale(e1, dl(v1.v.x, v1.d.x)), vscale(e2, dl(v1.v.y, v1.d.y))),
                       vscale(e3, dl(v1.v.z, v1.d.z))), vscale(vcross(t1.c1, e3), q));
    let f2 = vsub(vadd(vadd(vscale(e1, dl(v2.v.x, v2.d.x)), vscale(e2, dl(v2.v.y, v2.d.y))),
                       vscale(e3, dl(v2.v.z, v2.d.z))), vscale(vcross(t2.c1, e3), q));
    return Force(DV(-g.v, -g.d), f1, g, f2);
}

fn constant(v: vec3<real>) -> DV {
    return DV(v, vec3<real>(real(0.0)));
}

// The triad's columns with the derivative of a spin about `axis` (zero: none).
fn spun(t: Triad, axis: vec3<real>) -> Triad {
    return Triad(DV(t.c0.v, cr(axis, t.c0.v)), DV(t.c1.v, cr(axis, t.c1.v)), DV(t.c2.v, cr(axis, t.c2.v)));
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
        tri[node] = Triad(constant(cols[0]), constant(cols[1]), constant(cols[2]));
    }
#if F64
    // Node 2 at c + w₂ (the twin's positions): d = (c + w₂) − w₁, ū = |d| − l0.
    let d0 = (base + w[1]) - w[0];
#else
    let dw = w[1] - w[0];
    let d0 = base + dw;
    let lc = sqrt(dt(base, base));
#endif
    let zero = vec3<real>(real(0.0));
#if FORCE_ONLY
    let seeds = 1u;
#else
    // Nine passes, not twelve: the element sees the translations only through x₂ − x₁, so
    // node 1's translation columns are node 2's negated, exactly (a seed of −1 negates every
    // derivative without changing a rounding; the twin's DualN<9> carries the same nine).
    let seeds = 9u;
#endif
    for (var seed = 0u; seed < seeds; seed++) {
        // Seed k: 0–2 node 2's translations (columns 6–8), 3–5 node 1's spins (columns
        // 3–5), 6–8 node 2's spins (columns 9–11); the force alone: none.
        var dd = zero;
        var spin = array<vec3<real>, 2>(zero, zero);
#if !FORCE_ONLY
        let node = select(1u, 0u, seed >= 3u && seed < 6u);
        var unit = zero;
        unit[seed % 3u] = real(1.0);
        if (seed < 3u) {
            dd = unit;
        } else {
            spin[node] = unit;
        }
        let col = select(select(seed + 3u, seed, seed < 6u), seed + 6u, seed < 3u);
#endif
        let d = DV(d0, dd);
#if F64
        let u = vnorm(d) - dc(l0);
#else
        let dwd = DV(dw, dd);
        let bd = constant(base);
        let num = dmul(dc(real(2.0)), vdot(bd, dwd)) + vdot(dwd, dwd);
        let u = dc(stretch) + ddiv(num, vnorm(d) + dc(lc));
#endif
        let f = element_force(d, u, spun(tri[0], spin[0]), spun(tri[1], spin[1]), k, r1, r2);
        let out = array<DV, 4>(f.x1, f.t1, f.x2, f.t2);
        for (var j = 0u; j < 12u; j = j + 1u) {
            let part = out[j / 3u];
            if (seed == 0u) {
                elem_force[(12u * e + j) * nv + v] = part.v[j % 3u];
            }
#if !FORCE_ONLY
            elem_tangent[(144u * e + 12u * j + col) * nv + v] = part.d[j % 3u];
            if (seed < 3u) {
                elem_tangent[(144u * e + 12u * j + seed) * nv + v] = -part.d[j % 3u];
            }
#endif
        }
    }
}
