//! Implicit dynamics (generalised-α on the rotation group) against closed forms.

use holewall::model::Model;
use holewall::physics::mass::MassKind;
use holewall::solve::dynamics::{
    strain_energy, AlphaParams, DynamicOptions, DynamicState, Dynamics,
};
use holewall::solve::modal::{mass_matrix, modes, participation};
use holewall::solve::statics::{solve_static, StaticOptions};

const RHO: f64 = common::STEEL;

/// A weightless vertical cantilever (clamped top, free bit) of 6.5 in collar.
fn cantilever(l: f64, elements: usize) -> Model {
    Model {
        bit_lateral_fixed: false,
        ..common::weightless_collar(l, elements)
    }
}

/// Released from the deflection under a small tip load: free vibration.
fn released(m: &Model, tip_load: f64) -> (Model, holewall::solve::statics::StaticState) {
    let mut loaded = m.clone();
    let bit = m.nodes.len() - 1;
    loaded.point_loads = vec![(bit, [tip_load, 0.0, 0.0, 0.0, 0.0, 0.0])];
    let sol = solve_static(&loaded, &StaticOptions::default()).unwrap();
    (m.clone(), sol.state)
}

fn run(
    m: &Model,
    start: &holewall::solve::statics::StaticState,
    dt: f64,
    steps: usize,
    rho_inf: f64,
) -> (Vec<f64>, Vec<f64>) {
    run_with(m, start, dt, steps, rho_inf, MassKind::Lumped)
}

fn run_with(
    m: &Model,
    start: &holewall::solve::statics::StaticState,
    dt: f64,
    steps: usize,
    rho_inf: f64,
    mass: MassKind,
) -> (Vec<f64>, Vec<f64>) {
    let options = DynamicOptions {
        dt,
        alpha: AlphaParams::chung_hulbert(rho_inf),
        tolerance: 1e-10,
        mass,
        ..Default::default()
    };
    let mut dynamics = Dynamics::new(m, options, &|_| RHO);
    let mut s: DynamicState = dynamics.initial_state(start.clone()).unwrap();
    let bit = m.nodes.len() - 1;
    let mut tip = vec![s.q.u[bit][0]];
    let mut energy = vec![dynamics.kinetic_energy(&s) + strain_energy(m, &s.q)];
    for _ in 0..steps {
        dynamics.step(&mut s, dt).unwrap();
        tip.push(s.q.u[bit][0]);
        energy.push(dynamics.kinetic_energy(&s) + strain_energy(m, &s.q));
    }
    (tip, energy)
}

#[test]
fn small_free_vibration_keeps_its_energy_with_rho_inf_one() {
    let m = cantilever(10.0, 10);
    let (m, start) = released(&m, 50.0);
    let (tip, energy) = run(&m, &start, 2e-3, 1000, 1.0);
    let e0 = energy[0];
    let drift = energy.iter().fold(0.0f64, |d, e| d.max((e - e0).abs())) / e0;
    eprintln!(
        "energy drift over 1000 steps: {drift:.2e} (tip amplitude {:.2e} m)",
        tip[0]
    );
    assert!(drift <= 1e-6, "energy drift {drift:e}");
    // It did vibrate: the tip crossed zero.
    assert!(tip.iter().any(|x| *x < 0.0));
}

#[test]
fn free_vibration_period_matches_the_first_mode() {
    // Lumped and consistent mass, each against the modal solution with the same mass; the
    // consistent run must also keep its energy.
    for kind in [MassKind::Lumped, MassKind::Consistent] {
        let m = cantilever(10.0, 4);
        let sol = solve_static(&m, &StaticOptions::default()).unwrap();
        let mass = mass_matrix(&m, kind, &|_| RHO);
        let mode = modes(&m, &sol.state, &mass)
            .into_iter()
            .find(|md| participation(md, 0) > 0.5)
            .unwrap();
        let f1 = mode.frequency_hz;
        // Released from the mode shape (2 mm at the tip): only that mode vibrates.
        let start = from_mode(&sol.state, &mode.shape, 2e-3);
        let dt = 1.0 / (f1 * 400.0);
        let (tip, energy) = run_with(&m, &start, dt, 1200, 1.0, kind);
        // Zero crossings → period.
        let crossings: Vec<f64> = (1..tip.len())
            .filter(|&k| tip[k - 1] > 0.0 && tip[k] <= 0.0)
            .map(|k| (k as f64 - 1.0 + tip[k - 1] / (tip[k - 1] - tip[k])) * dt)
            .collect();
        assert!(crossings.len() >= 2);
        let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let drift = energy
            .iter()
            .fold(0.0f64, |d, e| d.max((e / energy[0] - 1.0).abs()));
        eprintln!(
            "{kind:?} mass: period {period:.6} s vs 1/f1 {:.6} s; energy drift {drift:.1e}",
            1.0 / f1
        );
        // Trapezoidal period error at 400 steps per period: (ωh)²/12 ≈ 2e-5.
        assert!((period * f1 - 1.0).abs() <= 1e-4, "{kind:?}");
        assert!(drift <= 1e-6, "{kind:?}: energy drift {drift:e}");
    }
}

