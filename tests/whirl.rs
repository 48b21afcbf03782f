//! Whirl from a mass imbalance (issue 16) against closed forms.

use holewall::model::Model;
use holewall::physics::mass::MassKind;
use holewall::solve::dynamics::{AlphaParams, DynamicOptions, Dynamics};
use holewall::solve::modal::{mass_matrix, modes};
use holewall::solve::statics::StaticState;

const RHO: f64 = common::STEEL;

#[path = "common/mod.rs"]
mod common;

/// A weightless vertical 6.5 in collar of length `l`: top clamped to the rotary table, bit
/// held laterally (a clamped–pinned shaft).
fn shaft(l: f64, elements: usize) -> Model {
    common::weightless_collar(l, elements)
}

/// The first lateral mode in x (rad/s) and its x-displacements per node.
fn first_x_mode(m: &Model) -> (f64, Vec<f64>) {
    let mass = mass_matrix(m, MassKind::Lumped, &|_| RHO);
    let ms = modes(m, &StaticState::initial(m), &mass);
    for mode in ms.iter().take(6) {
        let x: Vec<f64> = (0..m.nodes.len()).map(|i| mode.shape[6 * i]).collect();
        let y: Vec<f64> = (0..m.nodes.len()).map(|i| mode.shape[6 * i + 1]).collect();
        let nx: f64 = x.iter().map(|v| v * v).sum();
        let ny: f64 = y.iter().map(|v| v * v).sum();
        if nx > 100.0 * ny {
            return (std::f64::consts::TAU * mode.frequency_hz, x);
        }
    }
    panic!("no x mode among the lowest six");
}

/// Spins the shaft up to `r` × its first natural frequency with a mass imbalance shaped as
/// that mode (centre-of-mass offset `eps` at its antinode) and external damping ζ; returns
/// (measured whirl radius at the antinode, closed form, whirl rate / Ω, radius spread).
fn jeffcott(r: f64, zeta: f64, eps: f64) -> (f64, f64, f64, f64) {
    let mut m = shaft(10.0, 20);
    let (w1, phi) = first_x_mode(&m);
    let (k_max, phi_max) =
        phi.iter().enumerate().fold(
            (0, 0.0f64),
            |a, (k, v)| if v.abs() > a.1.abs() { (k, *v) } else { a },
        );
    let (mass, _) = holewall::solve::dynamics::lumped_mass(&m, &|_| RHO);
    m.unbalance = (0..m.nodes.len())
        .map(|i| [mass[i] * eps * phi[i] / phi_max, 0.0, 0.0])
        .collect();
    let omega = r * w1;
    m.rotation_speed = omega;
    let settling = 12.0 / (zeta * w1);
    let ramp = 2.0;
    let options = DynamicOptions {
        dt: (std::f64::consts::TAU / omega) / 120.0,
        alpha: AlphaParams::chung_hulbert(0.9),
        rayleigh: (2.0 * zeta * w1, 0.0),
        ramp_time: ramp,
        // The weightless shaft's force scale is 1 N (no loads): 1e-4 N is far above the
        // rounding of its axial forces (≈ 1e-5 N) and far below the imbalance's 435 N.
        tolerance: 1e-4,
        ..Default::default()
    };
    let mut d = Dynamics::new(&m, options, &|_| RHO);
    let mut s = d.initial_state(StaticState::initial(&m)).unwrap();
    let t_end = ramp + settling + 2.0;
    let (mut radii, mut angles) = (Vec::new(), Vec::new());
    let mut last = None::<f64>;
    let mut unwrapped = 0.0;
    d.run(&mut s, t_end, &mut |_, st| {
        let x = st.q.u[k_max][0];
        let y = st.q.u[k_max][1];
        let a = y.atan2(x);
        if let Some(l) = last {
            let mut da = a - l;
            da -= std::f64::consts::TAU * (da / std::f64::consts::TAU).round();
            unwrapped += da;
        }
        last = Some(a);
        if st.t > t_end - 2.0 {
            radii.push(x.hypot(y));
            angles.push((st.t, unwrapped));
        }
    })
    .unwrap();
    let mean = radii.iter().sum::<f64>() / radii.len() as f64;
    let spread = radii.iter().fold(0.0f64, |m, x| m.max((x - mean).abs())) / mean;
    let rate = (angles.last().unwrap().1 - angles[0].1) / (angles.last().unwrap().0 - angles[0].0);
    let closed = eps * r * r / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2)).sqrt();
    (mean, closed, rate / omega, spread)
}

