//! The one error type of the validation harness.
//!
//! Every variant names the file (and, for scenes and reference data, the line) it is about:
//! a validation run is read by someone who has to find the offending input quickly.

use std::fmt;
use std::path::PathBuf;

/// Why a study could not run (as opposed to a check that ran and failed, which is a result).
#[derive(Debug)]
pub enum Error {
    /// Reading or writing a file failed.
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A scene file is not valid TOML or does not match the scene schema.
    SceneSyntax {
        /// The scene file.
        path: PathBuf,
        /// 1-based line of the offending text (0 when the parser gave no position).
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message (it names the key).
        message: String,
    },
    /// A scene file parses but a value is unusable (wrong length, out of range, missing).
    SceneValue {
        /// The scene file.
        path: PathBuf,
        /// The key holding the value.
        key: String,
        /// 1-based line of the value (0 when the key is absent).
        line: usize,
        /// What is wrong with it.
        message: String,
    },
    /// A reference CSV file has a missing column or an unreadable number.
    Reference {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// A reference file could not be read (its error names the file, line and column).
    ReferenceFile {
        /// The test kit's reason.
        source: testkit::table::Error,
    },
    /// pw85 refused an input the harness built (a bug in the harness or a bad scene shape).
    Pw85 {
        /// What was being evaluated.
        context: String,
        /// pw85's error.
        source: pw85::Error,
    },
    /// implicit-packing refused an input the harness built.
    Implicit {
        /// What was being evaluated.
        context: String,
        /// The crate's message.
        message: String,
    },
    /// The `ellipack pack` pipeline refused a scene, or drawing its packing failed.
    Pack {
        /// The scene file or the step.
        context: String,
        /// The message.
        message: String,
    },
    /// cell-grid refused an input.
    Grid {
        /// The crate's message.
        message: String,
    },
    /// A study refused its options or input, or a peer program failed.
    Study {
        /// The study or the step.
        context: String,
        /// What is wrong.
        message: String,
    },
    /// Drawing a figure failed.
    Plot {
        /// The figure file.
        path: PathBuf,
        /// plotters' message.
        message: String,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Error::SceneSyntax {
                path,
                line,
                column,
                message,
            } => write!(
                f,
                "{}:{line}:{column}: {}",
                path.display(),
                message.trim_end()
            ),
            Error::SceneValue {
                path,
                key,
                line,
                message,
            } => write!(f, "{}:{line}: key `{key}`: {message}", path.display()),
            Error::Reference {
                path,
                line,
                message,
            } => write!(f, "{}:{line}: {message}", path.display()),
            Error::ReferenceFile { source } => write!(f, "reference data: {source}"),
            Error::Pw85 { context, source } => write!(f, "pw85 refused {context}: {source}"),
            Error::Implicit { context, message } => {
                write!(f, "implicit-packing refused {context}: {message}")
            }
            Error::Grid { message } => write!(f, "cell-grid: {message}"),
            Error::Pack { context, message } => write!(f, "{context}: {message}"),
            Error::Study { context, message } => write!(f, "{context}: {message}"),
            Error::Plot { path, message } => {
                write!(f, "{}: drawing failed: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            Error::ReferenceFile { source } => Some(source),
            _ => None,
        }
    }
}

impl From<testkit::table::Error> for Error {
    fn from(source: testkit::table::Error) -> Self {
        Error::ReferenceFile { source }
    }
}

/// Attaches a path to an I/O error.
pub(crate) fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Error {
    let path = path.into();
    move |source| Error::Io { path, source }
}

/// Attaches a description of the input to a pw85 error.
pub(crate) fn pw85(context: impl Into<String>) -> impl FnOnce(pw85::Error) -> Error {
    let context = context.into();
    move |source| Error::Pw85 { context, source }
}
