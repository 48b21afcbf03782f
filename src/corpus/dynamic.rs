//! A corpus of dynamic runs drawn from seeds: what a BHA engineer brings to `holewall run`,
//! to measure whether the implicit integrator (and the GPU engine) works on it rather than
//! on the shipped cases it was tuned on.
//!
//! Each seed gives one case (and its survey CSV), written to a folder and read back through
//! the case parser as a user's files are:
//! - **string**: a BHA — collars sized to the hole (6–12¼ in), 0–3 stabilizers (near-bit and
//!   5–25 m apart, blades up to ½ in under gauge), a bent motor housing (0.5–2°) in one case
//!   in eight, a mass imbalance in one in five — with drill pipe above it. Four cases in five
//!   are a **section** (the bottom 40–300 m of the string, its top clamped where the section
//!   is cut); one in five is a **whole string** of 1,000–3,000 m in the same kind of hole
//!   — its survey, like a section's, at the hole's inclination from MD 0 (no vertical
//!   kick-off from a rig: wells of that shape are the static corpus's, not drawn here);
//! - **hole**: vertical, tangent (10–70°), building (2–8°/30 m) or horizontal (86–92°), the
//!   stations every 10 m with dogleg noise (σ 0.05–0.3°); friction 0.1–0.4; mud 1.0–1.8 sg;
//! - **operation**: rotating off bottom or drilling (WOB up to 1.2 × the soft string's
//!   sinusoidal-buckling limit, capped at 150 kN; an ROP of 5–40 m/h in one drilling case
//!   in three), 40–200 rpm;
//! - **wall**: stiffness 1e6–1e9 N/m log-uniform, the linear, hard (m = 3/2) or soft
//!   (m = 2/3) law, wall damping 0–20 kN·s/m; contact at every node, or at the stabilizers
//!   only in a vertical hole (half of those with stabilizers);
//! - **mesh**: BHA elements of 0.25–2 m, pipe elements of 1–10 m (sections) or 10–30 m
//!   (whole strings);
//! - **integration**: 0.3–1 s simulated, steps of 0.5–5 ms, a table ramp of 0 (an impulsive
//!   start, one case in four) to 0.5 s, ρ∞ 0.5–1, lumped mass (consistent in one case in
//!   eight); a lateral kick or offset of the BHA in one case in four each.
//!
//! [`run_case_dynamic`] runs a case as `holewall run` does (the static start held in the hole,
//! then the integration) and reports what a user would see.

use super::*;
use crate::ensemble::qoi::{dynamic_variant_tracked, Status, VariantResult};

/// What a drawn dynamic case is (for the table).
#[derive(Clone, Debug, Serialize)]
pub struct DynamicSpec {
    /// Seed it was drawn from.
    pub seed: u64,
    /// `section` (the bottom of the string) or `string` (the whole string).
    pub class: String,
    /// `vertical`, `tangent`, `building`, `horizontal`.
    pub hole: String,
    /// Largest inclination (deg).
    pub max_inclination_deg: f64,
    /// Bit depth (m).
    pub total_md: f64,
    /// Open-hole diameter (in).
    pub hole_in: f64,
    /// Stabilizers.
    pub stabilizers: usize,
    /// Bent housing (deg), 0 for none.
    pub bend_deg: f64,
    /// Mass imbalance on the collars (kg·m), 0 for none.
    pub imbalance_kg_m: f64,
    /// `rotating` (off bottom) or `drilling`.
    pub mode: String,
    /// Weight on bit (N).
    pub wob_n: f64,
    /// Rotary speed (rpm).
    pub rpm: f64,
    /// Rate of penetration (m/h), 0 for none.
    pub rop_m_per_h: f64,
    /// Open-hole friction.
    pub friction: f64,
    /// Wall stiffness (N/m^m).
    pub wall_stiffness: f64,
    /// Spring exponent.
    pub exponent: f64,
    /// Wall damping (N·s/m).
    pub wall_damping: f64,
    /// `all_nodes` or `stabilizers`.
    pub sites: String,
    /// Pipe element length (m).
    pub element_m: f64,
    /// BHA element length (m).
    pub bha_element_m: f64,
    /// Simulated time (s).
    pub duration_s: f64,
    /// Time step (s).
    pub time_step_s: f64,
    /// Table ramp (s).
    pub ramp_s: f64,
    /// Generalised-α ρ∞.
    pub rho_inf: f64,
    /// `lumped` or `consistent`.
    pub mass: String,
    /// Initial lateral kick of the BHA (m/s).
    pub kick_m_per_s: f64,
    /// Initial lateral offset of the BHA (m).
    pub offset_m: f64,
}

