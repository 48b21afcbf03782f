//! A corpus of ordinary wells drawn from seeds (issue 22): what drilling engineers bring to
//! a static solve, to measure whether the solver works on it rather than on the wells it
//! was tuned on.
//!
//! Each seed gives one well as a case file and a survey CSV — written to a folder and read
//! back through the case parser, exactly as a user's files are:
//! - **trajectory**: vertical, build-and-hold, S-shaped (build, hold, drop) or horizontal
//!   (build to 86–92°, then a lateral), each possibly with a turn; stations every 30 m with
//!   dogleg noise (σ 0.05–0.4° per station in inclination and azimuth); 1,000–4,500 m MD;
//! - **hole**: 6, 6⅛, 8½, 8¾, 9⅞ or 12¼ in open hole below a casing of the size above it
//!   (shoe at 20–70 % of MD), friction 0.15–0.25 cased, 0.2–0.4 open; mud 1.0–1.8 sg;
//! - **string**: drill pipe, 0–300 m of HWDP, 30–250 m of collars sized to the hole, 0–4
//!   stabilizers (near-bit and 5–30 m apart, blades up to ½ in under gauge), a bent motor
//!   housing (0.5–2°) in one well in eight;
//! - **operation**: rotating off bottom, drilling (rotating on bottom), sliding, tripping in
//!   or out; the weight on bit drawn up to the soft-string sinusoidal-buckling limit of the
//!   string (capped at 150 kN), the torque on bit with it;
//! - **mesh**: pipe elements of 0.5–30 m, BHA elements of 0.25–2 m; contact at every node
//!   (at the stabilizers only in a vertical well with stabilizers);
//! - **wall**: stiffness 1e6–1e9 N/m log-uniform, a linear law (a hard m = 3/2 or soft
//!   m = 2/3 law in one well in ten each, its stiffness giving the same force at 1 mm).
//!
//! That is the `drawn` style; [`user`] draws a second, `user` style as users write wells
//! (tool joints, reaming, three hole sections, tapered strings, WOB past buckling).
//!
//! [`run_well`] solves one well with the FE static solve and the soft string and reports
//! what a user would see: solved or not (with the message), load steps and cuts, Newton
//! iterations, time, and the FE/soft-string hook-load and torque ratios.

use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::error::Error;
use draw::{contact_and_mesh, pick, survey, tube, write_survey};

mod draw;
pub mod dynamic;
mod engine;
mod row;
mod summary;
pub mod user;
pub use engine::{run_well_engine, EngineOutcome, EnginePath};
pub use row::WellRow;
pub(crate) use summary::{min_med_max, spread};
pub use summary::{CorpusSummary, Spread};

/// Kinds of trajectory in the corpus.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Trajectory {
    /// Vertical (with survey noise).
    Vertical,
    /// Kick-off, build, hold.
    BuildAndHold,
    /// Kick-off, build, hold, drop, hold.
    SShaped,
    /// Kick-off, build to about 90°, lateral.
    Horizontal,
}

impl Trajectory {
    /// Name as in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Trajectory::Vertical => "vertical",
            Trajectory::BuildAndHold => "build_and_hold",
            Trajectory::SShaped => "s_shaped",
            Trajectory::Horizontal => "horizontal",
        }
    }
}

/// What a corpus well is (for the table).
#[derive(Clone, Debug, Serialize)]
pub struct WellSpec {
    /// Seed it was drawn from.
    pub seed: u64,
    /// Trajectory kind.
    pub trajectory: Trajectory,
    /// Whether the azimuth turns.
    pub turn: bool,
    /// Bit depth (m).
    pub total_md: f64,
    /// Largest inclination (deg).
    pub max_inclination_deg: f64,
    /// Open-hole diameter (in).
    pub hole_in: f64,
    /// Operation: `rotating`, `drilling`, `sliding`, `tripping_in`, `tripping_out`.
    pub mode: String,
    /// Weight on bit (N).
    pub wob_n: f64,
    /// Pipe element length (m).
    pub element_m: f64,
    /// BHA element length (m).
    pub bha_element_m: f64,
    /// Stabilizers.
    pub stabilizers: usize,
    /// Bent housing angle (deg), 0 for none.
    pub bend_deg: f64,
    /// Contact sites: `all_nodes` or `stabilizers`.
    pub sites: String,
    /// Wall stiffness (N/m^m).
    pub wall_stiffness: f64,
    /// Spring exponent.
    pub exponent: f64,
}

