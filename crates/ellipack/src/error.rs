//! Errors of the command line: each names the file, and where it can, the line and column.

use std::path::PathBuf;

/// Why a command failed as a whole. (A single bad row of an otherwise readable file is not an
/// error of the command: its message goes into the row's `error` column.)
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The CSV structure is broken (unbalanced quotes, a row with a different number of
    /// fields, invalid UTF-8).
    #[error("{source_name}: line {line}: {message}")]
    MalformedCsv {
        /// The file, or `<built-in example>`.
        source_name: String,
        /// 1-based line number.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// A column the command needs is not in the header.
    #[error(
        "{source_name}: line 1: missing column `{column}` (the header must name r12_x, r12_y, r12_z, q1_0..q1_5, q2_0..q2_5)"
    )]
    MissingColumn {
        /// The file.
        source_name: String,
        /// The column name.
        column: String,
    },
    /// The file has a header and no data rows.
    #[error("{source_name}: no rows to evaluate")]
    Empty {
        /// The file.
        source_name: String,
    },
}
