//! A Verlet neighbour list: the close pairs of a grid built with the reach enlarged by a
//! skin, reused until some item has moved more than half the skin.

use std::ops::Range;

use crate::builder::{GridBuilder, Reach};
use crate::error::Error;
use crate::grid::Grid;
use crate::pairs::dot;

/// The pairs closer than the reach, found through a list of candidates that outlives the
/// positions it was built from.
///
/// An optimiser, a Monte Carlo or a molecular-dynamics code moves its items a little at a
/// time and asks for the close pairs after every move. Rebuilding the grid each time re-sorts
/// every item and re-enumerates every neighbouring cell, although the pairs barely change.
/// The list stores, at a *reference* configuration, every pair within the reach plus a skin
/// `s`: `|c_i − c_j| < r_i + r_j + s` (or `< cutoff + s`). While no item has moved more than
/// `s/2` from its reference position, every pair now closer than `r_i + r_j` was within
/// `r_i + r_j + s` there (triangle inequality), so it is in the list; each query scans the
/// list with the exact test and reports the same pairs as a fresh grid, at a fraction of its
/// cost. A query finds the list stale (an item moved too far, or the number of items
/// changed) itself and rebuilds it first.
///
/// # Order
/// Pairs are reported as `(i, j)` with `i < j`, in ascending lexicographic order: the output
/// depends on the positions only, not on where the list was last rebuilt (a sum over pairs
/// is then a function of the positions, bit for bit). `delta = p_j − p_i` and
/// `dist2 = |delta|²` are computed from the caller's points exactly as
/// [`Grid::for_each_close_pair`] computes them on open axes (on periodic axes through
/// [`Grid::min_image`] on the caller's points).
///
/// # Rounding
/// The triangle inequality holds for exact distances, and the computed tests round. A
/// computed difference of two doubles has a relative error of at most `u = 2⁻⁵³`, a computed
/// squared distance of at most about `(D + 2) u`, so the tests are exact to a relative
/// `~8u` of the distances involved. The allowed displacement is therefore
/// `s/2 − 16 u (2 r_max + s + L_max)` (`L_max` the longest periodic side, 0 without one), which
/// covers these errors with a factor of two; with `s = 0` (or a smaller skin than that margin)
/// every query rebuilds, and the list is then just the grid.
///
/// # Cost
/// A rebuild is a grid build with the enlarged reach, its pair enumeration and a counting sort
/// of the pairs by first item (`O(m + pairs)`); a query is one pass over the items (the
/// displacement test) and one over the listed pairs. In a local minimisation of 1 000
/// ellipsoids (ellipack's packer, 97 588 evaluations and about as many Hessian–vector
/// products) a skin of a tenth of the enclosing radius was outrun 394 times.
///
/// # References
/// L. Verlet, "Computer experiments on classical fluids. I. Thermodynamical properties of
/// Lennard-Jones molecules", Phys. Rev. 159 (1967) 98–103 (the neighbour list with a skin).
/// E. G. Birgin, R. D. Lobato, J. M. Martínez, Section 5.2 (the grid that builds it).
///
/// ```
/// use cell_grid::{GridBuilder, PairList};
///
/// let radii = [0.5, 0.5, 0.5];
/// let mut list = PairList::new(GridBuilder::<3>::with_radii(&radii), 0.4)?;
/// let mut points = [[0.0, 0.0, 0.0], [0.9, 0.0, 0.0], [5.0, 0.0, 0.0]];
/// let mut pairs = Vec::new();
/// list.for_each_close_pair(&points, |i, j, _delta, _dist2| pairs.push((i, j)))?;
/// assert_eq!(pairs, [(0, 1)]);
///
/// // A small move: the same list, the exact test now rejects the pair.
/// points[1][0] = 1.05;
/// pairs.clear();
/// list.for_each_close_pair(&points, |i, j, _, _| pairs.push((i, j)))?;
/// assert!(pairs.is_empty());
/// assert_eq!(list.builds(), 1);
///
/// // Item 2 jumps: the list is rebuilt before the scan.
/// points[2] = [0.0, 0.8, 0.0];
/// list.for_each_close_pair(&points, |i, j, _, _| pairs.push((i, j)))?;
/// assert_eq!(pairs, [(0, 2)]);
/// assert_eq!(list.builds(), 2);
/// # Ok::<(), cell_grid::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct PairList<const D: usize> {
    /// The configuration with the enlarged reach, kept for the first build.
    builder: GridBuilder<D>,
    /// The grid of the last rebuild (enlarged reach, reference positions).
    grid: Option<Grid<D>>,
    /// The exact per-item radii (`None` with a global cutoff).
    radii: Option<Vec<f64>>,
    /// The exact global cutoff (0 with per-item radii).
    cutoff: f64,
    skin: f64,
    /// Largest squared displacement from the reference that keeps the list valid (negative:
    /// none does).
    allowed2: f64,
    reference: Vec<[f64; D]>,
    /// Row `i` of the list is `partner[start[i]..start[i + 1]]`, the partners `j > i`,
    /// ascending.
    start: Vec<usize>,
    partner: Vec<u32>,
    /// Rebuild scratch: the enlarged grid's pairs as `i << 32 | j`.
    codes: Vec<u64>,
    builds: usize,
}