/// A Jeffcott rotor in continuum form: the imbalance shaped as the first mode drives that
/// mode alone, so the antinode whirls forward and synchronously on a circle of radius
/// `e r² / √((1 − r²)² + (2ζr)²)`, below and above the critical speed.
#[test]
fn imbalance_spins_up_into_forward_synchronous_whirl_of_jeffcott_amplitude() {
    for (r, zeta) in [(0.5, 0.05), (0.8, 0.05), (1.6, 0.05)] {
        // 1 mm: a realistic collar's centre-of-mass offset (a few tenths of a millimetre
        // of wall-thickness variation on 6.5 in).
        let eps = 1e-3;
        let (radius, closed, ratio, spread) = jeffcott(r, zeta, eps);
        eprintln!(
            "r = {r}, ζ = {zeta}: whirl radius {:.5} mm vs Jeffcott {:.5} mm ({:+.2e}), whirl/Ω {ratio:.5}, radius spread {spread:.1e}",
            1e3 * radius,
            1e3 * closed,
            radius / closed - 1.0
        );
        assert!(
            (ratio - 1.0).abs() < 2e-3,
            "r = {r}: not synchronous: {ratio}"
        );
        assert!(spread < 1e-2, "r = {r}: not circular: {spread}");
        // Measured −2.4e-4 at r = 0.5, 0.8 and 1.6 alike with 120 steps per revolution
        // (+1e-3, +6e-3, −6e-3 with 40: the period error of the scheme, amplified near
        // resonance): what stays is independent of the step and of r.
        assert!(
            (radius / closed - 1.0).abs() < 1e-3,
            "r = {r}: {radius} vs {closed}"
        );
    }
}

/// A 10 m collar hanging from the rotary table (weightless, bit free), a stabilizer of
/// radius `R_d` at its end in a hole of clearance `ΔR`: an imbalance throws the spinning
/// stabilizer to the wall; with high friction it rolls there, whirling backward at
/// `−Ω R_d/ΔR`. Returns the whirl analysis of its second half and the rolling rate (Hz).
fn imbalance_against_the_wall(
    mu: f64,
    spin: f64,
    eps: f64,
    t_end: f64,
) -> (holewall::whirl::Whirl, f64) {
    use holewall::model::{add_sites, ContactSettings};
    let (r_d, clearance) = (0.1, 0.02);
    let mut m = shaft(10.0, 10);
    m.bit_lateral_fixed = false;
    m.rotation_speed = spin;
    let bit = m.nodes.len() - 1;
    add_sites(
        &mut m,
        &[bit],
        |_| r_d + clearance,
        |_| r_d,
        |_| mu,
        &ContactSettings {
            wall_stiffness: 1e8,
            spring_exponent: 1.0,
            wall_damping: 2e3,
            eps: 1e-3,
            soft_blend: 1e-4,
        },
        true,
    );
    let (mass, _) = holewall::solve::dynamics::lumped_mass(&m, &|_| RHO);
    m.unbalance = (0..m.nodes.len())
        .map(|i| [mass[i] * eps, 0.0, 0.0])
        .collect();
    let options = DynamicOptions {
        dt: 1e-3,
        alpha: AlphaParams::chung_hulbert(0.8),
        ramp_time: 0.5,
        ..Default::default()
    };
    let mut d = Dynamics::new(&m, options, &|_| RHO);
    let mut s = d.initial_state(StaticState::initial(&m)).unwrap();
    let every = 5;
    let (mut x, mut y, mut normal) = (Vec::new(), Vec::new(), Vec::new());
    let mut spins = Vec::new();
    let mut step = 0usize;
    d.run(&mut s, t_end, &mut |dd, st| {
        step += 1;
        if step.is_multiple_of(every) && st.t > 0.5 * t_end {
            x.push(st.q.u[bit][0]);
            y.push(st.q.u[bit][1]);
            spins.push(st.v[6 * bit + 5]);
            let f = dd.contact_forces(st);
            normal.push(if f[0].contact { 1.0 } else { 0.0 });
        }
    })
    .unwrap();
    let mean_spin = spins.iter().sum::<f64>() / spins.len() as f64;
    let w = holewall::whirl::analyse(
        &x,
        &y,
        &normal,
        every as f64 * 1e-3,
        spin / std::f64::consts::TAU,
        clearance,
    );
    (w, -mean_spin * r_d / clearance / std::f64::consts::TAU)
}

