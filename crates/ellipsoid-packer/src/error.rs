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
    /// A container (of the goal, or of the packing to resume from) of another shape than the
    /// problem's.
    #[error("a container of shape {found:?} where the problem's is {expected:?}")]
    ContainerShape {
        /// The shape given.
        found: implicit_packing::ContainerShape,
        /// The problem's shape.
        expected: implicit_packing::ContainerShape,
    },
    /// A packing to resume from with another number of items than the problem.
    #[error("cannot resume: the packing has {found} items, the problem {expected}")]
    ResumeItems {
        /// Items of the packing.
        found: usize,
        /// Items of the problem.
        expected: usize,
    },
    /// An item of the packing to resume from with other semi-axes than the problem's.
    #[error(
        "cannot resume: item {item} has semi-axes {found:?} in the packing, {expected:?} in the problem"
    )]
    ResumeSemiAxes {
        /// The item (0-based).
        item: usize,
        /// Its semi-axes in the packing.
        found: Vec<f64>,
        /// Its semi-axes in the problem.
        expected: Vec<f64>,
    },
    /// A packing to resume from whose container is not the problem's fixed container.
    #[error(
        "cannot resume: the packing's container ({found:?}) is not the fixed container \
         ({expected:?})"
    )]
    ResumeFixedSize {
        /// The dimensions of the packing's container.
        found: Vec<f64>,
        /// The fixed container's dimensions.
        expected: Vec<f64>,
    },
    /// The packing to resume from is not a certified packing.
    #[error("cannot resume: the packing to resume from is not certified: {0}")]
    StartNotCertified(Box<StartDefects>),
    /// A thread of the run panicked (a bug: please report it with the scene).
    #[error("a start of the multi-start panicked")]
    StartPanicked,
}

/// What makes a packing to resume from uncertified: the items that overlap and those that
/// stick out (0-based, in the problem's order).
#[derive(Clone, Debug, PartialEq)]
pub struct StartDefects {
    /// Overlapping pairs `(i, j, μ²)` (μ² < 1).
    pub overlapping: Vec<(usize, usize, f64)>,
    /// Items outside the container, each with the factor by which the container would have
    /// to grow about its centre to hold it.
    pub outside: Vec<(usize, f64)>,
}

impl StartDefects {
    /// The overlapping pairs and the items outside of a certificate.
    pub fn of(certificate: &implicit_packing::Certificate) -> Self {
        StartDefects {
            overlapping: certificate
                .overlapping
                .iter()
                .map(|o| (o.items.0, o.items.1, o.mu2))
                .collect(),
            outside: certificate
                .outside
                .iter()
                .map(|o| (o.item, o.scale))
                .collect(),
        }
    }
}

/// How many overlapping pairs and items outside a message lists before it says "and n more".
const LISTED: usize = 8;

impl std::fmt::Display for StartDefects {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use implicit_packing::certificate::shown_mu2;
        let mut parts = Vec::new();
        if !self.overlapping.is_empty() {
            let list = listed(&self.overlapping, |&(i, j, m)| {
                format!("{i} and {j} (μ² = {})", shown_mu2(m, 6))
            });
            let n = self.overlapping.len();
            parts.push(format!("{n} overlapping pairs: items {list}"));
        }
        if !self.outside.is_empty() {
            let list = listed(&self.outside, |&(i, s)| {
                format!("{i} (the container would have to grow by {:.3e})", s - 1.0)
            });
            let n = self.outside.len();
            parts.push(format!("{n} items outside the container: {list}"));
        }
        write!(f, "{}", parts.join("; "))
    }
}

/// The first [`LISTED`] of `items`, shown by `show` and separated by commas, and how many more
/// there are.
fn listed<T>(items: &[T], show: impl Fn(&T) -> String) -> String {
    let mut list: Vec<String> = items.iter().take(LISTED).map(show).collect();
    if items.len() > LISTED {
        list.push(format!("and {} more", items.len() - LISTED));
    }
    list.join(", ")
}
