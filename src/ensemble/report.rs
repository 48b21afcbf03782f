//! A finished run's outputs: `variants.csv`, the Monte Carlo statistics and plots, the
//! broomstick, and `summary.json`'s shape.

use std::path::Path;

use serde::Serialize;

use super::qoi::*;
use crate::case::Case;
use crate::ensemble::Variant;
use crate::error::Error;
use crate::model::Model;

/// The command's summary.
#[derive(Clone, Debug, Serialize)]
pub struct EnsembleSummary {
    /// Case title.
    pub title: String,
    /// What the case holds that is allowed but unusual ([`crate::case::Case::warnings`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// `static` or `dynamic`.
    pub analysis: String,
    /// Where it ran.
    pub backend: String,
    /// Why variants ran on the CPU although the GPU engine was chosen (the case needs what
    /// only the CPU integrator has, or the variants' meshes differ); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backend_note: Option<String>,
    /// Float type of the engine (`f64`, or `f32` on the GPU); failed f32 variants re-run
    /// on the CPU in f64.
    pub precision: String,
    /// Variants run.
    pub variants: usize,
    /// Converged without cuts.
    pub converged: usize,
    /// Converged with step cuts: the variants whose `step_cuts` column in `variants.csv`
    /// is above 0 (a re-run on the CPU is counted in `solved_by_cpu`, not here).
    pub step_cut: usize,
    /// Failed.
    pub failed: usize,
    /// Names and reasons of the failed variants.
    pub failures: Vec<(String, String)>,
    /// Solved static variants whose equilibrium lies outside the hole where no contact site
    /// holds it (`variants.csv`: `outside_hole_m`; [`crate::diagnose::through_wall`]).
    pub outside_hole: usize,
    /// Failed static variants whose load path bracketed where the string stops (a
    /// lock-up; `variants.csv`: `stopped_load_factor`).
    #[serde(default)]
    pub stopped: usize,
    /// Solved static variants whose hook load is below zero (`variants.csv`:
    /// `hook_load_n`): the string pushed from the surface, an equilibrium past the weight
    /// indicator's lock-up that a string run in does not reach by its own weight
    /// ([`crate::diagnose::locked_up_warning`]; the corpus's `solved_pushed`).
    #[serde(default)]
    pub pushed: usize,
    /// Of the stopped, the variants whose string stands pushed from the surface where it stops
    /// (`variants.csv`: `stopped_hook_load_n` below zero): the weight indicator reached
    /// zero before the string stopped.
    #[serde(default)]
    pub stopped_pushed: usize,
    /// Solved static variants whose equilibrium came by relaxation past a fold, one of
    /// several — dynamic: variants whose static start did (`variants.csv`: `relaxed`;
    /// [`crate::diagnose::relaxed_variants`]).
    #[serde(default)]
    pub relaxed: usize,
    /// Variants the kernel engine solved.
    pub solved_by_engine: usize,
    /// Variants the CPU solved: all of them on the CPU backend; on the GPU backend, the
    /// engine's failures re-run there (each one's reason gives the engine's failure).
    pub solved_by_cpu: usize,
    /// Wall time of the variant runs (s).
    pub seconds: f64,
    /// Of the dynamic variant runs computed in this invocation on the engine, its phases
    /// (s): the static starts, the dynamic runs and, of those, observing the states
    /// ([`crate::tally`]); absent where no dynamic run used the engine (a static ensemble
    /// included).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub engine_seconds: Option<EngineSeconds>,
    /// Statistics and sensitivities of the quantities of interest (`--samples` runs).
    pub uncertainty: Option<crate::uq::report::UncertaintyReport>,
    /// Files written.
    pub outputs: Vec<String>,
}

/// The engine's phases in an ensemble run ([`EnsembleSummary::engine_seconds`]).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct EngineSeconds {
    /// The variants' static starts on the engine (held in the hole).
    pub static_starts: f64,
    /// The dynamic runs on the engine, observation included.
    pub dynamics: f64,
    /// Of those, observing the variants' states at every output step.
    pub observing: f64,
}

impl EngineSeconds {
    /// The phases counted between `before` and now, if the engine ran.
    pub fn since(before: &crate::tally::Tally) -> Option<Self> {
        let d = crate::tally::Tally::now().since(before);
        (d.static_starts_s + d.dynamics_s > 0.0).then_some(EngineSeconds {
            static_starts: d.static_starts_s,
            dynamics: d.dynamics_s,
            observing: d.observing_s,
        })
    }
}

