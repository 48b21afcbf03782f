//! `holewall ensemble` and `holewall merge` as library calls: variants (CSV, grid or
//! Monte Carlo samples) → checked output folder → chunks (resumable, shardable) → outputs,
//! `summary.json` last.

use std::path::Path;

use super::plots::{broomstick, over_the_inputs};
use super::qoi::*;
use super::report::*;
use super::runner::*;
use super::store::*;
use crate::backend::{BackendChoice, Precision};
use crate::case::{load_case, Analysis};
use crate::ensemble::apply;
use crate::error::{Error, InputError};
use crate::output::{out_error, write_atomic};

/// Runs the command.
pub fn run(
    case_path: &Path,
    variants_file: Option<&Path>,
    backend: BackendChoice,
    precision: Precision,
    out: &Path,
    show_progress: bool,
    options: &EnsembleOptions,
) -> Result<EnsembleSummary, Error> {
    let monte_carlo = options.monte_carlo.as_ref();
    let tally = crate::tally::Tally::now();
    let case = load_case(case_path)?;
    let settings = case.ensemble.clone();
    let cli_error = |key: &str, message: String| -> Error {
        InputError {
            source_name: case_path.display().to_string(),
            line: 0,
            key: key.into(),
            message,
        }
        .into()
    };
    let variants = match monte_carlo {
        Some(mc) => {
            if variants_file.is_some() {
                return Err(cli_error(
                    "--samples",
                    "give --variants FILE or --samples N, not both".into(),
                ));
            }
            let uncertain = settings
                .as_ref()
                .map(|s| s.uncertain.clone())
                .unwrap_or_default();
            let correlation = settings.as_ref().and_then(|s| s.correlation.clone());
            crate::ensemble::sample_variants(
                &uncertain,
                mc.samples,
                mc.seed,
                mc.sampling,
                mc.sobol_indices,
                correlation.as_ref(),
            )
                .map_err(|m| cli_error("ensemble.uncertain", m.to_string()))?
        }
        None => match crate::ensemble::case_variants(&case, variants_file)? {
            Some(v) => v,
            None => {
                return Err(InputError {
                    source_name: case_path.display().to_string(),
                    line: 1,
                    key: "ensemble.grid".into(),
                    message:
                        "no variants: give --variants FILE, an [ensemble.grid] table, or --samples N with an [ensemble.uncertain] table"
                            .into(),
                }
                .into())
            }
        },
    };
    // Stabilizers the variants place stand where they are placed: the mesh takes a node
    // there (`ran.stabK.from_bit_m` in variants.csv says where each ran).
    let case = crate::ensemble::placed_case(&case, &variants)?.unwrap_or(case);
    let analysis = settings
        .as_ref()
        .map(|s| s.analysis)
        .unwrap_or(Analysis::Static);
    let series: Vec<String> = settings
        .as_ref()
        .map(|s| s.series.clone())
        .unwrap_or_default();
    for name in &series {
        if !variants.iter().any(|v| &v.name == name) {
            return Err(InputError {
                source_name: case_path.display().to_string(),
                line: 1,
                key: "ensemble.series".into(),
                message: format!("no variant named {name:?}"),
            }
            .into());
        }
        if analysis == Analysis::Static {
            return Err(InputError {
                source_name: case_path.display().to_string(),
                line: 1,
                key: "ensemble.series".into(),
                message: "time series need analysis = \"dynamic\"".into(),
            }
            .into());
        }
    }
    if precision == Precision::F32 {
        let why = match (backend, analysis) {
            (BackendChoice::Cpu, _) => Some("the CPU backend computes in f64 (it is the oracle the GPU is tested against); f32 runs on --backend gpu or auto"),
            _ => None,
        };
        if let Some(message) = why {
            return Err(InputError {
                source_name: "--precision".into(),
                line: 0,
                key: "precision".into(),
                message: message.into(),
            }
            .into());
        }
    }
    // The GPU engine, where asked for (or, with auto, where a hardware adapter has f64).
    // The GPU engine where asked for; `auto` takes it on a hardware adapter (the CPU
    // backend computes in f64 only, so f32 always runs on the engine).
    let (resolved, resolve_note) = crate::backend::Backend::resolve_with(
        backend,
        precision,
        &[Precision::F64],
        crate::backend::AutoRule::FasterPath,
    )?;
    let gpu = match resolved {
        crate::backend::Backend::Gpu(ctx) => Some(ctx),
        crate::backend::Backend::Cpu => None,
    };
    // Thresholds must name a quantity this case reports (checked before any work).
    if let Some(mc) = monte_carlo {
        let names: Vec<String> = qoi_columns(
            &[],
            case.model.stabilizer_sites().len(),
            analysis == Analysis::Dynamic,
        )
        .into_iter()
        .map(|q| q.name)
        .collect();
        for (name, _) in &mc.thresholds {
            if !names.contains(name) {
                return Err(InputError {
                    source_name: "--exceed".into(),
                    line: 0,
                    key: name.clone(),
                    message: format!("no quantity {name:?}; allowed: {}", names.join(", ")),
                }
                .into());
            }
        }
    }
    // The measurements to draw over the broomstick, read before any work (a bad file is
    // refused with its line and column).
    let measured = match &options.measured {
        Some(p) => crate::ensemble::measured::read_measured(p)?,
        None => Vec::new(),
    };
    // Check every variant against the case before any work, keeping what it runs with
    // for `variants.csv` (the report does not build the model again).
    let stabs = case.model.stabilizer_sites().len();
    let mut ran_rows = Vec::with_capacity(variants.len());
    for v in &variants {
        match apply(&case, v) {
            Ok(model) => ran_rows.push(crate::ensemble::report::ran_row(&model, stabs)),
            Err(e) => {
                return Err(InputError {
                    source_name: variants_file
                        .map(|p| p.display().to_string())
                        .unwrap_or_else(|| case_path.display().to_string()),
                    line: 0,
                    key: format!("variant {}", v.name),
                    message: e.to_string(),
                }
                .into())
            }
        }
    }
    // The output folder, checked (and the run's manifest written) before any work.
    // The one range check of the chunk size (the command line passes it through).
    if !(1..=1_000_000).contains(&options.chunk_size) {
        return Err(cli_error(
            "--chunk-size",
            format!(
                "{} variants per chunk; allowed: 1 … 1000000 (default {DEFAULT_CHUNK})",
                options.chunk_size
            ),
        ));
    }
    let chunk_size = options.chunk_size;
    let manifest = Manifest::new(
        case_path,
        variants_file,
        backend,
        precision,
        options,
        chunk_size,
        variants.len(),
    )?;
    prepare_out(out, &manifest, options.force)?;
    let nchunks = manifest.chunks;
    let range = match options.shard {
        Some((k, n)) => (k - 1) * nchunks / n..k * nchunks / n,
        None => 0..nchunks,
    };
    let chunk_of = |c: usize| c * chunk_size..((c + 1) * chunk_size).min(variants.len());
    let in_range: usize = range.clone().map(|c| chunk_of(c).len()).sum();
    let bar = crate::output::progress_bar(
        show_progress,
        in_range as u64,
        "{bar:40} {pos}/{len} variants, {elapsed} elapsed, eta {eta}",
    );
    let clock = std::time::Instant::now();
    let mut computed_here = 0usize;
    for c in range.clone() {
        let path = chunk_path(out, c);
        if path.exists() {
            bar.inc(chunk_of(c).len() as u64);
            continue;
        }
        // At least one chunk per invocation, so runs repeated under a budget progress.
        if let (Some(budget), true) = (options.max_seconds, computed_here > 0) {
            if clock.elapsed().as_secs_f64() > budget {
                bar.finish_and_clear();
                let done = range
                    .clone()
                    .filter(|&c| chunk_path(out, c).exists())
                    .count();
                return Err(Error::Stopped(format!(
                    "the --max-seconds budget ({budget} s) is spent: {done} of {} chunks are \
                     in {}/chunks; the same command continues from them",
                    range.len(),
                    out.display()
                )));
            }
        }
        let start = std::time::Instant::now();
        let slice = &variants[chunk_of(c)];
        let before = bar.position();
        let (results, backend_name, backend_note) =
            compute(&case, analysis, slice, gpu, precision, &bar)?;
        bar.set_position(before + slice.len() as u64);
        let chunk = Chunk {
            first: chunk_of(c).start,
            backend: backend_name.to_string(),
            backend_note,
            seconds: start.elapsed().as_secs_f64(),
            results,
        };
        let text = serde_json::to_vec(&chunk).map_err(Error::from)?;
        write_atomic(&path, &text)?;
        computed_here += 1;
    }
    bar.finish_and_clear();
    if let Some((k, n)) = options.shard {
        return Ok(EnsembleSummary {
            warnings: case.warnings.clone(),
            title: case.title.clone(),
            analysis: format!("{analysis:?}").to_lowercase(),
            backend: format!("{backend:?}").to_lowercase(),
            backend_note: None,
            precision: format!("{precision:?}").to_lowercase(),
            variants: in_range,
            converged: 0,
            step_cut: 0,
            failed: 0,
            failures: Vec::new(),
            outside_hole: 0,
            stopped: 0,
            stopped_pushed: 0,
            pushed: 0,
            relaxed: 0,
            solved_by_engine: 0,
            solved_by_cpu: 0,
            seconds: 0.0,
            engine_seconds: super::report::EngineSeconds::since(&tally),
            uncertainty: None,
            outputs: vec![format!(
                "shard {k}/{n}: chunks {}..{} in {}/chunks; `holewall merge` gives the whole run",
                range.start,
                range.end,
                out.display()
            )],
        });
    }
    // Every chunk, read back (so a resumed or merged run has exactly these bits).
    let mut results = Vec::with_capacity(variants.len());
    let mut backend_name = "cpu";
    // Why `auto` chose the CPU, then the chunks' own notes.
    let mut backend_notes: Vec<String> = resolve_note.into_iter().collect();
    let mut seconds = 0.0;
    for c in 0..nchunks {
        let chunk = read_chunk(&chunk_path(out, c))?;
        if chunk.first != chunk_of(c).start || chunk.results.len() != chunk_of(c).len() {
            return Err(Error::Failed(format!(
                "{}: holds {} variants from {}, not the chunk's {} from {}",
                chunk_path(out, c).display(),
                chunk.results.len(),
                chunk.first,
                chunk_of(c).len(),
                chunk_of(c).start
            )));
        }
        if chunk.backend == "gpu" {
            backend_name = "gpu";
        }
        if let Some(n) = chunk.backend_note {
            if !backend_notes.contains(&n) {
                backend_notes.push(n);
            }
        }
        seconds += chunk.seconds;
        results.extend(chunk.results);
    }
    let dynamic = analysis == Analysis::Dynamic;
    let mut outputs = vec!["variants.csv".to_string()];
    write_atomic(
        &out.join("variants.csv"),
        &variants_csv(&case, &variants, &ran_rows, &results, stabs, dynamic)?,
    )?;
    let uncertainty = match monte_carlo {
        Some(mc) => {
            let (report, files) =
                uncertainty_report(mc, &case, &variants, &results, stabs, dynamic, out)?;
            outputs.extend(files);
            Some(report)
        }
        None => None,
    };
    outputs.extend(broomstick(&case, &variants, &results, &measured, out)?);
    if monte_carlo.is_none() {
        outputs.extend(over_the_inputs(&case, &variants, &results, stabs, out)?);
        if dynamic {
            outputs.extend(whirl_maps(&case, &variants, &results, stabs, out)?);
        }
        for name in &series {
            let v = variants
                .iter()
                .find(|v| &v.name == name)
                .ok_or_else(|| Error::failed(format!("no variant {name}")))?;
            let mut c = case.clone();
            c.model = apply(&case, v).map_err(Error::failed)?;
            let dir = out.join("series").join(name);
            crate::run::run_case_into(&c, &dir, false)?;
            outputs.push(format!("series/{name}/"));
        }
    }
    let count = |s: Status| results.iter().filter(|r| r.status == s).count();
    let summary = EnsembleSummary {
        warnings: case.warnings.clone(),
        title: case.title.clone(),
        analysis: if dynamic { "dynamic" } else { "static" }.into(),
        backend: backend_name.into(),
        backend_note: (!backend_notes.is_empty()).then(|| backend_notes.join("; ")),
        precision: if backend_name == "gpu" && precision == Precision::F32 {
            "f32"
        } else {
            "f64"
        }
        .into(),
        variants: variants.len(),
        converged: count(Status::Converged),
        step_cut: count(Status::StepCut),
        failed: count(Status::Failed),
        failures: results
            .iter()
            .filter(|r| r.status == Status::Failed)
            .map(|r| (r.name.clone(), r.reason.clone()))
            .collect(),
        outside_hole: results
            .iter()
            .filter(|r| r.status != Status::Failed && r.string.outside_hole_m > Some(0.0))
            .count(),
        stopped: results
            .iter()
            .filter(|r| r.string.stopped_load_factor.is_some())
            .count(),
        pushed: results
            .iter()
            .filter(|r| !dynamic && super::report::pushed(r))
            .count(),
        stopped_pushed: results
            .iter()
            .filter(|r| r.string.stands.is_some_and(|s| s.hook_load_n < 0.0))
            .count(),
        relaxed: results
            .iter()
            .filter(|r| r.status != Status::Failed && r.string.relaxed == Some(true))
            .count(),
        solved_by_engine: results
            .iter()
            .filter(|r| r.status != Status::Failed && r.solved_by == SolvedBy::Engine)
            .count(),
        solved_by_cpu: results
            .iter()
            .filter(|r| r.status != Status::Failed && r.solved_by == SolvedBy::Cpu)
            .count(),
        seconds,
        engine_seconds: super::report::EngineSeconds::since(&tally),
        uncertainty,
        outputs,
    };
    crate::output::write_json_atomic(&out.join("summary.json"), &summary)?;
    // `--units field`: variants.csv, the statistics' CSVs and summary.json translated (the
    // chunks and run.json, the run's own state, stay SI).
    crate::display_units::convert_folder(out)?;
    crate::report_html::write(out, "ensemble", Some(&case.path))?;
    Ok(summary)
}

