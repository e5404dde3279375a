//! The test kit of the ellipack workspace (dev-only, never published).
//!
//! - [`Rng`]: the seeded SplitMix64 generator every test, bench and example draws from, with
//!   uniform numbers, unit quaternions and unit directions.
//! - [`shape`]: quadratic forms of ellipsoids and ellipses from semi-axes and a rotation, and
//!   random pairs, as plain arrays (the PW85 storage: upper triangle, row-major).
//! - [`table`]: a comma-separated table read by column name, with errors that name the file,
//!   the line and the column.
//! - [`reference`](mod@reference): the independent high-precision reference values in the repository's
//!   `validation/reference/`, as typed rows.
//!
//! The kit depends on the standard library only. It must not depend on pw85 or the other
//! crates of the workspace: a test that uses both the kit and pw85 would then see two copies of
//! pw85's types.

#![deny(missing_docs)]

pub mod reference;
mod rng;
pub mod shape;
pub mod table;

pub use rng::Rng;
