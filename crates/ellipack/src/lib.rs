//! The parts of the `ellipack` command that a person touches — file formats, error messages,
//! atomic output — as a library, so that `cargo xtask` and tests reuse them.
#![deny(missing_docs)]
#![cfg_attr(not(test), warn(clippy::unwrap_used))]

pub mod error;
pub mod folder;
pub mod instances;
pub mod measure;
pub mod output;
pub mod pack;
pub mod packing;
pub mod pairs;
pub mod render;
pub mod scene;
pub mod table;
pub mod terminal;

pub use error::Error;

/// The example pairs bundled with the program (`crates/ellipack/data/pairs.csv`): what
/// `ellipack contact` evaluates when no `--input` is given.
pub const EXAMPLE_PAIRS: &str = include_str!("../data/pairs.csv");