/// A drawn dynamic case, written out.
#[derive(Clone, Debug)]
pub struct DynamicCase {
    /// What it is.
    pub spec: DynamicSpec,
    /// The case file.
    pub case_path: PathBuf,
}

fn survey_of(rng: &mut ChaCha8Rng, hole: &str, total_md: f64) -> Vec<[f64; 3]> {
    let azimuth = rng.random_range(0.0..360.0);
    let (inc0, rate, cap) = match hole {
        "vertical" => (0.0, 0.0, 0.0),
        "tangent" => (rng.random_range(10.0..70.0), 0.0, 90.0),
        "building" => (
            rng.random_range(5.0..40.0),
            rng.random_range(2.0..8.0),
            95.0,
        ),
        _ => (rng.random_range(86.0..92.0), 0.0, 95.0),
    };
    let sigma = rng.random_range(0.05..0.3);
    let noise = |rng: &mut ChaCha8Rng| {
        let u1: f64 = rng.random_range(1e-12..1.0);
        let u2: f64 = rng.random();
        sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    let mut out = Vec::new();
    let mut md = 0.0f64;
    // The hole's inclination from MD 0, for a whole string too (its top then lies in the
    // inclined hole: no vertical kick-off above it; module docs).
    loop {
        let plan = if inc0 == 0.0 {
            0.0
        } else {
            (inc0 + rate * md / 30.0).min(cap)
        };
        let (ni, na) = (noise(rng), noise(rng));
        let inc = if plan < 1e-9 {
            ni.abs()
        } else {
            (plan + ni).clamp(0.0, 179.0)
        };
        let az = (azimuth + na / inc.to_radians().sin().max(0.1)).rem_euclid(360.0);
        out.push([md, inc, az]);
        if md >= total_md {
            break;
        }
        md = (md + 10.0).min(total_md + 10.0);
    }
    out
}

/// Draws dynamic case `seed` and writes it into `dir` (`dyn_<seed>.toml` and `.csv`).
pub fn write_dynamic_case(seed: u64, dir: &Path) -> Result<DynamicCase, Error> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xd1a_0000);
    let whole = rng.random_bool(0.2);
    let hole = pick(
        &mut rng,
        &[
            ("vertical", 0.3),
            ("tangent", 0.3),
            ("building", 0.2),
            ("horizontal", 0.2),
        ],
    );
    let size = &SIZES[rng.random_range(0..SIZES.len())];
    let collar = size.collars[rng.random_range(0..size.collars.len())];
    let collar_len = rng.random_range(30.0f64..150.0).round();
    let stabilizers = pick(&mut rng, &[(0usize, 0.2), (1, 0.35), (2, 0.25), (3, 0.2)]);
    let under_gauge: Vec<f64> = (0..stabilizers)
        .map(|_| rng.random_range(0.0..0.5))
        .collect();
    let spacing: Vec<f64> = (0..stabilizers)
        .map(|_| rng.random_range(5.0f64..25.0).round())
        .collect();
    let bend = if rng.random_bool(0.125) {
        rng.random_range(0.5f64..2.0)
    } else {
        0.0
    };
    let eccentricity_mm = if rng.random_bool(0.2) {
        rng.random_range(0.5f64..5.0)
    } else {
        0.0
    };
    let total_md = if whole {
        rng.random_range(1000.0f64..3000.0).round()
    } else {
        (collar_len + rng.random_range(10.0f64..150.0)).round()
    };
    let stations = survey_of(&mut rng, hole, total_md);
    let friction = rng.random_range(0.1..0.4);
    let sg = rng.random_range(1.0..1.8);
    let drilling = rng.random_bool(0.65);
    let wob_fraction = rng.random_range(0.0..1.2);
    let rpm = rng.random_range(40.0f64..200.0).round();
    let rop = if drilling && rng.random_bool(1.0 / 3.0) {
        rng.random_range(5.0f64..40.0).round()
    } else {
        0.0
    };
    let exponent = pick(&mut rng, &[(1.0, 0.8), (1.5, 0.1), (2.0 / 3.0, 0.1)]);
    let k_linear = 10f64.powf(rng.random_range(6.0..9.0));
    let wall_stiffness = k_linear * 1e-3f64.powf(1.0 - exponent);
    let wall_damping = rng.random_range(0.0f64..2e4).round();
    let sites = if hole == "vertical" && stabilizers > 0 && rng.random_bool(0.5) {
        "stabilizers"
    } else {
        "all_nodes"
    };
    let bha_element = pick(
        &mut rng,
        &[(0.25f64, 0.1), (0.5, 0.3), (1.0, 0.35), (2.0, 0.25)],
    );
    let element = if whole {
        pick(&mut rng, &[(10.0f64, 0.4), (20.0, 0.35), (30.0, 0.25)])
    } else {
        pick(
            &mut rng,
            &[(1.0f64, 0.2), (2.0, 0.3), (5.0, 0.3), (10.0, 0.2)],
        )
    }
    .max(bha_element);
    let duration = (rng.random_range(0.3f64..1.0) * 20.0).round() / 20.0;
    let time_step = pick(
        &mut rng,
        &[(0.5e-3f64, 0.2), (1e-3, 0.35), (2e-3, 0.3), (5e-3, 0.15)],
    );
    let ramp = if rng.random_bool(0.25) {
        0.0
    } else {
        (rng.random_range(0.1f64..0.5) * 20.0).round() / 20.0
    };
    let rho_inf = (rng.random_range(0.5f64..1.0) * 20.0).round() / 20.0;
    let consistent = rng.random_bool(0.125);
    let kick = if rng.random_bool(0.25) {
        rng.random_range(0.05f64..0.5)
    } else {
        0.0
    };
    let clearance = 0.5 * (size.hole_in - collar.0) * INCH;
    let offset = if rng.random_bool(0.25) {
        rng.random_range(0.2..0.9) * clearance
    } else {
        0.0
    };

    // The string from the bit up.
    let (cod, cid) = collar;
    let collar_extra = if eccentricity_mm > 0.0 {
        format!("mass_eccentricity = \"{eccentricity_mm:.2} mm\"\n")
    } else {
        String::new()
    };
    let (mut comps, mut used) = bha_bottom(
        &mut rng,
        collar,
        size.hole_in,
        bend,
        &under_gauge,
        &spacing,
        &collar_extra,
    );
    let rest = (collar_len - used).max(9.0).round();
    comps.push(tube("collar", rest, cod, cid, &collar_extra));
    used += rest;
    comps.push(tube(
        "drill_pipe",
        (total_md - used + 1.0).max(1.0).round(),
        size.pipe.0,
        size.pipe.1,
        "",
    ));
    let imbalance_kg_m = if eccentricity_mm > 0.0 {
        let area = std::f64::consts::PI / 4.0 * (cod * cod - cid * cid) * INCH * INCH;
        7850.0 * area * (collar_len - 1.5 * stabilizers as f64).max(9.0) * eccentricity_mm * 1e-3
    } else {
        0.0
    };

    let name = format!("dyn_{seed}");
    let csv_name = write_survey(dir, &name, &stations)?;
    let max_inc = stations.iter().map(|s| s[1]).fold(0.0, f64::max);
    let case_text = |wob: f64| {
        let mut t = format!(
            "title = \"dynamic corpus case {seed}: {} {hole} {total_md} m, {} in hole, {} rpm\"\n",
            if whole { "string," } else { "section," },
            size.hole_in,
            rpm
        );
        t.push_str(&format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"{csv_name}\"\ntotal_md = \"{total_md} m\"\n"
        ));
        t.push_str(&format!(
            "[[hole]]\nbottom_md = \"{total_md} m\"\ndiameter = \"{} in\"\nfriction = {friction:.3}\n",
            size.hole_in
        ));
        t.push_str(&format!("[mud]\ndensity = \"{sg:.3} sg\"\n"));
        for c in &comps {
            t.push_str(c);
        }
        t.push_str(&format!(
            "[operation]\nmode = \"rotating\"\nrpm = \"{rpm} rpm\"\n"
        ));
        if wob > 0.0 {
            t.push_str(&format!(
                "weight_on_bit = \"{:.3} kN\"\ntorque_on_bit = \"{:.3} kN.m\"\n",
                wob / 1e3,
                0.02 * wob / 1e3 * size.hole_in * INCH / 0.2159
            ));
        }
        t.push_str(&format!(
            "[contact]\nsites = \"{sites}\"\nwall_stiffness = {wall_stiffness:.6e}\nexponent = {exponent:.6}\ndamping = {wall_damping}\n"
        ));
        t.push_str(&format!(
            "[mesh]\nelement_length = \"{element} m\"\nbha_element_length = \"{bha_element} m\"\n"
        ));
        t.push_str(&format!(
            "[dynamics]\nduration = \"{duration} s\"\ntime_step = \"{time_step} s\"\noutput_interval = \"10 ms\"\nramp_time = \"{ramp} s\"\nrho_inf = {rho_inf}\nmass = \"{}\"\n",
            if consistent { "consistent" } else { "lumped" }
        ));
        if rop > 0.0 {
            t.push_str(&format!("rop = \"{rop} m/h\"\n"));
        }
        if kick > 0.0 {
            t.push_str(&format!("initial_lateral_velocity = \"{kick:.4} m/s\"\n"));
        }
        if offset > 0.0 {
            t.push_str(&format!("initial_lateral_offset = \"{:.5} m\"\n", offset));
        }
        t
    };
    let case_path = dir.join(format!("{name}.toml"));
    let mut wob = 0.0;
    if drilling {
        let case = crate::case::parse_case(&case_path, &case_text(0.0))?;
        let limit = buckling_limited_wob(&case, false);
        wob = ((wob_fraction * limit).min(150e3) / 100.0).round() * 100.0;
    }
    crate::output::write_atomic(&case_path, case_text(wob).as_bytes())?;
    Ok(DynamicCase {
        spec: DynamicSpec {
            seed,
            class: if whole { "string" } else { "section" }.into(),
            hole: hole.into(),
            max_inclination_deg: max_inc,
            total_md,
            hole_in: size.hole_in,
            stabilizers,
            bend_deg: bend,
            imbalance_kg_m,
            mode: if wob > 0.0 { "drilling" } else { "rotating" }.into(),
            wob_n: wob,
            rpm,
            rop_m_per_h: rop,
            friction,
            wall_stiffness,
            exponent,
            wall_damping,
            sites: sites.into(),
            element_m: element,
            bha_element_m: bha_element,
            duration_s: duration,
            time_step_s: time_step,
            ramp_s: ramp,
            rho_inf,
            mass: if consistent { "consistent" } else { "lumped" }.into(),
            kick_m_per_s: kick,
            offset_m: offset,
        },
        case_path,
    })
}