/// The classic friction-driven transition: the same imbalance (1 cm offset, 7 rad/s, 0.86 of
/// the first natural frequency: a Jeffcott radius past the 2 cm clearance) throws the
/// stabilizer to the wall; with μ = 0.1 it stays in forward synchronous whirl, touching the
/// wall now and then; with μ = 0.5 the friction turns it into backward whirl, rolling on
/// the wall at `−Ω_s R_d/ΔR` (`Ω_s` the stabilizer's own spin), in contact throughout.
#[test]
fn imbalance_in_contact_with_high_friction_rolls_into_backward_whirl() {
    let spin = 7.0;
    let (w, rolling_hz) = imbalance_against_the_wall(0.5, spin, 10e-3, 12.0);
    eprintln!(
        "μ = 0.5: {:?}, dominant {:.3} Hz vs rolling −Ω R_d/ΔR = {rolling_hz:.3} Hz (resolution {:.3} Hz), peak share {:.2}, contact {:.2}, max radius {:.2} mm",
        w.class,
        w.dominant_hz,
        w.resolution_hz,
        w.peak_share,
        w.contact_fraction,
        1e3 * w.max_radius_m
    );
    assert_eq!(w.class, holewall::whirl::WhirlClass::Backward);
    assert!(w.peak_share > 0.9 && w.contact_fraction > 0.95, "{w:?}");
    // Within a bin, and the 3 % by which the radius exceeds ΔR (the wall's give).
    assert!(
        (w.dominant_hz - rolling_hz).abs() <= w.resolution_hz + 0.03 * rolling_hz.abs(),
        "{} vs {rolling_hz}",
        w.dominant_hz
    );
    let (w, _) = imbalance_against_the_wall(0.1, spin, 10e-3, 12.0);
    eprintln!(
        "μ = 0.1: {:?}, dominant {:.3} Hz vs Ω/2π = {:.3} Hz, contact {:.2}",
        w.class,
        w.dominant_hz,
        spin / std::f64::consts::TAU,
        w.contact_fraction
    );
    assert_eq!(w.class, holewall::whirl::WhirlClass::Forward);
    assert!((w.dominant_hz - spin / std::f64::consts::TAU).abs() <= w.resolution_hz);
    assert!(w.contact_fraction < 0.5, "{w:?}");
}

/// The imbalance keys: `mass_eccentricity` (m) and `imbalance` (kg·m) of a component give
/// the same nodal imbalance; both at once, or an offset beyond the pipe, are refused; the
/// ensemble key `ecc` sets the BHA's offset and leaves the drill pipe without.
#[test]
fn imbalance_keys_agree_and_the_ecc_key_sets_the_bha() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/spinup_short.toml"),
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("holewall-whirl-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let parse = |text: &str| {
        let p = dir.join("case.toml");
        std::fs::write(&p, text).unwrap();
        holewall::case::load_case(&p)
    };
    // The first collar: 9.25 m of 6.5 in × 2.8125 in steel.
    let first = "kind = \"collar\"\nlength = \"9.25 m\"";
    let mass =
        7850.0 * std::f64::consts::FRAC_PI_4 * (0.1651f64.powi(2) - 0.071_437_5f64.powi(2)) * 9.25;
    let by_offset =
        parse(&base.replacen(first, &format!("{first}\nmass_eccentricity = \"1 mm\""), 1)).unwrap();
    let by_moment = parse(&base.replacen(
        first,
        &format!("{first}\nimbalance = \"{} kg.m\"", mass * 1e-3),
        1,
    ))
    .unwrap();
    let total = |m: &Model| -> f64 { m.unbalance.iter().map(|u| u[0].hypot(u[1])).sum() };
    assert!(by_offset.model.has_unbalance());
    assert!(
        (total(&by_offset.model) / (mass * 1e-3) - 1.0).abs() < 1e-9,
        "{}",
        total(&by_offset.model)
    );
    for (a, b) in by_offset
        .model
        .unbalance
        .iter()
        .zip(&by_moment.model.unbalance)
    {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-12 * mass);
        }
    }
    let both = parse(&base.replacen(
        first,
        &format!("{first}\nmass_eccentricity = \"1 mm\"\nimbalance = \"1 kg.m\""),
        1,
    ))
    .unwrap_err();
    assert!(both.to_string().contains("not both"), "{both}");
    let far = parse(&base.replacen(first, &format!("{first}\nmass_eccentricity = \"10 cm\""), 1))
        .unwrap_err();
    assert!(far.to_string().contains("od/2"), "{far}");
    // ecc: the BHA (bit to the first drill pipe) only.
    let case = parse(&base).unwrap();
    assert!(!case.model.has_unbalance());
    let v = holewall::ensemble::variants_from_csv_text("v.csv", "ecc\n0.5 mm\n").unwrap();
    let m = holewall::ensemble::apply(&case, &v[0]).unwrap();
    let bha_top = case.bit_md - case.bha_length;
    for (i, u) in m.unbalance.iter().enumerate() {
        let on = u[0].hypot(u[1]) > 0.0;
        assert_eq!(
            on,
            m.nodes[i].md >= bha_top - 1e-9,
            "node {i} at {}",
            m.nodes[i].md
        );
    }
    assert!(m.has_unbalance());
}

