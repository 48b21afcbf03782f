//! Output files: written to a temporary file beside the target, then renamed, so a file
//! that already exists is never left half-written.

use std::path::Path;

/// Serialises `rows` (serde structs, one per line, header from the field names) as CSV and
/// writes them to `path` atomically ([`write_atomic`]).
pub fn write_csv_rows<T: serde::Serialize>(
    path: &Path,
    rows: impl IntoIterator<Item = T>,
) -> std::io::Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(std::io::Error::other)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| std::io::Error::other(e.to_string()))?;
    write_atomic(path, &bytes)
}

pub use crate::atomic_file::{write_atomic, write_json_atomic};

/// Serde for an `f64` that may be NaN: JSON has no NaN, so it is written as `null` (as
/// serde_json does anyway) and `null` is read back as NaN; every finite value round-trips
/// bit for bit (serde_json's `float_roundtrip`).
pub mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes `x`, NaN and infinities as `null`.
    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        if x.is_finite() {
            s.serialize_f64(*x)
        } else {
            s.serialize_none()
        }
    }

    /// Reads a number, or `null` as NaN.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// The error for an output folder that cannot be used: names `--out` and the path; exit 2.
pub fn out_error(out: &Path, message: String) -> crate::error::Error {
    crate::error::InputError {
        source_name: "--out".into(),
        line: 0,
        key: out.display().to_string(),
        message,
    }
    .into()
}

/// Whether `name` is a file a single run (`holewall static`, `holewall run`) writes.
fn is_single_run_output(name: &str) -> bool {
    [".png", ".svg", ".csv", ".json", ".html"]
        .iter()
        .any(|ext| name.ends_with(ext))
}

/// The output folder of one `holewall static` or `holewall run`: checked before any work, the
/// files written into a fresh staging folder beside it (`.NAME.partial-PID`), `summary.json`
/// written last, and the staging folder renamed to `--out` at the end. A run therefore never
/// leaves its files beside another run's, and an interrupted run leaves `--out` as it was.
///
/// `--out` may be new, an empty folder, or the folder of an earlier complete run (a
/// `summary.json` and only `.png/.svg/.csv/.json` files), which is replaced as a whole once
/// the new run is complete. A file, or a folder holding anything else, is refused before
/// computing (exit 2).
#[derive(Debug)]
pub struct RunFolder {
    target: std::path::PathBuf,
    staging: std::path::PathBuf,
    /// An earlier run is replaced at the end.
    pub replaces_earlier_run: bool,
    finished: bool,
    /// `report.html`'s command and case file ([`RunFolder::with_report`]).
    report: Option<(String, std::path::PathBuf)>,
}

impl RunFolder {
    /// Checks `out` and creates the staging folder (so an unwritable parent fails now).
    pub fn prepare(out: &Path) -> Result<RunFolder, crate::error::Error> {
        if out.as_os_str().is_empty() {
            return Err(out_error(out, "is empty; give a folder name".into()));
        }
        if out.exists() && !out.is_dir() {
            return Err(out_error(
                out,
                "is a file, not a folder; give a new or empty folder".into(),
            ));
        }
        let mut replaces_earlier_run = false;
        if out.is_dir() {
            let entries: Vec<(String, bool)> = std::fs::read_dir(out)
                .map_err(|e| out_error(out, format!("cannot read it: {e}")))?
                .filter_map(|e| e.ok())
                .map(|e| {
                    (
                        e.file_name().to_string_lossy().into_owned(),
                        e.path().is_file(),
                    )
                })
                .collect();
            if !entries.is_empty() {
                let earlier_run = entries.iter().any(|(n, _)| n == "summary.json")
                    && entries
                        .iter()
                        .all(|(n, file)| *file && is_single_run_output(n));
                if !earlier_run {
                    return Err(out_error(
                        out,
                        "holds files that are not the outputs of an earlier holewall run \
                         (a summary.json and .png/.svg/.csv/.json files only); give a new or \
                         empty folder"
                            .into(),
                    ));
                }
                replaces_earlier_run = true;
            }
        }
        let name = out
            .file_name()
            .ok_or_else(|| out_error(out, "has no folder name (.. or /); name a folder".into()))?
            .to_string_lossy()
            .into_owned();
        let parent = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(parent)
            .map_err(|e| out_error(out, format!("cannot create its parent folder: {e}")))?;
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if staging.exists() {
            std::fs::remove_dir_all(&staging)
                .map_err(|e| out_error(out, format!("cannot clear {}: {e}", staging.display())))?;
        }
        std::fs::create_dir(&staging)
            .map_err(|e| out_error(out, format!("cannot write into {}: {e}", parent.display())))?;
        Ok(RunFolder {
            target: out.to_path_buf(),
            staging,
            replaces_earlier_run,
            finished: false,
            report: None,
        })
    }

    /// The folder gets a `report.html` ([`crate::report_html`]) at [`RunFolder::finish`]:
    /// `command` made it from the case file `case`.
    pub fn with_report(mut self, command: &str, case: &Path) -> Self {
        self.report = Some((command.to_string(), case.to_path_buf()));
        self
    }

    /// Where the run writes its files until [`RunFolder::finish`].
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// `--out` as given.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Writes `summary.json` (last), then puts the staging folder in place of `--out`.
    pub fn finish(mut self, summary_json: &[u8]) -> Result<(), crate::error::Error> {
        write_atomic(&self.staging.join("summary.json"), summary_json)?;
        // `--units field`: the CSVs and summary.json translated, still in staging.
        crate::display_units::convert_folder(&self.staging)?;
        if let Some((command, case)) = &self.report {
            crate::report_html::write(&self.staging, command, Some(case))?;
        }
        let out = self.target.clone();
        if out.is_dir() {
            // An empty folder or an earlier run (checked by `prepare`): moved aside, then gone.
            let old = self.staging.with_file_name(format!(
                ".{}.old-{}",
                out.file_name().unwrap_or_default().to_string_lossy(),
                std::process::id()
            ));
            std::fs::rename(&out, &old)
                .map_err(|e| out_error(&out, format!("cannot replace it: {e}")))?;
            std::fs::rename(&self.staging, &out).map_err(|e| {
                let _ = std::fs::rename(&old, &out);
                out_error(&out, format!("cannot put the new run in place: {e}"))
            })?;
            let _ = std::fs::remove_dir_all(&old);
        } else {
            std::fs::rename(&self.staging, &out)
                .map_err(|e| out_error(&out, format!("cannot put the run in place: {e}")))?;
        }
        self.finished = true;
        Ok(())
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        if !self.finished {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

/// A progress bar on stderr with `template` (indicatif), or a hidden one when `show` is
/// false; the one style every long command uses.
pub fn progress_bar(show: bool, len: u64, template: &str) -> indicatif::ProgressBar {
    let bar = if show {
        indicatif::ProgressBar::new(len)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(template)
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}
