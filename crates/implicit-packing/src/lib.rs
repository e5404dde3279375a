//! The implicit-variable non-overlap model of ellipse and ellipsoid packing.
//!
//! For every pair of ellipsoids `(i, j)` the model of Birgin, Lobato and Martínez maps `E_i` to a
//! unit ball and `E_j` to `{x : xᵀ S_ij x ≤ 1}`; the closest point `X` and multiplier `U` of the
//! projection of the ball's centre onto that surface are *implicit* functions of the centres and
//! rotations, so the model has a number of variables and constraints linear in the number of
//! ellipsoids, and a cell grid makes its evaluation linear in time.
//!
//! Modules, by equation:
//!
//! * [`shape`]: centres, semi-axes, rotations (eqs. 1–2), quaternions;
//! * [`pair`]: the pair term `f` (eqs. 3, 21–22, 34–36, Prop. 3.3);
//! * `projection` (feature `internals`): the secular equation of the projection onto `xᵀ S x = 1`;
//! * [`round`]: the pair term of two circles or balls in closed form;
//! * [`derivatives`]: first derivatives of the pair term (Appendix A.1 and the envelope form)
//!   and exact Hessian–vector products;
//! * [`containment`]: exact containment in a ball, an ellipsoid or a box, with first
//!   derivatives and exact Hessian–vector products;
//! * [`periodic`]: periodic cells (fractional coordinates, lattice images);
//! * [`layout`]: where each item's variables are (a round item has no angles);
//! * [`model`]: the whole sum over the grid's candidate pairs (Section 5.2), containment and
//!   objective, with gradients and Hessian–vector products;
//! * [`certificate`]: the verdict that decides whether a configuration is a packing, independent
//!   of the model (PW85 on every close pair, exact containment).
//!
//! The packer (starts, local minimisation, repair, multi-start) is the crate
//! `ellipsoid-packer`; this crate is the model alone and depends on no solver.
//!
//! # References
//! E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//! variables for packing ellipsoids*, Journal of Global Optimization 68 (2017) 467–499.
#![deny(missing_docs)]
// Index loops mirror the subscripts of the formulas (x_k, S_km, …) over fixed N = 2, 3, and
// several arrays are indexed together; iterator chains would hide the mathematics.
#![allow(clippy::needless_range_loop)]

#[cfg(feature = "internals")]
pub mod batch;
#[cfg(not(feature = "internals"))]
mod batch;
pub mod certificate;
pub mod containment;
pub mod derivatives;
pub mod error;
pub(crate) mod lanes;
pub mod layout;
pub(crate) mod linalg;
pub mod model;
pub mod pair;
pub mod periodic;
#[cfg(feature = "internals")]
pub mod projection;
#[cfg(not(feature = "internals"))]
mod projection;
pub mod round;
#[cfg(feature = "rayon")]
pub(crate) mod scatter;
pub mod shape;
pub(crate) mod trig;

pub use certificate::Certificate;
pub use containment::{Container, ContainerShape};
pub use error::Error;
pub use layout::Layout;
pub use model::Model;
pub use pair::{PairTerm, Route, epsilon, overlap_measure, pair_term, pair_term_by};
pub use shape::{Body, Ellipse, Ellipsoid, Item, Orientation};