impl EnsembleSummary {
    /// What a user should read even with `--quiet` (the library prints nothing): the case's
    /// warnings, why the engine was not used, how many variants the engine failed and the
    /// CPU re-ran.
    pub fn notices(&self) -> Vec<String> {
        let mut n: Vec<String> = self
            .warnings
            .iter()
            .map(|w| format!("warning: {w}"))
            .collect();
        if let Some(note) = &self.backend_note {
            n.push(format!("note: {note}"));
        }
        if self.outside_hole > 0 {
            n.push(format!(
                "warning: {} of {} variants solved with the string outside the hole between \
                 its contact sites (variants.csv: outside_hole_m): equilibria of a string in no \
                 hole, whose side forces mean nothing; contact.sites = \"all_nodes\" holds it",
                self.outside_hole, self.variants
            ));
        }
        if self.stopped > 0 {
            n.push(format!(
                "{} of {} variants stop on their way (a lock-up): no equilibrium found at their \
                 loads; variants.csv's stopped_load_factor gives the largest fraction of the \
                 friction and bit loads at which each has one, and its stopped_* columns the \
                 string there (hook load, surface torque, largest side force) — one of a \
                 buckled, friction-held string's several equilibria, which the path chose \
                 (the CPU's and the engine's hook loads there 0.06–8.5 % apart on the \
                 lock-ups measured, docs/validation.md){}",
                self.stopped,
                self.variants,
                match self.stopped_pushed {
                    0 => String::new(),
                    k => format!(
                        "; {k} of them stand pushed from the surface there (a hook load below \
                         zero): their weight indicator reads zero before they stop"
                    ),
                }
            ));
        }
        if self.pushed > 0 {
            n.push(format!(
                "warning: {} of {} variants solved pushed from the surface (variants.csv: \
                 hook_load_n below zero): equilibria past the weight indicator's lock-up, which \
                 a string run in does not reach by its own weight",
                self.pushed, self.variants
            ));
        }
        let dynamic = self.analysis == "dynamic";
        if let Some(w) = crate::diagnose::relaxed_variants(self.relaxed, self.variants, dynamic) {
            n.push(format!("warning: {w}"));
        }
        if self.backend == "gpu" && self.solved_by_cpu > 0 {
            n.push(format!(
                "the engine failed {} of {} variants; they were re-run on the CPU \
                 (variants.csv: solved_by, reason)",
                self.solved_by_cpu, self.variants
            ));
        }
        n
    }

    /// A few lines for the terminal: counts, who solved what, the first failures, where
    /// the rest is.
    pub fn digest(&self, out: &std::path::Path) -> String {
        let mut t = format!(
            "{}: {} variants ({}, {} {}) in {:.1} s — {} converged, {} with step cuts, {} failed; \
             solved by the engine {}, by the CPU {}",
            self.title,
            self.variants,
            self.analysis,
            self.backend,
            self.precision,
            self.seconds,
            self.converged,
            self.step_cut,
            self.failed,
            self.solved_by_engine,
            self.solved_by_cpu
        );
        for (name, why) in self.failures.iter().take(3) {
            t.push_str(&format!("\n  failed {name}: {why}"));
        }
        if self.failures.len() > 3 {
            t.push_str(&format!("\n  … {} more failures", self.failures.len() - 3));
        }
        if let Some(u) = &self.uncertainty {
            let lines = [
                ("stops on its way (a lock-up)", &u.stops),
                (
                    "past the weight indicator's lock-up (pushed from the surface, or stopped)",
                    &u.past_weight_lock_up,
                ),
            ];
            for (what, p) in lines {
                if let Some(p) = p {
                    t.push_str(&format!(
                        "\n  {what}: {} of {} runs, probability {:.3} (95 %: {:.3}–{:.3})",
                        p.count, p.of, p.probability, p.ci95.0, p.ci95.1
                    ));
                }
            }
        }
        t.push_str(&format!(
            "\n  everything else: {}",
            out.join("summary.json").display()
        ));
        t
    }
}

/// A solved static variant the surface pushes (hook load below zero: past the weight
/// indicator's lock-up; [`EnsembleSummary::pushed`]).
pub(crate) fn pushed(r: &VariantResult) -> bool {
    r.status != Status::Failed && r.hook_load_n.is_some_and(|h| h < 0.0)
}

/// How far a variant's loads get: 1 where it reaches them, its stopped load factor where it
/// stops on its way (a lock-up), NaN where it failed otherwise.
pub(crate) fn loads_reached(r: &VariantResult) -> f64 {
    match (r.string.stopped_load_factor, r.status) {
        (Some(at), _) => at,
        (None, Status::Failed) => f64::NAN,
        (None, _) => 1.0,
    }
}

