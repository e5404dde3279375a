//! The crate's error type.

/// Why a packing run could not give a certified packing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The model refused the items, the container or a point (see its message).
    #[error(transparent)]
    Model(#[from] implicit_packing::Error),
    /// The augmented-Lagrangian solver refused the problem.
    #[error("solver: {0}")]
    Solver(#[from] auglag::Error),
    /// The solver's point could not be certified by any repair whose factor (the container's
    /// linear scale) is at most `max_dilation`: an item far outside the container.
    #[error(
        "the solver's point cannot be certified by a dilation up to {max_dilation}: \
         {overlapping} overlapping pairs, {outside} items outside the container"
    )]
    NotCertifiable {
        /// The largest dilation tried.
        max_dilation: f64,
        /// Overlapping pairs at that dilation.
        overlapping: usize,
        /// Items outside the container at that dilation.
        outside: usize,
    },
    /// The run was stopped before its first local minimisation, and its start is not a
    /// certified packing: nothing certified exists to return.
    #[error(
        "stopped before the first local minimisation, and the start is not a certified packing"
    )]
    StoppedBeforeStart,
    /// A shard number that is not below the number of shards.
    #[error("shard {index} of {count} does not exist: shards are numbered 0 to count − 1")]
    Shard {
        /// The shard asked for.
        index: usize,
        /// The number of shards.
        count: usize,
    },
    /// A fixed-container run ([`crate::fixed`]) ended without a certified packing; the least
    /// infeasible point it reached comes with the error.
    #[error(
        "no packing found at packing fraction {:.6} in {:.1} s ({} local minimisations): the \
         least overlapping configuration has {} overlapping pairs and {} items outside the \
         container (model overlap {:.3e}{})",
        .0.density,
        .0.wall_time.as_secs_f64(),
        .0.local_minimisations,
        .0.certificate.overlapping.len(),
        .0.certificate.outside.len(),
        .0.infeasibility,
        .0.certificate.min_mu2.map_or(String::new(), |m| format!(", smallest μ² {}", implicit_packing::certificate::shown_mu2(m, 6)))
    )]
    NotReached(Box<crate::fixed::Unfinished>),
    /// The random start ([`crate::random::sequential_addition`]) found no place for an item:
    /// the container is too small for the items (or the start fraction too high).
    #[error(
        "the random start found no place for item {item} in {attempts} attempts, after \
         placing {placed} items: the container is too small for the items"
    )]
    RandomStart {
        /// The item (0-based, in the problem's order) that found no place.
        item: usize,
        /// Items placed before it.
        placed: usize,
        /// Attempts made for it.
        attempts: usize,
    },
    /// A size or aspect distribution gave no draw within its bounds
    /// ([`crate::random::MAX_REJECTIONS`] draws in a row).
    #[error(
        "shape group {group}: its distribution gave no value within its bounds in {} draws",
        crate::random::MAX_REJECTIONS
    )]
    Distribution {
        /// The group (0-based).
        group: u64,
    },
    /// A thread of the run panicked (a bug: please report it with the scene).
    #[error("a start of the multi-start panicked")]
    StartPanicked,
}