#[test]
fn hook_lowered_at_rop_carries_the_string_down() {
    let mut m = cantilever(10.0, 5);
    m.bit_lateral_fixed = false;
    let (rop, ramp) = (0.01, 0.2);
    let options = DynamicOptions {
        dt: 1e-3,
        rop,
        ramp_time: ramp,
        ..Default::default()
    };
    let mut dynamics = Dynamics::new(&m, options, &|_| RHO);
    let mut s = dynamics
        .initial_state(holewall::solve::statics::StaticState::initial(&m))
        .unwrap();
    dynamics.run(&mut s, 1.0, &mut |_, _| {}).unwrap();
    let expected = 0.5 * rop * ramp + rop * (1.0 - ramp);
    let bit = m.nodes.len() - 1;
    // The top follows the hook exactly; the bit with it, up to the axial vibration the
    // ramp's kinks excite (inertia ≈ 70 N over EA/L: about 1e-7 m, ±1e-4 m/s).
    for (i, tol_x, tol_v) in [(0, 1e-12, 1e-12), (bit, 1e-6, 0.02 * rop)] {
        let dz = s.q.u[i][2];
        eprintln!(
            "node {i}: lowered {dz:.9} m vs {expected:.9} m, at {:.6} m/s",
            s.v[6 * i + 2]
        );
        assert!(
            (dz - expected).abs() <= tol_x,
            "node {i}: {dz} vs {expected}"
        );
        assert!((s.v[6 * i + 2] - rop).abs() <= tol_v);
    }
}

/// sin²(πt/0.2): a smooth load from rest (no shock to excite the high modes).
fn smooth(t: f64) -> f64 {
    (std::f64::consts::PI * t / 0.2).sin().powi(2)
}

#[test]
fn error_shrinks_at_second_order_in_the_step() {
    // A smooth tip load on the cantilever from rest; bit displacement at T = 0.2 s against a
    // run with an 8 times finer step than the finest compared.
    let mut m = cantilever(10.0, 10);
    let bit = m.nodes.len() - 1;
    m.point_loads = vec![(bit, [2000.0, 0.0, 0.0, 0.0, 0.0, 0.0])];
    let t_end = 0.2;
    let at = |dt: f64, rho_inf: f64| {
        let options = DynamicOptions {
            dt,
            alpha: AlphaParams::chung_hulbert(rho_inf),
            tolerance: 1e-11,
            load_factor: Some(smooth),
            ..Default::default()
        };
        let mut dynamics = Dynamics::new(&m, options, &|_| RHO);
        let mut s = dynamics
            .initial_state(holewall::solve::statics::StaticState::initial(&m))
            .unwrap();
        let steps = (t_end / dt).round() as usize;
        for _ in 0..steps {
            dynamics.step(&mut s, dt).unwrap();
        }
        s.q.u[bit][0]
    };
    for rho_inf in [1.0, 0.8, 0.5] {
        let reference = at(t_end / 1280.0, rho_inf);
        let errors: Vec<f64> = [t_end / 40.0, t_end / 80.0, t_end / 160.0]
            .iter()
            .map(|&dt| (at(dt, rho_inf) - reference).abs())
            .collect();
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        eprintln!("ρ∞ = {rho_inf}: bit displacement {reference:.6e} m; errors {errors:?}, observed orders {orders:?}");
        assert!(
            orders.iter().all(|o| (*o - 2.0).abs() <= 0.25),
            "ρ∞ = {rho_inf}: orders {orders:?}"
        );
    }
}