/// An error about one of `holewall merge`'s shard folders (an input, not `--out`).
fn shard_folder_error(dir: &Path, message: String) -> Error {
    InputError {
        source_name: "shard folder".into(),
        line: 0,
        key: dir.display().to_string(),
        message,
    }
    .into()
}

/// `holewall merge`: the shards in `dirs` (one run's `--shard K/N` folders, every K once)
/// into `out`, which then holds exactly what the run without shards would write.
pub fn merge(
    out: &Path,
    dirs: &[std::path::PathBuf],
    show_progress: bool,
) -> Result<EnsembleSummary, Error> {
    let read = |d: &std::path::PathBuf| -> Result<Manifest, Error> {
        let p = d.join("run.json");
        let t = std::fs::read(&p).map_err(|e| {
            shard_folder_error(d, format!("no run.json ({e}): not a holewall run folder"))
        })?;
        serde_json::from_slice(&t).map_err(|e| shard_folder_error(d, format!("run.json: {e}")))
    };
    let manifests = dirs.iter().map(read).collect::<Result<Vec<_>, Error>>()?;
    let first = manifests
        .first()
        .ok_or_else(|| out_error(out, "no shard folders given".into()))?;
    let n = match first.shard {
        Some((_, n)) => n,
        None => {
            return Err(shard_folder_error(
                &dirs[0],
                "is a whole run, not a shard".into(),
            ))
        }
    };
    let mut seen = vec![false; n];
    for (d, m) in dirs.iter().zip(&manifests) {
        if m.identity != first.identity {
            return Err(shard_folder_error(
                d,
                format!(
                    "is a shard of another run (identity {} against {})",
                    m.identity, first.identity
                ),
            ));
        }
        match m.shard {
            Some((k, nn)) if nn == n && (1..=n).contains(&k) && !seen[k - 1] => seen[k - 1] = true,
            other => {
                let which = match other {
                    Some((k, nn)) => format!("shard {k}/{nn}"),
                    None => "a whole run (not a shard)".to_string(),
                };
                return Err(shard_folder_error(
                    d,
                    format!("{which} does not fit {n} shards given once each"),
                ));
            }
        }
    }
    if let Some(k) = seen.iter().position(|s| !s) {
        return Err(out_error(out, format!("shard {}/{n} is missing", k + 1)));
    }
    let mut whole = first.clone();
    whole.shard = None;
    prepare_out(out, &whole, false)?;
    for (d, m) in dirs.iter().zip(&manifests) {
        let (k, _) = m.shard.unwrap_or((1, 1));
        for c in (k - 1) * whole.chunks / n..k * whole.chunks / n {
            let from = chunk_path(d, c);
            if !from.exists() {
                return Err(shard_folder_error(
                    d,
                    format!("chunk {c} is missing: the shard did not finish; run it again"),
                ));
            }
            let text = std::fs::read(&from)?;
            write_atomic(&chunk_path(out, c), &text)?;
        }
    }
    let options = EnsembleOptions {
        monte_carlo: whole.monte_carlo.clone(),
        chunk_size: whole.chunk_size,
        shard: None,
        force: false,
        max_seconds: None,
        measured: None,
    };
    run(
        &whole.case,
        whole.variants_file.as_deref(),
        whole.backend,
        whole.precision,
        out,
        show_progress,
        &options,
    )
}

