//! Quadratic forms as typed values, and the one way the entry points tell ellipses from
//! ellipsoids.
//!
//! An ellipsoid {m : (m − c)ᵀ Q⁻¹ (m − c) ≤ 1} is given by its centre c and its quadratic form
//! Q, a symmetric positive-definite matrix stored as its upper triangle in row-major order
//! (theory eq. 3): `[f64; 6]` = Q11, Q12, Q13, Q22, Q23, Q33 in 3D, `[f64; 3]` = Q11, Q12,
//! Q22 in 2D. The entry points ([`crate::contact_function`], [`crate::overlap`]) take any
//! [`QuadraticForm`]: the bare arrays of the PW85 library, or [`Form3`] / [`Form2`], which
//! hold arrays already checked to be finite and positive definite. The form's type decides
//! the dimension, and with it the type of r12 (`[f64; 3]` or `[f64; 2]`).

use crate::contact::{Contact, check_finite};
use crate::error::{Argument, Error};
use crate::sym::{Sym2, Sym3};

/// A quadratic form the entry points accept: `[f64; 6]` or [`Form3`] for an ellipsoid,
/// `[f64; 3]` or [`Form2`] for an ellipse (and references to them).
///
/// Sealed: the dimension-specific kernels behind it are this crate's.
pub trait QuadraticForm: sealed::Sealed {
    /// 3 for ellipsoids, 2 for ellipses.
    const DIMENSION: usize;
    /// The type of r12 and of every point: `[f64; 3]` or `[f64; 2]`.
    type Vector;
    /// The upper triangle, row-major: `[f64; 6]` or `[f64; 3]`.
    type Entries;
    /// The stored entries.
    fn entries(&self) -> &Self::Entries;
}

pub(crate) mod sealed {
    use super::QuadraticForm;
    use crate::{Contact, Error};

    /// The type of r12 for the form `Q`.
    pub(super) type Vector<Q> = <Q as QuadraticForm>::Vector;

    /// The dimension's kernels, out of the public surface.
    pub trait Sealed {
        /// μ² and λ₀ (see [`crate::contact_function`]).
        fn contact(r12: &Vector<Self>, q1: &Self, q2: &Self) -> Result<Contact, Error>
        where
            Self: QuadraticForm;
        /// The verdict (see [`crate::overlap`]).
        fn overlap(r12: &Vector<Self>, q1: &Self, q2: &Self) -> Result<bool, Error>
        where
            Self: QuadraticForm;
    }
}

/// A bare array is its own entries.
#[inline(always)]
fn identity<T>(q: &T) -> &T {
    q
}

/// Implements [`QuadraticForm`] for a storage type, its kernels given as paths.
macro_rules! quadratic_form {
    ($ty:ty, $dim:literal, $vector:ty, $entries:ty, $as_entries:expr, $contact:path, $overlap:path) => {
        impl QuadraticForm for $ty {
            const DIMENSION: usize = $dim;
            type Vector = $vector;
            type Entries = $entries;
            #[inline(always)]
            fn entries(&self) -> &$entries {
                $as_entries(self)
            }
        }
        impl sealed::Sealed for $ty {
            #[inline(always)]
            fn contact(r12: &$vector, q1: &Self, q2: &Self) -> Result<Contact, Error> {
                $contact(r12, q1.entries(), q2.entries())
            }
            #[inline(always)]
            fn overlap(r12: &$vector, q1: &Self, q2: &Self) -> Result<bool, Error> {
                $overlap(r12, q1.entries(), q2.entries())
            }
        }
    };
}

quadratic_form!(
    Sym3,
    3,
    [f64; 3],
    Sym3,
    identity,
    crate::contact::contact_function_3d,
    crate::overlap::overlap_3d
);
quadratic_form!(
    Form3,
    3,
    [f64; 3],
    Sym3,
    Form3::entries,
    crate::contact::contact_function_3d,
    crate::overlap::overlap_3d
);
quadratic_form!(
    Sym2,
    2,
    [f64; 2],
    Sym2,
    identity,
    crate::contact::contact_function_2d,
    crate::overlap::overlap_2d
);
quadratic_form!(
    Form2,
    2,
    [f64; 2],
    Sym2,
    Form2::entries,
    crate::contact::contact_function_2d,
    crate::overlap::overlap_2d
);

impl<Q: QuadraticForm> QuadraticForm for &Q {
    const DIMENSION: usize = Q::DIMENSION;
    type Vector = Q::Vector;
    type Entries = Q::Entries;
    #[inline(always)]
    fn entries(&self) -> &Q::Entries {
        (**self).entries()
    }
}