#[test]
fn damped_run_settles_to_the_static_solution() {
    let mut m = cantilever(10.0, 10);
    let bit = m.nodes.len() - 1;
    m.point_loads = vec![(bit, [2000.0, 0.0, 0.0, 0.0, 0.0, 0.0])];
    let static_tip = solve_static(&m, &StaticOptions::default()).unwrap().state.u[bit][0];
    // Mass-proportional Rayleigh damping, about 30 % of critical in the first mode (1.29 Hz).
    let options = DynamicOptions {
        dt: 0.01,
        rayleigh: (2.0 * 0.3 * 8.1, 0.0),
        alpha: AlphaParams::chung_hulbert(0.8),
        ..Default::default()
    };
    let mut dynamics = Dynamics::new(&m, options, &|_| RHO);
    let mut s = dynamics
        .initial_state(holewall::solve::statics::StaticState::initial(&m))
        .unwrap();
    let mut peak: f64 = 0.0;
    dynamics
        .run(&mut s, 12.0, &mut |_, st| {
            peak = peak.max(st.q.u[bit][0]);
        })
        .unwrap();
    let tip = s.q.u[bit][0];
    eprintln!("settled tip {tip:.6e} m vs static {static_tip:.6e} m (overshoot peak {peak:.4e} m)");
    assert!(
        peak > 1.2 * static_tip,
        "the load was applied suddenly: it must overshoot"
    );
    assert!((tip / static_tip - 1.0).abs() <= 1e-4);
    let v: f64 = s.v.iter().fold(0.0, |m, x| m.max(x.abs()));
    assert!(v < 1e-5, "still moving: {v:e}");
}

#[test]
fn hht_is_second_order_and_dissipative() {
    let p = AlphaParams::hht(0.1);
    assert!((p.gamma - 0.6).abs() < 1e-15 && (p.beta - 0.3025).abs() < 1e-15 && p.alpha_m == 0.0);
    let m = cantilever(10.0, 10);
    let (m, start) = released(&m, 50.0);
    let options = DynamicOptions {
        dt: 2e-3,
        alpha: p,
        tolerance: 1e-10,
        ..Default::default()
    };
    let mut dynamics = Dynamics::new(&m, options, &|_| RHO);
    let mut s = dynamics.initial_state(start).unwrap();
    let e0 = dynamics.kinetic_energy(&s) + strain_energy(&m, &s.q);
    for _ in 0..500 {
        dynamics.step(&mut s, 2e-3).unwrap();
    }
    let e1 = dynamics.kinetic_energy(&s) + strain_energy(&m, &s.q);
    assert!(
        e1 < e0 && e1 > 0.5 * e0,
        "HHT dissipates, mildly at low frequency: {e0} → {e1}"
    );
}

/// The energy error of a free, bent string spinning about its axis and tumbling: a large
/// rotation case (ρ∞ = 1, no damping, no contact). Returns the largest relative energy
/// error over `t_end`.
fn spinning_bent_string_energy_error(dt: f64, t_end: f64) -> f64 {
    let m = cantilever(10.0, 4);
    // Bent by a tip load to a deflection of about a tenth of its length.
    let (mut m, start) = released(&m, 2500.0);
    m.top = holewall::model::TopBoundary::Free;
    let n = m.nodes.len();
    let x0 = start.positions(&m);
    let centre: [f64; 3] = std::array::from_fn(|k| x0.iter().map(|x| x[k]).sum::<f64>() / n as f64);
    // Spin 20 rad/s about the (vertical) string axis, tumbling at 2 rad/s about a
    // horizontal one.
    let w = [0.0, 2.0, 20.0];
    let mut v = vec![0.0; 6 * n];
    for i in 0..n {
        let r: [f64; 3] = std::array::from_fn(|k| x0[i][k] - centre[k]);
        let u = [
            w[1] * r[2] - w[2] * r[1],
            w[2] * r[0] - w[0] * r[2],
            w[0] * r[1] - w[1] * r[0],
        ];
        v[6 * i..6 * i + 3].copy_from_slice(&u);
        v[6 * i + 3..6 * i + 6].copy_from_slice(&w);
    }
    let options = DynamicOptions {
        dt,
        alpha: AlphaParams::chung_hulbert(1.0),
        tolerance: 1e-11,
        ..Default::default()
    };
    let mut dynamics = Dynamics::new(&m, options, &|_| RHO);
    let mut s = dynamics.initial_state_moving(start, v).unwrap();
    let e0 = dynamics.kinetic_energy(&s) + strain_energy(&m, &s.q);
    let steps = (t_end / dt).round() as usize;
    let mut worst: f64 = 0.0;
    let mut turned = 0.0;
    for _ in 0..steps {
        dynamics.step(&mut s, dt).unwrap();
        let e = dynamics.kinetic_energy(&s) + strain_energy(&m, &s.q);
        worst = worst.max((e / e0 - 1.0).abs());
        turned += w[2] * dt;
    }
    assert!(turned > 4.0, "a large rotation: {turned} rad");
    worst
}