/// `[dynamics].initial_lateral_velocity`: the kick moves the BHA of the (otherwise exactly
/// axisymmetric) short spin-up off the hole axis, against the wall; without it the
/// stabilizer stays on the axis and the whirl analysis says `none`.
#[test]
fn an_initial_lateral_kick_starts_lateral_motion() {
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/spinup_short.toml"),
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("holewall-whirl-kick-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let run = |text: &str, name: &str| -> serde_json::Value {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(&p, text).unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_holewall"))
            .args([
                "run",
                p.to_str().unwrap(),
                "--out",
                dir.join(name).to_str().unwrap(),
                "--quiet",
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let still = run(&base, "still");
    assert_eq!(still["whirl"][0]["class"], "none");
    assert_eq!(still["whirl"][0]["max_radius_m"].as_f64().unwrap(), 0.0);
    let kicked = run(
        &base.replace(
            "rho_inf = 0.8",
            "rho_inf = 0.8\ninitial_lateral_velocity = \"0.05 m/s\"",
        ),
        "kicked",
    );
    let r = kicked["whirl"][0]["max_radius_m"].as_f64().unwrap();
    let clearance = 0.5 * (8.5 - 8.25) * 0.0254;
    eprintln!(
        "kicked: largest radius {:.3} mm (clearance {:.3} mm), contact {}",
        1e3 * r,
        1e3 * clearance,
        kicked["whirl"][0]["contact_fraction"]
    );
    assert!(r > 0.9 * clearance, "{r}");
    assert!(kicked["whirl"][0]["contact_fraction"].as_f64().unwrap() > 0.0);
    // `initial_lateral_offset`: the BHA let go from a half sine 2 mm off the axis at its
    // middle: the stabilizer starts at 2 mm × sin(π s) (s its height over the BHA's) and
    // moves back towards the axis.
    let offset = 2e-3;
    let _ = run(
        &base.replace(
            "rho_inf = 0.8",
            "rho_inf = 0.8\ninitial_lateral_offset = \"2 mm\"",
        ),
        "offset",
    );
    let csv = std::fs::read_to_string(dir.join("offset").join("contact_sites.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let (md, r0, r_end) = (rows[0][3], rows[0][6], rows.last().unwrap()[6]);
    let s = (60.0 - md) / 30.75;
    let expect = offset * (std::f64::consts::PI * s).sin();
    eprintln!(
        "released from a {:.1} mm offset: stabilizer starts at {:.4} mm (half sine {:.4} mm), ends at {:.4} mm",
        1e3 * offset,
        1e3 * r0,
        1e3 * expect,
        1e3 * r_end
    );
    assert!((r0 / expect - 1.0).abs() < 1e-9, "{r0} vs {expect}");
    assert!(r_end < 0.8 * r0, "let go: {r_end} vs {r0}");
}

/// `[dynamics].initial_lateral_offset`: a half sine over the BHA (zero at the bit and at the
/// first drill pipe, the offset at its middle) applied to the static start, the drill pipe
/// untouched; wider than the BHA's clearance is refused with the key and the clearance.
#[test]
fn the_initial_offset_is_a_half_sine_over_the_bha_within_its_clearance() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/spinup_short.toml");
    let base = std::fs::read_to_string(&path).unwrap();
    let text = base.replace(
        "rho_inf = 0.8",
        "rho_inf = 0.8\ninitial_lateral_offset = \"3 mm\"",
    );
    let case = holewall::case::parse_case(std::path::Path::new("offset.toml"), &text).unwrap();
    let m = &case.model;
    let q0 = StaticState::initial(m);
    let (q, v) = case.dynamic_start(m, q0.clone());
    assert!(v.is_none());
    let bit_md = m.nodes.last().unwrap().md;
    let mut largest = 0.0f64;
    for (i, nd) in m.nodes.iter().enumerate() {
        let d: Vec<f64> = (0..3).map(|k| q.u[i][k] - q0.u[i][k]).collect();
        let w = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let s = (bit_md - nd.md) / case.bha_length;
        let expect = if s <= 1.0 && i + 1 < m.nodes.len() {
            3e-3 * (std::f64::consts::PI * s).sin()
        } else {
            0.0
        };
        assert!(
            (w - expect.abs()).abs() < 1e-12,
            "node {i} at s = {s}: {w} vs {expect}"
        );
        let axial: f64 = (0..3).map(|k| d[k] * nd.hole_axis[k]).sum();
        assert!(axial.abs() < 1e-15, "lateral only");
        largest = largest.max(w);
    }
    assert!(largest > 2.9e-3, "{largest}");
    let wide = base.replace(
        "rho_inf = 0.8",
        "rho_inf = 0.8\ninitial_lateral_offset = \"5 cm\"",
    );
    let e = holewall::case::parse_case(std::path::Path::new("wide.toml"), &wide)
        .unwrap_err()
        .to_string();
    eprintln!("{e}");
    assert!(
        e.contains("dynamics.initial_lateral_offset") && e.contains("clearance"),
        "{e}"
    );
}

/// The shipped whirl map (`cases/whirl_map.toml`: a 3 mm collar imbalance, RPM × WOB ×
/// friction): with μ = 0.1 the stabilizer whirls forward and synchronously everywhere; with
/// μ = 0.5 it turns to backward whirl from 180 rpm on (its dominant frequency against the
/// rotation, faster than it; classed `backward` at 40 kN); one map per friction value.
#[test]
fn the_shipped_whirl_map() {
    let case = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/whirl_map.toml");
    let out = std::env::temp_dir().join(format!("holewall-whirl-map-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let s = common::ensemble_on_cpu(&case, None, &out);
    assert_eq!((s.variants, s.failed), (16, 0));
    let csv = std::fs::read_to_string(out.join("variants.csv")).unwrap();
    let mut rows = csv.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let mut classed_backward = 0;
    let (rpm, mu, whirl, hz) = (
        col("rpm"),
        col("mu"),
        col("stab1_whirl"),
        col("stab1_whirl_hz"),
    );
    for line in rows {
        let f: Vec<&str> = line.split(',').collect();
        let rpm_v: f64 = f[rpm].parse::<f64>().unwrap() * 60.0 / std::f64::consts::TAU;
        let mu_v: f64 = f[mu].parse().unwrap();
        let backward = mu_v > 0.3 && rpm_v > 150.0;
        if backward {
            // Backward whirl: the dominant frequency against the rotation and faster than
            // it. Its spectrum is broad: at 10 kN the share of its peak sits near the
            // chaotic class's threshold and moves with the time step, on the CPU
            // integrator's steps of before as on today's (180 rpm: 0.53, 0.54, 0.44 at 2,
            // 1 and 0.5 ms before; 0.46, 0.62, 0.44 now; 240 rpm: 0.86, 0.71, 0.37 before;
            // 0.48, 0.71, 0.37 now), so the class there reads `backward` or `chaotic`.
            let h: f64 = f[hz].parse().unwrap();
            assert!(h < -rpm_v / 60.0, "{line}");
            assert!(f[whirl] == "backward" || f[whirl] == "chaotic", "{line}");
            classed_backward += usize::from(f[whirl] == "backward");
        } else {
            assert_eq!(f[whirl], "forward", "{line}");
        }
        if !backward {
            // Synchronous: the rotary frequency within a bin (0.5 Hz over the 2 s window).
            let h: f64 = f[hz].parse().unwrap();
            assert!((h - rpm_v / 60.0).abs() <= 0.51, "{line}");
        }
    }
    // At 40 kN the backward whirl is clean at 180 and 240 rpm.
    assert!(classed_backward >= 2, "{classed_backward} classed backward");
    for f in ["whirl_map_stab1_mu0.1.png", "whirl_map_stab1_mu0.5.png"] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

/// A friction drawn per variant (a value each, as a Monte Carlo draw or a user's variants
/// file gives) is mapped in at most `WHIRL_MAP_FACETS` ranges, not one map per value: 9
/// variants of the shipped whirl map, shortened to 20 ms, with 9 distinct frictions give 6
/// maps named by their ranges, and every variant lies in exactly one of them.
#[test]
fn a_drawn_friction_is_mapped_in_ranges() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("holewall-whirl-drawn-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(root.join("cases/whirl_map.toml"))
        .unwrap()
        .replace("duration = \"4 s\"", "duration = \"20 ms\"");
    std::fs::write(dir.join("case.toml"), text).unwrap();
    let mut csv = String::from("rpm,wob,mu\n");
    let mus = [0.11, 0.15, 0.19, 0.23, 0.27, 0.31, 0.35, 0.39, 0.43];
    for (i, mu) in mus.iter().enumerate() {
        csv.push_str(&format!("{} rpm,{} kN,{mu}\n", 60 + 20 * i, 10 + 3 * i));
    }
    std::fs::write(dir.join("variants.csv"), csv).unwrap();
    let out = dir.join("out");
    let s = common::ensemble_on_cpu(
        &dir.join("case.toml"),
        Some(&dir.join("variants.csv")),
        &out,
    );
    assert_eq!((s.variants, s.failed), (9, 0));
    let mut maps: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("whirl_map_"))
        .collect();
    maps.sort();
    assert_eq!(
        maps.len(),
        holewall::ensemble::job::WHIRL_MAP_FACETS,
        "{maps:?}"
    );
    let ranges = holewall::ensemble::job::facets(&mus, holewall::ensemble::job::WHIRL_MAP_FACETS);
    for mu in mus {
        assert_eq!(
            ranges
                .iter()
                .filter(|(lo, hi)| (*lo..=*hi).contains(&mu))
                .count(),
            1,
            "{mu}: {ranges:?}"
        );
    }
    assert!(
        maps.contains(&"whirl_map_stab1_mu0.11-0.15.png".to_string()),
        "{maps:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The GPU dynamic engine starts from the case's initial offset and kick as the CPU
/// integrator does (`Case::dynamic_start` on each variant's static equilibrium): the short
/// spin-up let go 2 mm off the axis with a 0.02 m/s kick, two speeds, 0.3 s, f64 engine
/// against the CPU — the stabilizer's motion and side force to solver tolerance.
#[test]
fn the_dynamic_engine_starts_from_the_offset_and_kick() {
    if common::gpu().is_none() {
        return;
    }
    let text = common::shipped_case_text("spinup_short.toml").replace(
            "rho_inf = 0.8",
            "rho_inf = 0.8\ninitial_lateral_offset = \"2 mm\"\ninitial_lateral_velocity = \"0.02 m/s\"",
        )
        .replace("duration = \"1 s\"", "duration = \"0.3 s\"")
        .replace("ramp_time = \"0.5 s\"", "ramp_time = \"0.1 s\"");
    let grid = "\n[ensemble]\nanalysis = \"dynamic\"\n\n[ensemble.grid]\nrpm = [\"60 rpm\", \"120 rpm\"]\n";
    let (dir, worst) = common::engine_against_cpu("kick-engine", &format!("{text}{grid}"));
    // The start moved the stabilizer (1.78 mm at rest before the run: the half sine).
    assert!(
        common::variants_column(&dir.join("cpu"), "stab1_max_lateral_m")
            .iter()
            .all(|r| *r > 1.5e-3)
    );
    eprintln!(
        "offset and kick, GPU dynamic engine vs CPU integrator: worst relative difference {worst:.1e}"
    );
    assert!(worst <= 1e-6, "{worst:e}");
}

/// The GPU dynamic engine with a mass imbalance (the assembly built `UNBALANCE`:
/// `physics::mass::unbalance_terms`, as the CPU integrator) against the CPU: the short
/// spin-up with `ecc` 0.5 and 3 mm at 120 rpm, 0.3 s — the stabilizer's motion and side
/// force to solver tolerance.
#[test]
fn the_dynamic_engine_runs_a_mass_imbalance_as_the_cpu_does() {
    if common::gpu().is_none() {
        return;
    }
    let text = common::shipped_case_text("spinup_short.toml")
        .replace("duration = \"1 s\"", "duration = \"0.3 s\"")
        .replace("ramp_time = \"0.5 s\"", "ramp_time = \"0.1 s\"");
    let grid =
        "\n[ensemble]\nanalysis = \"dynamic\"\n\n[ensemble.grid]\necc = [\"0.5 mm\", \"3 mm\"]\n";
    let (dir, worst) = common::engine_against_cpu("ecc-engine", &format!("{text}{grid}"));
    let lateral = common::variants_column(&dir.join("cpu"), "stab1_max_lateral_m");
    assert!(
        lateral[1] > lateral[0] && lateral[0] > 0.0,
        "the imbalance moves the stabilizer: {lateral:?}"
    );
    eprintln!(
        "imbalance, GPU dynamic engine vs CPU integrator: worst relative difference {worst:.1e}"
    );
    assert!(worst <= 1e-6, "{worst:e}");
}

/// The spin-up string of `spinup_short.toml` made weightless in its mud (steel and mud both
/// 2,000 kg/m³: the buoyed weight `g (ρ_s A_s + ρ_i A_i − ρ_o A_o)` is zero), in a straight
/// hole `inclination` degrees off vertical from MD 0 (a survey written into `dir`), let go
/// 2 mm off the axis with a 0.3 m/s kick (the stabilizer strikes the wall), 0.3 s in 1 ms
/// steps. Without weight the problem is axisymmetric about the hole
/// axis, so its scalar results cannot depend on the hole's direction.
fn weightless_spinup(dir: &std::path::Path, inclination: f64) -> String {
    let survey = dir.join(format!("straight_{inclination}.csv"));
    std::fs::write(
        &survey,
        format!(
            "md_m, inclination_deg, azimuth_deg\n0, {inclination}, 30\n60, {inclination}, 30\n"
        ),
    )
    .unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(root.join("cases/spinup_short.toml"))
        .unwrap()
        .replace(
            "profile = \"vertical\"",
            &format!("profile = \"survey\"\nsurvey = \"{}\"", survey.display()),
        )
        .replace("density = \"1.2 sg\"", "density = \"2000 kg/m3\"")
        .replace("kind = \"", "density = \"2000 kg/m3\"\nkind = \"")
        .replace(
            "rho_inf = 0.8",
            "rho_inf = 0.8\ninitial_lateral_offset = \"2 mm\"\ninitial_lateral_velocity = \"0.3 m/s\"",
        )
        .replace("duration = \"1 s\"", "duration = \"0.3 s\"")
        .replace("ramp_time = \"0.5 s\"", "ramp_time = \"0.1 s\"")
        .replace("time_step = \"2 ms\"", "time_step = \"1 ms\"")
}

/// A clamped top in an inclined hole (the bottom of a string modelled alone) is turned by
/// the table about its own hole axis, and the run is the vertical one turned over: the
/// weightless spin-up ([`weightless_spinup`]) 60° off vertical gives the vertical hole's
/// stabilizer excursion, side force, surface torque and hook load. Before, the table
/// turned every top about the vertical, whipping an inclined string's end round: the
/// dynamic corpus's tangent and horizontal sections (`holewall bench dynamic-corpus`) cut
/// their steps down to 1e-7 s and failed, or rang against the wall at 100–700 kN.
#[test]
fn an_inclined_top_turns_about_its_hole_axis() {
    use holewall::ensemble::qoi::dynamic_variant;
    let dir = common::scratch_dir("inclined-top", "cpu");
    let run = |inclination: f64| {
        let path = dir.join(format!("straight_{inclination}.toml"));
        let case =
            holewall::case::parse_case(&path, &weightless_spinup(&dir, inclination)).unwrap();
        dynamic_variant(&case, "run", &case.model)
    };
    let (vertical, inclined) = (run(0.0), run(60.0));
    let pairs = [
        (
            "stab1 max lateral",
            vertical.stabilizers[0].max_lateral_m,
            inclined.stabilizers[0].max_lateral_m,
        ),
        (
            "stab1 max side force",
            vertical.stabilizers[0].max_side_force_n,
            inclined.stabilizers[0].max_side_force_n,
        ),
        (
            "max surface torque",
            vertical.max_surface_torque_nm,
            inclined.max_surface_torque_nm,
        ),
        (
            "hook load",
            vertical.hook_load_n.unwrap(),
            inclined.hook_load_n.unwrap(),
        ),
    ];
    for (name, a, b) in pairs {
        eprintln!("{name}: vertical {a:.9e}, 60° {b:.9e}");
        assert!(
            (a - b).abs() <= 1e-6 * a.abs().max(1e-9),
            "{name}: vertical {a:e}, 60° {b:e}"
        );
    }
    // The run is not trivial: the offset start swings the stabilizer to the wall.
    assert!(vertical.stabilizers[0].max_lateral_m > 1.5e-3);
    assert!(vertical.stabilizers[0].max_side_force_n > 0.0);
    assert_eq!(
        inclined.step_cuts, vertical.step_cuts,
        "{}",
        inclined.reason
    );
}

/// The GPU dynamic engine turns an inclined top about its hole axis as the CPU integrator
/// does (the top's kinematics as vectors along `n₀`, `kernels::dynamics::TOP_LEN`): the
/// weightless spin-up 60° off vertical, two frictions, f64 engine against the CPU.
#[test]
fn the_dynamic_engine_turns_an_inclined_top_as_the_cpu_does() {
    if common::gpu().is_none() {
        return;
    }
    let dir = common::scratch_dir("inclined-top", "survey");
    let text = weightless_spinup(&dir, 60.0);
    let grid = "\n[ensemble]\nanalysis = \"dynamic\"\n\n[ensemble.grid]\nmu = [0.2, 0.4]\n";
    let (_, worst) = common::engine_against_cpu("inclined-engine", &format!("{text}{grid}"));
    eprintln!(
        "inclined top, GPU dynamic engine vs CPU integrator: worst relative difference {worst:.1e}"
    );
    assert!(worst <= 1e-6, "{worst:e}");
}

/// An offset start in an inclined hole, where the BHA rests on the low side
/// (`Case::offset_scale`): the half sine applied is the largest that keeps every node with a
/// contact site in the hole — none past its clearance or deeper than at rest — here lifting
/// the BHA off its wall (the offset's own direction points into it). The spin-up string in
/// a straight 60° hole, contact at every node, 3 mm asked.
#[test]
fn an_offset_start_stays_in_the_hole_in_an_inclined_hole() {
    use holewall::solve::statics::{solve_static, StaticOptions};
    let dir = common::scratch_dir("offset-inclined", "case");
    std::fs::write(
        dir.join("straight.csv"),
        "md_m, inclination_deg, azimuth_deg\n0, 60, 30\n60, 60, 30\n",
    )
    .unwrap();
    let text = common::shipped_case_text("spinup_short.toml")
        .replace(
            "profile = \"vertical\"",
            "profile = \"survey\"\nsurvey = \"straight.csv\"",
        )
        .replace("sites = \"stabilizers\"", "sites = \"all_nodes\"")
        .replace(
            "rho_inf = 0.8",
            "rho_inf = 0.8\ninitial_lateral_offset = \"3 mm\"",
        );
    let case = holewall::case::parse_case(&dir.join("case.toml"), &text).unwrap();
    let m = &case.model;
    let rest = solve_static(m, &StaticOptions::default()).unwrap().state;
    let share = case.offset_scale(m, &rest);
    let (q, _) = case.dynamic_start(m, rest.clone());
    let lateral = |d: &[f64; 3], i: usize| {
        let nd = &m.nodes[i];
        let along: f64 = (0..3).map(|k| d[k] * nd.hole_axis[k]).sum();
        (0..3)
            .map(|k| (d[k] - along * nd.hole_axis[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let (mut moved, mut tight) = (0.0f64, f64::INFINITY);
    for site in &m.sites {
        let i = site.node;
        let (before, after) = (lateral(&rest.u[i], i), lateral(&q.u[i], i));
        let room = site.params.clearance.max(before);
        assert!(after <= room + 1e-12, "node {i}: {after} m past {room} m");
        let step: f64 = (0..3).map(|k| (q.u[i][k] - rest.u[i][k]).powi(2)).sum();
        moved = moved.max(step.sqrt());
        tight = tight.min(room - after);
    }
    eprintln!(
        "offset share {share:.3}: largest move {moved:.2e} m, tightest room left {tight:.1e} m"
    );
    assert!(
        share < 0.0 && share > -1.0,
        "lifted off the wall, scaled: {share}"
    );
    assert!(moved > 1e-3, "the start moved the BHA: {moved}");
    assert!(
        tight.abs() < 1e-9,
        "the largest half sine touches the far wall: {tight}"
    );
}