/// `variants.csv`'s columns of a variant that stops on its way ([`StringQoi`]'s
/// `stopped_load_factor` and `stands`).
pub const STOPPED_COLUMNS: [&str; 5] = [
    "stopped_load_factor",
    "stopped_hook_load_n",
    "stopped_surface_torque_nm",
    "stopped_max_side_force_per_length_n_per_m",
    "stopped_max_side_force_md_m",
];

pub(crate) fn fmt(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

/// `variants.csv`: per variant its overrides, what it ran with (`ran_rows`, [`ran_row`]) and
/// its quantities.
pub(crate) fn variants_csv(
    case: &Case,
    variants: &[Variant],
    ran_rows: &[Vec<String>],
    results: &[VariantResult],
    stabs: usize,
    dynamic: bool,
) -> Result<Vec<u8>, Error> {
    let ran_header = ran_header(stabs);
    let io = Error::from;
    let mut keys: Vec<String> = Vec::new();
    for v in variants {
        for (k, _) in &v.overrides {
            if !keys.contains(&k.name) {
                keys.push(k.name.clone());
            }
        }
    }
    let mut header: Vec<String> = vec!["index".into(), "name".into()];
    header.extend(keys.iter().cloned());
    header.extend(ran_header);
    header.extend(
        [
            "status",
            "solved_by",
            "reason",
            "neutral_point_from_bit_m",
            "hook_load_n",
            "max_surface_torque_nm",
            "max_side_force_per_length_n_per_m",
            "max_side_force_md_m",
        ]
        .map(String::from),
    );
    let rig = case.rig.is_some();
    if rig {
        // What the weight indicator reads (`[rig]`), after the string's load.
        let at = header.iter().position(|h| h == "hook_load_n").unwrap_or(0) + 1;
        header.insert(at, "weight_indicator_n".into());
    }
    if dynamic {
        header.extend(["stick_slip_severity", "relaxed"].map(String::from));
    } else {
        header.extend(
            [
                "sinusoidal_buckling",
                "helical_buckling",
                "outside_hole_m",
                "relaxed",
            ]
            .map(String::from),
        );
        header.extend(crate::bha::BIT_COLUMNS.map(String::from));
    }
    // A variant that stops on its way (a lock-up; a dynamic run's static start): the
    // largest fraction of its loads with an equilibrium, and its string there.
    header.extend(STOPPED_COLUMNS.map(String::from));
    for k in 1..=stabs {
        header.push(format!(
            "{}_max_side_force_n",
            crate::model::stabilizer_name(k)
        ));
        header.push(format!(
            "{}_max_lateral_m",
            crate::model::stabilizer_name(k)
        ));
        if dynamic {
            header.push(format!("{}_whirl_hz", crate::model::stabilizer_name(k)));
            header.push(format!("{}_whirl", crate::model::stabilizer_name(k)));
            header.push(format!(
                "{}_contact_fraction",
                crate::model::stabilizer_name(k)
            ));
        }
    }
    header.extend(["newton_iterations_per_step", "step_cuts"].map(String::from));
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&header).map_err(io)?;
    for (i, ((v, r), ran)) in variants
        .iter()
        .zip(results)
        .zip(ran_rows.iter().cloned())
        .enumerate()
    {
        let mut row = vec![i.to_string(), v.name.clone()];
        let overrides_end = row.len() + keys.len();
        for k in &keys {
            row.push(
                v.overrides
                    .iter()
                    .find(|(key, _)| &key.name == k)
                    .map(|(_, x)| {
                        if x.si().is_finite() {
                            x.to_string()
                        } else {
                            String::new()
                        }
                    })
                    .unwrap_or_default(),
            );
        }
        debug_assert_eq!(row.len(), overrides_end);
        row.extend(ran);
        row.push(
            match r.status {
                Status::Converged => "converged",
                Status::StepCut => "step_cut",
                Status::Failed => "failed",
            }
            .into(),
        );
        row.push(r.solved_by.name().into());
        row.push(r.reason.clone());
        row.push(r.neutral_point_from_bit_m.map(fmt).unwrap_or_default());
        row.push(r.hook_load_n.map(fmt).unwrap_or_default());
        if rig {
            row.push(r.weight_indicator_n.map(fmt).unwrap_or_default());
        }
        row.push(fmt(r.max_surface_torque_nm));
        let opt = |x: Option<f64>| x.map(fmt).unwrap_or_default();
        let flag = |x: Option<bool>| x.map(|b| b.to_string()).unwrap_or_default();
        row.push(opt(r.string.max_side_force_per_length_n_per_m));
        row.push(opt(r.string.max_side_force_md_m));
        if dynamic {
            row.push(opt(r.string.stick_slip_severity));
            row.push(flag(r.string.relaxed));
        } else {
            row.push(flag(r.string.sinusoidal_buckling));
            row.push(flag(r.string.helical_buckling));
            row.push(opt(r.string.outside_hole_m));
            row.push(flag(r.string.relaxed));
            match &r.bit {
                Some(b) => row.extend(b.columns().map(fmt)),
                None => row.extend(crate::bha::BIT_COLUMNS.map(|_| String::new())),
            }
        }
        row.push(opt(r.string.stopped_load_factor));
        let stands = r.string.stands.as_ref();
        row.push(opt(stands.map(|s| s.hook_load_n)));
        row.push(opt(stands.map(|s| s.surface_torque_nm)));
        row.push(opt(stands.map(|s| s.max_side_force_per_length_n_per_m)));
        row.push(opt(stands.and_then(|s| s.max_side_force_md_m)));
        for q in &r.stabilizers {
            row.push(fmt(q.max_side_force_n));
            row.push(fmt(q.max_lateral_m));
            if dynamic {
                row.push(q.whirl_hz.map(fmt).unwrap_or_default());
                row.push(
                    match q.whirl_class {
                        Some(crate::whirl::WhirlClass::None) => "none",
                        Some(crate::whirl::WhirlClass::Forward) => "forward",
                        Some(crate::whirl::WhirlClass::Backward) => "backward",
                        Some(crate::whirl::WhirlClass::Chaotic) => "chaotic",
                        None => "",
                    }
                    .into(),
                );
                row.push(q.contact_fraction.map(fmt).unwrap_or_default());
            }
        }
        row.push(fmt(r.newton_iterations_per_step));
        row.push(r.step_cuts.to_string());
        w.write_record(&row).map_err(io)?;
    }
    w.into_inner().map_err(Error::encode)
}