/// Per stabilizer, how it whirls against the varied inputs (`whirl_map_stabK.png`): a
/// scatter coloured by class (none, forward, backward, chaotic) over the first two varied
/// keys (RPM and WOB first: the whirl map), or over the one varied key against the whirl
/// frequency.
fn whirl_maps(
    case: &crate::case::Case,
    variants: &[crate::ensemble::Variant],
    results: &[VariantResult],
    stabs: usize,
    out: &Path,
) -> Result<Vec<String>, Error> {
    use crate::keys::Param;
    use crate::uq::report::Unit;
    use crate::whirl::WhirlClass;
    let mut keys: Vec<crate::keys::Key> = Vec::new();
    for v in variants {
        for (k, _) in &v.overrides {
            if !keys.iter().any(|x| x.name == k.name) && k.param != Param::Mode {
                keys.push(k.clone());
            }
        }
    }
    // RPM and WOB first.
    keys.sort_by_key(|k| match k.param {
        Param::Rpm => 0,
        Param::Wob => 1,
        _ => 2,
    });
    let value = |v: &crate::ensemble::Variant, k: &crate::keys::Key| {
        v.overrides
            .iter()
            .find(|(x, _)| x.name == k.name)
            .map_or(f64::NAN, |(_, x)| x.si())
    };
    let label = |k: &crate::keys::Key| {
        let (_, unit) = Unit::of_key(k).display();
        format!("{} ({unit})", k.name)
    };
    let classes = ["none", "forward", "backward", "chaotic"];
    let class_index = |c: Option<WhirlClass>| match c {
        Some(WhirlClass::Forward) => 1,
        Some(WhirlClass::Backward) => 2,
        Some(WhirlClass::Chaotic) => 3,
        _ => 0,
    };
    let mut written = Vec::new();
    let Some(kx) = keys.first() else {
        return Ok(written);
    };
    let (sx, _) = Unit::of_key(kx).display();
    // A third varied key (friction, say): one map per value of a grid, so no point hides
    // another; a drawn key (a value per variant) in at most `WHIRL_MAP_FACETS` ranges
    // (`whirl_map_groups`).
    let groups: Vec<Option<(f64, f64)>> = match keys.get(2) {
        None => vec![None],
        Some(kz) => {
            let ky = keys.get(1);
            let points: Vec<[f64; 3]> = variants
                .iter()
                .map(|v| [value(v, kx), ky.map_or(0.0, |k| value(v, k)), value(v, kz)])
                .collect();
            whirl_map_groups(&points).into_iter().map(Some).collect()
        }
    };
    for k in 0..stabs {
        for group in &groups {
            let (file, suffix) = match (group, keys.get(2)) {
                (Some((lo, hi)), Some(kz)) => {
                    let (sz, unit) = Unit::of_key(kz).display();
                    let unit = if unit == "–" {
                        String::new()
                    } else {
                        format!(" {unit}")
                    };
                    let (lo, hi) = (crate::units::show(sz * lo), crate::units::show(sz * hi));
                    if lo == hi {
                        (
                            format!("whirl_map_stab{}_{}{lo}.png", k + 1, kz.name),
                            format!(", {} = {lo}{unit}", kz.name),
                        )
                    } else {
                        (
                            format!("whirl_map_stab{}_{}{lo}-{hi}.png", k + 1, kz.name),
                            format!(", {} from {lo} to {hi}{unit}", kz.name),
                        )
                    }
                }
                _ => (format!("whirl_map_stab{}.png", k + 1), String::new()),
            };
            let points: Vec<(f64, f64, usize)> = variants
                .iter()
                .zip(results)
                .filter(|(v, _)| match (group, keys.get(2)) {
                    (Some((lo, hi)), Some(kz)) => (*lo..=*hi).contains(&value(v, kz)),
                    _ => true,
                })
                .filter_map(|(v, r)| {
                    let q = r.stabilizers.get(k)?;
                    let y = match keys.get(1) {
                        Some(ky) => Unit::of_key(ky).display().0 * value(v, ky),
                        None => q.whirl_hz.unwrap_or(0.0),
                    };
                    Some((sx * value(v, kx), y, class_index(q.whirl_class)))
                })
                .collect();
            let y_label = keys.get(1).map_or(
                "dominant whirl frequency (Hz; + forward)".to_string(),
                label,
            );
            crate::plots::class_scatter(
                &out.join(&file),
                &format!("{}: how stabilizer {} whirls{suffix}", case.title, k + 1),
                &label(kx),
                &y_label,
                &points,
                &classes,
            )?;
            written.push(file);
        }
    }
    Ok(written)
}