impl<const D: usize> PairList<D> {
    /// A list over the pairs `builder` defines (cutoff or per-item radii, domain, periodic
    /// axes), kept valid for moves up to `skin / 2`. Nothing is built until the first query.
    ///
    /// # Errors
    /// [`Error::InvalidSkin`] if `skin` is negative, NaN or infinite;
    /// [`Error::InvalidCutoff`] or [`Error::InvalidRadius`] for a bad cutoff or radius, and
    /// [`Error::InvalidSkin`] as well if the reach enlarged by the skin has no normal `f64`
    /// square. The builder's other errors (domain, periodic box) come with the first query.
    pub fn new(builder: GridBuilder<D>, skin: f64) -> Result<Self, Error> {
        if !(skin.is_finite() && skin >= 0.0) {
            return Err(Error::InvalidSkin { value: skin });
        }
        let (cutoff, radii, reach_max) = match &builder.reach {
            Reach::Cutoff(c) => {
                check_reach(*c, |value| Error::InvalidCutoff { value })?;
                (*c, None, *c)
            }
            Reach::Radii(r) => {
                for (index, &value) in r.iter().enumerate() {
                    check_reach(2.0 * value, |_| Error::InvalidRadius { index, value })?;
                }
                let r_max = r.iter().fold(0.0f64, |a, &b| a.max(b));
                (0.0, Some(r.clone()), 2.0 * r_max)
            }
        };
        // The enlarged reach must be valid too: a skin so large that its square overflows is
        // the skin's fault. (Without items there is no reach to enlarge.)
        if reach_max > 0.0 {
            check_reach(reach_max + skin, |_| Error::InvalidSkin { value: skin })?;
        }
        let mut enlarged = builder;
        enlarged.reach = match enlarged.reach {
            Reach::Cutoff(c) => Reach::Cutoff(c + skin),
            Reach::Radii(r) => Reach::Radii(r.iter().map(|&v| v + 0.5 * skin).collect()),
        };
        let mut period = 0.0f64;
        if let Some((lo, hi)) = enlarged.domain {
            for a in 0..D {
                if enlarged.periodic[a] {
                    period = period.max(hi[a] - lo[a]);
                }
            }
        }
        let h = 0.5 * skin - 16.0 * 0.5 * f64::EPSILON * (reach_max + skin + period);
        Ok(Self {
            builder: enlarged,
            grid: None,
            radii,
            cutoff,
            skin,
            allowed2: if h > 0.0 { h * h } else { -1.0 },
            reference: Vec::new(),
            start: Vec::new(),
            partner: Vec::new(),
            codes: Vec::new(),
            builds: 0,
        })
    }

    /// The skin `s`: pairs within the reach plus `s` are listed.
    pub fn skin(&self) -> f64 {
        self.skin
    }

