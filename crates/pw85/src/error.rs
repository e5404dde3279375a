//! The crate's error type.

use core::fmt;

/// Which argument of a query an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Argument {
    /// The centre-to-centre vector r12 = c2 − c1.
    R12,
    /// The quadratic form of the first ellipsoid.
    Q1,
    /// The quadratic form of the second ellipsoid.
    Q2,
    /// A semi-axis length given to a constructor.
    SemiAxis,
    /// A rotation (quaternion, matrix, angles or axis direction) given to a constructor.
    Rotation,
}

impl fmt::Display for Argument {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Argument::R12 => "r12",
            Argument::Q1 => "Q1",
            Argument::Q2 => "Q2",
            Argument::SemiAxis => "semi-axis",
            Argument::Rotation => "rotation",
        })
    }
}

/// Why a query or a constructor refused its input.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// An input entry is NaN or infinite.
    NonFinite {
        /// The argument holding it.
        argument: Argument,
        /// Its index in the argument's storage (for Q: 0..6 in the order Q11, Q12, Q13, Q22,
        /// Q23, Q33).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A quadratic form is not positive definite: its leading principal minor of the given
    /// order is not positive (Sylvester's criterion), decided in extended precision when the
    /// double-precision value is within its rounding error of zero.
    NotPositiveDefinite {
        /// Q1 or Q2.
        argument: Argument,
        /// Order of the first non-positive leading principal minor (1, 2 or 3).
        minor: usize,
        /// Its value.
        value: f64,
    },
    /// A full matrix given for symmetric storage is not symmetric (feature `nalgebra`).
    NotSymmetric {
        /// Which matrix.
        argument: Argument,
        /// Row of the first offending entry (0-based).
        row: usize,
        /// Its column.
        column: usize,
    },
    /// A semi-axis length is not a positive finite number.
    InvalidSemiAxis {
        /// Which semi-axis (0-based).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A rotation is not usable: a zero or non-finite quaternion or axis, or a matrix that is
    /// not orthogonal with determinant +1.
    InvalidRotation {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A λ outside [0, 1] given to [`crate::objective`].
    LambdaOutOfRange {
        /// The λ given.
        value: f64,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::NonFinite {
                argument,
                index,
                value,
            } => write!(f, "{argument}[{index}] is not finite ({value})"),
            Error::NotPositiveDefinite {
                argument,
                minor,
                value,
            } => write!(
                f,
                "{argument} is not positive definite: its leading principal minor of order \
                 {minor} is {value:e}, not > 0"
            ),
            Error::NotSymmetric {
                argument,
                row,
                column,
            } => write!(
                f,
                "{argument} is not symmetric: entries ({row}, {column}) and ({column}, {row}) differ"
            ),
            Error::InvalidSemiAxis { index, value } => write!(
                f,
                "semi-axis {index} must be a positive finite length, got {value:e}"
            ),
            Error::InvalidRotation { reason } => write!(f, "invalid rotation: {reason}"),
            Error::LambdaOutOfRange { value } => {
                write!(f, "λ must lie in [0, 1], got {value:e}")
            }
        }
    }
}

impl std::error::Error for Error {}