impl<Q: QuadraticForm> sealed::Sealed for &Q {
    #[inline(always)]
    fn contact(r12: &sealed::Vector<Self>, q1: &Self, q2: &Self) -> Result<Contact, Error> {
        Q::contact(r12, q1, q2)
    }
    #[inline(always)]
    fn overlap(r12: &sealed::Vector<Self>, q1: &Self, q2: &Self) -> Result<bool, Error> {
        Q::overlap(r12, q1, q2)
    }
}

/// The quadratic form of an ellipsoid, checked: finite entries and positive definite.
///
/// Converts from `[f64; 6]` (Q11, Q12, Q13, Q22, Q23, Q33) with [`Form3::new`] or
/// `TryFrom`, and back with `From` or [`Form3::entries`]. The shape constructors of
/// [`crate::shape`] give arrays that pass the check.
///
/// ```
/// use pw85::{Form3, contact_function};
///
/// let ball = Form3::new([1.0, 0.0, 0.0, 1.0, 0.0, 1.0])?;
/// let c = contact_function(&[3.0, 0.0, 0.0], &ball, &ball)?;
/// assert!((c.mu2 - 2.25).abs() < 1e-15);
/// assert!(Form3::new([1.0, 2.0, 0.0, 1.0, 0.0, 1.0]).is_err()); // not positive definite
/// let entries: [f64; 6] = ball.into();
/// # Ok::<(), pw85::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Form3(Sym3);

/// The quadratic form of an ellipse, checked: finite entries and positive definite.
///
/// Converts from `[f64; 3]` (Q11, Q12, Q22) with [`Form2::new`] or `TryFrom`, and back with
/// `From` or [`Form2::entries`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Form2(Sym2);

/// `new`, `entries` and the conversions of a checked form type over its storage.
macro_rules! checked_form {
    ($form:ident, $entries:ty, $order:literal) => {
        impl $form {
            /// `entries` (
            #[doc = $order]
            /// ) as a form, once checked.
            ///
            /// # Errors
            /// [`Error::NonFinite`] for a NaN or infinite entry, [`Error::NotPositiveDefinite`]
            /// otherwise if the matrix is not positive definite (decided whatever the units);
            /// the error names the argument [`Argument::Q1`].
            pub fn new(entries: $entries) -> Result<Self, Error> {
                check_finite(Argument::Q1, &entries)?;
                crate::extreme::check_positive_definite_balanced(Argument::Q1, &entries)?;
                Ok(Self(entries))
            }

            /// The stored entries (
            #[doc = $order]
            /// ).
            pub fn entries(&self) -> &$entries {
                &self.0
            }
        }

        impl TryFrom<$entries> for $form {
            type Error = Error;
            fn try_from(entries: $entries) -> Result<Self, Error> {
                Self::new(entries)
            }
        }

        impl From<$form> for $entries {
            fn from(q: $form) -> $entries {
                q.0
            }
        }
    };
}

checked_form!(Form3, Sym3, "Q11, Q12, Q13, Q22, Q23, Q33");
checked_form!(Form2, Sym2, "Q11, Q12, Q22");

/// The contact function μ² of two ellipsoids and its maximiser λ₀ (theory eqs. 6, 13).
///
/// `r12 = c2 − c1`; `q1`, `q2` are the quadratic forms of the ellipsoids
/// {m : (m − cᵢ)ᵀ Qᵢ⁻¹ (m − cᵢ) ≤ 1}, stored as Q11, Q12, Q13, Q22, Q23, Q33. The ellipsoids
/// overlap iff μ² < 1. Centres that coincide give μ² = 0 (not an error).
///
/// # Errors
/// [`Error::NonFinite`] for a NaN or infinite entry, [`Error::NotPositiveDefinite`] when Q1 or
/// Q2 is not positive definite.
///
/// # Example
/// ```
/// // Two unit spheres whose centres are 3 apart: μ = 3 / (1 + 1).
/// let q = pw85::spheroid(1.0, 1.0, &[0.0, 0.0, 1.0])?;
/// let c = pw85::contact_function(&[3.0, 0.0, 0.0], &q, &q)?;
/// assert!((c.mu2 - 2.25).abs() < 1e-15);
/// assert!((c.lambda - 0.5).abs() < 1e-15);
/// # Ok::<(), pw85::Error>(())
/// ```
///
/// The same call on ellipses (`r12: [f64; 2]`, forms `[f64; 3]`) is the contact function
/// of two ellipses: the form's type ([`QuadraticForm`]) chooses the dimension.
#[inline]
pub fn contact_function<Q: QuadraticForm>(
    r12: &Q::Vector,
    q1: &Q,
    q2: &Q,
) -> Result<Contact, Error> {
    Q::contact(r12, q1, q2)
}

