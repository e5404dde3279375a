//! # pw85 — the Perram–Wertheim contact function, exact and fast
//!
//! The contact function μ²(r12, Q1, Q2) of two ellipsoids {m : (m − cᵢ)ᵀ Qᵢ⁻¹ (m − cᵢ) ≤ 1}
//! is the square of the common factor by which both must be scaled about their centres to
//! become externally tangent: μ² < 1 means they overlap, μ² = 1 that they touch, μ² > 1 that
//! they are apart. It is
//!
//! ```text
//! μ² = max over 0 ≤ λ ≤ 1 of f(λ),   f(λ) = λ (1 − λ) r12ᵀ Q(λ)⁻¹ r12,   Q(λ) = (1 − λ) Q1 + λ Q2,
//! ```
//!
//! with r12 = c2 − c1 (eqs. 6, 10, 11 of the theory chapter of the PW85 library, whose storage
//! and entry points this crate keeps: a symmetric matrix is `[f64; 6]` = Q11, Q12, Q13, Q22,
//! Q23, Q33).
//!
//! - [`contact_function`] — μ² and its maximiser λ₀, to a relative error of about 1e-15 on
//!   ordinary pairs and below 1e-13 on needles (aspect ratio 1e4), pancakes, size ratios of 1e8
//!   and pairs within 1e-13 of tangency; [`contact_details`] adds the contact point, the common
//!   normal and the gradient of μ².
//! - [`overlap`] — the verdict alone, stopping as soon as it is certain.
//! - The same two calls on ellipses: `r12: [f64; 2]` and forms `[f64; 3]` (Q11, Q12, Q22).
//!   The form's type ([`QuadraticForm`]: the bare arrays, or the checked [`Form3`] and
//!   [`Form2`]) decides the dimension.
//! - [`batch`] — slices of pairs of either dimension, four at a time, on one thread or on all
//!   cores (`Parallelism`; feature `rayon`).
//! - [`shape`] — quadratic forms from semi-axes and a rotation (quaternion, matrix, the angles
//!   of Birgin–Lobato–Martínez eq. 2) or a spheroid's axis.
//! - `interop` (feature `nalgebra`) — conversions from and to nalgebra matrices.
//! - `sym`, `poly`, `baseline` (feature `internals`, outside the semver promise) — the
//!   building blocks (determinant, adjugate, the polynomials a, b, c of eqs. 16–20) and the
//!   straightforward solvers (bisection on c(λ) as in PW85, Brent on f, Newton on f′) that the
//!   validation compares against.
//!
//! ```
//! use pw85::{contact_function, overlap, shape::from_axes_quaternion};
//!
//! // Two of the packing paper's ellipsoids (1, 0.75, 0.5), one turned 90° about z.
//! let q1 = from_axes_quaternion(&[1.0, 0.75, 0.5], &[1.0, 0.0, 0.0, 0.0])?;
//! let s = std::f64::consts::FRAC_1_SQRT_2;
//! let q2 = from_axes_quaternion(&[1.0, 0.75, 0.5], &[s, 0.0, 0.0, s])?;
//! let r12 = [1.6, 0.3, 0.1];
//! let c = contact_function(&r12, &q1, &q2)?;
//! assert_eq!(overlap(&r12, &q1, &q2)?, c.mu2 < 1.0);
//! # Ok::<(), pw85::Error>(())
//! ```
//!
//! # References
//! - J. W. Perram and M. S. Wertheim, "Statistical mechanics of hard ellipsoids. I. Overlap
//!   algorithm and the contact function", J. Comput. Phys. 58 (1985) 409–416.
//! - S. Brisard, the PW85 library and its theory chapter (`pw85-theory.rst`), whose equation
//!   numbers the documentation cites.
#![deny(missing_docs)]
#![cfg_attr(not(test), warn(clippy::unwrap_used))]

mod arith;
#[cfg(feature = "internals")]
pub mod baseline;
#[cfg(not(feature = "internals"))]
#[allow(dead_code)]
mod baseline;
pub mod batch;
mod contact;
mod error;
mod extreme;
mod form;
#[cfg(feature = "nalgebra")]
pub mod interop;
mod lanes;
mod overlap;
#[cfg(feature = "internals")]
pub mod poly;
#[cfg(not(feature = "internals"))]
#[allow(dead_code)]
mod poly;
pub mod shape;
#[cfg(feature = "internals")]
pub mod sym;
#[cfg(not(feature = "internals"))]
#[allow(dead_code)]
mod sym;

pub use contact::{
    Contact, ContactDetails, REFINE_ABOVE, contact_details, contact_function_refined, objective,
};
pub use error::{Argument, Error};
pub use form::{Form2, Form3, QuadraticForm, contact_function, overlap};
pub use shape::spheroid;
pub use sym::{Sym2, Sym3};

/// The README's example, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
