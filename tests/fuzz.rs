//! Fuzzing the parsers (issue 15, part 6): the case parser (TOML, with its meshing), the
//! variants CSV, the survey CSV and the contact JSON lines, each fed mutated copies of real
//! inputs and arbitrary text. Property: every input returns `Ok` or a clean error — no panic —
//! within a time bound (a watchdog thread; a hang fails the test).
//!
//! `cargo fuzz` needs a nightly toolchain, so this is proptest with a fixed number of cases
//! per target and strategy (`HOLEWALL_FUZZ_CASES`, default 10 000) and a fixed seed: the same inputs in CI
//! every run; raise the count locally for a longer search. Prints the counts for
//! docs/validation.md.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// Per-input bound: parsing (and meshing) any accepted input is milliseconds; a mesh that
/// grows without bound or a loop that does not end trips it.
const BOUND: Duration = Duration::from_secs(10);

fn cases() -> u32 {
    std::env::var("HOLEWALL_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000)
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Replacement tokens: numbers at and past every edge, units, quotes, TOML syntax.
const TOKENS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "1e-308",
    "5e-324",
    "nan",
    "inf",
    "-inf",
    "NaN",
    "\"nan m\"",
    "\"inf N\"",
    "1e12",
    "1e-12",
    "0.1",
    "2",
    "3",
    "999999999999",
    "\"\"",
    "\"1.2\"",
    "\"90\"",
    "\"90 rpm\"",
    "\"1 MN\"",
    "\"-5 m\"",
    "\"1e400 m\"",
    "\"5 ft\"",
    "\"5 furlong\"",
    "\"5 kN\"",
    "\"10 ppg\"",
    "\"1.2 sg\"",
    "\"1.3 ppg\"",
    "\"12 sg\"",
    "400",
    "-10",
    "true",
    "[]",
    "{}",
    "[1, 2]",
    "\"rotating\"",
    "\"sliding\"",
    "\"survey\"",
    "\"all_nodes\"",
    "\"coupled\"",
    "=",
    "[[",
    "]]",
    "\"",
    "#",
    "\n",
    ",",
    "\u{0}",
    "é",
    "\u{FEFF}",
    "0x10",
    "1_000",
    "+1",
    ".5",
];

/// A mutation of `seed`: `edits` random edits (token swaps, line deletions and
/// duplications, byte insertions, truncation).
fn mutate(seed: &str, edits: &[(u8, u32, u32)]) -> String {
    let mut text = seed.to_string();
    for &(kind, a, b) in edits {
        let lines: Vec<&str> = text.lines().collect();
        if lines.is_empty() {
            text = TOKENS[a as usize % TOKENS.len()].to_string();
            continue;
        }
        let i = a as usize % lines.len();
        let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        match kind % 6 {
            // Replace the value after `=` (or a field of a CSV/JSON line) with a token.
            0 => {
                let tok = TOKENS[b as usize % TOKENS.len()];
                let line = &out[i];
                out[i] = if let Some((k, _)) = line.split_once('=') {
                    format!("{k}= {tok}")
                } else {
                    let mut fields: Vec<String> = line.split(',').map(|f| f.to_string()).collect();
                    let j = b as usize % fields.len();
                    fields[j] = tok.to_string();
                    fields.join(",")
                };
            }
            1 => {
                out.remove(i);
            }
            2 => {
                let l = out[i].clone();
                out.insert(i, l);
            }
            3 => {
                // Insert a token at a character boundary.
                let line = &out[i];
                let cut = line
                    .char_indices()
                    .map(|(k, _)| k)
                    .nth(b as usize % (line.chars().count() + 1))
                    .unwrap_or(line.len());
                out[i] = format!(
                    "{}{}{}",
                    &line[..cut],
                    TOKENS[(a ^ b) as usize % TOKENS.len()],
                    &line[cut..]
                );
            }
            4 => {
                // Swap two lines.
                let j = b as usize % out.len();
                out.swap(i, j);
            }
            _ => {
                // Truncate the text.
                out.truncate(i);
            }
        }
        text = out.join("\n");
    }
    text
}

/// Runs `f` on a watchdog thread: a panic or a run past [`BOUND`] fails.
fn guarded(what: &str, input: String, f: fn(&str) -> bool) -> Result<bool, TestCaseError> {
    let (tx, rx) = std::sync::mpsc::channel();
    let text = input.clone();
    let handle = std::thread::spawn(move || {
        let ok = f(&text);
        let _ = tx.send(ok);
    });
    match rx.recv_timeout(BOUND) {
        Ok(ok) => {
            let _ = handle.join();
            Ok(ok)
        }
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            HANGS.fetch_add(1, Ordering::Relaxed);
            Err(TestCaseError::fail(format!(
                "{what}: no answer within {BOUND:?} for input:\n{input}"
            )))
        }
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
            PANICS.fetch_add(1, Ordering::Relaxed);
            Err(TestCaseError::fail(format!(
                "{what}: panicked on input:\n{input}"
            )))
        }
    }
}

