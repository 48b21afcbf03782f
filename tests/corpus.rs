//! The corpus of ordinary wells (issue 22) in CI: the first 50 seeds of
//! `holewall bench corpus` (500 wells there), solved on the CPU, and the smallest of them
//! through the ensemble engine (CPU twins, GPU f64 and f32).
//!
//! What fails here is a result, not noise: the count of solved wells may only rise (raise
//! `SOLVED_AT_LEAST` with the solver), a well solved outside its hole
//! (`holewall::diagnose::through_wall`: after `profile::solve_in_hole` added contact where
//! the string met the wall, none should be) does not count as solved, and every solved well must
//! agree with the soft string on the hook load as a stiff string does.

mod common;

use holewall::corpus::{run_well, run_well_engine, write_well, EnginePath, WellResult};

/// Solved of the first 50 seeds: 50 with a relaxation budget of 20,000 Newton iterations
/// (seed 44, horizontal, sliding, 2 m elements, settles after 13,689); 49 where a load step that fails at the smallest step
/// first tries the rest of the load at once (seed 28) and a step whose residual has not
/// halved in 80 iterations is cut; 48 with a relaxation that settles where its residual
/// stalls at 2–3e-9 of the force scale (seed 0 too); 47 with the relaxation past a fold
/// (seed 17 relaxed); 46 with the prestressed start and 200 Newton iterations per step (42
/// with 100); the solver before issue 22 (low-side start, 40 iterations) solved 30.
const SOLVED_AT_LEAST: usize = 50;
const WELLS: u64 = 50;

fn corpus() -> (
    tempdir::Dir,
    Vec<(holewall::corpus::CorpusWell, WellResult)>,
) {
    let dir = tempdir::Dir::new("corpus");
    let rows = (0..WELLS)
        .map(|seed| {
            let well = write_well(seed, dir.path()).unwrap_or_else(|e| {
                panic!("seed {seed}: the generator wrote a case the parser refuses: {e}")
            });
            let r = run_well(&well, &Default::default()).unwrap();
            (well, r)
        })
        .collect();
    (dir, rows)
}