    /// How many times the list has been built.
    pub fn builds(&self) -> usize {
        self.builds
    }

    /// Number of listed (candidate) pairs.
    pub fn len(&self) -> usize {
        self.partner.len()
    }

    /// Whether the list holds no pair.
    pub fn is_empty(&self) -> bool {
        self.partner.is_empty()
    }

    /// Rebuilds the list at `points` unless it is still valid there; returns whether it was
    /// rebuilt. The queries call this themselves.
    ///
    /// # Errors
    /// Those of [`Grid::rebuild`] ([`Error::NonFiniteCoordinate`],
    /// [`Error::RadiiCountMismatch`], ...). On error the list is left empty and the next
    /// query rebuilds.
    pub fn refresh(&mut self, points: &[[f64; D]]) -> Result<bool, Error> {
        if self.is_valid_at(points) {
            return Ok(false);
        }
        if let Err(e) = self.rebuild(points) {
            self.grid = None;
            self.reference.clear();
            self.start.clear();
            self.partner.clear();
            return Err(e);
        }
        Ok(true)
    }

    /// Whether every item is within the allowed displacement of its reference position. A
    /// NaN coordinate fails the test, so the rebuild reports it.
    fn is_valid_at(&self, points: &[[f64; D]]) -> bool {
        let Some(grid) = &self.grid else {
            return false;
        };
        if points.len() != self.reference.len() {
            return false;
        }
        let h2 = self.allowed2;
        #[cfg(feature = "rayon")]
        if points.len() >= 2 * POINTS_PER_TASK {
            use rayon::prelude::*;
            return points
                .par_chunks(POINTS_PER_TASK)
                .zip(self.reference.par_chunks(POINTS_PER_TASK))
                .all(|(p, r)| moved_within(grid, p, r, h2));
        }
        moved_within(grid, points, &self.reference, h2)
    }

    fn rebuild(&mut self, points: &[[f64; D]]) -> Result<(), Error> {
        let grid = match self.grid.take() {
            Some(mut g) => {
                g.rebuild(points)?;
                g
            }
            None => self.builder.clone().build(points)?,
        };
        let code = |i: usize, j: usize| (i as u64) << 32 | j as u64;
        // The pairs in any order: the counting sort and the sorted rows below make the list
        // the same on any number of threads.
        #[cfg(feature = "rayon")]
        {
            self.codes = grid.par_fold_close_pairs(
                Vec::new,
                |acc, i, j, _, _| acc.push(code(i, j)),
                |mut a, mut b| {
                    a.append(&mut b);
                    a
                },
            );
        }
        #[cfg(not(feature = "rayon"))]
        {
            self.codes.clear();
            let codes = &mut self.codes;
            grid.for_each_close_pair(|i, j, _, _| codes.push(code(i, j)));
        }
        let codes = &self.codes;
        // Counting sort by first item, then each (short) row by partner.
        let m = points.len();
        self.start.clear();
        self.start.resize(m + 1, 0);
        for &c in codes.iter() {
            self.start[(c >> 32) as usize + 1] += 1;
        }
        for i in 0..m {
            self.start[i + 1] += self.start[i];
        }
        self.partner.clear();
        self.partner.resize(codes.len(), 0);
        // `start[i]` serves as row i's fill cursor and ends at row i + 1's beginning; the
        // shift back restores it.
        for &c in codes.iter() {
            let i = (c >> 32) as usize;
            self.partner[self.start[i]] = c as u32;
            self.start[i] += 1;
        }
        for i in (1..=m).rev() {
            self.start[i] = self.start[i - 1];
        }
        self.start[0] = 0;
        sort_rows(&self.start, &mut self.partner);
        self.reference.clear();
        self.reference.extend_from_slice(points);
        self.grid = Some(grid);
        self.builds += 1;
        Ok(())
    }

