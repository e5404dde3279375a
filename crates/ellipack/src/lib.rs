//! The parts of the `ellipack` command that a person touches — file formats, error messages,
//! atomic output — as a library, so that `cargo xtask` and tests reuse them.
//!
//! # Features
//! * `cli` (default): the `ellipack` program. It brings clap, indicatif and ctrlc, which a
//!   library user does not need: depend on `ellipack` with `default-features = false`.
//! * `pictures` (default, implied by `cli`): the `render` module, which draws packing.svg
//!   and packing.png with plotters. Without it the module is absent; the file names stay in
//!   [`folder`].
#![deny(missing_docs)]
#![cfg_attr(not(test), warn(clippy::unwrap_used))]

pub mod analysis;
pub mod atoms;
pub mod error;
pub mod export;
pub mod folder;
pub mod gsd;
pub mod instances;
pub mod items_csv;
pub mod lammps;
pub mod measure;
pub mod merge;
pub mod obj;
mod output;
pub mod pack;
pub mod packing;
pub mod pairs;
#[cfg(feature = "pictures")]
pub mod render;
pub mod scene;
mod scene_table;
#[cfg(feature = "pictures")]
pub mod structure_plots;
pub mod summary_json;
pub mod table;
mod toml_keys;
pub mod xyz;

pub use error::Error;
pub use output::{OutputFile, refuse_overwriting_input, write_atomically};

/// The example pairs bundled with the program (`crates/ellipack/data/pairs.csv`): what
/// `ellipack contact` evaluates when no `--input` is given.
pub const EXAMPLE_PAIRS: &str = include_str!("../data/pairs.csv");