/// A folder removed when dropped.
mod tempdir {
    pub struct Dir(std::path::PathBuf);
    impl Dir {
        pub fn new(name: &str) -> Dir {
            let p = std::env::temp_dir().join(format!("holewall_{name}_{}", std::process::id()));
            std::fs::create_dir_all(&p).unwrap();
            Dir(p)
        }
        pub fn path(&self) -> &std::path::Path {
            &self.0
        }
    }
    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

#[test]
fn corpus_sample_solves_and_agrees_with_the_soft_string() {
    let (_dir, rows) = corpus();
    let solved = solved_and_agreeing(&rows);
    eprintln!("corpus sample: {solved} of {WELLS} solved");
    assert!(
        solved >= SOLVED_AT_LEAST,
        "{solved} of {WELLS} corpus wells solved; {SOLVED_AT_LEAST} did when this was written"
    );
}

/// Solved of the user-style seeds 0–15 (`holewall bench corpus --style user`; stop 68): all
/// but seed 0, a horizontal well tripped in that locks up (its soft string runs away at MD
/// 1,526 m), which fails in 20 s saying so.
const USER_SOLVED_AT_LEAST: usize = 15;
const USER_SEEDS: std::ops::RangeInclusive<u64> = 0..=15;

/// The corpus's user style (tool joints, reaming and back-reaming, three hole sections,
/// tapered pipe, WOB past the buckling limit; src/corpus/user.rs) in CI: a sample solved
/// and checked as the drawn sample is.
#[test]
fn user_style_sample_solves_and_agrees_with_the_soft_string() {
    let dir = tempdir::Dir::new("corpus_user");
    let rows: Vec<_> = USER_SEEDS
        .map(|seed| {
            let well =
                holewall::corpus::user::write_user_well(seed, dir.path()).unwrap_or_else(|e| {
                    panic!("user seed {seed}: the generator wrote a case the parser refuses: {e}")
                });
            let r = run_well(&well, &Default::default()).unwrap();
            (well, r)
        })
        .collect();
    let solved = solved_and_agreeing(&rows);
    eprintln!("user-style sample: {solved} of {} solved", rows.len());
    assert!(
        solved >= USER_SOLVED_AT_LEAST,
        "{solved} of {} user-style wells solved; {USER_SOLVED_AT_LEAST} did when this was written",
        rows.len()
    );
}

/// `holewall bench corpus` names the solved wells the surface pushes (FE hook load below
/// zero: the equilibrium past a lock-up, docs/performance.md stop 81) in `summary.json` and
/// its line, and lists the wells of about 10 m elements over 2 s with whether they are
/// pushed. Drawn 2256 (tripped in, 20 m elements) is pushed with 9.7 kN; 2283 (drilling)
/// hangs from the hook.
#[test]
fn the_corpus_summary_names_the_pushed_strings() {
    let dir = common::scratch_dir("corpus", "pushed");
    let out = dir.join("out");
    let (code, stdout, stderr) = common::holewall(&[
        "bench",
        "corpus",
        "--seeds",
        "2256,2283",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("2 of 2 wells solved") && stdout.contains("1 pushed from the surface"),
        "{stdout}"
    );
    let summary: serde_json::Value = common::json(&out.join("summary.json"));
    assert_eq!(
        summary["solved_pushed"],
        serde_json::json!([2256]),
        "{summary}"
    );
    let rows = std::fs::read_to_string(out.join("corpus.csv")).unwrap();
    let header: Vec<&str> = rows.lines().next().unwrap().split(',').collect();
    let col = |k: &str| header.iter().position(|h| *h == k).unwrap();
    for line in rows.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let hook: f64 = f[col("fe_hook_load_n")].parse().unwrap();
        let seed: u64 = f[col("seed")].parse().unwrap();
        assert_eq!(hook < 0.0, seed == 2256, "seed {seed}: hook load {hook} N");
    }
    // Neither well is meshed at about 10 m: none is listed against the 2 s.
    assert_eq!(summary["over_2s_10m"], serde_json::json!([]), "{summary}");
}

/// Checks every solved well of `rows` against the soft string and every failure's words;
/// returns the wells solved inside their hole.
fn solved_and_agreeing(rows: &[(holewall::corpus::CorpusWell, WellResult)]) -> usize {
    let mut solved = 0;
    for (well, r) in rows {
        let s = &r.spec;
        eprintln!(
            "seed {:>3} {:<14} {:<12} {:>5} m, {:>4}/{:<4} m elements, {:>5} nodes: {} in {:.2} s, {} its, {} cuts, hook FE/soft {:.3}, torque {:.3} {}",
            s.seed,
            s.trajectory.name(),
            s.mode,
            s.total_md,
            s.element_m,
            s.bha_element_m,
            r.nodes,
            if r.solved { "solved" } else { "FAILED" },
            r.seconds,
            r.iterations,
            r.step_cuts,
            r.hook_load_ratio,
            r.torque_ratio,
            r.error.lines().next().unwrap_or_default()
        );
        if !r.solved {
            // A failure must say where and what to change.
            assert!(
                r.error.contains("MD") && !r.error.contains("0.0 % of 0.0 kN"),
                "seed {}: {}",
                s.seed,
                r.error
            );
            continue;
        }
        if r.through_wall_mm > 0.0 {
            // An equilibrium of a string outside its hole (contact at the stabilizers only):
            // no answer, and not counted as one.
            eprintln!(
                "seed {}: solved {:.0} mm outside the hole between contact sites",
                s.seed, r.through_wall_mm
            );
            continue;
        }
        solved += 1;
        let (fe, soft, drag) = (r.fe_hook_load_n, r.soft_hook_load_n, r.helical_drag_n);
        if drag > 0.07 * soft.abs() {
            // Compressed past its helical load, the string winds into a helix whose wall
            // force (Mitchell's `r F²/4EI`) adds drag a soft string leaves out: a stiff
            // string's hook load lies below the soft string's, by at most a few times that
            // drag's first-order estimate (the FE's coarser helix carries less of it), never
            // above it beyond the 7 % of a straight string.
            assert!(
                fe <= soft + 0.07 * soft.abs() && fe >= soft - 3.0 * drag,
                "seed {}: helically buckled, FE hook load {fe} N against the soft string's {soft} N less up to 3 × {drag} N of helix drag",
                s.seed
            );
        } else {
            // A stiff string carries the hook load a cable does, to a few per cent (side
            // forces differ where the pipe spans a bend; the issue's wells agreed within
            // 2.2 %).
            assert!(
                (0.93..=1.07).contains(&r.hook_load_ratio),
                "seed {}: FE/soft-string hook load {}",
                s.seed,
                r.hook_load_ratio
            );
        }
        // Torque: in a deviated hole (the pipe on the wall along most of its length) within
        // 40 %; near-vertical holes touch the wall only at survey noise, which a soft string
        // counts in full and a stiff string spans. With tool joints the soft string turns
        // every contact on the joints' radius, while the stiff string, pulled straight
        // between its joints through a dogleg, bears on its body there too (stop 68: the
        // user style's back-reaming wells 0.54–0.85 with joints, 0.76–0.95 without): the
        // lower bound falls by the body's radius over the joint's.
        if s.max_inclination_deg > 10.0 && r.torque_ratio.is_finite() {
            let case = holewall::case::load_case(&well.case_path).unwrap();
            let arm = case
                .model
                .elements
                .iter()
                .map(|e| e.outer_diameter / e.contact_diameter)
                .fold(1.0, f64::min);
            assert!(
                (0.6 * arm..=1.4).contains(&r.torque_ratio),
                "seed {}: FE/soft-string torque {}",
                s.seed,
                r.torque_ratio
            );
        }
    }
    solved
}

/// The engine paths this machine runs: the twins, and the GPU in f64 (where the adapter has
/// it) and f32 where there is an adapter.
fn engine_paths() -> Vec<EnginePath> {
    let mut paths = vec![EnginePath::Twin];
    if let Some(ctx) = common::gpu() {
        if ctx.has_f64 {
            paths.push(EnginePath::GpuF64);
        }
        paths.push(EnginePath::GpuF32);
    }
    paths
}

#[test]
fn corpus_wells_through_the_engine_match_the_cpu() {
    let dir = tempdir::Dir::new("corpus_engine");
    // The three smallest meshes of the first 50 seeds that the CPU solves: lavapipe runs
    // every kernel on the CPU.
    let mut rows: Vec<_> = (0..WELLS)
        .map(|seed| {
            let well = write_well(seed, dir.path()).unwrap();
            let nodes = holewall::case::load_case(&well.case_path)
                .unwrap()
                .model
                .nodes
                .len();
            (nodes, well)
        })
        .collect();
    rows.sort_by_key(|r| r.0);
    let mut checked = 0;
    for (_, well) in rows {
        let cpu = run_well(&well, &Default::default()).unwrap();
        if !cpu.solved {
            continue;
        }
        for path in engine_paths() {
            let e = run_well_engine(&well, path).unwrap();
            let diff = ((e.hook_load_n - cpu.fe_hook_load_n) / cpu.fe_hook_load_n).abs();
            eprintln!(
                "seed {} {path:?}: solved {} in {} iterations, {} cuts, hook load vs CPU {diff:.2e} {}",
                well.spec.seed, e.solved, e.iterations, e.step_cuts, e.error
            );
            assert!(e.solved, "seed {} {path:?}: {}", well.spec.seed, e.error);
            let tol = if path == EnginePath::GpuF32 {
                1e-4
            } else {
                1e-9
            };
            assert!(
                diff <= tol,
                "seed {} {path:?}: hook load off by {diff:e}",
                well.spec.seed
            );
        }
        checked += 1;
        if checked == 3 {
            break;
        }
    }
    assert_eq!(checked, 3);
}

/// The engine holds a string in the hole where it meets the wall as the CPU run does
/// (`profile::solve_in_hole`'s policy, each solve the engine's): corpus seed 94 (vertical,
/// contact at its stabilizers, 135 nodes) meets the wall between them; on every path the
/// engine adds the CPU run's sites and ends at its hook load.
#[test]
fn the_engine_holds_a_stabilizer_contact_well_in_the_hole_as_the_cpu_does() {
    let dir = tempdir::Dir::new("corpus_engine_wall");
    let well = write_well(94, dir.path()).unwrap();
    assert_eq!(well.spec.sites, "stabilizers");
    let cpu = run_well(&well, &Default::default()).unwrap();
    assert!(
        cpu.solved && cpu.wall_sites > 0,
        "{} sites added",
        cpu.wall_sites
    );
    for path in engine_paths() {
        let e = run_well_engine(&well, path).unwrap();
        let diff = ((e.hook_load_n - cpu.fe_hook_load_n) / cpu.fe_hook_load_n).abs();
        eprintln!(
            "seed 94 {path:?}: {} sites added (CPU {}), hook load vs CPU {diff:.2e}",
            e.wall_sites, cpu.wall_sites
        );
        assert!(e.solved, "{path:?}: {}", e.error);
        assert_eq!(e.wall_sites, cpu.wall_sites, "{path:?}");
        let tol = if path == EnginePath::GpuF32 {
            1e-5
        } else {
            1e-9
        };
        assert!(diff <= tol, "{path:?}: hook load off by {diff:e}");
    }
}

/// Two folds beyond the first 50 seeds that a relaxation whose shift stops at 1e-3 of its
/// start could not pass (each failed with it: the relaxation spent its budget), and that the
/// floor of 1e-5 (`continuation::RELAX_FLOOR`) solves: seed 206 (horizontal, tripping in,
/// 10 m elements) relaxes past a fold of the load steps, seed 372 (near-vertical, sliding,
/// stabilizer-only contact) in the gravity stage. Both must solve (206 relaxed), with the
/// hook load within 7 % of the soft string's. Seed 372's string meets the wall above its stabilizers,
/// where it has no contact site (it lay metres outside its hole before contact was added
/// there: `diagnose::through_wall`): it must end in the hole with sites added there
/// (`profile::solve_in_hole`), and 206 (contact at every node) with none.
#[test]
fn folds_beyond_the_sample_solve_by_relaxation() {
    let dir = tempdir::Dir::new("corpus_folds");
    for seed in [206, 372] {
        let well = write_well(seed, dir.path()).unwrap();
        let r = run_well(&well, &Default::default()).unwrap();
        eprintln!(
            "seed {seed}: solved {} in {:.2} s, {} Newton iterations, relaxed {}, hook FE {:.1} kN / soft {:.1} kN {}",
            r.solved,
            r.seconds,
            r.newton_iterations,
            r.relaxed,
            r.fe_hook_load_n / 1e3,
            r.soft_hook_load_n / 1e3,
            r.error
        );
        assert!(r.solved, "seed {seed}: {}", r.error);
        // 372 relaxes in its first solve; held at the wall, its last solve needs none.
        assert!(
            r.relaxed || seed == 372,
            "seed {seed}: solved without relaxing"
        );
        assert_eq!(r.through_wall_mm, 0.0, "seed {seed}: outside the hole");
        assert_eq!(
            r.wall_sites > 0,
            seed == 372,
            "seed {seed}: {} sites added at the wall",
            r.wall_sites
        );
        assert!(
            (r.hook_load_ratio - 1.0).abs() <= 0.07,
            "seed {seed}: FE/soft-string hook load {}",
            r.hook_load_ratio
        );
    }
}

/// `holewall static` says where its answer came by relaxation past a fold, whose
/// equilibrium is one of several (`holewall::diagnose::relaxed_warning`): corpus well 17
/// (horizontal, tripped in, 10 m elements) relaxes and is told so; well 1 (tripped out,
/// 30 m) does not relax and gets no such warning.
#[test]
fn a_relaxed_answer_says_it_is_one_of_several() {
    let dir = tempdir::Dir::new("corpus_relaxed");
    for (seed, relaxes) in [(17, true), (1, false)] {
        let well = write_well(seed, dir.path()).unwrap();
        let out = dir.path().join(format!("out_{seed}"));
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_holewall"))
            .arg("static")
            .arg("--quiet")
            .arg("--out")
            .arg(&out)
            .arg(&well.case_path)
            .status()
            .unwrap();
        assert!(status.success(), "seed {seed}: holewall static failed");
        let summary: serde_json::Value = common::json(&out.join("summary.json"));
        let logged = summary["solver_log"].as_array().unwrap().iter().any(|l| {
            l.as_str()
                .unwrap()
                .contains(holewall::solve::continuation::RELAXED)
        });
        // (`warnings` is left out of the summary where there is none.)
        let warned = summary["warnings"].as_array().is_some_and(|ws| {
            ws.iter()
                .any(|w| w.as_str().unwrap().contains("relaxation past a fold"))
        });
        assert_eq!(logged, relaxes, "seed {seed}: relaxed");
        assert_eq!(warned, relaxes, "seed {seed}: {:?}", summary["warnings"]);
    }
}

/// An ensemble says which variants relaxed (`variants.csv`: `relaxed`; `summary.json`:
/// `relaxed`, with a warning): corpus well 17 tripped in relaxes (as above), tripped out it
/// does not — as a static ensemble, and as a dynamic one (6 ms) whose static starts are
/// those equilibria, on the CPU and through the engine.
#[test]
fn an_ensemble_counts_its_relaxed_variants() {
    use holewall::backend::BackendChoice;
    let dir = tempdir::Dir::new("corpus_relaxed_ensemble");
    let well = write_well(17, dir.path()).unwrap();
    let variants = dir.path().join("modes.csv");
    std::fs::write(&variants, "mode\ntripping_in\ntripping_out\n").unwrap();
    let dynamic = dir.path().join("dynamic.toml");
    let text = std::fs::read_to_string(&well.case_path).unwrap();
    std::fs::write(
        &dynamic,
        format!(
            "{text}\n[dynamics]\nduration = \"0.006 s\"\ntime_step = \"2 ms\"\n\
             output_interval = \"2 ms\"\nramp_time = \"0.002 s\"\n\n[ensemble]\n\
             analysis = \"dynamic\"\n"
        ),
    )
    .unwrap();
    let gpu = common::gpu().is_some();
    let runs = [
        (
            &well.case_path,
            BackendChoice::Cpu,
            "reached their equilibria",
        ),
        (
            &dynamic,
            BackendChoice::Cpu,
            "started their dynamic runs from static",
        ),
    ]
    .into_iter()
    .chain(gpu.then_some((&dynamic, BackendChoice::Gpu, "started their dynamic runs")));
    for (k, (case, backend, said)) in runs.enumerate() {
        let out = dir.path().join(format!("out_{k}"));
        let s = common::ensemble_on(case, Some(&variants), backend, &out);
        assert_eq!((s.variants, s.failed, s.relaxed), (2, 0, 1), "{s:?}");
        let told = s
            .notices()
            .iter()
            .any(|n| n.contains(&format!("1 of 2 variants {said}")));
        assert!(told, "{:?}", s.notices());
        let mut csv = csv::Reader::from_path(out.join("variants.csv")).unwrap();
        let at = csv.headers().unwrap().iter().position(|h| h == "relaxed");
        let relaxed: Vec<String> = csv
            .records()
            .map(|r| r.unwrap()[at.unwrap()].to_string())
            .collect();
        assert_eq!(relaxed, ["true", "false"], "run {k}");
    }
}

/// `cases/build_and_hold_2500.toml` with its operation and mesh replaced.
fn reproducer(mode: &str, element: f64) -> holewall::case::Case {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/build_and_hold_2500.toml"
    ))
    .unwrap();
    let op = match mode {
        "drilling" => "mode = \"rotating\"\nrpm = \"120 rpm\"\nweight_on_bit = \"89 kN\"\n",
        "rotating" => "mode = \"rotating\"\nrpm = \"120 rpm\"\n",
        "tripping_in" => "mode = \"tripping_in\"\n",
        _ => "mode = \"tripping_out\"\n",
    };
    let head = text.split("[operation]").next().unwrap();
    let text = format!(
        "{head}[operation]\n{op}[contact]\nsites = \"all_nodes\"\n[mesh]\nelement_length = \"{element} m\"\nbha_element_length = \"1 m\"\n"
    );
    holewall::case::parse_case(
        std::path::Path::new("cases/build_and_hold_2500.toml"),
        &text,
    )
    .unwrap()
}