/// One dynamic case's outcome on the CPU integrator (a row of `dynamic_corpus.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct DynamicRow {
    /// The case (its columns come first in `dynamic_corpus.csv`: see [`DynamicRow::pair`]).
    #[serde(skip)]
    pub spec: DynamicSpec,
    /// Nodes of the mesh.
    pub nodes: usize,
    /// Ran to its duration with a finite state.
    pub solved: bool,
    /// Ran with no time step cut (a cut is a result to report, not a pass).
    pub uncut: bool,
    /// Time-step cuts.
    pub step_cuts: usize,
    /// Mean Newton iterations per step.
    pub iterations_per_step: f64,
    /// Wall time, the static start included (s).
    pub seconds: f64,
    /// Wall time per simulated second (s/s).
    pub seconds_per_simulated_s: f64,
    /// The largest lateral kinetic energy of the run's second half over its first, minus 1
    /// ([`dynamic_variant_tracked`]): ≫ 1 is a run that grows.
    pub lateral_energy_growth: f64,
    /// Largest surface torque (N·m).
    pub max_surface_torque_nm: f64,
    /// Hook load (the top element's axial force) in the last state (N).
    pub hook_load_n: f64,
    /// The near-bit stabilizer's largest side force (N; NaN without stabilizers).
    pub stab1_max_side_force_n: f64,
    /// How far the near-bit stabilizer went past its clearance (mm; ≤ 0 inside).
    pub stab1_penetration_mm: f64,
    /// Its whirl ([`crate::whirl::WhirlClass`]).
    pub stab1_whirl: String,
    /// Stick-slip severity (second half).
    pub stick_slip_severity: f64,
    /// Why it failed, or the first step cut (empty otherwise).
    pub reason: String,
}

