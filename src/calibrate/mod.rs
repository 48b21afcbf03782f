//! Friction factors calibrated from the loads the rig measured (issue 26):
//! `holewall calibrate CASE --measured FILE`.
//!
//! **Data.** A CSV of measurements against bit depth, one per row: `bit_md_m` (or
//! `bit_md_ft`), `mode` (`pick_up`/`tripping_out`, `slack_off`/`tripping_in`, `rotating`
//! (off bottom), `drilling`, `reaming`, `back_reaming`), and a hook load (`hook_load_n`,
//! `hook_load_kn` or `hook_load_klbf`: what the weight indicator showed) and/or a surface
//! torque (`surface_torque_nm`, `surface_torque_knm`, `surface_torque_kftlbf`; rotating
//! modes only); `wob_n`/`wob_kn`/`wob_klbf` for drilling rows, `rpm` where the rows rotate
//! at another speed than the case's. The model's hook load is what the case's `[rig]`
//! indicator reads ([`crate::rig`]), else the string's load at the top.
//!
//! **Unknowns.** The friction factor of the cased hole (`mu.cased`) and of the open hole
//! (`mu.open`), whichever sections the case has: one or two unknowns.
//!
//! **Posterior (a Bayesian grid).** The FE static model runs at every measured station
//! (depth, mode, WOB, rpm) on a grid of `nodes` friction values per unknown (the ensemble
//! machinery, one variant per station and node); a natural cubic spline per axis (tensor
//! product) interpolates the modelled loads onto a fine grid (`FINE` points per axis). The
//! noise model: hook loads and torques carry independent Gaussian errors of standard
//! deviations `σ_h`, `σ_t`, given or unknown; unknown ones are integrated out under
//! Jeffreys' prior `1/σ`, which leaves `p(μ | data) ∝ SSR_h(μ)^(−N_h/2) · SSR_t(μ)^(−N_t/2)`
//! (Gelman et al., *Bayesian Data Analysis*, §3.2); given ones give
//! `exp(−SSR_h/2σ_h² − SSR_t/2σ_t²)`. The prior on μ is uniform on the grid's range.
//! Reported: the marginal mean, standard deviation and central 95 % interval of each
//! factor, their correlation, the joint mode (MAP).
//!
//! **Checks.** The FE runs again at the MAP at every station: its residuals (measured −
//! modelled) are the ones written and plotted, and their difference from the spline's is
//! the surrogate's error (reported). The calibration is **rejected** (exit code 1, every
//! output still written) when a mode's residuals, or every mode's together, trend with
//! depth (least-squares slope, two-sided p < 0.001 by Student's t — friction cannot make a
//! load error that grows with depth; a wrong string weight or survey can), when per-mode
//! offsets and depth trends explain the residuals far better than the friction factors
//! alone (a lack-of-fit F-test, p < 0.001), or, with a stated noise, when the residuals
//! exceed it (χ², p < 0.001). A MAP on the range's edge,
//! an interval reaching it or a surrogate error above a quarter of the noise are warnings.

use serde::Serialize;

use crate::case::Case;
use crate::ensemble::{Key, Value, Variant};
use crate::error::{Error, InputError};

/// Fine-grid points per unknown for the posterior.
pub const FINE: usize = 161;

pub mod report;
pub mod stats;
pub mod synthetic;

pub use crate::ensemble::measured::{
    by_mode, modes_of, parse_measured, read_measured, MeasuredMode, Measurement,
};
pub use stats::LackOfFit;
use stats::{fill_from_neighbours, lack_of_fit, linspace, spline_weights, trend};

/// A modelled station: what one FE run gives for the rows measured there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Station {
    /// Bit depth (m).
    pub bit_md: f64,
    /// Operation.
    pub mode: MeasuredMode,
    /// Weight on bit (N).
    pub wob: f64,
    /// Rotary speed (rad/s), or the case's.
    pub rpm: Option<f64>,
}

/// The distinct stations of `rows`, and each row's station.
pub fn stations(rows: &[Measurement]) -> (Vec<Station>, Vec<usize>) {
    let mut st: Vec<Station> = Vec::new();
    let idx = rows
        .iter()
        .map(|r| {
            let s = Station {
                bit_md: r.bit_md,
                mode: r.mode,
                wob: r.wob,
                rpm: r.rpm,
            };
            st.iter().position(|x| *x == s).unwrap_or_else(|| {
                st.push(s);
                st.len() - 1
            })
        })
        .collect();
    (st, idx)
}

