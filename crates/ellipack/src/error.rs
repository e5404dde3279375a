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
        #[source]
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
    #[error("{source_name}: line 1: missing column `{column}` (the header must name {expected})")]
    MissingColumn {
        /// The file.
        source_name: String,
        /// The column name.
        column: String,
        /// Every column the file must have, for the message.
        expected: String,
    },
    /// A column name appears more than once in the header, so which one holds the data is
    /// ambiguous.
    #[error("{source_name}: line 1: {source}")]
    DuplicateColumn {
        /// The file.
        source_name: String,
        /// The column and where it appears.
        #[source]
        source: crate::table::DuplicateColumn,
    },
    /// The header of a pairs file is neither the 3D layout nor the 2D layout.
    #[error(
        "{source_name}: line 1: the header is neither a 3D pairs file (r12_x, r12_y, r12_z, \
         q1_0..q1_5, q2_0..q2_5: {three_d}) nor a 2D one (r12_x, r12_y, q1_0..q1_2, \
         q2_0..q2_2: {two_d})"
    )]
    PairLayout {
        /// The file.
        source_name: String,
        /// What the 3D layout lacks.
        three_d: String,
        /// What the 2D layout lacks, or which 3D-only column it has.
        two_d: String,
    },
    /// `--output` names the input file: writing would destroy the data being read.
    #[error(
        "--output {} is the input file {}: choose another output file",
        output.display(),
        input.display()
    )]
    SameFile {
        /// The input.
        input: PathBuf,
        /// The output, the same file under the same or another name.
        output: PathBuf,
    },
    /// The results could not be written.
    #[error("{destination}: {source}")]
    Write {
        /// The file, or `<standard output>`.
        destination: String,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// The file has a header and no data rows.
    #[error("{source_name}: no rows to evaluate")]
    Empty {
        /// The file.
        source_name: String,
    },
}
