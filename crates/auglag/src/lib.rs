//! A safeguarded augmented Lagrangian solver for smooth nonlinear programs
//!
//! ```text
//! minimise f(x)  subject to  h(x) = 0,  g(x) ≤ 0,  l ≤ x ≤ u,
//! ```
//!
//! in the style of Algencan (Birgin & Martínez 2014): an outer loop on the
//! Powell–Hestenes–Rockafellar augmented Lagrangian with multipliers projected onto a
//! safeguarding box, and an inner solver for the bound-constrained subproblems — a nonmonotone
//! spectral projected gradient ([`InnerSolver::Spg`]), an active-set projected L-BFGS
//! ([`InnerSolver::ProjectedLbfgs`]), or an active-set truncated Newton whose conjugate
//! gradients are preconditioned by an L-BFGS matrix of the previous step's pairs
//! ([`InnerSolver::TruncatedNewton`]). Memory is O(n) per iteration (no n×n matrix), all
//! buffers are allocated before the first iteration, and runs are deterministic.
//!
//! A model is seen only through the [`Problem`] trait. [`minimize`] or
//! [`minimize_with_callback`] return a [`Solution`] whose [`Report`] says how the run went.
//!
//! ```
//! use auglag::{minimize, Options, Problem, StopReason};
//!
//! /// min x₀² + x₁²  subject to  x₀ + x₁ = 1:  optimum (½, ½).
//! struct Closest;
//! impl Problem for Closest {
//!     fn dim(&self) -> usize { 2 }
//!     fn n_eq(&self) -> usize { 1 }
//!     fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
//!         if let Some(g) = grad { g[0] = 2.0 * x[0]; g[1] = 2.0 * x[1]; }
//!         x[0] * x[0] + x[1] * x[1]
//!     }
//!     fn constraints(&self, x: &[f64], c: &mut [f64]) { c[0] = x[0] + x[1] - 1.0; }
//!     fn constraints_jt_times(&self, _x: &[f64], w: &[f64], out: &mut [f64]) {
//!         out[0] += w[0];
//!         out[1] += w[0];
//!     }
//! }
//!
//! let solution = minimize(&Closest, &[3.0, -1.0], &Options::default()).unwrap();
//! assert_eq!(solution.report.stop_reason, StopReason::Converged);
//! assert!((solution.x[0] - 0.5).abs() < 1e-3 && (solution.x[1] - 0.5).abs() < 1e-3);
//! ```
//!
//! # References
//! - E. G. Birgin, J. M. Martínez, *Practical Augmented Lagrangian Methods for Constrained
//!   Optimization*, SIAM, 2014.
//! - E. G. Birgin, J. M. Martínez, M. Raydan, "Nonmonotone spectral projected gradient methods
//!   on convex sets", SIAM J. Optim. 10(4), 2000.
//! - D. P. Bertsekas, "Projected Newton methods for optimization problems with simple
//!   constraints", SIAM J. Control Optim. 20(2), 1982; R. H. Byrd, P. Lu, J. Nocedal, C. Zhu,
//!   "A limited memory algorithm for bound constrained optimization", SIAM J. Sci. Comput.
//!   16(5), 1995.
//! - R. S. Dembo, T. Steihaug, "Truncated-Newton algorithms for large-scale unconstrained
//!   optimization", Math. Program. 26, 1983; J. L. Morales, J. Nocedal, "Automatic
//!   preconditioning by limited memory quasi-Newton updating", SIAM J. Optim. 10(4), 2000.
#![deny(missing_docs)]

mod error;
mod inner;
mod lagrangian;
mod options;
mod outer;
mod phr;
mod problem;
mod projected_qn;
mod projection;
mod report;
mod spg;
mod truncated_newton;

pub use error::{Error, Evaluation};
pub use options::{InnerSolver, Options};
pub use outer::{minimize, minimize_with_callback};
pub use phr::Phr;
pub use problem::Problem;
pub use report::{Control, Event, Progress, Report, Solution, StopReason};

/// Runs the README's example as a doctest, so that it keeps compiling.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
