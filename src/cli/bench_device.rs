//! `holewall bench device`: the whole performance table of the machine it runs on, in one
//! command (issue 27) — for a user with a GPU to run and send back. It runs, in order, the
//! contact evaluations (`bench contact`), the beam element (`bench element`), the roofline
//! per kernel (`bench kernels`), the static ensembles on the shipped stress and
//! build-and-hold cases (`bench statics`), the dynamic ensembles (`bench ensemble`), the
//! stress statics and small dynamic ensembles again with the GPU engine's line-search trials
//! in rounds of up to 8 a submission (`--trial-round 8`, against the default of one above) and a user's
//! Monte Carlo job timed whole (`bench job`), each against the CPU path in the same run, and gathers their JSON into `device.json` and their tables into `device.md`. Nothing here measures anything itself: each part is the
//! benchmark of its own command.

use std::path::{Path, PathBuf};

use crate::backend::BackendChoice;
use crate::error::Error;

/// Sizes of the parts: `quick` for a first look (minutes on a laptop's CPU), else the
/// sizes of `docs/performance.md`'s tables.
#[derive(Clone, Copy, Debug)]
pub struct DeviceOptions {
    /// Smaller sizes and fewer repeats.
    pub quick: bool,
    /// Progress bar.
    pub show_progress: bool,
}

/// One part: its name, the command that reproduces it, and its JSON (or why it failed).
struct Part {
    name: &'static str,
    command: String,
    json: Result<serde_json::Value, String>,
}