#[test]
fn issue_reproducer_solves_in_four_modes_at_four_meshes() {
    // Before issue 22 every 10 m and 5 m mesh of this well failed, in every mode.
    for mode in ["rotating", "tripping_in", "tripping_out", "drilling"] {
        let mut hooks = Vec::new();
        for element in [20.0, 10.0, 5.0, 1.0] {
            let case = reproducer(mode, element);
            let sol = holewall::solve::statics::solve_static(&case.model, &Default::default())
                .unwrap_or_else(|e| panic!("{mode} at {element} m: {e}"));
            let (_, hook, torque, _) = holewall::profile::fe_rows(&case.model, &sol);
            let soft = case.soft_string().hook_load();
            eprintln!(
                "{mode:>12} {element:>4} m: {} load steps, {} iterations, {} cuts; hook load {:.1} kN (soft string {:.1} kN), torque {:.2} kN·m",
                sol.iterations.len(),
                sol.iterations.iter().sum::<usize>(),
                sol.log.len(),
                hook / 1e3,
                soft / 1e3,
                torque / 1e3
            );
            assert!((hook / soft - 1.0).abs() < 0.03, "{mode} {element} m");
            hooks.push(hook);
        }
        // The hook load converges with the mesh (20 m → 1 m within 0.5 %).
        let spread = hooks
            .iter()
            .fold(0.0f64, |m, h| m.max((h / hooks[3] - 1.0).abs()));
        assert!(spread < 5e-3, "{mode}: hook loads {hooks:?}");
    }
}

