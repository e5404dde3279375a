//! Periodic packings of identical items built from a small cell: the densest packing of 1, 2
//! or 4 items in a variable periodic cell, found by a few local minimisations, tiled into a
//! supercell that holds every item.
//!
//! Many dense crystals of identical ellipsoids have few items per primitive cell (the densest
//! known, of Donev, Stillinger, Chaikin and Torquato, two), which a minimisation with
//! hundreds of items rarely reaches from a lattice start, while one with a few items does in
//! seconds.
//!
//! # References
//! A. Donev, F. H. Stillinger, P. M. Chaikin, S. Torquato, *Unusually dense crystal packings of
//! ellipsoids*, Phys. Rev. Lett. 92, 255506 (2004).

use crate::Error;
use crate::local::item_measure;
use crate::multistart::{MultiStartProgress, MultiStartSettings, Observer, Shard, multistart};
use crate::random::{ATTEMPTS_PER_ITEM, sequential_addition};
use crate::starts::{periodic_lattice_start, supercell};
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;
use implicit_packing::periodic::entry;
use std::time::Duration;

/// Items per small cell tried.
pub const SMALL_CELLS: [usize; 3] = [1, 2, 4];

/// Stops the small cells' multi-starts when the caller's run stops; hears nothing else.
struct Forward<'a>(&'a dyn Observer);

impl Observer for Forward<'_> {
    fn finished(&mut self, _progress: &MultiStartProgress) {}
    fn should_stop(&self) -> bool {
        self.0.should_stop()
    }
}

/// Loose random starts of a small cell tried besides its lattice start, and the packing
/// fraction of their cube cell.
///
/// The lattice start of identical items (their affine face-centred cubic packing, density
/// 0.7405) is a local optimum the solver does not leave; the denser SM2 crystal of spheroids
/// of aspect ≥ √3 (density 0.7707, two items per cell, Donev et al. 2004) is reached from
/// items placed far apart and compressed.
pub const LOOSE_STARTS: u64 = 6;

/// See [`LOOSE_STARTS`].
pub const LOOSE_FRACTION: f64 = 0.01;

/// The densest small cell of `k` items `semi_axes` that one-thread multi-starts with the
/// `template`'s settings find within `time`: one from the lattice start, and one from each of
/// [`LOOSE_STARTS`] random starts ([`sequential_addition`]) in a cube cell at
/// [`LOOSE_FRACTION`], each with an equal share of the time and of the local minimisations.
fn small_cell<const N: usize>(
    semi_axes: [f64; N],
    k: usize,
    template: &MultiStartSettings,
    time: Duration,
    observer: &dyn Observer,
) -> Result<Vec<f64>, Error> {
    let axes = vec![semi_axes; k];
    let model = Model::<N>::new(axes.clone(), ContainerShape::Periodic)?;
    let side = (item_measure(&model) / LOOSE_FRACTION).powf(1.0 / N as f64);
    let cube: Vec<f64> = (0..N * (N + 1) / 2)
        .map(|v| {
            let (r, c) = entry::<N>(v);
            if r == c { side } else { 0.0 }
        })
        .collect();
    let mut starts = vec![periodic_lattice_start(&model, k, &[0.0; N])];
    // One item per cell is a lattice, which its lattice start already ranges over. A loose
    // start that finds no place (an item longer than the cube) is left out.
    let loose = if k > 1 { LOOSE_STARTS } else { 0 };
    starts.extend((0..loose).filter_map(|s| {
        sequential_addition(
            &model,
            &cube,
            template.seed.wrapping_add(s),
            ATTEMPTS_PER_ITEM,
        )
        .ok()
    }));
    let share = starts.len() as u32;
    let mut best: Option<(f64, Vec<f64>)> = None;
    for (n, x0) in starts.iter().enumerate() {
        let mut settings = template.clone();
        settings.time_limit = Some(time / share);
        settings.max_local_minimisations =
            (template.max_local_minimisations / share as usize).max(1);
        settings.threads = 1;
        settings.shard = Shard::WHOLE;
        if n > 0 {
            // From a loose start, the perturbations of its own best, not other lattices.
            settings.lattice_starts = 0;
        }
        let result = multistart(
            &axes,
            ContainerShape::Periodic,
            x0,
            &settings,
            &mut Forward(observer),
        )?;
        if best.as_ref().is_none_or(|b| result.best.density > b.0) {
            best = Some((result.best.density, result.best.x));
        }
    }
    best.map(|b| b.1).ok_or(Error::StoppedBeforeStart)
}

/// The variables of `m` items tiled from the small cell `x` of `k` items: the cell repeated
/// `c_1 × … × c_N` times (the counts of [`supercell`]), the first `m` images kept.
fn tiled<const N: usize>(x: &[f64], k: usize, m: usize) -> Vec<f64> {
    // The items are alike: each has the same variables, and the cell's follow them.
    let stride = (x.len() - N * (N + 1) / 2) / k;
    let cell_vars = &x[k * stride..];
    let heights: [f64; N] = std::array::from_fn(|d| cell_vars[d]);
    let counts = supercell::<N>(m, k, &heights);
    let mut out = Vec::with_capacity(m * stride + cell_vars.len());
    let mut n = [0usize; N];
    'cells: loop {
        for i in 0..k {
            if out.len() == m * stride {
                break 'cells;
            }
            let body = &x[i * stride..(i + 1) * stride];
            for d in 0..N {
                let s = body[d] - body[d].floor();
                out.push((n[d] as f64 + s) / counts[d] as f64);
            }
            out.extend_from_slice(&body[N..]);
        }
        if !crate::starts::next_cell(&mut n, &counts) {
            break;
        }
    }
    // H diag(c): column j of the cell scaled by c_j.
    for v in 0..N * (N + 1) / 2 {
        let (_, column) = entry::<N>(v);
        out.push(cell_vars[v] * counts[column] as f64);
    }
    out
}

/// A start for `problem` (a periodic cell of identical items): the densest of the small cells
/// with 1, 2 and 4 items (each a one-thread multi-start of `time_per_cell` with the
/// `template`'s settings) tiled to the problem's items, certified, with its density; `None`
/// when the items differ, the cell is not periodic or no small cell could be used. The small runs stop when `observer`
/// says so.
///
/// # Errors
/// Errors of the model and of the small multi-starts.
pub fn tiled_start<const N: usize>(
    problem: &mut Model<N>,
    template: &MultiStartSettings,
    time_per_cell: Duration,
    observer: &dyn Observer,
) -> Result<Option<(Vec<f64>, f64)>, Error> {
    let axes = problem.semi_axes();
    if problem.container_kind() != ContainerShape::Periodic || axes.iter().any(|a| *a != axes[0]) {
        return Ok(None);
    }
    let (semi_axes, m) = (axes[0], axes.len());
    let mut best: Option<(Vec<f64>, f64)> = None;
    for k in SMALL_CELLS.into_iter().filter(|&k| k <= m) {
        if observer.should_stop() {
            break;
        }
        // A small cell the model cannot hold (one elongated item in a cell thinner than its
        // reach needs too many images) is skipped: the run has its lattice start.
        let Ok(x) = small_cell(semi_axes, k, template, time_per_cell, observer) else {
            continue;
        };
        let y = tiled::<N>(&x, k, m);
        if !problem.certify(&y).is_ok_and(|c| c.is_feasible()) {
            continue;
        }
        let density = item_measure(problem) / problem.evaluate(&y, None)?.objective;
        if best.as_ref().is_none_or(|b| density > b.1) {
            best = Some((y, density));
        }
    }
    Ok(best)
}