/// At most this many whirl maps per stabilizer over a third varied key drawn per variant
/// ([`whirl_map_groups`]): one map per distinct value gave 378 PNGs of a few points each for
/// 1,024 variants of `cases/whirl_job.toml` with μ drawn to three digits.
pub const WHIRL_MAP_FACETS: usize = 6;

/// A grid's third key keeps one map per value up to this many values (a grid repeats its
/// (x, y) points for every value, and a map of two values would hide one under the other).
pub const WHIRL_MAP_GRID_VALUES: usize = 24;

/// The whirl maps' ranges of the third varied key from each variant's `[x, y, z]` (its
/// first, second and third varied keys): one map per value where there are at most
/// [`WHIRL_MAP_FACETS`] values, or where some (x, y) point recurs with two values of z (a
/// grid) and there are at most [`WHIRL_MAP_GRID_VALUES`]; else at most [`WHIRL_MAP_FACETS`]
/// ranges ([`facets`]).
pub fn whirl_map_groups(points: &[[f64; 3]]) -> Vec<(f64, f64)> {
    let z: Vec<f64> = points.iter().map(|p| p[2]).collect();
    let exact = facets(&z, usize::MAX);
    let mut seen: std::collections::HashMap<(u64, u64), u64> = std::collections::HashMap::new();
    let recurs = points.iter().any(|p| {
        let z = p[2].to_bits();
        *seen.entry((p[0].to_bits(), p[1].to_bits())).or_insert(z) != z
    });
    if exact.len() <= WHIRL_MAP_FACETS || (recurs && exact.len() <= WHIRL_MAP_GRID_VALUES) {
        exact
    } else {
        facets(&z, WHIRL_MAP_FACETS)
    }
}