impl DynamicRow {
    /// The CSV row: the case's columns, then the outcome's.
    pub fn pair(&self) -> (&DynamicSpec, &Self) {
        (&self.spec, self)
    }
}

/// The near-bit stabilizer's clearance (m), if the model has stabilizers.
fn stab1_clearance(model: &crate::model::Model) -> Option<f64> {
    model
        .stabilizer_sites()
        .first()
        .map(|&k| model.sites[k].params.clearance)
}

/// The row of a run's result.
fn row_of(
    spec: &DynamicSpec,
    model: &crate::model::Model,
    r: &VariantResult,
    growth: Option<f64>,
    seconds: f64,
) -> DynamicRow {
    let solved = r.status != Status::Failed;
    let s1 = r.stabilizers.first();
    DynamicRow {
        spec: spec.clone(),
        nodes: model.nodes.len(),
        solved,
        uncut: r.status == Status::Converged,
        step_cuts: r.step_cuts,
        iterations_per_step: r.newton_iterations_per_step,
        seconds,
        seconds_per_simulated_s: seconds / spec.duration_s,
        lateral_energy_growth: growth.unwrap_or(f64::NAN),
        max_surface_torque_nm: r.max_surface_torque_nm,
        hook_load_n: r.hook_load_n.unwrap_or(f64::NAN),
        stab1_max_side_force_n: s1.map_or(f64::NAN, |s| s.max_side_force_n),
        stab1_penetration_mm: match (s1, stab1_clearance(model)) {
            (Some(s), Some(c)) => 1e3 * (s.max_lateral_m - c),
            _ => f64::NAN,
        },
        stab1_whirl: s1
            .and_then(|s| s.whirl_class)
            .map_or(String::new(), |c| format!("{c:?}").to_lowercase()),
        stick_slip_severity: r.string.stick_slip_severity.unwrap_or(f64::NAN),
        reason: if r.status == Status::Converged {
            String::new()
        } else {
            r.reason.clone()
        },
    }
}

