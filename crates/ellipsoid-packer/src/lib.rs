//! # ellipsoid-packer — dense packings of ellipses and ellipsoids in a minimum container
//!
//! The packer of Birgin, Lobato and Martínez's implicit-variable model
//! ([`implicit_packing`]): it minimises the container's area or volume subject to the model's
//! overlap and containment constraints with the augmented Lagrangian of [`auglag`], certifies
//! every result with PW85 and exact containment ([`implicit_packing::certificate`]), repairs
//! it by the least enlargement of the container ([`local::repair`]), and repeats from many
//! starts.
//!
//! - [`run`] — one whole run, owned here: [`Packer::new`] and [`Packer::run`] from the problem
//!   and its settings to a certified [`Configuration`] of items and container.
//! - [`starts`] — the paper's first initial solution, dense lattice starts, perturbations.
//! - [`local`] — one local minimisation with its polish, certificate and repair.
//! - [`compression`] — the container made small by placements in shrinking fixed containers,
//!   for thousands of items.
//! - [`multistart`](mod@multistart) — the multi-start with chains, parallel rounds, a time limit, progress
//!   and cancellation.
//! - [`fixed`] — the multi-start in a container of given size: no minimisation, only
//!   placement, ending at the first certified packing.
//! - [`random`] — random packings: random sequential addition, then compression to a packing
//!   fraction or until jammed.
//!
//! ```
//! use ellipsoid_packer::{Goal, MultiStartSettings, Outcome, Packer, Problem, Settings};
//! use implicit_packing::ContainerShape;
//!
//! // Five ellipses (2, 1) in the smallest disc that two local minimisations find.
//! let problem = Problem {
//!     semi_axes: vec![[2.0, 1.0]; 5],
//!     shape: ContainerShape::Ball,
//!     goal: Goal::Densest,
//!     resume: None,
//! };
//! let mut multistart = MultiStartSettings::recommended(2, 1);
//! multistart.max_local_minimisations = 2;
//! let settings = Settings { multistart, orientations: Vec::new() };
//! let Outcome::Packed(packed) = Packer::new(problem, settings)?.run(&mut ())? else {
//!     unreachable!("a container the run chooses is always filled");
//! };
//! assert!(packed.certificate.is_feasible());
//! assert!(packed.configuration.density() > 0.5);
//! # Ok::<(), ellipsoid_packer::Error>(())
//! ```
//!
//! # References
//! - E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//!   variables for packing ellipsoids*, J. Global Optim. 68 (2017), Section 6.
#![deny(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod compression;
mod error;
pub mod fixed;
pub mod local;
mod merged;
pub mod multistart;
mod problem;
pub mod random;
mod repair;
pub mod run;
mod settings;
pub mod starts;
pub mod tiling;

pub use error::{Error, StartDefects};
pub use fixed::fill;
pub use local::{LocalResult, LocalSettings, local_minimisation};
pub use multistart::{
    MultiStartProgress, MultiStartResult, MultiStartSettings, Observer, SolverEvent,
    SolverProgress, SolverReport, multistart,
};
pub use random::{RandomPacking, RandomSettings, Target, random_packing};
pub use run::{Configuration, Goal, Outcome, Packed, Packer, Problem, Repair, Settings, Unfilled};
