//! Shared test helpers.
#![allow(dead_code)]

use holewall::gpu::GpuContext;

pub mod runners;

/// The shared GPU context. With `HOLEWALL_REQUIRE_GPU=1` (CI) a missing adapter fails the
/// test; otherwise the test is skipped, loudly.
pub fn gpu() -> Option<&'static GpuContext> {
    match GpuContext::shared() {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            if std::env::var("HOLEWALL_REQUIRE_GPU").as_deref() == Ok("1") {
                panic!("HOLEWALL_REQUIRE_GPU=1 but no GPU adapter: {e}");
            }
            eprintln!("\n*** SKIPPED: no GPU adapter ({e}); GPU tests did not run ***\n");
            None
        }
    }
}

/// Whether the adapter fuses `a·b + c` into one rounding
/// ([`GpuContext::fuses_multiply_add`]: NVIDIA does, lavapipe does not). Where it does, two
/// builds of one formula — a kernel and its twin, two forms or two specialisations of a
/// kernel — agree to rounding, not to the bit.
pub fn fuses(ctx: &GpuContext) -> bool {
    ctx.fuses_multiply_add()
        .expect("the multiply-add probe runs")
}

/// `a` equals `b` to the bit where the adapter does not fuse multiply-adds; where it does,
/// `measure(a, b) ≤ bound` — the measure and the bound the test already holds the kernel to
/// against its twin, which both sides meet, so no looser.
pub fn assert_same<T: Copy + Into<f64> + PartialEq + std::fmt::Debug>(
    ctx: &GpuContext,
    a: &[T],
    b: &[T],
    measure: impl Fn(&[f64], &[f64]) -> f64,
    bound: f64,
    what: &str,
) {
    if fuses(ctx) {
        let up = |x: &[T]| x.iter().map(|&y| y.into()).collect::<Vec<f64>>();
        let d = measure(&up(a), &up(b));
        assert!(
            d <= bound,
            "{what}: {d:.3e} > {bound:.1e} (fused multiply-adds)"
        );
    } else {
        assert_eq!(a, b, "{what}");
    }
}

/// The 60 m test bed (`tests/data/extreme_base.toml`: BHA and pipe on the low side of a 60°
/// hole, contact at every node) with friction, blade diameter, wall stiffness, exponent
/// and regularisation speed filled in.
pub fn bed_text(mu: &str, blade: &str, k_e: &str, m: &str, eps: &str) -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/extreme_base.toml"
    ))
    .unwrap()
    .replace("MU", mu)
    .replace("BLADE", blade)
    .replace("KE", k_e)
    .replace("EXP", m)
    .replace("EPS", eps)
}

/// [`bed_text`] near stick-slip (μ = 1, ε = 1e-6 m/s, 30 rpm, 10 ms steps): a run that
/// cuts its step to a quarter and regrows it, for the tests of the step control
/// (`solve::dynamics::control`).
pub fn stick_slip_bed_text() -> String {
    bed_text("1.0", "8.25 in", "6e7", "1", "1e-6")
        .replace("time_step = \"2 ms\"", "time_step = \"10 ms\"")
        .replace("rpm = \"120 rpm\"", "rpm = \"30 rpm\"")
}

/// [`bed_text`] parsed, with Table 1 values except the spring exponent `m`.
pub fn bed_case(m: &str) -> holewall::case::Case {
    holewall::case::parse_case(
        std::path::Path::new("bed.toml"),
        &bed_text("0.3", "8.25 in", "6e7", m, "1e-3"),
    )
    .unwrap()
}

/// Quantities of interest of a static solution: neutral point from the bit (m, NaN where
/// none), surface torque (N·m), largest side force (N), hook load (N).
pub fn static_qois(
    model: &holewall::model::Model,
    sol: &holewall::solve::statics::StaticSolution,
    bit_md: f64,
) -> [f64; 4] {
    use holewall::profile::{fe_rows, neutral_point};
    let (rows, hook, torque, _) = fe_rows(model, sol);
    let side = sol.contact.iter().map(|c| c.1).fold(0.0f64, f64::max);
    [
        neutral_point(&rows)
            .map(|md| bit_md - md)
            .unwrap_or(f64::NAN),
        torque,
        side,
        hook,
    ]
}