/// Whether two ellipsoids (or ellipses) overlap: μ²(r12, Q1, Q2) < 1 (theory eq. 6), with the arguments and
/// storage of [`crate::contact_function`]. Tangent ellipsoids (μ² = 1) do not overlap.
///
/// Stops as soon as the answer is certain: the projections on the centre line disjoint (no
/// overlap), the segment between the centres covered by the two ellipsoids' radial extents
/// (overlap), an iterate λ with f(λ) > 1 (no overlap, since f(λ) ≤ μ²), or
/// tangent lines of the concave f bounding max f below 1 (overlap), each with a margin for the
/// rounding error of f. Only pairs within that margin of tangency, or with a badly conditioned
/// pencil, pay for the full [`crate::contact_function`].
///
/// # Errors
/// As [`crate::contact_function`].
///
/// # Example
/// ```
/// let needle = pw85::spheroid(0.1, 1.0, &[1.0, 0.0, 0.0])?;
/// // Side by side, 0.15 apart across their thin direction: they overlap...
/// assert!(pw85::overlap(&[0.0, 0.15, 0.0], &needle, &needle)?);
/// // ...and 0.25 apart they do not.
/// assert!(!pw85::overlap(&[0.0, 0.25, 0.0], &needle, &needle)?);
/// # Ok::<(), pw85::Error>(())
/// ```
#[inline]
pub fn overlap<Q: QuadraticForm>(r12: &Q::Vector, q1: &Q, q2: &Q) -> Result<bool, Error> {
    Q::overlap(r12, q1, q2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typed_forms_and_arrays_give_the_same_bits() {
        let a = [2.0, 0.3, -0.1, 1.5, 0.2, 0.7];
        let b = [1.0, -0.2, 0.05, 0.8, 0.1, 1.2];
        let r = [1.1, -0.4, 0.9];
        let (fa, fb) = (Form3::new(a).unwrap(), Form3::new(b).unwrap());
        let bare = crate::contact_function(&r, &a, &b).unwrap();
        let typed = crate::contact_function(&r, &fa, &fb).unwrap();
        let by_ref = crate::contact_function(&r, &&fa, &&fb).unwrap();
        assert_eq!(bare.mu2.to_bits(), typed.mu2.to_bits());
        assert_eq!(bare.mu2.to_bits(), by_ref.mu2.to_bits());
        assert_eq!(crate::overlap(&r, &a, &b), crate::overlap(&r, &fa, &fb));
        let e2 = [1.0, 0.2, 0.5];
        let f2 = Form2::try_from(e2).unwrap();
        let r2 = [0.7, 0.3];
        assert_eq!(
            crate::contact_function(&r2, &e2, &e2)
                .unwrap()
                .mu2
                .to_bits(),
            crate::contact_function(&r2, &f2, &f2)
                .unwrap()
                .mu2
                .to_bits()
        );
        assert_eq!(Sym2::from(f2), e2);
        assert_eq!(<Form3 as QuadraticForm>::DIMENSION, 3);
        assert_eq!(<Form2 as QuadraticForm>::DIMENSION, 2);
    }

    #[test]
    fn a_form_is_checked_once_at_construction() {
        assert!(matches!(
            Form3::new([1.0, 0.0, 0.0, f64::NAN, 0.0, 1.0]),
            Err(Error::NonFinite { index: 3, .. })
        ));
        assert!(matches!(
            Form3::new([1.0, 0.0, 0.0, 1.0, 0.0, -1.0]),
            Err(Error::NotPositiveDefinite { minor: 3, .. })
        ));
        assert!(matches!(
            Form2::new([1.0, 2.0, 1.0]),
            Err(Error::NotPositiveDefinite { minor: 2, .. })
        ));
        // Positive definiteness does not depend on units: tiny and huge forms are accepted.
        assert!(Form3::new([1e-300, 0.0, 0.0, 1e-300, 0.0, 1e-300]).is_ok());
        assert!(Form2::new([1e300, 0.0, 1e300]).is_ok());
    }
}
