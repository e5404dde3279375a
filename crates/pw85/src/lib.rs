//! The Perram–Wertheim contact function (placeholder while the crate is written).
#![deny(missing_docs)]