/// A kernel path (behind a reference, so one closure serves the twin and the GPU) that
/// counts the static and the dynamic chunks it opens (compaction opens more).
pub struct Counting<'p> {
    inner: &'p dyn holewall::engine::KernelPath<f64>,
    /// Static chunks opened.
    pub opens: std::cell::Cell<usize>,
    /// Dynamic chunks opened.
    pub dynamic_opens: std::cell::Cell<usize>,
}

impl<'p> Counting<'p> {
    pub fn new(inner: &'p dyn holewall::engine::KernelPath<f64>) -> Self {
        Counting {
            inner,
            opens: std::cell::Cell::new(0),
            dynamic_opens: std::cell::Cell::new(0),
        }
    }
}

impl holewall::engine::KernelPath<f64> for Counting<'_> {
    fn max_batch(&self, model: &holewall::model::Model) -> usize {
        self.inner.max_batch(model)
    }
    fn open<'a>(
        &'a self,
        model: &'a holewall::model::Model,
        tables: &holewall::engine::BatchTables<f64>,
    ) -> Result<Box<dyn holewall::engine::ResidentStatic<f64> + 'a>, holewall::error::SystemError>
    {
        self.opens.set(self.opens.get() + 1);
        self.inner.open(model, tables)
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a holewall::model::Model,
        tables: &holewall::engine::BatchTables<f64>,
        dynamic: &holewall::engine::dynamic::DynamicTables<f64>,
    ) -> Result<
        Box<dyn holewall::engine::dynamic::ResidentDynamic<f64> + 'a>,
        holewall::error::SystemError,
    > {
        self.dynamic_opens.set(self.dynamic_opens.get() + 1);
        self.inner.open_dynamic(model, tables, dynamic)
    }
}

/// Steel density of the weightless test strings (kg/m³).
pub const STEEL: f64 = 7850.0;

/// A vertical 6.5 in × 0.071 m collar of length `l` in `elements` elements, in mud as dense
/// as steel (weightless): top clamped, bit held laterally (`Model::bare`).
pub fn weightless_collar(l: f64, elements: usize) -> holewall::model::Model {
    holewall::model::vertical_collar(l, elements, STEEL)
}

/// A column of an ensemble's `variants.csv` in `out`, as numbers (NaN where empty).
#[allow(dead_code)]
pub fn variants_column(out: &std::path::Path, name: &str) -> Vec<f64> {
    // A CSV reader: a reason holds commas, quoted.
    let mut csv = csv::Reader::from_path(out.join("variants.csv")).unwrap();
    let k = csv
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    csv.records()
        .map(|r| match &r.unwrap()[k] {
            "" => f64::NAN,
            x => x.parse().unwrap(),
        })
        .collect()
}

