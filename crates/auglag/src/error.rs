//! The crate's error type: everything that makes a run impossible before it starts.
//!
//! Trouble met *during* a run (a NaN at a trial point that backtracking cannot avoid, a limit,
//! an interrupt) is not an error: the run stops with a [`StopReason`](crate::StopReason) and
//! still returns the best point it has.

use std::fmt;

/// Which user function produced a value that is not finite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Evaluation {
    /// The objective value f(x).
    Objective,
    /// A component of the objective gradient ∇f(x).
    ObjectiveGradient,
    /// Constraint number `index` (equalities first, then inequalities).
    Constraint {
        /// Position in the constraint vector `[h(x); g(x)]`.
        index: usize,
    },
    /// A component of Jᵀw, the constraints' contribution to the gradient.
    ConstraintGradient,
    /// The fused [`Problem::lagrangian`](crate::Problem::lagrangian) hook,
    /// or a penalty term that overflowed although every part was finite.
    AugmentedLagrangian,
}

impl fmt::Display for Evaluation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Objective => write!(f, "the objective"),
            Self::ObjectiveGradient => write!(f, "the objective gradient"),
            Self::Constraint { index } => write!(f, "constraint {index}"),
            Self::ConstraintGradient => write!(f, "the constraint Jacobian-transpose product"),
            Self::AugmentedLagrangian => write!(f, "the augmented Lagrangian"),
        }
    }
}

/// Why a run could not start.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A slice has the wrong length.
    DimensionMismatch {
        /// Which slice.
        what: &'static str,
        /// The length the problem's dimensions require.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// Variable `index` has `lower > upper`, or a bound is NaN.
    InvalidBounds {
        /// Variable index.
        index: usize,
        /// Its lower bound.
        lower: f64,
        /// Its upper bound.
        upper: f64,
    },
    /// The starting point has a NaN or infinite component.
    NonFiniteStart {
        /// Variable index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A user function returned NaN or ±∞ at the (projected) starting point, where no
    /// backtracking can help.
    NonFiniteAtStart {
        /// Which function.
        what: Evaluation,
    },
    /// An option is outside its valid range.
    InvalidOption {
        /// Field name in [`Options`](crate::Options).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::DimensionMismatch {
                what,
                expected,
                found,
            } => write!(f, "{what} has length {found}, expected {expected}"),
            Self::InvalidBounds {
                index,
                lower,
                upper,
            } => write!(
                f,
                "variable {index} has invalid bounds: lower = {lower}, upper = {upper} \
                 (need lower <= upper, neither NaN)"
            ),
            Self::NonFiniteStart { index, value } => {
                write!(
                    f,
                    "starting point component {index} is not finite ({value})"
                )
            }
            Self::NonFiniteAtStart { what } => {
                write!(f, "{what} is not finite at the projected starting point")
            }
            Self::InvalidOption {
                name,
                value,
                requirement,
            } => write!(f, "option `{name}` = {value} is invalid: {requirement}"),
        }
    }
}

impl std::error::Error for Error {}
