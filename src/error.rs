//! The library's error types.

use thiserror::Error;

/// Errors of the GPU path.
#[derive(Clone, Debug, Error)]
pub enum GpuError {
    /// No adapter could be opened (no Vulkan driver, or `WGPU_ADAPTER_NAME` matches none).
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
    /// The device could not be created or was lost.
    #[error("GPU device: {0}")]
    Device(String),
    /// A shader failed to compose, validate or compile.
    #[error("shader: {0}")]
    Shader(String),
    /// The adapter lacks a feature the request needs.
    #[error("GPU feature missing: {0}")]
    Unsupported(String),
}

/// Why the machinery under a solve failed — a kernel path, a linear solve, a call out of
/// order — as opposed to a solve that ran and did not converge (a Newton event, a
/// [`crate::solve::statics::StaticError`]). The error of [`crate::solve::newton::NewtonSystem`],
/// [`crate::solve::continuation::StaticSystem`] and the engine's kernel paths.
#[derive(Clone, Debug, Error)]
pub enum SystemError {
    /// The GPU path failed (device, shader, read-back).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The block solve did not finish (a GPU dispatch left a status at running) or met a
    /// non-finite entry.
    #[error("block solve: {0}")]
    BlockSolve(String),
    /// A CPU linear solve failed (faer).
    #[error("linear solve: {0}")]
    Linear(String),
    /// The variants, scene or options cannot run on this path.
    #[error("{0}")]
    Unsupported(String),
    /// A call out of the order the system needs (a defect of the caller).
    #[error("called out of order: {0}")]
    Order(&'static str),
}

/// An input error: names the source, line, key and the allowed range. Exit code 2.
/// Shown as `source:line: key: message`, or `source: key: message` where no line applies
/// (`line` 0: a command-line option, a whole file); the key is left out where it is `-`.
#[derive(Clone, Debug, Error)]
pub struct InputError {
    /// File name, or `<stdin>`.
    pub source_name: String,
    /// 1-based line number; 0 where no line applies.
    pub line: usize,
    /// The offending key (or `-` where the line as a whole is wrong).
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: ", self.source_name, self.line)?;
        } else {
            write!(f, "{}: ", self.source_name)?;
        }
        if self.key != "-" {
            write!(f, "{}: ", self.key)?;
        }
        f.write_str(&self.message)
    }
}

/// Top-level error of a command.
#[derive(Debug, Error)]
pub enum Error {
    /// Bad user input: exit code 2.
    #[error(transparent)]
    Input(#[from] InputError),
    /// GPU failure.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The machinery under a solve failed (exit code 1).
    #[error(transparent)]
    System(#[from] SystemError),
    /// I/O failure (reading or writing a file).
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// A result that could not be encoded or decoded (CSV, JSON, a plot): exit code 1.
    #[error("{0}")]
    Encode(String),
    /// A solve, a run or an engine that failed on valid input (a static solve that did not
    /// converge, a time step that failed, the GPU engine's error): exit code 1.
    #[error("{0}")]
    Failed(String),
    /// Stopped by the user's budget (`--max-seconds`), resumable: exit code 3.
    #[error("{0}")]
    Stopped(String),
}

impl From<csv::Error> for Error {
    fn from(e: csv::Error) -> Self {
        Error::Encode(format!("CSV: {e}"))
    }
}

impl From<serde_json::Error> for Error {
    fn from(e: serde_json::Error) -> Self {
        Error::Encode(format!("JSON: {e}"))
    }
}

impl Error {
    /// [`Error::Encode`] from any message (a CSV writer's, a plot's).
    pub fn encode(message: impl std::fmt::Display) -> Self {
        Error::Encode(message.to_string())
    }

    /// [`Error::Failed`] from any message.
    pub fn failed(message: impl std::fmt::Display) -> Self {
        Error::Failed(message.to_string())
    }

    /// The process exit code for this error: 2 for bad input, 3 for a run stopped by its
    /// budget (resumable), 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input(_) => 2,
            Error::Stopped(_) => 3,
            _ => 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::InputError;

    #[test]
    fn an_input_error_names_its_key_unless_the_whole_line_or_file_is_wrong() {
        let e = |line, key: &str| InputError {
            source_name: "case.toml".into(),
            line,
            key: key.into(),
            message: "a message".into(),
        };
        assert_eq!(
            e(3, "hole.friction").to_string(),
            "case.toml:3: hole.friction: a message"
        );
        assert_eq!(
            e(0, "--variants").to_string(),
            "case.toml: --variants: a message"
        );
        assert_eq!(e(3, "-").to_string(), "case.toml:3: a message");
        assert_eq!(e(0, "-").to_string(), "case.toml: a message");
    }

    #[test]
    fn a_case_file_that_cannot_be_read_says_so() {
        let path = std::path::Path::new("/no/such/folder/case.toml");
        let err = crate::case::load_case(path).expect_err("no such file");
        let text = err.to_string();
        assert!(
            text.starts_with("/no/such/folder/case.toml: cannot read the case file: "),
            "{text}"
        );
    }
}