/// A drawn well, written out.
#[derive(Clone, Debug)]
pub struct CorpusWell {
    /// What it is.
    pub spec: WellSpec,
    /// The case file.
    pub case_path: PathBuf,
}

/// How a corpus draws its wells.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum CorpusStyle {
    /// [`write_well`]: spans geometry, string, loads, mesh and wall (the 500-well corpus).
    #[default]
    Drawn,
    /// [`user::write_user_well`]: as users write wells, with what `drawn` leaves out.
    User,
}

/// Draws well `seed` of `style` into `dir`.
pub fn write_corpus_well(style: CorpusStyle, seed: u64, dir: &Path) -> Result<CorpusWell, Error> {
    match style {
        CorpusStyle::Drawn => write_well(seed, dir),
        CorpusStyle::User => user::write_user_well(seed, dir),
    }
}

struct HoleSize {
    hole_in: f64,
    casing_id_in: f64,
    pipe: (f64, f64),
    hwdp: (f64, f64),
    collars: &'static [(f64, f64)],
}

const SIZES: [HoleSize; 6] = [
    HoleSize {
        hole_in: 6.0,
        casing_id_in: 6.276,
        pipe: (3.5, 2.764),
        hwdp: (3.5, 2.25),
        collars: &[(4.75, 2.25)],
    },
    HoleSize {
        hole_in: 6.125,
        casing_id_in: 6.276,
        pipe: (4.0, 3.34),
        hwdp: (4.0, 2.5625),
        collars: &[(4.75, 2.25), (5.0, 2.25)],
    },
    HoleSize {
        hole_in: 8.5,
        casing_id_in: 8.835,
        pipe: (5.0, 4.276),
        hwdp: (5.0, 3.0),
        collars: &[(6.5, 2.8125), (6.75, 2.8125)],
    },
    HoleSize {
        hole_in: 8.75,
        casing_id_in: 8.835,
        pipe: (5.0, 4.276),
        hwdp: (5.0, 3.0),
        collars: &[(6.5, 2.8125), (6.75, 2.8125)],
    },
    HoleSize {
        hole_in: 9.875,
        casing_id_in: 10.05,
        pipe: (5.0, 4.276),
        hwdp: (5.0, 3.0),
        collars: &[(7.0, 2.8125), (6.75, 2.8125)],
    },
    HoleSize {
        hole_in: 12.25,
        casing_id_in: 12.415,
        pipe: (5.5, 4.778),
        hwdp: (5.5, 3.375),
        collars: &[(8.0, 2.8125), (9.5, 3.0)],
    },
];

const INCH: f64 = 0.0254;

/// The bottom of a drawn BHA, from the bit up (both corpora): the bit; a bent motor housing
/// where `bend` > 0 (its length, 6–9 m, and the bend's height, 1–2.5 m, drawn from `rng`);
/// then a 1.5 m stabilizer per `under_gauge` entry (blade that much under `hole_in`), the
/// ones above the first `spacing` m of collar apart (`collar_extra` on those collars).
/// Returns the tables and their length (m).
fn bha_bottom(
    rng: &mut ChaCha8Rng,
    (cod, cid): (f64, f64),
    hole_in: f64,
    bend: f64,
    under_gauge: &[f64],
    spacing: &[f64],
    collar_extra: &str,
) -> (Vec<String>, f64) {
    let mut comps = vec![tube("bit", 0.3, cod, cid, "")];
    let mut used = 0.3;
    if bend > 0.0 {
        let motor_len = rng.random_range(6.0f64..9.0).round();
        comps.push(tube(
            "motor",
            motor_len,
            cod,
            cid,
            &format!(
                "bend = \"{bend:.2} deg\"\nbend_from_bottom = \"{:.1} m\"\n",
                rng.random_range(1.0..2.5)
            ),
        ));
        used += motor_len;
    }
    for (k, (ug, gap)) in under_gauge.iter().zip(spacing).enumerate() {
        if k > 0 {
            comps.push(tube("collar", *gap, cod, cid, collar_extra));
            used += gap;
        }
        comps.push(tube(
            "stabilizer",
            1.5,
            cod,
            cid,
            &format!("blade_diameter = \"{:.4} in\"\n", hole_in - ug),
        ));
        used += 1.5;
    }
    (comps, used)
}

