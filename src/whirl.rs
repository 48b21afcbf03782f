//! Whirl of a contact site from its lateral motion (issue 16): spectrum, dominant whirl
//! frequency against the rotary frequency, classification and contact fraction.
//!
//! The lateral displacement in the hole's cross-section is the complex signal
//! `z = x + i y` (`x`, `y` along the site's frame, `x × y` the down-hole axis), sampled
//! at the run's output interval over its second half (after the spin-up). Its spectrum
//! (Hann window, mean removed) separates forward whirl (positive frequencies: the sense of
//! the string's rotation) from backward whirl (negative ones). The amplitude at a
//! frequency is the radius of that circular component (mm).
//!
//! Classification, thresholds stated: `none` when the largest radius of the motion about
//! its mean stays below 1 µm (or 1e-6 of the clearance), or when the dominant frequency is
//! below two bins (fewer than two orbits over the window: a drift, or a site pinned to
//! the wall, is no whirl); otherwise `forward` or `backward`
//! when the dominant peak (±2 bins) holds at least half of the spectral energy, its sign
//! giving the sense, and `chaotic` when no peak does (energy spread over many
//! frequencies). `synchronous` forward whirl: within 5 % of the rotary frequency;
//! rolling backward whirl is expected at `−Ω R_d/ΔR`.

use rustfft::{num_complex::Complex, FftPlanner};
use serde::{Deserialize, Serialize};

/// Share of the spectral energy the dominant peak must hold to name a direction.
pub const PEAK_SHARE: f64 = 0.5;

/// How a site whirls.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WhirlClass {
    /// No lateral motion worth the name.
    None,
    /// Forward whirl (the sense of rotation).
    Forward,
    /// Backward whirl.
    Backward,
    /// No dominant frequency.
    Chaotic,
}

/// The whirl of one site.
#[derive(Clone, Debug, Serialize)]
pub struct Whirl {
    /// Dominant whirl frequency (Hz; + forward, − backward).
    pub dominant_hz: f64,
    /// The same over the rotary frequency.
    pub ratio_to_rotary: f64,
    /// Classification (module docs).
    pub class: WhirlClass,
    /// Share of the spectral energy within ±2 bins of the dominant peak.
    pub peak_share: f64,
    /// Forward whirl within 5 % of the rotary frequency.
    pub synchronous: bool,
    /// Share of the samples in contact with the wall.
    pub contact_fraction: f64,
    /// Largest radial displacement (m).
    pub max_radius_m: f64,
    /// Frequency resolution of the spectrum (Hz).
    pub resolution_hz: f64,
    /// The spectrum: (frequency (Hz), amplitude (m)), ascending frequency.
    #[serde(skip)]
    pub spectrum: Vec<(f64, f64)>,
}

/// Analyses uniformly sampled lateral motion `(x, y)` (m) with contact normal forces
/// `normal` (N) at interval `dt` (s), for a string turning at `rotary_hz` (Hz, signed:
/// positive in the sense `x → y`), in a clearance `clearance` (m). Uses all samples given
/// (pass the second half of a run).
pub fn analyse(
    x: &[f64],
    y: &[f64],
    normal: &[f64],
    dt: f64,
    rotary_hz: f64,
    clearance: f64,
) -> Whirl {
    let n = x.len().min(y.len());
    let contact_fraction = if normal.is_empty() {
        0.0
    } else {
        normal.iter().filter(|f| **f > 0.0).count() as f64 / normal.len() as f64
    };
    let max_radius_m = (0..n).fold(0.0f64, |m, k| m.max(x[k].hypot(y[k])));
    let resolution_hz = 1.0 / (n.max(1) as f64 * dt);
    let (mx, my) = (
        x.iter().take(n).sum::<f64>() / n.max(1) as f64,
        y.iter().take(n).sum::<f64>() / n.max(1) as f64,
    );
    let motion = (0..n).fold(0.0f64, |m, k| m.max((x[k] - mx).hypot(y[k] - my)));
    let none = Whirl {
        dominant_hz: 0.0,
        ratio_to_rotary: 0.0,
        class: WhirlClass::None,
        peak_share: 0.0,
        synchronous: false,
        contact_fraction,
        max_radius_m,
        resolution_hz,
        spectrum: Vec::new(),
    };
    if n < 8 || motion <= 1e-6f64.max(1e-6 * clearance) {
        return none;
    }
    // Hann-windowed complex signal, mean removed.
    let mut z: Vec<Complex<f64>> = (0..n)
        .map(|k| {
            let w = 0.5 - 0.5 * (std::f64::consts::TAU * k as f64 / n as f64).cos();
            Complex::new(w * (x[k] - mx), w * (y[k] - my))
        })
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut z);
    // Bin k ↔ frequency k/(n dt) for k < n/2, (k − n)/(n dt) above; a circle of radius A
    // gives |Z| = A n / 2 (the window's coherent gain).
    let freq = |k: usize| {
        let k = k as f64;
        let n = n as f64;
        if k < n / 2.0 {
            k / (n * dt)
        } else {
            (k - n) / (n * dt)
        }
    };
    let energy: Vec<f64> = z.iter().map(|c| c.norm_sqr()).collect();
    let total: f64 = energy.iter().sum();
    let peak = (0..n).fold(0, |b, k| if energy[k] > energy[b] { k } else { b });
    let share = (-2i64..=2)
        .map(|d| energy[((peak as i64 + d).rem_euclid(n as i64)) as usize])
        .sum::<f64>()
        / total.max(f64::MIN_POSITIVE);
    let dominant_hz = freq(peak);
    let ratio_to_rotary = if rotary_hz != 0.0 {
        dominant_hz / rotary_hz
    } else {
        0.0
    };
    // Forward means the sense of the string's rotation.
    let sense = if rotary_hz < 0.0 { -1.0 } else { 1.0 };
    let class = if dominant_hz.abs() < 2.0 * resolution_hz {
        WhirlClass::None
    } else if share < PEAK_SHARE {
        WhirlClass::Chaotic
    } else if sense * dominant_hz > 0.0 {
        WhirlClass::Forward
    } else {
        WhirlClass::Backward
    };
    let mut spectrum: Vec<(f64, f64)> = (0..n)
        .map(|k| (freq(k), z[k].norm() * 2.0 / n as f64))
        .collect();
    spectrum.sort_by(|a, b| a.0.total_cmp(&b.0));
    Whirl {
        dominant_hz,
        ratio_to_rotary,
        class,
        peak_share: share,
        synchronous: class == WhirlClass::Forward && (ratio_to_rotary - 1.0).abs() < 0.05,
        contact_fraction,
        max_radius_m,
        resolution_hz,
        spectrum,
    }
}