    /// Calls `f(i, j, delta, dist2)` for every pair `i < j` closer than the reach, in
    /// ascending `(i, j)` order, with `delta = p_j − p_i` and `dist2 = |delta|²` (see the
    /// type's documentation), after rebuilding the list if `points` made it stale.
    ///
    /// # Errors
    /// Those of [`refresh`](Self::refresh); `f` is not called then.
    pub fn for_each_close_pair<F>(&mut self, points: &[[f64; D]], mut f: F) -> Result<(), Error>
    where
        F: FnMut(usize, usize, [f64; D], f64),
    {
        self.refresh(points)?;
        self.close_pairs_in(points, 0..points.len(), &mut f);
        Ok(())
    }

    /// As [`for_each_close_pair`](Self::for_each_close_pair), for the pairs whose first item
    /// `i` is in `rows` only (the list is still built over every point): e.g. the pairs of the
    /// first items with any item, skipping those among the rest.
    ///
    /// # Errors
    /// Those of [`refresh`](Self::refresh); `f` is not called then.
    pub fn for_each_close_pair_from<F>(
        &mut self,
        points: &[[f64; D]],
        rows: Range<usize>,
        mut f: F,
    ) -> Result<(), Error>
    where
        F: FnMut(usize, usize, [f64; D], f64),
    {
        self.refresh(points)?;
        let rows = rows.start.min(points.len())..rows.end.min(points.len());
        self.close_pairs_in(points, rows, &mut f);
        Ok(())
    }

    /// The close pairs of the rows `rows`, the list being valid at `points`.
    ///
    /// About a quarter of the listed pairs fail the test, at random: a branch per pair
    /// would be mispredicted often. So the test only appends the pair to a small buffer
    /// (unconditional store, count advanced by the verdict), and `f` runs in a second,
    /// predictable loop, as in the grid's own scan.
    pub(crate) fn close_pairs_in<F>(&self, points: &[[f64; D]], rows: Range<usize>, f: &mut F)
    where
        F: FnMut(usize, usize, [f64; D], f64),
    {
        let Some(grid) = &self.grid else {
            return;
        };
        let periodic = grid.any_periodic;
        let delta = |a: &[f64; D], b: &[f64; D]| {
            if periodic {
                grid.min_image(*a, *b)
            } else {
                let mut d = [0.0; D];
                for k in 0..D {
                    d[k] = b[k] - a[k];
                }
                d
            }
        };
        let mut hits = [0u64; BATCH];
        let mut n = 0;
        let mut emit = |hits: &[u64]| {
            for &h in hits {
                let (i, j) = ((h >> 32) as usize, (h & 0xffff_ffff) as usize);
                let d = delta(&points[i], &points[j]);
                f(i, j, d, dot(&d, &d));
            }
        };
        for i in rows {
            let row = &self.partner[self.start[i]..self.start[i + 1]];
            // The two limits are chosen per row, outside the pair loop.
            match &self.radii {
                Some(radii) => {
                    let ri = radii[i];
                    let limit = |j: usize| {
                        let s = ri + radii[j];
                        s * s
                    };
                    scan_row(
                        points,
                        (i, row),
                        &delta,
                        limit,
                        (&mut hits, &mut n),
                        &mut emit,
                    );
                }
                None => {
                    let lim = self.cutoff * self.cutoff;
                    scan_row(
                        points,
                        (i, row),
                        &delta,
                        |_| lim,
                        (&mut hits, &mut n),
                        &mut emit,
                    );
                }
            }
        }
        emit(&hits[..n]);
    }

    /// The rows `rows` cut into consecutive ranges of about equal numbers of listed pairs.
    #[cfg(feature = "rayon")]
    pub(crate) fn row_chunks(&self, rows: Range<usize>, chunks: usize) -> Vec<Range<usize>> {
        if self.start.is_empty() {
            return Vec::new();
        }
        let m = rows.end.min(self.start.len() - 1);
        let mut lo = rows.start.min(m);
        let total = self.start[m] - self.start[lo];
        // Small lists are not worth a task each.
        let per = total.div_ceil(chunks.max(1)).max(4096);
        let mut out = Vec::with_capacity(chunks + 1);
        while lo < m {
            let target = self.start[lo] + per;
            // First row that starts at or beyond the target.
            let hi = lo + 1 + self.start[lo + 1..=m].partition_point(|&s| s < target);
            let hi = hi.min(m);
            out.push(lo..hi);
            lo = hi;
        }
        out
    }
}