fn read_json(path: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Runs every part into `out` (`cases` holds the shipped cases) and writes `device.json` and
/// `device.md`; a part that fails is reported in both and the others still run.
pub fn run(out: &Path, cases: &Path, options: DeviceOptions) -> Result<(), Error> {
    std::fs::create_dir_all(out)?;
    let q = options.quick;
    let (pairs, repeats, states) = if q {
        (100_000, 3, 500)
    } else {
        (1_000_000, 7, 2000)
    };
    let (nodes, variants): (Vec<usize>, Vec<usize>) = if q {
        (vec![100], vec![16, 256])
    } else {
        (vec![100, 400], vec![16, 256, 4096])
    };
    let kernel_variants = if q {
        vec![16, 256]
    } else {
        vec![16, 256, 4096]
    };
    let stress = cases.join("stress_two_stabilizers.toml");
    let stress_variants = cases.join("stress_two_stabilizers.csv");
    let build_and_hold = cases.join("ensemble_build_and_hold.toml");
    let bar = crate::output::progress_bar(
        options.show_progress,
        9,
        "{bar:30} {pos}/{len} parts, {elapsed} elapsed: {msg}",
    );
    let mut parts = Vec::new();
    let mut part = |name: &'static str,
                    command: String,
                    file: PathBuf,
                    f: &mut dyn FnMut(&Path) -> Result<(), Error>| {
        bar.set_message(name);
        let json = f(&file)
            .map_err(|e| e.to_string())
            .and_then(|_| read_json(&file));
        bar.inc(1);
        parts.push(Part {
            name,
            command,
            json,
        });
    };
    part(
        "contact",
        format!("holewall bench contact --pairs {pairs} --repeats {repeats}"),
        out.join("contact.json"),
        &mut |f| super::bench::contact(pairs, repeats, BackendChoice::Auto, Some(f)),
    );
    part(
        "element",
        format!("holewall bench element --states {states} --repeats {repeats}"),
        out.join("element.json"),
        &mut |f| super::bench::element(states, repeats, Some(f)),
    );
    let kernels_dir = out.join("kernels");
    part(
        "kernels",
        format!(
            "holewall bench kernels --variants {} --repeats 5 --out DIR",
            join(&kernel_variants)
        ),
        kernels_dir.join("kernels.json"),
        &mut |_| {
            super::bench_kernels::run(&kernel_variants, 21, 5, &kernels_dir, false).map(|_| ())
        },
    );
    part(
        "statics: stress_two_stabilizers",
        "holewall bench statics cases/stress_two_stabilizers.toml --variants cases/stress_two_stabilizers.csv --repeats 3".into(),
        out.join("statics_stress.json"),
        &mut |f| super::bench::statics(&stress, Some(&stress_variants), 3, Some(f)),
    );
    part(
        "statics: ensemble_build_and_hold",
        "holewall bench statics cases/ensemble_build_and_hold.toml --repeats 3".into(),
        out.join("statics_build_and_hold.json"),
        &mut |f| super::bench::statics(&build_and_hold, None, 3, Some(f)),
    );
    part(
        "dynamic ensembles",
        format!(
            "holewall bench ensemble --nodes {} --variants {} --steps 5 --repeats 3",
            join(&nodes),
            join(&variants)
        ),
        out.join("ensemble.json"),
        &mut |f| super::bench_ensemble::run(&nodes, &variants, 5, 3, 120.0, true, 100, Some(f)),
    );
    // The GPU engine's line-search trials in rounds of up to 8 a submission (issue 27,
    // item 3): against the parts above, which form one trial a submission (the default
    // since stop 52's H100 run, `crate::gpu::batch::trials_per_round`).
    let in_rounds = |f: &mut dyn FnMut() -> Result<(), Error>| {
        crate::gpu::batch::force_trials_per_round(Some(crate::gpu::batch::MAX_TRIALS_PER_ROUND));
        let r = f();
        crate::gpu::batch::force_trials_per_round(None);
        r
    };
    part(
        "statics: stress_two_stabilizers, trials in rounds of 8",
        "holewall bench statics cases/stress_two_stabilizers.toml --variants cases/stress_two_stabilizers.csv --repeats 3 --trial-round 8".into(),
        out.join("statics_stress_rounds.json"),
        &mut |f| in_rounds(&mut || super::bench::statics(&stress, Some(&stress_variants), 3, Some(f))),
    );
    part(
        "dynamic ensembles, trials in rounds of 8",
        "holewall bench ensemble --nodes 100 --variants 16,256 --steps 5 --repeats 3 --trial-round 8".into(),
        out.join("ensemble_rounds.json"),
        &mut |f| {
            in_rounds(&mut || {
                super::bench_ensemble::run(&[100], &[16, 256], 5, 3, 120.0, true, 0, Some(f))
            })
        },
    );
    let job_dir = out.join("job");
    let job_case = cases.join("whirl_job.toml");
    let job_samples = if q { 256 } else { 4096 };
    part(
        "a user's job",
        format!(
            "holewall bench job cases/whirl_job.toml --samples {job_samples} --repeats 2 --out DIR"
        ),
        job_dir.join("job.json"),
        &mut |_| {
            super::bench_job::run(&job_case, None, job_samples, 1, 2, &job_dir, false).map(|_| ())
        },
    );
    bar.finish_and_clear();
    let device = crate::gpu::GpuContext::shared()
        .map(|c| c.describe())
        .unwrap_or_else(|e| format!("no GPU adapter ({e})"));
    let mut all = serde_json::Map::new();
    all.insert("device".into(), device.clone().into());
    let mut md = format!(
        "# holewall on {device}\n\n`holewall bench device{}` — each part below is its own \
         benchmark (the command under its heading reproduces it); GPU/CPU ratios come from \
         one run.\n",
        if q { " --quick" } else { "" }
    );
    for p in &parts {
        md.push_str(&format!("\n## {}\n\n`{}`\n\n", p.name, p.command));
        match &p.json {
            Ok(v) => {
                md.push_str(&tables(v, 3));
                all.insert(p.name.into(), v.clone());
            }
            Err(e) => {
                md.push_str(&format!("**Failed**: {e}\n"));
                all.insert(p.name.into(), serde_json::json!({ "failed": e }));
            }
        }
    }
    crate::output::write_atomic(&out.join("device.md"), md.as_bytes())?;
    crate::output::write_json_atomic(&out.join("device.json"), &serde_json::Value::Object(all))?;
    let failed: Vec<&str> = parts
        .iter()
        .filter(|p| p.json.is_err())
        .map(|p| p.name)
        .collect();
    println!(
        "holewall bench device: {} of {} parts ran; {}/device.md and device.json{}",
        parts.len() - failed.len(),
        parts.len(),
        out.display(),
        if failed.is_empty() {
            String::new()
        } else {
            format!("; failed: {}", failed.join(", "))
        }
    );
    Ok(())
}

fn join(x: &[usize]) -> String {
    x.iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// A JSON value as markdown: scalars as a list, arrays of objects as tables (the union of
/// their keys as columns), nested objects under their own heading (down to `depth`).
pub fn tables(v: &serde_json::Value, depth: usize) -> String {
    use serde_json::Value;
    let cell = |x: &Value| match x {
        Value::Number(n) => n
            .as_f64()
            .map(|f| {
                if f != 0.0 && (f.abs() >= 1e5 || f.abs() < 1e-3) {
                    format!("{f:.3e}")
                } else {
                    format!("{}", (f * 1e4).round() / 1e4)
                }
            })
            .unwrap_or_default(),
        Value::String(s) => s.replace('|', "/"),
        Value::Null => "—".into(),
        other => other.to_string().replace('|', "/"),
    };
    let mut out = String::new();
    match v {
        Value::Object(o) => {
            let mut lists = String::new();
            for (k, x) in o {
                match x {
                    Value::Array(a) if a.iter().all(Value::is_object) && !a.is_empty() => {
                        out.push_str(&format!("**{k}**\n\n{}\n", tables(x, depth)));
                    }
                    Value::Object(_) if depth > 0 => {
                        out.push_str(&format!("**{k}**\n\n{}\n", tables(x, depth - 1)));
                    }
                    _ => lists.push_str(&format!("- {k}: {}\n", cell(x))),
                }
            }
            if !lists.is_empty() {
                out = format!("{lists}\n{out}");
            }
        }
        Value::Array(a) if a.iter().all(Value::is_object) && !a.is_empty() => {
            let mut keys: Vec<String> = Vec::new();
            for r in a {
                for k in r.as_object().map(|o| o.keys()).into_iter().flatten() {
                    if !keys.contains(k) {
                        keys.push(k.clone());
                    }
                }
            }
            out.push_str(&format!(
                "| {} |\n|{}\n",
                keys.join(" | "),
                "---|".repeat(keys.len())
            ));
            for r in a {
                let row: Vec<String> = keys.iter().map(|k| cell(&r[k])).collect();
                out.push_str(&format!("| {} |\n", row.join(" | ")));
            }
        }
        other => out.push_str(&format!("{}\n", cell(other))),
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn json_becomes_lists_and_tables() {
        let v = serde_json::json!({
            "device": "x",
            "rows": [{"a": 1.0, "b": "p"}, {"a": 2.5e-5, "c": null}],
            "ceilings": {"fma": 31.25}
        });
        let md = super::tables(&v, 2);
        assert!(md.contains("- device: x"), "{md}");
        assert!(
            md.contains("| a | b | c |\n|---|---|---|\n| 1 | p | — |\n| 2.500e-5 | — | — |"),
            "{md}"
        );
        assert!(md.contains("**ceilings**\n\n- fma: 31.25"), "{md}");
    }
}
