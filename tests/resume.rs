//! Ensemble runs are resumable and shardable, with the bits of one uninterrupted run: a run
//! killed (SIGKILL) mid-way and started again with the same command, and four `--shard K/4`
//! runs joined by `holewall merge`, give the same `variants.csv` and statistics; another
//! run's folder is refused (or replaced with `--force`); `--out` is checked before any work.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_holewall"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("holewall-resume-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn case() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/monte_carlo_two_stabilizers.toml")
}

fn args(out: &Path, seed: u64) -> Vec<String> {
    vec![
        "ensemble".into(),
        case().display().to_string(),
        "--samples".into(),
        "192".into(),
        "--seed".into(),
        seed.to_string(),
        "--backend".into(),
        "cpu".into(),
        "--chunk-size".into(),
        "8".into(),
        "--quiet".into(),
        "--out".into(),
        out.display().to_string(),
    ]
}

/// variants.csv, and summary.json's statistics (not its wall time).
fn result_of(out: &Path) -> (String, serde_json::Value) {
    let csv = std::fs::read_to_string(out.join("variants.csv")).unwrap();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    (csv, summary["uncertainty"].clone())
}

#[test]
fn a_killed_run_resumes_to_the_same_bits() {
    let reference = tmp("ref");
    assert!(bin()
        .args(args(&reference, 3))
        .output()
        .unwrap()
        .status
        .success());
    let (csv, stats) = result_of(&reference);
    assert!(stats["qois"].as_array().unwrap().len() >= 7);
    // Kill a second run once three of its 24 chunks are on disk.
    let out = tmp("killed");
    let mut child = bin()
        .args(args(&out, 3))
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let chunks = out.join("chunks");
    let start = std::time::Instant::now();
    loop {
        let n = std::fs::read_dir(&chunks)
            .map(|d| {
                d.filter(|e| {
                    e.as_ref()
                        .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "json"))
                })
                .count()
            })
            .unwrap_or(0);
        if n >= 3 || start.elapsed().as_secs() > 60 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();
    assert!(
        !out.join("summary.json").exists(),
        "the run finished before it was killed"
    );
    let done = std::fs::read_dir(&chunks).unwrap().count();
    eprintln!("killed with {done} chunk files on disk (of 24)");
    // The same command again: continues and ends with the uninterrupted run's bits.
    let again = bin().args(args(&out, 3)).output().unwrap();
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let (csv2, stats2) = result_of(&out);
    assert_eq!(csv2, csv);
    assert_eq!(stats2, stats);
    // Another seed into the same folder is refused, exit 2, nothing touched …
    let other = bin().args(args(&out, 4)).output().unwrap();
    assert_eq!(other.status.code(), Some(2));
    let msg = String::from_utf8_lossy(&other.stderr);
    assert!(
        msg.contains("run of other inputs") && msg.contains("--force"),
        "{msg}"
    );
    assert_eq!(result_of(&out).0, csv);
    // … and replaces it with --force (no stale chunk of the first run left).
    let mut forced = args(&out, 4);
    forced.push("--force".into());
    assert!(bin().args(&forced).output().unwrap().status.success());
    assert_ne!(result_of(&out).0, csv);
    // --out naming a file: refused before any work.
    let file = tmp("file");
    std::fs::write(&file, "x").unwrap();
    let e = bin().args(args(&file, 3)).output().unwrap();
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("is a file"));
}

#[test]
fn four_shards_merged_are_one_run() {
    let reference = tmp("whole");
    assert!(bin()
        .args(args(&reference, 5))
        .output()
        .unwrap()
        .status
        .success());
    let (csv, stats) = result_of(&reference);
    let shards: Vec<PathBuf> = (1..=4).map(|k| tmp(&format!("shard{k}"))).collect();
    for (k, dir) in shards.iter().enumerate() {
        let mut a = args(dir, 5);
        a.push("--shard".into());
        a.push(format!("{}/4", k + 1));
        let o = bin().args(&a).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            !dir.join("summary.json").exists(),
            "a shard writes chunks only"
        );
    }
    // Missing a shard: refused.
    let merged = tmp("merged");
    let partial = bin()
        .arg("merge")
        .arg("--out")
        .arg(&merged)
        .args(&shards[..3])
        .output()
        .unwrap();
    assert_eq!(partial.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&partial.stderr).contains("shard 4/4 is missing"));
    let _ = std::fs::remove_dir_all(&merged);
    let o = bin()
        .arg("merge")
        .arg("--out")
        .arg(&merged)
        .arg("--quiet")
        .args(&shards)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (csv2, stats2) = result_of(&merged);
    assert_eq!(csv2, csv);
    assert_eq!(stats2, stats);
    // Bad shard specs.
    for bad in ["0/4", "5/4", "1-4", "x/y"] {
        let mut a = args(&tmp("bad"), 5);
        a.push("--shard".into());
        a.push(bad.into());
        assert_eq!(
            bin().args(&a).output().unwrap().status.code(),
            Some(2),
            "{bad}"
        );
    }
}

/// `--max-seconds`: no chunk starts once the budget is spent; the run stops with exit code
/// 3 and how far it got, no summary; the same command (without the budget) continues to
/// the bits of an uninterrupted run.
#[test]
fn a_budget_stops_a_run_resumably() {
    let reference = tmp("budget-ref");
    assert!(bin()
        .args(args(&reference, 5))
        .output()
        .unwrap()
        .status
        .success());
    let (csv, stats) = result_of(&reference);
    let out = tmp("budget");
    let mut a = args(&out, 5);
    a.extend(["--max-seconds".into(), "1e-9".into()]);
    let o = bin().args(&a).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("--max-seconds budget") && stderr.contains("continues"),
        "{stderr}"
    );
    assert!(!out.join("summary.json").exists());
    let chunks = std::fs::read_dir(out.join("chunks")).unwrap().count();
    assert_eq!(
        chunks, 1,
        "one chunk started before the budget was read as spent"
    );
    let o = bin().args(args(&out, 5)).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(result_of(&out), (csv, stats));
}
