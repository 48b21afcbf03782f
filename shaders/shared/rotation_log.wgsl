// atan2 in either precision, θ / sin θ of a rotation and the rotation vector of a rotation
// matrix.
// Twin: physics::rotation::rotation_log (its log without the Jacobian's coefficient);
// included by beam.wgsl (its rel_log's factor) and assemble.wgsl built SHIFT (a
// relaxation's rotational shift, log(R R_aᵀ)).

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

// θ / sin θ of a rotation from s² = sin²θ and c = cos θ (physics::rotation::
// rotation_log_and_jacobian's factor), with sin θ: by its series in s² near θ = 0 (where
// sin θ is returned as 0, not formed), else atan2(s, c) / s.
fn log_factor(s2: real, c: real) -> vec2<real> {
    if (s2 < real(1e-6) && c > real(0.0)) {
        return vec2<real>(real(1.0) + s2 * (real(1.0) / real(6.0) + s2 * (real(3.0) / real(40.0))),
                          real(0.0));
    }
    let s = sqrt(s2);
    return vec2<real>(atan2_real(s, c) / s, s);
}

// log(M) of a rotation matrix M given by rows (m[a][b] = M_ab): the rotation vector θ with
// M = exp([θ]×), as physics::rotation::rotation_log: the skew part's axial vector w
// (|w| = sin θ) times θ / sin θ (log_factor).
fn rotation_log(m: array<vec3<real>, 3>) -> vec3<real> {
    let half = real(0.5);
    let w = half * vec3<real>(m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]);
    let c = half * (m[0][0] + m[1][1] + m[2][2] - real(1.0));
    return w * log_factor(dot(w, w), c).x;
}