/// The ranges (inclusive, from the smallest value to the largest) a third varied key's
/// values fall into, in order: one per distinct value where there are at most `max`, else
/// at most `max` ranges holding about as many variants each (edges at values, a value never
/// split between two). Values that are not finite (a variant without the key) fall in none.
pub fn facets(values: &[f64], max: usize) -> Vec<(f64, f64)> {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let mut distinct = sorted.clone();
    distinct.dedup();
    if distinct.len() <= max.max(1) {
        return distinct.into_iter().map(|x| (x, x)).collect();
    }
    let n = sorted.len();
    let mut ranges: Vec<(f64, f64)> = Vec::new();
    let mut start = 0;
    for b in 1..=max {
        // The upper edge of range b: the value at its share of the variants, with every
        // equal value after it.
        let mut end = (b * n).div_ceil(max).max(start + 1).min(n);
        while end < n && sorted[end] == sorted[end - 1] {
            end += 1;
        }
        if start < end {
            ranges.push((sorted[start], sorted[end - 1]));
        }
        start = end;
        if start >= n {
            break;
        }
    }
    ranges
}

#[cfg(test)]
mod tests {
    use super::facets;

    #[test]
    fn a_grid_of_many_values_keeps_its_maps_and_a_draw_is_binned() {
        use super::{whirl_map_groups, WHIRL_MAP_FACETS};
        // A grid: 4 × 2 (x, y) points at each of 9 frictions: one map each (two frictions
        // in one map would hide every point under another).
        let mut grid = Vec::new();
        for z in 0..9 {
            for x in 0..4 {
                for y in 0..2 {
                    grid.push([x as f64, y as f64, 0.1 + 0.05 * z as f64]);
                }
            }
        }
        assert_eq!(whirl_map_groups(&grid).len(), 9);
        // The same 72 variants drawn (no (x, y) point twice): six ranges.
        let drawn: Vec<[f64; 3]> = grid
            .iter()
            .enumerate()
            .map(|(i, p)| [i as f64, 0.5 * i as f64, p[2]])
            .collect();
        assert_eq!(whirl_map_groups(&drawn).len(), WHIRL_MAP_FACETS);
        // A grid of more values than a page of maps is read in ranges too.
        let wide: Vec<[f64; 3]> = (0..50).map(|i| [0.0, 0.0, i as f64]).collect();
        assert_eq!(whirl_map_groups(&wide).len(), WHIRL_MAP_FACETS);
    }