/// Draws well `seed` and writes it into `dir` (`well_<seed>.toml` and `.csv`). The weight on
/// bit is drawn up to the soft-string sinusoidal-buckling limit of the string as meshed,
/// so the case is read once without it first.
pub fn write_well(seed: u64, dir: &Path) -> Result<CorpusWell, Error> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let trajectory = pick(
        &mut rng,
        &[
            (Trajectory::Vertical, 0.1),
            (Trajectory::BuildAndHold, 0.35),
            (Trajectory::SShaped, 0.25),
            (Trajectory::Horizontal, 0.3),
        ],
    );
    let total_md = rng.random_range(1000.0f64..4500.0).round();
    let (stations, turn) = survey(&mut rng, trajectory, total_md);
    let size = &SIZES[rng.random_range(0..SIZES.len())];
    let shoe = (rng.random_range(0.2..0.7) * total_md).round();
    let mu_cased = rng.random_range(0.15..0.25);
    let mu_open = rng.random_range(0.2..0.4);
    let sg = rng.random_range(1.0..1.8);
    let collar = size.collars[rng.random_range(0..size.collars.len())];
    let collar_len = rng.random_range(30.0f64..250.0).round();
    let hwdp_len = if rng.random_bool(0.6) {
        rng.random_range(50.0f64..300.0).round()
    } else {
        0.0
    };
    let stabilizers = pick(
        &mut rng,
        &[(0usize, 0.2), (1, 0.3), (2, 0.25), (3, 0.15), (4, 0.1)],
    );
    let bend = if rng.random_bool(0.125) {
        rng.random_range(0.5f64..2.0)
    } else {
        0.0
    };
    let mode = pick(
        &mut rng,
        &[
            ("rotating", 0.2),
            ("drilling", 0.3),
            ("sliding", 0.15),
            ("tripping_in", 0.175),
            ("tripping_out", 0.175),
        ],
    );
    let wob_fraction: f64 = rng.random();
    let rpm = rng.random_range(40.0f64..180.0).round();
    let element: f64 = pick(
        &mut rng,
        &[
            (0.5, 0.05),
            (1.0, 0.1),
            (2.0, 0.1),
            (5.0, 0.2),
            (10.0, 0.25),
            (15.0, 0.05),
            (20.0, 0.15),
            (30.0, 0.1),
        ],
    );
    let bha_element: f64 = pick(
        &mut rng,
        &[
            (0.25f64, 0.1),
            (0.5, 0.25),
            (1.0, 0.35),
            (1.5, 0.15),
            (2.0, 0.15),
        ],
    )
    .min(element);
    let sites = if trajectory == Trajectory::Vertical && stabilizers > 0 && rng.random_bool(0.5) {
        "stabilizers"
    } else {
        "all_nodes"
    };
    let exponent = pick(&mut rng, &[(1.0, 0.8), (1.5, 0.1), (2.0 / 3.0, 0.1)]);
    let k_linear = 10f64.powf(rng.random_range(6.0..9.0));
    let wall_stiffness = k_linear * 1e-3f64.powf(1.0 - exponent);
    let under_gauge: Vec<f64> = (0..stabilizers)
        .map(|_| rng.random_range(0.0..0.5))
        .collect();
    let spacing: Vec<f64> = (0..stabilizers)
        .map(|_| rng.random_range(5.0f64..30.0).round())
        .collect();

    // The string from the bit up.
    let (mut comps, mut used) = bha_bottom(
        &mut rng,
        collar,
        size.hole_in,
        bend,
        &under_gauge,
        &spacing,
        "",
    );
    let (cod, cid) = collar;
    let rest = (collar_len - used).max(9.0);
    comps.push(tube("collar", rest, cod, cid, ""));
    used += rest;
    if hwdp_len > 0.0 {
        comps.push(tube("hwdp", hwdp_len, size.hwdp.0, size.hwdp.1, ""));
        used += hwdp_len;
    }
    comps.push(tube(
        "drill_pipe",
        (total_md - used + 1.0).max(1.0).round(),
        size.pipe.0,
        size.pipe.1,
        "",
    ));

    let name = format!("well_{seed}");
    let csv_name = write_survey(dir, &name, &stations)?;
    let max_inc = stations.iter().map(|s| s[1]).fold(0.0, f64::max);
    let (op_mode, rotating) = match mode {
        "drilling" => ("rotating", true),
        "rotating" => ("rotating", true),
        m => (m, false),
    };
    let on_bottom = matches!(mode, "drilling" | "sliding");
    let case_text = |wob: f64| {
        let mut t = format!(
            "title = \"corpus well {seed}: {} {}{}, {total_md} m, {} in hole, {mode}\"\n",
            trajectory.name(),
            if turn { "with turn" } else { "" },
            if bend > 0.0 { ", bent housing" } else { "" },
            size.hole_in
        );
        t.push_str(&format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"{csv_name}\"\ntotal_md = \"{total_md} m\"\n"
        ));
        t.push_str(&format!(
            "[[hole]]\nbottom_md = \"{shoe} m\"\ndiameter = \"{} in\"\ncased = true\nfriction = {mu_cased:.3}\n",
            size.casing_id_in
        ));
        t.push_str(&format!(
            "[[hole]]\nbottom_md = \"{total_md} m\"\ndiameter = \"{} in\"\nfriction = {mu_open:.3}\n",
            size.hole_in
        ));
        t.push_str(&format!("[mud]\ndensity = \"{sg:.3} sg\"\n"));
        for c in &comps {
            t.push_str(c);
        }
        t.push_str(&format!("[operation]\nmode = \"{op_mode}\"\n"));
        if rotating {
            t.push_str(&format!("rpm = \"{rpm} rpm\"\n"));
        }
        if on_bottom && wob > 0.0 {
            t.push_str(&format!(
                "weight_on_bit = \"{:.3} kN\"\ntorque_on_bit = \"{:.3} kN.m\"\n",
                wob / 1e3,
                if rotating {
                    0.02 * wob / 1e3 * size.hole_in * INCH / 0.2159
                } else {
                    0.0
                }
            ));
        }
        t.push_str(&contact_and_mesh(
            sites,
            wall_stiffness,
            exponent,
            element,
            bha_element,
        ));
        t
    };
    let spec = WellSpec {
        seed,
        trajectory,
        turn,
        total_md,
        max_inclination_deg: max_inc,
        hole_in: size.hole_in,
        mode: mode.to_string(),
        wob_n: 0.0,
        element_m: element,
        bha_element_m: bha_element,
        stabilizers,
        bend_deg: bend,
        sites: sites.to_string(),
        wall_stiffness,
        exponent,
    };
    let wob_of = |limit: f64| (wob_fraction * limit.min(150e3) / 100.0).round() * 100.0;
    write_at_wob(dir.join(format!("{name}.toml")), spec, &case_text, &wob_of)
}