/// Runs a drawn case on the CPU integrator as `holewall run` runs it (the static start held
/// in the hole, [`crate::profile::solve_in_hole`]; then generalised-α with step control).
pub fn run_case_dynamic(case: &DynamicCase) -> Result<DynamicRow, Error> {
    run_case_cpu(case, |_| {})
}

/// A drawn case on the CPU integrator, its loaded case changed by `change` first.
fn run_case_cpu(
    case: &DynamicCase,
    change: impl FnOnce(&mut crate::case::Case),
) -> Result<DynamicRow, Error> {
    let mut loaded = crate::case::load_case(&case.case_path)?;
    change(&mut loaded);
    let clock = std::time::Instant::now();
    let (r, growth) = dynamic_variant_tracked(&loaded, "cpu", &loaded.model, true);
    let seconds = clock.elapsed().as_secs_f64();
    Ok(row_of(&case.spec, &loaded.model, &r, growth, seconds))
}

/// The relative change of the start that [`run_case_perturbed`] makes: far above rounding
/// (1e-16 in f64), far below anything a user sets.
pub const START_PERTURBATION: f64 = 1e-8;

/// [`run_case_dynamic`] with the start changed by [`START_PERTURBATION`]: the BHA's kick
/// (`initial_lateral_velocity`) scaled by `1 + 1e-8`, or without a kick a kick of 1e-8 m/s
/// (not the initial offset: an offset that would start a node beyond its wall is scaled to
/// land on it, which takes any change of it away — dynamic corpus seed 266). Two CPU runs
/// this close differ by the case's own sensitivity to its start: the yardstick for an
/// engine's difference from the CPU (a chaotic run's end values cannot agree between two
/// solvers that differ at rounding).
pub fn run_case_perturbed(case: &DynamicCase) -> Result<DynamicRow, Error> {
    run_case_cpu(case, |loaded| {
        if let Some(d) = loaded.dynamics.as_mut() {
            d.initial_lateral_velocity = if d.initial_lateral_velocity != 0.0 {
                d.initial_lateral_velocity * (1.0 + START_PERTURBATION)
            } else {
                START_PERTURBATION
            };
        }
    })
}