#[test]
fn spinning_bent_string_keeps_its_energy_at_second_order() {
    let t_end = 0.25;
    // Steps that resolve the stiffest mode, a node's rotary inertia against its elements'
    // bending stiffness (ω ≈ √(8E/ρ)/l ≈ 6000 rad/s here): with ωh ≳ 1 the energy error
    // carries a high-frequency part that does not yet shrink at the asymptotic rate.
    let errors: Vec<f64> = [4e-4, 2e-4, 1e-4]
        .iter()
        .map(|&dt| spinning_bent_string_energy_error(dt, t_end))
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    eprintln!("spinning bent string: max relative energy errors {errors:?}, orders {orders:?}");
    assert!(errors[0] < 1e-2, "bounded: {errors:?}");
    assert!(orders.iter().all(|o| *o >= 1.8), "second order: {orders:?}");
}

/// `state` displaced along a mode shape, scaled to `amplitude` at its largest entry.
fn from_mode(
    state: &holewall::solve::statics::StaticState,
    shape: &[f64],
    amplitude: f64,
) -> holewall::solve::statics::StaticState {
    let eps = amplitude / shape.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let mut start = state.clone();
    for i in 0..start.u.len() {
        for k in 0..3 {
            start.u[i][k] += eps * shape[6 * i + k];
        }
        let th: [f64; 3] = std::array::from_fn(|k| eps * shape[6 * i + 3 + k]);
        start.rot[i] = holewall::physics::beam::rotation_exp(&th);
    }
    start
}

/// Spectral radius of the scheme's amplification matrix for `ẍ + ω²x = 0` at `ωh`
/// (state `(x, v, a)`; the equation of motion holds at `t_{n+1}`, as in the integrator).
fn spectral_radius(p: AlphaParams, wh: f64) -> f64 {
    let (h, w2) = (1.0, wh * wh);
    let advance = |x: f64, v: f64, a: f64| {
        // x1 = x + h v + h²(½−β) a + h²β a1, a1 = (−(1−α_f)ω² x1 − α_f ω² x − α_m a)/(1−α_m).
        let k = h * h * p.beta / (1.0 - p.alpha_m);
        let x1 =
            (x + h * v + h * h * (0.5 - p.beta) * a + k * (-p.alpha_f * w2 * x - p.alpha_m * a))
                / (1.0 + k * (1.0 - p.alpha_f) * w2);
        let a1 =
            (-(1.0 - p.alpha_f) * w2 * x1 - p.alpha_f * w2 * x - p.alpha_m * a) / (1.0 - p.alpha_m);
        let v1 = v + h * (1.0 - p.gamma) * a + h * p.gamma * a1;
        [x1, v1, a1]
    };
    let cols = [
        advance(1.0, 0.0, 0.0),
        advance(0.0, 1.0, 0.0),
        advance(0.0, 0.0, 1.0),
    ];
    let a = nalgebra::Matrix3::from_fn(|r, c| cols[c][r]);
    a.complex_eigenvalues()
        .iter()
        .fold(0.0f64, |m, z| m.max(z.norm()))
}