    #[test]
    fn a_grid_keeps_one_facet_per_value_and_a_draw_gets_ranges() {
        // A grid: three values, each its own map.
        let grid = [0.1, 0.3, 0.5, 0.1, 0.3, 0.5, 0.5];
        assert_eq!(facets(&grid, 6), vec![(0.1, 0.1), (0.3, 0.3), (0.5, 0.5)]);
        // A draw: 1,000 distinct values in six ranges of about equal counts, covering
        // every value once, in order, none split.
        let drawn: Vec<f64> = (0..1000)
            .map(|i| ((i * 7919) % 1000) as f64 / 1000.0)
            .collect();
        let r = facets(&drawn, 6);
        assert_eq!(r.len(), 6);
        assert_eq!((r[0].0, r[5].1), (0.0, 0.999));
        for w in r.windows(2) {
            assert!(w[0].1 < w[1].0, "{r:?}");
        }
        for (lo, hi) in &r {
            let count = drawn.iter().filter(|x| (*lo..=*hi).contains(*x)).count();
            assert!((166..=167).contains(&count), "{r:?}: {count}");
        }
        // Repeated values stay together; values not set fall in none.
        let tied = [1.0, 1.0, 1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, f64::NAN];
        let r = facets(&tied, 3);
        assert_eq!(r, vec![(1.0, 1.0), (2.0, 4.0), (5.0, 7.0)]);
    }
}
