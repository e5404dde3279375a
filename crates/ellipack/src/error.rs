//! The errors of the library: one enum, each message naming the file and, where it can, the
//! line and column (both 1-based), the item or the key.

use crate::pack::Unfinished;
use crate::packing::ContainerKind;
use implicit_packing::certificate::shown_mu2;
use std::path::PathBuf;
use std::time::Duration;

pub use crate::toml_keys::SceneError;

/// Why an `ellipack` operation failed. (A single bad row of an otherwise readable pairs file is
/// not an error of the command: its message goes into the row's `error` column.)
#[derive(Debug, thiserror::Error)]
pub enum Error {
    // Files: reading, writing, their structure.
    /// A file could not be read or written (or a temporary file of the PNG encoder used).
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// The structure of a file is broken (CSV quoting, a row with the wrong number of fields,
    /// invalid UTF-8 or JSON, an XYZ header that is not ours).
    #[error("{source_name}: line {line}: {message}")]
    Malformed {
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

    /// One value is unreadable or impossible (not a number, a negative semi-axis, a zero
    /// quaternion).
    #[error("{source_name}: line {line}, column {column} (`{name}`): {message}")]
    BadValue {
        /// The file.
        source_name: String,
        /// 1-based line.
        line: u64,
        /// 1-based column: the field's position in a CSV or XYZ row, the character in JSON.
        column: u64,
        /// The column or key.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// Two rows of the items table carry the same `id`, so a message about that id could
    /// not say which item it means.
    #[error("{source_name}: line {line}: id {id} is already the id of line {first_line}")]
    DuplicateId {
        /// The file.
        source_name: String,
        /// The repeated id.
        id: u64,
        /// 1-based line of its first row.
        first_line: u64,
        /// 1-based line of the repetition.
        line: u64,
    },
    /// The files contradict each other or the data model (a 2D table with a 3D container, a
    /// different item count).
    #[error("{source_name}: {message}")]
    Inconsistent {
        /// The file that disagrees.
        source_name: String,
        /// What disagrees.
        message: String,
    },
    /// A summary value is NaN or infinite: JSON has no way to store it, so nothing is written.
    #[error("summary: `{field}` is {value}, which JSON cannot store")]
    NonFinite {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
    },

    // Scenes.
    /// A scene file is wrong at a line and column.
    #[error(transparent)]
    Scene(#[from] SceneError),

    // Packing runs.
    /// The structure of a packing could not be measured.
    #[error("structure: {0}")]
    Structure(#[from] structure::Error),
    /// The model refused the problem.
    #[error("{0}")]
    Model(#[from] implicit_packing::Error),
    /// The packer could not give a certified packing.
    #[error("{0}")]
    Packer(#[from] ellipsoid_packer::Error),
    /// A packing given to resume from does not match the scene.
    #[error("cannot resume: {0}")]
    Mismatch(String),
    /// A value of an item or of the container that the model cannot hold, named as the
    /// packing states it (not as a model variable).
    #[error("{what} is {value}; {rule}")]
    OutOfRange {
        /// The item and coordinate, or the container's value.
        what: String,
        /// The value, as the model saw it.
        value: String,
        /// What the model accepts.
        rule: &'static str,
    },
    /// The folder to resume from holds a packing in another kind of container than the scene's.
    #[error(
        "cannot resume from {summary}: its container is {found}, but the scene ({scene}) has \
         {expected}"
    )]
    ContainerMismatch {
        /// The folder's `summary.json`.
        summary: PathBuf,
        /// The container kind of the folder.
        found: ContainerKind,
        /// The container kind of the scene.
        expected: ContainerKind,
        /// The scene's title.
        scene: String,
    },
    /// The output folder cannot be created or written to.
    #[error("the output folder {path} is not writable: {source}")]
    OutputFolder {
        /// The folder.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// A fixed container that the run could not fill without overlap: the least overlapping
    /// configuration comes with the error, to be kept apart from packings.
    #[error(
        "packing fraction {:.4} not reached in {:.1} s: the least overlapping configuration \
         ({} local minimisations) has {} overlapping pairs{} and {} items outside the container \
         (model overlap {:.3e})",
        .0.summary.density,
        .0.summary.wall_seconds,
        .0.summary.local_minimisations,
        .0.summary.certificate.overlapping_pairs,
        .0.summary.certificate.min_mu2.map_or(String::new(), |m| format!(" (smallest μ² {})", shown_mu2(m, 6))),
        .0.summary.certificate.containment_violations,
        .0.infeasibility
    )]
    NotReached(Box<Unfinished>),
    /// A fixed container given both by the scene and by a packing to resume from, of
    /// different sizes.
    #[error(
        "cannot resume: the packing's container ({found:?}) is not the scene's fixed container \
         ({expected:?})"
    )]
    FixedSizeMismatch {
        /// The size of the packing's container.
        found: Vec<f64>,
        /// The size the scene gives.
        expected: Vec<f64>,
    },
    /// A time limit that is not a positive number of seconds a clock can count to.
    #[error(
        "the time limit must be a number of seconds from 1e-9 (a nanosecond) to {max:.3e} \
         (about 585 billion years), not {seconds:e}",
        max = Duration::MAX.as_secs_f64()
    )]
    TimeLimit {
        /// The seconds given.
        seconds: f64,
    },

    // Output folders and merging.
    /// A file-system operation failed.
    #[error("{path}: cannot {action}: {source}")]
    Folder {
        /// The file or folder.
        path: PathBuf,
        /// What was being done.
        action: &'static str,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// The user's files in the output folder are not carried into the staging folder: too
    /// many, on another file system, or too large to copy.
    #[error("{path}: the user's files are not carried over: {reason}")]
    Carry {
        /// The folder or file.
        path: PathBuf,
        /// Why.
        reason: &'static str,
    },
    /// No input folder was given.
    #[error("nothing to merge: give at least one packing folder")]
    NoInputs,
    /// An input (or the output folder's packing) could not be read.
    #[error("{folder}: {source}")]
    Unreadable {
        /// The folder.
        folder: PathBuf,
        /// What was wrong with its files.
        #[source]
        source: Box<Error>,
    },
    /// An input could not be verified (its items do not form a valid model).
    #[error("{folder}: cannot verify: {source}")]
    Unverifiable {
        /// The folder.
        folder: PathBuf,
        /// Why.
        #[source]
        source: Box<Error>,
    },
    /// Two folders hold packings of different scenes.
    #[error("{other} is not a packing of the same scene as {first}: {difference}")]
    DifferentScenes {
        /// The first input.
        first: PathBuf,
        /// The folder that differs.
        other: PathBuf,
        /// How they differ.
        difference: String,
    },
    /// No input is a certified packing.
    #[error(
        "none of the {inputs} packings read is certified ({skipped} folders held no packing): \
         nothing to keep"
    )]
    NoneCertified {
        /// How many inputs were read.
        inputs: usize,
        /// How many folders held no packing.csv.
        skipped: usize,
    },
    /// A file of the best packing could not be copied into the output folder.
    #[error("cannot copy {path}: {source}")]
    NotCopied {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },

    // Exports and pictures.
    /// A format name that is not one of [`Format::ALL`](crate::export::Format::ALL).
    #[error("`{name}` is not a file format; the formats are lammps, gsd, xyz, obj")]
    UnknownFormat {
        /// The name given.
        name: String,
    },
    /// The folder to convert does not exist or is not a folder.
    #[error("{}: not a packing folder: {reason}", path.display())]
    NotAFolder {
        /// The path given.
        path: PathBuf,
        /// What it is instead.
        reason: String,
    },
    /// The folder holds the least overlapping configuration of a fixed container's run that
    /// did not reach its packing fraction, not a packing.
    #[error(
        "{}: the least overlapping configuration of an unfinished run ({overlapping_pairs} \
         overlapping pairs, {outside} items outside), not a packing: a simulation started from \
         its files would start from overlapping items; pass --unfinished to write them anyway",
        path.display()
    )]
    UnfinishedFolder {
        /// The folder.
        path: PathBuf,
        /// Its overlapping pairs.
        overlapping_pairs: u64,
        /// Its items outside the container.
        outside: u64,
    },
    /// plotters failed while drawing.
    #[error("{path}: drawing failed: {message}")]
    Draw {
        /// The picture.
        path: PathBuf,
        /// What plotters said.
        message: String,
    },
    /// The embedded font was rejected (a broken build, not user data).
    #[error("the embedded font could not be loaded")]
    Font,
    /// The caller asked to stop before the pictures were drawn (the run's time limit or a
    /// signal).
    #[error("the pictures were not drawn: the run was stopped or its time limit reached")]
    Stopped,
}