/// The friction keys a case's hole calls for: `mu.cased` where it has a cased section,
/// `mu.open` where it has an open one.
pub fn unknowns(case: &Case) -> Vec<Key> {
    let mut k = Vec::new();
    if case.hole.iter().any(|h| h.cased) {
        k.push(Key::parse("mu.cased").expect("a known key"));
    }
    if case.hole.iter().any(|h| !h.cased) {
        k.push(Key::parse("mu.open").expect("a known key"));
    }
    k
}

/// The variant of `station` with the friction factors `mu` (one per key of `keys`).
pub fn station_variant(name: String, station: &Station, keys: &[Key], mu: &[f64]) -> Variant {
    let key = |n: &str| Key::parse(n).expect("a known key");
    let number = |n: &str, x: f64| (key(n), Value::Number(x));
    let mut overrides = vec![
        number("depth", station.bit_md),
        (key("mode"), Value::Mode(station.mode.model_mode())),
    ];
    if station.mode == MeasuredMode::Drilling {
        overrides.push(number("wob", station.wob));
    }
    if let Some(r) = station.rpm {
        overrides.push(number("rpm", r));
    }
    overrides.extend(
        keys.iter()
            .cloned()
            .zip(mu.iter().map(|&m| Value::Number(m))),
    );
    Variant { name, overrides }
}

/// Modelled (hook load as read, surface torque) of one variant's result: the `[rig]`
/// indicator's reading where the case has one.
fn modelled(r: &crate::ensemble::qoi::VariantResult) -> Option<(f64, f64)> {
    if r.status == crate::ensemble::qoi::Status::Failed {
        return None;
    }
    let hook = r.weight_indicator_n.or(r.hook_load_n)?;
    Some((hook, r.max_surface_torque_nm))
}

/// The FE model's (hook load as read, surface torque) at every station with friction `mu`;
/// `Err` names the first station that failed.
pub fn model_at(
    case: &Case,
    stations: &[Station],
    keys: &[Key],
    mu: &[f64],
    bar: &indicatif::ProgressBar,
) -> Result<Vec<(f64, f64)>, Error> {
    let variants: Vec<Variant> = stations
        .iter()
        .enumerate()
        .map(|(i, s)| station_variant(format!("s{i}"), s, keys, mu))
        .collect();
    let results = crate::ensemble::runner::run_variants_cpu(
        case,
        crate::case::Analysis::Static,
        &variants,
        bar,
    );
    results
        .iter()
        .zip(stations)
        .map(|(r, s)| {
            modelled(r).ok_or_else(|| {
                Error::failed(format!(
                    "the model failed at {} m {} with {mu:?}: {}",
                    s.bit_md,
                    s.mode.name(),
                    r.reason
                ))
            })
        })
        .collect()
}

/// Options of [`calibrate`].
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    /// Grid nodes per unknown (FE runs at each).
    pub nodes: usize,
    /// Range of every friction factor.
    pub range: (f64, f64),
    /// Hook-load noise (N); `None`: unknown, integrated out.
    pub sigma_hook: Option<f64>,
    /// Torque noise (N·m); `None`: unknown, integrated out.
    pub sigma_torque: Option<f64>,
    /// No model run starts past this instant.
    pub deadline: Option<std::time::Instant>,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            nodes: 9,
            range: (0.05, 0.6),
            sigma_hook: None,
            sigma_torque: None,
            deadline: None,
        }
    }
}

/// One calibrated friction factor.
#[derive(Clone, Debug, Serialize)]
pub struct Estimate {
    /// Its key (`mu.cased`, `mu.open`).
    pub key: String,
    /// The joint posterior's mode.
    pub map: f64,
    /// Marginal mean.
    pub mean: f64,
    /// Marginal standard deviation.
    pub sd: f64,
    /// Central 95 % interval of the marginal.
    pub interval_95: (f64, f64),
}