static PANICS: AtomicUsize = AtomicUsize::new(0);
static HANGS: AtomicUsize = AtomicUsize::new(0);

/// One target: `seeds` mutated by up to 6 edits, and arbitrary text, `cases()` times each.
fn fuzz(what: &str, seeds: &[String], f: fn(&str) -> bool) {
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: cases(),
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]),
    );
    let accepted = AtomicUsize::new(0);
    let total = AtomicUsize::new(0);
    let clock = Instant::now();
    let n = seeds.len();
    let strategy = (
        0..n,
        proptest::collection::vec((any::<u8>(), any::<u32>(), any::<u32>()), 0..6),
    );
    let result = runner.run(&strategy, |(k, edits)| {
        let text = mutate(&seeds[k], &edits);
        total.fetch_add(1, Ordering::Relaxed);
        if guarded(what, text, f)? {
            accepted.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    });
    result.unwrap_or_else(|e| panic!("{what}: {e}"));
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: cases(),
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[11; 32]),
    );
    let result = runner.run(&"(?s).{0,400}", |text| {
        total.fetch_add(1, Ordering::Relaxed);
        if guarded(what, text, f)? {
            accepted.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    });
    result.unwrap_or_else(|e| panic!("{what}: {e}"));
    println!(
        "| {what} | {} | {} | {} | {} | {:.1} s |",
        total.load(Ordering::Relaxed),
        accepted.load(Ordering::Relaxed),
        PANICS.load(Ordering::Relaxed),
        HANGS.load(Ordering::Relaxed),
        clock.elapsed().as_secs_f64()
    );
}

fn case_seeds() -> Vec<String> {
    let mut seeds = Vec::new();
    for entry in std::fs::read_dir(root().join("cases")).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            seeds.push(std::fs::read_to_string(&p).unwrap());
        }
    }
    seeds.sort();
    seeds
}

#[test]
fn fuzz_case_parser() {
    fuzz("case TOML", &case_seeds(), |text| {
        holewall::case::parse_case(Path::new("fuzz.toml"), text).is_ok()
    });
}

#[test]
fn fuzz_variants_csv() {
    let seeds = vec![
        std::fs::read_to_string(root().join("cases/stress_two_stabilizers.csv")).unwrap(),
        "mu,wob,k_e,rpm\n0.1,5 kN,6e7,90 rpm\n0.6,30 kN,1e9,120 rpm\n".into(),
        "depth,mode,mu,stab1.from_bit,stab2.blade\n1000 m,tripping_out,0.25,1.5 m,8.25 in\n".into(),
        "layout,m,eps,c,mu_t.stab1\n1,1.5,1e-3,1e3,0.3\n2,0.6667,1e-2,0,0.1\n".into(),
    ];
    fuzz("variants CSV", &seeds, |text| {
        holewall::ensemble::variants_from_csv_text("fuzz.csv", text).is_ok()
    });
}

#[test]
fn fuzz_survey_csv() {
    let seeds = vec![
        "md,inclination,azimuth\n0,0,0\n300,0,0\n600,20,45\n1500,30,45\n".into(),
        "MD (ft),inc,azi\n0,0,0\n1000,5,350\n5000,89.9,10\n".into(),
        "0,0,0\n100,180,0\n200,90,720\n".into(),
    ];
    fuzz(
        "survey CSV",
        &seeds,
        |text| match holewall::case::survey_from_text("fuzz.csv", text) {
            Ok(read) => {
                let stations: Vec<_> = read.iter().map(|(s, _)| *s).collect();
                holewall::well::WellPath::from_survey(&stations, [0.0; 3]).is_ok()
                    && holewall::case::survey_plausibility("fuzz.csv", &read, 1500.0, 30.0).is_ok()
            }
            Err(_) => false,
        },
    );
}

#[test]
fn fuzz_contact_json() {
    let text = std::fs::read_to_string(root().join("cases/contact_examples.jsonl")).unwrap();
    let mut seeds: Vec<String> = text.lines().map(|l| l.to_string()).collect();
    seeds.push(text.clone());
    // JSON lines are one line each: split fields at commas so token edits hit values.
    let seeds: Vec<String> = seeds.iter().map(|s| s.replace(", ", ",\n")).collect();
    fuzz("contact JSON", &seeds, |text| {
        let one_line = text.replace(",\n", ", ");
        holewall::cli::contact::parse_all("fuzz.jsonl", &one_line, false).is_ok()
            | holewall::cli::contact::parse_all("fuzz.jsonl", text, true).is_ok()
    });
}
