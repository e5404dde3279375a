//! The crate's error type.

/// Why a packing's structure could not be measured.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No items.
    #[error("the packing has no items")]
    Empty,
    /// A setting out of range (the message says which).
    #[error("{0}")]
    Settings(String),
    /// The neighbour grid refused the centres.
    #[error("neighbour grid: {0}")]
    Grid(#[from] cell_grid::Error),
    /// PW85 refused a pair (`i`, `j`) while looking for contacts.
    #[error("items {} and {}: {source}", .pair.0, .pair.1)]
    Contact {
        /// The items (0-based).
        pair: (usize, usize),
        /// PW85's reason.
        #[source]
        source: implicit_packing::Error,
    },
}