/// One row's residual at the MAP.
#[derive(Clone, Debug, Serialize)]
pub struct Residual {
    /// Line in the measured file.
    pub line: usize,
    /// Bit depth (m).
    pub bit_md_m: f64,
    /// Mode.
    pub mode: MeasuredMode,
    /// Measured hook load (N).
    pub hook_load_measured_n: Option<f64>,
    /// Modelled (N).
    pub hook_load_modelled_n: f64,
    /// Measured − modelled (N).
    pub hook_load_residual_n: Option<f64>,
    /// Measured surface torque (N·m).
    pub torque_measured_nm: Option<f64>,
    /// Modelled (N·m).
    pub torque_modelled_nm: f64,
    /// Measured − modelled (N·m).
    pub torque_residual_nm: Option<f64>,
}

/// A mode's residual trend with depth (least squares).
#[derive(Clone, Debug, Serialize)]
pub struct Trend {
    /// Mode (`pick_up`, …), or `all` for every mode's residuals together.
    pub mode: &'static str,
    /// `hook_load` or `torque`.
    pub quantity: &'static str,
    /// Rows.
    pub rows: usize,
    /// Mean residual (N or N·m).
    pub mean: f64,
    /// RMS residual.
    pub rms: f64,
    /// Slope per 1000 m of depth.
    pub slope_per_km: f64,
    /// Two-sided p-value of a zero slope (Student's t, rows − 2 degrees of freedom).
    pub p_value: Option<f64>,
}