/// Whether every point is within `√h2` of its reference (minimum image on periodic axes).
/// No early exit: the common answer is "valid", and the loop without a branch per item
/// vectorises.
fn moved_within<const D: usize>(
    grid: &Grid<D>,
    points: &[[f64; D]],
    reference: &[[f64; D]],
    h2: f64,
) -> bool {
    let mut valid = true;
    if grid.any_periodic {
        for (p, r) in points.iter().zip(reference) {
            let d = grid.min_image(*r, *p);
            valid &= dot(&d, &d) <= h2;
        }
    } else {
        for (p, r) in points.iter().zip(reference) {
            let mut s = 0.0;
            for k in 0..D {
                let t = p[k] - r[k];
                s += t * t;
            }
            valid &= s <= h2;
        }
    }
    valid
}

/// Points per rayon task of the displacement test (two tasks' worth at least to split).
#[cfg(feature = "rayon")]
const POINTS_PER_TASK: usize = 8192;

/// Sorts each row `partner[start[i]..start[i + 1]]`; with `rayon`, blocks of
/// [`POINTS_PER_TASK`] rows on the pool's threads (the rows are disjoint, so the list is the
/// same on any number of threads). Most of a rebuild's own time is these short sorts.
fn sort_rows(start: &[usize], partner: &mut [u32]) {
    #[cfg(feature = "rayon")]
    if start.len() > 2 * POINTS_PER_TASK {
        let m = start.len() - 1;
        use rayon::prelude::*;
        let mut blocks = Vec::with_capacity(m.div_ceil(POINTS_PER_TASK));
        let mut rest = partner;
        for first in (0..m).step_by(POINTS_PER_TASK) {
            let end = (first + POINTS_PER_TASK).min(m);
            let (block, tail) = std::mem::take(&mut rest).split_at_mut(start[end] - start[first]);
            blocks.push((&start[first..=end], block));
            rest = tail;
        }
        blocks
            .into_par_iter()
            .for_each(|(rows, block)| sort_rows_here(rows, block));
        return;
    }
    sort_rows_here(start, partner);
}

/// [`sort_rows`] on the calling thread, for `partner` beginning at row `start[0]`.
fn sort_rows_here(start: &[usize], partner: &mut [u32]) {
    for row in start.windows(2) {
        partner[row[0] - start[0]..row[1] - start[0]].sort_unstable();
    }
}

/// Buffered candidates per scan before `f` runs.
const BATCH: usize = 64;

/// Row `i` of the list against its partners `row`: each pair goes into the buffer, which
/// advances only when the pair is closer than `limit(j)` (its squared reach); a full buffer
/// is handed to `emit`.
#[inline(always)]
fn scan_row<const D: usize>(
    points: &[[f64; D]],
    (i, row): (usize, &[u32]),
    delta: &impl Fn(&[f64; D], &[f64; D]) -> [f64; D],
    limit: impl Fn(usize) -> f64,
    (hits, n): (&mut [u64; BATCH], &mut usize),
    emit: &mut impl FnMut(&[u64]),
) {
    let pi = &points[i];
    for &j in row {
        let d = delta(pi, &points[j as usize]);
        hits[*n & (BATCH - 1)] = (i as u64) << 32 | u64::from(j);
        *n += usize::from(dot(&d, &d) < limit(j as usize));
        if *n == BATCH {
            emit(&hits[..]);
            *n = 0;
        }
    }
}

fn check_reach(value: f64, err: impl FnOnce(f64) -> Error) -> Result<f64, Error> {
    if crate::grid::valid_reach(value) {
        Ok(value)
    } else {
        Err(err(value))
    }
}