/// Runs the ensemble of case `text` (with its `[ensemble]` table) on the CPU backend and on
/// the GPU in f64, into `cpu/` and `gpu/` of a fresh folder named after `label`: the folder
/// and both summaries.
#[allow(dead_code)]
pub fn on_cpu_and_gpu(
    label: &str,
    text: &str,
) -> (
    std::path::PathBuf,
    holewall::ensemble::report::EnsembleSummary,
    holewall::ensemble::report::EnsembleSummary,
) {
    let dir = std::env::temp_dir().join(format!("holewall-{label}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let case = dir.join(format!("{label}.toml"));
    std::fs::write(&case, text).unwrap();
    let run = |backend, out: &str| {
        holewall::ensemble::job::run(
            &case,
            None,
            backend,
            holewall::backend::Precision::F64,
            &dir.join(out),
            false,
            &Default::default(),
        )
        .unwrap()
    };
    let cpu = run(holewall::backend::BackendChoice::Cpu, "cpu");
    let gpu = run(holewall::backend::BackendChoice::Gpu, "gpu");
    (dir, cpu, gpu)
}

/// Runs the case `text` (with its `[ensemble]` table) on the CPU and on the GPU engine in
/// f64 ([`on_cpu_and_gpu`]); asserts that nothing failed and that the
/// engine ran every variant itself (no CPU fallback). Returns the folder, the CPU's and the
/// engine's `stabilizer 1 lateral, side force, surface torque` columns' worst relative
/// difference, printed with each column.
#[allow(dead_code)]
pub fn engine_against_cpu(label: &str, text: &str) -> (std::path::PathBuf, f64) {
    let (dir, cpu, gpu) = on_cpu_and_gpu(label, text);
    assert_eq!((cpu.failed, gpu.failed), (0, 0));
    assert_eq!(gpu.backend, "gpu");
    assert_eq!(gpu.solved_by_engine, gpu.variants, "{:?}", gpu.backend_note);
    let mut worst: f64 = 0.0;
    for q in [
        "stab1_max_lateral_m",
        "stab1_max_side_force_n",
        "max_surface_torque_nm",
    ] {
        let (a, b) = (
            variants_column(&dir.join("gpu"), q),
            variants_column(&dir.join("cpu"), q),
        );
        eprintln!("{label}, {q}: GPU engine {a:?}, CPU {b:?}");
        for (x, y) in a.iter().zip(&b) {
            worst = worst.max((x - y).abs() / y.abs().max(1e-9));
        }
    }
    (dir, worst)
}

/// Runs the `holewall` binary with `args`: (exit code, stdout, stderr).
pub fn holewall(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_holewall"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

/// A fresh, empty scratch folder `holewall-<tag>-<pid>-<name>` under the temp dir.
/// A JSON file a command wrote (`summary.json`, `job.json`, …), parsed.
pub fn json(path: &std::path::Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

pub fn scratch_dir(tag: &str, name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("holewall-{tag}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// An ensemble's `summary.json` counts agree with its `variants.csv` (issue 23): `step_cut`
/// is the rows with `step_cuts > 0`, `converged`/`failed` the statuses, `solved_by_engine`
/// and `solved_by_cpu` the `solved_by` column of the rows that did not fail.
pub fn summary_agrees_with_csv(
    s: &holewall::ensemble::report::EnsembleSummary,
    out: &std::path::Path,
) {
    let text = std::fs::read_to_string(out.join("variants.csv")).unwrap();
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let header = rows.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (status, cuts, by) = (col("status"), col("step_cuts"), col("solved_by"));
    let (mut converged, mut failed, mut cut, mut engine, mut cpu) = (0, 0, 0, 0, 0);
    for r in rows.records() {
        let r = r.unwrap();
        match &r[status] {
            "converged" => converged += 1,
            "failed" => failed += 1,
            _ => {}
        }
        if r[status] != *"failed" {
            if r[cuts].parse::<usize>().unwrap() > 0 {
                cut += 1;
            }
            match &r[by] {
                "engine" => engine += 1,
                _ => cpu += 1,
            }
        }
    }
    assert_eq!(
        (
            s.converged,
            s.step_cut,
            s.failed,
            s.solved_by_engine,
            s.solved_by_cpu
        ),
        (converged, cut, failed, engine, cpu),
        "summary.json against variants.csv in {}",
        out.display()
    );
}

/// The text of the shipped case `cases/NAME`.
pub fn shipped_case_text(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `holewall ensemble CASE [--variants FILE] --backend cpu --out OUT`, through the library.
pub fn ensemble_on_cpu(
    case: &std::path::Path,
    variants: Option<&std::path::Path>,
    out: &std::path::Path,
) -> holewall::ensemble::report::EnsembleSummary {
    ensemble_on(case, variants, holewall::backend::BackendChoice::Cpu, out)
}

/// `holewall ensemble CASE [--variants FILE] --backend B --out OUT` (f64), through the
/// library.
pub fn ensemble_on(
    case: &std::path::Path,
    variants: Option<&std::path::Path>,
    backend: holewall::backend::BackendChoice,
    out: &std::path::Path,
) -> holewall::ensemble::report::EnsembleSummary {
    ensemble_with(case, variants, backend, out, &Default::default())
}

/// [`ensemble_on`] with `options` (a Monte Carlo run's, say).
pub fn ensemble_with(
    case: &std::path::Path,
    variants: Option<&std::path::Path>,
    backend: holewall::backend::BackendChoice,
    out: &std::path::Path,
    options: &holewall::ensemble::store::EnsembleOptions,
) -> holewall::ensemble::report::EnsembleSummary {
    holewall::ensemble::job::run(
        case,
        variants,
        backend,
        holewall::backend::Precision::F64,
        out,
        false,
        options,
    )
    .unwrap()
}