/// Statistics, sensitivities and plots of a `--samples` run.
pub(crate) fn uncertainty_report(
    mc: &crate::uq::report::MonteCarlo,
    case: &Case,
    variants: &[Variant],
    results: &[VariantResult],
    stabs: usize,
    dynamic: bool,
    out: &Path,
) -> Result<(crate::uq::report::UncertaintyReport, Vec<String>), Error> {
    let qois = qoi_columns(results, stabs, dynamic);
    let keys: Vec<crate::ensemble::Key> = variants
        .first()
        .map(|v| v.overrides.iter().map(|(k, _)| k.clone()).collect())
        .unwrap_or_default();
    let inputs: Vec<(crate::ensemble::Key, Vec<f64>)> = keys
        .iter()
        .enumerate()
        .map(|(k, key)| {
            (
                key.clone(),
                variants.iter().map(|v| v.overrides[k].1.si()).collect(),
            )
        })
        .collect();
    let failed: Vec<bool> = results.iter().map(|r| r.status == Status::Failed).collect();
    let mut report = crate::uq::report::analyse(mc, &inputs, &qois, &failed);
    let mut files = crate::uq::report::plot(&report, &inputs, &qois, out, &case.title)?;
    // Where runs stop on their way (a lock-up): how likely, of the runs whose outcome is
    // known, and how far each gets against the inputs.
    let reached: Vec<f64> = results.iter().map(loads_reached).collect();
    let sample = &reached[..report.base_samples];
    let known = sample.iter().filter(|x| x.is_finite()).count();
    let stopped = sample.iter().filter(|&&x| x < 1.0).count();
    let pushed = results[..report.base_samples]
        .iter()
        .filter(|r| pushed(r))
        .count();
    if !dynamic && stopped + pushed > 0 {
        report.past_weight_lock_up =
            Some(crate::uq::stats::Proportion::of(stopped + pushed, known));
    }
    if stopped > 0 {
        report.stops = Some(crate::uq::stats::Proportion::of(stopped, known));
        files.extend(crate::uq::report::plot_reached(
            &report,
            &inputs,
            &reached,
            out,
            &case.title,
        )?);
    }
    Ok((report, files))
}

/// The columns of what every variant ran with (not only its overrides), SI: bit depth,
/// rotary speed, weight and torque on bit, and per stabilizer its distance from the bit,
/// blade diameter, friction and wall stiffness ([`ran_row`]).
fn ran_header(stabs: usize) -> Vec<String> {
    let mut header: Vec<String> = [
        "ran.bit_md_m",
        "ran.rotation_speed_rad_s",
        "ran.wob_n",
        "ran.tob_nm",
    ]
    .map(String::from)
    .to_vec();
    for k in 1..=stabs {
        for f in ["from_bit_m", "blade_m", "mu_t", "mu_l", "k_e"] {
            header.push(format!("ran.stab{k}.{f}"));
        }
    }
    header
}

