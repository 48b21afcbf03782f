//! A run's folder: `run.json` (what it was asked, its identity), results in chunks written
//! atomically (`chunks/chunk_NNNNNN.json`), checks before any work, resume and `--force`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::qoi::*;
use crate::backend::{BackendChoice, Precision};
use crate::error::Error;
use crate::output::{out_error, write_atomic};

/// Variants per result chunk unless `--chunk-size` says otherwise.
pub const DEFAULT_CHUNK: usize = 256;

/// Options of an ensemble run beyond the case, the variants file and the backend.
#[derive(Clone, Debug)]
pub struct EnsembleOptions {
    /// Monte Carlo sampling of `[ensemble.uncertain]` (`--samples`).
    pub monte_carlo: Option<crate::uq::report::MonteCarlo>,
    /// Variants per result chunk, ≥ 1 (default [`DEFAULT_CHUNK`]; 0 is refused).
    pub chunk_size: usize,
    /// Run only the K-th (1-based) of N slices of the chunks (`--shard K/N`).
    pub shard: Option<(usize, usize)>,
    /// Replace the outputs of another run in the output folder (`--force`).
    pub force: bool,
    /// Wall-time budget (s, `--max-seconds`): no chunk is started once it is spent; the
    /// run stops resumable ([`crate::Error::Stopped`]).
    pub max_seconds: Option<f64>,
    /// Measured hook loads and surface torques (`--measured FILE`, the file of
    /// `holewall calibrate`): drawn over the broomstick. Only plots change, so a run resumed
    /// or merged with another file keeps its results.
    pub measured: Option<std::path::PathBuf>,
}

impl Default for EnsembleOptions {
    fn default() -> Self {
        EnsembleOptions {
            monte_carlo: None,
            chunk_size: DEFAULT_CHUNK,
            shard: None,
            force: false,
            max_seconds: None,
            measured: None,
        }
    }
}

/// `run.json`: what a run was asked, to resume it, refuse another run's folder, and merge
/// shards.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// FNV-1a 64 of the case text, the variants file's text and every option that changes
    /// results or the report (hex).
    pub identity: String,
    /// The case file.
    pub case: std::path::PathBuf,
    /// The variants file, if any.
    pub variants_file: Option<std::path::PathBuf>,
    /// `cpu`, `gpu` or `auto`.
    pub backend: BackendChoice,
    /// Precision asked for.
    pub precision: Precision,
    /// Monte Carlo request.
    pub monte_carlo: Option<crate::uq::report::MonteCarlo>,
    /// Variants per chunk.
    pub chunk_size: usize,
    /// Variants in the whole run.
    pub variants: usize,
    /// Chunks in the whole run.
    pub chunks: usize,
    /// This folder's shard (K, N), or the whole run.
    pub shard: Option<(usize, usize)>,
}

pub(crate) fn fnv1a(bytes: &[u8], mut h: u64) -> u64 {
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

impl Manifest {
    pub(crate) fn new(
        case_path: &Path,
        variants_file: Option<&Path>,
        backend: BackendChoice,
        precision: Precision,
        options: &EnsembleOptions,
        chunk_size: usize,
        variants: usize,
    ) -> Result<Manifest, Error> {
        let mut h = 0xcbf29ce484222325u64;
        h = fnv1a(&std::fs::read(case_path)?, h);
        if let Some(f) = variants_file {
            h = fnv1a(b"\0variants\0", h);
            h = fnv1a(&std::fs::read(f)?, h);
        }
        let tail = format!(
            "\0{backend:?}\0{precision:?}\0{:?}\0{chunk_size}\0{variants}",
            options.monte_carlo
        );
        h = fnv1a(tail.as_bytes(), h);
        let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        Ok(Manifest {
            identity: format!("{h:016x}"),
            case: abs(case_path),
            variants_file: variants_file.map(abs),
            backend,
            precision,
            monte_carlo: options.monte_carlo.clone(),
            chunk_size,
            variants,
            chunks: variants.div_ceil(chunk_size),
            shard: options.shard,
        })
    }
}

/// One chunk of results, `chunks/chunk_NNNNNN.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct Chunk {
    /// Index of its first variant.
    pub(crate) first: usize,
    /// Where it ran.
    pub(crate) backend: String,
    /// Why it ran on the CPU when the GPU engine was chosen (none otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) backend_note: Option<String>,
    /// Wall time (s).
    pub(crate) seconds: f64,
    /// Results in variant order.
    pub(crate) results: Vec<VariantResult>,
}

pub(crate) fn chunk_path(out: &Path, c: usize) -> std::path::PathBuf {
    out.join("chunks").join(format!("chunk_{c:06}.json"))
}

pub(crate) fn read_chunk(path: &Path) -> Result<Chunk, Error> {
    let text = std::fs::read(path)
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
    serde_json::from_slice(&text).map_err(|e| Error::encode(format!("{}: {e}", path.display())))
}

/// The files a run writes into its folder (what `--force` clears).
pub(crate) fn is_run_output(name: &str) -> bool {
    matches!(
        name,
        "run.json" | "summary.json" | "variants.csv" | "chunks" | "series" | "report.html"
    ) || name.ends_with(".png")
}

/// Checks the output folder before any work: a fresh or empty folder, or one holding this
/// very run (resumed: its chunks are kept); another run's folder, or a folder with other
/// files, is refused unless `force` (which removes the earlier run's files, never others).
/// Writes `run.json`.
pub fn prepare_out(out: &Path, manifest: &Manifest, force: bool) -> Result<(), Error> {
    if out.exists() && !out.is_dir() {
        return Err(out_error(out, "is a file, not a folder".into()));
    }
    if out.is_dir() {
        let run_json = out.join("run.json");
        let same = std::fs::read(&run_json)
            .ok()
            .and_then(|t| serde_json::from_slice::<Manifest>(&t).ok())
            .is_some_and(|m| m.identity == manifest.identity && m.shard == manifest.shard);
        let entries: Vec<String> = std::fs::read_dir(out)?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        if !same && !entries.is_empty() {
            let ours = entries.iter().all(|n| is_run_output(n));
            if !force {
                return Err(out_error(
                    out,
                    if run_json.exists() {
                        "holds a run of other inputs; give another --out, or --force to replace it"
                            .into()
                    } else {
                        "is not empty; give an empty or new folder, or --force to replace a run's files there".into()
                    },
                ));
            }
            if !ours && !run_json.exists() {
                return Err(out_error(
                    out,
                    "holds files that are not a run's outputs; --force replaces only a run's, give an empty folder".into(),
                ));
            }
            for n in entries.iter().filter(|n| is_run_output(n)) {
                let p = out.join(n);
                if p.is_dir() {
                    std::fs::remove_dir_all(&p)?;
                } else {
                    std::fs::remove_file(&p)?;
                }
            }
        }
    }
    std::fs::create_dir_all(out.join("chunks"))
        .map_err(|e| out_error(out, format!("cannot create it: {e}")))?;
    let text = serde_json::to_vec_pretty(manifest).map_err(Error::from)?;
    write_atomic(&out.join("run.json"), &text)
        .map_err(|e| out_error(out, format!("cannot write into it: {e}")))?;
    Ok(())
}
