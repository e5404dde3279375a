//! The crate's single error type.

use std::fmt;

/// Everything that can go wrong when user data enters the crate.
///
/// Every message names the offending item (which ellipsoid, which semi-axis or variable, which
/// value) so that a caller can point a person at it.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A centre coordinate is NaN, infinite or beyond ±1e30.
    NonFiniteCentre {
        /// Index of the ellipsoid, when known (`None` for a lone shape).
        item: Option<usize>,
        /// Which coordinate (0 = x, 1 = y, 2 = z).
        axis: usize,
        /// The offending value.
        value: f64,
    },
    /// A semi-axis is outside [1e-30, 1e30] (zero, negative, NaN, infinite, absurdly small or large).
    InvalidSemiAxis {
        /// Index of the ellipsoid, when known.
        item: Option<usize>,
        /// Which semi-axis (the column of the rotation it lies along).
        axis: usize,
        /// The offending value.
        value: f64,
    },
    /// A rotation angle is NaN or infinite.
    NonFiniteAngle {
        /// Index of the ellipsoid, when known.
        item: Option<usize>,
        /// Which angle (2D: 0 = θ; 3D: 0 = φ, 1 = θ, 2 = ψ of eq. 2).
        angle: usize,
        /// The offending value.
        value: f64,
    },
    /// A quaternion is zero, not finite, or too far from unit length to be a rotation.
    InvalidQuaternion {
        /// Index of the ellipsoid, when known.
        item: Option<usize>,
        /// The quaternion as given, (w, x, y, z).
        quaternion: [f64; 4],
        /// Its squared norm w² + x² + y² + z².
        norm2: f64,
    },
    /// A container dimension (radius, semi-axis, half-side) is zero, negative or not finite.
    InvalidContainer {
        /// Which dimension of the container.
        dimension: usize,
        /// The offending value.
        value: f64,
    },
    /// A variable of the whole model is NaN or infinite (or a centre coordinate beyond ±1e30).
    NonFiniteVariable {
        /// Index in the variable vector.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A slice has the wrong length for the problem.
    LengthMismatch {
        /// What the slice holds.
        what: &'static str,
        /// Length expected.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A pair names an item (ellipse or ellipsoid) that is not there.
    PairIndex {
        /// Position of the pair in the list.
        pair: usize,
        /// The pair's indices.
        indices: (usize, usize),
        /// How many ellipsoids there are.
        len: usize,
    },
    /// The problem has no item.
    Empty,
    /// A periodic cell so thin for its items that one pair term would reach more images than
    /// the workspace allows.
    PeriodicImages {
        /// The most points (items and images) allowed.
        points: usize,
        /// The cell's smallest width across its lattice planes.
        width: f64,
        /// The distance from the cell within which images are needed.
        reach: f64,
    },
    /// A periodic cell far smaller than its items (typically given in other units): their
    /// enclosing balls cover it `cover` times over, so that about `pairs` pairs of images would
    /// be checked, more than `limit`.
    CellCrowded {
        /// `Σ |B(r_i)| / |det H|`.
        cover: f64,
        /// The estimated number of close pairs of images.
        pairs: f64,
        /// The most pairs allowed.
        limit: usize,
    },
    /// A fractional coordinate of an item in a periodic cell so large that its lattice
    /// translation is not an `i32` (beyond ±2³⁰ cells).
    FractionalOutOfRange {
        /// Index in the variable vector.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// An item of a periodic cell so far from it that its lattice translation is not an `i32`
    /// (beyond ±2³⁰ cells), named by the item and the cell edge.
    ItemFarFromCell {
        /// The item.
        item: usize,
        /// The cell edge (0 = a, 1 = b, 2 = c) along which it is far.
        edge: usize,
        /// Its fractional coordinate along that edge.
        value: f64,
    },
    /// The neighbour grid rejected the input.
    Grid(cell_grid::Error),
    /// The threads asked for the model's evaluations could not be started (the error is
    /// `Clone`, so rayon's reason is kept as its message).
    ThreadPool {
        /// Threads asked for.
        threads: usize,
        /// Rayon's message.
        reason: String,
    },
    /// The PW85 contact function rejected a pair during certification.
    Certification {
        /// The pair `(i, j)`.
        pair: (usize, usize),
        /// PW85's refusal.
        source: pw85::Error,
    },
}

impl Error {
    /// The same error naming `item` where it names an item and did not know which.
    pub fn for_item(self, item: usize) -> Self {
        match self {
            Error::NonFiniteCentre { axis, value, .. } => Error::NonFiniteCentre {
                item: Some(item),
                axis,
                value,
            },
            Error::InvalidSemiAxis { axis, value, .. } => Error::InvalidSemiAxis {
                item: Some(item),
                axis,
                value,
            },
            Error::NonFiniteAngle { angle, value, .. } => Error::NonFiniteAngle {
                item: Some(item),
                angle,
                value,
            },
            Error::InvalidQuaternion {
                quaternion, norm2, ..
            } => Error::InvalidQuaternion {
                item: Some(item),
                quaternion,
                norm2,
            },
            other => other,
        }
    }

    /// `Ok` when a slice of `what` has the `expected` length, the `LengthMismatch` otherwise.
    pub(crate) fn check_length(
        what: &'static str,
        expected: usize,
        found: usize,
    ) -> Result<(), Error> {
        if found == expected {
            Ok(())
        } else {
            Err(Error::LengthMismatch {
                what,
                expected,
                found,
            })
        }
    }
}

/// "item i: " (an ellipse or an ellipsoid: the messages serve both dimensions).
fn item_prefix(f: &mut fmt::Formatter<'_>, item: Option<usize>) -> fmt::Result {
    match item {
        Some(i) => write!(f, "item {i}: "),
        None => Ok(()),
    }
}

/// A value as a person reads it in a message: `1e300`, not its 301 digits; at most six
/// significant digits (the value itself is in the error's fields).
fn short(x: f64) -> String {
    let trim = |s: String| match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        None if s.contains('.') => s.trim_end_matches('0').trim_end_matches('.').to_string(),
        _ => s,
    };
    if !x.is_finite() || x == 0.0 {
        format!("{x}")
    } else if x.abs() >= 1e6 || x.abs() < 1e-4 {
        trim(format!("{x:.5e}"))
    } else {
        trim(format!("{x:.6}"))
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::NonFiniteCentre { item, axis, value } => {
                item_prefix(f, item)?;
                write!(
                    f,
                    "centre coordinate {axis} is {}; coordinates must be finite, |x| <= 1e30",
                    short(value)
                )
            }
            Error::InvalidSemiAxis { item, axis, value } => {
                item_prefix(f, item)?;
                write!(
                    f,
                    "semi-axis {axis} is {}; semi-axes must lie in [1e-30, 1e30]",
                    short(value)
                )
            }
            Error::NonFiniteAngle { item, angle, value } => {
                item_prefix(f, item)?;
                write!(
                    f,
                    "rotation angle {angle} is {}, not a finite number",
                    short(value)
                )
            }
            Error::InvalidQuaternion {
                item,
                quaternion,
                norm2,
            } => {
                item_prefix(f, item)?;
                let [w, x, y, z] = quaternion.map(short);
                write!(
                    f,
                    "quaternion (w, x, y, z) = ({w}, {x}, {y}, {z}) has squared norm {}; \
                     a rotation needs a finite unit quaternion (|q|² within 1e-6 of 1)",
                    short(norm2)
                )
            }
            Error::InvalidContainer { dimension, value } => write!(
                f,
                "container dimension {dimension} is {}; it must be finite and positive",
                short(value)
            ),
            Error::NonFiniteVariable { index, value } => {
                write!(
                    f,
                    "variable {index} is {}; variables must be finite \
                     (centre coordinates within ±1e30)",
                    short(value)
                )
            }
            Error::LengthMismatch {
                what,
                expected,
                found,
            } => {
                write!(f, "{what}: expected {expected} values, found {found}")
            }
            Error::PairIndex {
                pair,
                indices: (i, j),
                len,
            } => write!(
                f,
                "pair {pair} is ({i}, {j}), but there are only {len} items"
            ),
            Error::Empty => write!(f, "the problem has no item"),
            Error::PeriodicImages {
                points,
                width,
                reach,
            } => write!(
                f,
                "periodic cell of width {} is too thin for items that reach {} beyond it: \
                 more than {points} images would be needed",
                short(width),
                short(reach)
            ),
            Error::CellCrowded {
                cover,
                pairs,
                limit,
            } => write!(
                f,
                "the periodic cell is far smaller than its items: their enclosing balls cover it \
                 {} times over, so about {} pairs of images would be checked (at most {limit}); \
                 is the cell given in the items' units?",
                short(cover),
                short(pairs.round())
            ),
            Error::FractionalOutOfRange { index, value } => write!(
                f,
                "variable {index} is the fractional coordinate {}; items of a periodic cell \
                 must lie within 2^30 cells of it",
                short(value)
            ),
            Error::ItemFarFromCell { item, edge, value } => write!(
                f,
                "item {item}'s fractional coordinate along the cell edge {} is {}; items of a \
                 periodic cell must lie within 2^30 cells of it",
                ["a", "b", "c"][edge.min(2)],
                short(value)
            ),
            Error::Grid(ref e) => write!(f, "neighbour grid: {e}"),
            Error::ThreadPool {
                threads,
                ref reason,
            } => write!(f, "could not start {threads} threads: {reason}"),
            Error::Certification {
                pair: (i, j),
                ref source,
            } => {
                write!(f, "certification of items {i} and {j}: {source}")
            }
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Grid(e) => Some(e),
            Error::Certification { source, .. } => Some(source),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_items_and_write_numbers_short() {
        let e = Error::NonFiniteCentre {
            item: Some(3),
            axis: 1,
            value: -1e300,
        };
        assert_eq!(
            e.to_string(),
            "item 3: centre coordinate 1 is -1e300; coordinates must be finite, |x| <= 1e30"
        );
        let e = Error::InvalidSemiAxis {
            item: None,
            axis: 0,
            value: 1.234_567_89e-40,
        };
        assert!(
            e.to_string().starts_with("semi-axis 0 is 1.23457e-40;"),
            "{e}"
        );
        assert_eq!(short(0.5), "0.5");
        assert_eq!(short(f64::NAN), "NaN");
        assert_eq!(short(2.0), "2");
    }
}