#[test]
fn slick_pendulum_tangency_matches_the_closed_form_on_fine_meshes() {
    // A slick 6.5 in assembly in a straight horizontal 8.5 in hole at zero WOB, no friction:
    // a pinned beam (the bit held on the axis) lifting off the low side, tangent to it at
    // L = (24 EI c / w)^¼ from the bit, where the wall's concentrated reaction sits. Issue
    // 22: the FE solve failed with 0.1 m BHA elements.
    let dir = std::env::temp_dir().join(format!("holewall_slick_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("h.csv"),
        "md, inclination, azimuth\n0, 90, 0\n300, 90, 0\n",
    )
    .unwrap();
    for bha in [0.25, 0.1, 0.05] {
        let text = format!(
            "[well]\nprofile = \"survey\"\nsurvey = \"h.csv\"\ntotal_md = \"200 m\"\n\
             [[hole]]\nbottom_md = \"200 m\"\ndiameter = \"8.5 in\"\nfriction = 0.0\n\
             [mud]\ndensity = \"1.2 sg\"\n\
             [[string]]\nkind = \"collar\"\nlength = \"200 m\"\nod = \"6.5 in\"\nid = \"2.8125 in\"\n\
             [operation]\nmode = \"rotating\"\nrpm = \"60 rpm\"\n\
             [contact]\nsites = \"all_nodes\"\n\
             [mesh]\nelement_length = \"1 m\"\nbha_element_length = \"{bha} m\"\n"
        );
        let case = holewall::case::parse_case(&dir.join("slick.toml"), &text).unwrap();
        let m = &case.model;
        let sol = holewall::solve::statics::solve_static(m, &Default::default())
            .unwrap_or_else(|e| panic!("{bha} m: {e}"));
        let el = &m.elements[m.elements.len() - 1];
        let site = m.sites.last().unwrap();
        let l = (24.0 * el.section.bending_stiffness() * site.params.clearance
            / el.buoyed_weight_per_length)
            .powf(0.25);
        let bit = m.nodes.last().unwrap().md;
        let (_, at) = m
            .sites
            .iter()
            .zip(&sol.contact)
            .filter(|(s, _)| bit - m.nodes[s.node].md < 2.0 * l)
            .map(|(s, c)| (c.1.abs(), bit - m.nodes[s.node].md))
            .fold((0.0, f64::NAN), |a, b| if b.0 > a.0 { b } else { a });
        eprintln!("BHA elements {bha} m: tangency {at:.3} m from the bit, closed form {l:.3} m");
        assert!(
            (at - l).abs() <= (0.02 * l).max(bha),
            "{bha} m: {at} vs {l}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Dynamic cases of the dynamic corpus (`holewall bench dynamic-corpus`, 100 cases there) in
/// CI: the first `DYNAMIC_SAMPLE` seeds whose mesh has at most 150 nodes (chosen by rule,
/// not by outcome), each run as `holewall run` runs it. Every one must run to its end with
/// a finite state; step cuts are printed (a result to report), and an offset start must
/// not begin beyond the wall (`Case::offset_scale`).
const DYNAMIC_SAMPLE: usize = 12;

fn dynamic_sample(
    dir: &std::path::Path,
    count: usize,
    max_nodes: usize,
) -> Vec<holewall::corpus::dynamic::DynamicCase> {
    (0..1000u64)
        .map(|seed| holewall::corpus::dynamic::write_dynamic_case(seed, dir).unwrap())
        .filter(|c| {
            holewall::case::load_case(&c.case_path)
                .unwrap()
                .model
                .nodes
                .len()
                <= max_nodes
        })
        .take(count)
        .collect()
}

/// Dynamic corpus seed 12: contact at the stabilizers only, in a deviated hole, whose static
/// start meets the wall between the sites. The dynamic engine used to hand such a variant
/// wholly to the CPU; now its start is held at the wall on the CPU (sites added, as the CPU
/// run's) and its dynamics run on the engine, f64 within 1e-6 of the CPU run and f32 within
/// 1e-3.
#[test]
fn a_dynamic_corpus_case_that_meets_the_wall_runs_on_the_engine() {
    use holewall::corpus::dynamic::write_dynamic_case;
    if common::gpu().is_none() {
        return;
    }
    let dir = tempdir::Dir::new("dynamic_corpus_wall");
    let case = write_dynamic_case(12, dir.path()).unwrap();
    let loaded = holewall::case::load_case(&case.case_path).unwrap();
    assert!(
        loaded.model.sites.iter().all(|s| s.stabilizer),
        "seed 12 is no longer a stabilizer-contact case"
    );
    let (_, rows) = cpu_and_engine(&case);
    for (f32, e) in rows {
        eprintln!(
            "dynamic seed 12 {}: by engine {}, hook load {:.1e}, torque {:.1e}, stab1 force {:.1e} off the CPU's; {}",
            e.path, e.by_engine, e.hook_load_rel, e.torque_rel, e.stab1_force_rel, e.reason
        );
        let tol = assert_engine_matches_cpu(&e, f32);
        assert!(
            e.stab1_force_rel <= 10.0 * tol,
            "{}: {}",
            e.path,
            e.stab1_force_rel
        );
    }
}

#[test]
fn dynamic_corpus_sample_runs_to_the_end() {
    use holewall::corpus::dynamic::run_case_dynamic;
    let dir = tempdir::Dir::new("dynamic_corpus");
    let cases = dynamic_sample(dir.path(), DYNAMIC_SAMPLE, 150);
    let mut cut = 0;
    for case in &cases {
        let r = run_case_dynamic(case).unwrap();
        eprintln!(
            "dynamic seed {} ({} {}, {} nodes, {} s in {} ms steps): solved {}, {} cuts, {:.1} iterations per step, {:.1} s; {}",
            r.spec.seed,
            r.spec.class,
            r.spec.hole,
            r.nodes,
            r.spec.duration_s,
            1e3 * r.spec.time_step_s,
            r.solved,
            r.step_cuts,
            r.iterations_per_step,
            r.seconds,
            r.reason
        );
        assert!(r.solved, "dynamic seed {}: {}", r.spec.seed, r.reason);
        cut += usize::from(r.step_cuts > 0);
    }
    eprintln!(
        "dynamic corpus sample: {} / {} run to the end, {cut} with step cuts",
        cases.len(),
        cases.len()
    );
}

/// The smallest of the dynamic corpus through the GPU engine, f64 and f32, against the CPU
/// integrator (the first seed of at most 80 nodes with lumped mass, which the engine runs,
/// that the CPU runs without a step cut): solved by the engine itself, hook load and largest
/// surface torque to solver tolerance in f64. A run that cuts is the next test's.
#[test]
fn a_dynamic_corpus_case_through_the_engine_matches_the_cpu() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempdir::Dir::new("dynamic_corpus_engine");
    let (case, cpu) = first_small_lumped(dir.path(), |cpu| cpu.step_cuts == 0);
    for (f32, e) in engine_rows(&case, &cpu) {
        eprintln!(
            "dynamic seed {} {}: by engine {}, {} cuts ({} on the CPU), hook load {:.1e}, torque {:.1e}, stab1 force {:.1e} off the CPU's, same whirl {}, {:.1} s; {}",
            e.seed,
            e.path,
            e.by_engine,
            e.step_cuts,
            cpu.step_cuts,
            e.hook_load_rel,
            e.torque_rel,
            e.stab1_force_rel,
            e.same_whirl,
            e.seconds,
            e.reason
        );
        assert_engine_matches_cpu(&e, f32);
        // The CPU's own spread (its start changed by 1e-8): the change reached the run, and
        // this uncut run is not sensitive to its start (its end values are a test of the
        // engine, as above).
        eprintln!(
            "dynamic seed {}: the CPU's own spread, hook load {:.1e}, torque {:.1e}",
            e.seed, e.cpu_spread_hook_rel, e.cpu_spread_torque_rel
        );
        assert!(
            e.cpu_spread_hook_rel > 0.0 || e.cpu_spread_torque_rel > 0.0,
            "the perturbed start changed nothing"
        );
        assert!(
            e.cpu_spread_hook_rel <= 1e-4 && e.cpu_spread_torque_rel <= 1e-4,
            "{} {}",
            e.cpu_spread_hook_rel,
            e.cpu_spread_torque_rel
        );
    }
}

/// The first dynamic corpus case of at most 80 nodes (lumped mass) that the CPU integrator
/// runs with step cuts, through the GPU engine in f64: both cut and regrow by one policy
/// (`solve::dynamics::control`), so the engine cuts as often as the CPU and its hook load and
/// largest surface torque lie within ten times the CPU's own spread (the CPU run again with
/// its kick changed by 1e-8) or 1e-6, whichever is larger. Before the policy was shared the
/// CPU regrew a cut step in the middle of the engine's step: seed 5's hook loads parted by
/// 5.2e-2.
#[test]
fn a_dynamic_corpus_case_that_cuts_takes_the_cpus_steps_in_the_engine() {
    if common::gpu().is_none_or(|c| !c.has_f64) {
        return;
    }
    let dir = tempdir::Dir::new("dynamic_corpus_engine_cut");
    let (case, cpu) = first_small_lumped(dir.path(), |cpu| cpu.step_cuts > 0);
    let again = holewall::corpus::dynamic::run_case_perturbed(&case).unwrap();
    let e = holewall::corpus::dynamic::run_case_engine(&case, &cpu, &again, false).unwrap();
    eprintln!(
        "dynamic seed {} gpu_f64: {} cuts ({} on the CPU), hook load {:.1e} (CPU spread {:.1e}), torque {:.1e} (spread {:.1e}), same whirl {}",
        e.seed,
        e.step_cuts,
        cpu.step_cuts,
        e.hook_load_rel,
        e.cpu_spread_hook_rel,
        e.torque_rel,
        e.cpu_spread_torque_rel,
        e.same_whirl
    );
    assert!(e.solved && e.by_engine, "{}", e.reason);
    assert_eq!(e.step_cuts, cpu.step_cuts, "cuts");
    let bound = |spread: f64| (10.0 * spread).max(1e-6);
    assert!(e.hook_load_rel <= bound(e.cpu_spread_hook_rel), "hook load");
    assert!(e.torque_rel <= bound(e.cpu_spread_torque_rel), "torque");
}

/// The first dynamic corpus case of at most 80 nodes with lumped mass (which the engine
/// runs) that the CPU solves and whose CPU row passes `want`: the case and that row.
fn first_small_lumped(
    dir: &std::path::Path,
    want: impl Fn(&holewall::corpus::dynamic::DynamicRow) -> bool,
) -> (
    holewall::corpus::dynamic::DynamicCase,
    holewall::corpus::dynamic::DynamicRow,
) {
    dynamic_sample(dir, 40, 80)
        .into_iter()
        .filter(|c| c.spec.mass == "lumped")
        .find_map(|c| {
            let cpu = holewall::corpus::dynamic::run_case_dynamic(&c).unwrap();
            eprintln!(
                "dynamic seed {}: {} CPU step cuts",
                c.spec.seed, cpu.step_cuts
            );
            (cpu.solved && want(&cpu)).then_some((c, cpu))
        })
        .unwrap()
}

/// A dynamic corpus case run on the CPU (which must solve it), then through the engine in
/// f64 and in f32: the CPU row and each engine row with its `f32` flag.
fn cpu_and_engine(
    case: &holewall::corpus::dynamic::DynamicCase,
) -> (
    holewall::corpus::dynamic::DynamicRow,
    Vec<(bool, holewall::corpus::dynamic::DynamicEngineRow)>,
) {
    let cpu = holewall::corpus::dynamic::run_case_dynamic(case).unwrap();
    assert!(cpu.solved, "{}", cpu.reason);
    let rows = engine_rows(case, &cpu);
    (cpu, rows)
}

/// A dynamic corpus case through the engine in f64 and in f32, against its CPU row: each
/// engine row with its `f32` flag.
fn engine_rows(
    case: &holewall::corpus::dynamic::DynamicCase,
    cpu: &holewall::corpus::dynamic::DynamicRow,
) -> Vec<(bool, holewall::corpus::dynamic::DynamicEngineRow)> {
    let again = holewall::corpus::dynamic::run_case_perturbed(case).unwrap();
    [false, true]
        .into_iter()
        .map(|f32| {
            let row = holewall::corpus::dynamic::run_case_engine(case, cpu, &again, f32).unwrap();
            (f32, row)
        })
        .collect()
}

/// A dynamic corpus case's engine row against its CPU run: run by the engine itself, hook
/// load and largest surface torque within 1e-6 (f64) or 1e-3 (f32); returns that tolerance.
fn assert_engine_matches_cpu(e: &holewall::corpus::dynamic::DynamicEngineRow, f32: bool) -> f64 {
    assert!(e.solved && e.by_engine, "{}", e.reason);
    let tol = if f32 { 1e-3 } else { 1e-6 };
    assert!(e.hook_load_rel <= tol, "{}: {}", e.path, e.hook_load_rel);
    assert!(e.torque_rel <= tol, "{}: {}", e.path, e.torque_rel);
    tol
}

/// Unseen user well 2771 (horizontal, 5,342 m, reaming 3½ in pipe; stop 86's one user
/// failure that was not a lock-up), its pipe meshed at 10 m. Above the kick-off (1,170 m)
/// its FE string winds into a helix in the near-vertical hole, where the soft string's
/// compression (10 kN at the kick-off) names no whirl. The first solve fails; the whirl's
/// rule on the FE string's own compression where it stopped names the span, and the model
/// solves again at the whirl's average there (`profile::hold_in_hole`; docs/performance.md,
/// stop 87: at 2, 5 and 10 m the same hook load within 12 N).
#[test]
fn a_whirl_the_soft_string_misses_is_found_on_the_fe_strings_own_compression() {
    let dir = tempdir::Dir::new("corpus_whirl_fe");
    let well = holewall::corpus::user::write_user_well(2771, dir.path()).unwrap();
    let text = std::fs::read_to_string(&well.case_path).unwrap();
    let coarse = text.replace("element_length = \"2 m\"", "element_length = \"10 m\"");
    assert_ne!(coarse, text, "the well's mesh is 2 m");
    let path = dir.path().join("user_2771_10m.toml");
    std::fs::write(&path, coarse).unwrap();
    let case = holewall::case::load_case(&path).unwrap();
    assert_eq!(
        holewall::diagnose::whirl_span(&case, &case.model),
        None,
        "the soft string names no whirl"
    );
    let mut model = case.model.clone();
    let sol = holewall::profile::solve_in_hole(
        &case,
        &mut model,
        &mut |m, nodes| holewall::profile::add_wall_sites(&case, m, nodes),
        &case.settings().statics(),
        &mut |_| {},
    )
    .expect("solved again at the whirl's average");
    let line = sol
        .log
        .iter()
        .find(|l| l.starts_with(holewall::profile::WHIRL_FROM_FE))
        .expect("the log says the solve was tried again");
    // "… whirls between MD {from} and {to} m, where …": the helix (1,050–1,160 m) inside.
    let span: Vec<f64> = line
        .split("whirls between MD ")
        .nth(1)
        .and_then(|s| s.split(" m,").next())
        .map(|s| s.split(" and ").map(|x| x.parse().unwrap()).collect())
        .unwrap();
    assert!(span[0] <= 1050.0 && span[1] >= 1160.0, "{line}");
    assert!(model.sites.iter().any(|s| s.whirls()));
    // The stiff string carries more drag than the soft string here (its hook load 8.2 %
    // below it at every mesh), never more hook load.
    let (_, hook, _, _) = holewall::profile::fe_rows(&model, &sol);
    let soft = case.soft_string().hook_load();
    eprintln!("hook load {hook} N, soft string {soft} N: {line}");
    assert!((0.85..=1.0).contains(&(hook / soft)), "{hook} {soft}");
}