/// Finest spectrum resolution, as a share of the rotary frequency, at which a whirl is
/// named: coarser, forward synchronous (1×) and half-synchronous (0.5×) whirl fall one
/// bin apart or in the same one.
pub const RESOLUTION_SHARE: f64 = 0.25;

/// Largest change of a mean, as a share of its scale, over an analysis window that is
/// called steady.
pub const STEADY_SHARE: f64 = 0.05;

/// The means of the first and the last quarter of `values`.
pub fn quarter_means(values: &[f64]) -> (f64, f64) {
    let q = (values.len() / 4).max(1);
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    if values.is_empty() {
        return (0.0, 0.0);
    }
    (
        mean(&values[..q.min(values.len())]),
        mean(&values[values.len().saturating_sub(q)..]),
    )
}

/// Why the whirl of a site over an analysis window of `window_s` seconds cannot be read
/// as a steady whirl (empty: it can): the site's spin rate (rad/s, sampled over the
/// window) still changes by more than [`STEADY_SHARE`] of the table's `rotary_hz`, or the
/// spectrum's resolution `1/window` is coarser than [`RESOLUTION_SHARE`] × rotary (with
/// the duration a run would need).
pub fn window_notes(spin: &[f64], rotary_hz: f64, window_s: f64, run_s: f64) -> Vec<String> {
    let mut notes = Vec::new();
    let omega = std::f64::consts::TAU * rotary_hz.abs();
    if omega == 0.0 {
        return notes;
    }
    let (first, last) = quarter_means(spin);
    let rpm = 60.0 / std::f64::consts::TAU;
    if (last - first).abs() > STEADY_SHARE * omega {
        notes.push(format!(
            "not at steady state: the stabilizer's spin goes from {:.1} to {:.1} rpm over the \
             analysis window (the run's second half; table {:.1} rpm): run longer or ramp \
             the table faster",
            first * rpm,
            last * rpm,
            omega * rpm
        ));
    }
    let resolution = 1.0 / window_s;
    if resolution > RESOLUTION_SHARE * rotary_hz.abs() {
        notes.push(format!(
            "the spectrum's resolution {:.3} Hz is {:.2} × the rotary frequency, too coarse \
             to name a whirl (≤ {RESOLUTION_SHARE} × needed): run at least {:.1} s (now {:.1} s)",
            resolution,
            resolution / rotary_hz.abs(),
            2.0 / (RESOLUTION_SHARE * rotary_hz.abs()),
            run_s
        ));
    }
    notes
}