/// One variant's row of [`ran_header`], read from the model it runs (`holewall ensemble`
/// records it when it checks the variant, so the report does not build the model again).
pub(crate) fn ran_row(m: &Model, stabs: usize) -> Vec<String> {
    let bit = m.nodes.last().map_or(f64::NAN, |n| n.md);
    let mut row = vec![
        fmt(bit),
        fmt(m.rotation_speed),
        fmt(m.weight_on_bit),
        fmt(m.torque_on_bit),
    ];
    let sites = m.stabilizer_sites();
    for k in 0..stabs {
        match sites.get(k).map(|&s| &m.sites[s]) {
            Some(site) => row.extend([
                fmt(bit - m.nodes[site.node].md),
                fmt(2.0 * site.params.disk_radius),
                fmt(site.params.mu_t),
                fmt(site.params.mu_l),
                fmt(site.params.wall_stiffness),
            ]),
            None => row.extend(vec![String::new(); 5]),
        }
    }
    row
}

/// The quantities of interest of every variant as columns (NaN where a variant has none).
pub fn qoi_columns(
    results: &[VariantResult],
    stabs: usize,
    dynamic: bool,
) -> Vec<crate::uq::report::Qoi> {
    use crate::uq::report::{Qoi, Unit};
    let col = |name: String, unit: Unit, f: &dyn Fn(&VariantResult) -> Option<f64>| Qoi {
        name,
        unit,
        values: results.iter().map(|r| f(r).unwrap_or(f64::NAN)).collect(),
    };
    let mut q = vec![
        col("neutral_point_from_bit_m".into(), Unit::Length, &|r| {
            r.neutral_point_from_bit_m
        }),
        col("hook_load_n".into(), Unit::Force, &|r| r.hook_load_n),
    ];
    if results.iter().any(|r| r.weight_indicator_n.is_some()) {
        q.push(col("weight_indicator_n".into(), Unit::Force, &|r| {
            r.weight_indicator_n
        }));
    }
    q.extend([
        col("max_surface_torque_nm".into(), Unit::Torque, &|r| {
            Some(r.max_surface_torque_nm)
        }),
        col(
            "max_side_force_per_length_n_per_m".into(),
            Unit::ForcePerLength,
            &|r| r.string.max_side_force_per_length_n_per_m,
        ),
    ]);
    if !dynamic {
        // The bit's loads and attitude (issue 25).
        for (j, name) in crate::bha::BIT_COLUMNS.iter().enumerate() {
            let unit = if name.ends_with("_deg") {
                Unit::Degrees
            } else {
                Unit::Force
            };
            q.push(col(name.to_string(), unit, &|r| {
                r.bit.as_ref().map(|b| b.columns()[j])
            }));
        }
    }
    // Flags as 0/1: their mean is the probability (e.g. that the string buckles).
    let as_number = |b: Option<bool>| b.map(|b| if b { 1.0 } else { 0.0 });
    if dynamic {
        q.push(col("stick_slip_severity".into(), Unit::Ratio, &|r| {
            r.string.stick_slip_severity
        }));
    } else {
        q.push(col("sinusoidal_buckling".into(), Unit::Ratio, &|r| {
            as_number(r.string.sinusoidal_buckling)
        }));
        q.push(col("helical_buckling".into(), Unit::Ratio, &|r| {
            as_number(r.string.helical_buckling)
        }));
        q.push(col("outside_hole".into(), Unit::Ratio, &|r| {
            as_number(r.string.outside_hole_m.map(|m| m > 0.0))
        }));
    }
    for k in 0..stabs {
        q.push(col(
            format!("{}_max_side_force_n", crate::model::stabilizer_name(k + 1)),
            Unit::Force,
            &|r| r.stabilizers.get(k).map(|s| s.max_side_force_n),
        ));
        q.push(col(
            format!("{}_max_lateral_m", crate::model::stabilizer_name(k + 1)),
            Unit::Length,
            &|r| r.stabilizers.get(k).map(|s| s.max_lateral_m),
        ));
        if dynamic {
            q.push(col(
                format!("{}_whirl_hz", crate::model::stabilizer_name(k + 1)),
                Unit::Frequency,
                &|r| r.stabilizers.get(k).and_then(|s| s.whirl_hz),
            ));
        }
    }
    q
}