#[test]
fn high_modes_lose_energy_at_the_rate_theory_gives() {
    let m = cantilever(10.0, 10);
    let sol = solve_static(&m, &StaticOptions::default()).unwrap();
    let mass = mass_matrix(&m, MassKind::Lumped, &|_| RHO);
    let all = modes(&m, &sol.state, &mass);
    let lateral: Vec<_> = all.iter().filter(|md| participation(md, 0) > 0.3).collect();
    for rho_inf in [0.5, 0.0] {
        let p = AlphaParams::chung_hulbert(rho_inf);
        // A mid-range mode at ωh = 1.5 and the highest lateral mode at the same step.
        let mid = lateral[4];
        let w_mid = std::f64::consts::TAU * mid.frequency_hz;
        let dt = 1.5 / w_mid;
        for mode in [mid, *lateral.last().unwrap()] {
            let wh = std::f64::consts::TAU * mode.frequency_hz * dt;
            // Released at rest from the mode shape, 0.1 mm amplitude (linear range).
            let start = from_mode(&sol.state, &mode.shape, 1e-4);
            let options = DynamicOptions {
                dt,
                alpha: p,
                tolerance: 1e-12,
                ..Default::default()
            };
            let mut dynamics = Dynamics::new(&m, options, &|_| RHO);
            let mut s = dynamics.initial_state(start).unwrap();
            let mut log_e = Vec::new();
            for _ in 0..80 {
                dynamics.step(&mut s, dt).unwrap();
                log_e.push((dynamics.kinetic_energy(&s) + strain_energy(&m, &s.q)).ln());
            }
            // Least-squares slope of ln E from step 3 (the spurious root has died out) while
            // the mode still holds 1e-7 of its energy (below that, what other modes received
            // from the tiny nonlinearity shows): E ∝ ρ^{2n}.
            let e0 = log_e[0];
            let pts: Vec<(f64, f64)> = (3..80)
                .take_while(|&k| log_e[k] > e0 - 7.0 * std::f64::consts::LN_10)
                .map(|k| (k as f64, log_e[k]))
                .collect();
            assert!(pts.len() >= 3, "{} points", pts.len());
            let nm = pts.len() as f64;
            let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
            let (mx, my) = (sx / nm, sy / nm);
            let slope = pts.iter().map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
                / pts.iter().map(|(x, _)| (x - mx).powi(2)).sum::<f64>();
            let measured = (0.5 * slope).exp();
            let theory = spectral_radius(p, wh);
            eprintln!(
                "ρ∞ = {rho_inf}, ωh = {wh:.2}: energy ratio per step {:.5} vs theory ρ² = {:.5}",
                measured * measured,
                theory * theory
            );
            assert!(
                (measured.ln() / theory.ln() - 1.0).abs() <= 0.02,
                "ρ∞ = {rho_inf}, ωh = {wh}: measured ρ {measured} vs theory {theory}"
            );
        }
        // The theory itself: ρ(ωh → ∞) = ρ∞.
        assert!((spectral_radius(p, 1e6) - rho_inf.max(1e-300)).abs() < 1e-3);
    }
}

/// A 10 m collar hanging from the rotary table (weightless), a stabilizer at its free end
/// pressed to the wall by whirling faster than the string's first natural frequency
/// (8.1 rad/s). Returns (measured whirl rate of the stabilizer centre, its own spin rate,
/// slip speed at the contact point / Ω·R_d), averaged over the second half of the run.
fn whirl(mu: f64, t_end: f64) -> (f64, f64, f64) {
    use holewall::model::{add_sites, ContactSettings};
    let (r_d, clearance, spin) = (0.1, 0.02, 4.0);
    let mut m = cantilever(10.0, 10);
    m.rotation_speed = spin;
    let bit = m.nodes.len() - 1;
    let settings = ContactSettings {
        wall_stiffness: 1e8,
        spring_exponent: 1.0,
        wall_damping: 2e3,
        eps: 1e-3,
        soft_blend: 1e-4,
    };
    add_sites(
        &mut m,
        &[bit],
        |_| r_d + clearance,
        |_| r_d,
        |_| mu,
        &settings,
        true,
    );
    // Start: the tip pushed to the wall (static shape under a tip load), whirling backward
    // at 0.7 times the rolling rate, the whole string spinning with the table.
    let mut pushed = m.clone();
    pushed.sites.clear();
    pushed.point_loads = vec![(
        bit,
        [22_100.0 * (clearance + 2e-5), 0.0, 0.0, 0.0, 0.0, 0.0],
    )];
    let start = solve_static(&pushed, &StaticOptions::default())
        .unwrap()
        .state;
    let w0 = -0.7 * spin * r_d / clearance;
    let n = m.nodes.len();
    let mut v = vec![0.0; 6 * n];
    for i in 0..n {
        let d = [start.u[i][0], start.u[i][1]];
        v[6 * i] = -w0 * d[1];
        v[6 * i + 1] = w0 * d[0];
        v[6 * i + 5] = spin;
    }
    let options = DynamicOptions {
        dt: 1e-3,
        alpha: AlphaParams::chung_hulbert(0.8),
        ..Default::default()
    };
    let mut dynamics = Dynamics::new(&m, options, &|_| RHO);
    let mut s = dynamics.initial_state_moving(start, v).unwrap();
    let (mut angle, mut last) = (Vec::new(), None::<f64>);
    let (mut spins, mut slips) = (Vec::new(), Vec::new());
    let mut unwrapped = 0.0;
    dynamics
        .run(&mut s, t_end, &mut |_, st| {
            let d = [st.q.u[bit][0], st.q.u[bit][1]];
            let a = d[1].atan2(d[0]);
            if let Some(l) = last {
                let mut da = a - l;
                da -= std::f64::consts::TAU * (da / std::f64::consts::TAU).round();
                unwrapped += da;
            }
            last = Some(a);
            if st.t > 0.5 * t_end {
                angle.push((st.t, unwrapped));
                let r = d[0].hypot(d[1]);
                let tangential = (d[0] * st.v[6 * bit + 1] - d[1] * st.v[6 * bit]) / r;
                let w = st.v[6 * bit + 5];
                spins.push(w);
                slips.push((tangential + w * r_d) / (spin * r_d));
                assert!(r > clearance * 0.99, "left the wall: r = {r}");
            }
        })
        .unwrap();
    let nm = angle.len() as f64;
    let (mt, ma) = angle
        .iter()
        .fold((0.0, 0.0), |(a, b), (t, x)| (a + t / nm, b + x / nm));
    let rate = angle.iter().map(|(t, x)| (t - mt) * (x - ma)).sum::<f64>()
        / angle.iter().map(|(t, _)| (t - mt).powi(2)).sum::<f64>();
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    (rate, mean(&spins), mean(&slips))
}