/// What [`calibrate`] found.
#[derive(Clone, Debug, Serialize)]
pub struct Calibration {
    /// The friction factors.
    pub estimates: Vec<Estimate>,
    /// Correlation of the two factors' posterior (two unknowns).
    pub correlation: Option<f64>,
    /// Hook-load noise: the given σ, or the residuals' RMS at the MAP (N).
    pub hook_load_sigma_n: Option<f64>,
    /// Whether that σ was given.
    pub sigma_given: bool,
    /// Torque noise, likewise (N·m).
    pub torque_sigma_nm: Option<f64>,
    /// Largest |spline − FE| at the MAP over the stations: hook load (N), torque (N·m).
    pub surrogate_error: (f64, f64),
    /// Per mode and quantity: the residuals' mean, RMS and trend with depth.
    pub trends: Vec<Trend>,
    /// Residual per row at the MAP.
    pub residuals: Vec<Residual>,
    /// The lack-of-fit F-tests (hook load, torque): per-mode offsets and depth trends
    /// against the friction factors alone.
    pub lack_of_fit: Vec<(&'static str, LackOfFit)>,
    /// FE runs.
    pub model_runs: usize,
    /// Whether the friction factors explain the data.
    pub accepted: bool,
    /// Why not.
    pub rejected_because: Vec<String>,
    /// Worth a look (a posterior running into the grid's edge …).
    pub warnings: Vec<String>,
    /// The grid: nodes of each unknown's fine axis.
    #[serde(skip)]
    pub fine: Vec<Vec<f64>>,
    /// The posterior on the fine grid (`[i][j]`; one row for one unknown), normalised to
    /// sum 1.
    #[serde(skip)]
    pub posterior: Vec<Vec<f64>>,
    /// Keys of the unknowns.
    #[serde(skip)]
    pub keys: Vec<Key>,
}

/// Calibrates the case's friction factors against `rows`.
pub fn calibrate(
    case: &Case,
    rows: &[Measurement],
    opts: &CalibrateOptions,
    bar: &indicatif::ProgressBar,
) -> Result<Calibration, Error> {
    let keys = unknowns(case);
    let (st, at) = stations(rows);
    let deepest = case.hole.last().map_or(0.0, |h| h.bottom_md);
    if let Some(r) = rows.iter().find(|r| r.bit_md > deepest + 1e-6) {
        return Err(InputError {
            source_name: "--measured".into(),
            line: r.line,
            key: "bit_md_m".into(),
            message: format!(
                "bit depth {} m is below the case's hole ({} m)",
                r.bit_md, deepest
            ),
        }
        .into());
    }
    let d = keys.len();
    let grid = linspace(opts.range.0, opts.range.1, opts.nodes);
    // Every node of the tensor grid (first unknown slowest), then every station.
    let node_count = opts.nodes.pow(d as u32);
    let node_mu = |k: usize| -> Vec<f64> {
        let mut mu = vec![0.0; d];
        let mut r = k;
        for a in (0..d).rev() {
            mu[a] = grid[r % opts.nodes];
            r /= opts.nodes;
        }
        mu
    };
    let variants: Vec<Variant> = (0..node_count)
        .flat_map(|k| {
            let mu = node_mu(k);
            st.iter()
                .enumerate()
                .map(|(i, s)| station_variant(format!("n{k}s{i}"), s, &keys, &mu))
                .collect::<Vec<_>>()
        })
        .collect();
    bar.set_length((variants.len() + st.len()) as u64);
    let results = run_until(case, &variants, opts.deadline, bar)?;
    // Modelled loads per station per node; a node whose FE run failed at some station (a
    // slack-off that locks up, a solve that does not converge) is filled from its grid
    // neighbours for the spline, and the posterior is zero around it.
    let mut hook = vec![vec![0.0; node_count]; st.len()];
    let mut torque = vec![vec![0.0; node_count]; st.len()];
    let mut failed_node = vec![false; node_count];
    let mut failures: Vec<String> = Vec::new();
    for (k, r) in results.iter().enumerate() {
        let (node, s) = (k / st.len(), k % st.len());
        match modelled(r) {
            Some((h, t)) => {
                hook[s][node] = h;
                torque[s][node] = t;
            }
            None => {
                hook[s][node] = f64::NAN;
                torque[s][node] = f64::NAN;
                failed_node[node] = true;
                failures.push(format!(
                    "{} m {} at {:?}: {}",
                    st[s].bit_md,
                    st[s].mode.name(),
                    node_mu(node),
                    r.reason.chars().take(160).collect::<String>()
                ));
            }
        }
    }
    if failed_node.iter().all(|f| *f) {
        return Err(Error::failed(format!(
            "the model failed at every grid node (e.g. {})",
            failures.first().cloned().unwrap_or_default()
        )));
    }
    for values in hook.iter_mut().chain(torque.iter_mut()) {
        fill_from_neighbours(values, opts.nodes, d);
    }
    // The fine grid and the spline weights per axis.
    let fine = linspace(opts.range.0, opts.range.1, FINE);
    let weights: Vec<Vec<f64>> = fine.iter().map(|&x| spline_weights(&grid, x)).collect();
    let fine_count = FINE.pow(d as u32);
    // Surrogate of station s's loads at fine point f (first unknown slowest).
    let surrogate = |values: &[f64], f: usize| -> f64 {
        match d {
            1 => (0..opts.nodes).map(|i| weights[f][i] * values[i]).sum(),
            _ => {
                let (fi, fj) = (f / FINE, f % FINE);
                let mut sum = 0.0;
                for i in 0..opts.nodes {
                    let wi = weights[fi][i];
                    if wi == 0.0 {
                        continue;
                    }
                    for j in 0..opts.nodes {
                        sum += wi * weights[fj][j] * values[i * opts.nodes + j];
                    }
                }
                sum
            }
        }
    };
    let n_h = rows.iter().filter(|r| r.hook_load.is_some()).count();
    let n_t = rows.iter().filter(|r| r.surface_torque.is_some()).count();
    // A fine point is left out when the grid node nearest it failed.
    let h_grid = grid.get(1).map_or(1.0, |g| g - grid[0]);
    let nearest = |x: f64| -> usize {
        (((x - grid[0]) / h_grid).round().max(0.0) as usize).min(opts.nodes - 1)
    };
    let masked = |f: usize| -> bool {
        let node = match d {
            1 => nearest(fine[f]),
            _ => nearest(fine[f / FINE]) * opts.nodes + nearest(fine[f % FINE]),
        };
        failed_node[node]
    };
    let log_post: Vec<f64> = {
        use rayon::prelude::*;
        (0..fine_count)
            .into_par_iter()
            .map(|f| {
                if masked(f) {
                    return f64::NEG_INFINITY;
                }
                let pred: Vec<(f64, f64)> = (0..st.len())
                    .map(|s| (surrogate(&hook[s], f), surrogate(&torque[s], f)))
                    .collect();
                let (mut ssr_h, mut ssr_t) = (0.0, 0.0);
                for (r, &s) in rows.iter().zip(&at) {
                    if let Some(h) = r.hook_load {
                        ssr_h += (h - pred[s].0).powi(2);
                    }
                    if let Some(t) = r.surface_torque {
                        ssr_t += (t - pred[s].1).powi(2);
                    }
                }
                let term = |ssr: f64, n: usize, sigma: Option<f64>| match (n, sigma) {
                    (0, _) => 0.0,
                    (_, Some(s)) => -ssr / (2.0 * s * s),
                    (n, None) => -0.5 * n as f64 * (ssr + 1e-300).ln(),
                };
                term(ssr_h, n_h, opts.sigma_hook) + term(ssr_t, n_t, opts.sigma_torque)
            })
            .collect()
    };
    let top = log_post.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut post: Vec<f64> = log_post.iter().map(|l| (l - top).exp()).collect();
    let total: f64 = post.iter().sum();
    post.iter_mut().for_each(|p| *p /= total);
    let map_index = (0..fine_count)
        .max_by(|&a, &b| post[a].total_cmp(&post[b]))
        .unwrap_or(0);
    let coord = |f: usize, a: usize| -> usize {
        if d == 1 {
            f
        } else if a == 0 {
            f / FINE
        } else {
            f % FINE
        }
    };
    let mut estimates = Vec::new();
    let mut means = vec![0.0; d];
    for (a, key) in keys.iter().enumerate() {
        let mut marginal = vec![0.0; FINE];
        for (f, p) in post.iter().enumerate() {
            marginal[coord(f, a)] += p;
        }
        let mean: f64 = marginal.iter().zip(&fine).map(|(p, x)| p * x).sum();
        let var: f64 = marginal
            .iter()
            .zip(&fine)
            .map(|(p, x)| p * (x - mean).powi(2))
            .sum();
        means[a] = mean;
        let quantile = |q: f64| -> f64 {
            // Each fine point holds its mass over its cell; linear within the cell.
            let h = fine[1] - fine[0];
            let mut acc = 0.0;
            for (i, p) in marginal.iter().enumerate() {
                if acc + p >= q {
                    let t = if *p > 0.0 { (q - acc) / p } else { 0.5 };
                    return (fine[i] - 0.5 * h + t * h).clamp(opts.range.0, opts.range.1);
                }
                acc += p;
            }
            opts.range.1
        };
        estimates.push(Estimate {
            key: key.name.clone(),
            map: fine[coord(map_index, a)],
            mean,
            sd: var.sqrt(),
            interval_95: (quantile(0.025), quantile(0.975)),
        });
    }
    let correlation = (d == 2).then(|| {
        let (mut cxy, mut cxx, mut cyy) = (0.0, 0.0, 0.0);
        for (f, p) in post.iter().enumerate() {
            let (x, y) = (fine[f / FINE] - means[0], fine[f % FINE] - means[1]);
            cxy += p * x * y;
            cxx += p * x * x;
            cyy += p * y * y;
        }
        cxy / (cxx * cyy).sqrt().max(f64::MIN_POSITIVE)
    });
    // The FE at the MAP: residuals and the surrogate's error.
    let map_mu: Vec<f64> = estimates.iter().map(|e| e.map).collect();
    if opts.deadline.is_some_and(|t| std::time::Instant::now() > t) {
        return Err(Error::Stopped(
            "calibrate: --max-seconds spent before the check at the MAP; nothing written \
             beyond the grid (a new run starts over)"
                .into(),
        ));
    }
    let at_map = model_at(case, &st, &keys, &map_mu, bar)?;
    let mut surrogate_error: (f64, f64) = (0.0, 0.0);
    for (s, m) in at_map.iter().enumerate() {
        surrogate_error.0 = surrogate_error
            .0
            .max((surrogate(&hook[s], map_index) - m.0).abs());
        if st[s].mode.rotates() {
            surrogate_error.1 = surrogate_error
                .1
                .max((surrogate(&torque[s], map_index) - m.1).abs());
        }
    }
    let residuals: Vec<Residual> = rows
        .iter()
        .zip(&at)
        .map(|(r, &s)| Residual {
            line: r.line,
            bit_md_m: r.bit_md,
            mode: r.mode,
            hook_load_measured_n: r.hook_load,
            hook_load_modelled_n: at_map[s].0,
            hook_load_residual_n: r.hook_load.map(|h| h - at_map[s].0),
            torque_measured_nm: r.surface_torque,
            torque_modelled_nm: at_map[s].1,
            torque_residual_nm: r.surface_torque.map(|t| t - at_map[s].1),
        })
        .collect();
    let mut trends = Vec::new();
    let mut rejected = Vec::new();
    let mut warnings = Vec::new();
    // Per mode, then every mode together (a wrong string weight shifts them all alike).
    let groups: Vec<(&'static str, Option<MeasuredMode>)> = std::iter::once(("all", None))
        .chain(
            MeasuredMode::NAMES
                .iter()
                .map(|(m, _)| (m.name(), Some(*m))),
        )
        .collect();
    let mut lack_of_fit_notes: Vec<(&'static str, LackOfFit)> = Vec::new();
    let several_modes = MeasuredMode::NAMES
        .iter()
        .filter(|(m, _)| rows.iter().any(|r| r.mode == *m))
        .count()
        > 1;
    for (group, mode) in groups {
        if mode.is_none() && !several_modes {
            continue;
        }
        for (quantity, pick) in [
            (
                "hook_load",
                (|r: &Residual| r.hook_load_residual_n) as fn(&Residual) -> Option<f64>,
            ),
            ("torque", |r: &Residual| r.torque_residual_nm),
        ] {
            let pts: Vec<(f64, f64)> = residuals
                .iter()
                .filter(|r| mode.is_none_or(|m| r.mode == m))
                .filter_map(|r| pick(r).map(|x| (r.bit_md_m, x)))
                .collect();
            if pts.is_empty() {
                continue;
            }
            let (mean, rms, slope, p) = trend(&pts);
            if let Some(p) = p.filter(|p| *p < 1e-3) {
                let unit = if quantity == "torque" { "kN·m" } else { "kN" };
                let whose = match mode {
                    Some(m) => format!("of {}", m.name()),
                    None => "of every mode together".into(),
                };
                rejected.push(format!(
                    "the {} residuals {whose} trend with depth ({:+.1} {unit} per 1000 m, p = \
                     {p:.1e}): friction does not make a load error that grows with depth — \
                     check the string (weights, lengths) and the survey",
                    quantity.replace('_', " "),
                    slope * 1e-3
                ));
            }
            trends.push(Trend {
                mode: group,
                quantity,
                rows: pts.len(),
                mean,
                rms,
                slope_per_km: slope,
                p_value: p,
            });
        }
    }
    // Lack of fit: do per-mode offsets and trends with depth explain the residuals
    // significantly better than the friction factors alone? (F-test, p < 0.001.)
    for (quantity, pick) in [
        (
            "hook load",
            (|r: &Residual| r.hook_load_residual_n) as fn(&Residual) -> Option<f64>,
        ),
        ("torque", |r: &Residual| r.torque_residual_nm),
    ] {
        let groups: Vec<Vec<(f64, f64)>> = MeasuredMode::NAMES
            .iter()
            .map(|(m, _)| {
                residuals
                    .iter()
                    .filter(|r| r.mode == *m)
                    .filter_map(|r| pick(r).map(|x| (r.bit_md_m, x)))
                    .collect::<Vec<_>>()
            })
            .filter(|g| !g.is_empty())
            .collect();
        if let Some(f) = lack_of_fit(&groups, d) {
            lack_of_fit_notes.push((quantity, f));
            if f.p_value < 1e-3 {
                rejected.push(format!(
                    "the {quantity} residuals have a structure friction cannot make: per-mode \
                     offsets and trends with depth explain them far better (F = {:.1} on {} \
                     and {} degrees of freedom, p = {:.1e}) — check the string (weights, \
                     lengths), the survey and the rig's reading",
                    f.f, f.df1, f.df2, f.p_value
                ));
            }
        }
    }
    for e in &estimates {
        let h = fine[1] - fine[0];
        if e.map <= opts.range.0 + 0.5 * h || e.map >= opts.range.1 - 0.5 * h {
            // A warning, not a rejection: a weakly constrained factor (a ridge of the
            // posterior) can peak anywhere along it.
            warnings.push(format!(
                "{}'s best value {:.3} is on the edge of the range {}–{}: the data ask for a \
                 friction factor there or beyond (or they hardly constrain it: see its 95 % \
                 interval); widen --mu-range only if such a value is physical",
                e.key, e.map, opts.range.0, opts.range.1
            ));
        } else if e.interval_95.0 <= opts.range.0 + h || e.interval_95.1 >= opts.range.1 - h {
            warnings.push(format!(
                "{}'s 95 % interval {:.3}–{:.3} reaches the range's edge: the data constrain \
                 it weakly (add pick-up and slack-off rows with the bit in that section)",
                e.key, e.interval_95.0, e.interval_95.1
            ));
        }
    }
    let rms = |v: Vec<f64>| -> Option<f64> {
        (!v.is_empty()).then(|| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt())
    };
    let hook_rms = rms(residuals
        .iter()
        .filter_map(|r| r.hook_load_residual_n)
        .collect());
    let torque_rms = rms(residuals
        .iter()
        .filter_map(|r| r.torque_residual_nm)
        .collect());
    // With a stated noise: the residuals against it (χ², p < 0.001).
    for (given, n, rms, what) in [
        (opts.sigma_hook, n_h, hook_rms, "hook-load"),
        (opts.sigma_torque, n_t, torque_rms, "torque"),
    ] {
        if let (Some(s), Some(rms)) = (given, rms) {
            use statrs::distribution::{ChiSquared, ContinuousCDF};
            let dof = (n as f64 - d as f64).max(1.0);
            let chi2 = n as f64 * rms * rms / (s * s);
            if let Ok(c) = ChiSquared::new(dof) {
                if 1.0 - c.cdf(chi2) < 1e-3 {
                    rejected.push(format!(
                        "the {what} residuals (RMS {rms:.4e}) are larger than the stated noise \
                         {s:.4e} allows (χ² = {chi2:.1} on {dof} degrees of freedom)"
                    ));
                }
            }
        }
    }
    for (e, what, sigma) in [
        (surrogate_error.0, "hook load", opts.sigma_hook.or(hook_rms)),
        (
            surrogate_error.1,
            "torque",
            opts.sigma_torque.or(torque_rms),
        ),
    ] {
        if let Some(s) = sigma.filter(|s| *s > 0.0 && e > 0.25 * s) {
            warnings.push(format!(
                "the spline between the grid's nodes is {e:.3e} off the FE's {what} at the \
                 MAP, more than a quarter of the noise ({s:.3e}): use more --nodes"
            ));
        }
    }
    if !failures.is_empty() {
        warnings.push(format!(
            "{} of {} model runs failed, at {} of {} grid nodes; the posterior is zero around \
             those nodes (first: {})",
            failures.len(),
            variants.len(),
            failed_node.iter().filter(|f| **f).count(),
            node_count,
            failures[0]
        ));
    }
    let fine_axes = vec![fine.clone(); d];
    let posterior = if d == 2 {
        (0..FINE)
            .map(|i| post[i * FINE..(i + 1) * FINE].to_vec())
            .collect()
    } else {
        vec![post.clone()]
    };
    Ok(Calibration {
        accepted: rejected.is_empty(),
        rejected_because: rejected,
        warnings,
        estimates,
        correlation,
        hook_load_sigma_n: opts.sigma_hook.or(hook_rms),
        sigma_given: opts.sigma_hook.is_some() || opts.sigma_torque.is_some(),
        torque_sigma_nm: opts.sigma_torque.or(torque_rms),
        surrogate_error,
        trends,
        residuals,
        lack_of_fit: lack_of_fit_notes,
        model_runs: variants.len() + st.len(),
        fine: fine_axes,
        posterior,
        keys,
    })
}

/// Runs `variants` on the CPU, none starting past `deadline` (then [`Error::Stopped`]).
fn run_until(
    case: &Case,
    variants: &[Variant],
    deadline: Option<std::time::Instant>,
    bar: &indicatif::ProgressBar,
) -> Result<Vec<crate::ensemble::qoi::VariantResult>, Error> {
    let mut out = Vec::with_capacity(variants.len());
    for chunk in variants.chunks(64) {
        if deadline.is_some_and(|t| std::time::Instant::now() > t) {
            return Err(Error::Stopped(format!(
                "calibrate: --max-seconds spent after {} of {} model runs; nothing written (a \
                 new run starts over: fewer --nodes or rows, or a larger budget)",
                out.len(),
                variants.len()
            )));
        }
        out.extend(crate::ensemble::runner::run_variants_cpu(
            case,
            crate::case::Analysis::Static,
            chunk,
            bar,
        ));
    }
    Ok(out)
}
