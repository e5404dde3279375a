//! Uniform cell grid for fixed-radius neighbour search: every pair of items closer than a
//! cutoff, exactly once, in `O(m)` time, in 2D and 3D.
//!
//! This is the device of paper Section 5.2 that keeps the ellipsoid packing model linear in
//! the number of ellipsoids `m`: enclose ellipsoid `i` in a ball of radius `r_i`; two
//! ellipsoids can only overlap if `|c_i - c_j| < r_i + r_j <= 2R` with `R = max r_i`
//! (Eq. (37)). Cut space into cells of edge `l >= 2R`; centres closer than `2R` then lie in
//! the same or in adjacent cells, so each ellipsoid is compared only with those of its own
//! and of the `3^D - 1` surrounding cells. At packing density a cell holds a bounded number of
//! items and the work is `O(m)`.
//!
//! ```
//! use cell_grid::Grid;
//!
//! let points = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.9, 0.0]];
//! let grid = Grid::<3>::build(&points, 1.0)?;
//! let mut pairs = Vec::new();
//! grid.for_each_pair_within(&points, |i, j, dist2| pairs.push((i, j, dist2)))?;
//! pairs.sort_by_key(|&(i, j, _)| (i, j));
//! // (0,1) at 0.5 and (0,3) at 0.9; (1,3) is at 1.03 and item 2 is alone.
//! assert_eq!(pairs.iter().map(|&(i, j, _)| (i, j)).collect::<Vec<_>>(), [(0, 1), (0, 3)]);
//! assert_eq!(pairs[1].2, 0.81);
//! # Ok::<(), cell_grid::Error>(())
//! ```
//!
//! # What the crate offers
//! - [`Grid::build`] with one cutoff, or [`GridBuilder`] for per-item radii, a fixed domain,
//!   periodic axes and the cap on cells.
//! - [`Grid::rebuild`] in place, allocation-free once the buffers are large enough.
//! - Pairs: [`Grid::for_each_candidate_pair`] (same or adjacent cells),
//!   [`Grid::for_each_pair_within`] (distance from the caller's points),
//!   [`Grid::for_each_close_pair`] (fast path, with minimum-image vectors), and with the
//!   `rayon` feature their parallel versions.
//! - [`PairList`]: a Verlet list over the grid, for items that move a little between
//!   queries (an optimiser's or a simulation's steps): the pairs within the reach plus a
//!   skin, kept until an item has moved more than half the skin; each query reports the exact
//!   close pairs, in ascending `(i, j)` order, without re-sorting the items.
//! - Neighbours of an item ([`Grid::for_each_neighbour`]) or of any point
//!   ([`Grid::for_each_near_point`]); the non-empty cells ([`Grid::cells`]).
//!
//! # Mixed sizes
//! With per-item radii a pair is a candidate when `|c_i - c_j| < r_i + r_j`, and plain cells
//! must have edge `l = 2 r_max`. If most items have radius `r` and a few have `r_max = k r`,
//! a cell holds about `k^D` times more small items than it would with `l = 2r`, and so does
//! the list of candidates of each item: `k^3 = 10^6` for a 100× spread in 3D, which is brute
//! force in disguise. The reported pairs stay exact (the test uses `r_i + r_j`); only time is
//! lost.
//!
//! The mitigation is built in ([`GridBuilder::split_large_items`], on by default): at each
//! build the radii are bucketed by binary order of magnitude and a cost estimate picks a
//! split radius `r_cut` (a power of two, or none). Items with radius `>= r_cut` are kept out
//! of the cells, whose edge becomes twice the largest radius `r_s < r_cut` left in them; each
//! large item searches the cells within `r_i + r_s` and tests the other large items
//! directly. A few giants among many small
//! items then cost about their own covered volume instead of inflating every cell (the
//! `3d_mixed_sizes` bench measures it). A continuous spread of sizes (say log-uniform over
//! two decades) gains less: there is no gap to cut at, and a hierarchy of grids, one per size
//! class, would be the next step.
//!
//! # Cost
//! Building is a counting sort: two passes over the points and one over the cells, `O(m)`
//! with at most `max(65 536, 16 m)` dense cells. Enumerating visits, per item, the items of
//! about `3^D / 2` cells; at packing density (13 neighbours within the cutoff in 3D) that is
//! about 40 candidates per item in 3D and 8 in 2D. Measured figures (build + all pairs, per
//! point, against brute force and a k-d tree) are in the crate's README.
//!
//! # Bad input
//! Non-finite coordinates, non-positive cutoffs or radii, inconsistent lengths and bad
//! domains are reported as [`Error`]; no input makes the grid panic. Distances are compared
//! squared, so a cutoff (or radius) whose square is not a normal `f64` (below about
//! `1.5e-154` or above `1.3e154`) is refused as well. An empty point set
//! gives an empty grid. All points identical, or on a line, give a single cell along the
//! degenerate axes. A cutoff tiny against the domain would need an enormous cell array: the
//! dense array is capped ([`GridBuilder::max_cells`]) and beyond the cap only non-empty cells
//! are stored in a hash map ([`Layout::Hashed`]), so memory stays `O(m)`.
//!
//! # Periodic boxes
//! On a periodic axis points are wrapped into the box and distances use the minimum image.
//! The reach must not exceed half the box side ([`Error::CutoffTooLargeForBox`]), else a pair
//! could be close through two images at once. Boxes with fewer than three cells along an axis
//! are handled: neighbouring cells that wrap onto the same cell are visited once.
//!
//! # References
//! E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//! variables for packing ellipsoids*, preprint of March 2016
//! (`shared/papers/birgin-lobato-martinez-implicit-variables-packing.md`), Section 5.2
//! "Efficient evaluation of the constraints": regions of edge `l = 2R`, the clamp `p(x)`,
//! comparison with the own and adjacent regions, the list of non-empty regions.
#![deny(missing_docs)]
// Per-axis loops `for a in 0..D` read several arrays (lo, edge, dims, ...) in lockstep; an
// index says that more plainly than nested zips.
#![allow(clippy::needless_range_loop)]

mod builder;
mod error;
mod grid;
mod hash;
mod pair_list;
mod pairs;
#[cfg(feature = "rayon")]
mod parallel;
mod query;

pub use builder::GridBuilder;
pub use error::Error;
pub use grid::{Cell, Grid, Layout};
pub use pair_list::PairList;

// The README's example is compiled and run as a doctest so that it cannot rot.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