#[test]
fn stabilizer_rolling_on_the_wall_whirls_backward_and_slips_with_low_friction() {
    let (r_d, clearance) = (0.1, 0.02);
    let (rate, spin, slip) = whirl(0.5, 1.5);
    let expected = -spin * r_d / clearance;
    eprintln!("μ = 0.5: whirl {rate:.4} rad/s vs −Ω·R_d/ΔR = {expected:.4} rad/s (spin {spin:.4}); slip {slip:.2e}");
    assert!(
        (rate / expected - 1.0).abs() <= 0.02,
        "rolling whirl {rate} vs {expected}"
    );
    assert!(slip.abs() < 0.02);
    let (rate, spin, slip) = whirl(0.01, 1.5);
    let expected = -spin * r_d / clearance;
    eprintln!(
        "μ = 0.01: whirl {rate:.4} rad/s vs −Ω·R_d/ΔR = {expected:.4} rad/s; slip {slip:.2e}"
    );
    assert!(
        rate < 0.0 && rate > 0.8 * expected,
        "slipping: {rate} vs {expected}"
    );
    assert!(slip > 0.2, "slipping: {slip}");
}

/// The bit is held laterally in the hole frame (its translation basis): in an inclined
/// hole its accelerations must stay along the hole axis, so the bit never leaves the axis.
#[path = "common/mod.rs"]
mod common;

#[test]
fn bit_held_laterally_in_an_inclined_hole() {
    let case = common::bed_case("1");
    let model = &case.model;
    let start = solve_static(model, &StaticOptions::default()).unwrap();
    let density = case.element_density.clone();
    let options = case.dynamics.as_ref().unwrap().integrator_options();
    let mut dynamics = Dynamics::new(model, options, &|e| density[e]);
    let mut s = dynamics.initial_state(start.state).unwrap();
    let bit = model.nodes.len() - 1;
    let nd = &model.nodes[bit];
    let mut worst: f64 = 0.0;
    let mut axial: f64 = 0.0;
    dynamics
        .run(&mut s, 0.05, &mut |_, st| {
            let d: [f64; 3] = st.q.u[bit];
            let along: f64 = (0..3).map(|k| d[k] * nd.hole_axis[k]).sum();
            let lateral = (0..3)
                .map(|k| (d[k] - along * nd.hole_axis[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(lateral);
            axial = axial.max(along.abs());
        })
        .unwrap();
    eprintln!(
        "bit in a 60° hole over 0.05 s: lateral offset {worst:.2e} m, axial travel {axial:.2e} m"
    );
    assert!(worst <= 1e-12, "the bit left the hole axis by {worst:e} m");
}