/// Why a run's analysis window (its second half, from `window_start` to the end) is not
/// a steady state (empty: it is): the table still ramping (`ramp_time` past the window's
/// start), or the surface torque's mean changing by more than [`STEADY_SHARE`] of its
/// scale over the window (`torque` sampled over it).
pub fn run_notes(ramp_time: f64, window_start: f64, torque: &[f64]) -> Vec<String> {
    let mut notes = Vec::new();
    if ramp_time > window_start {
        notes.push(format!(
            "not at steady state: the rotary table reaches its speed at t = {ramp_time:.2} s, \
             after the analysis window starts (t = {window_start:.2} s)"
        ));
    }
    let (first, last) = quarter_means(torque);
    let scale = first.abs().max(last.abs());
    if scale > 0.0 && (last - first).abs() > STEADY_SHARE * scale {
        notes.push(format!(
            "not at steady state: the surface torque's mean goes from {:.2} to {:.2} kN·m \
             over the analysis window",
            first / 1e3,
            last / 1e3
        ));
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(f: f64, a: f64, n: usize, dt: f64) -> (Vec<f64>, Vec<f64>) {
        let ph = |k: usize| std::f64::consts::TAU * f * k as f64 * dt;
        (
            (0..n).map(|k| a * ph(k).cos()).collect(),
            (0..n).map(|k| a * ph(k).sin()).collect(),
        )
    }

    #[test]
    fn circles_are_classified_by_sense_and_measured() {
        let (dt, n) = (0.01, 1000);
        // Forward synchronous at 2 Hz (the rotary frequency), radius 3 mm.
        let (x, y) = circle(2.0, 3e-3, n, dt);
        let w = analyse(&x, &y, &vec![1.0; n], dt, 2.0, 0.01);
        assert_eq!(w.class, WhirlClass::Forward);
        assert!(w.synchronous && (w.dominant_hz - 2.0).abs() < 1e-9);
        let amp = w.spectrum.iter().fold(0.0f64, |m, p| m.max(p.1));
        assert!((amp / 3e-3 - 1.0).abs() < 1e-9, "{amp}");
        assert_eq!(w.contact_fraction, 1.0);
        // Backward at −7 Hz against a +2 Hz rotation.
        let (x, y) = circle(-7.0, 1e-3, n, dt);
        let w = analyse(&x, &y, &[], dt, 2.0, 0.01);
        assert_eq!(w.class, WhirlClass::Backward);
        assert!((w.ratio_to_rotary + 3.5).abs() < 1e-9);
        // The same with the string turning the other way is forward.
        assert_eq!(
            analyse(&x, &y, &[], dt, -2.0, 0.01).class,
            WhirlClass::Forward
        );
        // Broadband motion: chaotic.
        let mut s = 12345u64;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s as f64 / u64::MAX as f64) - 0.5
        };
        let x: Vec<f64> = (0..n).map(|_| 1e-3 * rnd()).collect();
        let y: Vec<f64> = (0..n).map(|_| 1e-3 * rnd()).collect();
        let w = analyse(&x, &y, &[], dt, 2.0, 0.01);
        assert_eq!(w.class, WhirlClass::Chaotic, "share {}", w.peak_share);
        // A slow drift (one orbit over the window): none.
        let (x, y) = circle(0.1, 1e-3, n, dt);
        assert_eq!(analyse(&x, &y, &[], dt, 2.0, 0.01).class, WhirlClass::None);
        // At rest: none.
        let w = analyse(&vec![1e-9; n], &vec![0.0; n], &[], dt, 2.0, 0.01);
        assert_eq!(w.class, WhirlClass::None);
    }
}

#[cfg(test)]
mod window_tests {
    use super::*;

    #[test]
    fn a_spin_up_and_a_short_window_are_named() {
        let rotary_hz = 2.0; // 120 rpm
        let omega = std::f64::consts::TAU * rotary_hz;
        // Steady: no notes over a 4 s window (0.25 Hz = 0.125 × rotary).
        let steady = vec![omega; 400];
        assert!(window_notes(&steady, rotary_hz, 4.0, 8.0).is_empty());
        // Spinning up from 0.8 to 1.0 × Ω over the window.
        let ramp: Vec<f64> = (0..400)
            .map(|k| omega * (0.8 + 0.2 * k as f64 / 399.0))
            .collect();
        let n = window_notes(&ramp, rotary_hz, 4.0, 8.0);
        assert_eq!(n.len(), 1);
        assert!(n[0].contains("not at steady state"), "{n:?}");
        // A 1 s window: 1 Hz = 0.5 × rotary.
        let n = window_notes(&steady, rotary_hz, 1.0, 2.0);
        assert_eq!(n.len(), 1);
        assert!(
            n[0].contains("too coarse") && n[0].contains("run at least 4.0 s"),
            "{n:?}"
        );
        // The run: the table ramping into the window, a torque still rising.
        assert_eq!(run_notes(1.5, 1.0, &[10.0; 100]).len(), 1);
        let rising: Vec<f64> = (0..100).map(|k| 10e3 + 30.0 * k as f64).collect();
        assert_eq!(run_notes(0.5, 1.0, &rising).len(), 1);
        assert!(run_notes(0.5, 1.0, &[10e3; 100]).is_empty());
    }
}
