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
    /// A pair names an ellipsoid that is not there.
    PairIndex {
        /// Position of the pair in the list.
        pair: usize,
        /// The pair's indices.
        indices: (usize, usize),
        /// How many ellipsoids there are.
        len: usize,
    },
    /// The problem has no ellipsoid.
    Empty,
    /// The neighbour grid rejected the input.
    Grid(String),
    /// The optimiser refused the problem, or a packing could not be repaired.
    Solver(String),
    /// The PW85 contact function rejected a pair during certification.
    Certification {
        /// The pair `(i, j)`.
        pair: (usize, usize),
        /// PW85's message.
        message: String,
    },
}

fn item_prefix(f: &mut fmt::Formatter<'_>, item: Option<usize>) -> fmt::Result {
    match item {
        Some(i) => write!(f, "ellipsoid {i}: "),
        None => Ok(()),
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::NonFiniteCentre { item, axis, value } => {
                item_prefix(f, item)?;
                write!(
                    f,
                    "centre coordinate {axis} is {value}; coordinates must be finite, |x| <= 1e30"
                )
            }
            Error::InvalidSemiAxis { item, axis, value } => {
                item_prefix(f, item)?;
                write!(
                    f,
                    "semi-axis {axis} is {value}; semi-axes must lie in [1e-30, 1e30]"
                )
            }
            Error::NonFiniteAngle { item, angle, value } => {
                item_prefix(f, item)?;
                write!(f, "rotation angle {angle} is {value}, not a finite number")
            }
            Error::InvalidQuaternion {
                item,
                quaternion,
                norm2,
            } => {
                item_prefix(f, item)?;
                let [w, x, y, z] = quaternion;
                write!(
                    f,
                    "quaternion (w, x, y, z) = ({w}, {x}, {y}, {z}) has squared norm {norm2}; \
                     a rotation needs a finite unit quaternion (|q|² within 1e-6 of 1)"
                )
            }
            Error::InvalidContainer { dimension, value } => write!(
                f,
                "container dimension {dimension} is {value}; it must be finite and positive"
            ),
            Error::NonFiniteVariable { index, value } => {
                write!(
                    f,
                    "variable {index} is {value}; variables must be finite \
                     (centre coordinates within ±1e30)"
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
                "pair {pair} is ({i}, {j}), but there are only {len} ellipsoids"
            ),
            Error::Empty => write!(f, "the problem has no ellipsoid"),
            Error::Grid(ref msg) => write!(f, "neighbour grid: {msg}"),
            Error::Solver(ref msg) => write!(f, "solver: {msg}"),
            Error::Certification {
                pair: (i, j),
                ref message,
            } => {
                write!(f, "certification of ellipsoids {i} and {j}: {message}")
            }
        }
    }
}

impl std::error::Error for Error {}