/// One dynamic case through the GPU engine (a one-variant dynamic ensemble, as `holewall
/// ensemble --backend gpu` runs it), against the CPU run.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicEngineRow {
    /// Seed of the case.
    pub seed: u64,
    /// `gpu_f64` or `gpu_f32`.
    pub path: String,
    /// Nodes.
    pub nodes: usize,
    /// Ran to its duration.
    pub solved: bool,
    /// Solved by the engine itself (not re-run on the CPU: a fallback is a result, not a
    /// pass).
    pub by_engine: bool,
    /// Time-step cuts.
    pub step_cuts: usize,
    /// Wall time (s).
    pub seconds: f64,
    /// |Δ hook load| / |CPU hook load|.
    pub hook_load_rel: f64,
    /// |Δ hook load| / the run's force scale (the string's buoyed weight and the bit loads,
    /// [`crate::solve::statics::reference_force`]): the precision's measure, which a hook
    /// load near zero (a horizontal section's) does not inflate as it does `hook_load_rel`.
    pub hook_load_of_force_scale: f64,
    /// |Δ largest surface torque| / CPU's.
    pub torque_rel: f64,
    /// |Δ stab1's largest side force| / CPU's (NaN without stabilizers).
    pub stab1_force_rel: f64,
    /// The same whirl class as the CPU's at stab1.
    pub same_whirl: bool,
    /// The CPU's own sensitivity: |Δ hook load| / CPU's between the CPU run and the CPU run
    /// with its start changed by [`START_PERTURBATION`] ([`run_case_perturbed`]).
    pub cpu_spread_hook_rel: f64,
    /// The same for the largest surface torque.
    pub cpu_spread_torque_rel: f64,
    /// The same for stab1's largest side force (NaN without stabilizers).
    pub cpu_spread_stab1_rel: f64,
    /// Why the engine did not solve it itself.
    pub reason: String,
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / b.abs().max(1e-300)
    }
}

/// Runs `case` through the GPU engine in f64 (`f32 = false`) or f32 and compares it with the
/// CPU row `cpu`, beside the CPU's own spread (`perturbed`: [`run_case_perturbed`]). `Err`
/// where the path cannot run here (no adapter, no f64) or the case needs what only the CPU
/// integrator has (consistent mass).
pub fn run_case_engine(
    case: &DynamicCase,
    cpu: &DynamicRow,
    perturbed: &DynamicRow,
    f32: bool,
) -> Result<DynamicEngineRow, Error> {
    use crate::ensemble::runner::run_dynamic_gpu;
    let loaded = crate::case::load_case(&case.case_path)?;
    let ctx = crate::gpu::context::GpuContext::shared()?;
    if !f32 && !ctx.has_f64 {
        return Err(crate::error::GpuError::Unsupported(format!(
            "{} has no f64 in shaders",
            ctx.describe()
        ))
        .into());
    }
    let variant = crate::ensemble::Variant {
        name: "engine".into(),
        overrides: Vec::new(),
    };
    let bar = indicatif::ProgressBar::hidden();
    let clock = std::time::Instant::now();
    let out = if f32 {
        run_dynamic_gpu::<f32>(&loaded, std::slice::from_ref(&variant), ctx, &bar)?
    } else {
        run_dynamic_gpu::<f64>(&loaded, std::slice::from_ref(&variant), ctx, &bar)?
    };
    let seconds = clock.elapsed().as_secs_f64();
    let r = out
        .map_err(|e| Error::failed(format!("the engine cannot run it: {e}")))?
        .into_iter()
        .next()
        .ok_or_else(|| Error::failed("the engine returned no result"))?;
    let e = row_of(&case.spec, &loaded.model, &r, None, seconds);
    Ok(DynamicEngineRow {
        seed: case.spec.seed,
        path: if f32 { "gpu_f32" } else { "gpu_f64" }.into(),
        nodes: e.nodes,
        solved: e.solved,
        by_engine: e.solved && r.solved_by == crate::ensemble::qoi::SolvedBy::Engine,
        step_cuts: e.step_cuts,
        seconds,
        hook_load_rel: rel(e.hook_load_n, cpu.hook_load_n),
        hook_load_of_force_scale: (e.hook_load_n - cpu.hook_load_n).abs()
            / crate::solve::statics::reference_force(&loaded.model),
        torque_rel: rel(e.max_surface_torque_nm, cpu.max_surface_torque_nm),
        stab1_force_rel: rel(e.stab1_max_side_force_n, cpu.stab1_max_side_force_n),
        same_whirl: e.stab1_whirl == cpu.stab1_whirl,
        cpu_spread_hook_rel: rel(perturbed.hook_load_n, cpu.hook_load_n),
        cpu_spread_torque_rel: rel(perturbed.max_surface_torque_nm, cpu.max_surface_torque_nm),
        cpu_spread_stab1_rel: rel(perturbed.stab1_max_side_force_n, cpu.stab1_max_side_force_n),
        reason: if r.solved_by == crate::ensemble::qoi::SolvedBy::Engine {
            e.reason
        } else {
            r.reason
        },
    })
}
