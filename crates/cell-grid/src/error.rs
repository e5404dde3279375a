//! The crate's single error type.

use std::fmt;

/// Everything that can be wrong with the input of a [`Grid`](crate::Grid).
///
/// Each variant names the offending item (point index, axis, value) so that a caller can
/// point at the bad entry of its own data.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// The grid supports dimensions 1, 2 and 3 only (the stencil has `3^D` cells).
    UnsupportedDimension {
        /// The requested dimension `D`.
        dim: usize,
    },
    /// The global cutoff is not a finite positive number whose square is a normal `f64`
    /// (roughly `1.5e-154 ..= 1.3e154`; distances are compared squared).
    InvalidCutoff {
        /// The value given.
        value: f64,
    },
    /// A per-item radius `r` is not positive, or `(2r)^2` is not a normal `f64`.
    InvalidRadius {
        /// Index of the item.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// The radius of a point query is negative, NaN or infinite.
    InvalidQueryRadius {
        /// The value given.
        value: f64,
    },
    /// The per-item radii and the points have different lengths.
    RadiiCountMismatch {
        /// Number of radii.
        radii: usize,
        /// Number of points.
        points: usize,
    },
    /// A slice of points does not have the length of the grid's last build.
    PointCountMismatch {
        /// Number of points the grid was built with.
        expected: usize,
        /// Number of points given.
        found: usize,
    },
    /// A point coordinate is NaN or infinite.
    NonFiniteCoordinate {
        /// Index of the point.
        index: usize,
        /// Axis of the coordinate (0 = x).
        axis: usize,
        /// The value found.
        value: f64,
    },
    /// A query point has a NaN or infinite coordinate.
    NonFiniteQueryPoint {
        /// Axis of the coordinate (0 = x).
        axis: usize,
        /// The value found.
        value: f64,
    },
    /// The domain is not a finite box with `lo <= hi` (`lo < hi` on periodic axes).
    InvalidDomain {
        /// Axis of the bad bounds.
        axis: usize,
        /// Lower bound given.
        lo: f64,
        /// Upper bound given.
        hi: f64,
    },
    /// A periodic axis was requested without a domain to define the box.
    PeriodicWithoutDomain {
        /// The periodic axis.
        axis: usize,
    },
    /// On a periodic axis the interaction reach exceeds half the box side, so the
    /// minimum-image convention would not give a unique partner.
    CutoffTooLargeForBox {
        /// The periodic axis.
        axis: usize,
        /// The cutoff, or twice the largest radius.
        reach: f64,
        /// The box side along `axis`.
        box_length: f64,
    },
    /// More items than the grid can number: item indices and cell slots are stored as `u32`
    /// (half the memory traffic of `usize` in the sort), so a grid holds fewer than
    /// `u32::MAX` items.
    TooManyItems {
        /// Number of items given.
        count: usize,
        /// The largest number accepted.
        max: usize,
    },
    /// The skin of a [`PairList`](crate::PairList) is negative, NaN or infinite, or so large
    /// that the enlarged reach has no normal `f64` square.
    InvalidSkin {
        /// The value given.
        value: f64,
    },
    /// An item index is not below the number of items.
    ItemOutOfRange {
        /// The index given.
        index: usize,
        /// Number of items in the grid.
        len: usize,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::UnsupportedDimension { dim } => {
                write!(f, "dimension {dim} is not supported (only 1, 2 and 3)")
            }
            Error::InvalidCutoff { value } => {
                write!(
                    f,
                    "cutoff {value} is not a positive number with a normal f64 square"
                )
            }
            Error::InvalidRadius { index, value } => {
                write!(
                    f,
                    "radius of item {index} is {value}, not a positive number with a normal f64 square"
                )
            }
            Error::InvalidQueryRadius { value } => {
                write!(
                    f,
                    "query radius {value} is not a finite non-negative number"
                )
            }
            Error::RadiiCountMismatch { radii, points } => {
                write!(f, "{radii} radii given for {points} points")
            }
            Error::PointCountMismatch { expected, found } => {
                write!(f, "{found} points given, the grid holds {expected}")
            }
            Error::NonFiniteCoordinate { index, axis, value } => {
                write!(f, "coordinate {axis} of point {index} is {value}")
            }
            Error::NonFiniteQueryPoint { axis, value } => {
                write!(f, "coordinate {axis} of the query point is {value}")
            }
            Error::InvalidDomain { axis, lo, hi } => {
                write!(
                    f,
                    "domain along axis {axis} is [{lo}, {hi}], not a finite interval"
                )
            }
            Error::PeriodicWithoutDomain { axis } => {
                write!(f, "axis {axis} is periodic but no domain (box) was given")
            }
            Error::CutoffTooLargeForBox {
                axis,
                reach,
                box_length,
            } => write!(
                f,
                "reach {reach} exceeds half the periodic box side {box_length} along axis {axis}"
            ),
            Error::TooManyItems { count, max } => {
                write!(f, "{count} items given, a grid holds at most {max}")
            }
            Error::InvalidSkin { value } => {
                write!(
                    f,
                    "skin {value} is not a finite non-negative number that keeps the reach's square normal"
                )
            }
            Error::ItemOutOfRange { index, len } => {
                write!(f, "item {index} does not exist, the grid holds {len} items")
            }
        }
    }
}

impl std::error::Error for Error {}