/// Writes a drawn well's case (both styles): on bottom (drilling, sliding) at the weight on
/// bit `wob_of` gives for the buckling-limited WOB ([`buckling_limited_wob`]) of the case
/// read without one, off bottom at none; `case_text` writes the case at a WOB (N), and
/// `spec` takes the WOB written.
fn write_at_wob(
    case_path: PathBuf,
    mut spec: WellSpec,
    case_text: &dyn Fn(f64) -> String,
    wob_of: &dyn Fn(f64) -> f64,
) -> Result<CorpusWell, Error> {
    if matches!(spec.mode.as_str(), "drilling" | "sliding") {
        let case = crate::case::parse_case(&case_path, &case_text(0.0))?;
        spec.wob_n = wob_of(buckling_limited_wob(&case, spec.mode == "sliding"));
    }
    crate::output::write_atomic(&case_path, case_text(spec.wob_n).as_bytes())?;
    Ok(CorpusWell { spec, case_path })
}

/// The largest weight on bit (N) at which the soft-string compression stays below the
/// sinusoidal-buckling load of every element (bisection; friction of the operation).
pub fn buckling_limited_wob(case: &crate::case::Case, sliding: bool) -> f64 {
    use crate::solve::soft_string::{soft_string_with, Operation};
    let model = &case.model;
    let ok = |wob: f64| {
        let op = Operation {
            axial_speed: if sliding { 0.01 } else { 0.0 },
            rotation_speed: if sliding { 0.0 } else { 1.0 },
            weight_on_bit: wob,
            torque_on_bit: 0.0,
            friction: 0.0,
        };
        let prof = soft_string_with(model, &op, &|md| case.hole_at(md).friction);
        (0..model.elements.len()).all(|e| {
            let f = -0.5 * (prof.tension[e] + prof.tension[e + 1]);
            let md = 0.5 * (model.nodes[e].md + model.nodes[e + 1].md);
            f <= 0.0 || f <= crate::diagnose::critical_loads(model, e, case.hole_diameter_at(md)).0
        })
    };
    let (mut lo, mut hi) = (0.0, 1e6);
    if !ok(lo) {
        return 0.0;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// One well's outcome (a row of `corpus.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct WellResult {
    /// The well.
    #[serde(skip)]
    pub spec: WellSpec,
    /// Nodes of the mesh.
    pub nodes: usize,
    /// Whether the FE static solve converged at full load.
    pub solved: bool,
    /// Load steps completed (the gravity stage included).
    pub load_steps: usize,
    /// Load-step cuts and stage changes (each a result to report, not a pass).
    pub step_cuts: usize,
    /// Whether the load path relaxed past a fold ([`crate::solve::continuation`]): solved,
    /// reported apart.
    pub relaxed: bool,
    /// Newton iterations of the completed load steps.
    pub iterations: usize,
    /// Every Newton iteration the solve ran, failed tries, cut steps and relaxation
    /// sub-solves included (what the time was spent on; for failed wells too).
    pub newton_iterations: usize,
    /// Wall time of the FE solve (s).
    pub seconds: f64,
    /// FE hook load (N).
    pub fe_hook_load_n: f64,
    /// Soft-string hook load (N).
    pub soft_hook_load_n: f64,
    /// The drag a helically buckled string adds to the soft string's profile (N; 0 where
    /// no element passes its helical load: [`crate::diagnose::helical_drag`]).
    pub helical_drag_n: f64,
    /// Where a soft string carrying its buckled shape's wall force locks up (MD, m; NaN
    /// where it does not: [`crate::diagnose::lock_up`]).
    pub lock_up_md_m: f64,
    /// The load factor (friction and bit loads) at which that soft string starts to lock up
    /// (NaN where it does not: [`crate::diagnose::lock_up_fraction`]).
    pub lock_up_fraction: f64,
    /// Where a turning buckled string presses the wall harder than anything holds it: the
    /// MD of its worst element (m; NaN where none: [`crate::diagnose::rotating_whirl`]).
    pub whirl_md_m: f64,
    /// Solved by a second solve after the first failed, at the whirl's average over the
    /// span the FE string's own compression names ([`crate::profile::WHIRL_FROM_FE`]): a
    /// result to report (counted in `step_cuts` too).
    pub whirl_from_fe: bool,
    /// Solved by a relaxation that reached its ceiling and shifted the rotations too
    /// ([`crate::solve::continuation::ROTATIONS_SHIFTED`]): a result to report.
    pub rotations_shifted: bool,
    /// The load factor the FE solve reached: 1 when solved, where its load path stopped
    /// when not ([`crate::solve::statics::StaticError::reached`]; 0 in the gravity stage).
    pub fe_reached: f64,
    /// Failed where its load path bracketed where the string stops: the FE hook load (N)
    /// where it stands, at `fe_reached` ([`crate::solve::statics::Stopped`]); else NaN.
    pub stopped_hook_load_n: f64,
    /// Solved: how far the FE string lies outside the hole where no contact site holds it
    /// (mm; 0 inside it: [`crate::diagnose::through_wall`]). NaN when not solved.
    pub through_wall_mm: f64,
    /// Solved: how far the pipe's middle sags beyond the wall between two nodes not both
    /// contact sites (mm; 0 where every such span stays in the hole:
    /// [`crate::diagnose::span_through_wall`]). NaN when not solved.
    pub span_sag_mm: f64,
    /// Solved: whether its axial stress passes every API grade's yield somewhere
    /// ([`crate::diagnose::past_yield`]: an answer no pipe carries). False when not solved.
    pub past_yield: bool,
    /// Pipe-body contact sites the solve kept where the string lies on the wall (its guards
    /// in contact: [`crate::profile::solve_in_hole`]; 0 with contact at every node).
    pub wall_sites: usize,
    /// FE / soft-string hook load.
    pub hook_load_ratio: f64,
    /// FE surface torque (N·m).
    pub fe_torque_nm: f64,
    /// Soft-string surface torque (N·m).
    pub soft_torque_nm: f64,
    /// FE / soft-string surface torque (rotating modes; NaN otherwise).
    pub torque_ratio: f64,
    /// The failure's message (empty when solved).
    pub error: String,
    /// Largest contact (side) force, FE (N).
    pub max_side_force_n: f64,
    /// Where it acts (MD, m).
    pub max_side_force_md_m: f64,
    /// Each stabilizer's contact force, nearest the bit first (N).
    pub stabilizer_forces_n: Vec<f64>,
}

/// Solves a corpus well with the FE static solve (on the CPU, f64) and the soft string.
pub fn run_well(
    well: &CorpusWell,
    options: &crate::solve::statics::StaticOptions,
) -> Result<WellResult, Error> {
    let mut case = crate::case::load_case(&well.case_path)?;
    let soft = case.soft_string();
    let clock = std::time::Instant::now();
    // Every Newton iteration the load path runs, those of failed tries, relaxation
    // sub-solves and solves again with contact added at the wall included (the progress
    // callback is called once per iteration).
    let mut newton_iterations = 0usize;
    let mut model = case.model.clone();
    let sites_before = model.sites.len();
    let solved = crate::profile::solve_in_hole(
        &case,
        &mut model,
        &mut |m, nodes| crate::profile::add_wall_sites(&case, m, nodes),
        options,
        &mut |_| newton_iterations += 1,
    );
    let wall_sites = model.sites.len() - sites_before;
    case.model = model;
    let model = &case.model;
    let seconds = clock.elapsed().as_secs_f64();
    let rotating = model.rotation_speed != 0.0;
    let mut r = WellResult {
        spec: well.spec.clone(),
        nodes: model.nodes.len(),
        solved: false,
        load_steps: 0,
        step_cuts: 0,
        relaxed: false,
        iterations: 0,
        newton_iterations,
        seconds,
        fe_hook_load_n: f64::NAN,
        soft_hook_load_n: soft.hook_load(),
        helical_drag_n: crate::diagnose::helical_drag(&case, &soft.tension),
        lock_up_md_m: crate::diagnose::lock_up(&case).map_or(f64::NAN, |l| l.md),
        lock_up_fraction: crate::diagnose::lock_up_fraction(&case).unwrap_or(f64::NAN),
        whirl_md_m: crate::diagnose::rotating_whirl(&case, &soft.tension, &soft.side_force)
            .map_or(f64::NAN, |w| w.md),
        whirl_from_fe: false,
        rotations_shifted: false,
        fe_reached: 0.0,
        stopped_hook_load_n: f64::NAN,
        through_wall_mm: f64::NAN,
        span_sag_mm: f64::NAN,
        wall_sites,
        past_yield: false,
        hook_load_ratio: f64::NAN,
        fe_torque_nm: f64::NAN,
        soft_torque_nm: soft.surface_torque(),
        torque_ratio: f64::NAN,
        error: String::new(),
        max_side_force_n: f64::NAN,
        max_side_force_md_m: f64::NAN,
        stabilizer_forces_n: Vec::new(),
    };
    match solved {
        Ok(sol) => {
            let (_, hook, torque, _) = crate::profile::fe_rows(model, &sol);
            r.solved = true;
            r.fe_reached = 1.0;
            r.through_wall_mm = crate::diagnose::through_wall(&case, model, &sol.state)
                .map_or(0.0, |t| 1e3 * t.excess_m);
            let axial: Vec<f64> = sol.section_forces.iter().map(|f| f.axial).collect();
            r.past_yield = crate::diagnose::past_yield(&case, &axial).is_some();
            r.span_sag_mm = crate::diagnose::span_through_wall(&case, model, &sol.state, &axial)
                .map_or(0.0, |t| 1e3 * t.excess_m);
            r.load_steps = sol.iterations.len();
            r.step_cuts = crate::profile::path_events(&sol.log);
            r.relaxed = crate::solve::continuation::relaxed(&sol.log);
            r.whirl_from_fe = sol
                .log
                .iter()
                .any(|l| l.starts_with(crate::profile::WHIRL_FROM_FE));
            r.rotations_shifted = crate::solve::continuation::rotations_shifted(&sol.log);
            r.iterations = sol.iterations.iter().sum();
            r.fe_hook_load_n = hook;
            r.hook_load_ratio = hook / r.soft_hook_load_n;
            r.fe_torque_nm = torque;
            let mut stabs: Vec<(f64, f64)> = Vec::new();
            for (site, c) in model.sites.iter().zip(&sol.contact) {
                let md = model.nodes[site.node].md;
                if c.1.abs() > r.max_side_force_n.abs() || r.max_side_force_n.is_nan() {
                    r.max_side_force_n = c.1.abs();
                    r.max_side_force_md_m = md;
                }
                if site.stabilizer {
                    stabs.push((-md, c.1.abs()));
                }
            }
            stabs.sort_by(|a, b| a.0.total_cmp(&b.0));
            r.stabilizer_forces_n = stabs.into_iter().map(|s| s.1).collect();
            if rotating {
                r.torque_ratio = torque / r.soft_torque_nm;
            }
        }
        Err(e) => {
            r.fe_reached = e.reached();
            if let Some(st) = e.stopped() {
                r.stopped_hook_load_n = crate::profile::stopped_hook_load(st);
            }
            r.error = crate::diagnose::static_failure(&case, &e);
        }
    }
    Ok(r)
}

/// The same well meshed anew: pipe elements of `element` m, BHA elements of `bha_element`
/// m (the case file rewritten beside the original as `well_<seed>_<element>m.toml`).
pub fn remesh(well: &CorpusWell, element: f64, bha_element: f64) -> Result<CorpusWell, Error> {
    let text = std::fs::read_to_string(&well.case_path)?;
    let head = text
        .split("[mesh]")
        .next()
        .ok_or_else(|| Error::failed("a corpus case without its [mesh] table"))?
        .to_string();
    let text = format!(
        "{head}[mesh]\nelement_length = \"{element} m\"\nbha_element_length = \"{bha_element} m\"\n"
    );
    let path = well
        .case_path
        .with_file_name(format!("well_{}_{element}m.toml", well.spec.seed));
    crate::output::write_atomic(&path, text.as_bytes())?;
    let mut spec = well.spec.clone();
    spec.element_m = element;
    spec.bha_element_m = bha_element;
    Ok(CorpusWell {
        spec,
        case_path: path,
    })
}

/// The meshes of the mesh-convergence study: (pipe, BHA) element lengths, coarse to fine.
pub const MESHES: [(f64, f64); 7] = [
    (30.0, 2.0),
    (20.0, 2.0),
    (10.0, 1.0),
    (5.0, 1.0),
    (2.0, 0.5),
    (1.0, 0.5),
    (0.5, 0.25),
];

/// The wells of the mesh-convergence study: from seed 0 on, the first build-and-hold, the
/// first S-shaped and the first horizontal well drilling or rotating with a stabilizer
/// and contact at every node (chosen by rule, not by outcome).
pub fn mesh_study_seeds(dir: &Path) -> Result<Vec<u64>, Error> {
    let mut out = Vec::new();
    for kind in [
        Trajectory::BuildAndHold,
        Trajectory::SShaped,
        Trajectory::Horizontal,
    ] {
        for seed in 0..10_000u64 {
            let w = write_well(seed, dir)?;
            let s = &w.spec;
            if s.trajectory == kind
                && s.stabilizers > 0
                && s.sites == "all_nodes"
                && matches!(s.mode.as_str(), "drilling" | "rotating")
            {
                out.push(seed);
                break;
            }
        }
    }
    Ok(out)
}
